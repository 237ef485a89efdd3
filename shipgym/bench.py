"""Benchmarks run from the command line: ``shipgym bench observers`` (Tomera 2014 Table 6 style).

Each run is one closed-loop harbour manoeuvre; runs go to worker processes in parallel.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import numpy as np

__all__ = [
    "DEFAULT_OBSERVERS",
    "bench_observers",
    "observer_table",
    "observer_traces",
    "run_jobs",
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


def run_jobs(
    fn: Callable[[Any], Any],
    jobs: Sequence[Any],
    *,
    workers: int | None = None,
    progress: bool = True,
    desc: str = "runs",
) -> list[Any]:
    """``[fn(job) for job in jobs]`` in worker processes, in order, with a progress bar.

    ``fn`` must be a module-level function (picklable). Forks unless torch is loaded in this
    process (forking a process with torch's thread pools can hang): then ``forkserver``.
    """
    from tqdm import tqdm

    n = workers or min(len(jobs), os.cpu_count() or 1)
    bar = tqdm(total=len(jobs), disable=not progress, desc=desc, unit="run")
    out: list[Any] = []
    try:
        if n <= 1:
            for job in jobs:
                out.append(fn(job))
                bar.update(1)
        else:
            method = "forkserver" if "torch" in sys.modules else None
            ctx = multiprocessing.get_context(method)
            with ProcessPoolExecutor(max_workers=n, mp_context=ctx) as pool:
                for res in pool.map(fn, jobs):
                    out.append(res)
                    bar.update(1)
    finally:
        bar.close()
    return out


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
    return dict(run_jobs(_trace_job, jobs, workers=workers, progress=False))


def bench_observers(
    observers: Sequence[str] = DEFAULT_OBSERVERS,
    seeds: int = 10,
    wind: tuple[float, float] = (3.0, math.radians(300.0)),
    controller: str = "pid-smooth",
    workers: int | None = None,
    progress: bool = True,
) -> list[dict[str, Any]]:
    """Run the manoeuvre for every observer and seed; one row per run, in a fixed order."""
    jobs = [(obs, s, wind, controller) for obs in observers for s in range(seeds)]
    return run_jobs(_one, jobs, workers=workers, progress=progress, desc="observers x seeds")


def observer_table(rows: Sequence[dict[str, Any]]) -> str:
    """A markdown table in the form of Tomera (2014) Table 6 (mean +- std over seeds)."""
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
