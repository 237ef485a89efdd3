"""Learning curves of ``shipgym train`` runs (``shipgym plot training RUN_DIR ... --out FIG``).

Public names: ``MAX_EVALUATIONS_BYTES``, ``MAX_PROGRESS_BYTES``, ``TRAINING_SIZE``,
``TrainingCurves``, ``plot_training``, ``read_training_run``, ``training_figure``.

Design notes: docs/design/viz.training.md.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .report import DPI, _save

__all__ = [
    "MAX_EVALUATIONS_BYTES",
    "MAX_PROGRESS_BYTES",
    "TRAINING_SIZE",
    "TrainingCurves",
    "plot_training",
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
        FileNotFoundError: no ``progress.csv`` in the folder.
        ValueError: files that are not what ``shipgym train`` writes (named, one line).
    """
    d = Path(run_dir)
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


def _labels(dirs: Sequence[Path]) -> list[str]:
    """The folder names, or parent/name where they repeat."""
    names = [p.resolve().name for p in dirs]
    if len(set(names)) == len(names):
        return names
    return ["/".join(p.resolve().parts[-2:]) for p in dirs]


def training_figure(curves: Sequence[TrainingCurves]) -> Any:
    """A matplotlib figure: the training return (top), the evaluation (harbour completion or
    station-keeping fraction, in %) and, for harbour evaluations, the mean J_c of the completed
    runs (log scale) against environment steps, one line per run (same colour in every
    panel)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    kinds = {c.eval_kind for c in curves} - {"none"}
    with_jc = any(np.isfinite(c.eval_jc).any() for c in curves)
    size = (TRAINING_SIZE[0], TRAINING_SIZE[1] * (1.4 if with_jc else 1.0))
    fig = Figure(figsize=size, dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(3 if with_jc else 2, 1, sharex=True)
    ax_r, ax_e = axes[0], axes[1]
    for i, c in enumerate(curves):
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
    ax_r.set_title("Learning curves")
    ax_e.set_ylabel(what)
    ax_e.set_ylim(-5.0, 105.0)
    axes[-1].set_xlabel("environment steps")
    for ax in (ax_r, ax_e):
        ax.grid(True, alpha=0.3)
    if curves:
        ax_r.legend(loc="best", fontsize="small")
    if not kinds:
        ax_e.text(0.5, 0.5, "no evaluations", transform=ax_e.transAxes, ha="center")
    return fig


def plot_training(
    run_dirs: Sequence[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    *,
    labels: Sequence[str] | None = None,
) -> Path:
    """Write the learning curves of ``run_dirs`` (:func:`training_figure`) to the PNG ``out``.

    Args:
        run_dirs: ``shipgym train`` output folders.
        out: the figure (``.png``).
        labels: legend names, one per run (default: the folder names, parent/name where two
            repeat).

    Returns:
        The written path.
    """
    dirs = [Path(p) for p in run_dirs]
    if not dirs:
        raise ValueError("give at least one training run folder")
    out = Path(out)
    if out.suffix.lower() != ".png":
        raise ValueError(f"the figure must be a .png file, got {out}")
    if labels is not None and len(labels) != len(dirs):
        raise ValueError(f"{len(labels)} labels for {len(dirs)} runs: give one per run")
    names = list(labels) if labels is not None else _labels(dirs)
    curves = [read_training_run(d, n) for d, n in zip(dirs, names, strict=True)]
    out.parent.mkdir(parents=True, exist_ok=True)
    return _save(training_figure(curves), out)
