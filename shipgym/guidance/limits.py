"""Guidance limits of a vessel: its ``[limits]`` table, completed from its force capacity.

A vessel file may give every :class:`~shipgym.guidance.reference.Limits` field (the Blue
Lady's are chosen from its thruster capacity and a 3 m/s lake wind; Star Hercules' and Wimpey
Sealab's from theirs). Fields it leaves out are derived here, so a user's package without a
``[limits]`` table still gets a reference its thrusters can follow:

- accelerations: one sixth of the capacity per DOF over the design inertia
  (``a_i = C_i / (6 M_ii)``, ``C`` from :meth:`ActuatorSet.capacity`), the margin the
  packaged vessels leave for wind and feedback (the Blue Lady's surge: (451 N / 6) / 23 665 kg
  = 0.0032 m/s^2 against its chosen 0.0025);
- speeds: the Blue Lady's (0.2 m/s surge, 0.1 m/s astern, 0.05 m/s sway, 1 deg/s yaw) scaled
  with the length by Froude similarity (speeds with ``sqrt(L)``, the yaw rate with
  ``1/sqrt(L)``), the length ratio taken to the Blue Lady's 13.78 m;
- astern surge acceleration: 0.8 of the ahead one.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from shipgym.dynamics.params import BLUE_LADY_HULL

from .reference import BLUE_LADY_LIMITS, Limits

__all__ = ["vessel_limits"]


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
