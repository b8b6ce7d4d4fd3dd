#!/usr/bin/env python3
"""The summary table of results/generalization.md from results/generalization/*.json
(written by scripts/generalization.sh): per zoo policy and suite, train and test mean success,
the gap, and the rows skipped.

Usage: python3 scripts/generalization_table.py
"""
import json
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1]
SUITES = ["colour", "layout", "cross-task"]


def cell(r):
    means = {s["name"]: s["mean_success"] for s in r["splits"]}
    skipped = sum(row["skipped"] is not None for s in r["splits"] for row in s["rows"])
    total = sum(len(s["rows"]) for s in r["splits"])
    fmt = lambda v: "–" if v is None else f"{v:.3f}"
    text = f"{fmt(means.get('train'))} / {fmt(means.get('test'))} (gap {fmt(r['gap'])})"
    return text + (f", {skipped} of {total} rows skipped" if skipped else "")


def main():
    files = sorted((ROOT / "results" / "generalization").glob("*.json"))
    policies = sorted({f.name.split(".")[0] for f in files})
    print("| zoo policy | trained on | " + " | ".join(f"{s}: train / test" for s in SUITES) + " |")
    print("|---|---|" + "---|" * len(SUITES))
    for p in policies:
        results = {s: json.loads((ROOT / "results" / "generalization" / f"{p}.{s}.json").read_text()) for s in SUITES}
        task = results[SUITES[0]]["policy_task"]
        print(f"| {p} | {task} | " + " | ".join(cell(results[s]) for s in SUITES) + " |")
    shas = {s: results[s]["suite"]["sha256"][:12] for s in SUITES}
    print()
    print("Suite versions (sha256, first 12 hex digits): " + ", ".join(f"{s} `{h}`" for s, h in shas.items()) + ".")


if __name__ == "__main__":
    main()
