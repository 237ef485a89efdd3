"""Every Python snippet of the README runs as written, each in a fresh process (the slow
training one under ``make test-slow``)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)


def _slow(code: str) -> bool:
    return ".learn(" in code  # a training run


@pytest.mark.parametrize(
    "code",
    [pytest.param(b, marks=pytest.mark.slow) if _slow(b) else b for b in BLOCKS],
    ids=[f"snippet{i}" for i in range(len(BLOCKS))],
)
def test_readme_snippet_runs(code, tmp_path):
    if "torch" in code or "stable_baselines3" in code:
        pytest.importorskip("stable_baselines3", reason="the rl extra is not installed")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), MPLBACKEND="Agg")
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=600)  # fmt: skip
    assert r.returncode == 0, f"README snippet failed:\n{code}\n{r.stderr[-2000:]}"


def test_the_readme_has_snippets():
    assert len(BLOCKS) >= 5
