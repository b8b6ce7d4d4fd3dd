#!/usr/bin/env bash
# Training throughput of two `blockpuzzle` binaries side by side (e.g. before and after a change):
# `bench --train` for each algorithm, alternating the binaries, ROUNDS rounds, one JSON line per run.
# Usage: bash bench/train_ab.sh OLD_BINARY NEW_BINARY [ROUNDS]   (results/algorithm-core.md)
# `--ddpg` is the older name of `--train`: binaries from before the rename accept it too.
set -euo pipefail
OLD="$1" NEW="$2" ROUNDS="${3:-2}"
for round in $(seq "$ROUNDS"); do
    for algo in ddpg sac pggd; do
        for which in old new; do
            bp="$OLD"; [ "$which" = new ] && bp="$NEW"
            echo "$round $algo $which $("$bp" bench --ddpg --algo "$algo" --steps 3000 --updates 300 --json | tail -n 1)"
        done
    done
done
