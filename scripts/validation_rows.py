"""Rows of the validation table in results/headline.md, from validation evaluations (docs/training.md, former `make validate`).

    python3 scripts/validation_rows.py RUN LABEL EPOCH...

RUN is a run directory's name under runs/ (e.g. study-ours-nol2-s0), LABEL the row's first cell,
EPOCH the snapshot epochs validated (results/headline/validation/RUN-epochE[--challenge].json).
Each row: the label, epoch, env steps after that many epochs (progress.csv), then for Normal and
Challenge the success rate and the shares of no_contact, off_table, blue_met_grey and timeout
episodes.
"""

import csv
import json
import sys
from pathlib import Path


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    run, label, epochs = argv[0], argv[1], argv[2:]
    progress = Path("runs") / run / "progress.csv"
    if not progress.exists():
        sys.exit(f"{progress} not found: give a run directory's name under runs/")
    # Row e of progress.csv is the (e+1)-th epoch.
    steps = {int(r["epoch"]) + 1: int(r["time/env_steps"]) for r in csv.DictReader(progress.open())}
    for e in map(int, epochs):
        if e not in steps:
            sys.exit(f"{progress} has no epoch {e}")
        cells = []
        for distribution in ["", "--challenge"]:
            path = Path("results/headline/validation") / f"{run}-epoch{e}{distribution}.json"
            if not path.exists():
                sys.exit(f"{path} not found: evaluate runs/{run} at epoch {e} first (docs/training.md#former-make-targets, make validate)")
            d = json.loads(path.read_text())
            o, n = d["outcomes"], d["episodes"]
            cells.append(f"{d['success_rate']:.3f}")
            cells += [f"{o[k] / n:.3f}" for k in ("no_contact", "off_table", "blue_met_grey", "timeout")]
        print(f"| {label} | {e} | {steps[e] / 1e6:.2f} M | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
