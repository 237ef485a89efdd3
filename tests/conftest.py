"""Test-suite configuration: slow-test selection and the Hypothesis profiles.

* Tests marked ``@pytest.mark.slow`` are skipped unless selected: ``pytest -m slow`` (``make
  test-slow``), a ``-m`` expression naming ``slow``, or ``SHIPGYM_SLOW=1`` (with all the rest).
* Hypothesis: with the environment variable ``CI`` set (``.ci/run`` sets ``CI=true``) the ``ci``
  profile is loaded: derandomised (the same examples on every run, so a CI result does not
  depend on luck), no example database, no deadline, and a reproduction blob printed on failure.
  Otherwise the ``dev`` profile: random examples and the example database, no deadline either
  (a deadline is a wall-clock assertion, and no test asserts one). ``HYPOTHESIS_PROFILE=ci``
  (or ``dev``) picks a profile explicitly.
"""

from __future__ import annotations

import os

import pytest
from hypothesis import settings

settings.register_profile("ci", derandomize=True, database=None, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None, print_blob=True)


def _truthy(name: str) -> bool:
    return os.environ.get(name, "").strip().lower() not in ("", "0", "false", "no")


PROFILE = os.environ.get("HYPOTHESIS_PROFILE") or ("ci" if _truthy("CI") else "dev")
settings.load_profile(PROFILE)


def pytest_report_header(config: pytest.Config) -> str:
    return f"shipgym: hypothesis profile {PROFILE!r}"


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if _truthy("SHIPGYM_SLOW") or "slow" in (config.getoption("markexpr") or ""):
        return
    skip = pytest.mark.skip(reason="slow test: run with -m slow (make test-slow) or SHIPGYM_SLOW=1")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)
