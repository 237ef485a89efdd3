"""The results and command-line ergonomics: ``shipgym export``, ``report``'s default folder,
``n/a`` in printed tables, "did you mean" on unknown names, progress bars and notices, the
run header and per-task summaries, the thruster-limit warning, shell completion."""

from __future__ import annotations

import csv
import importlib.util
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from _helpers import one_line_error

from shipgym.cli import main, run_episode
from shipgym.viz import load_run, save_run_json

STEPS = 40  # a shortened harbour episode


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A short recorded harbour run: its ``.rrd``, a JSON run file of it and the results
    file of ``shipgym run --json``."""
    out = tmp_path_factory.mktemp("export")
    rrd = out / "run.rrd"
    results = out / "results.json"
    run_episode("harbour", record=rrd, json_path=results, env_kwargs={"max_episode_steps": STEPS})
    run = load_run(rrd)
    save_run_json(run, out / "runfile.json")
    return {"dir": out, "rrd": rrd, "json": out / "runfile.json", "results": results, "run": run}


def _copy(recorded, tmp_path, key="rrd"):
    src = recorded[key]
    dst = tmp_path / src.name
    shutil.copy(src, dst)
    return dst


# ---- 1. shipgym export -----------------------------------------------------------------------
def _read_csv(path):
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


def test_export_csv_next_to_the_run_with_units_in_the_column_names(recorded, tmp_path, capsys):
    rrd = _copy(recorded, tmp_path)
    assert main(["export", str(rrd), "--csv"]) == 0
    out = tmp_path / "run.csv"
    assert f"wrote {out}" in capsys.readouterr().out
    header, rows = _read_csv(out)
    run = recorded["run"]
    assert len(rows) == len(run.t) == STEPS + 1
    for label in ("t [s]", "x [m]", "y [m]", "psi [rad]", "u [m/s]", "r [rad/s]",
                  "tau_wind_X [N]", "tau_wind_N [N m]", "thrust_bow_tunnel [N]",
                  "command_main_propeller [rpm]", "wind_speed [m/s]", "psi_E [deg]"):  # fmt: skip
        assert label in header, label
    assert len(set(header)) == len(header)
    col = {name: i for i, name in enumerate(header)}
    # the values round-trip exactly, NaN included
    t = np.array([float(r[col["t [s]"]]) for r in rows])
    x = np.array([float(r[col["x [m]"]]) for r in rows])
    psi = np.array([float(r[col["psi [rad]"]]) for r in rows])
    thrust = np.array([float(r[col["thrust_bow_tunnel [N]"]]) for r in rows])
    assert np.array_equal(t, run.t) and np.array_equal(x, run.eta[:, 0])
    assert np.array_equal(psi, run.eta[:, 2]) and np.array_equal(thrust, run.thrust[:, 1])
    jc = np.array([float(r[col["J_c [-]"]]) for r in rows])
    assert np.array_equal(jc, run.accuracy[:, 3], equal_nan=True)
    assert {r[col["saturated_bow_tunnel [-]"]] for r in rows} <= {"0", "1"}


def test_export_csv_reads_back_with_pandas(recorded, tmp_path):
    pd = pytest.importorskip("pandas")
    rrd = _copy(recorded, tmp_path)
    assert main(["export", str(rrd), "--csv", "-o", str(tmp_path / "t.csv")]) == 0
    df = pd.read_csv(tmp_path / "t.csv")
    assert np.array_equal(df["x [m]"].to_numpy(), recorded["run"].eta[:, 0])


def test_export_npz_same_arrays_names_without_units(recorded, tmp_path, capsys):
    rrd = _copy(recorded, tmp_path)
    assert main(["export", str(rrd), "--npz"]) == 0
    out = tmp_path / "run.npz"
    assert f"wrote {out}" in capsys.readouterr().out
    run = recorded["run"]
    with np.load(out, allow_pickle=False) as a:
        units = dict(a["units"])
        assert units["x"] == "m" and units["psi"] == "rad" and units["u"] == "m/s"
        assert units["tau_wind_N"] == "N m" and units["t"] == "s" and units["meas_x"] == "m"
        assert set(units) <= set(a.files)
        assert np.array_equal(a["x"], run.eta[:, 0]) and np.array_equal(a["t"], run.t)
        assert np.array_equal(a["thrust_main_propeller"], run.thrust[:, 0])
        assert np.array_equal(a["meas_t"], run.meas_t)
        assert a["saturated_bow_tunnel"].dtype == bool
        meta = json.loads(str(a["metadata"]))
        assert meta["metadata"]["env_id"] == run.metadata["env_id"]
    # the CSV holds the same columns as the archive's steps
    assert main(["export", str(rrd), "--csv"]) == 0
    header, _ = _read_csv(tmp_path / "run.csv")
    names = [h.rsplit(" [", 1)[0] for h in header]
    with np.load(out) as a:
        assert names == [n for n in dict(a["units"]) if not n.startswith("meas_")]


def test_export_reads_a_json_run_file_and_the_measurements(recorded, tmp_path):
    src = _copy(recorded, tmp_path, "json")
    assert main(["export", str(src), "--csv"]) == 0
    header, rows = _read_csv(tmp_path / "runfile.csv")
    assert "x [m]" in header and len(rows) == STEPS + 1
    assert main(["export", str(src), "--csv", "--table", "measurements"]) == 0
    header, rows = _read_csv(tmp_path / "runfile.measurements.csv")
    assert header[:3] == ["t [s]", "step [-]", "x [m]"] and "outlier [-]" in header
    assert len(rows) == len(recorded["run"].meas_t) > 0


def test_export_refuses_to_overwrite_its_input(recorded, tmp_path, capsys):
    rrd = _copy(recorded, tmp_path)
    before = rrd.read_bytes()
    rc = main(["export", str(rrd), "--csv", "-o", str(rrd)])
    one_line_error(capsys, rc, "--out", "would overwrite the input RUN")
    assert rrd.read_bytes() == before


def test_export_replaces_an_earlier_export_atomically(recorded, tmp_path):
    rrd = _copy(recorded, tmp_path)
    out = tmp_path / "run.csv"
    out.write_text("old\n")
    assert main(["export", str(rrd), "--csv"]) == 0
    assert out.read_text().startswith("t [s],")
    assert [p.name for p in tmp_path.iterdir() if "partial" in p.name] == []


def test_export_of_the_results_file_says_how_to_record_one(recorded, tmp_path, capsys):
    res = _copy(recorded, tmp_path, "results")
    rc = main(["export", str(res), "--csv"])
    one_line_error(capsys, rc, "no time series", "--record RUN.rrd", "shipgym export")
    assert not (tmp_path / "results.csv").exists()


@pytest.mark.parametrize(
    "argv, needles",
    [
        (["export", "missing.rrd", "--csv"], ["no such run file", "missing.rrd"]),
        (["export", "RUN", "--csv", "--npz"], ["not allowed with"]),
        (["export", "RUN"], ["--csv", "--npz"]),
        (["export", "RUN", "--npz", "--table", "measurements"], ["--table", "--csv"]),
    ],
)
def test_export_misuse_is_one_line(argv, needles, recorded, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _copy(recorded, tmp_path)
    argv = [str(tmp_path / "run.rrd") if a == "RUN" else a for a in argv]
    one_line_error(capsys, main(argv), *needles)
    assert not (tmp_path / "missing.csv").exists()


def test_load_run_documents_its_arrays():
    doc = load_run.__doc__
    for name in ("eta", "nu", "command", "thrust", "tau_wind", "meas_t", "accuracy", "metadata",
                 "run_columns"):  # fmt: skip
        assert name in doc, name


# ---- 2. shipgym report without --out ---------------------------------------------------------
def test_report_defaults_to_a_folder_next_to_the_run(recorded, tmp_path, capsys):
    src = _copy(recorded, tmp_path, "json")  # a JSON run file
    assert main(["report", str(src)]) == 0
    folder = tmp_path / "runfile_report"
    assert (folder / "metrics.md").is_file() and list(folder.glob("*.png"))
    assert f"wrote {folder / 'metrics.md'}" in capsys.readouterr().out


def test_report_help_names_the_default_and_the_files_it_reads(capsys):
    assert main(["report", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "<RUN stem>_report" in text
    assert "RUN.rrd" in text and "save_run_json" in text
    assert "the results of 'shipgym run --json', which hold no time series: metrics.md only" in text


def test_report_of_a_missing_run_makes_no_folder(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    one_line_error(capsys, main(["report", "missing.rrd"]), "no such run file", "missing.rrd")
    assert list(tmp_path.iterdir()) == []


def test_report_of_the_results_file_writes_their_metrics(recorded, tmp_path, capsys):
    """``shipgym run --json`` results hold metrics, no time series: the report is their
    metrics.md (what ran, the indices, legs, thrusters, chatter, estimation errors), no
    figures, and says how to get them."""
    src = _copy(recorded, tmp_path, "results")
    res = json.loads(src.read_text())
    assert main(["report", str(src)]) == 0
    out = capsys.readouterr().out
    assert "no time series" in out and "--record RUN.rrd" in out
    folder = src.with_name(src.stem + "_report")
    assert sorted(p.name for p in folder.iterdir()) == ["metrics.md"]
    md = (folder / "metrics.md").read_text()
    assert f"`{res['env_id']}`" in md and f"| plant | {res['plant']} |" in md
    cell = lambda v: "n/a" if v is None else f"{v:.4f}"  # noqa: E731 (null: too short a run)
    assert f"| truth | {cell(res['x_E'])} | {cell(res['y_E'])} |" in md
    for name in res["vessel"]["actuators"]:  # the per-actuator rows under their names
        assert f"| {name.replace('_', ' ')} |" in md, name
    assert "## Estimation errors" in md or not res.get("rmse")


def test_run_json_records_the_vessel_that_ran(recorded):
    res = json.loads(Path(recorded["results"]).read_text())
    assert res["vessel"]["name"] == "blue-lady"
    assert res["vessel"]["actuators"] == ["main_propeller", "bow_tunnel", "stern_tunnel"]
    assert len(res["vessel"]["channels"]) == len(res["reversals_per_min"])


# ---- 3. n/a instead of inf / nan in printed tables -------------------------------------------
def _words(text):
    return set(text.replace("[", " ").replace("]", " ").replace(",", " ").split())


def test_printed_table_says_n_a_for_nan_and_inf_and_json_keeps_null(tmp_path, capsys):
    from shipgym.cli import _print_table

    res = run_episode("harbour", json_path=tmp_path / "r.json", env_kwargs={"max_episode_steps": 5})
    res = {**res, "J_c": math.inf, "x_E": -math.inf, "leg_times": [12.0, math.nan]}
    res["measured"] = {**(res["measured"] or {}), "J_c": math.inf, "psi_E": math.nan}
    res["thrust_mean_abs"] = [math.nan, 1.0, math.inf]
    res["limit_fraction"] = [math.inf, 0.5, math.nan]
    res["rmse"] = {"x": math.nan, "y": 0.1, "psi": math.inf, "u": 0.0, "v": 0.0, "r": math.nan}
    _print_table(res)
    out = capsys.readouterr().out
    words = {w.lower() for w in _words(out)}
    assert not words & {"nan", "inf", "-inf", "infinity"}, out
    assert "n/a" in words
    jc = next(ln for ln in out.splitlines() if ln.strip().startswith("J_c"))
    assert jc.split()[1:3] == ["n/a", "n/a"], jc
    assert "[12.0, n/a]" in out and "[n/a, 1.0, n/a]" in out and "x n/a m" in out
    doc = json.loads((tmp_path / "r.json").read_text())  # the file keeps strict JSON: null
    assert doc["J_c"] is None and doc["indices_note"]


def test_num_formats_finite_values_only():
    from shipgym._text import num, num_list

    assert num(0.12345) == "0.1235" and num(3, ".1f") == "3.0" and num(0.5, ".1%") == "50.0%"
    for bad in (math.nan, math.inf, -math.inf, None, np.float64("nan"), "x"):
        assert num(bad) == "n/a"
    assert num_list([240.0, 1 / 3, math.inf, None], 1) == "[240.0, 0.3, n/a, n/a]"


# ---- 4. "did you mean" on unknown names ------------------------------------------------------
def test_did_you_mean_helper():
    from shipgym._text import close_matches, did_you_mean

    assert did_you_mean("harbor", ["harbour", "tracking"]) == " (did you mean 'harbour'?)"
    assert did_you_mean("xyzzy", ["harbour", "tracking"]) == ""
    assert did_you_mean(None, ["harbour"]) == "" and did_you_mean(3, ["harbour"]) == ""
    assert close_matches("Blue_Lady", ["blue-lady", "wimpey-sealab"]) == ["blue-lady"]
    assert close_matches("StationKeeping-v0", ["shipgym/StationKeeping-v0"]) == [
        "shipgym/StationKeeping-v0"
    ]
    many = did_you_mean("kf41", ["kf14", "kf16", "kf12", "ekf"])
    assert many.startswith(" (did you mean 'kf1") and ", " in many and " or " in many


CLI_SUGGESTIONS = [
    (["run", "harbor"], "'harbor' (did you mean 'harbour'"),
    (["run", "--vessel", "blue_lday"], "(did you mean 'blue-lady'?)"),
    (["run", "--controller", "pdi"], "'pdi' (did you mean 'pid'?)"),
    (["run", "--observer", "ekff"], "'ekff' (did you mean 'ekf'?)"),
    (["run", "--plant", "defualt"], "'defualt' (did you mean 'default'?)"),
    (["run", "--scenario", "harbour-crosscurent"], "(did you mean 'harbour-crosscurrent'?)"),
    (["bench", "obsrvers"], "'obsrvers' (did you mean 'observers'?)"),
    (["bench", "dp", "--methods", "kf41"], "'kf41' (did you mean"),
    (["bench", "dp", "--task", "sway-stp"], "(did you mean 'sway-step'?)"),
    (["bench", "roll", "--task", "beamsea"], "(did you mean 'beam-sea'?)"),
    (["trials", "--manoeuvres", "zigzg10"], "(did you mean 'zigzag10'"),
    (["lst"], "'lst' (did you mean 'list'?)"),
]


@pytest.mark.parametrize(
    "argv, needle", CLI_SUGGESTIONS, ids=[" ".join(a) for a, _ in CLI_SUGGESTIONS]
)
def test_cli_suggests_close_names(argv, needle, capsys):
    line = one_line_error(capsys, main([*argv, "--no-progress"] if argv[0] == "run" else argv),
                           needle)  # fmt: skip
    assert line.count(", ") >= 1  # the list of the valid names is still there


def test_api_suggests_close_names():
    import shipgym
    from shipgym.controllers.batch import controller_spec
    from shipgym.disturbances import WindConfig
    from shipgym.observers import make_observer
    from shipgym.scenarios import load_scenario

    cases = [
        (lambda: shipgym.make("harbor"), "did you mean 'harbour'"),
        (lambda: shipgym.make("shipgym/StationKeepin-v0"), "'shipgym/StationKeeping-v0'"),
        (lambda: shipgym.load_vessel("wimpey-seelab"), "did you mean 'wimpey-sealab'"),
        (lambda: load_scenario("tomera2014-lak"), "did you mean 'tomera2014-lake'"),
        (lambda: make_observer("kbff"), "did you mean 'kbf'"),
        (lambda: controller_spec("pid-smoth"), "did you mean 'pid-smooth'"),
        (lambda: shipgym.load_vessel("blue-lady").plant("seed-lineer"), "'seed-linear'"),
        (
            lambda: WindConfig(speed=3.0, coefficients="tanker-loadd"),
            "did you mean 'tanker-loaded'",
        ),
    ]
    for call, needle in cases:
        with pytest.raises(ValueError) as info:
            call()
        assert needle in str(info.value), str(info.value)
    with pytest.raises(ValueError) as info:  # nothing close: no suggestion
        shipgym.make("zzzzzz")
    assert "did you mean" not in str(info.value)


# ---- 5. progress bars that end at 100 %, training budgets that round -------------------------
HAS_RL = all(importlib.util.find_spec(m) is not None for m in ("torch", "stable_baselines3"))


def test_run_progress_bar_ends_at_100_percent_and_says_why(monkeypatch, capsys):
    import shipgym._io

    monkeypatch.setattr(shipgym._io, "progress_enabled", lambda *a, **k: True)
    res = run_episode("harbour", progress=True)  # ends when the plan completes, before 2000 steps
    assert res["terminated"] and res["completed"]
    n = round(res["duration_s"])
    assert n < 2000
    last = capsys.readouterr().err.replace("\r", "\n").strip().splitlines()[-1]
    assert "100%" in last and f"{n}/{n}" in last, last
    assert f"ended at step {n} of the 2000 allowed: plan complete" in last, last


def test_run_progress_total_of_a_task_that_truncates_itself():
    import shipgym
    from shipgym.runner import _episode_steps

    env = shipgym.make("shipgym/DPStationKeeping-v0", vessel="wimpey-sealab")
    try:
        base = env.unwrapped
        assert env.spec.max_episode_steps is None
        assert _episode_steps(env) == round(base.episode_duration / base.control_period)
    finally:
        env.close()
    env = shipgym.make("harbour")
    assert _episode_steps(env) == 2000
    env.close()


def test_training_budget_rounds_to_whole_rollouts():
    from shipgym.rl.train import load_hyperparams, planned_timesteps, rounding_notice

    hp = {"n_steps": 2048, "n_envs": 16}
    assert planned_timesteps("ppo", hp, 20000) == (32768, 32768)
    assert planned_timesteps("ppo", hp, 65536) == (65536, 32768)
    note = rounding_notice("ppo", hp, 20000)
    assert (
        "20,000" in note and "rounded up to 32,768" in note and "n_steps 2,048 x n_envs 16" in note
    )
    assert "\n" not in note and rounding_notice("ppo", hp, 32768) is None
    assert planned_timesteps("sac", {"n_envs": 16, "train_freq": 1}, 20001) == (20016, 16)
    assert planned_timesteps("sac", {"n_envs": 4, "train_freq": [2, "step"]}, 9) == (16, 8)
    assert planned_timesteps("sac", {"n_envs": 4, "train_freq": [1, "episode"]}, 9) == (9, 0)
    assert rounding_notice("sac", {"n_envs": 4, "train_freq": [1, "episode"]}, 9) is None
    shipped = load_hyperparams("ppo", "shipgym/BlueLadyTracking-v0")
    assert (
        planned_timesteps("ppo", shipped, 20000)[0] % (shipped["n_steps"] * shipped["n_envs"]) == 0
    )


@pytest.mark.skipif(not HAS_RL, reason="needs the rl extra (torch, stable-baselines3)")
def test_train_says_the_budget_was_rounded(tmp_path, capsys):
    argv = ["train", "ppo", "--timesteps", "100", "--n-envs", "1", "--eval-freq", "0",
            "--checkpoint-freq", "0", "--out", str(tmp_path / "t"), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    cap = capsys.readouterr()
    notes = [ln for ln in cap.err.splitlines() if "rounded up" in ln]
    assert len(notes) == 1 and "budget of 100 timesteps is rounded up to 256" in notes[0]
    assert "trained 256 steps" in cap.out


# ---- 6. the run header's wind in words; a station keeping's own summary ----------------------
def test_run_header_prints_the_wind_in_words(capsys):
    assert main(["run", "harbour", "--no-progress"]) == 0
    head = capsys.readouterr().out.splitlines()[0]
    assert "{" not in head and "'speed'" not in head, head
    assert "wind 3 m/s from 300 deg, gusts 0.45 m/s rms and 10 deg rms (gauss-markov) |" in head


def test_wind_text_forms():
    from shipgym.cli import _wind_text

    wind = {"speed": 10.0, "from_deg": 45.0}
    assert _wind_text(None, None) == "none"
    assert _wind_text({"speed": 0.0, "from_deg": 0.0}, None) == "calm (0 m/s)"
    assert _wind_text(wind, None) == "10 m/s from 45 deg"  # results written before gusts
    steady = {"speed_std": 0.0, "spectrum": "gauss-markov", "direction_std_deg": 0.0}
    assert _wind_text(wind, steady) == "10 m/s from 45 deg, steady"
    npd = {"speed_std": 1.234, "spectrum": "npd", "direction_std_deg": 10.0}
    assert _wind_text(wind, npd) == "10 m/s from 45 deg, gusts 1.2 m/s rms and 10 deg rms (npd)"


def test_station_keeping_run_prints_its_own_summary(tmp_path, capsys):
    out = tmp_path / "sk.json"
    assert main(["run", "station-keeping", "--no-progress", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    for gone in ("legs completed", "leg times", "quay contact", "J_c"):
        assert gone not in text, gone
    rows = {ln[2:18].strip(): ln for ln in text.splitlines()[1:] if ln.strip()}
    assert "2.00 m radius" in rows["watch circle"]
    assert "% of the steps" in rows["time inside"] and " m " in rows["r95"]
    res = json.loads(out.read_text())
    sk = res["station_keeping"]
    assert sk["radius_m"] == 2.0 and sk["steps"] == 600
    assert 0.0 <= sk["inside_fraction"] <= 1.0 and 0.0 < sk["r95"] <= sk["r_max"]
    assert f"{sk['r95']:.3f} m" in rows["r95"]
    assert res["gusts"]["speed_std"] == pytest.approx(0.45) and res["J_c"] is not None
    harbour = run_episode("harbour", env_kwargs={"max_episode_steps": 3})
    assert harbour["station_keeping"] is None


def test_offshore_dp_watch_circle_is_al_takies():
    from shipgym.cli import _watch_radius
    from shipgym.dp.metrics import dp_radius

    assert _watch_radius("shipgym/DPStationKeeping-v0") == dp_radius() == 7.0
    assert _watch_radius("shipgym/BlueLadyStationKeeping-v0") == 2.0
    res = run_episode("station-keeping", env_kwargs={"max_episode_steps": 5}, watch_radius=0.5)
    assert res["station_keeping"]["radius_m"] == 0.5 and res["station_keeping"]["steps"] == 5
    with pytest.raises(ValueError, match="watch_radius"):
        run_episode("station-keeping", watch_radius=-1.0)


# ---- 7. a warning when a thruster sat at a limit most of the run -----------------------------
def test_warning_when_commands_sit_at_a_limit_most_of_the_run(capsys):
    assert main(["run", "station-keeping", "--wind", "8@90", "--no-progress"]) == 0
    cap = capsys.readouterr()
    limit = next(ln for ln in cap.out.splitlines() if "at a limit" in ln)
    warnings = [ln for ln in cap.err.splitlines() if ln.startswith("shipgym: warning:")]
    assert len(warnings) == 1, cap.err
    assert "bow_tunnel" in warnings[0] and "stern_tunnel" in warnings[0], warnings[0]
    assert "main_propeller" not in warnings[0]  # below half the run
    shares = json.loads(limit.split("at a limit", 1)[1])  # the row the warning reuses
    assert shares[0] <= 0.5 < min(shares[1:])
    assert main(["run", "station-keeping", "--no-progress"]) == 0  # the default wind: no warning
    assert "warning" not in capsys.readouterr().err


def test_limit_warning_threshold():
    from shipgym.cli import _limit_warning

    names = ["a", "b", "c"]
    assert _limit_warning({"limit_fraction": [0.5, 0.1, math.nan]}, names) is None
    line = _limit_warning({"limit_fraction": [0.51, 0.9, None]}, names)
    assert line.startswith("shipgym: warning:") and "\n" not in line
    assert line.index("b 90.0 %") < line.index("a 51.0 %")  # the worst first
    assert _limit_warning({}, names) is None


# ---- 8. optional shell completion ------------------------------------------------------------
def test_argcomplete_is_called_when_installed_and_optional(monkeypatch, capsys):
    import sys
    import types

    seen = []
    fake = types.SimpleNamespace(autocomplete=lambda parser: seen.append(parser))
    monkeypatch.setitem(sys.modules, "argcomplete", fake)
    assert main(["--version"]) == 0
    assert len(seen) == 1 and seen[0].prog == "shipgym"
    monkeypatch.setitem(sys.modules, "argcomplete", None)  # not installed: import fails
    assert main(["--version"]) == 0
    capsys.readouterr()


def test_help_says_how_to_switch_completion_on(capsys):
    assert main(["--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "pip install argcomplete" in text
    assert 'eval "$(register-python-argcomplete shipgym)"' in text
    head = Path(__file__).resolve().parents[1].joinpath("shipgym", "cli.py").read_text()[:1024]
    assert "PYTHON_ARGCOMPLETE_OK" in head  # global completion finds the marker


def test_run_options_complete_names():
    from shipgym.cli import _parser

    sub = next(a for a in _parser()._actions if a.dest == "command").choices["run"]
    comp = {a.dest: a.completer for a in sub._actions if hasattr(a, "completer")}
    assert "pid" in comp["controller"]("pi") and all(
        n.startswith("pi") for n in comp["controller"]("pi")
    )
    assert comp["scenario"]("stat") == ["station-keeping"]
    assert "wimpey-sealab" in comp["vessel"]("w") and "kbf" in comp["observer"]("")
    assert "beaufort5-offshore" in comp["scenario_file"]("beau")
    assert "ppo:PATH" not in comp["controller"]("")


def test_real_argcomplete_completes_subcommands(tmp_path):
    argcomplete = pytest.importorskip("argcomplete")
    import os
    import subprocess
    import sys

    line = "shipgym ben"
    env = {**os.environ, "_ARGCOMPLETE": "1", "COMP_LINE": line, "COMP_POINT": str(len(line)),
           "_ARGCOMPLETE_IFS": " ",
           "PYTHONPATH": os.pathsep.join([str(Path(argcomplete.__file__).parents[1]),
                                          os.environ.get("PYTHONPATH", "")])}  # fmt: skip
    cmd = f"'{sys.executable}' -m shipgym.cli 8>&1 9>/dev/null"
    out = subprocess.run(["bash", "-c", cmd], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.split() == ["bench"], out


# ---- a reader that stops reading -------------------------------------------------------------
def test_a_closed_pipe_ends_the_command_quietly(tmp_path):
    """A reader that stops reading (``shipgym list | true``; ``| head``): the command stops
    at the closed pipe with the status a shell gives a command SIGPIPE ended (141) and prints
    no error (it printed ``shipgym: error: cannot write: Broken pipe`` and exited 1, or, for an
    output that fit the pipe, Python's "Exception ignored ... BrokenPipeError" at exit)."""
    import subprocess
    import sys

    for args in ("list", "run harbour --no-progress"):
        # `true` has long exited when shipgym first writes (after its imports)
        cmd = f"'{sys.executable}' -m shipgym.cli {args} | true; echo \"status ${{PIPESTATUS[0]}}\""
        r = subprocess.run(["bash", "-c", cmd], cwd=tmp_path, capture_output=True, text=True,
                           timeout=300)  # fmt: skip
        assert r.stdout.splitlines() == ["status 141"], (args, r.stdout, r.stderr)
        for bad in ("error", "Traceback", "Exception ignored", "BrokenPipe"):
            assert bad not in r.stderr, (args, r.stderr)  # (a first-compile notice may show)
