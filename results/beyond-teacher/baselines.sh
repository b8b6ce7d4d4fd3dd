#!/usr/bin/env bash
# Issue 62: the solver's and the generalist's scores on each task's 1,000 test episodes
# (the test split of experiments/beyond-teacher/suites/TASK.toml; eval --suite plays its train split, the demonstrations' 100 seeds, too), the lines every arm is measured against.
# BP=target/release/blockpuzzle bash results/beyond-teacher/baselines.sh
set -euo pipefail
BP=${BP:-target/release/blockpuzzle}
for t in ToppleTower-v0 BlocksStack-v0 BlocksChoose-v0 clutter-20002-v0; do
  s=experiments/beyond-teacher/suites/$t.toml
  $BP eval --suite $s --baseline scripted --threads 1 --out results/beyond-teacher/$t.solver.json
  $BP eval --suite $s --checkpoint generalist-bc-entity --threads 1 --out results/beyond-teacher/$t.generalist.json
done
