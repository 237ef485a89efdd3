"""Pure LQ design functions in python-control's conventions: ``lqr``, ``dlqr``.

``K, S, E = lqr(A, B, Q, R)``: the gain for ``u = -K x``, the Riccati solution and the
closed-loop eigenvalues (as ``control.lqr``). Pure NumPy/SciPy (the LQ controller in
:mod:`~shipgym.controllers.lq` and Grimble's design in :mod:`~shipgym.controllers.grimble`
use them).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

__all__ = ["dlqr", "lqr"]

Array = NDArray[np.float64]


def _check_lq(
    A: ArrayLike, B: ArrayLike, Q: ArrayLike, R: ArrayLike, N: ArrayLike | None
) -> tuple[Array, Array, Array, Array, Array]:
    A_ = np.atleast_2d(np.asarray(A, dtype=float))
    B_ = np.atleast_2d(np.asarray(B, dtype=float))
    Q_ = np.atleast_2d(np.asarray(Q, dtype=float))
    R_ = np.atleast_2d(np.asarray(R, dtype=float))
    n = A_.shape[0]
    if A_.shape != (n, n):
        raise ValueError(f"A must be square, got shape {A_.shape}")
    if B_.shape[0] != n:
        raise ValueError(f"B must have {n} rows (like A), got shape {B_.shape}")
    m = B_.shape[1]
    if Q_.shape != (n, n):
        raise ValueError(f"Q must be {n}x{n}, got shape {Q_.shape}")
    if R_.shape != (m, m):
        raise ValueError(f"R must be {m}x{m}, got shape {R_.shape}")
    N_ = np.zeros((n, m)) if N is None else np.atleast_2d(np.asarray(N, dtype=float))
    if N_.shape != (n, m):
        raise ValueError(f"N must be {n}x{m}, got shape {N_.shape}")
    for name, X in (("A", A_), ("B", B_), ("Q", Q_), ("R", R_), ("N", N_)):
        if not np.all(np.isfinite(X)):
            raise ValueError(f"{name} contains NaN or infinite values")
    if not np.allclose(Q_, Q_.T) or not np.allclose(R_, R_.T):
        raise ValueError("Q and R must be symmetric")
    if np.min(np.linalg.eigvalsh(R_)) <= 0:
        raise ValueError("R must be positive definite")
    return A_, B_, Q_, R_, N_


def lqr(
    A: ArrayLike, B: ArrayLike, Q: ArrayLike, R: ArrayLike, N: ArrayLike | None = None
) -> tuple[Array, Array, NDArray[np.complex128]]:
    r"""lqr(A, B, Q, R[, N]): continuous-time linear quadratic regulator.

    Minimises :math:`J = \int_0^\infty (x^T Q x + u^T R u + 2 x^T N u)\,dt` for
    :math:`\dot x = A x + B u` with the state feedback :math:`u = -K x`, where ``S`` solves the
    continuous algebraic Riccati equation

    .. math:: A^T S + S A - (S B + N) R^{-1} (B^T S + N^T) + Q = 0

    and :math:`K = R^{-1} (B^T S + N^T)`. Same conventions and return tuple as
    ``control.lqr`` (python-control).

    Args:
        A: state matrix, shape (n, n).
        B: input matrix, shape (n, m).
        Q: state weight, symmetric positive semidefinite, shape (n, n).
        R: input weight, symmetric positive definite, shape (m, m).
        N: cross weight, shape (n, m); default zero.

    Returns:
        ``(K, S, E)``: gain (m, n), Riccati solution (n, n), closed-loop eigenvalues
        ``eig(A - B K)`` (n,).

    Raises:
        ValueError: inconsistent shapes, non-finite entries, ``R`` not positive definite, or
            no stabilising solution (e.g. ``(A, B)`` not stabilisable).
    """
    A_, B_, Q_, R_, N_ = _check_lq(A, B, Q, R, N)
    try:
        S = scipy.linalg.solve_continuous_are(A_, B_, Q_, R_, s=N_)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ValueError(f"no stabilising solution of the CARE: {exc}") from None
    K = np.linalg.solve(R_, B_.T @ S + N_.T)
    E = np.linalg.eigvals(A_ - B_ @ K)
    return K, S, E


def dlqr(
    A: ArrayLike, B: ArrayLike, Q: ArrayLike, R: ArrayLike, N: ArrayLike | None = None
) -> tuple[Array, Array, NDArray[np.complex128]]:
    r"""dlqr(A, B, Q, R[, N]): discrete-time linear quadratic regulator.

    Minimises :math:`J = \sum_k (x_k^T Q x_k + u_k^T R u_k + 2 x_k^T N u_k)` for
    :math:`x_{k+1} = A x_k + B u_k` with :math:`u_k = -K x_k`, where ``S`` solves the discrete
    algebraic Riccati equation

    .. math:: S = A^T S A - (A^T S B + N)(R + B^T S B)^{-1}(B^T S A + N^T) + Q

    and :math:`K = (R + B^T S B)^{-1}(B^T S A + N^T)`. Same conventions and return tuple as
    ``control.dlqr``.

    Args:
        A, B, Q, R, N: as in :func:`lqr`, for the discrete model.

    Returns:
        ``(K, S, E)``: gain, Riccati solution, closed-loop eigenvalues ``eig(A - B K)``
        (inside the unit circle).

    Raises:
        ValueError: as in :func:`lqr`.
    """
    A_, B_, Q_, R_, N_ = _check_lq(A, B, Q, R, N)
    try:
        S = scipy.linalg.solve_discrete_are(A_, B_, Q_, R_, s=N_)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ValueError(f"no stabilising solution of the DARE: {exc}") from None
    K = np.linalg.solve(R_ + B_.T @ S @ B_, B_.T @ S @ A_ + N_.T)
    E = np.linalg.eigvals(A_ - B_ @ K)
    return K, S, E
