"""``blockpuzzle.evaluate``: any policy (a callable, numpy in and numpy out, one batch of
observations per call) on an evaluation suite (docs/suites.md), with the CLI's definitions: per
row the success rate with its Wilson 95% interval, the red-blue failure rate, the mean steps to
success and the outcome counts (why episodes ended: success, failure, unstable, no_contact,
off_table, blue_met_grey, timeout); per split the mean success; the suite's score (test mean
success) and generalisation gap (train minus test).

A zoo policy (``blockpuzzle.zoo.load``) is evaluated by the command line's own evaluator and
forward pass (in the extension), so its numbers are the CLI's on the same engine, outcome count
for outcome count; any other callable plays through this module's loop. Every result carries a
``provenance`` block: package, commit, MuJoCo version, harness, policy, suite."""

from __future__ import annotations

import json
import os
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from . import _native
from ._checks import whole
from ._native import wilson95  # the CLI's interval, computed in Rust
from .vector import make_vec


def evaluate(policy: Callable[[Any], Any], suite: str, num_envs: int = 8, threads: int | None = None,
             obs_mode: str | None = None, name: str | None = None, episodes: int | None = None,
             progress: bool = True) -> dict[str, Any]:
    """Evaluates ``policy`` on ``suite`` (a built-in name such as "layout", or a suite file).

    ``policy`` is a zoo policy (``blockpuzzle.zoo.load(...)``), evaluated exactly as
    ``blockpuzzle eval --suite`` evaluates it (its own observation mode; a policy trained without
    grey blocks sees them removed; rows whose observation it cannot read are skipped, with the
    reason), or any callable ``policy(obs) -> actions``: it receives a batch of observations
    (``num_envs`` rows, or a dict of batches with ``obs_mode="objects"``) and returns a
    ``(num_envs, 4)`` array; rows of environments with no episode left to play are ignored. A
    callable with an ``obs_mode`` attribute gets that mode unless ``obs_mode`` is given; one that
    fails on a row's observation raises a ValueError naming the row's task and observation shape.
    Episode k of a row plays seed ``seed + k``, so the numbers do not depend on ``num_envs`` or
    ``threads``. ``name`` names the policy in the result (default: the zoo entry's name, else the
    callable's ``__name__``).

    ``episodes=N`` plays only the first N episodes of each row: a quick look, recorded in the
    result (``suite["episodes_per_row"]``), which is then not the suite's score (``blockpuzzle
    results`` refuses to rank it). ``progress`` prints a line per row to stderr as it is done.

    Returns the dict ``blockpuzzle eval --suite`` writes as JSON: ``provenance`` (``blockpuzzle``,
    ``commit``, ``mujoco``, ``harness`` "python", ``policy`` name and sha256, ``suite``),
    ``suite`` with its sha256, ``splits`` of ``rows`` (each with its ``task_sha256`` and its
    ``evaluation``), ``score`` and ``gap``.
    """
    num_envs = whole("num_envs", num_envs)
    threads = None if threads is None else whole("threads", threads)
    episodes = None if episodes is None else whole("episodes", episodes)
    on_row = _Progress(str(suite), episodes) if progress else None
    actor = getattr(policy, "native", None)
    if actor is not None:
        if obs_mode is not None and obs_mode != policy.obs_mode:
            raise ValueError(f"{policy.name} reads {policy.obs_mode!r} observations, not obs_mode={obs_mode!r}: "
                             "leave obs_mode out for a zoo policy")
        return json.loads(_native.evaluate_saved(str(policy.path), name or policy.name, str(suite), threads,
                                                 episodes, on_row))
    if not callable(policy):
        raise TypeError(f"evaluate() takes a callable policy(obs) -> actions or a zoo policy, and got "
                        f"{_what(policy)}")
    s = _native.suite(str(suite), episodes)
    name = name or getattr(policy, "__name__", type(policy).__name__)
    obs_mode = obs_mode or getattr(policy, "obs_mode", None) or "flat"
    total, done = sum(len(rows) for _, rows in s["splits"]), 0
    splits = []
    for split, rows in s["splits"]:
        results = []
        for row in rows:
            results.append(_row(policy, row, num_envs, threads, obs_mode))
            done += 1
            if on_row is not None:
                on_row(split, results[-1], done, total)
        rates = [r["evaluation"]["success_rate"] for r in results]
        splits.append({"name": split, "rows": results, "mean_success": sum(rates) / len(rates)})
    mean = {sp["name"]: sp["mean_success"] for sp in splits}
    suite_id = s["id"]
    return {
        "provenance": {**_native.build_info(), "harness": "python", "policy": {"name": name, "sha256": None},
                       "suite": suite_id},
        "suite": suite_id,
        "summary": s["summary"],
        "policy": name,
        "splits": splits,
        "score": mean["test"],
        "gap": mean["train"] - mean["test"],
    }


def _what(policy) -> str:
    """What a non-callable ``policy`` is, and what to pass instead."""
    if policy is None:
        return "None; pass the policy itself, e.g. blockpuzzle.zoo.load(NAME) or blockpuzzle.policies.solver()"
    if isinstance(policy, (str, bytes)) or hasattr(policy, "__fspath__"):
        return (f"{policy!r}, a name or path; load the zoo entry first: "
                f"blockpuzzle.evaluate(blockpuzzle.zoo.load({str(policy)!r}), ...)")
    if hasattr(policy, "predict"):
        return (f"a {type(policy).__name__} with .predict (a Stable-Baselines3 model?); pass "
                "lambda obs: model.predict(obs, deterministic=True)[0]")
    return f"a {type(policy).__name__}, which is not callable"


class _Progress:
    """One line per row on stderr: how far, the row, its success and the time so far."""

    def __init__(self, suite: str, episodes: int | None):
        self.suite = suite if episodes is None else f"{suite} (first {episodes} episodes per row)"
        self.start = time.monotonic()

    def __call__(self, split: str, row: dict, done: int, total: int) -> None:
        e = row.get("evaluation")
        what = f"success {e['success_rate']:.3f}" if e else f"skipped ({row.get('skipped')})"
        print(f"[{self.suite}] {done}/{total} {split} {row['task']} {row['distribution']}: {what} "
              f"({time.monotonic() - self.start:.0f} s)", file=sys.stderr, flush=True)


#: The outcomes in the order they are tested (src/episode/outcome.rs's ``Outcome::ALL``; docs/suites.md).
OUTCOMES: tuple[str, ...] = tuple(_native.facts()["outcomes"])
#: The colours in one-hot order (src/sim/rules.rs's ``Colour::ALL``): a colour's index is its place.
COLOURS: tuple[str, ...] = tuple(_native.facts()["colours"])


def _rows(obs, layout: dict) -> np.ndarray:
    """The blocks' rows of a batch of observations: ``(n, max_objects, features)`` (in the
    ``entities`` mode the gripper's, table's and floor's rows follow them, left out here)."""
    m = layout["max_objects"]
    if isinstance(obs, dict):
        return np.asarray(obs[layout["rows_key"]])[:, :m]
    r, f = layout["robot_dim"], layout["object_dim"]
    return np.asarray(obs)[:, r:r + m * f].reshape(len(obs), m, f)


def _blocks(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each block slot's colour (0-3; -1 for an absent slot, whose row is zero) and height."""
    hot = rows[..., 15:19]
    colour = np.where(hot.max(axis=-1) > 0.5, hot.argmax(axis=-1), -1)
    return colour, rows[..., 2].copy()


def _outcome(success, failure, unstable, matrix, surfaces, z0, colour_end, z_end) -> str:
    """The CLI's outcome of one episode, classified by the CLI's own code (``_native.outcome``),
    from the episode's contact matrix (rule objects gripper, table, blocks, then the floor if it is
    one), the colours of the gripper, table and floor (``surfaces``), and each block's colour and
    its height at the start and the end."""
    colours = list(surfaces[:2]) + [int(c) for c in colour_end] + list(surfaces[2:])
    touched = (np.asarray(matrix) > 0).tolist()
    return _native.outcome(bool(success), bool(failure), bool(unstable), touched, colours,
                           [float(z) for z in z0], [float(z) for z in z_end])


def _row(policy, row: dict, num_envs: int, threads: int | None, obs_mode: str) -> dict:
    episodes, first = row["episodes"], row["seed"]
    n = min(num_envs, episodes)
    if row["generated"]:
        # A task drawn from a family (no file holds it): its text, in a file of its own while it runs.
        import tempfile  # noqa: PLC0415
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, f"{row['task_id']}.toml")
            with open(path, "w") as f:
                f.write(row["toml"])
            envs = make_vec(path, num_envs=n, threads=threads, obs_mode=obs_mode)
    else:
        envs = make_vec(row["task"], num_envs=n, threads=threads, obs_mode=obs_mode)
    rule = [(name, COLOURS.index(c)) for name, c in envs.rule_objects]
    surfaces = [rule[0][1], rule[1][1]] + ([rule[-1][1]] if rule[-1][0] == "floor" else [])
    # As the CLI: the row's level, else the task's last; the row's distribution if it names one.
    level = envs.max_level if row["level"] is None else row["level"]
    options = {"level": level}
    if row["distribution"] is not None:
        options["distribution"] = row["distribution"]
    obs, _ = envs.reset(seed=[first + i for i in range(n)], options=options)
    _, z0 = _blocks(_rows(obs, envs.obs_layout))
    playing = list(range(n))  # the episode each environment plays (None: none left)
    next_episode = n
    steps = np.zeros(n, np.int64)
    success = np.zeros(n, np.bool_)
    failure = np.zeros(n, np.bool_)
    unstable = np.zeros(n, np.bool_)
    successes = failures = success_steps = finished = 0
    outcomes = dict.fromkeys(OUTCOMES, 0)
    while finished < episodes:
        try:
            actions = np.asarray(policy(obs), dtype=np.float32)
        except (ValueError, TypeError, IndexError) as e:
            shape = {k: v.shape for k, v in obs.items()} if isinstance(obs, dict) else obs.shape
            raise ValueError(f"the policy failed on {row['task_id']}'s observations (obs_mode={obs_mode!r}, "
                             f"batch shape {shape}): {e}. Give obs_mode= the mode the policy reads; a policy "
                             "trained on one task reads only tasks with the same observation") from e
        except Exception as e:
            # Any other error of the user's policy keeps its type, with the row it failed on.
            where = f"raised by the policy on the suite row {row['task_id']} (obs_mode={obs_mode!r})"
            if hasattr(e, "add_note"):
                e.add_note(where)
                raise
            raise RuntimeError(f"{type(e).__name__}: {e} ({where})") from e
        if actions.shape != (n, 4):
            raise ValueError(f"the policy returned actions of shape {actions.shape} for {n} observations; "
                             f"return one action per observation, shape ({n}, 4)")
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
            outcomes[_outcome(success[i], failure[i], unstable[i], info["contact_matrix"][i], surfaces, z0[i],
                              colour_end[i], z_end[i])] += 1
            if next_episode < episodes:
                playing[i], seeds[i], mask[i] = next_episode, first + next_episode, True
                next_episode += 1
            else:
                playing[i] = None
            steps[i], success[i], failure[i], unstable[i] = 0, False, False, False
        if any(mask):
            obs, _ = envs.reset(seed=seeds, options={**options, "reset_mask": mask})
            _, z = _blocks(_rows(obs, envs.obs_layout))
            for i in range(n):
                if mask[i]:
                    z0[i] = z[i]
    envs.close()
    # The CLI's row (src/benchmark/evaluate.rs RowResult), field for field.
    return {
        "task": row["task_id"],
        "task_sha256": row["task_sha256"],
        "distribution": row["distribution"] or "normal",
        "seed": first,
        "episodes": episodes,
        "evaluation": {
            "env": row["task_id"],
            "task_sha256": row["task_sha256"],
            "challenge": False,
            "level": level,
            "episodes": episodes,
            "seed": first,
            "successes": successes,
            "success_rate": successes / episodes,
            "ci95": list(wilson95(successes, episodes)),
            "grey_blind": False,
            "outcomes": outcomes,
            "mean_steps_to_success": success_steps / successes if successes else None,
        },
        "failure_rate": failures / episodes,
        "skipped": None,
    }
