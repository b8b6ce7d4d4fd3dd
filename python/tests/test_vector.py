"""The Rust-threaded vector environment: Gymnasium's next-step autoreset, per-env seeds and
options, and environment i's trajectory bit-identical whatever num_envs and threads are."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import blockpuzzle


def actions(num_envs, step):
    """Each environment's action depends on its index and the step only."""
    return np.stack([np.random.default_rng([i, step]).uniform(-1, 1, 4) for i in range(num_envs)]).astype(np.float32)


def trajectory(num_envs, threads, env_index, steps=130, seed=10):
    envs = blockpuzzle.make_vec("BlocksChoose-v0", num_envs=num_envs, threads=threads)
    obs, _ = envs.reset(seed=seed)
    rows = [obs[env_index]]
    for t in range(steps):
        obs, rew, term, trunc, info = envs.step(actions(num_envs, t))
        rows.append(np.concatenate([obs[env_index], [rew[env_index], term[env_index], trunc[env_index],
                                                     info["autoreset"][env_index]]]))
    envs.close()
    return np.concatenate(rows)


def test_env_3_is_the_same_whatever_num_envs_and_threads():
    a = trajectory(4, 1, 3)
    b = trajectory(8, 2, 3)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, trajectory(4, 1, 2)), "other environments differ"


def test_a_vector_env_plays_what_the_single_env_plays():
    envs = blockpuzzle.make_vec("BlocksTouch-v0", num_envs=3, threads=2)
    single = gym.make("BlockPuzzle/BlocksTouch-v0").unwrapped
    obs, _ = envs.reset(seed=5)
    s_obs, _ = single.reset(seed=7)  # environment 2 gets seed 5 + 2
    assert np.array_equal(obs[2], s_obs)
    for t in range(40):
        a = actions(3, t)
        obs, rew, term, trunc, _ = envs.step(a)
        s_obs, s_rew, s_term, s_trunc, _ = single.step(a[2])
        assert np.array_equal(obs[2], s_obs) and rew[2] == s_rew and (term[2], trunc[2]) == (s_term, s_trunc)
        if s_term or s_trunc:
            break


def test_next_step_autoreset_and_metadata():
    envs = blockpuzzle.make_vec("GripperTouch-v0", num_envs=2, threads=1)
    assert envs.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    assert envs.observation_space.shape == (2, envs.single_observation_space.shape[0])
    assert envs.action_space.shape == (2, 4)
    envs.reset(seed=0)
    ended_at = None
    for t in range(200):
        obs, rew, term, trunc, info = envs.step(actions(2, t))
        if ended_at is not None:
            assert info["autoreset"][0] and rew[0] == 0 and not term[0] and not trunc[0]
            assert info["elapsed_steps"][0] == 0
            break
        if term[0] or trunc[0]:
            ended_at = t
    assert ended_at is not None


def test_gymnasium_make_vec_uses_the_rust_vector_env():
    envs = gym.make_vec("BlockPuzzle/BlocksTouch-v0", num_envs=3, vectorization_mode="vector_entry_point")
    assert isinstance(envs, blockpuzzle.BlockPuzzleVectorEnv)
    obs, info = envs.reset(seed=[1, None, 3])
    assert obs.shape == (3, envs.single_observation_space.shape[0]) and obs.dtype == np.float32
    assert info["contact_matrix"].shape[0] == 3 and info["_is_success"].all()


def test_reset_mask_and_options_and_bad_input():
    envs = blockpuzzle.make_vec("BlocksChoose-v0", num_envs=3, threads=2)
    obs, info = envs.reset(seed=0, options={"level": 4})
    assert list(info["level"]) == [4, 4, 4]
    before = obs.copy()
    obs, info = envs.reset(seed=[9, 9, 9], options={"reset_mask": [False, True, False], "challenge": True})
    assert np.array_equal(obs[0], before[0]) and np.array_equal(obs[2], before[2])
    assert not np.array_equal(obs[1], before[1]) and info["challenge"][1] and not info["_level"][0]
    with pytest.raises(ValueError, match="shape"):
        envs.step(np.zeros((2, 4), np.float32))
    bad = np.zeros((3, 4), np.float32)
    bad[1, 2] = np.nan
    with pytest.raises(ValueError, match="environment 1"):
        envs.step(bad)
    with pytest.raises(ValueError, match="unknown reset options"):
        envs.reset(options={"lvl": 1})
    envs.step(np.zeros((3, 4), np.float32))  # still usable
    envs.close()
    with pytest.raises(RuntimeError, match="closed"):
        envs._native.step(np.zeros((3, 4), np.float32), envs._obs, envs._rewards, envs._terminated, envs._truncated)


def test_copy_false_returns_the_preallocated_buffers():
    envs = blockpuzzle.make_vec("BlocksTouch-v0", num_envs=2, copy=False)
    obs, _ = envs.reset(seed=0)
    obs2, *_ = envs.step(np.zeros((2, 4), np.float32))
    assert obs is obs2


def test_a_vector_env_can_move_between_threads():
    """Made on one thread, stepped on another (a data loader's worker, say), closed on a third."""
    import threading

    envs = blockpuzzle.make_vec("BlocksTouch-v0", num_envs=2, threads=2)
    out, errors = {}, []

    def play():
        try:
            obs, _ = envs.reset(seed=3)
            for t in range(5):
                obs, *_ = envs.step(actions(2, t))
            out["obs"] = obs
        except Exception as e:  # noqa: BLE001 - reported below, on the test's thread
            errors.append(e)

    worker = threading.Thread(target=play)
    worker.start()
    worker.join()
    assert not errors, errors
    obs, _ = envs.reset(seed=3)
    for t in range(5):
        obs, *_ = envs.step(actions(2, t))
    assert np.array_equal(out["obs"], obs)
    closer = threading.Thread(target=envs.close)
    closer.start()
    closer.join()
    with pytest.raises(RuntimeError, match="closed"):
        envs.step(actions(2, 0))


def test_absurd_sizes_are_refused_naming_the_range():
    with pytest.raises(ValueError, match="num_envs = 100,000: allowed are 1 to 4,096"):
        blockpuzzle.make_vec("BlocksTouch-v0", num_envs=100_000)
    with pytest.raises(ValueError, match="threads = 0: allowed are 1 to 256"):
        blockpuzzle.make_vec("BlocksTouch-v0", num_envs=2, threads=0)


def test_the_vector_info_has_the_single_environments_keys():
    single = gym.make("BlockPuzzle/BlocksTouch-v0")
    _, single_info = single.reset(seed=0)
    envs = blockpuzzle.make_vec("BlocksTouch-v0", num_envs=2, threads=1)
    _, info = envs.reset(seed=0)
    for key in single_info:
        assert key in info and f"_{key}" in info, key
    assert info["distribution"].shape == (2,) and info["distribution"][0] == single_info["distribution"]
    assert info["touching"].shape == (2,) and info["touching"][0] == single_info["touching"]
    _, _, _, _, info = envs.step(np.zeros((2, 4), np.float32))
    assert isinstance(info["touching"][1], list)


def test_make_vec_takes_the_spec_step_limit_and_refuses_another():
    envs = gym.make_vec("BlockPuzzle/BlocksTouch-v0", num_envs=2, vectorization_mode="vector_entry_point")
    assert envs.spec.max_episode_steps == 50
    with pytest.raises(ValueError, match="truncates its episodes at 50 steps"):
        gym.make_vec("BlockPuzzle/BlocksTouch-v0", num_envs=2, vectorization_mode="vector_entry_point",
                     max_episode_steps=10)


def episodes_of(mode, steps=150, obs_mode="flat"):
    """Environment 1's observations, rewards and flags under an autoreset mode, each episode's
    first observation as the mode reports it; DISABLED resets the ended environments itself."""
    envs = blockpuzzle.make_vec("GripperTouch-v0", num_envs=2, threads=1, obs_mode=obs_mode, autoreset_mode=mode)
    assert envs.metadata["autoreset_mode"] == AutoresetMode[mode.upper()]
    obs, _ = envs.reset(seed=3)

    def row(o, i):
        return o[i] if obs_mode == "flat" else np.concatenate([v[i].ravel() for v in o.values()])

    def flat(o):
        return row(o, 1)

    # Each action a function of the environment's own observation: the episodes do not depend on
    # where the steps fall (next-step autoreset spends a step on the reset).
    weights = np.random.default_rng(0).normal(size=(4, len(flat(obs)))) * 0.5

    def act(o):
        return np.stack([np.tanh(weights @ np.nan_to_num(row(o, i))) for i in range(2)]).astype(np.float32)

    starts, finals = [flat(obs)], []
    for t in range(steps):
        obs, rew, term, trunc, info = envs.step(act(obs))
        if mode == "next_step" and info["autoreset"][1]:
            starts.append(flat(obs))
            continue
        if term[1] or trunc[1]:
            if mode == "same_step":
                assert info["_final_obs"][1] and info["_final_info"][1]
                final = info["final_obs"][1]
                finals.append(final if obs_mode == "flat" else np.concatenate([v.ravel() for v in final.values()]))
                assert info["final_info"]["elapsed_steps"][1] > 0 and info["elapsed_steps"][1] == 0
                starts.append(flat(obs))
            else:
                finals.append(flat(obs))
            if mode == "disabled":
                done = term | trunc
                with pytest.raises(ValueError, match="DISABLED: reset them first"):
                    envs.step(act(obs))
                obs, _ = envs.reset(options={"reset_mask": done})
                starts.append(flat(obs))
        elif mode == "disabled" and (term[0] or trunc[0]):
            obs, _ = envs.reset(options={"reset_mask": term | trunc})
    envs.close()
    return starts, finals


@pytest.mark.parametrize("obs_mode", ["flat", "entities"])
def test_the_three_autoreset_modes_play_the_same_episodes(obs_mode):
    nxt = episodes_of("next_step", obs_mode=obs_mode)
    assert len(nxt[1]) >= 2, "episodes ended within the steps"
    for mode in ("same_step", "disabled"):
        other = episodes_of(mode, obs_mode=obs_mode)
        n = min(len(nxt[1]), len(other[1]))
        assert n >= 2
        for a, b in zip(nxt[0][:n + 1], other[0][:n + 1]):
            assert np.array_equal(a, b), mode
        for a, b in zip(nxt[1][:n], other[1][:n]):
            assert np.array_equal(a, b), mode
    with pytest.raises(ValueError, match="not one of Gymnasium's"):
        blockpuzzle.make_vec("GripperTouch-v0", num_envs=1, autoreset_mode="sometimes")
    envs = gym.make_vec("BlockPuzzle/GripperTouch-v0", num_envs=2, autoreset_mode=AutoresetMode.SAME_STEP)
    assert envs.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    envs.close()


def test_per_environment_wrappers_take_the_sync_mode():
    # Gymnasium refuses wrappers= for a vector entry point (its own environments' too); sync mode
    # wraps each environment, as docs/python.md says.
    with pytest.raises(gym.error.Error, match="wrappers"):
        gym.make_vec("BlockPuzzle/BlocksTouch-v0", num_envs=2, wrappers=[gym.wrappers.RecordEpisodeStatistics])
    envs = gym.make_vec("BlockPuzzle/BlocksTouch-v0", num_envs=2, vectorization_mode="sync",
                        wrappers=[gym.wrappers.RecordEpisodeStatistics])
    obs, _ = envs.reset(seed=0)
    assert obs.shape == (2, envs.single_observation_space.shape[0])
    envs.step(np.zeros((2, 4), np.float32))
    envs.close()
