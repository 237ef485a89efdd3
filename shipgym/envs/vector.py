r"""A native batched ``gymnasium.vector.VectorEnv`` of the open-water positioning tasks.

:class:`ShipVectorEnv` steps ``num_envs`` copies of ``shipgym/Tracking-v0`` or
``shipgym/StationKeeping-v0`` (any vessel that can position itself, 3 DOF) in one array
computation per step: the physics of every hull (:class:`~shipgym.envs.batchphysics.
BatchedPhysics`: plant, actuator lags, gusty wind and current), the sensors
(:class:`~shipgym.observers.sensors.BatchedSensors`), the guidance
(:class:`~shipgym.guidance.batch.BatchedGuidance`), the observation, the reward terms, and,
when asked, the Kalman observer and the DP controller of the training stack. It is made by
``gymnasium.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")`` (the default
mode for these ids).

Env ``i`` is the single env of the same id and arguments, reset with seed ``seed + i``
(gymnasium's convention): the same draws (plan, wind, current, sensor noise, start
perturbation, gusts and sensor streams, from the env's own generator in the single env's
order) and, with the same actions, the same trajectory within 1e-6 m and 1e-6 rad over whole
episodes (the same integration scheme; a test checks each task and vessel). The MuJoCo single
env stays the reference and the only form of the harbour task (quays need contacts).

What differs from the single env:

* ``info`` holds arrays (one row per env, gymnasium's vector convention with ``_key`` masks):
  ``t``, ``eta``, ``nu``, ``nav_eta``, ``nav_nu``, ``leg``, ``legs_completed``, ``finished``,
  ``command``, ``saturated``, ``action_clipped``, the ``reward_*`` terms, the step's last sensor
  sample ``z``, ``z_valid``, ``z_outlier`` (``z`` is NaN where none was taken or in a dropout),
  and ``episode_summary`` (``return``, ``length`` in control steps, ``duration_s``,
  ``legs_completed``, ``completed``) where an episode ended.
  There is no ``record`` and no ``episode_metrics`` (the Tomera indices need every sample of
  the episode; evaluate with the single env).
* Autoreset: Gymnasium 1.x's ``NEXT_STEP`` mode by default (the step after an episode's end
  resets that env and ignores its action); ``autoreset_mode="same-step"`` resets in the step
  that ends the episode and puts the last observation and info under ``final_obs`` and
  ``final_info`` (the mode stable-baselines3 expects: :mod:`shipgym.rl.vec`).
* The time limit is the env's own (``max_episode_steps``: the registered one by default).

Backends: NumPy. Waves, the harbour, 4-DOF hulls and rendering are the single env's only.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from shipgym.dynamics.frames import wrap_angle
from shipgym.guidance.batch import BatchedGuidance
from shipgym.observers.sensors import BatchedSensors, SensorConfig

from .base import ShipEnv, tracking_penalty
from .batchphysics import BatchedPhysics

__all__ = [
    "AUTORESET_MODES",
    "ShipVectorEnv",
    "navigation_observations",
    "station_keeping_vector_env",
    "tracking_vector_env",
]

Array = NDArray[np.float64]

#: the accepted ``autoreset_mode`` values (strings or :class:`gymnasium.vector.AutoresetMode`)
AUTORESET_MODES = {
    "next-step": AutoresetMode.NEXT_STEP,
    "same-step": AutoresetMode.SAME_STEP,
    AutoresetMode.NEXT_STEP: AutoresetMode.NEXT_STEP,
    AutoresetMode.SAME_STEP: AutoresetMode.SAME_STEP,
}


class ShipVectorEnv(gym.vector.VectorEnv[Any, Any, Any]):
    """``num_envs`` copies of a positioning task stepped together (module docstring).

    Spaces: the single env's, batched: ``observation_space`` ``Box(-inf, inf, (N, 12 + n),
    float32)`` (the layout of :class:`~shipgym.envs.base.ShipEnv`, ``observation_structure``;
    with an observer its estimate replaces the truth), ``action_space`` ``Box(-1, 1, (N, n),
    float32)`` (one normalised command, or with ``controller`` one residual, per channel; out
    of range is clipped and flagged in ``info["action_clipped"]``, NaN raises). Reward: the
    single env's terms (``info["reward_*"]``, which sum to it). Episodes end as the single
    env's: terminated when the plan is complete (Tracking), truncated at
    ``max_episode_steps``.

    Args:
        num_envs: number of envs, >= 1.
        task: the single env's class (:class:`~shipgym.envs.tasks.TrackingEnv`,
            :class:`~shipgym.envs.tasks.StationKeepingEnv` or a subclass) or its registered id.
        max_episode_steps: the time limit (control steps); ``None``: the id's registered one.
        autoreset_mode: ``"next-step"`` (default) or ``"same-step"``.
        controller: ``None`` (the actions drive the actuators) or a DP controller name
            (``"pid"``, ``"pid-smooth"``, ``"pid-seed"``: :func:`~shipgym.controllers.batch.
            batched_dp_controller`): the actions are residuals on its normalised command, as
            under :class:`~shipgym.controllers.wrappers.DPControllerWrapper`
            (``shipgym.make(..., controller=)``).
        residual_scale: the factor on the residual actions (with ``controller``).
        observer: ``None`` / ``"truth"`` (the observation and the controller use the true
            state) or a Kalman observer (``"kbf"``, ``"dkf"``, ``"tomera-kbf"``,
            ``"tomera-dkf"``: :class:`~shipgym.observers.batch.BatchedKalman`) fed every sensor
            sample, whose estimate they use instead, as under
            :class:`~shipgym.observers.wrapper.ObserverWrapper` (``shipgym.make(...,
            observer=)``).
        env_sensors: one sensor configuration per env, each as the ``sensors=`` of env ``i``
            (the training stack's per-env noise); they may differ only in their variances.
        **kwargs: the single env's arguments (``vessel=``, ``wind=``, ``max_legs=``, ...); the
            scene must be open water, without waves.

    Raises:
        ValueError: a task, vessel or argument the batched form does not cover, naming it.
    """

    metadata: dict[str, Any] = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(
        self,
        num_envs: int,
        task: type[ShipEnv] | str,
        *,
        max_episode_steps: int | None = None,
        autoreset_mode: str | AutoresetMode = "next-step",
        controller: str | None = None,
        residual_scale: float = 1.0,
        observer: str | None = None,
        env_sensors: Sequence[SensorConfig] | None = None,
        **kwargs: Any,
    ) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs must be an int >= 1, got {num_envs!r}")
        cls, steps = _task_class(task)
        if max_episode_steps is None:
            if steps is None:
                raise ValueError(
                    f"{cls.__name__} is not a registered batched task: pass max_episode_steps="
                )
            max_episode_steps = steps
        if not (isinstance(max_episode_steps, int) and max_episode_steps >= 1):
            raise ValueError(f"max_episode_steps must be an int >= 1, got {max_episode_steps!r}")
        if autoreset_mode not in AUTORESET_MODES:
            raise ValueError(
                f"autoreset_mode must be 'next-step' or 'same-step', got {autoreset_mode!r}"
            )
        if kwargs.get("render_mode") is not None:
            raise ValueError("the batched env does not render; use the single env (gym.make)")
        # the single env of these arguments: its configuration and its per-episode draws
        self.template = tmpl = cls(**kwargs)
        if tmpl.scene != "open-water" or tmpl.wave_config is not None:
            raise ValueError(
                "the batched env covers open water without waves (the Tracking and "
                f"StationKeeping tasks); got scene={tmpl.scene!r}, waves={tmpl.wave_config!r}: "
                "use gym.make for the single env"
            )
        self.num_envs = n = num_envs
        self.max_episode_steps = max_episode_steps
        self.autoreset_mode = AUTORESET_MODES[autoreset_mode]
        self.metadata = dict(self.metadata, autoreset_mode=self.autoreset_mode)
        self.vessel = tmpl.vessel
        self.actuators = tmpl.actuators
        self.n_actions = tmpl.n_actions
        phys = tmpl.physics
        self.physics = BatchedPhysics(
            self.vessel, n, phys.plant, wind=tmpl._wind, current=tmpl._current,
            timestep=phys.timestep,
        )  # fmt: skip
        self.n_substeps = tmpl.n_substeps
        self.control_period = tmpl.control_period
        cfg = tmpl._sensor_setting
        self.sensors = None if cfg is None else BatchedSensors(cfg, n)
        self._sensor_steps = tmpl._sensor_steps
        self.guidance = BatchedGuidance(n, limits=tmpl.limits)
        self.single_observation_space = tmpl.observation_space
        self.single_action_space = tmpl.action_space
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self.observation_structure = dict(tmpl.observation_structure)
        self._rngs: list[np.random.Generator | None] = [None] * n
        self._steps = np.zeros(n, dtype=np.int64)  # physics steps since reset
        self._elapsed = np.zeros(n, dtype=np.int64)  # control steps since reset
        self._return = np.zeros(n)
        self._prev = np.zeros((n, self.n_actions))
        self._ended = np.zeros(n, dtype=bool)  # NEXT_STEP: reset at the next step
        self._started = False
        lo, hi = self.actuators.lower, self.actuators.upper
        self._lo_tol, self._hi_tol = lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo)
        if not (isinstance(residual_scale, int | float) and math.isfinite(residual_scale)):
            raise ValueError(f"residual_scale must be a finite number, got {residual_scale!r}")
        self.controller_name = controller
        self.residual_scale = float(residual_scale)
        self.controller = None
        if controller is not None:
            from shipgym.controllers.batch import batched_dp_controller

            # the batched observers are all kinematic (BatchedKalman)
            src = "truth" if observer in (None, "truth") else "kinematic"
            self.controller = batched_dp_controller(
                controller, self.vessel, n, self.control_period, velocity_source=src
            )
        if env_sensors is not None:
            env_sensors = list(env_sensors)
            if len(env_sensors) != n or not all(isinstance(c, SensorConfig) for c in env_sensors):
                raise ValueError(f"env_sensors must be {n} SensorConfigs (one per env)")
            if self.sensors is None:
                raise ValueError("env_sensors needs sensors (the env was made with sensors=None)")
        self._env_sensors = env_sensors
        self.observer_name = None if observer in (None, "truth") else observer
        self.observer = None
        if self.observer_name is not None:
            from shipgym.observers.batch import BatchedKalman

            every = self._sensor_steps
            if self.sensors is None or every is None:
                raise ValueError(
                    "an observer needs sensors: create the env with sensors='default' (or "
                    "another preset), not sensors=None"
                )
            if self.n_substeps % every:
                raise ValueError(
                    f"the batched env's observer needs a sensor period that divides the control "
                    f"period ({self.control_period:g} s); got {self.sensors.config.period:g} s: "
                    "use the single env (shipgym.make) for it"
                )
            # the design noise of the vessel, as the observer wrapper's make_observer
            self.observer = BatchedKalman(self.observer_name, n, vessel=self.vessel)
        self._nis = np.full(n, np.nan)
        self._rejected = np.zeros(n, bool)
        self._cache: dict[str, Any] = {}  # this state's eta, nu (and estimate), read once
        self._ref: Any = None
        self._leg = np.zeros(n, dtype=np.int64)
        self._psi_P = np.zeros(n)
        self._last_z = np.full((n, 3), np.nan)
        self._z_valid = np.zeros(n, dtype=bool)
        self._z_outlier = np.zeros(n, dtype=bool)

    # ---- gymnasium API -------------------------------------------------------------------
    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        """Reset every env (or those of ``options["reset_mask"]``); env ``i`` is seeded with
        ``seed + i`` (an int), ``seed[i]`` (a sequence) or, without a seed, goes on with its
        generator (fresh entropy before the first seed)."""
        n = self.num_envs
        options = dict(options or {})
        mask = np.asarray(options.pop("reset_mask", np.ones(n, bool)), dtype=bool)
        if mask.shape != (n,):
            raise ValueError(f"options['reset_mask'] must be ({n},) booleans, got {mask.shape}")
        if options:
            raise ValueError(f"unknown reset options {sorted(options)}; valid: ['reset_mask']")
        if seed is None:
            seeds: list[int | None] = [None] * n
        elif isinstance(seed, int | np.integer) and not isinstance(seed, bool):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)  # type: ignore[arg-type]
            if len(seeds) != n:
                raise ValueError(f"seed must be an int or {n} seeds (one per env), got {seed!r}")
        for i in np.nonzero(mask)[0].tolist():
            if seeds[i] is not None or self._rngs[i] is None:
                self._rngs[i], _ = seeding.np_random(seeds[i])
        if not self._started:
            if not mask.all():
                raise ValueError("the first reset must reset every env (no reset_mask)")
            self._started = True
        self._reset_envs(mask)
        self._ended[mask] = False
        return self._observation(), self._info(mask, None, None, None, {})

    def step(
        self, actions: Any
    ) -> tuple[NDArray[np.float32], Array, NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]]:
        """One control period of every env (``actions``: (num_envs, n_channels) in [-1, 1]).

        Raises:
            gymnasium.error.ResetNeeded: before the first :meth:`reset`.
            ValueError: actions of the wrong shape or with NaN / infinite values.
        """
        if not self._started:
            raise gym.error.ResetNeeded("call reset() before step()")
        a = np.asarray(actions, dtype=float)
        n, m = self.num_envs, self.n_actions
        if a.shape != (n, m):
            raise ValueError(
                f"actions must have shape ({n}, {m}) (num_envs, channels), got {a.shape}"
            )
        if not np.all(np.isfinite(a)):
            bad = np.nonzero(~np.all(np.isfinite(a), axis=1))[0].tolist()
            raise ValueError(f"actions must be finite; NaN or infinite in envs {bad}")
        resetting = self._ended.copy()  # NEXT_STEP: these reset now and ignore their action
        active = ~resetting
        control: dict[str, Array] = {}
        if self.controller is not None:
            a, control = self._control(a)
        clipped = np.clip(a, -1.0, 1.0)
        action_clipped = clipped != a
        command = self.actuators.action_to_command(clipped)
        held = self.physics.set_command(command)
        saturated = held | (command <= self._lo_tol) | (command >= self._hi_tol)
        self._advance(active)
        t = self.physics.t
        eta = self._truth()[0]
        switched = self.guidance.update(t, eta)
        ref = self.guidance.reference(t)
        rewards = self._reward_terms(eta, ref, clipped, switched)
        self._ref = ref
        if self.controller is not None:  # a leg switch turns the controller's r-frame
            moved = ref.leg != self._leg
            if moved.any():
                psi_P = ref.eta_P[:, 2]
                self.controller.change_frame(wrap_angle(psi_P - self._psi_P), moved)
                self._leg = np.where(moved, ref.leg, self._leg)
                self._psi_P = np.where(moved, psi_P, self._psi_P)
        reward = sum(rewards.values())
        self._prev = clipped
        self._elapsed += 1
        terminated = self.guidance.finished & self.template.terminate_on_finish
        truncated = self._elapsed >= self.max_episode_steps
        done = (terminated | truncated) & active
        self._return += reward
        info = self._info(np.ones(n, bool), saturated, action_clipped, command, rewards, done=done)
        for k, v in control.items():
            info[k], info["_" + k] = v, np.ones(n, bool)
        if self.autoreset_mode == AutoresetMode.NEXT_STEP:
            obs = self._observation(ref)
            if resetting.any():
                self._reset_envs(resetting)
                obs[resetting] = self._observation()[resetting]
                reward = np.where(resetting, 0.0, reward)
                terminated = terminated & active
                truncated = truncated & active
                info = _merge_reset_info(info, self._info(resetting, None, None, None, {}),
                                         resetting)  # fmt: skip
            self._ended = done
            return obs, reward, terminated, truncated, info
        obs = self._observation(ref)
        if done.any():  # SAME_STEP: reset now, the last observation and info kept aside
            info["final_obs"] = np.where(done[:, None], obs, np.nan).astype(np.float32)
            info["_final_obs"] = done
            last = {k: v for k, v in info.items() if not k.lstrip("_").startswith("final")}
            info["final_info"] = last
            info["_final_info"] = done
            self._reset_envs(done)
            obs = np.where(done[:, None], self._observation(), obs)
        return obs, reward, terminated, truncated, info

    # ---- internals ------------------------------------------------------------------------
    def _truth(self) -> tuple[Array, Array]:
        """The hulls' ``(eta, nu)`` now, read once per state (cached until the next physics
        step, sample or reset)."""
        if self._cache.get("truth") is None:
            self._cache["truth"] = (self.physics.eta, self.physics.nu)
        return self._cache["truth"]

    def _navigation(self) -> tuple[Array, Array]:
        """What the controller and the observation use: the estimate, else the truth."""
        if self.observer is None:
            return self._truth()
        if self._cache.get("nav") is None:
            self._cache["nav"] = (self.observer.eta, self.observer.nu)
        return self._cache["nav"]

    def _control(self, residual: Array) -> tuple[Array, dict[str, Array]]:
        """The DP controller's action plus the residual, as the controller wrapper forms it
        (from the navigation data and reference at the end of the previous step)."""
        from shipgym.controllers.batch import apply_residual

        assert self.controller is not None
        ref = self._ref
        eta, nu = self._navigation()
        tau_c, alloc, a_ctrl = self.controller(
            ref.to_r(eta), nu, ref.eta_d_r, ref.eta_dot_d_r, ref.eta_ddot_d_r,
            state=self.physics.actuator_state,
        )  # fmt: skip
        applied, clipped = apply_residual(a_ctrl, residual, self.residual_scale)
        info = {
            "tau_c": np.ascontiguousarray(tau_c),
            "tau_delivered": np.ascontiguousarray(alloc.tau),
            "tau_error": np.ascontiguousarray(alloc.tau_error),
            "controller_action": np.ascontiguousarray(a_ctrl),
            "residual_clipped": clipped,
        }
        # the wrapper hands the env a float32 action
        return applied.astype(np.float32).astype(np.float64), info

    def _reset_envs(self, mask: NDArray[np.bool_]) -> None:
        """Reset the masked envs, each from its generator in the single env's order."""
        self._cache.clear()
        tmpl = self.template
        idx = np.nonzero(mask)[0].tolist()
        start = tmpl.start_pose
        eta0 = np.broadcast_to(start, (self.num_envs, 3)).copy()
        plans = []
        for i in idx:
            rng = self._rngs[i]
            assert rng is not None
            tmpl.np_random = rng  # the task's draws come from env i's generator
            plans.append(tmpl._episode_plan())
            wind, current = tmpl._episode_wind(), tmpl._episode_current()
            self.physics.set_disturbances(i, wind, current)
            if self._env_sensors is not None:  # env i as made with sensors=env_sensors[i]
                tmpl._sensor_setting = self._env_sensors[i]
            sensors = tmpl._episode_sensors()
            if sensors is not None and self.sensors is not None:
                self.sensors.set_config(i, sensors)
            eta0[i] = start + rng.uniform(-1.0, 1.0, 3) * tmpl.start_noise
        rngs = self._rngs
        self.physics.reset(eta=eta0, mask=mask, rngs=rngs)  # type: ignore[arg-type]
        self._steps[mask] = 0
        self._elapsed[mask] = 0
        self._return[mask] = 0.0
        self._prev[mask] = 0.0
        self.guidance.reset(plans, np.broadcast_to(start, (self.num_envs, 3)), 0.0, mask=mask)
        ref = self.guidance.reference(self.physics.t)
        # the reset envs' rows of the reference the next step's controller reads
        self._ref = ref if self._ref is None else _rows_from(self._ref, ref, mask)
        if self.controller is not None:
            self.controller.reset(mask)
            self._leg[mask] = ref.leg[mask]
            self._psi_P[mask] = ref.eta_P[mask, 2]
        if self.sensors is not None:
            self.sensors.reset(rngs, mask)  # type: ignore[arg-type]
            self._sample(mask, observe=False)
        if self.observer is not None:  # from the first fix, or the leg's start in a dropout
            eta_start = np.where(self._z_valid[:, None], self._last_z, ref.eta_P)
            self.observer.reset(self.physics.t, eta_start, mask=mask)
            self._cache.clear()

    def _sample(self, mask: NDArray[np.bool_], observe: bool = True) -> None:
        """A sensor sample of the masked envs now (the single env's ``_measure``), fed to the
        observer (every env samples at the same instants: the sensor period divides the
        control period)."""
        assert self.sensors is not None
        z, valid, outlier = self.sensors.measure(self.physics.t, self._truth()[0], mask)
        if observe and self.observer is not None:
            self._cache.pop("nav", None)
            info = self.observer.step(self.physics.t, z, valid & mask)
            self._nis = info.nis
            self._rejected = info.rejected
        self._last_z = np.where(mask[:, None], z, self._last_z)
        self._z_valid = np.where(mask, valid, self._z_valid)
        self._z_outlier = np.where(mask, outlier, self._z_outlier)

    def _advance(self, active: NDArray[np.bool_]) -> None:
        """``n_substeps`` physics steps, the sensors sampled on their grid (active envs)."""
        left = self.n_substeps
        every = self._sensor_steps
        self._nis = np.full(self.num_envs, np.nan)
        self._rejected = np.zeros(self.num_envs, bool)
        if self.sensors is not None:
            self._last_z[:] = np.nan
            self._z_valid[:] = False
            self._z_outlier[:] = False
        while left > 0:
            if every is None:
                k = left
            else:
                k = min(left, int((every - self._steps[active] % every).min(initial=every)))
            self.physics.step(k)
            self._cache.clear()
            self._steps += k
            left -= k
            if every is not None:
                hit = active & (self._steps % every == 0)
                if hit.any():
                    self._sample(hit)

    def _observation(self, ref: Any = None) -> NDArray[np.float32]:
        """The single env's observation (its class docstring) of every env, from the truth."""
        if ref is None:
            ref = self.guidance.reference(self.physics.t)
        eta, nu = self._navigation()
        return navigation_observations(eta, nu, ref, self._prev)

    def _reward_terms(
        self, eta: Array, ref: Any, action: Array, switched: NDArray[np.bool_]
    ) -> dict[str, Array]:
        w = self.template.reward_weights
        e = ref.to_r(eta) - ref.eta_d_r
        dn = self._truth()[1] - ref.nu_d
        prev = self._prev
        effort = np.zeros(self.num_envs)
        rate = np.zeros(self.num_envs)
        for j in range(self.n_actions):  # from 0 in channel order, as the single env sums
            effort = effort + action[:, j] * action[:, j]
            rate = rate + (action[:, j] - prev[:, j]) ** 2
        zero = np.zeros(self.num_envs)
        return {
            "reward_position": -tracking_penalty(
                w.position, e[:, 0] * e[:, 0] + e[:, 1] * e[:, 1], w.position_scale
            ),
            "reward_heading": -tracking_penalty(
                w.heading, wrap_angle(e[:, 2]) ** 2, w.heading_scale
            ),
            "reward_velocity": -tracking_penalty(
                w.velocity,
                dn[:, 0] * dn[:, 0] + dn[:, 1] * dn[:, 1] + dn[:, 2] * dn[:, 2],
                w.velocity_scale,
            ),
            "reward_effort": -w.effort * effort,
            "reward_rate": -w.rate * rate,
            "reward_contact": zero,
            "reward_leg": np.where(switched, w.leg_bonus, 0.0),
        }

    def _info(
        self,
        mask: NDArray[np.bool_],
        saturated: NDArray[np.bool_] | None,
        action_clipped: NDArray[np.bool_] | None,
        command: Array | None,
        rewards: dict[str, Array],
        done: NDArray[np.bool_] | None = None,
    ) -> dict[str, Any]:
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
            "legs_completed": g.legs_completed.copy(),
            "finished": g.finished.copy(),
            "command": self.physics.command if command is None else command,
            "saturated": np.zeros((n, m), bool) if saturated is None else saturated,
            "action_clipped": np.zeros((n, m), bool) if action_clipped is None else action_clipped,
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
        for k in rewards:
            info[k] = rewards[k]
        for k in list(info):
            info["_" + k] = mask
        if done is not None and done.any():
            info["episode_summary"] = {
                "return": np.where(done, self._return, 0.0),
                "length": np.where(done, self._elapsed, 0),
                "duration_s": np.where(done, self.physics.t, 0.0),
                "legs_completed": np.where(done, g.legs_completed, 0),
                "completed": done & g.finished,
            }
            info["_episode_summary"] = done
        return info


def navigation_observations(
    eta: Array, nu: Array, ref: Any, prev_action: Array
) -> NDArray[np.float32]:
    """:meth:`ShipEnv.navigation_observation <shipgym.envs.base.ShipEnv.navigation_observation>`
    of N envs: poses and velocities (N, 3), a batched reference, previous actions (N, n)."""
    psi = eta[:, 2]
    c, s = np.cos(psi), np.sin(psi)
    d = ref.eta_d_n
    dx, dy = eta[:, 0] - d[:, 0], eta[:, 1] - d[:, 1]
    n = eta.shape[0]
    out = np.empty((n, 12 + prev_action.shape[1]), dtype=np.float32)
    out[:, 0] = c * dx + s * dy
    out[:, 1] = c * dy - s * dx
    out[:, 2] = wrap_angle(psi - d[:, 2])
    out[:, 3:6] = nu
    out[:, 6:9] = ref.nu_d
    out[:, 9:12] = ref.nu_dot_d
    out[:, 12:] = prev_action
    return out


def _rows_from(old: Any, new: Any, mask: NDArray[np.bool_]) -> Any:
    """A batched reference with the rows of ``mask`` from ``new``, the others from ``old``."""
    from shipgym.guidance.batch import BatchedReference

    def pick(a: Any, b: Any) -> Any:
        return np.where(mask.reshape(mask.shape + (1,) * (np.ndim(a) - 1)), b, a)

    names = ("eta_d_r", "eta_dot_d_r", "eta_ddot_d_r", "eta_P", "eta_d_n", "eta_K", "leg",
             "t_leg", "finished")  # fmt: skip
    return BatchedReference(*(pick(getattr(old, k), getattr(new, k)) for k in names))


def _merge_reset_info(
    info: dict[str, Any], reset: dict[str, Any], mask: NDArray[np.bool_]
) -> dict[str, Any]:
    """``info`` with the rows of ``mask`` taken from the reset envs' ``reset`` info."""
    out = dict(info)
    for k, v in reset.items():
        if k.startswith("_"):
            continue
        if k in out and isinstance(v, np.ndarray) and v.shape == out[k].shape:
            sel = mask.reshape(mask.shape + (1,) * (v.ndim - 1))
            out[k] = np.where(sel, v, out[k])
    for k in [k for k in out if k.startswith("reward_")]:
        out[k] = np.where(mask, 0.0, out[k])
    return out


def _task_class(task: type[ShipEnv] | str) -> tuple[type[ShipEnv], int | None]:
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
        return getattr(importlib.import_module(mod), name), steps
    if not (isinstance(task, type) and issubclass(task, ShipEnv)):
        raise ValueError(f"task must be a ShipEnv subclass or a batched id, got {task!r}")
    for env_id in VECTOR_IDS:
        entry, steps = ENV_IDS[env_id]
        if entry == f"{task.__module__}:{task.__qualname__}":
            return task, steps
    return task, None


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
