"""Thrust allocation (Tomera 2014 eqs. 24-27) and the normalised action mapping."""

import dataclasses
import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import lsq_linear

from shipgym.controllers import (
    Allocation,
    action_to_command,
    allocate,
    allocate_inverse,
    command_to_action,
    default_weights,
    force_capacity,
)
from shipgym.dynamics import (
    BLUE_LADY_THRUSTERS,
    configuration_matrix,
    inverse_thrust,
    thrust,
)

P = BLUE_LADY_THRUSTERS
T = configuration_matrix(P)
F_LO, F_HI = P.force_lower, P.force_upper  # [-78.4, -44.1, -44.1], [451.3, 44.1, 44.1] N

# requests that every allocator can meet exactly
feasible_forces = st.tuples(
    st.floats(F_LO[0] * 0.99, F_HI[0] * 0.99),
    st.floats(F_LO[1] * 0.99, F_HI[1] * 0.99),
    st.floats(F_LO[2] * 0.99, F_HI[2] * 0.99),
)
any_tau = st.tuples(
    st.floats(-2000, 2000, allow_nan=False),
    st.floats(-500, 500, allow_nan=False),
    st.floats(-1500, 1500, allow_nan=False),
)


def objective(F2, F3, tau, w, p=P):
    """The sway/yaw objective of `allocate`, written from its definition."""
    return w[1] * (F2 + F3 - tau[1]) ** 2 + w[2] * (p.L2 * F2 - p.L3 * F3 - tau[2]) ** 2


def check_consistent(a: Allocation, tau, p=P):
    """Every allocation: ranges respected, force = thrust(command), tau = T force."""
    for arr in a[:4]:
        assert arr.shape == (3,) and arr.dtype == np.float64
    assert a.saturated.shape == (3,) and a.saturated.dtype == np.bool_
    assert np.all(a.command >= p.lower) and np.all(a.command <= p.upper)
    np.testing.assert_allclose(thrust(a.command, p), a.force, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(configuration_matrix(p) @ a.force, a.tau, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(a.tau_error, np.asarray(tau) - a.tau, rtol=0, atol=1e-9)


# ---- exact inverse when nothing saturates ----------------------------------------------------
@settings(max_examples=200, deadline=None)
@given(feasible_forces)
def test_inverse_reproduces_tau_when_feasible(F):
    tau = T @ np.array(F)
    for alloc in (allocate_inverse, allocate):
        a = alloc(tau, P)
        check_consistent(a, tau)
        np.testing.assert_allclose(a.force, np.linalg.solve(T, tau), rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(T @ a.force, tau, rtol=1e-9, atol=1e-9)
        np.testing.assert_array_equal(a.tau_error, 0.0)
        assert not a.saturated.any()
        # eqs. 26-27: n1 = sgn(F1) sqrt(|F1|/k1), p = F/k
        np.testing.assert_allclose(a.command, inverse_thrust(a.force, P), rtol=1e-12, atol=1e-12)


def test_known_numbers():
    # pure yaw moment of 56.16 N m: F2 = 10 N, F3 = -10 N (lever L2 + L3 = 5.616 m)
    a = allocate_inverse([0.0, 0.0, 56.16], P)
    np.testing.assert_allclose(a.force, [0.0, 10.0, -10.0], atol=1e-12)
    np.testing.assert_allclose(a.command, [0.0, 10 / 44.145, -10 / 44.145])
    # full ahead and full astern of the main propeller
    np.testing.assert_allclose(allocate([451.33056, 0, 0], P).command[0], 480.0)
    a = allocate([-500.0, 0, 0], P)
    assert a.command[0] == -200.0 and a.saturated.tolist() == [True, False, False]
    assert a.force[0] == pytest.approx(-1.9589e-3 * 200**2)
    assert a.tau_error[0] == pytest.approx(-500 + 1.9589e-3 * 200**2)
    np.testing.assert_allclose(force_capacity(P), [451.33056, 88.29, 44.145 * (3.24 + 2.376)])


# ---- saturation ------------------------------------------------------------------------------
@settings(max_examples=300, deadline=None)
@given(any_tau)
def test_box_constraints_and_bookkeeping(tau):
    for alloc in (allocate_inverse, allocate):
        a = alloc(tau, P)
        check_consistent(a, tau)
        assert np.all(a.force >= F_LO - 1e-9) and np.all(a.force <= F_HI + 1e-9)
    # surge is decoupled: both allocators clip X the same way
    assert allocate(tau, P).force[0] == allocate_inverse(tau, P).force[0]


def test_inverse_flags_exactly_the_clipped_commands():
    a = allocate_inverse([1000.0, 200.0, -500.0], P)
    raw = inverse_thrust(np.linalg.solve(T, [1000.0, 200.0, -500.0]), P)
    np.testing.assert_array_equal(a.saturated, (raw < P.lower) | (raw > P.upper))
    np.testing.assert_allclose(a.command, np.clip(raw, P.lower, P.upper), rtol=1e-12)


@pytest.mark.parametrize("tau", [[0, 80.0, 200.0], [0, -80.0, 150.0], [0, 60.0, -230.0]])
def test_allocate_keeps_yaw_better_than_clipped_inverse(tau):
    inv, opt = allocate_inverse(tau, P), allocate(tau, P)
    assert inv.saturated.any() and opt.saturated.any()
    assert abs(opt.tau_error[2]) < abs(inv.tau_error[2])
    w = default_weights(P)
    assert objective(*opt.force[1:], tau, w) < objective(*inv.force[1:], tau, w)


def test_pure_moment_beyond_capacity_uses_both_tunnels_fully():
    a = allocate([0.0, 0.0, 400.0], P)
    np.testing.assert_allclose(a.force[1:], [44.145, -44.145])
    np.testing.assert_allclose(a.tau[1:], [0.0, 247.91832], atol=1e-9)
    assert a.saturated.tolist() == [False, True, True]


def test_weights_shift_priority_between_sway_and_yaw():
    tau = [0.0, 80.0, 200.0]
    yaw_first = allocate(tau, P, weights=(1.0, 1.0, 100.0))
    sway_first = allocate(tau, P, weights=(1.0, 100.0, 1e-4))
    assert abs(yaw_first.tau_error[2]) < abs(sway_first.tau_error[2])
    assert abs(sway_first.tau_error[1]) < abs(yaw_first.tau_error[1])


def exact_box_lsq(tau, w, p=P):
    """Independent reference: scipy's bounded linear least squares on the weighted system."""
    A = np.array([[1.0, 1.0], [p.L2, -p.L3]]) * np.sqrt([[w[1]], [w[2]]])
    b = np.array([tau[1], tau[2]]) * np.sqrt([w[1], w[2]])
    lo = [p.k2 * p.p_min, p.k3 * p.p_min]
    hi = [p.k2 * p.p_max, p.k3 * p.p_max]
    return lsq_linear(A, b, bounds=(lo, hi), method="bvls", tol=1e-14).x


@pytest.mark.parametrize("w_N", [1e-3, 0.317, 30.0])
def test_allocate_matches_bounded_least_squares(w_N):
    rng = np.random.default_rng(7)
    w = (1.0, 1.0, w_N)
    for tau in rng.uniform([-600, -300, -900], [600, 300, 900], size=(200, 3)):
        a = allocate(tau, P, weights=w)
        ref = exact_box_lsq(tau, w)
        J, J_ref = objective(*a.force[1:], tau, w), objective(*ref, tau, w)
        assert J <= J_ref * (1 + 1e-9) + 1e-9


GRID = np.linspace(-44.145, 44.145, 241)


@settings(max_examples=150, deadline=None)
@given(
    any_tau,
    st.tuples(st.floats(1e-3, 1e3), st.floats(1e-3, 1e3)),
)
def test_allocate_never_worse_than_grid_search(tau, wYN):
    w = (1.0, *wYN)
    a = allocate(tau, P, weights=w)
    assert F_LO[1] <= a.force[1] <= F_HI[1] and F_LO[2] <= a.force[2] <= F_HI[2]
    F2, F3 = np.meshgrid(GRID, GRID, indexing="ij")
    J_grid = objective(F2, F3, tau, w).min()
    J = objective(a.force[1], a.force[2], tau, w)
    assert J <= J_grid * (1 + 1e-9) + 1e-9


def test_other_thruster_geometry():
    p = dataclasses.replace(P, L2=4.0, L3=1.5, k2=30.0, k3=60.0)
    tau = [10.0, 20.0, 15.0]
    a = allocate(tau, p)
    np.testing.assert_allclose(configuration_matrix(p) @ a.force, tau, atol=1e-9)
    check_consistent(a, tau, p)
    check_consistent(allocate([0, 100.0, -300.0], p), [0, 100.0, -300.0], p)


# ---- normalised actions ----------------------------------------------------------------------
def test_action_mapping_anchor_points():
    cmd = np.array([[0, 0, 0], [480, 1, -1], [-200, -1, 1], [240, 0.5, -0.25], [-100, 0, 0]])
    act = command_to_action(cmd, P)
    np.testing.assert_array_equal(
        act, [[0, 0, 0], [1, 1, -1], [-1, -1, 1], [0.5, 0.5, -0.25], [-0.5, 0, 0]]
    )
    np.testing.assert_array_equal(action_to_command(act, P), cmd)
    assert command_to_action([0.0, 0.0, 0.0], P).shape == (3,)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=3, max_size=3))
def test_action_round_trip(action):
    cmd = action_to_command(action, P)
    assert np.all(cmd >= P.lower) and np.all(cmd <= P.upper)
    np.testing.assert_allclose(command_to_action(cmd, P), action, rtol=1e-12, atol=1e-15)


def test_action_mapping_batch_and_range_errors():
    rng = np.random.default_rng(0)
    a = rng.uniform(-1, 1, size=(4, 5, 3))
    np.testing.assert_allclose(command_to_action(action_to_command(a, P), P), a, atol=1e-15)
    with pytest.raises(ValueError, match="outside"):
        action_to_command([1.5, 0, 0], P)
    with pytest.raises(ValueError, match="outside"):
        command_to_action([500.0, 0, 0], P)
    np.testing.assert_array_equal(action_to_command([1.5, -2, 0], P, clip=True), [480, -1, 0])
    np.testing.assert_array_equal(command_to_action([-900, 3, 0], P, clip=True), [-1, 1, 0])
    for bad in ([np.nan, 0, 0], [0, 0], [[0, 0]]):
        with pytest.raises(ValueError):
            action_to_command(bad, P)
        with pytest.raises(ValueError):
            command_to_action(bad, P, clip=True)


# ---- bad input -------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "tau",
    [
        [np.nan, 0, 0],
        [0, np.inf, 0],
        [0, 0],
        [0, 0, 0, 0],
        np.zeros((3, 1)),
        np.zeros((1, 3)),
        "abc",
        5.0,
        [0, "x", 0],
    ],
)
def test_bad_tau_raises(tau):
    for alloc in (allocate, allocate_inverse):
        with pytest.raises(ValueError):
            alloc(tau, P)


@pytest.mark.parametrize("w", [(1, 0, 1), (1, 1, -1), (1, 1, np.nan), (1, 1), "abc"])
def test_bad_weights_raise(w):
    with pytest.raises(ValueError, match="weights"):
        allocate([0, 1, 1], P, weights=w)


def test_bad_thrusters_raise():
    with pytest.raises(ValueError, match="ThrusterParameters"):
        allocate([0, 0, 0], thrusters={"k1": 1})  # type: ignore[arg-type]


def test_all_inputs_types_accepted():
    for tau in ([1, 2, 3], (1.0, 2.0, 3.0), np.array([1, 2, 3]), np.float32([1, 2, 3])):
        a, b = allocate(tau, P), allocate_inverse(tau, P)
        np.testing.assert_allclose(a.tau, [1, 2, 3], rtol=1e-6)
        np.testing.assert_allclose(b.tau, [1, 2, 3], rtol=1e-6)


def test_corners_of_the_box_are_reachable():
    # every corner of the tunnel box is the exact answer to the request it produces
    for p2, p3 in itertools.product((-1.0, 1.0), repeat=2):
        F = np.array([0.0, 44.145 * p2, 44.145 * p3])
        a = allocate(T @ F, P)
        np.testing.assert_allclose(a.force, F, atol=1e-9)
        assert not a.saturated.any()
