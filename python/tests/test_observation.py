"""Observation modes: the flat vector (every id's default), obs_mode="objects", a Dict of robot
features, object rows and a mask, and obs_mode="entities", whose rows add the gripper, the table and
the floor, in the single and the vector environment."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from gymnasium.utils.env_checker import check_env

import blockpuzzle


def test_objects_mode_is_a_dict_that_gymnasium_accepts():
    env = gym.make("BlockPuzzle/BlocksChoose-v0", obs_mode="objects")
    space = env.observation_space
    assert isinstance(space, spaces.Dict) and set(space.spaces) == {"robot", "objects", "mask"}
    assert space["objects"].shape == (3, 22) and space["robot"].shape == (10,) and space["mask"].shape == (3,)
    layout = env.unwrapped.obs_layout
    assert layout["mode"] == "objects" and len(layout["names"]) == layout["dim"] == 10 + 3 * 22 + 3
    assert layout["names"][10] == "object0/pos.x" and layout["names"][29] == "object0/size.x"
    assert layout["names"][-1] == "mask/2"
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_objects_mode_holds_the_flat_observation_sizes_and_a_full_mask():
    flat = gym.make("BlockPuzzle/BlocksChoose-v0")
    objects = gym.make("BlockPuzzle/BlocksChoose-v0", obs_mode="objects")
    a, _ = flat.reset(seed=4)
    b, _ = objects.reset(seed=4)
    for t in range(5):
        assert np.array_equal(b["robot"], a[:10])
        assert np.array_equal(b["objects"][:, :19].reshape(-1), a[10:])
        assert np.array_equal(b["objects"][:, 19:], np.full((3, 3), 0.025, np.float32))
        assert np.array_equal(b["mask"], np.ones(3, np.float32))
        action = np.random.default_rng(t).uniform(-1, 1, 4).astype(np.float32)
        a, *_ = flat.step(action)
        b, *_ = objects.step(action)


def test_vector_objects_mode_batches_the_dict():
    envs = blockpuzzle.make_vec("BlocksChoose-v0", num_envs=3, threads=2, obs_mode="objects")
    flat = blockpuzzle.make_vec("BlocksChoose-v0", num_envs=3, threads=2)
    assert envs.single_observation_space["objects"].shape == (3, 22)
    assert envs.observation_space["objects"].shape == (3, 3, 22)
    obs, _ = envs.reset(seed=1)
    ref, _ = flat.reset(seed=1)
    actions = np.zeros((3, 4), np.float32)
    for _ in range(3):
        assert obs["objects"].shape == (3, 3, 22) and obs["mask"].shape == (3, 3)
        assert np.array_equal(obs["objects"][:, :, :19].reshape(3, -1), ref[:, 10:])
        assert envs.observation_space.contains(obs)
        obs, *_ = envs.step(actions)
        ref, *_ = flat.step(actions)
    envs.close()
    flat.close()


def test_an_unknown_mode_is_refused_naming_the_known_ones():
    with pytest.raises(ValueError, match="flat, objects, entities"):
        gym.make("BlockPuzzle/BlocksTouch-v0", obs_mode="pixels")
    with pytest.raises(ValueError, match="flat, objects, entities"):
        blockpuzzle.make_vec("BlocksTouch-v0", num_envs=2, obs_mode="set")


def test_variable_counts_mask_absent_objects_and_pass_the_checker():
    env = gym.make("BlockPuzzle/BlocksChooseN-v0", obs_mode="objects")
    assert env.observation_space["objects"].shape == (6, 22)
    check_env(env.unwrapped, skip_render_check=True)
    counts = set()
    for seed in range(30):
        obs, _ = env.reset(seed=seed)
        mask = obs["mask"]
        # blue and green always; then the greys present form a prefix of their four slots
        assert mask[0] == mask[1] == 1.0
        n = int(mask[2:].sum())
        assert np.array_equal(mask[2:], np.array([1.0] * n + [0.0] * (4 - n), np.float32))
        assert not obs["objects"][2 + n:].any(), "absent rows are zero"
        assert (obs["objects"][:2 + n, 15:19].sum(axis=1) == 1).all(), "present rows carry a colour"
        counts.add(n)
    assert counts == {0, 1, 2, 3, 4}
    env.close()


def test_variable_counts_in_the_vector_env_do_not_depend_on_num_envs_or_threads():
    def run(num_envs, threads):
        envs = blockpuzzle.make_vec("BlocksChooseN-v0", num_envs=num_envs, threads=threads, obs_mode="objects")
        obs, _ = envs.reset(seed=[20 + i for i in range(num_envs)])
        out = [obs["mask"][1].copy(), obs["objects"][1].copy()]
        for t in range(60):  # past one episode end: the autoreset draws a new count
            actions = np.tile(np.float32([np.sin(t), np.cos(t), -0.3, 0.0]), (num_envs, 1))
            obs, reward, term, trunc, _ = envs.step(actions)
            out += [obs["mask"][1].copy(), obs["objects"][1].copy(), np.float32([reward[1], term[1], trunc[1]])]
        envs.close()
        return np.concatenate([o.ravel() for o in out])

    a = run(2, 1)
    assert np.array_equal(a, run(2, 2)) and np.array_equal(a, run(5, 3))


def test_flatten_observation_gives_the_documented_order():
    """gymnasium's FlattenObservation flattens a Dict in its space's key order: robot | objects | mask,
    the native vector a set policy reads, for one environment and for a batch."""
    from gymnasium.spaces import flatten
    from gymnasium.wrappers import FlattenObservation
    from gymnasium.vector.utils import batch_space

    env = gym.make("BlockPuzzle/BlocksChoose-v0", obs_mode="objects")
    assert list(env.observation_space.spaces) == ["robot", "objects", "mask"]
    assert list(batch_space(env.observation_space, 3).spaces) == ["robot", "objects", "mask"]
    obs, _ = env.reset(seed=0)
    flat = FlattenObservation(gym.make("BlockPuzzle/BlocksChoose-v0", obs_mode="objects"))
    vec, _ = flat.reset(seed=0)
    want = np.concatenate([obs["robot"], obs["objects"].reshape(-1), obs["mask"]])
    np.testing.assert_array_equal(vec, want)
    np.testing.assert_array_equal(flatten(env.observation_space, obs), want)


def test_every_mode_of_the_core_has_a_python_layout():
    # A mode added to the Rust core (ObsMode::ALL) fails here until blockpuzzle.observation lays it out.
    assert blockpuzzle.observation.OBS_MODES == tuple(blockpuzzle._native.obs_modes())
    assert set(blockpuzzle.observation.OBS_MODES) == set(blockpuzzle.observation.LAID_OUT)
    for mode in blockpuzzle.observation.OBS_MODES:
        env = gym.make("BlockPuzzle/BlocksChoose-v0", obs_mode=mode)
        obs, _ = env.reset(seed=0)
        assert env.observation_space.contains(obs), mode
        assert env.unwrapped.obs_layout["mask"] == (mode != "flat")
    with pytest.raises(ValueError, match="unknown obs_mode 'pixels'"):
        gym.make("BlockPuzzle/BlocksChoose-v0", obs_mode="pixels")


def test_entities_mode_shows_the_gripper_table_and_floor_and_passes_the_checkers():
    # BlocksAvoid-v0: grey gripper, grey table, red floor; blue, green and 1-3 reds (five block slots).
    env = gym.make("BlockPuzzle/BlocksAvoid-v0", obs_mode="entities")
    space = env.observation_space
    assert list(space.spaces) == ["robot", "entities", "mask"]
    assert space["entities"].shape == (8, 26) and space["mask"].shape == (8,)
    layout = env.unwrapped.obs_layout
    assert (layout["rows"], layout["max_objects"], layout["rows_key"]) == (8, 5, "entities")
    assert layout["names"][10 + 5 * 26] == "gripper/pos.x" and layout["names"][-3:] == ["mask/gripper", "mask/table", "mask/floor"]
    check_env(env.unwrapped, skip_render_check=True)
    obs, _ = env.reset(seed=3)
    rows, mask = obs["entities"], obs["mask"]
    colour, kind = rows[:, 15:19].argmax(axis=1), rows[:, 22:26].argmax(axis=1)
    present = mask[:5] == 1
    assert present[:3].all() and list(kind[:5][present]) == [3] * int(present.sum()), "present blocks are blocks"
    assert list(colour[:3]) == [1, 2, 0], "blue, green, a red block"
    assert not rows[:5][~present].any(), "absent blocks are zero rows"
    assert list(kind[5:]) == [0, 1, 2] and list(colour[5:]) == [3, 3, 0], "grey gripper and table, red floor"
    assert list(mask[5:]) == [1, 1, 1]
    np.testing.assert_array_equal(rows[5, :3], obs["robot"][:3])  # the gripper row is at the grip
    assert rows[6, 2] == pytest.approx(0.4, abs=1e-6) and rows[6, 21] == pytest.approx(0.2)  # the table's top, half height
    env.close()
    # Without a coloured floor its row is zero and masked.
    touch = gym.make("BlockPuzzle/BlocksTouch-v0", obs_mode="entities")
    obs, _ = touch.reset(seed=0)
    assert list(obs["mask"]) == [1, 1, 1, 1, 0] and not obs["entities"][4].any()
    touch.close()
    envs = blockpuzzle.make_vec("BlocksAvoid-v0", num_envs=2, threads=2, obs_mode="entities")
    assert envs.observation_space["entities"].shape == (2, 8, 26)
    obs, _ = envs.reset(seed=0)
    for _ in range(3):
        assert envs.observation_space.contains(obs)
        obs, *_ = envs.step(np.zeros((2, 4), np.float32))
    envs.close()
