#!/usr/bin/env python3
"""The physics suite's table (issue 76): per policy, the test split's mean success under randomised
dynamics, the nominal split's over the same rows, and their ratio (what the dynamics cost), per
engine, from `eval --suite physics` results. The nominal split plays the test split's very episodes
(same tasks, seeds and layouts), so the ratio compares like with like.
Usage: python3 bench/physics_table.py results/generalization/mujoco-*/ (folders of *.physics.json)"""
import json
import pathlib
import sys


def rows(result, split):
    for s in result["splits"]:
        if s["name"] == split:
            return {(r["task"], r["seed"]): r["evaluation"]["success_rate"] for r in s["rows"] if r.get("evaluation")}
    return {}


def main(folders):
    for folder in map(pathlib.Path, folders):
        files = sorted(folder.glob("*.physics.json"))
        if not files:
            continue
        engines = {json.loads(f.read_text())["provenance"]["mujoco"] for f in files}
        commits = {json.loads(f.read_text())["provenance"]["commit"] for f in files}
        print(f"\nMuJoCo {', '.join(sorted(engines))} ({folder}; commit {', '.join(sorted(commits))})\n")
        print("| policy | rows | train | test (randomised) | nominal (same episodes) | test / nominal |")
        print("|---|---:|---:|---:|---:|---:|")
        for f in files:
            r = json.loads(f.read_text())
            test, nominal, train = rows(r, "test"), rows(r, "nominal"), rows(r, "train")
            both = sorted(set(test) & set(nominal))
            if not both:
                print(f"| {r['policy']} | 0 | | | | |")
                continue
            t = sum(test[k] for k in both) / len(both)
            n = sum(nominal[k] for k in both) / len(both)
            tr = sum(train.values()) / len(train) if train else float("nan")
            ratio = f"{t / n:.2f}×" if n > 0 else "–"
            print(f"| {r['policy']} | {len(both)} | {tr:.3f} | {t:.3f} | {n:.3f} | {ratio} |")


if __name__ == "__main__":
    main(sys.argv[1:])
