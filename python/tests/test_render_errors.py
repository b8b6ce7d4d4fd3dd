"""Rendering errors say what to install, in apt terms (and that pip has no package for it), for each
step of EGL that can fail: the message builder for every step, then the real failures this machine
can be made to show (no Mesa EGL vendor, no Mesa drivers, rendering switched off)."""

import os
import subprocess
import sys

import gymnasium as gym
import pytest

import blockpuzzle  # noqa: F401  (registers the ids)
from blockpuzzle import _native

APT = "apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri"

RENDER = """
import gymnasium as gym, blockpuzzle
env = gym.make("BlockPuzzle/BlocksTouch-v0", render_mode="rgb_array", width=16, height=16)
env.reset(seed=0)
try:
    print("ok", env.render().shape)
except RuntimeError as e:
    print("RuntimeError", e)
"""


@pytest.mark.parametrize(("call", "reason", "missing"), [
    (None, "libEGL.so.1: cannot open shared object file: No such file or directory", "libegl1"),
    ("eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA)", "One or more argument values are invalid",
     "libegl-mesa0"),
    ("eglInitialize", "EGL is not initialized", "libgl1-mesa-dri"),
    ("eglCreateContext (EGL_KHR_no_config_context)", "Bad match", "libgl1-mesa-dri"),
])
def test_each_egl_failure_names_the_missing_package_and_the_apt_line(call, reason, missing):
    msg = _native._render_error_message(call, reason)
    assert f"the missing package is most likely {missing}" in msg, msg
    assert APT in msg and "dnf install" in msg and "no pip package provides" in msg, msg
    assert reason in msg and (call is None or f"{call} failed" in msg), msg
    assert "make setup" not in msg


def test_rendering_switched_off_says_which_variable_to_unset(monkeypatch):
    env = gym.make("BlockPuzzle/BlocksTouch-v0", render_mode="rgb_array", width=16, height=16)
    env.reset(seed=0)
    # This thread renders first: the switch holds for a thread that has rendered before (its OpenGL
    # context is kept for the next renderer).
    assert env.render().shape == (16, 16, 3)
    env.close()
    monkeypatch.setenv("BLOCKPUZZLE_NO_EGL", "1")
    env = gym.make("BlockPuzzle/BlocksTouch-v0", render_mode="rgb_array", width=16, height=16)
    env.reset(seed=0)
    with pytest.raises(RuntimeError, match="switched off by the environment variable BLOCKPUZZLE_NO_EGL; unset it"):
        env.render()
    env.close()


def render_in_a_process(**env):
    out = subprocess.run([sys.executable, "-c", RENDER], capture_output=True, text=True,
                         env={**os.environ, **env}, timeout=120)
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


@pytest.mark.parametrize(("variable", "missing"), [
    ("__EGL_VENDOR_LIBRARY_DIRS", "libegl-mesa0"),  # glvnd finds no vendor: as without libegl-mesa0
    ("LIBGL_DRIVERS_PATH", "libgl1-mesa-dri"),      # Mesa finds no driver: as without libgl1-mesa-dri
])
def test_a_real_missing_mesa_piece_names_its_package(variable, missing):
    if not render_in_a_process().startswith("ok"):
        pytest.skip("this machine does not render (no EGL): the message builder's test covers it")
    got = render_in_a_process(**{variable: "/nonexistent"})
    assert got.startswith("RuntimeError render(): headless rendering needs EGL with Mesa"), got
    assert f"most likely {missing}" in got and APT in got, got
