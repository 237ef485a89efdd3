"""The registered Blue Lady tasks: harbour manoeuvre, station keeping, tracking."""

from __future__ import annotations

import math
from typing import Any

from shipgym.disturbances import CurrentConfig, WindConfig
from shipgym.guidance import Leg, ManoeuvrePlan
from shipgym.observers.sensors import SensorConfig

from .base import BlueLadyEnv

__all__ = ["BlueLadyHarbourEnv", "BlueLadyStationKeepingEnv", "BlueLadyTrackingEnv"]


class BlueLadyHarbourEnv(BlueLadyEnv):
    r"""The 5-leg harbour manoeuvre of Tomera (2014) Fig. 7.

    Registered as ``shipgym/BlueLadyHarbour-v0``.

    The ship starts at rest alongside berth A and moves to berth B: 7 m to port, 38 m
    forward, a 90 deg turn to starboard, 15 m astern, 3 m to port. Legs switch when the ship
    is within 1 m of the leg's end point with a heading error below 5 deg (and the leg's
    reference has arrived). Default wind: 3 m/s from 300 deg with gusts (the lake trial).
    The episode terminates when the last leg completes or on quay contact; time limit
    2000 control steps (2000 s). Spaces, reward and info: see :class:`BlueLadyEnv`.
    """

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("plan", "tomera2014")
        kwargs.setdefault("scene", "harbour")
        super().__init__(**kwargs)


class BlueLadyStationKeepingEnv(BlueLadyEnv):
    r"""Hold the start pose against wind from a perturbed start.

    Registered as ``shipgym/BlueLadyStationKeeping-v0``.

    One zero-displacement leg on open water; the ship starts up to 2 m and 5 deg off the pose
    (uniform, seeded). Default wind 3 m/s from 300 deg with gusts. Never terminates on
    reaching the pose; time limit 600 control steps (600 s). Spaces, reward and info: see
    :class:`BlueLadyEnv`.
    """

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("plan", ManoeuvrePlan(legs=(Leg(name="hold"),), name="station-keeping"))
        kwargs.setdefault("scene", "open-water")
        kwargs.setdefault("start_noise", (2.0, 2.0, math.radians(5.0)))
        kwargs.setdefault("terminate_on_finish", False)
        super().__init__(**kwargs)


class BlueLadyTrackingEnv(BlueLadyEnv):
    r"""Randomised legs and wind on open water (the training task): ``shipgym/BlueLadyTracking-v0``.

    Each episode draws from the seeded generator 1-3 legs: lateral (2-8 m either side),
    longitudinal (5-30 m ahead or 3-15 m astern), rotation (30-120 deg either way) or combined
    (surge and sway together); a wind of 0-3.5 m/s from any direction with gusts (4 m/s on the
    beam exceeds the 248 N m yaw capacity); a lake current of 0-0.03 m/s in any direction
    (~1 % of the wind, assumed); and sensor noise within the lake presets (DGPS sigma
    0.07-0.15 m per axis, gyrocompass 0.2-0.45 deg). The episode terminates when the last leg
    completes; time limit 800 control steps. ``max_current_speed=0`` and
    ``randomize_sensors=False`` switch those draws off (the shipped PPO baseline was trained
    so). Spaces, reward and info: see :class:`BlueLadyEnv`.
    """

    def __init__(
        self,
        max_legs: int = 3,
        max_wind_speed: float = 3.5,
        max_current_speed: float = 0.03,
        randomize_sensors: bool = True,
        **kwargs: Any,
    ) -> None:
        if not (isinstance(max_legs, int) and max_legs >= 1):
            raise ValueError(f"max_legs must be an int >= 1, got {max_legs!r}")
        if not (math.isfinite(max_wind_speed) and max_wind_speed >= 0):
            raise ValueError(f"max_wind_speed must be >= 0 m/s, got {max_wind_speed!r}")
        if not (math.isfinite(max_current_speed) and max_current_speed >= 0):
            raise ValueError(f"max_current_speed must be >= 0 m/s, got {max_current_speed!r}")
        self.max_legs = max_legs
        self.max_wind_speed = float(max_wind_speed)
        self.max_current_speed = float(max_current_speed)
        self.randomize_sensors = bool(randomize_sensors)
        kwargs.setdefault("scene", "open-water")
        kwargs.setdefault("plan", ManoeuvrePlan(legs=(Leg(surge=10.0),), name="tracking"))
        super().__init__(**kwargs)

    def _episode_plan(self) -> ManoeuvrePlan:
        rng = self.np_random
        legs = []
        for i in range(int(rng.integers(1, self.max_legs + 1))):
            kind = int(rng.integers(4))
            side = 1.0 if rng.random() < 0.5 else -1.0
            if kind == 0:
                leg = Leg(sway=side * rng.uniform(2.0, 8.0), name=f"{i + 1}: lateral")
            elif kind == 1:
                dist = rng.uniform(5.0, 30.0) if side > 0 else -rng.uniform(3.0, 15.0)
                leg = Leg(surge=dist, name=f"{i + 1}: longitudinal")
            elif kind == 2:
                yaw = side * math.radians(rng.uniform(30.0, 120.0))
                leg = Leg(yaw=yaw, name=f"{i + 1}: rotation")
            else:
                leg = Leg(
                    surge=rng.uniform(3.0, 15.0), sway=side * rng.uniform(2.0, 5.0),
                    name=f"{i + 1}: combined",
                )  # fmt: skip
            legs.append(leg)
        return ManoeuvrePlan(legs=tuple(legs), name="tracking")

    def _episode_wind(self) -> WindConfig | None:
        rng = self.np_random
        speed = rng.uniform(0.0, self.max_wind_speed)
        return WindConfig(speed=speed, direction_from=rng.uniform(0.0, 2.0 * math.pi))

    def _episode_current(self) -> CurrentConfig | None:
        if self.max_current_speed == 0.0:  # no draw: the random stream stays as without current
            return self.current_config
        rng = self.np_random
        speed = rng.uniform(0.0, self.max_current_speed)
        return CurrentConfig(speed=speed, direction_to=rng.uniform(0.0, 2.0 * math.pi))

    def _episode_sensors(self) -> SensorConfig | None:
        if not self.randomize_sensors or self.sensor_config is None:
            return self.sensor_config
        rng = self.np_random
        pos = rng.uniform(0.07, 0.15)
        psi = math.radians(rng.uniform(0.2, 0.45))
        return self.sensor_config.replace(position_variance=pos * pos, heading_variance=psi * psi)
