r"""The numbers of a manoeuvring trial, and the IMO criteria (IMO MSC.137(76) (2002)).

Public names: ``TrialMetrics``, ``imo_criteria``, ``trial_metrics``, ``zigzag_limits``.

Design notes: docs/design/trials.metrics.md.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .manoeuvres import InitialTurning, Manoeuvre, Stop, TurningCircle, ZigZag, manoeuvre

__all__ = ["TrialMetrics", "imo_criteria", "trial_metrics", "zigzag_limits"]

Array = NDArray[np.float64]
_DEG = math.pi / 180.0


@dataclass(frozen=True)
class TrialMetrics:
    """A trial's figures (m, s, rad, m/s); ``None`` where one does not apply.

    Attributes:
        manoeuvre, kind: the manoeuvre's name and kind; angle: its rudder angle (rad).
        advance, transfer, tactical_diameter, steady_diameter: the turning circle's (m);
            steady_speed (m/s), speed_ratio (-); time_90, time_180, time_360 (s).
        overshoots: the zig-zag overshoot angles (rad, up to three); time_first_execute,
            period (s).
        initial_turning_distance, initial_turning_time: the initial turning test's (m, s).
        time_to_stop, head_reach, track_reach, lateral_deviation: a stop's (s, m);
            heading_change_at_stop (rad, signed), time_half_speed (s), track_half_speed (m).
        rudder_max: the largest ``|delta|`` (rad) when the rudder history was given.
        shaft: a stop's shaft command (fraction of ``n0``; < 0 the crash stop).
    """

    manoeuvre: str
    kind: str
    angle: float
    advance: float | None = None
    transfer: float | None = None
    tactical_diameter: float | None = None
    steady_diameter: float | None = None
    steady_speed: float | None = None
    speed_ratio: float | None = None
    time_90: float | None = None
    time_180: float | None = None
    time_360: float | None = None
    overshoots: tuple[float, ...] = ()
    time_first_execute: float | None = None
    period: float | None = None
    initial_turning_distance: float | None = None
    initial_turning_time: float | None = None
    time_to_stop: float | None = None
    head_reach: float | None = None
    track_reach: float | None = None
    lateral_deviation: float | None = None
    heading_change_at_stop: float | None = None
    time_half_speed: float | None = None
    track_half_speed: float | None = None
    rudder_max: float | None = None
    shaft: float | None = None

    def as_dict(self) -> dict[str, Any]:
        """The figures that apply (``None`` left out)."""
        return {k: v for k, v in dataclasses.asdict(self).items() if v is not None and v != ()}


def _crossing(t: Array, s: Array, level: float, start: int = 0) -> tuple[float, int] | None:
    """The first time ``s`` reaches ``level`` (``s`` rising through it) at or after
    ``start``, linearly interpolated, and the sample index after the crossing."""
    above = np.nonzero(s[start:] >= level)[0]
    if not above.size:
        return None
    i = start + int(above[0])
    if i == 0:
        return float(t[0]), 0
    f = (level - s[i - 1]) / (s[i] - s[i - 1])
    return float(t[i - 1] + f * (t[i] - t[i - 1])), i


def _interp(t: Array, y: Array, tc: float) -> float:
    return float(np.interp(tc, t, y))


def _circle_fit(x: Array, y: Array) -> tuple[float, float, float]:
    """Kasa's least-squares circle ``(xc, yc, radius)`` through the points."""
    A = np.c_[2 * x, 2 * y, np.ones_like(x)]
    b = x**2 + y**2
    (xc, yc, c), *_ = np.linalg.lstsq(A, b, rcond=None)
    return float(xc), float(yc), float(math.sqrt(c + xc**2 + yc**2))


def _check(t: ArrayLike, eta: ArrayLike, nu: ArrayLike) -> tuple[Array, Array, Array]:
    t = np.asarray(t, dtype=float).reshape(-1)
    eta = np.asarray(eta, dtype=float)
    nu = np.asarray(nu, dtype=float)
    n = t.size
    if n < 2 or eta.shape != (n, 3) or nu.shape != (n, 3):
        raise ValueError(
            f"t (n >= 2,), eta (n, 3) and nu (n, 3) needed, got {t.shape}, {eta.shape}, {nu.shape}"
        )
    if not (np.all(np.isfinite(t)) and np.all(np.diff(t) > 0)):
        raise ValueError("t must be finite and increasing")
    if not (np.all(np.isfinite(eta)) and np.all(np.isfinite(nu))):
        raise ValueError("eta and nu must be finite")
    return t, eta, nu


def trial_metrics(
    name_or_manoeuvre: str | Manoeuvre,
    t: ArrayLike,
    eta: ArrayLike,
    nu: ArrayLike,
    L: float,
    U0: float,
    delta: ArrayLike | None = None,
) -> TrialMetrics:
    """The figures of a recorded trial (module docstring).

    Args:
        name_or_manoeuvre: a name of :data:`~shipgym.trials.manoeuvres.MANOEUVRES` or a
            manoeuvre object.
        t: sample times (s), increasing, (n,); the manoeuvre starts at ``t[0]``.
        eta: the midship pose ``[x north m, y east m, psi rad]`` (n, 3).
        nu: body velocity ``[u m/s, v m/s, r rad/s]`` (n, 3).
        L: ship length (m); U0: the approach speed (m/s) (for the speed ratio and half speed).
        delta: optional rudder angle history (rad, (n,)): ``rudder_max``.

    Returns:
        :class:`TrialMetrics`.
    """
    m = manoeuvre(name_or_manoeuvre) if isinstance(name_or_manoeuvre, str) else name_or_manoeuvre
    if not isinstance(m, TurningCircle | ZigZag | InitialTurning | Stop):
        raise ValueError(f"not a manoeuvre: {name_or_manoeuvre!r}")
    if not (math.isfinite(L) and L > 0 and math.isfinite(U0) and U0 > 0):
        raise ValueError(f"L and U0 must be > 0, got {L!r}, {U0!r}")
    t, eta, nu = _check(t, eta, nu)
    psi = np.unwrap(eta[:, 2])
    psi0 = psi[0]
    dpsi = psi - psi0
    c0, s0 = math.cos(psi0), math.sin(psi0)
    dx, dy = eta[:, 0] - eta[0, 0], eta[:, 1] - eta[0, 1]
    along = c0 * dx + s0 * dy  # along the approach heading
    across = -s0 * dx + c0 * dy  # to starboard of it
    path = np.r_[0.0, np.cumsum(np.hypot(np.diff(eta[:, 0]), np.diff(eta[:, 1])))]
    speed = np.hypot(nu[:, 0], nu[:, 1])
    angle = float(getattr(m, "angle", 0.0))
    out: dict[str, Any] = {"manoeuvre": m.name, "kind": m.kind, "angle": angle}
    if delta is not None:
        d = np.asarray(delta, dtype=float).reshape(-1)
        if d.shape != t.shape:
            raise ValueError(f"delta must be (n,) = {t.shape}, got {d.shape}")
        out["rudder_max"] = float(np.max(np.abs(d)))

    if isinstance(m, TurningCircle):
        side = m.side
        h = side * dpsi
        lat = side * across
        for deg, key in ((90, "time_90"), (180, "time_180"), (360, "time_360")):
            c = _crossing(t, h, deg * _DEG)
            if c is None:
                continue
            tc = c[0]
            out[key] = tc
            if deg == 90:
                out["advance"] = _interp(t, along, tc)
                out["transfer"] = _interp(t, lat, tc)
            elif deg == 180:
                out["tactical_diameter"] = _interp(t, lat, tc)
        if h[-1] - h.min() >= 2 * math.pi:
            start = _crossing(t, h, h[-1] - 2 * math.pi)
            assert start is not None
            i = start[1]
            _, _, R = _circle_fit(eta[i:, 0], eta[i:, 1])
            out["steady_diameter"] = 2 * R
            out["steady_speed"] = float(np.mean(speed[i:]))
            out["speed_ratio"] = out["steady_speed"] / U0
    elif isinstance(m, ZigZag):
        side = m.side
        h = side * dpsi  # positive towards the first side
        executes: list[tuple[float, int]] = []
        towards, i = 1, 0
        while True:
            c = _crossing(t, towards * h, m.angle, i)
            if c is None:
                break
            executes.append(c)
            towards, i = -towards, c[1]
        over = []
        for k, (_, i0) in enumerate(executes[:3]):
            towards = 1 if k % 2 == 0 else -1
            last = k + 1 >= len(executes)
            seg = towards * h[i0 : (h.size if last else executes[k + 1][1])]
            j = int(np.argmax(seg))
            if last and j >= seg.size - 1:
                break  # the record ends before the heading turned back
            over.append(float(seg[j] - m.angle))
        out["overshoots"] = tuple(over)
        if executes:
            out["time_first_execute"] = executes[0][0] - float(t[0])
        if len(executes) >= 3:
            out["period"] = executes[2][0] - executes[0][0]
    elif isinstance(m, InitialTurning):
        c = _crossing(t, m.side * dpsi, m.heading_change)
        if c is not None:
            out["initial_turning_time"] = c[0] - float(t[0])
            out["initial_turning_distance"] = _interp(t, path, c[0])
    else:  # Stop
        out["shaft"] = m.shaft
        c = _crossing(t, -nu[:, 0], 0.0) if m.end_speed <= 0 else _crossing(t, -speed, -m.end_speed)
        if c is not None:
            tc = c[0]
            out["time_to_stop"] = tc - float(t[0])
            out["head_reach"] = _interp(t, along, tc)
            out["track_reach"] = _interp(t, path, tc)
            out["lateral_deviation"] = _interp(t, across, tc)
            out["heading_change_at_stop"] = _interp(t, dpsi, tc)
        c = _crossing(t, -speed, -0.5 * U0)
        if c is not None:
            out["time_half_speed"] = c[0] - float(t[0])
            out["track_half_speed"] = _interp(t, path, c[0])
    return TrialMetrics(**out)


def zigzag_limits(L_over_V: float) -> tuple[float, float, float]:
    """The IMO MSC.137(76) 5.3.3 overshoot limits (rad) at ``L/V`` (s): ``(first 10/10,
    second 10/10, first 20/20)``.

    First 10/10: 10 deg if ``L/V < 10`` s, 20 deg if ``L/V >= 30`` s, else ``5 + 0.5 L/V``
    deg; second 10/10: 25 deg, 40 deg, else ``17.5 + 0.75 L/V`` deg; first 20/20: 25 deg.
    """
    if not (math.isfinite(L_over_V) and L_over_V > 0):
        raise ValueError(f"L/V must be > 0 s, got {L_over_V!r}")
    if L_over_V < 10.0:
        a, b = 10.0, 25.0
    elif L_over_V >= 30.0:
        a, b = 20.0, 40.0
    else:
        a, b = 5.0 + 0.5 * L_over_V, 17.5 + 0.75 * L_over_V
    return a * _DEG, b * _DEG, 25.0 * _DEG


def imo_criteria(
    metrics: TrialMetrics, L: float, U0: float, *, track_reach_limit: float = 15.0
) -> list[tuple[str, float, float, bool]]:
    """The IMO MSC.137(76) Annex 5.3 criteria that apply to ``metrics``: ``(text, value, limit,
    passed)``, value and limit in m or rad.

    - turning (35 deg): advance <= 4.5 L, tactical diameter <= 5 L (5.3.1);
    - initial turning: distance <= 2.5 L at 10 deg heading change (5.3.2);
    - 10/10 zig-zag: first and second overshoots (:func:`zigzag_limits`); 20/20: first
      overshoot <= 25 deg (5.3.3);
    - crash stop (full astern, ``shaft < 0``): track reach <= 15 L (5.3.4; the Administration
      may allow more for ships of large displacement, never more than 20 L:
      ``track_reach_limit`` in ship lengths, at most 20).

    A figure that was not reached (``None``) fails its criterion with the value ``nan``.

    Args:
        metrics: :func:`trial_metrics`'s result.
        L: ship length (m); U0: the approach speed (m/s) (``L/V`` of the zig-zag limits).
        track_reach_limit: the stopping limit in ship lengths (15, up to 20).
    """
    if not (math.isfinite(L) and L > 0 and math.isfinite(U0) and U0 > 0):
        raise ValueError(f"L and U0 must be > 0, got {L!r}, {U0!r}")
    if not 0 < track_reach_limit <= 20:
        raise ValueError(
            f"track_reach_limit must be in (0, 20] ship lengths, got {track_reach_limit!r}"
        )
    out: list[tuple[str, float, float, bool]] = []

    def add(text: str, value: float | None, limit: float) -> None:
        v = math.nan if value is None else float(value)
        out.append((text, v, limit, bool(v <= limit)))

    kind = metrics.kind
    if kind == "turning":
        add("advance <= 4.5 L (IMO MSC.137(76) 5.3.1)", metrics.advance, 4.5 * L)
        add("tactical diameter <= 5 L (IMO MSC.137(76) 5.3.1)", metrics.tactical_diameter, 5 * L)
    elif kind == "initial_turning":
        add("initial turning distance at 10 deg <= 2.5 L (IMO MSC.137(76) 5.3.2)",
            metrics.initial_turning_distance, 2.5 * L)  # fmt: skip
    elif kind == "zigzag":
        first10, second10, first20 = zigzag_limits(L / U0)
        ov = list(metrics.overshoots) + [None, None]
        a = round(metrics.angle / _DEG, 6)
        if a == 10.0:
            add(f"10/10 first overshoot <= {first10 / _DEG:.1f} deg (IMO MSC.137(76) 5.3.3)",
                ov[0], first10)  # fmt: skip
            add(f"10/10 second overshoot <= {second10 / _DEG:.1f} deg (IMO MSC.137(76) 5.3.3)",
                ov[1], second10)  # fmt: skip
        elif a == 20.0:
            add("20/20 first overshoot <= 25 deg (IMO MSC.137(76) 5.3.3)", ov[0], first20)
    elif kind == "stop" and metrics.shaft is not None and metrics.shaft < 0:
        add(f"track reach <= {track_reach_limit:g} L (IMO MSC.137(76) 5.3.4)",
            metrics.track_reach, track_reach_limit * L)  # fmt: skip
    return out
