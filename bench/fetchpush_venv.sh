# Sourced by the scripts that run gymnasium-robotics (bench/fetchpush.sh, bench/align_fetchpush.sh):
# makes (once; skipped when the pinned versions are there) the git-ignored venv bench/.venv-fetchpush
# with, from PyPI, gymnasium-robotics==1.4.2 (pulls in gymnasium, numpy, ...) and mujoco==3.11.0
# (a 3.x pin on purpose: mujoco 4.x breaks FetchPush in gymnasium-robotics 1.4.2), and sets PY to
# its interpreter. Needs ROOT (the repository) and a `log` function.
VENV="$ROOT/bench/.venv-fetchpush"
PY="$VENV/bin/python"
GR_VERSION="1.4.2"
MUJOCO_VERSION="3.11.0"

have_pins() {
    [ -x "$PY" ] && "$PY" - "$GR_VERSION" "$MUJOCO_VERSION" <<'PINS' 2>/dev/null
import sys
from importlib.metadata import version
sys.exit(version("gymnasium-robotics") != sys.argv[1] or version("mujoco") != sys.argv[2])
PINS
}

if have_pins; then
    log "venv $VENV already has gymnasium-robotics==$GR_VERSION mujoco==$MUJOCO_VERSION"
else
    log "creating venv $VENV and installing gymnasium-robotics==$GR_VERSION mujoco==$MUJOCO_VERSION"
    python3 -m venv "$VENV"
    "$PY" -m pip install --quiet --disable-pip-version-check --no-compile \
        "gymnasium-robotics==$GR_VERSION" "mujoco==$MUJOCO_VERSION"
    have_pins || { log "install finished but pinned versions not found in $VENV"; exit 1; }
fi
