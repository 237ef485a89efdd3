"""Result files that are never half-written, and interrupts that say what they kept.

Files: every result file (recordings, run and bench JSON, reports) is written under a name
that says it is partial, in the folder of the final file, and renamed onto the final name
(``os.replace``, atomic on one file system) only when it is complete. A process killed at any
moment therefore leaves the earlier file intact, plus at most a file whose name contains
``.partial``:

- :func:`partial_path`: the user-facing partial name of a file, ``run.rrd`` ->
  ``run.partial.rrd`` (the suffix is kept, so ``rerun run.partial.rrd`` still opens it);
- :func:`atomic_path`: a context manager yielding a temporary path (``run.partial-<pid>.json``)
  renamed onto the destination when the block ends without an exception, removed otherwise;
- :func:`atomic_write_text`: write a text file that way;
- :func:`replace_together`: rename several complete files onto their final names at once, with
  SIGINT and SIGTERM held back, removing the old destinations first so that a new file never
  ends up next to a stale partner of an earlier run.

A destination that exists but is not a regular file (``/dev/stdout``, ``/dev/full``, a FIFO) is
written directly: a device cannot be replaced by a rename.

Interrupts: :func:`handle_signals` makes SIGTERM raise :class:`Interrupted` (a
``KeyboardInterrupt``) like SIGINT does, so the same clean-up runs for both; code that keeps
something on its way out records it with :func:`note_kept`, and the command line reports it in
one line (:func:`interrupt_message`) and exits with ``128 + signal number`` (130, 143).
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

__all__ = [
    "Interrupted",
    "atomic_path",
    "atomic_write_text",
    "handle_signals",
    "interrupt_message",
    "interrupt_status",
    "note_kept",
    "partial_path",
    "replace_together",
]

#: the word marking a file that is not (yet) complete
PARTIAL = "partial"


def partial_path(path: str | os.PathLike[str], suffix: str | None = None) -> Path:
    """``run.rrd`` -> ``run.partial.rrd`` (``suffix``: another suffix, e.g. ``".jsonl"``)."""
    p = Path(path)
    return p.with_name(f"{p.stem}.{PARTIAL}{p.suffix if suffix is None else suffix}")


def _direct(path: Path) -> bool:
    """True for an existing destination that is not a regular file (a device, a FIFO)."""
    return path.exists() and not path.is_file()


def _destination(path: Path) -> Path:
    """The file a rename must replace: the target of a symbolic link, else ``path``."""
    return Path(os.path.realpath(path)) if path.is_symlink() else path


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; rename it onto ``path`` when the block succeeds.

    On an exception (``KeyboardInterrupt`` included) the temporary file is removed and
    ``path`` is left as it was. A ``path`` that is a device or a FIFO is yielded itself.
    """
    dest = _destination(Path(path))
    if _direct(dest):
        yield dest
        return
    tmp = dest.with_name(f"{dest.stem}.{PARTIAL}-{os.getpid()}{dest.suffix}")
    try:
        yield tmp
        os.replace(tmp, dest)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def atomic_write_text(path: str | os.PathLike[str], text: str, *, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` through :func:`atomic_path` (flushed to disk first).

    Raises:
        OSError: the file could not be written (``path`` is then unchanged).
    """
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding=encoding) as fh:
            fh.write(text)
            fh.flush()
            if tmp.is_file():
                os.fsync(fh.fileno())
    return Path(path)


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """Hold SIGINT and SIGTERM back (delivered when the block ends); main thread, POSIX only."""
    if not hasattr(signal, "pthread_sigmask") or threading.current_thread() is not (
        threading.main_thread()
    ):
        yield
        return
    held = {signal.SIGINT, signal.SIGTERM}
    old = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def replace_together(
    moves: Sequence[tuple[Path, Path]], *, remove: Iterable[Path] = ()
) -> list[Path]:
    """Rename each complete ``(source, destination)`` pair; returns the destinations.

    The old destinations (and the stale files in ``remove``, e.g. the JSON of an earlier run
    whose new JSON could not be written) are removed first, then the sources renamed, with
    SIGINT and SIGTERM held back: a process killed in between leaves no new file next to an
    old partner. Devices and FIFOs are never removed.

    Raises:
        OSError: a rename failed (e.g. the folder was removed during the run).
    """
    dests = [(Path(src), _destination(Path(dst))) for src, dst in moves]
    with _signals_held():
        for p in [*(d for _, d in dests), *(_destination(Path(r)) for r in remove)]:
            if p.is_file():
                p.unlink()
        for src, dst in dests:
            os.replace(src, dst)
    return [d for _, d in dests]


# ---- interrupts ------------------------------------------------------------------------------
class Interrupted(KeyboardInterrupt):
    """SIGINT or SIGTERM arrived (``signum``); a ``KeyboardInterrupt``, so clean-up is shared."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = int(signum)


def note_kept(exc: BaseException, what: str) -> None:
    """Record on an interrupt ``exc`` what was kept (``"partial recording at X"``)."""
    kept = getattr(exc, "kept", None)
    if not isinstance(kept, list):
        kept = []
        exc.kept = kept  # type: ignore[attr-defined]
    kept.append(what)


def interrupt_status(exc: BaseException) -> int:
    """The exit status of an interrupt: 128 + the signal number (130 SIGINT, 143 SIGTERM)."""
    return 128 + int(getattr(exc, "signum", signal.SIGINT))


def interrupt_message(exc: BaseException, prog: str = "shipgym") -> str:
    """One line: which signal, and what was kept (see :func:`note_kept`)."""
    name = signal.Signals(getattr(exc, "signum", signal.SIGINT)).name
    kept: list[str] = list(getattr(exc, "kept", None) or [])
    tail = "; ".join(kept) if kept else "nothing was written"
    return f"{prog}: interrupted ({name}); {tail}"


@contextlib.contextmanager
def handle_signals() -> Iterator[None]:
    """Within the block, SIGINT and SIGTERM raise :class:`Interrupted` (main thread only).

    The first signal raises; the handlers then go back to the defaults, so a second Ctrl-C
    (``KeyboardInterrupt`` again) or SIGTERM (immediate exit) stops a clean-up that hangs.
    The previous handlers are restored when the block ends.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    sigs = [signal.SIGINT, signal.SIGTERM]
    old: dict[int, Any] = {s: signal.getsignal(s) for s in sigs}

    def handler(signum: int, frame: Any) -> None:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        raise Interrupted(signum)

    for s in sigs:
        if old[s] is not signal.SIG_IGN:  # e.g. SIGINT of a background job stays ignored
            signal.signal(s, handler)
    try:
        yield
    finally:
        for s, h in old.items():
            with contextlib.suppress(TypeError, ValueError):
                signal.signal(s, h if h is not None else signal.SIG_DFL)
