"""MuJoCo physics vs the 3-DOF model: exactness, parity with SciPy, thrusters, bad input."""

import dataclasses
import math

import mujoco
import numpy as np
import pytest

from shipgym.disturbances import WindConfig
from shipgym.dynamics import (
    BLUE_LADY_HULL,
    BLUE_LADY_THRUSTERS,
    BLUE_LADY_WINDAGE,
    PlantModel,
    plant_model,
    rot,
    simulate_reference,
    wrap_angle,
)
from shipgym.envs.physics import SimulationDiverged, VesselPhysics

GUSTY = WindConfig(speed=3.0, direction_from=math.radians(300.0), sample_period=1.0)


def _commands(duration, period, seed=0):
    """Time-varying, saturating commands: a turn with main propeller and tunnels."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, period)
    n = 300 * np.sin(2 * np.pi * t / 240) + 150 + 40 * rng.standard_normal(t.size)
    p2 = np.clip(np.sin(2 * np.pi * t / 150) + 0.3 * rng.standard_normal(t.size), -1.2, 1.2)
    p3 = np.clip(-np.cos(2 * np.pi * t / 110) + 0.3 * rng.standard_normal(t.size), -1.2, 1.2)
    return t, np.c_[n, p2, p3]


def _run_physics(phys, duration, ct, cmds, sample=1.0):
    steps_per_sample = round(sample / phys.timestep)
    steps_per_cmd = round((ct[1] - ct[0]) / phys.timestep)
    out = [np.r_[phys.eta, phys.nu]]
    k = 0
    for i in range(round(duration / phys.timestep)):
        if i % steps_per_cmd == 0:
            phys.set_command(cmds[k])
            k += 1
        phys.step()
        if (i + 1) % steps_per_sample == 0:
            out.append(np.r_[phys.eta, phys.nu])
    return np.array(out)


def _parity_errors(plant, timesteps, duration=600.0, wind=GUSTY):
    """The physics at each of ``timesteps`` against one run of the SciPy oracle (the same
    commands and gusts: the wind's grid does not depend on the step): ``([(pos_err,
    psi_err), ...], dist, ref)``."""
    trajs, gusts = [], []
    for timestep in timesteps:
        phys = VesselPhysics("blue-lady", plant, wind=wind, timestep=timestep)
        phys.reset(rng=np.random.default_rng(7))
        ct, cmds = _commands(duration, 5.0)
        trajs.append(_run_physics(phys, duration, ct, cmds))
        gusts.append(phys.wind.series(np.arange(0.0, duration, 0.37)))
    for g in gusts[1:]:  # every run had the oracle's gusts
        np.testing.assert_array_equal(g, gusts[0])
    t_eval = np.arange(0.0, duration + 0.5, 1.0)

    def env_load(t, eta, nu):
        return phys.wind.load(t, eta[2], nu[0], nu[1])

    ref = simulate_reference(
        phys.plant, t_eval, ct, cmds, actuators=phys.actuators, env_load=env_load,
        breakpoints=np.arange(0.0, duration, wind.sample_period), rtol=1e-10, atol=1e-10,
    )  # fmt: skip
    dist = np.sum(np.hypot(*np.diff(ref.eta[:, :2], axis=0).T))
    errors = [
        (
            np.max(np.hypot(*(traj[:, :2] - ref.eta[:, :2]).T)),
            np.degrees(np.max(np.abs(wrap_angle(traj[:, 2] - ref.eta[:, 2])))),
        )
        for traj in trajs
    ]
    return errors, dist, ref


@pytest.mark.parametrize("plant", ["default", "seed-linear"])
def test_qacc_is_exactly_the_model_acceleration(plant):
    """After one step, MuJoCo's joint acceleration equals R(psi)(nu_dot + r S nu) of the model.

    The thrust written out: the default plant's main propeller loses k_u (1 - w) |n| u
    (Blanke 1981) and its tunnels the factor eta(|u|) (MuJoCo's actuators carry no force: the
    physics applies these flow-dependent ones); the seed-linear plant's are the bollard laws of
    Tomera (2014) eqs. 8-9. MuJoCo's actuators carry no force: the physics applies all."""
    phys = VesselPhysics("blue-lady", plant, wind=WindConfig(speed=4.0, direction_from=1.0))
    phys.reset(eta=[1.0, 2.0, 0.7], nu=[0.4, -0.15, 0.02], actuators=[350.0, 0.6, -0.8])
    eta, nu = phys.eta, phys.nu
    F1, eta_t = 1.9589e-3 * 350**2, 1.0
    if plant == "default":
        F1 -= 0.4915 * (1 - 0.363) * 350 * nu[0]
        x2 = (nu[0] / 0.42) ** 2
        eta_t = 1 - 0.5 * x2 * math.exp(1 - x2)
    tau = np.array([F1, eta_t * 44.145 * (0.6 - 0.8), eta_t * 44.145 * (3.24 * 0.6 + 2.376 * 0.8)])
    tau_w = np.array(phys.wind.load(0.0, eta[2], nu[0], nu[1]))
    nu_dot = phys.plant.nu_dot(nu, tau + tau_w)
    S_nu = np.array([-nu[1], nu[0], 0.0])
    qacc = rot(eta[2]) @ (nu_dot + nu[2] * S_nu)
    phys.step()
    np.testing.assert_allclose(phys.data.qacc, qacc, rtol=1e-9, atol=1e-15)
    np.testing.assert_array_equal(phys.data.qfrc_actuator, np.zeros(3))


@pytest.mark.parametrize("plant", ["default", "sway-added-mass-equal-to-m"])
def test_parity_with_scipy_reference(plant):
    """600 s, time-varying saturating commands, gusty wind, quadratic damping, Coriolis and
    sway-yaw added-mass coupling, the vessel's actuators (the advance-speed and tunnel losses,
    the rate limits, which the commands' reversals hit): within 0.5 % of the distance and
    0.5 deg; halving dt helps."""
    if plant == "default":
        model = plant_model("default", hull=BLUE_LADY_HULL)
    else:  # sway added mass equal to the rigid-body mass: the lagged scheme is unstable here
        model = plant_model(
            "default", dataclasses.replace(BLUE_LADY_HULL, Y_vdot=-BLUE_LADY_HULL.m)
        )
        assert model.M_A[1][1] == pytest.approx(model.M_RB[1][1])
    ((e1, h1), (e2, h2)), dist, ref = _parity_errors(model, (0.05, 0.025))
    assert dist > 20.0, "the manoeuvre must actually travel"
    assert np.ptp(np.unwrap(ref.eta[:, 2])) > math.radians(30), "and turn"
    assert e1 < 0.005 * dist, (e1, dist)
    assert h1 < 0.5, h1
    assert e2 < 0.7 * e1 and h2 < 0.7 * h1 + 1e-6, (e1, e2, h1, h2)


def test_seed_linear_surge_step_matches_analytic_solution():
    """M11 u_dot + 21.1 u = F: steady speed F/21.1, time constant 23664.9/21.1 s."""
    phys = VesselPhysics("blue-lady", "seed-linear", timestep=0.05)
    n = 100.0
    phys.reset(actuators=[n, 0.0, 0.0])  # actuator already at the command: constant force
    phys.set_command([n, 0.0, 0.0])
    F = BLUE_LADY_THRUSTERS.k1 * n * n
    tau_c = 23664.9 / 21.1
    dt = phys.timestep
    steps = round(tau_c / dt)
    phys.step(steps)
    u_tau = phys.nu[0]
    phys.step(round(9 * tau_c / dt))
    u_end = phys.nu[0]
    U = F / 21.1
    # u(10 tau) = U (1 - e^-10); u(tau) = U (1 - e^-1)
    assert u_end / (1 - math.exp(-10)) == pytest.approx(U, rel=5e-3)
    tau_fit = -tau_c / math.log(1 - u_tau / U)
    assert tau_fit == pytest.approx(tau_c, rel=5e-3)
    assert abs(phys.nu[1]) < 1e-12 and abs(phys.nu[2]) < 1e-12


@pytest.mark.parametrize("psi_deg", [0.0, 45.0, 90.0, 200.0, -120.0])
def test_thrust_follows_heading(psi_deg):
    psi = math.radians(psi_deg)
    phys = VesselPhysics("blue-lady", "seed-linear")
    phys.reset(eta=[0, 0, psi], actuators=[300.0, 1.0, 0.0])
    phys.set_command([300.0, 1.0, 0.0])
    phys.step()
    tau_b = np.array([1.9589e-3 * 300**2, 44.145, 3.24 * 44.145])
    np.testing.assert_allclose(phys.tau_thrusters, tau_b, rtol=1e-9)
    # the hull accelerates along R(psi) M^-1 tau
    M = plant_model("seed-linear", hull=BLUE_LADY_HULL).mass_matrix()
    expect = rot(psi) @ np.linalg.solve(M, tau_b)
    np.testing.assert_allclose(phys.data.qacc, expect, rtol=1e-9)


@pytest.mark.parametrize("plant", ["default", "seed-linear"])
def test_saturation_at_physical_ranges(plant):
    phys = VesselPhysics("blue-lady", plant)
    flags = phys.set_command([900.0, -3.0, 0.5])
    np.testing.assert_array_equal(flags, [True, True, False])
    np.testing.assert_array_equal(phys.command, [480.0, -1.0, 0.5])
    phys.step(round(40 / phys.timestep))
    act = phys.actuator_state
    assert act[0] <= 480.0 and act[1] >= -1.0
    # Blanke (1981): k n^2 - k_u (1 - w) n u, at the last physics step's speed (the speed now
    # is one step on: 1e-3)
    u = phys.nu[0] if plant == "default" else 0.0
    assert phys.thrust[0] == pytest.approx(1.9589e-3 * 480**2 - 0.4915 * 0.637 * 480 * u,
                                           rel=1e-3 if u else 1e-6)  # fmt: skip
    phys.set_command([-900.0, 3.0, -3.0])
    phys.step(round(40 / phys.timestep))
    assert phys.actuator_state[0] == pytest.approx(-200.0, rel=1e-6)
    assert np.all(np.abs(phys.thrust[1:]) <= 44.145 + 1e-9)


@pytest.mark.parametrize("idx,cmd,T", [(0, 400.0, 2.0), (1, 1.0, 1.0), (2, -1.0, 1.0)])
def test_first_order_lag_time_constant(idx, cmd, T):
    phys = VesselPhysics("blue-lady", "seed-linear", timestep=0.01)
    command = np.zeros(3)
    command[idx] = cmd
    phys.set_command(command)
    t, a = [], []
    for _ in range(round(5 * T / phys.timestep)):
        phys.step()
        t.append(phys.time)
        a.append(phys.actuator_state[idx] / cmd)
    t_cross = np.interp(1 - math.exp(-1), a, t)
    assert t_cross == pytest.approx(T, rel=0.02)


def test_mjcf_thruster_values_agree_with_parameters():
    # the model built from vessel.toml against the Tomera (2014) record in ThrusterParameters
    from shipgym.dynamics.vessel import load_vessel
    from shipgym.envs.scene import build_model

    v = load_vessel("blue-lady")
    m = build_model(v, actuators=v.actuators_for("seed-linear"))  # the bollard laws as printed
    p = BLUE_LADY_THRUSTERS
    sites = [m.site_pos[m.actuator_trnid[i, 0]] for i in range(3)]
    np.testing.assert_allclose([s[0] for s in sites], [p.x_main, p.L2, -p.L3])
    acts = v.actuators_for("seed-linear")
    np.testing.assert_allclose(np.c_[acts.lower, acts.upper], np.c_[p.lower, p.upper])
    np.testing.assert_allclose([c.time_constant for c in acts.channels], p.time_constants)
    np.testing.assert_allclose(acts.thrust(np.c_[p.lower, p.upper].T), np.c_[
        p.force_lower, p.force_upper].T, rtol=1e-4)  # fmt: skip
    assert m.body("hull").mass[0] == pytest.approx(BLUE_LADY_HULL.m)
    assert m.opt.gravity.tolist() == [0, 0, 0]
    # MuJoCo's actuators name the channels; the physics applies every force (gain 0, no state)
    np.testing.assert_array_equal(build_model(v).actuator_gainprm[:, 0], [0.0, 0.0, 0.0])
    assert m.na == 0


def test_bad_input_raises_clear_errors():
    phys = VesselPhysics("blue-lady")
    with pytest.raises(ValueError, match="NaN or infinite"):
        phys.set_command([np.nan, 0.0, 0.0])
    with pytest.raises(ValueError, match="NaN or infinite"):
        phys.set_command([0.0, np.inf, 0.0])
    with pytest.raises(ValueError, match="shape"):
        phys.set_command([0.0, 0.0])
    with pytest.raises(ValueError, match="unknown plant variant"):
        VesselPhysics("blue-lady", "nonlinear")
    with pytest.raises(ValueError, match="timestep"):
        VesselPhysics("blue-lady", timestep=-0.1)
    with pytest.raises(ValueError, match="current"):
        VesselPhysics("blue-lady", current=(-1.0, 0.0))


def test_diverging_simulation_stops_with_an_error_not_nan():
    unstable = PlantModel(
        "unstable", np.diag([1.0e3, 1.0e3, 1.0e4]), np.zeros((3, 3)),
        -np.diag([5.0e3, 5.0e3, 5.0e4]), coriolis=False,
    )  # fmt: skip
    phys = VesselPhysics("blue-lady", unstable)
    phys.reset(nu=[0.1, 0.0, 0.0])
    with pytest.raises(SimulationDiverged, match="diverged"):
        phys.step(100_000)
    assert np.all(np.isfinite(phys.eta)) and np.all(np.isfinite(phys.nu))


def test_separate_models_in_one_process_do_not_interfere():
    a, b = VesselPhysics("blue-lady", "default"), VesselPhysics("blue-lady", "seed-linear")
    for ph in (a, b):
        ph.set_command([300.0, 0.5, -0.5])
    a.step(200)
    b.step(200)
    c = VesselPhysics("blue-lady", "default")
    c.set_command([300.0, 0.5, -0.5])
    c.step(200)
    np.testing.assert_array_equal(a.eta, c.eta)
    assert mujoco.get_mjcb_passive() is None


def test_still_air_drags_a_moving_hull_and_none_switches_aerodynamics_off():
    from shipgym.disturbances import wind_load

    still = VesselPhysics("blue-lady", "seed-linear", wind=WindConfig(speed=0.0))
    still.reset(nu=[1.0, 0.0, 0.0])
    still.step()
    # 1 m/s head wind on a hull at rest
    expect = wind_load(0.0, 0.0, 0.0, 1.0, 0.0, windage=BLUE_LADY_WINDAGE)
    np.testing.assert_allclose(still.tau_wind, expect, rtol=1e-9, atol=1e-12)
    assert still.tau_wind[0] < 0
    off = VesselPhysics("blue-lady", "seed-linear", wind=None)
    off.reset(nu=[1.0, 0.0, 0.0])
    off.step()
    assert off.tau_wind == (0.0, 0.0, 0.0)


def test_tau_thrusters_equals_the_configuration_matrix_times_thrust():
    from shipgym.dynamics import command_to_tau

    phys = VesselPhysics("blue-lady")
    phys.reset(actuators=[-150.0, 0.3, -0.7])
    np.testing.assert_allclose(
        phys.tau_thrusters, command_to_tau(phys.actuator_state, BLUE_LADY_THRUSTERS), rtol=1e-12
    )
