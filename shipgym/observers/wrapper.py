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


class ObserverWrapper(gym.Wrapper[Any, Any, Any, Any]):
    """``env`` rebuilt with the observer ``observer`` (rl-zoo3's ``env_wrapper``).

    The env made by ``gym.make(env.spec)`` with ``observer=observer`` (and
    ``observer_options=options``) added to its arguments replaces ``env`` (which is closed):
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

        spec = env.spec
        base = env.unwrapped
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
        rebuilt = gym.make(dataclasses.replace(spec, kwargs=kwargs))
        env.close()
        super().__init__(rebuilt)
        #: the observer's name
        self.observer_name = observer
