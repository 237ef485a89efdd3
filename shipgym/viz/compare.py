"""Figures comparing observers (``shipgym bench observers --report DIR``) like Tomera's Table 6."""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .report import DPI

__all__ = ["COMPARE_SIZES", "write_observer_report"]

#: Figure sizes (inches); pixels = inches * DPI.
COMPARE_SIZES: dict[str, tuple[float, float]] = {
    "observers_indices": (12.0, 5.0),
    "observers_velocity_errors": (12.0, 9.0),
}
_INDICES = (("x_E", "x_E (m)"), ("y_E", "y_E (m)"), ("psi_E", "psi_E (deg)"), ("J_c", "J_c"))


def _figure(name: str) -> Any:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=COMPARE_SIZES[name], dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def write_observer_report(
    rows: Sequence[Mapping[str, Any]],
    traces: Mapping[str, Mapping[str, Any]],
    out_dir: str | os.PathLike[str],
    *,
    vessel: str | None = None,
    task: str = "harbour manoeuvre",
    seed: int = 0,
) -> list[Path]:
    """Bar chart of the accuracy indices per observer and velocity-error plots.

    Args:
        rows: one mapping per run with ``observer``, ``measured`` and ``truth`` (dicts of
            x_E, y_E, psi_E, J_c), as returned by :func:`shipgym.bench.bench_observers`.
        traces: per observer, ``{"t": (N,), "err_nu": (N, 3)}`` velocity estimation errors
            ``[u, v, r]`` (m/s, m/s, rad/s) of one episode.
        out_dir: folder for ``observers_indices.png`` and ``observers_velocity_errors.png``.
        vessel, task, seed: what the runs were (the vessel's title, if given; the task; the
            seed of ``traces``), named in the figure titles.

    Returns:
        The written paths.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = list(dict.fromkeys(r["observer"] for r in rows))
    fig = _figure("observers_indices")
    axes = fig.subplots(1, 4)
    width = 0.38
    x = np.arange(len(names))
    for ax, (key, label) in zip(axes, _INDICES, strict=True):
        for j, (src, colour) in enumerate((("measured", "#1f77b4"), ("truth", "#2ca02c"))):
            vals = [np.array([r[src][key] for r in rows if r["observer"] == n]) for n in names]
            ax.bar(
                x + (j - 0.5) * width, [v.mean() for v in vals], width,
                yerr=[v.std() for v in vals], capsize=3, color=colour,
                label="from measurements" if src == "measured" else "from the truth",
            )  # fmt: skip
        ax.set_xticks(x, names)
        ax.set_title(label)
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend(fontsize=8)
    n_seeds = len(rows) // max(len(names), 1)
    what = task if vessel is None else f"{vessel}, {task}"
    fig.suptitle(
        f"{what}: accuracy indices (Tomera 2014 eqs. 54-57), mean and std over {n_seeds} seeds"
    )
    p1 = out / "observers_indices.png"
    fig.savefig(p1, dpi=DPI, format="png")

    fig = _figure("observers_velocity_errors")
    axes = fig.subplots(3, 1, sharex=True)
    units = ("u error (m/s)", "v error (m/s)", "r error (deg/s)")
    for name in names:
        tr = traces.get(name)
        if tr is None:
            continue
        t, e = np.asarray(tr["t"]), np.asarray(tr["err_nu"])
        for k, ax in enumerate(axes):
            scale = 180.0 / math.pi if k == 2 else 1.0
            rms = float(np.sqrt(np.mean(e[:, k] ** 2))) * scale
            ax.plot(t, e[:, k] * scale, lw=0.8, label=f"{name} (RMSE {rms:.3g})")
    for ax, unit in zip(axes, units, strict=True):
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=len(names))
    axes[-1].set_xlabel("time (s)")
    fig.suptitle(f"{what}, seed {seed}: velocity estimation error (estimate - truth)")
    p2 = out / "observers_velocity_errors.png"
    fig.savefig(p2, dpi=DPI, format="png")
    return [p1, p2]
