"""DGPS + gyrocompass sensor model (Tomera 2011, 2014; Artyszuk 2003)."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shipgym.observers.sensors import (
    SENSOR_PRESETS,
    TOMERA2011_HEADING_VARIANCE,
    Measurement,
    SensorConfig,
    Sensors,
    sensor_config,
)

QUIET = {"position_variance": 0.0, "heading_variance": 0.0}


def _sensors(seed=0, **kw):
    s = Sensors(SensorConfig(**kw))
    s.reset(np.random.default_rng(seed))
    return s


def _run(s, n, eta=(0.0, 0.0, 0.0)):
    return [s.measure(float(k + 1) * s.config.period, eta) for k in range(n)]


# ---- configuration ---------------------------------------------------------------------------
def test_defaults_are_the_seed_values():
    cfg = SensorConfig()
    assert cfg.period == 1.0  # Tomera (2014): "sampling time equal 1 (s)"
    assert cfg.position_variance == 0.01  # Tomera (2011) eq. 61
    # Tomera (2011) eq. 62: R_psi = 0.1, read as deg^2
    assert cfg.heading_variance == pytest.approx(0.1 * (math.pi / 180) ** 2)
    assert TOMERA2011_HEADING_VARIANCE == pytest.approx(3.0462e-5, rel=1e-4)
    assert cfg.antenna_offset == (0.0, 0.0)
    assert cfg.outlier_probability == 0.0 and cfg.dropout_probability == 0.0
    assert cfg.outlier_magnitude == 20.0 and cfg.dropout_duration == 10.0
    np.testing.assert_allclose(cfg.covariance, np.diag([0.01, 0.01, cfg.heading_variance]))
    for f in dataclasses.fields(SensorConfig):
        assert f.metadata.get("unit") and f.metadata.get("source"), f.name


def test_presets():
    assert set(SENSOR_PRESETS) == {
        "default", "dgps", "rtk", "tomera2014", "tomera2014-lake", "al-takie1982"
    }  # fmt: skip
    assert sensor_config("default") == SensorConfig()
    assert sensor_config("tomera2014") == SensorConfig()
    dgps = sensor_config("dgps")  # Artyszuk (2003): sigma 2 m per axis
    assert dgps.position_sigma == pytest.approx(2.0)
    assert dgps.heading_variance == SensorConfig().heading_variance
    rtk = sensor_config("rtk")  # assumed typical RTK: 0.02 m, 0.2 deg
    assert rtk.position_sigma == pytest.approx(0.02)
    assert math.degrees(rtk.heading_sigma) == pytest.approx(0.2)
    over = sensor_config("dgps", period=0.5, outlier_probability=0.1)
    assert over.period == 0.5 and over.outlier_probability == 0.1 and over.position_variance == 4
    with pytest.raises(ValueError, match="default, dgps, rtk, tomera2014"):
        sensor_config("gps")
    with pytest.raises(ValueError, match="unknown key"):
        sensor_config("rtk", sigma=1.0)


def test_from_dict_and_replace():
    cfg = SensorConfig.from_dict({"period": 2, "antenna_offset": [1.5, -0.2]})
    assert cfg.period == 2.0 and isinstance(cfg.period, float)
    assert cfg.antenna_offset == (1.5, -0.2)
    assert SensorConfig.from_dict(cfg.to_dict()) == cfg
    with pytest.raises(ValueError, match="unknown key.*valid keys"):
        SensorConfig.from_dict({"period": 1.0, "heading_sigma": 0.1})
    assert cfg.replace(period=0.1).period == 0.1
    with pytest.raises(ValueError, match="unknown key"):
        cfg.replace(perod=0.1)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"period": 0.0}, "period must be > 0"),
        ({"period": -1.0}, "period must be > 0"),
        ({"dropout_duration": 0.0}, "dropout_duration must be > 0"),
        ({"position_variance": -0.01}, "position_variance must be >= 0"),
        ({"heading_variance": -1e-6}, "heading_variance must be >= 0"),
        ({"outlier_magnitude": -1.0}, "outlier_magnitude must be >= 0"),
        ({"outlier_probability": 1.5}, r"outlier_probability .* \[0, 1\]"),
        ({"dropout_probability": -0.1}, r"dropout_probability .* \[0, 1\]"),
        ({"position_variance": math.nan}, "finite"),
        ({"period": math.inf}, "finite"),
        ({"antenna_offset": (1.0, math.nan)}, "finite"),
        ({"antenna_offset": (1.0, 0.0, 0.0)}, "antenna_offset must be two numbers"),
        ({"antenna_offset": "bow"}, "antenna_offset must be two numbers"),
        ({"period": "1 s"}, "period must be a number"),
        ({"period": True}, "period must be a number"),
    ],
)
def test_bad_config(kw, match):
    with pytest.raises(ValueError, match=match):
        SensorConfig(**kw)


# ---- sampling --------------------------------------------------------------------------------
def test_sample_times():
    s = Sensors()
    np.testing.assert_allclose(s.sample_times(0.0, 3.0), [1.0, 2.0, 3.0])
    np.testing.assert_allclose(s.sample_times(0.5, 2.5), [1.0, 2.0])
    assert s.sample_times(1.0, 1.0).size == 0 and s.sample_times(1.2, 1.9).size == 0
    fast = Sensors(SensorConfig(period=0.1))
    t = fast.sample_times(0.0, 0.1 * 10)  # 10 samples incl. t = 1.0 despite rounding
    assert t.size == 10 and t[-1] == pytest.approx(1.0)
    assert fast.sample_times(0.30000000000000004, 0.6).size == 3  # 0.4, 0.5, 0.6


def test_measure_needs_reset_and_valid_input():
    s = Sensors()
    with pytest.raises(RuntimeError, match="reset"):
        s.measure(1.0, [0, 0, 0])
    s.reset(np.random.default_rng(0))
    for bad in ([0, 0], [0, np.nan, 0], [[0, 0, 0]]):
        with pytest.raises(ValueError, match="eta_true"):
            s.measure(1.0, bad)
    with pytest.raises(TypeError, match="Generator"):
        s.reset("seed")
    with pytest.raises(TypeError, match="SensorConfig"):
        Sensors({"period": 1.0})
    s.reset(3)  # an int seed is accepted
    assert isinstance(s.measure(1.0, [0, 0, 0]), Measurement)


def test_noise_statistics():
    n = 40_000
    eta = np.array([12.0, -3.0, 0.4])
    s = _sensors(1)
    z = np.array([m.z for m in _run(s, n, eta)])
    err = z - eta
    cfg = s.config
    var = np.array([cfg.position_variance, cfg.position_variance, cfg.heading_variance])
    np.testing.assert_array_less(np.abs(err.mean(axis=0)), 4 * np.sqrt(var / n))
    np.testing.assert_allclose(err.var(axis=0), var, rtol=0.05)
    assert abs(np.corrcoef(err.T)[0, 1]) < 0.03  # independent axes
    # DGPS preset: sigma 2 m
    z = np.array([m.z for m in _run(_sensors(2, position_variance=4.0), n, eta)])
    np.testing.assert_allclose((z - eta)[:, :2].std(axis=0), 2.0, rtol=0.025)


@settings(max_examples=60, deadline=None)
@given(psi=st.floats(-50.0, 50.0), seed=st.integers(0, 2**32 - 1))
def test_heading_is_wrapped(psi, seed):
    s = _sensors(seed, heading_variance=0.05)
    m = s.measure(1.0, [0.0, 0.0, psi])
    assert -math.pi < m.z[2] <= math.pi
    d = (m.z[2] - psi + math.pi) % (2 * math.pi) - math.pi
    assert abs(d) < 10 * math.sqrt(0.05)


def test_heading_wraps_at_south_and_is_exact_without_noise():
    s = _sensors(0, **QUIET)
    assert s.measure(1.0, [0, 0, math.pi]).z[2] == pytest.approx(math.pi)
    assert s.measure(2.0, [0, 0, -math.pi]).z[2] == pytest.approx(math.pi)
    assert s.measure(3.0, [0, 0, 2 * math.pi + 0.1]).z[2] == pytest.approx(0.1)
    assert s.measure(4.0, [0, 0, math.radians(359)]).z[2] == pytest.approx(math.radians(-1))


def test_antenna_offset_geometry():
    # psi = 90 deg (heading east): an antenna 1 m forward reads 1 m east of the CG
    s = _sensors(0, antenna_offset=(1.0, 0.0), **QUIET)
    np.testing.assert_allclose(s.measure(1.0, [5.0, 2.0, math.pi / 2]).z, [5.0, 3.0, math.pi / 2])
    # psi = 0: 1 m to starboard reads 1 m east; psi = 180 deg: 1 m forward reads 1 m south
    s = _sensors(0, antenna_offset=(0.0, 1.0), **QUIET)
    np.testing.assert_allclose(s.measure(1.0, [0.0, 0.0, 0.0]).z, [0.0, 1.0, 0.0], atol=1e-15)
    s = _sensors(0, antenna_offset=(1.0, 0.0), **QUIET)
    np.testing.assert_allclose(
        s.measure(1.0, [0.0, 0.0, math.pi]).z, [-1.0, 0, math.pi], atol=1e-15
    )
    # general: lever arm length preserved, heading unaffected
    s = _sensors(0, antenna_offset=(3.0, -4.0), **QUIET)
    for psi in np.linspace(-3, 3, 13):
        z = s.measure(1.0, [1.0, 1.0, psi]).z
        assert math.hypot(z[0] - 1.0, z[1] - 1.0) == pytest.approx(5.0)
        assert z[2] == pytest.approx(psi)


def test_outliers_frequency_and_size():
    n, p = 20_000, 0.1
    ms = _run(_sensors(5, outlier_probability=p, **QUIET), n, (1.0, 2.0, 0.3))
    flags = np.array([m.outlier for m in ms])
    assert abs(flags.mean() - p) < 4 * math.sqrt(p * (1 - p) / n)
    jumps = np.array([math.hypot(m.z[0] - 1.0, m.z[1] - 2.0) for m in ms])
    np.testing.assert_allclose(jumps[flags], 20.0)
    np.testing.assert_allclose(jumps[~flags], 0.0, atol=1e-12)
    assert all(m.z[2] == pytest.approx(0.3) for m in ms)  # heading untouched
    # directions are spread over the circle
    ang = np.array([math.atan2(m.z[1] - 2.0, m.z[0] - 1.0) for m in ms if m.outlier])
    assert np.histogram(ang, bins=4, range=(-math.pi, math.pi))[0].min() > 0.2 * ang.size
    assert not any(m.outlier for m in _run(_sensors(5), 1000))  # none by default


def test_dropouts_frequency_and_duration():
    n, p = 20_000, 0.02
    ms = _run(_sensors(7, dropout_probability=p, dropout_duration=10.0), n)
    valid = np.array([m.valid for m in ms])
    assert all((m.z is None) == (not m.valid) for m in ms)
    starts = np.flatnonzero(~valid & np.r_[True, valid[:-1]])
    ends = np.flatnonzero(~valid & np.r_[valid[1:], True])
    lengths = ends - starts + 1
    assert len(starts) > 100
    assert np.all(lengths[:-1] % 10 == 0)  # back-to-back dropouts may merge
    assert np.mean(lengths[:-1] == 10) > 0.9
    # start probability per available sample (plus the restarts right at a dropout's end)
    n_starts = int(sum(math.ceil(k / 10) for k in lengths))
    eligible = int(valid.sum()) + n_starts
    rate = n_starts / eligible
    assert abs(rate - p) < 4 * math.sqrt(p * (1 - p) / eligible)
    # 10 s at a 0.5 s period: 20 missing samples
    ms = _run(_sensors(8, dropout_probability=1e-3, dropout_duration=10.0, period=0.5), 40_000)
    valid = np.array([m.valid for m in ms])
    starts = np.flatnonzero(~valid & np.r_[True, valid[:-1]])
    ends = np.flatnonzero(~valid & np.r_[valid[1:], True])
    assert np.all((ends - starts + 1)[:-1] % 20 == 0) and len(starts) > 10


def test_dropout_certain():
    ms = _run(_sensors(0, dropout_probability=1.0), 30)
    assert not any(m.valid for m in ms)


def test_seeding_reproducible_and_common_random_numbers():
    def zs(seed, **kw):
        return [m.z for m in _run(_sensors(seed, **kw), 200, (3.0, 4.0, 1.0))]

    a, b, c = zs(11), zs(11), zs(12)
    np.testing.assert_array_equal(np.array(a), np.array(b))
    assert not np.allclose(np.array(a), np.array(c))
    # reset from the same generator state gives the same stream; the generator advances
    s = Sensors()
    rng = np.random.default_rng(4)
    s.reset(rng)
    first = [m.z for m in _run(s, 5)]
    s.reset(rng)
    second = [m.z for m in _run(s, 5)]
    assert not np.allclose(np.array(first), np.array(second))
    s.reset(np.random.default_rng(4))
    np.testing.assert_array_equal(np.array([m.z for m in _run(s, 5)]), np.array(first))
    # switching faults on does not change the noise of the remaining samples
    faulty = _run(_sensors(11, outlier_probability=0.2, dropout_probability=0.05), 200, (3, 4, 1))
    same = [i for i, m in enumerate(faulty) if m.valid and not m.outlier]
    assert len(same) > 50
    np.testing.assert_array_equal(np.array([faulty[i].z for i in same]), np.array(a)[same])


def test_block_draws_are_one_draw_per_sample():
    """Sensors draws its streams in blocks; every sample must be what one draw per sample
    from the same three streams gives (written out here, across several block ends, with
    outliers, dropouts and an antenna offset)."""
    from shipgym.dynamics import wrap_angle
    from shipgym.observers.sensors import _streams

    cfg = SensorConfig(outlier_probability=0.1, dropout_probability=0.02,
                       antenna_offset=(1.5, -0.4))  # fmt: skip
    s = Sensors(cfg)
    s.reset(np.random.default_rng(21))
    noise, outl, drop, _ = _streams(np.random.default_rng(21))
    # the first three streams are those of the three-child spawn used before the correlated
    # errors' fourth stream was added: a white-noise configuration measures as before
    seq = np.random.SeedSequence(int(np.random.default_rng(21).integers(2**63)))
    for g, old in zip((noise, outl, drop), seq.spawn(3), strict=True):
        assert g.bit_generator.seed_seq.spawn_key == old.spawn_key
        assert g.bit_generator.seed_seq.entropy == old.entropy
    sig = np.array([cfg.position_sigma, cfg.position_sigma, cfg.heading_sigma])
    until = -math.inf
    kinds = {"valid": 0, "outlier": 0, "dropout": 0}
    for k in range(900):
        t = float(k + 1) * cfg.period
        eta = (0.01 * k, -0.02 * k, 0.003 * k - 1.0)
        m = s.measure(t, eta)
        n = noise.standard_normal(3) * sig
        u_out, ang = outl.random(2)
        u_drop = drop.random()
        if t < until - 1e-9 * cfg.period or u_drop < cfg.dropout_probability:
            if not t < until - 1e-9 * cfg.period:
                until = t + cfg.dropout_duration
            assert m.z is None and not m.valid
            kinds["dropout"] += 1
            continue
        c, sn = math.cos(eta[2]), math.sin(eta[2])
        xa, ya = cfg.antenna_offset
        z = np.array([eta[0] + c * xa - sn * ya, eta[1] + sn * xa + c * ya, eta[2]]) + n
        out = u_out < cfg.outlier_probability
        if out:
            z[0] += cfg.outlier_magnitude * math.cos(2.0 * math.pi * ang)
            z[1] += cfg.outlier_magnitude * math.sin(2.0 * math.pi * ang)
        z[2] = wrap_angle(float(z[2]))
        np.testing.assert_array_equal(m.z, z)
        assert m.valid and m.outlier == out and type(m.outlier) is bool
        kinds["outlier" if out else "valid"] += 1
    assert min(kinds.values()) > 10, kinds  # every branch, over three block ends


def test_batched_sensors_measure_what_each_env_s_sensors_measure():
    """Twelve envs, each seeded as a Sensors of its own, with noise, outliers, dropouts and an
    antenna offset; block refills every 7 samples (side by side on threads: 8 or more at once):
    the same flags, the same fixes, bit for bit (row i of the law over N is the law at N = 1
    on row i's inputs)."""
    import dataclasses

    from shipgym.observers.sensors import BatchedSensors

    cfg = dataclasses.replace(sensor_config("dgps"), outlier_probability=0.1,
                              dropout_probability=0.05, antenna_offset=(-3.0, 1.0))  # fmt: skip
    n = 12
    batched = BatchedSensors(cfg, n, block=7)
    batched.reset([np.random.default_rng(i) for i in range(n)])
    single = [Sensors(cfg) for _ in range(n)]
    for i, s in enumerate(single):
        s.reset(np.random.default_rng(i))
    rng = np.random.default_rng(99)
    counts = {"valid": 0, "outlier": 0, "dropped": 0}
    for k in range(80):
        eta = rng.normal(0.0, 50.0, (n, 3))
        z, valid, outlier = batched.measure(np.full(n, float(k)), eta)
        for i, s in enumerate(single):
            m = s.measure(float(k), eta[i])
            assert (m.valid, m.outlier) == (bool(valid[i]), bool(outlier[i])), (k, i)
            if m.valid:
                np.testing.assert_array_equal(z[i], m.z)  # bit for bit: one law
            else:
                assert np.all(np.isnan(z[i]))
        counts["valid"] += int(valid.sum())
        counts["outlier"] += int(outlier.sum())
        counts["dropped"] += int((~valid).sum())
    assert min(counts.values()) > 0  # every branch was taken
    with pytest.raises(RuntimeError, match="reset"):
        BatchedSensors(cfg, 2).measure([0.0, 0.0], np.zeros((2, 3)))


def test_batched_sensors_per_env_noise_and_masked_samples():
    """Each env its own variances (set_config) and its own sample instants (a mask): env i
    measures bit for bit what a Sensors of its configuration measures at its own instants."""
    import dataclasses

    from shipgym.observers.sensors import BatchedSensors

    base = dataclasses.replace(sensor_config("dgps"), outlier_probability=0.05,
                               dropout_probability=0.05)  # fmt: skip
    n = 3
    cfgs = [base.replace(position_variance=0.01 * (i + 1) ** 2, heading_variance=1e-4 * (i + 1))
            for i in range(n)]  # fmt: skip
    batched = BatchedSensors(base, n, block=5)
    for i, c in enumerate(cfgs):
        batched.set_config(i, c)
    batched.reset([np.random.default_rng(40 + i) for i in range(n)])
    single = [Sensors(c) for c in cfgs]
    for i, s in enumerate(single):
        s.reset(np.random.default_rng(40 + i))
    rng = np.random.default_rng(3)
    seen = np.zeros(n, int)
    for k in range(120):
        mask = rng.random(n) < 0.6
        eta = rng.normal(0.0, 20.0, (n, 3))
        z, valid, _ = batched.measure(np.full(n, float(k)), eta, mask)
        for i in np.nonzero(mask)[0]:
            m = single[i].measure(float(k), eta[i])
            assert m.valid == bool(valid[i])
            if m.valid:
                np.testing.assert_array_equal(z[i], m.z)  # bit for bit: one law
            seen[i] += 1
    assert seen.min() > 50
    with pytest.raises(ValueError, match="differ only"):
        batched.set_config(0, base.replace(period=2.0))


def test_measure_pose_is_measure_in_floats():
    # the environment's float form draws the same streams and gives the same samples
    kw = dict(
        dropout_probability=0.2, dropout_duration=2.0, outlier_probability=0.2,
        position_correlated_fraction=0.5, position_correlation_time=30.0, heading_bias_std=0.01,
        antenna_offset=(1.0, -0.5),
    )  # fmt: skip
    a, b = _sensors(4, **kw), _sensors(4, **kw)
    rng = np.random.default_rng(1)
    for k in range(600):  # past the 256-sample blocks
        eta = rng.uniform(-50.0, 50.0, 3)
        m = a.measure(float(k + 1), eta)
        t, z, valid, outlier = b.measure_pose(float(k + 1), *eta.tolist())
        assert (t, valid, outlier) == (m.t, m.valid, m.outlier)
        if m.z is None:
            assert z is None
        else:
            assert all(type(v) is float for v in z)
            np.testing.assert_array_equal(np.array(z), m.z)
    with pytest.raises(ValueError, match="finite"):
        b.measure_pose(1.0, 0.0, math.nan, 0.0)
    with pytest.raises(RuntimeError, match="reset"):
        Sensors().measure_pose(1.0, 0.0, 0.0, 0.0)
