#!/usr/bin/env bash
# Reads every zoo entry from Python with numpy + safetensors alone (no blockpuzzle, no torch)
# and checks that each reproduces the actions recorded at export (examples/python/zoo_policy.py).
# Installs (once) a venv at .venv-zoo (git-ignored) with pinned numpy and safetensors from PyPI.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv-zoo"
PINS=(numpy==2.2.6 safetensors==0.4.5)
if ! "$VENV/bin/python" -c "import numpy, safetensors; assert numpy.__version__ == '2.2.6' and safetensors.__version__ == '0.4.5'" 2>/dev/null; then
    echo "[zoo] creating $VENV with ${PINS[*]}"
    rm -rf "$VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q --disable-pip-version-check "${PINS[@]}"
fi
"$VENV/bin/python" "$ROOT/examples/python/zoo_policy.py" --check "$ROOT/zoo"
