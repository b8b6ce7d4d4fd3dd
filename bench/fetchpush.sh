#!/usr/bin/env bash
# Compare env steps/s: gymnasium-robotics FetchPush-v4 (Python, MuJoCo Python bindings)
# against our Rust BlocksTouch-v0, both stepped with uniformly random actions.
#
# Measures, with STEPS steps each (default 20000):
#   (a) FetchPush-v4, one Python process        (bench/fetchpush_steps.py)
#   (b) FetchPush-v4, two Python processes, aggregate steps/s
#   (c) BlocksTouch-v0, `cargo run --release -- bench ... --threads 1` and `--threads 2`
# and prints a markdown table with the BlocksTouch/FetchPush ratios.
#
# Installs (once; skipped when the pinned versions are already there) a Python venv at
# bench/.venv-fetchpush (git-ignored) with, from PyPI:
#   gymnasium-robotics==1.4.2 (pulls in gymnasium, numpy, ...)
#   mujoco==3.11.0  -- a 3.x pin on purpose: mujoco 4.x breaks FetchPush in
#                      gymnasium-robotics 1.4.2.
#
# Usage: bench/fetchpush.sh [STEPS]     (SEED=... overrides the seed, default 0)
# Run it on an otherwise idle machine: anything else using a core skews the 2-way numbers.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/bench/.venv-fetchpush"
PY="$VENV/bin/python"
STEPS="${1:-20000}"
SEED="${SEED:-0}"
GR_VERSION="1.4.2"
MUJOCO_VERSION="3.11.0"

log() { printf '[fetchpush] %s\n' "$*" >&2; }

case "$STEPS" in ''|*[!0-9]*) log "STEPS must be a positive integer, got '$STEPS'"; exit 2 ;; esac

# --- venv -----------------------------------------------------------------------------
have_pins() {
    [ -x "$PY" ] && "$PY" - "$GR_VERSION" "$MUJOCO_VERSION" <<'EOF' 2>/dev/null
import sys
from importlib.metadata import version
sys.exit(version("gymnasium-robotics") != sys.argv[1] or version("mujoco") != sys.argv[2])
EOF
}

if have_pins; then
    log "venv $VENV already has gymnasium-robotics==$GR_VERSION mujoco==$MUJOCO_VERSION"
else
    log "creating venv $VENV and installing gymnasium-robotics==$GR_VERSION mujoco==$MUJOCO_VERSION"
    python3 -m venv "$VENV"
    "$PY" -m pip install --quiet --disable-pip-version-check \
        "gymnasium-robotics==$GR_VERSION" "mujoco==$MUJOCO_VERSION"
    have_pins || { log "install finished but pinned versions not found in $VENV"; exit 1; }
fi

# --- measurements ---------------------------------------------------------------------
# Each bench prints one JSON line; keep the last line of stdout.
log "FetchPush-v4, 1 process, $STEPS steps"
PY1="$("$PY" "$ROOT/bench/fetchpush_steps.py" --steps "$STEPS" --seed "$SEED" | tail -n 1)"
echo "$PY1"
log "FetchPush-v4, 2 processes, $STEPS steps each"
PY2="$("$PY" "$ROOT/bench/fetchpush_steps.py" --steps "$STEPS" --seed "$SEED" --procs 2 | tail -n 1)"
echo "$PY2"

has_rate() {  # $1 = a line; true if it is JSON with "env_steps_per_s"
    python3 -c 'import json,sys; float(json.loads(sys.argv[1])["env_steps_per_s"])' "$1" 2>/dev/null
}
rust_bench() {  # $1 = threads; prints the JSON line, or nothing on failure
    local out=""
    if out="$(cd "$ROOT" && cargo run --release --quiet -- bench --env BlocksTouch-v0 \
            --steps "$STEPS" --threads "$1" --json | tail -n 1)" && has_rate "$out"; then
        printf '%s\n' "$out"
    else
        log "Rust bench (threads=$1) failed or printed no JSON with env_steps_per_s" \
            "(got: '${out:0:200}'); is the 'bench' subcommand there yet? Rust numbers skipped."
    fi
}
log "BlocksTouch-v0 (Rust), 1 thread"
RS1="$(rust_bench 1)"
[ -n "$RS1" ] && echo "$RS1"
log "BlocksTouch-v0 (Rust), 2 threads"
RS2="$(rust_bench 2)"
[ -n "$RS2" ] && echo "$RS2"

# --- table ----------------------------------------------------------------------------
echo
python3 - "$PY1" "$PY2" "$RS1" "$RS2" <<'EOF'
import json, sys

def rate(line):
    try:
        return float(json.loads(line)["env_steps_per_s"])
    except (ValueError, KeyError, TypeError):
        return None

py1, py2, rs1, rs2 = (rate(a) for a in sys.argv[1:5])
fmt = lambda v: "n/a" if v is None else f"{v:,.0f}"
ratio = lambda a, b: "n/a" if a is None or b is None else f"{a / b:.2f}x"
print("| env | runtime | parallel | env steps/s |")
print("| --- | --- | --- | ---: |")
print(f"| FetchPush-v4 | python | 1 proc | {fmt(py1)} |")
print(f"| FetchPush-v4 | python | 2 procs | {fmt(py2)} |")
print(f"| BlocksTouch-v0 | rust | 1 thread | {fmt(rs1)} |")
print(f"| BlocksTouch-v0 | rust | 2 threads | {fmt(rs2)} |")
print()
print(f"BlocksTouch/FetchPush, 1 thread vs 1 proc:   {ratio(rs1, py1)}")
print(f"BlocksTouch/FetchPush, 2 threads vs 2 procs: {ratio(rs2, py2)}")
EOF
