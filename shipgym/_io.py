"""Result files that are never half-written, and interrupts that say what they kept.

Public names: ``Interrupted``, ``WriteFailed``, ``atomic_path``, ``atomic_write_text``,
``check_writable``, ``progress_enabled``, ``handle_signals``, ``interrupt_message``, ...

Design notes: docs/design/_io.md.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import tempfile
import threading
from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any, TextIO

__all__ = [
    "private_cache_dir",
    "Interrupted",
    "WriteFailed",
    "atomic_path",
    "atomic_write_text",
    "check_folder",
    "check_outputs",
    "check_writable",
    "progress_enabled",
    "handle_signals",
    "interrupt_message",
    "interrupt_status",
    "on_interrupt",
    "output_lock",
    "os_reason",
    "partial_path",
    "rrd_complete",
    "replace_together",
    "signals_held",
    "write_partial_text",
]

#: the word marking a file that is not (yet) complete
PARTIAL = "partial"


def private_cache_dir(name: str) -> Path | None:
    """The per-user cache folder ``$XDG_CACHE_HOME`` (or ``~/.cache``) ``/shipgym/<name>``,
    created private (0700) and checked writable; ``None`` where it cannot be created or
    written, or is not private (owned by another user, or writable by group or others: a
    file planted there, such as a pickle, would be trusted on loading)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    path = Path(base) / "shipgym" / name
    try:
        path.mkdir(parents=True, exist_ok=True, mode=0o700)
        st = path.stat()
        if (hasattr(os, "getuid") and st.st_uid != os.getuid()) or st.st_mode & 0o022:
            return None
        tempfile.TemporaryFile(dir=path).close()
    except OSError:
        return None
    return path


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
def signals_held() -> Iterator[None]:
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
    with signals_held():
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


#: what an interrupt of the running command keeps: (text or a function giving it, file or None)
_NOTES: list[tuple[str | Callable[[], str | None], Path | None]] = []


def on_interrupt(
    what: str | Callable[[], str | None], *, path: str | os.PathLike[str] | None = None
) -> None:
    """Say what an interrupt of the running command keeps (``"partial recording kept at X"``).

    ``what`` may be a function, called when the message is made (``None``: nothing to say).
    With ``path``, the note is reported only if that file exists then (after every clean-up
    has run). The notes are cleared when :func:`handle_signals` begins and ends.
    """
    _NOTES.append((what, None if path is None else Path(path)))


def interrupt_status(exc: BaseException) -> int:
    """The exit status of an interrupt: 128 + the signal number (130 SIGINT, 143 SIGTERM)."""
    return 128 + int(getattr(exc, "signum", signal.SIGINT))


def interrupt_message(exc: BaseException, prog: str = "shipgym") -> str:
    """One line: which signal, and what was kept (see :func:`note_kept`)."""
    name = signal.Signals(getattr(exc, "signum", signal.SIGINT)).name
    kept = []
    for what, path in _NOTES:
        text = what() if callable(what) else what
        if text and (path is None or path.exists()):
            kept.append(text)
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
    _NOTES.clear()
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
        _NOTES.clear()
        for s, h in old.items():
            with contextlib.suppress(TypeError, ValueError):
                signal.signal(s, h if h is not None else signal.SIG_DFL)


# ---- result files ----------------------------------------------------------------------------
class WriteFailed(OSError):
    """A result file could not be written; ``results`` holds what should have gone there.

    The command line prints ``results`` (JSON) on stdout, says where they went in one line on
    stderr and exits with status 2: results are never lost to a full disk or a removed folder.
    """

    def __init__(self, message: str, results: Any) -> None:
        super().__init__(message)
        self.message = message
        self.results = results

    def __str__(self) -> str:
        return self.message


def write_partial_text(path: str | os.PathLike[str], text: str) -> Path | None:
    """Write ``text`` to ``partial_path(path)`` for a later :func:`replace_together`.

    Returns the partial file, or ``None`` when ``path`` is a device or FIFO and was written
    directly. On an error the partial file is removed and the ``OSError`` raised.
    """
    dest = _destination(Path(path))
    if _direct(dest):
        with open(dest, "w", encoding="utf-8") as fh:
            fh.write(text)
        return None
    tmp = partial_path(dest)
    try:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    return tmp


#: the last 12 bytes of a finished rerun recording: the footer's magic and version (rerun
#: writes the footer, a manifest of the file, when the recording's file sink is finalised)
RRD_FOOTER = b"RRF2FOOT"


def rrd_complete(path: str | os.PathLike[str]) -> bool:
    """Whether the ``.rrd`` file at ``path`` was written to its end (its footer is there): a
    recording cut short by a full disk, a lost folder or a killed process is not."""
    try:
        with open(path, "rb") as f:
            f.seek(0, os.SEEK_END)
            if f.tell() < 12:
                return False
            f.seek(-12, os.SEEK_END)
            return f.read(8) == RRD_FOOTER
    except OSError:
        return False


def os_reason(exc: OSError) -> str:
    """``No space left on device``: the short reason of an ``OSError``."""
    return exc.strerror or str(exc)


def progress_enabled(no_progress: bool = False, stream: TextIO | None = None) -> bool:
    """Whether to draw a progress bar: not switched off and ``stream`` (stderr) is a terminal.

    Pipes and log files get no bar (a bar's ``\\r`` frames would litter them).
    """
    if no_progress:
        return False
    s: Any = sys.stderr if stream is None else stream
    try:
        return bool(s.isatty())
    except (AttributeError, ValueError):  # closed or unusual streams
        return False


def check_writable(path: Path) -> None:
    """Create the parent folder and check that ``path`` can be written, before any work.

    Raises:
        ValueError: the folder cannot be created or the file cannot be opened for writing
            (the message names the path and the reason).
    """
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        existed = path.exists()
        with path.open("a"):
            pass
        if not existed:
            path.unlink()
    except OSError as exc:
        raise ValueError(f"cannot write {path}: {exc.strerror or exc}") from exc


def check_folder(path: Path) -> None:
    """Create the output folder ``path`` and check that files can be written in it, before
    any work.

    Raises:
        ValueError: the folder cannot be created (a file in the way, no permission) or
            written (the message names the path and the reason).
    """
    try:
        path.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=path).close()
    except OSError as exc:
        raise ValueError(f"cannot write into the folder {path}: {exc.strerror or exc}") from exc


def check_outputs(
    outputs: dict[str, Path | None],
    inputs: dict[str, Path | None] | None = None,
    folders: dict[str, tuple[str, ...]] | None = None,
) -> None:
    """Refuse, before any work, outputs that would overwrite an input or each other.

    A file output is one path; a folder output (named in ``folders``) writes files of the
    given name patterns (``*.png``, ``metrics.md``) directly into its folder and nothing else,
    so a ``--json`` next to a ``--report``'s figures is fine and a ``--markdown`` named
    ``metrics.md`` in it is not. Refused: two outputs that are the same path, a file output
    that a folder output would write, an output that is an input file or lies inside an input
    folder (a vessel package), a folder output that would write over an input file.

    Args:
        outputs: option name -> the path it writes (``None``: not given).
        inputs: option name -> a path it reads (``None``: not given).
        folders: option name -> the name patterns (:mod:`fnmatch`) its folder receives.

    Raises:
        ValueError: naming both options and the path.
    """
    from fnmatch import fnmatch

    folders = folders or {}

    def real(p: Path) -> Path:
        return Path(os.path.realpath(os.path.expanduser(p)))

    outs = [(k, real(p)) for k, p in outputs.items() if p is not None]
    ins = [(k, real(p)) for k, p in (inputs or {}).items() if p is not None]

    def writes(option: str, folder: Path, path: Path) -> bool:  # the folder output writes path
        return path.parent == folder and any(fnmatch(path.name, g) for g in folders[option])

    def clash(ka: str, a: Path, kb: str, b: Path) -> bool:  # two outputs
        if a == b:
            return True
        return (ka in folders and writes(ka, a, b)) or (kb in folders and writes(kb, b, a))

    for i, (ka, a) in enumerate(outs):
        for kb, b in outs[i + 1 :]:
            if clash(ka, a, kb, b):
                raise ValueError(
                    f"{ka} {a} and {kb} {b} would overwrite each other: give them separate paths"
                )
        for kb, b in ins:
            inside = a == b or (b.is_dir() and b in a.parents)
            if inside or (ka in folders and writes(ka, a, b)):
                raise ValueError(
                    f"{ka} {a} would overwrite the input {kb} {b}: write the results elsewhere"
                )


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process: alive
        return True
    return True


@contextlib.contextmanager
def output_lock(paths: Iterable[Path | None]) -> Iterator[None]:
    """One run at a time writes a set of outputs: a lock file ``.NAME.lock`` (holding the
    process id) next to each output for the duration of the block. A second run naming any of
    them is refused before any work; a lock left by a process that no longer exists is taken
    over.

    Raises:
        ValueError: another running process holds one of the outputs (naming it and the pid).
    """
    held: list[Path] = []
    try:
        for p in sorted({Path(os.path.realpath(p)) for p in paths if p is not None}):
            lock = p.parent / f".{p.name}.lock"
            for _ in range(2):
                try:
                    fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
                except FileExistsError:
                    try:
                        pid = int(lock.read_text().strip() or "0")
                    except (OSError, ValueError):
                        pid = 0
                    if pid and pid != os.getpid() and _alive(pid):
                        raise ValueError(
                            f"{p} is being written by another run (process {pid}, lock {lock}): "
                            "wait for it, or give this run other output paths"
                        ) from None
                    with contextlib.suppress(OSError):
                        lock.unlink()  # left by a process that died
                    continue
                with os.fdopen(fd, "w") as fh:
                    fh.write(str(os.getpid()))
                held.append(lock)
                break
            else:
                raise ValueError(f"cannot lock {p} (lock file {lock})")
        yield
    finally:
        for lock in held:
            with contextlib.suppress(OSError):
                lock.unlink()
