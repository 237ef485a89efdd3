"""Typed records of a step (``info["record"]``, :mod:`shipgym.records`).

Every part of the env (physics, observer, DP controller) puts into the :class:`StepRecord`
the same values as its ``info`` keys.
"""

from __future__ import annotations

import copy
import pickle

import gymnasium as gym
import numpy as np
import pytest

import shipgym
from shipgym.records import (
    ActuatorData,
    ControlData,
    Measurement,
    NavigationData,
    StepRecord,
    step_record,
)

ZERO = np.zeros(3, np.float32)


def _check_env_part(info):
    """The record holds what the env's own info keys say."""
    rec = info["record"]
    assert isinstance(rec, StepRecord)
    eq = np.testing.assert_array_equal
    assert rec.t == info["t"]
    eq(rec.truth.eta, info["eta"])
    eq(rec.truth.nu, info["nu"])
    eq(rec.nav.eta, info["nav_eta"])
    eq(rec.nav.nu, info["nav_nu"])
    eq(rec.eta_r, info["eta_r"])
    ref = rec.reference
    eq(ref.eta_d_n, info["eta_d"])
    for k in ("eta_d_r", "eta_dot_d_r", "eta_ddot_d_r", "eta_P"):
        eq(getattr(ref, k), info[k])
    assert (ref.leg, rec.legs_completed, ref.finished) == (
        info["leg"],
        info["legs_completed"],
        info["finished"],
    )
    act = rec.actuators
    for k in ("command", "thrust", "saturated", "action_clipped"):
        eq(getattr(act, k), info[k])
    for v in (act.action, act.command, act.thrust, act.saturated, act.action_clipped):
        assert len(v) == len(act.names)
    assert np.all(np.abs(act.action) <= 1.0)
    for k in ("tau_wind", "tau_waves", "current_body"):
        eq(getattr(rec, k), info[k])
    assert rec.quay_contact == info["quay_contact"]
    assert len(rec.measurements) == len(info["measurements"])
    for m, d in zip(rec.measurements, info["measurements"], strict=True):
        assert (m.t, m.valid, m.outlier) == (d["t"], d["valid"], d["outlier"])
        eq(m.tau, d["tau"])
        assert (m.z is None) == (d["z"] is None)
        if m.z is not None:
            eq(m.z, d["z"])


@pytest.mark.parametrize(
    ("observer", "controller"), [(None, None), ("kbf", None), (None, "pid"), ("ekf", "lq")]
)
def test_every_layer_hands_on_a_record_with_its_info_values(observer, controller):
    env = shipgym.make("harbour", observer=observer, controller=controller, max_episode_steps=40)
    _, info = env.reset(seed=3)
    _check_env_part(info)
    assert info["record"].control is None
    done = False
    while not done:
        _, _, term, trunc, info = env.step(ZERO)
        done = term or trunc
        _check_env_part(info)
        rec = info["record"]
        if controller is None:
            assert rec.control is None
        else:
            c = rec.control
            assert isinstance(c, ControlData) and c.controller == controller
            for attr, key in (
                ("tau_c", "tau_c"),
                ("tau_delivered", "tau_delivered"),
                ("tau_error", "tau_error"),
                ("action", "controller_action"),
                ("allocation_saturated", "allocation_saturated"),
                ("residual_clipped", "residual_clipped"),
            ):
                np.testing.assert_array_equal(getattr(c, attr), info[key])
        if observer is None:
            assert rec.nav == rec.truth and rec.nav.is_truth
        else:
            assert rec.nav.source == observer and not rec.nav.is_truth
        if not done:
            assert rec.estimation_rmse is None
    assert trunc  # 40 steps: the observer's RMSE comes with the truncated last step
    if observer is None:
        assert info["record"].estimation_rmse is None and "estimation_rmse" not in info
    else:
        assert dict(info["record"].estimation_rmse) == info["estimation_rmse"]
    env.close()


def test_the_records_navigation_data_is_the_observers_estimate():
    env = shipgym.make("harbour", observer="ekf", controller="pid")
    _, info = env.reset(seed=0)
    for _ in range(20):
        _, _, _, _, info = env.step(ZERO)
    est = env.unwrapped.observer.estimate(0)  # asked of the observer itself
    nav = info["record"].nav
    np.testing.assert_array_equal(nav.eta, est.eta)
    np.testing.assert_array_equal(nav.nu, est.nu)
    np.testing.assert_array_equal(nav.P_eta, est.P_eta)
    assert not np.allclose(nav.eta, info["record"].truth.eta)  # an estimate, not the truth
    assert nav.t == info["t"]
    env.close()


def test_runner_summary_takes_the_rmse_from_the_record():
    from shipgym.runner import episode_summary, step_episode

    env = shipgym.make("harbour", observer="kbf", controller="pid", max_episode_steps=30)
    end = step_episode(env, 0)
    res = episode_summary(env, end)
    assert res["rmse"] == end.info["estimation_rmse"]
    assert set(res["rmse"]) == {"x", "y", "psi", "u", "v", "r"}
    env.close()


def test_actuator_data_has_any_number_of_actuators():
    names = tuple(f"tunnel_{k}" for k in range(6))
    z = np.zeros(6)
    a = ActuatorData(names, z, z, z + 1.0, np.zeros(6, bool), np.zeros(6, bool))
    assert len(a.thrust) == 6
    with pytest.raises(ValueError, match=r"one per actuator \(6: tunnel_0"):
        ActuatorData(names, z, z, np.zeros(5), np.zeros(6, bool), np.zeros(6, bool))
    with pytest.raises(ValueError, match="got lengths 6, 6, 6, 3 and 6"):
        ActuatorData(names, z, z, z, np.zeros(6, bool), np.zeros(3, bool))


def test_actuator_data_of_azimuths_has_two_channels_per_actuator():
    names = ("a1", "a2")
    channels = ("a1", "a1_angle", "a2", "a2_angle")
    c = np.zeros(4)
    a = ActuatorData(names, c, c, np.ones(2), np.zeros(4, bool), np.zeros(4, bool), channels)
    assert len(a.thrust) == 2 and len(a.command) == 4
    with pytest.raises(ValueError, match=r"one entry per channel \(1: a1\)"):
        ActuatorData(names, c, c, np.ones(4), np.zeros(4, bool), np.zeros(4, bool), ("a1",))


def test_navigation_data_with_a_roll_component():
    nav = NavigationData(
        1.0,
        np.array([1.0, 2.0, 0.05, 0.3]),
        np.array([0.1, 0.0, 0.01, 0.02]),
        pose_names=("x", "y", "phi", "psi"),
        velocity_names=("u", "v", "p", "r"),
    )
    assert len(nav.eta) == len(nav.pose_names) == 4 and nav.is_truth


def test_records_compare_by_value_pickle_and_are_slotted():
    env = shipgym.make("harbour", observer="kbf", controller="pid")
    env.reset(seed=0)
    for _ in range(3):
        _, _, _, _, info = env.step(ZERO)
    rec = info["record"]
    env.close()
    assert pickle.loads(pickle.dumps(rec)) == rec  # SubprocVecEnv pickles infos
    assert copy.deepcopy(rec) == rec
    other = rec.with_nav(NavigationData(rec.t, rec.nav.eta + 1e-9, rec.nav.nu))
    assert other != rec
    nan = NavigationData(0.0, np.full(3, np.nan), np.zeros(3))
    assert nan == NavigationData(0.0, np.full(3, np.nan), np.zeros(3))
    m = Measurement(0.0, None, False, False, np.zeros(3))
    assert m == Measurement(0.0, None, False, False, np.zeros(3))
    assert m != Measurement(0.0, np.zeros(3), False, False, np.zeros(3))
    with pytest.raises(TypeError):
        hash(rec)
    with pytest.raises(AttributeError):
        rec.no_such_field = True  # type: ignore[attr-defined]  # slotted: nothing added


def test_step_record_of_a_foreign_info_is_a_clear_error():
    with pytest.raises(ValueError, match="no shipgym StepRecord under 'record'"):
        step_record({"t": 0.0, "eta": np.zeros(3)})


def test_the_records_action_is_what_the_env_applied():
    """The normalised action in the record is the action clipped to [-1, 1] (the env's own
    observation carries it too: its last three entries)."""
    env = gym.make("shipgym/BlueLadyHarbour-v0")
    _, info = env.reset(seed=0)
    np.testing.assert_array_equal(info["record"].actuators.action, np.zeros(3))
    a = np.array([0.5, -2.0, 1.5], np.float32)
    obs, _, _, _, info = env.step(a)
    act = info["record"].actuators
    np.testing.assert_array_equal(act.action, [0.5, -1.0, 1.0])
    np.testing.assert_array_equal(act.action_clipped, [False, True, True])
    np.testing.assert_allclose(obs[-3:], act.action)
    env.close()
