"""Figures of the Al-Takie (1982) DP benchmark (``shipgym bench dp --figures DIR``).

Like the thesis's figures (5.5-5.29): the LF and HF estimates against the truth, the thrust
commands of the wave filter and of the same controller on raw measurements, the wave-band
spectra of those commands, and the history of the 14-state filter's gains from ``P(0) = 0``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .report import DPI

__all__ = ["DP_SIZES", "write_dp_figures"]

#: Figure sizes (inches); pixels = inches * DPI.
DP_SIZES: dict[str, tuple[float, float]] = {
    "dp_estimates": (12.0, 9.0),
    "dp_thrust": (12.0, 7.0),
    "dp_gains": (12.0, 5.0),
}


def _figure(name: str) -> Any:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=DP_SIZES[name], dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def write_dp_figures(
    traces: Mapping[str, Mapping[str, Any]],
    gains: Mapping[str, Any],
    out_dir: str | os.PathLike[str],
    *,
    title: str = "",
) -> list[Path]:
    """Write ``dp_estimates_<filter>.png`` (kf14, kf16), ``dp_thrust.png`` and ``dp_gains.png``.

    Args:
        traces: per method (``"kf14"``, ``"raw-lq"``, ...), one episode as returned by
            :func:`shipgym.dp.bench.dp_trace`: ``t`` (s), ``eta`` (true pose in the set-point
            frame, m, m, rad), ``eta_hat`` (the estimate), ``z`` (the measurement), ``hf``
            (the true first-order wave motion), ``hf_hat`` (the filter's), ``tau_c``
            (N, N, N m) and ``capacity``.
        gains: :func:`shipgym.dp.bench.dp_gain_history`: ``t`` (s), ``K`` (steps, 14, 2)
            and ``settled`` (s, marked).
        out_dir: the folder (created).
        title: the figure titles' prefix (vessel, sea state).

    Returns:
        The written paths.
    """
    from scipy.signal import welch

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    colours = {"kf14": "#d62728", "raw-lq": "0.5", "kf16": "#9467bd", "notch-pid": "#2ca02c"}
    filters = [m for m in ("kf14", "kf16") if m in traces] or [next(iter(traces))]
    rows = (("sway position (m)", 1, 1.0), ("heading (deg)", 2, float(np.degrees(1.0))),
            ("surge position (m)", 0, 1.0))  # fmt: skip
    for m in filters:  # one figure per filter: its estimates against its own episode's truth
        tr = traces[m]
        fig = _figure("dp_estimates")
        axes = fig.subplots(3, 2, sharex=True)
        for row, (label, i, k) in enumerate(rows):
            ax, hf = axes[row]
            if i:
                ax.plot(tr["t"], k * tr["z"][:, i], color="0.8", lw=0.6, label="measured")
            ax.plot(tr["t"], k * tr["eta"][:, i], color="k", lw=1.0, label="true")
            ax.plot(tr["t"], k * tr["eta_hat"][:, i], color=colours.get(m, "#d62728"), lw=1.0,
                    label="LF estimate")  # fmt: skip
            hf.plot(tr["t"], k * tr["hf"][:, i], color="k", lw=0.8, label="true HF motion")
            hf.plot(tr["t"], k * tr["hf_hat"][:, i], color="#1f77b4", lw=0.7,
                    label="HF estimate")  # fmt: skip
            ax.set_ylabel(label)
            hf.set_ylabel("HF " + label)
            for a_ in (ax, hf):
                a_.grid(alpha=0.3)
        for a_ in axes[2]:
            a_.set_xlabel("t (s)")
        axes[0, 0].legend(fontsize=8, loc="upper right")
        axes[0, 1].legend(fontsize=8, loc="upper right")
        fig.suptitle(f"{title}: {m}, LF and HF estimates against the truth")
        paths.append(out / f"dp_estimates_{m}.png")
        fig.savefig(paths[-1])

    fig = _figure("dp_thrust")
    axes = fig.subplots(2, 2)
    order = sorted(traces, key=lambda m: m != "raw-lq")  # the raw measurements' first, below
    for name in order:
        tr = traces[name]
        cap = np.asarray(tr["capacity"], dtype=float)
        u = np.asarray(tr["tau_c"]) / cap
        c = colours.get(name, None)
        for j, (dof, label) in enumerate(((1, "sway"), (2, "yaw"))):
            axes[0, j].plot(tr["t"], u[:, dof], lw=0.7, color=c, label=name)
            axes[0, j].set_ylabel(f"{label} command / capacity")
            axes[0, j].set_xlabel("t (s)")
            fs = 1.0 / float(np.median(np.diff(tr["t"])))
            f, p = welch(u[:, dof], fs=fs, nperseg=min(len(u), int(round(100.0 * fs))))
            axes[1, j].semilogy(f, p, lw=0.9, color=c, label=name)
            axes[1, j].set_xlim(0.0, 0.3)
            axes[1, j].set_xlabel("frequency (Hz)")
            axes[1, j].set_ylabel(f"{label} command PSD (1/Hz)")
    for ax in axes[1]:
        ax.axvspan(0.0, 0.04, color="#2ca02c", alpha=0.08)
        ax.axvspan(0.05, 0.25, color="#1f77b4", alpha=0.08)
    for ax in axes.ravel():
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"{title}: thrust commands; LF band 0-0.04 Hz (green), wave band (blue)")
    paths.append(out / "dp_thrust.png")
    fig.savefig(paths[-1])

    fig = _figure("dp_gains")
    axes = fig.subplots(1, 2, sharex=True)
    K = np.asarray(gains["K"])
    t = np.asarray(gains["t"])
    lf = [(0, "v"), (1, "y"), (2, "r"), (3, "psi")]
    columns = (
        ("sway measurement", lf + [(6 + i, f"HF{i + 1}") for i in range(4)]),
        ("heading measurement", lf + [(10 + i, f"HF{i + 1}") for i in range(4)]),
    )
    for j, (label, states) in enumerate(columns):
        for i, nm in states:
            axes[j].plot(t, K[:, i, j], lw=0.9, label=nm)
        axes[j].set_title(f"gains on the {label}")
        axes[j].set_xlabel("t (s)")
        axes[j].axvline(float(gains["settled"]), color="k", ls="--", lw=0.8)
        axes[j].grid(alpha=0.3)
    axes[0].legend(fontsize=8, ncol=2)
    fig.suptitle(
        f"{title}: 14-state KF gains from P(0) = 0 (per unit); dashed: within 2 % of steady state"
    )
    paths.append(out / "dp_gains.png")
    fig.savefig(paths[-1])
    return paths
