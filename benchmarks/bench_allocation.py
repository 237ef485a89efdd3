"""Cost per call of the thrust allocators (run with ``make bench``).

Four cases, each on a fixed set of requests (a third well inside the capacity, a third near it,
a third beyond it, so that the active-set methods work for their answer):

- ``allocate``: the Blue Lady's three fixed thrusters in closed form (Tomera 2014 eqs. 24-27);
- ``allocate_wls`` / ``WLSAllocator``: six fixed thrusters (two propellers, four tunnel
  thrusters), box-constrained weighted least squares, per call and prepared once;
- ``allocate_azimuth`` / ``AzimuthAllocator``: two tunnel thrusters and four azimuths
  (rate-limited, not reversible), and six azimuths (rate-limited, two of them reversible, which
  costs a second QP for the branch), each call starting from the previous call's angles as in
  a control loop; per call and prepared once.

Each figure is the median over ``--repeats`` passes of the mean time per call in one pass, in
microseconds; absolute figures vary by +-30 % on a shared 2-core machine.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections.abc import Callable, Sequence

import numpy as np

from shipgym.controllers.allocation import (
    AzimuthAllocator,
    Azimuths,
    WLSAllocator,
    allocate,
    allocate_azimuth,
    allocate_wls,
    extended_thrust_matrix,
)
from shipgym.dynamics import BLUE_LADY_THRUSTERS

# six fixed thrusters of a supply vessel: two propellers aft, two bow and two stern tunnels
B6 = np.array(
    [
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 1.0, 1.0, 1.0],
        [-4.0, 4.0, 32.0, 28.0, -28.0, -32.0],
    ]
)
LO6 = np.array([-190e3, -190e3, -80e3, -80e3, -60e3, -60e3])
HI6 = np.array([280e3, 280e3, 80e3, 80e3, 60e3, 60e3])
TUNNELS = (B6[:, 2:4], LO6[2:4], HI6[2:4])
AZ4 = np.array([[31.5, 5.0], [31.5, -5.0], [-31.5, 5.0], [-31.5, -5.0]])
AZ6 = np.array([[35.0, 0.0], [20.0, 6.0], [20.0, -6.0], [-30.0, 6.0], [-30.0, -6.0], [-38.0, 0.0]])
F_AZ = 122.6e3
RATE = math.radians(10.0)  # 10 deg/s at 1 s


def requests(cap: np.ndarray, n: int, seed: int = 0) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    levels = np.repeat([0.3, 0.9, 2.0], n // 3 + 1)[:n]
    return [rng.uniform(-1.0, 1.0, cap.size) * cap * lv for lv in levels]


def median_us(fn: Callable[[np.ndarray], object], args: Sequence[np.ndarray], repeats: int):
    per = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for a in args:
            fn(a)
        per.append((time.perf_counter() - t0) / len(args))
    return statistics.median(per) * 1e6


def azimuth_loop(az: Azimuths, fixed, prepared: bool) -> Callable[[np.ndarray], object]:
    """One control step: allocate from the previous call's angles and keep the new ones."""
    state = {"az": az, "angle": az.angle_prev}
    allocator = AzimuthAllocator(az, fixed=fixed)

    def step(tau: np.ndarray) -> object:
        r = allocate_azimuth(tau, state["az"], fixed=fixed)
        state["az"] = state["az"].with_angles(r.angle)
        return r

    def step_prepared(tau: np.ndarray) -> object:
        r = allocator(tau, state["angle"])
        state["angle"] = r.angle
        return r

    return step_prepared if prepared else step


def main(argv: list[str] | None = None) -> dict[str, float]:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--calls", type=int, default=600, help="requests per pass")
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args(argv)
    n, rep = args.calls, args.repeats

    p = BLUE_LADY_THRUSTERS
    cap3 = np.array([p.force_upper[0], 2 * p.force_upper[1], 250.0])
    cap6 = np.abs(B6) @ np.maximum(-LO6, HI6)
    b_az = np.hstack((TUNNELS[0], extended_thrust_matrix(AZ4)))
    cap_mix = np.abs(b_az) @ np.concatenate((np.maximum(-TUNNELS[1], TUNNELS[2]), [F_AZ] * 8))
    cap_az6 = np.abs(extended_thrust_matrix(AZ6)) @ np.full(12, F_AZ)
    prepared = WLSAllocator(B6, LO6, HI6)
    az4 = Azimuths(AZ4, np.full(4, F_AZ), np.zeros(4), RATE)
    az6 = Azimuths(
        AZ6, np.full(6, F_AZ), np.zeros(6), RATE, [False, True, True, False, False, False]
    )

    results = {
        "allocate, 3 fixed (Blue Lady)": median_us(
            lambda t: allocate(t, p), requests(cap3, n), rep
        ),
        "allocate_wls, 6 fixed": median_us(
            lambda t: allocate_wls(t, B6, LO6, HI6), requests(cap6, n), rep
        ),
        "WLSAllocator (prepared), 6 fixed": median_us(prepared, requests(cap6, n), rep),
        "allocate_azimuth, 2 tunnels + 4 azimuths": median_us(
            azimuth_loop(az4, TUNNELS, False), requests(cap_mix, n), rep
        ),
        "AzimuthAllocator (prepared), 2 tunnels + 4 az.": median_us(
            azimuth_loop(az4, TUNNELS, True), requests(cap_mix, n), rep
        ),
        "allocate_azimuth, 6 azimuths (2 reversible)": median_us(
            azimuth_loop(az6, None, False), requests(cap_az6, n), rep
        ),
        "AzimuthAllocator (prepared), 6 azimuths": median_us(
            azimuth_loop(az6, None, True), requests(cap_az6, n), rep
        ),
    }
    for name, us in results.items():
        print(f"{name:<47}: {us:8.1f} us/call")
    return results


if __name__ == "__main__":
    main()
