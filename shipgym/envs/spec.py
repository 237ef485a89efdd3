"""What a plan-task env class is, for its single env and its vector env alike: its
arguments and their split (:class:`PlanEnvSpec`), the control timing's checks and the
harbour's placement.

Public names: ``ENV_ARGS``, ``MAX_CONTROL_PERIOD``, ``MAX_SUBSTEPS``, ``PlanEnvSpec``,
``check_control_period``, ``harbour_body``, ``place_harbour``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shipgym._config import is_real

from .physics import check_timestep
from .task import PlanTask

__all__ = [
    "ENV_ARGS",
    "MAX_CONTROL_PERIOD",
    "MAX_SUBSTEPS",
    "PlanEnvSpec",
    "check_control_period",
    "harbour_body",
    "place_harbour",
]

#: most physics steps per control step (``control_period / timestep``); bounds the work of
#: one ``env.step`` (10 000 steps are about half a second).
MAX_SUBSTEPS = 10_000
#: longest control period (s): a DP controller acts every second or so (Tomera 2014: 1 s)
MAX_CONTROL_PERIOD = 10.0


#: the env's own arguments (not the task's) and their defaults
ENV_ARGS: dict[str, Any] = {
    "vessel": None,
    "plant": "default",
    "timestep": 0.05,
    "control_period": 1.0,
    "render_mode": None,
    "integrator": None,
}


class PlanEnvSpec:
    """The class-level spec of a plan-task env (:class:`~shipgym.envs.base.ShipEnv` and its
    registered tasks): its task class, its arguments' split and its task, which
    :class:`~shipgym.envs.vector.ShipVectorEnv` reads from the class alone."""

    #: the task of this env class (the registered tasks set their own)
    task_class: type[PlanTask] = PlanTask
    #: the one vessel of an alias id (``shipgym/BlueLady*-v0``: ``"blue-lady"``), else None
    fixed_vessel: str | None = None

    #: what a DP controller feeds forward unless ``feedforward=`` says
    #: (:class:`~shipgym.controllers.feedforward.FeedforwardConfig` or a preset name;
    #: ``None``: nothing)
    default_feedforward: str | None = None

    #: the episode length (s) after which the env truncates itself (with
    #: ``info["episode_metrics"]``); ``None``: the registered time limit only
    episode_duration: float | None = None

    @classmethod
    def configure(cls, kwargs: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        """The env's arguments with a task's own defaults filled in (timing, sea, ...), and
        the settings the env keeps (``episode_duration``, ...): what the single env and the
        vector env of the class both start from (here: as given)."""
        return dict(kwargs), {}

    @classmethod
    def split_args(
        cls, kwargs: dict[str, Any]
    ) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
        """``(env, task, extras)``: the env's own arguments (:data:`ENV_ARGS`, defaults filled
        in), the task's arguments and the class's settings, after :meth:`configure` (the
        single env and the vector env of the class split alike)."""
        kwargs, extras = cls.configure(kwargs)
        env = {k: kwargs.pop(k, default) for k, default in ENV_ARGS.items()}
        return env, kwargs, extras

    @classmethod
    def make_task(cls, vessel: Any = None, **task_args: Any) -> PlanTask:
        """This env class's task for ``vessel`` and the task arguments (the single env and
        the vector env of the class make it alike)."""
        if cls.fixed_vessel is not None:
            vessel = cls.fixed_vessel if vessel is None else vessel
            if vessel != cls.fixed_vessel:
                base = cls.__mro__[1].__name__
                raise ValueError(
                    f"{cls.__name__} is the task of vessel {cls.fixed_vessel!r}; for "
                    f"vessel={vessel!r} use the vessel-neutral {base} (gym.make('shipgym/"
                    f"{base[:-3]}-v0', vessel=...))"
                )
        return cls.task_class(vessel, owner=cls.__name__, **task_args)


def harbour_body(model: Any) -> int | None:
    """The id of a world's static harbour body (``None`` in open water)."""
    try:
        return int(model.body("harbour").id)
    except KeyError:
        return None


def place_harbour(model: Any, body: int | None, start: NDArray[np.float64]) -> None:
    """Put the static harbour ``body`` of ``model`` at the start pose ``start`` (m, m, rad):
    the layout turns with the start (nothing in open water, ``body`` None)."""
    if body is None:
        return
    model.body_pos[body] = (start[0], start[1], 0.0)
    h = 0.5 * start[2]
    model.body_quat[body] = (math.cos(h), 0.0, 0.0, math.sin(h))


def check_control_period(control_period: Any) -> None:
    """A control period (s) is a number in ``(0, MAX_CONTROL_PERIOD]``.

    Raises:
        TypeError: not a number; ValueError: out of the range (NaN included).
    """
    if not is_real(control_period):
        raise TypeError(f"control_period must be a number of seconds, got {control_period!r}")
    if not 0 < control_period <= MAX_CONTROL_PERIOD:  # NaN fails too
        raise ValueError(
            f"control_period must be > 0 and <= {MAX_CONTROL_PERIOD:g} s, got {control_period!r}"
        )


def _check_timing(timestep: Any, control_period: Any) -> None:
    """Bounds of the physics timestep and control period (see :data:`MIN_TIMESTEP` etc.)."""
    check_timestep(timestep)
    check_control_period(control_period)
    if control_period / timestep > MAX_SUBSTEPS + 0.5:
        raise ValueError(
            f"control_period / timestep = {control_period / timestep:.0f} physics steps per "
            f"control step, more than {MAX_SUBSTEPS}: use a larger timestep"
        )


def _check_render_mode(render_mode: Any, metadata: Mapping[str, Any]) -> None:
    """``ValueError`` unless ``render_mode`` is ``None`` or one of the env's render modes."""
    if render_mode is not None and render_mode not in metadata["render_modes"]:
        raise ValueError(
            f"render_mode must be None or one of {metadata['render_modes']}, got {render_mode!r}"
        )


def _whole_multiple(control_period: float, timestep: float) -> int:
    """Physics steps per control step; raises unless the ratio is a whole number (dm_control)."""
    if not (timestep > 0 and control_period > 0):
        raise ValueError(
            f"timestep and control_period must be > 0 s, got {timestep!r}, {control_period!r}"
        )
    n = round(control_period / timestep)
    if n < 1 or abs(n * timestep - control_period) > 1e-9 * control_period:
        raise ValueError(
            f"control_period {control_period} s must be a whole multiple of the physics "
            f"timestep {timestep} s"
        )
    return n
