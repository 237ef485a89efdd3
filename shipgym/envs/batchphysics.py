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
3. MuJoCo's Euler update: a lagged state ``a += (c - a)(1 - exp(-h/T))`` (``filterexact``;
   a rate-limited one's ``c`` replaced as in the single physics), a
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
from shipgym.dynamics.actuators import ActuatorSet, Azimuth, Propeller
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
            (:class:`~shipgym.dynamics.model.PlantModel`, or any model with a batched
            ``nu_dot(nu, tau, nu_c)``: :class:`~shipgym.dynamics.mmg.MMGHull`).
        wind: any form of ``VesselPhysics(wind=)`` or ``None`` (no aerodynamic load).
        current: any form of ``VesselPhysics(current=)`` or ``None``.
        timestep: physics step (s), at most half the shortest actuator lag.

    The state is held component-major (``(3, n)``, ``(n_channels, n)``) so that every row is a
    contiguous array; the properties return the usual ``(n, 3)`` layout.
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
        # the actuators this plant drives (a plant of the paper's model: the bollard laws)
        self.actuators = acts = v.actuators_for(self.plant)
        self.h = check_timestep(timestep)
        chans = acts.channels
        lags = [c.time_constant for c in chans if c.dynamics == "lag"]
        if lags and self.h > 0.5 * min(lags) + 1e-12:
            raise ValueError(
                f"timestep {self.h:g} s is more than half the shortest actuator lag of "
                f"{v.name!r} ({min(lags):g} s): use timestep <= {0.5 * min(lags):g}"
            )
        col = (slice(None), None)  # per-channel constants as columns, (n_channels, 1)
        self.lower = acts.lower.copy()
        self.upper = acts.upper.copy()
        self._lo, self._hi = self.lower[col], self.upper[col]
        dyn = np.array([c.dynamics for c in chans])
        lag, servo, integ = dyn == "lag", dyn == "servo", dyn == "integrator"
        self._servo, self._integ = servo, integ
        self._any_servo, self._any_integ = bool(servo.any()), bool(integ.any())
        self._bounded = (lag | servo)[col]
        self._all_bounded = bool(self._bounded.all())
        tc = np.array([c.time_constant if c.dynamics == "lag" else 1.0 for c in chans])
        self._alpha = np.where(lag, 1.0 - np.exp(-self.h / tc), 0.0)[col]
        self._rate = np.array([c.rate if c.dynamics == "servo" else 0.0 for c in chans])[col]
        self._servo_T = np.array(
            [(c.time_constant or self.h) if c.dynamics == "servo" else 1.0 for c in chans]
        )[col]
        # rate-limited lags (as the single physics): past |c - a| = rate T the filter is fed
        # a +- rate h / (1 - exp(-h/T)), which moves the state by exactly rate h per step
        rl = np.array([c.dynamics == "lag" and np.isfinite(c.rate) for c in chans])
        self._any_rl = bool(rl.any())
        rl_rate = np.where(rl, [c.rate if rl[i] else 0.0 for i, c in enumerate(chans)], 0.0)
        self._rl = rl[col]
        self._rl_band = np.where(rl, rl_rate * tc, np.inf)[col]
        self._rl_step = np.where(rl, rl_rate * self.h / -np.expm1(-self.h / tc), 0.0)[col]
        self._tau = _actuator_kernel(acts)
        self._accel = _plant_kernel(self.plant)
        wind_cfg = WindConfig.coerce(wind, name="wind")
        cc = CurrentConfig.coerce(current, name="current") or CurrentConfig()
        self._coeffs = (wind_cfg.coefficients if wind_cfg else None) or v.windage.coefficients
        self._wind_load = WindLoad(blendermann(self._coeffs), v.windage).array_kernel()
        self._native = self._make_native()
        self.wind_configs: list[WindConfig | None] = [wind_cfg] * n
        self.current_configs: list[CurrentConfig] = [cc] * n
        self.winds = [Wind(wind_cfg or WindConfig(), v.windage) for _ in range(n)]
        self.currents = [Current(cc) for _ in range(n)]
        self._aero = np.full(n, wind_cfg is not None)
        self._update_flags()
        self.t = np.zeros(n)
        self._q = np.zeros((3, n))
        self._v = np.zeros((3, n))
        self._a = np.zeros((3, n))
        self._act = np.zeros((len(chans), n))
        self._cmd = np.zeros((len(chans), n))
        self.saturated = np.zeros((n, len(chans)), dtype=bool)
        self._wind_at: GridBatch | None = None
        self._current_at: GridBatch | None = None
        self.reset()

    def _update_flags(self) -> None:
        self.aerodynamics = bool(self._aero.any())
        self._aero_gate = None if self._aero.all() else self._aero.astype(float)
        self._has_current = not all(c.is_constant and c.speed == 0.0 for c in self.current_configs)

    def set_disturbances(self, i: int, wind: Any = None, current: Any = None) -> None:
        """Give hull ``i`` its own wind and current (any form of ``VesselPhysics(wind=,
        current=)``; ``None``: none), effective at its next :meth:`reset`, as
        ``VesselPhysics.set_wind`` / ``set_current``. Every hull's wind uses the same
        Blendermann coefficients (the vessel's, or those the constructor's wind names)."""
        wind_cfg = WindConfig.coerce(wind, name="wind")
        cc = CurrentConfig.coerce(current, name="current") or CurrentConfig()
        if wind_cfg is not None and (wind_cfg.coefficients or self._coeffs) != self._coeffs:
            raise ValueError(
                f"hull {i}: wind coefficients {wind_cfg.coefficients!r} differ from the batch's "
                f"{self._coeffs!r}; one batch uses one set of Blendermann coefficients"
            )
        self.wind_configs[i] = wind_cfg
        self.current_configs[i] = cc
        self.winds[i] = Wind(wind_cfg or WindConfig(), self.vessel.windage)
        self.currents[i] = Current(cc)
        if self._wind_at is not None and self._current_at is not None:
            self._wind_at.processes[i] = self.winds[i]
            self._current_at.processes[i] = self.currents[i]
        self._aero[i] = wind_cfg is not None
        self._update_flags()

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
        bounded = self._bounded[:, 0]
        act = np.where(bounded, np.clip(act, self.lower, self.upper), act)
        m = np.ones(self.n, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        if m.shape != (self.n,):
            raise ValueError(f"mask must be ({self.n},) booleans, got shape {m.shape}")
        if rngs is not None and len(rngs) != self.n:
            raise ValueError(f"rngs must hold one generator per hull ({self.n}), got {len(rngs)}")
        c, s = np.cos(e[:, 2]), np.sin(e[:, 2])
        qvel = np.stack([c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1], w[:, 2]])
        self._q[:, m] = e.T[:, m]
        self._v[:, m] = qvel[:, m]
        self._act[:, m] = act.T[:, m]
        self._cmd[:, m] = np.where(bounded, act, 0.0).T[:, m]
        self.saturated[m] = False
        self.t[m] = 0.0
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
        self._a[:, m] = 0.0
        Vw, bw, vc, bc = self._disturbances(self.t[None])
        a0 = self._qacc(self._q, self._v, self._a, self._act, Vw[0], bw[0], vc[0], bc[0])
        self._a[:, m] = a0[:, m]
        self._v[:, m] -= 0.5 * self.h * a0[:, m]

    @property
    def eta(self) -> Array:
        """Poses ``[x, y, psi]`` (n, 3) (m, m, rad; psi continuous)."""
        return self._q.T.copy()

    @property
    def nu(self) -> Array:
        """Body velocities ``[u, v, r]`` (n, 3) at the whole step."""
        w = self._v + 0.5 * self.h * self._a
        c, s = np.cos(self._q[2]), np.sin(self._q[2])
        return np.stack([c * w[0] + s * w[1], c * w[1] - s * w[0], w[2]], -1)

    @property
    def actuator_state(self) -> Array:
        """Actuator states (n, n_channels)."""
        return self._act.T.copy()

    @property
    def command(self) -> Array:
        """The held (clipped) commands (n, n_channels)."""
        return self._cmd.T.copy()

    # ---- stepping --------------------------------------------------------------------------
    def set_command(self, command: ArrayLike) -> NDArray[np.bool_]:
        """Commands ``(n, n_channels)`` (or one row for all), clipped to the channels' ranges;
        returns the clip flags (also :attr:`saturated`)."""
        c = self._rows(command, self.actuators.n_channels, "command", self._cmd.T)
        clipped = np.clip(c, self.lower, self.upper)
        self.saturated = clipped != c
        self._cmd = np.ascontiguousarray(clipped.T)
        return self.saturated.copy()

    def _disturbances(self, ts: Array) -> tuple[Array, Array, Array, Array]:
        """Wind ``(V_w, beta_w)`` and current ``(V_c, beta_c)`` at the times ``ts`` (k, n)."""
        z = np.zeros_like(ts)
        if self.aerodynamics:
            assert self._wind_at is not None
            Vw, bw = self._wind_at.at(ts)
            Vw = np.maximum(Vw, 0.0)
        else:
            Vw = bw = z
        if self._has_current:
            assert self._current_at is not None
            vc, bc = self._current_at.at(ts)
        else:
            vc = bc = z
        return Vw, bw, vc, bc

    def _qacc(
        self, q: Array, qv: Array, qa: Array, act: Array, Vw: Any, bw: Any, vc: Any, bc: Any
    ) -> Array:
        """``qacc*`` (3, n) of a state (steps 1-2 of the module docstring)."""
        w0, w1, r = qv + (0.5 * self.h) * qa
        psi = q[2]
        c, s = np.cos(psi), np.sin(psi)
        u = c * w0 + s * w1
        v = c * w1 - s * w0
        if self._has_current:
            d = bc - psi
            uc, vcb = vc * np.cos(d), vc * np.sin(d)
            ur, vr = u - uc, v - vcb
        else:
            uc = vcb = None
            ur, vr = u, v
        tau = np.empty((3, self.n))
        tau[0], tau[1], tau[2] = self._tau(act, ur, vr, r)
        if self.aerodynamics:
            wx, wy, wn = self._wind_load(psi, u, v, Vw, bw)
            if self._aero_gate is not None:  # hulls without aerodynamic loads
                g = self._aero_gate
                wx, wy, wn = wx * g, wy * g, wn * g
            tau[0] += wx
            tau[1] += wy
            tau[2] += wn
        ud, vd, rd = self._accel(u, v, r, tau, uc, vcb)
        bx = ud - r * v
        by = vd + r * u
        out = np.empty((3, self.n))
        out[0] = c * bx - s * by
        out[1] = s * bx + c * by
        out[2] = rd
        return out

    def step(self, k: int = 1) -> None:
        """Advance every hull ``k`` physics steps.

        Raises:
            SimulationDiverged: a non-finite or absurd state (naming the hulls).
        """
        h = self.h
        # each hull's times of the k steps, by the same additions as the clock (t += h)
        ts = np.empty((k, self.n))
        ts[0] = self.t
        for j in range(1, k):
            ts[j] = ts[j - 1] + h
        if self._native is not None:
            self._native(k, ts[-1])
            self._check()
            return
        Vw, bw, vc, bc = self._disturbances(ts)
        alpha, cmd, lo, hi = self._alpha, self._cmd, self._lo, self._hi
        q, qv, act = self._q, self._v, self._act
        for j in range(k):
            qa = self._qacc(q, qv, self._a, act, Vw[j], bw[j], vc[j], bc[j])
            if self._any_rl:  # the command of the rate-limited lags this step
                gap = cmd - act
                eff = np.where(gap > self._rl_band, np.minimum(act + self._rl_step, cmd), cmd)
                eff = np.where(-gap > self._rl_band, np.maximum(act - self._rl_step, cmd), eff)
                new = act + alpha * (eff - act)
            else:
                new = act + alpha * (cmd - act)  # lags (filterexact)
            if self._any_servo:
                wr = np.clip((cmd - act) / self._servo_T, -self._rate, self._rate)
                new = np.where(self._servo[:, None], act + h * wr, new)
            if self._any_integ:
                new = np.where(self._integ[:, None], act + h * cmd, new)
            held = np.minimum(np.maximum(new, lo), hi)  # np.clip's values, without its wrapper
            act = held if self._all_bounded else np.where(self._bounded, held, new)
            self._a = qa
            qv = qv + h * qa
            q = q + h * qv
        self._q, self._v, self._act = q, qv, act
        self.t = ts[-1] + h
        self._check()

    def _check(self) -> None:
        """Raise :class:`SimulationDiverged` for a non-finite or absurd state."""
        qv = self._v
        if not np.all(np.isfinite(self._a)):
            bad = np.nonzero(~np.all(np.isfinite(self._a), axis=0))[0]
            raise SimulationDiverged(
                f"simulation diverged in hulls {bad.tolist()} (t = {self.t[bad].tolist()} s): "
                "check the plant parameters, the timestep and the applied forces"
            )
        if not np.all(np.abs(qv) < 1e3):
            raise SimulationDiverged("simulation diverged: a hull passed 1 km/s")

    def _make_native(self) -> Any:
        """The compiled step (:func:`shipgym.envs._native.run_batched3`) as ``run(k,
        t_last)``, or ``None`` where it does not cover this batch (a plant other
        than a :class:`PlantModel`, rudders or MMG units, no Numba): then :meth:`step` runs
        the NumPy form."""
        import shipgym.envs._native as nat

        acts = self.actuators
        props = acts.propeller_flow_table()
        if (
            not nat.available()
            or not isinstance(self.plant, PlantModel)
            or not all(isinstance(a, Propeller | Azimuth) for a in acts)
            or (acts.flow_dependent and props is None)
        ):
            return None
        varying, lateral, static, azim, t_props = nat.actuator_tables(acts)
        fp = nat.parameters(self.plant, WindLoad(blendermann(self._coeffs), self.vessel.windage))
        fp[nat._FP : nat._FP + 2] = (0.5 * self.h, self.h)
        col = (slice(None), 0)
        chan = {
            "lo": self.lower.astype(np.float64), "hi": self.upper.astype(np.float64),
            "alpha": self._alpha[col].copy(), "rl_band": self._rl_band[col].copy(),
            "rl_step": self._rl_step[col].copy(), "servo": self._servo.copy(),
            "rate": self._rate[col].copy(), "servo_t": self._servo_T[col].copy(),
            "integ": self._integ.copy(), "bounded": self._bounded[col].copy(),
        }  # fmt: skip
        run_batched3 = nat.run_batched3
        none = (np.zeros(self.n), np.zeros((self.n, 2)), np.zeros((self.n, 2)))  # no process

        def run(k: int, t_last: Array) -> None:
            """``k`` steps; ``t_last`` each hull's time at the last of them."""
            fp[nat._FP + 9] = 1.0 if self._has_current else 0.0
            aero = self._aero.astype(np.float64)
            for name in ("_q", "_v", "_a", "_act", "_cmd", "t"):  # in place, contiguous
                a = getattr(self, name)
                if not a.flags.c_contiguous or not a.flags.writeable:
                    setattr(self, name, np.ascontiguousarray(a).copy())
            assert self._wind_at is not None and self._current_at is not None
            wind = self._wind_at.rows_until(t_last) if self.aerodynamics else none
            cur = self._current_at.rows_until(t_last) if self._has_current else none
            run_batched3(
                k, fp, self._q, self._v, self._a, self._act, self._cmd, chan["lo"], chan["hi"],
                chan["alpha"], chan["rl_band"], chan["rl_step"], chan["servo"], chan["rate"],
                chan["servo_t"], chan["integ"], chan["bounded"], varying, lateral, static, azim,
                t_props, aero, self.t, *wind, *cur,
            )  # fmt: skip

        return run


def _actuator_kernel(acts: ActuatorSet) -> Any:
    """``f(states (n_channels, n), u_r, v_r, r) -> (X, Y, N)``: the actuators' body force.

    Fixed-direction propellers and tunnels through their configuration matrix, azimuths
    through their angles, any other kind (rudders, MMG units) through
    :meth:`ActuatorSet.tau <shipgym.dynamics.actuators.ActuatorSet.tau>`.
    """
    if all(type(a) is Propeller for a in acts):
        props: list[Propeller] = list(acts)  # type: ignore[arg-type]
        ahead = np.array([a.k_ahead for a in props])[:, None]
        astern = np.array([a.k_astern for a in props])[:, None]
        quad = np.array([a.law == "quadratic" for a in props])[:, None]
        # the advance-speed loss k_u (1 - w) and the tunnel factor's d and 1/U_50
        kua = np.array([a.advance * (1.0 - a.wake) for a in props])[:, None]
        dep = np.array([a.loss_depth for a in props])[:, None]
        iu50 = np.array([1.0 / a.loss_speed for a in props])[:, None]
        advance, loss = bool(kua.any()), bool(dep.any())
        B = acts.configuration_matrix()

        def propellers(st: Array, ur: Array, vr: Array, r: Array) -> tuple[Array, Array, Array]:
            k = np.where(st >= 0.0, ahead, astern)
            F = np.where(quad, k * np.abs(st), k) * st
            if advance:
                F = F - kua * np.abs(st) * ur
            if loss:
                x = ur * iu50
                x = x * x
                F = F * (1.0 - dep * x * np.exp(1.0 - x))
            X, Y, N = B @ F
            return X, Y, N

        return propellers
    if all(type(a) is Azimuth for a in acts):
        sl = acts.slices
        thr = np.array([s.start for s in sl])
        ang = thr + 1
        Fmax = np.array([a.max_thrust_n for a in acts])[:, None]
        px = np.array([a.position[0] for a in acts])[:, None]
        py = np.array([a.position[1] for a in acts])[:, None]

        def azimuths(st: Array, ur: Array, vr: Array, r: Array) -> tuple[Array, Array, Array]:
            f = Fmax * st[thr]
            al = st[ang]
            fx, fy = f * np.cos(al), f * np.sin(al)
            return fx.sum(0), fy.sum(0), (px * fy - py * fx).sum(0)

        return azimuths
    flow = acts.flow_dependent

    def generic(st: Array, ur: Array, vr: Array, r: Array) -> tuple[Array, Array, Array]:
        nu = np.stack([ur, vr, r], -1) if flow else None
        X, Y, N = acts.tau(st.T, nu).T
        return X, Y, N

    return generic


def _plant_kernel(plant: Any) -> Any:
    """``f(u, v, r, tau (3, n), u_c, v_c) -> nu_dot (3, n)`` on (n,) arrays (``u_c = v_c =
    None``: no current). A :class:`PlantModel` in matrix form over the batch (the terms of its
    expanded kernel, :meth:`PlantModel.accel`, in a few array operations); other hulls through
    their batched ``nu_dot``."""
    if isinstance(plant, PlantModel):
        return _matrix_accel(plant)

    def nu_dot(u: Array, v: Array, r: Array, tau: Array, uc: Any, vc: Any) -> Array:
        z = np.zeros_like(u)
        nu_c = np.stack([z if uc is None else uc + z, z if vc is None else vc + z, z], -1)
        return np.asarray(plant.nu_dot(np.stack([u, v, r], -1), tau.T, nu_c)).T

    return nu_dot


def _matrix_accel(p: PlantModel) -> Any:
    """``M^-1 (tau - D_L nu_r - d |nu_r| nu_r - C_RB(nu) nu - C_A(nu_r) nu_r + M_A nu_c_dot)``
    (Fossen 2011 eq. 10.1 with the current as in the single physics) for (3, n) arrays."""
    A = np.asarray(p.M_A)
    a11, a22, a32 = A[0, 0], A[1, 1], A[2, 1]
    a23s = 0.5 * (A[1, 2] + A[2, 1])
    D = np.asarray(p.D_L)
    q = np.asarray(p.d_quad)[:, None]
    quad = bool(np.any(q))
    Mi = np.linalg.inv(p.mass_matrix())
    cor = p.coriolis
    m, xg = p.m, p.x_g
    mxg = m * xg

    def accel(u: Array, v: Array, r: Array, tau: Array, uc: Any, vc: Any) -> Array:
        ur = u if uc is None else u - uc
        vr = v if vc is None else v - vc
        nr = np.stack((ur, vr, r))
        f = tau - D @ nr
        if quad:
            f -= q * np.abs(nr) * nr
        if cor:  # C_RB(nu) nu + C_A(nu_r) nu_r
            w = a22 * vr + a23s * r
            a11u = a11 * ur
            f[0] += (m * (xg * r + v) + w) * r
            f[1] -= (m * u + a11u) * r
            f[2] -= mxg * r * u + w * ur - a11u * vr
        if uc is not None:  # + M_A nu_c_dot, nu_c_dot = [r v_c, -r u_c, 0]
            f[0] += a11 * (r * vc)
            ay = r * uc
            f[1] -= a22 * ay
            f[2] -= a32 * ay
        return Mi @ f

    return accel
