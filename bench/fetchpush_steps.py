#!/usr/bin/env python3
"""Time gymnasium-robotics FetchPush-v4 env steps with uniformly random actions.

Usage: fetchpush_steps.py --steps N --seed S [--procs K]

Prints one JSON line:
  {"env": "FetchPush-v4", "steps": N, "seconds": ..., "env_steps_per_s": ..., "procs": K}
With K > 1, K processes each step their own env N times, started together behind a
barrier; seconds is the wall time from the barrier to the last one finishing and
env_steps_per_s = K * N / seconds. Only the stepping loop is timed, after a warm-up.
"""
import argparse
import json
import multiprocessing as mp
import queue
import time

ENV_ID = "FetchPush-v4"
WARMUP_STEPS = 200


def make_env(seed):
    import gymnasium
    import gymnasium_robotics

    gymnasium.register_envs(gymnasium_robotics)
    env = gymnasium.make(ENV_ID)
    env.reset(seed=seed)
    env.action_space.seed(seed)
    return env


def run_steps(env, n):
    for _ in range(n):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            env.reset()


def worker(steps, seed, barrier, out):
    env = make_env(seed)
    run_steps(env, WARMUP_STEPS)
    barrier.wait()
    t0 = time.perf_counter()
    run_steps(env, steps)
    out.put((t0, time.perf_counter()))
    env.close()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, required=True)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--procs", type=int, default=1)
    args = ap.parse_args()
    if args.steps < 1 or args.procs < 1:
        ap.error("--steps and --procs must be >= 1")

    if args.procs == 1:
        env = make_env(args.seed)
        run_steps(env, WARMUP_STEPS)
        t0 = time.perf_counter()
        run_steps(env, args.steps)
        seconds = time.perf_counter() - t0
        env.close()
    else:
        ctx = mp.get_context("spawn")
        barrier, out = ctx.Barrier(args.procs), ctx.Queue()
        procs = [ctx.Process(target=worker, args=(args.steps, args.seed + i, barrier, out))
                 for i in range(args.procs)]
        for p in procs:
            p.start()
        spans = []
        while len(spans) < len(procs):
            try:
                spans.append(out.get(timeout=1.0))
            except queue.Empty:
                if any(p.exitcode not in (None, 0) for p in procs):
                    for p in procs:
                        p.terminate()
                    raise SystemExit("a FetchPush worker process failed")
        for p in procs:
            p.join()
        # perf_counter is CLOCK_MONOTONIC on Linux, so times compare across processes.
        # All workers leave the barrier together; wall time runs to the last finisher.
        seconds = max(end for _, end in spans) - min(start for start, _ in spans)

    total = args.steps * args.procs
    print(json.dumps({"env": ENV_ID, "steps": args.steps, "seconds": round(seconds, 4),
                      "env_steps_per_s": round(total / seconds, 1), "procs": args.procs}))


if __name__ == "__main__":
    main()
