"""Azimuth thrusters by extended thrust with magnitude and rate limits (allocation.azimuth).

Oracles: the limits and ``tau = B u`` recomputed here from the returned thrusts and angles;
scipy's SLSQP on the same convex problem, written here from its definition (polygon facets
from the polygon's vertices, the rate sector from its two edge directions); the Blue Lady's
closed form where azimuths are held at a fixed angle.
"""

import itertools
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize

from shipgym.controllers.allocation import (
    AzimuthAllocation,
    AzimuthAllocator,
    Azimuths,
    allocate_azimuth,
    allocate_wls,
    extended_thrust_matrix,
)

WIMPEY = np.array([[31.5, 5.0], [31.5, -5.0], [-31.5, 5.0], [-31.5, -5.0]])  # m
F_WIMPEY = 122.6e3  # N: 12.5 t
RATE = math.radians(10.0)  # 10 deg/s at 1 s


def delivered(r: AzimuthAllocation, az: Azimuths, Bf=None):
    """``tau`` from the returned thrusts and angles, written out per unit."""
    n_dof = az.n_dof
    tau = np.zeros(n_dof)
    for (x, y, *z), T, a in zip(az.positions, r.thrust, r.angle, strict=True):
        fx, fy = T * math.cos(a), T * math.sin(a)
        tau[0] += fx
        tau[1] += fy
        tau[-1] += x * fy - y * fx
        if n_dof == 4:
            tau[2] += -z[0] * fy
    if Bf is not None:
        tau += Bf @ r.force_fixed
    return tau


def check_limits(r: AzimuthAllocation, az: Azimuths, fixed=None):
    m = az.n
    assert r.thrust.shape == r.angle.shape == (m,)
    assert r.force_azimuth.shape == (m, 2)
    k = 0 if fixed is None else fixed[0].shape[1]
    assert r.force_fixed.shape == (k,)
    assert r.saturated.shape == (m + k,) and r.saturated.dtype == np.bool_
    # (a) the angle change never exceeds max_dangle (a few ulps of the angle for round-off)
    dang = np.abs(r.angle - az.angle_prev)
    ulp = 4 * np.spacing(np.maximum(np.abs(az.angle_prev), 1.0))
    assert np.all(dang <= az.max_dangle + ulp)
    assert np.all(np.abs(r.thrust) <= az.f_max)
    assert np.all(r.thrust[~az.reversible] >= 0.0)
    np.testing.assert_allclose(
        r.force_azimuth,
        np.column_stack((r.thrust * np.cos(r.angle), r.thrust * np.sin(r.angle))),
        rtol=0,
        atol=1e-12 * az.f_max.max(),
    )
    Bf = None
    if fixed is not None:
        Bf, lo, hi = fixed
        assert np.all(r.force_fixed >= lo) and np.all(r.force_fixed <= hi)
    scale = np.abs(extended_thrust_matrix(az.positions)).max() * az.f_max.max() * (m + k)
    np.testing.assert_allclose(r.tau, delivered(r, az, Bf), rtol=0, atol=1e-12 * scale)


def random_case(rng, *, four=None, with_fixed=None):
    m = int(rng.integers(1, 7))
    four = rng.random() < 0.3 if four is None else four
    pos = rng.uniform(-40, 40, (m, 3 if four else 2))
    fmax = rng.uniform(0.2, 1.5, m) * 1e5
    prev = rng.uniform(-30, 30, m)
    d = np.where(rng.random(m) < 0.15, np.inf, rng.uniform(0.0, math.radians(89.0), m))
    d[rng.random(m) < 0.1] = 0.0
    rev = rng.random(m) < 0.4
    az = Azimuths(pos, fmax, prev, d, rev)
    fixed = None
    if rng.random() < 0.5 if with_fixed is None else with_fixed:
        k = int(rng.integers(1, 4))
        Bf = rng.normal(size=(az.n_dof, k)) * np.array([1, 1, *([3] if four else []), 30])[:, None]
        lo, hi = -rng.uniform(0, 1e5, k), rng.uniform(0, 1e5, k)
        fixed = (Bf, lo, hi)
    B = extended_thrust_matrix(pos)
    cap = np.abs(B) @ np.repeat(fmax, 2)
    if fixed is not None:
        cap = cap + np.abs(fixed[0]) @ np.maximum(-fixed[1], fixed[2])
    tau = rng.uniform(-1.2, 1.2, az.n_dof) * cap * rng.choice([0.05, 0.3, 1.0])
    return az, fixed, tau, cap


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_limits_hold_for_random_layouts(seed):
    rng = np.random.default_rng(seed)
    az, fixed, tau, _ = random_case(rng)
    r = allocate_azimuth(tau, az, fixed=fixed)
    check_limits(r, az, fixed)
    np.testing.assert_array_equal(r.tau_error, tau - r.tau)
    # the next call from the new angles keeps within the limits too
    r2 = allocate_azimuth(-tau, az.with_angles(r.angle), fixed=fixed)
    check_limits(r2, az.with_angles(r.angle), fixed)


def _request_inside_the_limits(seed):
    rng = np.random.default_rng(seed)
    az, fixed, _, cap = random_case(rng)
    m = az.n
    # a layout whose scaled configuration is ill-conditioned (one in 3 000: two units at almost
    # the same depth of a 4-DOF hull) meets the request only to the regularisation's floor
    # (1e-12 of the curvature, times the condition number squared), not to round-off
    B = extended_thrust_matrix(az.positions) * np.repeat(az.f_max, 2)
    if fixed is not None:
        B = np.hstack((fixed[0] * np.maximum(-fixed[1], fixed[2]), B))
    if np.linalg.cond(B / cap[:, None]) >= 1e3:
        return False
    # a force per unit within half its rate sector and half its magnitude
    half = np.where(np.isfinite(az.max_dangle), 0.5 * az.max_dangle, math.pi)
    a = az.angle_prev + rng.uniform(-1.0, 1.0, m) * half
    T = rng.uniform(0.0, 0.5, m) * az.f_max
    T[az.reversible & (rng.random(m) < 0.5)] *= -1.0
    tau = extended_thrust_matrix(az.positions) @ np.column_stack(
        (T * np.cos(a), T * np.sin(a))
    ).reshape(-1)
    if fixed is not None:
        tau = tau + fixed[0] @ rng.uniform(0.5 * fixed[1], 0.5 * fixed[2])
    k = 0 if fixed is None else fixed[0].shape[1]
    r = allocate_azimuth(tau, az, fixed=fixed, H=np.full(k + 2 * m, 1e-24))
    check_limits(r, az, fixed)
    np.testing.assert_allclose(r.tau, tau, rtol=0, atol=1e-9 * cap.max())
    assert not r.saturated.any() and not r.rate_limited.any()
    return True


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_request_inside_the_limits_is_met(seed):
    """(b) Forces well inside every limit: the request is delivered to round-off (a
    well-conditioned layout)."""
    assume(_request_inside_the_limits(seed))


@pytest.mark.parametrize("seed", [8617, 12528, 19196])
def test_a_units_projected_branch_is_tried_against_the_other(seed):
    """Cases (a search of 20 000 seeds) of two reversible units, both backwards at the
    optimum, where one's relaxed force lies off both its sectors and the other's in its
    forward sector: that other unit's branch must be tried too (its projection's branch left
    it no force and 15 % of N undelivered)."""
    assert _request_inside_the_limits(seed)


# ---- (c) optimality against an independent solver ----------------------------------------------
def oracle(tau, az, fixed, W, h, backwards):
    """SLSQP on the same convex problem, written from its definition."""
    m, n_dof = az.n, az.n_dof
    Bf = np.zeros((n_dof, 0)) if fixed is None else fixed[0]
    k = Bf.shape[1]
    B = np.hstack((Bf, extended_thrust_matrix(az.positions)))
    s = np.concatenate(
        (np.ones(k) if fixed is None else np.maximum(-fixed[1], fixed[2]), np.repeat(az.f_max, 2))
    )
    Wm = np.diag(W)

    def J(x):
        u = x * s
        e = B @ u - tau
        return float(e @ Wm @ e + u @ (h * u)) / J0

    def dJ(x):
        u = x * s
        return 2.0 * s * (B.T @ Wm @ (B @ u - tau) + h * u) / J0

    J0 = float(tau @ Wm @ tau) + 1.0
    cons = []
    ns = az.n_sides
    for j in range(m):
        c = az.angle_prev[j] + (math.pi if backwards[j] else 0.0)
        verts = [
            (math.cos(c + 2 * math.pi * i / ns), math.sin(c + 2 * math.pi * i / ns))
            for i in range(ns)
        ]
        ix, iy = k + 2 * j, k + 2 * j + 1
        for i in range(ns):  # inside: to the left of each edge v_i -> v_i+1
            (x0, y0), (x1, y1) = verts[i], verts[(i + 1) % ns]
            cons.append(
                {
                    "type": "ineq",
                    "fun": lambda x, x0=x0, y0=y0, x1=x1, y1=y1, ix=ix, iy=iy: (
                        (x1 - x0) * (x[iy] - y0) - (y1 - y0) * (x[ix] - x0)
                    ),
                }
            )
        d = az.max_dangle[j]
        if np.isfinite(d):
            for sgn in (1.0, -1.0):  # f between the directions c - d and c + d
                ex, ey = math.cos(c + sgn * d), math.sin(c + sgn * d)
                cons.append(
                    {
                        "type": "ineq",
                        "fun": lambda x, ex=ex, ey=ey, sgn=sgn, ix=ix, iy=iy: (
                            -sgn * (ex * x[iy] - ey * x[ix])
                        ),
                    }
                )
            if d == 0.0:
                ex, ey = math.cos(c), math.sin(c)
                cons.append(
                    {
                        "type": "ineq",
                        "fun": lambda x, ex=ex, ey=ey, ix=ix, iy=iy: ex * x[ix] + ey * x[iy],
                    }
                )
    bounds = [(fixed[1][i] / s[i], fixed[2][i] / s[i]) for i in range(k)]
    bounds += [(-1.0, 1.0)] * (2 * m)
    best = None
    for x0 in (np.zeros(k + 2 * m),):
        res = minimize(
            J,
            x0,
            jac=dJ,
            bounds=bounds,
            constraints=cons,
            method="SLSQP",
            options={"ftol": 1e-15, "maxiter": 2000},
        )
        if best is None or res.fun < best.fun:
            best = res
    return best.fun * J0, J0


@pytest.mark.parametrize("seed", range(30))
def test_optimal_against_slsqp(seed):
    rng = np.random.default_rng(1000 + seed)
    az, fixed, tau, cap = random_case(rng)
    k = 0 if fixed is None else fixed[0].shape[1]
    W = 1.0 / cap**2
    h = (
        np.full(k + 2 * az.n, 1e-6)
        / np.concatenate(
            (
                np.ones(k) if fixed is None else np.maximum(-fixed[1], fixed[2]),
                np.repeat(az.f_max, 2),
            )
        )
        ** 2
    )
    r = allocate_azimuth(tau, az, fixed=fixed, W=W, H=h)
    check_limits(r, az, fixed)
    # the branch of each reversible unit: the one its thrust sign shows; a unit with no thrust
    # is in both, so the oracle takes the better of them
    branched = az.reversible & np.isfinite(az.max_dangle)
    backwards = branched & (r.thrust < 0.0)
    either = np.flatnonzero(branched & (r.thrust == 0.0))
    u = np.concatenate((r.force_fixed, r.force_azimuth.reshape(-1)))
    e = r.tau - tau
    J = float(e @ (W * e) + u @ (h * u))
    J_ref = math.inf
    for flips in itertools.product([False, True], repeat=either.size):
        bw = backwards.copy()
        bw[either] = flips
        Jb, J0 = oracle(tau, az, fixed, W, h, bw)
        J_ref = min(J_ref, Jb)
    assert J <= J_ref + 1e-9 * J0  # SLSQP finds nothing better
    assert J >= J_ref - 1e-6 * J0  # and it agrees (SLSQP's own accuracy)


def test_reversible_branch_follows_the_unconstrained_optimum():
    # one reversible unit pointing ahead, asked to push astern: it keeps its angle and reverses
    az = Azimuths([[0.0, 0.0]], [100.0], [0.0], RATE, True)
    r = allocate_azimuth([-50.0, 0.0, 0.0], az, H=0.0 + 1e-12)
    assert r.thrust[0] == pytest.approx(-50.0, rel=1e-8)
    assert r.angle[0] == pytest.approx(0.0, abs=1e-12)
    # the same unit not reversible can only turn by 10 deg: no astern thrust at all
    az = Azimuths([[0.0, 0.0]], [100.0], [0.0], RATE, False)
    r = allocate_azimuth([-50.0, 0.0, 0.0], az)
    assert abs(r.thrust[0]) < 1e-6
    np.testing.assert_allclose(r.tau_error, [-50.0, 0.0, 0.0], atol=1e-6)
    assert r.angle[0] == 0.0  # no force: the angle is kept


def test_ambiguous_branch_tries_both():
    """A case (found by a random search) where the relaxed optimum of the reversible unit lies
    off both of its sectors and its projection picks the worse branch: both are tried."""
    rng = np.random.default_rng(6133)
    az, fixed, tau, cap = random_case(rng)
    k = 0 if fixed is None else fixed[0].shape[1]
    W = 1.0 / cap**2
    s = np.concatenate(
        (np.ones(k) if fixed is None else np.maximum(-fixed[1], fixed[2]), np.repeat(az.f_max, 2))
    )
    h = np.full(k + 2 * az.n, 1e-6) / s**2
    r = allocate_azimuth(tau, az, fixed=fixed, W=W, H=h)
    u = np.concatenate((r.force_fixed, r.force_azimuth.reshape(-1)))
    e = r.tau - tau
    J = float(e @ (W * e) + u @ (h * u))
    branched = np.flatnonzero(az.reversible & np.isfinite(az.max_dangle))
    J_all = []
    for flips in itertools.product([False, True], repeat=branched.size):
        bw = np.zeros(az.n, dtype=bool)
        bw[branched] = flips
        J_all.append(oracle(tau, az, fixed, W, h, bw))
    J_best, J0 = min(J_all)
    assert max(j for j, _ in J_all) > J_best + 1e-4 * J0  # the branches differ
    assert J <= J_best + 1e-9 * J0  # the better one is found


# ---- (d) the Wimpey Sealab's four azimuths: a sway step met as the units turn -------------------
@pytest.mark.parametrize("reversible", [False, True])
def test_wimpey_sway_step_is_met_within_the_rate_limit(reversible):
    az = Azimuths(WIMPEY, np.full(4, F_WIMPEY), np.zeros(4), RATE, reversible)
    tau = np.array([0.0, 200e3, 0.0])  # a 200 kN sway step, the units pointing ahead
    W = 1.0 / (np.abs(extended_thrust_matrix(WIMPEY)) @ np.full(8, F_WIMPEY)) ** 2
    J_prev, met_at = math.inf, None
    for step in range(20):
        r = allocate_azimuth(tau, az, W=W)
        check_limits(r, az)
        assert np.all(np.abs(r.angle - az.angle_prev) <= RATE + 1e-15)
        J = float(r.tau_error @ (W * r.tau_error))
        assert J <= J_prev * (1 + 1e-9) + 1e-18  # the previous forces stay feasible
        J_prev = J
        if met_at is None and np.abs(r.tau_error).max() < 1e-6 * 200e3:
            met_at = step
        az = az.with_angles(r.angle)
    if reversible:
        # pairs turn opposite ways, one pushing and one pulling, so that X cancels:
        # 4 F_max sin(20 deg) = 168 kN < 200 kN after two calls, 245 kN after three
        assert met_at == 2
    else:
        # a unit that only pushes cancels no X unless it points abeam: 9 calls of 10 deg
        assert met_at == 8
    np.testing.assert_allclose(r.tau, tau, rtol=0, atol=1e-3)
    assert not r.saturated.any()
    # a step back to zero is met at once (zero force is always feasible)
    r = allocate_azimuth(np.zeros(3), az, W=W)
    np.testing.assert_allclose(r.thrust, 0.0, atol=1e-6)
    np.testing.assert_array_equal(r.angle, az.angle_prev)


def test_wimpey_rate_limited_flag_while_turning():
    az = Azimuths(WIMPEY, np.full(4, F_WIMPEY), np.zeros(4), RATE)
    r = allocate_azimuth([0.0, 200e3, 0.0], az)
    assert r.rate_limited.all() and r.saturated.all()
    np.testing.assert_allclose(np.abs(r.angle), RATE, rtol=1e-12)


def test_magnitude_limit_and_polygon():
    # one unit, no rate limit, asked for twice its capacity straight ahead: F_max (a vertex)
    az = Azimuths([[0.0, 0.0]], [100.0], [0.0])
    r = allocate_azimuth([200.0, 0.0, 0.0], az)
    assert r.thrust[0] == pytest.approx(100.0, rel=1e-9) and r.saturated[0]
    # between two vertices the polygon cuts to its apothem at worst: >= cos(pi/16) F_max
    az = Azimuths([[0.0, 0.0]], [100.0], [0.0])
    a = math.pi / 16
    r = allocate_azimuth([200.0 * math.cos(a), 200.0 * math.sin(a), 0.0], az)
    assert 100.0 * math.cos(math.pi / 16) - 1e-9 <= r.thrust[0] <= 100.0
    assert r.angle[0] == pytest.approx(a, abs=1e-9)


def test_four_dof_roll_row():
    # two units 3 m and 1 m below the CG: K = -z fy
    az = Azimuths([[10.0, 2.0, 3.0], [-10.0, -2.0, 1.0]], [1e4, 1e4], [0.5, 0.5])
    B = extended_thrust_matrix(az.positions)
    np.testing.assert_array_equal(B[2], [0.0, -3.0, 0.0, -1.0])
    u = np.array([1e3, 2e3, -1e3, 1.5e3])
    tau = B @ u
    r = allocate_azimuth(tau, az, H=np.full(4, 1e-24))
    np.testing.assert_allclose(r.tau, tau, rtol=0, atol=1e-6)
    np.testing.assert_allclose(r.force_azimuth.reshape(-1), u, rtol=1e-8)
    check_limits(r, az)


def test_held_azimuths_equal_fixed_thrusters_wls():
    """Azimuths with max_dangle = 0 and reversible are fixed thrusters along their axes
    (thrust in [-F_max, F_max]); the answer equals allocate_wls with those columns."""
    rng = np.random.default_rng(7)
    pos = np.array([[20.0, 0.0], [15.0, 3.0], [-15.0, -3.0]])
    ang = np.array([0.0, math.pi / 2, math.pi / 2])
    fmax = np.array([3e5, 1e5, 1e5])
    az = Azimuths(pos, fmax, ang, 0.0, True)
    Bc = np.array(
        [
            [math.cos(a), math.sin(a), x * math.sin(a) - y * math.cos(a)]
            for (x, y), a in zip(pos, ang, strict=True)
        ]
    ).T
    W = np.array([1e-10, 1e-9, 1e-12])
    for _ in range(30):
        tau = rng.uniform(-1, 1, 3) * np.array([4e5, 3e5, 6e6])
        r = allocate_azimuth(tau, az, W=W, H=np.full(6, 1e-30))
        w = allocate_wls(tau, Bc, -fmax, fmax, W=W, H=0.0)
        np.testing.assert_allclose(r.thrust, w.force, rtol=0, atol=1e-6 * fmax.max())
        np.testing.assert_array_equal(r.angle, ang)


def test_angles_stay_continuous():
    az = Azimuths([[0.0, 0.0]], [100.0], [100.0], RATE)  # 100 rad: many turns already
    r = allocate_azimuth([0.0, -50.0, 0.0], az)
    assert abs(r.angle[0] - 100.0) <= RATE + 1e-13
    az = Azimuths([[0.0, 0.0]], [100.0], [-7.0])  # no rate limit: within pi of the old angle
    r = allocate_azimuth([-50.0, -1.0, 0.0], az)
    assert abs(r.angle[0] + 7.0) <= math.pi
    assert math.cos(r.angle[0]) == pytest.approx(-1.0, abs=1e-3)


def test_zero_request_keeps_angles():
    rng = np.random.default_rng(2)
    az, fixed, _, _ = random_case(rng, with_fixed=True)
    r = allocate_azimuth(np.zeros(az.n_dof), az, fixed=fixed)
    np.testing.assert_allclose(r.thrust, 0.0, atol=1e-9)
    np.testing.assert_array_equal(r.angle, az.angle_prev)
    np.testing.assert_allclose(r.force_fixed, 0.0, atol=1e-9)


def test_with_angles():
    az = Azimuths(WIMPEY, np.full(4, F_WIMPEY), np.zeros(4), RATE, True)
    b = az.with_angles([1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(b.angle_prev, [1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(az.angle_prev, 0.0)  # the original is unchanged
    with pytest.raises(ValueError, match="angle must have shape"):
        az.with_angles([1.0])
    with pytest.raises(ValueError, match="NaN"):
        az.with_angles([1.0, np.nan, 0.0, 0.0])
    with pytest.raises(ValueError):
        b.angle_prev[0] = 3.0  # read-only


def test_prepared_allocator_gives_the_same_answers():
    rng = np.random.default_rng(21)
    for _ in range(30):
        az, fixed, tau, _ = random_case(rng)
        al = AzimuthAllocator(az, fixed=fixed)
        angles = az.angle_prev
        for _ in range(4):
            t = tau * rng.uniform(-1.5, 1.5)
            a = al(t, angles)
            b = allocate_azimuth(t, az.with_angles(angles), fixed=fixed)
            for x, y in zip(a, b, strict=True):
                np.testing.assert_array_equal(x, y)
            angles = a.angle
        np.testing.assert_array_equal(al(tau).angle, allocate_azimuth(tau, az, fixed=fixed).angle)
    with pytest.raises(ValueError, match="angle_prev must have shape"):
        al(tau, [0.0] * (az.n + 1))
    with pytest.raises(TypeError, match="Azimuths instance"):
        AzimuthAllocator("not azimuths")


# ---- bad input ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(positions=np.zeros((2, 4))), "positions must have shape"),
        (dict(positions=[[0.0, np.nan], [1.0, 1.0]]), "positions contain NaN"),
        (dict(f_max=[1.0, 0.0]), "f_max must be > 0"),
        (dict(f_max=[1.0]), "f_max must have shape"),
        (dict(angle_prev=[0.0, np.inf]), "angle_prev contains NaN"),
        (dict(max_dangle=math.pi / 2), r"max_dangle must be in \[0, pi/2\)"),
        (dict(max_dangle=-0.1), r"max_dangle must be in \[0, pi/2\)"),
        (dict(max_dangle=[0.1, 0.2, 0.3]), "max_dangle must be a number or shape"),
        (dict(reversible=[1, 0]), "reversible must be bool"),
        (dict(n_sides=7), "n_sides must be an even integer"),
        (dict(n_sides=2), "n_sides must be an even integer"),
    ],
)
def test_bad_azimuths_raise(kw, match):
    args = dict(positions=[[1.0, 0.0], [-1.0, 0.0]], f_max=[1.0, 1.0], angle_prev=[0.0, 0.0])
    with pytest.raises(ValueError, match=match):
        Azimuths(**{**args, **kw})


AZ = Azimuths([[1.0, 0.0], [-1.0, 0.0]], [1.0, 1.0], [0.0, 0.0], 0.1)


@pytest.mark.parametrize(
    "tau, kw, exc, match",
    [
        ([1.0, 2.0], {}, ValueError, "tau must have shape"),
        ([1.0, 2.0, np.nan], {}, ValueError, "tau contains NaN"),
        ([1.0, 0.0, 0.0], dict(fixed=(np.ones((4, 1)), [-1.0], [1.0])), ValueError, "3 rows"),
        ([1.0, 0.0, 0.0], dict(fixed=(np.ones((3, 1)), [0.5], [1.0])), ValueError, "contain 0"),
        (
            [1.0, 0.0, 0.0],
            dict(fixed=(np.ones((3, 1)), [1.0], [-1.0])),
            ValueError,
            "f_min > f_max",
        ),
        ([1.0, 0.0, 0.0], dict(fixed=np.ones((3, 1))), ValueError, "fixed must be a tuple"),
        ([1.0, 0.0, 0.0], dict(W=[1.0, -1.0, 1.0]), ValueError, "W must be >= 0"),
        ([1.0, 0.0, 0.0], dict(H=[1.0, 1.0]), ValueError, "H must have shape"),
    ],
)
def test_bad_allocation_input_raises(tau, kw, exc, match):
    with pytest.raises(exc, match=match):
        allocate_azimuth(tau, AZ, **kw)


def test_azimuths_type_checked():
    with pytest.raises(TypeError, match="Azimuths instance"):
        allocate_azimuth([0.0, 0.0, 0.0], {"positions": [[0.0, 0.0]]})


def test_turn_weight_keeps_the_angles_when_the_request_allows() -> None:
    """Two reversible units on the centre line pointing athwartships, a pure sway request:
    with the turning cost the answer keeps both angles and meets the request; the weight
    must be a finite number >= 0."""
    az = Azimuths(
        positions=np.array([[10.0, 0.0], [-10.0, 0.0]]),
        f_max=np.array([1e5, 1e5]),
        angle_prev=np.array([math.pi / 2, math.pi / 2]),
        max_dangle=math.radians(10.0),
        reversible=True,
    )
    tau = np.array([0.0, 5e4, 0.0])
    r = AzimuthAllocator(az, turn_weight=0.1)(tau)
    np.testing.assert_allclose(r.angle, az.angle_prev, atol=1e-9)
    np.testing.assert_allclose(r.tau, tau, atol=1e-3)
    with pytest.raises(ValueError, match="turn_weight"):
        AzimuthAllocator(az, turn_weight=-1.0)
