r"""The double-integrator Kalman filters (DKF, KBF) written once, over ``N >= 1`` envs, and
what every observer written so shares.

Public names: ``BatchedKalman``, ``BatchedStepInfo``; the registry of observers written once
over N envs (``BATCHED_OBSERVERS``, ``register_batched_observer``, ``register_batched_form``,
``make_batched_observer``), their N = 1 adapters ``OneOfBatch`` and ``BatchOfOne`` for the
single env, and the small dense algebra of the compiled laws (``mat_mul``, ``mat_mul_t``,
``joseph``, ``solve_small``, ``expm``).

Design notes: docs/design/observers.batch.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import entry, njit

from .base import (
    Estimate,
    Observer,
    OutlierGate,
    StepInfo,
    as_pose,
    as_tau,
    make_observer,
    no_measurement,
)
from .design import KalmanDesign, discretise, double_integrator

__all__ = [
    "BATCHED_OBSERVERS",
    "BatchOfOne",
    "BatchedKalman",
    "BatchedStepInfo",
    "OneOfBatch",
    "estimate_of",
    "make_batched_observer",
    "register_batched_form",
    "register_batched_observer",
]

Array = NDArray[np.float64]
_A, _C = double_integrator()
_TIME_TOL = 1e-9  # s: a clock this much behind counts as no time passing
_SHARED: dict[tuple[Any, ...], Any] = {}
"""Design-, ``R``- and interval-dependent matrices shared by all filters (designs are frozen)."""
_SHARED_SIZE = 4096
DEFAULT_INITIAL_VELOCITY_STD = (0.3, 0.3, math.radians(2.0))
"""Default initial std of ``[x_dot, y_dot, psi_dot]`` (m/s, m/s, rad/s) when ``P0`` is None:
the speeds of the harbour manoeuvre (up to 0.2 m/s, 1 deg/s) with a margin."""
_MODES = {(False, False): 0, (False, True): 1, (True, False): 2, (True, True): 3}
"""Kernel mode from ``(continuous, constant_gain)``: DKF, DKF eq. 30 gain, KBF, KBF eq. 35."""


def _dt_key(dt: float) -> float:
    return round(dt, 12)


class BatchedStepInfo(NamedTuple):
    """What one batched step did with each env's measurement (the arrays of
    :class:`~shipgym.observers.base.StepInfo`).

    Attributes:
        innovation: ``z - H x_pred`` (n, 3) (m, m, rad; heading wrapped), NaN rows where no
            measurement was given.
        nis: normalised innovation squared (n,) (-), NaN where no measurement.
        rejected: the measurement failed the NIS gate and was not used (n,).
        forced: the measurement failed the gate but was accepted (n,).
    """

    innovation: Array
    nis: Array
    rejected: NDArray[np.bool_]
    forced: NDArray[np.bool_]


# --------------------------------------------------------------------------------------------
# The run-time law: one compiled loop over the envs
# --------------------------------------------------------------------------------------------


#: the outlier gate's verdicts (:func:`outlier_gate`)
ACCEPT, FORCE, REJECT = 0, 1, 2


@njit(inline="always")
def outlier_gate(w, thr, max_rej, count, gate_open, j):  # type: ignore[no-untyped-def]
    """The outlier gate of env ``j`` (the compiled :meth:`base.OutlierGate.check
    <shipgym.observers.base.OutlierGate.check>`) for the normalised innovation ``w``: accept
    below ``thr``; else reject, up to ``max_rej`` times in a row, then force one acceptance and
    keep forcing until a sample passes. Updates ``count[j]`` and ``gate_open[j]``; returns
    ``ACCEPT``, ``FORCE`` or ``REJECT``."""
    if w <= thr:
        count[j] = 0
        gate_open[j] = False
        return ACCEPT
    if gate_open[j]:
        return FORCE
    if count[j] >= max_rej:
        count[j] = 0
        gate_open[j] = True
        return FORCE
    count[j] += 1
    return REJECT


@njit
def _kalman_step(mode, thr, max_rej, sel, dt, X, count, gate_open, yprev, has_prev, R, Rc,
                 gain, Q, blk, z, valid, innov, nis, rejected, forced):  # fmt: skip
    """Step the envs ``j`` with ``sel[j]`` over ``dt[j]`` (s) with the samples ``z[j]`` where
    ``valid[j]``, in place; returns ``-1``, or the first env whose valid sample is not finite
    (then nothing has changed).

    ``mode``: 0 DKF (Tomera 2011 eqs. 14-24), 1 DKF with the constant gain ``gain`` (Tomera 2014
    eq. 30), 2 time-varying KBF (Hamiltonian blocks ``blk[j, i]``: rows 0-3 ``exp(H dt)``, rows
    4, 5 the position rows of its two integrals), 3 steady-state KBF (Tomera 2014 eq. 35;
    ``blk[j, i]``: rows 0-1 ``exp(A_cl dt)``, row 2 the hold inputs, row 3 ``Q_cl``). ``Q[:, i]``:
    ``[Q_vv, Q_vp, Q_pp]`` of ``Q_k(dt)`` of DOF ``i``.
    """
    n = X.shape[2]
    for j in range(n):
        if sel[j] and valid[j]:
            for i in range(3):
                if not math.isfinite(z[j, i]):
                    return j
    pi, two_pi = math.pi, 2.0 * math.pi
    cont = mode >= 2
    const = mode == 1 or mode == 3
    pr = np.empty((5, 3))  # the prior [v, p, P_vv, P_vp, P_pp] per DOF
    e = np.empty(3)
    for j in range(n):
        if not sel[j]:
            continue
        d = dt[j]
        moving = d > 0.0
        for i in range(3):  # open-loop prediction F s, F P F^T + Q_k (F = I + A dt, exact)
            v, p, a, b, c = X[0, i, j], X[1, i, j], X[2, i, j], X[3, i, j], X[4, i, j]
            if moving:
                pr[0, i] = v
                pr[1, i] = p + d * v
                pr[2, i] = a + Q[0, i]
                pr[3, i] = (b + d * a) + Q[1, i]
                pr[4, i] = ((c + (2.0 * d) * b) + (d * d) * a) + Q[2, i]
            else:
                pr[0, i], pr[1, i], pr[2, i], pr[3, i], pr[4, i] = v, p, a, b, c
        if not valid[j]:  # coast (no time passing: nothing changes, the last sample kept)
            for i in range(3):
                for r in range(5):
                    X[r, i, j] = pr[r, i]
                innov[j, i] = np.nan
            nis[j] = np.nan
            rejected[j] = False
            forced[j] = False
            if moving:
                has_prev[j] = False
            continue
        w = 0.0
        for i in range(3):
            e[i] = z[j, i] - pr[1, i]
        # the heading innovation wrapped to (-pi, pi]
        e[2] = pi - np.fmod(np.fmod(pi - e[2], two_pi) + two_pi, two_pi)
        for i in range(3):
            innov[j, i] = e[i]
            w += e[i] * e[i] / (pr[4, i] + R[i, j])
        nis[j] = w
        verdict = outlier_gate(w, thr, max_rej, count, gate_open, j)
        force = verdict == FORCE
        if verdict == REJECT:
            for i in range(3):
                for r in range(5):
                    X[r, i, j] = pr[r, i]
            rejected[j] = True
            forced[j] = False
            has_prev[j] = False
            continue
        rejected[j] = False
        forced[j] = force
        if not cont:  # discrete: gain, Tomera (2011) eqs. 14, 23, Joseph form
            for i in range(3):
                a, b, c = pr[2, i], pr[3, i], pr[4, i]
                if force:  # a forced acceptance inflates the prior's position variance
                    c = c + e[i] * e[i]
                r_ = R[i, j]
                if const:
                    kv, kp = gain[0, i, j], gain[1, i, j]
                else:
                    s_ = c + r_
                    kv, kp = b / s_, c / s_
                X[0, i, j] = pr[0, i] + kv * e[i]
                X[1, i, j] = pr[1, i] + kp * e[i]
                m = 1.0 - kp  # (I - K H) P (I - K H)^T + R K K^T, H = [0, 1]
                m01 = b - kv * c
                m11 = m * c
                kvr = r_ * kv
                X[2, i, j] = ((a - kv * b) - m01 * kv) + kvr * kv
                p01 = m01 * m + kvr * kp
                p10 = (m * b - m11 * kv) + kvr * kp
                X[3, i, j] = 0.5 * (p01 + p10)
                X[4, i, j] = m11 * m + (r_ * kp) * kp
            continue
        # continuous: the sample y1 ends a first-order hold started at y0
        if not moving:  # dt = 0: the sample only becomes the next hold's start
            for i in range(3):
                yprev[i, j] = pr[1, i] + e[i]
            has_prev[j] = True
            continue
        for i in range(3):
            y1 = pr[1, i] + e[i]  # the sample, unwrapped next to the prediction
            y0 = y1 if (force or not has_prev[j]) else yprev[i, j]
            slope = (y1 - y0) / d
            s0, s1 = X[0, i, j], X[1, i, j]
            a, b, c = X[2, i, j], X[3, i, j], X[4, i, j]
            if force:
                c = c + e[i] * e[i]
            B = blk[j, i]
            if const:  # x = Phi x0 + B1 y0 + B2 slope, P = Phi P0 Phi^T + Q_cl
                f00, f01, f10, f11 = B[0, 0], B[0, 1], B[1, 0], B[1, 1]
                X[0, i, j] = ((f00 * s0 + f01 * s1) + B[2, 0] * y0) + B[2, 2] * slope
                X[1, i, j] = ((f10 * s0 + f11 * s1) + B[2, 1] * y0) + B[2, 3] * slope
                g00, g01 = f00 * a + f01 * b, f00 * b + f01 * c  # Phi P0
                g10, g11 = f10 * a + f11 * b, f10 * b + f11 * c
                X[2, i, j] = (g00 * f00 + g01 * f01) + B[3, 0]
                p01 = (g00 * f10 + g01 * f11) + B[3, 1]
                p10 = (g10 * f00 + g11 * f01) + B[3, 1]
                X[3, i, j] = 0.5 * (p01 + p10)
                X[4, i, j] = (g10 * f10 + g11 * f11) + B[3, 2]
            else:  # [X; Y] = exp(H dt) [I; P0], P = Y X^-1, x = X^-T (x0 + int Y^T C^T y / Rc)
                x00 = B[0, 0] + B[0, 2] * a + B[0, 3] * b
                x01 = B[0, 1] + B[0, 2] * b + B[0, 3] * c
                x10 = B[1, 0] + B[1, 2] * a + B[1, 3] * b
                x11 = B[1, 1] + B[1, 2] * b + B[1, 3] * c
                y00 = B[2, 0] + B[2, 2] * a + B[2, 3] * b
                y01 = B[2, 1] + B[2, 2] * b + B[2, 3] * c
                y10 = B[3, 0] + B[3, 2] * a + B[3, 3] * b
                y11 = B[3, 1] + B[3, 2] * b + B[3, 3] * c
                j00 = B[4, 0] + B[4, 2] * a + B[4, 3] * b
                j01 = B[4, 1] + B[4, 2] * b + B[4, 3] * c
                j10 = B[5, 0] + B[5, 2] * a + B[5, 3] * b
                j11 = B[5, 1] + B[5, 2] * b + B[5, 3] * c
                rc = Rc[i, j]
                r0 = s0 + (j00 * y0 + j10 * slope) / rc
                r1 = s1 + (j01 * y0 + j11 * slope) / rc
                det = x00 * x11 - x01 * x10
                i00, i01, i10, i11 = x11 / det, -x01 / det, -x10 / det, x00 / det
                X[0, i, j] = r0 * i00 + r1 * i10
                X[1, i, j] = r0 * i01 + r1 * i11
                X[2, i, j] = y00 * i00 + y01 * i10
                X[3, i, j] = 0.5 * ((y00 * i01 + y01 * i11) + (y10 * i00 + y11 * i10))
                X[4, i, j] = y10 * i01 + y11 * i11
            yprev[i, j] = y1
        has_prev[j] = True
    return -1


@njit
def _readout(X, eta, nu, P, P_nu):
    """The estimate of every env from its state ``X`` (5, 3, n), in place: pose ``eta`` and
    body velocity ``nu = R^T(psi) eta_dot`` (Tomera 2011 eq. 60) (n, 3), the covariance ``P``
    (n, 6, 6) of ``[x, y, psi, x_dot, y_dot, psi_dot]`` and ``P_nu = J P J^T`` (n, 3, 3),
    ``J`` the Jacobian of ``nu`` (``d nu / d psi = [v, -u, 0]``)."""
    for j in range(X.shape[2]):
        xd, yd, psid = X[0, 0, j], X[0, 1, j], X[0, 2, j]
        psi = X[1, 2, j]
        c, s = math.cos(psi), math.sin(psi)
        u = c * xd + s * yd
        v = -s * xd + c * yd
        for i in range(3):
            eta[j, i] = X[1, i, j]
            P[j, i, i] = X[4, i, j]
            P[j, i + 3, i + 3] = X[2, i, j]
            P[j, i, i + 3] = X[3, i, j]
            P[j, i + 3, i] = X[3, i, j]
        nu[j, 0], nu[j, 1], nu[j, 2] = u, v, psid
        vx, vy, vpsi = X[2, 0, j], X[2, 1, j], X[2, 2, j]
        ppsi, cpsi = X[4, 2, j], X[3, 2, j]
        P_nu[j, 0, 0] = v * v * ppsi + c * c * vx + s * s * vy
        P_nu[j, 0, 1] = P_nu[j, 1, 0] = -v * u * ppsi - c * s * vx + s * c * vy
        P_nu[j, 1, 1] = u * u * ppsi + s * s * vx + c * c * vy
        P_nu[j, 0, 2] = P_nu[j, 2, 0] = v * cpsi
        P_nu[j, 1, 2] = P_nu[j, 2, 1] = -u * cpsi
        P_nu[j, 2, 2] = vpsi


# ---- dense algebra of one env's small matrices, for the compiled laws (plain loops: no BLAS,
# so that an env's floats never depend on where its rows lie or on the other envs) ------------
@njit(inline="always")
def mat_mul(A, B, out):  # type: ignore[no-untyped-def]
    """``out = A B``, each entry summed in the order of ``A``'s columns (the zeros of ``A``
    skipped: the sparse transitions and measurement matrices cost their nonzeros)."""
    out[:] = 0.0
    for i in range(A.shape[0]):
        for q in range(A.shape[1]):
            a = A[i, q]
            if a != 0.0:
                for k in range(B.shape[1]):
                    out[i, k] += a * B[q, k]


@njit(inline="always")
def mat_mul_t(A, B, out):  # type: ignore[no-untyped-def]
    """``out = A B^T``, each entry summed in the order of ``B``'s columns (its zeros
    skipped)."""
    out[:] = 0.0
    for k in range(B.shape[0]):
        for q in range(B.shape[1]):
            b = B[k, q]
            if b != 0.0:
                for i in range(A.shape[0]):
                    out[i, k] += A[i, q] * b


@njit(inline="always")
def joseph(P, K, H, R, out, IKH, T, KR):  # type: ignore[no-untyped-def]
    """``out = (I - K H) P (I - K H)^T + K R K^T``: the Joseph-form covariance update
    (``IKH``, ``T`` (n, n) and ``KR`` (n, q): work space)."""
    n = P.shape[0]
    mat_mul(K, H, IKH)
    for i in range(n):
        for k in range(n):
            IKH[i, k] = (1.0 if i == k else 0.0) - IKH[i, k]
    mat_mul(IKH, P, T)
    mat_mul_t(T, IKH, out)
    mat_mul(K, R, KR)
    mat_mul_t(KR, K, T)
    for i in range(n):
        for k in range(n):
            out[i, k] += T[i, k]


@njit(inline="always")
def solve_small(S, B, out):  # type: ignore[no-untyped-def]
    """``out = S^-1 B`` (Cramer's rule for a 1x1 or 2x2 ``S``, else LAPACK)."""
    q = S.shape[0]
    if q == 1:
        for k in range(B.shape[1]):
            out[0, k] = B[0, k] / S[0, 0]
    elif q == 2:
        a, b, c, d = S[0, 0], S[0, 1], S[1, 0], S[1, 1]
        det = a * d - b * c
        for k in range(B.shape[1]):
            b0, b1 = B[0, k], B[1, k]
            out[0, k] = (d * b0 - b * b1) / det
            out[1, k] = (a * b1 - c * b0) / det
    else:
        out[:] = np.linalg.solve(S, B)


_PADE13 = (64764752532480000.0, 32382376266240000.0, 7771770303897600.0, 1187353796428800.0,
           129060195264000.0, 10559470521600.0, 670442572800.0, 33522128640.0, 1323241920.0,
           40840800.0, 960960.0, 16380.0, 182.0, 1.0)  # fmt: skip
"""The coefficients of the degree-13 Pade approximant of ``exp`` (Higham 2005, eq. 10.33)."""


@njit
def expm(A, out):  # type: ignore[no-untyped-def]
    """``out = exp(A)`` of one small square matrix: scaling and squaring with the degree-13
    Pade approximant (Higham 2005, the algorithm of ``scipy.linalg.expm`` for large norms),
    in plain loops (:func:`mat_mul`)."""
    n = A.shape[0]
    b = _PADE13
    norm = 0.0
    for k in range(n):
        c = 0.0
        for i in range(n):
            c += abs(A[i, k])
        norm = max(norm, c)
    s = max(0, int(math.ceil(math.log2(norm / 5.371920351148152)))) if norm > 0.0 else 0
    As = A / 2.0**s
    A2, A4, A6 = np.empty((n, n)), np.empty((n, n)), np.empty((n, n))
    mat_mul(As, As, A2)
    mat_mul(A2, A2, A4)
    mat_mul(A4, A2, A6)
    eye = np.eye(n)
    T = np.empty((n, n))
    mat_mul(A6, b[13] * A6 + b[11] * A4 + b[9] * A2, T)
    U = np.empty((n, n))
    mat_mul(As, T + b[7] * A6 + b[5] * A4 + b[3] * A2 + b[1] * eye, U)
    mat_mul(A6, b[12] * A6 + b[10] * A4 + b[8] * A2, T)
    V = T + b[6] * A6 + b[4] * A4 + b[2] * A2 + b[0] * eye
    R = np.linalg.solve(V - U, V + U)
    for _ in range(s):
        mat_mul(R, R, T)
        R[:] = T
    out[:] = R


_ENTRIES: dict[str, Any] = {}


def _call(name: str, fn: Any, *args: Any) -> Any:
    """``fn(*args)`` through its compiled entry point (the argument types never change)."""
    f = _ENTRIES.get(name)
    if f is None:
        f = _ENTRIES[name] = entry(fn, args)
    return f(*args)


# --------------------------------------------------------------------------------------------
# Design- and interval-dependent matrices (SciPy, cached)
# --------------------------------------------------------------------------------------------


def _shared(key: tuple[Any, ...], make: Callable[..., Any], *args: Any) -> Any:
    """``make(*args)``, computed once per ``key``."""
    val = _SHARED.get(key)
    if val is None:
        if len(_SHARED) >= _SHARED_SIZE:
            _SHARED.clear()
        val = _SHARED[key] = make(*args)
    return val


def _exact_noise(W: Array, dt: float) -> Array:
    """``Q_k(dt)`` per DOF (3, 2, 2) of the double integrator, exact (Van Loan 1978)."""
    return np.stack([discretise(_A, Wi, dt, method="exact")[1] for Wi in W])


def _hamiltonian_blocks(W: Array, Rc: Array, dt: float) -> Array:
    """Per DOF (3, 6, 4): ``exp(H dt)`` (rows 0-3) and the position rows of ``int_0^dt
    exp(H s) ds`` (row 4) and ``int_0^dt s exp(H s) ds`` (row 5), ``H = [[-A^T, C^T Rc^-1 C],
    [G Q G^T, A]]`` (Van Loan's block exponential)."""
    out = np.empty((3, 6, 4))
    for i in range(3):
        M = np.zeros((12, 12))
        M[:2, :2] = -_A.T
        M[:2, 2:4] = _C.T @ _C / Rc[i]
        M[2:4, :2] = W[i]
        M[2:4, 2:4] = _A
        M[:4, 4:8] = np.eye(4)
        M[4:8, 8:12] = np.eye(4)
        Ed = scipy.linalg.expm(M * dt)
        out[i, :4] = Ed[:4, :4]
        out[i, 4] = Ed[3, 4:8]
        out[i, 5] = dt * Ed[3, 4:8] - Ed[3, 8:12]
    return out


def _steady_blocks(W: Array, Rc: Array, L: Array, dt: float) -> Array:
    """Per DOF (3, 6, 4): ``exp(A_cl dt)`` (rows 0-1, columns 0-1), the first-order-hold
    inputs ``int_0^dt exp(A_cl (dt - s)) L [1, s] ds`` (row 2: ``[B1, B2]``) and the Lyapunov
    increment ``[Q_vv, Q_vp, Q_pp]`` of ``W + Rc L L^T`` (row 3), ``A_cl = A - L C``."""
    out = np.zeros((3, 6, 4))
    for i in range(3):
        Li = L[i][:, None]
        Acl = _A - Li @ _C
        M = np.zeros((4, 4))
        M[:2, :2] = Acl
        M[:2, 2:3] = Li
        M[2, 3] = 1.0
        Ed = scipy.linalg.expm(M * dt)
        out[i, :2, :2] = Ed[:2, :2]
        out[i, 2, :2] = Ed[:2, 2]
        out[i, 2, 2:] = Ed[:2, 3]
        Qcl = discretise(Acl, W[i] + Rc[i] * (Li @ Li.T), dt, method="exact")[1]
        out[i, 3, :3] = Qcl[0, 0], Qcl[0, 1], Qcl[1, 1]
    return out


class BatchedKalman:
    """``n`` double-integrator Kalman filters of one preset stepped together (module doc).

    Args:
        observer: a preset name (``"kbf"``, ``"dkf"``, ``"tomera-kbf"``, ``"tomera-dkf"``, or
            another name whose factory builds one of the two filter classes), a factory
            ``(**overrides) -> filter`` or a filter instance (its design and settings are used).
        n: number of envs, >= 1.
        vessel: the vessel the preset is fitted to, as :func:`~shipgym.observers.base.
            make_observer` (only with a name).
        R: per-env measurement variances ``(n, 3)`` or one ``(3,)`` (m^2, m^2, rad^2);
            ``None``: the design's.
        **overrides: the factory's options (design fields, ``gate_probability``, ...).

    Raises:
        ValueError: ``n`` not an int >= 1, an observer that is not one of the two
            double-integrator filters, bad ``R``.
    """

    def __init__(
        self,
        observer: str | Callable[..., Any] | Any = "kbf",
        n: int = 1,
        *,
        vessel: Any = None,
        R: ArrayLike | None = None,
        **overrides: Any,
    ) -> None:
        if isinstance(observer, str):
            template = make_observer(observer, vessel, **overrides)
        elif hasattr(observer, "_batch_settings"):
            if overrides or vessel is not None:
                raise ValueError("overrides and vessel= need a preset name or a factory")
            template = observer
        elif callable(observer):
            template = observer(**overrides)
        else:
            raise ValueError(f"observer must be a name, a factory or a filter, got {observer!r}")
        if not hasattr(template, "_batch_settings"):
            raise ValueError(
                "BatchedKalman batches the double-integrator filters (DiscreteKalmanFilter, "
                f"KalmanBucyFilter), got {type(template).__name__}"
            )
        self._setup(n=n, R=R, **template._batch_settings())

    @classmethod
    def from_design(
        cls,
        design: KalmanDesign,
        n: int = 1,
        *,
        continuous: bool,
        constant_gain: bool,
        name: str,
        gate_probability: float | None = 0.9999,
        max_rejections: int = 5,
        initial_velocity_std: ArrayLike = DEFAULT_INITIAL_VELOCITY_STD,
        R: ArrayLike | None = None,
    ) -> BatchedKalman:
        """``n`` filters of a :class:`~shipgym.observers.design.KalmanDesign`: the continuous
        (Kalman-Bucy) or discrete filter, time-varying or with the steady-state gain, the
        gate of ``gate_probability`` / ``max_rejections`` and the default initial std of the
        rates ``initial_velocity_std`` (m/s, m/s, rad/s)."""
        self = cls.__new__(cls)
        self._setup(
            n=n,
            R=R,
            design=design,
            continuous=continuous,
            constant_gain=constant_gain,
            name=name,
            gate=OutlierGate(gate_probability, dof=3, max_rejections=max_rejections),
            initial_velocity_std=initial_velocity_std,
        )
        return self

    def _setup(
        self,
        *,
        n: int,
        R: ArrayLike | None,
        design: KalmanDesign,
        continuous: bool,
        constant_gain: bool,
        name: str,
        gate: OutlierGate,
        initial_velocity_std: ArrayLike,
    ) -> None:
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ValueError(f"n must be an int >= 1 (the number of envs), got {n!r}")
        n = int(n)
        self.name = str(name)
        self.n = n
        self.design = design
        self.continuous = bool(continuous)
        self.constant_gain = bool(constant_gain)
        self.threshold = float(gate.threshold)
        self.max_rejections = int(gate.max_rejections)
        self._mode = _MODES[self.continuous, self.constant_gain]
        self._W = design.intensity()  # (3, 2, 2) G Q G^T per DOF
        self._vel_var = np.asarray(initial_velocity_std, dtype=float) ** 2
        self._T = float(design.T)
        self._X = np.zeros((5, 3, n))
        self._t = np.zeros(n)
        self._started = np.zeros(n, dtype=bool)
        self._all_started = False
        self._count = np.zeros(n, dtype=np.int64)
        self._open = np.zeros(n, dtype=bool)
        self._yprev = np.zeros((3, n))
        self._has_prev = np.zeros(n, dtype=bool)
        self._R = np.repeat(design.variance()[:, None], n, axis=1)
        self._Rc = self._R * self._T
        self._gain = np.zeros((2, 3, n))  # the steady-state gain per env (constant-gain kinds)
        self._blocks: dict[float, tuple[Array, Array]] = {}  # dt key -> (Q (3, 3), blocks)
        self._no_blocks = np.zeros((0, 3, 6, 4))
        self._all = np.ones(n, dtype=bool)
        self._none = np.zeros(n, dtype=bool)
        self._z0 = np.zeros((n, 3))
        self._dt = np.zeros(n)
        self._tt = np.zeros(n)  # step's times (s), (n,)
        self._innov = np.zeros((n, 3))
        self._nis = np.zeros(n)
        self._rej = np.zeros(n, dtype=bool)
        self._forced = np.zeros(n, dtype=bool)
        self._out: tuple[Array, ...] | None = None  # the read-outs of the current state
        self._set_R(self._R.T if R is None else R, self._all, force=True)

    # ---- parameters ---------------------------------------------------------------------------
    def _rows(self, x: ArrayLike, what: str, unit: str) -> Array:
        a = np.asarray(x, dtype=float)
        if a.shape == (3,):
            a = np.broadcast_to(a, (self.n, 3))
        if a.shape != (self.n, 3):
            raise ValueError(f"{what} must be (3,) or ({self.n}, 3) ({unit}), got {np.shape(x)}")
        return a

    def _mask(self, mask: ArrayLike | None) -> NDArray[np.bool_]:
        if mask is None:
            return self._all
        m = np.asarray(mask, dtype=bool)
        if m.shape != (self.n,):
            raise ValueError(f"mask must be ({self.n},) booleans, got shape {m.shape}")
        return m

    def _set_R(self, R: ArrayLike, m: NDArray[np.bool_], force: bool = False) -> None:
        """Set the variances of the envs in ``m``; refresh what depends on them."""
        Rn = self._rows(R, "R", "m^2, m^2, rad^2 per env").T
        if not np.all(np.isfinite(Rn[:, m])) or not np.all(Rn[:, m] > 0.0):
            raise ValueError("R must be finite variances > 0 (m^2, m^2, rad^2)")
        changed = m if force else m & np.any(Rn != self._R, axis=0)
        if not changed.any():
            return
        self._R[:, changed] = Rn[:, changed]
        self._Rc[:, changed] = self._R[:, changed] * self._T
        if self.constant_gain:
            for j in np.nonzero(changed)[0].tolist():
                self._gain[:, :, j] = self._steady_gain(tuple(self._R[:, j].tolist())).T
        self._blocks.clear()

    def _steady_gain(self, R: tuple[float, ...]) -> Array:
        """The steady-state gain (3, 2) for the variances ``R``: Tomera (2014) eq. 35 (KBF,
        :func:`~shipgym.observers.design.lqe`) or eq. 30 (the DKF's filter form at the
        design period ``T``, :func:`~shipgym.observers.design.dlqe`)."""
        d = self.design if R == self.design.R else self.design.replace(R=R)
        if self.continuous:
            return _shared(("L", d), lambda: d.kbf_gains()[0])
        return _shared(("K", d), lambda: d.dkf_gains(form="filter")[0])

    @property
    def R(self) -> Array:
        """The per-env measurement variances (n, 3) (m^2, m^2, rad^2), a copy."""
        return self._R.T.copy()

    @property
    def steady_state_gain(self) -> Array:
        """The per-env steady-state gains (n, 3, 2), seed order ``[velocity, position]``
        (constant-gain kinds only; zeros otherwise)."""
        return self._gain.transpose(2, 1, 0).copy()

    # ---- cached interval matrices --------------------------------------------------------------
    def _interval(self, dt: float) -> tuple[Array, Array]:
        """``Q_k(dt)`` (3, 3) ``[Q_vv, Q_vp, Q_pp]`` per DOF and the per-env blocks of the
        interval ``dt`` (s), already rounded to its key (:func:`_dt_key`): what a filter
        gets depends on its own interval only, never on which env, filter or test computed
        a shared entry first."""
        key = dt
        val = self._blocks.get(key)
        if val is not None:
            return val
        d = self.design
        if self.continuous:  # the continuous filter coasts with the exact Q_k
            Qd = _shared(("Qc", d, key), _exact_noise, self._W, dt)
        else:
            Qd = _shared(("Qd", d, key), lambda: d.sampled(dt)[1])
        Q = np.ascontiguousarray(np.stack([Qd[:, 0, 0], Qd[:, 0, 1], Qd[:, 1, 1]]))
        if self.continuous:
            blk = np.empty((self.n, 3, 6, 4))
            rows = np.unique(self._R.T, axis=0)
            for Rrow in rows:
                Rt = tuple(Rrow.tolist())
                Rc = Rrow * self._T
                if self.constant_gain:
                    L = self._steady_gain(Rt)
                    b = _shared(("ss", d, Rt, key), _steady_blocks, self._W, Rc, L, dt)
                else:
                    b = _shared(("tv", d, Rt, key), _hamiltonian_blocks, self._W, Rc, dt)
                blk[np.all(self._R.T == Rrow, axis=1)] = b
        else:
            blk = self._no_blocks
        if len(self._blocks) >= 16:
            self._blocks.clear()
        val = self._blocks[key] = (Q, blk)
        return val

    # ---- interface ----------------------------------------------------------------------------
    def reset(
        self,
        t0: ArrayLike,
        eta0: ArrayLike,
        *,
        mask: ArrayLike | None = None,
        R: ArrayLike | None = None,
        nu0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
    ) -> None:
        """Start the envs (all, or those where ``mask`` is True) at ``t0`` from ``eta0``.

        Args:
            t0: initial time (s), one number or (n,).
            eta0: poses ``[x, y, psi]`` (m, m, rad), (3,) or (n, 3); the heading's branch
                is kept.
            mask: (n,) booleans, ``None`` = all.
            R: new measurement variances (3,) or (n, 3) (m^2, m^2, rad^2) for the reset envs;
                ``None`` keeps theirs.
            nu0: body velocities ``[u, v, r]`` (m/s, m/s, rad/s), (3,) or (n, 3); ``None`` =
                rest.
            P0: initial covariances (6, 6) or (n, 6, 6) of ``[x, y, psi, x_dot, y_dot,
                psi_dot]`` (cross-DOF terms ignored); ``None``: ``R`` for the pose and
                ``initial_velocity_std**2`` for the rates.

        Raises:
            ValueError: mis-shaped or non-finite arguments, ``P0`` not symmetric ``>= 0``.
        """
        m = self._mask(mask)
        tt = np.broadcast_to(np.asarray(t0, dtype=float), (self.n,))
        eta = self._rows(eta0, "eta0", "m, m, rad")
        if not (np.all(np.isfinite(tt[m])) and np.all(np.isfinite(eta[m]))):
            raise ValueError("t0 and eta0 must be finite")
        if nu0 is not None:
            nu = self._rows(nu0, "nu0", "m/s, m/s, rad/s")
            if not np.all(np.isfinite(nu[m])):
                raise ValueError("nu0 must be finite")
        Pb = None if P0 is None else self._covariances(P0, m)
        if R is not None:
            self._set_R(R, m)
        X = self._X
        if nu0 is None:
            X[0][:, m] = 0.0
        else:
            c, s = np.cos(eta[:, 2]), np.sin(eta[:, 2])
            eta_dot = np.stack([c * nu[:, 0] - s * nu[:, 1], s * nu[:, 0] + c * nu[:, 1], nu[:, 2]])
            X[0][:, m] = eta_dot[:, m]
        X[1][:, m] = eta.T[:, m]
        if Pb is None:
            X[2][:, m] = self._vel_var[:, None]
            X[3][:, m] = 0.0
            X[4][:, m] = self._R[:, m]
        else:
            X[2:5][:, :, m] = Pb[:, :, m]
        self._t[m] = tt[m]
        self._count[m] = 0
        self._open[m] = False
        self._has_prev[m] = False
        self._started[m] = True
        self._all_started = bool(self._started.all())
        self._out = None

    def _covariances(self, P0: ArrayLike, m: NDArray[np.bool_]) -> Array:
        """``[P_vv, P_vp, P_pp]`` (3, 3, n) of the 6x6 ``P0`` per env, checked."""
        P6 = np.asarray(P0, dtype=float)
        if P6.shape == (6, 6):
            P6 = np.broadcast_to(P6, (self.n, 6, 6))
        if P6.shape != (self.n, 6, 6) or not np.isfinite(P6[m]).all():
            raise ValueError(
                f"P0 must be a finite 6x6 matrix (or one per env), got shape {np.shape(P0)}"
            )
        Pm = P6[m]
        if not np.allclose(Pm, Pm.transpose(0, 2, 1), rtol=1e-9, atol=1e-12):
            raise ValueError("P0 must be symmetric")
        scale = np.maximum(np.abs(Pm).max(axis=(1, 2)), 1e-300)
        if (np.linalg.eigvalsh(0.5 * (Pm + Pm.transpose(0, 2, 1)))[:, 0] < -1e-12 * scale).any():
            raise ValueError("P0 must be positive semi-definite")
        i = np.arange(3)
        out = np.empty((3, 3, self.n))
        out[0] = P6[:, i + 3, i + 3].T
        out[1] = 0.5 * (P6[:, i + 3, i] + P6[:, i, i + 3]).T
        out[2] = P6[:, i, i].T
        return out

    def step(
        self,
        t: ArrayLike,
        z: ArrayLike | None = None,
        valid: ArrayLike | None = None,
        tau: ArrayLike | None = None,
    ) -> BatchedStepInfo:
        """Propagate every env to its ``t`` and update it with its pose ``z`` where ``valid``.

        Args:
            t: time now (s), one number or (n,), not earlier than each env's previous call.
            z: measured poses ``[x, y, psi]`` (n, 3) (m, m, rad; heading in any branch), rows
                of invalid envs ignored (NaN allowed); ``None``: no measurement (coast).
            valid: (n,) booleans, ``None`` = all (with ``z``).
            tau: body thrust (n, 3) (N, N, N m), unused (kinematic model) or ``None``.

        Returns:
            :class:`BatchedStepInfo` (fresh arrays).

        Raises:
            RuntimeError: an env was never reset.
            ValueError: time going backwards, mis-shaped input, a non-finite valid ``z``.
        """
        n = self.n
        if tau is not None and np.shape(tau) != (n, 3):
            raise ValueError(f"tau must be ({n}, 3) [X, Y, N] (N, N, N m), got {np.shape(tau)}")
        if z is None:
            za, vm = self._z0, self._none
        else:
            za = np.ascontiguousarray(z, dtype=float)
            if za.shape != (n, 3):
                raise ValueError(
                    f"z must be ({n}, 3) poses [x, y, psi] (m, m, rad), got {za.shape}"
                )
            if valid is None:
                vm = self._all
            else:
                vm = np.ascontiguousarray(valid, dtype=bool)
                if vm.shape != (n,):
                    raise ValueError(f"valid must be ({n},) booleans, got shape {vm.shape}")
        tt = self._tt
        tt[:] = t  # a scalar or (n,) (broadcast, as np.broadcast_to refuses other shapes)
        self._advance(tt, za, vm)
        return BatchedStepInfo(
            self._innov.copy(), self._nis.copy(), self._rej.copy(), self._forced.copy()
        )

    def _advance(self, tt: Array, za: Array, vm: NDArray[np.bool_]) -> None:
        """The step into ``_innov``, ``_nis``, ``_rej``, ``_forced``: ``tt`` (n,) times (s),
        ``za`` (n, 3) C-contiguous samples, ``vm`` (n,) C-contiguous valid flags."""
        if not self._all_started:
            if not self._started.all():
                raise RuntimeError(f"{self.name}: call reset(t0, eta0) for every env before step()")
            self._all_started = True
        dt = self._dt
        np.subtract(tt, self._t, out=dt)
        d0 = float(dt[0])
        if not (d0 >= 0.0 and (self.n == 1 or (dt == d0).all())):
            if not np.all(np.isfinite(tt)):
                raise ValueError(f"{self.name}: t must be finite")
            if (dt < -_TIME_TOL).any():
                i = int(np.argmin(dt))
                raise ValueError(
                    f"{self.name}: time must not go backwards (env {i}: previous {self._t[i]}, "
                    f"got {tt[i]!r})"
                )
            back = dt < 0.0  # rounding of the caller's clock: no time passes
            tt = np.where(back, self._t, tt)
            dt[back] = 0.0
        keys = [_dt_key(d0)] if self.n == 1 or (dt == d0).all() else np.unique(np.round(dt, 12))
        for key in keys:
            key = float(key)
            sel = self._all if len(keys) == 1 else np.round(dt, 12) == key
            Q, blk = self._interval(key)  # from the key itself, not the first env's dt
            bad = _call(
                "step", _kalman_step, self._mode, self.threshold, self.max_rejections, sel, dt,
                self._X, self._count, self._open, self._yprev, self._has_prev, self._R,
                self._Rc, self._gain, Q, blk, za, vm, self._innov, self._nis, self._rej,
                self._forced,
            )  # fmt: skip
            if bad >= 0:
                raise ValueError(f"{self.name}: z must be finite where valid (env {bad})")
        self._t[:] = tt
        self._out = None

    # ---- estimates ----------------------------------------------------------------------------
    def _readouts(self) -> tuple[Array, ...]:
        """``(eta, nu, P, P_nu)`` of the current state (computed once per state)."""
        out = self._out
        if out is None:
            n = self.n
            out = (np.empty((n, 3)), np.empty((n, 3)), np.zeros((n, 6, 6)), np.empty((n, 3, 3)))
            _call("readout", _readout, self._X, *out)
            self._out = out
        return out

    @property
    def t(self) -> Array:
        """Each env's time (s), (n,)."""
        return self._t.copy()

    @property
    def eta(self) -> Array:
        """Estimated poses ``[x, y, psi]`` (n, 3) (m, m, rad; heading continuous)."""
        return self._readouts()[0].copy()

    @property
    def eta_dot(self) -> Array:
        """Estimated NED rates ``[x_dot, y_dot, psi_dot]`` (n, 3) (m/s, m/s, rad/s)."""
        return self._X[0].T.copy()

    @property
    def nu(self) -> Array:
        """Body velocities ``[u, v, r]`` (n, 3), ``R^T(psi) eta_dot`` (Tomera 2011 eq. 60)."""
        return self._readouts()[1].copy()

    @property
    def P_eta(self) -> Array:
        """Covariances of ``eta`` (n, 3, 3) (m^2, rad^2), diagonal."""
        return self._readouts()[2][:, :3, :3].copy()

    @property
    def P_nu(self) -> Array:
        """Covariances of ``nu`` (n, 3, 3): ``J P J^T`` with ``J`` the Jacobian of
        ``R^T(psi) eta_dot`` (``d nu / d psi = [v, -u, 0]``)."""
        return self._readouts()[3].copy()

    @property
    def P(self) -> Array:
        """Covariances (n, 6, 6) of ``[x, y, psi, x_dot, y_dot, psi_dot]``; cross-DOF terms
        are zero."""
        return self._readouts()[2].copy()

    @property
    def x(self) -> Array:
        """States (n, 6) ``[x, y, psi, x_dot, y_dot, psi_dot]``."""
        return np.concatenate([self._X[1].T, self._X[0].T], axis=1)

    def estimate(self, j: int) -> Estimate:
        """Env ``j``'s estimate (copies); ``P`` in ``[x, y, psi, x_dot, y_dot, psi_dot]``."""
        eta, nu, P, P_nu = self._readouts()
        return Estimate(t=float(self._t[j]), eta=eta[j].copy(), nu=nu[j].copy(), P=P[j].copy(),
                        P_eta=P[j, :3, :3].copy(), P_nu=P_nu[j].copy())  # fmt: skip


# ---- observers written once: the batched registry and its N = 1 adapter --------------------
#: batched observers by name: ``factory(n, vessel)`` returns an observer of ``n`` envs with
#: ``reset(t0, eta0, mask=None)`` (``t0`` (n,) s, ``eta0`` (n, 3) m, m, rad), ``step(t, z,
#: valid) -> BatchedStepInfo`` (``z`` (n, 3) with NaN rows where ``valid`` is False) and the
#: estimates ``eta``, ``nu`` ((n, 3) arrays); ``model_based`` (optional, default False) as
#: :attr:`Observer.model_based <shipgym.observers.base.Observer.model_based>`: a model-based
#: one's ``step`` also takes ``tau=`` (n, 3), the thrust its ``thrust_input`` names
#: (``"applied"``, default: the bollard model of the actuator states; ``"command"``). The vector env
#: runs it for N envs, the single env (``shipgym.make(..., observer=name)``) for one: one
#: implementation for both; :class:`OneOfBatch` is its scalar ``Observer`` interface.
#: An env steps env ``i``'s observer at env ``i``'s samples (the others' times unchanged)
#: and coasts it (``z=None``) to the end of a control period that did not end at a sample,
#: unless it has ``fixed_interval = True`` (discretised for one sampling interval).
BATCHED_OBSERVERS: dict[str, Callable[[int, Any], Any]] = {}


def register_batched_observer(name: str, factory: Callable[[int, Any], Any]) -> None:
    """Register an observer written once over N envs under ``name``, for the vector env
    (:data:`BATCHED_OBSERVERS`) and, at N = 1, for the single env (the observer registry of
    :func:`~shipgym.observers.base.make_observer`)."""
    from .base import register_observer

    if not isinstance(name, str) or not name:
        raise ValueError(f"an observer name must be a non-empty string, got {name!r}")
    BATCHED_OBSERVERS[name] = factory

    def one(vessel: Any = None, **overrides: Any) -> Observer:
        if overrides:
            raise TypeError(
                f"observer {name!r} (batched) takes no options, got {sorted(overrides)}"
            )
        return OneOfBatch(factory(1, vessel), name)

    register_observer(name, one, vessel_overrides=lambda vessel: {"vessel": vessel})


def register_batched_form(name: str) -> None:
    """Run the registered observer ``name`` batched: :data:`BATCHED_OBSERVERS` builds its
    preset for the vessel (:func:`~shipgym.observers.base.make_observer`) and takes the
    batched law of ``n`` envs from it (its ``batch(n)``); the single env keeps the preset's
    own factory (with its options), which runs the same law at N = 1."""
    BATCHED_OBSERVERS[name] = lambda n, vessel: make_observer(name, vessel).batch(n)  # type: ignore[attr-defined]


def make_batched_observer(name: str, n: int, vessel: Any, **options: Any) -> Any:
    """The observer ``name`` of ``n`` envs fitted to ``vessel``: a registered batched observer
    (:data:`BATCHED_OBSERVERS`: every built-in observer), else a double-integrator Kalman
    preset (:class:`BatchedKalman`, whose error names the valid ones).

    ``options``: the observer's options, as :func:`~shipgym.observers.base.make_observer`
    takes them (e.g. ``beaufort=5``, the sea state an ``alt-*`` wave filter is designed for);
    they win over the vessel's. An observer registered with :func:`register_batched_observer`
    takes none."""
    factory = BATCHED_OBSERVERS.get(name)
    if factory is None:
        from .base import _load_builtins

        _load_builtins()
        factory = BATCHED_OBSERVERS.get(name)
    if factory is None:
        return BatchedKalman(name, n, vessel=vessel, **options)
    if not options:
        return factory(n, vessel)
    preset = make_observer(name, vessel, **options)  # a batched form's preset, with them
    batch = getattr(preset, "batch", None)
    if batch is None:
        raise TypeError(f"observer {name!r} (batched) takes no options, got {sorted(options)}")
    return batch(n)


class BatchOfOne(Observer):
    """The :class:`~shipgym.observers.base.Observer` interface of one env of a batched
    observer ``self._b`` (set by the subclass): the single env runs the batched law at N = 1.

    The batch has ``reset(t0 (n,), eta0 (n, 3), mask=None, **rows)``, ``step(t (n,), z (n, 3),
    valid (n,)) -> BatchedStepInfo`` (a model-based one also ``tau=`` (n, 3) or ``None``) and
    ``estimate(j) -> Estimate``.
    """

    _b: Any
    _started = False
    _t = 0.0

    def _reset_one(self, t0: float, eta0: ArrayLike, **rows: Any) -> None:
        """Reset the batch of one at ``t0`` from ``eta0``; ``rows``: per-env arrays of the
        batch's reset (one env's value, or ``None``)."""
        t0 = float(t0)
        if not math.isfinite(t0):
            raise ValueError(f"t0 must be finite, got {t0!r}")
        extra = {
            k: None if v is None else np.asarray(v, dtype=float)[None] for k, v in rows.items()
        }
        self._b.reset(np.array([t0]), as_pose(eta0, "eta0").reshape(1, 3), **extra)
        self._t = t0
        self._started = True

    def step(self, t: float, z: ArrayLike | None, tau: ArrayLike | None = None) -> StepInfo:
        if not self._started:
            raise RuntimeError(f"{self.name}: call reset(t0, eta0) before step()")
        valid = z is not None
        args = (
            np.array([float(t)]),
            np.full((1, 3), np.nan) if z is None else as_pose(z).reshape(1, 3),
            np.array([valid]),
        )
        if self.model_based:  # the thrust, (1, 3) (only a model-based batch takes it)
            ta = as_tau(tau)
            info = self._b.step(*args, tau=None if ta is None else ta.reshape(1, 3))
        else:
            info = self._b.step(*args)
        self._t = float(t)
        return _step_info(info) if valid else no_measurement()

    def estimate(self) -> Estimate:
        if not self._started:
            raise RuntimeError(f"{self.name}: call reset(t0, eta0) before estimate()")
        return self._b.estimate(0)


class OneOfBatch(BatchOfOne):
    """A batched observer (:data:`BATCHED_OBSERVERS`) as the single env's
    :class:`~shipgym.observers.base.Observer`: the same code at N = 1.

    Its estimate has the pose and velocity only (``P`` and ``P_eta`` NaN, ``P_nu`` None)
    unless the batched observer has ``P_eta`` ((n, 3, 3)).
    """

    def __init__(self, batch: Any, name: str) -> None:
        self._b = batch
        self.name = name
        self.model_based = bool(getattr(batch, "model_based", False))

    def reset(
        self, t0: float, eta0: ArrayLike, *, nu0: ArrayLike | None = None, P0: Any = None
    ) -> None:
        if nu0 is not None or P0 is not None:
            raise ValueError(f"observer {self.name!r} starts from a pose only (no nu0, P0)")
        self._reset_one(t0, eta0)

    def estimate(self) -> Estimate:
        if not self._started:
            raise RuntimeError(f"{self.name}: call reset(t0, eta0) before estimate()")
        return estimate_of(self._b, 0, self._t)


def estimate_of(observer: Any, j: int, t: float = math.nan) -> Estimate:
    """Env ``j``'s :class:`~shipgym.observers.base.Estimate` of a batched observer: its
    ``estimate(j)`` where it has one, else its pose and velocity (``P`` and ``P_eta`` NaN
    unless it has ``P_eta`` ((n, 3, 3)), ``P_nu`` None) at the time ``t`` (s)."""
    own = getattr(observer, "estimate", None)
    if own is not None:
        return own(j)  # type: ignore[no-any-return]
    p = getattr(observer, "P_eta", None)
    P_eta = np.full((3, 3), np.nan) if p is None else np.array(p[j], dtype=float)
    return Estimate(
        t=float(t),
        eta=np.array(observer.eta[j], dtype=float),
        nu=np.array(observer.nu[j], dtype=float),
        P=np.full((6, 6), np.nan),
        P_eta=P_eta,
        P_nu=None,
    )


def _step_info(info: BatchedStepInfo) -> StepInfo:
    """Env 0's :class:`StepInfo` of a batched step."""
    innov = np.asarray(info.innovation, dtype=float)[0]
    nis = float(info.nis[0])
    if np.isnan(innov).all() and math.isnan(nis) and not info.rejected[0]:
        return no_measurement()
    return StepInfo(innov.copy(), None if math.isnan(nis) else nis, bool(info.rejected[0]),
                    bool(info.forced[0]))  # fmt: skip
