"""Guidance limited by the thrust capacity (issue 31): at the Blue Lady's limits a leg's
reference asks for at most CAPACITY_FRACTION of each DOF's capacity in its nominal wind
(shipgym.guidance.limits.capacity_use), checked against a hand computation."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from shipgym.disturbances.wind import wind_load
from shipgym.dynamics.vessel import load_vessel
from shipgym.guidance import BLUE_LADY_LIMITS
from shipgym.guidance.limits import CAPACITY_FRACTION, capacity_use, vessel_limits

BL = load_vessel("blue-lady")


def test_the_blue_ladys_limits_leave_a_quarter_of_every_capacity():
    assert vessel_limits(BL) == BLUE_LADY_LIMITS
    use = capacity_use(BL)
    assert set(use) == {"surge_ahead", "surge_brake", "surge_astern", "sway", "yaw"}
    assert max(use.values()) <= CAPACITY_FRACTION
    # the limits before issue 31 asked for more than the sway and yaw capacity
    old = dataclasses.replace(BLUE_LADY_LIMITS, surge_accel=0.0025, surge_astern_accel=0.002,
                              sway_speed=0.05, sway_accel=0.001, yaw_rate=math.radians(1.0),
                              yaw_accel=1.5e-4)  # fmt: skip
    before = capacity_use(BL, old)
    assert before["sway"] > 1.0 and before["yaw"] > 1.3


def test_capacity_use_by_hand():
    h, lim = BL.hull, BLUE_LADY_LIMITS
    beta = np.linspace(0.0, 2.0 * math.pi, 3601)
    w = np.abs(wind_load(0.0, 0.0, 0.0, 3.0, beta, None, BL.windage)).max(axis=0)
    assert w == pytest.approx([9.43, 24.8, 63.1], abs=0.05)  # Blendermann (1994), 3 m/s
    m22 = 22934.4 + 18962.0  # the plant's sway inertia: m - Y_vdot
    sway = (m22 * 5e-4 + 259.8 * 0.03 + 4200.0 * 0.03**2 + w[1]) / (2 * 44.145)
    yaw = (455182.1 * 9e-5 + 6130.5 * math.radians(0.5) + 3.3e5 * math.radians(0.5) ** 2
           + w[2]) / (44.145 * (3.24 + 2.376))  # fmt: skip
    brake = ((22934.4 + 730.5) * 0.002 + w[0]) / (1.9589e-3 * 200.0**2)
    use = capacity_use(BL, lim)
    assert use["sway"] == pytest.approx(sway, rel=1e-3)
    assert use["yaw"] == pytest.approx(yaw, rel=1e-3)
    assert use["surge_brake"] == pytest.approx(brake, rel=1e-3)
    assert h.m - h.Y_vdot == pytest.approx(m22)
    # twice the wind: more of every capacity
    assert all(capacity_use(BL, lim, 6.0)[k] > use[k] for k in use)


def test_capacity_use_refuses_bad_input():
    for bad in (-1.0, math.inf, True):
        with pytest.raises(ValueError, match="wind_speed"):
            capacity_use(BL, wind_speed=bad)
    with pytest.raises(ValueError, match="fossen3 hull"):
        capacity_use(load_vessel("kvlcc2-100m"))
