#!/usr/bin/env bash
# Environment steps/s of a task with a [physics] table that varies everything (issue 76) against the
# same task without one, side by side: BlocksTouch-v0 and its copy with the table, alternated ROUNDS
# times on one thread, one JSON line per run, then the ratio of the medians. The machine, the engine
# and the build come first (`blockpuzzle info`); results/physics.md quotes the output.
# Usage: bash bench/physics_speed.sh [BINARY] [ROUNDS] [STEPS]
set -euo pipefail
BP="${1:-target/release/blockpuzzle}" ROUNDS="${2:-5}" STEPS="${3:-20000}"
cd "$(dirname "$0")/.."
task="$(mktemp -d)/TouchPhysics-v0.toml"
trap 'rm -rf "$(dirname "$task")"' EXIT
sed 's/^id = "BlocksTouch-v0"/id = "TouchPhysics-v0"/' tasks/BlocksTouch-v0.toml > "$task"
cat >> "$task" <<'TOML'

[physics]
friction = [0.5, 2]
torsional_friction = [0.5, 2]
mass = [0.5, 2]
damping = [0.5, 2]
gain = [0.8, 1.25]
solref = [0.8, 1.25]
solimp = [0.95, 1.02]
action_noise = [0, 0.1]
latency = [0, 2]
obs_noise = [0, 0.005]
TOML
"$BP" info
grep -m1 'model name' /proc/cpuinfo || true
lines=()
for round in $(seq "$ROUNDS"); do
    for which in off on; do
        env=BlocksTouch-v0; [ "$which" = on ] && env="$task"
        line="$("$BP" bench --env "$env" --steps "$STEPS" --json | tail -n 1)"
        echo "$round $which $line"
        lines+=("$which $line")
    done
done
printf '%s\n' "${lines[@]}" | python3 -c '
import json, statistics, sys
rates = {"off": [], "on": []}
for line in sys.stdin:
    which, rest = line.split(" ", 1)
    rates[which].append(json.loads(rest)["env_steps_per_s"])
off, on = statistics.median(rates["off"]), statistics.median(rates["on"])
rounds = len(rates["on"])
print(f"median env steps/s: off {off:.0f}, on {on:.0f}; on / off = {on / off:.3f} ({rounds} rounds)")
'
