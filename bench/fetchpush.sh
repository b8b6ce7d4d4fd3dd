#!/usr/bin/env bash
# Compare env steps/s: gymnasium-robotics FetchPush-v4 (Python, MuJoCo Python bindings)
# against our Rust BlocksTouch-v0, both stepped with uniformly random actions.
#
# Measures, with STEPS steps each (default 20000):
#   (a) FetchPush-v4, one Python process        (bench/fetchpush_steps.py)
#   (b) FetchPush-v4, two Python processes, aggregate steps/s
#   (c) BlocksTouch-v0, `cargo run --release -- bench ... --threads 1` and `--threads 2`,
#       on Debian's MuJoCo 2.2.2 and, after `make setup-mujoco3`, on MuJoCo 3.11.0 (the
#       engine FetchPush-v4 runs on here: the comparison on equal engines)
#   (d) the FetchPush-like scene (src/episode/align/fetchpush.toml: FetchPush-v4's own scene, one block, the
#       gripper on the table) in Rust, `blockpuzzle align --bench-steps`, every episode starting
#       from a state FetchPush-v4 reset to: the like-for-like row (same engine, same scene)
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
STEPS="${1:-20000}"
SEED="${SEED:-0}"

log() { printf '[fetchpush] %s\n' "$*" >&2; }

case "$STEPS" in ''|*[!0-9]*) log "STEPS must be a positive integer, got '$STEPS'"; exit 2 ;; esac

# --- venv -----------------------------------------------------------------------------
. "$ROOT/bench/fetchpush_venv.sh"

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
M3=(--features mujoco3 --target-dir "$ROOT/target/mujoco3")
START="$ROOT/target/align/bench-start.json"
mkdir -p "$ROOT/target/align"
"$PY" "$ROOT/bench/align_fetchpush.py" --random 1 --scripted 0 --steps 1 --out "$START" >/dev/null 2>&1
rust_bench() {  # $1 = threads, $2 = scene (touch|like), then cargo's engine arguments; prints the JSON line, or nothing on failure
    local out="" threads="$1" scene="$2"
    shift 2
    local what=(bench --env BlocksTouch-v0 --steps "$STEPS" --threads "$threads" --json)
    [ "$scene" = like ] && what=(align --reference "$START" --bench-steps "$STEPS" --threads "$threads")
    if out="$(cd "$ROOT" && cargo run --release --quiet "$@" -- "${what[@]}" | tail -n 1)" && has_rate "$out"; then
        printf '%s\n' "$out"
    else
        log "Rust bench (threads=$1) failed or printed no JSON with env_steps_per_s" \
            "(got: '${out:0:200}'); is the 'bench' subcommand there yet? Rust numbers skipped."
    fi
}
measure() {  # $1 = what, then rust_bench's arguments; logs, shows and returns the JSON line
    log "$1"
    shift
    local out
    out="$(rust_bench "$@")"
    [ -n "$out" ] && printf '%s\n' "$out" >&2
    printf '%s' "$out"
}
RS1="$(measure "BlocksTouch-v0 (Rust, MuJoCo 2.2.2), 1 thread" 1 touch)"
RS2="$(measure "BlocksTouch-v0 (Rust, MuJoCo 2.2.2), 2 threads" 2 touch)"
M31="" M32="" L31="" L32=""
if [ -f "$ROOT/engines/mujoco-3.11.0/lib/libmujoco.so" ]; then
    M31="$(measure "BlocksTouch-v0 (Rust, MuJoCo 3.11.0), 1 thread" 1 touch "${M3[@]}")"
    M32="$(measure "BlocksTouch-v0 (Rust, MuJoCo 3.11.0), 2 threads" 2 touch "${M3[@]}")"
    L31="$(measure "FetchPush-like (Rust, MuJoCo 3.11.0), 1 thread" 1 like "${M3[@]}")"
    L32="$(measure "FetchPush-like (Rust, MuJoCo 3.11.0), 2 threads" 2 like "${M3[@]}")"
else
    log "MuJoCo 3.11.0 not fetched (make setup-mujoco3): 3.x rows skipped"
fi

# --- table ----------------------------------------------------------------------------
echo
python3 - "$PY1" "$PY2" "$RS1" "$RS2" "$M31" "$M32" "$L31" "$L32" <<'EOF'
import json, sys

def rate(line):
    try:
        return float(json.loads(line)["env_steps_per_s"])
    except (ValueError, KeyError, TypeError):
        return None

py1, py2, rs1, rs2, m31, m32, l31, l32 = (rate(a) for a in sys.argv[1:9])
fmt = lambda v: "n/a" if v is None else f"{v:,.0f}"
ratio = lambda a, b: "n/a" if a is None or b is None else f"{a / b:.2f}x"
print("| env | runtime | MuJoCo | parallel | env steps/s | vs FetchPush-v4 |")
print("| --- | --- | --- | --- | ---: | ---: |")
print(f"| FetchPush-v4 | python | 3.11.0 | 1 proc | {fmt(py1)} | |")
print(f"| FetchPush-v4 | python | 3.11.0 | 2 procs | {fmt(py2)} | |")
print(f"| BlocksTouch-v0 | rust | 2.2.2 | 1 thread | {fmt(rs1)} | {ratio(rs1, py1)} |")
print(f"| BlocksTouch-v0 | rust | 2.2.2 | 2 threads | {fmt(rs2)} | {ratio(rs2, py2)} |")
if m31 is not None or m32 is not None:
    print(f"| BlocksTouch-v0 | rust | 3.11.0 | 1 thread | {fmt(m31)} | {ratio(m31, py1)} |")
    print(f"| BlocksTouch-v0 | rust | 3.11.0 | 2 threads | {fmt(m32)} | {ratio(m32, py2)} |")
if l31 is not None or l32 is not None:
    print(f"| FetchPush-like (same scene) | rust | 3.11.0 | 1 thread | {fmt(l31)} | {ratio(l31, py1)} |")
    print(f"| FetchPush-like (same scene) | rust | 3.11.0 | 2 threads | {fmt(l32)} | {ratio(l32, py2)} |")
EOF
