"""The ``shipgym`` command.

``shipgym run SCENARIO``  closed-loop run (harbour manoeuvre, station keeping, tracking) with a
                          progress bar, a metrics table and an optional JSON file;
``shipgym demo``          open-loop turn of the Blue Lady in gusty wind, with a short summary;
``shipgym list``          env ids, scenarios, controllers, plant variants, wind models.

User mistakes end with a one-line error and exit status 2, never with a traceback.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["main", "parse_wind"]


def parse_wind(text: str) -> tuple[float, float]:
    """Parse ``SPEED@FROM_DEG`` (m/s, degrees the wind comes from) into ``(speed, from_rad)``."""
    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*@\s*(-?[0-9]*\.?[0-9]+)\s*", text)
    if not m:
        raise argparse.ArgumentTypeError(
            f"malformed wind {text!r}: expected SPEED@FROM_DEG, e.g. 3@300 (3 m/s from 300 deg)"
        )
    return float(m.group(1)), math.radians(float(m.group(2)))


def _cmd_list(args: argparse.Namespace) -> int:
    from shipgym import ENV_IDS
    from shipgym.controllers.wrappers import CONTROLLERS
    from shipgym.disturbances import BLENDERMANN
    from shipgym.dynamics import ACTUATOR_NAMES, PLANT_VARIANTS
    from shipgym.envs.make import SCENARIOS

    print("env ids        :", ", ".join(ENV_IDS))
    print("scenarios      :", ", ".join(f"{k} ({v})" for k, v in SCENARIOS.items()))
    print("controllers    :")
    for name, spec in CONTROLLERS.items():
        print(f"  {name:12s} {spec.description}")
    print(f"  {'ppo':12s} the shipped PPO baseline (residual on pid, through the kbf observer)")
    print(f"  {'ppo:PATH':12s} a PPO model trained with 'shipgym train ppo' (sac:PATH likewise)")
    from shipgym.observers import observer_names
    from shipgym.observers.sensors import SENSOR_PRESETS
    from shipgym.scenarios import SCENARIOS as SCENARIO_PRESETS

    print("observers      :", ", ".join(["truth", *observer_names()]))
    print("sensor presets :", ", ".join(SENSOR_PRESETS))
    print("scenario files :", ", ".join(SCENARIO_PRESETS), "(or a .yaml/.toml path)")
    print("plant variants :", ", ".join(PLANT_VARIANTS))
    print("wind models    :", ", ".join(f"blendermann:{k}" for k in BLENDERMANN))
    print("actuators      :", ", ".join(ACTUATOR_NAMES))
    return 0


def run_episode(
    scenario: str,
    *,
    controller: str = "pid",
    observer: str | None = None,
    seed: int = 0,
    wind: tuple[float, float] | None = (3.0, math.radians(300.0)),
    plant: str = "default",
    progress: bool = False,
    env_kwargs: dict[str, Any] | None = None,
    record: Path | None = None,
    spawn: bool = False,
    report: Path | None = None,
) -> dict[str, Any]:
    """Run one closed-loop episode and return its results (the ``--json`` content).

    Args:
        scenario: env scenario (``harbour``, ``station-keeping``, ``tracking``) or env id.
        controller, observer: names (see ``shipgym list``); observer ``None`` = truth.
        seed: episode seed.
        wind: ``(speed m/s, from rad)`` or ``None`` (no aerodynamic loads).
        plant: plant variant.
        progress: show a progress bar.
        env_kwargs: further environment arguments (they win over ``wind`` and ``plant``).
        record: write a rerun recording (``.rrd``) of the episode here.
        spawn: also try to open the rerun viewer.
        report: write PNG figures and ``metrics.md`` into this folder.
    """
    import numpy as np

    import shipgym
    from shipgym.disturbances import WindConfig

    kwargs: dict[str, Any] = {
        "wind": None if wind is None else WindConfig(speed=wind[0], direction_from=wind[1]),
        "plant": plant,
    }
    kwargs.update(env_kwargs or {})
    from shipgym.controllers.learned import is_learned_controller

    if is_learned_controller(controller):
        from shipgym.controllers.learned import make_learned_env

        # the learned policy runs with the observer it was trained with unless one is named
        obs_kw = {} if observer is None else {"observer": observer}
        env = make_learned_env(scenario, controller, **obs_kw, **kwargs)
    else:
        env = shipgym.make(scenario, observer=observer, controller=controller, **kwargs)
    if report is not None and record is None:
        record = report / "run.rrd"
    if record is not None:
        from shipgym.viz import RecordEpisode

        env = RecordEpisode(env, record, spawn=spawn)
    wc = env.unwrapped.wind_config  # type: ignore[attr-defined]
    wind_out = (
        None if wc is None else {"speed": wc.speed, "from_deg": math.degrees(wc.direction_from)}
    )
    limit = env.spec.max_episode_steps if env.spec is not None else None
    bar = _progress(total=limit, enabled=progress, desc=f"{scenario} seed {seed}")
    t0 = time.perf_counter()
    try:
        env.reset(seed=seed)
        zero = np.zeros(3, dtype=np.float32)
        terminated = truncated = False
        info: dict[str, Any] = {}
        while not (terminated or truncated):
            _, _, terminated, truncated, info = env.step(zero)
            bar.update(1)
            bar.set_postfix(leg=info["leg"] + 1, t=f"{info['t']:.0f}s", refresh=False)
        metrics = env.unwrapped.episode_metrics()  # type: ignore[attr-defined]
    finally:
        bar.close()
        env.close()
    wall = time.perf_counter() - t0
    files: list[str] = []
    if record is not None:
        files.append(str(record))
    if report is not None:
        from shipgym.viz import write_report

        run = getattr(env, "last_run", None)
        files += [str(p) for p in write_report(run if run is not None else record, report)]
    measured = metrics.get("measured")
    return {
        "scenario": scenario,
        "env_id": env.spec.id if env.spec is not None else None,
        "controller": controller,
        "observer": _observer_of(env) or "truth",
        "seed": seed,
        "plant": plant,
        "wind": wind_out,
        "completed": metrics["completed"],
        "legs_completed": metrics["legs_completed"],
        "duration_s": metrics["duration_s"],
        "quay_contact": metrics["quay_contact"],
        "terminated": bool(terminated),
        "truncated": bool(truncated),
        "x_E": metrics["x_E"],
        "y_E": metrics["y_E"],
        "psi_E": metrics["psi_E"],
        "J_c": metrics["J_c"],
        "measured": measured,
        "leg_times": metrics["leg_times"],
        "thrust_mean_abs": metrics["thrust_mean_abs"],
        "thrust_total_variation": metrics["thrust_total_variation"],
        "saturated_fraction": metrics["saturated_fraction"],
        "rmse": info.get("estimation_rmse"),
        "wall_time_s": wall,
        "files": files,
    }


def _observer_of(env: Any) -> str | None:
    """Name of the observer in a wrapper stack (``None``: the controller sees the truth)."""
    while hasattr(env, "env"):
        name = getattr(env, "observer_name", None)
        if name is not None:
            return str(name)
        env = env.env
    return None


def _progress(total: int | None, enabled: bool, desc: str) -> Any:
    from tqdm import tqdm

    return tqdm(total=total, disable=not enabled, desc=desc, unit="step", leave=False)


def _fmt(x: Any) -> str:
    return f"{x:.4f}" if isinstance(x, float) else str(x)


def _print_table(res: dict[str, Any]) -> None:
    meas = res.get("measured") or {}
    print(
        f"{res['scenario']} | controller {res['controller']} | observer {res['observer']} | "
        f"seed {res['seed']} | plant {res['plant']} | wind {res['wind']}"
    )
    rows = [
        ("completed", res["completed"], ""),
        ("legs completed", res["legs_completed"], ""),
        ("duration", round(res["duration_s"], 1), "s"),
        ("quay contact", res["quay_contact"], ""),
    ]
    for name, val, unit in rows:
        print(f"  {name:16s} {_fmt(val):>10s} {unit}")
    print(f"  {'index':16s} {'truth':>10s} {'measured':>10s}")
    for key, unit in (("x_E", "m"), ("y_E", "m"), ("psi_E", "deg"), ("J_c", "")):
        print(f"  {key:16s} {_fmt(res[key]):>10s} {_fmt(meas.get(key, 'n/a')):>10s} {unit}")
    print(f"  leg times (s)    {[round(t, 1) for t in res['leg_times']]}")
    print(f"  mean |thrust| (N) {[round(t, 1) for t in res['thrust_mean_abs']]}")
    print(f"  time saturated   {[round(t, 3) for t in res['saturated_fraction']]} (fraction)")
    if res.get("rmse"):
        r = res["rmse"]
        print(
            "  estimation RMSE  "
            f"x {r['x']:.3f} m, y {r['y']:.3f} m, psi {r['psi']:.3f} deg, "
            f"u {r['u']:.4f} m/s, v {r['v']:.4f} m/s, r {r['r']:.4f} deg/s"
        )
    print(f"  wall time        {res['wall_time_s']:.2f} s")


def _cmd_run(args: argparse.Namespace) -> int:
    from shipgym.controllers.wrappers import controller_spec
    from shipgym.dynamics import plant_model
    from shipgym.envs.make import resolve_env_id

    env_kwargs: dict[str, Any] = {}
    scenario_name = args.scenario
    if args.scenario_file is not None:
        from shipgym.scenarios import load_scenario

        sc = load_scenario(args.scenario_file)
        env_kwargs = sc.env_kwargs()
        scenario_name = args.scenario or sc.env
    scenario_name = scenario_name or "harbour"
    if args.wind is not None:
        env_kwargs["wind"] = WindConfigFromArg(args.wind)
    if args.plant is not None:
        env_kwargs["plant"] = args.plant
    args.scenario = scenario_name
    resolve_env_id(args.scenario)  # validate names before any work
    from shipgym.controllers.learned import is_learned_controller, parse_learned_controller

    if is_learned_controller(args.controller):
        parse_learned_controller(args.controller)  # the file exists and is a shipgym model
    else:
        controller_spec(args.controller)
    plant_model(env_kwargs.get("plant", "default"))
    observer = None if args.observer in (None, "truth") else args.observer
    if observer is not None:
        from shipgym.observers import make_observer

        make_observer(observer)
    for path in (args.json, args.record):
        if path is not None:
            _check_writable(path)
    if args.record is not None and args.record.suffix != ".rrd":
        raise ValueError(f"--record needs a .rrd path, got {args.record}")
    res = run_episode(
        args.scenario,
        controller=args.controller,
        observer=observer,
        seed=args.seed,
        wind=(3.0, math.radians(300.0)),
        plant="default",
        env_kwargs=env_kwargs,
        progress=not args.no_progress,
        record=args.record,
        spawn=args.spawn,
        report=args.report,
    )
    _print_table(res)
    for f in res["files"]:
        print(f"wrote {f}")
    if res["files"] and args.record is not None:
        print(f"open the recording with: rerun {args.record}")
    if args.json is not None:
        args.json.write_text(json.dumps(res, indent=2))
        print(f"results written to {args.json}")
    return 0


def write_bench_outputs(
    title: str,
    table: str,
    rows: list[dict[str, Any]],
    wall: float,
    *,
    json_path: Path | None = None,
    markdown: Path | None = None,
) -> None:
    """Print a benchmark's title and table; write its rows (JSON) and table (markdown)."""
    print(title)
    print(table)
    print(f"{len(rows)} runs in {wall:.1f} s")
    if json_path is not None:
        json_path.write_text(json.dumps({"title": title, "rows": rows}, indent=2))
        print(f"rows written to {json_path}")
    if markdown is not None:
        markdown.write_text(f"{title}\n\n{table}\n")
        print(f"table written to {markdown}")


def _cmd_bench(args: argparse.Namespace) -> int:
    from shipgym.bench import bench_observers, observer_table
    from shipgym.observers import make_observer

    for name in args.observers:
        make_observer(name)  # unknown names fail before any work
    for path in (args.json, args.markdown):
        if path is not None:
            _check_writable(path)
    t0 = time.perf_counter()
    rows = bench_observers(
        args.observers, seeds=args.seeds, wind=args.wind, workers=args.workers,
        progress=not args.no_progress, controller=args.controller,
    )  # fmt: skip
    wall = time.perf_counter() - t0
    table = observer_table(rows)
    speed, beta = args.wind
    title = (
        f"Observers on the harbour manoeuvre ({args.controller} controller, wind {speed:g} m/s "
        f"from {math.degrees(beta):g} deg, seeds 0-{args.seeds - 1}); indices from the measured "
        "pose as in Tomera (2014) Table 6, J_c truth from the true pose"
    )
    write_bench_outputs(title, table, rows, wall, json_path=args.json, markdown=args.markdown)
    if args.report is not None:
        from shipgym.bench import observer_traces
        from shipgym.viz import write_observer_report

        traces = observer_traces(
            args.observers, args.wind, workers=args.workers, controller=args.controller
        )
        for f in write_observer_report(rows, traces, args.report):
            print(f"wrote {f}")
        (args.report / "observers.md").write_text(f"{title}\n\n{table}\n")
        print(f"wrote {args.report / 'observers.md'}")
    return 0


def WindConfigFromArg(wind: tuple[float, float]) -> Any:  # noqa: N802 - reads as a type
    """A :class:`WindConfig` from ``parse_wind``'s ``(speed, from_rad)``."""
    from shipgym.disturbances import WindConfig

    return WindConfig(speed=wind[0], direction_from=wind[1])


def _cmd_report(args: argparse.Namespace) -> int:
    from shipgym.viz import write_report

    if not args.run.exists():
        raise ValueError(f"no such run file: {args.run}")
    for f in write_report(args.run, args.out):
        print(f"wrote {f}")
    return 0


def _check_writable(path: Path) -> None:
    """Create the parent folder and check that ``path`` can be written, before any work."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        existed = path.exists()
        with path.open("a"):
            pass
        if not existed:
            path.unlink()
    except OSError as exc:
        raise ValueError(f"cannot write {path}: {exc.strerror or exc}") from exc


def _cmd_demo(args: argparse.Namespace) -> int:
    from shipgym.disturbances import WindConfig
    from shipgym.envs.physics import VesselPhysics

    speed, beta = args.wind
    phys = VesselPhysics(args.plant, wind=WindConfig(speed=speed, direction_from=beta))
    phys.reset(rng=np.random.default_rng(args.seed))
    # open loop: half ahead, bow thruster to starboard and stern thruster to port (turn right)
    phys.set_command([300.0, 0.8, -0.8])
    steps = round(args.duration / phys.timestep)
    chunk = max(1, round(10.0 / phys.timestep))
    x0 = phys.eta
    path = 0.0
    wind_x, wind_y, wind_n = [], [], []
    t0 = time.perf_counter()
    last = phys.eta
    done = 0
    while done < steps:
        n = min(chunk, steps - done)
        phys.step(n)
        done += n
        eta = phys.eta
        path += float(np.hypot(*(eta[:2] - last[:2])))
        last = eta
        wx, wy, wn = phys.tau_wind
        wind_x.append(wx)
        wind_y.append(wy)
        wind_n.append(wn)
    wall = time.perf_counter() - t0
    eta, nu = phys.eta, phys.nu
    print("shipgym demo: Blue Lady open-loop turn (main propeller 300 rpm, bow +0.8, stern -0.8)")
    print(f"  plant {phys.plant.name!r}, wind {speed:.1f} m/s from {math.degrees(beta):.0f} deg")
    print(
        f"  simulated {phys.time:.0f} s in {wall:.2f} s wall ({phys.time / wall:,.0f}x real time)"
    )
    print(f"  start  x = {x0[0]:7.2f} m, y = {x0[1]:7.2f} m, psi = {math.degrees(x0[2]):7.1f} deg")
    print(
        f"  end    x = {eta[0]:7.2f} m, y = {eta[1]:7.2f} m, "
        f"psi = {math.degrees(eta[2]):7.1f} deg (heading change)"
    )
    print(f"  speed  u = {nu[0]:.3f} m/s, v = {nu[1]:.3f} m/s, r = {math.degrees(nu[2]):.3f} deg/s")
    print(f"  path length {path:.1f} m; thrust now {np.round(phys.thrust, 1).tolist()} N")
    print(
        f"  wind load (sampled every 10 s): X {np.mean(wind_x):6.1f} N, "
        f"Y {np.mean(wind_y):6.1f} N, "
        f"N {np.mean(wind_n):6.1f} N m on average"
    )
    return 0


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="shipgym", description="Ship manoeuvring simulator (MuJoCo).")
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("list", help="list plant variants, wind models and actuators")
    p.set_defaults(func=_cmd_list)
    p = sub.add_parser("run", help="run a closed-loop scenario; prints the metrics table")
    p.add_argument(
        "scenario", nargs="?", default=None,
        help="harbour (default), station-keeping, tracking, or an env id",
    )  # fmt: skip
    p.add_argument(
        "--scenario", dest="scenario_file", default=None, metavar="NAME|FILE",
        help="scenario preset or YAML/TOML file (see 'shipgym list'): plant, wind, waves, ...",
    )  # fmt: skip
    p.add_argument(
        "--controller", default="pid",
        help="pid (default), pid-smooth, pid-seed, lq, ppo (shipped baseline), ppo:PATH, sac:PATH",
    )  # fmt: skip
    p.add_argument(
        "--observer", default=None,
        help="truth, dkf, kbf, ekf, tomera-dkf/kbf/ekf (default: truth; a learned model's own)",
    )  # fmt: skip
    p.add_argument("--seed", type=int, default=0, help="episode seed (0)")
    p.add_argument("--wind", type=parse_wind, default=None, metavar="SPEED@FROM_DEG",
                   help="mean wind, e.g. 3@300 (default 3@300 or the scenario's)")  # fmt: skip
    p.add_argument("--plant", default=None, help="plant variant (default: 'default')")
    p.add_argument("--json", type=Path, default=None, metavar="PATH", help="write results")
    p.add_argument("--record", type=Path, default=None, metavar="PATH.rrd",
                   help="record the episode to a rerun file (no viewer needed)")  # fmt: skip
    p.add_argument("--spawn", action="store_true", help="also open the rerun viewer if possible")
    p.add_argument("--report", type=Path, default=None, metavar="DIR",
                   help="write PNG figures and metrics.md into DIR")  # fmt: skip
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_run)
    p = sub.add_parser("report", help="PNG figures and metrics.md from a recorded run")
    p.add_argument("run", type=Path, help="RUN.rrd or RUN.json")
    p.add_argument("--out", type=Path, required=True, metavar="DIR")
    p.set_defaults(func=_cmd_report)
    p = sub.add_parser("bench", help="benchmarks: 'bench observers', 'bench controllers'")
    bsub = p.add_subparsers(dest="what", required=True)
    b = bsub.add_parser("observers", help="Tomera (2014) Table-6-style comparison of observers")
    b.add_argument("--observers", nargs="+", default=["dkf", "kbf", "ekf"], metavar="NAME")
    b.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1 per observer (10)")
    b.add_argument(
        "--controller", default="pid-smooth", help="controller of every run (pid-smooth)"
    )
    b.add_argument("--wind", type=parse_wind, default=(3.0, math.radians(300.0)),
                   metavar="SPEED@FROM_DEG", help="mean wind (3@300)")  # fmt: skip
    b.add_argument("--workers", type=int, default=None, help="processes (default: CPUs)")
    b.add_argument("--json", type=Path, default=None, metavar="PATH")
    b.add_argument("--markdown", type=Path, default=None, metavar="PATH")
    b.add_argument("--report", type=Path, default=None, metavar="DIR",
                   help="bar chart of the indices and velocity-error plots (PNG)")  # fmt: skip
    b.add_argument("--no-progress", action="store_true")
    b.set_defaults(func=_cmd_bench)
    from shipgym.rl.cli import add_bench_controllers_parser, add_train_parser

    add_bench_controllers_parser(bsub)
    add_train_parser(sub)
    p = sub.add_parser("demo", help="open-loop turn in gusty wind; prints a summary")
    p.add_argument("--wind", type=parse_wind, default=(3.0, math.radians(300.0)),
                   metavar="SPEED@FROM_DEG", help="mean wind, e.g. 3@300 (default)")  # fmt: skip
    p.add_argument("--plant", default="default", help="plant variant (see 'shipgym list')")
    p.add_argument("--duration", type=float, default=300.0, help="simulated seconds (300)")
    p.add_argument("--seed", type=int, default=0, help="seed of the wind gusts (0)")
    p.set_defaults(func=_cmd_demo)
    return ap


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``shipgym`` console script."""
    args = _parser().parse_args(argv)
    try:
        return int(args.func(args))
    except (ValueError, FileNotFoundError, ImportError) as exc:
        print(f"shipgym: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("shipgym: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
