"""The Blanke & Christensen (1993) naval vessel (``shipgym.dynamics.blanke4``).

Independent references: the printed numbers of ``navalvessel.m`` recomputed by hand, SciPy's
``solve_ivp`` on the matrix form against a fixed-step RK4 on the scalar kernel, the uncoupled
roll oscillator's analytic eigenvalues, central differences against the analytic Jacobian.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from _helpers import accel_of
from scipy.integrate import solve_ivp

from shipgym.dynamics.blanke4 import (
    NAVAL_VESSEL,
    Blanke4Hull,
    linear_roll_model,
    roll_damping_ratio,
    roll_natural_frequency,
    roll_rhs,
    surge_thrust,
)

H = NAVAL_VESSEL
# the rudder of the package (shipgym/assets/mjcf/naval_vessel/vessel.toml): x = -L/2, z 1.55 m
# below the waterline origin; lift gain 0.5 rho A dC_L/dalpha = 0.5 1014 1.5 (0.054 180/pi)
X_R, Z_R = -25.75, 1.55
LIFT = 0.5 * 1014.0 * 1.5 * 0.054 * 180.0 / math.pi


def test_printed_numbers():
    m = 1014.0 * 357.0  # rho nabla, navalvessel.m
    assert H.m == pytest.approx(m, rel=1e-15)
    assert H.K_phi == pytest.approx(1014.0 * 9.81 * 357.0 * 1.1, rel=1e-15)
    assert H.z_G == pytest.approx(-1.06, rel=1e-12)
    assert H.X_vr == pytest.approx(0.33 * m) and H.K_phphph == pytest.approx(-0.325 * m * 9.81)
    # the notes' estimate: about 1.1 rad/s
    w = math.sqrt(1014.0 * 9.81 * 357.0 * 1.1 / (2.3763e6 + 774000.0))
    assert roll_natural_frequency(H) == pytest.approx(w, rel=1e-14)
    assert 1.05 < w < 1.15
    assert H.dofs == 4
    M = H.mass_matrix()
    assert M.shape == (4, 4)
    assert M[0, 0] == pytest.approx(m + 17400.0)
    assert M[1, 3] == pytest.approx(m * -3.38 + 1.4e6)
    assert M[2, 1] == pytest.approx(-(m * -1.06 + 296000.0))
    assert M[3, 3] == pytest.approx(47.934e6 + 38.7e6)


def test_kernel_equals_matrix_form_on_random_states():
    rng = np.random.default_rng(3)
    n = 200
    nu = rng.normal(size=(n, 4)) * [4.0, 1.0, 0.2, 0.1] + [6.0, 0, 0, 0]
    tau = rng.normal(size=(n, 4)) * [1e5, 5e4, 1e5, 1e6]
    nc = rng.normal(size=(n, 2)) * 0.5
    phi = rng.normal(size=n) * 0.2
    ref = H.nu_dot(nu, tau, nc, phi)
    for i in range(n):
        got = accel_of(H)(*nu[i].tolist(), float(phi[i]), *tau[i].tolist(), *nc[i].tolist())
        assert all(type(g) is float for g in got)
        np.testing.assert_allclose(got, ref[i], rtol=1e-12, atol=1e-12 * np.abs(ref[i]).max())
    # without current, a single state, and the 4-vector current form
    one = H.nu_dot(nu[0], tau[0], np.r_[nc[0], 0, 0], phi[0])
    np.testing.assert_allclose(one, ref[0], rtol=1e-14)
    np.testing.assert_allclose(
        accel_of(H)(*nu[1], phi[1], *tau[1]), H.nu_dot(nu[1], tau[1], phi=phi[1]), rtol=1e-12
    )


def test_current_enters_through_the_relative_velocity():
    # a hull moving with the water (nu = nu_c, p = r = phi = 0) feels no hydrodynamic force
    acc = H.nu_dot([1.3, -0.4, 0.0, 0.0], np.zeros(4), [1.3, -0.4], 0.0)
    np.testing.assert_allclose(acc, 0.0, atol=1e-15)
    assert np.abs(H.nu_dot([1.3, -0.4, 0.0, 0.0], np.zeros(4))).max() > 1e-4


def test_surge_thrust_holds_the_speed():
    for U in (4.0, 8.0, 10.0):
        X = surge_thrust(H, U)
        assert X == pytest.approx(1.96e3 * U * U, rel=1e-14)
        acc = H.nu_dot([U, 0.0, 0.0, 0.0], [X, 0.0, 0.0, 0.0])
        np.testing.assert_allclose(acc, 0.0, atol=1e-14)


@pytest.mark.parametrize("U", [4.0, 8.0, 12.0])
def test_linearisation_analytic_equals_central_differences(U):
    A, B, G = linear_roll_model(H, U, X_R, Z_R, LIFT)
    An, Bn, Gn = linear_roll_model(H, U, X_R, Z_R, LIFT, method="numerical")
    for a, b in ((A, An), (B, Bn), (G, Gn)):
        nz = np.abs(a) > 0
        np.testing.assert_allclose(b[nz], a[nz], rtol=1e-6)
        np.testing.assert_allclose(b[~nz], 0.0, atol=1e-9 * np.abs(a).max())
    # psi enters kinematically: psi_dot = r (at phi = 0), and nothing depends on psi
    np.testing.assert_array_equal(A[2], [0.0, 1.0, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(A[:, 2], 0.0)
    np.testing.assert_array_equal(A[4], [0.0, 0.0, 0.0, 1.0, 0.0])
    assert B[2] == B[4] == 0.0 and not G[2].any() and not G[4].any()
    # G is the (v, p, r) block of M^-1 for a roll and a yaw moment
    Mi = np.linalg.inv(H.mass_matrix()[1:, 1:])
    np.testing.assert_allclose(G[[0, 3, 1]], Mi[:, 1:], rtol=1e-14)
    # B: the rudder force lift U^2 at (x_R, z_R): [Y, K, N] = [1, -z_R, x_R] lift U^2
    np.testing.assert_allclose(
        B[[0, 3, 1]], Mi @ np.array([1.0, -Z_R, X_R]) * LIFT * U * U, rtol=1e-14
    )


def test_decoupled_roll_mode_matches_the_oscillator_formula():
    # with the roll row freed of sway and yaw (z_G, K_vdot, K_rdot, K_|u|v, K_ur = 0) the roll
    # mode is exactly (I_xx - K_pdot) p_dot = (K_p + K_|u|p U) p - (rho g nabla GM - K_phuu U^2) phi
    h0 = dataclasses.replace(H, z_G=0.0, K_vdot=0.0, K_rdot=0.0, K_auv=0.0, K_ur=0.0)
    U = 8.0
    A, _, _ = linear_roll_model(h0, U, X_R, Z_R, LIFT)
    I = 2.3763e6 + 774000.0
    k = 1014.0 * 9.81 * 357.0 * 1.1 + 1180.0 * U * U
    c = 500000.0 + 15500.0 * U
    lam = (-c + 1j * math.sqrt(4 * k * I - c * c)) / (2 * I)
    ev = np.linalg.eigvals(A)
    assert np.min(np.abs(ev - lam)) < 1e-12
    wn, zeta = abs(lam), -lam.real / abs(lam)
    assert roll_damping_ratio(H, U) == pytest.approx(zeta, rel=1e-12)
    assert math.sqrt(k / I) == pytest.approx(wn, rel=1e-12)


def _decay_reference(phi0: float, U: float, t_end: float) -> tuple[np.ndarray, np.ndarray]:
    def rhs(t, y):
        v, p, r, phi, psi = y
        acc = H.nu_dot([U, v, p, r], np.zeros(4), phi=phi)
        return [acc[1], acc[2], acc[3], p, r * math.cos(phi)]

    t = np.arange(0.0, t_end + 1e-9, 0.01)
    sol = solve_ivp(rhs, (0, t_end), [0, 0, 0, phi0, 0], "RK45", t, rtol=1e-10, atol=1e-12)
    return sol.t, sol.y


def _decay_rk4(phi0: float, U: float, t_end: float, dt: float) -> np.ndarray:
    acc = accel_of(H)

    def f(y):
        v, p, r, phi, _ = y
        _, vd, pd, rd = acc(U, v, p, r, phi, 0.0, 0.0, 0.0, 0.0)
        return (vd, pd, rd, p, r * math.cos(phi))

    y = (0.0, 0.0, 0.0, phi0, 0.0)
    out = [y]
    for _ in range(round(t_end / dt)):
        k1 = f(y)
        k2 = f(tuple(a + 0.5 * dt * b for a, b in zip(y, k1, strict=True)))
        k3 = f(tuple(a + 0.5 * dt * b for a, b in zip(y, k2, strict=True)))
        k4 = f(tuple(a + dt * b for a, b in zip(y, k3, strict=True)))
        y = tuple(
            a + dt / 6.0 * (b1 + 2 * b2 + 2 * b3 + b4)
            for a, b1, b2, b3, b4 in zip(y, k1, k2, k3, k4, strict=True)
        )
        out.append(y)
    return np.array(out).T


def test_roll_decay_kernel_rk4_matches_solve_ivp_and_the_linear_mode():
    U, phi0, t_end = 8.0, math.radians(5.0), 30.0
    t, ref = _decay_reference(phi0, U, t_end)
    got = _decay_rk4(phi0, U, t_end, 0.01)
    assert np.abs(got[3] - ref[3]).max() < 1e-8  # roll (rad)
    assert np.abs(got[0] - ref[0]).max() < 1e-8  # sway (m/s)
    # it decays
    assert np.abs(ref[3][t > 25]).max() < 0.2 * phi0
    # the period of the nonlinear decay is the linear model's roll mode (5 deg: small)
    A, _, _ = linear_roll_model(H, U, X_R, Z_R, LIFT)
    ev = np.linalg.eigvals(A)
    lam = ev[np.argmax(ev.imag)]
    phi = ref[3]
    up = np.flatnonzero((phi[:-1] < 0) & (phi[1:] >= 0))
    tc = t[up] - phi[up] * (t[up + 1] - t[up]) / (phi[up + 1] - phi[up])
    w_sim = 2 * math.pi / np.mean(np.diff(tc))
    assert w_sim == pytest.approx(lam.imag, rel=0.02)


def test_steady_turn_signs():
    # positive rudder lift: +Y at the stern (x < 0): the bow swings to port (r < 0), the hull
    # first heels inwards (K = -z_R Y < 0: port down) and settles heeled outwards (phi > 0)
    f = roll_rhs(H, 8.0, X_R, Z_R, LIFT)
    delta = math.radians(10.0)
    x0 = np.zeros(5)
    assert f(x0, delta)[1] < 0 and f(x0, delta)[3] < 0
    sol = solve_ivp(lambda t, x: f(x, delta), (0, 200), x0, rtol=1e-8, atol=1e-10, max_step=1.0)
    v, r, _, p, phi = sol.y[:, -1]
    assert r < 0 and phi > 0 and v > 0
    assert np.abs(f(sol.y[:, -1], delta)[[0, 1, 3, 4]]).max() < 1e-6  # steady
    A, B, _ = linear_roll_model(H, 8.0, X_R, Z_R, LIFT)
    i = [0, 1, 3, 4]
    xs = -np.linalg.solve(A[np.ix_(i, i)], B[i]) * delta
    assert xs[1] < 0 and xs[3] > 0
    # the nonlinear turn is slower and heels less than the linear one, same signs
    assert abs(r) < abs(xs[1])


def test_roll_rhs_stall_and_moments():
    stall = math.radians(23.0)
    f = roll_rhs(H, 8.0, X_R, Z_R, LIFT, stall_angle=stall)
    x = np.array([0.1, 0.01, 0.3, -0.02, 0.05])
    np.testing.assert_array_equal(f(x, math.radians(30.0)), f(x, stall))
    assert not np.array_equal(f(x, math.radians(20.0)), f(x, stall))
    # batched states, a roll moment adds G[:, 0] K_w
    _, _, G = linear_roll_model(H, 8.0, X_R, Z_R, LIFT)
    xs = np.stack([x, 2 * x])
    d = f(xs, 0.0, [1e5, 0.0]) - f(xs, 0.0)
    np.testing.assert_allclose(d, np.stack([G[:, 0], G[:, 0]]) * 1e5, rtol=1e-12, atol=1e-18)


def test_bad_input_raises_with_a_hint():
    with pytest.raises(ValueError, match="forward speed"):
        linear_roll_model(H, 0.0, X_R, Z_R, LIFT)
    with pytest.raises(ValueError, match="method"):
        linear_roll_model(H, 8.0, X_R, Z_R, LIFT, method="exact")
    with pytest.raises(ValueError, match="stall_angle"):
        roll_rhs(H, 8.0, X_R, Z_R, LIFT, stall_angle=-1.0)
    with pytest.raises(ValueError, match="I_xx"):
        dataclasses.replace(H, I_xx=-1.0)
    with pytest.raises(ValueError, match="finite number"):
        dataclasses.replace(H, K_p=float("nan"))
    with pytest.raises(ValueError, match="added-mass"):
        dataclasses.replace(H, Y_vdot=1e7)
    with pytest.raises(TypeError):
        Blanke4Hull()  # type: ignore[call-arg]
