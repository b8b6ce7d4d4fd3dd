#!/usr/bin/env python3
"""The solver's leaderboard rows before and after a re-measurement: for each `baseline-scripted.*`
result in the given folders, its test split's successes over episodes (the score) as committed at
OLD (a git commit) and as the file holds now, with 95% Wilson intervals, the solver version of
each, and whether the two differ beyond noise (the intervals do not overlap). Markdown on stdout.

    python3 bench/solver_rows.py OLD results/generalization/mujoco-2.2.2 results/generalization/mujoco-3.11.0
"""
import json
import pathlib
import subprocess
import sys

from solver_table import cell, verdict


def test_counts(result: dict) -> tuple[int, int]:
    """Successes and episodes of the scored split, summed over its rows (a baseline plays every row)."""
    split = next(s for s in result["splits"] if s["name"] == result.get("scored_split", "test"))
    k = sum(r["evaluation"]["successes"] for r in split["rows"])
    n = sum(r["evaluation"]["episodes"] for r in split["rows"])
    return k, n


def main(old: str, folders: list[str]) -> None:
    for folder in folders:
        engine = pathlib.Path(folder).name
        print(f"\n| {engine}: suite | old solver | new solver | |\n|---|---|---|---|")
        for path in sorted(pathlib.Path(folder).glob("baseline-scripted.*.json")):
            shown = subprocess.run(["git", "show", f"{old}:{path}"], capture_output=True, text=True)
            if shown.returncode != 0:
                continue
            before, now = json.loads(shown.stdout), json.loads(path.read_text())
            a, b = test_counts(before), test_counts(now)
            va, vb = before["provenance"].get("solver", 1), now["provenance"].get("solver", 1)
            suite = path.name[len("baseline-scripted."):-len(".json")]
            print(f"| {suite} | {cell(*a)} (v{va}) | {cell(*b)} (v{vb}) | {verdict(a, b)} |")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
