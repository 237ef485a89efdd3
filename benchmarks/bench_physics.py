"""Every packaged vessel's full plant, single and batched, and whole rudder-roll and sea-trial
episodes, against bare ``mujoco.mj_step`` on the same MuJoCo model (the Blue Lady's headline
ratios are ``bench_summary.py``'s).

Run with ``make bench``; the figures are written to ``runs/bench/bench_physics.json``
(``--json``). Each ratio is an interleaved pair (:func:`bench_summary.pair`): the two timings of
a repeat are taken one after the other, so that both see the same machine load; printed as the
median over the repeats with the smallest and largest. Every timing comes after a warm-up call
(the compiled step's first call loads it from Numba's cache, or compiles it), and records wall
and CPU (process) time.

Per vessel:

- ``physics_over_bare``: bare ``mj_step`` time over the single physics' time for the same
  steps, called as an env calls it: one control period (20 steps) per call (higher is better,
  1 = as fast as bare MuJoCo), with the ``mujoco`` integrator (MuJoCo's own ``mj_step`` with
  the hull's forces: the harbour's, with quay contact);
- ``physics_leapfrog_over_bare``: the same with the ``leapfrog`` integrator, the one the
  open-water envs step with (the same forces, no MuJoCo call);
- ``batched_hull_steps_per_s``: the batched physics, N = 256 hulls in a gusty wind (each its
  own gusts) and a Gauss-Markov current, 20 steps per call; ``batched_waves_ratio``: the same
  with the wave drift on (a sea of the vessel's scale, its grid ``Tp / 20``) over without. The
  realisations are generated as the hulls go (a chunk of 4096 samples of a grid at a time,
  after a first piece of 512), so each batched timing spans a whole number of chunks of the
  wave grid (or of the gusts' grid without waves; at least 4n hull-steps): a shorter timing
  would time some or none of the generation.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from bench_summary import _episode, machine, pair, print_machine

from shipgym.disturbances import CurrentConfig, WaveConfig, WindConfig
from shipgym.disturbances._grid import CHUNK
from shipgym.dynamics.vessel import load_vessel, vessel_names
from shipgym.envs.batchphysics import BatchedPhysics
from shipgym.envs.physics import VesselPhysics
from shipgym.envs.scene import build_model

#: the CPU seconds of the timings, beside their wall seconds
CPU: dict[str, list[float]] = {}


def _timed(key: str, fn: Callable[[], Any]) -> Callable[[], float]:
    """Wall time of ``fn()``; its CPU time appended to ``CPU[key]``."""

    def run() -> float:
        c0, t0 = time.process_time(), time.perf_counter()
        fn()
        wall = time.perf_counter() - t0
        CPU.setdefault(key, []).append(time.process_time() - c0)
        return wall

    return run


def _bare(key: str, model: Any, n: int) -> Callable[[], float]:
    d = mujoco.MjData(model)

    def steps() -> None:
        for _ in range(n):
            mujoco.mj_step(model, d)

    return _timed(key, steps)


def _fmt(r: dict) -> str:
    return f"{r['median']:.3f} [{r['min']:.3f}, {r['max']:.3f}]"


def _sea(v: Any) -> WaveConfig | None:
    """A sea of the vessel's scale: Hs 2.5 m, Tp 8 s at full scale, Froude-scaled; none for a
    hull written per unit inertia (Van der Klugt's: its task applies the wave moments itself,
    the drift of a sea is in newtons)."""
    if v.hull.m == 1.0:
        return None
    s = float(v.scale)
    return WaveConfig(Hs=2.5 / s, Tp=8.0 / math.sqrt(s), direction_from=math.radians(210.0))


def _whole_chunks(v: Any, calls: int) -> int:
    """At least ``calls`` calls of 20 steps, as many as span a whole number of chunks of the
    wave grid of :func:`_sea` (of the gusts' grid without one), within a call."""
    sea = _sea(v)
    grid = sea.grid_period if sea is not None else WindConfig().sample_period
    per_chunk = CHUNK * grid / BatchedPhysics(v, 1).h / 20.0  # calls a chunk lasts
    return max(1, round(math.ceil(calls / per_chunk) * per_chunk))


def _batched(v: Any, n_hulls: int, calls: int, waves: WaveConfig | None) -> Callable[[], None]:
    wind = WindConfig(speed=v.nominal_wind, direction_from=math.radians(300.0))
    current = CurrentConfig.from_std(0.3 / math.sqrt(v.scale), 0.5, 0.05, 300.0)
    bp = BatchedPhysics(v, n_hulls, wind=wind, current=current, waves=waves)
    bp.reset(rngs=[np.random.default_rng(i) for i in range(n_hulls)])
    bp.set_command(v.actuators.action_to_command(np.full(v.actuators.n_channels, 0.5)))
    bp.step(20)  # warm-up

    def run() -> None:
        for _ in range(calls):
            bp.step(20)

    return run


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--steps", type=int, default=30_000, help="physics steps per timing")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--hulls", type=int, default=256, help="hulls of the batched physics")
    ap.add_argument("--json", type=Path, default=Path("runs/bench/bench_physics.json"))
    args = ap.parse_args(argv)
    n, rep, nh = args.steps, args.repeats, args.hulls
    out: dict[str, Any] = {"steps": n, "repeats": rep, "hulls": nh, "machine": machine()}
    calls_b = max(1, n // (20 * nh) * 4)  # batched: about 4n hull-steps per timing
    for name in vessel_names():
        v = load_vessel(name)
        period = {}
        for integrator in ("mujoco", "leapfrog"):
            pv = VesselPhysics(v, wind=f"{v.nominal_wind:g}@300", integrator=integrator)
            pv.reset(rng=np.random.default_rng(0))
            pv.set_command(v.actuators.action_to_command(np.full(v.actuators.n_channels, 0.5)))
            pv.step(20)  # warm-up

            def calls(pv: VesselPhysics = pv) -> None:  # as an env calls the physics
                for _ in range(n // 20):
                    pv.step(20)

            period[integrator] = calls
        bare = _bare(f"{name}/bare", build_model(v), n)
        r = pair(bare, _timed(f"{name}/physics", period["mujoco"]), rep)
        lf = pair(bare, _timed(f"{name}/physics_leapfrog", period["leapfrog"]), rep)
        calls = _whole_chunks(v, calls_b)
        calm, sea = _batched(v, nh, calls, None), _batched(v, nh, calls, _sea(v))
        hs = calls * 20 * nh
        b = pair(_timed(f"{name}/batched", calm), _timed(f"{name}/batched_waves", sea), rep,
                 per_a=hs, per_b=hs)  # fmt: skip
        rec = {
            "physics_over_bare": r,
            "physics_steps_per_s": n / r["b_s"],
            "physics_leapfrog_over_bare": lf,
            "batched_hull_steps_per_s": 1.0 / b["a_s"],
            "batched_waves_ratio": b["a_s"] / b["b_s"],
            "cpu_s": {k.split("/")[1]: float(np.median(t)) for k, t in CPU.items()
                      if k.startswith(name + "/")},
        }  # fmt: skip
        out[name] = rec
        print(f"{name:16s} physics / bare mj_step {_fmt(r)} ({n / r['b_s']:,.0f} steps/s), "
              f"leapfrog {lf['median']:.2f}; "
              f"batched N = {nh}: {rec['batched_hull_steps_per_s'] / 1e6:.2f} M hull-steps/s, "
              f"with waves x{rec['batched_waves_ratio']:.2f}")  # fmt: skip
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
        phys = env.physics  # a batch of one has no MuJoCo model of its own: the same world's
        model = getattr(phys, "model", None) or build_model(phys.vessel, "open-water",
                                                            phys.actuators)  # fmt: skip
        r = pair(ep, _bare(key, model, steps), rep)
        sim = steps * getattr(phys, "timestep", getattr(phys, "h", None))
        out[key] = r
        print(f"{label:24s} / bare mj_step      : {_fmt(r)}   ({sim / r['a_s']:,.0f}x real time)")
    out["machine"] = machine(out["machine"])
    print_machine(out["machine"])
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(out, indent=2))
    print(f"written to {args.json}")
    return out


if __name__ == "__main__":
    main()
