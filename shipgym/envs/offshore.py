r"""Offshore dynamic-positioning tasks of Al-Takie (1982): station keeping and the sway step.

Sources: Al-Takie (1982) (the thesis: Wimpey Sealab and Star Hercules, per-unit time App. 1,
sampling App. 3, sensor noise 2.4.2, Beaufort 8 wind 3.2.3, HF wave filter App. 2, the
0.02 p.u. sway-step test ch. 5); WMO (1998) and NORSOK N-003 (the Beaufort table of
:mod:`shipgym.scenarios`); Fossen (2011) ch. 8.3 (Gauss-Markov current). Full entries:
``docs/references.md``.

Both tasks are generic over the vessel (``vessel=``): the thesis's vessels are at full scale
(``vessel.scale == 1``); any other (the 1:24 Blue Lady) gets the same sea, current, sensors
and timing Froude-scaled with ``vessel.scale`` (lengths ``/ scale``, times and speeds
``/ sqrt(scale)``) and with its own per-unit time ``sqrt(L_pp / g)`` (the bis system of
Fossen, used by the thesis: App. 1).
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

from shipgym.disturbances import CurrentConfig
from shipgym.disturbances.seastate import BEAUFORT_TABLE, beaufort
from shipgym.disturbances.spectra import G
from shipgym.disturbances.waves import WF_MODELS, al_takie_hf_peak_frequency
from shipgym.dynamics.vessel import load_vessel
from shipgym.guidance import Leg, ManoeuvrePlan
from shipgym.observers.sensors import sensor_config

from .spec import check_control_period
from .tasks import StationKeepingEnv

__all__ = [
    "AL_TAKIE1982_MEAN_WIND",
    "DP_BEAUFORT",
    "DP_CURRENT",
    "MAX_DP_TIMESTEP",
    "OffshoreDPEnv",
    "SwayStepEnv",
    "beaufort_sea",
    "dp_control_period",
    "dp_current",
    "dp_mean_wind",
    "dp_timing",
]

#: Beaufort numbers of the DP tasks: those of Al-Takie's (1982) HF wave-filter table (App. 2)
DP_BEAUFORT: tuple[int, ...] = (5, 6, 7, 8, 9)

#: mean winds (m/s, full scale, 10 m) that the thesis prints, replacing the middle of the WMO
#: band for those Beaufort numbers: Beaufort 8, "mean wind 19 m/s" (Al-Takie 1982 3.2.3,
#: printed; the WMO band 17.2-20.7 m/s has its middle at 18.95 m/s)
AL_TAKIE1982_MEAN_WIND: Mapping[int, float] = MappingProxyType({8: 19.0})

#: the default offshore current, full scale (Froude-scaled with the vessel): [chosen] a mean
#: of 0.5 m/s (the lower end of the project's offshore assumption of 0.5-1 m/s, see
#: :class:`~shipgym.disturbances.CurrentConfig`, as the packaged ``beaufort5-offshore``
#: scenario; the thesis prints no current), slowly varying
#: (first-order Gauss-Markov, Fossen 2011 ch. 8.3) with a stationary std of 0.05 m/s and a
#: time constant of 1500 s (the scenario's 300 s at 1:24 is 1470 s at full scale), bounded to
#: [0, 1] m/s; it sets east (to 90 deg), across the heading of a ship heading north, the
#: harder case for a DP system (sway and yaw)
DP_CURRENT: Mapping[str, float] = MappingProxyType(
    {"speed": 0.5, "std": 0.05, "time_constant": 1500.0, "v_max": 1.0, "direction_to_deg": 90.0}
)

#: largest physics timestep of the DP tasks (s): the control period is split into the fewest
#: whole steps of at most this (the default timestep of every other task)
MAX_DP_TIMESTEP = 0.05

#: the control period in per-unit time (Al-Takie 1982 App. 3: "dt = 0.1", read in p.u. time,
#: which makes the printed gain-settling times consistent; 0.3104 s Wimpey, 0.2728 s Star
#: Hercules)
DP_CONTROL_PERIOD_PU = 0.1


def dp_mean_wind(n: int) -> float:
    """The full-scale mean wind (m/s) of Beaufort ``n`` in the DP tasks.

    The WMO band middle of :data:`shipgym.scenarios.BEAUFORT_TABLE`, except where
    :data:`AL_TAKIE1982_MEAN_WIND` holds the thesis's printed value (Beaufort 8: 19.0 m/s).
    """
    _check_beaufort(n)
    return float(AL_TAKIE1982_MEAN_WIND.get(int(n), BEAUFORT_TABLE[int(n)].U10))


def dp_control_period(L_pp: float) -> float:
    """``0.1 sqrt(L_pp / g)`` (s): 0.1 per-unit time (Al-Takie 1982 App. 3) for ``L_pp`` in m.

    0.3104 s for Wimpey Sealab (94.49 m), 0.2728 s for Star Hercules (73 m), 0.117 s for the
    1:24 Blue Lady (13.5 m) (``g`` = 9.81 m/s^2).
    """
    if not (isinstance(L_pp, numbers.Real) and math.isfinite(L_pp) and L_pp > 0):
        raise ValueError(f"L_pp must be a length > 0 m, got {L_pp!r}")
    return DP_CONTROL_PERIOD_PU * math.sqrt(float(L_pp) / G)


def dp_timing(control_period: float, max_timestep: float = MAX_DP_TIMESTEP) -> tuple[float, int]:
    """``(timestep s, k)``: the control period split into the fewest ``k`` whole physics steps
    of at most ``max_timestep`` (``timestep = control_period / k``)."""
    k = max(1, math.ceil(control_period / max_timestep - 1e-9))
    return control_period / k, k


def _check_beaufort(n: Any) -> None:
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or int(n) not in DP_BEAUFORT:
        raise ValueError(
            f"beaufort must be an int from {DP_BEAUFORT[0]} to {DP_BEAUFORT[-1]} (the rows of "
            f"Al-Takie's (1982) HF wave-filter table), got {n!r}"
        )


def _check_number(x: Any, name: str, unit: str, lo: float | None = None) -> float:
    if isinstance(x, bool) or not isinstance(x, numbers.Real) or not math.isfinite(x):
        raise ValueError(f"{name} must be a finite number ({unit}), got {x!r}")
    if lo is not None and not float(x) >= lo:
        raise ValueError(f"{name} must be >= {lo:g} {unit}, got {x!r}")
    return float(x)


class OffshoreDPEnv(StationKeepingEnv):
    r"""Dynamic positioning offshore: hold the set-point in Beaufort 5-9 (Al-Takie 1982).

    Registered as ``shipgym/DPStationKeeping-v0`` (any vessel, ``vessel=``; the thesis's
    ``"wimpey-sealab"`` and ``"star-hercules"`` at full scale, the Blue Lady Froude-scaled).

    ## Description
    One zero-displacement leg on open water: the ship starts at rest on the set-point
    (``start_pose``, default the origin heading north) and must hold it against wind, waves
    and current. The measured pose carries the first-order wave-frequency (HF) motion, which
    the hull does not live (Al-Takie's measurement ``z = x_LF + x_HF + v``): a DP filter has
    to remove it (the thesis's problem). Spaces (the action and observation of
    :class:`~shipgym.envs.base.ShipEnv`: one normalised command per actuator channel;
    body-frame pose error, velocities, reference and previous action, in m, rad, m/s, rad/s),
    reward and info: see :class:`~shipgym.envs.base.ShipEnv`.

    ## Disturbances
    * Wind and waves: :func:`shipgym.scenarios.beaufort` ``(beaufort, scale=vessel.scale,
      direction_from=direction_from_deg, wf_model=wave_motion, first_order=True,
      drift=True)``: the WMO mean wind with NPD gusts (the preset's), a JONSWAP gamma 3.3
      sea (WMO ``Hs``, NORSOK ``Tp``) with second-order drift on the hull and first-order
      motion on the measurements; with one change: the mean wind is :func:`dp_mean_wind`,
      Beaufort 8 = 19.0 m/s full scale [printed, Al-Takie (1982) 3.2.3] instead of the WMO
      18.95 m/s (:data:`AL_TAKIE1982_MEAN_WIND`).
    * HF motion (``wave_motion``): ``"al-takie"`` (default), the thesis's 4th-order HF
      filter ``K s^2 / (s^4 + c1 s^3 + c2 s^2 + c3 s + c4)`` of the Beaufort row (App. 2) at
      its own frequencies, Froude-scaled: peak at 0.128 Hz (BF5), 0.100, 0.088, 0.083,
      0.069 Hz (BF9) at full scale, times ``sqrt(vessel.scale)``
      (:func:`~shipgym.disturbances.waves.al_takie_hf_peak_frequency`); ``"rao"``, motion
      coherent with the JONSWAP components of the sea (peak at ``w_p``); ``"fossen"``,
      Fossen's 2nd-order shaping filter at ``w_p``. Std ``Hs / 16`` along the waves and the
      :class:`~shipgym.disturbances.WaveConfig` heading default.
    * Current: :data:`DP_CURRENT` [chosen, see there]: 0.5 m/s full scale, Gauss-Markov
      (std 0.05 m/s, time constant 1500 s), Froude-scaled, going to
      ``current_direction_to_deg`` (default 90 deg: east).
    * ``direction_from_deg`` (default 45 deg, [chosen]): wind and waves come from 45 deg off
      the starboard bow of a ship heading north, so that they load surge, sway and yaw at
      once (head seas would load surge only, beam seas mostly sway); the thesis's LF model
      is the coupled sway-yaw one (eqs. 3.21-3.26).

    ``wind=``, ``waves=`` and ``current=`` of :class:`~shipgym.envs.base.ShipEnv`, when
    passed (``None`` included), override these.

    ## Sensors and timing
    * ``sensors`` default ``"al-takie1982"``: position-reference sigma 1/3 m per axis, gyro
      sigma 0.02 rad [printed, Al-Takie (1982) 2.4.2], no faults, sampled every control
      period; for a model (``vessel.scale > 1``) the position sigma is Froude-scaled
      (``/ scale``). Any preset *name* is sampled every control period; a
      :class:`~shipgym.observers.sensors.SensorConfig` or mapping is used as given.
    * ``control_period`` default :func:`dp_control_period` ``= 0.1 sqrt(L_pp / g)``: 0.1
      per-unit time (Al-Takie 1982 App. 3; 0.3104 s Wimpey Sealab, 0.2728 s Star Hercules).
    * ``timestep`` default ``control_period / k`` with the smallest whole ``k`` giving
      ``<= 0.05 s`` (:func:`dp_timing`: 7 steps of 0.0443 s for Wimpey Sealab).

    ## Starting State
    At rest on the set-point (``start_noise`` default zero: DP holding; pass it for a
    perturbed start); gusts, waves, current and sensor noise from the seeded generator.

    ## Episode End
    Never terminates on reaching the pose. Truncated after ``episode_duration`` seconds
    (default 2000 s; the env itself truncates, with ``info["episode_metrics"]``, since the
    number of control steps depends on the vessel's control period: 6445 steps for Wimpey
    Sealab, 7332 for Star Hercules; the ids are registered without ``max_episode_steps``).
    ``gym.make``'s ``max_episode_steps`` adds a ``TimeLimit`` on top.

    ## Arguments (besides those of :class:`~shipgym.envs.base.ShipEnv`)
    | Argument | Default | Description |
    |---|---|---|
    | ``beaufort`` | ``5`` | Beaufort number, an int 5-9 |
    | ``wave_motion`` | ``"al-takie"`` | HF motion model: ``"al-takie"``, ``"rao"``, ``"fossen"`` |
    | ``direction_from_deg`` | ``45`` | where wind and waves come from (deg, clockwise from N) |
    | ``current_direction_to_deg`` | ``90`` | where the default current goes (deg) |
    | ``episode_duration`` | ``2000`` | episode length (s) |

    Raises:
        ValueError: ``beaufort`` not an int 5-9, an unknown ``wave_motion``, a non-finite
            direction, ``episode_duration <= 0``, or a control period that is not a whole
            multiple of the timestep.

    ## Version History
    * v0: initial version.
    """

    #: the default episode length (s)
    default_duration = 2000.0

    #: the thesis's system assumes mean-wind feedforward (Al-Takie 1982 2.4, Fig. 1.1) and a
    #: current known at the LF model's linearisation point (3.1):
    #: :mod:`shipgym.controllers.feedforward`
    default_feedforward = "wind+current"

    @classmethod
    def configure(cls, kwargs: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        """The env's arguments with the DP task's defaults (timing, sea, current, sensors,
        plan) filled in, and its own settings (``beaufort``, ``wave_motion``,
        ``direction_from_deg``, ``episode_duration``): what the single env and the vector env
        of this class both start from."""
        kwargs = dict(kwargs)
        beaufort = kwargs.pop("beaufort", 5)
        wave_motion = kwargs.pop("wave_motion", "al-takie")
        direction_from_deg = kwargs.pop("direction_from_deg", 45.0)
        current_to_deg = kwargs.pop("current_direction_to_deg", DP_CURRENT["direction_to_deg"])
        duration = kwargs.pop("episode_duration", cls.default_duration)
        _check_beaufort(beaufort)
        if not isinstance(wave_motion, str) or wave_motion not in WF_MODELS:
            raise ValueError(
                f"wave_motion must be one of {', '.join(map(repr, WF_MODELS))}, got {wave_motion!r}"
            )
        direction = _check_number(direction_from_deg, "direction_from_deg", "deg")
        current_to = _check_number(current_to_deg, "current_direction_to_deg", "deg")
        duration = _check_number(duration, "episode_duration", "s")
        if not duration > 0:
            raise ValueError(f"episode_duration must be > 0 s, got {duration!r}")
        extras = {
            "beaufort": int(beaufort),
            "wave_motion": wave_motion,
            "direction_from_deg": direction,
            "episode_duration": duration,
        }
        if kwargs.get("vessel") is None:
            return kwargs, extras  # the task explains that a vessel is needed
        vessel = load_vessel(kwargs["vessel"])
        kwargs["vessel"] = vessel
        scale = float(vessel.scale)
        # timing: 0.1 p.u. control period, whole physics steps of <= 0.05 s
        if "control_period" not in kwargs:
            kwargs["control_period"] = dp_control_period(vessel.hull.L_pp)
        cp = kwargs["control_period"]
        check_control_period(cp)  # before the timing is derived from it
        if "timestep" not in kwargs:
            kwargs["timestep"] = dp_timing(float(cp))[0]
        # wind and waves: the Beaufort preset, Al-Takie's printed Beaufort 8 wind
        sea = beaufort_sea(int(beaufort), scale, math.radians(direction), wave_motion)
        kwargs.setdefault("wind", sea.wind)
        kwargs.setdefault("waves", sea.waves)
        if "current" not in kwargs:
            kwargs["current"] = dp_current(scale, math.radians(current_to))
        # sensors: a preset name is sampled every control period
        sensors = kwargs.get("sensors", "al-takie1982")
        if isinstance(sensors, str):
            over: dict[str, Any] = {"period": kwargs["control_period"]}
            if sensors == "al-takie1982" and scale != 1.0:
                base = sensor_config(sensors)
                over["position_variance"] = base.position_variance / (scale * scale)
            sensors = sensor_config(sensors, **over)
        kwargs["sensors"] = sensors
        kwargs.setdefault("start_noise", (0.0, 0.0, 0.0))
        kwargs.setdefault("plan", ManoeuvrePlan(legs=(Leg(name="hold"),), name="dp-hold"))
        return kwargs, extras


class SwayStepEnv(OffshoreDPEnv):
    r"""The thesis's test: a sway set-point step of 0.02 L_pp while holding (Al-Takie 1982).

    Registered as ``shipgym/DPSwayStep-v0`` (any vessel, ``vessel=``).

    Everything as :class:`OffshoreDPEnv` (disturbances, sensors, timing, spaces, reward,
    info), except the plan: the ship holds the start pose, and at ``step_time`` (default
    100 s) the sway set-point steps by ``step`` to starboard (default ``0.02 L_pp``:
    "0.02 p.u. step into sway" [printed, Al-Takie (1982) ch. 5]: 1.89 m for Wimpey Sealab,
    1.46 m for Star Hercules, 0.27 m for the 1:24 Blue Lady), heading set-point unchanged.
    The reference is a true step (:class:`~shipgym.guidance.Leg` with ``step=True`` and
    ``delay=step_time``): it jumps at ``step_time`` with zero reference velocity and
    acceleration, the thesis's test input, not a smoothed manoeuvre. The leg is complete
    once the ship is within 1 m and 5 deg of the new set-point after the step; the episode
    never terminates on it. Episode 400 s by default (``episode_duration``). The metrics
    (:class:`shipgym.metrics.ManoeuvreMetrics`) are those of the one leg.

    ## Arguments (besides those of :class:`OffshoreDPEnv`)
    | Argument | Default | Description |
    |---|---|---|
    | ``step_time`` | ``100`` | when the set-point steps (s), ``>= 0`` |
    | ``step`` | ``None`` | the step to starboard (m; negative: to port); ``None``: ``0.02 L_pp`` |
    | ``episode_duration`` | ``400`` | episode length (s) |

    Raises:
        ValueError: as :class:`OffshoreDPEnv`, and a negative or non-finite ``step_time`` or
            a non-finite ``step``.

    ## Version History
    * v0: initial version.
    """

    #: the step in per-unit length (Al-Takie 1982 ch. 5, printed: 0.02 p.u. into sway)
    STEP_PU = 0.02

    default_duration = 400.0

    @classmethod
    def configure(cls, kwargs: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        """:meth:`OffshoreDPEnv.configure` with the sway-step plan (``step_time``, ``step``)."""
        kwargs = dict(kwargs)
        t_step = _check_number(kwargs.pop("step_time", 100.0), "step_time", "s", lo=0.0)
        step = kwargs.pop("step", None)
        if step is not None:
            step = _check_number(step, "step", "m")
        if kwargs.get("vessel") is not None:
            vessel = load_vessel(kwargs["vessel"])
            kwargs["vessel"] = vessel
            if step is None:
                step = cls.STEP_PU * float(vessel.hull.L_pp)
            kwargs.setdefault(
                "plan",
                ManoeuvrePlan(
                    legs=(Leg(sway=step, delay=t_step, step=True, name="sway step"),),
                    name="sway-step",
                ),
            )
        kwargs, extras = super().configure(kwargs)
        return kwargs, {**extras, "step_time": t_step, "step_size": step}


def beaufort_sea(n: int, scale: float, direction_from: float, wave_motion: str) -> Any:
    """The DP tasks' sea state: :func:`shipgym.scenarios.beaufort` with :func:`dp_mean_wind`.

    Args:
        n: Beaufort number 5-9.
        scale: Froude scale of the vessel (1: full scale).
        direction_from: where wind and waves come from (rad).
        wave_motion: ``"al-takie"``, ``"rao"`` or ``"fossen"``; ``"al-takie"`` keeps the
            thesis's own HF frequencies (Froude-scaled) instead of moving its peak to the
            JONSWAP ``w_p``.

    Returns:
        ``SeaState(wind, waves)``.
    """
    _check_beaufort(n)
    sea = beaufort(
        n,
        scale=scale,
        direction_from=direction_from,
        wf_model=wave_motion,
        first_order=True,
        drift=True,
    )
    wind = dataclasses.replace(sea.wind, speed=dp_mean_wind(n) / math.sqrt(scale))
    waves = sea.waves
    if wave_motion == "al-takie":
        peak = al_takie_hf_peak_frequency(n) * math.sqrt(scale)
        waves = dataclasses.replace(waves, wf_peak_frequency=peak)
    return type(sea)(wind, waves)


def dp_current(scale: float, direction_to: float) -> CurrentConfig:
    """:data:`DP_CURRENT` Froude-scaled to ``1:scale``, going to ``direction_to`` (rad)."""
    sq = math.sqrt(scale)
    tc = DP_CURRENT["time_constant"] / sq
    mu = 1.0 / tc
    return CurrentConfig(
        speed=DP_CURRENT["speed"] / sq,
        direction_to=direction_to,
        mu=mu,
        sigma=DP_CURRENT["std"] / sq * math.sqrt(2.0 * mu),
        v_max=DP_CURRENT["v_max"] / sq,
        direction_mu=mu,
    )
