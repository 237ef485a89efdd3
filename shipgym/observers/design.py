r"""Steady-state Kalman gain design (python-control style) and the observers' design data.

``lqe`` (Tomera 2014 eqs. 33-34), ``dlqe`` (Tomera 2014 Table 3, eq. 30) and the per-DOF
double-integrator ``KalmanDesign`` of Tomera (2011) eqs. 56-59.

Public names: ``DKF_DESIGN``, ``HEADING_VARIANCE_TOMERA2011``, ``KBF_DESIGN``, ``KalmanDesign``,
``POSITION_VARIANCE_TOMERA2011``, ``TOMERA_DKF``, ``TOMERA_KBF``, ``discretise``, ...
Sources: Tomera (2014); Tomera (2011).

Design notes: docs/design/observers.design.md.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from .._config import from_mapping, param
from .sensors import TOMERA2011_HEADING_VARIANCE

__all__ = [
    "DKF_DESIGN",
    "HEADING_VARIANCE_TOMERA2011",
    "KBF_DESIGN",
    "KalmanDesign",
    "POSITION_VARIANCE_TOMERA2011",
    "TOMERA_DKF",
    "TOMERA_KBF",
    "discretise",
    "dlqe",
    "double_integrator",
    "lqe",
]

POSITION_VARIANCE_TOMERA2011 = 0.01
"""DGPS position variance per axis, m^2 (Tomera 2011 section 5: ``R_x = R_y = 0.01``)."""

HEADING_VARIANCE_TOMERA2011 = TOMERA2011_HEADING_VARIANCE
"""Gyrocompass heading variance, rad^2: Tomera's (2011) ``R_psi = 0.1`` read as deg^2 (the sensors'
default, :data:`shipgym.observers.sensors.TOMERA2011_HEADING_VARIANCE`).

Tomera (2011) gives no unit. As rad^2 it would be a 18 deg standard deviation, impossible for a
gyrocompass next to a 0.1 m DGPS; as deg^2 it is 0.32 deg, a typical gyrocompass accuracy
(typically 0.1-0.3 deg). ``0.1 deg^2 = 3.046e-5 rad^2``.
"""

_RANK_TOL = 1e-8  # relative tolerance of the PBH rank tests and the symmetry check

# --------------------------------------------------------------------------------------------
# Validation helpers
# --------------------------------------------------------------------------------------------


def _matrix(name: str, value: ArrayLike) -> NDArray[np.float64]:
    """A finite 2-D float array (scalars become 1x1, 1-D arrays one row, like python-control)."""
    try:
        M = np.array(value, dtype=float, ndmin=2)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a real matrix, got {value!r}") from exc
    if M.ndim != 2:
        raise ValueError(f"{name} must be a 2-D matrix, got an array of shape {M.shape}")
    if not np.all(np.isfinite(M)):
        raise ValueError(f"{name} must be finite (no NaN or inf), got {M.tolist()}")
    return M


def _check_shape(name: str, M: NDArray[np.float64], shape: tuple[int, int]) -> None:
    if M.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {M.shape}")


def _check_symmetric(name: str, M: NDArray[np.float64]) -> None:
    scale = max(float(np.max(np.abs(M))), np.finfo(float).tiny)
    if float(np.max(np.abs(M - M.T))) > _RANK_TOL * scale:
        raise ValueError(f"{name} must be symmetric, got {M.tolist()}")


def _check_psd(name: str, M: NDArray[np.float64]) -> None:
    """Symmetric positive semi-definite (``M >= 0``)."""
    _check_symmetric(name, M)
    eig = np.linalg.eigvalsh(0.5 * (M + M.T))
    if eig.size and eig[0] < -1e-12 * max(float(np.max(np.abs(eig))), 1e-300):
        raise ValueError(
            f"{name} must be positive semi-definite (a covariance), got eigenvalues {eig.tolist()}"
        )


def _check_pd(name: str, M: NDArray[np.float64]) -> None:
    """Symmetric positive definite (``M > 0``)."""
    _check_symmetric(name, M)
    eig = np.linalg.eigvalsh(0.5 * (M + M.T))
    if eig.size and eig[0] <= 1e-14 * max(float(np.max(np.abs(eig))), 1e-300):
        raise ValueError(
            f"{name} must be positive definite (a measurement noise covariance), got "
            f"eigenvalues {eig.tolist()}"
        )


def _sqrtm_psd(M: NDArray[np.float64]) -> NDArray[np.float64]:
    w, V = np.linalg.eigh(0.5 * (M + M.T))
    return (V * np.sqrt(np.clip(w, 0.0, None))) @ V.T


def _eig(M: NDArray[np.float64]) -> NDArray[np.complex128]:
    return np.asarray(np.linalg.eigvals(M), dtype=np.complex128)


def _unstable_modes(A: NDArray[np.float64], discrete: bool) -> NDArray[np.complex128]:
    """Eigenvalues of A on or outside the stability boundary (imaginary axis / unit circle)."""
    lam = _eig(A)
    if discrete:
        return lam[np.abs(lam) >= 1.0 - _RANK_TOL]
    return lam[lam.real >= -_RANK_TOL * max(1.0, float(np.max(np.abs(lam))))]


def _pbh_rank_deficient(
    M_of_lam: Any, modes: NDArray[np.complex128], scale: float
) -> list[complex]:
    """Modes at which the PBH matrix loses rank (smallest singular value ~ 0)."""
    bad: list[complex] = []
    for lam in modes:
        s = np.linalg.svd(M_of_lam(lam), compute_uv=False)
        if s[-1] <= _RANK_TOL * scale:
            bad.append(complex(lam))
    return bad


def _check_stabilisable_detectable(
    A: NDArray[np.float64],
    GQh: NDArray[np.float64],
    C: NDArray[np.float64],
    discrete: bool,
) -> None:
    """PBH tests: ``(A, C)`` detectable and ``(A, G Q^(1/2))`` stabilisable.

    Detectable: ``rank [A - lam I; C] = n`` and stabilisable: ``rank [A - lam I, G Q^1/2] = n``
    for every eigenvalue ``lam`` of ``A`` with ``Re lam >= 0`` (continuous) or ``|lam| >= 1``
    (discrete). Together they guarantee a unique stabilising solution ``P >= 0`` of the
    Riccati equation, to which the time-varying Riccati equation converges from any
    ``P0 >= 0``.
    """
    n = A.shape[0]
    eye = np.eye(n)
    modes = _unstable_modes(A, discrete)
    scale = max(1.0, float(np.linalg.norm(A, 2)))
    kind = "|lambda| >= 1" if discrete else "Re(lambda) >= 0"
    bad = _pbh_rank_deficient(
        lambda lam: np.vstack([A - lam * eye, C]), modes, max(scale, float(np.linalg.norm(C, 2)))
    )
    if bad:
        raise ValueError(
            f"(A, C) is not detectable: the mode(s) {bad} ({kind}) are not seen by the "
            "measurements (PBH test); measure a state that observes them"
        )
    bad = _pbh_rank_deficient(
        lambda lam: np.hstack([A - lam * eye, GQh]),
        modes,
        max(scale, float(np.linalg.norm(GQh, 2))),
    )
    if bad:
        raise ValueError(
            f"(A, G Q^1/2) is not stabilisable: the mode(s) {bad} ({kind}) receive no process "
            "noise (PBH test); add process noise on them (G, Q)"
        )


def _validate(
    A: ArrayLike,
    G: ArrayLike,
    C: ArrayLike,
    Q: ArrayLike,
    R: ArrayLike,
    names: tuple[str, str, str],
    discrete: bool,
) -> tuple[NDArray[np.float64], ...]:
    nA, nG, nC = names
    A_ = _matrix(nA, A)
    n = A_.shape[0]
    _check_shape(nA, A_, (n, n))
    G_ = _matrix(nG, G)
    if G_.shape[0] != n:
        raise ValueError(f"{nG} must have {n} rows (one per state of {nA}), got shape {G_.shape}")
    m = G_.shape[1]
    C_ = _matrix(nC, C)
    if C_.shape[1] != n:
        raise ValueError(
            f"{nC} must have {n} columns (one per state of {nA}), got shape {C_.shape}"
        )
    p = C_.shape[0]
    Q_ = _matrix("Q", Q)
    _check_shape("Q", Q_, (m, m))
    _check_psd("Q", Q_)
    R_ = _matrix("R", R)
    _check_shape("R", R_, (p, p))
    _check_pd("R", R_)
    Q_ = 0.5 * (Q_ + Q_.T)
    R_ = 0.5 * (R_ + R_.T)
    _check_stabilisable_detectable(A_, G_ @ _sqrtm_psd(Q_), C_, discrete)
    return A_, G_, C_, Q_, R_


# --------------------------------------------------------------------------------------------
# Gain design
# --------------------------------------------------------------------------------------------


def lqe(
    A: ArrayLike, G: ArrayLike, C: ArrayLike, Q: ArrayLike, R: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.complex128]]:
    r"""Continuous-time linear quadratic estimator (steady-state Kalman-Bucy filter).

    For ``x_dot = A x + G w``, ``y = C x + v`` with white noises of intensities
    ``E{w w^T} = Q delta``, ``E{v v^T} = R delta`` (Tomera 2014 eqs. 31-32), the stationary filter
    ``x_hat_dot = A x_hat + L (y - C x_hat)`` (Tomera 2011 eq. 52) with ``L = P C^T R^-1``
    (Tomera 2014 eq. 33) and ``P`` the stabilising solution of (Tomera 2014 eq. 34)::

        A P + P A^T + G Q G^T - P C^T R^-1 C P = 0

    Same meaning and return as ``control.lqe(A, G, C, QN, RN)``.

    Args:
        A: dynamics matrix, (n, n).
        G: process noise input matrix, (n, m).
        C: output matrix, (p, n).
        Q: process noise intensity, (m, m), symmetric ``>= 0``.
        R: measurement noise intensity, (p, p), symmetric ``> 0``.

    Returns:
        ``(L, P, E)``: gain (n, p), Riccati solution (n, n), estimator poles
        ``eig(A - L C)`` (n,).

    Raises:
        ValueError: non-finite values, wrong shapes, ``Q`` not ``>= 0``, ``R`` not ``> 0``,
            ``(A, C)`` not detectable or ``(A, G Q^1/2)`` not stabilisable (PBH tests).
    """
    A_, G_, C_, Q_, R_ = _validate(A, G, C, Q, R, ("A", "G", "C"), discrete=False)
    W = G_ @ Q_ @ G_.T
    try:
        P = scipy.linalg.solve_continuous_are(A_.T, C_.T, 0.5 * (W + W.T), R_)
    except (np.linalg.LinAlgError, ValueError) as exc:  # pragma: no cover - guarded by PBH
        raise ValueError(
            f"the continuous Riccati equation has no stabilising solution: {exc}"
        ) from exc
    P = 0.5 * (P + P.T)
    L = np.linalg.solve(R_, C_ @ P).T
    E = _eig(A_ - L @ C_)
    return L, P, E


def dlqe(
    F: ArrayLike,
    G: ArrayLike,
    H: ArrayLike,
    Q: ArrayLike,
    R: ArrayLike,
    *,
    form: Literal["predictor", "filter"] = "predictor",
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.complex128]]:
    r"""Discrete-time linear quadratic estimator (steady-state Kalman filter).

    For ``x[k+1] = F x[k] + G w[k]``, ``y[k] = H x[k] + v[k]`` with ``E{w w^T} = Q``,
    ``E{v v^T} = R`` (Tomera 2014 eqs. 28-29), ``P`` is the predicted (a priori) steady-state
    covariance ``P_bar``, the stabilising solution of::

        P = F P F^T - F P H^T (H P H^T + R)^-1 H P F^T + G Q G^T

    Args:
        F: state transition matrix, (n, n).
        G: process noise input matrix, (n, m).
        H: measurement matrix, (p, n).
        Q: process noise covariance, (m, m), symmetric ``>= 0``.
        R: measurement noise covariance, (p, p), symmetric ``> 0``.
        form: ``"predictor"`` (default): ``L = F P H^T (H P H^T + R)^-1``, the one-step
            predictor gain of ``x_bar[k+1] = F x_bar[k] + L (y[k] - H x_bar[k])``, exactly what
            python-control's ``dlqe`` returns. ``"filter"``: ``L = P H^T (H P H^T + R)^-1``,
            the measurement-update gain of ``x_hat[k] = x_bar[k] + L (y[k] - H x_bar[k])``
            (Tomera 2014 Table 3, the form of eq. 30; MATLAB ``dlqe``'s ``M``).

    Returns:
        ``(L, P, E)``: gain (n, p); the *predicted* covariance ``P_bar`` (n, n) in both forms
        (the updated one is ``(I - L_filter H) P_bar``, Tomera (2011) eq. 25); the estimator poles
        ``E = eig(F - L_predictor H) = eig((I - L_filter H) F)`` (n,), equal in both forms.

    Raises:
        ValueError: as :func:`lqe` (with the discrete stability boundary ``|lambda| = 1``),
            or an unknown ``form``.
    """
    if form not in ("predictor", "filter"):
        raise ValueError(f"form must be 'predictor' or 'filter', got {form!r}")
    F_, G_, H_, Q_, R_ = _validate(F, G, H, Q, R, ("F", "G", "H"), discrete=True)
    W = G_ @ Q_ @ G_.T
    try:
        P = scipy.linalg.solve_discrete_are(F_.T, H_.T, 0.5 * (W + W.T), R_)
    except (np.linalg.LinAlgError, ValueError) as exc:  # pragma: no cover - guarded by PBH
        raise ValueError(
            f"the discrete Riccati equation has no stabilising solution: {exc}"
        ) from exc
    P = 0.5 * (P + P.T)
    S = H_ @ P @ H_.T + R_
    K = np.linalg.solve(S, H_ @ P).T  # P H^T S^-1 (S symmetric)
    L_pred = F_ @ K
    E = _eig(F_ - L_pred @ H_)
    return (L_pred if form == "predictor" else K), P, E


def discretise(
    A: ArrayLike, W: ArrayLike, T: float, *, method: Literal["exact", "euler"] = "exact"
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Sampled model ``(F, Q_k)`` of ``x_dot = A x + w``, ``E{w w^T} = W delta``, period ``T``.

    Args:
        A: dynamics matrix, (n, n).
        W: process noise intensity ``G Q G^T``, (n, n).
        T: sampling period (s), ``>= 0``.
        method: ``"exact"``: ``F = exp(A T)``, ``Q_k = int_0^T exp(A s) W exp(A^T s) ds``
            (Van Loan 1978); ``"euler"``: ``F = I + A T`` (Tomera 2011 eq. 5) and ``Q_k = W T``
            (Tomera 2011 eq. 31).

    Returns:
        ``(F, Q_k)``, each (n, n).
    """
    A_ = _matrix("A", A)
    n = A_.shape[0]
    _check_shape("A", A_, (n, n))
    W_ = _matrix("W", W)
    _check_shape("W", W_, (n, n))
    if not (math.isfinite(T) and T >= 0.0):
        raise ValueError(f"the sampling period T must be finite and >= 0 s, got {T!r}")
    if method == "euler":
        return np.eye(n) + A_ * T, W_ * T
    if method != "exact":
        raise ValueError(f"method must be 'exact' or 'euler', got {method!r}")
    M = np.zeros((2 * n, 2 * n))
    M[:n, :n] = -A_
    M[:n, n:] = W_
    M[n:, n:] = A_.T
    E = scipy.linalg.expm(M * T)
    F = E[n:, n:].T
    Qk = F @ E[:n, n:]
    return F, 0.5 * (Qk + Qk.T)


def double_integrator() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(A, C)`` of one DOF in Tomera's (2011) state order ``[velocity, position]``, eqs. 56-59."""
    return np.array([[0.0, 0.0], [1.0, 0.0]]), np.array([[0.0, 1.0]])


# --------------------------------------------------------------------------------------------
# Design data
# --------------------------------------------------------------------------------------------

_Matrix = tuple[tuple[float, ...], ...]
_DOFS = ("x", "y", "psi")


def _per_dof_matrices(name: str, value: Any) -> tuple[_Matrix, _Matrix, _Matrix]:
    """One matrix for all DOFs, or three (x, y, psi), as nested tuples of floats."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):  # ragged: three matrices of different shapes
        arr = None
    if arr is not None and arr.ndim <= 2:
        m = _as_tuple(_matrix(name, arr))
        return (m, m, m)
    items = list(arr) if arr is not None else list(value)
    if len(items) != 3:
        raise ValueError(
            f"{name} must be one matrix for all DOFs or three (x, y, psi), got {value!r}"
        )
    a, b, c = (_as_tuple(_matrix(f"{name}[{dof}]", v)) for dof, v in zip(_DOFS, items, strict=True))
    return (a, b, c)


def _as_tuple(M: NDArray[np.float64]) -> _Matrix:
    return tuple(tuple(float(v) for v in row) for row in M)


@dataclass(frozen=True)
class KalmanDesign:
    """Design matrices of the per-DOF double-integrator KF/KBF (Tomera 2011 eqs. 56-62).

    The three DOFs ``x``, ``y`` (NED, m) and ``psi`` (rad) are independent double integrators
    with state ``[velocity, position]`` (Tomera 2011 eq. 59); ``G`` and ``Q`` are in that order.

    Attributes:
        G: process noise input matrix per DOF, (2, m), one for all DOFs or three.
        Q: process noise *intensity* per DOF, (m, m): ``G Q G^T`` in (m^2/s^3, m^2/s) for x, y
            and (rad^2/s^3, rad^2/s) for psi (velocity row first).
        R: variance of one sampled measurement per DOF ``(x, y, psi)`` in (m^2, m^2, rad^2).
            The continuous filter uses the intensity ``R T`` (Tomera 2011 eq. 35).
        T: nominal sampling period (s); the filters rebuild ``F``, ``Q_k`` for the actual
            interval between calls, the steady-state gains are designed at ``T``.
        discretisation: ``"exact"`` (Van Loan) or ``"euler"`` (Tomera 2011 eqs. 5, 31:
            ``Q_k = G Q G^T T``).
        model: ``"double-integrator"`` (the only model of Tomera (2011) section 5).
    """

    G: tuple = param(((1.0, 0.0), (0.0, 1.0)), "-", "Tomera (2011) eqs. 61-62 (noise input matrix)")
    Q: tuple = param(
        ((1e-4, 0.0), (0.0, 1e-4)), "m^2/s^3, m^2/s (rad for psi)", "Tomera (2011) eqs. 61-62"
    )
    R: tuple = param(
        (POSITION_VARIANCE_TOMERA2011, POSITION_VARIANCE_TOMERA2011, HEADING_VARIANCE_TOMERA2011),
        "m^2, m^2, rad^2",
        "Tomera (2011) section 5: R_x = R_y = 0.01, R_psi = 0.1 (deg^2)",
    )
    T: float = param(1.0, "s", "Tomera (2014): 'sampling time equal 1 (s)'")
    discretisation: str = param("exact", "-", "Tomera (2011) eqs. 5, 31 ('euler') or Van Loan")
    model: str = param("double-integrator", "-", "Tomera (2011) eqs. 56-59")

    def __post_init__(self) -> None:
        if self.model != "double-integrator":
            raise ValueError(f"model must be 'double-integrator', got {self.model!r}")
        if self.discretisation not in ("exact", "euler"):
            raise ValueError(
                f"discretisation must be 'exact' or 'euler', got {self.discretisation!r}"
            )
        if not (isinstance(self.T, int | float) and math.isfinite(self.T) and self.T > 0):
            raise ValueError(
                f"T (nominal sampling period, s) must be finite and > 0, got {self.T!r}"
            )
        object.__setattr__(self, "T", float(self.T))
        G = _per_dof_matrices("G", self.G)
        Q = _per_dof_matrices("Q", self.Q)
        R = np.array(self.R, dtype=float)
        if R.ndim == 0:
            R = np.full(3, float(R))
        if R.shape != (3,):
            raise ValueError(f"R must be one variance or three (x, y, psi), got {self.R!r}")
        A, C = double_integrator()
        for i, dof in enumerate(_DOFS):
            Gi, Qi = np.array(G[i]), np.array(Q[i])
            if Gi.shape[0] != 2:
                raise ValueError(
                    f"G for {dof} must have 2 rows (velocity, position), got {Gi.shape}"
                )
            if Qi.shape != (Gi.shape[1], Gi.shape[1]):
                raise ValueError(
                    f"Q for {dof} must be {Gi.shape[1]}x{Gi.shape[1]} to match G, got {Qi.shape}"
                )
            try:
                _validate(A, Gi, C, Qi, R[i : i + 1], ("A", "G", "C"), discrete=False)
            except ValueError as exc:
                raise ValueError(f"KalmanDesign, DOF {dof}: {exc}") from None
        object.__setattr__(self, "G", G)
        object.__setattr__(self, "Q", Q)
        object.__setattr__(self, "R", tuple(float(r) for r in R))

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> KalmanDesign:
        """Build from a mapping of field names; unknown keys raise ``ValueError``."""
        return from_mapping(cls, d, where="KalmanDesign")

    def replace(self, **changes: Any) -> KalmanDesign:
        """A copy with some fields replaced (validated again)."""
        return dataclasses.replace(self, **changes)

    def intensity(self) -> NDArray[np.float64]:
        """``G Q G^T`` per DOF, (3, 2, 2), seed order ``[velocity, position]``."""
        return np.stack(
            [np.array(g) @ np.array(q) @ np.array(g).T for g, q in zip(self.G, self.Q, strict=True)]
        )

    def variance(self) -> NDArray[np.float64]:
        """Measurement variances ``(R_x, R_y, R_psi)`` (m^2, m^2, rad^2), (3,)."""
        return np.array(self.R)

    def sampled(self, dt: float | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(F, Q_k)`` for an interval ``dt`` (default ``T``): (2, 2) and (3, 2, 2)."""
        dt = self.T if dt is None else float(dt)
        A, _ = double_integrator()
        method: Literal["exact", "euler"] = "euler" if self.discretisation == "euler" else "exact"
        out = [discretise(A, W, dt, method=method) for W in self.intensity()]
        return out[0][0], np.stack([q for _, q in out])

    def dkf_gains(
        self, *, form: Literal["predictor", "filter"] = "filter", dt: float | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.complex128]]:
        """Steady-state discrete gains per DOF by :func:`dlqe` at ``dt`` (default ``T``).

        Returns:
            ``L`` (3, 2) in seed order ``[velocity, position]``, the predicted covariance
            ``P_bar`` (3, 2, 2) and the poles ``E`` (3, 2).
        """
        F, Qk = self.sampled(dt)
        _, H = double_integrator()
        res = [dlqe(F, np.eye(2), H, q, r, form=form) for q, r in zip(Qk, self.R, strict=True)]
        return (
            np.stack([L[:, 0] for L, _, _ in res]),
            np.stack([P for _, P, _ in res]),
            np.stack([E for _, _, E in res]),
        )

    def kbf_gains(
        self,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.complex128]]:
        """Steady-state Kalman-Bucy gains per DOF by :func:`lqe` (Tomera 2014 eqs. 33-35).

        Uses the measurement intensity ``R_c = R T`` (Tomera 2011 eq. 35).

        Returns:
            ``L`` (3, 2) in seed order ``[velocity, position]``, ``P`` (3, 2, 2), ``E`` (3, 2).
        """
        A, C = double_integrator()
        res = [
            lqe(A, np.array(g), C, np.array(q), r * self.T)
            for g, q, r in zip(self.G, self.Q, self.R, strict=True)
        ]
        return (
            np.stack([L[:, 0] for L, _, _ in res]),
            np.stack([P for _, P, _ in res]),
            np.stack([E for _, _, E in res]),
        )


def _tomera(discretisation: str) -> KalmanDesign:
    R = (POSITION_VARIANCE_TOMERA2011, POSITION_VARIANCE_TOMERA2011, HEADING_VARIANCE_TOMERA2011)
    Q = tuple(_as_tuple(0.01 * r * np.eye(2)) for r in R)
    return KalmanDesign(G=_as_tuple(np.eye(2)), Q=Q, R=R, T=1.0, discretisation=discretisation)


TOMERA_DKF = _tomera("euler")
"""Tomera's (2014) discrete KF design for the Blue Lady (preset ``tomera-dkf``): ``G = I``,
``Q = 0.01 R I`` numerically per DOF (``R`` the sensor variance in m^2 or rad^2), ``T = 1 s``,
``Q_k = G Q G^T T`` (Tomera 2011 eq. 31); filter-form gain ``[0.07945, 0.36868]`` (eq. 30)."""

TOMERA_KBF = _tomera("euler")
"""Tomera's (2014) Kalman-Bucy design for the Blue Lady (preset ``tomera-kbf``; the same
matrices as :data:`TOMERA_DKF`, measurement intensity ``R_c = R T``): ``L = [0.1, 0.45826]``
(eq. 35)."""

ACCEL_PSD_XY = 1.5e-4
"""The Blue Lady's tuned white-noise acceleration intensity in x, y (m^2/s^3; DKF_DESIGN)."""

ACCEL_PSD_PSI = 1e-6
"""The Blue Lady's tuned white-noise yaw acceleration intensity (rad^2/s^3; DKF_DESIGN)."""


def _tuned() -> KalmanDesign:
    return KalmanDesign(
        G=((1.0,), (0.0,)),
        Q=(((ACCEL_PSD_XY,),), ((ACCEL_PSD_XY,),), ((ACCEL_PSD_PSI,),)),
        R=(POSITION_VARIANCE_TOMERA2011, POSITION_VARIANCE_TOMERA2011, HEADING_VARIANCE_TOMERA2011),
        T=1.0,
        discretisation="exact",
    )


DKF_DESIGN = _tuned()
"""Tuned design for the Blue Lady (presets ``dkf``, ``kbf``): white-noise acceleration.

``G = [1, 0]^T`` (noise on the velocity only: the position is the exact integral of the
velocity, no position random walk), ``Q = q``, exact discretisation (Van Loan), the default
sensor variances as ``R`` (0.01 m^2, 0.1 deg^2) and ``T = 1 s``.

Choice of ``q`` (white-noise acceleration intensity): for a constant acceleration ``a`` the
steady-state velocity error of this filter is ``sqrt(2) a / w`` and its velocity noise
variance ``sqrt(2) w^3 R T``, with the bandwidth ``w = (q / (R T))^(1/4)``; their sum is
smallest at ``w^5 ~ 0.94 a^2 / (R T)``: ``w ~ 0.3 rad/s`` for the reference accelerations of
the harbour manoeuvre (surge 0.005 m/s^2 with ``R = 0.01 m^2``; yaw 2.5e-4 rad/s^2 with
``R_psi = 3e-5 rad^2``), i.e. ``q = w^4 R T ~ 8e-5 m^2/s^3`` and ``3e-7 rad^2/s^3``. In the
closed loop (PID-type DP controller, 5-leg manoeuvre, 3 m/s wind with gusts, seeds 0-9) the
real motion has more high-frequency content than the smooth reference and estimation lag
feeds back into the control: velocity errors were lowest for ``q_xy = 1e-4 ... 2e-4`` and
``q_psi ~ 1e-6`` (with ``q_xy = 5e-5`` the Kalman-Bucy filter's extra lag let the ship
overshoot into the quay in 1 of 10 runs). Chosen: ``q_xy = 1.5e-4 m^2/s^3``
(``w = 0.35 rad/s``) and ``q_psi = 1e-6 rad^2/s^3`` (``w = 0.43 rad/s``). The paper's design
(:data:`TOMERA_DKF`, ``w = 0.32 rad/s`` in every DOF) is close in x, y; the tuned presets
differ mainly in the heading channel, the time-varying covariance (fast start, dropouts),
the exact discretisation, the first-order-hold KBF and the outlier gate.
"""

KBF_DESIGN = DKF_DESIGN
"""The Blue Lady's tuned Kalman-Bucy design: the same matrices as :data:`DKF_DESIGN`."""
