"""Guidance: r-frame (Tomera 2014 eqs. 1-2), smooth leg references, 5-leg plan, leg switching."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shipgym.dynamics import wrap_angle
from shipgym.guidance import (
    BLUE_LADY_LIMITS,
    PLANS,
    Guidance,
    Leg,
    ManoeuvrePlan,
    from_r_frame,
    leg_duration,
    leg_profile,
    leg_reference,
    plan,
    to_r_frame,
    tomera2014_plan,
)

DEG = math.pi / 180.0
coord = st.floats(-500.0, 500.0, allow_nan=False)
angle = st.floats(-10.0, 10.0, allow_nan=False)


def seed_eq1(eta_n, eta_P):
    """Tomera (2014) eq. 1 with the matrix of eq. 2, applied to a column vector."""
    c, s = math.cos(eta_P[2]), math.sin(eta_P[2])
    R2 = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    return R2 @ (np.asarray(eta_n, float) - np.asarray(eta_P, float))


# -- r-frame -------------------------------------------------------------------------------------
@settings(max_examples=200, deadline=None)
@given(coord, coord, angle, coord, coord, angle)
def test_r_frame_round_trip(x, y, psi, xP, yP, psiP):
    eta, P = np.array([x, y, psi]), np.array([xP, yP, psiP])
    r = to_r_frame(eta, P)
    assert -math.pi < r[2] <= math.pi
    back = from_r_frame(r, P)
    np.testing.assert_allclose(back[:2], eta[:2], atol=1e-9)
    assert wrap_angle(back[2] - eta[2]) == pytest.approx(0.0, abs=1e-9)
    # and the other way round for an r-frame heading within pi
    er = np.array([x, y, wrap_angle(psi)])
    np.testing.assert_allclose(to_r_frame(from_r_frame(er, P), P), er, atol=1e-9)


@settings(max_examples=100, deadline=None)
@given(coord, coord, st.floats(-0.5, 0.5), coord, coord, angle)
def test_r_frame_equals_seed_eq1(x, y, dpsi, xP, yP, psiP):
    P = np.array([xP, yP, psiP])
    eta = np.array([x, y, psiP + dpsi])
    np.testing.assert_allclose(to_r_frame(eta, P), seed_eq1(eta, P), atol=1e-9)


def test_r_frame_axes_and_batch():
    # heading east (90 deg): 1 m ahead is +x^r, 1 m to the north (port) is -y^r
    P = np.array([10.0, 20.0, 90 * DEG])
    pts = np.array([[10.0, 21.0, 90 * DEG], [11.0, 20.0, 90 * DEG], [10.0, 20.0, 0.0]])
    r = to_r_frame(pts, P)
    assert r.shape == (3, 3)
    np.testing.assert_allclose(r, [[1, 0, 0], [0, -1, 0], [0, 0, -90 * DEG]], atol=1e-12)
    np.testing.assert_allclose(from_r_frame(r, P)[:, :2], pts[:, :2], atol=1e-12)
    # batch on both arguments
    Ps = np.stack([P, P + [1.0, 0.0, 0.1]])
    assert to_r_frame(pts[:2], Ps).shape == (2, 3)
    with pytest.raises(ValueError, match="length 3"):
        to_r_frame([1.0, 2.0], P)


def test_r_frame_heading_near_wrap():
    P = np.array([0.0, 0.0, 359 * DEG])
    # ship at 1 deg (just across north) is 2 deg clockwise of P
    assert to_r_frame([0.0, 0.0, 1 * DEG], P)[2] == pytest.approx(2 * DEG)
    assert to_r_frame([0.0, 0.0, 361 * DEG], P)[2] == pytest.approx(2 * DEG)
    assert to_r_frame([0.0, 0.0, -359 * DEG], P)[2] == pytest.approx(2 * DEG)
    # a heading series crossing 0/360 maps to a smooth r-frame series
    psi = np.radians(np.linspace(340.0, 380.0, 81)) % (2 * np.pi)
    r = to_r_frame(np.stack([np.zeros_like(psi), np.zeros_like(psi), psi], -1), P)
    assert np.max(np.abs(np.diff(r[:, 2]))) < 1 * DEG
    # psi_ref_r unwraps around a reference beyond pi (a turn of 180 deg or more)
    P0 = np.zeros(3)
    assert to_r_frame([0, 0, 181 * DEG], P0)[2] == pytest.approx(-179 * DEG)
    assert to_r_frame([0, 0, 181 * DEG], P0, psi_ref_r=math.pi)[2] == pytest.approx(181 * DEG)
    assert to_r_frame([0, 0, -179 * DEG], P0, psi_ref_r=math.pi)[2] == pytest.approx(181 * DEG)
    assert to_r_frame([0, 0, 10 * DEG], P0, psi_ref_r=2 * math.pi)[2] == pytest.approx(370 * DEG)


# -- leg reference ---------------------------------------------------------------------------------
LEGS = [
    Leg(sway=-7.0),
    Leg(surge=38.0),
    Leg(yaw=math.pi / 2),
    Leg(surge=-15.0),
    Leg(sway=-3.0),
    Leg(surge=0.3),
    Leg(surge=10.0, sway=3.0, yaw=-0.4),
    Leg(surge=-4.0, sway=-1.0, yaw=3.5),
]


@pytest.mark.parametrize("leg", LEGS)
def test_reference_derivatives_are_consistent(leg):
    prof = leg_profile(leg, BLUE_LADY_LIMITS)
    T = prof.duration
    t = np.linspace(-0.05 * T, 1.05 * T, 22001)
    p, v, a = leg_reference(leg, BLUE_LADY_LIMITS, t)
    assert p.shape == v.shape == a.shape == (t.size, 3)
    dt = t[1] - t[0]
    scale_v = np.max(np.abs(v), axis=0) + 1e-300
    scale_a = np.max(np.abs(a), axis=0) + 1e-300
    fd_v = (p[2:] - p[:-2]) / (2 * dt)
    fd_a = (v[2:] - v[:-2]) / (2 * dt)
    assert np.all(np.abs(fd_v - v[1:-1]) <= 1e-5 * scale_v + 1e-12)
    assert np.all(np.abs(fd_a - a[1:-1]) <= 1e-3 * scale_a + 1e-12)
    # continuous acceleration: steps no larger than the bounded jerk pi a_peak / T_a allows
    jerk = math.pi * scale_a / prof.t_accel
    assert np.all(np.abs(np.diff(a, axis=0)) <= jerk * dt * (1 + 1e-9))
    # the trapezoidal integral of the acceleration reproduces the velocity and position
    v_int = np.concatenate([[v[0]], v[0] + np.cumsum(0.5 * (a[1:] + a[:-1]) * dt, axis=0)])
    np.testing.assert_allclose(v_int, v, atol=1e-6 * scale_v.max())


@pytest.mark.parametrize("leg", LEGS)
def test_reference_limits_and_endpoints(leg):
    lim = BLUE_LADY_LIMITS
    T = leg_duration(leg, lim)
    t = np.linspace(0.0, T, 50001)
    p, v, a = leg_reference(leg, lim, t)
    v_max, a_max = lim.for_displacement(leg.displacement)
    assert np.all(np.abs(v) <= v_max * (1 + 1e-12))
    assert np.all(np.abs(a) <= a_max * (1 + 1e-12))
    # time-optimal for the profile family: some DOF reaches its acceleration limit
    assert np.max(np.abs(a) / a_max) == pytest.approx(1.0, rel=1e-6)
    # exact rest at both ends, exact end point, held afterwards
    for tt in (0.0, -3.0):
        for arr in leg_reference(leg, lim, tt):
            assert np.array_equal(arr, np.zeros(3))
    for tt in (T, T + 1.0, 1e6):
        pe, ve, ae = leg_reference(leg, lim, tt)
        assert np.array_equal(pe, leg.displacement)
        assert np.array_equal(ve, np.zeros(3)) and np.array_equal(ae, np.zeros(3))
    # a scalar time gives the array's row (one compiled law)
    for k in (1, 5000, 17777, 33333, 49999):
        for s_arr, s_sc in zip(
            (p[k], v[k], a[k]), leg_reference(leg, lim, float(t[k])), strict=True
        ):
            assert np.array_equal(s_arr, s_sc)


@pytest.mark.parametrize("leg", [Leg(surge=38.0), Leg(sway=-3.0), Leg(yaw=math.pi / 2)])
def test_profile_is_the_raised_cosine_trapezoid_in_closed_form(leg):
    # Tomera (2014) Fig. 3 as this package shapes it: s_ddot = (A/2)(1 - cos(2 pi t / T_a))
    # while accelerating, s_dot = V cruising, the mirror image braking; the integral of the
    # speed is the displacement (SciPy's Simpson rule, independent of the closed forms)
    from scipy.integrate import simpson

    prof = leg_profile(leg, BLUE_LADY_LIMITS)
    A, V, Ta, T = prof.accel, prof.speed, prof.t_accel, prof.duration
    assert V == pytest.approx(0.5 * A * Ta, rel=1e-12)
    d = leg.displacement
    t = np.linspace(0.0, Ta, 401)[1:-1]
    _, v, a = prof.evaluate(t)
    want_a = (0.5 * A * (1.0 - np.cos(2.0 * math.pi * t / Ta)))[:, None] * d
    np.testing.assert_allclose(a, want_a, rtol=1e-12, atol=1e-18)
    want_v = (0.5 * A * (t - Ta / (2.0 * math.pi) * np.sin(2.0 * math.pi * t / Ta)))[:, None] * d
    np.testing.assert_allclose(v, want_v, rtol=1e-12, atol=1e-18)
    _, v_end, a_end = prof.evaluate(T - t)  # braking: the mirror image
    np.testing.assert_allclose(a_end, -want_a, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(v_end, want_v, rtol=1e-9, atol=1e-15)
    if prof.t_cruise > 0.0:
        _, v_c, a_c = prof.evaluate(np.linspace(Ta, T - Ta, 7))
        assert np.array_equal(v_c, np.tile(V * d, (7, 1))) and not np.any(a_c)
    tt = np.linspace(0.0, T, 20001)
    _, v_all, _ = prof.evaluate(tt)
    np.testing.assert_allclose(simpson(v_all, x=tt, axis=0), d, rtol=1e-9, atol=1e-12)


def test_combined_leg_is_synchronised_on_a_straight_line():
    lim = BLUE_LADY_LIMITS
    leg = Leg(surge=10.0, sway=3.0, yaw=-0.4)
    T = leg_duration(leg, lim)
    singles = [leg_duration(Leg(surge=10.0), lim), leg_duration(Leg(sway=3.0), lim)]
    singles.append(leg_duration(Leg(yaw=-0.4), lim))
    assert T >= max(singles) - 1e-9
    t = np.linspace(0.0, T, 2001)
    p, _, _ = leg_reference(leg, lim, t)
    frac = p / leg.displacement
    np.testing.assert_allclose(frac, np.repeat(frac[:, :1], 3, axis=1), atol=1e-12)
    # no DOF arrives before the others
    assert np.all(frac[:-1] < 1.0) and np.all(frac[-1] == 1.0)


def test_durations_of_the_seed_legs_match_the_closed_forms():
    lim = BLUE_LADY_LIMITS
    # raised-cosine trapezoid: T = d / v + 2 v / a ; triangle (d < 2 v^2 / a): T = 2 sqrt(2 d / a)
    assert leg_duration(Leg(sway=-7.0), lim) == pytest.approx(7 / 0.03 + 2 * 0.03 / 5e-4)
    assert leg_duration(Leg(surge=38.0), lim) == pytest.approx(2 * math.sqrt(2 * 38 / 0.002))
    assert leg_duration(Leg(yaw=math.pi / 2), lim) == pytest.approx(
        2 * math.sqrt(2 * (math.pi / 2) / 9e-5)
    )
    assert leg_duration(Leg(surge=-15.0), lim) == pytest.approx(15 / 0.1 + 2 * 0.1 / 0.0018)
    assert leg_duration(Leg(sway=-3.0), lim) == pytest.approx(2 * math.sqrt(2 * 3 / 5e-4))
    assert leg_duration(Leg(), lim) == 0.0
    # the per-leg override wins over the plan's limits
    fast = dataclasses.replace(BLUE_LADY_LIMITS, sway_speed=0.1, sway_accel=0.01)
    assert leg_duration(Leg(sway=-7.0, limits=fast), lim) == pytest.approx(7 / 0.1 + 20.0)
    assert tomera2014_plan().durations(BLUE_LADY_LIMITS) == pytest.approx(
        [
            7 / 0.03 + 120.0,
            2 * math.sqrt(38000.0),
            2 * math.sqrt(2 * (math.pi / 2) / 9e-5),
            15 / 0.1 + 0.2 / 0.0018,
            2 * math.sqrt(12000.0),
        ]
    )


def test_zero_leg_is_at_rest():
    p, v, a = leg_reference(Leg(), BLUE_LADY_LIMITS, np.array([0.0, 1.0]))
    assert not np.any(p) and not np.any(v) and not np.any(a)
    assert leg_profile(Leg(), BLUE_LADY_LIMITS).duration == 0.0


# -- plans -----------------------------------------------------------------------------------------
def test_tomera2014_waypoints_from_origin_heading_north():
    wp = tomera2014_plan().waypoints([0.0, 0.0, 0.0])
    expected = [
        [0, 0, 0],
        [0, -7, 0],
        [38, -7, 0],
        [38, -7, math.pi / 2],
        [38, -22, math.pi / 2],
        [41, -22, math.pi / 2],
    ]
    np.testing.assert_allclose(wp, expected, atol=1e-12)
    assert plan("tomera2014") == tomera2014_plan()
    assert set(PLANS) == {"tomera2014"}
    assert [leg.displacement.tolist() for leg in tomera2014_plan().legs] == [
        [0, -7, 0],
        [38, 0, 0],
        [0, 0, math.pi / 2],
        [-15, 0, 0],
        [0, -3, 0],
    ]


def test_waypoints_chain_on_planned_points_and_cross_north_without_jump():
    p = tomera2014_plan()
    start = np.array([100.0, -50.0, 350 * DEG])
    wp = p.waypoints(start)
    np.testing.assert_allclose(np.diff(wp[:, 2]), [0, 0, math.pi / 2, 0, 0], atol=1e-15)
    assert wp[-1, 2] == pytest.approx(440 * DEG)
    # every K_i is the leg displacement in the r-frame of P_i = K_{i-1}
    for i, leg in enumerate(p.legs):
        np.testing.assert_allclose(to_r_frame(wp[i + 1], wp[i]), leg.displacement, atol=1e-12)
    # rigid motion: same shape as from the origin heading north
    wp0 = p.waypoints([0.0, 0.0, 0.0])
    for i in range(len(wp)):
        np.testing.assert_allclose(to_r_frame(wp[i], start), wp0[i], atol=1e-9)


def test_plan_from_dict_round_trip_and_degrees():
    p = tomera2014_plan(settle_time=3.0)
    assert ManoeuvrePlan.from_dict(p.to_dict()) == p
    q = ManoeuvrePlan.from_dict(
        {
            "legs": [{"yaw_deg": -90, "name": "turn to port"}, {"surge": 5}],
            "switch_heading_deg": 3.0,
            "limits": {**BLUE_LADY_LIMITS.to_dict(), "yaw_rate": 0.01},
        }
    )
    assert q.legs[0].yaw == pytest.approx(-math.pi / 2)
    assert q.switch_heading == pytest.approx(3 * DEG)
    assert q.limits.yaw_rate == 0.01 and q.limits.sway_speed == BLUE_LADY_LIMITS.sway_speed
    assert q.switch_distance == 1.0


@pytest.mark.parametrize(
    ("data", "match"),
    [
        ({"legs": [{"surge": 1}], "switch_dist": 1.0}, "valid keys are: legs, switch_distance"),
        ({"legs": [{"surge": 1, "heave": 2}]}, r"legs\[0\].*valid keys are: surge, sway"),
        ({"legs": []}, "empty"),
        ({}, "no 'legs'"),
        ({"legs": {"surge": 1}}, "list of leg mappings"),
        ({"legs": [{"surge": float("nan")}]}, "finite"),
        ({"legs": [{"sway": float("inf")}]}, "finite"),
        ({"legs": [{"yaw": 1.0, "yaw_deg": 57.0}]}, "not both"),
        ({"legs": [{"surge": "ten"}]}, "must be a number"),
        ({"legs": [{"surge": 1}], "switch_distance": 0.0}, "switch_distance must be > 0"),
        ({"legs": [{"surge": 1}], "switch_heading_deg": -5}, "switch_heading"),
        ({"legs": [{"surge": 1}], "switch_min_progress": 1.5}, r"\[0, 1\]"),
        ({"legs": [{"surge": 1}], "settle_time": -1.0}, "settle_time"),
        ({"legs": [{"surge": 1}], "limits": {"surge_max": 1.0}}, "valid keys are: surge_speed"),
        (
            {"legs": [{"surge": 1}], "limits": {**BLUE_LADY_LIMITS.to_dict(), "sway_accel": -1.0}},
            "must be > 0",
        ),
        (
            {
                "legs": [{"surge": 1}],
                "limits": {**BLUE_LADY_LIMITS.to_dict(), "yaw_rate": float("nan")},
            },
            "finite",
        ),
    ],
)
def test_bad_plans_raise_clear_errors(data, match):
    with pytest.raises(ValueError, match=match):
        ManoeuvrePlan.from_dict(data)


def test_bad_names_and_constructors():
    with pytest.raises(ValueError, match="valid names are: tomera2014"):
        plan("tomera2015")
    with pytest.raises(ValueError, match="empty"):
        ManoeuvrePlan(legs=())
    with pytest.raises(ValueError, match="finite"):
        Leg(surge=float("nan"))
    with pytest.raises(ValueError, match="must be a Leg"):
        ManoeuvrePlan(legs=({"surge": 1.0},))
    with pytest.raises(ValueError, match="eta_start"):
        tomera2014_plan().waypoints([0.0, 0.0])
    assert isinstance(ManoeuvrePlan(legs=[Leg(surge=1.0)]).legs, tuple)


# -- runtime guidance and switching ------------------------------------------------------------
def run_perfect_tracker(p, start, dt=1.0, t_end=3000.0):
    """A ship that sits exactly on the reference; returns the guidance and the sampled refs."""
    g = Guidance(p, limits=BLUE_LADY_LIMITS)
    g.reset(start)
    refs, t = [], 0.0
    while t <= t_end:
        ref = g.reference(t)
        g.update(t, ref.eta_d_n)
        refs.append(g.reference(t))
        t += dt
    return g, refs


def test_perfect_tracker_completes_legs_on_the_reference_schedule():
    p = tomera2014_plan()
    g, refs = run_perfect_tracker(p, [0.0, 0.0, 0.0], dt=0.5)
    assert g.finished and g.leg_index == 4 and g.n_legs == 5
    durations = np.array(p.durations(BLUE_LADY_LIMITS))
    # switching waits for the reference (switch_min_progress = 1): each leg lasts its
    # reference duration rounded up to the 0.5 s step
    np.testing.assert_allclose(g.leg_durations, np.ceil(durations / 0.5) * 0.5)
    assert g.leg_start_times[0] == 0.0
    assert g.leg_start_times[1:] == g.leg_completion_times[:-1]
    np.testing.assert_allclose(refs[-1].eta_d_n, g.waypoints[-1], atol=1e-12)
    assert refs[-1].finished
    # no jump of the desired NED pose anywhere, leg switches included
    eta_d = np.array([r.eta_d_n for r in refs])
    assert np.max(np.abs(np.diff(eta_d[:, :2], axis=0))) < 0.2 * 0.5 + 1e-9
    assert np.max(np.abs(np.diff(eta_d[:, 2]))) < 1 * DEG * 0.5 + 1e-9
    assert g.update(1e4, g.waypoints[-1]) is False


def test_reference_heading_has_no_jump_across_north():
    start = np.array([0.0, 0.0, 350 * DEG])
    g, refs = run_perfect_tracker(tomera2014_plan(), start, dt=0.5)
    assert g.finished
    psi_d = np.array([r.eta_d_n[2] for r in refs])
    assert np.max(np.abs(np.diff(psi_d))) < 0.6 * DEG
    assert psi_d[0] == pytest.approx(350 * DEG) and psi_d[-1] == pytest.approx(440 * DEG)
    # the ship's heading reported wrapped to [0, 360) still maps onto the reference
    for r in refs[::50]:
        ship = r.eta_d_n.copy()
        ship[2] = ship[2] % (2 * math.pi)
        np.testing.assert_allclose(r.to_r(ship), r.eta_d_r, atol=1e-9)


def test_no_switch_until_all_conditions_hold():
    p = tomera2014_plan()
    g = Guidance(p, limits=BLUE_LADY_LIMITS)
    with pytest.raises(RuntimeError, match="reset"):
        g.reference(0.0)
    g.reset([0.0, 0.0, 0.0])
    K = g.waypoints[1]
    T0 = p.durations(BLUE_LADY_LIMITS)[0]
    # ship at rest at the start: 7 m from K
    assert not g.update(T0 + 100, [0.0, 0.0, 0.0])
    # ship already at K but the reference is still moving: no premature switch
    assert not g.update(0.5 * T0, K)
    assert g.switch_conditions(0.5 * T0, K) == (True, True, False)
    # distance 1 m exactly is not "within" 1 m; a heading error above 5 deg blocks
    assert not g.update(T0, K + [1.0, 0.0, 0.0])
    assert not g.update(T0, K + [0.0, 0.0, 5.01 * DEG])
    assert g.leg_index == 0
    assert g.update(T0 + 1.0, K + [0.6, -0.6, -4 * DEG])
    assert g.leg_index == 1 and g.leg_start_times == (0.0, T0 + 1.0)
    ref = g.reference(T0 + 1.0)
    assert ref.leg == 1 and ref.t_leg == 0.0
    np.testing.assert_allclose(ref.eta_P, K)
    np.testing.assert_allclose(ref.eta_d_n, K)


def test_rotation_leg_needs_heading_even_without_progress_guard():
    # seed rule alone (switch_min_progress = 0): at the start of the 90 deg rotation the
    # ship is within 1 m of K, but its heading is 90 deg off, so no switch
    p = ManoeuvrePlan(legs=(Leg(yaw=math.pi / 2), Leg(surge=1.0)), switch_min_progress=0.0)
    g = Guidance(p, limits=BLUE_LADY_LIMITS)
    g.reset([5.0, 5.0, 350 * DEG])
    assert not g.update(0.0, [5.0, 5.0, 350 * DEG])
    assert not g.update(10.0, [5.2, 5.0, 80 * DEG - 6 * DEG])
    # heading 444 deg == 84 deg: wrapped error to K (440 deg) is 4 deg -> switch
    assert g.update(11.0, [5.2, 5.0, 84 * DEG])
    assert g.leg_index == 1


def test_seed_rule_alone_switches_early_and_the_guard_prevents_it():
    legs = (Leg(sway=-7.0), Leg(surge=5.0))
    early = ManoeuvrePlan(legs=legs, switch_min_progress=0.0)
    g, _ = run_perfect_tracker(early, [0.0, 0.0, 0.0], t_end=500.0)
    assert g.leg_durations[0] < leg_duration(legs[0], BLUE_LADY_LIMITS) - 10.0
    g, _ = run_perfect_tracker(ManoeuvrePlan(legs=legs), [0.0, 0.0, 0.0], t_end=500.0)
    # the switch at the first step (1 s) at or after the reference's end
    assert g.leg_durations[0] == math.ceil(leg_duration(legs[0], BLUE_LADY_LIMITS))
    # a leg shorter than the switch distance waits for its reference too
    g = Guidance(ManoeuvrePlan(legs=(Leg(surge=0.5), Leg(surge=0.5))), limits=BLUE_LADY_LIMITS)
    g.reset([0.0, 0.0, 0.0])
    assert not g.update(0.0, [0.0, 0.0, 0.0])


def test_settle_time_requires_the_conditions_to_hold_continuously():
    p = ManoeuvrePlan(legs=(Leg(surge=2.0), Leg(surge=2.0)), settle_time=5.0)
    g = Guidance(p, limits=BLUE_LADY_LIMITS)
    g.reset([0.0, 0.0, 0.0])
    T = p.durations(BLUE_LADY_LIMITS)[0]
    K = g.waypoints[1]
    assert not g.update(T, K)
    assert not g.update(T + 3.0, K)
    assert not g.update(T + 4.0, K + [2.0, 0.0, 0.0])  # condition broken: timer restarts
    assert not g.update(T + 6.0, K)
    assert not g.update(T + 10.0, K)
    assert g.update(T + 11.0, K)
    assert g.leg_completion_times == (T + 11.0,)


def test_body_frame_reference_velocity_and_its_derivative():
    leg = Leg(surge=10.0, sway=3.0, yaw=1.2)
    g = Guidance(ManoeuvrePlan(legs=(leg,)), limits=BLUE_LADY_LIMITS)
    g.reset([1.0, 2.0, 3.0])
    T = leg_duration(leg, BLUE_LADY_LIMITS)
    h = 1e-3
    for t in np.linspace(0.05 * T, 0.95 * T, 7):
        ref = g.reference(t)
        psi = ref.eta_d_r[2]
        c, s = math.cos(psi), math.sin(psi)
        # eta_dot = R(psi) nu in the r-frame
        np.testing.assert_allclose(
            [c * ref.nu_d[0] - s * ref.nu_d[1], s * ref.nu_d[0] + c * ref.nu_d[1]],
            ref.eta_dot_d_r[:2],
            atol=1e-15,
        )
        fd = (g.reference(t + h).nu_d - g.reference(t - h).nu_d) / (2 * h)
        np.testing.assert_allclose(ref.nu_dot_d, fd, atol=1e-9)
        fd_n = (g.reference(t + h).eta_d_n - g.reference(t - h).eta_d_n) / (2 * h)
        np.testing.assert_allclose(ref.eta_dot_d_n, fd_n, atol=1e-9)


def test_guidance_reference_is_the_profile_and_the_body_velocities_rotate():
    # the guidance's reference is the leg's profile (one compiled law) at the leg's time, a
    # Reference equal field by field to the dataclass built from the same values, and the
    # body velocities R(psi)^T eta_dot (Fossen 2011 eq. 2.62) of a rotation matrix
    from shipgym.dynamics.frames import rot
    from shipgym.guidance import Reference

    legs = (
        Leg(surge=10.0, sway=3.0, yaw=1.2),
        Leg(sway=-4.0, delay=5.0),
        Leg(yaw=-2.0, step=True, delay=3.0),
    )
    g = Guidance(ManoeuvrePlan(legs=legs), limits=BLUE_LADY_LIMITS)
    g.reset([1.0, 2.0, 3.0])
    for i, leg in enumerate(legs):
        prof = leg_profile(leg, BLUE_LADY_LIMITS)
        T = prof.total_duration
        t_start = g.leg_start_times[-1]
        for t_leg in np.linspace(-1.0, T + 5.0, 23).tolist():
            ref = g.reference(t_start + t_leg)
            want = prof.evaluate(np.array([ref.t_leg]))
            for got, w in zip((ref.eta_d_r, ref.eta_dot_d_r, ref.eta_ddot_d_r), want, strict=True):
                np.testing.assert_array_equal(got, w[0])
        for t in np.linspace(0.0, T + 2.0, 9).tolist():
            ref = g.reference(float(g.leg_start_times[-1] + t))
            assert ref.leg == i
            # every field set, equal to the dataclass built from the same values, whose
            # cached body velocities are computed on first use
            plain = Reference(**{f.name: getattr(ref, f.name) for f in dataclasses.fields(ref)})
            assert {f.name for f in dataclasses.fields(ref)} <= set(vars(ref))
            assert ref._nu_d == plain._nu_d and ref._nu_dot_d == plain._nu_dot_d
            np.testing.assert_array_equal(ref.eta_dot_d_n, plain.eta_dot_d_n)
            R = rot(ref.eta_d_r[2])
            np.testing.assert_allclose(ref.nu_d, R.T @ ref.eta_dot_d_r, atol=1e-15)
            eta = ref.eta_d_n + [0.3, -0.2, 7.0]  # a heading many turns off: unwrapped near psi_d
            got = to_r_frame(eta, ref.eta_P, float(ref.eta_d_r[2]))
            # Tomera (2014) eq. 1 written out: R(psi_P)^T (p - p_P), the heading on the
            # branch within pi of psi_d^r
            want_xy = rot(ref.eta_P[2])[:2, :2].T @ (eta[:2] - ref.eta_P[:2])
            np.testing.assert_allclose(got[:2], want_xy, rtol=0, atol=1e-12)
            assert -math.pi < got[2] - ref.eta_d_r[2] <= math.pi
            turns = (got[2] - (eta[2] - ref.eta_P[2])) / (2 * math.pi)
            assert abs(turns - round(turns)) < 1e-12
            np.testing.assert_array_equal(ref.to_r(eta), got)
            many = to_r_frame(eta[None, :], ref.eta_P[None, :], ref.eta_d_r[2:3])[0]
            np.testing.assert_array_equal(many, got)  # one law for one pose or many
        # complete the leg on its end point
        K = g.waypoints[i + 1]
        assert g.update(g.leg_start_times[-1] + T + 1.0, K)
    assert g.finished and g.legs_completed == len(legs) == len(g.leg_completion_times)
