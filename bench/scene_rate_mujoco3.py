#!/usr/bin/env python3
"""mj_step/s of a BlockPuzzle scene under the MuJoCo Python bindings of the bench venv.

Usage: bench/scene_rate_mujoco3.py SCENE.xml [--steps-per-episode 50] [--episodes 60]

SCENE.xml is what `blockpuzzle scene --env ID` prints, saved inside models/ so that
its includes resolve. The robot is set up as in BlockEnv (base joints, weld reset,
gripper 0.2 m above the Fetch default, 10 settling actions), then driven by random
mocap moves of up to 5 cm per action, 20 substeps each, like the environment. Only
mj_step is timed. Compare with `blockpuzzle bench` (MuJoCo 2.2.2), whose
mj_steps_per_s counts the same thing.
"""
import argparse
import json
import time

import mujoco
import numpy as np


def settle(m, d):
    """The robot as BlockEnv sets it up: base joints, weld reset, gripper 0.2 m above the
    Fetch default, then 200 substeps to settle."""
    for i in range(m.neq):
        if m.eq_type[i] == mujoco.mjtEq.mjEQ_WELD:
            m.eq_data[i, :7] = [0, 0, 0, 0, 0, 0, 1]
    for k, v in enumerate([0.405, 0.48, 0.0]):
        d.qpos[m.jnt_qposadr[m.joint(f"robot0:slide{k}").id]] = v
    mujoco.mj_forward(m, d)
    d.mocap_pos[0] = d.site("robot0:grip").xpos + [-0.498, 0.005, -0.431 + 0.2]
    d.mocap_quat[0] = [1, 0, 1, 0]
    mujoco.mj_step(m, d, nstep=200)


def episodes(m, n, seed, steps_per_episode=50, on_substep=None, on_step=None):
    """n random-action episodes (blocks in a simple level-0-like layout, mocap moves of up
    to 5 cm, 20 substeps per action). Returns (seconds in mj_step, substeps). With
    on_substep(d) the substeps run one by one (and are not timed); on_step(d) is called
    after each action."""
    d = mujoco.MjData(m)
    settle(m, d)
    q0, v0 = d.qpos.copy(), d.qvel.copy()
    grip0 = d.site("robot0:grip").xpos[:2].copy()
    gripper = m.body("robot0:gripper_link").id
    blocks = [m.jnt_qposadr[j] for j in range(m.njnt) if m.joint(j).name.startswith("block")]
    rng = np.random.default_rng(seed)
    physics, substeps = 0.0, 0
    for _ in range(n):
        mujoco.mj_resetData(m, d)
        d.qpos[:], d.qvel[:] = q0, v0
        for k, adr in enumerate(blocks):
            d.qpos[adr:adr + 2] = grip0 + rng.uniform(-0.08, 0.08, 2) + [0.0, 0.08 * k]
        mujoco.mj_forward(m, d)
        for _ in range(steps_per_episode):
            d.mocap_pos[0] = d.xpos[gripper] + rng.uniform(-1, 1, 3) * 0.05
            d.mocap_quat[0] = d.xquat[gripper] + [1, 0, 1, 0]
            if on_substep:
                for _ in range(20):
                    mujoco.mj_step(m, d)
                    on_substep(d)
            else:
                t = time.perf_counter()
                mujoco.mj_step(m, d, nstep=20)
                physics += time.perf_counter() - t
            substeps += 20
            mujoco.mj_forward(m, d)
            if on_step:
                on_step(d)
    return physics, substeps


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("--episodes", type=int, default=60)
    ap.add_argument("--steps-per-episode", type=int, default=50)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()

    m = mujoco.MjModel.from_xml_path(args.scene)
    physics, substeps = episodes(m, args.episodes, args.seed, args.steps_per_episode)
    print(json.dumps({"mujoco": mujoco.__version__, "scene": args.scene, "mj_steps_per_s": round(substeps / physics)}))


if __name__ == "__main__":
    main()
