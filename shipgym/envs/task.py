r"""Tasks: what an episode is, for N >= 1 envs at once (dm_control's Task, batched).

Public names: ``MAX_START_OFFSET``, ``OBS_LAYOUT``, ``REWARD_TERMS``, ``SCENES``, ``Episode``,
``HarbourTask``, ``PlanTask``, ``RewardWeights``, ...
Sources: Tomera (2014).

Design notes: docs/design/envs.task.md.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple, Protocol

import numpy as np
from numpy.typing import NDArray

from shipgym._config import is_real, param, replace_drawn
from shipgym._jit import entry, njit
from shipgym.disturbances import CurrentConfig, WaveConfig, WindConfig
from shipgym.disturbances.current import MAX_CURRENT_SPEED
from shipgym.disturbances.wind import MAX_WIND_SPEED
from shipgym.dynamics.frames import wrap
from shipgym.dynamics.params import BLUE_LADY_HULL
from shipgym.dynamics.vessel import Vessel, load_vessel
from shipgym.guidance import Leg, ManoeuvrePlan
from shipgym.guidance import plan as named_plan
from shipgym.guidance.rframe import r_pose
from shipgym.observers.sensors import SensorConfig, sensor_config

__all__ = [
    "MAX_START_OFFSET",
    "OBS_LAYOUT",
    "REWARD_TERMS",
    "SCENES",
    "Episode",
    "HarbourTask",
    "PlanTask",
    "RewardWeights",
    "StationKeepingTask",
    "Task",
    "TrackingTask",
    "parse_sensors_arg",
    "parse_waves_arg",
    "plan_terms",
    "tracking_penalty",
]

Array = NDArray[np.float64]

#: largest |x|, |y| of a start pose (m) and of its noise, and largest |psi| (rad): 1000 km,
#: far beyond any harbour or trial area and far below the 1e10 at which MuJoCo declares a
#: position invalid and silently resets the state to the origin; float64 positions there
#: still resolve 1e-10 m.
MAX_START_OFFSET = 1e6

#: the scenes (worlds without a ship, :data:`shipgym.envs.scene.WORLDS`)
SCENES: tuple[str, ...] = ("harbour", "open-water")

#: observation blocks of a plan task before the previous action (whose length is the number
#: of channels)
OBS_LAYOUT = (
    ("pos_error_body", 3),
    ("nu", 3),
    ("nu_ref", 3),
    ("nu_dot_ref", 3),
)

#: the reward terms of a plan task, in the order of :func:`plan_terms`' columns
REWARD_TERMS = (
    "reward_position",
    "reward_heading",
    "reward_velocity",
    "reward_effort",
    "reward_rate",
    "reward_reversal",
    "reward_contact",
    "reward_leg",
)

#: the templates of an episode's drawn wind and current (:func:`replace_drawn`)
_CALM_WIND = WindConfig()
_STILL_WATER = CurrentConfig()

#: the default wind: the vessel's nominal wind from 300 deg
_NOMINAL: Any = type("_Nominal", (), {"__repr__": lambda self: "<the vessel's nominal wind>"})()


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the named reward terms (each term is ``-weight * quantity``).

    The three tracking terms are raw squares by default (``-w q^2``). With a scale ``s``
    (``position_scale`` m, ``heading_scale`` rad, ``velocity_scale`` m/s) a term saturates:
    ``-w s^2 (1 - exp(-q^2 / s^2))``, the same as the square for ``q << s`` (the weight keeps
    its unit and meaning) and bounded by ``w s^2`` however far the ship is off, so one bad
    episode early in training cannot dominate the returns (the raw squares of a drifting ship
    reach about -1e6 per episode).
    """

    position: float = param(1.0, "1/m^2", "squared horizontal tracking error")
    heading: float = param(3.0, "1/rad^2", "squared heading error")
    velocity: float = param(10.0, "s^2/m^2", "squared body-velocity error vs the reference")
    effort: float = param(0.01, "1", "squared normalised command")
    rate: float = param(0.01, "1", "squared change of the normalised command")
    reversal: float = param(
        0.0, "1", "per reversal: a two-sided channel's command through zero in one step"
    )
    contact: float = param(100.0, "1", "penalty once, when the hull touches a quay")
    leg_bonus: float = param(10.0, "1", "bonus per completed leg (a positive term)")
    position_scale: float | None = param(
        None, "m", "saturation scale of the position term (None: the raw square)"
    )
    heading_scale: float | None = param(
        None, "rad", "saturation scale of the heading term (None: the raw square)"
    )
    velocity_scale: float | None = param(
        None, "m/s", "saturation scale of the velocity term (None: the raw square)"
    )

    def __post_init__(self) -> None:
        # each term is -weight * quantity (+leg_bonus): weights are magnitudes, so a negative
        # or non-finite one would reward errors or make every reward NaN
        for f in dataclasses.fields(self):
            val = getattr(self, f.name)
            if f.name.endswith("_scale"):
                if val is None:
                    continue
                if not is_real(val) or not (math.isfinite(val) and val > 0):
                    raise ValueError(
                        f"reward_weights.{f.name} must be None (the raw square) or a finite "
                        f"number > 0 ({f.metadata['unit']}), got {val!r}"
                    )
                object.__setattr__(self, f.name, float(val))
                continue
            if not is_real(val):
                raise TypeError(f"reward_weights.{f.name} must be a number, got {val!r}")
            if not (math.isfinite(val) and val >= 0):
                raise ValueError(
                    f"reward_weights.{f.name} must be finite and >= 0 (the sign is in the "
                    f"reward term), got {val!r}"
                )
            object.__setattr__(self, f.name, float(val))

    def vector(self) -> Array:
        """The weights as :func:`plan_terms` reads them: ``position, heading, velocity,
        effort, rate, contact, leg_bonus``, the three scales (0: the raw square) and
        ``reversal``."""
        scales = (self.position_scale, self.heading_scale, self.velocity_scale)
        return np.array(
            [self.position, self.heading, self.velocity, self.effort, self.rate, self.contact,
             self.leg_bonus, *(0.0 if s is None else s for s in scales), self.reversal]
        )  # fmt: skip

    @classmethod
    def coerce(cls, value: Any) -> RewardWeights:
        """``None`` (the defaults), a :class:`RewardWeights` or a mapping of its fields."""
        if value is None:
            return cls()
        if isinstance(value, Mapping):
            from shipgym._config import from_mapping

            return from_mapping(cls, value, where="reward_weights")
        if not isinstance(value, cls):
            raise TypeError(
                f"reward_weights must be None, a RewardWeights or a mapping, got {value!r}"
            )
        return value


def tracking_penalty(weight: Any, q2: Any, scale: float | None) -> Any:
    """``weight * q2`` (``scale`` None) or ``weight * s^2 (1 - exp(-q2 / s^2))``: the magnitude
    of a tracking reward term of :class:`RewardWeights`, for floats or NumPy arrays alike (the
    design-time form; the envs compute it in :func:`plan_terms`)."""
    if scale is None:
        return weight * q2
    s2 = scale * scale
    return weight * s2 * -np.expm1(-np.asarray(q2, dtype=float) / s2)


# ---- the plan tasks' run-time law ------------------------------------------------------------
@njit(inline="always")
def _penalty(w, q2, s):  # type: ignore[no-untyped-def]
    """:func:`tracking_penalty` (``s = 0``: the raw square)."""
    if s == 0.0:
        return w * q2
    s2 = s * s
    return w * s2 * -math.expm1(-q2 / s2)


@njit
def plan_terms(  # type: ignore[no-untyped-def]
    eta, nu, nav_eta, nav_nu, ref, action, prev, switched, new_contact, w, two_sided, obs,
    rew, eta_r,
):  # fmt: skip
    """The observation and reward terms of N envs of a plan task (one law for every N).

    Args:
        eta, nu: (N, 3) the true NED poses ``[x, y, psi]`` (m, m, rad) and body velocities
            ``[u, v, r]`` (m/s, m/s, rad/s).
        nav_eta, nav_nu: (N, 3) the navigation data (the truth, or an observer's estimate).
        ref: (N, 10, 3) the guidance's reference
            (:attr:`BatchedReference.buffer <shipgym.guidance.batch.BatchedReference.buffer>`).
        action, prev: (N, m) the applied (clipped) normalised action and the previous one.
        switched, new_contact: (N,) booleans: a leg completed, a first quay contact.
        w: the weights (:meth:`RewardWeights.vector`).
        two_sided: (m,) 1.0 for a channel whose command has two sides (a reversible
            propeller or tunnel: its lower limit < 0), else 0.0: where the ``reversal`` term
            counts a command through zero (``a prev < 0``).
        obs: (N, 12 + m) float32 out: the observation (the layout of
            :class:`~shipgym.envs.base.ShipEnv`): the position error ship - reference in the
            ship's body frame (m), the wrapped heading error (rad), ``nav_nu``, ``nu_d``,
            ``nu_dot_d`` and the action just applied (the next step's previous action).
        rew: (N, 8) out: the reward terms in the order of :data:`REWARD_TERMS`.
        eta_r: (N, 3) out: the true poses in the current legs' r-frames (Tomera (2014) eq. 1,
            the heading on the branch of the desired one).
    """
    n, m = action.shape
    for i in range(n):
        r = ref[i]
        # the observation, from navigation data (what a controller may know)
        psi = nav_eta[i, 2]
        c, s = math.cos(psi), math.sin(psi)
        dx = nav_eta[i, 0] - r[4, 0]
        dy = nav_eta[i, 1] - r[4, 1]
        obs[i, 0] = c * dx + s * dy
        obs[i, 1] = c * dy - s * dx
        obs[i, 2] = wrap(psi - r[4, 2])
        for k in range(3):
            obs[i, 3 + k] = nav_nu[i, k]
            obs[i, 6 + k] = r[6, k]
            obs[i, 9 + k] = r[7, k]
        # the reward, from the truth in the leg's r-frame
        xr, yr, pr = r_pose(eta[i, 0], eta[i, 1], eta[i, 2], r[3, 0], r[3, 1], r[3, 2],
                            r[0, 2], True)  # fmt: skip
        eta_r[i, 0], eta_r[i, 1], eta_r[i, 2] = xr, yr, pr
        ex = xr - r[0, 0]
        ey = yr - r[0, 1]
        ep = wrap(pr - r[0, 2])
        du = nu[i, 0] - r[6, 0]
        dv = nu[i, 1] - r[6, 1]
        dr = nu[i, 2] - r[6, 2]
        effort = 0.0
        rate = 0.0
        reversals = 0.0
        for j in range(m):
            a = action[i, j]
            obs[i, 12 + j] = a
            effort += a * a
            rate += (a - prev[i, j]) * (a - prev[i, j])
            if a * prev[i, j] < 0.0:
                reversals += two_sided[j]
        rew[i, 0] = -_penalty(w[0], ex * ex + ey * ey, w[7])
        rew[i, 1] = -_penalty(w[1], ep * ep, w[8])
        rew[i, 2] = -_penalty(w[2], du * du + dv * dv + dr * dr, w[9])
        rew[i, 3] = -w[3] * effort
        rew[i, 4] = -w[4] * rate
        rew[i, 5] = -w[10] * reversals
        rew[i, 6] = -w[5] if new_contact[i] else 0.0
        rew[i, 7] = w[6] if switched[i] else 0.0


# ---- tasks -------------------------------------------------------------------------------
class Episode(NamedTuple):
    """One env's episode as its task draws it.

    Attributes:
        plan: the manoeuvre plan.
        wind: the wind (``None``: no aerodynamic load).
        current: the current (``None``: none).
        sensors: the sensor configuration (``None``: no sensors).
        start: the plan's start pose P of the first leg (m, m, rad; NED).
        eta0: the hull's start pose (``start`` plus the start perturbation).
    """

    plan: ManoeuvrePlan
    wind: WindConfig | None
    current: CurrentConfig | None
    sensors: SensorConfig | None
    start: Array
    eta0: Array


class Task(Protocol):
    """What an env asks of its task (dm_control's Task, over N envs).

    Attributes:
        needs: what the task needs of the vessel (:data:`shipgym.envs.registration.NEEDS`).
        vessel: the vessel it was made for.
        scene: the world (:data:`SCENES`); the harbour has quays (MuJoCo contacts).
        waves: the sea (``None``: calm).
        terminate_on_finish: whether an episode ends when its plan is complete.
    """

    needs: str
    vessel: Vessel
    scene: str
    waves: WaveConfig | None
    terminate_on_finish: bool
    reward_terms: tuple[str, ...]

    def initialize_episode(
        self,
        rng: np.random.Generator,
        start: Array | None = None,
        sensors: SensorConfig | None = None,
    ) -> Episode: ...  # pragma: no cover - protocol

    def observation_structure(
        self, n_actions: int
    ) -> tuple[dict[str, slice], int]: ...  # pragma: no cover - protocol

    def terms(
        self, eta: Array, nu: Array, nav_eta: Array, nav_nu: Array, ref: Array, action: Array,
        prev: Array, switched: NDArray[np.bool_], new_contact: NDArray[np.bool_],
        obs: NDArray[np.float32], rew: Array, eta_r: Array,
    ) -> None: ...  # pragma: no cover - protocol  # fmt: skip


class PlanTask:
    r"""A vessel on a manoeuvre plan: the common task of :class:`~shipgym.envs.base.ShipEnv`.

    Args (the env's task arguments; the table in :class:`~shipgym.envs.base.ShipEnv`):
        vessel: a :class:`~shipgym.dynamics.vessel.Vessel`, a packaged vessel's name or a
            package path (required: no default vessel).
        plan: a plan name or :class:`~shipgym.guidance.ManoeuvrePlan`.
        wind, current: any form of :meth:`WindConfig.coerce
            <shipgym.disturbances.WindConfig.coerce>` / :meth:`CurrentConfig.coerce
            <shipgym.disturbances.CurrentConfig.coerce>` (``None``: none); the default wind is
            the vessel's nominal wind from 300 deg.
        sensors: a preset name, a :class:`~shipgym.observers.sensors.SensorConfig`, a mapping
            or ``None`` (no sensors).
        waves: ``None``, a :class:`~shipgym.disturbances.WaveConfig`, a preset name or a
            mapping.
        scene: ``"harbour"`` or ``"open-water"``.
        start_pose: the NED start pose (m, m, rad); the harbour turns with it.
        start_noise: half-widths of the uniform start perturbation (m, m, rad).
        terminate_on_finish: end the episode when the plan is complete.
        reward_weights: :class:`RewardWeights`, a mapping of its fields or ``None``.

    A new task of this family overrides what differs: the draws (``episode_plan``,
    ``episode_wind``, ...), and for its own observation and reward :attr:`reward_terms`,
    :meth:`observation_structure` and :meth:`terms` (one function over N envs: the single
    env and the vector env both run it).

    Raises:
        TypeError, ValueError: a missing vessel, a vessel that cannot position itself, or a
            bad argument, each naming what to pass instead.
    """

    needs: ClassVar[str] = "positioning"
    default_plan: ClassVar[Any] = "tomera2014"
    default_scene: ClassVar[str] = "harbour"
    #: the names of the reward terms, in the order of :meth:`terms`' ``rew`` columns
    reward_terms: ClassVar[tuple[str, ...]] = REWARD_TERMS

    def __init__(
        self,
        vessel: Vessel | str | None = None,
        *,
        plan: str | ManoeuvrePlan | None = None,
        wind: Any = _NOMINAL,
        sensors: Any = "default",
        waves: Any = None,
        current: Any = None,
        scene: str | None = None,
        start_pose: Any = (0.0, 0.0, 0.0),
        start_noise: Any = (0.0, 0.0, 0.0),
        terminate_on_finish: bool = True,
        reward_weights: RewardWeights | Mapping[str, float] | None = None,
        owner: str | None = None,
    ) -> None:
        who = owner or type(self).__name__
        if vessel is None:
            from shipgym.dynamics.vessel import vessel_names

            raise TypeError(
                f"{who} needs vessel=NAME or a package path; packaged vessels: "
                f"{', '.join(vessel_names())} (the shipgym/BlueLady* ids pass vessel='blue-lady')"
            )
        self.vessel = v = load_vessel(vessel)
        if not v.can_position:
            raise ValueError(
                f"{who} is a positioning task: vessel {v.name!r} cannot push itself in surge, "
                f"sway and yaw at zero speed (actuators: "
                f"{', '.join(a.label for a in v.actuators)}); steer it in "
                + ("shipgym/RudderRollStabilisation-v0, shipgym/CourseKeeping-v0 or "
                   "shipgym/SeaTrial-v0" if v.dofs == 4
                   else "shipgym/CourseKeeping-v0 or shipgym/SeaTrial-v0")
            )  # fmt: skip
        if wind is _NOMINAL:
            wind = f"{v.nominal_wind:g}@300"
        plan = self.default_plan if plan is None else plan
        self.plan = named_plan(plan) if isinstance(plan, str) else plan
        if not isinstance(self.plan, ManoeuvrePlan):
            raise ValueError(f"plan must be a plan name or a ManoeuvrePlan, got {plan!r}")
        scene = self.default_scene if scene is None else scene
        if scene not in SCENES:
            raise ValueError(f"unknown scene {scene!r}; choose one of: {', '.join(SCENES)}")
        self.scene = scene
        self.start_pose = _vec3(start_pose, "start_pose")
        self.start_noise = _vec3(start_noise, "start_noise")
        if np.any(self.start_noise < 0):
            raise ValueError(f"start_noise must be >= 0, got {start_noise!r}")
        self.reward_weights = RewardWeights.coerce(reward_weights)
        self._w = self.reward_weights.vector()
        #: per action channel, 1.0 where the command has two sides (the ``reversal`` term)
        self._two_sided = (np.asarray(v.actuators.lower, dtype=float) < 0.0).astype(float)
        if not isinstance(terminate_on_finish, bool | np.bool_):
            raise TypeError(
                f"terminate_on_finish must be True or False, got {terminate_on_finish!r}"
            )
        self.terminate_on_finish = bool(terminate_on_finish)
        # the settings given (the defaults of an episode; drawing tasks may replace them)
        self.wind = WindConfig.coerce(wind, name="wind")
        self.current = CurrentConfig.coerce(current, name="current")
        self.sensors = parse_sensors_arg(sensors)
        self.waves = parse_waves_arg(waves)
        self._terms_entry: Any = None

    def __repr__(self) -> str:
        return f"{type(self).__name__}(vessel={self.vessel.name!r}, plan={self.plan.name!r})"

    # ---- the episode's draws (overridden by the drawing tasks) ------------------------------
    def episode_plan(self, rng: np.random.Generator) -> ManoeuvrePlan:
        """The plan of an episode (drawing tasks draw it from ``rng``)."""
        return self.plan

    def episode_wind(self, rng: np.random.Generator) -> WindConfig | None:
        """The wind of an episode (``None``: no aerodynamic loads)."""
        return self.wind

    def episode_current(self, rng: np.random.Generator) -> CurrentConfig | None:
        """The current of an episode (``None``: none)."""
        return self.current

    def episode_sensors(
        self, rng: np.random.Generator, given: SensorConfig | None
    ) -> SensorConfig | None:
        """The sensor configuration of an episode (``None``: no sensors), from the ``given``
        one (the task's, or an env's own: ``ShipVectorEnv(env_sensors=)``)."""
        return given

    def initialize_episode(
        self,
        rng: np.random.Generator,
        start: Array | None = None,
        sensors: SensorConfig | None = None,
    ) -> Episode:
        """One env's episode from its generator ``rng``, in a fixed order (plan, wind,
        current, sensors, the start perturbation; the physics then draws its gusts and the
        sensors their streams from the same generator). ``start``: the start pose instead
        of :attr:`start_pose` (m, m, rad); ``sensors``: the env's own sensors instead of the
        task's."""
        start = self.start_pose if start is None else _vec3(start, "start_pose")
        plan = self.episode_plan(rng)
        wind = self.episode_wind(rng)
        current = self.episode_current(rng)
        sensors = self.episode_sensors(rng, self.sensors if sensors is None else sensors)
        eta0 = start + rng.uniform(-1.0, 1.0, 3) * self.start_noise
        return Episode(plan, wind, current, sensors, start, eta0)

    # ---- what the envs compute with it ------------------------------------------------------
    def observation_structure(self, n_actions: int) -> tuple[dict[str, slice], int]:
        """The observation's blocks by name (:data:`OBS_LAYOUT` and the previous action) and
        its length."""
        out: dict[str, slice] = {}
        i = 0
        for name, k in (*OBS_LAYOUT, ("prev_action", n_actions)):
            out[name] = slice(i, i + k)
            i += k
        return out, i

    def terms(
        self, eta: Array, nu: Array, nav_eta: Array, nav_nu: Array, ref: Array, action: Array,
        prev: Array, switched: NDArray[np.bool_], new_contact: NDArray[np.bool_],
        obs: NDArray[np.float32], rew: Array, eta_r: Array,
    ) -> None:  # fmt: skip
        """The observation (into ``obs``), the reward terms (into ``rew``, the columns of
        :data:`REWARD_TERMS`) and the true r-frame poses (into ``eta_r``) of N envs:
        :func:`plan_terms` with this task's weights; ``ref`` the reference's (N, 10, 3)
        buffer."""
        args = (eta, nu, nav_eta, nav_nu, ref, action, prev, switched, new_contact, self._w,
                self._two_sided, obs, rew, eta_r)  # fmt: skip
        if self._terms_entry is None:
            self._terms_entry = entry(plan_terms, args)
        self._terms_entry(*args)


class HarbourTask(PlanTask):
    r"""The 5-leg harbour manoeuvre of Tomera (2014) Fig. 7, from berth A to berth B, in the
    harbour (quay contact ends the episode): :class:`~shipgym.envs.tasks.HarbourEnv`."""


class StationKeepingTask(PlanTask):
    r"""Hold the start pose against wind from a perturbed start (up to 2 m and 5 deg), in open
    water, never terminating on reaching the pose: :class:`~shipgym.envs.tasks.
    StationKeepingEnv`.

    ``random_wind=(low, high)`` (m/s) draws each episode's mean wind speed uniformly in
    ``[low, high]`` and its direction uniformly from every direction (after the plan, before
    the start perturbation), keeping the gusts and spectrum of ``wind=``.
    """

    default_scene = "open-water"

    def __init__(self, vessel: Any = None, *, random_wind: Any = None, **kwargs: Any) -> None:
        kwargs.setdefault("plan", ManoeuvrePlan(legs=(Leg(name="hold"),), name="station-keeping"))
        kwargs.setdefault("start_noise", (2.0, 2.0, math.radians(5.0)))
        kwargs.setdefault("terminate_on_finish", False)
        if random_wind is not None:
            try:
                lo, hi = (float(x) for x in random_wind)
            except (TypeError, ValueError):
                raise ValueError(
                    f"random_wind must be None or (low, high) mean wind speeds in m/s, got "
                    f"{random_wind!r}"
                ) from None
            if not (0.0 <= lo <= hi <= MAX_WIND_SPEED):
                raise ValueError(
                    f"random_wind must satisfy 0 <= low <= high <= {MAX_WIND_SPEED:g} m/s, got "
                    f"{random_wind!r}"
                )
            random_wind = (lo, hi)
        self.random_wind = random_wind
        super().__init__(vessel, **kwargs)
        if random_wind is not None and self.wind is None:
            raise ValueError("random_wind needs a wind (its gusts are kept); got wind=None")

    def episode_wind(self, rng: np.random.Generator) -> WindConfig | None:
        given = self.wind
        if self.random_wind is None or given is None:
            return given
        speed = rng.uniform(*self.random_wind)
        direction = rng.uniform(0.0, 2.0 * math.pi)
        return replace_drawn(given, speed=speed, direction_from=direction)  # (validated ranges)


class TrackingTask(PlanTask):
    r"""Randomised legs, wind, current and sensor noise on open water (the training task):
    :class:`~shipgym.envs.tasks.TrackingEnv` (whose docstring gives the draws).

    ``plan=``, ``wind=``, ``current=`` and ``sensors=`` given explicitly FIX that quantity;
    the draws are made in a fixed order even for a fixed quantity (and then discarded), so
    fixing one leaves every other draw of the seed unchanged.
    """

    default_scene = "open-water"

    def __init__(
        self,
        vessel: Any = None,
        *,
        max_legs: int = 3,
        max_wind_speed: float | None = None,
        max_current_speed: float | None = None,
        randomize_sensors: bool | None = None,
        **kwargs: Any,
    ) -> None:
        v = load_vessel(vessel) if vessel is not None else None
        nominal = v.nominal_wind if v is not None else 3.0
        if max_wind_speed is None:
            max_wind_speed = 3.5 * nominal / 3.0
        if max_current_speed is None:
            max_current_speed = 0.01 * nominal
        # distances with sqrt(L): at Froude-scaled reference speeds (sqrt(L), the vessels'
        # [limits]) an episode takes about as long as the Blue Lady's and fits the time limit
        self.leg_scale = 1.0 if v is None else math.sqrt(v.L_oa / BLUE_LADY_HULL.L_oa)
        if not (isinstance(max_legs, int) and max_legs >= 1):
            raise ValueError(f"max_legs must be an int >= 1, got {max_legs!r}")
        if not (_finite_real(max_wind_speed) and 0 <= max_wind_speed <= MAX_WIND_SPEED):
            raise ValueError(
                f"max_wind_speed must be in [0, {MAX_WIND_SPEED:g}] m/s, got {max_wind_speed!r}"
            )
        if not (_finite_real(max_current_speed) and 0 <= max_current_speed <= MAX_CURRENT_SPEED):
            raise ValueError(
                f"max_current_speed must be in [0, {MAX_CURRENT_SPEED:g}] m/s, "
                f"got {max_current_speed!r}"
            )
        if randomize_sensors is not None and not isinstance(randomize_sensors, bool):
            raise ValueError(
                f"randomize_sensors must be True, False or None, got {randomize_sensors!r}"
            )
        self.max_legs = max_legs
        self.max_wind_speed = float(max_wind_speed)
        self.max_current_speed = float(max_current_speed)
        # an argument that is passed fixes its quantity; the draw is the default only
        self._draw_plan = "plan" not in kwargs
        self._draw_wind = "wind" not in kwargs
        self._draw_current = "current" not in kwargs
        # the sensor draw is made unless switched off explicitly, and used unless fixed
        self._sensor_draw = randomize_sensors is not False
        self.randomize_sensors = (
            "sensors" not in kwargs if randomize_sensors is None else randomize_sensors
        )
        kwargs.setdefault(
            "plan", ManoeuvrePlan(legs=(Leg(surge=10.0 * self.leg_scale),), name="tracking")
        )
        super().__init__(vessel, **kwargs)

    def episode_plan(self, rng: np.random.Generator) -> ManoeuvrePlan:
        k = self.leg_scale
        legs = []
        for i in range(int(rng.integers(1, self.max_legs + 1))):
            kind = int(rng.integers(4))
            side = 1.0 if rng.random() < 0.5 else -1.0
            if kind == 0:
                leg = Leg(sway=side * rng.uniform(2.0, 8.0) * k, name=f"{i + 1}: lateral")
            elif kind == 1:
                dist = rng.uniform(5.0, 30.0) if side > 0 else -rng.uniform(3.0, 15.0)
                leg = Leg(surge=dist * k, name=f"{i + 1}: longitudinal")
            elif kind == 2:
                yaw = side * math.radians(rng.uniform(30.0, 120.0))
                leg = Leg(yaw=yaw, name=f"{i + 1}: rotation")
            else:
                leg = Leg(
                    surge=rng.uniform(3.0, 15.0) * k, sway=side * rng.uniform(2.0, 5.0) * k,
                    name=f"{i + 1}: combined",
                )  # fmt: skip
            legs.append(leg)
        if not self._draw_plan:  # drawn all the same (same stream), then discarded
            return self.plan
        return ManoeuvrePlan(legs=tuple(legs), name="tracking")

    def episode_wind(self, rng: np.random.Generator) -> WindConfig | None:
        speed = rng.uniform(0.0, self.max_wind_speed)  # drawn even when fixed (same stream)
        direction = rng.uniform(0.0, 2.0 * math.pi)
        if not self._draw_wind:
            return self.wind
        # WindConfig(speed=, direction_from=) of the drawn values (in the ranges checked when
        # the task was made: its validation not run again every reset)
        return replace_drawn(_CALM_WIND, speed=speed, direction_from=direction)

    def episode_current(self, rng: np.random.Generator) -> CurrentConfig | None:
        if self.max_current_speed == 0.0:  # no draw: the random stream stays as without current
            return self.current
        speed = rng.uniform(0.0, self.max_current_speed)
        direction = rng.uniform(0.0, 2.0 * math.pi)
        if not self._draw_current:
            return self.current
        return replace_drawn(_STILL_WATER, speed=speed, direction_to=direction)  # (as above)

    def episode_sensors(
        self, rng: np.random.Generator, given: SensorConfig | None
    ) -> SensorConfig | None:
        if given is None or not self._sensor_draw:  # no sensors, or no draw: as given
            return given
        pos = rng.uniform(0.07, 0.15)  # drawn even when fixed (same stream)
        psi = math.radians(rng.uniform(0.2, 0.45))
        if not self.randomize_sensors:
            return given
        return replace_drawn(given, position_variance=pos * pos, heading_variance=psi * psi)


# ---- argument parsing (the boundary: coerced once here) ------------------------------------
def parse_sensors_arg(sensors: Any) -> SensorConfig | None:
    """Accept ``None`` (no sensors), a preset name, a :class:`SensorConfig` or a mapping."""
    if sensors is None or isinstance(sensors, SensorConfig):
        return sensors
    if isinstance(sensors, str):
        return sensor_config(sensors)
    if isinstance(sensors, Mapping):
        return SensorConfig.from_dict(sensors)
    raise ValueError(
        f"sensors must be None, a preset name, a SensorConfig or a mapping, got {sensors!r}"
    )


def parse_waves_arg(waves: Any) -> WaveConfig | None:
    """Accept ``None``, a :class:`WaveConfig`, a preset name (``WAVE_PRESETS``) or a mapping."""
    if waves is None or isinstance(waves, WaveConfig):
        return waves
    if isinstance(waves, str):
        from shipgym.scenarios import WAVE_PRESETS

        if waves not in WAVE_PRESETS:
            raise ValueError(
                f"unknown wave preset {waves!r}; choose one of: {', '.join(WAVE_PRESETS)}"
            )
        preset = WAVE_PRESETS[waves]
        return preset() if callable(preset) else preset
    if isinstance(waves, Mapping):
        return WaveConfig.from_dict(waves)
    raise ValueError(f"waves must be None, a WaveConfig, a preset name or a mapping: {waves!r}")


def _vec3(x: Any, name: str) -> Array:
    """A pose-like triple (m, m, rad): finite, each |component| <= :data:`MAX_START_OFFSET`."""
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be three finite numbers (m, m, rad), got {x!r}") from None
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be three finite numbers (m, m, rad), got {x!r}")
    if np.any(np.abs(a) > MAX_START_OFFSET):
        raise ValueError(
            f"{name} must be within +-{MAX_START_OFFSET:g} (m, m, rad), got {x!r}: MuJoCo resets "
            "positions beyond 1e10 to the origin, and nothing shipgym models is that far out"
        )
    return a


def _finite_real(x: Any) -> bool:
    return is_real(x) and math.isfinite(x)
