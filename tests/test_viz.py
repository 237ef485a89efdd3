"""Headless rerun recording (RecordEpisode), reading runs back, and the PNG/Markdown report."""

import gc
import os
import shutil
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from _helpers import read_rrd

import shipgym
from shipgym.records import NavigationData
from shipgym.viz import (
    RecordEpisode,
    load_run,
    pixel_size,
    recording_problem,
    report_paths,
    save_run_json,
    write_report,
)
from shipgym.viz.run import DATA_VECTORS, P, command_path

STEPS = 200  # a shortened harbour episode (truncated by the time limit)


def _rerun_verify(path):
    """``rerun rrd verify PATH`` (footer checked) -> (ok, output); None without the CLI."""
    exe = shutil.which("rerun") or str(Path(sys.executable).parent / "rerun")
    if not Path(exe).exists():
        return None
    out = subprocess.run(
        [exe, "rrd", "verify", str(path)], capture_output=True, text=True, timeout=120
    )
    return out.returncode == 0, out.stdout + out.stderr


def _make(max_steps=STEPS):
    return shipgym.make("harbour", controller="pid", max_episode_steps=max_steps)


def _sorted(rows, column):
    order = np.argsort(rows["step"], kind="stable")
    return np.asarray(rows["step"])[order], [rows[column][i] for i in order]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    out = tmp_path_factory.mktemp("rec")
    env = RecordEpisode(
        _make(), out / "sub" / "run.rrd", json_path=out / "run.json", flush_every=64
    )
    _, info = env.reset(seed=0)
    infos = [info]
    while True:
        _, _, terminated, truncated, info = env.step(np.zeros(3, np.float32))
        infos.append(info)
        if terminated or truncated:
            break
    run = env.last_run
    env.close()
    return {
        "rrd": out / "sub" / "run.rrd",
        "json": out / "run.json",
        "infos": infos,
        "run": run,
        "truncated": truncated,
    }


def test_recording_has_entities_and_one_row_per_step(recorded):
    assert recorded["truncated"], "the shortened episode ends by the time limit"
    n_steps = len(recorded["infos"]) - 1
    assert n_steps == STEPS
    static, rows = read_rrd(recorded["rrd"])
    expected = [
        P.SHIP,
        P.THRUST,
        P.TRACK_TRUTH,
        P.TRACK_REF,
        P.DGPS,
        P.WIND,
        P.TARGET,
        P.HULL_TRACE,
        f"{P.POSITION}/x",
        f"{P.POSITION}/psi/measured",
        f"{P.VELOCITY}/r",
        P.PLOT_THRUST,
        command_path("rpm"),  # the main propeller
        command_path("1"),  # the tunnel thrusters
        P.ACCURACY,
        P.ACCURACY_MEAS,
        *(f"{P.DATA}/{k}" for k in DATA_VECTORS),
    ]
    for ent in expected:
        assert ent in rows, ent
    for ent in (P.NED, P.QUAYS, P.PLAN, P.WAYPOINTS, P.HULL, P.SUMMARY, P.META_JSON):
        assert ent in static, ent
    # step 0 is the state after reset, then one row per env.step
    for ent in (P.SHIP, P.TRACK_TRUTH, f"{P.POSITION}/x", f"{P.DATA}/eta"):
        steps = np.sort(rows[ent]["step"])
        np.testing.assert_array_equal(steps, np.arange(n_steps + 1))
    quays = static[P.QUAYS]["LineStrips2D:strips"]
    assert len(quays) == 6  # quay_east/south/west/north, pier_berth_b, pier_finger


def test_logged_truth_equals_info_values(recorded):
    infos = recorded["infos"]
    eta = np.array([i["eta"] for i in infos])
    t = np.array([i["t"] for i in infos])
    _, rows = read_rrd(recorded["rrd"])
    steps, trans = _sorted(rows[P.SHIP], "Transform3D:translation")
    trans = np.array(trans).reshape(-1, 3)
    np.testing.assert_array_equal(trans[:, :2], eta[:, :2].astype(np.float32))
    _, quat = _sorted(rows[P.SHIP], "Transform3D:quaternion")
    quat = np.array(quat).reshape(-1, 4)
    psi = 2.0 * np.arctan2(quat[:, 2], quat[:, 3])
    np.testing.assert_allclose(np.unwrap(psi), eta[:, 2], atol=2e-6)
    _, pts = _sorted(rows[P.TRACK_TRUTH], "Points2D:positions")
    np.testing.assert_array_equal(np.array(pts).reshape(-1, 2), eta[:, :2].astype(np.float32))
    _, data = _sorted(rows[f"{P.DATA}/eta"], "Scalars:scalars")
    np.testing.assert_array_equal(np.array(data).reshape(-1, 3), eta)  # float64, exact
    st, times = _sorted(rows[f"{P.DATA}/eta"], "sim_time")
    np.testing.assert_allclose(np.array(times) * 1e-9, t, atol=1e-9)


def test_load_run_rrd_and_json_agree_with_info(recorded):
    infos = recorded["infos"]
    r_rrd = load_run(recorded["rrd"])
    r_json = load_run(recorded["json"])
    assert r_rrd.n_steps == STEPS and r_json.n_steps == STEPS
    for name in ("eta", "nu", "nav_eta", "eta_d", "eta_d_r", "eta_r", "eta_P", "thrust"):
        ref = np.array([i[name] for i in infos])
        np.testing.assert_array_equal(getattr(r_rrd, name), ref, err_msg=name)
        np.testing.assert_array_equal(getattr(r_json, name), ref, err_msg=name)
    np.testing.assert_array_equal(r_rrd.leg, [i["leg"] for i in infos])
    np.testing.assert_array_equal(r_rrd.saturated, np.array([i["saturated"] for i in infos]))
    np.testing.assert_allclose(r_rrd.t, r_json.t, atol=1e-9)
    np.testing.assert_allclose(r_rrd.meas_z, r_json.meas_z)
    np.testing.assert_allclose(r_rrd.accuracy, r_json.accuracy, equal_nan=True)
    assert len(r_rrd.meas_t) == STEPS + 1  # 1 s DGPS samples, one per control step
    assert r_rrd.metadata["controller"] == "pid" and r_rrd.metadata["seed"] == 0
    assert r_rrd.metadata["env_id"] == "shipgym/BlueLadyHarbour-v0"
    assert r_rrd.quays.shape == (6, 4, 2) and len(r_rrd.hull) > 10
    np.testing.assert_allclose(r_rrd.waypoints[1], [0.0, -7.0, 0.0], atol=1e-12)


def test_running_accuracy_ends_at_the_env_metrics(recorded):
    """The recording's running indices are the env's metrics fed the recorded rows: the last
    row holds the episode's indices, float for float."""
    run = recorded["run"]
    m = run.metrics
    assert run.accuracy[-1].tolist() == [m["x_E"], m["y_E"], m["psi_E"], m["J_c"]]
    mm = m["measured"]
    assert run.accuracy_measured[-1].tolist() == [mm["x_E"], mm["y_E"], mm["psi_E"], mm["J_c"]]


def _interrupted(path, how):
    env = RecordEpisode(_make(), path, flush_every=1000)
    env.reset(seed=1)
    with pytest.raises(KeyboardInterrupt):
        for k in range(STEPS):
            if k == 50:
                raise KeyboardInterrupt
            env.step(np.zeros(3, np.float32))
    if how == "close":
        env.close()
    else:
        del env
        gc.collect()


@pytest.mark.parametrize("how", ["close", "gc"])
def test_interrupted_episode_leaves_a_readable_file(tmp_path, how):
    path = tmp_path / "interrupted.rrd"
    _interrupted(path, how)
    partial = tmp_path / "interrupted.partial.rrd"
    assert not path.exists(), "an incomplete episode never takes the final name"
    _, rows = read_rrd(partial)
    np.testing.assert_array_equal(np.sort(rows[P.SHIP]["step"]), np.arange(51))
    run = load_run(partial)
    assert run.n_steps == 50
    assert run.metadata["recording"]["complete"] is False
    assert run.metadata["recording"]["footer"] is True  # finalised by close() / the finaliser
    assert "stopped before its end after 50 steps" in recording_problem(run)


def test_complete_recording_is_marked_and_verifies(recorded):
    run = load_run(recorded["rrd"])
    assert run.metadata["recording"] == {
        "complete": True,
        "ended": "truncated",
        "steps": STEPS,
        "footer": True,
    }
    assert recording_problem(run) is None
    assert load_run(recorded["json"]).metadata["recording"]["complete"] is True
    assert not list(recorded["rrd"].parent.glob("*partial*"))
    verified = _rerun_verify(recorded["rrd"])
    if verified is not None:
        assert verified[0], verified[1]


def test_interrupted_rerecording_keeps_the_earlier_file(tmp_path, recorded):
    path = tmp_path / "again.rrd"
    shutil.copyfile(recorded["rrd"], path)
    before = path.read_bytes()
    _interrupted(path, "close")
    assert path.read_bytes() == before
    assert (tmp_path / "again.partial.rrd").is_file()
    # a complete re-recording replaces it, and takes the partial file's place
    env = RecordEpisode(_make(max_steps=5), path)
    env.reset(seed=3)
    for _ in range(5):
        env.step(np.zeros(3, np.float32))
    env.close()
    assert env.paths == [path]
    assert load_run(path).n_steps == 5
    assert not (tmp_path / "again.partial.rrd").exists()


@pytest.mark.parametrize("fraction", [0.0, 0.01, 0.3, 0.7, 0.999])
def test_truncated_recording_is_refused_or_marked(tmp_path, recorded, fraction):
    """A file cut short (a killed process): one-line ValueError, or a run marked incomplete."""
    data = recorded["rrd"].read_bytes()
    cut = tmp_path / "cut.rrd"
    cut.write_bytes(data[: int(len(data) * fraction)])
    try:
        run = load_run(cut)
    except ValueError as exc:
        assert "\n" not in str(exc) and "truncated" in str(exc)
        return
    assert recording_problem(run) is not None


def test_recording_without_footer_counts_as_incomplete(tmp_path, monkeypatch):
    """The footer check on its own: a finished episode whose file was not finalised."""

    def open_sinks(self, rec, path, blueprint):
        rec.save(path, write_footer=False)

    monkeypatch.setattr(RecordEpisode, "_open_sinks", open_sinks)
    path = tmp_path / "nofooter.rrd"
    env = RecordEpisode(_make(max_steps=4), path)
    env.reset(seed=0)
    for _ in range(4):
        env.step(np.zeros(3, np.float32))
    env.close()
    run = load_run(path)
    assert run.metadata["recording"]["complete"] is True  # the marker alone says complete
    assert "no rerun footer" in recording_problem(run)


def test_report_of_an_incomplete_recording_says_so(tmp_path):
    path = tmp_path / "int.rrd"
    _interrupted(path, "close")
    files = write_report(tmp_path / "int.partial.rrd", tmp_path / "rep")
    text = files[4].read_text()
    assert "**INCOMPLETE RECORDING**" in text and "50 control steps" in text
    assert not list((tmp_path / "rep").glob("*partial*"))


def test_unwritable_path_fails_before_the_episode(tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    env = _make()
    with pytest.raises(ValueError, match="cannot record to .*a_file"):
        RecordEpisode(env, blocker / "sub" / "run.rrd")
    with pytest.raises(ValueError, match="must end with .rrd"):
        RecordEpisode(env, tmp_path / "run.txt")
    with pytest.raises(ValueError, match="cannot record to"):
        RecordEpisode(env, tmp_path / "ok.rrd", json_path=blocker / "run.json")
    with pytest.raises(ValueError, match="flush_every"):
        RecordEpisode(env, tmp_path / "ok.rrd", flush_every=0)
    assert not (tmp_path / "ok.rrd").exists()  # the check leaves no file behind


def _blueprint_views(path):
    """The views of the blueprint stored in a ``.rrd`` file: ``{entity: {component: value}}``
    for each ``/view/<id>`` entity and its property entities (``/view/<id>/TimeAxis``...)."""
    from rerun.chunk import RrdReader

    reader = RrdReader(path)
    (store,) = reader.blueprints()
    views = {}
    for ch in reader.stream(store=store):
        if not ch.entity_path.startswith("/view/"):
            continue
        rb = ch.to_record_batch()
        slot = views.setdefault(ch.entity_path, {})
        for i, name in enumerate(rb.schema.names):
            if ":" not in name:  # a timeline (log_time: nanoseconds pyarrow cannot convert)
                continue
            values = rb.column(i).to_pylist()
            if values and values[-1] is not None:
                slot[name] = values[-1][0] if len(values[-1]) == 1 else values[-1]
    return views


def test_time_series_views_show_the_whole_episode_without_legends(recorded):
    """rerun shows a timeline longer than 60 s as the cursor +- 30 s unless the view's time
    axis says otherwise: every time series view of the stored blueprint has the whole timeline
    (both ends unbounded) on its time axis, and no legend drawn over its curves."""
    from shipgym.viz.recorder import PLOT_KEY

    run = recorded["run"]
    assert run.t[-1] - run.t[0] > 60.0  # long enough for rerun to narrow the axis otherwise
    views = _blueprint_views(recorded["rrd"])
    series = [
        e for e, c in views.items() if c.get("ViewBlueprint:class_identifier") == "TimeSeries"
    ]
    names = {views[e]["ViewBlueprint:display_name"] for e in series}
    assert {"x^r (m)", "u (m/s)", "psi^r (deg)", "thrust (N)", "accuracy indices"} <= names
    for e in series:
        axis = views.get(f"{e}/TimeAxis", {})
        assert axis.get("TimeAxis:view_range") == {"start": None, "end": None}, (e, axis)
        legend = views.get(f"{e}/PlotLegend", {})
        assert legend.get("PlotLegend:visible") is False, (e, legend)
    static, _ = read_rrd(recorded["rrd"])
    summary = static[P.SUMMARY]["TextDocument:text"]
    assert PLOT_KEY in (
        summary[0] if isinstance(summary, list) else summary
    )  # the colours' key, in place of the legends


def test_spawn_without_display_records_to_the_file(tmp_path, monkeypatch, capsys):
    if not sys.platform.startswith("linux"):
        pytest.skip("the no-display check is Linux-specific")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    path = tmp_path / "spawn.rrd"
    env = RecordEpisode(_make(), path, spawn=True)
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.zeros(3, np.float32))
    env.close()
    err = capsys.readouterr().err
    assert "no rerun viewer available" in err
    # the headless route to the file the episode ends in (not its partial file)
    assert f"rerun --serve-web --bind 127.0.0.1 {path}" in err
    assert "http://127.0.0.1:9090/?url=" in err
    assert env.paths == [tmp_path / "spawn.partial.rrd"]  # closed before the episode's end
    assert load_run(env.paths[0]).n_steps == 5


def test_episodes_go_to_numbered_files_and_spec_round_trips(tmp_path):
    path = tmp_path / "ep.rrd"
    env = RecordEpisode(_make(max_steps=3), path, flush_every=1)
    env.reset(seed=0)
    env.reset(seed=0)  # an empty episode is replaced, not kept
    for _ in range(2):
        for _ in range(3):
            *_, terminated, truncated, _ = env.step(np.zeros(3, np.float32))
        assert truncated
        env.reset(seed=1)
    env.close()
    # the third episode, closed right after its reset, is discarded with its partial file
    assert env.paths == [path, tmp_path / "ep-1.rrd"]
    assert [load_run(p).n_steps for p in env.paths] == [3, 3]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ep-1.rrd", "ep.rrd"]
    rebuilt = gym.make(env.spec)
    assert isinstance(rebuilt, RecordEpisode) and rebuilt.flush_every == 1
    rebuilt.close()


class _FakeObserver(gym.Wrapper):
    """Shifts the navigation pose, as an observer's estimate would differ from the truth.

    Only in the step's record (``info["nav_eta"]`` keeps the truth): the recorder reads the
    record."""

    def _shift(self, info):
        rec = info["record"]
        nav = NavigationData(rec.t, rec.truth.eta + np.array([0.5, -0.25, 0.01]), rec.truth.nu)
        info["record"] = rec.with_nav(nav)
        return info

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        return obs, self._shift(info)

    def step(self, action):
        obs, r, te, tr, info = self.env.step(action)
        return obs, r, te, tr, self._shift(info)


def test_estimate_track_is_logged_when_it_differs(tmp_path):
    path = tmp_path / "est.rrd"
    env = RecordEpisode(_FakeObserver(gym.make("shipgym/BlueLadyHarbour-v0")), path)
    env.reset(seed=0)
    for _ in range(10):
        env.step(np.zeros(3, np.float32))
    env.close()
    path = env.paths[0]
    _, rows = read_rrd(path)
    assert len(rows[P.TRACK_EST]["step"]) == 11
    run = load_run(path)
    np.testing.assert_allclose(run.nav_eta - run.eta, np.tile([0.5, -0.25, 0.01], (11, 1)))


def test_report_pngs_have_the_fixed_size(recorded, tmp_path):
    import matplotlib.image as mpimg

    files = write_report(recorded["rrd"], tmp_path / "report", hull_every=30.0)
    assert files == report_paths(tmp_path / "report")
    for f in files:
        assert f.is_file() and f.stat().st_size > 1000, f
    for f in files[:4]:
        h, w = mpimg.imread(f).shape[:2]
        assert (w, h) == pixel_size(f.stem), f
    text = files[4].read_text()
    assert "x_E (m)" in text and "| truth |" in text and "| measurements |" in text


def test_report_from_json_in_a_headless_process(recorded, tmp_path):
    """No display, no MPLBACKEND: the report module itself selects Agg."""
    run_json = tmp_path / "copy.json"
    save_run_json(load_run(recorded["json"]), run_json)
    env = {
        k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MPLBACKEND")
    }
    code = (
        "import sys, shipgym, shipgym.viz as v\n"
        "assert 'rerun' not in sys.modules and 'matplotlib' not in sys.modules\n"
        f"files = v.write_report({str(run_json)!r}, {str(tmp_path / 'r')!r})\n"
        "import matplotlib; print(matplotlib.get_backend(), len(files))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.lower().split() == ["agg", "5"]
    assert all(p.stat().st_size > 0 for p in report_paths(tmp_path / "r"))


def test_load_run_rejects_other_files(tmp_path):
    bad = tmp_path / "x.json"
    bad.write_text('{"hello": 1}')
    with pytest.raises(ValueError, match="not a shipgym run file"):
        load_run(bad)
    with pytest.raises(ValueError, match="does not exist"):
        load_run(tmp_path / "missing.rrd")
    with pytest.raises(ValueError, match="expected a .rrd or .json"):
        (tmp_path / "x.csv").write_text("")
        load_run(tmp_path / "x.csv")


def test_run_json_round_trip_keeps_nan(recorded, tmp_path):
    run = recorded["run"]
    p = save_run_json(run, Path(tmp_path) / "r.json")
    back = load_run(p)
    assert np.isnan(back.accuracy_measured).sum() == np.isnan(run.accuracy_measured).sum()
    np.testing.assert_array_equal(back.eta, run.eta)
    assert back.metrics["J_c"] == pytest.approx(run.metrics["J_c"])


def test_uncaught_interrupt_at_exit_still_leaves_the_file(tmp_path):
    """A script killed by Ctrl-C without close(): the recorder finishes the file at exit."""
    path = tmp_path / "exit.rrd"
    code = (
        "import numpy as np, shipgym\n"
        "from shipgym.viz import RecordEpisode\n"
        "env = RecordEpisode(shipgym.make('harbour', controller='pid'),"
        f" {str(path)!r}, flush_every=1000)\n"
        "env.reset(seed=0)\n"
        "for k in range(100):\n"
        "    if k == 30:\n"
        "        raise KeyboardInterrupt\n"
        "    env.step(np.zeros(3, np.float32))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False
    )
    assert "KeyboardInterrupt" in out.stderr
    assert not path.exists()
    run = load_run(tmp_path / "exit.partial.rrd")
    assert run.n_steps == 30 and recording_problem(run) is not None


def test_report_of_an_unfinished_run_says_its_indices_are_partial(tmp_path):
    from shipgym.runner import run_episode

    res = run_episode(
        "harbour", env_kwargs={"max_episode_steps": 20}, report=tmp_path / "figs"
    )  # 20 s of a 1220 s manoeuvre
    assert res["indices_note"] and not res["completed"]
    text = (tmp_path / "figs" / "metrics.md").read_text()
    assert "These indices do not describe a whole run" in text
    assert "manoeuvre not finished" in text


def test_report_of_a_whole_run_has_no_partial_warning(tmp_path):
    from shipgym.runner import run_episode

    res = run_episode("station-keeping", env_kwargs={"max_episode_steps": 30}, report=tmp_path)
    assert res["indices_note"] is None  # station keeping holds until its time limit
    assert "do not describe a whole run" not in (tmp_path / "metrics.md").read_text()


class _Cut(BaseException):
    """An interrupt landing at a chosen place (a BaseException, as ``KeyboardInterrupt``)."""


@pytest.mark.parametrize("where", ["_log_target", "_log_hull_trace"])
def test_an_interrupt_inside_a_flush_leaves_the_episode_recordable(tmp_path, monkeypatch, where):
    """Ctrl-C or SIGTERM landing inside a flush of the buffered rows, after the running
    accuracy indices took them but before the block was booked: the clean-up's flush sends
    the rows again from the same state (it replayed them into the indices a second time:
    'time went backwards (0.0 s < 98.99 s)', exit 2 instead of the interrupt's status)."""
    from shipgym.viz import recorder

    real = getattr(recorder._Episode, where)
    hit = {"n": 0}

    def cut(self, *args, **kwargs):
        hit["n"] += 1
        if hit["n"] == 1:
            raise _Cut
        return real(self, *args, **kwargs)

    a = np.zeros(3, np.float32)
    env = RecordEpisode(_make(), tmp_path / "cut.rrd", flush_every=50)
    env.reset(seed=0)
    for _ in range(48):
        env.step(a)
    monkeypatch.setattr(recorder._Episode, where, cut)
    with pytest.raises(_Cut):
        env.step(a)  # the 50th row (the reset's the first): the flush
    env.close()  # what the command line's clean-up does: the rows are sent once more
    monkeypatch.undo()
    run = load_run(tmp_path / "cut.partial.rrd")
    assert run.n_steps == 49 and recording_problem(run) is not None
    full = RecordEpisode(_make(), tmp_path / "whole.rrd", flush_every=1000)
    full.reset(seed=0)
    for _ in range(49):
        full.step(a)
    full.close()
    whole = load_run(tmp_path / "whole.partial.rrd")
    # the indices of the cut episode are those of the same rows recorded in one flush
    np.testing.assert_array_equal(run.t, whole.t)  # each row once
    np.testing.assert_array_equal(run.accuracy, whole.accuracy)
    np.testing.assert_array_equal(run.accuracy_measured, whole.accuracy_measured)
