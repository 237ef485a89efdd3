"""Small pieces of the text shipgym prints: numbers in tables.

Public names: ``MISSING``, ``num``, ``num_list``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

__all__ = ["MISSING", "num", "num_list"]

#: what a printed table shows for a value that is not a finite number (NaN, +-inf, None)
MISSING = "n/a"


def _finite(x: Any) -> float | None:
    """``x`` as a finite float, else ``None`` (NaN, infinities, ``None``, not a number)."""
    if x is None or isinstance(x, bool):
        return None
    try:
        f = float(x)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def num(x: Any, spec: str = ".4f", missing: str = MISSING) -> str:
    """``x`` formatted with ``spec`` (``format(x, spec)``), or ``missing`` (``"n/a"``) where
    it is not a finite number: a printed table never shows ``nan`` or ``inf`` (the JSON
    results keep their own encoding)."""
    f = _finite(x)
    return missing if f is None else format(f, spec)


def num_list(values: Iterable[Any], ndigits: int, missing: str = MISSING) -> str:
    """``[240.0, 590.0, n/a]``: each value rounded to ``ndigits`` (as Python prints a rounded
    float), ``missing`` for one that is not a finite number."""
    out = []
    for v in values:
        f = _finite(v)
        out.append(missing if f is None else repr(round(f, ndigits)))
    return "[" + ", ".join(out) + "]"
