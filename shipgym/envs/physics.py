r"""The physics of one hull: MuJoCo's rigid body moved exactly as the hull's model says.

Public names: ``INTEGRATORS``, ``VesselPhysics``, ``SimulationDiverged``, ``MAX_TIMESTEP``,
``MIN_TIMESTEP``, ``check_timestep``, ``joint_inertia``.

Design notes: docs/design/envs.physics.md.
"""

from __future__ import annotations

import operator
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import is_real
from shipgym.disturbances import (
    BLENDERMANN,
    Current,
    CurrentConfig,
    WaveConfig,
    Waves,
    Wind,
    WindConfig,
    WindLoad,
    blendermann,
)
from shipgym.dynamics import PlantModel, WindageParameters
from shipgym.dynamics.hull4 import Hull4
from shipgym.dynamics.vessel import Vessel, load_vessel
from shipgym.envs._mujoco import mujoco
from shipgym.sim.step import SimulationDiverged

from .scene import build_model

__all__ = [
    "INTEGRATORS",
    "VesselPhysics",
    "SimulationDiverged",
    "MAX_TIMESTEP",
    "MIN_TIMESTEP",
    "check_lags",
    "check_timestep",
    "contact_pairs",
    "joint_inertia",
]

#: bounds beyond which the simulation is declared diverged (m/s, rad/s, rad): far above
#: anything a displacement ship reaches (the Blue Lady: 1.6 m/s; a tanker: 8 m/s).
_MAX_ROLL = 1.2


#: the integrators of :class:`VesselPhysics` (:mod:`shipgym.sim.step`)
INTEGRATORS = ("mujoco", "leapfrog")

#: the current of a physics without one (one shared object, so that "no change" is cheap to see)
NO_CURRENT = CurrentConfig()


def _current_config(current: object) -> CurrentConfig:
    cfg = CurrentConfig.coerce(current, name="current")
    return NO_CURRENT if cfg is None else cfg


#: smallest physics timestep (s). The default 0.05 s resolves the fastest dynamics (thruster
#: lags of 1-2 s, the hull's surge/sway/yaw time constants of tens of seconds) many times
#: over; below 1e-4 s each simulated second costs more than 10 000 MuJoCo steps for nothing.
MIN_TIMESTEP = 1e-4
#: largest physics timestep (s): half the Blue Lady's shortest thruster time constant (1 s,
#: the tunnel thrusters), where MuJoCo's semi-implicit Euler still tracks the lags; a vessel
#: with faster actuators needs a smaller step (checked against its lags when it is built).
MAX_TIMESTEP = 0.5


def _clip(c: float, lo: float, hi: float) -> float:
    """``min(max(c, lo), hi)`` for a finite ``c``, as two comparisons."""
    return hi if c > hi else (lo if c < lo else c)


def joint_inertia(model: Any, actuators: Any, dofs: int) -> tuple[float, float, float]:
    """MuJoCo's joint-space inertia ``(m, I_z, I_x)`` (kg, kg m^2, kg m^2; ``I_x = 0`` for 3
    DOF) of a vessel model built by :func:`~shipgym.envs.scene.build_model`, after checking
    the model's layout: the joints ``x, y, psi[, phi]`` in this order, the actuators the
    channels in order, a constant diagonal inertia ``diag(m, m, I_z[, I_x])`` and no bias
    force (what the compiled step's ``qfrc_applied = M_q qacc`` relies on)."""
    m = model
    names = ("x", "y", "psi", "phi")[:dofs]
    jids = [m.joint(n).id for n in names]
    act_ids = [m.actuator(n).id for n in actuators.channel_names]
    if jids != list(range(dofs)) or m.nv != dofs:
        raise ValueError(f"the hull must have exactly the joints {names}, in this order")
    if act_ids != list(range(m.nu)) or m.nu != actuators.n_channels:
        raise ValueError("MuJoCo actuators must be the vessel's channels, in order")
    d = mujoco.MjData(m)
    if dofs == 4:  # a rolled, moving state: the inertia must not depend on it
        d.qpos[3] = 0.3
        d.qvel[:] = (0.4, -0.2, 0.05, 0.1)
    mujoco.mj_forward(m, d)
    Mq = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, Mq)
    diag = np.diag(Mq)
    scale = float(np.max(np.abs(Mq)))
    if (
        np.any(np.abs(Mq - np.diag(diag)) > 1e-9 * scale)
        or abs(diag[0] - diag[1]) > 1e-12 * diag[0]
        or np.any(np.abs(d.qfrc_bias) > 1e-9 * scale)
    ):
        raise ValueError(
            f"unexpected joint-space inertia (need a constant diag(m, m, I_z[, I_x])): {Mq}"
        )
    return float(Mq[0, 0]), float(Mq[2, 2]), float(Mq[3, 3]) if dofs == 4 else 0.0


def check_lags(actuators: Any, h: float, name: str) -> None:
    """``ValueError`` where the physics step ``h`` (s) is more than half the shortest
    actuator lag of the vessel ``name`` (the bound both physics classes set on their step)."""
    lags = [c.time_constant for c in actuators.channels if c.dynamics == "lag"]
    if lags and h > 0.5 * min(lags) + 1e-12:
        raise ValueError(
            f"timestep {h:g} s is more than half the shortest actuator lag of "
            f"{name!r} ({min(lags):g} s): use timestep <= {0.5 * min(lags):g}"
        )


def check_timestep(timestep: Any) -> float:
    """The physics timestep (s) as a float; ``TypeError``/``ValueError`` outside the bounds."""
    if not is_real(timestep):
        raise TypeError(f"timestep must be a number of seconds, got {timestep!r}")
    if not MIN_TIMESTEP <= timestep <= MAX_TIMESTEP:  # NaN fails too
        raise ValueError(
            f"timestep must be from {MIN_TIMESTEP:g} to {MAX_TIMESTEP:g} s, got {timestep!r}"
        )
    return float(timestep)


class VesselPhysics:
    """A MuJoCo hull driven by its actuators, its hull model, wind, waves and current.

    Args:
        vessel: a :class:`~shipgym.dynamics.vessel.Vessel`, a packaged vessel's name
            (``"blue-lady"``, ``shipgym.vessels()``) or the path of a vessel package.
        plant: a plant variant name of the vessel (``"default"``, ...) or a model object
            (:class:`PlantModel` for 3 DOF, :class:`~shipgym.dynamics.hull4.Hull4` for 4).
        wind: wind: a :class:`~shipgym.disturbances.WindConfig`, ``"SPEED@FROM_DEG"``,
            ``(speed m/s, from deg)`` or a mapping (any form of
            :meth:`WindConfig.coerce <shipgym.disturbances.WindConfig.coerce>`). ``None``
            switches aerodynamic loads off altogether; ``WindConfig(speed=0)`` is still air, in
            which a moving hull feels air drag.
        windage: projected areas for the wind load; ``None``: the vessel's.
        current: current in NED: a :class:`~shipgym.disturbances.CurrentConfig` (constant or
            Gauss-Markov), ``"SPEED@TO_DEG"``, a constant ``(speed m/s, direction it goes to,
            deg)``, a mapping (:meth:`CurrentConfig.coerce
            <shipgym.disturbances.CurrentConfig.coerce>`) or ``None`` (no current). It acts
            through the relative velocity ``nu_r = nu - nu_c`` only.
        waves: a :class:`~shipgym.disturbances.WaveConfig` for the second-order (mean and
            slowly varying) drift load on the hull, or ``None``. First-order wave motion is
            not a hull motion: the environment adds it to the measurements
            (:meth:`wave_motion`).
        world: ``"open-water"`` or ``"harbour"`` (:data:`shipgym.envs.scene.WORLDS`).
        timestep: physics step (s), :data:`MIN_TIMESTEP` to :data:`MAX_TIMESTEP` and at most
            half the shortest actuator lag; ``None`` keeps the world's value (0.05 s).
        integrator: ``"mujoco"`` (MuJoCo's ``mj_step``: contacts, the harbour, rendering) or
            ``"leapfrog"`` (the same update without MuJoCo, as the batched physics; open
            water, no contacts); both apply the same forces (:mod:`shipgym.sim.step`).

    Pose and velocity: :attr:`eta` ``[x, y, psi]`` and :attr:`nu` ``[u, v, r]`` for every
    vessel (what the planar DP stack uses); a 4-DOF vessel adds :attr:`phi`, :attr:`p` and the
    Fossen-ordered :attr:`eta_full` ``[x, y, phi, psi]``, :attr:`nu_full` ``[u, v, p, r]``.
    Commands and actuator states follow the vessel's channel order
    (``physics.actuators.channel_names``).

    The physics owns no task logic: commands in, state out (dm_control's Physics/Task split).
    """

    def __init__(
        self,
        vessel: Vessel | str | Path,
        plant: PlantModel | Hull4 | str = "default",
        *,
        wind: WindConfig | str | tuple[float, float] | Mapping[str, Any] | None = None,
        windage: WindageParameters | None = None,
        current: CurrentConfig | str | tuple[float, float] | Mapping[str, Any] | None = None,
        waves: WaveConfig | None = None,
        world: str = "open-water",
        timestep: float | None = None,
        integrator: str = "mujoco",
    ) -> None:
        self.vessel = load_vessel(vessel)
        v = self.vessel
        self.plant = v.plant(plant) if isinstance(plant, str) else plant
        dofs = getattr(self.plant, "dofs", None)
        if dofs not in (3, 4) or getattr(type(self.plant), "accel_kernel", None) is None:
            raise TypeError(
                f"plant must be a hull model of a hull family (PlantModel, Hull4, Blanke4Hull, "
                f"MMGHull, ...: a compiled accel_kernel) or a variant name, got {plant!r}"
            )
        if dofs != v.dofs:
            raise ValueError(f"plant {plant!r} has {dofs} DOF but vessel {v.name!r} has {v.dofs}")
        if integrator not in INTEGRATORS:
            raise ValueError(
                f"integrator must be one of {', '.join(INTEGRATORS)}, got {integrator!r}"
            )
        self.dofs = dofs
        self.integrator = integrator
        # the actuators this plant drives (a plant of the paper's model: the bollard laws)
        self.actuators = acts = v.actuators_for(self.plant)
        # the thrust model a DP system computes from the actuator states (feedback): the
        # bollard laws (the advance-speed and tunnel losses are the plant's, not known to it)
        self._model_actuators = acts.bollard()
        self._lower = acts.lower.tolist()
        self._upper = acts.upper.tolist()
        self.windage = v.windage if windage is None else windage
        if not isinstance(self.windage, WindageParameters):
            raise TypeError(f"windage must be WindageParameters or None, got {windage!r}")
        if (self.windage.coefficients or "") not in BLENDERMANN:
            raise ValueError(
                f"vessel {v.name!r}: windage.coefficients {self.windage.coefficients!r} is not a "
                f"Blendermann (1994) ship type; valid: {', '.join(sorted(BLENDERMANN))}"
            )
        wind_cfg = WindConfig.coerce(wind, name="wind")
        self.aerodynamics = wind_cfg is not None
        self.wind_config = wind_cfg if wind_cfg is not None else WindConfig()
        self.current_config = _current_config(current)
        self.current = Current(self.current_config)
        if waves is not None and not isinstance(waves, WaveConfig):
            raise ValueError(f"waves must be a WaveConfig or None, got {waves!r}")
        self.wave_config = waves
        self.waves = Waves(waves, v.hull) if waves is not None else None
        self.world = world
        self.model = build_model(v, world, acts)
        if timestep is not None:
            self.model.opt.timestep = check_timestep(timestep)
        self._check_lags(float(self.model.opt.timestep))
        self.data = mujoco.MjData(self.model)
        self._bind_model()
        self.wind = Wind(self.wind_config, self.windage)
        self._servo_channels = [i for i, c in enumerate(acts.channels) if c.dynamics == "servo"]
        self._flow_actuators = [i for i, a in enumerate(acts) if a.flow_dependent]
        self._holds = acts.holds_state
        self.saturated = np.zeros(v.actuators.n_channels, dtype=bool)
        self._at: Any = None  # _now(): the actuators' read-out at the current state
        self._vel: tuple[float, float, float, float] | None = None  # _velocity()
        self._build()
        self.reset()

    # ---- set-up ----------------------------------------------------------------------------
    def _check_lags(self, h: float) -> None:
        check_lags(self.actuators, h, self.vessel.name)

    def _build(self) -> None:
        """The hull batch of one (:class:`~shipgym.sim.step.HullBatch`) for the current step."""
        from shipgym.sim.step import HullBatch

        self._opt = self.model.opt  # (read at every step: has the timestep changed?)
        self._h = float(self._opt.timestep)
        name = self.wind_config.coefficients or self.windage.coefficients
        wind_load = WindLoad(blendermann(name), self.windage)
        self._hulls = HullBatch(
            self.plant, self.actuators, wind_load.kernel_constants(), 1, self._h,
            (self._m_q, self._m_q, self._i_q, self._i_x), integrator=self.integrator,
            model=self.model, data=self.data,
        )  # fmt: skip
        self._model_table = self._model_actuators.law_table()

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        del state["_opt"]  # (MuJoCo's MjOption view cannot be pickled: taken from the model)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._opt = self.model.opt

    def _bind_model(self) -> None:
        self.hull_body = self.model.body("hull").id
        self._m_q, self._i_q, self._i_x = joint_inertia(self.model, self.actuators, self.dofs)

    def set_current(
        self, current: CurrentConfig | str | tuple[float, float] | Mapping[str, Any] | None
    ) -> None:
        """Replace the current model (any form of ``current=``; effective at :meth:`reset`)."""
        self.current_config = _current_config(current)
        self.current = Current(self.current_config)

    def set_wind(
        self, wind: WindConfig | str | tuple[float, float] | Mapping[str, Any] | None
    ) -> None:
        """Replace the wind model (any form of ``wind=``; takes effect at :meth:`reset`)."""
        wind_cfg = WindConfig.coerce(wind, name="wind")
        self.aerodynamics = wind_cfg is not None
        self.wind_config = wind_cfg if wind_cfg is not None else WindConfig()
        self.wind = Wind(self.wind_config, self.windage)
        self._build()

    # ---- state -----------------------------------------------------------------------------
    def _vector(self, x: ArrayLike | None, n: tuple[int, ...], what: str) -> NDArray[np.float64]:
        a = np.asarray(x, dtype=float)
        if a.shape not in [(k,) for k in n] or not np.all(np.isfinite(a)):
            raise ValueError(f"{what} must be {' or '.join(map(str, n))} finite numbers, got {x!r}")
        return a

    def initial_actuator_state(self) -> NDArray[np.float64]:
        """Actuator states after a reset: zero thrust, azimuths at their rest angle."""
        return self.actuators.initial_state()

    def reset(
        self,
        eta: ArrayLike = (0.0, 0.0, 0.0),
        nu: ArrayLike = (0.0, 0.0, 0.0),
        actuators: ArrayLike | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        """Reset to pose ``eta``, body velocity ``nu`` and actuator states.

        ``eta`` is ``[x, y, psi]`` (m, m, rad) or, for a 4-DOF vessel, ``[x, y, phi, psi]``;
        ``nu`` likewise ``[u, v, r]`` or ``[u, v, p, r]``. ``actuators`` defaults to
        :meth:`initial_actuator_state`. ``rng`` seeds the stochastic disturbances (wind
        gusts, current, waves); ``None`` uses a fixed seed 0.
        """
        n = (3, 4) if self.dofs == 4 else (3,)
        eta_a = self._vector(eta, n, "eta")
        nu_a = self._vector(nu, n, "nu")
        if eta_a.size == 3:
            eta_a = np.array([eta_a[0], eta_a[1], 0.0, eta_a[2]]) if self.dofs == 4 else eta_a
        if nu_a.size == 3:
            nu_a = np.array([nu_a[0], nu_a[1], 0.0, nu_a[2]]) if self.dofs == 4 else nu_a
        if self.dofs == 4 and abs(eta_a[2]) >= _MAX_ROLL:
            raise ValueError(f"roll angle must be below {_MAX_ROLL} rad, got {eta_a[2]!r}")
        act = (
            self.initial_actuator_state()
            if actuators is None
            else self.actuators.check_states(actuators, "actuators")
        )
        if self._opt.timestep != self._h:
            self._check_lags(float(self._opt.timestep))
            self._build()
        self._at = self._vel = None
        self.saturated[:] = False
        act = np.where(self._holds, np.clip(act, self.actuators.lower, self.actuators.upper), act)
        drift = self.wave_config is not None and self.wave_config.drift
        self._hulls.reset_hull(
            0, eta_a, nu_a, act, self._holds, rng if rng is not None else np.random.default_rng(0),
            self.wind, self.current, self.waves, aerodynamics=self.aerodynamics, drift=drift,
        )  # fmt: skip
        if self.integrator == "leapfrog":  # MuJoCo's pose for rendering
            mujoco.mj_resetData(self.model, self.data)
            self._sync()
            mujoco.mj_forward(self.model, self.data)

    def _sync(self) -> None:
        """MuJoCo's pose and clock from the leapfrog state (rendering, contacts)."""
        if self.integrator == "leapfrog":
            self.data.qpos[:] = self._hulls.q[0]
            self.data.time = float(self._hulls.t[0])

    @property
    def _loads(self) -> list[float]:
        return self._hulls.loads[0].tolist()

    def wave_motion(self) -> tuple[float, float, float]:
        """First-order wave-frequency motion ``(dx m, dy m, dpsi rad)`` (NED) now, for sensors."""
        if self.waves is None or not self.wave_config.first_order:
            return (0.0, 0.0, 0.0)
        return self.waves.wf_motion(self.time)

    def wave_elevation(self) -> float:
        """Wave elevation (m) now at the wave field's reference point (0 without waves).

        The drift load and the first-order motion use the same reference point: the spatial
        phase change of the hull's slow displacement is neglected (long-crested sea).
        """
        if self.waves is None:
            return 0.0
        return float(np.asarray(self.waves.elevation(self.time)))

    @property
    def tau_wind(self) -> tuple[float, float, float]:
        """Wind load ``[X, Y, N]`` (N, N, N m, body) of the last physics step."""
        return tuple(self._loads[0:3])  # type: ignore[return-value]

    @property
    def tau_waves(self) -> tuple[float, float, float]:
        """Second-order wave drift load ``[X, Y, N]`` (N, N, N m, body) of the last step."""
        return tuple(self._loads[3:6])  # type: ignore[return-value]

    @property
    def nu_c(self) -> tuple[float, float]:
        """Current ``(u_c, v_c)`` (m/s) in the body frame at the last physics step."""
        return tuple(self._loads[6:8])  # type: ignore[return-value]

    @property
    def time(self) -> float:
        """Simulation time (s)."""
        return float(self._hulls.t[0])

    @property
    def timestep(self) -> float:
        """Physics step (s)."""
        return float(self.model.opt.timestep)

    @property
    def eta(self) -> NDArray[np.float64]:
        """Pose ``[x (m north), y (m east), psi (rad)]``; psi is continuous (not wrapped)."""
        return self._hulls.q[0, :3].copy()

    @property
    def phi(self) -> float:
        """Roll angle (rad, starboard down), 0 for a 3-DOF vessel."""
        return float(self._hulls.q[0, 3]) if self.dofs == 4 else 0.0

    @property
    def nu(self) -> NDArray[np.float64]:
        """Body velocity ``[u (m/s), v (m/s), r (rad/s)]``."""
        u, v, _p, r = self._velocity()
        return np.array([u, v, r])

    @property
    def p(self) -> float:
        """Roll rate (rad/s), 0 for a 3-DOF vessel."""
        return self._velocity()[2]

    @property
    def eta_full(self) -> NDArray[np.float64]:
        """``[x, y, psi]`` (3 DOF) or Fossen's ``[x, y, phi, psi]`` (4 DOF)."""
        q = self._hulls.q[0]
        return q.copy() if self.dofs == 3 else np.array([q[0], q[1], q[3], q[2]])

    @property
    def nu_full(self) -> NDArray[np.float64]:
        """``[u, v, r]`` (3 DOF) or Fossen's ``[u, v, p, r]`` (4 DOF)."""
        u, v, p, r = self._velocity()
        return np.array([u, v, r]) if self.dofs == 3 else np.array([u, v, p, r])

    @property
    def actuator_state(self) -> NDArray[np.float64]:
        """Actuator states (lagged commands; azimuth angles in rad), in channel order."""
        return self._hulls.act[0].copy()

    @property
    def command(self) -> NDArray[np.float64]:
        """Current (saturated) commands, in channel order (a servo's: its commanded angle)."""
        return self._hulls.cmd[0].copy()

    def _tau(self, st: NDArray[np.float64], table: Any = None) -> tuple[list[float], Any]:
        """``([X, Y, K, N], forces)`` of the actuators (``table``: the plant's, or another
        :meth:`~shipgym.dynamics.actuators.ActuatorSet.law_table`) at the states ``st`` and the
        current velocity through the water (the current of the last physics step): their
        compiled laws (:meth:`HullBatch.actuator_loads
        <shipgym.sim.step.HullBatch.actuator_loads>`, the batched physics' read-out)."""
        hb = self._hulls
        forces = np.empty((1, hb.kind_index.shape[0]))
        out = hb.actuator_loads(np.reshape(st, (1, -1)), table, forces)
        return out[0].tolist(), forces[0]

    def _velocity(self) -> tuple[float, float, float, float]:
        """``(u, v, p, r)`` at the current state, computed once per state (as :meth:`_now`)."""
        if self._vel is None:
            self._vel = self._hulls.body_velocity(0)
        return self._vel

    def _now(self) -> tuple[list[float], Any]:
        """:meth:`_tau` at the current actuator states, kept until the state changes."""
        if self._at is None:
            self._at = self._tau(self._hulls.act[0])
        return self._at

    @property
    def thrust(self) -> NDArray[np.float64]:
        """Signed thrust of every actuator (N) at the current states and flow (a rudder: its
        lift, an MMG unit: its propeller thrust)."""
        return self._now()[1].copy()

    @property
    def tau_thrusters(self) -> NDArray[np.float64]:
        """Body-frame actuator force ``[X, Y, N]`` (N, N, N m) at the current actuator states
        (rudders at the current flow)."""
        X, Y, _K, N = self._now()[0]
        return np.array([X, Y, N])

    @property
    def tau_model(self) -> NDArray[np.float64]:
        """Body-frame actuator force ``[X, Y, N]`` (N, N, N m) that a DP system computes from
        the current actuator states (its shaft-speed and thruster feedback) with its thrust
        model: every propeller on its bollard law (:meth:`ActuatorSet.bollard
        <shipgym.dynamics.actuators.ActuatorSet.bollard>`), without the plant's advance-speed
        and tunnel losses; :attr:`tau_thrusters` where the two laws are the same."""
        if self._model_actuators is self.actuators:
            return self.tau_thrusters
        X, Y, _K, N = self._tau(self._hulls.act[0], self._model_table)[0]
        return np.array([X, Y, N])

    @property
    def tau_actuators(self) -> NDArray[np.float64]:
        """Body-frame actuator force ``[X, Y, K, N]`` (N, N, N m, N m) at the current actuator
        states and flow (``K`` is 0 for a 3-DOF vessel)."""
        return np.array(self._now()[0])

    @property
    def external_force(self) -> tuple[float, float, float, float]:
        """The external load ``[X, Y, K, N]`` (N, N, N m, N m, body) set by
        :meth:`set_external_force`."""
        return tuple(self._hulls.external[0].tolist())  # type: ignore[return-value]

    def set_external_force(self, tau: ArrayLike) -> None:
        """Hold an external body load ``[X, Y, K, N]`` (N, N, N m, N m; ``[X, Y, N]`` for 3 DOF)
        until changed: a task's disturbance (wave roll and yaw moments). Reset clears it.

        Raises:
            ValueError: wrong shape or a non-finite value.
        """
        a = self._vector(tau, (self.dofs,), "external force")
        vals = a.tolist()
        self._hulls.external[0] = vals if self.dofs == 4 else (vals[0], vals[1], 0.0, vals[2])

    @property
    def tau_command(self) -> NDArray[np.float64]:
        """Body-frame thrust ``[X, Y, N]`` (N, N, N m) the current commands give in steady state.

        The thrust law of :attr:`tau_thrusters` with every lagged or servo channel's state
        replaced by its (saturated) command, while integrator channels (azimuth angles) keep
        their current state: the force the held commands would give once the lags have
        settled, at the actuators' current angles (the demand ``u`` of a model with its own
        thruster lags, Al-Takie 1982 eq. 3.21).
        """
        hb = self._hulls
        st = np.where(self._holds, hb.cmd[0], hb.act[0])
        X, Y, _K, N = self._tau(st)[0]
        return np.array([X, Y, N])

    # ---- stepping --------------------------------------------------------------------------
    def set_command(self, command: ArrayLike) -> NDArray[np.bool_]:
        """Set the actuator commands (channel order), clipped to the physical ranges.

        Returns:
            Flags of the commands that were clipped (also kept in :attr:`saturated`).

        Raises:
            ValueError: wrong shape, NaN or infinite values.
        """
        _, vals = self.actuators.as_vector(command, "command")
        # min(max(c, lo), hi) per channel, as comparisons (vals are finite: as_vector)
        clipped = list(map(_clip, vals, self._lower, self._upper))
        self.saturated = np.array(list(map(operator.ne, clipped, vals)))
        self._hulls.cmd[0] = clipped
        return self.saturated.copy()

    def step(self, n: int = 1, *, stop_on_contact: bool = False) -> int:
        """Advance ``n`` physics steps with hydrodynamics, wind and current refreshed every step.

        Args:
            n: number of physics steps.
            stop_on_contact: return early, after the step in which MuJoCo detects a contact
                (the ``mujoco`` integrator; the ``leapfrog`` one has no contacts).

        Returns:
            The number of steps taken.

        Raises:
            SimulationDiverged: a non-finite or absurd state (the state before the step is kept).
        """
        if self._opt.timestep != self._h:
            self._check_lags(float(self._opt.timestep))
            hb = self._hulls
            state = (hb.q.copy(), hb.qv.copy(), hb.qa.copy(), hb.act.copy(), hb.cmd.copy(),
                     hb.t.copy(), hb.external.copy())  # fmt: skip
            self._build()
            hb = self._hulls
            for dst, src in zip((hb.q, hb.qv, hb.qa, hb.act, hb.cmd, hb.t, hb.external), state,
                                strict=True):  # fmt: skip
                dst[:] = src
            drift = self.waves if self.wave_config is not None and self.wave_config.drift else None
            hb.set_processes(0, self.wind if self.aerodynamics else None, self.current, drift)
        hb = self._hulls
        self._at = self._vel = None
        taken = hb.advance(n, stop_on_contact=stop_on_contact)
        if self.integrator == "leapfrog":
            self._sync()
        return taken

    @property
    def rate_limited(self) -> NDArray[np.bool_]:
        """Per servo channel: whether the servo was still running at its rate limit in the last
        physics step of the last :meth:`step` (it has not reached its command because of the
        rate limit; an ideal servo runs at full rate for every move, and only a move that
        outlasts the call counts)."""
        return self._hulls.hits[0, self._servo_channels] > 0

    @property
    def stalled(self) -> NDArray[np.bool_]:
        """Per flow-dependent actuator (rudders, MMG units, propellers with an advance-speed
        or tunnel loss): whether its effective angle was past the stall angle at the last
        step."""
        return self._hulls.flags[0, self._flow_actuators] > 0

    def contacts(self) -> list[tuple[str, str]]:
        """Pairs of geom names in contact now (the hull's geom first when it is involved)."""
        return contact_pairs(self.model, self.data)


def contact_pairs(model: Any, data: Any) -> list[tuple[str, str]]:
    """Pairs of geom names in contact in ``data`` now (the hull's geom first when it is
    involved)."""
    hull = model.body("hull").id
    out = []
    for c in data.contact[: data.ncon]:
        a, b = model.geom(c.geom1), model.geom(c.geom2)
        if b.bodyid[0] == hull:
            a, b = b, a
        out.append((a.name, b.name))
    return out
