r"""Grimble's LQ weights and the LQ gains of Al-Takie (1982) ch. 4 on the LF sway-yaw model.

Public names: ``PRINTED_GAINS``, ``VARIANTS``, ``GrimbleLQController``, ``grimble_lq``,
``grimble_weights``, ``markov_order``.

Design notes: docs/design/controllers.grimble.md.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from types import MappingProxyType

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.altakie import (
    THESIS_LF,
    lf_model_from_vessel,
    saturated_lf_matrix,
    surge_model_from_vessel,
)
from shipgym.dynamics.perunit import PerUnit

from .design import lqr

__all__ = [
    "PRINTED_GAINS",
    "VARIANTS",
    "GrimbleLQController",
    "grimble_lq",
    "grimble_weights",
    "markov_order",
]

Array = NDArray[np.float64]

#: Printed LQ gains (thesis sign: ``u = K x``) [printed: Al-Takie (1982) 4.4-4.5; case (a)
#: ``f = 1e-3`` entry (2, 3) printed -3.95, its CARE value +3.93 (an OCR sign error)]
PRINTED_GAINS: Mapping[str, Array] = MappingProxyType(
    {
        "wimpey-sealab/b": np.array(
            [
                [-1.30, -0.59, -0.21, -0.097, -0.67, -0.005],
                [-2.54, -1.18, 0.41, 0.19, -0.005, -0.67],
            ]
        ),
        "wimpey-sealab/a": np.array(
            [
                [-2.87, -2.05, -0.44, -0.32, -1.20, -0.024],
                [-2.54, -1.17, 0.41, 0.19, -0.002, -0.66],
            ]
        ),
        "star-hercules": np.array(
            [
                [-1.40, -0.44, 0.0, 0.0, -0.51, 0.0],
                [0.0, 0.0, -0.09, -0.03, 0.0, -0.53],
            ]
        ),
    }
)


def markov_order(A: ArrayLike, B: ArrayLike, C: ArrayLike, tol: float = 1e-9) -> tuple[int, Array]:
    """The first ``k`` with ``C A^k B`` of full rank, and that Markov parameter.

    Raises:
        ValueError: non-square ``C B`` or no full-rank Markov parameter up to ``n``.
    """
    A_, B_, C_ = (np.asarray(M, dtype=float) for M in (A, B, C))
    m = B_.shape[1]
    if C_.shape[0] != m:
        raise ValueError(f"Grimble's rules need a square system: C is {C_.shape}, B {B_.shape}")
    M = B_.copy()
    for k in range(A_.shape[0]):
        CM = C_ @ M
        if np.linalg.matrix_rank(CM, tol=tol * max(1.0, float(np.abs(CM).max()))) == m:
            return k, CM
        M = A_ @ M
    raise ValueError("no Markov parameter C A^k B has full rank: the system is not invertible")


def grimble_weights(
    A: ArrayLike,
    B: ArrayLike,
    C: ArrayLike,
    ratios: tuple[float, ...] | None = None,
    f: float = 1.0,
    N: ArrayLike | None = None,
) -> tuple[Array, Array, int, Array]:
    """Grimble's state and input weights (Al-Takie 1982 eqs. 4.12-4.16).

    Args:
        A, B, C: the (square) system.
        ratios: asymptotic eigenvalue ratios ``lambda_i`` (one per input); ``None``: all 1
            (case b). ``(1.5, 1)`` is the thesis's case (a).
        f: scalar factor on ``R``.
        N: asymptotic closed-loop eigenvectors, (m, m); ``None``: ``I``.

    Returns:
        ``(Q, R, k, CAkB)``: (n, n), (m, m), the Markov order and ``C A^k B``.
    """
    k, CAkB = markov_order(A, B, C)
    m = CAkB.shape[0]
    N_ = np.eye(m) if N is None else np.asarray(N, dtype=float)
    lam = np.ones(m) if ratios is None else np.asarray(ratios, dtype=float)
    if lam.shape != (m,) or not (lam > 0).all():
        raise ValueError(f"ratios must be {m} positive numbers, got {ratios!r}")
    if not (np.isfinite(f) and f > 0):
        raise ValueError(f"f must be a positive number, got {f!r}")
    CN = CAkB @ N_
    Ci = np.linalg.inv(CN)
    Qy = Ci.T @ Ci
    C_ = np.asarray(C, dtype=float)
    Q = C_.T @ Qy @ C_
    Lam = (-1.0) ** k * np.diag((1.0 / lam) ** (2 * (k + 1)))
    Ni = np.linalg.inv(N_)
    R = f * Ni.T @ Lam @ Ni
    return 0.5 * (Q + Q.T), 0.5 * (R + R.T), k, CAkB


def grimble_lq(
    A: ArrayLike,
    B: ArrayLike,
    C: ArrayLike,
    case: str = "b",
    f: float = 1.0,
) -> tuple[Array, Array, NDArray[np.complex128]]:
    """The LQ gain of Al-Takie (1982) ch. 4 on a per-unit LF model: ``(K, S, E)``.

    Args:
        A, B, C: the LF model (:class:`~shipgym.dynamics.altakie.LFModel` matrices).
        case: ``"a"`` (``lambda_1 = 1.5 lambda_2``) or ``"b"`` (equal; the selected design).
        f: the factor on ``R``.

    Returns:
        As :func:`~shipgym.controllers.lq.lqr`: ``K`` for ``u = -K x``, the Riccati solution
        and the closed-loop eigenvalues (per-unit time).
    """
    if case not in ("a", "b"):
        raise ValueError(f"case must be 'a' or 'b' (Al-Takie 1982 4.4), got {case!r}")
    ratios = (1.5, 1.0) if case == "a" else None
    Q, R, _, _ = grimble_weights(A, B, C, ratios, f)
    return lqr(A, B, Q, R)


# ---- the DP controller for a simulated vessel (SI in, SI out) ---------------------------------

#: controller variants: ``"lq"`` (Grimble's case, re-solved on the vessel's own per-unit LF
#: model), ``"printed"`` (the thesis's printed gain of the vessel), ``"sdre"`` (re-solved on the
#: model linearised at the thruster states every ``relinearise_every`` calls, ch. 7)
VARIANTS = ("lq", "printed", "sdre")


class GrimbleLQController:
    """Al-Takie (1982) ch. 4 LQ (and ch. 7 SDRE) on a vessel, as a DP control law.

    Per unit on the vessel's own bases (:class:`~shipgym.dynamics.perunit.PerUnit`), the LF
    sway-yaw state ``x = [v, y_e, r, psi_e, f_Y, f_N]`` (body sway velocity, sway position
    error in the body frame, yaw rate, heading error, the thruster states) gives
    ``[Y, N] = -K x``; surge, decoupled in the thesis, gets the same design on its own model
    ``[u, x_e, f_X]`` (:func:`~shipgym.dynamics.altakie.surge_model_from_vessel`; Grimble's
    weights with ``k = 2``). No integral action (as in the thesis, which assumes wind
    feedforward): a steady load leaves an offset ``K^-1``-small at these gains.

    The thruster states are the controller's own first-order lag model of the force it asked
    for and was delivered (the 14-state filter's estimate of them is exactly that: they carry
    no noise, so its gain on them is zero).

    Args:
        vessel: the :class:`~shipgym.dynamics.vessel.Vessel`.
        dt: control period (s).
        variant: one of :data:`VARIANTS`.
        case: Grimble's case ``"a"`` or ``"b"`` (``"lq"``/``"sdre"``).
        relinearise_every: SDRE calls between re-solutions (2 printed).
        F1: SDRE saturation (p.u. force); ``None``: the vessel's sway capacity in p.u.
    """

    def __init__(
        self,
        vessel: object,
        dt: float,
        *,
        variant: str = "lq",
        case: str = "b",
        relinearise_every: int = 2,
        F1: float | None = None,
    ) -> None:
        if variant not in VARIANTS:
            raise ValueError(f"variant must be one of {', '.join(VARIANTS)}, got {variant!r}")
        self.vessel = vessel
        self.dt = float(dt)
        self.variant = variant
        self.pu = pu = PerUnit.of_vessel(vessel)
        lf = lf_model_from_vessel(vessel)
        self.lf = lf
        self._Q, self._R, _, _ = grimble_weights(
            lf.A, lf.B, lf.C, (1.5, 1.0) if case == "a" else None
        )
        name = getattr(vessel, "name", "")
        if variant == "printed":
            key = f"{name}/b" if name == "wimpey-sealab" else name
            if key not in PRINTED_GAINS or name not in THESIS_LF:
                raise ValueError(
                    f"the thesis prints LQ gains for {', '.join(THESIS_LF)} only, not {name!r}: "
                    "use the 'alt-lq' controller (Grimble's weights re-solved)"
                )
            Y = THESIS_LF[name].Y
            T = np.eye(6)
            T[4:, 4:] = Y
            # printed: u_units = K_p x_units; generalised: u = Y K_p T^-1 x (thesis sign u = K x)
            self.K = -(Y @ PRINTED_GAINS[key] @ np.linalg.inv(T))
        else:
            self.K = lqr(lf.A, lf.B, self._Q, self._R)[0]
        As, Bs, Cs, _ = surge_model_from_vessel(vessel)
        Qs, Rs, _, _ = grimble_weights(As, Bs, Cs)
        self.K_surge = lqr(As, Bs, Qs, Rs)[0]
        T_lag = 1.0 / (float(lf.thruster_pole[0]) / pu.time)  # s
        self._a = math.exp(-self.dt / T_lag)
        self.relinearise_every = int(relinearise_every)
        self.F1 = float(vessel.actuators.capacity()[1]) / pu.force if F1 is None else float(F1)
        self.reset()

    def reset(self) -> None:
        """Forget the thruster states and the last command."""
        self._f = np.zeros(3)  # p.u. [f_X, f_Y, f_N]
        self._u = np.zeros(3)
        self._calls = 0
        self._K_now = self.K

    def change_frame(self, dpsi: float) -> None:
        """Nothing to rotate: the state is in the body frame."""

    def _gain(self) -> Array:
        if self.variant != "sdre":
            return self.K
        if self._calls % self.relinearise_every == 0:
            A1 = saturated_lf_matrix(self.lf.A, self._f[1:], self.F1, 1.0 / self.F1)
            self._K_now = lqr(A1, self.lf.B, self._Q, self._R)[0]
        return self._K_now

    def __call__(
        self,
        eta_r: ArrayLike,
        nu: ArrayLike,
        eta_d_r: ArrayLike,
        eta_dot_d_r: ArrayLike | None = None,
        eta_ddot_d_r: ArrayLike | None = None,
        *,
        saturated: ArrayLike | None = None,
    ) -> Array:
        """Body-frame control force ``[X, Y, N]`` (N, N, N m) from the r-frame pose errors.

        Args:
            eta_r, nu, eta_d_r: pose (m, m, rad; r-frame), body velocity, set-point.
            eta_dot_d_r, eta_ddot_d_r: ignored (a set-point regulator, as in the thesis).
            saturated: the allocation's ``tau_error`` of the previous call (N, N, N m): the
                thruster model integrates what was delivered.
        """
        e = np.asarray(eta_r, dtype=float) - np.asarray(eta_d_r, dtype=float)
        n = np.asarray(nu, dtype=float)
        pu = self.pu
        if self._calls:
            delivered = self._u.copy()
            if saturated is not None:
                err = np.asarray(saturated, dtype=float)
                if err.shape == (3,) and err.dtype != bool:
                    delivered -= np.array(
                        [err[0] / pu.force, err[1] / pu.force, err[2] / pu.moment]
                    )
            self._f = self._a * self._f + (1.0 - self._a) * delivered
        psi = float(eta_r[2])  # type: ignore[index]
        c, s = math.cos(psi), math.sin(psi)
        ex, ey = c * e[0] + s * e[1], -s * e[0] + c * e[1]
        epsi = (e[2] + math.pi) % (2.0 * math.pi) - math.pi
        L, V, W = pu.L, pu.velocity, pu.angular_velocity
        x = np.array([n[1] / V, ey / L, n[2] / W, epsi, self._f[1], self._f[2]])
        xs = np.array([n[0] / V, ex / L, self._f[0]])
        u_sy = -self._gain() @ x
        u_x = float(-(self.K_surge @ xs)[0])
        self._u = np.array([u_x, u_sy[0], u_sy[1]])
        self._calls += 1
        return np.array([u_x * pu.force, u_sy[0] * pu.force, u_sy[1] * pu.moment])
