"""Packaged assets (MJCF models), located with importlib.resources, never by working directory."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["asset_path"]


def asset_path(*parts: str) -> Path:
    """Path of a packaged asset, e.g. ``asset_path("mjcf", "blue_lady", "scene.xml")``.

    Raises:
        FileNotFoundError: the asset does not exist (lists what is in its folder).
    """
    path = Path(str(resources.files("shipgym.assets").joinpath(*parts)))
    if not path.exists():
        folder = path.parent
        have = sorted(p.name for p in folder.iterdir()) if folder.is_dir() else []
        raise FileNotFoundError(f"no packaged asset {'/'.join(parts)!r}; {folder} holds {have}")
    return path
