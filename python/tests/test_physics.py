"""Dynamics that vary per episode (issue 76): a task file's ``[physics]`` table through the
Gymnasium environment and the vector environment, the ``physics`` reset option and its checks."""

import pathlib

import gymnasium as gym
import numpy as np
import pytest

import blockpuzzle

ROOT = pathlib.Path(__file__).resolve().parents[2]

TABLE = """
[physics]
friction = [0.5, 2]
mass = [0.5, 2]
latency = [0, 2]
obs_noise = [0, 0.005]
"""


@pytest.fixture
def task(tmp_path):
    text = (ROOT / "tasks" / "BlocksTouch-v0.toml").read_text()
    path = tmp_path / "TouchPhysics-v0.toml"
    path.write_text(text.replace('id = "BlocksTouch-v0"', 'id = "TouchPhysics-v0"') + TABLE)
    return str(path)


def test_the_draw_is_in_info_and_a_seed_repeats_it(task):
    env = gym.make("BlockPuzzle/Task-v0", task=task)
    _, info = env.reset(seed=3)
    drawn = info["physics"]
    assert set(drawn) == {"friction", "torsional_friction", "mass", "damping", "gain", "solref", "solimp",
                          "action_noise", "latency", "obs_noise"}
    assert 0.5 <= drawn["friction"] <= 2 and drawn["damping"] == 1.0 and isinstance(drawn["latency"], int)
    *_, step_info = env.step(np.zeros(4, np.float32))
    assert step_info["physics"] == drawn
    assert env.reset(seed=4)[1]["physics"] != drawn
    assert env.reset(seed=3)[1]["physics"] == drawn
    # A task without the table reports none.
    assert "physics" not in gym.make("BlockPuzzle/BlocksTouch-v0").reset(seed=0)[1]


def test_the_physics_option_pins_a_parameter_for_one_episode(task):
    env = gym.make("BlockPuzzle/Task-v0", task=task)
    _, info = env.reset(seed=0, options={"physics": {"mass": 1.5, "latency": 1}})
    assert info["physics"]["mass"] == 1.5 and info["physics"]["latency"] == 1
    # The next reset without the option draws again.
    assert env.reset(seed=0)[1]["physics"]["mass"] != 1.5


@pytest.mark.parametrize("physics, message", [
    ({"mass": 5.0}, "outside the task's range"),
    ({"wind": 1.0}, "no such parameter"),
    ({"damping": 1.0}, "does not vary it"),
    ({"mass": "heavy"}, "must be a number"),
    ([("mass", 1.0)], "must be a dict"),
])
def test_bad_physics_options_raise(task, physics, message):
    env = gym.make("BlockPuzzle/Task-v0", task=task)
    with pytest.raises(ValueError, match=message):
        env.reset(seed=0, options={"physics": physics})


def test_a_task_without_the_table_refuses_physics_options():
    env = gym.make("BlockPuzzle/BlocksTouch-v0")
    with pytest.raises(ValueError, match=r"a task with no \[physics\] table"):
        env.reset(seed=0, options={"physics": {"mass": 1.0}})


def test_a_bad_table_names_the_field(tmp_path):
    text = (ROOT / "tasks" / "BlocksTouch-v0.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text + "\n[physics]\nmass = [2, 0.5]\n")
    with pytest.raises(ValueError, match=r"physics.mass = \[2, 0.5\]: low is above high"):
        gym.make("BlockPuzzle/Task-v0", task=str(bad))


def test_the_vector_environment_reports_each_draw_and_takes_the_option(task):
    envs = blockpuzzle.make_vec(task, num_envs=3)
    _, info = envs.reset(seed=10)
    single = gym.make("BlockPuzzle/Task-v0", task=task)
    for i in range(3):
        drawn = single.reset(seed=10 + i)[1]["physics"]
        assert info["physics"]["mass"][i] == drawn["mass"]
    _, info = envs.reset(seed=10, options={"physics": {"friction": 0.75}})
    assert np.all(info["physics"]["friction"] == 0.75)
    with pytest.raises(ValueError, match="outside the task's range"):
        envs.reset(seed=10, options={"physics": {"friction": 3.0}})
