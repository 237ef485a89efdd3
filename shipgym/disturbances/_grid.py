"""Two-channel random processes sampled lazily on a fixed time grid (wind gusts, current).

The samples ``t_k = k * dt`` are generated in chunks of :data:`CHUNK` samples, always in time
order from ``t = 0``, so a realisation does not depend on the order of the queries. The first
piece of :data:`PIECE` samples is computed on its own (a reset: a short episode reads a few
hundred samples of its first chunk), the rest a chunk at a time as it is read (a compiled call
for thousands of samples, not one for each piece: the Python around a piece cost as much as
its samples): a chunk's random draws are made in their order when it is begun (all but the
last row's, drawn as far as read), its recursions and harmonic sums stop at the end of a
piece, so a piece is the same floats as in the whole chunk. The piece being read is kept as
Python lists, so a scalar query (every physics step) costs a few hundred nanoseconds; values
between samples are interpolated linearly. A grid keeps the chunk being filled and the one
before it; an older chunk read again (a series over a long run) is recomputed from the
realisation's seed, the same floats, so a long run's memory stays bounded.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import entry, njit, spread
from shipgym._seeding import child_seeds

__all__ = [
    "CHUNK",
    "PIECE",
    "GridPair",
    "PieceGrid",
    "load_windows",
    "gauss_markov",
    "gauss_markov_piece",
]

#: samples per chunk (each chunk also stores the first sample of the next one)
CHUNK = 4096

#: samples per piece of a chunk (computed on first read; a multiple of the harmonic sums'
#: block of 64 samples, a divisor of :data:`CHUNK`); a window (:meth:`PieceGrid.window`)
#: holds one piece and the piece's next sample
PIECE = 512


def fill_normals(rng: np.random.Generator, out: NDArray[np.float64]) -> None:
    """``out`` (K,) contiguous, filled with ``rng``'s next K standard normals (NumPy's
    ziggurat, in order: an array drawn in two calls holds the numbers of one)."""
    rng.standard_normal(out=out)


@njit
def gauss_markov(x, m, a, b, e, lo, hi, deviation, out):  # type: ignore[no-untyped-def]
    """A first-order Gauss-Markov sequence from ``x`` driven by the normals ``e`` (K,) into
    ``out`` (K + 1,), returning the last state: ``deviation`` True, the deviation form ``x_{k+1}
    = a x_k + b e_k``, ``out = m + x``; else the absolute form ``x_{k+1} = m + a (x_k - m) +
    b e_k`` clipped to ``[lo, hi]``, ``out = x`` (the grids' one recursion, compiled)."""
    out[0] = m + x if deviation else x
    for k in range(e.shape[0]):
        if deviation:
            x = a * x + b * e[k]
            out[k + 1] = m + x
        else:
            x = m + a * (x - m) + b * e[k]
            x = lo if x < lo else (hi if x > hi else x)
            out[k + 1] = x
    return x


@njit(nogil=True)
def _gauss_markov_piece(x, m, a, b, lo, hi, deviation, e, ka, kb, out):  # type: ignore[no-untyped-def]
    """:func:`gauss_markov_piece`, compiled."""
    s = ka - 1 if ka > 0 else 0
    for r in range(out.shape[0]):
        x[r] = gauss_markov(x[r], m[r], a[r], b[r], e[r, s : kb - 1], lo[r], hi[r], deviation,
                            out[r, s:kb])  # fmt: skip


def gauss_markov_piece(
    x: NDArray[np.float64],
    m: NDArray[np.float64],
    a: NDArray[np.float64],
    b: NDArray[np.float64],
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
    deviation: bool,
    e: NDArray[np.float64],
    ka: int,
    kb: int,
    out: NDArray[np.float64],
) -> None:
    """The samples ``ka ... kb - 1`` of a chunk of R Gauss-Markov channels (:func:`gauss_markov`,
    each with its own ``m, a, b, lo, hi``, (R,)) into ``out`` (R, CHUNK + 1), from the states
    ``x`` (R,) at the sample ``ka - 1`` (at ``ka = 0``: the chunk's start), driven by the
    chunk's normals ``e`` (R, CHUNK) (``rng.standard_normal((R, CHUNK))``, row by row,
    :meth:`PieceGrid._normals`, drawn up to ``e[:, kb - 2]`` at least); the states
    advanced in place to the sample ``kb - 1``. The recursion stopped and taken up again: the
    same floats as the whole chunk's; one compiled call for a piece."""
    args = (x, m, a, b, lo, hi, bool(deviation), e, int(ka), int(kb), out)
    if not _PIECE:
        _PIECE.append(entry(_gauss_markov_piece, args))
    _PIECE[0](*args)


_PIECE: list[Any] = []  # _gauss_markov_piece's compiled entry point


class PieceGrid:
    """Chunks of a grid computed a piece at a time, in time order (:data:`PIECE`).

    Subclasses implement :meth:`_begin` (a new chunk: its array, its draws) and :meth:`_piece`
    (the samples ``ka ... kb - 1`` of the chunk being filled), and call :meth:`_clear_pieces`
    at a reset. Chunk ``j`` is computed only once the chunks before it are whole.
    """

    #: samples computed past the first window's last one with the first piece: 1 (the next
    #: sample), or a harmonic sum's block (64), so that every block of the sums is computed
    #: once, whole
    _LEAD = 1

    #: drop the chunks before the one before the last (a long run's memory stays bounded: a
    #: few chunks a process); one read again is recomputed from the realisation's seed
    #: (:meth:`_replica`), the same floats
    _evict = True

    _chunks: list[NDArray[np.float64] | None]
    _fill: int  # samples of the last chunk computed (CHUNK + 1: whole)
    _drawn: int  # normals of the chunk being filled drawn (flat, C order)
    _draw_rng: np.random.Generator | None

    def _clear_pieces(self) -> None:
        self._chunks = []
        self._fill = CHUNK + 1

    def _normals(
        self,
        rng: np.random.Generator,
        shape: tuple[int, ...],
        out: NDArray[np.float64] | None = None,
    ) -> NDArray[np.float64]:
        """A chunk's normals ``rng.standard_normal(shape)`` (``shape[-1] = CHUNK``), to be read
        after :meth:`_draw_to`: every row but the last drawn now, the last one's (the last of
        the chunk's draws from ``rng``, a generator of this grid alone) as far as a piece
        needs them; the same numbers, ``rng`` in the same state once the chunk is whole.
        ``out``: an array of ``shape`` of this grid's own to fill (the last chunk's, read no
        more), else a new one."""
        e = out if out is not None and out.shape == shape else np.empty(shape)
        self._drawn = e.size - shape[-1]
        self._draw_rng = rng
        fill_normals(rng, e.reshape(-1)[: self._drawn])
        return e

    def _draw_to(self, e: NDArray[np.float64], kb: int) -> None:
        """The normals ``e[..., :kb - 1]`` of the chunk being filled drawn (:meth:`_normals`):
        what the samples before ``kb`` read."""
        need = e.size - e.shape[-1] + max(kb - 1, 0)
        if need > self._drawn:
            assert self._draw_rng is not None
            fill_normals(self._draw_rng, e.reshape(-1)[self._drawn : need])
            self._drawn = need

    def _ready_check(self) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _begin(self, j: int) -> NDArray[np.float64]:  # pragma: no cover - abstract
        raise NotImplementedError

    def _piece(self, j: int, ka: int, kb: int) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _replica(self) -> PieceGrid:  # pragma: no cover - abstract
        """A copy of this grid started afresh on the same realisation (its seed), sharing
        nothing it writes: it recomputes dropped chunks."""
        raise NotImplementedError

    def _chunk(self, j: int) -> NDArray[np.float64]:
        """Chunk ``j`` (computed as far as asked before): this grid's, or a dropped one
        recomputed by a replica (:attr:`_evict`)."""
        c = self._chunks[j]
        return c if c is not None else self._whole(j)[j]

    def _whole(self, j: int) -> list[NDArray[np.float64]]:
        """Chunks ``0 ... j``, whole (one replica for the dropped ones)."""
        self._extend_to(j)
        if self._chunks[0] is not None:
            return self._chunks[: j + 1]  # type: ignore[return-value]
        r = self._replica()
        r._evict = False
        r._extend_to(j)
        return [c if c is not None else r._chunks[k] for k, c in enumerate(self._chunks[: j + 1])]  # type: ignore[misc]

    def _fill_to(self, j: int, n: int) -> None:
        """Chunk ``j``'s first ``n`` samples (1 <= n <= CHUNK + 1) computed, and every chunk
        before it whole, in time order, a whole number of pieces (and the next sample)."""
        while True:
            last = len(self._chunks) - 1
            if last > j or (last == j and self._fill >= n):
                return
            if self._fill == CHUNK + 1:  # the next chunk: its array and draws
                self._ready_check()
                self._chunks.append(self._begin(last + 1))
                if self._evict and last >= 1:  # the one before the last goes
                    self._chunks[last - 1] = None
                self._fill = 0
                continue
            want = CHUNK + 1  # past the first piece, the rest of the chunk
            if last == j == 0 and self._fill == 0:  # the first piece: a reset's
                want = min(CHUNK + 1, -(-(n - 1) // PIECE) * PIECE + self._LEAD)
            self._piece(last, self._fill, want)
            self._fill = want

    def _extend_to(self, j: int) -> None:
        """Chunks ``0 ... j`` whole."""
        self._fill_to(j, CHUNK + 1)

    def computed(self, k: int) -> bool:
        """Whether :meth:`window` of ``k`` (>= 0) reads samples computed already (no piece,
        chunk or dropped chunk to compute)."""
        j, p = divmod(int(k), CHUNK)
        last = len(self._chunks) - 1
        if last < j or (last == j and self._fill < p - p % PIECE + PIECE + 1):
            return False
        return self._chunks[j] is not None

    def window(self, k: int) -> tuple[int, NDArray[np.float64]]:
        """The piece holding sample ``k`` (>= 0) and the piece's next sample: ``(k0, rows)``,
        ``rows`` (R, PIECE + 1) the samples ``k0 ... k0 + PIECE`` of every row (the next
        sample from the same chunk as the piece), ``k0 <= k < k0 + PIECE``; computed on first
        use (the first piece alone, then the rest of its chunk; read only)."""
        j, p = divmod(int(k), CHUNK)
        p -= p % PIECE
        self._fill_to(j, p + PIECE + 1)
        return j * CHUNK + p, self._chunk(j)[:, p : p + PIECE + 1]


def _windows_of(item: tuple[PieceGrid, list[int]]) -> None:
    grid, ks = item
    for k in ks:
        grid.window(k)


def load_windows(grids: list[PieceGrid], ks: list[int]) -> list[tuple[int, NDArray[np.float64]]]:
    """``grids[m].window(ks[m])`` for every ``m``: the grids whose samples must be computed
    first (a new piece or chunk: random draws, recursions, harmonic sums) computed side by
    side (:func:`shipgym._jit.spread`), each grid on one thread (its draws in their order:
    the same floats), then every window read in order. The draws and the compiled recursions
    and sums run without the GIL; a batch of hulls in step reaches a chunk's end together, so
    its grids are computed together."""
    todo: dict[int, tuple[PieceGrid, list[int]]] = {}
    for g, k in zip(grids, ks, strict=True):
        if not g.computed(k):
            todo.setdefault(id(g), (g, []))[1].append(k)
    spread(_windows_of, list(todo.values()))
    return [g.window(k) for g, k in zip(grids, ks, strict=True)]


class GridPair(PieceGrid):
    """Base of a two-channel process on a grid; subclasses implement :meth:`_begin` and
    :meth:`_piece` (:class:`PieceGrid`).

    Subclasses set ``self._inv_dt`` (1/s); their chunks have shape ``(2, CHUNK + 1)``.
    """

    _inv_dt: float
    _const: tuple[float, float] | None
    _rng: np.random.Generator | None

    def _start(
        self, rng: np.random.Generator | int | None, what: str
    ) -> np.random.Generator | None:
        """Clear, then take one child generator from ``rng`` (one ``integers(2**63)`` draw;
        ``None`` for a constant process, which draws nothing from it).

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
        seed = child_seeds(rng)  # drawn for a constant process too (the same stream)
        self._seed = seed
        # a constant process draws nothing from its child: none is made (a reset's cost)
        self._rng = None if self._const is not None else np.random.default_rng(seed)
        return self._rng

    def _draws(self, child: np.random.Generator | None) -> None:
        """A reset's draws from its child generator (none for a constant process)."""

    def _replica(self) -> GridPair:
        r = copy.copy(self)
        r._clear()
        r._rng = np.random.default_rng(self._seed)
        r._draws(r._rng)
        return r

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
        return self._chunk(j)

    def window(self, k: int) -> tuple[int, NDArray[np.float64]]:
        """:meth:`PieceGrid.window` of the grid, ``(k0, (2, PIECE + 1))``."""
        if self._const is not None:
            raise ValueError(f"a constant {type(self).__name__} has no grid: read .constant")
        return super().window(k)

    def _clear(self) -> None:
        self._clear_pieces()
        # the normals of the last chunk, whose array the next chunk's draw fills (this grid's
        # own: a replica, cleared, draws into its own)
        self._spent: NDArray[np.float64] | None = None
        self._cache: dict[int, tuple[list[float], list[float]]] = {}
        self._j = -1  # piece currently held as Python lists
        self._k0 = 0
        self._c0: list[float] = []
        self._c1: list[float] = []

    def _select(self, j: int) -> None:
        lists = self._cache.get(j)
        if lists is None:
            _k0, arr = self.window(j * PIECE)
            lists = (arr[0].tolist(), arr[1].tolist())
            if len(self._cache) >= 2:  # keep the two most recent pieces as lists
                del self._cache[next(iter(self._cache))]
            self._cache[j] = lists
        self._c0, self._c1 = lists
        self._j = j
        self._k0 = j * PIECE

    def _interp(self, t: float) -> tuple[float, float]:
        """Both channels at time ``t`` (s, >= 0), linearly interpolated (scalar, fast)."""
        x = float(t) * self._inv_dt
        if not x >= 0.0:
            raise ValueError(f"{type(self).__name__}: time must be >= 0 s, got {t!r}")
        k = int(x)
        if k // PIECE != self._j:
            self._select(k // PIECE)
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
        chunks = self._whole(jmax)
        grid = np.concatenate([c[:, :CHUNK] for c in chunks] + [chunks[jmax][:, CHUNK:]], axis=1)
        f = x - k
        s0, s1 = grid[0, k], grid[0, k + 1]
        d0, d1 = grid[1, k], grid[1, k + 1]
        return s0 + f * (s1 - s0), d0 + f * (d1 - d0)
