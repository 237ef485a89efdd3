r"""Discrete Kalman filter and Kalman-Bucy filter per DOF on a double integrator (Tomera 2011,
2014).

Model (Tomera 2011 eqs. 53-59)
------------------------------
Each NED DOF ``p`` in ``{x, y, psi}`` is an independent double integrator with state
``[p_dot, p]`` (Tomera's order: velocity first), ``A = [[0, 0], [1, 0]]``, ``C = [0, 1]``, driven by
white noise of intensity ``G Q G^T`` (:class:`~shipgym.observers.design.KalmanDesign`). The
filters are kinematic: Tomera (2011) (section 6) "does not take into account the model of ship
dynamics", so the thrust ``tau`` is accepted (and checked) but not used. The body velocity
follows from the NED rates by Tomera (2011) eq. 60, ``nu = R^T(psi) eta_dot``, with its covariance
``P_nu = J P J^T`` (``J`` the Jacobian of that map, including ``d nu / d psi = [v, -u, 0]``).

State and covariance layout: :attr:`x` and :attr:`Estimate.P <shipgym.observers.base.Estimate>`
are ``[x, y, psi, x_dot, y_dot, psi_dot]`` (m, m, rad, m/s, m/s, rad/s); cross-DOF covariances
are zero. The heading is unwrapped internally (continuous through north); heading innovations
are wrapped to ``(-pi, pi]``.

Filters
-------
:class:`DiscreteKalmanFilter` (Tomera 2014 Table 3; Tomera 2011 eqs. 14-24): ``F`` and ``Q_k`` are
rebuilt for the actual interval between calls (``F = I + A dt``, Tomera (2011) eq. 5, exact here;
``Q_k`` per the design's discretisation). Time-varying covariance (default) or, with
``constant_gain=True``, the steady-state filter-form gain of
:func:`~shipgym.observers.design.dlqe` at the design period ``T``, used whatever the interval
(as Tomera (2014) did with eq. 30); the constant-gain filter still propagates its true error
covariance (Joseph form with the fixed gain), so ``P``, NIS and the outlier gate stay honest.

:class:`KalmanBucyFilter` (Tomera 2014 Table 4; Tomera 2011 eqs. 39, 45, 52) in a sampled-data
implementation. The measurement between two samples is reconstructed by *first-order hold*:
``y(t)`` is the straight line from the previous accepted sample ``y_{k-1}`` at ``t_{k-1}`` to
the new one ``y_k`` at ``t_k``, and the filter ODEs are integrated *exactly* over the interval:

- time-varying (default): the Riccati ODE ``P_dot = A P + P A^T + G Q G^T - P C^T R_c^-1 C P``
  and ``x_hat_dot = A x_hat + P C^T R_c^-1 (y - C x_hat)`` are solved together in closed form
  through the Hamiltonian ``H = [[-A^T, C^T R_c^-1 C], [G Q G^T, A]]``: with
  ``[X; Y](s) = exp(H s) [I; P0]``, ``P(s) = Y X^-1`` and, because ``d/ds X^-T = (A - P C^T
  R_c^-1 C) X^-T`` and ``X^T P = Y^T``, ``x_hat(dt) = X(dt)^-T (x_hat0 + int_0^dt Y(s)^T C^T
  R_c^-1 y(s) ds)``. The integrals come from one matrix exponential per DOF and ``dt``
  (cached), so the step is exact for any stiffness and as cheap as a discrete filter;
- steady state (``steady_state=True``, Tomera (2014) eqs. 33-35): ``L`` of
  :func:`~shipgym.observers.design.lqe`, ``x_hat_dot = (A - L C) x_hat + L y`` solved exactly;
  ``P`` follows the closed-loop Lyapunov equation (so it stays ``P_inf`` while measuring and
  grows during dropouts).

Why first-order hold: a ship at constant speed ``V`` produces a ramp; holding ``y_k`` (or
``y_{k-1}``) over the interval biases the position estimate by about ``V dt / 2`` (0.1 m at
0.2 m/s, as large as the DGPS noise), whereas the continuous filter, a type-2 loop, tracks the
ramp of the first-order hold without error. The measurement intensity is ``R_c = R T`` (Tomera 2011
eq. 35), ``R`` the sample variance. Without a previous accepted sample (after a reset, a
dropout or a rejection) and after a forced acceptance (see below; a jump has no ramp) the new
sample is held over the whole interval instead, the averaged-measurement reading of Tomera (2011)
eq. 32 (starting the line from the filter's own estimate would feed the filter its own
output as if it were a measurement and make ``P`` optimistic). ``P`` is the
continuous filter's covariance: for the sampled data at ``T = 1 s`` and the designs here
(bandwidths 0.32-0.43 rad/s) it is 5-8 % conservative (mean NEES 0.92-0.95 of its 6 dof,
NIS 0.94-0.96 of 3); it is exact as ``T -> 0``. Compared with the discrete filter of the same
design the continuous filter lags a little more (about 10 % more velocity error under a
constant acceleration): the last sample enters only through the end of the hold. A measurement at
the same time as the previous call (``dt = 0``) only becomes the next hold's start.

Without a measurement (``z=None``) or for a rejected one, every filter coasts: ``x = F x``,
``P = F P F^T + Q_k`` (the continuous filter with the exact ``Q_k``).

Outliers: :class:`~shipgym.observers.base.OutlierGate` (99.99 %, at most 5 rejections in a
row). A forced acceptance also inflates the position variances of the prior by the squared
innovation, so the time-varying filters re-anchor on a real jump within one sample; the
constant-gain filters re-converge at their bandwidth.

Presets (:data:`~shipgym.observers.base.OBSERVERS`)
---------------------------------------------------
- ``tomera-dkf``: :data:`~shipgym.observers.design.TOMERA_DKF`, constant gain (eq. 30);
- ``tomera-kbf``: :data:`~shipgym.observers.design.TOMERA_KBF`, steady state (eqs. 33-35);
- ``dkf``: :data:`~shipgym.observers.design.DKF_DESIGN`, time-varying covariance;
- ``kbf``: :data:`~shipgym.observers.design.KBF_DESIGN`, time-varying Riccati.

Overrides: any :class:`~shipgym.observers.design.KalmanDesign` field (``G``, ``Q``, ``R``,
``T``, ``discretisation``), ``position_variance`` / ``heading_variance`` (set ``R``),
and the constructor's keywords (``gate_probability``, ``max_rejections``,
``initial_velocity_std``, ``constant_gain`` / ``steady_state``); the name is the preset's.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from ..dynamics import wrap_angle
from .base import (
    OBSERVERS,
    Estimate,
    Observer,
    OutlierGate,
    StepInfo,
    as_pose,
    as_tau,
    make_observer,
    no_measurement,
    register_observer,
)
from .design import (
    DKF_DESIGN,
    KBF_DESIGN,
    TOMERA_DKF,
    TOMERA_KBF,
    KalmanDesign,
    discretise,
    double_integrator,
)

__all__ = [
    "OBSERVERS",
    "DiscreteKalmanFilter",
    "KalmanBucyFilter",
    "make_observer",
]

_A, _C = double_integrator()
_EYE2 = np.eye(2)
_CACHE_SIZE = 16
_SHARED_CACHE_SIZE = 512
_SHARED: dict[tuple[Any, ...], Any] = {}
"""Design- and interval-dependent matrices shared by all filters (designs are frozen)."""
DEFAULT_INITIAL_VELOCITY_STD = (0.3, 0.3, math.radians(2.0))
"""Default initial std of ``[x_dot, y_dot, psi_dot]`` (m/s, m/s, rad/s) when ``P0`` is None:
the speeds of the harbour manoeuvre (up to 0.2 m/s, 1 deg/s) with a margin."""


def _dt_key(dt: float) -> float:
    return round(dt, 12)


def _inv2(M: NDArray[np.float64]) -> NDArray[np.float64]:
    """Inverses of a stack of 2x2 matrices, (k, 2, 2)."""
    if M.shape == (3, 2, 2):  # the three DOFs in plain floats: the same operations
        out3 = []
        try:
            for (a, b), (c, d) in M.tolist():
                det = a * d - b * c
                out3.append([[d / det, -b / det], [-c / det, a / det]])
        except ZeroDivisionError:  # a singular block: the array form's inf / nan
            pass
        else:
            return np.array(out3)
    a, b, c, d = M[:, 0, 0], M[:, 0, 1], M[:, 1, 0], M[:, 1, 1]
    det = a * d - b * c
    out = np.empty_like(M)
    out[:, 0, 0] = d / det
    out[:, 0, 1] = -b / det
    out[:, 1, 0] = -c / det
    out[:, 1, 1] = a / det
    return out


def _sym(P: NDArray[np.float64]) -> NDArray[np.float64]:
    return 0.5 * (P + P.transpose(0, 2, 1))


class _DoubleIntegratorFilter(Observer):
    """Shared state, reset, gate, step skeleton and estimate of the per-DOF filters."""

    def __init__(
        self,
        design: KalmanDesign | Mapping[str, Any],
        *,
        name: str,
        gate_probability: float | None = 0.9999,
        max_rejections: int = 5,
        initial_velocity_std: ArrayLike = DEFAULT_INITIAL_VELOCITY_STD,
    ) -> None:
        if isinstance(design, Mapping):
            design = KalmanDesign.from_dict(dict(design))
        if not isinstance(design, KalmanDesign):
            raise ValueError(f"design must be a KalmanDesign or a mapping, got {design!r}")
        std = np.asarray(initial_velocity_std, dtype=float)
        if std.shape != (3,) or not np.isfinite(std).all() or (std < 0).any():
            raise ValueError(
                "initial_velocity_std must be 3 finite values >= 0 (m/s, m/s, rad/s), "
                f"got {initial_velocity_std!r}"
            )
        self.name = str(name)
        self.design = design
        self.gate = OutlierGate(gate_probability, dof=3, max_rejections=max_rejections)
        self.initial_velocity_std = std
        self._R = design.variance()
        self._W = design.intensity()
        self._cache: dict[tuple[str, float], Any] = {}
        self._t: float | None = None
        self._s = np.zeros((3, 2))  # per DOF [velocity, position] (Tomera 2011 eq. 59)
        self._P = np.zeros((3, 2, 2))

    # ---- interface ---------------------------------------------------------------------------
    def reset(
        self,
        t0: float,
        eta0: ArrayLike,
        *,
        nu0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
    ) -> None:
        """Start at ``t0`` from the pose ``eta0`` (and body velocity ``nu0``, default rest).

        Args:
            t0: initial time (s).
            eta0: ``[x, y, psi]`` (m, m, rad); the heading's branch is kept (continuous
                estimate from there on).
            nu0: ``[u, v, r]`` (m/s, m/s, rad/s), ``None`` = 0.
            P0: (6, 6) covariance of ``[x, y, psi, x_dot, y_dot, psi_dot]``; cross-DOF terms
                are ignored. ``None``: the measurement variances ``R`` for the pose and
                ``initial_velocity_std**2`` for the rates.

        Raises:
            ValueError: non-finite or mis-shaped arguments, ``P0`` not symmetric ``>= 0``.
        """
        t0 = float(t0)
        if not math.isfinite(t0):
            raise ValueError(f"t0 must be finite, got {t0!r}")
        eta = as_pose(eta0, "eta0")
        if nu0 is None:
            eta_dot = np.zeros(3)
        else:
            nu = as_pose(nu0, "nu0", "[u, v, r] (m/s, m/s, rad/s)")
            c, s = math.cos(eta[2]), math.sin(eta[2])
            eta_dot = np.array([c * nu[0] - s * nu[1], s * nu[0] + c * nu[1], nu[2]])
        Pb = np.zeros((3, 2, 2))
        if P0 is None:
            Pb[:, 0, 0] = self.initial_velocity_std**2
            Pb[:, 1, 1] = self._R
        else:
            P6 = np.asarray(P0, dtype=float)
            if P6.shape != (6, 6) or not np.isfinite(P6).all():
                raise ValueError(f"P0 must be a finite 6x6 matrix, got shape {P6.shape}")
            if not np.allclose(P6, P6.T, rtol=1e-9, atol=1e-12):
                raise ValueError("P0 must be symmetric")
            if np.linalg.eigvalsh(0.5 * (P6 + P6.T))[0] < -1e-12 * max(np.abs(P6).max(), 1e-300):
                raise ValueError("P0 must be positive semi-definite")
            for i in range(3):
                Pb[i] = P6[np.ix_((3 + i, i), (3 + i, i))]
            Pb = _sym(Pb)
        self._s = np.stack([eta_dot, eta], axis=1)
        self._P = Pb
        self._t = t0
        self.gate.reset()
        self._after_reset()

    def step(self, t: float, z: ArrayLike | None, tau: ArrayLike | None = None) -> StepInfo:
        """Propagate to ``t`` and update with the measured pose ``z`` (``None``: coast).

        Args:
            t: time now (s), not earlier than the previous call.
            z: measured ``[x, y, psi]`` (m, m, rad; heading in any branch) or ``None``.
            tau: body thrust ``[X, Y, N]`` (N, N, N m); checked, not used (kinematic model).

        Returns:
            :class:`~shipgym.observers.base.StepInfo` (innovation, NIS, gate decision).

        Raises:
            RuntimeError: :meth:`reset` was not called.
            ValueError: time going backwards, ``z`` or ``tau`` not 3 finite values.
        """
        if self._t is None:
            raise RuntimeError(f"{self.name}: call reset(t0, eta0) before step()")
        t = float(t)
        dt = t - self._t
        if not dt >= 0.0:
            if dt >= -1e-9:  # rounding of the caller's clock
                dt, t = 0.0, self._t
            else:
                raise ValueError(
                    f"{self.name}: time must not go backwards (previous {self._t}, got {t!r})"
                )
        as_tau(tau)
        if z is None:
            if dt > 0.0:
                self._s, self._P = self._prior(dt)
            self._after_coast()
            self._t = t
            return no_measurement()
        z = as_pose(z)
        s_bar, P_bar = self._prior(dt) if dt > 0.0 else (self._s, self._P)
        innov = z - s_bar[:, 1]
        innov[2] = wrap_angle(float(innov[2]))
        S = P_bar[:, 1, 1] + self._R
        nis = float(np.dot(innov * innov, 1.0 / S))
        decision = self.gate.check(nis)
        if decision == "reject":
            self._s, self._P = s_bar, P_bar
            self._after_coast()
            self._t = t
            return StepInfo(innov, nis, True)
        forced = decision == "force"
        self._correct(dt, s_bar, P_bar, innov, forced)
        self._t = t
        return StepInfo(innov, nis, False, forced)

    def estimate(self) -> Estimate:
        """The current estimate (copies); ``P`` in ``[x, y, psi, x_dot, y_dot, psi_dot]``."""
        if self._t is None:
            raise RuntimeError(f"{self.name}: call reset(t0, eta0) before estimate()")
        (xd, x), (yd, y), (psid, psi) = self._s.tolist()  # per DOF [velocity, position]
        eta = np.array([x, y, psi])
        c, s = math.cos(psi), math.sin(psi)
        u = c * xd + s * yd
        v = -s * xd + c * yd
        nu = np.array([u, v, psid])
        P6 = self.P
        J = np.array([[0.0, 0.0, v, c, s, 0.0], [0.0, 0.0, -u, -s, c, 0.0],
                      [0.0, 0.0, 0.0, 0.0, 0.0, 1.0]])  # fmt: skip
        P_nu = J @ P6 @ J.T
        return Estimate(
            t=self._t,
            eta=eta,
            nu=nu,
            P=P6,
            P_eta=P6[:3, :3].copy(),
            P_nu=0.5 * (P_nu + P_nu.T),
        )

    # ---- extras ------------------------------------------------------------------------------
    @property
    def x(self) -> NDArray[np.float64]:
        """A copy of the state ``[x, y, psi, x_dot, y_dot, psi_dot]`` (NED, heading continuous)."""
        return np.concatenate([self._s[:, 1], self._s[:, 0]])

    @property
    def P(self) -> NDArray[np.float64]:
        """A copy of the (6, 6) covariance of :attr:`x`."""
        # per DOF [[vel-vel, vel-pos], [pos-vel, pos-pos]] (the upper off-diagonal is used)
        ((xv, xc), (_, xx)), ((yv, yc), (_, yy)), ((pv, pc), (_, pp)) = self._P.tolist()
        return np.array(
            [
                [xx, 0.0, 0.0, xc, 0.0, 0.0],
                [0.0, yy, 0.0, 0.0, yc, 0.0],
                [0.0, 0.0, pp, 0.0, 0.0, pc],
                [xc, 0.0, 0.0, xv, 0.0, 0.0],
                [0.0, yc, 0.0, 0.0, yv, 0.0],
                [0.0, 0.0, pc, 0.0, 0.0, pv],
            ]
        )

    @property
    def t(self) -> float | None:
        """Time of the current estimate (s), ``None`` before :meth:`reset`."""
        return self._t

    # ---- hooks -------------------------------------------------------------------------------
    def _after_reset(self) -> None:
        """Clear subclass state at reset."""

    def _after_coast(self) -> None:
        """Called after a step without an accepted measurement."""

    def _prior(self, dt: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Open-loop prediction ``(F s, F P F^T + Q_k)`` over ``dt`` > 0."""
        Q = self._cached("Q", dt, lambda: self._process_noise(dt)).tolist()
        # per DOF in plain floats, the same operations as the array form
        s_bar = [[v, p + dt * v] for v, p in self._s.tolist()]
        dt2, dtdt = 2.0 * dt, dt * dt
        P_bar = []
        for ((a, b), (_, d)), ((q00, q01), (q10, q11)) in zip(self._P.tolist(), Q, strict=True):
            c = b + dt * a  # the prior's off-diagonal (the upper one of P)
            P_bar.append([[a + q00, c + q01], [c + q10, d + dt2 * b + dtdt * a + q11]])
        return np.array(s_bar), np.array(P_bar)

    def _process_noise(self, dt: float) -> NDArray[np.float64]:
        return np.stack([discretise(_A, W, dt, method="exact")[1] for W in self._W])

    def _cached(self, kind: str, dt: float, make: Callable[[], Any]) -> Any:
        """Matrices for ``(kind, dt)``: per instance, then shared by filters of one design."""
        key = (kind, _dt_key(dt))
        val = self._cache.get(key)
        if val is None:
            shared_key = (type(self).__name__, self.design, *key)
            val = _SHARED.get(shared_key)
            if val is None:
                val = make()
                for a in val if isinstance(val, tuple) else (val,):
                    a.setflags(write=False)
                if len(_SHARED) >= _SHARED_CACHE_SIZE:
                    _SHARED.clear()
                _SHARED[shared_key] = val
            if len(self._cache) >= _CACHE_SIZE:
                self._cache.clear()
            self._cache[key] = val
        return val

    def _correct(
        self,
        dt: float,
        s_bar: NDArray[np.float64],
        P_bar: NDArray[np.float64],
        innov: NDArray[np.float64],
        forced: bool,
    ) -> None:
        raise NotImplementedError


class DiscreteKalmanFilter(_DoubleIntegratorFilter):
    """Discrete Kalman filter per DOF on the double integrator (Tomera 2014 Table 3).

    Args:
        design: :class:`~shipgym.observers.design.KalmanDesign` (or a mapping of its fields);
            default the Blue Lady's tuned :data:`~shipgym.observers.design.DKF_DESIGN` (for
            another vessel: ``make_observer("dkf", vessel)``).
        constant_gain: use the steady-state filter-form gain of
            :func:`~shipgym.observers.design.dlqe` at the design period ``T`` (Tomera 2014
            eq. 30) instead of the time-varying gain of Table 3.
        name: the observer's name.
        gate_probability: NIS gate probability (``None``: no gate), see
            :class:`~shipgym.observers.base.OutlierGate`.
        max_rejections: most measurements rejected in a row.
        initial_velocity_std: default initial std of ``[x_dot, y_dot, psi_dot]``
            (m/s, m/s, rad/s).
    """

    def __init__(
        self,
        design: KalmanDesign | Mapping[str, Any] = DKF_DESIGN,
        *,
        constant_gain: bool = False,
        name: str = "dkf",
        gate_probability: float | None = 0.9999,
        max_rejections: int = 5,
        initial_velocity_std: ArrayLike = DEFAULT_INITIAL_VELOCITY_STD,
    ) -> None:
        super().__init__(
            design,
            name=name,
            gate_probability=gate_probability,
            max_rejections=max_rejections,
            initial_velocity_std=initial_velocity_std,
        )
        self.constant_gain = bool(constant_gain)
        self.last_gain: NDArray[np.float64] | None = None
        """Gain of the last update, (3, 2), seed order ``[velocity, position]`` per DOF."""

    @property
    def steady_state_gain(self) -> NDArray[np.float64]:
        """Steady-state filter-form gain at the design period ``T``, (3, 2), seed order
        ``[velocity, position]`` per DOF (Tomera 2014 eq. 30)."""
        return self.design.dkf_gains(form="filter")[0]

    def _process_noise(self, dt: float) -> NDArray[np.float64]:
        return self.design.sampled(dt)[1]

    def _correct(
        self,
        dt: float,
        s_bar: NDArray[np.float64],
        P_bar: NDArray[np.float64],
        innov: NDArray[np.float64],
        forced: bool,
    ) -> None:
        if forced:
            P_bar = P_bar.copy()
            P_bar[:, 1, 1] += innov * innov
        R = self._R
        if self.constant_gain:
            K = self._cached("K", 0.0, lambda: self.design.dkf_gains(form="filter")[0])
        else:
            K = P_bar[:, :, 1] / (P_bar[:, 1, 1] + R)[:, None]  # Tomera (2011) eq. 23
        self.last_gain = K
        self._s = s_bar + K * innov[:, None]  # Tomera (2011) eq. 14
        IKH = np.broadcast_to(_EYE2, (3, 2, 2)).copy()
        IKH[:, :, 1] -= K
        KK = K[:, :, None] * K[:, None, :]
        self._P = _sym(IKH @ P_bar @ IKH.transpose(0, 2, 1) + R[:, None, None] * KK)  # Joseph


class KalmanBucyFilter(_DoubleIntegratorFilter):
    """Continuous Kalman-Bucy filter per DOF, sampled-data implementation (Tomera 2014 Table 4).

    Args:
        design: :class:`~shipgym.observers.design.KalmanDesign` (or a mapping of its fields);
            the continuous measurement intensity is ``R_c = R T``; default the Blue Lady's
            tuned :data:`~shipgym.observers.design.KBF_DESIGN` (for another vessel:
            ``make_observer("kbf", vessel)``).
        steady_state: use the constant gain of :func:`~shipgym.observers.design.lqe`
            (Tomera 2014 eqs. 33-35) instead of integrating the Riccati ODE.
        name: the observer's name.
        gate_probability: NIS gate probability (``None``: no gate).
        max_rejections: most measurements rejected in a row.
        initial_velocity_std: default initial std of ``[x_dot, y_dot, psi_dot]``
            (m/s, m/s, rad/s).
    """

    def __init__(
        self,
        design: KalmanDesign | Mapping[str, Any] = KBF_DESIGN,
        *,
        steady_state: bool = False,
        name: str = "kbf",
        gate_probability: float | None = 0.9999,
        max_rejections: int = 5,
        initial_velocity_std: ArrayLike = DEFAULT_INITIAL_VELOCITY_STD,
    ) -> None:
        super().__init__(
            design,
            name=name,
            gate_probability=gate_probability,
            max_rejections=max_rejections,
            initial_velocity_std=initial_velocity_std,
        )
        self.steady_state = bool(steady_state)
        self._Rc = self._R * self.design.T
        self._L = self._cached("L", 0.0, lambda: self.design.kbf_gains()[0])
        self._y_prev: NDArray[np.float64] | None = None

    @property
    def steady_state_gain(self) -> NDArray[np.float64]:
        """Steady-state gain ``L = P C^T R_c^-1``, (3, 2), seed order ``[velocity, position]``
        per DOF (Tomera 2014 eq. 35)."""
        return self._L.copy()

    def _after_reset(self) -> None:
        self._y_prev = None

    def _after_coast(self) -> None:
        self._y_prev = None

    def _correct(
        self,
        dt: float,
        s_bar: NDArray[np.float64],
        P_bar: NDArray[np.float64],
        innov: NDArray[np.float64],
        forced: bool,
    ) -> None:
        y1 = s_bar[:, 1] + innov  # the sample, unwrapped next to the prediction
        if dt <= 0.0:
            self._y_prev = y1
            return
        s0, P0 = self._s, self._P
        if forced:
            P0 = P0.copy()
            P0[:, 1, 1] += innov * innov
        y0 = y1 if (forced or self._y_prev is None) else self._y_prev
        slope = (y1 - y0) / dt
        if self.steady_state:
            Phi, B1, B2, Qcl = self._cached("ss", dt, lambda: self._steady_blocks(dt))
            self._s = (Phi @ s0[:, :, None])[:, :, 0] + B1 * y0[:, None] + B2 * slope[:, None]
            self._P = _sym(Phi @ P0 @ Phi.transpose(0, 2, 1) + Qcl)
        else:
            E11, E21, I1r, I2r, B = self._cached("tvb", dt, lambda: self._tv_blocks(dt))
            # the products with P0 in one matmul: rows [E12; E22; I1[3, 2:]; I2[3, 2:]] @ P0
            EP = B @ P0
            X = E11 + EP[:, 0:2]
            Y = E21 + EP[:, 2:4]
            J0 = I1r + EP[:, 4]  # row "position" of int Y
            J1 = I2r + EP[:, 5]  # row "position" of int s Y
            Xi = _inv2(X)
            rhs = s0 + (J0 * y0[:, None] + J1 * slope[:, None]) / self._Rc[:, None]
            # X^-T rhs and Y X^-1 in one matmul: rows [rhs; Y] @ X^-1
            RY = np.concatenate([rhs[:, None, :], Y], axis=1) @ Xi
            self._s = RY[:, 0, :]
            self._P = _sym(RY[:, 1:, :])
        self._y_prev = y1

    def _steady_blocks(self, dt: float) -> tuple[NDArray[np.float64], ...]:
        """``exp(A_cl dt)``, the first-order-hold input matrices and the Lyapunov increment."""
        Phi, B1, B2, Qcl = [], [], [], []
        for i in range(3):
            L = self._L[i][:, None]
            Acl = _A - L @ _C
            M = np.zeros((4, 4))
            M[:2, :2] = Acl
            M[:2, 2:3] = L
            M[2, 3] = 1.0
            Ed = scipy.linalg.expm(M * dt)
            Phi.append(Ed[:2, :2])
            B1.append(Ed[:2, 2])  # int_0^dt exp(Acl (dt - s)) L ds
            B2.append(Ed[:2, 3])  # int_0^dt exp(Acl (dt - s)) L s ds
            Wcl = self._W[i] + self._Rc[i] * (L @ L.T)
            Qcl.append(discretise(Acl, Wcl, dt, method="exact")[1])
        return np.stack(Phi), np.stack(B1), np.stack(B2), np.stack(Qcl)

    def _tv_blocks(self, dt: float) -> tuple[NDArray[np.float64], ...]:
        """The blocks of :meth:`_hamiltonian_blocks` the update uses: ``E11``, ``E21`` and the
        position rows of the integrals' left blocks (contiguous), and their right blocks
        stacked, ``[E12; E22; I1[3, :2]; I2[3, :2]]`` (3, 6, 2), for one product with P."""
        E, I1, I2 = self._cached("tv", dt, lambda: self._hamiltonian_blocks(dt))
        stacked = np.concatenate([E[:, :, 2:], I1[:, 3:4, 2:], I2[:, 3:4, 2:]], axis=1)
        return (E[:, :2, :2].copy(), E[:, 2:, :2].copy(), I1[:, 3, :2].copy(),
                I2[:, 3, :2].copy(), stacked)  # fmt: skip

    def _hamiltonian_blocks(self, dt: float) -> tuple[NDArray[np.float64], ...]:
        """``exp(H dt)``, ``int_0^dt exp(H s) ds`` and ``int_0^dt s exp(H s) ds`` per DOF."""
        E, I1, I2 = [], [], []
        for i in range(3):
            Ham = np.zeros((4, 4))
            Ham[:2, :2] = -_A.T
            Ham[:2, 2:] = _C.T @ _C / self._Rc[i]
            Ham[2:, :2] = self._W[i]
            Ham[2:, 2:] = _A
            M = np.zeros((12, 12))
            M[:4, :4] = Ham
            M[:4, 4:8] = np.eye(4)
            M[4:8, 8:12] = np.eye(4)
            Ed = scipy.linalg.expm(M * dt)
            E.append(Ed[:4, :4])
            I1.append(Ed[:4, 4:8])
            I2.append(dt * Ed[:4, 4:8] - Ed[:4, 8:12])
        return np.stack(E), np.stack(I1), np.stack(I2)


# --------------------------------------------------------------------------------------------
# Presets and registry
# --------------------------------------------------------------------------------------------

_DESIGN_KEYS = tuple(f.name for f in dataclasses.fields(KalmanDesign) if f.name != "model")


def _factory(
    cls: type[_DoubleIntegratorFilter], design: KalmanDesign, name: str, **fixed: Any
) -> Callable[..., Observer]:
    ctor_keys = ("gate_probability", "max_rejections", "initial_velocity_std") + tuple(fixed)

    def make(**overrides: Any) -> Observer:
        design_changes = {k: overrides.pop(k) for k in list(overrides) if k in _DESIGN_KEYS}
        pv = overrides.pop("position_variance", None)
        hv = overrides.pop("heading_variance", None)
        if pv is not None or hv is not None:
            R = list(design_changes.get("R", design.R))
            if len(R) != 3:
                R = [float(R[0])] * 3
            if pv is not None:
                R[0] = R[1] = float(pv)
            if hv is not None:
                R[2] = float(hv)
            design_changes["R"] = tuple(R)
        unknown = sorted(set(overrides) - set(ctor_keys))
        if unknown:
            valid = sorted(
                set(_DESIGN_KEYS) | set(ctor_keys) | {"position_variance", "heading_variance"}
            )
            raise ValueError(
                f"unknown option(s) {unknown} for observer {name!r}; valid: {', '.join(valid)}"
            )
        kwargs = {"name": name, **fixed, **overrides}
        d = dataclasses.replace(design, **design_changes) if design_changes else design
        return cls(d, **kwargs)

    make.__doc__ = f"A new {cls.__name__} preset {name!r} (keyword overrides, see module doc)."
    return make


register_observer(
    "tomera-dkf", _factory(DiscreteKalmanFilter, TOMERA_DKF, "tomera-dkf", constant_gain=True)
)
register_observer(
    "tomera-kbf", _factory(KalmanBucyFilter, TOMERA_KBF, "tomera-kbf", steady_state=True)
)


def vessel_noise(vessel: Any) -> dict[str, Any]:
    """The tuned presets' white-noise acceleration intensities for a vessel (its
    ``[observer]`` values ``accel_psd_xy`` m^2/s^3, ``accel_psd_psi`` rad^2/s^3)."""
    q_xy = float(vessel.observer["accel_psd_xy"])
    q_psi = float(vessel.observer["accel_psd_psi"])
    return {"Q": (((q_xy,),), ((q_xy,),), ((q_psi,),))}


register_observer(
    "dkf", _factory(DiscreteKalmanFilter, DKF_DESIGN, "dkf", constant_gain=False), vessel_noise
)
register_observer(
    "kbf", _factory(KalmanBucyFilter, KBF_DESIGN, "kbf", steady_state=False), vessel_noise
)
