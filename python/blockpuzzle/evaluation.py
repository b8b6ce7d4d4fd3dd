"""``blockpuzzle.evaluate``: any policy (a callable, numpy in and numpy out, one batch of
observations per call) on an evaluation suite (docs/suites.md), with the CLI's definitions: per
row the success rate with its Wilson 95% interval, the red-blue failure rate, the mean steps to
success and the outcome counts (why episodes ended: success, failure, unstable, no_contact,
off_table, blue_met_grey, timeout); per split the mean success; the suite's score (test mean
success) and generalisation gap (train minus test)."""

from __future__ import annotations

import numpy as np

from . import _native
from ._native import wilson95  # the CLI's interval, computed in Rust
from .vector import make_vec


def evaluate(policy, suite: str, num_envs: int = 8, threads: int | None = None, obs_mode: str = "flat") -> dict:
    """Evaluates ``policy`` on ``suite`` (a built-in name such as "layout", or a suite file).

    ``policy(obs) -> actions`` receives a batch of observations (``num_envs`` rows, or a dict of
    batches with ``obs_mode="objects"``) and returns a ``(num_envs, 4)`` array; rows of
    environments with no episode left to play are ignored. Episode k of a row plays seed
    ``seed + k``, so the numbers do not depend on ``num_envs`` or ``threads``.
    Returns a dict shaped like ``blockpuzzle eval --suite``'s JSON (``suite`` with its sha256,
    ``splits`` of ``rows``, ``score``, ``gap``).
    """
    s = _native.suite(str(suite))
    splits = []
    for name, rows in s["splits"]:
        results = [_row(policy, row, num_envs, threads, obs_mode) for row in rows]
        rates = [r["success_rate"] for r in results]
        splits.append({"name": name, "rows": results, "mean_success": sum(rates) / len(rates)})
    mean = {sp["name"]: sp["mean_success"] for sp in splits}
    return {
        "suite": {"name": s["name"], "sha256": s["sha256"]},
        "summary": s["summary"],
        "splits": splits,
        "score": mean["test"],
        "gap": mean["train"] - mean["test"],
    }


#: Height of the table top (m): a blue or green block that starts above it and ends below it was
#: knocked off (the CLI's ``off_table``; src/scene/xml.rs ``TABLE_TOP_Z``).
TABLE_TOP_Z = 0.4
#: The outcomes in the order they are tested (src/outcome.rs; docs/suites.md).
OUTCOMES = ("success", "failure", "unstable", "no_contact", "off_table", "blue_met_grey", "timeout")
_RED, _BLUE, _GREEN, _GREY = range(4)


def _rows(obs, layout: dict) -> np.ndarray:
    """The object rows of a batch of observations: ``(n, max_objects, features)``."""
    if isinstance(obs, dict):
        return np.asarray(obs["objects"])
    r, f, m = layout["robot_dim"], layout["object_dim"], layout["max_objects"]
    return np.asarray(obs)[:, r:r + m * f].reshape(len(obs), m, f)


def _blocks(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each block slot's colour (0-3; -1 for an absent slot, whose row is zero) and height."""
    hot = rows[..., 15:19]
    colour = np.where(hot.max(axis=-1) > 0.5, hot.argmax(axis=-1), -1)
    return colour, rows[..., 2].copy()


def _outcome(success, failure, unstable, matrix, surfaces, colour0, z0, colour_end, z_end) -> str:
    """The CLI's outcome of one episode (src/outcome.rs), from the episode's contact matrix (rule
    objects gripper, table, blocks, then the floor if it is one), the colours of the gripper, table
    and floor (``surfaces``), and each block's colour and height at the start and the end."""
    if success:
        return "success"
    if failure:
        return "failure"
    if unstable:
        return "unstable"
    m = len(colour0)
    touched = np.asarray(matrix) > 0
    blocks = range(2, 2 + m)
    if not any(touched[0, b] for b in blocks):
        return "no_contact"
    if any(colour0[k] in (_BLUE, _GREEN) and z0[k] > TABLE_TOP_Z and z_end[k] < TABLE_TOP_Z for k in range(m)):
        return "off_table"
    colour = list(surfaces[:2]) + [int(c) for c in colour_end] + list(surfaces[2:])
    n = len(colour)
    if any(colour[a] == _BLUE and colour[b] == _GREY and touched[a, b] for a in range(n) for b in blocks):
        return "blue_met_grey"
    return "timeout"


def _row(policy, row: dict, num_envs: int, threads: int | None, obs_mode: str) -> dict:
    episodes, first = row["episodes"], row["seed"]
    n = min(num_envs, episodes)
    envs = make_vec(row["task"], num_envs=n, threads=threads, obs_mode=obs_mode)
    names = {"red": _RED, "blue": _BLUE, "green": _GREEN, "grey": _GREY}
    rule = [(name, names[c]) for name, c in envs.rule_objects]
    surfaces = [rule[0][1], rule[1][1]] + ([rule[-1][1]] if rule[-1][0] == "floor" else [])
    # As the CLI: the row's level, else the task's last; the row's distribution if it names one.
    options = {"level": envs.max_level if row["level"] is None else row["level"]}
    if row["distribution"] is not None:
        options["distribution"] = row["distribution"]
    obs, _ = envs.reset(seed=[first + i for i in range(n)], options=options)
    colour0, z0 = _blocks(_rows(obs, envs.obs_layout))
    playing = list(range(n))  # the episode each environment plays (None: none left)
    next_episode = n
    steps = np.zeros(n, np.int64)
    success = np.zeros(n, np.bool_)
    failure = np.zeros(n, np.bool_)
    unstable = np.zeros(n, np.bool_)
    successes = failures = success_steps = finished = 0
    outcomes = dict.fromkeys(OUTCOMES, 0)
    while finished < episodes:
        actions = np.asarray(policy(obs), dtype=np.float32).reshape(n, 4)
        obs, _, terminated, truncated, info = envs.step(actions)
        steps += 1
        success |= info["is_success"]
        failure |= info["is_failure"]
        unstable |= info["unstable"]
        ended = [i for i in range(n) if playing[i] is not None and (terminated[i] or truncated[i])]
        if not ended:
            continue
        colour_end, z_end = _blocks(_rows(obs, envs.obs_layout))
        seeds, mask = [None] * n, [False] * n
        for i in ended:
            finished += 1
            successes += int(success[i])
            failures += int(failure[i])
            success_steps += int(steps[i]) if success[i] else 0
            outcomes[_outcome(success[i], failure[i], unstable[i], info["contact_matrix"][i], surfaces, colour0[i],
                              z0[i], colour_end[i], z_end[i])] += 1
            if next_episode < episodes:
                playing[i], seeds[i], mask[i] = next_episode, first + next_episode, True
                next_episode += 1
            else:
                playing[i] = None
            steps[i], success[i], failure[i], unstable[i] = 0, False, False, False
        if any(mask):
            obs, _ = envs.reset(seed=seeds, options={**options, "reset_mask": mask})
            colour, z = _blocks(_rows(obs, envs.obs_layout))
            for i in range(n):
                if mask[i]:
                    colour0[i], z0[i] = colour[i], z[i]
    envs.close()
    return {
        "task": row["task"],
        "distribution": row["distribution"] or "normal",
        "seed": first,
        "episodes": episodes,
        "successes": successes,
        "success_rate": successes / episodes,
        "ci95": wilson95(successes, episodes),
        "failure_rate": failures / episodes,
        "mean_steps_to_success": success_steps / successes if successes else None,
        "outcomes": outcomes,
    }
