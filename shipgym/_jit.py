"""Numba for the run-time laws: the decorator, the two kernel signatures, kernel compilation.

Every run-time law of the physics is one compiled function with one of two fixed signatures,
so that the one stepping loop (:mod:`shipgym.sim.step`) takes any hull family's acceleration
and any actuator kind's force law as a first-class function argument: the loop is compiled
once (and cached on disk by Numba), a new family or kind compiles only its own small law.

Public names: ``ACCEL_SIG``, ``LAW_SIG``, ``THREADS``, ``njit``, ``kernel``, ``entry``,
``threads_ok``, ``use_threads``, ``spread``, ``spread_rows``, ``law_input``, ``address``,
``function_at``.

Design notes: docs/design/_jit.md.
"""

from __future__ import annotations

import os
import sys
import threading
import warnings
from typing import Any

import numba
import numpy as np
from numba import njit as _njit
from numba import types
from numba.core.errors import NumbaExperimentalFeatureWarning

__all__ = [
    "ACCEL_SIG",
    "LAW_SIG",
    "THREADS",
    "njit",
    "kernel",
    "entry",
    "law_input",
    "threads_ok",
    "use_threads",
    "spread",
    "spread_rows",
    "address",
    "function_at",
]

# first-class function arguments are "experimental" in Numba; the loop relies on them
warnings.filterwarnings("ignore", category=NumbaExperimentalFeatureWarning)

_f8 = types.float64
_vec = types.float64[::1]

#: hull family acceleration: (k, u, v, p, r, phi, X, Y, K, N, u_c, v_c) -> 4 floats
ACCEL_SIG = types.UniTuple(_f8, 4)(_vec, *([_f8] * 11))
#: actuator force law: (row, st, u_r, v_r, p, r) -> (X, Y, K, N, F, flag)
LAW_SIG = types.UniTuple(_f8, 6)(_vec, _vec, _f8, _f8, _f8, _f8)

_DISABLED = bool(numba.config.DISABLE_JIT)


# ---- Numba's on-disk cache: a private folder per user ------------------------------------------
def _private_cache_dir() -> str | None:
    """The per-user cache folder (``$XDG_CACHE_HOME`` or ``~/.cache``, then
    ``shipgym/numba``), created private (0700); ``None`` where it cannot be created or written,
    or is not private (owned by another user, or writable by group or others: a pickle planted
    there would run on loading)."""
    from shipgym._io import private_cache_dir

    path = private_cache_dir("numba")
    return None if path is None else str(path)


def _configure_cache() -> bool:
    """Where Numba caches shipgym's compiled laws; whether it caches at all.

    ``NUMBA_CACHE_DIR`` set: Numba's own choice. Otherwise a private per-user folder
    (:func:`_private_cache_dir`; never a folder another user can write, such as a shared
    installation's ``__pycache__``), which this process's Numba then uses for every cached
    function; without one, shipgym compiles in memory only (a one-line notice on stderr).
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return True
    path = _private_cache_dir()
    if path is None:
        print(
            "shipgym: notice: no private writable cache folder (set XDG_CACHE_HOME or "
            "NUMBA_CACHE_DIR); compiling in memory, every process compiles again",
            file=sys.stderr,
        )
        return False
    numba.config.CACHE_DIR = path
    return True


def _tolerate_bad_cache_entries() -> None:
    """A cache entry that cannot be loaded (a truncated or foreign file) is discarded and the
    function compiled again, with one warning, instead of failing every run until deleted."""
    from numba.core import caching

    load = caching.Cache.load_overload
    if getattr(load, "shipgym", False):
        return

    def load_overload(self: Any, sig: Any, target_context: Any) -> Any:
        try:
            return load(self, sig, target_context)
        except Exception as exc:  # noqa: BLE001 - unpickling a damaged file raises anything
            warnings.warn(
                f"shipgym: discarded an unreadable Numba cache entry of {self._name} "
                f"({type(exc).__name__}); compiling it again",
                RuntimeWarning,
                stacklevel=2,
            )
            try:
                self._cache_file.flush()  # an empty index: the next save starts afresh
            except OSError:
                pass
            return None

    load_overload.shipgym = True  # type: ignore[attr-defined]
    caching.Cache.load_overload = load_overload


_CACHE = _configure_cache()
_tolerate_bad_cache_entries()


def njit(*args: Any, **kwargs: Any) -> Any:
    """``numba.njit`` with ``cache=True`` by default (compiled code cached on disk, in a
    private per-user folder: :func:`_configure_cache`), or without the cache for a function
    Numba cannot cache (one defined in an interactive session: no file to locate the cache by)
    or where no private writable folder exists."""
    if args and callable(args[0]):
        return njit(**kwargs)(args[0])
    kwargs.setdefault("cache", _CACHE)

    def wrap(fn: Any) -> Any:
        try:
            return _njit(*args, **kwargs)(fn)
        except RuntimeError as exc:  # "cannot cache function ...: no locator available"
            if "no locator" not in str(exc):
                raise
            return _njit(*args, **{**kwargs, "cache": False})(fn)

    return wrap


def kernel(fn: Any, sig: Any) -> Any:
    """``fn`` (an :func:`njit` function) compiled for ``sig`` (:data:`ACCEL_SIG`,
    :data:`LAW_SIG`, a law over rows) and for nothing else, so that a loop takes it as a
    first-class function
    (Numba types a dispatcher that cannot compile more as a function type: one compiled loop
    for every law of that signature); the function itself where compilation is off."""
    if _DISABLED or not hasattr(fn, "compile"):
        return fn
    if not fn.signatures:
        fn.compile(sig)
    fn.disable_compile()
    return fn


_ENTRIES: dict[tuple[Any, ...], Any] = {}


def _type_key(a: Any) -> Any:
    """What Numba's type of ``a`` depends on, cheaply: an array's dtype, dimensions, layout
    and flags; a Python number's type; else Numba's type itself."""
    if isinstance(a, np.ndarray):
        f = a.flags
        return (a.dtype.str, a.ndim, f.c_contiguous, f.f_contiguous, f.writeable, f.aligned)
    if type(a) in (bool, int, float):
        return type(a)
    return numba.typeof(a)


def entry(dispatcher: Any, args: tuple[Any, ...]) -> Any:
    """The compiled entry point of ``dispatcher`` for arguments like ``args`` (compiled if
    needed): calling it skips Numba's per-call type resolution, which costs tens of
    microseconds for first-class function arguments. Entry points are kept per dispatcher
    and argument types, so a new object with arguments of the same types (an episode's new
    physics) gets its entry point without resolving the types again. The function itself
    where compilation is off."""
    if _DISABLED or not hasattr(dispatcher, "overloads"):
        return dispatcher
    key = (dispatcher, *map(_type_key, args))
    found = _ENTRIES.get(key)
    if found is None:
        sig = tuple(dispatcher.typeof_pyval(a) for a in args)
        dispatcher.compile(sig)
        found = _ENTRIES[key] = dispatcher.overloads[sig].entry_point
    return found


def law_input(a: Any, dtype: Any = float) -> np.ndarray:
    """``a`` as a C-contiguous, writable array of ``dtype``: the one type a law's compiled entry
    point is typed for. A read-only or strided array is a Numba type of its own, so passing it
    would compile the whole law again; this copies only such an input (a frozen vessel's
    array, a broadcast row) and hands every other array through as it is."""
    if type(a) is np.ndarray and a.dtype == dtype:  # (the usual case, without np.require's cost)
        flags = a.flags
        if flags.c_contiguous and flags.writeable:
            return a
    return np.require(a, dtype=dtype, requirements=("C", "W"))


# ---- Numba's threads ---------------------------------------------------------------------------
#: ``used``: this process ran compiled code on Numba's threads; ``allowed``: it may (not in a
#: child forked from a process that did: GNU OpenMP, Numba's usual threading layer, is not
#: fork-safe, and Numba ends such a child; not in a worker of a pool that fills the cores)
THREADS = {"used": False, "allowed": True}
os.register_at_fork(after_in_child=lambda: THREADS.update(allowed=not THREADS["used"]))


def threads_ok() -> bool:
    """Whether compiled code may run on Numba's threads now: in the main thread (Numba's
    ``workqueue`` layer may not be entered from two threads at once) of a process allowed to
    (:data:`THREADS`)."""
    return THREADS["allowed"] and threading.current_thread() is threading.main_thread()


#: GNU OpenMP's spin before an idle thread sleeps (iterations, tens of microseconds): enough
#: for the next of back-to-back parallel calls (about 10 % faster than sleeping at once, as
#: ``OMP_WAIT_POLICY=PASSIVE`` does), short against GNU's default, whose spinning threads made a
#: step twice as slow on a busy machine
SPINCOUNT = "10000"


def use_threads() -> None:
    """Note that this process runs on Numba's threads (before the first parallel call: idle
    threads spin :data:`SPINCOUNT` iterations, then sleep, unless the user set
    ``OMP_WAIT_POLICY`` or ``GOMP_SPINCOUNT``)."""
    if not THREADS["used"]:
        if "OMP_WAIT_POLICY" not in os.environ:
            os.environ.setdefault("GOMP_SPINCOUNT", SPINCOUNT)
        THREADS["used"] = True


#: the fewest items :func:`spread` runs on its pool of threads
SPREAD_MIN = 8
_POOL: list[Any] = []  # spread's pool of threads, made on first use (dropped in a forked child)
os.register_at_fork(after_in_child=_POOL.clear)


def _share(fn: Any, items: list[Any]) -> None:
    for item in items:
        fn(item)


def spread(fn: Any, items: list[Any]) -> None:
    """``fn(item)`` for every item: on a pool of Numba's thread count of Python threads, one
    share of the items a thread (many short tasks queue on the GIL: no faster than one
    thread), where there are :data:`SPREAD_MIN` or more and this thread may use threads
    (:func:`threads_ok`); else in order here. For independent work that runs mostly without
    the GIL (NumPy's random draws, ``nogil`` compiled laws): each item on one thread, so its
    floats do not depend on the threads; an error in one is raised here. (The calling thread
    waits: had it taken a share, or had the threads taken the next item from one queue, the
    threads' Python parts would contend for the GIL, each waiting up to the 5 ms switch
    interval: a DP loop of 256 envs 15 % slower.)"""
    if len(items) < SPREAD_MIN:
        _share(fn, items)
    else:
        _on_threads(fn, items)


def _on_threads(fn: Any, items: list[Any]) -> None:
    if len(items) < 2 or not threads_ok():
        _share(fn, items)
        return
    if not _POOL:
        from concurrent.futures import ThreadPoolExecutor

        workers = max(1, int(numba.config.NUMBA_NUM_THREADS))
        _POOL.append((ThreadPoolExecutor(workers, "shipgym-spread"), workers))
    pool, k = _POOL[0]
    for done in pool.map(_share, [fn] * k, [items[w::k] for w in range(k)]):
        del done


#: chunks of rows a thread in :func:`spread_rows`: a few, so that rows of unequal work
#: balance, and not many, as each chunk's call unboxes its arguments under the GIL (256
#: azimuth requests on 2 threads: 16 chunks as fast as Numba's own threads, 64 about 5 %
#: slower)
CHUNKS_PER_THREAD = 8


def spread_rows(fn: Any, n: int, *args: Any) -> list[tuple[int, Any]]:
    """``fn(lo, hi, *args)`` on consecutive chunks ``[lo, hi)`` of the rows ``0 .. n - 1``
    (n >= 1), on :func:`spread`'s threads (from two chunks): ``(lo, fn(lo, hi, *args))`` a
    chunk, in the rows' order. For a ``nogil`` compiled law over a range of independent rows
    (requests, blocks of a grid): one compiled entry point serves the serial call
    ``fn(0, n, *args)`` and every chunk, and each row gets the floats it gets alone."""
    size = -(-n // min(n, CHUNKS_PER_THREAD * max(1, int(numba.config.NUMBA_NUM_THREADS))))
    lows = list(range(0, n, size))
    out: list[Any] = [None] * len(lows)

    def one(c: int) -> None:
        out[c] = fn(lows[c], min(lows[c] + size, n), *args)

    _on_threads(one, list(range(len(lows))))
    return list(zip(lows, out, strict=True))


# ---- laws by address ------------------------------------------------------------------------
# The loop receives each law as the address of its compiled code (an int): an int argument
# costs nothing to pass, where Numba's first-class function arguments cost microseconds per
# call to unbox, and a loop over ints and arrays is compiled once and cached on disk.
#: compilation off: the "address" is a key of the function
_PY_FUNCS: dict[int, Any] = {}
#: (function, signature) -> the address of its compiled code
_ADDRESSES: dict[tuple[Any, Any], int] = {}


def address(fn: Any, sig: Any) -> int:
    """The address of ``fn``'s compiled code for ``sig`` (:func:`kernel`), to pass to the loop;
    where compilation is off, a key under which the loop finds the Python function."""
    if _DISABLED or not hasattr(fn, "overloads"):
        _PY_FUNCS[id(fn)] = fn
        return id(fn)
    found = _ADDRESSES.get((fn, sig))
    if found is None:
        from numba.experimental.function_type import _get_jit_address

        kernel(fn, sig)
        found = _ADDRESSES[fn, sig] = int(_get_jit_address(fn, sig))
    return found


def function_at(sig: Any) -> Any:
    """An intrinsic ``f(addr) -> function`` that makes a first-class function of ``sig`` from
    the address of its compiled code (Numba's calling convention, :func:`address`)."""
    if _DISABLED:
        return lambda addr: _PY_FUNCS[addr]
    from llvmlite import ir
    from numba.core import cgutils
    from numba.extending import intrinsic

    fty = types.FunctionType(sig)

    @intrinsic
    def function_at(typingctx, addr):  # type: ignore[no-untyped-def]
        def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
            sfunc = cgutils.create_struct_proxy(fty)(context, builder)
            ptr = builder.inttoptr(args[0], ir.IntType(8).as_pointer())
            null = ir.Constant(ir.IntType(8).as_pointer(), None)
            sfunc.c_addr = null
            sfunc.py_addr = null
            sfunc.jit_addr = ptr
            return sfunc._getvalue()

        return fty(types.int64), codegen

    return function_at


#: ``accel_at(addr)``: the hull acceleration compiled at ``addr`` (:data:`ACCEL_SIG`)
accel_at = function_at(ACCEL_SIG)
#: ``law_at(addr)``: the actuator law compiled at ``addr`` (:data:`LAW_SIG`)
law_at = function_at(LAW_SIG)
#: a law over a range of rows: (first, end, integrator, stop_on_contact, h, table) -> code
#: (the physics loop, :func:`shipgym.sim.step.run`)
ROWS_SIG = types.int64(types.int64, types.int64, types.int64, types.boolean, _f8,
                       types.int64[::1])  # fmt: skip
#: ``rows_at(addr)``: the law over rows compiled at ``addr`` (:data:`ROWS_SIG`)
rows_at = function_at(ROWS_SIG)
