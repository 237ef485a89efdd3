r"""Wave-filtering Kalman filters of Al-Takie (1982): 14-state, reduced, semi-constant, EKF.

Discrete KF ``x- = Phi x + Delta u``, ``K = P- H^T (H P- H^T + R)^-1``, Joseph update
(Al-Takie 1982 eqs. 5.4-5.12, App. 3).

The filters separate the slow (LF) ship motion from the first-order wave (HF) motion in the
position and heading measurements, on the combined model of
:func:`~shipgym.dynamics.altakie.wave_filter_model` (per unit, ``x = [v, y, r, psi, f_Y, f_N,
HF sway(4), HF yaw(4)]``, ``z = [x2 + x9, x4 + x13] + v``).

Public names: ``BIAS_Q``, ``NOISE_DESIGNS``, ``DiscreteKF``, ``ReducedKF``, ``WaveFilterEKF``,
``WaveFilterObserver``, ``gain_settling_steps``, ``hf_gain_for_std``.

Design notes: docs/design/observers.wavefilter.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.altakie import (
    WaveFilterModel,
    discretise,
    hf_alpha,
    hf_block,
    lf_model_from_vessel,
    saturated_lf_matrix,
    saturated_lf_step,
    surge_model_from_vessel,
    wave_filter_model,
)
from shipgym.dynamics.perunit import PerUnit

from .base import Estimate, Observer, StepInfo, as_pose, as_tau, no_measurement, register_observer

__all__ = [
    "BIAS_Q",
    "NOISE_DESIGNS",
    "DiscreteKF",
    "ReducedKF",
    "WaveFilterEKF",
    "WaveFilterObserver",
    "gain_settling_steps",
    "hf_gain_for_std",
]

Array = NDArray[np.float64]


class DiscreteKF:
    """Time-varying discrete Kalman filter with the Joseph update (Al-Takie 1982 App. 3).

    Args:
        A, B, G, H: continuous model, (n, n), (n, m), (n, p), (q, n) (per-unit time).
        Q: process-noise intensity of ``w``, (p, p); ``Q_D = Q / dt``.
        R: measurement-noise covariance, (q, q).
        dt: sampling interval (per-unit time).
        freeze_after: ``None`` (time-varying) or the number of steps after which the gain is
            frozen (the semi-constant-gain filter).

    Attributes:
        x, P: state estimate and covariance after the last step.
        K: the last gain (n, q).
        steps: number of steps since :meth:`reset`.
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
    ) -> None:
        self.A = np.asarray(A, dtype=float)
        self.B = np.asarray(B, dtype=float)
        self.G = np.asarray(G, dtype=float)
        self.H = np.asarray(H, dtype=float)
        self.Q = np.asarray(Q, dtype=float)
        self.R = np.asarray(R, dtype=float)
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
        self.Phi, self.Delta, self.Gamma = discretise(self.A, self.B, self.G, self.dt)
        self.W = self.Gamma @ (self.Q / self.dt) @ self.Gamma.T
        self.W = 0.5 * (self.W + self.W.T)
        self.reset()

    @property
    def n(self) -> int:
        """Number of states."""
        return int(self.A.shape[0])

    @property
    def frozen(self) -> bool:
        """Whether the gain is frozen (semi-constant filter past ``freeze_after`` steps)."""
        return self.freeze_after is not None and self.steps >= self.freeze_after

    def reset(self, x0: ArrayLike | None = None, P0: ArrayLike | None = None) -> None:
        """Start from ``x0`` (default 0) with covariance ``P0`` (default 0, as printed)."""
        n = self.n
        self.x = np.zeros(n) if x0 is None else np.array(x0, dtype=float)
        self.P = np.zeros((n, n)) if P0 is None else np.array(P0, dtype=float)
        self.K = np.zeros((n, self.H.shape[0]))
        self.steps = 0
        self.innovation = np.full(self.H.shape[0], np.nan)
        self.nis: float | None = None

    def predict(self, u: ArrayLike) -> None:
        """``x- = Phi x + Delta u`` and, unless frozen, ``P- = Phi P Phi^T + W``."""
        self.x = self.Phi @ self.x + self.Delta @ np.asarray(u, dtype=float)
        if not self.frozen:
            self.P = self.Phi @ self.P @ self.Phi.T + self.W

    def update(self, z: ArrayLike | None, wrap: Callable[[Array], Array] | None = None) -> None:
        """Measurement update with ``z`` (``None``: no measurement, the prediction stands)."""
        self.steps += 1
        if z is None:
            self.innovation = np.full(self.H.shape[0], np.nan)
            self.nis = None
            return
        nu = np.asarray(z, dtype=float) - self.H @ self.x
        if wrap is not None:
            nu = wrap(nu)
        if not self.frozen:
            S = self.H @ self.P @ self.H.T + self.R
            self.K = np.linalg.solve(S, self.H @ self.P).T
            IKH = np.eye(self.n) - self.K @ self.H
            self.P = IKH @ self.P @ IKH.T + self.K @ self.R @ self.K.T
            self._S = S
        else:
            S = getattr(self, "_S", self.H @ self.P @ self.H.T + self.R)
        self.x = self.x + self.K @ nu
        self.innovation = nu
        self.nis = float(nu @ np.linalg.solve(S, nu))

    def step(self, z: ArrayLike | None, u: ArrayLike) -> None:
        """One sampling interval: predict with ``u`` (held over it), then update with ``z``."""
        self.predict(u)
        self.update(z)


class ReducedKF(DiscreteKF):
    """The reduced-order filter of Al-Takie (1982) 6.2 on a 14-state model: 12 states.

    The thruster states (indices 4, 5 of the LF model) are measured exactly; the filter keeps
    ``[v, y, r, psi]`` and the 8 HF states. :meth:`step` takes the thruster states at the
    start and at the end of the interval (``f0``, ``f1``); with the first-order lag they fix
    the demand ``u = Delta_f^-1 (f1 - Phi_f f0)`` over the interval, so the prediction is the
    14-state filter's, exactly.

    Args:
        model: the 14-state :class:`~shipgym.dynamics.altakie.WaveFilterModel`.
        dt, freeze_after: as :class:`DiscreteKF`.
    """

    THRUST = np.r_[4:6]

    def __init__(self, model: WaveFilterModel, dt: float, freeze_after: int | None = None) -> None:
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
        )
        # exact: the kept states see the thruster states through the 14-state Phi, Delta
        self.Phi = Phi[np.ix_(k, k)]
        self._Phi_kf = Phi[np.ix_(k, f)]
        self._Delta_k = Delta[k]
        self._Phi_f = Phi[np.ix_(f, f)]
        self._Delta_f = Delta[f]

    def step_thrust(self, z: ArrayLike | None, f0: ArrayLike, f1: ArrayLike) -> None:
        """One interval with the measured thruster states at its start ``f0`` and end ``f1``."""
        f0_ = np.asarray(f0, dtype=float)
        u = np.linalg.solve(self._Delta_f, np.asarray(f1, dtype=float) - self._Phi_f @ f0_)
        self.x = self.Phi @ self.x + self._Phi_kf @ f0_ + self._Delta_k @ u
        if not self.frozen:
            self.P = self.Phi @ self.P @ self.Phi.T + self.W
        self.update(z)

    def step(self, z: ArrayLike | None, u: ArrayLike) -> None:  # noqa: D102
        raise TypeError("ReducedKF takes the measured thruster states: use step_thrust(z, f0, f1)")


class WaveFilterEKF(DiscreteKF):
    """The extended filter of Al-Takie (1982) ch. 7 with saturating thrusters.

    The LF model's thruster columns act through ``psi(x5)``, ``psi(x6)``
    (:func:`~shipgym.dynamics.altakie.saturation`); the prediction integrates that nonlinear
    model over the interval (RK4, ``substeps``); ``Phi`` (and ``W``) are re-linearised at the
    estimate every ``relinearise_every`` steps.

    Args:
        model: the 14-state model.
        dt: sampling interval (p.u.).
        F1, F2: saturation limit (p.u.) and slope factor (``F1 F2 = 1``: slope 1 at 0).
        relinearise_every: steps between re-linearisations (2 printed).
        substeps: RK4 steps per interval.
    """

    def __init__(
        self,
        model: WaveFilterModel,
        dt: float,
        F1: float = 0.02,
        F2: float = 50.0,
        relinearise_every: int = 2,
        substeps: int = 4,
    ) -> None:
        super().__init__(model.A, model.B, model.G, model.H, model.Q, model.R, dt)
        if isinstance(relinearise_every, bool) or int(relinearise_every) < 1:
            raise ValueError(f"relinearise_every must be >= 1, got {relinearise_every!r}")
        self.F1, self.F2 = float(F1), float(F2)
        self.relinearise_every = int(relinearise_every)
        self.substeps = int(substeps)
        # the LF block is nonlinear; the HF blocks are linear and fixed (exact transition)
        self._A_rest = model.A[:6, 6:]  # the LF block's input from the other states (bias)
        self._B_lf = model.B[:6]
        self._G_lf = model.G[:6]
        self.relinearisations = 0

    def jacobian(self, x: ArrayLike) -> Array:
        """``A(x) = df/dx``: the thruster columns times ``psi'(x5)``, ``psi'(x6)``."""
        x_ = np.asarray(x, dtype=float)
        F = self.A.copy()
        F[:6, :6] = saturated_lf_matrix(self.A[:6, :6], x_[4:6], self.F1, self.F2)
        return F

    def predict(self, u: ArrayLike) -> None:
        u_ = np.asarray(u, dtype=float)
        if self.steps % self.relinearise_every == 0:
            # only the LF block depends on the estimate (the HF blocks are decoupled from it)
            F = self.jacobian(self.x)[:6, :6]
            Phi_l, _, Gam_l = discretise(F, self._B_lf, self._G_lf, self.dt)
            self.Phi[:6, :6] = Phi_l
            self.Gamma[:6] = Gam_l
            W = self.Gamma @ (self.Q / self.dt) @ self.Gamma.T
            self.W = 0.5 * (W + W.T)
            self.relinearisations += 1
        hf = self.Phi[6:, 6:] @ self.x[6:]
        u_in = self._B_lf @ u_ + self._A_rest @ self.x[6:]  # held over the interval
        x = saturated_lf_step(
            self.x[:6], u_in, self.A, self.dt, self.F1, self.F2, substeps=self.substeps
        )
        self.x = np.concatenate([x, hf])
        self.P = self.Phi @ self.P @ self.Phi.T + self.W


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
#:   ``q_x`` = the sway one: the filter of the printed gains; on the simulated vessels its LF
#:   estimate is nearly as fast as the wave band (velocity random walk 0.36 m/s per 270 s for
#:   Star Hercules), so it passes measurement noise and wave motion to the thrusters (wave-band
#:   thrust ratio 2.7-4.1, as LQ on raw measurements, 3.9-4.0; Wimpey Sealab, Beaufort 5, 8).
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


class WaveFilterObserver(Observer):
    """An Al-Takie (1982) wave filter for a simulated vessel (SI, NED; the presets ``alt-*``).

    Args:
        vessel: the :class:`~shipgym.dynamics.vessel.Vessel` (its design model and lags).
        kind: ``"kf14"`` (time-varying 14-state), ``"semiconstant"`` (frozen at
            ``freeze_time``), ``"kf12"`` (reduced: takes the applied thrust as measured thruster
            states), ``"ekf"`` (saturating thrusters, ``F1`` the saturation in p.u.) or
            ``"lf6"`` (the LF model only: no wave model) or ``"raw"`` (the measured pose as the
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
    """

    model_based = True  # the LF model and the thrust drive its prediction
    thrust_input = "command"

    def __init__(
        self,
        vessel: Any = None,
        kind: str = "kf14",
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
        if q_l is None:
            q_l = NOISE_DESIGNS[design]["q_l"]
        if q_x is None:
            q_x = NOISE_DESIGNS[design]["q_x"]
        if sigma_position is None:
            sigma_position = _SIGMA_POSITION / float(vessel.scale)
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
            self.core: DiscreteKF = ReducedKF(m, self.dt_pu)
        elif kind == "ekf":
            F1_ = _sway_capacity_pu(vessel, pu) if F1 is None else float(F1)
            self.core = WaveFilterEKF(
                m, self.dt_pu, F1=F1_, F2=1.0 / F1_, relinearise_every=relinearise_every
            )
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
            )
        else:
            self.core = DiscreteKF(m.A, m.B, m.G, m.H, m.Q, m.R, self.dt_pu, freeze)
        # surge: the decoupled [u, x, f_X] (+ 4 HF states) (+ a bias), the same design
        hf = None if kind in ("lf6", "raw") else hf_block(alpha, pu.time)
        A, B, G, H, Q = _surge_model(
            vessel,
            hf,
            d_pos,
            float(m.Q[0, 0]) if q_x is None else float(q_x),
            None if bias_q is None else bias_q[0],
        )
        self.surge = DiscreteKF(A, B, G, H, Q, m.R[:1, :1], self.dt_pu, freeze)
        self._origin = np.zeros(3)
        self._c = 1.0
        self._s = 0.0
        self._t = 0.0
        self._f_prev = np.zeros(3)
        self._psi_unwrap = 0.0
        self._z_last: Array | None = None

    # -- frames ------------------------------------------------------------------------------
    def _to_local(self, z: Array) -> Array:
        """NED pose -> ``[x', y', psi']`` in the reset frame (p.u. positions, rad)."""
        dx, dy = z[0] - self._origin[0], z[1] - self._origin[1]
        c, s = self._c, self._s
        psi = self._psi_unwrap + _wrap(z[2] - self._psi_unwrap)
        self._psi_unwrap = psi
        L = self.pu.L
        return np.array([(c * dx + s * dy) / L, (-s * dx + c * dy) / L, psi - self._origin[2]])

    def _forces(self, tau: Array | None) -> Array:
        if tau is None:
            return np.zeros(3)
        return np.array([tau[0] / self.pu.force, tau[1] / self.pu.force, tau[2] / self.pu.moment])

    # -- Observer interface ------------------------------------------------------------------
    def reset(
        self,
        t0: float,
        eta0: ArrayLike,
        *,
        nu0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
    ) -> None:
        e = as_pose(eta0, "eta0")
        self._origin = e.copy()
        self._c, self._s = math.cos(e[2]), math.sin(e[2])
        self._psi_unwrap = float(e[2])
        self._t = float(t0)
        x0 = np.zeros(self.core.n)
        xs = np.zeros(self.surge.n)
        if nu0 is not None:
            n0 = as_pose(nu0, "nu0", "[u, v, r] (m/s, m/s, rad/s)")
            xs[0] = n0[0] / self.pu.velocity
            x0[0] = n0[1] / self.pu.velocity
            x0[2] = n0[2] / self.pu.angular_velocity  # index 2 in both state layouts
        self.core.reset(x0, P0)
        self.surge.reset(xs)
        self._f_prev = np.zeros(3)
        self._z_last = None
        self._last_info = no_measurement()

    def step(self, t: float, z: ArrayLike | None, tau: ArrayLike | None = None) -> StepInfo:
        dt = float(t) - self._t
        if dt <= 1e-9 * self.dt:
            return self._last_info
        if abs(dt - self.dt) > 1e-6 * self.dt:
            raise ValueError(
                f"{self.name} samples every {self.dt:.6g} s (0.1 per-unit time of "
                f"{self.vessel.name}); got an interval of {dt:.6g} s: run the env with "
                f"control_period={self.dt:.6g} and sensors sampled at it"
            )
        self._t = float(t)
        f = self._forces(as_tau(tau))
        zl = None if z is None else self._to_local(as_pose(z))
        if zl is not None:
            self._z_last = zl
        core = self.core
        if isinstance(core, ReducedKF):
            core.step_thrust(None if zl is None else zl[1:], self._f_prev[1:], f[1:])
            # surge keeps its own lag model: the applied thrust's demand from the same lag law
            s_phi, s_del = self.surge.Phi[2, 2], self.surge.Delta[2, 0]
            self.surge.step(
                None if zl is None else zl[:1], [(f[0] - s_phi * self._f_prev[0]) / s_del]
            )
        else:
            core.predict(f[1:])
            core.update(None if zl is None else zl[1:], wrap=_wrap_heading)
            self.surge.step(None if zl is None else zl[:1], f[:1])
        self._f_prev = f
        if zl is None:
            self._last_info = no_measurement()
        else:
            inn = np.array(
                [
                    self.surge.innovation[0] * self.pu.L,
                    core.innovation[0] * self.pu.L,
                    core.innovation[1],
                ]
            )
            # in NED: rotate the position innovation back
            c, s = self._c, self._s
            inn[:2] = [c * inn[0] - s * inn[1], s * inn[0] + c * inn[1]]
            nis = (core.nis or 0.0) + (self.surge.nis or 0.0)
            self._last_info = StepInfo(inn, nis, False)
        return self._last_info

    def lf_state(self) -> Array:
        """The per-unit LF estimate ``[v, y, r, psi, f_Y, f_N]`` (sway-yaw, reset frame)."""
        core = self.core
        if isinstance(core, ReducedKF):
            x = np.zeros(6)
            x[[0, 1, 2, 3]] = core.x[:4]
            x[4:6] = self._f_prev[1:]
            return x
        return core.x[:6].copy()

    def hf_motion(self) -> Array:
        """The estimated first-order wave motion ``[x, y, psi]`` (m, m, rad; NED offsets)."""
        core = self.core
        if self.kind in ("lf6", "raw"):
            return np.zeros(3)
        i_s, i_y = self.model.HF_OUT
        if isinstance(core, ReducedKF):  # without the two thruster states
            i_s, i_y = i_s - 2, i_y - 2
        L = self.pu.L
        X, Y = self.surge.x[5] * L, core.x[i_s] * L
        c, s = self._c, self._s
        return np.array([c * X - s * Y, s * X + c * Y, core.x[i_y]])

    def estimate(self) -> Estimate:
        lf = self.lf_state()
        pu = self.pu
        xs, us = self.surge.x[1], self.surge.x[0]
        if self.kind == "raw" and self._z_last is not None:  # the measurement itself
            xs, lf = self._z_last[0], lf.copy()
            lf[1], lf[3] = self._z_last[1], self._z_last[2]
        c, s = self._c, self._s
        X, Y = xs * pu.L, lf[1] * pu.L
        eta = np.array(
            [
                self._origin[0] + c * X - s * Y,
                self._origin[1] + s * X + c * Y,
                self._origin[2] + lf[3],
            ]
        )
        nu = np.array([us * pu.velocity, lf[0] * pu.velocity, lf[2] * pu.angular_velocity])
        P = self.core.P
        iy, ipsi, iv, ir = (1, 3, 0, 2)  # the same in the 14-, 12- and 6-state layouts
        scale_pos = pu.L**2
        Ps = self.surge.P
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
            bias = np.array(
                [
                    self.surge.x[-1] * pu.force,
                    self.core.x[-2] * pu.force,
                    self.core.x[-1] * pu.moment,
                ]
            )
        return Estimate(self._t, eta, nu, scipy.linalg.block_diag(Ps, P), P_eta, P_nu, bias)


_KINDS = ("kf14", "kf12", "semiconstant", "ekf", "lf6", "raw")


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def _wrap_heading(nu: Array) -> Array:
    nu = nu.copy()
    nu[-1] = _wrap(float(nu[-1]))
    return nu


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
