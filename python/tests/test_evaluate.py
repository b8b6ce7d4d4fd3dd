"""blockpuzzle.evaluate: a callable policy on an evaluation suite, with the CLI's definitions."""

import json
import os
import subprocess
import sys
from pathlib import Path

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
    train, test = a["splits"][0]["rows"][0]["evaluation"], a["splits"][1]["rows"][0]["evaluation"]
    env = gym.make("BlockPuzzle/BlocksTouch-v0")
    wins, fails = explicit("BlocksTouch-v0", 3000000, 7, {"level": env.unwrapped.max_level})
    assert (train["successes"], round(a["splits"][0]["rows"][0]["failure_rate"] * 7)) == (wins, fails)
    wins, _ = explicit("BlocksChoose-v0", 1000000, 5, {"challenge": True, "level": 10})
    assert test["successes"] == wins
    assert a["score"] == test["success_rate"] and a["gap"] == train["success_rate"] - test["success_rate"]
    lo, hi = test["ci95"]
    assert 0 <= lo <= test["success_rate"] <= hi <= 1
    assert len(a["suite"]["sha256"]) == 64 and a["suite"]["name"] == "tiny"
    p = a["provenance"]
    assert (p["harness"], p["mujoco"], p["policy"], p["suite"]) == (
        "python", blockpuzzle.mujoco_version(), {"name": "policy", "sha256": None}, a["suite"])
    assert p["blockpuzzle"] == blockpuzzle.__version__
    assert all(r["task_sha256"].startswith("sha256:") for sp in a["splits"] for r in sp["rows"])


def test_built_in_suites_and_bad_suites():
    assert blockpuzzle._native.suite("layout")["splits"][1][0] == "test"
    with pytest.raises(ValueError, match="unknown suite"):
        blockpuzzle.evaluate(policy, suite="nonsense")
    with pytest.raises(FileNotFoundError):
        blockpuzzle.evaluate(policy, suite="/nonexistent/suite.toml")
    assert blockpuzzle.evaluation.wilson95(50, 100) == pytest.approx((0.4038, 0.5962), abs=1e-3)


def test_obs_hash_is_pinned_to_the_rust_bits():
    # The same bits src/policy/mod.rs pins for ObsHashPolicy.
    a = blockpuzzle.policies.obs_hash(np.array([[0.5, 1.0, -2.0], [0.0, 0.0, 0.0]], np.float32))
    assert [int(x) for x in a.view(np.uint32).ravel()] == [
        0x3E9CC9BC, 0xBD467480, 0x3EB28CC8, 0xBF50D8E4, 0xBF2D9F90, 0x3F5AFB30, 0x3F49A61C, 0x3ECBABCC]
    # A batch of Dict observations: each row as if hashed alone.
    envs = blockpuzzle.make_vec("BlocksChooseN-v0", num_envs=3, obs_mode="objects")
    d, _ = envs.reset(seed=[4, 5, 6])
    batch = blockpuzzle.policies.obs_hash(d)
    rows = [blockpuzzle.policies.obs_hash({k: v[i] for k, v in d.items()}) for i in range(3)]
    assert np.array_equal(batch, np.stack(rows)) and len({tuple(r) for r in batch.tolist()}) == 3


def cli_binary() -> Path:
    """The command line on the package's engine (MuJoCo 3.11.0): ``$BLOCKPUZZLE_BIN`` (e.g. the Rust
    binary built with ``--features train,mujoco3``), else the package's own ``blockpuzzle`` command
    (the same Rust command line, its commands that need no libtorch)."""
    given = os.environ.get("BLOCKPUZZLE_BIN")
    binary = Path(given) if given else Path(sys.executable).parent / "blockpuzzle"
    if not binary.is_file():
        pytest.fail(f"no blockpuzzle command at {binary}: install the package (its `blockpuzzle` script), or point "
                    "$BLOCKPUZZLE_BIN at a command line built on MuJoCo 3.11.0")
    return binary


PARITY = """
version = 1
name = "parity"
summary = "Episodes of tasks with and without counts where random actions touch, succeed and fail."
[[splits.train]]
task = "BlocksTouch-v0"
seed = 3000000
level = 0
episodes = 10
[[splits.test]]
task = "BlocksChooseN-v0"
seed = 1000000
level = 0
episodes = 10
[[splits.test]]
task = "BlocksAvoid-v0"
seed = 1000000
level = 0
episodes = 10
[[splits.test]]
task = "ReachAvoid-v0"
seed = 1000000
episodes = 10
"""


def test_evaluate_equals_the_cli_on_the_same_seeds(tmp_path):
    binary = cli_binary()
    info = subprocess.run([str(binary), "info"], capture_output=True, text=True, check=True).stdout
    assert f"MuJoCo {blockpuzzle.mujoco_version()}" in info, f"{binary} runs another MuJoCo than the package:\n{info}"
    suite = tmp_path / "parity.toml"
    suite.write_text(PARITY)
    out = tmp_path / "cli.json"
    subprocess.run([str(binary), "eval", "--suite", str(suite), "--baseline", "obs-hash", "--threads", "2",
                    "--out", str(out)], check=True, capture_output=True)
    cli = json.loads(out.read_text())
    py = blockpuzzle.evaluate(blockpuzzle.policies.obs_hash, suite=str(suite), num_envs=4, threads=2)
    assert py["suite"] == cli["suite"]
    assert (py["score"], py["gap"]) == (cli["score"], cli["gap"])
    # Row for row, field for field: the loop here keeps the CLI's definitions (and its JSON).
    assert py["splits"] == cli["splits"]
    assert {k: py["provenance"][k] for k in ("mujoco", "blockpuzzle", "suite")} == {
        k: cli["provenance"][k] for k in ("mujoco", "blockpuzzle", "suite")}
    # Not a vacuous comparison: with these seeds the hash policy succeeds, fails and times out.
    total = {k: sum(r["evaluation"]["outcomes"][k] for s in cli["splits"] for r in s["rows"]) for k in
             ("success", "failure", "no_contact", "timeout")}
    assert all(v > 0 for v in total.values()), total


def test_outcomes_follow_the_cli_order():
    from blockpuzzle.evaluation import _outcome
    # rule objects: gripper, table, two blocks (blue, grey); grey gripper and table, no floor
    surfaces = [3, 3]
    m = np.zeros((4, 4), np.int64)
    args = dict(surfaces=surfaces, z0=np.array([0.425, 0.425]), colour_end=np.array([1, 3]),
                z_end=np.array([0.425, 0.425]))
    assert _outcome(False, False, False, m, **args) == "no_contact"
    m[0, 2] = m[2, 0] = 1  # the gripper touched blue
    assert _outcome(False, False, False, m, **args) == "timeout"
    m[2, 3] = m[3, 2] = 2  # blue touches grey
    assert _outcome(False, False, False, m, **args) == "blue_met_grey"
    assert _outcome(False, False, False, m, **{**args, "z_end": np.array([0.02, 0.425])}) == "off_table"
    assert _outcome(False, False, True, m, **args) == "unstable"
    assert _outcome(False, True, True, m, **args) == "failure"
    assert _outcome(True, True, True, m, **args) == "success"
    # The classifier is the CLI's own: an absent slot (-1) is no block colour, a bad matrix is refused.
    assert _outcome(False, False, False, m, **{**args, "colour_end": np.array([1, -1])}) == "timeout"
    with pytest.raises(ValueError, match="contact matrix"):
        _outcome(False, False, False, np.zeros((3, 3)), **args)


def test_a_shortened_evaluation_says_so_and_reports_each_row(tmp_path, capsys):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    r = blockpuzzle.evaluate(policy, suite=str(path), num_envs=2, episodes=3)
    assert r["suite"]["episodes_per_row"] == 3 and r["provenance"]["suite"] == r["suite"]
    assert [row["evaluation"]["episodes"] for s in r["splits"] for row in s["rows"]] == [3, 3]
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 2 and lines[0].startswith(f"[{path} (first 3 episodes per row)] 1/2 train BlocksTouch-v0")
    # The first episodes of the full evaluation, seed for seed.
    full = blockpuzzle.evaluate(policy, suite=str(path), num_envs=2, progress=False)
    assert "episodes_per_row" not in full["suite"] and capsys.readouterr().err == ""
    short = TINY.replace("episodes = 7", "episodes = 3").replace("episodes = 5", "episodes = 3")
    (tmp_path / "short.toml").write_text(short)
    same = blockpuzzle.evaluate(policy, suite=str(tmp_path / "short.toml"), num_envs=2, progress=False)
    assert [s["rows"][0]["evaluation"]["outcomes"] for s in same["splits"]] == [
        s["rows"][0]["evaluation"]["outcomes"] for s in r["splits"]]
    with pytest.raises(ValueError, match="at least 1 episode"):
        blockpuzzle.evaluate(policy, suite=str(path), episodes=0)
    # A zoo policy, by the CLI's evaluator: the same marks and one line per row.
    z = blockpuzzle.evaluate(blockpuzzle.zoo.load("BlocksTouch-v0-ddpg"), suite=str(path), episodes=2)
    assert z["suite"]["episodes_per_row"] == 2 and len(capsys.readouterr().err.splitlines()) == 2


def test_a_policy_that_does_not_fit_the_observation_gets_a_clear_error(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    touch = blockpuzzle.zoo.load("BlocksTouch-v0-ddpg")  # 48 flat values; the test row has 67
    with pytest.raises(ValueError, match=r"BlocksChoose-v0's observations .*shape \(5, 67\).*reads flat observations "
                                         r"of shape \(48,\); these have shape \(67,\)"):
        blockpuzzle.evaluate(lambda obs: touch(obs), suite=str(path), num_envs=5, progress=False)
    env = gym.make("BlockPuzzle/BlocksChoose-v0")
    obs, _ = env.reset(seed=0)
    for act in (touch, lambda o: touch.act_numpy(o)):
        with pytest.raises(ValueError, match=r"\(48,\).*\(67,\).*gym.make\('BlockPuzzle/BlocksTouch-v0'"):
            act(obs)
    # A callable carrying its observation mode gets it.
    seen = []

    def objects_policy(obs):
        seen.append(type(obs))
        return np.zeros((len(obs["robot"]), 4), np.float32)

    objects_policy.obs_mode = "objects"
    blockpuzzle.evaluate(objects_policy, suite=str(path), episodes=1, progress=False)
    assert seen and all(t is dict for t in seen)


def test_an_error_in_the_row_callback_stops_the_clis_evaluator_and_is_raised():
    calls = []

    def stop(split, row, done, total):
        calls.append((split, row["task"], done, total))
        raise KeyboardInterrupt

    path = str(blockpuzzle.zoo.load("BlocksTouch-v0-ddpg").path)
    with pytest.raises(KeyboardInterrupt):
        blockpuzzle._native.evaluate_saved(path, "BlocksTouch-v0-ddpg", "layout", 2, 1, stop)
    assert len(calls) == 1 and calls[0][0] == "train" and calls[0][2] == 1


def test_what_is_not_a_policy_is_named_and_an_error_in_the_policy_names_its_row(tmp_path):
    # Issue 74: a zoo name, None or a model object got "set obs_mode"; a policy's own error named no row.
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    for given, words in [("BlocksTouch-v0-ddpg", r"blockpuzzle.zoo.load\('BlocksTouch-v0-ddpg'\)"),
                         (None, "None; pass the policy itself"),
                         (type("PPO", (), {"predict": lambda self, o: o})(), r"\.predict.*deterministic=True")]:
        with pytest.raises(TypeError, match="takes a callable policy.*" + words):
            blockpuzzle.evaluate(given, suite=str(path), progress=False)

    def broken(obs):
        raise ZeroDivisionError("oops")

    with pytest.raises(ZeroDivisionError, match="oops") as e:
        blockpuzzle.evaluate(broken, suite=str(path), episodes=1, progress=False)
    assert any("suite row BlocksTouch-v0" in n for n in getattr(e.value, "__notes__", [])), e.value


def test_obs_hash_reads_the_entities_observation_as_its_flat_vector():
    # Issue 74: obs_hash failed on the entities Dict.
    d, _ = blockpuzzle.make_vec("BlocksChoose-v0", num_envs=2, obs_mode="entities").reset(seed=[1, 2])
    a = blockpuzzle.policies.obs_hash(d)
    assert a.shape == (2, 4) and np.all(np.abs(a) <= 1)
    joined = np.concatenate([d["robot"], d["entities"].reshape(2, -1), d["mask"]], axis=1)
    assert np.array_equal(a, blockpuzzle.policies.obs_hash(joined))
    with pytest.raises(ValueError, match="holds 'robot', 'objects' or 'entities', and 'mask'"):
        blockpuzzle.policies.obs_hash({"robot": d["robot"]})
