"""Smooth reference trajectories of a manoeuvre leg (Tomera 2014 Fig. 3).

Public names: ``BLUE_LADY_LIMITS``, ``Limits``, ``LegProfile``, ``leg_profile``, ``leg_reference``,
``leg_duration``, ``path_law``.
Sources: Tomera (2014); Al-Takie (1982).

Design notes: docs/design/guidance.reference.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import from_mapping, require_finite, require_positive, required_param
from shipgym._jit import njit

if TYPE_CHECKING:  # pragma: no cover - typing only (plan.py imports this module)
    from .plan import Leg

__all__ = [
    "BLUE_LADY_LIMITS",
    "Limits",
    "LegProfile",
    "leg_profile",
    "leg_reference",
    "leg_duration",
    "path_law",
]


@dataclass(frozen=True)
class Limits:
    """Speed and acceleration limits of the reference per DOF (r-frame of the leg).

    Every field must be given (no vessel is a default): a vessel's limits come from its file
    (``Limits.from_dict(load_vessel(name).limits)``, chosen from its thrust capacity); the
    Blue Lady's are :data:`BLUE_LADY_LIMITS`. Each field's ``metadata`` holds its unit. Astern
    surge has its own limits (a main propeller is usually weaker astern).
    """

    surge_speed: float = required_param("m/s", "largest reference surge speed ahead")
    surge_accel: float = required_param("m/s^2", "largest reference surge acceleration ahead")
    surge_astern_speed: float = required_param("m/s", "largest reference surge speed astern")
    surge_astern_accel: float = required_param(
        "m/s^2", "largest reference surge acceleration astern"
    )
    sway_speed: float = required_param("m/s", "largest reference sway speed")
    sway_accel: float = required_param("m/s^2", "largest reference sway acceleration")
    yaw_rate: float = required_param("rad/s", "largest reference yaw rate")
    yaw_accel: float = required_param("rad/s^2", "largest reference yaw acceleration")

    def __post_init__(self) -> None:
        require_finite(self)
        require_positive(self, *(f.name for f in fields(self)))

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Limits:
        """Build from a mapping of every field (SI units); unknown or missing keys raise
        ``ValueError`` naming them (no vessel's values fill the gaps)."""
        missing = [f.name for f in fields(cls) if f.name not in d]
        if missing and not set(d) - {f.name for f in fields(cls)}:
            raise ValueError(
                f"limits need every field; missing {missing} (give the vessel's limits, e.g. "
                "load_vessel('blue-lady').limits, or a [limits] table in the vessel file)"
            )
        return from_mapping(cls, {k: float(v) for k, v in d.items()}, where="limits")

    def to_dict(self) -> dict[str, float]:
        """The fields as a plain dict (SI units)."""
        return {f.name: float(getattr(self, f.name)) for f in fields(self)}

    def for_displacement(self, displacement: ArrayLike) -> tuple[NDArray, NDArray]:
        """Speed and acceleration limits ``(v_max, a_max)``, each (3,), for a displacement.

        Args:
            displacement: ``[surge, sway, yaw]`` (m, m, rad); a negative surge selects the
                astern limits.

        Returns:
            ``v_max`` (m/s, m/s, rad/s) and ``a_max`` (m/s^2, m/s^2, rad/s^2).
        """
        v_max, a_max = self._for_surge(float(np.asarray(displacement, dtype=float)[0]))
        return np.array(v_max), np.array(a_max)

    def _for_surge(self, surge: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """:meth:`for_displacement` as Python floats, from the surge's sign alone."""
        astern = surge < 0.0
        vx = self.surge_astern_speed if astern else self.surge_speed
        ax = self.surge_astern_accel if astern else self.surge_accel
        return (vx, self.sway_speed, self.yaw_rate), (ax, self.sway_accel, self.yaw_accel)


#: The Blue Lady's limits (equal to ``[limits]`` of its vessel file; a test checks it), each
#: with its unit and source. The capacity notes: thrust capacity 451 N ahead, 78 N astern
#: (main propeller), 2 x 44.1 N sway and ~248 N m yaw (tunnel thrusters) against
#: the plant's inertia (23 665 kg, 41 896 kg with the corrected sway added mass, 4.55e5 kg m^2;
#: Tomera 2014 eq. 49 prints 24 831 kg in sway); wind loads at 3 m/s: Blendermann (1994). At
#: these limits a leg asks for at most 75 % of the capacity in every DOF
#: (:func:`shipgym.guidance.limits.capacity_use`, issue 31).
BLUE_LADY_LIMITS = Limits(
    surge_speed=0.2,  # m/s; assumed v_max 0.2-0.3 m/s (max speed 3.1 kn)
    # m/s^2; capacity: a forward leg is braked by the 78 N astern thrust: 72 % of it with the
    # 9.4 N of a 3 m/s wind (0.0025 before issue 31: 88 %)
    surge_accel=0.002,
    surge_astern_speed=0.1,  # m/s; half of surge_speed (78 N astern thrust)
    surge_astern_accel=0.0018,  # m/s^2; capacity: 70 % of the astern thrust (0.002: 76 %)
    # m/s, m/s^2; capacity: 65 % of the 88 N sway with the plant's 41.9 t sway inertia and
    # 24.8 N of wind (0.05 m/s, 0.001 m/s^2 before issue 31: 102 %)
    sway_speed=0.03,
    sway_accel=5e-4,
    # rad/s, rad/s^2; capacity: 74 % of the 248 N m yaw with 63 N m of wind (1 deg/s,
    # 1.5e-4 rad/s^2 before issue 31: 137 %; 2.5e-4 until issue 16)
    yaw_rate=math.radians(0.5),
    yaw_accel=9e-5,
)


@njit
def _ramp(A: float, Ta: float, t: float) -> tuple[float, float, float]:
    """The acceleration phase at ``t`` (s) in ``[0, T_a]``: ``s_ddot = (A/2)(1 - cos(w t))``,
    ``w = 2 pi / T_a`` (1/s), and its exact integrals ``s_dot`` (1/s) and ``s``."""
    h = 0.5 * A
    w = 2.0 * math.pi / Ta
    wt = w * t
    sh = math.sin(0.5 * wt)
    return (
        h * (0.5 * t * t - 2.0 * sh * sh / (w * w)),
        h * (t - math.sin(wt) / w),
        h * 2.0 * sh * sh,
    )


@njit
def path_law(
    V: float, A: float, Ta: float, Tc: float, T: float, tau: float
) -> tuple[float, float, float]:
    """``(s, s_dot, s_ddot)`` of the profile (module docstring) at ``tau`` (s) since the
    profile's start (the leg's time less its ``delay``): 0 for ``tau <= 0``, exactly 1 from
    ``tau = T`` on; ``T = 0`` (a step, or a zero leg) jumps to 1 at ``tau = 0``. The one
    form of the law: :class:`LegProfile` and the run-time guidance both call it."""
    if tau <= 0.0 or T == 0.0:
        return (1.0 if (T == 0.0 and tau >= 0.0) else 0.0), 0.0, 0.0
    if tau >= T:
        return 1.0, 0.0, 0.0
    if tau < Ta:
        return _ramp(A, Ta, tau)
    if tau <= Ta + Tc:
        return 0.5 * V * Ta + V * (tau - Ta), V, 0.0
    p, v, a = _ramp(A, Ta, T - tau)
    return 1.0 - p, v, -a


@njit
def _path_many(
    V: float, A: float, Ta: float, Tc: float, T: float, delay: float, t: NDArray
) -> NDArray:
    """:func:`path_law` at the leg times ``t`` (s), shape (m,): rows ``s, s_dot, s_ddot``."""
    out = np.empty((3, t.shape[0]))
    for k in range(t.shape[0]):
        out[0, k], out[1, k], out[2, k] = path_law(V, A, Ta, Tc, T, t[k] - delay)
    return out


@dataclass(frozen=True)
class LegProfile:
    """The smooth straight-line profile of one leg: ``eta_d^r(t) = s(t) * displacement``.

    Build with :func:`leg_profile`. Attributes are the normalised path parameters.

    Attributes:
        displacement: ``[surge, sway, yaw]`` (m, m, rad) in the r-frame, shape (3,).
        speed: cruise (peak) rate ``V`` of ``s`` (1/s).
        accel: peak acceleration ``A`` of ``s`` (1/s^2).
        t_accel: duration ``T_a`` of the acceleration (and of the deceleration) phase (s).
        t_cruise: duration ``T_c`` of the constant-speed phase (s); 0 for a triangle.
        duration: total duration ``T = 2 T_a + T_c`` (s); 0 for a zero displacement. With a
            ``delay`` the profile is shifted by it, and the leg's duration is
            :attr:`total_duration`.
        delay: rest at 0 before the profile starts (s).
        step: a step: ``s`` jumps from 0 to 1 at ``delay`` (``s_dot = s_ddot = 0``).
    """

    displacement: NDArray[np.float64]
    speed: float
    accel: float
    t_accel: float
    t_cruise: float
    duration: float
    delay: float = 0.0
    step: bool = False

    @property
    def total_duration(self) -> float:
        """``delay + duration`` (s): when the reference has arrived at the end point."""
        return self.delay + self.duration

    def path(self, t: ArrayLike) -> tuple[Any, Any, Any]:
        """Normalised path parameter ``(s, s_dot, s_ddot)`` at time ``t`` (s) since the start.

        Scalar ``t`` gives Python floats, array ``t`` arrays of its shape. ``s = 0`` before
        the start and ``s = 1`` (exactly) from ``t = total_duration`` on; a step has
        ``s = 1`` from ``t = delay`` on (:func:`path_law`).
        """
        tt = np.asarray(t, dtype=float)
        if not np.all(np.isfinite(tt)):
            raise ValueError(f"time must be finite (s), got {t!r}")
        out = _path_many(
            self.speed, self.accel, self.t_accel, self.t_cruise, self.duration, self.delay,
            np.ascontiguousarray(tt.reshape(-1)),
        )  # fmt: skip
        if tt.ndim == 0:
            s, sd, sdd = out[:, 0].tolist()
            return s, sd, sdd
        return out[0].reshape(tt.shape), out[1].reshape(tt.shape), out[2].reshape(tt.shape)

    def evaluate(self, t: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
        """Reference ``(eta_d^r, eta_dot_d^r, eta_ddot_d^r)`` at ``t`` (s) since the leg start.

        Each output has shape ``np.shape(t) + (3,)`` with units (m, m, rad), per second, per
        second squared.
        """
        d = self.displacement
        s, sd, sdd = self.path(t)
        if np.ndim(s) == 0:
            return s * d, sd * d, sdd * d
        return s[..., None] * d, sd[..., None] * d, sdd[..., None] * d


def _effective_limits(leg: Leg, limits: Limits | None) -> Limits:
    own = getattr(leg, "limits", None)
    if own is not None:
        return own
    if limits is None:
        raise TypeError(
            "the reference needs the vessel's limits: pass limits=..., e.g. "
            "Limits.from_dict(load_vessel('blue-lady').limits) (or give the leg its own)"
        )
    return limits


def leg_profile(leg: Leg, limits: Limits | None = None) -> LegProfile:
    """The smooth profile of a leg under the given limits (the leg's own limits win).

    Args:
        leg: a :class:`~shipgym.guidance.plan.Leg` (its ``displacement`` and ``limits``).
        limits: plan-wide limits (the vessel's); ``None``: the leg must have its own.

    Raises:
        TypeError: neither ``limits`` nor ``leg.limits`` given.

    Returns:
        The :class:`LegProfile` (see the module docstring for the profile).
    """
    disp = np.array(leg.displacement, dtype=float)
    disp.setflags(write=False)
    d = tuple(disp.tolist())  # (surge, sway, yaw) as Python floats
    delay = float(getattr(leg, "delay", 0.0))
    if getattr(leg, "step", False):  # no profile, no limits needed
        return LegProfile(disp, 0.0, 0.0, 0.0, 0.0, 0.0, delay, True)
    lim = _effective_limits(leg, limits)
    if d == (0.0, 0.0, 0.0):
        return LegProfile(disp, 0.0, 0.0, 0.0, 0.0, 0.0, delay)
    # the tightest of the moving DOFs' limits over their distances, in Python floats: the same
    # IEEE quotients as on arrays
    v_max, a_max = lim._for_surge(d[0])
    V = min([float(v) / abs(x) for v, x in zip(v_max, d, strict=True) if x != 0.0])
    A = min([float(a) / abs(x) for a, x in zip(a_max, d, strict=True) if x != 0.0])
    if 2.0 * V * V <= A:  # trapezoid: the distance 1 covers acceleration + deceleration
        Ta = 2.0 * V / A
        Tc = max(1.0 / V - Ta, 0.0)
    else:  # triangle: the speed limit is never reached
        V = math.sqrt(0.5 * A)
        Ta = 2.0 * V / A
        Tc = 0.0
    return LegProfile(disp, V, A, Ta, Tc, 2.0 * Ta + Tc, delay)


def leg_duration(leg: Leg, limits: Limits | None = None) -> float:
    """Duration (s) of the leg's reference under the limits (the leg's own limits win),
    its ``delay`` included."""
    return leg_profile(leg, limits).total_duration


def leg_reference(
    leg: Leg, limits: Limits | None, t: ArrayLike
) -> tuple[NDArray, NDArray, NDArray]:
    """Desired r-frame pose, velocity and acceleration of the virtual ship (Tomera 2014 Fig. 3).

    Args:
        leg: the leg (displacement ``[surge, sway, yaw]`` in its r-frame).
        limits: plan-wide :class:`Limits` (the vessel's); ``leg.limits`` overrides; one of
            the two is required.
        t: time since the leg started (s), scalar or array.

    Returns:
        ``(eta_d^r, eta_dot_d^r, eta_ddot_d^r)``, each of shape ``np.shape(t) + (3,)``, in
        (m, m, rad), (m/s, m/s, rad/s) and (m/s^2, m/s^2, rad/s^2). At rest at 0 for
        ``t <= 0`` and at rest exactly at the displacement for ``t >= leg_duration``.
    """
    return leg_profile(leg, limits).evaluate(t)
