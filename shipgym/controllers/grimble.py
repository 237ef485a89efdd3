r"""Grimble's LQ weights and the LQ gains of Al-Takie (1982) ch. 4 on the LF sway-yaw model.

Public names: ``PRINTED_GAINS``, ``VARIANTS``, ``GrimbleLQController``, ``grimble_lq``,
``grimble_weights``, ``markov_order``.

Design notes: docs/design/controllers.grimble.md.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import entry, njit
from shipgym.dynamics.altakie import THESIS_LF, lf_model_from_vessel, surge_model_from_vessel
from shipgym.dynamics.perunit import PerUnit

from .design import lqr
from .pid import _BAD_INPUT, _SAT_ERROR, BatchedLaw, bad_input

__all__ = [
    "PRINTED_GAINS",
    "VARIANTS",
    "BatchedGrimbleLQ",
    "GrimbleLQController",
    "care",
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

# Entries of the parameter vector ``P`` the compiled law reads.
_PA, _PB, _PF, _PMO, _PL, _PV, _PW, _PF1, _PEVERY, _PSDRE = range(10)
# Columns of the state ``S`` (float64, (n, 19)), one row per env; zeros: the reset state.
_SF = 0  # the thruster states [f_X, f_Y, f_N] (p.u.)
_SU = 3  # the last command [u_X, u_Y, u_N] (p.u.)
_SCALLS = 6  # calls since the reset
_SK = 7  # the SDRE's current sway-yaw gain (2, 6), row by row
_S_COLS = 19


@njit
def _inv_logdet(Z: Any) -> tuple[Any, float, bool]:
    """``(Z^-1, log |det Z|, ok)`` by Gauss-Jordan elimination with partial pivoting;
    ``ok`` false for a (numerically) singular ``Z``."""
    m = Z.shape[0]
    W = np.zeros((m, 2 * m))
    for i in range(m):
        for j in range(m):
            W[i, j] = Z[i, j]
        W[i, m + i] = 1.0
    logdet = 0.0
    for k in range(m):
        p, big = k, abs(W[k, k])
        for i in range(k + 1, m):
            if abs(W[i, k]) > big:
                p, big = i, abs(W[i, k])
        if not big > 0.0 or not math.isfinite(big):
            return W[:, m:], 0.0, False
        if p != k:
            for j in range(2 * m):
                W[k, j], W[p, j] = W[p, j], W[k, j]
        logdet += math.log(big)
        piv = W[k, k]
        for j in range(2 * m):
            W[k, j] /= piv
        for i in range(m):
            if i != k and W[i, k] != 0.0:
                f = W[i, k]
                for j in range(2 * m):
                    W[i, j] -= f * W[k, j]
    return W[:, m:].copy(), logdet, True


@njit
def _lstsq(M: Any, B: Any) -> Any:
    """The least-squares solution ``X`` of ``M X = B`` (``M`` (m, n) of full column rank,
    ``m >= n``) by Householder QR; ``M`` and ``B`` are overwritten."""
    m, n = M.shape
    k = B.shape[1]
    for j in range(n):
        norm = 0.0
        for i in range(j, m):
            norm += M[i, j] * M[i, j]
        norm = math.sqrt(norm)
        if norm == 0.0:
            continue
        alpha = -norm if M[j, j] >= 0.0 else norm
        v = M[j:, j].copy()
        v[0] -= alpha
        vv = 0.0
        for i in range(m - j):
            vv += v[i] * v[i]
        for c in range(j, n):
            dot = 0.0
            for i in range(m - j):
                dot += v[i] * M[j + i, c]
            f = 2.0 * dot / vv
            for i in range(m - j):
                M[j + i, c] -= f * v[i]
        for c in range(k):
            dot = 0.0
            for i in range(m - j):
                dot += v[i] * B[j + i, c]
            f = 2.0 * dot / vv
            for i in range(m - j):
                B[j + i, c] -= f * v[i]
    X = np.empty((n, k))
    for c in range(k):
        for i in range(n - 1, -1, -1):
            acc = B[i, c]
            for j in range(i + 1, n):
                acc -= M[i, j] * X[j, c]
            X[i, c] = acc / M[i, i]
    return X


@njit
def care(A: Any, G: Any, Q: Any) -> Any:
    """The stabilising solution ``S`` of ``A^T S + S A - S G S + Q = 0`` (``G = B R^-1 B^T``)
    by the matrix sign function of the Hamiltonian (Roberts 1980; determinant scaling,
    Byers 1987): ``S`` from the stable invariant subspace ``(sign(H) + I) [I; S] = 0``. NaNs
    where the iteration breaks down (no stabilising solution)."""
    n = A.shape[0]
    Z = np.empty((2 * n, 2 * n))
    for i in range(n):
        for j in range(n):
            Z[i, j] = A[i, j]
            Z[i, n + j] = -G[i, j]
            Z[n + i, j] = -Q[i, j]
            Z[n + i, n + j] = -A[j, i]
    close = False
    for _ in range(100):
        Zi, logdet, ok = _inv_logdet(Z)
        if not ok:
            return np.full((n, n), np.nan)
        c = math.exp(logdet / (2 * n))
        diff = big = 0.0
        for i in range(2 * n):
            for j in range(2 * n):
                z = 0.5 * (Z[i, j] / c + c * Zi[i, j])
                diff = max(diff, abs(z - Z[i, j]))
                big = max(big, abs(z))
                Z[i, j] = z
        if close:  # one more (quadratically convergent) step after the first small change
            break
        close = diff <= 1e-10 * big
    if not (close and np.all(np.isfinite(Z))):
        return np.full((n, n), np.nan)
    lhs = np.empty((2 * n, n))
    rhs = np.empty((2 * n, n))
    for i in range(n):
        for j in range(n):
            one = 1.0 if i == j else 0.0
            lhs[i, j] = Z[i, n + j]
            lhs[n + i, j] = Z[n + i, n + j] + one
            rhs[i, j] = -(Z[i, j] + one)
            rhs[n + i, j] = -Z[n + i, j]
    X = _lstsq(lhs, rhs)
    return 0.5 * (X + X.T)


@njit
def _sdre_gain(P: Any, A: Any, G: Any, Q: Any, RiBt: Any, s: Any) -> None:
    """The sway-yaw gain re-solved on ``A`` linearised at the thruster states (Al-Takie 1982
    7.2: the hull rows' thruster columns times ``psi'(f) = F1 F2 exp(-F2 |f|)``, ``F2 = 1 /
    F1``), into ``s[_SK:]``."""
    F1 = P[_PF1]
    F2 = 1.0 / F1
    A1 = A.copy()
    for j in range(2):
        slope = F1 * F2 * math.exp(-F2 * abs(s[_SF + 1 + j]))
        for i in range(4):
            A1[i, 4 + j] = A[i, 4 + j] * slope
    X = care(A1, G, Q)
    if not np.all(np.isfinite(X)):  # no solution (thrusters far beyond F1): keep the gain
        return
    for i in range(2):
        for j in range(6):
            acc = 0.0
            for k in range(6):
                acc += RiBt[i, k] * X[k, j]
            s[_SK + 6 * i + j] = acc


@njit
def _grimble_env(P: Any, K: Any, Ks: Any, A: Any, G: Any, Q: Any, RiBt: Any, s: Any, e: Any,
                 w: Any, ed: Any, sat: Any, kind: int, out: Any) -> None:  # fmt: skip
    """One env's control period (:class:`GrimbleLQController`)."""
    F, Mo = P[_PF], P[_PMO]
    if s[_SCALLS] != 0.0:  # the thruster lag integrates what was delivered
        a, b = P[_PA], P[_PB]
        for j in range(3):
            d = s[_SU + j]
            if kind == _SAT_ERROR:
                d -= sat[j] / (Mo if j == 2 else F)
            s[_SF + j] = a * s[_SF + j] + b * d
    e0, e1, e2 = e[0] - ed[0], e[1] - ed[1], e[2] - ed[2]
    c, sn = math.cos(e[2]), math.sin(e[2])
    ex, ey = c * e0 + sn * e1, -sn * e0 + c * e1
    epsi = (e2 + math.pi) % (2.0 * math.pi) - math.pi
    L, V, W = P[_PL], P[_PV], P[_PW]
    x = (w[1] / V, ey / L, w[2] / W, epsi, s[_SF + 1], s[_SF + 2])
    sdre = P[_PSDRE] != 0.0
    if sdre and s[_SCALLS] % P[_PEVERY] == 0.0:
        _sdre_gain(P, A, G, Q, RiBt, s)
    uy = un = 0.0
    for j in range(6):
        uy += (s[_SK + j] if sdre else K[0, j]) * x[j]
        un += (s[_SK + 6 + j] if sdre else K[1, j]) * x[j]
    uy, un = -uy, -un
    u_x = -(Ks[0] * (w[0] / V) + Ks[1] * (ex / L) + Ks[2] * s[_SF])
    s[_SU], s[_SU + 1], s[_SU + 2] = u_x, uy, un
    s[_SCALLS] += 1.0
    out[0], out[1], out[2] = u_x * F, uy * F, un * Mo


@njit
def grimble_law(P: Any, K: Any, Ks: Any, A: Any, G: Any, Q: Any, RiBt: Any, S: Any, eta: Any,
                nu: Any, eta_d: Any, sat: Any, kind: int, tau: Any) -> int:  # fmt: skip
    """The law of :class:`GrimbleLQController` for every env (row) of ``S``: writes ``tau``
    (n, 3) (N, N, N m) and advances the state. Returns 0, or the index of the first input
    that is not finite (the state is then left as it was)."""
    bad = bad_input(eta, nu, eta_d, eta_d, eta_d, sat)
    if bad:
        return bad
    for i in range(S.shape[0]):
        _grimble_env(P, K, Ks, A, G, Q, RiBt, S[i], eta[i], nu[i], eta_d[i], sat[i], kind,
                     tau[i])  # fmt: skip
    return 0


_ENTRY: list[Any] = []


def _law_entry() -> Any:
    """:func:`grimble_law`'s compiled entry point."""
    if not _ENTRY:
        m, v = np.zeros((1, 1)), np.zeros(1)
        _ENTRY.append(entry(grimble_law, (v, m, v, m, m, m, m, m, m, m, m, m, 0, m)))
    return _ENTRY[0]


class _GrimbleDesign(NamedTuple):
    """The arrays :func:`grimble_law` reads (read-only)."""

    P: Array
    K: Array
    Ks: Array
    A: Array
    G: Array
    Q: Array
    RiBt: Array


class BatchedGrimbleLQ(BatchedLaw):
    """:class:`GrimbleLQController` for ``n`` envs: the one run-time form (the controller is
    its ``n = 1`` adapter). Row ``i`` of a call equals the same call at ``n = 1`` on row
    ``i``'s inputs, bit for bit (the SDRE's Riccati equation is solved per env:
    :func:`care`).

    Args:
        controller: the design (:class:`GrimbleLQController`); the states start at zero.
        n: number of envs, >= 1.
    """

    def __init__(self, controller: GrimbleLQController, n: int) -> None:
        if not isinstance(controller, GrimbleLQController):
            raise TypeError(f"controller must be a GrimbleLQController, got {controller!r}")
        self._state(n, _S_COLS)
        self.controller = controller
        self._d = controller._design

    def change_frame(self, dpsi: ArrayLike, mask: ArrayLike | None = None) -> None:
        """Nothing to rotate: the state is in the body frame."""

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
        """Body-frame control forces ``[X, Y, N]`` (N, N, N m) of every env, (n, 3) (inputs
        as :meth:`GrimbleLQController.__call__`, (n, 3) each)."""
        # the law needs no reference derivatives
        e, w, ed, _, _, sat, kind = self._inputs(eta_r, nu, eta_d_r, None, None, saturated)
        tau = np.empty((self.n, 3))
        d = self._d
        code = _law_entry()(d.P, d.K, d.Ks, d.A, d.G, d.Q, d.RiBt, self._S, e, w, ed, sat, kind,
                            tau)  # fmt: skip
        if code:
            raise ValueError(f"{_BAD_INPUT[code]} contains NaN or infinite values")
        return tau


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
    no noise, so its gain on them is zero). The law is :class:`BatchedGrimbleLQ` at ``n = 1``.

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
        Q, R, _, _ = grimble_weights(lf.A, lf.B, lf.C, (1.5, 1.0) if case == "a" else None)
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
            self.K = lqr(lf.A, lf.B, Q, R)[0]
        As, Bs, Cs, _ = surge_model_from_vessel(vessel)
        Qs, Rs, _, _ = grimble_weights(As, Bs, Cs)
        self.K_surge = lqr(As, Bs, Qs, Rs)[0]
        T_lag = 1.0 / (float(lf.thruster_pole[0]) / pu.time)  # s
        a = math.exp(-self.dt / T_lag)
        self.relinearise_every = int(relinearise_every)
        if self.relinearise_every < 1:
            raise ValueError(f"relinearise_every must be >= 1, got {relinearise_every!r}")
        self.F1 = float(vessel.actuators.capacity()[1]) / pu.force if F1 is None else float(F1)
        RiBt = np.linalg.solve(R, np.asarray(lf.B, dtype=float).T)
        P = [a, 1.0 - a, pu.force, pu.moment, pu.L, pu.velocity, pu.angular_velocity, self.F1,
             float(self.relinearise_every), float(variant == "sdre")]  # fmt: skip
        arrays = [np.array(x, dtype=float) for x in (P, self.K, self.K_surge[0], lf.A,
                  lf.B @ RiBt, Q, RiBt)]  # fmt: skip
        for x in arrays:
            x.setflags(write=False)
        self._design = _GrimbleDesign(*arrays)
        self._law = BatchedGrimbleLQ(self, 1)

    def reset(self) -> None:
        """Forget the thruster states and the last command."""
        self._law.reset()

    def batched(self, n: int) -> BatchedGrimbleLQ:
        """This design for ``n`` envs (the states at zero)."""
        return BatchedGrimbleLQ(self, n)

    def change_frame(self, dpsi: float) -> None:
        """Nothing to rotate: the state is in the body frame."""

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
                thruster model integrates what was delivered (3 booleans: what was asked).
        """
        return self._law(eta_r, nu, eta_d_r, saturated=saturated)[0]
