"""Closed-loop episodes of any controller (classical or learned) and their result rows.

Thin on :mod:`shipgym.runner` (which builds and steps every episode), for everything that
compares controllers: the periodic harbour evaluation during
training (:data:`shipgym.rl.train.EVALUATIONS`) and ``shipgym bench controllers``
(:mod:`shipgym.rl.bench`). A result row carries the same keys as
:func:`shipgym.runner.run_episode` (``completed``, ``quay_contact``, ``x_E``, ``y_E``,
``psi_E``, ``J_c``, ``measured``, ``duration_s``, ``thrust_mean_abs``, ...).

Station keeping: :class:`StationTrack` collects the distance from the set point and the
heading error step by step (``on_step=``), for ``shipgym bench controllers --task
station-keeping`` and the periodic evaluation of training
(:data:`shipgym.rl.train.STATION_KEEPING`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from shipgym._text import did_you_mean
from shipgym.runner import (  # StationTrack, STATION_RADIUS: re-exported (they live there)
    ENV_DEFAULT,
    STATION_RADIUS,
    StationTrack,
    build_env,
    describe_wind,
    episode_summary,
    step_episode,
)

__all__ = [
    "DEFAULT_WIND",
    "STATION_RADIUS",
    "StationTrack",
    "available_observers",
    "default_observer",
    "make_controlled_env",
    "run_controlled_episode",
    "run_env_episode",
]

#: the lake-trial wind of Tomera (2014): 3 m/s from 300 deg ("SPEED@FROM_DEG")
DEFAULT_WIND = "3@300"

PolicyFn = Callable[[NDArray[np.float32]], NDArray[np.float32]]


def available_observers() -> list[str]:
    """Observer names this installation provides (empty while none is registered)."""
    try:
        from shipgym.observers import observer_names

        return list(observer_names())
    except ImportError:
        return []


def default_observer() -> str | None:
    """``"kbf"`` (the continuous Kalman-Bucy filter) when available, else ``None`` (truth)."""
    return "kbf" if "kbf" in available_observers() else None


def check_observer(observer: str | None) -> str | None:
    """Validate an observer name (``None``/``"truth"``: the truth); returns ``None`` or it."""
    if observer in (None, "truth"):
        return None
    names = available_observers()
    if observer not in names:
        have = ", ".join(names) if names else "none yet"
        raise ValueError(
            f"observer {observer!r}{did_you_mean(observer, ['truth', *names])} is not available "
            f"(registered observers: {have}); use 'truth' to let the controller see the true "
            "state"
        )
    return observer


def make_controlled_env(
    scenario: str,
    controller: str,
    *,
    observer: str | None = None,
    wind: Any = DEFAULT_WIND,
    **env_kwargs: Any,
) -> gym.Env[Any, Any]:
    """The wrapper stack of a named controller: classical (``pid``, ``lq``) or learned.

    Args:
        scenario: scenario name or env id (``harbour``, ``tracking``, ...).
        controller: a name in ``shipgym.controllers.batch.CONTROLLERS`` or a learned
            controller (a shipped baseline ``ppo``, ``sac``, ``ppo-residual`` for the scenario
            and ``vessel=``, or ``ppo:PATH``, ``sac:PATH``).
        observer: ``None``/``"truth"`` or an observer name. Learned controllers always get
            the observer given here (pass the model's own to reproduce its training setup).
        wind: any form of :meth:`WindConfig.coerce <shipgym.disturbances.WindConfig.coerce>`
            (``"3@300"``, ``(speed m/s, from deg)``, a ``WindConfig``), ``None`` (calm) or
            :data:`shipgym.runner.ENV_DEFAULT` (the env's own: the vessel's nominal wind for
            station keeping).
        **env_kwargs: further environment arguments (``vessel=``, ``max_episode_steps=``, ...).
    """
    from shipgym.controllers.learned import is_learned_controller
    from shipgym.disturbances import WindConfig

    if wind is not ENV_DEFAULT:
        env_kwargs["wind"] = WindConfig.coerce(wind, name="wind")
    observer = check_observer(observer)
    if observer is None and is_learned_controller(controller):
        observer = "truth"  # build_env's None would mean the model's own observer
    return build_env(scenario, controller=controller, observer=observer, **env_kwargs)


def run_env_episode(
    env: gym.Env[Any, Any],
    seed: int,
    policy: PolicyFn | None = None,
    *,
    on_step: Callable[[dict[str, Any]], None] | None = None,
) -> dict[str, Any]:
    """Run one episode to its end; ``policy(obs) -> action`` or zeros. Returns the result row.

    ``on_step(info)`` is called after every step (a trace, e.g. the station-keeping
    statistics of ``shipgym bench controllers``).

    The row has the keys of :func:`shipgym.runner.run_episode` that describe the run
    (``completed``, ``legs_completed``, ``duration_s``, ``quay_contact``, ``terminated``,
    ``truncated``, ``x_E``, ``y_E``, ``psi_E`` (deg), ``J_c``, ``measured``, ``leg_times``,
    ``thrust_mean_abs`` (N), ``thrust_total_variation`` (N), ``saturated_fraction``,
    ``rmse``, ``wall_time_s``, ``indices_note``, ``partial_indices``) plus ``seed`` and
    ``return`` (sum of rewards). The accuracy indices of a run that hit a quay, did not finish
    its plan or was too short are NaN, with the reason in ``indices_note``
    (:func:`shipgym.metrics.honest_indices`).
    """
    t0 = time.perf_counter()
    end = step_episode(env, seed, policy, on_step=on_step)
    result = episode_summary(env, end)
    wall = time.perf_counter() - t0
    return {"seed": int(seed), **result, "return": end.ret, "wall_time_s": wall}


def run_controlled_episode(
    scenario: str,
    controller: str,
    *,
    seed: int = 0,
    observer: str | None = None,
    wind: Any = DEFAULT_WIND,
    on_step: Callable[[dict[str, Any]], None] | None = None,
    **env_kwargs: Any,
) -> dict[str, Any]:
    """One closed-loop episode of a named controller (see :func:`make_controlled_env`).

    ``on_step(info)`` is called after every step. Returns the row of :func:`run_env_episode`
    plus ``scenario``, ``controller`` (the name as given), ``observer`` and ``wind`` (the wind
    the physics used: speed m/s, from deg).
    """
    env = make_controlled_env(scenario, controller, observer=observer, wind=wind, **env_kwargs)
    try:
        row = run_env_episode(env, seed, on_step=on_step)
        wind_used = describe_wind(env.unwrapped.wind_config)  # type: ignore[attr-defined]
    finally:
        env.close()
    return {
        "scenario": scenario,
        "controller": controller,
        "observer": observer or "truth",
        "wind": wind_used,
        **row,
    }
