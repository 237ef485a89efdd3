"""Learning curves of ``shipgym train`` runs (``shipgym plot training RUN_DIR ... --out FIG``):
one line per run, or, with groups of runs (``--group NAME=RUN_DIR,RUN_DIR...``: the training
seeds of one method), the mean over each group's runs with its 95 % stratified-bootstrap band.

Public names: ``MAX_EVALUATIONS_BYTES``, ``MAX_GRID_POINTS``, ``MAX_PROGRESS_BYTES``,
``TRAINING_SIZE``, ``GroupCurve``, ``TrainingCurves``, ``group_curves``,
``group_training_curves``, ``parse_group``, ``plot_training``, ``read_training_groups``,
``read_training_run``, ``training_figure``.

Design notes: docs/design/viz.training.md.
"""

from __future__ import annotations

import csv
import glob
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from .report import DPI, _save

__all__ = [
    "MAX_EVALUATIONS_BYTES",
    "MAX_GRID_POINTS",
    "MAX_PROGRESS_BYTES",
    "TRAINING_SIZE",
    "GroupCurve",
    "TrainingCurves",
    "group_curves",
    "group_training_curves",
    "parse_group",
    "plot_training",
    "read_training_groups",
    "read_training_run",
    "training_figure",
]

#: figure size (inches); pixels = inches * DPI
TRAINING_SIZE = (10.0, 7.0)
#: largest ``progress.csv`` read (a 100 M-step PPO run logs ~25 000 lines of ~400 bytes)
MAX_PROGRESS_BYTES = 256 << 20
#: largest ``evaluations.json`` read
MAX_EVALUATIONS_BYTES = 64 << 20
#: the columns of ``progress.csv`` the curves use
STEPS_COLUMN = "time/total_timesteps"
RETURN_COLUMN = "rollout/ep_rew_mean"
#: most steps of a group's common grid (:func:`group_curves`) [chosen: 1000, finer than the
#: figure's 1000-pixel width; a 16 M-step PPO run logs ~1000 returns, so a recipe's runs are
#: usually drawn at their own logged steps]
MAX_GRID_POINTS = 1000


@dataclass(frozen=True)
class TrainingCurves:
    """One training run's curves.

    Attributes:
        label: the run's name in the legend.
        path: the run folder.
        steps: environment steps of each logged return (-).
        returns: ``rollout/ep_rew_mean`` at those steps (the reward's units).
        eval_kind: ``"harbour"``, ``"station-keeping"`` or ``"none"`` (no evaluations).
        eval_steps: environment steps of each evaluation (-).
        eval_score: per evaluation, the fraction of harbour runs completed without quay
            contact, or the station-keeping fraction of time inside the watch circle (0-1).
        eval_jc: per harbour evaluation, the mean J_c of the completed runs (NaN when none;
            NaN for station keeping).
    """

    label: str
    path: Path
    steps: NDArray[np.float64]
    returns: NDArray[np.float64]
    eval_kind: str
    eval_steps: NDArray[np.float64]
    eval_score: NDArray[np.float64]
    eval_jc: NDArray[np.float64]


def _read_text(path: Path, limit: int, what: str) -> str:
    size = path.stat().st_size
    if size > limit:
        raise ValueError(f"{path}: {size:,} bytes, more than the {limit:,} a {what} may have")
    return path.read_text(encoding="utf-8")


def _number(text: str, where: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise ValueError(f"{where}: not a number: {text!r}") from None
    return x


def _read_progress(path: Path) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    text = _read_text(path, MAX_PROGRESS_BYTES, "progress.csv")
    reader = csv.DictReader(text.splitlines())
    cols = reader.fieldnames or []
    missing = [c for c in (STEPS_COLUMN, RETURN_COLUMN) if c not in cols]
    if missing:
        raise ValueError(
            f"{path} has no column {', '.join(missing)} (a progress.csv written by "
            f"'shipgym train' has both); it has: {', '.join(cols) or 'nothing'}"
        )
    steps, rets = [], []
    for i, row in enumerate(reader, start=2):
        s, r = row.get(STEPS_COLUMN) or "", row.get(RETURN_COLUMN) or ""
        if s.strip() and r.strip():
            steps.append(_number(s, f"{path} line {i} {STEPS_COLUMN}"))
            rets.append(_number(r, f"{path} line {i} {RETURN_COLUMN}"))
    return np.array(steps, float), np.array(rets, float)


def _as_float(v: Any) -> float:
    return math.nan if v is None else float(v)


_Evals = tuple[str, NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]


def _read_evaluations(path: Path) -> _Evals:
    empty = np.array([], float)
    if not path.is_file():
        return "none", empty, empty, empty
    text = _read_text(path, MAX_EVALUATIONS_BYTES, "evaluations.json")
    from shipgym._safeload import parse

    data = parse(text, "json", str(path), limit=1 << 24)
    if not isinstance(data, list):
        raise ValueError(f"{path} must hold a list of evaluations, got {type(data).__name__}")
    kinds, steps, score, jc = set(), [], [], []
    for i, e in enumerate(data):
        if not isinstance(e, dict) or "timesteps" not in e:
            raise ValueError(f"{path}: evaluation {i} is not an object with 'timesteps'")
        steps.append(float(e["timesteps"]))
        if "inside_fraction" in e or any("inside_fraction" in r for r in e.get("rows") or []):
            kinds.add("station-keeping")
            if "inside_fraction" in e:
                score.append(_as_float(e["inside_fraction"]))
            else:
                score.append(float(np.mean([_as_float(r["inside_fraction"]) for r in e["rows"]])))
            jc.append(math.nan)
        elif "completed" in e and "runs" in e:
            kinds.add("harbour")
            runs = int(e["runs"])
            score.append(int(e["completed"]) / runs if runs > 0 else math.nan)
            jc.append(_as_float(e.get("J_c")))
        else:
            raise ValueError(
                f"{path}: evaluation {i} has neither 'completed' and 'runs' (harbour) nor "
                "'inside_fraction' (station keeping)"
            )
    if len(kinds) > 1:
        raise ValueError(f"{path} mixes harbour and station-keeping evaluations")
    kind = kinds.pop() if kinds else "none"
    return kind, np.array(steps, float), np.array(score, float), np.array(jc, float)


def read_training_run(run_dir: str | os.PathLike[str], label: str | None = None) -> TrainingCurves:
    """The curves of one ``shipgym train`` run folder (see the module docstring).

    Raises:
        FileNotFoundError: no such folder, or no ``progress.csv`` in it.
        ValueError: files that are not what ``shipgym train`` writes (named, one line).
    """
    d = Path(run_dir)
    if not d.is_dir():
        what = "not a folder" if d.exists() else "no such folder"
        raise FileNotFoundError(
            f"{d}: {what} (pass the --out folder of a 'shipgym train' run, which holds its "
            "progress.csv)"
        )
    prog = d / "progress.csv"
    if not prog.is_file():
        raise FileNotFoundError(
            f"{d} has no progress.csv: not a run folder of 'shipgym train' (pass the --out "
            "folder of a training run)"
        )
    steps, rets = _read_progress(prog)
    kind, e_steps, score, jc = _read_evaluations(d / "evaluations.json")
    return TrainingCurves(
        label=label if label is not None else d.resolve().name,
        path=d,
        steps=steps,
        returns=rets,
        eval_kind=kind,
        eval_steps=e_steps,
        eval_score=score,
        eval_jc=jc,
    )


# ---- groups of runs: the mean and its 95 % band -----------------------------------------------
class GroupCurve(NamedTuple):
    """The mean curve of a group of runs on their common step grid (:func:`group_curves`).

    Attributes:
        grid: environment steps (-), increasing, inside the range every run covers.
        mean: the mean over the runs at each grid step (the curve's units).
        low: the lower bound of the ``1 - alpha`` stratified-bootstrap interval of the mean
            at each grid step; ``None`` for a group of one run (nothing to resample).
        high: the upper bound; ``None`` for a group of one run.
        runs: the number of runs averaged.
    """

    grid: NDArray[np.float64]
    mean: NDArray[np.float64]
    low: NDArray[np.float64] | None
    high: NDArray[np.float64] | None
    runs: int


def _checked_run(
    steps: Any, values: Any, name: str
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    s = np.asarray(steps, dtype=float)
    v = np.asarray(values, dtype=float)
    if s.ndim != 1 or v.shape != s.shape:
        raise ValueError(
            f"{name}: steps and values must be 1-D arrays of one length, got shapes "
            f"{s.shape} and {v.shape}"
        )
    if s.size == 0:
        raise ValueError(f"{name} has no points: leave it out of the group")
    bad = ~(np.isfinite(s) & np.isfinite(v))
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(
            f"{name}: the point at step {s[i]:g} is not finite (value {v[i]:g}): leave the run "
            "out of the group"
        )
    if s.size > 1 and not (np.diff(s) > 0).all():
        i = int(np.argmax(np.diff(s) <= 0)) + 1
        raise ValueError(
            f"{name}: the steps must increase, but step {s[i]:g} follows {s[i - 1]:g} (a log "
            "that was appended to twice?): leave the run out of the group"
        )
    return s, v


def group_curves(
    steps: Sequence[Any],
    values: Sequence[Any],
    *,
    names: Sequence[str] | None = None,
    alpha: float = 0.05,
    reps: int | None = None,
    seed: int = 0,
    max_points: int = MAX_GRID_POINTS,
) -> GroupCurve:
    """The mean over a group's runs of a curve, and its ``1 - alpha`` confidence band.

    Runs log at different steps, so each run is linearly interpolated (``np.interp``) onto
    one common grid, which is limited to the range every run covers: from the latest first
    step to the earliest last step of the runs (nothing is extrapolated; what a run logged
    outside that range is not drawn). The grid is the union of the runs' own steps inside
    that range (runs of one recipe that log at the same steps are not interpolated at all),
    or, where that union has more than ``max_points`` steps, ``max_points`` evenly spaced
    steps across the range.

    The band at each grid step is the percentile bootstrap of the mean over the runs (the
    training seeds, resampled with replacement; one task): the same draws and numbers as
    :func:`shipgym.stats.stratified_bootstrap_ci` of that step's values with
    ``statistic=np.mean`` and the same ``reps``, ``alpha`` and ``seed``, computed for all
    steps at once. Seeded: the same inputs give the same band. A group of one run has no
    band (``low`` and ``high`` are ``None``).

    Args:
        steps: per run, its environment steps (-), increasing.
        values: per run, the curve at those steps (any units; returned in the same).
        names: per run, its name in the error messages (default ``run 1``, ``run 2``...).
        alpha: 0.05 for a 95 % band.
        reps: bootstrap resamples, >= 100 (default :data:`shipgym.stats.DEFAULT_REPS`).
        seed: the resampling's seed.
        max_points: the most grid steps, >= 2.

    Raises:
        ValueError: no run; steps and values of different lengths; a run without points,
            with a point that is not finite or with steps that do not increase; runs
            without a common step range; a bad ``alpha``, ``reps`` or ``max_points``.
    """
    if len(steps) != len(values):
        raise ValueError(f"{len(steps)} step arrays for {len(values)} value arrays: one each")
    if not steps:
        raise ValueError("a group needs at least one run")
    labels = list(names) if names is not None else [f"run {i + 1}" for i in range(len(steps))]
    if len(labels) != len(steps):
        raise ValueError(f"{len(labels)} names for {len(steps)} runs: give one per run")
    if not (isinstance(alpha, int | float) and 0.0 < alpha < 1.0):
        raise ValueError(f"alpha must be in (0, 1) (0.05: a 95 % band), got {alpha!r}")
    if reps is None:
        from shipgym.stats import DEFAULT_REPS

        reps = DEFAULT_REPS
    if isinstance(reps, bool) or not isinstance(reps, int | np.integer) or reps < 100:
        raise ValueError(f"reps must be an int >= 100 (bootstrap resamples), got {reps!r}")
    if isinstance(max_points, bool) or not isinstance(max_points, int) or max_points < 2:
        raise ValueError(f"max_points must be an int >= 2, got {max_points!r}")
    runs = [_checked_run(s, v, n) for s, v, n in zip(steps, values, labels, strict=True)]
    lo = max(float(s[0]) for s, _ in runs)
    hi = min(float(s[-1]) for s, _ in runs)
    if lo > hi:
        spans = "; ".join(
            f"{n}: {s[0]:,.0f}-{s[-1]:,.0f}" for n, (s, _) in zip(labels, runs, strict=True)
        )
        raise ValueError(
            f"the runs cover no common step range ({spans} steps): group runs of one recipe, "
            "trained for comparable numbers of steps"
        )
    grid = np.unique(np.concatenate([s[(s >= lo) & (s <= hi)] for s, _ in runs]))
    if grid.size > max_points:
        grid = np.linspace(lo, hi, max_points)
    y = np.stack([np.interp(grid, s, v) for s, v in runs])  # (runs, grid)
    mean = y.mean(axis=0)
    n = len(runs)
    if n == 1:
        return GroupCurve(grid, mean, None, None, 1)
    # the draws of stratified_bootstrap_ci with one task: (reps, runs) run indices
    idx = np.random.default_rng(seed).integers(0, n, size=(reps, n, 1))[:, :, 0]
    counts = (idx[:, :, None] == np.arange(n)[None, None, :]).sum(axis=1)  # (reps, runs)
    boot = (counts.astype(float) @ y) / n  # (reps, grid): each resample's mean
    low, high = np.quantile(boot, [alpha / 2.0, 1.0 - alpha / 2.0], axis=0)
    return GroupCurve(grid, mean, low, high, n)


def parse_group(text: str) -> tuple[str, list[Path]]:
    """``NAME=RUN_DIR[,RUN_DIR...]`` (``ppo=runs/ppo/seed0,runs/ppo/seed1``) as
    ``(name, folders)``. A folder with ``*``, ``?`` or ``[`` is a glob
    (``ppo=runs/ppo/seed*``), expanded in sorted order. Folder paths with a comma cannot be
    given this way (:func:`plot_training` takes them in a mapping).

    Raises:
        ValueError: no ``=``, an empty name, an empty folder, a glob that matches nothing, a
            folder named twice.
    """
    text = str(text).strip()
    name, sep, rest = text.partition("=")
    form = "NAME=RUN_DIR[,RUN_DIR...], e.g. ppo=runs/ppo/seed0,runs/ppo/seed1"
    if not sep:
        raise ValueError(f"group {text!r} has no '=': write it as {form}")
    if not name.strip():
        raise ValueError(f"group {text!r} needs a name before the '=': {form}")
    if not rest.strip():
        raise ValueError(f"group {text!r} names no run folder: {form}")
    dirs: list[Path] = []
    for item in (p.strip() for p in rest.split(",")):
        if not item:
            raise ValueError(f"group {text!r} has an empty run folder: {form}")
        if any(ch in item for ch in "*?["):
            hits = sorted(glob.glob(item))
            if not hits:
                raise ValueError(f"group {text!r}: {item!r} matches no folder")
            dirs += [Path(h) for h in hits]
        else:
            dirs.append(Path(item))
    return name.strip(), dirs


def read_training_groups(
    groups: Mapping[str, Sequence[str | os.PathLike[str]]],
) -> dict[str, list[TrainingCurves]]:
    """The runs of each group (name -> run folders), read by :func:`read_training_run`
    (each labelled ``NAME/FOLDER``).

    Raises:
        ValueError: no group, an empty group name, a group without runs, a folder named twice
            in one group, runs of one group with different kinds of evaluation, or some with
            evaluations and some without.
        FileNotFoundError: a folder that is not a ``shipgym train`` run.
    """
    if not groups:
        raise ValueError("give at least one group of runs (--group NAME=RUN_DIR,RUN_DIR...)")
    out: dict[str, list[TrainingCurves]] = {}
    for name, dirs in groups.items():
        if not str(name).strip():
            raise ValueError("a group needs a name (--group NAME=RUN_DIR,RUN_DIR...)")
        paths = [Path(d) for d in dirs]
        if not paths:
            raise ValueError(f"group {name!r} has no run folder: give at least one")
        seen = [p.resolve() for p in paths]
        twice = sorted({str(p) for p, r in zip(paths, seen, strict=True) if seen.count(r) > 1})
        if twice:
            raise ValueError(
                f"group {name!r} names {', '.join(twice)} twice: each run once (a run counted "
                "twice would weigh its seed double)"
            )
        runs = [read_training_run(p, f"{name}/{p.resolve().name}") for p in paths]
        kinds = sorted({c.eval_kind for c in runs})
        if len(kinds) > 1:
            which = "; ".join(
                f"{c.path}: {'no evaluations' if c.eval_kind == 'none' else c.eval_kind}"
                for c in runs
            )
            raise ValueError(
                f"group {name!r} mixes kinds of evaluation ({which}): group runs of one "
                "task, each with its evaluations.json"
            )
        out[str(name)] = runs
    return out


def group_training_curves(
    runs: Sequence[TrainingCurves], *, reps: int | None = None, seed: int = 0
) -> tuple[GroupCurve | None, GroupCurve | None]:
    """``(returns, evaluation)``: :func:`group_curves` of a group's training returns and of
    its evaluation scores (fraction, 0-1), each ``None`` where no run of the group has one.

    Raises:
        ValueError: some runs of the group have returns (or evaluations) and others none;
            see also :func:`group_curves`.
    """
    if not runs:
        raise ValueError("a group needs at least one run")
    return (
        _group_curve(runs, "return", reps=reps, seed=seed),
        _group_curve(runs, "eval", reps=reps, seed=seed),
    )


def _group_curve(
    runs: Sequence[TrainingCurves], which: str, *, reps: int | None, seed: int
) -> GroupCurve | None:
    """:func:`group_curves` of the runs' returns (``which="return"``) or evaluation scores
    (``"eval"``); ``None`` where no run has one, an error where only some have."""
    pairs = [
        (c.steps, c.returns) if which == "return" else (c.eval_steps, c.eval_score) for c in runs
    ]
    lack = [str(c.path) for c, (s, _) in zip(runs, pairs, strict=True) if not s.size]
    if len(lack) == len(runs):
        return None
    if lack:
        what = "logged no return yet" if which == "return" else "has no evaluations.json"
        raise ValueError(
            f"{', '.join(lack)} {what}, unlike the other runs of its group: leave it out of "
            "the group (or draw the runs one per line, without --group)"
        )
    return group_curves(
        [s for s, _ in pairs],
        [v for _, v in pairs],
        names=[str(c.path) for c in runs],
        reps=reps,
        seed=seed,
    )


def _labels(dirs: Sequence[Path]) -> list[str]:
    """The folder names, or parent/name where they repeat."""
    names = [p.resolve().name for p in dirs]
    if len(set(names)) == len(names):
        return names
    return ["/".join(p.resolve().parts[-2:]) for p in dirs]


def training_figure(
    curves: Sequence[TrainingCurves] | Mapping[str, Sequence[TrainingCurves]],
    *,
    reps: int | None = None,
    seed: int = 0,
) -> Any:
    """A matplotlib figure: the training return (top) and the evaluation (harbour completion or
    station-keeping fraction, in %) against environment steps.

    ``curves`` a sequence of runs: one line per run (same colour in every panel) and, for
    harbour evaluations, a third panel with the mean J_c of the completed runs (log scale).

    ``curves`` a mapping of group names to runs (the training seeds of one method): per group
    and panel, the mean over its runs on their common step grid with its 95 % bootstrap band
    (:func:`group_curves`, ``reps`` resamples, ``seed``), labelled ``NAME (n=K)``; a group of
    one run is its line without a band. No J_c panel: the mean J_c of the completed runs is
    undefined at an evaluation where a run completed none.

    Raises:
        ValueError: see :func:`group_curves` and :func:`read_training_groups` (groups only).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    groups: dict[str, list[TrainingCurves]] = {}
    everyone: list[TrainingCurves]
    if isinstance(curves, Mapping):
        groups = {str(k): list(v) for k, v in curves.items()}
        everyone = [c for v in groups.values() for c in v]
    else:
        everyone = list(curves)
    grouped = isinstance(curves, Mapping)
    drawn = []  # (label, return GroupCurve, evaluation GroupCurve) per group
    for name, runs in groups.items():
        if not runs:
            raise ValueError(f"group {name!r} has no run: give at least one")
        drawn.append(
            (f"{name} (n={len(runs)})", *group_training_curves(runs, reps=reps, seed=seed))
        )
    kinds = {c.eval_kind for c in everyone} - {"none"}
    with_jc = not grouped and any(np.isfinite(c.eval_jc).any() for c in everyone)
    size = (TRAINING_SIZE[0], TRAINING_SIZE[1] * (1.4 if with_jc else 1.0))
    fig = Figure(figsize=size, dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(3 if with_jc else 2, 1, sharex=True)
    ax_r, ax_e = axes[0], axes[1]
    if grouped:
        for i, (label, ret, ev) in enumerate(drawn):
            color = f"C{i % 10}"
            for ax, g, scale, fmt in ((ax_r, ret, 1.0, "-"), (ax_e, ev, 100.0, "o-")):
                if g is None:
                    continue
                one = g.grid.size == 1  # one common step: a marker, the band an error bar
                ax.plot(g.grid, scale * g.mean, "o" if one else fmt, color=color, ms=3,
                        label=label)  # fmt: skip
                if g.low is None or g.high is None:
                    continue
                if one:
                    err = np.maximum(0.0, scale * np.array([g.mean - g.low, g.high - g.mean]))
                    ax.errorbar(g.grid, scale * g.mean, yerr=err, fmt="none", color=color,
                                capsize=4)  # fmt: skip
                else:
                    ax.fill_between(
                        g.grid, scale * g.low, scale * g.high, color=color, alpha=0.2, lw=0
                    )
    else:
        for i, c in enumerate(everyone):
            color = f"C{i % 10}"
            ax_r.plot(c.steps, c.returns, color=color, label=c.label)
            if c.eval_steps.size:
                ax_e.plot(c.eval_steps, 100.0 * c.eval_score, "o-", color=color, label=c.label)
            if with_jc and np.isfinite(c.eval_jc).any():
                axes[2].plot(c.eval_steps, c.eval_jc, "o-", color=color, label=c.label)
    if with_jc:
        axes[2].set_ylabel("harbour J_c of the\ncompleted runs (Tomera 2014 eq. 57)")
        axes[2].set_yscale("log")
        axes[2].grid(True, alpha=0.3, which="both")
    what = {
        frozenset({"harbour"}): "harbour runs completed,\nno quay contact (%)",
        frozenset({"station-keeping"}): "station keeping: time\ninside the radius (%)",
    }.get(frozenset(kinds), "harbour completion /\nstation-keeping fraction (%)")
    ax_r.set_ylabel("mean training return\n(rollout/ep_rew_mean)")
    ax_r.set_title(
        "Learning curves: mean over each group's runs, 95 % bootstrap CI"
        if grouped
        else "Learning curves"
    )
    ax_e.set_ylabel(what)
    ax_e.set_ylim(-5.0, 105.0)
    axes[-1].set_xlabel("environment steps")
    for ax in (ax_r, ax_e):
        ax.grid(True, alpha=0.3)
    legend_ax = ax_r if ax_r.lines or not ax_e.lines else ax_e
    if legend_ax.lines:
        legend_ax.legend(loc="best", fontsize="small")
    if not kinds:
        ax_e.text(0.5, 0.5, "no evaluations", transform=ax_e.transAxes, ha="center")
    return fig


def plot_training(
    run_dirs: Sequence[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    *,
    labels: Sequence[str] | None = None,
    groups: Mapping[str, Sequence[str | os.PathLike[str]]] | None = None,
    reps: int | None = None,
    seed: int = 0,
) -> Path:
    """Write the learning curves (:func:`training_figure`) to the PNG ``out``: of ``run_dirs``
    one line per run, or of ``groups`` the mean and 95 % band of each group.

    Args:
        run_dirs: ``shipgym train`` output folders, one line each (empty with ``groups``).
        out: the figure (``.png``).
        labels: legend names, one per run of ``run_dirs`` (default: the folder names,
            parent/name where two repeat).
        groups: group name -> its run folders (e.g. the training seeds of one method): the
            mean over the group's runs with its bootstrap band (:func:`group_curves`).
        reps: bootstrap resamples of the bands (default
            :data:`shipgym.stats.DEFAULT_REPS`).
        seed: the bands' resampling seed (the same inputs and seed, the same figure).

    Returns:
        The written path.

    Raises:
        ValueError: neither or both of ``run_dirs`` and ``groups``, ``labels`` with
            ``groups``, a bad group (:func:`read_training_groups`, :func:`group_curves`),
            an ``out`` that is not ``.png``.
        FileNotFoundError: a folder that is not a ``shipgym train`` run.
    """
    dirs = [Path(p) for p in run_dirs]
    if groups is not None and dirs:
        raise ValueError(
            "give run folders (one line per run) or groups (the mean of each group), not "
            "both: put every run in a group (--group NAME=RUN_DIR,...)"
        )
    if groups is None and not dirs:
        raise ValueError(
            "give at least one training run folder (RUN_DIR ...) or group "
            "(--group NAME=RUN_DIR,RUN_DIR...)"
        )
    if groups is not None and labels is not None:
        raise ValueError(
            "labels name runs drawn one per line; a group's legend is its name (--group "
            "NAME=...): drop the labels"
        )
    out = Path(out)
    if out.suffix.lower() != ".png":
        raise ValueError(f"the figure must be a .png file, got {out}")
    if groups is not None:
        fig = training_figure(read_training_groups(groups), reps=reps, seed=seed)
    else:
        if labels is not None and len(labels) != len(dirs):
            raise ValueError(f"{len(labels)} labels for {len(dirs)} runs: give one per run")
        names = list(labels) if labels is not None else _labels(dirs)
        fig = training_figure([read_training_run(d, n) for d, n in zip(dirs, names, strict=True)])
    out.parent.mkdir(parents=True, exist_ok=True)
    return _save(fig, out)
