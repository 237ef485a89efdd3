"""Two-channel random processes sampled lazily on a fixed time grid (wind gusts, current).

The samples ``t_k = k * dt`` are generated in chunks of :data:`CHUNK` samples, always in time
order from ``t = 0``, so a realisation does not depend on the order of the queries. The chunk
being read is kept as Python lists, so a scalar query (every physics step) costs a few
hundred nanoseconds; values between samples are interpolated linearly.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["CHUNK", "GridBatch", "GridPair"]

#: samples per chunk (each chunk also stores the first sample of the next one)
CHUNK = 4096


class GridPair:
    """Base of a two-channel process on a grid; subclasses implement :meth:`_extend_to`.

    Subclasses set ``self._inv_dt`` (1/s) and append chunks of shape ``(2, CHUNK + 1)`` to
    ``self._chunks`` in :meth:`_extend_to`.
    """

    _inv_dt: float
    _const: tuple[float, float] | None
    _rng: np.random.Generator | None

    def _start(
        self, rng: np.random.Generator | int | None, what: str
    ) -> np.random.Generator | None:
        """Clear, then take one child generator from ``rng`` (one ``integers(2**63)`` draw).

        ``rng`` may be ``None`` only for a constant process (``_const`` set); ``what`` names
        the varying process in the error message.
        """
        self._clear()
        if rng is None:
            if self._const is None:
                raise ValueError(
                    f"{type(self).__name__}.reset needs a numpy Generator (or a seed) for {what}"
                )
            self._rng = None
            return None
        if not isinstance(rng, np.random.Generator):
            rng = np.random.default_rng(rng)
        self._rng = np.random.default_rng(int(rng.integers(2**63)))
        return self._rng

    @property
    def constant(self) -> tuple[float, float] | None:
        """``(speed m/s, direction rad)`` of a constant process, ``None`` for a varying one."""
        return self._const

    @property
    def sample_rate(self) -> float:
        """Samples per second of the grid (1/s)."""
        return self._inv_dt

    def chunk(self, j: int) -> NDArray[np.float64]:
        """Chunk ``j`` of the grid, ``(2, CHUNK + 1)``: the samples ``k = j CHUNK ... (j + 1)
        CHUNK`` (times ``k / sample_rate``) of both channels, generated in time order on first
        use (the same realisation whatever the order of the queries). Read only."""
        if self._const is not None:
            raise ValueError(f"a constant {type(self).__name__} has no grid: read .constant")
        self._extend_to(j)
        return self._chunks[j]

    def _clear(self) -> None:
        self._chunks: list[NDArray[np.float64]] = []
        self._cache: dict[int, tuple[list[float], list[float]]] = {}
        self._j = -1  # chunk currently held as Python lists
        self._k0 = 0
        self._c0: list[float] = []
        self._c1: list[float] = []

    def _extend_to(self, j: int) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _select(self, j: int) -> None:
        lists = self._cache.get(j)
        if lists is None:
            self._extend_to(j)
            arr = self._chunks[j]
            lists = (arr[0].tolist(), arr[1].tolist())
            if len(self._cache) >= 2:  # keep the two most recent chunks as lists
                del self._cache[next(iter(self._cache))]
            self._cache[j] = lists
        self._c0, self._c1 = lists
        self._j = j
        self._k0 = j * CHUNK

    def _interp(self, t: float) -> tuple[float, float]:
        """Both channels at time ``t`` (s, >= 0), linearly interpolated (scalar, fast)."""
        x = float(t) * self._inv_dt
        if not x >= 0.0:
            raise ValueError(f"{type(self).__name__}: time must be >= 0 s, got {t!r}")
        k = int(x)
        if k // CHUNK != self._j:
            self._select(k // CHUNK)
        f = x - k
        i = k - self._k0
        c0, c1 = self._c0, self._c1
        a0, b0 = c0[i], c1[i]
        return a0 + f * (c0[i + 1] - a0), b0 + f * (c1[i + 1] - b0)

    def _interp_series(self, t: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`_interp` for an array of times (same values)."""
        tt = np.asarray(t, dtype=float)
        x = tt * self._inv_dt
        if not np.all(x >= 0.0):
            raise ValueError(f"{type(self).__name__}: all times must be >= 0 s (and not NaN)")
        if x.size == 0:
            return np.empty(tt.shape), np.empty(tt.shape)
        k = np.floor(x).astype(np.int64)
        jmax = int(k.max()) // CHUNK
        self._extend_to(jmax)
        grid = np.concatenate(
            [c[:, :CHUNK] for c in self._chunks[: jmax + 1]] + [self._chunks[jmax][:, CHUNK:]],
            axis=1,
        )
        f = x - k
        s0, s1 = grid[0, k], grid[0, k + 1]
        d0, d1 = grid[1, k], grid[1, k + 1]
        return s0 + f * (s1 - s0), d0 + f * (d1 - d0)


class GridBatch:
    """The processes of N envs (each a :class:`GridPair`, reset on its own) read at once:
    ``at(t)`` for a time per env, the same values as each process's scalar query (the same
    interpolation, in arrays). A constant process reads as its constant.

    Args:
        processes: one process per env (already reset).
    """

    def __init__(self, processes: list[GridPair]) -> None:
        self.processes = list(processes)
        n = len(self.processes)
        self._rows = np.arange(n)
        self._inv_dt = np.zeros(n)
        self._valid = np.zeros(n, dtype=np.int64)  # samples held per env
        self._g0 = np.zeros((n, 2))
        self._g1 = np.zeros((n, 2))
        self._offsets = self._rows * 2
        self._any_varying = False
        for i in range(n):
            self.refresh(i)

    def _grid(self, i: int, j: int) -> NDArray[np.float64]:
        p = self.processes[i]
        p._extend_to(j)
        return np.concatenate([c[:, :CHUNK] for c in p._chunks[: j + 1]]
                              + [p._chunks[j][:, CHUNK:]], axis=1)  # fmt: skip

    def _store(self, i: int, grid: NDArray[np.float64]) -> None:
        width = grid.shape[1]
        if width > self._g0.shape[1]:  # widen every row (padded with its last value)
            pad = width - self._g0.shape[1]
            self._g0 = np.concatenate([self._g0, np.repeat(self._g0[:, -1:], pad, 1)], 1)
            self._g1 = np.concatenate([self._g1, np.repeat(self._g1[:, -1:], pad, 1)], 1)
        self._offsets = self._rows * self._g0.shape[1]
        self._g0[i, :width] = grid[0]
        self._g1[i, :width] = grid[1]
        self._g0[i, width:] = grid[0, -1]
        self._g1[i, width:] = grid[1, -1]
        self._valid[i] = width

    def refresh(self, i: int) -> None:
        """Re-read env ``i``'s process (after its reset)."""
        p = self.processes[i]
        if p._const is not None:
            self._inv_dt[i] = 0.0
            self._store(i, np.array([[p._const[0]] * 2, [p._const[1]] * 2]))
            self._any_varying = bool(self._inv_dt.any())
            return
        self._inv_dt[i] = p._inv_dt
        self._store(i, self._grid(i, 0))
        self._any_varying = bool(self._inv_dt.any())

    def _hold(self, last: NDArray[np.int64]) -> None:
        """Make each env's rows hold its samples up to index ``last + 1``."""
        over = np.nonzero(last + 1 >= self._valid)[0]
        for i in over.tolist():  # a new chunk (rare): in time order, as the scalar query
            self._store(i, self._grid(i, int(last[i]) // CHUNK))

    def rows_until(self, t: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
        """``(inv_dt, channel 0, channel 1)``: each env's 1/dt (0 for a constant process) and
        its samples as ``(n, width)`` rows, holding every sample up to the times ``t`` (n,)
        (for reading the process at times up to ``t`` as :meth:`at` reads it: the compiled
        batched physics interpolates in them itself)."""
        if self._any_varying:
            self._hold((t * self._inv_dt).astype(np.int64))
        return self._inv_dt, self._g0, self._g1

    def at(self, t: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Both channels at the times ``t`` (n,) (s, >= 0), one per env; or (k, n): k times per
        env (the steps of a control period, read at once)."""
        if not self._any_varying:  # every process constant: a0 + f (a1 - a0) with a1 = a0
            shape = np.shape(t)
            return np.broadcast_to(self._g0[:, 0], shape), np.broadcast_to(self._g1[:, 0], shape)
        x = t * self._inv_dt
        k = x.astype(np.int64)  # x >= 0: int() truncation, as the scalar query
        self._hold(k if k.ndim == 1 else k.max(axis=0))
        f = x - k
        i = self._offsets + k  # flat indices into the (n, width) rows (faster than [rows, k])
        g0, g1 = self._g0.ravel(), self._g1.ravel()
        a0, b0 = g0.take(i), g1.take(i)
        i += 1
        return a0 + f * (g0.take(i) - a0), b0 + f * (g1.take(i) - b0)
