"""Microseconds per call of :class:`~shipgym.guidance.batch.BatchedGuidance` (update +
reference, and the read-outs a batched env uses) at N envs, against a scalar
:class:`~shipgym.guidance.runtime.Guidance` per env.

The envs follow drawn Tracking-v0-like plans (1-3 legs of the four kinds) from random start
poses, the ship pose being the reference plus noise, so that legs switch during the timing;
finished envs are reset with new plans (as a vector env's autoreset would), outside the
timing. Run: ``python benchmarks/bench_batch_guidance.py [--n 256 1] [--steps 3000]``.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from shipgym.guidance import BLUE_LADY_LIMITS, Guidance, Leg, ManoeuvrePlan
from shipgym.guidance.batch import BatchedGuidance


def _plan(rng: np.random.Generator) -> ManoeuvrePlan:
    """A plan as ``TrackingEnv._episode_plan`` draws it (Blue Lady scale)."""
    legs = []
    for _ in range(int(rng.integers(1, 4))):
        kind = int(rng.integers(4))
        side = 1.0 if rng.random() < 0.5 else -1.0
        if kind == 0:
            legs.append(Leg(sway=side * rng.uniform(2.0, 8.0)))
        elif kind == 1:
            legs.append(Leg(surge=rng.uniform(5.0, 30.0) if side > 0 else -rng.uniform(3.0, 15.0)))
        elif kind == 2:
            legs.append(Leg(yaw=side * math.radians(rng.uniform(30.0, 120.0))))
        else:
            legs.append(Leg(surge=rng.uniform(3.0, 15.0), sway=side * rng.uniform(2.0, 5.0)))
    return ManoeuvrePlan(legs=tuple(legs), name="tracking")


def bench(n: int, steps: int, seed: int = 0) -> dict[str, float]:
    """Microseconds per call at ``n`` envs over ``steps`` control steps of 1 s (medians over
    the steps, and the mean of update + reference, switching steps included)."""
    rng = np.random.default_rng(seed)
    g = BatchedGuidance(n, limits=BLUE_LADY_LIMITS)
    g.reset([_plan(rng) for _ in range(n)], rng.normal(0.0, 20.0, (n, 3)))
    t = np.zeros(n)
    ref = g.reference(t)
    noise = rng.normal(0.0, 1.0, (steps, n, 3)) * [0.3, 0.3, 0.02]
    times = np.zeros((steps, 3))
    switches = 0
    pc = time.perf_counter
    for k in range(steps):
        t = t + 1.0
        eta = ref.eta_d_n + noise[k]
        t1 = pc()
        sw = g.update(t, eta)
        t2 = pc()
        ref = g.reference(t)
        t3 = pc()
        ref.to_r(eta), ref.nu_d, ref.nu_dot_d
        t4 = pc()
        times[k] = t2 - t1, t3 - t2, t4 - t3
        switches += int(sw.sum())
        done = g.finished
        if done.any():  # autoreset, outside the timing
            m = int(done.sum())
            g.reset([_plan(rng) for _ in range(m)], ref.eta_d_n, t0=t, mask=done.copy())
    # the median step (robust to other load on the machine) and the mean
    med, mean = np.median(times, axis=0) * 1e6, times.mean(axis=0) * 1e6
    out = {"update": med[0], "reference": med[1], "to_r+nu_d+nu_dot_d": med[2]}
    out["update+reference"] = float(np.median(times[:, 0] + times[:, 1]) * 1e6)
    out["update+reference (mean)"] = float(mean[0] + mean[1])
    out["switches"] = switches
    # the scalar Guidance per env, for comparison (a few steps)
    k = min(steps, 200)
    sc = [Guidance(_plan(rng), limits=BLUE_LADY_LIMITS) for _ in range(n)]
    for s in sc:
        s.reset(np.zeros(3))
    zero = np.zeros(3)
    t1 = pc()
    for j in range(k):
        for s in sc:
            s.update(float(j), zero)
            s.reference(float(j))
    out["scalar update+reference x n"] = (pc() - t1) * 1e6 / k
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--n", type=int, nargs="+", default=[256, 1])
    ap.add_argument("--steps", type=int, default=3000)
    args = ap.parse_args(argv)
    for n in args.n:
        r = bench(n, args.steps)
        parts = ", ".join(f"{key} {val:.1f}" for key, val in r.items() if key != "switches")
        print(f"N = {n:4d}: us per call: {parts} ({r['switches']} switches)")


if __name__ == "__main__":
    main()
