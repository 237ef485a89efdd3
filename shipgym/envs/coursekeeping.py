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

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from shipgym._config import from_mapping, is_real, param
from shipgym.disturbances import CurrentConfig, WindConfig
from shipgym.dynamics import wrap_angle
from shipgym.dynamics.actuators import MMGPropulsion, Propeller
from shipgym.dynamics.vessel import Vessel, load_vessel
from shipgym.observers.dgps import (
    DGPS_SIGMA,
    S_P_OPTIMAL,
    DGPSOutput,
    DGPSReceiver,
    antenna_motion,
    velocity_outputs,
)

from .base import (
    TopCameraRender,
    _check_render_mode,
    _check_timing,
    _whole_multiple,
    rudder_action,
)
from .physics import VesselPhysics

__all__ = [
    "AUTO",
    "AUTO_CURRENT_SPEED",
    "COURSE_OBSERVATION",
    "CourseKeepingEnv",
    "CourseRewardWeights",
    "GYRO_STD",
    "RATE_GYRO_STD",
    "RECEIVERS",
    "TankerCourseKeepingEnv",
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


class CourseKeepingEnv(TopCameraRender, gym.Env[NDArray[np.float32], NDArray[np.float32]]):
    r"""Hold and change the heading with the rudder, seeing the DGPS receiver's velocity.

    **Physics.** Any vessel with a rudder (:attr:`Vessel.rudders
    <shipgym.dynamics.vessel.Vessel.rudders>`) in MuJoCo with the exact force injection of
    :class:`~shipgym.envs.physics.VesselPhysics` (physics step ``timestep`` 0.05 s; control
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
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 1}

    def __init__(
        self,
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
        render_mode: str | None = None,
    ) -> None:
        if vessel is None:
            raise TypeError(
                "CourseKeepingEnv needs vessel=NAME (a vessel with a rudder: 'kvlcc2-100m', "
                "'kvlcc2-l7', 'naval-vessel', 'container-ship', 'van-der-klugt') or a package path"
            )
        self.base_vessel = load_vessel(vessel)
        v = self.base_vessel
        if not v.rudders:
            raise ValueError(
                f"CourseKeepingEnv steers with a rudder; {v.name!r} has none (actuators: "
                f"{', '.join(a.label for a in v.actuators)})"
            )
        if speed is None:
            speed = v.approach_speed
            if speed is None:
                raise ValueError(
                    f"vessel {v.name!r} has no approach speed ([trials] approach_speed or "
                    "[roll_control] design_speed in its vessel.toml): pass speed= (m/s)"
                )
        if not (_finite(speed) and 0 < speed <= 30.0):
            raise ValueError(f"speed must be in (0, 30] m/s, got {speed!r}")
        self.U = float(speed)
        if not _finite(heading):
            raise ValueError(f"heading must be a finite angle (rad), got {heading!r}")
        self.heading = float(heading)
        if receiver not in RECEIVERS:
            raise ValueError(
                f"unknown receiver {receiver!r}; choose one of: {', '.join(RECEIVERS)}"
            )
        self.receiver = receiver
        if not (_finite(S_p) and S_p > 0):
            raise ValueError(f"S_p must be > 0 m^2/s^3, got {S_p!r}")
        self.S_p = float(S_p)
        if not (_finite(dgps_sigma) and dgps_sigma >= 0):
            raise ValueError(f"dgps_sigma must be >= 0 m, got {dgps_sigma!r}")
        self.dgps_sigma = float(dgps_sigma)
        ant = np.asarray(antenna, dtype=float).reshape(-1)
        if ant.shape != (2,) or not np.all(np.isfinite(ant)):
            raise ValueError(f"antenna must be a finite [x, y] (m), got {antenna!r}")
        self.antenna = (float(ant[0]), float(ant[1]))
        self.sensor_noise = bool(sensor_noise)
        if setpoint_period is not None and not (_finite(setpoint_period) and setpoint_period > 0):
            raise ValueError(f"setpoint_period must be > 0 s or None, got {setpoint_period!r}")
        self.setpoint_period = None if setpoint_period is None else float(setpoint_period)
        if not (_finite(max_heading_change) and 0 <= max_heading_change <= math.pi):
            raise ValueError(
                f"max_heading_change must be in [0, pi] rad, got {max_heading_change!r}"
            )
        self.max_heading_change = float(max_heading_change)
        if reward_weights is None:
            reward_weights = CourseRewardWeights()
        elif isinstance(reward_weights, Mapping):
            reward_weights = from_mapping(CourseRewardWeights, reward_weights,
                                          where="reward_weights")  # fmt: skip
        elif not isinstance(reward_weights, CourseRewardWeights):
            raise TypeError(f"reward_weights must be a CourseRewardWeights or a mapping, got "
                            f"{reward_weights!r}")  # fmt: skip
        self.reward_weights = reward_weights
        if not (_finite(episode_duration) and episode_duration > 0):
            raise ValueError(f"episode_duration must be > 0 s, got {episode_duration!r}")
        self.episode_duration = float(episode_duration)
        _check_timing(timestep, control_period)
        self.n_substeps = _whole_multiple(control_period, timestep)
        self.timestep = float(timestep)
        self.control_period = float(control_period)
        _check_render_mode(render_mode, self.metadata)
        self.render_mode = render_mode
        self._wind_arg = self._parse_disturbance(wind, WindConfig, "wind")
        self._current_arg = self._parse_disturbance(current, CurrentConfig, "current")
        self.wind_config: WindConfig | None = None
        self.current_config: CurrentConfig | None = None

        acts = v.actuators
        chans = acts.channel_names
        self._rudder_idx = [chans.index(n) for n in v.rudders]
        lim = {}
        rate = {}
        self._shafts: list[int] = []  # MMG propellers held at the self-propulsion point
        self._props: list[tuple[int, Propeller]] = []  # fixed propellers in the speed loop
        for a, sl in zip(acts, acts.slices, strict=True):
            if isinstance(a, MMGPropulsion):
                lim[a.rudder_name], rate[a.rudder_name] = a.max_angle, a.max_rate
                self._shafts.append(sl.start)
            elif a.name in v.rudders:
                lim[a.name], rate[a.name] = a.max_angle, a.max_rate
            elif isinstance(a, Propeller) and a.alpha == 0 and not a.tunnel:
                self._props.append((sl.start, a))
        # the rudders among the servo channels (VesselPhysics.rate_limited's order)
        servos = [j for j, c in enumerate(acts.channels) if c.dynamics == "servo"]
        self._servo_of_rudder = [servos.index(j) for j in self._rudder_idx]
        #: each rudder's angle limit (rad)
        self.max_angle = np.array([lim[n] for n in v.rudders])
        self._max_rate = np.array([rate[n] for n in v.rudders])
        n = len(self._rudder_idx)
        self.action_space = spaces.Box(-1.0, 1.0, (n,), dtype=np.float32)
        lo = [-math.pi, -2.0, *(-self.max_angle), 0.0, -math.pi]
        hi = [math.pi, 2.0, *self.max_angle, 100.0, math.pi]
        self.observation_space = spaces.Box(
            np.array(lo, dtype=np.float32), np.array(hi, dtype=np.float32), dtype=np.float32
        )
        self.physics: VesselPhysics | None = None
        self._renderer: Any = None
        self._receiver: DGPSReceiver | None = None

    # ---- set-up ----------------------------------------------------------------------------
    @staticmethod
    def _parse_disturbance(value: Any, cls: Any, name: str) -> Any:
        if isinstance(value, str) and value in (AUTO, *_NONE):
            return None if value in _NONE else AUTO
        return cls.coerce(value, name=name)

    def _disturbances(self, wind_dir: float, current_dir: float) -> None:
        v = self.base_vessel
        if self._wind_arg == AUTO:
            self.wind_config = WindConfig(speed=float(v.nominal_wind), direction_from=wind_dir)
        else:
            self.wind_config = self._wind_arg
        if self._current_arg == AUTO:
            s = AUTO_CURRENT_SPEED / math.sqrt(v.scale)
            self.current_config = CurrentConfig(speed=s, direction_to=current_dir)
        else:
            self.current_config = self._current_arg

    def _make_physics(self) -> VesselPhysics:
        if self.physics is None:
            self.physics = VesselPhysics(self.base_vessel, world="open-water",
                                         timestep=self.timestep)  # fmt: skip
        self.physics.set_wind(self.wind_config)
        self.physics.set_current(self.current_config)
        return self.physics

    def _setpoint(self, t: float) -> float:
        if self.setpoint_period is None:
            return self.heading
        k = min(int(math.floor(t / self.setpoint_period + 1e-9)), len(self._targets) - 1)
        return float(self._targets[k])

    # ---- episode ---------------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        rng = self.np_random
        # every draw in a fixed order, made even when the quantity is fixed: same seed, same
        # episode, and fixing one quantity leaves the others' draws unchanged
        seeds = rng.integers(2**63, size=3)  # gyros, receiver noise, physics (gusts)
        wind_dir = float(rng.uniform(0.0, 2.0 * math.pi))
        current_dir = float(rng.uniform(0.0, 2.0 * math.pi))
        n_changes = (
            0 if self.setpoint_period is None
            else int(math.ceil(self.episode_duration / self.setpoint_period))
        )  # fmt: skip
        m = self.max_heading_change
        changes = rng.uniform(-m, m, n_changes)
        self._targets = np.r_[self.heading, self.heading + changes[1:]] if n_changes else None
        self._disturbances(wind_dir, current_dir)
        phys = self._make_physics()
        self._noise_rng = np.random.default_rng(int(seeds[0]))
        U, psi0 = self.U, self.heading
        # straight running at U through the water, carried by the (mean) current
        cc = self.current_config
        uc = vc = 0.0
        if cc is not None:
            uc = cc.speed * math.cos(cc.direction_to - psi0)
            vc = cc.speed * math.sin(cc.direction_to - psi0)
        st0 = phys.initial_actuator_state()
        hull = phys.plant
        for j in self._shafts:
            st0[j] = float(hull.model.self_propulsion(U))
        self._thrust0 = 0.0
        if self._props:  # the thrust that balances the resistance at U, split evenly
            M = hull.mass_matrix()
            nu0 = np.zeros(M.shape[0])
            nu0[0] = U
            nd0 = np.asarray(hull.nu_dot(nu0, np.zeros(M.shape[0])))
            self._thrust0 = float(-(M @ nd0)[0]) / len(self._props)
            self._m11 = float(M[0, 0]) / len(self._props)
            for j, prop in self._props:
                st0[j] = float(np.clip(prop.inverse(self._thrust0), prop.lower, prop.upper))
        phys.reset(eta=(0.0, 0.0, psi0), nu=(U + uc, vc, 0.0), actuators=st0,
                   rng=np.random.default_rng(int(seeds[2])))  # fmt: skip
        phys.set_command(st0)
        self._receiver = DGPSReceiver(self.S_p, sigma=self.dgps_sigma, dt=self.control_period,
                                      antenna=self.antenna, rng=int(seeds[1]))  # fmt: skip
        out = self._receiver.reset(phys.eta, phys.nu)
        self._z_prev = out.z.copy()
        self._steps = 0
        self._metrics = _CourseMetrics()
        obs, info = self._observe(out, first=True)
        return obs, info

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        phys = self.physics
        if phys is None or self._receiver is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        a, action_clipped = rudder_action(action, self.action_space.shape, self.base_vessel.rudders)
        command = phys.command  # the shafts keep their command
        command[self._rudder_idx] = a * self.max_angle
        if self._props:  # hold the speed through the water: resistance + a 20 s speed loop
            u_r = float(phys.nu[0]) - float(phys.nu_c[0])
            for j, prop in self._props:
                thrust = self._thrust0 + self._m11 * (self.U - u_r) / 20.0
                command[j] = float(np.clip(prop.inverse(thrust), prop.lower, prop.upper))
        clipped = phys.set_command(command)
        phys.step(self.n_substeps)
        self._steps += 1
        out = self._receiver.update(phys.eta)
        obs, info = self._observe(out)
        delta = info["rudder"]
        w = self.reward_weights
        terms = {
            "heading": -((info["heading_error"] / w.psi0) ** 2),
            "rudder": -w.rudder * float(np.mean((delta / self.max_angle) ** 2)),
        }
        reward = float(sum(terms.values()))
        truncated = self._steps * self.control_period >= self.episode_duration - 1e-9
        at_limit = np.abs(delta) >= self.max_angle * (1.0 - 1e-9)
        rl = phys.rate_limited
        info.update({
            "rudder_command": phys.command[self._rudder_idx],
            "rate_limited": np.array([bool(rl[k]) for k in self._servo_of_rudder]),
            "saturated": at_limit | clipped[self._rudder_idx] | action_clipped,
            "action_clipped": action_clipped,
            "reward_terms": terms,
        })  # fmt: skip
        self._metrics.add(info)
        if truncated:
            info["episode_metrics"] = self.episode_metrics()
        return obs, reward, False, bool(truncated), info

    def _observe(
        self, out: DGPSOutput, first: bool = False
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        phys = self.physics
        assert phys is not None
        eta, nu = phys.eta, phys.nu
        psi, r = float(eta[2]), float(nu[2])
        if self.sensor_noise:
            g = self._noise_rng.standard_normal(2)
            psi_g, r_g = psi + GYRO_STD * float(g[0]), r + RATE_GYRO_STD * float(g[1])
        else:
            psi_g, r_g = psi, r
        t = self._steps * self.control_period
        psi_d = self._setpoint(t)
        _p, vg = antenna_motion(eta, nu, self.antenna)
        v_true, chi_true, beta_true = (float(x) for x in velocity_outputs(vg[0], vg[1], psi))
        if self.receiver == "dgps-pv":
            vn, ve = float(out.v_ns), float(out.v_ew)
        elif self.receiver == "truth":
            vn, ve = float(vg[0]), float(vg[1])
        elif first:  # raw: no difference yet; the receiver starts at the truth
            vn, ve = float(vg[0]), float(vg[1])
        else:
            dz = (out.z - self._z_prev) / self.control_period
            vn, ve = float(dz[0]), float(dz[1])
        self._z_prev = out.z.copy()
        v_rx, chi_rx, beta_rx = (float(x) for x in velocity_outputs(vn, ve, psi_g))
        delta = phys.actuator_state[self._rudder_idx]
        obs = np.array(
            [float(wrap_angle(psi_g - psi_d)), r_g, *delta.tolist(), v_rx, beta_rx],
            dtype=np.float32,
        )
        info: dict[str, Any] = {
            "time": phys.time,
            "eta": phys.eta_full,
            "nu": phys.nu_full,
            "heading": psi,
            "heading_setpoint": psi_d,
            "heading_error": float(wrap_angle(psi - psi_d)),
            "speed": v_true,
            "course": chi_true,
            "drift_angle": beta_true,
            "receiver_speed": v_rx,
            "receiver_course": chi_rx,
            "receiver_drift_angle": beta_rx,
            "speed_bias": v_rx - v_true,
            "drift_angle_bias": float(wrap_angle(beta_rx - beta_true)),
            "dgps_position": np.asarray(out.z, dtype=float).copy(),
            "rudder": delta.copy(),
        }
        return obs, info

    def episode_metrics(self) -> dict[str, Any]:
        """Heading, rudder and receiver-bias statistics of the episode so far."""
        return self._metrics.summary(self)


class _CourseMetrics:
    """Running sums of an episode: RMS heading error and rudder, the receiver's bias."""

    def __init__(self) -> None:
        self.n = 0
        self.sums = {"heading_error": 0.0, "rudder": 0.0, "drift_bias": 0.0, "speed_bias": 0.0}
        self.max_heading = 0.0
        self.max_drift_bias = 0.0
        self.rate_limited = 0
        self.saturated = 0

    def add(self, info: Mapping[str, Any]) -> None:
        self.n += 1
        s = self.sums
        s["heading_error"] += info["heading_error"] ** 2
        d = info["rudder"].tolist()
        s["rudder"] += sum(x * x for x in d) / len(d)
        s["drift_bias"] += abs(info["drift_angle_bias"])
        s["speed_bias"] += abs(info["speed_bias"])
        self.max_heading = max(self.max_heading, abs(info["heading_error"]))
        self.max_drift_bias = max(self.max_drift_bias, abs(info["drift_angle_bias"]))
        self.rate_limited += any(info["rate_limited"].tolist())
        self.saturated += any(info["saturated"].tolist())

    def summary(self, env: CourseKeepingEnv) -> dict[str, Any]:
        n = max(self.n, 1)
        return {
            "speed": env.U,
            "receiver": env.receiver,
            "steps": self.n,
            "heading_rms": math.sqrt(self.sums["heading_error"] / n),
            "heading_max": self.max_heading,
            "rudder_rms": math.sqrt(self.sums["rudder"] / n),
            "drift_angle_bias_mean_abs": self.sums["drift_bias"] / n,
            "drift_angle_bias_max_abs": self.max_drift_bias,
            "speed_bias_mean_abs": self.sums["speed_bias"] / n,
            "rate_limited_fraction": self.rate_limited / n,
            "saturated_fraction": self.saturated / n,
        }


class TankerCourseKeepingEnv(CourseKeepingEnv):
    """``shipgym/CourseKeeping-v0``: :class:`CourseKeepingEnv` on the seed's tanker.

    The KVLCC2 MMG hull scaled to 100 m (``vessel="kvlcc2-100m"``, Artyszuk (2003)'s ca.
    100 m chemical tanker at 7 m/s) unless ``vessel=`` names another; every argument of
    :class:`CourseKeepingEnv` can be given.
    """

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("vessel", "kvlcc2-100m")
        super().__init__(**kwargs)
