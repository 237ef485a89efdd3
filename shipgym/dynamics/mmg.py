r"""The MMG standard manoeuvring model (Yasukawa & Yoshimura 2015) of a single-screw ship.

``(m + m_x) u_dot - (m + m_y) v r - x_G m r^2 = X_H + X_R + X_P`` and sway, yaw likewise
(Yasukawa & Yoshimura 2015 eqs. 4-8).

The rudder's normal force ``F_N = (rho/2) A_R U_R^2 C_N(alpha_R)`` has one law,
:func:`rudder_normal_coefficient` (the MMG standard's ``f_alpha sin alpha_R`` with an optional
stall), and the propeller's side force one, :func:`propeller_side_force`: the array form
(:meth:`MMGModel.propulsion_forces`) and the compiled one
(:func:`shipgym.dynamics.actuators.law_mmg`) both call them. :data:`RUDDER_OPTIONS` holds the
rudders a ship can be given (``"schilling"``: a high-lift rudder, :meth:`MMGParameters.
with_rudder`, :func:`with_rudder` for a vessel).

Public names: ``accel_mmg``, ``KVLCC2_L7``, ``MMGHull``, ``MMGModel``, ``MMGParameters``,
``RUDDER_OPTIONS``, ``RudderOption``, ``kvlcc2``, ``rudder_normal_coefficient``,
``propeller_side_force``, ``with_rudder``.

Design notes: docs/design/dynamics.mmg.md.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import require_dimensions
from shipgym._jit import njit

__all__ = [
    "accel_mmg",
    "fujii_f_alpha",
    "KVLCC2_L7",
    "MMGHull",
    "MMGModel",
    "MMGParameters",
    "RUDDER_OPTIONS",
    "RudderOption",
    "kvlcc2",
    "propeller_side_force",
    "rudder_normal_coefficient",
    "rudder_option",
    "with_rudder",
]

Array = NDArray[np.float64]


@njit
def rudder_normal_coefficient(alpha, f_alpha, stall_angle, post_stall):  # type: ignore[no-untyped-def]
    r"""The rudder's normal-force coefficient ``C_N(alpha_R)`` (1): ``F_N = (rho/2) A_R U_R^2
    C_N``. The MMG standard's ``f_alpha sin alpha_R`` (Yasukawa & Yoshimura 2015 eq. 26) while
    the angle of attack ``a = asin|sin alpha_R|`` (``alpha_R`` folded to ``[0, pi/2]``, so
    that a flow from astern is treated alike) is at most ``stall_angle``; past it the
    coefficient holds at ``post_stall f_alpha sin(stall_angle)`` with the sign of ``sin
    alpha_R``. ``stall_angle = inf``: the standard law at every angle.

    The one law of the MMG rudder's normal force (scalar, compiled; the array form is
    :func:`rudder_normal_coefficients`).

    Args:
        alpha: the effective inflow angle ``alpha_R`` (rad).
        f_alpha: the normal-force slope (1/rad).
        stall_angle: rad (``> 0``, ``inf``: none). post_stall: 0 to 1.
    """
    s = math.sin(alpha)
    if math.asin(min(abs(s), 1.0)) <= stall_angle:
        return f_alpha * s
    c = post_stall * f_alpha * math.sin(stall_angle)
    return c if s >= 0.0 else -c


@njit
def _rudder_normal_coefficients(alpha, f_alpha, stall_angle, post_stall):  # type: ignore[no-untyped-def]
    out = np.empty_like(alpha)
    for i in range(alpha.size):
        out[i] = rudder_normal_coefficient(alpha[i], f_alpha, stall_angle, post_stall)
    return out


def rudder_normal_coefficients(alpha: ArrayLike, p: MMGParameters) -> Array:
    """:func:`rudder_normal_coefficient` of every ``alpha_R`` (rad, any shape) with the
    rudder of ``p``."""
    a = np.asarray(alpha, dtype=float)
    flat = np.ascontiguousarray(a.reshape(-1))
    out = _rudder_normal_coefficients(flat, float(p.f_alpha), float(p.stall_angle),
                                      float(p.post_stall))  # fmt: skip
    return out.reshape(a.shape)


@njit
def propeller_side_force(n, X_P, c_y, c_y_brake):  # type: ignore[no-untyped-def]
    r"""The side force ``Y_P`` (N) of a right-handed single screw at the shaft speed ``n``
    (rps) and the propeller's surge force ``X_P`` (N), acting at ``x_P L``.

    - astern (``n < 0``): ``Y_P = -c_y |X_P|``: the stern to port, the bow to starboard (the
      seed's crash stop, Artyszuk 2003 §3);
    - braking (``n >= 0`` and ``X_P < 0``: the shaft stopped or turning ahead slower than the
      flow drives it; the seed's zero-pitch coasting stop): ``Y_P = +c_y_brake |X_P|``: the
      stern to starboard, the bow to port (Artyszuk 2003 §3);
    - ahead (``X_P >= 0``): 0 (the working propeller's effects are in the hull and rudder
      coefficients, measured on the self-propelled model).

    The one law of the MMG propeller's side force (scalar, compiled)."""
    if n < 0.0:
        return -c_y * abs(X_P)
    if X_P < 0.0:
        return c_y_brake * abs(X_P)
    return 0.0


@njit
def _propeller_side_forces(n, X_P, c_y, c_y_brake):  # type: ignore[no-untyped-def]
    out = np.empty_like(X_P)
    for i in range(X_P.size):
        out[i] = propeller_side_force(n[i], X_P[i], c_y, c_y_brake)
    return out


def fujii_f_alpha(aspect_ratio: float) -> float:
    """Fujii's normal-force slope ``f_alpha = 6.13 Lambda / (Lambda + 2.25)`` (1/rad) of a
    rudder of aspect ratio ``Lambda`` (Fujii & Tsuda 1961, the estimate of Yasukawa &
    Yoshimura 2015 §3.5)."""
    if not (math.isfinite(aspect_ratio) and aspect_ratio > 0):
        raise ValueError(f"aspect_ratio must be > 0, got {aspect_ratio!r}")
    return 6.13 * aspect_ratio / (aspect_ratio + 2.25)


@dataclass(frozen=True)
class RudderOption:
    """A rudder a ship of the MMG family can be given instead of its own (:data:`RUDDER_OPTIONS`).

    Its normal-force slope is the ship's published ``f_alpha`` times Fujii's ratio
    ``f(k Lambda) / f(Lambda)`` (:func:`fujii_f_alpha`): the end plates of a high-lift rudder
    raise the effective aspect ratio ``Lambda = H_R^2 / A_R`` by the factor ``k``, the area
    and span stay the ship's.

    Attributes:
        name: the option's name.
        aspect_factor: ``k``, the effective aspect ratio over the geometric one (1, >= 1).
        stall_angle: rad (the angle of attack past which the normal force stops growing).
        post_stall: the fraction of the stall's normal force kept past it (0 to 1).
        max_angle: the steering gear's largest rudder angle (rad).
        source: where the numbers come from.
    """

    name: str
    aspect_factor: float
    stall_angle: float
    post_stall: float
    max_angle: float
    source: str

    def __post_init__(self) -> None:
        if not (math.isfinite(self.aspect_factor) and self.aspect_factor >= 1.0):
            raise ValueError(f"aspect_factor must be >= 1, got {self.aspect_factor!r}")
        if not (0.0 < self.stall_angle <= math.pi / 2):
            raise ValueError(f"stall_angle must be in (0, pi/2] rad, got {self.stall_angle!r}")
        if not 0.0 <= self.post_stall <= 1.0:
            raise ValueError(f"post_stall must be from 0 to 1, got {self.post_stall!r}")
        if not (0.0 < self.max_angle < math.pi / 2):
            raise ValueError(f"max_angle must be in (0, pi/2) rad, got {self.max_angle!r}")

    def f_alpha(self, p: MMGParameters) -> float:
        """The option's normal-force slope (1/rad) on the ship ``p``."""
        lam = p.aspect_ratio
        return p.f_alpha * fujii_f_alpha(self.aspect_factor * lam) / fujii_f_alpha(lam)


#: the rudder options of the MMG family by name: ``"schilling"``, a Schilling high-lift
#: rudder (a fish-tail section with end plates; usable to about 70 deg without stall)
RUDDER_OPTIONS: dict[str, RudderOption] = {
    "schilling": RudderOption(
        "schilling",
        aspect_factor=2.0,
        stall_angle=math.radians(70.0),
        post_stall=0.7,
        max_angle=math.radians(65.0),
        source="Molland & Turnock (2007) on high-lift rudders: a Schilling rudder (fish-tail "
        "section, end plates) works to about 70 deg without stall [stall 70 deg]; end plates "
        "double the effective aspect ratio [chosen: k = 2, mirror image of each plate]; "
        "Fujii & Tsuda (1961) slope (Yasukawa & Yoshimura 2015); post-stall 0.7 [chosen]; "
        "largest angle 65 deg (Artyszuk 2003: the HAH 65 deg turn)",
    ),
}


def rudder_option(name: str) -> RudderOption:
    """:data:`RUDDER_OPTIONS` ``name``.

    Raises:
        ValueError: unknown name (the message lists the valid ones).
    """
    try:
        return RUDDER_OPTIONS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown rudder option {name!r}; valid: "
                         f"{', '.join(RUDDER_OPTIONS)}") from None  # fmt: skip


@dataclass(frozen=True)
class MMGParameters:
    """A ship's MMG parameters: geometry in SI, the rest nondimensional (primes, ``rho/2 L d``
    / ``rho/2 L^2 d`` / ``rho/2 L^4 d`` bases).

    Every field but ``rho`` and ``c_y`` is required (no ship is a default): the published
    values of the KVLCC2 L7 model (Yasukawa & Yoshimura 2015 Tables 1-4) are
    :data:`KVLCC2_L7` (``x_P`` -0.48 as the notes recall it; implementations use -0.5 or
    -0.69).

    Attributes:
        L, B, d: length, beam, draught (m); nabla: displaced volume (m^3); x_G: longitudinal
            centre of gravity from midship (m, forward +); D_P: propeller diameter (m); H_R:
            rudder span (m); A_R: rudder area (m^2); rho: water density (kg/m^3); k_zz: yaw
            radius of gyration as a fraction of L.
        R0 ... N_rrr: hull resistance and manoeuvring derivatives.
        m_x, m_y, J_z: added masses and added moment (primes).
        t_P, w_P0, k0, k1, k2, C1, C2_pos, C2_neg, x_P: propeller.
        t_R, a_H, x_H, x_R, gamma_pos, gamma_neg, l_R, eps, kappa, f_alpha: rudder.
        c_y: the propeller's side force astern (``n < 0``), a fraction of ``|X_P|``, pushing
            the stern to port (a right-handed propeller: the bow goes to starboard; a chosen
            extension, 0 by default; :func:`propeller_side_force`).
        c_y_brake: the same in the braking quadrant (the shaft turning ahead or stopped, the
            thrust negative: the seed's zero-pitch coasting stop), pushing the stern to
            starboard (the bow to port; chosen extension, 0 by default).
        stall_angle: the rudder's stall angle (rad, the angle of attack ``alpha_R`` folded to
            ``[0, pi/2]``); ``inf`` (default): no stall, the MMG standard's ``f_alpha sin
            alpha_R`` at every angle (:func:`rudder_normal_coefficient`).
        post_stall: the fraction of the normal force at the stall angle kept past it (0 to 1;
            1 by default).
    """

    L: float
    B: float
    d: float
    nabla: float
    x_G: float
    D_P: float
    H_R: float
    A_R: float
    k_zz: float
    R0: float
    X_vv: float
    X_vr: float
    X_rr: float
    X_vvvv: float
    Y_v: float
    Y_r: float
    Y_vvv: float
    Y_vvr: float
    Y_vrr: float
    Y_rrr: float
    N_v: float
    N_r: float
    N_vvv: float
    N_vvr: float
    N_vrr: float
    N_rrr: float
    m_x: float
    m_y: float
    J_z: float
    t_P: float
    w_P0: float
    k0: float
    k1: float
    k2: float
    C1: float
    C2_pos: float
    C2_neg: float
    x_P: float
    t_R: float
    a_H: float
    x_H: float
    x_R: float
    gamma_neg: float
    gamma_pos: float
    l_R: float
    eps: float
    kappa: float
    f_alpha: float
    rho: float = 1025.0
    c_y: float = 0.0
    c_y_brake: float = 0.0
    stall_angle: float = math.inf
    post_stall: float = 1.0

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if f.name == "stall_angle" and v == math.inf:
                continue
            if not (isinstance(v, int | float) and math.isfinite(v)):
                raise ValueError(f"MMGParameters.{f.name} must be a finite number, got {v!r}")
        for k in ("L", "B", "d", "nabla", "D_P", "H_R", "A_R", "rho", "k_zz", "stall_angle"):
            if not getattr(self, k) > 0:
                raise ValueError(f"MMGParameters.{k} must be > 0, got {getattr(self, k)!r}")
        for k in ("c_y", "c_y_brake", "post_stall"):
            if not 0.0 <= getattr(self, k) <= 1.0:
                raise ValueError(f"MMGParameters.{k} must be from 0 to 1, got {getattr(self, k)!r}")
        require_dimensions(self, "L", "B", "d", "D_P")

    @property
    def aspect_ratio(self) -> float:
        """The rudder's geometric aspect ratio ``H_R^2 / A_R`` (1)."""
        return self.H_R**2 / self.A_R

    def with_rudder(self, option: str) -> MMGParameters:
        """The same ship with the rudder of :data:`RUDDER_OPTIONS` ``option``: its normal-force
        slope (:meth:`RudderOption.f_alpha`), stall angle and post-stall fraction.

        Raises:
            ValueError: an unknown option.
        """
        opt = rudder_option(option)
        return dataclasses.replace(self, f_alpha=opt.f_alpha(self), stall_angle=opt.stall_angle,
                                   post_stall=opt.post_stall)  # fmt: skip

    def scaled(self, L: float) -> MMGParameters:
        """The same hull geometrically scaled to the length ``L`` (m): lengths x ``L/self.L``,
        the volume x its cube; the nondimensional coefficients stay."""
        s = float(L) / self.L
        return dataclasses.replace(
            self, L=self.L * s, B=self.B * s, d=self.d * s, nabla=self.nabla * s**3,
            x_G=self.x_G * s, D_P=self.D_P * s, H_R=self.H_R * s, A_R=self.A_R * s**2,
        )  # fmt: skip


#: the KVLCC2 L7 model (Yasukawa & Yoshimura 2015): L 7 m, B 1.27 m, d 0.46 m, nabla
#: 3.27 m^3, x_G 0.25 m, D_P 0.216 m, H_R 0.345 m, A_R 0.0539 m^2 [published]
KVLCC2_L7 = MMGParameters(
    L=7.00, B=1.27, d=0.46, nabla=3.27, x_G=0.25, D_P=0.216, H_R=0.345, A_R=0.0539,
    k_zz=0.25, R0=0.022, X_vv=-0.040, X_vr=0.002, X_rr=0.011, X_vvvv=0.771, Y_v=-0.315,
    Y_r=0.083, Y_vvv=-1.607, Y_vvr=0.379, Y_vrr=-0.391, Y_rrr=0.008, N_v=-0.137,
    N_r=-0.049, N_vvv=-0.030, N_vvr=-0.294, N_vrr=0.055, N_rrr=-0.013, m_x=0.022,
    m_y=0.223, J_z=0.011, t_P=0.220, w_P0=0.40, k0=0.2931, k1=-0.2753, k2=-0.1385, C1=2.0,
    C2_pos=1.6, C2_neg=1.1, x_P=-0.48, t_R=0.387, a_H=0.312, x_H=-0.464, x_R=-0.5,
    gamma_neg=0.395, gamma_pos=0.640, l_R=-0.710, eps=1.09, kappa=0.50, f_alpha=2.747,
)  # fmt: skip


def kvlcc2(L: float = 7.0) -> MMGParameters:
    """The KVLCC2 at the length ``L`` (m): 7 m the L7 model, 100 m the seed's tanker."""
    return KVLCC2_L7.scaled(L)


class MMGModel:
    """The MMG equations of :class:`MMGParameters` (module docstring).

    Args:
        p: the parameters.
    """

    def __init__(self, p: MMGParameters) -> None:
        self.p = p
        h = 0.5 * p.rho * p.L * p.d
        self.m = p.rho * p.nabla
        self.mx = p.m_x * h * p.L
        self.my = p.m_y * h * p.L
        self.Jz = p.J_z * h * p.L**3
        self.IzG = self.m * (p.k_zz * p.L) ** 2
        M = np.array([[self.m + self.my, p.x_G * self.m],
                      [p.x_G * self.m, self.IzG + p.x_G**2 * self.m + self.Jz]])  # fmt: skip
        self._Minv = np.linalg.inv(M)

    def wake(self, beta_P: Array) -> Array:
        """``1 - w_P`` (Yasukawa & Yoshimura 2015): ``(1 - w_P0)[1 + (1 - exp(-C1 |beta_P|))
        (C2 - 1)]``, ``C2`` by the sign of ``beta_P``."""
        p = self.p
        C2 = np.where(beta_P > 0, p.C2_pos, p.C2_neg)
        return (1 - p.w_P0) * (1 + (1 - np.exp(-p.C1 * np.abs(beta_P))) * (C2 - 1))

    def hull_forces(self, nu: ArrayLike) -> tuple[Array, Array, Array]:
        """``(X_H, Y_H, N_H)`` (N, N, N m) of the bare hull at ``nu = [u, v, r]`` (..., 3)
        through the water (Yasukawa & Yoshimura 2015 eqs. 9-11)."""
        p = self.p
        nu = np.asarray(nu, dtype=float)
        u, v, r = nu[..., 0], nu[..., 1], nu[..., 2]
        U = np.hypot(u, v)
        Us = np.where(U > 1e-9, U, 1e-9)
        vp, rp = v / Us, r * p.L / Us
        q = 0.5 * p.rho * p.L * p.d * U**2
        XH = q * (-p.R0 + p.X_vv * vp**2 + p.X_vr * vp * rp + p.X_rr * rp**2
                  + p.X_vvvv * vp**4)  # fmt: skip
        YH = q * (p.Y_v * vp + p.Y_r * rp + p.Y_vvv * vp**3 + p.Y_vvr * vp**2 * rp
                  + p.Y_vrr * vp * rp**2 + p.Y_rrr * rp**3)  # fmt: skip
        NH = q * p.L * (p.N_v * vp + p.N_r * rp + p.N_vvv * vp**3 + p.N_vvr * vp**2 * rp
                        + p.N_vrr * vp * rp**2 + p.N_rrr * rp**3)  # fmt: skip
        return XH, YH, NH

    def propulsion_forces(
        self, nu: ArrayLike, delta: ArrayLike, n: ArrayLike
    ) -> tuple[Array, Array, Array, dict[str, Array]]:
        """``(X, Y, N, parts)`` of the propeller and rudder (N, N, N m) at ``nu = [u, v, r]``
        (..., 3) through the water, rudder angle ``delta`` (rad, the paper's sign: positive
        turns to starboard) and propeller speed ``n`` (rps); ``parts`` holds ``X_P``, ``Y_P``,
        ``N_P``, ``X_R``, ``Y_R``, ``N_R``, the thrust ``T``, ``K_T``, ``J_P``, ``u_R``,
        ``v_R``, ``alpha_R`` and ``F_N``."""
        p = self.p
        nu = np.asarray(nu, dtype=float)
        u, v, r = nu[..., 0], nu[..., 1], nu[..., 2]
        delta = np.asarray(delta, dtype=float)
        n = np.asarray(n, dtype=float)
        U = np.hypot(u, v)
        Us = np.where(U > 1e-9, U, 1e-9)
        rp = r * p.L / Us
        beta = np.arctan2(-v, u)
        # propeller
        one_w = self.wake(beta - p.x_P * rp)
        na = np.abs(n)
        ns = np.where(na > 1e-9, na, 1e-9)
        ua = u * one_w
        J = ua / (ns * p.D_P)
        ahead = n > 0
        D = p.D_P
        # T = rho n^2 D^4 K_T(J) without dividing by n: the shaft turning ahead or stopped
        # (n >= 0; n = 0 the seed's zero pitch, the propeller dragging rho k2 D^2 u_a^2), or
        # astern with K_T = -(0.2 + 0.25 J)
        T = np.where(
            n >= 0,
            p.rho * (p.k0 * n**2 * D**4 + p.k1 * n * D**3 * ua + p.k2 * D**2 * ua**2),
            -p.rho * (0.2 * n**2 * D**4 + 0.25 * na * D**3 * ua),
        )
        KT = T / (p.rho * ns**2 * D**4)
        XP = (1 - p.t_P) * T
        n_b, XP_b = np.broadcast_arrays(n, XP)
        YP = _propeller_side_forces(
            np.ascontiguousarray(n_b, dtype=float).reshape(-1),
            np.ascontiguousarray(XP_b, dtype=float).reshape(-1), float(p.c_y),
            float(p.c_y_brake),
        ).reshape(XP_b.shape)  # fmt: skip
        NP = p.x_P * p.L * YP
        # rudder
        eta = p.D_P / p.H_R
        Js = np.where(np.abs(J) > 1e-9, J, 1e-9)
        race = np.sqrt(np.maximum(1 + 8 * KT / (math.pi * Js**2), 0.0))
        slip = np.sqrt(eta * (1 + p.kappa * (race - 1)) ** 2 + 1 - eta)
        uR = p.eps * u * one_w * np.where(ahead, slip, 1.0)
        beta_R = beta - p.l_R * rp
        vR = U * np.where(beta_R < 0, p.gamma_neg, p.gamma_pos) * beta_R
        alpha = delta - np.arctan2(vR, uR)
        FN = 0.5 * p.rho * p.A_R * (uR**2 + vR**2) * rudder_normal_coefficients(alpha, p)
        XR = -(1 - p.t_R) * FN * np.sin(delta)
        YR = -(1 + p.a_H) * FN * np.cos(delta)
        NR = -(p.x_R * p.L + p.a_H * p.x_H * p.L) * FN * np.cos(delta)
        parts = {"X_P": XP, "Y_P": YP, "N_P": NP, "X_R": XR, "Y_R": YR, "N_R": NR, "T": T,
                 "K_T": KT, "J_P": J, "u_R": uR, "v_R": vR, "alpha_R": alpha,
                 "F_N": FN}  # fmt: skip
        return XP + XR, YP + YR, NP + NR, parts

    def forces(
        self, nu: ArrayLike, delta: ArrayLike, n: ArrayLike
    ) -> tuple[Array, Array, Array, dict[str, Array]]:
        """``(X, Y, N, parts)`` (N, N, N m) at ``nu = [u, v, r]`` (..., 3), rudder angle
        ``delta`` (rad, the paper's sign) and propeller speed ``n`` (rps): the hull's
        (:meth:`hull_forces`) plus the propeller's and rudder's (:meth:`propulsion_forces`);
        ``parts`` holds the hull terms ``X_H``, ``Y_H``, ``N_H`` too."""
        XH, YH, NH = self.hull_forces(nu)
        X, Y, N, parts = self.propulsion_forces(nu, delta, n)
        parts = {"X_H": XH, "Y_H": YH, "N_H": NH, **parts}
        return XH + X, YH + Y, NH + N, parts

    def nu_dot(self, nu: ArrayLike, delta: ArrayLike, n: ArrayLike) -> Array:
        """``[u_dot, v_dot, r_dot]`` (m/s^2, m/s^2, rad/s^2), shape of ``nu``."""
        p = self.p
        nu = np.asarray(nu, dtype=float)
        u, v, r = nu[..., 0], nu[..., 1], nu[..., 2]
        X, Y, N, _ = self.forces(nu, delta, n)
        ud = (X + (self.m + self.my) * v * r + p.x_G * self.m * r**2) / (self.m + self.mx)
        b1 = Y - (self.m + self.mx) * u * r
        b2 = N - p.x_G * self.m * u * r
        Mi = self._Minv
        vd = Mi[0, 0] * b1 + Mi[0, 1] * b2
        rd = Mi[1, 0] * b1 + Mi[1, 1] * b2
        return np.stack(np.broadcast_arrays(ud, vd, rd), -1)

    def self_propulsion(self, U: float) -> float:
        """The propeller speed (rps) that holds ``u = U`` in straight running (``X = 0``)."""
        from scipy.optimize import brentq

        return float(brentq(lambda n: self.nu_dot([U, 0.0, 0.0], 0.0, n)[0], 1e-3, 1e3))


@njit
def accel_mmg(k, u, v, p, r, phi, X, Y, K, N, u_c, v_c):  # type: ignore[no-untyped-def]
    r"""The ``mmg`` family's compiled acceleration (:data:`~shipgym._jit.ACCEL_SIG`).

    :meth:`MMGHull.nu_dot` written out (the equations of :class:`MMGHull`): the bare hull's
    forces of Yasukawa & Yoshimura (2015) eqs. 9-11 at ``nu_r = [u - u_c, v - v_c, r]``
    (:meth:`MMGModel.hull_forces`), the inertia of their eq. 4 with the
    current's terms, ``X``, ``Y``, ``N`` the actuators' and the environment's force.

    Args:
        k: the 29 constants of :meth:`MMGHull.kernel_constants` (float64, C-contiguous).
        u, v, p, r: body velocity over ground (m/s, m/s, rad/s, rad/s); ``p`` is ignored.
        phi: roll angle (rad), ignored (3 DOF).
        X, Y, K, N: total external generalised force (N, N, N m, N m); ``K`` is ignored.
        u_c, v_c: body-frame current (m/s), constant in NED.

    Returns:
        ``(u_dot, v_dot, 0.0, r_dot)`` (m/s^2, m/s^2, rad/s^2, rad/s^2).
    """
    L = k[1]
    m = k[19]
    mx = k[20]
    my = k[21]
    xg = k[22]
    ur = u - u_c
    vr = v - v_c
    # bare hull (Yasukawa & Yoshimura 2015 eqs. 9-11) at nu_r
    U2 = ur * ur + vr * vr
    U = math.sqrt(U2)
    Us = U if U > 1e-9 else 1e-9
    vp = vr / Us
    rp = r * L / Us
    q = k[0] * U2
    v2 = vp * vp
    r2 = rp * rp
    XH = q * (-k[2] + k[3] * v2 + k[4] * vp * rp + k[5] * r2 + k[6] * v2 * v2)
    YH = q * (k[7] * vp + k[8] * rp + k[9] * v2 * vp + k[10] * v2 * rp + k[11] * vp * r2
              + k[12] * r2 * rp)  # fmt: skip
    NH = q * L * (k[13] * vp + k[14] * rp + k[15] * v2 * vp + k[16] * v2 * rp
                  + k[17] * vp * r2 + k[18] * r2 * rp)  # fmt: skip
    # inertia (eq. 4) with the current's terms
    fx = XH + X + m * (v * r + xg * r * r) + my * vr * r + mx * r * v_c
    fy = YH + Y - m * u * r - mx * ur * r - my * r * u_c
    fn = NH + N - k[23] * u * r
    return k[24] * fx, k[25] * fy + k[26] * fn, 0.0, k[27] * fy + k[28] * fn


class MMGHull:
    r"""The MMG hull as a shipgym plant (3 DOF, midship origin): the bare hull's forces
    (:meth:`MMGModel.hull_forces`) and the inertia of the MMG equations, with the propeller
    and rudder as the vessel's actuator (:class:`~shipgym.dynamics.actuators.MMGPropulsion`,
    whose force the physics adds to ``tau``).

    With a current ``nu_c`` (constant in NED), the rigid body moves with ``nu`` and the water
    forces and added masses with ``nu_r = nu - nu_c``:

    .. math::

        m(\dot u - v r - x_G r^2) + m_x \dot u_r - m_y v_r r = X_H(\nu_r) + X \\
        m(\dot v + u r + x_G \dot r) + m_y \dot v_r + m_x u_r r = Y_H(\nu_r) + Y \\
        (I_{zG} + x_G^2 m)\dot r + x_G m(\dot v + u r) + J_z \dot r = N_H(\nu_r) + N

    with ``dot nu_r = dot nu - [r v_c, -r u_c, 0]``; without current these are Yasukawa &
    Yoshimura (2015) eq. 4 (the paper's yaw equation has no Munk moment of the added masses:
    it is in ``N'_v``).

    The family's compiled kernel is :attr:`accel_kernel` (:func:`accel_mmg`) with the constant
    vector of :meth:`kernel_constants` (29 values, layout there).

    Args:
        p: the parameters.
        name: the plant variant's name.
    """

    dofs = 3
    #: the hull family (``[hull] family`` of a vessel package)
    family: ClassVar[str] = "mmg"
    #: the family's compiled acceleration, :func:`accel_mmg` (``ACCEL_SIG``)
    accel_kernel = staticmethod(accel_mmg)

    def __init__(self, p: MMGParameters, name: str = "default") -> None:
        if not isinstance(p, MMGParameters):
            raise TypeError(f"MMGHull needs MMGParameters, got {type(p).__name__}")
        self.p = p
        self.name = name
        self.model = MMGModel(p)
        self.m = self.model.m

    def __repr__(self) -> str:
        return f"MMGHull({self.name!r}, L = {self.p.L:g} m)"

    def mass_matrix(self) -> Array:
        """``M = M_RB + M_A`` (kg, kg m, kg m^2) about midship, (3, 3)."""
        md = self.model
        xg = self.p.x_G * md.m
        return np.array([[md.m + md.mx, 0.0, 0.0], [0.0, md.m + md.my, xg],
                         [0.0, xg, md.IzG + self.p.x_G * xg + md.Jz]])  # fmt: skip

    def nu_dot(self, nu: ArrayLike, tau: ArrayLike, nu_c: ArrayLike | None = None) -> Array:
        """Body-frame acceleration (..., 3) by a linear solve of the equations above.

        Args:
            nu: body velocity over ground ``[u, v, r]`` (m/s, m/s, rad/s), (..., 3).
            tau: the actuators' and the environment's force ``[X, Y, N]`` (N, N, N m).
            nu_c: body-frame current ``[u_c, v_c, 0]`` (m/s).
        """
        md = self.model
        nu = np.asarray(nu, dtype=float)
        tau = np.asarray(tau, dtype=float)
        nu_c = np.zeros(3) if nu_c is None else np.asarray(nu_c, dtype=float)
        nu_r = nu - nu_c
        u, v, r = nu[..., 0], nu[..., 1], nu[..., 2]
        ur, vr = nu_r[..., 0], nu_r[..., 1]
        uc, vc = nu_c[..., 0], nu_c[..., 1]
        XH, YH, NH = md.hull_forces(nu_r)
        m, xg = md.m, self.p.x_G
        rhs = np.stack(np.broadcast_arrays(
            XH + tau[..., 0] + m * (v * r + xg * r * r) + md.my * vr * r + md.mx * r * vc,
            YH + tau[..., 1] - m * u * r - md.mx * ur * r - md.my * r * uc,
            NH + tau[..., 2] - m * xg * u * r,
        ), -1)  # fmt: skip
        return np.linalg.solve(self.mass_matrix(), rhs[..., None])[..., 0]

    def kernel_constants(self) -> Array:
        """The constant vector ``k`` of :func:`accel_mmg` (a new float64, C-contiguous array
        of 29; the hull coefficients nondimensional, Yasukawa & Yoshimura 2015 Table 2):

        - ``k[0]``: ``rho/2 L d`` (kg/m, the force base per ``U^2``); ``k[1]``: ``L`` (m);
        - ``k[2:7]``: ``R'_0, X'_vv, X'_vr, X'_rr, X'_vvvv``;
        - ``k[7:13]``: ``Y'_v, Y'_r, Y'_vvv, Y'_vvr, Y'_vrr, Y'_rrr``;
        - ``k[13:19]``: ``N'_v, N'_r, N'_vvv, N'_vvr, N'_vrr, N'_rrr``;
        - ``k[19:24]``: ``m, m_x, m_y`` (kg), ``x_G`` (m), ``m x_G`` (kg m);
        - ``k[24]``: ``1/(m + m_x)`` (1/kg); ``k[25:29]``: the sway-yaw block of ``M^-1`` by
          rows, ``i22, i23, i32, i33`` (1/kg, 1/(kg m), 1/(kg m), 1/(kg m^2)).
        """
        p, md = self.p, self.model
        Mi = np.linalg.inv(self.mass_matrix())
        k = (
            0.5 * p.rho * p.L * p.d, p.L,
            p.R0, p.X_vv, p.X_vr, p.X_rr, p.X_vvvv,
            p.Y_v, p.Y_r, p.Y_vvv, p.Y_vvr, p.Y_vrr, p.Y_rrr,
            p.N_v, p.N_r, p.N_vvv, p.N_vvr, p.N_vrr, p.N_rrr,
            md.m, md.mx, md.my, p.x_G, md.m * p.x_G,
            1.0 / (md.m + md.mx), Mi[1, 1], Mi[1, 2], Mi[2, 1], Mi[2, 2],
        )  # fmt: skip
        return np.ascontiguousarray(k, dtype=np.float64)


def with_rudder(vessel: Any, option: str) -> Any:
    """The vessel ``vessel`` (a :class:`~shipgym.dynamics.vessel.Vessel` of the ``mmg``
    family) with the rudder of :data:`RUDDER_OPTIONS` ``option``: every MMG unit's and hull's
    parameters through :meth:`MMGParameters.with_rudder`, the unit's largest rudder angle the
    option's (the rate limit, the servo and the rest stay the ship's).

    Raises:
        ValueError: an unknown option, or a vessel without an MMG unit.
    """
    opt = rudder_option(option)

    def mmg_unit(a: Any) -> bool:  # an MMGPropulsion (not imported here: it imports this)
        return isinstance(getattr(a, "params", None), MMGParameters)

    acts = [
        dataclasses.replace(a, params=a.params.with_rudder(option), max_angle=opt.max_angle)
        if mmg_unit(a) else a
        for a in vessel.actuators
    ]  # fmt: skip
    if not any(mmg_unit(a) for a in acts):
        raise ValueError(f"vessel {vessel.name!r} has no MMG rudder (an 'mmg' unit) to replace")
    plants = {k: MMGHull(h.p.with_rudder(option), h.name) if isinstance(h, MMGHull) else h
              for k, h in vessel.plants.items()}  # fmt: skip
    acts_set = type(vessel.actuators)(acts, vessel.dofs)
    return dataclasses.replace(vessel, actuators=acts_set, plants=plants,
                               title=f"{vessel.title}, {opt.name} rudder")  # fmt: skip
