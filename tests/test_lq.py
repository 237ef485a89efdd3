"""LQ optimal control with integral action (shipgym.controllers.lq; Al-Takie 1982 ch. 4)."""

import math

import control
import numpy as np
import pytest
from _helpers import BLUE_LADY_CONTROL, BLUE_LADY_DESIGN, assert_same_eigenvalues

from shipgym.controllers import lq
from shipgym.controllers.batch import CONTROLLERS, controller_spec
from shipgym.controllers.lq import (
    LQController,
    LQWeights,
    dlqr,
    lq_design,
    lq_model,
    lqr,
)
from shipgym.dynamics import seed_linear_matrices

M, D_L = seed_linear_matrices()


# ---- design functions vs python-control ------------------------------------------------------
def test_lqr_scalar_closed_form():
    # python-control's check_LQR: A = 0, B = 1 -> S = sqrt(Q R), K = S / R, pole -K
    for Q, R in ((1.0, 1.0), (4.0, 0.25), (0.01, 9.0)):
        K, S, E = lqr([[0.0]], [[1.0]], [[Q]], [[R]])
        assert S[0, 0] == pytest.approx(math.sqrt(Q * R), rel=1e-12)
        assert K[0, 0] == pytest.approx(math.sqrt(Q * R) / R, rel=1e-12)
        assert E[0] == pytest.approx(-K[0, 0], rel=1e-12)


@pytest.mark.parametrize("method", ["continuous", "discrete"])
def test_gains_match_python_control_on_the_blue_lady_model(method):
    d = lq_design("tuned", dt=1.0, method=method, **BLUE_LADY_DESIGN)
    ref = control.lqr if method == "continuous" else control.dlqr
    Q, R = (d.Q, d.R) if method == "continuous" else (d.dt * d.Q, d.dt * d.R)
    K_ref, S_ref, E_ref = ref(d.A, d.B, Q, R)
    np.testing.assert_allclose(d.K, K_ref, rtol=1e-6, atol=1e-9 * np.abs(K_ref).max())
    np.testing.assert_allclose(d.S, S_ref, rtol=1e-6, atol=1e-9 * np.abs(S_ref).max())
    assert_same_eigenvalues(d.E, E_ref, rtol=1e-6, atol=1e-9)


def test_lqr_and_dlqr_match_python_control_with_cross_weight():
    rng = np.random.default_rng(3)
    n, m = 4, 2
    A = rng.normal(size=(n, n))
    B = rng.normal(size=(n, m))
    G = rng.normal(size=(n, n))
    Q = G @ G.T + np.eye(n)
    R = np.diag([2.0, 0.5])
    N = 0.1 * rng.normal(size=(n, m))
    for mine, ref, Ad in ((lqr, control.lqr, A), (dlqr, control.dlqr, 0.3 * A)):
        K, S, E = mine(Ad, B, Q, R, N)
        K2, S2, E2 = ref(Ad, B, Q, R, N)
        np.testing.assert_allclose(K, K2, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(S, S2, rtol=1e-8, atol=1e-10)
        assert_same_eigenvalues(E, E2, rtol=1e-8, atol=1e-10)


def test_discrete_cost_equals_riccati_quadratic_form():
    # sum_k x'Qd x + u'Rd u along the closed loop from x0 equals x0' S x0 (DARE solution)
    d = lq_design("tuned", dt=1.0, **BLUE_LADY_DESIGN)
    Qd, Rd = d.dt * d.Q, d.dt * d.R
    Acl = d.A - d.B @ d.K
    x = np.array([1.0, -0.5, math.radians(3.0), 0.02, 0.0, 0.001, 2.0, 1.0, 0.1])
    x0 = x.copy()
    J = 0.0
    for _ in range(20000):
        u = -d.K @ x
        J += x @ Qd @ x + u @ Rd @ u
        x = Acl @ x
    assert J == pytest.approx(x0 @ d.S @ x0, rel=1e-9)


def test_design_model_and_poles():
    A, B = lq_model(**BLUE_LADY_DESIGN)
    np.testing.assert_allclose(A[3:6, 3:6], -np.linalg.solve(M, D_L))
    np.testing.assert_allclose(B[3:6], np.linalg.inv(M))
    c = lq_design("tuned", method="continuous", **BLUE_LADY_DESIGN)
    d = lq_design("tuned", dt=1.0, **BLUE_LADY_DESIGN)
    assert np.all(c.E.real < 0)
    assert np.all(np.abs(d.E) < 1)
    w = np.abs(d.continuous_poles)
    assert 0.02 < w.min() and w.max() < 0.25  # the PID's bandwidth range (rad/s)
    # continuous and discrete designs agree closely at h = 1 s
    np.testing.assert_allclose(d.K, c.K, rtol=0.15, atol=0.05 * np.abs(c.K).max())
    # equal x and y weights -> nearly equal surge/sway position and integral gains
    assert d.K[0, 0] == pytest.approx(d.K[1, 1], rel=0.05)
    assert d.K[0, 6] == pytest.approx(d.K[1, 7], rel=0.05)


def test_bad_input():
    with pytest.raises(ValueError, match="positive definite"):
        lqr([[0.0]], [[1.0]], [[1.0]], [[0.0]])
    with pytest.raises(ValueError, match="rows"):
        lqr(np.eye(2), np.ones((3, 1)), np.eye(2), [[1.0]])
    with pytest.raises(ValueError, match="NaN"):
        dlqr([[np.nan]], [[1.0]], [[1.0]], [[1.0]])
    with pytest.raises(ValueError, match="stabilising"):
        lqr(np.eye(2), [[1.0], [0.0]], np.eye(2), [[1.0]])  # second mode uncontrollable
    with pytest.raises(ValueError, match="preset"):
        lq_design("fast", **BLUE_LADY_DESIGN)
    with pytest.raises(ValueError, match="method"):
        lq_design("tuned", method="euler", **BLUE_LADY_DESIGN)
    with pytest.raises(ValueError, match="e_max"):
        LQWeights(e_max=(0.5, -1.0, 2.0))
    with pytest.raises(ValueError, match="eta_r"):
        LQController(**BLUE_LADY_CONTROL)([0.0, np.nan, 0.0], [0, 0, 0], [0, 0, 0])


# ---- the online controller --------------------------------------------------------------------
def test_feedforward_and_feedback_signs():
    ctrl = LQController(dt=1.0, **BLUE_LADY_CONTROL)
    # on the reference at rest: no force
    np.testing.assert_allclose(ctrl([0, 0, 0], [0, 0, 0], [0, 0, 0]), 0.0, atol=1e-12)
    ctrl.reset()
    # moving with the reference at constant speed, heading 90 deg in the r-frame: the
    # feedforward is exactly the model's damping force D_L nu_d (body frame)
    psi = math.pi / 2
    nu_d = np.array([0.1, 0.0, 0.0])  # r-frame velocity (0, 0.1) seen from the ship
    tau = ctrl([0, 0, psi], nu_d, [0, 0, psi], [0.0, 0.1, 0.0], [0, 0, 0])
    np.testing.assert_allclose(tau, D_L @ nu_d, atol=1e-9)
    ctrl.reset()
    tau = ctrl([1.0, 0.0, 0.0], [0, 0, 0], [0, 0, 0])  # 1 m ahead of the reference
    assert tau[0] < 0 and abs(tau[1]) < 1e-9
    ctrl.reset()
    tau = ctrl([0.0, 0.0, 0.1], [0, 0, 0], [0, 0, 0])  # heading too far to starboard
    assert tau[2] < 0


def test_change_frame_keeps_integral_force():
    ctrl = LQController(dt=1.0, **BLUE_LADY_CONTROL)
    for _ in range(5):
        ctrl([0.3, -0.2, 0.02], [0, 0, 0], [0, 0, 0])
    ctrl([0.3, -0.2, 0.02], [0, 0, 0], [0, 0, 0])  # integrates the pending error
    psi = 0.4
    f0 = ctrl._Ki @ ctrl._to_body(ctrl.integral, psi)
    dpsi = math.radians(90.0)
    ctrl.change_frame(dpsi)
    f1 = ctrl._Ki @ ctrl._to_body(ctrl.integral, psi - dpsi)  # same ship, new frame
    np.testing.assert_allclose(f1, f0, atol=1e-9)


def test_anti_windup_drops_increment_into_a_saturated_dof():
    a, b = LQController(dt=1.0, **BLUE_LADY_CONTROL), LQController(dt=1.0, **BLUE_LADY_CONTROL)
    for c in (a, b):
        c([2.0, 0.0, 0.0], [0, 0, 0], [0, 0, 0])  # ahead of the reference: pushes astern
    a([2.0, 0.0, 0.0], [0, 0, 0], [0, 0, 0], saturated=np.array([50.0, 0.0, 0.0]))  # cut ahead
    b([2.0, 0.0, 0.0], [0, 0, 0], [0, 0, 0], saturated=np.array([-50.0, 0.0, 0.0]))  # astern
    assert a.integral[0] == pytest.approx(2.0)  # integration kept: it pushes away from the cut
    assert b.integral[0] == 0.0  # dropped: it would push further astern


def test_registered_as_lq_with_constrained_allocation():
    assert "lq" in CONTROLLERS
    spec = controller_spec("lq")
    assert spec.allocation == "constrained"
    from shipgym.dynamics.vessel import load_vessel

    for name in ("blue-lady", "star-hercules", "wimpey-sealab"):
        assert isinstance(spec.factory(load_vessel(name), 1.0), LQController)
    lq.register_lq()  # idempotent


def test_harbour_manoeuvre_closed_loop():
    from shipgym.cli import run_episode

    res = run_episode("harbour", controller="lq", seed=0)
    assert res["completed"] and not res["quay_contact"]
    assert res["legs_completed"] == 5
    assert res["J_c"] < 0.2  # truth J_c (Tomera 2014 eq. 57); the tuned PID gets ~0.08 here
