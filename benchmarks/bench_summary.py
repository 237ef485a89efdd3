"""The headline speed ratios of shipgym, measured as interleaved pairs, with their spread.

Every ratio divides two timings taken in the same repeat, one right after the other (the order
alternating from repeat to repeat), so that both see the same machine load; each is printed as
the median over the repeats with the smallest and largest repeat, and all are written to
``runs/bench/bench.json`` (``--json``):

- ``physics_over_bare``: physics steps per second of the Blue Lady's full plant (thrusters,
  gusty wind, hydrodynamics) over bare ``mujoco.mj_step`` on the same model (higher is better);
  ``physics_period_over_bare`` the same called as an env calls it, one control period (20
  steps) per call;
- ``waves_over_no_waves``: the full plant with 100 wave components, drift and a Gauss-Markov
  current over the plain full plant (higher is better);
- ``episode_pid_over_bare``, ``episode_kbf_pid_over_bare``: the wall time of a whole
  closed-loop harbour episode (PID; the KBF observer and PID) over bare ``mj_step`` for the
  same number of physics steps (lower is better); ``episode_kbf_pid_mujoco_over_bare`` the
  same with ``integrator="mujoco"`` (MuJoCo's ``mj_step`` and its contacts instead of the
  compiled step and its quay-contact check);
- ``tracking_step_over_bare``: one ``shipgym/Tracking-v0`` step (random actions) over bare
  ``mj_step`` for its physics steps (lower is better);
- ``recording_overhead``: a recorded harbour episode (rerun) over an unrecorded one;
- ``allocation_us_6_thrusters``: the prepared least-squares allocator over six fixed thrusters,
  microseconds per call (median);
- ``batched_physics_hull_steps_per_s`` (N = 256) and ``batched_physics_over_single``: the
  batched physics (:class:`~shipgym.envs.batchphysics.BatchedPhysics`: plant, actuators and
  gusty wind) against the single MuJoCo physics in the same wind, hull-steps per second, each
  timing a whole chunk of the gusts' grid (8192 steps: their generation is in the figure);
- ``batched_hull_steps_per_s`` (N = 256) and ``batched_over_single``: the native
  batched ``Tracking`` env (:class:`~shipgym.envs.vector.ShipVectorEnv`: gusty wind, sensors,
  the KBF observer) in hull-steps per second, and over the single env with the same stack
  (``shipgym.make(..., observer="kbf")``), interleaved;
- ``vector_n1_over_single``: the batched env of one env over the single env, same stack
  (lower is better; the single plan-task env is that vector env of one with its single-env
  ``info`` and its typed step record, so this is the cost of those; these figures run the
  task's whole episodes, 801 steps a timing, with their autoresets, after a warm-up);
- ``closed_loop_n256``: hull-steps per second (wall and CPU) of each vessel on its own task
  with the whole stack at N = 256 (:data:`CLOSED_LOOPS`), over one whole episode of the task
  with its autoresets; ``closed_loop_n256_short`` the same over ``EPISODE_STEPS``-step
  episodes (reset-heavy);
- ``dp_every_step_over_pvs``: control at every physics step, shipgym's DP env over
  PythonVehicleSimulator's DP loop per step (lower is better; needs ``PVS_SRC``);
- ``ppo_fps_batched_over_single``: stable-baselines3 PPO's training rate (rollouts and
  updates, the shipped hyperparameters and KBF + PID-residual stack, 32 envs) on the batched
  env over the same on ``DummyVecEnv`` of single envs (``null`` without the ``rl`` extra);
  ``ppo_update_share_batched`` and ``ppo_env_share_batched`` the shares of SB3's update
  (``PPO.train``, the same work on both sides) and of the batched env's steps in the batched
  learn, and ``ppo_fps_ratio_bound`` the ratio a batched env and rollout that cost nothing
  would reach (the single learn over the update alone).

Every ratio records the CPU time beside the wall time (``cpu_median``, ``a_cpu_s``,
``b_cpu_s``). Absolute rates are printed too (this machine's); ratios are what compares
across machines. ``machine`` records the cores, Numba's threads, the load average
(runnable processes, 1 min) before and after the run, and the share of the cores other
processes kept busy in the second before it (``busy_before``; the load average still counts a
run that ended less than a minute before, such as the previous script of ``make bench``):
where another process was busy, the figures that run on threads (N = 256) read low.
``physics_step`` names the physics step that ran (:mod:`shipgym.sim.step`, compiled by Numba).
Run with ``make bench``.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

Timed = Callable[[], float]


def _busy_elsewhere(seconds: float = 1.0) -> float | None:
    """The share of all cores busy over ``seconds`` while this process sleeps (so: other
    processes, and the VM's stolen time), from Linux's ``/proc/stat``; ``None`` elsewhere.
    Unlike the load average, which decays over a minute, it does not count a run that just
    ended (``make bench``'s scripts one after the other)."""

    def ticks() -> tuple[int, int]:
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:]]
        idle = v[3] + v[4]  # idle, iowait
        return sum(v[:8]) - idle, sum(v[:8])

    try:
        b0, t0 = ticks()
        time.sleep(seconds)
        b1, t1 = ticks()
    except (OSError, ValueError, IndexError):
        return None
    return round((b1 - b0) / max(t1 - t0, 1), 2)


def machine(before: dict[str, Any] | None = None) -> dict[str, Any]:
    """The machine a run measures: cores, Numba's threads, versions, the 1-min load average
    now (``load_before``) and the share of the cores other processes keep busy
    (``busy_before``, :func:`_busy_elsewhere`), or, given the record made before the run,
    that record with ``load_after``."""
    import os
    import platform

    load = round(os.getloadavg()[0], 2) if hasattr(os, "getloadavg") else None
    if before is not None:
        return {**before, "load_after": load}
    import numba

    return {
        "cores": os.cpu_count(),
        "numba_threads": int(numba.config.NUMBA_NUM_THREADS),
        "python": platform.python_version(),
        "numba": numba.__version__,
        "mujoco": mujoco.__version__,
        "load_before": load,
        "busy_before": _busy_elsewhere(),
    }


def print_machine(m: dict[str, Any]) -> None:
    busy = m.get("busy_before")
    print(f"machine: {m['cores']} cores, {m['numba_threads']} Numba threads; load average "
          f"(1 min) {m['load_before']} before, {m.get('load_after')} after; other processes "
          f"busy before: {'?' if busy is None else f'{busy:.0%}'} of the cores")  # fmt: skip
    if busy is not None and busy > 0.2:
        print("  note: another process was busy before the run: the threaded figures read low")


def _timed(fn: Callable[[], Any]) -> Timed:
    def run() -> float:
        t0 = time.perf_counter()
        fn()
        return time.perf_counter() - t0

    return run


def pair(a: Timed, b: Timed, repeats: int, *, per_a: float = 1.0, per_b: float = 1.0) -> dict:
    """``(time of a / per_a) / (time of b / per_b)`` per repeat, a and b interleaved.

    Returns ``{"median", "min", "max", "a_s", "b_s", "cpu_median", "a_cpu_s", "b_cpu_s"}``:
    the wall-time ratios, the median wall seconds of each side per unit ``per_a`` /
    ``per_b``, and the same of the process's CPU time (all threads; measured around each
    call).
    """

    def call(f: Timed, per: float) -> tuple[float, float]:
        c0 = time.process_time()
        wall = f()
        return wall / per, (time.process_time() - c0) / per

    ratios, cpu, ta, tb, ca, cb = [], [], [], [], [], []
    for k in range(repeats):
        if k % 2 == 0:
            x, y = call(a, per_a), call(b, per_b)
        else:
            y, x = call(b, per_b), call(a, per_a)
        ta.append(x[0])
        tb.append(y[0])
        ca.append(x[1])
        cb.append(y[1])
        ratios.append(ta[-1] / tb[-1])
        cpu.append(ca[-1] / cb[-1] if cb[-1] > 0 else math.nan)
    med = statistics.median
    return {"median": med(ratios), "min": min(ratios), "max": max(ratios), "a_s": med(ta),
            "b_s": med(tb), "cpu_median": med(cpu), "a_cpu_s": med(ca),
            "b_cpu_s": med(cb)}  # fmt: skip


def _bare(model: Any, n: int) -> Timed:
    d = mujoco.MjData(model)

    def run() -> float:
        t0 = time.perf_counter()
        for _ in range(n):
            mujoco.mj_step(model, d)
        return time.perf_counter() - t0

    return run


def _episode(env: Any, action: Any) -> tuple[Timed, int]:
    """A timed whole episode (reset excluded) and its number of physics steps."""
    box: dict[str, int] = {}

    def run() -> float:
        env.reset(seed=0)
        t0 = time.perf_counter()
        done, steps = False, 0
        while not done:
            _, _, term, trunc, _ = env.step(action)
            done = term or trunc
            steps += 1
        wall = time.perf_counter() - t0
        box["steps"] = steps
        return wall

    run()
    u = env.unwrapped
    h = getattr(u.physics, "timestep", None) or u.physics.h  # (a batch of one: h)
    return run, box["steps"] * round(u.control_period / h)


def measure(repeats: int = 5, steps: int = 30_000) -> dict[str, Any]:
    """Every figure of the module docstring (a dict, as written to ``bench.json``)."""
    import shipgym
    from shipgym.disturbances import CurrentConfig, WaveConfig, WindConfig
    from shipgym.dynamics import load_vessel
    from shipgym.envs.physics import VesselPhysics
    from shipgym.envs.scene import build_model

    out: dict[str, Any] = {"repeats": repeats}
    model = build_model(load_vessel("blue-lady"))
    wind = WindConfig(speed=3.0, direction_from=math.radians(300.0))
    phys = VesselPhysics("blue-lady", wind=wind)
    phys.reset(rng=np.random.default_rng(0))
    phys.set_command([300.0, 0.5, -0.5])
    waves = WaveConfig(Hs=0.083, Tp=1.79, n_components=100, drift=True, first_order=True)
    sea = VesselPhysics("blue-lady", wind=wind, waves=waves,
                        current=CurrentConfig.from_std(0.1, 0.5, 0.02, 300.0))  # fmt: skip
    sea.reset(rng=np.random.default_rng(0))
    sea.set_command([300.0, 0.5, -0.5])
    # a first step of each outside the timings (the compiled step's first call loads it from
    # Numba's cache, or compiles it)
    out["physics_step"] = "compiled (shipgym.sim.step)"
    phys.step(1)
    sea.step(1)
    bare = _bare(model, steps)
    r = pair(bare, _timed(lambda: phys.step(steps)), repeats)
    out["physics_over_bare"] = r
    out["bare_steps_per_s"] = steps / r["a_s"]
    out["physics_steps_per_s"] = steps / r["b_s"]
    # as an env calls it: one control period (20 physics steps) per call
    period = _timed(lambda: [phys.step(20) for _ in range(steps // 20)])
    out["physics_period_over_bare"] = pair(bare, period, repeats)
    out["waves_over_no_waves"] = pair(
        _timed(lambda: phys.step(steps)), _timed(lambda: sea.step(steps)), repeats
    )
    for key, observer, integ in (
        ("episode_pid_over_bare", None, None),
        ("episode_kbf_pid_over_bare", "kbf", None),
        ("episode_kbf_pid_mujoco_over_bare", "kbf", "mujoco"),
    ):
        env = shipgym.make("harbour", controller="pid", observer=observer, wind="3@300",
                           integrator=integ)  # fmt: skip
        ep, n = _episode(env, np.zeros(3, np.float32))
        out[key] = pair(ep, _bare(env.unwrapped.physics.model, n), repeats)
        env.close()
    env = shipgym.make("shipgym/Tracking-v0", vessel="blue-lady")
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    acts = [rng.uniform(-1, 1, env.action_space.shape).astype(np.float32) for _ in range(200)]
    u = env.unwrapped
    n_sub = round(u.control_period / u.physics.timestep)

    def tracking() -> None:
        env.reset(seed=0)
        for a in acts:
            _, _, term, trunc, _ = env.step(a)
            if term or trunc:
                env.reset(seed=0)

    out["tracking_step_over_bare"] = pair(
        _timed(tracking), _bare(u.physics.model, len(acts) * n_sub), repeats
    )
    env.close()
    from shipgym.viz import RecordEpisode

    with tempfile.TemporaryDirectory() as tmp:
        rec = RecordEpisode(shipgym.make("harbour", controller="pid", wind="3@300"),
                            Path(tmp) / "bench.rrd")  # fmt: skip
        plain = shipgym.make("harbour", controller="pid", wind="3@300")
        er, _ = _episode(rec, np.zeros(3, np.float32))
        ep, _ = _episode(plain, np.zeros(3, np.float32))
        out["recording_overhead"] = pair(er, ep, max(3, repeats // 2))
        rec.close()
        plain.close()
    from bench_allocation import B6, HI6, LO6, requests

    from shipgym.controllers.allocation import WLSAllocator

    alloc = WLSAllocator(B6, LO6, HI6)
    reqs = requests(np.abs(B6) @ np.maximum(-LO6, HI6), 600)
    per = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for q in reqs:
            alloc(q)
        per.append((time.perf_counter() - t0) / len(reqs) * 1e6)
    out["allocation_us_6_thrusters"] = statistics.median(per)
    # the batched physics (plant, actuators, gusty wind) against the single MuJoCo physics in
    # the same wind, the same hull-steps
    from shipgym.disturbances._grid import CHUNK
    from shipgym.envs.batchphysics import BatchedPhysics

    nb = 256
    bp = BatchedPhysics("blue-lady", nb, wind=wind)
    # a timing spans a whole chunk of the gusts' grid: its generation (a chunk at a time) is
    # in the figure as often as over a long run
    kb = round(CHUNK / bp.winds[0].sample_rate / bp.h)
    bp.reset(rngs=[np.random.default_rng(i) for i in range(nb)])
    bp.set_command([300.0, 0.5, -0.5])
    calm = phys  # the single full plant in the same gusty wind
    rb = pair(_timed(lambda: calm.step(nb * kb // 4)), _timed(lambda: bp.step(kb)), repeats,
              per_a=nb * kb // 4, per_b=nb * kb)  # fmt: skip
    out["batched_physics_over_single"] = rb
    out["batched_physics_hull_steps_per_s"] = 1.0 / rb["b_s"]
    out.update(_batched_env(repeats))
    out.update(_closed_loops(max(3, repeats // 2)))
    pvs = _pvs_dp(repeats)
    if pvs is None:
        out.setdefault("missing", {})["dp_every_step_over_pvs"] = (
            "PythonVehicleSimulator not importable: set PVS_SRC to its checkout's src folder"
        )
    else:
        out["dp_every_step_over_pvs"] = pvs
    return out


#: the training stack the batched figures time: the Tracking task (gusty wind, DGPS and
#: gyrocompass sensors) with the KBF observer
BATCHED_STACK = {"observer": "kbf"}


#: control steps per episode of the reset-heavy closed-loop figure (``closed_loop_n256_short``):
#: each timing runs two such episodes of every env, their autoresets (batched) included
EPISODE_STEPS = 50


def _rollout(venv: Any, steps: int, warm: bool = True) -> Timed:
    """``steps`` zero-action steps of a vector env, autoresets included; ``warm``: reset
    (seed 0) and run once first (else the caller warmed it up and reset it)."""
    zeros = np.zeros(venv.action_space.shape, np.float32)

    def run() -> float:
        t0 = time.perf_counter()
        for _ in range(steps):
            venv.step(zeros)
        return time.perf_counter() - t0

    if warm:
        venv.reset(seed=0)
        run()  # warm-up: the compiled laws loaded, one episode and its resets done
    return run


def _batched_env(repeats: int, n: int = 256) -> dict[str, Any]:
    """``batched_hull_steps_per_s`` (N = ``n``) and ``batched_over_single``: the native
    batched Tracking env with gusts, sensors and the KBF against the single env with the same
    stack (``shipgym.make(..., observer="kbf")``), hull-steps per second over whole episodes
    with their resets, interleaved; ``vector_n1_over_single``: the batched env of one env over
    the single env (lower is better); and ``ppo_fps_batched_over_single`` (:func:`_ppo_fps`)."""
    import gymnasium as gym

    import shipgym

    env_id = "shipgym/BlueLadyTracking-v0"
    # whole episodes of the task (its registered 800 steps, or its end): a timing's steps
    # span about two of them with their autoresets
    k = gym.spec(env_id).max_episode_steps + 1
    limit: dict[str, Any] = {}
    venv = gym.make_vec(env_id, num_envs=n, **limit, **BATCHED_STACK)
    one = gym.make_vec(env_id, num_envs=1, **limit, **BATCHED_STACK)
    single = shipgym.make(env_id, **limit, **BATCHED_STACK)
    rng = np.random.default_rng(0)
    acts = rng.uniform(-1, 1, (k, 3)).astype(np.float32)
    n_sub = venv.unwrapped.n_substeps

    def single_run() -> float:
        single.reset(seed=0)
        t0 = time.perf_counter()
        for a in acts:
            _, _, term, trunc, _ = single.step(a)
            if term or trunc:
                single.reset()
        return time.perf_counter() - t0

    single_run()  # warm-up
    r = pair(_timed(single_run), _rollout(venv, k), repeats, per_a=k * n_sub,
             per_b=k * n * n_sub)  # fmt: skip
    out: dict[str, Any] = {
        "batched_hull_steps_per_s": 1.0 / r["b_s"],
        "single_hull_steps_per_s": 1.0 / r["a_s"],
        "batched_over_single": r,
        "batched_num_envs": n,
    }
    # the batch of one against the single env: > 1 means the batch of one is slower
    out["vector_n1_over_single"] = pair(_rollout(one, k), _timed(single_run), repeats)
    ppo = _ppo_fps(env_id, max(3, repeats // 2))
    out["ppo_fps_batched_over_single"] = ppo
    if ppo is not None:
        out["ppo_fps_batched"] = 1.0 / ppo["b_s"]
        out["ppo_fps_single"] = 1.0 / ppo["a_s"]
        # SB3's update, the same on both sides, caps the ratio (Amdahl): its share of the
        # batched learn, and the ratio a batched env and rollout of no cost would reach
        out["ppo_update_share_batched"] = ppo.pop("update_share_batched")
        out["ppo_env_share_batched"] = ppo.pop("env_share_batched")
        out["ppo_fps_ratio_bound"] = ppo.pop("bound")
    else:
        out["missing"] = {"ppo_fps_batched_over_single": "needs the rl extra (make rl)"}
    return out


#: the batched closed loops: (name, id, arguments): each vessel on its own task with the
#: whole stack (gusts, sensors, the KBF, the PID with its allocation, guidance)
CLOSED_LOOPS: tuple[tuple[str, str, dict[str, Any]], ...] = (
    ("blue-lady/tracking", "shipgym/BlueLadyTracking-v0", {"observer": "kbf", "controller": "pid"}),
    ("blue-lady/harbour", "shipgym/BlueLadyHarbour-v0", {"observer": "kbf", "controller": "pid"}),
    ("blue-lady/harbour-mujoco", "shipgym/BlueLadyHarbour-v0",
     {"observer": "kbf", "controller": "pid", "integrator": "mujoco"}),
    ("star-hercules/dp", "shipgym/DPStationKeeping-v0",
     {"vessel": "star-hercules", "observer": "kbf", "controller": "pid"}),
    ("wimpey-sealab/dp", "shipgym/DPStationKeeping-v0",
     {"vessel": "wimpey-sealab", "observer": "kbf", "controller": "pid"}),
    ("van-der-klugt/roll", "shipgym/RudderRollStabilisation-v0", {"episode_duration": 60.0}),
    ("naval-vessel/roll", "shipgym/NavalRollDamping-v0", {"episode_duration": 60.0}),
    ("kvlcc2-100m/course", "shipgym/CourseKeeping-v0", {"episode_duration": 60.0}),
    ("kvlcc2-100m/trial", "shipgym/SeaTrial-v0", {}),
)  # fmt: skip


def _task_episode(venv: Any, env_id: str) -> int:
    """Control steps of one whole episode of the task behind ``venv``: the registered step
    limit of a plan task, ``episode_duration / control_period`` of the roll and course tasks,
    the longest manoeuvre of a sea trial."""
    import gymnasium as gym

    u = venv.unwrapped
    limit = gym.spec(env_id).max_episode_steps
    if limit is not None:
        return int(limit)
    if getattr(u, "episode_duration", None) is not None:
        return math.ceil(u.episode_duration / u.control_period - 1e-9)
    return int(np.max(u.max_steps))


def _closed_loops(repeats: int, n: int = 256) -> dict[str, Any]:
    """Hull-steps per second (wall and CPU) of each :data:`CLOSED_LOOPS` entry at N = ``n``:

    - ``closed_loop_n256``: one whole episode of the task (:func:`_task_episode`: 800 steps of
      tracking, 2000 of the harbour, 2000 s of DP, ...) from a seeded reset, with the
      autoreset step that begins the next (every env's episode, early ends and their batched
      autoresets included), after a warm-up; one timing (a long average);
    - ``closed_loop_n256_short``: ``2 * EPISODE_STEPS`` steps of episodes cut at
      :data:`EPISODE_STEPS` (the plan tasks) or the task's own (the others), the median of
      ``repeats``: a reset-heavy figure (four resets of every env per 200 steps).

    An id without a vector entry point is listed under ``closed_loop_missing``."""
    import gymnasium as gym

    import shipgym  # noqa: F401  (registers the ids)

    whole: dict[str, Any] = {}
    short: dict[str, Any] = {}
    missing: dict[str, str] = {}
    for name, env_id, kwargs in CLOSED_LOOPS:
        spec = gym.spec(env_id)
        if spec.vector_entry_point is None:
            missing[name] = f"{env_id} has no vector entry point"
            continue
        # the plan tasks end at a step limit; the other families at their episode_duration
        # (the entry's 60 s of the roll and course tasks, or their registered 600 s) or their
        # manoeuvre's end (the sea trials)
        plan = spec.vector_entry_point.startswith("shipgym.envs.vector")
        cut = {"max_episode_steps": EPISODE_STEPS} if plan else {}
        venv = gym.make_vec(env_id, num_envs=n, **kwargs, **cut)
        k = 2 * EPISODE_STEPS
        short[name] = _hull_steps(venv, n, _rollout(venv, k), k, repeats)
        own = {key: v for key, v in kwargs.items() if key != "episode_duration"}
        limit = {"max_episode_steps": spec.max_episode_steps} if plan else {}
        venv = gym.make_vec(env_id, num_envs=n, **own, **limit)
        _rollout(venv, 2 * EPISODE_STEPS)  # warm-up, then one whole episode from a reset
        venv.reset(seed=1)
        k = _task_episode(venv, env_id) + 1
        whole[name] = _hull_steps(venv, n, _rollout(venv, k, warm=False), k, 1)
    return {"closed_loop_n256": whole, "closed_loop_n256_short": short,
            "closed_loop_missing": missing}  # fmt: skip


def _hull_steps(venv: Any, n: int, run: Timed, steps: int, repeats: int) -> dict[str, Any]:
    """Hull-steps per second (wall and CPU; median, min, max over ``repeats``) of ``run``, a
    rollout of ``steps`` control steps of the vector env ``venv`` of ``n`` envs
    (:func:`_rollout`), which it closes."""
    u = venv.unwrapped
    sub = getattr(u, "n_substeps", None) or round(u.control_period / u.physics.timestep)
    walls, cpus = [], []
    for _ in range(repeats):
        c0 = time.process_time()
        walls.append(run())
        cpus.append(time.process_time() - c0)
    venv.close()
    hs = n * steps * sub
    return {"hull_steps_per_s": hs / statistics.median(walls),
            "hull_steps_per_cpu_s": hs / statistics.median(cpus),
            "min": hs / max(walls), "max": hs / min(walls), "control_steps": steps}  # fmt: skip


def _pvs_dp(repeats: int, steps: int = 3000) -> dict[str, Any] | None:
    """Control at every physics step, per step: shipgym's single DP env (Star Hercules, the
    PID and its allocation, ``control_period = timestep``) over PythonVehicleSimulator's DP
    loop (Fossen's supply vessel, ``lib.mainLoop.simulate``: pole-placement DP, actuator
    dynamics, 6-DOF model), the same number of steps, interleaved (lower is better).
    PythonVehicleSimulator is not on PyPI: point ``PVS_SRC`` at the ``src`` folder of a
    checkout (cybergalactic/PythonVehicleSimulator); ``None`` without it."""
    import os
    import sys

    src = os.environ.get("PVS_SRC")
    if src:
        sys.path.insert(0, src)
    try:
        from python_vehicle_simulator.lib.mainLoop import simulate
        from python_vehicle_simulator.vehicles import supply
    except ImportError:
        return None
    import shipgym

    env = shipgym.make("shipgym/StationKeeping-v0", vessel="star-hercules", controller="pid",
                       timestep=0.05, control_period=0.05, max_episode_steps=10**9)  # fmt: skip
    zero = np.zeros(env.action_space.shape, np.float32)

    def ours() -> float:
        env.reset(seed=0)
        t0 = time.perf_counter()
        for _ in range(steps):
            env.step(zero)
        return time.perf_counter() - t0

    def theirs() -> float:
        vehicle = supply("DPcontrol", 4.0, 4.0, 50.0, 0.5, -20.0)
        t0 = time.perf_counter()
        simulate(steps - 1, 0.02, vehicle)  # steps - 1: its loop runs N + 1 steps
        return time.perf_counter() - t0

    ours()
    theirs()
    return pair(ours, theirs, repeats, per_a=steps, per_b=steps)


def _ppo_fps(env_id: str, repeats: int, n_envs: int = 32, n_steps: int = 32) -> Any:
    """PPO's training rate (environment steps per second, rollouts and updates together) on
    the native batched env over the same on SB3's ``DummyVecEnv`` of the single envs: the
    shipped hyperparameters and stack (KBF, PID residual), ``n_envs`` envs, ``n_steps``
    steps per rollout, one rollout and update per timing. ``None`` without the rl extra."""
    try:
        import torch
        from stable_baselines3 import PPO
    except ImportError:
        return None
    torch.set_num_threads(1)  # as shipgym train: small networks, one thread is fastest
    from shipgym.rl.train import _algo_kwargs, build_vec_env, load_hyperparams

    hp = dict(load_hyperparams("ppo", env_id, residual=True), n_steps=n_steps,
              batch_size=n_steps * n_envs // 4)  # fmt: skip
    models = {}
    for kind in ("dummy", "batched"):
        venv = build_vec_env(env_id, hp, n_envs, 0, kind)
        models[kind] = PPO(hp.get("policy", "MlpPolicy"), venv, seed=0, device="cpu",
                           **_algo_kwargs("ppo", hp))  # fmt: skip
        models[kind].learn(n_steps * n_envs)  # warm up (first rollout, first update)

    def learn(kind: str) -> Callable[[], Any]:
        return lambda: models[kind].learn(n_steps * n_envs, reset_num_timesteps=False)

    steps = n_steps * n_envs
    out = pair(_timed(learn("dummy")), _timed(learn("batched")), repeats, per_a=steps,
               per_b=steps)  # fmt: skip
    # the update alone (PPO.train on the last rollout, the same work on either env): what the
    # batched learn cannot lose; the ratio's bound with an env and rollout that cost nothing
    update = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        models["batched"].train()
        update.append((time.perf_counter() - t0) / steps)
    u = statistics.median(update)
    # the batched env's steps alone (zero actions), the rest of the rollout being SB3's
    venv = models["batched"].get_env()
    zeros = np.zeros((n_envs, *venv.action_space.shape), np.float32)
    env = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n_steps):
            venv.step(zeros)
        env.append((time.perf_counter() - t0) / steps)
    out["update_share_batched"] = u / out["b_s"]
    out["env_share_batched"] = statistics.median(env) / out["b_s"]
    out["bound"] = out["a_s"] / u
    return out


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--steps", type=int, default=30_000, help="physics steps per plant timing")
    ap.add_argument("--json", type=Path, default=Path("runs/bench/bench.json"))
    args = ap.parse_args(argv)
    before = machine()
    res = measure(args.repeats, args.steps)
    res["machine"] = machine(before)
    print_machine(res["machine"])
    print(res["physics_step"])
    print(f"ratios: median [min, max] over {args.repeats} interleaved repeats")
    for k, v in res.items():
        if isinstance(v, dict) and "median" in v:
            print(f"  {k:28s}: {v['median']:8.3f}  [{v['min']:.3f}, {v['max']:.3f}]")
    print(f"  {'bare mj_step':28s}: {res['bare_steps_per_s']:10,.0f} steps/s")
    print(f"  {'full plant':28s}: {res['physics_steps_per_s']:10,.0f} steps/s")
    print(f"  {'allocation_us_6_thrusters':28s}: {res['allocation_us_6_thrusters']:8.1f} us")
    print(f"  {'batched physics, N = 256':28s}: {res['batched_physics_hull_steps_per_s']:10,.0f} "
          "hull-steps/s")  # fmt: skip
    print(f"  {'batched env, N = 256':28s}: {res['batched_hull_steps_per_s']:10,.0f} hull-steps/s")
    print(f"  {'single env':28s}: {res['single_hull_steps_per_s']:10,.0f} hull-steps/s")
    if res.get("ppo_fps_batched") is not None:
        print(f"  {'PPO, batched / DummyVecEnv':28s}: {res['ppo_fps_batched']:10,.0f} / "
              f"{res['ppo_fps_single']:,.0f} steps/s; of the batched learn the update "
              f"{res['ppo_update_share_batched']:.0%}, the env "
              f"{res['ppo_env_share_batched']:.0%}; the ratio's bound "
              f"{res['ppo_fps_ratio_bound']:.2f}")  # fmt: skip
    print(
        "closed loops, N = 256, hull-steps/s (wall; CPU): one whole episode of the task "
        f"(steps) | {2 * EPISODE_STEPS} steps of {EPISODE_STEPS}-step episodes:"
    )
    for name, v in res["closed_loop_n256"].items():
        c = res["closed_loop_n256_short"][name]
        print(f"  {name:28s}: {v['hull_steps_per_s']:10,.0f}; {v['hull_steps_per_cpu_s']:,.0f} "
              f"({v['control_steps']}) | {c['hull_steps_per_s']:10,.0f}; "
              f"{c['hull_steps_per_cpu_s']:,.0f}")  # fmt: skip
    for name, why in {**res["closed_loop_missing"], **res.get("missing", {})}.items():
        print(f"  {name:28s}: not measured ({why})")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    flat = {k: (v["median"] if isinstance(v, dict) and "median" in v else v)
            for k, v in res.items()}  # fmt: skip
    flat["spread"] = {k: [v["min"], v["max"]] for k, v in res.items()
                      if isinstance(v, dict) and "median" in v}  # fmt: skip
    args.json.write_text(json.dumps(flat, indent=2))
    print(f"written to {args.json}")
    return flat


if __name__ == "__main__":
    main()
