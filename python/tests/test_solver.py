"""blockpuzzle.policies.solver(): the solver as a callable on entities observations, stateless."""

import random

import gymnasium as gym
import numpy as np
import pytest

import blockpuzzle


def play(task: str, seed: int, policy):
    """One episode of ``task`` with ``policy``: the observations seen and the actions taken."""
    env = gym.make(f"BlockPuzzle/{task}", obs_mode="entities")
    obs, _ = env.reset(seed=seed)
    seen = []
    while True:
        action = policy(obs)
        seen.append((obs, action))
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            return seen, info


def test_the_solver_solves_tasks_of_every_behaviour_and_keeps_no_state():
    solver = blockpuzzle.policies.solver()
    assert solver.obs_mode == "entities"
    assert solver.version == blockpuzzle._native.solver_version() >= 2
    seen_all = []
    for task in ("BlocksTouch-v0", "ReachAvoid-v0", "BlocksStack-v0", "BlocksGather-v0", "ToppleTower-v0"):
        wins = 0
        for seed in range(3):
            seen, info = play(task, seed, solver)
            wins += bool(info["is_success"])
            seen_all += seen
        assert wins >= 2, f"{task}: the solver won {wins} of 3"
    # Shuffled, one at a time and as one batch (dicts of batches): the same actions, bit for bit.
    random.Random(73).shuffle(seen_all)
    fresh = blockpuzzle.policies.solver()
    for obs, action in seen_all[:200]:
        np.testing.assert_array_equal(fresh(obs), action)
    for task in ("BlocksTouch-v0",):
        seen, _ = play(task, 5, solver)
        batch = {k: np.stack([o[k] for o, _ in seen]) for k in ("robot", "entities", "mask")}
        np.testing.assert_array_equal(fresh(batch), np.stack([a for _, a in seen]))


def test_the_solver_labels_a_learners_states_for_dagger():
    """The documented loop: the learner acts, the solver labels every state it visits."""
    env = gym.make("BlockPuzzle/BlocksTouch-v0", obs_mode="entities")
    expert = blockpuzzle.policies.solver()
    rng = np.random.default_rng(0)
    states, labels = [], []
    obs, _ = env.reset(seed=0)
    for _ in range(30):
        states.append(obs)
        labels.append(expert(obs))
        obs, _, terminated, truncated, _ = env.step(rng.uniform(-1, 1, 4).astype(np.float32))
        if terminated or truncated:
            obs, _ = env.reset()
    assert len(labels) == 30 and all(label.shape == (4,) for label in labels)
    assert any(np.abs(label).sum() > 0 for label in labels)


def test_the_solver_refuses_other_observations_naming_the_fix():
    solver = blockpuzzle.policies.solver()
    flat = gym.make("BlockPuzzle/BlocksTouch-v0")
    obs, _ = flat.reset(seed=0)
    with pytest.raises(ValueError, match='obs_mode="entities"'):
        solver(obs)
    objects = gym.make("BlockPuzzle/BlocksTouch-v0", obs_mode="objects")
    obs, _ = objects.reset(seed=0)
    with pytest.raises(ValueError, match="entities"):
        solver(obs)
    with pytest.raises(ValueError, match="one observation or a batch"):
        solver(np.zeros((2, 2, 2), np.float32))
