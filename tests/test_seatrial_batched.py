"""The sea-trial family written once, batched (shipgym.envs.seatrial): env i of
``make_vec("shipgym/SeaTrial-v0", N)`` is the single env seeded ``seed + i``, bit for bit,
over whole episodes with autoresets in both autoreset modes, on every fitting vessel; the
scripts of several manoeuvres as one batch; Gymnasium's and SB3's checks."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import shipgym
from shipgym.dynamics.vessel import load_vessel
from shipgym.envs.registration import task_fits_vessel
from shipgym.envs.seatrial import SeaTrialVectorEnv, run_trial, run_trials

ID = "shipgym/SeaTrial-v0"
VESSELS = [v for v in shipgym.vessels() if task_fits_vessel(ID, load_vessel(v))]
#: short episodes: the initial turning test (6 L/U0) with the receiver
KW = {"manoeuvre": "initial_turning", "receiver": "dgps-pv"}


def _same(single, batched):
    """A single env's value equals the batched row, bit for bit (NaN equal to NaN; the
    single env's ``None`` shaft of a vessel without one is a key the batch does not have)."""
    if isinstance(single, dict):
        absent = {k for k, v in single.items() if v is None}
        assert set(single) - absent == {k for k in batched if not k.startswith("_")}
        assert not absent & set(batched)
        for k, v in single.items():
            if v is not None:
                _same(v, batched[k])
        return
    b = np.asarray(batched)
    if b.dtype.kind in "US":
        assert single == batched
        return
    assert np.array_equal(np.asarray(single, dtype=b.dtype), b, equal_nan=True), (single, b)


def _row(info, i, skip=("_",)):
    """Row ``i`` of a batched info (nested dicts too), its masks and ``skip`` keys left out."""
    return {k: _row(v, i) if isinstance(v, dict) else v[i] for k, v in info.items()
            if not k.startswith(skip)}  # fmt: skip


def _same_metrics(single, batched, i):
    """The single env's episode metrics equal row ``i`` of the batch's arrays."""
    for k, v in single.items():
        row = batched[k][i]
        if k == "overshoots":
            assert np.array_equal(np.r_[v, [np.nan] * (3 - len(v))], row, equal_nan=True)
        elif k == "imo_pass":
            assert np.array_equal(np.nan if v is None else float(v), row, equal_nan=True)
        else:
            _same(v, row)


def _compare(vessel, mode, n=3, seed=7, episodes=2, **kw):
    """Run the batch and N single envs side by side over ``episodes`` episodes each."""
    venv = gym.make_vec(ID, num_envs=n, vessel=vessel, autoreset_mode=mode, **kw)
    singles = [gym.make(ID, vessel=vessel, **kw) for _ in range(n)]
    obs, info = venv.reset(seed=seed)
    for i, s in enumerate(singles):
        o, inf = s.reset(seed=seed + i)
        assert np.array_equal(o, obs[i])
        _same(inf, _row(info, i))
    override = kw.get("override", False)
    rng = np.random.default_rng(0)
    ended = np.zeros(n, dtype=int)
    resetting = np.zeros(n, dtype=bool)
    steps = 0
    while ended.min() < episodes:
        if override:
            a = rng.uniform(-1.2, 1.2, venv.action_space.shape).astype(np.float32)  # some clipped
        else:
            a = np.zeros(n, dtype=np.int64)
        obs, rew, term, trunc, info = venv.step(a)
        steps += 1
        for i, s in enumerate(singles):
            row = _row(info, i, ("_", "final", "episode"))
            if resetting[i]:  # next-step: this env resets now, its action ignored
                o, inf = s.reset()
                assert not term[i] and not trunc[i] and rew[i] == 0.0
                resetting[i] = False
            else:
                o, r, te, tr, inf = s.step(a[i] if override else int(a[i]))
                assert r == rew[i] and te == term[i] and tr == trunc[i]
                if te or tr:
                    ended[i] += 1
                    inf.pop("trial"), inf.pop("imo")
                    _same_metrics(inf.pop("episode_metrics"), info["episode_metrics"], i)
                    assert info["_episode_metrics"][i]
                    if mode == "same-step":
                        assert np.array_equal(info["final_obs"][i], o)
                        _same(inf, _row(info["final_info"], i, ("_", "episode")))
                        o, inf = s.reset()
                    else:
                        resetting[i] = True
            assert np.array_equal(o, obs[i]), (i, steps)
            if not (mode == "same-step" and (term[i] or trunc[i])):
                _same(inf, row)
    return steps


@pytest.mark.parametrize("mode", ["next-step", "same-step"])
@pytest.mark.parametrize("vessel", VESSELS)
def test_env_i_is_the_single_env_seeded_seed_plus_i(vessel, mode):
    """Whole episodes with autoresets, the DGPS receiver's noise drawn per env."""
    steps = _compare(vessel, mode, **KW)
    v = load_vessel(vessel)
    assert steps >= 2 * round(6 * v.L_pp / v.approach_speed)  # two whole episodes


@pytest.mark.parametrize("mode", ["next-step", "same-step"])
def test_override_actions_equal_the_single_envs(mode):
    """The Box action path (random actions, some clipped), the zig-zag's episode length."""
    _compare("naval-vessel", mode, episodes=1, override=True, manoeuvre="zigzag10")


def test_several_manoeuvres_fly_as_one_batch():
    """One batch of different manoeuvres (the scripts as one law over N envs) flies each
    exactly as a batch of one: run_trials equals run_trial per manoeuvre, bit for bit."""
    names = ["zigzag10", "crash_stop", "initial_turning", "turning35_port"]
    recs = run_trials("kvlcc2-100m", names, record_period=1.0)
    for nm, rec in zip(names, recs, strict=True):
        one = run_trial("kvlcc2-100m", nm, record_period=1.0)
        assert rec.manoeuvre == nm
        for f in ("t", "eta", "nu", "rudder", "shaft"):
            assert np.array_equal(getattr(rec, f), getattr(one, f))
    zz = recs[0].metrics()
    assert len(zz.overshoots) == 3  # the zig-zag reversed its rudder in the batch


@pytest.mark.parametrize("vessel", VESSELS)
def test_single_env_passes_gymnasiums_check(vessel):
    env = gym.make(ID, vessel=vessel, **KW)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_single_env_renders_the_hull():
    env = gym.make(ID, render_mode="rgb_array")
    env.reset(seed=0)
    env.step(0)
    try:
        frame = env.render()
    except RuntimeError as e:  # no OpenGL backend on this machine (tests/test_render.py)
        pytest.skip(str(e)[:80])
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.std() > 0
    env.close()


def test_sb3_vec_env_use():
    pytest.importorskip("stable_baselines3", reason="the rl extra is not installed")
    from stable_baselines3.common.vec_env import VecEnv

    from shipgym.rl.vec import make_batched_vec_env

    n = 2
    venv = make_batched_vec_env(ID, n, seed=0, vessel="kvlcc2-l7", manoeuvre="initial_turning")
    assert isinstance(venv, VecEnv)
    obs = venv.reset()
    assert obs.shape == (n, 9)
    steps = int(venv.venv.max_steps[0])
    for _ in range(steps):
        obs, r, done, infos = venv.step(np.zeros(n, dtype=np.int64))
    assert done.all() and r.shape == (n,) and len(infos) == n
    assert infos[0]["terminal_observation"].shape == (9,)
    assert not infos[0]["TimeLimit.truncated"]


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="2 names"):
        SeaTrialVectorEnv(2, "kvlcc2-100m", ["zigzag10"])
    with pytest.raises(ValueError, match="needs a main propeller"):
        SeaTrialVectorEnv(2, "van-der-klugt", ["zigzag10", "crash_stop"])
    with pytest.raises(ValueError, match="does not render"):
        gym.make_vec(ID, num_envs=2, render_mode="rgb_array")
    venv = gym.make_vec(ID, num_envs=2)
    venv.reset(seed=0)
    with pytest.raises(ValueError, match="actions? must be (the int )?0"):
        venv.step(np.array([0, 1]))


def test_a_masked_reset_restarts_only_its_envs():
    """``reset_mask``: env 1 restarts as the single env's unseeded reset (its generator goes
    on), envs 0 and 2 go on with their episodes."""
    kw = {"vessel": "naval-vessel", **KW}
    venv = gym.make_vec(ID, num_envs=3, **kw)
    singles = [gym.make(ID, **kw) for _ in range(3)]
    venv.reset(seed=1)
    for i, s in enumerate(singles):
        s.reset(seed=1 + i)
    a = np.zeros(3, dtype=np.int64)
    for _ in range(5):
        venv.step(a)
        for s in singles:
            s.step(0)
    obs, info = venv.reset(options={"reset_mask": np.array([False, True, False])})
    assert info["_t"].tolist() == [False, True, False]
    o1, _ = singles[1].reset()
    assert np.array_equal(obs[1], o1)
    for _ in range(5):
        obs, *_ = venv.step(a)
        for i, s in enumerate(singles):
            assert np.array_equal(obs[i], s.step(0)[0])
    assert singles[0].unwrapped.episode_metrics()["manoeuvre"] == "initial_turning"
