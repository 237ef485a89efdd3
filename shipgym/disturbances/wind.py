r"""Wind: relative wind, Blendermann (1994) loads and Gauss-Markov gusts.

Relative wind (Fossen 2011 ch. 8.1); ``X = q CX(gamma) A_F``, ``Y = q CY(gamma) A_L``,
``N = q CN(gamma) A_L L_oa``, ``q = 0.5 rho_a V_rw^2`` (Blendermann 1994).

Sources: Fossen (2011) ch. 8.1 (relative wind), Blendermann (1994) (loads), Harris (1971)
and ISO 19901-1 (2015) (gust spectra). Full entries: ``docs/references.md``.

Public names: ``BlendermannCoefficients``, ``BLENDERMANN``, ``blendermann``,
``blendermann_coefficients``, ``relative_wind``, ``wind_load``, ``WindLoad``, ``WindConfig``, ...

Design notes: docs/design/disturbances.wind.md.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import (
    from_mapping,
    is_real,
    param,
    require_angles,
    require_finite,
    require_positive,
)
from shipgym._jit import njit
from shipgym._text import did_you_mean
from shipgym.dynamics.params import WindageParameters

from ._boundary import coerce_config, parse_config
from ._grid import CHUNK, GridPair, gauss_markov_piece
from .spectra import (
    HARMONIC_BLOCK,
    harmonic_bins,
    harmonic_components,
    harmonic_sums,
    harmonic_table,
    wind_gust_spectrum,
)

__all__ = [
    "BlendermannCoefficients",
    "BLENDERMANN",
    "blendermann",
    "blendermann_coefficients",
    "relative_wind",
    "wind_load",
    "WindLoad",
    "WindConfig",
    "Wind",
    "GUST_SPECTRA",
    "MAX_WIND_SPEED",
]

#: Largest accepted mean wind speed and gust standard deviation (m/s). Basis: 70 m/s
#: (137 kn) is where category 5, the top of the Saffir-Simpson hurricane wind scale (NOAA
#: National Hurricane Center), begins; a mean wind above it is far outside ship handling and
#: dynamic positioning, and outside the range of Blendermann's (1994) wind-tunnel data. A
#: larger number is a unit mistake (km/h, kn) or a typo, so it is refused, not simulated.
MAX_WIND_SPEED = 70.0

#: Valid ``WindConfig.gust_spectrum`` values.
GUST_SPECTRA = ("gauss-markov", "npd", "harris")

_PI = math.pi
_HALF_PI = 0.5 * math.pi
_TWO_PI = 2.0 * math.pi
#: Slope of Blendermann's yaw-moment arm, 1/rad (Blendermann 1994).
_CN_SLOPE = 0.18

_BSRC = "Blendermann (1994), as in MSS blendermann94.m"


def _require_real(obj: Any, *names: str) -> None:
    for name in names:
        val = getattr(obj, name)
        if not is_real(val):
            raise ValueError(
                f"{type(obj).__name__}.{name} must be a real number, got {val!r} "
                f"({type(val).__name__})"
            )


# ---------------------------------------------------------------------------------------------
# Coefficient tables
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BlendermannCoefficients:
    """One row of Blendermann's (1994) wind-load parameter table (dimensionless).

    Source: W. Blendermann (1994), "Parameter identification of wind loads on ships",
    J. Wind Eng. Ind. Aerodyn. 51, 339-351; table as in Fossen (2011, ch. 8.1) and
    ``cybergalactic/MSS : LIBRARY/environment/blendermann94.m``.

    Attributes:
        CD_t: Transverse drag coefficient (beam wind), 1.
        CD_lAF0: Longitudinal drag coefficient for head wind, based on the frontal area, 1.
        CD_lAFpi: Longitudinal drag coefficient for following wind, frontal area based, 1.
        delta: Cross-force parameter, 1 (``0 <= delta < 2`` keeps the denominator positive).
        kappa: Rolling-moment factor, 1 (roll is not used by the 3-DOF model; kept for
            completeness).
    """

    CD_t: float = param(0.70, "1", _BSRC)
    CD_lAF0: float = param(0.90, "1", _BSRC)
    CD_lAFpi: float = param(0.55, "1", _BSRC)
    delta: float = param(0.40, "1", _BSRC)
    kappa: float = param(3.1, "1", _BSRC)

    def __post_init__(self) -> None:
        _require_real(self, "CD_t", "CD_lAF0", "CD_lAFpi", "delta", "kappa")
        require_finite(self)
        require_positive(self, "CD_t", "CD_lAF0", "CD_lAFpi")
        if not 0.0 <= self.delta < 2.0:
            raise ValueError(
                f"BlendermannCoefficients.delta must be in [0, 2) so that the Blendermann "
                f"denominator stays positive, got {self.delta!r}"
            )


_b = BlendermannCoefficients  # short alias for the table below (positional fields)


#: Blendermann (1994) rows by name: (CD_t, CD_lAF(0), CD_lAF(pi), delta, kappa). All 17 vessel
#: types of ``cybergalactic/MSS : LIBRARY/environment/blendermann94.m`` (BDATA), cross-checked
#: against ``mika-s/pyMarineCybernetics : util/wind/wind_coefficients.py`` (same values except
#: its typo kappa "1,4" for the container ship and 0.92 instead of 0.925 for the drilling
#: vessel, whose CD_lAF values are the mid-points of Blendermann's ranges 0.70-1.00 and
#: 0.75-1.10). A vessel names its type in its windage (the Blue Lady: "tanker-loaded", a choice).
BLENDERMANN: dict[str, BlendermannCoefficients] = {
    "car-carrier": _b(0.95, 0.55, 0.60, 0.80, 1.2),
    "cargo-loaded": _b(0.85, 0.65, 0.55, 0.40, 1.7),
    "cargo-container-on-deck": _b(0.85, 0.55, 0.50, 0.40, 1.4),
    "container-loaded": _b(0.90, 0.55, 0.55, 0.40, 1.4),
    "destroyer": _b(0.85, 0.60, 0.65, 0.65, 1.1),
    "diving-support": _b(0.90, 0.60, 0.80, 0.55, 1.7),
    "drilling": _b(1.00, 0.85, 0.925, 0.10, 1.7),
    "ferry": _b(0.90, 0.45, 0.50, 0.80, 1.1),
    "fishing": _b(0.95, 0.70, 0.70, 0.40, 1.1),
    "lng-tanker": _b(0.70, 0.60, 0.65, 0.50, 1.1),
    "offshore-supply": _b(0.90, 0.55, 0.80, 0.55, 1.2),
    "passenger-liner": _b(0.90, 0.40, 0.40, 0.80, 1.2),
    "research": _b(0.85, 0.55, 0.65, 0.60, 1.4),
    "speed-boat": _b(0.90, 0.55, 0.60, 0.60, 1.1),
    "tanker-loaded": _b(0.70, 0.90, 0.55, 0.40, 3.1),
    "tanker-ballast": _b(0.70, 0.75, 0.55, 0.40, 2.2),
    "tender": _b(0.85, 0.55, 0.55, 0.65, 1.1),
}


def blendermann(name: str) -> BlendermannCoefficients:
    """Look up a row of :data:`BLENDERMANN` by name.

    Args:
        name: Vessel type, e.g. ``"tanker-loaded"`` (the default for the Blue Lady).

    Returns:
        The coefficient row.

    Raises:
        ValueError: For an unknown name; the message lists the valid names.
    """
    try:
        return BLENDERMANN[name]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown Blendermann vessel type {name!r}{did_you_mean(name, BLENDERMANN)}; "
            "valid names are: "
            f"{', '.join(sorted(BLENDERMANN))}"
        ) from None


def _as_coeffs(coeffs: BlendermannCoefficients | str) -> BlendermannCoefficients:
    if isinstance(coeffs, BlendermannCoefficients):
        return coeffs
    return blendermann(coeffs)


# ---------------------------------------------------------------------------------------------
# The formulas, written once for floats (math) and arrays (numpy)
# ---------------------------------------------------------------------------------------------


class _Ops(NamedTuple):
    """The few elementary functions the formulas need: a math-like or numpy-like namespace."""

    cos: Any
    sin: Any
    sqrt: Any
    atan2: Any


_MATH = _Ops(math.cos, math.sin, math.sqrt, math.atan2)
_NUMPY = _Ops(np.cos, np.sin, np.sqrt, np.arctan2)


class _Consts(NamedTuple):
    """Constants of one (coefficient row, windage) pair, precomputed for the hot path."""

    cd_t: float  # CD_t
    cd_pi: float  # CD_lAF(pi)
    cd_jump: float  # CD_lAF(0) - CD_lAF(pi)
    half_delta: float  # delta / 2
    ratio: float  # (A_F / A_L) / CD_t, so that CD_l / CD_t = CD_lAF * ratio
    arm0: float  # s_L / L_oa
    kx: float  # 0.5 rho_a A_F
    ky: float  # 0.5 rho_a A_L
    kn: float  # 0.5 rho_a A_L L_oa


def _need_windage(windage: WindageParameters | None, where: str) -> WindageParameters:
    """``windage`` itself; a ``TypeError`` saying what to pass when it is missing."""
    if windage is None:
        raise TypeError(
            f"{where} needs the vessel's windage: pass windage=..., e.g. "
            "load_vessel('blue-lady').windage"
        )
    if not isinstance(windage, WindageParameters):
        raise TypeError(f"windage must be WindageParameters, got {type(windage).__name__}")
    return windage


def _consts(coeffs: BlendermannCoefficients, windage: WindageParameters) -> _Consts:
    half_rho = 0.5 * windage.rho_a
    return _Consts(
        cd_t=coeffs.CD_t,
        cd_pi=coeffs.CD_lAFpi,
        cd_jump=coeffs.CD_lAF0 - coeffs.CD_lAFpi,
        half_delta=0.5 * coeffs.delta,
        ratio=windage.A_F / windage.A_L / coeffs.CD_t,
        arm0=windage.s_L / windage.L_oa,
        kx=half_rho * windage.A_F,
        ky=half_rho * windage.A_L,
        kn=half_rho * windage.A_L * windage.L_oa,
    )


def _coefficients(k: _Consts, c: Any, s: Any, g: Any) -> tuple[Any, Any, Any]:
    """Blendermann CX, CY, CN from ``c = cos(gamma)``, ``s = sin(gamma)``, ``g = |gamma|``.

    Pure arithmetic (no function calls), so it works unchanged on floats and arrays. CX depends
    on ``c`` and ``g`` only (even in gamma); CY and CN are proportional to ``s`` (odd).
    """
    cd_t, cd_pi, cd_jump, half_delta, ratio, arm0, _, _, _ = k  # (tuple unpacking is fast)
    cd_laf = cd_pi + cd_jump * (g <= _HALF_PI)  # piecewise CD_lAF without if/else
    cs = c * s
    den = 1.0 - half_delta * (1.0 - cd_laf * ratio) * (4.0 * cs * cs)  # sin^2(2g)
    cy = cd_t * s / den
    return -cd_laf * c / den, cy, (arm0 - _CN_SLOPE * (g - _HALF_PI)) * cy


def _relative(ops: _Ops, psi: Any, u: Any, v: Any, V_w: Any, beta_w: Any) -> tuple[Any, Any]:
    """Body-frame relative wind ``(u_rw, v_rw)`` (m/s), Fossen (2011) ch. 8.1."""
    cos, sin, _, _ = ops
    ang = beta_w - _PI - psi
    return u - V_w * cos(ang), v - V_w * sin(ang)


def _loads(
    ops: _Ops, k: _Consts, psi: Any, u: Any, v: Any, V_w: Any, beta_w: Any
) -> tuple[Any, Any, Any]:
    """Wind loads ``(X, Y, N)`` in N, N, N m on the body axes."""
    u_rw, v_rw = _relative(ops, psi, u, v, V_w, beta_w)
    v2 = u_rw * u_rw + v_rw * v_rw
    _, _, sqrt, atan2 = ops
    vr = sqrt(v2)
    g = atan2(abs(v_rw), u_rw)  # |gamma_rw| in [0, pi]; exactly pi for a following wind
    inv = 1.0 / (vr + (vr == 0.0))  # cos/sin from the components; 0/1 when there is no wind
    cx, cy, cn = _coefficients(k, u_rw * inv, -v_rw * inv, g)
    _, _, _, _, _, _, kx, ky, kn = k
    return kx * v2 * cx, ky * v2 * cy, kn * v2 * cn


# ---------------------------------------------------------------------------------------------
# Public load API
# ---------------------------------------------------------------------------------------------


def blendermann_coefficients(
    gamma: ArrayLike,
    coeffs: BlendermannCoefficients | str | None = None,
    windage: WindageParameters | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Blendermann (1994) wind coefficients, folded to both sides.

    Args:
        gamma: Relative wind angle of attack gamma_rw (rad), any shape; 0 = head wind,
            -pi/2 = wind from starboard. Any real value (it is wrapped to (-pi, pi]).
        coeffs: A :class:`BlendermannCoefficients` row or its name in :data:`BLENDERMANN`;
            ``None``: the ship type of ``windage`` (``windage.coefficients``).
        windage: Projected areas (A_F, A_L in m^2), centroid s_L (m) and L_oa (m); required
            (e.g. ``load_vessel("blue-lady").windage``).

    Returns:
        ``(CX, CY, CN)``, dimensionless arrays of the shape of ``gamma``. CX is even in gamma,
        CY and CN are odd; ``CY = CN = 0`` exactly at ``gamma = 0`` and ``gamma = pi``.
    """
    w = _need_windage(windage, "blendermann_coefficients()")
    k = _consts(_as_coeffs(w.coefficients if coeffs is None else coeffs), w)
    g = np.asarray(gamma, dtype=float)
    g = _PI - np.mod(_PI - g, _TWO_PI)  # (-pi, pi]
    ga = np.abs(g)
    s = np.copysign(np.sin(np.minimum(ga, _PI - ga)), g)  # exact zeros at 0 and pi
    cx, cy, cn = _coefficients(k, np.cos(g), s, ga)
    return np.asarray(cx, dtype=float), np.asarray(cy, dtype=float), np.asarray(cn, dtype=float)


def relative_wind(
    psi: ArrayLike, u: ArrayLike, v: ArrayLike, V_w: ArrayLike, beta_w: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Relative wind in body axes (Fossen 2011, ch. 8.1).

    Args:
        psi: Heading (rad), clockwise from north.
        u: Surge velocity over ground (m/s).
        v: Sway velocity over ground (m/s).
        V_w: True wind speed (m/s).
        beta_w: True wind direction, where the wind comes from (rad, clockwise from north).

    Returns:
        ``(u_rw, v_rw, V_rw, gamma_rw)`` broadcast arrays: relative velocity of the ship
        through the air (m/s), its magnitude (m/s) and the angle of attack
        ``gamma_rw = -atan2(v_rw, u_rw)`` in (-pi, pi] (rad, 0 = head wind).
    """
    u_rw, v_rw = _relative(*_as_arrays(psi, u, v, V_w, beta_w, ops=_NUMPY))
    gamma = -np.arctan2(v_rw, u_rw)
    gamma = np.where(gamma <= -_PI, _PI, gamma)
    return u_rw, v_rw, np.hypot(u_rw, v_rw), gamma


def _as_arrays(*args: ArrayLike, ops: _Ops) -> tuple[Any, ...]:
    arrs = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in args))
    return (ops, *arrs)


def wind_load(
    psi: ArrayLike,
    u: ArrayLike,
    v: ArrayLike,
    V_w: ArrayLike,
    beta_w: ArrayLike,
    coeffs: BlendermannCoefficients | str | None = None,
    windage: WindageParameters | None = None,
) -> NDArray[np.float64]:
    """Blendermann wind loads on the body axes for any broadcastable batch of inputs.

    Args:
        psi: Heading (rad), clockwise from north.
        u: Surge velocity over ground (m/s).
        v: Sway velocity over ground (m/s).
        V_w: True wind speed (m/s).
        beta_w: True wind direction, where the wind comes from (rad).
        coeffs: A :class:`BlendermannCoefficients` row or its name in :data:`BLENDERMANN`;
            ``None``: the ship type of ``windage``.
        windage: Projected areas and air density (:class:`WindageParameters`); required
            (e.g. ``load_vessel("blue-lady").windage``).

    Returns:
        Array of shape ``broadcast_shape + (3,)`` holding ``[X, Y, N]`` in N, N, N m.
    """
    return WindLoad(coeffs, windage).array(psi, u, v, V_w, beta_w)


@njit
def blendermann_load(k, psi, u, v, V_w, beta_w):  # type: ignore[no-untyped-def]
    """The Blendermann (1994) load ``(X, Y, N)`` (N, N, N m, body) on a hull with heading
    ``psi`` (rad) moving at ``(u, v)`` (m/s, over ground) in a true wind of speed ``V_w`` (m/s)
    from ``beta_w`` (rad), with the constants ``k`` of :meth:`WindLoad.kernel_constants`: the
    run-time form (compiled) of :func:`_loads`, which stays the array form and the oracle."""
    cd_t, cd_pi, cd_0, half_delta, ratio, arm0 = k[0], k[1], k[2], k[3], k[4], k[5]
    kx, ky, kn, pi, half_pi, slope = k[6], k[7], k[8], k[9], k[10], k[11]
    ang = beta_w - pi - psi
    u_rw = u - V_w * math.cos(ang)
    v_rw = v - V_w * math.sin(ang)
    v2 = u_rw * u_rw + v_rw * v_rw
    vr = math.sqrt(v2)
    g = math.atan2(abs(v_rw), u_rw)
    inv = 1.0 / vr if vr != 0.0 else 1.0
    c = u_rw * inv
    s = -v_rw * inv
    cd_laf = cd_0 if g <= half_pi else cd_pi
    cs = c * s
    den = 1.0 - half_delta * (1.0 - cd_laf * ratio) * (4.0 * cs * cs)
    cy = cd_t * s / den
    return (
        kx * v2 * (-cd_laf * c / den),
        ky * v2 * cy,
        kn * v2 * ((arm0 - slope * (g - half_pi)) * cy),
    )


class WindLoad:
    """Blendermann wind loads for one vessel (the physics step evaluates them compiled:
    :func:`blendermann_load` with :meth:`kernel_constants`).

    Args:
        coeffs: A :class:`BlendermannCoefficients` row or its name in :data:`BLENDERMANN`;
            ``None``: the ship type of ``windage``.
        windage: Projected areas, centroid and air density (:class:`WindageParameters`);
            required (e.g. ``load_vessel("blue-lady").windage``).

    Example:
        >>> from shipgym.dynamics import BLUE_LADY_WINDAGE
        >>> wl = WindLoad("tanker-loaded", BLUE_LADY_WINDAGE)
        >>> X, Y, N = wl(0.0, 0.0, 0.0, 3.0, math.pi / 2)  # 3 m/s from the east (starboard)
        >>> round(Y, 1), round(N, 1)
        (-24.7, 27.2)
    """

    __slots__ = ("coeffs", "windage", "_k")

    def __init__(
        self,
        coeffs: BlendermannCoefficients | str | None = None,
        windage: WindageParameters | None = None,
    ) -> None:
        windage = _need_windage(windage, "WindLoad()")
        self.coeffs = _as_coeffs(windage.coefficients if coeffs is None else coeffs)
        self.windage = windage
        self._k = _consts(self.coeffs, windage)

    def __call__(
        self, psi: float, u: float, v: float, V_w: float, beta_w: float
    ) -> tuple[float, float, float]:
        """Loads ``(X, Y, N)`` (N, N, N m) for scalar inputs, computed with :mod:`math`.

        Args:
            psi: Heading (rad).
            u: Surge velocity over ground (m/s).
            v: Sway velocity over ground (m/s).
            V_w: True wind speed (m/s).
            beta_w: Direction the wind comes from (rad).

        Returns:
            A tuple of three Python floats.
        """
        return _loads(_MATH, self._k, float(psi), float(u), float(v), float(V_w), float(beta_w))

    def kernel_constants(self) -> tuple[float, ...]:
        """The 12 constants of :func:`blendermann_load`, in its order: ``CD_t, CD_lAF(pi),
        CD_lAF(0), delta/2, the area ratio, the moment arm at 90 deg, the X, Y, N factors,
        pi, pi/2`` and the moment arm's slope."""
        cd_t, cd_pi, cd_jump, half_delta, ratio, arm0, kx, ky, kn = self._k
        cd_0 = cd_pi + cd_jump  # CD_lAF on the bow side, cd_pi + cd_jump * True in _coefficients
        return (float(cd_t), float(cd_pi), float(cd_0), float(half_delta), float(ratio),
                float(arm0), float(kx), float(ky), float(kn), _PI, _HALF_PI, _CN_SLOPE)  # fmt: skip

    def array(
        self, psi: ArrayLike, u: ArrayLike, v: ArrayLike, V_w: ArrayLike, beta_w: ArrayLike
    ) -> NDArray[np.float64]:
        """Loads for broadcastable arrays: shape ``broadcast_shape + (3,)``, ``[X, Y, N]``."""
        ops, *a = _as_arrays(psi, u, v, V_w, beta_w, ops=_NUMPY)
        x, y, n = _loads(ops, self._k, *a)
        return np.stack(np.broadcast_arrays(x, y, n), axis=-1)

    def __repr__(self) -> str:
        return f"WindLoad(coeffs={self.coeffs!r}, windage={self.windage!r})"


# ---------------------------------------------------------------------------------------------
# Gusts
# ---------------------------------------------------------------------------------------------

_NOTES17 = "default lake gust model (a modelling assumption)"


@dataclass(frozen=True)
class WindConfig:
    """Mean wind plus gusts in speed and direction.

    ``V_w(t) = speed + g_V(t)``, ``beta_w(t) = direction_from + g_beta(t)``, with ``g_V`` and
    ``g_beta`` independent stationary Ornstein-Uhlenbeck processes of standard deviations
    ``gust_std``, ``direction_std`` and time constants ``gust_time_constant``,
    ``direction_time_constant``. The fields are SI units and radians; at the public boundary
    directions are degrees: :meth:`parse` (``"3@300"``: 3 m/s from 300 deg),
    :meth:`from_speed_dir` and :meth:`coerce` (the one conversion every entry point uses).

    With ``gust_spectrum = "npd"`` or ``"harris"`` the speed gust ``g_V`` is instead a sum of
    ``gust_components`` harmonics on logarithmic bins over ``[gust_f_min, gust_f_max]`` with
    random phases and random frequencies within the bins; the spectrum is
    evaluated at full scale for ``U10 = speed sqrt(spectrum_scale)`` and mapped to the simulated
    scale (:func:`~shipgym.disturbances.spectra.wind_gust_spectrum`). ``gust_time_constant`` is
    then unused and ``gust_std`` (when given) rescales the spectrum to that standard deviation.

    Attributes:
        speed: Mean wind speed (m/s, 0 to :data:`MAX_WIND_SPEED`), real wind at the model
            (lake: 0-5 m/s).
        direction_from: Mean direction the wind comes FROM (rad, clockwise from north).
        gust_std: Standard deviation of the speed gust (m/s); ``None`` means
            ``0.15 * speed`` (a modelling assumption).
        gust_time_constant: Correlation time of the speed gust (s, model time).
        direction_std: Standard deviation of the direction gust (rad).
        direction_time_constant: Correlation time of the direction gust (s).
        sample_period: Grid on which gust samples are drawn (s); values in between are
            linearly interpolated in time.
        coefficients: Name of the Blendermann row in :data:`BLENDERMANN`; ``None`` (default):
            the vessel's ship type (:attr:`WindageParameters.coefficients`).
        gust_spectrum: ``"gauss-markov"`` (default), ``"npd"`` or ``"harris"``.
        spectrum_scale: Froude scale ``lambda`` between the spectrum (full scale, 10 m) and the
            simulation (1: real wind; 24: a full-scale offshore wind on the 1:24 model).
        gust_components: Number of harmonics of a spectral gust (1-5000).
        gust_f_min: Lowest gust frequency (Hz, simulated time); ``None``: 1/3600 Hz full
            scale (the 1-hour mean of the NPD spectrum) for ``"npd"``, 0.01 Hz full scale (the
            validity limit of the Harris spectrum) for ``"harris"``, times ``sqrt(lambda)``.
        gust_f_max: Highest gust frequency (Hz, simulated time); ``None``: the smaller of
            1 Hz full scale (times ``sqrt(lambda)``) and ``0.25 / sample_period``.
    """

    speed: float = param(
        0.0, "m/s", "assumption: 0 nominal, 3 'moderate' (Tomera 2014 trial: 3 m/s from 300 deg)"
    )
    direction_from: float = param(0.0, "rad", "meteorological, clockwise from north")
    gust_std: float | None = param(None, "m/s", "assumption: None -> 0.15 * speed")
    gust_time_constant: float = param(5.0, "s", _NOTES17)
    direction_std: float = param(math.radians(10.0), "rad", _NOTES17 + ": 10 deg")
    direction_time_constant: float = param(20.0, "s", _NOTES17)
    sample_period: float = param(0.1, "s", "gust sample grid, linear interpolation [assumption]")
    coefficients: str | None = param(
        None, "-", "Blendermann (1994) row; None: the vessel's (WindageParameters.coefficients)"
    )
    gust_spectrum: str = param("gauss-markov", "-", "GM default (assumption); npd, harris")
    spectrum_scale: float = param(1.0, "1", "Froude scale of the gust spectrum")
    gust_components: int = param(200, "-", "harmonics of a spectral gust [assumption]")
    gust_f_min: float | None = param(None, "Hz", "None: 1/3600 Hz (npd), 0.01 Hz (harris) FS")
    gust_f_max: float | None = param(None, "Hz", "None: min(1 Hz FS, 0.25/sample_period)")

    def __post_init__(self) -> None:
        _require_real(
            self,
            "speed",
            "direction_from",
            "gust_time_constant",
            "direction_std",
            "direction_time_constant",
            "sample_period",
        )
        if self.gust_std is not None:
            _require_real(self, "gust_std")
        require_finite(self)
        require_angles(self, "direction_from")
        if self.speed < 0:
            raise ValueError(
                f"WindConfig.speed must be >= 0 (m/s), got {self.speed!r}; give the direction "
                "with direction_from instead of a negative speed"
            )
        for name in ("speed", "gust_std"):
            val = getattr(self, name)
            if val is not None and val > MAX_WIND_SPEED:
                raise ValueError(
                    f"WindConfig.{name} must be <= {MAX_WIND_SPEED:g} m/s (the start of "
                    f"category 5 of the Saffir-Simpson hurricane scale), got {val!r}"
                )
        for name in ("gust_std", "direction_std"):
            val = getattr(self, name)
            if val is not None and val < 0:
                raise ValueError(f"WindConfig.{name} must be >= 0, got {val!r}")
        require_positive(self, "gust_time_constant", "direction_time_constant", "sample_period")
        if self.coefficients is not None and (
            not isinstance(self.coefficients, str) or self.coefficients not in BLENDERMANN
        ):
            raise ValueError(
                f"WindConfig.coefficients: unknown Blendermann vessel type "
                f"{self.coefficients!r}{did_you_mean(self.coefficients, BLENDERMANN)}; valid "
                f"names are: {', '.join(sorted(BLENDERMANN))}"
            )
        if self.gust_spectrum not in GUST_SPECTRA:
            raise ValueError(
                f"WindConfig.gust_spectrum must be one of {', '.join(GUST_SPECTRA)}, "
                f"got {self.gust_spectrum!r}"
            )
        _require_real(self, "spectrum_scale")
        require_positive(self, "spectrum_scale")
        n = self.gust_components
        if not isinstance(n, int) or isinstance(n, bool) or not 1 <= n <= 5000:
            raise ValueError(f"WindConfig.gust_components must be an int in [1, 5000], got {n!r}")
        for name in ("gust_f_min", "gust_f_max"):
            if getattr(self, name) is not None:
                _require_real(self, name)
                if not getattr(self, name) > 0:
                    raise ValueError(
                        f"WindConfig.{name} must be > 0 Hz or None, got {getattr(self, name)!r}"
                    )
        lo, hi = self.gust_band
        if not lo < hi:
            raise ValueError(
                f"WindConfig: gust_f_min must be < gust_f_max, got [{lo!r}, {hi!r}] Hz"
            )
        nyquist = 0.5 / self.sample_period
        if self.gust_f_max is not None and self.gust_f_max > nyquist:
            raise ValueError(
                f"WindConfig.gust_f_max ({self.gust_f_max!r} Hz) must be <= the Nyquist "
                f"frequency 0.5 / sample_period = {nyquist:.4g} Hz"
            )

    @property
    def is_spectral(self) -> bool:
        """True for an NPD or Harris speed gust (harmonic superposition)."""
        return self.gust_spectrum != "gauss-markov"

    @property
    def gust_band(self) -> tuple[float, float]:
        """``(f_min, f_max)`` of a spectral gust in Hz of simulated time (see the attributes)."""
        sq = math.sqrt(float(self.spectrum_scale))
        if self.gust_f_min is not None:
            lo = float(self.gust_f_min)
        else:
            lo = (0.01 if self.gust_spectrum == "harris" else 1.0 / 3600.0) * sq
        if self.gust_f_max is not None:
            hi = float(self.gust_f_max)
        else:
            hi = min(1.0 * sq, 0.25 / float(self.sample_period))
        return lo, hi

    def gust_psd(self, f: ArrayLike) -> NDArray[np.float64]:
        """One-sided PSD of the speed gust at frequencies ``f`` (Hz), (m/s)^2/Hz.

        For ``"gauss-markov"`` the Ornstein-Uhlenbeck PSD ``4 sigma^2 T / (1 + (2 pi f T)^2)``;
        for a spectral gust the (scaled) target spectrum inside ``gust_band`` and 0 outside.
        """
        ff = np.asarray(f, dtype=float)
        if not self.is_spectral:
            sig, T = self.gust_sigma, float(self.gust_time_constant)
            return 4.0 * sig * sig * T / (1.0 + (2.0 * math.pi * ff * T) ** 2)
        lo, hi = self.gust_band
        s = wind_gust_spectrum(
            self.gust_spectrum, ff, float(self.speed), float(self.spectrum_scale)
        )
        if self.gust_std is not None:
            var = self._band_variance
            s = s * (float(self.gust_std) ** 2 / var if var > 0 else 0.0)
        return np.where((ff >= lo * (1 - 1e-12)) & (ff <= hi * (1 + 1e-12)), s, 0.0)

    @functools.cached_property
    def _band_variance(self) -> float:
        """Variance of the unscaled spectral gust over ``gust_band`` ((m/s)^2, quadrature)."""
        lo, hi = self.gust_band
        f = np.geomspace(lo, hi, 4001)
        s = wind_gust_spectrum(self.gust_spectrum, f, float(self.speed), float(self.spectrum_scale))
        return float(np.trapezoid(s * f, np.log(f)))

    @property
    def gust_sigma(self) -> float:
        """Effective speed-gust standard deviation (m/s).

        ``gust_std`` when given; otherwise ``0.15 * speed`` for Gauss-Markov gusts and the
        spectrum's standard deviation over ``gust_band`` for NPD / Harris gusts.
        """
        if self.gust_std is not None:
            return float(self.gust_std)
        if self.is_spectral:
            return math.sqrt(self._band_variance)
        return 0.15 * float(self.speed)

    @property
    def is_constant(self) -> bool:
        """True when the wind never changes: no speed gust, and no direction gust or no wind."""
        return self.gust_sigma == 0.0 and (self.direction_std == 0.0 or self.speed == 0.0)

    @classmethod
    def from_speed_dir(
        cls,
        speed: float,
        from_deg: float,
        *,
        direction_std_deg: float | None = None,
        **kw: Any,
    ) -> WindConfig:
        """Build a config from a speed and a direction in degrees (the edge of the code).

        Args:
            speed: Mean wind speed (m/s).
            from_deg: Direction the wind comes from (deg, clockwise from north), e.g. 300.
            direction_std_deg: Direction gust standard deviation (deg); default 10 deg.
            **kw: Any other :class:`WindConfig` field (SI units, radians).

        Returns:
            The validated config.
        """
        if direction_std_deg is not None:
            if "direction_std" in kw:
                raise ValueError("give direction_std (rad) or direction_std_deg, not both")
            kw["direction_std"] = math.radians(direction_std_deg)
        return cls(speed=speed, direction_from=math.radians(from_deg), **kw)

    @classmethod
    def from_dict(cls, mapping: Mapping[str, Any]) -> WindConfig:
        """Build from a mapping of field names (SI units, radians); unknown keys raise."""
        return from_mapping(cls, mapping, where="wind config")

    @classmethod
    def parse(cls, text: str, *, name: str = "wind") -> WindConfig:
        """Parse ``"SPEED@FROM_DEG"``: speed in m/s, direction the wind comes FROM in degrees.

        ``"3@300"`` is 3 m/s from 300 deg (a north-westerly) with the default gusts, the same
        as ``WindConfig.from_speed_dir(3, 300)``.

        Args:
            text: The string.
            name: The argument's name in error messages.

        Raises:
            ValueError: Malformed text, or a value :class:`WindConfig` refuses (the message
                names ``name`` and the field).
        """
        return parse_config(
            text, from_deg=cls.from_speed_dir, name=name, form="SPEED@FROM_DEG",
            example="3@300 (3 m/s from 300 deg)",
        )  # fmt: skip

    @classmethod
    def coerce(cls, value: Any, *, name: str = "wind") -> WindConfig | None:
        """The one conversion of a user's wind setting, used by every public entry point.

        Accepted: ``None`` (no aerodynamic loads), a :class:`WindConfig`, ``"SPEED@FROM_DEG"``
        (:meth:`parse`), ``(speed m/s, from deg)`` (:meth:`from_speed_dir`) or a mapping of
        :class:`WindConfig` fields (SI units, radians; ``direction_from_deg`` and
        ``direction_std_deg`` are accepted as degree twins).

        Raises:
            ValueError: Any other form or an invalid value; the message names ``name`` and
                the accepted forms.
        """
        return coerce_config(
            cls,
            value,
            name=name,
            parse=lambda text: cls.parse(text, name=name),
            from_deg=cls.from_speed_dir,
            deg_fields={
                "direction_from_deg": "direction_from",
                "direction_std_deg": "direction_std",
            },
            accepted=(
                "None, a WindConfig, 'SPEED@FROM_DEG' (e.g. '3@300': 3 m/s from 300 deg), "
                "(speed m/s, from deg) or a mapping of WindConfig fields"
            ),
        )

    def label(self) -> str:
        """Short human-readable form, e.g. ``"3 m/s from 300 deg"``."""
        deg = math.degrees(float(self.direction_from)) % 360.0
        return f"{float(self.speed):g} m/s from {deg:.4g} deg"


#: Gust samples per chunk. Fixed (not a parameter) so that a realisation depends on the seed
#: and the config only.


class Wind(GridPair):
    """Time-varying wind and its loads on one vessel (Fossen 2011 ch. 8.1).

    Speed and direction gusts are first-order Gauss-Markov (Ornstein-Uhlenbeck) processes
    sampled on a fixed grid ``t_k = k * sample_period`` with the exact discretisation
    ``x[k+1] = a x[k] + sigma sqrt(1 - a^2) w[k]``, ``a = exp(-sample_period / T)``,
    ``w[k] ~ N(0, 1)``, started from the stationary distribution ``x[0] ~ N(0, sigma^2)``.
    Between grid points the wind is linearly interpolated in time. Samples are generated
    lazily in chunks of 4096, always in time order from ``t = 0``, so the realisation depends
    only on the generator and the config, never on the pattern of queries; memory is about
    16 bytes per sample (~0.6 MB per simulated hour at 0.1 s).

    The speed is clipped at 0 after interpolation (``V_w >= 0``); with the default
    ``gust_std = 0.15 speed`` a negative excursion is a 6.7-sigma event, so the clip does not
    bias the statistics in practice. The direction is *not* wrapped: it stays continuous around
    ``direction_from`` so that it never jumps.

    A spectral speed gust (``gust_spectrum`` ``"npd"`` / ``"harris"``) is evaluated on the same
    grid as ``sum_j a_j cos(2 pi f_j t_k + phi_j)`` (components drawn at :meth:`reset`, chunks
    computed with :func:`~shipgym.disturbances.spectra.harmonic_sums`), so :meth:`at` costs the
    same; the direction gust stays Gauss-Markov.

    Args:
        config: Mean wind and gust parameters (default: calm, constant).
        windage: Projected areas and air density of the vessel; required (e.g.
            ``load_vessel("blue-lady").windage``).

    Example:
        >>> from shipgym.dynamics import load_vessel
        >>> w = Wind(WindConfig.from_speed_dir(3.0, 300.0), load_vessel("blue-lady").windage)
        >>> w.reset(np.random.default_rng(1))
        >>> V, beta = w.at(12.3)
        >>> X, Y, N = w.load(12.3, psi=0.0, u=0.5, v=0.0)
    """

    def __init__(
        self,
        config: WindConfig | None = None,
        windage: WindageParameters | None = None,
    ) -> None:
        windage = _need_windage(windage, "Wind()")
        self.config = WindConfig() if config is None else config
        self.windage = windage
        self.loads = WindLoad(self.config.coefficients or windage.coefficients, windage)
        cfg = self.config
        self._dt = float(cfg.sample_period)
        self._inv_dt = 1.0 / self._dt
        self._mean_v = float(cfg.speed)
        self._mean_b = float(cfg.direction_from)
        sig = (cfg.gust_sigma, float(cfg.direction_std))
        tau = (float(cfg.gust_time_constant), float(cfg.direction_time_constant))
        self._sigma = sig
        self._a = tuple(math.exp(-self._dt / t) for t in tau)
        # sigma sqrt(1 - a^2), computed without cancellation for dt << T
        self._b = tuple(
            s * math.sqrt(-math.expm1(-2.0 * self._dt / t)) for s, t in zip(sig, tau, strict=True)
        )
        self._const: tuple[float, float] | None = (
            (self._mean_v, self._mean_b) if cfg.is_constant else None
        )
        self._spectral = cfg.is_spectral and cfg.gust_sigma > 0.0
        if self._spectral:  # a piece's harmonic sums whole blocks (PieceGrid)
            self._LEAD = HARMONIC_BLOCK
        self._gw = self._ga = self._gph = np.zeros(0)
        self._bins: Any = None  # the spectral gust's harmonic_bins (computed at the first reset)
        self._table: Any = None
        self._clear()
        self._rng: np.random.Generator | None = None

    # -- state ------------------------------------------------------------------------------

    def _clear(self) -> None:
        super()._clear()  # chunks of shape (2, CHUNK + 1): [V, beta] rows
        self._state = (0.0, 0.0)  # gust state at the end of the last chunk

    @property
    def is_constant(self) -> bool:
        """True when the wind is exactly constant (no generator needed)."""
        return self._const is not None

    def reset(self, rng: np.random.Generator | int | None = None) -> None:
        """Start a new realisation.

        Everything is drawn from a child generator seeded with one ``integers(2**63)`` draw
        from ``rng``, so the same seed gives the same gusts. The draw is made even for a
        constant wind, so the parent's stream does not depend on the wind settings.

        Args:
            rng: Parent generator (or an integer seed). May be ``None`` only for a constant
                wind (``is_constant``).

        Raises:
            ValueError: If ``rng`` is ``None`` for a gusty wind.
        """
        self._draws(self._start(rng, "a gusty wind (gust_std or direction_std > 0)"))

    def _draws(self, child: np.random.Generator | None) -> None:
        """The gusts' start and (spectral) components from the reset's child generator."""
        if child is not None and self._const is None:
            z = child.standard_normal(2)
            self._state = (self._sigma[0] * float(z[0]), self._sigma[1] * float(z[1]))
            if self._spectral:
                cfg = self.config
                lo, hi = cfg.gust_band
                n = int(cfg.gust_components)
                if self._bins is None:  # the config's bins, the same at every reset
                    self._bins = harmonic_bins(cfg.gust_psd, lo, hi, n, log=True)
                f, a, ph = harmonic_components(
                    cfg.gust_psd, lo, hi, n, child, log=True, bins=self._bins
                )
                self._gw, self._ga, self._gph = 2.0 * math.pi * f, a, ph
                self._table: Any = None  # harmonic_table of the gust (at its first piece)

    def _ready_check(self) -> None:
        if self._rng is None:
            raise RuntimeError("call Wind.reset(rng) before querying a gusty wind")

    def _begin(self, j: int) -> NDArray[np.float64]:
        """Chunk ``j`` begun from the gust states at its start: its normals
        ``standard_normal((2, CHUNK))`` (the speed and direction gusts; a spectral speed gust:
        ``standard_normal((1, CHUNK))``, the direction's), the last row as far as read
        (:meth:`~shipgym.disturbances._grid.PieceGrid._normals`)."""
        assert self._rng is not None
        inf = math.inf
        if self._spectral:  # the direction gust only
            a, b, m = np.array(self._a[1:]), np.array(self._b[1:]), np.array([self._mean_b])
            x = np.array([self._state[1]])
        else:  # the deviation x_{k+1} = a x_k + b e_k of each channel about its mean
            m, a, b = np.array([self._mean_v, self._mean_b]), np.array(self._a), np.array(self._b)
            x = np.array(self._state)
        self._gm = (x, m, a, b, np.full(x.size, -inf), np.full(x.size, inf))
        self._e = self._normals(self._rng, (x.size, CHUNK), out=self._spent)  # the last chunk's
        self._spent = self._e
        return np.empty((2, CHUNK + 1))

    def _piece(self, j: int, ka: int, kb: int) -> None:
        """Samples ``ka ... kb - 1`` of chunk ``j``: the Gauss-Markov gusts' recursion
        (:func:`~shipgym.disturbances._grid.gauss_markov_piece`), a spectral speed gust's
        harmonic sum on the chunk's grid from ``t0 = j CHUNK dt``."""
        rows = self._chunk(j)
        x, m, a, b, lo, hi = self._gm
        self._draw_to(self._e, kb)
        if self._spectral:
            gauss_markov_piece(x, m, a, b, lo, hi, True, self._e, ka, kb, rows[1:])
            t0 = j * CHUNK * self._dt
            if self._table is None:
                self._table = harmonic_table(self._dt, self._gw)
            gust = harmonic_sums(
                t0, self._dt, kb - ka, self._gw, self._gph, self._ga, real=True, start=ka,
                table=self._table,
            )  # fmt: skip
            rows[0, ka:kb] = self._mean_v + gust
            if kb == CHUNK + 1:
                self._state = (0.0, float(x[0]))
        else:
            gauss_markov_piece(x, m, a, b, lo, hi, True, self._e, ka, kb, rows)
            if kb == CHUNK + 1:
                self._state = (float(x[0]), float(x[1]))

    # -- queries ----------------------------------------------------------------------------

    def at(self, t: float) -> tuple[float, float]:
        """True wind at simulation time ``t``.

        Args:
            t: Time (s), ``t >= 0``.

        Returns:
            ``(V_w, beta_w)``: speed (m/s, clipped at >= 0) and direction the wind comes from
            (rad, continuous, not wrapped).

        Raises:
            ValueError: For a negative or NaN time.
            RuntimeError: For a gusty wind that was never :meth:`reset`.
        """
        if self._const is not None:
            return self._const
        speed, beta = self._interp(t)
        return (speed if speed > 0.0 else 0.0), beta

    def load(self, t: float, psi: float, u: float, v: float) -> tuple[float, float, float]:
        """Wind loads on the body axes at time ``t`` (Blendermann, relative wind).

        Args:
            t: Time (s).
            psi: Heading (rad).
            u: Surge velocity over ground (m/s).
            v: Sway velocity over ground (m/s).

        Returns:
            ``(X, Y, N)`` in N, N, N m, Python floats.
        """
        V_w, beta_w = self.at(t)
        return self.loads(psi, u, v, V_w, beta_w)

    def series(self, t: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Wind speed and direction at many times (for plots and tests); same values as :meth:`at`.

        Args:
            t: Times (s), any shape, all ``>= 0``.

        Returns:
            ``(V_w, beta_w)`` arrays of the shape of ``t`` (m/s, rad).
        """
        tt = np.asarray(t, dtype=float)
        if self._const is not None:
            return np.full(tt.shape, self._const[0]), np.full(tt.shape, self._const[1])
        speed, beta = self._interp_series(tt)
        return np.maximum(speed, 0.0), beta

    def __repr__(self) -> str:
        return f"Wind(config={self.config!r}, windage={self.windage!r})"
