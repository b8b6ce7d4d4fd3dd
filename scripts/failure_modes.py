#!/usr/bin/env python3
"""Why episodes fail: counts from a `blockpuzzle rollout` dump (JSON Lines).

Usage: python3 scripts/failure_modes.py DUMP.jsonl [DUMP2.jsonl ...]

Each episode falls in the first class that fits:
  success        the task's success (every blue touches a green)
  failure        the task's failure (red touched blue)
  no contact     the gripper never touched a block (the arm did not reach)
  blue untouched the gripper touched other blocks but never the blue one
  blue via grey  blue touched grey (pushed into the distractor) and never green
  missed         blue was pushed but did not reach green
It also prints the mean of the largest action component per step (|a|max),
for all steps and for the last ten steps of failed episodes (a policy that has
given up tends to send small, constant actions).

Standard library only; object indices come from the dump's "objects" list.
"""
import json
import sys
from collections import Counter


def classify(ep):
    if ep["success"]:
        return "success"
    if ep["failure"]:
        return "failure"
    names = [o["name"] for o in ep["objects"]]
    colours = [o["colour"] for o in ep["objects"]]
    gripper = names.index("gripper")
    table = names.index("table")
    blocks = {i for i in range(len(names)) if i not in (gripper, table)}
    blue = {i for i in blocks if colours[i] == "blue"}
    grey = {i for i in blocks if colours[i] == "grey"}
    pairs = {tuple(p) for s in ep["steps"] for p in s["touching"]}
    gripper_touched = {b for p in pairs if gripper in p for b in p if b in blocks}
    if not gripper_touched:
        return "no contact"
    if not gripper_touched & blue:
        return "blue untouched"
    if any(a in blue and b in grey or b in blue and a in grey for a, b in pairs):
        return "blue via grey"
    return "missed"


def main(paths):
    if not paths:
        sys.exit(__doc__)
    for path in paths:
        try:
            episodes = [json.loads(line) for line in open(path) if line.strip()]
        except (OSError, json.JSONDecodeError) as err:
            sys.exit(f"{path}: not a readable rollout dump ({err}); write one with `blockpuzzle rollout --out {path}`")
        counts = Counter(classify(ep) for ep in episodes)
        amax_all = [max(abs(x) for x in s["action"]) for ep in episodes for s in ep["steps"]]
        amax_end = [max(abs(x) for x in s["action"]) for ep in episodes if not ep["success"] for s in ep["steps"][-10:]]
        n = len(episodes)
        print(f"{path}: {n} episodes")
        for cls in ("success", "failure", "no contact", "blue untouched", "blue via grey", "missed"):
            print(f"  {cls:15s} {counts[cls]:4d}  {counts[cls] / max(n, 1):.3f}")
        mean = lambda xs: sum(xs) / len(xs) if xs else float("nan")
        print(f"  |a|max mean: all steps {mean(amax_all):.3f}, last 10 steps of failed episodes {mean(amax_end):.3f}")


if __name__ == "__main__":
    main(sys.argv[1:])
