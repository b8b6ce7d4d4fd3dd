#!/usr/bin/env bash
# Every zoo policy on every built-in evaluation suite (results/generalization.md):
# blockpuzzle eval --suite SUITE --checkpoint ZOO_NAME -> results/generalization/ZOO_NAME.SUITE.{json,md}.
# Usage: bash scripts/generalization.sh [--threads N]   (after `cargo build --release`)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="$ROOT/target/release/blockpuzzle"
OUT="$ROOT/results/generalization"
mkdir -p "$OUT"
for policy in $(ls "$ROOT/zoo" | sed -n 's/\.safetensors$//p'); do
    for suite in colour layout cross-task; do
        "$BIN" eval --suite "$suite" --checkpoint "$policy" "$@" --out "$OUT/$policy.$suite.json"
    done
done
