"""The vessel library: packages, validation, the MuJoCo model built from them, physics parity.

Parity: every packaged vessel and a 4-DOF hull (written here as a user package) under
time-varying, saturating commands and gusty wind against an independent SciPy integration
(``simulate_reference``: the matrix form of the hull and the vectorised actuator laws).
"""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from shipgym.disturbances import WaveConfig, WindConfig
from shipgym.dynamics import simulate_reference, wrap_angle
from shipgym.dynamics.actuators import Azimuth
from shipgym.dynamics.mmg import MMGHull
from shipgym.dynamics.vessel import VesselError, load_vessel, vessel_names, vessels
from shipgym.envs.physics import VesselPhysics
from shipgym.envs.scene import build_model

VESSELS = vessel_names()
INTEGRATORS = ("mujoco", "leapfrog")
GUSTY = WindConfig(speed=3.0, direction_from=math.radians(300.0), sample_period=1.0)

# A linear 4-DOF hull (surge, sway, roll, yaw) of the Van der Klugt (1987) family: sway-roll
# and sway-yaw coupled added mass and damping, roll restoring K_phi = rho g nabla GM; the
# numbers are chosen for a 80 m, 2000 t ship (roll period 11 s, 10 % roll damping).
HULL4_TOML = """
[vessel]
name = "test-hull4"
title = "4-DOF test hull"
dofs = 4
nominal_wind = 8.0

[hull]
family = "linear4"
M = [[2.1e6, 0, 0, 0], [0, 3.0e6, -2.0e6, 5.0e6], [0, -2.0e6, 6.0e7, 0], [0, 5.0e6, 0, 1.0e9]]
D_L = [[5.0e4, 0, 0, 0], [0, 3.0e5, 1.0e5, -2.0e5], [0, 1.0e5, 6.9e6, 0], [0, -4.0e5, 0, 2.0e7]]
K_phi = { value = 1.96e7, unit = "N m/rad", source = "rho g nabla GM, GM = 1 m" }
d_quad = [0, 1.0e4, 0, 1.0e7]
m = 2.0e6
I_x = 4.0e7
I_z = 8.0e8
L_oa = 80.0
L_pp = 76.0
B = 12.0
T = 4.0

[design]
M = [[2.1e6, 0, 0], [0, 3.0e6, 5.0e6], [0, 5.0e6, 1.0e9]]
D_L = [[5.0e4, 0, 0], [0, 3.0e5, -2.0e5], [0, -4.0e5, 2.0e7]]

[windage]
A_F = 150.0
A_L = 500.0
s_L = 0.0
L_oa = 80.0
coefficients = "research"

[limits]
surge_speed = 0.5
surge_accel = 0.01
surge_astern_speed = 0.3
surge_astern_accel = 0.008
sway_speed = 0.2
sway_accel = 0.004
yaw_rate = 0.0087
yaw_accel = 2.0e-4

[[actuator]]
name = "propeller"
kind = "propeller"
position = [-36.0, 0.0, 3.0]
law = "quadratic"
unit = "rpm"
k = 2.0
range = [-150.0, 300.0]
time_constant = 3.0

[[actuator]]
name = "bow_tunnel"
kind = "tunnel"
position = [30.0, 0.0, 3.5]
k = 6.0e4
time_constant = 1.5

[[actuator]]
name = "stern_azimuth"
kind = "azimuth"
position = [-30.0, 0.0, 5.0]
max_thrust = 8.0e4
time_constant = 2.0
max_rate_deg = 8.0
angle0_deg = 30.0
"""

HULL_XML = """<mujoco model="box_hull">
  <worldbody>
    <body name="hull">
      <geom name="hull" type="box" size="40 6 3" mass="0" contype="1" conaffinity="2"/>
    </body>
  </worldbody>
</mujoco>
"""


def write_package(folder: Path, toml: str, xml: str = HULL_XML) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "vessel.toml").write_text(toml)
    (folder / "vessel.xml").write_text(xml)
    return folder


@pytest.fixture(scope="module")
def hull4(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_package(tmp_path_factory.mktemp("pkg") / "hull4", HULL4_TOML)


# ---- packages ------------------------------------------------------------------------------
def test_packaged_vessels_are_listed_and_load() -> None:
    assert {"blue-lady", "star-hercules", "wimpey-sealab"} <= set(VESSELS)
    vs = vessels()
    assert set(vs) == set(VESSELS)
    for name, v in vs.items():
        assert v.name == name and v.folder.is_dir() and (v.folder / "README.md").is_file()
        assert v.plant("default").mass_matrix().shape == (v.dofs, v.dofs)


@pytest.mark.parametrize("name", VESSELS)
def test_model_built_from_the_vessel_file(name: str) -> None:
    """Channels, sites and inertia of the MuJoCo model come from the vessel file (its
    actuators name the channels: the physics applies their forces and dynamics)."""
    v = load_vessel(name)
    m = build_model(v)
    acts = v.actuators
    assert m.nu == acts.n_channels and m.na == 0 and m.nv == v.dofs
    for i, ch in enumerate(acts.channels):
        assert m.actuator(i).name == ch.name
        assert m.actuator_gainprm[i, 0] == 0.0
    for a in acts:
        np.testing.assert_array_equal(m.site(a.name).pos, a.position)
    assert m.body("hull").mass[0] == v.rigid_inertia[0]


def test_blue_lady_layout_is_the_papers() -> None:
    """Tomera (2014) eq. 12: T = [[1, 0, 0], [0, 1, 1], [0, L2, -L3]], ranges and constants."""
    acts = load_vessel("blue-lady").actuators
    np.testing.assert_array_equal(
        acts.configuration_matrix(), [[1, 0, 0], [0, 1, 1], [0, 3.24, -2.376]]
    )
    np.testing.assert_allclose(acts.thrust([480.0, 1.0, -1.0]), [451.33056, 44.145, -44.145])


def test_star_hercules_and_wimpey_numbers() -> None:
    """SI values against the per-unit model of Al-Takie (1982) (bis system, App. 1)."""
    g = 9.81
    for name, m, L, mii, damp in (
        ("star-hercules", 4.377e6, 73.0, (1.033, 1.709, 0.1042),
         (0.01088, 0.03307, -0.00221, -0.004344, 0.003272)),
        ("wimpey-sealab", 5.670e6, 94.49, (1.044, 1.84, 0.1022),
         (0.01593, 0.1004, -0.002981, -0.005859, 0.007101)),
    ):  # fmt: skip
        v = load_vessel(name)
        M = v.plant().mass_matrix()
        np.testing.assert_allclose(np.diag(M), np.array(mii) * [m, m, m * L * L], rtol=5e-4)
        D = np.asarray(v.plant().D_L)
        x_u, y_v, y_r, n_v, n_r = damp
        s, r = math.sqrt(g / L), math.sqrt(g * L)
        np.testing.assert_allclose(
            [D[0, 0], D[1, 1], D[1, 2], D[2, 1], D[2, 2]],
            [x_u * m * s, y_v * m * s, y_r * m * r, n_v * m * r, n_r * m * L * r], rtol=5e-4,
        )  # fmt: skip
        np.testing.assert_allclose(v.design.M, M, rtol=1e-4)
    sh = load_vessel("star-hercules").actuators
    np.testing.assert_allclose(sh.thrust([1, 1, 1, 1]), [274.7e3, 50e3, 89.3e3, 50e3])
    np.testing.assert_allclose(sh.thrust([-1, -1, -1, -1]), [-186.4e3, -50e3, -89.3e3, -50e3])
    ws = load_vessel("wimpey-sealab").actuators
    assert all(isinstance(a, Azimuth) and a.max_thrust == 122.6e3 for a in ws)
    assert [c.time_constant for c in ws.channels[::2]] == [2.0] * 4


def test_user_package_outside_the_assets_runs_in_an_env(tmp_path: Path) -> None:
    import gymnasium as gym

    pkg = write_package(tmp_path / "my_ship", HULL4_TOML)
    env = gym.make("shipgym/StationKeeping-v0", vessel=str(pkg))
    obs, info = env.reset(seed=0)
    assert env.action_space.shape == (4,) and "phi" in info
    for _ in range(5):
        obs, r, term, trunc, info = env.step(env.action_space.sample())
    assert np.isfinite(obs).all() and np.isfinite(info["phi"])
    env.close()


# ---- validation: one test per error ----------------------------------------------------------
BL_TOML = (Path(__file__).parents[1] / "shipgym/assets/mjcf/blue_lady/vessel.toml").read_text()


def _bad(tmp_path: Path, toml: str, xml: str | None = None) -> str:
    src = Path(__file__).parents[1] / "shipgym/assets/mjcf/blue_lady/vessel.xml"
    pkg = write_package(tmp_path / "bad", toml, xml or src.read_text())
    with pytest.raises(VesselError) as exc:
        v = load_vessel(pkg)
        build_model(v)
    return str(exc.value)


def test_unknown_key_is_named(tmp_path: Path) -> None:
    msg = _bad(tmp_path, BL_TOML.replace("[hull]\n", "[hull]\nmass_kg = 3\n", 1))
    assert "hull.mass_kg" in msg and "unknown key" in msg and "valid keys" in msg


def test_missing_value_is_named(tmp_path: Path) -> None:
    toml = re.sub(r"\nY_vdot = [^\n]*", "", BL_TOML, count=1)
    assert "hull.Y_vdot: missing value" in _bad(tmp_path, toml)


def test_missing_limits_are_derived_from_the_capacity(tmp_path: Path) -> None:
    """Limits the file leaves out come from the capacity (shipgym.guidance.limits), those it
    gives are kept; a bad one is named."""
    from shipgym.guidance.limits import vessel_limits

    src = Path(__file__).parents[1] / "shipgym/assets/mjcf/blue_lady/vessel.xml"
    toml = re.sub(r"\nyaw_accel = [^\n]*", "", BL_TOML, count=1)
    v = load_vessel(write_package(tmp_path / "a", toml, src.read_text()))
    lim = vessel_limits(v)
    cap = v.actuators.capacity()
    assert lim.yaw_accel == pytest.approx(cap[2] / (6 * v.design.M[2, 2]))
    assert lim.surge_speed == 0.2  # given in the file
    toml = re.sub(r"\n\[limits\]\n(?:[a-z_]+ = [^\n]*\n)+", "\n", BL_TOML, count=1)
    lim = vessel_limits(load_vessel(write_package(tmp_path / "b", toml, src.read_text())))
    assert lim.surge_speed == pytest.approx(0.2)  # the Froude-scaled Blue Lady speed, lambda 1
    bad = BL_TOML.replace("yaw_accel = { value = 9e-5", "yaw_accel = { value = -9e-5", 1)
    assert "limits.yaw_accel: must be > 0" in _bad(tmp_path, bad)


def test_non_positive_mass_is_named(tmp_path: Path) -> None:
    toml = BL_TOML.replace("m = { value = 22934.4", "m = { value = -1.0", 1)
    assert "hull.m: must be > 0" in _bad(tmp_path, toml)


def test_singular_mass_matrix_is_named(tmp_path: Path) -> None:
    # Y_rdot so large that M_22 M_33 - M_23 M_32 = 0: the sway-yaw block is singular
    m22 = 22934.4 + 18962.0  # m - Y_vdot of the [hull]
    c = -math.sqrt(m22 * 455182.1)
    toml = BL_TOML.replace("Y_rdot = { value = -18351.9", f"Y_rdot = {{ value = {c!r}", 1)
    toml = toml.replace("N_vdot = { value = -18351.9", f"N_vdot = {{ value = {c!r}", 1)
    msg = _bad(tmp_path, toml)
    assert "singular" in msg and ": hull: " in msg  # the [hull], not a plant variant


def test_actuator_outside_the_hull_is_named(tmp_path: Path) -> None:
    toml = BL_TOML.replace("value = [3.24, 0.0, 0.5]", "value = [30.0, 0.0, 0.5]", 1)
    msg = _bad(tmp_path, toml)
    assert "actuator.bow_tunnel.position" in msg and "outside the hull" in msg


def test_wrong_unit_is_named(tmp_path: Path) -> None:
    toml = BL_TOML.replace('value = 455182.1, unit = "kg m^2"', 'value = 455182.1, unit = "t m^2"')
    assert "hull.I_z: unit must be 'kg m^2'" in _bad(tmp_path, toml)


def test_unknown_actuator_kind_is_named(tmp_path: Path) -> None:
    toml = BL_TOML.replace('kind = "tunnel"', 'kind = "waterjet"', 1)
    assert "actuator.bow_tunnel.kind: unknown actuator kind 'waterjet'" in _bad(tmp_path, toml)


def test_hull_body_without_joints_is_required(tmp_path: Path) -> None:
    xml = HULL_XML.replace('<body name="hull">', '<body name="hull"><joint name="j"/>')
    assert "must have no joints" in _bad(tmp_path, HULL4_TOML, xml)


def test_unknown_vessel_lists_the_packaged_ones() -> None:
    with pytest.raises(VesselError, match="blue-lady"):
        load_vessel("titanic")


# ---- physics parity -----------------------------------------------------------------------
def _commands(acts, duration: float, period: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Time-varying, saturating commands in every channel (actions beyond +-1 are clipped)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, period)
    n = acts.n_channels
    phase = rng.uniform(0, 2 * np.pi, n)
    per = rng.uniform(80.0, 250.0, n)
    a = 1.3 * np.sin(2 * np.pi * t[:, None] / per + phase) + 0.3 * rng.standard_normal((t.size, n))
    return t, acts.action_to_command(np.clip(a, -1.0, 1.0)) * np.where(np.abs(a) > 1, 1.2, 1.0)


def _parity(vessel, plant=None, timestep: float = 0.05, duration: float = 600.0,
            integrators: tuple[str, ...] = ("mujoco",), sea: bool = False):  # fmt: skip
    """The physics with each of ``integrators`` against one run of the SciPy oracle (the
    same vessel, commands and gusts): ``{integrator: (pos_err, ang_err, dist)}``; ``sea``: a
    constant current (0.3 m/s at full scale) and the wave drift (Hs 2.5 m, Tp 8 s at full
    scale) besides the gusts."""
    v = load_vessel(vessel)
    s = float(v.scale)
    # the wave drift of a sea is in newtons: not on a hull written per unit inertia
    waves = (WaveConfig(Hs=2.5 / s, Tp=8.0 / math.sqrt(s), direction_from=math.radians(210.0))
             if sea and v.hull.m != 1.0 else None)  # fmt: skip
    current = (0.3 / math.sqrt(s), math.radians(60.0)) if sea else (0.0, 0.0)
    flow = f"{current[0]:.17g}@{math.degrees(current[1]):.17g}"
    trajs, gusts, phys = {}, [], None
    for integrator in integrators:
        phys = VesselPhysics(v, plant or "default", wind=GUSTY, timestep=timestep,
                             integrator=integrator, waves=waves, current=flow)  # fmt: skip
        acts = phys.actuators
        ct, cmds = _commands(acts, duration, 10.0, seed=1)
        act0 = phys.initial_actuator_state()
        nu0 = np.zeros(phys.dofs)
        if isinstance(phys.plant, MMGHull):
            # a manoeuvring model (not valid at low speed): from its approach speed, the
            # propeller between 70 % and 100 % of the self-propulsion point, the rudder anywhere
            U0 = phys.vessel.trials["approach_speed"]
            n0 = phys.plant.model.self_propulsion(U0)
            nu0[0] = U0
            act0[0] = n0
            cmds[:, 0] = n0 * (0.85 + 0.15 * np.clip(cmds[:, 0] / acts.upper[0], -1.0, 1.0))
        phys.reset(nu=nu0, actuators=act0)
        n_cmd = round(10.0 / timestep)
        traj = [phys.eta_full]
        for k in range(ct.size):
            phys.set_command(cmds[k])
            for _ in range(round(n_cmd / 10)):
                phys.step(10)
                traj.append(phys.eta_full)
        trajs[integrator] = np.array(traj)
        gusts.append(phys.wind.series(np.arange(0.0, duration, 0.37)))
    for g in gusts[1:]:  # every integrator's physics had the oracle's gusts
        np.testing.assert_array_equal(g, gusts[0])
    t_eval = np.arange(trajs[integrators[0]].shape[0]) * 10 * timestep
    four = phys.dofs == 4

    def env_load(t, eta, nu):
        psi = eta[3] if four else eta[2]
        load = np.array(phys.wind.load(t, psi, nu[0], nu[1]))
        return load + phys.waves.drift_load(t, psi) if waves is not None else load

    grid = [np.arange(0.0, duration, GUSTY.sample_period)]
    if waves is not None:  # the drift energy is linear between its samples
        grid.append(np.arange(0.0, duration, 1.0 / phys.waves.sample_rate))
    ref = simulate_reference(
        phys.plant, t_eval, ct, cmds, actuators=acts, act0=act0, nu0=nu0, env_load=env_load,
        current=current, breakpoints=np.unique(np.concatenate(grid)),
    )  # fmt: skip
    dist = np.sum(np.hypot(*np.diff(ref.eta[:, :2], axis=0).T))
    out = {}
    for integrator, traj in trajs.items():
        pos_err = np.max(np.hypot(*(traj[:, :2] - ref.eta[:, :2]).T))
        ang_err = np.degrees(np.max(np.abs(wrap_angle(traj[:, 2:] - ref.eta[:, 2:]))))
        out[integrator] = pos_err, ang_err, dist
    return out


@pytest.mark.parametrize("name", [*VESSELS, "hull4"])
def test_parity_with_scipy_reference(name: str, hull4: Path) -> None:
    """600 s, saturating time-varying commands, gusty wind, with each integrator against one
    oracle run (the batched physics is the leapfrog one, bit for bit: test_batchphysics):
    <= 0.01 % of the distance, 0.01 deg."""
    vessel = hull4 if name == "hull4" else name
    for integrator, (pos, ang, dist) in _parity(vessel, integrators=INTEGRATORS).items():
        assert dist > 20.0  # the commands move the hull
        assert pos <= 1e-4 * dist and ang <= 0.01, (integrator, pos, dist, ang)


@pytest.mark.slow
@pytest.mark.parametrize("name", VESSELS)
def test_parity_in_a_sea(name: str) -> None:
    """As above with a current and the wave drift besides the gusts (slow: the oracle stops
    at every sample of the drift): <= 0.01 % of the distance, 0.05 deg (the heading error of
    the 0.05 s step grows in a sea, to 0.02 deg for Star Hercules; it falls with h^2,
    test_parity_error_falls_with_the_timestep)."""
    for integrator, (pos, ang, dist) in _parity(name, integrators=INTEGRATORS, sea=True).items():
        assert dist > 20.0
        assert pos <= 1e-4 * dist and ang <= 0.05, (integrator, pos, dist, ang)


@pytest.mark.parametrize("name", ["wimpey-sealab", "hull4"])
def test_parity_error_falls_with_the_timestep(name: str, hull4: Path) -> None:
    vessel = hull4 if name == "hull4" else name
    coarse = _parity(vessel, timestep=0.1, duration=300.0)["mujoco"]
    fine = _parity(vessel, timestep=0.025, duration=300.0)["mujoco"]
    assert fine[0] < 0.5 * coarse[0] and fine[1] < 0.5 * coarse[1] + 1e-9, (coarse, fine)


def test_four_dof_hull_rolls_under_a_tunnel_thruster(hull4: Path) -> None:
    """A bow tunnel below the CG heels the ship: steady roll K / K_phi = z F / K_phi."""
    phys = VesselPhysics(hull4, wind=None)
    phys.reset()
    cmd = np.zeros(phys.actuators.n_channels)
    cmd[1] = 1.0  # bow tunnel, full to starboard (60 kN at z = 3.5 m below the CG)
    phys.set_command(cmd)
    phys.step(round(3.0 / phys.timestep))
    assert phys.phi < 0.0  # starboard force below the CG: the ship heels to port at first


def test_vessel_package_can_be_copied_and_edited(tmp_path: Path) -> None:
    """A copy of a packaged vessel is a user package; edits take effect when reloaded."""
    src = load_vessel("star-hercules").folder
    dst = tmp_path / "sh2"
    shutil.copytree(src, dst)
    toml = (dst / "vessel.toml").read_text().replace('name = "star-hercules"', 'name = "sh2"')
    (dst / "vessel.toml").write_text(toml)
    v = load_vessel(dst)
    assert v.name == "sh2" and v.folder == dst.resolve()


def test_a_changed_timestep_is_picked_up_by_the_half_step() -> None:
    """model.opt.timestep changed after construction: the leapfrog half step follows it."""
    a = VesselPhysics("blue-lady", wind=GUSTY, timestep=0.02)
    b = VesselPhysics("blue-lady", wind=GUSTY, timestep=0.05)
    b.model.opt.timestep = 0.02
    for p in (a, b):
        p.reset(nu=[0.3, 0.05, 0.01])
        p.set_command([300.0, 0.5, -0.5])
        p.step(500)
    np.testing.assert_array_equal(a.eta, b.eta)
    np.testing.assert_array_equal(a.nu, b.nu)


@pytest.mark.parametrize("name", VESSELS)
def test_package_files_scene_and_readme_cover_every_number(name: str) -> None:
    """Menagerie layout: the scene compiles; the README lists every value that has a source."""
    import mujoco

    v = load_vessel(name)
    m = mujoco.MjModel.from_xml_path(str(v.folder / "scene.xml"))
    assert m.nbody >= 2
    readme = (v.folder / "README.md").read_text()
    missing = [k for k in v.sources if f"`{k}`" not in readme]
    assert not missing, f"{name}: README.md lacks {missing}"
    assert len(v.sources) >= 30  # the hull, windage and actuator numbers carry sources
