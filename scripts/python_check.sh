#!/usr/bin/env bash
# Builds the Python package (python/, PyO3 + maturin) into a venv and runs its pytest suite,
# Gymnasium's env checker included. Installs (once) .venv-py (git-ignored) with pinned versions
# from PyPI; rebuilds the package every run (cargo keeps python/target incremental).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv-py"
PINS=(maturin==1.16.0 gymnasium==1.4.0 numpy==2.2.6 pytest==9.2.0)
check="import importlib.metadata as m; assert [m.version(p.split('==')[0]) for p in '${PINS[*]}'.split()] == [p.split('==')[1] for p in '${PINS[*]}'.split()]"
if ! "$VENV/bin/python" -c "$check" 2>/dev/null; then
    echo "[python] creating $VENV with ${PINS[*]}"
    rm -rf "$VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q --disable-pip-version-check "${PINS[@]}"
fi
echo "[python] building the blockpuzzle package (python/) into $VENV"
(cd "$ROOT/python" && VIRTUAL_ENV="$VENV" PATH="$VENV/bin:$PATH" maturin develop --release --quiet)
cd "$ROOT/python"
"$VENV/bin/python" -m pytest -q tests
