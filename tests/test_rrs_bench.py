"""``shipgym.rrs.bench``: the rudder-roll sweep, its linear analysis and the acceptance runs.

The linear analysis goes through the vessel packages (``roll_model_of``) and must give the
notes' numbers of the seed's model (checks B6, B7); the naval vessel's closed loop must damp
the roll by at least 30 % over the heading autopilot with a heading RMS under 2 deg (seeds
0-4 with ``make test-slow``, seed 0 by default).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from shipgym.rrs.bench import (
    METHODS,
    SEED_CLAIM,
    bench_roll,
    roll_analysis,
    roll_analysis_table,
    roll_run,
    roll_table,
)

D = math.pi / 180.0


def test_the_seed_models_linear_analysis_through_its_package():
    """B6: stable on 2-30 m/s with the sway term, roll ratios 0.172/0.076/0.059; B7: without
    it unstable above 8.75 m/s at about 0.075 rad/s, with it x 0.2 above 15.7 m/s."""
    an = roll_analysis("van-der-klugt", [2.0, 8.0, 13.0, 15.0, 30.0])
    np.testing.assert_allclose(
        an["gain"], [107.74, -5.05, -3.16, -25.07, -29.54], rtol=1e-3, atol=0.01
    )
    assert max(an["margin"][1.0]) < 0 and max(an["margin_scheduled"]) < 0
    np.testing.assert_allclose(an["roll_ratio"][1:4], [0.172, 0.076, 0.059], atol=0.01)
    assert an["onset"][1.0] is None
    s0, w0 = an["onset"][0.0]
    assert s0 == pytest.approx(8.75, abs=0.1) and w0 == pytest.approx(0.075, abs=0.005)
    assert an["onset"][0.2][0] == pytest.approx(15.7, abs=0.1)
    text = roll_analysis_table(an)
    assert "unstable above 8.7" in text and "stable up to 30 m/s" in text
    naval = roll_analysis("naval-vessel", [2.0, 8.0, 20.0])  # its model holds to 10 m/s
    assert naval["speeds"] == [2.0, 8.0] and naval["top"] == 10.0
    assert "not reproducible" in SEED_CLAIM and "one tenth" in SEED_CLAIM


def _rms(vessel, U, method, seed, task, duration=300.0):
    return roll_run((vessel, U, method, seed, duration, task))


def test_without_sway_feedback_the_seed_models_heading_loop_goes_unstable_in_simulation():
    """The seed's narrative on the MuJoCo hull (its sinusoidal rudder, gyro noise, the filter):
    at 13 m/s the roll-damping LQR holds the heading with the sway term and loses it without."""
    full = _rms("van-der-klugt", 13.0, "rrs", 0, "seed-test")
    none = _rms("van-der-klugt", 13.0, "rrs-nosway", 0, "seed-test")
    base = _rms("van-der-klugt", 13.0, "autopilot", 0, "seed-test")
    assert full["heading_rms"] < 0.5 * D and none["heading_rms"] > 5 * D
    assert full["roll_rms"] < 0.2 * base["roll_rms"]  # the roll damped to a fifth or less
    assert full["v_hat_rmse"] < 0.35 * full["v_rms"]
    assert not full["capsized"]


def _naval(seed: int) -> tuple[float, float]:
    base = _rms("naval-vessel", 8.0, "autopilot", seed, "beam-sea", 400.0)
    rrs = _rms("naval-vessel", 8.0, "rrs", seed, "beam-sea", 400.0)
    return 1.0 - rrs["roll_rms"] / base["roll_rms"], rrs["heading_rms"]


def test_naval_vessel_roll_damping_seed_0():
    rrr, heading = _naval(0)
    assert rrr >= 0.30 and heading < 2 * D, (rrr, heading / D)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(5))
def test_naval_vessel_roll_damping_seeds_0_to_4(seed):
    """The issue's acceptance: at 8 m/s in the beam sea, seeds 0-4, roll reduced by >= 30 %
    over the heading autopilot alone, heading RMS under 2 deg."""
    rrr, heading = _naval(seed)
    assert rrr >= 0.30 and heading < 2 * D, (rrr, heading / D)


def test_bench_rows_and_table():
    rows = bench_roll(["van-der-klugt", "naval-vessel"], [8.0, 12.0], 1,
                      methods=["rrs"], duration=150.0, workers=1, progress=False)  # fmt: skip
    # the autopilot is added as the baseline; the naval vessel skips 12 m/s (its limit 10 m/s)
    keys = {(r["vessel"], r["speed"], r["method"]) for r in rows}
    assert keys == {("van-der-klugt", 8.0, "autopilot"), ("van-der-klugt", 8.0, "rrs"),
                    ("van-der-klugt", 12.0, "autopilot"), ("van-der-klugt", 12.0, "rrs"),
                    ("naval-vessel", 8.0, "autopilot"), ("naval-vessel", 8.0, "rrs")}  # fmt: skip
    for r in rows:
        if r["method"] == "autopilot":
            assert r["rrr"] == 0.0
        else:
            assert 0.0 < r["rrr"] < 1.0
    table = roll_table(rows)
    assert table.count("\n") == 1 + len(rows)
    assert "| naval-vessel | 8 | rrs |" in table
    with pytest.raises(ValueError, match="unknown roll method"):
        bench_roll(["van-der-klugt"], [8.0], 1, methods=["pid"])
    with pytest.raises(ValueError, match="no runs"):
        bench_roll(["naval-vessel"], [20.0], 1)
    assert set(METHODS) >= {"autopilot", "rrs", "rrs-nosway", "rrs-sway0.2", "rrs-scheduled"}


def test_roll_pilot_defaults_and_errors():
    from shipgym.controllers.rollpilot import roll_pilot
    from shipgym.dynamics.vessel import load_vessel
    from shipgym.observers.sway import calm_water_intensities

    v = load_vessel("naval-vessel")
    p = roll_pilot(v, 8.0)  # calm-water filter noise by default
    q = calm_water_intensities(v.plant())
    np.testing.assert_allclose(np.diag(p.model.Q_w), q)
    assert p(np.zeros(4), 0.0) == 0.0  # at rest on the heading: no rudder
    auto = roll_pilot(v, 8.0, "autopilot")
    assert auto.gain is None and p.gain is not None
    with pytest.raises(ValueError, match="roll_control"):
        roll_pilot(load_vessel("blue-lady"), 8.0)
