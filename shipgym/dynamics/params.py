"""Hull and windage parameter records (every field required) and the Blue Lady's values.

:class:`HullParameters` and :class:`WindageParameters` carry no vessel's numbers as defaults:
a vessel's values come from its package (:func:`shipgym.dynamics.load_vessel`) or from a named
record. :data:`BLUE_LADY_HULL` and :data:`BLUE_LADY_WINDAGE` are the Blue Lady's records, each
value with its unit and source (they equal ``shipgym/assets/mjcf/blue_lady/vessel.toml``, a
test checks it). Sources: Tomera (2014), Tables 1-2, eqs. 8-12 and 49-50; the estimates of the
richer plant use Clarke et al. (1983), Van Berlekom & Goddard (1972), Hoerner (1965), ITTC-57
and OCIMF (1994); values marked "assumption" or "estimate" are the project's own. Full
entries: ``docs/references.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

from shipgym._config import (
    param,
    require_dimensions,
    require_finite,
    require_positive,
    required_param,
)

__all__ = ["HullParameters", "WindageParameters", "BLUE_LADY_HULL", "BLUE_LADY_WINDAGE"]


@dataclass(frozen=True)
class HullParameters:
    """Rigid-body, added-mass and damping parameters of a 3-DOF hull (Fossen sign convention).

    Hydrodynamic derivatives follow SNAME notation: added-mass derivatives ``X_udot`` etc. are
    negative, damping derivatives ``X_u`` etc. are negative for a stable hull. Every field must
    be given (no vessel is a default): load a vessel (``load_vessel("blue-lady").hull``) or use
    a named record such as :data:`BLUE_LADY_HULL`.
    """

    name: str = required_param("-", "the vessel's name")
    m: float = required_param("kg", "rigid-body mass")
    I_z: float = required_param("kg m^2", "yaw moment of inertia about the CG")
    x_g: float = required_param("m", "longitudinal position of the CG")
    X_udot: float = required_param("kg", "surge added mass derivative")
    Y_vdot: float = required_param("kg", "sway added mass derivative")
    Y_rdot: float = required_param("kg m", "sway-yaw added mass derivative")
    N_vdot: float = required_param("kg m", "yaw-sway added mass derivative")
    N_rdot: float = required_param("kg m^2", "yaw added inertia derivative")
    X_u: float = required_param("N s/m", "linear surge damping derivative")
    Y_v: float = required_param("N s/m", "linear sway damping derivative")
    Y_r: float = required_param("N s", "linear sway-yaw damping derivative")
    N_v: float = required_param("N s", "linear yaw-sway damping derivative")
    N_r: float = required_param("N m s", "linear yaw damping derivative")
    X_uu: float = required_param("N s^2/m^2", "quadratic surge damping derivative")
    Y_vv: float = required_param("N s^2/m^2", "quadratic sway damping derivative")
    N_rr: float = required_param("N m s^2", "quadratic yaw damping derivative")
    L_oa: float = required_param("m", "length over all")
    L_pp: float = required_param("m", "length between perpendiculars")
    B: float = required_param("m", "beam")
    T: float = required_param("m", "mean draught")

    def __post_init__(self) -> None:
        require_finite(self)
        require_positive(self, "m", "I_z", "L_oa", "L_pp", "B", "T")
        require_dimensions(self, "L_oa", "L_pp", "B", "T")


@dataclass(frozen=True)
class WindageParameters:
    """Projected wind areas of the hull above water, their centroid and the air density.

    Every field but the (vessel-neutral) air density must be given: load a vessel
    (``load_vessel("blue-lady").windage``) or use a named record such as
    :data:`BLUE_LADY_WINDAGE`.
    """

    A_F: float = required_param("m^2", "frontal projected wind area")
    A_L: float = required_param("m^2", "lateral projected wind area")
    s_L: float = required_param("m", "longitudinal centroid of A_L, forward of midship")
    L_oa: float = required_param("m", "length over all")
    coefficients: str = required_param("-", "Blendermann (1994) ship type of the coefficients")
    rho_a: float = param(1.225, "kg/m^3", "ISA air density at 15 C")

    def __post_init__(self) -> None:
        require_finite(self)
        require_positive(self, "A_F", "A_L", "L_oa", "rho_a")
        require_dimensions(self, "L_oa")
        if not isinstance(self.coefficients, str):
            raise ValueError(
                f"coefficients must be a Blendermann ship type, got {self.coefficients!r}"
            )


#: The Blue Lady (1:24 VLCC model) hull: each value's unit and source in its comment.
BLUE_LADY_HULL = HullParameters(
    name="Blue Lady (1:24 VLCC model)",
    m=22934.4,  # kg; Tomera (2014) eq. 49: M11 - (-X_udot) = 23664.9 - 730.5
    I_z=455182.1,  # kg m^2; Tomera (2014) eq. 49: M33 (N_rdot = 0, lumped)
    x_g=0.0,  # m; Tomera (2014) Table 1: nominal x_G = 0
    X_udot=-730.5,  # kg; Tomera (2014) Table 2
    # kg; Tomera (2014) Table 2 prints -1896.20: read as -18962.0 (a decimal place lost, as
    # in k1 and k2); Clarke et al. (1983) give -18936
    Y_vdot=-18962.0,
    Y_rdot=-18351.9,  # kg m; Tomera (2014) Table 2
    # kg m; Tomera (2014) Table 2 prints 0; set equal to Y_rdot because potential-flow added
    # mass is symmetric (Clarke et al. 1983 give -Y_rdot ~ 19 700, -N_vdot ~ 17 000)
    N_vdot=-18351.9,
    N_rdot=0.0,  # kg m^2; Tomera (2014) Table 2 (added inertia lumped into I_z)
    X_u=-21.1,  # N s/m; Tomera (2014) Table 2 at u0 = 0.1 m/s
    Y_v=-259.8,  # N s/m; Tomera (2014) Table 2 at u0 = 0.1 m/s
    Y_r=-855.4,  # N s; Tomera (2014) Table 2 at u0 = 0.1 m/s
    N_v=-855.4,  # N s; Tomera (2014) Table 2 at u0 = 0.1 m/s
    N_r=-6130.5,  # N m s; Tomera (2014) Table 2 at u0 = 0.1 m/s
    X_uu=-70.0,  # N s^2/m^2; estimate: ITTC-57 + form factor; Van Berlekom & Goddard -64..-81
    Y_vv=-4200.0,  # N s^2/m^2; estimate: Hoerner (1965) cross-flow -4320, VB & G -4080
    N_rr=-3.3e5,  # N m s^2; estimate: cross-flow 0.5 rho T Cd L^4/32
    L_oa=13.78,  # m; Tomera (2014) Table 1
    L_pp=13.50,  # m; Tomera (2014) Table 1
    B=2.38,  # m; Tomera (2014) Table 1
    T=0.86,  # m; Tomera (2014) Table 1 (mean draught, full load)
)

#: The Blue Lady's windage (estimates of the project): unit and source in each comment.
BLUE_LADY_WINDAGE = WindageParameters(
    A_F=1.9,  # m^2; estimate: OCIMF (1994) VLCC full scale scaled 1/576 (range 1.4-2.2)
    A_L=6.4,  # m^2; estimate: scaled lateral area (range 5.6-6.9)
    s_L=-1.1,  # m; estimate: centroid of A_L, -0.08 L_oa (aft house)
    L_oa=13.78,  # m; Tomera (2014) Table 1
    coefficients="tanker-loaded",  # Blendermann (1994) ship type: a loaded VLCC (a choice)
    rho_a=1.225,  # kg/m^3; ISA air density at 15 C
)
