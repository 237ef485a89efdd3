r"""Sea trials: the IMO manoeuvres of a ship with a rudder, scripted, measured by the truth
and by a DGPS receiver (IMO MSC.137(76) (2002); Artyszuk 2003).

:class:`SeaTrialEnv` runs one manoeuvre of :data:`shipgym.trials.manoeuvres.MANOEUVRES` per
episode on any vessel with a rudder: the scripts of :mod:`shipgym.trials.manoeuvres` command
the rudder and the main propeller, the vessel's actuators (rate limits, the shaft's ramp)
carry them out, and at the end of the episode the trial's figures
(:func:`shipgym.trials.metrics.trial_metrics`) and the IMO criteria
(:func:`~shipgym.trials.metrics.imo_criteria`) are in ``info``. With ``receiver="dgps-pv"``
the observation also holds what the ship's DGPS receiver says (:class:`~shipgym.observers.
dgps.DGPSReceiver`: 2 m noise at 1 Hz, the printed PV Kalman filter), biased as Artyszuk
(2003) found. :func:`run_trial` is the script-only form (no Gymnasium loop) that the
``shipgym trials`` command uses.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from shipgym._config import is_real
from shipgym.disturbances import CurrentConfig
from shipgym.dynamics.mmg import MMGHull
from shipgym.dynamics.vessel import Vessel, load_vessel
from shipgym.observers.dgps import S_P_OPTIMAL, DGPSReceiver
from shipgym.trials.manoeuvres import manoeuvre, manoeuvre_names
from shipgym.trials.metrics import imo_criteria, trial_metrics

from .base import TopCameraRender, _check_render_mode, _check_timing, _whole_multiple
from .physics import VesselPhysics

__all__ = [
    "RECEIVERS",
    "SeaTrialEnv",
    "TrialRecord",
    "TankerSeaTrialEnv",
    "TrialStudy",
    "approach_command",
    "run_trial",
    "trial_study",
]

#: the receivers a trial can carry: none, the DGPS receiver's PV Kalman filter
RECEIVERS = (None, "dgps-pv")

#: the observation's entries, in order (the last four only with a receiver)
OBSERVATION = ("x/L", "y/L", "sin psi", "cos psi", "u/U0", "v/U0", "r L/U0", "rudder/max",
               "shaft/n0", "v_xy_hat/U0", "beta_A_hat", "x_hat/L", "y_hat/L")  # fmt: skip


def approach_command(physics: VesselPhysics, shaft: int, U0: float) -> float:
    """The command of the shaft channel ``shaft`` that holds ``U0`` (m/s) in straight running.

    The MMG hull's self-propulsion point (:meth:`~shipgym.dynamics.mmg.MMGModel.
    self_propulsion`), else the root of the straight-running surge acceleration of the
    plant under that command alone (the other channels at rest).

    Raises:
        ValueError: the shaft cannot hold ``U0`` within its command range.
    """
    from scipy.optimize import brentq

    plant = physics.plant
    if isinstance(plant, MMGHull):
        return plant.model.self_propulsion(U0)
    acts = physics.actuators
    st0 = physics.initial_actuator_state()
    four = physics.dofs == 4
    nu = np.array([U0, 0.0, 0.0, 0.0]) if four else np.array([U0, 0.0, 0.0])

    def surge(c: float) -> float:
        st = st0.copy()
        st[shaft] = c
        tau = acts.tau(st, nu if acts.flow_dependent else None)
        if four:
            return float(plant.nu_dot(nu, tau, np.zeros(2), 0.0)[0])
        return float(plant.nu_dot(nu, tau)[0])

    hi = float(acts.upper[shaft])
    if not surge(0.0) < 0.0 < surge(hi):
        raise ValueError(
            f"the shaft {acts.channel_names[shaft]!r} of {physics.vessel.name!r} cannot hold "
            f"{U0:g} m/s within its range [0, {hi:g}]"
        )
    return float(brentq(surge, 0.0, hi, xtol=1e-12))


@dataclass(frozen=True)
class TrialRecord:
    """One trial's true motion, over ground (SI).

    Attributes:
        vessel, manoeuvre: names. L: length between perpendiculars (m); U0: approach speed
        (m/s); n0: approach shaft command (its channel's unit; ``nan`` without a shaft);
        current: ``(speed m/s, direction it goes to, rad)``; t (s), eta ``[x, y, psi]``, nu
        ``[u, v, r]`` over ground (n, 3); rudder: the rudder angle (rad, shipgym's sign);
        shaft: the shaft state (n,) (``nan`` without one).
    """

    vessel: str
    manoeuvre: str
    L: float
    U0: float
    n0: float
    current: tuple[float, float]
    t: NDArray[np.float64] = field(repr=False)
    eta: NDArray[np.float64] = field(repr=False)
    nu: NDArray[np.float64] = field(repr=False)
    rudder: NDArray[np.float64] = field(repr=False)
    shaft: NDArray[np.float64] = field(repr=False)

    def metrics(self) -> Any:
        """:func:`~shipgym.trials.metrics.trial_metrics` of this record."""
        return trial_metrics(self.manoeuvre, self.t, self.eta, self.nu, self.L, self.U0,
                             delta=self.rudder)  # fmt: skip

    def criteria(self) -> list[tuple[str, float, float, bool]]:
        """:func:`~shipgym.trials.metrics.imo_criteria` of this record's metrics."""
        return imo_criteria(self.metrics(), self.L, self.U0)


class SeaTrialEnv(TopCameraRender, gym.Env[NDArray[np.float32], Any]):
    r"""One IMO manoeuvre per episode, scripted, on a vessel with a rudder.

    **Physics.** The vessel's MuJoCo hull (:class:`~shipgym.envs.physics.VesselPhysics`),
    physics step ``timestep`` (0.05 s); a constant current (``current``, any form of
    :meth:`CurrentConfig.coerce <shipgym.disturbances.CurrentConfig.coerce>`, e.g.
    ``"0.25@225"``: 0.25 m/s going south-west); optional wind. The ship starts at ``eta = 0``
    (heading north) running straight at the approach speed ``U0`` through the water
    (``speed``, default :attr:`Vessel.approach_speed <shipgym.dynamics.vessel.Vessel.
    approach_speed>`) with its main propeller at the
    command that holds it (:func:`approach_command`) and the rudder amidships.

    **Task.** ``manoeuvre``: one of :func:`~shipgym.trials.manoeuvres.manoeuvre_names`
    (``turning35_stbd``, ``turning35_port``, ``zigzag10``, ``zigzag20``, ``initial_turning``,
    ``crash_stop``, ``coasting_stop``). Its script commands the first rudder
    (:attr:`Vessel.rudders <shipgym.dynamics.vessel.Vessel.rudders>`) and the first main
    propeller (:attr:`~shipgym.dynamics.vessel.Vessel.shafts`, as a fraction of the approach
    command) every control step; a stopping manoeuvre needs a main propeller. The episode
    ends (``terminated``) after the manoeuvre's duration
    (:meth:`~shipgym.trials.manoeuvres.TurningCircle.duration`, a multiple of ``L/U0``).

    **Action.** ``override=False`` (default): ``Discrete(1)``, the only action (0) lets the
    script act. ``override=True``: the normalised command of every channel, ``Box(-1, 1,
    (n_channels,))`` (:meth:`ActuatorSet.action_to_command <shipgym.dynamics.actuators.
    ActuatorSet.action_to_command>`), and the script is not used: a controller flies the
    trial (the figures are computed the same way).

    **Observation** (float32, :data:`OBSERVATION`): ``x/L``, ``y/L``, ``sin psi``, ``cos
    psi``, ``u/U0``, ``v/U0``, ``r L/U0`` over ground, the rudder angle over its largest, the
    shaft state over ``n0`` (0 without a shaft); with ``receiver="dgps-pv"`` also the
    receiver's track speed ``v_xy/U0``, drift angle ``beta_A`` (rad, ``psi - course``) and
    position ``x_hat/L``, ``y_hat/L``, refreshed at its 1 Hz (held in between).

    **Reward.** 0 (an evaluation task): ``info["reward_terms"]`` is empty.

    **Info.** ``t`` (s), ``eta`` (the true pose), ``speed`` (m/s) and ``drift`` (rad) over
    ground, ``rudder`` (rad), ``rudder_command`` (rad), ``shaft`` (``None`` without one),
    ``rate_limited``, ``saturated``, ``clipped`` (``override``: an
    action outside ``[-1, 1]``), with a receiver ``receiver`` (its outputs); at the end
    ``trial`` (the figures, :meth:`TrialMetrics.as_dict <shipgym.trials.metrics.TrialMetrics.
    as_dict>`), ``imo`` (criterion, value, limit, passed) and ``episode_metrics``.

    Args:
        vessel: a vessel with a rudder (name, path or :class:`~shipgym.dynamics.vessel.
            Vessel`); the registered id uses ``kvlcc2-100m``.
        manoeuvre: the manoeuvre's name.
        speed: approach speed (m/s), ``None``: the vessel's.
        current: a constant current or ``None``.
        wind: wind (any form of ``VesselPhysics(wind=)``) or ``None``.
        receiver: ``None`` or ``"dgps-pv"``.
        S_p: the receiver filter's spectral amplitude (m^2/s^3), 0.01 the seed's optimum.
        antenna: the antenna ``[x, y]`` (m, body frame, from the hull's origin).
        receiver_sigma: the receiver's position noise (m per axis; 0: noise-free).
        override: the action drives the actuators instead of the script.
        timestep: physics step (s). control_period: s, a whole multiple of ``timestep``
            dividing the receiver's 1 s (1 s).
        render_mode: ``None`` or ``"rgb_array"``.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(
        self,
        vessel: str | Vessel | Any,
        manoeuvre: str = "turning35_stbd",
        *,
        speed: float | None = None,
        current: Any = None,
        wind: Any = None,
        receiver: str | None = None,
        S_p: float = S_P_OPTIMAL,
        antenna: Any = (0.0, 0.0),
        receiver_sigma: float = 2.0,
        override: bool = False,
        timestep: float = 0.05,
        control_period: float = 1.0,
        render_mode: str | None = None,
    ) -> None:
        super().__init__()
        v = load_vessel(vessel)
        if not v.rudders:
            raise ValueError(
                f"vessel {v.name!r} has no rudder: a sea trial steers with one (choose e.g. "
                "kvlcc2-100m, naval-vessel)"
            )
        self.base_vessel = v
        self.manoeuvre = _manoeuvre(manoeuvre)
        U0 = v.approach_speed if speed is None else speed
        if U0 is None:
            raise ValueError(
                f"vessel {v.name!r} has no approach speed ([trials] approach_speed): pass "
                "speed=... (m/s)"
            )
        if not (is_real(U0) and math.isfinite(U0) and U0 > 0):
            raise ValueError(f"speed must be > 0 m/s, got {U0!r}")
        self.U0 = float(U0)
        if receiver not in RECEIVERS:
            raise ValueError(f"unknown receiver {receiver!r}; choose None or 'dgps-pv'")
        self.receiver_name = receiver
        _check_render_mode(render_mode, self.metadata)
        self.render_mode = render_mode
        _check_timing(timestep, control_period)
        self.n_sub = _whole_multiple(control_period, timestep)
        self.control_period = float(control_period)
        if receiver is not None:
            per = 1.0 / self.control_period
            if abs(per - round(per)) > 1e-9:
                raise ValueError(
                    f"control_period {control_period} s must divide the receiver's 1 s sample"
                )
            self._rx_every = round(per)
        cfg = CurrentConfig.coerce(current, name="current")
        if cfg is not None and not cfg.is_constant:
            raise ValueError("a sea trial's current must be constant (a speed and a direction)")
        self.current = (0.0, 0.0) if cfg is None else (float(cfg.speed), float(cfg.direction_to))
        self.physics = VesselPhysics(v, current=cfg, wind=wind, timestep=timestep)
        chans = list(self.physics.actuators.channel_names)
        self._rudder = chans.index(v.rudders[0])
        self._shaft = chans.index(v.shafts[0]) if v.shafts else None
        kind = getattr(self.manoeuvre, "kind", "")
        if self._shaft is None and kind == "stop":
            raise ValueError(
                f"{self.manoeuvre.name!r} needs a main propeller and {v.name!r} has none "
                f"(its actuators: {', '.join(chans)})"
            )
        self.n0 = (
            approach_command(self.physics, self._shaft, self.U0)
            if self._shaft is not None
            else math.nan
        )
        self.L = float(v.L_pp)
        self.duration = float(self.manoeuvre.duration(self.L, self.U0))
        self.max_steps = math.ceil(self.duration / self.control_period - 1e-9)
        self.override = bool(override)
        n_ch = self.physics.actuators.n_channels
        self.action_space: spaces.Space[Any] = (
            spaces.Box(-1.0, 1.0, (n_ch,), dtype=np.float32) if override else spaces.Discrete(1)
        )
        n_obs = 9 + (4 if receiver else 0)
        self.observation_space = spaces.Box(-np.inf, np.inf, (n_obs,), dtype=np.float32)
        self.S_p = float(S_p)
        self.antenna = tuple(float(a) for a in np.asarray(antenna, dtype=float).reshape(2))
        self.receiver_sigma = float(receiver_sigma)
        self._max_angle = float(self.physics.actuators.upper[self._rudder])
        self._renderer = None
        self._rx: DGPSReceiver | None = None
        self._rx_out: Any = None
        self._hist: dict[str, list[Any]] = {}
        self._k = 0
        self._done = True

    # ---- episode ---------------------------------------------------------------------------
    def _initial_nu(self) -> NDArray[np.float64]:
        """Straight running at ``U0`` through the water: over ground plus the current."""
        vc, bc = self.current
        return np.array([self.U0 + vc * math.cos(bc), vc * math.sin(bc), 0.0])

    def reset(
        self, *, seed: int | None = None, options: Mapping[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        if options:
            raise ValueError(f"SeaTrialEnv.reset takes no options, got {dict(options)!r}")
        phys = self.physics
        act = phys.initial_actuator_state()
        if self._shaft is not None:
            act[self._shaft] = self.n0
        nu0 = self._initial_nu()
        ss = self.np_random.bit_generator.random_raw(2)
        phys.reset(eta=(0.0, 0.0, 0.0), nu=nu0, actuators=act,
                   rng=np.random.default_rng(int(ss[0])))  # fmt: skip
        self._command = act.copy()
        phys.set_command(self._command)
        self.script = self.manoeuvre.script()
        self.script.reset(0.0)
        if self.receiver_name is not None:
            self._rx = DGPSReceiver(self.S_p, sigma=self.receiver_sigma, antenna=self.antenna,
                                    rng=np.random.default_rng(int(ss[1])))  # fmt: skip
            self._rx_out = self._rx.reset(phys.eta, nu0)
        self._hist = {"t": [], "eta": [], "nu": [], "rudder": [], "shaft": []}
        self._record()
        self._k = 0
        self._done = False
        return self._observe(), self._info(np.zeros(1, dtype=bool))

    def _record(self) -> None:
        phys = self.physics
        h = self._hist
        st = phys.actuator_state
        h["t"].append(phys.time)
        h["eta"].append(phys.eta)
        h["nu"].append(phys.nu)
        h["rudder"].append(float(st[self._rudder]))
        h["shaft"].append(float(st[self._shaft]) if self._shaft is not None else math.nan)

    def step(self, action: Any) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        if self._done:
            raise RuntimeError("the trial has ended: call reset() first")
        phys = self.physics
        clipped = np.zeros(1, dtype=bool)
        if self.override:
            a = np.asarray(action, dtype=float)
            if a.shape != self.action_space.shape or not np.all(np.isfinite(a)):
                raise ValueError(
                    f"action must be {self.action_space.shape} finite numbers in [-1, 1] "
                    f"({', '.join(phys.actuators.channel_names)}), got {action!r}"
                )
            clipped = np.abs(a) > 1.0
            cmd = phys.actuators.action_to_command(np.clip(a, -1.0, 1.0))
        else:
            if not self.action_space.contains(action):
                raise ValueError(f"action must be 0 (the script acts), got {action!r}")
            eta = phys.eta
            rud, frac = self.script.command(phys.time, float(eta[2]), float(phys.nu[0]))
            cmd = self._command.copy()
            cmd[self._rudder] = rud
            if self._shaft is not None:
                cmd[self._shaft] = frac * self.n0
        self._command = np.asarray(cmd, dtype=float)
        phys.set_command(self._command)
        phys.step(self.n_sub)
        self._k += 1
        if self._rx is not None and self._k % self._rx_every == 0:
            self._rx_out = self._rx.update(phys.eta)
        self._record()
        terminated = self._k >= self.max_steps
        info = self._info(clipped)
        if terminated:
            self._done = True
            rec = self.record()
            m = rec.metrics()
            info["trial"] = m.as_dict()
            info["imo"] = imo_criteria(m, self.L, self.U0)
            info["episode_metrics"] = self.episode_metrics()
        return self._observe(), 0.0, terminated, False, info

    def _info(self, clipped: NDArray[np.bool_]) -> dict[str, Any]:
        phys = self.physics
        u, v, _r = phys.nu.tolist()
        st = phys.actuator_state
        info: dict[str, Any] = {
            "t": phys.time,
            "eta": phys.eta,
            "manoeuvre": self.manoeuvre.name,
            "speed": math.hypot(u, v),
            "drift": math.atan2(-v, u),
            "rudder": float(st[self._rudder]),
            "rudder_command": float(phys.command[self._rudder]),
            "shaft": float(st[self._shaft]) if self._shaft is not None else None,
            "rate_limited": bool(phys.rate_limited.any()),
            "saturated": bool(phys.saturated.any()),
            "clipped": bool(np.any(clipped)),
            "reward_terms": {},
        }
        if self._rx_out is not None:
            o = self._rx_out
            info["receiver"] = {
                "v_ns": float(o.v_ns), "v_ew": float(o.v_ew), "x": float(o.x_hat),
                "y": float(o.y_hat), "v_xy": float(o.v_xy), "chi": float(o.chi),
                "beta_A": float(o.beta_A),
            }  # fmt: skip
        return info

    def _observe(self) -> NDArray[np.float32]:
        phys = self.physics
        x, y, psi = phys.eta.tolist()
        u, v, r = phys.nu.tolist()
        st = phys.actuator_state
        L, U0 = self.L, self.U0
        shaft = float(st[self._shaft]) / self.n0 if self._shaft is not None and self.n0 else 0.0
        obs = [x / L, y / L, math.sin(psi), math.cos(psi), u / U0, v / U0, r * L / U0,
               float(st[self._rudder]) / self._max_angle, shaft]  # fmt: skip
        if self._rx_out is not None:
            o = self._rx_out
            obs += [float(o.v_xy) / U0, float(o.beta_A), float(o.x_hat) / L, float(o.y_hat) / L]
        return np.array(obs, dtype=np.float32)

    def record(self) -> TrialRecord:
        """The true motion recorded so far (every control step)."""
        h = self._hist
        if not h:
            raise RuntimeError("call reset() first")
        return TrialRecord(
            vessel=self.base_vessel.name, manoeuvre=self.manoeuvre.name, L=self.L, U0=self.U0,
            n0=self.n0, current=self.current, t=np.array(h["t"]), eta=np.array(h["eta"]),
            nu=np.array(h["nu"]), rudder=np.array(h["rudder"]), shaft=np.array(h["shaft"]),
        )  # fmt: skip

    def episode_metrics(self) -> dict[str, Any]:
        """The trial's figures so far (SI) and whether every IMO criterion passed."""
        rec = self.record()
        m = rec.metrics()
        crit = imo_criteria(m, self.L, self.U0)
        return {**m.as_dict(), "imo_pass": all(c[3] for c in crit) if crit else None}


class TankerSeaTrialEnv(SeaTrialEnv):
    """``shipgym/SeaTrial-v0``: :class:`SeaTrialEnv` on the seed's 100 m tanker
    (``kvlcc2-100m``) unless ``vessel=`` says otherwise."""

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("vessel", "kvlcc2-100m")
        super().__init__(**kwargs)


def _manoeuvre(name: Any) -> Any:
    if not isinstance(name, str):
        raise ValueError(f"manoeuvre must be a name, one of {', '.join(manoeuvre_names())}")
    return manoeuvre(name)


def run_trial(
    vessel: str | Vessel | Any,
    manoeuvre: str,
    *,
    speed: float | None = None,
    current: Any = None,
    timestep: float = 0.05,
    record_period: float | None = None,
) -> TrialRecord:
    """Fly one scripted manoeuvre and return its true motion (:class:`TrialRecord`).

    Args:
        vessel, manoeuvre, speed, current, timestep: as for :class:`SeaTrialEnv`.
        record_period: the record's sample time (s), a whole multiple of ``timestep``; the
            script acts at this period too (``None``: every physics step, so that a zig-zag's
            rudder is reversed within one step of the heading reaching the angle).
    """
    period = timestep if record_period is None else record_period
    env = SeaTrialEnv(vessel, manoeuvre, speed=speed, current=current, timestep=timestep,
                      control_period=period)  # fmt: skip
    env.reset(seed=0)
    done = False
    while not done:
        _, _, done, _, _ = env.step(0)
    return env.record()


def _until_stopped(rec: TrialRecord) -> TrialRecord:
    """A stopping manoeuvre's record up to the stop (``u <= 0``): after it the ship goes
    astern, and its drift angle and course mean nothing."""
    u = rec.nu[:, 0]
    stop = np.nonzero(u <= 0.0)[0]
    if not stop.size:
        return rec
    k = int(stop[0]) + 1
    return TrialRecord(rec.vessel, rec.manoeuvre, rec.L, rec.U0, rec.n0, rec.current,
                       rec.t[:k], rec.eta[:k], rec.nu[:k], rec.rudder[:k],
                       rec.shaft[:k])  # fmt: skip


@dataclass(frozen=True)
class TrialStudy:
    """The result of :func:`trial_study`: the records, the trial rows (SI, with the IMO
    criteria), the receiver-bias rows (SI) and the :class:`~shipgym.trials.bias.ReceiverBias`
    objects by ``(manoeuvre, S_p or "raw", corrected)``."""

    records: dict[str, TrialRecord]
    rows: list[dict[str, Any]]
    bias_rows: list[dict[str, Any]]
    bias: dict[tuple[str, float, bool], Any]


def trial_study(
    vessel: str | Vessel | Any,
    manoeuvres: list[str] | None = None,
    *,
    speed: float | None = None,
    current: Any = None,
    receiver: str | None = None,
    S_p: list[float] | tuple[float, ...] = (0.001, 0.01, 0.1),
    runs: int = 50,
    seed: int = 0,
    antenna: Any = (0.0, 0.0),
    timestep: float = 0.05,
    progress: Any = None,
) -> TrialStudy:
    """Run manoeuvres (all by default) and, with ``receiver="dgps-pv"``, the receiver-bias
    study of Artyszuk (2003) on each: per ``S_p`` the bias of the noise-free run and the noise
    of ``runs`` Monte-Carlo runs (:func:`shipgym.trials.bias.receiver_bias`), ground-referenced
    and, with a current, also water-referenced (the seed's correction); and the same for the
    seed's recommended alternative, the raw positions differentiated (key ``"raw"`` in
    :attr:`TrialStudy.bias`). A stopping manoeuvre's bias is measured up to the stop.

    Args:
        vessel, speed, current, timestep: as for :class:`SeaTrialEnv`.
        manoeuvres: names (``None``: every one the vessel can fly).
        receiver: ``None`` or ``"dgps-pv"``. S_p: the filter settings (m^2/s^3).
        runs, seed: the Monte Carlo. antenna: ``[x, y]`` (m, body frame).
        progress: optional callable ``progress(done, total, label)``.
    """
    from shipgym.trials.bias import receiver_bias
    from shipgym.trials.report import bias_row, trial_row

    v = load_vessel(vessel)
    if receiver not in RECEIVERS:
        raise ValueError(f"unknown receiver {receiver!r}; choose None or 'dgps-pv'")
    names = manoeuvres
    if names is None:
        names = [m for m in manoeuvre_names() if v.shafts or manoeuvre(m).kind != "stop"]
    for m in names:
        manoeuvre(m)  # unknown names fail before any work
    sps = [float(s) for s in S_p]
    for s in sps:
        if not (math.isfinite(s) and s > 0):
            raise ValueError(f"S_p must be > 0 m^2/s^3, got {s!r}")
    records: dict[str, TrialRecord] = {}
    rows, brows, bias = [], [], {}
    for i, m in enumerate(names):
        rec = run_trial(v, m, speed=speed, current=current, timestep=timestep)
        records[m] = rec
        met = rec.metrics()
        rows.append(trial_row(v.name, met, imo_criteria(met, rec.L, rec.U0), rec.L, rec.U0,
                              rec.current))  # fmt: skip
        if receiver is not None:
            cut = _until_stopped(rec) if manoeuvre(m).kind == "stop" else rec
            modes = [False, True] if rec.current[0] > 0 else [False]
            for s in [*sps, "raw"]:
                for corr in modes:
                    b = receiver_bias(
                        cut.t, cut.eta, cut.nu, S_p=sps[0] if s == "raw" else s, runs=runs,
                        seed=seed, antenna=antenna, current=_seed_current(rec.current),
                        correct=corr, method="raw" if s == "raw" else "dgps-pv",
                    )  # fmt: skip
                    bias[(m, s, corr)] = b
                    brows.append(bias_row(v.name, m, b, antenna=antenna, current=rec.current))
        if progress is not None:
            progress(i + 1, len(names), m)
    return TrialStudy(records, rows, brows, bias)


def _seed_current(current: tuple[float, float]) -> tuple[float, float] | None:
    """The current in the seed's convention (Artyszuk 2003 §1: ``gamma_c = 0`` a current
    towards north, the same as shipgym's direction it goes to)."""
    return None if current[0] == 0.0 else (current[0], current[1])
