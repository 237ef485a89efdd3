"""``shipgym bench controllers``: classical and learned controllers on the same runs.

Public names: ``DEFAULT_CONTROLLERS``, ``STATION_DURATION_S``, ``STATION_RADIUS``, ``TASKS``,
``StationTrack``, ``bench_controllers``, ``bench_title``, ``controller_labels``, ...
Sources: Tomera (2014); Al-Takie (1982).

Design notes: docs/design/rl.bench.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from shipgym.bench import mean_std as _ms
from shipgym.bench import mean_worst, run_jobs
from shipgym.metrics import CHATTER_KEYS
from shipgym.runner import ENV_DEFAULT

from .evaluation import (
    DEFAULT_WIND,
    STATION_RADIUS,
    StationTrack,
    check_observer,
    default_observer,
)

__all__ = [
    "DEFAULT_CONTROLLERS",
    "STATION_DURATION_S",
    "STATION_RADIUS",
    "TASKS",
    "StationTrack",
    "bench_controllers",
    "bench_title",
    "controller_labels",
    "controller_table",
    "default_controllers",
    "default_vessel",
    "missing_baselines",
    "station_table",
]

#: the classical controllers of every table (the learned ones: :func:`default_controllers`)
DEFAULT_CONTROLLERS = ("pid", "lq")
#: the tasks of the bench
TASKS = ("harbour", "station-keeping")
#: length of a station-keeping run (s), as in the station-keeping requirement of the README
STATION_DURATION_S = 1000.0
#: the station-keeping env
_STATION_ID = "shipgym/StationKeeping-v0"

_KEEP = (
    "seed",
    "completed",
    "legs_completed",
    "quay_contact",
    "duration_s",
    "x_E",
    "y_E",
    "psi_E",
    "J_c",
    "measured",
    "leg_times",
    "thrust_mean_abs",
    "thrust_total_variation",
    "saturated_fraction",
    *CHATTER_KEYS,
    "rmse",
    "wall_time_s",
)
_KEEP_STATION = (
    "seed",
    "duration_s",
    "thrust_mean_abs",
    "thrust_total_variation",
    "saturated_fraction",
    *CHATTER_KEYS,
    "rmse",
    "wind",
    "wall_time_s",
)


def default_vessel(task: str) -> str:
    """The vessel of a task when none is given: ``blue-lady`` for the harbour manoeuvre,
    ``star-hercules`` (the station-keeping baseline's) for station keeping."""
    _check_task(task)
    return "blue-lady" if task == "harbour" else "star-hercules"


def _check_task(task: str) -> None:
    if task not in TASKS:
        raise ValueError(f"unknown task {task!r}; choose one of: {', '.join(TASKS)}")


def _baselines(task: str, vessel: str) -> list[Any]:
    """The baselines that the names resolve to for ``task`` and ``vessel``
    (:func:`~shipgym.controllers.learned.find_baseline`), in name order."""
    from shipgym.controllers.learned import BASELINE_NAMES, find_baseline

    out = []
    for name in BASELINE_NAMES:
        try:
            out.append(find_baseline(name, task, vessel))
        except ValueError:
            continue
    return out


def default_controllers(task: str = "harbour", vessel: str | None = None) -> list[str]:
    """``pid``, ``lq`` and the shipped baselines of ``task`` and ``vessel`` whose files are
    present (in :data:`~shipgym.controllers.learned.BASELINE_MODELS` order)."""
    from shipgym.controllers.learned import models_dir

    v = vessel or default_vessel(task)
    have = [b.name for b in _baselines(task, v) if (models_dir() / b.file).is_file()]
    return [*DEFAULT_CONTROLLERS, *have]


def missing_baselines(task: str = "harbour", vessel: str | None = None) -> list[str]:
    """The baselines registered for ``task`` and ``vessel`` whose files are not shipped
    (``"name (file)"``)."""
    from shipgym.controllers.learned import models_dir

    v = vessel or default_vessel(task)
    return [
        f"{b.name} ({b.file})" for b in _baselines(task, v) if not (models_dir() / b.file).is_file()
    ]


def controller_labels(controllers: Sequence[str]) -> list[str]:
    """Short row labels: ``pid``, ``lq``, ``ppo`` (``ppo:PATH`` -> ``ppo``; when several models
    of one algorithm are compared, ``ppo:<stem>`` or ``ppo:<folder>/<stem>``, whichever is
    unique)."""
    from shipgym.controllers.learned import is_learned_controller

    heads = [c.split(":", 1)[0] if is_learned_controller(c) else c for c in controllers]
    out = list(heads)
    for depth in (1, 2, None):
        dup = {h for h in out if out.count(h) > 1}
        if not dup:
            break
        for i, c in enumerate(controllers):
            if out[i] in dup and ":" in c:
                parts = Path(c.split(":", 1)[1]).with_suffix("").parts
                tail = parts if depth is None else parts[-depth:]
                out[i] = f"{heads[i]}:{'/'.join(tail)}"
    if len(set(out)) != len(out):
        raise ValueError(f"controllers must be distinct, got {list(controllers)}")
    return out


def _learned_threads(controller: str) -> None:
    from shipgym.controllers.learned import is_learned_controller

    if is_learned_controller(controller):
        import torch

        torch.set_num_threads(1)


def _job(job: tuple[Any, ...]) -> dict[str, Any]:
    """One run in a worker process: ``(label, controller, seed, wind, observer[, task, vessel,
    steps, radius])``."""
    label, controller, seed, wind, observer, *rest = job
    task, vessel, steps, radius = rest or ("harbour", None, None, STATION_RADIUS)
    import shipgym.controllers.lq  # noqa: F401  (registers "lq")

    _learned_threads(controller)
    from .evaluation import run_controlled_episode

    row = {"controller": label, "controller_spec": controller, "observer": observer or "truth"}
    if task == "harbour":
        kw = {} if vessel in (None, "blue-lady") else {"vessel": vessel}
        res = run_controlled_episode(
            "harbour", controller, seed=seed, observer=observer, wind=wind, **kw
        )
        row.update({k: res[k] for k in _KEEP})
        return row
    track = StationTrack()
    res = run_controlled_episode(
        _STATION_ID, controller, seed=seed, observer=observer, wind=wind, on_step=track,
        vessel=vessel, max_episode_steps=steps,
    )  # fmt: skip
    row.update({"task": task, "vessel": vessel, "radius_m": radius})
    row.update({k: res[k] for k in _KEEP_STATION})
    row.update(track.summary(radius))
    return row


def _actuator_names(vessel: str) -> list[str]:
    from shipgym.dynamics.vessel import load_vessel

    return list(load_vessel(vessel).actuators.names)


def bench_controllers(
    controllers: Sequence[str] | None = None,
    seeds: int = 10,
    *,
    task: str = "harbour",
    vessel: str | None = None,
    wind: Any = ENV_DEFAULT,
    observer: str | None = "default",
    duration_s: float = STATION_DURATION_S,
    radius: float = STATION_RADIUS,
    workers: int | None = None,
    progress: bool = True,
    on_row: Callable[[int, dict[str, Any]], None] | None = None,
    known: Mapping[int, Any] | None = None,
    executor: Any = None,
) -> list[dict[str, Any]]:
    """Run the task for every controller and seed ``0..seeds-1``.

    Args:
        controllers: names: ``pid``, ``pid-seed``, ``lq``, the shipped baselines ``ppo``,
            ``sac``, ``ppo-residual`` (the files of this task and vessel), ``ppo:PATH``,
            ``sac:PATH``; default :func:`default_controllers`.
        seeds: number of seeds per controller.
        task: ``"harbour"`` (the harbour manoeuvre) or ``"station-keeping"``
            (``shipgym/StationKeeping-v0``, ``duration_s`` long).
        vessel: the vessel (default :func:`default_vessel`: ``blue-lady`` for the harbour,
            ``star-hercules`` for station keeping); station keeping needs a positioning vessel.
        wind: any form of :meth:`WindConfig.coerce <shipgym.disturbances.WindConfig.coerce>`
            (``"3@300"``: 3 m/s from 300 deg; ``(speed m/s, from deg)``; a ``WindConfig``),
            ``None`` (calm) or ``ENV_DEFAULT`` (default): the task's wind, 3 m/s from 300 deg
            for the Blue Lady's harbour manoeuvre (the lake trial), else the vessel's nominal
            wind from 300 deg (Star Hercules: 10 m/s).
        observer: ``"default"`` (the Kalman-Bucy filter ``kbf`` when available, else the
            truth), ``"truth"``/``None`` or an observer name; the same for every controller.
        duration_s: length of a station-keeping run (s; a whole number of control steps).
        radius: the station-keeping watch circle (m).
        workers: processes (default: CPUs, at most the number of runs); 1 runs in-process.
        executor: the process pool (default) or Ray (:func:`shipgym.bench.run_jobs`).
        progress: show a progress bar.
        on_row: called with ``(index, row)`` as each run finishes (e.g.
            :meth:`shipgym.bench.RowLog.add`, which keeps finished rows on an interrupt).

    Returns:
        One row per controller and seed, in the order of ``controllers`` then seeds. Each row
        has ``controller`` (label), ``controller_spec`` (as given), ``observer``, ``seed``,
        ``duration_s``, ``thrust_mean_abs`` (N, per actuator), ``thrust_total_variation`` (N),
        ``saturated_fraction``, ``rmse`` (observer), ``wall_time_s``. Harbour rows add
        ``completed``, ``legs_completed``, ``quay_contact``, ``x_E``, ``y_E`` (m), ``psi_E``
        (deg), ``J_c`` (truth), ``measured`` (indices from the measured pose), ``leg_times``
        (s). Station-keeping rows add ``task``, ``vessel``, ``radius_m``, ``wind`` (speed m/s,
        from deg), ``inside_fraction``, ``r95`` (m), ``r_max`` (m), ``heading_rms_deg``,
        ``steps`` (:class:`StationTrack`).

    Raises:
        ValueError: unknown task, controller or observer names, a vessel that cannot do the
            task, a model file that is not a shipgym model or not for this vessel (checked
            before any run).
        FileNotFoundError: a named baseline whose file is not shipped, a missing model file.
    """
    from shipgym.controllers.batch import controller_spec
    from shipgym.controllers.learned import is_learned_controller, parse_learned_controller
    from shipgym.controllers.lq import register_lq
    from shipgym.disturbances import WindConfig

    register_lq()
    _check_task(task)
    vessel = vessel or default_vessel(task)
    if task == "harbour" and wind is ENV_DEFAULT and vessel == "blue-lady":
        wind = DEFAULT_WIND
    if wind is not ENV_DEFAULT:
        wind = WindConfig.coerce(wind, name="wind")
    if not (isinstance(seeds, int) and seeds >= 1):
        raise ValueError(f"seeds must be an int >= 1, got {seeds!r}")
    if not (isinstance(radius, int | float) and math.isfinite(radius) and radius > 0):
        raise ValueError(f"radius must be a finite number of metres > 0, got {radius!r}")
    steps = None
    if task == "station-keeping":
        steps = _station_steps(vessel, duration_s)
    elif vessel != "blue-lady":
        import shipgym

        # a vessel the harbour world cannot take fails here, before any run
        shipgym.make("harbour", vessel=vessel).close()
    obs = default_observer() if observer == "default" else check_observer(observer)
    if controllers is None:
        controllers = default_controllers(task, vessel)
    resolved = []
    for c in controllers:
        if is_learned_controller(c):
            env_task = _STATION_ID if task == "station-keeping" else "harbour"
            algo, path = parse_learned_controller(c, task=env_task, vessel=vessel)
            _check_model_vessel(path, vessel)
            resolved.append(f"{algo}:{path}")
        else:
            controller_spec(c)
            resolved.append(c)
    labels = controller_labels(list(controllers))
    if task == "harbour":
        vkw: tuple[Any, ...] = () if vessel == "blue-lady" else (task, vessel, None, radius)
    else:
        vkw = (task, vessel, steps, float(radius))
    jobs = [
        (label, c, s, wind, obs, *vkw)
        for label, c in zip(labels, resolved, strict=True)
        for s in range(seeds)
    ]
    rows = run_jobs(
        _job, jobs, workers=workers, progress=progress, desc="controllers x seeds",
        on_result=on_row, known=known, executor=executor,
    )  # fmt: skip
    if task == "station-keeping":
        names = _actuator_names(vessel)
        for r in rows:
            r["actuators"] = names
    return rows


def _station_steps(vessel: str, duration_s: float) -> int:
    """Control steps of a station-keeping run of ``duration_s`` (checks that the vessel can
    keep station)."""
    import shipgym

    if not (isinstance(duration_s, int | float) and math.isfinite(duration_s) and duration_s > 0):
        raise ValueError(f"duration_s must be a finite number of seconds > 0, got {duration_s!r}")
    env = shipgym.make(_STATION_ID, vessel=vessel)
    try:
        dt = float(env.unwrapped.control_period)  # type: ignore[attr-defined]
    finally:
        env.close()
    steps = round(duration_s / dt)
    if steps < 1 or not math.isclose(steps * dt, duration_s, rel_tol=1e-9, abs_tol=1e-9):
        raise ValueError(
            f"duration_s must be a whole number of control steps of {dt:g} s, got {duration_s!r}"
        )
    return int(steps)


def _check_model_vessel(path: Path, vessel: str) -> None:
    """A model trained for another vessel is refused here, before any run."""
    from shipgym.controllers.learned import read_metadata, trained_vessel

    trained = trained_vessel(read_metadata(path))
    v = Path(str(vessel)).name
    if trained is not None and Path(trained).name != v:
        raise ValueError(
            f"{path} was trained for vessel {trained!r}, not {v!r}: choose a model of {v!r} "
            "(or --vessel to match it)"
        )


def controller_table(rows: Sequence[dict[str, Any]]) -> str:
    """A markdown table, one line per controller (mean +- std over seeds).

    Columns: completed without quay contact, mean legs completed (of 5), quay contacts, J_c
    from the truth and from the measured pose (Tomera 2014 eq. 57), mean J_c relative to ``pid``
    (when present), time to complete (s; completed runs), mean |thrust| per actuator (N),
    the command chatter of :func:`chatter_cells` (time at a limit, main-propeller
    reversals, starts and time at zero), wall time per run (s).
    """
    names = list(dict.fromkeys(r["controller"] for r in rows))
    pid = [r for r in rows if r["controller"] == "pid"]
    pid_jc = float(np.mean([r["J_c"] for r in pid])) if pid else math.nan
    head = (
        "| controller | runs | completed | legs | quay contact | J_c | J_c measured | J_c / pid "
        "| time (s) | mean abs thrust main/bow/stern (N) | " + chatter_head() + " | wall (s) |"
    )
    lines = [head, "|" + "---|" * (11 + len(_CHATTER_COLS))]
    for name in names:
        rs = [r for r in rows if r["controller"] == name]
        done = sum(bool(r["completed"]) and not r["quay_contact"] for r in rs)
        contact = sum(bool(r["quay_contact"]) for r in rs)
        jc = [r["J_c"] for r in rs]
        meas = [r["measured"]["J_c"] if r.get("measured") else math.nan for r in rs]
        ratio = float(np.mean(jc)) / pid_jc if pid_jc == pid_jc and pid_jc > 0 else math.nan
        times = [r["duration_s"] for r in rs if r["completed"]]
        thrust = np.mean([r["thrust_mean_abs"] for r in rs], axis=0)
        lines.append(
            f"| {name} | {len(rs)} | {done}/{len(rs)} "
            f"| {np.mean([r['legs_completed'] for r in rs]):.1f} | {contact} | {_ms(jc, '.4f')} "
            f"| {_ms(meas, '.4f')} | {ratio:.2f} | {_ms(times, '.0f')} "
            f"| {' / '.join(f'{t:.1f}' for t in thrust)} | {chatter_cells(rs)} "
            f"| {np.mean([r['wall_time_s'] for r in rs]):.1f} |"
        )
    return "\n".join(lines)


#: the chatter columns of the controller tables: (key, header, scale, format, per channel);
#: a per-channel column shows every channel, the others the first channel alone (the main
#: propeller of the Blue Lady and Star Hercules; :data:`shipgym.metrics.CHATTER_KEYS`)
_CHATTER_COLS = (
    ("limit_fraction", "at a limit (%) per channel, worst seed", 100.0, ".1f", True),
    ("reversals_per_min", "{} reversals / min", 1.0, ".2f", False),
    ("starts_per_min", "{} starts / min", 1.0, ".2f", False),
    ("zero_fraction", "{} at zero (%)", 100.0, ".0f", False),
)


def chatter_head(first: str = "main") -> str:
    """The headers of :func:`chatter_cells`, ``first`` naming the first channel."""
    return " | ".join(c[1].format(first) for c in _CHATTER_COLS)


def chatter_cells(rows: Sequence[dict[str, Any]]) -> str:
    """The chatter cells of one controller's rows (:data:`_CHATTER_COLS`): the time at a
    command limit per channel, worst seed (``a / b / c``), and the first channel's (main
    propeller's) reversals and starts per minute and time at zero, mean over the seeds and
    in brackets the worst seed (:func:`shipgym.metrics.command_chatter`); ``n/a`` for rows
    without commands."""
    cells = []
    for key, _, scale, fmt, per_channel in _CHATTER_COLS:
        per = [r.get(key) for r in rows if r.get(key)]
        if not per:
            cells.append("n/a")
            continue
        x = scale * np.array(per, dtype=float)  # (seeds, channels)
        if per_channel:
            worst = [np.nanmax(c) if np.isfinite(c).any() else math.nan for c in x.T]
            cells.append(" / ".join(f"{w:{fmt}}" for w in worst))
        else:
            cells.append(mean_worst(x[:, 0], fmt, np.max))
    return " | ".join(cells)


def station_table(rows: Sequence[dict[str, Any]]) -> str:
    """A markdown table of station-keeping rows, one line per controller (mean +- std over
    seeds).

    Columns: runs, time within the radius (% of the run, mean +- std, and the runs that stay
    inside at least 95 % of the time), r95 (m; the 95th percentile of the distance from the set
    point), the largest distance (m), heading error RMS (deg), mean |thrust| per actuator (N),
    the command chatter of :func:`chatter_cells` (the first actuator's reversals, starts and
    time at zero), wall time per run (s).
    """
    names = list(dict.fromkeys(r["controller"] for r in rows))
    radius = float(rows[0]["radius_m"]) if rows else STATION_RADIUS
    acts = rows[0].get("actuators") if rows else None
    head_t = "/".join(acts) if acts else "per actuator"
    head = (
        f"| controller | runs | inside {radius:g} m (%) | runs >= 95 % inside | r95 (m) "
        f"| r max (m) | heading RMS (deg) | mean abs thrust {head_t} (N) "
        f"| {chatter_head(acts[0] if acts else 'first channel')} | wall (s) |"
    )
    lines = [head, "|" + "---|" * (9 + len(_CHATTER_COLS))]
    for name in names:
        rs = [r for r in rows if r["controller"] == name]
        inside = [r["inside_fraction"] for r in rs]
        ok = sum(bool(f >= 0.95) for f in inside)
        thrust = np.mean([r["thrust_mean_abs"] for r in rs], axis=0)
        lines.append(
            f"| {name} | {len(rs)} | {_ms(inside, '.1f', scale=100.0)} | {ok}/{len(rs)} "
            f"| {_ms([r['r95'] for r in rs], '.2f')} | {_ms([r['r_max'] for r in rs], '.2f')} "
            f"| {_ms([r['heading_rms_deg'] for r in rs], '.2f')} "
            f"| {' / '.join(_thrust(t) for t in thrust)} | {chatter_cells(rs)} "
            f"| {np.mean([r['wall_time_s'] for r in rs]):.1f} |"
        )
    return "\n".join(lines)


def _thrust(t: float) -> str:
    """A thrust in N with 3 significant digits (the Blue Lady's tens of N, Star Hercules'
    tens of kN)."""
    return f"{t:.3g}" if abs(t) < 1e3 else f"{t:,.0f}"


def bench_title(rows: Sequence[dict[str, Any]], wind: Any, task: str = "harbour") -> str:
    """The one-line caption of :func:`controller_table` / :func:`station_table` (``wind`` as
    for the bench; station keeping reports the wind its runs used)."""
    from shipgym.disturbances import WindConfig

    seeds = sorted({r["seed"] for r in rows})
    obs = rows[0]["observer"] if rows else "truth"
    span = f"seeds {seeds[0]}-{seeds[-1]}" if seeds else "no runs"
    if task == "station-keeping":
        r0 = rows[0] if rows else {}
        w = r0.get("wind")
        wtxt = "calm" if w is None else f"wind {w['speed']:g} m/s from {w['from_deg']:.0f} deg"
        return (
            f"Station keeping of {r0.get('vessel', '?')} (shipgym/StationKeeping-v0, observer "
            f"{obs}, {wtxt} with gusts, {r0.get('duration_s', 0):.0f} s, start up to 2 m and "
            f"5 deg off, {span}); inside: time within "
            f"{r0.get('radius_m', STATION_RADIUS):g} m of the set point (requirement: 95 %), "
            "r95: 95th percentile of the distance"
        )
    if wind is ENV_DEFAULT:
        w = "the vessel's nominal wind"
    else:
        wc = WindConfig.coerce(wind, name="wind")
        w = "calm" if wc is None else f"wind {wc.label()}"
    return (
        f"Controllers on the harbour manoeuvre (observer {obs}, {w}, {span}); J_c from the "
        "true pose, 'J_c measured' from the DGPS/gyro samples as in Tomera (2014) Table 6"
    )
