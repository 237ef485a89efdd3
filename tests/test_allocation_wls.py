"""Box-constrained weighted least-squares allocation for N fixed thrusters (allocation.wls).

Oracles: scipy's bounded-variable least squares (``lsq_linear(method='bvls')``, Stark & Parker
1995) on the stacked problem, the KKT conditions written from their definition, and the Blue
Lady's closed form ``fixed3.allocate`` (the same objective with ``H = 0``).
"""

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import lsq_linear

from shipgym.controllers.allocation import (
    WLSAllocation,
    WLSAllocator,
    allocate,
    allocate_wls,
    default_weights,
)
from shipgym.dynamics import BLUE_LADY_THRUSTERS, configuration_matrix

P = BLUE_LADY_THRUSTERS
T = configuration_matrix(P)
F_LO, F_HI = P.force_lower, P.force_upper


def objective(f, tau, B, W, h):
    """``(B f - tau)^T W (B f - tau) + f^T diag(h) f``, from the definition."""
    e = B @ f - tau
    Wm = np.diag(W) if np.ndim(W) == 1 else W
    return float(e @ Wm @ e + f @ (h * f))


def bvls(tau, B, lo, hi, W, h):
    """The oracle: min ||A f - b||^2 in the box, A = [W^1/2 B; diag(h)^1/2], b = [W^1/2 tau; 0]."""
    Wm = np.diag(W) if np.ndim(W) == 1 else W
    ev, V = np.linalg.eigh(Wm)
    Wh = V @ np.diag(np.sqrt(np.clip(ev, 0.0, None))) @ V.T
    A = np.vstack([Wh @ B, np.diag(np.sqrt(h))])
    b = np.concatenate([Wh @ tau, np.zeros(B.shape[1])])
    held = lo == hi  # bvls wants lo < hi: held thrusts are substituted
    x = lo.copy()
    if (~held).any():
        b = b - A[:, held] @ lo[held]
        x[~held] = lsq_linear(
            A[:, ~held], b, bounds=(lo[~held], hi[~held]), method="bvls", tol=1e-15
        ).x
    return x


def random_problem(seed, *, degenerate=False):
    rng = np.random.default_rng(seed)
    n_dof = int(rng.choice([3, 4]))
    n = int(rng.integers(1, 9))
    B = rng.normal(size=(n_dof, n)) * rng.choice([1.0, 30.0], size=(n_dof, 1))
    if degenerate and n > 1:
        kind = rng.integers(3)
        if kind == 0:  # a duplicated (scaled) thruster: rank-deficient, redundant
            B[:, -1] = -2.0 * B[:, 0]
        elif kind == 1:  # a thruster that acts on nothing
            B[:, -1] = 0.0
        else:  # a DOF that nothing acts on
            B[0, :] = 0.0
    scale = 10.0 ** rng.uniform(0, 5)
    lo = -rng.uniform(0.0, 2.0, n) * scale
    hi = rng.uniform(0.0, 2.0, n) * scale
    held = rng.random(n) < 0.1
    hi[held] = lo[held]  # some thrusts held at one value
    cap = np.abs(B) @ np.maximum(-lo, hi)
    tau = rng.uniform(-1.5, 1.5, n_dof) * cap
    if rng.random() < 0.5:
        W = rng.uniform(0.1, 2.0, n_dof) / np.maximum(cap, 1.0) ** 2
    else:
        G = rng.normal(size=(n_dof, n_dof))
        W = (G @ G.T + 0.1 * np.eye(n_dof)) / np.maximum(cap.max(), 1.0) ** 2
    h = rng.uniform(1e-4, 1e-2, n) / scale**2
    return tau, B, lo, hi, W, h, scale


def check_result(r, tau, B, lo, hi):
    assert isinstance(r, WLSAllocation)
    n_dof, n = B.shape
    assert r.force.shape == (n,) and r.saturated.shape == (n,) and r.saturated.dtype == np.bool_
    assert r.tau.shape == (n_dof,) and r.tau_error.shape == (n_dof,)
    assert np.all(r.force >= lo) and np.all(r.force <= hi)  # exactly within the box
    # to the rounding bound of a sum of n products: n eps sum_j |B_ij f_j| (cancellation)
    bound = 4 * n * np.finfo(float).eps * (np.abs(B) @ np.abs(r.force)) + 1e-300
    assert np.all(np.abs(r.tau - B @ r.force) <= bound)
    np.testing.assert_array_equal(r.tau_error, tau - r.tau)


# ---- against the independent bounded least-squares solver --------------------------------------
@settings(max_examples=300, deadline=None)
@given(st.integers(0, 2**32 - 1), st.booleans())
def test_matches_bvls_on_random_problems(seed, degenerate):
    tau, B, lo, hi, W, h, scale = random_problem(seed, degenerate=degenerate)
    r = allocate_wls(tau, B, lo, hi, W=W, H=h)
    check_result(r, tau, B, lo, hi)
    ref = bvls(tau, B, lo, hi, W, h)
    J, Jref = objective(r.force, tau, B, W, h), objective(ref, tau, B, W, h)
    assert J <= Jref + 1e-12 * max(Jref, 1.0)  # never worse than the oracle
    # the minimiser is unique (h > 0): the same thrusts
    np.testing.assert_allclose(r.force, ref, rtol=0, atol=2e-7 * scale)


@settings(max_examples=150, deadline=None)
@given(st.integers(0, 2**32 - 1), st.booleans())
def test_kkt_conditions_hold(seed, degenerate):
    """Stationarity and complementarity, written from their definition (scaled to the problem)."""
    tau, B, lo, hi, W, h, scale = random_problem(seed, degenerate=degenerate)
    r = allocate_wls(tau, B, lo, hi, W=W, H=h)
    Wm = np.diag(W) if np.ndim(W) == 1 else W
    g = 2.0 * (B.T @ Wm @ (B @ r.force - tau) + h * r.force)  # gradient of the objective
    curv = np.abs(2.0 * (B.T @ Wm @ B + np.diag(h))).max() * scale  # gradient scale
    tol = 1e-9 * curv
    free = (r.force > lo) & (r.force < hi)
    assert np.all(np.abs(g[free]) <= tol)
    at_lo = (r.force == lo) & (lo < hi)
    at_hi = (r.force == hi) & (lo < hi)
    assert np.all(g[at_lo] >= -tol)  # pushing further down would not help ...
    assert np.all(g[at_hi] <= tol)  # ... nor further up
    # saturated = on a bound whose multiplier, over the thrust's curvature and range (the
    # relative distance the thrust would move past the bound if released), exceeds 1e-7
    s = np.maximum(np.abs(lo), np.abs(hi))
    qd = 2.0 * np.diag(B.T @ Wm @ B + np.diag(h))
    dist = g / (qd * s)
    assert not np.any(r.saturated & free)
    assert np.all(r.saturated[at_lo & (dist > 1e-6)])
    assert np.all(r.saturated[at_hi & (dist < -1e-6)])
    assert not np.any(r.saturated[(at_lo | at_hi) & (np.abs(dist) < 1e-8)])


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_default_h_is_optimal_for_the_unregularised_problem(seed):
    """The default H is tiny: the tau error is the least possible one (to 1e-7 of capacity)."""
    tau, B, lo, hi, W, _, _ = random_problem(seed, degenerate=True)
    r = allocate_wls(tau, B, lo, hi, W=W)
    check_result(r, tau, B, lo, hi)
    zero = np.zeros(B.shape[1])
    ref = bvls(tau, B, lo, hi, W, np.full(B.shape[1], 1e-300))
    J, Jref = objective(r.force, tau, B, W, zero), objective(ref, tau, B, W, zero)
    Wm = np.diag(W) if np.ndim(W) == 1 else W
    J_cap = float(np.abs(tau) @ np.abs(Wm) @ np.abs(tau)) + 1.0  # the objective's scale
    assert J <= Jref + 1e-7 * J_cap


def test_redundant_set_takes_the_least_weighted_thrust():
    # two identical thrusters side by side: the load is shared equally (H equal)
    B = np.array([[1.0, 1.0], [0.0, 0.0], [2.0, 2.0]])
    r = allocate_wls([10.0, 0.0, 20.0], B, [-50.0, -50.0], [50.0, 50.0])
    np.testing.assert_allclose(r.force, [5.0, 5.0], rtol=1e-8)
    assert not r.saturated.any()
    # with a larger H on the first, the second takes more: f1 / f2 = h2 / h1
    r = allocate_wls([10.0, 0.0, 20.0], B, [-50.0, -50.0], [50.0, 50.0], H=[4e-9, 1e-9])
    np.testing.assert_allclose(r.force[1] / r.force[0], 4.0, rtol=1e-6)


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_feasible_request_is_met(seed):
    """A tau that thrusts strictly inside the box produce is delivered (H's bias only)."""
    rng = np.random.default_rng(seed)
    n_dof = int(rng.choice([3, 4]))
    n = int(rng.integers(n_dof, 9))
    B = rng.normal(size=(n_dof, n))
    lo, hi = -rng.uniform(0.5, 2.0, n), rng.uniform(0.5, 2.0, n)
    f = rng.uniform(0.5 * lo, 0.5 * hi)
    tau = B @ f
    r = allocate_wls(tau, B, lo, hi)
    cap = np.abs(B) @ np.maximum(-lo, hi)
    # the bias of the default H (1e-9 relative) grows with the condition of B squared
    bias = 1e-9 * max(np.linalg.cond(B), 1.0) ** 2
    np.testing.assert_allclose(r.tau, tau, rtol=0, atol=bias * cap.max())
    assert not r.saturated.any()
    if n == n_dof:  # square and invertible: the one exact answer, with H = 0 to round-off
        r0 = allocate_wls(tau, B, lo, hi, H=0.0)
        np.testing.assert_allclose(r0.force, f, rtol=0, atol=1e-9 * np.linalg.cond(B))


def test_four_dof_roll_row():
    # a fin-like thruster high up and two low: X, Y, K, N
    B = np.array(
        [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 1.0],
            [0.0, -2.0, 1.0],  # K = -z f_y, z below the CG: -2 (above) and +1 (below)
            [0.0, 10.0, -10.0],
        ]
    )
    lo, hi = np.array([-100.0, -50.0, -50.0]), np.array([100.0, 50.0, 50.0])
    tau = np.array([30.0, 20.0, 5.0, 100.0])  # consistent? find the least-squares answer
    r = allocate_wls(tau, B, lo, hi, W=np.ones(4), H=0.0)
    ref = bvls(tau, B, lo, hi, np.ones(4), np.zeros(3) + 1e-300)
    np.testing.assert_allclose(r.force, ref, rtol=1e-9, atol=1e-9)
    check_result(r, tau, B, lo, hi)


# ---- the same problem as the Blue Lady's closed form -------------------------------------------
any_tau = st.tuples(
    st.floats(-2000, 2000, allow_nan=False),
    st.floats(-500, 500, allow_nan=False),
    st.floats(-1500, 1500, allow_nan=False),
)


@settings(max_examples=400, deadline=None)
@given(any_tau, st.floats(-2, 2), st.floats(-2, 2))
def test_equals_the_closed_form_on_the_blue_lady(tau, lg_wY, lg_wN):
    """``allocate`` minimises w_Y e_Y^2 + w_N e_N^2 over the tunnels and clips F1 = X on its
    own. With W = diag(w_X, w_Y, w_N) and H = 0 the WLS problem is the same (the X row and F1
    are decoupled from the rest, so any w_X > 0 gives F1 = clip(X)): the same thrusts."""
    wX, wY, wN = default_weights(P)
    w = (1.0, wY * 10.0**lg_wY, wN * 10.0**lg_wN)
    a = allocate(tau, P, weights=w)
    r = allocate_wls(tau, T, F_LO, F_HI, W=np.array(w), H=0.0)
    np.testing.assert_allclose(r.force, a.force, rtol=0, atol=1e-9 * F_HI.max())
    np.testing.assert_allclose(r.tau, a.tau, rtol=0, atol=1e-8 * F_HI.max())
    np.testing.assert_array_equal(r.saturated, a.saturated)


def test_default_weights_give_the_closed_form_within_h_bias():
    rng = np.random.default_rng(3)
    w = np.array(default_weights(P))
    for _ in range(200):
        tau = rng.uniform(-1.0, 1.0, 3) * np.array([900.0, 150.0, 500.0])
        a = allocate(tau, P)
        r = allocate_wls(tau, T, F_LO, F_HI, W=w)  # default H: 1e-9 relative
        np.testing.assert_allclose(r.force, a.force, rtol=0, atol=1e-6 * F_HI.max())


def test_other_thruster_geometry_matches_closed_form():
    p = dataclasses.replace(P, k1=1.0, k2=2.0, k3=1.0, L2=5.0, L3=1.0)
    B = configuration_matrix(p)
    w = default_weights(p)
    rng = np.random.default_rng(5)
    for _ in range(100):
        tau = rng.uniform(-1, 1, 3) * np.array([3e5, 5.0, 20.0])
        a = allocate(tau, p, weights=w)
        r = allocate_wls(tau, B, p.force_lower, p.force_upper, W=np.array(w), H=0.0)
        np.testing.assert_allclose(r.force, a.force, rtol=0, atol=1e-9 * p.force_upper.max())


# ---- saturation flags --------------------------------------------------------------------------
def test_saturated_means_an_active_bound():
    B = np.eye(3)
    lo, hi = -np.ones(3), np.ones(3)
    r = allocate_wls([2.0, 0.5, -3.0], B, lo, hi, H=0.0)
    np.testing.assert_array_equal(r.force, [1.0, 0.5, -1.0])
    np.testing.assert_array_equal(r.saturated, [True, False, True])
    # exactly at the bound, nothing more wanted: on the bound but not active
    r = allocate_wls([1.0, 0.5, -1.0], B, lo, hi, H=0.0)
    np.testing.assert_array_equal(r.force, [1.0, 0.5, -1.0])
    assert not r.saturated.any()
    np.testing.assert_array_equal(r.tau_error, 0.0)
    # a held thruster (f_min = f_max) is saturated when the request wants it to move
    r = allocate_wls([2.0, 0.5, 0.0], B, [-1.0, -1.0, 0.0], [1.0, 1.0, 0.0], H=0.0)
    np.testing.assert_array_equal(r.saturated, [True, False, False])
    r = allocate_wls([2.0, 0.5, 0.3], B, [-1.0, -1.0, 0.0], [1.0, 1.0, 0.0], H=0.0)
    np.testing.assert_array_equal(r.saturated, [True, False, True])


def test_prepared_allocator_gives_the_same_answers():
    rng = np.random.default_rng(11)
    for seed in range(40):
        tau, B, lo, hi, W, h, _ = random_problem(seed, degenerate=seed % 2 == 0)
        al = WLSAllocator(B, lo, hi, W=W, H=h)
        for _ in range(5):
            t = tau * rng.uniform(0.0, 2.0)
            a, b = al(t), allocate_wls(t, B, lo, hi, W=W, H=h)
            for x, y in zip(a, b, strict=True):
                np.testing.assert_array_equal(x, y)
    al = WLSAllocator(T, F_LO, F_HI)
    with pytest.raises(ValueError, match="tau must have shape"):
        al([1.0, 2.0])
    with pytest.raises(ValueError):
        al.B[0, 0] = 2.0  # read-only


# ---- bad input ---------------------------------------------------------------------------------
GOOD = dict(tau=[1.0, 2.0, 3.0], B=np.eye(3), f_min=-np.ones(3), f_max=np.ones(3))


@pytest.mark.parametrize(
    "change, match",
    [
        (dict(tau=[1.0, 2.0]), "tau must have shape"),
        (dict(tau=[1.0, np.nan, 3.0]), "tau contains NaN"),
        (dict(tau=["a", 1, 2]), "tau must be real"),
        (dict(B=np.ones(3)), "B must have shape"),
        (dict(B=np.full((3, 3), np.inf)), "B contains NaN"),
        (dict(f_min=-np.ones(2)), "f_min must have shape"),
        (dict(f_max=[1.0, np.nan, 1.0]), "f_max contains NaN"),
        (dict(f_min=[-1.0, 2.0, -1.0]), "f_min > f_max for thruster 1"),
        (dict(W=[1.0, -1.0, 1.0]), "W must be >= 0"),
        (dict(W=np.ones((2, 2))), "W must have shape"),
        (dict(W=[[1.0, 2.0, 0], [0, 1.0, 0], [0, 0, 1.0]]), "W must be symmetric"),
        (dict(W=-np.eye(3)), "positive semi-definite"),
        (dict(W=[1.0, np.inf, 1.0]), "W contains NaN"),
        (dict(H=[1.0, -1.0, 1.0]), "H must be >= 0"),
        (dict(H=[1.0, 1.0]), "H must have shape"),
        (dict(B=np.ones((3, 3)), H=0.0), "singular"),
        (dict(B=np.zeros((3, 3)), H=0.0), "is zero"),
    ],
)
def test_bad_input_raises(change, match):
    kw = {**GOOD, **change}
    with pytest.raises(ValueError, match=match):
        allocate_wls(kw.pop("tau"), kw.pop("B"), kw.pop("f_min"), kw.pop("f_max"), **kw)


def test_any_memory_layout_of_b_gives_a_correct_allocation():
    """The compiled law has one entry point; a transposed (Fortran-ordered) configuration
    matrix first, then a C-ordered one, must both deliver B f (a layout misread gave tau off
    by millions)."""
    rng = np.random.default_rng(1)
    B = rng.normal(size=(3, 5))
    lo, hi = -100.0 * np.ones(5), 100.0 * np.ones(5)
    for b in (np.asfortranarray(B), B, B.T.copy().T, B):
        r = allocate_wls(rng.normal(size=3) * 300.0, b, lo, hi)
        check_result(r, r.tau + r.tau_error, B, lo, hi)


def test_a_large_batch_on_threads_equals_the_requests_one_by_one():
    """A batch of at least ``PARALLEL_MIN`` requests (allocated in ranges on threads where this
    thread may use them) gives every row bit for bit as its own call, and a bad request is
    named as in a serial call: the first one in the batch."""
    from shipgym.controllers.allocation import wls

    rng = np.random.default_rng(11)
    n = 3 * wls.PARALLEL_MIN + 5
    al = WLSAllocator(T, F_LO, F_HI)
    tau = rng.normal(0.0, 1.0, (n, 3)) * np.abs(T).sum(axis=1) * F_HI.max() * 0.15
    force, delivered, error, active = al.batch(tau)
    for i in range(0, n, 7):
        one = al(tau[i])
        np.testing.assert_array_equal(force[i], one.force)
        np.testing.assert_array_equal(delivered[i], one.tau)
        np.testing.assert_array_equal(error[i], one.tau_error)
        np.testing.assert_array_equal(active[i], one.saturated)
    assert 0 < active.any(axis=1).sum() < n  # both kinds of rows
    bad = tau.copy()
    bad[n - 3, 1] = np.nan
    bad[n // 2, 0] = np.inf
    with pytest.raises(ValueError, match=r"\[inf, "):
        al.batch(bad)
