r"""Stepped tasks: a task written once over N >= 1 envs, and the one env that steps any of them.

dm_control's Task/Environment split, batched: a :class:`StepTask` says how N episodes start,
what a control step commands before the physics runs, and what it measures, rewards and ends
after; :class:`TaskEnv` owns the loop and Gymnasium's vector API, :class:`TaskSingleEnv` is
its batch of one. Course keeping, rudder-roll stabilisation and the sea trials are stepped
tasks. A new one is one class, run with no package file changed::

    gym.register("my/Task-v0", entry_point="shipgym.envs.stepped:TaskSingleEnv",
                 vector_entry_point="shipgym.envs.stepped:TaskEnv",
                 kwargs={"task": MyTask, "vessel": "kvlcc2-100m"})

Public names: ``StepTask``, ``TaskEnv``, ``TaskSingleEnv``.

Design notes: docs/design/envs.stepped.md.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from shipgym._jit import entry

from .batched import BatchedEnv, SingleEnv, check_num_envs
from .spec import _check_timing, _whole_multiple

__all__ = ["StepTask", "TaskEnv", "TaskSingleEnv"]

Array = NDArray[np.float64]
Bools = NDArray[np.bool_]


class StepTask:
    """A task over N >= 1 envs that :class:`TaskEnv` steps (module docstring).

    A subclass's ``__init__(num_envs, **settings)`` checks its settings, calls
    :meth:`set_timing` and :meth:`attach`, and builds its :attr:`physics` (a
    :class:`~shipgym.envs.batchphysics.BatchedPhysics` of ``num_envs`` hulls); it implements
    the hooks, each over every env at once (``mask`` / ``active``: the envs concerned; the
    others must not change):

    - ``initialize_episode(rngs, mask)``: start the episodes of ``mask``, env ``i`` drawing
      from ``rngs[i]`` in a fixed order (:attr:`steps` is already 0 there);
    - ``before_step(actions, active)``: the commands (and external forces) of one control
      period from ``actions`` ``(N, m)`` float64, finite, of the action space's shape (the
      task clips and flags what is beyond its range);
    - ``after_step(active)``: after the physics' ``n_substeps`` steps and :attr:`steps`
      counted, returns ``(terms, terminated, info)``: the reward terms (a dict name ->
      ``(N,)``, in :attr:`reward_terms`' order; the reward is their sum, left to right),
      the ``(N,)`` termination and the info dict of ``(N, ...)`` arrays;
    - ``observation()``: every env's observation now, ``(N, ...)``;
    - ``reset_info(mask)``: the info of a reset;
    - ``episode_metrics(done)`` (optional): the metrics of the envs of ``done`` at their
      episode's end, a dict of ``(N, ...)`` arrays.

    Attributes (set by :meth:`set_timing`, :meth:`attach` and the subclass):
        num_envs: N.
        physics: the hulls' physics (the subclass's).
        timestep: the physics step (s).
        control_period: the control period (s), a whole multiple of ``timestep``.
        n_substeps: physics steps per control period.
        episode_duration: the simulated time after which an episode is truncated (s);
            ``None``: the task ends its episodes itself.
        single_observation_space, single_action_space: one env's spaces.
        steps: each env's control steps in its episode, (N,) ints (the env counts them).
    """

    #: what the task needs of its vessel (:data:`shipgym.envs.registration.NEEDS`)
    needs: ClassVar[str] = "steering"
    #: the names of the reward terms, in the order they are summed
    reward_terms: ClassVar[tuple[str, ...]] = ()

    num_envs: int
    physics: Any
    timestep: float
    control_period: float
    n_substeps: int
    episode_duration: float | None
    single_observation_space: spaces.Space[Any]
    single_action_space: spaces.Space[Any]
    steps: NDArray[np.int64]

    def set_timing(
        self, timestep: float, control_period: float, episode_duration: float | None
    ) -> None:
        """The physics step and control period (s), checked (the control period a whole
        multiple of the physics step), and the episode's duration (s; ``None``: the task ends
        its episodes itself)."""
        _check_timing(timestep, control_period)
        self.n_substeps = _whole_multiple(control_period, timestep)
        self.timestep = float(timestep)
        self.control_period = float(control_period)
        self.episode_duration = None if episode_duration is None else float(episode_duration)

    def attach(
        self,
        num_envs: int,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
    ) -> None:
        """The batch's size and one env's spaces; the step counter and the compiled entry
        points start here."""
        check_num_envs(num_envs)
        self.num_envs = num_envs
        self.single_observation_space = observation_space
        self.single_action_space = action_space
        self.steps = np.zeros(num_envs, dtype=np.int64)
        self._entries: dict[Any, Any] = {}

    def call(self, fn: Any, *args: Any) -> None:
        """``fn(*args)`` through its compiled entry point (:func:`shipgym._jit.entry`, found
        once per function and task)."""
        e = self._entries.get(fn)
        if e is None:
            e = self._entries[fn] = entry(fn, args)
        e(*args)

    # ---- hooks -----------------------------------------------------------------------------
    def initialize_episode(self, rngs: list[np.random.Generator], mask: Bools) -> None:
        raise NotImplementedError

    def before_step(self, actions: Array, active: Bools) -> None:
        raise NotImplementedError

    def after_step(self, active: Bools) -> tuple[dict[str, Array], Bools, dict[str, Any]]:
        raise NotImplementedError

    def observation(self) -> Any:
        raise NotImplementedError

    def reset_info(self, mask: Bools) -> dict[str, Any]:
        raise NotImplementedError

    def episode_metrics(self, done: Bools) -> dict[str, Any] | None:
        return None


class TaskEnv(BatchedEnv):
    """N envs of a :class:`StepTask` stepped together (module docstring).

    ``TaskEnv(num_envs, *, autoreset_mode="next-step", task=None, **settings)``: ``task``
    the task class (a subclass names it in :attr:`task_class` instead), ``settings`` its
    arguments. Env ``i`` reset with seed ``s + i`` is the single env (:class:`TaskSingleEnv`)
    reset with ``s``, bit for bit. The task's attributes (its settings, ``physics``, ...)
    read through the env; the task itself is :attr:`task`.
    """

    #: the task class of a family's env (``None``: given as ``task=``)
    task_class: ClassVar[type[StepTask] | None] = None

    def __init__(
        self,
        num_envs: int,
        *,
        autoreset_mode: str = "next-step",
        task: type[StepTask] | None = None,
        **settings: Any,
    ) -> None:
        cls = task or self.task_class
        if not (isinstance(cls, type) and issubclass(cls, StepTask)):
            raise TypeError(f"task must be a StepTask subclass, got {cls!r}")
        self.task = t = cls(num_envs, **settings)
        self._setup(num_envs, t.single_observation_space, t.single_action_space,
                    autoreset_mode)  # type: ignore[arg-type]  # fmt: skip

    def __getattr__(self, name: str) -> Any:
        """The task's attributes (its settings, ``physics``, ...)."""
        task = self.__dict__.get("task")
        if task is None or name.startswith("__"):
            raise AttributeError(name)
        return getattr(task, name)

    def _reset_envs(self, mask: Bools) -> None:
        self.task.steps[mask] = 0
        self.task.initialize_episode(self._rngs, mask)  # type: ignore[arg-type]

    def _observation(self) -> Any:
        return self.task.observation()

    def _reset_info(self, mask: Bools) -> dict[str, Any]:
        return self.task.reset_info(mask)

    def _step_envs(
        self, actions: Array, active: Bools
    ) -> tuple[Array, Bools, Bools, dict[str, Any]]:
        t = self.task
        t.before_step(actions, active)
        every = bool(active.all())
        t.physics.step(t.n_substeps, mask=None if every else active)
        t.steps += active
        terms, terminated, info = t.after_step(active)
        values = list(terms.values())  # their sum left to right, the same at any N
        reward = values[0].copy() if values else np.zeros(self.num_envs)
        for value in values[1:]:
            reward += value
        info["reward_terms"] = terms
        if t.episode_duration is None:
            truncated = np.zeros(self.num_envs, dtype=bool)
        else:
            up = t.steps * t.control_period >= t.episode_duration - 1e-9
            truncated = up & ~terminated  # (the base keeps the active envs' flags)
        return reward, terminated, truncated, info

    def _episode_metrics(self, done: Bools) -> dict[str, Any] | None:
        return self.task.episode_metrics(done)


class TaskSingleEnv(SingleEnv):
    """The Gymnasium single env of a :class:`StepTask`: its :class:`TaskEnv` of one.

    ``TaskSingleEnv(render_mode=None, *, task=None, **settings)`` (a family's subclass names
    its vector env in ``batched``); the task's attributes read through it.
    """

    batched = TaskEnv
    batch: TaskEnv

    def __getattr__(self, name: str) -> Any:
        """The task's attributes (its settings, ``physics``, ...): the batch's."""
        batch = self.__dict__.get("batch")
        if batch is None or name.startswith("_"):
            raise AttributeError(name)
        return getattr(batch, name)
