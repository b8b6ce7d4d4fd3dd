"""A Gymnasium vector environment whose N environments step in Rust threads."""

from __future__ import annotations

import os
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from . import observation
from ._checks import whole
from ._native import Env as _NativeEnv
from ._native import max_episode_steps as _native_max_steps
from ._native import VecEnv as _NativeVecEnv


class BlockPuzzleVectorEnv(VectorEnv):
    """``num_envs`` copies of one task, stepped by ``threads`` Rust threads with the GIL released.

    Observations, rewards and flags are written into arrays allocated once (``copy=False`` returns
    those arrays themselves, overwritten by the next call; ``copy=True``, the default, returns
    copies). Autoreset is Gymnasium's next-step mode: the ``step`` after an episode ends resets that
    environment, ignores its action and returns its first observation with reward 0
    (``info["autoreset"]`` marks it). ``reset(seed=s)`` seeds environment i with ``s + i`` (or
    ``seed[i]`` for a list); environment i's trajectory depends only on its own seeds and actions,
    so it is the same whatever ``num_envs`` and ``threads`` are. ``reset(options=...)`` takes
    ``level``, ``challenge``, ``distribution`` (for every environment reset) and ``reset_mask`` (a
    bool array: reset only those environments). ``obs_mode="objects"`` gives ``Dict`` observations
    (``robot``, ``objects``, ``mask``; see ``BlockPuzzleEnv``).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, task: str, num_envs: int, threads: int | None = None, copy: bool = True,
                 obs_mode: str = "flat", max_episode_steps: int | None = None):
        # gymnasium.make_vec passes the spec's step limit: the task's own, where each environment
        # truncates. Another limit is a different task (write it in a task file).
        if max_episode_steps is not None and max_episode_steps != _native_max_steps(str(task)):
            raise ValueError(f"max_episode_steps={max_episode_steps}: {task} truncates its episodes at "
                             f"{_native_max_steps(str(task))} steps; for another limit write a task file with "
                             "max_episode_steps set")
        num_envs = whole("num_envs", num_envs)
        if threads is None:
            threads = min(num_envs, os.cpu_count() or 1, 256)  # 256: the engine's thread bound
        observation.check_mode(obs_mode)
        self._native = _NativeVecEnv(str(task), num_envs, whole("threads", threads), obs_mode)
        single = _NativeEnv(str(task), 1, 1, obs_mode)
        low, high = single.observation_bounds()
        self.obs_mode = obs_mode
        self.obs_layout = single.obs_layout()
        self.max_level = single.max_level
        self.task_id = single.id
        #: The rule objects as the task writes them: (name, colour) of the gripper, the table, each
        #: block slot, then the floor when it is one (the indices of ``info["contact_matrix"]``).
        self.rule_objects = single.objects()
        single.close()
        self.num_envs = int(num_envs)
        self.threads = int(threads)
        self.copy = copy
        self.single_observation_space = observation.space(self.obs_layout, low, high)
        self.single_action_space = spaces.Box(-1.0, 1.0, (4,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        n, d = self.num_envs, self._native.obs_dim
        self._obs = np.zeros((n, d), np.float32)
        self._rewards = np.zeros(n, np.float32)
        self._terminated = np.zeros(n, np.bool_)
        self._truncated = np.zeros(n, np.bool_)

    def _out(self, a):
        return a.copy() if self.copy else a

    def _out_obs(self):
        return observation.split(self._out(self._obs), self.obs_layout)

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None):
        # The vector's own generator takes an int seed (a list seeds the environments only).
        super().reset(seed=int(seed) if isinstance(seed, (int, np.integer)) else None)
        n = self.num_envs
        if seed is None:
            seeds = [None] * n
        elif isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = [None if s is None else int(s) for s in seed]
            if len(seeds) != n:
                raise ValueError(f"seed has {len(seeds)} entries; the vector has {n} environments")
        options = dict(options or {})
        unknown = set(options) - {"level", "challenge", "distribution", "reset_mask"}
        if unknown:
            raise ValueError(f"unknown reset options {sorted(unknown)}; known: level, challenge, distribution, reset_mask")
        mask = options.get("reset_mask")
        if mask is not None:
            given = np.asarray(mask)
            if given.shape != (n,):
                raise ValueError(f"options['reset_mask'] has shape {given.shape}; the vector has {n} environments: "
                                 f"give one bool per environment, shape ({n},)")
            mask = [bool(m) for m in given.astype(np.bool_)]
        level = options.get("level")
        if level is not None and (isinstance(level, bool) or not isinstance(level, (int, np.integer)) or level < 0):
            raise ValueError(f"options['level'] must be an int >= 0, not {level!r}")
        info = self._native.reset(self._obs, seeds, mask, level, options.get("challenge"), options.get("distribution"))
        return self._out_obs(), info

    def step(self, actions):
        actions = np.ascontiguousarray(actions, dtype=np.float32)
        if actions.shape != self.action_space.shape:
            raise ValueError(
                f"invalid actions of shape {actions.shape}: {self.num_envs} environments take a batch of shape "
                f"{self.action_space.shape}, one row each (nothing is reshaped)"
            )
        info = self._native.step(actions, self._obs, self._rewards, self._terminated, self._truncated)
        return (self._out_obs(), self._out(self._rewards), self._out(self._terminated),
                self._out(self._truncated), info)

    def __getstate__(self):
        raise observation.not_copyable(self)

    def __deepcopy__(self, memo):
        raise observation.not_copyable(self)

    def close_extras(self, **kwargs):
        self._native.close()


def make_vec(task: str, num_envs: int = 1, threads: int | None = None, copy: bool = True,
             obs_mode: str = "flat", **kwargs) -> BlockPuzzleVectorEnv:
    """``num_envs`` environments of ``task`` (an id, with or without ``BlockPuzzle/``, or a task
    file) stepped by ``threads`` Rust threads (default: one per core, at most ``num_envs``)."""
    if kwargs:
        raise TypeError(f"unexpected arguments {sorted(kwargs)}")
    task = str(task)
    if task.startswith("BlockPuzzle/"):
        task = task[len("BlockPuzzle/"):]
    return BlockPuzzleVectorEnv(task, num_envs, threads, copy, obs_mode)
