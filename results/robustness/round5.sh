#!/usr/bin/env bash
# The fifth round of bad input (issue 60): each case runs a command as a new user or a careless
# script would, in a scratch folder, and records in results/robustness/round5.tsv its exit code,
# seconds, whether it panicked, what it left behind, the words its message had to hold, its verdict
# and the first line it printed on stderr.
#
#   BP=target/release/blockpuzzle bash results/robustness/round5.sh
#
# Each case says what it expects: `refuse WORDS` (exit 1 or 2, a message matching each of the
# extended regular expressions WORDS, separated by '|' inside one alternative group when given as
# (a|b), and nothing left behind) or `accept` (exit 0). Verdicts, in the order checked:
#   panic     the message holds "panicked"
#   hang      the 60 s limit killed it
#   partial   a refused case left something in the scratch folder
#   accepted  a case that must be refused exited 0 ("wrongly accepted")
#   refused   a case that must succeed did not
#   misworded refused, but its message lacks one of the words that name the problem and the fix
#   clear     what the case expects
# The summary (printed, and in results/robustness.md) counts them.
set -uo pipefail
BP=${BP:-$(pwd)/target/release/blockpuzzle}
BP=$(realpath "$BP")
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
OUT=${OUT:-$ROOT/results/robustness/round5.tsv}
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"
unset BLOCKPUZZLE_ZOO

# Fixtures: a tiny suite and its result, a dump, a one-epoch run, a flat run of two tasks, a zoo copy,
# a family file, FIFOs.
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
"$BP" eval --suite suite.toml --baseline scripted --threads 1 --out result.json >/dev/null
"$BP" rollout --env BlocksTouch-v0 --policy scripted --episodes 1 --out d.jsonl >/dev/null
TINY=(--epochs 1 --cycles 1 --batches 1 --test-episodes 1 --hidden 8 --workers 1)
"$BP" train --env BlocksTouch-v0 "${TINY[@]}" --run-dir run >/dev/null 2>&1
"$BP" train --env GripperTouch-v0,BlocksChoose-v0 "${TINY[@]}" --run-dir flat2 >/dev/null 2>&1
mkdir zoo
for e in cross-task-v2-dagger-entity BlocksTouch-v0-ddpg; do cp "$ROOT/zoo/$e".json "$ROOT/zoo/$e".safetensors zoo/; done
cp "$ROOT/families/push.toml" push.toml
sed 's/gripper = \["grey"\]/gripper = ["green"]/' push.toml > green-gripper.toml
mkfifo fifo.toml fifo.jsonl
echo mine > file.txt
mkdir folder
python3 - <<'EOF'
import json, pathlib
r = json.loads(pathlib.Path("result.json").read_text())
def edit(name, f):
    v = json.loads(json.dumps(r)); f(v); pathlib.Path(name).write_text(json.dumps(v))
edit("r-score.json", lambda v: v.__setitem__("score", 0.123))
edit("r-gap.json", lambda v: v.__setitem__("gap", -5.0))
edit("r-negative.json", lambda v: v.__setitem__("score", -1.0))
def huge(v): v["splits"][0]["rows"][0]["episodes"] = 10**15
edit("r-episodes.json", huge)
edit("r-splits.json", lambda v: v.__setitem__("splits", []))
def successes(v):
    e = v["splits"][1]["rows"][0]["evaluation"]; e["successes"] = e["episodes"] + 3
edit("r-successes.json", successes)
def rate(v): v["splits"][1]["rows"][0]["evaluation"]["success_rate"] = 0.999
edit("r-rate.json", rate)
def mean(v): v["splits"][1]["mean_success"] = 0.5
edit("r-mean.json", mean)
def seed(v): v["splits"][1]["rows"][0]["seed"] = 7
edit("r-seed.json", seed)
z = json.loads(pathlib.Path("zoo/cross-task-v2-dagger-entity.json").read_text())
def zedit(name, f):
    v = json.loads(json.dumps(z)); f(v)
    pathlib.Path(f"zoo/{name}.json").write_text(json.dumps(v, indent=1))
    pathlib.Path(f"zoo/{name}.safetensors").write_bytes(pathlib.Path("zoo/cross-task-v2-dagger-entity.safetensors").read_bytes())
zedit("no-multi", lambda v: v.pop("multi_task"))
zedit("no-tasks", lambda v: v["multi_task"].__setitem__("tasks", []))
zedit("label-path", lambda v: v["multi_task"].__setitem__("label", "../../x y"))
zedit("sizes", lambda v: v["actor"]["sizes"].__setitem__(1, 128))
zedit("no-seal", lambda v: v.pop("meta_sha256"))
zedit("slots", lambda v: v["actor"]["set"].__setitem__("slots", 11))
zedit("other-eval", lambda v: v["evaluations"][0]["provenance"]["policy"].__setitem__("sha256", "sha256:" + "0" * 64))
pathlib.Path("zoo/lone.json").write_text(pathlib.Path("zoo/BlocksTouch-v0-ddpg.json").read_text())
d = json.loads(pathlib.Path("d.jsonl").read_text().splitlines()[0])
blue = next(i for i, o in enumerate(d["objects"]) if o["colour"] == "blue")
d["objects"][blue]["absent"] = True
d["success"] = True
pathlib.Path("d-absent.jsonl").write_text(json.dumps(d) + "\n")
push = pathlib.Path("push.toml").read_text()
families = {
    "nan-yaw": push.replace('start = { around = "gripper", distance = [0, 0.12], density = "area" }',
                            'start = { around = "gripper", distance = [0, 0.12], density = "area", yaw = nan }', 1),
    "distance-reversed": push.replace("distance = [0.12, 0.20]", "distance = [0.20, 0.12]"),
    "distance-negative": push.replace("distance = [0.12, 0.20]", "distance = [-0.1, 0.20]"),
    "around-unknown": push.replace('around = "blue"', 'around = "purple"'),
    "around-itself": push.replace('around = "blue"', 'around = "green"'),
    "no-blue": push.replace('colour = "blue"', 'colour = "grey"'),
    "no-green": push.replace('colour = "green"', 'colour = "grey"'),
    "settle": push.replace("[[blocks]]", "[placement]\nsettle_seconds = 1000\n\n[[blocks]]", 1),
    "runaway": push.replace("episodes = 20", "episodes = 1000").replace("max_candidates = 20", "max_candidates = 1000"),
    "count-three": push.replace("count = [0, 1]", "count = [0, 1, 2]"),
    "size-and-extents": push.replace("size = [0.02, 0.03]", "size = [0.02, 0.03]\nhalf_extents = [0.02, 0.02, 0.04]", 1),
}
for name, text in families.items():
    pathlib.Path(f"fam-{name}.toml").write_text(text)
def suite(name, row):
    pathlib.Path(name).write_text(
        'version = 1\nname = "s"\nsummary = "s"\n[[splits.train]]\n' + row + 'seed = 0\nepisodes = 1\n'
        '[[splits.test]]\ntask = "BlocksTouch-v0"\nseed = 10\nepisodes = 1\n')
suite("s-seeds3.toml", 'family = "push"\ngenerator_seeds = [0, 2, 4]\n')
suite("s-pinned.toml", 'family = "green-gripper.toml"\ngenerator_seeds = [3, 5]\ncandidates = [0, 1]\n')
suite("s-hash.toml", 'family = "push.toml"\ngenerator_seeds = [3, 4]\ncandidates = [0]\nfamily_sha256 = "sha256:' + "0" * 64 + '"\n')
pathlib.Path("r-bad.toml").write_text('env = "BlocksTouch-v0"\nepochs = "ten"\n')
pathlib.Path("r-zero.toml").write_text('env = "BlocksTouch-v0"\nhidden = 0\n')
EOF
mkdir corrupt && cp -r run/. corrupt/ && head -c 999 /dev/urandom > corrupt/checkpoint.bin
cp "$ROOT/tasks/BlocksTouch-v0.toml" touch-copy.toml
BEFORE=$(mktemp)
snapshot() { find . -mindepth 1 -printf '%p %y %s\n' | sort; }
snapshot > "$BEFORE"

source "$ROOT/results/robustness/harness.sh"

# 1. Published numbers: every derived number recomputed, a file that disagrees refused naming the field.
for f in score gap negative episodes splits successes rate mean seed; do
    case_ "results compare: result edited ($f)" "refuse:r-$f.json;restore|record|edited|again" \
        "$BP" results compare result.json "r-$f.json"
done
for f in score gap splits; do
    case_ "results leaderboard: result edited ($f)" "refuse:r-$f.json" "$BP" results leaderboard "r-$f.json" --out lb.md
done

# 2-3. Zoo entries checked as a whole.
for e in no-multi no-tasks label-path sizes no-seal; do
    case_ "zoo check: entry edited ($e)" "refuse:$e.json;restore" "$BP" zoo check "$e" --zoo zoo
done
case_ "zoo check: set layout edited" "refuse:layout .set.;restore" "$BP" zoo check slots --zoo zoo
case_ "zoo check: another policy's evaluation" "refuse:evaluations\[0\];not this one" "$BP" zoo check other-eval --zoo zoo
case_ "zoo check: .json without .safetensors" "refuse:lone.safetensors;missing;copy both" "$BP" zoo check lone --zoo zoo
case_ "eval: a zoo .json without .safetensors" "refuse:lone.safetensors;missing" \
    "$BP" eval --checkpoint zoo/lone.json --episodes 1
"$BP" eval --checkpoint "$ROOT/zoo/BlocksTouch-v0-ddpg.json" --episodes 2 --out other-eval.json >/dev/null
snapshot > "$BEFORE"
case_ "zoo export --eval of another policy" "refuse:not by this policy" "$BP" zoo export --from run --name y \
    --description d --trained-with t --eval other-eval.json --zoo zoo
case_ "zoo export --eval of a suite result" "refuse:suite's result;--env TASK" "$BP" zoo export --from run --name y \
    --description d --trained-with t --eval result.json --zoo zoo
case_ "zoo export: a 300-character name" "refuse:1 to 100 letters;characters" "$BP" zoo export --from run \
    --name "$(printf 'a%.0s' $(seq 300))" --description d --trained-with t --zoo zoo
case_ "BLOCKPUZZLE_ZOO set to a file" "refuse:file.txt;not a folder" \
    env BLOCKPUZZLE_ZOO=file.txt "$BP" zoo list

# 4-5. Training on a test split; the paper table's policy kinds.
case_ "train --suite procgen --split test" "refuse:--split test;--split train" \
    "$BP" train --suite procgen --split test "${TINY[@]}" --run-dir t1
case_ "table: a multi-task policy as DDPG" "refuse:several tasks" \
    "$BP" table --ddpg "$ROOT/zoo/cross-task-v2-dagger-entity.json" --episodes 1 --out t.md

# task generate: families that no draw can fix, runaway work, values that would be dropped.
for f in nan-yaw distance-reversed distance-negative around-unknown around-itself no-blue no-green settle; do
    case_ "task generate: family with $f" "refuse:fam-$f.toml;nothing was written|fam-$f.toml:[0-9]+" \
        "$BP" task generate "fam-$f.toml" --count 1 --out gen
done
case_ "task generate: a million-step check a seed" "refuse:steps;at most 1000000" \
    "$BP" task generate fam-runaway.toml --count 1 --out gen
case_ "task generate: count of three numbers" "refuse:exactly 2" "$BP" task generate fam-count-three.toml --out gen
case_ "task generate: size beside half_extents" "refuse:both .size.;give one" \
    "$BP" task generate fam-size-and-extents.toml --out gen
case_ "task generate: --out a file" "refuse:file.txt" "$BP" task generate push --count 1 --out file.txt
case_ "task generate: the largest seed" accept "$BP" task generate push --seed 18446744073709551615 --count 1 --out gen1
rm -rf gen1; snapshot > "$BEFORE"

# Suites: dropped values, pins the generator would not keep.
case_ "suite: generator_seeds of three numbers" "refuse:exactly 2" \
    "$BP" eval --suite s-seeds3.toml --baseline scripted --out e.json
case_ "suite: a pinned candidate the solver cannot play" "refuse:candidate 0;would not keep;green gripper" \
    "$BP" eval --suite s-pinned.toml --baseline scripted --out e.json
case_ "demos: a pinned candidate the solver cannot play" "refuse:would not keep" \
    "$BP" demos --suite s-pinned.toml --out e.safetensors
case_ "suite: a family edited since pinned" "refuse:family_sha256;task generate" \
    "$BP" eval --suite s-hash.toml --baseline scripted --out e.json

# --env lists.
case_ "train --env with an empty item" "refuse:item 2;empty" "$BP" train --env BlocksTouch-v0,,BlocksChoose-v0 \
    "${TINY[@]}" --run-dir t2
case_ "train --env with a task twice by id" "refuse:twice|once" "$BP" train --env BlocksTouch-v0,BlocksTouch-v0 \
    "${TINY[@]}" --run-dir t3
case_ "train --env with a task twice by content" "refuse:same content" \
    "$BP" train --env BlocksTouch-v0,touch-copy.toml "${TINY[@]}" --run-dir t4

# A flat policy of two tasks plays each, and refuses a task with more blocks.
case_ "eval a flat two-task policy on its smaller task" accept "$BP" eval --checkpoint flat2 --env GripperTouch-v0 \
    --episodes 1 --out e1.json
rm -f e1.json; snapshot > "$BEFORE"
case_ "eval a flat two-task policy on more blocks" "refuse:more blocks;--net set" \
    "$BP" eval --checkpoint flat2 --env BlocksChooseN-v0 --episodes 1 --out e2.json

# Inputs that are FIFOs or devices.
case_ "task check of a FIFO" "refuse:pipe|FIFO" "$BP" task check fifo.toml
case_ "task generate of a FIFO family" "refuse:pipe|FIFO" "$BP" task generate fifo.toml --out gen
case_ "eval --suite of a FIFO" "refuse:pipe|FIFO" "$BP" eval --suite fifo.toml --baseline scripted --out e.json
case_ "render a FIFO dump" "refuse:pipe|FIFO" "$BP" render --traj fifo.jsonl --out r.gif
case_ "train --config of a FIFO" "refuse:pipe|FIFO" "$BP" train --config fifo.toml --run-dir t5
case_ "task check of /dev/null" "refuse:device" "$BP" task check /dev/null

# Misworded before: each message names the field and the fix.
case_ "train --branch-from a corrupt checkpoint" "refuse:corrupt;another run" \
    "$BP" train --env BlocksTouch-v0 "${TINY[@]}" --epochs 2 --branch-from corrupt --run-dir child
if "$BP" train --help | grep -q -- "--expert"; then
    case_ "train bc with --expert" "refuse:--expert;drop --expert" "$BP" train --env BlocksTouch-v0 --algo bc \
        --expert "$ROOT/zoo/BlocksTouch-v0-ddpg.json" "${TINY[@]}" --run-dir t6
fi
case_ "train --run-dir onto a file" "refuse:file.txt;not a folder|is a file" \
    "$BP" train --env BlocksTouch-v0 "${TINY[@]}" --run-dir file.txt
case_ "report of a file" "refuse:run directory|folder" "$BP" report run/config.json
case_ "a recipe's bad value" "refuse:r-bad.toml;epochs;fix the value" "$BP" train --config r-bad.toml --run-dir t7
case_ "a recipe's out-of-range value" "refuse:r-zero.toml;hidden" "$BP" train --config r-zero.toml --run-dir t8
case_ "render a dump with blue marked absent" "refuse:absent;edited" "$BP" render --traj d-absent.jsonl --out a.gif

summary
