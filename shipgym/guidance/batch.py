"""The run-time guidance of N >= 1 envs: compiled reference and leg switching (Tomera 2014).

Public names: ``BatchedGuidance``, ``BatchedReference``.
Sources: Tomera (2014); Fossen (2011).

Design notes: docs/design/guidance.batch.md.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import njit

from .plan import ManoeuvrePlan
from .reference import LegProfile, Limits, leg_profile, path_law
from .rframe import r_frame_poses

__all__ = ["BatchedGuidance", "BatchedReference"]

Array = NDArray[np.float64]

_PI = math.pi
_TWO_PI = 2.0 * math.pi

# columns of the per-leg table: displacement [surge, sway, yaw] (m, m, rad), P and K (NED, m,
# m, rad), cos and sin of psi_P, the profile (V 1/s, A 1/s^2, T_a, T_c, T, delay s) and the
# progress threshold switch_min_progress * (delay + T) - 1e-9 (s)
_D, _P, _CP, _SP, _K = 0, 3, 6, 7, 8
_V, _A, _TA, _TC, _T, _DELAY, _NEED = 11, 12, 13, 14, 15, 16, 17
_R = 18
# columns of the per-env state: current leg, finished (1.0), its start time (s), since when
# the switching conditions hold (s, nan: they do not), the clock at reset (s), number of
# legs, switch distance (m), switch heading (rad), settle time (s)
_LEG, _FIN, _TSTART, _HOLD, _T0, _NLEGS, _SD, _SH, _SETTLE = range(9)
_S = 9
# rows of a reference's (n, 10, 3) buffer
_ROWS = ("eta_d_r", "eta_dot_d_r", "eta_ddot_d_r", "eta_P", "eta_d_n", "eta_K")
_NU, _NU_DOT, _ETA_DOT_N, _TLEG = 6, 7, 8, 9


# ---- the compiled laws ----------------------------------------------------------------------
@njit
def _kinematics(o: Array) -> None:
    """Rows 6-8 of one env's reference buffer ``o`` (10, 3) from rows 0-3: the body-frame
    velocity ``nu_d = R(psi_d^r)^T eta_dot_d^r``, its derivative ``nu_dot_d = R^T
    eta_ddot_d^r - S(r_d) nu_d`` (Fossen 2011 eq. 2.62, ``S(r) = [[0, -r, 0], [r, 0, 0],
    [0, 0, 0]]``) and the NED velocity ``R(psi_P) eta_dot_d^r``."""
    c, s = math.cos(o[0, 2]), math.sin(o[0, 2])
    v0, v1, r = o[1, 0], o[1, 1], o[1, 2]
    a0, a1 = o[2, 0], o[2, 1]
    nu0 = c * v0 + s * v1
    nu1 = -s * v0 + c * v1
    o[_NU, 0], o[_NU, 1], o[_NU, 2] = nu0, nu1, r
    o[_NU_DOT, 0] = c * a0 + s * a1 + r * nu1
    o[_NU_DOT, 1] = -s * a0 + c * a1 - r * nu0
    o[_NU_DOT, 2] = o[2, 2]
    cp, sp = math.cos(o[3, 2]), math.sin(o[3, 2])
    o[_ETA_DOT_N, 0] = cp * v0 - sp * v1
    o[_ETA_DOT_N, 1] = sp * v0 + cp * v1
    o[_ETA_DOT_N, 2] = r


@njit
def _reference(t: Array, tab: Array, st: Array) -> Array:
    """The reference of every env at its time ``t[i]`` (s): a new buffer (n, 10, 3) of
    rows ``eta_d_r, eta_dot_d_r, eta_ddot_d_r, eta_P, eta_d_n, eta_K, nu_d, nu_dot_d,
    eta_dot_d_n`` and ``[t_leg, 0, 0]``. ``eta_d^r = s(t_leg - delay) Delta`` and
    ``eta_d^n = P + R(psi_P) eta_d^r`` (Tomera 2014 eq. 2, heading not wrapped)."""
    n = t.shape[0]
    out = np.empty((n, 10, 3))
    for i in range(n):
        if not math.isfinite(t[i]):
            raise ValueError("the guidance's times t must be finite (s)")
        row = tab[i, int(st[i, _LEG])]
        t_leg = t[i] - st[i, _TSTART]
        s, sd, sdd = path_law(row[_V], row[_A], row[_TA], row[_TC], row[_T], t_leg - row[_DELAY])
        o = out[i]
        for k in range(3):
            d = row[_D + k]
            o[0, k] = s * d
            o[1, k] = sd * d
            o[2, k] = sdd * d
            o[3, k] = row[_P + k]
            o[5, k] = row[_K + k]
        c, sn = row[_CP], row[_SP]
        xr, yr = o[0, 0], o[0, 1]
        o[4, 0] = row[_P] + c * xr - sn * yr
        o[4, 1] = row[_P + 1] + sn * xr + c * yr
        o[4, 2] = row[_P + 2] + o[0, 2]
        _kinematics(o)
        o[_TLEG, 0], o[_TLEG, 1], o[_TLEG, 2] = t_leg, 0.0, 0.0
    return out


@njit
def _derived(eta_d_r: Array, eta_dot_d_r: Array, eta_ddot_d_r: Array, eta_P: Array) -> Array:
    """Reference buffers (n, 10, 3) of given rows 0-3 (each (n, 3)) with rows 6-8 filled
    (:func:`_kinematics`): the velocities of a reference built from its fields."""
    n = eta_d_r.shape[0]
    out = np.zeros((n, 10, 3))
    for i in range(n):
        o = out[i]
        for k in range(3):
            o[0, k], o[1, k] = eta_d_r[i, k], eta_dot_d_r[i, k]
            o[2, k], o[3, k] = eta_ddot_d_r[i, k], eta_P[i, k]
        _kinematics(o)
    return out


@njit
def _conditions(row: Array, sti: Array, t: float, x: float, y: float, psi: float) -> tuple:
    """The three instantaneous switching conditions of one env on its current leg ``row``:
    distance to K below ``switch_distance`` and ``|wrap(psi - psi_K)|`` below
    ``switch_heading`` (Tomera 2014), elapsed leg time at least ``switch_min_progress`` of
    the leg's reference duration (ours)."""
    near = math.hypot(x - row[_K], y - row[_K + 1]) < sti[_SD]
    wrapped = _PI - (_PI - (psi - row[_K + 2])) % _TWO_PI  # in (-pi, pi]
    return near, abs(wrapped) < sti[_SH], t - sti[_TSTART] >= row[_NEED]


@njit
def _bad_row(t: Array, eta: Array, st: Array) -> int:
    """The first unfinished env with a non-finite time or pose, -1 if none."""
    for i in range(t.shape[0]):
        if st[i, _FIN] == 0.0:
            ok = math.isfinite(t[i]) and math.isfinite(eta[i, 0])
            if not (ok and math.isfinite(eta[i, 1]) and math.isfinite(eta[i, 2])):
                return i
    return -1


@njit
def _update(t: Array, eta: Array, tab: Array, st: Array, comp: Array, sw: Any) -> int:
    """The switching rule of every env at its time ``t[i]`` (s) and pose ``eta[i]`` (m, m,
    rad): ``sw[i]`` True where the current leg completes (the conditions of
    :func:`_conditions` held for ``settle_time``); the next leg starts at ``t[i]``, or the
    plan is finished. Returns the number of switches, or ``-1 - i`` for a non-finite time or
    pose of the unfinished env ``i`` (then nothing changes)."""
    bad = _bad_row(t, eta, st)
    if bad >= 0:
        return -1 - bad
    count = 0
    for i in range(t.shape[0]):
        sw[i] = False
        sti = st[i]
        if sti[_FIN] != 0.0:
            continue
        j = int(sti[_LEG])
        ti = t[i]
        near, aligned, progressed = _conditions(tab[i, j], sti, ti, eta[i, 0], eta[i, 1], eta[i, 2])
        if not (near and aligned and progressed):
            sti[_HOLD] = np.nan
            continue
        if math.isnan(sti[_HOLD]):
            sti[_HOLD] = ti
        if ti - sti[_HOLD] < sti[_SETTLE]:
            continue
        sti[_HOLD] = np.nan
        comp[i, j] = ti
        if j + 1 < sti[_NLEGS]:
            sti[_LEG] = j + 1
            sti[_TSTART] = ti
        else:
            sti[_FIN] = 1.0
        sw[i] = True
        count += 1
    return count


# ---- the reference --------------------------------------------------------------------------
class BatchedReference:
    """The guidance output of ``n`` envs at one instant (the reference of
    :class:`~shipgym.guidance.runtime.Reference` per env).

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

    The guidance's references are read-only views of one buffer and never change afterwards.
    """

    __slots__ = (*_ROWS, "leg", "t_leg", "finished", "_buf")

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
        _buf: Array | None = None,
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
        self._buf = _buf

    @classmethod
    def _of(cls, buf: Array, leg: NDArray[np.intp], finished: NDArray[np.bool_]) -> Any:
        """The reference of a buffer of :func:`_reference` (made read-only)."""
        buf.setflags(write=False)
        b = buf
        return cls(b[:, 0], b[:, 1], b[:, 2], b[:, 3], b[:, 4], b[:, 5], leg, b[:, _TLEG, 0],
                   finished, b)  # fmt: skip

    @property
    def n(self) -> int:
        """Number of envs."""
        return int(self.t_leg.shape[0])

    def _row(self, k: int) -> Array:
        return self.buffer[:, k]

    @property
    def buffer(self) -> Array:
        """The reference as one (n, 10, 3) array, rows ``eta_d_r``, ``eta_dot_d_r``,
        ``eta_ddot_d_r``, ``eta_P``, ``eta_d_n``, ``eta_K``, ``nu_d``, ``nu_dot_d``,
        ``eta_dot_d_n`` and ``[t_leg, 0, 0]`` (what compiled consumers read)."""
        if self._buf is None:  # built from its fields: the velocities from them
            f = [np.ascontiguousarray(a, dtype=float) for a in (
                self.eta_d_r, self.eta_dot_d_r, self.eta_ddot_d_r, self.eta_P)]  # fmt: skip
            buf = _derived(*f)
            buf[:, 4], buf[:, 5], buf[:, _TLEG, 0] = self.eta_d_n, self.eta_K, self.t_leg
            buf.setflags(write=False)
            self._buf = buf
        return self._buf

    @property
    def eta_dot_d_n(self) -> Array:
        """Desired NED velocities ``R(psi_P) eta_dot_d^r`` (m/s, m/s, rad/s), (n, 3)."""
        return self._row(_ETA_DOT_N)

    @property
    def nu_d(self) -> Array:
        """Desired body-frame velocities ``R(psi_d^r)^T eta_dot_d^r`` (m/s, m/s, rad/s), (n, 3)."""
        return self._row(_NU)

    @property
    def nu_dot_d(self) -> Array:
        """Time derivative of :attr:`nu_d`: ``R^T eta_ddot_d^r - S(r_d) nu_d`` (m/s^2,
        m/s^2, rad/s^2), (n, 3) (Fossen 2011 eq. 2.62 differentiated)."""
        return self._row(_NU_DOT)

    def to_r(self, eta_n: ArrayLike) -> Array:
        """NED poses (n, 3) in each env's current leg's r-frame, heading unwrapped near
        ``psi_d^r`` (Tomera 2014 eq. 1, :func:`~shipgym.guidance.rframe.to_r_frame`).

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
        # to_r_frame(eta, eta_P, psi_ref_r=psi_d^r) without its broadcasting: the rows as they
        # are (the buffer's views), the same compiled law
        out = np.empty((n, 3))
        r_frame_poses(eta, self.eta_P, self.eta_d_r[:, 2], True, out)
        return out


# ---- the guidance ---------------------------------------------------------------------------
def _leg_table(plan: ManoeuvrePlan, profiles: Sequence[LegProfile], wp: Array) -> Array:
    """The table rows (n_legs, _R) of one plan with its leg profiles, started at the planned
    poses ``wp`` (n_legs + 1, 3)."""
    out = np.zeros((plan.n_legs, _R))
    for j, p in enumerate(profiles):
        row = out[j]
        row[_D : _D + 3] = p.displacement
        row[_P : _P + 3] = wp[j]
        psip = float(wp[j, 2])
        row[_CP], row[_SP] = math.cos(psip), math.sin(psip)
        row[_K : _K + 3] = wp[j + 1]
        row[_V], row[_A], row[_TA] = p.speed, p.accel, p.t_accel
        row[_TC], row[_T], row[_DELAY] = p.t_cruise, p.duration, p.delay
        row[_NEED] = plan.switch_min_progress * p.total_duration - 1e-9
    return out


#: leg tables kept by :meth:`BatchedGuidance._table` (plan objects a task reuses)
_TABLES = 16


class BatchedGuidance:
    """Leg-by-leg guidance of ``n`` envs, each through its own manoeuvre plan (module
    docstring; :class:`~shipgym.guidance.runtime.Guidance` is its ``n = 1`` case).

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
        self._tab = np.zeros((n, 1, _R))
        self._st = np.zeros((n, _S))
        self._st[:, _HOLD] = np.nan
        self._st[:, _NLEGS] = 1.0
        self._comp = np.full((n, 1), np.nan)  # completion time of each leg (s)
        self._leg = self._frozen(np.zeros(n, dtype=np.intp))
        self._finished = self._frozen(np.zeros(n, dtype=bool))
        self._ready = np.zeros(n, dtype=bool)
        self._all_ready = False
        # the leg tables of recent (plan, start) pairs: _table
        self._tables: dict[tuple[int, bytes], tuple[ManoeuvrePlan, Array]] = {}

    @staticmethod
    def _frozen(a: NDArray[Any]) -> NDArray[Any]:
        a.setflags(write=False)
        return a

    def _refresh(self) -> None:
        """New read-only ``leg`` and ``finished`` arrays after a switch or a reset."""
        self._leg = self._frozen(self._st[:, _LEG].astype(np.intp))
        self._finished = self._frozen(self._st[:, _FIN] != 0.0)

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
        *,
        _profiles: Sequence[Sequence[LegProfile]] | None = None,
        _waypoints: Sequence[Array] | None = None,
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
        if _profiles is None and _waypoints is None:
            rows = [self._table(p, e) for p, e in zip(chosen, starts, strict=True)]
        else:
            if _profiles is None:
                _profiles = [self._profiles(p) for p in chosen]
            if _waypoints is None:
                _waypoints = [p.waypoints(e) for p, e in zip(chosen, starts, strict=True)]
            rows = [
                _leg_table(p, prof, wp)
                for p, prof, wp in zip(chosen, _profiles, _waypoints, strict=True)
            ]
        L = max([self._tab.shape[1], *(p.n_legs for p in chosen)])
        if L > self._tab.shape[1]:  # a longer plan: pad the tables
            tab = np.zeros((self.n, L, _R))
            tab[:, : self._tab.shape[1]] = self._tab
            comp = np.full((self.n, L), np.nan)
            comp[:, : self._comp.shape[1]] = self._comp
            self._tab, self._comp = tab, comp
        st = self._st
        for i, p, r, t_0 in zip(idx.tolist(), chosen, rows, t0s.tolist(), strict=True):
            self._tab[i, : p.n_legs] = r
            st[i] = 0.0
            st[i, _HOLD] = np.nan
            st[i, _TSTART] = st[i, _T0] = t_0
            st[i, _NLEGS] = p.n_legs
            st[i, _SD], st[i, _SH] = p.switch_distance, p.switch_heading
            st[i, _SETTLE] = p.settle_time
            self.plans[i] = p
        self._comp[idx] = np.nan
        self._refresh()
        self._ready[idx] = True
        self._all_ready = bool(self._ready.all())

    def _profiles(self, plan: ManoeuvrePlan) -> list[LegProfile]:
        """The leg profiles of ``plan`` under its limits (its own, else the guidance's)."""
        limits = plan.limits if plan.limits is not None else self.limits
        return [leg_profile(leg, limits) for leg in plan.legs]

    def _table(self, plan: ManoeuvrePlan, start: Array) -> Array:
        """:func:`_leg_table` of ``plan`` started at ``start``, kept for the next episodes of
        the same plan object and start (a plan is frozen, and a task with a fixed plan and
        start gives every episode the same table: the harbour's five legs, the station's
        one); the last :data:`_TABLES` kept."""
        key = (id(plan), start.tobytes())
        hit = self._tables.get(key)
        if hit is not None and hit[0] is plan:
            return hit[1]
        rows = _leg_table(plan, self._profiles(plan), plan.waypoints(start))
        rows.setflags(write=False)
        if len(self._tables) >= _TABLES:
            del self._tables[next(iter(self._tables))]
        self._tables[key] = (plan, rows)
        return rows

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

    def _poses(self, eta_n: ArrayLike) -> Array:
        eta = np.asarray(eta_n, dtype=float)
        if eta.shape != (self.n, 3):
            raise ValueError(
                f"eta_n must have shape ({self.n}, 3) ([x, y, psi] per env), got {eta.shape}"
            )
        return eta

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
        return self._st[:, _NLEGS].astype(np.intp)

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
        return (float(self._st[i, _T0]), *self._comp[i, : self._leg[i]].tolist())

    def waypoints(self, i: int) -> Array:
        """Planned NED poses ``[P_0, K_0, ..., K_{n-1}]`` of env ``i``, (n_legs + 1, 3)."""
        nl = int(self._st[i, _NLEGS])
        out = np.empty((nl + 1, 3))
        out[:nl] = self._tab[i, :nl, _P : _P + 3]
        out[nl] = self._tab[i, nl - 1, _K : _K + 3]
        return out

    def reference_durations(self, i: int) -> tuple[float, ...]:
        """Planned reference duration (s) of every leg of env ``i`` (``delay`` included)."""
        tab = self._tab[i, : int(self._st[i, _NLEGS])]
        return tuple((tab[:, _DELAY] + tab[:, _T]).tolist())

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
        t, eta = self._times(t), self._poses(eta_n)
        switched = np.empty(self.n, dtype=bool)
        count = _update(t, eta, self._tab, self._st, self._comp, switched)
        if count < 0:
            i = -1 - count
            raise ValueError(
                f"t and eta_n must be finite: env {i} has t={t[i]!r}, eta_n={eta[i]!r}"
            )
        if count:
            self._refresh()
        return switched

    def reference(self, t: ArrayLike) -> BatchedReference:
        """The reference of every env at its time ``t`` (s), (n,), for its current leg
        (:meth:`Guidance.reference <shipgym.guidance.runtime.Guidance.reference>` per env:
        at rest at P before the leg's start and during its ``delay``, at rest at K after).

        Raises:
            ValueError: ``t`` of the wrong shape or not finite.
            RuntimeError: an env never reset.
        """
        self._require_reset()
        buf = _reference(self._times(t), self._tab, self._st)
        return BatchedReference._of(buf, self._leg, self._finished)
