"""Notch-filter wave filter (Al-Takie 1982 eq. 1.1): section, discrete cascade, observer."""

import math

import numpy as np
import pytest
from scipy import signal

from shipgym.dynamics.vessel import load_vessel
from shipgym.observers.base import OBSERVERS, make_observer
from shipgym.observers.notch import NotchCascade, NotchDesign, NotchObserver, notch_section

TWO_PI = 2.0 * math.pi
DT = 0.31  # Wimpey Sealab's sampling interval, 0.1 p.u. (Al-Takie 1982 App. 3)


def eq_1_1(w, w0, b, d):
    """Eq. 1.1 written out at s = j w, independently of notch_section's coefficients."""
    s = 1j * np.asarray(w, dtype=float)
    k = math.sqrt(1.0 - 2.0 * d * d)
    return (s**2 + (b * d / k) * s + w0**2) / (s**2 + (b / k) * s + w0**2)


def sine_gain(cascade, f, periods_settle=60, periods_measure=20):
    """Steady-state amplitude ratio of a sine at f (Hz) fed sample by sample through step()."""
    dt = cascade.dt
    n0 = int(math.ceil(periods_settle / f / dt))
    n1 = int(math.ceil(periods_measure / f / dt))
    t = np.arange(n0 + n1) * dt
    u = np.sin(TWO_PI * f * t)
    cascade.reset(0.0)
    y = np.array([cascade.step(ui)[0] for ui in u])
    # least-squares amplitude over the measuring window (sin and cos fit)
    A = np.stack([np.sin(TWO_PI * f * t[n0:]), np.cos(TWO_PI * f * t[n0:])], axis=1)
    coef = np.linalg.lstsq(A, y[n0:], rcond=None)[0]
    return float(np.hypot(*coef))


# --------------------------------------------------------------------------------------------
# The continuous section of eq. 1.1
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("w0", "b", "d"), [(0.52, 0.156, 0.1), (0.8, 0.8, 0.3), (2.0, 0.1, 0.7)])
def test_section_centre_edges_and_dc_gain(w0, b, d):
    num, den = notch_section(w0, b, d)
    # against eq. 1.1 written out, evaluated by scipy.signal.freqs
    w = np.array([1e-6, 0.5 * w0, w0, 2.0 * w0, 50.0 * w0])
    np.testing.assert_allclose(signal.freqs(num, den, worN=w)[1], eq_1_1(w, w0, b, d), rtol=1e-12)
    h = lambda x: abs(signal.freqs(num, den, worN=[x])[1][0])  # noqa: E731
    assert h(w0) == pytest.approx(d, rel=1e-12)  # the centre gain is d
    assert h(1e-9) == pytest.approx(1.0, abs=1e-12)  # DC gain 1
    assert h(1e6 * w0) == pytest.approx(1.0, abs=1e-6)  # and 1 at high frequency
    # eq. 1.1 exactly: |H|^2 = 1/2 where |w0^2 - w^2| = b w, i.e. w = sqrt(w0^2 + b^2/4) +- b/2
    lo = math.sqrt(w0 * w0 + b * b / 4.0) - b / 2.0
    hi = math.sqrt(w0 * w0 + b * b / 4.0) + b / 2.0
    assert hi - lo == pytest.approx(b, rel=1e-12)  # the 3-dB width is exactly b
    assert lo * hi == pytest.approx(w0 * w0, rel=1e-12)  # geometric symmetry about w0
    assert h(lo) == pytest.approx(1.0 / math.sqrt(2.0), rel=1e-10)
    assert h(hi) == pytest.approx(1.0 / math.sqrt(2.0), rel=1e-10)
    # the 3-dB edges by root finding on the response (no formula used)
    from scipy.optimize import brentq

    f = lambda x: h(x) - 1.0 / math.sqrt(2.0)  # noqa: E731
    assert brentq(f, 1e-9 * w0, w0) == pytest.approx(lo, rel=1e-9)
    assert brentq(f, w0, 1e3 * w0) == pytest.approx(hi, rel=1e-9)


def test_section_at_w0_plus_minus_b_over_2_is_only_near_minus_3_db():
    """w0 +- b/2 are the 3-dB points only to first order in b/w0 (b = 0.3 w0: 0.736 and
    0.683, within 5 %)."""
    w0, d = 1.0, 0.1
    b = 0.3 * w0
    num, den = notch_section(w0, b, d)
    g = np.abs(signal.freqs(num, den, worN=[w0 - b / 2, w0 + b / 2])[1])
    np.testing.assert_allclose(g, 1.0 / math.sqrt(2.0), rtol=0.05)
    assert not np.allclose(g, 1.0 / math.sqrt(2.0), rtol=1e-3)


@pytest.mark.parametrize(
    ("w0", "b", "d"),
    [(0.0, 0.1, 0.1), (-1.0, 0.1, 0.1), (1.0, 0.0, 0.1), (1.0, 0.1, 0.0), (1.0, 0.1, 0.71),
     (math.nan, 0.1, 0.1), (1.0, math.inf, 0.1), ("a", 0.1, 0.1)],
)  # fmt: skip
def test_section_rejects_bad_input(w0, b, d):
    with pytest.raises(ValueError):
        notch_section(w0, b, d)


def test_design_validates_and_rejects_unknown_keys():
    with pytest.raises(ValueError, match="unknown key"):
        NotchDesign.from_dict({"centre": (0.1,)})
    with pytest.raises(ValueError, match="centres_hz"):
        NotchDesign(centres_hz=(0.1, -0.2))
    with pytest.raises(ValueError, match="centres_hz"):
        NotchDesign(centres_hz=())
    with pytest.raises(ValueError, match="attenuation|d "):
        NotchDesign(attenuation=0.8)
    with pytest.raises(ValueError, match="velocity_time_constant"):
        NotchDesign(velocity_time_constant=0.0)


# --------------------------------------------------------------------------------------------
# The discrete cascade
# --------------------------------------------------------------------------------------------


def test_each_section_is_exactly_at_its_centre_after_prewarping():
    design = NotchDesign()
    for f0 in design.centres_hz:
        one = NotchCascade(NotchDesign(centres_hz=(f0,)), DT, channels=1)
        h = one.frequency_response([f0, 0.0])
        assert abs(h[0]) == pytest.approx(design.attenuation, rel=1e-9)
        assert abs(np.angle(h[0])) < 1e-9  # real at the centre, as the continuous section
        assert h[1] == pytest.approx(1.0, abs=1e-12)  # DC gain exactly 1
        # without prewarping (plain bilinear at fs = 1/dt) the notch would move off f0
        num, den = design.sections()[design.centres_hz.index(f0)]
        bz, az = signal.bilinear(num, den, fs=1.0 / DT)
        plain = abs(signal.freqz(bz, az, worN=[f0], fs=1.0 / DT)[1][0])
        assert abs(plain / design.attenuation - 1.0) > 1e-4


def test_discrete_cascade_matches_the_continuous_one():
    design = NotchDesign()
    cas = NotchCascade(design, DT)
    # at the centres: equal to the continuous cascade (the own section exactly, the others'
    # small frequency warping inside 0.3 %)
    f_c = np.array(design.centres_hz)
    np.testing.assert_allclose(
        np.abs(cas.frequency_response(f_c)), np.abs(design.frequency_response(f_c)), rtol=3e-3
    )
    # below 0.04 Hz within 1 % (complex response)
    f = np.linspace(0.0, 0.04, 81)
    err = np.abs(cas.frequency_response(f) - design.frequency_response(f))
    assert err.max() < 0.01


def test_step_equals_scipy_sosfilt_from_its_steady_state():
    cas = NotchCascade(NotchDesign(), DT, channels=2)
    rng = np.random.default_rng(3)
    x0 = np.array([5.0, -2.0])
    u = x0[:, None] + rng.standard_normal((2, 400))
    cas.reset(x0)
    y = np.stack([cas.step(u[:, k]) for k in range(u.shape[1])], axis=1)
    zi = signal.sosfilt_zi(np.array(cas.sos))
    for c in range(2):
        ref, _ = signal.sosfilt(np.array(cas.sos), u[c], zi=zi * x0[c])
        np.testing.assert_allclose(y[c], ref, rtol=1e-12, atol=1e-12)
    # the steady state: a constant input comes out unchanged from the first sample on
    cas.reset(x0)
    out = np.stack([cas.step(x0) for _ in range(50)])
    np.testing.assert_allclose(out, np.broadcast_to(x0, out.shape), rtol=1e-12)


def test_steady_state_sine_attenuation_and_pass_band():
    design = NotchDesign()
    cas = NotchCascade(design, DT, channels=1)
    # the Beaufort 8 HF peak (0.083 Hz): attenuated >= 10x
    assert sine_gain(cas, 0.083) <= 0.1
    # a 0.01 Hz sine passes with its gain within 2 %
    assert sine_gain(cas, 0.01, periods_settle=4, periods_measure=4) == pytest.approx(1.0, abs=0.02)
    # 0.1 Hz lies in the gap between the 0.083 and 0.128 Hz notches: only -4 dB, as the
    # continuous cascade (eq. 1.1) gives it
    g = sine_gain(cas, 0.1)
    assert g == pytest.approx(abs(design.frequency_response(0.1)), rel=0.01)
    assert 0.55 < g < 0.7


def test_sine_gain_agrees_with_sosfreqz():
    cas = NotchCascade(NotchDesign(), DT, channels=1)
    for f in (0.069, 0.128, 0.2):
        assert sine_gain(cas, f) == pytest.approx(abs(cas.frequency_response(f)[0]), rel=2e-3)


def test_cascade_rejects_a_centre_above_nyquist_and_bad_arguments():
    with pytest.raises(ValueError, match="Nyquist"):
        NotchCascade(NotchDesign(), 4.0)  # Nyquist 0.125 Hz < 0.128 Hz
    with pytest.raises(ValueError, match="dt"):
        NotchCascade(NotchDesign(), 0.0)
    with pytest.raises(ValueError, match="channels"):
        NotchCascade(NotchDesign(), DT, channels=0)
    with pytest.raises(ValueError, match="unknown key"):
        NotchCascade({"bandwith_ratio": 0.3}, DT)


# --------------------------------------------------------------------------------------------
# The observer
# --------------------------------------------------------------------------------------------


PSI0 = math.radians(30.0)


def _ramp_run(f_wave, psi0=PSI0, n=3000, dropout=None, A=1.0):
    """A slow ramp in x (V = 0.05 m/s) plus a wave oscillation of amplitude A (m) at f_wave
    (Hz) in x and y."""
    V = 0.05
    obs = make_observer("notch")
    t = np.arange(n) * DT
    obs.reset(0.0, [0.0, 0.0, psi0])
    est, nu = [], []
    for k in range(1, n):
        z = [V * t[k] + A * math.sin(TWO_PI * f_wave * t[k]),
             A * math.cos(TWO_PI * f_wave * t[k]) - A, psi0]  # fmt: skip
        info = obs.step(t[k], None if dropout and dropout[0] <= k < dropout[1] else z)
        if dropout and dropout[0] <= k < dropout[1]:
            assert np.isnan(info.innovation).all() and info.nis is None
        e = obs.estimate()
        est.append(e.eta)
        nu.append(e.nu)
    return obs, t[1:], np.array(est), np.array(nu), V, A


def test_observer_follows_a_ramp_and_removes_the_wave_oscillation():
    obs, t, est, nu, V, A = _ramp_run(0.083)
    tail = t > 300.0
    lag = V * obs.design.ramp_lag()  # the continuous cascade's analytic group delay at DC
    assert obs.cascade.dc_group_delay == pytest.approx(obs.design.ramp_lag(), rel=0.01)
    err_x = est[tail, 0] - V * t[tail]
    assert np.mean(err_x) == pytest.approx(-lag, rel=0.02)
    # what is left of the 1 m oscillation: amplitude <= 10 % (>= 90 % removed)
    for resid in (err_x - np.mean(err_x), est[tail, 1] - np.mean(est[tail, 1])):
        assert math.sqrt(2.0) * np.std(resid) <= 0.1 * A
    # velocity: V along north, in the body frame at psi = 30 deg: u = V cos, v = -V sin
    psi = math.radians(30.0)
    np.testing.assert_allclose(
        nu[tail].mean(axis=0), [V * math.cos(psi), -V * math.sin(psi), 0.0], atol=0.005
    )
    np.testing.assert_allclose(est[tail, 2], psi, atol=1e-12)


def test_observer_coasts_through_a_dropout_with_the_velocity():
    n, k0, k1 = 1500, 1000, 1030  # a 9.3 s dropout
    i = np.arange(k0 - 1, k1 - 1)  # est[k - 1] is the estimate at sample k
    # on the pure ramp the prediction with the velocity is exact: the estimate moves on at V
    _, t, est, nu, V, _ = _ramp_run(0.083, n=n, dropout=(k0, k1), A=0.0)
    slope = np.polyfit(t[i], est[i, 0], 1)[0]
    assert slope == pytest.approx(V, rel=1e-3)
    lag = V * NotchCascade(NotchDesign(), DT).dc_group_delay
    np.testing.assert_allclose(est[i, 0], V * t[i] - lag, atol=0.01)
    np.testing.assert_allclose(est[k1:, 0], V * t[k1:] - lag, atol=0.01)  # no jump after it
    # with the wave: the held velocity carries the residual wave velocity (about 0.02 m/s),
    # the estimate stays within 0.3 m of the uninterrupted run and is back within 100 s
    _, t, est, _, _, _ = _ramp_run(0.083, n=n, dropout=(k0, k1))
    _, _, ref, _, _, _ = _ramp_run(0.083, n=n)
    assert np.abs(est[i, 0] - ref[i, 0]).max() < 0.3
    assert np.abs(est[k1 + 330 :, 0] - ref[k1 + 330 :, 0]).max() < 0.02


def test_heading_is_continuous_through_north():
    obs = make_observer("notch")
    r = math.radians(0.5)  # rad/s
    psi0 = math.pi - 0.3
    obs.reset(0.0, [0.0, 0.0, psi0])
    for k in range(1, 400):
        psi = psi0 + r * k * DT
        obs.step(k * DT, [0.0, 0.0, math.atan2(math.sin(psi), math.cos(psi))])  # wrapped
    e = obs.estimate()
    true = psi0 + r * 399 * DT
    assert true > math.pi + 0.5
    assert e.eta[2] == pytest.approx(true - r * obs.design.ramp_lag(), abs=1e-3)
    assert e.nu[2] == pytest.approx(r, rel=0.01)


def test_fixed_sampling_interval_is_enforced():
    obs = make_observer("notch")
    obs.reset(0.0, [0.0, 0.0, 0.0])
    obs.step(DT, [0.0, 0.0, 0.0])
    assert obs.dt == pytest.approx(DT)
    obs.step(2 * DT * (1 + 1e-8), None)  # rounding of the caller's clock is fine
    with pytest.raises(ValueError, match="fixed sampling interval"):
        obs.step(2 * DT + 1.5 * DT, [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="fixed sampling interval"):
        obs.step(2 * DT, [0.0, 0.0, 0.0])  # dt = 0
    obs2 = make_observer("notch")
    obs2.reset(1.0, [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="after reset"):
        obs2.step(1.0, [0.0, 0.0, 0.0])
    with pytest.raises(RuntimeError, match="reset"):
        make_observer("notch").step(1.0, [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="P0"):
        obs.reset(0.0, [0.0, 0.0, 0.0], P0=np.eye(6))


def test_noise_covariance_matches_white_noise_through_the_observer():
    """P is the measurement-noise covariance through the chain: check it by simulation."""
    R = np.array([0.2, 0.05, 1e-3])
    obs = NotchObserver(measurement_variance=R)
    rng = np.random.default_rng(7)
    obs.reset(0.0, [0.0, 0.0, 0.0])
    n = 30000
    eta = np.empty((n, 3))
    eta_dot = np.empty((n, 3))
    for k in range(1, n + 1):
        obs.step(k * DT, np.sqrt(R) * rng.standard_normal(3))
        e = obs.estimate()
        eta[k - 1] = e.eta
        eta_dot[k - 1] = e.nu  # psi stays ~0: nu = eta_dot up to 1e-3 rad of rotation
    eta, eta_dot = eta[1000:], eta_dot[1000:]
    P = obs.estimate().P
    np.testing.assert_allclose(eta.var(axis=0), np.diag(P)[:3], rtol=0.1)
    np.testing.assert_allclose(eta_dot.var(axis=0), np.diag(P)[3:], rtol=0.1)
    cov = np.mean((eta - eta.mean(0)) * (eta_dot - eta_dot.mean(0)), axis=0)
    np.testing.assert_allclose(cov, np.diag(P[:3, 3:]), rtol=0.15)
    assert 0.85 < P[0, 0] / R[0] < 1.0  # DC gain 1, the notches take a little of the noise


def test_registry_and_froude_scaled_vessel_adapter():
    assert "notch" in OBSERVERS or make_observer("notch")
    full = (0.069, 0.083, 0.128)
    bl = load_vessel("blue-lady")
    assert bl.scale == 24.0
    obs = make_observer("notch", vessel=bl)
    np.testing.assert_allclose(obs.design.centres_hz, np.array(full) * math.sqrt(24.0))
    assert obs.design.velocity_time_constant == pytest.approx(3.0 / math.sqrt(24.0))
    # the 1:24 model's top notch (0.627 Hz) needs faster sampling than its 1 s sensors
    obs.reset(0.0, [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="Nyquist"):
        obs.step(1.0, [0.0, 0.0, 0.0])
    obs.reset(0.0, [0.0, 0.0, 0.0])
    obs.step(0.25, [0.0, 0.0, 0.0])
    assert abs(obs.cascade.frequency_response(full[1] * math.sqrt(24.0))[0]) < 0.1
    wimpey = load_vessel("wimpey-sealab")
    assert make_observer("notch", vessel=wimpey).design == NotchDesign()
    # user overrides win over the vessel's values; unknown options raise
    assert make_observer("notch", vessel=bl, attenuation=0.05).design.attenuation == 0.05
    with pytest.raises(ValueError, match="unknown option"):
        make_observer("notch", centre_hz=0.1)
