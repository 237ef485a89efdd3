r"""Grimble's LQ weights and the LQ gains of Al-Takie (1982) ch. 4 on the LF sway-yaw model.

Design (Al-Takie 1982 4.3, after Grimble's multivariable root-locus rules): for the square
system ``(A, B, C)`` whose first ``k`` Markov parameters ``C A^i B`` (``i < k``) are singular
and ``C A^k B`` is not,

.. math::

    Q_y = ((C A^k B N)^T)^{-1} (C A^k B N)^{-1}, \quad Q = C^T Q_y C, \quad
    R = f\,(N^T)^{-1} \Lambda_{k+1} N^{-1}, \quad
    \Lambda_{k+1} = (-1)^k \operatorname{diag}((1/\lambda_i)^{2(k+1)}),

with ``N`` the asymptotic closed-loop eigenvectors (``I``) and ``lambda_i`` the asymptotic
eigenvalue ratios. For Wimpey Sealab ``CB = CAB = 0``, so ``k = 2`` and
``C A^2 B = [[0.84243, 0.4216], [5.0654, -2.5327]]`` [printed]. The gain is the CARE solution
``K = R^-1 B^T S`` with ``u = -K x`` (python-control's convention); the thesis prints
``-K`` (its ``u = K x``), :data:`PRINTED_GAINS` keeps the printed sign.

Cases (Wimpey Sealab, ``f = 1``):

- ``"a"``: ``lambda_1 = 1.5 lambda_2`` (sway 1.5 x faster), ``R = f diag((1/1.5)^6, 1)``;
- ``"b"``: ``lambda_1 = lambda_2 = 1``, ``R = f I``: the selected design.

The Star Hercules gain printed in 4.5 is not re-derivable from the stated weights (its own
``C A^2 B`` is diagonal); it is used as printed (:data:`PRINTED_GAINS`).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .design import lqr

__all__ = [
    "PRINTED_GAINS",
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
