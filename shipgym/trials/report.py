"""Tables of sea trials: the IMO figures and the DGPS receiver's bias (Markdown and rows).

Pure formatting of :class:`~shipgym.trials.metrics.TrialMetrics`, the IMO criteria and
:class:`~shipgym.trials.bias.ReceiverBias`; lengths in ship lengths ``L``, angles in degrees
(the units of trial reports), every row also as SI numbers for JSON.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

__all__ = ["bias_row", "bias_table", "trial_row", "trials_table"]

_DEG = 180.0 / math.pi

#: the trial figures of the table: key, column title, scale ("L": per ship length, "deg",
#: "s", "m/s", "1")
_FIGURES = (
    ("advance", "advance (L)", "L"),
    ("transfer", "transfer (L)", "L"),
    ("tactical_diameter", "tactical diam. (L)", "L"),
    ("steady_diameter", "steady diam. (L)", "L"),
    ("steady_speed", "steady speed (m/s)", "m/s"),
    ("overshoot_1", "1st overshoot (deg)", "deg"),
    ("overshoot_2", "2nd overshoot (deg)", "deg"),
    ("initial_turning_distance", "initial turning (L)", "L"),
    ("head_reach", "head reach (L)", "L"),
    ("track_reach", "track reach (L)", "L"),
    ("lateral_deviation", "lateral dev. (L)", "L"),
    ("time_to_stop", "time to stop (s)", "s"),
)


def trial_row(
    vessel: str, metrics: Any, criteria: Sequence[tuple[str, float, float, bool]], L: float,
    U0: float, current: tuple[float, float] = (0.0, 0.0),
) -> dict[str, Any]:  # fmt: skip
    """One manoeuvre's row: SI figures (m, s, rad), the IMO criteria and their verdict.

    Args:
        vessel: its name. metrics: :class:`~shipgym.trials.metrics.TrialMetrics`.
        criteria: :func:`~shipgym.trials.metrics.imo_criteria`'s list.
        L: ship length (m); U0: approach speed (m/s); current: ``(m/s, direction to, rad)``.
    """
    d = dict(metrics.as_dict())
    for i, o in enumerate(d.pop("overshoots", ())):
        d[f"overshoot_{i + 1}"] = o
    return {
        "vessel": vessel, "L": L, "U0": U0, "current": list(current), **d,
        "imo": [{"criterion": c, "value": v, "limit": lim, "passed": ok}
                for c, v, lim, ok in criteria],
        "imo_pass": all(c[3] for c in criteria) if criteria else None,
    }  # fmt: skip


def _cell(row: Mapping[str, Any], key: str, scale: str) -> str:
    v = row.get(key)
    if v is None or not math.isfinite(float(v)):
        return ""
    v = float(v)
    if scale == "L":
        return f"{v / float(row['L']):.3f}"
    if scale == "deg":
        return f"{v * _DEG:.2f}"
    if scale == "s":
        return f"{v:.1f}"
    return f"{v:.3f}"


def trials_table(rows: Sequence[Mapping[str, Any]]) -> str:
    """The trials as a Markdown table (only the columns some row has) and the IMO verdicts."""
    cols = [f for f in _FIGURES if any(r.get(f[0]) is not None for r in rows)]
    head = ["vessel", "manoeuvre", *[c[1] for c in cols], "IMO"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        verdict = {True: "pass", False: "FAIL", None: "-"}[r.get("imo_pass")]
        cells = [r["vessel"], r["manoeuvre"], *[_cell(r, k, s) for k, _t, s in cols], verdict]
        lines.append("| " + " | ".join(cells) + " |")
    crit = ["", "| vessel | manoeuvre | IMO MSC.137(76) criterion | value | limit | |",
            "|---|---|---|---|---|---|"]  # fmt: skip
    for r in rows:
        for c in r.get("imo", ()):
            text = c["criterion"]
            ang = "overshoot" in text
            val = c["value"] * _DEG if ang else c["value"] / float(r["L"])
            lim = c["limit"] * _DEG if ang else c["limit"] / float(r["L"])
            unit = "deg" if ang else "L"
            crit.append(f"| {r['vessel']} | {r['manoeuvre']} | {text} | {val:.3f} {unit} | "
                        f"{lim:.3f} {unit} | {'pass' if c['passed'] else 'FAIL'} |")  # fmt: skip
    return "\n".join(lines + (crit if len(crit) > 3 else []))


def bias_row(vessel: str, manoeuvre: str, b: Any, *, antenna: Sequence[float] = (0.0, 0.0),
             current: tuple[float, float] = (0.0, 0.0)) -> dict[str, Any]:  # fmt: skip
    """One receiver-bias row (SI: m/s, rad, m) of a :class:`~shipgym.trials.bias.ReceiverBias`."""
    keys = ("method", "S_p", "sigma", "runs", "seed", "transient", "corrected", "speed_bias_max",
            "speed_bias_min", "speed_bias_rms", "drift_bias_max", "drift_bias_min",
            "drift_bias_rms", "position_bias_max", "position_bias_rms", "sigma_v",
            "sigma_beta")  # fmt: skip
    return {"vessel": vessel, "manoeuvre": manoeuvre, "antenna": list(antenna),
            "current": list(current), **{k: getattr(b, k) for k in keys}}  # fmt: skip


def bias_table(rows: Sequence[Mapping[str, Any]]) -> str:
    """The receiver's bias as a Markdown table (speed m/s, drift angle deg, position m)."""
    head = ["vessel", "manoeuvre", "filter S_p (m^2/s^3)", "current corr.", "speed bias max / min "
            "(m/s)", "drift bias max / min (deg)", "position bias max (m)", "sigma_v (m/s)",
            "sigma_beta (deg)"]  # fmt: skip
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        lines.append(
            f"| {r['vessel']} | {r['manoeuvre']} | "
            f"{'raw positions' if r.get('method') == 'raw' else format(r['S_p'], 'g')} | "
            f"{'yes' if r['corrected'] else 'no'} | "
            f"{r['speed_bias_max']:+.3f} / {r['speed_bias_min']:+.3f} | "
            f"{r['drift_bias_max'] * _DEG:+.2f} / {r['drift_bias_min'] * _DEG:+.2f} | "
            f"{r['position_bias_max']:.2f} | {r['sigma_v']:.3f} | {r['sigma_beta'] * _DEG:.2f} |"
        )
    return "\n".join(lines)
