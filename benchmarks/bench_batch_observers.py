"""Microseconds per step of the batched Kalman filters (shipgym.observers.batch) at N = 256
and N = 1, against one scalar filter's step: thread CPU time, best of 10 blocks of 400 steps.

    PYTHONPATH=. python benchmarks/bench_batch_observers.py
"""

from __future__ import annotations

import time

import numpy as np

from shipgym.observers.base import make_observer
from shipgym.observers.batch import BatchedKalman

PRESETS = ("kbf", "dkf", "tomera-kbf", "tomera-dkf")


def _best(fn, blocks: int = 10, reps: int = 400) -> float:
    out = []
    for _ in range(blocks):
        t0 = time.thread_time()
        fn(reps)
        out.append((time.thread_time() - t0) / reps * 1e6)
    return min(out)


def batched(name: str, n: int, valid_frac: float = 1.0, coast: bool = False) -> float:
    rng = np.random.default_rng(0)
    f = BatchedKalman(name, n)
    f.reset(0.0, np.zeros((n, 3)))
    Z = rng.normal(0.0, 0.1, (400, n, 3))
    V = rng.random((400, n)) < valid_frac
    clock = {"t": 0.0}

    def run(reps: int) -> None:
        for k in range(reps):
            clock["t"] += 1.0
            t = np.full(n, clock["t"])
            if coast:
                f.step(t, None)
            else:
                f.step(t, Z[k], V[k] if valid_frac < 1.0 else None)

    run(20)
    return _best(run)


def scalar(name: str) -> float:
    o = make_observer(name)
    o.reset(0.0, np.zeros(3))
    z = np.random.default_rng(0).normal(0.0, 0.1, (400, 3))
    clock = {"t": 0.0}

    def run(reps: int) -> None:
        for k in range(reps):
            clock["t"] += 1.0
            o.step(clock["t"], z[k])

    run(20)
    return _best(run)


def main() -> None:
    print("preset       N=256 step  (10% dropouts, coast)   N=1 step   scalar step  (us)")
    for name in PRESETS:
        print(
            f"{name:11s} {batched(name, 256):10.1f}  ({batched(name, 256, 0.9):6.1f}, "
            f"{batched(name, 256, coast=True):5.1f})      {batched(name, 1):8.1f}   "
            f"{scalar(name):8.1f}"
        )


if __name__ == "__main__":
    main()
