#!/usr/bin/env python3
"""Median steps to success from `blockpuzzle rollout --out` files (issue 73's precision target is
stated on medians, which suite results do not keep: they record each row's mean). Each file's
successful episodes are counted by their length (an episode ends at the step it succeeds), and the
files' episodes are pooled for the last line, so a policy's files and the solver's, played on the
same tasks and seeds, compare side by side.

    blockpuzzle task generate push --seed 20000 --count 10 --out T
    blockpuzzle rollout --env T/push-20000-v0.toml --policy POLICY --episodes 20 --seed 6000000 --out F.jsonl
    python3 bench/steps_median.py F.jsonl [...]
"""
import json
import statistics
import sys


def main(paths):
    pooled, played = [], 0
    for path in paths:
        episodes = [json.loads(line) for line in open(path)]
        steps = sorted(len(e["steps"]) for e in episodes if e["success"])
        played += len(episodes)
        pooled += steps
        median = statistics.median(steps) if steps else float("nan")
        print(f"{path}: {len(steps)}/{len(episodes)} successful, median steps {median:g}")
    pooled.sort()
    median = statistics.median(pooled) if pooled else float("nan")
    print(f"pooled: {len(pooled)}/{played} successful, median steps to success {median:g}")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
