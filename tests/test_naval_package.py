"""The naval vessel package (``shipgym/assets/mjcf/naval_vessel``) and the ``blanke4`` family.

The package is loaded as shipped (its rudder of the kind ``rudder`` included); the tests of
bad packages edit a copy (``tmp_path``).
"""

from __future__ import annotations

import dataclasses
import math
import re
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pytest

from shipgym.dynamics.blanke4 import NAVAL_VESSEL, Blanke4Hull, linear_roll_model
from shipgym.dynamics.vessel import VesselError, load_vessel

PKG = Path(__file__).resolve().parents[1] / "shipgym" / "assets" / "mjcf" / "naval_vessel"


def _copy(tmp_path: Path, text: str | None = None) -> Path:
    dst = tmp_path / "naval_vessel"
    shutil.copytree(PKG, dst)
    if text is not None:
        (dst / "vessel.toml").write_text(text)
    return dst


@pytest.fixture
def naval():
    return load_vessel(PKG)


def test_the_package_loads_as_the_published_hull(naval):
    assert naval.name == "naval-vessel" and naval.dofs == 4
    hull = naval.plant("default")
    assert isinstance(hull, Blanke4Hull)
    for f in dataclasses.fields(Blanke4Hull):
        if f.init and f.name not in ("name", "source"):
            assert getattr(hull, f.name) == pytest.approx(getattr(NAVAL_VESSEL, f.name), rel=1e-12)
    assert naval.dimensions == (55.0, 51.5, 8.6, 2.3)
    assert naval.rigid_inertia == pytest.approx((1014.0 * 357.0, 2.3763e6, 47.934e6))
    assert list(naval.actuators.names) == ["propeller", "rudder"]
    assert naval.rudders == ("rudder",) and naval.roll_control["design_speed"] == 8.0
    assert naval.sources["hull.K_p"][0] == "N m s"
    assert "navalvessel.m" in naval.sources["hull.N_rar"][1]


def test_design_model_is_the_hull_linearised_at_8_m_s(naval):
    # independent: the printed derivatives of navalvessel.m by hand
    m, U, xg = 1014.0 * 357.0, 8.0, -3.38
    M = [[m + 17400.0, 0, 0], [0, m + 393000.0, m * xg + 1.4e6], [0, m * xg - 538000.0,
         47.934e6 + 38.7e6]]  # fmt: skip
    D = [[2 * 1960.0 * U, 0, 0], [0, 11800.0 * U, -(131000.0 - m) * U],
         [0, 92000.0 * U, -(-4.71e6 - m * xg) * U]]  # fmt: skip
    np.testing.assert_allclose(naval.design.M, M, rtol=1e-9)
    np.testing.assert_allclose(naval.design.D_L, D, rtol=1e-9)
    # and the sway-yaw part of the 5-state linear model is -M^-1 D_L of it (phi = p = 0)
    A, _, _ = linear_roll_model(naval.plant(), U, -25.75, 1.55, 1.0)
    hull_M = naval.plant().mass_matrix()[1:, 1:]
    D3 = np.zeros((3, 3))  # rows v, p, r; columns v, p, r
    D3[0, [0, 2]] = np.asarray(D)[1, 1:]
    D3[2, [0, 2]] = np.asarray(D)[2, 1:]
    D3[1] = [-9260.0 * U, 500000.0 + 15500.0 * U, -(-102000.0 + m * -1.06) * U]
    acc = -np.linalg.solve(hull_M, D3)
    np.testing.assert_allclose(A[[0, 1, 3]][:, [0, 3, 1]], acc[[0, 2, 1]], rtol=1e-9)


def test_the_real_toml_has_the_rudder_in_the_agreed_format():
    data = tomllib.loads((PKG / "vessel.toml").read_text())
    rud = [a for a in data["actuator"] if a["name"] == "rudder"]
    assert len(rud) == 1
    r = rud[0]
    assert r["kind"] == "rudder"
    assert r["position"]["value"] == [-51.5 / 2, 0.0, 1.55] and r["position"]["unit"] == "m"
    assert r["area"]["value"] == 1.5
    assert r["lift_slope"]["value"] == pytest.approx(0.054 * 180.0 / math.pi, rel=1e-3)
    assert r["rho"]["value"] == 1014.0 and r["stall_angle_deg"]["value"] == 23.0
    assert r["max_angle_deg"]["value"] == 35.0 and r["max_rate_deg"]["value"] == 10.0
    prop = [a for a in data["actuator"] if a["name"] == "propeller"][0]
    # full thrust holds about 11 m/s against X_uau U^2 (navalvessel.m: -1.96e3)
    assert math.sqrt(prop["k"]["value"] / 1960.0) > 10.0
    assert prop["time_constant"]["value"] == 2.0


def test_readme_lists_every_sourced_number(naval):
    readme = (PKG / "README.md").read_text()
    missing = [k for k in naval.sources if f"`{k}`" not in readme]
    assert not missing
    for k in ("position", "area", "lift_slope", "stall_angle_deg", "max_rate_deg"):
        assert f"`actuator.rudder.{k}`" in readme
    assert len(naval.sources) >= 60


def test_bad_blanke4_packages_raise_naming_the_key(tmp_path: Path):
    text = (PKG / "vessel.toml").read_text()
    cases = [
        (text.replace('family = "blanke4"', 'family = "blanke4"\nY_vv = 1.0'), "hull.Y_vv"),
        (text.replace("dofs = 4", "dofs = 3"), "4-DOF family"),
        (re.sub(r"(?m)^m = .*$", "m = 3.0e5", text), "hull.m"),
        (re.sub(r"(?m)^K_p = .*$", "", text), "hull.K_p: missing"),
        (
            re.sub(
                r"(?m)^K_p = \{ value = -500000.0, unit = \"N m s\"",
                'K_p = { value = -5e5, unit = "N m"',
                text,
            ),
            "unit must be",
        ),  # fmt: skip
        (re.sub(r"(?m)^I_xx = \{ value = 2376300.0", "I_xx = { value = -1.0", text), "I_xx"),
    ]
    for i, (bad, word) in enumerate(cases):
        d = tmp_path / f"case{i}"
        d.mkdir()
        pkg = _copy(d, bad)
        with pytest.raises(VesselError, match=re.escape(word)):
            load_vessel(pkg)
