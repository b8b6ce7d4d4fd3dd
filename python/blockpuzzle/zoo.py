"""The model zoo in Python, with numpy alone: ``blockpuzzle.zoo.load(name)`` is a callable policy.

An entry is ``NAME.safetensors`` (float32 tensors) and ``NAME.json`` (metadata: task, training,
network shapes, recorded evaluations, probes); the format is zoo/README.md's. The package carries
the checkout's zoo (``names()``); ``load`` also takes the path of an entry elsewhere.

    import gymnasium as gym, blockpuzzle
    policy = blockpuzzle.zoo.load("BlocksTouch-v0-ddpg")
    env = policy.make_env()                   # its task (built in or generated), its observation mode
    obs, _ = env.reset(seed=0)
    action = policy(obs)                      # one observation, or a batch of rows
    policy.evaluations                        # what the CLI measured, on this MuJoCo

Inside the package a policy acts through the extension, with the command line's own forward pass
(``policy.native``), so that it plays exactly the episodes the CLI plays; the numpy forward pass
here (``policy.act_numpy``) is the reference for reading the format in your own code, equal to it
to about 1e-6 (float32 sums in another order), which can turn one episode in a few hundred.

Every reader checks an entry the same way: the extension's loader (the command line's ``zoo check``)
checks it whichever pass acts. This file imports nothing of blockpuzzle but that extension, and runs
on its own without it (examples/python/zoo_policy.py loads it by path): then the numpy pass acts, and
the entry is checked as the format (zoo/README.md) says, by what this file can know: its checksums,
``tensors_sha256`` and the metadata's seal ``meta_sha256`` (any edit of the metadata but its
evaluations, or of the tensors, is refused); no field of format 7 in an entry of an older format; and
each evaluation's rate and Wilson interval recomputed from its outcome counts; and each evaluation's
task and engine, against the core's facts (the built-in tasks' hashes, the engines), which it reads
from ``facts.json`` beside it, a copy the core's tests keep equal to ``_native.facts()``.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import math
import os
import pathlib
import statistics

import numpy as np


def _facts() -> dict:
    """The facts the Rust core defines (``_native.facts()``). Run on its own, without the extension,
    this file reads the same document from ``facts.json`` beside it, which the core's tests keep
    equal to its facts (tests/it/provenance.rs)."""
    try:
        from blockpuzzle import _native
        return _native.facts()
    except ImportError:
        return json.loads((pathlib.Path(__file__).resolve().parent / "facts.json").read_text())


_FACTS = _facts()
#: The formats this reader reads (the core's ``zoo::READS``).
FORMATS: tuple[str, ...] = tuple(_FACTS["zoo_formats"])
#: Where an object row's colour one-hot (red, blue, green, grey) begins in entries of formats 1-6,
#: which do not record it (format 7 records ``colour_feature``, written by the Rust exporter).
COLOUR_FEATURE: int = _FACTS["colour_feature"]
#: The zoo the package carries.
FOLDER = pathlib.Path(__file__).resolve().parent / "zoo_files"


def default_folder() -> pathlib.Path:
    """The zoo names are looked up in: ``$BLOCKPUZZLE_ZOO`` where it is set (as for the command
    line), else the package's own (``FOLDER``)."""
    given = os.environ.get("BLOCKPUZZLE_ZOO", "")
    return pathlib.Path(given) if given else FOLDER


def names(folder: str | pathlib.Path | None = None) -> list[str]:
    """The entries of a zoo folder (by default ``default_folder()``: ``$BLOCKPUZZLE_ZOO`` or the package's), sorted."""
    return sorted(p.stem for p in pathlib.Path(folder or default_folder()).glob("*.json"))


class ZooEntryNotFoundError(FileNotFoundError, KeyError):
    """No zoo entry of that name: a ``FileNotFoundError``, as every missing input of the package is
    (and a ``KeyError``, what ``load`` raised before, so that older ``except KeyError`` still works)."""

    def __str__(self) -> str:  # KeyError's would quote the message
        return str(self.args[0]) if self.args else ""


def _missing_entry(name: str, folder: str | pathlib.Path) -> ZooEntryNotFoundError:
    """The error for a name that is not in ``folder``: the closest entry, and how to list them all."""
    folder = pathlib.Path(folder)
    if not folder.is_dir():
        from_env = os.environ.get("BLOCKPUZZLE_ZOO") and folder == pathlib.Path(os.environ["BLOCKPUZZLE_ZOO"])
        where = "$BLOCKPUZZLE_ZOO" if from_env else "folder="
        what = "is not a folder" if folder.exists() else "does not exist"
        return ZooEntryNotFoundError(f"no zoo entry {name!r}: the zoo folder {folder} {what}; set {where} to a "
                                     "folder of NAME.json and NAME.safetensors entries, or leave it unset for the "
                                     "package's zoo")
    known = names(folder)
    lower = {n.lower(): n for n in known}
    close = [lower[m] for m in difflib.get_close_matches(str(name).lower(), list(lower), n=1, cutoff=0.6)]
    hint = f"did you mean {close[0]!r}? " if close else ""
    return ZooEntryNotFoundError(
        f"no zoo entry {name!r} in {folder}; {hint}blockpuzzle.zoo.names() (or `blockpuzzle zoo list`) lists its "
        f"{len(known)} entries")


def load(name: str | pathlib.Path, folder: str | pathlib.Path | None = None, native: bool | None = None) -> ZooPolicy:
    """The policy of a zoo entry: a name in ``folder`` (by default ``default_folder()``: ``$BLOCKPUZZLE_ZOO``
    where it is set, else the package's zoo) or the path of an entry's .json/.safetensors.
    ``native``: act through the extension (the CLI's arithmetic; None: where it can be imported).
    A name that is not there raises ``ZooEntryNotFoundError`` (a ``FileNotFoundError``) naming the
    closest entry."""
    path = pathlib.Path(name)
    if folder is None:
        folder = default_folder()
    if path.suffix not in (".json", ".safetensors"):
        path = pathlib.Path(folder) / f"{name}.json"
        if not path.is_file():
            raise _missing_entry(str(name), folder)
    return ZooPolicy(path, native=native)


def _unpickle(ref: tuple[str, str], files_sha256: str, native: bool) -> ZooPolicy:
    """A pickled ``ZooPolicy`` loaded again (``ZooPolicy.__reduce__``): from the unpickling
    process's package zoo (``("zoo", name)``) or from a path (``("path", json)``), refused where the
    files are not those it was pickled from."""
    kind, where = ref
    what = f"the zoo policy {pathlib.Path(where).stem!r}"
    try:
        policy = load(where, FOLDER, native=native) if kind == "zoo" else ZooPolicy(where, native=native)
    except FileNotFoundError as e:
        raise type(e)(f"cannot unpickle {what}: {e}; unpickle it where the package (or that file) has the "
                      "entry, or pickle it by loading the entry there") from None
    if policy.files_sha256 != files_sha256:
        raise ValueError(
            f"cannot unpickle {what}: its files ({policy.path}, {policy.path.with_suffix('.safetensors').name}) "
            f"changed since it was pickled (sha256 {files_sha256[7:19]}… then, {policy.files_sha256[7:19]}… now), "
            "so it would not act as the pickled policy did; load the entry as it is now and pickle that, or restore "
            "the files it was pickled from")
    return policy


def _native_actor(path: pathlib.Path, required: bool):
    """The extension's actor of the entry, or None where the extension cannot be imported."""
    try:
        from blockpuzzle import _native
    except ImportError:
        if required:
            raise
        return None
    return _native.ZooActor(str(path))


class _Number(str):
    """A JSON number as written: the seal hashes numbers as the writer wrote them."""


def _no_duplicates(pairs):
    keys = [k for k, _ in pairs]
    if len(set(keys)) != len(keys):
        raise ValueError(f"a JSON object has the field {next(k for k in keys if keys.count(k) > 1)!r} twice")
    return dict(pairs)


def _compact(v) -> str:
    """``v`` as compact JSON, the way the Rust core writes it (serde_json): no spaces, non-ASCII
    unescaped, numbers as read."""
    if isinstance(v, _Number):
        return str(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, bool) or v is None:
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ",".join(_compact(x) for x in v) + "]"
    return "{" + ",".join(json.dumps(k, ensure_ascii=False) + ":" + _compact(x) for k, x in v.items()) + "}"


def seal(meta_bytes: bytes) -> str:
    """The ``meta_sha256`` of an entry's metadata, as the core computes it (``ZooMeta::seal``): the
    sha256 of its compact JSON with ``evaluations`` empty and ``meta_sha256`` left out, fields in the
    order written."""
    meta = json.loads(meta_bytes, parse_float=_Number, parse_int=_Number, object_pairs_hook=_no_duplicates)
    meta["evaluations"] = []
    meta.pop("meta_sha256", None)
    return "sha256:" + hashlib.sha256(_compact(meta).encode()).hexdigest()


#: The fields format 7 introduced (zoo/README.md), which an entry of an older format cannot carry.
_FORMAT_7_FIELDS = ("kind", "obs_mode", "colour_feature", "fixtures", "blend", "started_from", "solver")
#: The normal quantile of a two-sided 95% Wilson interval.
_Z95 = statistics.NormalDist().inv_cdf(0.975)


def _wilson95(successes: int, n: int) -> tuple[float, float]:
    """The Wilson score interval at 95%, as the format records ``ci95``."""
    p, z2 = successes / n, _Z95 * _Z95
    denom = 1 + z2 / n
    centre = (p + z2 / (2 * n)) / denom
    half = _Z95 * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / denom
    return max(centre - half, 0.0), min(centre + half, 1.0)


def _same(stored, derived: float) -> bool:
    return isinstance(stored, (int, float)) and abs(stored - derived) <= 1e-9 * max(abs(derived), 1.0)


def _check_evaluations(meta: dict) -> None:
    """Each evaluation's counts add up: its outcomes to its episodes, its success rate and interval
    recomputed from them (format 1 kept no counts: its rate must be a whole count over its episodes)."""
    for k, e in enumerate(meta["evaluations"]):
        n = e["episodes"]
        if not isinstance(n, int) or n < 1:
            raise ValueError(f"evaluations[{k}]: episodes {n!r} is not a count of episodes")
        outcomes = e.get("outcomes")
        if outcomes is not None:
            if sum(outcomes.values()) != n:
                raise ValueError(f"evaluations[{k}]: its outcomes count {sum(outcomes.values())} episodes, and it "
                                 f"records {n}")
            successes = outcomes["success"]
        else:
            successes = round(e["success_rate"] * n)
        if not _same(e["success_rate"], successes / n):
            raise ValueError(f"evaluations[{k}]: success_rate {e['success_rate']}, but its outcomes give "
                             f"{successes / n} ({successes} of {n} episodes)")
        low, high = _wilson95(successes, n)
        if not (_same(e["ci95"][0], low) and _same(e["ci95"][1], high)):
            raise ValueError(f"evaluations[{k}]: ci95 {e['ci95']}, but {successes} of {n} episodes give "
                             f"({low}, {high})")


def _check_entry(meta: dict, meta_bytes: bytes, tensor_bytes: bytes) -> None:
    """An entry's own checks (``meta`` is ``meta_bytes`` read): its tensors are the ones
    ``tensors_sha256`` names, its metadata (evaluations aside) the one ``meta_sha256`` seals (which
    formats 6 and 7 require), an older format carries none of format 7's fields, and its evaluations'
    counts add up."""
    tensors = "sha256:" + hashlib.sha256(tensor_bytes).hexdigest()
    if meta["tensors_sha256"] != tensors:
        raise ValueError(f"its tensors are not the ones tensors_sha256 names ({meta['tensors_sha256']}; "
                         f"the .safetensors file's is {tensors})")
    version = int(meta["format"].rsplit("/", 1)[1])
    newer = [f for f in _FORMAT_7_FIELDS if f in meta]
    if version < 7 and newer:
        raise ValueError(f"it says format {meta['format']!r}, and carries {newer[0]}, which blockpuzzle-zoo/7 "
                         "introduced")
    if version >= 6 and "meta_sha256" not in meta:
        raise ValueError(f"format {version} seals its metadata, and meta_sha256 is missing")
    if "meta_sha256" in meta and meta["meta_sha256"] != (sealed := seal(meta_bytes)):
        raise ValueError(f"its metadata is not the one meta_sha256 sealed ({meta['meta_sha256']}; the "
                         f"metadata's is {sealed}): a field was edited")
    _check_evaluations(meta)
    _check_records(meta)


def _check_records(meta: dict) -> None:
    """Each evaluation names a task the core knows, with its content: the entry's own (or one of a
    multi-task run's) or a built-in one, whose hash its ``task_sha256`` must be; and an engine the
    project runs (the core's facts: ``tasks`` and ``engines``)."""
    own = {t["id"]: t["hash"] for t in [meta["task"], *((meta.get("multi_task") or {}).get("tasks") or [])]}
    for k, e in enumerate(meta["evaluations"]):
        env = e["env"]
        known = own.get(env) or _FACTS["tasks"].get(env)
        if known is None:
            raise ValueError(f"evaluations[{k}]: env {env!r} is neither a built-in task nor this entry's own "
                             f"({meta['task']['id']})")
        if e.get("task_sha256") not in (None, known):
            raise ValueError(f"evaluations[{k}]: task_sha256 {e['task_sha256']}, and task {env}'s hash is {known}")
        engine = (e.get("provenance") or {}).get("mujoco")
        if engine is not None and engine not in _FACTS["engines"]:
            raise ValueError(f"evaluations[{k}]: MuJoCo {engine!r} is no engine this project runs "
                             f"({', '.join(_FACTS['engines'])})")


#: Features of an ``entities`` row (an ``objects`` row's 22 and the type one-hot): how an entry of
#: formats 1-6, which does not record its observation, is read (format 7 records ``obs_mode``).
ENTITY_FEATURES: int = _FACTS["entity_features"]


def read_safetensors(path: str | pathlib.Path, fix: str = "restore the zoo entry") -> dict[str, np.ndarray]:
    """The float32 tensors of a safetensors file: an 8-byte header length, a JSON header, the data.
    A damaged file raises ValueError naming it, the tensor or field, and ``fix``: a header that is
    not JSON, a tensor that is not F32, ``data_offsets`` out of the data, overlapping another
    tensor's, leaving bytes no tensor covers, or not the size the shape calls for."""
    return parse_safetensors(_read_input(path), path, fix)


def _read_input(path: str | pathlib.Path) -> bytes:
    """A file's bytes; a folder is ValueError naming it (FileNotFoundError and PermissionError as open gives them)."""
    path = pathlib.Path(path)
    if path.is_dir():
        raise ValueError(f"{path} is a folder, not a file")
    return path.read_bytes()


def parse_safetensors(raw: bytes, path: str | pathlib.Path, fix: str) -> dict[str, np.ndarray]:
    """``read_safetensors`` of bytes already read from ``path`` (named in the errors)."""
    def bad(what: str) -> ValueError:
        return ValueError(f"{path} is not a usable safetensors file: {what}; {fix}")

    if len(raw) < 8:
        raise bad(f"it has {len(raw)} bytes, fewer than the 8 of the header length (cut short?)")
    n = int.from_bytes(raw[:8], "little")
    if 8 + n > len(raw):
        raise bad(f"its header claims {n} bytes, the file has {len(raw)} (cut short?)")
    try:
        header = json.loads(raw[8:8 + n])
    except (ValueError, UnicodeDecodeError) as e:
        raise bad(f"its header is not JSON ({e})") from None
    if not isinstance(header, dict):
        raise bad(f"its header is a JSON {type(header).__name__}, not an object of tensors")
    data = memoryview(raw)[8 + n:]
    spans, out = [], {}
    for key, t in header.items():
        if key == "__metadata__":
            if not isinstance(t, dict) or not all(isinstance(v, str) for v in t.values()):
                raise bad("its __metadata__ is not an object of strings")
            continue
        if not isinstance(t, dict):
            raise bad(f"tensor {key!r} is described by a JSON {type(t).__name__}, not an object")
        dtype, shape, offsets = t.get("dtype"), t.get("shape"), t.get("data_offsets")
        if dtype != "F32":
            raise bad(f"tensor {key!r} has dtype {dtype!r}; these files store F32 (float32) tensors only")
        if not isinstance(shape, list) or not all(type(d) is int and d >= 0 for d in shape):
            raise bad(f"tensor {key!r} has shape {shape!r}, not a list of sizes >= 0")
        if (not isinstance(offsets, list) or len(offsets) != 2 or not all(type(o) is int for o in offsets)
                or not 0 <= offsets[0] <= offsets[1]):
            raise bad(f"tensor {key!r} has data_offsets {offsets!r}, not [start, end] with 0 <= start <= end")
        start, end = offsets
        if end > len(data):
            raise bad(f"tensor {key!r} has data_offsets [{start}, {end}], beyond the {len(data)} bytes of data "
                      "(cut short?)")
        want = 4 * int(np.prod(shape, dtype=np.int64))
        if end - start != want:
            raise bad(f"tensor {key!r} has data_offsets [{start}, {end}] ({end - start} bytes), its F32 shape "
                      f"{shape} calls for {want}")
        if end > start:
            spans.append((start, end, key))
        out[key] = np.frombuffer(data[start:end], dtype="<f4").reshape(shape).astype(np.float32)
    # Every byte of the data belongs to exactly one tensor (the format's rule): no overlaps, no holes.
    covered = 0
    for (start, end, key), before in zip(sorted(spans), [None, *sorted(spans)]):
        if start < covered:
            raise bad(f"tensor {key!r} has data_offsets [{start}, {end}], overlapping tensor {before[2]!r}'s "
                      f"[{before[0]}, {before[1]}]")
        if start > covered:
            raise bad(f"bytes {covered}..{start} of the data belong to no tensor (before tensor {key!r})")
        covered = end
    if covered != len(data):
        raise bad(f"bytes {covered}..{len(data)} of the data (the end) belong to no tensor")
    return out


class ZooPolicy:
    """The deterministic action of a zoo entry: normalise, the network, tanh (DDPG) or clip(mu) (PGGD).

    The network is an MLP (ReLU layers) or, where the metadata gives a ``set`` layout, a set network
    over the ``objects`` or ``entities`` observation (robot | rows | mask): a per-row encoder (of the
    row, or with ``robot_tokens`` of the robot features and the row), optionally a self-attention
    block or pre-LayerNorm transformer blocks (``transformer``), masked mean and max pooling (overall, or per colour), and a head. A set
    network takes any number of object slots: the slot count is read from the observation's length.
    """

    def __init__(self, path, native: bool | None = None):
        json_path = pathlib.Path(path).with_suffix(".json")
        self.path = json_path
        # The extension's loader first, whichever pass acts: it checks the whole entry (checksums,
        # seal, layout, values, evaluation records) and names what is wrong.
        checked = _native_actor(json_path, required=bool(native))
        #: The extension's actor (the CLI's forward pass), or None: the numpy pass acts.
        self.native = None if native is False else checked
        meta_bytes = _read_input(json_path)
        tensor_path = json_path.with_suffix(".safetensors")
        tensor_bytes = _read_input(tensor_path)
        try:
            self.meta = json.loads(meta_bytes)
            if self.meta["format"] not in FORMATS:
                raise ValueError(f"unknown format {self.meta['format']!r}")
            self.layers = len(self.meta["actor"]["sizes"]) - 1
            self.set = self.meta["actor"].get("set")
            _check_entry(self.meta, meta_bytes, tensor_bytes)
        except (ValueError, KeyError, TypeError, AttributeError) as e:
            raise ValueError(f"zoo entry {json_path} is not usable: {e}; restore it") from e
        self.tensors = parse_safetensors(tensor_bytes, tensor_path, "restore the zoo entry")
        #: ``sha256:`` of the entry's two files as loaded (the .json's bytes, then the .safetensors'):
        #: what a pickled policy is checked against when it is unpickled.
        self.files_sha256 = "sha256:" + hashlib.sha256(
            len(meta_bytes).to_bytes(8, "little") + meta_bytes + tensor_bytes).hexdigest()

    def __reduce__(self):
        """Pickled by reference: the entry's name (an entry of the package's zoo, loaded from the
        unpickling process's own package) or its path (any other entry), the files' sha256 and
        whether it acts through the extension. Unpickling loads the entry again, with the same
        checks as ``load``, and refuses, naming the entry, files that changed since: the policy then
        acts exactly as the pickled one did."""
        if self.path.parent.resolve() == FOLDER.resolve():
            ref = ("zoo", self.path.stem)
        else:
            ref = ("path", str(self.path.resolve()))
        return _unpickle, (ref, self.files_sha256, self.native is not None)

    @property
    def name(self) -> str:
        return self.meta["name"]

    @property
    def task_id(self) -> str:
        """The environment id (or task name) the policy was trained on; for a policy trained on
        several tasks, the first of them (``training_tasks`` has them all)."""
        return self.meta["task"]["id"]

    def make_env(self, **kwargs):
        """A Gymnasium environment of the task the entry records (``task_id``: for a policy trained
        on several tasks, the first), reading the policy's observation mode: ``gym.make`` of the
        built-in id, or for a task that is not built in (a generated or hand-written task file) of
        the task text the entry carries, written once to ``blockpuzzle-tasks/`` in the temporary
        folder under its content hash. ``kwargs`` go to ``gym.make`` (``render_mode``, ...). A built-in
        task whose text has changed since the policy was trained is refused, naming both hashes."""
        try:
            import gymnasium as gym

            import blockpuzzle
        except ImportError as e:
            raise ImportError("make_env needs the blockpuzzle package (pip install blockpuzzle); this file "
                              "alone reads the entry with numpy") from e
        import tempfile

        task = self.meta["task"]
        kwargs.setdefault("obs_mode", self.obs_mode)
        recorded = task.get("hash")
        if task["id"] in blockpuzzle.env_ids():
            now = "sha256:" + blockpuzzle._native.task_sha256(task["id"]).removeprefix("sha256:")
            if recorded and recorded != now:
                raise ValueError(f"{self.name} was trained on {task['id']} {recorded}; this package's {task['id']} is "
                                 f"{now} (its text has changed): the policy's own task is not built in any more")
            return gym.make(f"{blockpuzzle.NAMESPACE}/{task['id']}", **kwargs)
        text = task.get("toml")
        if not text:
            raise ValueError(f"{self.name} records no task text for {task['id']!r}, which is not a built-in id: make "
                             "its environment from the task file, blockpuzzle.make_task(path)")
        digest = hashlib.sha256(text.encode()).hexdigest()
        folder = pathlib.Path(tempfile.gettempdir()) / "blockpuzzle-tasks"
        folder.mkdir(exist_ok=True)
        path = folder / f"{digest}.toml"
        if not path.is_file() or hashlib.sha256(path.read_bytes()).hexdigest() != digest:
            part = folder / f".{digest}.{os.getpid()}.tmp"
            part.write_text(text)
            os.replace(part, path)
        return blockpuzzle.make_task(path, **kwargs)

    @property
    def training_tasks(self) -> list[str]:
        """The ids of the tasks it was trained on: one, or a multi-task policy's every task
        (``train --suite S`` or ``--env A,B``; format 5's ``multi_task``), or a stream's (``train
        --families``; format 6's ``multi_task.stream``)."""
        multi = self.meta.get("multi_task")
        if not multi:
            return [self.task_id]
        if multi.get("stream"):
            return [t["id"] for t in multi["stream"]["tasks"]]
        return [t["id"] for t in multi["tasks"]]

    @property
    def version(self) -> int:
        """The entry's format version (``blockpuzzle-zoo/7`` -> 7)."""
        return int(self.meta["format"].rsplit("/", 1)[1])

    @property
    def obs_mode(self) -> str:
        """The observation mode it reads, as the entry records it (format 7); an older entry's is
        read off its network as before: "flat" for an MLP, for a set network "entities" where its
        rows have the entities' 26 features (``train --net entity``), else "objects"."""
        if self.version >= 7:
            return self.meta["obs_mode"]
        if self.set is None:
            return "flat"
        return "entities" if self.set["object"] == ENTITY_FEATURES else "objects"

    @property
    def fixtures(self) -> list[str]:
        """The rule objects other than blocks whose rows follow the blocks' in its observation, in
        row order ("gripper", "table", "floor" in the entities observation; none otherwise), as the
        entry records them; an entry written before they were recorded has its mode's."""
        if "fixtures" in self.meta:
            return list(self.meta["fixtures"])
        return ["gripper", "table", "floor"] if self.obs_mode == "entities" else []

    @property
    def algo(self) -> str | None:
        """The algorithm that trained it ("bc", "dagger", "ddpg", "td3", "sac", "pggd") where the
        entry records it (format 7, not "unrecorded"); None otherwise."""
        if self.version >= 7 and self.meta["algo"] != "unrecorded":
            return self.meta["algo"]
        return None

    @property
    def solver(self) -> int | None:
        """The version of the solver whose actions it learned from (behaviour cloning, DAgger, runs
        with demonstrations) where the entry records it; None for a policy that learned from rewards
        alone and for entries exported before it was recorded."""
        return self.meta.get("solver")

    @property
    def kind(self) -> str:
        """What acts: "deterministic" (a tanh actor) or "gaussian" (PGGD), recorded (format 7) or
        read from an older entry's ``algo`` ("ddpg" or "pggd")."""
        if self.version >= 7:
            return self.meta["kind"]
        return {"ddpg": "deterministic", "pggd": "gaussian"}[self.meta["algo"]]

    @property
    def evaluations(self) -> list[dict]:
        """The evaluations recorded on the MuJoCo this package runs (env, distribution, episodes, seed,
        success_rate, ci95, outcomes, provenance); ``all_evaluations`` has every engine's."""
        try:
            from blockpuzzle import _native
            engine = _native.mujoco_version()
        except ImportError:
            # Standalone: the engine the package pins (its metadata's mujoco requirement).
            import importlib.metadata
            try:
                requires = importlib.metadata.requires("blockpuzzle") or []
            except importlib.metadata.PackageNotFoundError:
                requires = []  # a copy of this file alone: no engine to name, so no evaluation is this engine's
            pins = [r.partition("==")[2] for r in requires if r.startswith("mujoco==")]
            engine = pins[0] if pins else None
        return [e for e in self.all_evaluations if (e.get("provenance") or {}).get("mujoco") == engine]

    @property
    def all_evaluations(self) -> list[dict]:
        """Every recorded evaluation, each with the ``provenance`` (engine) that made it where recorded."""
        return self.meta.get("evaluations", [])

    def __repr__(self) -> str:
        return f"ZooPolicy({self.name!r}, {self.algo or 'algorithm unrecorded'}, task {self.task_id}, epoch {self.meta['epoch']})"

    def __call__(self, obs) -> np.ndarray:
        """Actions for one observation (a vector or a dict of arrays) or a batch of them: the
        extension's forward pass where there is one (``native``), else ``act_numpy``."""
        if isinstance(obs, dict):
            rows = "entities" if self.obs_mode == "entities" else "objects"
            missing = [k for k in ("robot", rows, "mask") if k not in obs]
            if missing:
                raise ValueError(f"{self.name} reads the {self.obs_mode!r} observation (robot, {rows}, mask), and "
                                 f"this Dict has {sorted(obs)}, without {missing}; make the environment with "
                                 f"obs_mode={self.obs_mode!r}")
            parts = [np.asarray(obs[k], np.float32) for k in ("robot", rows, "mask")]
            batch = parts[0].ndim == 2
            n = len(parts[0]) if batch else 1
            flat = np.concatenate([p.reshape(n, -1) for p in parts], axis=1)
        else:
            flat = np.asarray(obs, np.float32)
            batch = flat.ndim == 2
            flat = flat.reshape(-1, flat.shape[-1])
        self._check_width(flat.shape[-1])
        if self.native is not None:
            actions = self.native.act(np.ascontiguousarray(flat, np.float32))
        else:
            actions = np.stack([self.act_numpy(row) for row in flat])
        return actions if batch else actions[0]

    @property
    def obs_dim(self) -> int | None:
        """The length of the flat observation it reads (None for a set network: any number of slots)."""
        return None if self.set is not None else int(self.tensors["obs_norm.mean"].shape[0])

    def _check_width(self, width: int) -> None:
        """An observation of another length is an error naming both shapes and the fix (not a numpy
        broadcast error, nor a set network silently reading a misaligned vector)."""
        fix = (f"make the environment with the policy's task and observation mode, policy.make_env() (for a "
               f"built-in task, gym.make('BlockPuzzle/{self.task_id}', obs_mode={self.obs_mode!r})), or evaluate it with "
               "blockpuzzle.evaluate(policy, suite=...), which plays each row the way the command line does")
        if self.set is None and width != self.obs_dim:
            raise ValueError(f"{self.name} reads flat observations of shape ({self.obs_dim},); these have shape "
                             f"({width},): {fix}")
        if self.set is not None:
            r, f = self.set["robot"], self.set["object"]
            if width < r or (width - r) % (f + 1):
                raise ValueError(f"{self.name} reads object-set observations of shape ({r} + k * {f + 1},) "
                                 f"(robot | {f}-feature rows | mask); these have shape ({width},): {fix}")

    def _dense(self, i, x, relu):
        y = x @ self.tensors[f"actor.{i}.weight"].T + self.tensors[f"actor.{i}.bias"]
        return np.maximum(y, 0.0) if relu else y

    def _normalise(self, x):
        t, clip = self.tensors, self.meta["norm_clip"]
        mean, std = t["obs_norm.mean"], t["obs_norm.std"]
        if self.set is not None:
            # Block rows share one mean and std per feature (slot 0's); the last `fixtures` rows (the
            # gripper's, table's and floor's, with statistics per row type) keep their own, those of
            # the saved vector's last rows; the mask passes unchanged.
            r, f, fx = self.set["robot"], self.set["object"], self.set.get("fixtures", 0)
            slots, saved = (len(x) - r) // (f + 1), (len(mean) - r) // (f + 1)

            def rows(v):
                own = [v[r + (saved - fx + i) * f:r + (saved - fx + i + 1) * f] for i in range(fx)]
                return np.concatenate([np.tile(v[r:r + f], slots - fx), *own]) if fx else np.tile(v[r:r + f], slots)

            mean = np.concatenate([mean[:r], rows(mean), np.zeros(slots, np.float32)])
            std = np.concatenate([std[:r], rows(std), np.ones(slots, np.float32)])
        return np.clip((x - mean) / std, -clip, clip)

    def _pool(self, x):
        """A set network's head input: robot features, masked mean and max of the encoded rows."""
        r, f, e = self.set["robot"], self.set["object"], self.set["encoder_layers"]
        slots = (len(x) - r) // (f + 1)
        rows = x[r:r + slots * f].reshape(slots, f)
        present = x[r + slots * f:r + slots * f + slots] > 0.5
        rows = rows[present]
        # Robot tokens: each row with the robot features before it (an actor has no extra inputs).
        h = rows
        if self.set.get("robot_tokens", False):
            h = np.concatenate([np.tile(x[:r], (len(rows), 1)), rows], axis=1)
        for i in range(e):
            h = self._dense(i, h, relu=True)
        first = e
        if self.set.get("attention", False):
            q, k, v = (self._dense(e + j, h, relu=False) for j in range(3))
            scores = q @ k.T / np.sqrt(q.shape[1], dtype=np.float32)
            w = np.exp(scores - scores.max(axis=1, keepdims=True)) if len(h) else scores
            w = w / w.sum(axis=1, keepdims=True) if len(h) else w
            h = np.maximum(h + self._dense(e + 3, w @ v, relu=False), 0.0)
            first = e + 4
        for _ in range(self.set.get("transformer", 0)):
            h = self._transformer_block(h, first)
            first += 6
        if self.set.get("transformer", 0):
            h = np.maximum(h, 0.0)
        width = self.tensors[f"actor.{e - 1}.bias"].shape[0]
        if self.set.get("query", False):
            # Attention pooling with a learned query: a softmax of the rows' scores weighs their values.
            pooled = np.zeros(self.tensors[f"actor.{first + 1}.bias"].shape[0], np.float32)
            if len(h):
                s = self._dense(first, h, relu=False)[:, 0] / np.sqrt(width, dtype=np.float32)
                w = np.exp(s - s.max())
                pooled = (w / w.sum()) @ self._dense(first + 1, h, relu=False)
            first += 2
        else:
            if self.set.get("by_colour", False):
                # One group per colour (red, blue, green, grey): the row's one-hot, passed by the normaliser.
                at = self.meta.get("colour_feature", COLOUR_FEATURE)
                groups = [rows[:, at + c] > 0.5 for c in range(4)]
            else:
                groups = [np.ones(len(h), bool)]
            means = [h[g].mean(axis=0) if g.any() else np.zeros(width, np.float32) for g in groups]
            peaks = [h[g].max(axis=0) if g.any() else np.zeros(width, np.float32) for g in groups]
            pooled = np.concatenate([*means, *peaks])
        if self.set.get("norm", False):
            # Layer normalisation without gain or bias (biased variance, libtorch's 1e-5 floor).
            pooled = (pooled - pooled.mean()) / np.sqrt(pooled.var() + np.float32(1e-5))
        return np.concatenate([x[:r], pooled.astype(np.float32)]), first

    def _transformer_block(self, h, first):
        """One pre-LayerNorm transformer block (layers ``first`` .. ``first + 5``: query, key, value,
        output, feed-forward pair) over the present rows ``h``: 4 heads of masked self-attention,
        then the feed-forward pair, each added to ``h``; layer normalisation without gain or bias."""
        def ln(v):
            return (v - v.mean(axis=1, keepdims=True)) / np.sqrt(v.var(axis=1, keepdims=True) + np.float32(1e-5))
        if not len(h):
            return h
        a = ln(h)
        q, k, v = (self._dense(first + j, a, relu=False) for j in range(3))
        d, heads = q.shape[1], 4
        dh = d // heads
        z = np.zeros_like(q)
        for j in range(heads):
            part = slice(j * dh, (j + 1) * dh)
            scores = q[:, part] @ k[:, part].T / np.sqrt(dh, dtype=np.float32)
            w = np.exp(scores - scores.max(axis=1, keepdims=True))
            z[:, part] = (w / w.sum(axis=1, keepdims=True)) @ v[:, part]
        h = h + self._dense(first + 3, z, relu=False)
        return h + self._dense(first + 5, self._dense(first + 4, ln(h), relu=True), relu=False)

    def act(self, obs) -> np.ndarray:
        """The action for one flat observation vector (as ``__call__`` computes it)."""
        return self(np.asarray(obs, np.float32))

    def act_numpy(self, obs) -> np.ndarray:
        """The action for one flat observation vector by the numpy reference pass."""
        obs = np.asarray(obs, np.float32)
        self._check_width(obs.shape[-1])
        x = self._normalise(obs)
        first = 0
        if self.set is not None:
            x, first = self._pool(x)
        for i in range(first, self.layers):
            x = self._dense(i, x, relu=i < self.layers - 1)
        if self.meta["actor"]["tanh_out"]:
            return np.tanh(x)
        return np.clip(x[: len(x) // 2], -1.0, 1.0)  # PGGD: [mu | sigma pre-activation]

    def probe_error(self) -> float:
        """The largest difference from the actions recorded at export for the probe observations."""
        return max((float(np.max(np.abs(self.act_numpy(p["obs"]) - np.asarray(p["action"], np.float32))))
                    for p in self.meta["probes"]), default=0.0)
