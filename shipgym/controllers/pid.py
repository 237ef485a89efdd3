r"""The multivariable PID-type DP controller of Tomera (2014) (eqs. 13-23).

Law (eq. 23 read in the r-frame): ``tau = M R^T(psi)(eta_ddot_d - K_D e_dot - K_P e - K_I xi)
+ ... + D_L nu``, error polynomial ``s^3 + K_D s^2 + K_P s + K_I`` (eq. 18); tuned gains.

Public names: ``PIDGains``, ``GAIN_PRESETS``, ``pid_gains``, ``pid_pole_placement``,
``error_loop``, ``BatchedPID``, ``MultivariablePID``, ``TUNED_OMEGA``, ...

Design notes: docs/design/controllers.pid.md.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import require_given
from shipgym._jit import entry, njit

_DESIGN_HINT = (
    "pass the vessel's design model, e.g. M=v.design.M, D_L=v.design.D_L with "
    "v = load_vessel('blue-lady')"
)
_LIMIT_HINT = (
    "pass the vessel's force capacity (N, N, N m), e.g. "
    "integral_limit=planar_capacity(load_vessel('blue-lady')), or inf"
)

__all__ = [
    "PIDGains",
    "GAIN_PRESETS",
    "pid_gains",
    "pid_pole_placement",
    "error_loop",
    "BatchedPID",
    "MultivariablePID",
    "TUNED_OMEGA",
    "SMOOTH_OMEGA",
    "SATURATION_TOL",
    "VELOCITY_SOURCES",
    "vessel_pid",
]

Vec3 = tuple[float, float, float]

#: |tau_error| (N or N m) above which a DOF counts as saturated in the anti-windup
SATURATION_TOL = 1e-6


def _gain3(value: Any, name: str) -> Vec3:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = np.full(3, float(arr))
    if arr.shape != (3,) or not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise ValueError(
            f"{name} must be a scalar or 3 finite values >= 0 (surge, sway, yaw), got {value!r}"
        )
    return (float(arr[0]), float(arr[1]), float(arr[2]))


@dataclass(frozen=True)
class PIDGains:
    """Diagonal gains of the PID-type DP controller (Tomera 2014 eqs. 18-19).

    The gains act on accelerations (``a = -K_D e_dot - K_P e - K_I xi``), so the per-DOF
    closed-loop error polynomial is ``s^3 + K_D s^2 + K_P s + K_I``. Each gain is a scalar
    (same for all DOFs) or three values (surge/x, sway/y, yaw), all >= 0.

    Attributes:
        K_P: proportional gain (1/s^2).
        K_I: integral gain (1/s^3).
        K_D: derivative gain (1/s).
    """

    K_P: Vec3 = field(metadata={"unit": "1/s^2", "source": "Tomera (2014) eq. 46 (seed preset)"})
    K_I: Vec3 = field(metadata={"unit": "1/s^3", "source": "Tomera (2014) eq. 47 (seed preset)"})
    K_D: Vec3 = field(metadata={"unit": "1/s", "source": "Tomera (2014) eq. 48 (seed preset)"})

    def __post_init__(self) -> None:
        for name in ("K_P", "K_I", "K_D"):
            object.__setattr__(self, name, _gain3(getattr(self, name), name))

    @classmethod
    def from_pole_placement(cls, omega: ArrayLike, zeta: float = 1.0) -> PIDGains:
        """Gains from :func:`pid_pole_placement` (``omega`` in rad/s, scalar or per DOF)."""
        K_P, K_I, K_D = pid_pole_placement(np.broadcast_to(np.asarray(omega, float), (3,)), zeta)
        return cls(tuple(K_P), tuple(K_I), tuple(K_D))  # type: ignore[arg-type]

    def error_poles(self, dt: float | None = None) -> NDArray[np.complex128]:
        """Error-loop poles per DOF, shape (3, 3): continuous, or the sampled loop's eigenvalues.

        See :func:`error_loop`.
        """
        return np.array(
            [
                error_loop(p, i, d, dt)[1]
                for p, i, d in zip(self.K_P, self.K_I, self.K_D, strict=True)
            ]
        )


def pid_pole_placement(
    omega: ArrayLike, zeta: float = 1.0
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    r"""Place the per-DOF error poles of eq. 18: returns ``K_P, K_I, K_D``.

    The per-DOF error dynamics ``e_ddot + K_D e_dot + K_P e + K_I xi = 0``, ``xi_dot = e``, have
    the characteristic polynomial ``s^3 + K_D s^2 + K_P s + K_I``. Matching it to

    .. math::

        (s + \omega)(s^2 + 2\zeta\omega s + \omega^2)
        = s^3 + (2\zeta + 1)\omega s^2 + (2\zeta + 1)\omega^2 s + \omega^3

    gives ``K_D = (2 zeta + 1) omega``, ``K_P = (2 zeta + 1) omega^2``, ``K_I = omega^3``
    (``zeta = 1``: a triple pole at ``-omega``).

    Args:
        omega: natural frequency (rad/s) > 0, scalar or array (one per DOF).
        zeta: relative damping of the complex pair (-) > 0.

    Returns:
        ``(K_P, K_I, K_D)`` in 1/s^2, 1/s^3, 1/s, each with the shape of ``omega``.

    Raises:
        ValueError: non-positive or non-finite ``omega`` or ``zeta``.
    """
    w = np.asarray(omega, dtype=float)
    if not (np.all(np.isfinite(w)) and np.all(w > 0)):
        raise ValueError(f"omega must be finite and > 0 (rad/s), got {omega!r}")
    if not (math.isfinite(zeta) and zeta > 0):
        raise ValueError(f"zeta must be finite and > 0, got {zeta!r}")
    c = 2.0 * zeta + 1.0
    return c * w * w, w * w * w, c * w


def error_loop(
    k_p: float, k_i: float, k_d: float, dt: float | None = None
) -> tuple[NDArray[np.float64], NDArray[np.complex128]]:
    """One DOF's closed error loop and its poles: returns ``A, E``.

    State ``x = [e, e_dot, xi]``. Continuous (``dt=None``): ``x_dot = A x`` with
    ``A = [[0, 1, 0], [-k_p, -k_d, -k_i], [1, 0, 0]]`` (eqs. 17-18). Sampled (``dt`` given): the
    controller of :class:`MultivariablePID` run every ``dt`` seconds on an exact model, i.e. the
    double integrator ``e_ddot = a`` with ``a_k = -k_p e_k - k_d e_dot_k - k_i xi_k`` held
    over the period (zero-order hold) and ``xi_{k+1} = xi_k + dt e_k``:
    ``x_{k+1} = A x_k``. The loop is stable when ``max |E| < 1`` (sampled) or
    ``max Re E < 0`` (continuous).

    Args:
        k_p: proportional gain (1/s^2).
        k_i: integral gain (1/s^3).
        k_d: derivative gain (1/s).
        dt: sampling period (s), or ``None`` for the continuous loop.

    Returns:
        ``(A, E)``: the 3x3 loop matrix and its eigenvalues.
    """
    if dt is None:
        A = np.array([[0.0, 1.0, 0.0], [-k_p, -k_d, -k_i], [1.0, 0.0, 0.0]])
    else:
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be finite and > 0 (s), got {dt!r}")
        h = 0.5 * dt * dt
        A = np.array(
            [
                [1.0 - h * k_p, dt - h * k_d, -h * k_i],
                [-dt * k_p, 1.0 - dt * k_d, -dt * k_i],
                [dt, 0.0, 1.0],
            ]
        )
    return A, np.linalg.eigvals(A)


#: natural frequencies (rad/s) of the ``"tuned"`` preset: r-frame x, y and yaw
TUNED_OMEGA: Vec3 = (0.06, 0.06, 0.1)

#: Lower bandwidth for feedback from an observer (rad/s): the velocity estimates of the
#: kinematic filters carry noise (r RMSE ~0.07 deg/s with the default sensors), which K_D
#: turns into tunnel-thruster chatter; with ``TUNED_OMEGA`` and the KBF the tunnels sit at a
#: limit ~60 % of the time, with ``SMOOTH_OMEGA`` ~30 %, and J_c drops from ~0.26 to ~0.16
#: (harbour manoeuvre, seeds 0-3, wind 3 m/s from 300 deg).
SMOOTH_OMEGA: Vec3 = (0.05, 0.05, 0.06)

#: The Blue Lady's gain presets by name (tuned for that vessel; other vessels get
#: :func:`pid_pole_placement` at their bandwidth). ``"seed"``: Tomera (2014) eqs. 46-48 as
#: printed. ``"tuned"``: :func:`pid_pole_placement` with ``omega = TUNED_OMEGA``, ``zeta = 1``
#: (module docstring). ``"smooth"``: the same at ``SMOOTH_OMEGA`` (for observer feedback).
GAIN_PRESETS: Mapping[str, PIDGains] = MappingProxyType(
    {
        "seed": PIDGains(K_P=(1.0, 1.0, 1.0), K_I=(0.01, 0.01, 0.01), K_D=(100.0, 100.0, 100.0)),
        # = pid_pole_placement(TUNED_OMEGA): K_P = 3 w^2, K_I = w^3, K_D = 3 w (a test checks it)
        "tuned": PIDGains(
            K_P=(0.0108, 0.0108, 0.03), K_I=(2.16e-4, 2.16e-4, 1e-3), K_D=(0.18, 0.18, 0.3)
        ),
        "smooth": PIDGains.from_pole_placement(SMOOTH_OMEGA),
    }
)


def pid_gains(name: str) -> PIDGains:
    """A gain preset of the Blue Lady by name (``"seed"``, ``"tuned"``, ``"smooth"``).

    Raises:
        ValueError: unknown name (the message lists the valid ones).
    """
    try:
        return GAIN_PRESETS[name]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown PID gain preset {name!r}; choose one of: {', '.join(GAIN_PRESETS)}"
        ) from None


# ---- the online controller: one compiled law over N envs ------------------------------------
def _mat3(x: ArrayLike, name: str) -> NDArray[np.float64]:
    a = np.asarray(x, dtype=float)
    if a.shape != (3, 3) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be a finite 3x3 matrix, got shape {a.shape}: {a!r}")
    return a


# Rows of the design matrix ``G`` (float64, (17, 3)) that the compiled law reads: the control
# model, the gains, the limits, the filters' gains, then (dt, s_x, s_y) and the switches.
_GM, _GMI, _GD = 0, 3, 6  # M (kg, kg m^2), M^-1, D_L (N s/m, N s, N m s): 3 rows each
_GKP, _GKI, _GKD, _GLIM, _GALPHA, _GBETA = 9, 10, 11, 12, 13, 14
_GMISC = 15  # (dt (s), s_x, s_y): the period and change_frame's scale of the x-y integral
_GFLAGS = 16  # (velocity filter on, command filter on, either on) as 1.0 / 0.0
# Columns of the state ``S`` (float64, (n, 18)), one row per env; zeros: the reset state.
_SXI = 0  # xi (m s, m s, rad s)
_SPEND = 3  # the pending increment's (e_x (m), e_y (m), e_psi (rad), psi (rad))
_SHAS = 7  # 1.0 while an increment is pending
_SSTART = 8  # 1.0 after the first call since the reset (the filters' start)
_SNUF = 9  # nu_f (m/s, m/s, rad/s)
_STP = 12  # the last output tau (N, N, N m)
_STF = 15  # the command filter's state (N, N, N m)
_S_COLS = 18
#: what ``saturated`` holds: nothing, a ``tau_error`` (N, N, N m), or 0/1 flags
_SAT_NONE, _SAT_ERROR, _SAT_FLAGS = 0, 1, 2
_BAD_INPUT = ("", "eta_r", "nu", "eta_d_r", "eta_dot_d_r", "eta_ddot_d_r", "saturated")


@njit(inline="always")  # (inlined: each call site's offset is a literal, a compile of its own)
def _mv(G: Any, k: int, x0: float, x1: float, x2: float) -> tuple[float, float, float]:
    """``A x`` for the 3x3 ``A = G[k:k + 3]``, each row summed left to right."""
    return (
        G[k, 0] * x0 + G[k, 1] * x1 + G[k, 2] * x2,
        G[k + 1, 0] * x0 + G[k + 1, 1] * x1 + G[k + 1, 2] * x2,
        G[k + 2, 0] * x0 + G[k + 2, 1] * x1 + G[k + 2, 2] * x2,
    )


@njit
def _direction(x: float, kind: int) -> int:
    """+1 / -1 (cut while pushing +/-), 2 (flagged, direction unknown) or 0 (free)."""
    if kind == _SAT_FLAGS:
        return 2 if x != 0.0 else 0
    return 1 if x > SATURATION_TOL else -1 if x < -SATURATION_TOL else 0


@njit
def _drops(d: int, f: float) -> bool:
    """Whether a body-force increment ``f`` (tau changes by ``-f``) pushes into a cut."""
    return (d == 2 and f != 0.0) or (d != 2 and d * -f > 0.0)


@njit
def _pid_env(G: Any, s: Any, e: Any, w: Any, ed: Any, vd: Any, ad: Any, sat: Any, kind: int,
             out: Any) -> None:  # fmt: skip
    """One env's control period (module docstring): filter, integral, clamp, eq. 23."""
    h = G[_GMISC, 0]
    x, y, psi = e[0], e[1], e[2]
    u, v, r = w[0], w[1], w[2]
    started = s[_SSTART] != 0.0
    kIx, kIy, kIz = G[_GKI, 0], G[_GKI, 1], G[_GKI, 2]
    if G[_GFLAGS, 0] != 0.0:  # the model-aided velocity filter
        if started:
            t0, t1, t2 = s[_STP], s[_STP + 1], s[_STP + 2]
            if kind == _SAT_ERROR:  # delivered = requested - tau_error
                t0, t1, t2 = t0 - sat[0], t1 - sat[1], t2 - sat[2]
            f0, f1, f2 = s[_SNUF], s[_SNUF + 1], s[_SNUF + 2]
            d0, d1, d2 = _mv(G, _GD, f0, f1, f2)
            q0, q1, q2 = _mv(G, _GMI, t0 - d0, t1 - d1, t2 - d2)
            p0, p1, p2 = f0 + h * q0, f1 + h * q1, f2 + h * q2
            a0, a1, a2 = G[_GALPHA, 0], G[_GALPHA, 1], G[_GALPHA, 2]
            u = u if a0 == 1.0 else p0 + a0 * (u - p0)
            v = v if a1 == 1.0 else p1 + a1 * (v - p1)
            r = r if a2 == 1.0 else p2 + a2 * (r - p2)
        s[_SNUF], s[_SNUF + 1], s[_SNUF + 2] = u, v, r
    # the pending increment h e_{k-1} (eq. 17) with conditional integration
    if s[_SHAS] != 0.0:
        dx, dy, dz = h * s[_SPEND], h * s[_SPEND + 1], h * s[_SPEND + 2]
        if kind != _SAT_NONE:
            j0, j1 = _direction(sat[0], kind), _direction(sat[1], kind)
            j2 = _direction(sat[2], kind)
            if j0 != 0 or j1 != 0 or j2 != 0:
                qx, qy, qz = kIx * dx, kIy * dy, kIz * dz  # r-frame acceleration
                c, sn = math.cos(s[_SPEND + 3]), math.sin(s[_SPEND + 3])
                f0, f1, f2 = _mv(G, _GM, c * qx + sn * qy, -sn * qx + c * qy, qz)  # body force
                changed = False
                if _drops(j0, f0):
                    f0, changed = 0.0, True
                if _drops(j1, f1):
                    f1, changed = 0.0, True
                if _drops(j2, f2):
                    f2, changed = 0.0, True
                if changed:
                    bx, by, bz = _mv(G, _GMI, f0, f1, f2)
                    if kIx > 0:
                        dx = (c * bx - sn * by) / kIx
                    if kIy > 0:
                        dy = (sn * bx + c * by) / kIy
                    if kIz > 0:
                        dz = bz / kIz
        s[_SXI] += dx
        s[_SXI + 1] += dy
        s[_SXI + 2] += dz
        s[_SHAS] = 0.0
    # the clamp of the integral force |M R^T K_I xi| <= integral_limit per body DOF
    c, sn = math.cos(psi), math.sin(psi)
    qx, qy, qz = kIx * s[_SXI], kIy * s[_SXI + 1], kIz * s[_SXI + 2]
    f0, f1, f2 = _mv(G, _GM, c * qx + sn * qy, -sn * qx + c * qy, qz)
    l0, l1, l2 = G[_GLIM, 0], G[_GLIM, 1], G[_GLIM, 2]
    if not (abs(f0) <= l0 and abs(f1) <= l1 and abs(f2) <= l2):
        bx, by, bz = _mv(G, _GMI, max(-l0, min(l0, f0)), max(-l1, min(l1, f1)),
                         max(-l2, min(l2, f2)))  # fmt: skip
        if kIx > 0:
            s[_SXI] = (c * bx - sn * by) / kIx
        if kIy > 0:
            s[_SXI + 1] = (sn * bx + c * by) / kIy
        if kIz > 0:
            s[_SXI + 2] = bz / kIz
    ex, ey = x - ed[0], y - ed[1]
    epsi = math.pi - (math.pi - (psi - ed[2])) % (2.0 * math.pi)  # wrap to (-pi, pi]
    # eq. 19 in the r-frame; r-frame velocity R(psi) nu (eq. 3)
    a0 = ad[0] - G[_GKD, 0] * (c * u - sn * v - vd[0]) - G[_GKP, 0] * ex - kIx * s[_SXI]
    a1 = ad[1] - G[_GKD, 1] * (sn * u + c * v - vd[1]) - G[_GKP, 1] * ey - kIy * s[_SXI + 1]
    a2 = ad[2] - G[_GKD, 2] * (r - vd[2]) - G[_GKP, 2] * epsi - kIz * s[_SXI + 2]
    # eqs. 21-22: nu_dot = R^T a - r S nu; eq. 20: tau = M nu_dot + D_L nu
    m0, m1, m2 = _mv(G, _GM, c * a0 + sn * a1 + r * v, -sn * a0 + c * a1 - r * u, a2)
    d0, d1, d2 = _mv(G, _GD, u, v, r)
    s[_SPEND], s[_SPEND + 1], s[_SPEND + 2], s[_SPEND + 3] = ex, ey, epsi, psi
    s[_SHAS] = 1.0
    t0, t1, t2 = m0 + d0, m1 + d1, m2 + d2
    if G[_GFLAGS, 1] != 0.0:  # the output low-pass
        if started:
            b0, b1, b2 = G[_GBETA, 0], G[_GBETA, 1], G[_GBETA, 2]
            s0, s1, s2 = s[_STF], s[_STF + 1], s[_STF + 2]
            t0 = t0 if b0 == 1.0 else s0 + b0 * (t0 - s0)
            t1 = t1 if b1 == 1.0 else s1 + b1 * (t1 - s1)
            t2 = t2 if b2 == 1.0 else s2 + b2 * (t2 - s2)
        s[_STF], s[_STF + 1], s[_STF + 2] = t0, t1, t2
    if G[_GFLAGS, 2] != 0.0:
        s[_STP], s[_STP + 1], s[_STP + 2] = t0, t1, t2
        s[_SSTART] = 1.0
    out[0], out[1], out[2] = t0, t1, t2


@njit
def bad_input(eta: Any, nu: Any, eta_d: Any, eta_dot_d: Any, eta_ddot_d: Any, sat: Any) -> int:
    """0, or the index in ``_BAD_INPUT`` of the first (n, 3) input with a value that is not
    finite (the check of every DP law before it changes a state)."""
    for i in range(eta.shape[0]):
        for j in range(3):
            if not math.isfinite(eta[i, j]):
                return 1
            if not math.isfinite(nu[i, j]):
                return 2
            if not math.isfinite(eta_d[i, j]):
                return 3
            if not math.isfinite(eta_dot_d[i, j]):
                return 4
            if not math.isfinite(eta_ddot_d[i, j]):
                return 5
            if not math.isfinite(sat[i, j]):
                return 6
    return 0


@njit
def pid_law(G: Any, S: Any, eta: Any, nu: Any, eta_d: Any, eta_dot_d: Any, eta_ddot_d: Any,
            sat: Any, kind: int, tau: Any) -> int:  # fmt: skip
    """The PID of Tomera (2014) eq. 23 for every env (row) of ``S``: writes ``tau`` (n, 3)
    (N, N, N m) and advances the state. Returns 0, or the index in ``_BAD_INPUT`` of the first
    input that is not finite (the state is then left as it was)."""
    bad = bad_input(eta, nu, eta_d, eta_dot_d, eta_ddot_d, sat)
    if bad:
        return bad
    for i in range(S.shape[0]):
        _pid_env(G, S[i], eta[i], nu[i], eta_d[i], eta_dot_d[i], eta_ddot_d[i], sat[i], kind,
                 tau[i])  # fmt: skip
    return 0


@njit
def pid_change_frame(G: Any, S: Any, dpsi: Any, mask: Any) -> int:
    """Rotate the integral (and a pending increment) of the masked envs by ``dpsi`` (rad):
    ``K_I xi_new = R^T(dpsi) K_I xi_old`` in x-y. Returns 1 (nothing changed) for a
    non-finite ``dpsi`` of a masked env, else 0."""
    n = S.shape[0]
    for i in range(n):
        if mask[i] and not math.isfinite(dpsi[i]):
            return 1
    sx, sy = G[_GMISC, 1], G[_GMISC, 2]
    for i in range(n):
        if not mask[i]:
            continue
        c, s = math.cos(dpsi[i]), math.sin(dpsi[i])
        for k in (_SXI, _SPEND):
            if k == _SPEND and S[i, _SHAS] == 0.0:
                continue
            ax, ay = sx * S[i, k], sy * S[i, k + 1]
            S[i, k] = (c * ax + s * ay) / sx
            S[i, k + 1] = (-s * ax + c * ay) / sy
        if S[i, _SHAS] != 0.0:
            S[i, _SPEND + 3] = S[i, _SPEND + 3] - dpsi[i]
    return 0


@dataclass(frozen=True, eq=False)
class _PIDDesign:
    """The validated design of a PID (constructor arguments of :class:`MultivariablePID`) and
    the matrix ``G`` the compiled law reads."""

    gains: PIDGains
    M: NDArray[np.float64]
    D_L: NDArray[np.float64]
    dt: float
    integral_limit: NDArray[np.float64]
    velocity_filter: Vec3
    command_filter: Vec3
    G: NDArray[np.float64]

    @classmethod
    def build(cls, who: str, gains: PIDGains | str, M: ArrayLike | None, D_L: ArrayLike | None,
              dt: float, integral_limit: ArrayLike | None, velocity_filter: ArrayLike,
              command_filter: ArrayLike) -> _PIDDesign:  # fmt: skip
        if isinstance(gains, str):
            gains = pid_gains(gains)
        if not isinstance(gains, PIDGains):
            raise ValueError(f"gains must be PIDGains or a preset name, got {type(gains).__name__}")
        require_given(who, _DESIGN_HINT, M=M, D_L=D_L)
        require_given(who, _LIMIT_HINT, integral_limit=integral_limit)
        Ma = _mat3(M, "M")
        Da = _mat3(D_L, "D_L")
        if not np.linalg.cond(Ma) < 1e12:
            raise ValueError(f"M must be invertible, got {Ma!r}")
        try:
            dt = float(dt)
        except (TypeError, ValueError):
            raise ValueError(f"dt must be a control period in seconds, got {dt!r}") from None
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a finite control period > 0 (s), got {dt!r}")
        lim = np.broadcast_to(np.asarray(integral_limit, dtype=float), (3,))
        if np.any(np.isnan(lim)) or np.any(lim <= 0):
            raise ValueError(f"integral_limit must be > 0 (N, N, N m; inf allowed), got {lim!r}")
        T_f = _gain3(velocity_filter, "velocity_filter (s)")
        T_c = _gain3(command_filter, "command_filter (s)")
        kx, ky = gains.K_I[0], gains.K_I[1]
        sx, sy = (kx, ky) if kx > 0 and ky > 0 else (1.0, 1.0)
        vel, cmd = any(t > 0.0 for t in T_f), any(t > 0.0 for t in T_c)
        G = np.vstack(
            [
                Ma,
                np.linalg.inv(Ma),
                Da,
                [gains.K_P, gains.K_I, gains.K_D, lim],
                # the filters' gains 1 - exp(-dt / T) per DOF (1: no filter)
                [[-math.expm1(-dt / t) if t > 0.0 else 1.0 for t in T] for T in (T_f, T_c)],
                [[dt, sx, sy], [float(vel), float(cmd), float(vel or cmd)]],
            ]
        )
        arrays = [a.copy() for a in (Ma, Da, lim, G)]
        for a in arrays:
            a.setflags(write=False)  # the controller works on private copies
        Ma, Da, lim, G = arrays
        return cls(gains, Ma, Da, dt, lim, T_f, T_c, G)


#: the compiled entry points of the laws (one signature each)
_ENTRIES: dict[str, Any] = {}
_F2 = np.zeros((1, 3))


def _pid_entry() -> Any:
    """:func:`pid_law`'s compiled entry point (no per-call type resolution)."""
    e = _ENTRIES.get("pid")
    if e is None:
        e = _ENTRIES["pid"] = entry(pid_law, (*[np.zeros((17, 3))] * 7, _F2, 0, _F2))
    return e


def _frame_entry() -> Any:
    """:func:`pid_change_frame`'s compiled entry point."""
    e = _ENTRIES.get("frame")
    if e is None:
        b = np.zeros(1, dtype=np.bool_)
        e = _ENTRIES["frame"] = entry(pid_change_frame, (_F2, _F2, np.zeros(1), b))
    return e


def _one(x: ArrayLike, name: str) -> NDArray[np.float64]:
    """One env's 3 values as a (1, 3) array (:func:`_rows` for ``n = 1``, fast for a float
    (3,) array)."""
    if type(x) is np.ndarray and x.shape == (3,) and x.dtype == np.float64 and x.strides == (8,):
        return x.reshape(1, 3)
    return _rows(x, name, 1)


def _rows(x: ArrayLike, name: str, n: int) -> NDArray[np.float64]:
    """``x`` as a C-contiguous float (n, 3) array (a (3,) one when ``n == 1``), or a clear
    ``ValueError``."""
    if type(x) is np.ndarray and x.dtype == np.float64:
        a = x
    else:
        try:
            a = np.asarray(x, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{name} must be 3 real numbers per env, got {x!r}") from None
    if a.shape != (n, 3):
        if n != 1 or a.shape != (3,):
            want = "(3,)" if n == 1 else f"({n}, 3)"
            raise ValueError(f"{name} must have shape {want}, got an array of shape {a.shape}")
        a = a.reshape(1, 3)
    return a if a.flags.c_contiguous else np.ascontiguousarray(a)


class BatchedLaw:
    """What every batched DP control law shares (:class:`BatchedPID`, the LQ laws): one state
    row per env (``_S``, reset by mask), the frame turn's arguments and the call's inputs,
    checked once."""

    n: int
    _S: NDArray[np.float64]
    _zeros: NDArray[np.float64]

    def _state(self, n: Any, cols: int) -> None:
        """``n`` envs (checked) of ``cols`` state values each, all zero."""
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ValueError(f"n must be an int >= 1 (the number of envs), got {n!r}")
        self.n = n = int(n)
        self._S = np.zeros((n, cols))
        self._zeros = np.zeros((n, 3))
        self._zeros.setflags(write=False)

    def reset(self, mask: ArrayLike | None = None) -> None:
        """Clear the state (integrals, pending increments, filters, thruster states) of every
        env, or of those where ``mask`` (``(n,)`` bool)."""
        m = _mask(mask, self.n)
        if m is None:
            self._S[:] = 0.0
        else:
            self._S[m] = 0.0

    def _turn(
        self, dpsi: ArrayLike, mask: ArrayLike | None
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """A frame turn's ``(dpsi (n,), mask (n,))``, C-contiguous (``None``: every env)."""
        n = self.n
        m = _mask(mask, n)
        try:
            d = np.ascontiguousarray(np.broadcast_to(np.asarray(dpsi, dtype=float), (n,)))
        except (TypeError, ValueError):
            raise ValueError(f"dpsi must be a rotation (rad), scalar or ({n},)") from None
        return d, np.ones(n, dtype=bool) if m is None else np.ascontiguousarray(m)

    def _inputs(
        self,
        eta_r: ArrayLike,
        nu: ArrayLike,
        eta_d_r: ArrayLike,
        eta_dot_d_r: ArrayLike | None,
        eta_ddot_d_r: ArrayLike | None,
        saturated: ArrayLike | None,
    ) -> tuple[Any, ...]:
        """A call's ``(eta, nu, eta_d, eta_dot_d, eta_ddot_d, sat, kind)`` as (n, 3) rows
        (the reference's derivatives zero where not given)."""
        n, z = self.n, self._zeros
        kind, sat = saturation_input(saturated, z)
        return (
            _rows(eta_r, "eta_r", n), _rows(nu, "nu", n), _rows(eta_d_r, "eta_d_r", n),
            z if eta_dot_d_r is None else _rows(eta_dot_d_r, "eta_dot_d_r", n),
            z if eta_ddot_d_r is None else _rows(eta_ddot_d_r, "eta_ddot_d_r", n),
            sat, kind,
        )  # fmt: skip


class BatchedPID(BatchedLaw):
    """The PID-type DP controller of Tomera (2014) eq. 23 for ``n`` envs: the one run-time form
    (:class:`MultivariablePID` is its ``n = 1`` adapter).

    Same gains and model for every env, one integral state, pending increment and filter
    state per env. Each env's row depends on that env's inputs alone: row ``i`` of a call
    equals the same call at ``n = 1`` on row ``i``'s inputs, bit for bit.

    Args:
        n: number of envs, >= 1.
        gains, M, D_L, dt, integral_limit, velocity_filter, command_filter: as
            :class:`MultivariablePID`.
    """

    def __init__(
        self,
        n: int,
        gains: PIDGains | str = "tuned",
        M: ArrayLike | None = None,
        D_L: ArrayLike | None = None,
        dt: float = 1.0,
        *,
        integral_limit: ArrayLike | None = None,
        velocity_filter: ArrayLike = 0.0,
        command_filter: ArrayLike = 0.0,
    ) -> None:
        design = _PIDDesign.build(
            "BatchedPID()", gains, M, D_L, dt, integral_limit, velocity_filter, command_filter
        )
        self._setup(n, design)

    @classmethod
    def from_scalar(cls, controller: MultivariablePID, n: int) -> BatchedPID:
        """``n`` envs of a controller's design (its gains, model, period, limit and filters;
        the states start at zero)."""
        if not isinstance(controller, MultivariablePID):
            raise TypeError(f"controller must be a MultivariablePID, got {controller!r}")
        self = cls.__new__(cls)
        self._setup(n, controller._law._design)
        return self

    def _setup(self, n: int, design: _PIDDesign) -> None:
        self._state(n, _S_COLS)
        self._design = d = design
        self.gains, self.M, self.D_L, self.dt = d.gains, d.M, d.D_L, d.dt
        self.integral_limit = d.integral_limit
        self.velocity_filter, self.command_filter = d.velocity_filter, d.command_filter
        self._G = d.G

    # ---- state -------------------------------------------------------------------------------
    @property
    def integral(self) -> NDArray[np.float64]:
        """The integral states ``xi`` (m s, m s, rad s), shape (n, 3) (a copy)."""
        return self._S[:, _SXI : _SXI + 3].copy()

    @property
    def filtered_velocity(self) -> NDArray[np.float64] | None:
        """The low-passed body velocities ``nu_f`` (m/s, m/s, rad/s) the last call used,
        (n, 3); ``None`` without a velocity filter (rows of envs not yet called since their
        reset are zeros)."""
        if self._G[_GFLAGS, 0] == 0.0:
            return None
        return self._S[:, _SNUF : _SNUF + 3].copy()

    def change_frame(self, dpsi: ArrayLike, mask: ArrayLike | None = None) -> None:
        """Re-express the integral states in the next leg's r-frame, rotated by ``dpsi`` (rad).

        The new frame's x axis is the old one turned by ``dpsi`` (clockwise positive, like the
        heading); its origin may move anywhere (the integral holds no position). The integral
        acts like a slowly varying force (wind, current), so its x-y *acceleration*
        ``K_I xi`` is rotated: ``K_I xi_new = R^T(dpsi) K_I xi_old``; the yaw part is unchanged.

        Args:
            dpsi: rotation of the frame (rad), shape (n,) or a scalar.
            mask: ``(n,)`` bool, the envs that switched leg (``None``: all); the others are
                left exactly as they are (their ``dpsi`` is not read).

        Raises:
            ValueError: a non-finite ``dpsi`` of a switching env, a wrong shape.
        """
        d, m = self._turn(dpsi, mask)
        if _frame_entry()(self._G, self._S, d, m):
            raise ValueError(f"dpsi must be finite (rad), got {dpsi!r}")

    # ---- control law -------------------------------------------------------------------------
    def __call__(
        self,
        eta_r: ArrayLike,
        nu: ArrayLike,
        eta_d_r: ArrayLike,
        eta_dot_d_r: ArrayLike | None = None,
        eta_ddot_d_r: ArrayLike | None = None,
        *,
        saturated: ArrayLike | None = None,
    ) -> NDArray[np.float64]:
        """Body-frame control forces ``tau = [X, Y, N]`` (N, N, N m) of every env, eq. 23.

        Args:
            eta_r: poses ``[x, y, psi]`` (m, m, rad) in the r-frames, shape (n, 3).
            nu: body velocities ``[u, v, r]`` (m/s, m/s, rad/s), shape (n, 3).
            eta_d_r: reference poses (m, m, rad), shape (n, 3).
            eta_dot_d_r: reference velocities (m/s, m/s, rad/s), (n, 3); default zero.
            eta_ddot_d_r: reference accelerations (m/s^2, m/s^2, rad/s^2), (n, 3); default zero.
            saturated: the allocation's ``tau_error`` of every env's previous ``tau`` (n, 3)
                (N, N, N m), or (n, 3) booleans, or ``None`` (integrate unconditionally), as
                :class:`MultivariablePID`'s ``saturated``.

        Returns:
            ``tau``, shape (n, 3) (a new array).

        Raises:
            ValueError: an input of the wrong shape or not finite (the state is unchanged).
        """
        e, w, ed, vd, ad, sat, kind = self._inputs(eta_r, nu, eta_d_r, eta_dot_d_r,
                                                   eta_ddot_d_r, saturated)  # fmt: skip
        tau = np.empty((self.n, 3))
        code = _pid_entry()(self._G, self._S, e, w, ed, vd, ad, sat, kind, tau)
        if code:
            raise ValueError(f"{_BAD_INPUT[code]} contains NaN or infinite values")
        return tau

    def __repr__(self) -> str:
        g = self.gains
        return f"BatchedPID(n={self.n}, K_P={g.K_P}, K_I={g.K_I}, K_D={g.K_D}, dt={self.dt})"


def saturation_input(
    saturated: ArrayLike | None, zeros: NDArray[np.float64]
) -> tuple[int, NDArray[np.float64]]:
    """A DP law's ``saturated`` argument for ``n = len(zeros)`` envs as ``(kind, rows)``:
    ``None`` (``_SAT_NONE``, the zeros), a ``tau_error`` (``_SAT_ERROR``) or flags
    (``_SAT_FLAGS``, as 0.0 / 1.0), rows (n, 3) (a (3,) input at ``n = 1``)."""
    if saturated is None:
        return _SAT_NONE, zeros
    if type(saturated) is np.ndarray and saturated.dtype == np.float64:
        return _SAT_ERROR, _rows(saturated, "saturated", zeros.shape[0])
    a = np.asarray(saturated)
    if a.dtype == np.bool_:
        return _SAT_FLAGS, _rows(a.astype(float), "saturated", zeros.shape[0])
    return _SAT_ERROR, _rows(a, "saturated", zeros.shape[0])


def _mask(mask: ArrayLike | None, n: int) -> NDArray[np.bool_] | None:
    """``None`` (all envs) or a ``(n,)`` boolean mask; ``ValueError`` on a wrong shape."""
    if mask is None:
        return None
    m = np.asarray(mask, dtype=bool)
    if m.shape != (n,):
        raise ValueError(f"mask must be ({n},) booleans, got shape {m.shape}")
    return m


class MultivariablePID:
    """The PID-type DP controller of Tomera (2014) eq. 23 in the r-frame of the current leg.

    Args:
        gains: a :class:`PIDGains` or a preset name of the Blue Lady (``"tuned"``,
            ``"smooth"``, ``"seed"``); other vessels: :meth:`PIDGains.from_pole_placement`.
        M: inertia matrix (kg, kg m^2) of the control model, required: the vessel's
            ``design.M`` (the Blue Lady's is Tomera (2014) eq. 49).
        D_L: linear damping (N s/m, N s, N m s) of the control model, required: the
            vessel's ``design.D_L`` (the Blue Lady's is Tomera (2014) eq. 50).
        dt: control period (s): the integral is advanced by ``dt * e`` per call.
        integral_limit: bound on the integral action ``|M R^T K_I xi|`` per body DOF
            (N, N, N m), required: the vessel's force capacity
            (:func:`~shipgym.controllers.actuation.planar_capacity`; the Blue Lady's
            ``(451.3, 88.3, 247.9)``); ``inf`` disables the clamp.
        velocity_filter: time constants ``T_f`` (s, >= 0; scalar or surge, sway, yaw) of the
            model-aided low-pass of the body velocity the law uses (the *filtered
            derivative*, module docstring "Filtered derivative"); 0 (default): the velocity
            as given.
        command_filter: time constants ``T_c`` (s, >= 0; scalar or X, Y, N) of a first-order
            low-pass of the output, ``tau_k = tau_{k-1} + (1 - exp(-dt / T_c)) (law_k -
            tau_{k-1})`` (sampled exactly; it starts at the first output after a reset): it
            takes the short-period position noise that ``M K_P`` passes out of the thruster
            commands; 0 (default): none. The allocation's ``tau_error`` (``saturated``) is
            then relative to the filtered output.

    Raises:
        TypeError: ``M``, ``D_L`` or ``integral_limit`` not given (the message says what to
            pass).

    Call it once per control period with the state and the reference expressed in the
    r-frame (see the module docstring); it returns the body-frame ``tau = [X, Y, N]``
    (N, N, N m) for the thrust allocation. Call :meth:`change_frame` when the guidance
    switches to the next leg and :meth:`reset` at the start of an episode.

    Example:
        >>> from shipgym.controllers import MultivariablePID, allocate
        >>> from shipgym.controllers.actuation import planar_capacity
        >>> from shipgym.dynamics import BLUE_LADY_THRUSTERS
        >>> from shipgym.dynamics.vessel import load_vessel
        >>> v = load_vessel("blue-lady")
        >>> ctrl = MultivariablePID(
        ...     "tuned", M=v.design.M, D_L=v.design.D_L, dt=1.0, integral_limit=planar_capacity(v)
        ... )
        >>> tau = ctrl([1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])  # 1 m too far ahead
        >>> alloc = allocate(tau, BLUE_LADY_THRUSTERS)  # -> alloc.command for the thrusters
        >>> tau = ctrl([0.9, 0, 0], [-0.05, 0, 0], [0, 0, 0], saturated=alloc.tau_error)
    """

    def __init__(
        self,
        gains: PIDGains | str = "tuned",
        M: ArrayLike | None = None,
        D_L: ArrayLike | None = None,
        dt: float = 1.0,
        *,
        integral_limit: ArrayLike | None = None,
        velocity_filter: ArrayLike = 0.0,
        command_filter: ArrayLike = 0.0,
    ) -> None:
        design = _PIDDesign.build(
            "MultivariablePID()", gains, M, D_L, dt, integral_limit, velocity_filter,
            command_filter,
        )  # fmt: skip
        self._law = law = BatchedPID.__new__(BatchedPID)
        law._setup(1, design)
        self.gains, self.M, self.D_L, self.dt = design.gains, design.M, design.D_L, design.dt
        self.integral_limit = design.integral_limit
        self.velocity_filter, self.command_filter = design.velocity_filter, design.command_filter

    def reset(self) -> None:
        """Clear the integral state and the filters (start of an episode)."""
        self._law.reset()

    def batched(self, n: int) -> BatchedPID:
        """This design for ``n`` envs (:meth:`BatchedPID.from_scalar`)."""
        return BatchedPID.from_scalar(self, n)

    @property
    def filtered_velocity(self) -> NDArray[np.float64] | None:
        """The low-passed body velocity ``nu_f`` (m/s, m/s, rad/s) the last call used, or
        ``None`` before the first call after a reset and without a velocity filter."""
        law = self._law
        if law._G[_GFLAGS, 0] == 0.0 or law._S[0, _SSTART] == 0.0:
            return None
        return law._S[0, _SNUF : _SNUF + 3].copy()

    @property
    def integral(self) -> NDArray[np.float64]:
        """The integral state ``xi`` (m s, m s, rad s) in the current r-frame (eq. 17).

        It is the sum used by the most recent call; that call's own error is added at the next
        call (when its allocation is known, see the module docstring).
        """
        return self._law._S[0, _SXI : _SXI + 3].copy()

    def change_frame(self, dpsi: float) -> None:
        """Re-express the integral state in the next leg's r-frame, rotated by ``dpsi`` (rad)
        (:meth:`BatchedPID.change_frame`)."""
        dpsi = float(dpsi)
        if not math.isfinite(dpsi):
            raise ValueError(f"dpsi must be finite (rad), got {dpsi!r}")
        self._law.change_frame(dpsi)

    def __call__(
        self,
        eta_r: ArrayLike,
        nu: ArrayLike,
        eta_d_r: ArrayLike,
        eta_dot_d_r: ArrayLike | None = None,
        eta_ddot_d_r: ArrayLike | None = None,
        *,
        saturated: ArrayLike | None = None,
    ) -> NDArray[np.float64]:
        """Body-frame control force ``tau = [X, Y, N]`` (N, N, N m), Tomera (2014) eq. 23.

        Args:
            eta_r: ship pose ``[x, y, psi]`` (m, m, rad) in the r-frame.
            nu: body velocity ``[u, v, r]`` (m/s, m/s, rad/s).
            eta_d_r: reference pose (m, m, rad) in the r-frame.
            eta_dot_d_r: reference velocity (m/s, m/s, rad/s) in the r-frame; default zero.
            eta_ddot_d_r: reference acceleration (m/s^2, m/s^2, rad/s^2); default zero.
            saturated: what the allocation did with the *previous* ``tau``: its ``tau_error``
                (requested - delivered, N, N, N m; a component above ``SATURATION_TOL`` in
                magnitude marks a DOF cut in that direction) or 3 booleans (a flagged DOF
                blocks integration in both directions). ``None``: integrate unconditionally.

        Returns:
            ``tau`` (3,), to be allocated to the thrusters.

        Raises:
            ValueError: an input is not 3 finite numbers (the state is unchanged).
        """
        law = self._law
        z = law._zeros
        kind, sat = saturation_input(saturated, z)
        tau = np.empty((1, 3))
        code = _pid_entry()(
            law._G, law._S, _one(eta_r, "eta_r"), _one(nu, "nu"), _one(eta_d_r, "eta_d_r"),
            z if eta_dot_d_r is None else _one(eta_dot_d_r, "eta_dot_d_r"),
            z if eta_ddot_d_r is None else _one(eta_ddot_d_r, "eta_ddot_d_r"),
            sat, kind, tau,
        )  # fmt: skip
        if code:
            raise ValueError(f"{_BAD_INPUT[code]} contains NaN or infinite values")
        return tau[0]

    def __repr__(self) -> str:
        g = self.gains
        xi = self.integral
        return (
            f"MultivariablePID(K_P={g.K_P}, K_I={g.K_I}, K_D={g.K_D}, dt={self.dt}, "
            f"integral={tuple(round(float(v), 6) for v in xi)})"
        )


#: where the DP controller's velocity comes from (:func:`vessel_pid`): the true state, a
#: kinematic observer (position fixes only) or a model-based one (hull model and thrust)
VELOCITY_SOURCES = ("truth", "kinematic", "model")


def vessel_pid(
    vessel: Any,
    preset: str,
    scale: float,
    dt: float,
    *,
    conditioned: bool = False,
    velocity_source: str = "kinematic",
) -> MultivariablePID:
    """The PID of Tomera (2014) eq. 23 designed for a vessel (the ``pid*`` controllers).

    Args:
        vessel: a :class:`~shipgym.dynamics.vessel.Vessel` (its design model, ``[control]``
            presets, bandwidth and damping ratio).
        preset: a gain preset of the vessel (``"tuned"``, ``"smooth"``, ``"seed"``); a vessel
            without it gets pole placement at its bandwidth times ``scale``
            (:meth:`PIDGains.from_pole_placement`), except ``"seed"`` (the printed gains of
            Tomera (2014), the Blue Lady's only).
        scale: factor on the vessel's bandwidth for pole placement.
        dt: control period (s).
        conditioned: low-pass the velocity (the filtered derivative) with time constants
            matched to its source; ``False``: the unfiltered law of Tomera (2014) eq. 23.
        velocity_source: where the velocity comes from (:data:`VELOCITY_SOURCES`):
            ``"kinematic"`` (a filter of the position fixes alone, e.g. ``kbf``, ``dkf``: the
            vessel's ``[control] velocity_filter`` and ``command_filter``), ``"model"`` (an
            observer with a hull model driven by the thrust, e.g. ``ekf``:
            ``velocity_filter_model_based`` and ``command_filter_model_based``) or
            ``"truth"`` (the true state, noise-free: no filter).

    Raises:
        ValueError: ``"seed"`` for a vessel without those gains, or an unknown
            ``velocity_source``.
    """
    from .actuation import planar_capacity

    if velocity_source not in VELOCITY_SOURCES:
        raise ValueError(
            f"velocity_source must be one of {VELOCITY_SOURCES}, got {velocity_source!r}"
        )

    d = vessel.design
    cap = planar_capacity(vessel)
    if preset in vessel.control.get("pid_presets", ()):
        gains: PIDGains | str = preset
    elif preset == "seed":
        raise ValueError(
            f"controller 'pid-seed' holds the printed gains of Tomera (2014) for the Blue "
            f"Lady; vessel {vessel.name!r} has none: use 'pid'"
        )
    else:
        bw = np.asarray(vessel.control["bandwidth"], dtype=float) * scale
        gains = PIDGains.from_pole_placement(bw, float(vessel.control["zeta"]))
    T_f: Any = 0.0
    T_c: Any = 0.0
    if conditioned and velocity_source != "truth":
        tail = "" if velocity_source == "kinematic" else "_model_based"
        T_f = vessel.control.get("velocity_filter" + tail, 0.0)
        T_c = vessel.control.get("command_filter" + tail, 0.0)
    return MultivariablePID(
        gains,
        M=d.M,
        D_L=d.D_L,
        dt=dt,
        integral_limit=cap,
        velocity_filter=T_f,
        command_filter=T_c,
    )
