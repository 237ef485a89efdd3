"""Figures of the rudder-roll stabilisation benchmark (``shipgym bench roll --figures DIR``).

Public names: ``ROLL_SIZES``, ``write_roll_figures``.
Sources: Radhakrishnan (n.d.).

Design notes: docs/design/viz.rrs.md.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .report import DPI

__all__ = ["ROLL_SIZES", "write_roll_figures"]

#: Figure sizes (inches) per vessel panel column, and of one estimates figure; pixels = inches *
#: DPI (the bench figures grow by one panel width per vessel).
ROLL_SIZES: dict[str, tuple[float, float]] = {
    "roll_reduction": (6.0, 4.5),
    "heading_rudder": (6.0, 9.0),
    "stability_margin": (6.0, 4.5),
    "estimates": (12.0, 11.0),
}

#: line colours per method of the bench (others: matplotlib's cycle)
_COLOURS = {
    "autopilot": "0.4",
    "rrs": "#d62728",
    "rrs-sway0.2": "#ff7f0e",
    "rrs-nosway": "#1f77b4",
    "rrs-scheduled": "#2ca02c",
}

_DEG = 180.0 / math.pi


def _figure(name: str, columns: int = 1) -> Any:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    w, h = ROLL_SIZES[name]
    fig = Figure(figsize=(w * columns, h), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _file_name(vessel: str) -> str:
    """A vessel name (or a package path) as a file-name part."""
    stem = Path(vessel).stem if ("/" in vessel or os.sep in vessel) else vessel
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", stem) or "vessel"


def _vessels(rows: Sequence[Mapping[str, Any]], analyses: Mapping[str, Any]) -> list[str]:
    out = list(analyses)
    for r in rows:
        if r["vessel"] not in out:
            out.append(r["vessel"])
    return out


def _methods(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    out: list[str] = []
    for r in rows:
        if r["method"] not in out:
            out.append(r["method"])
    return out


def _by_speed(
    rows: Sequence[Mapping[str, Any]], vessel: str, method: str, key: str, scale: float = 1.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(speeds, mean, std, capsized)`` of ``key`` over the seeds, sorted by speed."""
    groups: dict[float, list[Mapping[str, Any]]] = {}
    for r in rows:
        if r["vessel"] == vessel and r["method"] == method:
            groups.setdefault(float(r["speed"]), []).append(r)
    U = np.array(sorted(groups), dtype=float)
    mean, std, cap = [], [], []
    for u in U:
        vals = [r.get(key) for r in groups[float(u)]]
        a = np.array([scale * float(v) for v in vals if v is not None and math.isfinite(v)])
        mean.append(a.mean() if a.size else math.nan)
        std.append(a.std() if a.size > 1 else 0.0)
        cap.append(any(r.get("capsized") for r in groups[float(u)]))
    return U, np.array(mean), np.array(std), np.array(cap, dtype=bool)


def _plot_metric(
    ax: Any, rows: Sequence[Mapping[str, Any]], vessel: str, method: str, key: str, scale: float
) -> None:
    U, m, s, cap = _by_speed(rows, vessel, method, key, scale)
    if not U.size:
        return
    c = _COLOURS.get(method)
    ax.errorbar(U, m, yerr=s if s.any() else None, color=c, marker="o", ms=3, lw=1.0,
                capsize=2, label=method)  # fmt: skip
    if cap.any():
        ax.plot(U[cap], m[cap], "x", color=c, ms=9, mew=2)


def write_roll_figures(
    rows: Sequence[Mapping[str, Any]],
    analyses: Mapping[str, Mapping[str, Any]],
    traces: Mapping[str, Mapping[str, Any]],
    out_dir: str | os.PathLike[str],
    *,
    title: str = "",
    rate_limits: Mapping[str, float] | None = None,
) -> list[Path]:
    """Write ``roll_reduction.png``, ``heading_rudder.png``, ``stability_margin.png`` and
    ``estimates_<vessel>.png`` (one per vessel in ``traces``).

    Args:
        rows: the bench's rows (:func:`shipgym.rrs.bench.bench_roll`): ``vessel``, ``speed``
            (m/s), ``method``, ``seed``, ``rrr`` (-), ``heading_rms``, ``rudder_rms`` (rad),
            ``rudder_rate_rms`` (rad/s), ``capsized``; mean and standard deviation over the
            seeds are plotted, a capsize marked with a cross.
        analyses: per vessel (the rows' ``vessel``), :func:`shipgym.rrs.bench.roll_analysis`:
            ``speeds`` (m/s), ``margin`` (sway scale -> max Re lambda per speed, 1/s; the scale
            a number or, read back from JSON, its string), ``margin_scheduled``, ``onset``
            (scale -> ``(speed m/s, frequency rad/s)`` or ``None``) and ``design_speed``.
        traces: per vessel, one episode (:func:`shipgym.rrs.bench.roll_trace`): ``t`` (s),
            ``roll``, ``rudder``, ``heading_error`` (rad), ``v``, ``v_hat`` (m/s), ``trace_P``
            (mixed SI units squared), optionally ``speed`` (m/s) and ``method`` for the title.
        out_dir: the folder (created).
        title: the figure titles' prefix.
        rate_limits: per vessel, the rudder's rate limit (rad/s), dashed on the rate panels.

    Returns:
        The written paths.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    vessels = _vessels(rows, analyses)
    if not vessels:
        raise ValueError("write_roll_figures needs rows or analyses of at least one vessel")
    methods = _methods(rows)
    rate_limits = rate_limits or {}
    pre = f"{title}: " if title else ""
    paths: list[Path] = []

    # roll reduction ratio against speed
    fig = _figure("roll_reduction", len(vessels))
    axes = np.atleast_1d(fig.subplots(1, len(vessels), squeeze=False)[0])
    for ax, v in zip(axes, vessels, strict=True):
        for mth in methods:
            if mth != "autopilot":
                _plot_metric(ax, rows, v, mth, "rrr", 1.0)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_title(v)
        ax.set_xlabel("speed U (m/s)")
        ax.set_ylabel("roll reduction ratio RRR (-)")
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    fig.suptitle(f"{pre}RRR = 1 - roll RMS / roll RMS (heading autopilot only); x: capsized")
    paths.append(out / "roll_reduction.png")
    fig.savefig(paths[-1])

    # heading error, rudder and rudder rate against speed
    fig = _figure("heading_rudder", len(vessels))
    axes = fig.subplots(3, len(vessels), squeeze=False, sharex="col")
    panels = (("heading_rms", "heading error RMS (deg)"), ("rudder_rms", "rudder RMS (deg)"),
              ("rudder_rate_rms", "rudder-rate RMS (deg/s)"))  # fmt: skip
    for j, v in enumerate(vessels):
        for i, (key, label) in enumerate(panels):
            ax = axes[i, j]
            for mth in methods:
                _plot_metric(ax, rows, v, mth, key, _DEG)
            if key == "rudder_rate_rms" and v in rate_limits:
                lim = _DEG * float(rate_limits[v])
                ax.axhline(lim, color="k", ls="--", lw=0.9, label=f"rate limit {lim:g} deg/s")
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
        axes[0, j].set_title(v)
        axes[-1, j].set_xlabel("speed U (m/s)")
        if axes[-1, j].get_legend_handles_labels()[0]:
            axes[-1, j].legend(fontsize=8)
    fig.suptitle(f"{pre}heading error, rudder and rudder rate (RMS after the transient)")
    paths.append(out / "heading_rudder.png")
    fig.savefig(paths[-1])

    # linear analysis: stability margin against speed
    fig = _figure("stability_margin", len(vessels))
    axes = np.atleast_1d(fig.subplots(1, len(vessels), squeeze=False)[0])
    sway_colours = ("#d62728", "#ff7f0e", "#1f77b4", "#9467bd")
    for ax, v in zip(axes, vessels, strict=True):
        an = analyses.get(v)
        ax.set_title(v)
        ax.set_xlabel("speed U (m/s)")
        ax.set_ylabel("max Re(lambda) of the closed loop (1/s)")
        ax.grid(alpha=0.3)
        if an is None:
            ax.text(0.5, 0.5, "no linear analysis", ha="center", transform=ax.transAxes)
            continue
        U = np.asarray(an["speeds"], dtype=float)
        onsets = an.get("onset", {})
        for k, (scale, margin) in enumerate(an["margin"].items()):
            c = sway_colours[k % len(sway_colours)]
            o = onsets.get(scale)
            where = "stable on 2-30 m/s" if o is None else f"unstable above {o[0]:.2f} m/s"
            ax.plot(U, margin, color=c, marker="o", ms=3, lw=1.0,
                    label=f"fixed gain, sway x {float(scale):g} ({where})")  # fmt: skip
            if o is not None and U.size and U.min() <= o[0] <= U.max():
                ax.axvline(o[0], color=c, ls=":", lw=1.0)
                ax.plot([o[0]], [0.0], "v", color=c, ms=8)
        ax.plot(U, an["margin_scheduled"], color="#2ca02c", marker="s", ms=3, lw=1.0,
                label="scheduled gain, sway x 1")  # fmt: skip
        ax.axhline(0.0, color="k", lw=0.8)
        ds = an.get("design_speed")
        if ds is not None:
            ax.axvline(float(ds), color="0.5", ls="--", lw=0.8, label=f"design speed {ds:g} m/s")
        ax.legend(fontsize=7)
    fig.suptitle(f"{pre}linear closed loop, LQR of the design speed; > 0: unstable, "
                 "triangles: onset")  # fmt: skip
    paths.append(out / "stability_margin.png")
    fig.savefig(paths[-1])

    # one episode: the seed's Fig. 2 panels
    for v, tr in traces.items():
        fig = _figure("estimates")
        axes = fig.subplots(5, 1, sharex=True)
        t = np.asarray(tr["t"], dtype=float)
        axes[0].plot(t, _DEG * np.asarray(tr["roll"]), color="k", lw=0.9)
        axes[0].set_ylabel("roll phi (deg)")
        axes[1].plot(t, _DEG * np.asarray(tr["rudder"]), color="#d62728", lw=0.9)
        axes[1].set_ylabel("rudder delta (deg)")
        axes[2].plot(t, _DEG * np.asarray(tr["heading_error"]), color="#1f77b4", lw=0.9)
        axes[2].set_ylabel("heading error (deg)")
        axes[3].plot(t, np.asarray(tr["v"]), color="k", lw=1.0, label="true v")
        axes[3].plot(t, np.asarray(tr["v_hat"]), color="#ff7f0e", lw=0.9, ls="--",
                     label="KF v_hat")  # fmt: skip
        axes[3].set_ylabel("sway velocity (m/s)")
        axes[3].legend(fontsize=8, loc="upper right")
        P = np.asarray(tr["trace_P"], dtype=float)
        if (P > 0).all():
            axes[4].semilogy(t, P, color="#9467bd", lw=0.9)
        else:
            axes[4].plot(t, P, color="#9467bd", lw=0.9)
        axes[4].set_ylabel("trace(P) (mixed SI units^2)")
        axes[4].set_xlabel("t (s)")
        for ax in axes:
            ax.grid(alpha=0.3)
        what = []
        if "method" in tr:
            what.append(str(tr["method"]))
        if "speed" in tr:
            what.append(f"U = {float(tr['speed']):g} m/s")
        cap = " (capsized)" if tr.get("capsized") else ""
        fig.suptitle(f"{pre}{v}{', ' if what else ''}{', '.join(what)}{cap}: roll, rudder, "
                     "heading, sway velocity and its estimate, trace(P)")  # fmt: skip
        paths.append(out / f"estimates_{_file_name(v)}.png")
        fig.savefig(paths[-1])
    return paths
