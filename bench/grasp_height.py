#!/usr/bin/env python3
"""Where a policy closes its fingers on a stack task's blue block, from `blockpuzzle rollout --out`
files (issue 73): per file, the successes, the episodes in which the grey pedestal under blue was
lifted (the fingers closed on it too), and the grip's height over blue's centre at the first step
the fingers were commanded closed with the grip within 2 cm of blue in the plane.

    blockpuzzle rollout --env TASK.toml --policy POLICY --episodes 20 --seed 2000000 --out F.jsonl
    python3 bench/grasp_height.py F.jsonl [...]

Objects are read in the task file's order: the stack family's pedestal first, blue second.
"""
import json
import statistics
import sys


def main(paths):
    for path in paths:
        heights, lifted, successes = [], 0, 0
        episodes = [json.loads(line) for line in open(path)]
        for e in episodes:
            successes += bool(e["success"])
            pedestal = e["steps"][0]["blocks"][0]["pos"][2]
            for s in e["steps"]:
                g, b = s["gripper"], s["blocks"][1]["pos"]
                if s["action"][3] < 0 and abs(g[0] - b[0]) < 0.02 and abs(g[1] - b[1]) < 0.02:
                    heights.append(g[2] - b[2])
                    break
            if max(s["blocks"][0]["pos"][2] for s in e["steps"]) > pedestal + 0.01:
                lifted += 1
        h = sorted(heights) or [float("nan")]
        print(
            f"{path}: success {successes}/{len(episodes)}, pedestal lifted in {lifted}; closing height over "
            f"blue's centre (mm): median {statistics.median(h) * 1000:+.1f}, min {h[0] * 1000:+.1f}, "
            f"max {h[-1] * 1000:+.1f} (n={len(heights)})"
        )


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
