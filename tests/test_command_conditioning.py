"""Command conditioning of the DP stack (shipgym.controllers.conditioning and the PID's
velocity filter): each part against an independent expectation, then the harbour bound."""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest

from shipgym.controllers import MultivariablePID
from shipgym.controllers.actuation import make_allocator
from shipgym.controllers.conditioning import ReversalHysteresis
from shipgym.dynamics.vessel import VesselError, load_vessel

BL = load_vessel("blue-lady")


# ---- reversal hysteresis -----------------------------------------------------------------------
def test_reversal_hysteresis_holds_small_reversals_at_zero_thrust():
    alloc = make_allocator(BL)
    h = ReversalHysteresis(BL.actuators, [40.0, 0.0, 0.0], idle=0.0)  # no idle: stopped
    cases = [  # requested X (N), expected delivered X (N)
        (50.0, 50.0),  # sets the direction: ahead
        (-5.0, 0.0),  # astern below 40 N: held at zero
        (-39.0, 0.0),
        (20.0, 20.0),  # ahead again: passed (its side)
        (-45.0, -45.0),  # beyond 40 N: a reversal
        (10.0, 0.0),  # now ahead is the other side
        (0.0, 0.0),
        (-3.0, -3.0),  # its side
    ]
    for x, want in cases:
        tau = np.array([x, 12.0, -30.0])
        raw = alloc(tau, None)
        out = h(raw)
        assert out.force[0] == pytest.approx(want, abs=1e-12), x
        assert out.tau[0] == pytest.approx(want, abs=1e-12)
        # what is held back is reported as not delivered: the anti-windup sees it
        assert out.tau_error[0] == pytest.approx(x - want, abs=1e-12)
        # the command delivers the force (Tomera 2014 eq. 8: F = k1 |n| n)
        main = BL.actuators.actuators[0]
        n = out.command[0]
        assert main.k_ahead * abs(n) * n == pytest.approx(want, abs=1e-9)
        # the tunnels are untouched
        np.testing.assert_array_equal(out.command[1:], raw.command[1:])
        np.testing.assert_array_equal(out.tau[1:], raw.tau[1:])
    h.reset()
    assert h(alloc([-5.0, 0, 0], None)).force[0] == pytest.approx(-5.0)  # no direction yet


def test_reversal_hysteresis_on_a_wls_vessel_and_a_no_op_on_azimuths():
    sh = load_vessel("star-hercules")
    acts = sh.actuators
    alloc = make_allocator(sh)
    cap = acts.capacity()
    thr = [0.05 * cap[0]] + [0.0] * (len(acts) - 1)
    h = ReversalHysteresis(acts, thr, idle=0.0)
    assert h.active
    state = np.zeros(acts.n_channels)
    h(alloc([0.3 * cap[0], 0.0, 0.0], state))
    raw = alloc([-0.01 * cap[0], 0.0, 0.0], state)
    assert raw.force[0] < 0.0 and -raw.force[0] < thr[0]
    out = h(raw)
    assert out.force[0] == 0.0
    # delivered tau recomputed independently from the thrusts: sum of B_i F_i
    B = []
    for a in acts.actuators:
        c, s = a.direction
        x, y, _ = a.position
        B.append([c, s, x * s - y * c])
    np.testing.assert_allclose(np.array(B).T @ out.force, out.tau, atol=1e-9)
    np.testing.assert_allclose(out.tau + out.tau_error, raw.tau + raw.tau_error, atol=1e-9)
    wl = load_vessel("wimpey-sealab")  # azimuths only: nothing to condition
    assert not ReversalHysteresis(wl.actuators, [30.0] * len(wl.actuators)).active


def test_a_running_propeller_idles_instead_of_stopping():
    """Issue 31: inside the hysteresis (and below the idle thrust on its own side) a running
    propeller idles at IDLE_FRACTION of its range on its running side, never at zero."""
    from shipgym.controllers.conditioning import IDLE_FRACTION

    alloc = make_allocator(BL)
    main = BL.actuators.actuators[0]
    n_ahead, n_astern = IDLE_FRACTION * main.upper, IDLE_FRACTION * main.lower
    f_ahead, f_astern = main.k_ahead * n_ahead**2, -main.k_astern * n_astern**2
    assert n_ahead == pytest.approx(24.0) and f_ahead == pytest.approx(1.1283264)
    h = ReversalHysteresis(BL.actuators, [40.0, 0.0, 0.0])
    cases = [  # requested X (N), expected delivered X (N), expected command (rpm)
        (50.0, 50.0, None),  # sets the direction: ahead
        (-5.0, f_ahead, n_ahead),  # astern inside 40 N: idles ahead
        (0.5, f_ahead, n_ahead),  # ahead below the idle thrust: idles
        (0.0, f_ahead, n_ahead),
        (20.0, 20.0, None),
        (-45.0, -45.0, None),  # beyond 40 N (no dwell without dt): a reversal
        (10.0, f_astern, n_astern),  # ahead is now the other side: idles astern
    ]
    for x, want, cmd in cases:
        out = h(alloc(np.array([x, 0.0, 0.0]), None))
        assert out.force[0] == pytest.approx(want, abs=1e-12), x
        assert out.tau[0] == pytest.approx(want, abs=1e-12)
        assert out.tau_error[0] == pytest.approx(x - want, abs=1e-12)
        if cmd is not None:
            assert out.command[0] == pytest.approx(cmd)
        k = main.k_ahead if out.command[0] >= 0 else main.k_astern
        assert k * abs(out.command[0]) * out.command[0] == pytest.approx(want, abs=1e-9)
    with pytest.raises(ValueError, match="idle thrust"):
        ReversalHysteresis(BL.actuators, [1.0, 0.0, 0.0])  # 1.13 N idle above 1 N
    for bad in (-0.1, 1.0, True, float("nan")):
        with pytest.raises(ValueError, match="idle"):
            ReversalHysteresis(BL.actuators, [40.0, 0.0, 0.0], idle=bad)


def test_a_reversal_waits_for_the_low_pass():
    """With a control period the request must be past F_h on the other side and so must its
    low-pass (implicit Euler, a = dt / (T_r + dt)): a short excursion does not reverse, a
    sustained one does after about T_r."""
    alloc = make_allocator(BL)
    h = ReversalHysteresis(BL.actuators, [40.0, 0.0, 0.0], dt=1.0, filter_time=3.0)
    a = 1.0 / 4.0
    want = [50.0, 50.0, -60.0, -60.0, -10.0, -60.0, -60.0, -60.0, -60.0, -60.0]
    got = [float(h(alloc([x, 0.0, 0.0], None)).force[0]) for x in want]
    low, ahead, rev = 0.0, True, []
    for x in want:  # the law written out
        low += a * (x - low)
        if ahead and x < -40.0 and low < -40.0:
            ahead = False
        rev.append(not ahead)
    assert [g < 0 for g in got] == rev
    assert rev.index(True) == 7 and got[7] == pytest.approx(-60.0)  # low-pass -40.2 N
    assert got[3] > 0 and got[4] > 0  # held (idling ahead) while the low-pass lags
    for bad in ({"dt": 0.0}, {"dt": float("inf")}, {"dt": True},
                {"dt": 1.0, "filter_time": -1.0}):  # fmt: skip
        with pytest.raises(ValueError, match="dt|filter_time"):
            ReversalHysteresis(BL.actuators, [40.0, 0.0, 0.0], **bad)


def test_reversal_hysteresis_refuses_bad_thresholds():
    with pytest.raises(ValueError, match="one force"):
        ReversalHysteresis(BL.actuators, [1.0])
    with pytest.raises(ValueError, match=">= 0"):
        ReversalHysteresis(BL.actuators, [-1.0, 0.0, 0.0])


_BAD_KEYS = [  # (the vessel file's text, its replacement, the key the error names)
    (
        'reversal_threshold = { value = [50.0, 0.0, 0.0], unit = "N"',
        'reversal_threshold = { value = [50.0, 0.0], unit = "N"',
        "reversal_threshold",
    ),
    ("velocity_filter = { value = [20.0,", "velocity_filter = { value = [-1.0,", "velocity_filter"),
    (
        "velocity_filter_model_based = { value = [8.0,",
        "velocity_filter_model_based = { value = [-8.0,",
        "velocity_filter_model_based",
    ),
    ("command_filter = { value = [1.0,", "command_filter = { value = [-1.0,", "command_filter"),
]


@pytest.mark.parametrize(("old", "new", "key"), _BAD_KEYS, ids=[k for *_, k in _BAD_KEYS])
def test_vessel_package_keys_are_checked(tmp_path, old, new, key):
    import shipgym.assets

    base = __import__("pathlib").Path(shipgym.assets.__file__).parent / "mjcf" / "blue_lady"
    pkg = tmp_path / "bl"
    shutil.copytree(base, pkg)
    text = (pkg / "vessel.toml").read_text()
    bad = text.replace(old, new, 1)
    assert bad != text
    (pkg / "vessel.toml").write_text(bad)
    with pytest.raises(VesselError, match=key):
        load_vessel(pkg)


# ---- the PID's velocity filter -----------------------------------------------------------------
def _pid(T_f, M=None, D=None):
    d = BL.design
    return MultivariablePID(
        "smooth",
        M=d.M if M is None else M,
        D_L=d.D_L if D is None else D,
        dt=1.0,
        integral_limit=np.inf,
        velocity_filter=T_f,
    )


def test_with_nothing_delivered_the_filter_is_the_first_order_low_pass():
    # nothing delivered (tau_error = tau) and no damping: the prediction is the last
    # filtered velocity, so a velocity step is low-passed by 1 / (T_f s + 1), sampled
    # exactly: nu_f(k) = 1 - exp(-k dt / T_f) (the first sample starts the filter)
    T = (4.0, 10.0, 25.0)
    ctrl = _pid(T, D=np.zeros((3, 3)))
    tau = ctrl([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    for k in range(1, 40):
        tau = ctrl([0.0, 0.0, 0.0], [0.1, 0.2, 0.01], [0.0, 0.0, 0.0], saturated=tau)
        want = np.array([0.1, 0.2, 0.01]) * (1.0 - np.exp(-k / np.array(T)))
        np.testing.assert_allclose(ctrl.filtered_velocity, want, rtol=1e-9, atol=1e-12)


def test_the_filter_does_not_lag_what_the_model_explains():
    """A free decay of the design model M nu_dot + D_L nu = 0 (solved by scipy): the
    filtered velocity follows it within the prediction's Euler error, while a plain
    low-pass of the same T_f would lag by ~T_f (here: ~100x more error)."""
    from scipy.linalg import expm

    d = BL.design
    A = -np.linalg.solve(d.M, d.D_L)
    nu0 = np.array([0.2, 0.05, 0.01])
    ctrl = _pid((20.0, 20.0, 30.0))
    err_f, err_lp = 0.0, 0.0
    lp = nu0.copy()
    alpha = -np.expm1(-1.0 / np.array([20.0, 20.0, 30.0]))
    tau = None
    for k in range(200):
        nu = expm(A * k) @ nu0
        # nothing of the controller's force is delivered (tau_error = tau): a free decay
        tau = ctrl([0.0, 0.0, 0.0], nu, [0.0, 0.0, 0.0], saturated=tau)
        lp = lp + alpha * (nu - lp)
        err_f = max(err_f, float(np.abs(ctrl.filtered_velocity - nu).max()))
        err_lp = max(err_lp, float(np.abs(lp - nu).max()))
    assert err_f < 2e-5
    assert err_lp > 50 * err_f


def test_zero_time_constants_are_the_unfiltered_law():
    rng = np.random.default_rng(3)
    a, b = _pid(0.0), _pid((0.0, 0.0, 0.0))
    c = MultivariablePID("smooth", M=BL.design.M, D_L=BL.design.D_L, dt=1.0, integral_limit=np.inf)
    for _ in range(20):
        e, nu = rng.normal(size=3), rng.normal(size=3) * 0.1
        ta, tb, tc = (x(e, nu, [0.0, 0.0, 0.0]) for x in (a, b, c))
        np.testing.assert_array_equal(ta, tc)
        np.testing.assert_array_equal(tb, tc)
    with pytest.raises(ValueError, match="velocity_filter"):
        _pid(-1.0)


# ---- the harbour bound (issue acceptance, one seed; the bench runs seeds 0-9) -----------------
@pytest.mark.parametrize("observer", ["kbf", "dkf"])
def test_harbour_commands_meet_the_chatter_bound_and_raw_does_not(observer):
    from shipgym.runner import run_episode

    res = run_episode("harbour", controller="pid-smooth", observer=observer, seed=0, wind="3@300")
    raw = run_episode(
        "harbour", controller="pid-smooth-raw", observer=observer, seed=0, wind="3@300"
    )
    assert res["completed"] and not res["quay_contact"]
    assert res["reversals_per_min"][0] <= 1.0
    assert max(res["limit_fraction"]) <= 0.10
    assert max(res["hf_variance_fraction"]) < 0.25 or observer == "dkf"
    assert res["J_c"] <= 1.5 * 0.158
    # the unconditioned stack chatters (so the bound is not met by any controller)
    assert raw["reversals_per_min"][0] > 5.0 and max(raw["limit_fraction"]) > 0.2
    assert math.isfinite(res["travel_per_min"][0])


# ---- the filter matched to the velocity source ---------------------------------------------------
@pytest.mark.parametrize(
    ("observer", "source", "key"),
    [(None, "truth", None), ("kbf", "kinematic", "velocity_filter"),
     ("dkf", "kinematic", "velocity_filter"), ("ekf", "model", "velocity_filter_model_based")],
)  # fmt: skip
def test_the_controller_filters_the_velocity_for_its_source(observer, source, key):
    """The env's controller is made for its observer: no filter on the true state, the
    kinematic time constants with kbf/dkf, the model-based ones with the EKF; the raw
    controller never filters."""
    import shipgym

    env = shipgym.make("harbour", observer=observer, controller="pid-smooth")
    raw = shipgym.make("harbour", observer=observer, controller="pid-smooth-raw")
    try:
        assert env.unwrapped.controller.velocity_source == source
        want = (0.0, 0.0, 0.0) if key is None else tuple(BL.control[key])
        ctrl = env.unwrapped.controller.pid
        assert tuple(ctrl.velocity_filter) == want
        cmd = None if key is None else key.replace("velocity", "command")
        assert tuple(ctrl.command_filter) == ((0.0,) * 3 if cmd is None else tuple(BL.control[cmd]))
        assert tuple(raw.unwrapped.controller.pid.velocity_filter) == (0.0, 0.0, 0.0)
        assert tuple(raw.unwrapped.controller.pid.command_filter) == (0.0, 0.0, 0.0)
    finally:
        env.close()
        raw.close()
    assert BL.control["velocity_filter"] != BL.control["velocity_filter_model_based"]


def test_unknown_velocity_source_is_refused():
    from shipgym.controllers.pid import vessel_pid

    with pytest.raises(ValueError, match="velocity_source"):
        vessel_pid(BL, "smooth", 0.7, 1.0, conditioned=True, velocity_source="gps")


def test_the_command_filter_is_the_sampled_first_order_low_pass():
    """A step of the law's output (no integral, no velocity) through the output filter:
    ``tau_k = c (1 - (1 - b)^k)`` with ``b = 1 - exp(-dt / T_c)``, per DOF; T_c = 0 passes."""
    from shipgym.controllers.pid import PIDGains

    d = BL.design
    g = PIDGains(K_P=(0.01, 0.02, 0.03), K_I=0.0, K_D=0.0)
    T_c = (2.0, 5.0, 0.0)
    pid = MultivariablePID(g, M=d.M, D_L=d.D_L, dt=1.0, integral_limit=np.inf, command_filter=T_c)
    law = MultivariablePID(g, M=d.M, D_L=d.D_L, dt=1.0, integral_limit=np.inf)
    zero = np.zeros(3)
    np.testing.assert_array_equal(pid(zero, zero, zero), zero)  # starts at the first output
    step = np.array([1.0, -2.0, 0.1])
    c = law(step, zero, zero)
    for k in range(1, 30):
        out = pid(step, zero, zero)
        for j, t in enumerate(T_c):
            want = c[j] if t == 0.0 else c[j] * (1.0 - math.exp(-k / t))
            assert out[j] == pytest.approx(want, rel=1e-12, abs=1e-12)
    pid.reset()
    np.testing.assert_array_equal(pid(step, zero, zero), c)  # restarts at the law


# ---- the same conditioning on a pure policy's commands (condition_commands=True) -----------
def _reference_conditioning(actions, f_h, idle, a_lp, k, upper, lower):
    """The documented rule of BatchedCommandConditioning for the main propeller alone, written
    out scalar: bollard thrust k c|c| of the command, a running direction, the low-pass of the
    thrust deciding a reversal, idle on the running side otherwise."""
    d, low, out = 0.0, 0.0, []
    for a in actions:
        c = a * upper if a >= 0 else a * -lower
        f = k * c * abs(c)
        low += a_lp * (f - low)
        f_idle = k * (idle * upper) ** 2 if d > 0 else -k * (idle * lower) ** 2
        if d == 0.0:
            d = float(np.sign(f))
            out.append(a)
        elif f * d >= 0.0:
            out.append(a if abs(f) >= abs(f_idle) else d * idle)
        elif abs(f) > f_h and abs(low) > f_h and np.sign(low) == np.sign(f):
            d = -d
            out.append(a)
        else:
            out.append(d * idle)
    return np.array(out)


def test_policy_command_conditioning_is_the_documented_rule():
    from shipgym.controllers.conditioning import IDLE_FRACTION, BatchedCommandConditioning

    rng = np.random.default_rng(4)
    n, steps, dt = 5, 300, 1.0
    cond = BatchedCommandConditioning(BL.actuators, [50.0, 0.0, 0.0], n, dt=dt)
    walk = np.clip(np.cumsum(rng.normal(0, 0.15, (steps, n)), axis=0), -1, 1)  # main channel
    lo, hi = BL.actuators.lower, BL.actuators.upper
    got = np.empty((steps, n))
    held_any = 0
    for t in range(steps):
        a = np.column_stack([walk[t], rng.uniform(-1, 1, (n, 2))])
        c = np.where(a >= 0, a * hi, a * -lo)
        held = cond(c, a)
        assert not held[:, 1:].any()  # the tunnels have no threshold: never held
        np.testing.assert_allclose(
            c[:, 0], np.where(a[:, 0] >= 0, a[:, 0] * hi[0], a[:, 0] * -lo[0])
        )
        got[t] = a[:, 0]
        held_any += int(held[:, 0].sum())
    a_lp = dt / (4.0 + dt)
    for e in range(n):
        want = _reference_conditioning(
            walk[:, e], 50.0, IDLE_FRACTION, a_lp, BL.actuators.actuators[0].k_ahead, hi[0], lo[0]
        )
        np.testing.assert_allclose(got[:, e], want, rtol=0, atol=1e-12)
    assert held_any > 50
    # the command only changes sign through a reversal past 50 N: at most as often as the
    # raw walk crosses 0.8 of astern and 0.33 of ahead, far less than it crosses zero
    crossings = np.sum(got[1:] * got[:-1] < 0)
    assert crossings < np.sum(walk[1:] * walk[:-1] < 0) / 3


def test_condition_commands_in_the_env_and_its_refusals():
    import gymnasium as gym

    import shipgym  # noqa: F401

    env = gym.make("shipgym/BlueLadyTracking-v0", condition_commands=True, wind=None)
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([0.5, 0, 0], np.float32))  # ahead: sets the direction
    _, _, _, _, info = env.step(np.array([-0.3, 0, 0], np.float32))  # 28 N astern < 50 N: idles
    assert info["action_clipped"].tolist() == [True, False, False]
    assert info["command"][0] == pytest.approx(0.05 * 480.0)  # the idle, 24 rpm ahead
    with pytest.raises(ValueError, match="conditions its own"):
        gym.make("shipgym/BlueLadyTracking-v0", condition_commands=True, controller="pid")
    with pytest.raises(ValueError, match="reversal threshold"):
        gym.make("shipgym/Tracking-v0", vessel="star-hercules", condition_commands=True)
    with pytest.raises(TypeError, match="True or False"):
        gym.make("shipgym/BlueLadyTracking-v0", condition_commands="yes")


def test_a_policy_trained_with_conditioning_runs_only_with_it():
    import gymnasium as gym

    import shipgym  # noqa: F401
    from shipgym.controllers.learned import ModelMetadata, _check_stack, policy_env_kwargs

    meta = ModelMetadata(algorithm="ppo", env_id="shipgym/BlueLadyTracking-v0",
                         env_kwargs={"condition_commands": True, "max_legs": 2})  # fmt: skip
    assert policy_env_kwargs(meta.env_kwargs) == {"condition_commands": True}
    with pytest.raises(ValueError, match="condition_commands=True"):
        _check_stack(gym.make("shipgym/BlueLadyHarbour-v0"), meta)
    _check_stack(gym.make("shipgym/BlueLadyHarbour-v0", condition_commands=True), meta)
