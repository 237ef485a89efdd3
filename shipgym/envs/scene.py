"""Build a MuJoCo model from a world and a vessel package (``mujoco.MjSpec``).

Public names: ``WORLDS``, ``build_model``, ``fits``, ``world_path``.

Design notes: docs/design/envs.scene.md.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from shipgym.assets import asset_path
from shipgym.dynamics.actuators import ActuatorSet
from shipgym.dynamics.params import BLUE_LADY_HULL
from shipgym.dynamics.vessel import Vessel, VesselError

from ._mujoco import mujoco

__all__ = ["WORLDS", "build_model", "fits", "make_renderer", "world_path"]

#: world name -> file in ``shipgym/assets/mjcf/worlds/``
_PREFIX = "vessel/"

WORLDS: dict[str, str] = {"open-water": "open_water.xml", "harbour": "harbour.xml"}


def world_path(world: str) -> Path:
    """The MJCF file of a world by name (:data:`WORLDS`)."""
    if world not in WORLDS:
        raise ValueError(f"unknown world {world!r}; choose one of: {', '.join(WORLDS)}")
    return asset_path("mjcf", "worlds", WORLDS[world])


def _max_hull(spec: mujoco.MjSpec) -> tuple[float, float] | None:
    """The largest ``(L_oa, B)`` (m) a world takes (its numeric ``shipgym_max_hull``), if any."""
    n = spec.numeric("shipgym_max_hull")
    return None if n is None else (float(n.data[0]), float(n.data[1]))


def fits(vessel: Vessel, world: str) -> bool:
    """Whether ``vessel`` fits ``world`` (a world may declare its largest hull)."""
    limit = _max_hull(mujoco.MjSpec.from_file(str(world_path(world))))
    return limit is None or (vessel.L_oa <= limit[0] and vessel.B <= limit[1])


#: MJCF attributes that name files or folders (``<include file>``, assets, compiler dirs)
_FILE_ATTRIBUTES = ("file", "meshdir", "texturedir", "assetdir", "fileleft", "fileright",
                    "fileup", "filedown", "filefront", "fileback")  # fmt: skip


def check_package_files(xml: Path, root: Path | None = None, depth: int = 0) -> None:
    """Every file a vessel's MJCF names (includes, meshes, textures, the compiler's folders)
    lies inside its package folder ``root`` (default: the folder of ``xml``), so a vessel
    package cannot make MuJoCo read other files on the disk; included files are checked too.

    Raises:
        VesselError: a name outside the package, an unreadable or malformed file, or
            includes nested more than 8 deep.
    """
    import xml.etree.ElementTree as ET

    from shipgym._safeload import read_bounded

    root = (root or xml.parent).resolve()
    if depth > 8:
        raise VesselError(f"{xml}: <include> nested more than 8 deep")
    try:
        tree = ET.fromstring(read_bounded(xml, "MJCF file", 16 << 20))
    except (OSError, ValueError, ET.ParseError) as exc:
        raise VesselError(f"{xml}: not a readable MJCF file: {exc}") from None
    for el in tree.iter():
        for attr in _FILE_ATTRIBUTES:
            name = el.get(attr)
            if name is None:
                continue
            target = (xml.parent / name).resolve()
            if target != root and root not in target.parents:
                raise VesselError(
                    f"{xml}: <{el.tag} {attr}={name!r}> names a file outside the vessel package "
                    f"{root}: a package may only use its own files"
                )
            if el.tag == "include" and attr == "file":
                check_package_files(target, root, depth + 1)


def build_model(
    vessel: Vessel, world: str = "open-water", actuators: ActuatorSet | None = None
) -> mujoco.MjModel:
    """The compiled MuJoCo model of ``vessel`` in ``world``.

    ``actuators``: the actuator laws of the MuJoCo actuators (the channels of
    ``vessel.actuators``, e.g. :meth:`Vessel.actuators_for <shipgym.dynamics.vessel.Vessel.
    actuators_for>` a plant); ``None``: ``vessel.actuators``. A flow-dependent actuator's gain
    is 0 (the physics applies its force).

    Raises:
        VesselError: ``vessel.xml`` has no body ``hull`` or fails to compile.
        ValueError: unknown world, or a vessel that does not fit the harbour.
    """
    spec = mujoco.MjSpec.from_file(str(world_path(world)))
    limit = _max_hull(spec)
    if limit is not None and (vessel.L_oa > limit[0] or vessel.B > limit[1]):
        raise ValueError(
            f"vessel {vessel.name!r} (L_oa {vessel.L_oa:g} m, B {vessel.B:g} m) does not fit the "
            f"{world} world (at most {limit[0]:g} m x {limit[1]:g} m): use the open-water scene"
        )
    check_package_files(Path(vessel.body_xml))
    try:
        child = mujoco.MjSpec.from_file(str(vessel.body_xml))
    except Exception as exc:  # noqa: BLE001 - MuJoCo's parser raises assorted errors
        raise VesselError(f"{vessel.body_xml}: not a valid MJCF file: {exc}") from None
    src = child.body("hull")
    if src is None:
        raise VesselError(f"{vessel.body_xml}: needs a body named 'hull' (the hull geometry)")
    frame = spec.worldbody.add_frame()
    hull = frame.attach_body(src, _PREFIX, "")
    # the vessel's own names, without the attachment prefix (geoms name the contacts)
    hull.name = "hull"
    for el in (*hull.geoms, *hull.sites, *hull.cameras):
        if el.name.startswith(_PREFIX):
            el.name = el.name[len(_PREFIX) :]
    for j in list(hull.joints):
        raise VesselError(
            f"{vessel.body_xml}: the hull body must have no joints (found {j.name!r}); shipgym "
            "adds them from the vessel's DOF set"
        )
    m, I_x, I_z = vessel.rigid_inertia
    hull.explicitinertial = True
    hull.mass = m
    hull.ipos = [0.0, 0.0, 0.0]
    hull.iquat = [1.0, 0.0, 0.0, 0.0]
    hull.inertia = [I_x, I_z, I_z]
    # joints first in the body: x, y, psi (, phi); MuJoCo composes hinges in order
    axes = [("x", mujoco.mjtJoint.mjJNT_SLIDE, (1, 0, 0)), ("y", mujoco.mjtJoint.mjJNT_SLIDE,
            (0, 1, 0)), ("psi", mujoco.mjtJoint.mjJNT_HINGE, (0, 0, 1))]  # fmt: skip
    if vessel.dofs == 4:
        axes.append(("phi", mujoco.mjtJoint.mjJNT_HINGE, (1, 0, 0)))
    for name, typ, axis in axes:
        hull.add_joint(name=name, type=typ, axis=list(axis))
    size = 0.009 * vessel.L_oa
    acts = vessel.actuators if actuators is None else actuators
    if acts.channel_names != vessel.actuators.channel_names:
        raise ValueError(
            f"actuators must have the channels of {vessel.name!r}: "
            f"{vessel.actuators.channel_names}, got {acts.channel_names}"
        )
    for a in acts:
        hull.add_site(name=a.name, pos=list(a.position), size=[size, size, size],
                      rgba=[1.0, 0.8, 0.0, 1.0], group=3)  # fmt: skip
        for ch in a.channels:
            # a named channel at the actuator's site; its force and dynamics are the physics'
            # (shipgym.sim.step), so MuJoCo's actuator has no gain and no state
            act = spec.add_actuator(name=ch.name, target=a.name)
            act.trntype = mujoco.mjtTrn.mjTRN_SITE
            act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
            act.biastype = mujoco.mjtBias.mjBIAS_NONE
            act.dyntype = mujoco.mjtDyn.mjDYN_NONE
            act.gear = [0.0] * 6
            act.gainprm[0] = 0.0
    if world == "open-water":
        water = spec.geom("water")
        half = max(200.0, 15.0 * vessel.L_oa)
        water.size = [half, half, 0.1]
        L = vessel.L_oa / BLUE_LADY_HULL.L_oa  # the Blue Lady's cameras, scaled with the length
        spec.worldbody.add_camera(name="top", mode=mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM,
                                  pos=[0, 0, -40 * L], xyaxes=[0, 1, 0, 1, 0, 0])  # fmt: skip
        spec.worldbody.add_camera(name="map", pos=[0, 0, -120 * L], xyaxes=[0, 1, 0, 1, 0, 0])
    try:
        return spec.compile()
    except Exception as exc:  # noqa: BLE001
        raise VesselError(f"{vessel.folder}: the MuJoCo model does not compile: {exc}") from None


def make_renderer(model: Any) -> Any:
    """A 640 x 480 MuJoCo renderer of ``model``, or a ``RuntimeError`` that says how to get
    an OpenGL backend."""
    try:
        return mujoco.Renderer(model, 480, 640)
    except Exception as exc:  # noqa: BLE001 - any GL failure gets the same advice
        raise RuntimeError(
            f"rendering needs an OpenGL backend and none works here ({exc}); on a headless "
            "machine set MUJOCO_GL=egl (or MUJOCO_GL=osmesa with PYOPENGL_PLATFORM=osmesa and "
            "libosmesa installed) before importing mujoco"
        ) from exc
