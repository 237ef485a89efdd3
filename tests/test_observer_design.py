"""Gain design: lqe/dlqe against python-control and scipy, closed forms, errors, Tomera's gains."""

import math

import control
import numpy as np
import pytest
import scipy.linalg
from _helpers import assert_same_characteristic_polynomial as _same_poles
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from shipgym.observers.design import (
    DKF_DESIGN,
    HEADING_VARIANCE_TOMERA2011,
    KBF_DESIGN,
    POSITION_VARIANCE_TOMERA2011,
    TOMERA_DKF,
    TOMERA_KBF,
    KalmanDesign,
    discretise,
    dlqe,
    double_integrator,
    lqe,
)
from shipgym.observers.sensors import SensorConfig

EQ30 = np.array([0.07945, 0.36868])  # Tomera (2014) eq. 30, discrete, [velocity, position]
EQ35 = np.array([0.1, 0.45826])  # Tomera (2014) eq. 35, continuous


# --------------------------------------------------------------------------------------------
# Random stabilisable/detectable systems
# --------------------------------------------------------------------------------------------


def _pbh_margin(A, B, discrete, observe):
    """Smallest PBH singular value over the unstable/marginal modes (inf if none)."""
    n = A.shape[0]
    lam = np.linalg.eigvals(A)
    bad = np.abs(lam) >= 1.0 - 1e-3 if discrete else lam.real >= -1e-3
    margin = np.inf
    for mu in lam[bad]:
        M = np.vstack([A - mu * np.eye(n), B]) if observe else np.hstack([A - mu * np.eye(n), B])
        margin = min(margin, np.linalg.svd(M, compute_uv=False)[-1])
    return margin


@st.composite
def systems(draw, discrete):
    n = draw(st.integers(1, 3))
    m = draw(st.integers(1, n))
    p = draw(st.integers(1, 2))
    el = st.floats(-1.5, 1.5, allow_nan=False, allow_infinity=False).map(lambda v: round(v, 3))
    A = draw(arrays(float, (n, n), elements=el))
    G = draw(arrays(float, (n, m), elements=el))
    C = draw(arrays(float, (p, n), elements=el))
    Bq = draw(arrays(float, (m, m), elements=el))
    Br = draw(arrays(float, (p, p), elements=el))
    Q = Bq @ Bq.T + 0.05 * np.eye(m)
    R = Br @ Br.T + 0.1 * np.eye(p)
    # well away from the stabilisability/detectability boundary, so the Riccati solutions are
    # well conditioned and every solver must agree
    assume(_pbh_margin(A, C, discrete, observe=True) > 0.1)
    assume(_pbh_margin(A, G @ np.linalg.cholesky(Q), discrete, observe=False) > 0.1)
    if discrete:
        assume(np.all(np.abs(np.abs(np.linalg.eigvals(A)) - 1.0) > 0.05))
    else:
        assume(np.all(np.abs(np.linalg.eigvals(A).real) > 0.05))
    return A, G, C, Q, R


def _sym(M):
    """Exactly symmetric (python-control rejects G Q G^T with rounding asymmetry)."""
    return 0.5 * (M + M.T)


@settings(max_examples=30, deadline=None)
@given(systems(discrete=False))
def test_lqe_matches_python_control_and_scipy(sys):
    A, G, C, Q, R = sys
    L, P, E = lqe(A, G, C, Q, R)
    Lc, Pc, Ec = control.lqe(A, np.eye(len(A)), C, _sym(G @ Q @ G.T), R)
    scale = 1.0 + np.abs(Pc).max()
    np.testing.assert_allclose(P, Pc, rtol=1e-6, atol=1e-8 * scale)
    np.testing.assert_allclose(L, Lc, rtol=1e-6, atol=1e-8 * (1 + np.abs(Lc).max()))
    _same_poles(E, Ec)
    # scipy directly, and the Riccati equation itself (Tomera 2014 eq. 34)
    Ps = scipy.linalg.solve_continuous_are(A.T, C.T, G @ Q @ G.T, R)
    np.testing.assert_allclose(P, Ps, rtol=1e-6, atol=1e-8 * scale)
    res = A @ P + P @ A.T + G @ Q @ G.T - P @ C.T @ np.linalg.solve(R, C @ P)
    assert np.abs(res).max() < 1e-7 * scale**2
    np.testing.assert_allclose(L, P @ C.T @ np.linalg.inv(R), rtol=1e-8, atol=1e-10 * scale)
    assert np.all(E.real < 0)
    _same_poles(E, np.linalg.eigvals(A - L @ C))


@settings(max_examples=30, deadline=None)
@given(systems(discrete=True))
def test_dlqe_both_forms_match_python_control_and_scipy(sys):
    F, G, H, Q, R = sys
    Lp, P, E = dlqe(F, G, H, Q, R)
    Lc, Pc, Ec = control.dlqe(F, np.eye(len(F)), H, _sym(G @ Q @ G.T), R)
    scale = 1.0 + np.abs(Pc).max()
    np.testing.assert_allclose(P, Pc, rtol=1e-6, atol=1e-8 * scale)
    np.testing.assert_allclose(Lp, Lc, rtol=1e-6, atol=1e-8 * (1 + np.abs(Lc).max()))
    _same_poles(E, Ec)
    Ps = scipy.linalg.solve_discrete_are(F.T, H.T, G @ Q @ G.T, R)
    np.testing.assert_allclose(P, Ps, rtol=1e-6, atol=1e-8 * scale)
    # filter form: same P and E, L = P H^T (H P H^T + R)^-1, and F L_filter = L_predictor
    Lf, Pf, Ef = dlqe(F, G, H, Q, R, form="filter")
    np.testing.assert_array_equal(Pf, P)
    np.testing.assert_array_equal(Ef, E)
    S = H @ P @ H.T + R
    np.testing.assert_allclose(Lf, P @ H.T @ np.linalg.inv(S), rtol=1e-8, atol=1e-10 * scale)
    np.testing.assert_allclose(F @ Lf, Lp, rtol=1e-8, atol=1e-10 * scale)
    assert np.all(np.abs(E) < 1.0)
    _same_poles(E, np.linalg.eigvals((np.eye(len(F)) - Lf @ H) @ F))
    # P is the a priori covariance: it is a fixed point of update + propagation (Tomera 2011 eq. 40)
    P_post = (np.eye(len(F)) - Lf @ H) @ P
    np.testing.assert_allclose(F @ P_post @ F.T + G @ Q @ G.T, P, rtol=1e-6, atol=1e-8 * scale)


# --------------------------------------------------------------------------------------------
# Closed forms
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("q", "r"), [(1.0, 1.0), (0.01, 2.0), (3.0, 0.1)])
def test_lqe_scalar_integrator_closed_form(q, r):
    L, P, E = lqe([[0.0]], [[1.0]], [[1.0]], [[q]], [[r]])
    assert P[0, 0] == pytest.approx(math.sqrt(q * r))
    assert L[0, 0] == pytest.approx(math.sqrt(q / r))
    assert E[0] == pytest.approx(-math.sqrt(q / r))


@pytest.mark.parametrize(("qv", "qp", "r"), [(1e-4, 0.0, 0.01), (0.01, 0.01, 1.0), (2.0, 0.5, 0.3)])
def test_lqe_double_integrator_closed_form(qv, qp, r):
    """L = [sqrt(qv/r), sqrt(2 sqrt(qv/r) + qp/r)] in Tomera's (2011) order [velocity, position]."""
    A, C = double_integrator()
    L, _, _ = lqe(A, np.eye(2), C, np.diag([qv, qp]), r)
    w = math.sqrt(qv / r)
    np.testing.assert_allclose(L[:, 0], [w, math.sqrt(2 * w + qp / r)], rtol=1e-10)


def test_dlqe_scalar_random_walk_closed_form():
    """x+ = x + w, y = x + v: P^2 - q P - q r = 0, K_filter = P / (P + r)."""
    q, r = 0.3, 2.0
    P_exp = 0.5 * (q + math.sqrt(q * q + 4 * q * r))
    L, P, E = dlqe([[1.0]], [[1.0]], [[1.0]], [[q]], [[r]], form="filter")
    assert P[0, 0] == pytest.approx(P_exp)
    assert L[0, 0] == pytest.approx(P_exp / (P_exp + r))
    assert E[0] == pytest.approx(1.0 - P_exp / (P_exp + r))


def test_discretise_exact_and_euler_double_integrator():
    A, _ = double_integrator()
    W = np.array([[2.0, 0.3], [0.3, 0.5]])  # [velocity, position]
    T = 0.7
    F, Q = discretise(A, W, T)
    np.testing.assert_allclose(F, [[1.0, 0.0], [T, 1.0]], atol=1e-14)
    Wv, Wvp, Wp = W[0, 0], W[0, 1], W[1, 1]
    Q_exp = [
        [Wv * T, Wvp * T + Wv * T**2 / 2],
        [Wvp * T + Wv * T**2 / 2, Wp * T + Wvp * T**2 + Wv * T**3 / 3],
    ]
    np.testing.assert_allclose(Q, Q_exp, rtol=1e-12)
    Fe, Qe = discretise(A, W, T, method="euler")
    np.testing.assert_allclose(Fe, F)
    np.testing.assert_allclose(Qe, W * T)  # Tomera (2011) eq. 31


# --------------------------------------------------------------------------------------------
# Tomera (2014) eqs. 30 and 35 from design matrices
# --------------------------------------------------------------------------------------------


def test_tomera2014_eq30_from_design_matrices():
    """Discrete, T = 1 s, F = I + A T (eq. 5), Q_k = G Q G^T T (eq. 31), filter form."""
    A, C = double_integrator()
    T = 1.0
    for R in (POSITION_VARIANCE_TOMERA2011, HEADING_VARIANCE_TOMERA2011):
        G, Q = np.eye(2), 0.01 * R * np.eye(2)
        L, P, E = dlqe(np.eye(2) + A * T, G, C, G @ Q @ G.T * T, R, form="filter")
        np.testing.assert_allclose(L[:, 0], EQ30, rtol=1e-4)
        # python-control's dlqe (predictor form) of the same design: F times the filter gain
        Lc, _, _ = control.dlqe(np.eye(2) + A * T, G, C, G @ Q @ G.T * T, R)
        np.testing.assert_allclose(Lc, (np.eye(2) + A * T) @ L, rtol=1e-8)
        np.testing.assert_allclose(Lc[:, 0], [0.07946, 0.44814], rtol=1e-4)


def test_tomera2014_eq35_from_design_matrices():
    """Continuous, G Q G^T = 0.01 R I, intensity R_c = R T with T = 1 s (Tomera 2011 eq. 35)."""
    A, C = double_integrator()
    for R in (POSITION_VARIANCE_TOMERA2011, HEADING_VARIANCE_TOMERA2011):
        L, _, _ = lqe(A, np.eye(2), C, 0.01 * R * np.eye(2), R * 1.0)
        np.testing.assert_allclose(L[:, 0], EQ35, rtol=1e-4)
        Lc, _, _ = control.lqe(A, np.eye(2), C, 0.01 * R * np.eye(2), R)
        np.testing.assert_allclose(L, Lc, rtol=1e-8)


def test_tomera_presets_reproduce_tomera2014_gains():
    for dof in range(3):
        np.testing.assert_allclose(TOMERA_DKF.dkf_gains(form="filter")[0][dof], EQ30, rtol=1e-4)
        np.testing.assert_allclose(TOMERA_KBF.kbf_gains()[0][dof], EQ35, rtol=1e-4)
    assert TOMERA_DKF.T == TOMERA_KBF.T == 1.0
    assert TOMERA_DKF.discretisation == "euler"


def test_tomera2011_eqs61_62_do_not_give_tomera2014_gains():
    """The printed Tomera (2011) design values give other gains (documented in design.py)."""
    A, C = double_integrator()
    Gx, Qx = np.diag([1.0, 0.01]), np.diag([0.1, 0.2])
    Gp, Qp = np.diag([0.2, 0.01]), np.eye(2)
    Lx, _, _ = lqe(A, Gx, C, Qx, 0.01)
    Lp, _, _ = lqe(A, Gp, C, Qp, 0.1)
    np.testing.assert_allclose(Lx[:, 0], [3.1623, 2.5153], rtol=1e-4)
    np.testing.assert_allclose(Lp[:, 0], [0.63246, 1.1251], rtol=1e-4)


def test_default_variances_match_the_sensors():
    cfg = SensorConfig()
    assert cfg.position_variance == POSITION_VARIANCE_TOMERA2011
    assert cfg.heading_variance == pytest.approx(HEADING_VARIANCE_TOMERA2011)
    assert DKF_DESIGN.R == (cfg.position_variance, cfg.position_variance, cfg.heading_variance)
    assert KBF_DESIGN == DKF_DESIGN


def test_tuned_design_bandwidth():
    """The tuned filters have 0.35 and 0.43 rad/s bandwidths (w = (q / (R T))^(1/4))."""
    _, _, E = KBF_DESIGN.kbf_gains()
    w = np.abs(E).max(axis=1)
    np.testing.assert_allclose(w, [0.350, 0.350, 0.426], atol=0.002)
    assert np.all(np.abs(DKF_DESIGN.dkf_gains()[2]) < 1.0)


# --------------------------------------------------------------------------------------------
# Errors
# --------------------------------------------------------------------------------------------

A2, C2 = double_integrator()


@pytest.mark.parametrize(
    ("args", "match"),
    [
        ((A2, np.eye(2), C2, [[1.0, 0.5], [0.0, 1.0]], 1.0), "symmetric"),
        ((A2, np.eye(2), C2, np.diag([1.0, -1.0]), 1.0), "positive semi-definite"),
        ((A2, np.eye(2), C2, np.eye(2), 0.0), "positive definite"),
        ((A2, np.eye(2), C2, np.eye(2), -1.0), "positive definite"),
        ((A2, np.eye(2), C2, np.eye(3), 1.0), "Q must have shape"),
        ((A2, np.eye(2), C2, np.eye(2), np.eye(2)), "R must have shape"),
        ((A2, np.eye(3), C2, np.eye(3), 1.0), "G must have 2 rows"),
        ((A2, np.eye(2), [[0.0, 1.0, 0.0]], np.eye(2), 1.0), "C must have 2 columns"),
        ((np.ones((2, 3)), np.eye(2), C2, np.eye(2), 1.0), "A must have shape"),
        ((A2, np.eye(2), C2, [[np.nan, 0.0], [0.0, 1.0]], 1.0), "finite"),
        ((A2, np.eye(2), C2, np.eye(2), np.inf), "finite"),
        ((A2, np.eye(2), [[1.0, 0.0]], np.eye(2), 1.0), "not detectable"),
        ((np.diag([1.0, -1.0]), [[0.0], [1.0]], np.eye(2), [[1.0]], np.eye(2)), "stabilisable"),
        ((A2, [[0.0], [1.0]], C2, [[1.0]], 1.0), "stabilisable"),
    ],
)
def test_lqe_errors(args, match):
    with pytest.raises(ValueError, match=match):
        lqe(*args)


def test_dlqe_errors():
    F = np.eye(2) + A2
    with pytest.raises(ValueError, match="not detectable"):
        dlqe(np.diag([1.5, 0.5]), np.eye(2), [[0.0, 1.0]], np.eye(2), 1.0)
    with pytest.raises(ValueError, match="stabilisable"):
        dlqe(np.diag([1.5, 0.5]), [[0.0], [1.0]], np.eye(2), [[1.0]], np.eye(2))
    with pytest.raises(ValueError, match="form"):
        dlqe(F, np.eye(2), C2, np.eye(2), 1.0, form="smoother")
    with pytest.raises(ValueError, match="positive definite"):
        dlqe(F, np.eye(2), C2, np.eye(2), [[0.0]])
    # a stable uncontrollable mode is fine (stabilisable), an unstable one is not
    L, _, _ = dlqe(np.diag([1.0, 0.5]), [[1.0], [0.0]], np.eye(2), [[1.0]], np.eye(2))
    assert np.isfinite(L).all()


def test_kalman_design_errors():
    with pytest.raises(ValueError, match="positive semi-definite"):
        KalmanDesign(Q=np.diag([1e-4, -1e-4]))
    with pytest.raises(ValueError, match="positive definite"):
        KalmanDesign(R=(0.01, 0.0, 0.01))
    with pytest.raises(ValueError, match="R must be one variance or three"):
        KalmanDesign(R=(0.01, 0.01))
    with pytest.raises(ValueError, match="2 rows"):
        KalmanDesign(G=np.eye(3), Q=np.eye(3))
    with pytest.raises(ValueError, match="to match G"):
        KalmanDesign(G=[[1.0], [0.0]], Q=np.eye(2))
    with pytest.raises(ValueError, match="stabilisable"):
        KalmanDesign(G=[[0.0], [1.0]], Q=[[1.0]])  # noise on the position only
    with pytest.raises(ValueError, match="T"):
        KalmanDesign(T=0.0)
    with pytest.raises(ValueError, match="discretisation"):
        KalmanDesign(discretisation="tustin")
    with pytest.raises(ValueError, match="model"):
        KalmanDesign(model="constant-turn")
    with pytest.raises(ValueError, match="unknown key"):
        KalmanDesign.from_dict({"Qk": 1.0})


def test_kalman_design_per_dof_and_mapping():
    d = KalmanDesign.from_dict(
        {"G": [[1.0], [0.0]], "Q": [[[1e-4]], [[2e-4]], [[3e-7]]], "R": 0.01, "T": 0.5}
    )
    assert d.R == (0.01, 0.01, 0.01)
    np.testing.assert_allclose(d.intensity()[:, 0, 0], [1e-4, 2e-4, 3e-7])
    F, Qk = d.sampled()
    np.testing.assert_allclose(F, [[1.0, 0.0], [0.5, 1.0]])
    assert Qk.shape == (3, 2, 2)
    ragged = KalmanDesign(G=[np.eye(2), np.eye(2), [[1.0], [0.0]]], Q=[np.eye(2), np.eye(2), [[1]]])
    assert len(ragged.G[2][0]) == 1
