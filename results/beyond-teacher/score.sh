#!/usr/bin/env bash
# Issue 62: scores a run's snapshots on its task's 1,000 test episodes, named as the log names them
# (results/beyond-teacher/TASK.ARM-epochN.json for the run runs/beyond/TASK-ARM); a snapshot already
# scored is left as it is. Every score in results/beyond-teacher.md is MuJoCo 2.2.2's, so another
# engine is refused rather than mixed in.
# BP=target/release/blockpuzzle bash results/beyond-teacher/score.sh TASK RUN EPOCH...
# e.g. bash results/beyond-teacher/score.sh BlocksStack-v0 BlocksStack-v0-dagger15-finetune-s0 2 4 6
set -euo pipefail
BP=${BP:-target/release/blockpuzzle}
if [ $# -lt 3 ]; then
  echo "usage: score.sh TASK RUN EPOCH... (e.g. BlocksStack-v0 BlocksStack-v0-finetune-s0 2 4)" >&2
  exit 2
fi
task=$1 run=$2
shift 2
case $run in
  "$task"-*) arm=${run#"$task"-} ;;
  *) echo "score.sh: the run $run is not one of $task (runs/beyond/$task-ARM)" >&2; exit 2 ;;
esac
engine="$("$BP" info | sed -n 's/^MuJoCo \([0-9.]*\).*/\1/p')"
if [ "$engine" != 2.2.2 ]; then
  echo "score.sh: $BP runs MuJoCo $engine; the log's scores are 2.2.2's: use the default build" >&2
  exit 2
fi
for e in "$@"; do
  out=results/beyond-teacher/$task.$arm-epoch$e.json
  [ -e "$out" ] && continue
  "$BP" eval --suite "experiments/beyond-teacher/suites/$task.toml" \
    --checkpoint "runs/beyond/$run/snapshots/epoch-$(printf %04d "$e").json" --threads 1 --out "$out"
done
