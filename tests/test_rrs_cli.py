"""``shipgym bench roll`` and its figures (:mod:`shipgym.viz.rrs`).

The numbers checked come from outside the command: the notes' computed acceptance values of
seed 003 (the fixed LQR of 8 m/s: roll ratio 0.172 at 8 m/s; without the sway term unstable
above 8.75 m/s, with it x 0.2 above 15.7 m/s), the vessels' own limits, and the rows' own
RMS values against the printed table.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from shipgym.cli import _speed_list, main
from shipgym.rrs.bench import SEED_CLAIM

FAST = ["--duration", "150", "--seeds", "1", "--workers", "1", "--no-progress"]


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    """One small bench: both vessels at 8 and 12 m/s (the naval vessel's limit is 10 m/s)."""
    import contextlib
    import io

    d = tmp_path_factory.mktemp("roll")
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = main(["bench", "roll", "--vessel", "van-der-klugt", "naval-vessel", "--speeds",
                   "8,12", "--methods", "rrs", *FAST, "--json", str(d / "roll.json"),
                   "--markdown", str(d / "roll.md"), "--figures", str(d / "figs")])  # fmt: skip
    return rc, out.getvalue(), d


def test_speeds_parser():
    assert _speed_list("2..30") == [float(u) for u in range(2, 31, 2)]
    assert len(_speed_list("2..30")) == 15
    assert _speed_list("2..10:4") == [2.0, 6.0, 10.0]
    assert _speed_list("8,13,15") == [8.0, 13.0, 15.0]
    assert _speed_list("15,8") == [8.0, 15.0]
    assert _speed_list("8") == [8.0]
    assert _speed_list("2..9") == [2.0, 4.0, 6.0, 8.0]  # B not on the grid: left out
    assert _speed_list("0.5..1.5:0.5") == [0.5, 1.0, 1.5]
    assert _speed_list("30") == [30.0]
    for bad, msg in (("0", "(0, 30]"), ("31", "(0, 30]"), ("a..b", "A..B"), ("-2..8", "(0, 30]"),
                     ("10..2", "A <= B"), ("2..10:0", "step"), ("", "A..B"), ("nan", "(0, 30]"),
                     ("2..30:1e-9", "at most")):  # fmt: skip
        with pytest.raises(ValueError, match=re.escape(msg)):
            _speed_list(bad)


def test_bench_roll_command(bench):
    rc, out, d = bench
    assert rc == 0
    # the naval vessel cannot hold 12 m/s (limits.surge_speed 10 m/s): said in one line
    assert "naval-vessel: speeds 12 m/s skipped" in out
    assert "van-der-klugt: speeds" not in out
    from shipgym.rrs.bench import roll_from_json

    rows = roll_from_json(json.loads((d / "roll.json").read_text()))[0]
    cases = {(r["vessel"], r["speed"], r["method"]) for r in rows}
    assert cases == {("van-der-klugt", 8.0, "autopilot"), ("van-der-klugt", 8.0, "rrs"),
                     ("van-der-klugt", 12.0, "autopilot"), ("van-der-klugt", 12.0, "rrs"),
                     ("naval-vessel", 8.0, "autopilot"), ("naval-vessel", 8.0, "rrs")}  # fmt: skip
    base = {(r["vessel"], r["speed"]): r["roll_rms"] for r in rows if r["method"] == "autopilot"}
    for r in rows:
        # the RRR is the roll RMS against the autopilot's of the same case, and printed so
        rrr = 1.0 - r["roll_rms"] / base[(r["vessel"], r["speed"])]
        assert r["rrr"] == pytest.approx(rrr, abs=1e-12)
        line = f"| {r['vessel']} | {r['speed']:g} | {r['method']} | {rrr:.2f} | "
        line += f"{math.degrees(r['roll_rms']):.3f} |"
        assert line in out
    # the seed's rudder test: the roll damping works at 8 m/s in calm water
    vdk = {r["method"]: r for r in rows if r["vessel"] == "van-der-klugt" and r["speed"] == 8.0}
    assert vdk["rrs"]["roll_rms"] < 0.5 * vdk["autopilot"]["roll_rms"]
    # order: title, the table, one linear analysis per vessel, the seed's claim
    i_title = out.index("Rudder-roll stabilisation")
    i_table = out.index("| vessel | U (m/s) | method | RRR |")
    i_vdk = out.index("Linear analysis, van-der-klugt")
    i_nav = out.index("Linear analysis, naval-vessel")
    i_claim = out.index(SEED_CLAIM)
    assert i_title < i_table < i_vdk < i_nav < i_claim
    assert "not reproducible" in SEED_CLAIM and "one tenth" in SEED_CLAIM
    for p in ("roll.md",):
        md = (d / p).read_text()
        assert "| van-der-klugt | 12 | rrs |" in md
        assert "Linear analysis, naval-vessel" in md and SEED_CLAIM in md


def test_json_has_the_linear_analyses(bench):
    """The notes' seed-003 numbers (B6, B7) arrive in the JSON file, keyed records with units
    (schema 2)."""
    from shipgym.rrs.bench import roll_from_json

    _rc, _out, d = bench
    data = json.loads((d / "roll.json").read_text())
    assert data["schema_version"] == 2 and data["seed_claim"] == SEED_CLAIM
    an = data["analyses"]  # keyed by vessel, then by speed (m/s): no bare lists
    assert set(an) == {"van-der-klugt", "naval-vessel"}
    v = an["van-der-klugt"]
    assert list(v["per_speed"]) == ["8", "12"]
    assert list(an["naval-vessel"]["per_speed"]) == ["8"]  # only the speeds it can hold
    assert v["design_speed_m_per_s"] == 8.0
    at8, at12 = v["per_speed"]["8"], v["per_speed"]["12"]
    assert at8["speed_m_per_s"] == 8.0
    assert at8["roll_ratio"] == pytest.approx(0.172, abs=1e-2)
    assert v["onset"]["sway x 1"] is None  # stable on 2-30 m/s with the full sway term
    assert v["onset"]["sway x 0"]["speed_m_per_s"] == pytest.approx(8.75, abs=0.1)
    assert v["onset"]["sway x 0.2"]["speed_m_per_s"] == pytest.approx(15.7, abs=0.1)
    assert v["onset"]["sway x 0"]["frequency_rad_per_s"] == pytest.approx(0.075, abs=0.01)
    # 12 m/s lies above the no-sway onset: that loop is unstable there, stable at 8 m/s
    assert at8["margin_per_s"]["sway x 0"] < 0 < at12["margin_per_s"]["sway x 0"]
    assert max(at8["margin_per_s"]["sway x 1"], at12["margin_per_s"]["sway x 1"]) < 0
    assert max(at8["margin_scheduled_per_s"], at12["margin_scheduled_per_s"]) < 0
    # the runs keyed by vessel, speed, method and seed; angles in degrees, keys with units
    run = data["runs"]["van-der-klugt"]["8"]["rrs"]["0"]
    assert run["speed_m_per_s"] == 8.0 and run["duration_s"] == 150.0
    assert {"roll_rms_deg", "rudder_rate_rms_deg_per_s", "v_hat_rmse_m_per_s", "rrr"} <= set(run)
    assert data["units"]["suffixes"]["_deg"] == "deg"

    def bare_list(x):
        if isinstance(x, list):
            return True
        return isinstance(x, dict) and any(bare_list(y) for y in x.values())

    assert not bare_list({k: data[k] for k in ("runs", "analyses")})
    rows = roll_from_json(data)[0]  # the reader gives the SI rows back
    r8 = next(r for r in rows if (r["vessel"], r["speed"], r["method"]) == ("van-der-klugt", 8.0,
                                                                            "rrs"))  # fmt: skip
    assert r8["roll_rms"] == pytest.approx(math.radians(run["roll_rms_deg"]), rel=1e-12)
    with pytest.raises(ValueError, match="schema_version 2"):
        roll_from_json({"rows": []})


def test_cli_writes_the_figures(bench):
    _rc, out, d = bench
    names = {"roll_reduction.png", "heading_rudder.png", "stability_margin.png",
             "estimates_van-der-klugt.png", "estimates_naval-vessel.png"}  # fmt: skip
    assert {p.name for p in (d / "figs").iterdir()} == names
    for n in names:
        assert f"wrote {d / 'figs' / n}" in out
        assert (d / "figs" / n).stat().st_size > 10_000


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--speeds", "0"], "--speeds must lie in (0, 30] m/s"),
        (["--speeds", "31"], "--speeds must lie in (0, 30] m/s"),
        (["--speeds", "a..b"], "--speeds must be A..B[:STEP] or A,B,C"),
        (["--vessel", "no-such-ship"], "unknown vessel 'no-such-ship'"),
        (["--vessel", "blue-lady"], "has no [roll_control] table"),
        (["--methods", "rrs-magic"], "unknown roll method 'rrs-magic'; choose from autopilot"),
        (["--task", "zigzag"], "unknown roll task 'zigzag'; choose from seed-test, beam-sea"),
        (["--duration", "100"], "--duration: must be a finite number >= 150 s"),
        (["--vessel", "naval-vessel", "--speeds", "12"], "no runs"),
        (["--seeds", "0"], "--seeds"),
    ],
)
def test_bad_arguments_exit_2_before_any_work(args, message, capsys, monkeypatch):
    import shipgym.rrs.bench as rb

    def no_work(*a, **k):
        raise AssertionError("bench_roll ran")

    monkeypatch.setattr(rb, "bench_roll", no_work)
    assert main(["bench", "roll", *args, "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert message in err
    assert err.count("\n") == 1  # one line, no traceback


def test_write_roll_figures_from_json_rows(bench, tmp_path):
    """The figures take plain data: the rows and analyses read back from the JSON file (the
    sway scales then strings) and a trace of plain arrays; PNGs of the documented size."""
    from PIL import Image

    from shipgym.rrs.bench import roll_from_json, roll_trace
    from shipgym.viz.report import DPI
    from shipgym.viz.rrs import ROLL_SIZES, write_roll_figures

    _rc, _out, d = bench
    rows, ans = roll_from_json(json.loads((d / "roll.json").read_text()))
    analyses = {a["vessel"]: a for a in ans}
    tr = roll_trace(("van-der-klugt", 8.0, "rrs", 0, 150.0, "seed-test"))
    assert len(tr["t"]) == 1500 and np.all(np.diff(tr["t"]) > 0)
    for k in ("roll", "rudder", "heading_error", "v", "v_hat", "trace_P"):
        assert np.asarray(tr[k]).shape == tr["t"].shape
    rates = {"van-der-klugt": math.radians(10.0)}
    paths = write_roll_figures(
        rows, analyses, {"van-der-klugt": tr}, tmp_path, title="test", rate_limits=rates
    )
    names = ["roll_reduction.png", "heading_rudder.png", "stability_margin.png"]
    assert [p.name for p in paths] == [*names, "estimates_van-der-klugt.png"]
    for p in paths:
        w, h = Image.open(p).size
        key = "estimates" if p.stem.startswith("estimates") else p.stem
        W, H = ROLL_SIZES[key]
        cols = 1 if key == "estimates" else 2  # one panel column per vessel
        assert (w, h) == (round(W * cols * DPI), round(H * DPI))
        assert p.stat().st_size > 10_000
    with pytest.raises(ValueError, match="at least one vessel"):
        write_roll_figures([], {}, {}, tmp_path)


@pytest.mark.parametrize(
    "env_id", ["shipgym/RudderRollStabilisation-v0", "shipgym/NavalRollDamping-v0"]
)
def test_shipgym_run_points_a_roll_task_to_bench_roll(env_id, capsys):
    assert main(["run", env_id, "--vessel", "van-der-klugt", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "rudder-roll task" in err and "shipgym bench roll" in err and err.count("\n") == 1
