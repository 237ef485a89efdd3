"""Written once, tested for free: a new task (hold a heading at the reference speed) and a
new observer (an alpha-beta filter) defined in this file alone run single and batched,
through ``gym.make`` / ``shipgym.make`` and ``gym.make_vec``, with no change to a package
file: each is one function over N envs that both envs run, so env i of the batch is the
single env seeded ``seed + i`` to the last bit."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import shipgym
from shipgym.dynamics.frames import wrap_angle
from shipgym.envs.base import ShipEnv
from shipgym.envs.task import PlanTask
from shipgym.envs.vector import ShipVectorEnv
from shipgym.guidance import Leg, ManoeuvrePlan
from shipgym.guidance.rframe import to_r_frame
from shipgym.observers.base import OBSERVERS
from shipgym.observers.batch import BATCHED_OBSERVERS, BatchedStepInfo, register_batched_observer

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


# ---- a new observer -------------------------------------------------------------------------
class AlphaBeta:
    """An alpha-beta filter per DOF on the NED pose (Kalata 1984), N envs at once: predict
    ``p += v dt``, then with a fix ``p += alpha r``, ``v += beta r / dt`` (``r`` the
    innovation, the heading's wrapped); the body velocity ``nu = R(psi)^T v``."""

    def __init__(self, n, vessel, alpha=0.5, beta=0.1):
        self.alpha, self.beta = alpha, beta
        self.p = np.zeros((n, 3))
        self.v = np.zeros((n, 3))
        self.t = np.zeros(n)

    def reset(self, t0, eta0, mask=None):
        m = np.ones(self.t.shape, bool) if mask is None else np.asarray(mask, bool)
        self.t = np.where(m, np.broadcast_to(t0, self.t.shape), self.t)
        self.p[m] = np.asarray(eta0, float)[m]
        self.v[m] = 0.0

    def step(self, t, z, valid):
        dt = np.asarray(t, float) - self.t
        self.p += self.v * dt[:, None]
        r = np.where(valid[:, None], np.nan_to_num(z) - self.p, 0.0)
        r[:, 2] = wrap_angle(r[:, 2])
        safe = np.where(dt > 0, dt, 1.0)
        self.p += self.alpha * r
        self.v += np.where((dt > 0)[:, None], self.beta * r / safe[:, None], 0.0)
        self.t = np.array(t, float)
        nis = np.where(valid, (r * r).sum(axis=1), np.nan)
        no = np.zeros(self.t.shape, bool)
        return BatchedStepInfo(np.where(valid[:, None], r, np.nan), nis, no, no)

    @property
    def eta(self):
        return self.p.copy()

    @property
    def nu(self):
        c, s = np.cos(self.p[:, 2]), np.sin(self.p[:, 2])
        vx, vy, r = self.v.T
        return np.stack([c * vx + s * vy, -s * vx + c * vy, r], axis=1)


@pytest.fixture(scope="module")
def alpha_beta():
    register_batched_observer("test-alpha-beta", AlphaBeta)
    yield "test-alpha-beta"
    BATCHED_OBSERVERS.pop("test-alpha-beta", None)
    OBSERVERS.pop("test-alpha-beta", None)


@pytest.mark.parametrize("controller", [None, "pid"])
def test_the_new_observer_single_and_batched_is_one_code_path(alpha_beta, controller):
    """The alpha-beta filter estimates for the observation (and the PID), single through the
    single env, batched inside the vector env: the same estimates and observations."""
    env_id, n = "shipgym/Tracking-v0", 2
    kw = {"vessel": "blue-lady", "observer": alpha_beta, "max_episode_steps": 60, "max_legs": 1}
    if controller:
        kw["controller"] = controller
    venv = gym.make_vec(env_id, num_envs=n, **kw)
    singles = [shipgym.make(env_id, **kw) for _ in range(n)]
    obs, info = venv.reset(seed=4)
    for i, s in enumerate(singles):
        o, inf = s.reset(seed=4 + i)
        np.testing.assert_array_equal(obs[i], o)
        np.testing.assert_array_equal(info["nav_eta"][i], inf["nav_eta"])
    rng = np.random.default_rng(2)
    err = []
    for _ in range(50):
        a = rng.uniform(-0.3, 0.3, (n, 3)).astype(np.float32)
        obs, rew, term, trunc, info = venv.step(a)
        for i, s in enumerate(singles):
            o, r, te, tr, inf = s.step(a[i])
            np.testing.assert_array_equal(obs[i], o)
            np.testing.assert_array_equal(info["nav_eta"][i], inf["nav_eta"])
            assert r == rew[i]
            err.append(np.abs(inf["nav_eta"][:2] - inf["eta"][:2]).max())
    assert not np.array_equal(info["nav_eta"], info["eta"])  # the estimate, not the truth
    assert np.median(err) < 0.5  # and a working filter: within half a metre of the truth
