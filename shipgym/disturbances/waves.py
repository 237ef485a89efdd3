r"""Irregular long-crested waves: elevation, first-order (WF) motion and second-order drift.

``zeta(t) = sum_j A_j cos(w_j t + eps_j)``, ``A_j = sqrt(2 S(w_j) dw)`` (Fossen 2011
ch. 8.2); drift by Newman's (1974) approximation.

Sources: Pierson & Moskowitz (1964), Hasselmann et al. (1973), Fossen (2011) ch. 8.2,
Faltinsen (1990) ch. 5, Newman (1974); ``thesis`` = Al-Takie (1982), its high-frequency
model (ch. 2-3, App. 2). Full entries: ``docs/references.md``.

Public names: ``WAVE_SPECTRA``, ``WF_MODELS``, ``AL_TAKIE_HF_POLYNOMIALS``,
``al_takie_hf_peak_frequency``, ``al_takie_hf_polynomial``, ``WaveConfig``, ``Waves``,
``drift_coefficients``.

Design notes: docs/design/disturbances.waves.md.
"""

from __future__ import annotations

import copy
import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import from_mapping, is_real, param, require_angles, require_finite
from shipgym._jit import entry, njit
from shipgym._seeding import child_seeds
from shipgym.dynamics.params import HullParameters

from ._grid import CHUNK, PIECE, PieceGrid, load_windows
from .spectra import (
    HARMONIC_BLOCK,
    RHO_WATER,
    G,
    fit_shaping_filter_lambda,
    harmonic_bins,
    harmonic_components,
    harmonic_into,
    harmonic_table,
    wave_spectrum,
)

__all__ = [
    "WAVE_SPECTRA",
    "WF_MODELS",
    "AL_TAKIE_HF_POLYNOMIALS",
    "al_takie_hf_peak_frequency",
    "al_takie_hf_polynomial",
    "WaveConfig",
    "Waves",
    "drift_coefficients",
]

#: Valid ``WaveConfig.spectrum`` values.
WAVE_SPECTRA = ("jonswap", "pm", None)
#: Valid ``WaveConfig.wf_model`` values.
WF_MODELS = ("fossen", "al-takie", "rao")

#: Thesis Appendix 2 Table 1 (Wimpey Sealab, per-unit alpha_1..alpha_4) by Beaufort number; the
#: real-time polynomial is ``alpha_i / Tb`` with ``Tb = 3.104 s`` (Al-Takie 1982 App. 2).
_AL_TAKIE_ALPHA: dict[int, tuple[float, float, float, float]] = {
    5: (4.594, 4.384, 2.988, 1.470),
    6: (3.663, 2.698, 1.452, 0.556),
    7: (3.166, 2.119, 0.974, 0.341),
    8: (2.794, 1.789, 0.754, 0.251),
    9: (2.545, 1.353, 0.486, 0.131),
}
_AL_TAKIE_TB = 3.104

#: Real-time (full-scale, s^-i) coefficients ``(c1, c2, c3, c4)`` of Al-Takie's HF
#: denominator ``s^4 + c1 s^3 + c2 s^2 + c3 s + c4`` by Beaufort number (thesis App. 2).
AL_TAKIE_HF_POLYNOMIALS: dict[int, tuple[float, float, float, float]] = {
    bf: tuple(a / _AL_TAKIE_TB for a in alpha)  # type: ignore[misc]
    for bf, alpha in _AL_TAKIE_ALPHA.items()
}

_CHUNK = CHUNK


@njit
def wf_rows(x, k0, win, cb, sb, out):  # type: ignore[no-untyped-def]
    """First-order wave-frequency motion of N rows (one law for every N: the single and the
    batched physics): row ``i`` at the grid position ``x[i]`` (its time over the grid step;
    ``< 0``: no first-order motion, zeros), interpolated in its window ``win[i]`` (the HF
    position amplitude and heading rows of its chunk, from the sample ``k0[i]``), with the
    waves' direction cosines ``cb[i]``, ``sb[i]``, into ``out[i]`` ``(dx m, dy m, dpsi rad)``.
    A window holds the samples ``k0[i] ... k0[i] + W - 1`` (W = ``win.shape[2]``).

    Returns:
        -1, or the first row whose position lies outside its window (load its chunk, call
        again).
    """
    for i in range(x.shape[0]):
        xi = x[i]
        if xi < 0.0:
            out[i, 0] = 0.0
            out[i, 1] = 0.0
            out[i, 2] = 0.0
            continue
        k = int(xi)
        j = k - k0[i]
        if j < 0 or j >= win.shape[2] - 1:
            return i
        f = xi - k
        d0 = win[i, 0, j]
        d = d0 + f * (win[i, 0, j + 1] - d0)
        h0 = win[i, 1, j]
        out[i, 0] = d * cb[i]
        out[i, 1] = d * sb[i]
        out[i, 2] = h0 + f * (win[i, 1, j + 1] - h0)
    return -1


@njit(nogil=True)
def modal_filter_piece(lam, Gm, z, zi, s, ka, kb):  # type: ignore[no-untyped-def]
    """The WF filters' modal states over one chunk (the run-time form of
    :meth:`Waves._filter_piece`): for each mode ``i`` and DOF ``d`` the modal noise ``u_k =
    sum_j Gm[i, j] z[j, d, k]`` (the complex products with ``z + 0 i``, summed over ``j`` in
    order) and the exact discrete recursion ``s_k = lam_i s_{k-1} + u_k`` from the state
    ``zi[i, d] = lam_i s_{-1}``, into ``s`` (nf, 2, K) complex; only the samples ``ka ... kb -
    1``, from the states ``zi`` before ``ka``, left in ``zi`` after ``kb - 1`` (the recursion
    stopped and taken up again: the same floats). The float operations of
    ``scipy.signal.lfilter([1], [1, -lam_i], u, zi=zi)`` (direct form II transposed, as SciPy
    forms it for complex coefficients: ``a_0 = 1``, ``b = [1, 0]``), so the samples stay the
    same floats."""
    nf = lam.shape[0]
    # lfilter's normalised coefficients (a_0 = 1 + 0 i: |a_0|^2 = 1)
    a0r, a0i = 1.0, 0.0
    mag = a0r * a0r + a0i * a0i
    b0r = 1.0 * a0r + 0.0 * a0i
    b0i = 0.0 * a0r - 1.0 * a0i
    b1r = 0.0 * a0r + 0.0 * a0i
    b1i = 0.0 * a0r - 0.0 * a0i
    for i in range(nf):
        a1r = -lam[i].real
        a1i = -lam[i].imag
        tr = a1r * a0r + a1i * a0i
        ti = a1i * a0r - a1r * a0i
        for d in range(2):
            zr = zi[i, d].real
            zim = zi[i, d].imag
            for k in range(ka, kb):
                xr = 0.0
                xi = 0.0
                for j in range(nf):
                    g = Gm[i, j]
                    x = z[j, d, k]
                    xr += g.real * x - g.imag * 0.0
                    xi += g.real * 0.0 + g.imag * x
                yr = zr + (b0r * xr - b0i * xi) / mag
                yi = zim + (b0i * xr + b0r * xi) / mag
                zr = (b1r * xr - b1i * xi) / mag
                zim = (b1i * xr + b1r * xi) / mag
                zr -= (tr * yr - ti * yi) / mag
                zim -= (ti * yr + tr * yi) / mag
                s[i, d, k] = complex(yr, yi)
            zi[i, d] = complex(zr, zim)


class WaveMotionRows:
    """The first-order motion of N wave fields (``None``: none) at their own times, through
    :func:`wf_rows`, each field's current piece held in a window (:meth:`Waves.window`,
    loaded on first use)."""

    def __init__(self, waves: list[Any]) -> None:
        n = len(waves)
        self.waves = waves
        self.on = np.array([w is not None and w._wf_on for w in waves])
        self.k0 = np.full(n, -(1 << 62), dtype=np.int64)  # nothing loaded
        self.win = np.zeros((n, 2, PIECE + 1))
        self.inv_dt = np.array([w._inv_dt if w is not None else 0.0 for w in waves])
        self.cb = np.array([w._cb if w is not None else 0.0 for w in waves])
        self.sb = np.array([w._sb if w is not None else 0.0 for w in waves])
        self.out = np.zeros((n, 3))
        self._entry: Any = None

    def invalidate(self, i: int) -> None:
        """Field ``i`` drew a new realisation: its window is stale."""
        self.k0[i] = -(1 << 62)

    def __call__(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(dx, dy, dpsi)`` of every row at its time ``t`` (n,) (s, >= 0), (n, 3)."""
        x = np.where(self.on, t * self.inv_dt, -1.0)
        if not np.all((x >= 0.0) | ~self.on):
            raise ValueError(f"wave motion: times must be >= 0 s, got {t!r}")
        self.run(x)
        return self.out.copy()

    def run(self, x: NDArray[np.float64]) -> None:
        """:func:`wf_rows` at the grid positions ``x`` (n,) into :attr:`out`, each row's piece
        loaded where it is not in its window."""
        args = (x, self.k0, self.win, self.cb, self.sb, self.out)
        if self._entry is None:
            self._entry = entry(wf_rows, args)
        i = self._entry(*args)
        while i >= 0:
            # row i and every later row whose position is outside its window: loaded together
            # (load_windows: a batch in step computes its grids side by side)
            j = np.floor(x[i:]).astype(np.int64) - self.k0[i:]
            rows_ = (i + np.nonzero(self.on[i:] & ((j < 0) | (j >= PIECE)))[0]).tolist()
            got = load_windows([self.waves[r] for r in rows_], [int(x[r]) for r in rows_])
            for r, (k0, rows) in zip(rows_, got, strict=True):
                self.win[r] = rows[1:3]
                self.k0[r] = k0
            i = self._entry(*args)


_ZERO3 = (0.0, 0.0, 0.0)
_TWO_PI = 2.0 * math.pi


def al_takie_hf_polynomial(beaufort: int, peak_frequency: float | None = None) -> NDArray:
    """Denominator of Al-Takie's 4th-order HF wave filter ``K s^2 / den(s)`` (thesis App. 2).

    Args:
        beaufort: Beaufort number 5-9.
        peak_frequency: If given (rad/s), the frequency axis is rescaled (``c_i -> c_i r^i``)
            so that the peak of ``|s^2 / den(s)|`` falls on it; ``None`` keeps the thesis's
            full-scale real-time values (peak 0.806 rad/s at BF5 ... 0.436 rad/s at BF9).

    Returns:
        ``[1, c1, c2, c3, c4]`` (s^-i).
    """
    if isinstance(beaufort, bool) or beaufort not in AL_TAKIE_HF_POLYNOMIALS:
        raise ValueError(f"Al-Takie's HF filter exists for Beaufort 5-9 only, got {beaufort!r}")
    den = np.array([1.0, *AL_TAKIE_HF_POLYNOMIALS[beaufort]])
    if peak_frequency is None:
        return den
    r = float(peak_frequency) / al_takie_hf_peak_frequency(beaufort)
    return den * r ** np.arange(5)


def al_takie_hf_peak_frequency(beaufort: int) -> float:
    """Peak of ``|G(jw)|`` of Al-Takie's HF filter at the thesis's own, full-scale real-time
    frequencies (rad/s): 0.806 at BF5 (0.128 Hz) ... 0.436 at BF9 (0.069 Hz) (App. 2;
    to 5e-5 rad/s, the grid step).

    Args:
        beaufort: Beaufort number 5-9.
    """
    if isinstance(beaufort, bool) or beaufort not in AL_TAKIE_HF_POLYNOMIALS:
        raise ValueError(f"Al-Takie's HF filter exists for Beaufort 5-9 only, got {beaufort!r}")
    den = np.array([1.0, *AL_TAKIE_HF_POLYNOMIALS[beaufort]])
    w = np.linspace(0.05, 3.0, 60001)
    s = 1j * w
    return float(w[int(np.argmax(np.abs(s * s / np.polyval(den, s))))])


def drift_coefficients(
    hull: HullParameters,
    rho: float = RHO_WATER,
    g: float = G,
    side_fraction: float = 0.8,
) -> tuple[float, float]:
    """Maximum wall-sided drift coefficients ``(T_x0, T_y0)`` (Faltinsen 1990 ch. 5), N/m^2.

    ``T_x0 = (rho g / 2) (2/3) B`` (bow/stern as half-cylinders of radius ``B/2``),
    ``T_y0 = (rho g / 2) side_fraction L_pp`` (flat side). Multiply by ``zeta_a^2`` for regular
    waves or by ``sum A_j^2 = Hs^2 / 8`` for irregular ones: Blue Lady in beam seas,
    ``Hs = 0.05 m``: ``F_y = 16.6 N``; head seas 2.4 N (full reflection).

    Args:
        hull: Hull dimensions (``B``, ``L_pp`` in m).
        rho: Water density (kg/m^3).
        g: Gravity (m/s^2).
        side_fraction: Length of the parallel side over ``L_pp`` (1).

    Returns:
        ``(T_x0, T_y0)`` in N/m^2.
    """
    half = 0.5 * rho * g
    return half * (2.0 / 3.0) * hull.B, half * side_fraction * hull.L_pp


#: the largest significant wave height (m): well above the highest measured, 19 m (the WMO's
#: record, a North Atlantic buoy, 4 February 2013)
MAX_HS = 30.0


#: the longest peak period accepted (s): beyond any sea (long swell is about 25 s); a larger
#: value is a unit mistake
MAX_TP = 100.0


@dataclass(frozen=True)
class WaveConfig:
    """Sea state and wave-effect switches (SI units, radians).

    The default is the project's estimate of the lake / harbour sea (JONSWAP ``Hs = 0.05 m``,
    ``Tp = 1 s``, gamma 3.3, drift on, no first-order motion). Use ``Hs = 0`` or
    ``spectrum=None`` for calm water (every output exactly zero).

    Attributes:
        spectrum: ``"jonswap"``, ``"pm"`` (Pierson-Moskowitz) or ``None`` (no waves).
        Hs: Significant wave height (m), ``>= 0``.
        Tp: Peak period (s), ``> 0``.
        gamma: JONSWAP peak factor in [1, 10] (ignored for ``"pm"``).
        direction_from: Direction the waves come from (rad, clockwise from north).
        n_components: Number of harmonic components (1-5000).
        w_min: Lowest frequency (rad/s); ``None``: ``0.5 w_p``.
        w_max: Highest frequency (rad/s); ``None``: ``3.5 w_p``.
        drift: Apply the mean + slowly varying second-order drift loads.
        reflection: ``"kT"`` (``R = min(1, kT/2)^2`` per component), ``"full"`` (``R = 1``) or a
            constant factor in [0, 1].
        drift_gain: Extra factor on the drift loads (1; for calibration).
        drift_yaw_lever: Yaw lever ``l_N`` of the lateral drift force (m).
        first_order: Add first-order WF motion to the measured pose.
        wf_model: ``"fossen"``, ``"al-takie"`` or ``"rao"`` (see the module docstring).
        wf_position_std: Target std of the WF motion along the wave direction (m); ``None``:
            ``Hs / 16`` (assumed: 0.1-0.4 Hs/4 offshore).
        wf_heading_std: Target std of the WF heading motion (rad); ``None``:
            ``radians(2) Hs w_p^2 / g`` (2 deg times the steepness; 0.2 deg at BF5, 0.35 deg at
            BF9, inside the assumed 0.2-0.5 deg).
        wf_lambda: Damping of Fossen's filter (0 < lambda < 1); ``None``: fitted to the spectrum.
        wf_beaufort: Row of Al-Takie's HF table (5-9), needed for ``wf_model="al-takie"``.
        wf_peak_frequency: Where the ``"al-takie"`` filter's peak ``|G(jw)|`` falls (rad/s);
            ``None``: on ``w_p``. The offshore DP tasks put it on the thesis's own peak
            (:func:`al_takie_hf_peak_frequency`, Froude-scaled). Other models ignore it.
        sample_period: Grid of the precomputed envelope and WF motion (s), ``<= Tp / 10``;
            ``None``: ``Tp / 20`` (:attr:`grid_period`; 0.05 s for the lake's 1 s sea).
    """

    spectrum: str | None = param("jonswap", "-", "lake default (estimate)")
    Hs: float = param(0.05, "m", "estimate: lake, fetch-limited, U10 ~ 3-5 m/s")
    Tp: float = param(1.0, "s", "estimate: lake")
    gamma: float = param(3.3, "1", "JONSWAP mean (Hasselmann et al. 1973)")
    direction_from: float = param(0.0, "rad", "clockwise from north, coming from")
    n_components: int = param(100, "-", "harmonic components [assumption]")
    w_min: float | None = param(None, "rad/s", "None: 0.5 w_p [assumption]")
    w_max: float | None = param(None, "rad/s", "None: 3.5 w_p (>99 % of m0) [assumption]")
    drift: bool = param(True, "-", "estimate: lake drift not negligible")
    reflection: str | float = param("kT", "-", "assumption: R(kT) = min(1, kT/2)^2")
    drift_gain: float = param(1.0, "1", "calibration factor [assumption]")
    drift_yaw_lever: float = param(0.675, "m", "assumption: ~0.05 L_pp")
    first_order: bool = param(False, "-", "estimate: negligible on the lake")
    wf_model: str = param("fossen", "-", "Fossen (2011) ch. 8.2")
    wf_position_std: float | None = param(None, "m", "None: Hs/16 (assumption)")
    wf_heading_std: float | None = param(None, "rad", "None: rad(2) Hs w_p^2/g [assumption]")
    wf_lambda: float | None = param(None, "1", "None: LS fit (0.102 JONSWAP / 0.257 PM)")
    wf_beaufort: int | None = param(None, "-", "Al-Takie (1982) App. 2 (al-takie model only)")
    sample_period: float | None = param(
        None, "s", "None: Tp/20, grid of the precomputed signals [assumption]"
    )
    wf_peak_frequency: float | None = param(
        None, "rad/s", "None: w_p; peak of the al-takie filter (Al-Takie 1982 App. 2)"
    )

    def __post_init__(self) -> None:
        name = type(self).__name__
        if self.spectrum not in WAVE_SPECTRA:
            raise ValueError(
                f"{name}.spectrum must be one of 'jonswap', 'pm' or None, got {self.spectrum!r}"
            )
        for key in ("Hs", "Tp", "gamma", "direction_from", "drift_gain", "drift_yaw_lever"):
            if not is_real(getattr(self, key)):
                raise ValueError(f"{name}.{key} must be a real number, got {getattr(self, key)!r}")
        for key in (
            "w_min",
            "w_max",
            "wf_position_std",
            "wf_heading_std",
            "wf_lambda",
            "wf_peak_frequency",
            "sample_period",
        ):
            val = getattr(self, key)
            if val is not None and not is_real(val):
                raise ValueError(f"{name}.{key} must be a real number or None, got {val!r}")
        require_finite(self)
        require_angles(self, "direction_from")
        if not 0 <= self.Hs <= MAX_HS:
            raise ValueError(
                f"{name}.Hs must be >= 0 and <= {MAX_HS:g} m (beyond any sea measured), got "
                f"{self.Hs!r}"
            )
        if not 0 < self.Tp <= MAX_TP:
            raise ValueError(
                f"{name}.Tp must be > 0 and <= {MAX_TP:g} s (beyond any sea's peak period; "
                f"long swell is about 25 s), got {self.Tp!r}"
            )
        if not 1.0 <= self.gamma <= 10.0:
            raise ValueError(f"{name}.gamma must be in [1, 10], got {self.gamma!r}")
        n = self.n_components
        if not isinstance(n, int) or isinstance(n, bool) or not 1 <= n <= 5000:
            raise ValueError(f"{name}.n_components must be an int in [1, 5000], got {n!r}")
        for key in ("w_min", "w_max"):
            val = getattr(self, key)
            if val is not None and not val > 0:
                raise ValueError(f"{name}.{key} must be > 0 rad/s or None, got {val!r}")
        lo, hi = self.frequency_range
        if not lo < hi:
            raise ValueError(
                f"{name}: w_min must be < w_max, got the range [{lo!r}, {hi!r}] rad/s "
                f"(w_p = {self.peak_frequency:.4g} rad/s)"
            )
        for key in ("drift", "first_order"):
            if not isinstance(getattr(self, key), bool):
                raise ValueError(f"{name}.{key} must be true or false, got {getattr(self, key)!r}")
        r = self.reflection
        if isinstance(r, str):
            if r not in ("kT", "full"):
                raise ValueError(
                    f"{name}.reflection must be 'kT', 'full' or a number in [0, 1], got {r!r}"
                )
        elif not (is_real(r) and 0.0 <= r <= 1.0):
            raise ValueError(
                f"{name}.reflection must be 'kT', 'full' or a number in [0, 1], got {r!r}"
            )
        if self.drift_gain < 0:
            raise ValueError(f"{name}.drift_gain must be >= 0, got {self.drift_gain!r}")
        if self.wf_model not in WF_MODELS:
            raise ValueError(
                f"{name}.wf_model must be one of {', '.join(WF_MODELS)}, got {self.wf_model!r}"
            )
        for key in ("wf_position_std", "wf_heading_std"):
            val = getattr(self, key)
            if val is not None and val < 0:
                raise ValueError(f"{name}.{key} must be >= 0 or None, got {val!r}")
        if self.wf_peak_frequency is not None and not self.wf_peak_frequency > 0.0:
            raise ValueError(
                f"{name}.wf_peak_frequency must be > 0 rad/s or None, "
                f"got {self.wf_peak_frequency!r}"
            )
        if self.wf_lambda is not None and not 0.0 < self.wf_lambda < 1.0:
            raise ValueError(f"{name}.wf_lambda must be in (0, 1) or None, got {self.wf_lambda!r}")
        bf = self.wf_beaufort
        if bf is not None and (
            isinstance(bf, bool)
            or not isinstance(bf, numbers.Integral)
            or bf not in AL_TAKIE_HF_POLYNOMIALS
        ):
            raise ValueError(f"{name}.wf_beaufort must be None or an int 5-9, got {bf!r}")
        if self.wf_model == "al-takie" and bf is None:
            raise ValueError(
                f"{name}: wf_model 'al-takie' needs wf_beaufort (5-9), the row of Al-Takie's "
                "(1982) table"
            )
        h = self.sample_period
        if h is not None and not h > 0:
            raise ValueError(f"{name}.sample_period must be > 0 s, got {h!r}")
        if h is not None and h > self.Tp / 10.0:
            raise ValueError(
                f"{name}.sample_period ({h!r} s) must be <= Tp / 10 "
                f"({self.Tp / 10.0:.4g} s) to resolve the wave-frequency signals"
            )

    # -- derived ----------------------------------------------------------------------------

    @property
    def grid_period(self) -> float:
        """The grid step of the precomputed signals (s): ``sample_period``, or ``Tp / 20``
        where it is ``None``, whatever the wave effects on (so switching the first-order
        motion on leaves the drift as it was). Linear interpolation between samples ``h``
        apart loses ``(w h)^2 / 8`` of a component's amplitude: on ``Tp / 20``, 0.3 % at the
        drift envelope's difference frequencies up to ``w_p / 2`` and 1.2 % of the first-order
        motion at the peak frequency (the offshore sea states,
        :func:`~shipgym.disturbances.seastate.beaufort`, keep ``min(0.05 s, Tp / 20)``)."""
        if self.sample_period is not None:
            return float(self.sample_period)
        return float(self.Tp) / 20.0

    @property
    def peak_frequency(self) -> float:
        """``w_p = 2 pi / Tp`` (rad/s)."""
        return _TWO_PI / float(self.Tp)

    @property
    def frequency_range(self) -> tuple[float, float]:
        """``(w_min, w_max)`` actually used (rad/s)."""
        wp = self.peak_frequency
        lo = 0.5 * wp if self.w_min is None else float(self.w_min)
        hi = 3.5 * wp if self.w_max is None else float(self.w_max)
        return lo, hi

    @property
    def is_calm(self) -> bool:
        """True when there are no waves (``spectrum is None`` or ``Hs == 0``)."""
        return self.spectrum is None or self.Hs == 0.0

    @property
    def position_std(self) -> float:
        """Effective WF position std along the wave direction (m)."""
        if self.wf_position_std is not None:
            return float(self.wf_position_std)
        return float(self.Hs) / 16.0

    @property
    def heading_std(self) -> float:
        """Effective WF heading std (rad)."""
        if self.wf_heading_std is not None:
            return float(self.wf_heading_std)
        return math.radians(2.0) * float(self.Hs) * self.peak_frequency**2 / G

    @property
    def shaping_lambda(self) -> float:
        """Damping of Fossen's WF filter: ``wf_lambda`` or the fit to the spectrum (1)."""
        if self.wf_lambda is not None:
            return float(self.wf_lambda)
        kind = "pm" if self.spectrum is None else self.spectrum
        return fit_shaping_filter_lambda(kind, round(float(self.gamma), 6))

    def spectral_density(self, w: ArrayLike) -> NDArray[np.float64]:
        """The target spectrum ``S(w)`` (m^2 s/rad) at angular frequencies ``w`` (rad/s)."""
        return wave_spectrum(self.spectrum, w, float(self.Hs), float(self.Tp), float(self.gamma))

    @classmethod
    def from_dict(cls, mapping: Mapping[str, Any]) -> WaveConfig:
        """Build from a mapping of field names (SI units, radians); unknown keys raise."""
        return from_mapping(cls, mapping, where="wave config")


class Waves(PieceGrid):
    """Runtime wave model for one vessel: elevation, WF motion and drift loads.

    Args:
        config: Sea state (default: the lake sea of :class:`WaveConfig`).
        hull: Hull dimensions (``B``, ``L_pp``, draught ``T``); required (e.g.
            ``load_vessel("blue-lady").hull``).
        rho: Water density (kg/m^3).

    Example:
        >>> from shipgym.dynamics import BLUE_LADY_HULL
        >>> waves = Waves(WaveConfig(Hs=0.083, Tp=1.79, first_order=True), BLUE_LADY_HULL)
        >>> waves.reset(np.random.default_rng(1))
        >>> X, Y, N = waves.drift_load(12.3, psi=0.2)   # every physics step, body frame
        >>> dx, dy, dpsi = waves.wf_motion(12.3)        # add to the measured pose (NED)
    """

    _LEAD = HARMONIC_BLOCK  # a piece's harmonic sums whole blocks (PieceGrid)

    def __init__(
        self,
        config: WaveConfig | None = None,
        hull: HullParameters | None = None,
        rho: float = RHO_WATER,
    ) -> None:
        if hull is None:
            raise TypeError(
                "Waves() needs the vessel's hull: pass hull=..., e.g. load_vessel('blue-lady').hull"
            )
        self.config = cfg = WaveConfig() if config is None else config
        self.hull = hull
        self.rho = float(rho)
        self._dt = cfg.grid_period
        self._inv_dt = 1.0 / self._dt
        self._beta_p = float(cfg.direction_from) + math.pi
        self._cb = math.cos(self._beta_p)
        self._sb = math.sin(self._beta_p)
        tx0, ty0 = drift_coefficients(hull, self.rho)
        gain = float(cfg.drift_gain)
        self._kx = tx0 * gain
        self._ky = ty0 * gain
        self._kn = -float(cfg.drift_yaw_lever)
        self.calm = cfg.is_calm
        self._drift_on = cfg.drift and not self.calm and gain > 0.0
        self._wf_on = cfg.first_order and not self.calm
        self._sig_d = cfg.position_std
        self._sig_h = cfg.heading_std
        self._filter: tuple[Any, ...] | None = None
        if self._wf_on and cfg.wf_model != "rao":
            self._filter = self._build_filter()
        self._rng_wf: np.random.Generator | None = None
        self._wf_rows: WaveMotionRows | None = None  # wf_motion's window (one row)
        self._wf_x = np.zeros(1)  # and its grid position
        self._w = self._A = self._eps = np.zeros(0)
        self._weights = np.zeros((0, 0))  # the harmonic sums' weights of a piece (reset)
        self._bins: Any = None  # the sea's harmonic_bins (computed at the first reset)
        self._table: Any = None
        self._mean_E = 0.0
        self._reset_grid()
        self._ready = self.calm

    # -- setup ------------------------------------------------------------------------------

    def _build_filter(self) -> tuple[Any, ...]:
        """Exact discrete form of the unit-std WF filter (Phi modal, noise map, initial cov)."""
        from scipy.linalg import expm, solve_continuous_lyapunov

        cfg = self.config
        wp = cfg.peak_frequency
        if cfg.wf_model == "fossen":
            lam = cfg.shaping_lambda
            den = np.array([1.0, 2.0 * lam * wp, wp * wp])
            out = 1  # y = xi_2 = s xi_1
        else:  # al-takie
            peak = wp if cfg.wf_peak_frequency is None else float(cfg.wf_peak_frequency)
            den = al_takie_hf_polynomial(int(cfg.wf_beaufort), peak)  # type: ignore[arg-type]
            out = 2  # y = x_3 = s^2 x_1
        n = den.size - 1
        A = np.zeros((n, n))
        A[np.arange(n - 1), np.arange(1, n)] = 1.0
        A[-1, :] = -den[:0:-1]
        B = np.zeros((n, 1))
        B[-1, 0] = 1.0
        P = solve_continuous_lyapunov(A, -B @ B.T)
        P = 0.5 * (P + P.T) / P[out, out]  # unit output variance (gain folded in)
        Phi = expm(A * self._dt)
        Q = P - Phi @ P @ Phi.T
        Q = 0.5 * (Q + Q.T)
        Gq = _psd_sqrt(Q)
        G0 = _psd_sqrt(P)
        lam_i, V = np.linalg.eig(Phi)
        Vinv = np.linalg.inv(V)
        return lam_i, Vinv @ Gq, Vinv @ G0, V[out, :], n

    def _reset_grid(self) -> None:
        self._clear_pieces()
        self._work: tuple[NDArray[np.float64], NDArray[np.complex128]] | None = None
        self._cache: dict[int, list[float]] = {}  # drift_load's pieces of the envelope
        self._j = -1
        self._k0 = 0
        self._E: list[float] = []
        self._q: NDArray[np.complex128] | None = None

    def reset(self, rng: np.random.Generator | int | None = None) -> None:
        """Draw a new realisation (component frequencies and phases, WF noise).

        A child generator is seeded with one ``integers(2**63)`` draw from ``rng`` (made even
        for calm water, so the parent's stream does not depend on the wave settings); from it
        come the component draws and, independently, the WF-filter noise.

        Args:
            rng: Parent generator or integer seed; ``None`` only for calm water.

        Raises:
            ValueError: ``rng`` is ``None`` for a non-calm sea.
        """
        self._reset_grid()
        if self._wf_rows is not None:
            self._wf_rows.invalidate(0)
        if rng is None:
            if not self.calm:
                raise ValueError("Waves.reset needs a numpy Generator (or a seed) unless Hs = 0")
            self._ready = True
            return
        if not isinstance(rng, np.random.Generator):
            rng = np.random.default_rng(rng)
        self._seed = child_seeds(rng)
        self._draws()

    def _draws(self) -> None:
        """A reset's draws from its child generator (seeded with :attr:`_seed`)."""
        child = np.random.default_rng(self._seed)
        s_comp, s_wf = child_seeds(child, 2)
        self._ready = True
        if self.calm:
            return
        cfg = self.config
        crng = np.random.default_rng(int(s_comp))
        n = int(cfg.n_components)
        lo, hi = cfg.frequency_range
        if self._bins is None:  # the sea's bins, the same at every reset
            self._bins = harmonic_bins(cfg.spectral_density, lo, hi, n)
        w, A, eps = harmonic_components(cfg.spectral_density, lo, hi, n, crng, bins=self._bins)
        r = cfg.reflection
        if r == "kT":
            kT = w * w / G * float(self.hull.T)
            sqrtR = np.minimum(1.0, 0.5 * kT)
        elif r == "full":
            sqrtR = np.ones(n)
        else:
            sqrtR = np.full(n, math.sqrt(float(r)))
        self._w, self._A, self._eps = w, A, eps
        self._table: Any = None  # harmonic_table of the sea (at its first piece)
        self._cdrift = A * sqrtR
        self._mean_E = float(np.sum(self._cdrift**2))
        k = w * w / G
        a2 = float(np.sum(A * A))
        ka2 = float(np.sum((k * A) ** 2))
        self._g_rao = (
            self._sig_d / math.sqrt(0.5 * a2) if a2 > 0 else 0.0,
            self._sig_h / math.sqrt(0.5 * ka2) if ka2 > 0 else 0.0,
        )
        self._kA = k * A
        weights = [self._cdrift] if self._drift_on else []
        if self._wf_on and cfg.wf_model == "rao":
            weights += [A, self._kA]
        self._weights = np.ascontiguousarray(np.reshape(weights, (len(weights), n)), dtype=float)
        self._sums = np.empty((len(weights), 2, PIECE + HARMONIC_BLOCK))  # a piece's harmonic sums
        if self._filter is not None:
            self._rng_wf = np.random.default_rng(int(s_wf))
            lam_i, _, G0, _, nf = self._filter
            z0 = self._rng_wf.standard_normal((nf, 2))
            self._q = G0 @ z0  # modal state, (n, 2 DOFs)

    # -- grid generation --------------------------------------------------------------------

    def _ready_check(self) -> None:
        if not self._ready:
            raise RuntimeError("call Waves.reset(rng) before querying the waves")

    def _replica(self) -> Waves:
        r = copy.copy(self)
        r._wf_rows = None  # (the original's motion rows are its own)
        r._reset_grid()
        r._draws()
        return r

    def _begin(self, j: int) -> NDArray[np.float64]:
        """Chunk ``j`` begun (rows ``[E, d, h]`` on grid points ``j*CHUNK .. (j+1)*CHUNK``,
        inclusive): the WF filters' noise ``standard_normal((nf, 2, CHUNK))`` (its last row as
        far as read, :meth:`~shipgym.disturbances._grid.PieceGrid._normals`) and their
        recursion's state before its first sample."""
        if self._filter is not None:
            assert self._rng_wf is not None and self._q is not None
            lam_i, _, _, _, nf = self._filter
            # the (nf, 2 CHUNK) draw and the modal states: the last chunk's arrays again (its
            # samples are in its rows; fresh memory costs page faults at every chunk)
            z, s = self._work if self._work is not None else (None, None)
            self._z = self._normals(self._rng_wf, (nf, 2, _CHUNK), out=z)
            zi = np.empty((nf, 2), dtype=complex)
            for i in range(nf):
                zi[i] = lam_i[i] * self._q[i]  # the recursion's state before the first sample
            self._zi = zi
            self._s = s if s is not None else np.empty((nf, 2, _CHUNK), dtype=complex)
            self._work = (self._z, self._s)
        rows = np.empty((3, _CHUNK + 1))  # the rows that no piece writes are zeros
        if not self._drift_on:
            rows[0] = 0.0
        if not self._wf_on:
            rows[1:] = 0.0
        return rows

    def _piece(self, j: int, ka: int, kb: int) -> None:
        """Samples ``ka ... kb - 1`` of chunk ``j``: the drift envelope and the RAO motion
        (harmonic sums on the chunk's grid from ``t0 = j CHUNK dt``), or the WF filters'
        samples (:meth:`_filter_piece`)."""
        rows = self._chunk(j)
        weights = self._weights
        if weights.shape[0]:
            if self._table is None:
                self._table = harmonic_table(self._dt, self._w)
            zr, zi = self._table
            n = kb - ka
            if self._sums.shape[2] < n:
                self._sums = np.empty((weights.shape[0], 2, n))
            args = (j * _CHUNK * self._dt, self._dt, ka, n, self._w, self._eps, weights, True,
                    zr, zi, self._sums)  # fmt: skip
            harmonic_into(args)
            sums = self._sums[:, :, :n]  # (rows, re/im, n)
            r = 0
            if self._drift_on:
                e = rows[0, ka:kb]
                np.multiply(sums[0, 0], sums[0, 0], out=e)  # |sum|^2
                e += sums[0, 1] * sums[0, 1]
                r = 1
            if r < weights.shape[0]:  # the RAO motion
                rows[1, ka:kb] = self._g_rao[0] * sums[r, 1]
                rows[2, ka:kb] = self._g_rao[1] * sums[r + 1, 1]
        if self._filter is not None:
            rows[1:, ka:kb] = self._filter_piece(ka, kb)

    def _filter_piece(self, ka: int, kb: int) -> NDArray[np.float64]:
        """The WF filters' samples ``ka ... kb - 1`` of the chunk being filled (exact discrete
        recursion, modal; compiled: :func:`modal_filter_piece`), (2, kb - ka)."""
        assert self._filter is not None and self._q is not None
        lam_i, Gm, _, c_out, nf = self._filter
        sa = ka - 1 if ka > 0 else 0  # the modal states s_k of the samples k + 1
        s = self._s
        self._draw_to(self._z, kb)
        modal_filter_piece(
            np.ascontiguousarray(lam_i), np.ascontiguousarray(Gm), self._z, self._zi, s, sa,
            kb - 1,
        )  # fmt: skip
        y = np.zeros((2, kb - ka), dtype=complex)
        first = 1 if ka == 0 else 0
        for i in range(nf):
            if ka == 0:
                y[:, 0] += c_out[i] * self._q[i]
            y[:, first:] += c_out[i] * s[i, :, sa : kb - 1]
        if kb == _CHUNK + 1:
            self._q = s[:, :, -1].copy()
        out = y.real
        out[0] *= self._sig_d
        out[1] *= self._sig_h
        return out

    def _select(self, j: int) -> None:
        envelope = self._cache.get(j)
        if envelope is None:
            _k0, arr = self.window(j * PIECE)
            envelope = arr[0].tolist()
            if len(self._cache) >= 2:
                del self._cache[next(iter(self._cache))]
            self._cache[j] = envelope
        self._E = envelope
        self._j = j
        self._k0 = j * PIECE

    def _grid(self, rows: slice, t: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Linearly interpolated grid rows at times ``t`` (vectorised); returns (rows, shape)."""
        tt = np.asarray(t, dtype=float)
        x = tt.ravel() * self._inv_dt
        if not np.all(x >= 0.0):
            raise ValueError("Waves: all times must be >= 0 s (and not NaN)")
        if x.size == 0:
            return np.zeros((3, 0))[rows], tt
        k = np.floor(x).astype(np.int64)
        jmax = int(k.max()) // _CHUNK
        self._extend_to(jmax)
        chunks = self._whole(jmax)
        grid = np.concatenate([c[:, :_CHUNK] for c in chunks] + [chunks[jmax][:, _CHUNK:]], axis=1)
        grid = grid[rows]
        f = x - k
        return grid[:, k] + f * (grid[:, k + 1] - grid[:, k]), tt

    # -- per-step queries (plain floats) -----------------------------------------------------

    @property
    def drift_constants(self) -> tuple[float, float, float, float] | None:
        """``(beta_p rad, k_x, k_y, k_n m)`` of :meth:`drift_load` (``X = k_x cos b |cos b|
        E``, ``Y = k_y sin b |sin b| E``, ``N = k_n cos b Y``, ``b = beta_p - psi``, ``E`` the
        drift energy on the grid, :meth:`chunk` row 0), or ``None`` where there is no drift
        (calm water, ``drift`` off)."""
        if not self._drift_on:
            return None
        return (self._beta_p, self._kx, self._ky, self._kn)

    @property
    def sample_rate(self) -> float:
        """Samples per second of the wave grid (1/s)."""
        return self._inv_dt

    def chunk(self, j: int) -> NDArray[np.float64]:
        """Chunk ``j`` of the wave grid, ``(3, CHUNK + 1)``: the samples ``k = j CHUNK ... (j +
        1) CHUNK`` of the drift energy ``E`` and the first-order motion's two channels,
        generated in time order on first use. Read only."""
        self._extend_to(j)
        return self._chunk(j)

    def drift_load(self, t: float, psi: float) -> tuple[float, float, float]:
        """Mean + slowly varying second-order drift loads on the hull at time ``t``.

        Call it every physics step (about 1 us). Exactly zero for calm water or ``drift``
        off.

        Args:
            t: Simulation time (s), ``>= 0``.
            psi: Heading (rad).

        Returns:
            ``(X, Y, N)`` in N, N, N m on the body axes (Python floats).
        """
        if not self._drift_on:
            return _ZERO3
        x = t * self._inv_dt
        if not x >= 0.0:
            raise ValueError(f"Waves.drift_load: time must be >= 0 s, got {t!r}")
        k = int(x)
        if k // PIECE != self._j:
            self._select(k // PIECE)
        i = k - self._k0
        E = self._E
        e0 = E[i]
        e = e0 + (x - k) * (E[i + 1] - e0)
        b = self._beta_p - psi
        c = math.cos(b)
        s = math.sin(b)
        Y = self._ky * s * abs(s) * e
        return self._kx * c * abs(c) * e, Y, self._kn * c * Y

    def wf_motion(self, t: float) -> tuple[float, float, float]:
        """First-order wave-frequency motion to add to the *measured* pose at time ``t``.

        Zero-mean and purely wave-frequency; never apply it to the hull. Exactly zero for calm
        water or ``first_order`` off.

        Args:
            t: Simulation time (s), ``>= 0``.

        Returns:
            ``(dx, dy, dpsi)``: NED offsets (m, m) and heading offset (rad), Python floats.
        """
        if not self._wf_on:
            return _ZERO3
        if not t >= 0.0:
            raise ValueError(f"Waves.wf_motion: time must be >= 0 s, got {t!r}")
        rows = self._wf_rows
        if rows is None:
            rows = self._wf_rows = WaveMotionRows([self])
        self._wf_x[0] = t * self._inv_dt  # the grid position, as the rows' law forms it
        rows.run(self._wf_x)
        dx, dy, dpsi = rows.out[0].tolist()
        return dx, dy, dpsi

    def mean_drift_load(self, psi: float) -> tuple[float, float, float]:
        """Analytic mean drift loads ``T(beta) sum_j A_j^2 R_j`` of this realisation.

        Args:
            psi: Heading (rad).

        Returns:
            ``(X, Y, N)`` in N, N, N m (body axes); zeros for calm water or ``drift`` off.
        """
        if not self._drift_on:
            return _ZERO3
        if not self._ready:
            raise RuntimeError("call Waves.reset(rng) before querying the waves")
        b = self._beta_p - float(psi)
        c = math.cos(b)
        s = math.sin(b)
        Y = self._ky * s * abs(s) * self._mean_E
        return self._kx * c * abs(c) * self._mean_E, Y, self._kn * c * Y

    # -- vectorised queries (tests, plots) ---------------------------------------------------

    @property
    def components(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """``(w, A, eps)`` of the current realisation (rad/s, m, rad); empty when calm."""
        return self._w.copy(), self._A.copy(), self._eps.copy()

    def elevation(self, t: ArrayLike) -> NDArray[np.float64]:
        """Wave elevation at the ship ``zeta(t) = sum_j A_j cos(w_j t + eps_j)`` (m).

        Args:
            t: Times (s), any shape.

        Returns:
            Elevation (m), the shape of ``t`` (computed exactly, not from the grid).
        """
        tt = np.asarray(t, dtype=float)
        if not self._ready:
            raise RuntimeError("call Waves.reset(rng) before querying the waves")
        flat = tt.ravel()
        out = np.zeros(flat.size)
        if self.calm:
            return out.reshape(tt.shape)
        blk = 4096
        for s in range(0, flat.size, blk):
            ph = np.multiply.outer(flat[s : s + blk], self._w) + self._eps
            out[s : s + blk] = np.einsum("kj,j->k", np.cos(ph), self._A)
        return out.reshape(tt.shape)

    @property
    def component_hs(self) -> float:
        """Significant wave height of the realisation, ``4 sqrt(sum A_j^2 / 2)`` (m)."""
        return 4.0 * math.sqrt(0.5 * float(np.sum(self._A**2)))

    def hs_check(self, t: ArrayLike | None = None) -> float:
        """Ratio of the realised to the nominal ``Hs`` (1; 1.0 for calm water).

        Args:
            t: ``None``: from the component amplitudes (``4 sqrt(m0)``); else from the
                elevation record at these times (``4 std(zeta)``).

        Returns:
            ``Hs_realised / Hs``; within a few percent of 1 for the default range and 100
            components (the band ``[0.5, 3.5] w_p`` holds > 99 % of ``m0``).
        """
        if self.calm:
            return 1.0
        if t is None:
            hs = self.component_hs
        else:
            hs = 4.0 * float(np.std(self.elevation(t)))
        return hs / float(self.config.Hs)

    def envelope(self, t: ArrayLike) -> NDArray[np.float64]:
        """Drift envelope ``E(t)`` (m^2) from the grid (zeros when the drift is off)."""
        tt = np.asarray(t, dtype=float)
        if not self._drift_on:
            return np.zeros(tt.shape)
        vals, _ = self._grid(slice(0, 1), tt)
        return vals[0].reshape(tt.shape)

    def drift_series(
        self, t: ArrayLike, psi: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`drift_load` for arrays (same values); returns ``(X, Y, N)`` arrays."""
        e = self.envelope(t)
        b = self._beta_p - np.asarray(psi, dtype=float)
        c = np.cos(b)
        s = np.sin(b)
        Y = self._ky * s * np.abs(s) * e
        return self._kx * c * np.abs(c) * e, Y, self._kn * c * Y

    def wf_series(
        self, t: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`wf_motion` for arrays: ``(dx, dy, dpsi)`` of the shape of ``t``."""
        tt = np.asarray(t, dtype=float)
        if not self._wf_on:
            z = np.zeros(tt.shape)
            return z, z.copy(), z.copy()
        vals, _ = self._grid(slice(1, 3), tt)
        d = vals[0].reshape(tt.shape)
        return d * self._cb, d * self._sb, vals[1].reshape(tt.shape)

    def __repr__(self) -> str:
        return f"Waves(config={self.config!r})"


def _psd_sqrt(Q: NDArray[np.float64]) -> NDArray[np.float64]:
    """A square root ``L`` with ``L L^T = Q`` of a symmetric PSD matrix (eigen, clipped)."""
    d, V = np.linalg.eigh(Q)
    return V * np.sqrt(np.clip(d, 0.0, None))
