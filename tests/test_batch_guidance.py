"""Row i of the guidance of N envs equals the same compiled guidance run at N = 1 on row i's
inputs (:class:`Guidance`, the single env's), bit for bit: the plans Tracking-v0 draws, the
paper's 5-leg plan and plans with delays, a step, a zero leg, a turn beyond pi, own limits and
a settle time, driven along noisy trajectories that converge on the reference, with resets by
mask; the handed-out arrays; bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shipgym.guidance import (
    BLUE_LADY_LIMITS,
    Guidance,
    Leg,
    Limits,
    ManoeuvrePlan,
    tomera2014_plan,
)
from shipgym.guidance import batch as B
from shipgym.guidance.batch import BatchedGuidance, BatchedReference

LIM = BLUE_LADY_LIMITS
FIELDS = ("eta_d_r", "eta_dot_d_r", "eta_ddot_d_r", "eta_P", "eta_d_n", "eta_K")
DERIVED = ("nu_d", "nu_dot_d", "eta_dot_d_n")


@pytest.fixture(scope="module")
def draw_plan():
    """The plans of ``TrackingTask(vessel="blue-lady")`` from a seeded generator."""
    from shipgym.envs.task import TrackingTask
    from shipgym.guidance.limits import vessel_limits

    task = TrackingTask("blue-lady")
    assert vessel_limits(task.vessel) == LIM
    rng = np.random.default_rng(2024)
    yield lambda: task.episode_plan(rng)


def _special_plans() -> list[ManoeuvrePlan]:
    slow = Limits.from_dict({**LIM.to_dict(), "sway_speed": 0.02, "yaw_rate": 0.01})
    return [
        tomera2014_plan(),
        # delays, a step, a turn beyond pi (to_r's unwrapping), a zero leg; a settle time
        ManoeuvrePlan(
            legs=(
                Leg(surge=6.0, delay=15.0),
                Leg(sway=3.0, step=True, delay=20.0),
                Leg(yaw=-3.6),
                Leg(),
                Leg(sway=-2.0, limits=slow),
            ),
            settle_time=6.0,
            switch_min_progress=0.5,
        ),
        # the plan's own limits, an astern combined leg, a step without delay, settle time
        ManoeuvrePlan(
            legs=(Leg(surge=-4.0, sway=2.0, yaw=0.3), Leg(yaw=1.0, step=True), Leg(surge=0.5)),
            limits=slow,
            settle_time=3.0,
            switch_distance=0.8,
            switch_heading=math.radians(3.0),
        ),
    ]


def _phase(g: Guidance, t_leg: float) -> str:
    p = g._profiles[g.leg_index]
    tt = t_leg - p.delay
    if p.step or p.duration == 0.0:
        return "step after" if tt >= 0 else "step before"
    if tt <= 0.0:
        return "before"
    if tt >= p.duration:
        return "after"
    if tt < p.t_accel:
        return "accel"
    return "cruise" if tt <= p.t_accel + p.t_cruise else "decel"


def _compare(ref: BatchedReference, singles: list, eta: np.ndarray, err: dict) -> None:
    """Every output of the batched reference equals that of the references ``singles`` of
    the same guidance at N = 1, bit for bit (``to_r``, :func:`to_r_frame`'s batched and
    one-pose forms, to round-off: its largest difference goes to ``err``)."""
    n = len(singles)
    leg = np.array([r.leg for r in singles])
    assert np.array_equal(ref.leg, leg)
    assert np.array_equal(ref.finished, [r.finished for r in singles])
    assert np.array_equal(ref.t_leg, [r.t_leg for r in singles])
    for name in (*FIELDS, *DERIVED):
        b = getattr(ref, name)
        assert b.shape == (n, 3)
        assert np.array_equal(b, np.array([getattr(r, name) for r in singles])), name
    b = ref.to_r(eta)
    s = np.array([r.to_r(e) for r, e in zip(singles, eta, strict=True)])
    err["to_r"] = max(err.get("to_r", 0.0), float(np.abs(b - s).max()))


def test_row_i_of_n_envs_is_the_guidance_of_one_env(draw_plan) -> None:
    """61 drawn Tracking-v0 plans and the three special plans, 1800 control steps of 1 s
    (each env on its own clock), the ship at the reference plus a decaying offset, noise and
    random turns of 2 pi; finished drawn envs reset with new plans (as an autoreset does)
    and a few reset mid-leg: every output of env i equal to that of a Guidance (N = 1) fed
    env i's inputs, bit for bit, every switch at the same instant; switches, finishes, every
    profile phase, a step, the delays and an interrupted settle time all occur."""
    rng = np.random.default_rng(5)
    plans = [draw_plan() for _ in range(61)] + _special_plans()
    n = len(plans)
    special = np.arange(n) >= 61
    starts = rng.normal(0.0, 30.0, (n, 3))
    clock = rng.uniform(-100.0, 100.0, n)  # each env's own time
    g = BatchedGuidance(n, limits=LIM)
    g.reset(plans, starts, t0=clock)
    singles = [Guidance(p, limits=LIM) for p in plans]
    for i, s in enumerate(singles):
        s.reset(starts[i], t0=clock[i])
    sigma = rng.uniform(0.1, 0.35, (n, 1)) * [1.0, 1.0, 0.05]
    sigma[special] = [0.45, 0.45, 0.02]  # the settle times see the conditions break
    offset = rng.normal(0.0, 1.0, (n, 3)) * [3.0, 3.0, 0.1]
    spin = rng.random(n) < 0.3  # these envs' headings jump by multiples of 2 pi
    err: dict[str, float] = {}
    phases: dict[str, int] = {}
    n_switch = n_finish = n_reset = n_broken = 0
    refs = [s.reference(clock[i]) for i, s in enumerate(singles)]
    for k in range(1, 1801):  # the paper plan at the capacity-limited limits: ~1 600 s
        t = clock + k
        t_leg = np.array([r.t_leg for r in refs]) + 1.0
        eta = np.array([r.eta_d_n for r in refs])
        eta += offset * np.exp(-t_leg / 40.0)[:, None] + sigma * rng.standard_normal((n, 3))
        eta[spin, 2] += 2.0 * math.pi * rng.integers(-2, 3, int(spin.sum()))
        held = ~np.isnan(g._st[:, B._HOLD])  # the conditions held at the last step
        switched = g.update(t, eta)
        expect = [s.update(t[i], eta[i]) for i, s in enumerate(singles)]
        assert np.array_equal(switched, expect), f"step {k}"
        n_switch += int(switched.sum())
        n_broken += int((held & np.isnan(g._st[:, B._HOLD]) & ~switched).sum())
        ref = g.reference(t)
        refs = [s.reference(t[i]) for i, s in enumerate(singles)]
        _compare(ref, refs, eta, err)
        for i, s in enumerate(singles):
            name = _phase(s, refs[i].t_leg)
            phases[name] = phases.get(name, 0) + 1
        # autoreset of finished drawn envs (until step 800), and a few reset mid-leg
        done = g.finished & ~special & (k <= 800)
        if k == 300:
            done |= (np.arange(n) % 9 == 4) & ~g.finished & ~special
        if done.any():
            idx = np.nonzero(done)[0]
            n_finish += int(g.finished[idx].sum())
            n_reset += idx.size
            assert g.leg_completion_times() == [list(s.leg_completion_times) for s in singles]
            new = [draw_plan() for _ in idx]
            g.reset(new, eta, t0=t, mask=done)
            for i, p in zip(idx.tolist(), new, strict=True):
                singles[i] = Guidance(p, limits=LIM)
                singles[i].reset(eta[i], t0=t[i])
                refs[i] = singles[i].reference(t[i])
            _compare(g.reference(t), refs, eta, err)
    n_finish += int(g.finished.sum())
    assert err["to_r"] <= 1e-10, err
    # the completion times are the same floats, and the read-outs agree
    assert g.leg_completion_times() == [list(s.leg_completion_times) for s in singles]
    for i, s in enumerate(singles):
        assert g.leg_completion_times(i) == s.leg_completion_times
        assert g.leg_start_times(i) == s.leg_start_times
        assert np.array_equal(g.waypoints(i), s.waypoints)
        assert g.reference_durations(i) == s.reference_durations
    assert np.array_equal(g.legs_completed, [len(s.leg_completion_times) for s in singles])
    assert np.array_equal(g.n_legs, [s.n_legs for s in singles])
    # the branches occurred
    assert g.finished[special].all()  # the paper's plan and the special plans to their ends
    assert n_switch > 150 and n_finish > 40 and n_reset > 50, (n_switch, n_finish, n_reset)
    assert n_broken > 0  # a settle time interrupted by a condition that broke
    for name in ("before", "accel", "cruise", "decel", "after", "step before", "step after"):
        assert phases.get(name, 0) > 10, phases
    profiles = [p for s in singles for p in s._profiles if not p.step and p.duration > 0]
    assert any(p.t_cruise == 0.0 for p in profiles)  # triangles
    assert any(p.t_cruise > 0.0 for p in profiles)  # trapezoids


def test_handed_out_arrays_never_change() -> None:
    """A reference keeps its values across later switches and resets; state is read-only."""
    g = BatchedGuidance(2, limits=LIM)
    g.reset([tomera2014_plan(switch_min_progress=0.0)] * 2, np.zeros((2, 3)))
    ref = g.reference(0.0)  # a scalar time: the same for every env
    P, K, leg = ref.eta_P.copy(), ref.eta_K.copy(), ref.leg.copy()
    at_K = ref.eta_K.copy()
    assert g.update(np.ones(2), at_K).all()
    assert np.array_equal(g.leg, [1, 1]) and np.array_equal(ref.leg, leg)
    assert np.array_equal(ref.eta_P, P) and np.array_equal(ref.eta_K, K)
    g.reset([tomera2014_plan()], np.ones(3), mask=np.array([True, False]))
    assert np.array_equal(ref.eta_P, P) and np.array_equal(g.leg, [0, 1])
    for a in (g.leg, g.finished, ref.eta_P, ref.eta_K, ref.leg, ref.finished):
        with pytest.raises(ValueError):
            a[0] = 0


def test_reset_arguments_per_env_or_per_reset_env() -> None:
    """Plans, start poses and start times may be given per env (the masked ones used), per
    reset env, or one start pose and time for all."""
    plans = [tomera2014_plan(), ManoeuvrePlan(legs=(Leg(surge=3.0),)), tomera2014_plan()]
    starts = np.arange(9.0).reshape(3, 3)
    a, b = BatchedGuidance(3, limits=LIM), BatchedGuidance(3, limits=LIM)
    a.reset(plans, starts, t0=[1.0, 2.0, 3.0])
    b.reset(plans, starts[0])
    m = np.array([False, True, True])
    b.reset(plans, starts, t0=np.array([1.0, 2.0, 3.0]), mask=m)  # per env
    b.reset(plans[1:], starts[1:], t0=[2.0, 3.0], mask=m)  # per reset env
    for i in (1, 2):
        assert np.array_equal(a.waypoints(i), b.waypoints(i))
        assert a.leg_start_times(i) == b.leg_start_times(i)
    assert b.leg_start_times(0) == (0.0,) and np.array_equal(b.waypoints(0)[0], starts[0])
    empty = np.zeros(3, dtype=bool)
    b.reset([], np.zeros((3, 3)), mask=empty)  # nothing to reset
    assert b.leg_start_times(1) == (2.0,)


def test_bad_input_raises_clear_errors() -> None:
    with pytest.raises(ValueError, match="n must be"):
        BatchedGuidance(0)
    with pytest.raises(ValueError, match="n must be"):
        BatchedGuidance(True)
    with pytest.raises(TypeError, match="limits"):
        BatchedGuidance(2, limits={"surge_speed": 1.0})
    g = BatchedGuidance(3, limits=LIM)
    with pytest.raises(RuntimeError, match="reset"):
        g.update(np.zeros(3), np.zeros((3, 3)))
    plan = tomera2014_plan()
    g.reset([plan], np.zeros((3, 3)), mask=np.array([True, False, False]))
    with pytest.raises(RuntimeError, match=r"never reset: envs \[1, 2\]"):
        g.reference(np.zeros(3))
    with pytest.raises(ValueError, match="one plan per reset env"):
        g.reset([plan, plan], np.zeros((3, 3)))
    with pytest.raises(TypeError, match="ManoeuvrePlan"):
        g.reset([plan, plan, "tomera2014"], np.zeros((3, 3)))
    with pytest.raises(TypeError, match="sequence"):
        g.reset(plan, np.zeros((3, 3)))
    with pytest.raises(ValueError, match="eta_start"):
        g.reset([plan] * 3, np.zeros((3, 2)))
    with pytest.raises(ValueError, match="eta_start must be finite"):
        g.reset([plan] * 3, np.full((3, 3), np.nan))
    with pytest.raises(ValueError, match="t0"):
        g.reset([plan] * 3, np.zeros((3, 3)), t0=np.zeros(2))
    with pytest.raises(ValueError, match="t0 must be finite"):
        g.reset([plan] * 3, np.zeros((3, 3)), t0=math.inf)
    with pytest.raises(ValueError, match="mask"):
        g.reset([plan] * 3, np.zeros((3, 3)), mask=[1, 0, 1])
    with pytest.raises(ValueError, match="mask"):
        g.reset([plan] * 3, np.zeros((3, 3)), mask=np.ones(4, dtype=bool))
    with pytest.raises(TypeError, match="limits"):  # no limits anywhere, as Guidance
        BatchedGuidance(3).reset([plan] * 3, np.zeros((3, 3)))
    # a failing reset changes nothing
    before = g.waypoints(0).copy()
    with pytest.raises(TypeError):
        g.reset([ManoeuvrePlan(legs=(Leg(surge=9.0),)), plan, None], np.ones((3, 3)))
    assert np.array_equal(g.waypoints(0), before)
    g.reset([plan] * 3, np.zeros((3, 3)))
    with pytest.raises(ValueError, match=r"t must have shape \(3,\)"):
        g.update(np.zeros(4), np.zeros((3, 3)))
    with pytest.raises(ValueError, match=r"eta_n must have shape \(3, 3\)"):
        g.update(np.zeros(3), np.zeros((3, 2)))
    with pytest.raises(ValueError, match=r"eta_n must have shape"):
        g.update(np.zeros(3), np.zeros(3))
    with pytest.raises(ValueError, match="env 1"):
        g.update(np.zeros(3), np.array([[0.0, 0, 0], [np.nan, 0, 0], [0, 0, 0]]))
    with pytest.raises(ValueError, match="env 2"):
        g.update(np.array([0.0, 0.0, np.inf]), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="t must have shape"):
        g.reference(np.zeros((3, 1)))
    with pytest.raises(ValueError, match=r"eta_n must have shape \(3, 3\)"):
        g.reference(np.zeros(3)).to_r(np.zeros((2, 3)))


def test_a_finished_env_ignores_its_pose_as_guidance_does() -> None:
    """Once finished, an env never switches again and (as Guidance.update) does not check
    its pose; its reference stays at the last K."""
    plan = ManoeuvrePlan(legs=(Leg(surge=2.0),), switch_min_progress=0.0)
    g = BatchedGuidance(2, limits=LIM)
    g.reset([plan, plan], np.zeros((2, 3)))
    s = Guidance(plan, limits=LIM)
    s.reset(np.zeros(3))
    K = g.reference(np.zeros(2)).eta_K.copy()
    assert np.array_equal(g.update(np.ones(2), K), [True, True])
    assert s.update(1.0, K[0]) and s.finished
    assert np.array_equal(g.finished, [True, True]) and np.array_equal(g.legs_completed, [1, 1])
    nan_pose = np.full((2, 3), np.nan)
    assert not g.update(np.full(2, 2.0), nan_pose).any()
    assert not s.update(2.0, nan_pose[0])
    ref = g.reference(np.full(2, 5000.0))
    assert np.allclose(ref.eta_d_n, K, rtol=0.0, atol=1e-12) and not np.any(ref.eta_dot_d_r)


def test_a_longer_plan_at_a_reset_pads_the_tables() -> None:
    """Envs reset with 1-leg plans, then one of them with the paper's 5 legs mid-run: the
    other env's plan goes on unchanged, and both follow their Guidance to the end."""
    plans = [ManoeuvrePlan(legs=(Leg(surge=3.0),)), ManoeuvrePlan(legs=(Leg(sway=2.0),))]
    g = BatchedGuidance(2, limits=LIM)
    g.reset(plans, np.zeros((2, 3)), t0=[0.0, -300.0])
    singles = [Guidance(p, limits=LIM) for p in plans]
    singles[0].reset(np.zeros(3), t0=0.0)
    singles[1].reset(np.zeros(3), t0=-300.0)
    err: dict[str, float] = {}
    eta = np.zeros((2, 3))
    for k in range(1, 1800):  # the paper plan from step 40: ~1 600 s
        t = np.array([k, k - 300.0])
        if k == 40:  # env 0 mid-leg: a longer plan than the tables hold
            g.reset([tomera2014_plan()], eta, t0=t, mask=np.array([True, False]))
            singles[0] = Guidance(tomera2014_plan(), limits=LIM)
            singles[0].reset(eta[0], t0=t[0])
        switched = g.update(t, eta)
        assert np.array_equal(switched, [s.update(t[i], eta[i]) for i, s in enumerate(singles)])
        refs = [s.reference(t[i]) for i, s in enumerate(singles)]
        _compare(g.reference(t), refs, eta, err)
        eta = np.array([r.eta_d_n for r in refs])  # the ship on the reference
    assert err["to_r"] <= 1e-10, err
    assert g.finished.all() and np.array_equal(g.legs_completed, [5, 1])
    assert g.leg_completion_times() == [list(s.leg_completion_times) for s in singles]


def test_a_guidance_pickles_and_goes_on_where_it_was() -> None:
    """A Guidance (an env's part) pickles with its state; the copy and the original then
    give the same outputs."""
    import pickle

    g = Guidance(tomera2014_plan(switch_min_progress=0.0), limits=LIM)
    g.reset(np.zeros(3), t0=2.0)
    assert g.update(3.0, g.waypoints[1])
    h = pickle.loads(pickle.dumps(g))
    assert h.leg_index == g.leg_index == 1 and h.leg_start_times == g.leg_start_times
    for t in (3.0, 50.0, 400.0):
        assert np.array_equal(h.reference(t).eta_d_n, g.reference(t).eta_d_n)
        assert h.update(t, g.waypoints[2]) == g.update(t, g.waypoints[2])
