#!/usr/bin/env bash
# Runs bench/python_vector.py in a venv (bench/.venv-pyvec, git-ignored; created once) holding the
# blockpuzzle wheel (scripts/build_wheel.sh: MuJoCo 3.11.0 from the mujoco wheel, reinstalled each
# run) and, from PyPI, gymnasium-robotics==1.4.2 with mujoco==3.11.0 (the recipe of
# bench/fetchpush.sh): both sides on the same engine, the same library file.
# Usage: bash bench/python_vector.sh [--steps N] [--ns 1 2 8]. Run it on an otherwise idle machine.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/bench/.venv-pyvec"
PINS=(gymnasium-robotics==1.4.2 mujoco==3.11.0)
if ! "$VENV/bin/python" -c "import gymnasium_robotics, mujoco; assert mujoco.__version__ == '3.11.0'" 2>/dev/null; then
    echo "[pyvec] creating $VENV with ${PINS[*]}" >&2
    rm -rf "$VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q --disable-pip-version-check "${PINS[@]}"
fi
WHEEL="$(bash "$ROOT/scripts/build_wheel.sh")"
"$VENV/bin/pip" install -q --disable-pip-version-check --force-reinstall --no-deps "$WHEEL"
cd "$VENV"  # away from the checkout: the installed package is the one measured
"$VENV/bin/python" "$ROOT/bench/python_vector.py" "$@"
