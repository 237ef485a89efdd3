"""Benchmarks run from the command line: ``shipgym bench observers`` (Tomera 2014 Table 6 style).

Each run is one closed-loop harbour manoeuvre; runs go to worker processes in parallel
(:func:`run_jobs`). Finished rows are handed out as they come (``on_result``, e.g. a
:class:`RowLog` appending them to ``PATH.partial.jsonl``), so an interrupted benchmark keeps
them. Workers die with their parent: they ignore SIGINT (the parent handles it and stops
them), take SIGTERM's default action, and get SIGKILL when the parent dies (Linux, forked
workers: ``PR_SET_PDEATHSIG``) or see it gone (a watchdog thread, for forkserver or spawned
workers).
"""

from __future__ import annotations

import contextlib
import ctypes
import json
import math
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from shipgym._safeload import jsonable
from shipgym.metrics import CHATTER_KEYS

__all__ = [
    "DEFAULT_OBSERVERS",
    "EXECUTORS",
    "Executor",
    "RowLog",
    "bench_observers",
    "bench_scenario_kwargs",
    "table6_comparison",
    "velocity_error_evidence",
    "SCENARIO_WIND",
    "TABLE6",
    "chatter_table",
    "observer_table",
    "observer_traces",
    "row_log",
    "run_jobs",
    "mean_std",
    "mean_worst",
    "single_threaded_blas",
    "table_cell",
    "velocity_error_trace",
    "write_bench_outputs",
]

DEFAULT_OBSERVERS = ("dkf", "kbf", "ekf")
_INDICES = ("x_E", "y_E", "psi_E", "J_c")
_RMSE = ("u", "v", "r", "x", "y", "psi")


#: Tomera (2014) Table 6 (lake Silm), measured indices: x_E, y_E (m), psi_E (printed), J_c
TABLE6: dict[str, dict[str, float]] = {
    "dkf": {"x_E": 1.3523, "y_E": 0.4163, "psi_E": 377.0888, "J_c": 5.5395},
    "kbf": {"x_E": 0.2376, "y_E": 0.2984, "psi_E": 402.5533, "J_c": 4.5615},
    "ekf": {"x_E": 1.3774, "y_E": 0.4738, "psi_E": 387.4744, "J_c": 5.7259},
}
_WIND_DEFAULT = "3@300"  # the bench's wind without a scenario
SCENARIO_WIND = "scenario"  # bench_observers(wind=...): the scenario's own wind


def _one(job: tuple[Any, ...]) -> dict[str, Any]:
    from shipgym.runner import run_episode

    observer, seed, wind, controller = job[:4]
    env_kwargs = dict(job[4]) if len(job) > 4 and job[4] is not None else None
    res = run_episode(
        "harbour", controller=controller, observer=observer, seed=seed, wind=wind,
        env_kwargs=env_kwargs,
    )  # fmt: skip
    return {
        "observer": observer,
        "seed": seed,
        "completed": res["completed"],
        "quay_contact": res["quay_contact"],
        "duration_s": res["duration_s"],
        "truth": {k: res[k] for k in _INDICES},
        "measured": res["measured"],
        "rmse": res["rmse"],
        "chatter": {k: res.get(k) for k in CHATTER_KEYS},
    }


_PR_SET_PDEATHSIG = 1  # linux/prctl.h


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie, killed but not yet reaped, does not)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return True
    return state not in ("Z", "X")


def _watch_owner(owner: int) -> None:
    while _alive(owner):
        time.sleep(0.5)
    os._exit(1)


def serial_physics() -> None:
    """This process runs its compiled code on its own thread (the hull batches of
    :mod:`shipgym.sim.step`, the grids' harmonic sums): a pool's workers already fill the cores,
    and threads of their own would oversubscribe them."""
    from shipgym._jit import THREADS

    THREADS["allowed"] = False


def _serial_job(fn: Callable[[Any], Any], job: Any) -> Any:
    """``fn(job)`` in a Ray worker, with :func:`serial_physics`."""
    serial_physics()
    return fn(job)


def _worker_init(owner: int, forked: bool) -> None:
    """Initializer of the pool's workers: die with the pool's owner, leave SIGINT to it.

    ``owner``: the pid of the process that owns the pool; ``forked``: whether it is also the
    worker's parent (start method ``fork``). On Linux a forked worker gets SIGKILL when its
    parent dies (``PR_SET_PDEATHSIG``). A worker started by a forkserver (or spawned, on other
    systems) polls the owner instead: the forkserver outlives a killed owner as long as
    workers hold its "alive" pipe, so its death would never come.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C: the parent stops the pool
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # not the parent's handler, if inherited
    serial_physics()
    if forked and sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        if os.getppid() != owner:
            os._exit(1)  # the parent died before prctl took effect
        return
    threading.Thread(target=_watch_owner, args=(owner,), daemon=True).start()


def _stop_pool(pool: ProcessPoolExecutor) -> None:
    """Cancel what has not started and end the workers now (interrupt or failure)."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    # the pool's manager thread reaps the workers too (shutdown() forgets it: take it first);
    # until it has finished, a worker it reaped can still read as alive here
    manager = getattr(pool, "_executor_manager_thread", None)
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        with contextlib.suppress(Exception):
            p.terminate()
    deadline = time.monotonic() + 5.0
    for p in procs:
        with contextlib.suppress(Exception):
            p.join(max(0.0, deadline - time.monotonic()))
            if p.is_alive():
                p.kill()
                p.join(1.0)
    if manager is not None:
        manager.join(max(1.0, deadline - time.monotonic()))


#: the executors of :func:`run_jobs`: a local process pool, or Ray (the ``ray`` extra)
EXECUTORS = ("process", "ray")


@dataclass(frozen=True)
class Executor:
    """Where :func:`run_jobs` runs its jobs.

    Attributes:
        kind: ``"process"`` (a local process pool) or ``"ray"`` (Ray tasks: ``ray.init()`` on
            this machine, or the cluster at ``address``; needs the ``ray`` extra).
        address: a Ray cluster's address (``"ray://host:10001"``, ``"auto"``); ``None`` starts
            a local Ray instance with ``workers`` CPUs for the call (and stops it after).
    """

    kind: str = "process"
    address: str | None = None

    def __post_init__(self) -> None:
        if self.kind not in EXECUTORS:
            raise ValueError(
                f"unknown executor {self.kind!r}; choose one of {', '.join(EXECUTORS)}"
            )
        if self.address is not None and self.kind != "ray":
            raise ValueError("an executor address needs kind='ray'")

    @classmethod
    def coerce(cls, x: Executor | str | None) -> Executor:
        """An :class:`Executor` from itself, a kind name or ``None`` (the process pool)."""
        if x is None:
            return cls()
        if isinstance(x, Executor):
            return x
        if isinstance(x, str):
            return cls(x)
        raise TypeError(f"executor must be an Executor or one of {', '.join(EXECUTORS)}, got {x!r}")


def _import_ray() -> Any:
    try:
        import ray
    except ImportError:
        raise ImportError(
            "the Ray executor needs the ray extra: pip install 'shipgym[ray]' (or make ray)"
        ) from None
    return ray


def _run_ray(
    fn: Callable[[Any], Any], jobs: Sequence[tuple[int, Any]], n: int, address: str | None,
    done: Callable[[int, Any], None],
) -> None:  # fmt: skip
    """The ``(index, job)`` pairs as Ray tasks (:func:`run_jobs`), results handed to ``done``
    as they finish."""
    ray = _import_ray()
    started = False
    if not ray.is_initialized():
        kw: dict[str, Any] = {"log_to_driver": False, "configure_logging": False}
        local = {"num_cpus": n, "include_dashboard": False}
        if address is None and not os.environ.get("RAY_ADDRESS"):
            try:  # a local instance of n CPUs
                ray.init(**kw, **local)
            except ValueError as exc:  # Ray found a running local cluster and joins it
                if "existing cluster" not in str(exc):
                    raise
                ray.init(**kw)
        else:  # a cluster is taken as it is: Ray refuses local-only settings for one
            ray.init(address=address, **kw)
        started = True
    try:
        task = ray.remote(num_cpus=1)(_serial_job)
        pending = {task.remote(fn, job): i for i, job in jobs}
        try:
            while pending:
                ready, _ = ray.wait(list(pending), num_returns=1)
                for ref in ready:
                    done(pending.pop(ref), ray.get(ref))
        except BaseException:
            for ref in pending:
                with contextlib.suppress(Exception):
                    ray.cancel(ref, force=True)
            raise
    finally:
        if started:
            ray.shutdown()


def run_jobs(
    fn: Callable[[Any], Any],
    jobs: Sequence[Any],
    *,
    workers: int | None = None,
    progress: bool = True,
    desc: str = "runs",
    on_result: Callable[[int, Any], None] | None = None,
    start_method: str | None = None,
    executor: Executor | str | None = None,
    known: Mapping[int, Any] | None = None,
) -> list[Any]:
    """``[fn(job) for job in jobs]`` in worker processes, in order, with a progress bar.

    ``known``: results already at hand (job index -> result, an interrupted run's rows,
    :meth:`RowLog.resume`): those jobs are not run again.

    ``fn`` must be a module-level function (picklable). Forks unless torch is loaded in this
    process (forking a process with torch's thread pools can hang): then ``forkserver``
    (``start_method`` chooses another). ``on_result(index, result)`` is called in this process
    as each job finishes (in the order they finish). On an exception or an interrupt
    (``KeyboardInterrupt``, also SIGTERM under ``shipgym.cli.main``) the jobs not started are
    cancelled and the workers ended before it propagates; workers also die if this process is
    killed.

    ``executor`` (:class:`Executor`, ``"process"`` or ``"ray"``): with Ray the jobs are Ray
    tasks on a local instance of ``workers`` CPUs (or the cluster at its address); a job's
    result depends on the job only (its seed travels with it), so every executor gives the
    same list.
    """
    from tqdm import tqdm

    ex = Executor.coerce(executor)
    n = workers or min(len(jobs), os.cpu_count() or 1)
    if ex.kind == "ray":
        _import_ray()  # a missing extra fails before any work
    bar = tqdm(total=len(jobs), disable=not progress, desc=desc, unit="run")
    out: list[Any] = [None] * len(jobs)
    known = known or {}
    for i, res in known.items():
        out[i] = res
    bar.update(len(known))
    todo = [(i, job) for i, job in enumerate(jobs) if i not in known]

    def done(i: int, res: Any) -> None:
        out[i] = res
        if on_result is not None:
            on_result(i, res)
        bar.update(1)

    try:
        if ex.kind == "ray":
            _run_ray(fn, todo, max(n, 1), ex.address, done)
        elif n <= 1:
            for i, job in todo:
                done(i, fn(job))
        else:
            method = start_method or ("forkserver" if "torch" in sys.modules else None)
            ctx = multiprocessing.get_context(method)
            forked = ctx.get_start_method() == "fork"
            pool = ProcessPoolExecutor(
                max_workers=n, mp_context=ctx, initializer=_worker_init,
                initargs=(os.getpid(), forked),
            )  # fmt: skip
            try:
                pending = {pool.submit(fn, job): i for i, job in todo}
                while pending:
                    finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                    for fut in sorted(finished, key=pending.__getitem__):
                        done(pending.pop(fut), fut.result())
            except BaseException:
                _stop_pool(pool)
                raise
            pool.shutdown(wait=True)
    finally:
        bar.close()
    return out


class RowLog:
    """The finished rows of a benchmark, appended as JSON lines (``{"index": i, "row": ...}``)
    to ``path`` as they come (``path`` ``None``: counted only), after a first line with the
    bench's settings (``{"settings": ...}``).

    Pass :meth:`add` as ``on_result``; :meth:`discard` the file once the complete result is
    written. The file of an earlier, interrupted bench is replaced when the first row comes,
    unless this log resumes it (:meth:`resume`: its rows are :attr:`known` and are not run
    again). A file that cannot be written is reported once on stderr and then only counted.
    """

    def __init__(
        self,
        path: str | os.PathLike[str] | None,
        total: int,
        settings: Mapping[str, Any] | None = None,
    ) -> None:
        self.path = None if path is None else Path(path)
        self.total = int(total)
        self.count = 0
        self.written_to: Path | None = None
        # as read back from the file (tuples as lists; a configuration object by its repr)
        self.settings = json.loads(json.dumps(dict(settings or {}), default=repr))
        #: the rows of an interrupted run this log resumes (job index -> row)
        self.known: dict[int, Any] = {}
        self._append = False

    @classmethod
    def resume(
        cls, path: str | os.PathLike[str], total: int, settings: Mapping[str, Any]
    ) -> RowLog:
        """The log of an interrupted run at ``path``, continued: its rows become :attr:`known`.

        Raises:
            ValueError: no such file, a damaged one, or one of a run with other settings
                (naming the settings that differ).
        """
        log = cls(path, total, settings)
        p = Path(path)
        if not p.is_file():
            raise ValueError(f"nothing to resume: no partial rows at {p} (run without --resume)")
        items = []
        for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1):
            if not line.endswith("}"):
                continue  # a last line cut short by the interrupt
            try:
                items.append(json.loads(line))
            except json.JSONDecodeError:
                raise ValueError(f"cannot resume from {p}: line {n} is not a JSON row") from None
        head = items[0] if items and "settings" in items[0] else None
        if head is None or head["settings"] != log.settings:
            was = {} if head is None else head["settings"]
            diff = sorted(k for k in {*was, *log.settings} if was.get(k) != log.settings.get(k))
            raise ValueError(
                f"cannot resume from {p}: it holds the rows of a run with other settings "
                f"({', '.join(diff) or 'none recorded'}); run with the same options, or "
                "without --resume"
            )
        log.known = {int(d["index"]): d["row"] for d in items[1:] if 0 <= d["index"] < total}
        log.count = len(log.known)
        log._append = True
        return log

    def add(self, index: int, row: Any) -> None:
        """Append one finished row."""
        self.count += 1
        if self.path is None:
            return
        try:
            first = not self._append
            with open(self.path, "w" if first else "a", encoding="utf-8") as fh:
                if first:
                    fh.write(json.dumps({"settings": self.settings}) + "\n")
                # (NaN kept as JSON's NaN token: a resumed row is the row that was computed)
                fh.write(json.dumps({"index": index, "row": row}, default=_plain) + "\n")
            self._append = True
        except OSError as exc:
            print(
                f"shipgym: warning: cannot keep the finished rows in {self.path} "
                f"({exc.strerror or exc}); they are kept in memory only",
                file=sys.stderr,
            )
            self.path = None

    def summary(self) -> str:
        """One phrase for an interrupt message."""
        if self.written_to is not None:
            return f"the rows were written to {self.written_to}"
        if self.count == 0:
            return f"none of the {self.total} runs had finished"
        if self.path is None or not self.path.exists():
            return f"{self.count} of {self.total} runs had finished (not kept: no --json)"
        return (
            f"{self.count} of {self.total} finished rows kept at {self.path} (the same command "
            "with --resume continues)"
        )

    def discard(self, written_to: str | os.PathLike[str] | None = None) -> None:
        """Remove the file: the complete result is written (to ``written_to``)."""
        if self.path is not None:
            self.path.unlink(missing_ok=True)
        if written_to is not None:
            self.written_to = Path(written_to)

    @staticmethod
    def read(path: str | os.PathLike[str]) -> list[Any]:
        """The rows of a row log, in job order."""
        lines = Path(path).read_text(encoding="utf-8").splitlines()
        items = [json.loads(line) for line in lines if line.strip()]
        rows = [d for d in items if "index" in d]
        return [d["row"] for d in sorted(rows, key=lambda d: d["index"])]


def _plain(x: Any) -> Any:
    """A NumPy value in a row as a plain Python one (for the row log)."""
    if isinstance(x, np.ndarray | np.generic):
        return x.tolist()
    raise TypeError(f"a benchmark row holds a {type(x).__name__}, not JSON data")


def row_log(
    json_path: Path | None,
    markdown: Path | None,
    total: int,
    settings: Mapping[str, Any] | None = None,
    resume: bool = False,
) -> Any:
    """A :class:`RowLog` next to the bench's output (``PATH.partial.jsonl``), named in the
    message of an interrupt; with ``resume``, the interrupted run's log continued
    (:meth:`RowLog.resume`, which needs ``--json`` or ``--markdown``)."""
    from shipgym._io import on_interrupt, partial_path

    out = json_path or markdown
    usable = out is not None and (not out.exists() or out.is_file())  # not /dev/stdout
    path = partial_path(out, ".jsonl") if usable and out is not None else None
    if resume:
        if path is None:
            raise ValueError(
                "--resume continues the partial rows of --json or --markdown: give one"
            )
        log = RowLog.resume(path, total, settings or {})
    else:
        log = RowLog(path, total, settings)
    on_interrupt(log.summary)
    return log


def write_bench_outputs(
    title: str,
    table: str,
    rows: list[dict[str, Any]],
    wall: float,
    *,
    json_path: Path | None = None,
    markdown: Path | None = None,
    header: Mapping[str, Any] | None = None,
) -> None:
    """Print a benchmark's title and table; write its rows (JSON) and table (markdown).

    Each file is written atomically (a complete file or the earlier one). ``header``: more
    keys of the JSON document before its rows (a ``schema_version``, ``units``).

    Raises:
        shipgym._io.WriteFailed: a file could not be written; its content is in ``results``
            (the ``shipgym`` command prints it on stdout and exits with status 2).
    """
    from shipgym._io import WriteFailed, atomic_write_text, os_reason

    print(title)
    print(table)
    print(f"{len(rows)} runs in {wall:.1f} s")
    outputs = (
        (
            json_path,
            json.dumps(jsonable({"title": title, **(header or {}), "rows": rows}), indent=2),
            "rows",
        ),  # fmt: skip
        (markdown, f"{title}\n\n{table}\n", "table"),
    )
    for path, text, what in outputs:
        if path is None:
            continue
        try:
            atomic_write_text(path, text)
        except OSError as exc:
            why = f"cannot write the {what} to {path} ({os_reason(exc)})"
            raise WriteFailed(why, text) from None
        print(f"{what} written to {path}")


def velocity_error_trace(
    observer: str,
    seed: int = 0,
    wind: Any = "3@300",
    controller: str = "pid-smooth",
    env_kwargs: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Velocity estimation errors ``[u, v, r]`` over one harbour episode (for plots).

    ``wind``: any form of :meth:`WindConfig.coerce <shipgym.disturbances.WindConfig.coerce>`;
    ``env_kwargs``: further env arguments (a scenario's, :meth:`Scenario.env_kwargs`), they
    win over ``wind``. Returns ``t`` (s), ``err_nu`` (estimate - truth) and ``nu`` (truth).
    """
    from shipgym.records import step_record
    from shipgym.runner import build_env, step_episode

    kw = {"wind": wind, **(env_kwargs or {})}
    env = build_env("harbour", observer=observer, controller=controller, **kw)
    t, err, nu = [], [], []

    def keep(info: dict[str, Any]) -> None:
        rec = step_record(info)
        t.append(rec.t)
        err.append(rec.nav.nu - rec.truth.nu)
        nu.append(np.asarray(rec.truth.nu, dtype=float))

    try:
        step_episode(env, seed, on_step=keep)
    finally:
        env.close()
    return {"t": np.array(t), "err_nu": np.array(err), "nu": np.array(nu)}


def _trace_job(job: tuple[Any, ...]) -> tuple[str, dict[str, Any]]:
    seed = job[4] if len(job) > 4 else 0
    return job[0], velocity_error_trace(job[0], seed, job[1], job[2], job[3])


def observer_traces(
    observers: Sequence[str],
    wind: Any,
    workers: int | None = None,
    controller: str = "pid-smooth",
    env_kwargs: dict[str, Any] | None = None,
) -> dict[str, dict[str, Any]]:
    """:func:`velocity_error_trace` of seed 0 for each observer, in parallel."""
    jobs = [(o, wind, controller, env_kwargs) for o in observers]
    return dict(run_jobs(_trace_job, jobs, workers=workers, progress=False))


def velocity_error_evidence(trace: dict[str, Any], short_period: float = 20.0) -> dict[str, Any]:
    """Noise and lag of an observer's velocity estimate from a :func:`velocity_error_trace`.

    Returns per DOF ``[u, v, r]``: ``rmse`` (m/s, m/s, rad/s), ``hf_fraction`` (-, the share
    of the error variance at periods below ``short_period`` s, from a periodogram: noise
    that a controller's derivative term passes on), ``lag`` (s, the shift that maximises the
    correlation of the estimate with the truth, 0 to 30 s: the estimate's delay) and
    ``lf_rmse`` (the error's RMSE at periods of ``short_period`` s and longer: lag and bias).
    """
    t = np.asarray(trace["t"], dtype=float)
    err = np.asarray(trace["err_nu"], dtype=float)
    nu = np.asarray(trace["nu"], dtype=float)
    if t.size < 8:
        raise ValueError(f"the trace is too short for spectra ({t.size} samples)")
    dt = float(np.median(np.diff(t)))
    est = nu + err
    out: dict[str, Any] = {"rmse": [], "hf_fraction": [], "lf_rmse": [], "lag": []}
    f = np.fft.rfftfreq(t.size, dt)
    for j in range(3):
        e = err[:, j] - err[:, j].mean()
        p = np.abs(np.fft.rfft(e)) ** 2
        hf = f > 1.0 / short_period
        tot = float(p[1:].sum())
        out["rmse"].append(float(np.sqrt(np.mean(err[:, j] ** 2))))
        out["hf_fraction"].append(float(p[hf].sum() / tot) if tot > 0 else 0.0)
        lo = np.fft.rfft(err[:, j])
        lo[hf] = 0.0
        out["lf_rmse"].append(float(np.sqrt(np.mean(np.fft.irfft(lo, t.size) ** 2))))
        x, y = nu[:, j] - nu[:, j].mean(), est[:, j] - est[:, j].mean()
        shifts = range(0, min(int(round(30.0 / dt)), t.size // 4) + 1)
        cc = [float(x[: t.size - s] @ y[s:]) for s in shifts]
        out["lag"].append(float(int(np.argmax(cc)) * dt))
    return out


def bench_scenario_kwargs(scenario: Any) -> dict[str, Any] | None:
    """The env arguments of a harbour scenario (a name, file or
    :class:`~shipgym.scenarios.Scenario`) for the bench, or ``None`` for none."""
    if scenario is None:
        return None
    from shipgym.scenarios import Scenario, load_scenario

    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    if sc.env != "harbour":
        raise ValueError(
            f"the observer bench runs the harbour manoeuvre; scenario {sc.name!r} is for "
            f"{sc.env!r}: give a harbour scenario (e.g. tomera2014-lake)"
        )
    return sc.env_kwargs()


def bench_observers(
    observers: Sequence[str] = DEFAULT_OBSERVERS,
    seeds: int = 10,
    wind: Any = SCENARIO_WIND,
    controller: str = "pid-smooth",
    workers: int | None = None,
    progress: bool = True,
    on_row: Callable[[int, dict[str, Any]], None] | None = None,
    known: Mapping[int, Any] | None = None,
    executor: Executor | str | None = None,
    scenario: Any = None,
) -> list[dict[str, Any]]:
    """Run the manoeuvre for every observer and seed; one row per run, in a fixed order.

    ``executor``: where the runs go (:func:`run_jobs`; the process pool by default, or Ray).

    ``scenario``: a harbour scenario (name, file or ``Scenario``: ``"tomera2014-lake"``) whose
    plant, wind, waves, current, sensors, plan and start pose every run uses; ``None``: the
    harbour env's defaults. ``wind``: any form of :meth:`WindConfig.coerce
    <shipgym.disturbances.WindConfig.coerce>`, checked before any run; by default
    (:data:`SCENARIO_WIND`) the scenario's wind, or ``"3@300"`` (3 m/s from 300 deg) without
    a scenario; given, it replaces the scenario's.
    ``on_row(index, row)`` gets each row as its run finishes (e.g. :meth:`RowLog.add`).
    """
    from shipgym.disturbances import WindConfig

    env_kwargs = bench_scenario_kwargs(scenario)
    if isinstance(wind, str) and wind == SCENARIO_WIND:
        wind = env_kwargs["wind"] if env_kwargs is not None else _WIND_DEFAULT
    wind = WindConfig.coerce(wind, name="wind")
    if env_kwargs is not None:
        env_kwargs["wind"] = wind
    if isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1:
        raise ValueError(f"seeds must be an int >= 1 (runs seeds 0..seeds-1), got {seeds!r}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):  # fmt: skip
        raise ValueError(f"workers must be None (one per CPU) or an int >= 1, got {workers!r}")
    if isinstance(observers, str) or not observers:
        raise ValueError(f"observers must be a non-empty list of names, got {observers!r}")
    jobs = [(obs, s, wind, controller, env_kwargs) for obs in observers for s in range(seeds)]
    return run_jobs(
        _one, jobs, workers=workers, progress=progress, desc="observers x seeds",
        on_result=on_row, known=known, executor=executor,
    )  # fmt: skip


def mean_std(
    values: Sequence[float | None],
    fmt: str = ".4f",
    *,
    scale: float = 1.0,
    sep: str = " +- ",
    missing: str = "n/a",
    single: bool = False,
) -> str:
    """``"mean +- std"`` of the finite values (a failed run's index is NaN or None) times
    ``scale``, or ``missing``; with ``single=True`` one value is written alone."""
    x = scale * np.array([np.nan if v is None else v for v in values], dtype=float)
    x = x[np.isfinite(x)]
    if x.size == 0:
        return missing
    if single and x.size == 1:
        return f"{x[0]:{fmt}}"
    return f"{x.mean():{fmt}}{sep}{x.std():{fmt}}"


def table_cell(values: Sequence[float | None], fmt: str, scale: float = 1.0) -> str:
    """A sweep table's cell: ``"mean ± std"`` over the seeds, one seed's value alone, ``-``
    for none (:func:`mean_std`)."""
    return mean_std(values, fmt, scale=scale, sep=" ± ", missing="-", single=True)


def _get(d: dict[str, Any] | None, key: str) -> float | None:
    return None if d is None else d.get(key)


def observer_table(rows: Sequence[dict[str, Any]]) -> str:
    """A markdown table in the form of Tomera (2014) Table 6 (mean +- std over seeds).

    Means and standard deviations are over the runs whose indices are defined (a run that
    failed has none, see :func:`shipgym.metrics.honest_indices`); ``completed`` counts them."""
    names = list(dict.fromkeys(r["observer"] for r in rows))
    head = (
        "| observer | runs | completed | x_E (m) | y_E (m) | psi_E (deg) | J_c "
        "| J_c truth | RMSE u (m/s) | RMSE v (m/s) | RMSE r (deg/s) |"
    )
    lines = [head, "|" + "---|" * 11]
    for name in names:
        rs = [r for r in rows if r["observer"] == name]
        meas = {k: [_get(r["measured"], k) for r in rs] for k in _INDICES}
        truth = [_get(r["truth"], "J_c") for r in rs]
        rm = {k: [_get(r["rmse"], k) for r in rs] for k in ("u", "v", "r")}
        done = sum(r["completed"] and not r["quay_contact"] for r in rs)
        ms = mean_std
        lines.append(
            f"| {name} | {len(rs)} | {done}/{len(rs)} | {ms(meas['x_E'])} | {ms(meas['y_E'])} "
            f"| {ms(meas['psi_E'], '.3f')} | {ms(meas['J_c'])} | {ms(truth)} "
            f"| {ms(rm['u'], '.5f')} | {ms(rm['v'], '.5f')} | {ms(rm['r'], '.4f')} |"
        )
    return "\n".join(lines) + "\n\n" + chatter_table(rows)


def mean_worst(values: Any, fmt: str, worst: Callable[[Any], Any] = max) -> str:
    """``"mean [worst]"`` of the finite ``values`` (one per seed) in the format ``fmt``; ``-``
    where none is finite (the chatter tables' cell)."""
    c = np.asarray(values, dtype=float)
    c = c[np.isfinite(c)]
    return "-" if c.size == 0 else f"{c.mean():{fmt}} [{worst(c):{fmt}}]"


def chatter_table(rows: Sequence[dict[str, Any]]) -> str:
    """A markdown table of the command chatter (:func:`shipgym.metrics.command_chatter`) per
    observer: per channel (``a / b / c`` in the vessel's channel order), the mean over the
    seeds and, in brackets, the worst seed."""
    names = list(dict.fromkeys(r["observer"] for r in rows))
    cols = (
        ("reversals_per_min", "reversals / min", ".2f", 1.0, max),
        ("limit_fraction", "at a limit (%)", ".1f", 100.0, max),
        ("starts_per_min", "starts / min", ".2f", 1.0, max),
        ("zero_fraction", "at zero (%)", ".0f", 100.0, max),
        ("hf_variance_fraction", "variance at periods < 20 s (%)", ".1f", 100.0, max),
        ("travel_per_min", "travel (1/min)", ".2f", 1.0, max),
    )
    head = "| observer | " + " | ".join(c[1] for c in cols) + " |"
    lines = [
        "Command chatter per channel (mean over seeds [worst seed]):",
        "",
        head,
        "|" + "---|" * (len(cols) + 1),
    ]
    for name in names:
        rs = [(r.get("chatter") or {}) for r in rows if r["observer"] == name]
        cells = []
        for key, _, fmt, scale, worst in cols:
            per = [v.get(key) for v in rs if v.get(key)]
            if not per:
                cells.append("n/a")
                continue
            x = scale * np.array(per, dtype=float)  # (seeds, channels)
            cells.append(" / ".join(mean_worst(x[:, j], fmt, worst) for j in range(x.shape[1])))
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def table6_comparison(rows: Sequence[dict[str, Any]]) -> str:
    """Measured x_E, y_E against Tomera (2014) Table 6 (ratio simulated / lake, mean over
    the runs with defined indices) and the observer ranking by measured ``x_E + y_E``
    (best first; J_c is not used: its ``0.01 psi_E`` term is dominated by Table 6's printed
    psi_E of 377-403, which cannot be a mean heading error in degrees)."""
    names = list(dict.fromkeys(r["observer"] for r in rows))
    lines = [
        "| observer | x_E (m) | Table 6 x_E | ratio | y_E (m) | Table 6 y_E | ratio "
        "| x_E + y_E (m) | within 3x |",
        "|" + "---|" * 9,
    ]
    score: dict[str, float] = {}
    for name in names:
        rs = [r for r in rows if r["observer"] == name]
        m = {}
        for k in ("x_E", "y_E"):
            v = np.array([np.nan if _get(r["measured"], k) is None else _get(r["measured"], k)
                          for r in rs], dtype=float)  # fmt: skip
            v = v[np.isfinite(v)]
            m[k] = float(v.mean()) if v.size else math.nan
        score[name] = m["x_E"] + m["y_E"]
        ref = TABLE6.get(name)
        if ref is None:
            lines.append(f"| {name} | {m['x_E']:.4f} | - | - | {m['y_E']:.4f} | - | - "
                         f"| {score[name]:.4f} | - |")  # fmt: skip
            continue
        rx, ry = m["x_E"] / ref["x_E"], m["y_E"] / ref["y_E"]
        ok = all(1.0 / 3.0 <= r <= 3.0 for r in (rx, ry))
        lines.append(
            f"| {name} | {m['x_E']:.4f} | {ref['x_E']:.4f} | {rx:.2f} | {m['y_E']:.4f} "
            f"| {ref['y_E']:.4f} | {ry:.2f} | {score[name]:.4f} | {'yes' if ok else 'no'} |"
        )
    finite = {k: v for k, v in score.items() if math.isfinite(v)}
    ranking = " < ".join(sorted(finite, key=finite.__getitem__))
    paper = " < ".join(sorted(TABLE6, key=lambda k: TABLE6[k]["x_E"] + TABLE6[k]["y_E"]))
    lines += ["", f"ranking by measured x_E + y_E (best first): {ranking or 'n/a'}; "
              f"Tomera (2014) Table 6: {paper}"]  # fmt: skip
    return "\n".join(lines)


@contextlib.contextmanager
def single_threaded_blas() -> Iterator[None]:
    """One BLAS thread in the worker processes started inside (set before they load numpy):
    the runs are small-matrix work, and threaded BLAS in every worker oversubscribes the
    cores (5x slower on 2 cores)."""
    keys = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
    old = {k: os.environ.get(k) for k in keys}
    os.environ.update(dict.fromkeys(keys, "1"))
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
