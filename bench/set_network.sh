#!/usr/bin/env bash
# Update rates of the set and entity networks against the flat MLP (issues 31 and 47), f32 and bf16,
# side by side: `blockpuzzle bench --train` on BlocksChoose-v0 for each network (DDPG's actor and
# critics, or DAgger's actor alone), the whole list ROUNDS times, alternated so that a change in the
# machine's load touches every network alike. Prints one JSON line per measurement (bench --json,
# with the row's label) and a table of the medians and their ratios to the MLP's.
#   bash bench/set_network.sh [ROUNDS] [UPDATES]
# ONLY=REGEX keeps the networks whose label matches it (and the MLP, the baseline).
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS="${1:-2}"
UPDATES="${2:-100}"
BP=target/release/blockpuzzle
[ -x "$BP" ] || cargo build --release --quiet
PRECISIONS=(f32)
if "$BP" info 2>/dev/null | grep -q "bf16 updates yes"; then PRECISIONS+=(bf16); fi
# label|flags; the first is the baseline.
VARIANTS=(
    "mlp|--net mlp"
    "set mean-max|--net set"
    "set mean-max --set-norm|--net set --set-norm"
    "set mean-max --flat-critic|--net set --flat-critic"
    "set attention|--net set --set-pooling attention"
    "set colour|--net set --set-pooling colour"
    "entity|--net entity"
    "entity --flat-critic|--net entity --flat-critic"
    "entity --set-robot-tokens|--net entity --set-robot-tokens"
    "entity --set-pooling query|--net entity --set-pooling query"
    "entity, DAgger (actor alone)|--net entity --algo dagger"
    "entity --set-robot-tokens, DAgger (actor alone)|--net entity --set-robot-tokens --algo dagger"
    "entity --set-transformer 2 --set-pooling query|--net entity --set-transformer 2 --set-pooling query"
    "entity --set-transformer 2 --set-pooling query, DAgger (actor alone)|--net entity --set-transformer 2 --set-pooling query --algo dagger"
    "entity --set-width 64|--net entity --set-width 64"
    "entity --set-width 64, DAgger (actor alone)|--net entity --set-width 64 --algo dagger"
    "entity --set-transformer 2 --set-pooling query --set-width 64|--net entity --set-transformer 2 --set-pooling query --set-width 64"
    "entity --set-transformer 2 --set-pooling query --set-width 64, DAgger (actor alone)|--net entity --set-transformer 2 --set-pooling query --set-width 64 --algo dagger"
    "entity --set-transformer 2 --set-pooling query --set-width 64 --flat-critic|--net entity --set-transformer 2 --set-pooling query --set-width 64 --flat-critic"
    "entity --set-transformer 2 --set-pooling query --set-width 128|--net entity --set-transformer 2 --set-pooling query --set-width 128"
)
ONLY="${ONLY:-}"
OUT="$(mktemp)"
for _ in $(seq "$ROUNDS"); do
    for precision in "${PRECISIONS[@]}"; do
        for variant in "${VARIANTS[@]}"; do
            label="${variant%%|*}"
            if [ -n "$ONLY" ] && [ "$label" != mlp ] && ! [[ "$label" =~ $ONLY ]]; then continue; fi
            # shellcheck disable=SC2086
            "$BP" bench --train --json --env BlocksChoose-v0 ${variant#*|} --precision "$precision" \
                --updates "$UPDATES" --steps 500 --torch-threads 1 |
                python3 -c 'import json, sys; r = json.loads(sys.stdin.read().splitlines()[-1]); r["label"] = sys.argv[1]; print(json.dumps(r))' \
                    "$label" | tee -a "$OUT"
        done
    done
done
python3 - "$OUT" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
rates = {}
for r in rows:
    rates.setdefault((r["precision"], r["label"]), []).append(r["updates_per_s"])
print("| network | precision | updates/s (median) | × the MLP's (same precision) | × its f32 rate |")
print("|---|---|---:|---:|---:|")
for (precision, net), v in rates.items():
    base = statistics.median(rates[(precision, "mlp")])
    f32 = statistics.median(rates.get(("f32", net), v))
    print(f"| {net} | {precision} | {statistics.median(v):.1f} | {statistics.median(v) / base:.2f} | {statistics.median(v) / f32:.2f} |")
PY
rm -f "$OUT"
