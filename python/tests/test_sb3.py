"""Stable-Baselines3's own environment checker, a few SB3 training steps through the package (a
DummyVecEnv of gym.make environments, and the Rust vector environment through
``blockpuzzle.sb3.SB3VecEnv``), SB3VecEnv against DummyVecEnv step for step, and the example trainer
of the wheel (``python -m blockpuzzle.examples.sb3_td3``). Needs stable-baselines3 (and torch):
`bash scripts/sb3_check.sh` runs it in bench/.venv-sb3; elsewhere it is skipped (test_sb3_vec.py
checks SB3VecEnv's contract without SB3)."""

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


def test_sb3_td3_trains_on_the_rust_vector_env_through_the_adapter():
    from stable_baselines3 import TD3
    from stable_baselines3.common.vec_env import VecEnv, VecMonitor

    from blockpuzzle.sb3 import SB3VecEnv

    envs = VecMonitor(SB3VecEnv("BlocksTouch-v0", num_envs=2, threads=2))
    assert isinstance(envs.unwrapped, VecEnv)
    model = TD3("MlpPolicy", envs, learning_starts=100, batch_size=64, train_freq=10, seed=0, device="cpu")
    model.learn(total_timesteps=400)
    assert len(model.ep_info_buffer) >= 4 and all(e["l"] <= 50 for e in model.ep_info_buffer)
    action, _ = model.predict(envs.reset(), deterministic=True)
    assert action.shape == (2, 4) and np.all(np.abs(action) <= 1)
    # A Dict observation: SB3's MultiInputPolicy.
    objects = SB3VecEnv("BlocksChooseN-v0", num_envs=2, obs_mode="objects")
    TD3("MultiInputPolicy", objects, learning_starts=50, batch_size=32, train_freq=10, seed=0,
        device="cpu").learn(total_timesteps=120)
    envs.close()
    objects.close()


def test_sb3vecenv_plays_what_sb3_s_dummyvecenv_plays():
    from stable_baselines3.common.vec_env import DummyVecEnv

    from blockpuzzle.sb3 import SB3VecEnv

    rust = SB3VecEnv("BlocksTouch-v0", num_envs=2, threads=2)
    dummy = DummyVecEnv([lambda: gym.make("BlockPuzzle/BlocksTouch-v0") for _ in range(2)])
    for v in (rust, dummy):
        v.seed(3)
    a, b = rust.reset(), dummy.reset()
    assert np.array_equal(a, b)
    rng = np.random.default_rng(1)
    for _ in range(120):
        actions = rng.uniform(-1, 1, (2, 4)).astype(np.float32)
        (oa, ra, da, ia), (ob, rb, db, ib) = rust.step(actions), dummy.step(actions)
        assert np.array_equal(oa, ob) and np.array_equal(ra, rb) and np.array_equal(da, db)
        for x, y in zip(ia, ib):
            assert x["TimeLimit.truncated"] == y["TimeLimit.truncated"] and x["is_success"] == y["is_success"]
            assert ("terminal_observation" in x) == ("terminal_observation" in y)
            if "terminal_observation" in x:
                assert np.array_equal(x["terminal_observation"], y["terminal_observation"])


@pytest.mark.parametrize("vec_env", ["rust", "dummy"])
def test_the_example_trainer_of_the_wheel_trains_resumes_and_evaluates(tmp_path, vec_env):
    import json
    import subprocess
    import sys

    run = [sys.executable, "-m", "blockpuzzle.examples.sb3_td3", "--run-dir", str(tmp_path / "r"), "--vec-env", vec_env]
    short = ["--eval-every", "200", "--episodes", "2", "--save-every", "200"]
    env = {**__import__("os").environ, "OMP_NUM_THREADS": "1"}
    out = subprocess.run([*run, *short, "--timesteps", "400"], capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stderr
    rows = (tmp_path / "r" / "progress.csv").read_text().splitlines()
    assert rows[0].startswith("epoch,curriculum/level") and len(rows) == 3, rows
    out = subprocess.run([*run, *short, "--timesteps", "600", "--resume"], capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stderr
    assert len((tmp_path / "r" / "progress.csv").read_text().splitlines()) == 4
    # Evaluated without the run's --eval-every: the env steps are the saved model's own (issue 60:
    # they were read off the evaluation schedule, -3500 after a run with --eval-every 500).
    out = subprocess.run([*run, "--evaluate", "2"], capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert result["episodes"] == 2 and 0 <= result["success"] <= 1
    assert 600 <= result["env_steps"] <= 602, result
