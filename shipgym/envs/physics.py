r"""MuJoCo physics of a hull that moves exactly as its 3-DOF or 4-DOF model says.

MuJoCo gives a body one scalar mass, so anisotropic and coupled added mass cannot live in the
body's inertia. Every physics step :class:`VesselPhysics` therefore

1. reads the state (``qpos = eta``, ``qvel = R(psi) nu``) and the actuator states,
2. evaluates the full model acceleration ``nu_dot*`` (:meth:`PlantModel.accel`) from the
   thrust, wind and current at this instant,
3. converts it to the joint acceleration ``qacc* = R(psi) (nu_dot* + r S nu)`` (the time
   derivative of ``R(psi) nu``, Tomera (2014) eq. 22), and
4. writes ``qfrc_applied = M_q qacc* + qfrc_bias - qfrc_passive - qfrc_actuator``, where
   ``M_q`` is MuJoCo's own joint-space inertia and ``qfrc_actuator`` the thrust MuJoCo's
   actuators apply in this step,

so that MuJoCo's rigid body produces exactly ``qacc*``; then ``mj_step`` integrates it.

The same holds for a 4-DOF hull (surge, sway, roll, yaw; :class:`~shipgym.dynamics.hull4.Hull4`)
on the joints ``x, y, psi, phi``: ``qvel = J(q) nu`` with Fossen's kinematics (``x_dot = u cos
psi - v cos phi sin psi``, ``y_dot = u sin psi + v cos phi cos psi``, ``psi_dot = r cos phi``,
``phi_dot = p``), ``qacc* = J nu_dot* + J_dot nu``; MuJoCo's joint-space inertia is the
constant ``diag(m, m, I_z, I_x)`` with no bias force (the hull body has ``I_y = I_z``, see
:mod:`shipgym.envs.scene`; checked when the model is bound), and the actuators' generalised
force is ``[c_psi X - s_psi c_phi Y, s_psi X + c_psi c_phi Y, c_phi N + s_phi M_z, K]``
(``M_z = sum z_i F_x,i``), the force MuJoCo's site transmission applies to a rolled hull.

Thrust comes from the vessel's :class:`~shipgym.dynamics.actuators.ActuatorSet` (one law per
actuator kind, :meth:`~shipgym.dynamics.actuators.ActuatorSet.kernel`); the MuJoCo actuators
carry the same force: state-dependent gains (``k |n|``) and azimuth directions (``gear``) are
refreshed every step, so ``data.actuator_force`` reads each thrust in newtons; a
flow-dependent actuator's force (a rudder's lift, a propeller's advance-speed or tunnel loss)
is the physics' own (its MuJoCo gain is 0, :attr:`VesselPhysics.thrust` reads it). A lagged
actuator with a rate limit follows ``a_dot = clip((c - a) / T, +-rate)``: MuJoCo's exact
filter is fed, each step, the command that moves the state by exactly ``rate h`` while
``|c - a| > rate T`` and the command itself below. The actuators are those of the plant
(:meth:`Vessel.actuators_for <shipgym.dynamics.vessel.Vessel.actuators_for>`: the bollard laws
for a plant of the paper's model as printed).

MuJoCo's Euler step is the symplectic update ``qvel += h qacc; qpos += h qvel``. Read with
``qvel`` as the velocity at the half step (leapfrog), it is second-order accurate, provided the
acceleration is evaluated with the velocity at the whole step, ``v_k = qvel + h/2 qacc_prev``.
:class:`VesselPhysics` does exactly that, and :attr:`VesselPhysics.nu` reports ``v_k``, so
the trajectory error falls with ``h^2`` instead of ``h`` at no extra cost. No
force is lagged, so any invertible M works (added mass larger than the rigid-body mass
included), and no process-global MuJoCo callback is installed. A test checks ``d.qacc``
against ``qacc*`` and the trajectory against :func:`shipgym.dynamics.simulate_reference`.
"""

from __future__ import annotations

import math
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
from shipgym.dynamics.actuators import Azimuth
from shipgym.dynamics.hull4 import Hull4, is_hull4
from shipgym.dynamics.mmg import MMGHull
from shipgym.dynamics.vessel import Vessel, load_vessel
from shipgym.envs._mujoco import mujoco

from .scene import build_model

__all__ = [
    "VesselPhysics",
    "SimulationDiverged",
    "MAX_TIMESTEP",
    "MIN_TIMESTEP",
    "check_timestep",
]

#: bounds beyond which the simulation is declared diverged (m/s, rad/s, rad): far above
#: anything a displacement ship reaches (the Blue Lady: 1.6 m/s; a tanker: 8 m/s).
_MAX_SPEED = 50.0
_MAX_YAW_RATE = 10.0
_MAX_ROLL = 1.2


#: the current of a physics without one (one shared object, so that "no change" is cheap to see)
NO_CURRENT = CurrentConfig()


def _current_config(current: object) -> CurrentConfig:
    cfg = CurrentConfig.coerce(current, name="current")
    return NO_CURRENT if cfg is None else cfg


class SimulationDiverged(RuntimeError):
    """The simulation produced a non-finite or physically absurd state; it was stopped."""


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


def diverged(t: float, nu: Any, nud: Any) -> None:
    """Raise :class:`SimulationDiverged` for the state ``nu``, ``nu_dot`` at time ``t``."""
    raise SimulationDiverged(
        f"simulation diverged at t = {t:.3f} s: nu = ({', '.join(f'{x:.4g}' for x in nu)})"
        f", nu_dot = ({', '.join(f'{x:.4g}' for x in nud)}); check the plant parameters, "
        "the timestep and the applied forces"
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
    ) -> None:
        self.vessel = load_vessel(vessel)
        v = self.vessel
        self.plant = v.plant(plant) if isinstance(plant, str) else plant
        four = is_hull4(self.plant)
        if not (four or isinstance(self.plant, PlantModel | MMGHull)):
            raise TypeError(
                f"plant must be a PlantModel, an MMGHull, a 4-DOF hull (Hull4, Blanke4Hull) or a "
                f"variant "
                f"name, got {plant!r}"
            )
        dofs = 4 if four else 3
        if dofs != v.dofs:
            raise ValueError(f"plant {plant!r} has {dofs} DOF but vessel {v.name!r} has {v.dofs}")
        self.dofs = dofs
        # the actuators this plant drives (a plant of the paper's model: the bollard laws)
        self.actuators = acts = v.actuators_for(self.plant)
        # the thrust model a DP system computes from the actuator states (feedback): the
        # bollard laws (the advance-speed and tunnel losses are the plant's, not known to it)
        bollard = acts.bollard()
        self._model_actuators = None if bollard is acts else bollard
        # its plain-float kernel where every actuator of that set is MuJoCo-applied
        self._model_tau_of = (
            bollard.kernel() if bollard is not acts and not bollard.flow_dependent else None
        )
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
        lags = [c.time_constant for c in acts.channels if c.dynamics == "lag"]
        if lags and self.model.opt.timestep > 0.5 * min(lags) + 1e-12:
            raise ValueError(
                f"timestep {self.model.opt.timestep:g} s is more than half the shortest actuator "
                f"lag of {v.name!r} ({min(lags):g} s): use timestep <= {0.5 * min(lags):g}"
            )
        self.data = mujoco.MjData(self.model)
        self._bind_model()
        # plain-float thrust laws for reading (tau_thrusters, thrust): no MuJoCo writes
        self._tau_of = acts.kernel()
        self._thrust_of = acts.thrust_kernel()
        self._flow_mask = tuple(a.flow_dependent for a in acts)
        # channels whose state lags its command (the others integrate it: azimuth angles)
        self._lagged = tuple(i for i, c in enumerate(acts.channels) if c.dynamics == "lag")
        # rate-limited servos (rudders): (channel, largest rate rad/s, time constant s or 0)
        self._servos = tuple(
            (i, c.rate, c.time_constant)
            for i, c in enumerate(acts.channels)
            if c.dynamics == "servo"
        )
        self._servo_cmd = [0.0] * len(self._servos)
        # rate-limited lags: (channel, largest rate, time constant); their commands are held
        # here and MuJoCo's filterexact is fed the rate-limited command of each physics step
        self._ratelim = tuple(
            (i, c.rate, c.time_constant)
            for i, c in enumerate(acts.channels)
            if c.dynamics == "lag" and math.isfinite(c.rate)
        )
        self._rl_cmd = [0.0] * len(self._ratelim)
        # a rate-limited state may be ramping (set by a new command or a reset; cleared by
        # prepare once every state is within its band of its command, where it stays)
        self._ramping = True
        self._flow_of = acts.flow_kernel()
        n_flow = sum(1 for a in acts if a.flow_dependent)
        #: per servo channel: whether the servo was still running at its rate limit in the last
        #: physics step of the last :meth:`step` (it has not reached its command because of the
        #: rate limit; an ideal servo runs at full rate for every move, and only a move that
        #: outlasts the call counts)
        self.rate_limited = np.zeros(len(self._servos), dtype=bool)
        #: per flow-dependent actuator (rudders, MMG units): whether its effective angle was
        #: past the stall angle at the last step (an MMG unit never stalls)
        self.stalled = np.zeros(n_flow, dtype=bool)
        self._flow = (0.0, 0.0, 0.0, 0.0, (0.0,) * n_flow, (False,) * n_flow)
        self._rate_hits = [0] * len(self._servos)
        self._external = (0.0, 0.0, 0.0, 0.0)
        self._linear_kin = getattr(self.plant, "kinematics", "fossen") == "linear"
        self.wind = Wind(self.wind_config, self.windage)
        self._wind_load = self._make_wind_load()
        self._accel = self.plant.accel
        self._loads = (0.0,) * 8
        self.saturated = np.zeros(v.actuators.n_channels, dtype=bool)
        self._native: Any = None
        self._prepare = self._make_prepare()
        self.reset()

    # ---- set-up ----------------------------------------------------------------------------
    def _make_wind_load(self) -> WindLoad:
        name = self.wind_config.coefficients or self.windage.coefficients
        return WindLoad(blendermann(name), self.windage)

    def _bind_model(self) -> None:
        m = self.model
        names = ("x", "y", "psi", "phi")[: self.dofs]
        jids = [m.joint(n).id for n in names]
        self.hull_body = m.body("hull").id
        self._act_ids = [m.actuator(n).id for n in self.actuators.channel_names]
        if jids != list(range(self.dofs)) or m.nv != self.dofs:
            raise ValueError(f"the hull must have exactly the joints {names}, in this order")
        if self._act_ids != list(range(m.nu)) or m.nu != self.actuators.n_channels:
            raise ValueError("MuJoCo actuators must be the vessel's channels, in order")
        d = mujoco.MjData(m)
        if self.dofs == 4:  # a rolled, moving state: the inertia must not depend on it
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
        self._m_q, self._i_q = float(Mq[0, 0]), float(Mq[2, 2])
        self._i_x = float(Mq[3, 3]) if self.dofs == 4 else 0.0

    def set_current(
        self, current: CurrentConfig | str | tuple[float, float] | Mapping[str, Any] | None
    ) -> None:
        """Replace the current model (any form of ``current=``; effective at :meth:`reset`)."""
        self.current_config = _current_config(current)
        self.current = Current(self.current_config)
        self._prepare = self._make_prepare()

    def set_wind(
        self, wind: WindConfig | str | tuple[float, float] | Mapping[str, Any] | None
    ) -> None:
        """Replace the wind model (any form of ``wind=``; takes effect at :meth:`reset`)."""
        wind_cfg = WindConfig.coerce(wind, name="wind")
        self.aerodynamics = wind_cfg is not None
        self.wind_config = wind_cfg if wind_cfg is not None else WindConfig()
        self.wind = Wind(self.wind_config, self.windage)
        self._wind_load = self._make_wind_load()
        self._prepare = self._make_prepare()

    # ---- state -----------------------------------------------------------------------------
    def _vector(self, x: ArrayLike | None, n: tuple[int, ...], what: str) -> NDArray[np.float64]:
        a = np.asarray(x, dtype=float)
        if a.shape not in [(k,) for k in n] or not np.all(np.isfinite(a)):
            raise ValueError(f"{what} must be {' or '.join(map(str, n))} finite numbers, got {x!r}")
        return a

    def initial_actuator_state(self) -> NDArray[np.float64]:
        """Actuator states after a reset: zero thrust, azimuths at their rest angle."""
        out = np.zeros(self.actuators.n_channels)
        for a, sl in zip(self.actuators, self.actuators.slices, strict=True):
            if isinstance(a, Azimuth):
                out[sl.start + 1] = a.angle0
        return out

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
        act = (
            self.initial_actuator_state()
            if actuators is None
            else self.actuators.check_states(actuators, "actuators")
        )
        d = self.data
        mujoco.mj_resetData(self.model, d)
        if self.dofs == 3:
            d.qpos[:] = eta_a
            c, s = math.cos(eta_a[2]), math.sin(eta_a[2])
            d.qvel[:] = (c * nu_a[0] - s * nu_a[1], s * nu_a[0] + c * nu_a[1], nu_a[2])
        else:
            x, y, phi, psi = eta_a.tolist()
            u, v, p, r = nu_a.tolist()
            if abs(phi) >= _MAX_ROLL:
                raise ValueError(f"roll angle must be below {_MAX_ROLL} rad, got {phi!r}")
            d.qpos[:] = (x, y, psi, phi)
            c, s = math.cos(psi), math.sin(psi)
            cf = 1.0 if self._linear_kin else math.cos(phi)
            d.qvel[:] = (c * u - s * cf * v, s * u + c * cf * v, r * cf, p)
        lagged = np.array([ch.dynamics == "lag" for ch in self.actuators.channels])
        d.act[:] = np.where(lagged, np.clip(act, self.actuators.lower, self.actuators.upper), act)
        for k, (j, _rate, _tc) in enumerate(self._servos):  # a servo's angle within its range
            d.act[j] = min(max(float(act[j]), self._lower[j]), self._upper[j])
            self._servo_cmd[k] = float(d.act[j])
        for k, (j, _rate, _tc) in enumerate(self._ratelim):
            self._rl_cmd[k] = float(d.act[j])
        self._ramping = True
        d.ctrl[:] = np.where(lagged, d.act, 0.0)
        self.saturated[:] = False
        self.rate_limited[:] = False
        self._external = (0.0, 0.0, 0.0, 0.0)
        rng = rng if rng is not None else np.random.default_rng(0)
        # fixed order, one draw each: the same seed gives the same disturbances
        self.wind.reset(rng)
        self.current.reset(rng)
        if self.waves is not None:
            self.waves.reset(rng)
        # leapfrog start: qacc = a_0 = f(q_0, v_0), qvel = v_{-1/2} = v_0 - h/2 a_0
        if self.model.opt.timestep != self._h:
            self._prepare = self._make_prepare()
        self._prepare()
        mujoco.mj_forward(self.model, d)
        d.qvel[:] -= 0.5 * self.model.opt.timestep * d.qacc
        mujoco.mj_forward(self.model, d)

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
        return self._loads[0:3]

    @property
    def tau_waves(self) -> tuple[float, float, float]:
        """Second-order wave drift load ``[X, Y, N]`` (N, N, N m, body) of the last step."""
        return self._loads[3:6]

    @property
    def nu_c(self) -> tuple[float, float]:
        """Current ``(u_c, v_c)`` (m/s) in the body frame at the last physics step."""
        return self._loads[6:8]

    @property
    def time(self) -> float:
        """Simulation time (s)."""
        return float(self.data.time)

    @property
    def timestep(self) -> float:
        """Physics step (s)."""
        return float(self.model.opt.timestep)

    def _qvel_whole(self) -> list[float]:
        """The joint velocity at the whole step (leapfrog, module docstring)."""
        hh = 0.5 * self._h  # plain floats: the same products and sums as the array form
        qvel, qacc = self.data.qvel.tolist(), self.data.qacc.tolist()
        return [w + hh * a for w, a in zip(qvel, qacc, strict=True)]

    @property
    def eta(self) -> NDArray[np.float64]:
        """Pose ``[x (m north), y (m east), psi (rad)]``; psi is continuous (not wrapped)."""
        return self.data.qpos[:3].copy()

    @property
    def phi(self) -> float:
        """Roll angle (rad, starboard down), 0 for a 3-DOF vessel."""
        return float(self.data.qpos[3]) if self.dofs == 4 else 0.0

    @property
    def nu(self) -> NDArray[np.float64]:
        """Body velocity ``[u (m/s), v (m/s), r (rad/s)]``."""
        if self.dofs == 4:
            return self.nu_full[[0, 1, 3]]
        return np.array(self._nu3())

    def _nu3(self) -> tuple[float, float, float]:
        """``(u, v, r)`` of a 3-DOF hull as floats (:attr:`nu`)."""
        hh = 0.5 * self._h
        w0, w1, w2 = self.data.qvel.tolist()
        a0, a1, a2 = self.data.qacc.tolist()
        xd, yd = w0 + hh * a0, w1 + hh * a1
        psi = self.data.qpos.tolist()[2]
        c, s = math.cos(psi), math.sin(psi)
        return c * xd + s * yd, -s * xd + c * yd, w2 + hh * a2

    @property
    def p(self) -> float:
        """Roll rate (rad/s), 0 for a 3-DOF vessel."""
        return float(self.nu_full[2]) if self.dofs == 4 else 0.0

    @property
    def eta_full(self) -> NDArray[np.float64]:
        """``[x, y, psi]`` (3 DOF) or Fossen's ``[x, y, phi, psi]`` (4 DOF)."""
        q = self.data.qpos
        return q.copy() if self.dofs == 3 else np.array([q[0], q[1], q[3], q[2]])

    @property
    def nu_full(self) -> NDArray[np.float64]:
        """``[u, v, r]`` (3 DOF) or Fossen's ``[u, v, p, r]`` (4 DOF)."""
        if self.dofs == 3:
            return self.nu
        w = self._qvel_whole()
        psi = float(self.data.qpos[2])
        c, s = math.cos(psi), math.sin(psi)
        u = c * w[0] + s * w[1]
        vh = -s * w[0] + c * w[1]
        cf = 1.0 if self._linear_kin else math.cos(float(self.data.qpos[3]))
        return np.array([u, vh / cf, w[3], w[2] / cf])

    @property
    def actuator_state(self) -> NDArray[np.float64]:
        """Actuator states (lagged commands; azimuth angles in rad), in channel order."""
        return self.data.act.copy()

    @property
    def command(self) -> NDArray[np.float64]:
        """Current (saturated) commands, in channel order (a servo's: its commanded angle)."""
        out = self.data.ctrl.copy()
        for k, (j, _rate, _tc) in enumerate(self._servos):
            out[j] = self._servo_cmd[k]
        for k, (j, _rate, _tc) in enumerate(self._ratelim):
            out[j] = self._rl_cmd[k]
        return out

    @property
    def thrust(self) -> NDArray[np.float64]:
        """Signed thrust of every actuator (N) at the current states (a rudder: its lift, an
        MMG unit: its propeller thrust, at the last physics step)."""
        out = self._thrust_of(self.data.act.tolist())
        if self._flow_of is not None:
            lifts = iter(self._flow[4])
            out = [next(lifts) if flow else f for flow, f in zip(self._flow_mask, out, strict=True)]
        return np.array(out)

    def _flow_now(self, st: list[float]) -> tuple[float, float, float, float]:
        """The flow-dependent actuators' ``(X, Y, K, N)`` at the actuator states ``st`` and the
        current velocity through the water (the current of the last physics step)."""
        if self._flow_of is None:
            return 0.0, 0.0, 0.0, 0.0
        if self.dofs == 4:
            u, v, p, r = self.nu_full.tolist()
        else:
            u, v, r = self._nu3()
            p = 0.0
        uc, vc = self._loads[6], self._loads[7]
        X, Y, K, N, _l, _s = self._flow_of(st, u - uc, v - vc, p, r)
        return X, Y, K, N

    @property
    def tau_thrusters(self) -> NDArray[np.float64]:
        """Body-frame actuator force ``[X, Y, N]`` (N, N, N m) at the current actuator states
        (rudders at the current flow)."""
        st = self.data.act.tolist()
        X, Y, _K, N, _ = self._tau_of(st)
        if self._flow_of is None:
            return np.array([X, Y, N])
        fx, fy, _fk, fn = self._flow_now(st)
        return np.array([X + fx, Y + fy, N + fn])

    @property
    def tau_model(self) -> NDArray[np.float64]:
        """Body-frame actuator force ``[X, Y, N]`` (N, N, N m) that a DP system computes from
        the current actuator states (its shaft-speed and thruster feedback) with its thrust
        model: every propeller on its bollard law (:meth:`ActuatorSet.bollard
        <shipgym.dynamics.actuators.ActuatorSet.bollard>`), without the plant's advance-speed
        and tunnel losses; :attr:`tau_thrusters` where the two laws are the same."""
        if self._model_actuators is None:
            return self.tau_thrusters
        if self._model_tau_of is not None:
            X, Y, _K, N, _ = self._model_tau_of(self.data.act.tolist())
            return np.array([X, Y, N])
        return self._model_actuators.tau(self.data.act.copy())

    @property
    def tau_actuators(self) -> NDArray[np.float64]:
        """Body-frame actuator force ``[X, Y, K, N]`` (N, N, N m, N m) at the current actuator
        states and flow (``K`` is 0 for a 3-DOF vessel)."""
        st = self.data.act.tolist()
        X, Y, K, N, _ = self._tau_of(st)
        fx, fy, fk, fn = self._flow_now(st)
        return np.array([X + fx, Y + fy, K + fk if self.dofs == 4 else 0.0, N + fn])

    @property
    def external_force(self) -> tuple[float, float, float, float]:
        """The external load ``[X, Y, K, N]`` (N, N, N m, N m, body) set by
        :meth:`set_external_force`."""
        return self._external

    def set_external_force(self, tau: ArrayLike) -> None:
        """Hold an external body load ``[X, Y, K, N]`` (N, N, N m, N m; ``[X, Y, N]`` for 3 DOF)
        until changed: a task's disturbance (wave roll and yaw moments). Reset clears it.

        Raises:
            ValueError: wrong shape or a non-finite value.
        """
        a = self._vector(tau, (self.dofs,), "external force")
        vals = a.tolist()
        self._external = tuple(vals) if self.dofs == 4 else (vals[0], vals[1], 0.0, vals[2])

    @property
    def tau_command(self) -> NDArray[np.float64]:
        """Body-frame thrust ``[X, Y, N]`` (N, N, N m) the current commands give in steady state.

        The thrust law of :attr:`tau_thrusters` with every lagged channel's state replaced by
        its (saturated) command, while integrator channels (azimuth angles) keep their current
        state: the force the held commands would give once the lags have settled, at the
        actuators' current angles (the demand ``u`` of a model with its own thruster lags,
        Al-Takie 1982 eq. 3.21).
        """
        st = self.data.act.tolist()
        ctrl = self.data.ctrl.tolist()
        for i in self._lagged:
            st[i] = ctrl[i]
        for k, (j, _rate, _tc) in enumerate(self._ratelim):
            st[j] = self._rl_cmd[k]
        for k, (j, _rate, _tc) in enumerate(self._servos):
            st[j] = self._servo_cmd[k]
        X, Y, _K, N, _ = self._tau_of(st)
        fx, fy, _fk, fn = self._flow_now(st)
        return np.array([X + fx, Y + fy, N + fn])

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
        # (map: the lengths are equal by construction, as_vector checked the command's)
        clipped = list(map(_clip, vals, self._lower, self._upper))
        self.saturated = np.array(list(map(operator.ne, clipped, vals)))
        if self._servos or self._ratelim:
            held = self.data.ctrl.tolist()
            for k, (j, _rate, _tc) in enumerate(self._servos):
                # a servo's command is its angle; prepare() turns it into a rate
                self._servo_cmd[k] = clipped[j]
                clipped[j] = held[j]
            for k, (j, _rate, _tc) in enumerate(self._ratelim):
                # a rate-limited lag's command: prepare() feeds MuJoCo its ramp
                self._rl_cmd[k] = clipped[j]
                clipped[j] = held[j]
            if self._ratelim:
                self._ramping = True
        self.data.ctrl[:] = clipped
        return self.saturated.copy()

    def step(self, n: int = 1, *, stop_on_contact: bool = False) -> int:
        """Advance ``n`` physics steps with hydrodynamics, wind and current refreshed every step.

        Args:
            n: number of physics steps.
            stop_on_contact: return early, after the step in which MuJoCo detects a contact.

        Returns:
            The number of steps taken.

        Raises:
            SimulationDiverged: a non-finite or absurd state (the state before the step is kept).
        """
        if self.model.opt.timestep != self._h:
            self._prepare = self._make_prepare()
        if self._native is not None:
            return self._native(n, stop_on_contact)
        prepare, mj_step, m, d = self._prepare, mujoco.mj_step, self.model, self.data
        hits = self._rate_hits
        taken = n
        for i in range(n):
            prepare()
            mj_step(m, d)
            if stop_on_contact and d.ncon:
                taken = i + 1
                break
        if self._servos:
            self.rate_limited[:] = [h > 0 for h in hits]
        if self._flow_of is not None:
            self.stalled[:] = self._flow[5]
        return taken

    def contacts(self) -> list[tuple[str, str]]:
        """Pairs of geom names in contact now (the hull's geom first when it is involved)."""
        m, d = self.model, self.data
        out = []
        for c in d.contact[: d.ncon]:
            a, b = m.geom(c.geom1), m.geom(c.geom2)
            if b.bodyid[0] == self.hull_body:
                a, b = b, a
            out.append((a.name, b.name))
        return out

    def _make_prepare(self):  # type: ignore[no-untyped-def]
        """Build the per-step force computation as a closure (locals bound once: hot path)."""
        m, d = self.model, self.data
        qpos, qvel, qacc, act, qfrc = d.qpos, d.qvel, d.qacc, d.act, d.qfrc_applied
        # the thrust law of every actuator kind; it also refreshes MuJoCo's state-dependent
        # actuator gains (k |n|) and azimuth directions, so MuJoCo applies the same force
        tau_of = self.actuators.kernel(m.actuator_gainprm, m.actuator_gear)
        # every actuator flow-dependent (the Blue Lady's default plant): MuJoCo applies none
        mj_thrust = not all(a.flow_dependent for a in self.actuators)
        mq, iq, ix = self._m_q, self._i_q, self._i_x
        accel, wind_at, wind_load = self._accel, self.wind.at_kernel(), self._wind_load.kernel()
        cc = self.current_config
        current_at = None if (cc.is_constant and cc.speed == 0.0) else self.current.at
        drift = None if self.waves is None or not self.wave_config.drift else self.waves.drift_load
        aero = self.aerodynamics
        cos, sin, isfinite = math.cos, math.sin, math.isfinite
        four = self.dofs == 4
        this = self
        servos = tuple((k, j, rate, tc) for k, (j, rate, tc) in enumerate(self._servos))
        servo_cmd, hits, ctrl = self._servo_cmd, self._rate_hits, d.ctrl
        flow_of = self._flow_of
        linear_kin = self._linear_kin
        rl_cmd = self._rl_cmd
        # half the timestep, read once (a MuJoCo option read costs a third of a microsecond);
        # step() and reset() rebuild this closure when model.opt.timestep has changed
        self._h = float(m.opt.timestep)
        hh = 0.5 * self._h
        # a rate-limited lag a_dot = clip((c - a) / T, +-rate): past |c - a| = rate T MuJoCo's
        # exact filter is fed a + rate h / (1 - exp(-h/T)), which moves the state by exactly
        # rate h in the step; below it the command itself (the lag)
        rlims = tuple(
            (k, j, rate * tc, rate * self._h / -math.expm1(-self._h / tc))
            for k, (j, rate, tc) in enumerate(self._ratelim)
        )

        def ramp(st: list[float]) -> None:
            """MuJoCo's command of each rate-limited lag this step (above). Once every state
            is within its band, MuJoCo gets the commands themselves and the lags only close
            in on them (the filter is exact and monotone): nothing to do until the next
            command."""
            active = False
            for k, j, band, step in rlims:
                c_, a_ = rl_cmd[k], st[j]
                if c_ - a_ > band:
                    c_ = min(a_ + step, c_)
                    active = True
                elif a_ - c_ > band:
                    c_ = max(a_ - step, c_)
                    active = True
                ctrl[j] = c_
            if not active:
                this._ramping = False

        def loads(t: float, psi: float, u: float, v: float) -> tuple[float, ...]:
            """Wind (relative to the ground velocity), current (NED) and wave drift."""
            if aero:
                vw, bw = wind_at(t)
                wx, wy, wn = wind_load(psi, u, v, vw, bw)
            else:
                wx = wy = wn = 0.0
            if current_at is not None:
                vc, bc = current_at(t)
                uc = vc * cos(bc - psi)
                vcb = vc * sin(bc - psi)
            else:
                uc = vcb = 0.0
            if drift is not None:
                dx_, dy_, dn_ = drift(t, psi)
            else:
                dx_ = dy_ = dn_ = 0.0
            return wx, wy, wn, uc, vcb, dx_, dy_, dn_

        def servo(st: list[float]) -> None:
            """Each servo's rate this step: towards its command, limited (Channel "servo")."""
            for k, j, rate, tc in servos:
                w = (servo_cmd[k] - st[j]) / (tc if tc > 0.0 else this._h)
                if w > rate:
                    w = rate
                    hits[k] = 1
                elif w < -rate:
                    w = -rate
                    hits[k] = 1
                else:
                    hits[k] = 0
                ctrl[j] = w

        def prepare3() -> None:
            psi = qpos.tolist()[2]
            t = d.time
            # velocity at the whole step from the half-step qvel (leapfrog, see module doc)
            w0, w1, w2 = qvel.tolist()
            a0, a1, a2 = qacc.tolist()
            xd, yd, r = w0 + hh * a0, w1 + hh * a1, w2 + hh * a2
            st = act.tolist()
            c, s = cos(psi), sin(psi)
            u = c * xd + s * yd
            v = c * yd - s * xd
            if mj_thrust:
                tx, ty, _k, tn, _mz = tau_of(st)
            else:
                tx = ty = tn = 0.0
            wx, wy, wn, uc, vcb, dx_, dy_, dn_ = loads(t, psi, u, v)
            ex, ey, _ek, en = this._external
            if servos:
                servo(st)
            if rlims and this._ramping:
                ramp(st)
            if flow_of is not None:
                fl = flow_of(st, u - uc, v - vcb, 0.0, r)
                this._flow = fl
                ex += fl[0]
                ey += fl[1]
                en += fl[3]
            ud, vd, rd = accel(
                u, v, r, tx + (wx + dx_ + ex), ty + (wy + dy_ + ey), tn + (wn + dn_ + en), uc, vcb
            )
            if not (
                isfinite(ud + vd + rd) and abs(u) + abs(v) < _MAX_SPEED and abs(r) < _MAX_YAW_RATE
            ):
                diverged(t, (u, v, r), (ud, vd, rd))
            # joint acceleration qacc* = R(psi)(nu_dot + r S nu), S nu = [-v, u, 0]
            bx = ud - r * v
            by = vd + r * u
            # qfrc_applied = M_q qacc* - qfrc_actuator  (qfrc_bias = qfrc_passive = 0 here)
            qfrc[0] = mq * (c * bx - s * by) - (c * tx - s * ty)
            qfrc[1] = mq * (s * bx + c * by) - (s * tx + c * ty)
            qfrc[2] = iq * rd - tn
            this._loads = (wx, wy, wn, dx_, dy_, dn_, uc, vcb)

        def prepare4() -> None:
            _x, _y, psi, phi = qpos.tolist()
            t = d.time
            w0, w1, w2, w3 = qvel.tolist()
            a0, a1, a2, a3 = qacc.tolist()
            xd, yd, psid, phid = w0 + hh * a0, w1 + hh * a1, w2 + hh * a2, w3 + hh * a3
            c, s = cos(psi), sin(psi)
            # MuJoCo's transmission of the rolled hull (ct, st_), and the model's kinematics
            ct, st_ = cos(phi), sin(phi)
            cf, sf = (1.0, 0.0) if linear_kin else (ct, st_)
            u = c * xd + s * yd
            v = (c * yd - s * xd) / cf
            r = psid / cf
            p = phid
            st = act.tolist()
            tx, ty, tk, tn, tmz = tau_of(st)
            wx, wy, wn, uc, vcb, dx_, dy_, dn_ = loads(t, psi, u, v)
            ex, ey, ek, en = this._external
            if servos:
                servo(st)
            if rlims and this._ramping:
                ramp(st)
            if flow_of is not None:
                fl = flow_of(st, u - uc, v - vcb, p, r)
                this._flow = fl
                ex += fl[0]
                ey += fl[1]
                ek += fl[2]
                en += fl[3]
            ud, vd, pd, rd = accel(
                u, v, p, r, phi, tx + (wx + dx_ + ex), ty + (wy + dy_ + ey), tk + ek,
                tn + (wn + dn_ + en), uc, vcb,
            )  # fmt: skip
            if not (
                isfinite(ud + vd + pd + rd)
                and abs(u) + abs(v) < _MAX_SPEED
                and abs(r) + abs(p) < _MAX_YAW_RATE
                and abs(phi) < _MAX_ROLL
            ):
                diverged(t, (u, v, p, r), (ud, vd, pd, rd))
            # qacc* = J(q) nu_dot + J_dot nu (Fossen's 4-DOF kinematics, module docstring)
            xdd = c * ud - s * cf * vd - s * u * psid - c * cf * v * psid + s * sf * v * phid
            ydd = s * ud + c * cf * vd + c * u * psid - s * cf * v * psid - c * sf * v * phid
            psidd = cf * rd - sf * r * phid
            # minus the actuators' generalised force as MuJoCo's site transmission applies it
            qfrc[0] = mq * xdd - (c * tx - s * ct * ty)
            qfrc[1] = mq * ydd - (s * tx + c * ct * ty)
            qfrc[2] = iq * psidd - (ct * tn + st_ * tmz)
            qfrc[3] = ix * pd - tk
            this._loads = (wx, wy, wn, dx_, dy_, dn_, uc, vcb)

        self._native = None if four else self._make_native()
        return prepare4 if four else prepare3

    def _make_native(self) -> Any:
        """The compiled form of ``prepare3`` and the stepping loop (:mod:`shipgym.envs._native`)
        as ``run(n, stop_on_contact) -> steps taken``, or ``None`` where it does not cover this
        physics (then :meth:`step` runs the Python closure)."""
        import shipgym.envs._native as nat

        acts = self.actuators
        props = acts.propeller_flow_table()
        if (
            not nat.available()
            or not isinstance(self.plant, PlantModel)
            or (self._flow_of is not None and props is None)
        ):
            return None
        m, d = self.model, self.data
        t_var, t_lat, t_sta, t_azi, t_props = nat.actuator_tables(acts)
        h = self._h
        table = nat.table
        servos = table([(k, j, rate, tc) for k, (j, rate, tc) in enumerate(self._servos)], 4)
        rlims = table(
            [(k, j, rate * tc, rate * h / -math.expm1(-h / tc))
             for k, (j, rate, tc) in enumerate(self._ratelim)], 4
        )  # fmt: skip
        fp = nat.parameters(self.plant, self._wind_load)
        wind, cur = self.wind, self.current
        w_mode = -1.0 if not self.aerodynamics else (0.0 if wind._const is not None else 1.0)
        cc = self.current_config
        c_mode = 0.0 if (cc.is_constant and cc.speed == 0.0) else (
            1.0 if cur._const is not None else 2.0)  # fmt: skip
        F = nat._FP
        fp[F : F + 4] = (0.5 * h, h, self._m_q, self._i_q)
        fp[F + 4 : F + 9] = (w_mode, *(wind._const or (0.0, 0.0)), wind._inv_dt, 0.0)
        fp[F + 9 : F + 14] = (c_mode, *(cur._const or (0.0, 0.0)), cur._inv_dt, 0.0)
        fp[F + 17] = 0.0 if all(a.flow_dependent for a in acts) else 1.0
        waves = self.waves if self.wave_config is not None and self.wave_config.drift else None
        if waves is not None and waves._drift_on:
            from shipgym.disturbances.waves import _CHUNK

            assert _CHUNK == nat.CHUNK, "the compiled step reads wave chunks of the grid's size"
            fp[F + 18 : F + 25] = (1.0, waves._inv_dt, 0.0, waves._beta_p, waves._kx,
                                   waves._ky, waves._kn)  # fmt: skip
        n_flow = len(props or ())
        out = np.zeros(12 + n_flow)
        state = np.zeros(3, dtype=np.int64)
        no_chunk = np.zeros((2, 2))
        ncon = nat.ncon_view(m, d)
        hits = np.zeros(len(self._servos), dtype=np.int64)
        no_stall = (False,) * n_flow
        run3, mj_step = nat.run3, nat.mj_step_address()
        mp, dp = m._address, d._address
        qpos, qvel, qacc, act, ctrl, qfrc = d.qpos, d.qvel, d.qacc, d.act, d.ctrl, d.qfrc_applied
        gain, gear = m.actuator_gainprm, m.actuator_gear
        this = self

        # the processes read on a grid, by run3's code for "chunk needed": (slot in chunks,
        # the process, its 1/dt, where fp holds its chunk's first sample)
        grids = {
            code: (i, proc, proc._inv_dt, at)
            for i, (code, proc, on, at) in enumerate(
                (
                    (nat.NEED_WIND, wind, w_mode == 1.0, F + 8),
                    (nat.NEED_CURRENT, cur, c_mode == 2.0, F + 13),
                    (nat.NEED_DRIFT, waves, fp[F + 18] == 1.0, F + 20),
                )
            )  # fmt: skip
            if on
        }
        chunks = [no_chunk, no_chunk, no_chunk]
        s_cmd = np.zeros(len(self._servos))
        r_cmd = np.zeros(len(self._ratelim))
        last_ext: list[Any] = [None]

        def select(i: int, proc: Any, j: int, at: int) -> None:
            """The process's chunk ``j`` into ``chunks[i]``, made as the Python step makes it."""
            if proc._j != j:
                proc._select(j)
            fp[at] = j * nat.CHUNK
            chunks[i] = proc._chunks[j]

        def run(n: int, stop_on_contact: bool) -> int:
            ext = this._external
            if ext is not last_ext[0]:
                fp[F + 14 : F + 17] = (ext[0], ext[1], ext[3])
                last_ext[0] = ext
            state[0] = this._ramping
            if len(s_cmd):
                s_cmd[:] = this._servo_cmd
            if len(r_cmd):
                r_cmd[:] = this._rl_cmd
            t = d.time
            for i, proc, inv, at in grids.values():
                select(i, proc, int(t * inv) // nat.CHUNK, at)
            taken, left = 0, n
            while True:
                code = run3(
                    mj_step, mp, dp, left, stop_on_contact, t, ncon,
                    qpos, qvel, qacc, act, ctrl, qfrc, gain, gear,
                    fp, t_var, t_lat, t_sta, t_azi, t_props, servos, s_cmd, hits, rlims, r_cmd,
                    chunks[0], chunks[1], chunks[2], state, out,
                )  # fmt: skip
                k = int(state[1])
                taken += k
                left -= k
                if code not in grids:
                    break
                i, proc, _inv, at = grids[code]
                select(i, proc, int(state[2]), at)
                t = d.time
            this._ramping = bool(state[0])
            if len(hits):
                this._rate_hits[:] = hits.tolist()
                this.rate_limited[:] = hits > 0
            if taken:
                this._loads = tuple(out[:8].tolist())
                if n_flow:
                    vals = out.tolist()
                    this._flow = (*vals[8:12], tuple(vals[12:]), no_stall)
            if code == nat.DIVERGED:
                vals = out[:7].tolist()
                diverged(vals[0], vals[1:4], vals[4:7])
            return taken

        return run
