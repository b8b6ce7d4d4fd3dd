"""blockpuzzle.evaluate: a callable policy on an evaluation suite, with the CLI's definitions."""

import gymnasium as gym
import numpy as np
import pytest

import blockpuzzle

TINY = """
version = 1
name = "tiny"
summary = "A few episodes each way."
[[splits.train]]
task = "BlocksTouch-v0"
seed = 3000000
episodes = 7
[[splits.test]]
task = "BlocksChoose-v0"
distribution = "challenge"
seed = 1000000
episodes = 5
"""


def policy(obs):
    """Deterministic: move the gripper towards the first block (a poor but not hopeless pusher)."""
    obs = np.atleast_2d(obs)
    delta = obs[:, 10:13] - obs[:, 0:3]
    return np.concatenate([np.clip(delta * 20, -1, 1), np.zeros((len(obs), 1))], axis=1).astype(np.float32)


def explicit(task, seed, episodes, options):
    """The same episodes one by one in a single environment."""
    env = gym.make(f"BlockPuzzle/{task}")
    wins = fails = 0
    for k in range(episodes):
        obs, _ = env.reset(seed=seed + k, options=options)
        success = failure = False
        while True:
            obs, _, term, trunc, info = env.step(policy(obs)[0])
            success |= info["is_success"]
            failure |= info["is_failure"]
            if term or trunc:
                break
        wins, fails = wins + success, fails + failure
    return wins, fails


def test_evaluate_matches_single_environment_episodes_whatever_num_envs(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    a = blockpuzzle.evaluate(policy, suite=str(path), num_envs=3, threads=2)
    b = blockpuzzle.evaluate(policy, suite=str(path), num_envs=1, threads=1)
    assert a == b
    train, test = a["splits"][0]["rows"][0], a["splits"][1]["rows"][0]
    env = gym.make("BlockPuzzle/BlocksTouch-v0")
    wins, fails = explicit("BlocksTouch-v0", 3000000, 7, {"level": env.unwrapped.max_level})
    assert (train["successes"], round(train["failure_rate"] * 7)) == (wins, fails)
    wins, _ = explicit("BlocksChoose-v0", 1000000, 5, {"challenge": True, "level": 10})
    assert test["successes"] == wins
    assert a["score"] == test["success_rate"] and a["gap"] == train["success_rate"] - test["success_rate"]
    lo, hi = test["ci95"]
    assert 0 <= lo <= test["success_rate"] <= hi <= 1
    assert len(a["suite"]["sha256"]) == 64 and a["suite"]["name"] == "tiny"


def test_built_in_suites_and_bad_suites():
    assert blockpuzzle._native.suite("layout")["splits"][1][0] == "test"
    with pytest.raises(ValueError, match="unknown suite"):
        blockpuzzle.evaluate(policy, suite="nonsense")
    with pytest.raises(FileNotFoundError):
        blockpuzzle.evaluate(policy, suite="/nonexistent/suite.toml")
    assert blockpuzzle.evaluation.wilson95(50, 100) == pytest.approx((0.4038, 0.5962), abs=1e-3)
