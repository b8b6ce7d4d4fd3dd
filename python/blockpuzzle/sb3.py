"""Stable-Baselines3 over the Rust vector environment: ``SB3VecEnv``, SB3's ``VecEnv`` interface
around ``blockpuzzle.make_vec`` (N environments stepped by Rust threads, the GIL released).

SB3 does not take a Gymnasium vector environment (``make_vec``'s is refused as "not a Gymnasium
environment"): it has a vector interface of its own, with the auto-reset inside ``step_wait``
(the episode's last observation in ``infos[i]["terminal_observation"]``), seeds and options set
ahead of ``reset()``, and per-environment ``get_attr`` / ``set_attr`` / ``env_method``. This
class gives that interface; where ``stable_baselines3`` is installed it is a subclass of SB3's
``VecEnv`` (so SB3's algorithms and ``VecEnvWrapper``s take it), elsewhere it stands alone with the
same methods. This module does not import SB3 unless it is installed, and the package does not
import this module: ``from blockpuzzle.sb3 import SB3VecEnv``.

    from stable_baselines3 import TD3
    from blockpuzzle.sb3 import SB3VecEnv

    envs = SB3VecEnv("BlocksTouch-v0", num_envs=8, threads=2)
    model = TD3("MlpPolicy", envs, seed=0).learn(10_000)
    envs.set_attr("level", 3)           # a curriculum: each environment's next episode on level 3

Environment i's episodes are those ``gym.make("BlockPuzzle/<id>")`` plays with the same seeds and
actions, whatever ``num_envs`` and ``threads`` are.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from typing import Any, Union

import gymnasium
import numpy as np

from .vector import BlockPuzzleVectorEnv


def _sb3_base() -> type:
    """SB3's ``VecEnv`` where stable_baselines3 is installed, else ``object``."""
    try:
        from stable_baselines3.common.vec_env import VecEnv
    except ImportError:
        return object
    return VecEnv


#: Which environments a call is for: all (None), one index, or a list of them (SB3's ``VecEnvIndices``).
Indices = Union[None, int, Sequence[int]]
#: The class ``SB3VecEnv`` derives from: SB3's ``VecEnv``, or ``object`` without SB3.
BASE = _sb3_base()
#: The per-environment settings ``set_attr`` takes: each applies from the environment's next
#: episode on (auto-reset or ``reset()``) and stays in force, as the reset options of
#: ``BlockPuzzleEnv`` do.
SETTABLE = ("level", "challenge", "distribution")
#: What ``env_method`` calls on environment i.
METHODS = ("reset", "get_wrapper_attr", "set_wrapper_attr", "has_wrapper_attr")


class SB3VecEnv(BASE):  # type: ignore[misc,valid-type]
    """``num_envs`` environments of ``task`` (an id, with or without ``BlockPuzzle/``, or a task
    file) stepped by ``threads`` Rust threads, behind Stable-Baselines3's ``VecEnv`` interface.

    * ``reset()`` resets every environment with the seeds of ``seed(s)`` (environment i gets
      ``s + i``; without one, each environment's generator goes on) and the options of
      ``set_options`` (``level``, ``challenge``, ``distribution``); both are used once, as SB3 does.
      Returns the observations: an array ``(num_envs, obs_dim)``, or for ``obs_mode="objects"`` or
      ``"entities"`` a dict of arrays (``robot``, rows, ``mask``; SB3's ``MultiInputPolicy``).
    * ``step_async(actions)`` then ``step_wait()`` (or ``step(actions)``) step them: actions
      ``(num_envs, 4)``; returns observations, rewards ``float32 (num_envs,)``, dones ``bool
      (num_envs,)`` and a list of info dicts. An environment whose episode ended is reset at once
      (its seed stream going on): its observation is the new episode's first, its info has the
      ended episode's last in ``terminal_observation``, and ``TimeLimit.truncated`` says whether
      the episode was cut at the step limit rather than ended by the rules (``is_success``,
      ``is_failure`` and the Gymnasium environment's other info keys are there too).
    * ``get_attr(name)``: per environment ``task_id``, ``max_level``, ``max_episode_steps``,
      ``obs_mode``, ``obs_layout``, ``objects``, ``observation_space``, ``action_space``, ``spec``,
      ``render_mode`` (None), ``metadata``, and ``level``, ``challenge``, ``distribution``: the value
      for the environment's next episode where ``set_attr`` set one, else its current episode's.
    * ``set_attr(name, value)``: ``level``, ``challenge`` or ``distribution``, applied from each
      environment's next episode on (a curriculum: ``set_attr("level", 3)``).
    * ``env_method("reset", seed=..., options=...)`` resets environment i alone and returns its
      ``(obs, info)``; ``get_wrapper_attr`` / ``set_wrapper_attr`` / ``has_wrapper_attr`` are the
      attributes above.
    * ``env_is_wrapped`` is False (no Gymnasium wrappers: wrap the vector in SB3's ``VecMonitor``
      for episode statistics), ``render`` and ``get_images`` raise (render a ``gym.make``
      environment with the same seed), ``close()`` frees the threads and simulations.
    """

    def __init__(self, task: str, num_envs: int = 1, threads: int | None = None, obs_mode: str = "flat") -> None:
        task = str(task)
        if task.startswith("BlockPuzzle/"):
            task = task[len("BlockPuzzle/"):]
        self.venv = BlockPuzzleVectorEnv(task, num_envs, threads, copy=True, obs_mode=obs_mode)
        n = self.venv.num_envs
        self._task = task
        self._actions: np.ndarray | None = None
        self._pending: list[dict[str, Any]] = [{} for _ in range(n)]
        self._current: list[dict[str, Any]] = [{"level": None, "challenge": None, "distribution": None}
                                                for _ in range(n)]
        self._closed = False
        space, action = self.venv.single_observation_space, self.venv.single_action_space
        if BASE is object:
            self.num_envs, self.observation_space, self.action_space = n, space, action
            self.reset_infos: list[dict[str, Any]] = [{} for _ in range(n)]
            self._seeds: list[int | None] = [None] * n
            self._options: list[dict[str, Any]] = [{} for _ in range(n)]
            self.render_mode = None
            self.metadata: dict[str, Any] = {"render_modes": []}
        else:
            # SB3's constructor sets the same fields, reading render_mode through get_attr.
            BASE.__init__(self, n, space, action)

    # --- the vector interface -------------------------------------------------------------

    def reset(self) -> np.ndarray | dict[str, np.ndarray]:
        """Resets every environment (seeds of ``seed``, options of ``set_options``, then both
        cleared) and returns the first observations."""
        n = self.num_envs
        seeds = list(self._seeds)
        options = [{**self._pending[i], **(self._options[i] or {})} for i in range(n)]
        obs = None
        # One masked reset per distinct set of options (usually one for all).
        groups: dict[str, list[int]] = {}
        for i, o in enumerate(options):
            groups.setdefault(repr(sorted(o.items())), []).append(i)
        for members in groups.values():
            mask = np.zeros(n, bool)
            mask[members] = True
            obs, info = self.venv.reset(seed=seeds, options={**options[members[0]], "reset_mask": mask})
            self._record(info, members, reset=True)
        self._pending = [{} for _ in range(n)]
        self._seeds = [None] * n
        self._options = [{} for _ in range(n)]
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        """Takes the actions of the next ``step_wait``: ``(num_envs, 4)``, one row each."""
        self._actions = np.asarray(actions, dtype=np.float32)

    def step_wait(self) -> tuple[Any, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        """Steps every environment with the actions of ``step_async``; resets those whose episode
        ended (their ``infos[i]["terminal_observation"]``). Returns obs, rewards, dones, infos."""
        if self._actions is None:
            raise RuntimeError("step_wait() without step_async(actions): call step(actions), or step_async first")
        actions, self._actions = self._actions, None
        obs, rewards, terminated, truncated, info = self.venv.step(actions)
        n = self.num_envs
        infos = [self._info(info, i) for i in range(n)]
        self._record(info, range(n), reset=False)
        dones = terminated | truncated
        for i in range(n):
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        ended = np.flatnonzero(dones)
        if len(ended):
            for i in ended:
                infos[i]["terminal_observation"] = self._row(obs, i)
            obs = self._reset_ended(ended, obs)
        return obs, rewards.astype(np.float32), dones.astype(bool), infos

    def step(self, actions: np.ndarray) -> tuple[Any, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        """``step_async(actions)`` then ``step_wait()``."""
        self.step_async(actions)
        return self.step_wait()

    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Seeds of the next ``reset()``: environment i gets ``seed + i`` (a random ``seed`` where
        None). Returns them."""
        if seed is None:
            seed = int(np.random.default_rng().integers(0, 2**32 - 1))
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed <= 2**64 - self.num_envs:
            raise ValueError(f"seed {seed!r}: an int from 0 to 2**64 - num_envs ({self.num_envs}), so that every "
                             "environment's seed + i fits in 64 bits")
        self._seeds = [int(seed) + i for i in range(self.num_envs)]
        return list(self._seeds)

    def set_options(self, options: dict[str, Any] | list[dict[str, Any]] | None = None) -> None:
        """Reset options of the next ``reset()`` (one dict for all environments, or a list of one
        per environment): ``level``, ``challenge``, ``distribution``."""
        if options is None:
            options = {}
        if isinstance(options, dict):
            options = [options] * self.num_envs
        if len(options) != self.num_envs:
            raise ValueError(f"{len(options)} option dicts for {self.num_envs} environments: give one dict, or one per "
                             "environment")
        for o in options:
            unknown = set(o or {}) - set(SETTABLE)
            if unknown:
                raise ValueError(f"unknown reset options {sorted(unknown)}; known: {', '.join(SETTABLE)}")
        self._options = copy.deepcopy([dict(o or {}) for o in options])

    def close(self) -> None:
        """Frees the environments; later steps raise RuntimeError."""
        if not self._closed:
            self.venv.close()
            self._closed = True

    # --- per-environment attributes and methods -------------------------------------------

    def _indices(self, indices: Indices) -> list[int]:
        n = self.num_envs
        if indices is None:
            return list(range(n))
        if isinstance(indices, (int, np.integer)):
            indices = [indices]
        out = [int(i) for i in indices]
        for i in out:
            if not 0 <= i < n:
                raise IndexError(f"environment index {i}: this vector has environments 0 to {n - 1}")
        return out

    def _attr(self, name: str, i: int) -> Any:
        if name in SETTABLE:
            return self._pending[i].get(name, self._current[i][name])
        v = self.venv
        fixed = {
            "task_id": lambda: v.task_id, "max_level": lambda: v.max_level, "obs_mode": lambda: v.obs_mode,
            "obs_layout": lambda: v.obs_layout, "objects": lambda: [name for name, _ in v.rule_objects],
            "observation_space": lambda: v.single_observation_space,
            "action_space": lambda: v.single_action_space, "render_mode": lambda: None,
            "metadata": lambda: {"render_modes": [], "render_fps": 25},
            "max_episode_steps": lambda: _max_steps(self._task), "spec": lambda: self._spec(),
        }
        if name not in fixed:
            raise AttributeError(f"the environments have no attribute {name!r}; get_attr knows "
                                 f"{', '.join([*fixed, *SETTABLE])}")
        return fixed[name]()

    def _spec(self):
        """The registered spec of the task (None for a task file)."""
        from . import NAMESPACE
        full = f"{NAMESPACE}/{self._task}"
        return gymnasium.spec(full) if full in gymnasium.registry else None

    def get_attr(self, attr_name: str, indices: Indices = None) -> list[Any]:
        """``attr_name`` of each environment (all, or ``indices``)."""
        return [self._attr(attr_name, i) for i in self._indices(indices)]

    def has_attr(self, attr_name: str) -> bool:
        """Whether ``get_attr(attr_name)`` has a value."""
        try:
            self._attr(attr_name, 0)
        except AttributeError:
            return False
        return True

    def set_attr(self, attr_name: str, value: Any, indices: Indices = None) -> None:
        """Sets ``level``, ``challenge`` or ``distribution`` of the environments' next episodes."""
        if attr_name not in SETTABLE:
            raise AttributeError(f"{attr_name!r} cannot be set: set_attr takes {', '.join(SETTABLE)} (each applies "
                                 "from the environment's next episode on)")
        if attr_name == "level" and (isinstance(value, bool) or not isinstance(value, (int, np.integer))
                                     or not 0 <= value <= self.venv.max_level):
            raise ValueError(f"level {value!r}: an int from 0 to {self.venv.max_level} (the task's max_level)")
        if attr_name == "challenge" and not isinstance(value, (bool, np.bool_)):
            raise ValueError(f"challenge {value!r}: a bool")
        if attr_name == "distribution" and not isinstance(value, str):
            raise ValueError(f"distribution {value!r}: the name of one of the task file's distributions")
        for i in self._indices(indices):
            self._pending[i][attr_name] = value.item() if isinstance(value, np.generic) else value

    def env_method(self, method_name: str, *method_args: Any, indices: Indices = None,
                   **method_kwargs: Any) -> list[Any]:
        """Calls ``method_name`` on each environment (all, or ``indices``): ``reset(seed=None,
        options=None)`` of that environment alone, or ``get_wrapper_attr(name)``,
        ``set_wrapper_attr(name, value)``, ``has_wrapper_attr(name)``."""
        if method_name not in METHODS:
            raise AttributeError(f"the environments have no method {method_name!r} here; env_method calls "
                                 f"{', '.join(METHODS)}")
        out = []
        for i in self._indices(indices):
            if method_name == "reset":
                out.append(self._reset_one(i, *method_args, **method_kwargs))
            elif method_name == "get_wrapper_attr":
                out.append(self._attr(*method_args, i, **method_kwargs))
            elif method_name == "has_wrapper_attr":
                out.append(self.has_attr(*method_args, **method_kwargs))
            else:
                out.append(self.set_attr(*method_args, indices=[i], **method_kwargs))
        return out

    def env_is_wrapped(self, wrapper_class: type, indices: Indices = None) -> list[bool]:
        """False for each environment: the Rust environments have no Gymnasium wrappers."""
        return [False for _ in self._indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        raise NotImplementedError("the Rust vector environment does not render: render a "
                                  "gym.make(..., render_mode='rgb_array') environment reset with the same seed")

    def render(self, mode: str | None = None) -> np.ndarray | None:
        return self.get_images()  # type: ignore[return-value]

    @property
    def unwrapped(self) -> SB3VecEnv:
        return self

    def getattr_depth_check(self, name: str, already_found: bool) -> str | None:
        """SB3's wrapper bookkeeping: this class's name where it has ``name`` and a wrapper above did too."""
        if hasattr(self, name) and already_found:
            return f"{type(self).__module__}.{type(self).__name__}"
        return None

    # --- helpers ---------------------------------------------------------------------------

    def _row(self, obs, i: int):
        """Environment i's observation (a copy): an array, or a dict of arrays."""
        if isinstance(obs, dict):
            return {k: np.array(v[i]) for k, v in obs.items()}
        return np.array(obs[i])

    @staticmethod
    def _info(info: dict[str, Any], i: int) -> dict[str, Any]:
        """Environment i's info, as the Gymnasium environment gives it."""
        out = {}
        for k, v in info.items():
            if k.startswith("_") or k == "autoreset":
                continue
            x = v[i]
            out[k] = x.item() if isinstance(x, np.generic) else x
        return out

    def _record(self, info: dict[str, Any], members, reset: bool) -> None:
        """Keeps what each environment's episode uses (get_attr), and the reset infos."""
        for i in members:
            for k in ("level", "challenge", "distribution"):
                v = info[k][i]
                self._current[i][k] = v.item() if isinstance(v, np.generic) else v
            if reset:
                self.reset_infos[i] = self._info(info, i)

    def _reset_ended(self, ended: np.ndarray, obs):
        """Resets the environments ``ended`` (their seed streams going on, their pending settings
        applied); returns ``obs`` with their rows replaced by the new episodes' first observations."""
        n = self.num_envs
        groups: dict[str, list[int]] = {}
        for i in ended:
            groups.setdefault(repr(sorted(self._pending[i].items())), []).append(int(i))
        for members in groups.values():
            mask = np.zeros(n, bool)
            mask[members] = True
            fresh, info = self.venv.reset(options={**self._pending[members[0]], "reset_mask": mask})
            self._record(info, members, reset=True)
            for i in members:
                self._pending[i] = {}
                if isinstance(obs, dict):
                    for k in obs:
                        obs[k][i] = fresh[k][i]
                else:
                    obs[i] = fresh[i]
        return obs

    def _reset_one(self, i: int, seed: int | None = None, options: dict[str, Any] | None = None):
        """``reset`` of environment i alone: its observation and info."""
        mask = np.zeros(self.num_envs, bool)
        mask[i] = True
        seeds = [None] * self.num_envs
        seeds[i] = seed
        merged = {**self._pending[i], **(options or {})}
        obs, info = self.venv.reset(seed=seeds, options={**merged, "reset_mask": mask})
        self._pending[i] = {}
        self._record(info, [i], reset=True)
        return self._row(obs, i), self.reset_infos[i]

    def __getstate__(self):
        from . import observation
        raise observation.not_copyable(self.venv)

    def __deepcopy__(self, memo):
        from . import observation
        raise observation.not_copyable(self.venv)

    def __repr__(self) -> str:
        return f"SB3VecEnv({self._task!r}, num_envs={self.num_envs}, threads={self.venv.threads}, " \
               f"obs_mode={self.venv.obs_mode!r})"


def _max_steps(task: str) -> int:
    from ._native import max_episode_steps
    return max_episode_steps(task)
