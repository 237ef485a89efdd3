"""The DGPS receiver's PV Kalman filter of Artyszuk (2003), against the notes' computed
steady state (checks C1-C3), an independent recursion, a Monte-Carlo run and the current
correction's round trip (C10)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shipgym.observers.dgps import (
    DGPSPVFilter,
    apply_current,
    gain_cycles,
    pv_lag,
    pv_model,
    pv_steady_gain,
    raw_velocity,
    velocity_outputs,
    water_velocity,
)


@pytest.mark.parametrize(
    "S_p, K_v, K_x", [(0.001, 0.01447, 0.16291), (0.01, 0.04269, 0.27111), (0.1, 0.11936, 0.43012)]
)
def test_C1_steady_gain(S_p, K_v, K_x):
    K, P = pv_steady_gain(S_p)
    # north and east decouple: K_v on the velocity rows, K_x on the position rows
    np.testing.assert_allclose(K, [[K_v, 0], [0, K_v], [K_x, 0], [0, K_x]], atol=1e-5)
    if S_p == 0.01:
        np.testing.assert_allclose([P[0, 0], P[0, 2], P[2, 2]], [0.06851, 0.23426, 1.48777],
                                   atol=1e-5)  # fmt: skip


def test_C2_the_gain_converges_in_under_30_cycles_from_any_P0():
    for P0 in (np.zeros((4, 4)), np.eye(4), 100 * np.eye(4), 1e4 * np.eye(4)):
        assert 16 <= gain_cycles(0.01, P0) <= 20
        assert 30 <= gain_cycles(0.001, P0) <= 36


def test_C3_lag_and_noise_and_a_monte_carlo_check():
    tau, lag_x, sigma_v = pv_lag(0.01)
    assert tau == pytest.approx(5.85, abs=1e-2) and lag_x == pytest.approx(17.1, abs=0.05)
    assert sigma_v == pytest.approx(0.1255, abs=1e-3)
    # the filter under a constant acceleration: its velocity lags by a tau
    f = DGPSPVFilter(0.01, x0=np.zeros(4))
    a = 0.02
    for k in range(1, 400):
        x = f.step([0.5 * a * k**2, 0.0])
    assert (a * 399 - x[0]) / a == pytest.approx(tau, rel=1e-3)
    # noise only: the velocity's spread
    rng = np.random.default_rng(0)
    f = DGPSPVFilter(0.01, x0=np.zeros(4))
    v = [f.step(2.0 * rng.standard_normal(2))[0] for _ in range(20000)]
    assert np.std(v[100:]) == pytest.approx(sigma_v, rel=0.05)


def test_the_recursion_is_the_printed_one_and_tends_to_the_steady_filter():
    m = pv_model(0.01)
    rng = np.random.default_rng(1)
    z = np.cumsum(rng.normal(0, 1, (60, 2)), 0)
    f = DGPSPVFilter(0.01, steady=False, x0=np.zeros(4), P0=np.zeros((4, 4)))
    x, P = np.zeros(4), np.zeros((4, 4))
    for zk in z:  # eqs. of Artyszuk (2003) §2, written out
        Pm = m.Phi @ P @ m.Phi.T + m.Q
        K = Pm @ m.H.T @ np.linalg.inv(m.H @ Pm @ m.H.T + m.R)
        x = m.Phi @ x + K @ (zk - m.H @ m.Phi @ x)
        P = (np.eye(4) - K @ m.H) @ Pm
        np.testing.assert_allclose(f.step(zk), x, atol=1e-12)
    np.testing.assert_allclose(f.K, pv_steady_gain(0.01)[0], rtol=1e-3)


def test_outputs_raw_velocity_and_the_current_correction_round_trip():
    """C10: apply a current, correct it with the seed's formula, to 1e-12; the drift angle
    of a ship with starboard sway is negative (tan beta = -v/u)."""
    rng = np.random.default_rng(2)
    v = rng.normal(0, 3, (100, 2))
    psi = rng.uniform(-math.pi, math.pi, 100)
    for speed, gamma in ((0.25, math.pi), (0.25, 1.5 * math.pi), (1.0, 0.3)):
        g = apply_current(v, psi, speed, gamma)
        np.testing.assert_allclose(water_velocity(g, psi, speed, gamma), v, atol=1e-12)
    # a current to the north seen by a ship heading east is a sway to port
    np.testing.assert_allclose(apply_current([0.0, 0.0], math.pi / 2, 0.25, 0.0),
                               [0.0, -0.25], atol=1e-15)  # fmt: skip
    vxy, chi, beta = velocity_outputs(5.0, 1.0, 0.0)  # heading north, moving a bit east
    assert vxy == pytest.approx(math.hypot(5, 1)) and beta == pytest.approx(-math.atan(0.2))
    t = np.arange(50.0)
    p = np.c_[3 * t, 0.1 * t**2]
    np.testing.assert_allclose(raw_velocity(p)[1:-1], np.c_[3 * np.ones(48), 0.2 * t[1:-1]])
    with pytest.raises(ValueError, match="S_p"):
        pv_model(0.0)
    with pytest.raises(ValueError, match="position"):
        DGPSPVFilter().step([np.nan, 0.0])
