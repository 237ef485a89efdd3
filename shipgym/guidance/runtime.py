"""Run-time guidance: the current leg, its reference and leg switching (Tomera 2014).

:class:`Guidance` walks through a :class:`~shipgym.guidance.plan.ManoeuvrePlan`. Each leg's
reference starts at rest at the leg's planned start point P when the leg starts (at reset,
or at the switch from the previous leg) and follows the smooth profile of
:mod:`shipgym.guidance.reference` to the planned end point K.

Public names: ``Guidance``, ``Reference``.

Design notes: docs/design/guidance.runtime.md.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import entry

from .batch import (
    _ETA_DOT_N,
    _NU,
    _NU_DOT,
    _R,
    _S,
    _TLEG,
    _TSTART,
    BatchedGuidance,
    _conditions,
    _derived,
    _reference,
)
from .batch import _update as _update_kernel
from .plan import ManoeuvrePlan
from .reference import LegProfile, Limits, leg_profile
from .rframe import to_r_frame

__all__ = ["Guidance", "Reference"]


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

    The guidance's references are read-only views of one buffer of the compiled reference
    (:mod:`shipgym.guidance.batch`), which also holds the velocities below.
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
    def _buf(self) -> NDArray[np.float64]:
        """The (10, 3) buffer of the compiled reference (built from the fields where the
        reference was not made by the guidance)."""
        f = [
            np.ascontiguousarray(a, dtype=float).reshape(1, 3)
            for a in (self.eta_d_r, self.eta_dot_d_r, self.eta_ddot_d_r, self.eta_P)
        ]
        buf = _derived(*f)[0]
        buf[4], buf[5], buf[_TLEG, 0] = self.eta_d_n, self.eta_K, self.t_leg
        buf.setflags(write=False)
        return buf

    @property
    def buffer(self) -> NDArray[np.float64]:
        """The reference as one (1, 10, 3) array (the layout of
        :attr:`BatchedReference.buffer <shipgym.guidance.batch.BatchedReference.buffer>`)."""
        return self._buf[None]

    @functools.cached_property
    def _nu_d(self) -> tuple[float, float, float]:
        """:attr:`nu_d` as floats, computed once (the reference is immutable)."""
        u, v, r = self._buf[_NU].tolist()
        return u, v, r

    @functools.cached_property
    def _nu_dot_d(self) -> tuple[float, float, float]:
        """:attr:`nu_dot_d` as floats, computed once."""
        u, v, r = self._buf[_NU_DOT].tolist()
        return u, v, r

    @classmethod
    def _build(cls, o: NDArray[np.float64], leg: int, t_leg: float, finished: bool) -> Reference:
        """The guidance's constructor (one reference per control step) from one env's
        read-only buffer ``o`` (10, 3) of the compiled reference.

        A frozen dataclass's ``__init__`` sets its fields one by one through
        ``object.__setattr__``, three times the cost of filling the instance dict at once;
        a test checks that the result equals ``Reference(...)`` field by field.
        """
        ref = object.__new__(cls)
        nu, nu_dot = o[_NU : _NU_DOT + 1].tolist()  # the env reads them as floats
        ref.__dict__.update(
            eta_d_r=o[0],
            eta_dot_d_r=o[1],
            eta_ddot_d_r=o[2],
            eta_P=o[3],
            leg=leg,
            eta_d_n=o[4],
            eta_K=o[5],
            t_leg=t_leg,
            finished=finished,
            _buf=o,
            _nu_d=(*nu,),
            _nu_dot_d=(*nu_dot,),
        )
        return ref

    @property
    def eta_dot_d_n(self) -> NDArray[np.float64]:
        """Desired NED velocity ``[x_dot, y_dot, psi_dot]``: ``R(psi_P) eta_dot_d^r``."""
        return self._buf[_ETA_DOT_N]

    @property
    def nu_d(self) -> NDArray[np.float64]:
        """Desired body-frame velocity ``[u, v, r]``: ``R(psi_d^r)^T eta_dot_d^r`` (m/s, rad/s)."""
        return self._buf[_NU]

    @property
    def nu_dot_d(self) -> NDArray[np.float64]:
        """Time derivative of :attr:`nu_d`: ``R^T eta_ddot_d^r - S(r_d) nu_d`` (m/s^2, rad/s^2).

        ``S(r) = [[0, -r, 0], [r, 0, 0], [0, 0, 0]]`` (Fossen 2011, eq. 2.62 differentiated).
        """
        return self._buf[_NU_DOT]

    def to_r(self, eta_n: ArrayLike) -> NDArray[np.float64]:
        """A NED pose (or poses, (..., 3)) in this leg's r-frame, heading unwrapped near psi_d^r.

        Use it for the ship's (true or measured) pose, so that r-frame errors are
        ``eta_d_r - ref.to_r(eta_n)`` without any 2 pi jump (Tomera 2014 eq. 1).
        """
        return to_r_frame(eta_n, self.eta_P, psi_ref_r=self.eta_d_r[2])


@functools.cache
def _entries() -> tuple[Any, Any]:
    """The compiled entry points of the update and reference kernels for one env's arrays
    (:func:`shipgym._jit.entry`: no per-call type resolution)."""
    t, tab, st = np.zeros(1), np.zeros((1, 1, _R)), np.zeros((1, _S))
    upd = entry(_update_kernel, (t, np.zeros((1, 3)), tab, st, np.zeros((1, 1)), np.zeros(1, bool)))
    return upd, entry(_reference, (t, tab, st))


class Guidance:
    """Leg-by-leg guidance through a manoeuvre plan (Tomera 2014 Figs. 2-3 and 7).

    Usage::

        g = Guidance(tomera2014_plan(), limits=Limits.from_dict(vessel.limits))
        g.reset(eta_start)
        for each control step at time t:
            g.update(t, eta_n)          # may switch to the next leg (returns True)
            ref = g.reference(t)        # desired pose/velocity/acceleration

    Times are absolute (s since ``reset``'s ``t0`` clock); each leg's own clock starts at
    its start time. The compiled guidance of :mod:`shipgym.guidance.batch` for one env.
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
        self._g = BatchedGuidance(1, limits=self.limits)
        self._waypoints: NDArray[np.float64] | None = None
        self._t = np.zeros(1)  # the time of a call (s)
        self._eta = np.zeros((1, 3))  # the pose of a call (m, m, rad)
        self._sw = np.zeros(1, dtype=bool)
        self._leg = 0
        self._finished = False
        self._t_start = 0.0
        self._upd, self._ref = _entries()

    def __getstate__(self) -> dict[str, Any]:
        """The state without the compiled entry points (they do not pickle)."""
        return {k: v for k, v in self.__dict__.items() if k not in ("_upd", "_ref")}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._upd, self._ref = _entries()

    # -- state -------------------------------------------------------------------------------
    def reset(self, eta_start: ArrayLike, t0: float = 0.0) -> None:
        """Start the plan from the NED pose ``eta_start`` (m, m, rad) at time ``t0`` (s)."""
        t0 = float(t0)
        if not math.isfinite(t0):
            raise ValueError(f"t0 must be finite, got {t0!r}")
        wp = self.plan.waypoints(eta_start)  # checks the pose
        self._g.reset([self.plan], wp[0], t0, _profiles=[self._profiles], _waypoints=[wp])
        wp.setflags(write=False)
        self._waypoints = wp
        self._leg, self._finished, self._t_start = 0, False, t0

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
        self._require_reset()
        return self._g.leg_start_times(0)

    @property
    def leg_completion_times(self) -> tuple[float, ...]:
        """Completion (switch) time (s) of every leg completed so far."""
        if self._waypoints is None:
            return ()
        return self._g.leg_completion_times(0)  # type: ignore[no-any-return]

    @property
    def legs_completed(self) -> int:
        """Number of legs completed so far (``len(leg_completion_times)``)."""
        return self._leg + self._finished

    @property
    def leg_durations(self) -> tuple[float, ...]:
        """Actual durations (s) of the completed legs: completion minus start."""
        starts, ends = self.leg_start_times, self.leg_completion_times
        return tuple(c - s for s, c in zip(starts, ends, strict=False))

    @property
    def reference_durations(self) -> tuple[float, ...]:
        """Planned reference duration (s) of every leg."""
        return tuple(p.total_duration for p in self._profiles)

    # -- outputs -----------------------------------------------------------------------------
    def reference(self, t: float) -> Reference:
        """The reference at absolute time ``t`` (s) for the current leg.

        Times before the current leg's start give the reference at rest at P.
        """
        if self._waypoints is None:
            self._require_reset()
        t = float(t)
        if not math.isfinite(t):
            raise ValueError(f"time must be finite (s), got {t!r}")
        self._t[0] = t
        buf = self._ref(self._t, self._g._tab, self._g._st)
        buf.setflags(write=False)
        return Reference._build(buf[0], self._leg, t - self._t_start, self._finished)

    def _pose(self, eta_n: ArrayLike) -> None:
        """Check the pose ``eta_n`` (m, m, rad) of a call and copy it to the kernel's input."""
        eta = eta_n if type(eta_n) is np.ndarray else np.asarray(eta_n, dtype=float)
        if eta.shape != (3,):
            raise ValueError(f"eta_n must be a finite [x, y, psi] (m, m, rad), got {eta!r}")
        self._eta[0] = eta

    def switch_conditions(self, t: float, eta_n: ArrayLike) -> tuple[bool, bool, bool]:
        """The three instantaneous switching conditions for the current leg.

        Returns:
            ``(near, aligned, progressed)``: distance to K below ``switch_distance``, wrapped
            heading error to K below ``switch_heading``, and the leg's elapsed time at least
            ``switch_min_progress`` times its reference duration.
        """
        self._require_reset()
        self._pose(eta_n)
        if not np.all(np.isfinite(self._eta)):
            raise ValueError(f"eta_n must be a finite [x, y, psi] (m, m, rad), got {eta_n!r}")
        g, (x, y, psi) = self._g, self._eta[0].tolist()
        near, aligned, progressed = _conditions(g._tab[0, self._leg], g._st[0], float(t), x, y, psi)
        return bool(near), bool(aligned), bool(progressed)

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
        self._t[0] = t
        self._pose(eta_n)
        g = self._g
        count = self._upd(self._t, self._eta, g._tab, g._st, g._comp, self._sw)
        if not count:
            return False
        if count < 0:
            if not math.isfinite(self._t[0]):
                raise ValueError(f"t must be finite, got {t!r}")
            raise ValueError(f"eta_n must be a finite [x, y, psi] (m, m, rad), got {eta_n!r}")
        g._refresh()
        self._leg = int(g._leg[0])
        self._finished = bool(g._finished[0])
        self._t_start = float(g._st[0, _TSTART])
        return True
