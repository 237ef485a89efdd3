"""A long run's memory stays bounded: the gust, current and wave grids keep the chunk being
filled and the one before it, and recompute a dropped chunk from the realisation's seed when
it is read again, to the same floats as a grid that kept every chunk (the same realisation
whatever the order of the queries)."""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest

from shipgym.disturbances import Current, CurrentConfig, WaveConfig, Waves, Wind, WindConfig
from shipgym.disturbances._grid import CHUNK
from shipgym.dynamics.vessel import load_vessel

DT = 0.02  # s: a chunk is 82 s
CHUNKS = 6  # the run crosses five chunk boundaries (the first half two)


def _processes():
    v = load_vessel("blue-lady")
    d = math.radians(300.0)
    yield "gauss-markov gusts", lambda: Wind(
        WindConfig(speed=6.0, direction_from=d, gust_std=1.0, direction_std=0.1,
                   sample_period=DT), v.windage)  # fmt: skip
    yield (
        "spectral gusts",
        lambda: Wind(
            WindConfig(speed=6.0, direction_from=d, gust_spectrum="npd", sample_period=DT),
            v.windage,
        ),
    )
    yield (
        "current",
        lambda: Current(CurrentConfig.from_std(0.3, 0.5, 0.05, 300.0, sample_period=DT)),
    )
    for model in ("fossen", "rao"):
        yield f"waves ({model})", lambda model=model: Waves(
            WaveConfig(Hs=0.08, Tp=1.8, direction_from=math.radians(210.0), first_order=True,
                       wf_model=model, sample_period=DT), v.hull)  # fmt: skip


PROCESSES = dict(_processes())


def _query(p, t):
    """What the physics reads of ``p`` at time ``t`` (through its windows)."""
    if isinstance(p, Waves):
        return (*p.drift_load(t, 0.3), *np.ravel(p.wf_series(t)))
    return p.at(t)


def _kept(p) -> int:
    return sum(c is not None for c in p._chunks)


@pytest.mark.parametrize("name", list(PROCESSES))
def test_a_long_run_keeps_two_chunks_and_a_dropped_one_reads_the_same(name):
    bounded, whole = PROCESSES[name](), PROCESSES[name]()
    whole._evict = False
    for p in (bounded, whole):
        p.reset(np.random.default_rng(7))
    span = CHUNKS * CHUNK * DT
    times = np.arange(0.0, span, 1.93)
    for t in times[: len(times) // 2]:
        assert _query(bounded, t) == _query(whole, t)
    assert _kept(bounded) <= 2 < len(bounded._chunks)
    # the dropped chunks, read again (recomputed), and a series over the run so far
    j_now = len(bounded._chunks) - 1
    for j in range(j_now + 1):
        np.testing.assert_array_equal(bounded.chunk(j), whole.chunk(j))
    past = times[: len(times) // 2]
    if isinstance(bounded, Waves):
        np.testing.assert_array_equal(bounded.wf_series(past), whole.wf_series(past))
        np.testing.assert_array_equal(
            bounded.drift_series(past, 0.3), whole.drift_series(past, 0.3)
        )
    else:
        np.testing.assert_array_equal(bounded.series(past), whole.series(past))
    assert _kept(bounded) <= 2  # (the recomputation kept nothing)
    # and the run goes on where it was, the same floats
    for t in times[len(times) // 2 :]:
        assert _query(bounded, t) == _query(whole, t)
    assert len(bounded._chunks) >= CHUNKS and _kept(bounded) <= 2


@pytest.mark.parametrize("name", list(PROCESSES))
def test_windows_loaded_side_by_side_equal_those_loaded_one_by_one(name, monkeypatch):
    """``load_windows`` (a batch's grids computed on a pool of threads, each grid on one, the
    draw buffers of a spent chunk filled again) gives every grid's windows bit for bit as
    reading them one by one, across chunk boundaries, with a grid listed twice and grids
    whose windows are computed already."""
    from shipgym._jit import SPREAD_MIN as POOL_MIN
    from shipgym._jit import threads_ok
    from shipgym.disturbances import _grid
    from shipgym.disturbances._grid import PIECE, load_windows

    threads = set()
    windows_of = _grid._windows_of

    def spy(item):
        threads.add(threading.current_thread().name)
        return windows_of(item)

    monkeypatch.setattr(_grid, "_windows_of", spy)
    n = POOL_MIN + 3
    pooled, alone = [PROCESSES[name]() for _ in range(n)], [PROCESSES[name]() for _ in range(n)]
    for i in range(n):
        pooled[i].reset(np.random.default_rng(i))
        alone[i].reset(np.random.default_rng(i))
    for k in (0, PIECE + 3, CHUNK - 1, CHUNK + 5, 2 * CHUNK + 700, 3 * CHUNK + 1):
        ks = [k + 11 * i for i in range(n)]
        got = load_windows(pooled + pooled[:2], ks + ks[:2])
        for i, (k0, rows) in enumerate(got):
            w0, want = alone[i % n].window(ks[i % n])
            assert k0 == w0
            np.testing.assert_array_equal(rows, want)
    if threads_ok():  # grids were computed on the pool's threads
        assert any(name.startswith("shipgym-spread") for name in threads), threads
