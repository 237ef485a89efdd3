"""The azimuth allocation as one compiled law over N requests (allocation.azimuth.azimuth_law).

Oracles: the N = 1 call (row i of a batch is it, bit for bit); the KKT conditions of the dual
active-set QP checked here from their definition, and its optimum against scipy's
``trust-constr`` and SLSQP and DAQP (if installed, the solver the allocation used before);
the Wimpey Sealab layout's allocations against SLSQP on the same convex problem
(``test_allocation_azimuth.oracle``); the single DP env against the vector env.
"""

from __future__ import annotations

import itertools
import math

import gymnasium as gym
import numpy as np
import pytest
from scipy.optimize import LinearConstraint, minimize
from test_allocation_azimuth import F_WIMPEY, RATE, WIMPEY, check_limits, oracle, random_case

import shipgym
from shipgym.controllers.actuation import make_allocator
from shipgym.controllers.allocation import AzimuthAllocator, Azimuths, extended_thrust_matrix
from shipgym.controllers.allocation.azimuth import _cholesky, _dual_qp
from shipgym.dynamics.vessel import load_vessel


# ---- batch row i is the N = 1 call, bit for bit -------------------------------------------------
@pytest.mark.parametrize("seed", range(12))
def test_batch_rows_equal_single_calls(seed):
    rng = np.random.default_rng(500 + seed)
    az, fixed, tau, _ = random_case(rng)
    al = AzimuthAllocator(az, fixed=fixed, turn_weight=0.05 if seed % 3 == 0 else 0.0)
    n = 17
    taus = tau * rng.uniform(-1.5, 1.5, (n, 1))
    taus[3] = 0.0
    angles = az.angle_prev + rng.uniform(-4.0, 4.0, (n, az.n))
    out = al.batch(taus, angles)
    assert [o.shape[0] for o in out] == [n] * 8
    for i in range(n):
        one = al(taus[i], angles[i])
        for a, b in zip(one, out, strict=True):
            assert np.array_equal(a, b[i])
        check_limits(one, az.with_angles(angles[i]), fixed)
    # and a batch of other sizes gives the same rows
    for part in (slice(0, 1), slice(5, 9)):
        sub = al.batch(taus[part], angles[part])
        for a, b in zip(sub, out, strict=True):
            assert np.array_equal(a, b[part])


def test_wimpey_per_env_allocator_batch_equals_calls():
    """``make_allocator`` of Wimpey Sealab (what the DP controllers call): ``batch(tau,
    state)`` row i equals the call on row i (commands, forces, tau, error, saturation)."""
    v = load_vessel("wimpey-sealab")
    al = make_allocator(v, "constrained", 0.5)
    rng = np.random.default_rng(3)
    n = 40
    cap = v.actuators.capacity()[[0, 1, -1]]
    tau = rng.uniform(-1.2, 1.2, (n, 3)) * cap * rng.choice([0.05, 0.5, 1.0], (n, 1))
    state = np.zeros((n, v.actuators.n_channels))
    state[:, 1::2] = rng.uniform(-7.0, 7.0, (n, 4))  # the angles (thrust, angle per unit)
    out = al.batch(tau, state)
    assert out[-1].any()  # some saturate
    for i in range(n):
        one = al(tau[i], state[i])
        for a, b in zip(one, out, strict=True):
            assert np.array_equal(a, b[i])
    with pytest.raises(ValueError, match="NaN"):
        al.batch(np.full((2, 3), np.nan), state[:2])


def test_bad_batch_input_raises():
    az = Azimuths(WIMPEY, np.full(4, F_WIMPEY), np.zeros(4), RATE, True)
    al = AzimuthAllocator(az)
    with pytest.raises(ValueError, match="must have shape"):
        al.batch(np.zeros((2, 3)), np.zeros((3, 4)))
    with pytest.raises(ValueError, match="NaN"):
        al.batch(np.zeros((2, 3)), np.array([[0.0] * 4, [np.inf] * 4]))


# ---- the QP solver: KKT conditions, optimum against independent solvers -------------------------
def _solve(Q, c, A, b, eq):
    """:func:`_dual_qp` on dense rows ``A`` whose non-zeros are two neighbours (or one)."""
    n, p = c.shape[0], b.shape[0]
    L = np.zeros((n, n))
    assert _cholesky(Q, L)
    col = np.array([min(np.flatnonzero(a)[0], n - 2) for a in A])
    pairs = np.array([A[i, j : j + 2] for i, j in enumerate(col)])
    np.testing.assert_array_equal(pairs @ np.ones(2), A.sum(axis=1))  # nothing left out
    x, u = np.empty(n), np.empty(p)
    why = _dual_qp(L, c, col, pairs, b, eq, p, x, u, np.empty(p, np.bool_),
                   np.empty(p, np.bool_), np.empty(n + 1, np.int64), np.empty((p, n)),
                   np.empty((n + 1, n)), np.zeros((n + 1, n + 1)), np.empty(n + 1),
                   np.empty(n + 1), np.empty(n), np.empty(n))  # fmt: skip
    assert why == 0
    return x, u


def _random_qp(rng, n, p, conditioning):
    """A convex QP like the allocation's: ``Q = M^T M + eps I`` of low rank plus a little,
    unit-norm constraint rows (bounds, sector and facet rows of pairs of variables), zero
    feasible; some equalities."""
    M = rng.normal(size=(min(n, 4), n))
    Q = M.T @ M + conditioning * np.eye(n)
    Q /= Q.diagonal().max()
    c = rng.normal(size=n) * rng.choice([0.1, 1.0, 10.0])
    A = np.zeros((p, n))
    for i in range(p):
        j = rng.integers(0, n - 1)
        a = rng.uniform(0, 2 * math.pi)
        A[i, j], A[i, j + 1] = math.cos(a), math.sin(a)
    b = -rng.uniform(0.0, 1.0, p) * (rng.random(p) < 0.7)  # many through zero (degenerate)
    eq = rng.random(p) < 0.08
    b[eq] = 0.0
    return Q, c, A, b, eq


@pytest.mark.filterwarnings("ignore::scipy.optimize.OptimizeWarning")
@pytest.mark.filterwarnings("ignore:Singular Jacobian:UserWarning")
@pytest.mark.parametrize("seed", range(40))
def test_dual_qp_kkt_and_optimum(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 13))
    p = int(rng.integers(n, 4 * n + 8))
    Q, c, A, b, eq = _random_qp(rng, n, p, rng.choice([1e-9, 1e-4, 1e-1]))
    x, u = _solve(Q, c, A, b, eq)
    slack = A @ x - b
    scale = 1.0 + np.abs(c).max() + np.abs(x).max()
    # primal feasibility, dual feasibility, complementarity, stationarity (Q x - c = A^T u)
    assert slack[~eq].min() >= -1e-9 * scale and np.abs(slack[eq]).max(initial=0.0) <= 1e-9
    assert u[~eq].min(initial=0.0) >= 0.0
    assert np.abs(u * slack).max() <= 1e-9 * scale * (1.0 + np.abs(u).max())
    np.testing.assert_allclose(Q @ x - c, A.T @ u, rtol=0, atol=1e-8 * scale)
    J = 0.5 * x @ Q @ x - c @ x
    lo = np.where(eq, 0.0, b)
    hi = np.where(eq, 0.0, np.inf)
    for method in ("trust-constr", "SLSQP"):
        ref = minimize(lambda y: 0.5 * y @ Q @ y - c @ y, np.zeros(n), jac=lambda y: Q @ y - c,
                       hess=(lambda y: Q) if method == "trust-constr" else None, method=method,
                       constraints=[LinearConstraint(A, lo, hi)],
                       options={"maxiter": 5000, **({"gtol": 1e-12, "xtol": 1e-14}
                                                    if method == "trust-constr"
                                                    else {"ftol": 1e-15})})  # fmt: skip
        feasible = (A @ ref.x - b)[~eq].min(initial=0.0) >= -1e-7
        if feasible:
            assert J <= ref.fun + 1e-7 * scale**2  # nothing feasible is better
    daqp = pytest.importorskip("daqp")  # the solver the allocation used before (test-only)
    bu = np.where(eq, 0.0, 1e30)
    sense = np.where(eq, 5, 0).astype(np.int32)
    for settings in ({}, {"eps_prox": 1e-6, "eta_prox": 1e-12}):
        xd, _, flag, _ = daqp.solve(Q.copy(), -c, A, bu, b.copy(), sense, **settings)
        if flag in (1, 2):  # it reports cycling or infeasibility on some degenerate ones
            xd = np.asarray(xd)
            # as good as DAQP's answer, up to its primal tolerance (1e-6 by default)
            assert J <= 0.5 * xd @ Q @ xd - c @ xd + 1e-6 * scale**2
            break


def test_dual_qp_at_a_vertex_with_dependent_constraints():
    """Zero force asked (``c = 0``) with many constraints through the origin, some of them
    the same row twice and an equality: the answer is zero with zero multipliers."""
    A = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 0.0], [-1.0, 0.0], [0.6, 0.8]])
    b = np.zeros(5)
    eq = np.array([False, False, False, False, True])
    x, u = _solve(np.eye(2), np.zeros(2), A, b, eq)
    np.testing.assert_array_equal(x, 0.0)
    np.testing.assert_array_equal(u, 0.0)
    # pushed into a corner: x >= 0.5 twice (dependent) and y >= 1
    A = np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    x, u = _solve(np.eye(2), np.array([-1.0, 0.0]), A, np.array([0.5, 0.5, 1.0]),
                  np.zeros(3, np.bool_))  # fmt: skip
    np.testing.assert_allclose(x, [0.5, 1.0], atol=1e-15)
    assert u[0] + u[1] == pytest.approx(1.5) and u[2] == pytest.approx(1.0)


@pytest.mark.parametrize("reversible", [True, False])
def test_wimpey_allocations_are_optimal(reversible):
    """The Wimpey Sealab layout from random angles and requests: each allocation is the
    optimum of its branch (SLSQP finds nothing better), the limits hold."""
    rng = np.random.default_rng(11 if reversible else 12)
    az0 = Azimuths(WIMPEY, np.full(4, F_WIMPEY), np.zeros(4), RATE, reversible)
    cap = np.abs(extended_thrust_matrix(WIMPEY)) @ np.full(8, F_WIMPEY)
    W = 1.0 / cap**2
    h = np.full(8, 1e-6) / F_WIMPEY**2
    al = AzimuthAllocator(az0, W=W, H=h)
    n = 8
    taus = rng.uniform(-1.2, 1.2, (n, 3)) * cap * rng.choice([0.1, 0.5, 1.0], (n, 1))
    angles = rng.uniform(-math.pi, math.pi, (n, 4))
    out = al.batch(taus, angles)
    for i in range(n):
        az = az0.with_angles(angles[i])
        r = al(taus[i], angles[i])
        check_limits(r, az)
        backwards = az.reversible & (r.thrust < 0.0)
        either = np.flatnonzero(az.reversible & (r.thrust == 0.0))
        u = r.force_azimuth.reshape(-1)
        e = r.tau - taus[i]
        J = float(e @ (W * e) + u @ (h * u))
        J_ref, J0 = math.inf, 1.0
        for flips in itertools.product([False, True], repeat=either.size):
            bw = backwards.copy()
            bw[either] = flips
            Jb, J0 = oracle(taus[i], az, None, W, h, bw)
            J_ref = min(J_ref, Jb)
        assert J <= J_ref + 1e-9 * J0
        assert J >= J_ref - 1e-6 * J0
        assert np.array_equal(out[0][i], r.thrust)


# ---- the DP vector env equals the single env ------------------------------------------------
@pytest.mark.parametrize("mode", ["next-step", "same-step"])
def test_wimpey_dp_vector_env_equals_single_envs(mode):
    """DPStationKeeping with Wimpey Sealab's azimuth QP under the PID and the KBF: env i of the
    vector env is the single env seeded seed + i, bit for bit, over two whole episodes each
    (autoresets)."""
    n, dur = 3, 6.0
    kw = {"vessel": "wimpey-sealab", "controller": "pid", "observer": "kbf",
          "episode_duration": dur}  # fmt: skip
    venv = gym.make_vec("shipgym/DPStationKeeping-v0", num_envs=n, autoreset_mode=mode, **kw)
    singles = [shipgym.make("shipgym/DPStationKeeping-v0", **kw) for _ in range(n)]
    obs, _ = venv.reset(seed=21)
    for i, s in enumerate(singles):
        assert np.array_equal(obs[i], s.reset(seed=21 + i)[0])
    steps = round(dur / venv.unwrapped.control_period)
    rng = np.random.default_rng(4)
    pending = np.zeros(n, bool)
    ends = 0
    for _ in range(2 * steps + 3):
        a = rng.normal(0.0, 0.3, (n, venv.single_action_space.shape[0])).astype(np.float32)
        obs, rew, term, trunc, info = venv.step(a)
        for i, s in enumerate(singles):
            if pending[i] and mode == "next-step":
                o, _ = s.reset()
                assert np.array_equal(obs[i], o)
                continue
            o, r, te, tr, inf = s.step(a[i])
            assert (te, tr) == (bool(term[i]), bool(trunc[i]))
            assert r == rew[i]
            if te or tr:
                ends += 1
                if mode == "same-step":
                    o, _ = s.reset()
            assert np.array_equal(obs[i], o)
            for key in ("eta", "tau_c"):
                if key in inf:
                    assert np.array_equal(info[key][i], inf[key])
        pending = term | trunc
    assert ends >= 2 * n


def test_any_array_layout_gives_the_same_answer():
    """The law's one compiled entry point is typed for C-contiguous arrays: a Fortran-ordered
    or strided configuration, limits or request is copied to that layout, never misread."""
    rng = np.random.default_rng(9)
    az, fixed, tau, _ = random_case(rng, with_fixed=True)
    Bf, lo, hi = fixed
    odd = (np.asfortranarray(Bf), np.repeat(lo, 2)[::2], np.repeat(hi, 2)[::2])
    a = AzimuthAllocator(az, fixed=fixed)
    b = AzimuthAllocator(az, fixed=odd)
    taus = np.asfortranarray(tau * rng.uniform(-1, 1, (5, 1)))
    angles = (az.angle_prev + rng.uniform(-1, 1, (5, az.n)))[:, ::-1][:, ::-1]
    for x, y in zip(a.batch(np.ascontiguousarray(taus), np.ascontiguousarray(angles)),
                    b.batch(taus, angles), strict=True):  # fmt: skip
        assert np.array_equal(x, y)


def test_the_parallel_law_is_the_serial_law(monkeypatch):
    """Many requests run in ranges of rows on threads (``shipgym._jit.spread_rows``): the same
    floats as the serial law, row by row, and a bad row is reported as the serial law reports
    it."""
    import threading

    import shipgym.controllers.allocation.azimuth as law
    from shipgym._jit import threads_ok

    threads = set()
    spread_rows = law.spread_rows

    def spy(fn, n, *args):
        def seen(lo, hi, *a):
            threads.add(threading.current_thread().name)
            return fn(lo, hi, *a)

        return spread_rows(seen, n, *args)

    monkeypatch.setattr(law, "spread_rows", spy)

    v = load_vessel("wimpey-sealab")
    al = make_allocator(v, "constrained", 0.5)
    rng = np.random.default_rng(8)
    n = 70  # chunks of unequal size
    cap = v.actuators.capacity()[[0, 1, -1]]
    tau = rng.uniform(-1.2, 1.2, (n, 3)) * cap * rng.choice([0.05, 0.5, 1.0], (n, 1))
    state = np.zeros((n, v.actuators.n_channels))
    state[:, 1::2] = rng.uniform(-7.0, 7.0, (n, 4))
    monkeypatch.setattr(law, "PARALLEL_MIN", 1)
    par = al.batch(tau, state)
    if threads_ok():  # the chunks ran on the pool's threads
        assert any(name.startswith("shipgym-spread") for name in threads), threads
    monkeypatch.setattr(law, "PARALLEL_MIN", 10**9)
    ser = al.batch(tau, state)
    for a, b in zip(par, ser, strict=True):
        assert np.array_equal(a, b)
    monkeypatch.setattr(law, "PARALLEL_MIN", 1)
    tau[50, 1] = np.nan
    with pytest.raises(ValueError, match="NaN") as err:
        al.batch(tau, state)
    assert str(tau[50, 0]) in str(err.value)
