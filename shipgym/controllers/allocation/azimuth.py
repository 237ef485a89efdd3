r"""Azimuth-thruster allocation by the extended-thrust formulation, with angle-rate limits.

``fx_j = T_j cos(alpha_j)``, ``fy_j = T_j sin(alpha_j)``: a QP in the extended thrusts
with polygon magnitude limits and angle-rate sectors.

Public names: ``AzimuthAllocation``, ``AzimuthAllocator``, ``Azimuths``, ``allocate_azimuth``,
``extended_thrust_matrix``.
Sources: Fossen (2011); Johansen & Fossen (2013); Bemporad & Axehill (2022).

Design notes: docs/design/controllers.allocation.azimuth.md.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .wls import _bounds, _capacity, _config_matrix, _real_array, _scaled_problem, _scales, _weights

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
_NO_BOUND = 1e30  # DAQP's "no lower bound"
#: a reversible unit's relaxed force more than this (of F_max) outside both of its sectors
#: makes its branch ambiguous: both are tried, for at most _MAX_TRIED such units
_BRANCH_TOL = 1e-9
_MAX_TRIED = 3
#: DAQP settings, tried in turn. The proximal-point iteration (eps_prox > 0) keeps the dual
#: method exact when the objective is nearly singular (a redundant set with the tiny default
#: H), iterated until the proximal steps change the answer by less than eta_prox. A rare
#: degenerate problem makes DAQP report cycling (exit flag -2) or infeasibility with one
#: setting; the next (a larger proximal weight) is tried then
_DAQP_SETTINGS = (
    {"primal_tol": 1e-10, "eps_prox": 1e-6, "eta_prox": 1e-12},
    {"primal_tol": 1e-10, "eps_prox": 1e-4, "eta_prox": 1e-12},
    {"primal_tol": 1e-9, "eps_prox": 1e-2, "eta_prox": 1e-12, "iter_limit": 100_000},
)
_TWO_PI = 2.0 * math.pi


def _daqp() -> Any:
    try:
        import daqp
    except ImportError:  # pragma: no cover - a dependency of the package
        raise ImportError(
            "allocate_azimuth needs the QP solver 'daqp' (pip install daqp), a dependency of "
            "shipgym"
        ) from None
    return daqp


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


def _solve(
    Q: NDArray[np.float64],
    c: NDArray[np.float64],
    rows: _Rows,
    centre: NDArray[np.float64],
    xlo: NDArray[np.float64],
    xhi: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``argmin 0.5 x^T Q x - c^T x`` with the fixed thrusts (the first ``k``) in
    ``[xlo, xhi]`` and the azimuth rows about ``centre``, by DAQP. Returns ``x`` and the
    multipliers' magnitudes (the ``k`` bounds, then the rows)."""
    k = xlo.shape[0]
    ow = rows.owner
    ps = centre[ow] + rows.offset
    nrow = ps.size
    A = np.zeros((nrow, c.shape[0]))
    r = np.arange(nrow)
    A[r, k + 2 * ow] = np.cos(ps)
    A[r, k + 2 * ow + 1] = np.sin(ps)
    bu = np.concatenate((xhi, rows.upper))
    bl = np.concatenate((xlo, rows.lower))
    sense = np.zeros(k + nrow, dtype=np.int32)
    sense[k:][rows.equality] = 5
    solve = _daqp().solve
    flags = []
    for settings in _DAQP_SETTINGS:
        x, _, flag, info = solve(Q.copy(), -c, A, bu, bl, sense, **settings)
        if flag in (1, 2):
            return np.asarray(x), np.abs(np.asarray(info["lam"]))
        flags.append(flag)
    raise RuntimeError(
        f"allocate_azimuth: the QP solver DAQP failed (exit flags {flags}; please report the "
        "request and the azimuths)"
    )


def _wrap(a: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angles wrapped to [-pi, pi)."""
    return (a + math.pi) % _TWO_PI - math.pi


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
    return _allocate(prep, azimuths, azimuths.angle_prev, t)


class _Prepared(NamedTuple):
    """What depends on the units, the fixed thrusters and the weights but not on the angles."""

    n_dof: int
    k: int
    B: NDArray[np.float64]
    s: NDArray[np.float64]
    flo: NDArray[np.float64]
    fhi: NDArray[np.float64]
    Q: NDArray[np.float64]
    R: NDArray[np.float64]
    qd: NDArray[np.float64]
    turn: float = 0.0


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
    return _Prepared(n_dof, k, B, s, flo, fhi, Q, R, Q.diagonal().copy(), float(turn))


class AzimuthAllocator:
    """:func:`allocate_azimuth` for one set of units, fixed thrusters and weights, prepared once.

    ``AzimuthAllocator(azimuths, fixed=..., W=..., H=...)(tau, angle_prev)`` equals
    ``allocate_azimuth(tau, azimuths.with_angles(angle_prev), fixed=..., W=..., H=...)``
    (``angle_prev=None``: ``azimuths.angle_prev``); the configuration, scaling and weights are
    validated and built at construction, a call validates ``tau`` and the angles only.

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
        return _allocate(self._prep, az, a, t)


def _allocate(
    prep: _Prepared, az: Azimuths, a_prev: NDArray[np.float64], t: NDArray[np.float64]
) -> AzimuthAllocation:
    k, B, s, flo, fhi, Q, qd = prep.k, prep.B, prep.s, prep.flo, prep.fhi, prep.Q, prep.qd
    m = az.n
    fmax = az.f_max
    c = prep.R @ t
    if prep.turn > 0.0:  # a cost on the force across each unit's previous direction
        Q = Q.copy()
        ep = np.column_stack((-np.sin(a_prev), np.cos(a_prev)))  # (M, 2) unit normals
        q = prep.turn * 0.5 * (qd[k::2] + qd[k + 1 :: 2])
        blocks = q[:, None, None] * ep[:, :, None] * ep[:, None, :]
        for j in range(m):
            i = k + 2 * j
            Q[i : i + 2, i : i + 2] += blocks[j]

    # the sector of each unit: its centre angle (the reversed one for a reversible unit whose
    # relaxed optimum points backwards) and half-width
    dmax = az.max_dangle
    limited = dmax < math.inf
    centre = a_prev
    backwards = np.zeros(m, dtype=bool)
    rows = az._rows
    ow = rows.owner
    xlo, xhi = flo / s[:k], fhi / s[:k]
    if az._hull_rows is None:
        x, lam = _solve(Q, c, rows, centre, xlo, xhi)
    else:
        xr = _solve(Q, c, az._hull_rows, a_prev, xlo, xhi)[0]
        xy = xr[k:].reshape(m, 2)
        pick = az.reversible & limited
        along = xy[:, 0] * np.cos(a_prev) + xy[:, 1] * np.sin(a_prev)
        across = np.abs(-xy[:, 0] * np.sin(a_prev) + xy[:, 1] * np.cos(a_prev))
        backwards = pick & (along < 0.0)
        # units whose relaxed force lies in neither sector (beyond the rate limit off the axis):
        # both branches are tried (the first _MAX_TRIED of them; the others by projection)
        tan_d = np.tan(np.where(pick, dmax, 0.0))
        outside = pick & (across > np.abs(along) * tan_d + _BRANCH_TOL)
        ambiguous = np.flatnonzero(outside)[:_MAX_TRIED]
        best = None
        for flips in range(1 << ambiguous.size):
            bw = backwards.copy()
            for i, j in enumerate(ambiguous):
                bw[j] = bool(flips >> i & 1)
            cen = a_prev + np.where(bw, math.pi, 0.0)
            xb, lb = _solve(Q, c, rows, cen, xlo, xhi)
            J = 0.5 * float(xb @ Q @ xb) - float(c @ xb)
            if best is None or J < best[0]:
                best = (J, xb, lb, bw, cen)
        assert best is not None
        _, x, lam, backwards, centre = best

    # fixed thrusters within their limits; azimuth angle and magnitude within theirs exactly
    f_fixed = np.minimum(np.maximum(x[:k] * s[:k], flo), fhi)
    fxy = x[k:].reshape(m, 2) * fmax[:, None]
    mag = np.hypot(fxy[:, 0], fxy[:, 1])
    rel = np.arctan2(fxy[:, 1], fxy[:, 0]) - a_prev  # direction relative to the previous angle
    rel = _wrap(rel)
    sign = np.ones(m)
    flip = backwards | (az.reversible & ~limited & (np.abs(rel) > 0.5 * math.pi))
    sign[flip] = -1.0
    rel[flip] = _wrap(rel[flip] - math.pi)
    clamped = np.where(limited, np.clip(rel, -dmax, dmax), rel)
    thrust = sign * np.minimum(mag * np.maximum(np.cos(rel - clamped), 0.0), fmax)
    tiny = mag <= _ZERO_FORCE * fmax
    thrust[tiny] = 0.0
    clamped[tiny] = 0.0
    angle = a_prev + clamped
    f_az = thrust[:, None] * np.column_stack((np.cos(angle), np.sin(angle)))
    u = np.concatenate((f_fixed, f_az.reshape(-1)))
    delivered = B @ u

    # active limits: multiplier over the curvature of the variables it acts on (the distance,
    # in units of F_max or of the thrust range, the force would move past it if released)
    curv_az = 0.5 * (qd[k::2] + qd[k + 1 :: 2])
    row_active = lam[k:] > _ACTIVE_TOL * curv_az[ow]
    rate_row = rows.rate
    rate_limited = np.zeros(m, dtype=bool)
    np.logical_or.at(rate_limited, ow[row_active & rate_row], True)
    saturated = np.zeros(m + k, dtype=bool)
    np.logical_or.at(saturated, ow[row_active], True)
    saturated[m:] = lam[:k] > _ACTIVE_TOL * qd[:k]
    return AzimuthAllocation(
        thrust, angle, f_az, f_fixed, delivered, t - delivered, saturated, rate_limited
    )
