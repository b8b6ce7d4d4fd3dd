"""Demonstrations from Python: the solver's episodes recorded as the CLI records them, read with
numpy, and exported as a Minari dataset that Minari loads back equal to the recording."""

import importlib.util
import json

import gymnasium as gym
import numpy as np
import pytest

import blockpuzzle

SUITE = """
version = 1
name = "demo-test"
summary = "two tasks of different sizes"
[[splits.train]]
task = "BlocksTouch-v0"
seed = 7
episodes = 2
[[splits.train]]
task = "BlocksAvoid-v0"
seed = 11
episodes = 2
[[splits.test]]
task = "BlocksTouch-v0"
seed = 1000
episodes = 1
"""


def test_demos_record_load_and_match_the_cli(tmp_path):
    suite = tmp_path / "s.toml"
    suite.write_text(SUITE)
    counts = blockpuzzle.record_demos(suite, tmp_path / "a.safetensors", threads=1)
    assert counts["episodes"] == 4 and counts["rows"] == 8, counts
    blockpuzzle.record_demos(suite, tmp_path / "b.safetensors", threads=2)
    assert (tmp_path / "a.safetensors").read_bytes() == (tmp_path / "b.safetensors").read_bytes()
    d = blockpuzzle.load_demos(tmp_path / "a.safetensors")
    assert len(d) == 4 and d.provenance["harness"] == "python" and d.provenance["suite"]["name"] == "demo-test"
    assert [(e["row"], e["seed"]) for e in d.episodes] == [(0, 7), (0, 8), (1, 11), (1, 12)]
    ep = d.episode(3)
    assert ep["observations"]["entities"].shape == (ep["steps"] + 1, 8, 26)
    assert ep["terminations"][-1] or ep["truncations"][-1]
    assert ep["task"] == "BlocksAvoid-v0" and ep["task_sha256"].startswith("sha256:")
    # The package's command line records the same episodes on the same engine.
    from blockpuzzle.__main__ import main
    assert main(["demos", "--suite", str(suite), "--threads", "1", "--out", str(tmp_path / "cli.safetensors")]) == 0
    c = blockpuzzle.load_demos(tmp_path / "cli.safetensors")
    assert c.episodes == d.episodes and np.array_equal(c.entities, d.entities) and np.array_equal(c.actions, d.actions)
    # Not a demos file, and a missing split: named.
    zoo = next(blockpuzzle.zoo.FOLDER.glob("*.safetensors"))
    with pytest.raises(ValueError, match=r"no .blockpuzzle-demos. entry .it is a blockpuzzle-zoo/\d file"):
        blockpuzzle.load_demos(zoo)
    with pytest.raises(ValueError, match='no split "valid"'):
        blockpuzzle.record_demos(suite, tmp_path / "c.safetensors", split="valid")


def test_demos_export_to_minari_and_load_back(tmp_path, monkeypatch):
    minari = pytest.importorskip("minari")
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    suite = tmp_path / "s.toml"
    suite.write_text(SUITE)
    blockpuzzle.record_demos(suite, tmp_path / "d.safetensors", split="train", episodes=1, threads=2)
    d = blockpuzzle.load_demos(tmp_path / "d.safetensors")
    link = "https://example.org/blockpuzzle/tree/v0.1.0"
    blockpuzzle.to_minari(tmp_path / "d.safetensors", "blockpuzzle/demo-test/solver-v0", author="A. Tester",
                          author_email="a@example.org", code_permalink=link)
    ds = minari.load_dataset("blockpuzzle/demo-test/solver-v0")
    m = ds.storage.metadata
    assert (m["author"], m["author_email"], m["code_permalink"]) == ({"A. Tester"}, {"a@example.org"}, link), m
    assert ds.total_episodes == len(d) == 2 and ds.total_steps == len(d.rewards)
    assert "demo-test" in ds.storage.metadata["description"] and "MuJoCo" in ds.storage.metadata["description"]
    for i, got in enumerate(ds.iterate_episodes()):
        want = d.episode(i)
        for k in ("robot", "entities", "mask"):
            assert np.array_equal(got.observations[k], want["observations"][k]), k
        assert np.array_equal(got.actions, want["actions"]) and np.array_equal(got.rewards, want["rewards"])
        assert np.array_equal(got.terminations, want["terminations"])
        assert np.array_equal(got.truncations, want["truncations"])
    meta = list(ds.storage.get_episode_metadata([0, 1]))
    assert [m["seed"] for m in meta] == [7, 11]
    assert meta[1]["options"]["task_sha256"] == d.episodes[1]["task_sha256"]
    # The options are reset's own (issue 74: they held row and outcome, which reset refuses).
    assert set(meta[1]["options"]) == {"task", "task_sha256", "level"}, meta[1]["options"]
    assert int(meta[1]["options"]["level"]) == d.episodes[1]["level"] == gym.make(
        f"BlockPuzzle/{d.episodes[1]['task']}").get_wrapper_attr("max_level")


def record(tmp_path, split="train", name="d.safetensors"):
    suite = tmp_path / "s.toml"
    suite.write_text(SUITE)
    blockpuzzle.record_demos(suite, tmp_path / name, split=split, episodes=1, threads=1)
    return tmp_path / name


def parts(path):
    """A safetensors file as (header dict, the demos entry dict, data bytearray)."""
    raw = path.read_bytes()
    n = int.from_bytes(raw[:8], "little")
    header = json.loads(raw[8:8 + n])
    return header, json.loads(header["__metadata__"]["blockpuzzle-demos"]), bytearray(raw[8 + n:])


def write(path, header, demos=None, data=b"", raw_header=None):
    if demos is not None:
        header["__metadata__"]["blockpuzzle-demos"] = json.dumps(demos)
    text = raw_header if raw_header is not None else json.dumps(header).encode()
    path.write_bytes(len(text).to_bytes(8, "little") + text + bytes(data))
    return path


def set_value(header, data, tensor, index, value):
    start = header[tensor]["data_offsets"][0]
    np.frombuffer(data, dtype="<f4", count=1, offset=start + 4 * index)  # in range
    data[start + 4 * index:start + 4 * index + 4] = np.float32(value).tobytes()


def test_a_bad_demos_file_is_a_valueerror_naming_the_file_the_field_and_the_fix(tmp_path):
    """Every case is also read by the core's reader (what ``train --demos`` reads): the two readers
    accept and refuse the same files (issue 75)."""
    from blockpuzzle import _native
    good = record(tmp_path)
    assert json.loads(_native.read_demos(str(good)))["episodes"] == len(blockpuzzle.load_demos(good).episodes) > 0
    bad = tmp_path / "bad.safetensors"
    fix = "record it again with `blockpuzzle demos`"

    def case(edit, *want):
        header, demos, data = parts(good)
        raw_header = edit(header, demos, data)  # bytes: the header as written; anything else: edited in place
        write(bad, header, demos, data, raw_header=raw_header if isinstance(raw_header, bytes) else None)
        with pytest.raises(ValueError) as e:
            blockpuzzle.load_demos(bad)
        msg = str(e.value)
        assert type(e.value) is ValueError and msg.startswith(str(bad)) and fix in msg, msg
        for w in want:
            assert w in msg, (w, msg)
        with pytest.raises(ValueError, match="is not a usable demos file|safetensors|demos"):
            _native.read_demos(str(bad))
        if importlib.util.find_spec("minari"):
            with pytest.raises(ValueError, match="is not a usable"):
                blockpuzzle.to_minari(bad, "blockpuzzle/bad/solver-v0")

    # The values: NaN and infinite entities, a mask of 0.5, a flag of 2, an episode ended early.
    case(lambda h, d, data: set_value(h, data, "entities", 27, np.nan),
         "tensor 'entities' holds nan at episode 0, observation 0 (row 0); demos hold finite numbers only")
    case(lambda h, d, data: set_value(h, data, "robot", 10 * (d["episodes"][0]["steps"] + 2), np.inf),
         "tensor 'robot' holds inf at episode 1, observation 1")
    case(lambda h, d, data: set_value(h, data, "mask", 3, 0.5), "tensor 'mask' holds 0.5 at episode 0, observation 0",
         "its values are 0 or 1")
    case(lambda h, d, data: set_value(h, data, "truncations", 0, 2),
         "tensor 'truncations' holds 2.0 at episode 0, step 0")
    case(lambda h, d, data: set_value(h, data, "terminations", 0, 1), "end an episode at episode 0, step 0")
    case(lambda h, d, data: set_value(h, data, "rewards", d["episodes"][0]["steps"] - 1, -7), "episode 0's rewards sum to")
    # Values no environment gives: a feature of 1e30, an action of 1e9, a reward of 100 or 0.5.
    case(lambda h, d, data: set_value(h, data, "entities", 27, 1e30),
         "tensor 'entities' holds 1e+30 at episode 0, observation 0 (row 0); an observation is finite and within ±1000")
    case(lambda h, d, data: set_value(h, data, "actions", 5, 1e9),
         "tensor 'actions' holds 1e+09 at episode 0, step 1", "within [-1, 1]")
    case(lambda h, d, data: set_value(h, data, "rewards", 0, 100), "tensor 'rewards' holds 100 at episode 0, step 0",
         "the environment gives -1")
    case(lambda h, d, data: set_value(h, data, "rewards", d["episodes"][0]["steps"] - 1, -0.5),
         "tensor 'rewards' holds -0.5 at episode 0, step")
    # The layout: overlapping, out-of-range and mis-sized data_offsets, a missing tensor.
    def overlap(h, d, data):
        h["rewards"]["data_offsets"] = [x - 4 for x in h["rewards"]["data_offsets"]]
    case(overlap, "tensor 'rewards' has data_offsets", "overlapping tensor 'mask'")
    def beyond(h, d, data):
        h["truncations"]["data_offsets"] = [x + 8 for x in h["truncations"]["data_offsets"]]
    case(beyond, "tensor 'truncations' has data_offsets", "beyond the")
    def size(h, d, data):
        h["actions"]["shape"] = [h["actions"]["shape"][0], 3]
    case(size, "tensor 'actions' has data_offsets", "its F32 shape")
    def dtype(h, d, data):
        h["mask"]["dtype"] = "F16"
    case(dtype, "tensor 'mask' has dtype 'F16'")
    def missing(h, d, data):
        start, end = h.pop("actions")["data_offsets"]
        del data[start:end]
        for t in h.values():
            if "data_offsets" in t and t["data_offsets"][0] >= end:
                t["data_offsets"] = [x - (end - start) for x in t["data_offsets"]]
    case(missing, "no tensor 'actions'")
    # The header: not JSON, the demos entry not JSON, fields missing or of the wrong kind.
    case(lambda h, d, data: b"{not json", "its header is not JSON")
    def entry(h, d, data):
        h["__metadata__"]["blockpuzzle-demos"] = "{"
        return json.dumps(h).encode()
    case(entry, "its 'blockpuzzle-demos' metadata entry is not JSON")
    case(lambda h, d, data: d.pop("layout"), "field 'layout' of its header is missing")
    case(lambda h, d, data: d["episodes"][1].update(steps="7"), "field episodes[1].steps is '7', not a step count")
    case(lambda h, d, data: d["episodes"][0].pop("task"), "field episodes[0].task is missing")
    case(lambda h, d, data: d["layout"].update(rows=0), "field layout.rows is 0")
    # A file from before levels were recorded still reads, its options without one.
    header, demos, data = parts(good)
    assert demos["episodes"][0]["level"] == 5 and "distribution" not in demos["episodes"][0]
    for e in demos["episodes"]:
        e.pop("level")
    older = blockpuzzle.load_demos(write(tmp_path / "older.safetensors", header, demos, data))
    json.loads(_native.read_demos(str(tmp_path / "older.safetensors")))
    assert blockpuzzle.datasets.reset_options(older.episode(0)) == {"task": "BlocksTouch-v0",
                                                                    "task_sha256": older.episodes[0]["task_sha256"]}
    case(lambda h, d, data: d["episodes"][0].update(level=-1), "field episodes[0].level is -1, not a curriculum level")
    case(lambda h, d, data: d["episodes"][1].update(distribution=""), "field episodes[1].distribution is ''")
    case(lambda h, d, data: d.update(version=2), "version 2 (this package reads version 1)")
    # Fields of the right type whose values no recording has: an empty task id or hash, an unknown outcome.
    case(lambda h, d, data: d["episodes"][0].update(task=""), "field episodes[0].task is ''")
    case(lambda h, d, data: d["episodes"][1].update(task_sha256=""), "field episodes[1].task_sha256 is ''")
    case(lambda h, d, data: d["episodes"][0].update(outcome="victory"), "field episodes[0].outcome is 'victory'")
    # Cut short, and a folder.
    bad.write_bytes(good.read_bytes()[:5])
    with pytest.raises(ValueError, match=r"bad.safetensors is not a usable safetensors file: it has 5 bytes.*" + fix):
        blockpuzzle.load_demos(bad)
    with pytest.raises(ValueError, match=r"bad.safetensors.*5 bytes|bad.safetensors.*safetensors"):
        _native.read_demos(str(bad))
    with pytest.raises(ValueError, match="is a folder"):
        blockpuzzle.load_demos(tmp_path)
    with pytest.raises(FileNotFoundError, match="nothere"):
        blockpuzzle.load_demos(tmp_path / "nothere.safetensors")


def test_a_single_task_minari_export_recovers_its_environment_a_multi_task_one_has_none(tmp_path, monkeypatch):
    minari = pytest.importorskip("minari")
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    one = record(tmp_path, split="test", name="one.safetensors")
    blockpuzzle.to_minari(one, "blockpuzzle/one/solver-v0", author="A", author_email="a@example.org",
                          code_permalink="https://example.org/x")
    ds = minari.load_dataset("blockpuzzle/one/solver-v0")
    assert ds.env_spec.id == "BlockPuzzle/BlocksTouch-v0" and ds.env_spec.max_episode_steps == 50
    assert ds.env_spec.kwargs == {"task": "BlocksTouch-v0", "obs_mode": "entities"}
    env = ds.recover_environment()
    assert list(env.observation_space) == ["robot", "entities", "mask"] and env.observation_space == ds.observation_space
    # The recovered environment replays the recorded episode exactly.
    episode = next(iter(ds.iterate_episodes()))
    assert list(episode.observations) == ["robot", "entities", "mask"], "the documented order, not sorted"
    # Minari's way: the episode's seed and options, as recorded.
    meta = next(iter(ds.storage.get_episode_metadata([0])))
    obs, _ = env.reset(seed=meta["seed"], options=meta["options"])
    for k in obs:
        assert np.array_equal(obs[k], episode.observations[k][0]), k
    for t, action in enumerate(episode.actions):
        obs, reward, terminated, truncated, _ = env.step(action)
        assert reward == episode.rewards[t] and terminated == episode.terminations[t]
        assert all(np.array_equal(obs[k], episode.observations[k][t + 1]) for k in obs)
    assert terminated or truncated
    # Options of another task's episode, or of a task that has changed since, are refused.
    with pytest.raises(ValueError, match="make the environment of that task"):
        env.reset(seed=0, options={**meta["options"], "task": "BlocksAvoid-v0"})
    with pytest.raises(ValueError, match="the task has changed since the episode was recorded"):
        env.reset(seed=0, options={**meta["options"], "task_sha256": "sha256:" + "0" * 64})
    # A multi-task split: no spec, and Minari says so when asked.
    many = record(tmp_path, split="train", name="many.safetensors")
    blockpuzzle.to_minari(many, "blockpuzzle/many/solver-v0", author="A", author_email="a@example.org",
                          code_permalink="https://example.org/x")
    ds = minari.load_dataset("blockpuzzle/many/solver-v0")
    assert ds.env_spec is None
    with pytest.raises(ValueError, match="env_spec is None"):
        ds.recover_environment()


def test_a_task_that_is_not_built_in_exports_without_a_spec_and_says_why(tmp_path, monkeypatch):
    minari = pytest.importorskip("minari")
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    (task,) = [r for _, rows in blockpuzzle._native.suite("layout")["splits"] for r in rows][:1]
    (tmp_path / "mine.toml").write_text(task["toml"].replace(f'id = "{task["task_id"]}"', 'id = "MyTouch-v0"'))
    (tmp_path / "s.toml").write_text('version = 1\nname = "mine"\nsummary = "a task file"\n'
                                     '[[splits.train]]\ntask = "mine.toml"\nseed = 0\nepisodes = 1\n'
                                     '[[splits.test]]\ntask = "mine.toml"\nseed = 100\nepisodes = 1\n')
    blockpuzzle.record_demos(tmp_path / "s.toml", tmp_path / "m.safetensors", threads=1)
    assert blockpuzzle.load_demos(tmp_path / "m.safetensors").episodes[0]["task"] == "MyTouch-v0"
    with pytest.warns(UserWarning, match="'MyTouch-v0' is not a built-in id, so the dataset gets no environment spec"):
        blockpuzzle.to_minari(tmp_path / "m.safetensors", "blockpuzzle/mine/solver-v0", author="A",
                              author_email="a@example.org", code_permalink="https://example.org/x")
    assert minari.load_dataset("blockpuzzle/mine/solver-v0").env_spec is None
