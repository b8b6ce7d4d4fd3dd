#!/usr/bin/env bash
# Every zoo policy, and the two baselines (scripted, obs-hash), on every built-in evaluation suite
# (results/generalization.md), into one folder per engine (numbers of different engines differ):
#   blockpuzzle eval --suite SUITE --checkpoint ZOO_NAME -> results/generalization/mujoco-M/ZOO_NAME.SUITE.{json,md}
#   blockpuzzle eval --suite SUITE --baseline NAME       -> results/generalization/mujoco-M/baseline-NAME.SUITE.{json,md}
# where M is the MuJoCo version of the binary: $BIN, by default target/release/blockpuzzle (2.2.2);
# BIN=target/mujoco3/release/blockpuzzle for 3.11.0. Then `make leaderboard` redraws results/leaderboard.md.
# Usage: bash scripts/generalization.sh [--threads N]   (after `cargo build --release`)
# SUITES="count obstacles" bash scripts/generalization.sh … runs only those suites; POLICIES="A B" only
# those zoo entries, and BASELINES="" no baseline.
# Training runs' snapshots (issue 31's agents): AGENTS="RUN:EPOCH …" evaluates
# runs/RUN/snapshots/epoch-00EPOCH.json on every suite -> results/generalization/mujoco-2.2.2/agents/RUN-epochEPOCH.SUITE.{json,md},
# keeping results already there; with AGENTS set, no zoo policy or baseline runs unless named too.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${BIN:-$ROOT/target/release/blockpuzzle}"
ENGINE="$("$BIN" info | sed -n 's/^MuJoCo \([0-9.]*\).*/\1/p')"
[ -n "$ENGINE" ] || { echo "$BIN info names no MuJoCo version" >&2; exit 1; }
OUT="$ROOT/results/generalization/mujoco-$ENGINE"
SUITES="${SUITES:-colour layout cross-task count obstacles procgen compose cross-task-v2 procgen-v2 physics}"
mkdir -p "$OUT"
if [ -n "${AGENTS:-}" ]; then
    POLICIES="${POLICIES:-}"
    BASELINES="${BASELINES:-}"
    mkdir -p "$OUT/agents"
    for agent in $AGENTS; do
        run="${agent%%:*}"
        epoch="${agent##*:}"
        snapshot="$ROOT/runs/$run/snapshots/epoch-$(printf %04d "$epoch").json"
        [ -f "$snapshot" ] || { echo "no snapshot $snapshot (AGENTS takes RUN:EPOCH of runs/RUN/snapshots/)" >&2; exit 1; }
        for suite in $SUITES; do
            out="$OUT/agents/$run-epoch$epoch.$suite.json"
            [ -f "$out" ] && continue
            "$BIN" eval --suite "$suite" --checkpoint "$snapshot" "$@" --out "$out"
        done
    done
fi
POLICIES="${POLICIES-$(ls "$ROOT/zoo" | sed -n 's/\.safetensors$//p')}"
for policy in $POLICIES; do
    for suite in $SUITES; do
        "$BIN" eval --suite "$suite" --checkpoint "$policy" "$@" --out "$OUT/$policy.$suite.json"
    done
done
for baseline in ${BASELINES-scripted obs-hash}; do
    for suite in $SUITES; do
        "$BIN" eval --suite "$suite" --baseline "$baseline" "$@" --out "$OUT/baseline-$baseline.$suite.json"
    done
done
