"""The suite's own configuration (tests/conftest.py): slow-test selection, Hypothesis profile."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import conftest
import test_fuzz
from hypothesis import settings

ROOT = Path(__file__).resolve().parents[1]
ONE_SLOW = "tests/test_fuzz.py::test_random_episodes_stay_finite_and_bounded[0]"


def test_hypothesis_profile_follows_the_ci_variable() -> None:
    explicit = os.environ.get("HYPOTHESIS_PROFILE")
    assert conftest.PROFILE == (explicit or ("ci" if conftest._truthy("CI") else "dev"))
    assert settings.default.derandomize is (conftest.PROFILE == "ci")
    assert settings.default.deadline is None  # no wall-clock assertion in either profile


def test_truthy_reads_ci_values() -> None:
    os.environ["SHIPGYM_TEST_FLAG"] = "true"
    try:
        assert conftest._truthy("SHIPGYM_TEST_FLAG")
        for off in ("", "0", "false", "No"):
            os.environ["SHIPGYM_TEST_FLAG"] = off
            assert not conftest._truthy("SHIPGYM_TEST_FLAG")
    finally:
        del os.environ["SHIPGYM_TEST_FLAG"]


def test_slow_tests_are_skipped_unless_selected() -> None:
    env = {k: v for k, v in os.environ.items() if k != "SHIPGYM_SLOW"}
    run = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider", ONE_SLOW],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert run.returncode == 0, run.stdout + run.stderr
    assert "1 skipped" in run.stdout and "make test-slow" in run.stdout, run.stdout
    # selected with -m slow: collected, not skipped (--collect-only: nothing runs)
    run = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-m", "slow", "--collect-only",
         "-p", "no:cacheprovider", "tests/test_fuzz.py"],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert run.returncode == 0, run.stdout + run.stderr
    slow = test_fuzz.CHUNKS + len(test_fuzz.CASES)  # the fuzz chunks, every id x vessel
    assert re.search(rf"(^|\s){slow}(/\d+)? tests collected", run.stdout), run.stdout
