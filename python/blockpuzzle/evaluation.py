"""``blockpuzzle.evaluate``: any policy (a callable, numpy in and numpy out, one batch of
observations per call) on an evaluation suite (docs/suites.md), with the CLI's definitions: per
row the success rate with its Wilson 95% interval, the red-blue failure rate and the mean steps
to success; per split the mean success; the suite's score (test mean success) and generalisation
gap (train minus test)."""

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


def _row(policy, row: dict, num_envs: int, threads: int | None, obs_mode: str) -> dict:
    episodes, first = row["episodes"], row["seed"]
    n = min(num_envs, episodes)
    envs = make_vec(row["task"], num_envs=n, threads=threads, obs_mode=obs_mode)
    # As the CLI: the row's level, else the task's last; the row's distribution if it names one.
    options = {"level": envs.max_level if row["level"] is None else row["level"]}
    if row["distribution"] is not None:
        options["distribution"] = row["distribution"]
    obs, _ = envs.reset(seed=[first + i for i in range(n)], options=options)
    playing = list(range(n))  # the episode each environment plays (None: none left)
    next_episode = n
    steps = np.zeros(n, np.int64)
    success = np.zeros(n, np.bool_)
    failure = np.zeros(n, np.bool_)
    successes = failures = success_steps = finished = 0
    while finished < episodes:
        actions = np.asarray(policy(obs), dtype=np.float32).reshape(n, 4)
        obs, _, terminated, truncated, info = envs.step(actions)
        steps += 1
        success |= info["is_success"]
        failure |= info["is_failure"]
        ended = [i for i in range(n) if playing[i] is not None and (terminated[i] or truncated[i])]
        if not ended:
            continue
        seeds, mask = [None] * n, [False] * n
        for i in ended:
            finished += 1
            successes += int(success[i])
            failures += int(failure[i])
            success_steps += int(steps[i]) if success[i] else 0
            if next_episode < episodes:
                playing[i], seeds[i], mask[i] = next_episode, first + next_episode, True
                next_episode += 1
            else:
                playing[i] = None
            steps[i], success[i], failure[i] = 0, False, False
        if any(mask):
            obs, _ = envs.reset(seed=seeds, options={**options, "reset_mask": mask})
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
    }
