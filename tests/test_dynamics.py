"""The pure-NumPy model: frames, parameter validation, matrix form vs expanded kernel."""

import dataclasses

import numpy as np
import pytest
from _helpers import accel_of
from hypothesis import given, settings
from hypothesis import strategies as st

from shipgym._config import describe, from_mapping
from shipgym.dynamics import (
    BLUE_LADY_HULL,
    BLUE_LADY_THRUSTERS,
    HullParameters,
    PlantModel,
    configuration_matrix,
    inverse_thrust,
    plant_model,
    rot,
    saturate,
    thrust,
    wrap_angle,
)

finite = st.floats(-1.0, 1.0, allow_nan=False)


def test_wrap_angle_interval_and_batch():
    a = np.array([0.0, np.pi, -np.pi, 3 * np.pi, 2 * np.pi - 1e-3, -7.0])
    w = wrap_angle(a)
    assert np.all(w > -np.pi) and np.all(w <= np.pi)
    np.testing.assert_allclose(np.cos(w), np.cos(a), atol=1e-12)
    assert wrap_angle(np.radians(350) - np.radians(10)) == pytest.approx(np.radians(-20))
    assert isinstance(wrap_angle(1.0), float)


def test_wrap_angle_numpy_scalar_is_the_array_formula_bitwise():
    """A NumPy float64 takes a plain-float path that must give exactly the array formula
    ``pi - mod(pi - a, 2 pi)`` (NumPy's remainder), not the Python-float formula (which
    differs in the last bit for many angles)."""
    rng = np.random.default_rng(3)
    k = np.arange(-40, 41)
    a = np.concatenate([
        rng.uniform(-10.0, 10.0, 20000), rng.uniform(-1e6, 1e6, 2000),
        rng.normal(0.0, 1e-12, 500), k * np.pi, k * 2.0 * np.pi,
        np.nextafter(k * np.pi, np.inf), np.nextafter(k * np.pi, -np.inf),
        [0.0, -0.0, 5e-324, -5e-324, 1e300, -1e300],
    ])  # fmt: skip
    ref = np.pi - np.mod(np.pi - a, 2.0 * np.pi)
    got = np.array([wrap_angle(x) for x in a])  # iterating an array gives np.float64
    assert all(type(wrap_angle(x)) is float for x in a[:10])
    assert np.array_equal(got, ref) and np.array_equal(np.signbit(got), np.signbit(ref))
    # the Python-float formula differs for some of these angles: the fast path is not it
    plain = np.array([wrap_angle(float(x)) for x in a])
    assert not np.array_equal(plain, ref)
    with np.errstate(invalid="ignore"):  # non-finite angles take the array path (NaN)
        assert all(np.isnan(wrap_angle(np.float64(x))) for x in (np.inf, np.nan))


def test_rot_is_orthonormal_and_batched():
    psi = np.linspace(-4, 4, 7).reshape(7)
    R = rot(psi)
    assert R.shape == (7, 3, 3)
    np.testing.assert_allclose(
        R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape), atol=1e-12
    )
    # heading 90 deg: forward (body x) points east (NED y)
    np.testing.assert_allclose(rot(np.pi / 2) @ [1, 0, 0], [0, 1, 0], atol=1e-12)


def test_seed_linear_is_exactly_eqs_49_50():
    p = plant_model("seed-linear", hull=BLUE_LADY_HULL)
    np.testing.assert_array_equal(p.mass_matrix(), np.diag([23664.9, 24830.6, 455182.1]))
    np.testing.assert_array_equal(
        np.asarray(p.D_L), [[21.1, 0, 0], [0, 259.8, -855.4], [0, -855.4, 6130.5]]
    )
    nu = np.array([0.3, -0.2, 0.01])
    np.testing.assert_array_equal(p.coriolis_rb(nu), 0)
    np.testing.assert_array_equal(p.coriolis_a(nu), 0)
    np.testing.assert_array_equal(p.damping(nu), np.asarray(p.D_L))


def test_default_plant_mass_matrix_from_table_2():
    """Table 2 with its Y_vdot read as -18 962 kg (a decimal place lost; the vessel README's
    hull evidence): M22 = m + 18 962, not eq. 49's 24 830.6 (= m + 1 896.2, the literal
    reading, the 'table2-literal' plant of the vessel package)."""
    M = plant_model(hull=BLUE_LADY_HULL).mass_matrix()
    assert M[0, 0] == pytest.approx(23664.9)
    assert M[1, 1] == pytest.approx(22934.4 + 18962.0)
    assert M[2, 2] == pytest.approx(455182.1)
    assert M[1, 2] == pytest.approx(18351.9) and M[2, 1] == pytest.approx(18351.9)


def test_coriolis_matrices_are_skew_symmetric():
    p = plant_model(hull=BLUE_LADY_HULL)
    nu = np.random.default_rng(0).normal(size=(20, 3))
    for C in (p.coriolis_rb(nu), p.coriolis_a(nu)):
        np.testing.assert_allclose(C, -np.swapaxes(C, -1, -2), atol=1e-9)
        # a skew-symmetric C does no work: nu^T C nu = 0
        np.testing.assert_allclose(np.einsum("ni,nij,nj->n", nu, C, nu), 0, atol=1e-6)


@settings(max_examples=200, deadline=None)
@given(
    st.tuples(finite, finite, finite),
    st.tuples(finite, finite, finite),
    st.tuples(finite, finite),
    st.sampled_from(["default", "seed-linear"]),
)
def test_kernel_equals_matrix_form(nu, tau, cur, name):
    p = plant_model(name, hull=BLUE_LADY_HULL)
    nu = np.array(nu) * [1.0, 0.5, 0.05]
    tau = np.array(tau) * [400.0, 80.0, 250.0]
    nu_c = np.array([cur[0] * 0.2, cur[1] * 0.2, 0.0])
    a = p.nu_dot(nu, tau, nu_c)
    b = accel_of(p)(*nu, *tau, nu_c[0], nu_c[1])
    np.testing.assert_allclose(b, a, rtol=1e-10, atol=1e-14)


def test_current_and_ship_moving_together_feel_no_hydrodynamic_force():
    # nu = nu_c and no rotation: nu_r = 0, so no damping and no acceleration
    p = plant_model(hull=BLUE_LADY_HULL)
    np.testing.assert_allclose(p.nu_dot([0.1, 0.05, 0.0], [0, 0, 0], [0.1, 0.05, 0]), 0, atol=1e-15)


def test_switchable_terms():
    nu = np.array([0.5, 0.2, 0.01])
    off = plant_model("default", coriolis=False, quadratic_damping=False, hull=BLUE_LADY_HULL)
    np.testing.assert_array_equal(off.coriolis_rb(nu), 0)
    np.testing.assert_array_equal(off.damping(nu), np.asarray(off.D_L))
    nc = plant_model("default", sway_yaw_coupling=False, hull=BLUE_LADY_HULL)
    assert nc.mass_matrix()[1, 2] == 0


def test_bad_parameters_raise_clear_errors():
    with pytest.raises(ValueError, match="m must be > 0"):
        dataclasses.replace(BLUE_LADY_HULL, m=-1.0)
    with pytest.raises(ValueError, match="I_z must be > 0"):
        dataclasses.replace(BLUE_LADY_HULL, I_z=0.0)
    with pytest.raises(ValueError, match="T_main must be > 0"):
        dataclasses.replace(BLUE_LADY_THRUSTERS, T_main=-2.0)
    with pytest.raises(ValueError, match="finite"):
        dataclasses.replace(BLUE_LADY_HULL, X_u=float("nan"))
    with pytest.raises(ValueError, match="unknown plant variant 'linear'.*default, seed-linear"):
        plant_model("linear", hull=BLUE_LADY_HULL)
    with pytest.raises(ValueError, match="unknown plant option"):
        plant_model("default", coriolis_terms=False, hull=BLUE_LADY_HULL)
    with pytest.raises(ValueError, match="singular"):
        M_A = [[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        PlantModel("bad", np.zeros((3, 3)), M_A, np.eye(3), coriolis=False)
    with pytest.raises(ValueError, match="unknown key.*valid keys"):
        from_mapping(HullParameters, {"mass": 1.0})


def test_every_parameter_has_unit_and_source():
    """The records' fields carry their units; the Blue Lady's values their sources (its
    vessel package, which BLUE_LADY_HULL and BLUE_LADY_THRUSTERS equal)."""
    from shipgym.dynamics.vessel import load_vessel

    for obj in (BLUE_LADY_HULL, BLUE_LADY_THRUSTERS):
        for name, _, unit, _ in describe(obj):
            assert unit, f"{type(obj).__name__}.{name} lacks a unit"
    v = load_vessel("blue-lady")
    for name, *_ in describe(BLUE_LADY_HULL):
        if name != "name":
            unit, source = v.sources[f"hull.{name}"]
            assert unit and source, f"hull.{name} lacks unit or source"
    for a in ("main_propeller", "bow_tunnel", "stern_tunnel"):
        for key in ("position", "k", "range", "time_constant"):
            unit, source = v.sources[f"actuator.{a}.{key}"]
            assert unit and source, f"actuator.{a}.{key} lacks unit or source"


def test_thruster_model_and_inverse():
    p = BLUE_LADY_THRUSTERS
    F = thrust([480.0, 1.0, -1.0], p)
    np.testing.assert_allclose(F, [1.9589e-3 * 480**2, 44.145, -44.145])
    assert thrust([-200.0, 0, 0], p)[0] == pytest.approx(-1.9589e-3 * 200**2)
    cmds = np.array([[300.0, 0.5, -0.2], [-150.0, -1.0, 1.0]])
    np.testing.assert_allclose(inverse_thrust(thrust(cmds, p), p), cmds)
    T = configuration_matrix(p)
    np.testing.assert_allclose(T, [[1, 0, 0], [0, 1, 1], [0, 3.24, -2.376]])
    clipped, flags = saturate([1000.0, 2.0, -0.5], p)
    np.testing.assert_array_equal(clipped, [480.0, 1.0, -0.5])
    np.testing.assert_array_equal(flags, [True, True, False])
    with pytest.raises(ValueError, match="NaN or infinite"):
        saturate([np.nan, 0, 0], p)
    with pytest.raises(ValueError, match="shape"):
        saturate([1.0, 2.0], p)


def test_parameter_sets_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        BLUE_LADY_HULL.m = 1.0  # type: ignore[misc]
