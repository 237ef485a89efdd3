"""Map geometry of a run, taken from the MuJoCo model: quays, hull outline, thruster positions.

Pure NumPy (``mujoco`` is only touched through the model and data objects handed in). All map
coordinates are NED metres: ``x`` north, ``y`` east; body coordinates are ``x`` forward,
``y`` starboard.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "HULL_OUTLINE",
    "THRUSTER_NAMES",
    "THRUSTER_POSITIONS",
    "convex_outline",
    "hull_outline",
    "hull_polygon",
    "quay_polygons",
    "thruster_positions",
]

#: Thruster names in actuator order (main propeller, bow tunnel, stern tunnel).
THRUSTER_NAMES: tuple[str, str, str] = ("main_propeller", "bow_tunnel", "stern_tunnel")

#: Body-frame positions ``(x forward, y starboard)`` of the thrusters (m), Tomera 2014 / MJCF sites.
THRUSTER_POSITIONS: NDArray[np.float64] = np.array([[-6.5, 0.0], [3.24, 0.0], [-2.376, 0.0]])

#: Waterline outline of the Blue Lady hull in the body frame ``(x forward, y starboard)`` (m),
#: counter-clockwise in (x, y); the convex outline of the MJCF mesh ``hull_outline`` (Loa 13.78 m,
#: B 2.38 m). Used when a model without that mesh is recorded.
HULL_OUTLINE: NDArray[np.float64] = np.array(
    [
        [-6.89, -0.7378], [-6.8377, -0.9215], [-6.6806, -1.0227], [-6.4176, -1.0967],
        [-6.0426, -1.1487], [-5.53, -1.1797], [3.8, -1.19], [4.679, -1.1724],
        [5.2759, -1.1197], [5.7661, -1.0325], [6.1669, -0.9115], [6.481, -0.7572],
        [6.7074, -0.5684], [6.8442, -0.3385], [6.89, 0.0], [6.8442, 0.3385],
        [6.7074, 0.5684], [6.481, 0.7572], [6.1669, 0.9115], [5.7661, 1.0325],
        [5.2759, 1.1197], [4.679, 1.1724], [3.8, 1.19], [-5.53, 1.1797],
        [-6.0426, 1.1487], [-6.4176, 1.0967], [-6.6806, 1.0227], [-6.8377, 0.9215],
        [-6.89, 0.7378],
    ]
)  # fmt: skip


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


def hull_outline(model: Any = None, mesh: str = "hull_outline") -> NDArray[np.float64]:
    """Waterline outline of the hull in the body frame ``(x forward, y starboard)`` (m).

    Takes the convex outline of the mesh vertices, mapped back to the body frame through the
    geom's pose (MuJoCo re-centres and re-orients meshes when it compiles them). Falls back to
    :data:`HULL_OUTLINE` when ``model`` is ``None`` or has no such mesh.

    Args:
        model: a ``mujoco.MjModel`` (or ``None``).
        mesh: name of the hull mesh.

    Returns:
        (k, 2) outline vertices, counter-clockwise in (x, y), not closed.
    """
    if model is None:
        return HULL_OUTLINE.copy()
    try:
        mesh_id = int(model.mesh(mesh).id)
    except (KeyError, AttributeError):
        return HULL_OUTLINE.copy()
    users = np.flatnonzero(np.asarray(model.geom_dataid) == mesh_id)
    geoms = [int(g) for g in users if int(model.geom_type[g]) == 7]  # mjGEOM_MESH
    if not geoms:
        return HULL_OUTLINE.copy()
    g = geoms[0]
    adr, num = int(model.mesh_vertadr[mesh_id]), int(model.mesh_vertnum[mesh_id])
    vert = np.asarray(model.mesh_vert[adr : adr + num], dtype=float)
    body = vert @ _quat_to_mat(model.geom_quat[g]).T + np.asarray(model.geom_pos[g], dtype=float)
    return convex_outline(body[:, :2])


def thruster_positions(model: Any = None) -> NDArray[np.float64]:
    """Body-frame ``(x, y)`` positions (m) of the three thrusters, from the model's sites.

    Falls back to :data:`THRUSTER_POSITIONS` for sites the model lacks.
    """
    out = THRUSTER_POSITIONS.copy()
    if model is None:
        return out
    for i, name in enumerate(THRUSTER_NAMES):
        try:
            out[i] = np.asarray(model.site(name).pos, dtype=float)[:2]
        except (KeyError, AttributeError):
            pass
    return out


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
