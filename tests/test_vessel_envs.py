"""Every registered vessel x every task: Gymnasium and SB3 check_env, determinism, spec round
trip, the action space from the actuators. A new vessel package is tested here for free."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from _helpers import step_singles
from gymnasium.utils.env_checker import check_env

import shipgym
from shipgym.dynamics.vessel import load_vessel, vessel_names
from shipgym.envs.registration import ALIASES, NEEDS, VECTOR_IDS, task_fits_vessel
from shipgym.envs.scene import fits

TASKS = [i for i in shipgym.ENV_IDS if i not in ALIASES]
CASES = [
    (task, vessel)
    for task in TASKS
    for vessel in vessel_names()
    if task_fits_vessel(task, load_vessel(vessel))
    and (task != "shipgym/Harbour-v0" or fits(load_vessel(vessel), "harbour"))
]
IDS = [f"{t.split('/')[1]}-{v}" for t, v in CASES]


def _make(task: str, vessel: str, **kw):
    return gym.make(task, vessel=vessel, **kw)


@pytest.mark.parametrize(("task", "vessel"), CASES, ids=IDS)
def test_gymnasium_check_env(task: str, vessel: str) -> None:
    env = _make(task, vessel)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # infinite observation bounds are intended
        check_env(env.unwrapped, skip_render_check=True)
    env.close()


@pytest.mark.parametrize(("task", "vessel"), CASES, ids=IDS)
def test_sb3_check_env(task: str, vessel: str) -> None:
    checker = pytest.importorskip(
        "stable_baselines3.common.env_checker", reason="the rl extra is not installed"
    )
    env = _make(task, vessel)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        checker.check_env(env, warn=False)
    env.close()


@pytest.mark.parametrize(("task", "vessel"), CASES, ids=IDS)
def test_action_space_comes_from_the_actuators(task: str, vessel: str) -> None:
    env = _make(task, vessel)
    v = load_vessel(vessel)
    acts = v.actuators
    if task == "shipgym/SeaTrial-v0":  # scripted: one no-op action; override: every channel
        assert env.action_space == gym.spaces.Discrete(1)
        env.close()
        env = _make(task, vessel, override=True)
        assert env.action_space.shape == (acts.n_channels,)
        env.reset(seed=0)
        _, _, _, _, info = env.step(np.ones(acts.n_channels, dtype=np.float32))
        j = list(acts.channel_names).index(v.rudders[0])
        assert info["rudder_command"] == pytest.approx(acts.upper[j])
        env.close()
        return
    if NEEDS[task] == "roll-steering":  # the rudders steer; a propeller holds the speed
        n = len(v.rudders)
        assert env.action_space.shape == (n,)
        obs, info = env.reset(seed=0)
        assert obs.shape == env.observation_space.shape == (5 + n,)
        _, _, _, _, info = env.step(np.ones(n, dtype=np.float32))
        top = [a.max_angle for a in acts if a.name in v.rudders]
        np.testing.assert_allclose(info["rudder_command"], top)  # +1 is each rudder's limit
        env.close()
        return
    if NEEDS[task] == "steering":  # the rudders steer; the speed is the task's
        n = len(v.rudders)
        assert env.action_space.shape == (n,)
        obs, info = env.reset(seed=0)
        assert obs.shape == env.observation_space.shape == (4 + n,)
        _, _, _, _, info = env.step(np.ones(n, dtype=np.float32))
        top = [getattr(a, "max_angle", None) for a in acts
               if a.name in v.rudders or getattr(a, "rudder_name", None) in v.rudders]  # fmt: skip
        np.testing.assert_allclose(info["rudder_command"], top)  # +1 is each rudder's limit
        env.close()
        return
    assert env.action_space.shape == (acts.n_channels,)
    obs, info = env.reset(seed=0)
    assert obs.shape == env.observation_space.shape == (12 + acts.n_channels,)
    a = np.ones(acts.n_channels, dtype=np.float32)
    _, _, _, _, info = env.step(a)
    np.testing.assert_allclose(info["command"], acts.upper)  # +1 is each range's top
    assert info["thrust"].shape == (len(acts),)
    env.close()


@pytest.mark.parametrize(("task", "vessel"), CASES, ids=IDS)
def test_same_seed_same_episode_and_spec_round_trip(task: str, vessel: str) -> None:
    def run(env) -> list[np.ndarray]:
        out = []
        obs, _ = env.reset(seed=11)
        out.append(obs)
        rng = np.random.default_rng(5)
        discrete = isinstance(env.action_space, gym.spaces.Discrete)
        for _ in range(15):
            act = 0 if discrete else rng.uniform(-1, 1, env.action_space.shape)
            obs, r, term, trunc, info = env.step(act if discrete else act.astype(np.float32))
            out.append(np.r_[obs, r, info["eta"]])
            if term or trunc:
                break
        return out

    env = _make(task, vessel)
    a = run(env)
    b = run(env)
    c = run(gym.make(env.spec))  # rebuilt from the recorded spec
    for x, y, z in zip(a, b, c, strict=True):
        np.testing.assert_array_equal(x, y)
        np.testing.assert_array_equal(x, z)
    assert env.spec.kwargs["vessel"] == vessel
    env.close()


@pytest.mark.parametrize("alias", list(ALIASES))
def test_blue_lady_ids_are_aliases_with_the_same_episodes(alias: str) -> None:
    a = gym.make(alias)
    b = gym.make(ALIASES[alias], vessel="blue-lady")
    oa, _ = a.reset(seed=3)
    ob, _ = b.reset(seed=3)
    np.testing.assert_array_equal(oa, ob)
    rng = np.random.default_rng(0)
    for _ in range(30):
        act = rng.uniform(-1, 1, 3).astype(np.float32)
        ra = a.step(act)
        rb = b.step(act)
        np.testing.assert_array_equal(ra[0], rb[0])
        assert ra[1] == rb[1]


def test_vessel_neutral_ids_need_a_vessel() -> None:
    with pytest.raises(TypeError, match="vessel=NAME"):
        gym.make("shipgym/StationKeeping-v0")


def test_harbour_refuses_a_vessel_that_does_not_fit() -> None:
    with pytest.raises(ValueError, match="does not fit the harbour world"):
        gym.make("shipgym/Harbour-v0", vessel="wimpey-sealab")


VECTOR_CASES = [(t, v) for t, v in CASES if t in VECTOR_IDS]


@pytest.mark.parametrize(("task", "vessel"), VECTOR_CASES,
                         ids=[f"{t.split('/')[1]}-{v}" for t, v in VECTOR_CASES])  # fmt: skip
def test_every_batched_id_and_vessel(task: str, vessel: str) -> None:
    """Every id with a vector entry point x every vessel that fits it: gymnasium's vector
    conventions (batched spaces, info arrays with masks, reward terms summing to the reward,
    seeding), stable-baselines3's ``VecEnv`` use (``shipgym.rl.vec``), and env i of
    ``make_vec(id, N)`` equal to the single env seeded ``seed + i`` over random actions."""
    n = 2
    kw = {"vessel": vessel, "episode_duration": 4.0} if "DP" in task else {"vessel": vessel}
    venv = gym.make_vec(task, num_envs=n, **kw)
    u = venv.unwrapped
    assert isinstance(u, gym.vector.VectorEnv)
    assert venv.single_observation_space == gym.make(task, **kw).observation_space
    obs, info = venv.reset(seed=3)
    assert venv.observation_space.contains(obs)
    assert all(info["_" + k].all() for k in info if not k.startswith("_"))  # every key masked
    singles = [gym.make(task, **kw) for _ in range(n)]
    for i, s in enumerate(singles):
        np.testing.assert_array_equal(obs[i], s.reset(seed=3 + i)[0])
    venv.action_space.seed(1)
    for _ in range(6):
        a = venv.action_space.sample()
        obs, r, term, trunc, info = venv.step(a)
        terms = [info[k] for k in info if k.startswith("reward_") and k != "reward_terms"]
        named = info.get("reward_terms", {})
        terms += [v for k, v in named.items() if not k.startswith("_")]  # not the masks
        if terms:  # the named reward terms sum to the reward
            np.testing.assert_allclose(sum(terms), r)
        for i, s in enumerate(singles):
            o, ri, te, tr, _ = s.step(a[i])
            np.testing.assert_array_equal(obs[i], o)
            assert ri == r[i] and (te, tr) == (term[i], trunc[i])
        if (term | trunc).any():
            break
    from stable_baselines3.common.vec_env import VecEnv

    from shipgym.rl.vec import make_batched_vec_env

    sb3 = make_batched_vec_env(task, n, seed=0, **kw)
    assert isinstance(sb3, VecEnv)
    o = sb3.reset()
    o, r, d, infos = sb3.step(np.zeros((n, *sb3.action_space.shape), np.float32))
    assert o.shape == (n, *sb3.observation_space.shape) and r.shape == d.shape == (n,)
    assert len(infos) == n


def _short_episodes(task: str, vessel: str) -> tuple[dict, dict]:
    """``(vector kwargs, single kwargs)`` of short episodes of ``task``: a few control steps
    (a step limit, or the family's ``episode_duration``); the sea trials' manoeuvres run
    whole."""
    kw: dict = {"vessel": vessel}
    if "DP" in task:
        kw["episode_duration"] = 2.0
        return kw, kw
    if task in ("shipgym/RudderRollStabilisation-v0", "shipgym/NavalRollDamping-v0",
                "shipgym/CourseKeeping-v0"):  # fmt: skip
        kw["episode_duration"] = 6.0
        return kw, kw
    if task == "shipgym/SeaTrial-v0":
        return kw, kw
    return {**kw, "max_episode_steps": 5}, {**kw, "max_episode_steps": 5}


@pytest.mark.parametrize(("task", "vessel"), VECTOR_CASES,
                         ids=[f"{t.split('/')[1]}-{v}" for t, v in VECTOR_CASES])  # fmt: skip
def test_batched_env_equals_the_single_envs_over_whole_episodes(task: str, vessel: str) -> None:
    """Env i of ``make_vec(id, N)`` is the single env seeded ``seed + i``, bit for bit, over
    whole episodes and their autoresets (next-step mode: the step after an episode's end
    resets the env, as the single env's ``reset()``)."""
    n = 2
    vkw, skw = _short_episodes(task, vessel)
    venv = gym.make_vec(task, num_envs=n, **vkw)
    singles = [gym.make(task, **skw) for _ in range(n)]
    obs, _ = venv.reset(seed=11)
    for i, s in enumerate(singles):
        np.testing.assert_array_equal(obs[i], s.reset(seed=11 + i)[0])
    venv.action_space.seed(2)
    pending = np.zeros(n, bool)
    episodes = np.zeros(n, int)
    for _ in range(5000):
        a = venv.action_space.sample()
        obs, r, term, trunc, _ = venv.step(a)
        for i, (o, _, stepped) in enumerate(step_singles(singles, a, pending)):
            if stepped is not None:
                assert stepped == (r[i], term[i], trunc[i])
            np.testing.assert_array_equal(obs[i], o)
        pending = term | trunc
        episodes += pending
        if (episodes >= 2).all():
            break
    assert (episodes >= 2).all(), episodes
