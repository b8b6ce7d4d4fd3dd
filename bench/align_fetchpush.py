#!/usr/bin/env python3
"""Reference trajectories of gymnasium-robotics FetchPush-v4 for the alignment check.

Usage: bench/align_fetchpush.py --out REFERENCE.json [--random 4] [--scripted 4] [--steps 50]

Each episode is reset with its seed, then driven by uniformly random actions (seeded) or by a
scripted push (behind the block, down, through it). Written per episode: the state after reset
(qpos and qvel of every joint, by joint name), the actions, and after reset and after every step
the gripper position (observation[0:3], site robot0:grip) and the block position
(observation[3:6], site object0), as FetchPush-v4 reports them. `blockpuzzle align` and
tests/it/align_mujoco3.rs replay the episodes in a FetchPush-like BlockPuzzle environment from
the same states with the same actions and report how far the two drift apart.
"""
import argparse
import json
import os

import gymnasium as gym
import gymnasium_robotics
import mujoco
import numpy as np


def scripted_action(grip, block, phase_state):
    """Pushes the block 0.1 m along +y: behind it, down to its height, then through it."""
    behind = block + np.array([0.0, -0.06, 0.05])
    low = block + np.array([0.0, -0.06, 0.0])
    goal = phase_state.setdefault("goal", block + np.array([0.0, 0.10, 0.0]))
    if phase_state["phase"] == 0 and np.linalg.norm(grip - behind) < 0.01:
        phase_state["phase"] = 1
    if phase_state["phase"] == 1 and np.linalg.norm(grip - low) < 0.01:
        phase_state["phase"] = 2
    target = [behind, low, goal][phase_state["phase"]]
    a = np.zeros(4)
    a[:3] = np.clip((target - grip) / 0.05, -1.0, 1.0)
    return a


def state(env):
    m, d = env.unwrapped.model, env.unwrapped.data
    joints = {}
    for j in range(m.njnt):
        jt = m.jnt_type[j]
        nq = {0: 7, 1: 4}.get(int(jt), 1)  # free, ball, slide/hinge
        nv = {0: 6, 1: 3}.get(int(jt), 1)
        qa, va = m.jnt_qposadr[j], m.jnt_dofadr[j]
        joints[m.joint(j).name] = {"qpos": d.qpos[qa:qa + nq].tolist(), "qvel": d.qvel[va:va + nv].tolist()}
    return joints


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--random", type=int, default=4, help="episodes of random actions")
    ap.add_argument("--scripted", type=int, default=4, help="episodes of the scripted push")
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--f64-actions", action="store_true",
                    help="step with the actions as float64 (FetchPush scales a float32 action in float32)")
    args = ap.parse_args()

    gym.register_envs(gymnasium_robotics)
    env = gym.make("FetchPush-v4", max_episode_steps=args.steps)
    episodes = []
    for kind, count in (("random", args.random), ("scripted", args.scripted)):
        for k in range(count):
            seed = args.seed + k + (0 if kind == "random" else 1000)
            obs, _ = env.reset(seed=seed)
            o = obs["observation"]
            ep = {"kind": kind, "seed": seed, "joints": state(env), "actions": [],
                  "grip": [o[0:3].tolist()], "object": [o[3:6].tolist()]}
            rng = np.random.default_rng(seed)
            phase = {"phase": 0}
            for _ in range(args.steps):
                if kind == "random":
                    a = rng.uniform(-1.0, 1.0, 4)
                else:
                    a = scripted_action(o[0:3].astype(np.float64), o[3:6].astype(np.float64), phase)
                a = a.astype(np.float32)
                obs, _, terminated, truncated, _ = env.step(a.astype(np.float64) if args.f64_actions else a)
                o = obs["observation"]
                ep["actions"].append([float(x) for x in a])
                ep["grip"].append(o[0:3].tolist())
                ep["object"].append(o[3:6].tolist())
                if terminated or truncated:
                    break
            episodes.append(ep)
    # FetchPush's observation is float64 before gymnasium's float32 space: keep full precision.
    out = {"env": "FetchPush-v4", "mujoco": mujoco.__version__,
           "gymnasium_robotics": gymnasium_robotics.__version__, "episodes": episodes}
    with open(args.out + ".tmp", "w") as f:
        json.dump(out, f)
    os.replace(args.out + ".tmp", args.out)
    print(f"[align] {len(episodes)} FetchPush-v4 episodes on MuJoCo {mujoco.__version__} -> {args.out}")


if __name__ == "__main__":
    main()
