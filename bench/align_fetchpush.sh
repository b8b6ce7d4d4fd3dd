#!/usr/bin/env bash
# Alignment with gymnasium-robotics FetchPush-v4 (bench/align_fetchpush.py records its episodes on
# MuJoCo 3.11.0 in the venv of bench/fetchpush_venv.sh):
#   --record  only records the reference, target/align/fetchpush-v4.json, for tests/it/align_mujoco3.rs
#             (every step of every episode within 1e-4 m; `make test-mujoco3` runs both)
#   default   records it, runs that test, replays the reference on both engines (`blockpuzzle
#             align`) and writes the tables to results/align.md and the per-step figures to
#             results/align-mujoco-{3.11.0,2.2.2}.png
# Needs `make setup-mujoco3` (the MuJoCo 3 engine) for the mujoco3 build.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
log() { printf '[align] %s\n' "$*" >&2; }
. "$ROOT/bench/fetchpush_venv.sh"

REF="$ROOT/target/align/fetchpush-v4.json"
REF64="$ROOT/target/align/fetchpush-v4-f64-actions.json"
mkdir -p "$ROOT/target/align"
"$PY" "$ROOT/bench/align_fetchpush.py" --random 4 --scripted 4 --out "$REF" 2>/dev/null
[ "${1:-}" = "--record" ] && exit 0
M3=(--release --features mujoco3 --target-dir "$ROOT/target/mujoco3")
( cd "$ROOT" && BLOCKPUZZLE_ALIGN_REFERENCE="$REF" cargo test "${M3[@]}" --test it align_mujoco3:: -- --nocapture )

"$PY" "$ROOT/bench/align_fetchpush.py" --random 4 --scripted 4 --f64-actions --out "$REF64" 2>/dev/null
OUT="$ROOT/results/align.md"
{
    echo "# Alignment with gymnasium-robotics FetchPush-v4"
    echo
    echo "Made by \`bash bench/align_fetchpush.sh\` on $(date -u +%Y-%m-%d) ($(lscpu | sed -n 's/^Model name: *//p' | head -1))."
    echo "FetchPush-v4 episodes (gymnasium-robotics 1.4.2 on MuJoCo 3.11.0; 4 of random actions, 4 of a scripted"
    echo "push; 50 steps) replayed from the same state with the same actions in the FetchPush-like BlockPuzzle"
    echo "environment (src/episode/align/fetchpush.toml: one 5 cm block of 2 kg, the gripper blocked and not raised, no"
    echo "collision filter). Largest distance over the episode between the two gripper positions and the two"
    echo "block positions."
    echo
    echo "## Same engine: MuJoCo 3.11.0 (\`--features mujoco3\`)"
    echo
    echo '```'
    (cd "$ROOT" && cargo run "${M3[@]}" --quiet -- align --reference "$REF" --plot "$ROOT/results/align-mujoco-3.11.0.png")
    echo '```'
    echo
    echo '![per-step distance on MuJoCo 3.11.0](align-mujoco-3.11.0.png)'
    echo
    echo "FetchPush-v4 scales its float32 action by 0.05 in float32, BlockPuzzle in float64: the residual above"
    echo "(a few 1e-8 m) is that rounding. Stepped with the same actions as float64 (\`--f64-actions\`), the two"
    echo "trajectories are bit-identical:"
    echo
    echo '```'
    (cd "$ROOT" && cargo run "${M3[@]}" --quiet -- align --reference "$REF64")
    echo '```'
    echo
    echo "## The engines' own difference: Debian's MuJoCo 2.2.2 (the default build)"
    echo
    echo '```'
    (cd "$ROOT" && cargo run --release --quiet -- align --reference "$REF" --plot "$ROOT/results/align-mujoco-2.2.2.png")
    echo '```'
    echo
    echo '![per-step distance on MuJoCo 2.2.2](align-mujoco-2.2.2.png)'
} > "$OUT.tmp"
mv "$OUT.tmp" "$OUT"
log "wrote $OUT"
