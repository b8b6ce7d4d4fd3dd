"""Demonstrations as datasets: the solver's episodes on a suite split (``record_demos``, the
``blockpuzzle demos`` command's code), read with numpy alone (``load_demos``), and exported as a
Minari dataset (``to_minari``, with ``pip install "blockpuzzle[minari]"``), the format offline-RL
libraries load. The file format is in docs/datasets.md."""

from __future__ import annotations

import dataclasses
import json
import os
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

from blockpuzzle.zoo import _read_input, parse_safetensors

if TYPE_CHECKING:
    import gymnasium

FORMAT = "blockpuzzle-demos"
VERSION = 1


def record_demos(suite: str | os.PathLike[str], out: str | os.PathLike[str], split: str = "train",
                 episodes: int | None = None, threads: int | None = None) -> dict[str, int]:
    """Plays the solver (which reads only the ``entities`` observation) on every row of ``split``
    of ``suite`` (a built-in name or a suite file), ``episodes`` per row from the row's seed on
    (default: the row's own count), and writes the demos file ``out``. Returns the counts
    (episodes, steps, successes, rows). The same file whatever ``threads``."""
    from blockpuzzle import _native
    from blockpuzzle._checks import whole
    episodes = None if episodes is None else whole("episodes", episodes)
    threads = None if threads is None else whole("threads", threads)
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
    episodes: list[dict[str, Any]]
    layout: dict[str, Any]
    provenance: dict[str, Any]
    split: str

    def __len__(self) -> int:
        return len(self.episodes)

    def episode(self, i: int) -> dict[str, Any]:
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


#: The largest magnitude of an observation value a demos file may hold (the Rust reader's
#: ``MAX_OBSERVATION_VALUE``): observations are metres, metres per step and one-hot flags.
MAX_OBSERVATION_VALUE = 1e3
#: What every error about a demos file ends with.
FIX = "record it again with `blockpuzzle demos` (or blockpuzzle.record_demos)"
#: The tensors of a demos file.
TENSORS = ("robot", "entities", "mask", "actions", "rewards", "terminations", "truncations")
#: Those with a row per observation (an episode's steps + 1); the others have one per step.
OBS = ("robot", "entities", "mask")


def _bad(path: str | os.PathLike[str], what: str) -> ValueError:
    return ValueError(f"{path} is not a usable demos file: {what}; {FIX}")


def _int(v, least: int) -> bool:
    return type(v) is int and v >= least


def _outcomes() -> tuple[str, ...]:
    """The outcome names the core defines (``_native.facts()``)."""
    from blockpuzzle.evaluation import OUTCOMES
    return OUTCOMES


def _header(path, raw: bytes) -> dict:
    """The demos file's one metadata entry (version, split, provenance, layout, episodes), each
    field checked; the file's safetensors layout is checked before (``parse_safetensors``)."""
    n = int.from_bytes(raw[:8], "little")
    meta = json.loads(raw[8:8 + n]).get("__metadata__") or {}
    if FORMAT not in meta:
        other = f" (it is a {meta['format']} file)" if "format" in meta else ""
        raise _bad(path, f"its metadata has no {FORMAT!r} entry{other}")
    try:
        header = json.loads(meta[FORMAT])
    except ValueError as e:
        raise _bad(path, f"its {FORMAT!r} metadata entry is not JSON ({e})") from None
    if not isinstance(header, dict):
        raise _bad(path, f"its {FORMAT!r} metadata entry is a JSON {type(header).__name__}, not an object")
    if header.get("version") != VERSION:
        raise _bad(path, f"version {header.get('version')!r} (this package reads version {VERSION})")
    for key, kind in (("split", str), ("provenance", dict), ("layout", dict), ("episodes", list)):
        if not isinstance(header.get(key), kind):
            found = "missing" if key not in header else f"a {type(header[key]).__name__}"
            raise _bad(path, f"field {key!r} of its header is {found}, not a {kind.__name__}")
    layout = header["layout"]
    for key in ("robot", "entity"):
        names = layout.get(key)
        if not isinstance(names, list) or not names or not all(isinstance(x, str) for x in names):
            raise _bad(path, f"field layout.{key} is {names!r}, not a list of feature names")
    if not _int(layout.get("rows"), 1):
        raise _bad(path, f"field layout.rows is {layout.get('rows')!r}, not a row count >= 1")
    fields = {"task": (str, "a task id"), "task_sha256": (str, "a sha256"), "row": (0, "a suite row >= 0"),
              "seed": (0, "a seed >= 0"), "steps": (1, "a step count >= 1"), "outcome": (str, "an outcome name"),
              "episode_return": (float, "a finite number")}
    outcomes = _outcomes()
    for i, e in enumerate(header["episodes"]):
        if not isinstance(e, dict):
            raise _bad(path, f"episode {i} is a {type(e).__name__}, not an object")
        for key, (kind, what) in fields.items():
            v = e.get(key)
            if kind is str:
                ok = isinstance(v, str) and v != ""
            elif kind is float:
                ok = type(v) in (int, float) and np.isfinite(v)
            else:
                ok = _int(v, kind)
            if not ok:
                raise _bad(path, f"field episodes[{i}].{key} is {'missing' if key not in e else repr(v)}, not {what}")
        if e["outcome"] not in outcomes:
            raise _bad(path, f"field episodes[{i}].outcome is {e['outcome']!r}, not an outcome name ({', '.join(outcomes)})")
        # Recorded since levels were: absent in older files, checked where present.
        if "level" in e and not _int(e["level"], 0):
            raise _bad(path, f"field episodes[{i}].level is {e['level']!r}, not a curriculum level >= 0")
        if "distribution" in e and not (isinstance(e["distribution"], str) and e["distribution"]):
            raise _bad(path, f"field episodes[{i}].distribution is {e['distribution']!r}, not a distribution's name")
    return header


def _where(index: int, starts: np.ndarray, noun: str) -> str:
    """Episode and ``noun`` ("observation" or "step") within it of row ``index`` of tensors whose
    episodes start at ``starts``."""
    i = int(np.searchsorted(starts, index, side="right")) - 1
    return f"episode {i}, {noun} {index - int(starts[i])} (row {index})"


def _check_tensors(path, t: dict[str, np.ndarray], header: dict) -> None:
    """Every tensor there, of the shape the episodes call for, finite; masks and flags 0 or 1; each
    episode ended by its last step and by no other; each episode's rewards summing to its return."""
    layout, episodes = header["layout"], header["episodes"]
    steps = np.array([e["steps"] for e in episodes], dtype=np.int64)
    total, count = int(steps.sum()), len(episodes)
    rows, robot, entity = layout["rows"], len(layout["robot"]), len(layout["entity"])
    want = {"robot": (total + count, robot), "entities": (total + count, rows, entity), "mask": (total + count, rows),
            "actions": (total, 4), "rewards": (total,), "terminations": (total,), "truncations": (total,)}
    for k, shape in want.items():
        if k not in t:
            raise _bad(path, f"it has no tensor {k!r}")
        if t[k].shape != shape:
            raise _bad(path, f"tensor {k!r} is {t[k].shape}, its {count} episodes of {total} steps call for {shape}")
    step_starts = np.concatenate([[0], np.cumsum(steps)[:-1]]).astype(np.int64)
    obs_starts = step_starts + np.arange(count, dtype=np.int64)
    for k in TENSORS:
        a = t[k].reshape(len(t[k]), -1)
        bad_rows = np.flatnonzero(~np.isfinite(a).all(axis=1))
        if len(bad_rows):
            r = int(bad_rows[0])
            value = a[r][~np.isfinite(a[r])][0]
            where = _where(r, obs_starts, "observation") if k in OBS else _where(r, step_starts, "step")
            raise _bad(path, f"tensor {k!r} holds {value} at {where}; demos hold finite numbers only")
    for k in ("robot", "entities"):
        a = np.abs(t[k].reshape(len(t[k]), -1))
        bad_rows = np.flatnonzero((a > MAX_OBSERVATION_VALUE).any(axis=1))
        if len(bad_rows):
            r = int(bad_rows[0])
            value = t[k].reshape(len(t[k]), -1)[r][a[r] > MAX_OBSERVATION_VALUE][0]
            raise _bad(path, f"tensor {k!r} holds {float(value):g} at {_where(r, obs_starts, 'observation')}; an observation "
                             f"is finite and within ±{MAX_OBSERVATION_VALUE:g}")
    bad_rows = np.flatnonzero((np.abs(t["actions"]) > 1).any(axis=1))
    if len(bad_rows):
        r = int(bad_rows[0])
        value = t["actions"][r][np.abs(t["actions"][r]) > 1][0]
        raise _bad(path, f"tensor 'actions' holds {float(value):g} at {_where(r, step_starts, 'step')}; an action's "
                         "components are within [-1, 1]")
    for k in ("mask", "terminations", "truncations"):
        a = t[k].reshape(len(t[k]), -1)
        bad_rows = np.flatnonzero(~((a == 0) | (a == 1)).all(axis=1))
        if len(bad_rows):
            r = int(bad_rows[0])
            value = a[r][(a[r] != 0) & (a[r] != 1)][0]
            where = _where(r, obs_starts, "observation") if k in OBS else _where(r, step_starts, "step")
            raise _bad(path, f"tensor {k!r} holds {value} at {where}; its values are 0 or 1")
    ends = np.flatnonzero((t["terminations"] == 1) | (t["truncations"] == 1))
    last = step_starts + steps - 1
    if not np.array_equal(ends, last):
        extra = np.setdiff1d(ends, last)
        if len(extra):
            where = _where(int(extra[0]), step_starts, "step")
            raise _bad(path, f"tensors 'terminations'/'truncations' end an episode at {where}, before its last step")
        i = int(np.flatnonzero(~np.isin(last, ends))[0])
        raise _bad(path, f"episode {i} ({int(steps[i])} steps) is not ended at its last step by 'terminations' or "
                         "'truncations'")
    last_step = np.zeros(total, dtype=bool)
    last_step[last] = True
    r = t["rewards"]
    fits = np.where(last_step, (r <= 0) & (r == np.round(r)), r == -1)
    if not fits.all():
        k = int(np.flatnonzero(~fits)[0])
        raise _bad(path, f"tensor 'rewards' holds {r[k]:g} at {_where(k, step_starts, 'step')}; the environment gives "
                         "-1 for a step that does not end the episode, and 0 or a negative whole number for its last")
    if count:
        sums = np.add.reduceat(t["rewards"].astype(np.float64), step_starts)
        returns = np.array([e["episode_return"] for e in episodes], dtype=np.float64)
        off = np.flatnonzero(~np.isclose(sums, returns, rtol=0, atol=1e-3))
        if len(off):
            i = int(off[0])
            raise _bad(path, f"episode {i}'s rewards sum to {sums[i]:g}, its header's episode_return is {returns[i]:g}")


def load_demos(path: str | os.PathLike[str]) -> Demos:
    """Reads a demos file (numpy only). A missing file is FileNotFoundError; one that is not a
    usable demos file (not safetensors, a field missing or of the wrong kind, overlapping or
    out-of-range ``data_offsets``, a NaN or infinite value, a mask or flag other than 0 and 1, an
    episode not ended at its last step) is ValueError naming the file, the field and the fix."""
    raw = _read_input(path)
    t = parse_safetensors(raw, path, FIX)
    header = _header(path, raw)
    _check_tensors(path, t, header)
    return Demos(robot=t["robot"], entities=t["entities"], mask=t["mask"], actions=t["actions"],
                 rewards=t["rewards"], terminations=t["terminations"], truncations=t["truncations"],
                 episodes=header["episodes"], layout=header["layout"], provenance=header["provenance"],
                 split=header["split"])


def observation_space(demos: Demos) -> gymnasium.spaces.Dict:
    """The ``entities`` Dict space of the demos' padded rows (what ``gym.make(..., obs_mode="entities")``
    presents, with the split's largest row count), its keys in the documented order: robot,
    entities, mask."""
    from gymnasium import spaces
    r, e, f = len(demos.layout["robot"]), demos.layout["rows"], len(demos.layout["entity"])
    return spaces.Dict({
        "robot": spaces.Box(-np.inf, np.inf, (r,), np.float32),
        "entities": spaces.Box(-np.inf, np.inf, (e, f), np.float32),
        "mask": spaces.Box(0.0, 1.0, (e,), np.float32),
    }, sort_keys=False)


def env_spec(demos: Demos) -> gymnasium.envs.registration.EnvSpec | None:
    """The Gymnasium spec of the environment that plays the demos' episodes, what Minari's
    ``recover_environment()`` makes: ``BlockPuzzle/<id>`` with ``obs_mode="entities"`` (and the
    task's step limit) where every episode is of one built-in task whose content this package has
    (the same ``task_sha256``), else None: a multi-task file (no one environment plays its
    episodes, each episode's options name its task), or a task the package does not register (a
    task file, a generated task), or a built-in task that has changed since the recording. Each
    None but the multi-task one comes with a warning saying why."""
    import gymnasium

    from blockpuzzle import NAMESPACE, _native

    tasks = {(e["task"], e["task_sha256"]) for e in demos.episodes}
    if len(tasks) != 1:
        return None
    ((task, sha),) = tasks
    if task not in _native.env_ids():
        warnings.warn(f"to_minari: the demos' task {task!r} is not a built-in id, so the dataset gets no environment "
                      "spec (recover_environment() will fail); make its environment with "
                      "blockpuzzle.make_task(path, obs_mode='entities')", stacklevel=3)
        return None
    if _native.task_sha256(task) != sha:
        warnings.warn(f"to_minari: the demos' {task} ({sha}) is not this package's {task} "
                      f"({_native.task_sha256(task)}), so the dataset gets no environment spec; record the demos "
                      "again with this package to have one", stacklevel=3)
        return None
    spec = gymnasium.spec(f"{NAMESPACE}/{task}")
    spec = dataclasses.replace(spec, kwargs={**spec.kwargs, "obs_mode": "entities"})
    shape = gymnasium.make(spec).observation_space["entities"].shape
    if shape != demos.entities.shape[1:]:
        # Not expected: one task's demos have that task's rows.
        raise ValueError(f"the demos' entities rows {demos.entities.shape[1:]} are not {task}'s {shape}")
    return spec


def reset_options(episode: dict[str, Any]) -> dict[str, Any]:
    """The ``reset`` options that play a recorded episode again, with its seed: its task and task
    hash (which ``BlockPuzzleEnv.reset`` checks against its own), its level and, where it had one,
    its distribution. A file written before levels were recorded has none: such an episode was played
    at its task's top level (the suites' default)."""
    options = {"task": episode["task"], "task_sha256": episode["task_sha256"]}
    if episode.get("level") is not None:
        options["level"] = int(episode["level"])
    if episode.get("distribution"):
        options["distribution"] = episode["distribution"]
    return options


def to_minari(path: str | os.PathLike[str], dataset_id: str, *, author: str | None = None,
              author_email: str | None = None, code_permalink: str | None = None,
              description: str | None = None) -> Any:
    """Exports a demos file as the local Minari dataset ``dataset_id`` (in ``$MINARI_DATASETS_PATH``
    or ``~/.minari/datasets``, HDF5) and returns it (a ``minari.MinariDataset``): one Minari episode
    per recorded episode with its seed and, as its options, the ``reset`` options that play it again
    (``reset_options``: task id and hash, level, distribution), so that
    ``env.reset(seed=seed, options=options)`` on the recovered environment replays it;
    observations keep the documented key order (robot, entities, mask); the dataset's description
    says the suite, split, engine and build, its requirements the package. A file of one built-in
    task gets that task's environment spec (``env_spec``: ``dataset.recover_environment()`` makes
    it); a multi-task file gets none. ``author``, ``author_email`` and ``code_permalink`` (a link to
    the code that recorded it, at its version) go into the dataset's metadata as Minari asks of
    published datasets. Needs ``pip install "blockpuzzle[minari]"``."""
    try:
        import h5py
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
            options=reset_options(ep),
            observations=ep["observations"], actions=ep["actions"], rewards=ep["rewards"],
            terminations=ep["terminations"], truncations=ep["truncations"], infos={}))
    p = demos.provenance
    suite = p.get("suite") or {}
    made = (f"the BlockPuzzle solver's episodes on suite {suite.get('name')} (sha256 {suite.get('sha256')}), "
            f"split {demos.split}; blockpuzzle {p.get('blockpuzzle')} ({p.get('commit')}), MuJoCo {p.get('mujoco')}, "
            f"solver version {p.get('solver', 1)}; "
            "observations: the entities layout padded to the split's largest row count (mask 0)")
    # HDF5 lists a group's members by name unless the group tracks their creation order: with it,
    # an episode's observations come back robot, entities, mask, as written (the documented order).
    config = h5py.get_config()
    tracked = config.track_order
    config.track_order = True
    spec = env_spec(demos)
    try:
        return minari.create_dataset_from_buffers(
            dataset_id, buffers, env=spec, eval_env=spec,
            algorithm_name=f"blockpuzzle-solver-v{p.get('solver', 1)}", author=author,
            author_email=author_email, code_permalink=code_permalink,
            observation_space=observation_space(demos), action_space=spaces.Box(-1.0, 1.0, (4,), np.float32),
            description=description or made, data_format="hdf5",
            requirements=[f"blockpuzzle=={p.get('blockpuzzle')}"])
    finally:
        config.track_order = tracked
