r"""The native batched ``gymnasium.vector.VectorEnv`` of the plan tasks.

``ShipVectorEnv`` steps N envs of a plan task (harbour, station keeping, tracking, the
offshore DP tasks) at once; env ``i`` is the single env seeded ``seed + i``, bit for bit.

Public names: ``AUTORESET_MODES``, ``ShipVectorEnv``, and the vector entry points
``harbour_vector_env``, ``station_keeping_vector_env``, ``tracking_vector_env``,
``dp_station_keeping_vector_env``, ``dp_sway_step_vector_env``.

Design notes: docs/design/envs.vector.md.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode
from numpy.typing import NDArray

from shipgym._jit import law_input, njit
from shipgym.dynamics.actuators import channel_command
from shipgym.dynamics.frames import wrap_angle
from shipgym.guidance.batch import BatchedGuidance
from shipgym.guidance.limits import vessel_limits
from shipgym.guidance.rframe import r_frame_poses
from shipgym.metrics import BatchedManoeuvreMetrics
from shipgym.observers.sensors import BatchedSensors, SensorConfig

from .batched import AUTORESET_MODES, BatchedEnv, check_num_envs
from .batchphysics import BatchedPhysics
from .spec import (
    PlanEnvSpec,
    _check_timing,
    _whole_multiple,
    harbour_body,
    place_harbour,
)
from .task import _vec3

__all__ = [
    "AUTORESET_MODES",
    "ShipVectorEnv",
    "dp_station_keeping_vector_env",
    "dp_sway_step_vector_env",
    "harbour_vector_env",
    "station_keeping_vector_env",
    "tracking_vector_env",
]

Array = NDArray[np.float64]


class ShipVectorEnv(BatchedEnv):
    """``num_envs`` envs of a plan task stepped together (module docstring).

    Spaces: the single env's, batched: ``observation_space`` ``Box(-inf, inf, (N, 12 + n),
    float32)`` (the layout of :class:`~shipgym.envs.base.ShipEnv`, ``observation_structure``;
    with an observer its estimate replaces the truth), ``action_space`` ``Box(-1, 1, (N, n),
    float32)`` (one normalised command, or with ``controller`` one residual, per channel; out
    of range is clipped and flagged in ``info["action_clipped"]``, NaN raises). Reward: the
    single env's terms (``info["reward_*"]``, which sum to it). Episodes end as the single
    env's: terminated when the plan is complete (Tracking), truncated at
    ``max_episode_steps``; at an episode's end ``info["episode_metrics"]`` holds env ``i``'s
    :meth:`ShipEnv.episode_metrics <shipgym.envs.base.ShipEnv.episode_metrics>` (Tomera 2014
    eqs. 54-57, thruster usage, legs; :meth:`_episode_metrics`).

    Args:
        num_envs: number of envs, >= 1.
        task: the single env's class (:class:`~shipgym.envs.tasks.TrackingEnv`,
            :class:`~shipgym.envs.tasks.StationKeepingEnv` or a subclass) or its registered id.
        max_episode_steps: the time limit (control steps); ``None``: the id's registered one.
        autoreset_mode: ``"next-step"`` (default) or ``"same-step"``.
        controller: ``None`` (the actions drive the actuators) or a DP controller name
            (``"pid"``, ``"lq"``, ``"alt-sdre"``, any of :data:`~shipgym.controllers.batch.
            CONTROLLERS`: :func:`~shipgym.controllers.batch.batched_dp_controller`): the
            actions are residuals on its normalised command, as in the single env
            (``shipgym.make(..., controller=)``).
        residual_scale: the factor on the residual actions (with ``controller``).
        condition_commands: ``True`` (no ``controller`` only): the actions' propeller
            commands pass through the vessel's reversal hysteresis with an idling shaft
            (its ``[control] reversal_threshold``;
            :class:`~shipgym.controllers.conditioning.BatchedCommandConditioning`), the PID's
            command conditioning, as a pure learned policy's action filter: a propeller
            reverses only on a request past the threshold that its 4 s low-pass confirms,
            else idles on its running side. What it holds is flagged in
            ``info["action_clipped"]``; the observation's previous action, the reward and
            the metrics see the command applied.
        feedforward: what the controller feeds forward (``controller`` only):
            ``None`` the task class's ``default_feedforward`` (the DP tasks of Al-Takie 1982:
            ``"wind+current"``, as the thesis assumes; the other tasks: none), a name of
            :data:`~shipgym.controllers.feedforward.FEEDFORWARD_PRESETS` (``"none"`` turns
            it off), a bool, a mapping or a
            :class:`~shipgym.controllers.feedforward.FeedforwardConfig`: minus the wind load
            of the filtered anemometer wind and the hull's load in the mean current, added
            to the law's ``tau`` (``info["tau_ff"]``); a model-based observer is fed the
            thrust plus the loads it estimates.
        observer: ``None`` / ``"truth"`` (the observation and the controller use the true
            state) or an observer name (``shipgym.observers.observer_names()``, or one
            registered with :func:`~shipgym.observers.batch.register_batched_observer`:
            :func:`~shipgym.observers.batch.make_batched_observer`), fed every sensor sample
            (and a model-based one the thrust), whose estimate they use instead, as under
            as the single env's (``shipgym.make(id, observer=)``).
        observer_options: keyword arguments for the observer (e.g. ``{"beaufort": 5}``, the
            sea state an ``alt-*`` wave filter is designed for); they win over the vessel's.
        env_sensors: one sensor configuration per env, each as the ``sensors=`` of env ``i``
            (the training stack's per-env noise); they may differ only in their variances.
        **kwargs: the single env's arguments (``vessel=``, ``plant=``, ``timestep=``,
            ``control_period=``, the task's ``wind=``, ``max_legs=``, ``waves=``, ...,
            and the class's own, such as the DP tasks' ``beaufort=``), split as the single
            env splits them (:meth:`ShipEnv.split_args
            <shipgym.envs.base.ShipEnv.split_args>`); ``render_mode`` must be ``None``.

    Raises:
        ValueError: a task, vessel or argument the batched form does not cover, naming it.
    """

    _step_info_masked = True  # _info and _step_envs add every key's mask

    def __init__(
        self,
        num_envs: int,
        task: type[PlanEnvSpec] | str,
        *,
        max_episode_steps: int | None = None,
        autoreset_mode: str | AutoresetMode = "next-step",
        controller: str | None = None,
        residual_scale: float = 1.0,
        condition_commands: bool = False,
        feedforward: Any = None,
        observer: str | None = None,
        observer_options: Mapping[str, Any] | None = None,
        env_sensors: Sequence[SensorConfig] | None = None,
        **kwargs: Any,
    ) -> None:
        check_num_envs(num_envs)  # before anything is built for them
        cls, steps = _task_class(task)
        # the class's own defaults (the DP tasks' timing and sea), as its single env takes them
        env, task_args, extras = cls.split_args(kwargs)
        #: the class's settings (``episode_duration``, the sway step's ``step_time``, ...)
        self.extras = extras
        vessel, plant, render_mode = env["vessel"], env["plant"], env["render_mode"]
        timestep, control_period = env["timestep"], env["control_period"]
        #: the episode length (s) after which an env truncates (``None``: the step limit only)
        self.episode_duration: float | None = extras.get("episode_duration")
        if max_episode_steps is None and self.episode_duration is not None and steps is None:
            steps = sys.maxsize  # the time limit is the episode's duration
        if max_episode_steps is None:
            if steps is None:
                raise ValueError(
                    f"{cls.__name__} is not a registered batched task: pass max_episode_steps="
                )
            max_episode_steps = steps
        if not (isinstance(max_episode_steps, int) and max_episode_steps >= 1):
            raise ValueError(f"max_episode_steps must be an int >= 1, got {max_episode_steps!r}")
        if render_mode is not None:
            raise ValueError("the batched env does not render; use the single env (gym.make)")
        # the task of these arguments: its configuration and each env's per-episode draws
        self.task = task = cls.make_task(vessel, **task_args)
        n = num_envs
        self.max_episode_steps = max_episode_steps
        self.vessel = task.vessel
        _check_timing(timestep, control_period)
        self.n_substeps = _whole_multiple(control_period, timestep)
        self.control_period = float(control_period)
        harbour = task.scene == "harbour"
        # the compiled step everywhere, in the harbour with its quay-contact check (the quays
        # touched as MuJoCo finds them); integrator="mujoco": MuJoCo's mj_step per hull
        integrator = env["integrator"] or "leapfrog"
        self.physics = BatchedPhysics(
            self.vessel, n, plant, wind=task.wind, current=task.current, waves=task.waves,
            timestep=timestep, integrator=integrator, world=task.scene if harbour else None,
        )  # fmt: skip
        self.actuators = self.physics.actuators
        self.n_actions = self.actuators.n_channels
        cfg = task.sensors
        self.sensors = None if cfg is None else BatchedSensors(cfg, n)
        self._sensor_steps = None if cfg is None else _whole_multiple(cfg.period, timestep)
        # whether the sensor period divides the control period: every active env then starts
        # each period at a sample instant (its steps since reset a multiple of the period's)
        self._aligned = cfg is not None and self.n_substeps % self._sensor_steps == 0
        self.limits = vessel_limits(self.vessel)
        self.guidance = BatchedGuidance(n, limits=self.limits)
        self.observation_structure, size = task.observation_structure(self.n_actions)
        self._setup(
            num_envs,
            spaces.Box(-np.inf, np.inf, (size,), np.float32),
            spaces.Box(-1.0, 1.0, (self.n_actions,), np.float32),
            autoreset_mode,
        )
        self._obs = np.zeros((n, size), np.float32)
        self._rew = np.zeros((n, len(task.reward_terms)))
        self._eta_r = np.zeros((n, 3))
        # the harbour body (the same id in every hull's copy of the world), None in open water
        self._harbour = harbour_body(self.physics.models[0]) if harbour else None
        self._contact = np.zeros(n, dtype=bool)
        self._stop = harbour  # stop a hull after the physics step in which it touches a quay
        self._steps = np.zeros(n, dtype=np.int64)  # physics steps since reset
        self._elapsed = np.zeros(n, dtype=np.int64)  # control steps since reset
        self._return = np.zeros(n)
        self._prev = np.zeros((n, self.n_actions))
        self._fresh = False  # whether _obs is the observation now
        # the channels' limits as the compiled action law is typed (a frozen set's are read-only)
        lo, hi = law_input(self.actuators.lower), law_input(self.actuators.upper)
        self._lo, self._hi = lo, hi
        self._lo_tol, self._hi_tol = lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo)
        if not (isinstance(residual_scale, int | float) and not isinstance(residual_scale, bool)
                and 0 <= residual_scale < math.inf):  # fmt: skip
            raise ValueError(f"residual_scale must be a finite number >= 0, got {residual_scale!r}")
        self.controller_name = controller
        self.residual_scale = float(residual_scale)
        if env_sensors is not None:
            env_sensors = list(env_sensors)
            if len(env_sensors) != n or not all(isinstance(c, SensorConfig) for c in env_sensors):
                raise ValueError(f"env_sensors must be {n} SensorConfigs (one per env)")
            if self.sensors is None:
                raise ValueError("env_sensors needs sensors (the env was made with sensors=None)")
        self._env_sensors = env_sensors
        self.observer_name = None if observer in (None, "truth") else observer
        if observer_options and self.observer_name is None:
            raise ValueError(
                f"observer_options={dict(observer_options)!r} needs an observer: pass observer="
            )
        self.observer = None
        if self.observer_name is not None:
            from shipgym.observers.batch import make_batched_observer

            every = self._sensor_steps
            if self.sensors is None or every is None:
                raise ValueError(
                    "an observer needs sensors: create the env with sensors='default' (or "
                    "another preset), not sensors=None"
                )
            if self.n_substeps % every and n > 1:
                raise ValueError(
                    f"the batched env's observer needs a sensor period that divides the control "
                    f"period ({self.control_period:g} s); got {self.sensors.config.period:g} s: "
                    "use the single env (shipgym.make) for it"
                )
            # the design noise of the vessel (make_observer's), and the options given
            self.observer = make_batched_observer(
                self.observer_name, n, self.vessel, **dict(observer_options or {})
            )
            check = getattr(self.observer, "check_sample_interval", None)
            if check is not None:  # refused now, not at the first step
                check(self.sensors.config.period, self.control_period)
        self.controller = None
        if controller is not None:
            from shipgym.controllers.batch import apply_residual, batched_dp_controller

            self._apply_residual = apply_residual  # (imported once, not at every step)

            # the velocity filter for the observer's kind
            src = (
                "truth"
                if self.observer is None
                else ("model" if getattr(self.observer, "model_based", False) else "kinematic")
            )
            self.controller = batched_dp_controller(
                controller, self.vessel, n, self.control_period, velocity_source=src
            )
        #: the action filter of ``condition_commands`` (``None``: none)
        self.conditioning: Any = None
        if not isinstance(condition_commands, bool | np.bool_):
            raise TypeError(f"condition_commands must be True or False, got {condition_commands!r}")
        if condition_commands:
            if controller is not None:
                raise ValueError(
                    f"condition_commands filters actions that drive the actuators; the DP "
                    f"controller {controller!r} conditions its own commands: drop one of them"
                )
            from shipgym.controllers.conditioning import (
                BatchedCommandConditioning,
                reversal_threshold,
            )

            self.conditioning = BatchedCommandConditioning(
                self.actuators, reversal_threshold(self.vessel), n, dt=self.control_period
            )
        #: the controller's feedforward (``None``: none)
        self.feedforward: Any = None
        ff = cls.default_feedforward if feedforward is None else feedforward
        if ff is not None:
            from shipgym.controllers.feedforward import BatchedFeedforward, FeedforwardConfig

            cfg = FeedforwardConfig.coerce(ff)
            if cfg.active and controller is None and feedforward is not None:
                raise ValueError(
                    f"feedforward={feedforward!r} needs a DP controller: pass controller="
                )
            if cfg.active and controller is not None:
                self.feedforward = BatchedFeedforward(self.vessel, cfg, n, self.control_period)
        self._tau_ff = np.zeros((n, 3))  # the last control step's feedforward (N, N, N m)
        self._nis = np.full(n, np.nan)
        self._rejected = np.zeros(n, bool)
        self._cache: dict[str, Any] = {}  # this state's eta, nu (and estimate), read once
        self._ref: Any = None
        self._leg = np.zeros(n, dtype=np.int64)
        self._psi_P = np.zeros(n)
        self._last_z = np.full((n, 3), np.nan)
        self._z_valid = np.zeros(n, dtype=bool)
        self._z_outlier = np.zeros(n, dtype=bool)
        # what the step reads every period, decided once
        self._nan_n = np.full(n, np.nan)  # the observer's NIS before a sample (copied)
        self._true_n = np.ones(n, dtype=bool)  # the step info's masks (copied: np.ones is slow)
        self._no_contact = np.zeros(n, dtype=bool)  # open water: no quay (never written)
        obs = self.observer
        self._model_based = obs is not None and bool(getattr(obs, "model_based", False))
        # the observer's clock (s) and the thrust of its last sample (a coast to the end of a
        # period holds it): a period that does not end at a sample (a sensor period that does
        # not divide the control period, N = 1; a hull stopped at a quay) ends with a coast
        self._obs_t = np.zeros(n)
        self._obs_tau: Array | None = None
        # an observer of a fixed sampling interval (the notch, the wave filters) is stepped
        # at its samples only: its estimate stays at the last one
        self._coasts = obs is not None and not getattr(obs, "fixed_interval", False)
        mode = getattr(obs, "thrust_input", "applied")
        if self._model_based and mode not in ("applied", "command"):
            raise ValueError(
                f"observer {observer!r}: thrust_input must be 'applied' or 'command', got {mode!r}"
            )
        self._thrust_cmd = mode == "command"
        w = self.physics.wave_config
        self._seen_waves = w is not None and w.first_order  # sensors see the wave motion
        self._mask_names: dict[int, tuple[str, ...]] = {}  # info's key masks, by key count
        self.plans: list[Any] = [None] * n  # each env's plan of its episode
        self._start: Array | None = None  # the next reset's start poses (options)
        #: the sensor samples of a step, logged for the single env (N = 1), else None
        self.sample_log: list[dict[str, Any]] | None = None
        self._metrics_setup()

    # ---- the BatchedEnv hooks ------------------------------------------------------------
    def _reset_options(self, options: dict[str, Any], mask: NDArray[np.bool_]) -> None:
        """``options["start_pose"]``: the start pose (m, m, rad) of the reset envs instead of
        the task's, ``(3,)`` or one row per env ``(N, 3)``."""
        unknown = sorted(set(options) - {"start_pose"})
        if unknown:
            raise ValueError(
                f"unknown reset options {unknown}; valid: ['reset_mask', 'start_pose']"
            )
        self._start = None
        if "start_pose" in options:
            x = options["start_pose"]
            if np.ndim(x) == 2 and np.shape(x)[0] == self.num_envs:
                pose = [_vec3(r, f"options['start_pose'][{i}]") for i, r in enumerate(x)]
            else:
                pose = [_vec3(x, "options['start_pose']")] * self.num_envs
            self._start = np.array(pose)

    def _reset_info(self, mask: NDArray[np.bool_]) -> dict[str, Any]:
        return self._info(mask, None, None, None, {})

    def _step_envs(
        self, a: Array, active: NDArray[np.bool_]
    ) -> tuple[Array, NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]]:
        """One control period of the ``active`` envs (the others reset at this step)."""
        out = self.control_step(a, active)
        reward, terminated, truncated, saturated, action_clipped, command, control = out
        # each term's column, a row of one transposed copy
        rewards = dict(zip(self.task.reward_terms, self._rew.T.copy(), strict=True))
        done = (terminated | truncated) & active
        every = self._true_n.copy()
        info = self._info(every, saturated, action_clipped, command, rewards, done=done)
        if control is not None:
            info.update(control)
            info.update(dict.fromkeys(_CONTROL_MASKS, every))
        return reward, terminated, truncated, info

    def control_step(self, a: Array, active: NDArray[np.bool_]) -> tuple[Any, ...]:
        """One control period of the ``active`` envs from the actions ``a`` (n, m) (finite):
        ``(reward, terminated, truncated, saturated, action_clipped, command, control)``, the
        last the controller's info (``None`` without a controller), the reward terms in
        ``_rew``: what the vector env's step and the single env's (N = 1) both build their
        info from."""
        self._fresh = False  # the state changes from here
        control: dict[str, Array] | None = None
        if self.controller is not None:
            a, control = self._control(a)
        n, m = a.shape
        clipped, command = np.empty((n, m)), np.empty((n, m))
        action_clipped, near = np.empty((n, m), bool), np.empty((n, m), bool)
        _actions(a, self._lo, self._hi, self._lo_tol, self._hi_tol, clipped, action_clipped,
                 command, near)  # fmt: skip
        if self.conditioning is not None:  # held at the idle: changed, and off the limits
            held = self.conditioning(command, clipped)
            action_clipped |= held
            near &= ~held
        saturated = self.physics.set_command(command) | near
        self._advance(active)
        t = self.physics.t
        eta = self._truth()[0]
        switched = self.guidance.update(t, eta)
        ref = self.guidance.reference(t)
        if self._harbour is not None:
            touched = (self.physics.contact_counts > 0) & active
            new_contact = touched & ~self._contact
            self._contact |= touched
        else:  # open water: no quay to touch
            new_contact = self._no_contact
        self._terms(ref, clipped, switched, new_contact)
        self._fresh = True  # _obs is this state's observation
        self._ref = ref
        if self.controller is not None:  # a leg switch turns the controller's r-frame
            moved = ref.leg != self._leg
            if np.count_nonzero(moved):  # (any(): count_nonzero is the cheaper reduction)
                psi_P = ref.eta_P[:, 2]
                self.controller.change_frame(wrap_angle(psi_P - self._psi_P), moved)
                self._leg = np.where(moved, ref.leg, self._leg)
                self._psi_P = np.where(moved, psi_P, self._psi_P)
        # the terms added left to right (as the docs write the sum): cumsum accumulates in
        # order, where NumPy's reduction of 8 or more columns is pairwise
        reward = np.cumsum(self._rew, axis=1)[:, -1]
        self._prev = clipped
        self._elapsed += 1
        terminated = (self.guidance.finished & self.task.terminate_on_finish) | self._contact
        truncated = self._elapsed >= self.max_episode_steps
        if self.episode_duration is not None:  # to half a physics step
            truncated |= (t >= self.episode_duration - 0.5 * self.physics.h) & ~terminated
        self._return += reward
        self._metrics_record(active, ref, saturated, clipped)
        return reward, terminated, truncated, saturated, action_clipped, command, control

    # ---- internals ------------------------------------------------------------------------
    def _truth(self) -> tuple[Array, Array]:
        """The hulls' ``(eta, nu)`` now, read once per state (cached until the next physics
        step, sample or reset)."""
        truth = self._cache.get("truth")
        if truth is None:
            truth = self._cache["truth"] = (self.physics.eta, self.physics.nu)
        return truth  # type: ignore[no-any-return]

    def thrust(self) -> Array:
        """Every hull's actuator thrusts (N) now, (N, n_actuators), read once per state."""
        return self._readouts()[0]

    def _readouts(self, command: bool = False) -> tuple[Array, Array, Array | None]:
        """:meth:`BatchedPhysics.readouts <shipgym.envs.batchphysics.BatchedPhysics.readouts>`
        of the state now, ``(thrust, tau_model, tau_command)``, read once per state (again
        where ``command`` asks for the ``tau_command`` the cached read did not make)."""
        out = self._cache.get("readouts")
        if out is None or (command and out[2] is None):
            out = self._cache["readouts"] = self.physics.readouts(command)
        return out  # type: ignore[no-any-return]

    def _environment_now(self, psi: Array) -> tuple[Array, Array, Array | None]:
        """What the feedforward measures now, ``(wind, current, drift)``: the anemometer's
        true wind ``[V_w, beta_w]`` (m/s, rad from; still air without a wind load), the
        configured mean current ``[V_c, beta_c]`` (m/s, rad going to), (n, 2) each, and
        where it feeds the drift forward the sea state's mean drift load at the headings
        ``psi`` (n,) (N, N, N m, body; zeros without waves), (n, 3), else ``None``."""
        ph = self.physics
        t = ph.t
        wind = np.array([
            w.at(float(t[i])) if cfg is not None else (0.0, 0.0)
            for i, (w, cfg) in enumerate(zip(ph.winds, ph.wind_configs, strict=True))
        ])  # fmt: skip
        current = np.array([(c.speed, c.direction_to) for c in ph.current_configs])
        drift = None
        if self.feedforward is not None and self.feedforward.config.drift:
            drift = np.array([
                (0.0, 0.0, 0.0) if w is None else w.mean_drift_load(float(psi[i]))
                for i, w in enumerate(ph.waves)
            ])  # fmt: skip
        return wind, current, drift

    def _navigation(self) -> tuple[Array, Array]:
        """What the controller and the observation use: the estimate, else the truth."""
        if self.observer is None:
            return self._truth()
        nav = self._cache.get("nav")
        if nav is None:
            nav = self._cache["nav"] = (self.observer.eta, self.observer.nu)
        return nav  # type: ignore[no-any-return]

    def _control(self, residual: Array) -> tuple[Array, dict[str, Array]]:
        """The DP controller's action plus the residual
        (from the navigation data and reference at the end of the previous step)."""
        assert self.controller is not None
        ref = self._ref
        eta, nu = self._navigation()
        if self.feedforward is not None:
            self._tau_ff = self.feedforward(eta, nu, *self._environment_now(eta[:, 2]))
        tau_c, alloc, a_ctrl = self.controller(
            ref.to_r(eta), nu, ref.eta_d_r, ref.eta_dot_d_r, ref.eta_ddot_d_r,
            state=self.physics.actuator_state, tau_ff=self._tau_ff,
        )  # fmt: skip
        applied, clipped = self._apply_residual(a_ctrl, residual, self.residual_scale)
        info = {
            "tau_c": np.ascontiguousarray(tau_c),
            "tau_delivered": np.ascontiguousarray(alloc.tau),
            "tau_error": np.ascontiguousarray(alloc.tau_error),
            "controller_action": np.ascontiguousarray(a_ctrl),
            "allocation_saturated": np.ascontiguousarray(alloc.saturated),
            "residual_clipped": clipped,
            "tau_ff": self._tau_ff.copy(),
        }
        # the wrapper hands the env a float32 action
        return applied.astype(np.float32).astype(np.float64), info

    def _reset_envs(self, mask: NDArray[np.bool_]) -> None:
        """Reset the masked envs, each from its generator in the single env's order."""
        self._cache.clear()
        self._fresh = False
        task = self.task
        idx = np.nonzero(mask)[0].tolist()
        eta0 = np.zeros((self.num_envs, 3))
        start = np.zeros((self.num_envs, 3))
        for i in idx:
            rng = self._rngs[i]
            assert rng is not None
            # the task's draws from env i's generator; env i as made with sensors=env_sensors[i]
            own = None if self._env_sensors is None else self._env_sensors[i]
            start_i = None if self._start is None else self._start[i]
            ep = task.initialize_episode(rng, start_i, sensors=own)
            self.plans[i] = ep.plan
            self.physics.set_disturbances(i, ep.wind, ep.current)
            sensors = ep.sensors
            if sensors is not None and self.sensors is not None:
                self.sensors.set_config(i, sensors)
            eta0[i] = ep.eta0
            start[i] = ep.start
            if self._harbour is not None:
                place_harbour(self.physics.models[i], self._harbour, ep.start)
        self._start = None  # (one reset's option)
        rngs = self._rngs
        self.physics.reset(eta=eta0, mask=mask, rngs=rngs)  # type: ignore[arg-type]
        self._steps[mask] = 0
        self._elapsed[mask] = 0
        self._return[mask] = 0.0
        self._prev[mask] = 0.0
        self._contact[mask] = False
        self.guidance.reset([self.plans[i] for i in idx], start, 0.0, mask=mask)
        ref = self.guidance.reference(self.physics.t)
        # the reset envs' rows of the reference the next step's controller reads
        self._ref = ref if self._ref is None else _rows_from(self._ref, ref, mask)
        if self.conditioning is not None:
            self.conditioning.reset(mask)
        if self.controller is not None:
            self.controller.reset(mask)
            self._tau_ff[mask] = 0.0
            if self.feedforward is not None:
                self.feedforward.reset(mask)
            self._leg[mask] = ref.leg[mask]
            self._psi_P[mask] = ref.eta_P[mask, 2]
        if self.sensors is not None:
            self.sensors.reset(rngs, mask)  # type: ignore[arg-type]
            self._sample(mask, observe=False)
        if self.observer is not None:  # from the first fix, or the leg's start in a dropout
            eta_start = np.where(self._z_valid[:, None], self._last_z, ref.eta_P)
            self.observer.reset(self.physics.t, eta_start, mask=mask)
            self._obs_t = np.where(mask, self.physics.t, self._obs_t)
            self._cache.clear()
        self._metrics_record(mask, ref, reset=True)

    def _sample(self, mask: NDArray[np.bool_], observe: bool = True) -> None:
        """A sensor sample of the masked envs now (the single env's ``_measure``), fed to the
        observer (every env samples at the same instants: the sensor period divides the
        control period)."""
        assert self.sensors is not None
        physics = self.physics
        # first-order wave motion is seen, not lived (x + 0.0 without it, as x + zeros)
        eta = self._truth()[0]
        seen = eta + physics.wave_motion() if self._seen_waves else eta + 0.0
        z, valid, outlier = self.sensors.measure_rows(physics.t, seen, mask)
        # the sample's rows (mask) into the info's last sample (copies: info hands them out)
        # and the valid fixes into the metrics' last fix
        _store_sample(z, valid, outlier, mask, self._last_z, self._z_valid, self._z_outlier,
                      self._fix)  # fmt: skip
        if observe and self.observer is not None:
            self._cache.pop("nav", None)
            fixed = valid & mask
            # each env's observer on its own samples: the others stay where they are (no time
            # passes for them), as in their single envs
            t = np.where(mask, physics.t, self._obs_t)
            if self._model_based:  # the thrust its thrust_input names, held to the next sample
                _, tau_model, tau_command = self._readouts(self._thrust_cmd)
                tau = tau_command if self._thrust_cmd else tau_model
                if self.feedforward is not None:  # the thrust and the loads it estimates
                    tau = tau - self._tau_ff
                held = self._obs_tau
                self._obs_tau = tau if held is None else np.where(mask[:, None], tau, held)
            info = self._step_observer(t, z, fixed)
            self._nis = info.nis
            self._rejected = info.rejected
        log = self.sample_log
        if log is not None and mask[0]:  # the single env's info["measurements"] (env 0)
            ok = bool(valid[0])
            _, tau_model, tau_command = self._readouts(True)
            log.append({
                "t": float(physics.t[0]),
                "z": z[0].copy() if ok else None,
                "valid": ok,
                "outlier": ok and bool(outlier[0]),
                "tau": tau_model[0],
                "tau_command": tau_command[0],  # type: ignore[index]
            })  # fmt: skip

    def _advance(self, active: NDArray[np.bool_]) -> None:
        """``n_substeps`` physics steps, the sensors sampled on their grid (active envs)."""
        left = self.n_substeps
        every = self._sensor_steps
        if self.observer is not None:
            self._nis = self._nan_n.copy()
            self._rejected = np.zeros(self.num_envs, bool)
        if every is not None:
            self._last_z.fill(np.nan)
            self._z_valid.fill(False)
            self._z_outlier.fill(False)
        full = np.count_nonzero(active) == self.num_envs
        started = active
        while left > 0:
            if every is None:
                k = left
            elif self._aligned:  # every active env is at a sample instant: the next is every on
                k = every
            elif left == 1:  # (one step: no sample lies inside it)
                k = 1
            else:  # to the next sample of any active env: every - the largest phase
                phase = int(np.maximum.reduce(self._steps % every, where=active, initial=0))
                k = min(left, every - phase)
            # the steps each hull took (0 outside active; every hull: no mask to apply)
            taken = self.physics.step(k, stop_on_contact=self._stop, mask=None if full else active)
            self._cache.clear()
            self._steps += taken
            left -= k
            if self._stop:  # a hull that touched a quay stops (the episode ends with it)
                active = active & (taken == k)
                full = full and bool(active.all())
            if every is not None:  # (a hull stopped early is not at a sample instant)
                hit = active if self._aligned else active & (self._steps % every == 0)
                if np.count_nonzero(hit):
                    self._sample(hit)
        if self._coasts:  # a period that did not end at a sample: coast to now
            behind = started & (self._obs_t < self.physics.t)
            if np.count_nonzero(behind):
                self._coast(behind)

    def _coast(self, behind: NDArray[np.bool_]) -> None:
        """Propagate the observer of the envs ``behind`` to now without a measurement (holding
        the thrust of the last sample for a model-based one)."""
        t = np.where(behind, self.physics.t, self._obs_t)
        n = self.num_envs
        self._step_observer(t, np.full((n, 3), np.nan), np.zeros(n, dtype=bool))
        self._cache.pop("nav", None)

    def _step_observer(self, t: Array, z: Array, valid: NDArray[np.bool_]) -> Any:
        """Step the observer to the envs' times ``t`` with the samples ``z`` where ``valid``
        (a model-based one with the held thrust of each env's last sample) and keep its clock."""
        assert self.observer is not None
        if self._model_based:
            info = self.observer.step(t, z, valid, tau=self._obs_tau)
        else:
            info = self.observer.step(t, z, valid)
        self._obs_t = t
        return info

    def _terms(
        self, ref: Any, action: Array, switched: NDArray[np.bool_], new_contact: NDArray[np.bool_]
    ) -> None:
        """The task's observation (``_obs``, from the navigation data) and reward terms
        (``_rew``, from the truth) of every env."""
        eta, nu = self._truth()
        nav_eta, nav_nu = self._navigation()
        self.task.terms(eta, nu, nav_eta, nav_nu, ref.buffer, action, self._prev, switched,
                        new_contact, self._obs, self._rew, self._eta_r)  # fmt: skip

    def _observation(self, ref: Any = None) -> NDArray[np.float32]:
        """The observation of every env now (after a reset: its previous action is zero),
        computed once per state (``ref``: the guidance's reference now, where the caller has
        it)."""
        if self._fresh:
            return self._obs.copy()
        no = np.zeros(self.num_envs, dtype=bool)
        self._terms(ref if ref is not None else self.guidance.reference(self.physics.t),
                    self._prev, no, no)  # fmt: skip
        self._fresh = True  # _obs is this state's observation (until a step or reset)
        return self._obs.copy()

    def _info(
        self,
        mask: NDArray[np.bool_],
        saturated: NDArray[np.bool_] | None,
        action_clipped: NDArray[np.bool_] | None,
        command: Array | None,
        rewards: dict[str, Array],
        done: NDArray[np.bool_] | None = None,
    ) -> dict[str, Any]:
        """The info of a reset or a step: every key with its ``_key`` mask (``mask``)."""
        n, m = self.num_envs, self.n_actions
        g = self.guidance
        eta, nu = self._truth()
        nav_eta, nav_nu = self._navigation()
        info: dict[str, Any] = {
            "t": self.physics.t.copy(),
            "eta": eta,
            "nu": nu,
            "nav_eta": nav_eta,
            "nav_nu": nav_nu,
            "leg": g.leg.copy(),
            "legs_completed": g.legs_completed,
            "finished": g.finished.copy(),
            "command": self.physics.command if command is None else command,
            "saturated": np.zeros((n, m), bool) if saturated is None else saturated,
            "action_clipped": np.zeros((n, m), bool) if action_clipped is None else action_clipped,
            "quay_contact": self._contact.copy(),
        }
        if self.observer is not None:
            e = nav_eta - eta
            e[:, 2] = wrap_angle(e[:, 2])
            info["est_error_eta"] = e
            info["est_error_nu"] = nav_nu - nu
            info["observer_nis"] = self._nis.copy()
            info["observer_rejected"] = self._rejected.copy()
        if self.sensors is not None:
            info["z"] = self._last_z.copy()
            info["z_valid"] = self._z_valid.copy()
            info["z_outlier"] = self._z_outlier.copy()
        info.update(rewards)
        names = self._mask_names.get(len(info))
        if names is None:  # the keys of a reset (no reward terms) or of a step
            names = self._mask_names[len(info)] = tuple("_" + k for k in info)
        info.update(dict.fromkeys(names, mask))
        if done is not None and np.count_nonzero(done):
            summary = {
                "return": np.where(done, self._return, 0.0),
                "length": np.where(done, self._elapsed, 0),
                "duration_s": np.where(done, self.physics.t, 0.0),
                "legs_completed": np.where(done, g.legs_completed, 0),
                "completed": done & g.finished,
            }
            summary.update(dict.fromkeys(_SUMMARY_MASKS, mask))
            info["episode_summary"] = summary
            info["_episode_summary"] = done
        return info

    # ---- the episode metrics (ShipEnv.episode_metrics of each env) ----------------------
    def _metrics_setup(self) -> None:
        """The accumulator of the single env's :class:`~shipgym.metrics.ManoeuvreMetrics`
        for the N envs, and each env's last valid sensor fix (NED, NaN before the first)."""
        lower = self.actuators.lower
        self._metrics = BatchedManoeuvreMetrics(
            self.num_envs, 1.0, n_actuators=len(self.actuators), n_channels=self.n_actions,
            control_period=self.control_period, reversible=(lower < 0.0).tolist(),
        )  # fmt: skip
        slices = self.actuators.slices
        self._metrics_slices = None if all(x.stop - x.start == 1 for x in slices) else slices
        self._fix = np.full((self.num_envs, 3), np.nan)

    def _metrics_record(
        self,
        mask: NDArray[np.bool_],
        ref: Any,
        saturated: NDArray[np.bool_] | None = None,
        action: Array | None = None,
        *,
        reset: bool = False,
    ) -> None:
        """Record the envs of ``mask`` with the guidance's reference ``ref`` of this state as
        the single env's ``_record_metrics``: after a ``reset`` (the run restarts, no
        saturation or command), or after a control step with its per-channel ``saturated``
        flags and clipped ``action``."""
        m = self._metrics
        if reset:  # a new run from the first sample, as the single env's reset
            self._fix[mask & ~self._z_valid] = np.nan  # (no fix yet where it was a dropout)
            self._observation(ref)  # the r-frame poses of this state (_eta_r)
            m.reset(mask)
        if saturated is not None and self._metrics_slices is not None:  # per actuator
            saturated = np.stack([saturated[:, sl].any(axis=1) for sl in self._metrics_slices], 1)
        fix = self._fix
        measured = fix[:, 0] == fix[:, 0]  # (not NaN: a fix since the reset)
        meas = None
        if np.count_nonzero(measured):  # to_r_frame's compiled law on the rows (no broadcasting)
            meas = np.empty((self.num_envs, 3))
            psi_d_r = np.ascontiguousarray(ref.eta_d_r[:, 2])
            r_frame_poses(fix, np.ascontiguousarray(ref.eta_P), psi_d_r, True, meas)
        # (the env's own rows: the compiled step without the public record's checks)
        m.record_rows(self.physics.t, mask, self._eta_r, ref.eta_d_r, meas, measured,
                      self.thrust(), saturated, ref.leg, action)  # fmt: skip

    def episode_metrics(self, i: int) -> dict[str, Any]:
        """Env ``i``'s episode so far: accuracy indices (Tomera 2014 eqs. 54-57), thruster
        usage, legs and contact (:meth:`ShipEnv.episode_metrics
        <shipgym.envs.base.ShipEnv.episode_metrics>`)."""
        return self._episode_rows([i])[i]

    def _episode_rows(self, envs: list[int]) -> dict[int, dict[str, Any]]:
        """:meth:`episode_metrics` of each env of ``envs`` (their command chatter computed
        together)."""
        g = self.guidance
        rows = {}
        for i, out in zip(envs, self._metrics.summaries(envs), strict=True):
            times = g.leg_completion_times(i)
            out["completed"] = bool(g.finished[i])
            out["legs_completed"] = len(times)
            out["leg_times"] = list(times)
            out["quay_contact"] = bool(self._contact[i])
            out["duration_s"] = float(self.physics.t[i])
            rows[i] = out
        return rows

    def _episode_metrics(self, done: NDArray[np.bool_]) -> dict[str, Any]:
        """The single env's :meth:`~shipgym.envs.base.ShipEnv.episode_metrics` of the envs of
        ``done``: numbers as (N,) arrays (float NaN, int 0, bool False elsewhere), the other
        values (lists, dicts, ``None``) as (N,) object arrays (``None`` elsewhere); env ``i``'s
        dict is ``{k: v[i]}`` (numbers as ``v[i].item()``)."""
        # episode ends: per env
        rows = self._episode_rows(np.flatnonzero(done).tolist())
        n = self.num_envs
        fill = {float: np.nan, int: 0, bool: False}
        metrics: dict[str, Any] = {}
        for k in next(iter(rows.values())):
            kinds = {type(r[k]) for r in rows.values()}
            kind = kinds.pop() if len(kinds) == 1 else None
            if kind in fill:
                a = np.full(n, fill[kind], dtype=kind)
            else:
                a = np.full(n, None, dtype=object)
            for i, r in rows.items():
                a[i] = r[k]
            metrics[k] = a
        return metrics


#: the masks of the controller's info keys (:meth:`ShipVectorEnv._control`)
_CONTROL_MASKS = ("_tau_c", "_tau_delivered", "_tau_error", "_controller_action",
                  "_allocation_saturated", "_residual_clipped", "_tau_ff")  # fmt: skip
#: the masks of ``info["episode_summary"]``'s keys
_SUMMARY_MASKS = ("_return", "_length", "_duration_s", "_legs_completed", "_completed")


@njit
def _actions(a, lo, hi, lo_tol, hi_tol, clipped, flags, command, near):  # type: ignore[no-untyped-def]
    """The env's action law of every row of the actions ``a`` (n, m) (finite): the action
    clipped to ``[-1, 1]`` (``np.clip``'s floats) into ``clipped`` and where it was clipped
    into ``flags``, each channel's command of it (:func:`~shipgym.dynamics.actuators.
    channel_command`, ranges ``lo``, ``hi``) into ``command``, and whether that command is
    within ``1e-9`` of its range's ends (``lo_tol``, ``hi_tol``) into ``near``."""
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            x = a[i, j]
            c = -1.0 if x < -1.0 else (1.0 if x > 1.0 else x)
            clipped[i, j] = c
            flags[i, j] = c != x
            u = channel_command(c, lo[j], hi[j])
            command[i, j] = u
            near[i, j] = u <= lo_tol[j] or u >= hi_tol[j]


@njit
def _store_sample(z, valid, outlier, mask, last_z, z_valid, z_outlier, fix):  # type: ignore[no-untyped-def]
    """The rows of ``mask`` of a sensor sample (poses ``z`` (n, 3), flags ``valid``,
    ``outlier``) into ``last_z``, ``z_valid``, ``z_outlier``, and its valid rows into
    ``fix``."""
    for i in range(z.shape[0]):
        if mask[i]:
            for j in range(3):
                last_z[i, j] = z[i, j]
                if valid[i]:
                    fix[i, j] = z[i, j]
            z_valid[i] = valid[i]
            z_outlier[i] = outlier[i]


def _rows_from(old: Any, new: Any, mask: NDArray[np.bool_]) -> Any:
    """A batched reference with the rows of ``mask`` from ``new``, the others from ``old``."""
    from shipgym.guidance.batch import BatchedReference

    def pick(a: Any, b: Any) -> Any:
        return np.where(mask.reshape(mask.shape + (1,) * (np.ndim(a) - 1)), b, a)

    names = ("eta_d_r", "eta_dot_d_r", "eta_ddot_d_r", "eta_P", "eta_d_n", "eta_K", "leg",
             "t_leg", "finished")  # fmt: skip
    return BatchedReference(*(pick(getattr(old, k), getattr(new, k)) for k in names))


def _task_class(task: type[PlanEnvSpec] | str) -> tuple[type[PlanEnvSpec], int | None]:
    """The single env's class and registered time limit of ``task`` (a class or an id)."""
    import importlib

    from .registration import ENV_IDS, VECTOR_IDS

    if isinstance(task, str):
        if task not in VECTOR_IDS:
            raise ValueError(
                f"{task!r} has no batched form; batched ids: {', '.join(sorted(VECTOR_IDS))}"
            )
        entry, steps = ENV_IDS[task]
        mod, name = entry.split(":")
        cls = getattr(importlib.import_module(mod), name)
        if not issubclass(cls, PlanEnvSpec):
            raise ValueError(
                f"{task!r} is not a plan task: its batched env is gymnasium.make_vec({task!r}, "
                "num_envs=N), not ShipVectorEnv"
            )
        return cls, steps
    if not (isinstance(task, type) and issubclass(task, PlanEnvSpec)):
        raise ValueError(f"task must be a ShipEnv subclass or a batched id, got {task!r}")
    for env_id in VECTOR_IDS:
        entry, steps = ENV_IDS[env_id]
        if entry == f"{task.__module__}:{task.__qualname__}":
            return task, steps
    return task, None


def harbour_vector_env(num_envs: int, **kwargs: Any) -> ShipVectorEnv:
    """``shipgym/Harbour-v0``'s vector entry point (``vessel=`` required)."""
    return ShipVectorEnv(num_envs, "shipgym/Harbour-v0", **kwargs)


def blue_lady_harbour_vector_env(num_envs: int, **kwargs: Any) -> ShipVectorEnv:
    """``shipgym/BlueLadyHarbour-v0``'s vector entry point."""
    return ShipVectorEnv(num_envs, "shipgym/BlueLadyHarbour-v0", **kwargs)


def dp_station_keeping_vector_env(num_envs: int, **kwargs: Any) -> ShipVectorEnv:
    """``shipgym/DPStationKeeping-v0``'s vector entry point (``vessel=`` required)."""
    return ShipVectorEnv(num_envs, "shipgym/DPStationKeeping-v0", **kwargs)


def dp_sway_step_vector_env(num_envs: int, **kwargs: Any) -> ShipVectorEnv:
    """``shipgym/DPSwayStep-v0``'s vector entry point (``vessel=`` required)."""
    return ShipVectorEnv(num_envs, "shipgym/DPSwayStep-v0", **kwargs)


def tracking_vector_env(num_envs: int, **kwargs: Any) -> ShipVectorEnv:
    """``shipgym/Tracking-v0``'s vector entry point (``vessel=`` required)."""
    return ShipVectorEnv(num_envs, "shipgym/Tracking-v0", **kwargs)


def station_keeping_vector_env(num_envs: int, **kwargs: Any) -> ShipVectorEnv:
    """``shipgym/StationKeeping-v0``'s vector entry point (``vessel=`` required)."""
    return ShipVectorEnv(num_envs, "shipgym/StationKeeping-v0", **kwargs)


def blue_lady_tracking_vector_env(num_envs: int, **kwargs: Any) -> ShipVectorEnv:
    """``shipgym/BlueLadyTracking-v0``'s vector entry point."""
    return ShipVectorEnv(num_envs, "shipgym/BlueLadyTracking-v0", **kwargs)


def blue_lady_station_keeping_vector_env(num_envs: int, **kwargs: Any) -> ShipVectorEnv:
    """``shipgym/BlueLadyStationKeeping-v0``'s vector entry point."""
    return ShipVectorEnv(num_envs, "shipgym/BlueLadyStationKeeping-v0", **kwargs)
