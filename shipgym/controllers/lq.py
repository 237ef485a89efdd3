r"""LQ optimal DP control with integral action (Al-Takie 1982 ch. 4).

Design model ``x = [e, e_nu, xi_b]``, ``x_dot = A x + B u``; law ``tau = tau_ff - K x``,
``K = R^-1 B^T S`` from the Riccati equation (Al-Takie 1982 eqs. 4.3, 4.7-4.8).

Public names: ``LQ_PRESETS``, ``LQController``, ``LQDesign``, ``LQWeights``, ``dlqr``,
``lq_design``, ``lq_model``, ``lqr``, ...
Sources: Al-Takie (1982); Tomera (2014).

Design notes: docs/design/controllers.lq.md.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from shipgym._config import param, require_given
from shipgym._jit import entry, njit
from shipgym.dynamics.params import BLUE_LADY_HULL

from .design import dlqr, lqr
from .pid import (
    _BAD_INPUT,
    _DESIGN_HINT,
    _LIMIT_HINT,
    _SAT_NONE,
    BatchedLaw,
    _direction,
    _drops,
    _mv,
    bad_input,
)

__all__ = [
    "LQ_PRESETS",
    "BatchedLQ",
    "LQController",
    "LQDesign",
    "LQWeights",
    "dlqr",
    "lq_design",
    "lq_model",
    "lqr",
    "register_lq",
]

Array = NDArray[np.float64]


# ---- pure design functions: shipgym.controllers.design (python-control conventions) -------


# ---- the Blue Lady design ---------------------------------------------------------------------
Vec3 = tuple[float, float, float]


def _pos3(value: Any, name: str) -> Vec3:
    a = np.asarray(value, dtype=float)
    if a.ndim == 0:
        a = np.full(3, float(a))
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise ValueError(f"{name} must be a scalar or 3 finite values > 0, got {value!r}")
    return (float(a[0]), float(a[1]), float(a[2]))


@dataclass(frozen=True)
class LQWeights:
    """Bryson-rule weights: the largest acceptable value of each state and input.

    ``Q = diag(1/e_max^2, 1/v_max^2, 1/xi_max^2)``, ``R = diag(1/tau_max^2)``. Angles are in
    degrees here (converted to rad inside :meth:`matrices`). The defaults are the Blue Lady's
    ``"tuned"`` preset (``tau_max`` from its thruster capacity); for another vessel give at
    least ``tau_max`` from its capacity.

    Attributes:
        e_max: position error (m, m, deg): x, y (body frame) and heading.
        v_max: velocity error (m/s, m/s, deg/s): u, v, r.
        xi_max: integral of the error (m s, m s, deg s).
        tau_max: control force (N, N, N m): X, Y, N.
    """

    e_max: Vec3 = param((0.5, 0.5, 2.0), "m, m, deg", "design choice (module docstring)")
    v_max: Vec3 = param((0.05, 0.05, 0.5), "m/s, m/s, deg/s", "design choice")
    xi_max: Vec3 = param((15.0, 15.0, 60.0), "m s, m s, deg s", "design choice")
    tau_max: Vec3 = param((80.0, 80.0, 250.0), "N, N, N m", "thruster capacity (astern, sway)")

    def __post_init__(self) -> None:
        for name in ("e_max", "v_max", "xi_max", "tau_max"):
            object.__setattr__(self, name, _pos3(getattr(self, name), name))

    def matrices(self) -> tuple[Array, Array]:
        """``(Q, R)`` of the continuous cost (SI units, radians)."""
        d = math.radians
        e = np.array([self.e_max[0], self.e_max[1], d(self.e_max[2])])
        v = np.array([self.v_max[0], self.v_max[1], d(self.v_max[2])])
        xi = np.array([self.xi_max[0], self.xi_max[1], d(self.xi_max[2])])
        Q = np.diag(1.0 / np.concatenate([e, v, xi]) ** 2)
        R = np.diag(1.0 / np.asarray(self.tau_max) ** 2)
        return Q, R


#: the Blue Lady's weight presets by name (``"tuned"``: chosen for its thruster capacity, see
#: the module docstring; other vessels get Bryson weights from their capacity)
LQ_PRESETS: Mapping[str, LQWeights] = MappingProxyType({"tuned": LQWeights()})


def lq_model(M: ArrayLike | None = None, D_L: ArrayLike | None = None) -> tuple[Array, Array]:
    """The continuous design model ``(A, B)`` (9 states, 3 inputs) of the module docstring.

    Args:
        M: inertia (kg, kg m^2), required: the vessel's ``design.M`` (the Blue Lady's is
            Tomera (2014) eq. 49).
        D_L: linear damping (N s/m, N s, N m s), required: the vessel's ``design.D_L``
            (the Blue Lady's is Tomera (2014) eq. 50).

    Raises:
        TypeError: ``M`` or ``D_L`` not given.
    """
    require_given("lq_model()", _DESIGN_HINT, M=M, D_L=D_L)
    M_ = np.asarray(M, dtype=float)
    D_ = np.asarray(D_L, dtype=float)
    if M_.shape != (3, 3) or D_.shape != (3, 3):
        raise ValueError(f"M and D_L must be 3x3, got {M_.shape} and {D_.shape}")
    Mi = np.linalg.inv(M_)
    Z, I3 = np.zeros((3, 3)), np.eye(3)
    A = np.block([[Z, I3, Z], [Z, -Mi @ D_, Z], [I3, Z, Z]])
    B = np.vstack([Z, Mi, Z])
    return A, B


def _discretise(A: Array, B: Array, h: float) -> tuple[Array, Array]:
    """ZOH for the ``[e, e_nu]`` part, forward Euler ``xi += h e`` for the integral."""
    n = 6
    big = np.zeros((n + 3, n + 3))
    big[:n, :n] = A[:n, :n]
    big[:n, n:] = B[:n]
    Phi = scipy.linalg.expm(big * h)
    Ad = np.zeros((9, 9))
    Ad[:n, :n] = Phi[:n, :n]
    Ad[n:, :3] = h * np.eye(3)
    Ad[n:, n:] = np.eye(3)
    Bd = np.zeros((9, 3))
    Bd[:n] = Phi[:n, n:]
    return Ad, Bd


@dataclass(frozen=True)
class LQDesign:
    """Result of :func:`lq_design`.

    Attributes:
        K: gain (3, 9) on ``[e, e_nu, xi_b]`` (N/m, N s/m, N/(m s), ...; rad for yaw).
        S: Riccati solution (9, 9).
        E: closed-loop eigenvalues (continuous: rad/s; discrete: z-plane).
        A, B: the design model used (continuous or discretised).
        Q, R: the weights used (continuous; the discrete design uses ``h Q``, ``h R``).
        method: ``"discrete"`` or ``"continuous"``; dt: control period (s).
    """

    K: Array
    S: Array
    E: NDArray[np.complex128]
    A: Array
    B: Array
    Q: Array
    R: Array
    method: str
    dt: float

    @property
    def continuous_poles(self) -> NDArray[np.complex128]:
        """Closed-loop poles in rad/s (``log(z) / dt`` for a discrete design)."""
        if self.method == "continuous":
            return self.E
        return np.log(self.E.astype(complex)) / self.dt


def lq_design(
    weights: LQWeights | str = "tuned",
    *,
    dt: float = 1.0,
    method: str = "discrete",
    M: ArrayLike | None = None,
    D_L: ArrayLike | None = None,
) -> LQDesign:
    """Gains of the LQ controller with integral action (module docstring).

    Args:
        weights: :class:`LQWeights` or a preset name of the Blue Lady (``"tuned"``).
        dt: control period (s), used by the discrete design.
        method: ``"discrete"`` (:func:`dlqr` on the sampled model; default) or
            ``"continuous"`` (:func:`lqr`).
        M, D_L: control model, required: the vessel's ``design.M``, ``design.D_L`` (the
            Blue Lady's: Tomera (2014) eqs. 49-50).

    Raises:
        TypeError: ``M`` or ``D_L`` not given.
    """
    require_given("lq_design()", _DESIGN_HINT, M=M, D_L=D_L)
    if isinstance(weights, str):
        try:
            weights = LQ_PRESETS[weights]
        except KeyError:
            raise ValueError(
                f"unknown LQ weight preset {weights!r}; choose one of: {', '.join(LQ_PRESETS)}"
            ) from None
    if not isinstance(weights, LQWeights):
        raise ValueError(f"weights must be LQWeights or a preset name, got {weights!r}")
    if not (isinstance(dt, int | float) and math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a finite control period > 0 (s), got {dt!r}")
    A, B = lq_model(M, D_L)
    Q, R = weights.matrices()
    if method == "continuous":
        K, S, E = lqr(A, B, Q, R)
    elif method == "discrete":
        A, B = _discretise(A, B, float(dt))
        K, S, E = dlqr(A, B, dt * Q, dt * R)
    else:
        raise ValueError(f"method must be 'discrete' or 'continuous', got {method!r}")
    return LQDesign(K, S, E, A, B, Q, R, method, float(dt))


# ---- the online controller: one compiled law over N envs -------------------------------------
# Rows of the design matrix ``G`` (float64, (20, 3)) the compiled law reads.
_GM, _GD = 0, 3  # M (kg, kg m^2), D_L (N s/m, N s, N m s): 3 rows each
_GKE, _GKV, _GKI, _GKII = 6, 9, 12, 15  # K's blocks on e_b, nu - nu_d, xi_b; K_xi^-1
_GLIM, _GDT = 18, 19  # integral_limit (N, N, N m); (dt (s), 0, 0)
# Columns of the state ``S`` (float64, (n, 8)), one row per env; zeros: the reset state.
_SXI = 0  # xi (m s, m s, rad s), r-frame
_SPEND = 3  # the pending error (e_x (m), e_y (m), e_psi (rad)) and its psi (rad)
_SHAS = 7  # 1.0 while an error is pending
_S_COLS = 8


@njit
def _lq_env(G: Any, s: Any, e: Any, w: Any, ed: Any, vd: Any, ad: Any, sat: Any, kind: int,
            out: Any) -> None:  # fmt: skip
    """One env's control period: the pending integral increment (conditional), the clamp of
    the integral force, ``tau = tau_ff - K x`` (module docstring)."""
    x, y, psi = e[0], e[1], e[2]
    u, v, r = w[0], w[1], w[2]
    if s[_SHAS] != 0.0:  # xi += dt e_{k-1}, unless it pushes a cut DOF further
        h = G[_GDT, 0]
        dx, dy, dz = h * s[_SPEND], h * s[_SPEND + 1], h * s[_SPEND + 2]
        keep = True
        if kind != _SAT_NONE:
            j0, j1, j2 = (
                _direction(sat[0], kind),
                _direction(sat[1], kind),
                _direction(sat[2], kind),
            )
            if j0 != 0 or j1 != 0 or j2 != 0:
                c, sn = math.cos(s[_SPEND + 3]), math.sin(s[_SPEND + 3])
                f0, f1, f2 = _mv(G, _GKI, c * dx + sn * dy, -sn * dx + c * dy, dz)
                keep = not (_drops(j0, f0) or _drops(j1, f1) or _drops(j2, f2))
        if keep:
            s[_SXI] += dx
            s[_SXI + 1] += dy
            s[_SXI + 2] += dz
        s[_SHAS] = 0.0
    # the clamp of the integral force |K_xi xi_b| <= integral_limit per body DOF
    c, sn = math.cos(psi), math.sin(psi)
    f0, f1, f2 = _mv(G, _GKI, c * s[_SXI] + sn * s[_SXI + 1], -sn * s[_SXI] + c * s[_SXI + 1],
                     s[_SXI + 2])  # fmt: skip
    l0, l1, l2 = G[_GLIM, 0], G[_GLIM, 1], G[_GLIM, 2]
    if not (abs(f0) <= l0 and abs(f1) <= l1 and abs(f2) <= l2):
        bx, by, bz = _mv(G, _GKII, max(-l0, min(l0, f0)), max(-l1, min(l1, f1)),
                         max(-l2, min(l2, f2)))  # fmt: skip
        s[_SXI], s[_SXI + 1], s[_SXI + 2] = c * bx - sn * by, sn * bx + c * by, bz
    ex, ey = x - ed[0], y - ed[1]
    epsi = math.pi - (math.pi - (psi - ed[2])) % (2.0 * math.pi)  # wrap to (-pi, pi]
    # body-frame errors, reference velocity and acceleration (R^T(psi) of r-frame vectors)
    nd0, nd1, nd2 = c * vd[0] + sn * vd[1], -sn * vd[0] + c * vd[1], vd[2]
    a0 = c * ad[0] + sn * ad[1] + r * nd1
    a1 = -sn * ad[0] + c * ad[1] - r * nd0
    m0, m1, m2 = _mv(G, _GM, a0, a1, ad[2])
    d0, d1, d2 = _mv(G, _GD, nd0, nd1, nd2)
    e0, e1, e2 = _mv(G, _GKE, c * ex + sn * ey, -sn * ex + c * ey, epsi)
    v0, v1, v2 = _mv(G, _GKV, u - nd0, v - nd1, r - nd2)
    i0, i1, i2 = _mv(G, _GKI, c * s[_SXI] + sn * s[_SXI + 1], -sn * s[_SXI] + c * s[_SXI + 1],
                     s[_SXI + 2])  # fmt: skip
    out[0] = m0 + d0 - e0 - v0 - i0
    out[1] = m1 + d1 - e1 - v1 - i1
    out[2] = m2 + d2 - e2 - v2 - i2
    s[_SPEND], s[_SPEND + 1], s[_SPEND + 2], s[_SPEND + 3] = ex, ey, epsi, psi
    s[_SHAS] = 1.0


@njit
def lq_law(G: Any, S: Any, eta: Any, nu: Any, eta_d: Any, eta_dot_d: Any, eta_ddot_d: Any,
           sat: Any, kind: int, tau: Any) -> int:  # fmt: skip
    """The LQ law for every env (row) of ``S``: writes ``tau`` (n, 3) (N, N, N m) and advances
    the state. Returns 0, or the index of the first input that is not finite (the state is
    then left as it was)."""
    bad = bad_input(eta, nu, eta_d, eta_dot_d, eta_ddot_d, sat)
    if bad:
        return bad
    for i in range(S.shape[0]):
        _lq_env(G, S[i], eta[i], nu[i], eta_d[i], eta_dot_d[i], eta_ddot_d[i], sat[i], kind,
                tau[i])  # fmt: skip
    return 0


@njit
def lq_change_frame(S: Any, dpsi: Any, mask: Any) -> int:
    """Rotate the integral (and a pending error) of the masked envs by ``dpsi`` (rad):
    ``xi_new = R^T(dpsi) xi_old`` in x-y. Returns 1 (nothing changed) for a non-finite
    ``dpsi`` of a masked env, else 0."""
    n = S.shape[0]
    for i in range(n):
        if mask[i] and not math.isfinite(dpsi[i]):
            return 1
    for i in range(n):
        if not mask[i]:
            continue
        c, s = math.cos(dpsi[i]), math.sin(dpsi[i])
        for k in (_SXI, _SPEND):
            if k == _SPEND and S[i, _SHAS] == 0.0:
                continue
            x, y = S[i, k], S[i, k + 1]
            S[i, k], S[i, k + 1] = c * x + s * y, -s * x + c * y
        if S[i, _SHAS] != 0.0:
            S[i, _SPEND + 3] = S[i, _SPEND + 3] - dpsi[i]
    return 0


_F2 = np.zeros((1, 3))
_ENTRIES: dict[str, Any] = {}


def _entry(name: str) -> Any:
    """The compiled entry point of :func:`lq_law` (``"law"``) or :func:`lq_change_frame`."""
    e = _ENTRIES.get(name)
    if e is None:
        if name == "law":
            e = entry(lq_law, (np.zeros((20, 3)), np.zeros((1, _S_COLS)), *[_F2] * 6, 0, _F2))
        else:
            b = np.zeros(1, dtype=np.bool_)
            e = entry(lq_change_frame, (np.zeros((1, _S_COLS)), np.zeros(1), b))
        _ENTRIES[name] = e
    return e


class BatchedLQ(BatchedLaw):
    """The LQ DP controller for ``n`` envs: the one run-time form (:class:`LQController` is
    its ``n = 1`` adapter).

    Same design for every env, one integral state and pending error per env; row ``i`` of a
    call equals the same call at ``n = 1`` on row ``i``'s inputs, bit for bit.

    Args:
        n: number of envs, >= 1.
        weights, M, D_L, dt, method, integral_limit: as :class:`LQController`.
    """

    def __init__(
        self,
        n: int,
        weights: LQWeights | str = "tuned",
        M: ArrayLike | None = None,
        D_L: ArrayLike | None = None,
        dt: float = 1.0,
        *,
        method: str = "discrete",
        integral_limit: ArrayLike | None = None,
    ) -> None:
        require_given("LQController()", _DESIGN_HINT, M=M, D_L=D_L)
        require_given("LQController()", _LIMIT_HINT, integral_limit=integral_limit)
        Ma = np.array(M, dtype=float)
        Da = np.array(D_L, dtype=float)
        design = lq_design(weights, dt=dt, method=method, M=Ma, D_L=Da)
        lim = np.broadcast_to(np.asarray(integral_limit, dtype=float), (3,))
        if np.any(np.isnan(lim)) or np.any(lim <= 0):
            raise ValueError(f"integral_limit must be > 0 (N, N, N m; inf allowed), got {lim!r}")
        K = design.K
        G = np.vstack([Ma, Da, K[:, 0:3], K[:, 3:6], K[:, 6:9], np.linalg.inv(K[:, 6:9]),
                       lim, [float(dt), 0.0, 0.0]])  # fmt: skip
        G.setflags(write=False)
        self._setup(n, Ma, Da, design, np.array(lim), G)

    @classmethod
    def from_scalar(cls, controller: LQController, n: int) -> BatchedLQ:
        """``n`` envs of a controller's design (the states start at zero)."""
        if not isinstance(controller, LQController):
            raise TypeError(f"controller must be an LQController, got {controller!r}")
        law = controller._law
        self = cls.__new__(cls)
        self._setup(n, law.M, law.D_L, law.design, law.integral_limit, law._G)
        return self

    def _setup(self, n: int, M: Array, D_L: Array, design: LQDesign, lim: Array,
               G: Array) -> None:  # fmt: skip
        self._state(n, _S_COLS)
        self.M, self.D_L, self.design, self.integral_limit = M, D_L, design, lim
        self.dt = design.dt
        self.K = design.K.copy()
        self._G = G

    @property
    def integral(self) -> Array:
        """The integral states ``xi`` (m s, m s, rad s), r-frames, shape (n, 3) (a copy)."""
        return self._S[:, _SXI : _SXI + 3].copy()

    def change_frame(self, dpsi: ArrayLike, mask: ArrayLike | None = None) -> None:
        """Re-express the integrals (and the pending errors) in the next leg's r-frame.

        The new frame's x axis is the old one turned by ``dpsi`` (rad, clockwise positive):
        ``xi_new = R^T(dpsi) xi_old`` in x-y; the yaw part is unchanged. The body-frame
        integral ``xi_b`` and hence the integral force are unchanged by the switch.

        Args:
            dpsi: rotation of the frame (rad), shape (n,) or a scalar.
            mask: ``(n,)`` bool, the envs that switched leg (``None``: all).
        """
        d, m = self._turn(dpsi, mask)
        if _entry("frame")(self._S, d, m):
            raise ValueError(f"dpsi must be finite (rad), got {dpsi!r}")

    def __call__(
        self,
        eta_r: ArrayLike,
        nu: ArrayLike,
        eta_d_r: ArrayLike,
        eta_dot_d_r: ArrayLike | None = None,
        eta_ddot_d_r: ArrayLike | None = None,
        *,
        saturated: ArrayLike | None = None,
    ) -> Array:
        """Body-frame control forces ``tau = tau_ff - K x`` (N, N, N m) of every env, (n, 3)
        (inputs as :meth:`LQController.__call__`, (n, 3) each).

        Raises:
            ValueError: an input of the wrong shape or not finite (the state is unchanged).
        """
        e, w, ed, vd, ad, sat, kind = self._inputs(eta_r, nu, eta_d_r, eta_dot_d_r,
                                                   eta_ddot_d_r, saturated)  # fmt: skip
        tau = np.empty((self.n, 3))
        code = _entry("law")(self._G, self._S, e, w, ed, vd, ad, sat, kind, tau)
        if code:
            raise ValueError(f"{_BAD_INPUT[code]} contains NaN or infinite values")
        return tau


class LQController:
    """LQ DP controller with integral action in the r-frame of the current leg.

    Implements the controller protocol of :class:`~shipgym.controllers.batch.ControllerSpec`:
    call it once per control period
    with the pose and reference in the r-frame; it returns the body-frame
    ``tau = [X, Y, N]`` (N, N, N m) for the allocation. The law is :class:`BatchedLQ` at
    ``n = 1``.

    Args:
        weights: :class:`LQWeights` or a preset name of the Blue Lady (``"tuned"``).
        M: inertia (kg, kg m^2) of the control model, required: the vessel's ``design.M``
            (the Blue Lady's: Tomera (2014) eq. 49).
        D_L: linear damping (N s/m, N s, N m s), required: the vessel's ``design.D_L`` (the
            Blue Lady's: Tomera (2014) eq. 50).
        dt: control period (s).
        method: ``"discrete"`` (default) or ``"continuous"`` gain design.
        integral_limit: bound on the integral force ``|K_xi xi_b|`` per body DOF (N, N, N m),
            required: the vessel's force capacity
            (:func:`~shipgym.controllers.actuation.planar_capacity`); ``inf`` disables it.

    Raises:
        TypeError: ``M``, ``D_L`` or ``integral_limit`` not given.

    Example:
        >>> from shipgym.controllers.actuation import planar_capacity
        >>> from shipgym.controllers.lq import LQController
        >>> from shipgym.dynamics.vessel import load_vessel
        >>> v = load_vessel("blue-lady")
        >>> ctrl = LQController(
        ...     M=v.design.M, D_L=v.design.D_L, dt=1.0, integral_limit=planar_capacity(v)
        ... )
        >>> tau = ctrl([1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])  # 1 m too far ahead
        >>> bool(tau[0] < 0)
        True
    """

    def __init__(
        self,
        weights: LQWeights | str = "tuned",
        M: ArrayLike | None = None,
        D_L: ArrayLike | None = None,
        dt: float = 1.0,
        *,
        method: str = "discrete",
        integral_limit: ArrayLike | None = None,
    ) -> None:
        self._law = law = BatchedLQ(
            1, weights, M, D_L, dt, method=method, integral_limit=integral_limit
        )
        self.M, self.D_L, self.design, self.dt = law.M, law.D_L, law.design, law.dt
        self.integral_limit, self.K = law.integral_limit, law.K
        self._Ki = self.K[:, 6:9].copy()

    def reset(self) -> None:
        """Clear the integral state (start of an episode)."""
        self._law.reset()

    def batched(self, n: int) -> BatchedLQ:
        """This design for ``n`` envs (:meth:`BatchedLQ.from_scalar`)."""
        return BatchedLQ.from_scalar(self, n)

    @property
    def integral(self) -> Array:
        """The integral state ``xi`` (m s, m s, rad s) in the current r-frame."""
        return self._law._S[0, _SXI : _SXI + 3].copy()

    def change_frame(self, dpsi: float) -> None:
        """Re-express the integral in the next leg's r-frame (:meth:`BatchedLQ.change_frame`)."""
        dpsi = float(dpsi)
        if not math.isfinite(dpsi):
            raise ValueError(f"dpsi must be finite (rad), got {dpsi!r}")
        self._law.change_frame(dpsi)

    @staticmethod
    def _to_body(v: Array, psi: float) -> Array:
        """``R^T(psi) v`` in x-y (a vector of the r-frame seen from the ship)."""
        c, s = math.cos(psi), math.sin(psi)
        return np.array([c * v[0] + s * v[1], -s * v[0] + c * v[1], v[2]])

    def __call__(
        self,
        eta_r: ArrayLike,
        nu: ArrayLike,
        eta_d_r: ArrayLike,
        eta_dot_d_r: ArrayLike | None = None,
        eta_ddot_d_r: ArrayLike | None = None,
        *,
        saturated: ArrayLike | None = None,
    ) -> Array:
        """Body-frame control force ``tau = tau_ff - K x`` (N, N, N m).

        Args:
            eta_r: ship pose ``[x, y, psi]`` (m, m, rad) in the r-frame.
            nu: body velocity ``[u, v, r]`` (m/s, m/s, rad/s).
            eta_d_r: reference pose (m, m, rad) in the r-frame.
            eta_dot_d_r: reference velocity (m/s, m/s, rad/s), r-frame; default zero.
            eta_ddot_d_r: reference acceleration (m/s^2, m/s^2, rad/s^2); default zero.
            saturated: the allocation's ``tau_error`` of the previous ``tau`` (N, N, N m) or
                3 booleans, for the anti-windup; ``None``: integrate unconditionally.

        Returns:
            ``tau`` (3,).

        Raises:
            ValueError: an input is not 3 finite numbers.
        """
        return self._law(eta_r, nu, eta_d_r, eta_dot_d_r, eta_ddot_d_r, saturated=saturated)[0]

    def __repr__(self) -> str:
        return (
            f"LQController(method={self.design.method!r}, dt={self.dt}, "
            f"integral={tuple(round(float(v), 6) for v in self.integral)})"
        )


def _lq_for(vessel: Any, dt: float) -> LQController:
    """The ``"lq"`` controller of a vessel, on its design model.

    The Blue Lady keeps its ``"tuned"`` weights (fastest closed-loop pole 0.125 rad/s).
    Another vessel gets them carried over by Froude similarity (lengths times
    ``lambda = L_oa / 13.78 m``, speeds times ``sqrt(lambda)``, angular rates divided by it,
    the integral of a position error times ``lambda^1.5``, of the heading error times
    ``sqrt(lambda)``) with force limits proportional to its capacity, scaled (bisection on
    one factor) so that the fastest closed-loop pole sits at twice the vessel's PID
    bandwidth (``[control] bandwidth``). With the kinematic observers (0.4 rad/s) the loop
    is stable up to about 2.5 times (Star Hercules and Wimpey Sealab keep station within
    2.4-2.8 m, 95 %, in 10 and 15 m/s), unstable at three times.
    """
    from .actuation import planar_capacity

    cap = planar_capacity(vessel)
    if "tuned" in vessel.control.get("pid_presets", ()):
        return LQController(
            "tuned", M=vessel.design.M, D_L=vessel.design.D_L, dt=dt, integral_limit=cap
        )
    t = LQ_PRESETS["tuned"]
    lam = vessel.L_oa / BLUE_LADY_HULL.L_oa
    r = math.sqrt(lam)

    def weights(f: float) -> LQWeights:
        return LQWeights(
            e_max=(t.e_max[0] * lam, t.e_max[1] * lam, t.e_max[2]),
            v_max=(t.v_max[0] * r, t.v_max[1] * r, t.v_max[2] / r),
            xi_max=(t.xi_max[0] * lam * r, t.xi_max[1] * lam * r, t.xi_max[2] * r),
            tau_max=tuple(float(x) for x in f * cap),
        )

    target = 2.0 * float(max(vessel.control["bandwidth"]))
    lo, hi = 1e-4, 1.0  # fraction of the capacity; the fastest pole grows with it

    def fastest(f: float) -> float:
        d = lq_design(weights(f), dt=dt, M=vessel.design.M, D_L=vessel.design.D_L)
        return float(np.max(np.abs(d.continuous_poles)))

    for _ in range(30):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if fastest(mid) < target else (lo, mid)
    return LQController(
        weights(lo), M=vessel.design.M, D_L=vessel.design.D_L, dt=dt, integral_limit=cap
    )


def register_lq() -> None:
    """Register ``"lq"`` in the controller registry (idempotent); constrained allocation."""
    from .batch import CONTROLLERS, ControllerSpec, register_controller

    if "lq" not in CONTROLLERS:
        register_controller(
            "lq",
            ControllerSpec(
                _lq_for,
                "constrained",
                "LQ optimal control with integral action (Al-Takie 1982 ch. 4 on Tomera 2014 "
                "eqs. 49-50), "
                "constrained allocation",
            ),
        )


register_lq()
