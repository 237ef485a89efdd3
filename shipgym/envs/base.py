"""The ship Gymnasium environment: physics + guidance task (dm_control's Physics/Task split).

:class:`ShipEnv` composes a :class:`~shipgym.envs.physics.VesselPhysics` (MuJoCo and the
vessel's hull model) with a task: a manoeuvre plan followed through
:class:`~shipgym.guidance.Guidance`, a reward made of named terms, metrics and termination.
Everything is generic over the vessel (``vessel=``, a :class:`~shipgym.dynamics.vessel.Vessel`
package): the action space comes from its actuators, the guidance limits from the vessel file.
The registered tasks (:mod:`shipgym.envs.tasks`) differ only in their plan, start,
disturbances and time limit.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Mapping
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from shipgym._config import is_real
from shipgym.disturbances import CurrentConfig, WaveConfig, WindConfig
from shipgym.dynamics.vessel import Vessel
from shipgym.guidance import Guidance, ManoeuvrePlan, Reference
from shipgym.guidance.limits import vessel_limits
from shipgym.guidance.rframe import to_r_frame
from shipgym.metrics import ManoeuvreMetrics
from shipgym.observers.sensors import SensorConfig, Sensors
from shipgym.records import StepRecord, step_record_of_env

from .physics import MAX_TIMESTEP, MIN_TIMESTEP, NO_CURRENT, VesselPhysics, check_timestep
from .task import (
    MAX_START_OFFSET,
    SCENES,
    PlanTask,
    RewardWeights,
    _vec3,
    parse_sensors_arg,
    parse_waves_arg,
    tracking_penalty,
)

__all__ = [
    "MAX_CONTROL_PERIOD",
    "MAX_START_OFFSET",
    "MAX_SUBSTEPS",
    "MAX_TIMESTEP",
    "MIN_TIMESTEP",
    "BlueLadyEnv",
    "RewardWeights",
    "SCENES",
    "ShipEnv",
    "parse_sensors_arg",
    "parse_waves_arg",
    "tracking_penalty",
]

#: most physics steps per control step (``control_period / timestep``); bounds the work of
#: one ``env.step`` (10 000 steps are about half a second).
MAX_SUBSTEPS = 10_000
#: longest control period (s): a DP controller acts every second or so (Tomera 2014: 1 s)
MAX_CONTROL_PERIOD = 10.0


#: the observer and controller stack's arguments (shipgym.make's wrappers, the vector env's)
_STACK_ARGS = frozenset({"observer", "observer_options", "controller", "residual_scale"})

#: the env's own arguments (not the task's) and their defaults
ENV_ARGS: dict[str, Any] = {
    "vessel": None,
    "plant": "default",
    "timestep": 0.05,
    "control_period": 1.0,
    "render_mode": None,
}


class _Sample(NamedTuple):
    """What a step produced, before it is turned into observation and info.

    The arrays go into ``info``; the task's terms and the metrics read the same values. A
    tuple, not a frozen dataclass: built every control step, and a frozen dataclass costs a
    microsecond more to build.
    """

    t: float
    eta: NDArray[np.float64]
    nu: NDArray[np.float64]
    ref: Reference
    eta_r: NDArray[np.float64]
    thrust: NDArray[np.float64]  # of every actuator (N), read once per step
    ref_r: list[float]  # ref.eta_d_r


class ShipEnv(gym.Env[NDArray[np.float32], NDArray[np.float32]]):
    r"""A vessel on a manoeuvre plan: the common spec of every ``shipgym/...`` env.

    ## Description
    A ship of the vessel library (``vessel=``: ``"blue-lady"``, ``"star-hercules"``,
    ``"wimpey-sealab"``, or the path of a vessel package; ``shipgym.vessels()``) in the
    horizontal plane (plus roll for a 4-DOF vessel), simulated in MuJoCo with its exact hull
    model, actuator lags and gusty wind. A guidance system moves a virtual ship along a
    manoeuvre plan (legs in the r-frame of Tomera (2014)); the agent drives the actuators to
    follow it.

    ## Action Space
    ``Box(-1, 1, (n,), float32)`` with one normalised command per actuator channel
    (``vessel.actuators.channel_names``; ``n = 3`` for the Blue Lady). A range around zero is
    scaled separately on each side (``a >= 0 -> a * upper``, ``a < 0 -> a * |lower|``):

    | Vessel | Num | Action | Physical command | Unit |
    |--------|-----|--------|------------------|------|
    | Blue Lady | 0 | main propeller | ``a * 480`` if ``a >= 0`` else ``a * 200`` | rpm |
    |  | 1 | bow tunnel thruster | ``p2 = a`` (thrust 44.1 p2, to starboard) | 1 |
    |  | 2 | stern tunnel thruster | ``p3 = a`` | 1 |
    | Star Hercules | 0-3 | main propeller, three tunnels | relative thrust | 1 |
    | Wimpey Sealab | 0, 2, 4, 6 | azimuth thrust | relative thrust (reversible) | 1 |
    |  | 1, 3, 5, 7 | azimuth turning rate | ``a * 10`` | deg/s |

    Actions outside [-1, 1] are clipped and flagged in ``info["action_clipped"]``; NaN or
    infinite actions raise ``ValueError``.

    ## Observation Space
    ``Box(-inf, inf, (12 + n,), float32)``; what a controller may know (navigation data, i.e.
    the truth here and an observer's estimate once an observer wrapper is stacked):

    | Num | Observation | Unit |
    |-----|-------------|------|
    | 0-1 | position error ship - reference, body frame (forward, starboard) | m |
    | 2 | heading error ship - reference, wrapped | rad |
    | 3-5 | body velocity u, v, r | m/s, m/s, rad/s |
    | 6-8 | reference body velocity | m/s, m/s, rad/s |
    | 9-11 | reference body acceleration | m/s^2, m/s^2, rad/s^2 |
    | 12-(11+n) | previous (applied) normalised action | 1 |

    ``observation_structure`` maps these names to slices.
    :class:`~shipgym.envs.integral.ErrorIntegralObservation` (stacked above the observer)
    appends the leaky integral of the observed errors 0-2 (m s, m s, rad s), what a
    memoryless learned policy needs to cancel a steady load such as the mean wind.

    ## Rewards
    ``reward = reward_position + reward_heading + reward_velocity + reward_effort +
    reward_rate + reward_contact + reward_leg`` (each term in ``info``):
    ``-w_p |e_xy|^2``, ``-w_psi e_psi^2``, ``-w_v |nu - nu_d|^2``, ``-w_u |a|^2``,
    ``-w_du |a - a_prev|^2``, ``-w_c`` on quay contact, ``+w_leg`` per completed leg
    (weights: :class:`RewardWeights`, argument ``reward_weights``). With the weights'
    ``position_scale``, ``heading_scale``, ``velocity_scale`` the three tracking terms saturate
    (``-w s^2 (1 - exp(-q^2/s^2))``: the square near the reference, bounded by ``w s^2``), the
    form the learned baselines train with.

    ## Starting State
    At the plan's start pose (default: origin, heading north) at rest, plus uniform noise of
    ``start_noise`` (m, m, rad) when given; wind gusts from the seeded generator.

    ## Episode End
    Terminated when the hull touches a quay (``info["quay_contact"]``) or, if
    ``terminate_on_finish``, when the last leg is complete (``info["finished"]``).
    Truncated by the registered time limit (``max_episode_steps`` control steps, ``gym.make``'s
    ``TimeLimit``). At the end of every episode ``info`` holds ``episode_metrics``, and
    :meth:`step` raises ``gymnasium.error.ResetNeeded`` until :meth:`reset` is called (the env
    itself on termination; on truncation the
    :class:`~shipgym.envs.episode.EpisodeEnd` wrapper that ``gym.make`` applies to every
    shipgym id, outside the ``TimeLimit``).

    ## Info
    Truth ``eta`` (m, m, rad; NED), ``nu`` (and ``phi`` (rad), ``p`` (rad/s) for a 4-DOF
    vessel); navigation data ``nav_eta``, ``nav_nu`` (what
    controllers use); reference ``eta_d`` (NED), ``eta_d_r``, ``eta_dot_d_r``,
    ``eta_ddot_d_r``, ``eta_P`` (leg start) and ``eta_r`` (ship in the r-frame); ``leg``,
    ``legs_completed``, ``finished``, ``t`` (s); ``command`` (rpm, 1, 1), ``thrust`` (N),
    ``saturated``, ``action_clipped``; ``tau_wind``, ``tau_waves`` (N, N, N m, body);
    ``current_body`` (``nu_c = [u_c, v_c, 0]``, m/s), ``wave_elevation`` (m, wave reference point);
    ``measurements`` (the
    sensor samples taken during the step: ``t``, measured NED pose ``z`` or ``None`` in a
    dropout, ``valid``, ``outlier`` (a truth flag), applied body thrust ``tau`` and
    ``tau_command``, the body thrust the held commands give in steady state at the current
    azimuth angles, :attr:`VesselPhysics.tau_command
    <shipgym.envs.physics.VesselPhysics.tau_command>`); ``quay_contact``,
    ``contacts``; the ``reward_*`` terms; and at the end of every episode (terminated or
    truncated) ``episode_metrics``
    (Tomera 2014 eqs. 54-57 and thruster usage, :class:`shipgym.metrics.ManoeuvreMetrics`).
    ``record``: the same as a typed :class:`shipgym.records.StepRecord` (the same arrays),
    which the observer and controller wrappers hand on with their own parts.

    ## Arguments
    | Argument | Default | Description |
    |---|---|---|
    | ``vessel`` | (required) | vessel name, package path or :class:`Vessel` |
    | ``plan`` | ``"tomera2014"`` | plan name or :class:`ManoeuvrePlan` |
    | ``plant`` | ``"default"`` | plant variant of the vessel (Blue Lady: ``"table2-literal"``, |
    |  |  | ``"seed-linear"`` too) |
    | ``wind`` | nominal@300 | ``"SPEED@FROM_DEG"`` (m/s, deg the wind comes from; default |
    |  |  | the vessel's nominal wind from 300 deg: ``"3@300"`` for the Blue Lady), |
    |  |  | ``(speed m/s, from deg)``, ``WindConfig``, mapping, or ``None`` (no wind) |
    | ``sensors`` | ``"default"`` | preset (``default``, ``dgps``, ``rtk``), config or ``None`` |
    | ``waves`` | ``None`` | ``WaveConfig``, preset name or mapping: drift load on the hull, |
    |  |  | first-order motion added to the measurements |
    | ``current`` | ``None`` | ``"SPEED@TO_DEG"`` (m/s, deg the water goes to), |
    |  |  | ``(speed m/s, to deg)``, ``CurrentConfig``, mapping, or ``None`` (none) |
    | ``scene`` | ``"harbour"`` | ``"harbour"`` (vessels that fit it) or ``"open-water"`` |
    | ``start_pose`` | ``(0, 0, 0)`` | NED start pose (m, m, rad); the harbour turns with it |
    | ``start_noise`` | ``(0, 0, 0)`` | uniform start perturbation half-widths (m, m, rad) |
    | ``timestep`` | ``0.05`` | physics step (s) |
    | ``control_period`` | ``1.0`` | control step (s); a whole multiple of ``timestep`` |
    | ``terminate_on_finish`` | ``True`` | end the episode when the plan is complete |
    | ``reward_weights`` | ``RewardWeights()`` | weights of the reward terms |
    | ``render_mode`` | ``None`` | ``"rgb_array"`` (needs an EGL/OSMesa/GLFW backend) |

    ``wind`` and ``current`` accept exactly the forms of :meth:`WindConfig.coerce
    <shipgym.disturbances.WindConfig.coerce>` and :meth:`CurrentConfig.coerce
    <shipgym.disturbances.CurrentConfig.coerce>`: plain-number directions are degrees,
    everywhere. ``wind_config``, ``current_config`` and ``sensor_config`` report what the
    physics and the sensors use in the current episode (they are read from them, so a task
    that draws its disturbances per episode reports the draw after :meth:`reset`).

    ## Version History
    * v0: initial version (the ``shipgym/BlueLady*-v0`` ids are the Blue Lady's aliases of
      ``shipgym/Harbour-v0``, ``StationKeeping-v0``, ``Tracking-v0``).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 1}

    #: the task of this env class (the registered tasks set their own)
    task_class: type[PlanTask] = PlanTask
    #: the one vessel of an alias id (``shipgym/BlueLady*-v0``: ``"blue-lady"``), else None
    fixed_vessel: str | None = None

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

    def __init__(self, vessel: Vessel | str | None = None, **kwargs: Any) -> None:
        stack = sorted(set(kwargs) & _STACK_ARGS)
        if stack:  # the vector env takes them; the single env is wrapped by shipgym.make
            raise TypeError(
                f"{type(self).__name__} got {', '.join(stack)}: the observer and controller of a "
                "single env are wrappers; use shipgym.make(id, observer=..., controller=...) "
                "(gym.make_vec(id, num_envs, observer=..., controller=...) for a vector env)"
            )
        # the env's own arguments (plant, timestep, control_period, render_mode: ENV_ARGS),
        # the task's (plan, wind, sensors, waves, current, scene, start, reward), and the
        # settings the class keeps (episode_duration, ...), as the vector env splits them
        env, task_args, extras = self.split_args({"vessel": vessel, **kwargs})
        for name, value in extras.items():
            setattr(self, name, value)
        plant, timestep, control_period, render_mode = (
            env["plant"],
            env["timestep"],
            env["control_period"],
            env["render_mode"],
        )
        self.task = task = self.make_task(env["vessel"], **task_args)
        self.vessel = task.vessel
        _check_render_mode(render_mode, self.metadata)
        _check_timing(timestep, control_period)
        self.n_substeps = _whole_multiple(control_period, timestep)
        self.control_period = float(control_period)
        self.sensors = None if task.sensors is None else Sensors(task.sensors)
        self._sensor_steps = (
            None if task.sensors is None else _whole_multiple(task.sensors.period, timestep)
        )
        self._steps = 0
        self._episode_over = True  # until the first reset
        # the last measured pose (floats; None before the first valid sample)
        self._last_z: tuple[float, float, float] | None = None
        self.physics = VesselPhysics(
            self.vessel,
            plant,
            wind=task.wind,
            waves=task.waves,
            current=task.current,
            world=task.scene,
            timestep=timestep,
            # MuJoCo's step where there are quays; the same forces without MuJoCo in open water
            integrator="mujoco" if task.scene == "harbour" else "leapfrog",
        )
        self.actuators = self.physics.actuators  # the laws of this plant (vessel.actuators_for)
        self.n_actions = self.actuators.n_channels
        # (lower, upper, lower + tol, upper - tol) of the saturation test in step(), the
        # last two as lists of floats
        self._sat_bounds: tuple[Any, ...] | None = None
        self._actuator_names = self.actuators.names
        multi = self.actuators.channel_names != self.actuators.names
        self._channel_names = self.actuators.channel_names if multi else ()
        self.limits = vessel_limits(self.vessel)
        self.guidance = Guidance(task.plan, limits=self.limits)
        self.metrics = ManoeuvreMetrics(
            sample_period=1.0,
            n_actuators=len(self.actuators),
            n_channels=self.n_actions,
            control_period=self.control_period,
            reversible=(self.actuators.lower < 0.0).tolist(),
        )
        # per-actuator saturation from the channels' (None: one channel per actuator)
        sl = self.actuators.slices
        self._slices = None if all(x.stop - x.start == 1 for x in sl) else sl
        self.render_mode = render_mode
        self._renderer: Any = None
        n = self.n_actions
        self.action_space = spaces.Box(-1.0, 1.0, (n,), np.float32)
        self.observation_structure, i = task.observation_structure(n)
        self.observation_space = spaces.Box(-np.inf, np.inf, (i,), np.float32)
        self._harbour_body = harbour_body(self.physics.model)
        self._prev_action = np.zeros((1, n))
        self._contact = False
        # the task's outputs of N = 1: observation and reward terms; the inputs it reads
        self._obs = np.zeros((1, i), np.float32)
        self._rew = np.zeros((1, len(task.reward_terms)))
        self._flags = np.zeros((2, 1), bool)  # switched, new contact
        self._eta_r = np.zeros((1, 3))

    # ---- the task's settings ----------------------------------------------------------------
    @property
    def plan(self) -> ManoeuvrePlan:
        """The plan given (a drawing task's default)."""
        return self.task.plan

    @property
    def scene(self) -> str:
        return self.task.scene

    @property
    def start_pose(self) -> NDArray[np.float64]:
        return self.task.start_pose

    @property
    def start_noise(self) -> NDArray[np.float64]:
        return self.task.start_noise

    @property
    def reward_weights(self) -> RewardWeights:
        return self.task.reward_weights

    @property
    def terminate_on_finish(self) -> bool:
        return self.task.terminate_on_finish

    @property
    def wave_config(self) -> WaveConfig | None:
        return self.task.waves

    # ---- what the episode uses (read from the physics and sensors: always honest) ----------
    @property
    def wind_config(self) -> WindConfig | None:
        """The wind the physics uses now (``None``: no aerodynamic loads); set at reset."""
        return self.physics.wind_config if self.physics.aerodynamics else None

    @property
    def current_config(self) -> CurrentConfig:
        """The current the physics uses now (``speed == 0``: none); set at reset."""
        return self.physics.current_config

    @property
    def sensor_config(self) -> SensorConfig | None:
        """The sensor configuration the sensors use now (``None``: no sensors); set at reset."""
        return None if self.sensors is None else self.sensors.config

    # ---- gym API ---------------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        """Start an episode; ``options`` may hold ``start_pose`` (m, m, rad)."""
        super().reset(seed=seed)
        rng = self.np_random
        start = None
        unknown = sorted(set(options or {}) - {"start_pose"})
        if unknown:
            raise ValueError(f"unknown reset options {unknown}; valid: ['start_pose']")
        if options and "start_pose" in options:
            start = _vec3(options["start_pose"], "options['start_pose']")
        ep = self.task.initialize_episode(rng, start)
        if ep.plan is not self.guidance.plan:
            self.guidance = Guidance(ep.plan, limits=self.limits)
        if ep.wind is not self.wind_config:
            self.physics.set_wind(ep.wind)
        current = ep.current
        if (NO_CURRENT if current is None else current) is not self.physics.current_config:
            self.physics.set_current(current)
        sensors = ep.sensors
        if sensors is not None and self.sensors is not None and sensors is not self.sensors.config:
            self.sensors = Sensors(sensors)
        start = ep.start
        self._place_harbour(start)
        self.physics.reset(eta=ep.eta0, rng=rng)
        if self.sensors is not None:
            self.sensors.reset(rng)
        self._steps = 0
        self._episode_over = False
        self._last_z = None
        self.guidance.reset(start, t0=0.0)
        self.metrics.reset()
        self._prev_action = np.zeros((1, self.n_actions))
        self._contact = False
        measurements = [self._measure()] if self.sensors is not None else []
        self._flags[:] = False
        sample = self._observe(self._prev_action)
        self._record_metrics(sample)
        n = self.n_actions
        command = self.physics.command
        info = self._info(sample, command, np.zeros(n, bool), np.zeros(n, bool), False, {}, [])
        info["measurements"] = measurements
        info["record"] = self._record(info, sample)
        return self._obs[0].copy(), info

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        """Apply normalised thruster commands for one control period.

        Raises:
            gymnasium.error.ResetNeeded: before the first :meth:`reset` or after the episode
                terminated (after a time-limit truncation the ``EpisodeEnd`` wrapper raises).
            ValueError: an action of the wrong shape or with NaN / infinite values.
        """
        if self._episode_over:
            raise gym.error.ResetNeeded(
                "the episode has ended (terminated) or was never started: call reset() before "
                "step()"
            )
        # the control step in plain floats where the values only pass through (the same
        # comparisons and products as the array forms), and each physics value read once
        acts, phys = self.actuators, self.physics
        _, vals = acts.as_vector(action, "action")
        # np.clip(a, -1, 1) and its flags (comparisons: min() and max() of two numbers are
        # slow calls)
        cl = [-1.0 if v < -1.0 else 1.0 if v > 1.0 else v for v in vals]
        clipped = np.array(cl, float)
        action_clipped = list(map(operator.ne, cl, vals))  # (map: same lengths, no zip)
        command = acts.action_to_command(clipped)
        clipped_cmd = phys.set_command(command).tolist()
        # an actuator is saturated when its command sits at a limit of its range
        lo, hi = acts.lower, acts.upper
        bounds = self._sat_bounds
        if bounds is None or bounds[0] is not lo or bounds[1] is not hi:
            tol = 1e-9 * (hi - lo)
            bounds = self._sat_bounds = (lo, hi, (lo + tol).tolist(), (hi - tol).tolist())
        saturated = [
            k or c <= lt or c >= ht
            for k, c, lt, ht in zip(
                clipped_cmd, command.tolist(), bounds[2], bounds[3], strict=True
            )
        ]
        measurements = self._advance(self.n_substeps)
        contacts = phys.contacts() if phys.data.ncon else []
        new_contact = bool(contacts) and not self._contact
        self._contact = self._contact or bool(contacts)
        t, eta = phys.time, phys.eta
        switched = self.guidance.update(t, eta)
        flags = self._flags
        flags[0, 0], flags[1, 0] = switched, new_contact
        sample = self._observe(clipped.reshape(1, -1), t, eta)
        self._record_metrics(sample, saturated, clipped)
        rewards = dict(zip(self.task.reward_terms, self._rew[0].tolist(), strict=True))
        reward = float(sum(rewards.values()))
        self._prev_action = clipped.reshape(1, -1)
        finished = self.guidance.finished
        terminated = self._contact or (finished and self.terminate_on_finish)
        truncated = not terminated and self._past_duration(t)
        flags = np.array(list(map(operator.or_, saturated, action_clipped)), bool)
        info = self._info(
            sample, command, flags, np.array(action_clipped, bool), finished, rewards, contacts
        )
        info["measurements"] = measurements
        info["record"] = self._record(info, sample)
        if terminated or truncated:  # a time-limit truncation is seen by EpisodeEnd
            self._episode_over = True
            info["episode_metrics"] = self.episode_metrics()
        return self._obs[0].copy(), reward, terminated, truncated, info

    def _past_duration(self, t: float) -> bool:
        """Whether the time ``t`` (s) reached :attr:`episode_duration` (to half a step)."""
        d = self.episode_duration
        return d is not None and t >= d - 0.5 * self.physics.timestep

    def render(self) -> NDArray[np.uint8] | None:
        """An RGB frame (H, W, 3) of the map camera; needs ``render_mode="rgb_array"``."""
        if self.render_mode is None:
            gym.logger.warn("render() called without render_mode; pass render_mode='rgb_array'")
            return None
        if self._renderer is None:
            self._renderer = _make_renderer(self.physics.model)
        cam = "map" if self.scene == "harbour" else "top"
        self._renderer.update_scene(self.physics.data, camera=cam)
        return self._renderer.render()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # ---- helpers ---------------------------------------------------------------------------
    def _advance(self, n: int) -> list[dict[str, Any]]:
        """Step the physics ``n`` times, sampling the sensors on their grid; stop on contact."""
        phys = self.physics
        stop = self.scene == "harbour"
        out: list[dict[str, Any]] = []
        every = self._sensor_steps
        while n > 0:
            k = n if every is None else every - self._steps % every
            if k > n:  # (a comparison, not min(): two-argument min() is a slow call)
                k = n
            taken = phys.step(k, stop_on_contact=stop)
            self._steps += taken
            n -= taken
            if every is not None and self._steps % every == 0:
                out.append(self._measure())
            if taken < k:  # contact
                break
        return out

    def _measure(self) -> dict[str, Any]:
        """One sensor sample now: measured NED pose (or None in a dropout), the thrust the DP
        system computes from the actuator states (``tau``: its bollard model,
        :attr:`VesselPhysics.tau_model`) and the steady-state thrust of the held commands
        (``tau_command``)."""
        assert self.sensors is not None
        phys = self.physics
        x, y, psi = phys.eta.tolist()
        dx, dy, dpsi = phys.wave_motion()  # first-order wave motion is seen, not lived
        t = phys.time
        _, z, valid, outlier = self.sensors.measure_pose(t, x + dx, y + dy, psi + dpsi)
        if z is not None:
            self._last_z = z
        return {
            "t": t,
            "z": None if z is None else np.array(z, float),
            "valid": valid,
            "outlier": outlier,
            "tau": phys.tau_model,
            "tau_command": phys.tau_command,
        }

    def episode_metrics(self) -> dict[str, Any]:
        """Accuracy indices (Tomera 2014 eqs. 54-57), thruster usage, legs and contact so far."""
        out = dict(self.metrics.summary())
        out["completed"] = bool(self.guidance.finished)
        out["legs_completed"] = len(self.guidance.leg_completion_times)
        out["leg_times"] = list(self.guidance.leg_completion_times)
        out["quay_contact"] = bool(self._contact)
        out["duration_s"] = float(self.physics.time)
        return out

    def _observe(
        self,
        action: NDArray[np.float64],
        t: float | None = None,
        eta: NDArray[np.float64] | None = None,
    ) -> _Sample:
        """The sample now and the task's observation (``_obs``) and reward terms (``_rew``)
        of the applied ``action`` (1, n) (``t``, ``eta``: the time and pose, when already
        read)."""
        phys = self.physics
        if t is None or eta is None:
            t, eta = phys.time, phys.eta
        nu = phys.nu
        ref = self.guidance.reference(t)
        self.reference = ref
        e, w = eta.reshape(1, 3), nu.reshape(1, 3)
        self.task.terms(e, w, e, w, ref.buffer, action, self._prev_action, self._flags[0],
                        self._flags[1], self._obs, self._rew, self._eta_r)  # fmt: skip
        return _Sample(t, eta, nu, ref, self._eta_r[0].copy(), phys.thrust, ref.eta_d_r.tolist())

    def _record_metrics(
        self,
        s: _Sample,
        saturated: list[bool] | None = None,
        command: NDArray[np.float64] | None = None,
    ) -> None:
        z = self._last_z
        ref = s.ref
        # the arrays where they exist (their tolist() is cheaper than checking floats)
        self.metrics.record(
            s.t,
            s.eta_r,
            ref.eta_d_r,
            eta_meas_r=None if z is None else to_r_frame(z, ref.eta_P, s.ref_r[2]),
            thrust=s.thrust,
            saturated=saturated
            if saturated is None or self._slices is None
            else [any(saturated[sl]) for sl in self._slices],
            leg=ref.leg,
            command=command,
        )

    @property
    def prev_action(self) -> NDArray[np.float64]:
        """The normalised action applied in the last step (zeros after a reset)."""
        return self._prev_action[0].copy()

    def navigation_observation(
        self,
        eta: NDArray[np.float64],
        nu: NDArray[np.float64],
        ref: Reference,
        prev_action: NDArray[np.float64],
    ) -> NDArray[np.float32]:
        """The observation vector (layout in the class docstring) from navigation data (the
        task's observation of N = 1, as an observer wrapper forms it from its estimate)."""
        obs = np.zeros((1, self.observation_space.shape[0]), np.float32)
        e, w = np.reshape(eta, (1, 3)), np.reshape(nu, (1, 3))
        prev = np.reshape(prev_action, (1, -1)).astype(float)
        self.task.terms(e, w, e, w, ref.buffer, prev, prev, self._flags[0], self._flags[1], obs,
                        np.zeros((1, len(self.task.reward_terms))), np.zeros((1, 3)))  # fmt: skip
        return obs[0]

    def _info(
        self,
        s: _Sample,
        command: NDArray[np.float64],
        saturated: NDArray[np.bool_],
        action_clipped: NDArray[np.bool_],
        finished: bool,
        rewards: Mapping[str, float],
        contacts: list[tuple[str, str]],
    ) -> dict[str, Any]:
        phys = self.physics
        ref = s.ref
        # copies of the reference's arrays: info is the caller's to keep and change
        info: dict[str, Any] = {
            "t": s.t,
            "eta": s.eta,
            "nu": s.nu,
            "nav_eta": s.eta,
            "nav_nu": s.nu,
            "eta_d": ref.eta_d_n.copy(),
            "eta_d_r": ref.eta_d_r.copy(),
            "eta_dot_d_r": ref.eta_dot_d_r.copy(),
            "eta_ddot_d_r": ref.eta_ddot_d_r.copy(),
            "eta_P": ref.eta_P.copy(),
            "eta_r": s.eta_r,
            "leg": ref.leg,
            "legs_completed": self.guidance.legs_completed,
            "finished": finished,
            "command": np.asarray(command, dtype=float),
            "thrust": s.thrust,
            "actuator_state": phys.actuator_state,
            "saturated": saturated,
            "action_clipped": action_clipped,
            "tau_wind": np.array(phys.tau_wind, float),
            "tau_waves": np.array(phys.tau_waves, float),
            "current_body": np.array([*phys.nu_c, 0.0], float),
            "wave_elevation": phys.wave_elevation(),
            "quay_contact": self._contact,
            "contacts": contacts,
        }
        if phys.dofs == 4:
            info["phi"] = phys.phi
            info["p"] = phys.p
        info.update(rewards)
        return info

    def _record(self, info: Mapping[str, Any], s: _Sample) -> StepRecord:
        """The typed record of a step (``info["record"]``), holding the same arrays as ``info``."""
        return step_record_of_env(
            info, s.ref, self._prev_action[0], self._actuator_names, self._channel_names
        )

    def _place_harbour(self, start: NDArray[np.float64]) -> None:
        """Put the static harbour body at the start pose (the layout turns with the start)."""
        place_harbour(self.physics.model, self._harbour_body, start)

    def command_to_action(self, command: NDArray[np.float64]) -> NDArray[np.float64]:
        """Physical command (channel order, each in its unit) to the normalised action."""
        return self.actuators.command_to_action(command)


class BlueLadyEnv(ShipEnv):
    """:class:`ShipEnv` with the Blue Lady (``vessel="blue-lady"``): the older class name."""

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("vessel", "blue-lady")
        super().__init__(**kwargs)


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


def _make_renderer(model: Any) -> Any:
    from shipgym.envs._mujoco import mujoco

    try:
        return mujoco.Renderer(model, 480, 640)
    except Exception as exc:  # noqa: BLE001 - any GL failure gets the same advice
        raise RuntimeError(
            f"rendering needs an OpenGL backend and none works here ({exc}); on a headless "
            "machine set MUJOCO_GL=egl (or MUJOCO_GL=osmesa with PYOPENGL_PLATFORM=osmesa and "
            "libosmesa installed) before importing mujoco"
        ) from exc
