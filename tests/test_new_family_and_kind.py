"""A hull family and an actuator kind written once, here, in a test file: registered, read
from a vessel package in a temporary folder, and stepped by the single physics (both
integrators) and the batched physics, against the SciPy oracle, without a change to any
package file.

- ``nomoto3``: a first-order (Nomoto-type) decoupled 3-DOF hull: each of surge, sway and yaw
  a first-order response ``m_i nu_dot_i + d_i nu_r,i + q_i |nu_r,i| nu_r,i = tau_i`` (time
  constant ``m_i / d_i``; Nomoto 1957's first-order steering model in yaw), chosen for the test;
- ``waterjet``: a waterjet with a steering nozzle: thrust ``F = F_max a`` (``a`` in [0, 1], a
  first-order lag) along the nozzle angle ``delta`` (a rate-limited servo, +-30 deg), at the
  jet's position.
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any, ClassVar

import numpy as np
import pytest
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import njit
from shipgym.disturbances import WindConfig
from shipgym.dynamics import simulate_reference, wrap_angle
from shipgym.dynamics.actuators import Actuator, Channel
from shipgym.dynamics.vessel import (
    ACTUATOR_READERS,
    COMMON_ACTUATOR_KEYS,
    HULL_FAMILIES,
    ActuatorSite,
    HullFamily,
    VesselReader,
    load_vessel,
    register_actuator_kind,
    register_hull_family,
)
from shipgym.envs.batchphysics import BatchedPhysics
from shipgym.envs.physics import VesselPhysics


# ---- the family ------------------------------------------------------------------------------
@njit
def accel_nomoto3(k, u, v, p, r, phi, X, Y, K, N, u_c, v_c):  # type: ignore[no-untyped-def]
    """``nu_dot`` of :class:`NomotoHull` with ``k = [m_u, m_v, I_r, d_u, d_v, d_r, q_u]``."""
    ur = u - u_c
    vr = v - v_c
    return (
        (X - k[3] * ur - k[6] * abs(ur) * ur) / k[0],
        (Y - k[4] * vr) / k[1],
        0.0,
        (N - k[5] * r) / k[2],
    )


@dataclass(frozen=True)
class NomotoHull:
    """The ``nomoto3`` hull (module docstring); masses kg, kg m^2; damping N s/m, N m s."""

    family: ClassVar[str] = "nomoto3"
    dofs: ClassVar[int] = 3
    accel_kernel = staticmethod(accel_nomoto3)
    m_u: float
    m_v: float
    I_r: float
    d_u: float
    d_v: float
    d_r: float
    q_u: float = 0.0
    name: str = "default"

    def kernel_constants(self) -> NDArray[np.float64]:
        return np.array([self.m_u, self.m_v, self.I_r, self.d_u, self.d_v, self.d_r, self.q_u])

    def mass_matrix(self) -> NDArray[np.float64]:
        return np.diag([self.m_u, self.m_v, self.I_r])

    def nu_dot(self, nu: ArrayLike, tau: ArrayLike, nu_c: ArrayLike | None = None) -> Any:
        """The matrix form: ``M^-1 (tau - D nu_r - q |u_r| u_r)`` (the oracle's)."""
        nu = np.asarray(nu, dtype=float)
        nu_r = nu - (np.zeros(3) if nu_c is None else np.asarray(nu_c, dtype=float))
        nu_r = np.concatenate([nu_r[..., :2], nu[..., 2:]], -1)
        damp = nu_r * [self.d_u, self.d_v, self.d_r]
        damp[..., 0] += self.q_u * np.abs(nu_r[..., 0]) * nu_r[..., 0]
        return (np.asarray(tau, dtype=float) - damp) / [self.m_u, self.m_v, self.I_r]


_HULL_KEYS = {"m_u": "kg", "m_v": "kg", "I_r": "kg m^2", "d_u": "N s/m", "d_v": "N s/m",
              "d_r": "N m s", "q_u": "N s^2/m^2", "m": "kg", "I_z": "kg m^2", "L_oa": "m",
              "L_pp": "m", "B": "m", "T": "m"}  # fmt: skip


def read_nomoto3(
    r: VesselReader, data: Mapping[str, Any], t: Mapping[str, Any]
) -> tuple[Any, dict[str, Any]]:
    r.keys(t, "hull", {"family", *_HULL_KEYS})
    v = {k: r.number(t, k, "hull", u, positive=k != "q_u") for k, u in _HULL_KEYS.items()}
    dims = SimpleNamespace(**{k: v[k] for k in ("m", "I_z", "L_oa", "L_pp", "B", "T")})
    hull = NomotoHull(*(v[k] for k in ("m_u", "m_v", "I_r", "d_u", "d_v", "d_r", "q_u")))
    return dims, {"default": hull}


# ---- the kind --------------------------------------------------------------------------------
@njit
def law_waterjet(row, st, u, v, p, r):  # type: ignore[no-untyped-def]
    """``row = [channel, F_max (N), x, y, z (m)]``; states ``[a, delta]``."""
    j = int(row[0])
    f = row[1] * st[j]
    fx = f * math.cos(st[j + 1])
    fy = f * math.sin(st[j + 1])
    return fx, fy, -row[4] * fy, row[2] * fy - row[3] * fx, f, 0.0


@dataclass(frozen=True)
class Waterjet(Actuator):
    """The ``waterjet`` kind (module docstring)."""

    kind: ClassVar[str] = "waterjet"
    force_law: ClassVar[Any] = staticmethod(law_waterjet)
    name: str = ""
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    max_thrust_n: float = 1.0
    time_constant: float = 1.0
    max_angle: float = math.radians(30.0)
    max_rate: float = math.radians(20.0)
    colour: str = "#2ca02c"

    @property
    def channels(self) -> tuple[Channel, ...]:
        return (
            Channel(self.name, "1", 0.0, 1.0, "lag", self.time_constant),
            Channel(self.name + "_nozzle", "rad", -self.max_angle, self.max_angle, "servo", 0.0,
                    rate=self.max_rate),
        )  # fmt: skip

    def law_row(self, channel: int) -> tuple[float, ...]:
        return (float(channel), self.max_thrust_n, *self.position)

    def thrust(self, states: NDArray[np.float64]) -> Any:
        return self.max_thrust_n * np.asarray(states, dtype=float)[..., 0]

    def force(self, states: NDArray[np.float64]) -> tuple[Any, Any]:
        s = np.asarray(states, dtype=float)
        f = self.max_thrust_n * s[..., 0]
        return f * np.cos(s[..., 1]), f * np.sin(s[..., 1])

    @property
    def max_thrust(self) -> float:
        return self.max_thrust_n


def read_waterjet(r: VesselReader, t: Mapping[str, Any], site: ActuatorSite) -> Waterjet:
    w = site.where
    r.keys(t, w, COMMON_ACTUATOR_KEYS | {"max_thrust", "max_angle_deg", "max_rate_deg"})
    return Waterjet(
        name=site.name, position=site.position, colour=site.colour,
        max_thrust_n=r.number(t, "max_thrust", w, "N", positive=True),
        time_constant=r.number(t, "time_constant", w, "s", positive=True),
        max_angle=math.radians(r.number(t, "max_angle_deg", w, "deg", positive=True)),
        max_rate=math.radians(r.number(t, "max_rate_deg", w, "deg/s", positive=True)),
    )  # fmt: skip


VESSEL_TOML = """
[vessel]
name = "jet-boat"
title = "a waterjet boat of a first-order hull (test)"
dofs = 3
scale = { value = 1.0, unit = "1", source = "chosen" }
nominal_wind = { value = 8.0, unit = "m/s", source = "chosen" }

[hull]
family = "nomoto3"
m_u = { value = 2.2e5, unit = "kg", source = "chosen" }
m_v = { value = 3.5e5, unit = "kg", source = "chosen" }
I_r = { value = 9.0e7, unit = "kg m^2", source = "chosen" }
d_u = { value = 8.0e3, unit = "N s/m", source = "chosen" }
d_v = { value = 6.0e4, unit = "N s/m", source = "chosen" }
d_r = { value = 4.0e7, unit = "N m s", source = "chosen" }
q_u = { value = 2.0e3, unit = "N s^2/m^2", source = "chosen" }
m = { value = 2.0e5, unit = "kg", source = "chosen" }
I_z = { value = 6.0e7, unit = "kg m^2", source = "chosen" }
L_oa = { value = 40.0, unit = "m", source = "chosen" }
L_pp = { value = 38.0, unit = "m", source = "chosen" }
B = { value = 9.0, unit = "m", source = "chosen" }
T = { value = 2.0, unit = "m", source = "chosen" }

[design]
source = "the hull's linear part"
M = [[2.2e5, 0.0, 0.0], [0.0, 3.5e5, 0.0], [0.0, 0.0, 9.0e7]]
D_L = [[8.0e3, 0.0, 0.0], [0.0, 6.0e4, 0.0], [0.0, 0.0, 4.0e7]]

[windage]
A_F = { value = 40.0, unit = "m^2", source = "chosen" }
A_L = { value = 160.0, unit = "m^2", source = "chosen" }
s_L = { value = 0.0, unit = "m", source = "chosen" }
L_oa = { value = 40.0, unit = "m", source = "chosen" }
rho_a = { value = 1.225, unit = "kg/m^3", source = "ISA" }
coefficients = { value = "ferry", source = "Blendermann (1994) ship type" }

[[actuator]]
name = "jet_port"
kind = "waterjet"
position = { value = [-19.0, -2.0, 1.0], unit = "m", source = "chosen" }
time_constant = { value = 2.0, unit = "s", source = "chosen" }
max_thrust = { value = 6.0e4, unit = "N", source = "chosen" }
max_angle_deg = { value = 30.0, unit = "deg", source = "chosen" }
max_rate_deg = { value = 20.0, unit = "deg/s", source = "chosen" }

[[actuator]]
name = "jet_stbd"
kind = "waterjet"
position = { value = [-19.0, 2.0, 1.0], unit = "m", source = "chosen" }
time_constant = { value = 2.0, unit = "s", source = "chosen" }
max_thrust = { value = 6.0e4, unit = "N", source = "chosen" }
max_angle_deg = { value = 30.0, unit = "deg", source = "chosen" }
max_rate_deg = { value = 20.0, unit = "deg/s", source = "chosen" }
"""


@pytest.fixture
def jet_boat(tmp_path: Path) -> Iterator[Path]:
    """The package in a temporary folder, its family and kind registered for the test."""
    register_hull_family("nomoto3", HullFamily(3, read_nomoto3))
    register_actuator_kind("waterjet", read_waterjet)
    folder = tmp_path / "jet_boat"
    folder.mkdir()
    (folder / "vessel.toml").write_text(VESSEL_TOML)
    src = load_vessel("wimpey-sealab").folder  # any hull geometry will do
    shutil.copy(src / "vessel.xml", folder / "vessel.xml")
    try:
        yield folder
    finally:
        HULL_FAMILIES.pop("nomoto3", None)
        ACTUATOR_READERS.pop("waterjet", None)


GUSTY = WindConfig(speed=8.0, direction_from=math.radians(300.0), sample_period=1.0)


def _commands(acts: Any, k: int, seed: int) -> NDArray[np.float64]:
    rng = np.random.default_rng(seed)
    a = np.clip(rng.normal(0.3, 0.7, (k, acts.n_channels)), -1.3, 1.3)
    return np.clip(acts.action_to_command(np.clip(a, -1, 1)) * 1.2, acts.lower * 1.2,
                   acts.upper * 1.2)  # fmt: skip


def test_the_package_reads_with_its_family_and_kind(jet_boat: Path) -> None:
    v = load_vessel(jet_boat)
    assert isinstance(v.plant(), NomotoHull) and v.dofs == 3
    assert [type(a) for a in v.actuators] == [Waterjet, Waterjet]
    assert v.actuators.channel_names == ("jet_port", "jet_port_nozzle", "jet_stbd",
                                         "jet_stbd_nozzle")  # fmt: skip


def test_unregistered_family_is_named(tmp_path: Path) -> None:
    folder = tmp_path / "jet_boat"
    folder.mkdir()
    (folder / "vessel.toml").write_text(VESSEL_TOML)
    with pytest.raises(ValueError, match="unknown hull family 'nomoto3'"):
        load_vessel(folder)


@pytest.mark.parametrize("integrator", ["mujoco", "leapfrog"])
def test_single_physics_matches_the_scipy_oracle(jet_boat: Path, integrator: str) -> None:
    """300 s, saturating commands every 10 s, gusty wind: the compiled loop with this file's
    family and kind against SciPy's integration of their matrix forms."""
    phys = VesselPhysics(jet_boat, wind=GUSTY, integrator=integrator)
    acts = phys.actuators
    ct = np.arange(0.0, 300.0, 10.0)
    cmds = _commands(acts, ct.size, seed=1)
    phys.reset()
    traj = [phys.eta]
    for c in cmds:
        phys.set_command(c)
        for _ in range(10):
            phys.step(20)
            traj.append(phys.eta)
    traj = np.array(traj)
    t_eval = np.arange(traj.shape[0]) * 1.0

    def env_load(t: float, eta: Any, nu: Any) -> Any:
        return phys.wind.load(t, eta[2], nu[0], nu[1])

    ref = simulate_reference(phys.plant, t_eval, ct, cmds, actuators=acts,
                             act0=phys.initial_actuator_state(), env_load=env_load,
                             breakpoints=np.arange(0.0, 300.0, GUSTY.sample_period))  # fmt: skip
    dist = np.sum(np.hypot(*np.diff(ref.eta[:, :2], axis=0).T))
    pos = np.max(np.hypot(*(traj[:, :2] - ref.eta[:, :2]).T))
    ang = np.degrees(np.max(np.abs(wrap_angle(traj[:, 2] - ref.eta[:, 2]))))
    assert dist > 50.0  # the jets moved the boat
    assert pos <= 1e-4 * dist and ang <= 0.01, (pos, dist, ang)


def test_batched_hull_is_the_single_leapfrog_physics(jet_boat: Path) -> None:
    bp = BatchedPhysics(jet_boat, 3, wind=GUSTY)
    bp.reset(rngs=[np.random.default_rng(10 + i) for i in range(3)])
    single = VesselPhysics(jet_boat, wind=GUSTY, integrator="leapfrog")
    single.reset(rng=np.random.default_rng(12))
    for c in _commands(bp.actuators, 10, seed=2):
        cmd = np.stack([c, 0.5 * c, -c])
        bp.set_command(cmd)
        single.set_command(cmd[2])
        bp.step(100)
        single.step(100)
        np.testing.assert_array_equal(single.eta, bp.eta[2])
        np.testing.assert_array_equal(single.actuator_state, bp.actuator_state[2])
    assert not np.array_equal(bp.eta[0], bp.eta[2])
