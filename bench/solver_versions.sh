#!/usr/bin/env bash
# The solver of two builds side by side (issue 73): every built-in task (normal, and its challenge
# where it has one) and the procgen-v2 suite, played by `--baseline scripted` of each binary with
# the same seeds. Usage: bench/solver_versions.sh OLD_BINARY NEW_BINARY OUT_DIR [EPISODES]
# Writes OUT_DIR/{old,new}/*.json (the evaluations, each with its provenance); tabulate them with
# bench/solver_table.py OUT_DIR. SIDES=new plays the new binary's side alone (the old side kept).
set -euo pipefail
old=$1 new=$2 out=$3 episodes=${4:-500}
mkdir -p "$out/old" "$out/new"
tasks=$("$new" envs | awk '{print $1}')
for side in ${SIDES:-old new}; do
    bin=${!side}
    for t in $tasks; do
        "$bin" eval --env "$t" --baseline scripted --episodes "$episodes" --seed 3000000 --threads 2 \
            --out "$out/$side/$t.normal.json" | tail -1
        if "$bin" eval --env "$t" --baseline scripted --episodes 1 --challenge --threads 1 --out "$out/probe.json" >/dev/null 2>&1; then
            "$bin" eval --env "$t" --baseline scripted --episodes "$episodes" --seed 3000000 --challenge --threads 2 \
                --out "$out/$side/$t.challenge.json" | tail -1
        fi
    done
    "$bin" eval --suite procgen-v2 --baseline scripted --threads 2 --out "$out/$side/procgen-v2.json" | tail -1
done
rm -f "$out/probe.json"
