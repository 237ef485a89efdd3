"""Learning curves of groups of training runs (``shipgym plot training --group NAME=RUN_DIR,...``):
the mean over a group's runs on their common step grid and its 95 % bootstrap band, checked
against independent computations (a hand-written interpolation and mean, and
``shipgym.stats.stratified_bootstrap_ci`` at single grid steps), on fake run folders in the
format ``shipgym train`` writes (``progress.csv`` and ``evaluations.json``). Needs neither
stable-baselines3 nor torch (the one-line-per-run curves are tested in tests/test_rl_bench.py).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from matplotlib.collections import PolyCollection

from shipgym.cli import main
from shipgym.stats import stratified_bootstrap_ci
from shipgym.viz.training import (
    group_curves,
    group_training_curves,
    parse_group,
    plot_training,
    read_training_groups,
    read_training_run,
    training_figure,
)

REPS = 500  # bootstrap resamples in the tests (the default 2000 where not given)


def _fake_run(folder: Path, steps, returns, evals=None) -> Path:
    """A run folder as ``shipgym train`` writes it: SB3's progress.csv (a first row without a
    return, as before the first finished episode; evaluation rows of their own) and, with
    ``evals`` ((timesteps, completed, runs) triples), the harbour evaluations.json."""
    folder.mkdir(parents=True)
    head = "time/time_elapsed,time/total_timesteps,rollout/ep_rew_mean,eval/completed_fraction"
    rows = [head, f"0,{int(steps[0]) // 2},,"]
    rows += [f"{i},{int(s)},{r!r}," for i, (s, r) in enumerate(zip(steps, returns, strict=True), 1)]
    if evals:
        rows += [f"9,{t},,{c / n}" for t, c, n in evals]
    (folder / "progress.csv").write_text("\n".join(rows) + "\n")
    if evals is not None:
        data = [{"timesteps": t, "evaluation": "harbour", "completed": c, "runs": n,
                 "J_c": 0.2 if c else None, "rows": []} for t, c, n in evals]  # fmt: skip
        (folder / "evaluations.json").write_text(json.dumps(data))
    return folder


def _interp(x: float, xs: list[float], ys: list[float]) -> float:
    """Linear interpolation at ``x`` inside ``[xs[0], xs[-1]]``, by hand."""
    for k in range(len(xs) - 1):
        if xs[k] <= x <= xs[k + 1]:
            w = (x - xs[k]) / (xs[k + 1] - xs[k])
            return (1.0 - w) * ys[k] + w * ys[k + 1]
    assert len(xs) == 1 and x == xs[0]
    return ys[0]


#: three seeds of one recipe, logging at different steps over different ranges
STEPS = [
    [1000.0, 2000.0, 3000.0, 4000.0, 5000.0],
    [1500.0, 2500.0, 3500.0, 4500.0],
    [800.0, 1700.0, 2600.0, 3300.0, 4200.0, 6000.0],
]
RETURNS = [
    [-900.0, -700.0, -650.0, -400.0, -380.0],
    [-950.0, -800.0, -500.0, -420.0],
    [-990.0, -880.0, -610.0, -560.0, -300.0, -100.0],
]


def test_the_mean_is_the_runs_mean_on_the_common_grid():
    g = group_curves(STEPS, RETURNS, reps=REPS)
    lo = max(s[0] for s in STEPS)  # 1500: the latest first step
    hi = min(s[-1] for s in STEPS)  # 4500: the earliest last step
    want_grid = sorted({x for s in STEPS for x in s if lo <= x <= hi})
    np.testing.assert_array_equal(g.grid, want_grid)
    assert g.grid[0] == lo and g.grid[-1] == hi  # the common range only, nothing extrapolated
    want = [
        sum(_interp(x, s, r) for s, r in zip(STEPS, RETURNS, strict=True)) / 3 for x in want_grid
    ]
    np.testing.assert_allclose(g.mean, want, rtol=1e-13)
    assert g.runs == 3 and g.low is not None and g.high is not None
    assert (g.high - g.low > 0).any()


def test_the_band_is_the_stratified_bootstrap_of_the_mean_at_each_step():
    g = group_curves(STEPS, RETURNS, reps=REPS, seed=7)
    assert g.low is not None and g.high is not None
    runs = np.array(
        [[_interp(x, s, r) for x in g.grid] for s, r in zip(STEPS, RETURNS, strict=True)]
    )
    for j in (0, 3, len(g.grid) - 1):
        est, low, high = stratified_bootstrap_ci(runs[:, j], np.mean, reps=REPS, seed=7)
        assert g.mean[j] == pytest.approx(est, rel=1e-13)
        assert g.low[j] == pytest.approx(low, rel=1e-12)
        assert g.high[j] == pytest.approx(high, rel=1e-12)
    again = group_curves(STEPS, RETURNS, reps=REPS, seed=7)  # seeded: the same band
    np.testing.assert_array_equal(again.low, g.low)
    np.testing.assert_array_equal(again.high, g.high)


def test_the_band_contains_the_mean_and_is_flat_where_the_runs_agree():
    rng = np.random.default_rng(3)
    steps = [np.sort(rng.uniform(0, 1e5, 40)) for _ in range(6)]
    values = [np.cumsum(rng.normal(0, 10, 40)) for _ in range(6)]
    g = group_curves(steps, values, reps=REPS)
    assert g.low is not None and g.high is not None
    tol = 1e-9 * np.abs(g.mean).max()
    assert (g.low <= g.mean + tol).all() and (g.mean <= g.high + tol).all()
    same = group_curves([STEPS[0]] * 5, [RETURNS[0]] * 5, reps=REPS)
    assert same.low is not None and same.high is not None
    np.testing.assert_array_equal(same.grid, STEPS[0])
    np.testing.assert_array_equal(same.mean, RETURNS[0])
    np.testing.assert_array_equal(same.high - same.low, 0.0)
    np.testing.assert_array_equal(same.low, RETURNS[0])


def test_a_long_union_of_steps_is_thinned_to_an_even_grid():
    steps = [np.arange(0.0, 5000.0, 1.0), np.arange(0.5, 4000.0, 1.0)]
    values = [np.sin(s / 300.0) for s in steps]
    g = group_curves(steps, values, reps=REPS, max_points=200)
    np.testing.assert_allclose(g.grid, np.linspace(0.5, 3999.5, 200))
    want = (np.sin(g.grid / 300.0) + np.interp(g.grid, steps[1], values[1])) / 2.0
    np.testing.assert_allclose(g.mean, want, atol=1e-5)  # the first run: 1-step linear pieces


def test_a_group_of_one_run_has_no_band(tmp_path):
    g = group_curves([STEPS[0]], [RETURNS[0]])
    assert g.low is None and g.high is None and g.runs == 1
    np.testing.assert_array_equal(g.mean, RETURNS[0])
    run = _fake_run(tmp_path / "sac" / "seed0", STEPS[0], RETURNS[0], [(2000, 1, 2)])
    fig = training_figure(read_training_groups({"sac": [run]}))
    ax_r, ax_e = fig.axes
    assert [ln.get_label() for ln in ax_r.lines] == ["sac (n=1)"]
    assert not ax_r.collections and not ax_e.collections  # no band
    np.testing.assert_array_equal(ax_r.lines[0].get_ydata(), RETURNS[0])
    np.testing.assert_array_equal(ax_e.lines[0].get_ydata(), [50.0])


def test_one_common_step_is_a_marker_with_an_error_bar(tmp_path):
    a = _fake_run(tmp_path / "a", [100.0, 200.0], [1.0, 2.0])
    b = _fake_run(tmp_path / "b", [200.0, 300.0], [4.0, 5.0])
    ax_r, ax_e = training_figure(read_training_groups({"g": [a, b]}), reps=REPS).axes
    line = ax_r.lines[0]
    assert line.get_label() == "g (n=2)" and line.get_marker() == "o"
    np.testing.assert_array_equal(line.get_xdata(), [200.0])
    np.testing.assert_array_equal(line.get_ydata(), [3.0])
    (bar,) = ax_r.collections  # the band of the mean of 2 and 4: from 2 to 4
    np.testing.assert_array_equal(bar.get_segments()[0], [[200.0, 2.0], [200.0, 4.0]])
    assert not ax_e.lines  # neither run has evaluations


def test_the_figure_draws_each_groups_mean_and_band(tmp_path):
    evals = [[(2000, 0, 2), (4000, 1, 2)], [(2000, 1, 2), (4000, 2, 2)],
             [(2000, 0, 2), (4000, 2, 2)]]  # fmt: skip
    ppo = [_fake_run(tmp_path / "ppo" / f"seed{k}", s, r, e)
           for k, (s, r, e) in enumerate(zip(STEPS, RETURNS, evals, strict=True))]  # fmt: skip
    sac = [_fake_run(tmp_path / "sac" / f"seed{k}", STEPS[k], RETURNS[k][::-1], evals[k])
           for k in range(2)]  # fmt: skip
    groups = read_training_groups({"ppo": ppo, "sac": sac})
    assert [c.label for c in groups["ppo"]] == ["ppo/seed0", "ppo/seed1", "ppo/seed2"]
    fig = training_figure(groups, reps=REPS)
    assert len(fig.axes) == 2  # no J_c panel with groups
    ax_r, ax_e = fig.axes
    assert [ln.get_label() for ln in ax_r.lines] == ["ppo (n=3)", "sac (n=2)"]
    assert [t.get_text() for t in ax_r.get_legend().get_texts()] == ["ppo (n=3)", "sac (n=2)"]
    ret, ev = group_training_curves(groups["ppo"], reps=REPS)
    assert ret is not None and ev is not None and ret.low is not None and ret.high is not None
    np.testing.assert_array_equal(ax_r.lines[0].get_xdata(), ret.grid)
    np.testing.assert_array_equal(ax_r.lines[0].get_ydata(), ret.mean)
    band = [c for c in ax_r.collections if isinstance(c, PolyCollection)]
    assert len(band) == 2  # one band per group
    y = band[0].get_paths()[0].vertices[:, 1]
    assert y.min() == pytest.approx(ret.low.min()) and y.max() == pytest.approx(ret.high.max())
    np.testing.assert_array_equal(ev.grid, [2000, 4000])  # the same evaluation steps
    np.testing.assert_allclose(ax_e.lines[0].get_ydata(), [100 * 1 / 6, 100 * 5 / 6])
    assert len(ax_e.collections) == 2
    png = plot_training([], tmp_path / "curves.png", groups={"ppo": ppo, "sac": sac}, reps=REPS)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_cli_draws_groups(tmp_path, capsys, monkeypatch):
    for k in range(3):
        _fake_run(tmp_path / "runs" / "ppo" / f"seed{k}", STEPS[k], RETURNS[k], [(2000, k, 2)])
    _fake_run(tmp_path / "runs" / "sac" / "seed0", STEPS[0], RETURNS[0], [(2000, 1, 2)])
    monkeypatch.chdir(tmp_path)
    argv = ["plot", "training", "--group", "ppo=runs/ppo/seed0,runs/ppo/seed1,runs/ppo/seed2",
            "--group", "sac=runs/sac/seed*", "--out", "curves.png"]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "ppo (n=3): mean return" in out and "95 % CI" in out
    assert "sac (n=1): mean return -380 at 5,000 steps" in out and "wrote curves.png" in out
    assert (tmp_path / "curves.png").read_bytes()[:4] == b"\x89PNG"
    assert parse_group("ppo=runs/ppo/seed*")[1] == [Path(f"runs/ppo/seed{k}") for k in range(3)]


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--group", "ppo", "runs/a"], "group 'ppo' has no '=': write it as NAME=RUN_DIR"),
        (["--group", "ppo="], "group 'ppo=' names no run folder"),
        (["--group", "=runs/a"], "needs a name before the '='"),
        (["--group", "ppo=runs/a,,runs/b"], "has an empty run folder"),
        (["--group", "ppo=runs/nope"], "runs/nope: no such folder"),
        (["--group", "ppo=runs/z*"], "'runs/z*' matches no folder"),
        (["--group", "ppo=runs/a", "--group", "ppo=runs/b"], "'ppo' is given twice"),
        (["--group", "ppo=runs/a,runs/a"], "names runs/a twice"),
        (["runs/a", "--group", "ppo=runs/b"], "not both"),
        (["--group", "ppo=runs/a", "--labels", "x"], "drop --labels"),
        ([], "give at least one training run folder (RUN_DIR ...) or group"),
        (["--group", "ppo=runs/a,runs/late"], "cover no common step range"),
        (["--group", "ppo=runs/a,runs/noeval"], "mixes kinds of evaluation"),
    ],
)
def test_bad_groups_are_refused_in_one_line(extra, needle, tmp_path, capsys, monkeypatch):
    _fake_run(tmp_path / "runs" / "a", STEPS[0], RETURNS[0], [(2000, 1, 2)])
    _fake_run(tmp_path / "runs" / "b", STEPS[1], RETURNS[1], [(2000, 1, 2)])
    _fake_run(tmp_path / "runs" / "late", [9000.0, 9500.0], [1.0, 2.0], [(2000, 1, 2)])
    _fake_run(tmp_path / "runs" / "noeval", STEPS[2], RETURNS[2])
    monkeypatch.chdir(tmp_path)
    assert main(["plot", "training", *extra, "--out", "curves.png"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("shipgym: error: ") and needle in err[0], err
    assert not (tmp_path / "curves.png").exists()


def test_bad_groups_are_refused_by_the_api(tmp_path):
    a = _fake_run(tmp_path / "a", STEPS[0], RETURNS[0], [(2000, 1, 2)])
    noret = _fake_run(tmp_path / "noret", [100.0], [0.0], [(2000, 1, 2)])
    (noret / "progress.csv").write_text("time/total_timesteps,rollout/ep_rew_mean\n100,\n")
    with pytest.raises(ValueError, match="group 'ppo' has no run folder"):
        read_training_groups({"ppo": []})
    with pytest.raises(ValueError, match="at least one group"):
        read_training_groups({})
    with pytest.raises(FileNotFoundError, match="no such folder"):
        read_training_groups({"ppo": [a, tmp_path / "missing"]})
    with pytest.raises(FileNotFoundError, match="no such folder"):
        read_training_run(tmp_path / "missing")
    with pytest.raises(ValueError, match="logged no return yet, unlike the other runs"):
        training_figure(read_training_groups({"ppo": [a, noret]}))
    with pytest.raises(ValueError, match="not both"):
        plot_training([a], tmp_path / "x.png", groups={"ppo": [a]})
    with pytest.raises(ValueError, match="a group needs at least one run"):
        group_curves([], [])
    with pytest.raises(ValueError, match="run 2 has no points"):
        group_curves([[1.0, 2.0], []], [[1.0, 2.0], []])
    with pytest.raises(ValueError, match="the steps must increase, but step 2 follows 3"):
        group_curves([[1.0, 3.0, 2.0]], [[1.0, 2.0, 3.0]])
    with pytest.raises(ValueError, match="is not finite"):
        group_curves([[1.0, 2.0]], [[1.0, np.nan]])
    with pytest.raises(ValueError, match="reps must be an int >= 100"):
        group_curves(STEPS, RETURNS, reps=10)
    with pytest.raises(ValueError, match="alpha must be in"):
        group_curves(STEPS, RETURNS, alpha=1.5)
