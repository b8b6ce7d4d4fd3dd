"""Policies that need no training: the solver, and a reference for checking an evaluation harness.

``solver()`` is the solver of ``blockpuzzle eval --baseline scripted``, the teacher of the
generalist, as a callable on ``entities`` observations. It keeps no state: each action is a
function of the one observation it is given, so it labels any state, in any order, as it would act
there (an expert for DAgger).

``obs_hash`` gives pseudo-random actions that are a function of the observation alone, with the
same integer arithmetic as the Rust ``ObsHashPolicy`` (``blockpuzzle eval --suite S --baseline
obs-hash``): FNV-1a over each value's float32 bit pattern, then murmur3's finaliser once per
action component, 24 bits mapped to [-1, 1). Being stateless it gives bit-identical actions one
observation at a time or in a batch, so a Python evaluation and the CLI's play the same episodes.
"""

from __future__ import annotations

import numpy as np

from . import _native

_FNV_OFFSET = np.uint32(0x811C9DC5)
_FNV_PRIME = np.uint32(0x01000193)


def _flat(obs) -> np.ndarray:
    """The native vector(s) of ``obs``: itself, or a ``Dict`` observation (``objects`` or
    ``entities``) joined as robot | rows | mask, the layout of the mode's flat vector."""
    if isinstance(obs, dict):
        rows = next((k for k in ("objects", "entities") if k in obs), None)
        if rows is None or "robot" not in obs or "mask" not in obs:
            raise ValueError(f"a Dict observation holds 'robot', 'objects' or 'entities', and 'mask'; this one holds "
                             f"{sorted(obs)}")
        robot = np.asarray(obs["robot"], np.float32)
        lead = robot.shape[:-1]
        parts = [robot, np.asarray(obs[rows], np.float32).reshape(*lead, -1), np.asarray(obs["mask"], np.float32)]
        return np.concatenate(parts, axis=-1)
    return np.asarray(obs, np.float32)


def obs_hash(obs) -> np.ndarray:
    """Actions (``(..., 4)`` float32 in [-1, 1)) for one observation or a batch (flat or ``Dict``)."""
    x = np.ascontiguousarray(_flat(obs))
    bits = x.view(np.uint32)
    with np.errstate(over="ignore"):
        h = np.full(bits.shape[:-1], _FNV_OFFSET, np.uint32)
        for j in range(bits.shape[-1]):
            h = (h ^ bits[..., j]) * _FNV_PRIME
        out = []
        for k in range(4):
            v = h ^ np.uint32(((k + 1) * 0x9E3779B9) & 0xFFFFFFFF)
            v ^= v >> np.uint32(16)
            v *= np.uint32(0x85EBCA6B)
            v ^= v >> np.uint32(13)
            v *= np.uint32(0xC2B2AE35)
            v ^= v >> np.uint32(16)
            a = (v >> np.uint32(8)).astype(np.float32) * np.float32(1.0 / 16777216.0) * np.float32(2.0) - np.float32(1.0)
            out.append(a)
    return np.stack(out, axis=-1).astype(np.float32)


class Solver:
    """The solver (``blockpuzzle eval --baseline scripted``) as a callable on ``entities``
    observations: one (a ``Dict`` of ``robot``, ``entities``, ``mask``, or its flat vector) gives a
    ``(4,)`` action, a batch gives ``(n, 4)``. Stateless: the same observation gives the same
    action, bit for bit, whatever it saw before, so it can label the states of anyone's rollouts.
    ``version`` is the solver version that results and demonstrations record.
    """

    obs_mode = "entities"
    __name__ = "solver"

    @property
    def version(self) -> int:
        return _native.solver_version()

    def __call__(self, obs) -> np.ndarray:
        if isinstance(obs, dict):
            if "entities" not in obs:
                raise ValueError("the solver reads the entities observation (make the environment with "
                                 "obs_mode=\"entities\"); this Dict has no 'entities'")
        x = _flat(obs)
        if x.ndim == 1:
            return _native.solver_act(np.ascontiguousarray(x[None, :]))[0]
        if x.ndim != 2:
            raise ValueError(f"the solver takes one observation or a batch, not an array of shape {x.shape}")
        return _native.solver_act(np.ascontiguousarray(x))


def solver() -> Solver:
    """The solver as a callable policy on ``entities`` observations (see ``Solver``)."""
    return Solver()
