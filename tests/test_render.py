"""Headless rendering: works with EGL where it exists, fails with a clear message elsewhere."""

import os
import subprocess
import sys

import pytest

SNIPPET = """
import gymnasium as gym, shipgym
env = gym.make("shipgym/BlueLadyHarbour-v0", render_mode="rgb_array")
env.reset(seed=0)
frame = env.render()
print("SHAPE", frame.shape, frame.dtype, int(frame.std() > 1))
"""


def _run(**env_vars):
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "DISPLAY")}
    env.update(env_vars)
    return subprocess.run(
        [sys.executable, "-c", SNIPPET], env=env, capture_output=True, text=True, timeout=120
    )


def test_rgb_array_with_egl_or_a_clear_error():
    res = _run(MUJOCO_GL="egl")
    if res.returncode == 0:
        assert "SHAPE (480, 640, 3) uint8 1" in res.stdout
    else:  # no EGL on this machine: the error must say what to do
        assert "MUJOCO_GL" in res.stderr, res.stderr[-2000:]


def test_no_backend_gives_advice_not_a_crash():
    res = _run()  # no display, no MUJOCO_GL: GLFW cannot open a context
    if res.returncode != 0:
        assert "MUJOCO_GL=egl" in res.stderr, res.stderr[-2000:]
    else:
        pytest.skip("a default OpenGL backend works on this machine")


def test_unusable_backend_is_reported_at_import():
    res = _run(MUJOCO_GL="osmesa", PYOPENGL_PLATFORM="osmesa")
    if res.returncode != 0:
        assert "MUJOCO_GL='osmesa'" in res.stderr and "libosmesa6" in res.stderr
    else:
        assert "SHAPE" in res.stdout
