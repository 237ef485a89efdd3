"""Waves, current and scenarios inside the physics and the environments (issue: sea and weather)."""

import math

import numpy as np
import pytest

import shipgym
from shipgym.cli import run_episode
from shipgym.disturbances import CurrentConfig, WaveConfig
from shipgym.envs.physics import VesselPhysics
from shipgym.scenarios import load_scenario


def test_hull_drifts_with_the_current_and_feels_no_force_moving_with_the_water():
    """No thrust: the ground velocity goes to the current velocity, nu_r -> 0."""
    cur = CurrentConfig(speed=0.1, direction_to=math.radians(60.0))
    phys = VesselPhysics("blue-lady", "default", wind=None, current=cur)
    phys.reset()
    phys.step(round(8000 / phys.timestep))
    v_ned = phys.data.qvel[:2] + 0.5 * phys.timestep * phys.data.qacc[:2]
    expect = 0.1 * np.array([math.cos(math.radians(60.0)), math.sin(math.radians(60.0))])
    np.testing.assert_allclose(v_ned, expect, atol=2e-3)
    assert abs(phys.nu[2]) < 1e-4
    # a hull already moving with the water: no hydrodynamic force at all
    phys2 = VesselPhysics("blue-lady", "default", wind=None, current=cur)
    psi = 0.3
    u_c, v_c = 0.1 * math.cos(math.radians(60.0) - psi), 0.1 * math.sin(math.radians(60.0) - psi)
    phys2.reset(eta=[0, 0, psi], nu=[u_c, v_c, 0.0])
    phys2.step(200)
    np.testing.assert_allclose(phys2.nu, [u_c, v_c, 0.0], atol=1e-12)
    np.testing.assert_allclose(phys2.data.qacc, 0.0, atol=1e-12)


def test_first_order_wave_motion_is_seen_by_the_sensors_not_lived_by_the_hull():
    waves_on = WaveConfig(Hs=0.083, Tp=1.79, first_order=True, wf_position_std=0.05,
                          wf_heading_std=math.radians(0.3))  # fmt: skip
    waves_off = WaveConfig(Hs=0.083, Tp=1.79, first_order=False)
    runs = {}
    for name, w in (("on", waves_on), ("off", waves_off)):
        env = shipgym.make("station-keeping", controller="pid", waves=w, sensors="rtk",
                           start_noise=(0, 0, 0))  # fmt: skip
        env.reset(seed=1)
        eta, z = [], []
        for _ in range(400):
            _, _, _, _, info = env.step(np.zeros(3, np.float32))
            eta.append(info["eta"])
            z.append(info["measurements"][-1]["z"])
        runs[name] = (np.array(eta), np.array(z))
    # the hull (and, with truth feedback, the whole loop) is the same with and without WF motion
    np.testing.assert_array_equal(runs["on"][0], runs["off"][0])
    err = runs["on"][1] - runs["on"][0]
    hf_std = np.std(err[:, 0] - np.mean(err[:, 0]))
    noise = 0.02  # rtk position sigma (m)
    assert hf_std == pytest.approx(math.hypot(0.05, noise), rel=0.10)


def test_wave_drift_load_is_in_info_and_zero_in_calm_water():
    env = shipgym.make("station-keeping", controller="pid", waves=WaveConfig(Hs=0.083, Tp=1.79))
    env.reset(seed=0)
    loads = [env.step(np.zeros(3, np.float32))[4]["tau_waves"] for _ in range(200)]
    assert np.max(np.abs(loads)) > 0.1
    env0 = shipgym.make("station-keeping", controller="pid", waves=WaveConfig(Hs=0.0, Tp=1.79))
    env0.reset(seed=0)
    assert not np.any(env0.step(np.zeros(3, np.float32))[4]["tau_waves"])


@pytest.mark.parametrize("seed", range(10))
def test_harbour_with_kbf_under_the_lake_scenario(seed):
    kw = load_scenario("tomera2014-lake").env_kwargs()
    res = run_episode("harbour", controller="pid", observer="kbf", seed=seed, env_kwargs=kw)
    assert res["completed"] and not res["quay_contact"]


#: documented station-keeping radius in Beaufort 5 (Froude-scaled), PID + KBF (README)
BF5_RADIUS_M = 1.0


@pytest.mark.parametrize("seed", range(3))
def test_station_keeping_in_beaufort_5(seed):
    sc = load_scenario("beaufort5")
    env = shipgym.make(sc.env, observer="kbf", controller="pid", **sc.env_kwargs())
    env.reset(seed=seed)
    dist = []
    for _ in range(600):
        _, _, term, _, info = env.step(np.zeros(3, np.float32))
        assert not term
        dist.append(np.hypot(*(info["eta"][:2] - info["eta_d"][:2])))
    assert max(dist[200:]) < BF5_RADIUS_M
