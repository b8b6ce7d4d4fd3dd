#!/usr/bin/env python3
"""Env steps/s of the Python package: the binding's per-step cost against the Rust env's own step,
and blockpuzzle.make_vec("BlocksTouch-v0", num_envs=N) against gymnasium-robotics FetchPush-v4 in
Gymnasium's SyncVectorEnv and AsyncVectorEnv, N = 1, 2, 8, random actions, side by side in one run.

Usage: python bench/python_vector.py [--steps 4000] [--ns 1 2 8]    (bench/python_vector.sh sets up the venv)
Prints a Markdown report.
"""
import argparse
import os
import platform
import time

import gymnasium as gym
import numpy as np

import blockpuzzle
from blockpuzzle import _native

ENV = "BlocksTouch-v0"


def rust_loop(steps):
    env = _native.Env(ENV, 1, 1)
    env.bench_steps(200)  # warm-up
    return steps / env.bench_steps(steps, 1)


def python_single(steps):
    env = _native.Env(ENV, 1, 1)
    rng = np.random.default_rng(1)
    actions = rng.uniform(-1, 1, (steps, 4)).astype(np.float32)
    env.reset(0)
    for a in actions[:200]:
        _, _, term, trunc, _ = env.step(a)
        if term or trunc:
            env.reset()
    t0 = time.perf_counter()
    for a in actions:
        _, _, term, trunc, _ = env.step(a)
        if term or trunc:
            env.reset()
    return steps / (time.perf_counter() - t0)


def timed_vector(envs, steps, n):
    rng = np.random.default_rng(2)
    pool = [envs.action_space.sample() for _ in range(64)] if not hasattr(envs, "_native") else \
        [rng.uniform(-1, 1, (n, 4)).astype(np.float32) for _ in range(64)]
    envs.reset(seed=0)
    for k in range(50):
        envs.step(pool[k % 64])
    t0 = time.perf_counter()
    for k in range(steps):
        envs.step(pool[k % 64])
    seconds = time.perf_counter() - t0
    envs.close()
    return n * steps / seconds


def fetchpush(mode, n, steps):
    import gymnasium_robotics

    gym.register_envs(gymnasium_robotics)
    envs = gym.make_vec("FetchPush-v4", num_envs=n, vectorization_mode=mode)
    envs.action_space.seed(0)
    return timed_vector(envs, steps, n)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=4000, help="vector steps per measurement")
    ap.add_argument("--ns", type=int, nargs="+", default=[1, 2, 8])
    args = ap.parse_args()
    cores = os.cpu_count() or 1

    rust = rust_loop(args.steps)
    py = python_single(args.steps)
    overhead = (1 / py - 1 / rust) / (1 / rust)
    print(f"## One environment ({ENV})\n")
    print("| loop | env steps/s | µs per step |\n|---|---|---|")
    print(f"| Rust (`Env.bench_steps`, no Python in the loop) | {rust:.0f} | {1e6 / rust:.1f} |")
    print(f"| Python calling `env.step` | {py:.0f} | {1e6 / py:.1f} |")
    print(f"\nBinding overhead: {100 * overhead:.1f}% of the Rust step (target: under 10%).\n")

    print(f"## Vector environments, random actions ({cores} cores)\n")
    print("| N | blockpuzzle.make_vec (threads) | FetchPush-v4 SyncVectorEnv | FetchPush-v4 AsyncVectorEnv | "
          "make_vec / Async |\n|---|---|---|---|---|")
    for n in args.ns:
        threads = min(n, cores)
        bp = timed_vector(blockpuzzle.make_vec(ENV, num_envs=n, threads=threads), args.steps, n)
        sync = fetchpush("sync", n, max(args.steps // 4, 200))
        asyn = fetchpush("async", n, max(args.steps // 4, 200))
        print(f"| {n} | {bp:.0f} ({threads}) | {sync:.0f} | {asyn:.0f} | {bp / asyn:.2f}× |")
    print(f"\nCPU: {platform.processor() or platform.machine()}, {cores} cores; steps/s are env steps "
          "(vector steps × N). Target: make_vec ≥ 1.5× AsyncVectorEnv at N = 8.")


if __name__ == "__main__":
    main()
