r"""N hulls of one vessel stepped in one NumPy computation: the batched form of
:class:`~shipgym.envs.physics.VesselPhysics` (3 DOF, calm air and water for now).

The same integration scheme as the MuJoCo physics, so that the same commands give the same
trajectories (to round-off): per physics step ``h``

1. the velocity at the whole step ``v_k = qvel + h/2 qacc_prev`` (the leapfrog reading of
   MuJoCo's symplectic Euler step, :mod:`shipgym.envs.physics`), ``nu = R(psi)^T v_k``;
2. the actuators' force from their states at the start of the step
   (:meth:`ActuatorSet.tau <shipgym.dynamics.actuators.ActuatorSet.tau>`, the flow-dependent
   kinds at ``nu``) and the hull's acceleration ``nu_dot`` (the plant's ``accel`` kernel, which
   takes arrays), ``qacc = R(psi)(nu_dot + r S nu)`` (Tomera (2014) eq. 22);
3. MuJoCo's Euler update: a lagged state ``a += (c - a)(1 - exp(-h/T))`` (``filterexact``), a
   servo's angle ``a += h w`` with the rate ``w = clip((c - a)/T_s, +-rate)`` (``T_s`` the
   servo's time constant or ``h``), each clamped to its range; ``qvel += h qacc``; ``qpos += h
   qvel``.

Wind (gusts included: each hull its own realisation, drawn as the single physics draws it
from its generator) acts through the Blendermann (1994) load on the velocity over ground, and
the current through the velocity through the water, as in the single physics. Pose ``eta``
and velocity ``nu`` are arrays of shape ``(N, 3)``; commands ``(N, n_channels)``, clipped to
the channels' ranges (:attr:`saturated` flags); every hull keeps its own time (a reset
restarts it). Waves and the 4-DOF hulls are not batched yet.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.disturbances import Current, CurrentConfig, Wind, WindConfig, WindLoad, blendermann
from shipgym.disturbances._grid import GridBatch
from shipgym.dynamics import PlantModel
from shipgym.dynamics.hull4 import is_hull4
from shipgym.dynamics.vessel import Vessel, load_vessel

from .physics import SimulationDiverged, check_timestep

__all__ = ["BatchedPhysics"]

Array = NDArray[np.float64]

#: the default physics step of the worlds (s), as :class:`~shipgym.envs.physics.VesselPhysics`
DEFAULT_TIMESTEP = 0.05


class BatchedPhysics:
    """``n`` hulls of ``vessel`` (3 DOF) stepped together (module docstring).

    Args:
        vessel: a :class:`~shipgym.dynamics.vessel.Vessel`, a packaged vessel's name or a
            package path.
        n: number of hulls, >= 1.
        plant: a plant variant name of the vessel or a 3-DOF model
            (:class:`~shipgym.dynamics.model.PlantModel`, whose expanded kernel takes arrays,
            or any model with a batched ``nu_dot(nu, tau)``: :class:`~shipgym.dynamics.mmg.
            MMGHull`).
        wind: any form of ``VesselPhysics(wind=)`` or ``None`` (no aerodynamic load).
        current: any form of ``VesselPhysics(current=)`` or ``None``.
        timestep: physics step (s), at most half the shortest actuator lag.
    """

    def __init__(
        self,
        vessel: Vessel | str | Path,
        n: int,
        plant: Any = "default",
        *,
        wind: Any = None,
        current: Any = None,
        timestep: float = DEFAULT_TIMESTEP,
    ) -> None:
        self.vessel = load_vessel(vessel)
        v = self.vessel
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ValueError(f"n must be an int >= 1 (the number of hulls), got {n!r}")
        self.n = n
        self.plant = v.plant(plant) if isinstance(plant, str) else plant
        if v.dofs != 3 or is_hull4(self.plant):
            raise ValueError(
                f"BatchedPhysics steps 3-DOF hulls only for now; {v.name!r} has {v.dofs} DOF"
            )
        if not hasattr(self.plant, "nu_dot"):
            raise TypeError(f"plant must be a 3-DOF hull model (nu_dot), got {plant!r}")
        self.actuators = v.actuators
        self.h = check_timestep(timestep)
        chans = v.actuators.channels
        lags = [c.time_constant for c in chans if c.dynamics == "lag"]
        if lags and self.h > 0.5 * min(lags) + 1e-12:
            raise ValueError(
                f"timestep {self.h:g} s is more than half the shortest actuator lag of "
                f"{v.name!r} ({min(lags):g} s): use timestep <= {0.5 * min(lags):g}"
            )
        self.lower = v.actuators.lower.copy()
        self.upper = v.actuators.upper.copy()
        dyn = np.array([c.dynamics for c in chans])
        self._lag = dyn == "lag"
        self._servo = dyn == "servo"
        self._integ = dyn == "integrator"
        tc = np.array([c.time_constant if c.dynamics == "lag" else 1.0 for c in chans])
        self._alpha = np.where(self._lag, 1.0 - np.exp(-self.h / tc), 0.0)
        self._rate = np.array([c.rate if c.dynamics == "servo" else 0.0 for c in chans])
        self._servo_T = np.array(
            [(c.time_constant or self.h) if c.dynamics == "servo" else 1.0 for c in chans]
        )
        self._flow = v.actuators.flow_dependent
        # the expanded kernel takes arrays for a PlantModel; other hulls (MMG, whose kernel is
        # scalar) go through their batched matrix form
        self._kernel = self.plant.accel if isinstance(self.plant, PlantModel) else None
        wind_cfg = WindConfig.coerce(wind, name="wind")
        self.aerodynamics = wind_cfg is not None
        self.wind_config = wind_cfg if wind_cfg is not None else WindConfig()
        self.winds = [Wind(self.wind_config, v.windage) for _ in range(n)]
        self._wind_load = WindLoad(
            blendermann(self.wind_config.coefficients or v.windage.coefficients), v.windage
        )
        cc = CurrentConfig.coerce(current, name="current") or CurrentConfig()
        self.current_config = cc
        self.currents = [Current(cc) for _ in range(n)]
        self._has_current = not (cc.is_constant and cc.speed == 0.0)
        self.t = np.zeros(n)
        self.qpos = np.zeros((n, 3))
        self.qvel = np.zeros((n, 3))
        self.qacc = np.zeros((n, 3))
        self.act = np.zeros((n, len(chans)))
        self.cmd = np.zeros((n, len(chans)))
        self.saturated = np.zeros((n, len(chans)), dtype=bool)
        self._wind_at: GridBatch | None = None
        self._current_at: GridBatch | None = None
        self.reset()

    # ---- state -----------------------------------------------------------------------------
    def _rows(self, x: ArrayLike | None, width: int, what: str, default: Array) -> Array:
        if x is None:
            return default.copy()
        a = np.asarray(x, dtype=float)
        if a.shape == (width,):
            a = np.broadcast_to(a, (self.n, width))
        if a.shape != (self.n, width) or not np.all(np.isfinite(a)):
            raise ValueError(
                f"{what} must be ({width},) or ({self.n}, {width}) finite numbers, got shape "
                f"{np.shape(x)}"
            )
        return np.array(a, dtype=float)

    def initial_actuator_state(self) -> Array:
        """Actuator states after a reset, (n, n_channels): those of the single physics."""
        from shipgym.dynamics.actuators import Azimuth

        out = np.zeros(self.actuators.n_channels)
        for a, sl in zip(self.actuators, self.actuators.slices, strict=True):
            if isinstance(a, Azimuth):
                out[sl.start + 1] = a.angle0
        return np.broadcast_to(out, (self.n, out.size)).copy()

    def reset(
        self,
        eta: ArrayLike | None = None,
        nu: ArrayLike | None = None,
        actuators: ArrayLike | None = None,
        mask: ArrayLike | None = None,
        rngs: list[np.random.Generator] | None = None,
    ) -> None:
        """Reset the hulls (all, or those where ``mask`` is True) to ``eta``, ``nu`` (each
        ``(3,)`` or ``(n, 3)``) and actuator states; commands are set to hold them.

        ``rngs``: one generator per hull (the reset ones are used) for its wind gusts and
        current, drawn in the single physics' order (wind, then current); ``None``: seed 0 for
        each, as ``VesselPhysics.reset(rng=None)``.
        """
        zeros = np.zeros((self.n, 3))
        e = self._rows(eta, 3, "eta", zeros)
        w = self._rows(nu, 3, "nu", zeros)
        act = self._rows(actuators, self.actuators.n_channels, "actuators",
                         self.initial_actuator_state())  # fmt: skip
        # lagged states and servo angles within their ranges (an integrator's range bounds its
        # command, the rate, not its state)
        act = np.where(self._lag | self._servo, np.clip(act, self.lower, self.upper), act)
        m = np.ones(self.n, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        if m.shape != (self.n,):
            raise ValueError(f"mask must be ({self.n},) booleans, got shape {m.shape}")
        c, s = np.cos(e[:, 2]), np.sin(e[:, 2])
        qvel = np.stack([c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1], w[:, 2]], -1)
        self.qpos[m] = e[m]
        self.qvel[m] = qvel[m]
        self.act[m] = act[m]
        self.cmd[m] = np.where(self._lag | self._servo, act, 0.0)[m]
        self.saturated[m] = False
        self.t[m] = 0.0
        if rngs is not None and len(rngs) != self.n:
            raise ValueError(f"rngs must hold one generator per hull ({self.n}), got {len(rngs)}")
        for i in np.nonzero(m)[0].tolist():
            g = rngs[i] if rngs is not None else np.random.default_rng(0)
            self.winds[i].reset(g)
            self.currents[i].reset(g)
            if self._wind_at is not None and self._current_at is not None:
                self._wind_at.refresh(i)
                self._current_at.refresh(i)
        if self._wind_at is None or self._current_at is None:
            self._wind_at = GridBatch(self.winds)
            self._current_at = GridBatch(self.currents)
        # leapfrog start: qacc = a_0 = f(q_0, v_0), qvel = v_{-1/2} = v_0 - h/2 a_0
        self.qacc[m] = 0.0
        a0 = self._qacc()
        self.qacc[m] = a0[m]
        self.qvel[m] -= 0.5 * self.h * a0[m]

    @property
    def eta(self) -> Array:
        """Poses ``[x, y, psi]`` (n, 3) (m, m, rad; psi continuous)."""
        return self.qpos.copy()

    @property
    def nu(self) -> Array:
        """Body velocities ``[u, v, r]`` (n, 3) at the whole step."""
        w = self.qvel + 0.5 * self.h * self.qacc
        psi = self.qpos[:, 2]
        c, s = np.cos(psi), np.sin(psi)
        return np.stack([c * w[:, 0] + s * w[:, 1], -s * w[:, 0] + c * w[:, 1], w[:, 2]], -1)

    @property
    def actuator_state(self) -> Array:
        """Actuator states (n, n_channels)."""
        return self.act.copy()

    # ---- stepping --------------------------------------------------------------------------
    def set_command(self, command: ArrayLike) -> NDArray[np.bool_]:
        """Commands ``(n, n_channels)`` (or one row for all), clipped to the channels' ranges;
        returns the clip flags (also :attr:`saturated`)."""
        c = self._rows(command, self.actuators.n_channels, "command", self.cmd)
        clipped = np.clip(c, self.lower, self.upper)
        self.saturated = clipped != c
        self.cmd = clipped
        return self.saturated.copy()

    def _qacc(self) -> Array:
        """``qacc*`` of the current state (steps 1-2 of the module docstring)."""
        h = self.h
        w = self.qvel + 0.5 * h * self.qacc
        psi = self.qpos[:, 2]
        c, s = np.cos(psi), np.sin(psi)
        u = c * w[:, 0] + s * w[:, 1]
        v = c * w[:, 1] - s * w[:, 0]
        r = w[:, 2]
        if self._has_current:
            assert self._current_at is not None
            vc, bc = self._current_at.at(self.t)
            uc, vcb = vc * np.cos(bc - psi), vc * np.sin(bc - psi)
        else:
            uc = vcb = np.zeros_like(u)
        nu_w = np.stack([u - uc, v - vcb, r], -1)
        tau = self.actuators.tau(self.act, nu_w if self._flow else None)
        if self.aerodynamics:
            assert self._wind_at is not None
            Vw, bw = self._wind_at.at(self.t)
            tau = tau + self._wind_load.array(psi, u, v, np.maximum(Vw, 0.0), bw)
        if self._kernel is not None:
            ud, vd, rd = self._kernel(u, v, r, tau[:, 0], tau[:, 1], tau[:, 2], uc, vcb)
        else:
            nu_c = np.stack([uc, vcb, np.zeros_like(u)], -1)
            ud, vd, rd = self.plant.nu_dot(np.stack([u, v, r], -1), tau, nu_c).T
        bx = ud - r * v
        by = vd + r * u
        return np.stack([c * bx - s * by, s * bx + c * by, np.broadcast_to(rd, u.shape)], -1)

    def step(self, k: int = 1) -> None:
        """Advance every hull ``k`` physics steps.

        Raises:
            SimulationDiverged: a non-finite or absurd state (naming the hulls).
        """
        h = self.h
        lag, servo, integ = self._lag, self._servo, self._integ
        for _ in range(k):
            qacc = self._qacc()
            if not np.all(np.isfinite(qacc)):
                bad = np.nonzero(~np.all(np.isfinite(qacc), axis=1))[0]
                raise SimulationDiverged(
                    f"simulation diverged in hulls {bad.tolist()} (t = {self.t[bad].tolist()} s): "
                    "check the plant parameters, the timestep and the applied forces"
                )
            act = self.act
            new = act + self._alpha * (self.cmd - act)  # lags (filterexact)
            if servo.any():
                wr = np.clip((self.cmd - act) / self._servo_T, -self._rate, self._rate)
                new = np.where(servo, act + h * wr, new)
            if integ.any():
                new = np.where(integ, act + h * self.cmd, new)
            self.act = np.where(lag | servo, np.clip(new, self.lower, self.upper), new)
            self.qacc = qacc
            self.qvel = self.qvel + h * qacc
            self.qpos = self.qpos + h * self.qvel
            self.t += h
        if not np.all(np.abs(self.qvel) < 1e3):
            raise SimulationDiverged("simulation diverged: a hull passed 1 km/s")
