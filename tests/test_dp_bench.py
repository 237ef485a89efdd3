"""``shipgym bench dp`` and the Al-Takie (1982) controllers in closed loop on the MuJoCo vessels."""

from __future__ import annotations

import json

import numpy as np
import pytest

from shipgym.controllers.grimble import PRINTED_GAINS, GrimbleLQController
from shipgym.dp.bench import METHODS, dp_run, dp_table
from shipgym.dynamics.altakie import THESIS_LF
from shipgym.dynamics.vessel import load_vessel


def test_printed_gain_on_the_vessel_is_the_thesis_loop():
    """alt-lq-printed on Star Hercules: the generalised gain is the printed one (Y = I)."""
    c = GrimbleLQController(load_vessel("star-hercules"), 0.2728, variant="printed")
    np.testing.assert_allclose(-c.K, PRINTED_GAINS["star-hercules"])
    # Wimpey: printed in the lumped-unit inputs, mapped through Y; same closed-loop poles
    w = GrimbleLQController(load_vessel("wimpey-sealab"), 0.3104, variant="printed")
    lf = THESIS_LF["wimpey-sealab"]
    E_units = np.linalg.eigvals(lf.A + lf.B @ PRINTED_GAINS["wimpey-sealab/b"])
    g = lf.generalised()
    E_gen = np.linalg.eigvals(g.A - g.B @ w.K)
    np.testing.assert_allclose(np.sort_complex(E_gen), np.sort_complex(E_units), atol=1e-9)
    with pytest.raises(ValueError, match="prints LQ gains"):
        GrimbleLQController(load_vessel("blue-lady"), 0.1, variant="printed")


def test_controller_sign_and_units():
    """A sway position error to starboard asks for a force to port; heading error likewise."""
    c = GrimbleLQController(load_vessel("wimpey-sealab"), 0.3104)
    tau = c(np.array([0.0, 1.0, 0.0]), np.zeros(3), np.zeros(3))
    assert tau[1] < 0
    c.reset()
    tau = c(np.array([0.0, 0.0, 0.02]), np.zeros(3), np.zeros(3))
    assert tau[2] < 0
    c.reset()
    tau = c(np.array([2.0, 0.0, 0.0]), np.zeros(3), np.zeros(3))
    assert tau[0] < 0


@pytest.mark.parametrize("method", ["kf14", "kf12", "notch-pid", "raw-lq"])
def test_dp_run_holds_station(method):
    row = dp_run(("star-hercules", 5, method, 0, 200.0))
    assert row["inside_radius_pct"] == 100.0
    assert row["position_rms_m"] < 3.0
    assert row["filter_step_us"] > 0
    assert np.isfinite(row["wave_band_ratio"])


def test_dp_table_and_cli(tmp_path, capsys):
    from shipgym.cli import main

    out = tmp_path / "dp.json"
    md = tmp_path / "dp.md"
    rc = main(
        ["bench", "dp", "--vessel", "wimpey-sealab", "--beaufort", "6", "--seeds", "1",
         "--methods", "kf14", "semiconstant", "--duration", "120", "--workers", "1",
         "--json", str(out), "--markdown", str(md), "--no-progress"]
    )  # fmt: skip
    assert rc == 0
    doc = json.loads(out.read_text())
    rows = doc["rows"]
    assert {r["method"] for r in rows} == {"kf14", "semiconstant"}
    # machine-readable: a schema version, units for the keys without one, keyed records
    assert doc["schema_version"] == 2
    for r in rows:
        assert set(r["thrust_usage"]) == {"X", "Y", "N"}
        assert set(r["lf_rmse"]) == {"x_m", "y_m", "psi_deg"}
        assert r["feedforward"] == "wind+current"
        for key, value in r.items():
            unit = key.endswith(("_m", "_deg", "_s", "_pct", "_us", "_per_min"))
            if isinstance(value, int | float) and not isinstance(value, bool) and not unit:
                assert key in doc["units"], key
        assert not any(isinstance(v, list) for v in r.values())
    assert "| wimpey-sealab | 6 | kf14 |" in md.read_text()
    assert dp_table(rows).count("\n") == 3
    for bad in (["--beaufort", "4"], ["--methods", "kf99"], ["--duration", "10"]):
        assert main(["bench", "dp", *bad]) != 0
        err = capsys.readouterr().err
        assert "--beaufort" in err or "unknown DP method" in err or "--duration" in err
    assert set(METHODS) >= {"kf14", "kf12", "semiconstant", "ekf", "notch-pid"}


def test_dp_figures(tmp_path):
    """The figures are written (PNG of the documented size) from a short trace."""
    from shipgym.dp.bench import dp_gain_history, dp_trace
    from shipgym.viz.dp import DP_SIZES, write_dp_figures
    from shipgym.viz.report import DPI

    traces = {m: dp_trace(("star-hercules", 5, m, 0, 120.0)) for m in ("kf14", "raw-lq")}
    tr = traces["kf14"]
    assert tr["eta"].shape == tr["hf"].shape == tr["hf_hat"].shape == (len(tr["t"]), 3)
    # the filter's HF estimate follows the true wave motion on the measurement
    c = np.corrcoef(tr["hf"][200:, 1], tr["hf_hat"][200:, 1])[0, 1]
    assert c > 0.5
    gains = dp_gain_history("star-hercules", 5, duration=60.0)
    assert gains["K"].shape[1:] == (14, 2) and gains["settled"] > 0
    paths = write_dp_figures(traces, gains, tmp_path, title="test")
    assert {p.name for p in paths} == {"dp_estimates_kf14.png", "dp_thrust.png", "dp_gains.png"}
    from PIL import Image

    for p in paths:
        w, h = Image.open(p).size
        W, H = DP_SIZES["dp_estimates" if p.stem.startswith("dp_estimates") else p.stem]
        assert (w, h) == (round(W * DPI), round(H * DPI))


def test_sway_step_task():
    """The thesis's 0.02 p.u. sway step on the simulated Star Hercules (1.46 m at 100 s)."""
    row = dp_run(("star-hercules", 5, "kf16", 0, 300.0, "sway-step"))
    assert row["task"] == "sway-step"
    assert 5.0 < row["rise_time_s"] < 100.0
    assert row["overshoot_pct"] < 100.0
    with pytest.raises(ValueError, match="unknown DP task"):
        dp_run(("star-hercules", 5, "kf16", 0, 300.0, "zigzag"))


def test_shipgym_run_builds_the_wave_filter_for_the_vessel(capsys):
    """`shipgym run` validates an alt-* observer with the run's vessel (it needs one)."""
    from shipgym.cli import main

    rc = main(["run", "shipgym/DPStationKeeping-v0", "--vessel", "star-hercules",
               "--observer", "alt-kf16", "--controller", "alt-lq-printed"])  # fmt: skip
    assert rc == 0
    assert "estimation RMSE" in capsys.readouterr().out
