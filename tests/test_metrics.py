"""Accuracy indices of Tomera (2014) eqs. 54-57, the online accumulator and RMSE."""

import math

import numpy as np
import pytest

from shipgym.metrics import SEED_WEIGHTS, ManoeuvreMetrics, accuracy_indices, j_c, rmse

DEG = math.pi / 180.0

# Hand-computed example: 4 samples.
#   x errors  0.1, -0.2,  0.3, -0.4 m   -> x_E   = (0.1 + 0.2 + 0.3 + 0.4) / 4 = 0.25 m
#   y errors  0.5,  0.0, -0.5,  1.0 m   -> y_E   = (0.5 + 0 + 0.5 + 1.0) / 4   = 0.5 m
#   psi errors 2, -4, 6, 0 deg (in rad) -> psi_E = (2 + 4 + 6 + 0) / 4       = 3 deg
#   J_c = 1 * 0.25 + 1 * 0.5 + 0.01 * 3 = 0.78
ETA_D = np.array(
    [
        [1.0, -2.0, 0.3],
        [2.0, -2.5, 0.5],
        [3.0, -3.0, 0.7],
        [4.0, -3.5, 0.9],
    ]
)
ERR = np.array(
    [
        [0.1, 0.5, 2 * DEG],
        [-0.2, 0.0, -4 * DEG],
        [0.3, -0.5, 6 * DEG],
        [-0.4, 1.0, 0.0],
    ]
)
ETA = ETA_D - ERR  # errors are desired minus actual
HAND = {"x_E": 0.25, "y_E": 0.5, "psi_E": 3.0, "J_c": 0.78}


def test_hand_computed_example():
    res = accuracy_indices(ETA, ETA_D)
    assert res == pytest.approx(HAND, rel=1e-12)
    # the sign of the errors does not matter
    assert accuracy_indices(ETA_D, ETA) == pytest.approx(HAND, rel=1e-12)
    # other weights
    res = accuracy_indices(ETA, ETA_D, weights=(2.0, 0.0, 0.1))
    assert res["J_c"] == pytest.approx(2 * 0.25 + 0.1 * 3.0)


@pytest.mark.parametrize(
    ("x_E", "y_E", "psi_E", "J_c"),
    [
        (1.3523, 0.4163, 377.0888, 5.5395),  # discrete Kalman filter
        (0.2376, 0.2984, 402.5533, 4.5615),  # continuous Kalman-Bucy filter
        (1.3774, 0.4738, 387.4744, 5.7259),  # extended Kalman filter
    ],
)
def test_eq57_reproduces_seed_table6(x_E, y_E, psi_E, J_c):
    assert j_c(x_E, y_E, psi_E) == pytest.approx(J_c, abs=1e-4)
    assert SEED_WEIGHTS == (1.0, 1.0, 0.01)


def test_heading_errors_wrap_across_pi():
    eta_d = np.array([[0.0, 0.0, math.pi - 0.01], [0.0, 0.0, -math.pi + 0.5 * DEG]])
    eta = np.array([[0.0, 0.0, -math.pi + 0.01], [0.0, 0.0, math.pi - 0.5 * DEG]])
    res = accuracy_indices(eta, eta_d)
    assert res["psi_E"] == pytest.approx((0.02 / DEG + 1.0) / 2)
    # 350 deg vs 10 deg is 20 deg, in either representation
    res = accuracy_indices([[0, 0, 350 * DEG]], [[0, 0, 10 * DEG]])
    assert res["psi_E"] == pytest.approx(20.0)
    m = ManoeuvreMetrics()
    m.record(0.0, eta[0], eta_d[0])
    m.record(1.0, eta[1], eta_d[1])
    assert m.summary()["psi_E"] == pytest.approx((0.02 / DEG + 1.0) / 2)


def test_accumulator_matches_batch_and_hand_example():
    m = ManoeuvreMetrics()
    for k in range(4):
        assert m.record(float(k), ETA[k], ETA_D[k].tolist())
    s = m.summary()
    assert {k: s[k] for k in HAND} == pytest.approx(HAND, rel=1e-12)
    assert s["n_samples"] == 4 and s["measured"] is None


def test_samples_every_second_from_a_quarter_second_stream():
    m = ManoeuvreMetrics(sample_period=1.0)
    taken = []
    for k in range(41):  # t = 0, 0.25, ..., 10 s
        t = 0.25 * k
        err = 1.0 if k % 4 == 0 else 100.0  # only whole seconds should count
        if m.record(t, [0.0, 0.0, 0.0], [err, -err, 0.0]):
            taken.append(t)
    assert taken == [float(i) for i in range(11)]
    s = m.summary()
    assert s["n_samples"] == 11 and s["x_E"] == 1.0 and s["y_E"] == 1.0
    assert s["n_steps"] == 41


def test_sampling_is_robust_to_accumulated_float_time():
    m = ManoeuvreMetrics()
    t, taken = 0.0, []
    for _ in range(1001):  # t accumulates 0.1 s steps with rounding error
        if m.record(t, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]):
            taken.append(round(t, 6))
        t += 0.1
    assert taken == [float(i) for i in range(101)]
    # a stream that starts late and steps coarsely: one sample per call at most
    m = ManoeuvreMetrics(sample_period=1.0)
    flags = [m.record(t, np.zeros(3), np.zeros(3)) for t in (2.5, 2.9, 3.0, 4.7, 7.2, 7.4)]
    assert flags == [False, False, True, True, True, False]


def test_measured_and_truth_are_kept_apart():
    m = ManoeuvreMetrics()
    for k in range(5):
        m.record(float(k), [1.0, 2.0, 0.1], [1.0, 2.0, 0.1], eta_meas_r=[1.5, 1.8, 0.1 + DEG])
    s = m.summary()
    assert s["x_E"] == 0.0 and s["y_E"] == 0.0 and s["psi_E"] == 0.0 and s["J_c"] == 0.0
    meas = s["measured"]
    assert meas["x_E"] == pytest.approx(0.5)
    assert meas["y_E"] == pytest.approx(0.2)
    assert meas["psi_E"] == pytest.approx(1.0)
    assert meas["J_c"] == pytest.approx(0.5 + 0.2 + 0.01)
    assert s["n_measured_samples"] == 5


def test_thruster_usage_and_saturation():
    m = ManoeuvreMetrics()
    forces = [[0.0, 0.0, 0.0], [10.0, -5.0, 0.0], [20.0, 5.0, 0.0], [10.0, 5.0, 0.0]]
    sats = [[False, False, False], [True, False, False], [True, True, False], [False] * 3]
    for k in range(4):
        m.record(0.5 * k, np.zeros(3), np.zeros(3), thrust=np.array(forces[k]), saturated=sats[k])
    s = m.summary()
    assert s["thrust_mean_abs"] == pytest.approx([10.0, 3.75, 0.0])
    assert s["thrust_total_variation"] == pytest.approx([30.0, 15.0, 0.0])
    assert s["saturated_fraction"] == pytest.approx([0.5, 0.25, 0.0])
    assert s["saturated_time"] == pytest.approx([1.0, 0.5, 0.0])
    empty = ManoeuvreMetrics().summary()
    assert all(math.isnan(x) for x in empty["thrust_mean_abs"])
    assert math.isnan(empty["J_c"]) and empty["n_samples"] == 0


def test_leg_times_and_per_leg_indices():
    m = ManoeuvreMetrics()
    for k in range(10):
        leg = 0 if k < 4 else 1
        err = 0.2 if leg == 0 else 0.6
        m.record(float(k), [0.0, 0.0, 0.0], [err, 0.0, 0.0], leg=leg)
    m.complete_leg(9.5)
    s = m.summary()
    assert s["legs_completed"] == 2
    assert s["leg_times"] == pytest.approx([4.0, 5.5])
    assert s["leg_completion_times"] == pytest.approx([4.0, 9.5])
    assert s["per_leg"][0]["x_E"] == pytest.approx(0.2)
    assert s["per_leg"][1]["x_E"] == pytest.approx(0.6)
    assert s["per_leg"][0]["n_samples"] == 4 and s["per_leg"][1]["n_samples"] == 6
    assert s["x_E"] == pytest.approx((4 * 0.2 + 6 * 0.6) / 10)
    m.reset()
    assert m.summary()["legs_completed"] == 0 and m.n_samples == 0


def test_bad_input_raises():
    with pytest.raises(ValueError, match=r"shape \(N, 3\)"):
        accuracy_indices(np.zeros((4, 2)), np.zeros((4, 2)))
    with pytest.raises(ValueError, match="at least one sample"):
        accuracy_indices(np.zeros((0, 3)), np.zeros((0, 3)))
    with pytest.raises(ValueError, match="finite"):
        accuracy_indices([[0, 0, float("nan")]], [[0, 0, 0]])
    with pytest.raises(ValueError, match="weights"):
        accuracy_indices(ETA, ETA_D, weights=(1, 1))
    with pytest.raises(ValueError, match="sample_period"):
        ManoeuvreMetrics(sample_period=0.0)
    m = ManoeuvreMetrics()
    m.record(1.0, np.zeros(3), np.zeros(3))
    with pytest.raises(ValueError, match="backwards"):
        m.record(0.5, np.zeros(3), np.zeros(3))
    with pytest.raises(ValueError, match="finite"):
        m.record(2.0, [float("nan"), 0, 0], np.zeros(3))
    with pytest.raises(ValueError, match="3 elements"):
        m.record(3.0, [0.0, 0.0], np.zeros(3))
    with pytest.raises(ValueError, match="thrust must have 3"):
        m.record(3.5, np.zeros(3), np.zeros(3), thrust=[1.0, 2.0])
    with pytest.raises(ValueError, match="thrust must be finite"):
        m.record(3.6, np.zeros(3), np.zeros(3), thrust=[1.0, 2.0, float("inf")])


def test_rmse():
    a = np.array([[1.0, 0.0], [3.0, 0.0], [1.0, 0.0], [3.0, 4.0]])
    b = np.array([[2.0, 0.0], [2.0, 0.0], [2.0, 0.0], [2.0, 0.0]])
    np.testing.assert_allclose(rmse(a, b), [1.0, 2.0])
    assert rmse([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]) == 0.0
    assert rmse(a, b, axis=None) == pytest.approx(math.sqrt((4 * 1.0 + 16.0) / 8))
    # headings: pi - 0.1 vs -pi + 0.1 differ by 0.2 rad, not 2 pi - 0.2
    assert rmse([math.pi - 0.1], [-math.pi + 0.1], angle=True) == pytest.approx(0.2)
    assert rmse([math.pi - 0.1], [-math.pi + 0.1]) == pytest.approx(2 * math.pi - 0.2)
    with pytest.raises(ValueError, match="empty"):
        rmse([], [])


# ---- indices of runs that do not describe a whole manoeuvre (issue 10) ---------------------------
def _run_metrics(n, **extra):
    m = ManoeuvreMetrics()
    for k in range(n):
        m.record(float(k), [0.1, 0.2, 0.0], [0.0, 0.0, 0.0])
    return {**m.summary(), "completed": True, "quay_contact": False, "duration_s": n - 1.0, **extra}


def test_indices_note_and_honest_indices():
    from shipgym.metrics import MIN_SAMPLES, honest_indices, indices_note

    ok = _run_metrics(MIN_SAMPLES)
    assert indices_note(ok) is None
    idx = honest_indices(ok)
    assert idx["J_c"] == pytest.approx(0.3) and idx["indices_note"] is None  # 0.1 + 0.2
    short = _run_metrics(MIN_SAMPLES - 1)
    assert "too short: 9 accuracy samples" in indices_note(short)
    contact = _run_metrics(50, quay_contact=True, completed=False, duration_s=49.0)
    assert indices_note(contact).startswith("quay contact at 49.0 s")
    unfinished = _run_metrics(50, completed=False, legs_completed=2)
    assert "not finished (2 legs" in indices_note(unfinished)
    assert indices_note(unfinished, plan_finite=False) is None  # station keeping: holds
    idx = honest_indices(contact)
    assert all(math.isnan(idx[k]) for k in ("x_E", "y_E", "psi_E", "J_c"))
    assert idx["measured"] is None and idx["partial_indices"]["truth"]["J_c"] == pytest.approx(0.3)
