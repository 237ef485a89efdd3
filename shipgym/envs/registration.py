"""Registration of the shipgym environment ids (done on ``import shipgym``)."""

from __future__ import annotations

import gymnasium as gym

__all__ = ["ENV_IDS", "register_envs"]

#: env id -> (entry point, max_episode_steps)
ENV_IDS: dict[str, tuple[str, int]] = {
    "shipgym/BlueLadyHarbour-v0": ("shipgym.envs.tasks:BlueLadyHarbourEnv", 2000),
    "shipgym/BlueLadyStationKeeping-v0": ("shipgym.envs.tasks:BlueLadyStationKeepingEnv", 600),
    "shipgym/BlueLadyTracking-v0": ("shipgym.envs.tasks:BlueLadyTrackingEnv", 800),
}


def register_envs() -> None:
    """Register every id in :data:`ENV_IDS` with Gymnasium (idempotent)."""
    for env_id, (entry_point, steps) in ENV_IDS.items():
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point=entry_point, max_episode_steps=steps)
