r"""Box-constrained weighted least-squares allocation for N fixed-direction thrusters.

``tau = B f``; ``min_f (B f - tau)^T W (B f - tau) + f^T H f`` s.t. ``f_min <= f <= f_max``
(Fossen 2011 sec. 12.3), an active-set solution.

Public names: ``DEFAULT_H_REL``, ``WLSAllocation``, ``WLSAllocator``, ``allocate_wls``.
Sources: Fossen (2011); Johansen & Fossen (2013); Nocedal & Wright (2006).

Design notes: docs/design/controllers.allocation.wls.md.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg.lapack import dposv as _dposv
from scipy.linalg.lapack import dpotrf as _dpotrf
from scipy.linalg.lapack import dpotrs as _dpotrs

__all__ = ["DEFAULT_H_REL", "WLSAllocation", "WLSAllocator", "allocate_wls"]

#: default regularisation: ``H`` in scaled thrusts is this fraction of the mean curvature
DEFAULT_H_REL = 1e-9
#: a scaled thrust within this of a bound counts as on it (thrusts scaled to <= 1)
_BOUND_TOL = 1e-12
#: a bound whose multiplier (divided by the variable's curvature: the scaled distance it would
#: move past the bound if released) has the wrong sign by more than this is released
_MULT_TOL = 1e-10
#: ... and above this the bound counts as active for the ``saturated`` flag: larger than the
#: push of the default regularisation H (about DEFAULT_H_REL), so a redundant set that meets
#: its request is not reported saturated because H prefers a thrust beyond a bound
_ACTIVE_TOL = 1e-7
_SINGULAR = (
    "B^T W B + diag(H) is singular: the thrusters are redundant or some thruster affects no "
    "weighted DOF; give H > 0 (the default) for a unique answer"
)


class WLSAllocation(NamedTuple):
    """The result of :func:`allocate_wls`.

    Attributes:
        force: thrusts ``f`` (N), shape (N,), within ``[f_min, f_max]`` exactly.
        tau: delivered generalised force ``B f``, shape (n_dof,) (N, N m).
        tau_error: requested minus delivered ``tau``, shape (n_dof,); round-off (plus the tiny
            bias of ``H``) when nothing saturates.
        saturated: shape (N,) bool: the thruster sits on a bound and the bound is active: its
            Lagrange multiplier, divided by the thrust's curvature in the objective (the
            distance, in units of its range, that the thrust would move past the bound if
            released), exceeds 1e-7.
    """

    force: NDArray[np.float64]
    tau: NDArray[np.float64]
    tau_error: NDArray[np.float64]
    saturated: NDArray[np.bool_]


# ---- validation (shared with the azimuth allocation) -----------------------------------------
def _real_array(x: ArrayLike, name: str, shape: tuple[int, ...], what: str) -> NDArray[np.float64]:
    """``x`` as a float array of ``shape`` with finite entries, or a ``ValueError``."""
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be real numbers ({what}), got {x!r}") from None
    if a.shape != shape:
        raise ValueError(f"{name} must have shape {shape} ({what}), got shape {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{name} contains NaN or infinite values: {a.tolist()}")
    return a


def _config_matrix(B: ArrayLike) -> NDArray[np.float64]:
    try:
        b = np.asarray(B, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"B must be a real (n_dof, N) matrix, got {B!r}") from None
    if b.ndim != 2 or b.shape[0] < 1 or b.shape[1] < 1:
        raise ValueError(f"B must have shape (n_dof, N) with n_dof, N >= 1, got shape {b.shape}")
    if not np.isfinite(b).all():
        raise ValueError("B contains NaN or infinite values")
    return b


def _bounds(f_min: ArrayLike, f_max: ArrayLike, n: int, *, zero_inside: bool = False):
    lo = _real_array(f_min, "f_min", (n,), "lower thrust of each thruster, N")
    hi = _real_array(f_max, "f_max", (n,), "upper thrust of each thruster, N")
    bad = lo > hi
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(f"f_min > f_max for thruster {i}: {lo[i]} > {hi[i]} N")
    if zero_inside and ((lo > 0.0) | (hi < 0.0)).any():
        i = int(np.flatnonzero((lo > 0.0) | (hi < 0.0))[0])
        raise ValueError(
            f"the range [f_min, f_max] = [{lo[i]}, {hi[i]}] N of fixed thruster {i} must "
            "contain 0 (zero thrust must always be feasible)"
        )
    return lo, hi


def _capacity(B: NDArray[np.float64], s: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rough capacity of each DOF: ``sum_j |B_ij| s_j`` (N or N m)."""
    return np.abs(B) @ s


def _weights(W: ArrayLike | None, n_dof: int, cap: NDArray[np.float64]) -> NDArray[np.float64]:
    """The weights: shape (n_dof,) (a diagonal) or (n_dof, n_dof); ``diag(1 / capacity^2)``
    by default."""
    if W is None:
        top = float(cap.max())
        c = np.where(cap > 0.0, cap, top if top > 0.0 else 1.0)  # a DOF no thruster reaches
        return 1.0 / (c * c)
    try:
        w = np.asarray(W, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(
            f"W must be real weights, shape ({n_dof},) or ({n_dof}, {n_dof})"
        ) from None
    if not np.isfinite(w).all():
        raise ValueError(f"W contains NaN or infinite values: {w.tolist()}")
    if w.shape == (n_dof,):
        if (w < 0.0).any():
            raise ValueError(f"W must be >= 0 (weights of the tau error), got {w.tolist()}")
        return w
    if w.shape == (n_dof, n_dof):
        if not np.allclose(w, w.T, rtol=1e-12, atol=0.0):
            raise ValueError("W must be symmetric")
        ev = np.linalg.eigvalsh(w)
        if ev[0] < -1e-12 * max(abs(ev[-1]), 1e-300):
            raise ValueError(f"W must be positive semi-definite, its eigenvalues are {ev}")
        return w
    raise ValueError(f"W must have shape ({n_dof},) or ({n_dof}, {n_dof}), got shape {w.shape}")


def _scaled_problem(
    B: NDArray[np.float64],
    s: NDArray[np.float64],
    w: NDArray[np.float64],
    H: ArrayLike | None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``Q = S (B^T W B + H) S / k`` and ``R = S B^T W / k`` of the thrusts ``x = f / s``.

    The objective is then ``0.5 x^T Q x - (R tau)^T x`` (up to a constant and the factor
    ``2 / k``). ``w`` is the weight diagonal (n_dof,) or matrix; ``k`` normalises the largest
    curvature to 1 (so multipliers and tolerances are relative). Returns ``(Q, R)``.
    """
    n = s.shape[0]
    Bs = B * s
    BsW = Bs.T * w if w.ndim == 1 else Bs.T @ w
    Q = BsW @ Bs
    diag = Q.reshape(-1)[:: n + 1]  # a view: writes go into Q
    if H is None:
        tr = float(diag.sum())
        diag += DEFAULT_H_REL * (tr / n if tr > 0.0 else 1.0)
    else:
        if np.ndim(H) == 0:
            H = np.full(n, H, dtype=float)
        h = _real_array(H, "H", (n,), "regularisation weight of each thrust, 1/N^2")
        if (h < 0.0).any():
            raise ValueError(f"H must be >= 0, got {h.tolist()}")
        diag += h * s * s
    k = float(diag.max())
    if not k > 0.0:
        raise ValueError("B^T W B + H is zero: no thruster affects a weighted DOF and H = 0")
    Q /= k
    BsW /= k
    return Q, BsW


def _scales(lo: NDArray[np.float64], hi: NDArray[np.float64]) -> NDArray[np.float64]:
    s = np.maximum(np.abs(lo), np.abs(hi))
    s[s == 0.0] = 1.0
    return s


# ---- the solver ----------------------------------------------------------------------------
def _box_qp(
    Q: NDArray[np.float64],
    c: NDArray[np.float64],
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
    fac: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Exact ``argmin 0.5 x^T Q x - c^T x`` over ``lo <= x <= hi`` (Q positive definite).

    Primal active-set method on the bounds (Nocedal & Wright 2006 alg. 16.3). Each step solves
    the problem on the free variables with the others held at their bounds, written as one
    n x n positive-definite system (the held rows and columns replaced by the identity) for
    LAPACK's ``dposv``. Returns the minimiser and, per variable, whether its bound is active
    (non-zero multiplier of the right sign).

    ``fac``: the lower Cholesky factor of ``Q`` if known (``dpotrf``).

    Raises:
        ValueError: ``Q`` is not positive definite.
    """
    n = c.shape[0]
    if fac is None:
        _, x, info = _dposv(Q, c, lower=1)
        if info != 0:
            raise ValueError(_SINGULAR)
    else:
        x, _ = _dpotrs(fac, c, lower=1)
    if ((x >= lo - _BOUND_TOL) & (x <= hi + _BOUND_TOL)).all():
        return np.minimum(np.maximum(x, lo), hi), np.zeros(n, dtype=bool)
    lol, hil = lo.tolist(), hi.tolist()
    xl = x.tolist()
    # state per variable: 0 free, -1 on its lower bound, +1 on its upper bound, 2 held (lo = hi)
    st = [
        2 if a == b else (-1 if v <= a else (1 if v >= b else 0))
        for v, a, b in zip(xl, lol, hil, strict=True)
    ]
    xl = [a if v < a else b if v > b else v for v, a, b in zip(xl, lol, hil, strict=True)]
    diag = np.arange(n) * (n + 1)
    qd = Q.diagonal()
    for _ in range(10 * n + 10):
        fm = np.array([1.0 if k == 0 else 0.0 for k in st])
        xv = np.array(xl)
        if 0 in st:
            am = 1.0 - fm
            xa = am * xv
            M = Q * np.outer(fm, fm)
            M.flat[diag] += am
            _, xn, _ = _dposv(M, fm * (c - Q @ xa) + xa)
            xnl = xn.tolist()
            # ratio test: the largest step in [0, 1] towards xn that stays in the box
            alpha, j = 1.0, -1
            for i in range(n):
                if st[i] == 0:
                    v, t = xl[i], xnl[i]
                    if t < lol[i] and t < v:
                        a = (lol[i] - v) / (t - v)
                    elif t > hil[i] and t > v:
                        a = (hil[i] - v) / (t - v)
                    else:
                        continue
                    if a < alpha:
                        alpha, j = a, i
            if j >= 0:
                alpha = max(alpha, 0.0)
                xl = [
                    v + alpha * (t - v) if k == 0 else v
                    for v, t, k in zip(xl, xnl, st, strict=True)
                ]
                if xnl[j] < lol[j]:
                    xl[j], st[j] = lol[j], -1
                else:
                    xl[j], st[j] = hil[j], 1
                continue
            xl = [t if k == 0 else v for v, t, k in zip(xl, xnl, st, strict=True)]
            xv = xn
        # multipliers, in units of each variable's own curvature (the distance it would move
        # past its bound if released): >= 0 on lower bounds, <= 0 on upper bounds when optimal
        g = ((Q @ xv - c) / qd).tolist()
        worst, j = -_MULT_TOL, -1
        for i in range(n):
            k = st[i]
            if k == -1 or k == 1:
                m = -k * g[i]  # the multiplier of the bound
                if m < worst:
                    worst, j = m, i
        if j < 0:
            active = [
                (k == -1 and gi > _ACTIVE_TOL)
                or (k == 1 and gi < -_ACTIVE_TOL)
                or (k == 2 and abs(gi) > _ACTIVE_TOL)
                for k, gi in zip(st, g, strict=True)
            ]
            return np.array(xl), np.array(active)
        st[j] = 0
    raise RuntimeError("allocate_wls: the active-set method did not converge (report this)")


def _unscale(x, s, xlo, xhi, lo, hi) -> NDArray[np.float64]:
    """Thrusts ``x * s``, exactly ``lo`` or ``hi`` where ``x`` sits on a bound."""
    return np.where(x <= xlo, lo, np.where(x >= xhi, hi, np.minimum(np.maximum(x * s, lo), hi)))


class WLSAllocator:
    """:func:`allocate_wls` for one thruster set, prepared once: the hot path of a controller.

    Validates ``B``, the limits and the weights and builds the scaled problem and its Cholesky
    factor at construction; a call validates only ``tau`` (shape, finite). ``allocator(tau)``
    equals ``allocate_wls(tau, B, f_min, f_max, W=W, H=H)`` (same arguments and result; see
    there).
    """

    __slots__ = ("B", "f_min", "f_max", "_s", "_lo", "_hi", "_Q", "_fac", "_BsWk", "_n_dof")

    def __init__(
        self,
        B: ArrayLike,
        f_min: ArrayLike,
        f_max: ArrayLike,
        *,
        W: ArrayLike | None = None,
        H: ArrayLike | None = None,
    ) -> None:
        Bm = _config_matrix(B)
        n_dof, n = Bm.shape
        lo, hi = _bounds(f_min, f_max, n)
        s = _scales(lo, hi)
        w = _weights(W, n_dof, _capacity(Bm, s))
        Q, BsWk = _scaled_problem(Bm, s, w, H)
        fac, info = _dpotrf(Q, lower=1)
        if info != 0:
            raise ValueError(_SINGULAR)
        for a in (Bm, lo, hi):
            a.flags.writeable = False
        self.B, self.f_min, self.f_max = Bm, lo, hi
        self._s, self._lo, self._hi = s, lo / s, hi / s
        self._Q, self._fac, self._BsWk, self._n_dof = Q, fac, BsWk, n_dof

    def __call__(self, tau: ArrayLike) -> WLSAllocation:
        """The allocation of ``tau`` (shape (n_dof,), N and N m)."""
        t = _real_array(tau, "tau", (self._n_dof,), "requested generalised force, N and N m")
        c = self._BsWk @ t
        x, active = _box_qp(self._Q, c, self._lo, self._hi, self._fac)
        f = _unscale(x, self._s, self._lo, self._hi, self.f_min, self.f_max)
        delivered = self.B @ f
        return WLSAllocation(f, delivered, t - delivered, active)


def allocate_wls(
    tau: ArrayLike,
    B: ArrayLike,
    f_min: ArrayLike,
    f_max: ArrayLike,
    *,
    W: ArrayLike | None = None,
    H: ArrayLike | None = None,
) -> WLSAllocation:
    r"""Exact box-constrained weighted least-squares thrust allocation (Fossen 2011 sec. 12.3).

    Minimises ``(B f - tau)^T W (B f - tau) + f^T diag(H) f`` subject to
    ``f_min <= f <= f_max`` (see the module docstring for the method). For repeated calls
    with the same thrusters, :class:`WLSAllocator` validates and factors once.

    Args:
        tau: requested generalised force, shape (n_dof,): ``[X, Y, N]`` or ``[X, Y, K, N]``
            (N, N m).
        B: configuration matrix, shape (n_dof, N): column ``j`` is the generalised force of a
            unit thrust of thruster ``j`` (``[cos a, sin a, x sin a - y cos a]`` for a thruster
            at ``(x, y)`` m pointing at angle ``a`` in 3 DOF; Fossen 2011 sec. 12.3).
        f_min, f_max: thrust limits (N), shape (N,), ``f_min <= f_max`` (equal: a thrust held).
        W: weights of the tau error, shape (n_dof,) (a diagonal, >= 0) or (n_dof, n_dof)
            (symmetric positive semi-definite), units 1/N^2 and 1/(N m)^2. ``None``:
            ``diag(1 / c_i^2)`` with ``c_i = sum_j |B_ij| max(|f_min_j|, |f_max_j|)`` the
            rough capacity of DOF ``i`` (every DOF's error in units of its capacity).
        H: regularisation weights of the thrusts, shape (N,) or a scalar, >= 0 (1/N^2).
            ``None``: ``DEFAULT_H_REL = 1e-9`` of the mean curvature of the objective in
            thrusts scaled by their limits (``f_j / max|f_j|``): it picks the least-thrust
            answer of a redundant set and biases ``tau`` by about 1e-9 of the capacity. ``0``
            is allowed where ``B^T W B`` is non-singular.

    Returns:
        The :class:`WLSAllocation`.

    Raises:
        ValueError: wrong shapes, NaN or infinite values, ``f_min > f_max``, negative or
            asymmetric weights, or a singular ``B^T W B + diag(H)`` (e.g. ``H = 0`` with a
            redundant ``B``).
    """
    Bm = _config_matrix(B)
    n_dof, n = Bm.shape
    t = _real_array(tau, "tau", (n_dof,), "requested generalised force, N and N m")
    lo, hi = _bounds(f_min, f_max, n)
    s = _scales(lo, hi)
    w = _weights(W, n_dof, _capacity(Bm, s))
    Q, BsWk = _scaled_problem(Bm, s, w, H)
    xlo, xhi = lo / s, hi / s
    x, active = _box_qp(Q, BsWk @ t, xlo, xhi)
    f = _unscale(x, s, xlo, xhi, lo, hi)
    delivered = Bm @ f
    return WLSAllocation(f, delivered, t - delivered, active)
