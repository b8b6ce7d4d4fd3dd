#!/usr/bin/env bash
# Training across MPI ranks against threads on this machine, side by side in one run (issue 13):
# DDPG on BlocksTouch-v0 (the paper's settings) for one epoch of $CYCLES cycles in each layout,
# with per-cycle collection, per-update gradient and exchange times from progress.csv (rank 0's),
# and a projection of the paper's 20-rank configuration from the measured per-rank costs.
#
#   bash bench/mpi_scaling.sh                  # prints a Markdown report
#   CYCLES=20 ENV=BlocksChoose-v0 bash bench/mpi_scaling.sh
#
# Needs a release build (make build) and mpirun (make setup installs Open MPI). Nothing else
# should run on the machine meanwhile: the figures are wall-clock.
set -euo pipefail
cd "$(dirname "$0")/.."
BP=${BP:-target/release/blockpuzzle}
CYCLES=${CYCLES:-10}
ENV=${ENV:-BlocksTouch-v0}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
common=(train --algo ddpg --env "$ENV" --epochs 1 --cycles "$CYCLES" --seed 0)

# name, ranks, workers per rank, torch threads, extra flags
layouts=(
    "threads 1 2 2 "
    "threads-tt1 1 2 1 "
    "threads-shared 1 2 2 --replay shared"
    "mpi-1x1 1 1 1 "
    "mpi-2x1 2 1 1 "
)

# A column of the last progress.csv row, by name.
col() { awk -F, -v name="$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == name) c = i } END { print $c }' "$1"; }

echo "| layout | ranks × workers | torch threads | s per cycle (collect + 40 updates) | collect s per cycle | ms per update | of which exchange ms | exchange per update |"
echo "|---|---|---|---|---|---|---|---|"
declare -A upd red env
for l in "${layouts[@]}"; do
    read -r name np workers tt extra <<<"$l"
    dir="$tmp/$name"
    if [[ $name == mpi-* ]]; then
        out=$(mpirun --oversubscribe -np "$np" "$BP" "${common[@]}" --workers "$workers" --torch-threads "$tt" \
            --run-dir "$dir" 2>&1 >/dev/null | grep -o 'about [0-9]* KiB' | cut -d' ' -f2- || true)
    else
        # shellcheck disable=SC2086
        "$BP" "${common[@]}" --workers "$workers" --torch-threads "$tt" $extra --run-dir "$dir" >/dev/null 2>&1
        out=""
    fi
    p="$dir/progress.csv"
    env_s=$(col "$p" time/env_seconds)
    eval_s=$(col "$p" time/eval_seconds)
    upd_s=$(col "$p" time/update_seconds)
    red_s=$(col "$p" time/reduce_seconds)
    updates=$(col "$p" time/updates)
    read -r cyc collect ms_upd ms_red < <(awk -v e="$env_s" -v v="$eval_s" -v u="$upd_s" -v r="$red_s" -v n="$updates" -v c="$CYCLES" \
        'BEGIN { printf "%.3f %.3f %.2f %.3f\n", (e - v + u) / c, (e - v) / c, 1000 * u / n, 1000 * r / n }')
    upd[$name]=$ms_upd; red[$name]=$ms_red; env[$name]=$collect
    if [[ $np == 1 ]]; then out="none (the workers' mean in memory)"; else out="$out sent and received per rank"; fi
    echo "| $name${extra:+ ($extra)} | $np × $workers | $tt | $cyc | $collect | $ms_upd | $ms_red | $out |"
done

# Projection: 20 ranks × 1 worker on 20 cores. Per rank, a cycle is one worker's collection
# (as measured with 1 rank × 1 worker) and 40 updates, each one shard's gradient (the 1 × 1 update
# time less its exchange) plus the exchange, whose data per rank grows as 2(P-1)/P of a gradient:
# from P = 2 (1 gradient) to P = 20 (1.9 gradients).
awk -v c1="${env[mpi-1x1]}" -v u1="${upd[mpi-1x1]}" -v r1="${red[mpi-1x1]}" -v r2="${red[mpi-2x1]}" 'BEGIN {
    x20 = r2 * 1.9
    cycle = c1 + 40 * (u1 - r1 + x20) / 1000
    epoch = 50 * cycle
    printf "\nProjection (not a measurement) for `mpirun -np 20 ... --workers 1` on 20 such cores: exchange %.2f ms per update, %.1f s per cycle, %.0f s per epoch (50 cycles, before test episodes); the paper'"'"'s 0.90 at epoch 200: %.1f h; its 0.97 at epoch 500: %.1f h.\n", x20, cycle, epoch, 200 * epoch / 3600, 500 * epoch / 3600
}'
echo
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores; $ENV, $CYCLES cycles; $(mpirun --version | head -1)."
