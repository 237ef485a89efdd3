"""Physics step rate of the full plant vs bare ``mujoco.mj_step`` on the same MuJoCo model.

The Blue Lady in detail (plant, waves and current, a closed-loop harbour episode, a recorded
one), then the full plant of every other packaged vessel against its own bare model.

Run with ``make bench``. Reports ratios, which compare across machines; absolute rates vary
by +-30 % from run to run on a shared 2-core VM, so each figure is the best of several repeats.
"""

from __future__ import annotations

import argparse
import math
import time

import mujoco
import numpy as np

from shipgym.disturbances import WindConfig
from shipgym.dynamics.vessel import load_vessel, vessel_names
from shipgym.envs.physics import VesselPhysics
from shipgym.envs.scene import build_model


def _best_rate(fn, steps: int, repeats: int) -> float:
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn(steps)
        best = min(best, time.perf_counter() - t0)
    return steps / best


def _best_episode(env, repeats: int):  # type: ignore[no-untyped-def]
    """Best wall time of a whole zero-residual episode, and the last info."""
    best = math.inf
    info = {}
    for _ in range(repeats):
        env.reset(seed=0)
        t0 = time.perf_counter()
        done = False
        while not done:
            _, _, term, trunc, info = env.step(np.zeros(3, np.float32))
            done = term or trunc
        best = min(best, time.perf_counter() - t0)
    return best, info


def _episode_vs_bare(env, action, repeats: int) -> tuple[float, float]:  # type: ignore[no-untyped-def]
    """Best wall time (s) of one whole episode of ``env`` under a constant ``action``, and of
    bare ``mj_step`` on the env's model for the same number of physics steps."""
    wall = math.inf
    steps = 0
    for _ in range(repeats):
        env.reset(seed=0)
        t0 = time.perf_counter()
        done, steps = False, 0
        while not done:
            _, _, term, trunc, _ = env.step(action)
            done = term or trunc
            steps += 1
        wall = min(wall, time.perf_counter() - t0)
    n = steps * round(env.control_period / env.physics.timestep)
    m = env.physics.model
    d = mujoco.MjData(m)

    def bare(k: int) -> None:
        for _ in range(k):
            mujoco.mj_step(m, d)

    return wall, n / _best_rate(bare, n, repeats)


def main(argv: list[str] | None = None) -> dict[str, float]:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--steps", type=int, default=50_000, help="physics steps per repeat")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)

    m = build_model(load_vessel("blue-lady"))
    d = mujoco.MjData(m)
    d.ctrl[:] = [300.0, 0.5, -0.5]

    def bare_loop(n: int) -> None:
        for _ in range(n):
            mujoco.mj_step(m, d)

    def bare_c(n: int) -> None:
        mujoco.mj_step(m, d, nstep=n)

    wind = WindConfig(speed=3.0, direction_from=math.radians(300.0))
    phys = VesselPhysics("blue-lady", "default", wind=wind)
    phys.reset(rng=np.random.default_rng(0))
    phys.set_command([300.0, 0.5, -0.5])

    r_bare = _best_rate(bare_loop, args.steps, args.repeats)
    r_c = _best_rate(bare_c, args.steps, args.repeats)
    r_full = _best_rate(phys.step, args.steps, args.repeats)
    sim_rt = r_full * phys.timestep

    from shipgym.disturbances import CurrentConfig, WaveConfig

    waves = WaveConfig(Hs=0.083, Tp=1.79, n_components=100, drift=True, first_order=True)
    sea = VesselPhysics(
        "blue-lady", wind=wind, waves=waves, current=CurrentConfig.from_std(0.1, 0.5, 0.02, 300.0)
    )
    sea.reset(rng=np.random.default_rng(0))
    sea.set_command([300.0, 0.5, -0.5])
    r_sea = _best_rate(sea.step, args.steps, args.repeats)
    print(f"physics timestep                          : {phys.timestep:.3f} s")
    print(f"bare mujoco.mj_step, Python loop          : {r_bare:12,.0f} steps/s")
    print(f"bare mujoco.mj_step(nstep=N), C loop      : {r_c:12,.0f} steps/s")
    print(f"full plant (thrusters, gusty wind, hydro) : {r_full:12,.0f} steps/s")
    print(f"ratio full / bare Python-loop mj_step     : {r_full / r_bare:12.3f}   (target >= 0.2)")
    print(f"ratio full / bare C-loop mj_step          : {r_full / r_c:12.3f}")
    print(f"simulated seconds per wall second         : {sim_rt:12,.0f} x real time")
    print(f"+ 100 wave components, drift, GM current  : {r_sea:12,.0f} steps/s")
    print(f"  ratio with / without waves and current  : {r_sea / r_full:12.3f}   (target >= 0.5)")

    # one full closed-loop manoeuvre episode (guidance, PID, allocation, env, wrappers)
    import shipgym

    env = shipgym.make("harbour", controller="pid", wind="3@300")
    # interleave episode and bare stepping so that both see the same machine load
    best_wall, bare_same = math.inf, math.inf
    for _ in range(args.repeats):
        wall, info = _best_episode(env, 1)
        sim_t = info["t"]
        n_phys = round(sim_t / env.unwrapped.physics.timestep)
        t0 = time.perf_counter()
        bare_loop(n_phys)
        bare_same = min(bare_same, time.perf_counter() - t0)
        best_wall = min(best_wall, wall)
    print(f"closed-loop harbour episode               : {sim_t:.0f} s, {n_phys} physics steps")
    print(f"  wall time                               : {best_wall:12.3f} s")
    print(f"  bare mj_step, same number of steps      : {bare_same:12.3f} s")
    ratio, rt = best_wall / bare_same, sim_t / best_wall
    print(f"  ratio episode / bare mj_step            : {ratio:12.2f}   (target <= 8)")
    print(f"  faster than real time                   : {rt:12,.0f} x   (target >= 500)")

    # the same episode recorded to a rerun file (rerun imported beforehand, as in a session)
    import tempfile
    from pathlib import Path

    from shipgym.viz import RecordEpisode

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.rrd"
        rec = RecordEpisode(shipgym.make("harbour", controller="pid", wind="3@300"), path)
        rec_wall, _ = _best_episode(rec, args.repeats)
        rec.close()
        size_mb = max(p.stat().st_size for p in Path(tmp).glob("*.rrd")) / 1e6
    print(f"recorded harbour episode (rerun .rrd)     : {rec_wall:12.3f} s wall, {size_mb:.2f} MB")
    print(
        f"  ratio recorded / unrecorded             : {rec_wall / best_wall:12.2f}   (target <= 2)"
    )
    # every other packaged vessel: the full plant against bare mj_step on its own model
    others = {}
    for name in vessel_names():
        if name == "blue-lady":
            continue
        v = load_vessel(name)
        pv = VesselPhysics(v, wind=f"{v.nominal_wind:g}@300")
        pv.reset(rng=np.random.default_rng(0))
        pv.set_command(v.actuators.action_to_command(np.full(v.actuators.n_channels, 0.5)))
        mv = build_model(v)
        dv = mujoco.MjData(mv)

        def bare_v(n: int, mv=mv, dv=dv) -> None:  # type: ignore[no-untyped-def]
            for _ in range(n):
                mujoco.mj_step(mv, dv)

        rb, rf = _best_rate(bare_v, args.steps, args.repeats), _best_rate(pv.step, args.steps,
                                                                          args.repeats)  # fmt: skip
        others[name] = rf / rb
        print(
            f"{name:18s} full plant ({len(v.actuators)} actuators)   : {rf:12,.0f} steps/s, "
            f"ratio {rf / rb:.3f}"
        )
    # a rudder-roll episode (seed model at 12 m/s, its waves, the seed's rudder test, the sway
    # filter in the observation) against bare mj_step for the same number of physics steps
    from shipgym.envs.rollstab import RudderRollEnv

    renv = RudderRollEnv(vessel="van-der-klugt", speed=12.0, waves="seed", rudder_test=True,
                         sway_estimate=True, episode_duration=120.0)  # fmt: skip
    r_wall, bare_roll = _episode_vs_bare(renv, np.zeros(1, dtype=np.float32), args.repeats)
    print(
        f"rudder-roll episode (120 s, KF in the obs) : {r_wall:12.3f} s wall, "
        f"{120.0 / r_wall:,.0f}x real time, {r_wall / bare_roll:.1f}x bare mj_step"
    )
    # a sea trial (the 100 m tanker's 35 deg turn, 514 s, with the DGPS receiver; the script
    # acts at the receiver's 1 s) against bare mj_step for the same number of physics steps
    from shipgym.envs.seatrial import SeaTrialEnv

    tenv = SeaTrialEnv("kvlcc2-100m", "turning35_stbd", receiver="dgps-pv")
    t_wall, bare_trial = _episode_vs_bare(tenv, 0, args.repeats)
    print(
        f"sea trial (35 deg turn, {tenv.duration:.0f} s, DGPS)   : {t_wall:12.3f} s wall, "
        f"{tenv.duration / t_wall:,.0f}x real time, {t_wall / bare_trial:.1f}x bare mj_step"
    )
    return {
        "bare": r_bare,
        "roll_episode_ratio": r_wall / bare_roll,
        "trial_episode_ratio": t_wall / bare_trial,
        "bare_c": r_c,
        "full": r_full,
        "ratio": r_full / r_bare,
        "episode_ratio": best_wall / bare_same,
        **{f"ratio_{k}": val for k, val in others.items()},
    }


if __name__ == "__main__":
    main()
