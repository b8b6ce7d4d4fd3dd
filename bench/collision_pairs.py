#!/usr/bin/env python3
"""Could excluding collision pairs make mj_step faster without changing the physics?

Usage: bench/collision_pairs.py SCENE.xml [--episodes 40] [--grid 25]

SCENE.xml is what `blockpuzzle scene --env ID` prints, saved inside models/ so that its
includes resolve. Run with the MuJoCo 3 bench venv (bench/fetchpush_venv.sh); it needs
mj_geomDistance. The robot is driven as in bench/scene_rate_mujoco3.py (random mocap
moves of up to 5 cm, 20 substeps per action). The script reports:

1. the geom pairs that produced contacts over the episodes;
2. the eligible pairs (not excluded, not parent-child) whose bounding spheres overlap in
   most states but that never produced a contact: MuJoCo runs the convex narrow phase on
   them every substep for nothing;
3. the mj_step time saved by excluding those pairs (ratio of times, the two models
   alternated in one process) and the largest joint-position difference between the two
   models' trajectories (0 means that excluding them changed nothing on these episodes);
4. the smallest signed distance of each such pair over a grid of the joints that move them,
   within their limits (plus 0.05 rad): a negative distance means the pair can touch in some
   reachable pose, so excluding it would change the model there.
"""
import argparse
import itertools
import os

import mujoco
import numpy as np

from scene_rate_mujoco3 import episodes  # the same random-action driver


def eligible_pairs(m):
    excluded = {frozenset((s >> 16, s & 0xFFFF)) for s in m.exclude_signature[: m.nexclude]}
    geoms = [g for g in range(m.ngeom) if m.geom_contype[g] or m.geom_conaffinity[g]]
    out = []
    for a, b in itertools.combinations(geoms, 2):
        wa, wb = m.body_weldid[m.geom_bodyid[a]], m.body_weldid[m.geom_bodyid[b]]
        if wa == wb or frozenset((m.geom_bodyid[a], m.geom_bodyid[b])) in excluded:
            continue
        pa, pb = m.body_weldid[m.body_parentid[wa]], m.body_weldid[m.body_parentid[wb]]
        if (pa == wb and wb != 0) or (pb == wa and wa != 0):
            continue  # MuJoCo filters parent-child pairs by default
        out.append((a, b))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("--episodes", type=int, default=40)
    ap.add_argument("--grid", type=int, default=25)
    args = ap.parse_args()
    xml = open(args.scene).read()
    m = mujoco.MjModel.from_xml_path(args.scene)
    name = lambda g: m.geom(g).name or m.body(m.geom_bodyid[g]).name

    touched = set()
    episodes(m, args.episodes, 0, on_substep=lambda d: touched.update(
        frozenset((c.geom1, c.geom2)) for c in d.contact[: d.ncon]))
    print("1. pairs that touched:", sorted(f"{name(a)}/{name(b)}" for a, b in map(tuple, touched)))

    pairs = [p for p in eligible_pairs(m) if frozenset(p) not in touched]
    near = dict.fromkeys(pairs, 0)

    def count_near(d):
        for a, b in pairs:
            reach = m.geom_rbound[a] + m.geom_rbound[b] + m.geom_margin[a] + m.geom_margin[b]
            near[(a, b)] += np.linalg.norm(d.geom_xpos[a] - d.geom_xpos[b]) < reach

    _, substeps = episodes(m, args.episodes // 2, 1, on_step=count_near)
    states = substeps // 20  # one state per action
    often = [p for p in pairs if near[p] > 0.5 * states]
    print("2. never touched, bounding spheres overlapping in > 50% of states:")
    for p in often:
        print(f"   {name(p[0])} / {name(p[1])}: {near[p] / states:.2f}")
    if not often:
        return

    body = lambda g: m.body(m.geom_bodyid[g]).name
    excludes = "".join(f'<exclude body1="{body(a)}" body2="{body(b)}"/>' for a, b in often)
    if "</contact>" not in xml:
        raise SystemExit(f"{args.scene}: no <contact> section to add the exclusions to")
    tmp = args.scene.replace(".xml", ".excluded.xml")
    with open(tmp, "w") as f:
        f.write(xml.replace("</contact>", excludes + "</contact>", 1))
    try:
        m2 = mujoco.MjModel.from_xml_path(tmp)
    finally:
        os.remove(tmp)
    qa, qb = [], []
    episodes(m, 10, 2, on_step=lambda d: qa.append(d.qpos.copy()))
    episodes(m2, 10, 2, on_step=lambda d: qb.append(d.qpos.copy()))
    diff = max(float(np.abs(a - b).max()) for a, b in zip(qa, qb))
    ratios = []
    for r in range(6):
        t1, _ = episodes(m, 20, 10 + r)
        t2, _ = episodes(m2, 20, 10 + r)
        ratios.append(t1 / t2)
    print(f"3. excluding them: mj_step {np.median(ratios):.3f}x faster (median of {len(ratios)}: "
          f"{', '.join(f'{x:.3f}' for x in ratios)}); largest qpos difference {diff:g}")

    print("4. smallest signed distance within the joint limits (grid of the joints that move the pair):")
    d = mujoco.MjData(m)
    for a, b in often:
        chain = set()
        for g in (a, b):
            bid = m.geom_bodyid[g]
            while bid:
                chain.update(j for j in range(m.njnt) if m.jnt_bodyid[j] == bid and m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE)
                bid = m.body_parentid[bid]
        joints = sorted(j for j in chain if m.jnt_limited[j])
        grids = [np.linspace(m.jnt_range[j][0] - 0.05, m.jnt_range[j][1] + 0.05, args.grid) for j in joints]
        best, where = np.inf, None
        for values in itertools.product(*grids):
            for j, v in zip(joints, values):
                d.qpos[m.jnt_qposadr[j]] = v
            mujoco.mj_kinematics(m, d)
            dist = mujoco.mj_geomDistance(m, d, a, b, 1.0, None)
            if dist < best:
                best, where = dist, values
        at = ", ".join(f"{m.joint(j).name}={v:.2f}" for j, v in zip(joints, where))
        print(f"   {name(a)} / {name(b)}: {best:+.4f} m at {at}")


if __name__ == "__main__":
    main()
