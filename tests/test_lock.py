"""The venv built by the Makefile holds exactly the versions of the lock files.

``make`` installs ``requirements/lock.txt`` (and ``requirements/lock-rl.txt`` for the rl
extra) and leaves a stamp per file in the venv (``.lock-core``, ``.lock-rl``); outside such a
venv this test is skipped.
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
LOCKS = {".lock-core": "requirements/lock.txt", ".lock-rl": "requirements/lock-rl.txt"}
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
    core, rl = (_pins(ROOT / p) for p in LOCKS.values())
    assert core and rl
    assert not set(core) & set(rl), "a package is locked twice"
    assert rl.get("torch") == "2.13.0"
    for name in (*core, *rl):
        assert not name.startswith("nvidia-") and name != "triton", name
    for name in ("numpy", "mujoco", "gymnasium", "pytest", "pip", "setuptools"):
        assert name in core, name
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
