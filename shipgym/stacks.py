"""The composition root: an env with its stack, env (observer, DP controller) -> learned
policy (``shipgym.make``, ``make_learned_env``).

It sits above the envs, the observers and the controllers (it imports them; none of them
imports it), so a stack is assembled in one place.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym

from shipgym.controllers.learned import (
    LearnedControllerWrapper,
    check_trained_env,
    is_learned_controller,
    parse_learned_controller,
    policy_env_kwargs,
    read_metadata,
)
from shipgym.envs.registration import PLAN_IDS, resolve_env_id

__all__ = ["USE_MODEL", "make", "make_learned_env"]

#: ``make_learned_env(observer=USE_MODEL)``: the observer the model was trained with
USE_MODEL = "model"


def make(
    env_id: str,
    *,
    observer: str | None = None,
    observer_options: dict[str, Any] | None = None,
    controller: str | None = None,
    residual_scale: float = 1.0,
    **kwargs: Any,
) -> gym.Env[Any, Any]:
    """``gym.make`` of a registered id or a scenario name, with the observer and the DP
    controller of a plan task.

    The plan tasks (harbour, station keeping, tracking, the offshore DP tasks) run the
    observer and the controller inside their step, as their vector env does
    (``gym.make_vec(id, N, observer=..., controller=...)``: one implementation); ``gym.make(id,
    observer=..., controller=...)`` builds the same env.

    Args:
        env_id: a registered id or a scenario name (:data:`SCENARIOS`; with ``vessel=`` in
            ``kwargs`` a scenario name is that vessel's task, see :func:`resolve_env_id`).
        observer: ``None`` or ``"truth"`` (controllers see the true state), or an observer
            name (``shipgym.observers.observer_names()``).
        observer_options: keyword arguments for the observer (e.g. ``{"beaufort": 5}`` for the
            ``alt-*`` wave filters: the sea state their HF model is designed for).
        controller: ``None`` (raw thruster actions) or a controller name
            (:data:`~shipgym.controllers.batch.CONTROLLERS`): the actions are then residuals
            on its normalised command.
        residual_scale: the factor on the residual actions (with ``controller``).
        **kwargs: environment arguments (``wind="3@300"``, ``current=(0.1, 90)``, ...: any
            form of ``WindConfig.coerce`` / ``CurrentConfig.coerce``, directions in degrees;
            ``vessel=``; see :class:`~shipgym.envs.base.ShipEnv`) and ``gym.make``'s own
            (``max_episode_steps``).

    Raises:
        ValueError: an observer or controller for an env that is not a plan task.
    """
    env_id = resolve_env_id(env_id, kwargs.get("vessel"))
    if observer == "truth":
        observer = None
    if observer is not None or controller is not None:
        if env_id not in PLAN_IDS:
            raise ValueError(
                f"{env_id} has no observer or DP controller stack (observer=, controller= "
                "apply to the plan tasks: Harbour, StationKeeping, Tracking, DPStationKeeping, "
                "DPSwayStep)"
            )
        if observer is not None:
            kwargs["observer"] = observer
            if observer_options is not None:
                kwargs["observer_options"] = observer_options
        if controller is not None:
            kwargs["controller"] = controller
            kwargs["residual_scale"] = residual_scale
    env = gym.make(env_id, **kwargs)
    if not any(w.name == "EpisodeEnd" for w in env.spec.additional_wrappers):  # type: ignore[union-attr]
        from shipgym.envs.episode import EpisodeEnd  # the batched ids' (registration.VECTOR_IDS)

        env = EpisodeEnd(env)
    return env


def make_learned_env(
    env_id: str,
    model_path: str | Path,
    *,
    observer: str | None = USE_MODEL,
    deterministic: bool = True,
    **env_kwargs: Any,
) -> gym.Env[Any, Any]:
    """An environment driven by a learned controller: env -> observer -> [DP controller] -> policy.

    The observer, the residual controller and its scale come from the model's metadata;
    ``env_kwargs`` are passed to the environment (e.g. ``wind=``, ``plant=``).

    Args:
        env_id: a registered id or a scenario name (``harbour``, ``tracking``, ...).
        model_path: a shipgym model, or a controller name: a shipped baseline (``ppo``,
            ``sac``, ``ppo-residual``: the one for ``env_id``'s task and ``vessel=``) or
            ``ppo:PATH`` / ``sac:PATH``.
        observer: ``"model"`` (default: the model's own observer), ``None``/``"truth"`` or
            an observer name (an experiment with another observer; warns).
        deterministic: mean action (default) or sampled.
        **env_kwargs: environment arguments.

    Returns:
        The wrapped environment; ``env.step(np.zeros(3))`` runs the learned controller.
    """
    path = Path(model_path)
    if not path.is_file() and is_learned_controller(str(model_path)):
        _, path = parse_learned_controller(
            str(model_path), task=env_id, vessel=env_kwargs.get("vessel")
        )
    meta = read_metadata(path)
    check_trained_env(meta, path)
    obs_name = meta.observer if observer == USE_MODEL else observer
    if obs_name == "truth":
        obs_name = None
    env = make(
        env_id,
        observer=obs_name,
        controller=str(meta.controller) if meta.residual else None,
        residual_scale=meta.residual_scale if meta.residual else 1.0,
        **{**policy_env_kwargs(meta.env_kwargs), **env_kwargs},
    )
    if meta.error_integral is not None:
        from shipgym.envs.integral import ErrorIntegralObservation

        env = ErrorIntegralObservation(env, time_constant=meta.error_integral)
    return LearnedControllerWrapper(env, path, deterministic=deterministic)
