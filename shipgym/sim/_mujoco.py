"""Import MuJoCo once, turning a broken ``MUJOCO_GL`` setting into a clear error."""

from __future__ import annotations

import os

__all__ = ["mujoco"]

try:
    import mujoco
except Exception as exc:  # noqa: BLE001 - mujoco's GL set-up fails with assorted errors
    backend = os.environ.get("MUJOCO_GL")
    if not backend:
        raise
    raise ImportError(
        f"importing mujoco failed with MUJOCO_GL={backend!r} ({type(exc).__name__}: {exc}). "
        "That rendering backend is not usable here: use MUJOCO_GL=egl, or install OSMesa "
        "(Debian: libosmesa6) and also set PYOPENGL_PLATFORM=osmesa, or unset MUJOCO_GL when "
        "you do not render"
    ) from exc
