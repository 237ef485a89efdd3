"""The compiled physics step (shipgym.envs._native) against the Python step it replaces.

Each compiled kernel is checked bit for bit against its Python form on random inputs, and
whole runs (random commands, gusts, current, contacts, divergence) against the Python loop of
``VesselPhysics.step`` and the NumPy form of ``BatchedPhysics.step``, for every vessel the
compiled step covers; the Python step itself is checked against SciPy and the paper
elsewhere (test_physics.py, test_batchphysics.py).
"""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest

from shipgym.disturbances import CurrentConfig, WindConfig, WindLoad, blendermann
from shipgym.dynamics import PlantModel, load_vessel, vessel_names
from shipgym.dynamics.model import kernel_constants
from shipgym.envs import _native as nat
from shipgym.envs.batchphysics import BatchedPhysics
from shipgym.envs.physics import SimulationDiverged, VesselPhysics

pytestmark = pytest.mark.skipif(not nat.available(), reason=nat.status())

PLANAR = [n for n in vessel_names() if load_vessel(n).dofs == 3]
WIND = WindConfig(speed=6.0, direction_from=math.radians(300.0))
CURRENT = CurrentConfig.from_std(0.1, 0.5, 0.02, 300.0)


def _variants(name: str) -> list[str]:
    v = load_vessel(name)
    return [p for p in v.plants if isinstance(v.plant(p), PlantModel)]


COVERED = [(n, p) for n in PLANAR for p in _variants(n)]


def test_the_plant_kernel_is_the_python_kernel_bit_for_bit() -> None:
    rng = np.random.default_rng(0)
    for name, plant in COVERED:
        p = load_vessel(name).plant(plant)
        k = np.array(kernel_constants(p))
        for x in rng.normal(size=(200, 8)) * [1.0, 0.5, 0.05, 1e3, 1e3, 1e4, 0.2, 0.2]:
            assert nat.accel3(k, *x) == p.accel(*x), (name, plant)


def test_the_wind_load_is_the_python_kernel_bit_for_bit() -> None:
    rng = np.random.default_rng(1)
    for name in PLANAR:
        v = load_vessel(name)
        wl = WindLoad(blendermann(v.windage.coefficients), v.windage)
        f, k = wl.kernel(), np.array(wl.kernel_constants())
        for x in rng.normal(size=(300, 5)) * [3.0, 1.0, 0.5, 8.0, 3.0]:
            assert nat.wind_load(k, *x) == f(*x), name
        assert nat.wind_load(k, 0.0, 0.0, 0.0, 0.0, 0.0) == f(0.0, 0.0, 0.0, 0.0, 0.0)


@pytest.mark.parametrize("name", PLANAR)
def test_the_thrust_laws_are_the_python_kernels_bit_for_bit(name: str) -> None:
    for plant in _variants(name) or ["default"]:
        acts = load_vessel(name).actuators_for(load_vessel(name).plant(plant))
        try:
            rows = acts.thrust_tables3()
            tables = [np.array(t, float).reshape(len(t), w)
                      for t, w in zip(rows, (7, 4, 5, 4), strict=True)]  # fmt: skip
        except AssertionError:  # rudders, MMG units: not covered
            continue
        n = acts.n_channels
        gain, gear = np.zeros((n, 10)), np.zeros((n, 6))
        gain2, gear2 = np.zeros((n, 10)), np.zeros((n, 6))
        py = acts.kernel(gain2, gear2)
        props = acts.propeller_flow_table()
        flow = acts.flow_kernel()
        rng = np.random.default_rng(2)
        for _ in range(100):
            st = rng.uniform(acts.lower, acts.upper)
            X, Y, N = nat.thrust3(st, *tables, gain, gear, True)
            Xp, Yp, _K, Np, _M = py(st.tolist())
            assert (X, Y, N) == (Xp, Yp, Np)
            np.testing.assert_array_equal(gain, gain2)
            np.testing.assert_array_equal(gear, gear2)
            if props is not None:
                u = float(rng.normal())
                lifts = np.zeros(len(props))
                got = nat.propeller_flow(st, np.array(props, float), u, lifts)
                want = flow(st.tolist(), u, 0.1, 0.0, 0.01)
                assert got == want[:4]
                assert tuple(lifts) == want[4]


def _run(name: str, plant: str, native: bool, steps: int, **kw: object) -> np.ndarray:
    if native:
        p = VesselPhysics(name, plant, **kw)  # type: ignore[arg-type]
        assert p._native is not None, "the compiled step should cover this physics"
    else:
        with nat.disabled():
            p = VesselPhysics(name, plant, **kw)  # type: ignore[arg-type]
        assert p._native is None
    p.reset(rng=np.random.default_rng(3))
    rng = np.random.default_rng(4)
    rows = []
    for _ in range(steps // 20):
        p.set_command(rng.uniform(p.actuators.lower, p.actuators.upper))
        p.step(20)
        rows.append([*p.data.qpos, *p.data.qvel, *p.data.act, *p.data.ctrl, p.data.time,
                     *p._loads, *p.data.qfrc_applied, *p.thrust, *p.rate_limited])  # fmt: skip
    return np.array(rows, dtype=float)


@pytest.mark.parametrize(("name", "plant"), COVERED)
def test_whole_runs_are_the_python_step_bit_for_bit(name: str, plant: str) -> None:
    """Random commands every second for 500 s (past a chunk of the gust grid) in gusty wind
    and a Gauss-Markov current: every state, load and thrust equal."""
    kw = {"wind": WIND, "current": CURRENT}
    a = _run(name, plant, True, 10_000, **kw)
    b = _run(name, plant, False, 10_000, **kw)
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("sea", ["calm", "constant"])
def test_calm_and_constant_disturbances_are_the_python_step(sea: str) -> None:
    kw = {} if sea == "calm" else {"wind": "5@40", "current": (0.2, 30.0)}
    np.testing.assert_array_equal(_run("blue-lady", "default", True, 2000, **kw),
                                  _run("blue-lady", "default", False, 2000, **kw))  # fmt: skip


def test_the_clock_is_mujocos() -> None:
    """The loop keeps its own time (t += h, as mj_step does); MuJoCo's must agree."""
    p = VesselPhysics("blue-lady", wind=WIND)
    p.reset(rng=np.random.default_rng(0))
    t = 0.0
    for _ in range(100):
        p.step(37)
        for _ in range(37):
            t += p.timestep
        assert p.data.time == t


def test_a_quay_contact_stops_at_the_same_step() -> None:
    def first_contact(native: bool) -> tuple[int, list[tuple[str, str]]]:
        if native:
            p = VesselPhysics("blue-lady", world="harbour")
        else:
            with nat.disabled():
                p = VesselPhysics("blue-lady", world="harbour")
        assert (p._native is not None) is native
        # full ahead from the harbour entrance towards the quay (north)
        p.reset(eta=(0.0, 0.0, 0.0), nu=(1.0, 0.0, 0.0))
        p.set_command(p.actuators.upper)
        total = 0
        while total < 40_000:
            k = p.step(50, stop_on_contact=True)
            total += k
            if k < 50:
                return total, p.contacts()
        raise AssertionError("no contact in 2000 s")

    assert first_contact(True) == first_contact(False)
    assert first_contact(True)[1]


def test_ncon_view_reads_mujocos_contact_count() -> None:
    p = VesselPhysics("blue-lady", world="harbour")
    view = nat.ncon_view(p.model, p.data)
    p.data.ncon = 3
    assert view[0] == 3
    p.data.ncon = 0
    assert view[0] == 0


def test_divergence_is_reported_as_by_the_python_step() -> None:
    def blow_up(native: bool) -> str:
        if native:
            p = VesselPhysics("blue-lady")
        else:
            with nat.disabled():
                p = VesselPhysics("blue-lady")
        p.reset()
        p.set_external_force([1e12, 0.0, 0.0])
        with pytest.raises(SimulationDiverged) as err:
            p.step(100)
        return str(err.value)

    msg = blow_up(True)
    assert msg == blow_up(False)
    assert "diverged" in msg


def test_changing_the_timestep_rebuilds_the_compiled_step() -> None:
    a = VesselPhysics("blue-lady", wind=WIND)
    with nat.disabled():
        b = VesselPhysics("blue-lady", wind=WIND)
    for p in (a, b):
        p.model.opt.timestep = 0.02
        p.reset(rng=np.random.default_rng(0))
        p.set_command([200.0, 0.3, -0.3])
        p.step(500)
    assert a._native is not None
    np.testing.assert_array_equal(a.data.qpos, b.data.qpos)


@pytest.mark.parametrize("name", PLANAR)
def test_the_compiled_batch_is_the_numpy_batch(name: str) -> None:
    """Within round-off (the NumPy form sums the thrust through B @ F, the compiled form as
    the single physics does)."""
    try:
        a = BatchedPhysics(name, 6, wind=WIND, current=CURRENT)
    except ValueError:
        pytest.skip(f"{name}: not batched")
    with nat.disabled():
        b = BatchedPhysics(name, 6, wind=WIND, current=CURRENT)
    if a._native is None:
        pytest.skip(f"{name}: the compiled batch does not cover its plant or actuators")
    assert b._native is None
    eta0 = np.random.default_rng(9).normal(size=(6, 3))
    for bp in (a, b):
        bp.reset(eta=eta0, rngs=[np.random.default_rng(i) for i in range(6)])
    rng = np.random.default_rng(5)
    for _ in range(100):
        c = rng.uniform(a.lower, a.upper, (6, a.lower.size))
        a.set_command(c)
        b.set_command(c)
        a.step(20)
        b.step(20)
    scale = np.maximum(1.0, np.abs(b.eta))
    assert np.max(np.abs(a.eta - b.eta) / scale) < 1e-12
    np.testing.assert_allclose(a.nu, b.nu, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.actuator_state, b.actuator_state, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(a.t, b.t)


def test_shipgym_native_0_turns_it_off() -> None:
    code = "from shipgym.envs import _native as n; print(n.available()); print(n.status())"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env={**os.environ, "SHIPGYM_NATIVE": "0"}, check=True)  # fmt: skip
    lines = out.stdout.splitlines()
    assert lines[0] == "False"
    assert "SHIPGYM_NATIVE=0" in lines[1]


@pytest.mark.parametrize("name", ["blue-lady", "star-hercules"])
def test_wave_drift_is_the_python_step_bit_for_bit(name: str) -> None:
    """100 wave components with drift and first-order motion, 500 s (past a chunk)."""
    from shipgym.disturbances import WaveConfig

    Hs = 0.083 if name == "blue-lady" else 2.5
    Tp = 1.79 if name == "blue-lady" else 9.0
    waves = WaveConfig(Hs=Hs, Tp=Tp, n_components=100, drift=True, first_order=True)
    p = VesselPhysics(name, waves=waves)
    p.reset(rng=np.random.default_rng(0))
    p.step(100)
    assert p._native is not None
    assert min(abs(x) for x in p.tau_waves) > 0.0  # the drift acts
    kw = {"wind": WIND, "current": CURRENT, "waves": waves}
    np.testing.assert_array_equal(_run(name, "default", True, 10_000, **kw),
                                  _run(name, "default", False, 10_000, **kw))  # fmt: skip
