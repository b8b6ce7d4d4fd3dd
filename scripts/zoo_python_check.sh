#!/usr/bin/env bash
# Reads every zoo entry from Python with numpy alone (no blockpuzzle installed, no torch; the reader
# is python/blockpuzzle/zoo.py) and checks that each reproduces the actions recorded at export
# (examples/python/zoo_policy.py). Installs (once) a venv at .venv-zoo (git-ignored) with a pinned numpy;
# `--venv` only does that (scripts/python_venvs.sh).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv-zoo"
PINS=(numpy==2.2.6)
if ! "$VENV/bin/python" -c "import numpy; assert numpy.__version__ == '2.2.6'" 2>/dev/null; then
    echo "[zoo] creating $VENV with ${PINS[*]}"
    rm -rf "$VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q --disable-pip-version-check --no-compile "${PINS[@]}"
fi
[ "${1:-}" = "--venv" ] && exit 0
"$VENV/bin/python" "$ROOT/examples/python/zoo_policy.py" --check "$ROOT/zoo"

# Set networks (format 3): a few epochs of `train --net set` (mean-max, attention, colour, query, mean-max with
# --set-norm) and of `train --net entity` (the entities rows: the gripper's, table's and floor's too;
# and with --set-robot-tokens and --set-type-norm, trained by DAgger; and with two transformer blocks and
# query pooling over rows narrower than the head (--set-width), by DAgger; and on two tasks at once, by
# DAgger), exported to a scratch zoo, must
# act in numpy as in Rust too; the shipped entries may hold none of them.
# The command line: $BLOCKPUZZLE_BIN, else the newer of target/release and target/debug (`cargo test` builds
# the latter), else a debug build made now.
BP="${BLOCKPUZZLE_BIN:-}"
if [ -z "$BP" ]; then
    for candidate in "$ROOT/target/release/blockpuzzle" "$ROOT/target/debug/blockpuzzle"; do
        if [ -x "$candidate" ] && { [ -z "$BP" ] || [ "$candidate" -nt "$BP" ]; }; then BP="$candidate"; fi
    done
fi
if [ -z "$BP" ]; then (cd "$ROOT" && cargo build --quiet) && BP="$ROOT/target/debug/blockpuzzle"; fi
SCRATCH="$(mktemp -d)"
trap 'rm -rf "$SCRATCH"' EXIT
for variant in mean-max attention colour query mean-max-norm entity entity-tokens-dagger entity-transformer entity-two-tasks; do
    env=BlocksChooseN-v0
    if [ "$variant" = entity ]; then
        flags=(--net entity)
    elif [ "$variant" = entity-tokens-dagger ]; then
        flags=(--net entity --set-robot-tokens --set-type-norm --algo dagger)
    elif [ "$variant" = entity-transformer ]; then
        flags=(--net entity --set-transformer 2 --set-pooling query --set-width 16 --algo dagger)
    elif [ "$variant" = entity-two-tasks ]; then
        # A policy trained on two tasks (zoo format 5's multi_task): its probes in its own layout.
        env=BlocksTouch-v0,BlocksChooseN-v0
        flags=(--net entity --algo dagger)
    else
        flags=(--net set --set-pooling "${variant%-norm}")
        if [ "$variant" != "${variant%-norm}" ]; then flags+=(--set-norm); fi
    fi
    "$BP" train --env "$env" "${flags[@]}" --epochs 1 --cycles 2 --batches 3 \
        --batch-size 32 --hidden 32 --layers 2 --test-episodes 1 --torch-threads 1 \
        --run-dir "$SCRATCH/run-$variant" > /dev/null
    "$BP" zoo export --from "$SCRATCH/run-$variant" --name "set-$variant" --description "zoo_python_check" \
        --trained-with "scripts/zoo_python_check.sh" --zoo "$SCRATCH/zoo" > /dev/null
done
"$VENV/bin/python" "$ROOT/examples/python/zoo_policy.py" --check "$SCRATCH/zoo"
