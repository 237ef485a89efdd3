r"""MuJoCo physics of a planar hull that moves exactly as the 3-DOF model says.

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
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import is_real
from shipgym.assets import asset_path
from shipgym.disturbances import (
    Current,
    CurrentConfig,
    WaveConfig,
    Waves,
    Wind,
    WindConfig,
    WindLoad,
    blendermann,
)
from shipgym.dynamics import (
    ACTUATOR_NAMES,
    BLUE_LADY_HULL,
    BLUE_LADY_THRUSTERS,
    BLUE_LADY_WINDAGE,
    PlantModel,
    ThrusterParameters,
    WindageParameters,
    plant_model,
    validate_command,
)
from shipgym.envs._mujoco import mujoco

__all__ = [
    "VesselPhysics",
    "SimulationDiverged",
    "DEFAULT_SCENE",
    "MAX_TIMESTEP",
    "MIN_TIMESTEP",
    "check_timestep",
]

DEFAULT_SCENE = ("mjcf", "blue_lady", "scene.xml")

#: bounds beyond which the simulation is declared diverged (m/s, rad/s): far above anything
#: the Blue Lady can reach (max speed 3.1 kn = 1.6 m/s).
_MAX_SPEED = 50.0
_MAX_YAW_RATE = 10.0


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
#: largest physics timestep (s): half the shortest thruster time constant (1 s, the tunnel
#: thrusters), where MuJoCo's semi-implicit Euler still tracks the first-order lags.
MAX_TIMESTEP = 0.5


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
    """A MuJoCo hull driven by thrusters, the 3-DOF hydrodynamics, wind and current.

    Args:
        plant: a :class:`PlantModel` or a plant variant name (``"default"``, ``"seed-linear"``).
        thrusters: thruster parameters; written into the MJCF actuators at load time.
        wind: wind: a :class:`~shipgym.disturbances.WindConfig`, ``"SPEED@FROM_DEG"``,
            ``(speed m/s, from deg)`` or a mapping (any form of
            :meth:`WindConfig.coerce <shipgym.disturbances.WindConfig.coerce>`). ``None``
            switches aerodynamic loads off altogether; ``WindConfig(speed=0)`` is still air, in
            which a moving hull feels air drag.
        windage: projected areas for the wind load.
        current: current in NED: a :class:`~shipgym.disturbances.CurrentConfig` (constant or
            Gauss-Markov), ``"SPEED@TO_DEG"``, a constant ``(speed m/s, direction it goes to,
            deg)``, a mapping (:meth:`CurrentConfig.coerce
            <shipgym.disturbances.CurrentConfig.coerce>`) or ``None`` (no current). It acts
            through the relative velocity ``nu_r = nu - nu_c`` only.
        waves: a :class:`~shipgym.disturbances.WaveConfig` for the second-order (mean and
            slowly varying) drift load on the hull, or ``None``. First-order wave motion is
            not a hull motion: the environment adds it to the measurements
            (:meth:`wave_motion`).
        xml_path: MJCF scene with a body ``hull`` on joints ``x``, ``y``, ``psi`` and actuators
            ``main_propeller``, ``bow_tunnel``, ``stern_tunnel`` (default: the Blue Lady scene).
        timestep: physics step (s), :data:`MIN_TIMESTEP` to :data:`MAX_TIMESTEP`; ``None``
            keeps the MJCF value (0.05 s).

    The physics owns no task logic: commands in, state out (dm_control's Physics/Task split).
    """

    def __init__(
        self,
        plant: PlantModel | str = "default",
        thrusters: ThrusterParameters = BLUE_LADY_THRUSTERS,
        wind: WindConfig | str | tuple[float, float] | Mapping[str, Any] | None = None,
        windage: WindageParameters = BLUE_LADY_WINDAGE,
        *,
        current: CurrentConfig | str | tuple[float, float] | Mapping[str, Any] | None = None,
        waves: WaveConfig | None = None,
        xml_path: str | Path | None = None,
        timestep: float | None = None,
    ) -> None:
        self.plant = plant_model(plant, BLUE_LADY_HULL) if isinstance(plant, str) else plant
        if not isinstance(self.plant, PlantModel):
            raise TypeError(f"plant must be a PlantModel or a variant name, got {plant!r}")
        self.thrusters = thrusters
        self._lower = thrusters.lower.tolist()
        self._upper = thrusters.upper.tolist()
        wind_cfg = WindConfig.coerce(wind, name="wind")
        self.aerodynamics = wind_cfg is not None
        self.wind_config = wind_cfg if wind_cfg is not None else WindConfig()
        self.windage = windage
        self.current_config = _current_config(current)
        self.current = Current(self.current_config)
        if waves is not None and not isinstance(waves, WaveConfig):
            raise ValueError(f"waves must be a WaveConfig or None, got {waves!r}")
        self.wave_config = waves
        self.waves = Waves(waves, BLUE_LADY_HULL) if waves is not None else None
        path = Path(xml_path) if xml_path is not None else asset_path(*DEFAULT_SCENE)
        if not path.exists():
            raise FileNotFoundError(f"MJCF file not found: {path}")
        self.model = mujoco.MjModel.from_xml_path(str(path))
        if timestep is not None:
            self.model.opt.timestep = check_timestep(timestep)
        self.data = mujoco.MjData(self.model)
        self._bind_model()
        self.wind = Wind(self.wind_config, windage)
        self._wind_load = WindLoad(blendermann(self.wind_config.coefficients), windage)
        self._accel = self.plant.accel
        self.tau_wind = (0.0, 0.0, 0.0)
        self.tau_waves = (0.0, 0.0, 0.0)
        self.nu_c = (0.0, 0.0)
        self.saturated = np.zeros(3, dtype=bool)
        self._prepare = self._make_prepare()
        self.reset()

    # ---- set-up ----------------------------------------------------------------------------
    def _bind_model(self) -> None:
        m = self.model
        try:
            jids = [m.joint(n).id for n in ("x", "y", "psi")]
            self._act_ids = [m.actuator(n).id for n in ACTUATOR_NAMES]
            self.hull_body = m.body("hull").id
        except KeyError as exc:
            raise ValueError(
                "MJCF must define joints x, y, psi, a body 'hull' and actuators "
                f"{ACTUATOR_NAMES}: {exc}"
            ) from exc
        if jids != [0, 1, 2] or m.nv != 3 or m.nu != 3 or m.na != 3:
            raise ValueError("MJCF must have exactly the planar joints x, y, psi and 3 actuators")
        if self._act_ids != [0, 1, 2]:
            raise ValueError(f"actuators must be declared in the order {ACTUATOR_NAMES}")
        if np.any(np.abs(m.body_ipos[self.hull_body]) > 1e-12):
            raise ValueError(
                "the hull's centre of mass must sit at the body origin (inertial pos 0)"
            )
        p = self.thrusters
        lo, hi, tc = p.lower, p.upper, p.time_constants
        m.actuator_ctrlrange[:] = np.c_[lo, hi]
        m.actuator_actrange[:] = np.c_[lo, hi]
        m.actuator_forcerange[:] = np.c_[p.force_lower, p.force_upper]
        m.actuator_dynprm[:, 0] = tc
        m.actuator_gainprm[1, 0] = p.k2
        m.actuator_gainprm[2, 0] = p.k3
        for i, x in ((1, p.L2), (2, -p.L3)):
            m.site_pos[m.actuator_trnid[i, 0], 0] = x
        d = mujoco.MjData(m)
        mujoco.mj_forward(m, d)
        Mq = np.zeros((3, 3))
        mujoco.mj_fullM(m, d, Mq)
        if np.any(np.abs(Mq - np.diag(np.diag(Mq))) > 1e-9 * Mq.max()) or Mq[0, 0] != Mq[1, 1]:
            raise ValueError(f"unexpected joint-space inertia (need diag(m, m, Izz)): {Mq}")
        self._m_q, self._i_q = float(Mq[0, 0]), float(Mq[2, 2])

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
        self._wind_load = WindLoad(blendermann(self.wind_config.coefficients), self.windage)
        self._prepare = self._make_prepare()

    # ---- state -----------------------------------------------------------------------------
    def reset(
        self,
        eta: ArrayLike = (0.0, 0.0, 0.0),
        nu: ArrayLike = (0.0, 0.0, 0.0),
        actuators: ArrayLike = (0.0, 0.0, 0.0),
        rng: np.random.Generator | None = None,
    ) -> None:
        """Reset to pose ``eta`` (m, m, rad), body velocity ``nu`` and actuator states.

        ``rng`` seeds the stochastic disturbances (wind gusts); ``None`` uses a fixed seed 0.
        """
        eta_a = validate_command(eta)  # same checks: shape (3,), finite
        nu_a = validate_command(nu)
        act = validate_command(actuators)
        d = self.data
        mujoco.mj_resetData(self.model, d)
        d.qpos[:] = eta_a
        c, s = math.cos(eta_a[2]), math.sin(eta_a[2])
        d.qvel[:] = (c * nu_a[0] - s * nu_a[1], s * nu_a[0] + c * nu_a[1], nu_a[2])
        d.act[:] = np.clip(act, self.thrusters.lower, self.thrusters.upper)
        d.ctrl[:] = d.act
        self.saturated[:] = False
        rng = rng if rng is not None else np.random.default_rng(0)
        # fixed order, one draw each: the same seed gives the same disturbances
        self.wind.reset(rng)
        self.current.reset(rng)
        if self.waves is not None:
            self.waves.reset(rng)
        # leapfrog start: qacc = a_0 = f(q_0, v_0), qvel = v_{-1/2} = v_0 - h/2 a_0
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
    def time(self) -> float:
        """Simulation time (s)."""
        return float(self.data.time)

    @property
    def timestep(self) -> float:
        """Physics step (s)."""
        return float(self.model.opt.timestep)

    @property
    def eta(self) -> NDArray[np.float64]:
        """Pose ``[x (m north), y (m east), psi (rad)]``; psi is continuous (not wrapped)."""
        return self.data.qpos.copy()

    @property
    def nu(self) -> NDArray[np.float64]:
        """Body velocity ``[u (m/s), v (m/s), r (rad/s)]``."""
        xd, yd, r = self.data.qvel + 0.5 * self.model.opt.timestep * self.data.qacc
        c, s = math.cos(self.data.qpos[2]), math.sin(self.data.qpos[2])
        return np.array([c * xd + s * yd, -s * xd + c * yd, r])

    @property
    def actuator_state(self) -> NDArray[np.float64]:
        """Lagged actuator states ``[n1 (rpm), p2, p3]``."""
        return self.data.act.copy()

    @property
    def command(self) -> NDArray[np.float64]:
        """Current (saturated) commands ``[n1 (rpm), p2, p3]``."""
        return self.data.ctrl.copy()

    @property
    def thrust(self) -> NDArray[np.float64]:
        """Thrusts ``[F1, F2, F3]`` (N) at the current actuator states."""
        a = self.data.act
        p = self.thrusters
        return np.array([p.k1 * abs(a[0]) * a[0], p.k2 * a[1], p.k3 * a[2]])

    @property
    def tau_thrusters(self) -> NDArray[np.float64]:
        """Body-frame thrust ``tau = T F`` (N, N, N m) at the current actuator states."""
        p = self.thrusters
        n1, p2, p3 = self.data.act.tolist()
        f2, f3 = p.k2 * p2, p.k3 * p3
        return np.array([p.k1 * abs(n1) * n1, f2 + f3, p.L2 * f2 - p.L3 * f3])

    # ---- stepping --------------------------------------------------------------------------
    def set_command(self, command: ArrayLike) -> NDArray[np.bool_]:
        """Set thruster commands ``[n1 (rpm), p2, p3]``, clipped to the physical ranges.

        Returns:
            Flags of the commands that were clipped (also kept in :attr:`saturated`).

        Raises:
            ValueError: wrong shape, NaN or infinite values.
        """
        cmd = validate_command(command).tolist()
        lo, hi = self._lower, self._upper
        clipped = [min(max(c, a), b) for c, a, b in zip(cmd, lo, hi, strict=True)]
        self.saturated = np.array([c != x for c, x in zip(clipped, cmd, strict=True)])
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
        prepare, mj_step, m, d = self._prepare, mujoco.mj_step, self.model, self.data
        for i in range(n):
            prepare()
            mj_step(m, d)
            if stop_on_contact and d.ncon:
                return i + 1
        return n

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
        gain = m.actuator_gainprm
        p = self.thrusters
        k1, k2, k3, L2, L3 = p.k1, p.k2, p.k3, p.L2, p.L3
        mq, iq = self._m_q, self._i_q
        accel, wind_at, wind_load = self._accel, self.wind.at, self._wind_load
        cc = self.current_config
        current_at = None if (cc.is_constant and cc.speed == 0.0) else self.current.at
        drift = None if self.waves is None or not self.wave_config.drift else self.waves.drift_load
        aero = self.aerodynamics
        cos, sin, isfinite = math.cos, math.sin, math.isfinite
        this = self

        def prepare() -> None:
            hh = 0.5 * m.opt.timestep
            psi = qpos.tolist()[2]
            t = d.time
            # velocity at the whole step from the half-step qvel (leapfrog, see module doc)
            w0, w1, w2 = qvel.tolist()
            a0, a1, a2 = qacc.tolist()
            xd, yd, r = w0 + hh * a0, w1 + hh * a1, w2 + hh * a2
            n1, p2, p3 = act.tolist()
            c, s = cos(psi), sin(psi)
            u = c * xd + s * yd
            v = c * yd - s * xd
            # thrusters (Tomera 2014 eqs. 8-12), body frame
            f1 = k1 * abs(n1) * n1
            f2 = k2 * p2
            f3 = k3 * p3
            tx, ty, tn = f1, f2 + f3, L2 * f2 - L3 * f3
            # wind (relative to the ground velocity) and current (NED, constant)
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
                wx += dx_
                wy += dy_
                wn += dn_
            else:
                dx_ = dy_ = dn_ = 0.0
            ud, vd, rd = accel(u, v, r, tx + wx, ty + wy, tn + wn, uc, vcb)
            if not (
                isfinite(ud + vd + rd) and abs(u) + abs(v) < _MAX_SPEED and abs(r) < _MAX_YAW_RATE
            ):
                raise SimulationDiverged(
                    f"simulation diverged at t = {d.time:.3f} s: nu = ({u:.4g}, {v:.4g}, {r:.4g}), "
                    f"nu_dot = ({ud:.4g}, {vd:.4g}, {rd:.4g}); check the plant parameters, "
                    "the timestep and the applied forces"
                )
            # joint acceleration qacc* = R(psi)(nu_dot + r S nu), S nu = [-v, u, 0]
            bx = ud - r * v
            by = vd + r * u
            # qfrc_applied = M_q qacc* - qfrc_actuator  (qfrc_bias = qfrc_passive = 0 here)
            qfrc[0] = mq * (c * bx - s * by) - (c * tx - s * ty)
            qfrc[1] = mq * (s * bx + c * by) - (s * tx + c * ty)
            qfrc[2] = iq * rd - tn
            gain[0, 0] = k1 * abs(n1)
            this.tau_wind = (wx - dx_, wy - dy_, wn - dn_)
            this.tau_waves = (dx_, dy_, dn_)
            this.nu_c = (uc, vcb)

        return prepare
