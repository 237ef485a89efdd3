"""Cost per call of the batched DP controller (:mod:`shipgym.controllers.batch`), Blue Lady.

For ``N = 1`` and ``N = 256`` envs and two kinds of state (``calm``: no pose error, so the
integral stays put over the repeated calls, small velocities, nothing saturates;
``saturated``: large errors, every env's allocation on a limit, conditional integration and
the clamp at work), the time of one call of

- ``BatchedPID`` (with the previous call's ``tau_error`` fed back),
- ``BatchedAllocation`` (``"constrained"``: the exact box-constrained least squares),
- ``BatchedDPController`` (both and the normalised action: one control period of N envs),

against the scalar stack per env (``MultivariablePID``, ``allocate``, ``command_to_action``).
Each figure is the median of ``--repeats`` passes of the mean over ``--number`` calls, in
microseconds; absolute figures vary by +-30 % on a shared 2-core machine.
"""

from __future__ import annotations

import argparse
import statistics
import timeit
from functools import partial

import numpy as np

from shipgym.controllers.actuation import make_allocator
from shipgym.controllers.batch import batched_dp_controller, controller_spec
from shipgym.dynamics.vessel import load_vessel


def _us(fn, number: int, repeats: int) -> float:
    return statistics.median(timeit.repeat(fn, number=number, repeat=repeats)) / number * 1e6


def _inputs(n: int, size: float, seed: int = 0):
    rng = np.random.default_rng(seed)
    eta_d = rng.normal(0.0, 1.0, (n, 3))
    eta = eta_d + rng.normal(0.0, size, (n, 3)) * [1.0, 1.0, 0.05]
    nu = rng.normal(0.0, 0.005 * max(size, 0.1), (n, 3)) * [1.0, 1.0, 0.01]
    return eta, nu, eta_d, np.zeros((n, 3)), np.zeros((n, 3))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--number", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=7)
    a = ap.parse_args()
    v = load_vessel("blue-lady")
    print(f"{'case':24s} {'BatchedPID':>11s} {'Allocation':>11s} {'PID+alloc+action':>17s}")
    for n in (1, 256):
        for label, size, warm in (("calm", 0.0, 1), ("saturated", 3.0, 50)):
            b = batched_dp_controller("pid", v, n, 1.0)
            x = _inputs(n, size)
            for _ in range(warm):
                b(*x)
            tau = b.pid(*x, saturated=b.tau_error)
            b.tau_error = b.allocation(tau).tau_error
            sat = int(b.allocation(tau).saturated.any(axis=1).sum())
            t_pid = _us(partial(b.pid, *x, saturated=b.tau_error), a.number, a.repeats)
            t_al = _us(partial(b.allocation, tau), a.number, a.repeats)
            t_all = _us(partial(b, *x), a.number, a.repeats)
            case = f"N={n} {label} ({sat} sat.)"
            print(
                f"{case:24s} {t_pid:9.1f} us {t_al:9.1f} us {t_all:12.1f} us"
                f"  = {t_all / n:6.2f} us/env"
            )
    c = controller_spec("pid").factory(v, 1.0)
    al = make_allocator(v, "constrained", 1.0)
    for label, size in (("calm", 0.0), ("saturated", 3.0)):
        x1 = tuple(z[0] for z in _inputs(1, size))

        def one(x1: tuple = x1) -> None:
            t = c(*x1, saturated=np.zeros(3))
            v.actuators.command_to_action(al(t, None).command)

        t1 = _us(one, 10 * a.number, a.repeats)
        print(f"scalar stack, {label:9s}  {t1:6.1f} us/env (x 256 envs: {256 * t1:7.0f} us)")


if __name__ == "__main__":
    main()
