"""Discrete KF and Kalman-Bucy filters: consistency, heading wrap, dropouts, outliers, errors."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.stats import chi2

from shipgym.dynamics import rot, wrap_angle
from shipgym.observers.base import OBSERVERS, Estimate, OutlierGate, make_observer
from shipgym.observers.design import (
    DKF_DESIGN,
    HEADING_VARIANCE_TOMERA2011,
    KBF_DESIGN,
    TOMERA_DKF,
    TOMERA_KBF,
    discretise,
    double_integrator,
)
from shipgym.observers.kalman import DiscreteKalmanFilter, KalmanBucyFilter

PRESETS = ("tomera-dkf", "tomera-kbf", "dkf", "kbf")
SIGMA = np.sqrt([0.01, 0.01, HEADING_VARIANCE_TOMERA2011])  # default sensor noise (m, m, rad)


# --------------------------------------------------------------------------------------------
# Statistical consistency on each filter's own linear-Gaussian model
# --------------------------------------------------------------------------------------------


def _monte_carlo(make, design, T, steps, runs=50, seed=0):
    """Simulate the per-DOF double integrators with the design's own Q and R exactly.

    Returns NEES (runs, steps) of the 6-state [eta, eta_dot] and NIS (runs, steps).
    """
    A, _ = double_integrator()
    if isinstance(make(), DiscreteKalmanFilter):
        F, Qk = design.sampled(T)  # the DKF's own discretisation (euler or exact)
    else:  # the continuous model, sampled exactly
        pairs = [discretise(A, W, T, method="exact") for W in design.intensity()]
        F, Qk = pairs[0][0], np.stack([q for _, q in pairs])
    w, V = np.linalg.eigh(Qk)
    Lq = V * np.sqrt(np.clip(w, 0.0, None))[:, None, :]  # Lq Lq^T = Qk (Qk may be singular)
    R = design.variance()
    rng = np.random.default_rng(seed)
    eta0 = np.array([10.0, -5.0, 1.0])
    nees = np.empty((runs, steps))
    nis = np.empty((runs, steps))
    for r in range(runs):
        obs = make()
        obs.reset(0.0, eta0)
        P0 = obs.P  # the filter's prior: truth drawn from it
        x = obs.x + np.linalg.cholesky(P0) @ rng.standard_normal(6)
        s = np.stack([x[3:], x[:3]], axis=1)  # per DOF [velocity, position]
        e_all = np.empty((steps, 6))
        P_all = np.empty((steps, 6, 6))
        for k in range(steps):
            s = s @ F.T + np.einsum("dij,dj->di", Lq, rng.standard_normal((3, 2)))
            z = s[:, 1] + np.sqrt(R) * rng.standard_normal(3)
            nis[r, k] = obs.step((k + 1) * T, z).nis
            e_all[k] = np.concatenate([s[:, 1], s[:, 0]]) - obs.x
            P_all[k] = obs.P
        nees[r] = np.einsum("ki,ki->k", e_all, np.linalg.solve(P_all, e_all[:, :, None])[:, :, 0])
    return nees, nis


def _check_consistency(nees, nis, every):
    """Chi-square tests of NEES (6 dof) and NIS (3 dof) over the runs (Bar-Shalom et al. 2001,
    sec. 5.4): the run average at each step inside its two-sided 95 % interval for >= 90 % of
    the steps, and the average over runs and steps inside its own (tighter) 95 % interval.

    Errors are correlated over a few filter time constants (~4 s), so the time averages use
    steps ``every`` apart (10 s); the sampled-data KBF's innovations are not exactly white
    either (its NIS is ~1 % low at 0.2 s). Each criterion is a 95 % test, so a consistent
    filter fails one of them for a few per cent of seeds; the seed is fixed (0).
    """
    for stat, dof in ((nees, 6), (nis, 3)):
        runs, _ = stat.shape
        lo, hi = chi2.ppf([0.025, 0.975], runs * dof) / runs
        avg = stat.mean(axis=0)
        inside = np.mean((avg >= lo) & (avg <= hi))
        assert inside >= 0.9, f"{dof} dof: {inside:.0%} of the steps in [{lo:.2f}, {hi:.2f}]"
        sub = stat[:, every - 1 :: every]
        lo, hi = chi2.ppf([0.025, 0.975], sub.size * dof) / sub.size
        assert lo <= sub.mean() <= hi, (
            f"{dof} dof: mean {sub.mean():.3f} not in [{lo:.3f}, {hi:.3f}]"
        )


@pytest.mark.parametrize(
    ("make", "design"),
    [
        (lambda: DiscreteKalmanFilter(DKF_DESIGN, gate_probability=None), DKF_DESIGN),
        (
            lambda: DiscreteKalmanFilter(TOMERA_DKF, constant_gain=True, gate_probability=None),
            TOMERA_DKF,
        ),
    ],
    ids=["dkf", "tomera-dkf"],
)
def test_dkf_nees_nis_consistent(make, design):
    nees, nis = _monte_carlo(make, design, T=1.0, steps=100)
    _check_consistency(nees, nis, every=10)


# The continuous filter's own model is a continuous measurement: sample it 5x faster than the
# design (0.2 s, omega T ~ 0.06) with the same intensity R_c = R T, i.e. R / 0.2 per sample.
_KBF_FAST = KBF_DESIGN.replace(T=0.2, R=tuple(r / 0.2 for r in KBF_DESIGN.R))
_TOMERA_KBF_FAST = TOMERA_KBF.replace(T=0.2, R=tuple(r / 0.2 for r in TOMERA_KBF.R))


@pytest.mark.parametrize(
    ("make", "design"),
    [
        (lambda: KalmanBucyFilter(_KBF_FAST, gate_probability=None), _KBF_FAST),
        (
            lambda: KalmanBucyFilter(_TOMERA_KBF_FAST, steady_state=True, gate_probability=None),
            _TOMERA_KBF_FAST,
        ),
    ],
    ids=["kbf", "tomera-kbf"],
)
def test_kbf_nees_nis_consistent(make, design):
    nees, nis = _monte_carlo(make, design, T=0.2, steps=300)
    _check_consistency(nees, nis, every=50)


def test_kbf_at_one_second_is_conservative_not_optimistic():
    """At the design period T = 1 s the continuous P over-bounds the sampled-data error by
    5-15 % (bandwidths 0.35-0.43 rad/s): one long run, NEES averaged over 2000 s."""
    make = lambda: KalmanBucyFilter(KBF_DESIGN, gate_probability=None)  # noqa: E731
    nees, _ = _monte_carlo(make, KBF_DESIGN, T=1.0, steps=2000, runs=1)
    assert 0.75 * 6 < nees[0, 50:].mean() < 6.0


# --------------------------------------------------------------------------------------------
# Exactness of the sampled-data Kalman-Bucy step
# --------------------------------------------------------------------------------------------


def _per_dof(f):
    """Per DOF ``[velocity, position]`` state (3, 2) and 2x2 covariance (3, 2, 2) of a filter."""
    x, P = f.x, f.P
    s = np.column_stack([x[3:], x[:3]])
    Pd = np.array([[[P[i + 3, i + 3], P[i + 3, i]], [P[i, i + 3], P[i, i]]] for i in range(3)])
    return s, Pd


@pytest.mark.parametrize("steady_state", [False, True])
def test_kbf_interval_matches_ode_integration(steady_state):
    """One interval equals a tight solve_ivp of Tomera (2014) Table 4 with the first-order hold."""
    f = KalmanBucyFilter(TOMERA_KBF, steady_state=steady_state, gate_probability=None)
    f.reset(0.0, [1.0, 2.0, 0.5], nu0=[0.1, 0.02, 0.01])
    f.step(0.5, [1.03, 2.0, 0.503])  # gives a previous sample for the hold
    s0, P0 = _per_dof(f)
    y0 = f._b._yprev[:, 0].copy()  # the hold's start (m, m, rad)
    z, dt = np.array([1.2, 2.1, 0.52]), 1.3
    f.step(0.5 + dt, z)
    A, C = double_integrator()
    W, Rc = TOMERA_KBF.intensity(), TOMERA_KBF.variance() * TOMERA_KBF.T
    L = TOMERA_KBF.kbf_gains()[0]
    for i in range(3):

        def rhs(t, v, i=i):
            s, P = v[:2], v[2:].reshape(2, 2)
            y = y0[i] + (z[i] - y0[i]) * t / dt
            if steady_state:
                Acl = A - np.outer(L[i], C)
                dP = Acl @ P + P @ Acl.T + W[i] + Rc[i] * np.outer(L[i], L[i])
                K = L[i]
            else:
                dP = A @ P + P @ A.T + W[i] - P @ C.T @ C @ P / Rc[i]
                K = P[:, 1] / Rc[i]
            return np.concatenate([A @ s + K * (y - s[1]), dP.ravel()])

        x0 = np.concatenate([s0[i], P0[i].ravel()])
        sol = solve_ivp(rhs, (0.0, dt), x0, method="DOP853", rtol=1e-12, atol=1e-15)
        s1, P1 = _per_dof(f)
        np.testing.assert_allclose(s1[i], sol.y[:2, -1], atol=1e-9)
        np.testing.assert_allclose(P1[i].ravel(), sol.y[2:, -1], rtol=1e-8, atol=1e-14)


def test_kbf_tracks_a_ramp_without_bias():
    """First-order hold: a ship at constant speed is tracked with zero steady-state error."""
    for name in ("kbf", "tomera-kbf"):
        obs = make_observer(name)
        v = np.array([0.2, -0.1, math.radians(1.0)])
        obs.reset(0.0, [0.0, 0.0, 0.0])
        for k in range(1, 120):
            obs.step(float(k), v * k)
        est = obs.estimate()
        np.testing.assert_allclose(est.eta, v * 119, atol=1e-6)
        np.testing.assert_allclose(obs.x[3:], v, atol=1e-6)


# --------------------------------------------------------------------------------------------
# Seed numbers
# --------------------------------------------------------------------------------------------


def test_tomera_presets_steady_state_gains():
    np.testing.assert_allclose(
        make_observer("tomera-dkf").steady_state_gain, [[0.07945, 0.36868]] * 3, rtol=1e-4
    )
    np.testing.assert_allclose(
        make_observer("tomera-kbf").steady_state_gain, [[0.1, 0.45826]] * 3, rtol=1e-4
    )


def test_tomera_dkf_applies_eq30_gain():
    obs = make_observer("tomera-dkf")
    obs.reset(0.0, [0.0, 0.0, 0.0])
    x_bar = obs.x  # at rest: the prediction over 1 s is the same state
    obs.step(1.0, [0.1, -0.2, 0.001])
    dx = obs.x - x_bar
    np.testing.assert_allclose(dx[:3], 0.36868 * np.array([0.1, -0.2, 0.001]), rtol=1e-4)
    np.testing.assert_allclose(dx[3:], 0.07945 * np.array([0.1, -0.2, 0.001]), rtol=1e-4)


def test_time_varying_gain_settles_within_twelve_seconds():
    """Tomera (2014): the recursive gains of Table 3 'are steady-state within the first twelve
    s'."""
    obs = DiscreteKalmanFilter(TOMERA_DKF, gate_probability=None)
    obs.reset(0.0, [0.0, 0.0, 0.0])
    for k in range(1, 13):
        obs.step(float(k), [0.0, 0.0, 0.0])
    np.testing.assert_allclose(obs.last_gain[:2], [[0.07945, 0.36868]] * 2, rtol=0.02)


# --------------------------------------------------------------------------------------------
# Heading through north, dropouts, outliers
# --------------------------------------------------------------------------------------------


def _turning_ship(n, r_deg=1.0, psi0_deg=340.0, speed=0.2, seed=1):
    """A ship turning steadily through north: truth and measurements (heading wrapped)."""
    r, psi0 = math.radians(r_deg), math.radians(psi0_deg)
    t = np.arange(n, dtype=float)
    psi = psi0 + r * t
    R = speed / r
    x = R * np.sin(psi) - R * np.sin(psi0)
    y = -R * np.cos(psi) + R * np.cos(psi0)
    eta = np.stack([x, y, psi], axis=1)
    z = eta + SIGMA * np.random.default_rng(seed).standard_normal((n, 3))
    z[:, 2] = wrap_angle(z[:, 2])
    return t, eta, z, np.array([speed, 0.0, r])


@pytest.mark.parametrize("name", PRESETS)
def test_heading_through_north_no_jump(name):
    t, eta, z, nu_true = _turning_ship(80)
    obs = make_observer(name)
    obs.reset(t[0], z[0], nu0=nu_true)
    ests = []
    for k in range(1, len(t)):
        info = obs.step(t[k], z[k])
        assert not info.rejected
        assert abs(info.innovation[2]) < 0.1
        ests.append(obs.estimate())
    psi_hat = np.array([e.eta[2] for e in ests])
    nu_hat = np.array([e.nu for e in ests])
    # the crossing is at t = 20 s; no jump anywhere once the start-up transient is over
    assert np.all(np.abs(np.diff(psi_hat)) < math.radians(3.0))  # continuous, ~1 deg/s
    # (an unwrapped 2 pi innovation would move r by ~0.08 * 2 pi rad/s)
    assert np.all(np.abs(np.diff(nu_hat[10:], axis=0)) < [0.05, 0.05, math.radians(0.3)])
    assert np.all(np.abs(wrap_angle(psi_hat - eta[1:, 2])) < math.radians(1.0))
    assert np.all(np.abs(nu_hat[30:] - nu_true) < [0.05, 0.05, math.radians(0.2)])
    assert psi_hat[-1] - psi_hat[0] == pytest.approx(math.radians(78.0), abs=math.radians(1.0))


@pytest.mark.parametrize("name", PRESETS)
def test_dropout_then_recovery(name):
    t, eta, z, _ = _turning_ship(100, r_deg=0.2)
    obs = make_observer(name)
    obs.reset(t[0], z[0])
    var = []
    for k in range(1, len(t)):
        info = obs.step(t[k], None if 50 <= k < 60 else z[k])
        if 50 <= k < 60:
            assert info.nis is None and np.isnan(info.innovation).all()
        var.append(np.diag(obs.estimate().P_eta))
        err = obs.estimate().eta - eta[k]
        assert np.all(np.abs(err[:2]) < 1.0), (k, err)
    var = np.array(var)
    assert np.all(np.diff(var[49:59, 0]) > 0)  # grows while coasting
    assert var[-1, 0] < var[58, 0]  # shrinks again
    err = obs.estimate().eta - eta[-1]
    err[2] = wrap_angle(err[2])
    assert np.all(np.abs(err) < [0.3, 0.3, math.radians(1.0)])


@pytest.mark.parametrize("name", PRESETS)
def test_irregular_and_zero_intervals(name):
    """Any interval works (fractions, 1e-4 s, repeated times); the estimate stays on track."""
    rng = np.random.default_rng(3)
    times = np.cumsum(rng.choice([1.0, 0.37, 1e-4, 0.0, 2.5], size=150))
    v = np.array([0.2, -0.05, math.radians(0.5)])
    obs = make_observer(name)
    obs.reset(0.0, [0.0, 0.0, 0.0], nu0=v)
    for t in times:
        z = v * t + SIGMA * rng.standard_normal(3)
        info = obs.step(t, None if rng.random() < 0.1 else z)
        assert not info.rejected
    est = obs.estimate()
    assert est.t == times[-1]
    np.testing.assert_allclose(est.eta, v * times[-1], atol=0.3)
    assert np.all(np.abs(obs.x[3:] - v) < [0.05, 0.05, 0.005])  # NED rates


@pytest.mark.parametrize("name", PRESETS)
def test_single_outlier_rejected(name):
    t, eta, z, _ = _turning_ship(60)
    z[40, 0] += 20.0
    obs = make_observer(name)
    obs.reset(t[0], z[0])
    for k in range(1, len(t)):
        info = obs.step(t[k], z[k])
        assert info.rejected == (k == 40)
        assert np.all(np.abs(obs.estimate().eta[:2] - eta[k, :2]) < 1.0)


@pytest.mark.parametrize("name", PRESETS)
def test_real_jump_is_followed_after_max_rejections(name):
    t, eta, z, _ = _turning_ship(100)
    z[40:, 0] += 20.0  # a persistent 20 m shift (e.g. a new DGPS reference)
    obs = make_observer(name)
    obs.reset(t[0], z[0])
    rejected = []
    for k in range(1, len(t)):
        info = obs.step(t[k], z[k])
        rejected.append(info.rejected)
    assert sum(rejected) == obs.gate.max_rejections == 5
    assert np.all(np.abs(obs.estimate().eta[:2] - eta[-1, :2] - [20.0, 0.0]) < 0.5)


def test_outlier_gate_logic():
    gate = OutlierGate(0.9999, max_rejections=2)
    assert gate.threshold == pytest.approx(chi2.ppf(0.9999, 3))
    assert [gate.check(v) for v in (1.0, 50, 50, 50, 50, 1.0, 50)] == [
        "accept",
        "reject",
        "reject",
        "force",
        "force",  # the gate stays open until a measurement passes it
        "accept",
        "reject",
    ]
    assert OutlierGate(None).check(1e12) == "accept"


# --------------------------------------------------------------------------------------------
# Interface, estimate, registry, errors
# --------------------------------------------------------------------------------------------


def test_estimate_nu_and_its_covariance():
    obs = make_observer("dkf")
    psi = math.radians(30.0)
    obs.reset(0.0, [1.0, 2.0, psi], nu0=[0.2, 0.05, 0.01])
    est = obs.estimate()
    assert isinstance(est, Estimate) and est.t == 0.0
    np.testing.assert_allclose(est.nu, [0.2, 0.05, 0.01], atol=1e-15)
    np.testing.assert_allclose(obs.x[3:], rot(psi) @ [0.2, 0.05, 0.01], atol=1e-15)
    # P_nu = J P J^T with the Jacobian of nu = R^T(psi) eta_dot (finite differences)
    x0 = obs.x

    def nu_of(x):
        return rot(x[2]).T @ x[3:]

    J = np.stack([(nu_of(x0 + h) - nu_of(x0 - h)) / 2e-6 for h in 1e-6 * np.eye(6)], axis=1)
    np.testing.assert_allclose(est.P_nu, J @ est.P @ J.T, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(est.P_eta, est.P[:3, :3])
    est.eta[0] = 99.0  # a copy
    assert obs.estimate().eta[0] == 1.0


def test_registry_and_overrides():
    assert set(PRESETS) <= set(OBSERVERS)
    a, b = make_observer("dkf"), make_observer("dkf")
    assert a is not b and a.name == "dkf"
    obs = make_observer("kbf", position_variance=4.0, gate_probability=None, steady_state=True)
    assert obs.design.R[:2] == (4.0, 4.0) and obs.steady_state and obs.gate.probability is None
    obs = make_observer("tomera-dkf", constant_gain=False, R=(0.02, 0.02, 1e-4))
    assert not obs.constant_gain and obs.design.R == (0.02, 0.02, 1e-4)
    with pytest.raises(ValueError, match="unknown observer 'pf'.*dkf.*kbf"):
        make_observer("pf")
    with pytest.raises(ValueError, match="unknown option"):
        make_observer("dkf", q=1.0)


@pytest.mark.parametrize(
    ("overrides", "match"),
    [
        ({"Q": [[-1e-4]]}, "positive semi-definite"),
        ({"R": (0.01, 0.01, 0.0)}, "positive definite"),
        ({"R": (0.01, -1.0, 0.01)}, "positive definite"),
        ({"Q": np.eye(2)}, "to match G"),
        ({"G": np.eye(3)}, "2 rows"),
        ({"R": (0.01, 0.01)}, "one variance or three"),
        ({"gate_probability": 1.5}, "gate_probability"),
        ({"max_rejections": 0}, "max_rejections"),
        ({"initial_velocity_std": (1.0, 1.0)}, "initial_velocity_std"),
    ],
)
@pytest.mark.parametrize("name", ["dkf", "kbf"])
def test_bad_configuration_raises(name, overrides, match):
    with pytest.raises(ValueError, match=match):
        make_observer(name, **overrides)


@pytest.mark.parametrize("name", PRESETS)
def test_bad_calls_raise(name):
    obs = make_observer(name)
    with pytest.raises(RuntimeError, match="reset"):
        obs.step(1.0, [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="eta0"):
        obs.reset(0.0, [0.0, 0.0])
    with pytest.raises(ValueError, match="P0"):
        obs.reset(0.0, [0.0, 0.0, 0.0], P0=-np.eye(6))
    with pytest.raises(ValueError, match="P0"):
        obs.reset(0.0, [0.0, 0.0, 0.0], P0=np.eye(3))
    obs.reset(5.0, [0.0, 0.0, 0.0], P0=np.eye(6))
    np.testing.assert_array_equal(obs.estimate().P, np.eye(6))
    with pytest.raises(ValueError, match="backwards"):
        obs.step(4.0, [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="z must be 3 finite"):
        obs.step(6.0, [0.0, np.nan, 0.0])
    with pytest.raises(ValueError, match="tau"):
        obs.step(6.0, [0.0, 0.0, 0.0], tau=[1.0, 2.0])
    info = obs.step(6.0, [0.0, 0.0, 0.0], tau=[10.0, 0.0, 0.0])  # tau accepted (not used)
    assert info.nis is not None and not info.rejected
