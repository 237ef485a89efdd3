"""Run-time guidance: the current leg, its reference and leg switching (Tomera 2014).

:class:`Guidance` walks through a :class:`~shipgym.guidance.plan.ManoeuvrePlan`. Each leg's
reference starts at rest at the leg's planned start point P when the leg starts (at reset,
or at the switch from the previous leg) and follows the smooth profile of
:mod:`shipgym.guidance.reference` to the planned end point K.

Switching rule (:meth:`Guidance.update`): leg i is complete, and the next leg starts at that
instant, when all of these hold:

1. the ship is closer than ``switch_distance`` to K_i (NED distance, m) - Tomera (2014);
2. ``|wrap(psi - psi_K)| < switch_heading`` - Tomera (2014) ("course difference < 5 deg");
3. at least ``switch_min_progress`` of the leg's reference duration has elapsed (default 1:
   the reference has reached K). Without it, a rotation leg would still be safe (the ship
   starts at K's position but 90 deg off its heading), but any leg shorter than 1 m, or a
   rotation below 5 deg, would switch immediately, and a long leg would switch while the
   ship is still moving at speed 1 m before K, so that the next leg's reference would start
   at rest while the ship is not;
4. conditions 1-3 have held continuously for ``settle_time`` seconds (default 0).

After the last leg completes, :attr:`Guidance.finished` is True and the reference stays at
the last leg's end point.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.frames import wrap_angle

from .plan import ManoeuvrePlan
from .reference import LegProfile, Limits, leg_profile
from .rframe import to_r_frame

__all__ = ["Guidance", "Reference"]

_F64 = np.dtype(np.float64)


@dataclass(frozen=True, eq=False)
class Reference:
    """The guidance output at one instant.

    Attributes:
        eta_d_r: desired pose ``[x, y, psi]`` in the current leg's r-frame (m, m, rad), (3,).
        eta_dot_d_r: its time derivative (m/s, m/s, rad/s), (3,).
        eta_ddot_d_r: its second time derivative (m/s^2, m/s^2, rad/s^2), (3,).
        eta_P: NED pose of the current leg's start point P (m, m, rad), (3,).
        leg: index of the current leg (the last one once the plan is finished).
        eta_d_n: desired NED pose (m, m, rad), (3,); heading continuous (not wrapped).
        eta_K: NED planned end point K of the current leg (m, m, rad), (3,).
        t_leg: time since the current leg started (s).
        finished: True once every leg is complete.
    """

    eta_d_r: NDArray[np.float64]
    eta_dot_d_r: NDArray[np.float64]
    eta_ddot_d_r: NDArray[np.float64]
    eta_P: NDArray[np.float64]
    leg: int
    eta_d_n: NDArray[np.float64]
    eta_K: NDArray[np.float64]
    t_leg: float = 0.0
    finished: bool = False

    @functools.cached_property
    def _nu_d(self) -> tuple[float, float, float]:
        """:attr:`nu_d` as floats, computed once (the reference is immutable)."""
        return _body_velocities(self.eta_d_r.tolist()[2], self.eta_dot_d_r.tolist(), None)[0]

    @functools.cached_property
    def _nu_dot_d(self) -> tuple[float, float, float]:
        """:attr:`nu_dot_d` as floats, computed once."""
        out = _body_velocities(
            self.eta_d_r.tolist()[2], self.eta_dot_d_r.tolist(), self.eta_ddot_d_r.tolist()
        )
        return out[1]  # type: ignore[return-value]

    @classmethod
    def _build(
        cls,
        eta_d_r: NDArray[np.float64],
        eta_dot_d_r: NDArray[np.float64],
        eta_ddot_d_r: NDArray[np.float64],
        eta_P: NDArray[np.float64],
        leg: int,
        eta_d_n: NDArray[np.float64],
        eta_K: NDArray[np.float64],
        t_leg: float,
        finished: bool,
        nu_d: tuple[float, float, float],
        nu_dot_d: tuple[float, float, float],
    ) -> Reference:
        """The guidance's constructor (one reference per control step), with :attr:`_nu_d`
        and :attr:`_nu_dot_d` already computed (:func:`_body_velocities` of the same floats).

        A frozen dataclass's ``__init__`` sets its fields one by one through
        ``object.__setattr__``, three times the cost of filling the instance dict at once;
        a test checks that the result equals ``Reference(...)`` field by field.
        """
        ref = object.__new__(cls)
        ref.__dict__.update(
            eta_d_r=eta_d_r,
            eta_dot_d_r=eta_dot_d_r,
            eta_ddot_d_r=eta_ddot_d_r,
            eta_P=eta_P,
            leg=leg,
            eta_d_n=eta_d_n,
            eta_K=eta_K,
            t_leg=t_leg,
            finished=finished,
            _nu_d=nu_d,
            _nu_dot_d=nu_dot_d,
        )
        return ref

    @property
    def eta_dot_d_n(self) -> NDArray[np.float64]:
        """Desired NED velocity ``[x_dot, y_dot, psi_dot]``: ``R(psi_P) eta_dot_d^r``."""
        c, s = math.cos(self.eta_P[2]), math.sin(self.eta_P[2])
        v = self.eta_dot_d_r
        return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]])

    @property
    def nu_d(self) -> NDArray[np.float64]:
        """Desired body-frame velocity ``[u, v, r]``: ``R(psi_d^r)^T eta_dot_d^r`` (m/s, rad/s)."""
        return np.array(self._nu_d)

    @property
    def nu_dot_d(self) -> NDArray[np.float64]:
        """Time derivative of :attr:`nu_d`: ``R^T eta_ddot_d^r - S(r_d) nu_d`` (m/s^2, rad/s^2).

        ``S(r) = [[0, -r, 0], [r, 0, 0], [0, 0, 0]]`` (Fossen 2011, eq. 2.62 differentiated).
        """
        return np.array(self._nu_dot_d)

    def to_r(self, eta_n: ArrayLike) -> NDArray[np.float64]:
        """A NED pose (or poses, (..., 3)) in this leg's r-frame, heading unwrapped near psi_d^r.

        Use it for the ship's (true or measured) pose, so that r-frame errors are
        ``eta_d_r - ref.to_r(eta_n)`` without any 2 pi jump (Tomera 2014 eq. 1).
        """
        return to_r_frame(eta_n, self.eta_P, psi_ref_r=self.eta_d_r[2])


def _body_velocities(
    psi: float, v: Sequence[float], a: Sequence[float] | None
) -> tuple[tuple[float, float, float], tuple[float, float, float] | None]:
    """``(nu_d, nu_dot_d)`` in floats from the r-frame heading ``psi_d^r``, ``eta_dot_d^r``
    and ``eta_ddot_d^r`` (``a`` None: ``nu_dot_d`` None): ``nu_d = R(psi)^T eta_dot``,
    ``nu_dot_d = R(psi)^T eta_ddot - S(r_d) nu_d`` (:attr:`Reference.nu_d`, ``nu_dot_d``)."""
    c, s = math.cos(psi), math.sin(psi)
    v0, v1, r = v
    nu0, nu1 = c * v0 + s * v1, -s * v0 + c * v1
    if a is None:
        return (nu0, nu1, r), None
    a0, a1, a2 = a
    return (nu0, nu1, r), (c * a0 + s * a1 + r * nu1, -s * a0 + c * a1 - r * nu0, a2)


class Guidance:
    """Leg-by-leg guidance through a manoeuvre plan (Tomera 2014 Figs. 2-3 and 7).

    Usage::

        g = Guidance(tomera2014_plan(), limits=Limits.from_dict(vessel.limits))
        g.reset(eta_start)
        for each control step at time t:
            g.update(t, eta_n)          # may switch to the next leg (returns True)
            ref = g.reference(t)        # desired pose/velocity/acceleration

    Times are absolute (s since ``reset``'s ``t0`` clock); each leg's own clock starts at
    its start time.
    """

    def __init__(self, plan: ManoeuvrePlan, limits: Limits | None = None) -> None:
        if not isinstance(plan, ManoeuvrePlan):
            raise TypeError(f"Guidance needs a ManoeuvrePlan, got {type(plan).__name__}")
        if limits is not None and not isinstance(limits, Limits):
            raise TypeError(f"limits must be a Limits or None, got {type(limits).__name__}")
        self.plan = plan
        #: the plan's limits, else the vessel's (``limits``); each leg's own limits win
        self.limits = plan.limits if plan.limits is not None else limits
        self._profiles: tuple[LegProfile, ...] = tuple(
            leg_profile(leg, self.limits) for leg in plan.legs
        )
        self._waypoints: NDArray[np.float64] | None = None
        self._wp_list: list[list[float]] = []
        self._cs: list[tuple[float, float]] = []
        self._leg = 0
        self._finished = False
        self._starts: list[float] = []
        self._completions: list[float] = []
        self._hold_since: float | None = None

    # -- state -------------------------------------------------------------------------------
    def reset(self, eta_start: ArrayLike, t0: float = 0.0) -> None:
        """Start the plan from the NED pose ``eta_start`` (m, m, rad) at time ``t0`` (s)."""
        t0 = float(t0)
        if not math.isfinite(t0):
            raise ValueError(f"t0 must be finite, got {t0!r}")
        wp = self.plan.waypoints(eta_start)
        wp.setflags(write=False)
        self._waypoints = wp
        # scalar copies for the per-step fast path (same arithmetic as from_r_frame)
        self._wp_list = wp.tolist()
        self._cs = [(math.cos(p[2]), math.sin(p[2])) for p in self._wp_list]
        self._leg = 0
        self._finished = False
        self._starts = [t0]
        self._completions = []
        self._hold_since = None

    def _require_reset(self) -> NDArray[np.float64]:
        if self._waypoints is None:
            raise RuntimeError("Guidance.reset(eta_start) must be called before use")
        return self._waypoints

    @property
    def n_legs(self) -> int:
        """Number of legs of the plan."""
        return self.plan.n_legs

    @property
    def leg_index(self) -> int:
        """Index of the current leg (stays at the last leg once finished)."""
        return self._leg

    @property
    def finished(self) -> bool:
        """True once the last leg's switching condition has held."""
        return self._finished

    @property
    def waypoints(self) -> NDArray[np.float64]:
        """Planned NED poses ``[P_0, K_0, ..., K_{n-1}]``, shape (n_legs + 1, 3), read-only."""
        return self._require_reset()

    @property
    def leg_start_times(self) -> tuple[float, ...]:
        """Start time (s) of every leg started so far."""
        return tuple(self._starts)

    @property
    def leg_completion_times(self) -> tuple[float, ...]:
        """Completion (switch) time (s) of every leg completed so far."""
        return tuple(self._completions)

    @property
    def legs_completed(self) -> int:
        """Number of legs completed so far (``len(leg_completion_times)``)."""
        return len(self._completions)

    @property
    def leg_durations(self) -> tuple[float, ...]:
        """Actual durations (s) of the completed legs: completion minus start."""
        return tuple(c - s for s, c in zip(self._starts, self._completions, strict=False))

    @property
    def reference_durations(self) -> tuple[float, ...]:
        """Planned reference duration (s) of every leg."""
        return tuple(p.total_duration for p in self._profiles)

    # -- outputs -----------------------------------------------------------------------------
    def reference(self, t: float) -> Reference:
        """The reference at absolute time ``t`` (s) for the current leg.

        Times before the current leg's start give the reference at rest at P.
        """
        wp = self._waypoints
        if wp is None:
            wp = self._require_reset()
        i = self._leg
        t_leg = float(t) - self._starts[i]
        # plain floats, and the reference's body velocities computed here from the same
        # floats (every control step: the hot path)
        eta_d, eta_dot, eta_ddot = self._profiles[i].evaluate_one(t_leg)
        xP, yP, psiP = self._wp_list[i]
        c, s = self._cs[i]
        xr, yr, pr = eta_d
        nu_d, nu_dot_d = _body_velocities(pr, eta_dot, eta_ddot)
        return Reference._build(
            np.array(eta_d, float),
            np.array(eta_dot, float),
            np.array(eta_ddot, float),
            wp[i],
            i,
            np.array([xP + c * xr - s * yr, yP + s * xr + c * yr, psiP + pr], float),
            wp[i + 1],
            t_leg,
            self._finished,
            nu_d,
            nu_dot_d,  # type: ignore[arg-type]
        )

    def switch_conditions(self, t: float, eta_n: ArrayLike) -> tuple[bool, bool, bool]:
        """The three instantaneous switching conditions for the current leg.

        Returns:
            ``(near, aligned, progressed)``: distance to K below ``switch_distance``, wrapped
            heading error to K below ``switch_heading``, and the leg's elapsed time at least
            ``switch_min_progress`` times its reference duration.
        """
        if self._waypoints is None:
            self._require_reset()
        # the env's pose array as it is (every control step: asarray's keyword call is slow)
        eta = (
            eta_n if type(eta_n) is np.ndarray and eta_n.dtype == _F64 else np.asarray(eta_n, float)
        )
        e = eta.tolist() if eta.shape == (3,) else None
        if e is None or not all(map(math.isfinite, e)):
            raise ValueError(f"eta_n must be a finite [x, y, psi] (m, m, rad), got {eta!r}")
        i = self._leg
        kx, ky, kpsi = self._wp_list[i + 1]
        dist = math.hypot(e[0] - kx, e[1] - ky)
        # np.float64: wrap_angle's array formula, as for the array elements this once took
        head = abs(wrap_angle(np.float64(e[2] - kpsi)))
        t_leg = float(t) - self._starts[i]
        need = self.plan.switch_min_progress * self._profiles[i].total_duration
        return (
            dist < self.plan.switch_distance,
            head < self.plan.switch_heading,
            t_leg >= need - 1e-9,
        )

    def update(self, t: float, eta_n: ArrayLike) -> bool:
        """Check the switching rule at time ``t`` (s) for the ship at NED pose ``eta_n``.

        Returns:
            True when the current leg completes at this call (the next leg starts at ``t``,
            or the plan is finished after the last leg); False otherwise, and always once
            finished.
        """
        if self._waypoints is None:
            self._require_reset()
        if self._finished:
            return False
        t = float(t)
        if not math.isfinite(t):
            raise ValueError(f"t must be finite, got {t!r}")
        if not all(self.switch_conditions(t, eta_n)):
            self._hold_since = None
            return False
        if self._hold_since is None:
            self._hold_since = t
        if t - self._hold_since < self.plan.settle_time:
            return False
        self._hold_since = None
        self._completions.append(t)
        if self._leg + 1 < self.n_legs:
            self._leg += 1
            self._starts.append(t)
        else:
            self._finished = True
        return True
