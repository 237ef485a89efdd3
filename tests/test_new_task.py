"""Written once, tested for free: a new task defined in this file alone (hold a heading at
the reference speed) runs single and batched, through ``gym.make`` and ``gym.make_vec``, with
no change to a package file: its episode draws, observation and reward terms are one
function over N envs that both envs run, so env i of the batch is the single env seeded
``seed + i`` to the last bit."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from shipgym.dynamics.frames import wrap_angle
from shipgym.envs.base import ShipEnv
from shipgym.envs.task import PlanTask
from shipgym.envs.vector import ShipVectorEnv
from shipgym.guidance import Leg, ManoeuvrePlan
from shipgym.guidance.rframe import to_r_frame

ID = "shipgym-test/HeadingAtSpeed-v0"
STEPS = 40


class HeadingAtSpeedTask(PlanTask):
    """Follow a long straight leg: keep the reference heading and the reference surge speed,
    from a perturbed start; a drawn beam wind (0-4 m/s from either side) each episode."""

    default_scene = "open-water"
    reward_terms = ("reward_heading", "reward_speed", "reward_effort")

    def __init__(self, vessel=None, **kwargs):
        kwargs.setdefault("plan", ManoeuvrePlan(legs=(Leg(surge=400.0),), name="heading"))
        kwargs.setdefault("start_noise", (1.0, 1.0, 0.1))
        kwargs.setdefault("terminate_on_finish", False)
        super().__init__(vessel, **kwargs)

    def episode_wind(self, rng):
        speed = rng.uniform(0.0, 4.0)
        side = 1.0 if rng.random() < 0.5 else -1.0
        if self.wind is None:
            return None
        return dataclasses.replace(self.wind, speed=speed, direction_from=side * np.pi / 2)

    def observation_structure(self, n_actions):
        names = (("heading_error", 1), ("speed_error", 1), ("yaw_rate", 1),
                 ("prev_action", n_actions))  # fmt: skip
        out, i = {}, 0
        for name, k in names:
            out[name] = slice(i, i + k)
            i += k
        return out, i

    def terms(self, eta, nu, nav_eta, nav_nu, ref, action, prev, switched, new_contact, obs,
              rew, eta_r):  # fmt: skip
        psi_d, u_d = ref[:, 4, 2], ref[:, 6, 0]  # the reference buffer's rows (eta_d_n, nu_d)
        obs[:, 0] = wrap_angle(nav_eta[:, 2] - psi_d)
        obs[:, 1] = nav_nu[:, 0] - u_d
        obs[:, 2] = nav_nu[:, 2]
        obs[:, 3:] = action
        rew[:, 0] = -(wrap_angle(eta[:, 2] - psi_d) ** 2)
        rew[:, 1] = -((nu[:, 0] - u_d) ** 2)
        rew[:, 2] = -0.01 * (action * action).sum(axis=1)
        eta_r[:] = to_r_frame(eta, ref[:, 3], ref[:, 0, 2])


class HeadingAtSpeedEnv(ShipEnv):
    """:class:`ShipEnv` with :class:`HeadingAtSpeedTask`."""

    task_class = HeadingAtSpeedTask


def heading_vector_env(num_envs, **kwargs):
    kwargs.setdefault("max_episode_steps", STEPS)
    return ShipVectorEnv(num_envs, HeadingAtSpeedEnv, **kwargs)


@pytest.fixture(scope="module", autouse=True)
def registered():
    gym.register(ID, entry_point=HeadingAtSpeedEnv, vector_entry_point=heading_vector_env,
                 max_episode_steps=STEPS)  # fmt: skip
    yield
    gym.registry.pop(ID, None)


@pytest.mark.parametrize("vessel", ["blue-lady", "wimpey-sealab"])
def test_the_new_task_single_and_batched_is_one_code_path(vessel):
    env = gym.make(ID, vessel=vessel)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.unwrapped.observation_structure["prev_action"].stop == env.observation_space.shape[0]
    n = 3
    venv = gym.make_vec(ID, num_envs=n, vessel=vessel)
    singles = [gym.make(ID, vessel=vessel) for _ in range(n)]
    obs, _ = venv.reset(seed=7)
    for i, s in enumerate(singles):
        o, _ = s.reset(seed=7 + i)
        np.testing.assert_array_equal(obs[i], o)
    rng = np.random.default_rng(1)
    pending = np.zeros(n, bool)
    ends = 0
    winds = set()
    for _ in range(2 * STEPS + 5):
        a = rng.uniform(-1, 1, (n, venv.single_action_space.shape[0])).astype(np.float32)
        obs, rew, term, trunc, info = venv.step(a)
        for i, s in enumerate(singles):
            if pending[i]:
                o, _ = s.reset()
                assert rew[i] == 0.0
            else:
                o, r, te, tr, inf = s.step(a[i])
                assert (te, tr) == (bool(term[i]), bool(trunc[i]))
                assert r == rew[i] == sum(inf[k] for k in HeadingAtSpeedTask.reward_terms)
                np.testing.assert_array_equal(info["eta"][i], inf["eta"])
                winds.add(round(s.unwrapped.wind_config.speed, 9))
            np.testing.assert_array_equal(obs[i], o)
        ends += int((term | trunc).sum())
        pending = term | trunc
    assert ends >= n  # every env ended an episode (the time limit) and was reset
    assert len(winds) > n  # each episode its own drawn wind
