"""Recordings and reports of every vessel: thrust arrows, series and names from its actuators.

Each packaged vessel and a 4-DOF user package (written to a temporary folder) keeps station
for 60 s (``pid`` on the ``kbf`` estimate) under :class:`~shipgym.viz.RecordEpisode`; the
recording is read back with rerun's reader and through ``shipgym report``. The expected
arrows are computed here from the ``info`` values (thrust, actuator states) and the vessel
file's mounting angles, not by the viz code.
"""

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from _helpers import read_rrd

import shipgym
from shipgym.cli import main as cli_main
from shipgym.dynamics.actuators import Azimuth, Propeller
from shipgym.dynamics.vessel import load_vessel, vessel_names
from shipgym.viz import RecordEpisode, load_run, pixel_size, report_paths, save_run_json
from shipgym.viz.geometry import REFERENCE_LENGTH, hull_outline
from shipgym.viz.recorder import THRUST_ARROW_LENGTH
from shipgym.viz.run import P, command_path

sys.path.insert(0, str(Path(__file__).parent))
from test_vessel_library import HULL4_TOML, write_package  # noqa: E402

DURATION = 60.0  # s of station keeping per vessel
USER = "user-hull4"  # the 4-DOF package written by the test
#: the vessels that can keep station (a rudder-steered ship cannot)
POSITIONING = [n for n in vessel_names() if load_vessel(n).can_position]
VESSELS = [*POSITIONING, USER]
#: the vessels with azimuth thrusters (the user package has one)
AZIMUTH_VESSELS = [n for n in POSITIONING if not load_vessel(n).actuators.fixed] + [USER]


def _by_step(rows, column):
    order = np.argsort(rows["step"], kind="stable")
    return [rows[column][i] for i in order]


@pytest.fixture(scope="module")
def package(tmp_path_factory):
    return write_package(tmp_path_factory.mktemp("pkg") / "hull4", HULL4_TOML)


@pytest.fixture(scope="module")
def recordings(tmp_path_factory, package):
    out = tmp_path_factory.mktemp("rec")
    done = {}
    for name in VESSELS:
        vessel = str(package) if name == USER else name
        env = shipgym.make(
            "shipgym/StationKeeping-v0", vessel=vessel, controller="pid", observer="kbf"
        )
        steps = int(round(DURATION / env.unwrapped.control_period))
        env.close()
        env = RecordEpisode(
            shipgym.make(
                "shipgym/StationKeeping-v0",
                vessel=vessel,
                controller="pid",
                observer="kbf",
                max_episode_steps=steps,
            ),
            out / f"{name}.rrd",
            json_path=out / f"{name}.json",
        )
        _, info = env.reset(seed=0)
        infos = [info]
        while True:
            _, _, terminated, truncated, info = env.step(np.zeros(env.action_space.shape))
            infos.append(info)
            if terminated or truncated:
                break
        v = env.unwrapped.vessel
        model = env.unwrapped.physics.model
        env.close()
        done[name] = {
            "rrd": out / f"{name}.rrd",
            "json": out / f"{name}.json",
            "infos": infos,
            "vessel": v,
            "model": model,
        }
    return done


def _expected_arrows(vessel, infos):
    """Arrows (steps, actuators, 2) from the info thrust and states and the vessel file."""
    length = THRUST_ARROW_LENGTH * vessel.L_oa / REFERENCE_LENGTH
    acts = vessel.actuators
    out = np.zeros((len(infos), len(acts), 2))
    for k, info in enumerate(infos):
        thrust = np.asarray(info["thrust"])
        state = np.asarray(info["actuator_state"])
        for i, (a, sl) in enumerate(zip(acts, acts.slices, strict=True)):
            if isinstance(a, Azimuth):
                angle = state[sl][1]
            else:
                assert isinstance(a, Propeller)
                angle = a.alpha
            out[k, i] = thrust[i] / a.max_thrust * length * np.array([math.cos(angle),
                                                                      math.sin(angle)])  # fmt: skip
    return out


@pytest.mark.parametrize("name", VESSELS)
def test_arrows_follow_the_actuators(recordings, name):
    r = recordings[name]
    vessel, infos = r["vessel"], r["infos"]
    acts = vessel.actuators
    static, rows = read_rrd(r["rrd"])
    # one arrow per actuator, named and coloured as in the vessel file, at its position
    assert static[P.THRUST]["Arrows2D:labels"] == list(acts.names)
    colours = [f"#{c >> 24:02x}{(c >> 16) & 255:02x}{(c >> 8) & 255:02x}"
               for c in static[P.THRUST]["Arrows2D:colors"]]  # fmt: skip
    assert colours == [c.lower() for c in acts.colours]
    vectors = _by_step(rows[P.THRUST], "Arrows2D:vectors")
    origins = _by_step(rows[P.THRUST], "Arrows2D:origins")
    assert len(vectors) == len(infos)
    assert all(len(v) == len(acts) for v in vectors)
    pos = np.array([a.position[:2] for a in acts])
    np.testing.assert_allclose(np.array(origins[-1]), pos, atol=1e-5)
    got = np.array(vectors, dtype=float)
    want = _expected_arrows(vessel, infos)
    scale = THRUST_ARROW_LENGTH * vessel.L_oa / REFERENCE_LENGTH
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6 * scale)
    assert np.abs(got).max() > 1e-3 * scale, "the controller used its actuators"
    assert np.linalg.norm(got, axis=-1).max() <= scale * (1 + 1e-6)


@pytest.mark.parametrize("name", AZIMUTH_VESSELS)
def test_azimuth_arrows_turn_with_the_angle(recordings, name):
    """The arrow of an azimuth points along its angle state (or against it, thrust < 0)."""
    r = recordings[name]
    acts = r["vessel"].actuators
    _, rows = read_rrd(r["rrd"])
    got = np.array(_by_step(rows[P.THRUST], "Arrows2D:vectors"), dtype=float)
    states = np.array([i["actuator_state"] for i in r["infos"]])
    thrust = np.array([i["thrust"] for i in r["infos"]])
    n_az = 0
    for i, (a, sl) in enumerate(zip(acts, acts.slices, strict=True)):
        if not isinstance(a, Azimuth):
            continue
        n_az += 1
        angle = states[:, sl.start + 1]
        on = np.abs(thrust[:, i]) > 1e-3 * a.max_thrust
        assert on.sum() > 10
        drawn = np.arctan2(got[on, i, 1], got[on, i, 0])
        expected = angle[on] + np.where(thrust[on, i] < 0, math.pi, 0.0)
        diff = (drawn - expected + math.pi) % (2 * math.pi) - math.pi
        np.testing.assert_allclose(diff, 0.0, atol=1e-4)
        # the check above covers several directions: the angle turned in these 60 s, or the
        # thrust reversed (the allocation's turning cost holds the angles when it can)
        f = thrust[on, i]
        assert np.ptp(angle) > math.radians(5.0) or (f.max() > 0 > f.min())
    assert n_az >= 1


@pytest.mark.parametrize("name", VESSELS)
def test_thrust_and_command_series_are_named_by_the_vessel(recordings, name):
    r = recordings[name]
    acts = r["vessel"].actuators
    static, rows = read_rrd(r["rrd"])
    assert static[P.PLOT_THRUST]["SeriesLines:names"] == [f"{n} (N)" for n in acts.names]
    thrust = np.array(_by_step(rows[P.PLOT_THRUST], "Scalars:scalars"), dtype=float)
    np.testing.assert_allclose(thrust, [i["thrust"] for i in r["infos"]], rtol=1e-6)
    # one command plot per unit, its series the channels of that unit, in order
    units = list(dict.fromkeys(acts.units))
    plots = sorted(e for e in static if e.startswith(P.COMMAND + "/"))
    assert plots == sorted(command_path(u) for u in units)
    command = np.array([i["command"] for i in r["infos"]])
    seen = []
    for u in units:
        cols = [j for j, cu in enumerate(acts.units) if cu == u]
        names = static[command_path(u)]["SeriesLines:names"]
        assert names == [f"{acts.channel_names[j]} ({u})" for j in cols]
        vals = np.array(_by_step(rows[command_path(u)], "Scalars:scalars"), dtype=float)
        np.testing.assert_allclose(vals.reshape(len(command), -1), command[:, cols], rtol=1e-6)
        seen += cols
    assert sorted(seen) == list(range(acts.n_channels))


def test_blue_lady_keeps_its_two_command_plots(recordings):
    static, _ = read_rrd(recordings["blue-lady"]["rrd"])
    assert static[command_path("rpm")]["SeriesLines:names"] == ["main_propeller (rpm)"]
    assert static[command_path("1")]["SeriesLines:names"] == ["bow_tunnel (1)", "stern_tunnel (1)"]


@pytest.mark.parametrize("name", VESSELS)
def test_run_files_carry_the_actuators(recordings, name, tmp_path):
    r = recordings[name]
    acts = r["vessel"].actuators
    for src in ("rrd", "json"):
        run = load_run(r[src])
        assert run.actuator_names == list(acts.names)
        assert run.channel_names == list(acts.channel_names)
        assert run.actuators["colours"] == list(acts.colours)
        assert run.actuators["units"] == list(acts.units)
        assert run.vessel["title"] == r["vessel"].title
        assert run.command.shape == (len(r["infos"]), acts.n_channels)
        assert run.saturated.shape == (len(r["infos"]), acts.n_channels)
        assert run.thrust.shape == (len(r["infos"]), len(acts))
        np.testing.assert_array_equal(
            run.actuator_state, np.array([i["actuator_state"] for i in r["infos"]])
        )
        np.testing.assert_allclose(run.thrusters, [a.position[:2] for a in acts])
        if r["vessel"].dofs == 4:
            np.testing.assert_array_equal(
                run.roll, np.array([[i["phi"], i["p"]] for i in r["infos"]])
            )
        else:
            assert run.roll.shape == (0, 2)
    copy = save_run_json(load_run(r["rrd"]), tmp_path / "copy.json")
    assert load_run(copy).actuator_names == list(acts.names)


@pytest.mark.parametrize("name", VESSELS)
def test_shipgym_report_works_for_every_vessel(recordings, name, tmp_path, capsys):
    r = recordings[name]
    out = tmp_path / "report"
    assert cli_main(["report", str(r["rrd"]), "--out", str(out)]) == 0
    from PIL import Image

    for p in report_paths(out):
        assert p.is_file() and p.stat().st_size > 0, p
        if p.suffix == ".png":
            with Image.open(p) as im:
                assert im.size == pixel_size(p.stem)
    md = (out / "metrics.md").read_text()
    assert r["vessel"].title in md
    for a in r["vessel"].actuators.names:
        assert f"| {a.replace('_', ' ')} |" in md


def test_hull_outlines_come_from_the_vessel_geometry(recordings):
    # the user package's hull is a 80 m x 12 m box: its outline is that rectangle
    o = hull_outline(recordings[USER]["model"])
    np.testing.assert_allclose(np.sort(np.unique(o[:, 0])), [-40.0, 40.0], atol=1e-6)
    np.testing.assert_allclose(np.sort(np.unique(o[:, 1])), [-6.0, 6.0], atol=1e-6)
    assert len(o) == 4
    # the packaged vessels: the outline spans the documented length and breadth
    for name in POSITIONING:
        v = recordings[name]["vessel"]
        o = hull_outline(recordings[name]["model"])
        assert np.ptp(o[:, 0]) == pytest.approx(v.L_oa, rel=0.05), name
        assert np.ptp(o[:, 1]) == pytest.approx(v.B, rel=0.05), name
    # the Blue Lady's mesh: Tomera (2014) L_oa 13.78 m, B 2.38 m, bow at x = +6.89 m
    o = hull_outline(recordings["blue-lady"]["model"])
    assert o[:, 0].max() == pytest.approx(6.89, abs=1e-3)
    assert o[:, 0].min() == pytest.approx(-6.89, abs=1e-3)
    assert np.ptp(o[:, 1]) == pytest.approx(2.38, abs=1e-3)


def test_runs_recorded_before_the_actuator_names_read_as_the_blue_lady(recordings, tmp_path):
    """A JSON run file of an earlier version (no actuators, vessel, states) still loads."""
    doc = json.loads(recordings["blue-lady"]["json"].read_text())
    for key in ("actuators", "vessel"):
        doc.pop(key)
    doc["arrays"].pop("actuator_state")
    doc["arrays"].pop("roll")
    old = tmp_path / "old.json"
    old.write_text(json.dumps(doc))
    run = load_run(old)
    assert run.actuator_names == list(load_vessel("blue-lady").actuators.names)
    assert run.vessel_title == "Blue Lady"
    assert np.isnan(run.actuator_state).all() and run.actuator_state.shape == (len(run.t), 3)
    assert cli_main(["report", str(old), "--out", str(tmp_path / "r")]) == 0


def test_recording_a_non_shipgym_env_is_refused(tmp_path):
    import gymnasium as gym

    env = RecordEpisode(gym.make("CartPole-v1"), tmp_path / "x.rrd")
    with pytest.raises(ValueError, match="shipgym environment"):
        env.reset(seed=0)


def test_observer_comparison_names_the_vessel(tmp_path):
    from shipgym.viz import write_observer_report

    idx = {"x_E": 1.0, "y_E": 2.0, "psi_E": 3.0, "J_c": 3.03}
    rows = [{"observer": o, "measured": idx, "truth": idx} for o in ("kbf", "ekf")]
    t = np.arange(5.0)
    traces = {o: {"t": t, "err_nu": np.zeros((5, 3))} for o in ("kbf", "ekf")}
    files = write_observer_report(
        rows, traces, tmp_path, vessel="Wimpey Sealab (drill ship)", task="station keeping"
    )
    assert [f.name for f in files] == ["observers_indices.png", "observers_velocity_errors.png"]
    assert all(f.stat().st_size > 0 for f in files)
