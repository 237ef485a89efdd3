"""DP metrics (Al-Takie 1982 2.3, 3.1) against analytic values."""

import math

import numpy as np
import pytest
from scipy.stats import chi2

from shipgym.dp import dp_metrics, dp_radius, wave_band_ratio

TWO_PI = 2.0 * math.pi
DT = 0.31


def _t(duration=2000.0, dt=DT):
    return np.arange(int(duration / dt)) * dt


@pytest.mark.parametrize(("A1", "A2"), [(1.0, 0.3), (0.2, 0.5), (0.05, 0.05)])
def test_wave_band_ratio_of_two_tones(A1, A2):
    t = _t()
    cap = np.array([2.0e5, 3.0e5, 1.0e7])
    rng = np.random.default_rng(1)
    # each DOF: the same normalised tones with random phases, so the ratio is (A2/A1)^2
    u = np.stack(
        [A1 * np.sin(TWO_PI * 0.02 * t + rng.uniform(0, TWO_PI))
         + A2 * np.sin(TWO_PI * 0.1 * t + rng.uniform(0, TWO_PI)) for _ in range(3)],
        axis=1,
    )  # fmt: skip
    ratio = wave_band_ratio(t, u * cap, cap)
    assert ratio == pytest.approx((A2 / A1) ** 2, rel=0.05)


def test_wave_band_ratio_sums_over_dofs_and_ignores_out_of_band_power():
    t = _t()
    cap = np.array([1.0, 2.0])
    # DOF 0: LF tone 1.0; DOF 1: HF tone 0.5 (normalised) and a 0.4 Hz tone outside both bands
    u = np.stack(
        [np.sin(TWO_PI * 0.02 * t),
         cap[1] * (0.5 * np.sin(TWO_PI * 0.15 * t) + 2.0 * np.sin(TWO_PI * 0.4 * t))],
        axis=1,
    )  # fmt: skip
    assert wave_band_ratio(t, u, cap) == pytest.approx(0.25, rel=0.05)
    # a mean thrust is LF effort (no detrending): a DC of 1 plus the HF tone 0.5
    u2 = 1.0 + 0.5 * np.sin(TWO_PI * 0.1 * t)
    assert wave_band_ratio(t, u2, [1.0]) == pytest.approx(0.125 / 1.0, rel=0.05)
    # HF only: the LF band holds only the Hann window's far side lobes
    assert wave_band_ratio(t, 0.5 * np.sin(TWO_PI * 0.1 * t), [1.0]) > 1e6


def test_wave_band_ratio_rejects_bad_input():
    t = _t(300.0)
    u = np.sin(TWO_PI * 0.02 * t)
    with pytest.raises(ValueError, match="uniform"):
        wave_band_ratio(np.r_[t[:-1], t[-1] + 0.1], u, [1.0])
    with pytest.raises(ValueError, match="shorter than one Welch segment"):
        wave_band_ratio(t[:200], u[:200], [1.0])
    with pytest.raises(ValueError, match="capacity"):
        wave_band_ratio(t, u, [0.0])
    with pytest.raises(ValueError, match="Nyquist"):
        wave_band_ratio(np.arange(200) * 3.0, np.ones(200), [1.0])
    with pytest.raises(ValueError, match="hf_band"):
        wave_band_ratio(t, u, [1.0], hf_band=(0.3, 0.1))
    with pytest.raises(ValueError, match="no power"):
        wave_band_ratio(t, np.zeros_like(t), [1.0])


def test_circle_gives_rms_and_max_equal_to_its_radius():
    t = _t(600.0)
    r = 3.0
    th = TWO_PI * t / 200.0
    eta = np.stack([10.0 + r * np.cos(th), -4.0 + r * np.sin(th), np.zeros_like(t)], axis=1)
    m = dp_metrics(t, eta, [10.0, -4.0, 0.0], np.ones((t.size, 3)), [2.0, 4.0, 8.0])
    assert m["position_rms_m"] == pytest.approx(r, rel=1e-12)
    assert m["max_radial_error_m"] == pytest.approx(r, rel=1e-12)
    assert m["inside_radius_pct"] == 100.0
    assert m["heading_rms_deg"] == 0.0
    np.testing.assert_allclose(m["thrust_usage"], [0.5, 0.25, 0.125])
    assert m["thrust_usage_mean"] == pytest.approx((0.5 + 0.25 + 0.125) / 3)
    assert m["samples"] == t.size and m["duration_s"] == pytest.approx(t[-1])
    assert m["saturated_pct"] is None and m["lf_rmse"] is None and m["nis_mean"] is None


def test_inside_percentage_of_a_known_trajectory():
    """A straight drift away at 0.01 m/s from the set-point for 1 000 s: inside 7 m for the
    first 700 s (70 %), inside a 3 % of 100 m depth = 3 m radius for 30 %."""
    t = np.arange(100_000) * 0.01  # fine sampling: the fraction converges to the time fraction
    eta = np.stack([0.006 * t, 0.008 * t, np.zeros_like(t)], axis=1)  # |v| = 0.01 m/s
    tau = np.ones((t.size, 3))
    assert dp_radius() == 7.0
    assert dp_radius(100.0) == pytest.approx(3.0)
    assert dp_radius(500.0) == 7.0
    m7 = dp_metrics(t, eta, np.zeros(3), tau, np.ones(3))
    m3 = dp_metrics(t, eta, np.zeros(3), tau, np.ones(3), radius=dp_radius(100.0))
    assert m7["inside_radius_pct"] == pytest.approx(70.0, abs=0.01)
    assert m3["inside_radius_pct"] == pytest.approx(30.0, abs=0.01)
    assert m3["radius_m"] == pytest.approx(3.0)
    assert m7["max_radial_error_m"] == pytest.approx(0.01 * t[-1], rel=1e-12)
    assert m7["position_rms_m"] == pytest.approx(0.01 * t[-1] / math.sqrt(3.0), rel=1e-4)


def test_heading_errors_are_wrapped():
    t = _t(300.0)
    # measured just past north, desired just before: the true error is +-2 deg, not 356 deg
    psi = np.where(np.arange(t.size) % 2 == 0, math.radians(179.0), math.radians(-179.0))
    eta = np.stack([np.zeros_like(t), np.zeros_like(t), psi], axis=1)
    m = dp_metrics(t, eta, [0.0, 0.0, math.radians(-179.0)], np.ones((t.size, 3)), np.ones(3))
    expected = 2.0 * math.sqrt(np.mean(np.arange(t.size) % 2 == 0))  # 2 deg on even samples
    assert m["heading_rms_deg"] == pytest.approx(expected, rel=1e-9)
    eta[:, 2] += 4.0 * math.pi  # any branch
    m2 = dp_metrics(t, eta, [0.0, 0.0, math.radians(-179.0)], np.ones((t.size, 3)), np.ones(3))
    assert m2["heading_rms_deg"] == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("dof", [2, 3])
def test_nis_of_chi_square_samples(dof):
    rng = np.random.default_rng(dof)
    n = 20000
    t = np.arange(n) * 1.0
    nis = rng.chisquare(dof, n)
    nis[::50] = np.nan  # missing samples
    m = dp_metrics(t, np.zeros((n, 3)), np.zeros(3), np.ones((n, 3)), np.ones(3), nis=nis,
                   nis_dof=dof)  # fmt: skip
    assert m["nis_mean"] == pytest.approx(dof, rel=0.03)
    assert m["nis_inside_95_pct"] == pytest.approx(95.0, abs=0.6)
    # an overconfident filter (NIS 3x too large) is flagged
    m_bad = dp_metrics(t, np.zeros((n, 3)), np.zeros(3), np.ones((n, 3)), np.ones(3),
                       nis=3.0 * nis, nis_dof=dof)  # fmt: skip
    assert m_bad["nis_inside_95_pct"] < 80.0
    assert chi2.ppf(0.975, dof) > 0  # the interval exists


def test_saturation_lf_error_and_wave_ratio_reported():
    t = _t(1000.0)
    n = t.size
    sat = np.zeros((n, 4), dtype=bool)
    sat[: n // 4, 2] = True
    sat[: n // 8, 0] = True  # overlaps: still a quarter of the samples
    lf = np.stack([np.full(n, 0.3), np.where(np.arange(n) % 2 == 0, 1.0, -1.0)], axis=1)
    tau = np.stack([np.sin(TWO_PI * 0.02 * t), 0.2 * np.sin(TWO_PI * 0.1 * t), 0 * t], axis=1)
    m = dp_metrics(t, np.zeros((n, 3)), np.zeros(3), tau, np.ones(3), saturated=sat,
                   lf_error=lf)  # fmt: skip
    assert m["saturated_pct"] == pytest.approx(100.0 * (n // 4) / n)
    np.testing.assert_allclose(m["lf_rmse"], [0.3, 1.0])
    assert m["wave_band_ratio"] == pytest.approx(0.04, rel=0.05)
    # a record shorter than the 100 s Welch segment: no ratio, the rest still computed
    short = dp_metrics(t[:100], np.zeros((100, 3)), np.zeros(3), tau[:100], np.ones(3))
    assert short["wave_band_ratio"] is None and short["position_rms_m"] == 0.0


@pytest.mark.parametrize(
    "kwargs",
    [
        {"t": np.array([0.0, 1.0, 3.0])},
        {"t": np.array([0.0])},
        {"eta": np.zeros((5, 2))},
        {"eta_d": np.zeros(2)},
        {"tau_c": np.zeros((4, 3))},
        {"capacity": [1.0, -1.0, 1.0]},
        {"capacity": [1.0, 1.0]},
        {"radius": 0.0},
        {"nis": np.array([1.0, -2.0])},
        {"nis": np.array([1.0]), "nis_dof": 0},
        {"saturated": np.zeros(3, dtype=bool)},
        {"lf_error": np.zeros((4, 2))},
        {"eta": np.full((5, 3), np.nan)},
    ],
)
def test_bad_input_raises(kwargs):
    args = {
        "t": np.arange(5.0),
        "eta": np.zeros((5, 3)),
        "eta_d": np.zeros(3),
        "tau_c": np.zeros((5, 3)),
        "capacity": np.ones(3),
    }
    kw = {k: kwargs.pop(k) for k in list(kwargs) if k not in args}
    args.update(kwargs)
    with pytest.raises(ValueError):
        dp_metrics(args["t"], args["eta"], args["eta_d"], args["tau_c"], args["capacity"], **kw)


@pytest.mark.parametrize("depth", [0.0, -5.0, math.nan, "deep", True])
def test_dp_radius_rejects_bad_depths(depth):
    with pytest.raises(ValueError, match="depth"):
        dp_radius(depth)


def test_step_metrics_of_a_second_order_response():
    """Against the analytic step response of zeta = 0.5, w_n = 0.2 rad/s."""
    from shipgym.dp.metrics import step_metrics

    z, wn, t0, A = 0.5, 0.2, 100.0, 1.9
    t = np.arange(0.0, 400.0, 0.01)
    tau = np.clip(t - t0, 0.0, None)
    wd = wn * np.sqrt(1 - z * z)
    y = A * (
        1 - np.exp(-z * wn * tau) * (np.cos(wd * tau) + z / np.sqrt(1 - z * z) * np.sin(wd * tau))
    )
    m = step_metrics(t, y, t0, A)
    assert m["overshoot_pct"] == pytest.approx(
        100 * np.exp(-np.pi * z / np.sqrt(1 - z * z)), rel=1e-3
    )
    # the 10-90 % rise time of this system: 1.64 / w_n (the standard table value for zeta 0.5)
    assert m["rise_time_s"] == pytest.approx(1.64 / wn, rel=0.01)
    assert 4.0 / (z * wn) * 0.6 < m["settling_time_s"] < 4.0 / (z * wn) * 1.1
    never = step_metrics(t, 0.5 * y, t0, A)  # stops at half the step
    assert never["rise_time_s"] == np.inf and never["settling_time_s"] == np.inf
    with pytest.raises(ValueError, match="step must be"):
        step_metrics(t, y, t0, 0.0)
