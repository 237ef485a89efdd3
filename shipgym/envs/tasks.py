"""The registered tasks: harbour manoeuvre, station keeping, tracking, for any vessel.

Each task is one class, generic over the vessel (``vessel=``); the ``shipgym/BlueLady*-v0``
ids register the same classes with ``vessel="blue-lady"`` and give the same episodes as the
vessel-neutral ids with that vessel.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from shipgym._config import is_real
from shipgym.disturbances import CurrentConfig, WindConfig
from shipgym.disturbances.current import MAX_CURRENT_SPEED
from shipgym.disturbances.wind import MAX_WIND_SPEED
from shipgym.dynamics.params import BLUE_LADY_HULL
from shipgym.guidance import Leg, ManoeuvrePlan
from shipgym.observers.sensors import SensorConfig

from .base import ShipEnv

__all__ = [
    "BlueLadyHarbourEnv",
    "BlueLadyStationKeepingEnv",
    "BlueLadyTrackingEnv",
    "HarbourEnv",
    "StationKeepingEnv",
    "TrackingEnv",
]


class HarbourEnv(ShipEnv):
    r"""The 5-leg harbour manoeuvre of Tomera (2014) Fig. 7.

    Registered as ``shipgym/Harbour-v0`` (``vessel=`` a vessel that fits the basin, which was
    built for the Blue Lady) and ``shipgym/BlueLadyHarbour-v0`` (the Blue Lady).

    The ship starts at rest alongside berth A and moves to berth B: 7 m to port, 38 m
    forward, a 90 deg turn to starboard, 15 m astern, 3 m to port. Legs switch when the ship
    is within 1 m of the leg's end point with a heading error below 5 deg (and the leg's
    reference has arrived). Default wind: 3 m/s from 300 deg with gusts (the lake trial).
    The episode terminates when the last leg completes or on quay contact; time limit
    2000 control steps (2000 s). Spaces, reward and info: see :class:`ShipEnv`.
    """

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("plan", "tomera2014")
        kwargs.setdefault("scene", "harbour")
        super().__init__(**kwargs)


class StationKeepingEnv(ShipEnv):
    r"""Hold the start pose against wind from a perturbed start.

    Registered as ``shipgym/StationKeeping-v0`` (any vessel, ``vessel=``) and
    ``shipgym/BlueLadyStationKeeping-v0`` (the Blue Lady).

    One zero-displacement leg on open water; the ship starts up to 2 m and 5 deg off the pose
    (uniform, seeded). Default wind: the vessel's nominal wind (3 m/s for the Blue Lady) from
    300 deg with gusts. Never terminates on reaching the pose; time limit 600 control steps
    (600 s; pass ``max_episode_steps`` to ``gym.make`` for longer). Spaces, reward and info:
    see :class:`ShipEnv`.

    ``random_wind=(low, high)`` (m/s) draws each episode's mean wind speed uniformly in
    ``[low, high]`` and its direction uniformly from every direction, from the seeded
    generator (after the plan, before the start perturbation), keeping the gusts and spectrum
    of ``wind=`` (the training distribution of the learned station-keeping baseline);
    ``None`` (default) keeps ``wind=`` for every episode and the random stream as without
    the option.
    """

    def __init__(self, random_wind: tuple[float, float] | None = None, **kwargs: Any) -> None:
        kwargs.setdefault("plan", ManoeuvrePlan(legs=(Leg(name="hold"),), name="station-keeping"))
        kwargs.setdefault("scene", "open-water")
        kwargs.setdefault("start_noise", (2.0, 2.0, math.radians(5.0)))
        kwargs.setdefault("terminate_on_finish", False)
        if random_wind is not None:
            try:
                lo, hi = (float(x) for x in random_wind)
            except (TypeError, ValueError):
                raise ValueError(
                    f"random_wind must be None or (low, high) mean wind speeds in m/s, got "
                    f"{random_wind!r}"
                ) from None
            if not (0.0 <= lo <= hi <= MAX_WIND_SPEED):
                raise ValueError(
                    f"random_wind must satisfy 0 <= low <= high <= {MAX_WIND_SPEED:g} m/s, got "
                    f"{random_wind!r}"
                )
            random_wind = (lo, hi)
        self.random_wind = random_wind
        super().__init__(**kwargs)
        if random_wind is not None and self._wind is None:
            raise ValueError("random_wind needs a wind (its gusts are kept); got wind=None")

    def _episode_wind(self) -> WindConfig | None:
        given = super()._episode_wind()
        if self.random_wind is None or given is None:
            return given
        rng = self.np_random
        speed = rng.uniform(*self.random_wind)
        direction = rng.uniform(0.0, 2.0 * math.pi)
        return dataclasses.replace(given, speed=speed, direction_from=direction)


class TrackingEnv(ShipEnv):
    r"""Randomised legs and wind on open water (the training task).

    Registered as ``shipgym/Tracking-v0`` (any vessel, ``vessel=``) and
    ``shipgym/BlueLadyTracking-v0`` (the Blue Lady).

    Each episode draws from the seeded generator 1-``max_legs`` legs: lateral (2-8 m either
    side), longitudinal (5-30 m ahead or 3-15 m astern), rotation (30-120 deg either way) or
    combined (surge and sway together), the distances for the Blue Lady's 13.78 m and scaled
    with the square root of the vessel's length overall (so that at Froude-scaled reference
    speeds an episode takes as long); and, by default, a wind of 0-``max_wind_speed`` m/s
    from any direction with the default gusts (4 m/s on the beam exceeds the 248 N m yaw
    capacity), a constant lake current of 0-``max_current_speed`` m/s in any direction
    (~1 % of the wind, assumed) and sensor noise within the lake presets (DGPS sigma
    0.07-0.15 m per axis, gyrocompass 0.2-0.45 deg) on top of the ``"default"`` sensors.
    The episode terminates when the last leg completes; time limit 800 control steps.

    Arguments (besides those of :class:`BlueLadyEnv`):

    | Argument | Default | Description |
    |---|---|---|
    | ``max_legs`` | ``3`` | most legs per episode (int >= 1) |
    | ``max_wind_speed`` | ``None`` | upper end of the drawn mean wind speed (m/s); ``None``: |
    |  |  | 7/6 of the vessel's nominal wind (3.5 m/s for the Blue Lady) |
    | ``max_current_speed`` | ``None`` | upper end of the drawn current speed (m/s); 0: none; |
    |  |  | ``None``: 1 % of the nominal wind (0.03 m/s for the Blue Lady) |
    | ``randomize_sensors`` | ``None`` | draw the sensor noise per episode; ``None``: unless |
    |  |  | ``sensors=`` is given |

    ``plan=``, ``wind=``, ``current=`` and ``sensors=`` given explicitly (in any accepted
    form; ``None`` for no wind, no current, no sensors) FIX that quantity for every episode:
    the draw is only the default, when the argument is not passed. ``randomize_sensors=True``
    together with ``sensors=`` draws the noise variances per episode on top of the given
    sensors. The draws are made in a fixed order (plan, wind, current when
    ``max_current_speed > 0``, sensors unless ``randomize_sensors=False``) even for a fixed
    quantity, and then discarded, so fixing one quantity leaves every other draw of the seed
    unchanged. ``max_current_speed=0`` and ``randomize_sensors=False`` switch those draws off
    (the shipped PPO baseline was trained so). ``wind_config``, ``current_config`` and
    ``sensor_config`` report the episode's values after :meth:`reset`. Spaces, reward and
    info: see :class:`ShipEnv`.
    """

    def __init__(
        self,
        max_legs: int = 3,
        max_wind_speed: float | None = None,
        max_current_speed: float | None = None,
        randomize_sensors: bool | None = None,
        **kwargs: Any,
    ) -> None:
        from shipgym.dynamics.vessel import load_vessel

        vessel = load_vessel(kwargs["vessel"]) if kwargs.get("vessel") is not None else None
        nominal = vessel.nominal_wind if vessel is not None else 3.0
        if max_wind_speed is None:
            max_wind_speed = 3.5 * nominal / 3.0
        if max_current_speed is None:
            max_current_speed = 0.01 * nominal
        # distances with sqrt(L): at Froude-scaled reference speeds (sqrt(L), the vessels'
        # [limits]) an episode takes about as long as the Blue Lady's and fits the time limit
        self._leg_scale = 1.0 if vessel is None else math.sqrt(vessel.L_oa / BLUE_LADY_HULL.L_oa)
        if not (isinstance(max_legs, int) and max_legs >= 1):
            raise ValueError(f"max_legs must be an int >= 1, got {max_legs!r}")
        if not (_finite_real(max_wind_speed) and 0 <= max_wind_speed <= MAX_WIND_SPEED):
            raise ValueError(
                f"max_wind_speed must be in [0, {MAX_WIND_SPEED:g}] m/s, got {max_wind_speed!r}"
            )
        if not (_finite_real(max_current_speed) and 0 <= max_current_speed <= MAX_CURRENT_SPEED):
            raise ValueError(
                f"max_current_speed must be in [0, {MAX_CURRENT_SPEED:g}] m/s, "
                f"got {max_current_speed!r}"
            )
        if randomize_sensors is not None and not isinstance(randomize_sensors, bool):
            raise ValueError(
                f"randomize_sensors must be True, False or None, got {randomize_sensors!r}"
            )
        self.max_legs = max_legs
        self.max_wind_speed = float(max_wind_speed)
        self.max_current_speed = float(max_current_speed)
        # an argument that is passed fixes its quantity; the draw is the default only
        self._draw_plan = "plan" not in kwargs
        self._draw_wind = "wind" not in kwargs
        self._draw_current = "current" not in kwargs
        # the sensor draw is made unless switched off explicitly, and used unless fixed
        self._sensor_draw = randomize_sensors is not False
        self.randomize_sensors = (
            "sensors" not in kwargs if randomize_sensors is None else randomize_sensors
        )
        kwargs.setdefault("scene", "open-water")
        kwargs.setdefault(
            "plan", ManoeuvrePlan(legs=(Leg(surge=10.0 * self._leg_scale),), name="tracking")
        )
        super().__init__(**kwargs)

    def _episode_plan(self) -> ManoeuvrePlan:
        rng = self.np_random
        k = self._leg_scale
        legs = []
        for i in range(int(rng.integers(1, self.max_legs + 1))):
            kind = int(rng.integers(4))
            side = 1.0 if rng.random() < 0.5 else -1.0
            if kind == 0:
                leg = Leg(sway=side * rng.uniform(2.0, 8.0) * k, name=f"{i + 1}: lateral")
            elif kind == 1:
                dist = rng.uniform(5.0, 30.0) if side > 0 else -rng.uniform(3.0, 15.0)
                leg = Leg(surge=dist * k, name=f"{i + 1}: longitudinal")
            elif kind == 2:
                yaw = side * math.radians(rng.uniform(30.0, 120.0))
                leg = Leg(yaw=yaw, name=f"{i + 1}: rotation")
            else:
                leg = Leg(
                    surge=rng.uniform(3.0, 15.0) * k, sway=side * rng.uniform(2.0, 5.0) * k,
                    name=f"{i + 1}: combined",
                )  # fmt: skip
            legs.append(leg)
        if not self._draw_plan:  # drawn all the same (same stream), then discarded
            return super()._episode_plan()
        return ManoeuvrePlan(legs=tuple(legs), name="tracking")

    def _episode_wind(self) -> WindConfig | None:
        rng = self.np_random
        speed = rng.uniform(0.0, self.max_wind_speed)  # drawn even when fixed (same stream)
        direction = rng.uniform(0.0, 2.0 * math.pi)
        if not self._draw_wind:
            return super()._episode_wind()
        return WindConfig(speed=speed, direction_from=direction)

    def _episode_current(self) -> CurrentConfig | None:
        if self.max_current_speed == 0.0:  # no draw: the random stream stays as without current
            return super()._episode_current()
        rng = self.np_random
        speed = rng.uniform(0.0, self.max_current_speed)
        direction = rng.uniform(0.0, 2.0 * math.pi)
        if not self._draw_current:
            return super()._episode_current()
        return CurrentConfig(speed=speed, direction_to=direction)

    def _episode_sensors(self) -> SensorConfig | None:
        given = super()._episode_sensors()
        if given is None or not self._sensor_draw:  # no sensors, or no draw: as given
            return given
        rng = self.np_random
        pos = rng.uniform(0.07, 0.15)  # drawn even when fixed (same stream)
        psi = math.radians(rng.uniform(0.2, 0.45))
        if not self.randomize_sensors:
            return given
        return given.replace(position_variance=pos * pos, heading_variance=psi * psi)


def _finite_real(x: Any) -> bool:
    return is_real(x) and math.isfinite(x)


def _blue_lady(cls: type[ShipEnv], name: str, doc: str) -> type[ShipEnv]:
    """The Blue Lady alias of a task class (``vessel="blue-lady"``, the same episodes)."""

    def __init__(self: Any, **kwargs: Any) -> None:
        vessel = kwargs.setdefault("vessel", "blue-lady")
        if vessel != "blue-lady":
            raise ValueError(
                f"{name} is the Blue Lady's task; for vessel={vessel!r} use the vessel-neutral "
                f"{cls.__name__} (gym.make('shipgym/{cls.__name__[:-3]}-v0', vessel=...))"
            )
        cls.__init__(self, **kwargs)

    return type(name, (cls,), {"__init__": __init__, "__doc__": doc, "__module__": __name__})


BlueLadyHarbourEnv = _blue_lady(
    HarbourEnv, "BlueLadyHarbourEnv", "``shipgym/BlueLadyHarbour-v0``: :class:`HarbourEnv` "
    "with the Blue Lady."
)  # fmt: skip
BlueLadyStationKeepingEnv = _blue_lady(
    StationKeepingEnv, "BlueLadyStationKeepingEnv", "``shipgym/BlueLadyStationKeeping-v0``: "
    ":class:`StationKeepingEnv` with the Blue Lady."
)  # fmt: skip
BlueLadyTrackingEnv = _blue_lady(
    TrackingEnv, "BlueLadyTrackingEnv", "``shipgym/BlueLadyTracking-v0``: :class:`TrackingEnv` "
    "with the Blue Lady."
)  # fmt: skip
