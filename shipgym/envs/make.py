"""``shipgym.make``: build an environment with its observer/controller wrapper stack."""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from .registration import ALIASES, ENV_IDS

__all__ = ["SCENARIOS", "make", "resolve_env_id"]

#: short scenario names accepted by ``shipgym run`` and ``shipgym.make``: the Blue Lady's
#: ids; with ``vessel=`` another vessel, the vessel-neutral id of the same task.
SCENARIOS: dict[str, str] = {
    "harbour": "shipgym/BlueLadyHarbour-v0",
    "station-keeping": "shipgym/BlueLadyStationKeeping-v0",
    "tracking": "shipgym/BlueLadyTracking-v0",
}


def resolve_env_id(name: str, vessel: Any = None) -> str:
    """A registered env id from an id or a scenario name; unknown names list the valid ones.

    A scenario name means the Blue Lady's id, or with a ``vessel`` other than the Blue Lady
    the vessel-neutral id of the same task (``"harbour"`` -> ``shipgym/Harbour-v0``).
    """
    if name in ENV_IDS:
        return name
    if name in SCENARIOS:
        env_id = SCENARIOS[name]
        if vessel is not None and vessel != "blue-lady":
            return ALIASES[env_id]
        return env_id
    raise ValueError(
        f"unknown scenario or env id {name!r}; choose a scenario ({', '.join(SCENARIOS)}) "
        f"or an id ({', '.join(ENV_IDS)})"
    )


def make(
    env_id: str,
    *,
    observer: str | None = None,
    observer_options: dict[str, Any] | None = None,
    controller: str | None = None,
    residual_scale: float = 1.0,
    **kwargs: Any,
) -> gym.Env[Any, Any]:
    """``gym.make`` plus the wrapper stack: env -> observer wrapper -> controller wrapper.

    The one place that stacks these wrappers (``shipgym.make``, the learned controllers'
    stacks and the training envs use it).

    Args:
        env_id: a registered id or a scenario name (:data:`SCENARIOS`; with ``vessel=`` in
            ``kwargs`` a scenario name is that vessel's task, see :func:`resolve_env_id`).
        observer: ``None`` or ``"truth"`` (controllers see the true state), or an observer
            name (``shipgym.observers.OBSERVERS``).
        observer_options: keyword arguments for the observer (e.g. ``{"beaufort": 5}`` for the
            ``alt-*`` wave filters: the sea state their HF model is designed for).
        controller: ``None`` (raw thruster actions) or a controller name.
        residual_scale: the controller wrapper's factor on the residual action (see
            :class:`~shipgym.controllers.wrappers.DPControllerWrapper`).
        **kwargs: environment arguments (``wind="3@300"``, ``current=(0.1, 90)``, ...: any
            form of ``WindConfig.coerce`` / ``CurrentConfig.coerce``, directions in degrees;
            ``vessel=``; see :class:`~shipgym.envs.base.ShipEnv`) and ``gym.make``'s own
            (``max_episode_steps``).
    """
    env = gym.make(resolve_env_id(env_id, kwargs.get("vessel")), **kwargs)
    if not any(w.name == "EpisodeEnd" for w in env.spec.additional_wrappers):  # type: ignore[union-attr]
        from .episode import EpisodeEnd  # the batched ids' (registration.VECTOR_IDS)

        env = EpisodeEnd(env)
    if observer not in (None, "truth"):
        from shipgym.observers.wrapper import ObserverWrapper

        env = ObserverWrapper(env, observer=observer, options=observer_options)
    if controller is not None:
        from shipgym.controllers.wrappers import DPControllerWrapper

        env = DPControllerWrapper(env, controller=controller, residual_scale=residual_scale)
    return env
