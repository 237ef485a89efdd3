"""What the learning tasks add for the learned baselines: the saturated tracking terms of
:class:`RewardWeights` (the analytic formula from the step's own errors, the raw square for
small errors, a bound however far off, the same in the batched env as in gymnasium's
SyncVectorEnv, clear errors for bad scales) and station keeping's per-episode random wind."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import shipgym  # noqa: F401  (registers the ids)
from shipgym.dynamics import wrap_angle
from shipgym.envs.base import RewardWeights, tracking_penalty

SCALES = {"position_scale": 2.0, "heading_scale": 0.5, "velocity_scale": 0.3}


def test_penalty_is_the_square_near_zero_and_bounded_far_off():
    for q in (1e-3, 0.01):
        assert tracking_penalty(3.0, q * q, 2.0) == pytest.approx(3.0 * q * q, rel=q * q / 4.0)
    assert tracking_penalty(3.0, 1e6, 2.0) == pytest.approx(3.0 * 4.0)
    assert tracking_penalty(3.0, 4.0, 2.0) == pytest.approx(12.0 * (1 - math.exp(-1.0)))
    assert tracking_penalty(3.0, 4.0, None) == 12.0
    q2 = np.array([0.0, 4.0, 1e6])
    np.testing.assert_allclose(
        tracking_penalty(3.0, q2, 2.0), [tracking_penalty(3.0, float(x), 2.0) for x in q2]
    )


def test_env_terms_follow_the_formula_from_truth():
    """The terms in info against the formula applied to the truth in info (eta_r, eta_d_r,
    nu and the reference velocity), for a ship driven well off its reference."""
    w = RewardWeights(**SCALES)
    env = gym.make("shipgym/BlueLadyTracking-v0", reward_weights=dict(SCALES), max_legs=1)
    env.reset(seed=3)
    worst = 0.0
    for _ in range(120):
        _, r, term, trunc, info = env.step(np.array([1.0, 1.0, -1.0], np.float32))
        e = info["eta_r"] - info["eta_d_r"]
        worst = max(worst, math.hypot(e[0], e[1]))
        p = -tracking_penalty(w.position, e[0] ** 2 + e[1] ** 2, 2.0)
        h = -tracking_penalty(w.heading, wrap_angle(e[2]) ** 2, 0.5)
        assert info["reward_position"] == pytest.approx(p, rel=1e-9, abs=1e-12)
        assert info["reward_heading"] == pytest.approx(h, rel=1e-9, abs=1e-12)
        assert info["reward_position"] >= -w.position * 4.0
        terms = [k for k in info if k.startswith("reward_")]
        assert r == pytest.approx(sum(info[k] for k in terms))
        if term or trunc:
            break
    assert worst > 4.0  # far into the saturation: the bound was exercised


def test_batched_env_gives_the_single_envs_saturated_rewards():
    kw = {"vessel": "blue-lady", "max_episode_steps": 30, "reward_weights": dict(SCALES)}
    native = gym.make_vec("shipgym/Tracking-v0", num_envs=2,
                          vectorization_mode="vector_entry_point", **kw)  # fmt: skip
    sync = gym.make_vec("shipgym/Tracking-v0", num_envs=2, vectorization_mode="sync", **kw)
    native.reset(seed=2)
    sync.reset(seed=2)
    rng = np.random.default_rng(0)
    for _ in range(30):
        a = rng.uniform(-1, 1, (2, 3)).astype(np.float32)
        _, r1, _, _, i1 = native.step(a)
        _, r2, _, _, i2 = sync.step(a)
        np.testing.assert_allclose(r1, r2, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(i1["reward_position"], i2["reward_position"], rtol=1e-9)


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), "2", True])
def test_bad_scale_is_refused(bad):
    with pytest.raises(ValueError, match="position_scale.*None"):
        RewardWeights(position_scale=bad)


def test_station_keeping_random_wind_draws_per_episode_and_keeps_the_gusts():
    """random_wind: a mean speed in [low, high] and any direction per episode, seeded, the
    gusts of wind= kept; the batched env draws the same; without it the stream is unchanged."""
    kw = {"vessel": "star-hercules", "wind": "10@300"}
    env = gym.make("shipgym/StationKeeping-v0", random_wind=(6, 11), **kw).unwrapped
    base = gym.make("shipgym/StationKeeping-v0", **kw).unwrapped
    draws = []
    for seed in range(40):
        env.reset(seed=seed)
        w = env.wind_config
        assert 6.0 <= w.speed <= 11.0 and 0.0 <= w.direction_from < 2 * math.pi
        assert w.gust_std == base.task.wind.gust_std
        draws.append((w.speed, w.direction_from))
    d = np.array(draws)
    assert d[:, 1].max() - d[:, 1].min() > 5.0 and d[:, 0].std() > 1.0  # spread, not fixed
    env.reset(seed=3)
    again = (env.wind_config.speed, env.wind_config.direction_from)
    assert again == draws[3]
    # the batched env: env i with seed 3 + i has the single env's draw of seed 3 + i
    venv = gym.make_vec("shipgym/StationKeeping-v0", num_envs=2, random_wind=(6, 11),
                        vectorization_mode="vector_entry_point", **kw)  # fmt: skip
    venv.reset(seed=3)
    got = [(w.speed, w.direction_from) for w in venv.unwrapped.physics.wind_configs]
    assert got == draws[3:5]
    # without the option: the given wind, and the start draw as before
    base.reset(seed=3)
    assert base.wind_config.speed == 10.0
    with pytest.raises(ValueError, match="random_wind"):
        gym.make("shipgym/StationKeeping-v0", random_wind=(5, 1), **kw)
    with pytest.raises(ValueError, match="random_wind"):
        gym.make("shipgym/StationKeeping-v0", random_wind="fast", **kw)
