#!/usr/bin/env bash
# The Python package as a user gets it: builds the sdist and from it the manylinux_2_28 wheel
# (scripts/build_wheel.sh: against the mujoco==3.11.0 wheel, repaired by auditwheel without
# libmujoco), installs it into a fresh venv (with its dependencies from PyPI: mujoco,
# gymnasium-robotics, gymnasium, numpy) and runs the pytest suite from another folder, with HOME
# temporary and BLOCKPUZZLE_MODELS_DIR unset, so nothing can come from this checkout: the engine is
# the mujoco package's, the Fetch files are gymnasium-robotics', the zoo is the package's. The
# suite's CLI comparisons run the package's own `blockpuzzle` command (or $BLOCKPUZZLE_BIN, a
# command line built on MuJoCo 3.11.0).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
WHEEL="$(bash "$ROOT/scripts/build_wheel.sh")"
echo "[python] built $(basename "$WHEEL")"
# The extension keeps no path of the checkout's models (it would read the checkout's Fetch files).
NATIVE="$(mktemp -d)"
trap 'rm -rf "$NATIVE"' EXIT
python3 -c "import sys, zipfile; zipfile.ZipFile(sys.argv[1]).extractall(sys.argv[2])" "$WHEEL" "$NATIVE"
if grep -q -a "$ROOT/models" "$NATIVE"/blockpuzzle/_native*.so; then
    echo "[python] the extension names $ROOT/models: a wheel must not read the checkout's files" >&2
    exit 1
fi
WORK="$(mktemp -d)"
trap 'rm -rf "$NATIVE" "$WORK"' EXIT
echo "[python] installing it into a fresh venv ($WORK/venv)"
python3 -m venv "$WORK/venv"
"$WORK/venv/bin/pip" install -q --disable-pip-version-check "$WHEEL" pytest==9.2.0 pytest-xdist==3.8.0 \
    gymnasium==1.4.0 numpy==2.2.6 minari==0.5.4 h5py==3.16.0
mkdir -p "$WORK/home"
cd "$WORK"
# Two pytest workers (pytest-xdist; PYTEST_WORKERS=N for another count), each test module in one of them.
env -u BLOCKPUZZLE_MODELS_DIR HOME="$WORK/home" BLOCKPUZZLE_WHEEL_TEST="$ROOT" \
    "$WORK/venv/bin/python" -m pytest -q -p no:cacheprovider -n "${PYTEST_WORKERS:-2}" --dist loadscope \
    "$ROOT/python/tests"
