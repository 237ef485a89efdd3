"""The rudder actuator, the speed-proportional 4-DOF hull and the seed's model as a MuJoCo hull.

Checks against independent references: the seed's state space written from the paper
(Radhakrishnan n.d. eqs. 5-11, :mod:`shipgym.dynamics.vanderklugt`), its frequency response
(the notes' open-loop amplitudes, check B4), the naval vessel's analytic linearisation
(Blanke & Christensen 1993, :mod:`shipgym.dynamics.blanke4`), and the rate and angle limits
the servo must never pass.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest
from _helpers import accel_of, compiled_forces

from shipgym.dynamics.actuators import ActuatorSet, Rudder
from shipgym.dynamics.blanke4 import NAVAL_VESSEL, linear_roll_model
from shipgym.dynamics.hull4 import Hull4
from shipgym.dynamics.linearise import roll_model_of, roll_rhs_of, rudder_of
from shipgym.dynamics.vanderklugt import open_loop_amplitudes, roll_model, seed_vessel
from shipgym.dynamics.vessel import VesselError, load_vessel
from shipgym.envs.physics import VesselPhysics

D = math.pi / 180.0


def _rudder(**kw):
    base = dict(name="r", position=(-20.0, 0.0, 2.0), lift_gain=1000.0, stall_angle=20 * D)
    return Rudder(**{**base, **kw})


@pytest.mark.parametrize("inflow", [False, True])
@pytest.mark.parametrize("post_stall", [1.0, 0.5])
def test_lift_kernel_equals_the_array_law(inflow, post_stall):
    rud = _rudder(inflow=inflow, post_stall=post_stall)
    acts = ActuatorSet([rud], dofs=4)
    flow = functools.partial(compiled_forces, acts)
    rng = np.random.default_rng(1)
    for _ in range(200):
        d = rng.uniform(-35, 35) * D
        u, v, p, r = (
            rng.uniform(-2, 10),
            rng.normal(0, 0.5),
            rng.normal(0, 0.1),
            rng.normal(0, 0.05),
        )
        X, Y, K, N, lifts, stalls = flow([d], u, v, p, r)
        assert X == 0.0  # a rudder without drag
        F = float(rud.lift(np.array([d]), np.array([u, v, p, r])))
        assert lifts[0] == pytest.approx(F, rel=1e-12, abs=1e-12)
        assert (Y, K, N) == pytest.approx((F, -2.0 * F, -20.0 * F), rel=1e-12, abs=1e-9)
        tau = acts.tau(np.array([d]), np.array([u, v, p, r]))
        np.testing.assert_allclose(tau, [0.0, F, -2.0 * F, -20.0 * F], atol=1e-9)
        alpha = d - (math.atan2(v - 20.0 * r - 2.0 * p, abs(u)) if inflow else 0.0)
        assert stalls[0] == (abs(alpha) > 20 * D)


def test_lift_grows_with_the_speed_squared_and_stalls():
    rud = _rudder()
    nu = np.array([8.0, 0.0, 0.0, 0.0])
    lift = [float(rud.lift(np.array([d * D]), nu)) for d in (5, 10, 20, 30)]
    np.testing.assert_allclose(lift[:3], [1000.0 * 64 * d * D for d in (5, 10, 20)])
    assert lift[3] == pytest.approx(lift[2])  # capped past the stall angle
    half = _rudder(post_stall=0.5)
    assert float(half.lift(np.array([30 * D]), nu)) == pytest.approx(0.5 * lift[2])
    assert float(rud.lift(np.array([10 * D]), 2 * nu)) == pytest.approx(4 * lift[1])
    with pytest.raises(ValueError, match="depends on the flow"):
        rud.force(np.array([0.1]))


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"lift_gain": 0.0}, "lift_gain"),
        ({"max_rate": -1.0}, "max_rate"),
        ({"post_stall": 1.5}, "post_stall"),
        ({"servo_time_constant": -0.1}, "servo_time_constant"),
    ],
)
def test_bad_rudders_are_refused(kw, match):
    with pytest.raises(ValueError, match=match):
        _rudder(**kw)


def test_hull4_speed_damping_and_roll_coupling_kernel_equals_the_matrix_form():
    rng = np.random.default_rng(2)
    M = np.eye(4) * [2.0e6, 3.0e6, 6.0e7, 1.0e9] + 1e5 * np.array(
        [[0, 0, 0, 0], [0, 0, -1, 2], [0, -1, 0, 0], [0, 2, 0, 0]]
    )
    h = Hull4("t", M, np.diag([5e4, 3e5, 6.9e6, 2e7]), 1.96e7, (0, 1e4, 0, 1e7), 2e6,
              D_u=rng.normal(0, 1e4, (4, 4)), phi_coupling=(5e4, 2e7))  # fmt: skip
    for _ in range(50):
        nu = rng.normal(0, 1, 4)
        tau = rng.normal(0, 1e5, 4)
        phi, uc, vc = rng.normal(0, 0.1), rng.normal(0, 0.3), rng.normal(0, 0.3)
        ref = h.nu_dot(nu, tau, [uc, vc], phi)
        got = accel_of(h)(*nu, phi, *tau, uc, vc)
        np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-12)
    with pytest.raises(ValueError, match="kinematics"):
        Hull4("t", M, np.eye(4), 1.0, kinematics="euler")


# ---- the seed's model as a MuJoCo hull --------------------------------------------------------
@pytest.mark.parametrize("U", [8.0, 13.0, 15.0])
def test_the_package_linearises_to_the_seed_state_space(U):
    """``van-der-klugt`` (D_L + |u| D_u, rudder k_L u|u| at a point) is eqs. 5-11 exactly."""
    got = roll_model_of(load_vessel("van-der-klugt"), U)
    ref = roll_model(U)
    np.testing.assert_allclose(got.A, ref.A, atol=1e-12)
    np.testing.assert_allclose(got.B, ref.B, atol=1e-14)
    p = ref.parameters
    np.testing.assert_allclose(got.G @ np.diag([p.omega_n**2, 1 / p.T_r]), ref.G, atol=1e-14)
    printed = roll_model_of(seed_vessel("printed", speed=U), U)
    np.testing.assert_allclose(printed.B, roll_model(U, kdp_law="printed").B, rtol=1e-9)


@pytest.mark.parametrize("U", [4.0, 8.0, 12.0])
def test_the_generic_linearisation_equals_the_naval_vessels_analytic_one(U):
    v = load_vessel("naval-vessel")
    rud = rudder_of(v)
    got = roll_model_of(v, U)
    A, B, G = linear_roll_model(NAVAL_VESSEL, U, rud.position[0], rud.position[2], rud.lift_gain)
    np.testing.assert_allclose(got.A, A, rtol=1e-6, atol=1e-9 * np.abs(A).max())
    np.testing.assert_allclose(got.B, B, rtol=1e-9)
    np.testing.assert_allclose(got.G, G, rtol=1e-9)
    f = roll_rhs_of(v, U)
    np.testing.assert_allclose(f(np.zeros(5), 0.0), 0.0, atol=1e-12)


def _roll_amplitude(vessel, U: float, h: float, t_end: float = 300.0) -> float:
    """The steady roll amplitude (deg) of the MuJoCo hull under 10 deg sin(0.43 t) of rudder,
    a least-squares sinusoid fitted to the last 150 s."""
    p = VesselPhysics(vessel, timestep=h)
    p.reset(eta=(0.0, 0.0, 0.0, 0.0), nu=(U, 0.0, 0.0, 0.0))
    amp, w = 10 * D, 0.43
    n = round(t_end / h)
    t, phi = [], []
    for k in range(n):
        p.set_command([amp * math.sin(w * (k + 1) * h)])
        p.step(1)
        if p.time > t_end - 150.0:
            t.append(p.time)
            phi.append(p.eta_full[2])
        assert abs(p.actuator_state[0]) <= 35 * D
    t = np.asarray(t)
    X = np.c_[np.sin(w * t), np.cos(w * t), np.ones_like(t)]
    c = np.linalg.lstsq(X, np.asarray(phi), rcond=None)[0]
    return math.degrees(math.hypot(c[0], c[1]))


@pytest.mark.parametrize(
    "U, law, expected",
    [(8.0, "U2", 1.597), (13.0, "U2", 4.041), (15.0, "U2", 5.270),
     (8.0, "printed", 0.567), (13.0, "printed", 2.306), (15.0, "printed", 3.450)],
)  # fmt: skip
def test_B4_open_loop_roll_amplitude_measured_on_the_mujoco_hull(U, law, expected):
    """Notes check B4: 10 deg at 0.43 rad/s, to 1e-3 deg, from the simulated hull."""
    vessel = seed_vessel(law, speed=U)
    got = _roll_amplitude(vessel, U, h=0.005)
    exact = math.degrees(open_loop_amplitudes(U, kdp_law=law)["phi"])
    assert got == pytest.approx(expected, abs=1e-3)
    assert got == pytest.approx(exact, abs=5e-4)  # the leapfrog step's O(h^2) error


def test_servo_never_passes_its_rate_or_angle_limit():
    """Random angle commands, beyond the limits too: |d delta| <= rate h, |delta| <= max."""
    p = VesselPhysics("van-der-klugt", timestep=0.01)
    p.reset(eta=(0.0, 0.0, 0.0, 0.0), nu=(12.0, 0.0, 0.0, 0.0))
    rud = rudder_of(p.vessel)
    rng = np.random.default_rng(3)
    prev = p.actuator_state[0]
    limited_seen = False
    for k in range(2000):
        if k % 7 == 0:
            cmd = rng.uniform(-50, 50) * D
            clipped = p.set_command([cmd])
            assert clipped[0] == (abs(cmd) > rud.max_angle)
            assert p.command[0] == pytest.approx(np.clip(cmd, -rud.max_angle, rud.max_angle))
        p.step(1)
        d = p.actuator_state[0]
        assert abs(d - prev) <= rud.max_rate * 0.01 * (1 + 1e-9)
        assert abs(d) <= rud.max_angle * (1 + 1e-12)
        # the flag: the servo still runs at its limit at the end of the step
        far = abs(p.command[0] - d) > 1e-12
        assert bool(p.rate_limited[0]) == far
        limited_seen |= far
        prev = d
    assert limited_seen


def test_an_ideal_servo_reaches_a_small_command_in_one_step():
    p = VesselPhysics("van-der-klugt", timestep=0.01)
    p.reset(eta=(0.0, 0.0, 0.0, 0.0), nu=(8.0, 0.0, 0.0, 0.0))
    p.set_command([0.05 * D])
    p.step(1)
    assert p.actuator_state[0] == pytest.approx(0.05 * D, abs=1e-15)
    assert not p.rate_limited[0]
    p.set_command([10 * D])  # 1 s at 10 deg/s
    p.step(50)
    assert p.actuator_state[0] == pytest.approx(5.05 * D, rel=1e-9) and p.rate_limited[0]
    p.step(50)
    assert p.actuator_state[0] == pytest.approx(10 * D, rel=1e-9)


def test_the_rudder_force_is_what_the_hull_feels():
    """tau_actuators = the lift law at the hull's velocity; zero speed, zero force."""
    p = VesselPhysics("naval-vessel", timestep=0.01)
    p.reset(eta=(0.0, 0.0, 0.0, 0.0), nu=(8.0, 0.0, 0.0, 0.0))
    p.set_command([0.0, 10 * D])
    p.step(200)
    rud = rudder_of(p.vessel)
    F = float(rud.lift(p.actuator_state[1:], p.nu_full))
    x, _y, z = rud.position
    tau = p.tau_actuators
    assert tau[1] == pytest.approx(F, rel=1e-12)
    assert tau[2] == pytest.approx(-z * F, rel=1e-12)
    assert tau[3] == pytest.approx(x * F, rel=1e-12)
    assert p.thrust[1] == pytest.approx(F, rel=1e-3)  # the lift at the last physics step
    assert not p.vessel.can_position and p.vessel.rudders == ("rudder",)


def _package(tmp_path: Path, rudder: str) -> Path:
    src = load_vessel("van-der-klugt").folder
    out = tmp_path / "pkg"
    out.mkdir()
    text = (src / "vessel.toml").read_text()
    head, _, tail = text.partition("[[actuator]]")
    tail = tail[tail.index("\n[roll_control]") :]
    (out / "vessel.toml").write_text(head + rudder + tail)
    (out / "vessel.xml").write_text((src / "vessel.xml").read_text())
    return out


@pytest.mark.parametrize(
    "rudder, match",
    [
        ('[[actuator]]\nname = "rudder"\nkind = "rudder"\nposition = [-1.0, 0.0, 1.0]\n'
         'lift_gain = 1e-4\narea = 1.0\nmax_angle_deg = 35.0\nmax_rate_deg = 10.0\n', "either"),
        ('[[actuator]]\nname = "rudder"\nkind = "rudder"\nposition = [-1.0, 0.0, 1.0]\n'
         'area = 1.0\nlift_slope = 3.0\nmax_angle_deg = 35.0\nmax_rate_deg = 10.0\n', "rho"),
        ('[[actuator]]\nname = "rudder"\nkind = "rudder"\nposition = [-1.0, 0.0, 1.0]\n'
         'lift_gain = 1e-4\nmax_angle_deg = 35.0\n', "max_rate_deg"),
        ('[[actuator]]\nname = "rudder"\nkind = "rudder"\nposition = [-1.0, 0.0, 1.0]\n'
         'lift_gain = 1e-4\nmax_angle_deg = 35.0\nmax_rate_deg = 10.0\ntime_constant = 1.0\n',
         "unknown key"),
    ],
)  # fmt: skip
def test_bad_rudder_tables_name_the_key(tmp_path, rudder, match):
    with pytest.raises(VesselError, match=match):
        load_vessel(_package(tmp_path, rudder))


def test_a_rudder_from_area_slope_and_density(tmp_path):
    rudder = ('[[actuator]]\nname = "rudder"\nkind = "rudder"\nposition = [-1.62, 0.0, 4.0]\n'
              'area = 2.0\nlift_slope = 3.0\nrho = 1025.0\nmax_angle_deg = 30.0\n'
              'max_rate_deg = 15.0\nstall_angle_deg = 25.0\n')  # fmt: skip
    v = load_vessel(_package(tmp_path, rudder))
    rud = rudder_of(v)
    assert rud.lift_gain == pytest.approx(0.5 * 1025.0 * 2.0 * 3.0)
    assert rud.max_rate == pytest.approx(15 * D) and rud.stall_angle == pytest.approx(25 * D)
