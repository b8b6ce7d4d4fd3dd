"""Stable-Baselines3's own environment checker, and a few SB3 training steps through the package.
Needs stable-baselines3 (and torch): `bash scripts/sb3_check.sh` runs it in bench/.venv-sb3;
elsewhere it is skipped."""

import gymnasium as gym
import numpy as np
import pytest

sb3 = pytest.importorskip("stable_baselines3")
from stable_baselines3.common.env_checker import check_env  # noqa: E402

import blockpuzzle  # noqa: E402,F401


@pytest.mark.parametrize("env_id", ["BlocksTouch-v0", "BlocksChoose-v0", "GripperTouch-v0"])
def test_sb3_env_checker_passes(env_id):
    check_env(gym.make(f"BlockPuzzle/{env_id}").unwrapped, warn=True)


def test_sb3_td3_trains_a_few_steps_on_the_vector_env():
    from stable_baselines3 import TD3
    from stable_baselines3.common.vec_env import DummyVecEnv

    envs = DummyVecEnv([lambda: gym.make("BlockPuzzle/BlocksTouch-v0") for _ in range(2)])
    model = TD3("MlpPolicy", envs, learning_starts=100, batch_size=64, train_freq=10, seed=0, device="cpu")
    model.learn(total_timesteps=400)
    obs = envs.reset()
    action, _ = model.predict(obs, deterministic=True)
    assert action.shape == (2, 4) and np.all(np.abs(action) <= 1)
