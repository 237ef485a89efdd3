"""Tests of shipgym.disturbances.current: constant and Gauss-Markov current."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shipgym.disturbances import Current, CurrentConfig, current_body_velocity


def test_constant_current_needs_no_rng_and_is_exact() -> None:
    cfg = CurrentConfig(speed=0.1, direction_to=math.pi / 2)
    assert cfg.is_constant and cfg.speed_std == 0.0
    c = Current(cfg)
    c.reset(None)
    assert c.at(0.0) == (0.1, math.pi / 2)
    assert c.at(1e5) == (0.1, math.pi / 2)
    V, b = c.series([1.0, 2.0])
    assert V.tolist() == [0.1, 0.1] and b.tolist() == [math.pi / 2] * 2
    # sigma = 0 gives a constant current also after a seeded reset
    c.reset(np.random.default_rng(3))
    assert c.at(77.7) == (0.1, math.pi / 2)
    assert Current().at(5.0) == (0.0, 0.0)  # default: no current


def test_body_velocity_convention() -> None:
    # a current going east seen from a ship heading north sets to starboard
    u, v = current_body_velocity(0.2, math.pi / 2, 0.0)
    assert u == pytest.approx(0.0, abs=1e-15) and v == pytest.approx(0.2)
    # ship heading east: the same current is along the bow
    u, v = current_body_velocity(0.2, math.pi / 2, math.pi / 2)
    assert u == pytest.approx(0.2) and v == pytest.approx(0.0, abs=1e-15)
    c = Current(CurrentConfig(speed=0.2, direction_to=math.pi))  # going south
    c.reset(None)
    assert c.velocity_ned(0.0) == pytest.approx((-0.2, 0.0), abs=1e-15)
    assert c.body_velocity(0.0, 0.0) == pytest.approx((-0.2, 0.0), abs=1e-15)


def test_gauss_markov_statistics() -> None:
    T, std = 300.0, 0.01
    cfg = CurrentConfig.from_std(0.05, 1.0, std=std, time_constant=T)
    assert cfg.mu == pytest.approx(1 / 300) and cfg.sigma == pytest.approx(0.01 * math.sqrt(2 / T))
    assert cfg.speed_std == pytest.approx(std)
    c = Current(cfg)
    c.reset(np.random.default_rng(0))
    t = np.arange(0.0, 400_000.0, 1.0)
    V, b = c.series(t)
    assert float(np.mean(V)) == pytest.approx(0.05, abs=0.1 * std)
    assert float(np.std(V)) == pytest.approx(std, rel=0.10)
    # autocorrelation exp(-tau / T)
    x = V - V.mean()
    for lag in (100, 300):
        rho = float(np.dot(x[:-lag], x[lag:]) / np.dot(x, x))
        assert rho == pytest.approx(math.exp(-lag / T), abs=0.08)
    assert np.all(b == 1.0)  # no direction variation requested


def test_saturation_and_direction_random_walk() -> None:
    cfg = CurrentConfig(
        speed=0.1, mu=0.0, sigma=0.01, v_min=0.05, v_max=0.12, direction_mu=0.0,
        direction_sigma=0.01,
    )  # fmt: skip
    assert math.isinf(cfg.speed_std) and math.isinf(cfg.direction_std)
    c = Current(cfg)
    c.reset(np.random.default_rng(1))
    t = np.arange(0.0, 50_000.0, 1.0)
    V, b = c.series(t)
    assert float(V.min()) >= 0.05 and float(V.max()) <= 0.12
    assert float(V.min()) == 0.05 and float(V.max()) == 0.12  # both bounds are hit
    # a random walk starts at the mean and its increments have std sigma sqrt(dt)
    assert b[0] == 0.0 and V[0] == 0.1
    assert float(np.std(np.diff(b))) == pytest.approx(0.01, rel=0.05)


def test_same_seed_same_realisation_and_query_order() -> None:
    cfg = CurrentConfig.from_std(0.1, 0.5, std=0.02, direction_std=0.1)
    a, b, c = Current(cfg), Current(cfg), Current(cfg)
    a.reset(np.random.default_rng(9))
    b.reset(np.random.default_rng(9))
    c.reset(np.random.default_rng(10))
    ts = [0.0, 0.5, 4095.5, 4096.0, 10_000.25]
    for t in reversed(ts):
        b.at(t)
    assert [a.at(t) for t in ts] == [b.at(t) for t in ts]
    assert [a.at(t) for t in ts] != [c.at(t) for t in ts]
    V, d = a.series(np.array(ts))
    assert V.tolist() == pytest.approx([a.at(t)[0] for t in ts], abs=1e-15)
    assert d.tolist() == pytest.approx([a.at(t)[1] for t in ts], abs=1e-15)


def test_errors() -> None:
    c = Current(CurrentConfig(speed=0.1, sigma=0.001))
    with pytest.raises(RuntimeError, match="reset"):
        c.at(1.0)
    with pytest.raises(ValueError, match="needs a numpy Generator"):
        c.reset(None)
    c.reset(4)
    with pytest.raises(ValueError, match=">= 0 s"):
        c.at(-1.0)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"speed": -0.1}, "speed must be >= 0"),
        ({"sigma": -1.0}, "sigma must be >= 0"),
        ({"mu": -1.0}, "mu must be >= 0"),
        ({"speed": 0.3, "v_max": 0.2}, r"must lie in \[v_min, v_max\]"),
        ({"speed": "0.1"}, "speed must be a real number"),
        ({"v_max": "big"}, "v_max must be a real number or None"),
        ({"sample_period": 0.0}, "sample_period must be > 0"),
        ({"direction_to": math.inf}, "finite"),
    ],
)
def test_config_validation(kw: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        CurrentConfig(**kw)


def test_from_dict_and_from_std_errors() -> None:
    assert CurrentConfig.from_dict({"speed": 0.1}).speed == 0.1
    with pytest.raises(ValueError, match="valid keys are: speed"):
        CurrentConfig.from_dict({"velocity": 0.1})
    with pytest.raises(ValueError, match="time_constant must be > 0"):
        CurrentConfig.from_std(0.1, 0.0, std=0.01, time_constant=0.0)
