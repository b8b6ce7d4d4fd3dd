"""Demonstrations as datasets: the solver's episodes on a suite split (``record_demos``, the
``blockpuzzle demos`` command's code), read with numpy alone (``load_demos``), and exported as a
Minari dataset (``to_minari``, with ``pip install "blockpuzzle[minari]"``), the format offline-RL
libraries load. The file format is in docs/datasets.md."""

from __future__ import annotations

import dataclasses
import json

import numpy as np

from blockpuzzle.zoo import read_safetensors

FORMAT = "blockpuzzle-demos"
VERSION = 1


def record_demos(suite: str, out, split: str = "train", episodes: int | None = None,
                 threads: int | None = None) -> dict:
    """Plays the solver (which reads only the ``entities`` observation) on every row of ``split``
    of ``suite`` (a built-in name or a suite file), ``episodes`` per row from the row's seed on
    (default: the row's own count), and writes the demos file ``out``. Returns the counts
    (episodes, steps, successes, rows). The same file whatever ``threads``."""
    from blockpuzzle import _native
    return json.loads(_native.record_demos(str(suite), str(out), split, episodes, threads))


@dataclasses.dataclass
class Demos:
    """A demos file in memory: observation tensors (``robot`` [O, R], ``entities`` [O, E, F], ``mask``
    [O, E]), step tensors (``actions`` [T, 4], ``rewards``, ``terminations``, ``truncations`` [T]),
    and per episode its task, task hash, row, seed, steps, return and outcome."""

    robot: np.ndarray
    entities: np.ndarray
    mask: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    terminations: np.ndarray
    truncations: np.ndarray
    episodes: list
    layout: dict
    provenance: dict
    split: str

    def __len__(self) -> int:
        return len(self.episodes)

    def episode(self, i: int) -> dict:
        """Episode ``i``: its ``observations`` (a Dict of ``steps + 1`` rows: the reset's, then each
        step's), ``actions``, ``rewards``, ``terminations``, ``truncations`` and its facts."""
        steps = [e["steps"] for e in self.episodes]
        t0 = sum(steps[:i])
        o0 = t0 + i
        n = steps[i]
        return {
            "observations": {"robot": self.robot[o0:o0 + n + 1], "entities": self.entities[o0:o0 + n + 1],
                             "mask": self.mask[o0:o0 + n + 1]},
            "actions": self.actions[t0:t0 + n],
            "rewards": self.rewards[t0:t0 + n],
            "terminations": self.terminations[t0:t0 + n].astype(bool),
            "truncations": self.truncations[t0:t0 + n].astype(bool),
            **self.episodes[i],
        }


def _header(path) -> dict:
    """The demos file's one metadata entry (version, split, provenance, layout, episodes)."""
    # The header alone (the tensors, perhaps gigabytes, are read once, by read_safetensors).
    fix = "record one with `blockpuzzle demos`"
    with open(path, "rb") as f:
        size = f.seek(0, 2)
        f.seek(0)
        n = int.from_bytes(f.read(8), "little")
        if size < 8 or 8 + n > size:
            raise ValueError(f"{path} is not a usable demos file: cut short; {fix}")
        meta = json.loads(f.read(n)).get("__metadata__") or {}
    if FORMAT not in meta:
        other = f" (it is a {meta['format']} file)" if "format" in meta else ""
        raise ValueError(f"{path} is not a usable demos file: its metadata has no {FORMAT!r} entry{other}; {fix}")
    header = json.loads(meta[FORMAT])
    if header.get("version") != VERSION:
        raise ValueError(f"{path} is not a usable demos file: version {header.get('version')} (this package reads "
                         f"version {VERSION}); {fix}")
    return header


def load_demos(path) -> Demos:
    """Reads a demos file (numpy only). A file that is not one raises ValueError naming what is wrong."""
    header = _header(path)
    t = read_safetensors(path, fix="record it again with `blockpuzzle demos`")
    layout, episodes = header["layout"], header["episodes"]
    steps = sum(e["steps"] for e in episodes)
    want = {"robot": (steps + len(episodes), len(layout["robot"])), "actions": (steps, 4), "rewards": (steps,),
            "entities": (steps + len(episodes), layout["rows"], len(layout["entity"]))}
    for k, shape in want.items():
        if t[k].shape != shape:
            raise ValueError(f"{path} is not a usable demos file: tensor {k} is {t[k].shape}, its episodes call for {shape}")
    return Demos(robot=t["robot"], entities=t["entities"], mask=t["mask"], actions=t["actions"],
                 rewards=t["rewards"], terminations=t["terminations"], truncations=t["truncations"],
                 episodes=episodes, layout=layout, provenance=header["provenance"], split=header["split"])


def observation_space(demos: Demos):
    """The ``entities`` Dict space of the demos' padded rows (what ``gym.make(..., obs_mode="entities")``
    presents, with the split's largest row count)."""
    from gymnasium import spaces
    r, e, f = len(demos.layout["robot"]), demos.layout["rows"], len(demos.layout["entity"])
    return spaces.Dict({
        "robot": spaces.Box(-np.inf, np.inf, (r,), np.float32),
        "entities": spaces.Box(-np.inf, np.inf, (e, f), np.float32),
        "mask": spaces.Box(0.0, 1.0, (e,), np.float32),
    })


def to_minari(path, dataset_id: str, *, author: str | None = None, author_email: str | None = None,
              code_permalink: str | None = None, description: str | None = None):
    """Exports a demos file as the local Minari dataset ``dataset_id`` (in ``$MINARI_DATASETS_PATH``
    or ``~/.minari/datasets``, HDF5): one Minari episode per recorded episode with its seed, and as
    its options the task id, task hash, row and outcome; the dataset's description says the suite,
    split, engine and build, its requirements the package. ``author``, ``author_email`` and
    ``code_permalink`` (a link to the code that recorded it, at its version) go into the dataset's
    metadata as Minari asks of published datasets. Needs ``pip install "blockpuzzle[minari]"``."""
    try:
        import minari
    except ImportError as e:
        raise ImportError('to_minari needs Minari: pip install "blockpuzzle[minari]"') from e
    from gymnasium import spaces
    from minari.data_collector import EpisodeBuffer

    demos = load_demos(path)
    buffers = []
    for i in range(len(demos)):
        ep = demos.episode(i)
        buffers.append(EpisodeBuffer(
            id=i, seed=int(ep["seed"]),
            options={"task": ep["task"], "task_sha256": ep["task_sha256"], "row": ep["row"], "outcome": ep["outcome"]},
            observations=ep["observations"], actions=ep["actions"], rewards=ep["rewards"],
            terminations=ep["terminations"], truncations=ep["truncations"], infos={}))
    p = demos.provenance
    suite = p.get("suite") or {}
    made = (f"the BlockPuzzle solver's episodes on suite {suite.get('name')} (sha256 {suite.get('sha256')}), "
            f"split {demos.split}; blockpuzzle {p.get('blockpuzzle')} ({p.get('commit')}), MuJoCo {p.get('mujoco')}; "
            "observations: the entities layout padded to the split's largest row count (mask 0)")
    return minari.create_dataset_from_buffers(
        dataset_id, buffers, env=None, algorithm_name="blockpuzzle-solver", author=author,
        author_email=author_email, code_permalink=code_permalink,
        observation_space=observation_space(demos), action_space=spaces.Box(-1.0, 1.0, (4,), np.float32),
        description=description or made, data_format="hdf5",
        requirements=[f"blockpuzzle=={p.get('blockpuzzle')}"])
