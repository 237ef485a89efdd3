"""Cost per call of the disturbance queries the physics makes every step.

Run with ``make bench``. The wind, current and wave processes are precomputed on a time grid,
so a query is a grid lookup: ``Wind.at``, ``Current.at``, ``Waves.drift_load`` and
``Waves.wf_motion`` should each cost a few microseconds (target < 5 us, a Python-level
``mujoco.mj_step`` of the same model is printed for scale). Each figure is the best of several
repeats; absolute figures vary by +-30 % on a shared 2-core machine, the ratio to ``mj_step``
less so. (These figures were wall-clock assertions in the tests; timing belongs here.)
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable, Sequence

import mujoco
import numpy as np

from shipgym.disturbances import Current, CurrentConfig, WaveConfig, Waves, Wind, WindConfig
from shipgym.dynamics import BLUE_LADY_HULL, BLUE_LADY_WINDAGE, load_vessel
from shipgym.envs.scene import build_model

TARGET_US = 5.0
BF5 = {"Hs": 2.0 / 24, "Tp": (4.883 + 2.68 * 2.0**0.54) / math.sqrt(24)}  # Beaufort 5 at 1:24


def per_call(fn: Callable[..., object], args: Sequence[tuple], repeats: int) -> float:
    """Best seconds per call of ``fn(*a)`` over ``args``, over ``repeats`` passes."""
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        for a in args:
            fn(*a)
        best = min(best, (time.perf_counter() - t0) / len(args))
    return best


def main(argv: list[str] | None = None) -> dict[str, float]:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--calls", type=int, default=20_000, help="queries per repeat")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    n, dt = args.calls, 0.05
    times = [(100.0 + dt * k,) for k in range(n)]
    t_end = 100.0 + dt * n + 1.0

    m = build_model(load_vessel("blue-lady"))  # the Blue Lady's model on open water
    d = mujoco.MjData(m)
    mj = per_call(lambda: mujoco.mj_step(m, d), [()] * n, args.repeats)

    results: dict[str, float] = {}
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
        results[name] = per_call(proc.at, times, args.repeats)

    waves = Waves(WaveConfig(**BF5, first_order=True), BLUE_LADY_HULL)  # type: ignore[arg-type]
    waves.reset(np.random.default_rng(1))
    waves.envelope([t_end])
    results["Waves.drift_load, BF5"] = per_call(
        waves.drift_load, [(t, 0.3) for (t,) in times], args.repeats
    )
    results["Waves.wf_motion, BF5"] = per_call(waves.wf_motion, times, args.repeats)
    t0 = time.perf_counter()
    fresh = Waves(WaveConfig(**BF5, first_order=True), BLUE_LADY_HULL)  # type: ignore[arg-type]
    fresh.reset(np.random.default_rng(2))
    fresh.envelope([4096.0])
    precompute = (time.perf_counter() - t0) / 4096.0 * 3600.0

    print(f"bare mujoco.mj_step, Python loop (scale)  : {mj * 1e6:8.2f} us/call")
    for name, sec in results.items():
        flag = "" if sec * 1e6 <= TARGET_US else f"   (above the {TARGET_US:g} us target)"
        print(f"{name:<42}: {sec * 1e6:8.2f} us/call = {sec / mj:5.2f} x mj_step{flag}")
    print(f"wave precompute, BF5 first order + drift  : {precompute * 1e3:8.0f} ms per simulated h")
    results["mj_step"] = mj
    return results


if __name__ == "__main__":
    main()
