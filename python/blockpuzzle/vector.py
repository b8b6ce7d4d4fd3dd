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
from .env import physics_option
from ._native import Env as _NativeEnv
from ._native import max_episode_steps as _native_max_steps
from ._native import VecEnv as _NativeVecEnv


def _autoreset_mode(mode: AutoresetMode | str) -> AutoresetMode:
    """Gymnasium's autoreset mode from itself, its value ("SameStep") or its name in any case
    ("same_step")."""
    if isinstance(mode, AutoresetMode):
        return mode
    for m in AutoresetMode:
        if isinstance(mode, str) and mode.lower() in (m.value.lower(), m.name.lower()):
            return m
    raise ValueError(f"autoreset_mode {mode!r} is not one of Gymnasium's: {[m.name for m in AutoresetMode]} "
                     "(gymnasium.vector.AutoresetMode, its value or its name)")


class BlockPuzzleVectorEnv(VectorEnv):
    """``num_envs`` copies of one task, stepped by ``threads`` Rust threads with the GIL released.

    Observations, rewards and flags are written into arrays allocated once (``copy=False`` returns
    those arrays themselves, overwritten by the next call; ``copy=True``, the default, returns
    copies). ``autoreset_mode`` is one of Gymnasium's three (``gymnasium.vector.AutoresetMode`` or
    its value): ``NEXT_STEP`` (the default) resets an environment at the ``step`` after its episode
    ends, ignoring its action and returning its first observation with reward 0
    (``info["autoreset"]`` marks it); ``SAME_STEP`` resets it within the step that ends its episode,
    returning the new episode's first observation, with the last one in ``info["final_obs"]`` and
    that step's info in ``info["final_info"]`` (``info["_final_obs"]`` marks which); ``DISABLED``
    never resets: ``reset(options={"reset_mask": ...})`` the environments that ended before stepping
    them again (a step of one that ended is refused). The episodes are the same in every mode: an
    environment reset by autoreset continues its own seed sequence. ``reset(seed=s)`` seeds
    environment i with ``s + i`` (or ``seed[i]`` for a list); environment i's trajectory depends
    only on its own seeds and actions, so it is the same whatever ``num_envs`` and ``threads`` are. ``reset(options=...)`` takes
    ``level``, ``challenge``, ``distribution`` (for every environment reset), ``physics`` (parameters
    of the task's ``[physics]`` table pinned, name to value, for the episodes of the environments reset,
    autoresets included, until the next ``reset``) and ``reset_mask`` (a bool array: reset only those
    environments). A task with a ``[physics]`` table reports each environment's drawn values in
    ``info["physics"]`` (parameter name to an array). ``obs_mode="objects"`` gives ``Dict`` observations
    (``robot``, ``objects``, ``mask``; see ``BlockPuzzleEnv``).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, task: str, num_envs: int, threads: int | None = None, copy: bool = True,
                 obs_mode: str = "flat", max_episode_steps: int | None = None,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP):
        # gymnasium.make_vec passes the spec's step limit: the task's own, where each environment
        # truncates. Another limit is a different task (write it in a task file).
        if max_episode_steps is not None and max_episode_steps != _native_max_steps(str(task)):
            raise ValueError(f"max_episode_steps={max_episode_steps}: {task} truncates its episodes at "
                             f"{_native_max_steps(str(task))} steps; for another limit write a task file with "
                             "max_episode_steps set")
        self.autoreset_mode = _autoreset_mode(autoreset_mode)
        self.metadata = {**type(self).metadata, "autoreset_mode": self.autoreset_mode}
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
        #: The task file's distribution names (``reset(options={"distribution": name})``).
        self.distributions: list[str] = list(single.distributions())
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
        # Environments whose episode ended at the last step and that no reset has reached since.
        self._ended = np.zeros(n, np.bool_)

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
        unknown = set(options) - {"level", "challenge", "distribution", "reset_mask", "physics"}
        if unknown:
            raise ValueError(f"unknown reset options {sorted(unknown)}; known: level, challenge, distribution, "
                             "reset_mask, physics")
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
        info = self._native.reset(self._obs, seeds, mask, level, options.get("challenge"), options.get("distribution"),
                                  physics_option(options.get("physics")))
        if mask is None:
            self._ended[:] = False
        else:
            self._ended[np.asarray(mask, np.bool_)] = False
        return self._out_obs(), info

    def step(self, actions):
        actions = np.ascontiguousarray(actions, dtype=np.float32)
        if actions.shape != self.action_space.shape:
            raise ValueError(
                f"invalid actions of shape {actions.shape}: {self.num_envs} environments take a batch of shape "
                f"{self.action_space.shape}, one row each (nothing is reshaped)"
            )
        mode = self.autoreset_mode
        if mode is AutoresetMode.DISABLED and self._ended.any():
            ended = np.flatnonzero(self._ended).tolist()
            raise ValueError(f"environments {ended} ended at an earlier step and autoreset_mode is DISABLED: reset them "
                             "first, env.reset(options={'reset_mask': mask}) with mask true for those")
        info = self._native.step(actions, self._obs, self._rewards, self._terminated, self._truncated)
        done = self._terminated | self._truncated
        if mode is AutoresetMode.SAME_STEP and done.any():
            info = self._reset_ended(info, done)
        # NEXT_STEP: the engine resets them at the next step; DISABLED: the caller does.
        self._ended = done.copy() if mode is not AutoresetMode.SAME_STEP else np.zeros_like(done)
        return (self._out_obs(), self._out(self._rewards), self._out(self._terminated),
                self._out(self._truncated), info)

    def _reset_ended(self, info: dict[str, Any], done: np.ndarray) -> dict[str, Any]:
        """SAME_STEP: resets the environments in ``done`` now (each continuing its own seed
        sequence, as the next-step reset would), keeping their last observation and step info in
        ``final_obs`` and ``final_info``; their reset's info takes their place in ``info``."""
        n = self.num_envs
        last = observation.split(self._obs.copy(), self.obs_layout)
        final_obs = np.empty(n, dtype=object)
        for i in np.flatnonzero(done):
            final_obs[i] = {k: v[i] for k, v in last.items()} if isinstance(last, dict) else last[i]
        fresh = self._native.reset(self._obs, [None] * n, done.tolist(), None, None, None)
        merged: dict[str, Any] = {}
        for key, value in info.items():
            if key.startswith("_") or key == "autoreset":
                merged[key] = value
                continue
            value = np.array(value, copy=True)
            value[done] = fresh[key][done]
            merged[key] = value
        merged["final_obs"], merged["_final_obs"] = final_obs, done.copy()
        merged["final_info"], merged["_final_info"] = info, done.copy()
        return merged

    def __getstate__(self):
        raise observation.not_copyable(self)

    def __deepcopy__(self, memo):
        raise observation.not_copyable(self)

    def close_extras(self, **kwargs):
        self._native.close()


def make_vec(task: str, num_envs: int = 1, threads: int | None = None, copy: bool = True,
             obs_mode: str = "flat", autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
             **kwargs) -> BlockPuzzleVectorEnv:
    """``num_envs`` environments of ``task`` (an id, with or without ``BlockPuzzle/``, or a task
    file) stepped by ``threads`` Rust threads (default: one per core, at most ``num_envs``), with
    Gymnasium's ``autoreset_mode``."""
    if kwargs:
        raise TypeError(f"unexpected arguments {sorted(kwargs)}")
    task = str(task)
    if task.startswith("BlockPuzzle/"):
        task = task[len("BlockPuzzle/"):]
    return BlockPuzzleVectorEnv(task, num_envs, threads, copy, obs_mode, autoreset_mode=autoreset_mode)
