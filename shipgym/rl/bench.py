"""``shipgym bench controllers``: classical and learned controllers on the same harbour runs.

Every controller runs the 5-leg harbour manoeuvre (Tomera 2014) for the same seeds, wind and
observer; the runs go to worker processes in parallel (with a progress bar) and come back as
one row per controller and seed (:func:`bench_controllers`), summarised in one markdown table
(:func:`controller_table`): completion, quay contact, J_c (truth and measured, and relative to
the PID), time, thruster usage.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from shipgym.bench import mean_std as _ms
from shipgym.bench import run_jobs

from .evaluation import DEFAULT_WIND, check_observer, default_observer

__all__ = ["DEFAULT_CONTROLLERS", "bench_controllers", "controller_labels", "controller_table"]

#: pid, lq and the shipped PPO baseline
DEFAULT_CONTROLLERS = ("pid", "lq", "ppo")

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
    "rmse",
    "wall_time_s",
)


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


def _job(job: tuple[str, str, int, Any, str | None]) -> dict[str, Any]:
    """One harbour run in a worker process."""
    label, controller, seed, wind, observer = job
    import shipgym.controllers.lq  # noqa: F401  (registers "lq")
    from shipgym.controllers.learned import is_learned_controller

    if is_learned_controller(controller):
        import torch

        torch.set_num_threads(1)
    from .evaluation import run_controlled_episode

    res = run_controlled_episode("harbour", controller, seed=seed, observer=observer, wind=wind)
    row = {"controller": label, "controller_spec": controller, "observer": observer or "truth"}
    row.update({k: res[k] for k in _KEEP})
    return row


def bench_controllers(
    controllers: Sequence[str] = DEFAULT_CONTROLLERS,
    seeds: int = 10,
    *,
    wind: Any = DEFAULT_WIND,
    observer: str | None = "default",
    workers: int | None = None,
    progress: bool = True,
    on_row: Callable[[int, dict[str, Any]], None] | None = None,
    executor: Any = None,
) -> list[dict[str, Any]]:
    """Run the harbour manoeuvre for every controller and seed ``0..seeds-1``.

    Args:
        controllers: names: ``pid``, ``pid-seed``, ``lq``, ``ppo`` (the shipped baseline),
            ``ppo:PATH``, ``sac:PATH``.
        seeds: number of seeds per controller.
        wind: any form of :meth:`WindConfig.coerce <shipgym.disturbances.WindConfig.coerce>`
            (``"3@300"``: 3 m/s from 300 deg, the default; ``(speed m/s, from deg)``; a
            ``WindConfig``) or ``None`` (calm).
        observer: ``"default"`` (the Kalman-Bucy filter ``kbf`` when available, else the
            truth), ``"truth"``/``None`` or an observer name; the same for every controller.
        workers: processes (default: CPUs, at most the number of runs); 1 runs in-process.
        executor: the process pool (default) or Ray (:func:`shipgym.bench.run_jobs`).
        progress: show a progress bar.
        on_row: called with ``(index, row)`` as each run finishes (e.g.
            :meth:`shipgym.bench.RowLog.add`, which keeps finished rows on an interrupt).

    Returns:
        One row per controller and seed, in the order of ``controllers`` then seeds. Each row:
        ``controller`` (label), ``controller_spec`` (as given), ``observer``, ``seed``,
        ``completed``, ``legs_completed``, ``quay_contact``, ``duration_s``, ``x_E``, ``y_E``
        (m), ``psi_E`` (deg), ``J_c`` (truth), ``measured`` (indices from the measured pose),
        ``leg_times`` (s), ``thrust_mean_abs`` (N), ``thrust_total_variation`` (N),
        ``saturated_fraction``, ``rmse`` (observer), ``wall_time_s``.

    Raises:
        ValueError: unknown controller or observer names, a model file that is not a shipgym
            model (checked before any run).
    """

    from shipgym.controllers.learned import is_learned_controller, parse_learned_controller
    from shipgym.controllers.lq import register_lq
    from shipgym.controllers.wrappers import controller_spec
    from shipgym.disturbances import WindConfig

    register_lq()
    wind = WindConfig.coerce(wind, name="wind")
    if not (isinstance(seeds, int) and seeds >= 1):
        raise ValueError(f"seeds must be an int >= 1, got {seeds!r}")
    obs = default_observer() if observer == "default" else check_observer(observer)
    resolved = []
    for c in controllers:
        if is_learned_controller(c):
            algo, path = parse_learned_controller(c)
            resolved.append(f"{algo}:{path}")
        else:
            controller_spec(c)
            resolved.append(c)
    labels = controller_labels(list(controllers))
    jobs = [
        (label, c, s, wind, obs)
        for label, c in zip(labels, resolved, strict=True)
        for s in range(seeds)
    ]
    return run_jobs(
        _job, jobs, workers=workers, progress=progress, desc="controllers x seeds",
        on_result=on_row, executor=executor,
    )  # fmt: skip


def controller_table(rows: Sequence[dict[str, Any]]) -> str:
    """A markdown table, one line per controller (mean +- std over seeds).

    Columns: completed without quay contact, mean legs completed (of 5), quay contacts, J_c
    from the truth and from the measured pose (Tomera 2014 eq. 57), mean J_c relative to ``pid``
    (when present), time to complete (s; completed runs), mean |thrust| per actuator (N),
    wall time per run (s).
    """
    names = list(dict.fromkeys(r["controller"] for r in rows))
    pid = [r for r in rows if r["controller"] == "pid"]
    pid_jc = float(np.mean([r["J_c"] for r in pid])) if pid else math.nan
    head = (
        "| controller | runs | completed | legs | quay contact | J_c | J_c measured | J_c / pid "
        "| time (s) | mean abs thrust main/bow/stern (N) | wall (s) |"
    )
    lines = [head, "|" + "---|" * 11]
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
            f"| {' / '.join(f'{t:.1f}' for t in thrust)} "
            f"| {np.mean([r['wall_time_s'] for r in rs]):.1f} |"
        )
    return "\n".join(lines)


def bench_title(rows: Sequence[dict[str, Any]], wind: Any) -> str:
    """The one-line caption of :func:`controller_table` (``wind`` as for the bench)."""
    from shipgym.disturbances import WindConfig

    seeds = sorted({r["seed"] for r in rows})
    obs = rows[0]["observer"] if rows else "truth"
    wc = WindConfig.coerce(wind, name="wind")
    w = "calm" if wc is None else f"wind {wc.label()}"
    return (
        f"Controllers on the harbour manoeuvre (observer {obs}, {w}, seeds "
        f"{seeds[0]}-{seeds[-1]}); J_c from the true pose, 'J_c measured' from the DGPS/gyro "
        "samples as in Tomera (2014) Table 6"
    )
