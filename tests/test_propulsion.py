"""The Blue Lady's actuator physics: the advance-speed thrust law of the main propeller
(Blanke 1981), the tunnel thrusters' loss with forward speed (KMW/HyA model tests,
International Shipbuilding Progress 1967) and the actuator rate limits; each against its
formula written out here, an analytic solution or Tomera (2014)'s numbers, not against the
code's own output."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _helpers import compiled_forces
from scipy.optimize import brentq

from shipgym.dynamics import BLUE_LADY_THRUSTERS, simulate_reference, wrap_angle
from shipgym.dynamics.actuators import ActuatorSet, Propeller
from shipgym.dynamics.vessel import VesselError, load_vessel
from shipgym.envs.batchphysics import BatchedPhysics
from shipgym.envs.physics import VesselPhysics

KN = 1852.0 / 3600.0  # m/s per knot
K1 = 1.9589e-3  # N/rpm^2, Tomera (2014) eq. 8 (read in N/rpm^2)
KU, W = 0.4915, 0.363  # N/(rpm m/s) and the wake fraction of vessel.toml
K_T = 44.145  # N, Tomera (2014) eq. 9
U50, DEPTH = 0.42, 0.5


def _main(n: float, u: float) -> float:
    """Blanke (1981): k n|n| - k_u |n| (1 - w) u."""
    return K1 * n * abs(n) - KU * abs(n) * (1.0 - W) * u


def _eta(u: float) -> float:
    x2 = (u / U50) ** 2
    return 1.0 - DEPTH * x2 * math.exp(1.0 - x2)


def test_the_vessel_file_gives_the_documented_laws() -> None:
    v = load_vessel("blue-lady")
    main, bow, stern = v.actuators
    assert (main.advance, main.wake, main.rate_limit) == (KU, W, 100.0)
    for t in (bow, stern):
        assert (t.loss_speed, t.loss_depth, t.rate_limit) == (U50, DEPTH, 1.0)
    assert all(a.flow_dependent for a in v.actuators)


@pytest.mark.parametrize("n", [480.0, 250.0, 37.0, 0.0, -80.0, -200.0])
@pytest.mark.parametrize("u", [1.6, 0.42, 0.05, 0.0, -0.3, -0.9])
def test_thrust_laws_against_their_formulas(n: float, u: float) -> None:
    """Ahead and astern, forward and backward speed, in the array form and the plain-float
    flow kernel of the physics (with a sway velocity and yaw rate, which do not enter)."""
    acts = load_vessel("blue-lady").actuators
    p = 0.7
    st = np.array([n, p, -p])
    nu = np.array([u, 0.03, -0.01])
    want = [_main(n, u), K_T * p * _eta(u), -K_T * p * _eta(u)]
    np.testing.assert_allclose(acts.thrust(st, nu), want, rtol=1e-12, atol=1e-12)
    X, Y, _K, N, thrusts, _stalled = compiled_forces(acts, st, u, 0.03, 0.0, -0.01)
    np.testing.assert_allclose(thrusts, want, rtol=1e-12, atol=1e-12)
    tau = acts.tau(st, nu)
    np.testing.assert_allclose(
        tau, [want[0], want[1] + want[2], 3.24 * want[1] - 2.376 * want[2]], rtol=1e-12, atol=1e-9
    )
    np.testing.assert_allclose([X, Y, N], tau, rtol=1e-12, atol=1e-9)


def test_tunnel_factor_shape() -> None:
    """1 at rest and flat at low speed, the KMW/HyA 50 % at 4 kn (Froude-scaled 0.42 m/s) as
    its minimum, back to the zero-speed effect at 15 kn full scale, the same astern."""
    bow = load_vessel("blue-lady").actuators.actuators[1]
    assert bow.efficiency(0.0) == 1.0
    assert bow.efficiency(U50) == pytest.approx(0.5, abs=1e-15)
    u = np.linspace(0.0, 3.0, 3001)
    e = bow.efficiency(u)
    assert u[np.argmin(e)] == pytest.approx(U50, abs=1e-3)
    kn15 = 15 * KN / math.sqrt(24.0)
    assert bow.efficiency(kn15) == pytest.approx(_eta(kn15)) and _eta(kn15) > 0.999
    assert bow.efficiency(0.05) > 0.98  # works well at low speed
    np.testing.assert_array_equal(bow.efficiency(-u), e)


def test_calm_water_top_speed_is_tomeras_3_1_knots() -> None:
    """480 rpm, default plant, no wind: the steady speed is Table 1's 3.1 kn +- 10 % (aimed at
    the centre), the root of thrust(u) = X_u u + X_uu u |u| of the hull."""
    v = load_vessel("blue-lady")
    h = v.hull
    root = brentq(lambda u: _main(480.0, u) - (-h.X_u * u - h.X_uu * u * abs(u)), 0.0, 5.0)
    assert root / KN == pytest.approx(3.1, rel=1e-3)
    phys = VesselPhysics(v)
    phys.set_command([480.0, 0.0, 0.0])
    phys.step(round(1500.0 / phys.timestep))  # 1500 s: about 100 surge time constants
    u = phys.nu[0]
    assert abs(u / KN - 3.1) <= 0.31
    assert u == pytest.approx(root, rel=1e-6)
    # Tomera's bollard law alone would reach 4.65 kn (the 2.39 m/s): the law matters
    bollard = brentq(lambda u: K1 * 480**2 - (-h.X_u * u - h.X_uu * u * abs(u)), 0.0, 5.0)
    assert bollard / KN == pytest.approx(4.65, abs=0.01)


def test_astern_speed_and_turning_on_the_spot() -> None:
    """The README's figures: -200 rpm astern, and both tunnels full opposite at rest."""
    v = load_vessel("blue-lady")
    h = v.hull
    phys = VesselPhysics(v)
    phys.set_command([-200.0, 0.0, 0.0])
    phys.step(round(5000.0 / phys.timestep))  # astern: a surge time constant of about 530 s
    root = brentq(lambda u: _main(-200.0, u) - (-h.X_u * u - h.X_uu * u * abs(u)), -5.0, 0.0)
    assert phys.nu[0] == pytest.approx(root, rel=1e-6)
    assert phys.nu[0] == pytest.approx(-0.617, abs=1e-3)
    phys.reset()
    phys.set_command([0.0, 1.0, -1.0])
    phys.step(round(1200.0 / phys.timestep))
    r = math.degrees(phys.nu[2])
    assert r == pytest.approx(1.163, abs=1e-3)
    # the hull drifts slowly while it turns (the Coriolis and Munk terms): the tunnels lose a
    # little of their thrust at that surge speed
    u = phys.nu[0]
    assert 0.01 < abs(u) < 0.05
    np.testing.assert_allclose(phys.thrust[1:], [K_T * _eta(u), -K_T * _eta(u)], rtol=1e-4)


def _reversal(actuator: int, start: float, end: float, rate: float, T: float, h: float):
    phys = VesselPhysics("blue-lady", timestep=h, wind=None)
    st = [0.0, 0.0, 0.0]
    st[actuator] = start
    phys.reset(actuators=st)
    cmd = list(st)
    cmd[actuator] = end
    phys.set_command(cmd)
    n = round((abs(end - start) / rate + 6 * T) / h)
    a = [start]
    for _ in range(n):
        phys.step()
        a.append(float(phys.actuator_state[actuator]))
    return np.arange(n + 1) * h, np.array(a)


@pytest.mark.parametrize(
    ("actuator", "start", "end", "rate", "T"),
    [(0, 480.0, -200.0, 100.0, 2.0), (0, -200.0, 480.0, 100.0, 2.0), (1, 1.0, -1.0, 1.0, 1.0),
     (2, -1.0, 1.0, 1.0, 1.0)],
)  # fmt: skip
@pytest.mark.parametrize("h", [0.05, 0.01])
def test_a_reversal_takes_the_time_the_rate_limit_says(actuator, start, end, rate, T, h):
    """a_dot = clip((c - a) / T, +-rate): a ramp at the rate limit until |c - a| = rate T
    (t1 = (|c - a0| - rate T) / rate), then the lag: a = c + (a(t1) - c) e^-((t - t1)/T)."""
    t, a = _reversal(actuator, start, end, rate, T, h)
    s = math.copysign(1.0, end - start)
    t1 = (abs(end - start) - rate * T) / rate
    want = np.where(t <= t1, start + s * rate * t, end - s * rate * T * np.exp(-(t - t1) / T))
    # exact on the ramp and in the lag; the switch falls between two steps: < rate h
    np.testing.assert_allclose(a[t <= t1 - h], want[t <= t1 - h], rtol=0, atol=1e-9 * rate)
    assert np.max(np.abs(a - want)) < rate * h
    # the time to pass zero thrust and the time to 90 % of the reversal
    t0 = np.interp(0.0, s * a, t)  # on the ramp (or at its end) in all four cases
    assert t0 == pytest.approx(abs(start) / rate, abs=h)
    t90 = np.interp(0.9, s * (a - start) / abs(end - start), t)
    want90 = t1 + T * math.log(rate * T / (0.1 * abs(end - start)))
    assert t90 == pytest.approx(want90, abs=h)


def test_rate_limit_in_the_reference_integrator_and_the_batched_physics() -> None:
    """The reversal of the main propeller in solve_ivp's clip((c - a)/T, +-rate) and in the
    batched physics: the same analytic ramp."""
    acts = load_vessel("blue-lady").actuators
    plant = load_vessel("blue-lady").plant()
    t = np.arange(0.0, 20.0, 0.5)
    ref = simulate_reference(plant, t, [0.0], [[-200.0, -1.0, 1.0]], actuators=acts,
                             act0=[480.0, 1.0, -1.0])  # fmt: skip
    t1 = (680.0 - 200.0) / 100.0
    want = np.where(t <= t1, 480.0 - 100.0 * t, -200.0 + 200.0 * np.exp(-(t - t1) / 2.0))
    np.testing.assert_allclose(ref.act[:, 0], want, atol=1e-6)
    bp = BatchedPhysics("blue-lady", 2, timestep=0.05)
    bp.reset(actuators=[480.0, 1.0, -1.0])
    bp.set_command([-200.0, -1.0, 1.0])
    bp.step(round(t1 / 0.05) - 1)
    np.testing.assert_allclose(bp.actuator_state[:, 0], 480.0 - 100.0 * (t1 - 0.05), atol=1e-9)


def test_seed_linear_keeps_tomeras_bollard_laws_and_its_trajectories() -> None:
    """The seed-linear plant drives the actuators as Tomera (2014) eqs. 8-9 print them (no
    advance-speed or tunnel loss, no rate limit): its trajectory under reversing commands at
    speed is that of the reference integration with the bollard thrusters."""
    v = load_vessel("blue-lady")
    acts = v.actuators_for("seed-linear")
    assert not acts.flow_dependent and not acts.rate_limited
    assert [a.k_ahead for a in acts] == [K1, K_T, K_T]
    assert v.actuators_for(v.plant("seed-linear")) is acts
    assert v.actuators_for("default") is v.actuators
    phys = VesselPhysics(v, "seed-linear", wind=None)
    phys.reset(nu=[0.5, 0.0, 0.0], actuators=[300.0, 0.0, 0.0])
    ct = np.arange(0.0, 300.0, 20.0)
    cmds = np.c_[np.where(np.arange(ct.size) % 2, -200.0, 480.0),
                 np.where(np.arange(ct.size) % 3, 1.0, -1.0), np.zeros(ct.size) - 0.5]  # fmt: skip
    out = [np.r_[phys.eta, phys.nu]]
    for k in range(ct.size):
        phys.set_command(cmds[k])
        for _ in range(20):
            phys.step(20)
            out.append(np.r_[phys.eta, phys.nu])
    traj = np.array(out)
    t_eval = np.arange(traj.shape[0]) * 1.0
    ref = simulate_reference(
        phys.plant, t_eval, ct, cmds, thrusters=BLUE_LADY_THRUSTERS, nu0=[0.5, 0.0, 0.0],
        act0=[300.0, 0.0, 0.0],
    )  # fmt: skip
    dist = np.sum(np.hypot(*np.diff(ref.eta[:, :2], axis=0).T))
    assert dist > 100.0
    assert np.max(np.hypot(*(traj[:, :2] - ref.eta[:, :2]).T)) < 1e-4 * dist
    assert np.degrees(np.max(np.abs(wrap_angle(traj[:, 2] - ref.eta[:, 2])))) < 0.01
    # no rate limit: a reversal 480 -> -200 rpm is the plain lag, a = -200 + 680 e^(-t/2)
    phys.reset(actuators=[480.0, 1.0, -1.0])
    phys.set_command([-200.0, -1.0, 1.0])
    phys.step(round(1.0 / phys.timestep))
    np.testing.assert_allclose(
        phys.actuator_state, [-200.0 + 680.0 * math.exp(-0.5), -1 + 2 * math.exp(-1), 1 - 2 *
                              math.exp(-1)], rtol=1e-9)  # fmt: skip


def test_the_allocation_stays_on_the_bollard_model() -> None:
    """Propeller.inverse inverts the bollard law (the controller's design model)."""
    main = load_vessel("blue-lady").actuators.actuators[0]
    assert float(main.inverse(K1 * 300.0**2)) == pytest.approx(300.0)
    assert main.bollard().advance == 0.0 and math.isinf(main.bollard().rate_limit)


def test_bad_actuator_options_raise_clear_errors(tmp_path) -> None:
    with pytest.raises(ValueError, match="wake must be from 0 to below 1"):
        Propeller(name="p", wake=1.0)
    with pytest.raises(ValueError, match="rate_limit must be > 0"):
        Propeller(name="p", rate_limit=0.0)
    with pytest.raises(ValueError, match="loss_depth must be from 0 to 1"):
        Propeller(name="p", loss_depth=1.5)
    with pytest.raises(ValueError, match="advance must be >= 0"):
        Propeller(name="p", advance=-1.0)
    src = (load_vessel("blue-lady").folder / "vessel.toml").read_text()
    cases = {
        'actuators = "bollard"': ('actuators = "printed"', "choose 'vessel'"),
        'loss_depth = { value = 0.5, unit = "1", source': ('loss_dept = { value = 0.5, unit = "1",'
                                                          ' source', "unknown key"),
        'wake = { value = 0.363, unit = "1"': ('wake = { value = 0.363, unit = "%"', "unit must"),
        'rate_limit = { value = 100.0, unit = "rpm/s"': (
            'rate_limit = { value = -1.0, unit = "rpm/s"', "must be > 0"),
    }  # fmt: skip
    for i, (old, (new, msg)) in enumerate(cases.items()):
        assert old in src, old
        d = tmp_path / f"v{i}"
        d.mkdir()
        (d / "vessel.toml").write_text(src.replace(old, new, 1))
        (d / "vessel.xml").write_text((load_vessel("blue-lady").body_xml).read_text())
        with pytest.raises(VesselError, match=msg):
            load_vessel(d)
    one = src.replace(
        'loss_depth = { value = 0.5, unit = "1", source = "KMW/HyA model tests (International '
        'Shipbuilding Progress 1967): about 50 % of the zero-speed effect left at 4 kn" }\n',
        "",
        1,
    )
    assert one != src
    d = tmp_path / "half"
    d.mkdir()
    (d / "vessel.toml").write_text(one)
    (d / "vessel.xml").write_text((load_vessel("blue-lady").body_xml).read_text())
    with pytest.raises(VesselError, match="give both loss_speed"):
        load_vessel(d)


def test_bollard_set_of_a_set_without_options_is_itself() -> None:
    acts = ActuatorSet([Propeller(name="a"), Propeller(name="b", alpha=math.pi / 2)])
    assert acts.bollard() is acts and not acts.rate_limited


def test_the_observers_thrust_is_the_bollard_model_of_the_states() -> None:
    """What a DP system computes from its shaft-speed and thruster feedback (Measurement.tau,
    fed to the EKF): Tomera's bollard laws of the actuator states, not the plant's losses;
    the seed-linear plant's laws are those already."""
    v = load_vessel("blue-lady")
    phys = VesselPhysics(v)
    phys.reset(nu=[0.3, 0.0, 0.0], actuators=[300.0, 0.6, -0.4])
    st = phys.actuator_state
    n, p2, p3 = st
    want = [K1 * n * abs(n), K_T * (p2 + p3), K_T * (3.24 * p2 - 2.376 * p3)]
    np.testing.assert_allclose(phys.tau_model, want, rtol=1e-12)
    assert not np.allclose(phys.tau_thrusters, want, rtol=1e-3)  # the plant's losses
    lin = VesselPhysics(v, plant="seed-linear")
    lin.reset(nu=[0.3, 0.0, 0.0], actuators=[300.0, 0.6, -0.4])
    np.testing.assert_array_equal(lin.tau_model, lin.tau_thrusters)
