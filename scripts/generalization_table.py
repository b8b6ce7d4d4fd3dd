#!/usr/bin/env python3
"""The summary table of results/generalization.md from results/generalization/*.json
(written by scripts/generalization.sh): per zoo policy and suite, train and test mean success,
the gap, and the rows skipped.

Usage: python3 scripts/generalization_table.py
"""
import json
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1]
SUITES = ["colour", "layout", "cross-task", "count", "obstacles"]
BASELINES = ["baseline-scripted", "baseline-obs-hash"]


def applies(r):
    """A suite applies to a policy trained on one of its train split's tasks."""
    train = next(s for s in r["splits"] if s["name"] == "train")
    return r["policy_task"] in {row["task"] for row in train["rows"]}


def main():
    files = sorted((ROOT / "results" / "generalization").glob("*.json"))
    policies = sorted({f.name.split(".")[0] for f in files} - set(BASELINES))
    results = {
        p: {s: json.loads((ROOT / "results" / "generalization" / f"{p}.{s}.json").read_text()) for s in SUITES}
        for p in policies
    }
    for title, keep in [("Where the suite applies (the policy was trained on a task of its train split)", True),
                        ("Elsewhere, for reference (the train split is not the policy's training task)", False)]:
        print(f"**{title}**")
        print()
        print("| zoo policy | trained on | suite | train | test | gap | rows skipped |")
        print("|---|---|---|---:|---:|---:|---:|")
        for p in policies:
            for s in SUITES:
                r = results[p][s]
                if applies(r) != keep:
                    continue
                means = {sp["name"]: sp["mean_success"] for sp in r["splits"]}
                skipped = sum(row["skipped"] is not None for sp in r["splits"] for row in sp["rows"])
                total = sum(len(sp["rows"]) for sp in r["splits"])
                f = lambda v: "–" if v is None else f"{v:.3f}"
                print(f"| {p} | {r['policy_task']} | {s} | {f(means.get('train'))} | {f(means.get('test'))} | "
                      f"{f(r['gap'])} | {skipped} of {total} |")
        print()
    print("**Baselines (no training): the scripted controllers, and pseudo-random actions (obs-hash)**")
    print()
    print("| baseline | suite | train | test | gap |")
    print("|---|---|---:|---:|---:|")
    for b in BASELINES:
        for s in SUITES:
            r = json.loads((ROOT / "results" / "generalization" / f"{b}.{s}.json").read_text())
            means = {sp["name"]: sp["mean_success"] for sp in r["splits"]}
            f = lambda v: "–" if v is None else f"{v:.3f}"
            print(f"| {b.removeprefix('baseline-')} | {s} | {f(means.get('train'))} | {f(means.get('test'))} | {f(r['gap'])} |")
    print()
    shas = {s: results[policies[0]][s]["suite"]["sha256"][:12] for s in SUITES}
    print("Suite versions (sha256, first 12 hex digits): " + ", ".join(f"{s} `{h}`" for s, h in shas.items()) + ".")


if __name__ == "__main__":
    main()
