#!/usr/bin/env python3
"""Stable-Baselines3 TD3 on a BlockPuzzle task with the paper's curriculum: the example now ships in
the package, `python -m blockpuzzle.examples.sb3_td3` (python/blockpuzzle/examples/sb3_td3.py); this
path runs it with the same arguments, so the commands of results/python.md still work."""
import sys

from blockpuzzle.examples.sb3_td3 import main

if __name__ == "__main__":
    main(sys.argv[1:])
