"""The registered tasks: harbour manoeuvre, station keeping, tracking, for any vessel.

Each task is one class, generic over the vessel (``vessel=``); the ``shipgym/BlueLady*-v0``
ids register the same classes with ``vessel="blue-lady"`` and give the same episodes as the
vessel-neutral ids with that vessel.
"""

from __future__ import annotations

from .base import ShipEnv
from .task import HarbourTask, StationKeepingTask, TrackingTask

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

    task_class = HarbourTask


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

    task_class = StationKeepingTask

    @property
    def random_wind(self) -> tuple[float, float] | None:
        """The range of the drawn mean wind speed (m/s; ``None``: the given wind)."""
        return self.task.random_wind


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

    task_class = TrackingTask

    @property
    def max_legs(self) -> int:
        return self.task.max_legs

    @property
    def max_wind_speed(self) -> float:
        return self.task.max_wind_speed

    @property
    def max_current_speed(self) -> float:
        return self.task.max_current_speed

    @property
    def randomize_sensors(self) -> bool:
        return self.task.randomize_sensors


def _blue_lady(cls: type[ShipEnv], name: str, doc: str) -> type[ShipEnv]:
    """The Blue Lady alias of a task class (``vessel="blue-lady"``, the same episodes)."""
    return type(name, (cls,), {"fixed_vessel": "blue-lady", "__doc__": doc, "__module__": __name__})


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
