"""Command-line hooks of the RL subcommands, for ``shipgym.cli`` to mount.

- ``shipgym train ppo|sac [--env ID] [--timesteps N] [--seed S] [--n-envs K] [--out DIR]
  [--resume CKPT] [--residual] [--observer NAME] [--max-minutes M] ...``:
  :func:`add_train_parser`, :func:`cmd_train`;
- ``shipgym bench controllers [--task harbour|station-keeping] [--vessel NAME]
  [--controllers ...] [--seeds 10] [--json PATH] [--markdown PATH]``:
  :func:`add_bench_controllers_parser`, :func:`cmd_bench_controllers`;
- ``shipgym bench rl [--suite harbour|tracking|station-keeping-star-hercules]
  [--method NAME=SPEC,...] [--seeds 10] [--split all|held-in|held-out] [--json PATH]
  [--markdown PATH] [--figure PNG]``:
  :func:`add_bench_rl_parser`, :func:`cmd_bench_rl` (the protocol of :mod:`shipgym.rl.protocol`);
- ``shipgym plot training RUN_DIR [RUN_DIR ...] --out FIG.png`` (one line per run) or
  ``shipgym plot training --group NAME=RUN_DIR[,RUN_DIR...] [--group ...] --out FIG.png`` (the
  mean and 95 % band of each group): :func:`add_plot_parser`, :func:`cmd_plot_training`
  (learning curves, :mod:`shipgym.viz.training`).

The commands return an exit status; user mistakes raise ``ValueError`` /
``FileNotFoundError`` (and ``ImportError`` without the ``rl`` extra) with a one-line message,
which ``shipgym.cli.main`` turns into ``shipgym: error: ...``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from shipgym._argtypes import (
    MAX_COUNT,
    add_bench_outputs,
    add_executor_options,
    bench_settings,
    bounded_float,
    bounded_int,
    executor_of,
    nonneg_int,
    parse_wind,
    path_arg,
    seed_int,
)
from shipgym._io import progress_enabled
from shipgym._text import num

__all__ = [
    "add_bench_controllers_parser",
    "add_bench_rl_parser",
    "add_plot_parser",
    "add_train_parser",
    "cmd_bench_controllers",
    "cmd_bench_rl",
    "cmd_plot_training",
    "cmd_train",
]


def add_train_parser(sub: Any) -> argparse.ArgumentParser:
    """Add ``train`` to the ``shipgym`` subparsers (``sub = ap.add_subparsers(...)``)."""
    p = sub.add_parser(
        "train",
        help="train a learned controller (PPO or SAC) on the tracking task",
        description="Train PPO or SAC on shipgym/BlueLadyTracking-v0 or another env id "
        "(--env; hyperparameters: shipgym/rl/hyperparams/<algo>.yml, rl-zoo3's layout). "
        "Writes model.zip, best_model.zip, checkpoints, evaluations.json, progress.csv (and "
        "tb/ for TensorBoard when installed), config.yml and command.txt into --out.",
    )
    p.add_argument("algo", choices=["ppo", "sac"], help="algorithm")
    p.add_argument(
        "--env",
        default=None,
        metavar="ID",
        help="training env id: a block of the hyperparameter file "
        "(default shipgym/BlueLadyTracking-v0; e.g. shipgym/StationKeeping-v0)",
    )
    p.add_argument(
        "--timesteps",
        type=bounded_int(1, 10**10),
        default=None,
        help="environment steps, 1 to 10**10 (YAML default)",
    )
    p.add_argument("--seed", type=seed_int, default=0, help="seed of everything, >= 0 (0)")
    p.add_argument(
        "--seeds",
        type=seed_int,
        nargs="+",
        default=None,
        metavar="S",
        help="train once per seed, in parallel (--workers, --executor); each run in OUT/seed<S>",
    )
    p.add_argument(
        "--workers", type=bounded_int(1, 1024), default=None, help="parallel runs with --seeds"
    )
    add_executor_options(p)
    p.add_argument(
        "--n-envs",
        type=bounded_int(1, 256),
        default=None,
        help="parallel environments, 1-256 (YAML)",
    )
    p.add_argument("--out", type=path_arg, default=None, help="output folder")
    p.add_argument(
        "--resume",
        type=path_arg,
        default=None,
        metavar="CKPT",
        help="continue a checkpoint/model written by 'shipgym train' (nothing is unpickled: "
        "the model is rebuilt from its metadata, weights read with weights_only=True)",
    )
    p.add_argument(
        "--residual",
        action="store_true",
        help="learn a residual on top of the tuned PID (YAML 'residual' block)",
    )
    p.add_argument(
        "--observer",
        default=None,
        help="what the policy sees: kbf (YAML default), dkf, ekf or truth",
    )
    p.add_argument("--hyperparams", type=path_arg, default=None, help="another YAML file")
    p.add_argument(
        "--eval-freq",
        type=nonneg_int,
        default=None,
        help="steps between periodic evaluations (0: none); harbour manoeuvre or station "
        "keeping, after the env id",
    )
    p.add_argument(
        "--checkpoint-freq",
        type=nonneg_int,
        default=None,
        help="steps between checkpoints (0: none)",
    )
    p.add_argument(
        "--vec-env",
        choices=["dummy", "subproc", "batched"],
        default=None,
        help="dummy: one process; subproc: a process per env; batched: the native batched env "
        "(open-water tasks; every env in one array computation)",
    )
    p.add_argument(
        "--max-minutes",
        type=bounded_float(0.0, 525_600.0, lo_open=True, unit="min"),
        default=None,
        help="wall-clock limit (> 0, at most a year)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument(
        "--log-interval",
        type=bounded_float(0.0, 86_400.0, lo_open=True, unit="s"),
        default=None,
        metavar="SECONDS",
        help="without a progress bar (off a terminal, --no-progress, --seeds), a progress line "
        "on stderr every SECONDS of wall-clock time: steps, fps, time left, the last "
        "evaluation (default 30)",
    )
    p.add_argument("--verbose", type=bounded_int(0, 2), default=0, help="SB3 verbosity, 0-2 (0)")
    p.set_defaults(func=cmd_train, folders={"--out": ("*",)})  # a model folder
    return p


def cmd_train(args: argparse.Namespace) -> int:
    """Run :func:`shipgym.rl.train.train` from parsed arguments; prints a summary."""
    from shipgym.controllers.learned import algorithm_class
    from shipgym.rl.train import train

    algorithm_class(args.algo)  # a missing RL extra fails here, with what to run
    if args.hyperparams is not None and not args.hyperparams.exists():
        raise FileNotFoundError(f"hyperparameter file {str(args.hyperparams)!r} does not exist")
    from shipgym._io import on_interrupt

    # SIGINT and SIGTERM stop training through shipgym.cli.main (exit 130 / 143); say what stays
    on_interrupt(lambda: _kept_by_train(args.out))
    if args.seeds is not None:
        return _train_many(args)
    if args.workers is not None or args.executor != "process":
        raise ValueError("--workers and --executor go with --seeds (several training runs)")
    res = train(
        args.algo,
        timesteps=args.timesteps,
        seed=args.seed,
        n_envs=args.n_envs,
        out=args.out,
        resume=args.resume,
        residual=args.residual,
        observer=args.observer,
        env_id=_env_id(args),
        hyperparams=args.hyperparams,
        eval_freq=args.eval_freq,
        checkpoint_freq=args.checkpoint_freq,
        vec_env=args.vec_env,
        max_minutes=args.max_minutes,
        progress=progress_enabled(args.no_progress),
        verbose=args.verbose,
        log_interval_s=_log_interval(args),
    )
    print(f"trained {res.num_timesteps} steps in {res.wall_time_s / 60:.1f} min")
    print(f"  model       {res.model_path}")
    if res.best_model_path is not None:
        print(f"  best model  {res.best_model_path}")
    if res.evaluations:
        e = res.evaluations[-1]
        if e.get("evaluation") == "station-keeping":
            print(
                f"  last station-keeping evaluation: {num(e['inside_fraction'], '.1%')} of the "
                f"time within {e['radius_m']:g} m, mean return {num(e['return'], '.4g')}"
            )
        else:
            print(
                f"  last harbour evaluation: {e['completed']}/{e['runs']} completed, "
                f"J_c {num(e['J_c'])}"
            )
    print(f"  command     {res.metadata.command}")
    return 0


def _train_many(args: argparse.Namespace) -> int:
    """``shipgym train ... --seeds S ...``: :func:`shipgym.rl.train.train_seeds`."""
    from shipgym.rl.train import train_seeds

    if args.resume is not None:
        raise ValueError("--resume continues one run; it does not go with --seeds")
    rows = train_seeds(
        args.algo, args.seeds, out=args.out, executor=executor_of(args), workers=args.workers,
        progress=progress_enabled(args.no_progress), timesteps=args.timesteps,
        n_envs=args.n_envs, residual=args.residual, observer=args.observer,
        env_id=_env_id(args), hyperparams=args.hyperparams, eval_freq=args.eval_freq,
        checkpoint_freq=args.checkpoint_freq, vec_env=args.vec_env,
        max_minutes=args.max_minutes, verbose=args.verbose, log_interval_s=_log_interval(args),
    )  # fmt: skip
    for r in rows:
        print(f"seed {r['seed']}: {r['num_timesteps']} steps in {r['wall_time_s'] / 60:.1f} min, "
              f"model {r['model_path']}")  # fmt: skip
    return 0


def _log_interval(args: argparse.Namespace) -> float:
    """``--log-interval`` or :data:`~shipgym.rl.train.LOG_INTERVAL_S` (s)."""
    from shipgym.rl.train import LOG_INTERVAL_S

    return LOG_INTERVAL_S if args.log_interval is None else float(args.log_interval)


def _env_id(args: argparse.Namespace) -> str:
    """``--env`` or the default training env id."""
    from shipgym.rl.train import DEFAULT_ENV_ID

    env = args.env
    if env is None:
        return DEFAULT_ENV_ID
    if args.resume is not None:
        raise ValueError("--resume continues the checkpoint's own env id; drop --env")
    return str(env)


def _kept_by_train(out: Path | None) -> str:
    """What an interrupted ``train`` leaves: the checkpoints so far (the model.zip comes last)."""
    if out is not None and (out / "checkpoints").is_dir():
        n = len(list((out / "checkpoints").glob("*.zip")))
        return f"{n} checkpoint(s) kept in {out / 'checkpoints'}; no final model.zip written"
    return "no final model.zip written (checkpoints, if any, are in the output folder)"


def add_bench_controllers_parser(bsub: Any) -> argparse.ArgumentParser:
    """Add ``controllers`` to the ``shipgym bench`` subparsers."""
    b = bsub.add_parser(
        "controllers",
        help="pid vs lq vs the learned policies on the harbour manoeuvre or station keeping",
    )
    b.add_argument(
        "--controllers",
        nargs="+",
        default=None,
        metavar="NAME",
        help="pid, pid-seed, lq, the shipped baselines ppo (pure PPO), sac (pure SAC), "
        "ppo-residual (PPO on the PID) of the task and vessel, ppo:PATH, sac:PATH (a shipgym "
        "model, or a stable-baselines3 / rl-zoo3 zip with its args.yml and vecnormalize.pkl) "
        "(default: pid, lq and every shipped baseline of the task and vessel)",
    )
    b.add_argument(
        "--task",
        choices=["harbour", "station-keeping"],
        default="harbour",
        help="the harbour manoeuvre (default) or 1000 s of station keeping "
        "(shipgym/StationKeeping-v0)",
    )
    b.add_argument(
        "--vessel",
        default=None,
        help="vessel name or package path (default: blue-lady for the harbour, star-hercules "
        "for station keeping)",
    )
    b.add_argument(
        "--seeds",
        type=bounded_int(1, MAX_COUNT),
        default=10,
        help=f"seeds 0..N-1 per controller, 1 <= N <= {MAX_COUNT} (10)",
    )
    b.add_argument(
        "--observer", default="default", help="kbf when available (default), truth, dkf, ekf, ..."
    )
    b.add_argument(
        "--wind",
        type=parse_wind,
        default=None,
        metavar="SPEED@FROM_DEG",
        help="mean wind (default: the task's: 3@300 for the Blue Lady's harbour manoeuvre, the "
        "vessel's nominal wind from 300 deg for station keeping, 10@300 for star-hercules)",
    )
    add_bench_outputs(b)
    b.add_argument("--no-progress", action="store_true")
    b.set_defaults(func=cmd_bench_controllers)
    return b


def cmd_bench_controllers(args: argparse.Namespace) -> int:
    """Run :func:`shipgym.rl.bench.bench_controllers`; print and write the table / rows."""
    import sys

    from shipgym.catalogue import check_controller
    from shipgym.rl.bench import (
        bench_controllers,
        bench_title,
        controller_table,
        default_controllers,
        default_vessel,
        missing_baselines,
        station_table,
    )
    from shipgym.runner import ENV_DEFAULT

    vessel = default_vessel(args.task) if args.vessel is None else args.vessel
    if args.vessel is not None:
        from shipgym.dynamics.vessel import load_vessel
        from shipgym.envs.registration import resolve_env_id, task_fits_vessel

        env_id = resolve_env_id(args.task, vessel)
        if not task_fits_vessel(env_id, load_vessel(vessel)):
            raise ValueError(
                f"vessel {vessel!r} cannot do {args.task} (it needs thrust in surge, sway and "
                "yaw at rest); choose a positioning vessel, e.g. star-hercules or wimpey-sealab"
            )
    task_id = "shipgym/StationKeeping-v0" if args.task == "station-keeping" else "harbour"
    from shipgym.rl.interop import resolve_controller

    # ppo:PATH / sac:PATH of an SB3 or rl-zoo3 model (no shipgym.json): imported with the
    # env id and vecnormalize.pkl next to it (shipgym.rl.interop)
    controllers = [resolve_controller(c) for c in args.controllers or ()] or default_controllers(
        args.task, vessel
    )
    for name in controllers:
        # unknown names and missing model files fail before any work
        check_controller(name, task=task_id, vessel=vessel)
    if args.observer not in ("default", "truth"):
        from shipgym.observers import make_observer

        make_observer(args.observer)
    from shipgym.bench import row_log, write_bench_outputs

    missing = missing_baselines(args.task, vessel) if args.controllers is None else []
    if missing:
        print(
            f"shipgym: note: baselines registered for {args.task} ({vessel}) but not shipped, "
            f"left out: {', '.join(missing)}",
            file=sys.stderr,
        )
    total = len(controllers) * max(args.seeds, 0)
    log = row_log(args.json, args.markdown, total, bench_settings(args), args.resume)
    wind = ENV_DEFAULT if args.wind is None else args.wind
    t0 = time.perf_counter()
    rows = bench_controllers(
        controllers,
        seeds=args.seeds,
        task=args.task,
        vessel=vessel,
        wind=wind,
        observer=args.observer,
        workers=args.workers,
        progress=progress_enabled(args.no_progress),
        on_row=log.add,
        known=log.known,
        executor=executor_of(args),
    )
    wall = time.perf_counter() - t0
    if args.task == "harbour" and args.wind is None and vessel == "blue-lady":
        wind = "3@300"
    title = bench_title(rows, wind, args.task)
    table = station_table(rows) if args.task == "station-keeping" else controller_table(rows)
    write_bench_outputs(title, table, rows, wall, json_path=args.json, markdown=args.markdown)
    log.discard(args.json or args.markdown)
    return 0


def add_bench_rl_parser(bsub: Any) -> argparse.ArgumentParser:
    """Add ``rl`` to the ``shipgym bench`` subparsers."""
    from shipgym.rl.protocol import SUITES

    b = bsub.add_parser(
        "rl",
        help="the learned baselines' protocol: IQM and 95 %% CI over training seeds, held-in "
        "and held-out conditions",
        description="Evaluates every run (training seed) of every method on every condition "
        "of a suite (held-in: inside the training conditions, on unseen episode seeds; "
        "held-out: winds above the training range, DGPS dropouts and outliers, current) and "
        "reports the interquartile mean with its 95 % stratified-bootstrap interval over "
        "training seeds (Agarwal et al. 2021), per split and per condition.",
    )
    b.add_argument("--suite", choices=list(SUITES), default="harbour",
                   help="the task and its conditions (default: harbour)")  # fmt: skip
    b.add_argument(
        "--method",
        action="append",
        default=None,
        metavar="NAME=SPEC[,SPEC...]",
        help="a method and its runs, one controller spec per training seed: "
        "ppo=ppo:runs/s0/model.zip,ppo:runs/s1/model.zip, a glob ppo=ppo:runs/ppo/seed*/"
        "best_model.zip, or one name (pid, lq, ppo: the shipped baseline); repeat for more "
        "methods (default: pid, lq and every shipped baseline of the suite, one run each)",
    )
    b.add_argument("--seeds", type=bounded_int(1, MAX_COUNT), default=10,
                   help=f"episode seeds 0..N-1 per run and condition, 1 <= N <= {MAX_COUNT} "
                   "(10)")  # fmt: skip
    b.add_argument("--split", choices=["all", "held-in", "held-out"], default="all",
                   help="the conditions to run (default: all)")  # fmt: skip
    b.add_argument("--observer", default="default",
                   help="kbf when available (default), truth, dkf, ekf, ...")  # fmt: skip
    b.add_argument("--reps", type=bounded_int(100, 100_000), default=2000,
                   help="bootstrap resamples of the intervals (2000)")  # fmt: skip
    add_bench_outputs(b, json_help="the episodes, cells and aggregates (JSON, with units)")
    b.add_argument("--figure", type=path_arg, default=None, metavar="PNG",
                   help="performance profiles of the task metric, one panel per split")  # fmt: skip
    b.add_argument("--no-progress", action="store_true")
    b.set_defaults(func=cmd_bench_rl)
    return b


def cmd_bench_rl(args: argparse.Namespace) -> int:
    """Run :func:`shipgym.rl.protocol.bench_rl`; print and write the tables, JSON, figure."""
    from shipgym.bench import row_log, write_bench_outputs
    from shipgym.rl.protocol import (
        SCHEMA_VERSION,
        UNITS,
        bench_rl,
        default_methods,
        parse_method,
        profile_figure,
        rl_tables,
        suite,
        summarise,
    )

    s = suite(args.suite)
    methods = [parse_method(m) for m in args.method] if args.method else default_methods(s)
    n_conds = sum(1 for c in s.conditions
                  if args.split == "all" or c.held_out == (args.split == "held-out"))  # fmt: skip
    total = sum(len(m.runs) for m in methods) * n_conds * args.seeds
    log = row_log(args.json, args.markdown, total, bench_settings(args), args.resume)
    t0 = time.perf_counter()
    rows = bench_rl(
        args.suite,
        methods,
        seeds=args.seeds,
        observer=args.observer,
        split=args.split,
        workers=args.workers,
        progress=progress_enabled(args.no_progress),
        on_row=log.add,
        known=log.known,
        executor=executor_of(args),
    )
    wall = time.perf_counter() - t0
    summary = summarise(rows, args.suite, reps=args.reps)
    title = (
        f"bench rl, suite {s.name} ({s.task}, {s.vessel}; trained on: {s.training}), "
        f"{args.seeds} episode seeds per run and condition, observer "
        f"{rows[0]['observer'] if rows else args.observer}"
    )
    header = {
        "schema_version": SCHEMA_VERSION,
        "units": UNITS,
        "suite": {
            "name": s.name,
            "task": s.task,
            "vessel": s.vessel,
            "training": s.training,
            "radius_m": s.radius_m,
            "duration_s": s.duration_s,
            "conditions": [c.to_dict() for c in s.conditions],
        },  # fmt: skip
        "methods": [{"name": m.name, "runs": list(m.runs)} for m in methods],
        "interval": {
            "statistic": "IQM",
            "level": 0.95,
            "bootstrap": "stratified percentile",
            "reps": args.reps,
            "over": "training seeds (runs), conditions kept",
        },  # fmt: skip
        "cells": summary["cells"],
        "aggregates": summary["aggregates"],
        "per_condition": summary["per_condition"],
    }
    write_bench_outputs(title, rl_tables(summary, args.suite), rows, wall,
                        json_path=args.json, markdown=args.markdown, header=header)  # fmt: skip
    if args.figure is not None:
        print(f"wrote {profile_figure(summary, args.suite, args.figure, reps=args.reps)}")
    log.discard(args.json or args.markdown)
    return 0


def add_plot_parser(sub: Any) -> argparse.ArgumentParser:
    """Add ``plot`` (with ``plot training``) to the ``shipgym`` subparsers."""
    p = sub.add_parser("plot", help="figures of finished work: 'plot training' (learning curves)")
    psub = p.add_subparsers(dest="what", required=True)
    t = psub.add_parser(
        "training",
        help="learning curves of 'shipgym train' runs: return and harbour completion (or "
        "station-keeping fraction) against steps",
        description="Reads progress.csv (time/total_timesteps, rollout/ep_rew_mean) and "
        "evaluations.json of each run folder and draws one line per run (RUN_DIR ...), or, "
        "per --group (the training seeds of one method), the mean over its runs with a 95 % "
        "percentile-bootstrap band over the runs (seeded), on the steps every run of the "
        "group covers (each run interpolated linearly onto them). Give either RUN_DIRs or "
        "--group, not both. Example: shipgym plot training --group "
        "ppo=runs/ppo/seed0,runs/ppo/seed1 --group sac=runs/sac/seed* --out curves.png",
    )
    t.add_argument("runs", nargs="*", type=path_arg, metavar="RUN_DIR",
                   help="output folders of 'shipgym train' (--out), one line each")  # fmt: skip
    t.add_argument(
        "--group",
        action="append",
        default=None,
        metavar="NAME=RUN_DIR[,RUN_DIR...]",
        help="a method and its runs (training seeds), drawn as their mean and 95 %% band, "
        "labelled 'NAME (n=K)' (one run: its line, no band); a folder with * is a glob "
        "(ppo=runs/ppo/seed*); repeat for more methods. No J_c panel with groups",
    )
    t.add_argument("--out", type=path_arg, required=True, metavar="FIG.png",
                   help="the figure (PNG)")  # fmt: skip
    t.add_argument("--labels", nargs="+", default=None, metavar="NAME",
                   help="legend names, one per RUN_DIR (default: the folder names); not "
                   "with --group, whose legend is NAME (n=K)")  # fmt: skip
    t.set_defaults(func=cmd_plot_training)
    return p


def cmd_plot_training(args: argparse.Namespace) -> int:
    """Run :func:`shipgym.viz.training.plot_training`; prints what it drew (per run, or per
    group its mean and 95 % interval at the last step every run of the group reached)."""
    from shipgym.viz.training import plot_training, read_training_run

    if args.group:
        return _plot_training_groups(args)
    path = plot_training(args.runs, args.out, labels=args.labels)
    for d in args.runs:
        c = read_training_run(d)
        last = (
            f"{100 * c.eval_score[-1]:.0f} % at {c.eval_steps[-1]:,.0f}"
            if c.eval_steps.size
            else "none"
        )
        ret = f"{c.returns[-1]:.4g} at {c.steps[-1]:,.0f}" if c.steps.size else "none"
        print(f"{d}: return {ret} steps; last {c.eval_kind} evaluation {last} steps")
    print(f"wrote {path}")
    return 0


def _plot_training_groups(args: argparse.Namespace) -> int:
    """``shipgym plot training --group NAME=RUN_DIR,... --out FIG.png``."""
    from shipgym.viz.training import (
        GroupCurve,
        group_training_curves,
        parse_group,
        plot_training,
        read_training_groups,
    )

    groups: dict[str, list[Path]] = {}
    for text in args.group:  # first: 'NAME RUN_DIR' would leave RUN_DIR as a positional
        name, dirs = parse_group(text)
        if name in groups:
            raise ValueError(f"--group {name!r} is given twice: list all its runs in one --group")
        groups[name] = dirs
    if args.runs:
        raise ValueError(
            "give RUN_DIRs (one line per run) or --group (the mean of each group), not both: "
            "put every run in a --group NAME=RUN_DIR,..."
        )
    if args.labels is not None:
        raise ValueError("--labels names RUN_DIRs; a group's legend is its NAME: drop --labels")
    path = plot_training([], args.out, groups=groups)

    def at_end(g: GroupCurve | None, scale: float, unit: str) -> str:
        if g is None:
            return "none"
        band = "" if g.low is None or g.high is None else (
            f" [95 % CI {scale * g.low[-1]:.4g}, {scale * g.high[-1]:.4g}]")  # fmt: skip
        return f"{scale * g.mean[-1]:.4g}{unit}{band} at {g.grid[-1]:,.0f} steps"

    for name, runs in read_training_groups(groups).items():
        ret, ev = group_training_curves(runs)
        kind = runs[0].eval_kind
        print(f"{name} (n={len(runs)}): mean return {at_end(ret, 1.0, '')}; mean {kind} "
              f"evaluation {at_end(ev, 100.0, ' %')}")  # fmt: skip
    print(f"wrote {path}")
    return 0
