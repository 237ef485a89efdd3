"""Render the docs' vessel gallery: one PNG per packaged vessel, ``docs/vessels/<name>.png``.

Each image is the vessel's MuJoCo model (``shipgym.envs.scene.build_model``: the package's
hull geometry and its actuator sites, on open water) seen from the starboard quarter by a free
camera at a distance scaled with the length overall. Needs an OpenGL backend: on a headless
machine run it as ``MUJOCO_GL=egl python tools/render_vessels.py`` (the docs build does not
render; it uses the committed images, and ``tests/test_docs.py`` checks there is one for every
vessel).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from shipgym.dynamics import vessels  # noqa: E402
from shipgym.envs.scene import build_model  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "docs" / "vessels"
WIDTH, HEIGHT = 640, 360


def render(name: str) -> np.ndarray:
    """The RGB image (HEIGHT, WIDTH, 3) of vessel ``name``."""
    v = vessels()[name]
    model = build_model(v)
    model.vis.global_.offwidth, model.vis.global_.offheight = WIDTH, HEIGHT
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = data.xpos[model.body("hull").id]
    # NED world (z down): MuJoCo's free camera keeps +z up, so an elevation of +25 deg puts it
    # above the deck (at negative z) and its image upside down: turned by 180 deg below
    cam.distance = 1.1 * v.L_oa
    cam.azimuth = 150.0
    cam.elevation = 25.0
    opt = mujoco.MjvOption()
    opt.sitegroup[3] = 1  # the actuator sites
    with mujoco.Renderer(model, HEIGHT, WIDTH) as r:
        r.update_scene(data, camera=cam, scene_option=opt)
        return np.ascontiguousarray(r.render()[::-1, ::-1])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", help="vessels to render (default: every packaged one)")
    args = ap.parse_args(argv)
    import matplotlib.pyplot as plt

    OUT.mkdir(parents=True, exist_ok=True)
    for name in args.names or sorted(vessels()):
        path = OUT / f"{name}.png"
        plt.imsave(path, render(name))
        print(f"{path} ({path.stat().st_size // 1024} KiB)")


if __name__ == "__main__":
    main()
