"""The package metadata in pyproject.toml is fit for PyPI and ships every asset.

Read with tomllib, no build: the supported Pythons are declared (classifiers and
requires-python), the rl extra gives torch a range (the lock pins it), the description and
authors are today's, and ``[tool.setuptools.package-data]`` has no pattern that matches nothing
and leaves no data file of the package out of the wheel. ``make dist`` builds and checks the
wheel itself, ``make dist-check`` installs it on each Python.
"""

from __future__ import annotations

import importlib.util
import re
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.specifiers import SpecifierSet
from packaging.version import Version

ROOT = Path(__file__).resolve().parents[1]
PYTHONS = ("3.11", "3.12", "3.13")


@pytest.fixture(scope="module")
def project() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]


@pytest.fixture(scope="module")
def package_data() -> dict[str, list[str]]:
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    return pyproject["tool"]["setuptools"]["package-data"]


def test_classifiers_declare_the_supported_pythons(project: dict) -> None:
    classifiers = project.get("classifiers", [])
    declared = {
        c.rsplit(" :: ", 1)[1]
        for c in classifiers
        if re.fullmatch(r"Programming Language :: Python :: 3\.\d+", c)
    }
    assert declared == set(PYTHONS), f"Python classifiers {sorted(declared)}, want {PYTHONS}"
    assert len(classifiers) == len(set(classifiers)), "a classifier twice"


def test_requires_python_is_311_and_newer(project: dict) -> None:
    spec = SpecifierSet(project["requires-python"])
    for v in PYTHONS:
        assert spec.contains(v), f"requires-python {spec} excludes {v}"
    assert not spec.contains("3.10"), f"requires-python {spec} admits 3.10"
    assert ">=3.11" in project["requires-python"].replace(" ", "")


def test_license_is_an_spdx_expression_without_a_license_classifier(project: dict) -> None:
    """PEP 639: setuptools refuses a ``License ::`` classifier next to a license
    expression, so the build would fail with one."""
    assert project["license"] == "MIT"
    assert not [c for c in project.get("classifiers", []) if c.startswith("License ::")]
    for pattern in project.get("license-files", []):
        assert list(ROOT.glob(pattern)), f"license-files {pattern!r} matches no file"


def test_typed_classifier_only_where_py_typed_ships(project: dict, package_data) -> None:
    typed = "Typing :: Typed" in project.get("classifiers", [])
    ships = "py.typed" in package_data.get("shipgym", []) and (ROOT / "shipgym/py.typed").is_file()
    assert typed == ships, f"Typing :: Typed classifier {typed}, py.typed shipped {ships}"


def test_rl_extra_gives_torch_a_range_that_holds_the_locked_pin(project: dict) -> None:
    rl = [Requirement(r) for r in project["optional-dependencies"]["rl"]]
    (torch,) = [r for r in rl if r.name == "torch"]
    ops = {s.operator for s in torch.specifier}
    assert not ops & {"==", "==="}, f"the rl extra pins torch ({torch}); give it a range"
    assert ">=" in ops and "<" in ops, f"torch{torch.specifier}: want a lower and upper bound"
    lock = (ROOT / "requirements/lock-rl.txt").read_text()
    (pin,) = re.findall(r"^torch==(\S+)$", lock, re.M)
    assert Version(pin) in torch.specifier, f"the locked torch {pin} is outside {torch}"


def test_description_is_todays(project: dict) -> None:
    """One line that names more than the Blue Lady's 3-DOF harbour manoeuvre."""
    text = project["description"]
    assert "\n" not in text and len(text) <= 512, "PyPI's summary: one line, <= 512 characters"
    low = text.lower()
    for topic in ("4-dof", "roll", "offshore", "sea trial", "vector", "kalman"):
        assert topic in low, f"the description does not mention {topic!r}: {text!r}"


def test_authors_and_keywords_as_in_citation(project: dict) -> None:
    import yaml

    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert [a["name"] for a in project.get("authors", [])] == [a["name"] for a in cff["authors"]]
    assert project.get("version") == str(cff["version"])
    assert len(project.get("keywords", [])) >= 5


def test_every_package_data_pattern_matches_a_file(package_data) -> None:
    dead = [
        f"{package}: {pattern}"
        for package, patterns in package_data.items()
        for pattern in patterns
        if not any(p.is_file() for p in (ROOT / package.replace(".", "/")).glob(pattern))
    ]
    assert not dead, f"package-data patterns that match no file: {dead}"


def test_every_data_file_of_the_package_is_package_data(package_data) -> None:
    """Each file git tracks under ``shipgym/`` other than a module (without git: each on
    disk) is matched by a pattern, so the wheel carries it (the same files as
    tools/wheel_assets.py checks in the built wheel: its ``tree_assets``)."""
    spec = importlib.util.spec_from_file_location(
        "wheel_assets", ROOT / "tools" / "wheel_assets.py"
    )
    assert spec is not None and spec.loader is not None
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    data = tool.tree_assets()
    assert data, "no data files tracked under shipgym/"
    matched = {
        p.relative_to(ROOT).as_posix()
        for pattern in package_data.get("shipgym", [])
        for p in (ROOT / "shipgym").glob(pattern)
    }
    left_out = sorted(data - matched)
    assert not left_out, f"data files no package-data pattern ships: {left_out}"
