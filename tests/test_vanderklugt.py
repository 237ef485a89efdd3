"""The Van der Klugt (1987) roll model of Radhakrishnan (n.d.): typos, transfer functions, zero,
open-loop amplitudes (seed 003 checks B1-B4), errors."""

import math

import numpy as np
import pytest
import scipy.linalg
import scipy.signal

from shipgym.dynamics.vanderklugt import (
    KDP_LAWS,
    OUTPUT_NAMES,
    STATE_NAMES,
    VAN_DER_KLUGT,
    VARIANTS,
    VanDerKlugtParameters,
    frequency_response,
    open_loop_amplitudes,
    roll_model,
    roll_rudder_zero,
    transfer_functions,
)

SPEEDS = (4.0, 8.0, 13.0, 15.0, 20.0)


def test_parameters_at_speed_are_the_printed_laws():
    p = VAN_DER_KLUGT.at(8.0)
    assert p.omega_n == 0.63
    assert p.T_v == pytest.approx(78 / 8) and p.T_r == pytest.approx(13 / 8)
    assert p.K_vr == -0.46 and p.K_dr == pytest.approx(-0.0027 * 8)
    assert p.K_dp == pytest.approx(-0.0014 * 64) and p.K_dv == pytest.approx(0.08)
    assert p.K_vp == pytest.approx(0.21 * 8) and p.xi == pytest.approx(0.064 + 0.0038 * 8)
    assert p.q_phi == pytest.approx((0.7 * math.pi / 180) ** 2)
    assert p.q_psi == pytest.approx((0.35 * math.pi / 180) ** 2)
    assert VAN_DER_KLUGT.at(8.0, "printed").K_dp == pytest.approx(-0.0014 / 64)


def test_open_loop_roll_rms_of_the_chosen_wave_intensity():
    """Notes 2.2 item 7: sqrt(q w_n / (4 xi)) ~ 0.9 deg at 8 m/s, from a Lyapunov solve."""
    m = roll_model(8.0)
    # the roll subsystem only (the waves reach v, r, psi only through r, which roll misses)
    idx = [3, 4]
    A = m.A[np.ix_(idx, idx)]
    Gq = m.G[idx] @ m.Q_w @ m.G[idx].T
    P = scipy.linalg.solve_continuous_lyapunov(A, -Gq)
    p = m.parameters
    assert math.sqrt(P[1, 1]) == pytest.approx(math.sqrt(p.q_phi * p.omega_n / (4 * p.xi)), 1e-9)
    assert math.degrees(math.sqrt(P[1, 1])) == pytest.approx(0.904, abs=2e-3)


@pytest.mark.parametrize("U", SPEEDS)
def test_b1_the_printed_model_is_unstable(U):
    """B1: eq. 10 as printed has +U/78 and -xi w_n + sqrt((xi w_n)^2 + w_n^2)."""
    m = roll_model(U, "seed-printed")
    xi = 0.064 + 0.0038 * U
    w = 0.63
    eig = np.linalg.eigvals(m.A)
    for expected in (U / 78, -xi * w + math.sqrt((xi * w) ** 2 + w**2)):
        assert np.min(np.abs(eig - expected)) < 1e-10
    assert np.max(eig.real) > 0.5
    assert np.all(np.linalg.eigvals(roll_model(U).A).real <= 1e-12)  # reconstructed: stable


def test_b1_printed_numbers_at_8():
    eig = np.sort(np.linalg.eigvals(roll_model(8.0, "seed-printed").A).real)
    assert eig[-2] == pytest.approx(0.1026, abs=1e-4)
    assert eig[-1] == pytest.approx(0.5733, abs=1e-4)


def test_the_printed_variant_differs_from_the_reconstruction_in_the_four_entries():
    a, b = roll_model(8.0, "seed-printed"), roll_model(8.0)
    dA = np.argwhere(~np.isclose(a.A, b.A)).tolist()
    assert sorted(dA) == [[0, 0], [1, 0], [3, 4]]
    assert np.flatnonzero(~np.isclose(a.B, b.B)).tolist() == [3]
    assert a.B[3] == pytest.approx(-b.B[3])
    np.testing.assert_array_equal(a.G, b.G)


@pytest.mark.parametrize("law", KDP_LAWS)
@pytest.mark.parametrize("U", SPEEDS)
def test_b2_state_space_has_the_transfer_functions_of_eqs_5_to_7(U, law):
    """B2: ss2tf of the reconstructed A, B equals eqs. 5-7 (cross-multiplied: no cancelling)."""
    m = roll_model(U, kdp_law=law)
    nums, den = scipy.signal.ss2tf(m.A, m.B.reshape(5, 1), np.eye(5), np.zeros((5, 1)))
    tfs = transfer_functions(U, law)
    for name, (num_tf, den_tf) in tfs.items():
        num_ss = nums[STATE_NAMES.index(name)]
        lhs = np.polymul(num_ss, den_tf)
        rhs = np.polymul(num_tf, den)
        n = max(lhs.size, rhs.size)
        lhs, rhs = np.pad(lhs, (n - lhs.size, 0)), np.pad(rhs, (n - rhs.size, 0))
        scale = np.max(np.abs(rhs))
        assert np.max(np.abs(lhs - rhs)) <= 1e-10 * scale, name
    # and the printed state space does not
    mp = roll_model(U, "seed-printed", law)
    nums_p, den_p = scipy.signal.ss2tf(mp.A, mp.B.reshape(5, 1), np.eye(5), np.zeros((5, 1)))
    num_tf, den_tf = tfs["phi"]
    lhs, rhs = np.polymul(nums_p[4], den_tf), np.polymul(num_tf, den_p)
    n = max(lhs.size, rhs.size)
    assert not np.allclose(np.pad(lhs, (n - lhs.size, 0)), np.pad(rhs, (n - rhs.size, 0)))


@pytest.mark.parametrize("U", SPEEDS)
def test_b3_roll_rudder_zero_in_the_right_half_plane(U):
    z = roll_rudder_zero(U, "U2")
    assert z.shape == (1,)
    assert z[0] == pytest.approx(U / 156, abs=1e-6)
    # the same zero from the state space: the finite generalised eigenvalues of the
    # Rosenbrock pencil [[A, B], [C_phi, 0]] - s [[I, 0], [0, 0]]
    m = roll_model(U)
    M = np.zeros((6, 6))
    M[:5, :5], M[:5, 5], M[5, 4] = m.A, m.B, 1.0
    N = np.diag([1.0] * 5 + [0.0])
    zs = scipy.linalg.eigvals(M, N)
    zs = zs[np.isfinite(zs)]
    # (r and psi never reach phi: their poles 0 and -1/T_r are decoupling zeros)
    np.testing.assert_allclose(np.sort(zs.real), np.sort([U / 156, 0.0, -U / 13]), atol=1e-6)
    np.testing.assert_allclose(zs.imag, 0.0, atol=1e-9)


def test_b3_printed_law_zero():
    U = 8.0
    p = VAN_DER_KLUGT.at(U, "printed")
    expected = -(1 + p.K_vp * p.K_dv / p.K_dp) / p.T_v
    assert roll_rudder_zero(U, "printed")[0] == pytest.approx(expected, rel=1e-9)


B4 = {
    "U2": {8.0: 1.597, 13.0: 4.041, 15.0: 5.270},
    "printed": {8.0: 0.567, 13.0: 2.306, 15.0: 3.450},
}


@pytest.mark.parametrize("law", KDP_LAWS)
@pytest.mark.parametrize("U", (8.0, 13.0, 15.0))
def test_b4_open_loop_roll_amplitude(U, law):
    amp = open_loop_amplitudes(U, kdp_law=law)
    assert math.degrees(amp["phi"]) == pytest.approx(B4[law][U], abs=1e-3)


def test_b4_amplitude_from_the_transfer_function_and_a_simulation():
    """Independent of the state space: |phi/delta(j w)| of eqs. 5-7, and lsim's steady state."""
    U, w, a = 8.0, 0.43, math.radians(10)
    num, den = transfer_functions(U)["phi"]
    g = np.polyval(num, 1j * w) / np.polyval(den, 1j * w)
    amp = open_loop_amplitudes(U)
    assert amp["phi"] == pytest.approx(abs(g) * a, rel=1e-12)
    num_v, den_v = transfer_functions(U)["v"]
    assert amp["v"] == pytest.approx(abs(np.polyval(num_v, 1j * w) / np.polyval(den_v, 1j * w)) * a)
    assert amp["v"] == pytest.approx(0.0032, abs=5e-5)
    assert math.degrees(amp["psi"]) == pytest.approx(0.48, abs=5e-3)
    m = roll_model(U)
    t = np.arange(0.0, 400.0, 0.05)
    _, y, _ = scipy.signal.lsim(
        (m.A, m.B.reshape(5, 1), np.eye(5), np.zeros((5, 1))), a * np.sin(w * t), t
    )
    tail = t > 300
    assert 0.5 * np.ptp(y[tail, 4]) == pytest.approx(amp["phi"], rel=2e-3)


def test_frequency_response_shapes():
    m = roll_model(10.0)
    assert frequency_response(m, 0.43).shape == (5,)
    assert frequency_response(m, [0.1, 0.43, 1.0]).shape == (3, 5)
    # r = j w psi
    g = frequency_response(m, 0.3)
    assert g[1] == pytest.approx(1j * 0.3 * g[2])


def test_model_metadata():
    m = roll_model(8.0)
    assert m.states == STATE_NAMES == ("v", "r", "psi", "p", "phi")
    assert m.outputs == OUTPUT_NAMES == ("r", "psi", "p", "phi")
    np.testing.assert_array_equal(m.C @ np.arange(5.0), [1.0, 2.0, 3.0, 4.0])
    assert m.A.shape == (5, 5) and m.B.shape == (5,) and m.G.shape == (5, 2)
    w2 = 0.63**2
    np.testing.assert_allclose(m.G, [[0, 0], [0, 8 / 13], [0, 0], [w2, 0], [0, 0]])
    assert m.U == 8.0 and m.variant == "reconstructed" and "Radhakrishnan" in m.source


@pytest.mark.parametrize("U", (0.0, -1.0, math.nan, math.inf))
def test_bad_speed(U):
    with pytest.raises(ValueError, match="U must be"):
        roll_model(U)
    with pytest.raises(ValueError, match="U must be"):
        transfer_functions(U)


def test_bad_variant_and_law():
    with pytest.raises(ValueError, match="reconstructed"):
        roll_model(8.0, "typo")
    with pytest.raises(ValueError, match="U2"):
        roll_model(8.0, kdp_law="U3")
    with pytest.raises(ValueError, match="U2"):
        VAN_DER_KLUGT.at(8.0, "nope")
    with pytest.raises(ValueError, match="omega"):
        frequency_response(roll_model(8.0), 0.0)
    with pytest.raises(ValueError, match="omega_n"):
        VanDerKlugtParameters(omega_n=-1.0)
    with pytest.raises(TypeError):
        VanDerKlugtParameters(omega=1.0)  # unknown key
    assert VARIANTS == ("reconstructed", "seed-printed")
