r"""Thrust allocation for the three-thruster pattern of the Blue Lady (Tomera 2014 eqs. 24-27).

``tau = T F`` (Tomera 2014 eq. 12), ``T = [[1, 0, 0], [0, 1, 1], [0, L_2, -L_3]]``;
``allocate_inverse``: ``F = T^-1 tau`` (eq. 25) and clipping.

Public names: ``Allocation``, ``Fixed3Allocator``, ``fixed3_law``, ``law_parameters``,
``allocate``, ``allocate_inverse``, ``default_weights``, ``force_capacity``, ...

Design notes: docs/design/controllers.allocation.fixed3.md.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import entry, njit
from shipgym.dynamics.thrusters import ThrusterParameters

__all__ = [
    "Allocation",
    "Fixed3Allocator",
    "fixed3_law",
    "law_parameters",
    "allocate",
    "allocate_inverse",
    "default_weights",
    "force_capacity",
    "HEADING_WEIGHT",
    "command_to_action",
    "action_to_command",
]

#: relative tolerance (of a force range) used to decide that a force sits on a limit
_AT_LIMIT_RTOL = 1e-9
#: requests outside a range by less than this fraction of it are round-off, not saturation
_ROUND_OFF_RTOL = 1e-12

#: how much more a yaw-moment error costs than a sway-force error of the same size at the
#: lever ``L2 + L3`` when the tunnels saturate (:func:`default_weights`): heading first.
#: [chosen] (issue 31): 100, a priority (the sway force gives way until the moment is met to
#: about 1 % of the sway shortfall, in lever-arm units); it was 10, a compromise that let a
#: saturated turn or a cross-current give up heading, whose error then turned the wind and
#: waves further onto the beam: on the lake preset (KBF + pid-smooth, seeds 0-9) seed 6 hit
#: the quay with 10 and completes with 100 (and 1000). 1000 gives pid the same figures but
#: costs the bang-bang lq more (harbour, KBF, seeds 0-9: J_c 0.155 with 10, 0.255 with 100,
#: 0.376 with 1000: its tunnels live at their limits, so its sway always gives way).
HEADING_WEIGHT = 100.0


class Allocation(NamedTuple):
    """The result of a thrust allocation (all arrays have shape (3,)).

    Attributes:
        command: actuator commands ``[n1 (rpm), p2 (-), p3 (-)]`` within their ranges.
        force: thrusts ``[F1, F2, F3]`` (N) the commands deliver (after saturation).
        tau: delivered generalised force ``T force`` = ``[X, Y, N]`` (N, N, N m).
        tau_error: requested minus delivered ``tau`` (N, N, N m); zero when nothing saturates.
            Its sign tells in which direction each DOF was cut, which is what the anti-windup
            of :class:`~shipgym.controllers.pid.MultivariablePID` needs.
        saturated: per actuator, ``True`` where the request could not be met because that
            actuator was held at a limit of its range.
    """

    command: NDArray[np.float64]
    force: NDArray[np.float64]
    tau: NDArray[np.float64]
    tau_error: NDArray[np.float64]
    saturated: NDArray[np.bool_]


# ---- helpers ---------------------------------------------------------------------------------
def _tau3(tau: ArrayLike) -> tuple[float, float, float]:
    """``tau`` as three finite floats, or a ``ValueError`` that says what is wrong."""
    if isinstance(tau, np.ndarray):
        if tau.shape != (3,):
            raise ValueError(
                f"tau must have shape (3,) ([X N, Y N, N N m]), got an array of shape {tau.shape}"
            )
        vals = tau.tolist()
    else:
        try:
            vals = list(tau)  # type: ignore[arg-type]
        except TypeError:
            raise ValueError(
                f"tau must be a sequence of 3 numbers [X, Y, N], got {tau!r}"
            ) from None
        if len(vals) != 3:
            raise ValueError(f"tau must have 3 entries [X, Y, N], got {len(vals)}: {tau!r}")
    try:
        X, Y, N = (float(v) for v in vals)
    except (TypeError, ValueError):
        raise ValueError(f"tau must contain 3 real numbers [X, Y, N], got {tau!r}") from None
    if not (math.isfinite(X) and math.isfinite(Y) and math.isfinite(N)):
        raise ValueError(f"tau contains NaN or infinite values: {tau!r} (check the controller)")
    return X, Y, N


def _check_thrusters(thrusters: ThrusterParameters) -> None:
    if not isinstance(thrusters, ThrusterParameters):
        raise ValueError(
            f"thrusters must be a ThrusterParameters instance, got {type(thrusters).__name__}"
        )


def _force_box(p: ThrusterParameters) -> tuple[float, float, float, float, float, float]:
    """Force ranges ``(F1_lo, F1_hi, F2_lo, F2_hi, F3_lo, F3_hi)`` (N) of the three actuators."""
    return (
        -p.k1 * p.n_min * p.n_min,
        p.k1 * p.n_max * p.n_max,
        p.k2 * p.p_min,
        p.k2 * p.p_max,
        p.k3 * p.p_min,
        p.k3 * p.p_max,
    )


# ---- the one run-time law: N requests, compiled ------------------------------------------------
@njit
def _clip(x: float, lo: float, hi: float) -> float:
    return lo if x < lo else hi if x > hi else x


@njit
def _inside(x: float, lo: float, hi: float) -> bool:
    tol = _ROUND_OFF_RTOL * (hi - lo)
    return lo - tol <= x <= hi + tol


@njit
def _at_limit(x: float, lo: float, hi: float) -> bool:
    tol = _AT_LIMIT_RTOL * (hi - lo)
    return x <= lo + tol or x >= hi - tol


@njit
def fixed3_law(P: Any, tau: Any, inverse: bool, cmd: Any, F: Any, tdel: Any, err: Any,
               sat: Any) -> int:  # fmt: skip
    """:func:`allocate` (or, with ``inverse``, :func:`allocate_inverse`) of every row of
    ``tau`` (n, 3) (N, N, N m), written to ``cmd``, ``F``, ``tdel``, ``err``, ``sat`` (the
    :class:`Allocation` fields, one row per request). ``P``: :func:`law_parameters`.
    Returns 1 (nothing written) when ``tau`` is not finite, else 0."""
    n = tau.shape[0]
    for i in range(n):
        for j in range(3):
            if not math.isfinite(tau[i, j]):
                return 1
    k1, k2, k3, L2, L3 = P[0], P[1], P[2], P[3], P[4]
    n_min, n_max, p_min, p_max, wY, wN = P[5], P[6], P[7], P[8], P[9], P[10]
    f1lo, f1hi = -k1 * n_min * n_min, k1 * n_max * n_max
    f2lo, f2hi, f3lo, f3hi = k2 * p_min, k2 * p_max, k3 * p_min, k3 * p_max
    lever = L2 + L3
    d3 = wY + wN * L3 * L3  # curvature along F3 (F2 fixed)
    d2 = wY + wN * L2 * L2  # curvature along F2 (F3 fixed)
    for i in range(n):
        X, Y, N = tau[i, 0], tau[i, 1], tau[i, 2]
        F1 = _clip(X, f1lo, f1hi)
        F2 = (L3 * Y + N) / lever  # T^-1 tau, eq. 25
        F3 = (L2 * Y - N) / lever
        if inverse:
            b2, b3 = _clip(F2, f2lo, f2hi), _clip(F3, f3lo, f3hi)
            s2, s3 = not _inside(F2, f2lo, f2hi), not _inside(F3, f3lo, f3hi)
        elif _inside(F2, f2lo, f2hi) and _inside(F3, f3lo, f3hi):
            b2, b3 = _clip(F2, f2lo, f2hi), _clip(F3, f3lo, f3hi)
            s2 = s3 = False
        else:  # the optimum is on the boundary: best of the four edges, each in closed form
            best = math.inf
            b2 = b3 = 0.0
            for edge in (f2lo, f2hi):  # F2 = edge, minimise over F3
                f3 = _clip((wY * (Y - edge) + wN * L3 * (L2 * edge - N)) / d3, f3lo, f3hi)
                eY = edge + f3 - Y
                eN = L2 * edge - L3 * f3 - N
                J = wY * eY * eY + wN * eN * eN
                if J < best:
                    best, b2, b3 = J, edge, f3
            for edge in (f3lo, f3hi):  # F3 = edge, minimise over F2
                f2 = _clip((wY * (Y - edge) + wN * L2 * (N + L3 * edge)) / d2, f2lo, f2hi)
                eY = f2 + edge - Y
                eN = L2 * f2 - L3 * edge - N
                J = wY * eY * eY + wN * eN * eN
                if J < best:
                    best, b2, b3 = J, f2, edge
            s2, s3 = _at_limit(b2, f2lo, f2hi), _at_limit(b3, f3lo, f3hi)
        Yd, Nd = Y, N  # F2, F3 = T^-1 (Y, N) exactly: tau_error exactly zero
        if s2 or s3:
            Yd, Nd = b2 + b3, L2 * b2 - L3 * b3
        # inverse thruster characteristics, eqs. 26-27 (with |F1|), clipped for round-off
        n1 = math.copysign(math.sqrt(abs(F1) / k1), F1) if F1 != 0.0 else 0.0
        cmd[i, 0] = _clip(n1, n_min, n_max)
        cmd[i, 1] = _clip(b2 / k2, p_min, p_max)
        cmd[i, 2] = _clip(b3 / k3, p_min, p_max)
        F[i, 0], F[i, 1], F[i, 2] = F1, b2, b3
        tdel[i, 0], tdel[i, 1], tdel[i, 2] = F1, Yd, Nd
        err[i, 0], err[i, 1], err[i, 2] = X - F1, Y - Yd, N - Nd
        sat[i, 0], sat[i, 1], sat[i, 2] = F1 != X, s2, s3
    return 0


def law_parameters(
    thrusters: ThrusterParameters, weights: tuple[float, float, float] | None = None
) -> NDArray[np.float64]:
    """The constants :func:`fixed3_law` reads: ``(k1, k2, k3, L2, L3, n_min, n_max, p_min,
    p_max, w_Y, w_N)`` (``weights``: as :func:`allocate`; ``None``: :func:`default_weights`).

    Raises:
        ValueError: ``thrusters`` of the wrong type, non-positive or non-finite weights.
    """
    _check_thrusters(thrusters)
    p = thrusters
    if weights is None:
        lever = p.L2 + p.L3
        wY, wN = 1.0, HEADING_WEIGHT / (lever * lever)
    else:
        try:
            wX, wY, wN = (float(w) for w in weights)
        except (TypeError, ValueError):
            raise ValueError(
                f"weights must be three numbers (w_X, w_Y, w_N), got {weights!r}"
            ) from None
        if not all(math.isfinite(w) and w > 0 for w in (wX, wY, wN)):
            raise ValueError(f"weights must be finite and > 0, got {weights!r}")
    return np.array([p.k1, p.k2, p.k3, p.L2, p.L3, p.n_min, p.n_max, p.p_min, p.p_max, wY, wN])


_ENTRY: list[Any] = []


def run_law(
    P: NDArray[np.float64], tau: NDArray[np.float64], inverse: bool
) -> tuple[NDArray[np.float64], ...]:
    """:func:`fixed3_law` on ``tau`` (n, 3) (C-contiguous float64) through its compiled entry
    point: ``(command, force, tau, tau_error, saturated)``, each (n, 3).

    Raises:
        ValueError: ``tau`` contains NaN or infinite values.
    """
    n = tau.shape[0]
    out = np.empty((4, n, 3))
    sat = np.empty((n, 3), dtype=np.bool_)
    args = (P, tau, inverse, out[0], out[1], out[2], out[3], sat)
    if not _ENTRY:
        _ENTRY.append(entry(fixed3_law, args))
    if _ENTRY[0](*args):
        raise ValueError(f"tau contains NaN or infinite values: {tau!r} (check the controller)")
    return out[0], out[1], out[2], out[3], sat


class Fixed3Allocator:
    """The allocation of one three-thruster set as an allocator object, ``alloc(tau, state)
    -> Allocation`` (what :func:`~shipgym.controllers.actuation.make_allocator` returns for
    the pattern): :func:`allocate` (``inverse=False``) or :func:`allocate_inverse`, with the
    constants prepared once.

    Args:
        thrusters: thruster constants, lever arms and ranges.
        inverse: the paper's ``T^-1`` (eq. 25) instead of the constrained least squares.
        weights: as :func:`allocate` (ignored with ``inverse``).
    """

    def __init__(
        self,
        thrusters: ThrusterParameters,
        inverse: bool = False,
        weights: tuple[float, float, float] | None = None,
    ) -> None:
        self.thrusters = thrusters
        self.inverse = bool(inverse)
        self._P = law_parameters(thrusters, None if inverse else weights)

    def __call__(self, tau: ArrayLike, state: ArrayLike | None = None) -> Allocation:
        """Allocate ``tau = [X, Y, N]`` (N, N, N m); ``state`` is unused (the closed form has
        no rate limits)."""
        if type(tau) is np.ndarray and tau.shape == (3,) and tau.dtype == np.float64:
            t = tau.reshape(1, 3)
            t = t if t.flags.c_contiguous else np.ascontiguousarray(t)
        else:
            t = np.array([_tau3(tau)])
        c, f, d, e, s = run_law(self._P, t, self.inverse)
        return Allocation(c[0], f[0], d[0], e[0], s[0])

    def __repr__(self) -> str:
        return f"Fixed3Allocator({'inverse' if self.inverse else 'constrained'})"


def force_capacity(thrusters: ThrusterParameters) -> NDArray[np.float64]:
    """Largest ``|X|, |Y|, |N|`` (N, N, N m) the thrusters can produce, each DOF alone.

    For the Blue Lady: ``k1 n_max^2 = 451.3 N`` ahead (astern only 78.4 N),
    ``k2 + k3 = 88.3 N`` of sway and ``k2 L2 + k3 L3 = 247.9 N m`` of yaw moment.
    """
    _check_thrusters(thrusters)
    f1lo, f1hi, f2lo, f2hi, f3lo, f3hi = _force_box(thrusters)
    L2, L3 = thrusters.L2, thrusters.L3
    return np.array(
        [
            max(f1hi, -f1lo),
            max(f2hi + f3hi, -(f2lo + f3lo)),
            max(L2 * f2hi - L3 * f3lo, -(L2 * f2lo - L3 * f3hi)),
        ]
    )


def default_weights(thrusters: ThrusterParameters) -> tuple[float, ...]:
    """Default ``(w_X, w_Y, w_N)`` of :func:`allocate`: ``(1, 1, HEADING_WEIGHT / (L2 + L3)^2)``.

    The moment error is normalised by the lever arm ``L2 + L3`` (a moment error of
    ``(L2 + L3) * 1 N`` costs as much as a 1 N force error) and then weighted
    :data:`HEADING_WEIGHT` (100) times more, so that when the tunnels saturate the yaw moment
    is kept first and the sway force gives way (heading first). The units are 1/N^2 for
    ``w_X, w_Y`` and 1/(N m)^2 for ``w_N``.
    """
    _check_thrusters(thrusters)
    lever = thrusters.L2 + thrusters.L3
    return (1.0, 1.0, HEADING_WEIGHT / (lever * lever))


# ---- the allocators --------------------------------------------------------------------------
def allocate_inverse(tau: ArrayLike, thrusters: ThrusterParameters) -> Allocation:
    """The paper's allocation: ``F = T^-1 tau`` (eq. 25), inverse characteristics, saturation.

    ``n1 = sgn(F1) sqrt(|F1| / k1)`` (eq. 26; the paper prints ``sqrt(F1 / k1)``, which is
    undefined for astern thrust) and ``p_i = F_i / k_i`` (eq. 27), each then clipped to
    ``[n_min, n_max]`` rpm and ``[p_min, p_max]``.

    Args:
        tau: requested generalised force ``[X, Y, N]`` (N, N, N m), shape (3,).
        thrusters: thruster constants, lever arms and ranges.

    Returns:
        The :class:`Allocation`; ``saturated[i]`` is ``True`` where command ``i`` was clipped.

    Raises:
        ValueError: ``tau`` is not three finite numbers, or ``thrusters`` has the wrong type.
    """
    t = np.array([_tau3(tau)])
    c, f, d, e, s = run_law(law_parameters(thrusters), t, True)
    return Allocation(c[0], f[0], d[0], e[0], s[0])


def allocate(
    tau: ArrayLike,
    thrusters: ThrusterParameters,
    weights: tuple[float, float, float] | None = None,
) -> Allocation:
    r"""Constrained weighted allocation: exact box-constrained least squares for sway/yaw.

    Surge: ``F1 = clip(X, F1_min, F1_max)``. Sway and yaw: the exact minimiser of
    ``w_Y (F2 + F3 - Y)^2 + w_N (L2 F2 - L3 F3 - N)^2`` over ``F2 in [k2 p_min, k2 p_max]``,
    ``F3 in [k3 p_min, k3 p_max]`` (see the module docstring). When ``tau`` is feasible the
    result equals :func:`allocate_inverse` (``F = T^-1 tau``, eq. 25).

    Args:
        tau: requested generalised force ``[X, Y, N]`` (N, N, N m), shape (3,).
        thrusters: thruster constants, lever arms and ranges.
        weights: ``(w_X, w_Y, w_N)`` > 0 (1/N^2, 1/N^2, 1/(N m)^2); ``w_X`` has no effect
            (surge is decoupled). ``None``: :func:`default_weights`.

    Returns:
        The :class:`Allocation`; ``saturated[i]`` is ``True`` where actuator ``i`` sits on a
        limit and the request was not met.

    Raises:
        ValueError: ``tau`` is not three finite numbers, non-positive or non-finite weights,
            or ``thrusters`` of the wrong type.
    """
    t = np.array([_tau3(tau)])
    c, f, d, e, s = run_law(law_parameters(thrusters, weights), t, False)
    return Allocation(c[0], f[0], d[0], e[0], s[0])


# ---- normalised actions ----------------------------------------------------------------------
def _range_check(
    a: NDArray[np.float64], lo: NDArray[np.float64], hi: NDArray[np.float64], what: str
) -> None:
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what} contains NaN or infinite values: {a}")
    bad = (a < lo) | (a > hi)
    if np.any(bad):
        raise ValueError(
            f"{what} outside its range [{lo.tolist()}, {hi.tolist()}]: {a} "
            "(pass clip=True to clip it on purpose)"
        )


def _scale_one(
    x: list[float], p: ThrusterParameters, *, to_action: bool
) -> NDArray[np.float64] | None:
    """Plain-float mapping of one in-range vector; ``None`` sends it to the checked path."""
    lo = (p.n_min, p.p_min, p.p_min)
    hi = (p.n_max, p.p_max, p.p_max)
    out = []
    for v, a, b in zip(x, lo, hi, strict=True):
        if to_action:
            if not a <= v <= b:  # also False for NaN
                return None
            out.append(v / b if v >= 0.0 else v / -a)
        else:
            if not -1.0 <= v <= 1.0:
                return None
            out.append(v * b if v >= 0.0 else v * -a)
    return np.array(out)


def _as_batch3(x: ArrayLike, what: str) -> NDArray[np.float64]:
    a = np.asarray(x, dtype=float)
    if a.ndim == 0 or a.shape[-1] != 3:
        raise ValueError(f"{what} must have shape (..., 3) ([n1 rpm, p2, p3]), got {a.shape}")
    return a


def command_to_action(
    command: ArrayLike,
    thrusters: ThrusterParameters,
    *,
    clip: bool = False,
) -> NDArray[np.float64]:
    """Physical command ``[n1 (rpm), p2, p3]`` -> normalised action in ``[-1, 1]^3``.

    Each axis is scaled separately on each side of zero, so 0 maps to 0 and both range ends
    to +-1: ``n1 >= 0 -> n1 / n_max``, ``n1 < 0 -> n1 / |n_min|`` (480 rpm -> 1,
    -200 rpm -> -1); ``p`` likewise with ``p_max``, ``|p_min|`` (the identity for +-1).

    Args:
        command: commands, shape (..., 3).
        thrusters: the ranges.
        clip: clip out-of-range commands instead of raising.

    Raises:
        ValueError: wrong shape, NaN/inf, or (with ``clip=False``) a command out of range.
    """
    _check_thrusters(thrusters)
    c = _as_batch3(command, "command")
    if c.shape == (3,) and not clip:  # fast path: one command per control step
        out = _scale_one(c.tolist(), thrusters, to_action=True)
        if out is not None:
            return out
    lo, hi = thrusters.lower, thrusters.upper
    if clip:
        if not np.all(np.isfinite(c)):
            raise ValueError(f"command contains NaN or infinite values: {c}")
        c = np.clip(c, lo, hi)
    else:
        _range_check(c, lo, hi, "command")
    return np.where(c >= 0.0, c / hi, c / -lo)


def action_to_command(
    action: ArrayLike,
    thrusters: ThrusterParameters,
    *,
    clip: bool = False,
) -> NDArray[np.float64]:
    """Normalised action in ``[-1, 1]^3`` -> physical command ``[n1 (rpm), p2, p3]``.

    The inverse of :func:`command_to_action`: ``a >= 0 -> a * upper``, ``a < 0 -> a * |lower|``.

    Args:
        action: actions, shape (..., 3).
        thrusters: the ranges.
        clip: clip actions outside ``[-1, 1]`` instead of raising.

    Raises:
        ValueError: wrong shape, NaN/inf, or (with ``clip=False``) an action outside [-1, 1].
    """
    _check_thrusters(thrusters)
    a = _as_batch3(action, "action")
    if a.shape == (3,) and not clip:  # fast path: one action per control step
        out = _scale_one(a.tolist(), thrusters, to_action=False)
        if out is not None:
            return out
    one = np.ones(3)
    if clip:
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action contains NaN or infinite values: {a}")
        a = np.clip(a, -one, one)
    else:
        _range_check(a, -one, one, "action")
    return np.where(a >= 0.0, a * thrusters.upper, a * -thrusters.lower)
