"""The seeds of child generators: the one way a stochastic part takes its own stream.

Public names: ``child_seeds``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["child_seeds"]

_TOP = 2**63 - 1  # the largest int64: [0, _TOP] is [0, 2**63)


def child_seeds(rng: np.random.Generator, size: int | None = None) -> Any:
    """``rng.integers(2**63)`` (``size=None``: one Python int) or ``rng.integers(2**63,
    size=size)`` (an int64 array): the same draws, and ``rng`` left in the same state (the
    same bounded-integer law on ``[0, 2**63 - 1]``), without NumPy's object-arithmetic path
    for a bound past int64 (about 2 us a call, several calls an episode start)."""
    if size is None:
        return int(rng.integers(_TOP, endpoint=True))
    return rng.integers(_TOP, size=size, endpoint=True)
