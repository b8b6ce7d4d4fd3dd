#!/usr/bin/env bash
# Issue 62: the blend's weight chosen on validation episodes and tasks, never on the test ones.
# For each W: blend the generalist with the fine-tuned policy TUNED, then score the blend on
# validation-TASK (TASK: ToppleTower-v0 unless given; 500 episodes from seed 2,000,000) and validation-procgen (35 generated
# tasks at generator seeds 30000-30004). The rule, fixed before any of these numbers was seen: the
# largest W whose validation-procgen score is at least 0.8x the generalist's there.
# BP=target/release/blockpuzzle TAG=s1-epoch4 TUNED=runs/beyond/ToppleTower-v0-finetune-s1/snapshots/epoch-0004.json bash results/beyond-teacher/blend-validation.sh 0.4 0.5 0.6 0.7 0.8 1
# BP=target/release/blockpuzzle TASK=BlocksStack-v0 TAG=dagger25-s0-epoch30 TUNED=runs/beyond/BlocksStack-v0-dagger25-finetune-s0/snapshots/epoch-0030.json bash results/beyond-teacher/blend-validation.sh 0.2 0.4 0.5 0.6 0.8 1
set -euo pipefail
BP=${BP:-target/release/blockpuzzle}
: "${TAG:?TAG names the fine-tuned policy in the file names, e.g. s1-epoch4}"
: "${TUNED:?TUNED is the fine-tuned policy file}"
TASK=${TASK:-ToppleTower-v0}
V=experiments/beyond-teacher/suites
OUT=results/beyond-teacher/validation
mkdir -p "$OUT" runs/beyond/probe-blend
for w in "$@"; do
  # ToppleTower-v0's blends kept their first names (TAG-wW); another task's carry it in front.
  if [ "$TASK" = ToppleTower-v0 ]; then name=$TAG; else name=$TASK.$TAG; fi
  p=runs/beyond/probe-blend/$name-w$w.json
  $BP blend --base generalist-bc-entity --tuned "$TUNED" --weight "$w" --out "$p"
  for s in "validation-$TASK" validation-procgen; do
    $BP eval --suite "$V/$s.toml" --checkpoint "$p" --threads 1 --out "$OUT/blend$w-$name.$s.json"
  done
done
