"""Map geometry of a run from the MuJoCo model and the vessel: quays, hull outline, thrusters.

Pure NumPy (``mujoco`` is only touched through the model and data objects handed in). All map
coordinates are NED metres: ``x`` north, ``y`` east; body coordinates are ``x`` forward,
``y`` starboard.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.params import BLUE_LADY_HULL

__all__ = [
    "REFERENCE_LENGTH",
    "convex_outline",
    "hull_length",
    "hull_outline",
    "hull_polygon",
    "quay_polygons",
    "thrust_arrows",
    "thruster_positions",
]

#: Lengths drawn on a map (arrows, margins, line widths) are given for a hull of this overall
#: length (m; the Blue Lady, 13.78 m) and scale with the vessel's ``L_oa``.
REFERENCE_LENGTH = BLUE_LADY_HULL.L_oa


def convex_outline(points: ArrayLike) -> NDArray[np.float64]:
    """Convex hull of 2-D points (Andrew's monotone chain), counter-clockwise, not closed.

    Args:
        points: (n, 2) array of points (any unit).

    Returns:
        (k, 2) hull vertices, first vertex not repeated.
    """
    p = np.unique(np.round(np.asarray(points, dtype=float), 9), axis=0)
    if len(p) < 3:
        return p

    def cross(o: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
        return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))

    lower: list[NDArray[np.float64]] = []
    for q in p:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], q) <= 0:
            lower.pop()
        lower.append(q)
    upper: list[NDArray[np.float64]] = []
    for q in p[::-1]:
        while len(upper) >= 2 and cross(upper[-2], upper[-1], q) <= 0:
            upper.pop()
        upper.append(q)
    return np.array(lower[:-1] + upper[:-1])


def _quat_to_mat(q: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrix of a unit quaternion ``[w, x, y, z]`` (MuJoCo order)."""
    w, x, y, z = np.asarray(q, dtype=float).reshape(4).tolist()
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


#: geom types of ``mujoco.mjtGeom`` (the outline of each is sampled in its own frame)
_SPHERE, _CAPSULE, _ELLIPSOID, _CYLINDER, _BOX, _MESH = 2, 3, 4, 5, 6, 7
_N_ARC = 32  # points per circle when sampling round geoms


def _geom_points(model: Any, g: int) -> NDArray[np.float64]:
    """Points spanning geom ``g`` in its parent body's frame (m), shape (k, 3); empty for a
    geom type without a finite shape (plane, height field)."""
    kind = int(model.geom_type[g])
    size = np.asarray(model.geom_size[g], dtype=float)
    ang = np.linspace(0.0, 2.0 * math.pi, _N_ARC, endpoint=False)
    circle = np.column_stack([np.cos(ang), np.sin(ang), np.zeros_like(ang)])
    if kind == _BOX:
        local = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]) * size
    elif kind == _CYLINDER:
        r, h = size[0], size[1]
        local = np.vstack([r * circle + [0, 0, -h], r * circle + [0, 0, h]])
    elif kind == _CAPSULE:  # a cylinder with hemispherical ends
        r, h = size[0], size[1]
        ball = r * np.vstack([circle, circle[:, [0, 2, 1]], circle[:, [2, 0, 1]]])
        local = np.vstack([ball + [0, 0, -h], ball + [0, 0, h]])
    elif kind in (_SPHERE, _ELLIPSOID):
        axes = np.full(3, size[0]) if kind == _SPHERE else size
        ring = np.vstack([circle, circle[:, [0, 2, 1]], circle[:, [2, 0, 1]]])
        local = ring * axes
    elif kind == _MESH:
        mesh_id = int(model.geom_dataid[g])
        adr, num = int(model.mesh_vertadr[mesh_id]), int(model.mesh_vertnum[mesh_id])
        local = np.asarray(model.mesh_vert[adr : adr + num], dtype=float)
    else:
        return np.zeros((0, 3))
    return local @ _quat_to_mat(model.geom_quat[g]).T + np.asarray(model.geom_pos[g], dtype=float)


def hull_outline(model: Any, body: str = "hull") -> NDArray[np.float64]:
    """Waterline outline of the hull in the body frame ``(x forward, y starboard)`` (m).

    The convex outline, seen from above, of the collision geoms (``contype`` or
    ``conaffinity`` non-zero) of the hull body: boxes, cylinders, capsules, spheres,
    ellipsoids and meshes (a mesh's vertices, mapped back to the body frame through the geom's
    pose, as MuJoCo re-centres and re-orients meshes when it compiles them). Drawing-only
    geoms (a deckhouse, a derrick) are left out; a hull body with no collision geom uses all
    its geoms.

    Args:
        model: a ``mujoco.MjModel`` holding the vessel.
        body: name of the hull body.

    Returns:
        (k, 2) outline vertices, counter-clockwise in (x, y), not closed.

    Raises:
        ValueError: the model has no such body, or the body has no geom with a shape.
    """
    try:
        body_id = int(model.body(body).id)
    except KeyError:
        raise ValueError(f"the model has no hull body named {body!r}") from None
    geoms = np.flatnonzero(np.asarray(model.geom_bodyid) == body_id).tolist()
    collide = [
        g for g in geoms if int(model.geom_contype[g]) != 0 or int(model.geom_conaffinity[g]) != 0
    ]
    pts = [_geom_points(model, g) for g in (collide or geoms)]
    xy = np.vstack([p[:, :2] for p in pts]) if pts else np.zeros((0, 2))
    if len(xy) < 3:
        raise ValueError(f"the hull body {body!r} has no geom to draw its outline from")
    return convex_outline(xy)


def hull_length(outline: ArrayLike) -> float:
    """Length (m) of a body-frame hull outline along x (forward); 0 for an empty outline."""
    o = np.asarray(outline, dtype=float).reshape(-1, 2)
    return float(o[:, 0].max() - o[:, 0].min()) if len(o) else 0.0


def thruster_positions(actuators: Any) -> NDArray[np.float64]:
    """Body-frame ``(x, y)`` positions (m) of a vessel's actuators, shape (n_actuators, 2).

    Args:
        actuators: the vessel's :class:`~shipgym.dynamics.actuators.ActuatorSet`.
    """
    return np.array([a.position[:2] for a in actuators], dtype=float).reshape(-1, 2)


def thrust_arrows(
    actuators: Any, states: ArrayLike, length: float, thrust: ArrayLike | None = None
) -> NDArray[np.float64]:
    """Thrust arrows ``(dx, dy)`` in the body frame (m), shape (..., n_actuators, 2).

    Each arrow points along the actuator's force (an azimuth's turns with its angle state)
    and is ``length`` long at the actuator's largest thrust (``max_thrust``).

    Args:
        actuators: the :class:`~shipgym.dynamics.actuators.ActuatorSet`.
        states: actuator states (..., n_channels) (MuJoCo's ``act``; ``info["actuator_state"]``).
        length: arrow length (m) at full thrust.
        thrust: the signed thrust (..., n_actuators) (N; ``info["thrust"]``), which includes
            the flow-dependent laws (a propeller's advance-speed or tunnel loss); ``None``: the
            thrust of the states at rest (``actuators.forces(states)``).
    """
    from shipgym.dynamics.actuators import Azimuth, Propeller

    f_max = np.array([max(float(a.max_thrust), 1e-12) for a in actuators])
    if thrust is None:
        return length * actuators.forces(states) / f_max[:, None]
    st = np.asarray(states, dtype=float)
    T = np.asarray(thrust, dtype=float)
    cols = []
    for i, (a, sl) in enumerate(zip(actuators, actuators.slices, strict=True)):
        if isinstance(a, Azimuth):
            ang = st[..., sl.start + 1]
            c, s = np.cos(ang), np.sin(ang)
        elif isinstance(a, Propeller):
            c, s = a.direction
        elif a.kind == "rudder":  # a rudder's lift acts athwartships
            c, s = 0.0, 1.0
        else:  # an MMG unit's propeller thrust, ahead
            c, s = 1.0, 0.0
        cols.append(np.stack(np.broadcast_arrays(c * T[..., i], s * T[..., i]), -1))
    return length * np.stack(cols, -2) / f_max[:, None]


def quay_polygons(model: Any, data: Any) -> tuple[list[str], NDArray[np.float64]]:
    """World (NED) corner polygons of the quay and pier box geoms (after a reset).

    Quays are the box geoms whose names start with ``quay_`` or ``pier_``.

    Args:
        model: ``mujoco.MjModel``.
        data: ``mujoco.MjData`` whose kinematics are current (``geom_xpos``, ``geom_xmat``).

    Returns:
        ``(names, corners)`` with corners of shape (k, 4, 2): ``(x north, y east)`` (m),
        counter-clockwise in (x, y).
    """
    names: list[str] = []
    polys: list[NDArray[np.float64]] = []
    signs = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], dtype=float)
    for g in range(int(model.ngeom)):
        name = model.geom(g).name
        if not (name.startswith("quay_") or name.startswith("pier_")):
            continue
        if int(model.geom_type[g]) != 6:  # mjGEOM_BOX
            continue
        half = np.asarray(model.geom_size[g][:2], dtype=float)
        mat = np.asarray(data.geom_xmat[g], dtype=float).reshape(3, 3)
        centre = np.asarray(data.geom_xpos[g][:2], dtype=float)
        local = signs * half
        polys.append(centre + local @ mat[:2, :2].T)
        names.append(name)
    if not polys:
        return [], np.zeros((0, 4, 2))
    return names, np.array(polys)


def hull_polygon(outline: ArrayLike, eta: ArrayLike) -> NDArray[np.float64]:
    """The hull outline placed at a NED pose, closed (first vertex repeated).

    Args:
        outline: (k, 2) body-frame outline ``(x forward, y starboard)`` (m).
        eta: pose ``[x north (m), y east (m), psi (rad, clockwise from north)]``.

    Returns:
        (k + 1, 2) NED ``(x, y)`` vertices (m).
    """
    o = np.asarray(outline, dtype=float)
    x, y, psi = (float(v) for v in np.asarray(eta, dtype=float)[:3])
    c, s = math.cos(psi), math.sin(psi)
    pts = np.column_stack([x + c * o[:, 0] - s * o[:, 1], y + s * o[:, 0] + c * o[:, 1]])
    return np.vstack([pts, pts[:1]])
