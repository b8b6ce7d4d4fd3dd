#!/usr/bin/env bash
# Update rates of the set networks against the flat MLP (issue 31), f32 and bf16, side by side:
# `blockpuzzle bench --train` on BlocksChoose-v0 for each network, the whole list ROUNDS times,
# alternated so that a change in the machine's load touches every network alike. Prints one JSON
# line per measurement (bench --json) and a table of the medians and their ratios to the MLP's.
#   bash bench/set_network.sh [ROUNDS] [UPDATES]
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS="${1:-2}"
UPDATES="${2:-100}"
BP=target/release/blockpuzzle
[ -x "$BP" ] || cargo build --release --quiet
PRECISIONS=(f32)
if "$BP" info 2>/dev/null | grep -q "bf16 updates yes"; then PRECISIONS+=(bf16); fi
OUT="$(mktemp)"
for _ in $(seq "$ROUNDS"); do
    for precision in "${PRECISIONS[@]}"; do
        for net in "mlp mean-max" "set mean-max" "set mean-max --set-norm" "set mean-max --flat-critic" "set attention" "set colour"; do
            set -- $net
            "$BP" bench --train --json --env BlocksChoose-v0 --net "$1" --set-pooling "$2" ${3:-} --precision "$precision" \
                --updates "$UPDATES" --steps 500 --torch-threads 1 | tee -a "$OUT"
        done
    done
done
python3 - "$OUT" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
rates = {}
for r in rows:
    rates.setdefault((r["precision"], r["net"]), []).append(r["updates_per_s"])
print("| network | precision | updates/s (median) | × the MLP's (same precision) | × its f32 rate |")
print("|---|---|---:|---:|---:|")
for (precision, net), v in rates.items():
    base = statistics.median(rates[(precision, "mlp")])
    f32 = statistics.median(rates.get(("f32", net), v))
    print(f"| {net} | {precision} | {statistics.median(v):.1f} | {statistics.median(v) / base:.2f} | {statistics.median(v) / f32:.2f} |")
PY
rm -f "$OUT"
