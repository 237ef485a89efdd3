"""Manoeuvre plans: legs, switching rule and limits as data (Tomera 2014 Fig. 7).

Public names: ``Leg``, ``ManoeuvrePlan``, ``tomera2014_plan``, ``PLANS``, ``plan``.

Design notes: docs/design/guidance.plan.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import MAX_ANGLE, param
from shipgym._text import did_you_mean

from .reference import Limits, leg_duration
from .rframe import from_r_frame

__all__ = ["Leg", "ManoeuvrePlan", "tomera2014_plan", "PLANS", "plan"]


#: the longest leg accepted (m): 1,000 km, far beyond any manoeuvre
MAX_LEG = 1.0e6


def _finite(owner: str, name: str, value: Any) -> float:
    if type(value) is float and math.isfinite(value):  # the common case, at once
        return value
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise ValueError(f"{owner}.{name} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{owner}.{name} must be finite, got {value!r}")
    return value


def _reject_unknown(d: Mapping[str, Any], valid: tuple[str, ...], where: str) -> None:
    if not isinstance(d, Mapping):
        raise ValueError(f"{where} must be a mapping, got {type(d).__name__}")
    unknown = sorted(set(d) - set(valid))
    if unknown:
        raise ValueError(f"unknown key(s) {unknown} in {where}; valid keys are: {', '.join(valid)}")


def _deg_or_rad(d: Mapping[str, Any], key: str, where: str, default: float) -> float:
    if key in d and f"{key}_deg" in d:
        raise ValueError(f"{where}: give either '{key}' (rad) or '{key}_deg' (deg), not both")
    if f"{key}_deg" in d:
        return math.radians(_finite(where, f"{key}_deg", d[f"{key}_deg"]))
    if key in d:
        return _finite(where, key, d[key])
    return default


@dataclass(frozen=True)
class Leg:
    """One leg of a manoeuvre: a displacement in the r-frame of the leg's start point P.

    Attributes:
        surge: displacement along the ship's heading at P (m, + forward).
        sway: displacement across it (m, + to starboard, - to port).
        yaw: heading change (rad, + clockwise / to starboard).
        name: a label for plots and reports.
        limits: optional :class:`Limits` for this leg only (override the plan's).
        delay: the reference rests at P for this long after the leg starts (s, >= 0).
        step: ``True``: the reference is a step, not a smooth profile: it jumps to the end
            point K at ``delay`` after the leg start, with zero velocity and acceleration
            (the set-point step of a DP test, Al-Takie 1982 ch. 5; the limits are not used).
    """

    surge: float = param(0.0, "m", "r-frame of the leg start (Tomera 2014 eq. 1)")
    sway: float = param(0.0, "m", "r-frame of the leg start (Tomera 2014 eq. 1)")
    yaw: float = param(0.0, "rad", "clockwise positive")
    name: str = ""
    limits: Limits | None = None
    delay: float = param(0.0, "s", "rest at P before the reference moves (project addition)")
    step: bool = param(False, "-", "step reference instead of the smooth profile (DP tests)")

    def __post_init__(self) -> None:
        for key in ("surge", "sway", "yaw"):
            object.__setattr__(self, key, _finite("Leg", key, getattr(self, key)))
        for key, bound, unit in (("surge", MAX_LEG, "m"), ("sway", MAX_LEG, "m"),
                                 ("yaw", MAX_ANGLE, "rad")):  # fmt: skip
            if abs(getattr(self, key)) > bound:
                raise ValueError(
                    f"Leg.{key} must be within +-{bound:g} {unit}, got {getattr(self, key)!r}: "
                    "a unit mistake (a leg is a manoeuvre, not a voyage)"
                )
        if not isinstance(self.name, str):
            raise ValueError(f"Leg.name must be a string, got {self.name!r}")
        if self.limits is not None and not isinstance(self.limits, Limits):
            raise ValueError(f"Leg.limits must be a Limits or None, got {self.limits!r}")
        delay = _finite("Leg", "delay", self.delay)
        if delay < 0.0:
            raise ValueError(f"Leg.delay must be >= 0 s, got {delay!r}")
        object.__setattr__(self, "delay", delay)
        if not isinstance(self.step, bool):
            raise ValueError(f"Leg.step must be True or False, got {self.step!r}")

    @property
    def displacement(self) -> NDArray[np.float64]:
        """``[surge, sway, yaw]`` (m, m, rad), shape (3,)."""
        return np.array([self.surge, self.sway, self.yaw])

    _KEYS = ("surge", "sway", "yaw", "yaw_deg", "name", "limits", "delay", "step")

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], where: str = "leg") -> Leg:
        """Build from a mapping; ``yaw`` in rad or ``yaw_deg`` in degrees; ``limits`` a dict;
        ``delay`` (s) and ``step`` (bool) optional.

        Raises:
            ValueError: unknown keys (the message lists the valid ones), non-finite values.
        """
        _reject_unknown(d, cls._KEYS, where)
        lim = d.get("limits")
        if isinstance(lim, Mapping):
            lim = Limits.from_dict(dict(lim))
        return cls(
            surge=_finite(where, "surge", d.get("surge", 0.0)),
            sway=_finite(where, "sway", d.get("sway", 0.0)),
            yaw=_deg_or_rad(d, "yaw", where, 0.0),
            name=d.get("name", ""),
            limits=lim,
            delay=d.get("delay", 0.0),
            step=d.get("step", False),
        )

    def to_dict(self) -> dict[str, Any]:
        """A plain dict that :meth:`from_dict` reads back (SI units, yaw in rad)."""
        out: dict[str, Any] = {"surge": self.surge, "sway": self.sway, "yaw": self.yaw}
        out["name"] = self.name
        if self.limits is not None:
            out["limits"] = self.limits.to_dict()
        if self.delay:
            out["delay"] = self.delay
        if self.step:
            out["step"] = True
        return out


@dataclass(frozen=True)
class ManoeuvrePlan:
    """A sequence of legs with its switching rule and reference limits (plans are data).

    Attributes:
        legs: the legs, in order (at least one).
        switch_distance: the ship must be closer than this to the leg's planned end point K
            (m; Tomera 2014: 1 m).
        switch_heading: and its heading error to K's heading must be below this (rad, wrapped;
            Tomera (2014): 5 deg).
        limits: speed/acceleration limits of the reference (per leg overridable); ``None``
            (default): the vessel's, given to :class:`~shipgym.guidance.Guidance` (the
            environments pass ``Limits.from_dict(vessel.limits)``).
        switch_min_progress: fraction of the leg's reference duration that must have elapsed
            before the leg may be switched (0: the paper's rule alone; 1, default: the
            reference must have reached K). Guards against premature switches, e.g. a leg
            shorter than ``switch_distance`` or a rotation smaller than ``switch_heading``.
        settle_time: the switching conditions must hold continuously this long (s; 0 = at
            the first instant they hold).
        name: the plan's name.
    """

    legs: tuple[Leg, ...]
    switch_distance: float = param(1.0, "m", "Tomera (2014) (manoeuvre description): 1 m")
    switch_heading: float = param(
        math.radians(5.0), "rad", "Tomera (2014): course difference < 5 deg"
    )
    limits: Limits | None = None
    switch_min_progress: float = param(1.0, "1", "guard against premature switching (ours)")
    settle_time: float = param(0.0, "s", "optional dwell before switching (project addition)")
    name: str = "custom"

    def __post_init__(self) -> None:
        legs = self.legs
        if isinstance(legs, Leg) or not isinstance(legs, list | tuple):
            raise ValueError(f"ManoeuvrePlan.legs must be a sequence of Leg, got {legs!r}")
        legs = tuple(legs)
        if not legs:
            raise ValueError("ManoeuvrePlan.legs is empty; a plan needs at least one Leg")
        for i, leg in enumerate(legs):
            if not isinstance(leg, Leg):
                raise ValueError(f"ManoeuvrePlan.legs[{i}] must be a Leg, got {leg!r}")
        object.__setattr__(self, "legs", legs)
        sd = _finite("ManoeuvrePlan", "switch_distance", self.switch_distance)
        sh = _finite("ManoeuvrePlan", "switch_heading", self.switch_heading)
        mp = _finite("ManoeuvrePlan", "switch_min_progress", self.switch_min_progress)
        st = _finite("ManoeuvrePlan", "settle_time", self.settle_time)
        if not sd > 0.0:
            raise ValueError(f"ManoeuvrePlan.switch_distance must be > 0 m, got {sd}")
        if not 0.0 < sh <= math.pi:
            raise ValueError(f"ManoeuvrePlan.switch_heading must be in (0, pi] rad, got {sh}")
        if not 0.0 <= mp <= 1.0:
            raise ValueError(f"ManoeuvrePlan.switch_min_progress must be in [0, 1], got {mp}")
        if not st >= 0.0:
            raise ValueError(f"ManoeuvrePlan.settle_time must be >= 0 s, got {st}")
        if self.limits is not None and not isinstance(self.limits, Limits):
            raise ValueError(f"ManoeuvrePlan.limits must be a Limits or None, got {self.limits!r}")
        if not isinstance(self.name, str):
            raise ValueError(f"ManoeuvrePlan.name must be a string, got {self.name!r}")
        for key, val in (
            ("switch_distance", sd),
            ("switch_heading", sh),
            ("switch_min_progress", mp),
            ("settle_time", st),
        ):
            object.__setattr__(self, key, val)

    @property
    def n_legs(self) -> int:
        """Number of legs."""
        return len(self.legs)

    def leg_limits(self, i: int, limits: Limits | None = None) -> Limits | None:
        """The limits that apply to leg ``i``: its own, else the plan's, else ``limits``."""
        own = self.legs[i].limits
        if own is not None:
            return own
        return self.limits if self.limits is not None else limits

    def durations(self, limits: Limits | None = None) -> tuple[float, ...]:
        """Reference duration of each leg (s) under its limits (``limits``: the vessel's,
        used where neither the leg nor the plan has its own)."""
        lim = self.limits if self.limits is not None else limits
        return tuple(leg_duration(leg, lim) for leg in self.legs)

    def waypoints(self, eta_start: ArrayLike) -> NDArray[np.float64]:
        """Planned NED poses ``[P_0, K_0, K_1, ...]``, shape (n_legs + 1, 3) (m, m, rad).

        ``P_0 = eta_start``, ``K_i = from_r_frame(leg_i.displacement, P_i)``,
        ``P_{i+1} = K_i``. Headings are not wrapped (they accumulate the legs' yaw from the
        start heading), so they never jump across 0/360 deg.
        """
        p = np.asarray(eta_start, dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"eta_start must be a finite [x, y, psi] (m, m, rad), got {p!r}")
        out = np.empty((self.n_legs + 1, 3))
        out[0] = p
        for i, leg in enumerate(self.legs):
            out[i + 1] = from_r_frame(leg.displacement, out[i])
        return out

    _KEYS = (
        "legs",
        "switch_distance",
        "switch_heading",
        "switch_heading_deg",
        "limits",
        "switch_min_progress",
        "settle_time",
        "name",
    )

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> ManoeuvrePlan:
        """Build a plan from plain data (e.g. parsed YAML/JSON), validating everything.

        Keys: ``legs`` (list of leg mappings, see :meth:`Leg.from_dict`), ``switch_distance``
        (m), ``switch_heading`` (rad) or ``switch_heading_deg`` (deg), ``limits`` (mapping of
        :class:`Limits` fields), ``switch_min_progress``, ``settle_time`` (s), ``name``.

        Raises:
            ValueError: unknown keys (listing the valid ones), missing or empty ``legs``,
                non-finite or out-of-range values.
        """
        _reject_unknown(d, cls._KEYS, "plan")
        if "legs" not in d:
            raise ValueError("plan has no 'legs'; give a non-empty list of leg mappings")
        raw = d["legs"]
        if isinstance(raw, Mapping | str) or not isinstance(raw, list | tuple):
            raise ValueError(f"plan 'legs' must be a list of leg mappings, got {raw!r}")
        legs = tuple(
            leg if isinstance(leg, Leg) else Leg.from_dict(leg, where=f"plan legs[{i}]")
            for i, leg in enumerate(raw)
        )
        lim = d.get("limits")
        if isinstance(lim, Mapping):
            lim = Limits.from_dict(dict(lim))
        kwargs: dict[str, Any] = {"legs": legs, "limits": lim}
        kwargs["switch_heading"] = _deg_or_rad(d, "switch_heading", "plan", math.radians(5.0))
        for key in ("switch_distance", "switch_min_progress", "settle_time", "name"):
            if key in d:
                kwargs[key] = d[key]
        return cls(**kwargs)

    def to_dict(self) -> dict[str, Any]:
        """A plain dict that :meth:`from_dict` reads back (SI units)."""
        out: dict[str, Any] = {
            "name": self.name,
            "legs": [leg.to_dict() for leg in self.legs],
            "switch_distance": self.switch_distance,
            "switch_heading": self.switch_heading,
        }
        if self.limits is not None:
            out["limits"] = self.limits.to_dict()
        out["switch_min_progress"] = self.switch_min_progress
        out["settle_time"] = self.settle_time
        return out


def tomera2014_plan(**overrides: Any) -> ManoeuvrePlan:
    """The 5-leg harbour manoeuvre of Tomera (2014) (Fig. 7) with its switching rule (1 m, 5 deg).

    The rotation is taken clockwise (``yaw = +pi/2``; the paper gives no sign).

    Args:
        **overrides: plan fields to replace (e.g. ``limits=Limits(...)``, ``settle_time=5``).
    """
    legs = (
        Leg(sway=-7.0, name="1: lateral to port 7 m"),
        Leg(surge=38.0, name="2: forward 38 m"),
        Leg(yaw=math.pi / 2.0, name="3: rotate 90 deg clockwise"),
        Leg(surge=-15.0, name="4: backward 15 m"),
        Leg(sway=-3.0, name="5: lateral to port 3 m"),
    )
    kwargs: dict[str, Any] = {
        "legs": legs,
        "switch_distance": 1.0,
        "switch_heading": math.radians(5.0),
        "name": "tomera2014",
    }
    kwargs.update(overrides)
    return ManoeuvrePlan(**kwargs)


PLANS: dict[str, Callable[..., ManoeuvrePlan]] = {"tomera2014": tomera2014_plan}


def plan(name: str, **overrides: Any) -> ManoeuvrePlan:
    """A registered plan by name (see ``PLANS``); ``overrides`` replace plan fields.

    Raises:
        ValueError: unknown name (the message lists the valid names).
    """
    try:
        factory = PLANS[name]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown manoeuvre plan {name!r}{did_you_mean(name, PLANS)}; valid names are: "
            f"{', '.join(sorted(PLANS))}"
        ) from None
    return factory(**overrides)
