#!/usr/bin/env python3
"""Where a student pushes on an avoid task, against the solver on the same episodes (issue 73):
from `blockpuzzle rollout --out` files of the two policies on the same task and seeds, the heading
of each episode's first push (the direction from the gripper to blue just before blue first moves
5 mm, in degrees from the blue-green line: 0 is straight at green) and whether the two turned the
same way. Episodes are grouped by who succeeded. The tasks' blocks are named as the avoid family
names them (`blue`, `green`, `red`).

    blockpuzzle rollout --env avoid-S-v0.toml --policy scripted --episodes 20 --seed 6000000 --out solver-S.jsonl
    blockpuzzle rollout --env avoid-S-v0.toml --policy POLICY --episodes 20 --seed 6000000 --out student-S.jsonl
    python3 bench/avoid_heading.py solver-S.jsonl student-S.jsonl [solver-T.jsonl student-T.jsonl ...]
"""
import json
import math
import statistics
import sys

FIXTURES = {"gripper", "table", "floor"}


def frame(episode):
    """Blue's and the gripper's path in the frame of blue's start (x along the line to green, y
    across it)."""
    names = [o["name"] for o in episode["objects"] if o["name"] not in FIXTURES]
    blue, green = names.index("blue"), names.index("green")
    first = episode["steps"][0]["blocks"]
    b0, g = first[blue]["pos"][:2], first[green]["pos"][:2]
    length = math.hypot(g[0] - b0[0], g[1] - b0[1])
    u = ((g[0] - b0[0]) / length, (g[1] - b0[1]) / length)

    def to(p):
        d = (p[0] - b0[0], p[1] - b0[1])
        return (d[0] * u[0] + d[1] * u[1], -d[0] * u[1] + d[1] * u[0])

    blues = [to(s["blocks"][blue]["pos"][:2]) for s in episode["steps"]]
    grips = [to(s["gripper"][:2]) for s in episode["steps"]]
    return blues, grips


def first_push(episode):
    """The heading (degrees from the blue-green line) of the first push, None if blue never moves."""
    blues, grips = frame(episode)
    for k, b in enumerate(blues):
        if math.hypot(b[0] - blues[0][0], b[1] - blues[0][1]) > 0.005:
            b, g = blues[max(k - 1, 0)], grips[max(k - 1, 0)]
            return math.degrees(math.atan2(b[1] - g[1], b[0] - g[0]))
    return None


def main(paths):
    if len(paths) < 2 or len(paths) % 2:
        sys.exit(__doc__)
    groups = {}
    for solver_path, student_path in zip(paths[::2], paths[1::2]):
        solver = [json.loads(line) for line in open(solver_path)]
        student = [json.loads(line) for line in open(student_path)]
        for s, p in zip(solver, student):
            if s["seed"] != p["seed"]:
                sys.exit(f"{solver_path} and {student_path} do not play the same seeds")
            hs, hp = first_push(s), first_push(p)
            if hs is None or hp is None:
                continue
            key = ("solver succeeded" if s["success"] else "solver failed") + ", " + (
                "student succeeded" if p["success"] else "student failed"
            )
            groups.setdefault(key, []).append((hs, hp))
    for key in sorted(groups):
        rows = groups[key]
        same = sum((a > 0) == (b > 0) for a, b in rows)
        print(
            f"{key}: {len(rows)} episodes; first push |heading| median: solver {statistics.median(abs(a) for a, _ in rows):.0f}, "
            f"student {statistics.median(abs(b) for _, b in rows):.0f} degrees; turned the same way in {same}"
        )


if __name__ == "__main__":
    main(sys.argv[1:])
