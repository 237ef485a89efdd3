"""Tests of shipgym.disturbances.spectra and the spectral (NPD / Harris) wind-gust options."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import gamma as gamma_fn

from shipgym.disturbances import Wind, WindConfig
from shipgym.disturbances.spectra import (
    FROUDE_EXPONENTS,
    dnv_gamma,
    fit_shaping_filter_lambda,
    froude_factor,
    froude_scale,
    gauss_markov_psd,
    harmonic_components,
    harmonic_into,
    harmonic_rows,
    harmonic_sums,
    harmonic_table,
    harris_wind_spectrum,
    jonswap,
    model_force,
    model_frequency,
    model_length,
    model_moment,
    model_time,
    model_velocity,
    norsok_peak_period,
    npd_wind_spectrum,
    pierson_moskowitz,
    shaping_filter_psd,
    significant_wave_height,
    spectral_moment,
    wave_spectrum,
    wind_gust_spectrum,
)
from shipgym.dynamics import BLUE_LADY_WINDAGE

W = np.linspace(1e-3, 40.0, 100_001)

# ---------------------------------------------------------------------------------------------
# wave spectra
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("gamma", [1.0, 2.0, 3.3, 5.0, 7.0])
def test_jonswap_m0_is_hs2_over_16(gamma: float) -> None:
    Hs, Tp = 2.0, 8.8
    m0 = spectral_moment(W, jonswap(W, Hs, Tp, gamma))
    assert 4.0 * math.sqrt(m0) == pytest.approx(Hs, rel=0.01)  # DNV normalisation


def test_pierson_moskowitz_m0_peak_and_itttc_form() -> None:
    Hs, Tp = 0.083, 1.79
    S = pierson_moskowitz(W, Hs, Tp)
    assert 4.0 * math.sqrt(spectral_moment(W, S)) == pytest.approx(Hs, rel=1e-3)
    wp = 2 * math.pi / Tp
    # peak of S_PM at w_p (5/4 w_p^4 w^-4 = 5/4 -> dS/dw = 0 at w = w_p)
    assert W[np.argmax(S)] == pytest.approx(wp, abs=1e-3)
    # ITTC modal form of the modified PM spectrum: A = 487 Hs^2 / T0^4, B = 1949 / T0^4
    w = np.array([2.0, 3.5, 6.0])
    itt = 487.0 * Hs**2 / Tp**4 * w**-5 * np.exp(-1949.0 / Tp**4 * w**-4)
    assert pierson_moskowitz(w, Hs, Tp) == pytest.approx(itt, rel=0.01)  # rounded constants
    assert pierson_moskowitz([0.0, -1.0], Hs, Tp).tolist() == [0.0, 0.0]


def test_jonswap_shape() -> None:
    Hs, Tp = 1.0, 2 * math.pi  # w_p = 1
    assert jonswap(W, Hs, Tp, 1.0) == pytest.approx(pierson_moskowitz(W, Hs, Tp))
    # at the peak the enhancement is gamma times the normalisation
    ratio = jonswap([1.0], Hs, Tp, 3.3)[0] / pierson_moskowitz([1.0], Hs, Tp)[0]
    assert ratio == pytest.approx(3.3 * (1 - 0.287 * math.log(3.3)))
    # sigma 0.07 below, 0.09 above the peak: enhancement exponent at +-0.1 w_p
    g = 3.3

    def exponent(w: float) -> float:
        r = jonswap([w], Hs, Tp, g)[0] / pierson_moskowitz([w], Hs, Tp)[0]
        return math.log(r / (1 - 0.287 * math.log(g))) / math.log(g)

    assert exponent(0.9) == pytest.approx(math.exp(-(0.1**2) / (2 * 0.07**2)))
    assert exponent(1.1) == pytest.approx(math.exp(-(0.1**2) / (2 * 0.09**2)))


def test_wave_spectrum_dispatch_and_errors() -> None:
    assert wave_spectrum(None, [1.0, 2.0], 1.0, 5.0).tolist() == [0.0, 0.0]
    assert wave_spectrum("pm", [1.0], 1.0, 5.0) == pytest.approx(pierson_moskowitz([1.0], 1, 5))
    with pytest.raises(ValueError, match="unknown wave spectrum 'bretschneider'"):
        wave_spectrum("bretschneider", [1.0], 1.0, 5.0)
    with pytest.raises(ValueError, match="gamma"):
        jonswap([1.0], 1.0, 5.0, 0.5)
    with pytest.raises(ValueError, match="Tp must be > 0"):
        jonswap([1.0], 1.0, 0.0)
    with pytest.raises(ValueError, match="Hs must be"):
        pierson_moskowitz([1.0], -1.0, 5.0)


def test_dnv_gamma_and_norsok() -> None:
    assert dnv_gamma(4.0, 7.0) == 5.0  # k = 3.5
    assert dnv_gamma(1.0, 4.5) == pytest.approx(math.exp(5.75 - 1.15 * 4.5))
    assert dnv_gamma(2.0, 8.8) == 1.0  # k = 6.2
    assert norsok_peak_period(2.0) == pytest.approx(8.78, abs=0.01)
    assert norsok_peak_period(0.6) == pytest.approx(6.9, abs=0.05)  # BF3 of the Beaufort table
    assert significant_wave_height([1.0, -1.0, 1.0, -1.0]) == pytest.approx(4.0)


# ---------------------------------------------------------------------------------------------
# wind-gust spectra
# ---------------------------------------------------------------------------------------------


def test_npd_formula_point_and_variance() -> None:
    U = 10.0
    f = 0.01
    ft = 172.0 * f
    expect = 320.0 / (1.0 + ft**0.468) ** (5.0 / (3.0 * 0.468))
    assert npd_wind_spectrum([f], U)[0] == pytest.approx(expect)
    # variance (1/n) B(1/n, 2/(3n)) * 320/172 (U/10)^2.75 at z = 10 (closed form)
    n = 0.468
    beta = gamma_fn(1 / n) * gamma_fn(2 / (3 * n)) / gamma_fn(1 / n + 2 / (3 * n))
    var = 320.0 / 172.0 * beta / n
    fg = np.geomspace(1e-7, 1e3, 200_001)
    num = np.trapezoid(npd_wind_spectrum(fg, U) * fg, np.log(fg))
    assert num == pytest.approx(var, rel=2e-3)
    assert npd_wind_spectrum([0.1], 0.0).tolist() == [0.0]
    # height dependence (z/10)^0.45 at f = 0
    assert npd_wind_spectrum([0.0], U, z=20.0)[0] == pytest.approx(320 * 2**0.45)


def test_harris_variance_closed_form() -> None:
    U, kappa = 10.0, 0.0026
    f = np.geomspace(1e-8, 1e4, 200_001)
    num = np.trapezoid(harris_wind_spectrum(f, U) * f, np.log(f))
    # int_0^inf (2 + x^2)^(-5/6) dx = 2^(-1/3) sqrt(pi) Gamma(1/3) / (2 Gamma(5/6))
    integral = 2 ** (-1 / 3) * math.sqrt(math.pi) * gamma_fn(1 / 3) / (2 * gamma_fn(5 / 6))
    assert num == pytest.approx(4 * kappa * U**2 * integral, rel=2e-3)
    assert harris_wind_spectrum([0.0], U)[0] == pytest.approx(4 * kappa * 1800 * U / 2 ** (5 / 6))


def test_gauss_markov_psd_integrates_to_variance() -> None:
    f = np.geomspace(1e-7, 1e5, 400_001)
    assert np.trapezoid(gauss_markov_psd(f, 0.45, 5.0) * f, np.log(f)) == pytest.approx(
        0.45**2, rel=1e-3
    )


def test_wind_gust_spectrum_froude_scaling_keeps_variance_over_lambda() -> None:
    lam, Um = 24.0, 1.9
    fm = np.geomspace(1e-6, 1e3, 200_001)
    for kind in ("npd", "harris"):
        vm = np.trapezoid(wind_gust_spectrum(kind, fm, Um, lam) * fm, np.log(fm))
        fs = fm / math.sqrt(lam)
        full = npd_wind_spectrum if kind == "npd" else harris_wind_spectrum
        vs = np.trapezoid(full(fs, Um * math.sqrt(lam)) * fs, np.log(fs))
        assert vm == pytest.approx(vs / lam, rel=1e-6)
    with pytest.raises(ValueError, match="'npd', 'harris'"):
        wind_gust_spectrum("davenport", fm, 1.0)


# ---------------------------------------------------------------------------------------------
# shaping filter and Froude scaling
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kind", "gamma", "lam"), [("pm", 1.0, 0.257), ("jonswap", 3.3, 0.102), ("jonswap", 5.0, 0.081)]
)
def test_shaping_filter_lambda_matches_notes(kind: str, gamma: float, lam: float) -> None:
    assert fit_shaping_filter_lambda(kind, gamma) == pytest.approx(lam, abs=0.002)


def test_shaping_filter_psd_peak() -> None:
    assert shaping_filter_psd([2.0], 0.1, 2.0, 0.3)[0] == pytest.approx(0.09)
    assert shaping_filter_psd([0.0], 0.1, 2.0, 0.3)[0] == 0.0


def test_froude_factors() -> None:
    lam = 24.0
    assert froude_factor("force", lam) == pytest.approx(1 / 13_824)
    assert froude_factor("moment", lam) == pytest.approx(1 / 331_776)
    assert froude_factor("time", lam) == pytest.approx(0.2041, abs=1e-4)
    assert froude_factor("frequency", lam) == pytest.approx(4.899, abs=1e-3)
    assert froude_factor("force", lam, 1000 / 1025) == pytest.approx(1000 / 1025 / 13_824)
    assert froude_factor("angle", lam) == 1.0
    assert model_length(2.0, lam) == pytest.approx(0.0833, abs=1e-4)  # BF5 Hs
    assert model_time(8.78, lam) == pytest.approx(1.79, abs=0.005)  # BF5 Tp
    assert model_velocity(9.35, lam) == pytest.approx(1.91, abs=0.005)
    assert model_frequency(1.0, lam) == pytest.approx(math.sqrt(24))
    assert model_force(13_824.0, lam) == pytest.approx(1.0)
    assert model_moment(331_776.0, lam) == pytest.approx(1.0)
    for kind in FROUDE_EXPONENTS:
        v = froude_scale(kind, froude_scale(kind, 3.7, lam), lam, to_model=False)
        assert v == pytest.approx(3.7)
    arr = froude_scale("length", [24.0, 48.0], lam)
    assert arr.tolist() == pytest.approx([1.0, 2.0])
    with pytest.raises(ValueError, match="valid kinds are"):
        froude_factor("speed", lam)
    with pytest.raises(ValueError, match="scale must be > 0"):
        froude_factor("length", 0.0)


def test_harmonic_sums_match_direct_evaluation() -> None:
    rng = np.random.default_rng(0)
    w = rng.uniform(0.5, 20.0, 37)
    eps = rng.uniform(0, 2 * np.pi, 37)
    c = rng.normal(size=(2, 37))
    t0, dt, n = 1234.5, 0.05, 200
    got = harmonic_sums(t0, dt, n, w, eps, c)
    t = t0 + dt * np.arange(n)
    ref = np.exp(1j * (np.multiply.outer(t, w) + eps)) @ c.T
    assert np.allclose(got, ref.T, atol=1e-11)
    assert harmonic_sums(t0, dt, n, w, eps, c[0]).shape == (n,)


def test_harmonic_sums_are_the_numpy_blocks_floats() -> None:
    """The compiled sums are the floats of the NumPy block form they replaced (the gust and
    wave grids, hence every episode, stay the same), real parts alone included."""
    rng = np.random.default_rng(3)
    for nj, t0, dt in ((200, 0.0, 0.1), (100, 3 * 4096 * 0.0443, 0.0443), (7, 12.5, 0.25)):
        w = rng.uniform(0.01, 6.0, nj)
        eps = rng.uniform(0, 2 * np.pi, nj)
        c = rng.uniform(0.0, 2.0, (2, nj))
        c[0, :3] = 0.0  # zero amplitudes (a spectrum's empty bins)
        n = 4097
        n_blk = -(-n // 64)
        zb = np.exp(1j * (np.multiply.outer(t0 + (64 * dt) * np.arange(n_blk), w) + eps))
        zm = np.exp(1j * np.multiply.outer(dt * np.arange(64), w))
        ref = np.stack([np.einsum("bj,mj->bm", zb * c[r], zm).ravel()[:n] for r in range(2)])
        got = harmonic_sums(t0, dt, n, w, eps, c)
        assert np.array_equal(got, ref)
        assert np.array_equal(harmonic_sums(t0, dt, n, w, eps, c[1], real=True), ref[1].real)


@pytest.mark.parametrize("start,n", [(0, 4097), (37, 3000), (576, 3521), (100, 5)])
def test_harmonic_rows_on_threads_are_the_serial_floats(start: int, n: int, monkeypatch) -> None:
    """A chunk's sums in ranges of blocks on threads are the floats of the serial loop over
    all its blocks, for any range of samples."""
    from shipgym.disturbances import spectra

    rng = np.random.default_rng(5)
    w = rng.uniform(0.3, 3.0, 100)
    eps = rng.uniform(0, 2 * np.pi, 100)
    c = rng.uniform(0.0, 1.0, (3, 100))
    zr, zi = harmonic_table(0.07, w)
    args = (11.0, 0.07, start, n, w, eps, c, True, zr, zi)
    serial, threads = np.zeros((3, 2, n)), np.zeros((3, 2, n))
    harmonic_rows(0, -(-(start + n) // 64) - start // 64, *args, serial)
    monkeypatch.setattr(spectra, "PARALLEL_SAMPLES", 0)
    harmonic_into((*args, threads))
    assert np.array_equal(serial, threads) and np.all(serial[:, 1] != 0.0)


def test_harmonic_components_bin_energy_exact() -> None:
    rng = np.random.default_rng(3)
    f, a, ph = harmonic_components(lambda x: np.exp(-x), 0.1, 3.0, 29, rng, log=True)
    edges = np.geomspace(0.1, 3.0, 30)
    assert np.all((f >= edges[:-1]) & (f <= edges[1:]))
    assert np.sum(a**2) / 2 == pytest.approx(math.exp(-0.1) - math.exp(-3.0), rel=1e-7)
    assert np.all((ph >= 0) & (ph < 2 * np.pi))


# ---------------------------------------------------------------------------------------------
# spectral wind gusts
# ---------------------------------------------------------------------------------------------


def _band_ratios(cfg: WindConfig, seed: int, duration: float) -> tuple[list[float], Wind]:
    """Energy in log bands of the gust (PSD of a long series) over the target energy.

    A Hann-windowed periodogram of the whole record resolves the lines finely (df = 1 /
    duration), so the energy of a band is the energy of the components inside it.
    """
    from scipy.signal import periodogram

    w = Wind(cfg, windage=BLUE_LADY_WINDAGE)
    w.reset(np.random.default_rng(seed))
    fs = 1.0 / cfg.sample_period
    t = np.arange(0.0, duration, cfg.sample_period)
    V, _ = w.series(t)
    f, P = periodogram(V - cfg.speed, fs=fs, window="hann")
    lo, hi = cfg.gust_band
    # four bands of 25 whole synthesis bins each, from around the peak of f S(f) (or from
    # where the periodogram resolves neighbouring lines) upwards
    bins = np.geomspace(lo, hi, cfg.gust_components + 1)
    peak = f[1:][np.argmax((f * cfg.gust_psd(f))[1:])]
    i0 = int(np.searchsorted(bins, max(peak / 2, 400 * f[1])))
    edges = bins[i0 : i0 + 101 : 25]
    ratios = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        m = (f >= a) & (f < b)
        ff = np.geomspace(a, b, 2001)
        tgt = np.trapezoid(cfg.gust_psd(ff) * ff, np.log(ff))
        ratios.append(float(np.sum(P[m]) * (f[1] - f[0]) / tgt))
    return ratios, w


@pytest.mark.parametrize(
    ("kind", "speed", "scale"), [("npd", 1.91, 24.0), ("harris", 1.91, 24.0), ("npd", 3.0, 1.0)]
)
def test_spectral_gust_psd_matches_target(kind: str, speed: float, scale: float) -> None:
    cfg = WindConfig(speed=speed, gust_spectrum=kind, spectrum_scale=scale)
    ratios, w = _band_ratios(cfg, seed=2, duration=16_000.0)
    assert all(abs(r - 1.0) < 0.10 for r in ratios), ratios
    # the realisation's variance is the band variance, and the series has it
    V, _ = w.series(np.arange(0.0, 16_000.0, cfg.sample_period))
    assert float(np.mean(V)) == pytest.approx(speed, abs=0.1 * cfg.gust_sigma)
    assert float(np.std(V)) == pytest.approx(cfg.gust_sigma, rel=0.10)


def test_spectral_gust_sigma_and_rescale() -> None:
    cfg = WindConfig(speed=1.91, gust_spectrum="npd", spectrum_scale=24.0)
    lo, hi = cfg.gust_band
    assert lo == pytest.approx(math.sqrt(24) / 3600)
    assert hi == pytest.approx(2.5)  # min(sqrt(24) Hz, 0.25 / 0.1 s)
    f = np.geomspace(lo, hi, 20001)
    var = np.trapezoid(wind_gust_spectrum("npd", f, 1.91, 24.0) * f, np.log(f))
    assert cfg.gust_sigma == pytest.approx(math.sqrt(var), rel=1e-4)
    # about 9 % turbulence intensity for NPD at U10 = 9.35 m/s over the band
    assert 0.07 < cfg.gust_sigma / cfg.speed < 0.12
    cfg2 = WindConfig(speed=1.91, gust_spectrum="npd", spectrum_scale=24.0, gust_std=0.3)
    assert cfg2.gust_sigma == 0.3
    ff = np.geomspace(lo, hi, 20001)
    assert np.trapezoid(cfg2.gust_psd(ff) * ff, np.log(ff)) == pytest.approx(0.09, rel=1e-3)
    w = Wind(cfg2, windage=BLUE_LADY_WINDAGE)
    w.reset(np.random.default_rng(5))
    V, _ = w.series(np.arange(0, 8000.0, 0.1))
    assert float(np.std(V)) == pytest.approx(0.3, rel=0.1)
    harris = WindConfig(speed=3.0, gust_spectrum="harris")
    assert harris.gust_band[0] == pytest.approx(0.01)
    # Gauss-Markov PSD for reference: 4 sigma^2 T / (1 + (2 pi f T)^2)
    gm = WindConfig(speed=3.0)
    assert gm.gust_psd([0.0])[0] == pytest.approx(4 * 0.45**2 * 5.0)


def test_spectral_gust_same_seed_same_realisation() -> None:
    cfg = WindConfig(speed=3.0, gust_spectrum="harris", direction_std=0.1)
    a, b, c = (
        Wind(cfg, windage=BLUE_LADY_WINDAGE),
        Wind(cfg, windage=BLUE_LADY_WINDAGE),
        Wind(cfg, windage=BLUE_LADY_WINDAGE),
    )
    a.reset(np.random.default_rng(11))
    b.reset(np.random.default_rng(11))
    c.reset(np.random.default_rng(12))
    ts = [0.0, 3.14, 400.0, 409.6, 1000.05, 5000.0]
    va = [a.at(t) for t in ts]
    assert va == [b.at(t) for t in reversed(ts)][::-1]  # query order does not matter
    assert va != [c.at(t) for t in ts]
    V, beta = a.series(np.array(ts))
    assert V.tolist() == pytest.approx([v for v, _ in va], abs=1e-12)
    assert beta.tolist() == pytest.approx([d for _, d in va], abs=1e-12)
    # direction gust still Gauss-Markov with its std
    _, bb = a.series(np.arange(0, 20000.0, 0.1))
    assert float(np.std(bb)) == pytest.approx(0.1, rel=0.25)


def test_spectral_calm_is_constant() -> None:
    cfg = WindConfig(speed=0.0, gust_spectrum="npd", spectrum_scale=24.0)
    assert cfg.gust_sigma == 0.0 and cfg.is_constant
    w = Wind(cfg, windage=BLUE_LADY_WINDAGE)
    w.reset(None)
    assert w.at(12.0) == (0.0, 0.0)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"gust_spectrum": "davenport"}, "gust_spectrum must be one of"),
        ({"spectrum_scale": 0.0}, "spectrum_scale must be > 0"),
        ({"gust_components": 0}, "gust_components must be an int"),
        ({"gust_components": 10.0}, "gust_components must be an int"),
        ({"gust_f_min": -1.0}, "gust_f_min must be > 0"),
        ({"gust_f_max": 6.0}, "Nyquist"),
        ({"gust_f_min": 0.5, "gust_f_max": 0.1}, "gust_f_min must be < gust_f_max"),
    ],
)
def test_wind_config_spectral_validation(kw: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        WindConfig(speed=3.0, **kw)


def test_wind_config_from_dict_accepts_new_fields() -> None:
    cfg = WindConfig.from_dict({"speed": 2.0, "gust_spectrum": "npd", "spectrum_scale": 24})
    assert cfg.is_spectral and cfg.spectrum_scale == 24
    with pytest.raises(ValueError, match="valid keys are"):
        WindConfig.from_dict({"speed": 2.0, "spectrum": "npd"})
