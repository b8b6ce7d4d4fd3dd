#!/usr/bin/env bash
# Stable-Baselines3 against the Python package: SB3's env checker and a short TD3 run
# (python/tests/test_sb3.py). Opt-in, not part of `make test`: it needs torch, whose PyPI wheel is
# the CUDA build (a ~5 GB venv). Uses bench/.venv-sb3 (the venv of bench/sb3_ddpg.sh, git-ignored;
# created once with its pins) and installs the blockpuzzle wheel (scripts/build_wheel.sh) into it.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/bench/.venv-sb3"
PINS=(stable-baselines3==2.9.2 torch==2.15.0 gymnasium-robotics==1.4.2 mujoco==3.11.0 pytest==9.2.0)
check="import importlib.metadata as m; assert [m.version(p.split('==')[0]) for p in '${PINS[*]}'.split()] == [p.split('==')[1] for p in '${PINS[*]}'.split()]"
if ! "$VENV/bin/python" -c "$check" 2>/dev/null; then
    echo "[sb3] installing ${PINS[*]} into $VENV (torch's CUDA wheel: several GB)"
    [ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q --disable-pip-version-check "${PINS[@]}"
fi
WHEEL="$(bash "$ROOT/scripts/build_wheel.sh")"
"$VENV/bin/pip" install -q --disable-pip-version-check --force-reinstall --no-deps "$WHEEL"
cd "$VENV"
"$VENV/bin/python" -m pytest -q -p no:cacheprovider "$ROOT/python/tests/test_sb3.py" "$@"
