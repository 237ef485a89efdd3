r"""Azimuth-thruster allocation by the extended-thrust formulation, with angle-rate limits.

``fx_j = T_j cos(alpha_j)``, ``fy_j = T_j sin(alpha_j)``: a QP in the extended thrusts
with polygon magnitude limits and angle-rate sectors.

Public names: ``AzimuthAllocation``, ``AzimuthAllocator``, ``Azimuths``, ``allocate_azimuth``,
``extended_thrust_matrix``.
One compiled law over N requests (``azimuth_law``); the QPs by Goldfarb & Idnani's dual
active-set method.

Sources: Fossen (2011); Johansen & Fossen (2013); Goldfarb & Idnani (1983).

Design notes: docs/design/controllers.allocation.azimuth.md.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import entry, law_input, njit, spread_rows, threads_ok

from .wls import (
    _bounds,
    _capacity,
    _config_matrix,
    _real_array,
    _scaled_problem,
    _scales,
    _weights,
)
from .wls import cholesky as _cholesky

__all__ = [
    "AzimuthAllocation",
    "AzimuthAllocator",
    "Azimuths",
    "allocate_azimuth",
    "extended_thrust_matrix",
]

#: a limit is active (``saturated``) where its multiplier over the curvature of the variables it
#: acts on exceeds this (as in :mod:`.wls`: above the push of the default regularisation)
_ACTIVE_TOL = 1e-7
#: a force below this fraction of F_max has no direction: the unit keeps its angle
_ZERO_FORCE = 1e-12
_NO_BOUND = 1e30  # a row's "no lower bound"
#: a reversible unit's relaxed force more than this (of F_max) outside both of its sectors
#: makes its branch ambiguous: both are tried, for at most _MAX_TRIED such units
_BRANCH_TOL = 1e-9
_MAX_TRIED = 3
#: the local search keeps another branch where it lowers the cost by more than this (of the
#: cost's scale): not for round-off
_BETTER = 1e-9
#: the floor of the regularisation H in the scaled problem (Q scaled to a largest diagonal of
#: 1), so the dual method's Cholesky factor exists for any H >= 0: a smaller H acts as this
_MIN_CURV = 1e-12
#: a constraint violated by more than this (scaled forces, |x| <= 1) is added to the active set
_PRIMAL_TOL = 1e-10
#: a constraint whose normal's part outside the active normals (in the metric of Q^-1) is below
#: this fraction of its norm (squared) is linearly dependent on them
_DEPENDENT = 1e-20
_TWO_PI = 2.0 * math.pi


class _Rows(NamedTuple):
    """The constraint rows of a set of azimuths, fixed by ``max_dangle`` and ``n_sides``.

    Row ``i`` reads ``[cos psi_i, sin psi_i] . (fx, fy)_j / F_max_j in [lower_i, upper_i]`` with
    ``j = owner[i]`` and ``psi_i = centre_j + offset[i]``.
    """

    owner: NDArray[np.intp]
    offset: NDArray[np.float64]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    rate: NDArray[np.bool_]  # a rate-limit row (else a magnitude-polygon facet)
    equality: NDArray[np.bool_]


def _row_structure(
    dmax: NDArray[np.float64], ns: int, hull: NDArray[np.bool_] | None = None
) -> _Rows:
    """The rows of each unit's polygon facets and rate sector; for the units where ``hull`` is
    set, the convex hull of the double sector instead (whole polygon, ``|cross(e, f)| <=
    F_max sin(max_dangle)``: the branch-choosing relaxation of a reversible unit)."""
    half = math.pi / ns
    apothem = math.cos(half)
    owner, offset, lower, upper, rate = [], [], [], [], []
    for j, d in enumerate(dmax.tolist()):
        if hull is not None and hull[j]:
            for o in range(ns):
                owner.append(j)
                offset.append((2 * o + 1) * half)
                lower.append(-_NO_BOUND)
                upper.append(apothem)
                rate.append(False)
            owner.append(j)
            offset.append(0.5 * math.pi)
            lower.append(-math.sin(d))
            upper.append(math.sin(d))
            rate.append(True)
            continue
        # the facets that meet the sector: vertices at centre + 2 pi k / ns, facet normals
        # half-way between them
        q = ns // 2 if d == math.inf else max(1, math.ceil(d / (2.0 * half) - 1e-9))
        offs = range(ns) if 2 * q >= ns else range(-q, q)
        for o in offs:
            owner.append(j)
            offset.append((2 * o + 1) * half)
            lower.append(-_NO_BOUND)
            upper.append(apothem)
            rate.append(False)
        if d == 0.0:  # a held direction: cross(e, f) = 0 and e . f >= 0
            owner += [j, j]
            offset += [0.5 * math.pi, math.pi]
            lower += [0.0, -_NO_BOUND]
            upper += [0.0, 0.0]
            rate += [True, True]
        elif d < math.inf:  # cross(e(centre + d), f) <= 0 and cross(e(centre - d), f) >= 0
            owner += [j, j]
            offset += [d + 0.5 * math.pi, -d - 0.5 * math.pi]
            lower += [-_NO_BOUND, -_NO_BOUND]
            upper += [0.0, 0.0]
            rate += [True, True]
    lo = np.array(lower)
    up = np.array(upper)
    return _Rows(np.array(owner), np.array(offset), lo, up, np.array(rate), lo == up)


@dataclass(frozen=True)
class Azimuths:
    """A set of M azimuth thrusters and their angles at the previous control step.

    Attributes:
        positions: shape (M, 2): ``(x, y)`` m of each unit in the body frame (x forward,
            y starboard), giving 3 DOF ``[X, Y, N]``; or shape (M, 3): ``(x, y, z)`` with ``z``
            m below the centre of gravity, giving 4 DOF ``[X, Y, K, N]``.
        f_max: largest thrust of each unit (N), > 0, shape (M,).
        angle_prev: each unit's angle at the previous step (rad, from the x axis towards y),
            shape (M,). Any real value: the new angle is reported near it (continuous).
        max_dangle: the largest angle change in one call (rad), slew rate x control period,
            in ``[0, pi/2)``, or ``inf`` for no rate limit; shape (M,) or a scalar.
        reversible: shape (M,) or a scalar bool: the unit can also thrust backwards along its
            axis (variable pitch), so ``thrust`` may be negative.
        n_sides: sides of the polygon inscribed in each magnitude circle (even, >= 4).

    Raises:
        ValueError: wrong shapes, NaN or infinite values, ``f_max <= 0``, ``max_dangle``
            outside ``[0, pi/2)`` and not ``inf``, or a bad ``n_sides``.
    """

    positions: NDArray[np.float64]
    f_max: NDArray[np.float64]
    angle_prev: NDArray[np.float64]
    max_dangle: NDArray[np.float64] | float = math.inf
    reversible: NDArray[np.bool_] | bool = False
    n_sides: int = 16
    _rows: _Rows = field(init=False, repr=False, compare=False)
    _hull_rows: _Rows | None = field(init=False, repr=False, compare=False)
    _B: NDArray[np.float64] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        try:
            pos = np.array(self.positions, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"positions must be real numbers, got {self.positions!r}") from None
        if pos.ndim != 2 or pos.shape[0] < 1 or pos.shape[1] not in (2, 3):
            raise ValueError(
                "positions must have shape (M, 2) ((x, y) m, 3 DOF) or (M, 3) ((x, y, z) m, "
                f"4 DOF) with M >= 1, got shape {pos.shape}"
            )
        if not np.isfinite(pos).all():
            raise ValueError(f"positions contain NaN or infinite values: {pos.tolist()}")
        m = pos.shape[0]
        fmax = _real_array(self.f_max, "f_max", (m,), "largest thrust of each azimuth, N")
        if (fmax <= 0.0).any():
            raise ValueError(f"f_max must be > 0 N, got {fmax.tolist()}")
        ang = _real_array(self.angle_prev, "angle_prev", (m,), "previous angle of each unit, rad")
        try:
            dmax = np.array(np.broadcast_to(np.asarray(self.max_dangle, dtype=float), (m,)))
        except (TypeError, ValueError):
            raise ValueError(
                f"max_dangle must be a number or shape ({m},) (rad), got {self.max_dangle!r}"
            ) from None
        bad = ~(((dmax >= 0.0) & (dmax < 0.5 * math.pi)) | (dmax == math.inf))
        if bad.any():
            raise ValueError(
                "max_dangle must be in [0, pi/2) rad (slew rate x control period) or inf (no "
                f"rate limit), got {dmax.tolist()}"
            )
        rev = np.asarray(self.reversible)
        if rev.dtype != np.bool_:
            raise ValueError(f"reversible must be bool (one or ({m},)), got {self.reversible!r}")
        try:
            rev = np.array(np.broadcast_to(rev, (m,)))
        except ValueError:
            raise ValueError(
                f"reversible must be one bool or shape ({m},), got {rev.shape}"
            ) from None
        ns = self.n_sides
        if isinstance(ns, bool) or not isinstance(ns, int | np.integer) or ns < 4 or ns % 2:
            raise ValueError(f"n_sides must be an even integer >= 4, got {ns!r}")
        for name, a in (
            ("positions", pos),
            ("f_max", fmax),
            ("angle_prev", ang),
            ("max_dangle", dmax),
            ("reversible", rev),
        ):
            a.flags.writeable = False
            object.__setattr__(self, name, a)
        object.__setattr__(self, "n_sides", int(ns))
        object.__setattr__(self, "_rows", _row_structure(dmax, int(ns)))
        hull = rev & (dmax < math.inf)
        object.__setattr__(
            self, "_hull_rows", _row_structure(dmax, int(ns), hull) if hull.any() else None
        )
        object.__setattr__(self, "_B", extended_thrust_matrix(pos))

    @property
    def n(self) -> int:
        """Number of units M."""
        return int(self.positions.shape[0])

    @property
    def n_dof(self) -> int:
        """3 (``[X, Y, N]``) for (M, 2) positions, 4 (``[X, Y, K, N]``) for (M, 3)."""
        return 3 if self.positions.shape[1] == 2 else 4

    def with_angles(self, angle: ArrayLike) -> Azimuths:
        """The same units with ``angle_prev = angle`` (e.g. the last allocation's ``angle``).

        Cheaper than :func:`dataclasses.replace` (only the angles are validated).
        """
        ang = _real_array(angle, "angle", (self.n,), "previous angle of each unit, rad")
        ang.flags.writeable = False
        new = copy.copy(self)
        object.__setattr__(new, "angle_prev", ang)
        return new


class AzimuthAllocation(NamedTuple):
    """The result of :func:`allocate_azimuth` (M azimuths, K fixed thrusters).

    Attributes:
        thrust: shape (M,): thrust along the new angle (N); ``>= 0`` unless reversible,
            ``|thrust| <= f_max``.
        angle: shape (M,): the new angles (rad), within ``max_dangle`` of ``angle_prev`` and
            continuous with it (not wrapped to (-pi, pi]).
        force_azimuth: shape (M, 2): body-frame components ``(fx, fy)`` (N) of each unit.
        force_fixed: shape (K,): thrusts of the fixed thrusters (N), within their limits.
        tau: delivered generalised force (N, N m), shape (n_dof,).
        tau_error: requested minus delivered ``tau``, shape (n_dof,).
        saturated: shape (M + K,) bool, azimuths first: a limit of the actuator is active (its
            multiplier is non-zero): an azimuth's magnitude polygon or its rate limit, a fixed
            thruster's bound.
        rate_limited: shape (M,) bool: the azimuth's rate limit is active.
    """

    thrust: NDArray[np.float64]
    angle: NDArray[np.float64]
    force_azimuth: NDArray[np.float64]
    force_fixed: NDArray[np.float64]
    tau: NDArray[np.float64]
    tau_error: NDArray[np.float64]
    saturated: NDArray[np.bool_]
    rate_limited: NDArray[np.bool_]


def extended_thrust_matrix(positions: ArrayLike) -> NDArray[np.float64]:
    """Configuration matrix of M azimuths in extended thrust: shape (n_dof, 2M).

    Columns ``2j, 2j + 1`` are the generalised force of a unit ``fx_j``, ``fy_j``:
    ``[1, 0, -y_j]`` and ``[0, 1, x_j]`` for ``[X, Y, N]`` ((M, 2) positions), or
    ``[1, 0, 0, -y_j]`` and ``[0, 1, -z_j, x_j]`` for ``[X, Y, K, N]`` ((M, 3) positions, ``z``
    below the centre of gravity) (Fossen 2011 sec. 12.3).
    """
    pos = np.asarray(positions, dtype=float)
    if pos.ndim != 2 or pos.shape[1] not in (2, 3):
        raise ValueError(f"positions must have shape (M, 2) or (M, 3), got shape {pos.shape}")
    m = pos.shape[0]
    four = pos.shape[1] == 3
    B = np.zeros((4 if four else 3, 2 * m))
    B[0, 0::2] = 1.0
    B[1, 1::2] = 1.0
    B[-1, 0::2] = -pos[:, 1]
    B[-1, 1::2] = pos[:, 0]
    if four:
        B[2, 1::2] = -pos[:, 2]
    return B


def _fixed_part(fixed: Any, n_dof: int):
    if fixed is None:
        return np.zeros((n_dof, 0)), np.zeros(0), np.zeros(0)
    if not isinstance(fixed, tuple | list) or len(fixed) != 3:
        raise ValueError(
            f"fixed must be a tuple (B_fixed, f_min, f_max), got {type(fixed).__name__}"
        )
    Bf, lo, hi = fixed
    Bm = _config_matrix(Bf)
    if Bm.shape[0] != n_dof:
        raise ValueError(
            f"fixed B_fixed must have {n_dof} rows (the DOF of the azimuth positions), got "
            f"shape {Bm.shape}"
        )
    lo, hi = _bounds(lo, hi, Bm.shape[1], zero_inside=True)
    return Bm, lo, hi


def allocate_azimuth(
    tau: ArrayLike,
    azimuths: Azimuths,
    *,
    fixed: tuple[ArrayLike, ArrayLike, ArrayLike] | None = None,
    W: ArrayLike | None = None,
    H: ArrayLike | None = None,
) -> AzimuthAllocation:
    r"""Allocate ``tau`` to azimuth thrusters (and fixed ones) with magnitude and rate limits.

    Solves the QP of the module docstring (extended thrust, Johansen & Fossen 2013): minimise
    ``(B u - tau)^T W (B u - tau) + u^T diag(H) u`` over the fixed thrusts and the azimuth
    force components, subject to the fixed thrusters' ranges, each azimuth's magnitude polygon
    and its angle-rate sector (the branch of a reversible unit chosen as described there).

    Args:
        tau: requested generalised force (N, N m), shape (n_dof,): ``[X, Y, N]`` or
            ``[X, Y, K, N]`` as the azimuth positions say.
        azimuths: the :class:`Azimuths` (positions, limits, previous angles).
        fixed: optional ``(B_fixed, f_min, f_max)``: configuration matrix (n_dof, K) and
            thrust limits (K,) (N) of fixed-direction thrusters, ``f_min <= 0 <= f_max``.
        W: weights of the tau error, shape (n_dof,) or (n_dof, n_dof); ``None``: every DOF's
            error in units of its capacity (as :func:`~.wls.allocate_wls`).
        H: regularisation of the forces, shape (K + 2M,) in the order ``(f, fx_1, fy_1, ...)``
            or a scalar, >= 0 (1/N^2); ``None``: tiny (as :func:`~.wls.allocate_wls`).

    Returns:
        The :class:`AzimuthAllocation`.

    Raises:
        ValueError: bad ``tau``, ``fixed``, ``W`` or ``H`` (shapes, NaN, ranges without 0).
        TypeError: ``azimuths`` is not an :class:`Azimuths`.
        RuntimeError: the QP solver failed (it should not: zero force is always feasible).
    """
    prep = _prepare(azimuths, fixed, W, H)
    t = _real_array(tau, "tau", (prep.n_dof,), "requested generalised force, N and N m")
    return AzimuthAllocation(*(x[0] for x in _run(prep, t[None], azimuths.angle_prev[None])))


# ---- the QP: Goldfarb & Idnani's dual active-set method -----------------------------------------
@njit(inline="always")
def _forward(L, b, y):  # type: ignore[no-untyped-def]
    """``y = L^-1 b`` (``L`` lower triangular)."""
    for i in range(b.shape[0]):
        t = b[i]
        for j in range(i):
            t -= L[i, j] * y[j]
        y[i] = t / L[i, i]


@njit(inline="always")
def _backward(L, y, x):  # type: ignore[no-untyped-def]
    """``x = L^-T y``."""
    n = y.shape[0]
    for i in range(n - 1, -1, -1):
        t = y[i]
        for j in range(i + 1, n):
            t -= L[j, i] * x[j]
        x[i] = t / L[i, i]


@njit
def _orthonormalise(G, act, q, U, Rt):  # type: ignore[no-untyped-def]
    """QR of the columns ``G[act[:q]]`` by modified Gram-Schmidt with one re-orthogonalisation:
    rows ``U[:q]`` orthonormal, ``Rt[j, i]`` the upper triangular factor's entry ``(i, j)``."""
    n = G.shape[1]
    for j in range(q):
        v = U[j]
        g = G[act[j]]
        for e in range(n):
            v[e] = g[e]
        for i in range(j):
            Rt[j, i] = 0.0
        for _ in range(2):
            for i in range(j):
                t = 0.0
                for e in range(n):
                    t += U[i, e] * v[e]
                Rt[j, i] += t
                for e in range(n):
                    v[e] -= t * U[i, e]
        t = 0.0
        for e in range(n):
            t += v[e] * v[e]
        t = math.sqrt(t)
        Rt[j, j] = t
        for e in range(n):
            v[e] /= t


@njit(inline="always")
def _r_solve(Rt, q, d, r):  # type: ignore[no-untyped-def]
    """``r = R^-1 d`` (``Rt[j, i]`` is ``R``'s entry ``(i, j)``, ``i <= j < q``)."""
    for i in range(q - 1, -1, -1):
        t = d[i]
        for j in range(i + 1, q):
            t -= Rt[j, i] * r[j]
        r[i] = t / Rt[i, i]


@njit(inline="always")
def _rt_solve(Rt, q, d):  # type: ignore[no-untyped-def]
    """``d = R^-T d`` in place."""
    for i in range(q):
        t = d[i]
        for j in range(i):
            t -= Rt[i, j] * d[j]
        d[i] = t / Rt[i, i]


@njit(inline="always")
def _append(act, q, ip, U, Rt, d, w, zn):  # type: ignore[no-untyped-def]
    """Constraint ``ip`` joins the QR of the active ``L^-1 a`` (after :func:`_direction` for
    it: ``d = U L^-1 a_p``, ``w`` its orthogonal part, ``zn = |w|^2``): one more row of ``U``
    and column of ``R``. Returns the new number of active constraints."""
    t = math.sqrt(zn)
    for e in range(w.shape[0]):
        U[q, e] = w[e] / t
    for i in range(q):
        Rt[q, i] = d[i]
    Rt[q, q] = t
    act[q] = ip
    return q + 1


@njit
def _direction(L, col, A, G, have, ip, q, U, Rt, d, r, w, z):  # type: ignore[no-untyped-def]
    """The primal step ``z = H a_p`` and the dual step ``r = N* a_p`` of Goldfarb & Idnani
    (1983) for adding constraint ``ip`` to the ``q`` active ones (``U``, ``Rt``: the QR of
    their ``L^-1 a``; ``G[ip] = L^-1 a_p`` is computed here where ``have[ip]`` is not set).
    ``w`` is left as the part of ``L^-1 a_p`` orthogonal to them. Returns ``(|w|^2,
    |L^-1 a_p|^2)``: ``z . a_p`` and its scale."""
    if not have[ip]:  # a_p has two entries, at col and col + 1: L^-1 a_p from there on
        g, j = G[ip], col[ip]
        for e in range(j):
            g[e] = 0.0
        g[j] = A[ip, 0] / L[j, j]
        g[j + 1] = (A[ip, 1] - L[j + 1, j] * g[j]) / L[j + 1, j + 1]
        for e in range(j + 2, g.shape[0]):
            t = 0.0
            for f in range(j, e):
                t -= L[e, f] * g[f]
            g[e] = t / L[e, e]
        have[ip] = True
    n = w.shape[0]
    g = G[ip]
    w0 = 0.0
    for e in range(n):
        w[e] = g[e]
        w0 += g[e] * g[e]
    for i in range(q):
        d[i] = 0.0
    for _ in range(2):
        for i in range(q):
            t = 0.0
            for e in range(n):
                t += U[i, e] * w[e]
            d[i] += t
            for e in range(n):
                w[e] -= t * U[i, e]
    _r_solve(Rt, q, d, r)
    _backward(L, w, z)
    t = 0.0
    for e in range(n):
        t += w[e] * w[e]
    return t, w0


@njit(inline="always")
def _slack(col, A, b, i, x):  # type: ignore[no-untyped-def]
    """``a_i . x - b_i`` (``a_i``: ``A[i]`` at ``col[i]`` and ``col[i] + 1``)."""
    j = col[i]
    return A[i, 0] * x[j] + A[i, 1] * x[j + 1] - b[i]


@njit
def _correct(L, col, A, b, act, q, U, Rt, x, u, d, r, w, z):  # type: ignore[no-untyped-def]
    """Make the active constraints hold to round-off again: ``x += Q^-1 N y`` with ``N^T (x +
    dx) = b_N`` (``y = (N^T Q^-1 N)^-1 (b_N - N^T x)``, through their QR) and ``u_N += y``,
    which keeps ``Q x - c = N u`` (the steps' round-off would otherwise accumulate where ``Q``
    is nearly singular)."""
    n = x.shape[0]
    for i in range(q):  # d = R^-T (b_N - N^T x), r = R^-1 d
        d[i] = -_slack(col, A, b, act[i], x)
    _rt_solve(Rt, q, d)
    _r_solve(Rt, q, d, r)
    for e in range(n):
        t = 0.0
        for i in range(q):
            t += U[i, e] * d[i]
        w[e] = t
    _backward(L, w, z)
    for e in range(n):
        x[e] += z[e]
    for i in range(q):
        u[act[i]] += r[i]


@njit
def _resolve(L, c, b, act, q, U, Rt, x, u, d, r, w):  # type: ignore[no-untyped-def]
    """``x`` and the active multipliers solved afresh from the active set (the minimum of
    ``0.5 x^T Q x - c^T x`` on ``N^T x = b_N``: ``u_N = (N^T Q^-1 N)^-1 (b_N - N^T Q^-1 c)``,
    ``x = Q^-1 (c + N u_N)``), free of the steps' accumulated round-off."""
    n = x.shape[0]
    _forward(L, c, w)  # w = L^-1 c
    for i in range(q):  # d = R^-T b_N - U w (V = L^-1 N = U R)
        d[i] = b[act[i]]
    _rt_solve(Rt, q, d)
    for i in range(q):
        t = 0.0
        for e in range(n):
            t += U[i, e] * w[e]
        d[i] -= t
    for i in range(q):  # x = L^-T (w + U d)
        for e in range(n):
            w[e] += U[i, e] * d[i]
    _backward(L, w, x)
    _r_solve(Rt, q, d, r)  # u_N = R^-1 d
    for i in range(q):
        u[act[i]] = r[i]


@njit
def _dual_qp(L, c, col, A, b, eq, p, x, u, on, have, act, G, U, Rt, d, r, w, z):  # type: ignore[no-untyped-def]
    """``argmin 0.5 x^T Q x - c^T x`` subject to ``a_i . x >= b[i]`` (``= b[i]`` where
    ``eq[i]``), ``i < p``, ``a_i`` being ``A[i, 0]`` and ``A[i, 1]`` at ``col[i]`` and
    ``col[i] + 1`` (zero elsewhere), with ``Q = L L^T`` positive definite, into ``x``; the
    multipliers into ``u`` (``>= 0`` for inequalities, 0 for inactive constraints). The rest
    are scratch.
    Returns 0 or 1 (no convergence).

    The dual active-set method of Goldfarb & Idnani (1983): start from the unconstrained
    minimum, add the equalities, then repeatedly the most violated inequality, stepping along
    the primal direction ``z`` and the dual direction ``r`` and dropping an active inequality
    whose multiplier reaches zero first (a partial step). The active normals' ``L^-1 a`` are
    kept orthonormalised (their QR, extended by a column or rebuilt after a drop), as in the
    method's numerically stable form, and the active constraints are made to hold again after
    each change
    (:func:`_correct`). A violated constraint that depends on active ones none of which can be
    dropped is left out (it would prove the problem infeasible: here it is round-off, zero
    being feasible in every problem of the allocation). At the end ``x`` and ``u`` are solved
    afresh on the active set (:func:`_resolve`, then :func:`_correct`; twice at most, should
    that violate another constraint).
    """
    n = c.shape[0]
    _forward(L, c, w)
    _backward(L, w, x)
    for i in range(p):
        u[i] = 0.0
        on[i] = False
        have[i] = False
    # (the active count and the entering constraint typed int64 from the start: a literal
    # 0 or -1 reaching a callee would compile it once more for that literal)
    q = np.int64(0)
    resolved = 0
    fresh = False
    for i in range(p):  # equalities: full steps, multipliers of either sign, never dropped
        if not eq[i]:
            continue
        zn, w0 = _direction(L, col, A, G, have, i, q, U, Rt, d, r, w, z)
        on[i] = True
        if zn <= _DEPENDENT * w0:
            continue  # dependent on those already active (consistent: zero is feasible)
        t = -_slack(col, A, b, i, x) / zn
        for e in range(n):
            x[e] += t * z[e]
        for j in range(q):
            u[act[j]] -= t * r[j]
        u[i] = t
        q = _append(act, q, i, U, Rt, d, w, zn)
        _correct(L, col, A, b, act, q, U, Rt, x, u, d, r, w, z)
    for _ in range(10 * (n + p) + 10):
        ip, worst = np.int64(-1), -_PRIMAL_TOL
        for i in range(p):
            if not on[i]:
                sl = _slack(col, A, b, i, x)
                if sl < worst:
                    ip, worst = i, sl
        if ip < 0:
            if resolved == 2 or fresh:
                return 0
            fresh = True
            _resolve(L, c, b, act, q, U, Rt, x, u, d, r, w)
            _correct(L, col, A, b, act, q, U, Rt, x, u, d, r, w, z)
            resolved += 1
            continue
        fresh = False
        up = 0.0
        added = False
        for _ in range(2 * n + 2):
            zn, w0 = _direction(L, col, A, G, have, ip, q, U, Rt, d, r, w, z)
            rmax = 0.0
            for j in range(q):
                rmax = max(rmax, abs(r[j]))
            t1, kd = math.inf, -1  # the partial step: an active inequality's multiplier to zero
            for j in range(q):
                if r[j] > _DEPENDENT * rmax and not eq[act[j]]:
                    t = u[act[j]] / r[j]
                    if t < t1:
                        t1, kd = t, j
            if zn > _DEPENDENT * w0:
                t2 = max(-_slack(col, A, b, ip, x) / zn, 0.0)  # the full step
                t = min(t1, t2)
                for e in range(n):
                    x[e] += t * z[e]
            elif kd < 0:
                on[ip] = True  # round-off (see above): left out
                added = True
                break
            else:
                t2 = math.inf
                t = t1
            for j in range(q):
                u[act[j]] -= t * r[j]
            up += t
            if t2 <= t1:  # a full step: p joins the active set
                u[ip] = up
                on[ip] = True
                q = _append(act, q, ip, U, Rt, d, w, zn)
                _correct(L, col, A, b, act, q, U, Rt, x, u, d, r, w, z)
                added = True
                break
            i = act[kd]  # a partial step: drop the inequality kd
            u[i] = 0.0
            on[i] = False
            q -= 1
            for j in range(kd, q):
                act[j] = act[j + 1]
            _orthonormalise(G, act, q, U, Rt)
            _correct(L, col, A, b, act, q, U, Rt, x, u, d, r, w, z)
        if not added:
            return 1
    return 1


@njit
def _constraints(k, xlo, xhi, owner, co, so, lower, upper, equality, cc, sc, col, A, b, eq, orig):  # type: ignore[no-untyped-def]
    """The QP's constraints ``a . x >= b`` / ``= b`` (:func:`_dual_qp`) of the fixed thrusts'
    bounds and the rows (:class:`_Rows`, their offsets' cosines and sines ``co``, ``so``)
    about the units' centre angles (their cosines and sines ``cc``, ``sc``); ``orig``: each
    one's bound (``< k``) or row (``k + row``). Returns their number."""
    p = 0
    for i in range(k):  # (col + 1 exists: the azimuths' variables follow)
        if xlo[i] == xhi[i]:
            col[p], A[p, 0], A[p, 1], b[p], eq[p], orig[p] = i, 1.0, 0.0, xlo[i], True, i
            p += 1
            continue
        col[p], A[p, 0], A[p, 1], b[p], eq[p], orig[p] = i, 1.0, 0.0, xlo[i], False, i
        p += 1
        col[p], A[p, 0], A[p, 1], b[p], eq[p], orig[p] = i, -1.0, 0.0, -xhi[i], False, i
        p += 1
    for row in range(owner.shape[0]):
        o = owner[row]
        j = k + 2 * o
        cs = cc[o] * co[row] - sc[o] * so[row]  # the normal at centre + offset
        sn = sc[o] * co[row] + cc[o] * so[row]
        if equality[row]:
            col[p], A[p, 0], A[p, 1], b[p], eq[p], orig[p] = j, cs, sn, upper[row], True, k + row
            p += 1
            continue
        if lower[row] > -_NO_BOUND:
            col[p], A[p, 0], A[p, 1], b[p], eq[p], orig[p] = j, cs, sn, lower[row], False, k + row
            p += 1
        col[p], A[p, 0], A[p, 1], b[p], eq[p], orig[p] = j, -cs, -sn, -upper[row], False, k + row
        p += 1
    return p


@njit(inline="always")
def _enumerated(amb, na, j):  # type: ignore[no-untyped-def]
    """Whether unit ``j`` is one of the ``na`` units ``amb`` whose branches were enumerated."""
    for i in range(na):
        if amb[i] == j:
            return True
    return False


@njit
def _wrap(a):  # type: ignore[no-untyped-def]
    """An angle wrapped to [-pi, pi)."""
    return (a + math.pi) % _TWO_PI - math.pi


@njit(nogil=True)
def azimuth_law(first, end, Q0, R, qd, turn, B, s, flo, fhi, fmax, dmax, rev, rows, hull, tau,
                a_prev, thrust, angle, f_az, f_fixed, delivered, error, saturated,
                rate_limited):  # type: ignore[no-untyped-def]  # fmt: skip
    """The azimuth allocation of the requests ``first .. end - 1`` of N
    (:func:`allocate_azimuth` documents the problem, the module's design note the branches of
    reversible units), one after the other, each with the same floats whatever the range. It
    releases the GIL: :func:`_run` spreads ranges of a large batch over threads.

    Args:
        first, end: the rows allocated (int64).
        Q0, R, qd, turn: the scaled problem (n, n), (n, n_dof), the curvatures ``diag(Q)``
            (n,) and the turning cost's weight (:class:`AzimuthAllocator`).
        B, s, flo, fhi: the configuration (n_dof, n), the scales (n,) and the fixed thrusts'
            limits (k,) (N).
        fmax, dmax, rev: the units' F_max (N), max_dangle (rad) and reversibility (M,).
        rows, hull: the rows (:class:`_Rows`: owner, offset, lower, upper, rate, equality) of
            the sectors and of the branch-choosing relaxation (no rows: no reversible unit
            with a rate limit).
        tau, a_prev: (N, n_dof) the requests (N, N m), (N, M) the previous angles (rad).
        thrust, angle, f_az, f_fixed, delivered, error, saturated, rate_limited: out, the
            fields of :class:`AzimuthAllocation` with a leading axis N.

    Returns:
        0, or the first failing request's index + 1 times 8 plus the reason (1: not finite;
        2: the QP did not converge; 3: its curvature not positive definite).
    """
    n_dof = tau.shape[1]
    m = fmax.shape[0]
    n = s.shape[0]
    k = n - 2 * m
    owner, offset, lower, upper, rate, equality = rows
    howner, hoffset, hlower, hupper, _, hequality = hull
    pmax = 2 * k + 2 * max(owner.shape[0], howner.shape[0])
    xlo = np.empty(k)
    xhi = np.empty(k)
    for i in range(k):
        xlo[i], xhi[i] = flo[i] / s[i], fhi[i] / s[i]
    Q = np.empty((n, n))
    L = np.zeros((n, n))
    c = np.empty(n)
    col = np.empty(pmax, np.int64)
    A = np.empty((pmax, 2))
    b = np.empty(pmax)
    have = np.empty(pmax, np.bool_)
    eq = np.empty(pmax, np.bool_)
    orig = np.empty(pmax, np.int64)
    on = np.empty(pmax, np.bool_)
    u = np.empty(pmax)
    act = np.empty(n + 1, np.int64)
    G = np.empty((pmax, n))
    U = np.empty((n + 1, n))
    Rt = np.zeros((n + 1, n + 1))
    d = np.empty(n + 1)
    r = np.empty(n + 1)
    w = np.empty(n)
    z = np.empty(n)
    x = np.empty(n)
    bx = np.empty(n)
    blam = np.empty(n + owner.shape[0])
    ca, sa, cc, sc = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    co, so, hco, hso = np.cos(offset), np.sin(offset), np.cos(hoffset), np.sin(hoffset)
    bw = np.empty(m, np.bool_)
    bbw = np.empty(m, np.bool_)
    amb = np.empty(_MAX_TRIED, np.int64)
    u_all = np.empty(n)
    limited = dmax < math.inf
    for row in range(first, end):
        ap = a_prev[row]
        for i in range(n_dof):
            if not math.isfinite(tau[row, i]):
                return 8 * (row + 1) + 1
        for j in range(m):
            if not math.isfinite(ap[j]):
                return 8 * (row + 1) + 1
            ca[j], sa[j] = math.cos(ap[j]), math.sin(ap[j])
        for i in range(n):
            t = 0.0
            for e in range(n_dof):
                t += R[i, e] * tau[row, e]
            c[i] = t
            for e in range(n):
                Q[i, e] = Q0[i, e]
        if turn > 0.0:  # a cost on the force across each unit's previous direction
            for j in range(m):
                i = k + 2 * j
                e0, e1 = -sa[j], ca[j]
                qj = turn * 0.5 * (qd[i] + qd[i + 1])
                Q[i, i] += qj * e0 * e0
                Q[i, i + 1] += qj * e0 * e1
                Q[i + 1, i] += qj * e1 * e0
                Q[i + 1, i + 1] += qj * e1 * e1
        if not _cholesky(Q, L):
            return 8 * (row + 1) + 3

        # the sector of each unit: its centre angle (reversed for a reversible unit whose
        # relaxed optimum points backwards) and half-width
        for j in range(m):
            bw[j] = False
        na = 0
        if howner.shape[0]:
            p = _constraints(k, xlo, xhi, howner, hco, hso, hlower, hupper, hequality, ca, sa,
                             col, A, b, eq, orig)  # fmt: skip
            why = _dual_qp(L, c, col, A, b, eq, p, x, u, on, have, act, G, U, Rt, d, r, w, z)
            if why:
                return 8 * (row + 1) + 1 + why
            for j in range(m):
                if rev[j] and limited[j]:
                    x0, x1 = x[k + 2 * j], x[k + 2 * j + 1]
                    along = x0 * ca[j] + x1 * sa[j]
                    across = abs(-x0 * sa[j] + x1 * ca[j])
                    bw[j] = along < 0.0
                    # relaxed force in neither sector (beyond the rate limit off the axis): both
                    # branches are tried (for the first _MAX_TRIED such units)
                    if across > abs(along) * math.tan(dmax[j]) + _BRANCH_TOL and na < _MAX_TRIED:
                        amb[na] = j
                        na += 1
        # the branches: every combination of the ambiguous units' (the others at their
        # projection's); then, where the relaxed optimum was not feasible (na > 0), a local
        # search: another reversible unit whose rate limit is active in the best answer so far
        # may do better in its other branch now that the ambiguous units' forces changed (its
        # projection's branch was the relaxed optimum's); each such unit's other branch is
        # tried once, in turn, and kept where it lowers the cost by more than round-off
        best = math.inf
        trials = 1 << na
        trial = 0
        unit = 0  # the next unit the local search looks at
        while True:
            if trial < trials:
                for i in range(na):
                    bw[amb[i]] = (trial >> i) & 1 == 1
            else:
                flip = -1
                while na and unit < m and flip < 0:
                    if rev[unit] and limited[unit] and not _enumerated(amb, na, unit):
                        lim = _ACTIVE_TOL * 0.5 * (qd[k + 2 * unit] + qd[k + 2 * unit + 1])
                        for i in range(owner.shape[0]):
                            if owner[i] == unit and rate[i] and blam[k + i] > lim:
                                flip = unit
                    unit += 1
                if flip < 0:
                    break
                for j in range(m):
                    bw[j] = bbw[j]
                bw[flip] = not bbw[flip]
            for j in range(m):  # the centre angle, reversed where backwards
                cc[j], sc[j] = (-ca[j], -sa[j]) if bw[j] else (ca[j], sa[j])
            p = _constraints(k, xlo, xhi, owner, co, so, lower, upper, equality, cc, sc, col, A,
                             b, eq, orig)  # fmt: skip
            why = _dual_qp(L, c, col, A, b, eq, p, x, u, on, have, act, G, U, Rt, d, r, w, z)
            if why:
                return 8 * (row + 1) + 1 + why
            J = 0.0
            for i in range(n):
                t = 0.0
                for e in range(n):
                    t += Q[i, e] * x[e]
                J += x[i] * (0.5 * t - c[i])
            if trial < trials:
                better = trial == 0 or J < best
            else:  # J is the cost less its constant: compare against the cost's scale
                better = J < best - _BETTER * (abs(best) + qd.max())
            if better:
                best = J
                for i in range(n):
                    bx[i] = x[i]
                for i in range(blam.shape[0]):
                    blam[i] = 0.0
                for i in range(p):
                    if u[i] != 0.0:
                        blam[orig[i]] = max(blam[orig[i]], abs(u[i]))
                for j in range(m):
                    bbw[j] = bw[j]
            trial += 1

        # fixed thrusters within their limits; azimuth angle and magnitude within theirs exactly
        for i in range(k):
            f = min(max(bx[i] * s[i], flo[i]), fhi[i])
            f_fixed[row, i] = f
            u_all[i] = f
        for j in range(m):
            fx, fy = bx[k + 2 * j] * fmax[j], bx[k + 2 * j + 1] * fmax[j]
            mag = math.hypot(fx, fy)
            rel = _wrap(math.atan2(fy, fx) - ap[j])  # relative to the previous angle
            sign = 1.0
            if bbw[j] or (rev[j] and not limited[j] and abs(rel) > 0.5 * math.pi):
                sign = -1.0
                rel = _wrap(rel - math.pi)
            cl = min(max(rel, -dmax[j]), dmax[j]) if limited[j] else rel
            th = sign * min(mag * max(math.cos(rel - cl), 0.0), fmax[j])
            if mag <= _ZERO_FORCE * fmax[j]:
                th, cl = 0.0, 0.0
            a = ap[j] + cl
            thrust[row, j] = th
            angle[row, j] = a
            f_az[row, j, 0] = th * math.cos(a)
            f_az[row, j, 1] = th * math.sin(a)
            u_all[k + 2 * j] = f_az[row, j, 0]
            u_all[k + 2 * j + 1] = f_az[row, j, 1]
        for i in range(n_dof):
            t = 0.0
            for e in range(n):
                t += B[i, e] * u_all[e]
            delivered[row, i] = t
            error[row, i] = tau[row, i] - t

        # active limits: multiplier over the curvature of the variables it acts on (the
        # distance, in units of F_max or of the thrust range, the force would move past it if
        # released)
        for j in range(m + k):
            saturated[row, j] = False
        for j in range(m):
            rate_limited[row, j] = False
        for i in range(owner.shape[0]):
            j = owner[i]
            if blam[k + i] > _ACTIVE_TOL * 0.5 * (qd[k + 2 * j] + qd[k + 2 * j + 1]):
                saturated[row, j] = True
                if rate[i]:
                    rate_limited[row, j] = True
        for i in range(k):
            saturated[row, m + i] = blam[i] > _ACTIVE_TOL * qd[i]
    return 0


class _Prepared(NamedTuple):
    """What depends on the units, the fixed thrusters and the weights but not on the angles:
    the law's arguments before the requests."""

    n_dof: int
    m: int
    k: int
    args: tuple[Any, ...]


def _law_rows(rows: _Rows | None) -> tuple[NDArray[Any], ...]:
    if rows is None:
        e = np.zeros(0)
        return (np.zeros(0, np.int64), e, e, e, np.zeros(0, np.bool_), np.zeros(0, np.bool_))
    return tuple(_c(a, np.int64 if i == 0 else np.bool_ if i > 3 else float)
                 for i, a in enumerate(rows))  # fmt: skip


def _c(a: Any, dtype: Any = float) -> NDArray[Any]:
    """A writeable C-contiguous copy: the law's one compiled entry point is typed for that."""
    return np.array(a, dtype=dtype, order="C")


def _prepare(
    az: Azimuths, fixed: Any, W: ArrayLike | None, H: ArrayLike | None, turn: float = 0.0
) -> _Prepared:
    if not isinstance(az, Azimuths):
        raise TypeError(f"azimuths must be an Azimuths instance, got {type(az).__name__}")
    n_dof = az.n_dof
    Bf, flo, fhi = _fixed_part(fixed, n_dof)
    k = Bf.shape[1]
    B = np.hstack((Bf, az._B)) if k else az._B
    s = np.concatenate((_scales(flo, fhi), np.repeat(az.f_max, 2)))
    w = _weights(W, n_dof, _capacity(B, s))
    Q, R = _scaled_problem(B, s, w, H)
    if not (isinstance(turn, int | float) and math.isfinite(turn) and turn >= 0.0):
        raise ValueError(f"turn_weight must be a finite number >= 0, got {turn!r}")
    qd = Q.diagonal().copy()
    # the regularisation's part of the curvature (Q less the weighted configuration's), floored
    h = qd - np.einsum("ij,ji->i", R, B * s)
    Q = Q + np.diag(np.maximum(_MIN_CURV - h, 0.0))
    args = (_c(Q), _c(R), _c(qd), float(turn), _c(B), _c(s), _c(flo), _c(fhi), _c(az.f_max),
            _c(az.max_dangle), _c(az.reversible, np.bool_), _law_rows(az._rows),
            _law_rows(az._hull_rows))  # fmt: skip
    return _Prepared(n_dof, az.n, k, args)


#: the law's compiled entry point
_LAW: list[Any] = []

#: the fewest requests allocated in chunks on threads (:func:`shipgym._jit.spread_rows`): a request
#: costs tens of microseconds (a QP per branch), so a few pay for the threads
PARALLEL_MIN = 16


def _run(prep: _Prepared, tau: NDArray[np.float64], a_prev: NDArray[np.float64]):  # type: ignore[no-untyped-def]
    """:func:`azimuth_law` on ``tau`` (N, n_dof) from ``a_prev`` (N, M) through its compiled
    entry point: the fields of :class:`AzimuthAllocation`, each with a leading axis N."""
    t, a = law_input(tau), law_input(a_prev)  # (a frozen Azimuths' angles: read-only)
    N, m, k = t.shape[0], prep.m, prep.k
    out = (np.empty((N, m)), np.empty((N, m)), np.empty((N, m, 2)), np.empty((N, k)),
           np.empty((N, prep.n_dof)), np.empty((N, prep.n_dof)),
           np.empty((N, m + k), dtype=np.bool_), np.empty((N, m), dtype=np.bool_))  # fmt: skip
    args = (*prep.args, t, a, *out)
    if not _LAW:
        _LAW.append(entry(azimuth_law, (np.int64(0), np.int64(N), *args)))
    fn = _LAW[0]
    if N >= PARALLEL_MIN and threads_ok():
        # the first failing row's code, as one call on every row gives it
        code = next((int(c) for _, c in spread_rows(fn, N, *args) if c), 0)
    else:
        code = fn(0, N, *args)
    if code:
        row, why = divmod(code, 8)
        if why == 1:
            raise ValueError(
                f"tau or angle_prev contains NaN or infinite values: {t[row - 1].tolist()}, "
                f"{a[row - 1].tolist()}"
            )
        what = "did not converge" if why == 2 else "met a curvature not positive definite"
        raise RuntimeError(
            f"allocate_azimuth: the dual active-set QP {what} (please report the request "
            f"{t[row - 1].tolist()} and the angles {a[row - 1].tolist()})"
        )
    return out


class AzimuthAllocator:
    """:func:`allocate_azimuth` for one set of units, fixed thrusters and weights, prepared once.

    ``AzimuthAllocator(azimuths, fixed=..., W=..., H=...)(tau, angle_prev)`` equals
    ``allocate_azimuth(tau, azimuths.with_angles(angle_prev), fixed=..., W=..., H=...)``
    (``angle_prev=None``: ``azimuths.angle_prev``); the configuration, scaling and weights are
    validated and built at construction, a call validates ``tau`` and the angles only.
    :meth:`batch` allocates N requests at once (row ``i`` equals the call on row ``i``).

    ``turn_weight`` (default 0: the plain problem) adds a cost on each unit's force across its
    previous direction, ``turn_weight * q_j * (e_perp(alpha_prev) . f_j / F_max_j)^2`` with
    ``q_j`` the unit's mean curvature in the objective: among allocations that deliver
    (nearly) the same ``tau`` it prefers those that keep the angles, so a redundant set of
    units stops turning back and forth. It trades a little of ``tau`` for that; the delivered
    ``tau`` and ``tau_error`` are reported as always.
    """

    __slots__ = ("azimuths", "_prep")

    def __init__(
        self,
        azimuths: Azimuths,
        *,
        fixed: tuple[ArrayLike, ArrayLike, ArrayLike] | None = None,
        W: ArrayLike | None = None,
        H: ArrayLike | None = None,
        turn_weight: float = 0.0,
    ) -> None:
        self._prep = _prepare(azimuths, fixed, W, H, turn_weight)
        self.azimuths = azimuths

    def __call__(self, tau: ArrayLike, angle_prev: ArrayLike | None = None) -> AzimuthAllocation:
        """The allocation of ``tau`` (N, N m) from the angles ``angle_prev`` (rad, (M,))."""
        az = self.azimuths
        t = _real_array(tau, "tau", (self._prep.n_dof,), "requested generalised force, N and N m")
        if angle_prev is None:
            a = az.angle_prev
        else:
            a = _real_array(angle_prev, "angle_prev", (az.n,), "previous angle of each unit, rad")
        return AzimuthAllocation(*(x[0] for x in _run(self._prep, t[None], a[None])))

    def batch(self, tau: ArrayLike, angle_prev: ArrayLike) -> tuple[NDArray[Any], ...]:
        """The allocations of N requests ``tau`` (N, n_dof) from the angles ``angle_prev``
        (N, M) (:func:`azimuth_law`): the fields of :class:`AzimuthAllocation`, each with a
        leading axis N.

        Raises:
            ValueError: wrong shapes, or NaN or infinite values.
        """
        t = np.asarray(tau, dtype=float)
        a = np.asarray(angle_prev, dtype=float)
        n_dof, m = self._prep.n_dof, self._prep.m
        if t.ndim != 2 or t.shape[1] != n_dof or a.shape != (t.shape[0], m):
            raise ValueError(
                f"tau must have shape (N, {n_dof}) and angle_prev (N, {m}), got {t.shape} and "
                f"{a.shape}"
            )
        return _run(self._prep, t, a)
