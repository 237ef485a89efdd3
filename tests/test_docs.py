"""Every code block of the README and the docs runs as written, and the docs site builds.

Blocks of a page run in order, in one fresh folder, each in a fresh process: a ``python``
block with ``python -c`` (a block of ``>>>`` lines as a doctest), a ``sh`` block with ``bash -e``
and the environment's ``bin`` first on the PATH. Other fences must name a language that is
not code (``text``, ``math``), so that no block is left out by accident. An HTML comment on
the line before a fence marks it:

- ``<!-- slow -->``: runs under ``make test-slow`` only (in a folder of its own);
- ``<!-- not run: REASON -->``: not run, reported as a skip with its reason (a server that
  runs until stopped, the make targets CI itself runs, an install);
- ``<!-- needs: ... -->``: says which earlier block of the page makes its inputs.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
RUN = {"python", "sh"}
NOT_CODE = {"text", "math"}
FENCE = re.compile(r"^```(\S*)\n(.*?)^```$", re.S | re.M)
MARK = re.compile(r"<!-- (slow|not run: .+?|needs: .+?) -->\s*$")


@dataclass(frozen=True)
class Block:
    page: Path
    line: int
    lang: str
    code: str
    mark: str  # "", "slow", "not run: ...", "needs: ..."

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def blocks(page: Path) -> list[Block]:
    text = page.read_text()
    out = []
    for m in FENCE.finditer(text):
        before = text[: m.start()].rstrip("\n").rsplit("\n", 1)[-1]
        mark = MARK.search(before)
        line = text.count("\n", 0, m.start()) + 1
        out.append(Block(page, line, m.group(1), m.group(2), mark.group(1) if mark else ""))
    return out


ALL = [b for p in PAGES for b in blocks(p)]


def _needs_rl(code: str) -> bool:
    return "stable_baselines3" in code or "shipgym train" in code or "learned" in code


def _run(block: Block, cwd: Path) -> None:
    path = os.pathsep.join([str(Path(sys.executable).parent), os.environ["PATH"]])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), MPLBACKEND="Agg", PATH=path)
    if block.lang == "python" and block.code.lstrip().startswith(">>>"):
        (cwd / "block.txt").write_text(block.code)
        cmd = [sys.executable, "-m", "doctest", "-o", "ELLIPSIS", "-o", "NORMALIZE_WHITESPACE",
               "block.txt"]  # fmt: skip
    elif block.lang == "python":
        cmd = [sys.executable, "-c", block.code]
    else:
        cmd = ["bash", "-e", "-o", "pipefail", "-c", block.code]
    r = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=1800)
    assert r.returncode == 0, (
        f"{block.where}: the {block.lang} block failed (exit {r.returncode}):\n{block.code}\n"
        f"--- stdout\n{r.stdout[-2000:]}\n--- stderr\n{r.stderr[-3000:]}"
    )


def _skip_without_rl(todo: list[Block]) -> None:
    if any(_needs_rl(b.code) for b in todo):
        pytest.importorskip("stable_baselines3", reason="the rl extra is not installed (make rl)")


def _default(page: Path) -> list[Block]:
    return [b for b in blocks(page) if b.lang in RUN and not b.mark.startswith(("slow", "not"))]


CODE_PAGES = [p for p in PAGES if _default(p)]


@pytest.mark.parametrize("page", CODE_PAGES, ids=[str(p.relative_to(ROOT)) for p in CODE_PAGES])
def test_page_blocks_run(page, tmp_path):
    """The page's blocks that are neither slow nor marked 'not run', in order."""
    todo = _default(page)
    _skip_without_rl(todo)
    for b in todo:
        _run(b, tmp_path)


SLOW = [b for b in ALL if b.lang in RUN and b.mark == "slow"]


@pytest.mark.slow
@pytest.mark.parametrize("block", SLOW, ids=[b.where for b in SLOW])
def test_slow_block_runs(block, tmp_path):
    _skip_without_rl([block])
    _run(block, tmp_path)


NOT_RUN = [b for b in ALL if b.mark.startswith("not run")]


@pytest.mark.parametrize("block", NOT_RUN, ids=[b.where for b in NOT_RUN])
def test_blocks_not_run_say_why(block):
    """A block left out is reported, with its reason (and a reason is given)."""
    reason = block.mark.removeprefix("not run:").strip()
    assert len(reason) >= 10, f"{block.where}: say why the block is not run"
    pytest.skip(f"{block.where} not run: {reason}")


def test_every_fence_names_its_language():
    """A fence without a language (or an unknown one) would be left out silently."""
    bad = [f"{b.where}: ```{b.lang}" for b in ALL if b.lang not in RUN | NOT_CODE]
    assert not bad, "fences must be python, sh (run) or text, math (not code):\n" + "\n".join(bad)


def test_marks_are_known():
    text = "\n".join(p.read_text() for p in PAGES)
    marks = re.findall(r"<!-- ((?:slow|not run|needs)\b.*?) -->", text)
    assert all(MARK.search(f"<!-- {m} -->") for m in marks)


def test_the_docs_have_code():
    assert len([b for b in ALL if b.lang in RUN]) >= 20


def test_readme_is_one_screen():
    size = len((ROOT / "README.md").read_bytes())
    assert size <= 12 * 1024, f"README.md is {size} bytes: keep it at most 12 KB (details: docs/)"


def test_docs_site_builds(tmp_path):
    """``mkdocs build --strict``: every page, link and docstring without a warning."""
    pytest.importorskip("mkdocs", reason="the docs extra is not installed (make docs)")
    pytest.importorskip("mkdocstrings", reason="the docs extra is not installed (make docs)")
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1", MPLBACKEND="Agg")
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir",
                        str(tmp_path / "site")], cwd=ROOT, env=env, capture_output=True,
                       text=True, timeout=900)  # fmt: skip
    assert r.returncode == 0, f"mkdocs build --strict failed:\n{r.stderr[-5000:]}"
    site = tmp_path / "site"
    import gymnasium as gym

    import shipgym

    for env_id in shipgym.ENV_IDS:
        slug = re.sub(r"[^a-z0-9]+", "-", env_id.removeprefix("shipgym/").lower()).strip("-")
        page = (site / "envs" / slug / "index.html").read_text()
        assert env_id in page and gym.spec(env_id) is not None
    for name in shipgym.vessels():
        page = (site / "vessels" / name / "index.html").read_text()
        assert f"{name}.png" in page and (site / "vessels" / f"{name}.png").is_file()
    for page in ("cli-reference", "api/shipgym.envs.base", "papers/al-takie-1982"):
        assert (site / page / "index.html").is_file(), page
    # the docstrings' Sphinx roles (:func:`load_run`) become links where the name resolves
    api = (site / "api" / "shipgym.viz.run" / "index.html").read_text()
    assert ":func:" not in api and ":class:" not in api
    assert 'href="#shipgym.viz.run.load_run"' in api


def test_every_vessel_has_a_gallery_image():
    import shipgym

    missing = [v for v in shipgym.vessels() if not (ROOT / "docs" / "vessels" / f"{v}.png")
               .is_file()]  # fmt: skip
    assert not missing, f"run MUJOCO_GL=egl python tools/render_vessels.py {' '.join(missing)}"
