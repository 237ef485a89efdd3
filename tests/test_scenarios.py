"""Tests of shipgym.scenarios: Beaufort presets, Froude scaling, scenario files and registry."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from shipgym.disturbances import CurrentConfig, WaveConfig, Waves, WindConfig
from shipgym.dynamics import BLUE_LADY_HULL
from shipgym.scenarios import (
    BEAUFORT_TABLE,
    SCENARIO_KEYS,
    SCENARIOS,
    WAVE_PRESETS,
    Scenario,
    beaufort,
    beaufort_row,
    lake_current,
    lake_waves,
    load_scenario,
    scenario_files,
    scenario_from_dict,
)

# Beaufort table: BF -> (U10 band, Hs, Tp full scale; model U, Hs, Tp, w_p at 1:24)
NOTES_22 = {
    3: ((3.4, 5.4), 0.6, 6.9, 0.9, 0.025, 1.41, 4.45),
    4: ((5.5, 7.9), 1.0, 7.6, 1.4, 0.042, 1.54, 4.07),
    5: ((8.0, 10.7), 2.0, 8.8, 1.9, 0.083, 1.79, 3.51),
    6: ((10.8, 13.8), 3.0, 9.7, 2.5, 0.125, 1.99, 3.16),
    7: ((13.9, 17.1), 4.0, 10.6, 3.2, 0.167, 2.15, 2.92),
    8: ((17.2, 20.7), 5.5, 11.6, 3.9, 0.229, 2.37, 2.65),
    9: ((20.8, 24.4), 7.0, 12.6, 4.6, 0.292, 2.56, 2.45),
}


@pytest.mark.parametrize("n", sorted(NOTES_22))
def test_beaufort_table_matches_notes(n: int) -> None:
    band, hs, tp, U_m, hs_m, tp_m, wp_m = NOTES_22[n]
    row = beaufort_row(n)
    assert (row.U10_min, row.U10_max) == band
    assert row.U10 == pytest.approx(0.5 * sum(band))
    assert row.Hs == hs
    assert row.Tp == pytest.approx(tp, abs=0.06)  # notes round 10.549 and 12.548 up
    wind, waves = beaufort(n, scale=24)
    assert wind.speed == pytest.approx(U_m, abs=0.05)
    assert waves.Hs == pytest.approx(hs_m, abs=5e-4)
    assert waves.Tp == pytest.approx(tp_m, abs=0.006)
    assert waves.peak_frequency == pytest.approx(wp_m, abs=0.011)


def test_beaufort5_model_values_and_options() -> None:
    wind, waves = beaufort(5)  # 1:24 by default
    assert waves.Hs == pytest.approx(0.0833, abs=1e-4)
    assert waves.Tp == pytest.approx(1.79, abs=0.005)
    assert wind.speed == pytest.approx(9.35 / math.sqrt(24))
    assert (wind.gust_spectrum, wind.spectrum_scale) == ("npd", 24.0)
    assert (waves.spectrum, waves.gamma, waves.first_order, waves.drift) == (
        "jonswap",
        3.3,
        True,
        True,
    )
    assert waves.wf_beaufort == 5
    # same direction for wind and waves; full scale with scale = 1
    wind, waves = beaufort(7, scale=1.0, direction_from=1.0, gust_spectrum="harris")
    assert wind.direction_from == waves.direction_from == 1.0
    assert waves.Hs == 4.0 and wind.speed == pytest.approx(15.5)
    assert wind.gust_spectrum == "harris"
    _, waves = beaufort(9, wf_model="al-takie")
    assert waves.wf_model == "al-takie" and waves.wf_beaufort == 9
    assert beaufort(3).waves.wf_beaufort is None


def test_beaufort0_is_calm_and_every_row_builds() -> None:
    wind, waves = beaufort(0)
    assert wind.speed == 0.0 and wind.is_constant
    assert waves.Hs == 0.0 and waves.is_calm
    w = Waves(waves, hull=BLUE_LADY_HULL)
    w.reset(np.random.default_rng(1))
    assert w.drift_load(10.0, 0.0) == (0.0, 0.0, 0.0)
    assert len(BEAUFORT_TABLE) == 10
    for n in range(10):
        wind, waves = beaufort(n, scale=24)
        Waves(waves, hull=BLUE_LADY_HULL)  # every preset builds
    with pytest.raises(ValueError, match="Beaufort number must be an int 0-9"):
        beaufort(10)
    with pytest.raises(ValueError, match="scale must be a number >= 1"):
        beaufort(5, scale=0.5)


def test_lake_preset() -> None:
    cfg = lake_waves(direction_from=1.0)
    assert (cfg.spectrum, cfg.Hs, cfg.Tp, cfg.gamma) == ("jonswap", 0.05, 1.0, 3.3)
    assert cfg.drift and not cfg.first_order and cfg.direction_from == 1.0
    assert lake_waves(Hs=0.03).Hs == 0.03
    assert set(WAVE_PRESETS) == {"lake", "calm"}
    assert WAVE_PRESETS["calm"]().is_calm


def test_seed_presets() -> None:
    lake = SCENARIOS["tomera2014-lake"]
    assert lake.env == "harbour" and lake.plan == "tomera2014"
    assert lake.wind is not None and lake.wind.speed == 3.0
    assert lake.wind.direction_from == pytest.approx(math.radians(300.0))
    assert lake.waves == lake_waves(direction_from=math.radians(300.0))
    assert lake.sensors == "tomera2014-lake"
    # the wind-driven current: 1/300 of the wind speed, going where the wind goes (to 120 deg),
    # speed std 0.01 m/s and direction std 10 deg over 300 s
    c = lake.current
    assert c is not None and c.speed == pytest.approx(0.01, abs=1e-15)
    assert math.degrees(c.direction_to) == pytest.approx(120.0)
    assert c.speed_std == pytest.approx(0.01) and 1.0 / c.mu == pytest.approx(300.0)
    assert math.degrees(c.direction_std) == pytest.approx(10.0)
    assert lake.current == lake_current(3.0, 300.0)
    assert lake_current(5.0, 90.0).speed == pytest.approx(5.0 / 300.0)
    assert math.degrees(lake_current(5.0, 90.0).direction_to) == pytest.approx(270.0)
    sim = SCENARIOS["tomera2011-sim"]
    assert sim.wind is not None and (sim.wind.speed, sim.wind.direction_from) == (2.0, 0.0)
    assert sim.waves is None
    for n in range(10):
        s = SCENARIOS[f"beaufort{n}"]
        assert s.env == "station-keeping" and s.plan is None
        assert s.waves == beaufort(n).waves
    assert SCENARIOS["calm"].wind is None and SCENARIOS["calm"].waves is None


def test_env_kwargs() -> None:
    kw = SCENARIOS["tomera2014-lake"].env_kwargs()
    assert set(kw) == {"plant", "wind", "waves", "current", "sensors", "plan", "start_pose"}
    assert isinstance(kw["wind"], WindConfig) and isinstance(kw["waves"], WaveConfig)
    assert isinstance(kw["current"], CurrentConfig) and kw["plan"] == "tomera2014"
    assert kw["start_pose"] == (0.0, 0.0, 0.0)
    kw = SCENARIOS["beaufort5"].env_kwargs()
    assert "plan" not in kw  # the environment's own default plan
    assert SCENARIOS["beaufort5"].env_id == "shipgym/BlueLadyStationKeeping-v0"


# ---------------------------------------------------------------------------------------------
# files
# ---------------------------------------------------------------------------------------------


def test_packaged_files_load() -> None:
    files = scenario_files()
    assert {"tomera2014-lake", "beaufort5-offshore", "harbour-crosscurrent"} <= set(files)
    for stem, path in files.items():
        s = load_scenario(path)
        assert s.name == stem
    # the packaged lake file is the named preset
    assert load_scenario(files["tomera2014-lake"]) == SCENARIOS["tomera2014-lake"]
    off = load_scenario("beaufort5-offshore")  # by stem
    assert off.env == "station-keeping" and off.sensors == "rtk"
    assert off.waves is not None and off.waves.Hs == pytest.approx(2.0 / 24)
    assert off.waves.direction_from == pytest.approx(math.radians(30.0))
    assert off.wind is not None and off.wind.gust_spectrum == "npd"
    assert off.current is not None and off.current.speed == 0.1
    assert off.current.speed_std == pytest.approx(0.01)
    assert off.current.direction_to == pytest.approx(math.pi / 2)
    toml = load_scenario("harbour-crosscurrent")
    base = SCENARIOS["tomera2014-lake"]
    assert toml.wind == base.wind and toml.waves == base.waves and toml.plan == base.plan
    assert toml.current is not None and toml.current.speed == 0.05


def test_pyproject_ships_the_scenario_files() -> None:
    pyproject = Path(__file__).resolve().parents[1] / "pyproject.toml"
    text = pyproject.read_text()
    if "assets/scenarios" not in text:
        pytest.skip("package-data glob for assets/scenarios not added to pyproject.toml yet")
    assert "assets/scenarios/*.yaml" in text and "assets/scenarios/*.toml" in text


def _write(tmp_path: Path, data: object, name: str = "s.yaml") -> Path:
    p = tmp_path / name
    p.write_text(yaml.safe_dump(data))
    return p


def test_round_trip_through_to_dict(tmp_path: Path) -> None:
    for name in ("tomera2014-lake", "beaufort5", "calm"):
        s = SCENARIOS[name]
        assert scenario_from_dict(s.to_dict()) == s
    s = load_scenario("beaufort5-offshore")
    assert load_scenario(_write(tmp_path, s.to_dict())) == s
    custom = Scenario(
        name="x",
        sensors=None,
        plan=None,
        current=CurrentConfig(speed=0.1),
        start_pose=(1, 2, 0.5),
    )
    assert scenario_from_dict(custom.to_dict()) == custom


def test_file_options(tmp_path: Path) -> None:
    data = {
        "name": "mine",
        "env": "tracking",
        "plant": "seed-linear",
        "beaufort": {"number": 6, "scale": 24, "direction_from_deg": 90, "first_order": False},
        "wind": {"direction_std_deg": 5.0},
        "waves": {"n_components": 50},
        "current": {"speed": 0.1, "direction_to_deg": 180, "sigma": 0.001, "mu": 0.01},
        "sensors": {"preset": "rtk", "period": 0.5},
        "plan": {"legs": [{"surge": 10.0}, {"yaw_deg": 90}], "name": "two-legs"},
        "start_pose": {"x": 1.0, "y": -2.0, "psi_deg": 45.0},
    }
    s = load_scenario(_write(tmp_path, data))
    assert s.name == "mine" and s.env == "tracking" and s.plant == "seed-linear"
    assert s.wind is not None and s.waves is not None and s.current is not None
    assert s.wind.direction_from == pytest.approx(math.pi / 2)
    assert s.wind.direction_std == pytest.approx(math.radians(5.0))
    assert s.waves.n_components == 50 and not s.waves.first_order
    assert s.waves.Hs == pytest.approx(3.0 / 24)
    assert s.current.direction_to == pytest.approx(math.pi)
    assert s.sensors.period == 0.5 and s.sensors.position_variance == pytest.approx(0.02**2)
    assert len(s.plan.legs) == 2 and s.plan.legs[1].yaw == pytest.approx(math.pi / 2)
    assert s.start_pose == pytest.approx((1.0, -2.0, math.pi / 4))
    # switching things off, TOML style
    toml = tmp_path / "off.toml"
    toml.write_text('base = "tomera2014-lake"\nwind = false\nwaves = false\nsensors = false\n')
    off = load_scenario(toml)
    assert off.wind is None and off.waves is None and off.sensors is None
    assert off.name == "off" and off.plan == "tomera2014"
    # an empty file is the default scenario named after the file
    empty = tmp_path / "empty.yaml"
    empty.write_text("")
    assert load_scenario(empty) == Scenario(name="empty")


@pytest.mark.parametrize(
    ("data", "match"),
    [
        ({"wnd": {}}, r"unknown key\(s\) \['wnd'\]; valid keys are: name, description, base"),
        ({"wind": {"speeed": 3}}, r"wind: unknown key\(s\) \['speeed'\]; valid keys are: speed"),
        ({"wind": {"speed": -3}}, "wind: WindConfig.speed must be >= 0"),
        ({"wind": {"direction_from": 1, "direction_from_deg": 50}}, "not both"),
        ({"wind": 3}, "wind must be a mapping"),
        ({"wind": "3 from 300"}, "wind.*expected SPEED@FROM_DEG"),
        ({"wind": "100@300"}, "wind '100@300': WindConfig.speed must be <= 70 m/s"),
        ({"current": "0.1"}, "current.*expected SPEED@TO_DEG"),
        ({"waves": {"Hs": -0.1}}, "waves: WaveConfig.Hs must be >= 0"),
        ({"waves": {"Hs": "5e-2"}}, "waves: WaveConfig.Hs must be a real number"),
        ({"waves": "sea"}, "unknown wave preset 'sea'; valid names are: lake, calm"),
        ({"current": {"speed": 0.1, "std": 0.01, "sigma": 0.1}}, "not both"),
        ({"current": {"spd": 0.1}}, r"current: unknown key\(s\) \['spd'\]"),
        ({"current": {"speed": 0.1, "time_constant": -1}}, "time_constant must be"),
        (
            {"env": "docking"},
            r"unknown env 'docking' \(did you mean 'tracking'\?\); valid names are: harbour",
        ),
        ({"env": 3}, "env must be a string"),
        ({"plant": "fancy"}, "unknown plant variant 'fancy'; valid names are"),
        ({"sensors": "lidar"}, "unknown sensor preset 'lidar'; valid names are"),
        ({"sensors": {"noise": 1}}, r"sensors: unknown key\(s\) \['noise'\]"),
        ({"sensors": {"period": -1.0}}, "sensors: .*period must be > 0"),
        ({"plan": "zigzag"}, "unknown plan 'zigzag'; valid names are: tomera2014"),
        ({"plan": {"legs": []}}, "plan"),
        ({"plan": {"lgs": []}}, r"unknown key\(s\) \['lgs'\]"),
        ({"start_pose": [0, 0]}, "start_pose must be three finite numbers"),
        ({"start_pose": {"x": 0, "heading": 1}}, r"start_pose: unknown key\(s\) \['heading'\]"),
        ({"base": "moon"}, "unknown base scenario 'moon'; valid names are: calm"),
        ({"beaufort": 12}, "beaufort: Beaufort number must be an int 0-9"),
        ({"beaufort": {"scale": 24}}, "missing 'number'"),
        ({"beaufort": {"number": 5, "gama": 3}}, r"beaufort: unknown key\(s\) \['gama'\]"),
        ({"description": ["x"]}, "description must be a string"),
    ],
)
def test_bad_files_raise_clear_errors(tmp_path: Path, data: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        load_scenario(_write(tmp_path, data))


def test_load_errors(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="unknown scenario 'nope'; valid names are: calm"):
        load_scenario("nope")
    with pytest.raises(FileNotFoundError):
        load_scenario(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("wind: [1, 2\n")
    with pytest.raises(ValueError, match="not valid YAML"):
        load_scenario(bad)
    bad = tmp_path / "bad.toml"
    bad.write_text("wind = \n")
    with pytest.raises(ValueError, match="not valid TOML"):
        load_scenario(bad)
    lst = tmp_path / "list.yaml"
    lst.write_text("- 1\n- 2\n")
    with pytest.raises(ValueError, match="must hold a mapping"):
        load_scenario(lst)
    # yaml.safe_load: no arbitrary Python objects
    evil = tmp_path / "evil.yaml"
    evil.write_text("name: !!python/object/apply:os.system ['echo hi']\n")
    with pytest.raises(ValueError, match="not valid YAML"):
        load_scenario(evil)
    assert "beaufort" in SCENARIO_KEYS


def test_scenario_constructor_validation() -> None:
    with pytest.raises(ValueError, match="wind must be a WindConfig or None"):
        Scenario(name="x", wind={"speed": 3.0})  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="non-empty string"):
        Scenario(name="")
    with pytest.raises(ValueError, match="start_pose must be three finite numbers"):
        Scenario(name="x", start_pose=(0.0, math.nan, 0.0))
    s = SCENARIOS["calm"].replace(env="station-keeping")
    assert s.env == "station-keeping"
    with pytest.raises(ValueError, match="unknown env"):
        SCENARIOS["calm"].replace(env="x")


# ---- bounded, code-free loading (issue 10 item 8) -----------------------------------------------
def test_yaml_uses_the_c_safe_loader_when_present():
    import yaml

    from shipgym._safeload import yaml_loader

    expected = yaml.CSafeLoader if yaml.__with_libyaml__ else yaml.SafeLoader
    assert yaml_loader() is expected
    assert issubclass(yaml_loader(), yaml.SafeLoader) or yaml_loader() is yaml.CSafeLoader


@pytest.mark.parametrize("suffix", [".yaml", ".toml"])
def test_oversize_scenario_file_is_refused_before_parsing(tmp_path, suffix):
    from shipgym._safeload import MAX_CONFIG_BYTES

    p = tmp_path / f"big{suffix}"
    p.write_text('name = "x"\n' + "#" * (MAX_CONFIG_BYTES + 10) + "\n")
    with pytest.raises(ValueError, match=r"big\..*more than the limit of 1,048,576"):
        load_scenario(p)


def test_yaml_alias_bomb_and_python_tags_are_refused(tmp_path):
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    for i in range(1, 9):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]")
    bomb = tmp_path / "bomb.yaml"
    bomb.write_text("\n".join(lines) + "\n")  # 10**9 values once expanded
    with pytest.raises(ValueError, match="more than 100,000 values"):
        load_scenario(bomb)
    marker = tmp_path / "ran"
    evil = tmp_path / "evil.yaml"
    evil.write_text(f"name: !!python/object/apply:os.system ['touch {marker}']\n")
    with pytest.raises(ValueError, match="not valid YAML"):
        load_scenario(evil)
    assert not marker.exists()


def test_scenario_path_that_is_a_folder(tmp_path):
    (tmp_path / "d.yaml").mkdir()
    with pytest.raises(ValueError, match="not a file"):
        load_scenario(tmp_path / "d.yaml")


@pytest.mark.parametrize(
    ("current", "match"),
    [
        ({"direction_std_deg": "ten"}, "direction_std_deg must be a finite number"),
        ({"direction_std": 0.1, "direction_sigma": 0.01}, "either 'direction_sigma'"),
        ({"direction_time_constant": 0.0}, "direction_time_constant must be a number > 0"),
        ({"direction_time_constant": 60.0, "direction_mu": 0.1}, "either 'direction_mu'"),
        ({"direction_std": 0.1, "direction_mu": 0.0}, "needs direction_mu > 0"),
    ],
)
def test_current_direction_std_keys_refuse_bad_values(current, match) -> None:
    with pytest.raises(ValueError, match=match):
        scenario_from_dict({"current": {"speed": 0.05, **current}})


def test_current_direction_std_keys() -> None:
    sc = scenario_from_dict(
        {"current": {"speed": 0.05, "direction_std_deg": 10.0, "direction_time_constant": 200.0}}
    )
    assert sc.current is not None and 1.0 / sc.current.direction_mu == pytest.approx(200.0)
    assert math.degrees(sc.current.direction_std) == pytest.approx(10.0)
