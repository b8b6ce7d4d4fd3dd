"""The zoo in the package: every entry loads with numpy alone and reproduces its recorded actions;
a zoo policy scores on seeded episodes what the command line (built on the same MuJoCo) scores."""

import json
import os
import pathlib
import subprocess

import gymnasium as gym
import numpy as np
import pytest

import blockpuzzle
from blockpuzzle import zoo

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_the_package_carries_the_zoo_and_each_entry_reproduces_its_probes():
    names = zoo.names()
    assert "BlocksTouch-v0-ddpg" in names and len(names) >= 10
    for name in names:
        policy = zoo.load(name)
        assert policy.name == name and policy.evaluations, name
        assert policy.probe_error() < 1e-5, name
    if os.environ.get("BLOCKPUZZLE_WHEEL_TEST"):  # the installed package's copy, not the checkout's
        assert not zoo.FOLDER.resolve().is_relative_to(os.environ["BLOCKPUZZLE_WHEEL_TEST"])


def test_a_zoo_policy_acts_on_single_and_batched_observations():
    policy = zoo.load("BlocksTouch-v0-ddpg")
    env = gym.make(f"BlockPuzzle/{policy.task_id}", obs_mode=policy.obs_mode)
    obs, _ = env.reset(seed=0)
    a = policy(obs)
    assert a.shape == (4,) and np.all(np.abs(a) <= 1)
    batch = policy(np.stack([obs, obs]))
    assert batch.shape == (2, 4) and np.array_equal(batch[0], a)
    with pytest.raises(KeyError, match="no zoo entry 'NoSuch'"):
        zoo.load("NoSuch")


def test_a_zoo_policy_scores_as_the_cli_on_100_seeded_episodes(tmp_path):
    from test_evaluate import cli_binary

    binary = cli_binary()
    info = subprocess.run([str(binary), "info"], capture_output=True, text=True, check=True).stdout
    assert f"MuJoCo {blockpuzzle.mujoco_version()}" in info, f"{binary} runs another MuJoCo than the package:\n{info}"
    name = "BlocksTouch-v0-ddpg"
    suite = tmp_path / "zoo.toml"
    suite.write_text(
        'version = 1\nname = "zoo-parity"\nsummary = "100 seeded episodes of BlocksTouch-v0 at the top level."\n'
        '[[splits.train]]\ntask = "BlocksTouch-v0"\nseed = 3000000\nepisodes = 1\n'
        '[[splits.test]]\ntask = "BlocksTouch-v0"\nseed = 1000000\nepisodes = 100\n')
    policy = zoo.load(name)
    py = blockpuzzle.evaluate(policy, suite=str(suite), obs_mode=policy.obs_mode)
    out = tmp_path / "cli.json"
    subprocess.run([str(binary), "eval", "--suite", str(suite), "--checkpoint", name, "--out", str(out)],
                   check=True, capture_output=True)
    cli = json.loads(out.read_text())
    py_row, cli_row = py["splits"][1]["rows"][0], cli["splits"][1]["rows"][0]
    assert cli_row["evaluation"]["episodes"] == 100
    # A zoo policy is evaluated by the CLI's own code: the same row, field for field.
    assert py_row == cli_row
    assert py_row["evaluation"]["success_rate"] >= 0.8
    assert py["provenance"]["policy"]["sha256"] == cli["provenance"]["policy"]["sha256"] == policy.native.sha256
