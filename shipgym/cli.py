# PYTHON_ARGCOMPLETE_OK
"""The ``shipgym`` command.

``shipgym run SCENARIO``  closed-loop run (harbour manoeuvre, station keeping, tracking) with a
                          progress bar, a metrics table and an optional JSON file;
``shipgym export RUN``    a recorded run's time series as CSV (``--csv``) or ``.npz`` (``--npz``);
``shipgym demo``          open-loop turn of the Blue Lady in gusty wind, with a short summary;
``shipgym list``          env ids, scenarios, controllers, plant variants, wind models.

User mistakes end with a one-line error and exit status 2, never with a traceback; a
simulation that diverges (a plant or setting that does not simulate) with one and status 3.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from shipgym._argtypes import (
    add_bench_outputs,
    bench_settings,
    executor_of,
    parse_wind,
    path_arg,
)
from shipgym._io import check_folder, check_writable
from shipgym._safeload import jsonable
from shipgym._text import did_you_mean, num, num_list
from shipgym.bench import row_log, write_bench_outputs
from shipgym.catalogue import catalogue, check_controller, controller_catalogue
from shipgym.runner import ENV_DEFAULT, run_episode

# a leaf: nothing in the library imports this module; the names above are re-exported for the
# users who import them from here (tests/test_layering.py keeps it so)
__all__ = [
    "ENV_DEFAULT",
    "catalogue",
    "check_controller",
    "controller_catalogue",
    "main",
    "parse_wind",
    "run_episode",
    "write_bench_outputs",
]


def _cmd_list(args: argparse.Namespace) -> int:
    cat = catalogue()
    if args.json:
        print(json.dumps(cat, indent=2))
        return 0

    def names(key: str) -> str:
        return ", ".join(cat[key])

    print("env ids         :", names("env_ids"))
    print("env scenarios   :", ", ".join(f"{k} ({v})" for k, v in cat["env_scenarios"].items()))
    print("controllers     :")
    for name, desc in cat["controllers"].items():
        print(f"  {name:16s} {desc}")
    print("observers       :", names("observers"))
    print("sensor presets  :", names("sensor_presets"))
    print("scenario presets:", names("scenario_presets"), "(or a .yaml/.toml path)")
    print("wave presets    :", names("wave_presets"))
    print("plans           :", names("plans"))
    own = "; ".join(f"{v}: {', '.join(p)}" for v, p in cat["vessel_plants"].items())
    print("plant variants  :", names("plant_variants"), f"({own})" if own else "")
    print("wind models     :", names("wind_models"))
    print("actuators       :", names("actuators"), "(the Blue Lady's)")
    print("vessels         :")
    for name, desc in cat["vessels"].items():
        print(f"  {name:16s} {desc}")
    return 0


def _fmt(x: Any) -> str:
    """A table cell: a float to 4 decimals, ``n/a`` for NaN, an infinity or ``None``."""
    if x is None or (isinstance(x, float | np.floating) and not isinstance(x, bool)):
        return num(x, ".4f")
    return str(x)


def _wind_text(wind: dict[str, Any] | None, gusts: dict[str, Any] | None) -> str:
    """``3 m/s from 300 deg, gusts 0.45 m/s rms and 10 deg rms (gauss-markov)``: a run's wind
    (``describe_wind``) and its gusts in words; ``none`` without wind."""
    if not wind:
        return "none"
    if not wind.get("speed"):
        return "calm (0 m/s)"
    text = f"{num(wind['speed'], 'g')} m/s from {num(wind['from_deg'], '.0f')} deg"
    if not gusts:
        return text
    sd, dd = gusts.get("speed_std") or 0.0, gusts.get("direction_std_deg") or 0.0
    if sd == 0.0 and dd == 0.0:
        return f"{text}, steady"
    return (
        f"{text}, gusts {num(sd, '.2g')} m/s rms and {num(dd, '.0f')} deg rms "
        f"({gusts.get('spectrum', 'gauss-markov')})"
    )


def _header(res: dict[str, Any]) -> str:
    """The first line of the run table: what was run, in which sea."""
    waves = res.get("waves")
    cur = res.get("current")
    waves_s = (
        "none"
        if not waves or not waves["Hs"]
        else f"{waves['spectrum']} Hs {waves['Hs']:g} m Tp {waves['Tp']:g} s "
        f"from {waves['from_deg']:.0f} deg"
    )
    cur_s = (
        "none"
        if not cur or (not cur["speed"] and not cur["varying"])
        else f"{cur['speed']:g} m/s to {cur['to_deg']:.0f} deg"
        + (" (varying)" if cur["varying"] else "")
    )
    name = res["scenario"]
    preset = res.get("scenario_preset")
    if preset:
        name = f"{name} (scenario {preset})"
    parts = [
        name,
        f"controller {res['controller']}",
        f"observer {res['observer']}",
        f"seed {res['seed']}",
        f"plant {res['plant']}",
        f"wind {_wind_text(res.get('wind'), res.get('gusts'))}",
        f"waves {waves_s}",
        f"current {cur_s}",
    ]
    return " | ".join(parts)


def _print_table(res: dict[str, Any]) -> None:
    """The run's results in words: the header, the task's summary (a manoeuvre's completion
    and accuracy indices, or a station keeping's watch circle), the actuators' use."""
    print(_header(res))
    model = res.get("model")
    if model:
        print(
            f"  model {model['path']} ({model['algorithm']}, trained on {model['trained_on']} "
            f"through observer {model['trained_observer']})"
        )
    if res.get("station_keeping"):
        _print_station_keeping(res)
    else:
        _print_manoeuvre(res)
    print(f"  mean |thrust| (N) {num_list(res['thrust_mean_abs'], 1)}")
    print(f"  time saturated   {num_list(res['saturated_fraction'], 3)} (fraction)")
    if res.get("reversals_per_min"):
        print("  command chatter per channel (normalised commands):")
        for key, label, nd in (
            ("reversals_per_min", "reversals / min", 2),
            ("starts_per_min", "starts / min", 2),
            ("zero_fraction", "at zero", 3),
            ("limit_fraction", "at a limit", 3),
            ("hf_variance_fraction", "var. < 20 s", 3),
            ("travel_per_min", "travel / min", 2),
        ):
            if res.get(key) is not None:
                print(f"    {label:16s} {num_list(res[key], nd)}")
    if res.get("rmse"):
        r = res["rmse"]
        print(
            "  estimation RMSE  "
            f"x {num(r['x'], '.3f')} m, y {num(r['y'], '.3f')} m, "
            f"psi {num(r['psi'], '.3f')} deg, u {num(r['u'])} m/s, v {num(r['v'])} m/s, "
            f"r {num(r['r'])} deg/s"
        )
    print(f"  wall time        {res['wall_time_s']:.2f} s")


def _print_manoeuvre(res: dict[str, Any]) -> None:
    """A manoeuvre's rows (harbour, tracking): completion, legs, Tomera's accuracy indices."""
    meas = res.get("measured") or {}
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
    if res.get("indices_note"):
        print(f"  indices n/a: {res['indices_note']}")
    print(f"  leg times (s)    {num_list(res['leg_times'], 1)}")


def _print_station_keeping(res: dict[str, Any]) -> None:
    """A station keeping's rows: the time inside the watch circle, r95, the largest distance
    and the heading error (the true pose against the set point)."""
    sk = res["station_keeping"]
    rows = [
        ("duration", num(res["duration_s"], ".1f"), "s"),
        ("watch circle", num(sk["radius_m"], ".2f"), "m radius"),
        ("time inside", num(sk["inside_fraction"], ".1%"), "of the steps (requirement: 95 %)"),
        ("r95", num(sk["r95"], ".3f"), "m (95 % of the steps closer to the set point)"),
        ("largest distance", num(sk["r_max"], ".3f"), "m"),
        ("heading RMS", num(sk["heading_rms_deg"], ".3f"), "deg"),
    ]
    for name, val, unit in rows:
        print(f"  {name:16s} {val:>10s} {unit}")


def _no_vessel(env_id: str) -> str:
    from shipgym.dynamics.vessel import vessel_names

    raise ValueError(f"{env_id} needs --vessel NAME ({', '.join(vessel_names())}) or a path")


def _cmd_run(args: argparse.Namespace) -> int:
    from shipgym.dynamics.vessel import load_vessel
    from shipgym.envs.registration import resolve_env_id

    env_kwargs: dict[str, Any] = {}
    scenario_name = args.scenario
    if args.scenario_file is not None:
        from shipgym.scenarios import load_scenario

        sc = load_scenario(args.scenario_file)
        env_kwargs = sc.env_kwargs()
        scenario_name = args.scenario or sc.env
    scenario_name = scenario_name or "harbour"
    if args.wind is not None:
        env_kwargs["wind"] = args.wind
    if args.plant is not None:
        env_kwargs["plant"] = args.plant
    if args.vessel is not None:
        env_kwargs["vessel"] = args.vessel
    args.scenario = scenario_name
    # validate names before any work
    env_id = resolve_env_id(args.scenario, env_kwargs.get("vessel"))
    from shipgym.envs.registration import NEEDS

    if NEEDS.get(env_id) == "roll-steering":
        raise ValueError(
            f"shipgym run drives the positioning tasks; {env_id} is a rudder-roll task: run its "
            "classical pilots with 'shipgym bench roll --vessel NAME --speeds U', or use "
            "gym.make(...) with shipgym.controllers.rollpilot.roll_pilot"
        )
    if NEEDS.get(env_id) == "steering":
        raise ValueError(
            f"shipgym run drives the positioning tasks; {env_id} is a steering task: run the "
            "sea trials with 'shipgym trials --vessel NAME', or use gym.make(...) (course "
            "keeping: shipgym.controllers.coursepilot.course_autopilot)"
        )
    from shipgym.envs.registration import ALIASES

    name = env_kwargs.get("vessel", "blue-lady" if env_id in ALIASES else None)
    if args.controller.partition(":")[1]:  # an SB3 / rl-zoo3 model: imported with its files
        from shipgym.rl.interop import resolve_controller

        args.controller = resolve_controller(args.controller)
    check_controller(args.controller, task=env_id, vessel=name)
    vessel = load_vessel(name if name is not None else _no_vessel(env_id))
    vessel.plant(env_kwargs.get("plant", "default"))
    observer = args.observer  # None: truth, or a learned model's own observer
    if observer not in (None, "truth"):
        from shipgym.observers import make_observer

        make_observer(observer, vessel=vessel)  # unknown names fail before any work
    from shipgym.controllers.learned import is_learned_controller, parse_learned_controller

    if observer is not None and is_learned_controller(args.controller):
        from shipgym.controllers.learned import read_metadata

        model = parse_learned_controller(args.controller, task=env_id, vessel=name)[1]
        trained = read_metadata(model).observer
        if (trained or "truth") != observer:
            print(
                f"shipgym: warning: the model was trained on observer {trained or 'truth'!r}; "
                f"running it with {observer!r} as asked (--observer); the results say so",
                file=sys.stderr,
            )
    if args.record is not None and args.record.suffix != ".rrd":
        raise ValueError(f"--record needs a .rrd path, got {args.record}")
    from shipgym._io import on_interrupt, partial_path

    if args.record is not None:  # what an interrupt keeps (said if the file is there)
        on_interrupt(f"partial recording kept at {partial_path(args.record)}",
                     path=partial_path(args.record))  # fmt: skip
    for path in (args.record, args.json):
        if path is not None and path.is_file():
            on_interrupt(f"{path} left as it was", path=path)
    from shipgym._io import output_lock

    with output_lock((args.record, args.json, args.report)):  # one run per set of outputs
        res = run_episode(
            args.scenario,
            controller=args.controller,
            observer=observer if is_learned_controller(args.controller) else _truth_none(observer),
            seed=args.seed,
            plant="default",
            env_kwargs=env_kwargs,
            progress=not args.no_progress,
            record=args.record,
            spawn=args.spawn,
            report=args.report,
            json_path=args.json,
            scenario_preset=None if args.scenario_file is None else str(args.scenario_file),
            watch_radius=_watch_radius(env_id),
        )
    _print_table(res)
    warning = _limit_warning(res, vessel.actuators.channel_names)
    if warning is not None:
        print(warning, file=sys.stderr)
    for f in res["files"]:
        print(f"wrote {f}")
    if res["files"] and args.record is not None:
        from shipgym.viz.viewer import viewer_hint

        print(viewer_hint(args.record))
    if args.json is not None:
        print(f"results written to {args.json}")
    return 0


#: the share of a run above which a channel's command at a limit is warned about
LIMIT_WARNING_FRACTION = 0.5


def _limit_warning(res: dict[str, Any], channels: Any) -> str | None:
    """One line when a control channel sat at a limit for most of the run (its ``at a limit``
    share, ``limit_fraction``, above :data:`LIMIT_WARNING_FRACTION`); ``None`` otherwise."""
    fractions = res.get("limit_fraction") or []
    names = list(channels)
    hits = [
        (names[i] if i < len(names) else f"channel {i + 1}", float(f))
        for i, f in enumerate(fractions)
        if f is not None and math.isfinite(f) and f > LIMIT_WARNING_FRACTION
    ]
    if not hits:
        return None
    hits.sort(key=lambda h: -h[1])
    which = ", ".join(f"{n} {100.0 * f:.1f} %" for n, f in hits)
    return (
        f"shipgym: warning: commands at a limit for most of the run ({which} of the steps, "
        "the 'at a limit' row): the actuators cannot deliver what the controller asks, so "
        "these results measure their capacity more than the controller"
    )


def _watch_radius(env_id: str) -> float:
    """The watch circle of a station-keeping task (m): Al-Takie (1982) 2.3's 7 m
    (:func:`shipgym.dp.metrics.dp_radius`, the depth unknown) for the offshore DP task, else
    the 2 m of the generic PID's requirement (:data:`shipgym.runner.STATION_RADIUS`)."""
    from shipgym.runner import STATION_RADIUS

    if env_id == "shipgym/DPStationKeeping-v0":
        from shipgym.dp.metrics import dp_radius

        return dp_radius()
    return STATION_RADIUS


def _truth_none(observer: str | None) -> str | None:
    return None if observer == "truth" else observer


def _cmd_bench(args: argparse.Namespace) -> int:
    from shipgym.bench import (
        bench_observers,
        bench_scenario_kwargs,
        observer_table,
        table6_comparison,
    )
    from shipgym.dynamics.vessel import load_vessel
    from shipgym.observers import make_observer

    env_kwargs = bench_scenario_kwargs(args.scenario)  # a bad scenario fails before any work
    if args.wind is None:
        from shipgym.disturbances import WindConfig

        args.wind = WindConfig.coerce(
            env_kwargs["wind"] if env_kwargs is not None else "3@300", name="wind"
        )

    blue_lady = load_vessel("blue-lady")  # the benchmark's harbour manoeuvre
    for name in args.observers:
        make_observer(name, vessel=blue_lady)  # unknown names fail before any work
    total = len(args.observers) * args.seeds
    log = row_log(args.json, args.markdown, total, bench_settings(args), args.resume)
    t0 = time.perf_counter()
    check_controller(args.controller)
    from shipgym._io import progress_enabled

    rows = bench_observers(
        args.observers, seeds=args.seeds, wind=args.wind, workers=args.workers,
        progress=progress_enabled(args.no_progress), controller=args.controller,
        on_row=log.add, known=log.known, executor=executor_of(args), scenario=args.scenario,
    )  # fmt: skip
    wall = time.perf_counter() - t0
    table = observer_table(rows) + "\n\n" + table6_comparison(rows)
    where = "" if args.scenario is None else f", scenario {args.scenario}"
    wind = "none" if args.wind is None else args.wind.label()
    title = (
        f"Observers on the harbour manoeuvre ({args.controller} controller{where}, wind "
        f"{wind}, seeds 0-{args.seeds - 1}); indices from the measured "
        "pose as in Tomera (2014) Table 6, J_c truth from the true pose"
    )
    write_bench_outputs(title, table, rows, wall, json_path=args.json, markdown=args.markdown)
    log.discard(args.json or args.markdown)
    if args.report is not None:
        from shipgym.bench import observer_traces
        from shipgym.viz import write_observer_report

        traces = observer_traces(
            args.observers, args.wind, workers=args.workers, controller=args.controller,
            env_kwargs=None if env_kwargs is None else {**env_kwargs, "wind": args.wind},
        )  # fmt: skip
        for f in write_observer_report(rows, traces, args.report):
            print(f"wrote {f}")
        from shipgym._io import atomic_write_text

        atomic_write_text(args.report / "observers.md", f"{title}\n\n{table}\n")
        print(f"wrote {args.report / 'observers.md'}")
    return 0


def _beaufort_list(text: str) -> list[int]:
    """``"5..9"``, ``"8"`` or ``"5,8"`` -> Beaufort numbers (5-9), else ``ValueError``."""
    try:
        if ".." in text:
            a, b = (int(x) for x in text.split(".."))
            out = list(range(a, b + 1))
        else:
            out = [int(x) for x in text.split(",")]
    except ValueError:
        out = []
    if not out or any(not 5 <= n <= 9 for n in out):
        raise ValueError(f"--beaufort must be numbers 5-9 as N, A..B or N,M; got {text!r}")
    return out


def _cmd_bench_dp(args: argparse.Namespace) -> int:
    from shipgym._io import progress_enabled
    from shipgym.dp.bench import DP_SCHEMA_VERSION, DP_UNITS, METHODS, TASKS, bench_dp, dp_table
    from shipgym.dynamics.vessel import load_vessel

    beauforts = _beaufort_list(args.beaufort)
    for v in args.vessel:
        load_vessel(v)  # unknown names fail before any work
    methods = args.methods or list(METHODS)
    for m in methods:
        if m not in METHODS:
            raise ValueError(
                f"unknown DP method {m!r}{did_you_mean(m, METHODS)}; choose from "
                f"{', '.join(METHODS)}"
            )
    if args.duration is None:
        args.duration = 400.0 if args.task == "sway-step" else 600.0
    total = len(args.vessel) * len(beauforts) * len(methods) * args.seeds
    log = row_log(args.json, args.markdown, total, bench_settings(args), args.resume)
    t0 = time.perf_counter()
    rows = bench_dp(
        args.vessel, beauforts, args.seeds, methods=methods, duration=args.duration,
        task=args.task, workers=args.workers, progress=progress_enabled(args.no_progress),
        on_row=log.add, known=log.known, executor=executor_of(args),
    )  # fmt: skip
    wall = time.perf_counter() - t0
    title = (
        f"Al-Takie (1982) DP in closed loop: {', '.join(args.vessel)}, Beaufort "
        f"{args.beaufort}, seeds 0-{args.seeds - 1}, {args.duration:g} s episodes "
        f"({TASKS[args.task]}); wind and current feedforward but in kf14-no-ff; HF thrust "
        "RMS = detrended thrust command in 0.05-0.25 Hz (fraction of capacity); wave-band "
        "ratio = thrust-command power in 0.05-0.25 Hz over 0-0.04 Hz; at limit, reversals: "
        "the busiest thrust channel"
    )
    header = {"schema_version": DP_SCHEMA_VERSION, "units": DP_UNITS}
    write_bench_outputs(title, dp_table(rows), rows, wall, json_path=args.json,
                        markdown=args.markdown, header=header)  # fmt: skip
    log.discard(args.json or args.markdown)
    if args.figures is not None:
        from shipgym.dp.bench import dp_gain_history, dp_trace
        from shipgym.viz.dp import write_dp_figures

        bf = 8 if 8 in beauforts else max(beauforts)  # the thesis's nominal sea state
        for v in args.vessel:
            traces = {
                m: dp_trace((v, bf, m, 0, args.duration, args.task))
                for m in ("kf14", "kf16", "raw-lq")
                if m in methods
            }
            if not traces:
                raise ValueError("--figures needs one of the methods kf14, kf16, raw-lq")
            out = args.figures / v
            for f in write_dp_figures(
                traces, dp_gain_history(v, bf), out, title=f"{v}, Beaufort {bf}"
            ):
                print(f"wrote {f}")
    return 0


#: the fastest speed ``shipgym bench roll`` accepts (m/s): the seed's analysis range, 2-30 m/s
MAX_ROLL_SPEED = 30.0
#: most speeds in one ``--speeds`` range
MAX_ROLL_SPEEDS = 1000


def _speed_list(text: str) -> list[float]:
    """``"2..30"`` (step 2 m/s), ``"2..10:4"``, ``"8,13,15"`` or ``"8"`` -> sorted speeds (m/s).

    Raises:
        ValueError: not of that form, a step <= 0, or a speed not in (0, 30] m/s.
    """
    form = "A..B[:STEP] or A,B,C in m/s, e.g. 2..30, 2..10:4 or 8,13,15"
    try:
        if ".." in text:
            span, _, step_s = text.partition(":")
            a, b = (float(x) for x in span.split(".."))
            step = float(step_s) if step_s else 2.0
            if not (math.isfinite(step) and step > 0.0):
                raise ValueError(f"--speeds: the step must be > 0, got {step_s!r}")
            if not (math.isfinite(a) and math.isfinite(b)) or b < a:
                raise ValueError(f"--speeds: A..B needs A <= B, got {text!r}")
            n = math.floor((b - a) / step + 1e-9)
            if n >= MAX_ROLL_SPEEDS:
                raise ValueError(f"--speeds: at most {MAX_ROLL_SPEEDS} speeds, got {n + 1}")
            out = [round(a + i * step, 9) for i in range(n + 1)]
        else:
            out = [float(x) for x in text.split(",")]
    except ValueError as exc:
        if str(exc).startswith("--speeds"):
            raise
        raise ValueError(f"--speeds must be {form}; got {text!r}") from None
    bad = [u for u in out if not (math.isfinite(u) and 0.0 < u <= MAX_ROLL_SPEED)]
    if not out or bad:
        raise ValueError(f"--speeds must lie in (0, {MAX_ROLL_SPEED:g}] m/s ({form}); got {text!r}")
    return sorted(set(out))


def _write_json(path: Path, payload: dict[str, Any]) -> None:
    """``payload`` as JSON, atomically; ``WriteFailed`` (its text) if it cannot be written."""
    from shipgym._io import WriteFailed, atomic_write_text, os_reason

    text = json.dumps(jsonable(payload), indent=2)
    try:
        atomic_write_text(path, text)
    except OSError as exc:
        raise WriteFailed(f"cannot write the rows to {path} ({os_reason(exc)})", text) from None
    print(f"rows written to {path}")


def _cmd_bench_roll(args: argparse.Namespace) -> int:
    from shipgym._io import progress_enabled
    from shipgym.dynamics.vessel import load_vessel
    from shipgym.rrs.bench import (
        METHODS,
        SEED_CLAIM,
        TASKS,
        bench_roll,
        default_task,
        roll_analysis,
        roll_analysis_table,
        roll_table,
    )

    speeds = _speed_list(args.speeds)
    vessels = {}
    for v in args.vessel:
        vv = load_vessel(v)  # unknown names fail before any work
        if not vv.roll_control:
            raise ValueError(
                f"vessel {vv.name!r} has no [roll_control] table (a 4-DOF rudder vessel's "
                "rudder-roll design); choose e.g. van-der-klugt or naval-vessel"
            )
        vessels[v] = vv
    methods = args.methods or list(METHODS)
    for m in methods:
        if m not in METHODS:
            raise ValueError(
                f"unknown roll method {m!r}{did_you_mean(m, METHODS)}; choose from "
                f"{', '.join(METHODS)}"
            )
    if args.task is not None and args.task not in TASKS:
        raise ValueError(
            f"unknown roll task {args.task!r}{did_you_mean(args.task, TASKS)}; choose from "
            f"{', '.join(TASKS)}"
        )
    run_speeds: dict[str, list[float]] = {}
    for v, vv in vessels.items():
        top = vv.limits.get("surge_speed", math.inf)
        run_speeds[v] = [u for u in speeds if u <= top + 1e-9]
        skipped = [u for u in speeds if u > top + 1e-9]
        if skipped:
            print(f"{v}: speeds {', '.join(f'{u:g}' for u in skipped)} m/s skipped (above its "
                  f"surge_speed limit, {top:g} m/s)")  # fmt: skip
    if not any(run_speeds.values()):
        raise ValueError("no runs: every speed lies above the vessels' surge_speed limits")
    n_methods = len(methods) + ("autopilot" not in methods)  # the RRR's baseline is added
    total = sum(len(u) for u in run_speeds.values()) * n_methods * args.seeds
    log = row_log(args.json, args.markdown, total, bench_settings(args), args.resume)
    t0 = time.perf_counter()
    rows = bench_roll(
        list(vessels), speeds, args.seeds, methods=methods, duration=args.duration,
        task=args.task, workers=args.workers, progress=progress_enabled(args.no_progress),
        on_row=log.add, known=log.known, executor=executor_of(args),
    )  # fmt: skip
    analyses = {v: roll_analysis(v, u) for v, u in run_speeds.items() if u}
    wall = time.perf_counter() - t0
    tasks = {v: args.task or default_task(vv) for v, vv in vessels.items()}
    task_s = "; ".join(f"{v}: {t} ({TASKS[t]})" for v, t in tasks.items())
    title = (
        f"Rudder-roll stabilisation, Radhakrishnan (n.d.) after Van der Klugt (1987): "
        f"{', '.join(vessels)}, speeds {args.speeds} m/s, seeds 0-{args.seeds - 1}, "
        f"{args.duration:g} s episodes, metrics after 100 s; tasks {task_s}; "
        "RRR = 1 - roll RMS / roll RMS (heading autopilot only)"
    )
    parts = [roll_table(rows)]
    parts += [roll_analysis_table(an) for an in analyses.values()]
    parts.append(SEED_CLAIM)
    write_bench_outputs(title, "\n\n".join(parts), rows, wall, markdown=args.markdown)
    if args.json is not None:
        from shipgym.rrs.bench import roll_json

        _write_json(args.json, roll_json(title, rows, list(analyses.values()), SEED_CLAIM))
    log.discard(args.json or args.markdown)
    if args.figures is not None:
        from shipgym.dynamics.actuators import Rudder
        from shipgym.rrs.bench import roll_trace
        from shipgym.viz.rrs import write_roll_figures

        traces, rates = {}, {}
        for v, vv in vessels.items():
            U = float(vv.roll_control["design_speed"])
            tr = dict(roll_trace((v, U, "rrs", 0, args.duration, tasks[v])))
            tr.update(speed=U, method="rrs")
            traces[v] = tr
            rudders = [a.max_rate for a in vv.actuators if isinstance(a, Rudder)]
            if rudders:
                rates[v] = float(min(rudders))
        for f in write_roll_figures(rows, analyses, traces, args.figures, rate_limits=rates,
                                    title="bench roll"):  # fmt: skip
            print(f"wrote {f}")
    return 0


def _float_list(text: str, what: str) -> list[float]:
    """``"0.001,0.01,0.1"`` -> floats > 0; ``ValueError`` naming ``what`` otherwise."""
    try:
        out = [float(x) for x in text.split(",")]
    except ValueError:
        raise ValueError(f"{what} must be numbers separated by commas, got {text!r}") from None
    if not out or not all(math.isfinite(x) and x > 0 for x in out):
        raise ValueError(f"{what} must be positive numbers separated by commas, got {text!r}")
    return out


def _cmd_trials(args: argparse.Namespace) -> int:
    from shipgym._io import progress_enabled
    from shipgym.dynamics.vessel import load_vessel
    from shipgym.envs.seatrial import trial_study
    from shipgym.trials.manoeuvres import manoeuvre_names
    from shipgym.trials.report import bias_table, trials_table

    v = load_vessel(args.vessel)
    names = None
    if args.manoeuvres != "all":
        names = [m.strip() for m in args.manoeuvres.split(",") if m.strip()]
        bad = [m for m in names if m not in manoeuvre_names()]
        if bad or not names:
            name = bad[0] if bad else args.manoeuvres
            raise ValueError(f"unknown manoeuvre {name!r}"
                             f"{did_you_mean(name, [*manoeuvre_names(), 'all'])}; choose from "
                             f"{', '.join(manoeuvre_names())} or all")  # fmt: skip
    sps = _float_list(args.sp, "--sp")
    try:
        ax, ay = (float(x) for x in args.antenna.split(","))
    except ValueError:
        ax = ay = math.nan
    if not (math.isfinite(ax) and math.isfinite(ay) and max(abs(ax), abs(ay)) <= MAX_ANTENNA):
        raise ValueError(
            f"--antenna must be X,Y: two finite numbers within +-{MAX_ANTENNA:g} m (body frame, "
            f"from midship), got {args.antenna!r}"
        )
    receiver = None if args.receiver == "none" else args.receiver
    bar = None
    if progress_enabled(args.no_progress):
        from tqdm import tqdm

        bar = tqdm(total=len(names or manoeuvre_names()), unit="trial", leave=False)

    def tick(done: int, total: int, label: str) -> None:
        if bar is not None:
            bar.total = total
            bar.set_postfix_str(label)
            bar.update(1)

    t0 = time.perf_counter()
    study = trial_study(
        v, names, speed=args.speed, current=args.current, receiver=receiver, S_p=sps,
        runs=args.runs, seed=args.seed, antenna=(ax, ay), progress=tick,
    )  # fmt: skip
    if bar is not None:
        bar.close()
    wall = time.perf_counter() - t0
    rec0 = next(iter(study.records.values()))
    cur = rec0.current
    U0 = max(r.U0 for r in study.records.values())  # full ahead (a half-ahead turn: slower)
    slower = {m: r.U0 for m, r in study.records.items() if r.U0 < U0}
    title = (
        f"Sea trials (IMO MSC.137(76)) of {v.name}: L = {rec0.L:g} m, approach speed "
        f"{U0:g} m/s (L/V {rec0.L / U0:.1f} s"
        + "".join(f"; {m} from {u:.3g} m/s" for m, u in slower.items())
        + "), current "
        + (f"{cur[0]:g} m/s to {math.degrees(cur[1]):g} deg" if cur[0] > 0 else "none")
    )
    parts = [trials_table(study.rows)]
    if receiver is not None:
        parts.append(
            f"DGPS receiver (Artyszuk 2003): PV Kalman filter, S_p = {args.sp} m^2/s^3, 2 m "
            f"noise at 1 Hz, antenna at ({ax:g}, {ay:g}) m; bias of the noise-free run, noise "
            f"spread of {args.runs} Monte-Carlo runs (seed {args.seed}); stops up to u = 0"
        )
        parts.append(bias_table(study.bias_rows))
    write_bench_outputs(title, "\n\n".join(parts), study.rows, wall,
                        markdown=args.markdown)  # fmt: skip
    if args.json is not None:
        from shipgym.trials.report import trials_json

        _write_json(args.json, trials_json(title, study.rows, study.bias_rows, wall))
    if args.figures is not None:
        from shipgym.viz.trials import write_trial_figures

        for f in write_trial_figures(study, args.figures, title=v.name):
            print(f"wrote {f}")
    return 0


def _report_folder(run: Path) -> Path:
    """The default folder of ``shipgym report RUN``: ``<RUN stem>_report`` next to RUN."""
    return run.with_name(f"{run.stem}_report")


def _report_defaults(args: argparse.Namespace) -> None:
    """``shipgym report``: the run file must exist (before the output folder is made);
    ``--out`` defaults to :func:`_report_folder`."""
    if not args.run.is_file():
        raise ValueError(f"no such run file: {args.run} (expected a .rrd or .json run file)")
    if args.out is None:
        args.out = _report_folder(args.run)


def _cmd_report(args: argparse.Namespace) -> int:
    from shipgym.viz import load_run_or_results, write_report
    from shipgym.viz.report import write_results_report

    run = load_run_or_results(args.run)  # a file that is neither: one-line ValueError
    if isinstance(run, dict):  # the results of run --json: metrics.md, no figures
        for f in write_results_report(run, args.out):
            print(f"wrote {f}")
        print(
            f"{args.run} holds the results of 'shipgym run --json' (metrics, no time "
            "series): no figures; record the run with --record RUN.rrd for them"
        )
        return 0
    _warn_incomplete(args.run, run, "the report covers the {n} steps recorded and metrics.md "
                     "says INCOMPLETE")  # fmt: skip
    for f in write_report(run, args.out):
        print(f"wrote {f}")
    return 0


def _warn_incomplete(path: Path, run: Any, consequence: str) -> None:
    """One warning line on stderr where the recording ``run`` of ``path`` is incomplete;
    ``consequence`` says what that means for the output (``{n}``: the steps recorded)."""
    from shipgym.viz import recording_problem

    problem = recording_problem(run)
    if problem is not None:
        print(f"shipgym: warning: {path} is an incomplete recording ({problem}); "
              + consequence.format(n=run.n_steps), file=sys.stderr)  # fmt: skip


def _export_defaults(args: argparse.Namespace) -> None:
    """``shipgym export``: the run file must exist; ``--out`` defaults to the run file's path
    with the format's suffix (set before the outputs are checked against the input)."""
    if not args.run.is_file():
        raise ValueError(f"no such run file: {args.run} (expected a .rrd or .json run file)")
    if args.out is None:
        from shipgym.viz.export import export_path

        args.out = export_path(args.run, "csv" if args.csv else "npz", args.table)


def _cmd_export(args: argparse.Namespace) -> int:
    from shipgym.viz import load_run
    from shipgym.viz.export import write_run_csv, write_run_npz

    if args.npz and args.table != "steps":
        raise ValueError("--table applies to --csv; the .npz archive holds both tables")
    run = load_run(args.run)  # a file that is not a run: one-line ValueError
    _warn_incomplete(args.run, run, "the export holds the {n} steps recorded")
    if args.csv:  # an OSError (a full disk) leaves args.out as it was: main says so
        path, cols = write_run_csv(run, args.out, table=args.table)
    else:
        path, cols = write_run_npz(run, args.out)
    rows = len(cols[0].values) if cols else 0
    print(f"wrote {path} ({rows} rows, {len(cols)} columns)")
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    from shipgym.envs.physics import VesselPhysics

    phys = VesselPhysics("blue-lady", args.plant, wind=args.wind)
    phys.reset(rng=np.random.default_rng(args.seed))
    # open loop: half ahead, bow thruster to starboard and stern thruster to port (turn right)
    phys.set_command([300.0, 0.8, -0.8])
    steps = max(1, round(args.duration / phys.timestep))
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
    print(f"  plant {phys.plant.name!r}, wind {phys.wind_config.label()}")
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


#: longest simulated time of ``shipgym demo`` (s): one day
MAX_DEMO_DURATION = 86_400.0
#: farthest antenna from midship (m): beyond any hull's half length (a VLCC: 170 m)
MAX_ANTENNA = 500.0
#: longest episode of ``shipgym bench dp`` / ``bench roll`` (s): one day per episode (a
#: larger value is a typo, and would hold the machine for days)
MAX_BENCH_DURATION = 86_400.0


def _version() -> str:
    import shipgym

    return f"shipgym {shipgym.__version__}"


def _parser() -> argparse.ArgumentParser:
    from shipgym._argtypes import (
        MAX_COUNT,
        OneLineParser,
        bounded_float,
        bounded_int,
        seed_int,
    )

    ap = OneLineParser(
        prog="shipgym",
        description="Ship manoeuvring simulator (MuJoCo).",
        epilog=COMPLETION_HELP,
    )
    ap.add_argument("--version", action="version", version=_version())
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser(
        "list", help="list env ids, scenarios, controllers, observers, plants, wind models"
    )
    p.add_argument("--json", action="store_true", help="machine-readable (JSON) output")
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
        help="pid (default), pid-smooth, pid-seed, lq, the shipped learned baselines ppo (pure "
        "PPO), sac (pure SAC), ppo-residual (PPO on the PID) for the scenario and vessel, "
        "ppo:PATH, sac:PATH (a shipgym model, or a stable-baselines3 / rl-zoo3 zip with its "
        "args.yml and vecnormalize.pkl: docs/tutorials/train-ppo.md)",
    )  # fmt: skip
    p.add_argument(
        "--observer", default=None,
        help="truth, dkf, kbf, ekf, tomera-dkf/kbf/ekf (default: truth, or a learned model's "
        "own; an explicit observer, truth included, is honoured with a warning for a model "
        "trained on another)",
    )  # fmt: skip
    p.add_argument("--seed", type=seed_int, default=0, help="episode seed, an int >= 0 (0)")
    p.add_argument("--wind", type=parse_wind, default=None, metavar="SPEED@FROM_DEG",
                   help="mean wind, e.g. 3@300 (m/s, deg it comes from; default: the "
                   "scenario's, 3@300 for harbour, drawn per episode for tracking)")  # fmt: skip
    p.add_argument("--plant", default=None, help="plant variant (default: 'default')")
    p.add_argument(
        "--vessel", default=None,
        help="vessel name or package path (see 'shipgym list'; the Blue Lady ids imply it)",
    )  # fmt: skip
    p.add_argument("--json", type=path_arg, default=None, metavar="PATH", help="write results")
    p.add_argument("--record", type=path_arg, default=None, metavar="PATH.rrd",
                   help="record the episode to a rerun file (no viewer needed)")  # fmt: skip
    p.add_argument("--spawn", action="store_true", help="also open the rerun viewer if possible")
    p.add_argument("--report", type=path_arg, default=None, metavar="DIR",
                   help="write PNG figures and metrics.md into DIR")  # fmt: skip
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    _name_completers(p, RUN_COMPLETERS)
    p.set_defaults(func=_cmd_run, folders={"--report": REPORT})
    p = sub.add_parser("report", help="PNG figures and metrics.md from a recorded run")
    p.add_argument("run", type=path_arg, metavar="RUN",
                   help="RUN.rrd (shipgym run --record) or a JSON run file "
                   "(shipgym.viz.save_run_json, RecordEpisode(json_path=)): figures and "
                   "metrics.md; or the results of 'shipgym run --json', which hold no time "
                   "series: metrics.md only")  # fmt: skip
    p.add_argument("--out", type=path_arg, default=None, metavar="DIR",
                   help="folder of the figures and metrics.md (default: <RUN stem>_report "
                   "next to RUN, e.g. runs/h.rrd -> runs/h_report)")  # fmt: skip
    p.set_defaults(func=_cmd_report, folders={"--out": REPORT}, prepare=_report_defaults)
    p = sub.add_parser(
        "export", help="a recorded run's time series as CSV or a NumPy archive (.npz)",
        description="Write the time series of a recorded run as CSV (one column per signal "
        "component, the unit in each column name: 't [s]', 'x [m]', 'psi [rad]', "
        "'thrust_bow_tunnel [N]', ...) or as a NumPy archive (the same arrays under names "
        "without units, a 'units' entry of (name, unit) pairs and the run's metadata as "
        "JSON). Example: shipgym export run.rrd --csv",
    )  # fmt: skip
    p.add_argument("run", type=path_arg, metavar="RUN",
                   help="RUN.rrd (shipgym run --record) or a JSON run file "
                   "(shipgym.viz.save_run_json); not the results of 'shipgym run --json', "
                   "which hold no time series")  # fmt: skip
    fmt = p.add_mutually_exclusive_group(required=True)
    fmt.add_argument("--csv", action="store_true", help="write CSV")
    fmt.add_argument("--npz", action="store_true", help="write a NumPy archive (.npz)")
    p.add_argument("-o", "--out", type=path_arg, default=None, metavar="PATH",
                   help="output file (default: next to RUN with the suffix .csv or .npz; "
                   "the measurements table: RUN.measurements.csv); never RUN itself")  # fmt: skip
    p.add_argument("--table", choices=("steps", "measurements"), default="steps",
                   help="--csv: one row per control step (default) or per valid position "
                   "measurement (DGPS and gyrocompass, at their own times)")  # fmt: skip
    p.set_defaults(func=_cmd_export, prepare=_export_defaults)
    p = sub.add_parser(
        "bench",
        help="benchmarks: 'bench observers', 'bench controllers', 'bench rl', 'bench dp', "
        "'bench roll'",
    )
    bsub = p.add_subparsers(dest="what", required=True)
    b = bsub.add_parser("observers", help="Tomera (2014) Table-6-style comparison of observers")
    b.add_argument("--observers", nargs="+", default=["dkf", "kbf", "ekf"], metavar="NAME")
    b.add_argument(
        "--seeds", type=bounded_int(1, MAX_COUNT), default=10,
        help=f"seeds 0..N-1 per observer, 1 <= N <= {MAX_COUNT} (10)",
    )  # fmt: skip
    b.add_argument(
        "--controller", default="pid-smooth", help="controller of every run (pid-smooth)"
    )
    b.add_argument("--wind", type=parse_wind, default=None, metavar="SPEED@FROM_DEG",
                   help="mean wind (the scenario's; 3@300 without one)")  # fmt: skip
    b.add_argument("--scenario", default=None, metavar="NAME|FILE",
                   help="harbour scenario preset or YAML/TOML file: plant, wind, waves, "
                   "current, sensors (e.g. tomera2014-lake; default: the harbour env's)",
                   )  # fmt: skip
    add_bench_outputs(b)
    b.add_argument("--report", type=path_arg, default=None, metavar="DIR",
                   help="bar chart of the indices and velocity-error plots (PNG)")  # fmt: skip
    b.add_argument("--no-progress", action="store_true")
    b.set_defaults(func=_cmd_bench, folders={"--report": REPORT})
    b = bsub.add_parser(
        "dp", help="Al-Takie (1982) DP wave filters in closed loop, Beaufort 5-9 (table)"
    )
    b.add_argument("--vessel", nargs="+", default=["wimpey-sealab", "star-hercules"],
                   metavar="NAME", help="vessels (wimpey-sealab star-hercules)")  # fmt: skip
    b.add_argument("--beaufort", default="5..9", metavar="N|A..B",
                   help="Beaufort numbers 5-9: one, a range A..B or a list 5,8 (5..9)")  # fmt: skip
    b.add_argument(
        "--seeds", type=bounded_int(1, MAX_COUNT), default=3,
        help=f"seeds 0..N-1 per case, 1 <= N <= {MAX_COUNT} (3)",
    )  # fmt: skip
    b.add_argument("--methods", nargs="+", default=None, metavar="NAME",
                   help="methods of shipgym.dp.bench.METHODS (all)")  # fmt: skip
    b.add_argument("--duration", type=bounded_float(100.0, MAX_BENCH_DURATION, unit="s"),
                   default=None, help="episode length, s, >= 100 (the metrics' spectra) and <= "
                   f"{MAX_BENCH_DURATION:g} (600; the sway step: 400)")  # fmt: skip
    b.add_argument("--task", choices=("station-keeping", "sway-step"), default="station-keeping",
                   help="DPStationKeeping-v0 or the thesis's 0.02 p.u. sway step, DPSwayStep-v0 "
                   "(station-keeping)")  # fmt: skip
    add_bench_outputs(b)
    b.add_argument("--figures", type=path_arg, default=None, metavar="DIR",
                   help="estimates vs truth, thrust spectra and gain history (PNG), per vessel "
                   "in Beaufort 8 (or the highest given), seed 0")  # fmt: skip
    b.add_argument("--no-progress", action="store_true")
    b.set_defaults(func=_cmd_bench_dp, folders={"--figures": FIGURES})
    b = bsub.add_parser(
        "roll", help="Radhakrishnan (n.d.) rudder-roll stabilisation across speeds (table)"
    )
    b.add_argument("--vessel", nargs="+", default=["van-der-klugt", "naval-vessel"],
                   metavar="NAME",
                   help="4-DOF rudder vessels (van-der-klugt naval-vessel)")  # fmt: skip
    b.add_argument("--speeds", default="2..30", metavar="A..B[:STEP]|A,B,C",
                   help=f"speeds in (0, {MAX_ROLL_SPEED:g}] m/s: a range A..B (step 2 m/s, or "
                   "A..B:STEP), a list 8,13,15 or one; those above a vessel's surge_speed "
                   "limit are skipped (2..30)")  # fmt: skip
    b.add_argument(
        "--seeds", type=bounded_int(1, MAX_COUNT), default=1,
        help=f"seeds 0..N-1 per case, 1 <= N <= {MAX_COUNT} (1)",
    )  # fmt: skip
    b.add_argument("--methods", nargs="+", default=None, metavar="NAME",
                   help="methods of shipgym.rrs.bench.METHODS (all; autopilot, the RRR's "
                   "baseline, always runs)")  # fmt: skip
    b.add_argument("--task", default=None, metavar="seed-test|beam-sea",
                   help="the seed's sinusoidal rudder in calm water, or a beam sea (each "
                   "vessel's default: seed-test for van-der-klugt, else beam-sea)")  # fmt: skip
    b.add_argument("--duration", type=bounded_float(150.0, MAX_BENCH_DURATION, unit="s"),
                   default=400.0, help="episode length, s, >= 150 (the metrics skip the first "
                   f"100 s) and <= {MAX_BENCH_DURATION:g} (400)")  # fmt: skip
    add_bench_outputs(b)
    b.add_argument("--figures", type=path_arg, default=None, metavar="DIR",
                   help="RRR, heading/rudder, stability margin against speed, and one episode "
                   "per vessel at its design speed (PNG)")  # fmt: skip
    b.add_argument("--no-progress", action="store_true")
    b.set_defaults(func=_cmd_bench_roll, folders={"--figures": FIGURES})
    from shipgym.rl.cli import (
        add_bench_controllers_parser,
        add_bench_rl_parser,
        add_plot_parser,
        add_train_parser,
    )

    add_bench_controllers_parser(bsub)
    add_bench_rl_parser(bsub)
    add_train_parser(sub)
    add_plot_parser(sub)
    p = sub.add_parser(
        "trials", help="IMO sea trials (turning, zig-zag, stops) and the DGPS receiver's bias"
    )
    p.add_argument("--vessel", default="kvlcc2-100m", metavar="NAME",
                   help="a vessel with a rudder (kvlcc2-100m)")  # fmt: skip
    p.add_argument("--manoeuvres", default="all", metavar="A,B|all",
                   help="turning35_stbd, turning35_port, zigzag10, zigzag20, initial_turning, "
                   "crash_stop, coasting_stop, turning65_half_ahead (the Schilling rudder) (all "
                   "the vessel can fly)")  # fmt: skip
    p.add_argument("--speed", type=bounded_float(0.01, 50.0), default=None,
                   help="approach speed, m/s (the vessel's [trials] approach_speed)")  # fmt: skip
    p.add_argument("--current", default=None, metavar="SPEED@TO_DEG",
                   help="constant current, e.g. 0.25@225 (0.25 m/s going south-west)")  # fmt: skip
    p.add_argument(
        "--receiver",
        choices=["none", "dgps-pv"],
        default="none",
        help="the DGPS receiver's PV Kalman filter (Artyszuk 2003): bias study",
    )
    p.add_argument(
        "--sp",
        default="0.001,0.01,0.1",
        metavar="A,B,C",
        help="the receiver filter's S_p values, m^2/s^3 (0.001,0.01,0.1)",
    )
    p.add_argument("--runs", type=bounded_int(2, 10000), default=50,
                   help="Monte-Carlo runs of the receiver noise (50)")  # fmt: skip
    p.add_argument("--seed", type=seed_int, default=0, help="the Monte Carlo's seed (0)")
    p.add_argument(
        "--antenna",
        default="0,0",
        metavar="X,Y",
        help="antenna position, m, body frame from midship (0,0; the seed's: aft)",
    )
    p.add_argument("--json", type=path_arg, default=None, metavar="PATH")
    p.add_argument("--markdown", type=path_arg, default=None, metavar="PATH")
    p.add_argument(
        "--figures",
        type=path_arg,
        default=None,
        metavar="DIR",
        help="tracks, drift angle and speed against time, receiver bias (PNG)",
    )
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(func=_cmd_trials, folders={"--figures": FIGURES})
    p = sub.add_parser("demo", help="open-loop turn in gusty wind; prints a summary")
    p.add_argument("--wind", type=parse_wind, default="3@300",
                   metavar="SPEED@FROM_DEG", help="mean wind, e.g. 3@300 (default)")  # fmt: skip
    p.add_argument("--plant", default="default", help="plant variant (see 'shipgym list')")
    p.add_argument(
        "--duration", type=bounded_float(0.0, MAX_DEMO_DURATION, lo_open=True, unit="s"),
        default=300.0, help=f"simulated seconds, > 0 and <= {MAX_DEMO_DURATION:g} (300)",
    )  # fmt: skip
    p.add_argument("--seed", type=seed_int, default=0, help="seed of the wind gusts (0)")
    p.set_defaults(func=_cmd_demo)
    return ap


#: the options that write files or folders (every subcommand)
OUTPUT_OPTIONS = ("json", "markdown", "record", "report", "out", "figures")
#: the names a report folder and a figures folder write (a subcommand's ``folders`` default
#: maps its folder options to these; every other output option is one file)
REPORT = ("*.png", "*.md")
FIGURES = ("*.png",)


def _check_paths(args: argparse.Namespace) -> None:
    """Outputs never overwrite an input or each other (:func:`shipgym._io.check_outputs`):
    the inputs are the path-typed options, the scenario file, vessel packages given as folders
    and a model behind ``ppo:PATH`` (a name such as ``harbour`` is not a path even where a
    file of that name exists)."""
    from shipgym._io import check_outputs

    names = {"scenario_file": "--scenario", "run": "RUN"}  # dests named otherwise
    outputs: dict[str, Path | None] = {}
    inputs: dict[str, Path | None] = {}
    for key, value in vars(args).items():
        name = names.get(key, "--" + key.replace("_", "-"))
        if key in OUTPUT_OPTIONS:
            if isinstance(value, Path):
                outputs[name] = value
            continue
        values = value if isinstance(value, list) else [value]
        for i, v in enumerate(values):
            if isinstance(v, str) and key in ("scenario_file", "vessel", "controller"):
                v = Path(v.split(":", 1)[1] if ":" in v else v)
                v = v if v.exists() else None
            if isinstance(v, Path):
                inputs[name if len(values) == 1 else f"{name}[{i}]"] = v
    folders: dict[str, tuple[str, ...]] = getattr(args, "folders", {})
    check_outputs(outputs, inputs, folders)
    for name, path in outputs.items():  # writable, before any work
        (check_folder if name in folders else check_writable)(path)  # type: ignore[arg-type]


#: said once where a command compiles shipgym's laws (a silent pause of up to a minute)
COMPILE_NOTICE = (
    "shipgym: compiling the simulation's laws for this machine (the first run here, or of a "
    "new checkout: up to a minute; later runs load them from Numba's cache)"
)


def _compile_notice(stream: Any) -> Any:
    """A context in which the first Numba compile says :data:`COMPILE_NOTICE` once on
    ``stream``, where ``stream`` is a terminal (a log or a pipe stays quiet); a run whose laws
    are all in the cache compiles nothing and says nothing."""
    import contextlib

    from shipgym._io import progress_enabled

    if not progress_enabled(False, stream):
        return contextlib.nullcontext()
    from numba.core import event

    class _Notice(event.Listener):  # type: ignore[misc]
        said = False

        def on_start(self, ev: Any) -> None:
            if not self.said:
                self.said = True
                print(COMPILE_NOTICE, file=stream, flush=True)

        def on_end(self, ev: Any) -> None:
            pass

    return event.install_listener("numba:compile", _Notice())


#: the --help epilog: how to switch on the optional shell completion
COMPLETION_HELP = (
    "Shell completion (optional): pip install argcomplete, then run once "
    'eval "$(register-python-argcomplete shipgym)" (bash, zsh; put it in ~/.bashrc to keep it).'
)


#: ``shipgym run``'s options whose names the shell completes (dest -> :func:`catalogue` key)
RUN_COMPLETERS = {
    "scenario": "scenarios",
    "scenario_file": "scenario_presets",
    "controller": "controllers",
    "observer": "observers",
    "plant": "plant_variants",
    "vessel": "vessels",
}


def _completion_names(key: str) -> list[str]:
    """The names a completion offers for a :func:`catalogue` key (``scenarios``: the env
    scenarios and ids; the ``ppo:PATH`` forms left out)."""
    cat = catalogue()
    if key == "scenarios":
        return [*cat["env_scenarios"], *cat["env_ids"]]
    return [n for n in cat[key] if not n.endswith(":PATH")]


def _name_completers(p: argparse.ArgumentParser, completers: dict[str, str]) -> None:
    """Give the options ``completers`` names an argcomplete completer (an attribute argparse
    ignores; read only when the shell asks for a completion)."""

    def completer(key: str) -> Any:
        def complete(prefix: str, **_: Any) -> list[str]:
            return [n for n in _completion_names(key) if n.startswith(prefix)]

        return complete

    for action in p._actions:
        if action.dest in completers:
            action.completer = completer(completers[action.dest])  # type: ignore[attr-defined]


def _autocomplete(parser: argparse.ArgumentParser) -> None:
    """Complete the command line in the shell when ``argcomplete`` is installed (optional:
    no dependency); outside a completion request it returns at once."""
    try:
        import argcomplete
    except ImportError:
        return
    argcomplete.autocomplete(parser)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``shipgym`` console script.

    SIGTERM is handled like SIGINT (Ctrl-C): the command stops, keeps what it can (a partial
    recording, a bench's finished rows), says so in one line on stderr and exits with status
    130 (SIGINT) or 143 (SIGTERM). A second signal stops the clean-up itself.
    """
    from shipgym._io import WriteFailed, handle_signals, interrupt_message, interrupt_status
    from shipgym.sim.step import SimulationDiverged

    parser = _parser()
    _autocomplete(parser)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: 2 after a usage error, 0 after --help / --version
        return 0 if exc.code is None else exc.code if isinstance(exc.code, int) else 2
    with handle_signals(), _compile_notice(sys.stderr):
        try:
            prepare = getattr(args, "prepare", None)
            if prepare is not None:  # defaults that depend on other arguments (a subcommand's)
                prepare(args)
            _check_paths(args)
            rc = int(args.func(args))
            sys.stdout.flush()  # a closed pipe shows here, not at the interpreter's exit
            return rc
        except WriteFailed as exc:  # the results go to stdout instead of being lost
            res = exc.results
            out = res if isinstance(res, str) else json.dumps(jsonable(res), indent=2)
            print(out, flush=True)
            print(f"shipgym: error: {exc}; the results are printed on stdout", file=sys.stderr)
            return 2
        except (ValueError, FileNotFoundError, ImportError) as exc:
            print(f"shipgym: error: {exc}", file=sys.stderr)
            return 2
        except SimulationDiverged as exc:  # a plant or setting that does not simulate
            print(f"shipgym: error: {exc}", file=sys.stderr)
            return 3
        except BrokenPipeError:  # the reader stopped reading (shipgym list | head): quietly,
            # with the status a shell gives a command SIGPIPE ended; stdout to /dev/null so
            # that the interpreter's last flush does not fail again
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 128 + signal.SIGPIPE
        except OSError as exc:  # a full disk, a folder removed during the run, ...
            where = f" {exc.filename}" if exc.filename else ""
            print(f"shipgym: error: cannot write{where}: {exc.strerror or exc}", file=sys.stderr)
            return 1
        except KeyboardInterrupt as exc:
            print(interrupt_message(exc), file=sys.stderr, flush=True)
            return interrupt_status(exc)


if __name__ == "__main__":
    sys.exit(main())
