"""The 9-state extended Kalman filter of Tomera (2014) (eqs. 36-53, Table 5)."""

import dataclasses
import math

import numpy as np
import pytest
from _helpers import BLUE_LADY_DESIGN
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.stats import chi2

from shipgym.dynamics import rot, seed_linear_matrices, wrap_angle
from shipgym.observers.ekf import (
    EKF_PRESETS,
    EKFConfig,
    ExtendedKalmanFilter,
    default_ekf,
    ekf_config,
    tomera_ekf,
)
from shipgym.observers.sensors import SensorConfig, Sensors

M, D_L = seed_linear_matrices()
Z3 = np.zeros(3)


def _tau(k):
    """A known, smooth thrust sequence (N, N, N m) within the Blue Lady's capacity."""
    return np.array([60 * math.sin(0.03 * k), 25 * math.cos(0.05 * k), 80 * math.sin(0.02 * k)])


def _f_ref(x, tau, frame="body"):
    """Independent statement of the model (M nu_dot + D_L nu = tau + b)."""
    eta, nu, b = x[:3], x[3:6], x[6:9]
    force = b if frame == "body" else rot(eta[2]).T @ b
    return np.concatenate(
        [rot(eta[2]) @ nu, np.linalg.solve(M, tau - D_L @ nu + force), -b / 1000.0]
    )


def _noise_cov(cfg: EKFConfig) -> np.ndarray:
    Qc = np.zeros((9, 9))
    Qc[3:6, 3:6] = cfg.Q_nu
    E = np.array(cfg.E_b)
    Qc[6:9, 6:9] = E @ np.array(cfg.Q) @ E.T
    return Qc


def _ship_state(rng, heading=None):
    x = np.concatenate(
        [rng.normal(0, 10, 2), [rng.uniform(-4, 4)], rng.normal(0, [0.5, 0.2, 0.02]),
         rng.normal(0, [30, 30, 60])]
    )  # fmt: skip
    if heading is not None:
        x[2] = heading
    return x


# ---- model and Jacobian ----------------------------------------------------------------------
@pytest.mark.parametrize("frame", ["body", "ned"])
def test_vector_field_matches_model(frame):
    ekf = default_ekf(bias_frame=frame)
    rng = np.random.default_rng(0)
    for _ in range(20):
        x, tau = _ship_state(rng), rng.normal(0, 50, 3)
        np.testing.assert_allclose(ekf.f(x, tau), _f_ref(x, tau, frame), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(ekf.f(x), _f_ref(x, Z3, frame), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("frame", ["body", "ned"])
@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_jacobian_against_finite_differences(frame, seed):
    ekf = default_ekf(bias_frame=frame, antenna_offset=(1.5, -0.4))
    rng = np.random.default_rng(seed)
    x, tau = _ship_state(rng), rng.normal(0, 50, 3)
    J = ekf.jacobian(x)
    num = np.empty((9, 9))
    for j in range(9):
        h = 1e-6 * max(1.0, abs(x[j]))
        e = np.zeros(9)
        e[j] = h
        num[:, j] = (ekf.f(x + e, tau) - ekf.f(x - e, tau)) / (2 * h)
    np.testing.assert_allclose(J, num, rtol=1e-6, atol=1e-9)
    # measurement Jacobian with a lever arm
    _, H = ekf.measurement_model(x)
    numH = np.empty((3, 9))
    for j in range(9):
        e = np.zeros(9)
        e[j] = 1e-6
        numH[:, j] = (ekf.measurement_model(x + e)[0] - ekf.measurement_model(x - e)[0]) / 2e-6
    np.testing.assert_allclose(H, numH, atol=1e-8)


def test_one_step_is_table5_euler():
    """One call = eqs. 43-45 at T = 1 s: x+ = x + T f, P+ = F P F^T + G Q G^T (G = T E)."""
    cfg = ekf_config("tomera-ekf")
    ekf = ExtendedKalmanFilter(cfg)
    rng = np.random.default_rng(3)
    x0 = _ship_state(rng)
    P0 = np.diag(cfg.P0)
    ekf.reset(0.0, x0[:3], nu0=x0[3:6], bias0=x0[6:9])
    tau = np.array([40.0, -10.0, 30.0])
    ekf.step(1.0, None, tau)
    F = np.eye(9) + ekf.jacobian(x0)
    G = np.vstack([np.zeros((6, 3)), np.eye(3)])
    np.testing.assert_allclose(ekf.state, x0 + _f_ref(x0, tau), rtol=1e-12)
    np.testing.assert_allclose(ekf.estimate().P, F @ P0 @ F.T + G @ (0.1 * np.eye(3)) @ G.T)
    # a 10 s coast is 10 Euler sub-steps of 1 s (max_substep)
    a, b = tomera_ekf(), tomera_ekf()
    for o in (a, b):
        o.reset(0.0, x0[:3], nu0=x0[3:6], bias0=x0[6:9])
    a.step(10.0, None, tau)
    for k in range(1, 11):
        b.step(float(k), None, tau)
    np.testing.assert_allclose(a.state, b.state, rtol=1e-12)
    np.testing.assert_allclose(a.estimate().P, b.estimate().P, rtol=1e-12)


def test_euler_model_converges_to_continuous_solution():
    """The prediction with a small period approaches the exact ODE solution (eq. 36)."""
    ekf = default_ekf(max_substep=0.01)
    x0 = np.array([0.0, 0.0, 0.5, 0.4, -0.05, 0.01, 10.0, -20.0, 30.0])
    tau = np.array([50.0, 20.0, -40.0])
    ekf.reset(0.0, x0[:3], nu0=x0[3:6], bias0=x0[6:9])
    ekf.step(60.0, None, tau)
    sol = solve_ivp(lambda t, x: _f_ref(x, tau), (0, 60), x0, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(ekf.state, sol.y[:, -1], rtol=2e-3, atol=2e-3)


# ---- statistical consistency -----------------------------------------------------------------
@pytest.mark.parametrize("preset", ["ekf", "tomera-ekf"])
def test_nees_and_nis_consistency(preset):
    """Monte Carlo on the filter's own Euler-discrete model: NEES and NIS within 95 % bounds."""
    cfg = ekf_config(preset, gate_probability=None)
    n_runs, n_steps, T = 50, 120, 1.0
    Qd = T * _noise_cov(cfg)
    Lq = np.linalg.cholesky(Qd + 1e-30 * np.eye(9))
    R = np.array(cfg.R)
    Lr = np.linalg.cholesky(R)
    P0 = np.diag(cfg.P0)
    rng = np.random.default_rng(2024)
    nees = np.empty((n_runs, n_steps))
    nis = np.empty((n_runs, n_steps))
    ref = ExtendedKalmanFilter(cfg)  # only its vector field f, for the truth
    for i in range(n_runs):
        x_hat0 = np.array([0, 0, 1.0, 0.2, 0, 0, 0, 0, 0])
        x = x_hat0 + np.sqrt(np.diag(P0)) * rng.standard_normal(9)
        ekf = ExtendedKalmanFilter(cfg)
        ekf.reset(0.0, x_hat0[:3], nu0=x_hat0[3:6], bias0=x_hat0[6:9], P0=P0)
        for k in range(n_steps):
            tau = _tau(k)
            x = x + T * ref.f(x, tau) + Lq @ rng.standard_normal(9)
            z = x[:3] + Lr @ rng.standard_normal(3)
            z[2] = wrap_angle(z[2])
            info = ekf.step((k + 1) * T, z, tau)
            est = ekf.estimate()
            e = x - np.concatenate([est.eta, est.nu, est.bias])
            e[2] = wrap_angle(e[2])
            nees[i, k] = e @ np.linalg.solve(est.P, e)
            nis[i, k] = info.nis
    for stat, dof in ((nees, 9), (nis, 3)):
        lo, hi = chi2.ppf([0.025, 0.975], n_runs * dof) / n_runs
        inside = np.mean((stat.mean(axis=0) >= lo) & (stat.mean(axis=0) <= hi))
        assert inside >= 0.9, (dof, inside, stat.mean(axis=0))
        assert abs(stat.mean() / dof - 1.0) < 0.1


# ---- heading continuity ----------------------------------------------------------------------
@pytest.mark.parametrize("z_range", ["pm180", "0-360"])
def test_heading_crossing_north_and_south_without_jumps(z_range):
    """A ship turning through 360 deg twice: estimates continuous whatever the z convention."""
    T, r = 1.0, 0.02  # 1.15 deg/s: crosses north and south several times in 700 s
    nu = np.array([0.3, 0.0, r])
    tau = D_L @ nu  # steady turn in the model
    sens = Sensors(SensorConfig())
    sens.reset(np.random.default_rng(9))
    ekf = default_ekf()
    psi0 = -0.5
    ekf.reset(0.0, [0.0, 0.0, psi0], nu0=nu)
    eta = np.array([0.0, 0.0, psi0])
    psi_hat, nu_hat = [], []
    for k in range(700):
        eta = eta + T * rot(eta[2]) @ nu
        z = sens.measure((k + 1) * T, eta).z
        if z_range == "0-360":
            z[2] = z[2] % (2 * math.pi)  # gyro repeaters give 0..360 deg
        info = ekf.step((k + 1) * T, z, tau)
        assert -math.pi < info.innovation[2] <= math.pi
        assert abs(info.innovation[2]) < 0.05 and not info.rejected
        est = ekf.estimate()
        psi_hat.append(est.eta[2])
        nu_hat.append(est.nu)
        assert abs(wrap_angle(est.eta[2] - eta[2])) < 0.02
    psi_hat, nu_hat = np.array(psi_hat), np.array(nu_hat)
    assert psi_hat[-1] - psi_hat[0] == pytest.approx(699 * r, abs=0.05)  # unwrapped, 8 rad
    np.testing.assert_array_less(np.abs(np.diff(psi_hat) - r * T), 0.01)
    # after the start-up transient no estimate moves by more than noise per sample
    assert np.all(np.abs(np.diff(nu_hat[50:], axis=0)) < [0.01, 0.01, 0.001])
    assert np.all(np.abs(nu_hat[100:] - nu) < [0.03, 0.03, 0.002])


# ---- faults: dropout, outlier, real jump -----------------------------------------------------
def _own_model_run(ekf, n, fault, seed=1):
    """Truth = the EKF's own model (no process noise), default sensor noise; returns errors."""
    sens = Sensors(SensorConfig())
    sens.reset(np.random.default_rng(seed))
    x = np.array([0.0, 0.0, 0.3, 0.2, 0.0, 0.0, 10.0, -15.0, 20.0])
    ekf.reset(0.0, x[:3], nu0=x[3:6])
    errs, infos = [], []
    for k in range(n):
        tau = _tau(k)
        x = x + ekf.f(x, tau)
        z = sens.measure(k + 1.0, x[:3]).z
        z = fault(k, z)
        infos.append(ekf.step(k + 1.0, z, tau))
        est = ekf.estimate()
        e = np.r_[est.eta - x[:3], est.nu - x[3:6]]
        e[2] = wrap_angle(e[2])
        errs.append(e)
    return np.array(errs), infos


@pytest.mark.parametrize("make", [default_ekf, tomera_ekf])
def test_dropout_and_outlier_do_not_diverge(make):
    def fault(k, z):
        if 100 <= k < 110:  # 10 s dropout
            return None
        if k == 150:  # single 20 m outlier
            return z + np.array([20.0 * math.cos(1.0), 20.0 * math.sin(1.0), 0.0])
        return z

    errs, infos = _own_model_run(make(), 250, fault)
    assert not any(i.forced for i in infos)
    assert infos[105].nis is None and np.all(np.isnan(infos[105].innovation))
    assert infos[150].rejected and infos[150].nis > 100
    assert sum(i.rejected for i in infos) == 1
    pos = np.hypot(errs[:, 0], errs[:, 1])
    assert pos[60:].max() < 1.0
    assert pos[110:].max() < 1.0  # after the dropout
    assert np.all(np.abs(errs[60:, 3:5]) < 0.1)
    # without the gate the outlier still does not make it diverge, but it hurts
    if make is default_ekf:
        errs2, _ = _own_model_run(make(gate_probability=None), 250, fault)
        assert np.hypot(errs2[150, 0], errs2[150, 1]) > pos[150]
        assert np.hypot(errs2[-1, 0], errs2[-1, 1]) < 1.0


def test_recovers_after_a_real_jump():
    """A permanent 5 m shift of the position fix is accepted after max_rejections samples."""
    shift = np.array([3.0, 4.0, 0.0])

    def fault(k, z):
        return z + shift if k >= 100 else z

    ekf = default_ekf(max_rejections=3)
    errs, infos = _own_model_run(ekf, 160, fault)
    assert [i.rejected for i in infos[100:104]] == [True, True, True, False]
    assert [i.forced for i in infos[100:106]] == [False, False, False, True, False, False]
    assert max(i.nis for i in infos[104:]) < 21.2  # one forced update re-anchored it
    # the estimate follows the shifted fix soon after
    np.testing.assert_allclose(errs[110:, :2], np.tile(shift[:2], (50, 1)), atol=0.5)


# ---- bias estimation -------------------------------------------------------------------------
@pytest.mark.parametrize("hold", [False, True])
def test_bias_converges_to_constant_body_force(hold):
    """M nu_dot + D_L nu = tau + b_true with b_true = [0, 20, -20] (N, N, N m) in the body."""
    b_true = np.array([0.0, 20.0, -20.0])
    sens = Sensors(SensorConfig())
    sens.reset(np.random.default_rng(5))
    ekf = default_ekf()
    eta, nu = np.array([0.0, 0.0, 0.2]), np.zeros(3)
    ekf.reset(0.0, sens.measure(0.0, eta).z)
    Minv = np.linalg.inv(M)
    dt, n_sub = 0.05, 20
    bias = []
    for k in range(900):
        est = ekf.estimate()
        if hold:  # simple DP feedback on the estimate, without integral action
            e = est.eta - np.array([0, 0, 0.2])
            e[2] = wrap_angle(e[2])
            w = np.array([0.05, 0.05, 0.08])
            tau = M @ (-(rot(est.eta[2]).T @ (w**2 * e)) - 2 * w * est.nu) + D_L @ est.nu
        else:  # let it drift and turn
            tau = Z3
        for _ in range(n_sub):  # midpoint rule on the continuous truth
            a1 = Minv @ (tau + b_true - D_L @ nu)
            nu_m = nu + 0.5 * dt * a1
            eta_m = eta + 0.5 * dt * rot(eta[2]) @ nu
            eta = eta + dt * rot(eta_m[2]) @ nu_m
            nu = nu + dt * Minv @ (tau + b_true - D_L @ nu_m)
        ekf.step((k + 1) * 1.0, sens.measure((k + 1) * 1.0, eta).z, tau)
        bias.append(ekf.estimate().bias)
    b_end = np.mean(bias[-100:], axis=0)
    np.testing.assert_allclose(b_end, b_true, atol=0.2 * 20.0)
    if not hold:
        assert abs(eta[2] - 0.2) > 2 * math.pi  # it really turned around
    else:
        assert math.hypot(eta[0], eta[1]) < 10.0


# ---- presets and configuration ---------------------------------------------------------------
def test_presets():
    assert set(EKF_PRESETS) == {"ekf", "tomera-ekf"}
    t = tomera_ekf()
    assert t.name == "tomera-ekf"
    c = t.config
    np.testing.assert_allclose(c.M, np.diag([23664.9, 24830.6, 455182.1]))  # eq. 49
    np.testing.assert_allclose(c.D_L, [[21.1, 0, 0], [0, 259.8, -855.4], [0, -855.4, 6130.5]])
    assert c.T_b == (1000.0, 1000.0, 1000.0)  # eq. 51
    np.testing.assert_allclose(c.Q, 0.1 * np.eye(3))  # eq. 52
    np.testing.assert_allclose(c.R, 0.1 * np.eye(3))  # eq. 53
    np.testing.assert_allclose(c.E_b, np.eye(3))
    np.testing.assert_allclose(c.Q_nu, 0.0)
    assert c.bias_frame == "body" and c.antenna_offset == (0.0, 0.0)
    d = default_ekf()
    assert d.name == "ekf"
    np.testing.assert_allclose(d.config.R, SensorConfig().covariance)
    assert np.all(np.diag(d.config.Q_nu) > 0)
    o = default_ekf(Q=[1.0, 2.0, 3.0], T_b=500.0, R=SensorConfig(position_variance=4.0).covariance)
    np.testing.assert_allclose(o.config.Q, np.diag([1.0, 2.0, 3.0]))
    assert o.config.T_b == (500.0,) * 3 and o.config.R[0][0] == 4.0
    with pytest.raises(ValueError, match="tomera-ekf, ekf"):
        ekf_config("ukf")
    with pytest.raises(ValueError, match="unknown key"):
        default_ekf(Qb=1.0)
    for f in dataclasses.fields(EKFConfig):  # the vessel's M, D_L: a meaning, no source
        assert f.metadata.get("unit") and (f.metadata.get("source") or f.metadata["meaning"])
    assert EKFConfig.from_dict(c.to_dict()) == c


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"Q": [0.1, -0.1, 0.1]}, "Q must be positive definite"),
        ({"Q": 0.0}, "Q must be positive definite"),
        ({"R": [[1, 2, 0], [2, 1, 0], [0, 0, 1]]}, "R must be positive definite"),
        ({"R": [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]}, "R must be symmetric"),
        ({"R": [0.1, 0.1]}, r"R must be .* 3x3"),
        ({"R": np.eye(4)}, r"R must be .* 3x3"),
        ({"Q": [0.1, np.nan, 0.1]}, "Q must be finite"),
        ({"Q_nu": [-1e-6, 0, 0]}, "Q_nu must be positive semi-definite"),
        ({"M": np.diag([1.0, -1.0, 1.0])}, "M must be invertible"),
        ({"M": np.ones((3, 3))}, "M must be invertible"),
        ({"D_L": np.ones((2, 2))}, r"D_L must be .* 3x3"),
        ({"T_b": [1000.0, 0.0, 1000.0]}, "T_b must be"),
        ({"T_b": [1.0, 2.0]}, "T_b must be"),
        ({"P0": [1.0] * 8}, "P0 must be 9"),
        ({"P0": [1.0] * 8 + [-1.0]}, "P0 must be 9"),
        ({"bias_frame": "earth"}, "bias_frame"),
        ({"antenna_offset": (1.0,)}, "antenna_offset"),
        ({"gate_probability": 1.0}, "gate_probability"),
        ({"max_rejections": 0}, "max_rejections"),
        ({"max_rejections": 1.5}, "max_rejections"),
        ({"max_substep": 0.0}, "max_substep"),
        ({"Q": "big"}, "Q must be numeric"),
    ],
)
def test_bad_config(kw, match):
    with pytest.raises(ValueError, match=match):
        EKFConfig(**{**BLUE_LADY_DESIGN, **kw})


def test_bad_runtime_input():
    ekf = default_ekf()
    with pytest.raises(RuntimeError, match="reset"):
        ekf.step(1.0, [0, 0, 0])
    with pytest.raises(RuntimeError, match="reset"):
        ekf.estimate()
    with pytest.raises(TypeError, match="EKFConfig"):
        ExtendedKalmanFilter({"Q": 1.0})
    with pytest.raises(ValueError, match="eta0"):
        ekf.reset(0.0, [0, 0])
    with pytest.raises(ValueError, match="nu0"):
        ekf.reset(0.0, [0, 0, 0], nu0=[0, np.inf, 0])
    with pytest.raises(ValueError, match="P0"):
        ekf.reset(0.0, [0, 0, 0], P0=-np.eye(9))
    with pytest.raises(ValueError, match="P0"):
        ekf.reset(0.0, [0, 0, 0], P0=np.eye(3))
    ekf.reset(5.0, [0, 0, 0], P0=np.full(9, 0.5))
    assert ekf.estimate().t == 5.0 and np.allclose(np.diag(ekf.estimate().P), 0.5)
    with pytest.raises(ValueError, match="backwards"):
        ekf.step(4.0, None)
    with pytest.raises(ValueError, match="z must be"):
        ekf.step(6.0, [0, 0, np.nan])
    with pytest.raises(ValueError, match="z must be"):
        ekf.step(6.0, [0, 0])
    with pytest.raises(ValueError, match="tau must be"):
        ekf.step(6.0, None, [0, 0])
    info = ekf.step(5.0, [0.0, 0.0, 0.0])  # dt = 0: update only
    assert info.nis is not None and not info.rejected


def test_estimate_is_a_copy_and_consistent():
    ekf = default_ekf()
    ekf.reset(0.0, [1.0, 2.0, math.pi - 0.002], nu0=[0.1, 0.0, 0.0])
    ekf.step(1.0, [1.1, 2.0, -math.pi + 0.002], [10.0, 0.0, 0.0])
    est = ekf.estimate()
    np.testing.assert_allclose(est.P_eta, est.P[:3, :3])
    np.testing.assert_allclose(est.P_nu, est.P[3:6, 3:6])
    assert est.eta[2] > math.pi - 0.002  # the measured -pi + 0.002 is just past south
    est.eta[:] = 0.0
    est.P[:] = 0.0
    assert ekf.estimate().eta[0] != 0.0 and ekf.estimate().P[0, 0] > 0
    np.testing.assert_allclose(ekf.estimate().P, ekf.estimate().P.T)
    assert np.linalg.eigvalsh(ekf.estimate().P).min() > 0
