"""The zoo in the package: every entry loads and reproduces its recorded actions, and records its
evaluations on the package's MuJoCo (test_provenance.py: a zoo policy scores what the command line,
built on the same MuJoCo, scores)."""

import os

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
    assert generalist.meta["format"] == "blockpuzzle-zoo/6"
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
    with pytest.raises(KeyError, match="no zoo entry 'NoSuch'"):
        zoo.load("NoSuch")
