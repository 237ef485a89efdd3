"""Tests of shipgym.disturbances.wind: relative wind, Blendermann loads and Gauss-Markov gusts."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shipgym.disturbances import (
    BLENDERMANN,
    BlendermannCoefficients,
    Wind,
    WindConfig,
    WindLoad,
    blendermann,
    blendermann_coefficients,
    relative_wind,
    wind_load,
)
from shipgym.disturbances.wind import blendermann_load
from shipgym.dynamics.params import BLUE_LADY_WINDAGE, WindageParameters

PI = math.pi
WL = WindLoad("tanker-loaded", BLUE_LADY_WINDAGE)

# --------------------------------------------------------------------------------------------
# Coefficient table
# --------------------------------------------------------------------------------------------


def test_tanker_rows() -> None:
    assert blendermann("tanker-loaded") == BlendermannCoefficients(0.70, 0.90, 0.55, 0.40, 3.1)
    assert blendermann("tanker-ballast") == BlendermannCoefficients(0.70, 0.75, 0.55, 0.40, 2.2)
    assert len(BLENDERMANN) == 17


def test_unknown_row_lists_valid_names() -> None:
    with pytest.raises(ValueError, match="tanker-loaded"):
        blendermann("supertanker")


@pytest.mark.parametrize(
    ("kw", "match"),
    [({"CD_t": 0.0}, "CD_t"), ({"delta": 2.5}, "delta"), ({"kappa": math.nan}, "finite")],
)
def test_bad_coefficients(kw: dict[str, float], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        BlendermannCoefficients(**kw)


# --------------------------------------------------------------------------------------------
# Signs and magnitudes (Fossen 2011 ch. 8.1; Blendermann 1994)
# --------------------------------------------------------------------------------------------


def test_head_wind_pushes_astern() -> None:
    X, Y, N = WL(0.0, 0.0, 0.0, 3.0, 0.0)  # heading north, wind from north
    assert X < 0
    assert Y == pytest.approx(0.0, abs=1e-12)
    assert N == pytest.approx(0.0, abs=1e-12)
    # q CD_lAF(0) A_F = 0.5 * 1.225 * 9 * 0.9 * 1.9 (the project estimate "3 m/s head: X ~ -9 N")
    assert X == pytest.approx(-0.5 * 1.225 * 9.0 * 0.90 * 1.9, rel=1e-12)


def test_following_wind_pushes_ahead_without_side_force() -> None:
    X, Y, N = WL(0.0, 0.0, 0.0, 3.0, PI)  # wind from south
    assert X == pytest.approx(0.5 * 1.225 * 9.0 * 0.55 * 1.9, rel=1e-12)
    assert Y == 0.0 and N == 0.0  # exactly: no sign ambiguity at gamma = pi
    cx, cy, cn = blendermann_coefficients([PI, -PI, 3 * PI], windage=BLUE_LADY_WINDAGE)
    np.testing.assert_array_equal(cy, 0.0)
    np.testing.assert_array_equal(cn, 0.0)
    np.testing.assert_allclose(cx, 0.55)


def test_beam_wind_magnitudes_and_signs() -> None:
    # 3 m/s from starboard (east) on a ship heading north: pushed to port, stern to port.
    X, Y, N = WL(0.0, 0.0, 0.0, 3.0, PI / 2)
    assert Y < 0
    assert Y == pytest.approx(-24.7, rel=0.02)
    assert N == pytest.approx(27.2, rel=0.03)
    assert N > 0  # force to port at the aft centroid s_L < 0 turns the bow to starboard
    assert X == pytest.approx(0.0, abs=1e-12)
    # From port: mirror image.
    Xp, Yp, Np = WL(0.0, 0.0, 0.0, 3.0, -PI / 2)
    assert Yp > 0
    assert (Yp, Np) == pytest.approx((-Y, -N), rel=1e-12)
    # Exact value: q CD_t A_L and q CD_t (s_L / L_oa) A_L L_oa
    q = 0.5 * 1.225 * 9.0
    assert Y == pytest.approx(-q * 0.70 * 6.4, rel=1e-12)
    assert N == pytest.approx(q * 0.70 * 1.1 * 6.4, rel=1e-12)


def test_heading_rotates_the_wind() -> None:
    # Ship heading east, wind from east: head wind.
    X, Y, N = WL(PI / 2, 0.0, 0.0, 2.0, PI / 2)
    assert X < 0 and Y == pytest.approx(0.0, abs=1e-12)
    # Tomera (2014) trial: 3 m/s from 300 deg on a ship heading north -> wind on the port bow.
    X, Y, N = WL(0.0, 0.0, 0.0, 3.0, math.radians(300.0))
    assert X < 0 and Y > 0


def test_symmetry_of_coefficients() -> None:
    g = np.linspace(0.0, PI, 181)
    cx, cy, cn = blendermann_coefficients(g, windage=BLUE_LADY_WINDAGE)
    cxm, cym, cnm = blendermann_coefficients(-g, windage=BLUE_LADY_WINDAGE)
    np.testing.assert_allclose(cxm, cx, rtol=0, atol=1e-15)
    np.testing.assert_allclose(cym, -cy, rtol=0, atol=1e-15)
    np.testing.assert_allclose(cnm, -cn, rtol=0, atol=1e-15)
    assert cy[0] == 0.0 and cn[0] == 0.0
    assert np.all(cy[1:-1] > 0)  # gamma > 0: wind from port pushes to starboard
    # Wrapping: gamma + 2 pi gives the same coefficients.
    for a, b in zip(
        blendermann_coefficients(g + 2 * PI, windage=BLUE_LADY_WINDAGE), (cx, cy, cn), strict=True
    ):
        np.testing.assert_allclose(a, b, atol=1e-12)


def test_coefficients_match_the_unfolded_formula_on_starboard_side() -> None:
    # For gamma in [0, pi] the folded formula is Blendermann's (MSS blendermann94.m).
    w, k = BLUE_LADY_WINDAGE, blendermann("tanker-loaded")
    g = np.linspace(0.0, PI, 37)
    cd = np.where(g <= PI / 2, k.CD_lAF0, k.CD_lAFpi)
    den = 1 - 0.5 * k.delta * (1 - cd * w.A_F / w.A_L / k.CD_t) * np.sin(2 * g) ** 2
    cy = k.CD_t * np.sin(g) / den
    cn = (w.s_L / w.L_oa - 0.18 * (g - PI / 2)) * cy
    got = blendermann_coefficients(g, windage=BLUE_LADY_WINDAGE)
    for a, b in zip(got, (-cd * np.cos(g) / den, cy, cn), strict=True):
        np.testing.assert_allclose(a, b, atol=1e-14)


def test_load_matches_coefficients_and_fossen_relative_wind() -> None:
    rng = np.random.default_rng(3)
    psi, u, v = rng.uniform(-4, 4, 50), rng.uniform(-1, 1, 50), rng.uniform(-0.5, 0.5, 50)
    V, beta = rng.uniform(0, 6, 50), rng.uniform(-7, 7, 50)
    u_rw, v_rw, V_rw, gamma = relative_wind(psi, u, v, V, beta)
    np.testing.assert_allclose(u_rw, u - V * np.cos(beta - PI - psi))
    np.testing.assert_allclose(v_rw, v - V * np.sin(beta - PI - psi))
    cx, cy, cn = blendermann_coefficients(gamma, windage=BLUE_LADY_WINDAGE)
    q = 0.5 * 1.225 * V_rw**2
    w = BLUE_LADY_WINDAGE
    expect = np.stack([q * cx * w.A_F, q * cy * w.A_L, q * cn * w.A_L * w.L_oa], axis=-1)
    np.testing.assert_allclose(
        wind_load(psi, u, v, V, beta, windage=BLUE_LADY_WINDAGE), expect, rtol=1e-10, atol=1e-12
    )


def test_zero_relative_wind_gives_zero_load() -> None:
    # Ship heading north-east at 2 m/s, wind from south-west at 2 m/s: moving with the air.
    psi = math.radians(45.0)
    assert WL(psi, 2.0, 0.0, 2.0, psi + PI) == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    np.testing.assert_allclose(
        wind_load(psi, 2.0, 0.0, 2.0, psi + PI, windage=BLUE_LADY_WINDAGE), 0.0, atol=1e-12
    )
    assert WL(0.0, 0.0, 0.0, 0.0, 0.0) == (0.0, 0.0, 0.0)  # no wind at all: no NaN


def test_ship_moving_in_calm_air_feels_head_wind() -> None:
    u_rw, v_rw, V_rw, gamma = relative_wind(0.0, 1.0, 0.0, 0.0, 0.0)
    assert (float(u_rw), float(v_rw), float(V_rw), float(gamma)) == (1.0, 0.0, 1.0, 0.0)
    X, Y, N = WL(0.0, 1.0, 0.0, 0.0, 0.0)
    assert X == pytest.approx(WL(0.0, 0.0, 0.0, 1.0, 0.0)[0], rel=1e-12)  # = 1 m/s head wind
    assert X < 0


@pytest.mark.parametrize("shape", [(5,), (2, 4)])
def test_batch_shapes(shape: tuple[int, ...]) -> None:
    rng = np.random.default_rng(0)
    psi = rng.uniform(-PI, PI, shape)
    out = wind_load(psi, 0.3, 0.0, 3.0, rng.uniform(0, 2 * PI, shape), windage=BLUE_LADY_WINDAGE)
    assert out.shape == shape + (3,)
    cx, cy, cn = blendermann_coefficients(psi, windage=BLUE_LADY_WINDAGE)
    assert cx.shape == cy.shape == cn.shape == shape
    # Scalar inputs give shape (3,).
    assert wind_load(0.0, 0.0, 0.0, 3.0, 1.0, windage=BLUE_LADY_WINDAGE).shape == (3,)
    # Broadcasting across arguments.
    assert wind_load(
        np.zeros((2, 1)), 0.0, 0.0, np.ones(4), 1.0, windage=BLUE_LADY_WINDAGE
    ).shape == (2, 4, 3)


_f = st.floats


@settings(max_examples=200, deadline=None)
@given(
    psi=_f(-10, 10),
    u=_f(-3, 3),
    v=_f(-3, 3),
    V=_f(0, 20),
    beta=_f(-10, 10),
    name=st.sampled_from(sorted(BLENDERMANN)),
)
def test_scalar_path_equals_array_path(
    psi: float, u: float, v: float, V: float, beta: float, name: str
) -> None:
    wl = WindLoad(name, WindageParameters(A_F=1.7, A_L=6.0, s_L=0.4, L_oa=13.0, coefficients=name))
    scalar = wl(psi, u, v, V, beta)
    assert all(isinstance(x, float) for x in scalar)
    np.testing.assert_allclose(scalar, wl.array(psi, u, v, V, beta), rtol=1e-12, atol=1e-10)
    # NumPy scalars are accepted on the hot path as well.
    assert wl(np.float64(psi), u, v, V, np.float64(beta)) == scalar
    # the physics step's compiled law gives the same loads as the shared float path
    k = np.array(wl.kernel_constants())
    np.testing.assert_allclose(blendermann_load(k, psi, u, v, V, beta), scalar, rtol=1e-12,
                               atol=1e-10)  # fmt: skip
    np.testing.assert_allclose(blendermann_load(k, psi, u, v, 0.0, beta),
                               wl(psi, u, v, 0.0, beta), rtol=1e-12, atol=1e-10)  # fmt: skip


def test_kernel_at_zero_relative_wind_and_at_pi() -> None:
    kc = np.array(WL.kernel_constants())

    def k(*a: float) -> tuple[float, float, float]:
        return blendermann_load(kc, *a)

    assert k(0.3, 0.0, 0.0, 0.0, 1.0) == WL(0.3, 0.0, 0.0, 0.0, 1.0) == (0.0, 0.0, 0.0)
    for beta in (PI, 0.0, -PI / 2, PI / 2, 1e-300):  # following, head, beam winds
        np.testing.assert_allclose(k(0.0, 0.0, 0.0, 4.0, beta), WL(0.0, 0.0, 0.0, 4.0, beta),
                                   rtol=1e-12, atol=1e-10)  # fmt: skip


# --------------------------------------------------------------------------------------------
# Config
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"speed": -1.0}, "speed must be >= 0"),
        ({"speed": math.inf}, "finite"),
        ({"direction_from": math.nan}, "finite"),
        ({"gust_std": -0.1}, "gust_std must be >= 0"),
        ({"direction_std": -0.1}, "direction_std must be >= 0"),
        ({"gust_time_constant": 0.0}, "gust_time_constant must be > 0"),
        ({"direction_time_constant": -5.0}, "direction_time_constant must be > 0"),
        ({"sample_period": 0.0}, "sample_period must be > 0"),
        ({"coefficients": "supertanker"}, "valid names are"),
        ({"speed": "3"}, "real number"),
    ],
)
def test_bad_config_raises(kw: dict[str, object], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        WindConfig(**kw)  # type: ignore[arg-type]


def test_config_helpers() -> None:
    cfg = WindConfig.from_speed_dir(3.0, 300.0)
    assert cfg.direction_from == pytest.approx(math.radians(300.0))
    assert cfg.gust_sigma == pytest.approx(0.45)
    assert cfg.direction_std == pytest.approx(math.radians(10.0))
    assert WindConfig.from_speed_dir(2.0, 0.0, direction_std_deg=5.0).direction_std == (
        pytest.approx(math.radians(5.0))
    )
    assert WindConfig.from_dict({"speed": 2.0, "gust_std": 0.0}).gust_sigma == 0.0
    with pytest.raises(ValueError, match="unknown key"):
        WindConfig.from_dict({"speed": 2.0, "direction_deg": 30.0})
    assert WindConfig().is_constant  # calm
    assert WindConfig(speed=2.0, gust_std=0.0, direction_std=0.0).is_constant
    assert not WindConfig(speed=2.0).is_constant


# --------------------------------------------------------------------------------------------
# Gusts
# --------------------------------------------------------------------------------------------


def test_constant_wind_needs_no_rng() -> None:
    w = Wind(
        WindConfig(speed=2.0, direction_from=1.0, gust_std=0.0, direction_std=0.0),
        windage=BLUE_LADY_WINDAGE,
    )
    assert w.is_constant
    assert w.at(0.0) == (2.0, 1.0)
    w.reset()
    assert w.at(1234.5) == (2.0, 1.0)
    V, b = w.series(np.array([0.0, 10.0]))
    np.testing.assert_array_equal(V, 2.0)
    np.testing.assert_array_equal(b, 1.0)
    assert w.load(3.0, 0.0, 0.0, 0.0) == WL(0.0, 0.0, 0.0, 2.0, 1.0)


def test_gusty_wind_needs_rng() -> None:
    w = Wind(WindConfig(speed=3.0), windage=BLUE_LADY_WINDAGE)
    with pytest.raises(RuntimeError, match="reset"):
        w.at(1.0)
    with pytest.raises(ValueError, match="Generator"):
        w.reset(None)
    w.reset(np.random.default_rng(0))
    with pytest.raises(ValueError, match=">= 0"):
        w.at(-1.0)


def _cfg() -> WindConfig:
    return WindConfig(speed=3.0, direction_from=1.0)


def test_gust_statistics() -> None:
    cfg = _cfg()
    w = Wind(cfg, windage=BLUE_LADY_WINDAGE)
    w.reset(np.random.default_rng(12345))
    dt = cfg.sample_period
    n = int(2e5 / dt)
    t = np.arange(n) * dt
    V, beta = w.series(t)
    sV, sb = cfg.gust_sigma, cfg.direction_std
    assert V.mean() == pytest.approx(cfg.speed, rel=0.05)
    assert V.std() == pytest.approx(sV, rel=0.05)
    assert beta.mean() == pytest.approx(cfg.direction_from, abs=0.05 * sb)
    assert beta.std() == pytest.approx(sb, rel=0.05)
    for x, T in ((V, cfg.gust_time_constant), (beta, cfg.direction_time_constant)):
        lag = round(T / dt)
        y = x - x.mean()
        rho = float(np.dot(y[:-lag], y[lag:]) / np.dot(y, y))
        assert rho == pytest.approx(math.exp(-1.0), abs=0.03)
    # Grid-point values equal the samples; in between, linear interpolation.
    Vq, bq = w.at(10.05)
    assert Vq == pytest.approx(0.5 * (V[100] + V[101]), rel=1e-12)
    assert bq == pytest.approx(0.5 * (beta[100] + beta[101]), rel=1e-12)


def test_same_seed_same_gusts_different_seeds_differ() -> None:
    t = np.linspace(0.0, 900.0, 777)
    w1, w2, w3 = (
        Wind(_cfg(), windage=BLUE_LADY_WINDAGE),
        Wind(_cfg(), windage=BLUE_LADY_WINDAGE),
        Wind(_cfg(), windage=BLUE_LADY_WINDAGE),
    )
    w1.reset(np.random.default_rng(7))
    w2.reset(np.random.default_rng(7))
    w3.reset(np.random.default_rng(8))
    a, b, c = w1.series(t), w2.series(t), w3.series(t)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.allclose(a[0], c[0])
    # An integer seed is accepted, and a second reset with the same seed repeats the gusts.
    w1.reset(np.random.default_rng(7))
    np.testing.assert_array_equal(w1.series(t)[0], a[0])


def test_realisation_independent_of_query_order() -> None:
    ts = [0.037 * i for i in range(13515)]  # 0 .. 500 s, across chunk boundaries
    w1, w2 = Wind(_cfg(), windage=BLUE_LADY_WINDAGE), Wind(_cfg(), windage=BLUE_LADY_WINDAGE)
    w1.reset(np.random.default_rng(42))
    w2.reset(np.random.default_rng(42))
    in_order = [w1.at(t) for t in ts]
    w2.at(500.0)
    w2.at(60.0)
    shuffled = [w2.at(t) for t in ts]
    assert in_order == shuffled
    # series() gives exactly the values of at().
    V, beta = w2.series(np.array(ts))
    assert list(zip(V.tolist(), beta.tolist(), strict=True)) == in_order


def test_gust_chunks_are_the_gauss_markov_recursion() -> None:
    """Each chunk of a Gauss-Markov gust is ``x_{k+1} = a x_k + b e_k`` from the wind's child
    stream (written out here as the loop, compared bit for bit over two chunks), and ``at``
    reads them across the chunk boundary as ``series`` does."""
    from shipgym.disturbances._grid import CHUNK

    cfg = WindConfig(speed=3.0, direction_from=1.0, gust_std=0.6, direction_std=0.2)
    w = Wind(cfg, windage=BLUE_LADY_WINDAGE)
    w.reset(np.random.default_rng(5))
    w._extend_to(1)
    child = np.random.default_rng(int(np.random.default_rng(5).integers(2**63)))
    z = child.standard_normal(2)
    state = [w._sigma[0] * float(z[0]), w._sigma[1] * float(z[1])]
    for j in range(2):
        e = child.standard_normal((2, CHUNK)).tolist()
        for r, mean in enumerate((cfg.speed, cfg.direction_from)):
            x, a, b = state[r], w._a[r], w._b[r]
            row = [mean + x]
            for ek in e[r]:
                x = a * x + b * ek
                row.append(mean + x)
            state[r] = x
            assert w._chunks[j][r].tolist() == row
    assert list(w._state) == state
    ts = [0.0371 * i for i in range(30000)]  # across the chunk boundary at 409.6 s
    V, beta = w.series(np.array(ts))
    assert [w.at(t) for t in ts] == list(zip(np.maximum(V, 0.0).tolist(), beta.tolist(),
                                             strict=True))  # fmt: skip
    steady = WindConfig(speed=2.0, direction_from=0.5, gust_std=0.0, direction_std=0.0)
    calm = Wind(steady, windage=BLUE_LADY_WINDAGE)
    assert calm.at(12.0) == (2.0, 0.5)
    with pytest.raises(ValueError, match="time must be >= 0"):
        w.at(-1.0)


def test_speed_clipped_at_zero_and_load_uses_gusts() -> None:
    w = Wind(WindConfig(speed=0.2, gust_std=1.0, direction_std=0.0), windage=BLUE_LADY_WINDAGE)
    w.reset(np.random.default_rng(1))
    V, beta = w.series(np.arange(0.0, 300.0, 0.05))
    assert V.min() == 0.0  # the process does go negative and is clipped
    np.testing.assert_array_equal(beta, 0.0)
    t = 17.3
    Vt, bt = w.at(t)
    assert w.load(t, 0.2, 0.1, 0.0) == w.loads(0.2, 0.1, 0.0, Vt, bt)
