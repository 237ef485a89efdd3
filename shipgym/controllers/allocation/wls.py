r"""Box-constrained weighted least-squares allocation for N fixed-direction thrusters.

``tau = B f``; ``min_f (B f - tau)^T W (B f - tau) + f^T H f`` s.t. ``f_min <= f <= f_max``
(Fossen 2011 sec. 12.3), an active-set solution.

Public names: ``DEFAULT_H_REL``, ``WLSAllocation``, ``WLSAllocator``, ``allocate_wls``.
Sources: Fossen (2011); Johansen & Fossen (2013); Nocedal & Wright (2006).

Design notes: docs/design/controllers.allocation.wls.md.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import prange, types
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import (
    _DISABLED,
    address,
    entry,
    function_at,
    law_input,
    njit,
    threads_ok,
    use_threads,
)

__all__ = ["DEFAULT_H_REL", "WLSAllocation", "WLSAllocator", "allocate_wls", "run_wls", "wls_law"]

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


# ---- the solver: one compiled law over N requests -------------------------------------------
@njit
def cholesky(M, L):  # type: ignore[no-untyped-def]
    """Lower Cholesky factor of ``M`` into ``L``: False where ``M`` is not positive definite
    (the allocation laws' one factorisation)."""
    n = M.shape[0]
    for j in range(n):
        d = M[j, j]
        for k in range(j):
            d -= L[j, k] * L[j, k]
        if not d > 0.0:
            return False
        d = math.sqrt(d)
        L[j, j] = d
        for i in range(j + 1, n):
            t = M[i, j]
            for k in range(j):
                t -= L[i, k] * L[j, k]
            L[i, j] = t / d
    return True


@njit(inline="always")
def _cholesky_solve(M, b, L, y, x):  # type: ignore[no-untyped-def]
    """``x = M^-1 b`` by Cholesky (``L`` scratch, lower): False where ``M`` is not positive
    definite."""
    n = b.shape[0]
    if not cholesky(M, L):
        return False
    for i in range(n):
        t = b[i]
        for k in range(i):
            t -= L[i, k] * y[k]
        y[i] = t / L[i, i]
    for i in range(n - 1, -1, -1):
        t = y[i]
        for k in range(i + 1, n):
            t -= L[k, i] * x[k]
        x[i] = t / L[i, i]
    return True


@njit(inline="always")
def _box_qp(Q, c, lo, hi, x, active, st, M, rhs, xn, L, y):  # type: ignore[no-untyped-def]
    """Exact ``argmin 0.5 x^T Q x - c^T x`` over ``lo <= x <= hi`` (Q positive definite) into
    ``x``, and per variable whether its bound is active (non-zero multiplier of the right
    sign) into ``active``; the rest are scratch. Returns 0, 1 (``Q`` not positive definite)
    or 2 (no convergence).

    Primal active-set method on the bounds (Nocedal & Wright 2006 alg. 16.3). Each step solves
    the problem on the free variables with the others held at their bounds, written as one
    n x n positive-definite system (the held rows and columns replaced by the identity).
    """
    n = c.shape[0]
    if not _cholesky_solve(Q, c, L, y, x):
        return 1
    inside = True
    for i in range(n):
        active[i] = False
        if not (x[i] >= lo[i] - _BOUND_TOL and x[i] <= hi[i] + _BOUND_TOL):
            inside = False
    if inside:
        for i in range(n):
            x[i] = min(max(x[i], lo[i]), hi[i])
        return 0
    # state per variable: 0 free, -1 on its lower bound, +1 on its upper bound, 2 held (lo = hi)
    for i in range(n):
        v = x[i]
        if lo[i] == hi[i]:
            st[i] = 2
        elif v <= lo[i]:
            st[i] = -1
        elif v >= hi[i]:
            st[i] = 1
        else:
            st[i] = 0
        x[i] = lo[i] if v < lo[i] else hi[i] if v > hi[i] else v
    for _ in range(10 * n + 10):
        free = False
        for i in range(n):
            free |= st[i] == 0
        if free:
            for i in range(n):
                t = c[i]
                for k in range(n):
                    if st[k] != 0:
                        t -= Q[i, k] * x[k]
                rhs[i] = t if st[i] == 0 else x[i]
                for k in range(n):
                    M[i, k] = Q[i, k] if st[i] == 0 and st[k] == 0 else 0.0
                if st[i] != 0:
                    M[i, i] = 1.0
            _cholesky_solve(M, rhs, L, y, xn)
            # ratio test: the largest step in [0, 1] towards xn that stays in the box
            alpha, j = 1.0, -1
            for i in range(n):
                if st[i] == 0:
                    v, t = x[i], xn[i]
                    if t < lo[i] and t < v:
                        a = (lo[i] - v) / (t - v)
                    elif t > hi[i] and t > v:
                        a = (hi[i] - v) / (t - v)
                    else:
                        continue
                    if a < alpha:
                        alpha, j = a, i
            if j >= 0:
                alpha = max(alpha, 0.0)
                for i in range(n):
                    if st[i] == 0:
                        x[i] = x[i] + alpha * (xn[i] - x[i])
                if xn[j] < lo[j]:
                    x[j], st[j] = lo[j], -1
                else:
                    x[j], st[j] = hi[j], 1
                continue
            for i in range(n):
                if st[i] == 0:
                    x[i] = xn[i]
        # multipliers, in units of each variable's own curvature (the distance it would move
        # past its bound if released): >= 0 on lower bounds, <= 0 on upper bounds when optimal
        worst, j = -_MULT_TOL, -1
        for i in range(n):
            g = -c[i]
            for k in range(n):
                g += Q[i, k] * x[k]
            g /= Q[i, i]
            y[i] = g
            if st[i] == -1 or st[i] == 1:
                m = -st[i] * g  # the multiplier of the bound
                if m < worst:
                    worst, j = m, i
        if j < 0:
            for i in range(n):
                k, g = st[i], y[i]
                active[i] = (
                    (k == -1 and g > _ACTIVE_TOL)
                    or (k == 1 and g < -_ACTIVE_TOL)
                    or (k == 2 and abs(g) > _ACTIVE_TOL)
                )
            return 0
        st[j] = 0
    return 2


@njit
def wls_law(first, end, Q, R, xlo, xhi, s, lo, hi, B, tau, force, delivered, error, active):  # type: ignore[no-untyped-def]
    """The box-constrained weighted least-squares allocation of the requests ``first .. end -
    1`` of N (:func:`allocate_wls` documents the problem), one after the other, each with the
    same floats whatever the range (:func:`wls_threads` runs ranges on threads).

    Args:
        first, end: the rows allocated (int64).
        Q, R: the scaled problem (:func:`_scaled_problem`), (n, n) and (n, n_dof).
        xlo, xhi: the scaled bounds ``lo / s``, ``hi / s`` (n,); ``s`` the scales (n,).
        lo, hi: the thrust limits (N) (n,); ``B``: the configuration matrix (n_dof, n).
        tau: (N, n_dof) the requests (N and N m).
        force, delivered, error, active: out, (N, n), (N, n_dof), (N, n_dof), (N, n) bool:
            the thrusts (exactly on a bound where the scaled one is), ``B f``, ``tau - B f``
            and the active bounds.

    Returns:
        0, or the first failing request's index + 1 times 4 plus the reason (1: ``Q`` not
        positive definite; 2: no convergence; 3: a request not finite).
    """
    n_dof = tau.shape[1]
    n = s.shape[0]
    c = np.empty(n)
    x = np.empty(n)
    st = np.empty(n, np.int64)
    M = np.empty((n, n))
    rhs = np.empty(n)
    xn = np.empty(n)
    L = np.zeros((n, n))
    y = np.empty(n)
    for r in range(first, end):
        for i in range(n_dof):
            if not math.isfinite(tau[r, i]):
                return 4 * (r + 1) + 3
        for i in range(n):
            t = 0.0
            for k in range(n_dof):
                t += R[i, k] * tau[r, k]
            c[i] = t
        why = _box_qp(Q, c, xlo, xhi, x, active[r], st, M, rhs, xn, L, y)
        if why:
            return 4 * (r + 1) + why
        for i in range(n):
            if x[i] <= xlo[i]:
                force[r, i] = lo[i]
            elif x[i] >= xhi[i]:
                force[r, i] = hi[i]
            else:
                force[r, i] = min(max(x[i] * s[i], lo[i]), hi[i])
        for k in range(n_dof):
            t = 0.0
            for i in range(n):
                t += B[k, i] * force[r, i]
            delivered[r, k] = t
            error[r, k] = tau[r, k] - t
    return 0


_F1, _F2 = types.float64[::1], types.float64[:, ::1]
#: :func:`wls_law`'s one signature (its address is called on Numba's threads)
WLS_SIG = types.int64(types.int64, types.int64, _F2, _F2, *([_F1] * 5), _F2, _F2, _F2, _F2, _F2,
                      types.boolean[:, ::1])  # fmt: skip
_wls_at = function_at(WLS_SIG)


@njit(parallel=True)
def wls_threads(at, Q, R, xlo, xhi, s, lo, hi, B, tau, force, delivered, error, active):  # type: ignore[no-untyped-def]
    """:func:`wls_law` (compiled at the address ``at``) on ranges of the requests on Numba's
    threads: the one compiled law, called through its address (a direct call would compile
    the law again into this one), each request the floats it gets alone, and the code of the
    first failing request, as one call on every request gives it. A batch takes about 1 us a
    request: too short for Python threads, whose wake-up costs hundreds of microseconds on a
    VM, where Numba's threads spin between back-to-back calls."""
    go = _wls_at(at)
    N = tau.shape[0]
    chunks = min(N, 64)
    size = (N + chunks - 1) // chunks
    codes = np.zeros(chunks, dtype=np.int64)
    for c in prange(chunks):
        codes[c] = go(min(c * size, N), min((c + 1) * size, N), Q, R, xlo, xhi, s, lo, hi, B,
                      tau, force, delivered, error, active)  # fmt: skip
    for c in range(chunks):
        if codes[c]:
            return codes[c]
    return 0


#: the fewest requests allocated on Numba's threads (:func:`wls_threads`)
PARALLEL_MIN = 64
_WLS: list[Any] = []  # the law's compiled entry point


def run_wls(Q, R, xlo, xhi, s, lo, hi, B, tau):  # type: ignore[no-untyped-def]
    """:func:`wls_law` on ``tau`` (N, n_dof) through its compiled entry point: ``(force,
    delivered, error, active)``.

    Raises:
        ValueError: a request with NaN or infinite values, or ``Q`` not positive definite.
        RuntimeError: the active-set method did not converge.
    """
    # C-contiguous float64 throughout: the one compiled entry point is typed for that layout
    # (a transposed B, as a configuration matrix built column by column is, would be misread)
    return _run_wls(_problem(Q, R, xlo, xhi, s, lo, hi, B), tau)


def _problem(*arrays: Any) -> tuple[NDArray[np.float64], ...]:
    """:func:`run_wls`'s problem arrays ``(Q, R, xlo, xhi, s, lo, hi, B)`` as its compiled
    entry point is typed (:func:`~shipgym._jit.law_input`)."""
    return tuple(law_input(a) for a in arrays)


def _run_wls(problem: tuple[NDArray[np.float64], ...], tau: ArrayLike) -> tuple[Any, ...]:
    """:func:`run_wls` of a problem of :func:`_problem` (prepared once by a
    :class:`WLSAllocator`)."""
    t = law_input(tau)
    N, n = t.shape[0], problem[4].shape[0]
    out = (np.empty((N, n)), np.empty((N, t.shape[1])), np.empty((N, t.shape[1])),
           np.empty((N, n), dtype=np.bool_))  # fmt: skip
    args = (*problem, t, *out)
    if not _WLS:
        _WLS.append(entry(wls_law, (np.int64(0), np.int64(N), *args)))
    fn = _WLS[0]
    if N >= PARALLEL_MIN and threads_ok() and not _DISABLED:
        use_threads()
        code = wls_threads(address(wls_law, WLS_SIG), *args)
    else:
        code = fn(0, N, *args)
    if code:
        row, why = divmod(code, 4)
        if why == 3:
            raise ValueError(f"tau contains NaN or infinite values: {t[row - 1].tolist()}")
        if why == 1:
            raise ValueError(_SINGULAR)
        raise RuntimeError("allocate_wls: the active-set method did not converge (report this)")
    return out


class WLSAllocator:
    """:func:`allocate_wls` for one thruster set, prepared once: the hot path of a controller.

    Validates ``B``, the limits and the weights and builds the scaled problem and its Cholesky
    factor at construction; a call validates only ``tau`` (shape, finite). ``allocator(tau)``
    equals ``allocate_wls(tau, B, f_min, f_max, W=W, H=H)`` (same arguments and result; see
    there).
    """

    __slots__ = ("B", "f_min", "f_max", "_s", "_lo", "_hi", "_Q", "_BsWk", "_n_dof", "_problem")

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
        if not np.all(np.linalg.eigvalsh(Q) > 0.0):
            raise ValueError(_SINGULAR)
        for a in (Bm, lo, hi):
            a.flags.writeable = False
        self.B, self.f_min, self.f_max = Bm, lo, hi
        self._s, self._lo, self._hi = s, lo / s, hi / s
        self._Q, self._BsWk, self._n_dof = Q, np.ascontiguousarray(BsWk), n_dof
        self._problem = _problem(self._Q, self._BsWk, self._lo, self._hi, self._s, self.f_min,
                                 self.f_max, self.B)  # fmt: skip

    def __call__(self, tau: ArrayLike) -> WLSAllocation:
        """The allocation of ``tau`` (shape (n_dof,), N and N m)."""
        t = _real_array(tau, "tau", (self._n_dof,), "requested generalised force, N and N m")
        f, delivered, error, active = self.batch(t.reshape(1, -1))
        return WLSAllocation(f[0], delivered[0], error[0], active[0])

    def batch(self, tau: ArrayLike) -> tuple[NDArray[np.float64], ...]:
        """The allocations of N requests ``tau`` (N, n_dof) (:func:`wls_law`): ``(force,
        delivered, tau_error, saturated)``, each with a leading axis N."""
        return _run_wls(self._problem, tau)


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
    f, delivered, error, active = run_wls(Q, np.ascontiguousarray(BsWk), lo / s, hi / s, s, lo,
                                          hi, Bm, t.reshape(1, -1))  # fmt: skip
    return WLSAllocation(f[0], delivered[0], error[0], active[0])
