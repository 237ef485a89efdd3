"""The end of an episode, the same for every shipgym env however it ends.

Public names: ``EpisodeEnd``, ``EPISODE_END_ENTRY_POINT``.

Design notes: docs/design/envs.episode.md.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

__all__ = ["EpisodeEnd", "EPISODE_END_ENTRY_POINT"]

#: entry point of :class:`EpisodeEnd` for ``gymnasium.envs.registration.WrapperSpec``
EPISODE_END_ENTRY_POINT = "shipgym.envs.episode:EpisodeEnd"


class EpisodeEnd(gym.Wrapper[Any, Any, Any, Any], gym.utils.RecordConstructorArgs):
    """The episode's end in the last ``info`` (``episode_metrics``; the env's ``end_info`` where
    it has one, e.g. with the estimation RMSE) at every episode end; ``step()`` after the end
    raises ``ResetNeeded``.

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
            if "episode_metrics" not in info:  # a time-limit truncation: the env's end
                base: Any = self.env.unwrapped
                end = getattr(base, "end_info", None)
                if end is not None:
                    end(info)
                else:
                    info["episode_metrics"] = base.episode_metrics()
        return obs, reward, terminated, truncated, info
