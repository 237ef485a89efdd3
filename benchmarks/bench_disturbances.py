"""Cost per call of the disturbance queries the physics makes every step.

Run with ``make bench``. The wind, current and wave processes are precomputed on a time grid,
so a query is a grid lookup: ``Wind.at``, ``Current.at``, ``Waves.drift_load`` and
``Waves.wf_motion`` should each cost a few microseconds (target < 5 us). Each query is timed
as an interleaved pair with a Python-level ``mujoco.mj_step`` loop of the same model
(:func:`bench_summary.pair`: the order alternates between repeats, so both see the same load)
and printed as microseconds per call and its ratio to one ``mj_step``, median [min, max] over
the repeats. (These figures were wall-clock assertions in the tests; timing belongs here.)
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections.abc import Callable, Sequence

import numpy as np
from bench_summary import _bare, _timed, pair

from shipgym.disturbances import Current, CurrentConfig, WaveConfig, Waves, Wind, WindConfig
from shipgym.dynamics import BLUE_LADY_HULL, BLUE_LADY_WINDAGE, load_vessel
from shipgym.envs.scene import build_model

TARGET_US = 5.0
BF5 = {"Hs": 2.0 / 24, "Tp": (4.883 + 2.68 * 2.0**0.54) / math.sqrt(24)}  # Beaufort 5 at 1:24


def _calls(fn: Callable[..., object], args: Sequence[tuple]) -> Callable[[], None]:
    def run() -> None:
        for a in args:
            fn(*a)

    return run


def main(argv: list[str] | None = None) -> dict[str, float]:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--calls", type=int, default=20_000, help="queries per repeat")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    n, dt = args.calls, 0.05
    times = [(100.0 + dt * k,) for k in range(n)]
    t_end = 100.0 + dt * n + 1.0

    m = build_model(load_vessel("blue-lady"))  # the Blue Lady's model on open water
    bare = _bare(m, n)

    def paired(fn: Callable[..., object], calls: Sequence[tuple]) -> dict:
        return pair(_timed(_calls(fn, calls)), bare, args.repeats, per_a=len(calls), per_b=n)

    results: dict[str, dict] = {}
    wind_gm = Wind(WindConfig(speed=3.0), BLUE_LADY_WINDAGE)
    wind_harris = Wind(
        WindConfig(speed=3.0, gust_spectrum="harris", direction_std=0.1), BLUE_LADY_WINDAGE
    )
    current = Current(CurrentConfig.from_std(0.1, 0.5, std=0.02, direction_std=0.1))
    for name, proc in (
        ("Wind.at, Gauss-Markov gusts", wind_gm),
        ("Wind.at, Harris gusts", wind_harris),
        ("Current.at, Gauss-Markov", current),
    ):
        proc.reset(np.random.default_rng(1))
        proc.series(np.array([0.0, t_end]))  # generate the grid first: time the lookups only
        results[name] = paired(proc.at, times)

    waves = Waves(WaveConfig(**BF5, first_order=True), BLUE_LADY_HULL)  # type: ignore[arg-type]
    waves.reset(np.random.default_rng(1))
    waves.envelope([t_end])
    results["Waves.drift_load, BF5"] = paired(waves.drift_load, [(t, 0.3) for (t,) in times])
    results["Waves.wf_motion, BF5"] = paired(waves.wf_motion, times)
    t0 = time.perf_counter()
    fresh = Waves(WaveConfig(**BF5, first_order=True), BLUE_LADY_HULL)  # type: ignore[arg-type]
    fresh.reset(np.random.default_rng(2))
    fresh.envelope([4096.0])
    precompute = (time.perf_counter() - t0) / 4096.0 * 3600.0

    mj = statistics.median(r["b_s"] for r in results.values())
    print(f"bare mujoco.mj_step, Python loop (scale)  : {mj * 1e6:8.2f} us/call")
    for name, r in results.items():
        us = r["a_s"] * 1e6
        flag = "" if us <= TARGET_US else f"   (above the {TARGET_US:g} us target)"
        print(f"{name:<42}: {us:8.2f} us/call = {r['median']:5.2f} x mj_step "
              f"[{r['min']:.2f}, {r['max']:.2f}]{flag}")  # fmt: skip
    print(f"wave precompute, BF5 first order + drift  : {precompute * 1e3:8.0f} ms per simulated h")
    return {**{k: r["a_s"] for k, r in results.items()}, "mj_step": mj}


if __name__ == "__main__":
    main()
