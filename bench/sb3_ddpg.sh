#!/usr/bin/env bash
# DDPG throughput side by side: stable-baselines3 on gymnasium-robotics FetchPush-v4 and
# blockpuzzle on BlocksTouch-v0 (the same Fetch robot plus two blocks), both on CPU, with the
# ratio blockpuzzle / SB3 for updates/s and env steps/s.
#
# For each torch thread count, blockpuzzle runs first, SB3 right after, so that both see the
# same machine load:
#   blockpuzzle bench --train --workers 1 --torch-threads T --steps STEPS --updates UPDATES
#     (src/learn/bench/ddpg.rs: the training loop's collection path -- plain-Rust actor + noise,
#     env step, replay insert, normaliser update -- then DDPG updates at batch 256);
# on CPUs with AMX or AVX512-BF16 also with --precision bf16 (hidden-layer products in
# bfloat16, an opt-in departure from the paper's float32); and once more with --workers 2 (two
# environments stepped in parallel threads, as `train --workers 2` collects).
#
# For each torch thread count in THREADS (default "1 2") runs bench/sb3_ddpg.py, which
# builds DDPG("MultiInputPolicy", FetchPush-v4) -- actor and critic [256,256,256],
# batch 256, buffer 1e6, lr 1e-3, gamma 0.98, tau 0.05, plain replay buffer (no HER),
# device cpu -- and measures separately:
#   env_steps_per_s  SB3's own collection loop (actor forward + noise, env step,
#                    replay insert), gradient updates switched off;
#   updates_per_s    one model.train(gradient_steps=UPDATES, batch_size=256) call.
# Each run prints one JSON line; a markdown table follows.
#
# Installs (once; skipped when the pinned versions are already there) a Python venv at
# bench/.venv-sb3 (git-ignored) with, from PyPI:
#   stable-baselines3==2.9.2  -- the current release when this script was written
#   torch==2.15.0             -- the default PyPI wheel, i.e. the CUDA build (~5 GB venv
#                                with its nvidia-* wheels); it is only run on CPU here
#   gymnasium-robotics==1.4.2 (pulls in gymnasium, numpy, ...)
#   mujoco==3.11.0            -- a 3.x pin on purpose: mujoco 4.x breaks FetchPush in
#                                gymnasium-robotics 1.4.2.
#
# Usage: bench/sb3_ddpg.sh [STEPS] [UPDATES]   (defaults 3000 and 300)
# Needs the project set up (make setup) for the blockpuzzle side.
#   THREADS="1 2" overrides the torch thread counts, SEED=... the seed (default 0).
# Run it on an otherwise idle machine: anything else using a core skews the numbers.
# With threads=2 on a busy 2-core machine, torch's OpenMP workers spin-wait for each other
# and both rates collapse (5-10x slower here); OMP_WAIT_POLICY=PASSIVE, which the Python
# process inherits from this script's environment, avoids that. Left at the default on purpose,
# so that the numbers show plain SB3 as people run it.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/bench/.venv-sb3"
PY="$VENV/bin/python"
STEPS="${1:-3000}"
UPDATES="${2:-300}"
THREADS="${THREADS:-1 2}"
SEED="${SEED:-0}"
SB3_VERSION="2.9.2"
TORCH_VERSION="2.15.0"
GR_VERSION="1.4.2"
MUJOCO_VERSION="3.11.0"

log() { printf '[sb3_ddpg] %s\n' "$*" >&2; }

is_digits() { case "$1" in ''|*[!0-9]*) return 1 ;; esac; }
is_pos() { is_digits "$1" && [ "$((10#$1))" -gt 0 ]; }
is_pos "$STEPS"   || { log "STEPS must be a positive integer, got '$STEPS'"; exit 2; }
is_pos "$UPDATES" || { log "UPDATES must be a positive integer, got '$UPDATES'"; exit 2; }
is_digits "$SEED" || { log "SEED must be a non-negative integer, got '$SEED'"; exit 2; }
[ -n "${THREADS// /}" ] || { log "THREADS must list at least one thread count"; exit 2; }
for t in $THREADS; do
    is_pos "$t" || { log "THREADS must be positive integers, got '$THREADS'"; exit 2; }
done

# --- venv -----------------------------------------------------------------------------
have_pins() {
    [ -x "$PY" ] && "$PY" - "$SB3_VERSION" "$TORCH_VERSION" "$GR_VERSION" "$MUJOCO_VERSION" \
        <<'EOF' 2>/dev/null
import sys
from importlib.metadata import version
want = dict(zip(["stable-baselines3", "torch", "gymnasium-robotics", "mujoco"], sys.argv[1:]))
# torch wheels may carry a local tag (2.x.y+cu...); compare the public part.
sys.exit(any(version(p).split("+")[0] != v for p, v in want.items()))
EOF
}

PINS="stable-baselines3==$SB3_VERSION torch==$TORCH_VERSION gymnasium-robotics==$GR_VERSION mujoco==$MUJOCO_VERSION"
if have_pins; then
    log "venv $VENV already has $PINS"
else
    log "creating venv $VENV and installing $PINS (torch is a large download; minutes)"
    python3 -m venv "$VENV"
    # shellcheck disable=SC2086  # PINS is a word list on purpose
    "$PY" -m pip install --quiet --disable-pip-version-check $PINS
    have_pins || { log "install finished but pinned versions not found in $VENV"; exit 1; }
fi

# --- measurements ---------------------------------------------------------------------
log "building blockpuzzle (release)"
(cd "$ROOT" && cargo build --release --quiet)
BP="$ROOT/target/release/blockpuzzle"
LINES=()
for t in $THREADS; do
    log "blockpuzzle DDPG, BlocksTouch-v0, threads=$t: $STEPS env steps, $UPDATES updates"
    line="$("$BP" bench --train --workers 1 --torch-threads "$t" --steps "$STEPS" \
        --updates "$UPDATES" --seed "$SEED" --json)"
    echo "$line"
    LINES+=("$line")
    if grep -qwE 'amx_bf16|avx512_bf16' /proc/cpuinfo; then
        log "blockpuzzle DDPG, --precision bf16, threads=$t: $UPDATES updates"
        line="$("$BP" bench --train --workers 1 --torch-threads "$t" --steps 500 \
            --updates "$UPDATES" --seed "$SEED" --precision bf16 --json)"
        echo "$line"
        LINES+=("$line")
    fi
    log "SB3 DDPG, FetchPush-v4, threads=$t: $STEPS env steps, $UPDATES updates"
    # Keep the last line of stdout (the JSON); warnings go to stderr.
    line="$("$PY" "$ROOT/bench/sb3_ddpg.py" --steps "$STEPS" --updates "$UPDATES" \
        --threads "$t" --seed "$SEED" | tail -n 1)"
    echo "$line"
    LINES+=("$line")
done
log "blockpuzzle DDPG collection with 2 workers: $STEPS env steps"
line="$("$BP" bench --train --workers 2 --torch-threads 1 --steps "$STEPS" --updates 1 --seed "$SEED" --json)"
echo "$line"
LINES+=("$line")

# --- table ----------------------------------------------------------------------------
echo
"$PY" - "${LINES[@]}" <<'EOF'
import json, sys

rows = [json.loads(a) for a in sys.argv[1:]]
sb3 = {r["threads"]: r for r in rows if r["impl"] == "sb3"}
ours = {r["threads"]: r for r in rows
        if r["impl"] == "blockpuzzle" and r["workers"] == 1 and r.get("precision", "f32") == "f32"}
bf16 = {r["threads"]: r for r in rows if r["impl"] == "blockpuzzle" and r.get("precision") == "bf16"}
two = [r for r in rows if r["impl"] == "blockpuzzle" and r["workers"] == 2]
if sb3:
    r = next(iter(sb3.values()))
    print(f"stable-baselines3 {r['sb3']} (torch {r['torch']}) on {r['env']} vs blockpuzzle on "
          f"BlocksTouch-v0; batch {r['batch_size']}, CPU, one environment")
    print()
print("| torch threads | updates/s sb3 | updates/s ours | ratio | env steps/s sb3 | env steps/s ours | ratio |")
print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for t, s in sb3.items():
    o = ours.get(t)
    if o is None:
        continue
    print(f"| {t} | {s['updates_per_s']:,.1f} | {o['updates_per_s']:,.1f} | "
          f"{o['updates_per_s'] / s['updates_per_s']:.2f}x | {s['env_steps_per_s']:,.0f} | "
          f"{o['env_steps_per_s']:,.0f} | {o['env_steps_per_s'] / s['env_steps_per_s']:.2f}x |")
for t, o in bf16.items():
    s = sb3.get(t)
    if s:
        print(f"\nblockpuzzle --precision bf16, {t} thread(s): {o['updates_per_s']:,.1f} updates/s "
              f"({o['updates_per_s'] / s['updates_per_s']:.2f}x sb3's float32)")
for o in two:
    s = sb3.get(1)
    ratio = f" ({o['env_steps_per_s'] / s['env_steps_per_s']:.2f}x sb3's one environment)" if s else ""
    print(f"\nblockpuzzle collection with 2 workers: {o['env_steps_per_s']:,.0f} env steps/s{ratio}")
EOF
