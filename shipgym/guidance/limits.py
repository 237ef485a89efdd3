"""Guidance limits of a vessel: its ``[limits]`` table, completed from its force capacity.

Public names: ``vessel_limits``.

Design notes: docs/design/guidance.limits.md.
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
