"""Validated command-line values, in one place: argparse types and the one-line error parser.

Every number the ``shipgym`` command takes goes through one of these types, so a bad value
ends as ``shipgym: error: argument --seed: must be a whole number >= 0, got '-1'`` (exit
status 2) before any work starts. The bounds are part of each option's definition (its
``help`` names them); :data:`MAX_SEED` etc. document the shared ones.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn

__all__ = [
    "MAX_COUNT",
    "MAX_SEED",
    "MAX_WORKERS",
    "OneLineParser",
    "add_bench_outputs",
    "add_executor_options",
    "bounded_float",
    "executor_of",
    "bounded_int",
    "nonneg_int",
    "parse_wind",
    "positive_int",
    "seed_int",
]

#: largest seed accepted (numpy's SeedSequence takes any int >= 0; 2**63 - 1 keeps seeds int64)
MAX_SEED = 2**63 - 1
#: largest count of seeds / runs in one benchmark (a bigger job list is a typo, not a plan)
MAX_COUNT = 100_000
#: largest number of worker processes (each holds a MuJoCo model, ~100 MB)
MAX_WORKERS = 256


def _fmt(x: float) -> str:
    return f"{x:g}"


def bounded_int(
    lo: int, hi: int | None = None, what: str = "a whole number", rng: str | None = None
) -> Callable[[str], int]:
    """An argparse type: an int ``lo <= n <= hi`` (``hi`` ``None``: no upper bound).

    ``rng`` replaces the range's wording in the message (default ``">= lo"`` or
    ``"from lo to hi"``).
    """
    if rng is None:
        rng = f">= {lo}" if hi is None else f"from {lo} to {hi}"

    def parse(text: str) -> int:
        try:
            n = int(str(text).strip(), 10)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {what} {rng}, got {text!r}") from None
        if n < lo or (hi is not None and n > hi):
            raise argparse.ArgumentTypeError(f"must be {what} {rng}, got {text!r}")
        return n

    parse.__name__ = f"int {rng}"
    return parse


def bounded_float(
    lo: float | None = None,
    hi: float | None = None,
    *,
    lo_open: bool = False,
    unit: str = "",
) -> Callable[[str], float]:
    """An argparse type: a finite float in ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``)."""
    u = f" {unit}" if unit else ""
    parts = []
    if lo is not None:
        parts.append(f"{'>' if lo_open else '>='} {_fmt(lo)}{u}")
    if hi is not None:
        parts.append(f"<= {_fmt(hi)}{u}")
    rng = "a finite number" + (" " + " and ".join(parts) if parts else "")

    def parse(text: str) -> float:
        try:
            x = float(str(text).strip())
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {rng}, got {text!r}") from None
        ok = math.isfinite(x)
        if ok and lo is not None:
            ok = x > lo if lo_open else x >= lo
        if ok and hi is not None:
            ok = x <= hi
        if not ok:
            raise argparse.ArgumentTypeError(f"must be {rng}, got {text!r}")
        return x

    parse.__name__ = rng
    return parse


#: options that do not change a benchmark's rows (how and where it runs, what it writes)
RUN_ONLY = ("workers", "json", "markdown", "executor", "ray_address", "no_progress", "resume",
            "func", "folders", "report", "figures")  # fmt: skip


def add_resume_option(p: argparse.ArgumentParser) -> None:
    """A benchmark's ``--resume``: continue an interrupted run from its partial rows."""
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted run of the same options from the finished "
                   "rows it kept (PATH.partial.jsonl beside --json or --markdown)")  # fmt: skip


def bench_settings(args: argparse.Namespace) -> dict[str, Any]:
    """The options that decide a benchmark's rows (all but :data:`RUN_ONLY`): a resumed run
    must have the same."""
    return {k: v for k, v in sorted(vars(args).items()) if k not in RUN_ONLY}


def ray_address(text: str) -> str:
    """An argparse type: a Ray address (``ray://host:10001``, ``host:6379``, ``auto``), not
    empty or blank (which would silently mean a local instance)."""
    if not str(text).strip() or any(c.isspace() for c in str(text)):
        raise argparse.ArgumentTypeError(
            f"must be a Ray address such as ray://host:10001 or auto, got {text!r}"
        )
    return str(text)


def path_arg(text: str) -> Path:
    """An argparse type: a file or folder path, not empty (``Path("")`` would mean the
    current folder)."""
    if not str(text).strip():
        raise argparse.ArgumentTypeError(f"must be a file or folder path, got {text!r}")
    return Path(text)


path_arg.__name__ = "path"


def parse_wind(text: str) -> Any:
    """The ``--wind`` argparse type: :meth:`WindConfig.parse` (``"3@300"``: 3 m/s from 300 deg).

    Returns a :class:`~shipgym.disturbances.WindConfig`; a malformed or out-of-range value
    becomes an ``argparse`` error (one line, exit status 2).
    """
    from shipgym.disturbances import WindConfig

    try:
        return WindConfig.parse(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


#: a seed: a whole number from 0 to :data:`MAX_SEED`
seed_int = bounded_int(0, MAX_SEED, rng=">= 0 (at most 2**63 - 1)")
#: a whole number >= 0 (e.g. a frequency where 0 disables)
nonneg_int = bounded_int(0)
#: a whole number >= 1
positive_int = bounded_int(1)


def add_executor_options(p: argparse.ArgumentParser) -> None:
    """A benchmark's ``--executor process|ray`` and ``--ray-address`` options."""
    p.add_argument("--executor", choices=["process", "ray"], default="process",
                   help="run the jobs in a local process pool (default) or as Ray tasks "
                   "(the ray extra)")  # fmt: skip
    p.add_argument("--ray-address", type=ray_address, default=None, metavar="ADDRESS",
                   help="a Ray cluster (ray://host:10001, auto); default: a local Ray "
                   "instance of --workers CPUs")  # fmt: skip


def add_bench_outputs(b: argparse.ArgumentParser, json_help: str | None = None) -> None:
    """A benchmark's ``--workers``, ``--json``, ``--markdown``, executor and ``--resume``
    options (every ``shipgym bench`` command has them)."""
    b.add_argument(
        "--workers", type=bounded_int(1, MAX_WORKERS), default=None,
        help=f"processes, 1 to {MAX_WORKERS} (default: CPUs)",
    )  # fmt: skip
    b.add_argument("--json", type=path_arg, default=None, metavar="PATH", help=json_help)
    b.add_argument("--markdown", type=path_arg, default=None, metavar="PATH")
    add_executor_options(b)
    add_resume_option(b)


def executor_of(args: argparse.Namespace) -> Any:
    """The :class:`shipgym.bench.Executor` of :func:`add_executor_options`' options."""
    from shipgym.bench import Executor

    if args.ray_address is not None and args.executor != "ray":
        raise ValueError("--ray-address needs --executor ray")
    return Executor(args.executor, args.ray_address)


class OneLineParser(argparse.ArgumentParser):
    """``argparse.ArgumentParser`` whose errors are one line: ``shipgym: error: ...``.

    argparse prints the usage block and then ``prog: error: message``; here the message
    alone (with a pointer to ``--help``) goes to stderr, and the exit status stays 2.
    Subparsers inherit the class.
    """

    def error(self, message: str) -> NoReturn:
        root = self.prog.split()[0] if self.prog else "shipgym"
        msg = " ".join(str(message).split())
        self.exit(2, f"{root}: error: {msg} (see '{self.prog} --help')\n")

    def _check_value(self, action: argparse.Action, value: Any) -> None:
        """argparse's check of a value against ``choices`` (a subcommand included), with
        the close names suggested (:func:`shipgym._text.did_you_mean`)."""
        try:
            super()._check_value(action, value)  # type: ignore[misc]
        except argparse.ArgumentError:
            from shipgym._text import did_you_mean

            choices = [str(c) for c in action.choices or ()]
            raise argparse.ArgumentError(
                action,
                f"invalid choice: {value!r}{did_you_mean(value, choices)}; choose from "
                f"{', '.join(choices)}",
            ) from None
