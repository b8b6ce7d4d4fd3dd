#!/usr/bin/env bash
# The gallery (issue 77): one animated GIF of the solver on each built-in task, and on two tasks
# each family draws (generator seeds 0 and 1), in docs/gallery/, and docs/gallery.md, the page that
# shows them with each task's name, summary and outcome. One command rebuilds every picture:
#   bash scripts/gallery.sh            (after `cargo build --release`; BIN=... for another binary)
# The episodes start from seed 1,000,000 (the evaluation seeds' first) at the task's evaluation
# level; the pictures are small (160 x 160, at most 16 frames of the episode), so that the whole
# gallery stays a few MB. Whatever the outcome, it is shown: the gallery is no highlight reel.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${BIN:-$ROOT/target/release/blockpuzzle}"
OUT="$ROOT/docs/gallery"
PAGE="$ROOT/docs/gallery.md"
SEED=1000000
VIEW=(--width 160 --height 160 --distance 1.6 --max-frames 16 --fps 5 --no-caption)
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
mkdir -p "$OUT"
rm -f "$OUT"/*.gif

# One episode of the solver on task $1 (an id or a task file), rendered to docs/gallery/$2.gif;
# prints its outcome (success, failure or unfinished).
episode() {
    "$BIN" rollout --env "$1" --policy scripted --episodes 1 --seed "$SEED" --out "$WORK/$2.jsonl" \
        --render "$OUT/$2.gif" "${VIEW[@]}" > /dev/null
    python3 - "$WORK/$2.jsonl" <<'EOF'
import json, sys
r = json.loads(open(sys.argv[1]).readline())
print("success" if r["success"] else "failure" if r["failure"] else "unfinished", len(r["steps"]))
EOF
}

{
    echo "# Gallery"
    echo
    engine="$("$BIN" info | sed -n 's/^MuJoCo \([0-9.]*\).*/\1/p')"
    commit="$("$BIN" info | sed -n 's/^commit \(.\{7\}\).*/\1/p')"
    echo "The scripted solver (\`--policy scripted\`) playing one episode of every built-in task, and of two"
    echo "tasks each task family draws: red must not touch blue, and every blue must touch a green."
    echo "[environments.md](environments.md) describes the tasks, [task-format.md](task-format.md) the files"
    echo "and families."
    echo
    echo "Made by \`bash scripts/gallery.sh\` (MuJoCo $engine, commit $commit): seed $SEED, each task's"
    echo "evaluation level, at most 16 frames of each episode."
    echo
    echo "## Built-in tasks"
    echo
    echo "| | task | what it asks | solver |"
    echo "|---|---|---|---|"
    "$BIN" envs | while read -r id _ _ _ _ summary; do
        read -r outcome steps < <(episode "$id" "$id")
        echo "| ![$id](gallery/$id.gif) | \`$id\` | $summary | $outcome in $steps steps |"
    done
    echo
    echo "## Task families"
    echo
    echo "Two draws of each family (\`blockpuzzle task generate FAMILY --seed 0 --count 2\`)."
    echo
    echo "| | task | what it draws | solver |"
    echo "|---|---|---|---|"
    for family in "$ROOT"/families/*.toml; do
        name="$(basename "$family" .toml)"
        "$BIN" task generate "$name" --seed 0 --count 2 --out "$WORK/$name" > /dev/null 2>&1
        for task in "$WORK/$name"/*.toml; do
            id="$(basename "$task" .toml)"
            summary="$(sed -n 's/^summary = "\(.*\)"$/\1/p' "$task" | head -n 1)"
            read -r outcome steps < <(episode "$task" "$id")
            echo "| ![$id](gallery/$id.gif) | \`$id\` | $summary | $outcome in $steps steps |"
        done
    done
} > "$PAGE.tmp"
mv "$PAGE.tmp" "$PAGE"
# The README's opening picture: four of the tasks side by side in one GIF (examples/reel.rs).
REEL=()
for id in BlocksAvoid-v0 ToppleTower-v0 BlocksStack-v0 BlocksGather-v0; do REEL+=("$OUT/$id.gif"); done
(cd "$ROOT" && cargo run --release --quiet --example reel -- "$OUT/reel.gif" 5 "${REEL[@]}")
echo "wrote $PAGE and $(ls "$OUT"/*.gif | wc -l) GIFs ($(du -sh "$OUT" | cut -f1)) in $OUT"
