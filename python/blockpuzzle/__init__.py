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
    policy = blockpuzzle.zoo.load("BlocksTouch-v0-ddpg")  # a trained policy, numpy alone

The engine is the ``mujoco`` package (exactly ``MUJOCO_PIN``): the extension links its library.
The Fetch robot's files are read from the installed ``gymnasium-robotics`` (``envs/assets``,
checked against their sha256 at import), or from ``$BLOCKPUZZLE_MODELS_DIR`` where it is set (a
folder with ``scene.xml`` and ``gymnasium_robotics/``, like a checkout's ``models/``).
"""

from __future__ import annotations

import importlib.metadata as _metadata
import importlib.util as _util
import os as _os
import pathlib as _pathlib
from typing import Any as _Any

def _pinned(requirement: str) -> str:
    """The exact version the installed package requires of ``requirement`` (``mujoco==3.11.0``):
    pyproject.toml's pins, read from the package's own metadata, so that they are written once."""
    try:
        requires = _metadata.requires("blockpuzzle") or []
    except _metadata.PackageNotFoundError:
        raise ImportError("blockpuzzle's package metadata is missing (it pins the engine and the Fetch files): "
                          "install the package (pip install blockpuzzle, or maturin develop in python/)") from None
    for line in requires:
        name, _, version = line.partition("==")
        if name.strip() == requirement and version:
            return version.split(";")[0].strip()
    raise ImportError(f"blockpuzzle's metadata pins no {requirement} version: reinstall the package")


#: The MuJoCo the extension is built against and links (``libmujoco.so.3.11.0``; pyproject.toml's pin).
MUJOCO_PIN = _pinned("mujoco")
#: The gymnasium-robotics whose Fetch files the scenes read (pyproject.toml's pin).
GYMNASIUM_ROBOTICS_PIN = _pinned("gymnasium-robotics")


def _check_engine() -> None:
    """A missing or other ``mujoco`` would fail as an unreadable library: say what to install."""
    try:
        found = _metadata.version("mujoco")
    except _metadata.PackageNotFoundError:
        raise ImportError(f"blockpuzzle runs on MuJoCo {MUJOCO_PIN}, and the mujoco package is not installed: "
                          f"pip install mujoco=={MUJOCO_PIN}") from None
    if found != MUJOCO_PIN:
        raise ImportError(f"blockpuzzle was built against mujoco=={MUJOCO_PIN} but mujoco {found} is installed: "
                          f"pip install mujoco=={MUJOCO_PIN}")


def _fetch_assets() -> _pathlib.Path | None:
    """The installed gymnasium-robotics' assets folder (none needed under $BLOCKPUZZLE_MODELS_DIR)."""
    spec = _util.find_spec("gymnasium_robotics")
    if spec is None or not spec.submodule_search_locations:
        if _os.environ.get("BLOCKPUZZLE_MODELS_DIR"):
            return None
        raise ImportError("blockpuzzle reads the Fetch robot's files from gymnasium-robotics, which is not installed: "
                          f"pip install gymnasium-robotics=={GYMNASIUM_ROBOTICS_PIN}")
    return _pathlib.Path(spec.submodule_search_locations[0]) / "envs" / "assets"


_check_engine()

import gymnasium  # noqa: E402

from . import _native  # noqa: E402

_assets = _fetch_assets()
if _assets is not None:
    try:
        _native._use_fetch_assets(str(_assets))
    except (FileNotFoundError, ValueError) as e:
        if not _os.environ.get("BLOCKPUZZLE_MODELS_DIR"):
            raise ImportError(str(e)) from None

#: The package version (the Rust crate's; results record it in their ``provenance``).
__version__ = _native.build_info()["blockpuzzle"]

from . import datasets, policies, zoo  # noqa: E402
from ._native import mujoco_version  # noqa: E402
from .env import BlockPuzzleEnv  # noqa: E402
from .datasets import load_demos, record_demos, to_minari  # noqa: E402
from .evaluation import evaluate  # noqa: E402
from .vector import BlockPuzzleVectorEnv, make_vec  # noqa: E402


def assets_dir() -> _pathlib.Path:
    """The folder scenes load from: the installed gymnasium-robotics' ``envs/assets``, or
    ``$BLOCKPUZZLE_MODELS_DIR``."""
    return _pathlib.Path(_native.assets_dir())


__all__ = ["__version__", "BlockPuzzleEnv", "BlockPuzzleVectorEnv", "GYMNASIUM_ROBOTICS_PIN", "MUJOCO_PIN", "NAMESPACE",
           "assets_dir", "datasets", "env_ids", "evaluate", "generate_tasks", "load_demos", "make_task", "make_vec",
           "mujoco_version", "policies", "record_demos", "to_minari", "zoo"]

#: Gymnasium namespace of the registered ids: ``BlockPuzzle/BlocksTouch-v0``.
NAMESPACE = "BlockPuzzle"


def env_ids() -> list[str]:
    """The built-in environment ids ("BlocksTouch-v0", …), each registered as ``BlockPuzzle/<id>``."""
    return list(_native.env_ids())


def generate_tasks(family: str | _os.PathLike[str], out: str | _os.PathLike[str], seed: int = 0, count: int = 10,
                   threads: int | None = None) -> dict[str, _Any]:
    """Task files drawn from a task family (a shipped one by name, "push", "gripper", "stack",
    "gather", "topple", "avoid", "clutter" or "choose", or a family file), one per generator seed from ``seed`` on, each kept where the solver can play it:
    ``blockpuzzle task generate``'s code.
    Writes ``out/ID.toml`` per task and ``out/generated.json``, and returns that record (the family's
    hash, the generator's version, each task's id, hash, the solver's success and its layouts' draw
    and rejection rates, the rejections by reason). Deterministic
    in the seeds, whatever ``threads``."""
    import json
    return json.loads(_native.generate_tasks(_os.fspath(family), _os.fspath(out), seed, count, threads))


def make_task(path: str | _os.PathLike[str], **kwargs: _Any) -> gymnasium.Env:
    """A Gymnasium environment from a task file: ``gymnasium.make("BlockPuzzle/Task-v0", task=path)``,
    with the task file's step limit as its spec's ``max_episode_steps`` (as the built-in ids have
    theirs); ``max_episode_steps=`` given here wins, as in ``gymnasium.make``."""
    path = _os.fspath(path)
    if kwargs.get("max_episode_steps") is None:
        kwargs["max_episode_steps"] = _native.max_episode_steps(path)
    return gymnasium.make(f"{NAMESPACE}/Task-v0", task=path, **kwargs)


def _register() -> None:
    # Each task file sets its own step limit and the environment truncates there itself; the
    # registry records it too (spec.max_episode_steps, which TimeLimit, RecordEpisodeStatistics
    # and SB3's Monitor read; the TimeLimit gymnasium.make adds truncates at the same step).
    # `Task-v0` takes any task file, gymnasium.make(..., task=path), so its spec has no limit: pass
    # max_episode_steps= to gymnasium.make where a wrapper needs one.
    for env_id in [*env_ids(), "Task-v0"]:
        full = f"{NAMESPACE}/{env_id}"
        if full in gymnasium.registry:
            continue
        kwargs = {} if env_id == "Task-v0" else {"task": env_id}
        gymnasium.register(
            id=full,
            entry_point="blockpuzzle.env:BlockPuzzleEnv",
            vector_entry_point="blockpuzzle.vector:BlockPuzzleVectorEnv",
            max_episode_steps=None if env_id == "Task-v0" else _native.max_episode_steps(env_id),
            kwargs=kwargs,
        )


_register()
