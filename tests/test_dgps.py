"""The DGPS receiver's PV Kalman filter of Artyszuk (2003), against the notes' computed
steady state (checks C1-C3), an independent recursion, a Monte-Carlo run and the current
correction's round trip (C10)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shipgym.observers.dgps import (
    DGPSReceiver,
    antenna_motion,
    apply_current,
    gain_cycles,
    pv_filter_batch,
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
    a = 0.02
    k = np.arange(400.0)
    x = pv_filter_batch(np.c_[0.5 * a * k**2, 0 * k], np.zeros(4), 0.01)[-1]
    assert (a * 399 - x[0]) / a == pytest.approx(tau, rel=1e-3)
    # noise only: the velocity's spread
    rng = np.random.default_rng(0)
    v = pv_filter_batch(2.0 * rng.standard_normal((20001, 2)), np.zeros(4), 0.01)[1:, 0]
    assert np.std(v[100:]) == pytest.approx(sigma_v, rel=0.05)


def test_the_recursion_is_the_printed_one_and_tends_to_the_steady_filter():
    m = pv_model(0.01)
    rng = np.random.default_rng(1)
    z = np.cumsum(rng.normal(0, 1, (60, 2)), 0)
    rx = DGPSReceiver(0.01, steady=False, sigma=0.0)  # the receiver's recursion, from P0 = 0
    rx.reset(np.zeros(3), np.zeros(3))
    rx.P[:] = 0.0
    x, P = np.zeros(4), np.zeros((4, 4))
    for zk in z:  # eqs. of Artyszuk (2003) §2, written out
        Pm = m.Phi @ P @ m.Phi.T + m.Q
        K = Pm @ m.H.T @ np.linalg.inv(m.H @ Pm @ m.H.T + m.R)
        x = m.Phi @ x + K @ (zk - m.H @ m.Phi @ x)
        P = (np.eye(4) - K @ m.H) @ Pm
        o = rx.update([zk[0], zk[1], 0.0])
        np.testing.assert_allclose([o.v_ns, o.v_ew, o.x_hat, o.y_hat], x, atol=1e-12)
    np.testing.assert_allclose(rx.K[0], pv_steady_gain(0.01)[0], rtol=1e-3)


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
    with pytest.raises(ValueError, match="finite"):
        DGPSReceiver().reset([np.nan, 0.0, 0.0], np.zeros(3))


def _track(n=120):
    """A ship accelerating into a starboard turn, sampled at 1 Hz (analytic)."""
    t = np.arange(float(n))
    psi = 0.3 + 0.0004 * t**2
    r = 0.0008 * t
    u = 6.0 - 0.01 * t
    x = np.cumsum(u * np.cos(psi)) + 10.0
    y = np.cumsum(u * np.sin(psi)) - 5.0
    return np.c_[x, y, psi], np.c_[u, 0.1 * np.ones(n), r]


def test_receiver_streaming_and_batch_agree_exactly():
    eta, nu = _track()
    for kw in ({}, {"antenna": (-40.0, 1.5)}, {"S_p": 0.1, "sigma": 0.5}):
        batch = DGPSReceiver(**kw, rng=7).run(eta, nu[0])
        rec = DGPSReceiver(**kw, rng=7)
        first = rec.reset(eta[0], nu[0])
        stream = [first] + [rec.update(e) for e in eta[1:]]
        for name in batch._fields:
            got = np.array([getattr(o, name) for o in stream])
            np.testing.assert_array_equal(got, getattr(batch, name), err_msg=name)
        # and against the printed filter (matrix form) on the same measurements
        x0 = np.r_[batch.v_ns[0], batch.v_ew[0], batch.x_hat[0], batch.y_hat[0]]
        m = pv_model(kw.get("S_p", 0.01))
        ref = [x0]
        for z in batch.z[1:]:  # eq. 5 in the printed matrix form
            xp = m.Phi @ ref[-1]
            ref.append(xp + rec.K_inf @ (z - m.H @ xp))
        np.testing.assert_allclose(np.c_[batch.v_ns, batch.v_ew, batch.x_hat, batch.y_hat], ref,
                                   atol=1e-9)  # fmt: skip
        np.testing.assert_array_equal(pv_filter_batch(batch.z, x0, kw.get("S_p", 0.01))[:, 0],
                                      batch.v_ns)  # fmt: skip
    # the recursion form: the gain from P_prior, and sigma 0 is noise-free
    rs = DGPSReceiver(steady=False, sigma=0.0).run(eta, nu[0])
    np.testing.assert_array_equal(rs.z, eta[:, :2])
    with pytest.raises(RuntimeError, match="reset"):
        DGPSReceiver().update(eta[0])
    with pytest.raises(ValueError, match="sigma"):
        DGPSReceiver(sigma=-1.0)


def test_receiver_starts_at_the_truth_and_an_antenna_in_a_pure_rotation():
    # straight run: started at the truth, noise-free, the estimate stays on it
    n = 60
    t = np.arange(float(n))
    eta = np.c_[7.0 * t * math.cos(0.4), 7.0 * t * math.sin(0.4), np.full(n, 0.4)]
    nu = np.tile([7.0, 0.0, 0.0], (n, 1))
    out = DGPSReceiver(sigma=0.0).run(eta, nu[0])
    np.testing.assert_allclose(out.v_xy, 7.0, atol=1e-12)
    np.testing.assert_allclose(out.beta_A, 0.0, atol=1e-12)
    np.testing.assert_allclose(np.c_[out.x_hat, out.y_hat], eta[:, :2], atol=1e-9)
    # a pure rotation about the origin: the antenna traces R(psi) a
    psi = np.linspace(0.0, 2.0, n)
    rot = np.c_[np.zeros(n), np.zeros(n), psi]
    a = np.array([-40.0, 3.0])
    o = DGPSReceiver(sigma=0.0, antenna=a).run(rot, [0.0, 0.0, psi[1] - psi[0]])
    want = np.c_[np.cos(psi) * a[0] - np.sin(psi) * a[1], np.sin(psi) * a[0] + np.cos(psi) * a[1]]
    np.testing.assert_allclose(o.z, want, atol=1e-12)
    # the antenna's velocity in a pure rotation is r x a, perpendicular to a
    _, v = antenna_motion([0.0, 0.0, 0.0], [0.0, 0.0, 0.1], a)
    np.testing.assert_allclose(v, [-0.1 * a[1], 0.1 * a[0]], atol=1e-15)
    # noise: seeded, and about sigma
    e1 = DGPSReceiver(rng=3).run(eta, nu[0]).z - eta[:, :2]
    e2 = DGPSReceiver(rng=3).run(eta, nu[0]).z - eta[:, :2]
    np.testing.assert_array_equal(e1, e2)
    assert np.std(e1[1:]) == pytest.approx(2.0, rel=0.2)


def test_receiver_i_of_a_batch_is_the_single_receiver_with_its_generator():
    """n receivers, each with its own generator, updated under masks (the others wait): row
    i is bit for bit the single receiver with that generator, updated when its mask is set;
    blocks of draws smaller than the episode (refills) change nothing."""
    eta, nu = _track(150)
    tracks = np.stack([eta, eta + [5.0, -3.0, 0.2], eta[::-1]])
    nus = np.stack([nu[0], nu[0] * 0.5, nu[-1]])
    kw = {"antenna": (-40.0, 1.5), "S_p": 0.02}
    batch = DGPSReceiver(n=3, rng=[7, 8, 9], block=16, **kw)
    singles = [DGPSReceiver(rng=s, **kw) for s in (7, 8, 9)]
    out = batch.reset(tracks[:, 0], nus)
    ones = [s.reset(tracks[i, 0], nus[i]) for i, s in enumerate(singles)]
    masks = np.random.default_rng(0).random((149, 3)) < 0.8
    for k in range(1, 150):
        out = batch.update(tracks[:, k], mask=masks[k - 1])
        for i, s in enumerate(singles):
            if masks[k - 1, i]:
                ones[i] = s.update(tracks[i, k])
            for name in out._fields:
                np.testing.assert_array_equal(getattr(out, name)[i], getattr(ones[i], name))
    # a reset with new generators restarts the draws of the reset receivers only
    batch.reset(tracks[:, 0], nus, rngs=[1, 2, 3], mask=[True, False, False])
    s = DGPSReceiver(rng=1, **kw)
    s.reset(tracks[0, 0], nus[0])
    np.testing.assert_array_equal(batch.update(tracks[:, 1]).z[0], s.update(tracks[0, 1]).z)
    # the offline run over n tracks at once, rows as the single runs
    many = DGPSReceiver(n=3, rng=[7, 8, 9], **kw).run(tracks, nus)
    assert many.v_xy.shape == (3, 150) and many.z.shape == (3, 150, 2)
    for i in range(3):
        one = DGPSReceiver(rng=7 + i, **kw).run(tracks[i], nus[i])
        for name in one._fields:
            np.testing.assert_array_equal(getattr(many, name)[i], getattr(one, name))
    with pytest.raises(ValueError, match="n must be"):
        DGPSReceiver(n=0)
    with pytest.raises(ValueError, match=r"\(3, 3\)"):
        batch.update(eta[0])
