"""``blockpuzzle.sb3.SB3VecEnv``: Stable-Baselines3's ``VecEnv`` contract over the Rust vector
environment, checked without SB3 (the class then stands alone; with SB3 installed it is a subclass
of SB3's ``VecEnv`` and these tests run the same). Environment i must play exactly what a
``gym.make`` environment plays with the same seeds and actions, reset by hand as SB3's
``DummyVecEnv`` resets it. The tests that use SB3 itself are in test_sb3.py. Also: the SB3 example
trainer travels in the wheel and runs with ``python -m``."""

import importlib.util
import os
import pathlib
import pickle
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

import blockpuzzle
from blockpuzzle import sb3
from blockpuzzle.sb3 import SB3VecEnv

HAS_SB3 = importlib.util.find_spec("stable_baselines3") is not None


def equal(a, b):
    if isinstance(a, dict):
        return list(a) == list(b) and all(np.array_equal(a[k], b[k]) for k in a)
    return np.array_equal(a, b)


def row(obs, i):
    return {k: v[i] for k, v in obs.items()} if isinstance(obs, dict) else obs[i]


def test_it_derives_from_sb3_s_vecenv_exactly_where_sb3_is_installed():
    if HAS_SB3:
        from stable_baselines3.common.vec_env import VecEnv
        assert issubclass(SB3VecEnv, VecEnv)
    else:
        assert sb3.BASE is object and SB3VecEnv.__mro__[1] is object
    assert "stable_baselines3" not in sys.modules or HAS_SB3


@pytest.mark.parametrize("obs_mode", ["flat", "objects"])
def test_steps_and_auto_resets_match_gym_make_environments_reset_by_hand(obs_mode):
    """Shapes, rewards, dones, the auto-reset with terminal_observation and TimeLimit.truncated,
    and the seeds: step for step what two gym.make environments give."""
    n = 2
    policy = blockpuzzle.zoo.load("BlocksTouch-v0-ddpg")
    envs = SB3VecEnv("BlockPuzzle/BlocksTouch-v0", num_envs=n, threads=2, obs_mode=obs_mode)
    refs = [gym.make("BlockPuzzle/BlocksTouch-v0", obs_mode=obs_mode) for _ in range(n)]
    assert envs.num_envs == n and envs.observation_space == refs[0].observation_space
    assert envs.action_space == refs[0].action_space
    assert envs.seed(100) == [100, 101]
    obs = envs.reset()
    want = [r.reset(seed=100 + i)[0] for i, r in enumerate(refs)]
    for i in range(n):
        assert equal(row(obs, i), want[i])
    if obs_mode == "objects":
        assert list(obs) == ["robot", "objects", "mask"] and obs["objects"].shape == (n, 2, 22)
    else:
        assert obs.shape == (n, 48) and obs.dtype == np.float32
    assert envs.reset_infos[0]["level"] == 0 and "is_success" in envs.reset_infos[1]
    rng = np.random.default_rng(0)
    ended = {"terminated": 0, "truncated": 0}
    for _ in range(130):
        # Environment 0 plays the trained policy (episodes that end by the rules), 1 random actions
        # (episodes cut at the step limit).
        a0 = policy(want[0]) if obs_mode == "flat" else rng.uniform(-1, 1, 4)
        actions = np.stack([a0, rng.uniform(-1, 1, 4)]).astype(np.float32)
        envs.step_async(actions)
        obs, rewards, dones, infos = envs.step_wait()
        assert rewards.shape == (n,) and rewards.dtype == np.float32 and dones.shape == (n,) and dones.dtype == bool
        assert isinstance(infos, list) and len(infos) == n
        for i, r in enumerate(refs):
            o, rew, term, trunc, info = r.step(actions[i])
            assert rew == rewards[i] and (term or trunc) == dones[i]
            assert infos[i]["is_success"] == info["is_success"] and infos[i]["elapsed_steps"] == info["elapsed_steps"]
            assert infos[i]["TimeLimit.truncated"] == (trunc and not term)
            if term or trunc:
                ended["terminated" if term else "truncated"] += 1
                assert equal(infos[i]["terminal_observation"], o)
                o, _ = r.reset()  # the environment's own seed stream goes on, as in DummyVecEnv
            else:
                assert "terminal_observation" not in infos[i]
            assert equal(row(obs, i), o)
            want[i] = o
    assert ended["truncated"] >= 2, ended
    if obs_mode == "flat":
        assert ended["terminated"] >= 2, ended
    envs.close()
    for r in refs:
        r.close()


def test_seed_options_and_per_environment_settings():
    envs = SB3VecEnv("BlocksTouch-v0", num_envs=3, threads=1)
    ref = gym.make("BlockPuzzle/BlocksTouch-v0")
    top = envs.get_attr("max_level")[0]
    # set_options: used by the next reset() only (as SB3 does), and the seeds of seed() likewise.
    envs.seed(7)
    envs.set_options({"level": 2})
    obs = envs.reset()
    assert [i["level"] for i in envs.reset_infos] == [2, 2, 2]
    assert np.array_equal(obs[1], ref.reset(seed=8, options={"level": 2})[0])
    assert envs._options == [{}, {}, {}] and envs._seeds == [None, None, None]
    with pytest.raises(ValueError, match="unknown reset options.*lvl"):
        envs.set_options({"lvl": 1})
    with pytest.raises(ValueError, match="2 option dicts for 3 environments"):
        envs.set_options([{}, {}])
    with pytest.raises(ValueError, match="seed -1"):
        envs.seed(-1)
    # set_attr: from each environment's next episode on (an auto-reset, or env_method's reset).
    assert envs.get_attr("level") == [2, 2, 2]
    envs.set_attr("level", top, indices=[0])
    assert envs.get_attr("level") == [top, 2, 2]
    (first, info), = envs.env_method("reset", seed=5, indices=0)
    assert info["level"] == top and np.array_equal(first, ref.reset(seed=5, options={"level": top})[0])
    envs.set_attr("level", 0, indices=2)
    for _ in range(50):  # every episode of random actions ends by step 50
        obs, _, dones, infos = envs.step(np.zeros((3, 4), np.float32))
        if dones[2]:
            break
    assert dones[2] and envs.reset_infos[2]["level"] == 0 and envs.get_attr("level", 2) == [0]
    with pytest.raises(ValueError, match=f"level {top + 1}: an int from 0 to {top}"):
        envs.set_attr("level", top + 1)
    with pytest.raises(AttributeError, match="'task_id' cannot be set"):
        envs.set_attr("task_id", "x")
    envs.close()


def test_get_attr_env_method_and_the_rest_of_the_interface():
    envs = SB3VecEnv("ReachAvoid-v0", num_envs=2, threads=1)
    single = gym.make("BlockPuzzle/ReachAvoid-v0").unwrapped
    assert envs.get_attr("task_id") == ["ReachAvoid-v0"] * 2
    assert envs.get_attr("max_episode_steps", indices=[1]) == [50]
    assert envs.get_attr("spec")[0].id == "BlockPuzzle/ReachAvoid-v0"
    assert envs.get_attr("observation_space")[0] == single.observation_space
    assert envs.get_attr("objects", 0) == [[n for n, _ in single._env.objects()]]
    assert envs.get_attr("render_mode") == [None, None] and envs.render_mode is None
    assert envs.has_attr("max_level") and not envs.has_attr("nope")
    with pytest.raises(AttributeError, match="no attribute 'nope'; get_attr knows task_id"):
        envs.get_attr("nope")
    with pytest.raises(IndexError, match="environments 0 to 1"):
        envs.get_attr("task_id", indices=[2])
    assert envs.env_method("get_wrapper_attr", "max_level") == [single.max_level] * 2
    assert envs.env_method("has_wrapper_attr", "obs_layout", indices=[0]) == [True]
    with pytest.raises(AttributeError, match="no method 'render' here; env_method calls reset"):
        envs.env_method("render")
    assert envs.env_is_wrapped(gym.Wrapper) == [False, False]
    assert envs.unwrapped is envs
    with pytest.raises(NotImplementedError, match="does not render"):
        envs.get_images()
    with pytest.raises(RuntimeError, match="step_wait.. without step_async"):
        envs.step_wait()
    with pytest.raises(TypeError, match="cannot be pickled"):
        pickle.dumps(envs)
    envs.reset()
    envs.close()
    envs.close()  # a second close does nothing
    with pytest.raises(RuntimeError, match="closed"):
        envs.step(np.zeros((2, 4), np.float32))


def test_the_example_trainer_is_in_the_wheel_and_runs_with_python_m(tmp_path):
    from blockpuzzle.examples import sb3_td3
    if os.environ.get("BLOCKPUZZLE_WHEEL_TEST"):  # the installed package's copy, not the checkout's
        assert not pathlib.Path(sb3_td3.__file__).resolve().is_relative_to(os.environ["BLOCKPUZZLE_WHEEL_TEST"])
    run = [sys.executable, "-m", "blockpuzzle.examples.sb3_td3"]
    out = subprocess.run([*run, "--help"], capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 0 and "--vec-env {dummy,rust}" in out.stdout and "--evaluate" in out.stdout, out
    # The description is whole (it was cut at the docstring's first line), and --env says what it takes.
    words = " ".join(out.stdout.split())  # argparse wraps lines at the terminal's width
    assert "so the two trainers' curves on the same environment can be drawn side by side." in words, words
    assert "with or without the BlockPuzzle/ namespace" in words, words
    if HAS_SB3:
        pytest.skip("SB3 is installed: test_sb3.py runs the trainer")
    out = subprocess.run([*run, "--timesteps", "10", "--run-dir", "r"], capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 1 and "pip install stable-baselines3" in out.stderr, out
    assert not (tmp_path / "r").exists()
