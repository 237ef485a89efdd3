"""Run closed-loop episodes: the one runner behind ``shipgym run``, the benchmarks and the RL
evaluation.

Public names: ``ENV_DEFAULT``, ``STATION_RADIUS``, ``EpisodeEnd``, ``StationTrack``,
``build_env``, ``describe_wind``, ``episode_summary``, ``is_station_keeping``, ``run_episode``,
``step_episode``.

Design notes: docs/design/runner.md.
"""

from __future__ import annotations

import json
import math
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from shipgym._safeload import jsonable

__all__ = [
    "ENV_DEFAULT",
    "STATION_RADIUS",
    "EpisodeEnd",
    "StationTrack",
    "build_env",
    "describe_wind",
    "episode_summary",
    "is_station_keeping",
    "run_episode",
    "step_episode",
]


class _EnvDefault:
    """The type of :data:`ENV_DEFAULT`."""

    def __repr__(self) -> str:
        return "ENV_DEFAULT"

    def __reduce__(self) -> str:
        return "ENV_DEFAULT"  # unpickles as the module's one instance (worker processes)


#: ``run_episode(wind=...)`` default: pass no wind, so the env uses its own default
ENV_DEFAULT: Any = _EnvDefault()

#: the watch circle (m) of the station-keeping requirement documented for the generic PID
#: (95 % of the time inside it; Al-Takie (1982) 2.3 asks for 3 % of the water depth or 7 m)
STATION_RADIUS = 2.0


def run_episode(
    scenario: str,
    *,
    controller: str = "pid",
    observer: str | None = None,
    seed: int = 0,
    wind: Any = ENV_DEFAULT,
    plant: str = "default",
    progress: bool = False,
    env_kwargs: dict[str, Any] | None = None,
    record: Path | None = None,
    spawn: bool = False,
    report: Path | None = None,
    json_path: Path | None = None,
    scenario_preset: str | None = None,
    watch_radius: float = STATION_RADIUS,
) -> dict[str, Any]:
    """Run one closed-loop episode and return its results (the ``--json`` content).

    Args:
        scenario: env scenario (``harbour``, ``station-keeping``, ``tracking``) or env id.
        controller, observer: names (see ``shipgym list``). Observer ``None``: the truth
            for a classical controller, the model's own observer for a learned one;
            ``"truth"`` always means the truth (a learned policy trained on an observer's
            estimate then runs on the true state: an experiment, warned about and recorded
            in ``observer`` and ``model``).
        seed: episode seed (an int >= 0).
        wind: any form of :meth:`WindConfig.coerce <shipgym.disturbances.WindConfig.coerce>`
            (``"3@300"``, ``(speed m/s, from deg)``, a ``WindConfig``, ...) or ``None`` (no
            aerodynamic loads); by default the env's own (3 m/s from 300 deg for the harbour
            and station keeping, a drawn wind for tracking). The result's ``wind`` is the wind
            the physics used.
        plant: plant variant.
        progress: show a progress bar.
        env_kwargs: further environment arguments (they win over ``wind`` and ``plant``).
        record: write a rerun recording (``.rrd``) of the episode here.
        spawn: also try to open the rerun viewer.
        report: write PNG figures and ``metrics.md`` into this folder.
        json_path: also write the results there (JSON). The recording and this file are
            written under partial names and renamed together when both are complete, so an
            earlier pair is replaced by a complete new pair or left as it was.
        scenario_preset: the scenario preset or file the env arguments came from (recorded
            in the results).
        watch_radius: the watch circle of a station-keeping task (m, > 0): the time inside
            it is reported (default :data:`STATION_RADIUS`; the offshore DP task's requirement
            is ``shipgym.dp.metrics.dp_radius()``).

    The results of a station-keeping task (:func:`is_station_keeping`) carry
    ``station_keeping``: the watch circle ``radius_m`` and the :class:`StationTrack` summary
    (``inside_fraction``, ``r95``, ``r_max`` (m), ``heading_rms_deg``, ``steps``); ``None``
    for the other tasks. ``gusts`` describes the wind's gusts (``speed_std`` m/s,
    ``spectrum``, ``direction_std_deg``; ``None`` without wind).

    Raises:
        shipgym._io.WriteFailed: the results (``.results``) or the recording could not be
            written (a full disk, a removed folder).
        KeyboardInterrupt: interrupted: the recording stays at its partial name
            (``NAME.partial.rrd``), the JSON is not written and an earlier pair is untouched.
    """

    from shipgym.disturbances import WindConfig
    from shipgym.records import step_record

    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed must be an int >= 0, got {seed!r}")
    if isinstance(watch_radius, bool) or not (
        isinstance(watch_radius, int | float) and math.isfinite(watch_radius) and watch_radius > 0
    ):
        raise ValueError(
            f"watch_radius must be a finite number of metres > 0, got {watch_radius!r}"
        )

    kwargs: dict[str, Any] = {"plant": plant}
    if wind is not ENV_DEFAULT:
        kwargs["wind"] = WindConfig.coerce(wind, name="wind")
    kwargs.update(env_kwargs or {})
    # a learned policy runs with the observer it was trained with unless one is named; an
    # explicit one is honoured (the CLI warns) and recorded below ("observer", "model")
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*was trained with observer")
        env = build_env(scenario, controller=controller, observer=observer, **kwargs)
    model_info = _model_info(env, controller)
    if report is not None and record is None:
        record = report / "run.rrd"
    if record is not None:
        from shipgym.viz import RecordEpisode

        env = RecordEpisode(env, record, spawn=spawn, rename=False)
    bar = _progress(total=_episode_steps(env), enabled=progress, desc=f"{scenario} seed {seed}")
    track = StationTrack() if is_station_keeping(env) else None

    def tick(info: dict[str, Any]) -> None:
        if track is not None:
            track(info)
        rec = step_record(info)
        bar.update(1)
        bar.set_postfix(leg=rec.reference.leg + 1, t=f"{rec.t:.0f}s", refresh=False)

    t0 = time.perf_counter()
    try:
        end = step_episode(env, seed, on_step=tick)
        _finish_bar(bar, end)
        # the episode's wind (set at reset: the Tracking task draws one per episode)
        wind_out = describe_wind(env.unwrapped.wind_config)  # type: ignore[attr-defined]
        gusts_out = _describe_gusts(env.unwrapped.wind_config)  # type: ignore[attr-defined]
        result = episode_summary(env, end)
        waves_out = _describe_waves(env.unwrapped.physics.wave_config)  # type: ignore[attr-defined]
        current_out = _describe_current(env.unwrapped.physics.current_config)  # type: ignore[attr-defined]
        # what ran, read from the built physics (not the argument: env_kwargs may name another)
        plant_out = getattr(env.unwrapped.physics.plant, "name", plant)  # type: ignore[attr-defined]
        vessel_out = _describe_vessel(getattr(env.unwrapped, "vessel", None))
    finally:
        bar.close()
        env.close()
    wall = time.perf_counter() - t0
    files: list[str] = []
    if record is not None:
        files.append(str(record))
    report_failed = None
    report_moves: list[tuple[Path, Path]] = []
    if report is not None:  # at partial names: renamed with the recording and the JSON
        from shipgym._io import os_reason
        from shipgym.viz import load_run
        from shipgym.viz.report import report_files

        run = getattr(env, "last_run", None)
        try:
            report.mkdir(parents=True, exist_ok=True)
            report_moves = report_files(run if run is not None else load_run(record), report)
        except OSError as exc:  # a full disk: the results are printed instead
            report_failed = f"cannot write the report into {report} ({os_reason(exc)})"
        files += [str(dst) for _, dst in report_moves]
    res = {
        "scenario": scenario,
        "scenario_preset": scenario_preset,
        "env_id": env.spec.id if env.spec is not None else None,
        "controller": controller,
        "observer": step_record(end.info).nav.source,  # "truth" or the observer's name
        "seed": seed,
        "plant": plant_out,
        "vessel": vessel_out,
        "wind": wind_out,
        "gusts": gusts_out,
        "waves": waves_out,
        "current": current_out,
        "model": model_info,
        **result,
        "station_keeping": None
        if track is None
        else {"radius_m": float(watch_radius), **track.summary(float(watch_radius))},
        "wall_time_s": wall,
        "files": files,
    }
    if record is not None or json_path is not None:
        _commit_results(res, env if record is not None else None, json_path, report_moves,
                        failed=[report_failed] if report_failed else [])  # fmt: skip
    return res


def _describe_vessel(vessel: Any) -> dict[str, Any] | None:
    """The vessel that ran, for the results: its name, title, actuators and command
    channels (the order of the per-actuator and per-channel metrics)."""
    if vessel is None:
        return None
    return {"name": vessel.name, "title": vessel.title,
            "actuators": [a.name for a in vessel.actuators],
            "channels": list(vessel.actuators.channel_names)}  # fmt: skip


def build_env(
    scenario: str, *, controller: str = "pid", observer: str | None = None, **env_kwargs: Any
) -> Any:
    """The wrapper stack env -> observer -> controller (classical) or -> learned policy.

    Args:
        scenario: env scenario (``harbour``, ``station-keeping``, ``tracking``) or env id.
        controller: a classical controller name (``pid``, ``lq``, ...) or a learned one
            (a shipped baseline ``ppo``, ``sac``, ``ppo-residual``, chosen for the scenario
            and ``vessel=``; ``ppo:PATH``, ``sac:PATH``).
        observer: ``None``: the truth for a classical controller, the model's own observer
            for a learned one; ``"truth"``: always the truth; or an observer name (a learned
            policy then runs with it, with a warning if it was trained with another).
        **env_kwargs: environment arguments (``wind=``, ``plant=``, ...).
    """
    from shipgym.controllers.learned import is_learned_controller

    if is_learned_controller(controller):
        from shipgym.stacks import make_learned_env

        obs_kw: dict[str, Any] = {} if observer is None else {"observer": observer}
        return make_learned_env(scenario, controller, **obs_kw, **env_kwargs)
    import shipgym

    return shipgym.make(scenario, observer=observer, controller=controller, **env_kwargs)


class StationTrack:
    """Collects a station-keeping run step by step (``on_step(info)`` of the episode runner).

    ``r`` (m): horizontal distance of the true position from the set point ``eta_d``;
    ``e`` (deg): heading error, wrapped to [-180, 180).
    """

    def __init__(self) -> None:
        self.r: list[float] = []
        self.e: list[float] = []

    def __call__(self, info: dict[str, Any]) -> None:
        from shipgym.dynamics import wrap_angle

        eta, d = info["eta"], info["eta_d"]
        self.r.append(math.hypot(float(eta[0]) - float(d[0]), float(eta[1]) - float(d[1])))
        self.e.append(math.degrees(float(wrap_angle(float(eta[2]) - float(d[2])))))

    def summary(self, radius: float = STATION_RADIUS) -> dict[str, Any]:
        """``inside_fraction`` (of the steps with ``r <= radius``), ``r95`` (m, 95th
        percentile, linear interpolation), ``r_max`` (m), ``heading_rms_deg`` (deg),
        ``steps``."""
        r = np.asarray(self.r, float)
        e = np.asarray(self.e, float)
        if r.size == 0:
            nan = math.nan
            return {"inside_fraction": nan, "r95": nan, "r_max": nan, "heading_rms_deg": nan,
                    "steps": 0}  # fmt: skip
        return {
            "inside_fraction": float(np.mean(r <= radius)),
            "r95": float(np.percentile(r, 95.0)),
            "r_max": float(r.max()),
            "heading_rms_deg": float(np.sqrt(np.mean(e**2))),
            "steps": int(r.size),
        }


@dataclass(frozen=True)
class EpisodeEnd:
    """How an episode of :func:`step_episode` ended.

    Attributes:
        terminated, truncated: the flags of the last step.
        info: the last step's ``info``.
        steps: control steps taken.
        ret: the sum of the rewards.
    """

    terminated: bool
    truncated: bool
    info: dict[str, Any]
    steps: int
    ret: float


def step_episode(
    env: Any,
    seed: int,
    policy: Callable[[Any], Any] | None = None,
    *,
    on_step: Callable[[dict[str, Any]], None] | None = None,
) -> EpisodeEnd:
    """Reset ``env`` with ``seed`` and step it to the end of the episode.

    Args:
        env: a stack of :func:`build_env` (any Gymnasium env with a finite episode).
        seed: the episode seed.
        policy: ``policy(obs) -> action``; ``None``: zero actions (a controller stack then runs
            its controller alone).
        on_step: called with every step's ``info`` (a progress bar, a trace).
    """
    obs, info = env.reset(seed=seed)
    zero = np.zeros(env.action_space.shape, dtype=np.float32)
    terminated = truncated = False
    ret = 0.0
    steps = 0
    while not (terminated or truncated):
        action = zero if policy is None else policy(obs)
        obs, reward, terminated, truncated, info = env.step(action)
        ret += float(reward)
        steps += 1
        if on_step is not None:
            on_step(info)
    return EpisodeEnd(bool(terminated), bool(truncated), info, steps, ret)


def episode_summary(env: Any, end: EpisodeEnd) -> dict[str, Any]:
    """The plain-data result of the episode that just ended in ``env``
    (:func:`shipgym.metrics.episode_result`: completion, indices, thruster usage, ...)."""
    from shipgym.metrics import episode_result
    from shipgym.records import step_record

    base = env.unwrapped
    return episode_result(
        base.episode_metrics(),
        step_record(end.info),
        terminated=end.terminated,
        truncated=end.truncated,
        plan_finite=bool(base.terminate_on_finish),
    )


def _model_info(env: Any, controller: str) -> dict[str, Any] | None:
    """The learned model of a stack as plain data (``None``: a classical controller)."""
    from shipgym.controllers.learned import is_learned_controller

    if not is_learned_controller(controller):
        return None
    meta = env.policy.metadata
    return {
        "path": str(env.model_path),
        "algorithm": meta.algorithm,
        "trained_on": meta.env_id,
        "trained_observer": meta.observer or "truth",
    }


def _commit_results(
    res: dict[str, Any],
    recorder: Any,
    json_path: Path | None,
    more: Sequence[tuple[Path, Path]] = (),
    failed: Sequence[str] = (),
) -> None:
    """Rename the recording (``recorder.ended``), the JSON results and ``more`` (the report's
    ``(partial, final)`` files) onto their names together, only when all were written to their
    ends (``failed``: what could not be written already).

    Where one could not be written (a full disk) nothing is renamed and nothing removed: the
    earlier complete outputs stay as they were, the new partial recording stays at its
    partial name; the failure is raised as :class:`shipgym._io.WriteFailed` with the results.
    """
    from shipgym._io import (
        WriteFailed,
        os_reason,
        replace_together,
        rrd_complete,
        write_partial_text,
    )

    moves = [*(recorder.ended if recorder is not None else ()), *more]
    failed = [*failed] + [
        f"the recording {dst} could not be written to its end (a full disk?); the incomplete "
        f"file is at {src}"
        for src, dst in moves
        if Path(dst).suffix == ".rrd" and not rrd_complete(src)
    ]
    if json_path is not None:
        try:
            tmp = write_partial_text(json_path, json.dumps(jsonable(res), indent=2))
        except OSError as exc:
            failed.append(f"cannot write the results to {json_path} ({os_reason(exc)})")
        else:
            if tmp is not None:
                moves.append((tmp, json_path))
    if not failed:
        try:
            replace_together(moves)
            if recorder is not None:
                recorder.ended.clear()
        except OSError as exc:
            where = ", ".join(str(dst) for _, dst in moves)
            failed.append(f"cannot rename the finished files onto {where} ({os_reason(exc)})")
    if failed:
        for src, dst in moves:  # the new JSON's partial file (the recording's stays)
            if Path(dst).suffix != ".rrd":
                Path(src).unlink(missing_ok=True)
        raise WriteFailed("; ".join(failed) + "; the earlier outputs are kept as they were", res)


def _progress(total: int | None, enabled: bool, desc: str) -> Any:
    """A tqdm bar on stderr, drawn only when ``enabled`` and stderr is a terminal; it stays
    on the screen at its end (:func:`_finish_bar`)."""
    from tqdm import tqdm

    from shipgym._io import progress_enabled

    on = enabled and progress_enabled()
    return tqdm(total=total, disable=not on, desc=desc, unit="step", leave=True)


def _episode_steps(env: Any) -> int | None:
    """The control steps of a whole episode: the time limit (``max_episode_steps``), or the
    env's ``episode_duration`` over its control period (the DP tasks truncate themselves);
    ``None``: unknown."""
    limit = env.spec.max_episode_steps if env.spec is not None else None
    if limit is not None:
        return int(limit)
    base = env.unwrapped
    duration = getattr(base, "episode_duration", None)
    period = getattr(base, "control_period", None)
    if duration and period and math.isfinite(duration / period):
        return max(1, round(duration / period))
    return None


def _finish_bar(bar: Any, end: EpisodeEnd) -> None:
    """End the progress bar at 100 %: an episode that ended before its time limit (the plan
    completed, a quay contact) has taken all its steps, and the bar says why it ended."""
    if bar.disable:
        return
    from shipgym.records import step_record

    total = bar.total
    if end.terminated:
        why = "quay contact" if step_record(end.info).quay_contact else "plan complete"
        limit = f" of the {total} allowed" if total and bar.n < total else ""
        bar.set_postfix_str(f"ended at step {bar.n}{limit}: {why}", refresh=False)
    if total != bar.n:  # the last step counts (the DP tasks' estimated total included)
        bar.total = bar.n
    bar.refresh()


def describe_wind(w: Any) -> dict[str, Any] | None:
    """The wind of a run as plain data: ``speed`` (m/s), ``from_deg`` (``None``: no wind)."""
    if w is None:
        return None
    return {"speed": float(w.speed), "from_deg": math.degrees(float(w.direction_from)) % 360.0}


def _describe_gusts(w: Any) -> dict[str, Any] | None:
    """The gusts of a run's wind as plain data: ``speed_std`` (m/s, the effective standard
    deviation of the speed gust), ``spectrum`` (``gauss-markov``, ``npd``, ``harris``),
    ``direction_std_deg`` (deg); ``None``: no wind."""
    if w is None:
        return None
    return {
        "speed_std": float(w.gust_sigma),
        "spectrum": str(w.gust_spectrum),
        "direction_std_deg": math.degrees(float(w.direction_std)),
    }


def is_station_keeping(env: Any) -> bool:
    """Whether ``env`` is a station-keeping task (:class:`~shipgym.envs.tasks.StationKeepingEnv`,
    the offshore DP task included; not the sway step, whose set point moves)."""
    from shipgym.envs.offshore import SwayStepEnv
    from shipgym.envs.tasks import StationKeepingEnv

    base = env.unwrapped
    return isinstance(base, StationKeepingEnv) and not isinstance(base, SwayStepEnv)


def _describe_waves(w: Any) -> dict[str, Any] | None:
    """The waves of a run as plain data (``None``: no waves)."""
    if w is None:
        return None
    return {
        "spectrum": w.spectrum,
        "Hs": float(w.Hs),
        "Tp": float(w.Tp),
        "from_deg": math.degrees(float(w.direction_from)),
    }


def _describe_current(c: Any) -> dict[str, Any] | None:
    """The current of a run as plain data (``None``: no current)."""
    if c is None:
        return None
    return {
        "speed": float(c.speed),
        "to_deg": math.degrees(float(c.direction_to)),
        "varying": bool(c.sigma > 0 or c.direction_sigma > 0),
    }
