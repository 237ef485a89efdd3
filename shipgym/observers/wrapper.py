"""rl-zoo3's ``env_wrapper`` form of ``shipgym.make(id, observer=NAME)``.

A plan-task env runs its observer itself (``shipgym.make(id, observer="kbf")``,
``gym.make(id, observer="kbf")``, ``gym.make_vec(id, N, observer="kbf")``: the one
implementation, the vector env's). rl-zoo3 builds ``gym.make(id, **env_kwargs)`` and wraps it
in the classes its hyperparameters' ``env_wrapper`` names; :class:`ObserverWrapper` is that
class for the observer: it rebuilds the env from its spec with ``observer=``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import gymnasium as gym

__all__ = ["ObserverWrapper"]

#: the wrappers gym.make puts around an env (the rebuilt env has its own)
_MAKE_WRAPPERS = (
    gym.wrappers.TimeLimit,
    gym.wrappers.OrderEnforcing,
    gym.wrappers.PassiveEnvChecker,
)


class ObserverWrapper(gym.Wrapper[Any, Any, Any, Any]):
    """``env`` rebuilt with the observer ``observer`` (rl-zoo3's ``env_wrapper``).

    The env made by ``gym.make`` from ``env.unwrapped.spec`` with ``observer=observer`` (and
    ``observer_options=options``) added to its arguments replaces the env ``gym.make`` made
    (which is closed), under any wrapper put on top of it (SB3's ``Monitor``, which
    ``make_vec_env`` puts below the ``wrapper_class``):
    the same env as ``shipgym.make(id, observer=observer, ...)``, whose observation holds the
    estimate and whose ``info`` the estimation errors (:class:`~shipgym.envs.base.ShipEnv`).

    Args:
        env: a plan-task env made by ``gym.make`` (``shipgym/Harbour-v0``,
            ``shipgym/Tracking-v0``, ...; its spec must be intact) without an observer.
        observer: an observer name (``shipgym.observers.observer_names()``).
        options: keyword arguments for the observer (e.g. ``{"beaufort": 5}``).

    Raises:
        ValueError: an env without a spec, not a plan task, or that already has an observer.
    """

    def __init__(
        self,
        env: gym.Env[Any, Any],
        observer: str = "kbf",
        options: Mapping[str, Any] | None = None,
    ) -> None:
        from shipgym.envs.base import ShipEnv

        base = env.unwrapped
        spec = base.spec  # what gym.make made it from (the wrappers above it not included)
        if spec is None or not isinstance(base, ShipEnv):
            raise ValueError(
                "ObserverWrapper rebuilds a plan-task env made by gym.make (it needs its spec); "
                f"got {type(base).__name__}: use shipgym.make(id, observer=...)"
            )
        if base.observer_name is not None:
            raise ValueError(f"the env already runs observer {base.observer_name!r}")
        kwargs = {**spec.kwargs, "observer": observer}
        if options is not None:
            kwargs["observer_options"] = dict(options)
        rebuilt = gym.make(dataclasses.replace(spec, kwargs=kwargs, additional_wrappers=()))
        # the wrappers put on top of gym.make's (SB3's Monitor: make_vec_env wraps it below
        # this one) stay; the env gym.make made, with its own wrappers, is replaced under them
        parent, made = None, env
        while isinstance(made, gym.Wrapper) and not isinstance(made, _MAKE_WRAPPERS):
            parent, made = made, made.env
        made.close()
        if parent is None:
            super().__init__(rebuilt)
        else:
            parent.env = rebuilt
            super().__init__(env)
        #: the observer's name
        self.observer_name = observer
