"""RRS design on the Van der Klugt model (seed 003 checks B6, B7), the PID autopilot and the
roll-damping controller."""

import math

import control
import numpy as np
import pytest
import scipy.linalg
import scipy.signal
from scipy.integrate import solve_ivp

from shipgym.controllers.rollcontrol import (
    RRS_WEIGHTS,
    HeadingAutopilot,
    RollDampingController,
    closed_loop,
    heading_pid_gains,
    instability_onset,
    nomoto_first_order,
    roll_ratio,
    rrs_lqr,
    scheduled_rrs_gains,
    stability_margin,
)
from shipgym.dynamics.vanderklugt import roll_model

K_PRINTED_NOTES = np.array([107.74, -5.05, -3.16, -25.07, -29.54])


@pytest.fixture(scope="module")
def K8():
    return rrs_lqr(roll_model(8.0))[0]


def test_b6_gain_at_8(K8):
    np.testing.assert_allclose(K8, K_PRINTED_NOTES, rtol=1e-2)


def test_gain_against_python_control():
    m = roll_model(8.0)
    K, S, E = rrs_lqr(m)
    Kc, Sc, Ec = control.lqr(m.A, m.B.reshape(5, 1), np.diag(RRS_WEIGHTS["Q"]), RRS_WEIGHTS["R"])
    np.testing.assert_allclose(K, np.asarray(Kc).reshape(-1), rtol=1e-8)
    np.testing.assert_allclose(S, Sc, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(np.sort_complex(E), np.sort_complex(Ec), rtol=1e-7)
    np.testing.assert_allclose(
        np.sort_complex(np.linalg.eigvals(closed_loop(m, K))), np.sort_complex(E), rtol=1e-9
    )


def test_b6_fixed_gain_is_stable_on_2_to_30(K8):
    margins = [stability_margin(roll_model(U), K8) for U in np.linspace(2.0, 30.0, 141)]
    assert max(margins) < 0
    assert instability_onset(K8, 1.0) is None


@pytest.mark.parametrize(("U", "ratio"), [(8.0, 0.172), (13.0, 0.076), (15.0, 0.059)])
def test_b6_roll_ratio(K8, U, ratio):
    assert roll_ratio(roll_model(U), K8) == pytest.approx(ratio, abs=0.01)


def test_roll_ratio_against_a_simulation(K8):
    """The closed-loop roll amplitude from scipy's lsim of the loop, steady tail."""
    m = roll_model(13.0)
    Acl = closed_loop(m, K8)
    t = np.arange(0.0, 300.0, 0.02)
    u = math.radians(10) * np.sin(0.43 * t)
    _, y_cl, _ = scipy.signal.lsim((Acl, m.B.reshape(5, 1), np.eye(5), np.zeros((5, 1))), u, t)
    _, y_ol, _ = scipy.signal.lsim((m.A, m.B.reshape(5, 1), np.eye(5), np.zeros((5, 1))), u, t)
    tail = t > 200
    ratio = np.ptp(y_cl[tail, 4]) / np.ptp(y_ol[tail, 4])
    assert ratio == pytest.approx(roll_ratio(m, K8), rel=5e-3)


def test_b7_onset_without_sway_feedback(K8):
    onset = instability_onset(K8, 0.0)
    assert onset is not None
    assert onset.speed == pytest.approx(8.75, abs=0.1)
    assert onset.frequency == pytest.approx(0.075, abs=0.01)  # oscillatory, ~84 s period
    # stable just below, unstable just above (independent of the bisection)
    assert stability_margin(roll_model(onset.speed - 0.05), K8, 0.0) < 0
    assert stability_margin(roll_model(onset.speed + 0.05), K8, 0.0) > 0
    # notes: +0.027 +- 0.075j at 15 m/s
    eig = np.linalg.eigvals(closed_loop(roll_model(15.0), K8, 0.0))
    worst = eig[np.argmax(eig.real)]
    assert worst.real == pytest.approx(0.027, abs=2e-3)
    assert abs(worst.imag) == pytest.approx(0.075, abs=5e-3)


def test_b7_onset_with_a_fifth_of_the_sway_gain(K8):
    onset = instability_onset(K8, 0.2)
    assert onset is not None
    assert onset.speed == pytest.approx(15.7, abs=0.1)
    assert 0.05 < onset.frequency < 0.1
    assert instability_onset(K8, 0.6) is None


def test_onset_on_a_loop_unstable_everywhere():
    onset = instability_onset(np.zeros(5), 1.0, speeds=(2.0, 10.0))  # psi integrator: margin 0
    assert onset is not None and onset.speed == 2.0


def test_scheduled_gains_interpolate_and_match_the_design():
    sched = scheduled_rrs_gains([6.0, 8.0, 12.0])
    np.testing.assert_allclose(sched(8.0), rrs_lqr(roll_model(8.0))[0], rtol=1e-12)
    np.testing.assert_allclose(sched(10.0), 0.5 * (sched(8.0) + sched(12.0)), rtol=1e-12)
    np.testing.assert_allclose(sched(40.0), sched(12.0))
    for U in (6.0, 9.0, 12.0):
        assert stability_margin(roll_model(U), sched(U)) < 0
    with pytest.raises(ValueError, match="increasing"):
        scheduled_rrs_gains([8.0, 6.0])


def test_nomoto_first_order_is_t1_plus_t2_minus_t3():
    for U in (4.0, 8.0, 15.0):
        m = roll_model(U)
        p = m.parameters
        K = p.K_dr + p.K_vr * p.K_dv
        T = p.T_v + p.T_r - p.K_dr * p.T_v / K
        assert nomoto_first_order(m) == pytest.approx((K, T), rel=1e-12)


@pytest.mark.parametrize("nomoto", ["direct", "first-order"])
def test_heading_pid_pole_placement(nomoto):
    m = roll_model(8.0)
    w, zeta = 0.15, 0.9
    g = heading_pid_gains(m, w, zeta, nomoto=nomoto)
    if nomoto == "direct":
        a, b = -m.A[1, 1], m.B[1]
    else:
        K, T = nomoto_first_order(m)
        a, b = 1 / T, K / T
    # closed loop of the Nomoto part with the state [z = int e, psi, r] and delta = -(...)
    Acl = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-b * g.ki, -b * g.kp, -a - b * g.kd]])
    expected = np.roots(np.polymul([1.0, 2 * zeta * w, w**2], [1.0, 0.1 * w]))
    np.testing.assert_allclose(
        np.sort_complex(np.linalg.eigvals(Acl)), np.sort_complex(expected), atol=1e-9
    )
    assert g.kp < 0 and g.ki < 0  # the rudder turns the ship to port for delta > 0 (K_dr < 0)


@pytest.mark.parametrize("U", [2.0, 8.0, 15.0, 25.0])
@pytest.mark.parametrize("w", [0.05, 0.1, 0.3])
def test_heading_pid_stabilises_the_full_model(U, w):
    """The first-order Nomoto design on the whole 5-state model plus the integrator state."""
    m = roll_model(U)
    g = heading_pid_gains(m, w)
    A = np.zeros((6, 6))
    A[:5, :5], A[5, 2] = m.A, 1.0
    gain = np.array([0.0, g.kd, g.kp, 0.0, 0.0, g.ki])
    assert np.max(np.linalg.eigvals(A - np.outer(np.r_[m.B, 0.0], gain)).real) < 0


def _simulate_heading(m, pilot, psi0, t_end=400.0, dt=0.1):
    x = np.array([0.0, 0.0, psi0, 0.0, 0.0])
    aug = np.zeros((6, 6))
    aug[:5, :5], aug[:5, 5] = m.A, m.B
    E = scipy.linalg.expm(aug * dt)
    Ad, Bd = E[:5, :5], E[:5, 5]
    out = []
    for k in range(int(t_end / dt)):
        d = pilot(k * dt, m.C @ x)
        x = Ad @ x + Bd * d
        out.append((x.copy(), d))
    return np.array([o[0] for o in out]), np.array([o[1] for o in out])


def test_heading_autopilot_holds_heading_on_the_full_model():
    m = roll_model(8.0)
    g = heading_pid_gains(m, 0.1, 1.0)
    pilot = HeadingAutopilot(*g, delta_max=math.radians(35))
    xs, ds = _simulate_heading(m, pilot, math.radians(5))
    assert abs(xs[-1, 2]) < math.radians(0.05)
    assert np.max(np.abs(ds)) <= math.radians(35) + 1e-12
    # signs: a positive heading error gives a positive rudder (K_dr < 0 turns to port)
    pilot.reset()
    assert pilot(0.0, [0.0, math.radians(5), 0.0, 0.0]) > 0


def test_heading_autopilot_anti_windup():
    m = roll_model(8.0)
    g = heading_pid_gains(m, 0.1, 1.0)
    lim = math.radians(2)
    clamped = HeadingAutopilot(*g, delta_max=lim)
    xs, ds = _simulate_heading(m, clamped, math.radians(40), t_end=800.0)
    assert np.max(np.abs(ds)) <= lim + 1e-12
    assert abs(xs[-1, 2]) < math.radians(0.5)
    # the integral stays bounded while saturated: the overshoot is small
    assert np.min(xs[:, 2]) > -math.radians(8)
    with pytest.raises(ValueError, match="delta_max"):
        HeadingAutopilot(*g, delta_max=0.0)
    with pytest.raises(ValueError, match=r"\[r, psi, p, phi\]"):
        clamped(0.0, [1.0, 2.0])


def test_roll_damping_controller_is_the_lqr_law(K8):
    ctl = RollDampingController(K8, sway_scale=0.2, delta_max=math.radians(35), psi_d=0.1)
    x = np.array([0.001, 0.0002, 0.11, 0.001, 0.002])
    Kp = K8.copy()
    Kp[0] *= 0.2
    e = x - np.array([0, 0, 0.1, 0, 0])
    assert ctl(0.0, x) == pytest.approx(-Kp @ e)
    # heading wrap: psi = pi - 0.01 against psi_d = -pi + 0.01 is a -0.02 rad error
    x2 = np.array([0, 0, math.pi - 0.01, 0, 0])
    assert ctl(0.0, x2, psi_d=-math.pi + 0.01) == pytest.approx(-K8[2] * -0.02)
    assert abs(ctl(0.0, [0, 0, 0, 1.0, 0])) == pytest.approx(math.radians(35))
    sched = scheduled_rrs_gains([8.0, 15.0])
    sc = RollDampingController(schedule=sched)
    assert sc(0.0, x, U=15.0) == pytest.approx(-sched(15.0) @ x)
    with pytest.raises(ValueError, match="speed U"):
        sc(0.0, x)
    with pytest.raises(ValueError, match="K"):
        RollDampingController()


def test_rrs_reduces_roll_in_a_time_simulation(K8):
    """The controller in the loop of the continuous plant (solve_ivp), with the seed's rudder
    disturbance added to its command: the roll amplitude is roll_ratio x the open loop."""
    m = roll_model(8.0)
    ctl = RollDampingController(K8)

    def f(t, x, closed):
        d = math.radians(10) * math.sin(0.43 * t) + (ctl(t, x) if closed else 0.0)
        return m.A @ x + m.B * d

    amps = []
    for closed in (False, True):
        sol = solve_ivp(
            f,
            (0, 250),
            np.zeros(5),
            args=(closed,),
            max_step=0.1,
            rtol=1e-8,
            atol=1e-11,
            t_eval=np.arange(150, 250, 0.05),
        )
        amps.append(0.5 * np.ptp(sol.y[4]))
    assert amps[1] / amps[0] == pytest.approx(roll_ratio(m, K8), rel=1e-2)


def test_errors():
    m = roll_model(8.0)
    with pytest.raises(ValueError, match="5 finite gains"):
        closed_loop(m, [1.0, 2.0])
    with pytest.raises(ValueError, match="omega"):
        roll_ratio(m, np.zeros(5), omega=0.0)
    with pytest.raises(ValueError, match="speeds"):
        instability_onset(np.zeros(5), 0.0, speeds=(10.0, 2.0))
    with pytest.raises(ValueError, match="first-order"):
        heading_pid_gains(m, 0.1, nomoto="second")
    with pytest.raises(ValueError, match="bandwidth"):
        heading_pid_gains(m, -1.0)
    with pytest.raises(ValueError, match="sway_scale"):
        closed_loop(m, np.zeros(5), math.nan)
