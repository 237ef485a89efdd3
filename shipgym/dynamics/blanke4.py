r"""The nonlinear 4-DOF naval vessel of Blanke & Christensen (1993) (surge, sway, roll, yaw).

``M nu_dot = f_h(nu_r, p, r, phi) + f_c(nu, phi) + tau``, ``nu = [u, v, p, r]``, about
the waterline origin (Blanke & Christensen 1993).

Public names: ``Blanke4Hull``, ``NAVAL_VESSEL``, ``NAVAL_VESSEL_SOURCE``,
``roll_natural_frequency``, ``roll_damping_ratio``, ``linear_roll_model``, ``roll_rhs``,
``surge_thrust``, ...
Sources: Blanke & Christensen (1993); Fossen & Perez (2004); Radhakrishnan (n.d.).

Design notes: docs/design/dynamics.blanke4.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import require_dimensions, require_positive, required_param
from shipgym._jit import njit

__all__ = [
    "Blanke4Hull",
    "NAVAL_VESSEL",
    "NAVAL_VESSEL_SOURCE",
    "roll_natural_frequency",
    "roll_damping_ratio",
    "linear_roll_model",
    "roll_rhs",
    "surge_thrust",
    "SEED_STATE",
    "accel_blanke4",
]

#: the seed's state order of :func:`linear_roll_model` and :func:`roll_rhs`
SEED_STATE = ("v", "r", "psi", "p", "phi")


@njit
def accel_blanke4(k, u, v, p, r, phi, X, Y, K, N, u_c, v_c):  # type: ignore[no-untyped-def]
    r"""The ``blanke4`` family's compiled acceleration (:data:`~shipgym._jit.ACCEL_SIG`).

    :meth:`Blanke4Hull.nu_dot` written out (the equations of the module docstring, Blanke &
    Christensen 1993 with the data layout of ``navalvessel.m``):
    ``M nu_dot = tau + f_h(nu_r, p, r, phi) + f_c(nu, phi)``.

    Args:
        k: the 53 constants of :meth:`Blanke4Hull.kernel_constants` (float64, C-contiguous).
        u, v, p, r: body velocity over ground (m/s, m/s, rad/s, rad/s).
        phi: roll angle (rad).
        X, Y, K, N: total external generalised force (N, N, N m, N m).
        u_c, v_c: body-frame current (m/s).

    Returns:
        ``(u_dot, v_dot, p_dot, r_dot)`` (m/s^2, m/s^2, rad/s^2, rad/s^2).
    """
    m = k[16]
    xg = k[17]
    zg = k[18]
    ur = u - u_c
    vr = v - v_c
    au = abs(ur)
    av = abs(vr)
    ar = abs(r)
    auv = abs(ur * vr)
    aur = au * ar
    f1 = X + k[20] * ur * au + k[21] * vr * r + m * (v * r + xg * r * r - zg * p * r)
    f2 = (Y + k[22] * au * vr + k[23] * ur * r + k[24] * vr * av + k[25] * r * ar
          + k[26] * vr * ar + k[27] * r * av
          + phi * (k[28] * auv + k[29] * aur + k[30] * ur * ur) - m * u * r)  # fmt: skip
    f3 = (K + k[31] * au * vr + k[32] * ur * r + k[33] * vr * av + k[34] * r * ar
          + k[35] * vr * ar + k[36] * r * av
          + phi * (k[37] * auv + k[38] * aur + k[39] * ur * ur - k[19] + k[43] * phi * phi)
          + (k[40] * au + k[41] * abs(p) + k[42]) * p + m * zg * u * r)  # fmt: skip
    f4 = (N + k[44] * au * vr + k[45] * au * r + k[46] * vr * av + k[47] * r * ar
          + k[48] * vr * ar + k[49] * r * av - m * xg * u * r
          + phi * (k[50] * auv + k[51] * ur * ar + k[52] * ur * au))  # fmt: skip
    return (
        k[0] * f1 + k[1] * f2 + k[2] * f3 + k[3] * f4,
        k[4] * f1 + k[5] * f2 + k[6] * f3 + k[7] * f4,
        k[8] * f1 + k[9] * f2 + k[10] * f3 + k[11] * f4,
        k[12] * f1 + k[13] * f2 + k[14] * f3 + k[15] * f4,
    )


@dataclass(frozen=True)
class Blanke4Hull:
    """Data of a Blanke & Christensen (1993) nonlinear 4-DOF hull (dimensional derivatives).

    Every field is required (no vessel is a default); :data:`NAVAL_VESSEL` holds the naval
    vessel of ``navalvessel.m``. Naming: ``a`` marks an absolute value and ``ph`` the roll
    angle, e.g. ``Y_auv`` is ``Y_{|u|v}``, ``K_phauv`` is ``K_{phi|uv|}``, ``N_phuar`` is
    ``N_{phi u|r|}`` (the module docstring has the equations). Units in each field's metadata.

    Derived attributes: ``m = rho nabla`` (kg), ``K_phi = rho g nabla GM`` (N m/rad, the
    linear roll restoring), ``dofs = 4``.

    The family's compiled kernel is :attr:`accel_kernel` (:func:`accel_blanke4`) with the
    constant vector of :meth:`kernel_constants` (53 values, layout there).
    """

    #: the hull family (``[hull] family`` of a vessel package)
    family: ClassVar[str] = "blanke4"
    #: the family's compiled acceleration, :func:`accel_blanke4` (``ACCEL_SIG``)
    accel_kernel = staticmethod(accel_blanke4)

    name: str = required_param("-", "the hull's name")
    source: str = required_param("-", "where the numbers come from")
    rho: float = required_param("kg/m^3", "water density")
    g: float = required_param("m/s^2", "gravity")
    L_pp: float = required_param("m", "length between perpendiculars")
    B: float = required_param("m", "beam")
    T: float = required_param("m", "draught")
    nabla: float = required_param("m^3", "displaced volume (m = rho nabla)")
    I_xx: float = required_param("kg m^2", "roll moment of inertia")
    I_zz: float = required_param("kg m^2", "yaw moment of inertia")
    x_G: float = required_param("m", "x of the CG in the body frame (forward +)")
    z_G: float = required_param("m", "z of the CG in the body frame (down +; < 0 above the WL)")
    GM: float = required_param("m", "transverse metacentric height")
    X_udot: float = required_param("kg", "surge added mass")
    X_uau: float = required_param("kg/m", "X_{u|u|}, surge resistance")
    X_vr: float = required_param("kg", "X_{vr}")
    Y_vdot: float = required_param("kg", "sway added mass")
    Y_pdot: float = required_param("kg m", "sway-roll added mass")
    Y_rdot: float = required_param("kg m", "sway-yaw added mass")
    Y_auv: float = required_param("kg/m", "Y_{|u|v}")
    Y_ur: float = required_param("kg", "Y_{ur}")
    Y_vav: float = required_param("kg/m", "Y_{v|v|}")
    Y_rar: float = required_param("kg m", "Y_{r|r|}")
    Y_var: float = required_param("kg", "Y_{v|r|}")
    Y_rav: float = required_param("kg", "Y_{r|v|}")
    Y_phauv: float = required_param("kg/m", "Y_{phi|uv|}")
    Y_phaur: float = required_param("kg", "Y_{phi|ur|}")
    Y_phuu: float = required_param("kg/m", "Y_{phi uu}")
    K_vdot: float = required_param("kg m", "roll-sway added mass")
    K_pdot: float = required_param("kg m^2", "roll added inertia")
    K_rdot: float = required_param("kg m^2", "roll-yaw added inertia")
    K_auv: float = required_param("kg", "K_{|u|v}")
    K_ur: float = required_param("kg m", "K_{ur}")
    K_vav: float = required_param("kg", "K_{v|v|}")
    K_rar: float = required_param("kg m^2", "K_{r|r|}")
    K_var: float = required_param("kg m", "K_{v|r|}")
    K_rav: float = required_param("kg m", "K_{r|v|}")
    K_phauv: float = required_param("kg", "K_{phi|uv|}")
    K_phaur: float = required_param("kg m", "K_{phi|ur|}")
    K_phuu: float = required_param("kg", "K_{phi uu}")
    K_aup: float = required_param("kg m", "K_{|u|p}")
    K_pap: float = required_param("kg m^2", "K_{p|p|}")
    K_p: float = required_param("N m s", "K_{p}, linear roll damping")
    K_phphph: float = required_param("N m", "K_{phi phi phi}, cubic roll restoring")
    N_vdot: float = required_param("kg m", "yaw-sway added mass")
    N_pdot: float = required_param("kg m^2", "yaw-roll added inertia")
    N_rdot: float = required_param("kg m^2", "yaw added inertia")
    N_auv: float = required_param("kg", "N_{|u|v}")
    N_aur: float = required_param("kg m", "N_{|u|r}")
    N_vav: float = required_param("kg", "N_{v|v|}")
    N_rar: float = required_param("kg m^2", "N_{r|r|}")
    N_var: float = required_param("kg m", "N_{v|r|}")
    N_rav: float = required_param("kg m", "N_{r|v|}")
    N_phauv: float = required_param("kg", "N_{phi|uv|}")
    N_phuar: float = required_param("kg m", "N_{phi u|r|}")
    N_phuau: float = required_param("kg", "N_{phi u|u|}")
    m: float = field(init=False, metadata={"unit": "kg", "meaning": "rigid mass rho nabla"})
    K_phi: float = field(init=False, metadata={"unit": "N m/rad", "meaning": "rho g nabla GM"})
    dofs: int = field(default=4, init=False)
    _Mi: Any = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for f in fields(self):
            if f.init and f.name not in ("name", "source"):
                val = getattr(self, f.name)
                if (
                    isinstance(val, bool)
                    or not isinstance(val, int | float)
                    or not (math.isfinite(val))
                ):
                    raise ValueError(
                        f"Blanke4Hull.{f.name} must be a finite number ({f.metadata['unit']}), "
                        f"got {val!r}"
                    )
                object.__setattr__(self, f.name, float(val))
        object.__setattr__(self, "m", self.rho * self.nabla)
        object.__setattr__(self, "K_phi", self.rho * self.g * self.nabla * self.GM)
        require_positive(self, "rho", "g", "L_pp", "B", "T", "nabla", "I_xx", "I_zz", "GM")
        require_dimensions(self, "L_pp", "B", "T")
        M = self.mass_matrix()
        if not np.all(np.diag(M) > 0) or not np.linalg.cond(M) < 1e12:
            raise ValueError(
                f"hull {self.name!r}: the mass matrix M_RB + M_A must have a positive diagonal "
                f"and be regular (check the added-mass signs: X_udot etc. < 0): {M.tolist()}"
            )
        Mi = np.linalg.inv(M)
        object.__setattr__(self, "_Mi", Mi)

    def mass_matrix(self) -> NDArray[np.float64]:
        """``M = M_RB + M_A`` (4, 4), order ``u, v, p, r`` (kg, kg m, kg m^2)."""
        m, xg, zg = self.m, self.x_G, self.z_G
        return np.array(
            [
                [m - self.X_udot, 0.0, 0.0, 0.0],
                [0.0, m - self.Y_vdot, -(m * zg + self.Y_pdot), m * xg - self.Y_rdot],
                [0.0, -(m * zg + self.K_vdot), self.I_xx - self.K_pdot, -self.K_rdot],
                [0.0, m * xg - self.N_vdot, -self.N_pdot, self.I_zz - self.N_rdot],
            ]
        )

    def forces(
        self,
        nu: ArrayLike,
        nu_c: ArrayLike | None = None,
        phi: ArrayLike = 0.0,
    ) -> NDArray[np.float64]:
        """Hydrodynamic, restoring and rigid-body centripetal forces ``f_h + f_c`` (..., 4).

        Args:
            nu: ``[u, v, p, r]`` (m/s, m/s, rad/s, rad/s), shape (..., 4).
            nu_c: current on the body axes ``[u_c, v_c]`` or ``[u_c, v_c, 0, 0]`` (m/s).
            phi: roll angle (rad), broadcast against ``nu[..., 0]``.

        Returns:
            ``[X, Y, K, N]`` (N, N, N m, N m), shape (..., 4).
        """
        nu = np.asarray(nu, dtype=float)
        u, v, p, r = (nu[..., i] for i in range(4))
        ph = np.asarray(phi, dtype=float)
        if nu_c is None:
            ur, vr = u, v
        else:
            c = np.asarray(nu_c, dtype=float)
            ur, vr = u - c[..., 0], v - c[..., 1]
        h = self
        au, av, ar, ap = np.abs(ur), np.abs(vr), np.abs(r), np.abs(p)
        auv, aur = np.abs(ur * vr), np.abs(ur * r)
        X = h.X_uau * ur * au + h.X_vr * vr * r
        Y = (h.Y_auv * au * vr + h.Y_ur * ur * r + h.Y_vav * vr * av + h.Y_rar * r * ar
             + h.Y_var * vr * ar + h.Y_rav * r * av
             + ph * (h.Y_phauv * auv + h.Y_phaur * aur + h.Y_phuu * ur * ur))  # fmt: skip
        K = (h.K_auv * au * vr + h.K_ur * ur * r + h.K_vav * vr * av + h.K_rar * r * ar
             + h.K_var * vr * ar + h.K_rav * r * av
             + ph * (h.K_phauv * auv + h.K_phaur * aur + h.K_phuu * ur * ur)
             + h.K_aup * au * p + h.K_pap * p * ap + h.K_p * p
             + h.K_phphph * ph**3 - h.K_phi * ph)  # fmt: skip
        N = (h.N_auv * au * vr + h.N_aur * au * r + h.N_vav * vr * av + h.N_rar * r * ar
             + h.N_var * vr * ar + h.N_rav * r * av
             + ph * (h.N_phauv * auv + h.N_phuar * ur * ar + h.N_phuau * ur * au))  # fmt: skip
        m, xg, zg = h.m, h.x_G, h.z_G
        X = X + m * (v * r + xg * r * r - zg * p * r)
        Y = Y - m * u * r
        K = K + m * zg * u * r
        N = N - m * xg * u * r
        return np.stack(np.broadcast_arrays(X, Y, K, N), -1)

    def nu_dot(
        self,
        nu: ArrayLike,
        tau: ArrayLike,
        nu_c: ArrayLike | None = None,
        phi: ArrayLike = 0.0,
    ) -> NDArray[np.float64]:
        """Body acceleration (..., 4) by a linear solve (the matrix form).

        Args:
            nu: ``[u, v, p, r]`` (m/s, m/s, rad/s, rad/s), shape (..., 4).
            tau: external ``[X, Y, K, N]`` (N, N, N m, N m), shape (..., 4).
            nu_c: current on the body axes ``[u_c, v_c]`` or ``[u_c, v_c, 0, 0]`` (m/s).
            phi: roll angle (rad).

        Returns:
            ``[u_dot, v_dot, p_dot, r_dot]`` (m/s^2, m/s^2, rad/s^2, rad/s^2), shape (..., 4).
        """
        rhs = np.asarray(tau, dtype=float) + self.forces(nu, nu_c, phi)
        return np.linalg.solve(self.mass_matrix(), rhs[..., None])[..., 0]

    def kernel_constants(self) -> NDArray[np.float64]:
        """The constant vector ``k`` of :func:`accel_blanke4` (a new float64, C-contiguous
        array of 53; units of each derivative in its field's metadata):

        - ``k[0:16]``: ``M^-1`` by rows, order ``(u, v, p, r)`` (1/kg, 1/(kg m), 1/(kg m^2));
        - ``k[16:20]``: ``m`` (kg), ``x_G``, ``z_G`` (m), ``K_phi = rho g nabla GM`` (N m/rad);
        - ``k[20:22]``: ``X_uau, X_vr``;
        - ``k[22:31]``: ``Y_auv, Y_ur, Y_vav, Y_rar, Y_var, Y_rav, Y_phauv, Y_phaur, Y_phuu``;
        - ``k[31:44]``: ``K_auv, K_ur, K_vav, K_rar, K_var, K_rav, K_phauv, K_phaur, K_phuu,
          K_aup, K_pap, K_p, K_phphph``;
        - ``k[44:53]``: ``N_auv, N_aur, N_vav, N_rar, N_var, N_rav, N_phauv, N_phuar,
          N_phuau``.
        """
        h = self
        rest = (
            h.m, h.x_G, h.z_G, h.K_phi,
            h.X_uau, h.X_vr,
            h.Y_auv, h.Y_ur, h.Y_vav, h.Y_rar, h.Y_var, h.Y_rav, h.Y_phauv, h.Y_phaur, h.Y_phuu,
            h.K_auv, h.K_ur, h.K_vav, h.K_rar, h.K_var, h.K_rav, h.K_phauv, h.K_phaur, h.K_phuu,
            h.K_aup, h.K_pap, h.K_p, h.K_phphph,
            h.N_auv, h.N_aur, h.N_vav, h.N_rar, h.N_var, h.N_rav, h.N_phauv, h.N_phuar,
            h.N_phuau,
        )  # fmt: skip
        return np.ascontiguousarray(
            np.concatenate([np.asarray(self._Mi, dtype=np.float64).ravel(), rest]),
            dtype=np.float64,
        )


_MSS = "published: MSS CRAFT/SHIP/models/navalvessel.m (Fossen & Perez 2004)"

#: source label of :data:`NAVAL_VESSEL`
NAVAL_VESSEL_SOURCE = (
    f"{_MSS}, after Blanke & Christensen (1993); DMI PMM data adapted by T. Perez to an ADI design"
)

_M_NAVAL = 1014.0 * 357.0
_MG_NAVAL = _M_NAVAL * 9.81

#: The naval vessel of Blanke & Christensen (1993) with the data of ``navalvessel.m`` (51.5 m,
#: 362 t, U_nom = 8 m/s). ``X_vr = 0.33 m``, ``K_phphph = -0.325 m g`` as in the file.
NAVAL_VESSEL = Blanke4Hull(
    name="naval vessel (Blanke & Christensen 1993)",
    source=NAVAL_VESSEL_SOURCE,
    rho=1014.0, g=9.81, L_pp=51.5, B=8.6, T=2.3, nabla=357.0,
    I_xx=2.3763e6, I_zz=47.934e6, x_G=-3.38, z_G=-(3.36 - 2.3), GM=1.1,
    X_udot=-17400.0, X_uau=-1.96e3, X_vr=0.33 * _M_NAVAL,
    Y_vdot=-393000.0, Y_pdot=-296000.0, Y_rdot=-1400000.0, Y_auv=-11800.0, Y_ur=131000.0,
    Y_vav=-3700.0, Y_rar=0.0, Y_var=-794000.0, Y_rav=-182000.0, Y_phauv=10800.0,
    Y_phaur=251000.0, Y_phuu=-74.0,
    K_vdot=296000.0, K_pdot=-774000.0, K_rdot=0.0, K_auv=9260.0, K_ur=-102000.0,
    K_vav=29300.0, K_rar=0.0, K_var=621000.0, K_rav=142000.0, K_phauv=-8400.0,
    K_phaur=-196000.0, K_phuu=-1180.0, K_aup=-15500.0, K_pap=-416000.0, K_p=-500000.0,
    K_phphph=-0.325 * _MG_NAVAL,
    N_vdot=538000.0, N_pdot=0.0, N_rdot=-38.7e6, N_auv=-92000.0, N_aur=-4710000.0,
    N_vav=0.0, N_rar=-202000000.0, N_var=0.0, N_rav=-15600000.0, N_phauv=-214000.0,
    N_phuar=-4980000.0, N_phuau=-8000.0,
)  # fmt: skip


# ---- roll: natural frequency, linearisation, the 5-state right-hand side ---------------------


def roll_natural_frequency(hull: Blanke4Hull) -> float:
    """Uncoupled roll natural frequency ``sqrt(rho g nabla GM / (I_xx - K_pdot))`` (rad/s).

    Ignores the sway/yaw couplings and the speed-dependent ``K_phuu U^2`` restoring (about
    1.1 rad/s for :data:`NAVAL_VESSEL`, the notes' estimate).
    """
    return math.sqrt(hull.K_phi / (hull.I_xx - hull.K_pdot))


def roll_damping_ratio(hull: Blanke4Hull, U: float) -> float:
    """Uncoupled linear roll damping ratio at speed ``U`` (m/s), dimensionless.

    ``zeta = -(K_p + K_aup |U|) / (2 sqrt(K_eff (I_xx - K_pdot)))`` with the linear restoring
    ``K_eff = rho g nabla GM - K_phuu U^2`` (the roll row of the model alone).
    """
    k_eff = hull.K_phi - hull.K_phuu * U * U
    return -(hull.K_p + hull.K_aup * abs(U)) / (2.0 * math.sqrt(k_eff * (hull.I_xx - hull.K_pdot)))


def _check_speed(U: float) -> float:
    if isinstance(U, bool) or not isinstance(U, int | float) or not U > 0 or not math.isfinite(U):
        raise ValueError(f"U must be a forward speed > 0 m/s, got {U!r}")
    return float(U)


def _rudder_column(rudder_x: float, rudder_z: float) -> NDArray[np.float64]:
    """``[X, Y, K, N]`` of a unit sway force at ``(x, 0, z)`` (z down): ``[0, 1, -z, x]``."""
    return np.array([0.0, 1.0, -float(rudder_z), float(rudder_x)])


def linear_roll_model(
    hull: Blanke4Hull,
    U: float,
    rudder_x: float,
    rudder_z: float,
    lift_gain: float,
    *,
    method: str = "analytic",
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Linear sway-yaw-roll model ``x_dot = A x + B delta + G w`` about straight running.

    State in the seed's order ``x = [v, r, psi, p, phi]`` (Radhakrishnan (n.d.) eq. 9; m/s,
    rad/s, rad, rad/s, rad), linearised about ``u = U``, ``v = p = r = phi = 0`` with the surge
    decoupled (``u`` held at ``U``). The rudder gives ``Y = lift_gain U^2 delta`` at
    ``(rudder_x, 0, rudder_z)``: ``K = -rudder_z Y``, ``N = rudder_x Y``; ``w = [K_w, N_w]``
    are an external roll and yaw moment (N m).

    Args:
        hull: the hull.
        U: forward speed (m/s), > 0.
        rudder_x: x of the rudder's centre of pressure in the body frame (m, < 0 aft).
        rudder_z: z of the rudder's centre of pressure (m, down +, body frame).
        lift_gain: ``dY/d(delta)/U^2`` (N s^2/(m^2 rad)), e.g. ``0.5 rho A dC_L/dalpha``.
        method: ``"analytic"`` (from the derivatives) or ``"numerical"`` (central
            differences of :meth:`Blanke4Hull.nu_dot`; the two agree, a test checks it).

    Returns:
        ``(A (5, 5), B (5,), G (5, 2))``: ``B`` in (state units)/rad, ``G`` per N m.

    Raises:
        ValueError: ``U <= 0`` or an unknown ``method``.
    """
    U = _check_speed(U)
    if method == "numerical":
        return _linear_numerical(hull, U, rudder_x, rudder_z, lift_gain)
    if method != "analytic":
        raise ValueError(f"method must be 'analytic' or 'numerical', got {method!r}")
    h = hull
    m = h.m
    # d[Y, K, N] / d[v, p, r, phi] at u = U > 0 (module docstring; second-order terms vanish)
    D = np.array(
        [
            [h.Y_auv * U, 0.0, (h.Y_ur - m) * U, h.Y_phuu * U * U],
            [h.K_auv * U, h.K_aup * U + h.K_p, (h.K_ur + m * h.z_G) * U,
             h.K_phuu * U * U - h.K_phi],
            [h.N_auv * U, 0.0, (h.N_aur - m * h.x_G) * U, h.N_phuau * U * U],
        ]
    )  # fmt: skip
    M3i = np.linalg.inv(h.mass_matrix()[1:, 1:])  # rows/cols v, p, r
    acc = M3i @ D  # [v_dot, p_dot, r_dot] per [v, p, r, phi]
    b3 = M3i @ (_rudder_column(rudder_x, rudder_z)[1:] * (lift_gain * U * U))
    g3 = M3i[:, 1:]  # per [K, N]
    # seed order: x = [v, r, psi, p, phi]; acc columns are [v, p, r, phi]
    col = [0, 2, None, 1, 3]
    A = np.zeros((5, 5))
    for row, k in ((0, 0), (1, 2), (3, 1)):
        for j, c in enumerate(col):
            if c is not None:
                A[row, j] = acc[k, c]
    A[2, 1] = 1.0  # psi_dot = r cos(phi) -> r
    A[4, 3] = 1.0  # phi_dot = p
    B = np.array([b3[0], b3[2], 0.0, b3[1], 0.0])
    G = np.zeros((5, 2))
    G[0], G[1], G[3] = g3[0], g3[2], g3[1]
    return A, B, G


def roll_rhs(
    hull: Blanke4Hull,
    U: float,
    rudder_x: float,
    rudder_z: float,
    lift_gain: float,
    stall_angle: float | None = None,
) -> Callable[..., NDArray[np.float64]]:
    """The nonlinear 5-state right-hand side ``f(x, delta, w=None) -> x_dot`` (for an EKF).

    The full model with ``u`` held at ``U`` (surge decoupled), state ``x = [v, r, psi, p,
    phi]`` (seed order), ``psi_dot = r cos(phi)``, the rudder's sway force ``Y = lift_gain U^2
    delta_e`` at ``(rudder_x, 0, rudder_z)`` with ``delta_e = clip(delta, -stall, stall)``.

    Args:
        hull: the hull.
        U: forward speed (m/s), > 0.
        rudder_x, rudder_z: the rudder's centre of pressure (m, body frame, z down).
        lift_gain: ``dY/d(delta)/U^2`` (N s^2/(m^2 rad)).
        stall_angle: the rudder angle (rad) above which the force stays constant, or ``None``.

    Returns:
        ``f(x, delta, w=None)``: ``x`` (..., 5), ``delta`` (rad, broadcast), ``w`` optional
        ``[K_w, N_w]`` (N m); returns ``x_dot`` (..., 5).
    """
    U = _check_speed(U)
    if stall_angle is not None and not stall_angle > 0:
        raise ValueError(f"stall_angle must be > 0 rad or None, got {stall_angle!r}")
    col = _rudder_column(rudder_x, rudder_z) * (lift_gain * U * U)

    def f(x: ArrayLike, delta: ArrayLike, w: ArrayLike | None = None) -> NDArray[np.float64]:
        x = np.asarray(x, dtype=float)
        d = np.asarray(delta, dtype=float)
        if stall_angle is not None:
            d = np.clip(d, -stall_angle, stall_angle)
        v, r, p, ph = x[..., 0], x[..., 1], x[..., 3], x[..., 4]
        nu = np.stack(np.broadcast_arrays(np.full_like(v, U), v, p, r), -1)
        tau = d[..., None] * col
        if w is not None:
            wk = np.asarray(w, dtype=float)
            tau = tau + np.concatenate([np.zeros(wk.shape[:-1] + (2,)), wk], -1)
        acc = hull.nu_dot(nu, tau, phi=ph)
        return np.stack(
            np.broadcast_arrays(acc[..., 1], acc[..., 3], r * np.cos(ph), acc[..., 2], p), -1
        )

    return f


def _linear_numerical(
    hull: Blanke4Hull, U: float, rudder_x: float, rudder_z: float, lift_gain: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    f = roll_rhs(hull, U, rudder_x, rudder_z, lift_gain)
    x0 = np.zeros(5)
    scale = np.array([U, U / hull.L_pp, 1.0, U / hull.L_pp, 1.0])
    A = np.zeros((5, 5))
    for j in range(5):
        e = np.zeros(5)
        e[j] = 1e-9 * scale[j]  # O(h) error from the |.| kinks: keep h small
        A[:, j] = (f(x0 + e, 0.0) - f(x0 - e, 0.0)) / (2.0 * e[j])
    hd = 1e-6
    B = (f(x0, hd) - f(x0, -hd)) / (2.0 * hd)
    G = np.zeros((5, 2))
    for j in range(2):
        w = np.zeros(2)
        w[j] = 1.0e3
        G[:, j] = (f(x0, 0.0, w) - f(x0, 0.0, -w)) / (2.0 * w[j])
    return A, B, G


def surge_thrust(hull: Blanke4Hull, U: float) -> float:
    """The propeller thrust (N) that holds ``u = U`` in straight running (``v = p = r = 0``).

    ``X = -X_uau U |U|`` (the only surge force at ``v = r = 0``); ``U`` in m/s, relative to
    the water.
    """
    if isinstance(U, bool) or not isinstance(U, int | float) or not math.isfinite(U):
        raise ValueError(f"U must be a finite speed (m/s), got {U!r}")
    return float(-hull.X_uau * U * abs(U))
