"""Every observer written once over N >= 1 envs: env i of ``gymnasium.make_vec(id,
num_envs=3, observer=name)`` is the single env ``shipgym.make(id, observer=name)`` seeded
``seed + i``, to the last bit (estimates, observations, rewards, NIS and gate flags, the
episode ends), over whole episodes with autoresets, for every registered observer and the
vessels and tasks it fits: the plan tasks' 1 s sensors (the kinematic filters, the EKFs and
the notch filter where its notches lie below the sensors' Nyquist frequency) and the offshore
DP task (every observer: its sensors sample every control period, 0.1 per-unit time, the
Al-Takie wave filters' interval)."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import shipgym
from shipgym.dynamics.vessel import load_vessel, vessel_names
from shipgym.envs.registration import task_fits_vessel
from shipgym.observers import make_observer, observer_names
from shipgym.observers.batch import BATCHED_OBSERVERS, BatchedKalman, make_batched_observer

DP = "shipgym/DPStationKeeping-v0"
PLAN = "shipgym/StationKeeping-v0"
NAMES = observer_names()


def _fits(name: str, env_id: str, vessel: str) -> bool:
    v = load_vessel(vessel)
    if not task_fits_vessel(env_id, v) or v.dofs != 3:
        return False
    if env_id == DP:
        return True
    if name.startswith("alt-"):  # they sample every 0.1 per-unit time: the DP task's period
        return False
    if name == "notch":  # the top notch (Froude-scaled) below the 1 s sensors' Nyquist
        return 0.128 * math.sqrt(v.scale) < 0.5
    return True


CASES = [(name, env_id, v) for name in NAMES for env_id in (PLAN, DP) for v in vessel_names()
         if _fits(name, env_id, v)]  # fmt: skip


def test_every_observer_has_its_batched_form():
    assert len(NAMES) == 14
    for name in NAMES:
        batch = make_batched_observer(name, 2, load_vessel("star-hercules"))
        assert name in BATCHED_OBSERVERS or isinstance(batch, BatchedKalman)
        batch.reset(np.zeros(2), np.zeros((2, 3)))
        assert batch.eta.shape == (2, 3) and batch.nu.shape == (2, 3)


@pytest.mark.parametrize("name", NAMES)
def test_n_envs_are_n_single_observers(name):
    """The batched observer of 4 envs, with dropouts, outliers (the gates' rejections and
    forced acceptances) and thrust, against 4 single observers (its batch of one, the single
    env's), to the last bit."""
    vessel = load_vessel("wimpey-sealab")
    n = 4
    batch = make_batched_observer(name, n, vessel)
    singles = [make_observer(name, vessel=vessel) for _ in range(n)]
    dt = batch.dt if name.startswith("alt-") else 1.0
    rng = np.random.default_rng(3)
    eta0 = rng.normal(0.0, 1.0, (n, 3))
    batch.reset(np.zeros(n), eta0)
    for i, s in enumerate(singles):
        s.reset(0.0, eta0[i])
    model = getattr(batch, "model_based", False)
    for k in range(1, 60):
        z = eta0 + 0.02 * k + rng.normal(0.0, 0.05, (n, 3))
        z[:, 2] = (z[:, 2] + math.pi) % (2 * math.pi) - math.pi
        valid = rng.random(n) > 0.15
        if 20 <= k < 30:  # a jump in env 1's fixes: rejected, then forced in
            z[1, :2] += 30.0
        tau = rng.normal(0.0, 1e4, (n, 3))
        info = batch.step(np.full(n, k * dt), np.where(valid[:, None], z, np.nan), valid,
                          **({"tau": tau} if model else {}))  # fmt: skip
        for i, s in enumerate(singles):
            si = s.step(k * dt, z[i] if valid[i] else None, tau[i])
            if valid[i]:
                np.testing.assert_array_equal(info.innovation[i], si.innovation)
                assert info.rejected[i] == si.rejected
            e = s.estimate()
            np.testing.assert_array_equal(batch.eta[i], e.eta)
            np.testing.assert_array_equal(batch.nu[i], e.nu)


def _run(name, env_id, vessel, mode, n=3, steps=6, total=20, seed=11):
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point",
                        vessel=vessel, observer=name, max_episode_steps=steps,
                        autoreset_mode=mode)  # fmt: skip
    singles = [shipgym.make(env_id, vessel=vessel, observer=name, max_episode_steps=steps)
               for _ in range(n)]  # fmt: skip
    obs, info = venv.reset(seed=seed)
    for i, s in enumerate(singles):
        o, inf = s.reset(seed=seed + i)
        np.testing.assert_array_equal(obs[i], o)
        np.testing.assert_array_equal(info["nav_eta"][i], inf["nav_eta"])
    rng = np.random.default_rng(seed)
    pending = np.zeros(n, bool)
    ends = 0
    for _ in range(total):
        a = rng.uniform(-1.0, 1.0, (n, venv.single_action_space.shape[0])).astype(np.float32)
        obs, rew, term, trunc, info = venv.step(a)
        for i, s in enumerate(singles):
            if pending[i]:  # next-step: the batched env reset env i in this step
                o, inf = s.reset()
                assert rew[i] == 0.0 and not term[i] and not trunc[i]
            else:
                o, r, te, tr, inf = s.step(a[i])
                assert (bool(term[i]), bool(trunc[i])) == (te, tr)
                assert rew[i] == r
                ends += te or tr
                if (te or tr) and mode == "same-step":
                    np.testing.assert_array_equal(info["final_obs"][i], o)
                    o, inf = s.reset()
                    continue
            np.testing.assert_array_equal(obs[i], o)
            np.testing.assert_array_equal(info["eta"][i], inf["eta"])
            np.testing.assert_array_equal(info["nav_eta"][i], inf["nav_eta"])
            np.testing.assert_array_equal(info["nav_nu"][i], inf["nav_nu"])
            if not pending[i]:
                nis = inf["observer_nis"]
                assert (math.isnan(info["observer_nis"][i]) if nis is None
                        else info["observer_nis"][i] == nis)  # fmt: skip
                assert info["observer_rejected"][i] == inf["observer_rejected"]
        pending = (term | trunc) if mode == "next-step" else np.zeros(n, bool)
    assert ends >= n  # every env autoreset at least once


@pytest.mark.parametrize(("name", "env_id", "vessel"), CASES)
def test_vector_env_equals_the_single_env_with_the_observer(name, env_id, vessel):
    _run(name, env_id, vessel, "next-step")


@pytest.mark.parametrize("name", [n for n in NAMES if n.startswith("alt-")] + ["ekf", "notch"])
def test_same_step_autoreset(name):
    _run(name, DP, "wimpey-sealab", "same-step", steps=5, total=12)


@pytest.mark.parametrize("name", ["dkf", "kbf", "tomera-dkf", "tomera-kbf"])
def test_a_coast_of_no_time_changes_nothing(name):
    """A step without a measurement in which no time passes (env i at its own time while
    another env coasts) leaves env i's filter as it was: the estimate and the next updates
    (the time-varying KBF's previous sample included)."""
    rng = np.random.default_rng(1)
    zs = rng.normal(0.0, 0.3, (12, 2, 3))
    out = []
    for coast in (False, True):
        b = BatchedKalman(name, 2)
        b.reset(np.zeros(2), np.zeros((2, 3)))
        for k in range(1, 6):
            b.step(np.full(2, 0.5 * k), zs[k], np.ones(2, bool))
        if coast:  # env 0 coasts 0.2 s, env 1 stays at its time
            b.step(np.array([2.7, 2.5]), None)
        shift = np.array([0.2 if coast else 0.0, 0.0])
        for k in range(6, 12):
            b.step(np.full(2, 0.5 * k) + shift, zs[k], np.ones(2, bool))
        out.append((b.x[1], b.P[1]))
    np.testing.assert_array_equal(out[0][0], out[1][0])
    np.testing.assert_array_equal(out[0][1], out[1][1])
