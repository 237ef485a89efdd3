"""The Son & Nomoto (1982) container ship package against MSS ``Lcontainer.m`` (its printed
nondimensional matrices, written out here independently) and the notes' computed numbers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from shipgym.dynamics.linearise import roll_model_of
from shipgym.dynamics.vessel import load_vessel
from shipgym.envs.rollstab import RudderRollEnv

L, U0, RHO = 175.0, 7.0, 1025.0
# Lcontainer.m (Fossen & Perez 2004), nu = [v r p], eta = [y psi phi]
M_ = np.array([[0.01497, 0.0003525, -0.0002205], [0.0003525, 0.000875, 0.0],
               [-0.0002205, 0.0, 0.0000210]])  # fmt: skip
N_ = np.array([[0.012035, 0.00522, 0.0], [0.0038436, 0.00243, -0.000213],
               [-0.000314, 0.0000692, 0.0000075]])  # fmt: skip
G_ = np.array([[0, 0, 0.0000704], [0, 0, 0.0001468], [0, 0, 0.0004966]])
b_ = np.array([-0.002578, 0.00126, 0.0000855])


def _lcontainer(U: float) -> tuple[np.ndarray, np.ndarray]:
    """Lcontainer.m's linear model as x = [v, r, psi, p, phi], delta in shipgym's sign."""
    T, Ti = np.diag([1, 1 / L, 1 / L]), np.diag([1, L, L])
    Minv = np.linalg.inv(T @ M_ @ Ti)
    A_nu = -Minv @ ((U / L) * T @ N_ @ Ti)  # d nu / d nu
    A_eta = -Minv @ ((U0 / L) ** 2 * T @ G_ @ Ti)  # d nu / d eta (G' written at U0)
    B_nu = Minv @ ((U**2 / L) * T @ b_)
    A = np.zeros((5, 5))
    rows = {0: 0, 1: 1, 3: 2}  # v, r, p in x
    for xi, i in rows.items():
        A[xi, [0, 1, 3]] = A_nu[i]
        A[xi, 4] = A_eta[i, 2]
    A[2, 1] = 1.0  # psi_dot = r
    A[4, 3] = 1.0  # phi_dot = p
    B = np.zeros(5)
    for xi, i in rows.items():
        B[xi] = -B_nu[i]  # shipgym: positive delta pushes the stern to starboard
    return A, B


@pytest.mark.parametrize("U", [5.0, 7.0, 9.0])
def test_the_package_is_lcontainer_in_si(U):
    m = roll_model_of(load_vessel("container-ship"), U)
    A, B = _lcontainer(U)
    # 8 digits in the vessel file: a near-cancelling entry (A[1, 4] ~ 7.5e-7) keeps 1e-11
    np.testing.assert_allclose(m.A, A, rtol=2e-7, atol=1e-9)
    np.testing.assert_allclose(m.B, B, rtol=2e-7, atol=1e-14)


def test_the_notes_numbers_at_7_m_s():
    """Roll 0.217 rad/s, damping 0.040; the roll/rudder RHP zero at +0.1855 rad/s; static
    roll per rudder 1.17 rad/rad (-1.17 in container.m's sign)."""
    m = roll_model_of(load_vessel("container-ship"), U0)
    ev = np.linalg.eigvals(m.A)
    osc = ev[np.abs(ev.imag) > 1e-6][0]
    assert abs(osc) == pytest.approx(0.217, abs=5e-4)
    assert -osc.real / abs(osc) == pytest.approx(0.040, abs=5e-4)
    # zeros of phi/delta: the generalised eigenvalues of the Rosenbrock pencil
    from scipy.linalg import eig

    P = np.block([[m.A, m.B[:, None]], [np.eye(5)[4:5], np.zeros((1, 1))]])
    E = np.block([[np.eye(5), np.zeros((5, 1))], [np.zeros((1, 6))]])
    z = eig(P, E, right=False)
    z = z[np.isfinite(z)]
    assert np.any(np.abs(z - 0.1855) < 5e-4)
    keep = [0, 1, 3, 4]  # psi does not feed back: the static gain of the rest
    x = -np.linalg.solve(m.A[np.ix_(keep, keep)], m.B[keep])
    assert x[3] == pytest.approx(1.17, abs=5e-3)


def test_the_couplings_are_lcontainers_not_exrrds():
    """exRRD1/2.m reorder the states to [v p r] but not M' row 1; the package keeps
    Lcontainer.m's v-p and v-r couplings (order u, v, p, r)."""
    M = np.asarray(load_vessel("container-ship").plant().M)
    S = 0.5 * RHO * L**3
    assert M[1, 2] == pytest.approx(S * L * -0.0002205, rel=1e-6)  # v-p
    assert M[1, 3] == pytest.approx(S * L * 0.0003525, rel=1e-6)  # v-r
    assert M[2, 2] == pytest.approx(S * L**2 * 0.0000210, rel=1e-6)


def test_a_long_swell_rolls_the_container_ship():
    """Its roll mode has a 29 s period: the default short beam sea hardly rolls it, a 16 s
    swell (Hs 3 m, Tp 16 s) rolls it several times more."""
    rms = []
    for waves in (None, {"Hs": 3.0, "Tp": 16.0, "chi_deg": 90.0}):
        kw = {} if waves is None else {"waves": waves}
        env = RudderRollEnv(vessel="container-ship", speed=7.0, episode_duration=200.0, **kw)
        env.reset(seed=0)
        phi = []
        while True:
            _, _, term, trunc, info = env.step(np.zeros(1, dtype=np.float32))
            phi.append(info["roll"])
            if term or trunc:
                break
        rms.append(math.degrees(float(np.sqrt(np.mean(np.square(phi))))))
    assert rms[0] < 0.1 and rms[1] > 5 * rms[0], rms
