"""The offshore DP tasks of Al-Takie (1982) and the commanded-thrust input of the observers.

Independent references: the thesis's printed numbers (per-unit time, the 0.02 p.u. step,
Beaufort 8 = 19 m/s, the HF filter's peak frequencies from its alpha table), the WMO band
middles, the exact first-order-lag response ``1 - exp(-t / T)`` and the array path of
``ActuatorSet.tau`` (not the plain-float kernel the physics uses).
"""

from __future__ import annotations

import math
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from scipy.signal import welch

import shipgym  # noqa: F401  (registers the ids)
from shipgym.dynamics.vessel import load_vessel
from shipgym.observers.batch import BATCHED_OBSERVERS, BatchedStepInfo
from shipgym.records import Measurement

IDS = ("shipgym/DPStationKeeping-v0", "shipgym/DPSwayStep-v0")
THESIS_VESSELS = ("wimpey-sealab", "star-hercules")
CASES = [(i, v) for i in IDS for v in THESIS_VESSELS]
CASE_IDS = [f"{i.split('/')[1]}-{v}" for i, v in CASES]

#: Al-Takie (1982) App. 1 [printed]: L_pp (m) and the per-unit time sqrt(L/g) (s)
LPP = {"wimpey-sealab": 94.49, "star-hercules": 73.0}
TB_PRINTED = {"wimpey-sealab": 3.104, "star-hercules": 2.728}
#: peaks of the HF filter of the alpha table, full scale (Hz; Al-Takie 1982 App. 2, the
#: lightly damped pole pair; seed note A11): Beaufort 5-9
HF_PEAK_HZ = {5: 0.128, 6: 0.100, 7: 0.088, 8: 0.083, 9: 0.069}


def _zeros(env: gym.Env) -> np.ndarray:
    return np.zeros(env.action_space.shape, np.float32)


# ---- Gymnasium / SB3 -----------------------------------------------------------------------
@pytest.mark.parametrize(("env_id", "vessel"), CASES, ids=CASE_IDS)
def test_gymnasium_check_env(env_id: str, vessel: str) -> None:
    env = gym.make(env_id, vessel=vessel)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # infinite observation bounds are intended
        check_env(env.unwrapped, skip_render_check=True)
    env.close()


@pytest.mark.parametrize(("env_id", "vessel"), CASES, ids=CASE_IDS)
def test_sb3_check_env(env_id: str, vessel: str) -> None:
    checker = pytest.importorskip(
        "stable_baselines3.common.env_checker",
        reason="stable-baselines3 is not installed (the rl extra): SB3 check_env skipped",
    )
    env = gym.make(env_id, vessel=vessel)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        checker.check_env(env, warn=False)
    env.close()


@pytest.mark.parametrize(("env_id", "vessel"), CASES, ids=CASE_IDS)
def test_same_seed_same_episode(env_id: str, vessel: str) -> None:
    def run(seed: int) -> np.ndarray:
        env = gym.make(env_id, vessel=vessel)
        obs, info = env.reset(seed=seed)
        rng = np.random.default_rng(4)
        rows = [np.r_[obs, info["measurements"][0]["z"]]]
        for _ in range(20):
            a = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
            obs, r, _, _, info = env.step(a)
            rows.append(np.r_[obs, r, info["eta"], info["measurements"][-1]["z"]])
        return np.concatenate(rows)

    a, b, c = run(7), run(7), run(8)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)  # the seed matters (noise, gusts, waves)


# ---- disturbances --------------------------------------------------------------------------
@pytest.mark.parametrize("vessel", [*THESIS_VESSELS, "blue-lady"])
def test_beaufort_8_mean_wind_is_the_thesis_19_m_s(vessel: str) -> None:
    scale = load_vessel(vessel).scale
    env = gym.make("shipgym/DPStationKeeping-v0", vessel=vessel, beaufort=8)
    env.reset(seed=0)
    assert env.unwrapped.wind_config.speed == pytest.approx(19.0 / math.sqrt(scale), rel=1e-12)
    # the other rows keep the WMO band middle: Beaufort 5 is 8.0-10.7 m/s
    env5 = gym.make("shipgym/DPStationKeeping-v0", vessel=vessel, beaufort=5)
    assert env5.unwrapped.wind_config.speed == pytest.approx(9.35 / math.sqrt(scale))


def test_wind_and_waves_come_from_the_given_direction_and_current_is_offshore() -> None:
    env = gym.make(
        "shipgym/DPStationKeeping-v0", vessel="wimpey-sealab", direction_from_deg=30.0
    ).unwrapped
    assert env.wind_config.direction_from == pytest.approx(math.radians(30.0))
    assert env.wave_config.direction_from == pytest.approx(math.radians(30.0))
    assert env.wave_config.first_order and env.wave_config.drift
    assert env.current_config.speed == 0.5 and env.current_config.sigma > 0
    assert env.current_config.direction_to == pytest.approx(math.radians(90.0))
    # current= of ShipEnv overrides the default
    env = gym.make("shipgym/DPStationKeeping-v0", vessel="wimpey-sealab", current=None)
    assert env.unwrapped.current_config.speed == 0.0


def _hf_peak_hz(env_id: str, vessel: str, bf: int, duration: float) -> tuple[float, float]:
    """Peak (Hz) of the Welch spectrum of the HF motion along the waves and its resolution."""
    env = gym.make(env_id, vessel=vessel, beaufort=bf).unwrapped
    env.reset(seed=1)
    waves = env.physics.waves
    dt = env.control_period
    t = np.arange(1, int(duration / dt)) * dt
    motion = np.array([waves.wf_motion(x) for x in t])
    beta = env.wave_config.direction_from + math.pi
    d = motion[:, 0] * math.cos(beta) + motion[:, 1] * math.sin(beta)
    nper = 4096
    f, p = welch(d, fs=1.0 / dt, nperseg=nper)
    fh, ph = welch(motion[:, 2], fs=1.0 / dt, nperseg=nper)
    assert abs(fh[np.argmax(ph)] - f[np.argmax(p)]) <= f[1]  # heading peaks there too
    return float(f[np.argmax(p)]), float(f[1])


@pytest.mark.parametrize("bf", [5, 6, 7, 8, 9])
@pytest.mark.parametrize("vessel", THESIS_VESSELS)
def test_hf_motion_peaks_at_the_al_takie_filter_frequency(vessel: str, bf: int) -> None:
    peak, df = _hf_peak_hz("shipgym/DPStationKeeping-v0", vessel, bf, 16000.0)
    assert abs(peak - HF_PEAK_HZ[bf]) <= df + 5e-4  # FFT resolution + printed rounding


def test_hf_peak_is_froude_scaled_for_the_blue_lady() -> None:
    peak, df = _hf_peak_hz("shipgym/DPStationKeeping-v0", "blue-lady", 5, 3000.0)
    assert abs(peak - HF_PEAK_HZ[5] * math.sqrt(24.0)) <= df + 5e-4 * math.sqrt(24.0)


def test_measured_pose_is_truth_plus_hf_motion() -> None:
    """With noise-free sensors the measurement minus the truth is exactly the HF motion."""
    cp = 0.1 * math.sqrt(LPP["wimpey-sealab"] / 9.81)
    env = gym.make(
        "shipgym/DPStationKeeping-v0",
        vessel="wimpey-sealab",
        sensors={"period": cp, "position_variance": 0.0, "heading_variance": 0.0},
    )
    env.reset(seed=2)
    waves = env.unwrapped.physics.waves
    seen = []
    for _ in range(30):
        *_, info = env.step(_zeros(env))
        (m,) = info["measurements"]
        assert m["t"] == info["t"]
        np.testing.assert_allclose(m["z"] - info["eta"], waves.wf_motion(m["t"]), atol=1e-9)
        seen.append(np.hypot(*(m["z"] - info["eta"])[:2]))
    assert max(seen) > 1e-3  # there is HF motion to see (std Hs/16 = 0.125 m at Beaufort 5)


@pytest.mark.parametrize("motion", ["rao", "fossen"])
def test_other_wave_motion_models(motion: str) -> None:
    env = gym.make("shipgym/DPStationKeeping-v0", vessel="star-hercules", wave_motion=motion)
    assert env.unwrapped.wave_config.wf_model == motion
    env.reset(seed=0)
    env.step(_zeros(env))


# ---- timing, sensors, start, episode -------------------------------------------------------
@pytest.mark.parametrize("vessel", THESIS_VESSELS)
def test_control_period_is_a_tenth_of_the_per_unit_time(vessel: str) -> None:
    env = gym.make("shipgym/DPStationKeeping-v0", vessel=vessel).unwrapped
    cp = env.control_period
    assert cp == pytest.approx(0.1 * math.sqrt(LPP[vessel] / 9.81), rel=1e-12)
    assert cp == pytest.approx(0.1 * TB_PRINTED[vessel], abs=1e-4)  # App. 3: 0.3104 / 0.2728 s
    k, h = env.n_substeps, env.physics.timestep
    assert k * h == pytest.approx(cp, rel=1e-12)
    assert h <= 0.05 < cp / (k - 1)  # the fewest whole steps of <= 0.05 s
    assert env.sensor_config.period == cp
    assert env.sensor_config.position_sigma == pytest.approx(1.0 / 3.0)
    assert env.sensor_config.heading_sigma == pytest.approx(0.02)
    assert env.sensor_config.outlier_probability == env.sensor_config.dropout_probability == 0
    _, info = env.reset(seed=0)
    np.testing.assert_array_equal(info["eta"], [0.0, 0.0, 0.0])  # no start offset


def test_blue_lady_is_froude_scaled() -> None:
    env = gym.make("shipgym/DPStationKeeping-v0", vessel="blue-lady").unwrapped
    assert env.control_period == pytest.approx(0.1 * math.sqrt(13.5 / 9.81))
    assert env.sensor_config.position_sigma == pytest.approx(1.0 / 3.0 / 24.0)
    assert env.current_config.speed == pytest.approx(0.5 / math.sqrt(24.0))


def test_episode_is_truncated_after_its_duration_with_metrics() -> None:
    default = gym.make("shipgym/DPStationKeeping-v0", vessel="star-hercules").unwrapped
    assert default.episode_duration == 2000.0
    env = gym.make("shipgym/DPStationKeeping-v0", vessel="star-hercules", episode_duration=3.0)
    env.reset(seed=0)
    n, trunc = 0, False
    while not trunc:
        _, _, term, trunc, info = env.step(_zeros(env))
        n += 1
        assert not term
    cp = env.unwrapped.control_period
    assert n == math.ceil(3.0 / cp - 1e-9)
    assert math.isfinite(info["episode_metrics"]["J_c"])
    assert info["episode_metrics"]["duration_s"] == pytest.approx(n * cp)
    with pytest.raises(gym.error.ResetNeeded):
        env.step(_zeros(env))


# ---- the sway step -------------------------------------------------------------------------
@pytest.mark.parametrize(("vessel", "printed"), [("wimpey-sealab", 1.89), ("star-hercules", 1.46)])
def test_sway_step_reference_steps_exactly_at_step_time(vessel: str, printed: float) -> None:
    env = gym.make("shipgym/DPSwayStep-v0", vessel=vessel).unwrapped
    assert env.episode_duration == 400.0 and env.step_time == 100.0
    env.reset(seed=0)
    g = env.guidance
    before, at = g.reference(100.0 - 1e-9), g.reference(100.0)
    np.testing.assert_array_equal(before.eta_d_n, [0.0, 0.0, 0.0])
    step = 0.02 * LPP[vessel]
    assert step == pytest.approx(printed, abs=0.005)  # 0.02 p.u. [printed]
    np.testing.assert_allclose(at.eta_d_n, [0.0, step, 0.0], rtol=0, atol=1e-12)
    for ref in (before, at, g.reference(250.0)):  # a step: no reference velocity
        np.testing.assert_array_equal(ref.nu_d, 0.0)
        np.testing.assert_array_equal(ref.nu_dot_d, 0.0)


def test_sway_step_in_an_episode_and_its_metrics() -> None:
    env = gym.make(
        "shipgym/DPSwayStep-v0", vessel="wimpey-sealab", step_time=1.0, episode_duration=2.0
    )
    env.reset(seed=0)
    ys, ts, trunc = [], [], False
    while not trunc:
        _, _, _, trunc, info = env.step(_zeros(env))
        ys.append(info["eta_d"][1])
        ts.append(info["t"])
    ts, ys = np.array(ts), np.array(ys)
    assert np.all(ys[ts < 1.0] == 0.0)
    assert np.all(ys[ts >= 1.0] == pytest.approx(0.02 * 94.49))
    m = info["episode_metrics"]
    assert math.isfinite(m["J_c"]) and m["duration_s"] >= 2.0


# ---- bad arguments -------------------------------------------------------------------------
@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"beaufort": 4}, "beaufort must be an int from 5 to 9"),
        ({"beaufort": 10}, "beaufort must be an int from 5 to 9"),
        ({"beaufort": "x"}, "beaufort must be an int from 5 to 9"),
        ({"beaufort": True}, "beaufort must be an int from 5 to 9"),
        ({"beaufort": 5.0}, "beaufort must be an int from 5 to 9"),
        ({"wave_motion": "foo"}, "wave_motion must be one of"),
        ({"direction_from_deg": math.nan}, "direction_from_deg must be a finite number"),
        ({"episode_duration": 0.0}, "episode_duration must be > 0"),
        ({"timestep": 0.05}, "whole multiple"),
    ],
)
def test_bad_arguments_raise(env_id: str, kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        gym.make(env_id, vessel="wimpey-sealab", **kwargs)


def test_sway_step_bad_arguments_and_no_vessel() -> None:
    with pytest.raises(ValueError, match="step_time must be >= 0"):
        gym.make("shipgym/DPSwayStep-v0", vessel="star-hercules", step_time=-1.0)
    with pytest.raises(ValueError, match="step must be a finite number"):
        gym.make("shipgym/DPSwayStep-v0", vessel="star-hercules", step=math.inf)
    for env_id in IDS:
        with pytest.raises(TypeError, match="vessel=NAME"):
            gym.make(env_id)


# ---- tau_command ---------------------------------------------------------------------------
def test_tau_command_is_constant_and_tau_follows_the_2_s_lag() -> None:
    """Wimpey Sealab: a constant action, azimuths not turning (athwartships at rest)."""
    env = gym.make("shipgym/DPStationKeeping-v0", vessel="wimpey-sealab", wind=None, waves=None)
    _, info = env.reset(seed=0)
    np.testing.assert_array_equal(info["measurements"][0]["tau_command"], 0.0)
    a = np.zeros(8, np.float32)
    a[[0, 2, 4, 6]] = (0.5, 0.5, 0.3, 0.3)  # thrust; the angle rates stay 0
    first = None
    tau_lag = 2.0  # s, Al-Takie (1982) [printed]; the vessel file's time_constant
    for _ in range(40):
        *_, info = env.step(a)
        for m in info["measurements"]:
            if first is None:
                first = m["tau_command"]
                # steady state: 0.8 x 122.6 kN to starboard, moment 31.5 m x (0.5 - 0.3) x 2 units
                np.testing.assert_allclose(
                    first, [0.0, 1.6 * 1.226e5, 31.5 * 0.4 * 1.226e5], atol=1e-6
                )
            np.testing.assert_array_equal(m["tau_command"], first)
            np.testing.assert_allclose(
                m["tau"], first * (1.0 - math.exp(-m["t"] / tau_lag)), rtol=1e-9, atol=1e-6
            )
    assert info["t"] > 10.0  # tau has come close: within e^-5
    np.testing.assert_allclose(info["measurements"][-1]["tau"], first, rtol=1e-2)


def test_tau_command_equals_the_actuator_sets_tau_of_the_commands() -> None:
    """Star Hercules (fixed thrusters) and Wimpey Sealab (turning azimuths)."""
    for vessel in THESIS_VESSELS:
        acts = load_vessel(vessel).actuators
        lag = np.array([c.dynamics == "lag" for c in acts.channels])
        env = gym.make("shipgym/DPStationKeeping-v0", vessel=vessel)
        env.reset(seed=0)
        rng = np.random.default_rng(3)
        for _ in range(25):
            a = rng.uniform(-1, 1, acts.n_channels).astype(np.float32)
            *_, info = env.step(a)
            state = np.where(lag, info["command"], info["actuator_state"])
            (m,) = info["measurements"]
            np.testing.assert_allclose(m["tau_command"], acts.tau(state), rtol=1e-12, atol=1e-6)
            if acts.fixed:  # no angles: the commands alone
                np.testing.assert_allclose(
                    m["tau_command"], acts.tau(info["command"]), rtol=1e-12, atol=1e-6
                )
            rec = info["record"].measurements[-1]
            assert rec.tau_command is m["tau_command"]


def test_measurement_from_mapping_tolerates_no_tau_command() -> None:
    d = {"t": 1.0, "z": np.zeros(3), "valid": True, "outlier": False, "tau": np.ones(3)}
    assert Measurement.from_mapping(d).tau_command is None
    m = Measurement.from_mapping({**d, "tau_command": np.full(3, 2.0)})
    np.testing.assert_array_equal(m.tau_command, 2.0)


class _Recorder:
    """A stub observer of N envs that records the thrust it is given."""

    model_based = True

    def __init__(self, n: int, thrust_input: str) -> None:
        self.n = n
        self.thrust_input = thrust_input
        self.taus: list[np.ndarray | None] = []
        self.eta = np.zeros((n, 3))
        self.nu = np.zeros((n, 3))

    def reset(self, t0, eta0, mask=None) -> None:
        self.eta = np.array(eta0, float)

    def step(self, t, z, valid, tau=None) -> BatchedStepInfo:
        self.taus.append(None if tau is None else np.array(tau))
        n = self.n
        return BatchedStepInfo(np.full((n, 3), np.nan), np.full(n, np.nan), np.zeros(n, bool),
                               np.zeros(n, bool))  # fmt: skip

    def estimate(self, j):
        from shipgym.observers.base import Estimate

        return Estimate(0.0, self.eta[j], np.zeros(3), np.eye(6), np.eye(3), None)


@pytest.mark.parametrize("mode", ["applied", "command"])
def test_the_env_passes_the_thrust_the_observer_asks_for(monkeypatch, mode) -> None:
    made: list[_Recorder] = []

    def factory(n, vessel):
        made.append(_Recorder(n, mode))
        return made[-1]

    monkeypatch.setitem(BATCHED_OBSERVERS, "recorder-test", factory)
    env = gym.make("shipgym/DPStationKeeping-v0", vessel="star-hercules", observer="recorder-test")
    env.reset(seed=0)
    want = []
    for _ in range(5):
        *_, info = env.step(np.full(4, 0.5, np.float32))
        key = "tau" if mode == "applied" else "tau_command"
        want += [m[key] for m in info["measurements"]]
    got = made[0].taus
    assert len(got) == len(want) == 5
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(g[0], w)
    # the two differ while the thrusters lag (so the test can tell them apart)
    assert not np.allclose(info["measurements"][0]["tau"], info["measurements"][0]["tau_command"])


def test_the_env_refuses_an_unknown_thrust_input(monkeypatch) -> None:
    monkeypatch.setitem(BATCHED_OBSERVERS, "recorder-bad", lambda n, v: _Recorder(n, "lagged"))
    with pytest.raises(ValueError, match="thrust_input must be 'applied' or 'command'"):
        gym.make("shipgym/DPStationKeeping-v0", vessel="star-hercules", observer="recorder-bad")
