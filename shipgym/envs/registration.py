"""Registration of the shipgym environment ids (done on ``import shipgym``)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
from gymnasium.envs.registration import WrapperSpec

from shipgym._text import did_you_mean

from .episode import EPISODE_END_ENTRY_POINT

__all__ = [
    "ALIASES",
    "ENV_IDS",
    "NEEDS",
    "SCENARIOS",
    "PLAN_IDS",
    "VECTOR_IDS",
    "register_envs",
    "resolve_env_id",
    "task_fits_vessel",
]

#: env id -> (entry point, max_episode_steps); ``None``: the env truncates itself after its
#: ``episode_duration`` (the DP tasks, whose number of steps depends on the vessel)
ENV_IDS: dict[str, tuple[str, int | None]] = {
    "shipgym/Harbour-v0": ("shipgym.envs.tasks:HarbourEnv", 2000),
    "shipgym/StationKeeping-v0": ("shipgym.envs.tasks:StationKeepingEnv", 600),
    "shipgym/Tracking-v0": ("shipgym.envs.tasks:TrackingEnv", 800),
    "shipgym/DPStationKeeping-v0": ("shipgym.envs.offshore:OffshoreDPEnv", None),
    "shipgym/DPSwayStep-v0": ("shipgym.envs.offshore:SwayStepEnv", None),
    "shipgym/RudderRollStabilisation-v0": ("shipgym.envs.rollstab:SeedRollEnv", None),
    "shipgym/NavalRollDamping-v0": ("shipgym.envs.rollstab:NavalRollEnv", None),
    "shipgym/SeaTrial-v0": ("shipgym.envs.seatrial:TankerSeaTrialEnv", None),
    "shipgym/CourseKeeping-v0": ("shipgym.envs.coursekeeping:TankerCourseKeepingEnv", None),
    "shipgym/BlueLadyHarbour-v0": ("shipgym.envs.tasks:BlueLadyHarbourEnv", 2000),
    "shipgym/BlueLadyStationKeeping-v0": ("shipgym.envs.tasks:BlueLadyStationKeepingEnv", 600),
    "shipgym/BlueLadyTracking-v0": ("shipgym.envs.tasks:BlueLadyTrackingEnv", 800),
}

#: ids with a native batched form (:class:`~shipgym.envs.vector.ShipVectorEnv` or a stepped
#: task's :class:`~shipgym.envs.stepped.TaskEnv`): id -> its
#: vector entry point, for ``gymnasium.make_vec(id, num_envs=N)``. Gymnasium refuses a vector
#: entry point next to additional wrappers, so these ids do without :class:`EpisodeEnd`
#: under a bare ``gym.make``: ``shipgym.make`` applies it (episode metrics at a time-limit
#: truncation, no step after the end); the env itself reports its metrics when it terminates.
VECTOR_IDS: dict[str, str] = {
    "shipgym/Harbour-v0": "shipgym.envs.vector:harbour_vector_env",
    "shipgym/DPStationKeeping-v0": "shipgym.envs.vector:dp_station_keeping_vector_env",
    "shipgym/DPSwayStep-v0": "shipgym.envs.vector:dp_sway_step_vector_env",
    "shipgym/BlueLadyHarbour-v0": "shipgym.envs.vector:blue_lady_harbour_vector_env",
    "shipgym/Tracking-v0": "shipgym.envs.vector:tracking_vector_env",
    "shipgym/StationKeeping-v0": "shipgym.envs.vector:station_keeping_vector_env",
    "shipgym/BlueLadyTracking-v0": "shipgym.envs.vector:blue_lady_tracking_vector_env",
    "shipgym/BlueLadyStationKeeping-v0": "shipgym.envs.vector:blue_lady_station_keeping_vector_env",
    "shipgym/CourseKeeping-v0": "shipgym.envs.coursekeeping:course_keeping_vector_env",
    "shipgym/SeaTrial-v0": "shipgym.envs.seatrial:sea_trial_vector_env",
    "shipgym/RudderRollStabilisation-v0": "shipgym.envs.rollstab:seed_roll_vector_env",
    "shipgym/NavalRollDamping-v0": "shipgym.envs.rollstab:naval_roll_vector_env",
}

#: the plan tasks (their env a :class:`~shipgym.envs.spec.PlanEnvSpec`, their vector env a
#: :class:`~shipgym.envs.vector.ShipVectorEnv`), which take ``observer=`` and ``controller=``
PLAN_IDS: frozenset[str] = frozenset(
    k for k, v in VECTOR_IDS.items() if v.startswith("shipgym.envs.vector:")
)

#: the Blue Lady aliases: id -> the vessel-neutral id they equal with ``vessel="blue-lady"``
ALIASES: dict[str, str] = {
    "shipgym/BlueLadyHarbour-v0": "shipgym/Harbour-v0",
    "shipgym/BlueLadyStationKeeping-v0": "shipgym/StationKeeping-v0",
    "shipgym/BlueLadyTracking-v0": "shipgym/Tracking-v0",
}


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
        f"unknown scenario or env id {name!r}{did_you_mean(name, [*SCENARIOS, *ENV_IDS])}; "
        f"choose a scenario ({', '.join(SCENARIOS)}) or an id ({', '.join(ENV_IDS)})"
    )


#: what an id needs of its vessel: ``"positioning"`` (thrust in surge, sway and yaw at rest:
#: :attr:`Vessel.can_position <shipgym.dynamics.vessel.Vessel.can_position>`),
#: ``"roll-steering"`` (4 DOF and a rudder) or ``"steering"`` (a rudder and a known approach
#: speed: ``[trials] approach_speed`` or ``[roll_control] design_speed``: the sea trials and
#: course keeping)
NEEDS: dict[str, str] = {
    env_id: "roll-steering" if "Roll" in env_id else "positioning" for env_id in ENV_IDS
}
NEEDS["shipgym/SeaTrial-v0"] = "steering"
NEEDS["shipgym/CourseKeeping-v0"] = "steering"


def task_fits_vessel(env_id: str, vessel: Any) -> bool:
    """Whether the task ``env_id`` can run ``vessel`` (a :class:`~shipgym.dynamics.vessel.
    Vessel`): see :data:`NEEDS`."""
    if NEEDS[env_id] == "roll-steering":
        return vessel.dofs == 4 and bool(vessel.rudders)
    if NEEDS[env_id] == "steering":
        return bool(vessel.rudders) and vessel.approach_speed is not None
    return bool(vessel.can_position)


def register_envs() -> None:
    """Register every id in :data:`ENV_IDS` with Gymnasium (idempotent).

    An id without a vector entry point carries :class:`~shipgym.envs.episode.EpisodeEnd` as
    an additional wrapper, so ``gym.make`` applies it outside the ``TimeLimit``:
    ``info["episode_metrics"]`` at the end of every episode and no ``step()`` after it. Every
    packaged id has a vector entry point, and Gymnasium's ``make_vec`` refuses those with an
    additional wrapper: ``shipgym.make`` adds ``EpisodeEnd`` for them.
    """
    end = WrapperSpec(name="EpisodeEnd", entry_point=EPISODE_END_ENTRY_POINT, kwargs={})
    for env_id, (entry_point, steps) in ENV_IDS.items():
        if env_id not in gym.registry:
            gym.register(
                id=env_id,
                entry_point=entry_point,
                max_episode_steps=steps,
                additional_wrappers=() if env_id in VECTOR_IDS else (end,),
                vector_entry_point=VECTOR_IDS.get(env_id),
            )
