"""The data files (assets) a built wheel carries, counted and checked against the tree.

``python tools/wheel_assets.py dist/shipgym-*.whl`` (run by ``make dist``): prints the wheel's
file count and its non-Python files of the package per folder, and fails (exit 1) where a
non-Python file that git tracks under ``shipgym/`` is missing from the wheel, i.e. where
``[tool.setuptools.package-data]`` leaves it out (without git: every such file on disk).
"""

from __future__ import annotations

import subprocess
import sys
import zipfile
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = "shipgym"


def tree_assets() -> set[str]:
    """The package's non-Python files: git's tracked ones, or (no git) those on disk."""
    try:
        out = subprocess.run(
            ["git", "ls-files", "--", PACKAGE],
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.split()
    except (OSError, subprocess.CalledProcessError):
        out = [
            p.relative_to(ROOT).as_posix()
            for p in (ROOT / PACKAGE).rglob("*")
            if p.is_file() and "__pycache__" not in p.parts
        ]
    return {p for p in out if not p.endswith(".py")}


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python tools/wheel_assets.py WHEEL", file=sys.stderr)
        return 2
    wheel = Path(argv[0])
    with zipfile.ZipFile(wheel) as zf:
        names = [n for n in zf.namelist() if not n.endswith("/")]
    assets = sorted(n for n in names if n.startswith(f"{PACKAGE}/") and not n.endswith(".py"))
    modules = sum(1 for n in names if n.startswith(f"{PACKAGE}/") and n.endswith(".py"))
    per_folder = Counter(str(Path(n).parent) for n in assets)
    print(f"{wheel.name}: {len(names)} files, {modules} modules, {len(assets)} assets")
    for folder, n in sorted(per_folder.items()):
        print(f"  {n:3d}  {folder}/")
    missing = sorted(tree_assets() - set(assets))
    if missing:
        print(
            f"error: {len(missing)} package files of the tree are not in the wheel "
            "(extend [tool.setuptools.package-data] in pyproject.toml):",
            file=sys.stderr,
        )
        for name in missing:
            print(f"  {name}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
