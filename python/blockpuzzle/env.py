"""The Gymnasium environment around ``blockpuzzle._native.Env``."""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from . import observation
from ._checks import whole
from ._native import Env as _NativeEnv


class BlockPuzzleEnv(gymnasium.Env):
    """A BlockPuzzle task on the Fetch robot.

    Observation: float32 vector (gripper, fingers, and per block its position, rotation, velocities
    and colour one-hot); with ``obs_mode="objects"`` a ``Dict`` of ``robot``, ``objects`` (one row
    per object slot) and ``mask`` (1 where a slot holds an object); with ``obs_mode="entities"`` a
    ``Dict`` of ``robot``, ``entities`` (the blocks' rows, then the gripper's, the table's and the
    floor's, each with a type one-hot, so that every colour the rules read is observed) and
    ``mask``. ``obs_layout`` names every component. Action: float32 in [-1, 1]^4 (gripper displacement, finger command).
    Reward: -1 per step, 0 on success, minus the steps left on failure. ``terminated`` when the
    colour rules end the episode (success: every blue object touches a green one; failure: red
    touches blue), ``truncated`` at the task's step limit or on numerical instability.

    ``reset(options=...)`` takes ``level`` (curriculum level), ``challenge`` (bool) and
    ``distribution`` (a name from the task file, listed in ``distributions``); they stay in force
    for later resets until changed. ``physics`` (a dict, parameter name to value) pins parameters
    of the task's ``[physics]`` table for this episode only; a task without one refuses it.
    ``task`` and ``task_sha256`` are checks: a recorded episode's
    options (``blockpuzzle.datasets.reset_options``) name its task, and another task is refused.
    ``info`` has ``is_success``, ``is_failure``, ``level``, ``challenge``,
    ``distribution``, ``touching`` (object index pairs touching during the step),
    ``contact_matrix`` (int8, 0 never touched, 1 touched before, 2 touching now),
    ``elapsed_steps`` and ``unstable``, and for a task with a ``[physics]`` table ``physics``
    (the episode's drawn values, parameter name to value); ``env.unwrapped.objects`` names the indices.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 25}

    def __init__(self, task: str | None = None, render_mode: str | None = None, width: int = 480,
                 height: int = 480, obs_mode: str = "flat"):
        if task is None:
            raise ValueError("no task: pass task='BlocksTouch-v0' (an id) or task='path/to/task.toml'")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r} is not supported; use one of {self.metadata['render_modes']} or None")
        width, height = whole("width", width), whole("height", height)
        self._task = str(task)
        self._env = _NativeEnv(self._task, width, height, observation.check_mode(obs_mode))
        self.obs_mode = obs_mode
        self.obs_layout = self._env.obs_layout()
        low, high = self._env.observation_bounds()
        self.observation_space = observation.space(self.obs_layout, low, high)
        self.action_space = spaces.Box(low=-1.0, high=1.0, shape=(self._env.act_dim,), dtype=np.float32)
        self.render_mode = render_mode
        self.task_id = self._env.id
        self.objects = [name for name, _ in self._env.objects()]
        self.max_level = self._env.max_level
        #: The names of the task file's distributions, what ``reset(options={"distribution": name})``
        #: takes (empty for a task with none).
        self.distributions: list[str] = list(self._env.distributions())

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = dict(options or {})
        unknown = set(options) - {"level", "challenge", "distribution", "task", "task_sha256", "physics"}
        if unknown:
            raise ValueError(f"unknown reset options {sorted(unknown)}; known: level, challenge, distribution, "
                             "task, task_sha256, physics")
        self._check_task(options)
        if seed is not None and not (0 <= int(seed) < 2**64):
            raise ValueError(f"seed {seed} is outside [0, 2**64)")
        level = options.get("level")
        if level is not None and (isinstance(level, bool) or not isinstance(level, (int, np.integer)) or level < 0):
            raise ValueError(f"options['level'] must be an int >= 0, not {level!r}")
        if "challenge" in options and not isinstance(options["challenge"], (bool, np.bool_)):
            raise ValueError(f"options['challenge'] must be a bool, not {options['challenge']!r}")
        obs, info = self._env.reset(
            None if seed is None else int(seed),
            options.get("level"),
            options.get("challenge"),
            options.get("distribution"),
            physics_option(options.get("physics")),
        )
        return observation.split(obs, self.obs_layout), info

    def _check_task(self, options: dict[str, Any]) -> None:
        """``task`` and ``task_sha256`` options (a recorded episode's, as Minari replays it) must be
        this environment's own: an episode of another task is refused, not played on this one."""
        if options.get("task") not in (None, self.task_id):
            raise ValueError(f"options['task'] is {options['task']!r}, and this environment plays {self.task_id}: "
                             "make the environment of that task to replay its episode")
        wanted = options.get("task_sha256")
        if wanted is not None:
            from ._native import task_sha256

            own = task_sha256(self._task)
            if str(wanted).removeprefix("sha256:") != own.removeprefix("sha256:"):
                raise ValueError(f"options['task_sha256'] is {wanted}, and this environment's {self.task_id} is "
                                 f"{own}: the task has changed since the episode was recorded")

    def step(self, action):
        action = np.ascontiguousarray(action, dtype=np.float32)
        if action.shape != self.action_space.shape:
            raise ValueError(
                f"invalid action of shape {action.shape}: this environment takes one action of shape "
                f"{self.action_space.shape} (for a batch of environments use blockpuzzle.make_vec)"
            )
        obs, reward, terminated, truncated, info = self._env.step(action)
        return observation.split(obs, self.obs_layout), reward, terminated, truncated, info

    def render(self):
        if self.render_mode is None:
            gymnasium.logger.warn("render() without a render_mode: pass render_mode='rgb_array' to gymnasium.make")
            return None
        return self._env.render()

    def __getstate__(self):
        raise observation.not_copyable(self)

    def __deepcopy__(self, memo):
        raise observation.not_copyable(self)

    def close(self):
        self._env.close()


def physics_option(given: Any) -> list[tuple[str, float]] | None:
    """``reset``'s ``physics`` option (parameter name to value, pinned for the episode) as the
    extension takes it; the extension checks the names and values against the task's table."""
    if given is None:
        return None
    if not isinstance(given, dict):
        raise ValueError(f"options['physics'] must be a dict of parameter name to value, not {given!r}")
    pairs = []
    for name, value in given.items():
        if not isinstance(name, str):
            raise ValueError(f"options['physics'] key {name!r} is not a parameter name (a str)")
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise ValueError(f"options['physics'][{name!r}] must be a number, not {value!r}")
        pairs.append((name, float(value)))
    return pairs
