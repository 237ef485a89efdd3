"""Tables of sea trials: the IMO figures and the DGPS receiver's bias (Markdown and rows).

Pure formatting of :class:`~shipgym.trials.metrics.TrialMetrics`, the IMO criteria and
:class:`~shipgym.trials.bias.ReceiverBias`; lengths in ship lengths ``L``, angles in degrees
(the units of trial reports), every row also as SI numbers for JSON.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

__all__ = [
    "TRIALS_SCHEMA_VERSION",
    "bias_key",
    "bias_record",
    "bias_row",
    "bias_table",
    "trial_record",
    "trial_row",
    "trials_json",
    "trials_table",
]

_DEG = 180.0 / math.pi

#: the trial figures of the table: key, column title, scale ("L": per ship length, "deg",
#: "s", "m/s", "1")
_FIGURES = (
    ("U0", "approach (m/s)", "m/s"),
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
    U0: float, current: tuple[float, float] = (0.0, 0.0), *, reference: str = "ground",
) -> dict[str, Any]:  # fmt: skip
    """One manoeuvre's row: SI figures (m, s, rad), the IMO criteria and their verdict.

    Args:
        vessel: its name. metrics: :class:`~shipgym.trials.metrics.TrialMetrics`.
        criteria: :func:`~shipgym.trials.metrics.imo_criteria`'s list.
        L: ship length (m); U0: approach speed (m/s); current: ``(m/s, direction to, rad)``.
        reference: ``"ground"`` (the track over ground) or ``"water"`` (the track less the
            current's drift, :meth:`~shipgym.envs.seatrial.TrialRecord.water_referenced`).
    """
    if reference not in ("ground", "water"):
        raise ValueError(f"reference must be 'ground' or 'water', got {reference!r}")
    d = dict(metrics.as_dict())
    for i, o in enumerate(d.pop("overshoots", ())):
        d[f"overshoot_{i + 1}"] = o
    return {
        "vessel": vessel, "L": L, "U0": U0, "current": list(current), "reference": reference,
        **d,
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
        name = r["manoeuvre"] + (" (through the water)" if r.get("reference") == "water" else "")
        cells = [r["vessel"], name, *[_cell(r, k, s) for k, _t, s in cols], verdict]
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
            name = r["manoeuvre"] + (" (water)" if r.get("reference") == "water" else "")
            crit.append(f"| {r['vessel']} | {name} | {text} | {val:.3f} {unit} | "
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


# ---- the JSON of ``shipgym trials --json``: keyed records, every key with its unit ------------

#: the schema of ``shipgym trials --json`` (2: keyed records with units in the keys; 1, before:
#: lists of SI rows without units)
TRIALS_SCHEMA_VERSION = 2

#: the unit suffixes of the keys of ``shipgym trials --json`` (a key without one is a name, a
#: flag, a count or dimensionless: :data:`DIMENSIONLESS`)
UNIT_SUFFIXES = {"_m": "m", "_s": "s", "_deg": "deg", "_m_per_s": "m/s",
                 "_m2_per_s3": "m^2/s^3", "_rps": "rps"}  # fmt: skip
#: the numeric keys of the file without a unit suffix: dimensionless (1)
DIMENSIONLESS = ("speed_ratio", "shaft_fraction", "runs", "seed")

#: a trial figure's key in SI rows -> (its JSON key, the factor from SI)
_JSON_FIGURES = {
    "angle": ("rudder_angle_deg", _DEG), "advance": ("advance_m", 1.0),
    "transfer": ("transfer_m", 1.0), "tactical_diameter": ("tactical_diameter_m", 1.0),
    "steady_diameter": ("steady_diameter_m", 1.0), "steady_speed": ("steady_speed_m_per_s", 1.0),
    "speed_ratio": ("speed_ratio", 1.0), "time_90": ("time_90_s", 1.0),
    "time_180": ("time_180_s", 1.0), "time_360": ("time_360_s", 1.0),
    "time_first_execute": ("time_first_execute_s", 1.0), "period": ("period_s", 1.0),
    "initial_turning_distance": ("initial_turning_distance_m", 1.0),
    "initial_turning_time": ("initial_turning_time_s", 1.0),
    "time_to_stop": ("time_to_stop_s", 1.0), "head_reach": ("head_reach_m", 1.0),
    "track_reach": ("track_reach_m", 1.0), "lateral_deviation": ("lateral_deviation_m", 1.0),
    "heading_change_at_stop": ("heading_change_at_stop_deg", _DEG),
    "time_half_speed": ("time_half_speed_s", 1.0),
    "track_half_speed": ("track_half_speed_m", 1.0), "rudder_max": ("rudder_max_deg", _DEG),
    "shaft": ("shaft_fraction", 1.0),
}  # fmt: skip

#: a bias row's key -> (its JSON key, the factor from SI)
_JSON_BIAS = {
    "S_p": ("S_p_m2_per_s3", 1.0), "sigma": ("sigma_m", 1.0), "runs": ("runs", 1.0),
    "seed": ("seed", 1.0), "transient": ("transient_s", 1.0),
    "speed_bias_max": ("speed_bias_max_m_per_s", 1.0),
    "speed_bias_min": ("speed_bias_min_m_per_s", 1.0),
    "speed_bias_rms": ("speed_bias_rms_m_per_s", 1.0),
    "drift_bias_max": ("drift_bias_max_deg", _DEG), "drift_bias_min": ("drift_bias_min_deg", _DEG),
    "drift_bias_rms": ("drift_bias_rms_deg", _DEG),
    "position_bias_max": ("position_bias_max_m", 1.0),
    "position_bias_rms": ("position_bias_rms_m", 1.0), "sigma_v": ("sigma_v_m_per_s", 1.0),
    "sigma_beta": ("sigma_beta_deg", _DEG),
}  # fmt: skip


def _num(v: Any, f: float) -> Any:
    return None if v is None or not math.isfinite(float(v)) else float(v) * f


def _current(c: Sequence[float]) -> dict[str, float]:
    return {"speed_m_per_s": float(c[0]), "direction_to_deg": float(c[1]) * _DEG}


def trial_record(row: Mapping[str, Any]) -> dict[str, Any]:
    """A :func:`trial_row` as the JSON's record: every figure under a key with its unit
    (degrees for angles), the overshoots keyed ``"1"``, ``"2"``, ... and the IMO criteria
    keyed by their text."""
    out: dict[str, Any] = {"vessel": row["vessel"], "manoeuvre": row["manoeuvre"],
                           "reference": row.get("reference", "ground"),
                           "kind": row.get("kind"), "L_m": float(row["L"]),
                           "U0_m_per_s": float(row["U0"]),
                           "current": _current(row["current"])}  # fmt: skip
    for k, (key, f) in _JSON_FIGURES.items():
        if row.get(k) is not None:
            out[key] = _num(row[k], f)
    ov = {k[len("overshoot_") :]: _num(v, _DEG) for k, v in row.items()
          if k.startswith("overshoot_")}  # fmt: skip
    if ov:
        out["overshoots_deg"] = ov
    imo = {}
    for c in row.get("imo", ()):
        ang = "overshoot" in c["criterion"]
        u, f = ("deg", _DEG) if ang else ("m", 1.0)
        imo[c["criterion"]] = {f"value_{u}": _num(c["value"], f), f"limit_{u}": _num(c["limit"], f),
                               "passed": bool(c["passed"])}  # fmt: skip
    out["imo"] = imo
    out["imo_pass"] = row.get("imo_pass")
    return out


def bias_key(row: Mapping[str, Any]) -> tuple[str, str]:
    """The keys of a bias row in the JSON: ``(filter, reference)``, ``filter`` ``"S_p=0.01"``
    (the receiver's PV filter) or ``"raw"`` (the raw positions differentiated), ``reference``
    ``"ground"`` or ``"water"`` (the seed's current correction)."""
    filt = "raw" if row.get("method") == "raw" else f"S_p={float(row['S_p']):g}"
    return filt, "water" if row["corrected"] else "ground"


def bias_record(row: Mapping[str, Any]) -> dict[str, Any]:
    """A :func:`bias_row` as the JSON's record: every number under a key with its unit
    (degrees for angles); the antenna and the current keyed."""
    out: dict[str, Any] = {"method": row["method"], "reference": bias_key(row)[1],
                           "antenna_m": {"x": float(row["antenna"][0]),
                                         "y": float(row["antenna"][1])},
                           "current": _current(row["current"])}  # fmt: skip
    for k, (key, f) in _JSON_BIAS.items():
        out[key] = _num(row[k], f) if key not in ("runs", "seed") else int(row[k])
    if row.get("method") == "raw":
        out.pop("S_p_m2_per_s3")  # the raw positions have no filter
    return out


def trials_json(
    title: str, rows: Sequence[Mapping[str, Any]], bias_rows: Sequence[Mapping[str, Any]],
    wall: float,
) -> dict[str, Any]:  # fmt: skip
    """The file of ``shipgym trials --json`` (:data:`TRIALS_SCHEMA_VERSION`): ``trials``
    keyed by manoeuvre and reference (``"ground"``; with a current also ``"water"``, the
    water-referenced track's figures; :func:`trial_record`), ``bias`` keyed by manoeuvre,
    filter and reference (:func:`bias_key`, :func:`bias_record`), the ``units`` of the key
    suffixes."""
    bias: dict[str, dict[str, dict[str, Any]]] = {}
    for r in bias_rows:
        filt, ref = bias_key(r)
        bias.setdefault(r["manoeuvre"], {}).setdefault(filt, {})[ref] = bias_record(r)
    trials: dict[str, dict[str, Any]] = {}
    for r in rows:
        trials.setdefault(r["manoeuvre"], {})[r.get("reference", "ground")] = trial_record(r)
    return {
        "schema_version": TRIALS_SCHEMA_VERSION,
        "title": title,
        "units": {"suffixes": dict(UNIT_SUFFIXES), "dimensionless": list(DIMENSIONLESS)},
        "trials": trials,
        "bias": bias,
        "wall_s": float(wall),
    }
