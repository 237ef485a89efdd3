r"""``shipgym bench roll``: rudder-roll stabilisation across speeds, with and without sway feedback.

Public names: ``METHODS``, ``SEED_CLAIM``, ``TASKS``, ``bench_roll``, ``default_task``,
``roll_analysis``, ``roll_run``, ``roll_table``, ...
Sources: Radhakrishnan (n.d.).

Design notes: docs/design/rrs.bench.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

__all__ = [
    "ROLL_SCHEMA_VERSION",
    "roll_from_json",
    "roll_json",
    "speed_key",
    "METHODS",
    "SEED_CLAIM",
    "TASKS",
    "bench_roll",
    "default_task",
    "roll_analysis",
    "roll_run",
    "roll_table",
    "roll_trace",
    "roll_analysis_table",
]

#: method -> (pilot mode, sway-feedback scale, gain scheduling)
METHODS: dict[str, tuple[str, float, bool]] = {
    "autopilot": ("autopilot", 1.0, False),
    "rrs": ("rrs", 1.0, False),
    "rrs-sway0.2": ("rrs", 0.2, False),
    "rrs-nosway": ("rrs", 0.0, False),
    "rrs-scheduled": ("rrs", 1.0, True),
}

#: task -> description
TASKS: dict[str, str] = {
    "seed-test": "the seed's sinusoidal rudder, 10 deg at 0.43 rad/s, calm water",
    "beam-sea": "beam sea Hs 0.5 m, Tp 7 s (JONSWAP)",
}

#: the seed's claim and what the bench shows instead
SEED_CLAIM = (
    "Radhakrishnan (n.d.) states that with sway-velocity feedback the roll is reduced to one "
    "tenth up to 13 m/s and turns oscillatory from 15 m/s; its gain is not printed, so this is "
    "not reproducible. Shown instead, with the chosen LQR at 8 m/s: the linear loop is stable "
    "at every speed from 2 to 30 m/s, roll ratios 0.17 / 0.076 / 0.059 at 8 / 13 / 15 m/s; "
    "without the sway term it turns unstable (oscillatory, about 0.075 rad/s) above 8.7 m/s, "
    "with the sway term x 0.2 above 15.7 m/s. The simulation (the seed's 10 deg sinusoidal "
    "rudder, gyro noise, the filter, the 10 deg/s rudder) loses the heading the same way: "
    "without the sway term above about 10 m/s, with it x 0.2 above about 16 m/s; with the full "
    "sway term the roll stays damped by 80-98 % from 8 to 22 m/s, beyond which the rudder "
    "rate limit saturates."
)

#: seconds skipped before the metrics (the transients of the filter and the sway mode)
SETTLE = 100.0


def default_task(vessel: Any) -> str:
    """``beam-sea`` for a hull with a displacement, else ``seed-test`` (the per-unit seed
    model)."""
    return "beam-sea" if getattr(vessel.plant(), "nabla", 0.0) > 0 else "seed-test"


def _env(vessel: str, U: float, task: str, duration: float) -> Any:
    from shipgym.envs.rollstab import BEAM_SEA, RudderRollEnv

    if task == "seed-test":
        kw: dict[str, Any] = {"waves": None, "rudder_test": True}
    elif task == "beam-sea":
        kw = {"waves": BEAM_SEA}
    else:
        raise ValueError(f"unknown roll task {task!r}; choose from {', '.join(TASKS)}")
    return RudderRollEnv(vessel=vessel, speed=U, episode_duration=duration, **kw)


def _episode(job: tuple[Any, ...]) -> dict[str, Any]:
    from shipgym.controllers.rollpilot import roll_pilot

    vessel, U, method, seed, duration, task = job
    mode, sway, schedule = METHODS[method]
    env = _env(vessel, float(U), task, float(duration))
    obs, _ = env.reset(seed=int(seed))
    pilot = roll_pilot(env.vessel, float(U), mode, sway_scale=sway, schedule=schedule,
                       dt=env.control_period, q=env.filter_intensities(float(U)))  # fmt: skip
    dmax = float(env.max_angle[0])
    cols = ("t", "roll", "heading_error", "rudder", "rudder_rate", "v", "v_hat", "trace_P",
            "rate_limited", "saturated", "p", "r")  # fmt: skip
    rec: dict[str, list[float]] = {c: [] for c in cols}
    d_prev = float(obs[4])
    capsized = False
    while True:
        d_mean = 0.5 * (d_prev + float(obs[4]))
        d_prev = float(obs[4])
        cmd = pilot(obs[:4], d_mean, U=float(U))
        obs, _r, term, trunc, info = env.step(np.array([cmd / dmax], dtype=np.float32))
        rec["t"].append(info["time"])
        for c in ("roll", "heading_error", "v", "p", "r"):
            rec[c].append(info[c])
        rec["rudder"].append(float(info["rudder"][0]))
        rec["rudder_rate"].append(float(info["rudder_rate"][0]))
        rec["rate_limited"].append(float(info["rate_limited"][0]))
        rec["saturated"].append(float(info["saturated"][0]))
        rec["v_hat"].append(pilot.v_hat)
        rec["trace_P"].append(pilot.filter.trace_P)
        if term:
            capsized = True
        if term or trunc:
            break
    env.close()
    out = {k: np.asarray(v) for k, v in rec.items()}
    out["capsized"] = capsized
    return out


def _metrics(tr: dict[str, Any]) -> dict[str, Any]:
    t = tr["t"]
    m = t > SETTLE
    if not m.any():
        m = np.ones_like(t, dtype=bool)

    def rms(x: Any) -> float:
        return float(np.sqrt(np.mean(np.asarray(x)[m] ** 2)))

    return {
        "roll_rms": rms(tr["roll"]),
        "roll_max": float(np.max(np.abs(tr["roll"][m]))),
        "heading_rms": rms(tr["heading_error"]),
        "heading_max": float(np.max(np.abs(tr["heading_error"][m]))),
        "rudder_rms": rms(tr["rudder"]),
        "rudder_rate_rms": rms(tr["rudder_rate"]),
        "rate_limited": float(np.mean(tr["rate_limited"][m])),
        "saturated": float(np.mean(tr["saturated"][m])),
        "v_rms": rms(tr["v"]),
        "v_hat_rmse": rms(tr["v_hat"] - tr["v"]),
        "trace_P": float(tr["trace_P"][-1]),
        "capsized": bool(tr["capsized"]),
    }


def roll_run(job: tuple[Any, ...]) -> dict[str, Any]:
    """One run ``(vessel, U m/s, method, seed, duration s, task)``: a row of metrics."""
    vessel, U, method, seed, duration, task = job
    row = {"vessel": vessel, "speed": float(U), "method": method, "seed": int(seed),
           "task": task, "duration": float(duration)}  # fmt: skip
    row.update(_metrics(_episode(job)))
    return row


def roll_trace(job: tuple[Any, ...]) -> dict[str, Any]:
    """One run's time series (``t``, ``roll``, ``heading_error``, ``rudder``, ``v``, ``v_hat``,
    ``trace_P``, ...), for the figures."""
    return _episode(job)


def bench_roll(
    vessels: Sequence[str],
    speeds: Sequence[float],
    seeds: int,
    *,
    methods: Sequence[str] | None = None,
    duration: float = 400.0,
    task: str | None = None,
    workers: int | None = None,
    progress: bool = True,
    on_row: Callable[[int, Any], None] | None = None,
    known: Mapping[int, Any] | None = None,
    executor: Any = None,
) -> list[dict[str, Any]]:
    """All (vessel, speed, method, seed) runs in worker processes; rows with the RRR added.

    Speeds above a vessel's ``limits.surge_speed`` are skipped for it (its propeller cannot
    hold them). ``task`` ``None``: each vessel's :func:`default_task`. ``executor``: the
    process pool (default) or Ray (:func:`shipgym.bench.run_jobs`).
    """
    from shipgym.bench import run_jobs, single_threaded_blas
    from shipgym.dynamics.vessel import load_vessel

    names = list(METHODS) if methods is None else list(methods)
    for mth in names:
        if mth not in METHODS:
            raise ValueError(f"unknown roll method {mth!r}; choose from {', '.join(METHODS)}")
    if "autopilot" not in names:
        names.insert(0, "autopilot")  # the baseline of the RRR
    if task is not None and task not in TASKS:
        raise ValueError(f"unknown roll task {task!r}; choose from {', '.join(TASKS)}")
    jobs = []
    for v in vessels:
        vv = load_vessel(v)
        top = vv.limits.get("surge_speed", math.inf)
        tk = task or default_task(vv)
        for U in speeds:
            if U > top + 1e-9:
                continue
            for mth in names:
                for s in range(seeds):
                    jobs.append((v, float(U), mth, s, float(duration), tk))
    if not jobs:
        raise ValueError("no runs: every speed lies above the vessels' surge_speed limits")
    with single_threaded_blas():
        rows = run_jobs(roll_run, jobs, workers=workers, progress=progress, desc="roll runs",
                        on_result=on_row, known=known, start_method="forkserver",
                        executor=executor)  # fmt: skip
    base = {(r["vessel"], r["speed"], r["seed"]): r["roll_rms"] for r in rows
            if r["method"] == "autopilot"}  # fmt: skip
    for r in rows:
        b = base.get((r["vessel"], r["speed"], r["seed"]))
        r["rrr"] = 1.0 - r["roll_rms"] / b if b else math.nan
    return rows


def roll_analysis(
    vessel: str, speeds: Sequence[float], sway_scales: Sequence[float] = (1.0, 0.2, 0.0)
) -> dict[str, Any]:
    """The linear analysis of the vessel's RRS design against speed.

    Returns a mapping with ``vessel`` (the argument, as the rows name it), ``speeds``;
    ``margin[scale]`` (max Re lambda, 1/s, of the fixed
    design-speed gain with the sway gain x scale) and ``margin_scheduled``; ``roll_ratio``
    (closed/open roll amplitude of the seed's sinusoidal rudder, fixed gain, full sway);
    ``onset[scale]``: ``(speed m/s, frequency rad/s)`` above which the fixed gain is unstable
    on 2 m/s to the vessel's ``limits.surge_speed`` (at most 30 m/s), or ``None``; ``gain`` the
    fixed gain and ``design_speed``. Speeds above the surge limit are left out (the hull model
    is not meant for them).
    """
    from shipgym.controllers.rollcontrol import (
        instability_onset,
        roll_ratio,
        rrs_lqr,
        stability_margin,
    )
    from shipgym.dynamics.linearise import roll_model_of
    from shipgym.dynamics.vessel import load_vessel

    v = load_vessel(vessel)
    rc = v.roll_control
    if not rc:
        raise ValueError(f"vessel {v.name!r} has no [roll_control] table")
    top = min(30.0, v.limits.get("surge_speed", 30.0))  # the hull's model holds up to there
    speeds = [float(U) for U in speeds if U <= top + 1e-9]
    if not speeds:
        raise ValueError(f"no speed at or below {v.name!r}'s surge_speed limit of {top:g} m/s")
    Q, R = np.diag(rc["Q"]), rc["R"]
    K = rrs_lqr(roll_model_of(v, rc["design_speed"]), Q, R)[0]
    margin: dict[float, list[float]] = {s: [] for s in sway_scales}
    sched, ratio = [], []
    for U in speeds:
        m = roll_model_of(v, float(U))
        for s in sway_scales:
            margin[s].append(stability_margin(m, K, s))
        sched.append(stability_margin(m, rrs_lqr(m, Q, R)[0], 1.0))
        ratio.append(roll_ratio(m, K, 1.0))

    def model_fn(U: float, variant: str = "", kdp_law: str = "") -> Any:
        return roll_model_of(v, U)

    onset = {}
    for s in sway_scales:
        o = instability_onset(K, s, speeds=(min(2.0, 0.5 * top), top), model_fn=model_fn)
        onset[s] = None if o is None else (float(o.speed), float(o.frequency))
    return {"vessel": str(vessel), "speeds": [float(u) for u in speeds], "design_speed":
            rc["design_speed"], "gain": K.tolist(), "margin": margin,
            "margin_scheduled": sched, "roll_ratio": ratio, "onset": onset,
            "top": top}  # fmt: skip


def roll_table(rows: Sequence[dict[str, Any]]) -> str:
    """Markdown: one line per (vessel, speed, method), mean ± std over the seeds."""
    from shipgym.bench import table_cell

    keys: dict[tuple[str, float, str], list[dict[str, Any]]] = {}
    for r in rows:
        keys.setdefault((r["vessel"], r["speed"], r["method"]), []).append(r)
    d = 180.0 / math.pi
    lines = [
        "| vessel | U (m/s) | method | RRR | roll RMS (deg) | heading RMS (deg) | rudder RMS "
        "(deg) | rate RMS (deg/s) | rate-limited | v-hat RMSE (m/s) | trace(P) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (v, U, mth), rs in keys.items():
        cap = " (capsized)" if any(r["capsized"] for r in rs) else ""
        lines.append(
            f"| {v} | {U:g} | {mth}{cap} | {table_cell([r['rrr'] for r in rs], '.2f')} | "
            f"{table_cell([r['roll_rms'] for r in rs], '.3f', d)} | "
            f"{table_cell([r['heading_rms'] for r in rs], '.3f', d)} | "
            f"{table_cell([r['rudder_rms'] for r in rs], '.2f', d)} | "
            f"{table_cell([r['rudder_rate_rms'] for r in rs], '.2f', d)} | "
            f"{table_cell([r['rate_limited'] for r in rs], '.0%')} | "
            f"{table_cell([r['v_hat_rmse'] for r in rs], '.4f')} | "
            f"{table_cell([r['trace_P'] for r in rs], '.2e')} |"
        )
    return "\n".join(lines)


def roll_analysis_table(an: dict[str, Any]) -> str:
    """Markdown of :func:`roll_analysis`: margins and roll ratio per speed, then the onsets."""
    scales = list(an["margin"])
    head = " | ".join(f"margin, sway x {s:g}" for s in scales)
    lines = [
        f"Linear analysis, {an['vessel']}: LQR at {an['design_speed']:g} m/s, "
        f"K = [{', '.join(f'{k:.4g}' for k in an['gain'])}] (u = -K x, x = [v, r, psi, p, phi])",
        "",
        f"| U (m/s) | {head} | margin, scheduled | roll ratio (sinusoid) |",
        "|---|" + "---|" * (len(scales) + 2),
    ]
    for i, U in enumerate(an["speeds"]):
        ms = " | ".join(f"{an['margin'][s][i]:+.4f}" for s in scales)
        lines.append(f"| {U:g} | {ms} | {an['margin_scheduled'][i]:+.4f} | "
                     f"{an['roll_ratio'][i]:.3f} |")  # fmt: skip
    lines.append("")
    for s in scales:
        o = an["onset"][s]
        lines.append(
            f"- sway x {s:g}: " + (f"stable up to {an['top']:g} m/s" if o is None else
                                   f"unstable above {o[0]:.2f} m/s (mode at {o[1]:.3f} rad/s)")
        )  # fmt: skip
    return "\n".join(lines)


#: the schema of ``shipgym bench roll --json`` (2: keyed records with units in the keys; 1,
#: before: a list of rows and per-speed lists, without units)
ROLL_SCHEMA_VERSION = 2

_RAD = 180.0 / math.pi

#: a run row's key -> (its JSON key, the factor from the row's SI value)
_ROLL_RUN_KEYS = {
    "task": ("task", None), "duration": ("duration_s", 1.0),
    "roll_rms": ("roll_rms_deg", _RAD), "roll_max": ("roll_max_deg", _RAD),
    "heading_rms": ("heading_rms_deg", _RAD), "heading_max": ("heading_max_deg", _RAD),
    "rudder_rms": ("rudder_rms_deg", _RAD), "rudder_rate_rms": ("rudder_rate_rms_deg_per_s", _RAD),
    "rate_limited": ("rate_limited_fraction", 1.0), "saturated": ("saturated_fraction", 1.0),
    "v_rms": ("v_rms_m_per_s", 1.0), "v_hat_rmse": ("v_hat_rmse_m_per_s", 1.0),
    "trace_P": ("trace_P_mixed", 1.0), "capsized": ("capsized", None), "rrr": ("rrr", 1.0),
}  # fmt: skip


def _f(v: Any, k: float | None) -> Any:
    if k is None or v is None or isinstance(v, bool):
        return v
    v = float(v)
    return v * k if math.isfinite(v) else None


def speed_key(U: float) -> str:
    """The key of the speed ``U`` (m/s) in the roll JSON: ``"8"``, ``"12.5"`` (m/s)."""
    return f"{float(U):g}"


def roll_json(
    title: str, rows: Sequence[Mapping[str, Any]], analyses: Sequence[Mapping[str, Any]],
    seed_claim: str,
) -> dict[str, Any]:  # fmt: skip
    """The file of ``shipgym bench roll --json`` (:data:`ROLL_SCHEMA_VERSION`): ``runs``
    keyed by vessel, speed (:func:`speed_key`, m/s), method and seed (``"0"``), each a record
    of the run's metrics with the unit in every key (degrees for angles); ``analyses`` keyed
    by vessel, its ``per_speed`` results keyed by speed (``roll_ratio``, the margins in 1/s
    keyed by the sway-gain scale), the onsets keyed by scale; ``units``: the key suffixes."""
    runs: dict[str, Any] = {}
    for r in rows:
        rec = {key: _f(r.get(k), f) for k, (key, f) in _ROLL_RUN_KEYS.items() if k in r}
        rec["speed_m_per_s"] = float(r["speed"])
        (runs.setdefault(r["vessel"], {}).setdefault(speed_key(r["speed"]), {})
         .setdefault(r["method"], {}))[str(int(r["seed"]))] = rec  # fmt: skip
    an_out: dict[str, Any] = {}
    for an in analyses:
        scales = list(an["margin"])
        per = {}
        for i, U in enumerate(an["speeds"]):
            per[speed_key(U)] = {
                "speed_m_per_s": float(U),
                "roll_ratio": float(an["roll_ratio"][i]),
                "margin_per_s": {f"sway x {s:g}": float(an["margin"][s][i]) for s in scales},
                "margin_scheduled_per_s": float(an["margin_scheduled"][i]),
            }
        onset = {
            f"sway x {s:g}": None if o is None else {"speed_m_per_s": float(o[0]),
                                                     "frequency_rad_per_s": float(o[1])}
            for s, o in an["onset"].items()
        }  # fmt: skip
        an_out[an["vessel"]] = {
            "design_speed_m_per_s": float(an["design_speed"]),
            "top_speed_m_per_s": float(an["top"]),
            "gain": dict(
                zip(("v", "r", "psi", "p", "phi"), (float(k) for k in an["gain"]), strict=True)
            ),  # fmt: skip
            "per_speed": per,
            "onset": onset,
        }
    return {
        "schema_version": ROLL_SCHEMA_VERSION,
        "title": title,
        "units": {
            "suffixes": {
                "_deg": "deg",
                "_deg_per_s": "deg/s",
                "_m_per_s": "m/s",
                "_s": "s",
                "_per_s": "1/s",
                "_rad_per_s": "rad/s",
                "_fraction": "1 (of the time)",
                "_mixed": "the trace of the observer's covariance (mixed units)",
            },
            "dimensionless": ["rrr", "roll_ratio"],
            "gain": "rad of rudder per unit of the state: v (m/s), r (rad/s), psi (rad), p "
            "(rad/s), phi (rad)",
            "keys": "runs: vessel, speed (m/s), method, seed; analyses: vessel, speed (m/s)",
        },  # fmt: skip
        "runs": runs,
        "analyses": an_out,
        "seed_claim": seed_claim,
    }


def roll_from_json(data: Mapping[str, Any]) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """The rows of :func:`bench_roll` and the analyses of :func:`roll_analysis` (SI, as in
    memory) from a file of :func:`roll_json`, for :func:`shipgym.viz.rrs.write_roll_figures`.

    Raises:
        ValueError: another schema version.
    """
    ver = data.get("schema_version")
    if ver != ROLL_SCHEMA_VERSION:
        raise ValueError(
            f"a bench roll file of schema_version {ROLL_SCHEMA_VERSION} is needed, got {ver!r}"
        )
    back = {key: (k, f) for k, (key, f) in _ROLL_RUN_KEYS.items()}
    rows = []
    for vessel, speeds in data["runs"].items():
        for methods in speeds.values():
            for method, seeds in methods.items():
                for seed, rec in seeds.items():
                    row: dict[str, Any] = {"vessel": vessel, "speed": rec["speed_m_per_s"],
                                           "method": method, "seed": int(seed)}  # fmt: skip
                    for key, v in rec.items():
                        if key in back:
                            k, f = back[key]
                            row[k] = _f(v, None if f is None else 1.0 / f)
                            if row[k] is None and f is not None:
                                row[k] = math.nan
                    rows.append(row)
    analyses = []
    for vessel, an in data["analyses"].items():
        per = list(an["per_speed"].values())
        scales = [float(s.removeprefix("sway x ")) for s in per[0]["margin_per_s"]] if per else []
        analyses.append({
            "vessel": vessel, "speeds": [p["speed_m_per_s"] for p in per],
            "design_speed": an["design_speed_m_per_s"], "top": an["top_speed_m_per_s"],
            "gain": list(an["gain"].values()),
            "margin": {s: [p["margin_per_s"][f"sway x {s:g}"] for p in per] for s in scales},
            "margin_scheduled": [p["margin_scheduled_per_s"] for p in per],
            "roll_ratio": [p["roll_ratio"] for p in per],
            "onset": {float(k.removeprefix("sway x ")): None if o is None else
                      (o["speed_m_per_s"], o["frequency_rad_per_s"])
                      for k, o in an["onset"].items()},
        })  # fmt: skip
    return rows, analyses
