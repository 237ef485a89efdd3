"""The batched physics against the MuJoCo single physics: the same commands give the same
trajectories (same integration scheme) for every 3-DOF vessel; resets by mask; bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shipgym import _jit
from shipgym.disturbances import Current, CurrentConfig, WaveConfig, Wind, WindConfig
from shipgym.disturbances._grid import CHUNK
from shipgym.dynamics.mmg import MMGHull
from shipgym.dynamics.vessel import load_vessel, vessel_names
from shipgym.envs.batchphysics import BatchedPhysics
from shipgym.envs.physics import VesselPhysics

PLANAR = [n for n in vessel_names() if load_vessel(n).dofs == 3]


def _start(bp: BatchedPhysics) -> tuple[np.ndarray, np.ndarray, float]:
    """Rest, or an MMG hull's approach speed with its shaft at the self-propulsion point."""
    nu0 = np.zeros((bp.n, 3))
    act0 = bp.initial_actuator_state()
    n0 = 0.0
    if isinstance(bp.plant, MMGHull):
        U = bp.vessel.approach_speed
        n0 = bp.plant.model.self_propulsion(U)
        nu0[:, 0] = U
        act0[:, 0] = n0
    return nu0, act0, n0


GUSTY = WindConfig(speed=8.0, direction_from=math.radians(300.0), sample_period=1.0)
GM_CURRENT = CurrentConfig.from_std(0.3, 0.5, 0.05, 300.0)


def _gap(bp: BatchedPhysics, singles: list[VesselPhysics]) -> float:
    """The largest pose and velocity difference (m, rad, m/s, rad/s) of the batched hulls from
    their single physics; their actuator states must agree to 1e-9."""
    eta = np.array([p.eta for p in singles])
    nu = np.array([p.nu for p in singles])
    np.testing.assert_allclose(bp.actuator_state, [p.actuator_state for p in singles],
                               rtol=0, atol=1e-9)  # fmt: skip
    return max(float(np.abs(eta - bp.eta).max()), float(np.abs(nu - bp.nu).max()))


@pytest.mark.parametrize("name", PLANAR)
@pytest.mark.parametrize("sea", ["calm", "wind+current"])
def test_same_commands_same_trajectories_as_the_mujoco_physics(name: str, sea: str) -> None:
    """300 s of random, partly saturating commands changed every 10 s, three hulls each with
    its own commands (and its own gusts and Gauss-Markov current, drawn from its own seed):
    every pose and velocity within 1e-6 m, m/s and rad of the single physics."""
    n = 3
    wind, current = (None, None) if sea == "calm" else (GUSTY, GM_CURRENT)
    bp = BatchedPhysics(name, n, wind=wind, current=current)
    acts = bp.actuators
    nu0, act0, n0 = _start(bp)
    bp.reset(nu=nu0, actuators=act0, rngs=[np.random.default_rng(20 + i) for i in range(n)])
    singles = []
    for i in range(n):
        p = VesselPhysics(name, wind=wind, current=current)
        p.reset(nu=nu0[i], actuators=act0[i], rng=np.random.default_rng(20 + i))
        singles.append(p)
    rng = np.random.default_rng(7)
    err = 0.0
    for _ in range(30):
        a = np.clip(rng.normal(0.0, 0.7, (n, acts.n_channels)), -1.3, 1.3)
        cmd = acts.action_to_command(np.clip(a, -1, 1)) * np.where(np.abs(a) > 1, 1.2, 1.0)
        if n0:
            cmd[:, 0] = n0 * (0.85 + 0.15 * np.clip(a[:, 0], -1, 1))
        flags = bp.set_command(cmd)
        for i, p in enumerate(singles):
            np.testing.assert_array_equal(flags[i], p.set_command(cmd[i]))
        bp.step(200)
        for p in singles:
            p.step(200)
        err = max(err, _gap(bp, singles))
    assert np.abs(bp.eta[:, :2]).max() > 5.0  # the hulls moved
    assert err < 1e-6, err


def test_a_mask_resets_some_hulls_only():
    bp = BatchedPhysics("blue-lady", 4)
    bp.set_command([300.0, 0.5, -0.5])
    bp.step(100)
    before = bp.eta
    bp.reset(eta=[1.0, 2.0, 0.3], mask=[False, True, False, True])
    after = bp.eta
    np.testing.assert_array_equal(after[[0, 2]], before[[0, 2]])
    np.testing.assert_array_equal(after[[1, 3]], [[1.0, 2.0, 0.3]] * 2)
    np.testing.assert_allclose(bp.nu[[1, 3]], 0.0, atol=1e-12)


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="has 3 DOF but vessel .naval-vessel. has 4"):
        BatchedPhysics("naval-vessel", 2, plant=load_vessel("blue-lady").plant())
    with pytest.raises(ValueError, match=r"n must be an int in \[1, 65536\]"):
        BatchedPhysics("blue-lady", 0)
    bp = BatchedPhysics("blue-lady", 2)
    with pytest.raises(ValueError, match=r"command must be \(3,\) or \(2, 3\)"):
        bp.set_command(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="finite"):
        bp.set_command([np.nan, 0.0, 0.0])


def test_the_loops_grid_lookup_reads_what_each_process_reads():
    """Gusts and a Gauss-Markov current of five seeds, read by the physics loop's lookup from
    each process's public grid (``chunk(j)``) at times past a chunk's end too: the same values
    as each process's own scalar query."""
    from shipgym.dynamics import BLUE_LADY_WINDAGE
    from shipgym.sim.step import grid_at

    winds = [Wind(GUSTY, BLUE_LADY_WINDAGE) for _ in range(5)]
    currents = [Current(GM_CURRENT) for _ in range(5)]
    for i, (w, c) in enumerate(zip(winds, currents, strict=True)):
        g = np.random.default_rng(i)
        w.reset(g)
        c.reset(g)
    rng = np.random.default_rng(3)
    for top in (100.0, CHUNK * 1.0 + 50.0, 3 * CHUNK * 1.0):
        for t in rng.uniform(0.0, top, 5).tolist():
            for proc, clamp in [(w, True) for w in winds] + [(c, False) for c in currents]:
                j = int(t * proc.sample_rate) // CHUNK
                win = np.ascontiguousarray(proc.chunk(j)[None])
                ok, a, b = grid_at(t, proc.sample_rate, j * CHUNK, win, 0)
                assert ok and ((max(a, 0.0) if clamp else a), b) == proc.at(t)
                assert not grid_at(t, proc.sample_rate, (j + 1) * CHUNK, win, 0)[0]


def test_each_hull_its_own_wind_and_current():
    """Hulls given their own wind (one none) and current by set_disturbances move as a single
    physics with that wind and current."""
    cases = [(GUSTY, None), (None, GM_CURRENT), ("2@45", "0.2@90"), (None, None)]
    bp = BatchedPhysics("blue-lady", len(cases), wind="3@300")
    for i, (w, c) in enumerate(cases):
        bp.set_disturbances(i, w, c)
    assert bp.wind_configs[1] is None and bp.current_configs[2].speed == pytest.approx(0.2)
    bp.reset(rngs=[np.random.default_rng(5 + i) for i in range(len(cases))])
    singles = []
    for i, (w, c) in enumerate(cases):
        p = VesselPhysics("blue-lady", wind=w, current=c)
        p.reset(rng=np.random.default_rng(5 + i))
        singles.append(p)
    cmd = np.array([[300.0, 0.5, -0.5], [-150.0, -0.3, 0.8], [100.0, 1.0, 1.0], [0.0, 0.2, 0.2]])
    bp.set_command(cmd)
    for i, p in enumerate(singles):
        p.set_command(cmd[i])
        p.step(1200)
    bp.step(1200)
    np.testing.assert_allclose(bp.eta, [p.eta for p in singles], rtol=0, atol=1e-7)
    np.testing.assert_allclose(bp.nu, [p.nu for p in singles], rtol=0, atol=1e-8)
    with pytest.raises(ValueError, match="coefficients"):
        bp.set_disturbances(0, WindConfig(speed=3.0, coefficients="destroyer"))


@pytest.mark.parametrize("plant", ["default", "seed-linear"])
def test_blue_lady_reversals_at_speed_in_a_current_match_the_single_physics(plant: str) -> None:
    """Full reversals every 10 s from 1 m/s in a 0.3 m/s current: the advance-speed law (the
    speed through the water), the tunnel loss and the rate limits (default plant; the
    seed-linear plant: the bollard laws, no limit) as the single physics, to 1e-6."""
    current = CurrentConfig.from_std(0.3, 0.5, 0.05, 300.0)
    n = 2
    bp = BatchedPhysics("blue-lady", n, plant, current=current)
    nu0 = np.array([[1.0, 0.0, 0.0], [0.4, 0.05, 0.01]])
    act0 = np.array([[400.0, 0.5, -0.5], [-150.0, -1.0, 1.0]])
    bp.reset(nu=nu0, actuators=act0, rngs=[np.random.default_rng(3 + i) for i in range(n)])
    singles = []
    for i in range(n):
        p = VesselPhysics("blue-lady", plant, current=current)
        p.reset(nu=nu0[i], actuators=act0[i], rng=np.random.default_rng(3 + i))
        singles.append(p)
    err, ramp = 0.0, 0.0
    for k in range(12):
        s = 1.0 if k % 2 else -1.0
        cmd = np.array([[s * 480.0, -s, s], [-s * 200.0, s, -s]])
        bp.set_command(cmd)
        for i, p in enumerate(singles):
            p.set_command(cmd[i])
        before = bp.actuator_state
        bp.step(20)  # 1 s: a reversal's ramp
        ramp = max(ramp, float(np.abs(bp.actuator_state[:, 0] - before[:, 0]).max()))
        bp.step(180)
        for p in singles:
            p.step(200)
        err = max(err, _gap(bp, singles))
    assert err < 1e-6, err
    if plant == "default":  # 100 rpm/s: 1 s of a reversal moves the shaft by 100 rpm
        assert ramp == pytest.approx(100.0, rel=1e-9)
    else:  # the plain 2 s lag from nearly settled: up to 680 rpm (1 - e^-0.5) = 268 rpm
        assert 250.0 < ramp <= 680.0 * (1 - math.exp(-0.5)) + 1e-9


WAVES = WaveConfig(Hs=2.5, Tp=8.0, direction_from=math.radians(210.0))


def _commands(acts, n: int, k: int, seed: int) -> np.ndarray:
    """``k`` rounds of random, partly saturating commands for ``n`` hulls."""
    rng = np.random.default_rng(seed)
    a = np.clip(rng.normal(0.0, 0.7, (k, n, acts.n_channels)), -1.3, 1.3)
    return acts.action_to_command(np.clip(a, -1, 1)) * np.where(np.abs(a) > 1, 1.2, 1.0)


@pytest.mark.parametrize("name", vessel_names())
def test_hull_i_of_the_batch_is_the_single_leapfrog_physics_bit_for_bit(name: str) -> None:
    """Every vessel (3 and 4 DOF, every hull family and actuator kind), gusts, a Gauss-Markov
    current and the wave drift, 600 s: hull i of a batch of three and a single physics with the
    leapfrog integrator, seeded and commanded alike, run the same code: the same floats. The
    single physics with MuJoCo's integrator applies the same forces: within 1e-9 m and rad."""
    n = 3
    # a hull written per unit inertia (Van der Klugt's): its task applies the waves' roll and
    # yaw moments itself (a held external load), not the drift of a sea in newtons
    waves = None if load_vessel(name).hull.m == 1.0 else WAVES
    bp = BatchedPhysics(name, n, wind=GUSTY, current=GM_CURRENT, waves=waves)
    nu0, act0, n0 = _start(bp)
    nu0 = nu0 if bp.dofs == 3 else np.insert(nu0, 2, 0.0, axis=1)
    bp.reset(nu=nu0, actuators=act0, rngs=[np.random.default_rng(20 + i) for i in range(n)])
    i = 1
    single = {}
    for integ in ("leapfrog", "mujoco"):
        p = VesselPhysics(name, wind=GUSTY, current=GM_CURRENT, waves=waves, integrator=integ)
        p.reset(nu=nu0[i], actuators=act0[i], rng=np.random.default_rng(20 + i))
        single[integ] = p
    cmds = _commands(bp.actuators, n, 60, seed=3)  # 60 x 10 s
    if n0:
        cmds[..., 0] = n0 * (0.85 + 0.15 * np.clip(cmds[..., 0] / bp.actuators.upper[0], -1, 1))
    gap = 0.0
    for cmd in cmds:
        bp.set_command(cmd)
        bp.step(200)
        for p in single.values():
            p.set_command(cmd[i])
            p.step(200)
        lf, mj = single["leapfrog"], single["mujoco"]
        np.testing.assert_array_equal(lf.eta_full, bp.eta_full[i])
        np.testing.assert_array_equal(lf.nu_full, bp.nu_full[i])
        np.testing.assert_array_equal(lf.actuator_state, bp.actuator_state[i])
        gap = max(gap, float(np.abs(mj.eta_full - lf.eta_full).max()))
    assert np.abs(bp.eta[:, :2]).max() > 5.0  # the hulls moved
    assert not np.array_equal(bp.eta[0], bp.eta[1])  # each its own commands and weather
    assert gap < 1e-9, gap


@pytest.mark.parametrize("name", ["blue-lady", "naval-vessel"])
def test_hull_i_of_a_mujoco_batch_is_the_single_mujoco_physics_bit_for_bit(name: str) -> None:
    """The ``mujoco`` integrator per hull: hull i of a batch of three (each its own mjModel and
    mjData) and a single MuJoCo physics, seeded and commanded alike, give the same floats over
    300 s in gusts and a Gauss-Markov current (the same code: the loop calls ``mj_step`` on
    each hull's data)."""
    n = 3
    bp = BatchedPhysics(name, n, wind=GUSTY, current=GM_CURRENT, integrator="mujoco")
    bp.reset(rngs=[np.random.default_rng(20 + i) for i in range(n)])
    singles = []
    for i in range(n):
        p = VesselPhysics(name, wind=GUSTY, current=GM_CURRENT)
        p.reset(rng=np.random.default_rng(20 + i))
        singles.append(p)
    for cmd in _commands(bp.actuators, n, 30, seed=5):
        bp.set_command(cmd)
        assert bp.step(200).tolist() == [200] * n
        for i, p in enumerate(singles):
            p.set_command(cmd[i])
            p.step(200)
            np.testing.assert_array_equal(p.eta_full, bp.eta_full[i])
            np.testing.assert_array_equal(p.nu_full, bp.nu_full[i])
            np.testing.assert_array_equal(p.actuator_state, bp.actuator_state[i])
    assert not np.array_equal(bp.eta[0], bp.eta[1])  # each its own commands and weather


def test_a_mujoco_batch_in_the_harbour_stops_each_hull_at_its_own_quay_contact() -> None:
    """The Blue Lady in the harbour, three hulls pushed to starboard (towards the quay beside
    berth A) at different thrusts: each stops after the step in which it touches the quay, as
    the single physics with ``stop_on_contact`` does, the others go on."""
    n = 3
    bp = BatchedPhysics("blue-lady", n, integrator="mujoco", world="harbour")
    bp.reset()
    singles = [VesselPhysics("blue-lady", world="harbour") for _ in range(n)]
    for p in singles:
        p.reset()
    acts = bp.actuators
    cmd = acts.action_to_command(np.array([[0.0, s, s] for s in (1.0, 0.6, -0.3)]))
    bp.set_command(cmd)
    for i, p in enumerate(singles):
        p.set_command(cmd[i])
    taken_all = np.zeros(n, dtype=np.int64)
    for _ in range(100):  # 100 x 10 s
        taken = bp.step(200, stop_on_contact=True)
        taken_all += taken
        for i, p in enumerate(singles):
            k = p.step(200, stop_on_contact=True)
            assert k == taken[i]
            np.testing.assert_array_equal(p.eta_full, bp.eta_full[i])
        if (bp.contact_counts > 0).all() or (taken < 200).sum() >= 2:
            break
    counts = bp.contact_counts
    assert counts[0] > 0 and counts[2] == 0, counts  # pushed to starboard: the quay; to port: not
    assert (taken_all < taken_all.max()).any()  # the hulls stopped at different steps


@pytest.mark.parametrize("integrator", ["leapfrog", "mujoco"])
def test_a_batch_on_numbas_threads_gives_the_floats_of_the_serial_loop(integrator, monkeypatch):
    """A batch of at least ``PARALLEL_MIN`` hulls steps on Numba's threads
    (:func:`~shipgym.sim.step.run_threads`): the same per-hull law, so the same floats as the
    serial loop, across grid chunks that every hull needs at the same step (a 0.05 s gust grid:
    a chunk is 204.8 s) and with each hull's own commands and weather; hull 7 is also the
    single physics bit for bit (leapfrog)."""
    from shipgym.sim import step

    n = step.PARALLEL_MIN + 3
    wind = WindConfig(speed=8.0, direction_from=math.radians(300.0), sample_period=0.05)

    def trajectory(parallel: bool) -> list[np.ndarray]:
        monkeypatch.setattr(step, "PARALLEL_MIN", step.PARALLEL_MIN if parallel else 10**9)
        bp = BatchedPhysics("blue-lady", n, wind=wind, current=GM_CURRENT, integrator=integrator)
        bp.reset(rngs=[np.random.default_rng(40 + i) for i in range(n)])
        out = []
        for cmd in _commands(bp.actuators, n, 25, seed=9):  # 25 x 10 s, two chunk boundaries
            bp.set_command(cmd)
            bp.step(200)
            out.append(np.concatenate([bp.eta_full, bp.nu_full, bp.actuator_state], axis=1))
        return out

    par, ser = trajectory(True), trajectory(False)
    for a, b in zip(par, ser, strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.array_equal(par[-1][0], par[-1][1])
    if integrator == "leapfrog":
        p = VesselPhysics("blue-lady", wind=wind, current=GM_CURRENT, integrator="leapfrog")
        p.reset(rng=np.random.default_rng(47))
        for cmd in _commands(p.actuators, n, 25, seed=9):
            p.set_command(cmd[7])
            p.step(200)
        np.testing.assert_array_equal(p.eta_full, par[-1][7, : p.eta_full.size])


def _forked_child_trajectory(q) -> None:  # type: ignore[no-untyped-def]
    from shipgym.sim import step

    bp = BatchedPhysics("blue-lady", step.PARALLEL_MIN, wind=GUSTY)
    bp.reset(rngs=[np.random.default_rng(i) for i in range(bp.n)])
    bp.set_command(np.tile(bp.actuators.upper, (bp.n, 1)))
    bp.step(400)
    q.put((bp.eta_full.tolist(), _jit.THREADS["allowed"]))


@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="needs fork()")
def test_a_child_forked_after_threaded_steps_steps_serially_to_the_same_floats():
    """GNU OpenMP (Numba's usual threading layer) is not fork-safe: Numba ends a forked child
    that enters a parallel region its parent used. A child forked from a process that stepped
    a large batch on threads steps serially instead, to the same floats."""
    import multiprocessing as mp

    from shipgym.sim import step

    bp = BatchedPhysics("blue-lady", step.PARALLEL_MIN, wind=GUSTY)
    bp.reset(rngs=[np.random.default_rng(i) for i in range(bp.n)])
    bp.set_command(np.tile(bp.actuators.upper, (bp.n, 1)))
    bp.step(400)
    assert _jit.THREADS["used"]
    ctx = mp.get_context("fork")
    q = ctx.Queue()
    child = ctx.Process(target=_forked_child_trajectory, args=(q,))
    child.start()
    eta, allowed = q.get(timeout=120)
    child.join(30)
    assert child.exitcode == 0 and not allowed
    np.testing.assert_array_equal(np.array(eta), bp.eta_full)


def _physics_threads_allowed(_: int) -> bool:
    return bool(_jit.THREADS["allowed"])


def test_the_workers_of_a_pool_step_their_batches_serially():
    """A bench's or a seed sweep's worker processes already fill the cores: their batches
    step on their own thread (threads of their own would oversubscribe the machine)."""
    from shipgym.bench import run_jobs

    assert run_jobs(_physics_threads_allowed, [0, 1], workers=2, progress=False,
                    start_method="fork") == [False, False]  # fmt: skip


@pytest.mark.parametrize("integrator", ["leapfrog", "mujoco"])
@pytest.mark.parametrize("how", ["deepcopy", "pickle"])
def test_a_copied_physics_steps_its_own_state_as_the_original_would(integrator, how):
    """The compiled loop reads its arrays and MuJoCo's data through addresses: a copy (or an
    unpickled physics) binds its own, so stepping it moves the copy alone, to the floats the
    original reaches with the same steps (single physics and a batch of three)."""
    import copy
    import pickle

    def dup(x):
        return copy.deepcopy(x) if how == "deepcopy" else pickle.loads(pickle.dumps(x))

    single = VesselPhysics("star-hercules", integrator=integrator, wind="6@300")
    single.reset(rng=np.random.default_rng(3))
    batch = BatchedPhysics("star-hercules", 3, integrator=integrator, wind="6@300")
    batch.reset(rngs=[np.random.default_rng(i) for i in range(3)])
    for phys in (single, batch):
        phys.set_command(phys.actuators.action_to_command(np.full(phys.actuators.n_channels, 0.4)))
        phys.step(20)
        twin = dup(phys)
        before = np.array(phys.eta, copy=True)
        twin.step(200)
        assert np.array_equal(phys.eta, before)  # the original did not move
        phys.step(200)
        assert np.array_equal(twin.eta, phys.eta) and not np.array_equal(twin.eta, before)
        assert np.array_equal(twin.nu, phys.nu)


@pytest.mark.parametrize("env_id", ["shipgym/BlueLadyTracking-v0", "shipgym/BlueLadyHarbour-v0"])
def test_a_deep_copied_env_continues_its_episode_as_the_original(env_id):
    """A look-ahead copy of an env (model-predictive control does this): both run on, each
    its own physics, to the same observations."""
    import copy

    import gymnasium as gym

    env = gym.make(env_id)
    env.reset(seed=0)
    a = np.full(env.action_space.shape, 0.3, np.float32)
    for _ in range(3):
        env.step(a)
    twin = copy.deepcopy(env)
    ours = [twin.step(a)[0] for _ in range(5)]
    theirs = [env.step(a)[0] for _ in range(5)]
    assert all(np.array_equal(x, y) for x, y in zip(ours, theirs, strict=True))
    assert not np.array_equal(ours[0], ours[-1])


def test_pieces_of_a_long_run_are_the_whole_chunks_floats() -> None:
    """A spectral gust wind, a Gauss-Markov current and a sea with drift and Fossen's WF
    filter on fine grids (0.02 s: a chunk is 82 s, a piece 10 s), 200 s: every hull's physics
    window, read as it crosses pieces and two chunk boundaries, holds the samples of the whole
    chunk of a fresh process of the same seed (``chunk(j)``, computed in one go); the wave
    motion, the wind and the drift queried on the batch's processes are those of the fresh
    ones; hull 1 is the single physics bit for bit."""
    from dataclasses import replace

    from shipgym.disturbances import Waves
    from shipgym.disturbances._grid import PIECE
    from shipgym.sim.step import CURRENT, DRIFT, WIND

    name, n, dt = "blue-lady", 3, 0.02
    wind = WindConfig(
        speed=6.0, direction_from=math.radians(300.0), gust_spectrum="npd", sample_period=dt
    )
    current = replace(GM_CURRENT, sample_period=dt)
    waves = WaveConfig(Hs=0.08, Tp=1.8, direction_from=math.radians(210.0), first_order=True,
                       wf_model="fossen", sample_period=dt)  # fmt: skip
    bp = BatchedPhysics(name, n, wind=wind, current=current, waves=waves)
    nu0, act0, _ = _start(bp)
    bp.reset(nu=nu0, actuators=act0, rngs=[np.random.default_rng(40 + i) for i in range(n)])
    single = VesselPhysics(name, wind=wind, current=current, waves=waves, integrator="leapfrog")
    single.reset(nu=nu0[1], actuators=act0[1], rng=np.random.default_rng(41))
    fresh = []
    v = load_vessel(name)
    for i in range(n):
        g = np.random.default_rng(40 + i)
        procs = (Wind(wind, v.windage), Current(current), Waves(waves, v.hull))
        for p in procs:
            p.reset(g)
        fresh.append(procs)
    hb = bp._hulls
    cmds = _commands(bp.actuators, n, 20, seed=5)  # 20 x 10 s
    seen = set()
    for cmd in cmds:
        bp.set_command(cmd)
        bp.step(200)
        single.set_command(cmd[1])
        single.step(200)
        np.testing.assert_array_equal(single.eta_full, bp.eta_full[1])
        np.testing.assert_array_equal(single.nu_full, bp.nu_full[1])
        motion = bp.wave_motion()
        for i in range(n):
            for slot, proc in ((WIND, fresh[i][0]), (CURRENT, fresh[i][1]), (DRIFT, fresh[i][2])):
                k0 = int(hb.k0[i, slot])
                j, p = divmod(k0, CHUNK)
                assert p % PIECE == 0 and hb.windows[slot].shape[2] == PIECE + 1
                whole = proc.chunk(j)[:2, p : p + PIECE + 1]
                np.testing.assert_array_equal(hb.windows[slot][i], whole)
                seen.add((slot, j))
            t = float(bp.t[i])
            w_batch, w_fresh = bp.winds[i], fresh[i][0]
            assert w_batch.at(t) == w_fresh.at(t) and w_batch.at(0.5 * t) == w_fresh.at(0.5 * t)
            assert bp.currents[i].at(t) == fresh[i][1].at(t)
            assert bp.waves[i].drift_load(t, 0.3) == fresh[i][2].drift_load(t, 0.3)
            np.testing.assert_array_equal(motion[i], np.ravel(fresh[i][2].wf_series(t)))
    assert {j for _, j in seen} == {0, 1, 2}  # two chunk boundaries crossed
    for i in range(n):  # the batch's grids, completed piece by piece, are the whole chunks
        for b, f in zip((bp.winds[i], bp.currents[i]), fresh[i][:2], strict=True):
            for j in range(3):
                np.testing.assert_array_equal(b.chunk(j), f.chunk(j))
        for j in range(3):
            np.testing.assert_array_equal(bp.waves[i].chunk(j), fresh[i][2].chunk(j))


@pytest.mark.parametrize("name", vessel_names())
def test_the_one_call_readouts_are_the_properties_floats(name: str) -> None:
    """What an env reads of one state in one compiled call (``readouts``) is the thrust, the
    bollard-model load and the load at the held commands of the properties, bit for bit, on
    every vessel (own laws or a separate bollard model; lagged, servo and integrator channels)
    in a current, after commands the lags have not reached."""
    n = 3
    bp = BatchedPhysics(name, n, current=GM_CURRENT)
    nu0, act0, _ = _start(bp)
    nu0 = nu0 if bp.dofs == 3 else np.insert(nu0, 2, 0.0, axis=1)
    bp.reset(nu=nu0, actuators=act0, rngs=[np.random.default_rng(i) for i in range(n)])
    for cmd in _commands(bp.actuators, n, 3, seed=5):
        bp.set_command(cmd)
        bp.step(7)
        thrust, tau_model, tau_command = bp.readouts(True)
        np.testing.assert_array_equal(thrust, bp.thrust)
        np.testing.assert_array_equal(tau_model, bp.tau_model)
        np.testing.assert_array_equal(tau_command, bp.tau_command)
        assert bp.readouts()[2] is None
        np.testing.assert_array_equal(bp.readouts()[1], tau_model)
    assert np.abs(thrust).max() > 0.0
