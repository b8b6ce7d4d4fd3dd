"""The zoo in the package: every entry loads and reproduces its recorded actions, and records its
evaluations on the package's MuJoCo (test_provenance.py: a zoo policy scores what the command line,
built on the same MuJoCo, scores)."""

import json
import os
import pathlib
import shutil

import gymnasium as gym
import numpy as np
import pytest

import blockpuzzle
from blockpuzzle import zoo


def test_the_package_carries_the_zoo_and_each_entry_reproduces_its_probes():
    names = zoo.names()
    assert "BlocksTouch-v0-ddpg" in names and len(names) >= 10
    for name in names:
        policy = zoo.load(name)
        assert policy.name == name and policy.evaluations, name
        assert policy.probe_error() < 1e-5, name
    if os.environ.get("BLOCKPUZZLE_WHEEL_TEST"):  # the installed package's copy, not the checkout's
        assert not zoo.FOLDER.resolve().is_relative_to(os.environ["BLOCKPUZZLE_WHEEL_TEST"])


def test_a_multi_task_entry_names_every_training_task_and_a_single_task_entry_its_own():
    multi = zoo.load("cross-task-v2-dagger-entity")
    assert multi.training_tasks[0] == multi.task_id == "BlocksTouch-v0"
    assert len(multi.training_tasks) == 8 and "GripperTouch-v0" in multi.training_tasks
    assert "ReachAvoid-v0" not in multi.training_tasks, "a held-out task"
    single = zoo.load("BlocksTouch-v0-ddpg")
    assert single.training_tasks == [single.task_id] == ["BlocksTouch-v0"]


def test_a_stream_entry_names_its_stream_s_tasks():
    generalist = zoo.load("generalist-bc-entity")
    assert generalist.meta["format"] == "blockpuzzle-zoo/7"
    tasks = generalist.training_tasks
    assert len(tasks) == 1029 and tasks[0] == generalist.task_id == "push-200-v0"
    assert "clutter-346-v0" in tasks and not any(t.endswith("-v0") and "-20000-" in t for t in tasks)
    assert generalist.obs_mode == "entities"


def test_a_zoo_policy_acts_on_single_and_batched_observations():
    policy = zoo.load("BlocksTouch-v0-ddpg")
    env = gym.make(f"BlockPuzzle/{policy.task_id}", obs_mode=policy.obs_mode)
    obs, _ = env.reset(seed=0)
    a = policy(obs)
    assert a.shape == (4,) and np.all(np.abs(a) <= 1)
    batch = policy(np.stack([obs, obs]))
    assert batch.shape == (2, 4) and np.array_equal(batch[0], a)


def test_a_missing_name_is_filenotfounderror_naming_the_closest_entry_and_how_to_list_them(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"no zoo entry 'BlocksTouch-v0-dpg' in .*; did you mean "
                       r"'BlocksTouch-v0-ddpg'\? blockpuzzle.zoo.names\(\) \(or `blockpuzzle zoo list`\) lists its "
                       rf"{len(zoo.names())} entries$") as e:
        zoo.load("BlocksTouch-v0-dpg")
    assert isinstance(e.value, zoo.ZooEntryNotFoundError) and isinstance(e.value, KeyError)
    assert "BlocksChoose-v0-ddpg-ours" not in str(e.value), "not every name"
    with pytest.raises(FileNotFoundError, match="did you mean 'BlocksTouch-v0-ddpg'"):
        zoo.load("blockstouch-v0-ddpg")
    with pytest.raises(FileNotFoundError, match=r"no zoo entry 'NoSuch' in .*zoo_files; blockpuzzle.zoo.names"):
        zoo.load("NoSuch")
    with pytest.raises(FileNotFoundError, match="the zoo folder .*nowhere does not exist"):
        zoo.load("BlocksTouch-v0-ddpg", folder=tmp_path / "nowhere")


@pytest.mark.parametrize("native", [None, False])
def test_a_zoo_policy_pickles_by_name_and_hash_and_acts_the_same_after(native):
    import pickle

    policy = zoo.load("BlocksTouch-v0-ddpg", native=native)
    data = pickle.dumps(policy)
    assert len(data) < 1000, "by reference, not by weights"
    again = pickle.loads(data)
    assert again is not policy and again.name == policy.name and again.files_sha256 == policy.files_sha256
    assert (again.native is None) == (policy.native is None)
    env = gym.make("BlockPuzzle/BlocksTouch-v0")
    obs = np.stack([env.reset(seed=s)[0] for s in range(16)])
    assert np.array_equal(again(obs), policy(obs))
    # A set network, and a process of its own (as multiprocessing's workers are).
    import concurrent.futures
    import multiprocessing

    set_policy = zoo.load("cross-task-v2-dagger-entity")
    env = gym.make(f"BlockPuzzle/{set_policy.task_id}", obs_mode=set_policy.obs_mode)
    obs, _ = env.reset(seed=3)
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(1, mp_context=context) as pool:
        assert np.array_equal(pool.submit(set_policy, obs).result(), set_policy(obs))


def test_unpickling_an_entry_whose_files_changed_is_refused_naming_it(tmp_path):
    import pickle
    import shutil

    for suffix in (".json", ".safetensors"):
        shutil.copy((zoo.FOLDER / "BlocksTouch-v0-ddpg").with_suffix(suffix), tmp_path / f"mine{suffix}")
    policy = zoo.load(tmp_path / "mine.json")
    data = pickle.dumps(policy)
    assert np.array_equal(pickle.loads(data)(np.zeros(48, np.float32)), policy(np.zeros(48, np.float32)))
    text = (tmp_path / "mine.json").read_text()
    (tmp_path / "mine.json").write_text(text + "\n")  # still a valid entry, but not the bytes pickled
    with pytest.raises(ValueError, match=r"cannot unpickle the zoo policy 'mine': its files \(.*mine.json, "
                       r"mine.safetensors\) changed since it was pickled .*load the entry as it is now"):
        pickle.loads(data)
    (tmp_path / "mine.json").unlink()
    with pytest.raises(FileNotFoundError, match="cannot unpickle the zoo policy 'mine'"):
        pickle.loads(data)


def test_an_entry_gives_its_mode_kind_and_algorithm_from_its_fields(tmp_path):
    """Format 7 records what the policy reads and is and who trained it; readers take it from the
    fields (issue 61). An older entry (format 6) is read as before: its mode off the network, its
    kind from ``algo``, its algorithm unrecorded."""
    import json
    import shutil
    expected = {"generalist-bc-entity": ("entities", "bc"), "BlocksChoose-v0-dagger-entity": ("entities", "dagger"),
                "BlocksChoose-v0-ddpg-ours": ("flat", "td3"), "BlocksChoose-v0-pggd": ("flat", "pggd")}
    assert zoo.load("generalist-bc-entity-v2", native=False).solver == 4
    assert zoo.load("generalist-bc-entity-v3", native=False).solver == 5
    for name, (mode, algo) in expected.items():
        p = zoo.load(name, native=False)
        assert (p.version, p.obs_mode, p.algo) == (7, mode, algo), name
        # The solver version an imitation entry learned from, where recorded (issue 73).
        assert p.solver is None, name
        assert (p.meta["obs_mode"], p.meta["algo"]) == (mode, algo)
        # The colour one-hot's place, recorded by the Rust exporter from the observation's one definition.
        assert p.meta["colour_feature"] == zoo.COLOUR_FEATURE
        # The fixtures' rows after the blocks' (a set layout with statistics per row type has one for each).
        assert p.fixtures == (["gripper", "table", "floor"] if mode == "entities" else [])
        assert (p.set or {}).get("fixtures", 0) in (0, len(p.fixtures))
    assert zoo.load("BlocksChoose-v0-pggd", native=False).kind == "gaussian"
    assert zoo.load("BlocksTouch-v0-ddpg", native=False).kind == "deterministic"
    # An edited mode is refused by the numpy reader as by the extension's, naming the field.
    for ext in ("json", "safetensors"):
        shutil.copy(zoo.FOLDER / f"BlocksTouch-v0-ddpg.{ext}", tmp_path / f"x.{ext}")
    meta = json.loads((tmp_path / "x.json").read_text())
    (tmp_path / "x.json").write_text(json.dumps(dict(meta, obs_mode="objects")))
    for native in (False, True):
        with pytest.raises(ValueError, match="obs_mode records `objects`"):
            zoo.load("x", folder=tmp_path, native=native)
    # A format-5 entry (before seals): read as before.
    old = dict(meta, format="blockpuzzle-zoo/5", algo="ddpg")
    for k in ("obs_mode", "kind", "meta_sha256", "colour_feature", "fixtures"):
        old.pop(k)
    (tmp_path / "x.json").write_text(json.dumps(old))
    p = zoo.load("x", folder=tmp_path, native=False)
    assert (p.version, p.obs_mode, p.kind, p.algo, p.fixtures) == (5, "flat", "deterministic", None, [])


def _corpus(folder):
    """Zoo entries good and edited, each made from ReachAvoid-v0-ddpg by editing its files' bytes (so
    that every number stays as the core wrote it): {name: whether it is usable}."""
    base = (zoo.FOLDER / "ReachAvoid-v0-ddpg.json").read_bytes()
    tensors = (zoo.FOLDER / "ReachAvoid-v0-ddpg.safetensors").read_bytes()
    meta = json.loads(base)

    def sub(old, new):
        assert base.count(old.encode()) == 1, old
        return base.replace(old.encode(), new.encode())

    described = sub(meta["description"], "another description")
    described = described.replace(meta["meta_sha256"].encode(), zoo.seal(described).encode())
    rate = '"success_rate": 0.99,'
    cases = {
        "good": (base, tensors, True),
        "resealed-description": (described, tensors, True),  # a free-text field edited and sealed again
        "edited-description": (sub(meta["description"], "another description"), tensors, False),
        "edited-obs-mode": (sub('"obs_mode": "flat"', '"obs_mode": "objects"'), tensors, False),
        "edited-kind": (sub('"kind": "deterministic"', '"kind": "gaussian"'), tensors, False),
        "edited-algo": (sub('"algo": "ddpg"', '"algo": "pggd"'), tensors, False),
        "unknown-algo": (sub('"algo": "ddpg"', '"algo": "ppo"'), tensors, False),
        "added-solver": (sub('"algo": "ddpg",', '"algo": "ddpg",\n  "solver": 4,'), tensors, False),
        "edited-epoch": (sub('"epoch": 31,', '"epoch": 32,'), tensors, False),
        "duplicate-field": (sub('"epoch": 31,', '"epoch": 31,\n  "epoch": 31,'), tensors, False),
        "seal-removed": (sub(f',\n  "meta_sha256": "{meta["meta_sha256"]}"', ""), tensors, False),
        "tensor-byte": (base, tensors[:-1] + bytes([tensors[-1] ^ 1]), False),
        "tensors-cut": (base, tensors[:-4], False),
        # Outside the seal: the evaluation records, recomputed from their counts.
        "edited-success-rate": (sub(rate, '"success_rate": 0.5,'), tensors, False),
        "edited-outcome-count": (sub('"success": 198,', '"success": 197,'), tensors, False),
        "edited-ci95": (sub('0.9642782382838231', '0.5'), tensors, False),
        # ...and what only the core knows: its built-in tasks and the engines it runs.
        "unknown-task": (base.replace(b'"env": "ReachAvoid-v0",', b'"env": "BlocksNowhere-v0",', 1), tensors, False),
        "unknown-engine": (sub('"mujoco": "3.11.0"', '"mujoco": "9.9.9"'), tensors, False),
        # An entry relabelled as older than what it carries.
        "relabelled-format": (sub('"blockpuzzle-zoo/7"', '"blockpuzzle-zoo/5"').replace(
            f',\n  "meta_sha256": "{meta["meta_sha256"]}"'.encode(), b""), tensors, False),
    }
    for name, (meta_bytes, tensor_bytes, _) in cases.items():
        (folder / f"{name}.json").write_bytes(meta_bytes)
        (folder / f"{name}.safetensors").write_bytes(tensor_bytes)
    return {name: usable for name, (_, _, usable) in cases.items()}


def test_every_zoo_reader_accepts_and_refuses_the_same_entries(tmp_path):
    """Issue 75: one corpus through every reader: the command line's ``zoo check``, the extension's
    loader, ``zoo.load`` acting natively and with numpy, and zoo.py on its own (its own checksums)."""
    import subprocess
    import sys
    from blockpuzzle import _native
    usable = _corpus(tmp_path)

    def accepts(read):
        try:
            read()
            return True
        except ValueError:
            return False

    script = pathlib.Path(sys.executable).parent / "blockpuzzle"
    readers = {
        "zoo check": lambda n: subprocess.run([str(script), "zoo", "check", n, "--zoo", str(tmp_path)],
                                              capture_output=True).returncode == 0,
        "extension": lambda n: accepts(lambda: _native.ZooActor(str(tmp_path / f"{n}.json"))),
        "native": lambda n: accepts(lambda: zoo.load(n, folder=tmp_path, native=True)),
        "numpy": lambda n: accepts(lambda: zoo.load(n, folder=tmp_path, native=False)),
    }
    for reader, read in readers.items():
        got = {n: read(n) for n in usable}
        assert got == usable, (reader, {n: v for n, v in got.items() if v != usable[n]})
    code = ("import sys, importlib.util, json, pathlib; sys.modules['blockpuzzle'] = None; "
            f"spec = importlib.util.spec_from_file_location('z', {str(pathlib.Path(zoo.__file__))!r}); "
            "z = importlib.util.module_from_spec(spec); spec.loader.exec_module(z); out = {}\n"
            f"for n in {sorted(usable)!r}:\n"
            "    try:\n"
            f"        z.load(n, folder={str(tmp_path)!r}); out[n] = True\n"
            "    except ValueError:\n"
            "        out[n] = False\n"
            "print(json.dumps(out))")
    standalone = json.loads(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                            check=True).stdout)
    assert standalone == usable, {n: v for n, v in standalone.items() if v != usable[n]}


def test_blockpuzzle_zoo_names_the_zoo_as_for_the_command_line(tmp_path, monkeypatch):
    # Issue 74: $BLOCKPUZZLE_ZOO worked in the CLI but not in Python.
    for ext in ("json", "safetensors"):
        shutil.copy(zoo.FOLDER / f"BlocksTouch-v0-ddpg.{ext}", tmp_path / f"BlocksTouch-v0-ddpg.{ext}")
    monkeypatch.setenv("BLOCKPUZZLE_ZOO", str(tmp_path))
    assert zoo.default_folder() == tmp_path and zoo.names() == ["BlocksTouch-v0-ddpg"]
    assert zoo.load("BlocksTouch-v0-ddpg").path.parent == tmp_path
    with pytest.raises(FileNotFoundError, match="no zoo entry 'generalist-bc-entity' in"):
        zoo.load("generalist-bc-entity")
    monkeypatch.setenv("BLOCKPUZZLE_ZOO", str(tmp_path / "BlocksTouch-v0-ddpg.json"))
    with pytest.raises(FileNotFoundError, match=r"is not a folder; set \$BLOCKPUZZLE_ZOO"):
        zoo.load("generalist-bc-entity")
    monkeypatch.delenv("BLOCKPUZZLE_ZOO")
    assert zoo.default_folder() == zoo.FOLDER and "generalist-bc-entity" in zoo.names()


def test_a_policy_makes_its_own_environment_built_in_or_generated(tmp_path):
    # Trained on a generated task: its id is no registered one, and gym.make cannot take it.
    generalist = zoo.load("generalist-bc-entity")
    assert generalist.task_id not in blockpuzzle.env_ids()
    env = generalist.make_env()
    assert env.unwrapped.task_id == generalist.task_id and env.unwrapped.obs_mode == generalist.obs_mode
    assert env.spec.max_episode_steps is not None, "the task file's step limit, as make_task gives it"
    obs, _ = env.reset(seed=0)
    assert generalist(obs).shape == (4,)
    again = generalist.make_env(render_mode="rgb_array")   # the task file is written once, and kwargs pass on
    assert again.render_mode == "rgb_array"
    # Built in: gym.make of its id, in its observation mode.
    touch = zoo.load("BlocksTouch-v0-ddpg")
    env = touch.make_env()
    assert env.spec.id == "BlockPuzzle/BlocksTouch-v0" and env.unwrapped.obs_mode == "flat"
    obs, _ = env.reset(seed=0)
    assert touch(obs).shape == (4,)
    # A built-in task whose text changed since training is not passed off as the policy's.
    touch.meta = {**touch.meta, "task": {**touch.meta["task"], "hash": "sha256:" + "0" * 64}}
    with pytest.raises(ValueError, match="its text has changed"):
        touch.make_env()
