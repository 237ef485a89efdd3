"""The ``shipgym`` command.

``shipgym demo``  open-loop turn of the Blue Lady in gusty wind, with a short summary;
``shipgym list``  plant variants, wind coefficient sets and actuators.

User mistakes end with a one-line error and exit status 2, never with a traceback.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
import time

import numpy as np

__all__ = ["main", "parse_wind"]


def parse_wind(text: str) -> tuple[float, float]:
    """Parse ``SPEED@FROM_DEG`` (m/s, degrees the wind comes from) into ``(speed, from_rad)``."""
    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*@\s*(-?[0-9]*\.?[0-9]+)\s*", text)
    if not m:
        raise argparse.ArgumentTypeError(
            f"malformed wind {text!r}: expected SPEED@FROM_DEG, e.g. 3@300 (3 m/s from 300 deg)"
        )
    return float(m.group(1)), math.radians(float(m.group(2)))


def _cmd_list(args: argparse.Namespace) -> int:
    from shipgym.disturbances import BLENDERMANN
    from shipgym.dynamics import ACTUATOR_NAMES, PLANT_VARIANTS

    print("plant variants :", ", ".join(PLANT_VARIANTS))
    print("wind models    :", ", ".join(f"blendermann:{k}" for k in BLENDERMANN))
    print("actuators      :", ", ".join(ACTUATOR_NAMES))
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    from shipgym.disturbances import WindConfig
    from shipgym.envs.physics import VesselPhysics

    speed, beta = args.wind
    phys = VesselPhysics(args.plant, wind=WindConfig(speed=speed, direction_from=beta))
    phys.reset(rng=np.random.default_rng(args.seed))
    # open loop: half ahead, bow thruster to starboard and stern thruster to port (turn right)
    phys.set_command([300.0, 0.8, -0.8])
    steps = round(args.duration / phys.timestep)
    chunk = max(1, round(10.0 / phys.timestep))
    x0 = phys.eta
    path = 0.0
    wind_x, wind_y, wind_n = [], [], []
    t0 = time.perf_counter()
    last = phys.eta
    done = 0
    while done < steps:
        n = min(chunk, steps - done)
        phys.step(n)
        done += n
        eta = phys.eta
        path += float(np.hypot(*(eta[:2] - last[:2])))
        last = eta
        wx, wy, wn = phys.tau_wind
        wind_x.append(wx)
        wind_y.append(wy)
        wind_n.append(wn)
    wall = time.perf_counter() - t0
    eta, nu = phys.eta, phys.nu
    print("shipgym demo: Blue Lady open-loop turn (main propeller 300 rpm, bow +0.8, stern -0.8)")
    print(f"  plant {phys.plant.name!r}, wind {speed:.1f} m/s from {math.degrees(beta):.0f} deg")
    print(
        f"  simulated {phys.time:.0f} s in {wall:.2f} s wall ({phys.time / wall:,.0f}x real time)"
    )
    print(f"  start  x = {x0[0]:7.2f} m, y = {x0[1]:7.2f} m, psi = {math.degrees(x0[2]):7.1f} deg")
    print(
        f"  end    x = {eta[0]:7.2f} m, y = {eta[1]:7.2f} m, "
        f"psi = {math.degrees(eta[2]):7.1f} deg (heading change)"
    )
    print(f"  speed  u = {nu[0]:.3f} m/s, v = {nu[1]:.3f} m/s, r = {math.degrees(nu[2]):.3f} deg/s")
    print(f"  path length {path:.1f} m; thrust now {np.round(phys.thrust, 1).tolist()} N")
    print(
        f"  wind load (sampled every 10 s): X {np.mean(wind_x):6.1f} N, "
        f"Y {np.mean(wind_y):6.1f} N, "
        f"N {np.mean(wind_n):6.1f} N m on average"
    )
    return 0


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="shipgym", description="Ship manoeuvring simulator (MuJoCo).")
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("list", help="list plant variants, wind models and actuators")
    p.set_defaults(func=_cmd_list)
    p = sub.add_parser("demo", help="open-loop turn in gusty wind; prints a summary")
    p.add_argument("--wind", type=parse_wind, default=(3.0, math.radians(300.0)),
                   metavar="SPEED@FROM_DEG", help="mean wind, e.g. 3@300 (default)")  # fmt: skip
    p.add_argument("--plant", default="default", help="plant variant (see 'shipgym list')")
    p.add_argument("--duration", type=float, default=300.0, help="simulated seconds (300)")
    p.add_argument("--seed", type=int, default=0, help="seed of the wind gusts (0)")
    p.set_defaults(func=_cmd_demo)
    return ap


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``shipgym`` console script."""
    args = _parser().parse_args(argv)
    try:
        return int(args.func(args))
    except (ValueError, FileNotFoundError) as exc:
        print(f"shipgym: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("shipgym: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
