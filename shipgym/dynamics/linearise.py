r"""The linear sway-yaw-roll model of any 4-DOF vessel with a rudder, about straight running.

Public names: ``roll_model_of``, ``roll_rhs_of``, ``rudder_of``.
Sources: Radhakrishnan (n.d.); Blanke & Christensen (1993).

Design notes: docs/design/dynamics.linearise.md.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .actuators import Rudder, tau_of_table
from .hull4 import is_hull4
from .vanderklugt import OUTPUT_NAMES, STATE_NAMES, RollModel

__all__ = ["roll_model_of", "roll_rhs_of", "rudder_of"]

#: the seed's state order (Radhakrishnan n.d. eq. 9) in the hull's ``nu = [u, v, p, r]``
_V, _R, _PSI, _P, _PHI = range(5)


def rudder_of(vessel: Any, name: str | None = None) -> Rudder:
    """The vessel's rudder ``name`` (default: its only or first rudder).

    Raises:
        ValueError: the vessel has no rudder, or none of that name.
    """
    rudders = [a for a in vessel.actuators if isinstance(a, Rudder)]
    if not rudders:
        raise ValueError(f"vessel {vessel.name!r} has no rudder (actuators: "
                         f"{', '.join(vessel.actuators.names)})")  # fmt: skip
    if name is None:
        return rudders[0]
    for a in rudders:
        if a.name == name:
            return a
    raise ValueError(f"vessel {vessel.name!r} has no rudder {name!r}; its rudders: "
                     f"{', '.join(a.name for a in rudders)}")  # fmt: skip


def _hull_and_rudder(vessel: Any, U: Any, rudder: str | None, plant: str) -> tuple[Any, Rudder]:
    if not (isinstance(U, int | float) and math.isfinite(U) and U > 0):
        raise ValueError(f"U must be a forward speed > 0 m/s, got {U!r}")
    hull = vessel.plant(plant)
    if not is_hull4(hull):
        raise ValueError(f"vessel {vessel.name!r} has {vessel.dofs} DOF: a roll model needs 4")
    return hull, rudder_of(vessel, rudder)


def _rhs(plant: Any, rudder: Rudder, U: float, x: NDArray[np.float64], delta: float,
         w: NDArray[np.float64]) -> NDArray[np.float64]:  # fmt: skip
    v, r, _psi, p, phi = x
    nu = np.array([U, v, p, r])
    F = float(rudder.lift(np.array([delta]), nu))
    xr, _yr, zr = rudder.position
    tau = np.array([0.0, F, -zr * F + w[0], xr * F + w[1]])
    nd = plant.nu_dot(nu, tau, None, phi)
    return np.array([nd[1], nd[3], r, nd[2], p])


def roll_model_of(
    vessel: Any,
    U: float,
    *,
    rudder: str | None = None,
    plant: str = "default",
    q: tuple[float, float] | None = None,
) -> RollModel:
    """The vessel's linear sway-yaw-roll model at the forward speed ``U`` (module docstring).

    Args:
        vessel: a :class:`~shipgym.dynamics.vessel.Vessel` with 4 DOF and a rudder.
        U: forward speed (m/s), > 0.
        rudder: the rudder's name (default: the first).
        plant: the plant variant.
        q: intensities ``(q_K, q_N)`` of the disturbance moments ((N m)^2 s), for a filter.

    Returns:
        :class:`~shipgym.dynamics.vanderklugt.RollModel` with ``G`` per N m of roll and yaw
        moment, ``parameters = None``.

    Raises:
        ValueError: ``U <= 0``, a 3-DOF vessel, no rudder.
    """
    hull, rud = _hull_and_rudder(vessel, U, rudder, plant)
    U = float(U)
    x0 = np.zeros(5)
    w0 = np.zeros(2)
    f0 = _rhs(hull, rud, U, x0, 0.0, w0)
    # central differences with small steps: a term v|v| differences to h|h|/h = h, not 0
    A = np.zeros((5, 5))
    for j, h in enumerate((1e-7 * U, 1e-8, 1e-3, 1e-8, 1e-8)):
        e = np.zeros(5)
        e[j] = h
        A[:, j] = (_rhs(hull, rud, U, x0 + e, 0.0, w0) - _rhs(hull, rud, U, x0 - e, 0.0, w0)) / (
            2 * h
        )
    hd = 1e-5
    B = (_rhs(hull, rud, U, x0, hd, w0) - _rhs(hull, rud, U, x0, -hd, w0)) / (2 * hd)
    # the moments enter linearly: one-sided with a large step is exact to rounding
    hw = 1.0e3
    G = np.stack(
        [(_rhs(hull, rud, U, x0, 0.0, np.array(e)) - f0) / hw for e in ((hw, 0.0), (0.0, hw))], 1
    )
    C = np.zeros((4, 5))
    for i, name in enumerate(OUTPUT_NAMES):
        C[i, STATE_NAMES.index(name)] = 1.0
    return RollModel(
        A, B, G, C, U, None, "linearised",
        source=f"{vessel.name} ({type(hull).__name__}) with rudder {rud.name!r}, linearised at "
        f"U = {U:g} m/s", q=q,
    )  # fmt: skip


def roll_rhs_of(vessel: Any, U: float, *, rudder: str | None = None, plant: str = "default") -> Any:
    """The vessel's nonlinear sway-yaw-roll dynamics at the held speed ``U``, for an EKF.

    ``f(x, delta, w=None) -> x_dot`` with ``x = [v, r, psi, p, phi]`` (the seed's order),
    ``delta`` the rudder angle (rad), ``w = [K_w, N_w]`` optional moments (N m): the hull's
    compiled acceleration and the rudder's lift (stall included) with ``u = U``
    held and the kinematics ``psi_dot = r cos(phi)`` (``r`` for ``kinematics = "linear"``).
    The model :func:`roll_model_of` linearises; the EKF variant of the seed's filter
    (:class:`~shipgym.observers.sway.SwayVelocityEKF`) propagates it.

    Raises:
        ValueError: as :func:`roll_model_of`.
    """
    hull, rud = _hull_and_rudder(vessel, U, rudder, plant)
    acts = vessel.actuators
    j = acts.channel_names.index(rud.name)
    accel, k = type(hull).accel_kernel, hull.kernel_constants()
    table, laws, kinds = acts.law_table()
    out = np.zeros(len(kinds)), np.zeros(len(kinds))
    linear = getattr(hull, "kinematics", "fossen") == "linear"
    st = np.zeros(acts.n_channels)
    Uf = float(U)

    def f(x: Any, delta: float, w: Any = None) -> NDArray[np.float64]:
        v, r, _psi, p, phi = (float(c) for c in x)
        st[j] = float(delta)
        _X, Y, K, N = tau_of_table(table, laws, kinds, st, Uf, v, p, r, *out)
        if w is not None:
            K += float(w[0])
            N += float(w[1])
        _ud, vd, pd, rd = accel(k, Uf, v, p, r, phi, 0.0, Y, K, N, 0.0, 0.0)
        psid = r if linear else r * math.cos(phi)
        return np.array([vd, rd, psid, pd, p])

    return f
