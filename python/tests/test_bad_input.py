"""Bad input from Python (issue 43): one exception convention for files, environments that work
from any thread, actions of the wrong shape refused, damaged zoo files named."""

import shutil
import threading

import gymnasium as gym
import numpy as np
import pytest

import blockpuzzle
from blockpuzzle import zoo


def zeros(obs):
    return np.zeros((len(obs), 4), np.float32)


def test_a_missing_file_is_filenotfounderror_and_a_bad_one_valueerror(tmp_path):
    missing = tmp_path / "nothere.toml"
    with pytest.raises(FileNotFoundError, match="nothere.toml"):
        blockpuzzle.make_task(missing)
    with pytest.raises(FileNotFoundError, match="nothere.toml"):
        blockpuzzle.evaluate(zeros, suite=str(missing))
    with pytest.raises(FileNotFoundError, match="nothere"):
        zoo.load(tmp_path / "nothere.json")
    folder = tmp_path / "folder.toml"
    folder.mkdir()
    with pytest.raises(ValueError, match="folder"):
        blockpuzzle.evaluate(zeros, suite=str(folder))
    nul = tmp_path / "nul.toml"
    nul.write_bytes(b"\0" * 100)
    with pytest.raises(ValueError, match="NUL byte"):
        blockpuzzle.make_task(nul)


def test_an_environment_works_from_another_thread_and_rendering_stays_on_its_thread():
    env = gym.make("BlockPuzzle/BlocksTouch-v0", render_mode="rgb_array", width=32, height=32).unwrapped
    env.reset(seed=0)
    assert env.render().shape == (32, 32, 3)
    errors, steps = [], []

    def use():
        try:
            obs, *_ = env.step(np.zeros(4, np.float32))
            steps.append(obs)
            env.render()
        except BaseException as e:  # a PanicException would be a BaseException
            errors.append(e)

    t = threading.Thread(target=use)
    t.start()
    t.join()
    assert len(steps) == 1, "stepping from another thread works"
    assert len(errors) == 1 and type(errors[0]) is RuntimeError, errors
    assert "thread" in str(errors[0])
    env.close()


def test_an_action_of_another_shape_is_refused_not_flattened():
    env = gym.make("BlockPuzzle/BlocksTouch-v0")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(2, 2\).*\(4,\)"):
        env.step(np.zeros((2, 2), np.float32))
    with pytest.raises(ValueError, match=r"shape \(1, 4\)"):
        env.step(np.zeros((1, 4), np.float32))
    env.step(np.zeros(4, np.float32))
    envs = blockpuzzle.make_vec("BlocksTouch-v0", num_envs=2, threads=1)
    envs.reset(seed=0)
    for shape in [(8,), (4, 2), (1, 4)]:
        with pytest.raises(ValueError, match=r"invalid actions of shape"):
            envs.step(np.zeros(shape, np.float32))
    envs.step(np.zeros((2, 4), np.float32))
    envs.close()
    with pytest.raises(ValueError, match=r"actions of shape \(4, 8\) for 8 observations"):
        blockpuzzle.evaluate(lambda obs: np.zeros((4, len(obs))), suite="layout", num_envs=8, threads=1)


@pytest.mark.parametrize("native", [True, False])
def test_a_cut_short_zoo_entry_names_its_file(tmp_path, native):
    for suffix in (".json", ".safetensors"):
        src = zoo.FOLDER / "BlocksTouch-v0-ddpg"
        for s in (".json", ".safetensors"):
            shutil.copy(src.with_suffix(s), tmp_path / f"e{s}")
        cut = tmp_path / f"e{suffix}"
        data = cut.read_bytes()
        cut.write_bytes(data[: len(data) // 2])
        with pytest.raises(ValueError, match=f"e{suffix}"):
            zoo.load(tmp_path / "e.json", native=native)


def test_pickling_or_copying_an_environment_says_how_to_remake_it():
    import copy
    import pickle

    for env in (gym.make("BlockPuzzle/BlocksTouch-v0").unwrapped, blockpuzzle.make_vec("BlocksTouch-v0", num_envs=2)):
        for attempt in (pickle.dumps, copy.deepcopy):
            with pytest.raises(TypeError, match="cannot be pickled or copied.*same seed"):
                attempt(env)
        env.close()


def test_counts_and_masks_of_the_wrong_kind_are_named():
    # Issue 74: a negative count was a bare OverflowError; a mask of the wrong length blamed "environment 0".
    for call, name in [(lambda: blockpuzzle.make_vec("BlocksTouch-v0", num_envs=-2), "num_envs=-2"),
                       (lambda: blockpuzzle.make_vec("BlocksTouch-v0", num_envs=2, threads=-1), "threads=-1"),
                       (lambda: gym.make("BlockPuzzle/BlocksTouch-v0", width=-5), "width=-5"),
                       (lambda: blockpuzzle.evaluate(lambda o: o, suite="layout", num_envs=-1), "num_envs=-1"),
                       (lambda: blockpuzzle.evaluate(lambda o: o, suite="layout", episodes=-3), "episodes=-3")]:
        with pytest.raises(ValueError, match=f"{name}: give a whole number"):
            call()
    with pytest.raises(TypeError, match="num_envs must be a whole number"):
        blockpuzzle.make_vec("BlocksTouch-v0", num_envs=2.5)
    envs = blockpuzzle.make_vec("BlocksTouch-v0", num_envs=3)
    envs.reset(seed=0)
    with pytest.raises(ValueError, match=r"reset_mask'\] has shape \(2,\); the vector has 3 environments"):
        envs.reset(options={"reset_mask": [True, False]})


def test_a_zoo_policy_given_the_other_dict_mode_names_the_mode_it_reads():
    # Issue 74: a bare KeyError.
    policy = zoo.load("generalist-bc-entity")
    obs, _ = gym.make("BlockPuzzle/BlocksChoose-v0", obs_mode="objects").reset(seed=0)
    with pytest.raises(ValueError, match=r"reads the 'entities' observation .*without \['entities'\].*obs_mode='entities'"):
        policy(obs)
