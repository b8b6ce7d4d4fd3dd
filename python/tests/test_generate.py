"""Task families from Python: the core's generator (``blockpuzzle task generate``), deterministic in
the seeds, writing task files that gym.make runs in the entities mode."""

import json

import gymnasium as gym
import pytest

import blockpuzzle

FAMILY = """
version = 1
family = "tiny"
gripper = ["grey"]
table = ["grey"]
floor = ["none", "red"]

[check]
episodes = 3
min_solver_success = 0.3

[[blocks]]
name = "blue"
colour = "blue"
start = { around = "gripper", distance = [0, 0.08], density = "area" }

[[blocks]]
name = "green"
colour = "green"
start = { around = "blue", distance = [0.12, 0.16] }
"""


def test_generated_tasks_are_deterministic_and_run(tmp_path):
    family = tmp_path / "tiny.toml"
    family.write_text(FAMILY)
    a = blockpuzzle.generate_tasks(family, tmp_path / "a", seed=3, count=2, threads=1)
    b = blockpuzzle.generate_tasks(family, tmp_path / "b", seed=3, count=2, threads=2)
    assert [t["hash"] for t in a["tasks"]] == [t["hash"] for t in b["tasks"]]
    assert a["family_hash"].startswith("sha256:") and a["first_seed"] == 3
    assert json.loads((tmp_path / "a" / "generated.json").read_text())["tasks"] == a["tasks"]
    assert a["tasks"], a["rejected"]
    for t in a["tasks"]:
        assert t["id"] in (f"tiny-{s}-v0" for s in (3, 4)) and t["script"] == "push"
        env = blockpuzzle.make_task(tmp_path / "a" / f"{t['id']}.toml", obs_mode="entities")
        obs, _ = env.reset(seed=0)
        assert env.observation_space.contains(obs)
        env.close()
    # A shipped family by name.
    s = blockpuzzle.generate_tasks("stack", tmp_path / "s", seed=2, count=1, threads=1)
    assert s["family"] == "stack" and s["tasks"][0]["script"] == "pick-place", s


def test_a_bad_family_is_a_clear_error(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(FAMILY.replace('table = ["grey"]', "table = []"))
    with pytest.raises(ValueError, match="`table` lists nothing to draw from"):
        blockpuzzle.generate_tasks(bad, tmp_path / "out")
    with pytest.raises(FileNotFoundError):
        blockpuzzle.generate_tasks(tmp_path / "missing.toml", tmp_path / "out")
