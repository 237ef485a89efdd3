"""Guidance of N envs at once: the batched form of :class:`~shipgym.guidance.runtime.Guidance`.

Each env walks through its own :class:`~shipgym.guidance.plan.ManoeuvrePlan` (its own number
of legs, leg kinds, ``delay``/``step`` legs, switching rule and limits), exactly as a
:class:`~shipgym.guidance.runtime.Guidance` per env would (a test runs one per env and
compares every output to 1e-10, the switch instants exactly):

- the reference of the current leg is the smooth straight-line profile of
  :mod:`shipgym.guidance.reference` (raised-cosine acceleration, trapezoidal or triangular
  speed, Tomera (2014) Fig. 3), its phases chosen per env with ``np.where`` and a clipped
  ramp time: the ramp runs on the time since the start (acceleration) or to the end
  (deceleration), clipped to ``[0, T_a]``, so that 0 gives the rest at P (before the start,
  during the ``delay``) and at K (from ``T`` on; a ``step`` leg, ``T = 0``, jumps at its
  ``delay``), and ``T_a`` the cruise, written ``1 - ramp(T_a) - V (T - T_a - t)`` (equal to
  the scalar ``V T_a / 2 + V (t - T_a)`` to round-off, as ``2 ramp(T_a) + V T_c = 1``);
- the switching rule of :meth:`Guidance.update <shipgym.guidance.runtime.Guidance.update>`
  (distance to K and heading error to K, Tomera (2014); progress and ``settle_time``, ours).

At :meth:`BatchedGuidance.reset` (a Python loop over the reset envs, once per episode) every
leg's profile parameters, planned poses P and K and switching threshold are written to a
table padded to the longest plan, shape ``(K, n, max_legs)``; the current leg's column of
each env is copied to a ``(K, n)`` array when the env starts a leg, so that
:meth:`~BatchedGuidance.update` and :meth:`~BatchedGuidance.reference` are a fixed number of
NumPy operations on ``(n,)`` and ``(3, n)`` arrays (no loop over envs). Arrays handed out are
never written afterwards (a leg switch or a reset makes new ones), so a
:class:`BatchedReference` keeps its values.

Poses and velocities come and go as ``(n, 3)`` arrays ``[x, y, psi]`` (m, m, rad) per env
(NED, or the current leg's r-frame, Tomera (2014) eqs. 1-2); times as ``(n,)`` arrays (s),
each env on its own clock (a reset restarts it at ``t0``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .plan import ManoeuvrePlan
from .reference import Limits, leg_profile

__all__ = ["BatchedGuidance", "BatchedReference"]

Array = NDArray[np.float64]

_PI = math.pi
_TWO_PI = 2.0 * math.pi

# rows of the per-leg table (and of the current-leg array)
_D = slice(0, 3)  # r-frame displacement [surge, sway, yaw] (m, m, rad)
_DN = slice(3, 6)  # its NED image R(psi_P) [surge, sway] and yaw: K - P (m, m, rad)
_P = slice(6, 9)  # planned start pose P (NED)
_CP, _SP = 9, 10  # cos and sin of psi_P
_K = slice(11, 14)  # planned end pose K (NED)
_KX, _KY, _KPSI = 11, 12, 13
# profile: V, T_a, T (s), delay (s), T - T_a, A, A/2, A/4, A/w^2, A/(2 w), w, w/2 (w = 2 pi/T_a)
_V, _TA, _T, _DELAY, _TMTA, _A, _H, _HH, _HQ, _HW, _W, _W2 = range(14, 26)
_NEED = 26  # switch_min_progress * (delay + T) - 1e-9 (s); inf once the plan is finished
_ROWS = 27


class BatchedReference:
    """The guidance output of ``n`` envs at one instant (the batched
    :class:`~shipgym.guidance.runtime.Reference`; every formula is the scalar one per env).

    Attributes:
        eta_d_r: desired poses in each env's current leg's r-frame (m, m, rad), (n, 3).
        eta_dot_d_r: their time derivatives (m/s, m/s, rad/s), (n, 3).
        eta_ddot_d_r: their second time derivatives (m/s^2, m/s^2, rad/s^2), (n, 3).
        eta_P: NED poses of the current legs' start points P (m, m, rad), (n, 3).
        eta_d_n: desired NED poses (m, m, rad), (n, 3); headings continuous (not wrapped).
        eta_K: NED planned end points K of the current legs (m, m, rad), (n, 3).
        leg: index of each env's current leg (the last one once its plan is finished), (n,).
        t_leg: time since each env's current leg started (s), (n,).
        finished: True where every leg of the env's plan is complete, (n,).

    The ``(n, 3)`` arrays are views of ``(3, n)`` arrays; those that show the guidance's state
    (``eta_P``, ``eta_K``, ``leg``, ``finished``) are read-only and never change afterwards.
    """

    __slots__ = (
        "eta_d_r",
        "eta_dot_d_r",
        "eta_ddot_d_r",
        "eta_P",
        "eta_d_n",
        "eta_K",
        "leg",
        "t_leg",
        "finished",
        "_cur",
        "_cs",
    )

    def __init__(
        self,
        eta_d_r: Array,
        eta_dot_d_r: Array,
        eta_ddot_d_r: Array,
        eta_P: Array,
        eta_d_n: Array,
        eta_K: Array,
        leg: NDArray[np.intp],
        t_leg: Array,
        finished: NDArray[np.bool_],
        _cur: Array | None = None,
    ) -> None:
        self.eta_d_r = eta_d_r
        self.eta_dot_d_r = eta_dot_d_r
        self.eta_ddot_d_r = eta_ddot_d_r
        self.eta_P = eta_P
        self.eta_d_n = eta_d_n
        self.eta_K = eta_K
        self.leg = leg
        self.t_leg = t_leg
        self.finished = finished
        self._cur = _cur
        self._cs: tuple[Array, Array] | None = None

    @property
    def n(self) -> int:
        """Number of envs."""
        return int(self.t_leg.shape[0])

    def _cos_sin_d(self) -> tuple[Array, Array]:
        if self._cs is None:
            psi = self.eta_d_r[:, 2]
            self._cs = (np.cos(psi), np.sin(psi))
        return self._cs

    @property
    def eta_dot_d_n(self) -> Array:
        """Desired NED velocities ``R(psi_P) eta_dot_d^r`` (m/s, m/s, rad/s), (n, 3)."""
        if self._cur is not None:
            c, s = self._cur[_CP], self._cur[_SP]
        else:
            c, s = np.cos(self.eta_P[:, 2]), np.sin(self.eta_P[:, 2])
        v = self.eta_dot_d_r
        out = np.empty((3, v.shape[0]))
        out[0] = c * v[:, 0] - s * v[:, 1]
        out[1] = s * v[:, 0] + c * v[:, 1]
        out[2] = v[:, 2]
        return out.T

    @property
    def nu_d(self) -> Array:
        """Desired body-frame velocities ``R(psi_d^r)^T eta_dot_d^r`` (m/s, m/s, rad/s), (n, 3)."""
        c, s = self._cos_sin_d()
        v = self.eta_dot_d_r
        v0, v1 = v[:, 0], v[:, 1]
        out = np.empty((3, v.shape[0]))
        out[0] = c * v0 + s * v1
        out[1] = -s * v0 + c * v1
        out[2] = v[:, 2]
        return out.T

    @property
    def nu_dot_d(self) -> Array:
        """Time derivative of :attr:`nu_d`: ``R^T eta_ddot_d^r - S(r_d) nu_d`` (m/s^2,
        m/s^2, rad/s^2), (n, 3); ``S(r) = [[0, -r, 0], [r, 0, 0], [0, 0, 0]]`` (Fossen 2011,
        eq. 2.62 differentiated)."""
        c, s = self._cos_sin_d()
        a = self.eta_ddot_d_r
        a0, a1 = a[:, 0], a[:, 1]
        v = self.eta_dot_d_r
        v0, v1, r = v[:, 0], v[:, 1], v[:, 2]
        nu0 = c * v0 + s * v1
        nu1 = -s * v0 + c * v1
        out = np.empty((3, a.shape[0]))
        out[0] = c * a0 + s * a1 + r * nu1
        out[1] = -s * a0 + c * a1 - r * nu0
        out[2] = a[:, 2]
        return out.T

    def to_r(self, eta_n: ArrayLike) -> Array:
        """NED poses (n, 3) in each env's current leg's r-frame, heading unwrapped near
        ``psi_d^r`` (Tomera 2014 eq. 1; the scalar :meth:`Reference.to_r
        <shipgym.guidance.runtime.Reference.to_r>` per env).

        Args:
            eta_n: the ships' (true or measured) NED poses ``[x, y, psi]`` (m, m, rad), (n, 3).

        Returns:
            ``[x^r, y^r, psi^r]`` (m, m, rad), (n, 3), so that ``eta_d_r - ref.to_r(eta)`` has
            no 2 pi jump.

        Raises:
            ValueError: ``eta_n`` not of shape (n, 3).
        """
        eta = np.asarray(eta_n, dtype=float)
        n = self.t_leg.shape[0]
        if eta.shape != (n, 3):
            raise ValueError(
                f"eta_n must have shape ({n}, 3) ([x, y, psi] per env), got {eta.shape}"
            )
        P = self.eta_P
        if self._cur is not None:
            c, s = self._cur[_CP], self._cur[_SP]
        else:
            c, s = np.cos(P[:, 2]), np.sin(P[:, 2])
        dx = eta[:, 0] - P[:, 0]
        dy = eta[:, 1] - P[:, 1]
        ref = self.eta_d_r[:, 2]
        out = np.empty((3, n))
        out[0] = c * dx + s * dy
        out[1] = -s * dx + c * dy
        # psi^r = ref + wrap(psi - psi_P - ref), wrap(a) = pi - mod(pi - a, 2 pi)
        out[2] = ref + (_PI - np.mod(_PI - (eta[:, 2] - P[:, 2] - ref), _TWO_PI))
        return out.T


def _profile_rows(plan: ManoeuvrePlan, limits: Limits | None, wp: Array) -> Array:
    """The table columns (_ROWS, n_legs) of one plan started at the waypoints ``wp``."""
    out = np.zeros((_ROWS, plan.n_legs))
    for j, leg in enumerate(plan.legs):
        p = leg_profile(leg, limits)
        xp, yp, psip = wp[j].tolist()
        c, s = math.cos(psip), math.sin(psip)
        d0, d1, d2 = p.displacement.tolist()
        Ta, A = p.t_accel, p.accel
        w = 2.0 * math.pi / Ta if Ta > 0.0 else 1.0  # unused where T_a = 0 (no profile)
        col = out[:, j]
        col[_D] = (d0, d1, d2)
        col[_DN] = (c * d0 - s * d1, s * d0 + c * d1, d2)
        col[_P] = (xp, yp, psip)
        col[_CP], col[_SP] = c, s
        col[_K] = wp[j + 1]
        col[_V] = p.speed
        col[_TA] = Ta
        col[_T] = p.duration
        col[_DELAY] = p.delay
        col[_TMTA] = p.duration - Ta
        col[_A] = A
        col[_H] = 0.5 * A
        col[_HH] = 0.25 * A
        col[_HQ] = A / (w * w)
        col[_HW] = 0.5 * A / w
        col[_W] = w
        col[_W2] = 0.5 * w
        col[_NEED] = plan.switch_min_progress * p.total_duration - 1e-9
    return out


class BatchedGuidance:
    """Leg-by-leg guidance of ``n`` envs, each through its own manoeuvre plan (module
    docstring; per env exactly :class:`~shipgym.guidance.runtime.Guidance`).

    Usage::

        g = BatchedGuidance(n, limits=vessel_limits(vessel))
        g.reset(plans, eta_start)                 # one plan per env, (n, 3) start poses
        for each control step at times t (n,):
            switched = g.update(t, eta)           # eta (n, 3); True where a leg completed
            ref = g.reference(t)                  # BatchedReference, (n, 3) arrays
        g.reset(new_plans, eta_start, t0=t, mask=done)   # the envs whose episode ended

    Args:
        n: number of envs, >= 1.
        limits: the vessel's :class:`~shipgym.guidance.reference.Limits` (a plan's own limits,
            and a leg's own, win, as in :class:`Guidance`).
    """

    def __init__(self, n: int, limits: Limits | None = None) -> None:
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ValueError(f"n must be an int >= 1 (the number of envs), got {n!r}")
        if limits is not None and not isinstance(limits, Limits):
            raise TypeError(f"limits must be a Limits or None, got {type(limits).__name__}")
        n = int(n)
        self.n = n
        self.limits = limits
        self.plans: list[ManoeuvrePlan | None] = [None] * n
        self._L = 1  # legs of the table (the longest plan so far)
        self._tab = np.zeros((_ROWS, n, 1))
        self._tab[_W] = self._tab[_W2] = 1.0
        self._cur = self._tab[:, :, 0].copy()
        self._cur.setflags(write=False)
        self._n_legs = np.ones(n, dtype=np.intp)
        self._sd = np.ones(n)  # switch distance (m)
        self._sh = np.ones(n)  # switch heading (rad)
        self._settle = np.zeros(n)  # settle time (s)
        self._leg = self._frozen(np.zeros(n, dtype=np.intp))
        self._finished = self._frozen(np.zeros(n, dtype=bool))
        self._active = np.ones(n, dtype=bool)  # ~finished
        self._t_start = np.zeros(n)  # start time of the current leg (s)
        self._t0 = np.zeros(n)
        self._hold = np.full(n, np.nan)  # since when the conditions hold (nan: they do not)
        self._comp = np.full((n, 1), np.nan)  # completion time of each leg (s)
        self._ready = np.zeros(n, dtype=bool)
        self._all_ready = False
        self._rows = np.arange(n)

    @staticmethod
    def _frozen(a: NDArray[Any]) -> NDArray[Any]:
        a.setflags(write=False)
        return a

    # -- state -------------------------------------------------------------------------------
    def _mask(self, mask: ArrayLike | None) -> NDArray[np.bool_]:
        if mask is None:
            return np.ones(self.n, dtype=bool)
        m = np.asarray(mask)
        if m.shape != (self.n,) or m.dtype != bool:
            raise ValueError(
                f"mask must be a bool array of shape ({self.n},), got {m.dtype} {m.shape}"
            )
        return m

    def _per_env(self, x: ArrayLike, idx: NDArray[np.intp], name: str, shape: tuple) -> Array:
        """``x`` for the reset envs: one entry per env (the reset ones used), one per reset
        env, or one for all."""
        a = np.asarray(x, dtype=float)
        k = idx.shape[0]
        if a.shape == shape:
            a = np.broadcast_to(a, (k, *shape))
        elif a.shape == (self.n, *shape):
            a = a[idx]
        elif a.shape != (k, *shape):
            want = " x ".join(str(s) for s in shape) or "scalar"
            raise ValueError(
                f"{name} must hold one {want} per env ({self.n}) or per reset env ({k}), "
                f"or one for all, got shape {a.shape}"
            )
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{name} must be finite, got {a!r}")
        return a

    def reset(
        self,
        plans: Sequence[ManoeuvrePlan],
        eta_start: ArrayLike,
        t0: ArrayLike = 0.0,
        mask: ArrayLike | None = None,
    ) -> None:
        """Start the plans of the envs (all, or those where ``mask`` is True).

        Args:
            plans: one :class:`ManoeuvrePlan` per reset env (in env order), or one per env
                (the reset envs' used).
            eta_start: the NED start poses ``[x, y, psi]`` (m, m, rad): (n, 3) (the reset
                envs' rows used), one row per reset env, or (3,) for all.
            t0: the reset envs' clocks at the start (s): a scalar, (n,) or one per reset env.
            mask: bool (n,), the envs to reset; ``None``: all.

        Raises:
            ValueError: wrong shapes or counts, non-finite values.
            TypeError: a plan that is not a :class:`ManoeuvrePlan`, or no limits for a leg
                (neither ``limits``, the plan's nor the leg's own).
        """
        m = self._mask(mask)
        idx = np.nonzero(m)[0]
        k = idx.shape[0]
        if isinstance(plans, ManoeuvrePlan) or not isinstance(plans, Sequence):
            raise TypeError(
                f"plans must be a sequence of ManoeuvrePlan, got {type(plans).__name__}"
            )
        if len(plans) == k:
            chosen = list(plans)
        elif len(plans) == self.n:
            chosen = [plans[i] for i in idx.tolist()]
        else:
            raise ValueError(
                f"plans must hold one plan per reset env ({k}) or per env ({self.n}), "
                f"got {len(plans)}"
            )
        for p in chosen:
            if not isinstance(p, ManoeuvrePlan):
                raise TypeError(f"BatchedGuidance needs ManoeuvrePlans, got {type(p).__name__}")
        starts = self._per_env(eta_start, idx, "eta_start", (3,))
        t0s = self._per_env(t0, idx, "t0", ())
        # everything computed before any state changes (a failing reset changes nothing)
        cols = []
        for p, e in zip(chosen, starts, strict=True):
            lim = p.limits if p.limits is not None else self.limits
            cols.append(_profile_rows(p, lim, p.waypoints(e)))
        L = max([self._L, *(p.n_legs for p in chosen)])
        if L > self._L:  # a longer plan: pad the tables
            tab = np.zeros((_ROWS, self.n, L))
            tab[_W] = tab[_W2] = 1.0
            tab[:, :, : self._L] = self._tab
            comp = np.full((self.n, L), np.nan)
            comp[:, : self._L] = self._comp
            self._tab, self._comp, self._L = tab, comp, L
        for i, p, col in zip(idx.tolist(), chosen, cols, strict=True):
            nl = p.n_legs
            self._tab[:, i, :nl] = col
            self._n_legs[i] = nl
            self._sd[i] = p.switch_distance
            self._sh[i] = p.switch_heading
            self._settle[i] = p.settle_time
            self.plans[i] = p
        self._comp[idx] = np.nan
        self._t0[idx] = t0s
        self._t_start[idx] = t0s
        self._hold[idx] = np.nan
        leg = self._leg.copy()
        leg[idx] = 0
        self._leg = self._frozen(leg)
        fin = self._finished.copy()
        fin[idx] = False
        self._finished = self._frozen(fin)
        self._active[idx] = True
        cur = self._cur.copy()
        cur[:, idx] = self._tab[:, idx, 0]
        self._cur = self._frozen(cur)
        self._ready[idx] = True
        self._all_ready = bool(self._ready.all())

    def _require_reset(self) -> None:
        if not self._all_ready:
            bad = np.nonzero(~self._ready)[0].tolist()
            raise RuntimeError(
                f"BatchedGuidance.reset(plans, eta_start) must be called for every env before "
                f"use; never reset: envs {bad[:10]}{'...' if len(bad) > 10 else ''}"
            )

    def _times(self, t: ArrayLike) -> Array:
        tt = np.asarray(t, dtype=float)
        if tt.shape != (self.n,):
            if tt.ndim != 0:
                raise ValueError(
                    f"t must have shape ({self.n},) (one time per env, s), got {tt.shape}"
                )
            tt = np.full(self.n, float(tt))
        return tt

    # -- read-outs ---------------------------------------------------------------------------
    @property
    def leg(self) -> NDArray[np.intp]:
        """Index of each env's current leg (the last one once finished), (n,), read-only."""
        return self._leg

    @property
    def finished(self) -> NDArray[np.bool_]:
        """True where the env's last leg's switching condition has held, (n,), read-only."""
        return self._finished

    @property
    def n_legs(self) -> NDArray[np.intp]:
        """Number of legs of each env's plan, (n,)."""
        return self._n_legs.copy()

    @property
    def legs_completed(self) -> NDArray[np.intp]:
        """Number of legs each env has completed, (n,)."""
        return self._leg + self._finished

    def leg_completion_times(self, i: int | None = None) -> Any:
        """Completion (switch) times (s) of the legs completed so far: of env ``i`` as a
        tuple, or (``i=None``) of every env as a list of lists."""
        done = self.legs_completed
        if i is not None:
            return tuple(self._comp[i, : done[i]].tolist())
        return [self._comp[j, : done[j]].tolist() for j in range(self.n)]

    def leg_start_times(self, i: int) -> tuple[float, ...]:
        """Start times (s) of the legs env ``i`` has started so far."""
        return (float(self._t0[i]), *self._comp[i, : self._leg[i]].tolist())

    def waypoints(self, i: int) -> Array:
        """Planned NED poses ``[P_0, K_0, ..., K_{n-1}]`` of env ``i``, (n_legs + 1, 3)."""
        nl = int(self._n_legs[i])
        out = np.empty((nl + 1, 3))
        out[:nl] = self._tab[_P, i, :nl].T
        out[nl] = self._tab[_K, i, nl - 1]
        return out

    def reference_durations(self, i: int) -> tuple[float, ...]:
        """Planned reference duration (s) of every leg of env ``i`` (``delay`` included)."""
        nl = int(self._n_legs[i])
        return tuple((self._tab[_DELAY, i, :nl] + self._tab[_T, i, :nl]).tolist())

    # -- per step ----------------------------------------------------------------------------
    def update(self, t: ArrayLike, eta_n: ArrayLike) -> NDArray[np.bool_]:
        """Check the switching rule of every env (:meth:`Guidance.update
        <shipgym.guidance.runtime.Guidance.update>` per env).

        Args:
            t: each env's time (s), (n,) (a scalar: the same for all).
            eta_n: each env's ship pose ``[x, y, psi]`` in NED (m, m, rad), (n, 3).

        Returns:
            bool (n,): True where the env's current leg completes at this call (its next leg
            starts at its ``t``, or its plan is finished); always False for a finished env.

        Raises:
            ValueError: wrong shapes, or a non-finite time or pose of an unfinished env.
            RuntimeError: an env never reset.
        """
        self._require_reset()
        t = self._times(t)
        eta = np.asarray(eta_n, dtype=float)
        if eta.shape != (self.n, 3):
            raise ValueError(
                f"eta_n must have shape ({self.n}, 3) ([x, y, psi] per env), got {eta.shape}"
            )
        if not math.isfinite(float(t.sum() + eta.sum())):
            bad = ~(np.isfinite(t) & np.isfinite(eta).all(axis=1)) & self._active
            if bad.any():
                i = int(np.nonzero(bad)[0][0])
                raise ValueError(
                    f"t and eta_n must be finite: env {i} has t={t[i]!r}, eta_n={eta[i]!r}"
                )
        cur = self._cur  # finished envs: _NEED is inf (never switch again)
        # 1. distance to K below switch_distance; 2. |wrap(psi - psi_K)| below switch_heading
        near = np.hypot(eta[:, 0] - cur[_KX], eta[:, 1] - cur[_KY]) < self._sd
        a = eta[:, 2] - cur[_KPSI]
        near &= np.abs(_PI - np.mod(_PI - a, _TWO_PI)) < self._sh
        # 3. progress: the leg's time at least switch_min_progress of its duration
        near &= t - self._t_start >= cur[_NEED]
        # 4. held continuously for settle_time
        hold = np.where(near, np.where(np.isnan(self._hold), t, self._hold), np.nan)
        switched = t - hold >= self._settle
        self._hold = hold
        if switched.any():
            self._switch(switched, t)
        return switched

    def _switch(self, switched: NDArray[np.bool_], t: Array) -> None:
        """Complete the current legs of the ``switched`` envs at their times ``t``."""
        idx = np.nonzero(switched)[0]
        legs = self._leg[idx]
        self._comp[idx, legs] = t[idx]
        self._hold[idx] = np.nan
        nxt = legs + 1
        last = nxt >= self._n_legs[idx]
        done = idx[last]
        adv = idx[~last]
        cur = self._cur.copy()
        if done.shape[0]:  # the plan is finished: the reference stays at the last K
            fin = self._finished.copy()
            fin[done] = True
            self._finished = self._frozen(fin)
            self._active[done] = False
            cur[_NEED, done] = np.inf
        if adv.shape[0]:  # the next leg starts now, at rest at its P
            leg = self._leg.copy()
            leg[adv] = nxt[~last]
            self._leg = self._frozen(leg)
            self._t_start[adv] = t[adv]
            cur[:, adv] = self._tab[:, adv, leg[adv]]
        self._cur = self._frozen(cur)

    def reference(self, t: ArrayLike) -> BatchedReference:
        """The reference of every env at its time ``t`` (s), (n,), for its current leg
        (:meth:`Guidance.reference <shipgym.guidance.runtime.Guidance.reference>` per env:
        at rest at P before the leg's start and during its ``delay``, at rest at K after).

        Raises:
            ValueError: ``t`` of the wrong shape.
            RuntimeError: an env never reset.
        """
        self._require_reset()
        t = self._times(t)
        cur = self._cur
        t_leg = t - self._t_start
        tt = t_leg - cur[_DELAY]  # the profile's time
        acc = tt < cur[_TA]
        # the ramp's time: since the start (acceleration), else to the end (deceleration),
        # clipped to [0, T_a]: 0 gives rest (s = 0 before the start and during the delay, 1
        # from T on; a step or zero leg has T_a = T = 0), T_a the cruise
        u = np.where(acc, tt, cur[_T] - tt)
        np.minimum(u, cur[_TA], out=u)
        np.maximum(u, 0.0, out=u)
        # the raised-cosine ramp (reference.LegProfile._ramp): s_ddot = (A/2)(1 - cos(w u))
        sh = np.sin(cur[_W2] * u)
        q = sh * sh
        p = cur[_HH] * (u * u) - cur[_HQ] * q
        sd = cur[_H] * u - cur[_HW] * np.sin(cur[_W] * u)
        a = cur[_A] * q
        # deceleration (and cruise, rest at K): 1 - ramp(T - t) - V (T - T_a - t)^+
        s = np.where(acc, p, 1.0 - p - cur[_V] * np.maximum(cur[_TMTA] - tt, 0.0))
        sdd = np.where(acc, a, -a)
        D = cur[_D]
        eta_d_r = s * D
        eta_d_n = cur[_P] + s * cur[_DN]
        return BatchedReference(
            eta_d_r.T,
            (sd * D).T,
            (sdd * D).T,
            cur[_P].T,
            eta_d_n.T,
            cur[_K].T,
            self._leg,
            t_leg,
            self._finished,
            cur,
        )
