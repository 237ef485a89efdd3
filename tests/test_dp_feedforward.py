"""Environmental feedforward of the DP stacks and the consistency of their filters (issue:
"DP and sea trials a marine engineer would sign off", items 1, 2 and 4).

- the current load against the compiled fossen3 acceleration (the run-time law, written out
  component by component), the wind feedforward against the Blendermann load;
- the HF thrust RMS against a sine of known amplitude;
- the env: ``info["tau_ff"]``, the switch, the errors;
- the acceptance: ``shipgym bench dp --beaufort 5,8 --seeds 3`` with kf14 + the printed LQ +
  feedforward: mean NIS within [1.5, 6], Wimpey Sealab position RMS < 1 m and Star Hercules
  inside 7 m >= 95 % of the time in Beaufort 8, the detrended HF thrust RMS of kf14 at most
  0.2x that of the LQ on raw measurements. The default suite runs Beaufort 8, seed 0; ``make
  test-slow`` the whole table.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import shipgym
from shipgym.controllers.feedforward import (
    FEEDFORWARD_PRESETS,
    BatchedFeedforward,
    FeedforwardConfig,
    current_load,
)
from shipgym.disturbances.wind import WindLoad
from shipgym.dp.bench import dp_run
from shipgym.dp.metrics import hf_thrust_rms
from shipgym.dynamics.model import accel_fossen3
from shipgym.dynamics.vessel import load_vessel

VESSELS = ("wimpey-sealab", "star-hercules")


def test_config_names_bools_mappings_and_errors():
    assert FeedforwardConfig.coerce("wind+current") == FeedforwardConfig()
    assert FeedforwardConfig.coerce(False).label == "none"
    assert not FeedforwardConfig.coerce("none").active
    assert FeedforwardConfig.coerce({"current": False}).label == "wind"
    assert set(FEEDFORWARD_PRESETS) == {"wind+current", "wind+current+drift", "wind", "current",
                                        "none"}  # fmt: skip
    assert FeedforwardConfig.coerce("wind+current+drift").label == "wind+current+drift"
    with pytest.raises(ValueError, match="did you mean 'wind'"):
        FeedforwardConfig.coerce("wnd")
    with pytest.raises(ValueError, match="unknown feedforward keys"):
        FeedforwardConfig.coerce({"gusts": True})
    with pytest.raises(ValueError, match="wind_time_constant"):
        FeedforwardConfig(wind_time_constant=0.0)
    with pytest.raises(ValueError, match="must be a bool"):
        FeedforwardConfig(wind=1)  # type: ignore[arg-type]


@pytest.mark.parametrize("vessel", [*VESSELS, "blue-lady"])
def test_current_load_is_the_compiled_hull_law_at_rest(vessel):
    """``M nu_dot(0, 0, nu_c)`` equals ``M`` times the compiled acceleration of a hull at rest
    in the current; a current setting to starboard pushes the ship to starboard."""
    plant = load_vessel(vessel).plant()
    k = np.ascontiguousarray(plant.kernel_constants(), dtype=float)
    M = plant.mass_matrix()
    for u_c, v_c in [(0.0, 0.5), (0.3, -0.4), (-0.5, 0.1)]:
        a = accel_fossen3(k, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, u_c, v_c)
        want = M @ np.array([a[0], a[1], a[3]])
        np.testing.assert_allclose(current_load(plant, [u_c, v_c, 0.0]), want, rtol=1e-9,
                                   atol=1e-9 * np.abs(want).max())  # fmt: skip
    assert current_load(plant, [0.0, 0.5, 0.0])[1] > 0.0


def test_wind_feedforward_is_minus_the_filtered_blendermann_load():
    v = load_vessel("wimpey-sealab")
    dt = 0.5
    ff = BatchedFeedforward(v, FeedforwardConfig(current=False), 2, dt)
    eta = np.array([[0.0, 0.0, 0.3], [5.0, 1.0, -1.0]])
    nu = np.array([[0.1, -0.05, 0.0], [0.0, 0.0, 0.01]])
    wind = np.array([[19.0, math.radians(45.0)], [10.0, math.radians(200.0)]])
    tau = ff(eta, nu, wind)  # the first sample starts the filter
    for i in range(2):
        want = np.array(
            WindLoad(None, v.windage)(eta[i, 2], nu[i, 0], nu[i, 1], wind[i, 0], wind[i, 1])
        )
        np.testing.assert_allclose(tau[i], -want, rtol=1e-12)
    # a step of the wind: the filtered wind vector follows with exp(-dt / T)
    a = math.exp(-dt / FeedforwardConfig().wind_time_constant)
    new = np.array([[25.0, math.radians(45.0)], [10.0, math.radians(200.0)]])
    for k in range(1, 6):
        ff(eta, nu, new)
        V = ff.filtered_wind[0, 0]
        assert V == pytest.approx(25.0 - 6.0 * a**k, rel=1e-12)
    assert ff.filtered_wind[1, 0] == pytest.approx(10.0, rel=1e-12)  # (the angle wrapped)
    assert math.cos(ff.filtered_wind[1, 1] - new[1, 1]) == pytest.approx(1.0, abs=1e-12)
    ff.reset(np.array([True, False]))
    ff(eta, nu, wind)
    assert ff.filtered_wind[0, 0] == pytest.approx(19.0)


def test_drift_feedforward_is_minus_the_sea_states_mean_drift():
    v = load_vessel("star-hercules")
    ff = BatchedFeedforward(v, FeedforwardConfig(wind=False, current=False, drift=True), 1, 0.3)
    drift = np.array([[1e4, -3e4, 2e5]])
    np.testing.assert_array_equal(ff(np.zeros((1, 3)), np.zeros((1, 3)), drift=drift), -drift)
    with pytest.raises(ValueError, match="mean drift load"):
        ff(np.zeros((1, 3)), np.zeros((1, 3)))
    env = _dp(controller="alt-lq-printed", feedforward="wind+current+drift", beaufort=8)
    env.reset(seed=1)
    _, _, _, _, info = env.step(np.zeros(env.action_space.shape, np.float32))
    both = _dp(controller="alt-lq-printed", beaufort=8)
    both.reset(seed=1)
    _, _, _, _, ref = both.step(np.zeros(env.action_space.shape, np.float32))
    psi = 0.0  # the controller's heading before the first step: the start, heading north
    waves = env.unwrapped.physics.waves
    np.testing.assert_allclose(
        info["tau_ff"] - ref["tau_ff"], -np.array(waves.mean_drift_load(psi)), rtol=1e-6
    )


def test_hf_thrust_rms_of_a_sine_on_a_trend():
    t = np.arange(0.0, 600.0, 0.25)
    cap = np.array([1e5, 2e5, 1e7])
    A = 0.1  # fraction of capacity, in sway, at 0.1 Hz (inside 0.05-0.25 Hz)
    tau = np.zeros((t.size, 3))
    tau[:, 0] = 0.5 * cap[0] + 50.0 * t  # a mean load and a slow ramp: no HF content
    tau[:, 1] = A * cap[1] * np.sin(2.0 * math.pi * 0.1 * t)
    assert hf_thrust_rms(t, tau, cap) == pytest.approx(A / math.sqrt(2.0), rel=0.03)
    tau[:, 1] = 0.0
    assert hf_thrust_rms(t, tau, cap) < 1e-3
    with pytest.raises(ValueError, match="shorter than one Welch segment"):
        hf_thrust_rms(t[:100], tau[:100], cap)


def _dp(**kw):
    return shipgym.make(
        "shipgym/DPStationKeeping-v0", vessel="star-hercules", episode_duration=60.0, **kw
    )


def test_the_dp_env_feeds_the_loads_forward_by_default():
    env = _dp(controller="alt-lq-printed", observer="alt-kf14")
    env.reset(seed=0)
    a = np.zeros(env.action_space.shape, np.float32)
    _, _, _, _, info = env.step(a)
    ff = info["tau_ff"]
    assert np.abs(ff).max() > 1e3 and np.all(np.isfinite(ff))
    assert env.unwrapped.batch.feedforward.config.label == "wind+current"
    np.testing.assert_array_equal(info["record"].control.tau_ff, ff)
    env.close()
    off = _dp(controller="alt-lq-printed", feedforward="none")
    off.reset(seed=0)
    _, _, _, _, info = off.step(a)
    np.testing.assert_array_equal(info["tau_ff"], np.zeros(3))
    assert off.unwrapped.batch.feedforward is None
    # without a controller the DP env runs without one; asked for, it is refused
    _dp().reset(seed=0)
    with pytest.raises(ValueError, match="needs a DP controller"):
        _dp(feedforward="wind")
    with pytest.raises(ValueError, match="unknown feedforward"):
        _dp(controller="pid", feedforward="gusts")
    # the other tasks feed nothing forward unless asked
    env = shipgym.make("shipgym/StationKeeping-v0", vessel="blue-lady", controller="pid")
    assert env.unwrapped.batch.feedforward is None


def _acceptance(vessel, bf, seed):
    kf = dp_run((vessel, bf, "kf14", seed, 600.0))
    raw = dp_run((vessel, bf, "raw-lq", seed, 600.0))
    assert kf["feedforward"] == "wind+current"
    return kf, raw


def _check(vessel, bf, rows):
    nis = np.mean([kf["nis_mean"] for kf, _ in rows])
    assert 1.5 <= nis <= 6.0, (vessel, bf, nis)
    hf_ratio = np.mean([kf["hf_thrust_rms"] for kf, _ in rows]) / np.mean(
        [raw["hf_thrust_rms"] for _, raw in rows]
    )
    assert hf_ratio <= 0.2, (vessel, bf, hf_ratio)
    if bf == 8 and vessel == "wimpey-sealab":
        assert np.mean([kf["position_rms_m"] for kf, _ in rows]) < 1.0
    if bf == 8 and vessel == "star-hercules":
        assert np.mean([kf["inside_radius_pct"] for kf, _ in rows]) >= 95.0


@pytest.mark.parametrize("vessel", VESSELS)
def test_kf14_with_feedforward_is_consistent_and_holds_in_beaufort_8(vessel):
    _check(vessel, 8, [_acceptance(vessel, 8, 0)])


@pytest.mark.slow
@pytest.mark.parametrize("vessel", VESSELS)
@pytest.mark.parametrize("bf", [5, 8])
def test_kf14_with_feedforward_three_seeds(vessel, bf):
    _check(vessel, bf, [_acceptance(vessel, bf, s) for s in range(3)])
