"""The tomera2014-lake trial: its sensors, current and model mismatch, and the bench report.

The model split is checked against the numbers printed in Tomera (2014): the controllers and
the EKF use eqs. 49-50 (``M = diag(23664.9, 24830.6, 455182.1)``, ``D_L`` with ``-855.4``
off the diagonal), while the plant of the lake run is the richer default (Table 2 with
``+855.4``, added-mass coupling, nonlinear damping, Coriolis).
"""

import math

import numpy as np
import pytest

from shipgym.bench import TABLE6, bench_scenario_kwargs, table6_comparison
from shipgym.observers.sensors import sensor_config
from shipgym.scenarios import SCENARIOS, load_scenario, scenario_files

EQ49_M = np.diag([23664.9, 24830.6, 455182.1])
EQ50_D_L = np.array([[21.10, 0.0, 0.0], [0.0, 259.8, -855.4], [0.0, -855.4, 6130.5]])


def test_the_lake_file_and_preset_agree_and_use_the_new_models():
    lake = SCENARIOS["tomera2014-lake"]
    assert load_scenario(scenario_files()["tomera2014-lake"]) == lake
    assert lake.plant == "default" and lake.sensors == "tomera2014-lake"
    cfg = sensor_config(lake.sensors)
    assert cfg.position_variance == 0.01  # Tomera (2011) eq. 61, in total
    assert cfg.position_correlated_fraction > 0 and cfg.heading_bias_std > 0
    assert lake.current is not None and lake.current.speed > 0
    assert lake.waves is not None and lake.waves.drift and not lake.waves.first_order


@pytest.mark.parametrize("observer", ["dkf", "kbf", "ekf"])
def test_the_lake_run_splits_plant_and_design_model(observer):
    from shipgym.runner import build_env

    kw = SCENARIOS["tomera2014-lake"].env_kwargs()
    env = build_env("harbour", observer=observer, controller="pid-smooth", **kw)
    try:
        base = env.unwrapped
        plant = base.physics.plant
        assert plant.name == "default"
        D_plant = np.asarray(plant.D_L, dtype=float)
        assert D_plant[1, 2] == pytest.approx(855.4) and D_plant[2, 1] == pytest.approx(855.4)
        assert min(plant.d_quad) > 0 and plant.coriolis  # nonlinear damping and Coriolis on
        M_plant = np.asarray(plant.M_RB, dtype=float) + np.asarray(plant.M_A, dtype=float)[:3]
        # the controller: eqs. 49-50, not the plant
        ctrl = base.controller.pid
        np.testing.assert_array_equal(np.asarray(ctrl.M), EQ49_M)
        np.testing.assert_array_equal(np.asarray(ctrl.D_L), EQ50_D_L)
        assert not np.allclose(np.asarray(ctrl.D_L), D_plant)
        assert not np.allclose(np.asarray(ctrl.M), M_plant)
        # the observer: the EKF holds eqs. 49-50; the kinematic filters hold no hull model
        obs = base.observer
        if observer == "ekf":
            np.testing.assert_array_equal(np.asarray(obs.config.M), EQ49_M)
            np.testing.assert_array_equal(np.asarray(obs.config.D_L), EQ50_D_L)
        else:
            assert not hasattr(obs, "config") or not hasattr(obs.config, "D_L")
        # the env's sensors are the lake preset's
        assert base.sensors is not None and base.sensors.config == sensor_config("tomera2014-lake")
    finally:
        env.close()


def test_bench_scenario_kwargs_refuses_other_envs():
    assert bench_scenario_kwargs(None) is None
    assert bench_scenario_kwargs("tomera2014-lake")["sensors"] == "tomera2014-lake"
    with pytest.raises(ValueError, match="harbour scenario"):
        bench_scenario_kwargs("beaufort5")


def test_table6_comparison_ratios_and_ranking():
    def row(obs, x, y):
        return {"observer": obs, "measured": {"x_E": x, "y_E": y}}

    rows = [row("dkf", 1.3523 * 2.0, 0.4163), row("kbf", 0.2376 / 4.0, 0.2984),
            row("ekf", 1.3774, math.nan), row("ekf", 1.3774, 0.4738)]  # fmt: skip
    text = table6_comparison(rows)
    lines = text.splitlines()
    assert "| dkf | 2.7046 | 1.3523 | 2.00 |" in lines[2] and lines[2].endswith("| yes |")
    assert "| 0.25 |" in lines[3] and lines[3].endswith("| no |")  # kbf x_E 4x below
    assert "| ekf | 1.3774 | 1.3774 | 1.00 | 0.4738 | 0.4738 | 1.00 |" in lines[4]
    assert "(best first): kbf < ekf < dkf" in text
    assert "Table 6: kbf < dkf < ekf" in text
    assert TABLE6["kbf"]["x_E"] + TABLE6["kbf"]["y_E"] + 0.01 * TABLE6["kbf"]["psi_E"] == (
        pytest.approx(TABLE6["kbf"]["J_c"], abs=1e-4)
    )  # eq. 57 holds for the printed row


def test_bench_observers_cli_with_the_lake_scenario(tmp_path, capsys):
    import json

    from shipgym.cli import main

    args = ["bench", "observers", "--observers", "kbf", "--seeds", "1", "--no-progress",
            "--scenario", "tomera2014-lake"]  # fmt: skip
    assert main([*args, "--json", str(tmp_path / "b.json"), "--report", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    assert "scenario tomera2014-lake, wind 3 m/s from 300 deg" in out
    assert "| kbf | 1 | 1/1 |" in out and "| 0.2376 |" in out and "ranking by measured" in out
    assert json.loads((tmp_path / "b.json").read_text())["rows"][0]["observer"] == "kbf"
    assert (tmp_path / "r" / "observers.md").read_text().count("Table 6") >= 2
    assert main(["bench", "observers", "--scenario", "beaufort5", "--seeds", "1"]) == 2
    assert "harbour scenario" in capsys.readouterr().err


def test_velocity_error_evidence_on_a_known_signal():
    """A synthetic trace: the estimate is the truth delayed by 3 s plus white noise; the
    evidence finds the 3 s lag, the RMSE, and a high-frequency share near that of white
    noise (frequencies above 1/20 Hz of the 0-0.5 Hz band of 1 Hz samples: 0.9)."""
    from shipgym.bench import velocity_error_evidence

    rng = np.random.default_rng(0)
    t = np.arange(4000.0)
    nu = np.stack([np.sin(2 * np.pi * t / 200.0)] * 3, axis=1) * 0.05
    est = np.roll(nu, 3, axis=0)
    noise = rng.normal(0.0, 0.002, nu.shape)
    ev = velocity_error_evidence({"t": t, "nu": nu, "err_nu": est - nu})
    assert ev["lag"] == [3.0, 3.0, 3.0]
    ev = velocity_error_evidence({"t": t, "nu": nu, "err_nu": noise})
    for j in range(3):
        assert ev["rmse"][j] == pytest.approx(0.002, rel=0.05)
        assert ev["hf_fraction"][j] == pytest.approx(0.9, abs=0.03)
        assert ev["lag"][j] == 0.0
