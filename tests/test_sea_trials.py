"""Sea trials on the MuJoCo hull (Artyszuk 2003; IMO MSC.137(76)): the KVLCC2 scaled to 100 m
against the notes' independent computation from the MMG paper (C4, C5), the L7 model at the
paper's scale, the DGPS receiver's bias on the simulated trials (C6-C9), the current's effect
against the geometry (C10), the env and the ``shipgym trials`` command."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time

import gymnasium as gym
import numpy as np
import pytest

import shipgym  # noqa: F401  (registers the ids)
from shipgym.envs.seatrial import SeaTrialEnv, run_trial, trial_study
from shipgym.trials.bias import receiver_bias

D = math.pi / 180.0


@pytest.fixture(scope="module")
def trials():
    """The 100 m tanker's trials, flown once by the MuJoCo hull (0.05 s physics step)."""
    names = ("turning35_stbd", "zigzag10", "zigzag20", "crash_stop", "initial_turning")
    return {m: run_trial("kvlcc2-100m", m) for m in names}


def test_C4_turning_circle_on_the_mujoco_hull(trials):
    """Advance 3.37 L and tactical diameter 3.14 L (+-0.05 L); 90 deg at 66 s, steady speed
    2.68 m/s (the notes' integration of the same equations)."""
    rec = trials["turning35_stbd"]
    m = rec.metrics()
    assert m.advance / rec.L == pytest.approx(3.37, abs=0.05)
    assert m.tactical_diameter / rec.L == pytest.approx(3.14, abs=0.05)
    assert m.transfer / rec.L == pytest.approx(1.35, abs=0.05)
    assert m.time_90 == pytest.approx(66.0, abs=1.0)
    assert m.steady_speed == pytest.approx(2.68, abs=0.03)
    assert rec.eta[-1, 2] > 2 * math.pi  # turned to starboard (psi grows)
    assert max(abs(rec.rudder)) == pytest.approx(35 * D, abs=1e-9)  # never past its limit


def test_C5_zigzag_overshoots_on_the_mujoco_hull(trials):
    ov10 = trials["zigzag10"].metrics().overshoots
    ov20 = trials["zigzag20"].metrics().overshoots
    assert ov10[0] / D == pytest.approx(7.4, abs=0.5)
    assert ov20[0] / D == pytest.approx(18.3, abs=0.5)
    assert ov10[1] / D == pytest.approx(18.2, abs=0.5)


def test_every_imo_criterion_passes(trials):
    for m, rec in trials.items():
        crit = rec.criteria()
        assert crit, m
        assert all(c[3] for c in crit), (m, crit)
    assert trials["initial_turning"].metrics().initial_turning_distance / 100 == pytest.approx(
        1.87, abs=0.05
    )


@pytest.mark.parametrize(("name", "advance", "tactical"), [
    ("turning35_stbd", 3.08, 3.12), ("turning35_port", 3.09, 3.10),
])  # fmt: skip
def test_the_L7_model_at_the_papers_scale(name, advance, tactical):
    """KVLCC2 L7 at 1.179 m/s, rudder 15.8 deg/s: the notes' 3.08 / 3.12 L (starboard) and
    3.09 / 3.10 L (port)."""
    rec = run_trial("kvlcc2-l7", name, timestep=0.02)
    m = rec.metrics()
    assert m.advance / rec.L == pytest.approx(advance, abs=0.05)
    assert m.tactical_diameter / rec.L == pytest.approx(tactical, abs=0.05)


# ---- the DGPS receiver on the simulated trials (Artyszuk 2003) ----------------------------
def _bias(rec, S_p, runs=30):
    return receiver_bias(rec.t, rec.eta, rec.nu, S_p=S_p, runs=runs, seed=1)


def test_C6_C7_C8_turning_bias(trials):
    """S_p 0.01: drift-angle bias +8..+12 deg, speed bias +0.25..+0.6 m/s, position < 5 m;
    S_p 0.001: position bias 7-13 m ("even 10 m"); S_p 0.1: smaller bias, > 2x the noise."""
    rec = trials["turning35_stbd"]
    b1, b2, b3 = (_bias(rec, s) for s in (0.001, 0.01, 0.1))
    assert 8 * D <= b2.drift_bias_max <= 12 * D
    assert 0.25 <= b2.speed_bias_max <= 0.6
    assert b2.position_bias_max < 5.0
    assert 7.0 <= b1.position_bias_max <= 13.0
    assert b3.drift_bias_max < b2.drift_bias_max and b3.speed_bias_max < b2.speed_bias_max
    assert b3.position_bias_max < b2.position_bias_max
    assert b3.sigma_v > 2 * b2.sigma_v


def test_C9_crash_stop_speed_bias(trials):
    rec = trials["crash_stop"]
    k = int(np.argmax(rec.nu[:, 0] <= 0.0)) + 1  # up to the stop
    b = receiver_bias(rec.t[:k], rec.eta[:k], rec.nu[:k], S_p=0.01, runs=10)
    assert b.speed_bias_max > 0.3


def test_C10_current_shifts_the_drift_angle_as_the_geometry_says():
    """A uniform current moves the hull with the water (the MuJoCo hull feels only the
    velocity through the water): the ground-referenced velocity of the turn in a 0.25 m/s
    current is the no-current turn's plus the current, at the same headings, and the drift
    angle over ground shifts by up to atan(0.25 / 2.68) = 5.3 deg in the steady turn."""
    calm = run_trial("kvlcc2-100m", "turning35_stbd", record_period=0.5)
    vc, bc = 0.25, math.radians(225.0)  # going south-west: the seed's south and west current
    cur = run_trial("kvlcc2-100m", "turning35_stbd", current="0.25@225", record_period=0.5)
    np.testing.assert_allclose(cur.eta[:, 2], calm.eta[:, 2], atol=1e-6)  # same headings
    psi = calm.eta[:, 2]
    uc = vc * np.cos(bc - psi)
    vcb = vc * np.sin(bc - psi)
    np.testing.assert_allclose(cur.nu[:, 0], calm.nu[:, 0] + uc, atol=1e-6)
    np.testing.assert_allclose(cur.nu[:, 1], calm.nu[:, 1] + vcb, atol=1e-6)
    drift = lambda nu: np.arctan2(-nu[:, 1], nu[:, 0])  # noqa: E731
    steady = calm.t > 300.0
    shift = np.degrees(drift(cur.nu) - drift(calm.nu))[steady]
    assert np.max(np.abs(shift)) == pytest.approx(math.degrees(math.atan(0.25 / 2.68)), abs=0.6)
    # the track drifts with the current: 0.25 m/s over the record, to the south-west
    d = cur.eta[-1, :2] - calm.eta[-1, :2]
    np.testing.assert_allclose(d, vc * cur.t[-1] * np.array([math.cos(bc), math.sin(bc)]),
                               atol=1e-3)  # fmt: skip


def test_the_water_referenced_track_is_the_calm_water_trial(tmp_path):
    """The ITTC way with a current: the track less the current's drift and the velocity
    through the water give back the calm-water trial (the hull feels only the water), its
    velocities equal the seed's correction (observers.dgps.water_velocity, written apart),
    and ``trial_current.png`` draws both tracks and both drift angles (the seed's Fig. 1)."""
    from shipgym.observers.dgps import water_velocity
    from shipgym.viz.trials import write_trial_figures

    calm = run_trial("kvlcc2-100m", "turning35_stbd", record_period=0.5)
    cur = run_trial("kvlcc2-100m", "turning35_stbd", current="0.25@225", record_period=0.5)
    w = cur.water_referenced()
    assert w.current == (0.0, 0.0) and calm.water_referenced() is calm
    np.testing.assert_allclose(w.eta, calm.eta, atol=1e-6)
    np.testing.assert_allclose(w.nu, calm.nu, atol=1e-6)
    seed = water_velocity(cur.nu[:, :2], cur.eta[:, 2], 0.25, math.radians(225.0))
    np.testing.assert_allclose(w.nu[:, :2], seed, atol=1e-12)
    assert w.metrics().advance / w.L == pytest.approx(3.37, abs=0.05)
    assert abs(cur.metrics().tactical_diameter - w.metrics().tactical_diameter) > 5.0
    study = trial_study("kvlcc2-100m", ["turning35_stbd"], current="0.25@225")
    assert [r["reference"] for r in study.rows] == ["ground", "water"]
    paths = write_trial_figures(study, tmp_path, title="t")
    assert str(tmp_path / "trial_current.png") in paths


# ---- the env --------------------------------------------------------------------------------
def test_the_registered_trial_is_the_tankers_turn_and_reports_the_figures():
    env = gym.make("shipgym/SeaTrial-v0", receiver="dgps-pv")
    obs, info = env.reset(seed=0)
    assert env.unwrapped.base_vessel.name == "kvlcc2-100m" and obs.shape == (13,)
    done, n = False, 0
    betas = []
    while not done:
        obs, r, term, trunc, info = env.step(0)
        done = term or trunc
        n += 1
        assert r == 0.0 and info["reward_terms"] == {}
        betas.append((info["drift"], info["receiver"]["beta_A"]))
    assert info["trial"]["advance"] / 100 == pytest.approx(3.37, abs=0.05)
    assert info["episode_metrics"]["imo_pass"] is True
    assert n == env.unwrapped.max_steps
    b = np.array(betas)
    assert np.max(b[:, 1] - b[:, 0]) > 4 * D  # the receiver's drift angle lags high
    env.close()


def test_stops_need_a_main_propeller_and_bad_input_is_named():
    with pytest.raises(ValueError, match="needs a main propeller"):
        SeaTrialEnv("van-der-klugt", "crash_stop")
    with pytest.raises(ValueError, match="unknown manoeuvre|choose"):
        SeaTrialEnv("kvlcc2-100m", "figure_eight")
    with pytest.raises(ValueError, match="unknown receiver"):
        SeaTrialEnv("kvlcc2-100m", receiver="gps")
    with pytest.raises(ValueError, match="has no rudder"):
        SeaTrialEnv("blue-lady")
    env = SeaTrialEnv("kvlcc2-100m")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="actions? must be (the int )?0"):
        env.step(1)
    env = SeaTrialEnv("kvlcc2-100m", override=True)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="finite numbers"):
        env.step(np.array([np.nan, 0.0]))
    _, _, _, _, info = env.step(np.array([1.0, 1.5]))
    assert info["clipped"]


def test_override_flies_the_same_trial_as_the_script():
    """A controller that sends the script's commands through the action gets the script's
    figures (the override path is the same physics)."""
    env = SeaTrialEnv("kvlcc2-100m", "turning35_stbd", override=True, control_period=0.05)
    acts = env.physics.actuators
    env.reset(seed=0)
    done = False
    while not done:
        cmd = np.array([env.n0, -35 * D])
        _, _, done, _, info = env.step(acts.command_to_action(cmd))
    ref = run_trial("kvlcc2-100m", "turning35_stbd").metrics()
    assert info["trial"]["advance"] == pytest.approx(ref.advance, rel=1e-9)


def test_trial_study_with_current_correction():
    """The seed's correction removes the current from the receiver's drift angle: with it the
    bias on the current's turn equals the no-current bias."""
    calm = trial_study("kvlcc2-100m", ["turning35_stbd"], receiver="dgps-pv", S_p=[0.01], runs=4)
    cur = trial_study("kvlcc2-100m", ["turning35_stbd"], receiver="dgps-pv", S_p=[0.01], runs=4,
                      current="0.25@225")  # fmt: skip
    b0 = calm.bias[("turning35_stbd", 0.01, False)]
    bc = cur.bias[("turning35_stbd", 0.01, True)]
    bg = cur.bias[("turning35_stbd", 0.01, False)]
    assert bc.drift_bias_max == pytest.approx(b0.drift_bias_max, abs=0.05 * D)
    assert abs(bg.drift_bias_max - b0.drift_bias_max) > 0.2 * D  # uncorrected: it differs


@pytest.mark.slow
def test_shipgym_trials_runs_every_manoeuvre_and_three_S_p_in_under_5_minutes(tmp_path):
    t0 = time.perf_counter()
    out = subprocess.run(
        [sys.executable, "-m", "shipgym.cli", "trials", "--receiver", "dgps-pv", "--sp",
         "0.001,0.01,0.1", "--json", str(tmp_path / "t.json"), "--figures", str(tmp_path),
         "--no-progress"],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    wall = time.perf_counter() - t0
    assert wall < 300.0
    data = json.loads((tmp_path / "t.json").read_text())
    assert len(data["trials"]) == 8 and len(data["bias"]) == 8  # every manoeuvre
    assert all(len(b) == 4 for b in data["bias"].values())  # three S_p and raw
    assert all(r["ground"]["imo_pass"] in (True, None) for r in data["trials"].values())
    assert "FAIL" not in out.stdout
    assert (tmp_path / "bias_turning35_stbd.png").is_file()


def test_the_half_ahead_65_deg_schilling_turn_gives_the_seeds_bias():
    """The seed's largest bias (its Fig. 3: half ahead, a 65 deg Schilling rudder, S_p 0.01:
    "of order 0.5 m/s ... and 10 deg"): the tanker with the Schilling option (no stall to 70
    deg, 65 deg rudder) approaching at the steady speed of the half-ahead command (0.85 n0:
    5.95 m/s, linear in n for this hull) gives a speed bias of 0.4-0.6 m/s and a drift-angle
    bias of 8-12 deg."""
    from shipgym.trials.manoeuvres import HALF_AHEAD, manoeuvre

    m = manoeuvre("turning65_half_ahead")
    assert (m.angle, m.side, m.shaft, m.rudder) == (65 * D, 1, HALF_AHEAD, "schilling")
    rec = run_trial("kvlcc2-100m", "turning65_half_ahead")
    assert rec.U0 == pytest.approx(HALF_AHEAD * 7.0, rel=1e-6)  # n proportional to U (MMG)
    assert rec.n0 == pytest.approx(HALF_AHEAD * 4.9256, rel=1e-4)
    assert rec.nu[0, 0] == pytest.approx(rec.U0)  # it starts at the half-ahead speed
    assert max(abs(rec.rudder)) == pytest.approx(65 * D, abs=1e-9)  # the option's limit
    assert rec.eta[-1, 2] > 2 * math.pi  # a starboard turn
    met = rec.metrics()
    assert met.tactical_diameter / rec.L == pytest.approx(2.12, abs=0.05)  # 3.14 L at 35 deg
    b = receiver_bias(rec.t, rec.eta, rec.nu, S_p=0.01, runs=4)
    assert 0.4 <= b.speed_bias_max <= 0.6, b.speed_bias_max
    assert 8 * D <= b.drift_bias_max <= 12 * D, b.drift_bias_max / D
    assert (b.speed_bias_max, b.drift_bias_max / D) == pytest.approx((0.467, 8.89), abs=0.01)
    # the lag model: the drift-angle bias about tau r_max (notes 3.2, tau 5.85 s)
    assert b.drift_bias_max == pytest.approx(5.85 * rec.nu[:, 2].max(), rel=0.2)
    # the MMG rudder at the same 65 deg is weaker (lower slope); the Schilling's own 0.5 n0
    # (3.5 m/s) turn is slower: the bias scales with the approach speed
    from shipgym.trials.manoeuvres import MANOEUVRES, TurningCircle

    MANOEUVRES["_hah_half"] = TurningCircle("_hah_half", 65 * D, 1, shaft=0.5,
                                            rudder="schilling")  # fmt: skip
    try:
        slow = run_trial("kvlcc2-100m", "_hah_half")
    finally:
        del MANOEUVRES["_hah_half"]
    bs = receiver_bias(slow.t, slow.eta, slow.nu, S_p=0.01, runs=4)
    assert slow.U0 == pytest.approx(3.5, rel=1e-6)
    assert bs.speed_bias_max < 0.2 and bs.drift_bias_max < 6 * D


def test_crash_stop_ends_to_starboard_and_coasting_stop_to_port():
    """Artyszuk (2003) section 3: the crash stop (full astern) "alters the course to starboard
    due to the propeller lateral thrust", the coasting stop (zero pitch) "turns to port for the
    same reasons": the vessel's default side force (c_y 0.1 astern, c_y_brake 0.05 braking).
    The approach track is the x axis (north), starboard is y > 0."""
    crash = run_trial("kvlcc2-100m", "crash_stop")
    coast = run_trial("kvlcc2-100m", "coasting_stop")
    k = int(np.argmax(crash.nu[:, 0] <= 0.0))  # the crash stop ends at the stop (u = 0)
    assert crash.eta[k, 1] > 20.0 and crash.eta[k, 2] > 30 * D  # 27 m, 43 deg to starboard
    # (passing zero pitch the braking push sets it a few centimetres to port first)
    assert crash.eta[: k + 1, 1].min() > -0.1
    cm = crash.metrics()
    assert cm.lateral_deviation == pytest.approx(crash.eta[k, 1], abs=0.5)
    assert cm.heading_change_at_stop > 30 * D
    assert all(c[3] for c in crash.criteria())  # track reach still within 15 L
    # the coasting stop ends at 2 m/s: 101 m and 19 deg to port, and keeps turning
    sm = coast.metrics()
    assert sm.lateral_deviation < -50.0 and sm.heading_change_at_stop < -10 * D
    assert coast.eta[:, 1].max() < 0.01 and coast.eta[-1, 2] < -90 * D


def test_raw_positions_differentiated_are_unbiased_but_noisy(trials):
    """The seed's recommendation: the raw 1 Hz positions differentiated (central differences)
    have no lag, so no bias to speak of on the turn, and the noise of a difference of two
    2 m fixes over 2 s: sigma / sqrt(2) = 1.41 m/s per axis."""
    rec = trials["turning35_stbd"]
    raw = receiver_bias(rec.t, rec.eta, rec.nu, S_p=0.01, runs=40, seed=2, method="raw")
    kf = _bias(rec, 0.01)
    assert abs(raw.speed_bias_max) < 0.05 and abs(raw.drift_bias_max) < 1.0 * D
    assert raw.position_bias_max < 1e-9  # the raw fixes are the positions
    assert raw.sigma_v == pytest.approx(2.0 / math.sqrt(2.0), rel=0.05)
    assert raw.sigma_v > 10 * kf.sigma_v
    with pytest.raises(ValueError, match="unknown method"):
        receiver_bias(rec.t, rec.eta, rec.nu, S_p=0.01, method="smoothed")


@pytest.mark.parametrize("env_id", ["shipgym/SeaTrial-v0", "shipgym/CourseKeeping-v0"])
def test_shipgym_run_points_a_steering_task_to_trials(env_id, capsys):
    from shipgym.cli import main

    assert main(["run", env_id, "--vessel", "kvlcc2-100m", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "steering task" in err and "shipgym trials" in err and err.count("\n") == 1


def test_shipgym_trials_json_is_keyed_with_units_and_meets_the_seeds_cases(tmp_path):
    """``shipgym trials --json`` (schema 2): the trials keyed by manoeuvre, the bias by
    manoeuvre, filter and reference; every number under a key with its unit (degrees for
    angles, no radians under a unitless key), no bare lists. Its numbers are the acceptance:
    the half-ahead 65 deg Schilling turn's bias (S_p 0.01) 0.4-0.6 m/s and 8-12 deg, the crash
    stop to starboard, the coasting stop to port; with a current, the water-referenced rows."""
    from shipgym.cli import main
    from shipgym.trials.report import DIMENSIONLESS, UNIT_SUFFIXES

    path = tmp_path / "t.json"
    assert main(["trials", "--manoeuvres", "turning65_half_ahead,crash_stop,coasting_stop",
                 "--receiver", "dgps-pv", "--sp", "0.01", "--runs", "4", "--json", str(path),
                 "--no-progress"]) == 0  # fmt: skip
    data = json.loads(path.read_text())
    assert data["schema_version"] == 2 and data["units"]["suffixes"] == UNIT_SUFFIXES
    assert list(data["trials"]) == ["turning65_half_ahead", "crash_stop", "coasting_stop"]
    hah = data["bias"]["turning65_half_ahead"]["S_p=0.01"]["ground"]
    assert 0.4 <= hah["speed_bias_max_m_per_s"] <= 0.6
    assert 8.0 <= hah["drift_bias_max_deg"] <= 12.0
    assert hah["S_p_m2_per_s3"] == 0.01 and "raw" in data["bias"]["turning65_half_ahead"]
    t = {m: r["ground"] for m, r in data["trials"].items()}
    assert all(list(r) == ["ground"] for r in data["trials"].values())  # no current
    assert t["turning65_half_ahead"]["U0_m_per_s"] == pytest.approx(5.95, abs=0.01)
    assert t["turning65_half_ahead"]["rudder_angle_deg"] == pytest.approx(65.0)
    assert t["crash_stop"]["lateral_deviation_m"] > 10.0  # to starboard
    assert t["crash_stop"]["heading_change_at_stop_deg"] > 30.0
    assert t["coasting_stop"]["lateral_deviation_m"] < -50.0  # to port
    assert t["coasting_stop"]["heading_change_at_stop_deg"] < -10.0

    def has_unit(k):
        return any(k.endswith(s) for s in UNIT_SUFFIXES)

    def check(x, where="", inherited=False):  # a key's unit holds for the keys under it
        assert not isinstance(x, list), f"a bare list at {where}"
        if isinstance(x, dict):
            for k, v in x.items():
                if isinstance(v, int | float) and not isinstance(v, bool):
                    ok = inherited or has_unit(k) or k in DIMENSIONLESS
                    assert ok, f"{where}/{k} has no unit"
                check(v, f"{where}/{k}", inherited or has_unit(k))

    check({k: data[k] for k in ("trials", "bias")})
    # with a current: ground- and water-referenced rows (the seed's correction)
    assert main(["trials", "--manoeuvres", "turning35_stbd", "--receiver", "dgps-pv", "--sp",
                 "0.01", "--runs", "2", "--current", "0.25@225", "--json", str(path),
                 "--no-progress"]) == 0  # fmt: skip
    data = json.loads(path.read_text())
    b = data["bias"]["turning35_stbd"]["S_p=0.01"]
    assert set(b) == {"ground", "water"}
    assert b["water"]["current"] == {"speed_m_per_s": 0.25, "direction_to_deg": 225.0}
    # the IMO figures of the water-referenced track (the ITTC way) next to the ground track's:
    # through the water the turn is the calm-water one (advance 3.37 L, tactical 3.14 L)
    tr = data["trials"]["turning35_stbd"]
    assert tr["water"]["reference"] == "water"
    assert tr["water"]["advance_m"] == pytest.approx(337.2, abs=0.5)
    assert tr["water"]["tactical_diameter_m"] == pytest.approx(313.6, abs=0.5)
    assert abs(tr["ground"]["tactical_diameter_m"] - tr["water"]["tactical_diameter_m"]) > 5.0


def test_shipgym_trials_names_bad_input(capsys):
    from shipgym.cli import main

    for argv, text in ((["--manoeuvres", "loop"], "unknown manoeuvre"),
                       (["--sp", "0,1"], "--sp must be positive"),
                       (["--antenna", "1"], "--antenna must be X,Y"),
                       (["--vessel", "blue-lady"], "has no rudder")):  # fmt: skip
        assert main(["trials", *argv, "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert text in err and err.count("\n") == 1, err
