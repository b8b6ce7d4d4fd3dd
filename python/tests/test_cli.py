"""The package's command line (``blockpuzzle`` and ``python -m blockpuzzle``): the Rust command
line's commands that need no libtorch, on the package's engine, with the package's zoo."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

import blockpuzzle
from blockpuzzle import zoo

SCRIPT = Path(sys.executable).parent / "blockpuzzle"


def run(*args, cwd=None):
    return subprocess.run([str(SCRIPT), *args], capture_output=True, text=True, cwd=cwd)


def test_the_command_and_the_module_list_the_environments():
    a = run("envs")
    b = subprocess.run([sys.executable, "-m", "blockpuzzle", "envs"], capture_output=True, text=True)
    assert a.returncode == b.returncode == 0, a.stderr + b.stderr
    assert a.stdout == b.stdout
    assert [line.split()[0] for line in a.stdout.splitlines()] == blockpuzzle.env_ids()
    info = run("info").stdout
    assert f"MuJoCo {blockpuzzle.MUJOCO_PIN}" in info and f"blockpuzzle {blockpuzzle.__version__}" in info


def test_help_usage_errors_and_training_commands_say_what_to_do():
    h = run("--help")
    assert h.returncode == 0 and "rollout" in h.stdout
    assert not any(line.strip().startswith(("train ", "bench ")) for line in h.stdout.splitlines()), h.stdout
    bad = run("eval", "--suite", "layout", "--no-such-flag")
    assert bad.returncode == 2 and "--no-such-flag" in bad.stderr
    for args in (["train", "--env", "BlocksTouch-v0"], ["zoo", "export", "--name", "x"]):
        t = run(*args)
        assert t.returncode == 2 and "Rust command line" in t.stderr and "cargo run --release" in t.stderr, t.stderr
    # The browser app is the package's too (docs/serve.md).
    assert any(line.strip().startswith("serve ") for line in h.stdout.splitlines()), h.stdout
    # The paper's table needs no libtorch: the package's command has it.
    table = run("table", "--help")
    assert table.returncode == 0 and "--zoo" in table.stdout, table.stderr
    missing = run("eval", "--suite", "no-such-suite", "--baseline", "obs-hash")
    assert missing.returncode == 1 and "unknown suite" in missing.stderr and "Traceback" not in missing.stderr


def test_zoo_list_shows_the_packages_entries():
    out = run("zoo", "list")
    assert out.returncode == 0, out.stderr
    for name in zoo.names():
        assert name in out.stdout


def test_a_shortened_suite_evaluation_of_a_zoo_policy_equals_evaluate(tmp_path):
    out = tmp_path / "short.json"
    r = run("eval", "--suite", "layout", "--checkpoint", "BlocksTouch-v0-ddpg", "--episodes-per-row", "2",
            "--threads", "2", "--out", str(out))
    assert r.returncode == 0, r.stderr
    cli = json.loads(out.read_text())
    assert cli["suite"]["episodes_per_row"] == 2 and cli["provenance"]["harness"] == "cli"
    assert cli["provenance"]["mujoco"] == blockpuzzle.MUJOCO_PIN
    py = blockpuzzle.evaluate(zoo.load("BlocksTouch-v0-ddpg"), suite="layout", episodes=2, threads=2, progress=False)
    assert py["splits"] == cli["splits"] and py["suite"] == cli["suite"]
    # The 2-block policy plays the 3-block rows as the CLI does: grey blocks removed from its view.
    assert any(r["evaluation"]["grey_blind"] for s in py["splits"] for r in s["rows"] if r["evaluation"])
    assert (tmp_path / "short.md").is_file()


def test_rollout_writes_a_dump_and_render_draws_it(tmp_path):
    dump = tmp_path / "run.jsonl"
    r = run("rollout", "--env", "BlocksTouch-v0", "--policy", "scripted", "--episodes", "2", "--out", str(dump))
    assert r.returncode == 0, r.stderr
    episodes = [json.loads(line) for line in dump.read_text().splitlines()]
    assert len(episodes) == 2 and episodes[0]["env_id"] == "BlocksTouch-v0"
    png = tmp_path / "strip.png"
    r = run("render", "--traj", str(dump), "--filmstrip", "3", "--width", "64", "--height", "64", "--out", str(png))
    if r.returncode != 0 and "EGL" in r.stderr:
        pytest.skip(f"no EGL on this machine: {r.stderr.strip()}")
    assert r.returncode == 0, r.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
