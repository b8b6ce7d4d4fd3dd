"""The Gymnasium face of BlockPuzzle: registration, Gymnasium's own checker, seeding, options,
info, rendering, task files, and errors that raise instead of ending the interpreter."""

import os
import pathlib
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import blockpuzzle

IDS = blockpuzzle.env_ids()
ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_every_builtin_task_is_registered():
    assert {"BlocksTouch-v0", "BlocksChoose-v0", "GripperTouch-v0"} <= set(IDS)
    for env_id in IDS:
        assert f"BlockPuzzle/{env_id}" in gym.registry


@pytest.mark.parametrize("env_id", IDS)
def test_gymnasium_env_checker_passes(env_id):
    env = gym.make(f"BlockPuzzle/{env_id}", render_mode="rgb_array", width=64, height=64)
    check_env(env.unwrapped)
    env.close()


def test_spaces_follow_gymnasium():
    env = gym.make("BlockPuzzle/BlocksChoose-v0")
    assert env.action_space == gym.spaces.Box(-1.0, 1.0, (4,), np.float32)
    assert env.observation_space.dtype == np.float32
    obs, _ = env.reset(seed=0)
    assert obs.dtype == np.float32 and obs.shape == env.observation_space.shape
    assert env.observation_space.contains(obs)


def rollout(env, seed, steps=30):
    obs, _ = env.reset(seed=seed)
    out = [obs]
    rng = np.random.default_rng(7)
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, 4).astype(np.float32))
        out.append(np.append(obs, reward))
        if terminated or truncated:
            break
    return np.concatenate(out)


def test_a_seed_reproduces_the_episode_and_another_seed_does_not():
    env = gym.make("BlockPuzzle/BlocksChoose-v0")
    a, b, c = rollout(env, 3), rollout(env, 3), rollout(env, 4)
    assert np.array_equal(a, b)
    assert not np.array_equal(a[: len(c)], c[: len(a)])
    other = gym.make("BlockPuzzle/BlocksChoose-v0")
    assert np.array_equal(rollout(other, 3), a), "a fresh environment plays the same episode"


def test_options_set_level_and_challenge_and_bad_ones_raise_valueerror():
    env = gym.make("BlockPuzzle/BlocksChoose-v0")
    _, info = env.reset(seed=0, options={"level": 2})
    assert info["level"] == 2 and not info["challenge"]
    _, info = env.reset(seed=0, options={"challenge": True})
    assert info["challenge"]
    with pytest.raises(ValueError, match="beyond the maximum level"):
        env.reset(options={"level": 999})
    with pytest.raises(ValueError, match="unknown reset options"):
        env.reset(options={"levle": 1})
    with pytest.raises(ValueError, match="no challenge mode"):
        gym.make("BlockPuzzle/GripperTouch-v0").reset(options={"challenge": True})


def test_info_carries_success_failure_touching_and_the_contact_matrix():
    env = gym.make("BlockPuzzle/BlocksTouch-v0")
    _, info = env.reset(seed=1)
    n = len(env.unwrapped.objects)
    assert info["contact_matrix"].shape == (n, n) and info["contact_matrix"].dtype == np.int8
    _, _, _, _, info = env.step(np.zeros(4, np.float32))
    for key in ("is_success", "is_failure", "level", "touching", "elapsed_steps"):
        assert key in info
    # The blocks rest on the table: the matrix says so, and touching lists the same pairs.
    table = env.unwrapped.objects.index("table")
    for a, b in info["touching"]:
        assert info["contact_matrix"][a, b] == 2
    assert any(table in pair for pair in info["touching"])


def test_bad_actions_raise_valueerror_and_the_env_goes_on():
    env = gym.make("BlockPuzzle/BlocksTouch-v0")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="invalid action"):
        env.unwrapped.step(np.array([np.nan, 0, 0, 0], np.float32))
    with pytest.raises(ValueError, match="invalid action"):
        env.unwrapped.step(np.zeros(3, np.float32))
    env.unwrapped.step(np.zeros(4, np.float32))


def test_render_returns_an_rgb_image():
    env = gym.make("BlockPuzzle/BlocksChoose-v0", render_mode="rgb_array", width=96, height=80)
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (80, 96, 3) and frame.dtype == np.uint8
    assert frame.std() > 5, "not a blank image"


def test_close_frees_the_env_and_later_calls_raise():
    env = gym.make("BlockPuzzle/BlocksTouch-v0").unwrapped
    env.reset(seed=0)
    env.close()
    with pytest.raises(RuntimeError, match="closed"):
        env.reset(seed=0)


def test_task_files_load_by_path_and_bad_ones_raise(tmp_path):
    path = ROOT / "tasks" / "BlocksStack-v0.toml"
    env = blockpuzzle.make_task(path)
    obs, info = env.reset(seed=0)
    assert env.unwrapped.task_id == "BlocksStack-v0" and obs.shape == env.observation_space.shape
    env = gym.make("BlockPuzzle/BlocksTouch-v0", task=str(path))
    assert env.unwrapped.task_id == "BlocksStack-v0"
    bad = tmp_path / "bad.toml"
    bad.write_text(path.read_text() + "\nno_such_setting = 1\n")
    with pytest.raises(ValueError, match="no_such_setting"):
        blockpuzzle.make_task(bad)
    with pytest.raises(ValueError, match="unknown environment id"):
        gym.make("BlockPuzzle/Task-v0", task="NoSuchTask-v0")


def test_missing_fetch_assets_raise_filenotfounderror_naming_the_setup(monkeypatch, tmp_path):
    monkeypatch.setenv("BLOCKPUZZLE_MODELS_DIR", str(tmp_path))
    with pytest.raises(FileNotFoundError, match="make setup"):
        gym.make("BlockPuzzle/BlocksTouch-v0")


def run_python(code):
    """Runs `code` in a fresh interpreter; the words it printed (it must exit cleanly)."""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr
    return out.stdout.split()


def test_errors_leave_the_interpreter_running():
    code = (
        "import gymnasium as gym, numpy as np, blockpuzzle\n"
        "env = gym.make('BlockPuzzle/BlocksTouch-v0').unwrapped\n"
        "for bad in (lambda: env.step(np.zeros(4, np.float32)), lambda: env.reset(options={'level': -1}),\n"
        "            lambda: env.step(np.full(4, np.inf, np.float32))):\n"
        "    try: bad()\n"
        "    except Exception as e: print(type(e).__name__)\n"
        "env.reset(seed=0); env.step(np.zeros(4, np.float32)); print('alive')\n"
    )
    assert run_python(code) == ["RuntimeError", "ValueError", "ValueError", "alive"]


def test_a_fatal_mujoco_error_raises_and_the_interpreter_goes_on():
    code = (
        "import numpy as np, gymnasium as gym, blockpuzzle\n"
        "from blockpuzzle import _native\n"
        "try: _native._mujoco_fatal_error_selftest()\n"
        "except RuntimeError as e: print('raised', 'stack overflow' in str(e).lower())\n"
        "env = gym.make('BlockPuzzle/BlocksTouch-v0'); env.reset(seed=0); env.step(np.zeros(4, np.float32))\n"
        "print('alive')\n"
    )
    assert run_python(code) == ["raised", "True", "alive"]


def test_mujoco_version_is_the_engine_built_for():
    # scripts/python_check.sh --mujoco3 builds against MuJoCo 3.11.0 and says so here.
    want = os.environ.get("BLOCKPUZZLE_EXPECT_MUJOCO", "2.2.2")
    assert blockpuzzle.mujoco_version() == want
