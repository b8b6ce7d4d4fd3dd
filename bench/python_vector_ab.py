#!/usr/bin/env python3
"""Env steps/s of the installed blockpuzzle package only (single env and make_vec, random actions):
for comparing two builds of the package side by side, e.g. before and after a change, each
installed in its own venv and run alternately:

    for i in 1 2 3; do OLD_VENV/bin/python bench/python_vector_ab.py; NEW_VENV/bin/python bench/python_vector_ab.py; done

Prints one line per measurement: label, env steps/s.
"""
import argparse
import time

import numpy as np

import blockpuzzle
from blockpuzzle import _native

ENV = "BlocksTouch-v0"


def single(steps):
    env = _native.Env(ENV, 1, 1)
    actions = np.random.default_rng(1).uniform(-1, 1, (steps + 200, 4)).astype(np.float32)
    env.reset(0)
    t0 = None
    for k, a in enumerate(actions):
        if k == 200:
            t0 = time.perf_counter()
        _, _, term, trunc, _ = env.step(a)
        if term or trunc:
            env.reset()
    return steps / (time.perf_counter() - t0)


def vector(n, threads, steps):
    envs = blockpuzzle.make_vec(ENV, num_envs=n, threads=threads, copy=False)
    actions = np.random.default_rng(2).uniform(-1, 1, (steps + 50, n, 4)).astype(np.float32)
    envs.reset(seed=0)
    t0 = None
    for k, a in enumerate(actions):
        if k == 50:
            t0 = time.perf_counter()
        envs.step(a)
    rate = n * steps / (time.perf_counter() - t0)
    envs.close()
    return rate


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=3000)
    args = ap.parse_args()
    print(f"single {single(args.steps):.0f}")
    for n, threads in [(1, 1), (2, 2), (8, 2)]:
        print(f"make_vec n={n} threads={threads} {vector(n, threads, max(args.steps // n, 200)):.0f}")


if __name__ == "__main__":
    main()
