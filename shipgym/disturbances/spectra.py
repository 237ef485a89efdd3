r"""Wave and wind-gust spectra, shaping-filter fits and Froude scaling (NumPy/SciPy; the
harmonic sums of the gust and wave grids are compiled).

``S_PM(w) = (5/16) Hs^2 w_p^4 w^-5 exp(-1.25 (w_p/w)^4)``, JONSWAP ``S_J = (1 - 0.287 ln
gamma) S_PM gamma^...``; NPD/ISO 19901-1 gust spectrum.

Every spectrum is one-sided. Full entries of the sources: ``docs/references.md``.

Public names: ``G``, ``RHO_WATER``, ``pierson_moskowitz``, ``jonswap``, ``wave_spectrum``,
``dnv_gamma``, ``norsok_peak_period``, ``spectral_moment``, ...
Sources: Fossen (2011).

Design notes: docs/design/disturbances.spectra.md.
"""

from __future__ import annotations

import functools
import math
import numbers
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import entry, law_input, njit, spread_rows, threads_ok

__all__ = [
    "G",
    "RHO_WATER",
    "pierson_moskowitz",
    "jonswap",
    "wave_spectrum",
    "dnv_gamma",
    "norsok_peak_period",
    "spectral_moment",
    "significant_wave_height",
    "npd_wind_spectrum",
    "harris_wind_spectrum",
    "gauss_markov_psd",
    "wind_gust_spectrum",
    "shaping_filter_psd",
    "fit_shaping_filter_lambda",
    "harmonic_bins",
    "harmonic_components",
    "HARMONIC_BLOCK",
    "harmonic_into",
    "harmonic_rows",
    "harmonic_sums",
    "harmonic_table",
    "FROUDE_EXPONENTS",
    "froude_factor",
    "froude_scale",
    "model_length",
    "model_time",
    "model_velocity",
    "model_frequency",
    "model_force",
    "model_moment",
]

#: Gravitational acceleration, m/s^2 (standard gravity).
G = 9.81
#: Fresh-water density used for the hydrodynamics of the model, kg/m^3 (lake Silm).
RHO_WATER = 1000.0

_SIGMA_LOW = 0.07
_SIGMA_HIGH = 0.09
_NPD_N = 0.468
_HARRIS_KAPPA = 0.0026
_HARRIS_L = 1800.0


def _check_nonneg(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not value >= 0.0:
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return float(value)


def _check_pos(name: str, value: float) -> float:
    v = _check_nonneg(name, value)
    if v <= 0.0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return v


# ---------------------------------------------------------------------------------------------
# Wave spectra
# ---------------------------------------------------------------------------------------------


def pierson_moskowitz(w: ArrayLike, Hs: float, Tp: float) -> NDArray[np.float64]:
    """Modified Pierson-Moskowitz (ITTC / Bretschneider) wave spectrum.

    Source: Pierson & Moskowitz (1964); MSS ``waveSpectrum.m`` case "modified PM"; DNV-RP-C205
    eq. 3.5.5.

    Args:
        w: Angular frequencies (rad/s), any shape; values ``<= 0`` give 0.
        Hs: Significant wave height (m), ``>= 0``.
        Tp: Peak period (s), ``> 0``.

    Returns:
        ``S(w)`` in m^2 s/rad, the shape of ``w``; ``int S dw = Hs^2 / 16``.
    """
    Hs = _check_nonneg("Hs", Hs)
    wp = 2.0 * math.pi / _check_pos("Tp", Tp)
    ww = np.asarray(w, dtype=float)
    out = np.zeros(ww.shape)
    pos = ww > 0.0
    wpos = ww[pos]
    r4 = (wp / wpos) ** 4
    out[pos] = (5.0 / 16.0) * Hs * Hs * r4 / wpos * np.exp(-1.25 * r4)
    return out


def jonswap(w: ArrayLike, Hs: float, Tp: float, gamma: float = 3.3) -> NDArray[np.float64]:
    """JONSWAP wave spectrum in the DNV-RP-C205 form.

    Source: Hasselmann et al. (1973); DNV-RP-C205 (2010) sec. 3.5.5.2; MSS ``waveSpectrum.m``
    case 7.

    Args:
        w: Angular frequencies (rad/s), any shape; values ``<= 0`` give 0.
        Hs: Significant wave height (m), ``>= 0``.
        Tp: Peak period (s), ``> 0``.
        gamma: Peak enhancement factor, ``1 <= gamma <= 10`` (``1`` is Pierson-Moskowitz;
            3.3 is the JONSWAP mean; DNV gives the range 1-7, see :func:`dnv_gamma`).

    Returns:
        ``S(w)`` in m^2 s/rad, the shape of ``w``.
    """
    if isinstance(gamma, bool) or not isinstance(gamma, numbers.Real) or not 1.0 <= gamma <= 10:
        raise ValueError(f"JONSWAP gamma must be a number in [1, 10], got {gamma!r}")
    wp = 2.0 * math.pi / _check_pos("Tp", Tp)
    ww = np.asarray(w, dtype=float)
    sigma = np.where(ww <= wp, _SIGMA_LOW, _SIGMA_HIGH)
    peak = np.exp(-((ww - wp) ** 2) / (2.0 * sigma * sigma * wp * wp))
    return (1.0 - 0.287 * math.log(gamma)) * pierson_moskowitz(ww, Hs, Tp) * gamma**peak


def wave_spectrum(
    kind: str | None, w: ArrayLike, Hs: float, Tp: float, gamma: float = 3.3
) -> NDArray[np.float64]:
    """A wave spectrum by name.

    Args:
        kind: ``"jonswap"``, ``"pm"`` (Pierson-Moskowitz) or ``None`` (no waves: zeros).
        w: Angular frequencies (rad/s).
        Hs: Significant wave height (m).
        Tp: Peak period (s).
        gamma: JONSWAP peak enhancement (ignored for ``"pm"``).

    Returns:
        ``S(w)`` in m^2 s/rad.

    Raises:
        ValueError: For an unknown ``kind``.
    """
    if kind is None:
        return np.zeros(np.shape(w))
    if kind == "jonswap":
        return jonswap(w, Hs, Tp, gamma)
    if kind == "pm":
        return pierson_moskowitz(w, Hs, Tp)
    raise ValueError(f"unknown wave spectrum {kind!r}; valid names are: 'jonswap', 'pm', None")


def dnv_gamma(Hs: float, Tp: float) -> float:
    """DNV-RP-C205 rule for the JONSWAP peak factor from ``k = Tp / sqrt(Hs)``.

    ``gamma = 5`` for ``k <= 3.6``, ``exp(5.75 - 1.15 k)`` for ``3.6 < k <= 5``, ``1`` above
    (DNV-RP-C205). Only meaningful at full scale (``k`` is dimensional, s/m^0.5).

    Args:
        Hs: Significant wave height (m, full scale), ``> 0``.
        Tp: Peak period (s, full scale), ``> 0``.

    Returns:
        gamma (1).
    """
    k = _check_pos("Tp", Tp) / math.sqrt(_check_pos("Hs", Hs))
    if k <= 3.6:
        return 5.0
    if k <= 5.0:
        return math.exp(5.75 - 1.15 * k)
    return 1.0


def norsok_peak_period(Hs: float) -> float:
    """Expected peak period for a given ``Hs`` (NORSOK N-003, North Sea; MSS ``Wave_init.m``).

    ``Tp = 4.883 + 2.68 Hs^0.54`` (full scale).

    Args:
        Hs: Significant wave height (m, full scale), ``>= 0``.

    Returns:
        Tp (s, full scale).
    """
    return 4.883 + 2.68 * _check_nonneg("Hs", Hs) ** 0.54


def spectral_moment(w: ArrayLike, S: ArrayLike, n: int = 0) -> float:
    """Spectral moment ``m_n = int w^n S(w) dw`` by the trapezoidal rule.

    Args:
        w: Increasing frequencies (rad/s or Hz).
        S: Spectral density at ``w``.
        n: Order of the moment.

    Returns:
        ``m_n`` in the units of ``S`` times ``w^(n+1)``.
    """
    ww = np.asarray(w, dtype=float)
    return float(np.trapezoid(ww**n * np.asarray(S, dtype=float), ww))


def significant_wave_height(elevation: ArrayLike) -> float:
    """Significant wave height ``Hs = 4 std(zeta)`` of an elevation record (m).

    Args:
        elevation: Wave elevation samples (m), 1-D.

    Returns:
        ``4 sqrt(m0)`` estimated from the samples (the mean is removed).
    """
    z = np.asarray(elevation, dtype=float)
    if z.size < 2:
        raise ValueError("significant_wave_height needs at least two samples")
    return float(4.0 * np.std(z))


# ---------------------------------------------------------------------------------------------
# Wind-gust spectra (one-sided, f in Hz)
# ---------------------------------------------------------------------------------------------


def npd_wind_spectrum(f: ArrayLike, U10: float, z: float = 10.0) -> NDArray[np.float64]:
    """NPD / ISO 19901-1 (Andersen & Lovseth) wind-gust spectrum, one-sided.

    Source: Andersen & Lovseth (2006); ISO 19901-1 (2015) sec. 7.3; DNV-RP-C205 eq. 2.3.2.10
    (same formula).

    Args:
        f: Frequencies (Hz, full scale), any shape; values ``<= 0`` give ``S(0+)``.
        U10: One-hour mean wind speed at 10 m (m/s, full scale), ``>= 0``.
        z: Height above the sea (m), ``> 0``.

    Returns:
        ``S(f)`` in (m/s)^2/Hz of the longitudinal gust, the shape of ``f``; zeros for
        ``U10 = 0``.
    """
    U10 = _check_nonneg("U10", U10)
    z = _check_pos("z", z)
    ff = np.maximum(np.asarray(f, dtype=float), 0.0)
    if U10 == 0.0:
        return np.zeros(ff.shape)
    u = U10 / 10.0
    zz = z / 10.0
    ft = 172.0 * ff * zz ** (2.0 / 3.0) * u ** (-0.75)
    n = _NPD_N
    return 320.0 * u * u * zz**0.45 / (1.0 + ft**n) ** (5.0 / (3.0 * n))


def harris_wind_spectrum(
    f: ArrayLike, U10: float, kappa: float = _HARRIS_KAPPA, L: float = _HARRIS_L
) -> NDArray[np.float64]:
    """Harris (1971, DNV-RP-C205) wind-gust spectrum, one-sided.

    Source: Harris (1971) (cross-checked with ``mika-s/pyMarineCybernetics`` and the SIMA
    manual); not valid below about 0.01 Hz at full scale.

    Args:
        f: Frequencies (Hz, full scale), any shape; values ``<= 0`` give ``S(0)``.
        U10: Mean wind speed at 10 m (m/s, full scale), ``>= 0``.
        kappa: Sea-surface drag coefficient (1), 0.0025-0.0026.
        L: Length scale (m), 1800.

    Returns:
        ``S(f)`` in (m/s)^2/Hz, the shape of ``f``; zeros for ``U10 = 0``.
    """
    U10 = _check_nonneg("U10", U10)
    kappa = _check_pos("kappa", kappa)
    L = _check_pos("L", L)
    ff = np.maximum(np.asarray(f, dtype=float), 0.0)
    if U10 == 0.0:
        return np.zeros(ff.shape)
    x = L * ff / U10
    return 4.0 * kappa * L * U10 / (2.0 + x * x) ** (5.0 / 6.0)


def gauss_markov_psd(f: ArrayLike, sigma: float, T: float) -> NDArray[np.float64]:
    """One-sided PSD of a first-order Gauss-Markov (Ornstein-Uhlenbeck) process.

    ``S(f) = 4 sigma^2 T / (1 + (2 pi f T)^2)``, so that ``int_0^inf S df = sigma^2``
    (the process ``x_dot = -x/T + w`` with stationary std ``sigma``).

    Args:
        f: Frequencies (Hz), any shape.
        sigma: Stationary standard deviation (units of the process), ``>= 0``.
        T: Correlation time (s), ``> 0``.

    Returns:
        ``S(f)`` in units^2/Hz.
    """
    sigma = _check_nonneg("sigma", sigma)
    T = _check_pos("T", T)
    ff = np.asarray(f, dtype=float)
    return 4.0 * sigma * sigma * T / (1.0 + (2.0 * math.pi * ff * T) ** 2)


def wind_gust_spectrum(
    kind: str, f: ArrayLike, U10: float, scale: float = 1.0
) -> NDArray[np.float64]:
    """A wind-gust spectrum by name, optionally Froude-scaled to a model.

    With ``scale = lambda > 1`` the spectrum is evaluated at full scale (speed
    ``U10 sqrt(lambda)``, frequency ``f / sqrt(lambda)``) and mapped back to the model:
    ``S_m(f) = S_s(f / sqrt(lambda)) / lambda^1.5``: from ``S_m df_m = S_s df_s / lambda``
    (velocity^2 scales with ``1/lambda``) and ``df_s = df_m / sqrt(lambda)``, so the model
    variance is the full-scale variance over ``lambda`` (the project's offshore assumption:
    "synthesised then time-compressed by 1/sqrt(24) and speed-scaled by 1/sqrt(24)").

    Args:
        kind: ``"npd"`` or ``"harris"``.
        f: Frequencies (Hz) in the simulated (model) time.
        U10: Mean wind speed (m/s) in the simulated (model) scale.
        scale: Froude scale ``lambda >= 1`` (1 = full scale / real wind).

    Returns:
        ``S(f)`` in (m/s)^2/Hz at the simulated scale.

    Raises:
        ValueError: For an unknown ``kind``.
    """
    scale = _check_pos("scale", scale)
    sq = math.sqrt(scale)
    ff = np.asarray(f, dtype=float) / sq
    if kind == "npd":
        s = npd_wind_spectrum(ff, U10 * sq)
    elif kind == "harris":
        s = harris_wind_spectrum(ff, U10 * sq)
    else:
        raise ValueError(f"unknown wind-gust spectrum {kind!r}; valid names are: 'npd', 'harris'")
    return s / (scale * sq)


# ---------------------------------------------------------------------------------------------
# Harmonic superposition
# ---------------------------------------------------------------------------------------------


def harmonic_bins(
    spectrum: Any, lo: float, hi: float, n: int, *, log: bool = False
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The bins of :func:`harmonic_components` and their amplitudes, which do not depend on
    the draws: ``(edges, widths, amplitudes)``, ``n + 1``, ``n`` and ``n`` values (read-only
    arrays; a process keeps them for its next realisations).

    The band ``[lo, hi]`` is cut into ``n`` bins (equal widths, or equal ratios with
    ``log=True``); a bin's amplitude is ``sqrt(2 int_bin S df)`` (the bin's energy, 16-interval
    Simpson rule).
    """
    edges = np.geomspace(lo, hi, n + 1) if log else np.linspace(lo, hi, n + 1)
    df = np.diff(edges)
    m = 16  # Simpson sub-intervals per bin
    sub = edges[:-1, None] + df[:, None] * (np.arange(m + 1) / m)
    wts = np.ones(m + 1)
    wts[1:-1:2] = 4.0
    wts[2:-1:2] = 2.0
    dens = np.maximum(np.asarray(spectrum(sub), dtype=float), 0.0)
    energy = np.einsum("jk,k->j", dens, wts) * df / (3.0 * m)
    amp = np.sqrt(2.0 * energy)
    for a in (edges, df, amp):
        a.setflags(write=False)
    return edges, df, amp


def harmonic_components(
    spectrum: Any,
    lo: float,
    hi: float,
    n: int,
    rng: np.random.Generator,
    *,
    log: bool = False,
    bins: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Random components of a harmonic superposition of a one-sided spectrum.

    The band ``[lo, hi]`` is cut into ``n`` bins (equal widths, or equal ratios with
    ``log=True``); each component sits at a uniformly random frequency inside its bin (so the
    sum never repeats) with a uniform random phase. Its amplitude is
    ``sqrt(2 int_bin S df)`` (the bin's energy, 16-interval Simpson rule) rather than
    ``sqrt(2 S(f_j) df)``: the same to first order, but the energy of every bin, hence of
    every band of whole bins and the variance of the sum, is exact whatever frequency was
    drawn. Draws: ``n`` uniforms for the frequencies, then ``n`` phases.

    Args:
        spectrum: Callable ``S(f)`` on arrays (any one-sided density).
        lo: Lowest frequency (same unit as the argument of ``spectrum``), ``> 0`` if ``log``.
        hi: Highest frequency, ``> lo``.
        n: Number of components, ``>= 1``.
        rng: Generator to draw from.
        log: Logarithmic bins (for spectra spread over decades, like wind gusts).
        bins: :func:`harmonic_bins` of these arguments, computed before (``None``: computed
            here).

    Returns:
        ``(f, a, phase)``: frequencies, amplitudes (sqrt of the spectrum's variance units;
        read-only) and phases (rad), each of length ``n``.
    """
    edges, df, amp = harmonic_bins(spectrum, lo, hi, n, log=log) if bins is None else bins
    f = edges[:-1] + rng.random(n) * df
    phase = rng.uniform(0.0, 2.0 * math.pi, n)
    return f, amp, phase


#: grid points per block of :func:`harmonic_sums` (the block factor is computed directly)
HARMONIC_BLOCK = 64


@njit(nogil=True)
def _in_block(dt, w, zr, zi):  # type: ignore[no-untyped-def]
    """The in-block factors ``exp(i w_j (dt m))`` of :func:`harmonic_sums` into ``zr``, ``zi``
    (N, 64): their cosines and sines."""
    for j in range(w.shape[0]):
        for m in range(HARMONIC_BLOCK):
            x = (dt * m) * w[j]
            zr[j, m] = math.cos(x)
            zi[j, m] = math.sin(x)


def harmonic_table(dt: float, w: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """The in-block factors of :func:`harmonic_sums` on the grid step ``dt`` (s) for the
    angular frequencies ``w`` (rad/s): ``(cos, sin)`` of ``w_j dt m``, (N, 64) each, computed
    once for a realisation whose pieces are summed one by one (``table=``)."""
    w = np.ascontiguousarray(w, dtype=float)
    zr = np.empty((w.shape[0], HARMONIC_BLOCK))
    zi = np.empty((w.shape[0], HARMONIC_BLOCK))
    _in_block(float(dt), w, zr, zi)
    return zr, zi


@njit(inline="always")
def _harmonic_block(b, t0, dt, start, end, w, eps, c, imag, zr, zi, out, cb, sb, acc_r, acc_i):  # type: ignore[no-untyped-def]
    """Block ``b`` of :func:`harmonic_rows` (its samples in ``[start, end)``), with the work
    arrays ``cb``, ``sb`` (N,) and ``acc_r``, ``acc_i`` (64,)."""
    nj = w.shape[0]
    tb = t0 + (HARMONIC_BLOCK * dt) * b
    for j in range(nj):
        x = tb * w[j] + eps[j]
        cb[j] = math.cos(x)
        sb[j] = math.sin(x)
    k0 = b * HARMONIC_BLOCK
    m0 = start - k0 if start > k0 else 0
    m1 = min(HARMONIC_BLOCK, end - k0)
    for r in range(c.shape[0]):
        acc_r[:] = 0.0
        acc_i[:] = 0.0
        for j in range(nj):
            # the block factor times the weight (a complex product with c_j + 0 i)
            ar = cb[j] * c[r, j]
            ai = sb[j] * c[r, j]
            if imag:  # both parts in one pass over the in-block factors
                for m in range(HARMONIC_BLOCK):
                    x = zr[j, m]
                    y = zi[j, m]
                    acc_r[m] += ar * x - ai * y
                    acc_i[m] += ar * y + ai * x
            else:
                for m in range(HARMONIC_BLOCK):
                    acc_r[m] += ar * zr[j, m] - ai * zi[j, m]
        for m in range(m0, m1):
            out[r, 0, k0 + m - start] = acc_r[m]
        if imag:
            for m in range(m0, m1):
                out[r, 1, k0 + m - start] = acc_i[m]


@njit(nogil=True)
def harmonic_rows(first, end, t0, dt, start, n, w, eps, c, imag, zr, zi, out):  # type: ignore[no-untyped-def]
    """:func:`harmonic_sums` of the real weights ``c`` (R, N) at the grid points ``k = start
    ... start + n - 1`` into ``out`` (R, 2, n): the real parts (``out[r, 0]``) and, where
    ``imag``, the imaginary parts (``out[r, 1]``; else left as they are), of the blocks
    ``first .. end - 1`` of the range (``0 .. -(-(start + n) // 64) - start // 64 - 1``: all of
    it; :func:`harmonic_into` spreads ranges of blocks of a long range over threads). The
    float operations of the NumPy form this replaced, in its order: the phase ``w_j (t0 + 64
    dt b) + eps_j`` and ``w_j (dt m)``, ``exp(i x) = cos x + i sin x``, the block factor
    times ``c``, and each sample summed over ``j`` in order (the real part ``sum (a_re z_re -
    a_im z_im)``; the in-block factors ``zr``, ``zi`` from :func:`_in_block`), so that a
    grid's samples stay the same floats; the samples of a block are summed side by side
    (independent sums: vectorised). The blocks are those of the grid from ``k = 0`` (``k =
    64 b + m``), each computed directly, so any range of samples is the same floats as in the
    whole grid (a partly read block is summed whole)."""
    nj = w.shape[0]
    stop = start + n
    cb, sb = np.empty(nj), np.empty(nj)
    acc_r, acc_i = np.empty(HARMONIC_BLOCK), np.empty(HARMONIC_BLOCK)
    for b in range(start // HARMONIC_BLOCK + first, start // HARMONIC_BLOCK + end):
        _harmonic_block(b, t0, dt, start, stop, w, eps, c, imag, zr, zi, out, cb, sb, acc_r,
                        acc_i)  # fmt: skip


#: samples from which :func:`harmonic_into` sums ranges of blocks on threads
PARALLEL_SAMPLES = 1024


def harmonic_into(args: tuple[Any, ...]) -> None:
    """:func:`harmonic_rows` of ``args`` ``(t0, dt, start, n, w, eps, c, imag, zr, zi, out)``,
    on every block of the range: in ranges of blocks on threads for a range of at least
    :data:`PARALLEL_SAMPLES` samples where this thread may use them
    (:func:`shipgym._jit.spread_rows`), the same floats either way."""
    start, n = args[2], args[3]
    blocks = -(-(start + n) // HARMONIC_BLOCK) - start // HARMONIC_BLOCK
    fn = entry(harmonic_rows, (np.int64(0), np.int64(blocks), *args))
    if n >= PARALLEL_SAMPLES and threads_ok():
        spread_rows(fn, blocks, *args)
    else:
        fn(0, blocks, *args)


def harmonic_sums(
    t0: float,
    dt: float,
    n: int,
    w: NDArray[np.float64],
    eps: NDArray[np.float64],
    weights: ArrayLike,
    *,
    real: bool = False,
    start: int = 0,
    table: tuple[NDArray[np.float64], ...] | None = None,
) -> NDArray[np.complex128] | NDArray[np.float64]:
    """Phasor sums ``sum_j c[r, j] exp(i (w_j t_k + eps_j))`` on the grid ``t_k = t0 + k dt``,
    ``k = start ... start + n - 1``.

    With ``k = 64 b + m`` the phasor factorises into a block factor ``exp(i (w_j (t0 + 64 b dt)
    + eps_j))`` and an in-block factor ``exp(i w_j m dt)``, so each row is one small product
    instead of ``n x N`` complex exponentials; every block factor is computed directly, so no
    rounding error accumulates. Compiled (:func:`harmonic_rows`); complex weights are summed
    as their real and imaginary parts' sums.

    Args:
        t0: First time (s).
        dt: Grid step (s).
        n: Number of grid points.
        w: Angular frequencies (rad/s), shape ``(N,)``.
        eps: Phases (rad), shape ``(N,)``.
        weights: Real or complex weights, shape ``(R, N)`` (or ``(N,)`` for one row).
        real: return the real parts only (``sum c_j cos(w_j t + eps_j)``, real weights;
            the imaginary parts are not computed).
        start: The first grid point (``>= 0``): the points ``start ... start + n - 1`` of
            the grid from ``t0`` are the same floats as in the whole grid (a piece of a chunk
            computed on its own).
        table: :func:`harmonic_table` of ``dt`` and ``w`` (``None``: computed here).

    Returns:
        Complex array ``(R, n)`` (or ``(n,)`` for 1-D weights). The real part of a row is
        ``sum c_j cos(w_j t + eps_j)``, the imaginary part ``sum c_j sin(w_j t + eps_j)``;
        with ``real``, those real parts as a float array of the same shape.
    """
    c = np.asarray(weights)
    one = c.ndim == 1
    c = np.atleast_2d(c)
    w, eps = law_input(w), law_input(eps)  # (the wind's frozen spectrum: read-only)
    if np.iscomplexobj(c):
        if real:
            raise ValueError("harmonic_sums(real=True) takes real weights")
        re = harmonic_sums(t0, dt, n, w, eps, c.real, start=start, table=table)
        im = harmonic_sums(t0, dt, n, w, eps, c.imag, start=start, table=table)
        out_c = re + 1j * im
        return out_c[0] if one else out_c
    c = law_input(c)
    rows = np.zeros((c.shape[0], 2, n))
    zr, zi = harmonic_table(dt, w) if table is None else table
    harmonic_into((float(t0), float(dt), int(start), int(n), w, eps, c, not real, zr, zi, rows))
    if real:
        out = rows[:, 0]
    else:
        out = np.empty((c.shape[0], n), dtype=complex)
        out.real = rows[:, 0]
        out.imag = rows[:, 1]
    return out[0] if one else out


# ---------------------------------------------------------------------------------------------
# Fossen's linear shaping filter
# ---------------------------------------------------------------------------------------------


def shaping_filter_psd(w: ArrayLike, lam: float, w0: float, sigma: float) -> NDArray[np.float64]:
    """PSD of Fossen's 2nd-order wave shaping filter driven by unit white noise.

    ``h(s) = K_w s / (s^2 + 2 lam w0 s + w0^2)``, ``K_w = 2 lam w0 sigma``, so
    ``P(w) = |h(jw)|^2 = 4 (lam w0 sigma)^2 w^2 / ((w0^2 - w^2)^2 + 4 (lam w0 w)^2)`` with the
    peak ``P(w0) = sigma^2`` (Fossen 2011 ch. 8.2.5).

    Args:
        w: Angular frequencies (rad/s).
        lam: Relative damping (1), ``> 0``.
        w0: Peak frequency (rad/s), ``> 0``.
        sigma: ``sqrt`` of the peak value (units of ``sqrt(S)``).

    Returns:
        ``P(w)`` in the units of ``sigma^2``.
    """
    ww = np.asarray(w, dtype=float)
    num = 4.0 * (lam * w0 * sigma) ** 2 * ww * ww
    return num / ((w0 * w0 - ww * ww) ** 2 + 4.0 * (lam * w0 * ww) ** 2)


@functools.lru_cache(maxsize=64)
def fit_shaping_filter_lambda(kind: str = "jonswap", gamma: float = 3.3) -> float:
    """Least-squares damping ``lambda`` of Fossen's shaping filter fitted to a wave spectrum.

    Method of MSS ``exLinspec.m``: ``w0 = w_p`` and ``sigma^2 = max S`` are
    fixed, ``lambda`` minimises ``sum (P(w) - S(w))^2`` over ``0 < w <= 4 w_p``. The spectrum
    shape is scale-invariant, so the result depends only on the spectrum kind and ``gamma``
    (notes: 0.257 for PM, 0.102 for JONSWAP gamma 3.3, 0.081 for gamma 5).

    Args:
        kind: ``"jonswap"`` or ``"pm"``.
        gamma: JONSWAP peak factor (ignored for ``"pm"``).

    Returns:
        lambda (1).
    """
    from scipy.optimize import minimize_scalar

    w = np.linspace(0.02, 4.0, 2000)  # w / w_p, Tp = 2 pi
    S = wave_spectrum(kind, w, 1.0, 2.0 * math.pi, gamma)
    sig = math.sqrt(float(S.max()))
    w0 = float(w[int(np.argmax(S))])

    def cost(lam: float) -> float:
        return float(np.sum((shaping_filter_psd(w, lam, w0, sig) - S) ** 2))

    res = minimize_scalar(cost, bounds=(0.01, 1.0), method="bounded", options={"xatol": 1e-6})
    return float(res.x)


# ---------------------------------------------------------------------------------------------
# Froude scaling
# ---------------------------------------------------------------------------------------------

#: Quantity kind -> (exponent of lambda, power of the density ratio) of the full-scale ->
#: model factor ``density_ratio^p / lambda^e`` (frequency has ``e = -0.5``).
FROUDE_EXPONENTS: dict[str, tuple[float, int]] = {
    "length": (1.0, 0),
    "area": (2.0, 0),
    "volume": (3.0, 0),
    "time": (0.5, 0),
    "period": (0.5, 0),
    "velocity": (0.5, 0),
    "acceleration": (0.0, 0),
    "angle": (0.0, 0),
    "frequency": (-0.5, 0),
    "angular_velocity": (-0.5, 0),
    "mass": (3.0, 1),
    "force": (3.0, 1),
    "moment": (4.0, 1),
    "inertia": (5.0, 1),
    "power": (3.5, 1),
}


def froude_factor(kind: str, scale: float, density_ratio: float = 1.0) -> float:
    """Factor that turns a full-scale quantity into its model-scale value (Froude similarity).

    Args:
        kind: A key of :data:`FROUDE_EXPONENTS` (``length``, ``time``, ``velocity``,
            ``frequency``, ``force``, ``moment``, ...).
        scale: Geometric scale ``lambda = L_ship / L_model`` (24 for the Blue Lady), ``> 0``.
        density_ratio: ``rho_model / rho_ship`` for mass, force, moment, inertia and power
            (e.g. 1000/1025 for salt-to-fresh water); ignored for the kinematic kinds.

    Returns:
        ``density_ratio^p / lambda^e`` (1).

    Raises:
        ValueError: For an unknown kind (the message lists the valid ones) or a bad scale.
    """
    try:
        e, p = FROUDE_EXPONENTS[kind]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown Froude quantity kind {kind!r}; valid kinds are: {', '.join(FROUDE_EXPONENTS)}"
        ) from None
    scale = _check_pos("scale", scale)
    density_ratio = _check_pos("density_ratio", density_ratio)
    return density_ratio**p / scale**e


def froude_scale(
    kind: str,
    value: Any,
    scale: float,
    *,
    to_model: bool = True,
    density_ratio: float = 1.0,
) -> Any:
    """Froude-scale a value (float or array) between full scale and model scale.

    Example: ``froude_scale("period", 8.78, 24) == 1.792`` (s);
    ``froude_scale("length", 2.0, 24) == 0.0833`` (m).

    Args:
        kind: Quantity kind, see :func:`froude_factor`.
        value: Full-scale value (or model value with ``to_model=False``).
        scale: Geometric scale ``lambda`` (> 0).
        to_model: ``True``: full scale -> model; ``False``: model -> full scale.
        density_ratio: ``rho_model / rho_ship`` for the dynamic kinds.

    Returns:
        The scaled value (float for a real input, array for an array).
    """
    k = froude_factor(kind, scale, density_ratio)
    if not to_model:
        k = 1.0 / k
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return float(value) * k
    return np.asarray(value, dtype=float) * k


def model_length(value: Any, scale: float) -> Any:
    """Full-scale length (m) -> model length (m): ``/ lambda``."""
    return froude_scale("length", value, scale)


def model_time(value: Any, scale: float) -> Any:
    """Full-scale time or period (s) -> model time (s): ``/ sqrt(lambda)``."""
    return froude_scale("time", value, scale)


def model_velocity(value: Any, scale: float) -> Any:
    """Full-scale velocity (m/s) -> model velocity (m/s): ``/ sqrt(lambda)``."""
    return froude_scale("velocity", value, scale)


def model_frequency(value: Any, scale: float) -> Any:
    """Full-scale frequency (Hz or rad/s) -> model frequency: ``* sqrt(lambda)``."""
    return froude_scale("frequency", value, scale)


def model_force(value: Any, scale: float, density_ratio: float = 1.0) -> Any:
    """Full-scale force (N) -> model force (N): ``* density_ratio / lambda^3``."""
    return froude_scale("force", value, scale, density_ratio=density_ratio)


def model_moment(value: Any, scale: float, density_ratio: float = 1.0) -> Any:
    """Full-scale moment (N m) -> model moment (N m): ``* density_ratio / lambda^4``."""
    return froude_scale("moment", value, scale, density_ratio=density_ratio)
