"""Every packaged vessel's full plant, and whole rudder-roll and sea-trial episodes, against
bare ``mujoco.mj_step`` on the same MuJoCo model (the Blue Lady's headline ratios are
``bench_summary.py``'s).

Run with ``make bench``. Each ratio is an interleaved pair (:func:`bench_summary.pair`): the
two timings of a repeat are taken one after the other, so that both see the same machine
load; printed as the median over the repeats with the smallest and largest.
"""

from __future__ import annotations

import argparse

import mujoco
import numpy as np
from bench_summary import _bare, _episode, _timed, pair

from shipgym.dynamics.vessel import load_vessel, vessel_names
from shipgym.envs.physics import VesselPhysics
from shipgym.envs.scene import build_model


def _fmt(r: dict) -> str:
    return f"{r['median']:.3f} [{r['min']:.3f}, {r['max']:.3f}]"


def main(argv: list[str] | None = None) -> dict[str, float]:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--steps", type=int, default=30_000, help="physics steps per timing")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    n, rep = args.steps, args.repeats
    out: dict[str, float] = {}
    m = build_model(load_vessel("blue-lady"))
    d = mujoco.MjData(m)
    c_loop = pair(_bare(m, n), _timed(lambda: mujoco.mj_step(m, d, nstep=n)), rep)
    print(f"bare mj_step: Python-loop time / C-loop time   : {_fmt(c_loop)}")
    out["python_loop_over_c_loop"] = c_loop["median"]
    for name in vessel_names():
        v = load_vessel(name)
        pv = VesselPhysics(v, wind=f"{v.nominal_wind:g}@300")
        pv.reset(rng=np.random.default_rng(0))
        pv.set_command(v.actuators.action_to_command(np.full(v.actuators.n_channels, 0.5)))
        pv.step(20)  # outside the timings: the first call loads the compiled step
        # as an env calls the physics: one control period (20 steps) per call
        period = _timed(lambda pv=pv: [pv.step(20) for _ in range(n // 20)])
        r = pair(_bare(build_model(v), n), period, rep)
        out[f"ratio_{name}"] = r["median"]
        print(f"{name:18s} full plant / bare mj_step     : {_fmt(r)}   ({n / r['b_s']:,.0f} "
              f"steps/s, 20 steps a call)")  # fmt: skip
    # a rudder-roll episode (seed model at 12 m/s, its waves, the seed's rudder test, the sway
    # filter in the observation) and a sea trial (the 100 m tanker's 35 deg turn with the DGPS
    # receiver) against bare mj_step for the same number of physics steps
    from shipgym.envs.rollstab import RudderRollEnv
    from shipgym.envs.seatrial import SeaTrialEnv

    renv = RudderRollEnv(vessel="van-der-klugt", speed=12.0, waves="seed", rudder_test=True,
                         sway_estimate=True, episode_duration=120.0)  # fmt: skip
    tenv = SeaTrialEnv("kvlcc2-100m", "turning35_stbd", receiver="dgps-pv")
    for key, env, action, label in (
        ("roll_episode_ratio", renv, np.zeros(1, dtype=np.float32), "rudder-roll episode"),
        ("trial_episode_ratio", tenv, 0, "sea trial (35 deg turn)"),
    ):
        ep, steps = _episode(env, action)
        r = pair(ep, _bare(env.physics.model, steps), rep)
        sim = steps * env.physics.timestep
        out[key] = r["median"]
        print(f"{label:24s} / bare mj_step      : {_fmt(r)}   ({sim / r['a_s']:,.0f}x real time)")
    return out


if __name__ == "__main__":
    main()
