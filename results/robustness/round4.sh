#!/usr/bin/env bash
# The fourth round of bad input (issue 43): each case runs a command as a new user or a careless
# script would, in a scratch folder, and records its verdict in results/robustness/round4.tsv:
# exit code, seconds, peak memory (KiB), whether it panicked, whether it left anything behind in
# the scratch folder, and the first line it printed on stderr.
#
#   BP=target/release/blockpuzzle bash results/robustness/round4.sh
#
# A case passes when the command exits 0, 1 or 2 (2: a usage error, as clap reports one; never a
# signal), does not panic, ends within its
# 60 s limit, stays under 2 GiB and leaves the scratch folder as it found it (a command that should
# write, such as onto the folder's own null device, writes nothing beside it either). The few
# cases meant to succeed (their output in the folder) are marked "expected" in results/robustness.md.
set -uo pipefail
BP=${BP:-$(pwd)/target/release/blockpuzzle}
BP=$(realpath "$BP")
OUT=${OUT:-$(pwd)/results/robustness/round4.tsv}
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"

# Fixtures: a dump, a tiny suite, a one-epoch run, a FIFO, a read-only file, a folder, a zoo copy.
"$BP" rollout --env BlocksTouch-v0 --policy random --episodes 2 --out d.jsonl >/dev/null
cat > suite.toml <<'TOML'
version = 1
name = "tiny"
summary = "one episode a split"
[[splits.train]]
task = "BlocksTouch-v0"
seed = 0
episodes = 1
[[splits.test]]
task = "BlocksTouch-v0"
seed = 100
episodes = 1
TOML
"$BP" train --env BlocksTouch-v0 --epochs 1 --cycles 1 --batches 1 --test-episodes 1 --hidden 8 --workers 1 \
    --run-dir run >/dev/null 2>&1
"$BP" eval --suite suite.toml --baseline scripted --threads 1 --out result.json >/dev/null
echo mine > ro.txt && chmod 444 ro.txt
mkdir folder
mkdir zoo && cp "$(dirname "$BP")/../../zoo/BlocksTouch-v0-ddpg".* zoo/ 2>/dev/null || true
printf 'epoch,time/env_steps,finals/success\n' > header-only.csv
head -c 100000 /dev/urandom > random.bin
printf 'version = 1\nid = "X-v0"\n[[objects]]\nname = "b"\ncolour = "blue"\n' > noblue.toml
BEFORE=$(mktemp)
snapshot() { find . -mindepth 1 -printf '%p %y %s %m\n' | sort; }
snapshot > "$BEFORE"

printf 'case\tcommand\texit\tseconds\tpeak_kib\tpanicked\tleft_behind\tfirst_line\n' > "$OUT"
n=0
case_() {
    local name=$1; shift
    n=$((n + 1))
    local t0=$(date +%s.%N)
    /usr/bin/time -f '%M' -o mem.txt timeout 60 "$@" > stdout.txt 2> stderr.txt < /dev/null
    local rc=$?
    local secs=$(echo "$(date +%s.%N) - $t0" | bc)
    local mem=$(tail -1 mem.txt 2>/dev/null)
    local panicked=no
    grep -q "panicked" stderr.txt stdout.txt && panicked=yes
    rm -f mem.txt stdout.txt.keep
    local first=$(grep -m1 . stderr.txt | cut -c1-200 | tr '\t' ' ')
    rm -f stdout.txt stderr.txt
    local left=no
    if ! diff -q <(snapshot) "$BEFORE" >/dev/null; then
        left=$(diff <(snapshot) "$BEFORE" | grep '^<' | head -3 | tr '\n' ' ')
        # Put the folder back as it was for the next case.
        for p in $(diff <(snapshot) "$BEFORE" | grep '^<' | awk '{print $2}'); do rm -rf "$p"; done
    fi
    local cmd=$(printf '%q ' "$@" | sed "s#$BP#blockpuzzle#g")
    printf '%s\t%s\t%s\t%.2f\t%s\t%s\t%s\t%s\n' "$name" "$cmd" "$rc" "$secs" "$mem" "$panicked" "$left" "$first" >> "$OUT"
}

# 1. Outputs that are not regular files, or not ours. The devices are this folder's own (made with
# mknod where this is root): a build with the old writer would replace what it is given, so the
# script never points one at the machine's /dev.
if mknod dev-null.json c 1 3 2>/dev/null; then
    for ext in md jsonl gif; do mknod dev-null.$ext c 1 3; done
    for ext in json md jsonl gif png; do mknod dev-full.$ext c 1 7; done
    DEVICES=yes
else
    echo "not root: the device cases are left out" >&2
    DEVICES=no
fi
for ext in gif png json; do mkfifo fifo.$ext; echo mine > ro.$ext; chmod 444 ro.$ext; done
ln -s /proc/self/fd/1 stdout-link.jsonl
ln -s nowhere/x.json dangling.json
snapshot > "$BEFORE"
case_ "eval onto a FIFO nobody reads" "$BP" eval --checkpoint BlocksTouch-v0-ddpg --episodes 1 --out fifo.json
case_ "eval --suite onto a folder" "$BP" eval --suite suite.toml --baseline scripted --out folder
case_ "eval --suite onto a read-only file" "$BP" eval --suite suite.toml --baseline scripted --out ro.json
case_ "eval onto a link to nowhere" "$BP" eval --checkpoint BlocksTouch-v0-ddpg --episodes 1 --out dangling.json
case_ "eval into a folder that does not exist" "$BP" eval --checkpoint BlocksTouch-v0-ddpg --episodes 1 --out nodir/e.json
case_ "rollout onto a folder" "$BP" rollout --env BlocksTouch-v0 --policy random --episodes 1 --out folder
case_ "rollout onto a link to this process's stdout" "$BP" rollout --env BlocksTouch-v0 --policy random --episodes 1 --out stdout-link.jsonl
case_ "rollout --render onto a read-only GIF" "$BP" rollout --env BlocksTouch-v0 --policy random --episodes 1 --out x.jsonl --render ro.gif
case_ "render onto a FIFO nobody reads" "$BP" render --traj d.jsonl --out fifo.gif
case_ "render frames into an existing file" "$BP" render --traj d.jsonl --width 64 --height 64 --out ro.txt
case_ "render a filmstrip onto a folder path" "$BP" render --traj d.jsonl --filmstrip 2 --out folder/
case_ "table onto a folder" "$BP" table --episodes 1 --out folder
case_ "task check --render onto a read-only PNG" "$BP" task check BlocksTouch-v0 --samples 1 --render ro.png
case_ "plot --overlay onto a FIFO nobody reads" "$BP" plot --overlay run --out fifo.png
case_ "plot --overlay onto a JPEG" "$BP" plot --overlay run --out o.jpg
case_ "leaderboard onto a folder" "$BP" results leaderboard result.json --out folder
case_ "leaderboard onto a read-only file" "$BP" results leaderboard result.json --out ro.json
case_ "zoo export into a file as zoo" "$BP" zoo export --from run --name n --description d --trained-with t --zoo ro.txt
case_ "zoo export with a path as name" "$BP" zoo export --from run --name ../n --description d --trained-with t --zoo z
case_ "zoo export with an empty name" "$BP" zoo export --from run --name "" --description d --trained-with t --zoo z
case_ "train into a read-only file as run dir" "$BP" train --env BlocksTouch-v0 --epochs 1 --run-dir ro.txt
if [ "$DEVICES" = yes ]; then
    case_ "eval --suite onto a null device (no companion .md)" "$BP" eval --suite suite.toml --baseline scripted --threads 1 --out dev-null.json
    case_ "eval --suite onto a full device" "$BP" eval --suite suite.toml --baseline scripted --threads 1 --out dev-full.json
    case_ "rollout onto a full device" "$BP" rollout --env BlocksTouch-v0 --policy random --episodes 1 --out dev-full.jsonl
    case_ "render a GIF onto a null device" "$BP" render --traj d.jsonl --width 64 --height 64 --out dev-null.gif
    case_ "render a GIF onto a full device" "$BP" render --traj d.jsonl --width 64 --height 64 --out dev-full.gif
    case_ "table onto a full device" "$BP" table --episodes 1 --out dev-full.md
    case_ "task check --render onto a full device" "$BP" task check BlocksTouch-v0 --samples 1 --render dev-full.png
    case_ "train with a device as run dir" "$BP" train --env BlocksTouch-v0 --epochs 1 --run-dir dev-null.md
    case_ "zoo export with a device as zoo" "$BP" zoo export --from run --name n --description d --trained-with t --zoo dev-null.md
fi

# 2. Options that the run would not use.
for flags in "--algo sac --noise-eps 0.1" "--algo sac --random-eps 0.5" "--algo sac --action-l2 0" \
    "--algo sac --noise-correlation 0.5" "--target-noise 0.3" "--target-noise-clip 0.4" "--policy-delay 3" \
    "--algo pggd --lr-actor 0.01" "--algo pggd --polyak 0.9" "--algo pggd --precision bf16" \
    "--pg-lr 0.001" "--pg-sigma-min 0.1" "--pg-normalize standardize" "--beta0 0.5" "--algo pggd --t0 10" \
    "--pg-weight expert-advantage" "--set-encoder-layers 3" "--set-pooling attention" "--set-norm" \
    "--hindsight-strategy pairs" "--flat-critic" "--algo sac --td3"; do
    # shellcheck disable=SC2086
    case_ "train $flags" "$BP" train --env BlocksTouch-v0 --epochs 1 --run-dir r2 $flags
done
printf 'env = "BlocksTouch-v0"\nalgo = "sac"\nnoise-eps = 0.1\n' > recipe1.toml
printf 'env = "BlocksTouch-v0"\ntd3 = "yes"\n' > recipe2.toml
printf 'env = "BlocksTouch-v0"\nepochs = true\n' > recipe3.toml
printf 'env = "BlocksTouch-v0"\nepochs = [1, 2]\n' > recipe4.toml
snapshot > "$BEFORE"
case_ "recipe: a DDPG option with SAC" "$BP" train --config recipe1.toml --run-dir r2
case_ "recipe: a switch given a string" "$BP" train --config recipe2.toml
case_ "recipe: a value given true" "$BP" train --config recipe3.toml
case_ "recipe: a list" "$BP" train --config recipe4.toml
case_ "bench --ddpg --set-pooling without --net set" "$BP" bench --ddpg --set-pooling attention --steps 10 --updates 1
case_ "bench --ddpg --algo pggd --precision bf16" "$BP" bench --ddpg --algo pggd --precision bf16 --steps 10
case_ "bench --ddpg --flat-critic with mlp" "$BP" bench --ddpg --flat-critic --steps 10

# 3. Cameras.
for v in "--distance nan" "--distance inf" "--distance 0" "--distance -2" "--distance 1e9" "--elevation 91" \
    "--elevation -inf" "--azimuth nan" "--azimuth inf"; do
    # shellcheck disable=SC2086
    case_ "render $v" "$BP" render --traj d.jsonl --out v.gif $v
done
case_ "rollout --render --distance nan" "$BP" rollout --env BlocksTouch-v0 --policy random --episodes 1 --out y.jsonl --render y.gif --distance nan
case_ "task check --render --elevation 500" "$BP" task check BlocksTouch-v0 --samples 1 --render y.png --elevation 500

# 4. Dumps edited or damaged.
python3 - <<'PY'
import json
lines = open("d.jsonl").read().splitlines()
ep = json.loads(lines[0])
def write(name, e):
    open(name, "w").write(json.dumps(e) + "\n")
e = json.loads(lines[0]); e["task"]["toml"] = e["task"]["toml"].replace("max_episode_steps = 50", "max_episode_steps = 9"); write("edited-task.jsonl", e)
e = json.loads(lines[0]); e["objects"][2]["name"] = "purple"; write("edited-objects.jsonl", e)
e = json.loads(lines[0]); e["objects"] = e["objects"][:2]; write("fewer-objects.jsonl", e)
e = json.loads(lines[0]); e["env_id"] = "BlocksChoose-v0"; write("edited-id.jsonl", e)
e = json.loads(lines[0]); e["initial"]["qpos"] = e["initial"]["qpos"][:3]; write("short-qpos.jsonl", e)
e = json.loads(lines[0]); e["initial"]["qpos"][0] = 1e308 * 10 if False else 1e308; write("huge-qpos.jsonl", e)
e = json.loads(lines[0]); e["steps"] = []; write("no-steps.jsonl", e)
open("cut.jsonl", "w").write(lines[0][: len(lines[0]) // 2])
open("empty.jsonl", "w").write("")
open("not-json.jsonl", "w").write("hello\n")
PY
snapshot > "$BEFORE"
for f in edited-task edited-objects fewer-objects edited-id short-qpos huge-qpos no-steps cut empty not-json; do
    case_ "render a dump: $f" "$BP" render --traj $f.jsonl --width 64 --height 64 --out r.gif
done
case_ "render episode 99 of 2" "$BP" render --traj d.jsonl --episode 99 --out r.gif
case_ "render a folder as dump" "$BP" render --traj folder --out r.gif
case_ "render a FIFO as dump (no writer)" "$BP" render --traj fifo.json --out r.gif
case_ "render a binary file as dump" "$BP" render --traj random.bin --out r.gif

# 5. Odd run directories and inputs.
case_ "report a folder without a run" "$BP" report folder
case_ "plot a header-only log" "$BP" plot --overlay header-only.csv --out o.png
case_ "plot a JSON file as log" "$BP" plot --overlay result.json --out o.png
case_ "plot a binary file as log" "$BP" plot --overlay random.bin --out o.png
case_ "report a missing run" "$BP" report nothere
case_ "eval a folder as policy" "$BP" eval --checkpoint folder --episodes 1
case_ "eval a binary file as policy" "$BP" eval --checkpoint random.bin --episodes 1
case_ "eval a suite that is a folder" "$BP" eval --suite folder --baseline scripted
case_ "task check a folder" "$BP" task check folder
case_ "task check a task with no blue at minimum count" "$BP" task check noblue.toml
case_ "results compare a run's config" "$BP" results compare run/config.json result.json
case_ "results compare one file" "$BP" results compare result.json
case_ "results leaderboard of a folder with no results" "$BP" results leaderboard folder
case_ "zoo check a zoo that is a file" "$BP" zoo check --zoo ro.txt
case_ "zoo list of a missing zoo" "$BP" zoo list --zoo nothere
case_ "zoo evaluate an unknown name" "$BP" zoo evaluate nope --zoo zoo
for edit in 's/name = "tiny"/name = ""/' 's/name = "tiny"/name = "..\/up"/' 's/name = "tiny"/name = ".hidden"/' \
    's/episodes = 1/episodes = 0/' 's/seed = 100/seed = 0/' 's/version = 1/version = 2/' 's/task = "BlocksTouch-v0"/task = "Nope-v0"/' \
    's/episodes = 1/episodes = -1/' 's/seed = 0/seed = 18446744073709551615/'; do
    sed "$edit" suite.toml > bad-suite.toml; snapshot > "$BEFORE"
    case_ "suite: $edit" "$BP" eval --suite bad-suite.toml --baseline scripted --threads 1 --out bs.json
done
cp suite.toml dup-suite.toml; printf '[[splits.test]]\ntask = "BlocksTouch-v0"\nseed = 100\nepisodes = 1\n' >> dup-suite.toml
snapshot > "$BEFORE"
case_ "suite: a test row twice" "$BP" eval --suite dup-suite.toml --baseline scripted --out bs.json
for edit in 's/count = \[1, 3\]/count = [1, 3, 9]/' 's/count = \[1, 3\]/count = [3]/' 's/count = \[1, 3\]/count = [3, 1]/' \
    's/count = \[1, 3\]/count = [1, 1000000]/' 's/max_episode_steps = 50/max_episode_steps = 0/'; do
    sed "$edit" "$(dirname "$BP")/../../tasks/BlocksAvoid-v0.toml" > bad-task.toml; snapshot > "$BEFORE"
    case_ "task: $edit" "$BP" task check bad-task.toml --samples 1
done
snapshot > "$BEFORE"

# 6. Unbounded input.
truncate -s 1G huge.toml; snapshot > "$BEFORE"
case_ "a 1 GiB suite" "$BP" eval --suite huge.toml --baseline scripted
case_ "a 1 GiB task" "$BP" task check huge.toml
case_ "a 1 GiB recipe" "$BP" train --config huge.toml
case_ "a 1 GiB result" "$BP" results compare huge.toml huge.toml
case_ "a 1 GiB policy" "$BP" eval --checkpoint huge.toml --episodes 1
head -c 3000000 /dev/zero | tr '\0' a > long.toml; snapshot > "$BEFORE"
case_ "a 3 MB one-line suite" "$BP" eval --suite long.toml --baseline scripted
case_ "a 3 MB one-line task" "$BP" task check long.toml
case_ "a 3 MB one-line recipe" "$BP" train --config long.toml
case_ "a 100 kB env id" "$BP" rollout --env "$(head -c 100000 /dev/zero | tr '\0' a)" --out z.jsonl
rm -f huge.toml long.toml; snapshot > "$BEFORE"

# 7. Messages and odd arguments.
case_ "info into a closed pipe" bash -c "'$BP' info | head -c 1"
case_ "env ids into a closed pipe" bash -c "'$BP' task list 2>/dev/null | head -c 1; '$BP' --help | head -c 1"
case_ "eval --episodes 0" "$BP" eval --checkpoint BlocksTouch-v0-ddpg --episodes 0
case_ "eval --threads 0" "$BP" eval --checkpoint BlocksTouch-v0-ddpg --episodes 1 --threads 0
case_ "rollout --seed -1" "$BP" rollout --env BlocksTouch-v0 --policy random --episodes 1 --seed -1 --out s.jsonl
case_ "rollout --level 99" "$BP" rollout --env BlocksTouch-v0 --policy random --episodes 1 --level 99 --out s.jsonl
case_ "rollout an unknown policy" "$BP" rollout --env BlocksTouch-v0 --policy nope --episodes 1 --out s.jsonl
case_ "train --resume a run with --counts changed" "$BP" train --env BlocksTouch-v0 --epochs 2 --run-dir run --counts grey=0-2 --resume
case_ "train --resume with another --hidden" "$BP" train --env BlocksTouch-v0 --epochs 2 --run-dir run --hidden 9 --cycles 1 --batches 1 --test-episodes 1 --workers 1 --resume
case_ "report --target 2" "$BP" report run --target 2
case_ "eval --env of another observation size" "$BP" eval --checkpoint BlocksTouch-v0-ddpg --env BlocksChooseN-v0 --episodes 1
case_ "render --fps 0" "$BP" render --traj d.jsonl --fps 0 --out f.gif
case_ "render --filmstrip 1000" "$BP" render --traj d.jsonl --filmstrip 1000 --out f.png
case_ "render --width 100000" "$BP" render --traj d.jsonl --width 100000 --out f.gif
case_ "an unknown subcommand" "$BP" evaluate
case_ "a non-UTF-8 path" "$BP" rollout --env BlocksTouch-v0 --policy random --episodes 1 --out "$(printf 'x\377.jsonl')"

echo "$n cases -> $OUT"
