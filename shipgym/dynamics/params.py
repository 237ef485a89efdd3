"""Parameter sets of the Blue Lady, each field with its unit and source.

Sources: Tomera (2014), Tables 1-2, eqs. 8-12 and 49-50; the estimates of the richer plant
use Clarke et al. (1983), Van Berlekom & Goddard (1972), Hoerner (1965), ITTC-57 and
OCIMF (1994); values marked "assumption" or "estimate" are the project's own.
Full entries: ``docs/references.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

from shipgym._config import param, require_finite, require_positive

__all__ = ["HullParameters", "WindageParameters", "BLUE_LADY_HULL", "BLUE_LADY_WINDAGE"]

_T2 = "Tomera (2014) Table 2"


@dataclass(frozen=True)
class HullParameters:
    """Rigid-body, added-mass and damping parameters of a 3-DOF hull (Fossen sign convention).

    Hydrodynamic derivatives follow SNAME notation: added-mass derivatives ``X_udot`` etc. are
    negative, damping derivatives ``X_u`` etc. are negative for a stable hull.
    """

    name: str = "Blue Lady (1:24 VLCC model)"
    m: float = param(22934.4, "kg", "Tomera (2014) eq. 49: M11 - (-X_udot) = 23664.9 - 730.5")
    I_z: float = param(455182.1, "kg m^2", "Tomera (2014) eq. 49: M33 (N_rdot = 0, lumped)")
    x_g: float = param(0.0, "m", "Tomera (2014) Table 1: nominal x_G = 0")
    X_udot: float = param(-730.5, "kg", _T2)
    Y_vdot: float = param(-1896.2, "kg", _T2)
    Y_rdot: float = param(-18351.9, "kg m", _T2)
    N_vdot: float = param(
        -18351.9,
        "kg m",
        "Tomera (2014) Table 2 prints 0; set equal to Y_rdot because potential-flow added mass is "
        "symmetric (Clarke et al. 1983 give -Y_rdot ~ 19 700, -N_vdot ~ 17 000)",
    )
    N_rdot: float = param(0.0, "kg m^2", _T2 + " (added inertia lumped into I_z)")
    X_u: float = param(-21.1, "N s/m", _T2 + " at u0 = 0.1 m/s")
    Y_v: float = param(-259.8, "N s/m", _T2 + " at u0 = 0.1 m/s")
    Y_r: float = param(-855.4, "N s", _T2 + " at u0 = 0.1 m/s")
    N_v: float = param(-855.4, "N s", _T2 + " at u0 = 0.1 m/s")
    N_r: float = param(-6130.5, "N m s", _T2 + " at u0 = 0.1 m/s")
    X_uu: float = param(-70.0, "N s^2/m^2", "estimate: ITTC-57 + form factor; VB bis -64..-81")
    Y_vv: float = param(-4200.0, "N s^2/m^2", "estimate: Hoerner cross-flow -4320, VB bis -4080")
    N_rr: float = param(-3.3e5, "N m s^2", "estimate: cross-flow 0.5 rho T Cd L^4/32")
    L_oa: float = param(13.78, "m", "Tomera (2014) Table 1")
    L_pp: float = param(13.50, "m", "Tomera (2014) Table 1")
    B: float = param(2.38, "m", "Tomera (2014) Table 1")
    T: float = param(0.86, "m", "Tomera (2014) Table 1 (mean draught, full load)")

    def __post_init__(self) -> None:
        require_finite(self)
        require_positive(self, "m", "I_z", "L_oa", "L_pp", "B", "T")


@dataclass(frozen=True)
class WindageParameters:
    """Projected wind areas of the hull above water (estimates of the project)."""

    A_F: float = param(1.9, "m^2", "estimate: OCIMF VLCC full scale scaled 1/576 (range 1.4-2.2)")
    A_L: float = param(6.4, "m^2", "estimate: scaled lateral area (range 5.6-6.9)")
    s_L: float = param(-1.1, "m", "estimate: centroid of A_L, -0.08 L_oa (aft house)")
    L_oa: float = param(13.78, "m", "Tomera (2014) Table 1")
    rho_a: float = param(1.225, "kg/m^3", "ISA air density at 15 C")
    coefficients: str = param(
        "tanker-loaded", "-", "Blendermann (1994) ship type of the wind coefficients (a choice)"
    )

    def __post_init__(self) -> None:
        require_finite(self)
        require_positive(self, "A_F", "A_L", "L_oa", "rho_a")
        if not isinstance(self.coefficients, str):
            raise ValueError(
                f"coefficients must be a Blendermann ship type, got {self.coefficients!r}"
            )


BLUE_LADY_HULL = HullParameters()
BLUE_LADY_WINDAGE = WindageParameters()
