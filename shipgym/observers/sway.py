r"""Sway-velocity estimation for rudder roll stabilisation: the KF of Radhakrishnan (n.d.) and an
EKF.

KF of Radhakrishnan (n.d.) eqs. 1-4 on the zero-order-hold model (``A_d = exp(A dt)``),
``y = [r, psi, p, phi]``.

Public names: ``DT``, ``P0_SWAY``, ``Q_V``, ``R_SWAY``, ``SwayKFResult``, ``SwayVelocityEKF``,
``SwayVelocityKF``, ``process_noise``, ...
Sources: Radhakrishnan (n.d.); Van der Klugt (1987); Van Loan (1978).

Design notes: docs/design/observers.sway.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import entry, njit
from shipgym.dynamics.frames import wrap
from shipgym.dynamics.vanderklugt import RollModel, roll_model

from .design import discretise

__all__ = [
    "DT",
    "P0_SWAY",
    "Q_V",
    "R_SWAY",
    "SwayKFResult",
    "SwayVelocityEKF",
    "SwayVelocityKF",
    "process_noise",
    "simulate_sway_kf",
    "sway_kf_step",
    "zoh",
]

Array = NDArray[np.float64]

_D = math.pi / 180.0
#: the KF sample time (s) [chosen; the paper prints none]
DT = 0.1
#: extra process-noise variance on the sway velocity per step ((m/s)^2) [chosen]
Q_V = 1.0e-8
#: measurement variances of ``[r, psi, p, phi]``: (0.05 deg/s)^2, (0.1 deg)^2, (0.05 deg/s)^2,
#: (0.1 deg)^2 in rad^2/s^2 and rad^2 [chosen: rate gyros and gyros]
R_SWAY = ((0.05 * _D) ** 2, (0.1 * _D) ** 2, (0.05 * _D) ** 2, (0.1 * _D) ** 2)
#: initial covariance of ``[v, r, psi, p, phi]``: (0.01 m/s)^2, (0.1 deg/s)^2, (1 deg)^2,
#: (0.1 deg/s)^2, (1 deg)^2 [chosen]
P0_SWAY = (0.01**2, (0.1 * _D) ** 2, (1.0 * _D) ** 2, (0.1 * _D) ** 2, (1.0 * _D) ** 2)

_C = np.zeros((4, 5))  # y = C x (the design's form; the compiled update picks the rows)
_C[0, 1] = _C[1, 2] = _C[2, 3] = _C[3, 4] = 1.0
_PSI_OUT = 1  # the heading's row in y


def zoh(A: ArrayLike, B: ArrayLike, dt: float) -> tuple[Array, Array]:
    """Zero-order-hold discretisation ``(A_d, B_d)`` of ``x_dot = A x + B u`` (exact).

    One matrix exponential of ``[[A, B], [0, 0]] dt``.

    Args:
        A: (n, n) state matrix (1/s).
        B: (n,) input vector.
        dt: sample time (s), > 0.

    Returns:
        ``(A_d (n, n), B_d (n,))``.
    """
    A_ = np.asarray(A, dtype=float)
    B_ = np.asarray(B, dtype=float).reshape(-1)
    n = A_.shape[0]
    _check_dt(dt)
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n] = A_, B_
    E = scipy.linalg.expm(M * dt)
    return E[:n, :n], E[:n, n]


def _check_dt(dt: float) -> float:
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"the sample time dt must be finite and > 0 s, got {dt!r}")
    return float(dt)


def process_noise(G: ArrayLike, q: ArrayLike, dt: float, q_v: float = Q_V) -> Array:
    """The chosen discrete process noise ``Q_W = (G dt) diag(q) / dt (G dt)^T + q_v e_v e_v^T``.

    Args:
        G: (5, 2) noise input of the model (:class:`~shipgym.dynamics.vanderklugt.RollModel`).
        q: (2,) intensities ``(q_phi, q_psi)`` (rad^2 s, rad^2/s).
        dt: sample time (s).
        q_v: extra variance on the sway velocity ((m/s)^2).

    Returns:
        (5, 5) covariance per step.
    """
    G_ = np.asarray(G, dtype=float)
    q_ = np.asarray(q, dtype=float).reshape(-1)
    if q_.shape != (G_.shape[1],) or np.any(q_ < 0) or not np.all(np.isfinite(q_)):
        raise ValueError(f"q must be {G_.shape[1]} finite intensities >= 0, got {q!r}")
    if not (math.isfinite(q_v) and q_v >= 0):
        raise ValueError(f"q_v must be >= 0 (m/s)^2, got {q_v!r}")
    dt = _check_dt(dt)
    Gd = G_ * dt
    Q = Gd @ np.diag(q_) @ Gd.T / dt
    Q[0, 0] += q_v
    return 0.5 * (Q + Q.T)


def _cov(value: ArrayLike | None, default: tuple[float, ...], n: int, name: str) -> Array:
    M = np.asarray(default if value is None else value, dtype=float)
    if M.ndim == 1:
        M = np.diag(M)
    if M.shape != (n, n) or not np.all(np.isfinite(M)):
        raise ValueError(f"{name} must be {n} variances or an {n}x{n} covariance, got {value!r}")
    tol = 1e-12 * max(1.0, float(np.max(np.abs(M), initial=0.0)))
    if not np.allclose(M, M.T) or np.min(np.linalg.eigvalsh(0.5 * (M + M.T))) < -tol:
        raise ValueError(f"{name} must be symmetric positive semidefinite")
    return 0.5 * (M + M.T)


@njit(inline="always")
def _mul(a, b, out):  # type: ignore[no-untyped-def]
    """``out = a b`` (small matrices, in index order)."""
    for j in range(out.shape[0]):
        for k in range(out.shape[1]):
            acc = 0.0
            for m in range(b.shape[0]):
                acc += a[j, m] * b[m, k]
            out[j, k] = acc


@njit(inline="always")
def _update_row(i, xp, Pp, R, y, x, P, gain, S, Si, GP):  # type: ignore[no-untyped-def]
    """Eq. 4 for row ``i``: the gain ``G = P^- C^T (C P^- C^T + R)^-1`` (``C`` picks
    ``[r, psi, p, phi]``), the wrapped heading innovation, ``x = x^- + G (y - C x^-)``,
    ``P = (I - G C) P^-`` symmetrised (``S``, ``Si``, ``GP``: scratch)."""
    for a in range(4):
        for b in range(4):
            S[a, b] = Pp[a + 1, b + 1] + R[i, a, b]
            Si[a, b] = 1.0 if a == b else 0.0
    for c in range(4):  # S^-1 by Gauss-Jordan (S is positive definite: no pivoting)
        piv = S[c, c]
        for k in range(4):
            S[c, k] /= piv
            Si[c, k] /= piv
        for r in range(4):
            f = S[r, c] if r != c else 0.0
            for k in range(4):
                S[r, k] -= f * S[c, k]
                Si[r, k] -= f * Si[c, k]
    _mul(Pp[:, 1:], Si, gain[i])
    _mul(gain[i], Pp[1:], GP)
    for j in range(5):
        acc = xp[j]
        for b in range(4):
            inn = y[i, b] - xp[b + 1]
            acc += gain[i, j, b] * (wrap(inn) if b == _PSI_OUT else inn)
        x[i, j] = acc
    for j in range(5):
        for k in range(j + 1):
            m_ = 0.5 * ((Pp[j, k] - GP[j, k]) + (Pp[k, j] - GP[k, j]))
            P[i, j, k] = m_
            P[i, k, j] = m_


@njit
def sway_kf_step(A, B, Q, R, y, delta, mask, x, P, gain):  # type: ignore[no-untyped-def]
    """One predict-update cycle of the KF of each row ``i`` where ``mask[i]`` (eqs. 3-4):
    ``x^- = A_d x + B_d delta``, ``P^- = A_d P A_d^T + Q_W``, then :func:`_update_row` with
    ``y[i]``. Shapes: A, Q (N, 5, 5); B (N, 5); R (N, 4, 4); y (N, 4); delta (N,); mask (N,)
    bool; x (N, 5), P (N, 5, 5), gain (N, 5, 4) updated in place. Rows are independent."""
    xp, T, Pp, GP = np.empty(5), np.empty((5, 5)), np.empty((5, 5)), np.empty((5, 5))
    S, Si = np.empty((4, 4)), np.empty((4, 4))
    for i in range(x.shape[0]):
        if mask[i]:
            for j in range(5):
                xp[j] = B[i, j] * delta[i]
                for k in range(5):
                    xp[j] += A[i, j, k] * x[i, k]
            _mul(A[i], P[i], T)
            _mul(T, A[i].T, Pp)
            for j in range(5):
                for k in range(5):
                    Pp[j, k] += Q[i, j, k]
            _update_row(i, xp, Pp, R, y, x, P, gain, S, Si, GP)


@njit
def sway_update(xp, Pp, R, y, x, P, gain):  # type: ignore[no-untyped-def]
    """Eq. 4 alone for row 0 (the EKF's update, after its own prediction ``xp``, ``Pp``)."""
    _update_row(0, xp, Pp, R, y, x, P, gain, np.empty((4, 4)), np.empty((4, 4)), np.empty((5, 5)))


class _SwayFilterBase:
    """The state and the measurement update shared by the KF and the EKF (eqs. 3-4): a batch
    of one of :func:`sway_kf_step`'s rows."""

    def __init__(self, R: Array, x0: ArrayLike | None, P0: ArrayLike | None) -> None:
        self.R = R
        if np.min(np.linalg.eigvalsh(R)) <= 0:
            raise ValueError("the measurement covariance r must be positive definite")
        self._x0 = np.zeros(5) if x0 is None else np.asarray(x0, dtype=float).reshape(-1)
        if self._x0.shape != (5,) or not np.all(np.isfinite(self._x0)):
            raise ValueError(f"x0 must be [v, r, psi, p, phi] (5 finite values), got {x0!r}")
        self._P0 = _cov(P0, P0_SWAY, 5, "P0")
        self._R1 = np.ascontiguousarray(R[None])
        self.reset()

    def reset(self) -> None:
        """Back to ``x0``, ``P0``; the gain cleared."""
        self._x = self._x0[None].copy()
        self._P = self._P0[None].copy()
        self._gain = np.zeros((1, 5, 4))

    @property
    def x(self) -> Array:
        """The state estimate ``[v, r, psi, p, phi]`` (m/s, rad/s, rad, rad/s, rad)."""
        return self._x[0].copy()

    @property
    def P(self) -> Array:
        """The estimate's covariance (5, 5) (SI units squared)."""
        return self._P[0].copy()

    @property
    def trace_P(self) -> float:
        """``trace(P)`` (mixed SI units squared; the paper's Fig. 2d/2j)."""
        return float(np.trace(self._P[0]))

    @property
    def gain(self) -> Array:
        """The last Kalman gain ``G(k)`` (5, 4) (eq. 4)."""
        return self._gain[0].copy()

    @staticmethod
    def _measurement(y: ArrayLike) -> Array:
        y_ = np.asarray(y, dtype=float).reshape(-1)
        if y_.shape != (4,) or not np.all(np.isfinite(y_)):
            raise ValueError(f"y must be the measurement [r, psi, p, phi] (4 finite), got {y!r}")
        return y_[None]


def _delta(delta: float) -> float:
    d = float(delta)
    if not math.isfinite(d):
        raise ValueError(f"the rudder angle delta must be finite (rad), got {delta!r}")
    return d


class SwayVelocityKF(_SwayFilterBase):
    """The discrete KF of Radhakrishnan (n.d.) eqs. 1-4 on a :class:`RollModel`.

    Args:
        model: the plant model (:func:`~shipgym.dynamics.vanderklugt.roll_model`).
        dt: sample time (s) (:data:`DT`).
        q: ``(q_phi, q_psi)`` wave intensities (rad^2 s, rad^2/s), or a (5, 5) ``Q_W`` per
            step; default the model's, through :func:`process_noise`.
        r: (4,) variances or (4, 4) ``R_v`` of ``[r, psi, p, phi]``; default :data:`R_SWAY`.
        x0: initial estimate (5,); default 0.
        P0: (5,) variances or (5, 5) initial covariance; default :data:`P0_SWAY`.
    """

    def __init__(
        self,
        model: RollModel,
        dt: float = DT,
        q: ArrayLike | None = None,
        r: ArrayLike | None = None,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
    ) -> None:
        self.model = model
        self.dt = _check_dt(dt)
        self.A_d, self.B_d = zoh(model.A, model.B, self.dt)
        q_ = np.diag(model.Q_w) if q is None else np.asarray(q, dtype=float)
        self.Q = q_ if q_.shape == (5, 5) else process_noise(model.G, q_, self.dt)
        self.Q = _cov(self.Q, (), 5, "q")
        super().__init__(_cov(r, R_SWAY, 4, "r"), x0, P0)
        self._args = (self.A_d[None].copy(), self.B_d[None].copy(), self.Q[None].copy(),
                      self._R1)  # fmt: skip
        self._entry: Any = None  # sway_kf_step's compiled entry point

    def step(self, y: ArrayLike, delta: float) -> Array:
        """One predict-update cycle: eq. 3 over ``dt``, then eq. 4 with ``y``.

        Args:
            y: the measurement ``[r, psi, p, phi]`` at the end of the step (rad/s, rad).
            delta: the rudder angle (rad) held over the step that ends at ``y``.

        Returns:
            the new estimate ``[v, r, psi, p, phi]``.
        """
        y_ = self._measurement(y)
        d = np.array([_delta(delta)])
        args = (*self._args, y_, d, _ONE, self._x, self._P, self._gain)
        if self._entry is None:
            self._entry = entry(sway_kf_step, args)
        self._entry(*args)
        return self.x


_ONE = np.ones(1, dtype=np.bool_)


class SwayVelocityEKF(_SwayFilterBase):
    """An EKF with the KF's measurements for a nonlinear model ``x_dot = f(x, delta)``.

    Prediction: RK4 over ``dt`` in ``substeps`` equal steps with ``delta`` held; ``F`` the
    central finite-difference Jacobian of that map (step ``eps (1 + |x_i|)``); ``P^- = F P F^T
    + Q_W``. The update is eq. 4 (linear measurements ``y = [r, psi, p, phi]``).

    Args:
        f: ``f(x, delta) -> x_dot``, ``x = [v, r, psi, p, phi]`` (SI), ``delta`` in rad.
        dt: sample time (s).
        q: (5, 5) ``Q_W`` per step, or the (2,) wave intensities with ``G``.
        r: (4,) variances or (4, 4) ``R_v``; default :data:`R_SWAY`.
        x0: initial estimate (5,); default 0.
        P0: (5,) variances or (5, 5); default :data:`P0_SWAY`.
        G: (5, 2) noise input when ``q`` holds intensities (:func:`process_noise`).
        substeps: RK4 steps per ``dt`` (>= 1).
        eps: relative finite-difference step.
    """

    def __init__(
        self,
        f: Callable[[Array, float], ArrayLike],
        dt: float,
        q: ArrayLike,
        r: ArrayLike | None = None,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
        *,
        G: ArrayLike | None = None,
        substeps: int = 4,
        eps: float = 1.0e-6,
    ) -> None:
        if not callable(f):
            raise ValueError("f must be a callable f(x, delta) -> x_dot")
        self.f = f
        self.dt = _check_dt(dt)
        if int(substeps) != substeps or substeps < 1:
            raise ValueError(f"substeps must be an integer >= 1, got {substeps!r}")
        self.substeps = int(substeps)
        if not (math.isfinite(eps) and eps > 0):
            raise ValueError(f"eps must be > 0, got {eps!r}")
        self.eps = float(eps)
        q_ = np.asarray(q, dtype=float)
        if q_.shape != (5, 5):
            if G is None:
                raise ValueError("q must be a 5x5 Q_W per step, or the wave intensities with G")
            q_ = process_noise(G, q_, self.dt)
        self.Q = _cov(q_, (), 5, "q")
        super().__init__(_cov(r, R_SWAY, 4, "r"), x0, P0)

    def _xdot(self, x: Array, d: float) -> Array:
        out = np.asarray(self.f(x, d), dtype=float).reshape(-1)
        if out.shape != (5,):
            raise ValueError(f"f(x, delta) must return 5 derivatives, got shape {out.shape}")
        return out

    def propagate(self, x: ArrayLike, delta: float) -> Array:
        """The RK4 map: the state after ``dt`` from ``x`` with the rudder ``delta`` held."""
        x_ = np.asarray(x, dtype=float).reshape(-1).copy()
        h = self.dt / self.substeps
        for _ in range(self.substeps):
            k1 = self._xdot(x_, delta)
            k2 = self._xdot(x_ + 0.5 * h * k1, delta)
            k3 = self._xdot(x_ + 0.5 * h * k2, delta)
            k4 = self._xdot(x_ + h * k3, delta)
            x_ = x_ + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        return x_

    def jacobian(self, x: ArrayLike, delta: float) -> Array:
        """``d propagate / d x`` (5, 5) by central differences."""
        x_ = np.asarray(x, dtype=float).reshape(-1)
        F = np.empty((5, 5))
        for i in range(5):
            h = self.eps * (1.0 + abs(x_[i]))
            e = np.zeros(5)
            e[i] = h
            F[:, i] = (self.propagate(x_ + e, delta) - self.propagate(x_ - e, delta)) / (2 * h)
        return F

    def step(self, y: ArrayLike, delta: float) -> Array:
        """One predict-update cycle (as :meth:`SwayVelocityKF.step`)."""
        y_ = self._measurement(y)
        d = _delta(delta)
        x = self._x[0]
        F = self.jacobian(x, d)
        x_pred = self.propagate(x, d)
        P_pred = F @ self._P[0] @ F.T + self.Q
        sway_update(x_pred, np.ascontiguousarray(P_pred), self._R1, y_, self._x, self._P,
                    self._gain)  # fmt: skip
        return self.x


@dataclass(frozen=True)
class SwayKFResult:
    """What :func:`simulate_sway_kf` returns.

    Attributes:
        t: (n,) sample times (s), from 0.
        x: (n, 5) true states.
        x_hat: (n, 5) estimates (``x_hat[0]`` the prior ``x0``).
        trace_P: (n,) ``trace(P)``.
        delta: (n,) rudder angle held from each sample (rad).
        v_rms: RMS of the true sway velocity (m/s).
        v_error_rms: RMS of ``v_hat - v`` (m/s).
        trace_settle_time: the first time after which ``trace(P)`` stays within 5 % of its final
            value (s).
    """

    t: Array
    x: Array
    x_hat: Array
    trace_P: Array
    delta: Array
    v_rms: float
    v_error_rms: float
    trace_settle_time: float


def simulate_sway_kf(
    U: float,
    t_end: float,
    seed: int,
    dt: float = DT,
    amplitude: float = math.radians(10.0),
    omega: float = 0.43,
    kdp_law: str = "U2",
) -> SwayKFResult:
    """The seed's sway-velocity KF experiment on the exactly sampled reconstructed plant.

    Truth: ``x_{k+1} = A_d x_k + B_d delta_k + w_k``, ``w_k ~ N(0, Q_k)`` with ``Q_k`` the exact
    sampled covariance of the wave noise ``G w`` (Van Loan (1978)), ``x_0 = 0``;
    ``delta_k = amplitude sin(omega t_k)`` held over each step (Radhakrishnan (n.d.) section 4:
    10 deg at 0.43 rad/s); ``y_k = C x_k + v_k``, ``v_k ~ N(0, R_v)`` (:data:`R_SWAY`). The KF is
    :class:`SwayVelocityKF` with its defaults. One seeded ``numpy`` Generator draws everything.

    Args:
        U: forward speed (m/s).
        t_end: duration (s), > dt.
        seed: random seed.
        dt: sample time (s).
        amplitude: rudder amplitude (rad).
        omega: rudder frequency (rad/s).
        kdp_law: the ``K_dp`` law.

    Returns:
        :class:`SwayKFResult` (the RMS values over samples 1..n-1).
    """
    if not (math.isfinite(t_end) and t_end > dt):
        raise ValueError(f"t_end must be > dt = {dt} s, got {t_end!r}")
    model = roll_model(U, kdp_law=kdp_law)
    kf = SwayVelocityKF(model, dt)
    _, Qk = discretise(model.A, model.G @ model.Q_w @ model.G.T, dt, method="exact")
    w_vals, w_vecs = np.linalg.eigh(Qk)
    Lq = w_vecs * np.sqrt(np.clip(w_vals, 0.0, None))
    Lr = np.sqrt(np.diag(kf.R))
    rng = np.random.default_rng(seed)
    n = int(round(t_end / dt)) + 1
    t = np.arange(n) * dt
    delta = amplitude * np.sin(omega * t)
    x = np.zeros((n, 5))
    x_hat = np.zeros((n, 5))
    trace = np.zeros(n)
    x_hat[0], trace[0] = kf.x, kf.trace_P
    for k in range(1, n):
        x[k] = kf.A_d @ x[k - 1] + kf.B_d * delta[k - 1] + Lq @ rng.standard_normal(5)
        y = _C @ x[k] + Lr * rng.standard_normal(4)
        x_hat[k] = kf.step(y, delta[k - 1])
        trace[k] = kf.trace_P
    outside = np.flatnonzero(np.abs(trace - trace[-1]) > 0.05 * abs(trace[-1]))
    settle = float(t[outside[-1] + 1]) if outside.size else 0.0
    return SwayKFResult(
        t=t,
        x=x,
        x_hat=x_hat,
        trace_P=trace,
        delta=delta,
        v_rms=float(np.sqrt(np.mean(x[1:, 0] ** 2))),
        v_error_rms=float(np.sqrt(np.mean((x_hat[1:, 0] - x[1:, 0]) ** 2))),
        trace_settle_time=settle,
    )


def calm_water_intensities(hull: Any) -> tuple[float, float]:
    """A small process noise for a filter in calm water: white roll and yaw moments of
    intensity ``(K_phi 0.1 deg)^2`` ((N m)^2 s, the restoring moment of 0.1 deg of heel)
    [chosen], for a hull with a roll restoring ``K_phi`` (N m/rad)."""
    q = (float(hull.K_phi) * math.radians(0.1)) ** 2
    return q, q
