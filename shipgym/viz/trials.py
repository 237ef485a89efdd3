"""Figures of a sea trial and of the DGPS receiver's bias (Artyszuk 2003 Figs. 2-7).

- :func:`plot_tracks`: the midship tracks of trials in ship lengths (north up, east right),
  optionally with ship outlines along them;
- :func:`plot_bias`: speed, drift angle and position error against time, the truth and the
  receiver's estimate for each ``S_p`` (the seed's Figs. 2-7);
- :func:`plot_histories`: speed, drift angle and rudder against time of trials;
- :func:`plot_current`: with a current, the tracks and drift angles over ground next to the
  water-referenced ones (the ITTC way; Artyszuk 2003 Fig. 1);
- :func:`write_trial_figures`: all of them for a ``shipgym trials`` study.

Inputs in SI (m, rad, m/s, s); angles are plotted in degrees. matplotlib is imported inside
the functions (Agg canvas, no display needed). Each function returns the Figure and saves it
when given a path.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .report import DPI

__all__ = ["plot_bias", "plot_current", "plot_histories", "plot_tracks", "write_trial_figures"]

_DEG = 180.0 / math.pi


def _figure(size: tuple[float, float]) -> Any:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _saved(fig: Any, path: str | os.PathLike[str] | None) -> Any:
    """``fig``, saved as a PNG at ``path`` first when one is given."""
    if path is not None:
        fig.savefig(path, dpi=DPI)
    return fig


def _outline(x: float, y: float, psi: float, L: float, B: float) -> np.ndarray:
    """A ship outline (pointed bow) of length ``L`` and beam ``B`` at midship ``(x, y)``."""
    body = np.array([[0.5, 0.0], [0.3, 0.5], [-0.5, 0.5], [-0.5, -0.5], [0.3, -0.5], [0.5, 0.0]])
    body = body * [L, B]
    c, s = math.cos(psi), math.sin(psi)
    return np.c_[x + c * body[:, 0] - s * body[:, 1], y + s * body[:, 0] + c * body[:, 1]]


def plot_tracks(
    tracks: Mapping[str, ArrayLike],
    L: float,
    *,
    path: str | os.PathLike[str] | None = None,
    outlines: int = 0,
    beam: float | None = None,
    title: str = "",
) -> Any:
    """The tracks of trials in ship lengths.

    Args:
        tracks: label -> the midship pose ``eta`` (n, 3) (m, m, rad), north ``x``, east ``y``.
        L: ship length (m), the unit of the axes.
        path: save the figure there (PNG) when given.
        outlines: ship outlines drawn per track, evenly in sample index (0 none).
        beam: the outline's beam (m; default ``L / 5.5``, a tanker's ratio [chosen]).
        title: the figure title.

    Returns:
        The matplotlib Figure.
    """
    if not (math.isfinite(L) and L > 0):
        raise ValueError(f"L must be > 0 m, got {L!r}")
    B = L / 5.5 if beam is None else float(beam)
    fig = _figure((6.5, 6.5))
    ax = fig.add_subplot(1, 1, 1)
    for label, eta in tracks.items():
        e = np.asarray(eta, dtype=float)
        if e.ndim != 2 or e.shape[1] != 3:
            raise ValueError(f"track {label!r}: eta must be (n, 3), got {e.shape}")
        (line,) = ax.plot(e[:, 1] / L, e[:, 0] / L, lw=1.2, label=label)
        if outlines > 0:
            for i in np.linspace(0, e.shape[0] - 1, outlines).astype(int):
                o = _outline(e[i, 0], e[i, 1], e[i, 2], L, B) / L
                ax.plot(o[:, 1], o[:, 0], color=line.get_color(), lw=0.8)
    ax.set_xlabel("east y / L")
    ax.set_ylabel("north x / L")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    if tracks:
        ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    return _saved(fig, path)


def plot_bias(
    t: ArrayLike,
    truth: Mapping[str, ArrayLike],
    estimates_by_Sp: Mapping[float, Mapping[str, ArrayLike]],
    *,
    path: str | os.PathLike[str] | None = None,
    title: str = "",
) -> Any:
    """Speed, drift angle and position error against time, truth and estimates (the seed's
    Figs. 2-7).

    Args:
        t: sample times (s), (n,).
        truth: ``v_xy`` (m/s) and ``beta_A`` (rad), (n,) each
            (:attr:`shipgym.trials.bias.ReceiverBias.truth`).
        estimates_by_Sp: ``S_p`` (m^2/s^3) -> ``v_xy``, ``beta_A`` and ``position_error`` (m)
            of the receiver's estimate (:attr:`~shipgym.trials.bias.ReceiverBias.estimate`).
        path: save the figure there (PNG) when given.
        title: the figure title.

    Returns:
        The matplotlib Figure (three panels).
    """
    tt = np.asarray(t, dtype=float)
    fig = _figure((8.0, 9.0))
    axes = [fig.add_subplot(3, 1, i + 1) for i in range(3)]
    axes[0].plot(tt, np.asarray(truth["v_xy"]), "k", lw=1.6, label="truth")
    axes[1].plot(tt, np.asarray(truth["beta_A"]) * _DEG, "k", lw=1.6, label="truth")
    for S_p, est in estimates_by_Sp.items():
        lab = f"KF S_p = {S_p:g}"
        axes[0].plot(tt, np.asarray(est["v_xy"]), lw=1.0, label=lab)
        axes[1].plot(tt, np.asarray(est["beta_A"]) * _DEG, lw=1.0, label=lab)
        axes[2].plot(tt, np.asarray(est["position_error"]), lw=1.0, label=lab)
    for ax, yl in zip(axes, ("speed v_xy (m/s)", "drift angle beta_A (deg)",
                             "position error (m)"), strict=True):  # fmt: skip
        ax.set_ylabel(yl)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    axes[-1].set_xlabel("time (s)")
    if title:
        fig.suptitle(title)
    return _saved(fig, path)


def plot_histories(records: Mapping[str, Any], *, path: str | os.PathLike[str] | None = None,
                   title: str = "") -> Any:  # fmt: skip
    """Drift angle, speed and rudder angle against time of trials (the seed's Fig. 1 style).

    Args:
        records: label -> a :class:`~shipgym.envs.seatrial.TrialRecord` (or anything with
            ``t``, ``nu`` (n, 3) over ground and ``rudder`` (n,)).
        path: save the figure there (PNG) when given.
        title: the figure title.
    """
    fig = _figure((8.0, 8.0))
    axes = [fig.add_subplot(3, 1, i + 1) for i in range(3)]
    for label, rec in records.items():
        t = np.asarray(rec.t)
        nu = np.asarray(rec.nu)
        axes[0].plot(t, np.hypot(nu[:, 0], nu[:, 1]), lw=1.0, label=label)
        axes[1].plot(t, np.degrees(np.arctan2(-nu[:, 1], nu[:, 0])), lw=1.0, label=label)
        axes[2].plot(t, np.degrees(np.asarray(rec.rudder)), lw=1.0, label=label)
    for ax, yl in zip(axes, ("speed over ground (m/s)", "drift angle beta (deg)",
                             "rudder angle (deg, + to port)"), strict=True):  # fmt: skip
        ax.set_ylabel(yl)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7, ncol=2)
    axes[-1].set_xlabel("time (s)")
    if title:
        fig.suptitle(title)
    return _saved(fig, path)


def plot_current(
    records: Mapping[str, Any], L: float, *, path: str | os.PathLike[str] | None = None,
    title: str = "",
) -> Any:  # fmt: skip
    """The current's effect on trials (Artyszuk 2003 Fig. 1): left, each track over ground
    (solid) next to the water-referenced track (dashed, the ITTC way: the track less the
    current's drift); right, the drift angle over ground (solid) and through the water
    (dashed) against time: the same manoeuvre through the water, another over ground.

    Args:
        records: label -> a :class:`~shipgym.envs.seatrial.TrialRecord` (its ``current``
            and :meth:`~shipgym.envs.seatrial.TrialRecord.water_referenced`).
        L: ship length (m), the unit of the track axes.
        path: save the figure there (PNG) when given.
        title: the figure title.
    """
    if not (math.isfinite(L) and L > 0):
        raise ValueError(f"L must be > 0 m, got {L!r}")
    fig = _figure((12.0, 6.0))
    ax_t, ax_b = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    for label, rec in records.items():
        w = rec.water_referenced()
        (line,) = ax_t.plot(rec.eta[:, 1] / L, rec.eta[:, 0] / L, lw=1.2,
                            label=f"{label}, over ground")  # fmt: skip
        c = line.get_color()
        ax_t.plot(w.eta[:, 1] / L, w.eta[:, 0] / L, "--", color=c, lw=1.0,
                  label=f"{label}, through the water")  # fmt: skip
        for r, style, what in ((rec, "-", "over ground"), (w, "--", "through the water")):
            beta = np.degrees(np.arctan2(-r.nu[:, 1], r.nu[:, 0]))
            ax_b.plot(r.t, beta, style, color=c, lw=1.0, label=f"{label}, {what}")
    ax_t.set_xlabel("east y / L")
    ax_t.set_ylabel("north x / L")
    ax_t.set_aspect("equal", adjustable="datalim")
    ax_b.set_xlabel("time (s)")
    ax_b.set_ylabel("drift angle beta (deg)")
    for ax in (ax_t, ax_b):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    if title:
        fig.suptitle(title)
    return _saved(fig, path)


def write_trial_figures(
    study: Any, folder: str | os.PathLike[str], *, title: str = ""
) -> list[str]:
    """The figures of a :class:`~shipgym.envs.seatrial.TrialStudy` in ``folder`` (PNG): the
    tracks (``trial_tracks.png``), the time histories (``trial_histories.png``), with a
    current the ground and water-referenced tracks and drift angles (``trial_current.png``,
    :func:`plot_current`) and, with a receiver, one bias figure per manoeuvre
    (``bias_<manoeuvre>.png``, every ``S_p``, the ground-referenced estimate). Returns the
    paths written."""
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    recs = study.records
    if not recs:
        return []
    L = next(iter(recs.values())).L
    written = []
    plot_tracks({m: r.eta for m, r in recs.items()}, L, outlines=4,
                      path=out / "trial_tracks.png", title=f"{title}: tracks")  # fmt: skip
    written.append(str(out / "trial_tracks.png"))
    plot_histories(recs, path=out / "trial_histories.png", title=f"{title}: histories")
    written.append(str(out / "trial_histories.png"))
    current = next(iter(recs.values())).current
    if current[0] > 0:  # the water-referenced tracks and drift angles next to the ground's
        plot_current(recs, L, path=out / "trial_current.png",
                     title=f"{title}: current {current[0]:g} m/s to "
                     f"{math.degrees(current[1]) % 360:g} deg")  # fmt: skip
        written.append(str(out / "trial_current.png"))
    for m in recs:
        found = {sp: b for (mm, sp, corr), b in study.bias.items()
                 if mm == m and not corr and sp != "raw"}  # fmt: skip
        if not found:
            continue
        b0 = next(iter(found.values()))
        path = out / f"bias_{m}.png"
        plot_bias(b0.t, b0.truth, {sp: b.estimate for sp, b in found.items()}, path=path,
                  title=f"{title}: {m}, DGPS receiver against the truth")  # fmt: skip
        written.append(str(path))
    return written
