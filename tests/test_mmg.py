"""The MMG model (Yasukawa & Yoshimura 2015) of the KVLCC2, scaled to the seed's 100 m
tanker (Artyszuk 2003), against the notes' independent computation (checks C4, C5) and
the bugs of open implementations that it must not have."""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pytest
from _helpers import accel_of, compiled_forces
from scipy.integrate import solve_ivp

from shipgym.dynamics.mmg import KVLCC2_L7, MMGModel, MMGParameters, kvlcc2

D = math.pi / 180.0
RATE = 2.32 * D  # IMO: 35 deg one side to 30 deg the other in 28 s


@pytest.fixture(scope="module")
def tanker():
    m = MMGModel(kvlcc2(100.0))
    return m, m.self_propulsion(7.0)


def test_the_100_m_tanker(tanker):
    m, n = tanker
    assert m.m / 1e3 == pytest.approx(9772, abs=1)  # t
    assert n == pytest.approx(4.926, abs=1e-3)  # rps for 7 m/s (295.5 rpm)
    p = m.p
    assert (p.B, p.d, p.D_P, p.A_R) == pytest.approx((18.14, 6.57, 3.09, 11.00), abs=0.01)


def test_C4_turning_circle_35_deg(tanker):
    """Advance 3.37 L and tactical diameter 3.14 L (+-0.05 L); 90 deg at 66 s, steady speed
    2.68 m/s, steady drift angle 19.0 deg (the notes' computation from the same paper)."""
    m, n = tanker

    def rhs(t, x):
        u, v, r, _x, _y, psi = x
        ud, vd, rd = m.nu_dot([u, v, r], min(RATE * t, 35 * D), n)
        c, s = math.cos(psi), math.sin(psi)
        return [ud, vd, rd, u * c - v * s, u * s + v * c, r]

    sol = solve_ivp(rhs, (0, 400), [7.0, 0, 0, 0, 0, 0], rtol=1e-9, atol=1e-9,
                    dense_output=True, max_step=1.0)  # fmt: skip
    t = np.linspace(0, 400, 40001)
    u, v, r, x, y, psi = sol.sol(t)
    i90, i180 = np.argmax(psi >= math.pi / 2), np.argmax(psi >= math.pi)
    assert x[i90] / 100 == pytest.approx(3.37, abs=0.05)
    assert y[i180] / 100 == pytest.approx(3.14, abs=0.05)
    assert t[i90] == pytest.approx(66.0, abs=1.0)
    assert math.hypot(u[-1], v[-1]) == pytest.approx(2.68, abs=0.02)
    assert math.degrees(math.atan2(-v[-1], u[-1])) == pytest.approx(19.0, abs=0.2)
    assert r.max() / D == pytest.approx(1.84, abs=0.02) and r[-1] > 0  # to starboard


def _zigzag(m, n, angle):
    """First overshoot (deg) of the angle/angle zigzag (IMO MSC.137(76)), RK4 at 0.05 s."""
    h, x, d, target = 0.05, np.array([7.0, 0.0, 0.0, 0.0]), 0.0, angle * D  # u, v, r, psi

    def f(s, d):
        return np.r_[m.nu_dot(s[:3], d, n), s[2]]

    over, switched = 0.0, False
    for _ in range(int(400 / h)):
        d += float(np.clip(target - d, -RATE * h, RATE * h))
        k1 = f(x, d)
        k2 = f(x + 0.5 * h * k1, d)
        k3 = f(x + 0.5 * h * k2, d)
        k4 = f(x + h * k3, d)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if not switched and x[3] >= angle * D:  # the first execute: counter-rudder
            target, switched = -angle * D, True
        if switched:
            over = max(over, x[3] / D - angle)
            if x[2] < 0:  # the heading turned back: the first overshoot is over
                break
    return over


@pytest.mark.parametrize("angle, first", [(10.0, 7.4), (20.0, 18.3)])
def test_C5_zigzag_first_overshoot(tanker, angle, first):
    m, n = tanker
    assert _zigzag(m, n, angle) == pytest.approx(first, abs=0.5)


def test_no_wake_bracket_bug_and_x_R_is_a_length():
    """mmgdynamics/TUD_RL: ``1 - exp(-C1|b|)*(C2 - 1)`` (wrong bracket) and ``x_R`` without
    its factor L; here ``1 - w_P = 1 - w_P0`` straight ahead, and ``N_R/Y_R`` is the lever."""
    m = MMGModel(KVLCC2_L7)
    p = m.p
    assert float(m.wake(np.array(0.0))) == pytest.approx(1 - p.w_P0, abs=1e-15)
    b = 0.2
    want = (1 - p.w_P0) * (1 + (1 - math.exp(-p.C1 * b)) * (p.C2_pos - 1))
    assert float(m.wake(np.array(b))) == pytest.approx(want, rel=1e-14)
    _, _, _, parts = m.forces([1.179, 0.0, 0.0], 20 * D, 10.0)
    lever = (p.x_R + p.a_H * p.x_H) * p.L / (1 + p.a_H)
    assert float(parts["N_R"] / parts["Y_R"]) == pytest.approx(lever, rel=1e-12)
    assert float(parts["F_N"]) > 0 and float(parts["N_R"]) > 0  # positive rudder: starboard


def test_batched_and_astern():
    m = MMGModel(kvlcc2(100.0))
    rng = np.random.default_rng(0)
    nu = np.c_[rng.uniform(1, 8, 20), rng.normal(0, 0.5, 20), rng.normal(0, 0.02, 20)]
    delta, n = rng.uniform(-0.6, 0.6, 20), rng.uniform(-5, 5, 20)
    batch = m.nu_dot(nu, delta, n)
    one = np.array([m.nu_dot(nu[i], delta[i], n[i]) for i in range(20)])
    np.testing.assert_allclose(batch, one, rtol=1e-13, atol=1e-15)
    # astern: the propeller pulls back, and the rudder has no slipstream
    _, _, _, a = m.forces([5.0, 0.0, 0.0], 0.0, -4.0)
    assert float(a["X_P"]) < 0 and float(a["u_R"]) == pytest.approx(
        m.p.eps * 5.0 * float(m.wake(np.array(0.0))), rel=1e-12
    )
    import dataclasses

    with pytest.raises(ValueError, match="must be > 0"):
        dataclasses.replace(KVLCC2_L7, L=0.0)
    with pytest.raises(TypeError):  # no ship is a default: every coefficient is required
        MMGParameters(L=7.0, B=1.27, d=0.46, nabla=3.27, x_G=0.25, D_P=0.2, H_R=0.3, A_R=0.05)


# ---- the MMG hull and unit in shipgym: compiled laws against the array forms --------------
@pytest.mark.parametrize("rudder", [None, "schilling"])
def test_kernels_equal_the_array_forms(rudder):
    """The unit's compiled force law (law_mmg) and the hull's compiled acceleration
    (accel_mmg) against propulsion_forces and MMGHull.nu_dot (random states, ahead, stopped
    and astern, with current; the MMG rudder and the Schilling option past its stall)."""
    from shipgym.dynamics.actuators import ActuatorSet, MMGPropulsion
    from shipgym.dynamics.mmg import MMGHull

    p = dataclasses.replace(kvlcc2(100.0), c_y=0.1, c_y_brake=0.05)
    p = p if rudder is None else p.with_rudder(rudder)
    m, hull = MMGModel(p), MMGHull(p)
    unit = ActuatorSet([MMGPropulsion("prop", p, max_rps=10.0, min_rps=-10.0)])
    acc = accel_of(hull)
    rng = np.random.default_rng(3)
    for k in range(300):
        nu = np.array([rng.uniform(-1, 8), rng.normal(0, 1), rng.normal(0, 0.02)])
        delta, n = rng.uniform(-1.3, 1.3), rng.uniform(-6, 6) if k % 5 else 0.0
        X, Y, N, parts = m.propulsion_forces(nu, delta, n)
        # the unit's states [n, delta]: shipgym's rudder angle is the paper's -delta
        gx, gy, _gk, gn, T, _ = compiled_forces(unit, [n, -delta], nu[0], nu[1], 0.0, nu[2])
        np.testing.assert_allclose((gx, gy, gn, T[0]), (X, Y, N, parts["T"]), rtol=1e-12,
                                   atol=1e-6)  # fmt: skip
        tau = rng.normal(0, 1e5, 3)
        nc = np.array([rng.normal(0, 0.3), rng.normal(0, 0.3), 0.0])
        np.testing.assert_allclose(
            acc(*nu, *tau, nc[0], nc[1]), hull.nu_dot(nu, tau, nc), rtol=1e-9, atol=1e-12
        )


def test_mmg_hull_without_current_is_the_papers_equations():
    """MMGHull.nu_dot with no current equals MMGModel.nu_dot (Yasukawa & Yoshimura 2015
    eq. 4) with the unit's force added as tau."""
    from shipgym.dynamics.mmg import MMGHull

    p = kvlcc2(100.0)
    m, hull = MMGModel(p), MMGHull(p)
    nu = np.array([[6.5, -0.4, 0.01], [3.0, 0.8, -0.02]])
    delta, n = np.array([0.3, -0.5]), np.array([4.9, 3.0])
    X, Y, N, _ = m.propulsion_forces(nu, delta, n)
    np.testing.assert_allclose(
        hull.nu_dot(nu, np.stack([X, Y, N], -1)), m.nu_dot(nu, delta, n), rtol=1e-10
    )


def test_the_unit_uses_shipgyms_rudder_sign():
    """In the vessel's actuator set, a positive rudder angle pushes the stern to starboard
    (Y > 0) and turns the bow to port (N < 0): the paper's angle is its negative."""
    from shipgym.dynamics.vessel import load_vessel

    acts = load_vessel("kvlcc2-100m").actuators
    tau = acts.tau(np.array([4.926, math.radians(20)]), np.array([7.0, 0.0, 0.0]))
    assert tau[1] > 0 and tau[2] < 0
    X, Y, N, _ = MMGModel(kvlcc2(100.0)).propulsion_forces([7.0, 0.0, 0.0], -math.radians(20),
                                                            4.926)  # fmt: skip
    np.testing.assert_allclose(tau, [X, Y, N], rtol=1e-12)
    flow = functools.partial(compiled_forces, acts)
    out = flow([4.926, math.radians(20)], 7.0, 0.0, 0.0, 0.0)
    np.testing.assert_allclose(out[:4], [tau[0], tau[1], 0.0, tau[2]], rtol=1e-12)


def test_vessel_file_mistakes_are_named(tmp_path):
    """An mmg unit on a non-mmg hull, a misspelt coefficient and an mmg hull with 4 DOF are
    refused with the key named."""
    import shutil

    from shipgym.dynamics.vessel import VesselError, load_vessel

    src = load_vessel("kvlcc2-100m").folder
    text = (src / "vessel.toml").read_text()

    def pkg(name, new):
        d = tmp_path / name
        shutil.copytree(src, d)
        (d / "vessel.toml").write_text(new)
        return d

    with pytest.raises(VesselError, match="hull.Y_vv: unknown key"):
        load_vessel(pkg("a", text.replace("\nY_vvv = ", "\nY_vv = ")))
    with pytest.raises(VesselError, match="3-DOF family"):
        load_vessel(pkg("b", text.replace("dofs = 3", "dofs = 4")))
    with pytest.raises(VesselError, match="actuator.propeller.max_rps: missing"):
        load_vessel(pkg("c", "\n".join(line for line in text.splitlines()
                                       if not line.startswith("max_rps"))))  # fmt: skip
    blue = (load_vessel("blue-lady").folder / "vessel.toml").read_text()
    unit = text[text.index("[[actuator]]") : text.index("[limits]")]
    with pytest.raises(VesselError, match="needs an 'mmg' hull"):
        load_vessel(pkg("d", blue + "\n" + unit.replace("[-48.0, 0.0, 3.2857143]",
                                                        "[-5.0, 0.0, 0.5]")))  # fmt: skip


# ---- the rudder's normal-force law and the propeller's side force ---------------------------
def test_rudder_normal_coefficient_is_the_mmg_law_without_stall_and_holds_past_it():
    """No stall (the MMG standard, every ship's default): ``f_alpha sin alpha_R`` at every
    angle, from astern too; the Schilling option: Fujii's slope ratio for an effective aspect
    ratio doubled by the end plates (by hand: Lambda = 0.345^2 / 0.0539 = 2.2083, Fujii 3.0363
    and 4.0611 at 2 Lambda: f_alpha 2.747 x 1.3375 = 3.6741), the sine law to 70 deg, then
    0.7 of the stall's value."""
    from shipgym.dynamics.mmg import (
        RUDDER_OPTIONS,
        fujii_f_alpha,
        rudder_normal_coefficient,
        rudder_normal_coefficients,
    )

    p = kvlcc2(100.0)
    a = np.linspace(-math.pi, math.pi, 721)
    np.testing.assert_allclose(rudder_normal_coefficients(a, p), 2.747 * np.sin(a), rtol=1e-15)
    assert fujii_f_alpha(2.2083) == pytest.approx(6.13 * 2.2083 / 4.4583, rel=1e-12)
    s = p.with_rudder("schilling")
    assert s.aspect_ratio == pytest.approx(0.345**2 / 0.0539, rel=1e-12)
    assert s.f_alpha == pytest.approx(2.747 * (6.13 * 4.4165 / 6.6665) / (6.13 * 2.20825 / 4.45825),
                                      rel=1e-4)  # fmt: skip
    assert s.f_alpha / p.f_alpha == pytest.approx(1.337, abs=1e-3)
    assert (s.stall_angle, s.post_stall) == (math.radians(70.0), 0.7)
    assert RUDDER_OPTIONS["schilling"].max_angle == pytest.approx(math.radians(65.0))
    deg = np.radians(np.arange(0.0, 90.1, 1.0))
    cn = rudder_normal_coefficients(deg, s)
    up = deg <= math.radians(70.0) + 1e-12
    np.testing.assert_allclose(cn[up], s.f_alpha * np.sin(deg[up]), rtol=1e-15)
    assert np.all(np.diff(cn[up]) > 0)  # no stall to 70 deg: the force grows to it
    np.testing.assert_allclose(cn[~up], 0.7 * s.f_alpha * math.sin(math.radians(70.0)))
    # at the 65 deg rudder the Schilling's coefficient is 2.11x the MMG rudder's at 35 deg
    assert rudder_normal_coefficient(math.radians(65), s.f_alpha, s.stall_angle, 0.7) / (
        2.747 * math.sin(math.radians(35))
    ) == pytest.approx(2.11, abs=0.01)
    # symmetric; a flow from astern is folded: 180 deg - 80 deg is past the stall as 80 deg is
    assert rudder_normal_coefficients(-deg, s) == pytest.approx(-cn)
    assert rudder_normal_coefficient(math.radians(100.0), s.f_alpha, s.stall_angle, 0.7) == (
        pytest.approx(cn[80])
    )
    for bad in ({"stall_angle": 0.0}, {"post_stall": 1.5}, {"c_y_brake": -0.1},
                {"stall_angle": math.nan}):  # fmt: skip
        with pytest.raises(ValueError, match="MMGParameters"):
            dataclasses.replace(p, **bad)
    with pytest.raises(ValueError, match="unknown rudder option 'flap'; valid: schilling"):
        p.with_rudder("flap")


def test_propeller_side_force_turns_a_crash_stop_to_starboard_and_a_coasting_stop_to_port():
    """A right-handed screw (Artyszuk 2003 section 3): astern the stern goes to port, the bow
    to starboard (N > 0); the shaft stopped at speed (the seed's zero pitch) drags and pushes
    the stern to starboard, the bow to port (N < 0); ahead, working: no side force."""
    p = dataclasses.replace(kvlcc2(100.0), c_y=0.1, c_y_brake=0.05)
    m = MMGModel(p)
    nu = [6.0, 0.0, 0.0]
    _, _, _, astern = m.propulsion_forces(nu, 0.0, -4.9)
    _, _, _, stopped = m.propulsion_forces(nu, 0.0, 0.0)
    _, _, _, ahead = m.propulsion_forces(nu, 0.0, 4.9)
    assert astern["X_P"] < 0 and astern["N_P"] > 0
    assert astern["Y_P"] == pytest.approx(-0.1 * abs(astern["X_P"]), rel=1e-12)
    # the stopped propeller's drag: the K_T polynomial's limit rho k2 D^2 u_a^2 (1 - t_P)
    ua = 6.0 * (1 - p.w_P0)
    drag = (1 - p.t_P) * p.rho * p.k2 * p.D_P**2 * ua**2
    assert stopped["X_P"] == pytest.approx(drag, rel=1e-12) and drag < 0
    assert stopped["Y_P"] == pytest.approx(0.05 * abs(drag), rel=1e-12) and stopped["N_P"] < 0
    assert ahead["X_P"] > 0 and ahead["Y_P"] == 0.0
    # continuous in n down to the stop (the thrust law divides by no n)
    _, _, _, slow = m.propulsion_forces(nu, 0.0, 1e-7)
    assert slow["X_P"] == pytest.approx(stopped["X_P"], rel=1e-6)
