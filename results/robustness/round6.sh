#!/usr/bin/env bash
# The sixth round of bad input (issue 74): each case runs a command as a new user or a careless
# script would, in a scratch folder, and records in results/robustness/round6.tsv its exit code,
# seconds, whether it panicked, what it left behind, the words its message had to hold, its verdict
# and the first line it printed on stderr. The harness (case_, verdicts) is round 5's, in harness.sh.
#
#   BP=target/release/blockpuzzle bash results/robustness/round6.sh
#
# Each case covers one class of issue 74 (held-out material, records checked instead of trusted,
# options that do nothing, misworded messages, leftovers); the words are the ones its message must
# hold to name the problem and the fix.
set -uo pipefail
BP=${BP:-$(pwd)/target/release/blockpuzzle}
BP=$(realpath "$BP")
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
OUT=${OUT:-$ROOT/results/robustness/round6.tsv}
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"
unset BLOCKPUZZLE_ZOO
export BLOCKPUZZLE_CACHE_DIR="$W/cache"

# Fixtures: a tiny suite, a one-epoch run, a one-epoch stream run, a zoo copy, family files, a FIFO,
# a one-level task, demos of a test split.
cat > suite.toml <<'TOML'
version = 1
name = "tiny"
summary = "one episode a split"
[[splits.train]]
task = "BlocksTouch-v0"
seed = 0
episodes = 2
[[splits.test]]
task = "BlocksTouch-v0"
seed = 100
episodes = 2
TOML
TINY=(--epochs 1 --cycles 1 --batches 1 --test-episodes 1 --hidden 8 --workers 1)
STREAM=(--algo dagger --net entity --set-width 8 --epochs 1 --cycles 1 --batches 1 --batch-size 8 --test-episodes 1 --workers 1)
"$BP" train --env BlocksTouch-v0 "${TINY[@]}" --run-dir run >/dev/null 2>&1
"$BP" train --families push --generator-seeds 0..2 "${STREAM[@]}" --run-dir stream >/dev/null 2>&1
"$BP" demos --suite suite.toml --split test --episodes 1 --out test-demos.safetensors >/dev/null 2>&1
mkdir zoo
for e in BlocksTouch-v0-ddpg ToppleTower-v0-td3-finetuned; do cp "$ROOT/zoo/$e".json "$ROOT/zoo/$e".safetensors zoo/; done
sed 's/^family = "push"/family = "my-push"/' "$ROOT/families/push.toml" > my-push.toml
sed 's/max_level = 5/max_level = 0/; s/BlocksTouch-v0/OneLevel-v0/' "$ROOT/tasks/BlocksTouch-v0.toml" > one-level.toml
mkfifo fifo.safetensors
python3 - <<'EOF'
import json, pathlib
def zedit(name, f, src="BlocksTouch-v0-ddpg"):
    v = json.loads(pathlib.Path(f"zoo/{src}.json").read_text()); f(v)
    pathlib.Path(f"zoo/{name}.json").write_text(json.dumps(v, indent=1))
    pathlib.Path(f"zoo/{name}.safetensors").write_bytes(pathlib.Path(f"zoo/{src}.safetensors").read_bytes())
def rate(v): v["evaluations"][0]["success_rate"] = 0.999
zedit("eval-rate", rate)
def episodes(v): v["evaluations"][0]["episodes"] = 10**15
zedit("eval-episodes", episodes)
def engine(v): v["evaluations"][0].setdefault("provenance", {})["mujoco"] = "9.9.9"
zedit("eval-engine", engine)
def relabel(v): v["format"] = "blockpuzzle-zoo/5"; v.pop("meta_sha256")
zedit("relabelled", relabel)
zedit("bad-seal", lambda v: v.__setitem__("meta_sha256", "d41d8cd98f00b204"))
p = json.loads(pathlib.Path("run/policy.json").read_text()); p["algo"] = "ppo"
pathlib.Path("ppo.json").write_text(json.dumps(p))
c = json.loads(pathlib.Path("run/config.json").read_text())
EOF
cp -r run edited-config && python3 -c "
import json, pathlib
p = pathlib.Path('edited-config/config.json'); c = json.loads(p.read_text()); c['seed'] = 7; p.write_text(json.dumps(c, indent=2))"
BEFORE=$(mktemp)
snapshot() { find . -mindepth 1 -not -path './cache*' -printf '%p %y %s\n' | sort; }
snapshot > "$BEFORE"

source "$ROOT/results/robustness/harness.sh"

# 1. Held-out material does not reach training.
case_ "a renamed copy of push on procgen's test seeds" "refuse:held out by;give generator seeds" \
    "$BP" train --families my-push.toml --generator-seeds 1000..1008 "${STREAM[@]}" --run-dir t1
case_ "demos of a suite's test split in a run" "refuse:test split;suite" \
    "$BP" train --env BlocksTouch-v0 --net entity "${TINY[@]}" --demos test-demos.safetensors --run-dir t2

# 2. Records checked, not trusted.
for e in eval-rate eval-episodes eval-engine relabelled; do
    case_ "zoo check: $e" "refuse:$e.json;restore|again|evaluate" "$BP" zoo check "$e" --zoo zoo
done
case_ "zoo check: a seal that is no hash" "refuse:not a content hash;restore" "$BP" zoo check bad-seal --zoo zoo
case_ "zoo upgrade seals no relabelled entry" "refuse:relabelled|introduced" "$BP" zoo upgrade relabelled --zoo zoo
case_ "zoo upgrade --algo pggd of a DDPG entry" "refuse:records ddpg|does not train" \
    "$BP" zoo upgrade BlocksTouch-v0-ddpg --algo pggd --zoo zoo
case_ "resume of an edited config.json" "refuse:config|seal|settings" \
    "$BP" train --resume --run-dir edited-config --epochs 2
case_ "--init-from a policy file recording algo ppo" "refuse:ppo" \
    "$BP" train --env BlocksTouch-v0 "${TINY[@]}" --init-from ppo.json --run-dir t3
case_ "blend of unrelated policies" "refuse:fine-tuned|started" \
    "$BP" blend --base run --tuned "$ROOT/zoo/BlocksTouch-v0-ddpg.json" --weight 0.5 --out b.json

# 3. Options that do nothing.
case_ "--families with an empty item" "refuse:item 2;empty" \
    "$BP" train --families push, --generator-seeds 0..2 "${STREAM[@]}" --run-dir t4
case_ "--level-replay on a task of one level" "refuse:one curriculum level;leave --level-replay out" \
    "$BP" train --env one-level.toml --level-replay 0.3 "${TINY[@]}" --run-dir t5
case_ "a TD3 warm-up that leaves the actor no update" "refuse:--policy-delay;never learn" \
    "$BP" train --env ToppleTower-v0 --init-from generalist-bc-entity --net entity --set-width 64 --td3 \
    --critic-warmup 3 --epochs 1 --cycles 1 --batches 4 --test-episodes 1 --workers 1 --run-dir t6
case_ "--episodes-per-row without --suite" "refuse:--suite" \
    "$BP" eval --checkpoint BlocksTouch-v0-ddpg --episodes-per-row 2

# 4. Unbounded and partial.
case_ "--demos of a FIFO" "refuse:pipe|FIFO" \
    "$BP" train --env BlocksTouch-v0 --net entity "${TINY[@]}" --demos fifo.safetensors --run-dir t7
case_ "a branch refused at its start leaves nothing" "refuse:--level-replay" \
    "$BP" train --env BlocksTouch-v0 "${TINY[@]}" --epochs 2 --level-replay 2 --branch-from run --run-dir child

# 5. Figures and the table.
case_ "table: a fine-tuned TD3 of ToppleTower-v0 as DDPG (3 blocks)" "refuse:trained by td3" \
    "$BP" table --ddpg "$ROOT/zoo/ToppleTower-v0-td3-finetuned.json" --episodes 1 --out t.md
case_ "zoo describe with a figure" "refuse:figure;zoo list" \
    "$BP" zoo describe BlocksTouch-v0-ddpg --description "solves 0.95 of episodes" --zoo zoo
case_ "zoo export with a figure" "refuse:figure" "$BP" zoo export --from run --name y --description "a 50% gain" \
    --trained-with t --zoo zoo

# 6. Misworded: a folder, pipe or empty file named as what it is; a default not called a flag given.
mkdir -p a-folder && : > empty.json
snapshot > "$BEFORE"
case_ "zoo check of a FIFO here" "refuse:is a pipe \\(FIFO\\) here, not the name of a zoo entry;zoo list" \
    "$BP" zoo check fifo.safetensors --zoo zoo
case_ "zoo check of a folder here" "refuse:is a folder here;zoo list" "$BP" zoo check a-folder --zoo zoo
case_ "task check of a folder" "refuse:is a folder; give the task file itself" "$BP" task check a-folder
case_ "eval --checkpoint of a folder that holds no run" "refuse:neither best_policy.json nor policy.json;run directory" \
    "$BP" eval --env BlocksTouch-v0 --checkpoint a-folder --episodes 1
case_ "plot --run-dir of a folder that holds no run" "refuse:holds no run;train --run-dir" \
    "$BP" plot --run-dir a-folder
case_ "eval --checkpoint of an empty file" "refuse:is empty;policy.json" \
    "$BP" eval --env BlocksTouch-v0 --checkpoint empty.json --episodes 1
case_ "--demos with no --net given" "refuse:mlp \\(--net's default\\);--net entity" \
    "$BP" train --env BlocksTouch-v0 "${TINY[@]}" --demos test-demos.safetensors --run-dir t8

# 7. Work on stream runs, and the cache.
case_ "report of a stream run" accept "$BP" report stream
case_ "plot of a stream run" accept "$BP" plot --run-dir stream
snapshot > "$BEFORE"

summary
