r"""Wave-filtering Kalman filters of Al-Takie (1982): 14-state, reduced, semi-constant, EKF.

Discrete KF ``x- = Phi x + Delta u``, ``K = P- H^T (H P- H^T + R)^-1``, Joseph update
(Al-Takie 1982 eqs. 5.4-5.12, App. 3).

The filters separate the slow (LF) ship motion from the first-order wave (HF) motion in the
position and heading measurements, on the combined model of
:func:`~shipgym.dynamics.altakie.wave_filter_model` (per unit, ``x = [v, y, r, psi, f_Y, f_N,
HF sway(4), HF yaw(4)]``, ``z = [x2 + x9, x4 + x13] + v``).

Public names: ``BIAS_Q``, ``NOISE_DESIGNS``, ``BatchedWaveFilter``, ``DiscreteKF``, ``ReducedKF``,
``WaveFilterEKF``, ``WaveFilterObserver``, ``gain_settling_steps``, ``hf_gain_for_std``.

Design notes: docs/design/observers.wavefilter.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import law_input, njit
from shipgym.dynamics.altakie import (
    WaveFilterModel,
    discretise,
    hf_alpha,
    hf_block,
    lf_model_from_vessel,
    saturated_lf_matrix,
    saturated_lf_rows,
    surge_model_from_vessel,
    wave_filter_model,
)
from shipgym.dynamics.perunit import PerUnit

from .base import Estimate, as_pose, register_observer
from .batch import (
    BatchedStepInfo,
    BatchOfOne,
    expm,
    joseph,
    mat_mul,
    mat_mul_t,
    register_batched_form,
    solve_small,
)

__all__ = [
    "BIAS_Q",
    "NOISE_DESIGNS",
    "BatchedWaveFilter",
    "DiscreteKF",
    "ReducedKF",
    "WaveFilterEKF",
    "WaveFilterObserver",
    "gain_settling_steps",
    "hf_gain_for_std",
]

Array = NDArray[np.float64]


# ---- the law over N envs: compiled loops over the envs -----------------------------------------
@njit
def _mv_rows(M, u, out):  # type: ignore[no-untyped-def]
    """``out[j] = M[j or 0] u[j]`` for every row (``M`` (1 or N, r, c), ``u`` (N, c))."""
    shared = M.shape[0] == 1
    for j in range(u.shape[0]):
        Mj = M[0] if shared else M[j]
        for i in range(Mj.shape[0]):
            acc = 0.0
            for k in range(Mj.shape[1]):
                acc += Mj[i, k] * u[j, k]
            out[j, i] = acc


@njit
def _kf_predict(sel, linear, Phi, add, W, freeze, steps, x, P):  # type: ignore[no-untyped-def]
    """The prediction of the envs ``sel``: ``x = Phi x + add`` (where ``linear``; else the
    caller has set ``x``) and, unless the gain is frozen (``0 <= freeze <= steps``), ``P =
    Phi P Phi^T + W`` (``Phi``, ``W``: (1 or N, n, n)), in place."""
    n = x.shape[1]
    shared = Phi.shape[0] == 1
    xn = np.empty((n, 1))
    T = np.empty((n, n))
    for j in range(x.shape[0]):
        if not sel[j]:
            continue
        F = Phi[0] if shared else Phi[j]
        if linear:
            mat_mul(F, x[j].reshape(n, 1), xn)
            for i in range(n):
                x[j, i] = xn[i, 0] + add[j, i]
        if not 0 <= freeze <= steps[j]:
            mat_mul(F, P[j], T)
            mat_mul_t(T, F, P[j])
            P[j] += W[0] if shared else W[j]


@njit
def _kf_update(sel, valid, z, H, R, wrap, freeze, steps, x, P, K, S, has_S, innov, nis):  # type: ignore[no-untyped-def]  # noqa: E501
    """The measurement update of the envs ``sel`` with ``z`` (N, q) where ``valid`` (Al-Takie
    1982 App. 3: gain, Joseph form; the gain and ``S`` held once frozen), in place; ``wrap``:
    the last component of the innovation is a heading, wrapped to ``[-pi, pi)``."""
    n, q = x.shape[1], z.shape[1]
    pi, two_pi = math.pi, 2.0 * math.pi
    e, w, HP, Kt = np.empty((q, 1)), np.empty((q, 1)), np.empty((q, n)), np.empty((q, n))
    T, IKH, T2, KR = np.empty((n, n)), np.empty((n, n)), np.empty((n, n)), np.empty((n, q))
    Ke = np.empty((n, 1))
    for j in range(x.shape[0]):
        if not sel[j]:
            continue
        steps[j] += 1
        if not valid[j]:
            innov[j] = np.nan
            nis[j] = np.nan
            continue
        mat_mul(H, x[j].reshape(n, 1), e)
        for i in range(q):
            e[i, 0] = z[j, i] - e[i, 0]
        if wrap:
            e[q - 1, 0] = (e[q - 1, 0] + pi) % two_pi - pi
        frozen = 0 <= freeze <= steps[j]
        if not (frozen and has_S[j]):  # S = H P H^T + R
            mat_mul(H, P[j], HP)
            mat_mul_t(HP, H, S[j])
            S[j] += R
            has_S[j] = True
        if not frozen:  # K = (S^-1 H P)^T, the Joseph form
            solve_small(S[j], HP, Kt)
            K[j] = Kt.T
            joseph(P[j], K[j], H, R, T, IKH, T2, KR)
            P[j] = T
        mat_mul(K[j], e, Ke)
        solve_small(S[j], e, w)
        acc = 0.0
        for i in range(q):
            innov[j, i] = e[i, 0]
            acc += e[i, 0] * w[i, 0]
        nis[j] = acc
        for i in range(n):
            x[j, i] = x[j, i] + Ke[i, 0]


@njit
def _relinearise(sel, X, A_lf, B_lf, G_lf, F1, F2, dt, Qd, Phi, Gamma, W, count):  # type: ignore[no-untyped-def]  # noqa: E501
    """Al-Takie (1982) ch. 7 at the estimates of the envs ``sel``: the LF block of each env's
    ``Phi`` and ``Gamma`` (:func:`~shipgym.dynamics.altakie.discretise` of the LF matrix with
    the thruster columns times ``psi'(x5)``, ``psi'(x6)``,
    :func:`~shipgym.dynamics.altakie.saturated_lf_matrix`) and its ``W = Gamma Qd Gamma^T``
    (symmetrised), in place."""
    m, p = B_lf.shape[1], G_lf.shape[1]
    k = 6 + m + p
    M = np.zeros((k, k))
    E = np.empty((k, k))
    n = Gamma.shape[1]
    GQ = np.empty((n, p))
    T = np.empty((n, n))
    for j in range(X.shape[0]):
        if not sel[j]:
            continue
        for i in range(6):
            for c in range(6):
                a = A_lf[i, c]
                if i < 4 and c >= 4:  # the hull rows see the thrusters through psi
                    a = a * (F1 * F2 * math.exp(-F2 * abs(X[j, c])))
                M[i, c] = a * dt
            for c in range(m):
                M[i, 6 + c] = B_lf[i, c] * dt
            for c in range(p):
                M[i, 6 + m + c] = G_lf[i, c] * dt
        expm(M, E)
        Phi[j, :6, :6] = E[:6, :6]
        Gamma[j, :6] = E[:6, 6 + m :]
        mat_mul(Gamma[j], Qd, GQ)
        mat_mul_t(GQ, Gamma[j], T)
        W[j] = 0.5 * (T + T.T)
        count[j] += 1


def _rows(a: ArrayLike | None, shape: tuple[int, ...]) -> Array:
    """``a`` as float rows of ``shape`` of the compiled update's one type
    (:func:`~shipgym._jit.law_input`; broadcast from one row, a copy; zeros for ``None``)."""
    if a is None:
        return np.zeros(shape)
    if isinstance(a, np.ndarray) and a.shape == shape and a.dtype == np.float64:
        return law_input(a)
    return np.array(np.broadcast_to(np.asarray(a, dtype=float), shape), order="C")


class DiscreteKF:
    """Time-varying discrete Kalman filter with the Joseph update (Al-Takie 1982 App. 3), over
    ``envs >= 1`` envs at once (compiled loops over the envs: :func:`_kf_predict`,
    :func:`_kf_update`); ``x``, ``P``, ``K``, ``steps``, ``innovation``, ``nis`` and the
    methods' one-env arguments are env 0's (the single filter, ``envs = 1``).

    Args:
        A, B, G, H: continuous model, (n, n), (n, m), (n, p), (q, n) (per-unit time).
        Q: process-noise intensity of ``w``, (p, p); ``Q_D = Q / dt``.
        R: measurement-noise covariance, (q, q).
        dt: sampling interval (per-unit time).
        freeze_after: ``None`` (time-varying) or the number of steps after which the gain is
            frozen (the semi-constant-gain filter).
        envs: number of envs.

    Attributes:
        X, PP: every env's state estimates (envs, n) and covariances (envs, n, n).
    """

    def __init__(
        self,
        A: ArrayLike,
        B: ArrayLike,
        G: ArrayLike,
        H: ArrayLike,
        Q: ArrayLike,
        R: ArrayLike,
        dt: float,
        freeze_after: int | None = None,
        *,
        envs: int = 1,
    ) -> None:
        self.A = np.asarray(A, dtype=float)
        self.B = np.asarray(B, dtype=float)
        self.G = np.asarray(G, dtype=float)
        self.H = np.ascontiguousarray(H, dtype=float)
        self.Q = np.asarray(Q, dtype=float)
        self.R = np.ascontiguousarray(R, dtype=float)
        n = self.A.shape[0]
        if self.A.shape != (n, n) or self.B.shape[0] != n or self.G.shape[0] != n:
            raise ValueError(f"inconsistent shapes A {self.A.shape}, B {self.B.shape}")
        if self.H.shape[1] != n or self.R.shape != (self.H.shape[0],) * 2:
            raise ValueError(f"inconsistent shapes H {self.H.shape}, R {self.R.shape}")
        if freeze_after is not None and (isinstance(freeze_after, bool) or freeze_after < 1):
            raise ValueError(
                f"freeze_after must be None or a step count >= 1, got {freeze_after!r}"
            )
        self.dt = float(dt)
        self.freeze_after = freeze_after
        self.envs = int(envs)
        self.Phi, self.Delta, self.Gamma = discretise(self.A, self.B, self.G, self.dt)
        self.W = self.Gamma @ (self.Q / self.dt) @ self.Gamma.T
        self.W = 0.5 * (self.W + self.W.T)
        e, q = self.envs, self.H.shape[0]
        self.X = np.zeros((e, n))
        self.PP = np.zeros((e, n, n))
        self._K = np.zeros((e, n, q))
        self._S = np.zeros((e, q, q))
        self._has_S = np.zeros(e, dtype=bool)
        self._steps = np.zeros(e, dtype=np.int64)
        self._innov = np.full((e, q), np.nan)
        self._nis = np.full(e, np.nan)
        self._all = np.ones(e, dtype=bool)
        self.reset()

    @property
    def n(self) -> int:
        """Number of states."""
        return int(self.A.shape[0])

    # ---- env 0: the single filter -----------------------------------------------------------
    @property
    def x(self) -> Array:
        """The state estimate after the last step (env 0's; writable view)."""
        return self.X[0]

    @x.setter
    def x(self, value: ArrayLike) -> None:
        self.X[0] = value

    @property
    def P(self) -> Array:
        """The covariance after the last step (env 0's; writable view)."""
        return self.PP[0]

    @P.setter
    def P(self, value: ArrayLike) -> None:
        self.PP[0] = value

    @property
    def K(self) -> Array:
        """The last gain (n, q) (env 0's)."""
        return self._K[0]

    @property
    def steps(self) -> int:
        """Number of steps since :meth:`reset` (env 0's)."""
        return int(self._steps[0])

    @property
    def innovation(self) -> Array:
        """The last innovation (q,), NaN without a measurement (env 0's)."""
        return self._innov[0].copy()

    @property
    def nis(self) -> float | None:
        """The last NIS, ``None`` without a measurement (env 0's)."""
        v = float(self._nis[0])
        return None if math.isnan(v) else v

    @property
    def frozen(self) -> bool:
        """Whether the gain is frozen (semi-constant filter past ``freeze_after`` steps)."""
        return self.freeze_after is not None and self.steps >= self.freeze_after

    # ---- the law over the envs ----------------------------------------------------------------
    def _freeze(self) -> int:
        return -1 if self.freeze_after is None else int(self.freeze_after)

    def reset(
        self, x0: ArrayLike | None = None, P0: ArrayLike | None = None, mask: Any = None
    ) -> None:
        """Start the envs of ``mask`` (``None``: all) from ``x0`` ((n,) or (envs, n); default
        0) with covariance ``P0`` (default 0, as printed)."""
        m = self._all if mask is None else np.asarray(mask, dtype=bool)
        n, q = self.n, self.H.shape[0]
        self.X[m] = _rows(x0, (self.envs, n))[m]
        self.PP[m] = _rows(P0, (self.envs, n, n))[m]
        self._K[m] = 0.0
        self._S[m] = 0.0
        self._has_S[m] = False
        self._steps[m] = 0
        self._innov[m] = np.full(q, np.nan)
        self._nis[m] = np.nan

    def _phi_w(self) -> tuple[Array, Array]:
        """The transition and noise matrices (1 or envs, n, n) of the next prediction."""
        return np.ascontiguousarray(self.Phi)[None], np.ascontiguousarray(self.W)[None]

    def _propagate(self, add: Array | None, sel: Any = None) -> None:
        """``x = Phi x + add`` (``None``: the caller has set ``x``) and ``P``, envs ``sel``."""
        s = self._all if sel is None else np.asarray(sel, dtype=bool)
        Phi, W = self._phi_w()
        a = np.zeros((1, self.n)) if add is None else add
        _kf_predict(s, add is not None, Phi, a, W, self._freeze(), self._steps, self.X, self.PP)

    def _times(self, M: NDArray[Any], u: ArrayLike, width: int) -> Array:
        """``M u`` of every env's ``u`` ((width,) or (envs, width)), (envs, rows of M)."""
        out = np.empty((self.envs, M.shape[-2]))
        Mr = np.ascontiguousarray(M if M.ndim == 3 else M[None])
        _mv_rows(Mr, _rows(u, (self.envs, width)), out)
        return out

    def predict(self, u: ArrayLike, sel: Any = None) -> None:
        """``x- = Phi x + Delta u`` and, unless frozen, ``P- = Phi P Phi^T + W`` (``u``: (m,)
        or (envs, m); ``sel``: the envs, ``None`` = all)."""
        self._propagate(self._times(self.Delta, u, self.B.shape[1]), sel)

    def update(
        self, z: ArrayLike | None, wrap: bool = False, valid: Any = None, sel: Any = None
    ) -> None:
        """Measurement update with ``z`` ((q,) or (envs, q); ``None``: no measurement, the
        prediction stands) where ``valid`` (``None``: all); ``wrap``: the last component is a
        heading (its innovation wrapped); ``sel``: the envs, ``None`` = all."""
        e, q = self.envs, self.H.shape[0]
        s = self._all if sel is None else np.asarray(sel, dtype=bool)
        if z is None:
            za, v = np.zeros((e, q)), np.zeros(e, dtype=bool)
        else:
            za = _rows(z, (e, q))
            v = self._all if valid is None else np.asarray(valid, dtype=bool)
        _kf_update(s, v, za, self.H, self.R, bool(wrap), self._freeze(), self._steps, self.X,
                   self.PP, self._K, self._S, self._has_S, self._innov, self._nis)  # fmt: skip

    def step(self, z: ArrayLike | None, u: ArrayLike) -> None:
        """One sampling interval: predict with ``u`` (held over it), then update with ``z``."""
        self.predict(u)
        self.update(z)


class ReducedKF(DiscreteKF):
    """The reduced-order filter of Al-Takie (1982) 6.2 on a 14-state model: 12 states.

    The thruster states (indices 4, 5 of the LF model) are measured exactly; the filter keeps
    ``[v, y, r, psi]`` and the 8 HF states. :meth:`step_thrust` takes the thruster states at
    the start and at the end of the interval (``f0``, ``f1``); with the first-order lag they fix
    the demand ``u = Delta_f^-1 (f1 - Phi_f f0)`` over the interval, so the prediction is the
    14-state filter's, exactly.

    Args:
        model: the 14-state :class:`~shipgym.dynamics.altakie.WaveFilterModel`.
        dt, freeze_after, envs: as :class:`DiscreteKF`.
    """

    THRUST = np.r_[4:6]

    def __init__(
        self, model: WaveFilterModel, dt: float, freeze_after: int | None = None, *, envs: int = 1
    ) -> None:
        Phi, Delta, _ = discretise(model.A, model.B, model.G, dt)
        #: the kept states: all but the thruster states (12, or 14 with bias states)
        self.KEEP = k = np.r_[0:4, 6 : model.n]
        f = self.THRUST
        super().__init__(
            model.A[np.ix_(k, k)],
            model.A[np.ix_(k, f)],
            model.G[k],
            model.H[:, k],
            model.Q,
            model.R,
            dt,
            freeze_after,
            envs=envs,
        )
        # exact: the kept states see the thruster states through the 14-state Phi, Delta
        self.Phi = Phi[np.ix_(k, k)]
        self._Phi_kf = Phi[np.ix_(k, f)]
        self._Delta_k = Delta[k]
        self._Phi_f = Phi[np.ix_(f, f)]
        self._Delta_f_inv = np.linalg.inv(Delta[f])

    def step_thrust(
        self, z: ArrayLike | None, f0: ArrayLike, f1: ArrayLike, valid: Any = None, sel: Any = None
    ) -> None:
        """One interval with the measured thruster states at its start ``f0`` and end ``f1``
        ((2,) or (envs, 2)), then the update with ``z`` where ``valid``; envs ``sel``."""
        f0_ = _rows(f0, (self.envs, 2))
        u = self._times(self._Delta_f_inv, _rows(f1, (self.envs, 2)) - self._times(
            self._Phi_f, f0_, 2), 2)  # fmt: skip
        self._propagate(self._times(self._Phi_kf, f0_, 2) + self._times(self._Delta_k, u, 2), sel)
        self.update(z, valid=valid, sel=sel)

    def step(self, z: ArrayLike | None, u: ArrayLike) -> None:  # noqa: D102
        raise TypeError("ReducedKF takes the measured thruster states: use step_thrust(z, f0, f1)")


class WaveFilterEKF(DiscreteKF):
    """The extended filter of Al-Takie (1982) ch. 7 with saturating thrusters.

    The LF model's thruster columns act through ``psi(x5)``, ``psi(x6)``
    (:func:`~shipgym.dynamics.altakie.saturation`); the prediction integrates that nonlinear
    model over the interval (RK4, ``substeps``: :func:`~shipgym.dynamics.altakie.
    saturated_lf_rows`); each env's ``Phi`` (and ``W``) are re-linearised at its estimate
    every ``relinearise_every`` steps.

    Args:
        model: the 14-state model.
        dt: sampling interval (p.u.).
        F1, F2: saturation limit (p.u.) and slope factor (``F1 F2 = 1``: slope 1 at 0).
        relinearise_every: steps between re-linearisations (2 printed).
        substeps: RK4 steps per interval.
        envs: number of envs.
    """

    def __init__(
        self,
        model: WaveFilterModel,
        dt: float,
        F1: float = 0.02,
        F2: float = 50.0,
        relinearise_every: int = 2,
        substeps: int = 4,
        *,
        envs: int = 1,
    ) -> None:
        super().__init__(model.A, model.B, model.G, model.H, model.Q, model.R, dt, envs=envs)
        if isinstance(relinearise_every, bool) or int(relinearise_every) < 1:
            raise ValueError(f"relinearise_every must be >= 1, got {relinearise_every!r}")
        self.F1, self.F2 = float(F1), float(F2)
        self.relinearise_every = int(relinearise_every)
        self.substeps = int(substeps)
        # the LF block is nonlinear; the HF blocks are linear and fixed (exact transition)
        self._A_rest = model.A[:6, 6:]  # the LF block's input from the other states (bias)
        self._B_lf = np.ascontiguousarray(model.B[:6])
        self._G_lf = np.ascontiguousarray(model.G[:6])
        self._A_lf = np.ascontiguousarray(self.A[:6, :6])
        self._Phi_env = np.repeat(self.Phi[None], self.envs, axis=0)
        self._Gamma_env = np.repeat(self.Gamma[None], self.envs, axis=0)
        self._W_env = np.repeat(self.W[None], self.envs, axis=0)
        self._relin = np.zeros(self.envs, dtype=np.int64)

    @property
    def relinearisations(self) -> int:
        """How often env 0's ``Phi`` was re-linearised."""
        return int(self._relin[0])

    def jacobian(self, x: ArrayLike) -> Array:
        """``A(x) = df/dx``: the thruster columns times ``psi'(x5)``, ``psi'(x6)``."""
        x_ = np.asarray(x, dtype=float)
        F = self.A.copy()
        F[:6, :6] = saturated_lf_matrix(self.A[:6, :6], x_[4:6], self.F1, self.F2)
        return F

    def _phi_w(self) -> tuple[Array, Array]:
        return self._Phi_env, self._W_env

    def predict(self, u: ArrayLike, sel: Any = None) -> None:
        s = self._all if sel is None else np.asarray(sel, dtype=bool)
        relin = s & (self._steps % self.relinearise_every == 0)
        if relin.any():  # only the LF block depends on the estimate (the HF blocks do not)
            _relinearise(relin, self.X, self._A_lf, self._B_lf, self._G_lf, self.F1, self.F2,
                         self.dt, self.Q / self.dt, self._Phi_env, self._Gamma_env,
                         self._W_env, self._relin)  # fmt: skip
        hf = self._times(np.ascontiguousarray(self._Phi_env[:, 6:, 6:]), self.X[:, 6:], self.n - 6)
        # held over the interval
        u_in = self._times(self._B_lf, u, self.B.shape[1]) + self._times(
            self._A_rest, self.X[:, 6:], self.n - 6)  # fmt: skip
        x = np.ascontiguousarray(self.X[:, :6])
        saturated_lf_rows(x, u_in, self._A_lf, self.dt, self.F1, self.F2, self.substeps)
        self.X[s] = np.concatenate([x, hf], axis=1)[s]
        self._propagate(None, s)


# ---- observers for the simulated vessels -------------------------------------------------------


def gain_settling_steps(
    A: ArrayLike,
    G: ArrayLike,
    H: ArrayLike,
    Q: ArrayLike,
    R: ArrayLike,
    dt: float,
    tol: float = 0.02,
    max_steps: int = 100_000,
) -> int:
    """Steps until the time-varying gain from ``P(0) = 0`` stays within ``tol`` of steady state.

    ``tol`` relative to ``max |K_inf|`` (the steady-state gain of the DARE); the filter of
    :class:`DiscreteKF` (``Q_D = Q / dt``). Once within ``tol`` the Riccati recursion converges
    monotonically here, so the first such step is returned.
    """
    A_, G_, H_, R_ = (np.asarray(M, dtype=float) for M in (A, G, H, R))
    Phi, _, Gam = discretise(A_, np.zeros((A_.shape[0], 1)), G_, dt)
    W = Gam @ (np.asarray(Q, dtype=float) / dt) @ Gam.T
    P_inf = scipy.linalg.solve_discrete_are(Phi.T, H_.T, W, R_)
    K_inf = P_inf @ H_.T @ np.linalg.inv(H_ @ P_inf @ H_.T + R_)
    scale = float(np.abs(K_inf).max())
    P = np.zeros_like(Phi)
    for k in range(1, max_steps + 1):
        Pm = Phi @ P @ Phi.T + W
        K = Pm @ H_.T @ np.linalg.inv(H_ @ Pm @ H_.T + R_)
        if float(np.abs(K - K_inf).max()) <= tol * scale:
            return k
        P = Pm - K @ H_ @ Pm
    raise ValueError(f"the gain did not settle within {max_steps} steps")


def hf_gain_for_std(alpha: ArrayLike, Tb: float, std: float) -> float:
    """The HF noise gain ``d`` (``D_h = [0, 0, 0, d]``, unit noise) giving an output std ``std``.

    From the stationary Lyapunov solution of the per-unit block ``A_hs``.
    """
    A = hf_block(alpha, Tb)
    Bw = np.array([[0.0], [0.0], [0.0], [1.0]])
    P = scipy.linalg.solve_continuous_lyapunov(A, -Bw @ Bw.T)
    return float(std) / math.sqrt(float(P[2, 2]))


_SIGMA_POSITION = 1.0 / 3.0  # m: the thesis's position reference (Al-Takie 1982 2.4.2) [printed]
_SIGMA_HEADING = 0.02  # rad: the thesis's gyro (Al-Takie 1982 2.4.2) [printed]

#: Noise designs of the ``alt-*`` observers: ``q_l`` (sway force, yaw moment), ``q_x`` (surge
#: force) variances (p.u.^2) of the LF model.
#:
#: - ``"thesis"``: ``Q_l`` as printed (the mean wind forcing taken as the noise sigma, Al-Takie
#:   1982 2.4.1) with the reconstructed yaw entry (``altakie.D_H_RECONSTRUCTED``),
#:   ``q_x`` = the sway one, and the HF noise of the physical sea (``hf_std``): a hybrid, NOT
#:   the filter of the printed gains, whose HF noise (``D_H_RECONSTRUCTED``) is 28-67x the
#:   physical one (9.6 m of HF sway in Beaufort 8: :mod:`shipgym.dp.seed`). Against the
#:   physical HF noise the printed ``Q_l`` makes the LF estimate nearly as fast as the wave
#:   band (velocity random walk 0.36 m/s per 270 s for Star Hercules), so it passes
#:   measurement noise and wave motion to the thrusters (wave-band thrust ratio 2.7-4.1, as LQ
#:   on raw measurements, 3.9-4.0; Wimpey Sealab, Beaufort 5, 8).
#: - ``"simulated"`` (default) [chosen]: ``q_l = (1e-8, 1e-8)``, ``q_x = 1e-9``: an LF velocity
#:   random walk of about 2 cm/s per 5 minutes, the slow drift of a ship held in gusty wind;
#:   picked from a scan on ``shipgym/DPStationKeeping-v0`` (both vessels, Beaufort 5 and 8,
#:   600 s): wave-band ratio 0.001-0.14 against 0.06-2.9 for the same LQ on raw measurements,
#:   at the cost of a larger LF lag (see ``alt-kf16`` for its bias states).
NOISE_DESIGNS: dict[str, dict[str, Any]] = {
    "thesis": {"q_l": None, "q_x": None},
    "simulated": {"q_l": (1e-8, 1e-8), "q_x": 1e-9},
}

#: bias-force intensities ``(b_X, b_Y, b_N)`` of ``alt-kf16`` (p.u.^2 per p.u. time) [chosen:
#: from the same scan (1e-11 to 1e-7): they take the mean wind, drift and current loads off the
#: LF states, so the LF noise can stay small without a lag: Wimpey Sealab Beaufort 8 position
#: RMS 4.9 m -> 0.8 m, heading 3.1 deg -> 0.9 deg, wave-band ratio 0.09 -> 0.14 (raw: 2.2)]
BIAS_Q = (1e-10, 1e-10, 1e-10)


class BatchedWaveFilter:
    """``n`` Al-Takie (1982) wave filters of one vessel and design stepped together (the
    presets ``alt-*``; :class:`WaveFilterObserver` is one env of it): the frames and forces
    elementwise over the envs, the filters' algebra in their compiled loops.

    Args:
        vessel, kind, **settings: as :class:`WaveFilterObserver`.
        n: number of envs, >= 1.
    """

    #: discretised for one sampling interval: stepped at its samples only (an env does not
    #: coast it to the end of a period without a sample)
    fixed_interval = True

    model_based = True  # the LF model and the thrust drive its prediction
    thrust_input = "command"

    def __init__(
        self,
        vessel: Any = None,
        kind: str = "kf14",
        n: int = 1,
        *,
        beaufort: int = 8,
        hf_std: tuple[float, float] | None = None,
        sigma_position: float | None = None,
        sigma_heading: float = _SIGMA_HEADING,
        design: str = "simulated",
        q_l: tuple[float, float] | None = None,
        q_x: float | None = None,
        bias_q: tuple[float, float, float] | None = None,
        dt: float = 0.1,
        freeze_time: float | None = None,
        relinearise_every: int = 2,
        F1: float | None = None,
    ) -> None:
        if vessel is None:
            raise TypeError(
                "the Al-Takie wave filters need the vessel: make_observer(name, vessel=...) "
                "or shipgym.make(..., vessel=..., observer=name)"
            )
        if kind not in _KINDS:
            raise ValueError(f"kind must be one of {', '.join(_KINDS)}, got {kind!r}")
        if design not in NOISE_DESIGNS:
            raise ValueError(f"design must be one of {', '.join(NOISE_DESIGNS)}, got {design!r}")
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ValueError(f"n must be an int >= 1 (the number of envs), got {n!r}")
        self._settings: dict[str, Any] = {
            "beaufort": beaufort, "hf_std": hf_std, "sigma_position": sigma_position,
            "sigma_heading": sigma_heading, "design": design, "q_l": q_l, "q_x": q_x,
            "bias_q": bias_q, "dt": dt, "freeze_time": freeze_time,
            "relinearise_every": relinearise_every, "F1": F1,
        }  # fmt: skip
        if q_l is None:
            q_l = NOISE_DESIGNS[design]["q_l"]
        if q_x is None:
            q_x = NOISE_DESIGNS[design]["q_x"]
        if sigma_position is None:
            sigma_position = _SIGMA_POSITION / float(vessel.scale)
        self.n = n = int(n)
        self.vessel = vessel
        self.kind = kind
        self.name = "alt-kf16" if kind == "kf14" and bias_q is not None else f"alt-{kind}"
        if kind == "kf12":
            self.thrust_input = "applied"
        pu = PerUnit.of_vessel(vessel)
        self.pu = pu
        self.has_bias = bias_q is not None
        self.dt_pu = float(dt)
        self.dt = self.dt_pu * pu.time
        if hf_std is None:
            hf_std = _preset_hf_std(vessel, beaufort)
        L = pu.L
        alpha = hf_alpha(beaufort, pu, vessel.name)
        d_pos = hf_gain_for_std(alpha, pu.time, hf_std[0] / L)
        d_psi = hf_gain_for_std(alpha, pu.time, hf_std[1])
        r = ((sigma_position / L) ** 2, sigma_heading**2)
        lf = lf_model_from_vessel(vessel)
        self.model = wave_filter_model(
            lf,
            beaufort,
            ship=vessel.name,
            d_h=(d_pos, d_psi),
            q_l=q_l,
            r=r,
            bias_q=None if bias_q is None else (bias_q[1], bias_q[2]),
        )
        m = self.model
        freeze = None
        if kind == "semiconstant":
            if freeze_time is None and design == "thesis":
                freeze_time = 28.0
            if freeze_time is None:
                freeze = gain_settling_steps(m.A, m.G, m.H, m.Q, m.R, self.dt_pu)
            else:
                freeze = max(1, math.ceil(freeze_time / self.dt - 1e-9))
        if kind == "kf12":
            self.core: DiscreteKF = ReducedKF(m, self.dt_pu, envs=n)
        elif kind == "ekf":
            F1_ = _sway_capacity_pu(vessel, pu) if F1 is None else float(F1)
            self.core = WaveFilterEKF(m, self.dt_pu, F1=F1_, F2=1.0 / F1_,
                                      relinearise_every=relinearise_every, envs=n)  # fmt: skip
        elif kind in ("lf6", "raw"):
            keep = np.r_[0:6, 14 : m.n]  # no HF states (bias states kept)
            noise = np.r_[0:2, 4 : m.Q.shape[0]]
            self.core = DiscreteKF(
                m.A[np.ix_(keep, keep)],
                m.B[keep],
                m.G[np.ix_(keep, noise)],
                m.H[:, keep],
                m.Q[np.ix_(noise, noise)],
                m.R,
                self.dt_pu,
                envs=n,
            )
        else:
            self.core = DiscreteKF(m.A, m.B, m.G, m.H, m.Q, m.R, self.dt_pu, freeze, envs=n)
        # surge: the decoupled [u, x, f_X] (+ 4 HF states) (+ a bias), the same design
        hf = None if kind in ("lf6", "raw") else hf_block(alpha, pu.time)
        A, B, G, H, Q = _surge_model(
            vessel,
            hf,
            d_pos,
            float(m.Q[0, 0]) if q_x is None else float(q_x),
            None if bias_q is None else bias_q[0],
        )
        self.surge = DiscreteKF(A, B, G, H, Q, m.R[:1, :1], self.dt_pu, freeze, envs=n)
        self._scale = np.array([pu.force, pu.force, pu.moment])
        self._origin = np.zeros((n, 3))
        self._c = np.ones(n)
        self._s = np.zeros(n)
        self._t = np.zeros(n)
        self._f_prev = np.zeros((n, 3))
        self._psi_unwrap = np.zeros(n)
        self._z_last = np.zeros((n, 3))
        self._has_z = np.zeros(n, dtype=bool)
        self._started = np.ones(n, dtype=bool)  # at rest at the origin until a reset
        self._info = BatchedStepInfo(np.full((n, 3), np.nan), np.full(n, np.nan),
                                     np.zeros(n, bool), np.zeros(n, bool))  # fmt: skip

    def check_sample_interval(self, period: float, control_period: float) -> None:
        """Refuse, when an env is built, sensors sampled (``period``, s) or control steps
        (``control_period``, s) at another interval than the filter's :attr:`dt`: the first
        step would raise.

        Raises:
            ValueError: naming both intervals and the setting to use.
        """
        for what, x in (("sensor period", period), ("control period", control_period)):
            if abs(float(x) - self.dt) > 1e-6 * self.dt:
                raise ValueError(
                    f"{self.name} samples every {self.dt:.6g} s (0.1 per-unit time of "
                    f"{self.vessel.name}); the env's {what} is {float(x):.6g} s: run the env "
                    f"with control_period={self.dt:.6g} and sensors sampled at it"
                )

    def batch(self, n: int) -> BatchedWaveFilter:
        """A new batch of ``n`` envs with these settings."""
        return BatchedWaveFilter(self.vessel, self.kind, n, **self._settings)

    def reset(
        self,
        t0: ArrayLike,
        eta0: ArrayLike,
        *,
        mask: ArrayLike | None = None,
        nu0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
    ) -> None:
        """Start the envs of ``mask`` (``None``: all) at ``t0`` (n,) in the frame of ``eta0``
        (n, 3), at ``nu0`` (n, 3) (``None``: rest), ``P0`` the core filter's covariance
        (``None``: 0)."""
        n = self.n
        m = np.ones(n, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        e = _rows(eta0, (n, 3))
        tt = np.broadcast_to(np.asarray(t0, dtype=float), (n,))
        if not (np.isfinite(e[m]).all() and np.isfinite(tt[m]).all()):
            raise ValueError("t0 and eta0 must be finite")
        self._origin[m] = e[m]
        self._c[m], self._s[m] = np.cos(e[m, 2]), np.sin(e[m, 2])
        self._psi_unwrap[m] = e[m, 2]
        self._t[m] = tt[m]
        x0 = np.zeros((n, self.core.n))
        xs = np.zeros((n, self.surge.n))
        if nu0 is not None:
            n0 = _rows(nu0, (n, 3))
            xs[:, 0] = n0[:, 0] / self.pu.velocity
            x0[:, 0] = n0[:, 1] / self.pu.velocity
            x0[:, 2] = n0[:, 2] / self.pu.angular_velocity  # index 2 in both state layouts
        self.core.reset(x0, P0, mask=m)
        self.surge.reset(xs, mask=m)
        self._f_prev[m] = 0.0
        self._has_z[m] = False
        self._info.innovation[m] = np.nan
        self._info.nis[m] = np.nan
        self._info.rejected[m] = False
        self._started[m] = True

    def step(
        self,
        t: ArrayLike,
        z: ArrayLike | None = None,
        valid: ArrayLike | None = None,
        tau: ArrayLike | None = None,
    ) -> BatchedStepInfo:
        """One sampling interval to ``t`` (n,) of every env whose time moves (the others
        keep their last step's information), with the demand ``tau`` (n, 3) (N, N, N m;
        ``thrust_input``; ``None``: zero) held over it, and the update with ``z`` (n, 3)
        where ``valid``.

        Raises:
            RuntimeError: an env was never reset.
            ValueError: an interval that is not the filter's sampling interval.
        """
        n = self.n
        if not self._started.all():
            raise RuntimeError(f"{self.name}: call reset(t0, eta0) before step()")
        tt = np.broadcast_to(np.asarray(t, dtype=float), (n,))
        dt = tt - self._t
        sel = ~(dt <= 1e-9 * self.dt)
        if (np.abs(dt[sel] - self.dt) > 1e-6 * self.dt).any():
            bad = float(dt[sel][np.abs(dt[sel] - self.dt) > 1e-6 * self.dt][0])
            raise ValueError(
                f"{self.name} samples every {self.dt:.6g} s (0.1 per-unit time of "
                f"{self.vessel.name}); got an interval of {bad:.6g} s: run the env with "
                f"control_period={self.dt:.6g} and sensors sampled at it"
            )
        if not sel.any():
            return self._info_copy()
        self._t[sel] = tt[sel]
        f = np.zeros((n, 3)) if tau is None else np.asarray(tau, dtype=float) / self._scale
        if z is None:
            v = np.zeros(n, dtype=bool)
            zl = np.zeros((n, 3))
        else:
            v = sel & (np.ones(n, bool) if valid is None else np.asarray(valid, dtype=bool))
            if not np.isfinite(np.asarray(z, dtype=float)[v]).all():
                raise ValueError(f"{self.name}: z must be finite where valid")
            zl = self._to_local(np.where(v[:, None], z, 0.0), v)
            self._z_last[v] = zl[v]
            self._has_z |= v
        core, surge, fp = self.core, self.surge, self._f_prev
        if isinstance(core, ReducedKF):
            core.step_thrust(zl[:, 1:], fp[:, 1:], f[:, 1:], valid=v, sel=sel)
            # surge keeps its own lag model: the applied thrust's demand from the same lag law
            s_phi, s_del = surge.Phi[2, 2], surge.Delta[2, 0]
            surge.predict(((f[:, 0] - s_phi * fp[:, 0]) / s_del)[:, None], sel)
        else:
            core.predict(f[:, 1:], sel)
            core.update(zl[:, 1:], wrap=True, valid=v, sel=sel)
            surge.predict(f[:, :1], sel)
        surge.update(zl[:, :1], valid=v, sel=sel)
        fp[sel] = f[sel]
        L = self.pu.L
        X, Y = surge._innov[:, 0] * L, core._innov[:, 0] * L
        c, s = self._c, self._s
        inn = np.stack([c * X - s * Y, s * X + c * Y, core._innov[:, 1]], axis=1)
        info = self._info
        info.innovation[sel] = np.where(v[:, None], inn, np.nan)[sel]
        info.nis[sel] = np.where(v, core._nis + surge._nis, np.nan)[sel]
        return self._info_copy()

    def _info_copy(self) -> BatchedStepInfo:
        i = self._info
        return BatchedStepInfo(i.innovation.copy(), i.nis.copy(), i.rejected.copy(),
                               i.forced.copy())  # fmt: skip

    def _to_local(self, z: Array, v: NDArray[np.bool_]) -> Array:
        """NED poses -> ``[x', y', psi']`` in the reset frames (p.u. positions, rad); the
        unwrapped heading of the envs ``v`` moves on."""
        dx, dy = z[:, 0] - self._origin[:, 0], z[:, 1] - self._origin[:, 1]
        c, s = self._c, self._s
        pu = self._psi_unwrap
        psi = pu + ((z[:, 2] - pu + math.pi) % (2.0 * math.pi) - math.pi)
        self._psi_unwrap = np.where(v, psi, pu)
        L = self.pu.L
        return np.stack(
            [(c * dx + s * dy) / L, (-s * dx + c * dy) / L, psi - self._origin[:, 2]], 1
        )

    # ---- estimates ----------------------------------------------------------------------------
    def lf_states(self) -> Array:
        """The per-unit LF estimates ``[v, y, r, psi, f_Y, f_N]`` (n, 6) (sway-yaw, reset
        frames)."""
        core = self.core
        if isinstance(core, ReducedKF):
            return np.concatenate([core.X[:, :4], self._f_prev[:, 1:]], axis=1)
        return core.X[:, :6].copy()

    def _lf_now(self) -> tuple[Array, Array, Array]:
        """``(x_s, u_s, lf)``: surge position, surge speed, LF states (p.u.), the measurement
        itself for ``raw`` where there is one."""
        lf = self.lf_states()
        xs, us = self.surge.X[:, 1].copy(), self.surge.X[:, 0]
        if self.kind == "raw":  # the measurement itself
            h = self._has_z
            xs[h] = self._z_last[h, 0]
            lf[h, 1], lf[h, 3] = self._z_last[h, 1], self._z_last[h, 2]
        return xs, us, lf

    @property
    def eta(self) -> Array:
        """The estimated poses (n, 3) (m, m, rad; NED)."""
        xs, _, lf = self._lf_now()
        X, Y = xs * self.pu.L, lf[:, 1] * self.pu.L
        c, s, o = self._c, self._s, self._origin
        return np.stack([o[:, 0] + c * X - s * Y, o[:, 1] + s * X + c * Y, o[:, 2] + lf[:, 3]], 1)

    @property
    def nu(self) -> Array:
        """The estimated body velocities (n, 3) (m/s, m/s, rad/s)."""
        _, us, lf = self._lf_now()
        pu = self.pu
        return np.stack([us * pu.velocity, lf[:, 0] * pu.velocity,
                         lf[:, 2] * pu.angular_velocity], 1)  # fmt: skip

    def hf_motion(self, j: int) -> Array:
        """Env ``j``'s estimated first-order wave motion ``[x, y, psi]`` (m, m, rad; NED)."""
        core = self.core
        if self.kind in ("lf6", "raw"):
            return np.zeros(3)
        i_s, i_y = self.model.HF_OUT
        if isinstance(core, ReducedKF):  # without the two thruster states
            i_s, i_y = i_s - 2, i_y - 2
        L = self.pu.L
        X, Y = self.surge.X[j, 5] * L, core.X[j, i_s] * L
        c, s = self._c[j], self._s[j]
        return np.array([c * X - s * Y, s * X + c * Y, core.X[j, i_y]])

    def estimate(self, j: int) -> Estimate:
        """Env ``j``'s estimate."""
        pu = self.pu
        xs, us, lf = self._lf_now()
        X, Y = xs[j] * pu.L, lf[j, 1] * pu.L
        c, s, o = self._c[j], self._s[j], self._origin[j]
        eta = np.array([o[0] + c * X - s * Y, o[1] + s * X + c * Y, o[2] + lf[j, 3]])
        nu = np.array([us[j] * pu.velocity, lf[j, 0] * pu.velocity,
                       lf[j, 2] * pu.angular_velocity])  # fmt: skip
        P, Ps = self.core.PP[j], self.surge.PP[j]
        iy, ipsi, iv, ir = (1, 3, 0, 2)  # the same in the 14-, 12- and 6-state layouts
        scale_pos = pu.L**2
        P_eta = np.diag([Ps[1, 1] * scale_pos, P[iy, iy] * scale_pos, P[ipsi, ipsi]])
        P_nu = np.diag(
            [
                Ps[0, 0] * pu.velocity**2,
                P[iv, iv] * pu.velocity**2,
                P[ir, ir] * pu.angular_velocity**2,
            ]
        )
        bias = None
        if self.has_bias:  # the last states of both filters
            x, xsj = self.core.X[j], self.surge.X[j]
            bias = np.array([xsj[-1] * pu.force, x[-2] * pu.force, x[-1] * pu.moment])
        ns = Ps.shape[0]
        P_all = np.zeros((ns + P.shape[0],) * 2)  # the block diagonal [surge, sway-yaw]
        P_all[:ns, :ns] = Ps
        P_all[ns:, ns:] = P
        return Estimate(float(self._t[j]), eta, nu, P_all, P_eta, P_nu, bias)


class WaveFilterObserver(BatchOfOne):
    """An Al-Takie (1982) wave filter for a simulated vessel (SI, NED; the presets ``alt-*``):
    one env of :class:`BatchedWaveFilter`.

    Args:
        vessel: the :class:`~shipgym.dynamics.vessel.Vessel` (its design model and lags).
        kind: ``"kf14"`` (time-varying 14-state), ``"semiconstant"`` (frozen at
            ``freeze_time``), ``"kf12"`` (reduced: takes the applied thrust as measured thruster
            states), ``"ekf"`` (saturating thrusters, Al-Takie 1982 ch. 7), ``"lf6"`` (the
            LF model only: no wave model) or ``"raw"`` (the measured pose as the
            estimate, velocities from the ``lf6`` filter: a controller "on raw measurements").
        beaufort: Beaufort number (5-9) of the filter's HF model; the thesis's nominal design
            is 8 (and it recommends designing for a higher sea than expected).
        hf_std: ``(position m, heading rad)`` std of the first-order motion the HF model
            expects; ``None``: the WF stds of the Beaufort preset at the vessel's scale
            (``shipgym.scenarios.beaufort``: ``Hs/16`` and ``radians(2) Hs w_p^2 / g``).
        sigma_position, sigma_heading: measurement-noise stds (m, rad); ``None``: the thesis's
            1/3 m (divided by the vessel's scale) and 0.02 rad.
        design: the LF noise design, a key of :data:`NOISE_DESIGNS` (``"simulated"``).
        q_l: LF noise variances (sway force, yaw moment, p.u.^2); ``None``: the design's.
        q_x: surge force noise variance of the surge filter (p.u.^2); ``None``: the design's.
        bias_q: ``None`` (the thesis's model) or the intensities (p.u.^2 per p.u. time) of
            random-walk bias forces ``(b_X, b_Y, b_N)`` added to the model (16 states in sway-yaw,
            :func:`~shipgym.dynamics.altakie.wave_filter_model`); reported as ``bias`` (N, N, N m).
        dt: sampling interval in per-unit time (0.1 printed).
        freeze_time: when the semi-constant filter freezes its gain (s real time); ``None``:
            28 s for the ``"thesis"`` design (printed), else the time by which every gain is
            within 2 % of steady state (:func:`gain_settling_steps`; the thesis froze its gain
            8 s after it had settled).
        relinearise_every: EKF steps between re-linearisations (2 printed).
        F1: EKF thruster saturation (p.u. force); ``None``: the vessel's sway capacity in p.u.

    The filter expects one :meth:`step` per sampling interval ``dt`` (real time ``dt T_b``);
    a call at another interval raises. ``thrust_input`` is ``"command"`` (the demand, which
    the filter lags itself), except for ``kf12`` (``"applied"``: measured thruster states).
    Its ``vessel``, ``kind``, ``name``, ``pu``, ``has_bias``, ``dt_pu``, ``dt``, ``model``,
    ``core`` and ``surge`` (the filters, at N = 1) are the batch's.
    """

    model_based = True

    def __init__(self, vessel: Any = None, kind: str = "kf14", **settings: Any) -> None:
        self._b = BatchedWaveFilter(vessel, kind, 1, **settings)
        self.name = self._b.name
        self.thrust_input = self._b.thrust_input
        self._started = True  # at rest at the origin until a reset

    def __getattr__(self, key: str) -> Any:
        if key in _SHARED_ATTRS:
            return getattr(self.__dict__["_b"], key)
        raise AttributeError(key)

    def check_sample_interval(self, period: float, control_period: float) -> None:
        """The batch's :meth:`BatchedWaveFilter.check_sample_interval`."""
        self._b.check_sample_interval(period, control_period)

    def batch(self, n: int) -> BatchedWaveFilter:
        """This filter's law over ``n`` envs (the vector env's)."""
        return self._b.batch(n)

    def reset(
        self,
        t0: float,
        eta0: ArrayLike,
        *,
        nu0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
    ) -> None:
        if nu0 is not None:
            nu0 = as_pose(nu0, "nu0", "[u, v, r] (m/s, m/s, rad/s)")
        self._reset_one(t0, eta0, nu0=nu0, P0=P0)

    def lf_state(self) -> Array:
        """The per-unit LF estimate ``[v, y, r, psi, f_Y, f_N]`` (sway-yaw, reset frame)."""
        return self._b.lf_states()[0]

    def hf_motion(self) -> Array:
        """The estimated first-order wave motion ``[x, y, psi]`` (m, m, rad; NED offsets)."""
        return self._b.hf_motion(0)


_SHARED_ATTRS = frozenset(
    ("vessel", "kind", "pu", "has_bias", "dt_pu", "dt", "model", "core", "surge")
)


_KINDS = ("kf14", "kf12", "semiconstant", "ekf", "lf6", "raw")


def _surge_model(
    vessel: Any, hf: Array | None, d: float, q: float, bias_q: float | None
) -> tuple[Array, Array, Array, Array, Array]:
    """The surge filter's model: ``[u, x, f_X]``, the HF block (output its 3rd state, noise
    ``d`` into its 4th), a random-walk bias force; ``(A, B, G, H, Q)`` per unit."""
    As, Bs, _, Ds = surge_model_from_vessel(vessel)
    blocks, noises, Q = [As], [Ds], [q]
    if hf is not None:
        blocks.append(hf)
        noises.append(np.array([[0.0], [0.0], [0.0], [d]]))
        Q.append(1.0)
    if bias_q is not None:
        blocks.append(np.zeros((1, 1)))
        noises.append(np.ones((1, 1)))
        Q.append(float(bias_q))
    A = scipy.linalg.block_diag(*blocks)
    G = scipy.linalg.block_diag(*noises)
    n = A.shape[0]
    if bias_q is not None:
        A[0, n - 1] = As[0, 2]  # a force on the hull, like the thruster output
    B = np.zeros((n, 1))
    B[:3] = Bs
    H = np.zeros((1, n))
    H[0, 1] = 1.0
    if hf is not None:
        H[0, 5] = 1.0
    return A, B, G, H, np.diag(Q)


def _preset_hf_std(vessel: Any, beaufort: int) -> tuple[float, float]:
    from shipgym.disturbances.seastate import beaufort as sea_state

    waves = sea_state(int(beaufort), scale=float(vessel.scale)).waves
    return float(waves.position_std), float(waves.heading_std)


def _sway_capacity_pu(vessel: Any, pu: PerUnit) -> float:
    return float(vessel.actuators.capacity()[1]) / pu.force


def _factory(kind: str, **preset: Any) -> Callable[..., WaveFilterObserver]:
    def make(**kw: Any) -> WaveFilterObserver:
        return WaveFilterObserver(kind=kind, **{**preset, **kw})

    return make


def _with_vessel(vessel: Any) -> dict[str, Any]:
    return {"vessel": vessel}


for _kind in _KINDS:
    register_observer(f"alt-{_kind}", _factory(_kind), _with_vessel)
#: the 14-state filter with two bias states in sway-yaw (and one in surge): 16 states
register_observer("alt-kf16", _factory("kf14", bias_q=BIAS_Q), _with_vessel)
for _name in [f"alt-{k}" for k in _KINDS] + ["alt-kf16"]:
    register_batched_form(_name)
