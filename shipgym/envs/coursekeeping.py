r"""Course keeping through a DGPS receiver: steer with the rudder, see the receiver's velocity.

The course-keeping task of the notes' seed 004 mapping: a ship at its approach speed holds
and changes its heading with the rudder alone, in wind and current, and its velocity comes
from a DGPS receiver whose position-velocity Kalman filter (Artyszuk 2003 eqs. 1-5,
:class:`~shipgym.observers.dgps.DGPSReceiver`) lags the manoeuvre: during a turn the
receiver's drift angle is biased high (by up to about ``r tau``, ``tau`` 5.85 s for ``S_p =
0.01``) and its speed lags a speed loss. The learner sees that biased velocity
(``receiver="dgps-pv"``), the true one (``"truth"``) or the raw positions differentiated
(``"raw"``, the seed's recommended alternative), for comparison. Generic over any vessel
with a rudder and a known approach speed; the registered ``shipgym/CourseKeeping-v0`` is the
seed's 100 m tanker (``kvlcc2-100m``, the KVLCC2 MMG hull of Yasukawa & Yoshimura 2015
scaled). The classical baseline is :func:`shipgym.controllers.coursepilot.course_autopilot`.
Sources in full: ``docs/references.md``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from shipgym._config import from_mapping, is_real, param
from shipgym._seeding import child_seeds
from shipgym.disturbances import CurrentConfig, WindConfig
from shipgym.dynamics import wrap_angle
from shipgym.dynamics.actuators import MMGPropulsion, Propeller
from shipgym.dynamics.vessel import Vessel, load_vessel
from shipgym.observers.dgps import (
    DGPS_SIGMA,
    S_P_OPTIMAL,
    DGPSReceiver,
    NormalStreams,
    antenna_motion,
    velocity_outputs,
)

from .batchphysics import BatchedPhysics
from .stepped import StepTask, TaskEnv, TaskSingleEnv

__all__ = [
    "AUTO",
    "AUTO_CURRENT_SPEED",
    "COURSE_OBSERVATION",
    "CourseKeepingEnv",
    "CourseKeepingTask",
    "CourseKeepingVectorEnv",
    "CourseRewardWeights",
    "GYRO_STD",
    "RATE_GYRO_STD",
    "RECEIVERS",
    "TankerCourseKeepingEnv",
    "course_keeping_vector_env",
]

#: the velocity sources of the observation: the receiver's PV filter, the truth, the raw
#: positions differentiated (a two-point backward difference, the only causal form)
RECEIVERS = ("dgps-pv", "truth", "raw")

#: ``wind="auto"`` / ``current="auto"``: the task's default disturbances (class docstring)
AUTO = "auto"

#: the default current's speed (m/s) at full scale [printed, Artyszuk (2003) §1: "even 0.25
#: m/s current could be destructive"; Fig. 1 uses 0.25 m/s]; Froude-scaled by ``1/sqrt(scale)``
AUTO_CURRENT_SPEED = 0.25

#: the gyro compass's noise (rad) per sample [chosen: 0.1 deg, the gyros of the roll tasks]
GYRO_STD = math.radians(0.1)
#: the rate gyro's noise (rad/s) per sample [chosen: 0.05 deg/s, the rate gyros of the roll
#: tasks]
RATE_GYRO_STD = math.radians(0.05)

#: the observation's entries, in order
COURSE_OBSERVATION = ("heading_error", "yaw_rate", "rudder", "track_speed", "drift_angle")

_NONE = ("none", "off")


@dataclass(frozen=True)
class CourseRewardWeights:
    """Scales of the reward ``-(e_psi/psi0)^2 - rudder (delta/delta_max)^2``.

    Attributes:
        psi0: heading-error scale (rad).
        rudder: weight of the rudder term (-); ``delta_max`` is the rudder's limit (35 deg
            on the tankers).
    """

    psi0: float = param(math.radians(5.0), "rad", "chosen: 5 deg (the notes' seed-004 task)")
    rudder: float = param(0.1, "1", "chosen: full rudder costs a tenth of a 5 deg error")

    def __post_init__(self) -> None:
        if not (is_real(self.psi0) and math.isfinite(self.psi0) and self.psi0 > 0):
            raise ValueError(f"CourseRewardWeights.psi0 must be > 0 rad, got {self.psi0!r}")
        if not (is_real(self.rudder) and math.isfinite(self.rudder) and self.rudder >= 0):
            raise ValueError(f"CourseRewardWeights.rudder must be >= 0, got {self.rudder!r}")


def _finite(x: Any) -> bool:
    return is_real(x) and math.isfinite(x)


def _check(ok: bool, message: str, error: type[Exception] = ValueError) -> None:
    if not ok:
        raise error(message)


def _disturbance(value: Any, cls: Any, name: str) -> Any:
    if isinstance(value, str) and value in (AUTO, *_NONE):
        return None if value in _NONE else AUTO
    return cls.coerce(value, name=name)


class CourseKeepingTask(StepTask):
    """The course-keeping task over N >= 1 envs (:class:`CourseKeepingEnv` is its spec; the
    arguments are its own), stepped by :class:`CourseKeepingVectorEnv`."""

    reward_terms = ("heading", "rudder")

    def __init__(
        self,
        num_envs: int,
        *,
        vessel: Vessel | str | None = None,
        speed: float | None = None,
        heading: float = 0.0,
        wind: Any = AUTO,
        current: Any = AUTO,
        receiver: str = "dgps-pv",
        S_p: float = S_P_OPTIMAL,
        dgps_sigma: float = DGPS_SIGMA,
        antenna: tuple[float, float] = (0.0, 0.0),
        sensor_noise: bool = True,
        setpoint_period: float | None = 150.0,
        max_heading_change: float = math.radians(30.0),
        reward_weights: CourseRewardWeights | Mapping[str, float] | None = None,
        episode_duration: float = 600.0,
        timestep: float = 0.05,
        control_period: float = 1.0,
    ) -> None:
        _check(vessel is not None, "CourseKeepingEnv needs vessel=NAME (a vessel with a rudder: "
               "'kvlcc2-100m', 'kvlcc2-l7', 'naval-vessel', 'container-ship', 'van-der-klugt') or "
               "a package path", TypeError)  # fmt: skip
        self.base_vessel = v = load_vessel(vessel)  # type: ignore[arg-type]
        _check(bool(v.rudders), f"CourseKeepingEnv steers with a rudder; {v.name!r} has none "
               f"(actuators: {', '.join(a.label for a in v.actuators)})")  # fmt: skip
        speed = v.approach_speed if speed is None else speed
        _check(speed is not None, f"vessel {v.name!r} has no approach speed ([trials] "
               "approach_speed or [roll_control] design_speed in its vessel.toml): pass speed= "
               "(m/s)")  # fmt: skip
        ok = _finite(speed) and 0 < speed <= 30.0  # type: ignore[operator]
        _check(ok, f"speed must be in (0, 30] m/s, got {speed!r}")
        _check(_finite(heading), f"heading must be a finite angle (rad), got {heading!r}")
        _check(receiver in RECEIVERS,
               f"unknown receiver {receiver!r}; choose one of: {', '.join(RECEIVERS)}")  # fmt: skip
        _check(_finite(dgps_sigma) and dgps_sigma >= 0,
               f"dgps_sigma must be >= 0 m, got {dgps_sigma!r}")  # fmt: skip
        _check(setpoint_period is None or (_finite(setpoint_period) and setpoint_period > 0),
               f"setpoint_period must be > 0 s or None, got {setpoint_period!r}")  # fmt: skip
        _check(
            _finite(max_heading_change) and 0 <= max_heading_change <= math.pi,
            f"max_heading_change must be in [0, pi] rad, got {max_heading_change!r}",
        )
        if isinstance(reward_weights, Mapping):
            reward_weights = from_mapping(CourseRewardWeights, reward_weights,
                                          where="reward_weights")  # fmt: skip
        _check(isinstance(reward_weights, CourseRewardWeights | None), "reward_weights must be a "
               f"CourseRewardWeights or a mapping, got {reward_weights!r}", TypeError)  # fmt: skip
        _check(_finite(episode_duration) and episode_duration > 0,
               f"episode_duration must be > 0 s, got {episode_duration!r}")  # fmt: skip
        self.U, self.heading = float(speed), float(heading)  # type: ignore[arg-type]
        self.receiver, self.S_p, self.dgps_sigma = receiver, float(S_p), float(dgps_sigma)
        self.sensor_noise = bool(sensor_noise)
        self.setpoint_period = None if setpoint_period is None else float(setpoint_period)
        self.max_heading_change = float(max_heading_change)
        self.reward_weights = reward_weights or CourseRewardWeights()
        self.set_timing(timestep, control_period, episode_duration)
        self._wind_arg = _disturbance(wind, WindConfig, "wind")
        self._current_arg = _disturbance(current, CurrentConfig, "current")
        acts = v.actuators
        chans = acts.channel_names
        self._rudder_idx = [chans.index(name) for name in v.rudders]
        lim = {}
        shafts: list[int] = []  # MMG propellers held at the self-propulsion point
        self._props: list[tuple[int, Propeller]] = []  # fixed propellers in the speed loop
        for a, sl in zip(acts, acts.slices, strict=True):
            if isinstance(a, MMGPropulsion):
                lim[a.rudder_name] = a.max_angle
                shafts.append(sl.start)
            elif a.name in v.rudders:
                lim[a.name] = a.max_angle
            elif isinstance(a, Propeller) and a.alpha == 0 and not a.tunnel:
                self._props.append((sl.start, a))
        #: each rudder's angle limit (rad)
        self.max_angle = np.array([lim[name] for name in v.rudders])
        n_r = len(self._rudder_idx)
        lo = [-math.pi, -2.0, *(-self.max_angle), 0.0, -math.pi]
        hi = [math.pi, 2.0, *self.max_angle, 100.0, math.pi]
        obs_space = spaces.Box(
            np.array(lo, dtype=np.float32), np.array(hi, dtype=np.float32), dtype=np.float32
        )
        self.attach(num_envs, obs_space, spaces.Box(-1.0, 1.0, (n_r,), dtype=np.float32))
        n = num_envs
        self.rx = DGPSReceiver(self.S_p, n=n, sigma=self.dgps_sigma, dt=self.control_period,
                               antenna=antenna)  # fmt: skip
        self.antenna = (float(self.rx.antenna[0]), float(self.rx.antenna[1]))
        fixed_wind = None if self._wind_arg == AUTO else self._wind_arg
        self.physics = BatchedPhysics(v, n, wind=fixed_wind, timestep=self.timestep)
        servos = self.physics.servo_channels  # the rudders' columns of its rate_limited
        self._rudder_servo = [servos.index(j) for j in self._rudder_idx]
        # the actuators' start: shafts at the self-propulsion point, propellers at the thrust
        # that balances the resistance at U (split evenly), the rest at rest
        st0 = self.physics.actuators.initial_state()
        hull = self.physics.plant
        for j in shafts:
            st0[j] = float(hull.model.self_propulsion(self.U))
        self._thrust0 = self._m11 = 0.0
        if self._props:
            M = hull.mass_matrix()
            nu0 = np.zeros(M.shape[0])
            nu0[0] = self.U
            nd0 = np.asarray(hull.nu_dot(nu0, np.zeros(M.shape[0])))
            self._thrust0 = float(-(M @ nd0)[0]) / len(self._props)
            self._m11 = float(M[0, 0]) / len(self._props)
            for j, prop in self._props:
                st0[j] = float(np.clip(prop.inverse(self._thrust0), prop.lower, prop.upper))
        self._st0 = st0
        self._n_changes = (
            0 if self.setpoint_period is None
            else int(math.ceil(self.episode_duration / self.setpoint_period))
        )  # fmt: skip
        self.targets = np.full((n, max(self._n_changes, 1)), self.heading)
        self.wind_configs: list[WindConfig | None] = [None] * n
        self.current_configs: list[CurrentConfig | None] = [None] * n
        self._gyro = NormalStreams(n, 2)
        self._z_prev = np.zeros((n, 2))
        self._obs = np.zeros((n, 4 + n_r), dtype=np.float32)
        self._info: dict[str, Any] = {}
        self._sums = np.zeros((6, n))  # e^2, delta^2, |drift bias|, |speed bias|, their maxima
        self._counts = np.zeros((3, n), dtype=np.int64)  # steps, rate-limited, saturated

    # ---- episode ---------------------------------------------------------------------------
    def initialize_episode(self, rngs: list[Any], mask: NDArray[np.bool_]) -> None:
        n, v = self.num_envs, self.base_vessel
        nu0 = np.zeros((n, 3))
        nu0[:, 0] = self.U
        phys_rngs: list[Any] = [None] * n
        rx_rngs: list[Any] = [None] * n
        m = self.max_heading_change
        for i in np.nonzero(mask)[0].tolist():
            rng = rngs[i]
            # every draw in a fixed order, made even when the quantity is fixed: same seed,
            # same episode, and fixing one quantity leaves the others' draws unchanged
            seeds = child_seeds(rng, 3)  # gyros, receiver noise, physics (gusts)
            wind_dir = float(rng.uniform(0.0, 2.0 * math.pi))
            current_dir = float(rng.uniform(0.0, 2.0 * math.pi))
            changes = rng.uniform(-m, m, self._n_changes)
            if self._n_changes:
                self.targets[i] = np.r_[self.heading, self.heading + changes[1:]]
            wc = self._wind_arg
            if wc == AUTO:
                wc = WindConfig(speed=float(v.nominal_wind), direction_from=wind_dir)
            cc = self._current_arg
            if cc == AUTO:
                cc = CurrentConfig(speed=AUTO_CURRENT_SPEED / math.sqrt(v.scale),
                                   direction_to=current_dir)  # fmt: skip
            self.wind_configs[i], self.current_configs[i] = wc, cc
            self.physics.set_disturbances(i, wc, cc)
            self._gyro.seed(i, int(seeds[0]))
            rx_rngs[i] = int(seeds[1])
            phys_rngs[i] = np.random.default_rng(int(seeds[2]))
            if cc is not None:  # straight running at U through the water, with the current
                nu0[i, 0] += cc.speed * math.cos(cc.direction_to - self.heading)
                nu0[i, 1] = cc.speed * math.sin(cc.direction_to - self.heading)
        phys = self.physics
        phys.reset(eta=(0.0, 0.0, self.heading), nu=nu0, actuators=self._st0, mask=mask,
                   rngs=phys_rngs)  # fmt: skip
        phys.set_command(np.where(mask[:, None], self._st0, phys.command))
        self._sums[:, mask] = 0.0
        self._counts[:, mask] = 0
        self._sense(mask, rx_rngs)

    def _sense(self, mask: NDArray[np.bool_], rx_rngs: list[Any] | None = None) -> None:
        """The receiver's sample, the observation and the info of the envs of ``mask`` now
        (gyro draws for them); ``rx_rngs``: at a reset, the receivers' new generators."""
        phys = self.physics
        eta_full, nu_full = phys.eta_full, phys.nu_full
        eta, nu = (eta_full, nu_full) if phys.dofs == 3 else (eta_full[:, [0, 1, 3]],
                                                              nu_full[:, [0, 1, 3]])  # fmt: skip
        first = rx_rngs is not None
        if first:
            out = self.rx.reset(eta, nu, rngs=rx_rngs, mask=mask)
        else:
            out = self.rx.update(eta, mask=mask)
        psi, r = eta[:, 2], nu[:, 2]
        if self.sensor_noise:
            g = self._gyro.draw(mask)
            psi_g, r_g = psi + GYRO_STD * g[:, 0], r + RATE_GYRO_STD * g[:, 1]
        else:
            psi_g, r_g = psi, r
        if self.setpoint_period is None:
            psi_d = np.full(self.num_envs, self.heading)
        else:
            t = self.steps * self.control_period
            k = np.minimum(np.floor(t / self.setpoint_period + 1e-9).astype(np.int64),
                           self._n_changes - 1)  # fmt: skip
            psi_d = self.targets[np.arange(self.num_envs), k]
        _p, vg = antenna_motion(eta, nu, self.antenna)
        v_true, chi_true, beta_true = velocity_outputs(vg[:, 0], vg[:, 1], psi)
        if self.receiver == "dgps-pv":
            vn, ve = out.v_ns, out.v_ew
        elif self.receiver == "truth" or first:  # raw: no difference yet at the reset
            vn, ve = vg[:, 0], vg[:, 1]
        else:
            dz = (out.z - self._z_prev) / self.control_period
            vn, ve = dz[:, 0], dz[:, 1]
        self._z_prev = np.where(mask[:, None], out.z, self._z_prev)
        v_rx, chi_rx, beta_rx = velocity_outputs(vn, ve, psi_g)
        delta = phys.actuator_state[:, self._rudder_idx]
        obs = np.empty(self._obs.shape)
        obs[:, 0], obs[:, 1], obs[:, 2:-2] = wrap_angle(psi_g - psi_d), r_g, delta
        obs[:, -2], obs[:, -1] = v_rx, beta_rx
        obs32 = obs.astype(np.float32)
        self._obs = obs32 if mask.all() else np.where(mask[:, None], obs32, self._obs)
        self._info = {
            "time": phys.t.copy(),
            "eta": eta_full,
            "nu": nu_full,
            "heading": psi,
            "heading_setpoint": psi_d,
            "heading_error": wrap_angle(psi - psi_d),
            "speed": v_true,
            "course": chi_true,
            "drift_angle": beta_true,
            "receiver_speed": v_rx,
            "receiver_course": chi_rx,
            "receiver_drift_angle": beta_rx,
            "speed_bias": v_rx - v_true,
            "drift_angle_bias": wrap_angle(beta_rx - beta_true),
            "dgps_position": out.z.copy(),
            "rudder": delta,
        }

    def observation(self) -> NDArray[np.float32]:
        return self._obs.copy()

    def reset_info(self, mask: NDArray[np.bool_]) -> dict[str, Any]:
        return dict(self._info)

    def before_step(self, actions: NDArray[np.float64], active: NDArray[np.bool_]) -> None:
        phys = self.physics
        a = np.clip(actions, -1.0, 1.0)
        action_clipped = (np.abs(actions) > 1.0) & active[:, None]
        held = phys.command
        command = held.copy()  # the shafts keep their command
        command[:, self._rudder_idx] = a * self.max_angle
        if self._props:  # hold the speed through the water: resistance + a 20 s speed loop
            u_r = phys.nu[:, 0] - phys.nu_c[:, 0]
            thrust = self._thrust0 + self._m11 * (self.U - u_r) / 20.0
            for j, prop in self._props:
                command[:, j] = np.clip(prop.inverse(thrust), prop.lower, prop.upper)
        every = bool(active.all())
        clipped = phys.set_command(command if every else np.where(active[:, None], command, held))
        self._held = clipped, action_clipped  # (after_step reads them)

    def after_step(
        self, active: NDArray[np.bool_]
    ) -> tuple[dict[str, NDArray[np.float64]], NDArray[np.bool_], dict[str, Any]]:
        phys = self.physics
        clipped, action_clipped = self._held
        every = bool(active.all())
        self._sense(active)
        info = self._info
        delta = info["rudder"]
        w = self.reward_weights
        n_r = delta.shape[1]
        rudder, rudder2 = np.zeros(self.num_envs), np.zeros(self.num_envs)
        for j in range(n_r):  # elementwise per rudder: a row's sum does not depend on N
            rudder += (delta[:, j] / self.max_angle[j]) ** 2
            rudder2 += delta[:, j] ** 2
        terms = {"heading": -((info["heading_error"] / w.psi0) ** 2),
                 "rudder": -w.rudder * (rudder / n_r)}  # fmt: skip
        at_limit = np.abs(delta) >= self.max_angle * (1.0 - 1e-9)
        rate_limited = phys.rate_limited[:, self._rudder_servo] & active[:, None]
        saturated = (at_limit | clipped[:, self._rudder_idx] | action_clipped) & active[:, None]
        info.update({
            "rudder_command": phys.command[:, self._rudder_idx],
            "rate_limited": rate_limited,
            "saturated": saturated,
            "action_clipped": action_clipped,
        })  # fmt: skip
        # the episode's running sums
        s, c = self._sums, self._counts
        e, db = info["heading_error"], np.abs(info["drift_angle_bias"])
        add = np.stack([e**2, rudder2 / n_r, db, np.abs(info["speed_bias"])])
        top = np.maximum(s[4:6], np.stack([np.abs(e), db]))
        s[:4], s[4:6] = (s[:4] + add, top) if every else (np.where(active, s[:4] + add, s[:4]),
                                                         np.where(active, top, s[4:6]))  # fmt: skip
        c += np.stack([active, rate_limited.any(axis=1), saturated.any(axis=1)])
        return terms, np.zeros(self.num_envs, dtype=bool), dict(info)

    def episode_metrics(self, done: NDArray[np.bool_]) -> dict[str, Any]:
        """Heading, rudder and receiver-bias statistics of each env's episode so far."""
        s, c = self._sums, self._counts
        n = np.maximum(c[0], 1)
        return {
            "speed": np.full(self.num_envs, self.U),
            "receiver": np.full(self.num_envs, self.receiver),
            "steps": c[0].copy(),
            "heading_rms": np.sqrt(s[0] / n),
            "heading_max": s[4].copy(),
            "rudder_rms": np.sqrt(s[1] / n),
            "drift_angle_bias_mean_abs": s[2] / n,
            "drift_angle_bias_max_abs": s[5].copy(),
            "speed_bias_mean_abs": s[3] / n,
            "rate_limited_fraction": c[1] / n,
            "saturated_fraction": c[2] / n,
        }


class CourseKeepingVectorEnv(TaskEnv):
    """``num_envs`` course-keeping envs stepped together: :class:`CourseKeepingTask` in the
    env of every stepped task (:class:`CourseKeepingEnv`, its batch of one, is the spec).
    Env ``i`` reset with seed ``s + i`` is the single env reset with that seed, bit for bit.

    Args:
        num_envs: number of envs, >= 1.
        autoreset_mode: ``"next-step"`` or ``"same-step"``.
        **kwargs: the arguments of :class:`CourseKeepingEnv` (``vessel=`` required), but
            ``render_mode``.
    """

    task_class = CourseKeepingTask


class CourseKeepingEnv(TaskSingleEnv):
    r"""Hold and change the heading with the rudder, seeing the DGPS receiver's velocity.

    **Physics.** Any vessel with a rudder (:attr:`Vessel.rudders
    <shipgym.dynamics.vessel.Vessel.rudders>`) in open water, integrated by
    :class:`~shipgym.envs.batchphysics.BatchedPhysics` (the leapfrog step of
    :mod:`shipgym.sim.step`; physics step ``timestep`` 0.05 s; control
    period ``control_period`` 1 s, the receiver's sample time, a whole multiple of it). The
    episode starts in straight running at the speed ``U`` through the water (``speed``;
    default the vessel's approach speed, ``Vessel.approach_speed``) on the heading ``heading``,
    moving with the current. The speed is not the agent's: an MMG unit's propeller
    (:class:`~shipgym.dynamics.actuators.MMGPropulsion`) starts and is held at its
    self-propulsion point at ``U`` (commanded once, at reset); a fixed propeller pointing
    ahead holds ``U`` with the resistance's thrust and a 20 s speed loop (as the roll
    tasks); a linear 4-DOF hull keeps its speed itself. A 4-DOF vessel rolls, but the task
    and its observation are planar (the roll is ignored).

    **Disturbances** (seeded, drawn at reset in a fixed order). ``wind="auto"`` (default):
    the vessel's ``nominal_wind`` (10 m/s for the tanker) from a direction drawn uniformly
    per episode, with :class:`~shipgym.disturbances.WindConfig`'s default gusts;
    ``current="auto"`` (default): :data:`AUTO_CURRENT_SPEED` / ``sqrt(vessel.scale)`` (0.25
    m/s at full scale) going to a direction drawn per episode. Any form of
    :meth:`WindConfig.coerce <shipgym.disturbances.WindConfig.coerce>` /
    :meth:`CurrentConfig.coerce <shipgym.disturbances.CurrentConfig.coerce>` (``"10@45"``,
    ``"0.25@180"``, ...) fixes it for every episode; ``None`` or ``"none"``: none.

    **Set-points.** The desired heading ``psi_d`` is ``heading`` for the first
    ``setpoint_period`` (150 s) and then, every ``setpoint_period``, ``heading`` plus a change
    drawn uniformly from ``+-max_heading_change`` (30 deg) [chosen]; ``setpoint_period=None``
    holds ``heading``.

    **Action** (``Box(-1, 1, (n,))``, one per rudder): the commanded rudder angle over its
    limit ``max_angle`` (35 deg for the tanker; shipgym's sign: positive turns to PORT),
    through the rate-limited steering gear (2.32 deg/s for the tanker); values beyond +-1
    are clipped (``info["action_clipped"]``).

    **Observation** (``float32``, :data:`COURSE_OBSERVATION`):

    0. ``e_psi`` (rad): the gyro heading minus ``psi_d``, wrapped to ``[-pi, pi]``; gyro noise
       :data:`GYRO_STD` (0.1 deg);
    1. ``r`` (rad/s): the rate gyro's yaw rate, noise :data:`RATE_GYRO_STD` (0.05 deg/s);
    2. ``delta`` (rad): each rudder's angle;
    3. ``v_xy`` (m/s): the track speed from the velocity source ``receiver``;
    4. ``beta_A`` (rad): the drift angle ``psi_g - chi`` from that source and the gyro
       heading ``psi_g`` (Artyszuk 2003 eq. 7; positive when the bow points inside a
       starboard turn; course minus heading is ``-beta_A``).

    ``receiver="dgps-pv"`` (default): the receiver's PV filter (spectral amplitude ``S_p``,
    0.01 m^2/s^3; steady gain of eq. 5) on the antenna positions (``antenna``, m in the body
    frame, default midship) with ``dgps_sigma`` (2 m) noise per axis, started at the truth;
    ``"truth"``: the true ground velocity of the antenna; ``"raw"``: the noisy positions
    differentiated over one sample, ``(z_k - z_{k-1}) / dt`` (noise ``sqrt(2) sigma/dt`` per
    axis: 2.8 m/s; the reset's observation is the truth, as the filter starts there). All
    three use the same receiver and noise; ``sensor_noise=False`` removes the gyro noise
    (``dgps_sigma=0`` the position noise).

    **Reward**: ``heading + rudder``, ``heading = -(e_psi/psi0)^2`` (the true heading error),
    ``rudder = -w (delta/max_angle)^2`` (mean over the rudders; :class:`CourseRewardWeights`:
    5 deg, 0.1), the terms in ``info["reward_terms"]``. No termination; **truncation** after
    ``episode_duration`` (600 s) of simulated time.

    **Info**: ``time`` (s), ``eta``, ``nu`` (true, the vessel's full state), ``heading``,
    ``heading_setpoint``, ``heading_error`` (true, rad), the truth at the antenna (``speed``
    m/s, ``course``, ``drift_angle`` rad), the observed source's (``receiver_speed``,
    ``receiver_course``, ``receiver_drift_angle``), their errors ``speed_bias``,
    ``drift_angle_bias`` (observed minus true), the receiver's measured antenna position
    ``dgps_position`` (m), ``rudder``, ``rudder_command`` (rad), ``rate_limited`` (each
    rudder's servo still at its rate limit), ``saturated`` (at its limit or its command
    clipped), ``action_clipped``, ``reward_terms``; at the end ``episode_metrics`` (RMS of the
    heading error and the rudder, the mean and largest ``|drift_angle_bias|``, the mean
    ``|speed_bias|``, the fractions rate-limited and saturated).

    Example::

        import gymnasium as gym
        import shipgym
        from shipgym.controllers.coursepilot import course_autopilot

        env = gym.make("shipgym/CourseKeeping-v0")        # the 100 m tanker at 7 m/s
        obs, info = env.reset(seed=0)
        pilot = course_autopilot(env)                     # PID on the gyro
        done = False
        while not done:
            obs, reward, term, trunc, info = env.step(pilot(obs))
            done = term or trunc
        print(info["episode_metrics"]["heading_rms"])    # rad

    Args:
        vessel: a vessel with a rudder (name, path or :class:`Vessel`); required.
        speed: speed through the water (m/s); default ``Vessel.approach_speed``.
        heading: initial and base desired heading (rad).
        wind: ``"auto"``, any wind form, ``None`` / ``"none"``.
        current: ``"auto"``, any current form, ``None`` / ``"none"``.
        receiver: :data:`RECEIVERS`.
        S_p: the receiver filter's spectral amplitude (m^2/s^3).
        dgps_sigma: the position noise per axis (m), >= 0.
        antenna: the antenna's ``[x, y]`` (m, body frame, from the vessel's origin).
        sensor_noise: gyro and rate-gyro noise.
        setpoint_period: time between heading changes (s), or ``None``.
        max_heading_change: largest change from ``heading`` (rad), in ``[0, pi]``.
        reward_weights: :class:`CourseRewardWeights` or a mapping of its fields.
        episode_duration: simulated time per episode (s).
        timestep: physics step (s).
        control_period: control period and receiver sample time (s), a whole multiple of
            ``timestep``.
        render_mode: ``None`` or ``"rgb_array"``.

    The env is the batch of one of :class:`CourseKeepingVectorEnv` (the one code path;
    ``gymnasium.make_vec("shipgym/CourseKeeping-v0", num_envs=N)``): :attr:`batch`.
    """

    batched = CourseKeepingVectorEnv
    batch: CourseKeepingVectorEnv

    def __init__(self, vessel: Vessel | str | None = None, render_mode: str | None = None,
                 **kwargs: Any) -> None:  # fmt: skip
        super().__init__(render_mode=render_mode, vessel=vessel, **kwargs)

    @property
    def wind_config(self) -> WindConfig | None:
        """This episode's wind (``None`` before the first reset or without wind)."""
        return self.batch.wind_configs[0]

    @property
    def current_config(self) -> CurrentConfig | None:
        """This episode's current (``None`` before the first reset or without current)."""
        return self.batch.current_configs[0]


class TankerCourseKeepingEnv(CourseKeepingEnv):
    """``shipgym/CourseKeeping-v0``: :class:`CourseKeepingEnv` on the seed's tanker.

    The KVLCC2 MMG hull scaled to 100 m (``vessel="kvlcc2-100m"``, Artyszuk (2003)'s ca.
    100 m chemical tanker at 7 m/s) unless ``vessel=`` names another; every argument of
    :class:`CourseKeepingEnv` can be given.
    """

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("vessel", "kvlcc2-100m")
        super().__init__(**kwargs)


def course_keeping_vector_env(num_envs: int, **kwargs: Any) -> CourseKeepingVectorEnv:
    """``shipgym/CourseKeeping-v0``'s vector entry point (the tanker unless ``vessel=``)."""
    kwargs.setdefault("vessel", "kvlcc2-100m")
    return CourseKeepingVectorEnv(num_envs, **kwargs)
