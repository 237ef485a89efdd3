"""``shipgym._jit.spread_rows``: a law over ranges of rows on threads covers every row once, in
consecutive ranges, and hands back each range's result in the rows' order (the callers take
the first failing row's code from it)."""

from __future__ import annotations

import threading

import numba
import pytest

from shipgym import _jit


@pytest.mark.parametrize("n", [1, 2, 3, 15, 16, 17, 255, 1000])
def test_spread_rows_covers_every_row_once_in_order(n: int) -> None:
    lock = threading.Lock()
    seen: list[int] = []
    names: set[str] = set()

    def law(lo: int, hi: int) -> tuple[int, int]:
        assert 0 <= lo < hi <= n
        with lock:
            seen.extend(range(lo, hi))
            names.add(threading.current_thread().name)
        return lo, hi

    out = _jit.spread_rows(law, n)
    assert sorted(seen) == list(range(n))  # each row once
    los = [lo for lo, _ in out]
    assert los == sorted(los) and los[0] == 0
    for (lo, (a, b)), nxt in zip(out, [*los[1:], n], strict=True):
        assert (a, b) == (lo, nxt)  # consecutive ranges, each result with its own range
    most = min(n, _jit.CHUNKS_PER_THREAD * max(1, int(numba.config.NUMBA_NUM_THREADS)))
    sizes = [b - a for _, (a, b) in out]
    assert len(out) <= most and len(set(sizes[:-1])) <= 1 and sizes[-1] <= sizes[0]
    if n >= 2 and _jit.threads_ok() and numba.config.NUMBA_NUM_THREADS > 1:
        assert all(name.startswith("shipgym-spread") for name in names), names


def test_spread_rows_raises_a_ranges_error_here() -> None:
    def law(lo: int, hi: int) -> int:
        if lo <= 40 < hi:
            raise ValueError("row 40")
        return 0

    with pytest.raises(ValueError, match="row 40"):
        _jit.spread_rows(law, 64)
