"""The ship Gymnasium environment of the plan tasks: the vector env of one.

:class:`ShipEnv` is the single-env form of :class:`~shipgym.envs.vector.ShipVectorEnv` with
``num_envs=1`` (one code path: env ``i`` of a vector env is the single env seeded
``seed + i``): its physics (MuJoCo and the vessel's hull model, read through
:class:`~shipgym.envs.batchphysics.HullView`), a task (a manoeuvre plan followed by the
guidance, a reward made of named terms, metrics and termination) and the single-env API:
spaces, Python-number ``info`` and the typed :class:`~shipgym.records.StepRecord`.
Everything is generic over the vessel (``vessel=``, a :class:`~shipgym.dynamics.vessel.Vessel`
package): the action space comes from its actuators, the guidance limits from the vessel file.
The registered tasks (:mod:`shipgym.envs.tasks`) differ only in their plan, start,
disturbances and time limit.
"""

from __future__ import annotations

import functools
import math
import sys
from collections.abc import Callable, Mapping
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from shipgym.disturbances import CurrentConfig, WaveConfig, WindConfig
from shipgym.dynamics.frames import wrap_angle
from shipgym.dynamics.vessel import Vessel
from shipgym.guidance import ManoeuvrePlan, Reference
from shipgym.observers.batch import estimate_of
from shipgym.observers.sensors import BatchedSensors, SensorConfig
from shipgym.records import ControlData, LazyInfo, NavigationData, step_record_of_env

from .physics import MAX_TIMESTEP, MIN_TIMESTEP
from .scene import make_renderer
from .spec import (
    MAX_CONTROL_PERIOD,
    MAX_SUBSTEPS,
    PlanEnvSpec,
    _check_render_mode,
)
from .task import (
    MAX_START_OFFSET,
    SCENES,
    RewardWeights,
    parse_sensors_arg,
    parse_waves_arg,
    tracking_penalty,
)
from .vector import ShipVectorEnv

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


class ShipEnv(PlanEnvSpec, gym.Env[NDArray[np.float32], NDArray[np.float32]]):
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

    Actions outside [-1, 1] are clipped and flagged in ``info["action_clipped"]`` (which also
    flags a propeller command held at its idle by ``condition_commands``); NaN or infinite
    actions raise ``ValueError``.

    ## Observation Space
    ``Box(-inf, inf, (12 + n,), float32)``; what a controller may know (navigation data: the
    truth, or with ``observer=`` the observer's estimate):

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
    reward_rate + reward_reversal + reward_contact + reward_leg`` (each term in ``info``):
    ``-w_p |e_xy|^2``, ``-w_psi e_psi^2``, ``-w_v |nu - nu_d|^2``, ``-w_u |a|^2``,
    ``-w_du |a - a_prev|^2``, ``-w_rev`` per two-sided channel (a reversible propeller or
    tunnel) whose command went through zero in the step (``a a_prev < 0``; weight 0 by
    default), ``-w_c`` on quay contact, ``+w_leg`` per completed leg
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
    :meth:`step` raises ``gymnasium.error.ResetNeeded`` until :meth:`reset` is called: the env
    itself on termination and at its ``episode_duration``; at the ``TimeLimit``'s truncation
    the :class:`~shipgym.envs.episode.EpisodeEnd` wrapper that ``shipgym.make`` applies
    outside it. A bare ``gym.make`` has no ``EpisodeEnd`` (the ``TimeLimit`` is outside the
    env, and Gymnasium's ``make_vec`` refuses an id with a vector entry point that carries an
    additional wrapper): there the time limit's last ``info`` has no ``episode_metrics``
    (call :meth:`episode_metrics`).

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
    with the observer's and the controller's parts where the env has them. ``info`` is a
    :class:`~shipgym.records.LazyInfo`: a ``dict`` made when it is first read (a loop that
    does not read it does not pay for it), with the values of its step whenever it is read.

    With ``observer=`` the info's ``nav_eta``, ``nav_nu`` are the estimate, and it gains
    ``est_error_eta`` (m, m, rad; heading wrapped), ``est_error_nu`` (m/s, m/s, rad/s),
    ``observer_nis`` (``None`` in a period without a fix) and ``observer_rejected`` (the
    outlier gate) of the period's last sample, and at the end of an episode
    ``estimation_rmse`` (x, y, psi, u, v, r; psi and r in deg and deg/s). With
    ``controller=`` the action is a residual on the controller's normalised command (their
    sum clipped to [-1, 1], flagged in ``residual_clipped``), and the info gains ``tau_c``
    (the law's demand, N, N, N m, body), ``tau_delivered``, ``tau_error`` (what the
    allocation could not deliver), ``controller_action``, ``allocation_saturated`` and
    ``tau_ff`` (the feedforward part of ``tau_c``; zeros without one).

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
    | ``integrator`` | ``"leapfrog"`` | the compiled step (in the harbour with its quay-contact |
    |  |  | check: the step MuJoCo finds a contact at), or ``"mujoco"`` (MuJoCo's ``mj_step``; |
    |  |  | the harbour's quays by MuJoCo's contacts, with their impulse) |
    | ``terminate_on_finish`` | ``True`` | end the episode when the plan is complete |
    | ``reward_weights`` | ``RewardWeights()`` | weights of the reward terms |
    | ``observer`` | ``None`` | an observer name (``shipgym.observers.observer_names()``) fed |
    |  |  | every sensor sample; ``None``: the truth |
    | ``observer_options`` | ``None`` | the observer's options (``{"beaufort": 5}``) |
    | ``controller`` | ``None`` | a DP controller name (``shipgym.controllers.batch.CONTROLLERS``) |
    | ``feedforward`` | ``None`` | the controller's wind/current feedforward |
    |  |  | (:mod:`shipgym.controllers.feedforward`): ``None`` the task's default |
    |  |  | (DP tasks: ``"wind+current"``), ``"none"``, ``"wind"``, ``"current"`` |
    | ``residual_scale`` | ``1.0`` | the factor on the residual actions (with ``controller``) |
    | ``condition_commands`` | ``False`` | without ``controller``: the actions' propeller |
    |  |  | commands through the vessel's reversal hysteresis with an idling shaft (the |
    |  |  | PID's conditioning; a learned policy's action filter); what it holds is flagged |
    |  |  | in ``action_clipped`` |
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

    def __init__(
        self,
        vessel: Vessel | str | None = None,
        *,
        observer: str | None = None,
        observer_options: Mapping[str, Any] | None = None,
        controller: str | None = None,
        residual_scale: float = 1.0,
        **kwargs: Any,
    ) -> None:
        render_mode = kwargs.pop("render_mode", None)
        _check_render_mode(render_mode, self.metadata)
        # the env is the vector env of one: its physics, sensors, guidance, task, metrics,
        # observer and controller (the time limit is gym.make's TimeLimit, or the class's
        # episode_duration)
        self.batch = b = ShipVectorEnv(
            1, type(self), max_episode_steps=sys.maxsize, vessel=vessel, observer=observer,
            observer_options=observer_options, controller=controller,
            residual_scale=residual_scale, **kwargs,
        )  # fmt: skip
        #: the observer's name (``None``: the controllers and the observation use the truth)
        self.observer_name: str | None = b.observer_name
        #: the DP controller's name (``None``: the actions drive the actuators)
        self.controller_name: str | None = b.controller_name
        #: the factor on the residual actions (with a controller)
        self.residual_scale = b.residual_scale
        self._sq = np.zeros(6)  # the estimation errors' sums of squares, and their count
        self._n_est = 0
        for name, value in b.extras.items():  # the class's settings (episode_duration, ...)
            setattr(self, name, value)
        self.task = b.task
        self.vessel = b.vessel
        self.n_substeps = b.n_substeps
        self.control_period = b.control_period
        #: the hull, read as a single physics (:class:`~shipgym.envs.batchphysics.HullView`)
        self.physics = b.physics.hull(0)
        self.actuators = b.actuators  # the laws of this plant (vessel.actuators_for)
        self.n_actions = b.n_actions
        self.limits = b.limits
        self.guidance = GuidanceView(b, 0)
        #: the episode's accuracy and usage accumulator (env 0 of the batch's)
        self.metrics = b._metrics
        self._actuator_names = self.actuators.names
        multi = self.actuators.channel_names != self.actuators.names
        self._channel_names = self.actuators.channel_names if multi else ()
        self.render_mode = render_mode
        self._renderer: Any = None
        self.action_space = b.single_action_space
        self.observation_structure = b.observation_structure
        self.observation_space = b.single_observation_space
        self._harbour = self.task.scene == "harbour"
        self._episode_over = True  # until the first reset
        self._active = np.ones(1, dtype=bool)
        #: the keys of the info of a step and of a reset (with rewards, with control)
        self._info_keys: dict[tuple[bool, bool], frozenset[str]] = {}

    # ---- the task's settings ----------------------------------------------------------------
    @property
    def observer(self) -> Any:
        """The observer (the batch's, N = 1; ``None``: none): ``observer.eta``, ``nu``,
        ``estimate(0)``, ..."""
        return self.batch.observer

    @property
    def controller(self) -> Any:
        """The DP controller and its allocation (the batch's, N = 1; ``None``: none)."""
        return self.batch.controller

    @property
    def sensors(self) -> BatchedSensors | None:
        """The sensors (the batch's of one; ``None``: no sensors)."""
        return self.batch.sensors

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
        s = self.batch.sensors
        return None if s is None else s.configs[0]

    # ---- gym API ---------------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        """Start an episode; ``options`` may hold ``start_pose`` (m, m, rad)."""
        super().reset(seed=seed)
        unknown = sorted(set(options or {}) - {"start_pose"})
        if unknown:
            raise ValueError(f"unknown reset options {unknown}; valid: ['start_pose']")
        b = self.batch
        b._rngs[0] = self.np_random  # the env's generator is the batch's (gym.Env's seeding)
        b.sample_log = [] if b.sensors is not None else None
        b.reset(options=options)
        self._episode_over = False
        self._sq[:] = 0.0
        self._n_est = 0
        n = self.n_actions
        info = self._info(self.physics.command, np.zeros(n, bool), np.zeros(n, bool), None, [])
        return b._observation()[0], info

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
        a, _ = self.actuators.as_vector(action, "action")  # the shape and finiteness checked
        b = self.batch
        if b.sensors is not None:
            b.sample_log = []
        out = b.control_step(a.reshape(1, -1), self._active)
        reward, terminated, truncated, saturated, action_clipped, command, control = out
        contacts = self.physics.contacts() if self._harbour else []
        flags = saturated[0] | action_clipped[0]
        info = self._info(command[0], flags, action_clipped[0], b._rew[0].tolist(), contacts,
                          control)  # fmt: skip
        done = bool(terminated[0]), bool(truncated[0])
        if done[0] or done[1]:  # a time-limit truncation is seen by EpisodeEnd
            self._episode_over = True
            self.end_info(info)
        return b._obs[0].copy(), float(reward[0]), done[0], done[1], info

    def render(self) -> NDArray[np.uint8] | None:
        """An RGB frame (H, W, 3) of the map camera; needs ``render_mode="rgb_array"``."""
        if self.render_mode is None:
            gym.logger.warn("render() called without render_mode; pass render_mode='rgb_array'")
            return None
        if self._renderer is None:
            self._renderer = make_renderer(self.physics.model)
        cam = "map" if self.scene == "harbour" else "top"
        self._renderer.update_scene(self.physics.data, camera=cam)
        return self._renderer.render()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # ---- helpers ---------------------------------------------------------------------------
    def episode_metrics(self) -> dict[str, Any]:
        """Accuracy indices (Tomera 2014 eqs. 54-57), thruster usage, legs and contact so far."""
        return self.batch.episode_metrics(0)

    @property
    def prev_action(self) -> NDArray[np.float64]:
        """The normalised action applied in the last step (zeros after a reset)."""
        return self.batch._prev[0].copy()

    @property
    def reference(self) -> Reference:
        """The guidance reference of the state now (the last step's or reset's)."""
        return _row_reference(self.batch._ref, 0)

    def _info(
        self,
        command: NDArray[np.float64],
        saturated: NDArray[np.bool_],
        action_clipped: NDArray[np.bool_],
        rewards: list[float] | None,
        contacts: list[tuple[str, str]],
        control: Mapping[str, NDArray[Any]] | None = None,
    ) -> LazyInfo:
        """The info of the state now (env 0 of the batch), with its typed ``record``: the
        observer's part, and the controller's (``control``: its info of the step, (1, ...)
        rows) where the env has them; ``rewards``: the reward terms' values (``None`` after a
        reset).

        What changes with the next step is read now (the arrays below are new at each state
        or copied); the dict is made from them on its first read (:class:`LazyInfo`).
        """
        b, phys = self.batch, self.physics
        ref = b._ref
        # the reference's buffer never changes; its leg and flag are the guidance's (they do):
        # legs completed = leg + finished
        ref_now = (ref.buffer[0], int(ref.leg[0]), float(ref.t_leg[0]), bool(ref.finished[0]))
        eta, nu = b._truth()
        t = phys.time
        now = (
            t, eta[0], nu[0], b._eta_r[0].copy(), b.thrust()[0], phys.actuator_state,
            phys.environment_loads(), phys.wave_elevation(), bool(b._contact[0]),
            b._prev[0].copy(), b.sample_log, (phys.phi, phys.p) if phys.dofs == 4 else None,
        )  # fmt: skip
        # the observer's estimate now, and its errors into the episode's RMSE
        nav = None if b.observer is None else self._observer_now(t, eta[0], nu[0])
        # the controller's arrays are new at each step, but for tau_error, which it zeroes at
        # a reset
        ctrl = None if control is None else (control, control["tau_error"][0].copy())
        kind = (rewards is not None, ctrl is not None)
        keys = self._info_keys.get(kind)
        make: Callable[[], dict[str, Any]] = functools.partial(
            self._make_info, command, saturated, action_clipped, rewards, contacts, ref_now, now,
            nav, ctrl,
        )  # fmt: skip
        if keys is None:  # the first info of its kind, made now: its keys for the next ones
            made = make()
            keys = self._info_keys[kind] = frozenset(made)
            make = lambda: made  # noqa: E731
        return LazyInfo(keys, make)

    def _make_info(
        self,
        command: NDArray[np.float64],
        saturated: NDArray[np.bool_],
        action_clipped: NDArray[np.bool_],
        rewards: list[float] | None,
        contacts: list[tuple[str, str]],
        ref_now: tuple[Any, ...],
        now: tuple[Any, ...],
        nav: tuple[Any, ...] | None,
        ctrl: tuple[Mapping[str, NDArray[Any]], NDArray[np.float64]] | None,
    ) -> dict[str, Any]:
        """The dict of :meth:`_info` from what it read of the state."""
        ref = Reference._build(*ref_now)
        t, e, w, eta_r, thrust, act, loads, elevation, contact, prev, log, roll = now
        tau_wind, tau_waves, current_body = loads
        # copies of the reference's arrays: info is the caller's to keep and change
        info: dict[str, Any] = {
            "t": t,
            "eta": e,
            "nu": w,
            "nav_eta": e,
            "nav_nu": w,
            "eta_d": ref.eta_d_n.copy(),
            "eta_d_r": ref.eta_d_r.copy(),
            "eta_dot_d_r": ref.eta_dot_d_r.copy(),
            "eta_ddot_d_r": ref.eta_ddot_d_r.copy(),
            "eta_P": ref.eta_P.copy(),
            "eta_r": eta_r,
            "leg": ref.leg,
            "legs_completed": ref.leg + ref.finished,
            "finished": ref.finished,
            "command": np.array(command, dtype=float),
            "thrust": thrust,
            "actuator_state": act,
            "saturated": saturated,
            "action_clipped": action_clipped,
            "tau_wind": tau_wind,
            "tau_waves": tau_waves,
            "current_body": current_body,
            "wave_elevation": elevation,
            "quay_contact": contact,
            "contacts": contacts,
        }
        if roll is not None:
            info["phi"], info["p"] = roll
        if rewards is not None:
            info.update(zip(self.task.reward_terms, rewards, strict=True))
        info["measurements"] = log if log is not None else []
        rec = step_record_of_env(info, ref, prev, self._actuator_names, self._channel_names)
        if nav is not None:
            est_nav, e_eta, e_nu, nis, rejected = nav
            info["nav_eta"] = est_nav.eta
            info["nav_nu"] = est_nav.nu
            info["est_error_eta"] = e_eta
            info["est_error_nu"] = e_nu
            info["observer_nis"] = nis
            info["observer_rejected"] = rejected
            rec = rec.with_nav(est_nav)
        if ctrl is not None:
            control, tau_error = ctrl
            rows = [tau_error if k == "tau_error" else control[k][0].copy() for k in _CONTROL_KEYS]
            info.update(zip(_CONTROL_KEYS, rows, strict=True))
            rec = rec.with_control(ControlData(self.controller_name or "", *rows))
        info["record"] = rec
        return info

    def _observer_now(
        self, t: float, eta: NDArray[np.float64], nu: NDArray[np.float64]
    ) -> tuple[Any, ...]:
        """The observer's part of the info now: ``(navigation data, est_error_eta,
        est_error_nu, NIS, rejected)`` (its estimate, the estimation errors against the truth,
        the NIS and gate decision of the period's last sample); the errors go into the
        episode's RMSE."""
        b = self.batch
        est = estimate_of(b.observer, 0, t)
        e_eta = np.array(
            [est.eta[0] - eta[0], est.eta[1] - eta[1], wrap_angle(est.eta[2] - eta[2])]
        )
        e_nu = est.nu - nu
        self._sq += np.concatenate([e_eta, e_nu]) ** 2
        self._n_est += 1
        nav = NavigationData(t, est.eta, est.nu, est.P_eta, est.P_nu, self.observer_name)
        nis = float(b._nis[0])
        return nav, e_eta, e_nu, None if math.isnan(nis) else nis, bool(b._rejected[0])

    def end_info(self, info: dict[str, Any]) -> None:
        """The end of an episode into its last step's ``info``: ``episode_metrics``, and with
        an observer ``estimation_rmse`` (also in ``info["record"]``). The env calls it when
        the episode terminates or reaches its ``episode_duration``; the
        :class:`~shipgym.envs.episode.EpisodeEnd` wrapper at a time-limit truncation."""
        info["episode_metrics"] = self.episode_metrics()
        if self.batch.observer is not None:
            rmse = self.estimation_rmse()
            info["estimation_rmse"] = rmse
            rec = info["record"]
            info["record"] = rec.with_nav(rec.nav, estimation_rmse=rmse)

    def estimation_rmse(self) -> dict[str, float]:
        """RMSE of the observer's estimate over the episode's states so far, its reset's
        included (m, m, deg, m/s, m/s, deg/s); an env without an observer has none."""
        if self.batch.observer is None:
            raise ValueError("the env has no observer: make it with observer=NAME")
        r = np.sqrt(self._sq / max(self._n_est, 1))
        r[2] = math.degrees(r[2])
        r[5] = math.degrees(r[5])
        return dict(zip(("x", "y", "psi", "u", "v", "r"), r.tolist(), strict=True))

    def command_to_action(self, command: NDArray[np.float64]) -> NDArray[np.float64]:
        """Physical command (channel order, each in its unit) to the normalised action."""
        return self.actuators.command_to_action(command)


#: the controller's keys of the step info, in :class:`~shipgym.records.ControlData`'s order
_CONTROL_KEYS = ("tau_c", "tau_delivered", "tau_error", "controller_action",
                 "allocation_saturated", "residual_clipped", "tau_ff")  # fmt: skip


class GuidanceView:
    """Env ``i``'s guidance of a plan task's vector env, read as a single
    :class:`~shipgym.guidance.Guidance` is: its plan, waypoints and references (the legs are
    in the step's ``info``)."""

    def __init__(self, env: Any, i: int) -> None:
        self._env = env
        self._i = i

    @property
    def plan(self) -> ManoeuvrePlan:
        """The plan of the episode (before the first reset: the task's)."""
        plan = self._env.plans[self._i]
        return self._env.task.plan if plan is None else plan  # type: ignore[no-any-return]

    @property
    def waypoints(self) -> NDArray[np.float64]:
        """Planned NED poses ``[P_0, K_0, ..., K_{n-1}]``, (n_legs + 1, 3)."""
        return self._env.guidance.waypoints(self._i)  # type: ignore[no-any-return]

    def reference(self, t: float) -> Reference:
        """The reference at time ``t`` (s) of the current leg."""
        n = self._env.num_envs
        return _row_reference(self._env.guidance.reference(np.full(n, float(t))), self._i)


def _row_reference(ref: Any, i: int) -> Reference:
    """Row ``i`` of a :class:`~shipgym.guidance.batch.BatchedReference` as a
    :class:`~shipgym.guidance.Reference`."""
    return Reference._build(ref.buffer[i], int(ref.leg[i]), float(ref.t_leg[i]),
                            bool(ref.finished[i]))  # fmt: skip


class BlueLadyEnv(ShipEnv):
    """:class:`ShipEnv` with the Blue Lady (``vessel="blue-lady"``): the older class name."""

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("vessel", "blue-lady")
        super().__init__(**kwargs)
