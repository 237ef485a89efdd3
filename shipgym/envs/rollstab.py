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

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from shipgym._config import from_mapping, is_real, param
from shipgym._jit import njit
from shipgym._seeding import child_seeds
from shipgym.disturbances.rollwaves import RollWaveConfig, RollWaves, roll_wave_moments
from shipgym.disturbances.spectra import wave_spectrum
from shipgym.dynamics.actuators import Propeller, Rudder
from shipgym.dynamics.frames import wrap
from shipgym.dynamics.linearise import roll_model_of
from shipgym.dynamics.vanderklugt import KDP_LAWS, VAN_DER_KLUGT, seed_vessel
from shipgym.dynamics.vessel import Vessel, load_vessel
from shipgym.observers.sway import (
    R_SWAY,
    SwayVelocityKF,
    calm_water_intensities,
    sway_kf_step,
)

from .batchphysics import BatchedPhysics
from .stepped import StepTask, TaskEnv, TaskSingleEnv

__all__ = [
    "AUTO_WAVES",
    "BEAM_SEA",
    "NavalRollEnv",
    "ROLL_SENSOR_STD",
    "RollRewardWeights",
    "RudderRollEnv",
    "RudderRollTask",
    "RudderRollVectorEnv",
    "SEED_WAVES",
    "SeedRollEnv",
    "naval_roll_vector_env",
    "seed_roll_vector_env",
    "seed_wave_intensities",
]

Array = NDArray[np.float64]
Bools = NDArray[np.bool_]

#: the seed's white-noise waves (:func:`seed_wave_intensities`)
SEED_WAVES = "seed"

#: standard deviations of the measured ``[r, psi, p, phi]`` (rad/s, rad, rad/s, rad): the
#: rate gyros' 0.05 deg/s and the gyros' 0.1 deg [chosen, the sway filter's R]
ROLL_SENSOR_STD: tuple[float, float, float, float] = tuple(math.sqrt(x) for x in R_SWAY)  # type: ignore[assignment]


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


def _real(name: str, value: Any, what: str, lo: float = -math.inf, hi: float = math.inf,
          strict: bool = False) -> float:  # fmt: skip
    """``value`` as a float, checked finite and in ``[lo, hi)`` (``(lo, hi)`` if ``strict``)."""
    ok = is_real(value) and math.isfinite(value) and lo <= value < hi
    if not ok or (strict and value == lo):
        raise ValueError(f"{name} must be {what}, got {value!r}")
    return float(value)


#: normal draws per env and refill (a generator's ``standard_normal((k, m))`` is the stream of
#: ``k`` calls of ``standard_normal(m)``)
BLOCK = 256


class _Normals:
    """Per env a stream of ``m`` standard normals per step from its own generator, drawn in
    blocks of :data:`BLOCK` and refilled when used up."""

    def __init__(self, n: int, m: int) -> None:
        self.gens: list[np.random.Generator | None] = [None] * n
        self.draws = np.zeros((n, BLOCK, m))
        self.k = np.full(n, BLOCK, dtype=np.int64)

    def reset(self, i: int, gen: np.random.Generator) -> None:
        self.gens[i] = gen
        self.k[i] = BLOCK

    def ready(self, mask: Bools) -> tuple[Array, NDArray[np.int64]]:
        """``(draws, k)`` with an unused draw ``draws[i, k[i]]`` for each env of ``mask``
        (the envs that used up their block refilled); the taker moves ``k[i]`` on."""
        if self.k.max() >= BLOCK:
            for i in np.nonzero(mask & (self.k >= BLOCK))[0].tolist():
                self.draws[i] = self.gens[i].standard_normal(self.draws.shape[1:])  # type: ignore[union-attr]
                self.k[i] = 0
        return self.draws, self.k


@njit
def roll_command(  # type: ignore[no-untyped-def]
    actions, active, max_angle, amp, freq, t, cp, ridx, cmd, aclip, white, draws, wk, sigma,
    moment,
):  # fmt: skip
    """The rudder commands of the active envs into ``cmd[:, ridx]`` (rad): each action
    clipped to [-1, 1] (``aclip`` where it was beyond) times the rudder's limit, plus the
    rudder test ``amp sin(freq (t + cp))`` (``amp`` 0: none); with ``white``, the seed's wave
    moments ``sigma draws[i, wk[i]]`` into ``moment`` (``wk`` moved on)."""
    for i in range(actions.shape[0]):
        if not active[i]:
            continue
        if white:
            moment[i, 0] = sigma[i, 0] * draws[i, wk[i], 0]
            moment[i, 1] = sigma[i, 1] * draws[i, wk[i], 1]
            wk[i] += 1
        test = amp * math.sin(freq * (t[i] + cp)) if amp != 0.0 else 0.0
        for k in range(actions.shape[1]):
            a = actions[i, k]
            aclip[i, k] = abs(a) > 1.0
            a = 1.0 if a > 1.0 else (-1.0 if a < -1.0 else a)
            cmd[i, ridx[k]] = a * max_angle[k] + test


@njit
def roll_measure(mask, eta, nu, sensor, draws, kn, std, y):  # type: ignore[no-untyped-def]
    """The gyros' ``y = [r, psi, p, phi]`` of the envs of ``mask``, with ``sensor`` plus
    ``std`` times the draws ``draws[i, kn[i]]`` (``kn`` moved on)."""
    for i in range(eta.shape[0]):
        if mask[i]:
            y[i, 0], y[i, 1], y[i, 2], y[i, 3] = nu[i, 3], eta[i, 3], nu[i, 2], eta[i, 2]
            if sensor:
                for j in range(4):
                    y[i, j] = y[i, j] + std[j] * draws[i, kn[i], j]
                kn[i] += 1


@njit
def roll_observe(mask, y, delta, heading, U, x_hat, obs):  # type: ignore[no-untyped-def]
    """The observation rows of ``mask`` (:class:`RudderRollEnv`): ``[y_r, wrap(y_psi -
    heading), y_p, y_phi, delta..., U]`` and, in a wider ``obs``, the filter's ``x_hat``."""
    nr = delta.shape[1]
    for i in range(y.shape[0]):
        if mask[i]:
            obs[i, 0] = np.float32(y[i, 0])
            obs[i, 1] = np.float32(wrap(y[i, 1] - heading))
            obs[i, 2] = np.float32(y[i, 2])
            obs[i, 3] = np.float32(y[i, 3])
            for k in range(nr):
                obs[i, 4 + k] = np.float32(delta[i, k])
            obs[i, 4 + nr] = np.float32(U[i])
            if obs.shape[1] > 5 + nr:
                obs[i, 5 + nr] = np.float32(x_hat[i])


@njit
def roll_terms(  # type: ignore[no-untyped-def]
    active, eta, delta, dprev, heading, phi0, psi0, w_rate, max_rate, max_angle, clipped,
    aclip, cp, max_roll, sums, rate, dmean, e_psi, terms, term, sat,
):  # fmt: skip
    """The task's step law for the active envs (:class:`RudderRollEnv`): the rudder rate and
    mean over the control period (``dprev`` moved on), the reward terms ``roll``,
    ``heading``, ``rudder_rate``, termination at ``max_roll``, the saturation flags and the
    episode sums (:attr:`RudderRollTask._sums`; the rate-limit and filter sums are the
    caller's)."""
    nr = delta.shape[1]
    for i in range(eta.shape[0]):
        if not active[i]:
            continue
        rr = 0.0
        d2 = 0.0
        w2 = 0.0
        any_sat = False
        for k in range(nr):
            d = delta[i, k]
            rate[i, k] = (d - dprev[i, k]) / cp
            dmean[i, k] = 0.5 * (d + dprev[i, k])
            dprev[i, k] = d
            x = rate[i, k] / max_rate[k]
            rr += x * x
            d2 += d * d
            w2 += rate[i, k] * rate[i, k]
            sat[i, k] = abs(d) >= max_angle[k] * (1.0 - 1e-9) or clipped[i, k] or aclip[i, k]
            any_sat = any_sat or sat[i, k]
        phi = eta[i, 2]
        e = wrap(eta[i, 3] - heading)
        e_psi[i] = e
        terms[i, 0] = -((phi / phi0) ** 2)
        terms[i, 1] = -((e / psi0) ** 2)
        terms[i, 2] = -w_rate * rr / nr
        term[i] = abs(phi) > max_roll
        s = sums[i]
        s[0] += phi * phi
        s[1] += e * e
        s[2] += d2 / nr
        s[3] += w2 / nr
        s[5] = max(s[5], abs(phi))
        s[6] = max(s[6], abs(e))
        s[8] += any_sat


class RudderRollTask(StepTask):
    """The rudder-roll task over N >= 1 envs (:class:`RudderRollEnv` is its spec; the
    arguments are its own), stepped by :class:`RudderRollVectorEnv`. Each env draws its own
    speed per episode; with ``kdp_law="printed"`` each hull gets the rudder of the printed
    law at its speed (:meth:`~shipgym.envs.batchphysics.BatchedPhysics.set_actuators`)."""

    needs = "roll-steering"
    reward_terms = ("roll", "heading", "rudder_rate")

    def __init__(
        self,
        num_envs: int,
        *,
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
        self.heading = _real("heading", heading, "a finite angle (rad)")
        self.waves = self._parse_waves(waves)
        self.rudder_test = bool(rudder_test)
        self.rudder_test_amplitude = _real(
            "rudder_test_amplitude", rudder_test_amplitude, ">= 0", 0.0
        )
        self.rudder_test_frequency = _real(
            "rudder_test_frequency", rudder_test_frequency, ">= 0", 0.0
        )
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
        self.episode_duration = _real(
            "episode_duration", episode_duration, "> 0 s", 0.0, strict=True
        )
        self.max_roll = _real("max_roll", max_roll, "in (0, 1.2) rad", 0.0, 1.2, strict=True)
        self.set_timing(timestep, control_period, self.episode_duration)
        n = num_envs if isinstance(num_envs, int) and num_envs >= 1 else 1  # _setup checks it
        self.physics = BatchedPhysics(v, n, timestep=self.timestep)
        acts = self.physics.actuators
        chans = acts.channel_names
        self._ridx = np.array([chans.index(r) for r in v.rudders], dtype=np.int64)
        rudders = [a for a in acts if isinstance(a, Rudder)]
        self._rudder_name = rudders[0].name
        self._props = [(chans.index(a.name), a) for a in acts
                       if isinstance(a, Propeller) and a.alpha == 0]  # fmt: skip
        #: each rudder's angle limit (rad): an action of 1 commands it
        self.max_angle = np.array([a.max_angle for a in rudders])
        self._max_rate = np.array([a.max_rate for a in rudders])
        nr = len(rudders)
        lo = [-12.0, -math.pi, -12.0, -1.2, *(-self.max_angle), 0.0]
        hi = [12.0, math.pi, 12.0, 1.2, *self.max_angle, 30.0]
        if self.sway_estimate:
            lo.append(-50.0)
            hi.append(50.0)
        obs_space = spaces.Box(np.array(lo, dtype=np.float32), np.array(hi, dtype=np.float32),
                               dtype=np.float32)  # fmt: skip
        self.attach(num_envs, obs_space, spaces.Box(-1.0, 1.0, (nr,), dtype=np.float32))
        hull = self.physics.plant
        self._M = hull.mass_matrix()
        self._m11 = float(self._M[0, 0])
        self.U = np.full(n, self.speed_range[0])  # each env's speed this episode (m/s)
        self.vessels: list[Vessel] = [v] * n  # each env's vessel (the printed law: at its U)
        self._thrust0 = np.zeros(n)
        self._noise = _Normals(n, 4)
        self._white = _Normals(n, 2)
        self._sigma = np.zeros((n, 2))  # the seed's white moments' standard deviations
        nc = RollWaveConfig().n_components if not isinstance(self.waves, RollWaveConfig) else (
            self.waves.n_components)  # fmt: skip
        self._sea = [np.zeros((n, nc)) for _ in range(4)]  # w_e, eps, c_K, c_N of each sea
        self._kf = [np.zeros(s) for s in ((n, 5, 5), (n, 5), (n, 5, 5), (n, 4, 4))]
        self._kx, self._kP, self._kG = np.zeros((n, 5)), np.zeros((n, 5, 5)), np.zeros((n, 5, 4))
        self._std = np.array(ROLL_SENSOR_STD)
        self._rows = np.arange(n)
        self._external = np.zeros((n, 4))  # [X, Y, K, N]: the waves' K, N
        self._delta_prev = np.zeros((n, nr))
        self._obs = np.zeros((n, obs_space.shape[0]), dtype=np.float32)
        #: per env the sums of roll^2, e_psi^2, rudder^2, rate^2, v_err^2, max |phi|,
        #: max |e_psi|, steps rate-limited, steps saturated
        self._sums = np.zeros((n, 9))

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

    def vessel_at(self, U: float) -> Vessel:
        """The vessel of an episode at the speed ``U`` (m/s): the printed ``K_dp`` law's
        rudder is placed for ``U``; otherwise the vessel itself."""
        if self.kdp_law == "printed":
            return seed_vessel("printed", speed=U)
        return self.base_vessel

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
        hull = self.physics.plant
        if isinstance(self.waves, RollWaveConfig):
            c = self.waves
            wn = math.sqrt(hull.K_phi / hull.mass_matrix()[2, 2])
            S = float(wave_spectrum(c.spectrum, np.array([wn]), c.Hs, c.Tp, c.gamma)[0])
            q = math.pi * (hull.K_phi * math.sin(c.chi) * wn**2 / 9.81) ** 2 * S
            return q, q
        return calm_water_intensities(hull)

    # ---- episodes --------------------------------------------------------------------------
    def initialize_episode(self, rngs: list[Any], mask: Bools) -> None:
        n = self.num_envs
        phys = self.physics
        hull = phys.plant
        lo, hi = self.speed_range
        gens: list[Any] = [None] * n
        for i in np.nonzero(mask)[0].tolist():
            rng = rngs[i]
            U = float(rng.uniform(lo, hi)) if hi > lo else lo  # type: ignore[union-attr]
            self.U[i] = U
            # one child generator per stochastic part, in a fixed order: same seed, same episode
            seeds = child_seeds(rng, 3)  # type: ignore[arg-type]
            self._noise.reset(i, np.random.default_rng(int(seeds[0])))
            wave_rng = np.random.default_rng(int(seeds[1]))
            self._white.reset(i, wave_rng)
            gens[i] = np.random.default_rng(int(seeds[2]))
            self.vessels[i] = vessel = self.vessel_at(U)
            if self.kdp_law == "printed":
                phys.set_actuators(i, vessel)
            if self._props:  # the thrust that balances the resistance in straight running at U
                nd0 = np.asarray(hull.nu_dot(np.array([U, 0.0, 0.0, 0.0]), np.zeros(4)))
                self._thrust0[i] = -(self._M @ nd0)[0]
            if self.waves == SEED_WAVES:
                q_K, q_N = seed_wave_intensities(U)
                self._sigma[i] = math.sqrt(q_K / self.control_period), math.sqrt(
                    q_N / self.control_period)  # fmt: skip
            elif isinstance(self.waves, RollWaveConfig):
                w = RollWaves(dataclasses.replace(self.waves, U=U), hull.K_phi,
                              length=vessel.L_pp, nabla=hull.nabla, rho=hull.rho)  # fmt: skip
                w.reset(wave_rng)
                for dst, src in zip(self._sea, w.moment_constants, strict=True):
                    dst[i] = src
            if self.sway_estimate:
                model = roll_model_of(vessel, U, rudder=self._rudder_name)
                x0 = np.array([0.0, 0.0, self.heading, 0.0, 0.0])  # on the known heading
                kf = SwayVelocityKF(model, dt=self.control_period, q=self.filter_intensities(U),
                                    x0=x0)  # fmt: skip
                for dst, src in zip(self._kf, (kf.A_d, kf.B_d, kf.Q, kf.R), strict=True):
                    dst[i] = src
                self._kx[i], self._kP[i], self._kG[i] = kf.x, kf.P, kf.gain
        z = np.zeros(n)
        eta = np.stack([z, z, z, np.full(n, self.heading)], 1)
        nu = np.stack([self.U, z, z, z], 1)
        phys.reset(eta=eta, nu=nu, mask=mask, rngs=gens)
        delta = phys.actuator_state[:, self._ridx]
        self._delta_prev[mask] = delta[mask]
        self._sums[mask] = 0.0
        self._observe(mask, self._measure(mask, phys.eta_full, phys.nu_full), delta)

    def _measure(self, mask: Bools, eta: Array, nu: Array) -> Array:
        """The gyros' ``[r, psi, p, phi]`` (n, 4) of the envs of ``mask`` (their noise drawn)."""
        y = np.zeros((self.num_envs, 4))
        noise = self._noise
        nd, nk = noise.ready(mask) if self.sensor_noise else (noise.draws, noise.k)
        self.call(roll_measure, mask, eta, nu, self.sensor_noise, nd, nk, self._std, y)
        return y

    def _observe(self, mask: Bools, y: Array, delta: Array) -> None:
        self.call(roll_observe, mask, y, delta, self.heading, self.U, self._kx[:, 0].copy(),
                   self._obs)  # fmt: skip

    def observation(self) -> NDArray[np.float32]:
        return self._obs.copy()

    def reset_info(self, mask: Bools) -> dict[str, Any]:
        info: dict[str, Any] = {"speed": self.U.copy(), "time": np.zeros(self.num_envs)}
        if self.sway_estimate:
            info["v_hat"] = self._kx[:, 0].copy()
            info["trace_P"] = np.trace(self._kP, axis1=1, axis2=2)
        return info

    def before_step(self, actions: Array, active: Bools) -> None:
        phys = self.physics
        n, nr = actions.shape
        command = phys.command
        t0 = phys.t.copy()
        aclip = np.zeros((n, nr), dtype=np.bool_)
        amp = self.rudder_test_amplitude if self.rudder_test else 0.0
        white = self.waves == SEED_WAVES
        wd, wk = self._white.ready(active) if white else (self._white.draws, self._white.k)
        moment = np.zeros((n, 2))
        self.call(roll_command, actions, active, self.max_angle, amp,
                   self.rudder_test_frequency, t0, self.control_period, self._ridx, command,
                   aclip, white, wd, wk, self._sigma, moment)  # fmt: skip
        if self._props:  # hold the speed: resistance at U + a 20 s speed loop
            thrust = self._thrust0 + self._m11 * (self.U - phys.nu_full[:, 0]) / 20.0
            for j, prop in self._props:
                c = np.clip(prop.inverse(thrust), prop.lower, prop.upper)
                command[:, j] = np.where(active, c, command[:, j])
        clipped = phys.set_command(command)[:, self._ridx]
        if isinstance(self.waves, RollWaveConfig):  # the sea's, mid-period
            t = np.ascontiguousarray(t0 + 0.5 * self.control_period)
            K, N = np.empty(n), np.empty(n)
            self.call(roll_wave_moments, t, self._rows, *self._sea, K, N)
            moment[:, 0], moment[:, 1] = K, N
        if self.waves is not None:
            self._external[:, 2:] = moment
            phys.set_external_force(self._external)
        self._held = clipped, aclip, moment

    def after_step(self, active: Bools) -> tuple[dict[str, Array], Bools, dict[str, Any]]:
        phys = self.physics
        clipped, aclip, moment = self._held
        n, nr = aclip.shape
        eta, nu, delta = phys.eta_full, phys.nu_full, phys.actuator_state[:, self._ridx]
        y = self._measure(active, eta, nu)
        w = self.reward_weights
        terms, e_psi = np.zeros((n, 3)), np.zeros(n)
        rate, dmean, sat = np.zeros((n, nr)), np.zeros((n, nr)), np.zeros((n, nr), np.bool_)
        term = np.zeros(n, np.bool_)
        self.call(roll_terms, active, eta, delta, self._delta_prev, self.heading, w.phi0, w.psi0,
                  w.rate, self._max_rate, self.max_angle, clipped, aclip, self.control_period,
                  self.max_roll, self._sums, rate, dmean, e_psi, terms, term, sat)  # fmt: skip
        info: dict[str, Any] = {
            "time": phys.t.copy(),
            "eta": eta,
            "nu": nu,
            "speed": nu[:, 0].copy(),
            "v": nu[:, 1].copy(),
            "p": nu[:, 2].copy(),
            "r": nu[:, 3].copy(),
            "roll": eta[:, 2].copy(),
            "heading_error": e_psi,
            "rudder": delta,
            "rudder_command": phys.command[:, self._ridx],
            "rudder_rate": rate,
            "saturated": sat,
            "rate_limited": phys.rate_limited[:, :nr],
            "stalled": phys.stalled,
            "action_clipped": aclip,
            "wave_moment": moment,
        }
        s = self._sums
        s[:, 7] += active & info["rate_limited"].any(1)
        if self.sway_estimate:
            self.call(sway_kf_step, *self._kf, y, dmean[:, 0].copy(), active, self._kx,
                       self._kP, self._kG)  # fmt: skip
            v_hat = self._kx[:, 0].copy()
            s[:, 4] += np.where(active, (v_hat - nu[:, 1]) ** 2, 0.0)
            info["v_hat"] = v_hat
            info["trace_P"] = np.trace(self._kP, axis1=1, axis2=2)
        self._observe(active, y, delta)
        names = self.reward_terms
        return {names[k]: terms[:, k] for k in range(3)}, term, info

    # ---- metrics ---------------------------------------------------------------------------
    def episode_metrics(self, done: Bools) -> dict[str, Any]:
        """Roll, heading and rudder statistics of each env's episode so far: RMS of roll,
        heading error, rudder and rudder rate, their maxima, the fractions of steps
        rate-limited and saturated, the v-hat RMSE (with the filter)."""
        s = self._sums
        n = np.maximum(self.steps, 1)
        out: dict[str, Any] = {
            "speed": self.U.copy(),
            "steps": self.steps.copy(),
            "roll_rms": np.sqrt(s[:, 0] / n),
            "roll_max": s[:, 5].copy(),
            "heading_rms": np.sqrt(s[:, 1] / n),
            "heading_max": s[:, 6].copy(),
            "rudder_rms": np.sqrt(s[:, 2] / n),
            "rudder_rate_rms": np.sqrt(s[:, 3] / n),
            "rate_limited_fraction": s[:, 7] / n,
            "saturated_fraction": s[:, 8] / n,
        }
        if self.sway_estimate:
            out["v_hat_rmse"] = np.sqrt(s[:, 4] / n)
        return out


class RudderRollVectorEnv(TaskEnv):
    """N envs of :class:`RudderRollEnv` stepped together (its docstring is the task's spec):
    ``RudderRollVectorEnv(num_envs, *, autoreset_mode="next-step", **RudderRollEnv's
    arguments but render_mode)``, :class:`RudderRollTask` in the env of every stepped task;
    env ``i`` seeded ``seed + i`` is the single env seeded so, bit for bit."""

    task_class = RudderRollTask


class RudderRollEnv(TaskSingleEnv):
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

    batched = RudderRollVectorEnv
    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(self, vessel: Vessel | str | None = None, **kwargs: Any) -> None:
        super().__init__(vessel=vessel, **kwargs)

    @property
    def U(self) -> float:
        """The episode's forward speed (m/s)."""
        return float(self.batch.U[0])

    @property
    def vessel(self) -> Vessel:
        """The episode's vessel (:meth:`RudderRollVectorEnv.vessel_at` its speed)."""
        return self.batch.vessels[0]


class SeedRollEnv(RudderRollEnv):
    """``shipgym/RudderRollStabilisation-v0``: :class:`RudderRollEnv` on the seed's model.

    The Van der Klugt (1987) hull of Radhakrishnan (n.d.) (``vessel="van-der-klugt"``, the
    reconstructed model) unless ``vessel=`` names another, ``U`` drawn from 8-15 m/s per
    episode, the vessel's ``waves="auto"`` (the seed's white noise for the seed's model);
    every argument of :class:`RudderRollEnv` can be given.
    """

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**{**SEED_TASK, **kwargs})


class NavalRollEnv(RudderRollEnv):
    """``shipgym/NavalRollDamping-v0``: :class:`RudderRollEnv` on the naval vessel.

    The nonlinear 4-DOF naval vessel of Blanke & Christensen (1993) (``vessel=
    "naval-vessel"``) unless ``vessel=`` names another, ``U`` drawn from 6-10 m/s, in the
    vessel's ``waves="auto"`` (the beam sea :data:`BEAM_SEA`); every argument of
    :class:`RudderRollEnv` can be given.
    """

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**{**NAVAL_TASK, **kwargs})


#: the registered tasks' vessel and speed range, where not given
SEED_TASK: dict[str, Any] = {"vessel": "van-der-klugt", "speed": (8.0, 15.0)}
NAVAL_TASK: dict[str, Any] = {"vessel": "naval-vessel", "speed": (6.0, 10.0)}


def seed_roll_vector_env(num_envs: int, **kwargs: Any) -> RudderRollVectorEnv:
    """``shipgym/RudderRollStabilisation-v0``'s vector entry point."""
    return RudderRollVectorEnv(num_envs, **{**SEED_TASK, **kwargs})


def naval_roll_vector_env(num_envs: int, **kwargs: Any) -> RudderRollVectorEnv:
    """``shipgym/NavalRollDamping-v0``'s vector entry point."""
    return RudderRollVectorEnv(num_envs, **{**NAVAL_TASK, **kwargs})
