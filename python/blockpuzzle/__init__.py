"""BlockPuzzle: a physical-reasoning benchmark for robot learning, as Gymnasium environments.

Objects are coloured red (constraint), blue (manipulated), green (goal) or grey (neutral); an
episode fails when red touches blue and succeeds when every blue object touches a green one. The
environments put coloured blocks in front of the Fetch robot in MuJoCo; the simulation runs in
Rust (``blockpuzzle._native``).

    import gymnasium as gym
    import blockpuzzle  # registers the ids

    env = gym.make("BlockPuzzle/BlocksTouch-v0", render_mode="rgb_array")
    obs, info = env.reset(seed=0, options={"level": 3})
    env = blockpuzzle.make_task("my-task.toml")           # a task file
    envs = blockpuzzle.make_vec("BlocksTouch-v0", num_envs=8, threads=2)   # Rust threads
    blockpuzzle.evaluate(policy, suite="layout")          # any callable on an evaluation suite

The Fetch assets are read from ``$BLOCKPUZZLE_MODELS_DIR``, else from the ``models/`` folder of the
checkout the package was built from (filled by ``make setup``).
"""

from __future__ import annotations

import gymnasium

from . import policies
from ._native import env_ids, mujoco_version
from .env import BlockPuzzleEnv
from .evaluation import evaluate
from .vector import BlockPuzzleVectorEnv, make_vec

__all__ = ["BlockPuzzleEnv", "BlockPuzzleVectorEnv", "env_ids", "evaluate", "make_task", "make_vec", "mujoco_version",
           "policies", "NAMESPACE"]

#: Gymnasium namespace of the registered ids: ``BlockPuzzle/BlocksTouch-v0``.
NAMESPACE = "BlockPuzzle"


def make_task(path: str, **kwargs) -> gymnasium.Env:
    """A Gymnasium environment from a task file: ``gymnasium.make("BlockPuzzle/Task-v0", task=path)``."""
    return gymnasium.make(f"{NAMESPACE}/Task-v0", task=str(path), **kwargs)


def _register() -> None:
    # Each task file sets its own step limit and the environment truncates there itself, so no
    # TimeLimit wrapper is added. `Task-v0` takes any task file: gymnasium.make(..., task=path).
    for env_id in [*env_ids(), "Task-v0"]:
        full = f"{NAMESPACE}/{env_id}"
        if full in gymnasium.registry:
            continue
        kwargs = {} if env_id == "Task-v0" else {"task": env_id}
        gymnasium.register(
            id=full,
            entry_point="blockpuzzle.env:BlockPuzzleEnv",
            vector_entry_point="blockpuzzle.vector:BlockPuzzleVectorEnv",
            kwargs=kwargs,
        )


_register()
