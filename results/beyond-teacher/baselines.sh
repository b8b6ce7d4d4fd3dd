#!/usr/bin/env bash
# Issue 62: the solver's and the generalist's scores on each task's 1,000 test episodes
# (the test split of experiments/beyond-teacher/suites/TASK.toml; eval --suite plays its train split,
# the demonstrations' 100 seeds, too), the lines every arm is measured against. They go where the
# leaderboard reads (results/generalization/mujoco-M/, one table per suite: `make leaderboard`),
# named as scripts/generalization.sh names its results (NAME.SUITE.json; the suites are beyond-TASK).
# BP=target/release/blockpuzzle bash results/beyond-teacher/baselines.sh
set -euo pipefail
BP=${BP:-target/release/blockpuzzle}
ENGINE="$("$BP" info | sed -n 's/^MuJoCo \([0-9.]*\).*/\1/p')"
OUT=results/generalization/mujoco-$ENGINE
for t in ToppleTower-v0 BlocksStack-v0 BlocksChoose-v0 clutter-20002-v0 topple-20003-v0; do
  s=experiments/beyond-teacher/suites/$t.toml
  $BP eval --suite $s --baseline scripted --threads 1 --out $OUT/baseline-scripted.beyond-$t.json
  $BP eval --suite $s --checkpoint generalist-bc-entity --threads 1 --out $OUT/generalist-bc-entity.beyond-$t.json
done
