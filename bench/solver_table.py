#!/usr/bin/env python3
"""Tabulates bench/solver_versions.sh's output: per built-in task and per procgen-v2 family (both
splits), the old solver's success against the new one's, with 95% Wilson intervals, and whether
the new one is lower or higher beyond noise (the intervals do not overlap). Markdown on stdout."""
import json
import math
import pathlib
import re
import sys
from collections import defaultdict


def wilson(k: int, n: int) -> tuple[float, float]:
    if n == 0:
        return (0.0, 1.0)
    z = 1.959963984540054
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return (max(0.0, c - h), min(1.0, c + h))


def cell(k: int, n: int) -> str:
    lo, hi = wilson(k, n)
    return f"{k / n:.3f} [{lo:.3f}, {hi:.3f}]"


def verdict(a: tuple[int, int], b: tuple[int, int]) -> str:
    (alo, ahi), (blo, bhi) = wilson(*a), wilson(*b)
    if bhi < alo:
        return "**lower**"
    if blo > ahi:
        return "higher"
    return "within noise"


def main(out: pathlib.Path) -> None:
    builds = {}
    for side in ("old", "new"):
        p = json.loads((out / side / "procgen-v2.json").read_text())["provenance"]
        builds[side] = f"commit `{p.get('commit')}`, MuJoCo {p['mujoco']}, solver version {p.get('solver', 1)}"
    print(f"Old: {builds['old']}. New: {builds['new']}.\n")
    print("| built-in task | old solver | new solver | |")
    print("|---|---|---|---|")
    for f in sorted((out / "new").glob("*-v0.*.json")):
        old, new = (json.loads((out / s / f.name).read_text()) for s in ("old", "new"))
        a, b = (old["successes"], old["episodes"]), (new["successes"], new["episodes"])
        name = f.name.removesuffix(".json").replace(".normal", "").replace(".", ", ")
        print(f"| {name} | {cell(*a)} | {cell(*b)} | {verdict(a, b)} |")
    print("\n| procgen-v2 family, split | old solver | new solver | |")
    print("|---|---|---|---|")
    counts = {s: defaultdict(lambda: [0, 0]) for s in ("old", "new")}
    for s in ("old", "new"):
        for split in json.loads((out / s / "procgen-v2.json").read_text())["splits"]:
            for row in split["rows"]:
                fam = re.sub(r"-\d+-v0$", "", row["task"])
                ev = row["evaluation"]
                for key in ((fam, split["name"]), ("all seven", split["name"])):
                    counts[s][key][0] += ev["successes"]
                    counts[s][key][1] += ev["episodes"]
    for key in sorted(counts["new"], key=lambda k: (k[0] == "all seven", k)):
        a, b = tuple(counts["old"][key]), tuple(counts["new"][key])
        print(f"| {key[0]}, {key[1]} | {cell(*a)} | {cell(*b)} | {verdict(a, b)} |")


if __name__ == "__main__":
    main(pathlib.Path(sys.argv[1]))
