"""PNG and Markdown reports of a recorded run (Tomera 2014 Figs. 8-11), headless.

Public names: ``DPI``, ``FIGURE_SIZES``, ``pixel_size``, ``report_paths``, ``write_report``.

Design notes: docs/design/viz.report.md.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .geometry import REFERENCE_LENGTH, hull_length, hull_polygon
from .run import Run, indices_warning, load_results, load_run, recording_problem

os.environ.setdefault("MPLBACKEND", "Agg")  # headless by default, whatever imports pyplot later

__all__ = [
    "DPI",
    "FIGURE_SIZES",
    "pixel_size",
    "report_paths",
    "results_markdown",
    "write_report",
    "write_results_report",
]

#: Resolution of the PNG files (dots per inch).
DPI = 100
#: Figure sizes (inches, width x height); pixels = inches * DPI.
FIGURE_SIZES: dict[str, tuple[float, float]] = {
    "trajectory": (8.0, 10.0),
    "positions": (10.0, 8.0),
    "velocities": (10.0, 8.0),
    "thrusters": (12.0, 8.0),
}
_FILES = ("trajectory.png", "positions.png", "velocities.png", "thrusters.png", "metrics.md")
_DEG = 180.0 / math.pi

_C_DES = "#222222"
_C_MEAS = "#1f77b4"
_C_TRUE = "#2ca02c"
_C_EST = "#d62728"
_C_HULL = "#1a3d6d"
_C_QUAY = "#8c8c84"
_C_WATER = "#e3eef7"
_C_SAT = "#ff7f0e"


def pixel_size(name: str) -> tuple[int, int]:
    """``(width, height)`` in pixels of the report figure ``name`` (e.g. ``"trajectory"``)."""
    w, h = FIGURE_SIZES[name]
    return round(w * DPI), round(h * DPI)


def report_paths(out_dir: str | os.PathLike[str]) -> list[Path]:
    """The files :func:`write_report` writes into ``out_dir``, in order."""
    return [Path(out_dir) / f for f in _FILES]


def _figure(name: str) -> Any:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=FIGURE_SIZES[name], dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _save(fig: Any, path: Path) -> Path:
    from shipgym._io import atomic_path

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=DPI, format="png")  # no bbox_inches: the pixel size stays fixed
    return path


def _title(run: Run) -> str:
    m = run.metadata
    parts = [str(m.get("scenario") or m.get("env_id") or "run")]
    if m.get("seed") is not None:
        parts.append(f"seed {m['seed']}")
    parts.append(f"observer {m.get('observer', '?')}, controller {m.get('controller', '?')}")
    if recording_problem(run) is not None:
        parts.append("INCOMPLETE recording")
    return f"{run.vessel_title}: " + ", ".join(parts)


def _scale(run: Run) -> float:
    """Lengths on the map are given for a 13.78 m hull (the Blue Lady) and scale with L_oa."""
    length = float(run.vessel.get("L_oa") or hull_length(run.hull) or REFERENCE_LENGTH)
    return length / REFERENCE_LENGTH


def _label(name: str) -> str:
    """An actuator or channel name for a plot (``bow_tunnel`` -> ``bow tunnel``)."""
    return name.replace("_", " ")


def _wind_text(run: Run) -> str | None:
    w = run.metadata.get("wind")
    if not w:
        return None
    return f"$V_w$ = {w['speed']:.1f} m/s, $\\gamma_{{wa}}$ = {w['from_deg']:.0f}°"


def _leg_marks(ax: Any, run: Run, top: bool) -> None:
    """Dotted lines at the leg switches, leg numbers on the top axis."""
    if len(run.leg) == 0:
        return
    change = np.flatnonzero(np.diff(run.leg) != 0) + 1
    for i in change:
        ax.axvline(run.t[i], color="0.6", lw=0.8, ls=":", zorder=0)
    if top:
        starts = np.concatenate([[0], change])
        ends = np.concatenate([change, [len(run.t) - 1]])
        for s, e in zip(starts, ends, strict=True):
            mid = 0.5 * (run.t[s] + run.t[e])
            ax.text(
                mid,
                1.02,
                f"leg {int(run.leg[s]) + 1}",
                transform=ax.get_xaxis_transform(),
                ha="center",
                va="bottom",
                fontsize=8,
                color="0.35",
            )


# ---- trajectory -------------------------------------------------------------------------------
def _plot_trajectory(run: Run, path: Path, hull_every: float) -> Path:
    """Map in (east, north) axes: x (north) up, y (east) right, equal scale."""
    from matplotlib.patches import Polygon

    fig = _figure("trajectory")
    k = _scale(run)
    ax = fig.add_subplot()
    ax.set_facecolor(_C_WATER)
    harbour = len(run.quays) > 0
    for q in run.quays:  # corners (north, east) -> drawn as (east, north)
        ax.add_patch(Polygon(q[:, ::-1], closed=True, fc=_C_QUAY, ec="0.3", lw=0.8, zorder=2))
    eta = run.eta
    extent = [p for p in (run.quays.reshape(-1, 2), eta[:, :2], run.eta_d[:, :2]) if len(p)]
    if len(run.waypoints):
        wp = run.waypoints
        ax.plot(
            wp[:, 1],
            wp[:, 0],
            ls="none",
            marker="o",
            ms=4,
            color="#ff7f0e",
            zorder=9,
            label="leg end points",
        )
        groups: dict[tuple[float, float], list[str]] = {}
        for i, (x, y) in enumerate(wp[:, :2].tolist()):
            groups.setdefault((round(x, 2), round(y, 2)), []).append("P" if i == 0 else str(i))
        for (x, y), names in groups.items():
            ax.annotate(
                ", ".join(names),
                (y, x),
                xytext=(5, 4),
                textcoords="offset points",
                fontsize=8,
                color="#b35900",
                fontweight="bold",
                zorder=10,
            )
    if len(run.eta_d):
        ax.plot(
            run.eta_d[:, 1],
            run.eta_d[:, 0],
            "--",
            color="#ff7f0e",
            lw=1.2,
            zorder=8,
            label="desired path",
        )
    ax.plot(eta[:, 1], eta[:, 0], "-", color=_C_TRUE, lw=1.3, zorder=5, label="true path")
    if np.any(np.abs(run.nav_eta[:, :2] - eta[:, :2]) > 1e-9):
        ax.plot(
            run.nav_eta[:, 1],
            run.nav_eta[:, 0],
            ":",
            color=_C_EST,
            lw=1.2,
            zorder=5,
            label="estimated path",
        )
    if len(run.hull):
        for n, i in enumerate(_hull_indices(run.t, hull_every)):
            poly = hull_polygon(run.hull, eta[i])
            extent.append(poly)
            label = f"hull every {hull_every:g} s" if n == 0 else None
            ax.add_patch(
                Polygon(
                    poly[:, ::-1],
                    closed=True,
                    fc="none",
                    ec=_C_HULL,
                    lw=0.7,
                    alpha=0.8,
                    zorder=6,
                    label=label,
                )
            )
        ends = (
            (0, "A start" if harbour else "start", "#9ecae1"),
            (len(eta) - 1, "B end" if harbour else "end", "#fdd0a2"),
        )
        for i, name, fc in ends:
            poly = hull_polygon(run.hull, eta[i])
            extent.append(poly)
            ax.add_patch(
                Polygon(poly[:, ::-1], closed=True, fc=fc, ec=_C_HULL, lw=1.4, alpha=0.85, zorder=3)
            )
            # label on the aft half of the hull, clear of the leg end point at the centre
            psi = float(eta[i, 2])
            aft = 3.2 * k
            cx, cy = eta[i, 0] - aft * math.cos(psi), eta[i, 1] - aft * math.sin(psi)
            ax.text(
                cy,
                cx,
                name,
                ha="center",
                va="center",
                fontsize=7.5,
                zorder=8,
                rotation=_text_angle(psi),
                rotation_mode="anchor",
            )
    allp = np.vstack(extent)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    margin = (3.0 if harbour else 5.0) * k
    ax.set_xlim(lo[1] - margin, hi[1] + margin)
    ax.set_ylim(lo[0] - margin, hi[0] + margin + 6.0 * k)  # room for the wind arrow
    ax.set_aspect("equal", adjustable="box")
    wind = _wind_text(run)
    w = run.metadata.get("wind")
    if wind and w:
        to = math.radians(w["from_deg"]) + math.pi  # where the wind blows to
        start = np.array([0.12, 0.94])
        vec = 0.07 * np.array([math.sin(to), math.cos(to)])  # (east, north) in axes fractions
        ax.annotate(
            "",
            xy=start + vec,
            xytext=start - vec,
            xycoords="axes fraction",
            zorder=9,
            arrowprops={"arrowstyle": "-|>", "lw": 2.0, "color": "#3182bd"},
        )
        ax.text(
            0.22,
            0.94,
            "wind\n" + wind,
            transform=ax.transAxes,
            va="center",
            fontsize=9,
            bbox={"fc": "white", "ec": "0.7", "alpha": 0.85},
            zorder=9,
        )
    ax.text(
        0.97,
        0.97,
        "N ↑",
        transform=ax.transAxes,
        ha="right",
        va="top",
        fontsize=11,
        fontweight="bold",
        zorder=9,
    )
    ax.set_xlabel("y, east (m)")
    ax.set_ylabel("x, north (m)")
    ax.grid(True, color="white", lw=0.6, zorder=1)
    ax.set_axisbelow(True)
    ax.legend(loc="lower left", fontsize=8, framealpha=0.9)
    ax.set_title(_title(run), fontsize=10)
    return _save(fig, path)


def _text_angle(psi: float) -> float:
    """Text rotation (deg, counter-clockwise on screen) along a hull of heading psi (rad)."""
    a = 90.0 - math.degrees(psi)
    a = (a + 90.0) % 180.0 - 90.0
    return a


def _hull_indices(t: NDArray[np.float64], every: float) -> list[int]:
    """Rows at t = 0, every, 2 every, ... (first row at or after each multiple)."""
    if not every or every <= 0 or len(t) == 0:
        return []
    out: list[int] = []
    nxt = t[0]
    for i, ti in enumerate(t.tolist()):
        if ti >= nxt - 1e-9:
            out.append(i)
            nxt = (math.floor(ti / every + 1e-9) + 1) * every
    return out


# ---- time series ------------------------------------------------------------------------------
def _plot_positions(run: Run, path: Path) -> Path:
    fig = _figure("positions")
    roll = len(run.roll) == len(run.t) and len(run.t) > 0
    axes = fig.subplots(3 + roll, 1, sharex=True)
    labels = (r"$x^r$ (m)", r"$y^r$ (m)", r"$\psi^r$ (deg)")
    scale = (1.0, 1.0, _DEG)
    if roll:
        _plot_roll(axes[3], run, 0, r"$\phi$ (deg)")
    for k, ax in enumerate(axes[:3]):
        s = scale[k]
        ax.plot(run.t, run.eta_r[:, k] * s, color=_C_TRUE, lw=0.9, alpha=0.8, label="true")
        if len(run.meas_t):
            ax.plot(
                run.meas_t, run.meas_z_r[:, k] * s, "-", color=_C_MEAS, lw=1.0, label="measured"
            )
        ax.plot(run.t, run.eta_d_r[:, k] * s, "--", color=_C_DES, lw=1.4, label="desired")
        ax.set_ylabel(labels[k])
        ax.grid(True, alpha=0.3)
        _leg_marks(ax, run, top=k == 0)
    axes[0].legend(loc="upper right", fontsize=8, ncols=3)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle(
        _title(run) + "\nposition in the r-frame: desired (dashed), measured (solid)", fontsize=10
    )
    return _save(fig, path)


def _plot_velocities(run: Run, path: Path) -> Path:
    fig = _figure("velocities")
    roll = len(run.roll) == len(run.t) and len(run.t) > 0
    axes = fig.subplots(3 + roll, 1, sharex=True)
    labels = ("u (m/s)", "v (m/s)", "r (deg/s)")
    scale = (1.0, 1.0, _DEG)
    nu_d = run.nu_d
    differs = bool(len(run.nu)) and bool(np.any(np.abs(run.nav_nu - run.nu) > 1e-12))
    if roll:
        _plot_roll(axes[3], run, 1, "p (deg/s)")
    for k, ax in enumerate(axes[:3]):
        s = scale[k]
        ax.plot(run.t, run.nu[:, k] * s, color=_C_TRUE, lw=0.9, alpha=0.8, label="true")
        if differs:
            ax.plot(run.t, run.nav_nu[:, k] * s, "-", color=_C_EST, lw=1.0, label="estimated")
        ax.plot(run.t, nu_d[:, k] * s, "--", color=_C_DES, lw=1.4, label="desired")
        ax.set_ylabel(labels[k])
        ax.grid(True, alpha=0.3)
        _leg_marks(ax, run, top=k == 0)
    axes[0].legend(loc="upper right", fontsize=8, ncols=3)
    axes[-1].set_xlabel("t (s)")
    est = "estimated (solid)" if differs else "true (solid; controller used the truth)"
    fig.suptitle(_title(run) + f"\nbody velocity: desired (dashed), {est}", fontsize=10)
    return _save(fig, path)


def _plot_roll(ax: Any, run: Run, col: int, label: str) -> None:
    """The true roll angle (``col`` 0) or rate (1) of a 4-DOF vessel, in degrees."""
    ax.plot(run.t, run.roll[:, col] * _DEG, color=_C_TRUE, lw=0.9, label="true")
    ax.set_ylabel(label)
    ax.grid(True, alpha=0.3)
    _leg_marks(ax, run, top=False)


def _spans(flags: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """Index ranges ``[start, end)`` of consecutive True flags."""
    f = np.concatenate([[False], np.asarray(flags, dtype=bool), [False]])
    d = np.diff(f.astype(np.int8))
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1), strict=True))


def _plot_thrusters(run: Run, path: Path) -> Path:
    """One row per actuator: its channel commands (left), its thrust (right)."""
    fig = _figure("thrusters")
    acts = run.actuators
    names, colours = acts["names"], acts["colours"]
    owner = list(acts["channel_actuator"])
    units, state_units = acts["units"], acts["state_units"]
    n = len(names)
    axes = fig.subplots(n, 2, sharex=True, squeeze=False)
    t = run.t
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
    limits = run.metadata.get("command_limits")
    for i in range(n):
        ax_c, ax_f = axes[i]
        cols = [j for j, o in enumerate(owner) if o == i]
        colour = colours[i]
        for m, j in enumerate(cols):
            ax = ax_c if m == 0 else ax_c.twinx()
            ls = "-" if m == 0 else "--"
            ax.step(t, run.command[:, j], where="pre", color="#444444" if m == 0 else colour,
                    lw=1.0, ls=ls)  # fmt: skip
            if limits and j < len(limits[0]):
                for lim in (limits[0][j], limits[1][j]):
                    ax.axhline(lim, color="#d62728", lw=0.8, ls=":")
            ax.set_ylabel(f"{_label(acts['channels'][j])} ({units[j]})", fontsize=8)
        ax_f.plot(t, run.thrust[:, i], color=colour, lw=1.0)
        angles = [j for j in cols if state_units[j] == "rad"]
        if angles and run.actuator_state.shape[1] > max(angles):
            ax_a = ax_f.twinx()
            for j in angles:
                ax_a.plot(t, run.actuator_state[:, j] * _DEG, color="0.4", lw=0.9, ls="--")
            ax_a.set_ylabel("angle (deg, dashed)", fontsize=8)
        sat = np.any(run.saturated[:, cols], axis=1) if cols else np.zeros(len(t), bool)
        for a, b in _spans(sat):
            t0 = t[a] - dt
            t1 = t[b - 1]
            for ax in (ax_c, ax_f):
                ax.axvspan(t0, t1, color=_C_SAT, alpha=0.25, lw=0, zorder=0)
        ax_f.set_ylabel(f"$F_{{{i + 1}}}$ (N)")
        ax_c.set_title(f"{_label(names[i])}: command", fontsize=9, loc="left")
        ax_f.set_title(f"{_label(names[i])}: thrust", fontsize=9, loc="left")
        for ax in (ax_c, ax_f):
            ax.grid(True, alpha=0.3)
            ax.axhline(0.0, color="0.5", lw=0.6)
    for ax in axes[-1]:
        ax.set_xlabel("t (s)")
    fig.suptitle(
        _title(run) + "\nactuators (dotted: command limits; shaded: saturated)", fontsize=10
    )
    return _save(fig, path)


# ---- metrics ----------------------------------------------------------------------------------
def _fmt(x: Any, nd: int = 4) -> str:
    try:
        f = float(x)
    except (TypeError, ValueError):
        return "n/a"
    return f"{f:.{nd}f}" if math.isfinite(f) else "n/a"


def _metrics_markdown(run: Run, files: list[Path]) -> str:
    m = run.metrics or {}
    meta = run.metadata or {}
    acc = run.accuracy[-1] if len(run.accuracy) else np.full(4, np.nan)
    acc_m = run.accuracy_measured[-1] if len(run.accuracy_measured) else np.full(4, np.nan)
    keys = ("x_E", "y_E", "psi_E", "J_c")
    truth = {k: m.get(k, acc[i]) for i, k in enumerate(keys)}
    meas_src = m.get("measured") or {k: acc_m[i] for i, k in enumerate(keys)}
    wind = meta.get("wind")
    wind_txt = "none" if not wind else f"{wind['speed']:.1f} m/s from {wind['from_deg']:.0f} deg"
    duration = m.get("duration_s", float(run.t[-1]) if len(run.t) else float("nan"))
    problem = recording_problem(run)
    lines = [f"# Run report: {meta.get('scenario', 'run')}", ""]
    if problem is not None:
        lines += [
            f"**INCOMPLETE RECORDING**: {problem}; the figures and indices cover the "
            f"{run.n_steps} control steps recorded, not a whole episode.",
            "",
        ]
    lines += [
        "| | |",
        "|---|---|",
        f"| env id | `{meta.get('env_id')}` |",
        f"| vessel | {run.vessel_title} |",
        f"| seed | {meta.get('seed')} |",
        f"| observer | {meta.get('observer')} |",
        f"| controller | {meta.get('controller')} |",
        f"| wind | {wind_txt} |",
        f"| plan | {meta.get('plan')} |",
        f"| control steps | {run.n_steps} |",
        f"| duration | {_fmt(duration, 1)} s |",
        f"| completed | {m.get('completed', 'n/a')} "
        f"({m.get('legs_completed', int(run.legs_completed[-1]) if len(run.t) else 0)} legs) |",
        f"| quay contact | {m.get('quay_contact', 'n/a')} |",
        "",
        *_indices_table(truth, meas_src),
        *([w, ""] if (w := indices_warning(m, meta)) else []),
        "## Legs",
        "",
        "| leg | name | started at (s) | completed at (s) | duration (s) |",
        "|---|---|---|---|---|",
    ]
    names = meta.get("legs") or []
    completed = _leg_completions(run)
    n_legs = max(len(names), len(completed), int(run.leg.max()) + 1 if len(run.leg) else 0)
    start = float(run.t[0]) if len(run.t) else 0.0
    for i in range(n_legs):
        name = names[i] if i < len(names) else ""
        if i < len(completed):
            end = completed[i]
            row = f"{_fmt(start, 1)} | {_fmt(end, 1)} | {_fmt(end - start, 1)}"
            start = end
        elif len(run.leg) and i == int(run.leg[-1]):
            row = f"{_fmt(start, 1)} | not completed | > {_fmt(float(run.t[-1]) - start, 1)}"
        else:
            row = "not started | | "
        lines.append(f"| {i + 1} | {name} | {row} |")
    act_names = run.actuator_names
    owner = np.asarray(run.actuators["channel_actuator"], dtype=int)
    per_actuator = np.column_stack(
        [np.any(run.saturated[:, owner == i], axis=1) for i in range(len(act_names))]
    ) if len(run.t) else np.zeros((0, len(act_names)), bool)  # fmt: skip
    mean_abs = m.get("thrust_mean_abs") or np.mean(np.abs(run.thrust), axis=0).tolist()
    tv = m.get("thrust_total_variation") or np.abs(np.diff(run.thrust, axis=0)).sum(0).tolist()
    sat_f = m.get("saturated_fraction") or per_actuator.mean(axis=0).tolist()
    sat_t = m.get("saturated_time") or [float("nan")] * len(act_names)
    lines += _thrusters_table([_label(a) for a in act_names], mean_abs, tv, sat_f, sat_t)
    lines += _chatter_table(_channel_labels(run), m)
    lines += ["", "## Figures", ""]
    lines += [f"- [{p.name}]({p.name})" for p in files]
    return "\n".join(lines) + "\n"


def _indices_table(truth: dict[str, Any], measured: dict[str, Any]) -> list[str]:
    """The accuracy indices of Tomera (2014) eqs. 54-57 as markdown lines, from the truth and
    from the measurements."""
    keys = ("x_E", "y_E", "psi_E", "J_c")
    return [
        "## Accuracy indices (Tomera 2014 eqs. 54-57, r-frame, sampled at 1 s)",
        "",
        "| from | x_E (m) | y_E (m) | psi_E (deg) | J_c |",
        "|---|---|---|---|---|",
        "| truth | " + " | ".join(_fmt(truth.get(k)) for k in keys) + " |",
        "| measurements | " + " | ".join(_fmt(measured.get(k)) for k in keys) + " |",
        "",
        "J_c = x_E + y_E + 0.01 psi_E.",
        "",
    ]


def _thrusters_table(names: list[str], mean_abs: Any, tv: Any, sat_f: Any, sat_t: Any) -> list[str]:
    """Each actuator's thrust statistics as markdown lines (a value missing: n/a)."""
    lines = [
        "",
        "## Thrusters",
        "",
        "| actuator | mean abs F (N) | total variation (N) | saturated fraction | "
        "saturated time (s) |",
        "|---|---|---|---|---|",
    ]
    for i, name in enumerate(names):
        cells = [_fmt(_at(mean_abs, i), 2), _fmt(_at(tv, i), 1), _fmt(_at(sat_f, i), 3),
                 _fmt(_at(sat_t, i), 1)]  # fmt: skip
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return lines


def _chatter_table(names: list[str], m: dict[str, Any]) -> list[str]:
    """Each command channel's chatter (:func:`shipgym.metrics.command_chatter`) as markdown
    lines; none without the metrics."""
    if not m.get("reversals_per_min"):
        return []
    lines = [
        "",
        "## Command chatter",
        "",
        "Per channel, from the normalised commands (shipgym.metrics.command_chatter): "
        "reversals of the command's direction through a band of 2 % around zero, starts "
        "(leaving that band after a stop), time inside it (at zero), time at a command "
        "limit, share of the detrended command's variance at periods below 20 s, command "
        "travel.",
        "",
        "| channel | reversals / min | starts / min | at zero | at a limit | variance < 20 s "
        "| travel (1/min) |",
        "|---|---|---|---|---|---|---|",
    ]
    for j, name in enumerate(names):
        lines.append(
            f"| {name} | {_fmt(_at(m['reversals_per_min'], j), 2)} | "
            f"{_fmt(_at(m.get('starts_per_min'), j), 2)} | "
            f"{_fmt(_at(m.get('zero_fraction'), j), 3)} | "
            f"{_fmt(_at(m.get('limit_fraction'), j), 3)} | "
            f"{_fmt(_at(m.get('hf_variance_fraction'), j), 3)} | "
            f"{_fmt(_at(m.get('travel_per_min'), j), 2)} |"
        )
    return lines


def _at(values: Any, i: int) -> Any:
    """``values[i]``, or ``None`` where the list is missing or shorter."""
    try:
        return values[i]
    except (TypeError, IndexError, KeyError):
        return None


def _channel_labels(run: Run) -> list[str]:
    """The run's command channels labelled ``actuator`` (or ``actuator: channel index``)."""
    acts = run.actuators
    names = [_label(a) for a in acts["names"]]
    owner = [int(o) for o in acts["channel_actuator"]]
    out = []
    for j, o in enumerate(owner):
        k = owner[:j].count(o)
        out.append(names[o] if owner.count(o) == 1 else f"{names[o]} ({k + 1})")
    return out


def _leg_completions(run: Run) -> list[float]:
    """Times (s) at which ``legs_completed`` reached 1, 2, ... (from the recorded steps)."""
    out: list[float] = []
    done = run.legs_completed
    for k in range(1, int(done.max()) + 1 if len(done) else 1):
        i = np.flatnonzero(done >= k)
        if len(i):
            out.append(float(run.t[i[0]]))
    return out


def write_report(
    run_or_path: Run | str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    hull_every: float = 60.0,
) -> list[Path]:
    """Write the PNG figures and ``metrics.md`` of a run (no display needed).

    Args:
        run_or_path: a :class:`Run`, or a ``.rrd`` / ``.json`` run file (:func:`load_run`).
        out_dir: output folder (created).
        hull_every: period of the hull outlines on the trajectory map (s).

    Returns:
        The files written: ``trajectory.png``, ``positions.png``, ``velocities.png``,
        ``thrusters.png`` (sizes :func:`pixel_size`) and ``metrics.md``.

    Raises:
        ValueError: an unreadable run file, a run without any step, or an unusable folder.
    """
    run = run_or_path if isinstance(run_or_path, Run) else load_run(run_or_path)
    if len(run.t) == 0:
        raise ValueError("the run holds no control step: nothing to report")
    if not (isinstance(hull_every, int | float) and math.isfinite(hull_every)):
        raise ValueError(f"hull_every must be a finite number of seconds, got {hull_every!r}")
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"cannot create the report folder {out}: {exc.strerror or exc}") from None
    from shipgym._io import replace_together

    return replace_together(report_files(run, out, hull_every=float(hull_every)))


def results_markdown(res: dict[str, Any]) -> str:
    """``metrics.md`` of the results of ``shipgym run --json`` (the episode's metrics and what
    ran, no time series): the run, the accuracy indices, the legs, the station-keeping
    summary, the thrusters, the command chatter and the estimation errors."""
    ves = res.get("vessel") or {}
    wind = res.get("wind")
    wind_txt = "none" if not wind else f"{wind['speed']:.1f} m/s from {wind['from_deg']:.0f} deg"
    cur = res.get("current")
    cur_txt = ("none" if not cur or not cur.get("speed")
               else f"{cur['speed']:.2f} m/s going to {cur['to_deg']:.0f} deg")  # fmt: skip
    lines = [
        f"# Run results: {res.get('scenario', 'run')}",
        "",
        "The results of `shipgym run --json`: the episode's metrics, no time series (record the "
        "run with `--record RUN.rrd` for the figures: `shipgym report RUN.rrd`).",
        "",
        "| | |",
        "|---|---|",
        f"| env id | `{res.get('env_id')}` |",
        f"| vessel | {ves.get('title', ves.get('name', 'n/a'))} |",
        f"| seed | {res.get('seed')} |",
        f"| observer | {res.get('observer')} |",
        f"| controller | {res.get('controller')} |",
        f"| plant | {res.get('plant')} |",
        f"| wind | {wind_txt} |",
        f"| current | {cur_txt} |",
        f"| duration | {_fmt(res.get('duration_s'), 1)} s |",
        f"| completed | {res.get('completed', 'n/a')} ({res.get('legs_completed', 0)} legs) |",
        f"| quay contact | {res.get('quay_contact', 'n/a')} |",
        "",
        *_indices_table(res, res.get("measured") or {}),
    ]
    if res.get("indices_note"):
        lines += [f"**These indices do not describe a whole run**: {res['indices_note']}.", ""]
    legs = res.get("leg_times") or []
    if legs:
        lines += ["## Legs", "", "| leg | completed at (s) | duration (s) |", "|---|---|---|"]
        start = 0.0
        for i, end in enumerate(legs):
            lines.append(f"| {i + 1} | {_fmt(end, 1)} | {_fmt(end - start, 1)} |")
            start = end
    sk = res.get("station_keeping")
    if sk:
        lines += ["", "## Station keeping", "", "| | |", "|---|---|"]
        lines += [f"| {k} | {_fmt(v, 3) if not isinstance(v, str) else v} |" for k, v in sk.items()]
    acts = ves.get("actuators") or [f"actuator {i + 1}" for i in
                                    range(len(res.get("thrust_mean_abs") or []))]  # fmt: skip
    lines += _thrusters_table([_label(a) for a in acts], res.get("thrust_mean_abs"),
                              res.get("thrust_total_variation"), res.get("saturated_fraction"),
                              res.get("saturated_time"))  # fmt: skip
    chans = ves.get("channels") or [f"channel {j + 1}" for j in
                                    range(len(res.get("reversals_per_min") or []))]  # fmt: skip
    lines += _chatter_table([_label(c) for c in chans], res)
    rmse = res.get("rmse")
    if rmse:
        units = {"x": "m", "y": "m", "psi": "deg", "u": "m/s", "v": "m/s", "r": "deg/s"}
        lines += ["", "## Estimation errors (RMS, estimate minus truth)", "",
                  "| " + " | ".join(f"{k} ({units.get(k, '')})" for k in rmse) + " |",
                  "|" + "---|" * len(rmse),
                  "| " + " | ".join(_fmt(v) for v in rmse.values()) + " |"]  # fmt: skip
    return "\n".join(lines) + "\n"


def write_results_report(
    results_or_path: dict[str, Any] | str | os.PathLike[str], out_dir: str | os.PathLike[str]
) -> list[Path]:
    """Write ``metrics.md`` of the results of ``shipgym run --json`` (:func:`results_markdown`)
    into ``out_dir`` (created): what those results allow; the figures need a recording.

    Returns:
        ``[out_dir / "metrics.md"]``.

    Raises:
        ValueError: an unreadable file, one that is not such results, or an unusable folder.
    """
    res = results_or_path if isinstance(results_or_path, dict) else load_results(results_or_path)
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"cannot create the report folder {out}: {exc.strerror or exc}") from None
    from shipgym._io import atomic_write_text

    return [atomic_write_text(out / "metrics.md", results_markdown(res))]


def report_files(run: Run, out: Path, *, hull_every: float = 60.0) -> list[tuple[Path, Path]]:
    """The report of :func:`write_report` written at partial names (``trajectory.partial.png``
    ...) in the existing folder ``out``: ``(partial, final)`` pairs for
    :func:`shipgym._io.replace_together`, so that a report replaces the earlier one as a
    whole, with the run's other outputs, or not at all. A failed write (a full disk) removes
    the partial files written so far and raises its ``OSError``."""
    from shipgym._io import atomic_write_text, partial_path

    files = report_paths(out)
    parts = [partial_path(f) for f in files]
    try:
        _plot_trajectory(run, parts[0], hull_every)
        _plot_positions(run, parts[1])
        _plot_velocities(run, parts[2])
        _plot_thrusters(run, parts[3])
        atomic_write_text(parts[4], _metrics_markdown(run, files[:4]))
    except BaseException:
        for p in parts:
            p.unlink(missing_ok=True)
        raise
    return list(zip(parts, files, strict=True))
