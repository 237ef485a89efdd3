"""The venv built by the Makefile holds exactly the versions of the lock files.

``make`` installs ``requirements/lock.txt`` (core), ``lock-dev.txt`` (test and dev extras)
``lock-rl.txt`` (rl extra) and ``lock-ray.txt`` (ray extra) as far as a target needs them,
and leaves a stamp per file in the venv (``.lock-core``, ``.lock-dev``, ``.lock-rl``,
``.lock-ray``); outside such a venv the comparison is skipped.
"""

from __future__ import annotations

import re
import sys
from importlib import metadata
from pathlib import Path

import pytest
from packaging.specifiers import SpecifierSet
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[1]
LOCKS = {
    ".lock-core": "requirements/lock.txt",
    ".lock-dev": "requirements/lock-dev.txt",
    ".lock-rl": "requirements/lock-rl.txt",
    ".lock-ray": "requirements/lock-ray.txt",
}
_PIN = re.compile(r"^([A-Za-z0-9][A-Za-z0-9._-]*)==(\S+)$")


def _pins(path: Path) -> dict[str, str]:
    pins = {}
    for line in path.read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        m = _PIN.match(line)
        assert m, f"{path.name}: not an exact pin 'name==version': {line!r}"
        pins[canonicalize_name(m[1])] = m[2]
    return pins


def test_lock_files_are_exact_pins_without_cuda_packages() -> None:
    core, dev, rl, ray = (_pins(ROOT / p) for p in LOCKS.values())
    assert core and dev and rl and ray
    names = [*core, *dev, *rl]
    assert len(names) == len(set(names)), "a package is locked twice"
    assert not set(ray) & (set(core) | set(dev)), "the ray lock repeats a core or dev pin"
    clash = {n: (rl[n], ray[n]) for n in set(rl) & set(ray) if rl[n] != ray[n]}
    assert not clash, f"the rl and ray extras lock different versions: {clash}"
    assert "ray" in ray
    assert rl.get("torch") == "2.13.0"
    for name in names:
        assert not name.startswith("nvidia-") and name != "triton", name
    for name in ("numpy", "mujoco", "gymnasium", "rerun-sdk", "pip", "setuptools"):
        assert name in core, name
    for name in ("pytest", "hypothesis", "control", "ruff", "pytest-random-order", "pytest-xdist"):
        assert name in dev, name
    assert "stable-baselines3" in rl


@pytest.mark.parametrize("stamp", list(LOCKS))
def test_installed_versions_equal_the_lock(stamp: str) -> None:
    if not (Path(sys.prefix) / stamp).exists():
        pytest.skip(
            f"not a venv built by the Makefile from {LOCKS[stamp]} "
            f"(no {stamp} stamp in {sys.prefix}): run make test"
        )
    wrong = []
    for name, version in _pins(ROOT / LOCKS[stamp]).items():
        try:
            got = metadata.version(name)
        except metadata.PackageNotFoundError:
            wrong.append(f"{name}: locked {version}, not installed")
            continue
        # ==2.13.0 matches a local build such as 2.13.0+cpu, as it does for pip
        if got not in SpecifierSet(f"=={version}"):
            wrong.append(f"{name}: locked {version}, installed {got}")
    assert not wrong, f"the venv differs from {LOCKS[stamp]} (run make): " + "; ".join(wrong)


@pytest.mark.parametrize("lock", sorted(LOCKS.values()))
def test_lock_is_from_the_committed_pyproject(lock: str) -> None:
    """``make lock`` writes pyproject.toml's sha256 into every header: a pyproject changed
    without a new lock fails here."""
    import hashlib

    want = hashlib.sha256((ROOT / "pyproject.toml").read_bytes()).hexdigest()[:16]
    text = (ROOT / lock).read_text()
    m = re.search(r"^# From pyproject.toml with sha256 ([0-9a-f]{16})", text, re.M)
    assert m is not None, f"{lock} has no pyproject hash: run make lock"
    assert m.group(1) == want, f"{lock} is older than pyproject.toml: run make lock"
