"""Small pieces of the text shipgym prints: numbers in tables, suggestions for unknown names.

Public names: ``MISSING``, ``close_matches``, ``did_you_mean``, ``num``, ``num_list``.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Iterable
from typing import Any

__all__ = ["MISSING", "close_matches", "did_you_mean", "num", "num_list"]

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


def close_matches(name: Any, valid: Iterable[Any], n: int = 3, cutoff: float = 0.6) -> list[str]:
    """The names of ``valid`` closest to ``name`` (:func:`difflib.get_close_matches`, ignoring
    case, ``-`` against ``_``, and a ``shipgym/`` prefix), best first; none for a ``name``
    that is not a string."""
    if not isinstance(name, str) or not name:
        return []

    def key(s: str) -> str:
        s = s.strip().lower().replace("_", "-")
        return s.removeprefix("shipgym/")

    names: dict[str, str] = {}
    for v in valid:
        names.setdefault(key(str(v)), str(v))
    return [names[k] for k in difflib.get_close_matches(key(name), list(names), n, cutoff)]


def did_you_mean(name: Any, valid: Iterable[Any]) -> str:
    """``" (did you mean 'harbour'?)"`` for the names of ``valid`` close to an unknown
    ``name`` (:func:`close_matches`; two or three: ``'a' or 'b'``), else ``""``: the one
    suggestion every "unknown name" message of shipgym appends to the name it quotes."""
    matches = close_matches(name, valid)
    if not matches:
        return ""
    quoted = [repr(m) for m in matches]
    alts = quoted[0] if len(quoted) == 1 else f"{', '.join(quoted[:-1])} or {quoted[-1]}"
    return f" (did you mean {alts}?)"
