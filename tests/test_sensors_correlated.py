"""Time-correlated sensor errors: the Gauss-Markov DGPS error and the gyrocompass bias.

Checked against the process they are meant to be (independent of the implementation): the
stationary variance and the lag-k autocorrelation ``f exp(-k T / tau)`` of a first-order
Gauss-Markov error plus white noise, with tolerances from the estimators' sampling
distributions (Bartlett's formula for the autocorrelation), and the exact recursion written
out from its formula.
"""

import math

import numpy as np
import pytest

from shipgym.observers.sensors import (
    LAKE_HEADING_BIAS_STD,
    BatchedSensors,
    SensorConfig,
    Sensors,
    _streams,
    sensor_config,
)


def _errors(cfg: SensorConfig, n: int, seed: int) -> np.ndarray:
    """Measurement errors (n, 3) of n samples at the origin (heading error wrapped)."""
    s = Sensors(cfg)
    s.reset(np.random.default_rng(seed))
    z = np.array([s.measure((k + 1) * cfg.period, (0.0, 0.0, 0.0)).z for k in range(n)])
    return z


def _acf(x: np.ndarray, lags: list[int]) -> np.ndarray:
    x = x - x.mean()
    c0 = float(x @ x) / x.size
    return np.array([float(x[:-k] @ x[k:]) / x.size / c0 for k in lags])


def _bartlett_sd(rho, k: int, n: int) -> float:
    """Bartlett's large-sample std of the lag-k sample autocorrelation, for the true ACF
    ``rho(m)`` (m >= 0; symmetric)."""
    m = np.arange(-2000, 2001)
    r = np.vectorize(lambda j: rho(abs(int(j))))
    rm, rp, rn, rk = r(m), r(m + k), r(m - k), rho(k)
    var = np.sum(rm**2 + rp * rn - 4.0 * rk * rm * rn + 2.0 * rm**2 * rk**2) / n
    return float(math.sqrt(var))


@pytest.mark.parametrize("f, tau", [(1.0, 20.0), (0.8, 60.0)])
def test_dgps_error_variance_and_autocorrelation(f, tau):
    cfg = SensorConfig(position_variance=0.01, position_correlated_fraction=f,
                       position_correlation_time=tau)  # fmt: skip
    n = 60_000
    e = _errors(cfg, n, seed=5)
    a = math.exp(-cfg.period / tau)

    def rho(m: int) -> float:
        return 1.0 if m == 0 else f * a**m

    # effective sample size of the variance estimator of this process: n / (sum rho^2 * 2)
    s2 = 1.0 + 2.0 * sum(rho(m) ** 2 for m in range(1, 5000))
    rel_sd = math.sqrt(2.0 * s2 / n)
    for axis in (0, 1):
        x = e[:, axis]
        assert x.var() == pytest.approx(0.01, rel=4.5 * rel_sd), (axis, x.var(), rel_sd)
        lags = [1, 5, 20, 60]
        got = _acf(x, lags)
        for k, r in zip(lags, got, strict=True):
            tol = 4.5 * _bartlett_sd(rho, k, n)
            assert abs(r - f * a**k) < tol, (axis, k, r, f * a**k, tol)
    # x and y are independent processes
    assert abs(np.corrcoef(e[:, 0], e[:, 1])[0, 1]) < 4.5 * math.sqrt(s2 / n)


def test_recursion_is_the_exact_discretisation_written_out():
    """b_{k+1} = exp(-T/tau) b_k + sqrt(s^2 (1 - exp(-2T/tau))) w_k from the fourth stream,
    b_0 ~ N(0, s^2), plus the white part sqrt(1 - f) sigma n_k of the first stream; the bias:
    a constant b ~ N(0, s_b^2) (correlation time 0) or the same recursion."""
    for tb in (0.0, 30.0):
        cfg = SensorConfig(position_variance=0.04, position_correlated_fraction=0.7,
                           position_correlation_time=25.0, heading_bias_std=0.01,
                           heading_bias_correlation_time=tb, period=0.5)  # fmt: skip
        s = Sensors(cfg)
        s.reset(np.random.default_rng(3))
        noise, _, _, corr = _streams(np.random.default_rng(3))
        sd_p, sd_b = math.sqrt(0.7 * 0.04), 0.01
        a_p = math.exp(-0.5 / 25.0)
        a_b = 1.0 if tb == 0.0 else math.exp(-0.5 / tb)
        w0 = corr.standard_normal(3)
        b = np.array([sd_p * w0[0], sd_p * w0[1], sd_b * w0[2]])
        white = np.array([math.sqrt(0.3 * 0.04)] * 2 + [cfg.heading_sigma])
        first = b[2]
        for k in range(700):  # across block ends (256)
            t = 0.5 * (k + 1)
            m = s.measure(t, (1.0, -2.0, 0.3))
            w = corr.standard_normal(3)
            b = (
                np.array([a_p, a_p, a_b]) * b
                + np.array([sd_p * math.sqrt(1 - a_p**2)] * 2 + [sd_b * math.sqrt(1 - a_b**2)]) * w
            )
            z = np.array([1.0, -2.0, 0.3]) + white * noise.standard_normal(3) + b
            np.testing.assert_allclose(m.z, z, rtol=0, atol=1e-12)
            np.testing.assert_allclose(s.correlated_error, b, rtol=0, atol=1e-15)
        if tb == 0.0:
            assert b[2] == first  # constant over the episode


def test_heading_bias_across_episodes():
    """A constant bias per episode with std s_b: over many episodes the episode biases have
    that std (chi-square tolerance) and each episode's heading error minus its bias is the
    white gyro noise."""
    cfg = sensor_config("tomera2014-lake")
    assert math.degrees(cfg.heading_bias_std) == pytest.approx(0.25 / math.cos(math.radians(53.6)))
    n_ep = 3000
    biases = []
    rng = np.random.default_rng(11)
    for _ in range(n_ep):
        s = Sensors(cfg)
        s.reset(rng)
        b0 = s.correlated_error[2]
        for k in range(3):
            m = s.measure(float(k + 1), (0.0, 0.0, 0.0))
        assert s.correlated_error[2] == b0
        biases.append(b0)
    sd = float(np.std(biases))
    assert sd == pytest.approx(LAKE_HEADING_BIAS_STD, rel=4.5 / math.sqrt(2 * n_ep))
    assert m.z is not None


def test_white_noise_and_faults_unchanged_by_the_correlated_errors():
    """Common random numbers: switching the correlated errors on keeps the validity and
    outlier flags, and z - correlated error is the white configuration's noise scaled by
    sqrt(1 - f) in position."""
    base = SensorConfig(outlier_probability=0.05, dropout_probability=0.02)
    on = base.replace(position_correlated_fraction=0.75, position_correlation_time=40.0,
                      heading_bias_std=0.005)  # fmt: skip
    a, b = Sensors(base), Sensors(on)
    a.reset(np.random.default_rng(8))
    b.reset(np.random.default_rng(8))
    eta = np.array([3.0, 4.0, 0.2])
    for k in range(400):
        ma, mb = a.measure(k + 1.0, eta), b.measure(k + 1.0, eta)
        assert (ma.valid, ma.outlier) == (mb.valid, mb.outlier)
        if ma.valid:
            wa = ma.z - eta
            wb = mb.z - eta - b.correlated_error
            np.testing.assert_allclose(wb[:2], 0.5 * wa[:2] if not ma.outlier else wb[:2],
                                       rtol=0, atol=1e-12)  # fmt: skip
            np.testing.assert_allclose(wb[2], wa[2], rtol=0, atol=1e-12)


def test_defaults_are_white_and_seeded():
    cfg = SensorConfig()
    assert not cfg.correlated and cfg.position_correlated_fraction == 0.0
    assert cfg.heading_bias_std == 0.0
    e1 = _errors(sensor_config("tomera2014-lake"), 50, seed=2)
    e2 = _errors(sensor_config("tomera2014-lake"), 50, seed=2)
    np.testing.assert_array_equal(e1, e2)
    assert not np.array_equal(e1, _errors(sensor_config("tomera2014-lake"), 50, seed=3))


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"position_correlated_fraction": 1.5}, "in \\[0, 1\\]"),
        ({"position_correlated_fraction": 0.5}, "position_correlation_time must be > 0"),
        ({"heading_bias_std": -0.1}, "heading_bias_std must be >= 0"),
        ({"heading_bias_correlation_time": -1.0}, "must be >= 0"),
        ({"position_correlation_time": float("inf")}, "finite"),
    ],
)
def test_bad_correlated_config(kw, match):
    with pytest.raises(ValueError, match=match):
        SensorConfig(**kw)


def test_batched_sensors_implement_the_same_process():
    """Per-env variances, masked samples, dropouts and the correlated errors: env i of the
    batch measures bit for bit what a Sensors of its configuration measures."""
    base = sensor_config("tomera2014-lake", dropout_probability=0.03, outlier_probability=0.05)
    n = 11  # (8 or more refills at once run side by side on threads)
    cfgs = [base.replace(position_variance=0.01 * (i + 1), heading_variance=1e-5 * (i + 1))
            for i in range(n)]  # fmt: skip
    batched = BatchedSensors(base, n, block=6)
    for i, c in enumerate(cfgs):
        batched.set_config(i, c)
    batched.reset([np.random.default_rng(70 + i) for i in range(n)])
    single = [Sensors(c) for c in cfgs]
    for i, s in enumerate(single):
        s.reset(np.random.default_rng(70 + i))
    rng = np.random.default_rng(4)
    seen = np.zeros(n, int)
    for k in range(150):
        mask = rng.random(n) < 0.7
        eta = rng.normal(0.0, 20.0, (n, 3))
        z, valid, _ = batched.measure(np.full(n, float(k)), eta, mask)
        for i in np.nonzero(mask)[0]:
            m = single[i].measure(float(k), eta[i])
            assert m.valid == bool(valid[i])
            np.testing.assert_array_equal(batched.correlated_error[i], single[i].correlated_error)
            if m.valid:
                np.testing.assert_array_equal(z[i], m.z)  # bit for bit: one law
            seen[i] += 1
    assert seen.min() > 80
    with pytest.raises(ValueError, match="differ only"):
        batched.set_config(0, base.replace(position_correlation_time=10.0))
