"""The native batched env (``gymnasium.make_vec(id, vectorization_mode="vector_entry_point")``)
against the single env: env i with seed s + i is the single env reset with that seed, and the
same actions give the same episodes to the last bit (poses, estimates, observations, rewards,
terminations and truncations, autoresets included: one code path) for every batched task and
positioning vessel, the harbour included; gymnasium's vector-env conventions; bad input."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from _helpers import step_singles

import shipgym
from shipgym.dynamics.vessel import load_vessel, vessel_names
from shipgym.envs.registration import VECTOR_IDS

POSITIONING = [
    n for n in vessel_names() if load_vessel(n).can_position and load_vessel(n).dofs == 3
]
TASKS = ["shipgym/Tracking-v0", "shipgym/StationKeeping-v0"]


def _pair(env_id, n, steps, **kw):
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point",
                        max_episode_steps=steps, **kw)  # fmt: skip
    # the single envs, driven by the PID DP controller (so that legs complete and episodes
    # terminate); the vector env gets the actions the controller applied
    singles = [shipgym.make(env_id, controller="pid", max_episode_steps=steps, **kw)
               for _ in range(n)]  # fmt: skip
    assert venv.unwrapped.observer is not None
    return venv, singles


@pytest.mark.parametrize(
    ("env_id", "vessel"),
    [(t, v) for t in TASKS for v in POSITIONING] + [("shipgym/Harbour-v0", "blue-lady")],
)
def test_batched_episodes_equal_the_single_envs(env_id, vessel):
    """Whole episodes and autoresets with the KBF observer (what the policy sees: its
    estimate), the single envs driven by the PID controller; the harbour with MuJoCo's
    integrator per hull (its quays)."""
    n, steps, total = 2, 250, 600
    kw = {"max_legs": 1} if env_id == "shipgym/Tracking-v0" else {}
    venv, singles = _pair(env_id, n, steps, vessel=vessel, observer="kbf", **kw)
    obs, info = venv.reset(seed=30)
    for i, s in enumerate(singles):
        o, inf = s.reset(seed=30 + i)
        np.testing.assert_array_equal(obs[i], o)
        np.testing.assert_array_equal(info["eta"][i], inf["eta"])
    pending = np.zeros(n, bool)  # NEXT_STEP: the single env resets when the batched one does
    ends = {"terminated": 0, "truncated": 0}
    for _ in range(total):
        actions = np.zeros((n, venv.single_action_space.shape[0]), np.float32)
        outs = []
        for i, s in enumerate(singles):
            if pending[i]:
                outs.append(("reset", *s.reset()))
            else:
                out = s.step(np.zeros(s.action_space.shape, np.float32))
                actions[i] = s.unwrapped.prev_action
                outs.append(("step", *out))
        obs, rew, term, trunc, info = venv.step(actions)
        for i, out in enumerate(outs):
            if out[0] == "reset":
                _, o, inf = out
                assert rew[i] == 0.0 and not term[i] and not trunc[i]
            else:
                _, o, r, te, tr, inf = out
                assert (bool(term[i]), bool(trunc[i])) == (te, tr)
                assert rew[i] == r
                ends["terminated"] += te
                ends["truncated"] += tr
            np.testing.assert_array_equal(info["eta"][i], inf["eta"])
            np.testing.assert_array_equal(info["nav_eta"][i], inf["nav_eta"])
            np.testing.assert_array_equal(obs[i], o)
            assert info["leg"][i] == inf["leg"]
        pending = term | trunc
    assert ends["terminated"] + ends["truncated"] >= n  # every env autoreset at least once
    # Tracking: legs completed and episodes ended; station keeping, harbour: the time limit
    assert ends["terminated" if env_id == "shipgym/Tracking-v0" else "truncated"] > 0


def test_same_step_autoreset_and_episode_statistics():
    venv = gym.make_vec("shipgym/BlueLadyStationKeeping-v0", num_envs=3, max_episode_steps=4,
                        autoreset_mode="same-step")  # fmt: skip
    assert venv.metadata["autoreset_mode"] == gym.vector.AutoresetMode.SAME_STEP
    obs0, _ = venv.reset(seed=1)
    a = np.zeros((3, 3), np.float32)
    total = np.zeros(3)
    for _ in range(4):
        obs, r, term, trunc, info = venv.step(a)
        total += r
    assert trunc.all() and not term.any()
    np.testing.assert_array_equal(info["_final_obs"], [True] * 3)
    np.testing.assert_allclose(info["episode_summary"]["return"], total)
    np.testing.assert_array_equal(info["episode_summary"]["length"], [4, 4, 4])
    # the returned observation is the next episode's first one (same generator, not seed 1)
    assert not np.allclose(obs, obs0)
    assert np.abs(info["final_obs"] - obs).max() > 0


def test_vector_env_follows_gymnasium_conventions():
    venv = gym.make_vec("shipgym/BlueLadyTracking-v0", num_envs=4)
    assert isinstance(venv.unwrapped, gym.vector.VectorEnv)
    assert venv.observation_space.shape == (4, 15) and venv.action_space.shape == (4, 3)
    obs, info = venv.reset(seed=0)
    assert venv.observation_space.contains(obs)
    assert info["eta"].shape == (4, 3) and info["_eta"].all()
    obs, r, term, trunc, info = venv.step(venv.action_space.sample())
    assert obs.dtype == np.float32 and r.shape == (4,) and term.dtype == bool
    terms = [k for k in info if k.startswith("reward_") and not k.startswith("_")]
    np.testing.assert_allclose(sum(info[k] for k in terms), r)
    # same seed, same episodes; a different seed, different ones
    a = np.full((4, 3), 0.3, np.float32)
    runs = []
    for seed in (5, 5, 6):
        venv.reset(seed=seed)
        runs.append(venv.step(a)[0])
    np.testing.assert_array_equal(runs[0], runs[1])
    assert not np.allclose(runs[0], runs[2])
    # env i with seed s + i: env 1 of seed 5 is env 0 of seed 6
    np.testing.assert_array_equal(runs[0][1], runs[2][0])
    assert set(VECTOR_IDS) <= set(gym.registry)


def test_bad_input_is_refused_clearly():
    venv = gym.make_vec("shipgym/BlueLadyTracking-v0", num_envs=2)
    with pytest.raises(gym.error.ResetNeeded):
        venv.step(np.zeros((2, 3)))
    venv.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        venv.step(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="envs \\[1\\]"):
        venv.step(np.array([[0, 0, 0], [np.nan, 0, 0]]))
    with pytest.raises(ValueError, match="reset options"):
        venv.reset(options={"no_such_option": 1})
    with pytest.raises(ValueError, match="no batched form"):
        from shipgym.envs.vector import ShipVectorEnv

        ShipVectorEnv(2, "shipgym/NoSuchTask-v0")


@pytest.mark.parametrize("env_id", TASKS)
def test_same_as_gymnasiums_sync_vector_env(env_id):
    """Gymnasium's own SyncVectorEnv of the single envs is the reference of the vector
    semantics (seeding, NEXT_STEP autoreset, info masks): the same actions give the same
    observations, rewards and ends, step by step."""
    n, kw = 3, {"vessel": "blue-lady", "max_episode_steps": 7}
    native = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kw)
    sync = gym.make_vec(env_id, num_envs=n, vectorization_mode="sync", **kw)
    assert sync.metadata["autoreset_mode"] == native.metadata["autoreset_mode"]
    for venv in (native, sync):
        venv.action_space.seed(3)
    o1, i1 = native.reset(seed=11)
    o2, i2 = sync.reset(seed=11)
    np.testing.assert_array_equal(o1, o2)
    rng = np.random.default_rng(4)
    ends = np.zeros(n, int)
    for _ in range(20):
        a = rng.uniform(-1.2, 1.2, (n, 3)).astype(np.float32)
        o1, r1, t1, u1, i1 = native.step(a)
        o2, r2, t2, u2, i2 = sync.step(a)
        np.testing.assert_array_equal(o1, o2)
        np.testing.assert_array_equal(r1, r2)
        np.testing.assert_array_equal(t1, t2)
        np.testing.assert_array_equal(u1, u2)
        np.testing.assert_array_equal(i1["eta"], i2["eta"])
        np.testing.assert_array_equal(i1["_eta"], i2["_eta"])
        np.testing.assert_array_equal(i1["action_clipped"], i2["action_clipped"])
        ends += u1.astype(int)
    np.testing.assert_array_equal(ends, [2, 2, 2])  # 20 steps of 7 (+1 reset step): autoresets


def test_gymnasium_vector_wrappers_work_on_it():
    from gymnasium.wrappers.vector import ClipAction, NormalizeObservation, RecordEpisodeStatistics

    venv = gym.make_vec("shipgym/BlueLadyStationKeeping-v0", num_envs=2, max_episode_steps=3)
    venv = RecordEpisodeStatistics(NormalizeObservation(ClipAction(venv)))
    venv.reset(seed=0)
    for _ in range(3):
        _, _, _, trunc, info = venv.step(np.full((2, 3), 2.0, np.float32))
    assert trunc.all() and info["_episode"].all() and (info["episode"]["l"] == 3).all()


@pytest.mark.parametrize("observer", [None, "kbf", "dkf", "tomera-kbf"])
@pytest.mark.parametrize("env_id", TASKS)
def test_batched_controller_residuals_equal_the_controller_wrapper(env_id, observer):
    """``controller="pid"``: the actions are residuals on the batched PID and allocation, as
    ``shipgym.make(..., controller="pid")`` forms them (leg switches turn its frame); with an
    observer, the controller and the observation use its estimate, as under the observer
    wrapper. ``pid`` is conditioned (velocity filter, reversal hysteresis). Tracking runs
    episodes of 300 steps: its legs at the Blue Lady's capacity-limited speeds (issue 31)
    take longer than 150 s."""
    tracking = env_id == "shipgym/Tracking-v0"
    _residual_parity(env_id, observer, "pid", steps=300 if tracking else 150)


@pytest.mark.parametrize("controller", ["pid-smooth", "pid-raw", "pid-smooth-raw"])
def test_batched_conditioned_and_raw_controllers_equal_the_wrapper(controller):
    """The other PID entries: conditioned (``pid-smooth``) and raw, with the KBF."""
    _residual_parity("shipgym/StationKeeping-v0", "kbf", controller)


@pytest.mark.parametrize("vessel", ["star-hercules", "wimpey-sealab"])
def test_batched_iterative_allocations_equal_the_single_env(vessel):
    """The vessels whose allocation is iterative (active-set least squares, azimuth QP): each
    env allocates with its own allocator inside the batched step, as the single env does."""
    _residual_parity("shipgym/StationKeeping-v0", "kbf", "pid", vessel=vessel, steps=60)


def _residual_parity(env_id, observer, controller, vessel="blue-lady", steps=150):
    n, scale = 3, 0.3
    kw = {"vessel": vessel, "max_episode_steps": steps, "observer": observer}
    if observer is not None:  # outliers and dropouts, so the gate and the holds act
        kw["sensors"] = {"outlier_probability": 0.05, "dropout_probability": 0.03}
    if env_id == "shipgym/Tracking-v0":
        kw["max_legs"] = 2
    venv = gym.make_vec(env_id, num_envs=n, controller=controller, residual_scale=scale, **kw)
    singles = [shipgym.make(env_id, controller=controller, residual_scale=scale, **kw)
               for _ in range(n)]  # fmt: skip
    venv.reset(seed=50)
    for i, s in enumerate(singles):
        s.reset(seed=50 + i)
    rng = np.random.default_rng(8)
    pending = np.zeros(n, bool)
    legs = clipped = rejected = 0
    err = 0.0
    for _ in range(320 if steps >= 150 else 130):
        res = rng.normal(0.0, 0.6, (n, venv.single_action_space.shape[0])).astype(np.float32)
        obs, rew, term, trunc, info = venv.step(res)
        for i, (o, inf, stepped) in enumerate(step_singles(singles, res, pending)):
            if stepped is not None:
                r, te, tr = stepped
                assert (te, tr) == (bool(term[i]), bool(trunc[i]))
                assert rew[i] == r
                np.testing.assert_array_equal(info["tau_c"][i], inf["tau_c"])
                np.testing.assert_array_equal(info["residual_clipped"][i], inf["residual_clipped"])
                clipped += int(inf["residual_clipped"].any())
            err = max(err, float(np.abs(info["eta"][i] - inf["eta"]).max()))
            err = max(err, float(np.abs(info["nav_eta"][i] - inf["nav_eta"]).max()))
            np.testing.assert_array_equal(obs[i], o)
            if observer is not None and "observer_rejected" in inf:
                assert info["observer_rejected"][i] == inf["observer_rejected"]
                rejected += int(inf["observer_rejected"])
        legs += int(info["legs_completed"].sum())
        pending = term | trunc
    assert err < 1e-6, err
    assert clipped > 0
    if observer is not None:
        assert rejected > 0
    if env_id == "shipgym/Tracking-v0" and observer in (None, "kbf"):
        assert legs > 0  # leg switches turned the controller's frame


@pytest.mark.parametrize(
    ("kw", "error", "match"),
    [
        ({"observer": "nope"}, ValueError, "unknown observer"),
        ({"controller": "nope"}, ValueError, "unknown controller"),
        ({"sensors": None, "observer": "kbf"}, ValueError, "needs sensors"),
        ({"controller": "pid", "residual_scale": float("nan")}, ValueError, "finite"),
        ({"controller": "pid", "residual_scale": True}, ValueError, "finite"),
        ({"observer_options": {"beaufort": 5}}, ValueError, "needs an observer"),
        ({"autoreset_mode": "sometimes"}, ValueError, "autoreset_mode"),
        ({"render_mode": "rgb_array"}, ValueError, "does not render"),
    ],
)
def test_what_the_batched_env_does_not_cover_says_so(kw, error, match):
    kw = {"vessel": "blue-lady", **kw}
    with pytest.raises(error, match=match):
        gym.make_vec("shipgym/Tracking-v0", num_envs=2, **kw)


def test_batched_env_with_time_correlated_sensor_errors_equals_the_single_envs():
    """The lake sensors (Gauss-Markov DGPS error, gyrocompass bias) plus dropouts in the
    batched env: the navigation estimate of env i is the single env's (to 1e-6)."""
    from shipgym.observers.sensors import sensor_config

    env_id, n, steps = "shipgym/StationKeeping-v0", 2, 120
    sensors = sensor_config("tomera2014-lake", dropout_probability=0.03)
    kw = {"vessel": "blue-lady", "max_episode_steps": steps, "observer": "kbf",
          "sensors": sensors}  # fmt: skip
    venv = gym.make_vec(env_id, num_envs=n, controller="pid", residual_scale=0.3, **kw)
    singles = [shipgym.make(env_id, controller="pid", residual_scale=0.3, **kw)
               for _ in range(n)]  # fmt: skip
    venv.reset(seed=7)
    for i, s in enumerate(singles):
        s.reset(seed=7 + i)
    rng = np.random.default_rng(1)
    err = 0.0
    biased = 0.0
    for _ in range(steps - 1):
        res = rng.normal(0.0, 0.5, (n, 3)).astype(np.float32)
        _, _, _, _, info = venv.step(res)
        for i, s in enumerate(singles):
            _, _, _, _, inf = s.step(res[i])
            err = max(err, float(np.abs(info["nav_eta"][i] - inf["nav_eta"]).max()))
            biased = max(biased, abs(float(s.unwrapped.sensors.correlated_error[0, 2])))
    assert err < 1e-6, err
    assert biased > 0  # the bias was on
    assert venv.unwrapped.sensors.correlated_error.shape == (n, 3)


@pytest.mark.parametrize(
    ("env_id", "vessel"),
    [("shipgym/DPStationKeeping-v0", "wimpey-sealab"), ("shipgym/DPSwayStep-v0", "star-hercules")],
)
def test_batched_dp_tasks_equal_the_single_envs(env_id, vessel):
    """The offshore DP tasks batched (Beaufort 7 sea with first-order motion in the fixes and
    drift on the hulls, the DP timing of the vessel, its iterative allocation under the PID,
    the KBF): env i is the single env seeded seed + i to the last bit, truncated at the same
    episode duration, then autoreset."""
    n = 2
    kw = {"vessel": vessel, "beaufort": 7, "episode_duration": 12.0, "controller": "pid",
          "observer": "kbf"}  # fmt: skip
    if env_id == "shipgym/DPSwayStep-v0":
        kw["step_time"] = 3.0
    venv = gym.make_vec(env_id, num_envs=n, **kw)
    singles = [shipgym.make(env_id, **kw) for _ in range(n)]
    obs, _ = venv.reset(seed=5)
    for i, s in enumerate(singles):
        np.testing.assert_array_equal(obs[i], s.reset(seed=5 + i)[0])
    assert venv.unwrapped.control_period == singles[0].unwrapped.control_period < 0.5
    rng = np.random.default_rng(0)
    pending = np.zeros(n, bool)
    ends = 0
    for _ in range(2 * round(12.0 / venv.unwrapped.control_period) + 3):
        a = rng.normal(0.0, 0.3, (n, venv.single_action_space.shape[0])).astype(np.float32)
        obs, rew, term, trunc, info = venv.step(a)
        for i, s in enumerate(singles):
            if pending[i]:
                o, _ = s.reset()
            else:
                o, r, te, tr, inf = s.step(a[i])
                assert (te, tr) == (bool(term[i]), bool(trunc[i])) and r == rew[i]
                np.testing.assert_array_equal(info["eta"][i], inf["eta"])
                np.testing.assert_array_equal(info["nav_eta"][i], inf["nav_eta"])
            np.testing.assert_array_equal(obs[i], o)
        ends += int(trunc.sum())
        pending = term | trunc
    assert ends >= n  # every env reached the episode's duration and was reset


def test_start_pose_option_one_row_per_env_equals_the_single_envs():
    """``reset(options={"start_pose": ...})``: a row per env (or one pose for all) starts each
    env where its single env with the same option starts, for that reset only."""
    poses = np.array([[1.0, 2.0, 0.1], [-3.0, 0.5, -0.2]])
    venv = gym.make_vec("shipgym/BlueLadyStationKeeping-v0", num_envs=2)
    _, info = venv.reset(seed=3, options={"start_pose": poses})
    for i in range(2):
        env = gym.make("shipgym/BlueLadyStationKeeping-v0")
        _, one = env.reset(seed=3 + i, options={"start_pose": poses[i]})
        np.testing.assert_array_equal(info["eta"][i], one["eta"])
    assert not np.allclose(info["eta"][0], info["eta"][1])
    _, info = venv.reset(seed=3, options={"start_pose": poses[1]})  # one pose for all
    for i in range(2):
        _, one = gym.make("shipgym/BlueLadyStationKeeping-v0").reset(
            seed=3 + i, options={"start_pose": poses[1]}
        )
        np.testing.assert_array_equal(info["eta"][i], one["eta"])
    _, again = venv.reset(seed=3)  # the option was that reset's only
    _, task = gym.make("shipgym/BlueLadyStationKeeping-v0").reset(seed=3)
    np.testing.assert_array_equal(again["eta"][0], task["eta"])
    with pytest.raises(ValueError, match="start_pose"):
        venv.reset(options={"start_pose": [[0.0, 0.0]] * 2})


@pytest.mark.parametrize("observer", ["kbf", "ekf", "notch"])
def test_batched_harbour_with_quay_contacts_equals_the_single_envs(observer):
    """Hulls driven into the quays at different times: a hull stops mid-period at its
    contact, the others sample on; env i's estimate follows env i's samples only (the
    others' samples leave it where it is), and a kinematic or model-based observer coasts
    to the contact, as in the single env; autoresets follow."""
    n = 3
    kw = {"observer": observer, "max_episode_steps": 60, "sensors": {"period": 0.5}}
    venv = gym.make_vec("shipgym/BlueLadyHarbour-v0", num_envs=n, **kw)
    singles = [shipgym.make("harbour", **kw) for _ in range(n)]
    venv.reset(seed=3)
    for i, s in enumerate(singles):
        s.reset(seed=3 + i)
    pending = np.zeros(n, bool)
    contacts = 0
    a = np.array([[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, 1.0]], np.float32)
    for _ in range(100):
        obs, _, term, trunc, info = venv.step(a)
        for i, (o, inf, stepped) in enumerate(step_singles(singles, a, pending)):
            if stepped is not None:
                contacts += int(inf["quay_contact"])
            np.testing.assert_array_equal(obs[i], o)
            np.testing.assert_array_equal(info["nav_eta"][i], inf["nav_eta"])
        pending = term | trunc
    assert contacts >= 3
