"""How saturated a policy's actions are, from a `blockpuzzle rollout` dump.

    python3 scripts/action_saturation.py DUMP.jsonl

Prints, for each action dimension (x, y, z, gripper), the share of steps whose action is within
0.01 of ±1 (the tanh saturated) and the mean |action|, over every step of every episode.
"""

import json
import sys
from pathlib import Path


def main(argv):
    if len(argv) != 1:
        sys.exit(__doc__)
    path = Path(argv[0])
    if not path.exists():
        sys.exit(f"{path} not found: write it with `blockpuzzle rollout ... --out {path}`")
    actions = []
    for number, line in enumerate(path.open(), 1):
        try:
            actions += [step["action"] for step in json.loads(line)["steps"]]
        except (json.JSONDecodeError, KeyError) as e:
            sys.exit(f"{path}:{number}: not a rollout episode ({e})")
    if not actions:
        sys.exit(f"{path} holds no steps")
    n = len(actions)
    for k, name in enumerate(["x", "y", "z", "gripper"]):
        size = [abs(a[k]) for a in actions]
        saturated = sum(s > 0.99 for s in size) / n
        print(f"{name:8} saturated {saturated:.2f}  mean |a| {sum(size) / n:.2f}")
    print(f"{n} steps")


if __name__ == "__main__":
    main(sys.argv[1:])
