"""Aggregates over training seeds (Agarwal et al. 2021): the IQM, the stratified bootstrap,
performance profiles; checked against scipy.stats.bootstrap and by coverage."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats as sps

from shipgym.stats import aggregate, iqm, performance_profile, stratified_bootstrap_ci


def test_iqm_is_the_mean_of_the_middle_half():
    assert iqm(np.arange(100.0)) == pytest.approx(49.5)  # the mean of 25 ... 74
    assert iqm([1.0, 2.0, 3.0, 4.0, 1000.0]) == pytest.approx(3.0)  # one run off: no matter
    assert iqm(np.arange(12.0).reshape(4, 3)) == pytest.approx(np.mean(np.arange(3.0, 9.0)))


def test_one_task_interval_is_scipys_percentile_bootstrap():
    rng = np.random.default_rng(1)
    x = rng.gamma(2.0, 1.0, size=25)  # skewed: the IQM is not the mean
    est, lo, hi = stratified_bootstrap_ci(x, reps=20000, seed=2)
    ref = sps.bootstrap(
        (x,), lambda s, axis: sps.trim_mean(s, 0.25, axis=axis), n_resamples=20000,
        method="percentile", random_state=3,
    )  # fmt: skip
    width = hi - lo
    assert est == pytest.approx(sps.trim_mean(x, 0.25))
    assert lo == pytest.approx(ref.confidence_interval.low, abs=0.03 * width)
    assert hi == pytest.approx(ref.confidence_interval.high, abs=0.03 * width)


def test_the_bootstrap_keeps_each_tasks_runs_in_their_task():
    runs = np.column_stack([np.linspace(0.0, 1.0, 6), np.linspace(100.0, 101.0, 6)])

    def separated(x):
        return float(np.all(x[:, 0] <= 1.0) and np.all(x[:, 1] >= 100.0))

    assert stratified_bootstrap_ci(runs, separated, reps=500) == (1.0, 1.0, 1.0)
    # the task means stay put: the mean's interval is the runs' spread / sqrt(6), not the tasks'
    est, lo, hi = stratified_bootstrap_ci(runs, np.mean, reps=2000)
    assert est == pytest.approx(50.5) and hi - lo < 0.6


def test_95_percent_intervals_cover_the_true_value():
    rng = np.random.default_rng(5)
    covered = 0
    trials = 150
    for k in range(trials):
        x = rng.normal(1.0, 1.0, size=(10, 3))  # symmetric: the true IQM is the mean, 1
        _, lo, hi = stratified_bootstrap_ci(x, reps=300, seed=k)
        covered += lo <= 1.0 <= hi
    assert 0.85 <= covered / trials <= 0.99, covered


def test_performance_profile():
    frac, lo, hi = performance_profile(np.arange(10.0), [-1.0, 4.5, 9.0], reps=500)
    np.testing.assert_allclose(frac, [1.0, 0.5, 0.0])
    assert np.all(lo <= frac) and np.all(frac <= hi)
    assert lo[0] == hi[0] == 1.0 and lo[2] == hi[2] == 0.0
    assert 0.0 < lo[1] < 0.5 < hi[1] < 1.0


def test_aggregate_is_seeded_per_method():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(5, 4)), rng.normal(1.0, 1.0, size=(5, 4))
    one = aggregate({"ppo": a, "pid": b}, reps=300)
    two = aggregate({"pid": b, "ppo": a}, reps=300)
    assert one == two  # a method's interval does not depend on the others listed
    assert one["ppo"]["runs"] == 5 and one["ppo"]["tasks"] == 4
    assert one["ppo"] != aggregate({"ppo": a}, reps=300, seed=1)["ppo"]


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: iqm([1.0, np.nan]), "must be finite"),
        (lambda: iqm(np.zeros((2, 2, 2))), r"must be \(runs, tasks\)"),
        (lambda: stratified_bootstrap_ci([1.0, 2.0], reps=10), "reps must be"),
        (lambda: stratified_bootstrap_ci([1.0, 2.0], alpha=1.5), "alpha must be"),
        (lambda: performance_profile([1.0], [np.inf]), "taus must be"),
        (lambda: aggregate({}), "at least one method"),
        (lambda: aggregate({"sac": [np.inf]}), "scores of 'sac'"),
    ],
)
def test_bad_input_says_what_to_do(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_the_vectorised_iqm_is_the_generic_path():
    x = np.random.default_rng(9).normal(size=(7, 3))
    assert stratified_bootstrap_ci(x, reps=300, seed=4) == stratified_bootstrap_ci(
        x, lambda a: iqm(a), reps=300, seed=4
    )


def test_missing_scores_are_left_out_of_their_task_only():
    rng = np.random.default_rng(3)
    x = rng.normal(size=(6, 3))
    y = x.copy()
    y[[1, 4], 0] = np.nan  # two runs of task 0 have no score
    kept = np.concatenate([x[[0, 2, 3, 5], 0], x[:, 1], x[:, 2]])
    assert iqm(y, missing="omit") == pytest.approx(sps.trim_mean(kept, 0.25))
    est, lo, hi = stratified_bootstrap_ci(y, reps=4000, seed=1, missing="omit")
    assert est == pytest.approx(sps.trim_mean(kept, 0.25)) and lo < est < hi
    # a task's resamples stay inside its finite runs: a task of one run adds no spread
    z = np.column_stack([[5.0, np.nan, np.nan], [1.0, 2.0, 3.0]])
    ref = stratified_bootstrap_ci(np.array([1.0, 2.0, 3.0]), np.mean, reps=500, seed=2)
    boot = stratified_bootstrap_ci(z, reps=500, seed=2, missing="omit")
    assert boot[0] == pytest.approx(sps.trim_mean([5.0, 1.0, 2.0, 3.0], 0.25))
    assert ref[2] - ref[1] > 0 and boot[2] - boot[1] > 0
    out = aggregate({"ppo": y}, reps=300, missing="omit")["ppo"]
    assert out["missing"] == 2 and out["estimate"] == pytest.approx(iqm(y, missing="omit"))
    with pytest.raises(ValueError, match="every task needs"):
        iqm(np.column_stack([[np.nan, np.nan], [1.0, 2.0]]), missing="omit")
    with pytest.raises(ValueError, match="iqm statistic only"):
        stratified_bootstrap_ci(y, np.mean, missing="omit")
    with pytest.raises(ValueError, match="must be finite"):
        iqm([1.0, np.inf], missing="omit")  # only NaN is a missing score
