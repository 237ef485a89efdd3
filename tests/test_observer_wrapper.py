"""Observer wrapper in the closed loop: estimates feed the controller, errors in info."""

import gymnasium as gym
import numpy as np
import pytest

import shipgym
from shipgym.cli import run_episode
from shipgym.disturbances import WindConfig


@pytest.mark.parametrize("observer", ["dkf", "kbf", "ekf"])
@pytest.mark.parametrize("seed", range(10))
def test_manoeuvre_completes_with_each_observer(observer, seed):
    """Acceptance: wind 3 m/s from 300 deg, seeds 0-9, no quay contact."""
    res = run_episode("harbour", controller="pid", observer=observer, seed=seed)
    assert res["completed"] and not res["quay_contact"]
    assert res["rmse"]["u"] < 0.05 and res["rmse"]["x"] < 0.2


def test_controller_uses_the_estimate_not_the_truth():
    env = shipgym.make("harbour", observer="kbf", controller="pid")
    _, info = env.reset(seed=0)
    for _ in range(5):
        _, _, _, _, info = env.step(np.zeros(3, np.float32))
    assert not np.allclose(info["nav_eta"], info["eta"])
    np.testing.assert_allclose(info["est_error_eta"][:2], info["nav_eta"][:2] - info["eta"][:2])


def test_spec_round_trip_with_observer_and_controller():
    env = shipgym.make("harbour", observer="ekf", controller="pid")
    env2 = gym.make(env.spec)
    assert env2.unwrapped.observer_name == "ekf" and env2.unwrapped.controller_name == "pid"
    o1, _ = env.reset(seed=2)
    o2, _ = env2.reset(seed=2)
    for _ in range(10):
        o1, *_ = env.step(np.zeros(3, np.float32))
        o2, *_ = env2.step(np.zeros(3, np.float32))
    np.testing.assert_array_equal(o1, o2)


def test_ekf_bias_converges_to_the_wind_load_when_holding_position():
    steady = WindConfig(speed=3.0, direction_from=np.radians(300.0), gust_std=0.0,
                        direction_std=0.0)  # fmt: skip
    env = shipgym.make("station-keeping", observer="ekf", controller="pid-raw", wind=steady,
                       start_noise=(0.0, 0.0, 0.0))  # fmt: skip
    env.reset(seed=0)
    observer = env.unwrapped.observer
    # the estimate wanders with the measurement noise (yaw: 4 N m RMS about the mean over
    # 300 s), so the mean over the second half is compared, not one sample
    bias, load = [], []
    for k in range(600):
        _, _, _, trunc, info = env.step(np.zeros(3, np.float32))
        if k >= 300:
            bias.append(observer.estimate(0).bias)
            load.append(info["tau_wind"])
    bias, load = np.mean(bias, axis=0), np.mean(load, axis=0)
    assert np.hypot(*info["est_error_eta"][:2]) < 0.3
    np.testing.assert_allclose(bias, load, rtol=0.2, atol=0.05 * np.abs(load).max())


def test_observer_needs_sensors_and_known_names():
    with pytest.raises(ValueError, match="needs sensors"):
        shipgym.make("harbour", observer="kbf", sensors=None)
    with pytest.raises(ValueError, match="unknown observer 'kalman'"):
        shipgym.make("harbour", observer="kalman")


def test_bench_observers_cli_writes_table_json_and_figures(tmp_path, capsys):
    import json

    from matplotlib.image import imread

    from shipgym.cli import main
    from shipgym.viz import COMPARE_SIZES, DPI

    out = tmp_path / "rep"
    args = ["bench", "observers", "--observers", "dkf", "ekf", "--seeds", "2", "--no-progress"]
    assert main([*args, "--json", str(tmp_path / "b.json"), "--report", str(out)]) == 0
    table = capsys.readouterr().out
    assert "| dkf | 2 | 2/2 |" in table and "| ekf | 2 | 2/2 |" in table
    rows = json.loads((tmp_path / "b.json").read_text())["rows"]
    assert [(r["observer"], r["seed"]) for r in rows] == [
        ("dkf", 0), ("dkf", 1), ("ekf", 0), ("ekf", 1)
    ]  # fmt: skip
    for name, (w, h) in COMPARE_SIZES.items():
        img = imread(out / f"{name}.png")
        assert img.shape[:2] == (round(h * DPI), round(w * DPI))
    assert main(["bench", "observers", "--observers", "nope"]) == 2


def test_dropout_at_reset_starts_the_observer_from_the_planned_pose():
    from shipgym.observers.sensors import sensor_config

    cfg = sensor_config("default", dropout_probability=1.0, dropout_duration=5.0)
    env = shipgym.make("harbour", observer="kbf", controller="pid", sensors=cfg)
    _, info = env.reset(seed=0)
    assert info["measurements"][0]["z"] is None
    np.testing.assert_allclose(info["nav_eta"], info["eta_P"])
    for _ in range(3):
        _, _, _, _, info = env.step(np.zeros(3, np.float32))
    assert np.all(np.isfinite(info["nav_eta"]))


@pytest.mark.parametrize("observer", ["kbf", "ekf"])
def test_a_sensor_period_off_the_control_period_coasts_to_the_step_end(observer):
    """Sensors every 0.3 s under a 1 s control period: the env feeds its observer each sample
    of the step (with the thrust the observer asks for) and coasts it to the end of the
    period: its estimate equals the same observer (``make_observer``) stepped by hand with the
    step's ``info["measurements"]`` and coasted to ``info["t"]`` with the last sample's
    thrust."""
    from shipgym.observers import make_observer

    env = shipgym.make("harbour", observer=observer, controller="pid", sensors={"period": 0.3})
    _, info = env.reset(seed=4)
    vessel = env.unwrapped.vessel
    ref = make_observer(observer, vessel=vessel)
    first = info["measurements"][0]
    ref.reset(first["t"], first["z"])
    key = "tau_command" if getattr(ref, "thrust_input", "applied") == "command" else "tau"
    coasts = 0
    for _ in range(12):
        _, _, _, _, info = env.step(np.zeros(3, np.float32))
        ms = info["measurements"]
        for m in ms:
            ref.step(m["t"], m["z"], m[key])
        if ms[-1]["t"] < info["t"]:
            ref.step(info["t"], None, ms[-1][key])
            coasts += 1
        np.testing.assert_array_equal(ref.estimate().eta, info["nav_eta"])
        np.testing.assert_array_equal(ref.estimate().nu, info["nav_nu"])
    assert coasts > 0
