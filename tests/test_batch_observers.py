"""One law over N envs: every env of a :class:`~shipgym.observers.batch.BatchedKalman` gives bit
for bit what the same law run at N = 1 (the filter ``make_observer(name, R=R_i)``, an N = 1
adapter) fed env ``i``'s samples gives, at every sample, for every preset, with per-env
measurement variances, outliers, forced acceptances, dropouts, coasting, samples at the time of
the previous call, envs on different intervals and masked resets."""

from __future__ import annotations

import numpy as np
import pytest

from shipgym.observers.base import make_observer
from shipgym.observers.batch import BatchedKalman

PRESETS = ["kbf", "dkf", "tomera-kbf", "tomera-dkf"]
N = 32


def _variances(rng: np.random.Generator, n: int) -> np.ndarray:
    return np.column_stack(
        [
            rng.uniform(0.004, 0.05, n),
            rng.uniform(0.004, 0.05, n),
            rng.uniform(1e-5, 1e-4, n),
        ]
    )


class _Run:
    """The batched filter and one scalar filter per env, fed the same samples."""

    def __init__(self, name: str, R: np.ndarray) -> None:
        self.name = name
        self.batch = BatchedKalman(name, N, R=R)
        self.single = [make_observer(name, R=tuple(r)) for r in R]
        self.counts = {"rejected": 0, "forced": 0, "dropped": 0, "coast": 0, "grouped": 0,
                       "same_time": 0, "reset": 0}  # fmt: skip

    def reset(self, t0: np.ndarray, eta0: np.ndarray, mask=None, R=None) -> None:
        self.batch.reset(t0, eta0, mask=mask, R=R)
        for i in np.nonzero(np.ones(N, bool) if mask is None else mask)[0]:
            if R is not None:
                self.single[i] = make_observer(self.name, R=tuple(R[i]))
            self.single[i].reset(float(t0[i]), eta0[i])
        self.counts["reset"] += 1

    def step(self, t: np.ndarray, z: np.ndarray | None, valid: np.ndarray | None) -> None:
        b = self.batch
        dt = t - b.t
        if not np.all(dt == dt[0]):
            self.counts["grouped"] += 1
        if np.any(dt == 0.0) and z is not None:
            self.counts["same_time"] += 1
        info = b.step(t, z, valid)
        got = [b.eta, b.nu, b.P, b.P_nu, info.innovation, info.nis]
        ref = [np.empty_like(g) for g in got]
        flags = np.zeros((N, 2), bool)
        for i, f in enumerate(self.single):
            zi = None if z is None or (valid is not None and not valid[i]) else z[i]
            si = f.step(float(t[i]), zi)
            est = f.estimate()
            ref[0][i], ref[1][i], ref[2][i], ref[3][i] = est.eta, est.nu, est.P, est.P_nu
            ref[4][i] = si.innovation
            ref[5][i] = np.nan if si.nis is None else si.nis
            flags[i] = si.rejected, si.forced
        for g, r in zip(got, ref, strict=True):
            np.testing.assert_array_equal(g, r)  # bit for bit; NaN where N = 1 has none
        np.testing.assert_array_equal(np.column_stack([info.rejected, info.forced]), flags)
        self.counts["rejected"] += int(info.rejected.sum())
        self.counts["forced"] += int(info.forced.sum())
        if z is None:
            self.counts["coast"] += 1
        elif valid is not None:
            self.counts["dropped"] += int((~valid).sum())


@pytest.mark.parametrize("name", PRESETS)
def test_every_env_is_the_law_at_n_1(name: str) -> None:
    rng = np.random.default_rng(15)
    R = _variances(rng, N)
    run = _Run(name, R)
    # the ships: circles at their own speed and turn rate (headings through +-pi)
    speed = rng.uniform(0.05, 0.5, N)
    rate = rng.uniform(-0.01, 0.01, N)
    truth = np.column_stack([rng.normal(0, 50, N), rng.normal(0, 50, N), rng.uniform(-3, 3, N)])
    noise = [np.random.default_rng(1000 + i) for i in range(N)]  # one noise stream per env
    sig = np.sqrt(R)
    t = np.zeros(N)
    run.reset(t, truth + 0.05)
    jump = np.zeros((N, 3))

    def measure(trueR: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        z = truth + np.stack([g.standard_normal(3) for g in noise]) * np.sqrt(trueR) + jump
        z[:, 2] = np.arctan2(np.sin(z[:, 2]), np.cos(z[:, 2]))  # a gyrocompass: (-pi, pi]
        out = rng.random(N) < 0.05
        z[out, 0] += 30.0  # outliers
        valid = rng.random(N) > 0.1  # dropouts
        z[~valid] = np.nan
        return z, valid

    def move(dt: np.ndarray) -> None:
        truth[:, 0] += dt * speed * np.cos(truth[:, 2])
        truth[:, 1] += dt * speed * np.sin(truth[:, 2])
        truth[:, 2] += dt * rate

    trueR = sig**2
    for k in range(330):
        if k == 100:
            jump[:4, 0] = 25.0  # a real position jump: rejected, then forced
        if k == 150:  # a masked reset, off the others' clock, with new variances
            m = np.zeros(N, bool)
            m[::4] = True
            newR = _variances(rng, N)
            t = np.where(m, t + 0.25, t)
            run.reset(t, truth + 0.1, mask=m, R=newR)
            R = np.where(m[:, None], newR, R)
            trueR = R
        if k % 10 == 5:  # coast half a period, then sample at that same instant
            dt = np.full(N, 0.5)
            move(dt)
            t = t + dt
            run.step(t, None, None)
            z, valid = measure(trueR)
            run.step(t, z, valid)
            continue
        # envs on different intervals now and then
        dt = rng.choice([0.5, 1.0], N) if 200 <= k < 215 else np.full(N, 1.0)
        move(dt)
        t = t + dt
        z, valid = measure(trueR)
        run.step(t, z, valid if k % 3 else None if valid.all() else valid)
    c = run.counts
    assert c["rejected"] > 10 and c["forced"] >= 4 and c["dropped"] > 100, c
    assert c["coast"] >= 30 and c["same_time"] >= 30 and c["grouped"] >= 10 and c["reset"] == 2, c


@pytest.mark.parametrize("name", ["tomera-dkf", "tomera-kbf"])
def test_steady_state_gains_per_env(name: str) -> None:
    R = _variances(np.random.default_rng(3), 8)
    b = BatchedKalman(name, 8, R=R)
    for i in range(8):
        ref = make_observer(name, R=tuple(R[i])).steady_state_gain
        np.testing.assert_allclose(b.steady_state_gain[i], ref, rtol=1e-12, atol=0)


def test_bad_use() -> None:
    b = BatchedKalman("kbf", 3)
    with pytest.raises(RuntimeError, match="reset"):
        b.step(1.0, np.zeros((3, 3)))
    b.reset(np.array([0.0, 0.0, 5.0]), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="backwards"):
        b.step(1.0, np.zeros((3, 3)))  # env 2 is at 5 s
    b.step(np.array([1.0, 1.0, 5.0 - 1e-12]), None)  # a clock a hair behind: no time passes
    assert b.t[2] == 5.0
    with pytest.raises(ValueError, match="z must be"):
        b.step(6.0, np.zeros((2, 3)))
    z = np.zeros((3, 3))
    z[1, 0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        b.step(6.0, z)
    b.step(6.0, z, np.array([True, False, True]))  # a NaN row is fine where not valid
    with pytest.raises(ValueError, match="mask"):
        b.reset(0.0, np.zeros((3, 3)), mask=[True, False])
    with pytest.raises(ValueError, match="R must"):
        b.reset(0.0, np.zeros((3, 3)), R=[0.01, -1.0, 1e-5])
    with pytest.raises(ValueError, match="double-integrator"):
        BatchedKalman("ekf", 2)
    with pytest.raises(ValueError, match="n must"):
        BatchedKalman("kbf", 0)


def test_reset_keeps_the_other_envs_and_accepts_nu0() -> None:
    b = BatchedKalman("dkf", 4)
    b.reset(0.0, np.zeros((4, 3)))
    for k in range(5):
        b.step(k + 1.0, np.full((4, 3), 0.1 * k))
    before = b.eta
    m = np.array([False, True, False, False])
    b.reset(5.0, np.ones((4, 3)), mask=m, nu0=[1.0, 0.0, 0.0])
    np.testing.assert_array_equal(b.eta[~m], before[~m])
    np.testing.assert_allclose(b.eta[1], 1.0)
    np.testing.assert_allclose(b.nu[1], [1.0, 0.0, 0.0], atol=1e-15)
    ref = make_observer("dkf")
    ref.reset(5.0, np.ones(3), nu0=[1.0, 0.0, 0.0])
    np.testing.assert_allclose(b.P[1], ref.P)


@pytest.mark.parametrize("name", PRESETS)
def test_reset_with_p0_and_nu0_per_env_is_the_law_at_n_1(name: str) -> None:
    """Per-env ``P0`` and ``nu0`` at a masked reset: row i equals the N = 1 filter reset with
    row i's arguments, bit for bit, through the next samples."""
    n = 3
    rng = np.random.default_rng(8)
    b = BatchedKalman(name, n)
    b.reset(0.0, np.zeros((n, 3)))
    single = [make_observer(name) for _ in range(n)]
    for f in single:
        f.reset(0.0, np.zeros(3))
    G = rng.normal(size=(n, 6, 6)) * 0.1
    P0 = G @ G.transpose(0, 2, 1) + 1e-3 * np.eye(6)
    nu0 = rng.normal(0.0, 0.2, (n, 3))
    eta0 = rng.normal(0.0, 5.0, (n, 3))
    m = np.array([True, False, True])
    b.reset(0.0, eta0, mask=m, nu0=nu0, P0=P0)
    for i in np.nonzero(m)[0]:
        single[i].reset(0.0, eta0[i], nu0=nu0[i], P0=P0[i])
    for k in range(1, 6):
        z = eta0 + rng.normal(0.0, 0.1, (n, 3))
        info = b.step(float(k), z)
        for i, f in enumerate(single):
            si = f.step(float(k), z[i])
            np.testing.assert_array_equal(info.innovation[i], si.innovation)
            np.testing.assert_array_equal(b.x[i], f.x)
            np.testing.assert_array_equal(b.P[i], f.P)
            np.testing.assert_array_equal(b.P_nu[i], f.estimate().P_nu)
    with pytest.raises(ValueError, match="symmetric"):
        b.reset(0.0, eta0, P0=np.triu(np.ones((6, 6))))
