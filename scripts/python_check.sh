#!/usr/bin/env bash
# Builds the Python package (python/, PyO3 + maturin) into a venv and runs its pytest suite,
# Gymnasium's env checker included. Installs (once) .venv-py (git-ignored) with pinned versions
# from PyPI; rebuilds the package every run (cargo keeps python/target incremental).
#
# --mujoco3: the same against MuJoCo 3.11.0 (`make setup-mujoco3`), in .venv-py-mujoco3 with its
# own cargo target folder (python/target-mujoco3), so that the two builds stay apart.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv-py"
BUILD=(--release --quiet)
if [ "${1:-}" = "--mujoco3" ]; then
    VENV="$ROOT/.venv-py-mujoco3"
    BUILD+=(--features mujoco3)
    export CARGO_TARGET_DIR="$ROOT/python/target-mujoco3" BLOCKPUZZLE_EXPECT_MUJOCO=3.11.0
fi
PINS=(maturin==1.16.0 gymnasium==1.4.0 numpy==2.2.6 pytest==9.2.0)
check="import importlib.metadata as m; assert [m.version(p.split('==')[0]) for p in '${PINS[*]}'.split()] == [p.split('==')[1] for p in '${PINS[*]}'.split()]"
if ! "$VENV/bin/python" -c "$check" 2>/dev/null; then
    echo "[python] creating $VENV with ${PINS[*]}"
    rm -rf "$VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q --disable-pip-version-check "${PINS[@]}"
fi
echo "[python] building the blockpuzzle package (python/) into $VENV"
(cd "$ROOT/python" && VIRTUAL_ENV="$VENV" PATH="$VENV/bin:$PATH" maturin develop "${BUILD[@]}")
cd "$ROOT/python"
"$VENV/bin/python" -m pytest -q tests
