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
(2003) found. The family is written once, batched: :class:`SeaTrialVectorEnv` steps N
trials (``gymnasium.make_vec``), and :class:`SeaTrialEnv` is its batch of one.
:func:`run_trials` flies several manoeuvres as one batch without a Gymnasium loop (the
``shipgym trials`` command); :func:`run_trial` one.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from shipgym._config import is_real
from shipgym.disturbances import CurrentConfig
from shipgym.dynamics.actuators import MMGPropulsion
from shipgym.dynamics.mmg import MMGHull, with_rudder
from shipgym.dynamics.vessel import Vessel, load_vessel
from shipgym.observers.dgps import S_P_OPTIMAL, DGPSOutput, DGPSReceiver
from shipgym.trials.manoeuvres import Scripts, manoeuvre, manoeuvre_names
from shipgym.trials.metrics import TrialMetrics, imo_criteria, trial_metrics

from .batchphysics import BatchedPhysics
from .stepped import StepTask, TaskEnv, TaskSingleEnv

__all__ = [
    "RECEIVERS",
    "SeaTrialEnv",
    "SeaTrialTask",
    "SeaTrialVectorEnv",
    "TrialRecord",
    "TankerSeaTrialEnv",
    "TrialStudy",
    "approach_command",
    "run_trial",
    "run_trials",
    "sea_trial_vector_env",
    "steady_speed",
    "trial_study",
]

#: the receivers a trial can carry: none, the DGPS receiver's PV Kalman filter
RECEIVERS = (None, "dgps-pv")

#: the observation's entries, in order (the last four only with a receiver)
OBSERVATION = ("x/L", "y/L", "sin psi", "cos psi", "u/U0", "v/U0", "r L/U0", "rudder/max",
               "shaft/n0", "v_xy_hat/U0", "beta_A_hat", "x_hat/L", "y_hat/L")  # fmt: skip

#: ``info["receiver"]``'s keys: the receiver's outputs (:class:`~shipgym.observers.dgps.
#: DGPSOutput` fields)
_RX_KEYS = {"v_ns": "v_ns", "v_ew": "v_ew", "x": "x_hat", "y": "y_hat", "v_xy": "v_xy",
            "chi": "chi", "beta_A": "beta_A"}  # fmt: skip


def _surge_acceleration(physics: BatchedPhysics, shaft: int, command: float, U: float) -> float:
    """The surge acceleration (m/s^2) of straight running at ``U`` (m/s) with the shaft channel
    ``shaft`` at ``command`` and the other channels at rest: the MMG hull's equations
    (:meth:`~shipgym.dynamics.mmg.MMGModel.nu_dot`), else the plant under the actuators'
    generalised force."""
    plant = physics.plant
    if isinstance(plant, MMGHull):
        return float(plant.model.nu_dot([U, 0.0, 0.0], 0.0, command)[0])
    acts = physics.actuators
    st = acts.initial_state()
    st[shaft] = command
    four = physics.dofs == 4
    nu = np.array([U, 0.0, 0.0, 0.0]) if four else np.array([U, 0.0, 0.0])
    tau = acts.tau(st, nu if acts.flow_dependent else None)
    if four:
        return float(plant.nu_dot(nu, tau, np.zeros(2), 0.0)[0])
    return float(plant.nu_dot(nu, tau)[0])


def approach_command(physics: BatchedPhysics, shaft: int, U0: float) -> float:
    """The command of the shaft channel ``shaft`` that holds ``U0`` (m/s) in straight running.

    The MMG hull's self-propulsion point (:meth:`~shipgym.dynamics.mmg.MMGModel.
    self_propulsion`), else the root of the straight-running surge acceleration of the
    plant under that command alone (the other channels at rest).

    Raises:
        ValueError: the shaft cannot hold ``U0`` within its command range.
    """
    from scipy.optimize import brentq

    if isinstance(physics.plant, MMGHull):
        return physics.plant.model.self_propulsion(U0)
    acts = physics.actuators

    def surge(c: float) -> float:
        return _surge_acceleration(physics, shaft, c, U0)

    hi = float(acts.upper[shaft])
    if not surge(0.0) < 0.0 < surge(hi):
        raise ValueError(
            f"the shaft {acts.channel_names[shaft]!r} of {physics.vessel.name!r} cannot hold "
            f"{U0:g} m/s within its range [0, {hi:g}]"
        )
    return float(brentq(surge, 0.0, hi, xtol=1e-12))


def steady_speed(physics: BatchedPhysics, shaft: int, command: float, U0: float) -> float:
    """The straight-running speed (m/s) that the shaft channel ``shaft`` holds at
    ``command`` (the root of the surge acceleration in ``(0, 2 U0]``; the MMG hull's
    equations directly, :meth:`~shipgym.dynamics.mmg.MMGModel.nu_dot`).

    Raises:
        ValueError: no such speed up to ``2 U0``.
    """
    from scipy.optimize import brentq

    def surge(U: float) -> float:
        return _surge_acceleration(physics, shaft, command, U)

    lo, hi = 1e-3 * U0, 2.0 * U0
    if not surge(lo) > 0.0 > surge(hi):
        raise ValueError(f"the shaft command {command:g} holds no speed in (0, {hi:g}] m/s")
    return float(brentq(surge, lo, hi, xtol=1e-12))


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

    def water_referenced(self) -> TrialRecord:
        """The same trial referenced to the water (the ITTC way, ITTC 7.5-04-02-01):
        the track less the current's drift since the start, ``[x, y] - V_c [cos gamma_c,
        sin gamma_c] (t - t_0)``, and the body velocity through the water, ``u - V_c
        cos(gamma_c - psi)``, ``v - V_c sin(gamma_c - psi)`` (Artyszuk 2003 section 1, the
        current constant in NED); ``current`` then ``(0, 0)``. Without a current: this record."""
        V, g = self.current
        if V == 0.0:
            return self
        dt = self.t - self.t[0]
        eta = self.eta.copy()
        eta[:, 0] -= V * math.cos(g) * dt
        eta[:, 1] -= V * math.sin(g) * dt
        psi = self.eta[:, 2]
        nu = self.nu.copy()
        nu[:, 0] -= V * np.cos(g - psi)
        nu[:, 1] -= V * np.sin(g - psi)
        return dataclasses.replace(self, eta=eta, nu=nu, current=(0.0, 0.0))


class SeaTrialTask(StepTask):
    r"""The sea trials over N >= 1 envs (:class:`SeaTrialEnv` is the spec; the arguments are
    its own, ``manoeuvre`` a name or ``num_envs`` names), stepped by
    :class:`SeaTrialVectorEnv`. An episode ends (terminates) when its manoeuvre's duration
    is flown; no reward."""

    def __init__(
        self,
        num_envs: int,
        vessel: str | Vessel | Any,
        manoeuvre: str | Sequence[str] = "turning35_stbd",
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
    ) -> None:
        v = load_vessel(vessel)
        if not v.rudders:
            raise ValueError(
                f"vessel {v.name!r} has no rudder: a sea trial steers with one (choose e.g. "
                "kvlcc2-100m, naval-vessel)"
            )
        names = [manoeuvre] * num_envs if isinstance(manoeuvre, str) else list(manoeuvre)
        if isinstance(num_envs, int) and len(names) != num_envs:
            raise ValueError(f"manoeuvre must be a name or {num_envs} names, got {manoeuvre!r}")
        self.manoeuvres = [_manoeuvre(m) for m in names]
        options = {m.rudder for m in self.manoeuvres}
        if len(options) > 1:
            raise ValueError(
                "the manoeuvres of one batch must use the same rudder (run_trials groups "
                f"them), got {sorted(str(o) for o in options)}"
            )
        #: the rudder option of the manoeuvres (None: the vessel's own rudder)
        self.rudder_option = options.pop()
        if self.rudder_option is not None:
            v = with_rudder(v, self.rudder_option)
        self.base_vessel = v
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
        self.set_timing(timestep, control_period, None)
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
        self.physics = phys = BatchedPhysics(v, num_envs, wind=wind, current=cfg,
                                             timestep=timestep)  # fmt: skip
        acts = phys.actuators
        chans = list(acts.channel_names)
        self._rudder = chans.index(v.rudders[0])
        self._shaft = chans.index(v.shafts[0]) if v.shafts else None
        stop = next((m for m in self.manoeuvres if m.kind == "stop"), None)
        if self._shaft is None and stop is not None:
            raise ValueError(
                f"{stop.name!r} needs a main propeller and {v.name!r} has none "
                f"(its actuators: {', '.join(chans)})"
            )
        self.n0 = (
            approach_command(phys, self._shaft, self.U0) if self._shaft is not None else math.nan
        )
        self.L = float(v.L_pp)
        fracs = np.array([m.approach_shaft() for m in self.manoeuvres])
        if self._shaft is None and (fracs != 1.0).any():
            raise ValueError(
                f"a reduced-shaft approach needs a main propeller; {v.name!r} has none"
            )
        shaft = self._shaft
        speeds = {
            f: self.U0 if f == 1.0 or shaft is None else steady_speed(phys, shaft, f * self.n0,
                                                                       self.U0)
            for f in set(fracs)
        }  # fmt: skip
        #: every env's approach shaft command (the channel's unit) and speed (m/s): ``n0`` and
        #: ``U0``, or the steady speed of a reduced command (a half-ahead turn)
        self.n_start = fracs * self.n0
        self.U_start = np.array([speeds[f] for f in fracs])
        self.duration = np.array(
            [m.duration(self.L, u) for m, u in zip(self.manoeuvres, self.U_start, strict=True)]
        )
        self.max_steps = np.ceil(self.duration / self.control_period - 1e-9).astype(np.int64)
        self.override = bool(override)
        n_ch = acts.n_channels
        action_space: Any = (
            spaces.Box(-1.0, 1.0, (n_ch,), dtype=np.float32) if override else spaces.Discrete(1)
        )
        n_obs = 9 + (4 if receiver else 0)
        obs_space = spaces.Box(-np.inf, np.inf, (n_obs,), dtype=np.float32)
        self.attach(num_envs, obs_space, action_space)
        self.S_p = float(S_p)
        self.antenna = tuple(float(a) for a in np.asarray(antenna, dtype=float).reshape(2))
        self.receiver_sigma = float(receiver_sigma)
        self._max_angle = float(acts.upper[self._rudder])
        self._names = np.array([m.name for m in self.manoeuvres])
        self.scripts = Scripts(self.manoeuvres)
        n = num_envs
        self._command = phys.initial_actuator_state()
        self._clipped = np.zeros(n, dtype=bool)
        # the record of every env's episode: t, x, y, psi, u, v, r, rudder, shaft per step
        self._hist = np.zeros((int(self.max_steps.max()) + 1, n, 9))
        self._row = np.full((n, 9), np.nan)
        # the observation from the row: x/L, y/L, u/U0, v/U0, r L/U0, rudder/max, shaft/n0
        L, U0 = self.L, self.U0
        has_shaft = self._shaft is not None and bool(self.n0)
        self._obs_to = [0, 1, 4, 5, 6, 7] + ([8] if has_shaft else [])
        self._obs_from = [1, 2, 4, 5, 6, 7] + ([8] if has_shaft else [])
        self._obs_scale = np.array([1 / L, 1 / L, 1 / U0, 1 / U0, L / U0, 1 / self._max_angle]
                                   + ([1 / self.n0] if has_shaft else []))  # fmt: skip
        self.receiver = DGPSReceiver(self.S_p, n=n, sigma=self.receiver_sigma,
                                     antenna=self.antenna)  # fmt: skip
        self._rx_out: DGPSOutput | None = None  # the receiver's outputs, held between samples
        self._now = False  # whether _row holds the state now

    # ---- episode ---------------------------------------------------------------------------
    def _state(self) -> NDArray[np.float64]:
        """Every env's ``t, x, y, psi, u, v, r, rudder, shaft`` now (N, 9) (the record's row;
        the shaft NaN without one), read once per state."""
        if not self._now:
            p, row = self.physics, self._row
            st = p.actuator_state
            row[:, 0], row[:, 1:4], row[:, 4:7], row[:, 7] = p.t, p.eta, p.nu, st[:, self._rudder]
            if self._shaft is not None:
                row[:, 8] = st[:, self._shaft]
            self._now = True
        return self._row

    def initialize_episode(self, rngs: list[Any], mask: NDArray[np.bool_]) -> None:
        phys = self.physics
        idx = np.nonzero(mask)[0].tolist()
        gens: list[Any] = [None] * self.num_envs
        rx_rngs: list[Any] = [None] * self.num_envs
        for i in idx:  # env i's generator: the physics' seed, then the receiver's
            ss = rngs[i].bit_generator.random_raw(2)
            gens[i], rx_rngs[i] = (np.random.default_rng(int(s)) for s in ss)
        act = phys.initial_actuator_state()
        if self._shaft is not None:
            act[:, self._shaft] = self.n_start
        vc, bc = self.current  # straight running at U_start through the water, over ground
        nu0 = np.zeros((self.num_envs, 3))
        nu0[:, 0] = self.U_start + vc * math.cos(bc)
        nu0[:, 1] = vc * math.sin(bc)
        phys.reset(eta=(0.0, 0.0, 0.0), nu=nu0, actuators=act, mask=mask, rngs=gens)
        self._command[mask] = act[mask]
        phys.set_command(self._command)
        self.scripts.reset(np.zeros(self.num_envs), mask)
        self._now = False
        self._clipped[mask] = False
        if self.receiver_name is not None:
            self._rx_out = self.receiver.reset(self._state()[:, 1:4], nu0, rngs=rx_rngs,
                                               mask=mask)  # fmt: skip
        self._record(mask)

    def _record(self, mask: NDArray[np.bool_]) -> None:
        """The state now into the record of the envs of ``mask``, at their step count."""
        i = np.nonzero(mask)[0]
        self._hist[self.steps[i], i] = self._state()[i]

    def before_step(self, actions: NDArray[np.float64], active: NDArray[np.bool_]) -> None:
        phys = self.physics
        keep = ~active[:, None]
        if self.override:
            self._clipped = (np.abs(actions) > 1.0).any(axis=1)
            cmd = phys.actuators.action_to_command(np.clip(actions, -1.0, 1.0))
        else:
            if (actions != 0).any():
                raise ValueError(
                    "actions must be 0 (the script steers; override=True to steer yourself), "
                    f"got {actions!r}"
                )
            rud, frac = self.scripts.command(self._state()[:, 3])
            cmd = self._command.copy()
            cmd[:, self._rudder] = rud
            if self._shaft is not None:
                cmd[:, self._shaft] = frac * self.n0
        cmd = np.where(keep, self._command, cmd)
        if not (cmd == self._command).all():  # (a held command is held)
            self._command = cmd
            phys.set_command(cmd)

    def after_step(
        self, active: NDArray[np.bool_]
    ) -> tuple[dict[str, Any], NDArray[np.bool_], dict[str, Any]]:
        self._now = False
        if self.receiver_name is not None:
            sample = active & (self.steps % self._rx_every == 0)
            if sample.any():
                self._rx_out = self.receiver.update(self._state()[:, 1:4], mask=sample)
        self._record(active)
        return {}, self.steps >= self.max_steps, self._info()

    def observation(self) -> NDArray[np.float32]:
        row = self._state()
        obs = np.zeros((self.num_envs, self.single_observation_space.shape[0]), np.float32)
        obs[:, self._obs_to] = row[:, self._obs_from] * self._obs_scale
        obs[:, 2], obs[:, 3] = np.sin(row[:, 3]), np.cos(row[:, 3])
        o = self._rx_out
        if o is not None:  # v_xy/U0, beta_A, x_hat/L, y_hat/L
            obs[:, 9], obs[:, 10] = o.v_xy / self.U0, o.beta_A
            obs[:, 11], obs[:, 12] = o.x_hat / self.L, o.y_hat / self.L
        return obs

    def reset_info(self, mask: NDArray[np.bool_]) -> dict[str, Any]:
        return self._info()

    def _info(self) -> dict[str, Any]:
        phys = self.physics
        row = self._state()
        u, v = row[:, 4], row[:, 5]
        info: dict[str, Any] = {
            "t": row[:, 0].copy(),
            "eta": row[:, 1:4].copy(),
            "manoeuvre": self._names.copy(),
            "speed": np.hypot(u, v),
            "drift": np.arctan2(-v, u),
            "rudder": row[:, 7].copy(),
            "rudder_command": phys.command[:, self._rudder],
            # (BatchedPhysics has no rate_limited: its hull batch's servo hits, read here)
            "rate_limited": phys.rate_limited.any(axis=1),
            "saturated": phys.saturated.any(axis=1),
            "clipped": self._clipped.copy(),
            "reward_terms": {},
        }
        if self._shaft is not None:  # (a vessel without a shaft: no key, not NaN)
            info["shaft"] = row[:, 8].copy()
        if self._rx_out is not None:
            info["receiver"] = {k: getattr(self._rx_out, f).copy() for k, f in _RX_KEYS.items()}
        return info

    def episode_metrics(self, done: NDArray[np.bool_]) -> dict[str, Any]:
        n = self.num_envs
        out: dict[str, Any] = {"overshoots": np.full((n, 3), np.nan)}
        for i in np.nonzero(done)[0].tolist():  # the trial's analysis, at its end
            for k, val in _summary(*self.result(i)).items():
                if k == "overshoots":
                    out[k][i, : len(val)] = val
                elif isinstance(val, str):
                    out.setdefault(k, np.full(n, "", dtype=object))[i] = val
                else:
                    out.setdefault(k, np.full(n, np.nan))[i] = math.nan if val is None else val
        return {k: v.astype(str) if v.dtype == object else v for k, v in out.items()}

    def record(self, i: int = 0) -> TrialRecord:
        """Env ``i``'s true motion recorded so far in its episode (every control step)."""
        h = self._hist[: self.steps[i] + 1, i]
        return TrialRecord(
            vessel=self.base_vessel.name, manoeuvre=self.manoeuvres[i].name, L=self.L,
            U0=float(self.U_start[i]), n0=float(self.n_start[i]), current=self.current,
            t=h[:, 0].copy(),
            eta=h[:, 1:4].copy(), nu=h[:, 4:7].copy(), rudder=h[:, 7].copy(),
            shaft=h[:, 8].copy(),
        )  # fmt: skip

    def result(self, i: int = 0) -> tuple[TrialMetrics, list[tuple[str, float, float, bool]]]:
        """Env ``i``'s trial figures and IMO criteria, from its record so far."""
        m = self.record(i).metrics()
        return m, imo_criteria(m, self.L, float(self.U_start[i]))


def _summary(m: TrialMetrics, crit: list[tuple[str, float, float, bool]]) -> dict[str, Any]:
    """A trial's figures (SI) and whether every IMO criterion passed (``None``: none applies):
    the single env's ``episode_metrics()``."""
    return {**m.as_dict(), "imo_pass": all(c[3] for c in crit) if crit else None}


class SeaTrialVectorEnv(TaskEnv):
    r"""``num_envs`` sea trials stepped together: the batched form of :class:`SeaTrialEnv`
    (its docstring is the spec; env ``i`` is it seeded ``seed + i``), :class:`SeaTrialTask`
    in the env of every stepped task, with ``autoreset_mode`` (``"next-step"`` or
    ``"same-step"``) and ``manoeuvre`` a name or ``num_envs`` names (one per env).
    ``info["episode_metrics"]``: the figures as arrays, ``(N,)`` floats (NaN where one does
    not apply), ``overshoots`` ``(N, 3)``, ``manoeuvre`` and ``kind`` strings, ``imo_pass``
    1.0 / 0.0 (NaN: no criterion applies)."""

    task_class = SeaTrialTask

    def __init__(
        self,
        num_envs: int,
        vessel: str | Vessel | Any,
        manoeuvre: str | Sequence[str] = "turning35_stbd",
        *,
        autoreset_mode: str = "next-step",
        **kwargs: Any,
    ) -> None:
        super().__init__(num_envs, autoreset_mode=autoreset_mode, vessel=vessel,
                         manoeuvre=manoeuvre, **kwargs)  # fmt: skip


class SeaTrialEnv(TaskSingleEnv):
    r"""One IMO manoeuvre per episode, scripted, on a vessel with a rudder.

    **Physics.** The vessel's hull (:class:`~shipgym.envs.batchphysics.BatchedPhysics` of
    one, the open-water leapfrog integrator), physics step ``timestep`` (0.05 s); a constant
    current (``current``, any form of :meth:`CurrentConfig.coerce
    <shipgym.disturbances.CurrentConfig.coerce>`, e.g. ``"0.25@225"``: 0.25 m/s going
    south-west); optional wind. The ship starts at ``eta = 0`` (heading north) running
    straight at the approach speed ``U0`` through the water (``speed``, default
    :attr:`Vessel.approach_speed <shipgym.dynamics.vessel.Vessel.approach_speed>`) with its
    main propeller at the command that holds it (:func:`approach_command`) and the rudder
    amidships; a turn at a reduced shaft command (``turning65_half_ahead``: 0.85 of it)
    starts at that command's steady speed (:func:`steady_speed`).

    **Task.** ``manoeuvre``: one of :func:`~shipgym.trials.manoeuvres.manoeuvre_names`
    (``turning35_stbd``, ``turning35_port``, ``zigzag10``, ``zigzag20``, ``initial_turning``,
    ``crash_stop``, ``coasting_stop``, ``turning65_half_ahead``: Artyszuk's (2003) half-ahead
    65 deg turn, flown with the Schilling rudder option of an MMG ship,
    :func:`shipgym.dynamics.mmg.with_rudder`). Its script (:class:`~shipgym.trials.manoeuvres.
    Scripts`) commands the first rudder (:attr:`Vessel.rudders <shipgym.dynamics.vessel.
    Vessel.rudders>`) and the first main propeller (:attr:`~shipgym.dynamics.vessel.Vessel.
    shafts`, as a fraction of the approach command) every control step; a stopping manoeuvre
    needs a main propeller. The episode ends (``terminated``) after the manoeuvre's duration
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

    **Info.** ``t`` (s), ``eta`` (the true pose), ``manoeuvre``, ``speed`` (m/s) and
    ``drift`` (rad) over ground, ``rudder`` (rad), ``rudder_command`` (rad), ``shaft``
    (``None`` without one), ``rate_limited``, ``saturated``, ``clipped`` (``override``: an
    action outside ``[-1, 1]``), with a receiver ``receiver`` (its outputs); at the end
    ``trial`` (the figures, :meth:`TrialMetrics.as_dict <shipgym.trials.metrics.TrialMetrics.
    as_dict>`), ``imo`` (criterion, value, limit, passed) and ``episode_metrics``.

    The batched form is :class:`SeaTrialVectorEnv` (``gymnasium.make_vec``); this env is its
    batch of one (:attr:`batch`).

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

    batched = SeaTrialVectorEnv
    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(
        self,
        vessel: str | Vessel | Any,
        manoeuvre: str = "turning35_stbd",
        *,
        render_mode: str | None = None,
        **kwargs: Any,
    ) -> None:
        if not isinstance(manoeuvre, str):
            raise ValueError(f"manoeuvre must be a name, one of {', '.join(manoeuvre_names())}")
        super().__init__(render_mode, vessel=vessel, manoeuvre=manoeuvre, **kwargs)
        b = self.batch
        self.manoeuvre = b.manoeuvres[0]
        self.duration, self.max_steps = float(b.duration[0]), int(b.max_steps[0])

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        obs, info = super().reset(seed=seed, options=options)
        return obs, self._scalar(info)

    def step(self, action: Any) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        if self.override:
            a = np.asarray(action, dtype=float)
            if a.shape != self.action_space.shape or not np.all(np.isfinite(a)):
                raise ValueError(
                    f"action must be {self.action_space.shape} finite numbers in [-1, 1] "
                    f"({', '.join(self.physics.actuators.channel_names)}), got {action!r}"
                )
        elif not (type(action) is int and action == 0) and not self.action_space.contains(action):
            raise ValueError(
                "action must be the int 0 of the action space Discrete(1) (the script steers; "
                f"override=True to steer yourself), got {action!r}"
            )
        obs, reward, terminated, truncated, info = super().step(action)
        info = self._scalar(info)
        if terminated:
            m, crit = self.batch.result(0)
            info.update(trial=m.as_dict(), imo=crit, episode_metrics=_summary(m, crit))
        return obs, reward, terminated, truncated, info

    def _scalar(self, info: dict[str, Any]) -> dict[str, Any]:
        if self.batch._shaft is None:  # the single env's shaft without one: None
            info["shaft"] = None  # (the batch has no such key)
        return info

    def record(self) -> TrialRecord:
        """The true motion recorded so far (every control step)."""
        return self.batch.record(0)

    def episode_metrics(self) -> dict[str, Any]:
        """The trial's figures so far (SI) and whether every IMO criterion passed."""
        return _summary(*self.batch.result(0))


class TankerSeaTrialEnv(SeaTrialEnv):
    """``shipgym/SeaTrial-v0``: :class:`SeaTrialEnv` on the seed's 100 m tanker
    (``kvlcc2-100m``) unless ``vessel=`` says otherwise."""

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("vessel", "kvlcc2-100m")
        super().__init__(**kwargs)


def sea_trial_vector_env(num_envs: int, **kwargs: Any) -> SeaTrialVectorEnv:
    """``shipgym/SeaTrial-v0``'s vector entry point (``kvlcc2-100m`` unless ``vessel=``)."""
    kwargs.setdefault("vessel", "kvlcc2-100m")
    if kwargs.pop("render_mode", None) is not None:
        raise ValueError("the batched env does not render; use the single env (gym.make)")
    return SeaTrialVectorEnv(num_envs, **kwargs)


def _manoeuvre(name: Any) -> Any:
    if not isinstance(name, str):
        raise ValueError(f"manoeuvre must be a name, one of {', '.join(manoeuvre_names())}")
    return manoeuvre(name)


def run_trials(
    vessel: str | Vessel | Any,
    manoeuvres: Sequence[str],
    *,
    speed: float | None = None,
    current: Any = None,
    timestep: float = 0.05,
    record_period: float | None = None,
) -> list[TrialRecord]:
    """Fly scripted manoeuvres as one batch (:class:`SeaTrialVectorEnv`, one env each) and
    return their true motions (:class:`TrialRecord`), in order.

    Args:
        vessel, speed, current, timestep: as for :class:`SeaTrialEnv`.
        manoeuvres: the manoeuvres' names.
        record_period: the record's sample time (s), a whole multiple of ``timestep``; the
            script acts at this period too (``None``: every physics step, so that a zig-zag's
            rudder is reversed within one step of the heading reaching the angle).
    """
    period = timestep if record_period is None else record_period
    out: list[TrialRecord | None] = [None] * len(manoeuvres)
    groups: dict[Any, list[int]] = {}  # one batch per rudder (a rudder option: another ship)
    for i, m in enumerate(manoeuvres):
        groups.setdefault(_manoeuvre(m).rudder, []).append(i)
    for idx in groups.values():
        n = len(idx)
        env = SeaTrialVectorEnv(n, vessel, [manoeuvres[i] for i in idx], speed=speed,
                                current=current, timestep=timestep,
                                control_period=period)  # fmt: skip
        env.reset(seed=0)
        got: list[TrialRecord | None] = [None] * n
        while any(r is None for r in got):
            _, _, terminated, _, _ = env.step(np.zeros(n, dtype=np.int64))
            for j in np.nonzero(terminated)[0].tolist():
                got[j] = got[j] or env.record(j)
        for j, i in enumerate(idx):
            out[i] = got[j]
    return out  # type: ignore[return-value]


def run_trial(vessel: str | Vessel | Any, manoeuvre: str, **kwargs: Any) -> TrialRecord:
    """Fly one scripted manoeuvre and return its true motion (:class:`TrialRecord`); the
    keyword arguments are :func:`run_trials`'."""
    return run_trials(vessel, [manoeuvre], **kwargs)[0]


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
    """The result of :func:`trial_study`: the records (over ground), the trial rows (SI, with
    the IMO criteria; with a current a second, water-referenced row per manoeuvre, its
    ``reference`` ``"water"``), the receiver-bias rows (SI) and the
    :class:`~shipgym.trials.bias.ReceiverBias` objects by ``(manoeuvre, S_p or "raw",
    corrected)``."""

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
        manoeuvres: names (``None``: every one the vessel can fly: the stops need a main
            propeller, a rudder option an MMG unit).
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
        mmg = any(isinstance(a, MMGPropulsion) for a in v.actuators)
        names = [
            m for m in manoeuvre_names()
            if (v.shafts or manoeuvre(m).kind != "stop") and (mmg or manoeuvre(m).rudder is None)
        ]  # fmt: skip
    for m in names:
        manoeuvre(m)  # unknown names fail before any work
    sps = [float(s) for s in S_p]
    for s in sps:
        if not (math.isfinite(s) and s > 0):
            raise ValueError(f"S_p must be > 0 m^2/s^3, got {s!r}")
    records = dict(zip(names, run_trials(v, names, speed=speed, current=current,
                                         timestep=timestep), strict=True))  # fmt: skip
    rows, brows, bias = [], [], {}
    for i, (m, rec) in enumerate(records.items()):
        met = rec.metrics()
        rows.append(trial_row(v.name, met, imo_criteria(met, rec.L, rec.U0), rec.L, rec.U0,
                              rec.current))  # fmt: skip
        if rec.current[0] > 0:  # and the figures of the water-referenced track (the ITTC way)
            wm = rec.water_referenced().metrics()
            rows.append(trial_row(v.name, wm, imo_criteria(wm, rec.L, rec.U0), rec.L, rec.U0,
                                  rec.current, reference="water"))  # fmt: skip
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
