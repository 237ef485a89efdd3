"""rl-zoo3's ``env_wrapper`` form of the observer (:class:`shipgym.observers.wrapper.
ObserverWrapper`) under SB3's ``make_vec_env``, which puts its ``Monitor`` below the wrapper."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import shipgym
from shipgym.observers.wrapper import ObserverWrapper

pytest.importorskip("stable_baselines3")

KW = {"vessel": "star-hercules"}


def test_under_make_vec_env_the_monitor_stays_and_the_env_is_shipgyms():
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.monitor import Monitor

    venv = make_vec_env("shipgym/StationKeeping-v0", n_envs=1, env_kwargs=KW,
                        wrapper_class=ObserverWrapper, seed=3)  # fmt: skip
    env = venv.envs[0]
    assert isinstance(env, ObserverWrapper) and isinstance(env.env, Monitor)
    assert env.unwrapped.observer_name == "kbf"
    ref = shipgym.make("shipgym/StationKeeping-v0", observer="kbf", **KW)
    assert venv.observation_space == ref.observation_space
    obs = venv.reset()
    want, _ = ref.reset(seed=3)
    np.testing.assert_array_equal(obs[0], want)
    a = np.full((1, venv.action_space.shape[0]), 0.3, np.float32)
    for _ in range(20):
        obs, _, _, _ = venv.step(a)
        want, *_ = ref.step(a[0])
        np.testing.assert_array_equal(obs[0], want)
    venv.close()


def test_on_a_plain_gym_make_env_and_its_errors():
    env = ObserverWrapper(gym.make("shipgym/StationKeeping-v0", **KW), observer="dkf")
    assert env.unwrapped.observer_name == "dkf"
    with pytest.raises(ValueError, match="already runs observer"):
        ObserverWrapper(env)
    with pytest.raises(ValueError, match="made by gym.make"):
        ObserverWrapper(gym.make("CartPole-v1"))
