"""Bounded, code-free reading of the configuration files users give (YAML, TOML).

Public names: ``MAX_CONFIG_BYTES``, ``MAX_DEPTH``, ``MAX_NODES``, ``jsonable``,
``load_config_file``, ``parse``, ``read_bounded``, ``yaml_loader``.

Design notes: docs/design/_safeload.md.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

__all__ = [
    "MAX_CONFIG_BYTES",
    "MAX_DEPTH",
    "MAX_NODES",
    "jsonable",
    "load_config_file",
    "parse",
    "read_bounded",
    "yaml_loader",
]

#: largest configuration file read (bytes)
MAX_CONFIG_BYTES = 1 << 20
#: most values (mappings, lists and scalars, aliases expanded) in one configuration file
MAX_NODES = 100_000
#: deepest nesting of mappings and lists in any file shipgym reads (its own files use < 8)
MAX_DEPTH = 32


def jsonable(x: Any) -> Any:
    """``x`` with NaN and infinite floats replaced by ``None`` (strict JSON has no NaN)."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [jsonable(v) for v in x]
    return x


def yaml_loader() -> Any:
    """libyaml's ``CSafeLoader`` when available, else PyYAML's ``SafeLoader``."""
    import yaml

    return getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def read_bounded(path: str | Path, what: str, max_bytes: int = MAX_CONFIG_BYTES) -> bytes:
    """The bytes of a file of at most ``max_bytes`` (checked before reading)."""
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"{what} {str(p)!r} does not exist")
    if not p.is_file():
        raise ValueError(f"{what} {str(p)!r} is not a file")
    try:
        size = p.stat().st_size
        if size > max_bytes:
            raise ValueError(
                f"{what} {str(p)!r} has {size:,} bytes, more than the limit of {max_bytes:,}"
            )
        with p.open("rb") as fh:
            data = fh.read(max_bytes + 1)
    except OSError as exc:
        raise ValueError(f"cannot read {what} {str(p)!r}: {exc.strerror or exc}") from None
    if len(data) > max_bytes:  # grew while reading, or a special file
        raise ValueError(f"{what} {str(p)!r} is larger than the limit of {max_bytes:,} bytes")
    return data


def _check_nodes(obj: Any, where: str, limit: int = MAX_NODES) -> None:
    stack = [(obj, 0)]
    n = 0
    while stack:
        x, depth = stack.pop()
        n += 1
        if n > limit:
            raise ValueError(
                f"{where} holds more than {limit:,} values (YAML aliases expanded): refused"
            )
        if depth > MAX_DEPTH:
            raise ValueError(f"{where} is nested more than {MAX_DEPTH} levels deep: refused")
        if isinstance(x, dict):
            stack.extend((k, depth + 1) for k in x)
            stack.extend((v, depth + 1) for v in x.values())
        elif isinstance(x, list | tuple):
            stack.extend((v, depth + 1) for v in x)


def parse(text: str, fmt: str, where: str, limit: int = MAX_NODES) -> Any:
    """Plain data from TOML, YAML (a safe loader: no code) or JSON ``text``, within the limits
    (``MAX_DEPTH`` levels, ``limit`` values): every failure is a ``ValueError`` naming
    ``where`` (a parser's ``RecursionError`` on a deeply nested file included).

    Args:
        text: the file's text.
        fmt: ``"toml"``, ``"yaml"`` or ``"json"``.
        where: the file, as the messages name it.
        limit: the most values (mappings, lists and scalars).
    """
    try:
        if fmt == "toml":
            import tomllib

            try:
                data: Any = tomllib.loads(text)
            except tomllib.TOMLDecodeError as exc:
                raise ValueError(f"{where} is not valid TOML: {exc}") from None
        elif fmt == "json":
            import json

            try:
                data = json.loads(text)
            except json.JSONDecodeError as exc:
                raise ValueError(f"{where} is not valid JSON: {exc}") from None
        elif fmt == "yaml":
            import yaml

            try:
                data = yaml.load(text, Loader=yaml_loader())  # noqa: S506 - a safe loader
            except yaml.YAMLError as exc:
                msg = " ".join(str(exc).split())
                raise ValueError(f"{where} is not valid YAML: {msg}") from None
        else:
            raise ValueError(f"unknown format {fmt!r}; use 'toml', 'yaml' or 'json'")
    except RecursionError:
        raise ValueError(f"{where} is nested too deeply (more than {MAX_DEPTH} levels)") from None
    _check_nodes(data, where, limit)
    return data


def load_config_file(
    path: str | Path, what: str = "file", max_bytes: int = MAX_CONFIG_BYTES
) -> Any:
    """Parse a ``.yaml``/``.yml`` or ``.toml`` file into plain data, within the limits.

    Raises:
        FileNotFoundError: no such file.
        ValueError: too large, not valid YAML/TOML, too many values, other suffix.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in (".yaml", ".yml", ".toml"):
        raise ValueError(f"{what} {str(p)!r}: unknown format; use .yaml, .yml or .toml")
    raw = read_bounded(p, what, max_bytes)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{what} {str(p)!r} is not UTF-8 text ({exc.reason})") from None
    return parse(text, "toml" if suffix == ".toml" else "yaml", f"{what} {str(p)!r}")
