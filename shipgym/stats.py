r"""Aggregate scores over training seeds: the interquartile mean, stratified-bootstrap
confidence intervals and performance profiles (Agarwal et al. 2021, the ``rliable`` method).

A method's scores are an array ``(runs, tasks)``: one score per training seed (run) and task
(a condition of a suite: a wind, a direction, a sensor fault...). The aggregates:

- :func:`iqm`: the interquartile mean of all ``runs x tasks`` scores, the mean of the middle
  50 % (``scipy.stats.trim_mean(x, 0.25)``): robust to an outlying run, yet using half the
  data (Agarwal et al. 2021 sec. 4.3);
- :func:`stratified_bootstrap_ci`: a percentile-bootstrap confidence interval of any such
  aggregate in which each task's runs are resampled with replacement on their own (the
  stratified bootstrap, sec. 4.1: the uncertainty is over training seeds, every task kept);
- :func:`performance_profile`: the fraction of runs whose score exceeds each threshold
  ``tau`` (a run-score distribution, sec. 4.2), with its bootstrap band;
- :func:`aggregate`: the point estimates and intervals of several methods at once, with one
  generator for reproducible intervals.

Pure NumPy/SciPy; seeded (the same ``seed`` gives the same intervals). Independent checks in
``tests/test_stats.py``: ``scipy.stats.bootstrap`` (one task) and the interval's coverage.

Public names: ``aggregate``, ``iqm``, ``performance_profile``, ``stratified_bootstrap_ci``.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.stats import trim_mean

__all__ = ["aggregate", "iqm", "performance_profile", "stratified_bootstrap_ci"]

Array = NDArray[np.float64]

#: bootstrap resamples of :func:`stratified_bootstrap_ci` [chosen: 2000, the Monte Carlo error
#: of a 95 % percentile bound is then about 1 % of the interval's width; Agarwal et al. 2021
#: use 2000 for their figures]
DEFAULT_REPS = 2000


def _scores(scores: ArrayLike, name: str = "scores", missing: str = "raise") -> Array:
    """``scores`` as a finite (runs, tasks) array; (runs,) is one task. ``missing="omit"``
    lets NaN through (a missing score) as long as every task keeps a finite one."""
    a = np.asarray(scores, dtype=float)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2 or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError(
            f"{name} must be (runs, tasks) (or (runs,) for one task) with at least one run, "
            f"got shape {np.shape(scores)}"
        )
    if missing not in ("raise", "omit"):
        raise ValueError(f"missing must be 'raise' or 'omit', got {missing!r}")
    bad = ~np.isfinite(a)
    if missing == "omit":
        bad &= ~np.isnan(a)
        if np.isnan(a).all(axis=0).any():
            raise ValueError(f"{name}: with missing='omit' every task needs a finite score")
    if bad.any():
        raise ValueError(
            f"{name} must be finite: score a failed run with the task's worst value (e.g. 0 "
            "for a success rate), not NaN or inf (or pass missing='omit' to leave NaN out)"
        )
    return a


def iqm(scores: ArrayLike, *, missing: str = "raise") -> float:
    """The interquartile mean of all the scores ``(runs, tasks)``: the mean of the middle
    50 % (``scipy.stats.trim_mean(scores.ravel(), 0.25)``; Agarwal et al. 2021 sec. 4.3).
    ``missing="omit"``: NaN scores (a run without a value, e.g. a cost of runs that all
    failed) are left out.

    Raises:
        ValueError: not a finite (runs, tasks) or (runs,) array.
    """
    a = _scores(scores, missing=missing).ravel()
    return float(trim_mean(a[~np.isnan(a)], 0.25))


def _check_reps(reps: int, alpha: float) -> None:
    if isinstance(reps, bool) or not isinstance(reps, int | np.integer) or reps < 100:
        raise ValueError(f"reps must be an int >= 100 (bootstrap resamples), got {reps!r}")
    if not (isinstance(alpha, int | float) and 0.0 < alpha < 1.0):
        raise ValueError(f"alpha must be in (0, 1) (0.05: a 95 % interval), got {alpha!r}")


def _resample_index(rng: np.random.Generator, runs: int, tasks: int, reps: int) -> NDArray[Any]:
    """``(reps, runs, tasks)`` run indices: each task's runs drawn with replacement on their
    own (the stratified bootstrap)."""
    return rng.integers(0, runs, size=(reps, runs, tasks))


def stratified_bootstrap_ci(
    scores: ArrayLike,
    statistic: Callable[[Array], float] = iqm,
    *,
    reps: int = DEFAULT_REPS,
    alpha: float = 0.05,
    seed: int | np.random.Generator | None = 0,
    missing: str = "raise",
) -> tuple[float, float, float]:
    """``(estimate, low, high)``: the statistic of ``scores`` (runs, tasks) and its
    ``1 - alpha`` percentile-bootstrap interval, each task's runs resampled with replacement
    independently (Agarwal et al. 2021 sec. 4.1; Efron & Tibshirani 1993 ch. 13).

    Args:
        scores: (runs, tasks) or (runs,).
        statistic: an aggregate of a (runs, tasks) array (:func:`iqm`; ``np.mean``; a
            success rate...).
        reps: bootstrap resamples, >= 100.
        alpha: 0.05 for a 95 % interval.
        seed: the resampling's generator or seed (the same seed, the same interval).
        missing: ``"raise"`` (NaN is an error) or ``"omit"``: each task's NaN runs are left
            out and its remaining runs resampled among themselves (the IQM only).

    Raises:
        ValueError: bad ``scores``, ``reps`` or ``alpha``; ``missing="omit"`` with another
            statistic than :func:`iqm`.
    """
    a = _scores(scores, missing=missing)
    _check_reps(reps, alpha)
    rng = np.random.default_rng(seed)
    if missing == "omit" and np.isnan(a).any():
        if statistic is not iqm:
            raise ValueError("missing='omit' supports the iqm statistic only")
        cols = [a[~np.isnan(a[:, j]), j] for j in range(a.shape[1])]
        boot = trim_mean(
            np.concatenate([c[rng.integers(0, c.size, size=(reps, c.size))] for c in cols],
                           axis=1), 0.25, axis=1)  # fmt: skip
        lo, hi = np.quantile(boot, [alpha / 2.0, 1.0 - alpha / 2.0])
        return iqm(a, missing="omit"), float(lo), float(hi)
    runs, tasks = a.shape
    idx = _resample_index(rng, runs, tasks, reps)
    samples = a[idx, np.arange(tasks)[None, None, :]]  # (reps, runs, tasks)
    if statistic is iqm:  # (the same numbers, all resamples in one call)
        boot = trim_mean(samples.reshape(reps, -1), 0.25, axis=1)
    else:
        boot = np.array([statistic(samples[k]) for k in range(reps)])
    lo, hi = np.quantile(boot, [alpha / 2.0, 1.0 - alpha / 2.0])
    return float(statistic(a)), float(lo), float(hi)


def performance_profile(
    scores: ArrayLike,
    taus: ArrayLike,
    *,
    reps: int = DEFAULT_REPS,
    alpha: float = 0.05,
    seed: int | np.random.Generator | None = 0,
) -> tuple[Array, Array, Array]:
    """The run-score distribution ``P(score > tau)`` at each threshold of ``taus`` with its
    stratified-bootstrap band (Agarwal et al. 2021 sec. 4.2): ``(fraction, low, high)``, each
    of the shape of ``taus``. A score equal to ``tau`` does not count.

    Raises:
        ValueError: bad ``scores``, ``taus`` not finite, ``reps`` or ``alpha``.
    """
    a = _scores(scores)
    t = np.asarray(taus, dtype=float)
    if t.ndim != 1 or t.size < 1 or not np.isfinite(t).all():
        raise ValueError(f"taus must be a 1-D array of finite thresholds, got {taus!r}")
    _check_reps(reps, alpha)
    rng = np.random.default_rng(seed)
    runs, tasks = a.shape
    frac = (a.ravel()[:, None] > t[None, :]).mean(axis=0)
    idx = _resample_index(rng, runs, tasks, reps)
    boot = a[idx, np.arange(tasks)[None, None, :]].reshape(reps, -1)  # (reps, runs * tasks)
    bf = (boot[:, :, None] > t[None, None, :]).mean(axis=1)  # (reps, taus)
    lo, hi = np.quantile(bf, [alpha / 2.0, 1.0 - alpha / 2.0], axis=0)
    return frac, lo, hi


def aggregate(
    methods: Mapping[str, ArrayLike],
    statistic: Callable[[Array], float] = iqm,
    *,
    reps: int = DEFAULT_REPS,
    alpha: float = 0.05,
    seed: int = 0,
    missing: str = "raise",
) -> dict[str, dict[str, float]]:
    """:func:`stratified_bootstrap_ci` of each method's scores: ``{method: {"estimate",
    "low", "high", "runs", "tasks"}}``. Each method is resampled from a generator of
    ``(seed, crc32(name))``: its interval depends on its scores, the seed and its name only,
    not on the other methods listed. ``missing``: as :func:`stratified_bootstrap_ci`
    (``"omit"`` adds ``"missing"``, the number of NaN scores left out).

    Raises:
        ValueError: no method, or bad scores (the message names the method).
    """
    if not methods:
        raise ValueError("methods must name at least one method's scores")
    out: dict[str, dict[str, float]] = {}
    for name, s in methods.items():
        a = _scores(s, name=f"scores of {name!r}", missing=missing)
        rng = np.random.default_rng([int(seed), zlib.crc32(str(name).encode())])
        est, lo, hi = stratified_bootstrap_ci(a, statistic, reps=reps, alpha=alpha, seed=rng,
                                              missing=missing)  # fmt: skip
        out[name] = {"estimate": est, "low": lo, "high": hi, "runs": a.shape[0],
                     "tasks": a.shape[1]}  # fmt: skip
        if missing == "omit":
            out[name]["missing"] = int(np.isnan(a).sum())
    return out
