r"""The double-integrator Kalman filters of :mod:`shipgym.observers.kalman` for ``N`` envs at once.

:class:`BatchedKalman` runs ``N`` copies of one preset (``kbf``, ``dkf``, ``tomera-kbf``,
``tomera-dkf``, or any :class:`~shipgym.observers.kalman.KalmanBucyFilter` /
:class:`~shipgym.observers.kalman.DiscreteKalmanFilter` built by a factory) in one NumPy
computation, each env exactly as the scalar filter (same model, Tomera (2011) eqs. 53-60;
same first-order hold and hold rules, Hamiltonian blocks, Joseph update, outlier gate) so that
env ``i`` gives what a scalar filter fed the same samples gives, to round-off (a test checks
it for every preset, with outliers, forced acceptances, dropouts and masked resets)::

    f = BatchedKalman("kbf", n, vessel=vessel)
    f.reset(t0, eta0)                          # t0 (n,) or a number, eta0 (n, 3)
    info = f.step(t, z, valid)                 # t (n,), z (n, 3), valid (n,) bool
    f.eta, f.nu, f.P_eta, f.P_nu               # (n, 3), (n, 3), (n, 3, 3), (n, 3, 3)

Layout: the DOFs are independent 2x2 problems (cross-DOF covariances are zero), so the state
is one array ``(5, 3, n)``: per DOF (rows ``x, y, psi``) and env (last axis) the NED rate,
the pose, and the covariance entries ``P_vv, P_vp, P_pp`` of ``[velocity, position]``
(Tomera's (2011) order); the 2x2 algebra is written out elementwise (no ``np.linalg`` in the
step), with the env axis last so that each operation runs over contiguous rows.

Per-env design: the measurement variances ``R`` may differ per env (``R=`` at construction or
reset, ``(n, 3)`` in m^2, m^2, rad^2), as ``make_observer(name, vessel, R=R_i)`` would build
env ``i``'s filter. What depends on ``R`` is recomputed per env when ``R`` changes: the
Hamiltonian blocks of the time-varying Kalman-Bucy filter (one batched matrix exponential per
interval, as the scalar filter's), the steady-state gains (the Kalman-Bucy gain of Tomera (2014)
eq. 35 in its closed form ``L = [sqrt(q_v / r), sqrt(2 sqrt(q_v r) / r + q_p / r)]``; the
discrete filter-form gain of eq. 30 from the discrete Riccati equation, reduced to one
equation in ``P_pp`` and solved by Newton's method, :func:`dare_filter_gain`) and the
steady-state blocks. The process noise ``Q_k(dt)`` does not depend on ``R``.

Intervals: the matrices that depend on the interval ``dt`` are cached per ``dt`` (rounded to
1e-12 s, as the scalar filters key them). Envs whose ``dt`` differ (a reset mid-episode
restarts an env's clock) are stepped in groups of equal ``dt``; the common case, one ``dt`` for
all envs, is one group.

Not batched: ``P0`` at reset (the default initial covariance is used: ``R`` for the pose,
``initial_velocity_std**2`` for the rates) and the thrust (accepted, unused: the filters are
kinematic).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from .base import make_observer
from .design import KalmanDesign, dlqe, double_integrator
from .kalman import DiscreteKalmanFilter, KalmanBucyFilter, _dt_key

__all__ = ["BatchedKalman", "BatchedStepInfo", "dare_filter_gain"]

Array = NDArray[np.float64]
_A, _C = double_integrator()
_PI = math.pi
_TWO_PI = 2.0 * math.pi
_CACHE_SIZE = 16
_TIME_TOL = 1e-9  # s: a clock this much behind counts as no time passing (as the scalar filters)


class BatchedStepInfo(NamedTuple):
    """What one batched step did with each env's measurement (the arrays of
    :class:`~shipgym.observers.base.StepInfo`).

    Attributes:
        innovation: ``z - H x_pred`` (n, 3) (m, m, rad; heading wrapped), NaN rows where no
            measurement was given.
        nis: normalised innovation squared (n,) (-), NaN where no measurement.
        rejected: the measurement failed the NIS gate and was not used (n,).
        forced: the measurement failed the gate but was accepted (n,).
    """

    innovation: Array
    nis: Array
    rejected: NDArray[np.bool_]
    forced: NDArray[np.bool_]


def dare_filter_gain(F_dt: float, Qk: ArrayLike, R: ArrayLike) -> tuple[Array, Array]:
    r"""Steady-state filter-form gains of the sampled double integrator, many at once.

    For ``F = [[1, 0], [dt, 1]]``, ``H = [0, 1]``, process noise ``Q_k`` and measurement
    variance ``r`` the predicted steady-state covariance ``P = [[a, b], [b, c]]`` of the discrete
    Riccati equation (:func:`~shipgym.observers.design.dlqe`) satisfies, with ``S = c + r``,
    ``b^2 = q_vv S`` and ``c^2 = dt b (c + 2 r) + (q_pp - dt q_vp) S`` (the ``(0, 0)``, ``(0, 1)``
    and ``(1, 1)`` entries of the fixed point); the gain is ``K = [b, c] / S`` (Tomera 2014 eq. 30,
    Table 3). The equation in ``c`` is solved by Newton's method from above; entries where it does
    not converge fall back to :func:`~shipgym.observers.design.dlqe`.

    Args:
        F_dt: the sampling interval of ``F`` (s).
        Qk: ``[q_vv, q_vp, q_pp]`` each of shape ``(...)``, i.e. ``(3, ...)``.
        R: measurement variances ``(...)``.

    Returns:
        ``(K_v, K_p)``, each of shape ``(...)``.
    """
    q = np.asarray(Qk, dtype=float)
    r = np.asarray(R, dtype=float)
    q1, q12, q2 = np.broadcast_arrays(q[0], q[1], q[2], r)[:3]
    r = np.broadcast_to(r, q1.shape)
    T = float(F_dt)
    rq1 = np.sqrt(q1)
    lin = q2 - T * q12

    def f(c: Array) -> Array:
        return c * c - T * np.sqrt(q1 * (c + r)) * (c + 2.0 * r) - lin * (c + r)

    c = np.maximum(r, 1e-300).astype(float)
    for _ in range(400):  # an upper bound of the root (f > 0 right of it)
        low = f(c) <= 0.0
        if not low.any():
            break
        c = np.where(low, 4.0 * c, c)
    for _ in range(100):
        s = np.sqrt(c + r)
        df = 2.0 * c - T * rq1 * (0.5 * (c + 2.0 * r) / s + s) - lin
        step = f(c) / df
        c = c - step
        if np.all(np.abs(step) <= 1e-16 * np.abs(c)):
            break
    S = c + r
    b = np.sqrt(q1 * S)
    Kv, Kp = b / S, c / S
    bad = ~(np.abs(f(c)) <= 1e-12 * np.maximum(c * c, 1e-300)) | ~(c > 0.0)
    if bad.any():  # pragma: no cover - a far-off design (no convex equation): the scipy path
        F = np.eye(2) + _A * T
        for i in zip(*np.nonzero(bad), strict=True):
            Qi = np.array([[q1[i], q12[i]], [q12[i], q2[i]]])
            K = dlqe(F, np.eye(2), _C, Qi, np.array([[r[i]]]), form="filter")[0][:, 0]
            Kv[i], Kp[i] = K
    return Kv, Kp


def _expm(M: Array) -> Array:
    """``exp`` of a stack of square matrices (each as ``scipy.linalg.expm`` of one)."""
    return np.asarray(scipy.linalg.expm(M))


class BatchedKalman:
    """``n`` double-integrator Kalman filters of one preset stepped together (module doc).

    Args:
        observer: a preset name (``"kbf"``, ``"dkf"``, ``"tomera-kbf"``, ``"tomera-dkf"``, or
            another name whose factory builds one of the two filter classes), a factory
            ``(**overrides) -> filter`` or a filter instance (its design and settings are used).
        n: number of envs, >= 1.
        vessel: the vessel the preset is fitted to, as :func:`~shipgym.observers.base.
            make_observer` (only with a name).
        R: per-env measurement variances ``(n, 3)`` or one ``(3,)`` (m^2, m^2, rad^2);
            ``None``: the design's.
        **overrides: the factory's options (design fields, ``gate_probability``, ...).

    Raises:
        ValueError: ``n`` not an int >= 1, an observer that is not one of the two
            double-integrator filters, bad ``R``.
    """

    def __init__(
        self,
        observer: str | Callable[..., Any] | DiscreteKalmanFilter | KalmanBucyFilter = "kbf",
        n: int = 1,
        *,
        vessel: Any = None,
        R: ArrayLike | None = None,
        **overrides: Any,
    ) -> None:
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ValueError(f"n must be an int >= 1 (the number of envs), got {n!r}")
        n = int(n)
        if isinstance(observer, str):
            template = make_observer(observer, vessel, **overrides)
        elif isinstance(observer, DiscreteKalmanFilter | KalmanBucyFilter):
            if overrides or vessel is not None:
                raise ValueError("overrides and vessel= need a preset name or a factory")
            template = observer
        elif callable(observer):
            template = observer(**overrides)
        else:
            raise ValueError(f"observer must be a name, a factory or a filter, got {observer!r}")
        if not isinstance(template, DiscreteKalmanFilter | KalmanBucyFilter):
            raise ValueError(
                "BatchedKalman batches the double-integrator filters (DiscreteKalmanFilter, "
                f"KalmanBucyFilter), got {type(template).__name__}"
            )
        self.template = template
        self.name = template.name
        self.n = n
        self.design: KalmanDesign = template.design
        self.continuous = isinstance(template, KalmanBucyFilter)
        self.constant_gain = bool(
            template.steady_state if isinstance(template, KalmanBucyFilter)
            else template.constant_gain
        )  # fmt: skip
        self.threshold = float(template.gate.threshold)
        self.max_rejections = int(template.gate.max_rejections)
        self._W = np.array(template._W)  # (3, 2, 2) G Q G^T per DOF
        self._vel_var = np.asarray(template.initial_velocity_std, dtype=float) ** 2
        self._T = float(self.design.T)
        self._X = np.zeros((5, 3, n))
        self._t = np.zeros(n)
        self._started = np.zeros(n, dtype=bool)
        self._count = np.zeros(n, dtype=np.int64)
        self._open = np.zeros(n, dtype=bool)
        self._yprev = np.zeros((3, n))
        self._has_prev = np.zeros(n, dtype=bool)
        self._R = np.repeat(self.design.variance()[:, None], n, axis=1)
        self._Rc = self._R * self._T
        self._gain = np.zeros((2, 3, n))  # the steady-state gain per env (constant-gain kinds)
        self._Q: dict[float, Array] = {}
        self._blocks: dict[float, list[Any]] = {}  # key -> [blocks (..., n), stale (n,) bool]
        self._nan3 = np.full((n, 3), np.nan)
        self._nan = np.full(n, np.nan)
        self._false = np.zeros(n, dtype=bool)
        self._true = np.ones(n, dtype=bool)
        self._all_started = False
        for a in (self._nan3, self._nan, self._false, self._true):
            a.setflags(write=False)
        self._set_R(self._R.T if R is None else R, np.ones(n, dtype=bool), force=True)

    # ---- parameters ---------------------------------------------------------------------------
    def _rows(self, x: ArrayLike, what: str, unit: str) -> Array:
        a = np.asarray(x, dtype=float)
        if a.shape == (3,):
            a = np.broadcast_to(a, (self.n, 3))
        if a.shape != (self.n, 3):
            raise ValueError(f"{what} must be (3,) or ({self.n}, 3) ({unit}), got {np.shape(x)}")
        return a

    def _mask(self, mask: ArrayLike | None) -> NDArray[np.bool_]:
        if mask is None:
            return np.ones(self.n, dtype=bool)
        m = np.asarray(mask, dtype=bool)
        if m.shape != (self.n,):
            raise ValueError(f"mask must be ({self.n},) booleans, got shape {m.shape}")
        return m

    def _set_R(self, R: ArrayLike, m: NDArray[np.bool_], force: bool = False) -> None:
        """Set the variances of the envs in ``m``; refresh what depends on them."""
        Rn = self._rows(R, "R", "m^2, m^2, rad^2 per env").T
        if not np.all(np.isfinite(Rn[:, m])) or not np.all(Rn[:, m] > 0.0):
            raise ValueError("R must be finite variances > 0 (m^2, m^2, rad^2)")
        changed = m if force else m & np.any(Rn != self._R, axis=0)
        if not changed.any():
            return
        self._R[:, changed] = Rn[:, changed]
        self._Rc[:, changed] = self._R[:, changed] * self._T
        if self.constant_gain:
            if self.continuous:  # Tomera (2014) eqs. 33-35, closed form (design module doc)
                r = self._Rc[:, changed]
                b = np.sqrt(self._W[:, 0, 0, None] * r)
                c = np.sqrt(r * (2.0 * b + self._W[:, 1, 1, None]))
                self._gain[0][:, changed] = b / r
                self._gain[1][:, changed] = c / r
            else:  # Tomera (2014) eq. 30: the filter form at the design period T
                Qk = self.design.sampled(self._T)[1]
                q = np.stack([Qk[:, 0, 0], Qk[:, 0, 1], Qk[:, 1, 1]])[:, :, None]
                Kv, Kp = dare_filter_gain(self._T, q, self._R[:, changed])
                self._gain[0][:, changed] = Kv
                self._gain[1][:, changed] = Kp
        for entry in self._blocks.values():
            entry[1] |= changed

    @property
    def R(self) -> Array:
        """The per-env measurement variances (n, 3) (m^2, m^2, rad^2), a copy."""
        return self._R.T.copy()

    @property
    def steady_state_gain(self) -> Array:
        """The per-env steady-state gains (n, 3, 2), seed order ``[velocity, position]``
        (constant-gain kinds only; zeros otherwise)."""
        return self._gain.transpose(2, 1, 0).copy()

    # ---- cached interval matrices --------------------------------------------------------------
    def _process_noise(self, key: float, dt: float) -> Array:
        """``[Q_vv, Q_vp, Q_pp]`` (3, 3, n) of ``Q_k(dt)`` (the same for every env)."""
        Q = self._Q.get(key)
        if Q is None:
            Qd = self.template._process_noise(dt)
            if len(self._Q) >= _CACHE_SIZE:
                self._Q.clear()
            Q = np.empty((3, 3, self.n))
            Q[0], Q[1], Q[2] = Qd[:, 0, 0, None], Qd[:, 0, 1, None], Qd[:, 1, 1, None]
            self._Q[key] = Q
        return Q

    def _interval_blocks(self, key: float, dt: float) -> list[Array]:
        """The ``R``-dependent blocks for ``dt`` of every env, refreshed where stale."""
        entry = self._blocks.get(key)
        if entry is None:
            if len(self._blocks) >= _CACHE_SIZE:
                self._blocks.clear()
            make = self._steady_blocks if self.constant_gain else self._hamiltonian_blocks
            entry = [make(dt, np.arange(self.n)), np.zeros(self.n, dtype=bool)]
            self._blocks[key] = entry
        elif entry[1].any():
            idx = np.nonzero(entry[1])[0]
            make = self._steady_blocks if self.constant_gain else self._hamiltonian_blocks
            for old, new in zip(entry[0], make(dt, idx), strict=True):
                old[..., idx] = new
            entry[1][:] = False
        return entry[0]

    def _unique_R(self, idx: NDArray[np.intp]) -> tuple[Array, NDArray[np.intp]]:
        """The distinct ``R_c`` columns among the envs ``idx`` (3, u) and each env's column."""
        u, inv = np.unique(self._Rc[:, idx].T, axis=0, return_inverse=True)
        return u.T, inv.reshape(-1)

    def _hamiltonian_blocks(self, dt: float, idx: NDArray[np.intp]) -> list[Array]:
        """``[K, M0, M1]``, each (6, 2, 3, len(idx)), from the rows ``r`` of ``exp(H dt)`` and
        the position rows of ``int_0^dt exp(H s) ds`` and ``int_0^dt s exp(H s) ds`` per DOF
        and env (as :meth:`KalmanBucyFilter._hamiltonian_blocks`, one batched exponential),
        arranged so that ``K + M0 P0[0, j] + M1 P0[1, j]`` is column ``j`` of ``X``, ``Y``
        (rows 0-3) and of the two integrals (rows 4, 5)."""
        Rc, inv = self._unique_R(idx)
        u = Rc.shape[1]
        Ham = np.zeros((3, u, 4, 4))
        Ham[..., :2, :2] = -_A.T
        Ham[..., :2, 2:] = (_C.T @ _C)[None, None] / Rc[:, :, None, None]
        Ham[..., 2:, :2] = self._W[:, None]
        Ham[..., 2:, 2:] = _A
        M = np.zeros((3, u, 12, 12))
        M[..., :4, :4] = Ham
        M[..., :4, 4:8] = np.eye(4)
        M[..., 4:8, 8:12] = np.eye(4)
        Ed = _expm(M * dt)
        Eb = np.empty((6, 4, 3, u))
        Eb[0:4] = Ed[..., :4, :4].transpose(2, 3, 0, 1)
        Eb[4] = Ed[..., 3, 4:8].transpose(2, 0, 1)
        Eb[5] = (dt * Ed[..., 3, 4:8] - Ed[..., 3, 8:12]).transpose(2, 0, 1)
        Eb = Eb[..., inv]
        return [
            np.ascontiguousarray(Eb[:, 0:2]),
            np.repeat(Eb[:, 2:3], 2, axis=1),
            np.repeat(Eb[:, 3:4], 2, axis=1),
        ]

    def _steady_blocks(self, dt: float, idx: NDArray[np.intp]) -> list[Array]:
        """``[PhiA, PhiB, B1, B2, Qcl]``: ``exp(A_cl dt)`` by columns (``PhiA[i, j] = Phi[i,
        0]``, ``PhiB[i, j] = Phi[i, 1]``, (2, 2, 3, k)), the first-order-hold input vectors (2,
        3, k) and the Lyapunov increment ``[Q_vv, Q_vp, Q_pp]`` (3, 3, k), as
        :meth:`KalmanBucyFilter._steady_blocks` per env; for the discrete kind nothing."""
        if not self.continuous:
            return []
        k = len(idx)
        L = self._gain[:, :, idx].transpose(1, 2, 0)  # (3, k, 2)
        Rc = self._Rc[:, idx]
        Acl = np.zeros((3, k, 2, 2))
        Acl[..., 0, 1] = -L[..., 0]
        Acl[..., 1, 0] = 1.0
        Acl[..., 1, 1] = -L[..., 1]
        M = np.zeros((3, k, 4, 4))
        M[..., :2, :2] = Acl
        M[..., :2, 2] = L
        M[..., 2, 3] = 1.0
        Ed = _expm(M * dt)
        Wcl = self._W[:, None] + Rc[:, :, None, None] * (L[..., :, None] * L[..., None, :])
        M2 = np.zeros((3, k, 4, 4))
        M2[..., :2, :2] = -Acl
        M2[..., :2, 2:] = Wcl
        M2[..., 2:, 2:] = Acl.swapaxes(-1, -2)
        E2 = _expm(M2 * dt)
        F = E2[..., 2:, 2:].swapaxes(-1, -2)
        Qk = F @ E2[..., :2, 2:]
        Qcl = 0.5 * (Qk + Qk.swapaxes(-1, -2))
        Phi = Ed[..., :2, :2].transpose(2, 3, 0, 1)  # (2, 2, 3, k)
        return [
            np.repeat(Phi[:, 0:1], 2, axis=1),
            np.repeat(Phi[:, 1:2], 2, axis=1),
            np.ascontiguousarray(Ed[..., :2, 2].transpose(2, 0, 1)),
            np.ascontiguousarray(Ed[..., :2, 3].transpose(2, 0, 1)),
            np.stack([Qcl[..., 0, 0], Qcl[..., 0, 1], Qcl[..., 1, 1]]),
        ]

    # ---- interface ----------------------------------------------------------------------------
    def reset(
        self,
        t0: ArrayLike,
        eta0: ArrayLike,
        *,
        mask: ArrayLike | None = None,
        R: ArrayLike | None = None,
        nu0: ArrayLike | None = None,
    ) -> None:
        """Start the envs (all, or those where ``mask`` is True) at ``t0`` from ``eta0``.

        Args:
            t0: initial time (s), one number or (n,).
            eta0: poses ``[x, y, psi]`` (m, m, rad), (3,) or (n, 3); the heading's branch
                is kept.
            mask: (n,) booleans, ``None`` = all.
            R: new measurement variances (3,) or (n, 3) (m^2, m^2, rad^2) for the reset envs;
                ``None`` keeps theirs.
            nu0: body velocities ``[u, v, r]`` (m/s, m/s, rad/s), (3,) or (n, 3); ``None`` =
                rest.

        Raises:
            ValueError: mis-shaped or non-finite arguments.
        """
        m = self._mask(mask)
        tt = np.broadcast_to(np.asarray(t0, dtype=float), (self.n,))
        eta = self._rows(eta0, "eta0", "m, m, rad")
        if not (np.all(np.isfinite(tt[m])) and np.all(np.isfinite(eta[m]))):
            raise ValueError("t0 and eta0 must be finite")
        if R is not None:
            self._set_R(R, m)
        if nu0 is None:
            eta_dot = np.zeros((3, self.n))
        else:
            nu = self._rows(nu0, "nu0", "m/s, m/s, rad/s")
            if not np.all(np.isfinite(nu[m])):
                raise ValueError("nu0 must be finite")
            c, s = np.cos(eta[:, 2]), np.sin(eta[:, 2])
            eta_dot = np.stack([c * nu[:, 0] - s * nu[:, 1], s * nu[:, 0] + c * nu[:, 1], nu[:, 2]])
        X = self._X
        X[0][:, m] = eta_dot[:, m]
        X[1][:, m] = eta.T[:, m]
        X[2][:, m] = self._vel_var[:, None]
        X[3][:, m] = 0.0
        X[4][:, m] = self._R[:, m]
        self._t[m] = tt[m]
        self._count[m] = 0
        self._open[m] = False
        self._has_prev[m] = False
        self._started[m] = True
        self._all_started = bool(self._started.all())

    def step(
        self,
        t: ArrayLike,
        z: ArrayLike | None = None,
        valid: ArrayLike | None = None,
        tau: ArrayLike | None = None,
    ) -> BatchedStepInfo:
        """Propagate every env to its ``t`` and update it with its pose ``z`` where ``valid``.

        Args:
            t: time now (s), one number or (n,), not earlier than each env's previous call.
            z: measured poses ``[x, y, psi]`` (n, 3) (m, m, rad; heading in any branch), rows
                of invalid envs ignored (NaN allowed); ``None``: no measurement (coast).
            valid: (n,) booleans, ``None`` = all (with ``z``).
            tau: body thrust (n, 3) (N, N, N m), unused (kinematic model) or ``None``.

        Returns:
            :class:`BatchedStepInfo`.

        Raises:
            RuntimeError: an env was never reset.
            ValueError: time going backwards, mis-shaped input, a non-finite valid ``z``.
        """
        if not self._all_started:
            if not self._started.all():
                raise RuntimeError(f"{self.name}: call reset(t0, eta0) for every env before step()")
            self._all_started = True
        n = self.n
        tt = np.asarray(t, dtype=float)
        if tt.shape != (n,):
            tt = np.broadcast_to(tt, (n,))
        dt = tt - self._t
        if tau is not None and np.shape(tau) != (n, 3):
            raise ValueError(f"tau must be ({n}, 3) [X, Y, N] (N, N, N m), got {np.shape(tau)}")
        if z is None:
            zT = None
            vm = None
            n_valid = 0
        else:
            za = np.asarray(z, dtype=float)
            if za.shape != (n, 3):
                raise ValueError(
                    f"z must be ({n}, 3) poses [x, y, psi] (m, m, rad), got {za.shape}"
                )
            zT = za.T
            if valid is None:
                vm = None
                n_valid = n
            else:
                vm = np.asarray(valid, dtype=bool)
                if vm.shape != (n,):
                    raise ValueError(f"valid must be ({n},) booleans, got shape {vm.shape}")
                n_valid = int(np.count_nonzero(vm))
                if n_valid == n:
                    vm = None
        d0 = float(dt[0])
        if d0 >= 0.0 and math.isfinite(d0) and (dt == d0).all():  # one interval for all
            out = self._group(None, _dt_key(d0), d0, d0, zT, vm, n_valid)
            np.copyto(self._t, tt)
            return out
        if dt.min() < 0.0 or not math.isfinite(dt.sum()):
            tt, dt = self._clock(tt, dt)
        return self._grouped(tt, dt, zT, vm, n_valid)

    def _clock(self, tt: Array, dt: Array) -> tuple[Array, Array]:
        if not np.all(np.isfinite(tt)):
            raise ValueError(f"{self.name}: t must be finite")
        back = dt < 0.0
        if (dt < -_TIME_TOL).any():
            i = int(np.argmin(dt))
            raise ValueError(
                f"{self.name}: time must not go backwards (env {i}: previous {self._t[i]}, "
                f"got {tt[i]!r})"
            )
        return np.where(back, self._t, tt), np.where(back, 0.0, dt)

    def _grouped(
        self,
        tt: Array,
        dt: Array,
        zT: Array | None,
        vm: NDArray[np.bool_] | None,
        n_valid: int,
    ) -> BatchedStepInfo:
        """Step the envs in groups of equal (rounded) interval."""
        n = self.n
        keys = np.round(dt, 12)
        innov = np.full((n, 3), np.nan)
        nis = np.full(n, np.nan)
        rej = np.zeros(n, dtype=bool)
        forced = np.zeros(n, dtype=bool)
        for key in np.unique(keys).tolist():
            ix = np.nonzero(keys == key)[0]
            if n_valid == 0 or zT is None:
                zs, sub_v, nv = None, None, 0
            else:
                zs = zT[:, ix]
                sub_v = None if vm is None else vm[ix]
                nv = len(ix) if sub_v is None else int(np.count_nonzero(sub_v))
                if nv == len(ix):
                    sub_v = None
            d = dt[ix]
            d0 = float(d[0])
            o = self._group(ix, float(key), d0, d0 if (d == d0).all() else d, zs, sub_v, nv)
            innov[ix], nis[ix], rej[ix], forced[ix] = o
        self._t = np.array(tt, dtype=float)
        return BatchedStepInfo(innov, nis, rej, forced)

    # ---- the kernel ---------------------------------------------------------------------------
    def _group(
        self,
        ix: NDArray[np.intp] | None,
        key: float,
        d0: float,
        dt: float | Array,
        zT: Array | None,
        vm: NDArray[np.bool_] | None,
        n_valid: int,
    ) -> BatchedStepInfo:
        """Step the envs ``ix`` (``None``: all) that share the interval key ``key``.

        ``dt`` is the interval (a number, or one per env of the group), ``d0`` one of them;
        ``vm`` the valid mask (``None``: all valid), ``n_valid`` how many are valid.
        """
        full = ix is None
        X = self._X if full else self._X[:, :, ix]
        k = X.shape[2]
        moving = key > 0.0
        Q = None
        if moving:  # open-loop prediction (the scalar filters' _prior): the position first
            Q = self._process_noise(key, d0)
            if not full:
                Q = Q[:, :, :k]
            pb = X[1] + dt * X[0]
            cb = X[4] + (2.0 * dt) * X[3]
            cb += (dt * dt) * X[2]
            cb += Q[2]
        else:
            pb, cb = X[1], X[4]
        if n_valid == 0:  # coast
            if moving:
                self._store(ix, self._prior(X, dt, Q, pb, cb))
            if self.continuous:
                self._set(ix, self._has_prev, False)
            if full:
                return BatchedStepInfo(self._nan3, self._nan, self._false, self._false)
            return BatchedStepInfo(
                np.full((k, 3), np.nan), np.full(k, np.nan), np.zeros(k, bool), np.zeros(k, bool)
            )
        assert zT is not None
        R = self._R if full else self._R[:, ix]
        innov = zT - pb
        if not (np.abs(innov[2]) <= _PI).all():  # wrap the heading innovation to (-pi, pi]
            innov[2] = _PI - np.fmod(np.fmod(_PI - innov[2], _TWO_PI) + _TWO_PI, _TWO_PI)
        sq = innov * innov
        S = cb + R
        w = sq / S
        nis = w[0] + w[1]
        nis += w[2]
        if vm is None:
            if not math.isfinite(nis.sum()):
                raise ValueError(f"{self.name}: z must be finite where valid")
        elif not math.isfinite(np.where(vm, nis, 0.0).sum()):
            raise ValueError(f"{self.name}: z must be finite where valid")
        # the outlier gate (OutlierGate.check per env)
        count = self._count if full else self._count[ix]
        opened = self._open if full else self._open[ix]
        force = reject = None
        if vm is None and nis.max() <= self.threshold:  # every sample passes
            acc = None
            count_new = np.zeros(k, np.int64)
            open_new = np.zeros(k, bool)
        else:
            passed = nis <= self.threshold
            if vm is not None:
                passed &= vm
                over = vm & ~passed
            else:
                over = ~passed
            if over.any():
                force = over & (opened | (count >= self.max_rejections))
                reject = over & ~force
                acc = passed | force
                count_new = np.where(reject, count + 1, np.where(acc, 0, count))
                open_new = (opened | force) & ~passed
                if not force.any():
                    force = None
            else:
                acc = passed
                count_new = np.where(acc, 0, count)
                open_new = opened & ~acc
        if full:
            self._count, self._open = count_new, open_new
        else:
            self._count[ix], self._open[ix] = count_new, open_new
        if self.continuous:
            self._kbf_update(ix, key, d0, X, Q, pb, cb, innov, sq, dt, acc, force)
        else:
            Xb = self._prior(X, dt, Q, pb, cb) if moving else X
            self._dkf_update(ix, Xb, innov, sq, S, R, vm, acc, force)
        if vm is not None:
            innov = np.where(vm, innov, np.nan)
            nis = np.where(vm, nis, np.nan)
        no = self._false if full else np.zeros(k, bool)
        if reject is None:
            reject = no
        return BatchedStepInfo(innov.T, nis, reject, no if force is None else force)

    @staticmethod
    def _prior(X: Array, dt: float | Array, Q: Array | None, pb: Array, cb: Array) -> Array:
        """The prediction ``(F s, F P F^T + Q_k)`` (5, 3, k), given its position ``pb`` and
        position variance ``cb``."""
        if Q is None:
            return X
        Xb = np.empty_like(X)
        Xb[0] = X[0]
        Xb[1] = pb
        np.add(X[2], Q[0], out=Xb[2])
        np.add(X[3] + dt * X[2], Q[1], out=Xb[3])
        Xb[4] = cb
        return Xb

    def _dkf_update(
        self,
        ix: NDArray[np.intp] | None,
        Xb: Array,
        innov: Array,
        sq: Array,
        S: Array,
        R: Array,
        vm: NDArray[np.bool_] | None,
        acc: NDArray[np.bool_] | None,
        force: NDArray[np.bool_] | None,
    ) -> None:
        """``DiscreteKalmanFilter._correct`` for the envs whose sample is used (``acc``,
        ``None``: all); the gain is zero for the others, which leaves their prediction exactly
        as it is."""
        vb, pb, ab, bb, cb = Xb
        if force is not None:  # a forced acceptance inflates the position variance of the prior
            cb = np.where(force, cb + sq, cb)
            S = cb + R
        if self.constant_gain:
            G = self._gain if ix is None else self._gain[:, :, ix]
            Kv, Kp = G[0], G[1]
        else:
            Kv = bb / S  # Tomera (2011) eq. 23
            Kp = cb / S
        if acc is not None:
            accf = acc.astype(float)
            Kv = Kv * accf
            Kp = Kp * accf
            if vm is not None:
                innov = np.where(vm, innov, 0.0)
        Xn = np.empty_like(Xb)
        np.add(vb, Kv * innov, out=Xn[0])  # Tomera (2011) eq. 14
        np.add(pb, Kp * innov, out=Xn[1])
        m = 1.0 - Kp
        if self.constant_gain:
            # Joseph form (I - K H) P (I - K H)^T + R K K^T, H = [0, 1]
            M01 = bb - Kv * cb
            M11 = m * cb
            KvR = R * Kv
            np.add((ab - Kv * bb) - M01 * Kv, KvR * Kv, out=Xn[2])
            P01 = M01 * m + KvR * Kp
            P10 = m * bb - M11 * Kv + KvR * Kp
            np.multiply(0.5, P01 + P10, out=Xn[3])
            np.add(M11 * m, (R * Kp) * Kp, out=Xn[4])
        else:
            # the optimal gain: the Joseph form is (I - K H) P (to round-off)
            np.subtract(ab, Kv * bb, out=Xn[2])
            np.multiply(m, bb, out=Xn[3])
            np.multiply(m, cb, out=Xn[4])
        self._store(ix, Xn)

    def _kbf_update(
        self,
        ix: NDArray[np.intp] | None,
        key: float,
        d0: float,
        X: Array,
        Q: Array | None,
        pb: Array,
        cb: Array,
        innov: Array,
        sq: Array,
        dt: float | Array,
        acc: NDArray[np.bool_] | None,
        force: NDArray[np.bool_] | None,
    ) -> None:
        """``KalmanBucyFilter._correct`` and the hold rules for the envs whose sample is used
        (``acc``, ``None``: all): an accepted sample starts the next first-order hold; a
        rejected or missing one clears it (the prediction is kept)."""
        full = ix is None
        y1 = pb + innov  # the sample, unwrapped next to the prediction
        has = acc if acc is not None else self._true if full else np.ones(X.shape[2], bool)
        if key <= 0.0:  # dt = 0: the sample only becomes the next hold's start
            self._hold(ix, y1, has)
            return
        has_prev = self._has_prev if full else self._has_prev[ix]
        yprev = self._yprev if full else self._yprev[:, ix]
        if force is not None:
            y0 = np.where(force | ~has_prev, y1, yprev)
        elif has_prev.all():
            y0 = yprev
        else:
            y0 = np.where(has_prev, yprev, y1)
        slope = (y1 - y0) / dt
        Pst = X[2:5]
        if force is not None:
            Pst = Pst.copy()
            Pst[2] = np.where(force, Pst[2] + sq, Pst[2])
        row0, row1 = Pst[0:2], Pst[1:3]  # the rows of P0: (a, b) and (b, c)
        Xc = np.empty_like(X)
        blocks = self._interval_blocks(key, d0)
        if not full:
            blocks = [bk[..., ix] for bk in blocks]
        if self.constant_gain:  # steady state: exp(A_cl dt), hold inputs, Lyapunov increment
            PhiA, PhiB, B1, B2, Qcl = blocks
            s0 = X[0:2]
            t = PhiA[:, 0] * s0[0]
            t += PhiB[:, 0] * s0[1]
            t += B1 * y0
            t += B2 * slope
            Xc[0:2] = t
            Mp = PhiA * row0  # Phi P0 (2, 2, 3, k)
            Mp += PhiB * row1
            # (Phi P0 Phi^T + Qcl), the three entries of a symmetric matrix
            P00 = Mp[0, 0] * PhiA[0, 0] + Mp[0, 1] * PhiB[0, 0] + Qcl[0]
            P01 = Mp[0, 0] * PhiA[1, 0] + Mp[0, 1] * PhiB[1, 0] + Qcl[1]
            P10 = Mp[1, 0] * PhiA[0, 0] + Mp[1, 1] * PhiB[0, 0] + Qcl[1]
            P11 = Mp[1, 0] * PhiA[1, 0] + Mp[1, 1] * PhiB[1, 0] + Qcl[2]
            Xc[2] = P00
            np.multiply(0.5, P01 + P10, out=Xc[3])
            Xc[4] = P11
        else:  # time-varying Riccati through the Hamiltonian blocks
            K6, M0, M1 = blocks
            Rc = self._Rc if full else self._Rc[:, ix]
            out = M0 * row0  # (6, 2, 3, k): E_r2 P0[0, j] + E_r3 P0[1, j] + E_rj
            out += M1 * row1
            out += K6
            Xm, Ym, J0, J1 = out[0:2], out[2:4], out[4], out[5]
            X00, X01, X10, X11 = Xm[0, 0], Xm[0, 1], Xm[1, 0], Xm[1, 1]
            det = X00 * X11 - X01 * X10
            rhs = J0 * y0
            rhs += J1 * slope
            rhs /= Rc
            rhs += X[0:2]
            # with adj(X) = det X^-1: s = X^-T rhs, P = Y X^-1 (P_vp from one product: P is
            # symmetric to round-off, the scalar filter averages the two)
            np.subtract(rhs[0] * X11, rhs[1] * X10, out=Xc[0])
            np.subtract(rhs[1] * X00, rhs[0] * X01, out=Xc[1])
            np.subtract(Ym[0, 0] * X11, Ym[0, 1] * X10, out=Xc[2])
            np.subtract(Ym[1, 0] * X11, Ym[1, 1] * X10, out=Xc[3])
            np.subtract(Ym[1, 1] * X00, Ym[1, 0] * X01, out=Xc[4])
            Xc /= det
        if acc is not None:
            Xc = np.where(acc, Xc, self._prior(X, dt, Q, pb, cb))
        self._store(ix, Xc)
        self._hold(ix, y1, has)

    def _hold(self, ix: NDArray[np.intp] | None, y1: Array, has: NDArray[np.bool_]) -> None:
        if ix is None:
            self._yprev, self._has_prev = y1, has.copy()
        else:
            self._yprev[:, ix], self._has_prev[ix] = y1, has

    def _store(self, ix: NDArray[np.intp] | None, Xn: Array) -> None:
        if ix is None:
            self._X = Xn
        else:
            self._X[:, :, ix] = Xn

    def _set(self, ix: NDArray[np.intp] | None, arr: NDArray[Any], value: Any) -> None:
        if ix is None:
            arr[:] = value
        else:
            arr[ix] = value

    # ---- estimates ----------------------------------------------------------------------------
    @property
    def t(self) -> Array:
        """Each env's time (s), (n,)."""
        return self._t.copy()

    @property
    def eta(self) -> Array:
        """Estimated poses ``[x, y, psi]`` (n, 3) (m, m, rad; heading continuous)."""
        return self._X[1].T.copy()

    @property
    def eta_dot(self) -> Array:
        """Estimated NED rates ``[x_dot, y_dot, psi_dot]`` (n, 3) (m/s, m/s, rad/s)."""
        return self._X[0].T.copy()

    @property
    def nu(self) -> Array:
        """Body velocities ``[u, v, r]`` (n, 3), ``R^T(psi) eta_dot`` (Tomera 2011 eq. 60)."""
        ed, psi = self._X[0], self._X[1, 2]
        c, s = np.cos(psi), np.sin(psi)
        out = np.empty((self.n, 3))
        out[:, 0] = c * ed[0] + s * ed[1]
        out[:, 1] = -s * ed[0] + c * ed[1]
        out[:, 2] = ed[2]
        return out

    @property
    def P_eta(self) -> Array:
        """Covariances of ``eta`` (n, 3, 3) (m^2, rad^2), diagonal."""
        out = np.zeros((self.n, 3, 3))
        i = np.arange(3)
        out[:, i, i] = self._X[4].T
        return out

    @property
    def P_nu(self) -> Array:
        """Covariances of ``nu`` (n, 3, 3): ``J P J^T`` with ``J`` the Jacobian of
        ``R^T(psi) eta_dot`` (``d nu / d psi = [v, -u, 0]``), as the scalar filters."""
        ed, psi = self._X[0], self._X[1, 2]
        c, s = np.cos(psi), np.sin(psi)
        u = c * ed[0] + s * ed[1]
        v = -s * ed[0] + c * ed[1]
        vx, vy, vpsi = self._X[2]
        ppsi = self._X[4, 2]
        cpsi = self._X[3, 2]  # cov(psi, psi_dot)
        out = np.empty((self.n, 3, 3))
        out[:, 0, 0] = v * v * ppsi + c * c * vx + s * s * vy
        out[:, 0, 1] = out[:, 1, 0] = -v * u * ppsi - c * s * vx + s * c * vy
        out[:, 1, 1] = u * u * ppsi + s * s * vx + c * c * vy
        out[:, 0, 2] = out[:, 2, 0] = v * cpsi
        out[:, 1, 2] = out[:, 2, 1] = -u * cpsi
        out[:, 2, 2] = vpsi
        return out

    @property
    def P(self) -> Array:
        """Covariances (n, 6, 6) of ``[x, y, psi, x_dot, y_dot, psi_dot]`` (the scalar
        filters' :attr:`~shipgym.observers.kalman.KalmanBucyFilter.P` per env)."""
        out = np.zeros((self.n, 6, 6))
        i = np.arange(3)
        out[:, i, i] = self._X[4].T
        out[:, i + 3, i + 3] = self._X[2].T
        out[:, i, i + 3] = out[:, i + 3, i] = self._X[3].T
        return out

    @property
    def x(self) -> Array:
        """States (n, 6) ``[x, y, psi, x_dot, y_dot, psi_dot]``."""
        return np.concatenate([self._X[1].T, self._X[0].T], axis=1)
