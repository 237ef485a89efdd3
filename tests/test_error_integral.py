"""The leaky error integral appended to the observation (shipgym.envs.integral): the closed
form for a constant error, the batched SB3 adapter against DummyVecEnv of single wrappers
(autoresets and terminal observations included), the zoo-form env_wrapper, and the model
loader rebuilding the stack from the metadata."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from shipgym.envs.integral import ErrorIntegralObservation

pytest.importorskip("stable_baselines3")
pytest.importorskip("torch")

from stable_baselines3.common.vec_env import DummyVecEnv  # noqa: E402

from shipgym.rl import train as train_mod  # noqa: E402
from shipgym.rl.train import build_vec_env, load_hyperparams, train  # noqa: E402

ID = "shipgym/BlueLadyTracking-v0"


class _ConstantError(gym.Env):
    """A stub with the shipgym observation layout whose errors are constant."""

    observation_structure = {"pos_error_body": slice(0, 3)}
    control_period = 2.0
    observation_space = gym.spaces.Box(-np.inf, np.inf, (5,), np.float32)
    action_space = gym.spaces.Box(-1, 1, (1,), np.float32)
    e = np.array([0.5, -0.25, 0.125, 9.0, 9.0], np.float32)

    def reset(self, *, seed=None, options=None):
        return self.e.copy(), {}

    def step(self, action):
        return self.e.copy(), 0.0, False, False, {}


def test_closed_form_for_a_constant_error():
    T, dt = 50.0, 2.0
    env = ErrorIntegralObservation(_ConstantError(), time_constant=T)
    obs, _ = env.reset()
    assert obs.shape == (8,) and np.all(obs[5:] == 0) and np.all(obs[:5] == _ConstantError.e)
    lam = math.exp(-dt / T)
    for k in range(1, 200):
        obs, *_ = env.step(np.zeros(1))
        want = dt * _ConstantError.e[:3] * (1 - lam**k) / (1 - lam)
        np.testing.assert_allclose(obs[5:], want, rtol=1e-6)
    np.testing.assert_allclose(obs[5:], T * _ConstantError.e[:3], rtol=0.03)  # -> ~T e
    env.reset()
    obs, *_ = env.step(np.zeros(1))
    np.testing.assert_allclose(obs[5:], dt * _ConstantError.e[:3], rtol=1e-6)  # reset zeroes
    assert env.observation_structure["error_integral"] == slice(5, 8)


def test_needs_a_positioning_env_and_a_sane_time_constant():
    with pytest.raises(ValueError, match="time_constant"):
        ErrorIntegralObservation(_ConstantError(), time_constant=0.0)
    with pytest.raises(ValueError, match="positioning env"):
        ErrorIntegralObservation(gym.make("CartPole-v1"), time_constant=10.0)


def _hp(integral=100.0):
    hp = load_hyperparams("ppo", ID)
    hp["env_kwargs"] = dict(hp["env_kwargs"], max_legs=1)
    hp["error_integral"] = integral
    return hp


def test_batched_adapter_equals_dummy_vec_env_of_single_wrappers():
    n, hp = 3, _hp(40.0)
    hp["env_kwargs"]["max_episode_steps"] = 7  # autoresets within the test
    batched = build_vec_env(ID, hp, n, 5, "batched").venv  # inside VecMonitor
    dummy = build_vec_env(ID, hp, n, 5, "dummy").venv
    assert isinstance(dummy, DummyVecEnv)
    assert batched.observation_space.shape == dummy.observation_space.shape == (18,)
    for venv in (batched, dummy):
        venv.seed(5)
    np.testing.assert_allclose(batched.reset(), dummy.reset(), rtol=0, atol=1e-6)
    rng = np.random.default_rng(2)
    dones = 0
    for _ in range(17):
        a = rng.uniform(-1, 1, (n, 3)).astype(np.float32)
        o1, _, d1, i1 = batched.step(a)
        o2, _, d2, i2 = dummy.step(a)
        np.testing.assert_array_equal(d1, d2)
        np.testing.assert_allclose(o1, o2, rtol=1e-5, atol=1e-5)
        for i in np.nonzero(d1)[0]:
            t1, t2 = i1[i]["terminal_observation"], i2[i]["terminal_observation"]
            np.testing.assert_allclose(t1, t2, rtol=1e-5, atol=1e-5)
            assert np.abs(t1[15:]).max() > 0  # the integral up to the end, not zeroed
            assert np.all(o1[i, 15:] == 0)  # the next episode starts from zero
            dones += 1
    assert dones >= 2 * n


def test_zoo_form_env_wrapper_is_parsed_in_order_only():
    obs = {train_mod.OBSERVER_WRAPPER: {"observer": "kbf"}}
    integ = {train_mod.INTEGRAL_WRAPPER: {"time_constant": 80}}
    assert train_mod.parse_env_wrapper([obs, integ]) == ("kbf", 80.0)
    assert train_mod.parse_env_wrapper([obs]) == ("kbf", None)
    with pytest.raises(ValueError, match="supports"):
        train_mod.parse_env_wrapper([integ, obs])
    with pytest.raises(ValueError, match="time_constant"):
        train_mod.parse_env_wrapper([obs, {train_mod.INTEGRAL_WRAPPER: {"tau": 3}}])
    with pytest.raises(ValueError, match="time_constant"):
        train_mod.parse_env_wrapper([obs, {train_mod.INTEGRAL_WRAPPER: {"time_constant": -1}}])
    mod, _, name = train_mod.INTEGRAL_WRAPPER.rpartition(".")  # importable as rl-zoo3 does
    import importlib

    assert getattr(importlib.import_module(mod), name) is ErrorIntegralObservation


def test_a_model_with_the_integral_runs_through_the_loader(tmp_path):
    from shipgym.controllers.learned import (
        LearnedControllerWrapper,
        read_metadata,
    )
    from shipgym.stacks import make, make_learned_env

    run = train("ppo", timesteps=128, seed=0, n_envs=2, out=tmp_path, vec_env="batched",
                eval_freq=0, checkpoint_freq=0, overrides={"n_steps": 64, "batch_size": 64,
                "n_epochs": 1, "error_integral": 60.0})  # fmt: skip
    meta = read_metadata(run.model_path)
    assert meta.error_integral == 60.0 and meta.observation_shape == (18,)
    env = make_learned_env("shipgym/BlueLadyHarbour-v0", run.model_path)
    obs, _ = env.reset(seed=0)
    assert obs.shape == (18,)
    _, _, _, _, info = env.step(np.zeros(3, np.float32))
    assert np.all(np.isfinite(info["policy_action"]))
    bare = make("shipgym/BlueLadyHarbour-v0", observer="kbf")
    with pytest.raises(ValueError, match="error integral"):
        LearnedControllerWrapper(bare, run.model_path)
    wrong = ErrorIntegralObservation(make("shipgym/BlueLadyHarbour-v0", observer="kbf"), 30.0)
    with pytest.raises(ValueError, match="time constant"):
        LearnedControllerWrapper(wrong, run.model_path)
