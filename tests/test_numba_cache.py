"""Numba's on-disk cache (issue 33 item 7): a private per-user folder by default, never one
another user can write; a damaged entry is compiled again; no writable folder: in memory."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(os.name != "posix", reason="POSIX permissions")

#: a module with one cached law, run in a fresh process (the cache is set up at import)
LAW = """
from shipgym._jit import njit
import numba

@njit
def twice(x):
    return 2.0 * x

print(twice(21.0), numba.config.CACHE_DIR)
"""


def _run(tmp: Path, cache_home: Path, **env: str):
    mod = tmp / "law_mod.py"
    mod.write_text(LAW)
    e = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    e.update(XDG_CACHE_HOME=str(cache_home), PYTHONPATH=os.pathsep.join([str(tmp), *sys.path]))
    e.update(env)
    return subprocess.run([sys.executable, "-c", "import law_mod"], env=e, cwd=tmp,
                          capture_output=True, text=True, timeout=300)  # fmt: skip


def test_the_default_cache_is_a_private_per_user_folder(tmp_path):
    home = tmp_path / "cache"
    r = _run(tmp_path, home)
    assert r.returncode == 0, r.stderr
    value, where = r.stdout.split()
    assert float(value) == 42.0 and Path(where) == home / "shipgym" / "numba"
    assert (Path(where).stat().st_mode & 0o777) == 0o700
    assert list(Path(where).rglob("*.nbi"))  # cached there


def test_a_damaged_cache_entry_is_compiled_again(tmp_path):
    home = tmp_path / "cache"
    assert _run(tmp_path, home).returncode == 0
    files = list((home / "shipgym" / "numba").rglob("*.nb[ic]"))
    assert files
    for f in files:  # truncated (a full disk, a killed process)
        f.write_bytes(f.read_bytes()[:7])
    r = _run(tmp_path, home)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split()[0] == "42.0"
    assert "discarded an unreadable Numba cache entry" in r.stderr


def test_a_folder_others_can_write_is_not_used(tmp_path):
    home = tmp_path / "cache"
    (home / "shipgym" / "numba").mkdir(parents=True)
    (home / "shipgym" / "numba").chmod(0o777)  # planted: anyone could put a pickle there
    r = _run(tmp_path, home)
    assert r.returncode == 0, r.stderr
    assert "compiling in memory" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not list((home / "shipgym" / "numba").rglob("*.nbi"))


def test_no_writable_folder_compiles_in_memory(tmp_path):
    if os.geteuid() == 0:  # root writes anywhere: a file where the folder should be instead
        home = tmp_path / "blocked"
        home.write_text("not a folder")
    else:
        home = tmp_path / "ro"
        home.mkdir()
        home.chmod(0o500)
    r = _run(tmp_path, home)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split()[0] == "42.0" and "compiling in memory" in r.stderr


def test_numba_cache_dir_is_the_users_choice(tmp_path):
    mine = tmp_path / "mine"
    r = _run(tmp_path, tmp_path / "cache", NUMBA_CACHE_DIR=str(mine))
    assert r.returncode == 0, r.stderr
    assert Path(r.stdout.split()[1]) == mine


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_cli_says_once_that_it_compiles_and_only_on_a_terminal():
    """The first run's compiles are a silent pause of up to a minute: the command says so once
    on a terminal (a compile happens below: a new function), and nothing on a pipe or log."""
    import numba

    from shipgym.cli import COMPILE_NOTICE, _compile_notice

    term, log = _Terminal(), io.StringIO()
    with _compile_notice(term), _compile_notice(log):
        assert numba.njit(lambda x: x + 1)(1) == 2
        assert numba.njit(lambda x: x * 2.0)(1.5) == 3.0
    assert term.getvalue() == COMPILE_NOTICE + "\n"
    assert log.getvalue() == ""
    with _compile_notice(term):  # a run that only loads from the cache says nothing more
        pass
    assert term.getvalue().count(COMPILE_NOTICE) == 1
