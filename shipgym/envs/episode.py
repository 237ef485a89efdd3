"""The end of an episode, the same for every shipgym env however it ends.

``gym.make`` puts its ``TimeLimit`` around the env, so the env itself cannot see a time-limit
truncation (``gym.make(id, max_episode_steps=5)`` does not tell the env). :class:`EpisodeEnd`
is registered as an additional wrapper of every shipgym id, so ``gym.make`` applies it right
outside the ``TimeLimit``; it sees every episode end (termination or truncation) and

* puts ``info["episode_metrics"]`` (:meth:`BlueLadyEnv.episode_metrics
  <shipgym.envs.base.BlueLadyEnv.episode_metrics>`) into the last ``info`` when the env did not
  already (the env does on termination), and
* refuses :meth:`step` after the end with ``gymnasium.error.ResetNeeded`` until :meth:`reset`,
  instead of silently stepping on (and changing the metrics).

The ids with a native batched form (:data:`~shipgym.envs.registration.VECTOR_IDS`) cannot
carry it (Gymnasium refuses a vector entry point next to additional wrappers): for them
``shipgym.make`` applies it, and a bare ``gym.make`` gives Gymnasium's plain ``TimeLimit``
(the env still reports ``episode_metrics`` and refuses steps when it terminates).

Gymnasium's own vector envs and stable-baselines3's ``VecEnv`` reset a finished env instead
of stepping it, so they never hit the error.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

__all__ = ["EpisodeEnd", "EPISODE_END_ENTRY_POINT"]

#: entry point of :class:`EpisodeEnd` for ``gymnasium.envs.registration.WrapperSpec``
EPISODE_END_ENTRY_POINT = "shipgym.envs.episode:EpisodeEnd"


class EpisodeEnd(gym.Wrapper[Any, Any, Any, Any], gym.utils.RecordConstructorArgs):
    """``episode_metrics`` at every episode end; ``step()`` after the end raises ``ResetNeeded``.

    Args:
        env: a shipgym env, usually wrapped in ``TimeLimit`` (``gym.make`` does it).
    """

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.Wrapper.__init__(self, env)
        self._over = True  # until the first reset

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        out = self.env.reset(seed=seed, options=options)
        self._over = False
        return out

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if self._over:
            raise gym.error.ResetNeeded(
                "the episode has ended (terminated or truncated) or was never started: call "
                "reset() before step()"
            )
        obs, reward, terminated, truncated, info = self.env.step(action)
        if terminated or truncated:
            self._over = True
            if "episode_metrics" not in info:
                info["episode_metrics"] = self.env.unwrapped.episode_metrics()  # type: ignore[attr-defined]
        return obs, reward, terminated, truncated, info
