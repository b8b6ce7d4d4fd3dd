#!/usr/bin/env bash
# Every zoo policy, and the two baselines (scripted, obs-hash), on every built-in evaluation suite
# (results/generalization.md):
#   blockpuzzle eval --suite SUITE --checkpoint ZOO_NAME -> results/generalization/ZOO_NAME.SUITE.{json,md}
#   blockpuzzle eval --suite SUITE --baseline NAME       -> results/generalization/baseline-NAME.SUITE.{json,md}
# Usage: bash scripts/generalization.sh [--threads N]   (after `cargo build --release`)
# SUITES="count obstacles" bash scripts/generalization.sh … runs only those suites; POLICIES="A B" only
# those zoo entries, and BASELINES="" no baseline.
# Training runs' snapshots (issue 31's agents): AGENTS="RUN:EPOCH …" evaluates
# runs/RUN/snapshots/epoch-00EPOCH.json on every suite -> results/generalization/agents/RUN-epochEPOCH.SUITE.{json,md},
# keeping results already there; with AGENTS set, no zoo policy or baseline runs unless named too.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="$ROOT/target/release/blockpuzzle"
OUT="$ROOT/results/generalization"
SUITES="${SUITES:-colour layout cross-task count obstacles}"
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
