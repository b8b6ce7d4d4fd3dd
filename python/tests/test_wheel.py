"""The wheel and sdist as released: the installed wheel's tags are the manylinux_2_28 baseline
(scripts/build_wheel.sh builds it from the sdist with zig and fails unless `auditwheel show`
agrees), and the sdist beside it holds what a source build needs and nothing of the results."""

import importlib.metadata
import os
import tarfile
from pathlib import Path

import pytest


def test_the_installed_wheel_is_the_abi3_manylinux_2_28_one():
    wheel = importlib.metadata.distribution("blockpuzzle").read_text("WHEEL")
    tags = [line.split(":", 1)[1].strip() for line in wheel.splitlines() if line.startswith("Tag:")]
    assert tags == ["cp310-abi3-manylinux_2_28_x86_64"], wheel


def test_the_sdist_holds_the_sources_and_no_results():
    root = os.environ.get("BLOCKPUZZLE_WHEEL_TEST")
    if not root:
        pytest.skip("run by scripts/python_check.sh, which names the checkout whose target/wheelhouse has the sdist")
    (sdist,) = (Path(root) / "target" / "wheelhouse").glob("blockpuzzle-*.tar.gz")
    with tarfile.open(sdist) as t:
        names = {n.split("/", 1)[1] for n in t.getnames() if "/" in n}
    for need in ("pyproject.toml", "python/Cargo.toml", "python/src/lib.rs", "Cargo.toml", "src/lib.rs",
                 "src/cli/mod.rs", "mujoco-sys/build.rs", "tasks/BlocksTouch-v0.toml", "suites/layout.toml",
                 "models/scene.xml", "blockpuzzle/__init__.py", "blockpuzzle/zoo_files/BlocksTouch-v0-ddpg.json"):
        assert need in names, need
    assert not [n for n in names if n.startswith(("results/", "tests/", "docs/", "models/gymnasium_robotics"))]


def test_the_metadata_names_the_author_and_no_address_that_does_not_exist():
    tomllib = pytest.importorskip("tomllib")
    meta = importlib.metadata.metadata("blockpuzzle")
    project = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())["project"]
    assert meta["Author"] == project["authors"][0]["name"] != "", meta["Author"]
    assert meta["Summary"] and meta["License"] == "MIT"
    # No public address exists yet (no remote, none in Cargo.toml or the docs): none is invented, and
    # any one added must be an https URL.
    urls = meta.get_all("Project-URL") or []
    assert all(u.split(", ", 1)[1].startswith("https://") for u in urls), urls
    assert bool(urls) == bool(project.get("urls")), urls
