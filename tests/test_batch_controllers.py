"""The DP controller's laws over N envs: row i of a batch equals the law at N = 1, bit for bit.

The PID (Tomera 2014 eq. 23), the closed-form allocation (eqs. 12, 25-27) and the reversal
hysteresis are each one compiled law over a leading axis of envs; the single env's controller
wrapper runs them at N = 1 (:class:`~shipgym.controllers.pid.MultivariablePID`,
:func:`~shipgym.controllers.actuation.make_allocator`,
:class:`~shipgym.controllers.conditioning.ReversalHysteresis`). Each test runs a batch with
different inputs per row, masks, leg switches and resets against one N = 1 law per row on
that row's inputs (``np.array_equal``), and asserts that the branches it is meant to cover
(allocation saturation in both directions, conditional integration, the integral clamp, frame
changes, partial resets, held reversals) did occur. Independent references of the laws:
tests/test_pid.py (python-control), tests/test_allocation.py (SciPy's lsq_linear).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import lsq_linear

import shipgym
from shipgym.controllers import MultivariablePID, PIDGains, allocate, allocate_inverse
from shipgym.controllers.actuation import fixed3_parameters, make_allocator
from shipgym.controllers.allocation import default_weights
from shipgym.controllers.batch import (
    BATCHED_CONTROLLERS,
    CONTROLLERS,
    BatchedAllocation,
    BatchedPID,
    apply_residual,
    batched_dp_controller,
    controller_spec,
)
from shipgym.controllers.conditioning import ReversalHysteresis, reversal_threshold
from shipgym.controllers.pid import vessel_pid
from shipgym.dynamics.vessel import load_vessel

VESSELS = shipgym.vessels()


def _same(a, b, scale=None):
    """Bit for bit (``np.array_equal``; ``scale`` is ignored)."""
    return np.array_equal(np.asarray(a, float), np.asarray(b, float))


def _unsupported(vessel):
    """Why the batched controller does not run ``vessel`` (``None``: it does)."""
    try:
        BatchedAllocation(vessel, "constrained")
    except NotImplementedError as e:
        return str(e)
    except ValueError as e:
        return f"{vessel.name}: the scalar allocation fails too ({e})"
    return None


class _Errors:
    """Random error trajectories per env: a biased random walk of the pose error around a
    random reference, with bias sizes spread from small (integral builds, clamp) to large
    (allocation saturated, conditional integration)."""

    def __init__(self, n, seed):
        self.rng = np.random.default_rng(seed)
        r = self.rng
        self.n = n
        self.err = r.normal(0.0, 0.5, (n, 3)) * [1.0, 1.0, 0.05]
        self.bias = np.exp(r.uniform(np.log(1e-3), np.log(0.3), (n, 3))) * r.choice(
            [-1.0, 1.0], (n, 3)
        )
        self.bias[:, 2] *= 0.05

    def step(self, k):
        r, n = self.rng, self.n
        self.err += self.bias + r.normal(0.0, 0.05, (n, 3)) * [1.0, 1.0, 0.01]
        self.err = np.clip(self.err, -8.0, 8.0)
        eta_d = r.normal(0.0, 3.0, (n, 3))
        eta = eta_d + self.err
        nu = r.normal(0.0, 0.1, (n, 3)) * [1.0, 1.0, 0.01]
        if k % 3 == 0:  # the defaults (no reference motion)
            return eta, nu, eta_d, None, None
        vd = r.normal(0.0, 0.1, (n, 3)) * [1.0, 1.0, 0.01]
        ad = r.normal(0.0, 0.01, (n, 3)) * [1.0, 1.0, 0.001]
        return eta, nu, eta_d, vd, ad


def _integral_force(pid, xi, psi):
    """``|M R^T(psi) K_I xi|`` per env (n, 3): the quantity the clamp bounds."""
    q = np.asarray(pid.gains.K_I) * xi
    c, s = np.cos(psi), np.sin(psi)
    b = np.stack([c * q[:, 0] + s * q[:, 1], -s * q[:, 0] + c * q[:, 1], q[:, 2]], -1)
    return np.abs(b @ np.asarray(pid.M).T)


def _names(vessel):
    return [
        name
        for name in BATCHED_CONTROLLERS
        if name != "pid-seed" or "seed" in vessel.control.get("pid_presets", ())
    ]


# ---- the controller and its allocation, env by env, against the wrapper's N = 1 stack --------
@pytest.mark.parametrize("vessel_name", sorted(VESSELS))
def test_row_i_of_the_batched_stack_is_the_n1_stack(vessel_name):
    vessel = VESSELS[vessel_name]
    why = _unsupported(vessel)
    if why:
        pytest.skip(why)
    n, steps, dt = 32, 240, 1.0
    acts = vessel.actuators
    for name in _names(vessel):
        spec = controller_spec(name)
        scalars = [spec.factory(vessel, dt) for _ in range(n)]
        alloc_s = make_allocator(vessel, spec.allocation, dt)
        # the wrapper's conditioning after the allocation (none where the vessel sets none)
        hyst = [
            ReversalHysteresis(acts, reversal_threshold(vessel), dt=dt)
            if spec.conditioned
            else None
            for _ in range(n)
        ]
        batch = batched_dp_controller(name, vessel, n, dt)
        shadow = BatchedPID.from_scalar(scalars[0], n)  # integrates unconditionally
        tau_err = [None] * n
        errs = _Errors(n, seed=list(BATCHED_CONTROLLERS).index(name))
        seen = dict(cut_pos=0, cut_neg=0, windup=0, clamp=0, switch=0, reset=0, edge=0)
        conditioned = spec.conditioned and hyst[0].active
        held = 0
        for k in range(steps):
            eta, nu, eta_d, vd, ad = errs.step(k)
            tau_b, al_b, act_b = batch(eta, nu, eta_d, vd, ad, state=np.zeros((n, acts.n_channels)))
            shadow(eta, nu, eta_d, vd, ad)
            for i in range(n):
                row = (None if vd is None else vd[i], None if ad is None else ad[i])
                tau = scalars[i](eta[i], nu[i], eta_d[i], *row, saturated=tau_err[i])
                al = alloc_s(tau, np.zeros(acts.n_channels))
                if hyst[i] is not None:
                    al_raw, al = al, hyst[i](al)
                    held += int(al is not al_raw)
                tau_err[i] = al.tau_error
                scale = float(np.abs(tau).max()) + 1.0
                assert _same(tau_b[i], tau, scale), (name, k, i, tau_b[i], tau)
                assert _same(al_b.command[i], al.command), (name, k, i)
                assert _same(al_b.force[i], al.force, scale), (name, k, i)
                assert _same(al_b.tau[i], al.tau, scale), (name, k, i)
                assert _same(al_b.tau_error[i], al.tau_error, scale), (name, k, i)
                assert np.array_equal(al_b.saturated[i], al.saturated), (name, k, i)
                assert _same(act_b[i], acts.command_to_action(al.command)), (name, k, i)
            xi_s = np.array([c.integral for c in scalars])
            assert _same(batch.pid.integral, xi_s, 1.0 + float(np.abs(xi_s).max()))
            # branches
            te = al_b.tau_error
            seen["cut_pos"] += int((te > 1e-6).sum())
            seen["cut_neg"] += int((te < -1e-6).sum())
            seen["edge"] += int((al_b.saturated[:, 1:].any(axis=1) & ~al_b.saturated[:, 0]).sum())
            if not np.array_equal(shadow.integral, batch.pid.integral):
                seen["windup"] += 1
            lim = np.asarray(batch.pid.integral_limit)
            f = _integral_force(batch.pid, batch.pid.integral, eta[:, 2])
            seen["clamp"] += int((f >= lim * (1.0 - 1e-9)).any(axis=1).sum())
            if k % 37 == 36:  # leg switches of some envs
                m = errs.rng.random(n) < 0.4
                dpsi = errs.rng.uniform(-np.pi, np.pi, n)
                batch.change_frame(dpsi, m)
                shadow.change_frame(dpsi, m)
                for i in np.flatnonzero(m):
                    scalars[i].change_frame(float(dpsi[i]))
                seen["switch"] += int(m.sum())
            if k % 61 == 60:  # a few envs start a new episode
                m = errs.rng.random(n) < 0.25
                batch.reset(m)
                shadow.reset(m)
                for i in np.flatnonzero(m):
                    scalars[i].reset()
                    if hyst[i] is not None:
                        hyst[i].reset()
                    tau_err[i] = None
                seen["reset"] += int(m.sum())
        # every branch of the closed form; an iterative allocation's own branches are its
        # solver's (tests/test_allocation_wls.py, test_allocation_azimuth.py)
        need = (
            seen
            if fixed3_parameters(acts) is not None
            else {k: seen[k] for k in ("cut_pos", "cut_neg", "windup", "switch", "reset")}
        )
        assert all(v > 0 for v in need.values()), (name, seen)
        assert held > 0 or not conditioned, (name, "the reversal hysteresis never held")


def test_batched_pid_rows_general_model_bool_flags_and_a_zero_integral_gain():
    """Rows against N = 1 with a full M and D_L, K_I = 0 in surge (the ``kI > 0`` branches and
    the unit rotation scale of change_frame), saturation as floats, booleans or None."""
    rng = np.random.default_rng(7)
    M = np.array([[2.0e4, 0.0, 0.0], [0.0, 2.5e4, 1.8e4], [0.0, 1.8e4, 4.5e5]])
    D = np.array([[20.0, 1.0, 0.0], [0.0, 260.0, -855.0], [3.0, -855.0, 6130.0]])
    gains = PIDGains(K_P=(0.01, 0.012, 0.03), K_I=(0.0, 5e-4, 2e-3), K_D=(0.2, 0.18, 0.3))
    lim = (400.0, 90.0, 250.0)
    n = 32
    scalars = [MultivariablePID(gains, M=M, D_L=D, dt=0.5, integral_limit=lim) for _ in range(n)]
    batch = BatchedPID(n, gains, M=M, D_L=D, dt=0.5, integral_limit=lim)
    shadow = BatchedPID(n, gains, M=M, D_L=D, dt=0.5, integral_limit=lim)  # no anti-windup
    errs = _Errors(n, seed=3)
    dropped = clamped = 0
    for k in range(220):
        eta, nu, eta_d, vd, ad = errs.step(k)
        kind = k % 4
        if kind == 0:
            sat = None
        elif kind == 1:
            sat = rng.random((n, 3)) < 0.3
        else:
            sat = rng.normal(0.0, 1.0, (n, 3)) * (rng.random((n, 3)) < 0.5)
        tau_b = batch(eta, nu, eta_d, vd, ad, saturated=sat)
        shadow(eta, nu, eta_d, vd, ad)
        for i in range(n):
            row = (None if vd is None else vd[i], None if ad is None else ad[i])
            s_i = None if sat is None else sat[i]
            tau = scalars[i](eta[i], nu[i], eta_d[i], *row, saturated=s_i)
            assert _same(tau_b[i], tau, 1.0 + float(np.abs(tau).max())), (k, i)
        xi_s = np.array([c.integral for c in scalars])
        assert _same(batch.integral, xi_s, 1.0 + float(np.abs(xi_s).max()))
        dropped += int(not np.array_equal(shadow.integral, batch.integral))
        f = _integral_force(batch, batch.integral, eta[:, 2])
        clamped += int((f >= np.asarray(lim) * (1.0 - 1e-9)).any(axis=1).sum())
        if k % 29 == 28:
            m = rng.random(n) < 0.5
            dpsi = rng.uniform(-3.0, 3.0, n)
            batch.change_frame(dpsi, m)
            shadow.change_frame(dpsi, m)
            for i in np.flatnonzero(m):
                scalars[i].change_frame(float(dpsi[i]))
        if k % 53 == 52:
            m = rng.random(n) < 0.3
            batch.reset(m)
            shadow.reset(m)
            for i in np.flatnonzero(m):
                scalars[i].reset()
    assert dropped > 0 and clamped > 0, (dropped, clamped)


def test_change_frame_of_all_envs_and_a_scalar_dpsi():
    v = VESSELS["blue-lady"]
    n = 8
    spec = controller_spec("pid")
    scalars = [spec.factory(v, 1.0) for _ in range(n)]
    batch = BatchedPID.from_scalar(scalars[0], n)
    errs = _Errors(n, seed=11)
    for k in range(30):
        eta, nu, eta_d, vd, ad = errs.step(k)
        tau_b = batch(eta, nu, eta_d, vd, ad)
        for i in range(n):
            row = (None if vd is None else vd[i], None if ad is None else ad[i])
            assert _same(tau_b[i], scalars[i](eta[i], nu[i], eta_d[i], *row), 1e3)
        if k % 10 == 9:
            batch.change_frame(0.7)  # every env (mask None), one angle
            for c in scalars:
                c.change_frame(0.7)
    assert np.abs(batch.integral).max() > 0.0


# ---- the allocation alone, on requests spread over the whole box -------------------------------
@pytest.mark.parametrize("method", ["constrained", "inverse"])
def test_batched_allocation_rows_are_the_n1_law(method):
    v = VESSELS["blue-lady"]
    p = fixed3_parameters(v.actuators)
    rng = np.random.default_rng(5)
    n = 4000
    tau = rng.normal(0.0, 1.0, (n, 3)) * [300.0, 80.0, 250.0]
    tau[:50, 0] = 0.0  # F1 = 0: the command's zero branch
    tau[50:100] *= 1e-3  # well inside the box
    tau[100:110, 0] = 451.3 * 2  # far ahead
    batch = BatchedAllocation(v, method)
    res = batch(tau)
    scalar = allocate if method == "constrained" else allocate_inverse
    patterns = set()
    for i in range(n):
        a = scalar(tau[i], p)  # the law at N = 1
        scale = float(np.abs(tau[i]).max()) + 1.0
        assert _same(res.command[i], a.command), i
        assert _same(res.force[i], a.force, scale), i
        assert _same(res.tau[i], a.tau, scale), i
        assert _same(res.tau_error[i], a.tau_error, scale), i
        assert np.array_equal(res.saturated[i], a.saturated), i
        patterns.add(tuple(a.saturated.tolist()))
    assert np.all(res.command[:50, 0] == 0.0)
    # every combination of saturated actuators occurs (inside, each edge, corners)
    assert len(patterns) == 8, patterns
    if method == "constrained":  # the batch's rows against SciPy's bounded least squares
        wY, wN = default_weights(p)[1:]
        A = np.array([[1.0, 1.0], [p.L2, -p.L3]]) * np.sqrt([[wY], [wN]])
        box = ([p.k2 * p.p_min, p.k3 * p.p_min], [p.k2 * p.p_max, p.k3 * p.p_max])

        def J(F, t):
            return float(np.sum((A @ F - np.sqrt([wY, wN]) * t[1:]) ** 2))

        for i in range(0, n, 23):
            b = np.sqrt([wY, wN]) * tau[i, 1:]
            ref = lsq_linear(A, b, bounds=box, method="bvls", tol=1e-14).x
            assert J(res.force[i, 1:], tau[i]) <= J(ref, tau[i]) * (1 + 1e-9) + 1e-9, i
    act = batch.command_to_action(res.command)
    for i in range(0, n, 97):
        assert _same(act[i], v.actuators.command_to_action(res.command[i]))


def test_apply_residual_is_the_wrappers_sum_and_clip():
    a = np.array([[0.5, -0.9, 1.0], [0.0, 0.2, -0.3]])
    r = np.array([[1.0, -1.0, 0.0], [0.1, -0.1, 0.5]])
    applied, clipped = apply_residual(a, r, 0.5)
    assert np.array_equal(applied, np.clip(a + 0.5 * r, -1.0, 1.0))
    assert np.allclose(applied, [[1.0, -1.0, 1.0], [0.05, 0.15, -0.05]], rtol=0, atol=1e-15)
    assert np.array_equal(clipped, [[False, True, False], [False, False, False]])


# ---- against the real wrapper (MuJoCo env), several envs in lockstep ---------------------------
def test_against_the_controller_wrapper_in_a_tracking_run():
    """``make(..., controller="pid")``: the batched controller, fed each env's record as the
    wrapper reads it (to_r_frame, the tau_error of the previous step, change_frame on a leg
    switch), gives the wrapper's tau_c, controller action, allocation and residual clip."""
    from shipgym.dynamics import wrap_angle
    from shipgym.guidance import to_r_frame
    from shipgym.stacks import make

    n, scale = 3, 0.4
    envs = [
        make("shipgym/Tracking-v0", vessel="blue-lady", controller="pid", residual_scale=scale)
        for _ in range(n)
    ]
    recs = [e.reset(seed=i)[1]["record"] for i, e in enumerate(envs)]
    # no observer: the controller's velocity is the truth, its velocity filter off
    assert envs[0].unwrapped.controller.velocity_source == "truth"
    batch = batched_dp_controller(
        "pid", "blue-lady", n, envs[0].unwrapped.control_period, velocity_source="truth"
    )
    batch.reset()
    legs = np.array([r.reference.leg for r in recs])
    psi_P = np.array([float(r.reference.eta_P[2]) for r in recs])
    rng = np.random.default_rng(0)
    switches = clipped = 0
    for _ in range(260):
        eta_r = np.array(
            [
                to_r_frame(r.nav.eta, r.reference.eta_P, psi_ref_r=float(r.reference.eta_d_r[2]))
                for r in recs
            ]
        )
        nu = np.array([r.nav.nu for r in recs])
        eta_d = np.array([r.reference.eta_d_r for r in recs])
        vd = np.array([r.reference.eta_dot_d_r for r in recs])
        ad = np.array([r.reference.eta_ddot_d_r for r in recs])
        tau_b, al_b, act_b = batch(eta_r, nu, eta_d, vd, ad)
        residual = rng.uniform(-1.0, 1.0, (n, 3)).astype(np.float32)
        applied, res_clipped = apply_residual(act_b, residual, scale)
        for i, e in enumerate(envs):
            info = e.step(residual[i])[4]
            assert _same(tau_b[i], info["tau_c"], 1e3)
            assert _same(act_b[i], info["controller_action"])
            assert _same(al_b.tau_error[i], info["tau_error"], 1e3)
            assert np.array_equal(al_b.saturated[i], info["allocation_saturated"])
            assert np.array_equal(res_clipped[i], info["residual_clipped"])
            recs[i] = info["record"]
        clipped += int(res_clipped.sum())
        new_legs = np.array([r.reference.leg for r in recs])
        m = new_legs != legs
        if m.any():
            new_psi = np.array([float(r.reference.eta_P[2]) for r in recs])
            batch.change_frame(wrap_angle(new_psi - psi_P), m)
            psi_P = np.where(m, new_psi, psi_P)
            legs = new_legs
            switches += int(m.sum())
    assert switches > 0 and clipped > 0, (switches, clipped)
    assert np.abs(batch.pid.integral).max() > 0.0


# ---- the factory, and what is not batched ------------------------------------------------------
def test_factory_mirrors_the_wrappers_pid_entries():
    for name, (_, _, method, _) in BATCHED_CONTROLLERS.items():
        assert CONTROLLERS[name].allocation == method, name
    for vname, v in VESSELS.items():
        if v.dofs != 3:
            continue
        for name, (preset, scale, _, cond) in BATCHED_CONTROLLERS.items():
            assert CONTROLLERS[name].conditioned == cond, name
            try:
                ref = CONTROLLERS[name].factory(v, 0.5)
            except ValueError as e:  # the same refusal (pid-seed elsewhere; no capacity)
                with pytest.raises(ValueError) as mine_e:
                    vessel_pid(v, preset, scale, 0.5, conditioned=cond)
                assert str(mine_e.value) == str(e), (vname, name)
                continue
            mine = vessel_pid(v, preset, scale, 0.5, conditioned=cond)
            assert mine.gains == ref.gains, (vname, name)
            assert mine.velocity_filter == ref.velocity_filter, (vname, name)
            assert np.array_equal(mine.M, ref.M) and np.array_equal(mine.D_L, ref.D_L)
            assert np.array_equal(mine.integral_limit, ref.integral_limit)
            assert mine.dt == ref.dt


@pytest.mark.parametrize("name", ["star-hercules", "wimpey-sealab"])
def test_iterative_allocations_run_per_env_as_the_single_allocator(name):
    """The active-set least squares (Star Hercules) and the azimuth QP (Wimpey Sealab) for N
    envs: row i is the single env's allocator (make_allocator) on row i, bit for bit, each
    env from its own actuator state."""
    v = load_vessel(name)
    n = 5
    batch = BatchedAllocation(v, "constrained", 1.0)
    singles = [make_allocator(v, "constrained", 1.0) for _ in range(n)]
    rng = np.random.default_rng(4)
    cap = np.array([2e4, 2e4, 2e5]) * (v.hull.m / 2e6)
    state = np.tile(v.actuators.initial_state(), (n, 1))
    for _ in range(20):
        tau = rng.normal(0.0, 1.0, (n, 3)) * cap
        got = batch(tau, state)
        for i, alloc in enumerate(singles):
            want = alloc(tau[i], state[i])
            for g, w in zip(got, want, strict=True):
                assert np.array_equal(g[i], w)
        state = got.command


def test_what_is_not_batched_says_so():
    with pytest.raises(ValueError, match="integral_limit"):  # no sway/yaw thrusters
        batched_dp_controller("pid", "kvlcc2-100m", 4, 1.0)
    with pytest.raises(ValueError, match="integral_limit"):  # a 4-DOF hull's, likewise
        batched_dp_controller("pid", "naval-vessel", 4, 1.0)
    with pytest.raises(ValueError, match="pid-seed"):
        batched_dp_controller("pid-seed", "star-hercules", 4, 1.0)
    with pytest.raises(ValueError, match="unknown controller 'nope'"):
        batched_dp_controller("nope", "blue-lady", 4, 1.0)
    with pytest.raises(ValueError, match="prints LQ gains"):  # as the scalar factory
        batched_dp_controller("alt-lq-printed", "blue-lady", 4, 1.0)
    with pytest.raises(ValueError, match="inverse"):
        BatchedAllocation("star-hercules", "inverse")


def test_bad_inputs_raise_and_leave_the_state_alone():
    b = batched_dp_controller("pid", "blue-lady", 4, 1.0)
    z = np.zeros((4, 3))
    e = np.full((4, 3), 0.5)
    b(e, z, z)
    xi = b.pid.integral
    bad = e.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match="eta_r"):
        b.pid(bad, z, z, saturated=b.tau_error)
    with pytest.raises(ValueError, match="shape"):
        b.pid(e[:3], z, z)
    with pytest.raises(ValueError, match="saturated contains NaN"):
        b.pid(e, z, z, saturated=np.where(bad > 1, 0.0, bad))
    with pytest.raises(ValueError, match="mask"):
        b.reset(np.ones(3, bool))
    with pytest.raises(ValueError, match="finite"):
        b.change_frame(np.array([0.0, np.inf, 0.0, 0.0]))
    with pytest.raises(ValueError, match="tau"):
        b.allocation(np.full((4, 3), np.inf))
    assert np.array_equal(b.pid.integral, xi)
    b.change_frame(np.array([0.0, np.inf, 0.0, 0.0]), np.array([True, False, True, True]))
    with pytest.raises(ValueError, match="n must be"):
        BatchedPID.from_scalar(controller_spec("pid").factory(VESSELS["blue-lady"], 1.0), 0)
