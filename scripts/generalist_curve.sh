#!/usr/bin/env bash
# The Procgen curve of issue 59 (results/generalist.md): the generalist's recipe
# (experiments/generalist/stream-dagger.toml: DAgger, entity network 64 wide), EPOCHS epochs (default 10:
# the same env-step budget at every point, about 90,000 env steps) over pools of 21, 70, 259 and 1029
# generated tasks (generator seeds 200..203, 200..210, 200..237, 200..347 of the seven families), each
# run's snapshot of that epoch evaluated on procgen-v2 -> results/generalist/curve-TASKS-sSEED-epochE.procgen-v2.{json,md}
# (the 1029-task point is the generalist's run, runs/generalist-1029-dagger-entity-w64-sSEED, and its
# snapshot). Runs resume where they stopped; finished snapshots and evaluations are kept.
# Usage: SEEDS="0 1" POINTS="3 10 37 147" EPOCHS=10 bash scripts/generalist_curve.sh   (after `cargo build --release`)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${BIN:-$ROOT/target/release/blockpuzzle}"
OUT="$ROOT/results/generalist"
mkdir -p "$OUT"
EPOCHS="${EPOCHS:-10}"
snapshot="snapshots/epoch-$(printf %04d "$EPOCHS").json"
for seed in ${SEEDS:-0 1}; do
    for per_family in ${POINTS:-3 10 37 147}; do
        run="$ROOT/runs/generalist-curve-$per_family-dagger-entity-w64-s$seed"
        # The full pool's point is the generalist's own run (its snapshot of the same epoch).
        [ "$per_family" = 147 ] && run="$ROOT/runs/generalist-1029-dagger-entity-w64-s$seed"
        if [ ! -f "$run/$snapshot" ]; then
            resume=""
            [ -f "$run/checkpoint.bin" ] && resume="--resume"
            "$BIN" train --config "$ROOT/experiments/generalist/stream-dagger.toml" --generator-seeds "200..$((200 + per_family))" \
                --epochs "$EPOCHS" --seed "$seed" --torch-threads 1 --run-dir "$run" $resume
        fi
        tasks="$(python3 -c "import json,sys; print(len(json.load(open(sys.argv[1]))['stream']['tasks']))" "$run/config.json")"
        out="$OUT/curve-$tasks-s$seed-epoch$EPOCHS.procgen-v2.json"
        [ -f "$out" ] || "$BIN" eval --suite procgen-v2 --checkpoint "$run/$snapshot" --threads 1 --out "$out"
    done
done
