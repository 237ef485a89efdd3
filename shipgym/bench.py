"""Benchmarks run from the command line: ``shipgym bench observers`` (seed001 Table 6 style).

Each run is one closed-loop harbour manoeuvre; runs go to worker processes in parallel.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import numpy as np

__all__ = [
    "DEFAULT_OBSERVERS",
    "bench_observers",
    "observer_table",
    "observer_traces",
    "velocity_error_trace",
]

DEFAULT_OBSERVERS = ("dkf", "kbf", "ekf")
_INDICES = ("x_E", "y_E", "psi_E", "J_c")
_RMSE = ("u", "v", "r", "x", "y", "psi")


def _one(job: tuple[str, int, tuple[float, float], str]) -> dict[str, Any]:
    from shipgym.cli import run_episode

    observer, seed, wind, controller = job
    res = run_episode("harbour", controller=controller, observer=observer, seed=seed, wind=wind)
    return {
        "observer": observer,
        "seed": seed,
        "completed": res["completed"],
        "quay_contact": res["quay_contact"],
        "duration_s": res["duration_s"],
        "truth": {k: res[k] for k in _INDICES},
        "measured": res["measured"],
        "rmse": res["rmse"],
    }


def velocity_error_trace(
    observer: str,
    seed: int = 0,
    wind: tuple[float, float] = (3.0, math.radians(300.0)),
    controller: str = "pid-smooth",
) -> dict[str, Any]:
    """Velocity estimation errors ``[u, v, r]`` over one harbour episode (for plots)."""
    import shipgym
    from shipgym.disturbances import WindConfig

    env = shipgym.make(
        "harbour", observer=observer, controller=controller,
        wind=WindConfig(speed=wind[0], direction_from=wind[1]),
    )  # fmt: skip
    env.reset(seed=seed)
    t, err = [], []
    done = False
    while not done:
        _, _, term, trunc, info = env.step(np.zeros(3, np.float32))
        t.append(info["t"])
        err.append(info["est_error_nu"])
        done = term or trunc
    env.close()
    return {"t": np.array(t), "err_nu": np.array(err)}


def _trace_job(job: tuple[str, tuple[float, float], str]) -> tuple[str, dict[str, Any]]:
    return job[0], velocity_error_trace(job[0], 0, job[1], job[2])


def observer_traces(
    observers: Sequence[str],
    wind: tuple[float, float],
    workers: int | None = None,
    controller: str = "pid-smooth",
) -> dict[str, dict[str, Any]]:
    """:func:`velocity_error_trace` of seed 0 for each observer, in parallel."""
    jobs = [(o, wind, controller) for o in observers]
    workers = workers or min(len(jobs), os.cpu_count() or 1)
    if workers <= 1:
        return dict(map(_trace_job, jobs))
    with ProcessPoolExecutor(max_workers=workers) as pool:
        return dict(pool.map(_trace_job, jobs))


def bench_observers(
    observers: Sequence[str] = DEFAULT_OBSERVERS,
    seeds: int = 10,
    wind: tuple[float, float] = (3.0, math.radians(300.0)),
    controller: str = "pid-smooth",
    workers: int | None = None,
    progress: bool = True,
) -> list[dict[str, Any]]:
    """Run the manoeuvre for every observer and seed; one row per run, in a fixed order."""
    from tqdm import tqdm

    jobs = [(obs, s, wind, controller) for obs in observers for s in range(seeds)]
    workers = workers or min(len(jobs), os.cpu_count() or 1)
    bar = tqdm(total=len(jobs), disable=not progress, desc="observers x seeds", unit="run")
    rows: list[dict[str, Any]] = []
    try:
        if workers <= 1:
            for job in jobs:
                rows.append(_one(job))
                bar.update(1)
        else:
            with ProcessPoolExecutor(max_workers=workers) as pool:
                for row in pool.map(_one, jobs):
                    rows.append(row)
                    bar.update(1)
    finally:
        bar.close()
    return rows


def observer_table(rows: Sequence[dict[str, Any]]) -> str:
    """A markdown table in the form of seed001 Table 6 (mean +- std over seeds)."""
    names = list(dict.fromkeys(r["observer"] for r in rows))
    head = (
        "| observer | runs | completed | x_E (m) | y_E (m) | psi_E (deg) | J_c "
        "| J_c truth | RMSE u (m/s) | RMSE v (m/s) | RMSE r (deg/s) |"
    )
    lines = [head, "|" + "---|" * 11]
    for name in names:
        rs = [r for r in rows if r["observer"] == name]
        meas = {k: np.array([r["measured"][k] for r in rs]) for k in _INDICES}
        truth = np.array([r["truth"]["J_c"] for r in rs])
        rm = {k: np.array([r["rmse"][k] for r in rs]) for k in ("u", "v", "r")}
        done = sum(r["completed"] and not r["quay_contact"] for r in rs)

        def ms(a: np.ndarray, f: str = ".4f") -> str:
            return f"{a.mean():{f}} +- {a.std():{f}}"

        lines.append(
            f"| {name} | {len(rs)} | {done}/{len(rs)} | {ms(meas['x_E'])} | {ms(meas['y_E'])} "
            f"| {ms(meas['psi_E'], '.3f')} | {ms(meas['J_c'])} | {ms(truth)} "
            f"| {ms(rm['u'], '.5f')} | {ms(rm['v'], '.5f')} | {ms(rm['r'], '.4f')} |"
        )
    return "\n".join(lines)
