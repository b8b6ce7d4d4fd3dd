#!/usr/bin/env python3
"""Per-family success of suite results over generated tasks (procgen-v2, the generalist's
validation suite): one column per result file, one row per family and split, each cell the pooled
success over the family's rows, then each split's mean (every row weighing the same, as the suite's
score). The last column divides the last file by the first (the solver's, usually). Markdown on stdout.
With --steps, each cell is instead the mean number of steps of the family's successful episodes
(each row's mean weighted by its successes), and each split's last line the same over all rows.

    python3 bench/family_table.py [--steps] results/generalist/validation/baseline-scripted.json FILE...
"""
import json
import sys
from collections import defaultdict


def table(paths: list[str], steps: bool = False) -> str:
    results = [json.load(open(p)) for p in paths]
    splits = [s["name"] for s in results[0]["splits"]]
    head = "| split | family | " + " | ".join(p.rsplit("/", 1)[-1].removesuffix(".json") for p in paths)
    lines = [head + " | last / first |", "|---|---|" + "---:|" * (len(paths) + 1)]
    for split in splits:
        cells = []
        for r in results:
            fam = defaultdict(lambda: [0, 0])
            for row in next(s for s in r["splits"] if s["name"] == split)["rows"]:
                e = row.get("evaluation")
                if e:
                    f = fam[row["task"].rsplit("-", 2)[0]]
                    if steps:
                        took = e["successes"] * (e.get("mean_steps_to_success") or 0.0)
                        f[0] += took
                        f[1] += e["successes"]
                    else:
                        f[0] += e["successes"]
                        f[1] += e["episodes"]
            if steps:
                took, successes = (sum(f[k] for f in fam.values()) for k in (0, 1))
                mean = took / successes if successes else float("nan")
            else:
                mean = next(s for s in r["splits"] if s["name"] == split)["mean_success"]
            cells.append((fam, mean))
        fmt = (lambda x: f"{x:.1f}") if steps else (lambda x: f"{x:.3f}")
        for family in cells[0][0]:
            rates = [c[0][family][0] / c[0][family][1] if c[0][family][1] else float("nan") for c in cells]
            ratio = rates[-1] / rates[0] if rates[0] else float("nan")
            lines.append(f"| {split} | {family} | " + " | ".join(fmt(x) for x in rates) + f" | {ratio:.2f}× |")
        means = [c[1] for c in cells]
        lines.append(f"| **{split}** | **{'steps' if steps else 'mean'}** | " + " | ".join(f"**{fmt(x)}**" for x in means)
                     + f" | **{means[-1] / means[0]:.2f}×** |")
    return "\n".join(lines)


if __name__ == "__main__":
    args = sys.argv[1:]
    steps = "--steps" in args
    files = [a for a in args if a != "--steps"]
    if not files:
        sys.exit("usage: family_table.py [--steps] RESULT.json [RESULT.json ...] (suite results of one suite)")
    print(table(files, steps))
