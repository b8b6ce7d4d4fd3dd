"""The Gymnasium face of BlockPuzzle: registration, Gymnasium's own checker, seeding, options,
info, rendering, task files, and errors that raise instead of ending the interpreter."""

import json
import os
import pathlib
import shutil
import subprocess
import re
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


def test_a_task_lists_its_distributions_and_each_is_a_reset_option():
    env = gym.make("BlockPuzzle/BlocksAvoid-v0")
    names = env.get_wrapper_attr("distributions")
    assert sorted(names) == ["challenge", "clear"], names
    for name in names:
        _, info = env.reset(seed=0, options={"distribution": name})
        assert info["distribution"] == name
    assert gym.make("BlockPuzzle/GripperTouch-v0").get_wrapper_attr("distributions") == []
    envs = blockpuzzle.make_vec("BlocksAvoid-v0", num_envs=1)
    assert envs.distributions == names
    envs.close()


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


def test_mujoco_version_is_the_pinned_mujoco_package():
    import importlib.metadata

    assert blockpuzzle.mujoco_version() == blockpuzzle.MUJOCO_PIN == importlib.metadata.version("mujoco")


GOLDEN = json.loads((ROOT / "tests" / "golden.json").read_text())["cases"]


@pytest.mark.parametrize("case", GOLDEN, ids=lambda c: f"{c['env']}-{c['policy']}-{c['level']}-{c['seed']}")
def test_episodes_are_bit_identical_to_the_rust_golden_digests(case):
    # The digests the Rust tests check on the same engine (tests/it/golden.rs built with mujoco3).
    engine = blockpuzzle.mujoco_version()
    got = blockpuzzle._native._golden_digest(case["env"], case["policy"] == "scripted", case["level"],
                                             case["challenge"], case["seed"])
    assert got == case[engine]


def test_the_fetch_files_come_from_the_installed_gymnasium_robotics():
    import importlib.util

    if os.environ.get("BLOCKPUZZLE_MODELS_DIR"):
        pytest.skip("BLOCKPUZZLE_MODELS_DIR overrides the assets")
    package = pathlib.Path(importlib.util.find_spec("gymnasium_robotics").submodule_search_locations[0])
    assert blockpuzzle.assets_dir() == package / "envs" / "assets"
    checkout = os.environ.get("BLOCKPUZZLE_WHEEL_TEST")
    if checkout:  # scripts/python_check.sh: the installed wheel, nothing of the checkout
        assert not pathlib.Path(blockpuzzle.__file__).resolve().is_relative_to(checkout)
        assert not blockpuzzle.assets_dir().resolve().is_relative_to(checkout)


def test_a_changed_fetch_file_is_refused_naming_it(tmp_path):
    assets = blockpuzzle.assets_dir()
    if not (assets / "fetch" / "shared.xml").exists():
        pytest.skip("the assets are a models folder (BLOCKPUZZLE_MODELS_DIR)")
    for sub in ("fetch", "stls/fetch", "textures"):
        shutil.copytree(assets / sub, tmp_path / sub)
    blockpuzzle._native._use_fetch_assets(str(tmp_path))  # an exact copy passes
    blockpuzzle._native._use_fetch_assets(str(assets))
    shared = tmp_path / "fetch" / "shared.xml"
    original = shared.read_bytes()
    shared.write_bytes(original + b"\n")
    with pytest.raises(ValueError, match="shared.xml.*gymnasium-robotics==1.4.2"):
        blockpuzzle._native._use_fetch_assets(str(tmp_path))
    shared.write_bytes(original)
    (tmp_path / "textures" / "block.png").unlink()
    with pytest.raises(FileNotFoundError, match="block.png"):
        blockpuzzle._native._use_fetch_assets(str(tmp_path))
    assert blockpuzzle.assets_dir() == assets  # refusals change nothing


@pytest.mark.parametrize("patch, pip", [
    ("m.version = lambda n, v=m.version: '3.12.0' if n == 'mujoco' else v(n)", "pip install mujoco==3.11.0"),
    ("def gone(n):\n    raise m.PackageNotFoundError(n)\nm.version = gone", "pip install mujoco==3.11.0"),
    ("u.find_spec = lambda n, *a, f=u.find_spec: None if n == 'gymnasium_robotics' else f(n, *a)",
     "pip install gymnasium-robotics==1.4.2"),
])
def test_a_missing_or_other_dependency_is_an_importerror_naming_the_pip_command(patch, pip):
    code = (
        "import importlib.metadata as m, importlib.util as u, os\n"
        "os.environ.pop('BLOCKPUZZLE_MODELS_DIR', None)\n"
        f"{patch}\n"
        "try:\n    import blockpuzzle\nexcept ImportError as e:\n    print(str(e))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and pip in out.stdout, out.stdout + out.stderr


def test_the_registry_records_each_tasks_step_limit():
    for env_id in blockpuzzle.env_ids():
        spec = gym.spec(f"BlockPuzzle/{env_id}")
        assert spec.max_episode_steps == blockpuzzle._native.max_episode_steps(env_id) > 0, env_id
    env = gym.wrappers.RecordEpisodeStatistics(gym.make("BlockPuzzle/BlocksTouch-v0"))
    assert env.spec.max_episode_steps == 50
    env.reset(seed=0)
    for t in range(50):
        _, _, terminated, truncated, info = env.step(np.zeros(4, np.float32))
        if terminated or truncated:
            break
    assert truncated and t == 49 and info["episode"]["l"] == 50


def test_make_task_gives_its_spec_the_task_file_s_step_limit(tmp_path):
    files = sorted((ROOT / "tasks").glob("*.toml"))
    assert len(files) >= 10
    for path in files:
        env = blockpuzzle.make_task(path)
        (written,) = [int(x) for x in re.findall(r"(?m)^max_episode_steps = (\d+)$", path.read_text())]  # 50, or 100
        assert env.spec.max_episode_steps == written == gym.spec(f"BlockPuzzle/{path.stem}").max_episode_steps
        env.close()
    text = (ROOT / "tasks" / "BlocksTouch-v0.toml").read_text()
    assert "max_episode_steps = 50" in text
    short = tmp_path / "short.toml"
    short.write_text(text.replace("max_episode_steps = 50", "max_episode_steps = 30"))
    env = gym.wrappers.RecordEpisodeStatistics(blockpuzzle.make_task(short))
    assert env.spec.max_episode_steps == 30
    env.reset(seed=0)
    for t in range(50):
        _, _, terminated, truncated, info = env.step(np.zeros(4, np.float32))
        if terminated or truncated:
            break
    assert truncated and t == 29 and info["episode"]["l"] == 30
    assert blockpuzzle.make_task(short, max_episode_steps=10).spec.max_episode_steps == 10
    with pytest.raises(FileNotFoundError, match="nothere.toml"):
        blockpuzzle.make_task(tmp_path / "nothere.toml")
