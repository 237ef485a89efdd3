"""The course-keeping task written once over N envs (CourseKeepingVectorEnv): env i of
``gymnasium.make_vec("shipgym/CourseKeeping-v0", num_envs=N)`` reset with seed s + i is the
single env (``gym.make``) reset with that seed, bit for bit, over whole episodes with
autoresets in both autoreset modes, for every packaged vessel that fits the task and every
velocity source; gymnasium's check_env on the single env; SB3's VecEnv use of the batch."""

from __future__ import annotations

import os
import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import shipgym
from shipgym.envs.coursekeeping import RECEIVERS, CourseKeepingEnv, CourseKeepingVectorEnv
from shipgym.envs.registration import task_fits_vessel

ID = "shipgym/CourseKeeping-v0"
VESSELS = [n for n in shipgym.vessels() if task_fits_vessel(ID, shipgym.load_vessel(n))]
#: short episodes with set-point changes inside them, each vessel with another velocity source
KW = {"episode_duration": 7.0, "setpoint_period": 3.0}


def _kw(vessel):
    return {"vessel": vessel, "receiver": RECEIVERS[VESSELS.index(vessel) % 3], **KW}


def _same_info(vec, i, single, where):
    """Every key of the single env's info equals row i of the batch's (nested dicts too)."""
    for k, v in single.items():
        if isinstance(v, dict):
            _same_info(vec[k], i, v, f"{where}.{k}")
        else:
            assert vec.get(f"_{k}", np.ones(i + 1, bool))[i], f"{where}: {k} masked out"
            assert np.array_equal(vec[k][i], v), f"{where}: {k} {vec[k][i]} != {v}"


@pytest.mark.parametrize("mode", ["next-step", "same-step"])
@pytest.mark.parametrize("vessel", VESSELS)
def test_env_i_is_the_single_env_seeded_seed_plus_i(vessel, mode):
    n, seed = 3, 40
    venv = gym.make_vec(ID, num_envs=n, autoreset_mode=mode, **_kw(vessel))
    assert isinstance(venv.unwrapped, CourseKeepingVectorEnv)
    singles = [gym.make(ID, **_kw(vessel)) for _ in range(n)]
    obs, info = venv.reset(seed=seed)
    for i, s in enumerate(singles):
        o, inf = s.reset(seed=seed + i)
        assert np.array_equal(obs[i], o)
        _same_info(info, i, inf, "reset")
    rng = np.random.default_rng(1)
    pending = np.zeros(n, bool)  # next-step: the batch resets these envs at this step
    ends = 0
    for k in range(24):
        if k == 10:  # a partial reset: env 1 only, its generator goes on
            obs, info = venv.reset(options={"reset_mask": np.array([False, True, False])})
            o, inf = singles[1].reset()
            assert np.array_equal(obs[1], o) and not info["_eta"][0]
            _same_info(info, 1, inf, "masked reset")
            pending[1] = False
        actions = rng.uniform(-1.3, 1.3, (n, *venv.single_action_space.shape)).astype(np.float32)
        obs, rew, term, trunc, info = venv.step(actions)
        for i, s in enumerate(singles):
            if pending[i]:
                o, inf = s.reset()
                assert rew[i] == 0.0 and not term[i] and not trunc[i]
                assert np.array_equal(obs[i], o)
                _same_info(info, i, inf, "autoreset")
                continue
            o, r, te, tr, inf = s.step(actions[i])
            assert rew[i] == r and (bool(term[i]), bool(trunc[i])) == (te, tr)
            if te or tr:
                ends += 1
                metrics = inf.pop("episode_metrics")
                assert info["_episode_metrics"][i]
                _same_info(info["episode_metrics"], i, metrics, "metrics")
                assert metrics["steps"] == 7 and isinstance(metrics["receiver"], str)
            if mode == "same-step" and (te or tr):
                assert np.array_equal(info["final_obs"][i], o)
                _same_info(info["final_info"], i, inf, "final info")
                o, inf = s.reset()
                assert np.array_equal(obs[i], o)
                continue
            assert np.array_equal(obs[i], o)
            _same_info(info, i, inf, "step")
        pending = (term | trunc) if mode == "next-step" else np.zeros(n, bool)
    assert ends >= 2 * n


@pytest.mark.parametrize("vessel", VESSELS)
def test_gymnasium_check_env_on_the_single_env(vessel):
    env = gym.make(ID, **_kw(vessel))
    assert isinstance(env.unwrapped, CourseKeepingEnv)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(env.unwrapped, skip_render_check=True)
    env.reset(seed=0)
    for _ in range(7):
        *_, trunc, info = env.step(np.zeros(env.action_space.shape, np.float32))
    assert trunc and info["episode_metrics"]["steps"] == 7
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(env.action_space.shape, np.float32))


def test_sb3_vec_env_of_the_batch():
    pytest.importorskip("stable_baselines3", reason="the rl extra is not installed")
    from stable_baselines3.common.vec_env import VecEnv

    from shipgym.rl.vec import make_batched_vec_env

    n = 3
    sb3 = make_batched_vec_env(ID, n, seed=5, **KW)
    assert isinstance(sb3, VecEnv)
    singles = [gym.make(ID, **KW) for _ in range(n)]
    obs = sb3.reset()
    for i, s in enumerate(singles):
        assert np.array_equal(obs[i], s.reset(seed=5 + i)[0])
    actions = np.full((n, *sb3.action_space.shape), 0.2, np.float32)
    for _ in range(10):
        obs, r, done, infos = sb3.step(actions)
        assert obs.shape == (n, *sb3.observation_space.shape) and r.dtype == np.float32
        for i, s in enumerate(singles):
            o, ri, te, tr, _ = s.step(actions[i])
            assert r[i] == np.float32(ri) and done[i] == (te or tr)
            if done[i]:
                assert np.array_equal(infos[i]["terminal_observation"], o)
                assert infos[i]["TimeLimit.truncated"]
                o, _ = s.reset()
            assert np.array_equal(obs[i], o)
    assert sb3.get_attr("U") == [7.0] * n


def test_the_batch_refuses_bad_input():
    with pytest.raises(ValueError, match="num_envs"):
        CourseKeepingVectorEnv(0, vessel="kvlcc2-100m")
    with pytest.raises(TypeError, match="vessel=NAME"):
        CourseKeepingVectorEnv(2)
    venv = gym.make_vec(ID, num_envs=2)
    venv.reset(seed=0)
    with pytest.raises(ValueError, match="NaN"):
        venv.step(np.array([[0.0], [np.nan]]))


def test_the_single_env_renders_its_hull():
    snippet = (
        "import gymnasium as gym, shipgym\n"
        "env = gym.make('shipgym/CourseKeeping-v0', render_mode='rgb_array')\n"
        "env.reset(seed=0)\n"
        "env.step(env.action_space.sample())\n"
        "f = env.render()\n"
        "print('SHAPE', f.shape, f.dtype, int(f.std() > 1))\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"} | {"MUJOCO_GL": "egl"}
    res = subprocess.run([sys.executable, "-c", snippet], env=env, capture_output=True,
                         text=True, timeout=120)  # fmt: skip
    if res.returncode != 0 and "MUJOCO_GL" in res.stderr:
        pytest.skip("no EGL on this machine")
    assert "SHAPE (480, 640, 3) uint8 1" in res.stdout, res.stderr[-2000:]
