r"""Rudder-roll stabilisation: hold a heading at speed while the rudder damps the roll.

The task of Radhakrishnan (n.d.) (after Van der Klugt 1987): a ship at 8-15 m/s rolling in
waves, whose rudder is moved at high frequency to damp the roll without disturbing the
heading. Generic over any 4-DOF vessel with a rudder (``vessel=``): the registered
``shipgym/RudderRollStabilisation-v0`` is the seed's Van der Klugt model (``van-der-klugt``)
in the seed's white-noise waves, ``shipgym/NavalRollDamping-v0`` the nonlinear naval vessel
of Blanke & Christensen (1993) (``naval-vessel``) in a beam sea. Sources in full:
``docs/references.md``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from shipgym._config import from_mapping, is_real, param
from shipgym.disturbances.rollwaves import RollWaveConfig, RollWaves
from shipgym.dynamics import wrap_angle
from shipgym.dynamics.actuators import Propeller, Rudder
from shipgym.dynamics.linearise import roll_model_of
from shipgym.dynamics.vanderklugt import KDP_LAWS, VAN_DER_KLUGT, seed_vessel
from shipgym.dynamics.vessel import Vessel, load_vessel
from shipgym.observers.sway import R_SWAY, SwayVelocityKF, calm_water_intensities

from .base import (
    TopCameraRender,
    _check_render_mode,
    _check_timing,
    _whole_multiple,
    rudder_action,
)
from .physics import VesselPhysics

__all__ = [
    "AUTO_WAVES",
    "BEAM_SEA",
    "NavalRollEnv",
    "ROLL_SENSOR_STD",
    "RollRewardWeights",
    "RudderRollEnv",
    "SEED_WAVES",
    "SeedRollEnv",
    "seed_wave_intensities",
]

#: the seed's white-noise waves (:func:`seed_wave_intensities`)
SEED_WAVES = "seed"

#: standard deviations of the measured ``[r, psi, p, phi]`` (rad/s, rad, rad/s, rad): the
#: rate gyros' 0.05 deg/s and the gyros' 0.1 deg [chosen, the sway filter's R]
ROLL_SENSOR_STD: tuple[float, float, float, float] = tuple(math.sqrt(x) for x in R_SWAY)  # type: ignore[assignment]

#: the observation's entries, in order (the last only with ``sway_estimate=True``)
OBSERVATION = ("r", "heading_error", "p", "phi", "rudder", "speed", "v_hat")


#: the default sea of a hull with a displacement: [chosen] a slight beam sea (sea state 3),
#: Hs 0.5 m, Tp 7 s (JONSWAP, gamma 3.3), whose roll-moment spectrum reaches the naval
#: vessel's roll mode (1.1 rad/s) and which its 10 deg/s rudder can still work against (the
#: rudder-rate demand grows with Hs: at Hs 1.5 m the same design is rate-limited most of the time)
BEAM_SEA = RollWaveConfig(Hs=0.5, Tp=7.0, chi=math.pi / 2)

#: ``waves="auto"``: the seed's waves for the seed model, :data:`BEAM_SEA` otherwise
AUTO_WAVES = "auto"


@dataclass(frozen=True)
class RollRewardWeights:
    """Scales of the reward ``-(phi/phi0)^2 - (e_psi/psi0)^2 - rate (delta_dot/delta_dot_max)^2``.

    Attributes:
        phi0: roll scale (rad).
        psi0: heading-error scale (rad).
        rate: weight of the rudder-rate term (-).
    """

    phi0: float = param(math.radians(1.0), "rad", "chosen: 1 deg (the notes' RRS task)")
    psi0: float = param(math.radians(2.0), "rad", "chosen: 2 deg (the notes' RRS task)")
    rate: float = param(0.1, "1", "chosen: the rudder rate costs a tenth of the roll")

    def __post_init__(self) -> None:
        for k in ("phi0", "psi0"):
            v = getattr(self, k)
            if not (is_real(v) and math.isfinite(v) and v > 0):
                raise ValueError(f"RollRewardWeights.{k} must be > 0 rad, got {v!r}")
        if not (is_real(self.rate) and math.isfinite(self.rate) and self.rate >= 0):
            raise ValueError(f"RollRewardWeights.rate must be >= 0, got {self.rate!r}")


def seed_wave_intensities(U: float) -> tuple[float, float]:
    """The seed's wave disturbance as white-noise moment intensities ``(q_K, q_N)``.

    Radhakrishnan (n.d.) eqs. 6-7 put ``w_phi`` through ``w_n^2`` into the roll acceleration
    and ``w_psi`` through ``1/T_r`` into the yaw acceleration; with the intensities
    ``q_phi = (0.7 deg)^2 rad^2 s``, ``q_psi = (0.35 deg)^2 rad^2/s`` [chosen reading of the
    printed 0.7 and 0.35] the moments per unit inertia of the ``van-der-klugt`` hull are white
    with ``q_K = w_n^4 q_phi`` and ``q_N = q_psi / T_r^2``, ``T_r = 13/U``.

    Args:
        U: forward speed (m/s), > 0.

    Returns:
        ``(q_K, q_N)`` ((N m)^2 s per unit inertia).
    """
    p = VAN_DER_KLUGT.at(U)
    return p.omega_n**4 * p.q_phi, p.q_psi / p.T_r**2


def _speed_range(speed: Any) -> tuple[float, float]:
    if is_real(speed):
        lo = hi = float(speed)
    else:
        try:
            lo, hi = (float(x) for x in speed)
        except (TypeError, ValueError):
            raise ValueError(
                f"speed must be a forward speed (m/s) or a range (lo, hi), got {speed!r}"
            ) from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi <= 30.0):
        raise ValueError(f"speed must lie in (0, 30] m/s with lo <= hi, got {speed!r}")
    return lo, hi


class RudderRollEnv(TopCameraRender, gym.Env[NDArray[np.float32], NDArray[np.float32]]):
    r"""Hold a heading at speed with the rudder while damping the roll in waves.

    **Physics.** A 4-DOF vessel (surge, sway, roll, yaw) with a rudder (:class:`~shipgym.
    dynamics.actuators.Rudder`: commanded angle through a rate-limited servo, lift from the
    flow speed, stall), in MuJoCo with the exact force injection of
    :class:`~shipgym.envs.physics.VesselPhysics` (physics step ``timestep``, 0.01 s; the
    control period ``control_period``, 0.1 s, a whole multiple of it). The episode starts in
    straight running at the speed ``U`` drawn uniformly from ``speed`` (m/s), on the heading
    ``heading``. A propeller, if the vessel has one, is held by the task at the thrust that
    balances the hull's resistance at ``U`` plus a proportional speed loop; the agent steers.

    **Waves.** ``waves="auto"`` (default): the beam sea :data:`BEAM_SEA` for a hull with a
    displacement (``nabla``), ``"seed"`` for the per-unit ``van-der-klugt`` model, calm water
    otherwise. ``waves="seed"``: the white-noise roll and yaw disturbances ``w_phi``,
    ``w_psi`` of Radhakrishnan (n.d.) eqs. 6-7 (:func:`seed_wave_intensities`; for the
    ``van-der-klugt`` hull, whose moments are per unit inertia), one sample per control
    period; a :class:`~shipgym.disturbances.rollwaves.RollWaveConfig` (or its mapping): a
    long-crested sea's Froude-Krylov roll and yaw moments (for a hull with a displacement,
    e.g. ``naval-vessel``), evaluated at the middle of each control period and held over it;
    ``None``: calm water. ``rudder_test=True`` adds the seed's sinusoidal rudder
    (``rudder_test_amplitude`` 10 deg at ``rudder_test_frequency`` 0.43 rad/s) to the command.

    **Action** (``Box(-1, 1, (n,))``, one per rudder of the vessel): the commanded rudder
    angle as a fraction of its limit ``max_angle`` (35 deg for the seed model and the naval
    vessel); values beyond +-1 are clipped (``info["action_clipped"]``).

    **Observation** (``float32``): ``[r (rad/s), e_psi (rad, wrapped heading error psi -
    psi_d), p (rad/s), phi (rad), delta (rad, each rudder's angle), U (m/s, the episode's
    speed)]``, with gyro noise of :data:`ROLL_SENSOR_STD` on the first four (seeded;
    ``sensor_noise=False`` for exact values) and, with ``sway_estimate=True``, the estimated
    sway velocity ``v_hat`` (m/s) of the seed's Kalman filter (:class:`~shipgym.observers.
    sway.SwayVelocityKF`, Radhakrishnan (n.d.) eqs. 1-4) on the vessel's linear model at
    ``U`` (:func:`~shipgym.dynamics.linearise.roll_model_of`).

    **Reward**: ``roll + heading + rudder_rate`` with ``roll = -(phi/phi0)^2``, ``heading =
    -(e_psi/psi0)^2``, ``rudder_rate = -rate (delta_dot/delta_dot_max)^2`` (the true states;
    ``delta_dot`` the mean rate over the control period; :class:`RollRewardWeights`: 1 deg,
    2 deg, 0.1), the terms in ``info["reward_terms"]``.

    **Termination**: ``|phi| > max_roll`` (30 deg). **Truncation**: ``episode_duration``
    (600 s) of simulated time.

    **Info**: ``time`` (s), ``eta`` ``[x, y, phi, psi]`` (m, m, rad, rad) and ``nu`` ``[u, v,
    p, r]`` (m/s, rad/s) (true), ``speed`` (u, m/s), ``v`` (m/s), ``roll``, ``heading_error``
    (rad), ``rudder``, ``rudder_command`` (rad), ``rudder_rate`` (rad/s), ``saturated`` (each
    rudder at its angle limit or its command clipped), ``rate_limited`` (its servo still at
    the rate limit at the end of the step: it has not reached its command), ``stalled``,
    ``action_clipped``, ``wave_moment`` ``[K, N]`` (N m), ``reward_terms``, and ``v_hat``,
    ``trace_P`` with the filter; at the end ``episode_metrics`` (RMS of roll, heading error,
    rudder and rudder rate, the fractions rate-limited and saturated, the v-hat RMSE).
    :meth:`filter_intensities` gives the wave-noise intensities a pilot's filter should use.

    Args:
        vessel: a 4-DOF vessel with a rudder (name, path or :class:`Vessel`); required.
        speed: forward speed (m/s) or a range ``(lo, hi)`` drawn per episode.
        heading: desired (and initial) heading (rad).
        waves: ``"auto"``, ``"seed"``, a :class:`RollWaveConfig` / mapping, or ``None``.
        kdp_law: ``"U2"`` or ``"printed"``: the seed's direct rudder-roll law (``van-der-klugt``
            only; :func:`~shipgym.dynamics.vanderklugt.seed_vessel`).
        rudder_test: add the seed's sinusoidal rudder to the command.
        rudder_test_amplitude: its amplitude (rad).
        rudder_test_frequency: its frequency (rad/s).
        sensor_noise: gyro noise on the measurements.
        sway_estimate: append the filter's ``v_hat`` to the observation.
        reward_weights: :class:`RollRewardWeights` or a mapping of its fields.
        episode_duration: simulated time per episode (s).
        timestep: physics step (s).
        control_period: control period (s), a whole multiple of ``timestep``.
        max_roll: roll at which the episode terminates (rad).
        render_mode: ``None`` or ``"rgb_array"``.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(
        self,
        vessel: Vessel | str | None = None,
        speed: float | tuple[float, float] = (8.0, 15.0),
        heading: float = 0.0,
        waves: str | RollWaveConfig | Mapping[str, Any] | None = "auto",
        kdp_law: str = "U2",
        rudder_test: bool = False,
        rudder_test_amplitude: float = math.radians(10.0),
        rudder_test_frequency: float = 0.43,
        sensor_noise: bool = True,
        sway_estimate: bool = False,
        reward_weights: RollRewardWeights | Mapping[str, float] | None = None,
        episode_duration: float = 600.0,
        timestep: float = 0.01,
        control_period: float = 0.1,
        max_roll: float = math.radians(30.0),
        render_mode: str | None = None,
    ) -> None:
        if vessel is None:
            raise TypeError(
                "RudderRollEnv needs vessel=NAME (a 4-DOF vessel with a rudder: "
                "'van-der-klugt', 'naval-vessel') or a package path"
            )
        self.base_vessel = load_vessel(vessel)
        v = self.base_vessel
        if v.dofs != 4 or not v.rudders:
            raise ValueError(
                f"RudderRollEnv needs a 4-DOF vessel with a rudder; {v.name!r} has {v.dofs} DOF "
                f"and the actuators {', '.join(a.label for a in v.actuators)}"
            )
        if kdp_law not in KDP_LAWS:
            raise ValueError(f"kdp_law must be one of {KDP_LAWS}, got {kdp_law!r}")
        if kdp_law != "U2" and v.name != "van-der-klugt":
            raise ValueError("kdp_law='printed' is the seed's law: it needs vessel='van-der-klugt'")
        self.kdp_law = kdp_law
        self.speed_range = _speed_range(speed)
        if not (is_real(heading) and math.isfinite(heading)):
            raise ValueError(f"heading must be a finite angle (rad), got {heading!r}")
        self.heading = float(heading)
        self.waves = self._parse_waves(waves)
        self.rudder_test = bool(rudder_test)
        for nm, val in (("rudder_test_amplitude", rudder_test_amplitude),
                        ("rudder_test_frequency", rudder_test_frequency)):  # fmt: skip
            if not (is_real(val) and math.isfinite(val) and val >= 0):
                raise ValueError(f"{nm} must be a finite number >= 0, got {val!r}")
        self.rudder_test_amplitude = float(rudder_test_amplitude)
        self.rudder_test_frequency = float(rudder_test_frequency)
        self.sensor_noise = bool(sensor_noise)
        self.sway_estimate = bool(sway_estimate)
        if reward_weights is None:
            reward_weights = RollRewardWeights()
        elif isinstance(reward_weights, Mapping):
            reward_weights = from_mapping(RollRewardWeights, reward_weights, where="reward_weights")
        elif not isinstance(reward_weights, RollRewardWeights):
            raise TypeError(f"reward_weights must be a RollRewardWeights or a mapping, got "
                            f"{reward_weights!r}")  # fmt: skip
        self.reward_weights = reward_weights
        if not (is_real(episode_duration) and 0 < episode_duration < math.inf):
            raise ValueError(f"episode_duration must be > 0 s, got {episode_duration!r}")
        self.episode_duration = float(episode_duration)
        if not (is_real(max_roll) and 0 < max_roll < 1.2):
            raise ValueError(f"max_roll must be in (0, 1.2) rad, got {max_roll!r}")
        self.max_roll = float(max_roll)
        _check_timing(timestep, control_period)
        self.n_substeps = _whole_multiple(control_period, timestep)
        self.timestep = float(timestep)
        self.control_period = float(control_period)
        _check_render_mode(render_mode, self.metadata)
        self.render_mode = render_mode
        self._renderer: Any = None
        chans = v.actuators.channel_names
        self._rudder_idx = [chans.index(n) for n in v.rudders]
        self._rudders = [a for a in v.actuators if isinstance(a, Rudder)]
        self._props = [
            (chans.index(a.name), a)
            for a in v.actuators
            if isinstance(a, Propeller) and a.alpha == 0
        ]
        n = len(self._rudder_idx)
        self.action_space = spaces.Box(-1.0, 1.0, (n,), dtype=np.float32)
        dmax = np.array([a.max_angle for a in self._rudders])
        lo = [-12.0, -math.pi, -12.0, -1.2, *(-dmax), 0.0]
        hi = [12.0, math.pi, 12.0, 1.2, *dmax, 30.0]
        if self.sway_estimate:
            lo.append(-50.0)
            hi.append(50.0)
        self.observation_space = spaces.Box(
            np.array(lo, dtype=np.float32), np.array(hi, dtype=np.float32), dtype=np.float32
        )
        self._max_angle = dmax
        self._max_rate = np.array([a.max_rate for a in self._rudders])
        self.physics: VesselPhysics | None = None
        self._physics_key: Any = None
        self.U = float(self.speed_range[0])
        self._rng = np.random.default_rng()

    # ---- set-up ----------------------------------------------------------------------------
    def _parse_waves(self, waves: Any) -> str | RollWaveConfig | None:
        if waves is None:
            return None
        if isinstance(waves, str) and waves == AUTO_WAVES:
            if getattr(self.base_vessel.plant(), "nabla", 0.0) > 0:
                return BEAM_SEA
            return SEED_WAVES if self.base_vessel.name == "van-der-klugt" else None
        if isinstance(waves, str):
            if waves != SEED_WAVES:
                raise ValueError(f"waves must be None, 'auto', 'seed', a RollWaveConfig or a "
                                 f"mapping, got {waves!r}")  # fmt: skip
            if self.base_vessel.name != "van-der-klugt":
                raise ValueError(
                    "waves='seed' are the seed's disturbances per unit inertia of the "
                    "'van-der-klugt' hull; give this vessel a sea: waves={'Hs': 2.0, 'Tp': 8.0}"
                )
            return SEED_WAVES
        cfg = RollWaveConfig.coerce(waves, name="waves")
        hull = self.base_vessel.plant()
        if not getattr(hull, "nabla", 0.0) > 0:
            raise ValueError(
                f"a wave spectrum needs the hull's displacement: {self.base_vessel.name!r} "
                f"({type(hull).__name__}) has none (hull.nabla); use waves='seed' or None"
            )
        return cfg

    def _vessel_at(self, U: float) -> Vessel:
        if self.kdp_law == "printed":
            return seed_vessel("printed", speed=U)
        return self.base_vessel

    def _make_physics(self, U: float) -> VesselPhysics:
        key = (self.kdp_law, U if self.kdp_law == "printed" else None)
        if self.physics is None or key != self._physics_key:
            if self._renderer is not None:
                self._renderer.close()
                self._renderer = None
            self.physics = VesselPhysics(self._vessel_at(U), world="open-water",
                                         timestep=self.timestep)  # fmt: skip
            self._physics_key = key
        return self.physics

    # ---- episode ---------------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        rng = self.np_random
        lo, hi = self.speed_range
        U = float(rng.uniform(lo, hi)) if hi > lo else lo
        if options and "speed" in options:
            U = float(_speed_range(options["speed"])[0])
        self.U = U
        phys = self._make_physics(U)
        # one child generator per stochastic part, in a fixed order: same seed, same episode
        seeds = rng.integers(2**63, size=3)
        self._noise_rng = np.random.default_rng(int(seeds[0]))
        self._wave_rng = np.random.default_rng(int(seeds[1]))
        phys.reset(eta=(0.0, 0.0, 0.0, self.heading), nu=(U, 0.0, 0.0, 0.0),
                   rng=np.random.default_rng(int(seeds[2])))  # fmt: skip
        hull = phys.plant
        # the propeller's thrust that balances the resistance in straight running at U
        nd0 = np.asarray(hull.nu_dot(np.array([U, 0.0, 0.0, 0.0]), np.zeros(4)))
        self._thrust0 = float(-(hull.mass_matrix() @ nd0)[0])
        self._m11 = float(hull.mass_matrix()[0, 0])
        self._wave_source = self._make_waves(U)
        self._filter = None
        if self.sway_estimate:
            q = self.filter_intensities(U)
            model = roll_model_of(phys.vessel, U, rudder=self._rudders[0].name)
            x0 = np.array([0.0, 0.0, self.heading, 0.0, 0.0])  # starts on the known heading
            self._filter = SwayVelocityKF(model, dt=self.control_period, q=q, x0=x0)
        self._steps = 0
        self._delta_prev = phys.actuator_state[self._rudder_idx].copy()
        self._command = np.zeros(len(self._rudder_idx))
        self._moment = (0.0, 0.0)
        self._metrics = _RollMetrics()
        obs = self._observe()
        info = {"speed": U, "time": 0.0}
        if self._filter is not None:
            info["v_hat"] = float(self._filter.x[0])
            info["trace_P"] = self._filter.trace_P
        return obs, info

    def _make_waves(self, U: float) -> Any:
        if self.waves is None:
            return None
        if self.waves == SEED_WAVES:
            q_K, q_N = seed_wave_intensities(U)
            return ("white", math.sqrt(q_K / self.control_period),
                    math.sqrt(q_N / self.control_period))  # fmt: skip
        hull = self.physics.plant  # type: ignore[union-attr]
        cfg = dataclasses.replace(self.waves, U=U)
        w = RollWaves(cfg, hull.K_phi, length=self.physics.vessel.L_pp, nabla=hull.nabla,  # type: ignore[union-attr]
                      rho=hull.rho)  # fmt: skip
        w.reset(self._wave_rng)
        return ("sea", w)

    def filter_intensities(self, U: float) -> tuple[float, float]:
        """The filter's white-noise intensities of the roll and yaw moments ((N m)^2 s).

        The seed's (:func:`seed_wave_intensities`) for its waves; for a sea, ``q_K = pi
        S_K(w_roll)`` (the one-sided roll-moment spectrum at the roll natural frequency: a white
        noise with that density there) and ``q_N = q_K`` [chosen]; in calm water
        :func:`~shipgym.observers.sway.calm_water_intensities` (a small process noise).
        The filter of ``sway_estimate=True`` uses them; pass them to a pilot of your own
        (:func:`~shipgym.controllers.rollpilot.roll_pilot`).
        """
        if self.waves == SEED_WAVES:
            return seed_wave_intensities(U)
        hull = self.physics.plant  # type: ignore[union-attr]
        if isinstance(self._wave_source, tuple) and self._wave_source[0] == "sea":
            w = self._wave_source[1]
            M = hull.mass_matrix()
            wn = math.sqrt(hull.K_phi / M[2, 2])
            S = float(w.spectrum(np.array([wn]))[0])
            s = math.sin(w.config.chi)
            q = math.pi * (hull.K_phi * s * wn**2 / 9.81) ** 2 * S
            return q, q
        return calm_water_intensities(hull)

    def _wave_moment(self, t0: float) -> tuple[float, float]:
        src = self._wave_source
        if src is None:
            return 0.0, 0.0
        if src[0] == "white":
            a, b = self._wave_rng.standard_normal(2)
            return float(src[1] * a), float(src[2] * b)
        K, N = src[1].moment(t0 + 0.5 * self.control_period)
        return float(K), float(N)

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        phys = self.physics
        if phys is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        a, action_clipped = rudder_action(action, self.action_space.shape, self.base_vessel.rudders)
        cmd_angle = a * self._max_angle
        t0 = phys.time
        if self.rudder_test:
            cmd_angle = cmd_angle + self.rudder_test_amplitude * math.sin(
                self.rudder_test_frequency * (t0 + self.control_period)
            )
        command = phys.command
        command[self._rudder_idx] = cmd_angle
        u = float(phys.nu_full[0])
        for j, prop in self._props:  # hold the speed: resistance at U + a 20 s speed loop
            thrust = self._thrust0 + self._m11 * (self.U - u) / 20.0
            command[j] = float(np.clip(prop.inverse(thrust), prop.lower, prop.upper))
        clipped = phys.set_command(command)
        self._command = phys.command[self._rudder_idx]
        K, N = self._wave_moment(t0)
        self._moment = (K, N)
        phys.set_external_force([0.0, 0.0, K, N])
        phys.step(self.n_substeps)
        self._steps += 1
        delta = phys.actuator_state[self._rudder_idx]
        rate = (delta - self._delta_prev) / self.control_period
        delta_mean = 0.5 * (delta + self._delta_prev)
        self._delta_prev = delta.copy()
        obs = self._observe(delta_mean)
        eta, nu = phys.eta_full, phys.nu_full
        phi = float(eta[2])
        e_psi = float(wrap_angle(eta[3] - self.heading))
        w = self.reward_weights
        terms = {
            "roll": -((phi / w.phi0) ** 2),
            "heading": -((e_psi / w.psi0) ** 2),
            "rudder_rate": -w.rate
            * sum(x * x for x in (rate / self._max_rate).tolist())
            / len(rate),
        }
        reward = float(sum(terms.values()))
        terminated = abs(phi) > self.max_roll
        truncated = (
            not terminated and self._steps * self.control_period >= self.episode_duration - 1e-9
        )
        at_limit = np.abs(delta) >= self._max_angle * (1.0 - 1e-9)
        saturated = at_limit | clipped[self._rudder_idx] | action_clipped
        rl = phys.rate_limited
        rate_limited = np.array([bool(rl[k]) for k in range(len(self._rudder_idx))])
        info: dict[str, Any] = {
            "time": phys.time,
            "eta": eta,
            "nu": nu,
            "speed": float(nu[0]),
            "v": float(nu[1]),
            "p": float(nu[2]),
            "r": float(nu[3]),
            "roll": phi,
            "heading_error": e_psi,
            "rudder": delta.copy(),
            "rudder_command": self._command.copy(),
            "rudder_rate": rate,
            "saturated": saturated,
            "rate_limited": rate_limited,
            "stalled": phys.stalled.copy(),
            "action_clipped": action_clipped,
            "wave_moment": np.array([K, N]),
            "reward_terms": terms,
        }
        if self._filter is not None:
            info["v_hat"] = float(self._filter.x[0])
            info["trace_P"] = self._filter.trace_P
        self._metrics.add(info)
        if terminated or truncated:
            info["episode_metrics"] = self.episode_metrics()
        return obs, reward, bool(terminated), bool(truncated), info

    def _observe(self, delta_mean: NDArray[np.float64] | None = None) -> NDArray[np.float32]:
        phys = self.physics
        assert phys is not None
        eta, nu = phys.eta_full, phys.nu_full
        y = np.array([nu[3], eta[3], nu[2], eta[2]])
        if self.sensor_noise:
            y = y + np.asarray(ROLL_SENSOR_STD) * self._noise_rng.standard_normal(4)
        delta = phys.actuator_state[self._rudder_idx]
        if self._filter is not None and delta_mean is not None:
            self._filter.step(y, float(delta_mean[0]))
        obs = [y[0], float(wrap_angle(y[1] - self.heading)), y[2], y[3], *delta, self.U]
        if self.sway_estimate:
            obs.append(float(self._filter.x[0]) if self._filter is not None else 0.0)
        return np.asarray(obs, dtype=np.float32)

    def episode_metrics(self) -> dict[str, Any]:
        """Roll, heading and rudder statistics of the episode so far (:class:`_RollMetrics`)."""
        return self._metrics.summary(self)


class _RollMetrics:
    """Running sums of an episode: RMS of roll, heading error, rudder, rudder rate."""

    def __init__(self) -> None:
        self.n = 0
        self.sums = {"roll": 0.0, "heading_error": 0.0, "rudder": 0.0, "rudder_rate": 0.0,
                     "v_error": 0.0}  # fmt: skip
        self.max_roll = 0.0
        self.max_heading = 0.0
        self.rate_limited = 0
        self.saturated = 0
        self.n_est = 0

    def add(self, info: Mapping[str, Any]) -> None:
        self.n += 1
        s = self.sums
        s["roll"] += info["roll"] ** 2
        s["heading_error"] += info["heading_error"] ** 2
        d, w = info["rudder"].tolist(), info["rudder_rate"].tolist()  # plain floats: cheap
        s["rudder"] += sum(x * x for x in d) / len(d)
        s["rudder_rate"] += sum(x * x for x in w) / len(w)
        self.max_roll = max(self.max_roll, abs(info["roll"]))
        self.max_heading = max(self.max_heading, abs(info["heading_error"]))
        self.rate_limited += any(info["rate_limited"].tolist())
        self.saturated += any(info["saturated"].tolist())
        if "v_hat" in info:
            s["v_error"] += (info["v_hat"] - info["v"]) ** 2
            self.n_est += 1

    def summary(self, env: RudderRollEnv) -> dict[str, Any]:
        n = max(self.n, 1)
        out: dict[str, Any] = {
            "speed": env.U,
            "steps": self.n,
            "roll_rms": math.sqrt(self.sums["roll"] / n),
            "roll_max": self.max_roll,
            "heading_rms": math.sqrt(self.sums["heading_error"] / n),
            "heading_max": self.max_heading,
            "rudder_rms": math.sqrt(self.sums["rudder"] / n),
            "rudder_rate_rms": math.sqrt(self.sums["rudder_rate"] / n),
            "rate_limited_fraction": self.rate_limited / n,
            "saturated_fraction": self.saturated / n,
        }
        if self.n_est:
            out["v_hat_rmse"] = math.sqrt(self.sums["v_error"] / self.n_est)
        return out


class SeedRollEnv(RudderRollEnv):
    """``shipgym/RudderRollStabilisation-v0``: :class:`RudderRollEnv` on the seed's model.

    The Van der Klugt (1987) hull of Radhakrishnan (n.d.) (``vessel="van-der-klugt"``, the
    reconstructed model) unless ``vessel=`` names another, ``U`` drawn from 8-15 m/s per
    episode, the vessel's ``waves="auto"`` (the seed's white noise for the seed's model);
    every argument of :class:`RudderRollEnv` can be given.
    """

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("vessel", "van-der-klugt")
        kwargs.setdefault("speed", (8.0, 15.0))
        super().__init__(**kwargs)


class NavalRollEnv(RudderRollEnv):
    """``shipgym/NavalRollDamping-v0``: :class:`RudderRollEnv` on the naval vessel.

    The nonlinear 4-DOF naval vessel of Blanke & Christensen (1993) (``vessel=
    "naval-vessel"``) unless ``vessel=`` names another, ``U`` drawn from 6-10 m/s, in the
    vessel's ``waves="auto"`` (the beam sea :data:`BEAM_SEA`); every argument of
    :class:`RudderRollEnv` can be given.
    """

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("vessel", "naval-vessel")
        kwargs.setdefault("speed", (6.0, 10.0))
        super().__init__(**kwargs)
