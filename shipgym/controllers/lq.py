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
from shipgym.dynamics.params import BLUE_LADY_HULL

from .design import dlqr, lqr
from .pid import _DESIGN_HINT, _LIMIT_HINT, _saturation_directions, _vec3

__all__ = [
    "LQ_PRESETS",
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


# ---- the online controller -------------------------------------------------------------------
class LQController:
    """LQ DP controller with integral action in the r-frame of the current leg.

    Implements the controller protocol of
    :class:`~shipgym.controllers.wrappers.DPControllerWrapper`: call it once per control period
    with the pose and reference in the r-frame; it returns the body-frame
    ``tau = [X, Y, N]`` (N, N, N m) for the allocation.

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
        require_given("LQController()", _DESIGN_HINT, M=M, D_L=D_L)
        require_given("LQController()", _LIMIT_HINT, integral_limit=integral_limit)
        self.M = np.array(M, dtype=float)
        self.D_L = np.array(D_L, dtype=float)
        self.design = lq_design(weights, dt=dt, method=method, M=self.M, D_L=self.D_L)
        self.dt = float(dt)
        lim = np.broadcast_to(np.asarray(integral_limit, dtype=float), (3,))
        if np.any(np.isnan(lim)) or np.any(lim <= 0):
            raise ValueError(f"integral_limit must be > 0 (N, N, N m; inf allowed), got {lim!r}")
        self.integral_limit = np.array(lim)
        K = self.design.K
        self.K = K.copy()
        self._Ke = K[:, 0:3].copy()
        self._Kv = K[:, 3:6].copy()
        self._Ki = K[:, 6:9].copy()
        self._xi = np.zeros(3)
        self._pending: tuple[float, float, float, float] | None = None

    def reset(self) -> None:
        """Clear the integral state (start of an episode)."""
        self._xi = np.zeros(3)
        self._pending = None

    @property
    def integral(self) -> Array:
        """The integral state ``xi`` (m s, m s, rad s) in the current r-frame."""
        return self._xi.copy()

    def change_frame(self, dpsi: float) -> None:
        """Re-express the integral (and the pending error) in the next leg's r-frame.

        The new frame's x axis is the old one turned by ``dpsi`` (rad, clockwise positive):
        ``xi_new = R^T(dpsi) xi_old`` in x-y; the yaw part is unchanged. The body-frame
        integral ``xi_b`` and hence the integral force are unchanged by the switch.
        """
        dpsi = float(dpsi)
        if not math.isfinite(dpsi):
            raise ValueError(f"dpsi must be finite (rad), got {dpsi!r}")
        c, s = math.cos(dpsi), math.sin(dpsi)
        x, y = self._xi[0], self._xi[1]
        self._xi[0], self._xi[1] = c * x + s * y, -s * x + c * y
        if self._pending is not None:
            ex, ey, epsi, psi = self._pending
            self._pending = (c * ex + s * ey, -s * ex + c * ey, epsi, psi - dpsi)

    @staticmethod
    def _to_body(v: Array, psi: float) -> Array:
        c, s = math.cos(psi), math.sin(psi)
        return np.array([c * v[0] + s * v[1], -s * v[0] + c * v[1], v[2]])

    def _integrate(self, saturated: ArrayLike | None) -> None:
        dirs = None if saturated is None else _saturation_directions(saturated)
        if self._pending is None:
            return
        ex, ey, epsi, psi = self._pending
        self._pending = None
        d = self.dt * np.array([ex, ey, epsi])
        if dirs is not None and any(dirs):
            df = -self._Ki @ self._to_body(d, psi)  # change of the body force
            for j, dj in enumerate(dirs):
                if (dj == 2 and df[j] != 0.0) or (dj in (1, -1) and dj * df[j] > 0.0):
                    return  # would push a cut DOF further: drop the increment
        self._xi += d

    def _clamp(self, psi: float) -> None:
        f = self._Ki @ self._to_body(self._xi, psi)
        lim = self.integral_limit
        if np.all(np.abs(f) <= lim):
            return
        fc = np.clip(f, -lim, lim)
        xb = np.linalg.solve(self._Ki, fc)
        c, s = math.cos(psi), math.sin(psi)
        self._xi = np.array([c * xb[0] - s * xb[1], s * xb[0] + c * xb[1], xb[2]])

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
        x, y, psi = _vec3(eta_r, "eta_r")
        nu_ = np.array(_vec3(nu, "nu"))
        xd, yd, psid = _vec3(eta_d_r, "eta_d_r")
        vd = np.zeros(3) if eta_dot_d_r is None else np.array(_vec3(eta_dot_d_r, "eta_dot_d_r"))
        ad = np.zeros(3) if eta_ddot_d_r is None else np.array(_vec3(eta_ddot_d_r, "eta_ddot_d_r"))
        self._integrate(saturated)
        self._clamp(psi)
        ex, ey = x - xd, y - yd
        epsi = math.pi - (math.pi - (psi - psid)) % (2.0 * math.pi)  # wrap to (-pi, pi]
        e_b = self._to_body(np.array([ex, ey, epsi]), psi)
        nu_d = self._to_body(vd, psi)
        r = nu_[2]
        nu_dot_d = self._to_body(ad, psi) + np.array([r * nu_d[1], -r * nu_d[0], 0.0])
        tau_ff = self.M @ nu_dot_d + self.D_L @ nu_d
        xi_b = self._to_body(self._xi, psi)
        tau = tau_ff - self._Ke @ e_b - self._Kv @ (nu_ - nu_d) - self._Ki @ xi_b
        self._pending = (ex, ey, epsi, psi)
        return tau

    def __repr__(self) -> str:
        return (
            f"LQController(method={self.design.method!r}, dt={self.dt}, "
            f"integral={tuple(round(float(v), 6) for v in self._xi)})"
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
    from .wrappers import CONTROLLERS, ControllerSpec, register_controller

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
