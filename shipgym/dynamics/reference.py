"""Independent reference integration of the hull models with SciPy (the physics' oracle).

Integrates ``eta_dot = R(psi) nu`` (3 DOF) or Fossen's 4-DOF kinematics (``x_dot = u cos psi
- v cos phi sin psi``, ``y_dot = u sin psi + v cos phi cos psi``, ``phi_dot = p``, ``psi_dot
= r cos phi``), the matrix form ``M nu_dot = tau - C nu - D nu (- g)`` (``nu_dot``, a linear
solve, not the expanded kernel the physics uses), the actuator states (first-order lags
``act_dot = clip((cmd - act) / T, +-rate)`` with a lag's rate limit, integrators
``act_dot = cmd`` for azimuth angles) and their
thrust (:meth:`ActuatorSet.tau <shipgym.dynamics.actuators.ActuatorSet.tau>`, the matrix
form) with ``scipy.integrate.solve_ivp`` at tight tolerances, segment by segment between the
instants where the piecewise-constant commands (or any other input) change.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp

from .actuators import ActuatorSet
from .frames import rot
from .hull4 import Hull4, is_hull4
from .model import PlantModel
from .thrusters import ThrusterParameters, command_to_tau

__all__ = ["ReferenceSolution", "simulate_reference"]

EnvLoad = Callable[[float, NDArray[np.float64], NDArray[np.float64]], ArrayLike]


@dataclass(frozen=True)
class ReferenceSolution:
    """Sampled reference trajectory: ``t`` (s), ``eta`` (m, m, rad), ``nu``, actuator states.

    ``eta`` and ``nu`` are ``[x, y, psi]``, ``[u, v, r]`` for 3 DOF and Fossen's
    ``[x, y, phi, psi]``, ``[u, v, p, r]`` for 4 DOF.
    """

    t: NDArray[np.float64]
    eta: NDArray[np.float64]
    nu: NDArray[np.float64]
    act: NDArray[np.float64]


def simulate_reference(
    plant: PlantModel | Hull4,
    t_eval: ArrayLike,
    command_times: ArrayLike,
    commands: ArrayLike,
    *,
    thrusters: ThrusterParameters | None = None,
    actuators: ActuatorSet | None = None,
    eta0: ArrayLike | None = None,
    nu0: ArrayLike | None = None,
    act0: ArrayLike | None = None,
    env_load: EnvLoad | None = None,
    current: tuple[float, float] = (0.0, 0.0),
    breakpoints: ArrayLike = (),
    rtol: float = 1e-10,
    atol: float = 1e-10,
    method: str = "DOP853",
) -> ReferenceSolution:
    """Integrate the plant under zero-order-hold thruster commands.

    Args:
        plant: the model to integrate.
        t_eval: output times (s), increasing, starting at 0.
        command_times: instants (s) at which ``commands[k]`` starts to apply (first one 0).
        commands: (K, n) commands in channel order (clipped to the ranges); for the Blue
            Lady's ``thrusters`` ``[n1 (rpm), p2, p3]``.
        thrusters: :class:`~shipgym.dynamics.thrusters.ThrusterParameters` of a three-thruster
            vessel (e.g. ``BLUE_LADY_THRUSTERS``), used when ``actuators`` is None.
        actuators: any vessel's :class:`~shipgym.dynamics.actuators.ActuatorSet`
            (``load_vessel(name).actuators``). One of ``thrusters`` and ``actuators`` is
            required.
        eta0, nu0, act0: initial pose, body velocity and actuator states (Fossen order for
            a 4-DOF ``plant``).
        env_load: ``f(t, eta, nu) -> [X, Y, N]`` body-frame environmental load (N, N, N m),
            e.g. the wind; it should be smooth between ``breakpoints``.
        current: constant NED current ``(speed m/s, direction to, rad)``.
        breakpoints: extra instants (s) where ``env_load`` is not smooth.
        rtol, atol, method: passed to ``solve_ivp``.

    Raises:
        TypeError: neither ``actuators`` nor ``thrusters`` given.
    """
    t_eval = np.asarray(t_eval, dtype=float)
    ct = np.asarray(command_times, dtype=float)
    four = is_hull4(plant)
    nd = 4 if four else 3
    if actuators is not None:
        lo, hi = actuators.lower, actuators.upper
        lagged = np.array([c.dynamics == "lag" for c in actuators.channels])
        servo = np.array([c.dynamics == "servo" for c in actuators.channels])
        tc = np.array([c.time_constant if c.dynamics != "integrator" else 1.0
                       for c in actuators.channels])  # fmt: skip
        rate = np.array([c.rate if c.dynamics == "servo" else np.inf for c in actuators.channels])
        # a lag's rate limit: act_dot = clip((cmd - act) / T, +-rate)
        lag_rate = np.array([c.rate if c.dynamics == "lag" and np.isfinite(c.rate) else np.inf
                             for c in actuators.channels])  # fmt: skip
        flow = actuators.flow_dependent

        def tau_of(act: NDArray[np.float64], nu: NDArray[np.float64]) -> NDArray[np.float64]:
            return actuators.tau(act, nu if flow else None)

        na = actuators.n_channels
    elif thrusters is not None:
        p3 = thrusters
        lo, hi = p3.lower, p3.upper
        lagged = np.ones(3, dtype=bool)
        servo = np.zeros(3, dtype=bool)
        tc = p3.time_constants
        rate = np.full(3, np.inf)
        lag_rate = np.full(3, np.inf)
        na = 3

        def tau_of(act: NDArray[np.float64], nu: NDArray[np.float64]) -> NDArray[np.float64]:
            return command_to_tau(act, p3)
    else:
        raise TypeError(
            "simulate_reference() needs the vessel's actuators: pass "
            "actuators=load_vessel(name).actuators (or thrusters=BLUE_LADY_THRUSTERS)"
        )

    cmds = np.clip(np.asarray(commands, dtype=float), lo, hi)
    if cmds.shape != (ct.size, na):
        raise ValueError(f"commands must have shape ({ct.size}, {na}), got {cmds.shape}")
    vc, bc = current
    ip = 3 if four else 2  # index of psi in eta

    ideal = servo & (tc == 0.0)  # ideal servos: full rate until the command is reached
    tc_lag = np.where(tc > 0.0, tc, 1.0)  # no division by an ideal servo's 0
    servo_rate = np.where(servo, rate, 0.0)
    linear_kin = four and getattr(plant, "kinematics", "fossen") == "linear"

    def rhs(
        t: float, x: NDArray[np.float64], cmd: NDArray[np.float64], ideal_rate: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        eta, nu, act = x[0:nd], x[nd : 2 * nd], x[2 * nd :]
        psi = eta[ip]
        nu_c = np.array([vc * np.cos(bc - psi), vc * np.sin(bc - psi), 0.0])
        # the flow-dependent actuators (rudders, MMG units) feel the velocity through the water
        nu_w = nu - (np.array([nu_c[0], nu_c[1], 0.0, 0.0]) if four else nu_c)
        tau = np.asarray(tau_of(act, nu_w), dtype=float)
        if env_load is not None:
            planar = np.asarray(env_load(t, eta, nu), dtype=float)  # [X, Y, N]
            tau = tau + (np.array([planar[0], planar[1], 0.0, planar[2]]) if four else planar)
        act_dot = np.where(lagged, np.clip((cmd - act) / tc_lag, -lag_rate, lag_rate), cmd)
        if servo.any():
            w = np.clip((cmd - act) / np.where(ideal, 1.0, tc_lag), -rate, rate)
            act_dot = np.where(servo, np.where(ideal, ideal_rate, w), act_dot)
        if four:
            u, v, p, r = nu
            phi = eta[2]
            cf = 1.0 if linear_kin else np.cos(phi)
            c, s = np.cos(psi), np.sin(psi)
            eta_dot = [u * c - v * cf * s, u * s + v * cf * c, p, r * cf]
            nu_dot = plant.nu_dot(nu, tau, nu_c[:2], phi)
        else:
            eta_dot = rot(psi) @ nu
            nu_dot = plant.nu_dot(nu, tau, nu_c)
        return np.concatenate([eta_dot, nu_dot, act_dot])

    t_end = float(t_eval[-1])
    cuts = np.unique(np.concatenate([[0.0, t_end], ct, np.asarray(breakpoints, dtype=float)]))
    cuts = cuts[(cuts >= 0.0) & (cuts <= t_end)]
    zeros = (0.0,) * nd
    eta0 = zeros if eta0 is None else eta0
    nu0 = zeros if nu0 is None else nu0
    act0 = np.zeros(na) if act0 is None else act0
    x = np.concatenate([np.asarray(eta0, float), np.asarray(nu0, float), np.asarray(act0, float)])
    out = np.empty((t_eval.size, x.size))
    if t_eval[0] == 0.0:
        out[0] = x
    pieces = []
    for t0, t1 in zip(cuts[:-1], cuts[1:], strict=True):
        k = int(np.searchsorted(ct, t0, side="right")) - 1
        pieces.append((t0, t1, cmds[max(k, 0)]))
    while pieces:
        t0, t1, cmd = pieces.pop(0)
        ideal_rate = np.zeros(na)
        if ideal.any():  # an ideal servo reaches its command at t0 + |cmd - act| / rate: a cut
            gap = np.where(ideal, cmd - x[2 * nd :], 0.0)
            reach = t0 + np.abs(gap) / np.where(ideal, servo_rate, 1.0)
            ideal_rate = np.where(reach > t0 + 1e-12, np.sign(gap) * servo_rate, 0.0)
            inner = reach[(ideal_rate != 0.0) & (reach < t1 - 1e-12)]
            if inner.size:
                tm = float(inner.min())
                pieces.insert(0, (tm, t1, cmd))
                t1 = tm
        mask = (t_eval > t0) & (t_eval <= t1)
        te = t_eval[mask]
        if te.size == 0 or te[-1] != t1:  # the segment's end too: the next segment starts there
            te = np.append(te, t1)
        sol = solve_ivp(
            rhs, (t0, t1), x, method=method, rtol=rtol, atol=atol, t_eval=te,
            args=(cmd, ideal_rate),
        )  # fmt: skip
        if not sol.success or sol.t[-1] != t1:
            raise RuntimeError(f"reference integration failed on [{t0}, {t1}]: {sol.message}")
        if mask.any():
            out[mask] = sol.y.T[: mask.sum()]
        x = sol.y[:, -1].copy()
        if ideal.any():  # land exactly on the command reached at this cut
            x[2 * nd :] = np.where(ideal & (np.abs(x[2 * nd :] - cmd) < 1e-9), cmd, x[2 * nd :])
    return ReferenceSolution(t_eval, out[:, 0:nd], out[:, nd : 2 * nd], out[:, 2 * nd :])
