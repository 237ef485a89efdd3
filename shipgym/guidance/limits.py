"""Guidance limits of a vessel: its ``[limits]`` table, completed from its force capacity, and
the check that the limits leave the thrusters a margin (``capacity_use``).

Public names: ``vessel_limits``, ``capacity_use``, ``CAPACITY_FRACTION``.

Design notes: docs/design/guidance.limits.md.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shipgym.dynamics.params import BLUE_LADY_HULL, HullParameters

from .reference import BLUE_LADY_LIMITS, Limits

__all__ = ["CAPACITY_FRACTION", "capacity_use", "vessel_limits"]

#: the largest share of a DOF's thrust capacity that the reference of a leg may ask for in the
#: vessel's nominal wind (:func:`capacity_use`). [chosen]: the remaining quarter is the
#: feedback's: the corrections of a position error, gusts, the command noise of an observer
#: (about 20-40 N and 50-80 N m RMS for the Blue Lady with the KBF) and the tunnels' loss with
#: speed. With the limits of issue 16 the Blue Lady's reference asked for 102 % of its sway
#: and 122 % of its yaw capacity, and a tunnel sat at its limit 11-13 % of the harbour
#: manoeuvre on the worst seeds (KBF + pid, 3 m/s from 300 deg).
CAPACITY_FRACTION = 0.75


def vessel_limits(vessel: Any) -> Limits:
    """The guidance :class:`Limits` of ``vessel`` (its ``[limits]``, completed as above)."""
    given = dict(vessel.limits)
    bl = BLUE_LADY_LIMITS  # the chosen speeds of the Blue Lady, Froude-scaled
    lam = vessel.L_oa / BLUE_LADY_HULL.L_oa
    M = np.diag(np.asarray(vessel.design.M, dtype=float))
    cap = np.asarray(vessel.actuators.capacity(), dtype=float)
    cap3 = cap if cap.size == 3 else cap[[0, 1, 3]]
    acc = cap3 / (6.0 * M)
    derived = {
        "surge_speed": bl.surge_speed * math.sqrt(lam),
        "surge_astern_speed": bl.surge_astern_speed * math.sqrt(lam),
        "sway_speed": bl.sway_speed * math.sqrt(lam),
        "yaw_rate": bl.yaw_rate / math.sqrt(lam),
        "surge_accel": float(acc[0]),
        "surge_astern_accel": 0.8 * float(acc[0]),
        "sway_accel": float(acc[1]),
        "yaw_accel": float(acc[2]),
    }
    return Limits.from_dict({**derived, **given})


def capacity_use(
    vessel: Any, limits: Limits | None = None, wind_speed: float | None = None
) -> dict[str, float]:
    r"""The share of the thrust capacity that a leg's reference at ``limits`` asks for, per
    DOF and direction, in a steady wind (the check that guidance is limited by the capacity).

    For each DOF the peak demand is the plant's inertia at the largest reference acceleration
    plus its damping at the largest reference speed plus the largest wind load on that axis,
    taken together (a bound: the raised-cosine profile reaches them at different times):

    - surge ahead, ``surge_ahead``: ``m_11 a_u + |X_u| U + |X_uu| U^2 + X_w`` against the
      ahead thrust; braking a forward leg, ``surge_brake``: ``m_11 a_u + X_w`` against the
      astern thrust (the damping helps); astern, ``surge_astern``: the same at the astern
      limits against the astern thrust;
    - sway, ``sway``: ``m_22 a_v + |Y_v| V + |Y_vv| V^2 + Y_w``;
    - yaw, ``yaw``: ``m_33 a_r + |N_r| R + |N_rr| R^2 + N_w``,

    with ``m_11 = m - X_udot``, ``m_22 = m - Y_vdot``, ``m_33 = I_z - N_rdot`` of the plant's
    hull (not the controller's design model: the Blue Lady's design ``M`` repeats Tomera
    2014's printed sway added mass, 10x below the plant's), the capacities of
    :meth:`~shipgym.dynamics.actuators.ActuatorSet.capacity` at rest (the Blue Lady: 451 N
    ahead, 78 N astern, 88 N sway, 248 N m yaw) and the wind loads the largest over all
    relative directions (Blendermann 1994 with the vessel's windage) at ``wind_speed``.

    Args:
        vessel: a vessel with a ``fossen3`` hull (:class:`~shipgym.dynamics.params.HullParameters`).
        limits: the limits to check (default: :func:`vessel_limits` of ``vessel``).
        wind_speed: steady wind (m/s, >= 0; default: the vessel's ``nominal_wind``).

    Returns:
        ``{"surge_ahead", "surge_brake", "surge_astern", "sway", "yaw"}``: demand over
        capacity (1 = all of it).

    Raises:
        ValueError: a vessel without a ``fossen3`` hull or windage, a negative or non-finite
            wind speed.
    """
    h = vessel.hull
    if not isinstance(h, HullParameters):
        raise ValueError(
            f"capacity_use needs a fossen3 hull (HullParameters), vessel {vessel.name!r} has "
            f"{type(h).__name__}"
        )
    if vessel.windage is None:
        raise ValueError(f"capacity_use needs the vessel's windage; {vessel.name!r} has none")
    w = vessel.nominal_wind if wind_speed is None else wind_speed
    if isinstance(w, bool) or not (isinstance(w, int | float) and math.isfinite(w) and w >= 0):
        raise ValueError(f"wind_speed must be a finite speed >= 0 m/s, got {wind_speed!r}")
    lim = vessel_limits(vessel) if limits is None else limits
    from shipgym.disturbances.wind import wind_load

    beta = np.linspace(0.0, 2.0 * math.pi, 721)
    load: NDArray[np.float64] = np.abs(wind_load(0.0, 0.0, 0.0, float(w), beta, None,
                                                 vessel.windage)).max(axis=0)  # fmt: skip
    acts = vessel.actuators
    cap = np.asarray(acts.capacity(), dtype=float)
    cap3 = cap if cap.size == 3 else cap[[0, 1, 3]]
    astern = -sum(
        min(0.0, float(a.force_lower)) * float(getattr(a, "direction", (0.0, 0.0))[0])
        for a in acts.actuators
        if hasattr(a, "force_lower") and getattr(a, "direction", (0.0, 0.0))[0] > 0.0
    )
    astern = astern if astern > 0.0 else float(cap3[0])
    m11, m22, m33 = h.m - h.X_udot, h.m - h.Y_vdot, h.I_z - h.N_rdot

    def drag(lin: float, quad: float, s: float) -> float:
        return abs(lin) * s + abs(quad) * s * s

    U, Ua, V, R = lim.surge_speed, lim.surge_astern_speed, lim.sway_speed, lim.yaw_rate
    X, Y, N = (float(x) for x in load)
    c_x, c_y, c_n = (float(x) for x in cap3)
    return {
        "surge_ahead": (m11 * lim.surge_accel + drag(h.X_u, h.X_uu, U) + X) / c_x,
        "surge_brake": (m11 * lim.surge_accel + X) / astern,
        "surge_astern": (m11 * lim.surge_astern_accel + drag(h.X_u, h.X_uu, Ua) + X) / astern,
        "sway": (m22 * lim.sway_accel + drag(h.Y_v, h.Y_vv, V) + Y) / c_y,
        "yaw": (m33 * lim.yaw_accel + drag(h.N_r, h.N_rr, R) + N) / c_n,
    }
