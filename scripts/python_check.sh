#!/usr/bin/env bash
# The Python package as a user gets it: builds the sdist and from it the manylinux_2_28 wheel
# (scripts/build_wheel.sh: against the mujoco==3.11.0 wheel, repaired by auditwheel without
# libmujoco), installs it into a venv of its own outside the checkout (in $TMPDIR, named by the
# checkout's path: the package's dependencies from PyPI, mujoco, gymnasium-robotics, gymnasium,
# numpy, and the tests' pins, made once; the package is installed anew each run) and runs the
# pytest suite from another folder, with HOME temporary and BLOCKPUZZLE_MODELS_DIR unset, so nothing
# can come from this checkout: the engine is the mujoco package's, the Fetch files are
# gymnasium-robotics', the zoo is the package's. The suite's CLI comparisons run the package's own
# `blockpuzzle` command (or $BLOCKPUZZLE_BIN, a command line built on MuJoCo 3.11.0). `--venv` only
# makes the venv (scripts/python_venvs.sh).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# Outside the checkout: the tests check that nothing the package reads lies in it.
VENV="${TMPDIR:-/tmp}/blockpuzzle-wheel-test-$(printf %s "$ROOT" | sha256sum | cut -c1-12)"
PINS=(pytest==9.2.0 pytest-xdist==3.8.0 gymnasium==1.4.0 numpy==2.2.6 minari==0.5.4 h5py==3.16.0)
# The package's own dependencies, as pyproject.toml declares them.
mapfile -t DEPS < <(python3 -c 'import sys, tomllib; print(*tomllib.load(open(sys.argv[1], "rb"))["project"]["dependencies"], sep="\n")' \
    "$ROOT/python/pyproject.toml")
check="import importlib.metadata as m; assert [m.version(p.split('==')[0]) for p in '${PINS[*]}'.split()] == [p.split('==')[1] for p in '${PINS[*]}'.split()]"
if ! "$VENV/bin/python" -c "$check" 2>/dev/null || ! "$VENV/bin/pip" install -q --disable-pip-version-check --dry-run \
        --no-index "${DEPS[@]}" >/dev/null 2>&1; then
    echo "[python] making $VENV with ${PINS[*]} ${DEPS[*]}"
    rm -rf "$VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q --disable-pip-version-check --no-compile "${PINS[@]}" "${DEPS[@]}"
fi
# The minimum-versions venv: every dependency pyproject.toml gives a floor (`name>=X.Y`) at that
# floor's release line (`name==X.Y.*`), the rest as declared, and the test tools; no Minari (its
# releases need a newer numpy), so its tests skip there. The suite runs in it too, but for the two
# CLI comparisons of test_provenance.py (the Rust outcome counts, the same whatever numpy).
MIN_VENV="$VENV-min"
mapfile -t MIN_DEPS < <(printf '%s\n' "${DEPS[@]}" | sed -E 's/^([A-Za-z0-9_.-]+)>=([0-9]+\.[0-9]+).*/\1==\2.*/')
MIN_PINS=(pytest==9.2.0 pytest-xdist==3.8.0 "${MIN_DEPS[@]}")
if ! "$MIN_VENV/bin/pip" install -q --disable-pip-version-check --dry-run --no-index "${MIN_PINS[@]}" >/dev/null 2>&1; then
    echo "[python] making $MIN_VENV with ${MIN_PINS[*]}"
    rm -rf "$MIN_VENV"
    python3 -m venv "$MIN_VENV"
    "$MIN_VENV/bin/pip" install -q --disable-pip-version-check --no-compile "${MIN_PINS[@]}"
fi
[ "${1:-}" = "--venv" ] && exit 0
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
echo "[python] installing it into $VENV"
"$VENV/bin/pip" uninstall -q -y blockpuzzle 2>/dev/null || true
# Its dependencies are resolved again from its metadata: the wheel must ask for what the venv has.
"$VENV/bin/pip" install -q --disable-pip-version-check --no-compile "$WHEEL" "${PINS[@]}"
mkdir -p "$WORK/home"
cd "$WORK"
# Two pytest workers (pytest-xdist; PYTEST_WORKERS=N for another count), a test at a time to whichever
# is free (the two suite comparisons of test_provenance.py take half a minute each).
env -u BLOCKPUZZLE_MODELS_DIR HOME="$WORK/home" BLOCKPUZZLE_WHEEL_TEST="$ROOT" \
    "$VENV/bin/python" -m pytest -q -p no:cacheprovider -n "${PYTEST_WORKERS:-2}" --dist worksteal \
    "$ROOT/python/tests"
echo "[python] the minimum versions: $("$MIN_VENV/bin/python" -c 'import numpy, gymnasium; print("numpy", numpy.__version__, "gymnasium", gymnasium.__version__)')"
"$MIN_VENV/bin/pip" uninstall -q -y blockpuzzle 2>/dev/null || true
"$MIN_VENV/bin/pip" install -q --disable-pip-version-check --no-compile --no-deps "$WHEEL"
"$MIN_VENV/bin/pip" check >/dev/null || { "$MIN_VENV/bin/pip" check >&2; exit 1; }
rm -rf "$WORK/home" && mkdir -p "$WORK/home"
env -u BLOCKPUZZLE_MODELS_DIR HOME="$WORK/home" BLOCKPUZZLE_WHEEL_TEST="$ROOT" \
    "$MIN_VENV/bin/python" -m pytest -q -p no:cacheprovider -n "${PYTEST_WORKERS:-2}" --dist worksteal \
    -k "not clis_outcome_counts" "$ROOT/python/tests"
