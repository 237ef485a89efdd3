r"""``shipgym bench dp``: the wave filters of Al-Takie (1982) in closed loop, Beaufort 5-9.

Public names: ``DP_SCHEMA_VERSION``, ``DP_UNITS``, ``METHODS``, ``bench_dp``,
``dp_gain_history``, ``dp_run``, ``dp_table``, ``dp_trace``, ``TASKS``, ``thesis_controller``.

Design notes: docs/design/dp.bench.md.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from shipgym._text import did_you_mean

from .metrics import dp_metrics, step_metrics

__all__ = [
    "DP_SCHEMA_VERSION",
    "DP_UNITS",
    "METHODS",
    "bench_dp",
    "dp_gain_history",
    "dp_run",
    "dp_table",
    "dp_trace",
    "TASKS",
    "thesis_controller",
]

#: method -> (observer, controller, observer options, env overrides): ``"noise100"`` 100x the
#: sensor variances, ``"no-ff"`` no feedforward, ``"drift-ff"`` the mean wave drift fed forward
#: too (every other method has the DP tasks' wind and current feedforward,
#: :mod:`shipgym.controllers.feedforward`)
METHODS: dict[str, tuple[str, str, dict[str, Any] | None, str | None]] = {
    "kf14": ("alt-kf14", "thesis-lq", None, None),
    "kf16": ("alt-kf16", "thesis-lq", None, None),
    "kf12": ("alt-kf12", "thesis-lq", None, None),
    "semiconstant": ("alt-semiconstant", "thesis-lq", None, None),
    "ekf": ("alt-ekf", "alt-sdre", None, None),
    "kf14-pid": ("alt-kf14", "pid", None, None),
    "notch-pid": ("notch", "pid", None, None),
    "raw-lq": ("alt-raw", "thesis-lq", None, None),
    "kbf-pid": ("kbf", "pid", None, None),
    "kf14-bf5": ("alt-kf14", "thesis-lq", {"beaufort": 5}, None),
    "kf14-noise100": ("alt-kf14", "thesis-lq", None, "noise100"),
    "kf14-no-ff": ("alt-kf14", "thesis-lq", None, "no-ff"),
    "kf14-drift-ff": ("alt-kf14", "thesis-lq", None, "drift-ff"),
}


#: the schema of ``shipgym bench dp --json`` rows (2: keyed records, units in the keys or in
#: :data:`DP_UNITS`, the feedforward, HF thrust RMS and chatter columns; 1, before: per-DOF
#: lists without units)
DP_SCHEMA_VERSION = 2

#: the units of the row keys whose names carry none (the others end in ``_m``, ``_deg``,
#: ``_s``, ``_pct``, ``_us``, ``_per_min``)
DP_UNITS: dict[str, str] = {
    "thrust_usage": "1: mean |tau_c| / capacity per DOF (X, Y, N)",
    "thrust_usage_mean": "1: the mean of thrust_usage",
    "hf_thrust_rms": (
        "1: sqrt of the summed 0.05-0.25 Hz powers of the detrended tau_c / capacity (X, Y, N)"
    ),
    "wave_band_ratio": "1: thrust-command power 0.05-0.25 Hz over 0-0.04 Hz",
    "lf_rmse": "m (x_m, y_m) and deg (psi_deg): the estimate's error against the truth",
    "nis_mean": "1: mean normalised innovation squared (3 DOF: about 3 when consistent)",
    "samples": "count",
    "seed": "count",
    "beaufort": "Beaufort number",
}


def thesis_controller(vessel: str) -> str:
    """``alt-lq-printed`` for a vessel with a printed gain (Al-Takie 1982 4.4-4.5), else
    ``alt-lq``."""
    from shipgym.controllers.grimble import PRINTED_GAINS

    return "alt-lq-printed" if any(k.split("/")[0] == vessel for k in PRINTED_GAINS) else "alt-lq"


#: the tasks of the benchmark: the env ids
TASKS = {"station-keeping": "shipgym/DPStationKeeping-v0", "sway-step": "shipgym/DPSwayStep-v0"}


def _make_env(
    vessel_name: str, bf: int, method: str, duration: float, task: str = "station-keeping"
) -> Any:
    """The environment stack of one method (see :data:`METHODS`) on a task of :data:`TASKS`."""
    import shipgym
    from shipgym.dynamics.vessel import load_vessel
    from shipgym.envs.offshore import dp_control_period
    from shipgym.observers.sensors import AL_TAKIE1982_HEADING_SIGMA, AL_TAKIE1982_POSITION_SIGMA

    obs_name, ctl, opts, env_mod = METHODS[method]
    vessel = load_vessel(vessel_name)
    if ctl == "thesis-lq":
        ctl = thesis_controller(vessel_name)
    options = None
    if obs_name.startswith("alt-"):
        options = {"beaufort": bf} if opts is None else dict(opts)
    kwargs: dict[str, Any] = {}
    if env_mod == "noise100":
        kwargs["sensors"] = {
            "period": dp_control_period(float(vessel.hull.L_pp)),
            "position_variance": 100.0 * (AL_TAKIE1982_POSITION_SIGMA / float(vessel.scale)) ** 2,
            "heading_variance": 100.0 * AL_TAKIE1982_HEADING_SIGMA**2,
        }
    elif env_mod == "no-ff":
        kwargs["feedforward"] = "none"
    elif env_mod == "drift-ff":
        kwargs["feedforward"] = "wind+current+drift"
    return shipgym.make(
        TASKS[task],
        vessel=vessel_name,
        beaufort=bf,
        episode_duration=duration,
        observer=obs_name,
        observer_options=options,
        controller=ctl,
        **kwargs,
    )


def _episode(
    job: tuple[Any, ...], on_step: Callable[[Any, dict[str, Any]], None]
) -> tuple[Any, float]:
    """One episode, ``on_step(env, info)`` after every step; ``(env, filter seconds per step)``."""
    vessel_name, bf, method, seed, duration = job[:5]
    env = _make_env(vessel_name, bf, method, duration, _task(job))
    observer = env.unwrapped.observer  # the env's observer (N = 1)
    spent = [0.0, 0]
    step = observer.step

    def timed(*a: Any, **k: Any) -> Any:
        t0 = time.perf_counter()
        out = step(*a, **k)
        spent[0] += time.perf_counter() - t0
        spent[1] += 1
        return out

    observer.step = timed  # type: ignore[method-assign]
    env.reset(seed=seed)
    a = np.zeros(env.action_space.shape, np.float32)
    while True:
        _, _, term, trunc, info = env.step(a)
        on_step(env, info)
        if term or trunc:
            break
    env.close()
    return env, spent[0] / max(spent[1], 1)


def dp_run(job: tuple[Any, ...]) -> dict[str, Any]:
    """One episode: ``(vessel, beaufort, method, seed, duration_s[, task])`` -> a row of metrics.

    ``task`` is a key of :data:`TASKS` (``"station-keeping"``); the sway step's rows also have
    ``rise_time_s`` and ``overshoot_pct`` (:func:`~shipgym.dp.metrics.step_metrics` of the true
    sway in the set-point's frame, from its mean over the 10 s before the step; no settling
    time: in waves and gusts the response rarely stays within 5 % of the step).
    """
    from shipgym.controllers.actuation import planar_capacity

    t, eta, eta_d, tau, sat, err, nis = [], [], [], [], [], [], []
    end: dict[str, Any] = {}

    def keep(env: Any, info: dict[str, Any]) -> None:
        rec = info["record"]
        t.append(rec.t)
        eta.append(rec.truth.eta)
        eta_d.append(rec.reference.eta_d_n)
        tau.append(info["tau_c"])
        sat.append(bool(np.any(info["allocation_saturated"])))
        err.append(info["est_error_eta"])
        nis.append(np.nan if info["observer_nis"] is None else info["observer_nis"])
        if "episode_metrics" in info:
            end.update(info["episode_metrics"])

    env, per_step = _episode(job, keep)
    vessel_name, bf, method, seed, _ = job[:5]
    nis_a = np.array(nis, dtype=float)
    m = dp_metrics(
        np.array(t),
        np.array(eta),
        np.array(eta_d),
        np.array(tau),
        planar_capacity(env.unwrapped.vessel),
        saturated=np.array(sat)[:, None],
        lf_error=np.array(err),
        nis=nis_a[np.isfinite(nis_a)] if np.isfinite(nis_a).any() else None,
        nis_dof=3,
    )
    usage = m["thrust_usage"]
    m["thrust_usage"] = dict(zip(("X", "Y", "N"), usage, strict=True))
    if m["lf_rmse"] is not None:
        ex, ey, epsi = m["lf_rmse"]
        m["lf_rmse"] = {"x_m": ex, "y_m": ey, "psi_deg": math.degrees(epsi)}
    m.update(
        vessel=vessel_name,
        beaufort=bf,
        method=method,
        observer=METHODS[method][0],
        controller=env.unwrapped.controller_name,
        seed=seed,
        task=_task(job),
        feedforward=env.unwrapped.batch.feedforward.config.label
        if env.unwrapped.batch.feedforward is not None
        else "none",
        filter_step_us=1e6 * per_step,
        **_thruster_chatter(env.unwrapped.actuators, end),
    )
    if _task(job) == "sway-step":
        base = env.unwrapped
        c, s_ = np.cos(eta_d[0][2]), np.sin(eta_d[0][2])
        e = np.array(eta)[:, :2] - np.array(eta_d[0])[:2]
        sway = -s_ * e[:, 0] + c * e[:, 1]  # in the set-point's frame
        ta = np.array(t)
        before = (ta >= base.step_time - 10.0) & (ta < base.step_time)
        if before.any():  # from where the ship held before the step (its LF offset)
            sway = sway - float(np.mean(sway[before]))
        sm = step_metrics(ta, sway, base.step_time, base.step_size)
        m.update(rise_time_s=sm["rise_time_s"], overshoot_pct=sm["overshoot_pct"])
    return m


def _thruster_chatter(actuators: Any, metrics: dict[str, Any]) -> dict[str, float]:
    """The thrust channels' worst chatter of an episode (its ``episode_metrics``): an
    azimuth's angle channel (a slew-rate command) is left out, its sign changes are no
    thrust reversals.

    Returns:
        ``at_limit_pct`` (% of the control steps the busiest thrust channel's command is at
        a limit), ``reversals_per_min`` and ``starts_per_min`` (of the channel with the most).
    """
    thrust = [i for i, c in enumerate(ch for u in actuators for ch in u.channels)
              if c.state_unit != "rad"]  # fmt: skip

    def worst(key: str) -> float:
        return float(max(metrics[key][i] for i in thrust))

    return {
        "at_limit_pct": 100.0 * worst("limit_fraction"),
        "reversals_per_min": worst("reversals_per_min"),
        "starts_per_min": worst("starts_per_min"),
    }


def _task(job: tuple[Any, ...]) -> str:
    task = job[5] if len(job) > 5 else "station-keeping"
    if task not in TASKS:
        raise ValueError(
            f"unknown DP task {task!r}{did_you_mean(task, TASKS)}; choose from {', '.join(TASKS)}"
        )
    return str(task)


def dp_trace(job: tuple[Any, ...]) -> dict[str, Any]:
    """One episode's time series for the figures (:func:`shipgym.viz.dp.write_dp_figures`).

    Returns:
        ``t`` (s), ``eta`` (true pose), ``eta_hat`` (estimate), ``z`` (last measurement),
        ``hf`` (true first-order wave motion on the measurement), ``hf_hat`` (the filter's
        estimate of it, zeros for filters without), ``tau_c`` (N, N, N m), ``capacity``.
    """
    from shipgym.controllers.actuation import planar_capacity

    cols: dict[str, list[Any]] = {k: [] for k in ("t", "eta", "eta_hat", "z", "hf", "hf_hat")}
    cols["tau_c"] = []

    def keep(env: Any, info: dict[str, Any]) -> None:
        rec = info["record"]
        obs = env.unwrapped.observer
        zs = [m.z for m in rec.measurements if m.z is not None]
        cols["t"].append(rec.t)
        cols["eta"].append(rec.truth.eta)
        cols["eta_hat"].append(rec.nav.eta)
        cols["z"].append(zs[-1] if zs else np.full(3, np.nan))
        cols["hf"].append(np.array(env.unwrapped.physics.wave_motion()))
        cols["hf_hat"].append(obs.hf_motion(0) if hasattr(obs, "hf_motion") else np.zeros(3))
        cols["tau_c"].append(info["tau_c"])

    env, _ = _episode(job, keep)
    out: dict[str, Any] = {k: np.array(v, dtype=float) for k, v in cols.items()}
    out["capacity"] = planar_capacity(env.unwrapped.vessel)
    return out


def dp_gain_history(vessel: str, beaufort: int, duration: float = 120.0) -> dict[str, Any]:
    """The ``alt-kf14`` filter's gains from ``P(0) = 0`` over ``duration`` s (its own design).

    Returns:
        ``t`` (s), ``K`` (steps, 14, 2) and ``settled`` (s): when every gain is within 2 % of
        steady state (:func:`~shipgym.observers.wavefilter.gain_settling_steps`).
    """
    from shipgym.dynamics.vessel import load_vessel
    from shipgym.observers import make_observer
    from shipgym.observers.wavefilter import gain_settling_steps

    obs = make_observer("alt-kf14", vessel=load_vessel(vessel), beaufort=beaufort)
    kf = obs.core
    n = int(round(duration / obs.dt))
    K = np.zeros((n, kf.n, 2))
    for k in range(n):
        kf.step(np.zeros(2), np.zeros(2))
        K[k] = kf.K
    settled = gain_settling_steps(kf.A, kf.G, kf.H, kf.Q, kf.R, kf.dt) * obs.dt
    return {"t": (np.arange(n) + 1) * obs.dt, "K": K, "settled": settled}


def bench_dp(
    vessels: Sequence[str],
    beauforts: Sequence[int],
    seeds: int,
    *,
    methods: Sequence[str] | None = None,
    duration: float = 600.0,
    task: str = "station-keeping",
    workers: int | None = None,
    progress: bool = True,
    on_row: Callable[[int, Any], None] | None = None,
    known: Mapping[int, Any] | None = None,
    executor: Any = None,
) -> list[dict[str, Any]]:
    """All (vessel, Beaufort, method, seed) runs, in worker processes (or Ray tasks:
    ``executor``, :func:`shipgym.bench.run_jobs`); rows of metrics."""
    from shipgym.bench import run_jobs, single_threaded_blas

    names = list(METHODS) if methods is None else list(methods)
    for m in names:
        if m not in METHODS:
            raise ValueError(f"unknown DP method {m!r}; choose from {', '.join(METHODS)}")
    _task(("", 0, "", 0, 0.0, task))
    jobs = [
        (v, int(bf), m, s, float(duration), task)
        for v in vessels
        for bf in beauforts
        for m in names
        for s in range(seeds)
    ]
    # one BLAS thread per worker: the runs are small-matrix work and threaded BLAS in every
    # worker oversubscribes the cores (5x slower on 2 cores); fresh workers (forkserver) read
    # the setting when they load numpy
    with single_threaded_blas():
        return run_jobs(
            dp_run,
            jobs,
            workers=workers,
            progress=progress,
            desc="dp runs",
            on_result=on_row,
            known=known,
            start_method="forkserver",
            executor=executor,
        )


def dp_table(rows: Sequence[dict[str, Any]]) -> str:
    """A Markdown table: one line per (vessel, Beaufort, method), means ± std over seeds."""
    from shipgym.bench import table_cell

    keys: dict[tuple[str, int, str], list[dict[str, Any]]] = {}
    for r in rows:
        keys.setdefault((r["vessel"], r["beaufort"], r["method"]), []).append(r)
    head = (
        "| vessel | Bf | method | pos RMS (m) | max radial (m) | inside 7 m (%) | "
        "heading RMS (deg) | thrust use | HF thrust RMS | saturated (%) | at limit (%) | "
        "reversals / min | wave-band ratio | est. RMSE x, y (m) | NIS mean | "
        "filter step (us) |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    )
    step = any("rise_time_s" in r for r in rows)
    if step:
        head = head.replace("| filter step (us) |", "| rise 10-90 % (s) | overshoot (%) | "
                            "filter step (us) |")  # fmt: skip
        head += "---|---|"
    lines = [head]
    for (v, bf, m), rs in keys.items():
        lf = [r.get("lf_rmse") for r in rs]
        lf_xy = [None if x is None else float(np.hypot(x["x_m"], x["y_m"])) for x in lf]
        lines.append(
            f"| {v} | {bf} | {m} | "
            f"{table_cell([r['position_rms_m'] for r in rs], '.2f')} | "
            f"{table_cell([r['max_radial_error_m'] for r in rs], '.2f')} | "
            f"{table_cell([r['inside_radius_pct'] for r in rs], '.1f')} | "
            f"{table_cell([r['heading_rms_deg'] for r in rs], '.2f')} | "
            f"{table_cell([r['thrust_usage_mean'] for r in rs], '.3f')} | "
            f"{table_cell([r['hf_thrust_rms'] for r in rs], '.4f')} | "
            f"{table_cell([r['saturated_pct'] for r in rs], '.1f')} | "
            f"{table_cell([r['at_limit_pct'] for r in rs], '.1f')} | "
            f"{table_cell([r['reversals_per_min'] for r in rs], '.2f')} | "
            f"{table_cell([r['wave_band_ratio'] for r in rs], '.3f')} | "
            f"{table_cell(lf_xy, '.2f')} | "
            f"{table_cell([r['nis_mean'] for r in rs], '.2f')} | "
            + (
                f"{table_cell([r['rise_time_s'] for r in rs], '.1f')} | "
                f"{table_cell([r['overshoot_pct'] for r in rs], '.1f')} | "
                if step
                else ""
            )
            + f"{table_cell([r['filter_step_us'] for r in rs], '.0f')} |"
        )
    return "\n".join(lines)
