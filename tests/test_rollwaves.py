"""Wave roll and yaw moments (``shipgym.disturbances.rollwaves``).

References: the spectrum's moments by SciPy quadrature (``int S dw = Hs^2/16``, ``int k^2 S
dw``), the yaw moment's length integral by quadrature along the hull, the encounter frequency
formula, and the sin(chi) / cos(chi) zeros of the long-wave model.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from shipgym.disturbances.rollwaves import RollWaveConfig, RollWaves
from shipgym.disturbances.spectra import jonswap

K_PHI, L, NABLA, RHO, G = 3.906e6, 51.5, 357.0, 1014.0, 9.81


def make(seed: int = 0, **kw) -> RollWaves:
    w = RollWaves(RollWaveConfig(**kw), K_PHI, length=L, nabla=NABLA, rho=RHO)
    w.reset(np.random.default_rng(seed))
    return w


def test_elevation_and_slope_variances_match_the_spectrum():
    cfg = dict(Hs=3.0, Tp=8.0, gamma=3.3, n_components=300)
    w = make(1, **cfg)
    om, a, _, _ = w.components
    band, _ = quad(lambda x: jonswap(x, 3.0, 8.0, 3.3), 0.15, 3.0, limit=200)
    slope_band, _ = quad(lambda x: (x * x / G) ** 2 * jonswap(x, 3.0, 8.0, 3.3), 0.15, 3.0,
                         limit=200)  # fmt: skip
    # the components' variance is the band's energy; the band holds ~all of Hs^2/16
    assert np.sum(a * a) / 2 == pytest.approx(band, rel=1e-6)
    assert band == pytest.approx(3.0**2 / 16, rel=0.02)
    # the slope of the components (k_i at the drawn frequency within each bin)
    assert np.sum((om * om / G * a) ** 2) / 2 == pytest.approx(slope_band, rel=0.01)
    # and the sample statistics of the time series, over many periods
    t = np.arange(0.0, 20000.0, 1.1)
    assert np.var(w.elevation(t)) == pytest.approx(band, rel=0.05)
    assert np.var(w.slope(t)) == pytest.approx(slope_band, rel=0.05)  # beam sea: sin(chi) = 1
    K, _ = w.moment(t)
    np.testing.assert_allclose(K, K_PHI * w.slope(t), rtol=1e-12, atol=1e-9 * np.abs(K).max())


def test_same_seed_same_moment_other_seed_other_moment():
    t = np.linspace(0.0, 100.0, 501)
    K1, N1 = make(5, chi=math.radians(60)).moment(t)
    K2, N2 = make(5, chi=math.radians(60)).moment(t)
    K3, _ = make(6, chi=math.radians(60)).moment(t)
    np.testing.assert_array_equal(K1, K2)
    np.testing.assert_array_equal(N1, N2)
    assert np.abs(K1 - K3).max() > 0.1 * np.abs(K1).max()
    # a Generator and its seed give the same sea; vectorised over t as pointwise
    w = RollWaves(RollWaveConfig(chi=math.radians(60)), K_PHI, length=L, nabla=NABLA, rho=RHO)
    w.reset(5)
    np.testing.assert_array_equal(w.moment(t)[0], K1)
    assert w.moment(float(t[63]))[0] == pytest.approx(K1[63], rel=1e-12)


def test_beam_head_and_following_seas():
    t = np.linspace(0.0, 200.0, 2001)
    Kb, Nb = make(2, chi=math.pi / 2).moment(t)
    assert np.std(Kb) > 1e4  # a real roll moment in beam seas (N m)
    assert np.abs(Nb).max() < 1e-9 * np.abs(Kb).max()  # no yaw moment in pure beam seas
    for chi in (0.0, math.pi):
        K, N = make(2, chi=chi).moment(t)
        assert np.abs(K).max() < 1e-12 * np.abs(Kb).max()
        assert np.abs(N).max() < 1e-12 * np.abs(Kb).max()
    Kq, Nq = make(2, chi=math.radians(45)).moment(t)  # quartering
    assert np.std(Kq) == pytest.approx(np.std(Kb) * math.sin(math.radians(45)), rel=1e-9)
    assert np.std(Nq) > 1e4


def test_yaw_moment_is_the_length_integral_of_the_lateral_force():
    chi, U = math.radians(135), 5.0
    w = make(3, chi=chi, U=U, n_components=40)
    om, a, eps, we = w.components
    k = om * om / G
    np.testing.assert_allclose(we, om - k * U * math.cos(chi), rtol=1e-14)
    t0 = 17.3

    # lateral Froude-Krylov force per unit length: rho g (nabla/L) times the local slope
    def f(x: float) -> float:
        slope = math.sin(chi) * np.sum(k * a * np.sin(we * t0 + eps - k * x * math.cos(chi)))
        return RHO * G * NABLA / L * slope * x

    ref, _ = quad(f, -L / 2, L / 2, limit=400, epsabs=0.0, epsrel=1e-10)
    assert w.moment(t0)[1] == pytest.approx(ref, rel=1e-8)


def test_head_sea_raises_the_encounter_frequency():
    w = make(0, chi=math.pi, U=8.0)
    om, _, _, we = w.components
    np.testing.assert_allclose(we, om + om**2 * 8.0 / G, rtol=1e-14)


def test_config_validation_and_coerce():
    c = RollWaveConfig.coerce({"Hs": 2.5, "chi_deg": 60.0})
    assert c.chi == pytest.approx(math.radians(60.0)) and c.Hs == 2.5
    assert RollWaveConfig.coerce(None) is None
    assert RollWaveConfig.coerce(c) is c
    with pytest.raises(ValueError, match="unknown key"):
        RollWaveConfig.coerce({"Hs": 2.0, "heading": 1.0})
    with pytest.raises(ValueError, match="not both"):
        RollWaveConfig.coerce({"chi": 1.0, "chi_deg": 60.0})
    with pytest.raises(ValueError, match="mapping"):
        RollWaveConfig.coerce("2@90")
    for bad in ({"Hs": -1.0}, {"Tp": 0.0}, {"spectrum": "bretschneider"}, {"gamma": 0.5},
                {"n_components": 0}, {"omega_min": 2.0, "omega_max": 1.0}, {"U": -1.0},
                {"chi": float("nan")}):  # fmt: skip
        with pytest.raises(ValueError):
            RollWaveConfig(**bad)
    with pytest.raises(ValueError, match="restoring"):
        RollWaves(RollWaveConfig(), -1.0, length=L, nabla=NABLA, rho=RHO)
    with pytest.raises(RuntimeError, match="reset"):
        RollWaves(RollWaveConfig(), K_PHI, length=L, nabla=NABLA, rho=RHO).moment(0.0)
    # Pierson-Moskowitz works too
    w = make(0, spectrum="pm", Hs=2.0, Tp=9.0)
    assert np.sum(w.components[1] ** 2) / 2 == pytest.approx(2.0**2 / 16, rel=0.03)
