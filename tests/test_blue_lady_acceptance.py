"""Issue 31's Blue Lady acceptance: seeds 0-9, 3 m/s from 300 deg (the harbour default) and
the ``tomera2014-lake`` preset; every observer meant for the Blue Lady completes with ``pid``
(``shipgym run``'s default controller) except ``tomera-ekf``, which cannot on this plant (the
evidence below); with ``kbf`` + ``pid`` no thruster at a limit more than 10 % of the time in
the harbour, main-propeller reversals and starts at most one a minute, no stop/start cycling.

On the lake preset the tunnels' time at a limit is not within 10 % (the bow tunnel's worst
seed 25 %, the stern tunnel's 22 %; 37 % and 26 % before issue 31): docs/papers/tomera-2014.md
says why; the slow test pins what is reached so that it does not get worse unnoticed.

The Blue Lady's observers are those of ``shipgym list`` that run at its 1 s sensor period
(``notch`` and the ``alt-*`` filters of Al-Takie 1982 refuse it with an error)."""

from __future__ import annotations

import numpy as np
import pytest

from shipgym.bench import bench_scenario_kwargs
from shipgym.runner import run_episode

OBSERVERS = ("truth", "dkf", "kbf", "ekf", "tomera-dkf", "tomera-kbf")
SEEDS = range(10)


def _run(observer: str, seed: int, scenario: str | None = None, **kw) -> dict:
    env_kwargs = dict(bench_scenario_kwargs(scenario)) if scenario else {}
    wind = env_kwargs.pop("wind", None) if scenario else "3@300"
    env_kwargs.update(kw)
    return run_episode("harbour", controller="pid", observer=None if observer == "truth"
                       else observer, seed=seed, wind=wind, env_kwargs=env_kwargs)  # fmt: skip


def _chatter(rows: list[dict]) -> dict[str, np.ndarray]:
    keys = ("limit_fraction", "reversals_per_min", "starts_per_min", "zero_fraction")
    return {k: np.array([r[k] for r in rows]) for k in keys}


def test_harbour_kbf_pid_meets_the_chatter_and_limit_bounds():
    rows = [_run("kbf", s) for s in SEEDS]
    assert all(r["completed"] and not r["quay_contact"] for r in rows)
    c = _chatter(rows)
    assert c["limit_fraction"].max() <= 0.10  # every thruster, every seed (13.2 % before)
    main_rev, main_starts = c["reversals_per_min"][:, 0], c["starts_per_min"][:, 0]
    assert main_rev.max() <= 1.0 and main_rev.mean() <= 0.85  # 1.06 mean before
    assert main_starts.max() <= 1.0 and main_starts.mean() <= 0.9  # 3.04 mean before
    assert c["zero_fraction"][:, 0].max() == 0.0  # 31 % mean before: it never stops
    assert np.mean([r["J_c"] for r in rows]) <= 0.188  # no worse than before (0.188)


@pytest.mark.slow
@pytest.mark.parametrize("scenario", [None, "tomera2014-lake"], ids=["harbour", "lake"])
@pytest.mark.parametrize("observer", OBSERVERS)
def test_every_blue_lady_observer_completes_with_pid(observer, scenario):
    rows = [_run(observer, s, scenario) for s in SEEDS]
    assert all(r["completed"] and not r["quay_contact"] for r in rows), observer


@pytest.mark.slow
def test_lake_kbf_pid_reversals_starts_and_the_limits_reached():
    rows = [_run("kbf", s, "tomera2014-lake") for s in SEEDS]
    assert all(r["completed"] and not r["quay_contact"] for r in rows)
    c = _chatter(rows)
    assert c["reversals_per_min"][:, 0].mean() <= 1.0  # 0.92 (worst seed 1.19)
    assert c["starts_per_min"][:, 0].mean() <= 1.0  # 0.96 (worst seed 1.23)
    assert c["zero_fraction"][:, 0].max() == 0.0
    assert c["limit_fraction"][:, 0].max() <= 0.10  # the main propeller: 4 % at most
    # the tunnels: not the 10 % of the acceptance (25 % and 22 % on the worst seeds; 37 % and
    # 26 % before issue 31), in the lake's cross-current (see the module docstring)
    assert c["limit_fraction"].max() <= 0.26


# ---- tomera-ekf: why the paper's EKF cannot complete the manoeuvre on this plant ------------
# The paper's matrices (Tomera 2014 eqs. 49-53): its design model repeats Table 2's printed
# sway added mass (M22 = 24 831 kg) and its R = 0.1 reads as 0.1 rad^2 (18 deg std) on the
# gyrocompass, so its heading and yaw-rate estimates follow the model driven by the commanded
# thrust. The plant has the corrected sway added mass (M22 = 41 896 kg, the hull evidence of
# the Blue Lady's README): the model's sway-yaw response is wrong, and the ship is steered
# into the quay (seeds 0-9 with pid: 2/10 harbour, 0/10 lake).
def test_tomera_ekf_fails_on_the_corrected_plant_and_completes_on_the_printed_one():
    for seed in (0, 1):
        r = _run("tomera-ekf", seed)
        assert r["quay_contact"] and not r["completed"]  # the default plant
        r = _run("tomera-ekf", seed, plant="table2-literal")  # Tomera's printed Y_vdot
        assert r["completed"] and not r["quay_contact"]


def test_tomera_ekf_completes_with_the_sensors_variance_not_with_the_plants_mass():
    from shipgym.observers.ekf import EKF_PRESETS

    M = np.array(EKF_PRESETS["tomera-ekf"]["M"])
    M[1, 1] = 22934.4 + 18962.0  # the plant's sway inertia in the filter's model
    for seed in (0, 1):
        r = _run("tomera-ekf", seed, observer_options={"R": EKF_PRESETS["ekf"]["R"]})
        assert r["completed"] and not r["quay_contact"]  # trusting the gyrocompass: it does
        r = _run("tomera-ekf", seed, observer_options={"M": M.tolist()})
        assert not r["completed"]  # the model's mass alone does not repair it


# ---- the lake's forward leg: a steady load the bow tunnel cannot carry ---------------------
# Why the 10 % bound on the tunnels' time at a limit is not reached on the lake preset's worst
# seeds (6-9), on the true state as with the KBF: in the forward leg (38 m ahead at the plan's
# 0.2 m/s, heading held north) the lake's Gauss-Markov current reaches 0.03 m/s across the hull
# (its mean 0.01 m/s plus two standard deviations). The hull in that cross-flow carries the
# Munk moment of the corrected sway added mass, and with the 3 m/s wind from 300 deg the
# steady allocation T^-1 tau (Tomera 2014 eq. 25) asks the bow tunnel for more than it gives
# at that speed (its thrust falls to 75 % at 0.2 m/s with the tunnel loss). The check is the
# plant's own steady equation of motion (Fossen 2011 eq. 6.1 with nu_dot = 0: C_RB(nu) nu +
# C_A(nu_r) nu_r + D(nu_r) nu_r = tau + tau_wind), independent of the simulation loop; it
# leaves the lake's wave drift out (13 N more across), so it is a lower bound.
def _bow_tunnel_share_in_the_forward_leg(u: float, v_c: float) -> float:
    import math

    from shipgym.controllers.actuation import fixed3_parameters
    from shipgym.disturbances import wind_load
    from shipgym.dynamics.vessel import load_vessel

    vessel = load_vessel("blue-lady")
    plant = vessel.plant("default")
    th = fixed3_parameters(vessel.actuators)
    nu = np.array([u, 0.0, 0.0])  # on the track, heading held (m/s, m/s, rad/s)
    nu_r = nu - np.array([0.0, v_c, 0.0])  # the current pushes to starboard
    hull = plant.coriolis_rb(nu) @ nu + plant.coriolis_a(nu_r) @ nu_r + plant.damping(nu_r) @ nu_r
    wind = wind_load(0.0, u, 0.0, 3.0, math.radians(300.0), windage=vessel.windage)
    tau = hull - wind  # what the thrusters must give (N, N, N m)
    f_bow = (th.L3 * tau[1] + tau[2]) / (th.L2 + th.L3)  # eq. 25
    bow = next(a for a in vessel.actuators if a.name == "bow_tunnel")
    return float(abs(f_bow) / (bow.max_thrust * float(bow.efficiency(u))))


def test_lake_forward_leg_needs_more_bow_thrust_than_the_tunnel_has_in_a_cross_current():
    # at the plan's speed in the worst seeds' current: over the tunnel's thrust at that speed
    assert _bow_tunnel_share_in_the_forward_leg(0.2, 0.03) > 1.15  # 1.23 (1.41 with the drift)
    # in the mean current, or at a third of the speed, the same leg is carried with a margin
    assert _bow_tunnel_share_in_the_forward_leg(0.2, 0.01) < 0.7  # 0.64
    assert _bow_tunnel_share_in_the_forward_leg(0.07, 0.03) < 0.7  # 0.65
