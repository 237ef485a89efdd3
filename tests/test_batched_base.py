"""The batched-env mechanics (shipgym.envs.batched) on a toy family defined here: seeding,
autoreset modes, info masks, the single env as the batch of one."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from gymnasium.utils.env_checker import check_env

from shipgym.envs.batched import BatchedEnv, SingleEnv, unbatch


class Walk(BatchedEnv):
    """A random walk x += a + noise, truncated after ``length`` steps."""

    def __init__(self, num_envs: int, length: int = 3, autoreset_mode: str = "next-step"):
        box = spaces.Box(-np.inf, np.inf, (1,), np.float32)
        self._setup(num_envs, box, spaces.Box(-1.0, 1.0, (1,), np.float32), autoreset_mode)
        self.length = length
        self.x = np.zeros(num_envs)
        self.k = np.zeros(num_envs, dtype=np.int64)

    def _reset_envs(self, mask):
        for i in np.nonzero(mask)[0]:
            self.x[i] = self._rngs[i].normal()
        self.k[mask] = 0

    def _observation(self):
        return self.x[:, None].astype(np.float32)

    def _reset_info(self, mask):
        return {"x": self.x.copy()}

    def _step_envs(self, actions, active):
        pairs = zip(self._rngs, active, strict=True)
        noise = np.array([r.normal() if a else 0.0 for r, a in pairs])
        self.x = np.where(active, self.x + actions[:, 0] + noise, self.x)
        self.k += active
        info = {"x": self.x.copy(), "r": -(self.x**2)}
        return -(self.x**2), np.zeros(self.num_envs, bool), self.k >= self.length, info

    def _episode_metrics(self, done):
        return {"final_x": self.x.copy()}


class OneWalk(SingleEnv):
    batched = Walk


def _rollout(env, seed, steps):
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for _ in range(steps):
        obs, r, term, trunc, info = env.step(np.full(env.action_space.shape, 0.5, np.float32))
        out.append((obs, r, term, trunc))
        if term or trunc:
            out.append(info["episode_metrics"]["final_x"])
            obs, _ = env.reset()
            out.append(obs)
    return out


def test_env_i_is_the_single_env_seeded_seed_plus_i():
    vec = Walk(3, autoreset_mode="same-step")
    obs, info = vec.reset(seed=10)
    assert info["_x"].all()
    singles = [OneWalk() for _ in range(3)]
    s_obs = [e.reset(seed=10 + i)[0] for i, e in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.stack(s_obs))
    for _ in range(7):
        obs, r, term, trunc, info = vec.step(np.full((3, 1), 0.5))
        for i, e in enumerate(singles):
            o, ri, te, tr, inf = e.step(np.array([0.5], np.float32))
            assert r[i] == ri and trunc[i] == tr
            if tr:  # same-step: the batch reset this env; the final obs is kept aside
                np.testing.assert_array_equal(info["final_obs"][i], o)
                assert info["episode_metrics"]["final_x"][i] == inf["episode_metrics"]["final_x"]
                o, _ = e.reset()
            np.testing.assert_array_equal(obs[i], o)


def test_next_step_autoreset_ignores_the_action_and_zeroes_the_reward():
    vec = Walk(2, length=2)
    vec.reset(seed=0)
    vec.step(np.zeros((2, 1)))
    _, _, _, trunc, info = vec.step(np.zeros((2, 1)))
    assert trunc.all() and info["_episode_metrics"].all()
    obs, r, term, trunc, info = vec.step(np.ones((2, 1)))
    assert not trunc.any() and (r == 0).all()
    assert (info["r"] == 0).all()  # a step-only float is zeroed for a resetting env
    np.testing.assert_array_equal(obs[:, 0], vec.x.astype(np.float32))
    fresh = Walk(2, length=2)
    o2, _ = fresh.reset(seed=0)
    assert not np.array_equal(o2, obs)  # the generator went on, it was not re-seeded


def test_a_masked_reset_leaves_the_last_steps_info_as_it_was():
    """A reset by mask after an episode end (next-step mode) does not change the mask the
    last step handed out in its ``info``."""
    vec = Walk(2, length=2)
    vec.reset(seed=0)
    vec.step(np.zeros((2, 1)))
    _, _, _, trunc, info = vec.step(np.zeros((2, 1)))
    assert trunc.all() and info["_episode_metrics"].all()
    vec.reset(options={"reset_mask": np.array([True, False])})
    assert info["_episode_metrics"].tolist() == [True, True]


def test_bad_actions_and_options_are_refused():
    vec = Walk(2)
    with pytest.raises(gym.error.ResetNeeded):
        vec.step(np.zeros((2, 1)))
    vec.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        vec.step(np.zeros((3, 1)))
    with pytest.raises(ValueError, match="envs \\[1\\]"):
        vec.step(np.array([[0.0], [np.nan]]))
    with pytest.raises(ValueError, match="reset options"):
        vec.reset(options={"nope": 1})
    with pytest.raises(ValueError, match="num_envs"):
        Walk(0)


def test_single_env_passes_gymnasiums_check_and_unbatches_scalars():
    env = OneWalk()
    check_env(env, skip_render_check=True)
    _, info = env.reset(seed=1)
    assert isinstance(info["x"], float)
    assert unbatch({"a": np.ones((1, 2)), "_a": np.ones(1, bool)}).keys() == {"a"}
    env.step(np.zeros(1, np.float32))
    env.step(np.zeros(1, np.float32))
    _, _, _, trunc, info = env.step(np.zeros(1, np.float32))
    assert trunc and "final_x" in info["episode_metrics"]
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(1, np.float32))
