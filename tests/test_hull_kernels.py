"""Every hull family's compiled acceleration kernel against the family's matrix form.

Each family (``fossen3``, ``linear4``, ``blanke4``, ``mmg``) has ONE Numba kernel of the
signature :data:`shipgym._jit.ACCEL_SIG`, ``accel(k, u, v, p, r, phi, X, Y, K, N, u_c, v_c)``,
with the constant vector of the plant's ``kernel_constants()``. The independent oracle is the
plant's ``nu_dot`` (linear solve of the matrix form). Checked for every plant variant of every
packaged vessel, plus a few variants built here for the branches the packages do not reach
(the ``fossen3`` options, a ``linear4`` hull without speed-dependent damping).
"""

from __future__ import annotations

import dataclasses
import math
import zlib

import numpy as np
import pytest

from shipgym._jit import ACCEL_SIG, kernel
from shipgym.dynamics.blanke4 import Blanke4Hull, accel_blanke4
from shipgym.dynamics.hull4 import Hull4, accel_linear4
from shipgym.dynamics.mmg import MMGHull, accel_mmg
from shipgym.dynamics.model import PlantModel, accel_fossen3
from shipgym.dynamics.vessel import load_vessel, vessel_names

FAMILIES = {
    "fossen3": (PlantModel, accel_fossen3, 3),
    "linear4": (Hull4, accel_linear4, 4),
    "blanke4": (Blanke4Hull, accel_blanke4, 4),
    "mmg": (MMGHull, accel_mmg, 3),
}
#: indices of switches (not coefficients) in a family's constant vector
FLAGS = {"linear4": (55,)}
N_STATES = 200
RTOL = 1e-9


def _cases() -> list[tuple[str, str]]:
    out = []
    for name in vessel_names():
        for variant, plant in load_vessel(name).plants.items():
            if hasattr(plant, "accel_kernel"):
                out.append((name, variant))
    # variants built here: the fossen3 default's options, a linear4 hull without D_u
    out += [("blue-lady", f"default:{opt}") for opt in
            ("coriolis", "quadratic_damping", "sway_yaw_coupling")]  # fmt: skip
    out += [("container-ship", "default:no-D_u"), ("van-der-klugt", "default:no-D_u")]
    return out


CASES = _cases()


def _plant(name: str, variant: str):  # type: ignore[no-untyped-def]
    v = load_vessel(name)
    base, _, option = variant.partition(":")
    if not option:
        return v.plant(base)
    if option == "no-D_u":
        return dataclasses.replace(v.plant(base), D_u=np.zeros((4, 4)))
    return v.plant(base, **{option: False})


def _states(name: str, plant, seed: int) -> tuple[np.ndarray, ...]:  # type: ignore[no-untyped-def]
    """Random states at the vessel's scale: ``(u, v, p, r, phi, X, Y, K, N, u_c, v_c)``,
    each (N_STATES,), the last four with zero velocity through the water."""
    v = load_vessel(name)
    L = v.L_pp
    U = v.approach_speed or 0.2 * math.sqrt(9.81 * L)  # Froude number about 0.2
    rng = np.random.default_rng(seed)
    n = N_STATES
    uni = lambda lo, hi: rng.uniform(lo, hi, n)  # noqa: E731
    u, vv = uni(-0.4 * U, 1.5 * U), uni(-0.3 * U, 0.3 * U)
    p, r, phi = uni(-0.1, 0.1), uni(-0.3, 0.3) * U / L, uni(-0.3, 0.3)
    uc, vc = uni(-1.0, 1.0), uni(-1.0, 1.0)
    u[-4:], vv[-4:] = uc[-4:], vc[-4:]  # at rest in the water (u_r = v_r = 0)
    M = np.diag(plant.mass_matrix())
    mt = M[0]  # the mass (kg), or the surge inertia of a per-unit model
    Mr = M[-1]
    X, Y = uni(-1, 1) * 0.01 * mt, uni(-1, 1) * 0.01 * mt
    K = uni(-1, 1) * 0.001 * (M[2] if len(M) == 4 else Mr)
    N = uni(-1, 1) * 0.001 * Mr
    return u, vv, p, r, phi, X, Y, K, N, uc, vc


def _run(f, k, s) -> np.ndarray:  # type: ignore[no-untyped-def]
    return np.array([f(k, *(float(x[i]) for x in s)) for i in range(len(s[0]))])


def _oracle(plant, s) -> np.ndarray:  # type: ignore[no-untyped-def]
    """``nu_dot`` of the matrix form as ``(u_dot, v_dot, p_dot, r_dot)`` rows."""
    u, v, p, r, phi, X, Y, K, N, uc, vc = s
    z = np.zeros_like(u)
    if FAMILIES[plant.family][2] == 4:
        return plant.nu_dot(np.stack([u, v, p, r], -1), np.stack([X, Y, K, N], -1),
                            np.stack([uc, vc], -1), phi)  # fmt: skip
    nd = plant.nu_dot(np.stack([u, v, r], -1), np.stack([X, Y, N], -1), np.stack([uc, vc, z], -1))
    return np.stack([nd[:, 0], nd[:, 1], z, nd[:, 2]], -1)


def _atol(want: np.ndarray) -> np.ndarray:
    """1e-12 of each component's acceleration scale (its largest magnitude in the sample)."""
    return 1e-12 * np.max(np.abs(want), axis=0)


def _close(got: np.ndarray, want: np.ndarray) -> bool:
    """The criterion of :func:`numpy.testing.assert_allclose` below, as a bool."""
    return bool(np.all(np.abs(got - want) <= _atol(want) + RTOL * np.abs(want)))


@pytest.fixture(scope="module")
def compiled():  # type: ignore[no-untyped-def]
    return {fam: kernel(f, ACCEL_SIG) for fam, (_, f, _) in FAMILIES.items()}


@pytest.mark.parametrize("name,variant", CASES, ids=[f"{n}/{v}" for n, v in CASES])
def test_the_kernel_is_the_matrix_form(name: str, variant: str, compiled) -> None:  # type: ignore[no-untyped-def]
    plant = _plant(name, variant)
    fam = plant.family
    cls, fn, dofs = FAMILIES[fam]
    assert isinstance(plant, cls) and type(plant).accel_kernel is fn
    assert getattr(plant, "dofs", 3) == dofs  # PlantModel: 3 DOF, no attribute
    f = compiled[fam]
    k = plant.kernel_constants()
    s = _states(name, plant, seed=zlib.crc32(f"{name}/{variant}".encode()))
    got, want = _run(f, k, s), _oracle(plant, s)
    assert np.all(np.isfinite(want))
    for j, atol in enumerate(_atol(want)):
        np.testing.assert_allclose(got[:, j], want[:, j], rtol=RTOL, atol=atol, err_msg=f"{j}")
    # the comparison can fail: 1 % on any coefficient the kernel uses shows
    for i in np.flatnonzero(k):
        if i in FLAGS.get(fam, ()):
            continue
        k2 = k.copy()
        k2[i] *= 1.01
        assert not _close(_run(f, k2, s), want), f"{name}/{variant}: k[{i}] changes nothing"
    if fam == "linear4":  # the D_u switch: off, the speed-dependent damping is gone
        k2 = k.copy()
        k2[55] = 0.0
        if np.any(np.asarray(plant.D_u) != 0.0):
            assert not _close(_run(f, k2, s), want)
        else:
            assert np.array_equal(_run(f, k2, s), got)


@pytest.mark.parametrize("name,variant", CASES, ids=[f"{n}/{v}" for n, v in CASES])
def test_the_kernel_is_pure_and_its_constants_are_a_fresh_float64_vector(
    name: str, variant: str, compiled
) -> None:  # type: ignore[no-untyped-def]
    plant = _plant(name, variant)
    f = compiled[plant.family]
    k = plant.kernel_constants()
    assert k.dtype == np.float64 and k.ndim == 1 and k.flags.c_contiguous
    assert np.all(np.isfinite(k))
    k_again = plant.kernel_constants()
    assert k_again is not k and np.array_equal(k_again, k)
    k_again[:] = np.nan  # a new array: the plant's next vector is unaffected
    assert np.array_equal(plant.kernel_constants(), k)
    kept = k.copy()
    s = _states(name, plant, seed=7)
    first, second = _run(f, k, s), _run(f, k, s)
    assert np.array_equal(first, second)
    assert np.array_equal(k, kept)  # the kernel does not write to its constants


CASES3 = [c for c in CASES if FAMILIES[_plant(*c).family][2] == 3]


@pytest.mark.parametrize("name,variant", CASES3, ids=[f"{n}/{v}" for n, v in CASES3])
def test_a_3dof_kernel_ignores_roll(name: str, variant: str, compiled) -> None:  # type: ignore[no-untyped-def]
    plant = _plant(name, variant)
    f = compiled[plant.family]
    k = plant.kernel_constants()
    u, v, p, r, phi, X, Y, K, N, uc, vc = _states(name, plant, seed=3)
    zero = np.zeros_like(u)
    with_roll = _run(f, k, (u, v, p, r, phi, X, Y, K, N, uc, vc))
    without = _run(f, k, (u, v, zero, r, zero, X, Y, zero, N, uc, vc))
    assert np.all(with_roll[:, 2] == 0.0)
    assert np.array_equal(with_roll, without)


def test_every_family_is_covered_by_a_packaged_vessel() -> None:
    seen = {_plant(n, v).family for n, v in CASES if ":" not in v}
    assert seen == set(FAMILIES)
    for fam, (cls, fn, _) in FAMILIES.items():
        assert cls.family == fam and cls.accel_kernel is fn
