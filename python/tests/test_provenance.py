"""One number per policy and engine: a zoo policy gives the command line's outcome counts on the
built-in suites (the CLI built on the package's MuJoCo), whichever harness plays it, and every
result says what made it."""

import json
import importlib.metadata
import subprocess

import gymnasium as gym
import numpy as np
import pytest

import blockpuzzle
from blockpuzzle import zoo
from test_evaluate import cli_binary


def cli_suite(tmp_path, entry: zoo.ZooPolicy, suite: str) -> dict:
    binary = cli_binary()
    info = subprocess.run([str(binary), "info"], capture_output=True, text=True, check=True).stdout
    assert f"MuJoCo {blockpuzzle.mujoco_version()}" in info, f"{binary} runs another MuJoCo than the package:\n{info}"
    out = tmp_path / f"{entry.name}.{suite}.json"
    subprocess.run([str(binary), "eval", "--suite", suite, "--checkpoint", str(entry.path), "--threads", "2",
                    "--out", str(out)], check=True, capture_output=True)
    return json.loads(out.read_text())


def counts(result: dict) -> list:
    return [(r["task"], r["distribution"], r["evaluation"] and r["evaluation"]["outcomes"])
            for s in result["splits"] for r in s["rows"]]


@pytest.mark.parametrize("name,suite", [("BlocksChoose-v0-ddpg-ours", "layout"), ("BlocksChoose-v0-ddpg-set", "count")])
def test_a_zoo_policy_has_the_clis_outcome_counts_on_a_built_in_suite(tmp_path, name, suite):
    policy = zoo.load(name)
    cli = cli_suite(tmp_path, policy, suite)
    py = blockpuzzle.evaluate(policy, suite=suite, threads=2)
    assert counts(py) == counts(cli) and py["splits"] == cli["splits"]
    assert all(r["evaluation"] for s in cli["splits"] for r in s["rows"]), "no row skipped: not a vacuous comparison"
    p, c = py["provenance"], cli["provenance"]
    assert (p["harness"], c["harness"]) == ("python", "cli")
    assert p["mujoco"] == c["mujoco"] == blockpuzzle.mujoco_version()
    assert p["policy"] == {"name": name, "sha256": policy.native.sha256} and c["policy"]["sha256"] == policy.native.sha256
    assert p["suite"] == c["suite"] == py["suite"]
    if suite == "layout":
        # Python's own episode loop, the policy acting through the extension: the same counts again.
        loop = blockpuzzle.evaluate(lambda obs: policy(obs), suite=suite, num_envs=8, threads=2, name="loop")
        assert counts(loop) == counts(cli)


def test_the_numpy_reference_acts_as_the_native_forward_pass_to_a_tolerance(tmp_path):
    for name in zoo.names():
        native, reference = zoo.load(name), zoo.load(name, native=False)
        assert native.native is not None and reference.native is None
        if native.task_id in blockpuzzle.env_ids():
            env = gym.make(f"BlockPuzzle/{native.task_id}", obs_mode=native.obs_mode)
        else:  # a generated task (a stream's first): from the text the entry records
            task = tmp_path / f"{native.task_id}.toml"
            task.write_text(native.meta["task"]["toml"])
            env = blockpuzzle.make_task(task, obs_mode=native.obs_mode)
        rows = []
        for seed in range(4):
            obs, _ = env.reset(seed=seed)
            rows.append(obs)
        batch = {k: np.stack([r[k] for r in rows]) for k in rows[0]} if isinstance(rows[0], dict) else np.stack(rows)
        a, b = native(batch), reference(batch)
        assert a.shape == b.shape == (4, 4), name
        assert np.max(np.abs(a - b)) < 1e-4, name
        # The native pass is the one recorded at export: its probes are exact.
        for probe in native.meta["probes"]:
            assert np.array_equal(native(np.asarray(probe["obs"], np.float32)),
                                  np.asarray(probe["action"], np.float32)), name


def test_a_zoo_policy_refuses_another_observation_mode_and_wrong_sizes():
    policy = zoo.load("BlocksChoose-v0-ddpg-ours")
    with pytest.raises(ValueError, match="reads 'flat' observations"):
        blockpuzzle.evaluate(policy, suite="layout", obs_mode="objects")
    with pytest.raises(ValueError, match=r"reads flat observations of shape \(67,\); these have shape \(5,\)"):
        policy(np.zeros((2, 5), np.float32))


def test_the_build_says_what_it_is():
    info = blockpuzzle._native.build_info()
    assert info["mujoco"] == blockpuzzle.mujoco_version() == blockpuzzle.MUJOCO_PIN
    assert info["blockpuzzle"] == blockpuzzle.__version__ == importlib.metadata.version("blockpuzzle")
