"""Observation layouts: the flat vector every id has by default, the object-centric ``Dict``
(``robot``, ``objects`` of max objects x features, ``mask``) chosen with ``obs_mode="objects"``, and
the entity ``Dict`` (``robot``, ``entities``: the blocks' rows then the gripper's, the table's and
the floor's, each with a type one-hot, ``mask``) chosen with ``obs_mode="entities"``.

The Rust core describes the layout (``_native.Env.obs_layout()``); in the set modes the native
vector is laid out robot | rows | mask, and ``split`` views it as the ``Dict``.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from . import _native

#: The observation modes the core has (``ObsMode::ALL``).
OBS_MODES = tuple(_native.obs_modes())


def check_mode(obs_mode: str) -> str:
    if obs_mode not in OBS_MODES:
        raise ValueError(f"unknown obs_mode {obs_mode!r}; use one of {', '.join(OBS_MODES)}")
    return obs_mode


#: The modes this module lays out: each is handled by ``space`` and ``split`` (a mode the extension
#: knows and this module does not is an error there, and in ``tests/test_observation.py``).
LAID_OUT = ("flat", "objects", "entities")


def _known(layout: dict) -> str:
    if layout["mode"] not in LAID_OUT:
        raise NotImplementedError(f"observation mode {layout['mode']!r} has no Python layout yet "
                                  f"(blockpuzzle.observation lays out {', '.join(LAID_OUT)})")
    return layout["mode"]


def space(layout: dict, low: np.ndarray, high: np.ndarray) -> spaces.Space:
    """The single environment's observation space for ``layout``."""
    mode = _known(layout)
    if mode == "flat":
        return spaces.Box(low=low, high=high, dtype=np.float32)
    r, f, m, key = layout["robot_dim"], layout["object_dim"], layout["rows"], layout["rows_key"]
    # sort_keys=False keeps this order (by default a Dict sorts its keys: mask | objects | robot), and
    # batch_space keeps the setting, so gymnasium's FlattenObservation gives the documented
    # robot | rows | mask vector for one environment and for a batch.
    return spaces.Dict({
        "robot": spaces.Box(-np.inf, np.inf, (r,), np.float32),
        key: spaces.Box(-np.inf, np.inf, (m, f), np.float32),
        "mask": spaces.Box(0.0, 1.0, (m,), np.float32),
    }, sort_keys=False)


def split(obs: np.ndarray, layout: dict):
    """``obs`` (one observation or a batch: the last axis is the native vector) in ``layout``'s
    form: itself for ``flat``, else a dict of views of it."""
    if _known(layout) == "flat":
        return obs
    r, f, m, key = layout["robot_dim"], layout["object_dim"], layout["rows"], layout["rows_key"]
    lead = obs.shape[:-1]
    return {
        "robot": obs[..., :r],
        key: obs[..., r:r + m * f].reshape(*lead, m, f),
        "mask": obs[..., r + m * f:],
    }


def not_copyable(env) -> TypeError:
    """The error pickling or deep-copying an environment raises: it holds a MuJoCo simulation (and
    threads, for the vector one), which is remade rather than copied."""
    spec = getattr(env, "spec", None)
    how = (f"gymnasium.make({spec.id!r}, **{spec.kwargs!r})" if spec is not None
           else "blockpuzzle.make_task(path) or gymnasium.make(id)")
    return TypeError(f"a {type(env).__name__} cannot be pickled or copied: it holds a MuJoCo simulation. Make "
                     f"another with {how} and reset it with the same seed, which reproduces the episode exactly")
