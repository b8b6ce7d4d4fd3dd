#!/usr/bin/env bash
# The filmstrips docs/environments.md and docs/training.md show (results/filmstrip-*.png): the
# solver's episode on each built-in task it pictures, six frames of 320 x 320 (BlocksGather-v0,
# three blue blocks, eight), from seed 1,000,000 (the evaluation seeds' first) at the task's highest
# level, in its challenge distribution where the caption says so; and the DDPG policy's episode of
# docs/training.md. One command rebuilds them all, from a clean build:
#   bash scripts/filmstrips.sh        (after `cargo build --release`; BIN=... for another binary)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${BIN:-$ROOT/target/release/blockpuzzle}"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
SEED=1000000

# The solver on task $1 (extra rollout flags after it), $2 frames.
strip() {
    local id="$1" frames="$2"
    shift 2
    "$BIN" rollout --env "$id" --policy scripted --episodes 1 --seed "$SEED" "$@" --out "$WORK/$id.jsonl" \
        --render "$ROOT/results/filmstrip-$id.png" --filmstrip "$frames" --width 320 --height 320
}
strip ReachAvoid-v0 6
strip ToppleTower-v0 6
strip BlocksStack-v0 6
strip BlocksChooseShuffled-v0 6 --challenge
strip BlocksChooseN-v0 6 --challenge
strip BlocksAvoid-v0 6 --challenge
strip BlocksGather-v0 8
"$BIN" render --policy BlocksChoose-v0-ddpg-ours --env BlocksChoose-v0 --challenge --seed "$SEED" \
    --filmstrip 6 --distance 1.1 --elevation -45 --azimuth 270 --width 360 --height 360 \
    --out "$ROOT/results/filmstrip-BlocksChoose-v0-ddpg-ours.png"
