"""Tests of shipgym.disturbances.waves: realisation, drift loads and first-order WF motion."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import periodogram

from shipgym.disturbances import WaveConfig, Waves, al_takie_hf_polynomial, drift_coefficients
from shipgym.disturbances.spectra import RHO_WATER, G
from shipgym.dynamics.params import BLUE_LADY_HULL

BF5 = {"Hs": 2.0 / 24, "Tp": (4.883 + 2.68 * 2.0**0.54) / math.sqrt(24)}  # NORSOK Tp


def _waves(seed: int = 1, **kw: object) -> Waves:
    w = Waves(WaveConfig(**kw), hull=BLUE_LADY_HULL)  # type: ignore[arg-type]
    w.reset(np.random.default_rng(seed))
    return w


# ---------------------------------------------------------------------------------------------
# elevation
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kw",
    [
        {"spectrum": "jonswap", **BF5},
        {"spectrum": "jonswap", "Hs": 0.05, "Tp": 1.0, "gamma": 3.3},  # lake
        {"spectrum": "pm", "Hs": 0.1, "Tp": 2.0},
    ],
)
def test_elevation_psd_and_hs_match_target(kw: dict) -> None:
    w = _waves(seed=4, **kw)
    cfg = w.config
    dt, n = 0.1, 2**15
    zeta = w.elevation(np.arange(n) * dt)
    # Hs of the record and of the components within 5 % (the band holds > 99 % of m0)
    assert 4.0 * float(np.std(zeta)) == pytest.approx(cfg.Hs, rel=0.05)
    assert w.hs_check() == pytest.approx(1.0, abs=0.01)
    assert w.hs_check(np.arange(n) * dt) == pytest.approx(1.0, rel=0.05)
    # energy per band of 5 whole frequency bins around the peak within 10 %
    f, P = periodogram(zeta, fs=1 / dt, window="hann")
    om, S_meas = 2 * np.pi * f, P / (2 * np.pi)  # m^2 s/rad
    lo, hi = cfg.frequency_range
    bins = np.linspace(lo, hi, cfg.n_components + 1)
    i0 = int(np.searchsorted(bins, 0.7 * cfg.peak_frequency))
    edges = bins[i0 : i0 + 51 : 5]  # 0.7 w_p .. ~2.2 w_p
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        m = (om >= a) & (om < b)
        meas = float(np.sum(S_meas[m]) * (om[1] - om[0]))
        wg = np.linspace(a, b, 2001)
        target = float(np.trapezoid(cfg.spectral_density(wg), wg))
        assert meas == pytest.approx(target, rel=0.10), (a / cfg.peak_frequency, meas / target)


def test_components_inside_bins_random_and_no_repetition() -> None:
    w = _waves(seed=2, **BF5)
    om, A, eps = w.components
    lo, hi = w.config.frequency_range
    bins = np.linspace(lo, hi, 101)
    assert np.all((om >= bins[:-1]) & (om <= bins[1:]))
    assert not np.allclose(om, 0.5 * (bins[:-1] + bins[1:]))  # not bin centres
    # no repetition after 2 pi / dw (the period of a bin-centre realisation)
    T_rep = 2 * np.pi / (bins[1] - bins[0])
    t = np.arange(0.0, 30.0, 0.05)
    z0, z1 = w.elevation(t), w.elevation(t + T_rep)
    assert float(np.std(z0 - z1)) > 0.5 * float(np.std(z0))


def test_same_seed_same_realisation_and_stream_independence() -> None:
    kw = {**BF5, "first_order": True}
    a, b, c = _waves(7, **kw), _waves(7, **kw), _waves(8, **kw)
    ts = [0.0, 0.05, 12.3, 204.8, 999.95, 3000.0]
    for t in reversed(ts):  # query order does not matter
        b.drift_load(t, 0.3)
        b.wf_motion(t)
    assert [a.drift_load(t, 0.3) for t in ts] == [b.drift_load(t, 0.3) for t in ts]
    assert [a.wf_motion(t) for t in ts] == [b.wf_motion(t) for t in ts]
    assert [a.drift_load(t, 0.3) for t in ts] != [c.drift_load(t, 0.3) for t in ts]
    assert np.array_equal(a.elevation(ts), b.elevation(ts))
    # the parent generator advances by one draw whatever the sea state
    p1, p2 = np.random.default_rng(5), np.random.default_rng(5)
    Waves(WaveConfig(**kw), hull=BLUE_LADY_HULL).reset(p1)  # type: ignore[arg-type]
    Waves(WaveConfig(Hs=0.0), hull=BLUE_LADY_HULL).reset(p2)
    assert p1.integers(2**63) == p2.integers(2**63)
    # the drift realisation does not depend on the first-order switch
    d = _waves(7, **BF5)
    assert [a.drift_load(t, 0.3) for t in ts] == [d.drift_load(t, 0.3) for t in ts]


# ---------------------------------------------------------------------------------------------
# drift
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kw", [BF5, {"Hs": 0.05, "Tp": 1.0}])
def test_mean_drift_over_long_run_matches_analytic(kw: dict) -> None:
    w = _waves(seed=3, **kw)
    psi = 0.7
    n = 100_000  # 5000 s at 0.05 s, through the per-step API
    X = Y = N = 0.0
    for k in range(n):
        x, y, m = w.drift_load(k * 0.05, psi)
        X += x
        Y += y
        N += m
    mean = w.mean_drift_load(psi)
    for got, ref in zip((X / n, Y / n, N / n), mean, strict=True):
        assert got == pytest.approx(ref, rel=0.05)
    # and the array version gives the same values as the per-step calls
    t = np.array([0.0, 0.02, 1.0, 1234.56])
    Xs, Ys, Ns = w.drift_series(t, psi)
    for i, ti in enumerate(t):
        assert w.drift_load(float(ti), psi) == pytest.approx((Xs[i], Ys[i], Ns[i]), abs=1e-12)


def test_drift_envelope_is_the_newman_geometric_mean_sum() -> None:
    w = _waves(seed=9, **BF5)
    om, A, eps = w.components
    kT = om**2 / G * BLUE_LADY_HULL.T
    sqrtR = np.minimum(1.0, kT / 2)
    h = w.config.grid_period  # Tp / 20 (drift alone)
    assert h == pytest.approx(BF5["Tp"] / 20.0)
    t = h * np.array([0.0, 1.0, 200.0, 4096.0, 15554.0])  # grid points: exact
    Z = np.exp(1j * (np.multiply.outer(t, om) + eps)) @ (A * sqrtR)
    assert w.envelope(t) == pytest.approx(np.abs(Z) ** 2, rel=1e-9, abs=1e-15)
    # = the double sum sum_jk a_j a_k cos((w_j - w_k) t + eps_j - eps_k)
    a = A * sqrtR
    ph = np.multiply.outer(t, om) + eps
    dbl = np.einsum("j,k,tjk->t", a, a, np.cos(ph[:, :, None] - ph[:, None, :]))
    assert w.envelope(t) == pytest.approx(dbl, rel=1e-9, abs=1e-15)
    assert w.mean_drift_load(0.0)[0] == pytest.approx(
        -drift_coefficients(BLUE_LADY_HULL)[0] * float(np.sum(a**2))
    )


def test_drift_directions_and_notes_magnitudes() -> None:
    # beam sea from port (waves from west, ship heading north): pushed to starboard
    kw = {"Hs": 0.05, "Tp": 1.0, "reflection": "full", "direction_from": -math.pi / 2}
    w = _waves(seed=1, **kw)
    X, Y, N = w.mean_drift_load(0.0)
    assert abs(X) < 1e-9 and abs(N) < 1e-9
    # wall-sided drift (Faltinsen 1990): rho g Hs^2 (0.8 L) / 16 = 16.6 N (band holds ~99 % of m0)
    assert Y == pytest.approx(RHO_WATER * G * 0.05**2 * 0.8 * 13.5 / 16, rel=0.03)
    assert Y == pytest.approx(16.6, rel=0.03)
    # head sea: pushed aft, rho g Hs^2 B / 24 = 2.4 N
    w = _waves(seed=1, **{**kw, "direction_from": 0.0})
    X, Y, N = w.mean_drift_load(0.0)
    assert X == pytest.approx(-2.43, rel=0.03) and abs(Y) < 1e-9
    # waves from the port bow: aft, to starboard, bow turned to starboard (towards beam-on)
    w = _waves(seed=1, **{**kw, "direction_from": -math.pi / 4})
    X, Y, N = w.mean_drift_load(0.0)
    assert X < 0 and Y > 0 and N > 0
    assert N == pytest.approx(0.675 * math.cos(math.pi / 4) * Y)
    # heading changes the relative angle: the same sea from starboard beam after a 180 deg turn
    X2, Y2, _ = w.mean_drift_load(math.pi)
    assert X2 > 0 and Y2 < 0
    # the kT reflection factor lowers longer waves' drift (BF5 model: kT ~ 1.1)
    full = _waves(seed=1, **BF5, reflection="full").mean_drift_load(0.0)[0]
    kT = _waves(seed=1, **BF5).mean_drift_load(0.0)[0]
    assert 0.2 < kT / full < 0.6
    half = _waves(seed=1, **BF5, reflection=0.5).mean_drift_load(0.0)[0]
    assert half / full == pytest.approx(0.5)
    gain = _waves(seed=1, **BF5, drift_gain=2.0).mean_drift_load(0.0)[0]
    assert gain / kT == pytest.approx(2.0)


def test_calm_is_exactly_zero() -> None:
    for cfg in (
        WaveConfig(Hs=0.0, first_order=True),
        WaveConfig(spectrum=None, first_order=True),
    ):
        w = Waves(cfg, hull=BLUE_LADY_HULL)
        w.reset(None)  # no generator needed
        assert w.drift_load(12.3, 0.4) == (0.0, 0.0, 0.0)
        assert w.wf_motion(12.3) == (0.0, 0.0, 0.0)
        assert w.mean_drift_load(0.4) == (0.0, 0.0, 0.0)
        assert np.all(w.elevation([0.0, 1.0]) == 0.0)
        w.reset(np.random.default_rng(0))
        assert w.drift_load(5.0, 0.0) == (0.0, 0.0, 0.0)
        X, Y, N = w.drift_series([1.0, 2.0], 0.0)
        assert np.all(X == 0) and np.all(Y == 0) and np.all(N == 0)
    off = _waves(seed=1, **BF5, drift=False)
    assert off.drift_load(3.0, 0.0) == (0.0, 0.0, 0.0)
    assert off.mean_drift_load(0.0) == (0.0, 0.0, 0.0)
    assert off.wf_motion(3.0) == (0.0, 0.0, 0.0)  # first_order off by default


def test_errors_before_reset_and_for_negative_time() -> None:
    w = Waves(WaveConfig(**BF5), hull=BLUE_LADY_HULL)  # type: ignore[arg-type]
    with pytest.raises(RuntimeError, match="reset"):
        w.drift_load(1.0, 0.0)
    with pytest.raises(ValueError, match="unless Hs = 0"):
        w.reset(None)
    w.reset(1)  # an integer seed works
    with pytest.raises(ValueError, match=">= 0 s"):
        w.drift_load(-0.1, 0.0)
    with pytest.raises(ValueError, match=">= 0 s"):
        w.envelope([-1.0])


# ---------------------------------------------------------------------------------------------
# first-order wave-frequency motion
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("model", ["fossen", "al-takie", "rao"])
def test_wf_motion_std_zero_mean_and_no_low_frequency(model: str) -> None:
    cfg = WaveConfig(
        **BF5,
        first_order=True,
        wf_model=model,
        wf_beaufort=5,
        direction_from=math.radians(30.0),
    )
    w = Waves(cfg, hull=BLUE_LADY_HULL)
    w.reset(np.random.default_rng(21))
    t = np.arange(0.0, 6000.0, 0.05)
    dx, dy, dpsi = w.wf_series(t)
    # motion along the propagation direction (from 30 deg -> towards 210 deg)
    bp = math.radians(210.0)
    assert np.allclose(dx * math.sin(bp), dy * math.cos(bp), atol=1e-15)
    d = dx * math.cos(bp) + dy * math.sin(bp)
    for sig, target in ((np.std(d), cfg.position_std), (np.std(dpsi), cfg.heading_std)):
        assert float(sig) == pytest.approx(target, rel=0.10)
    for x, target in ((d, cfg.position_std), (dpsi, cfg.heading_std)):
        assert abs(float(np.mean(x))) < 0.05 * target
        ma = np.convolve(x, np.ones(1200) / 1200, mode="valid")  # 60 s moving average
        assert float(np.max(np.abs(ma))) < 0.05 * target
    # the preset stds (assumed: 0.1-0.4 Hs/4 and 0.2-0.5 deg offshore)
    assert cfg.position_std == pytest.approx(BF5["Hs"] / 16)
    assert 0.15 < math.degrees(cfg.heading_std) < 0.5
    # per-step calls equal the array version
    for ti in (0.0, 12.34, 3000.0):
        assert w.wf_motion(ti) == pytest.approx(
            tuple(float(v[0]) for v in w.wf_series(np.array([ti]))), abs=1e-15
        )


def test_wf_fossen_psd_peaks_at_wp_and_explicit_std() -> None:
    cfg = WaveConfig(**BF5, first_order=True, wf_position_std=0.01, wf_heading_std=0.002)
    w = Waves(cfg, hull=BLUE_LADY_HULL)
    w.reset(np.random.default_rng(4))
    t = np.arange(0.0, 4096.0, 0.05)
    dx, dy, dpsi = w.wf_series(t)
    f, P = periodogram(dpsi, fs=20.0, nfft=2**16)
    Ps = np.convolve(P, np.ones(21) / 21, mode="same")
    assert 2 * np.pi * f[np.argmax(Ps)] == pytest.approx(cfg.peak_frequency, rel=0.15)
    assert float(np.std(np.hypot(dx, dy))) == pytest.approx(0.01 * math.sqrt(1 - 2 / np.pi), 0.1)
    assert float(np.std(dpsi)) == pytest.approx(0.002, rel=0.1)
    assert cfg.shaping_lambda == pytest.approx(0.102, abs=0.002)


def test_al_takie_polynomials_match_thesis() -> None:
    den = al_takie_hf_polynomial(5)
    assert den[1:] == pytest.approx([1.480, 1.412, 0.963, 0.474], abs=1e-3)
    assert al_takie_hf_polynomial(8)[1:] == pytest.approx([0.900, 0.576, 0.243, 0.0809], abs=1e-3)
    w = np.linspace(0.05, 3.0, 30001)
    s = 1j * w
    assert w[np.argmax(np.abs(s * s / np.polyval(den, s)))] == pytest.approx(0.806, abs=2e-3)
    scaled = al_takie_hf_polynomial(5, peak_frequency=3.5)
    w = np.linspace(0.5, 8.0, 30001)
    s = 1j * w
    assert w[np.argmax(np.abs(s * s / np.polyval(scaled, s)))] == pytest.approx(3.5, abs=2e-3)
    with pytest.raises(ValueError, match="Beaufort 5-9"):
        al_takie_hf_polynomial(4)


# ---------------------------------------------------------------------------------------------
# config
# ---------------------------------------------------------------------------------------------


def test_config_defaults_are_the_lake() -> None:
    cfg = WaveConfig()
    assert (cfg.spectrum, cfg.Hs, cfg.Tp, cfg.gamma) == ("jonswap", 0.05, 1.0, 3.3)
    assert cfg.drift and not cfg.first_order
    assert cfg.frequency_range == pytest.approx((0.5 * 2 * math.pi, 3.5 * 2 * math.pi))
    assert WaveConfig(w_min=2.0, w_max=30.0).frequency_range == (2.0, 30.0)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"spectrum": "bretschneider"}, "spectrum must be one of"),
        ({"Hs": -0.1}, "Hs must be >= 0"),
        ({"Hs": "0.05"}, "Hs must be a real number"),
        ({"Tp": 0.0}, "Tp must be > 0"),
        ({"gamma": 0.5}, "gamma must be in"),
        ({"n_components": 0}, "n_components must be an int"),
        ({"n_components": True}, "n_components must be an int"),
        ({"w_min": 9.0, "w_max": 8.0}, "w_min must be < w_max"),
        ({"w_min": -1.0}, "w_min must be > 0"),
        ({"drift": 1}, "drift must be true or false"),
        ({"reflection": "partial"}, "reflection must be"),
        ({"reflection": 1.5}, "reflection must be"),
        ({"wf_model": "raos"}, "wf_model must be one of"),
        ({"wf_model": "al-takie"}, "needs wf_beaufort"),
        ({"wf_beaufort": 4}, "wf_beaufort must be"),
        ({"wf_lambda": 1.0}, "wf_lambda must be in"),
        ({"wf_position_std": -1.0}, "wf_position_std must be >= 0"),
        ({"sample_period": 0.2}, "sample_period"),
        ({"Hs": float("nan")}, "finite"),
    ],
)
def test_config_validation(kw: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        WaveConfig(**kw)


def test_from_dict_rejects_unknown_keys() -> None:
    assert WaveConfig.from_dict({"Hs": 0.1, "Tp": 2.0}).Hs == 0.1
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['hs'\].*valid keys are: spectrum"):
        WaveConfig.from_dict({"hs": 0.1})


def test_modal_filter_is_lfilter_floats() -> None:
    """The compiled WF-filter recursion is SciPy's ``lfilter`` (direct form II transposed,
    complex) on the modal noise ``einsum("ij,jdk->idk", Gm, z)``, float for float."""
    from scipy.signal import lfilter

    from shipgym.disturbances.waves import modal_filter_piece

    rng = np.random.default_rng(4)
    nf, k = 4, 500
    lam = 0.97 * np.exp(1j * rng.uniform(-1, 1, nf))
    Gm = rng.normal(size=(nf, nf)) + 1j * rng.normal(size=(nf, nf))
    z = rng.standard_normal((nf, 2, k))
    q = rng.normal(size=(nf, 2)) + 1j * rng.normal(size=(nf, 2))
    zi = np.stack([lam[i] * q[i] for i in range(nf)])
    got = np.empty((nf, 2, k), dtype=complex)
    modal_filter_piece(lam, Gm, z, zi.copy(), got, 0, k)  # the whole chunk
    u = np.einsum("ij,jdk->idk", Gm, z)
    for i in range(nf):
        ref = lfilter([1.0], [1.0, -lam[i]], u[i], axis=-1, zi=zi[i][:, None])[0]
        assert np.array_equal(got[i], ref)
