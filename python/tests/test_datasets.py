"""Demonstrations from Python: the solver's episodes recorded as the CLI records them, read with
numpy, and exported as a Minari dataset that Minari loads back equal to the recording."""

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
