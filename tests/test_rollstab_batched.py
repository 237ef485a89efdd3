"""The rudder-roll family written once (shipgym.envs.rollstab.RudderRollVectorEnv): env i of
``make_vec(id, 3)`` is the single env seeded seed + i, bit for bit, over whole episodes with
autoresets in both autoreset modes, for every vessel that fits each id; the single env passes
gymnasium's check; stable-baselines3 drives the batch; the printed K_dp law gives each hull
the rudder of its own speed."""

from __future__ import annotations

import os
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import shipgym
from shipgym.dynamics.vanderklugt import seed_vessel
from shipgym.dynamics.vessel import load_vessel
from shipgym.envs.registration import VECTOR_IDS, task_fits_vessel
from shipgym.envs.rollstab import RudderRollEnv, RudderRollVectorEnv

IDS = ("shipgym/RudderRollStabilisation-v0", "shipgym/NavalRollDamping-v0")
CASES = [(t, v) for t in IDS for v in shipgym.vessels() if task_fits_vessel(t, load_vessel(v))]
#: short episodes (15 control steps), the sway filter in the observation
SHORT = {"episode_duration": 1.5, "sway_estimate": True}
N = 3


def _equal(a, b, where):
    """``a`` (a row of the batch's value) equals ``b`` (the single env's), bit for bit."""
    if isinstance(b, dict):
        assert set(a) == set(b), (where, sorted(a), sorted(b))
        for k in b:
            _equal(a[k], b[k], f"{where}.{k}")
    else:
        assert np.array_equal(np.asarray(a), np.asarray(b)), (where, a, b)


def _row(info, i):
    """Row ``i`` of a batched info dict (the ``_key`` masks dropped)."""
    if isinstance(info, dict):
        return {k: _row(v, i) for k, v in info.items() if not k.startswith("_")}
    return info[i]


def _episodes(env_id, mode, steps=40, **kw):
    """Run the batch and N single envs side by side; returns the number of episode ends."""
    vec = gym.make_vec(env_id, num_envs=N, vectorization_mode="vector_entry_point",
                       autoreset_mode=mode, **kw).unwrapped  # fmt: skip
    assert isinstance(vec, RudderRollVectorEnv) and vec.num_envs == N
    singles = [gym.make(env_id, **kw) for _ in range(N)]
    obs, info = vec.reset(seed=11)
    for i, s in enumerate(singles):
        o, inf = s.reset(seed=11 + i)
        _equal(obs[i], o, "reset obs")
        _equal(_row(info, i), inf, "reset info")
    rng = np.random.default_rng(0)
    pending = np.zeros(N, bool)  # next-step: these envs reset at this step
    ends = 0
    for k in range(steps):
        a = rng.uniform(-1.3, 1.3, (N, 1)).astype(np.float32)  # beyond the limits too
        obs, r, term, trunc, info = vec.step(a)
        for i, s in enumerate(singles):
            where = f"step {k} env {i}"
            if pending[i]:
                o, inf = s.reset()
                _equal(obs[i], o, where)
                assert r[i] == 0.0 and not (term[i] or trunc[i])
                for key in inf:
                    _equal(info[key][i], inf[key], f"{where} reset {key}")
                pending[i] = False
                continue
            o, ri, te, tr, inf = s.step(a[i])
            assert (ri, te, tr) == (r[i], term[i], trunc[i]), where
            step_keys = {key: v for key, v in info.items() if not key.startswith(("_", "final"))}
            _equal(_row(step_keys, i), inf, where)  # every info key, episode_metrics too
            if not (te or tr):
                _equal(obs[i], o, where)
                continue
            ends += 1
            assert info["_episode_metrics"][i]
            if mode == "same-step":
                _equal(info["final_obs"][i], o, where)
                o, _ = s.reset()
                _equal(obs[i], o, f"{where} autoreset")
            else:
                _equal(obs[i], o, where)
                pending[i] = True
    vec.close()
    return ends


@pytest.mark.parametrize("mode", ["next-step", "same-step"])
@pytest.mark.parametrize(("env_id", "vessel"), CASES,
                         ids=[f"{t.split('/')[1]}-{v}" for t, v in CASES])  # fmt: skip
def test_env_i_is_the_single_env_seeded_seed_plus_i(env_id, vessel, mode):
    assert _episodes(env_id, mode, vessel=vessel, **SHORT) >= 2 * N


@pytest.mark.parametrize("mode", ["next-step", "same-step"])
def test_printed_law_each_hull_its_own_rudder(mode):
    """kdp_law="printed": each env draws its speed and its hull gets the rudder of the printed
    law at that speed (per-hull actuator constants), the rudder test and the sea in the loop."""
    kw = {"kdp_law": "printed", "rudder_test": True, **SHORT}
    assert _episodes(IDS[0], mode, **kw) >= 2 * N
    vec = RudderRollVectorEnv(N, vessel="van-der-klugt", **kw)
    vec.reset(seed=3)
    assert len(set(vec.U.tolist())) == N
    tables = vec.physics._hulls.table
    for i, U in enumerate(vec.U.tolist()):
        want = seed_vessel("printed", speed=U).actuators.law_table()[0]
        np.testing.assert_array_equal(tables[i], want)
        assert vec.vessels[i].actuators.law_table()[0].tolist() == want.tolist()


@pytest.mark.parametrize(("env_id", "vessel"), CASES,
                         ids=[f"{t.split('/')[1]}-{v}" for t, v in CASES])  # fmt: skip
def test_single_env_passes_gymnasiums_check(env_id, vessel):
    env = gym.make(env_id, vessel=vessel, sway_estimate=True)
    assert isinstance(env.unwrapped, RudderRollEnv)
    check_env(env.unwrapped, skip_render_check=True)
    _, info = env.reset(seed=0)
    assert isinstance(info["speed"], float) and isinstance(info["v_hat"], float)
    _, r, _, _, info = env.step(np.zeros(1, np.float32))
    assert isinstance(r, float) and isinstance(info["reward_terms"]["roll"], float)
    assert info["rudder"].shape == (1,) and info["eta"].shape == (4,)
    assert set(env.unwrapped.episode_metrics()) >= {"roll_rms", "v_hat_rmse", "steps"}


def test_the_single_env_ends_and_says_so():
    env = gym.make(IDS[0], episode_duration=0.3)
    env.reset(seed=0)
    for _ in range(3):
        _, _, term, trunc, info = env.step(np.zeros(1, np.float32))
    assert trunc and not term and info["episode_metrics"]["steps"] == 3
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(1, np.float32))


def test_pilot_attributes_of_the_single_env():
    env = RudderRollEnv(vessel="naval-vessel", speed=7.0, kdp_law="U2")
    env.reset(seed=0)
    assert env.U == 7.0 and env.vessel.name == "naval-vessel"
    assert env.max_angle.shape == (1,) and env.control_period == 0.1
    q = env.filter_intensities(7.0)
    assert q[0] > 0 and q[0] == q[1]


def test_stable_baselines3_drives_the_batch():
    pytest.importorskip("stable_baselines3", reason="the rl extra is not installed")
    from stable_baselines3.common.vec_env import VecEnv

    from shipgym.rl.vec import make_batched_vec_env

    for env_id in IDS:
        assert env_id in VECTOR_IDS
        sb3 = make_batched_vec_env(env_id, N, seed=0, episode_duration=0.5)
        assert isinstance(sb3, VecEnv)
        o = sb3.reset()
        for _ in range(5):
            o, r, d, infos = sb3.step(np.zeros((N, 1), np.float32))
        assert o.shape == (N, *sb3.observation_space.shape) and r.dtype == np.float32
        assert d.all() and all("terminal_observation" in x for x in infos)  # 5 steps, then end
        sb3.close()


def test_rgb_array_render_of_the_single_env():
    snippet = (
        "import gymnasium as gym, shipgym\n"
        "env = gym.make('shipgym/NavalRollDamping-v0', render_mode='rgb_array')\n"
        "env.reset(seed=0)\n"
        "print('SHAPE', env.render().shape)\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "DISPLAY")}
    env["MUJOCO_GL"] = "egl"
    res = subprocess.run([sys.executable, "-c", snippet], env=env, capture_output=True,
                         text=True, timeout=120)  # fmt: skip
    if res.returncode != 0:
        pytest.skip("no EGL rendering on this machine")
    assert "SHAPE (480, 640, 3)" in res.stdout
