"""Independent reference integration of the 3-DOF model with SciPy (the physics' oracle).

Integrates ``eta_dot = R(psi) nu``, the matrix form ``M nu_dot = tau - C nu - D nu``
(:meth:`PlantModel.nu_dot`, a linear solve, not the expanded kernel the physics uses) and the
first-order thruster lags ``act_dot = (cmd - act) / T`` with ``scipy.integrate.solve_ivp``
at tight tolerances, segment by segment between the instants where the piecewise-constant
commands (or any other input) change.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp

from .frames import rot
from .model import PlantModel
from .thrusters import BLUE_LADY_THRUSTERS, ThrusterParameters, command_to_tau

__all__ = ["ReferenceSolution", "simulate_reference"]

EnvLoad = Callable[[float, NDArray[np.float64], NDArray[np.float64]], ArrayLike]


@dataclass(frozen=True)
class ReferenceSolution:
    """Sampled reference trajectory: ``t`` (s), ``eta`` (m, m, rad), ``nu``, actuator states."""

    t: NDArray[np.float64]
    eta: NDArray[np.float64]
    nu: NDArray[np.float64]
    act: NDArray[np.float64]


def simulate_reference(
    plant: PlantModel,
    t_eval: ArrayLike,
    command_times: ArrayLike,
    commands: ArrayLike,
    *,
    thrusters: ThrusterParameters = BLUE_LADY_THRUSTERS,
    eta0: ArrayLike = (0.0, 0.0, 0.0),
    nu0: ArrayLike = (0.0, 0.0, 0.0),
    act0: ArrayLike = (0.0, 0.0, 0.0),
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
        commands: (K, 3) commands ``[n1 (rpm), p2, p3]`` (clipped to the thruster ranges).
        thrusters: thruster parameters (constants, ranges, lags).
        eta0, nu0, act0: initial pose, body velocity and actuator states.
        env_load: ``f(t, eta, nu) -> [X, Y, N]`` body-frame environmental load (N, N, N m),
            e.g. the wind; it should be smooth between ``breakpoints``.
        current: constant NED current ``(speed m/s, direction to, rad)``.
        breakpoints: extra instants (s) where ``env_load`` is not smooth.
        rtol, atol, method: passed to ``solve_ivp``.
    """
    t_eval = np.asarray(t_eval, dtype=float)
    ct = np.asarray(command_times, dtype=float)
    cmds = np.clip(np.asarray(commands, dtype=float), thrusters.lower, thrusters.upper)
    if cmds.shape != (ct.size, 3):
        raise ValueError(f"commands must have shape ({ct.size}, 3), got {cmds.shape}")
    tc = thrusters.time_constants
    vc, bc = current

    def rhs(t: float, x: NDArray[np.float64], cmd: NDArray[np.float64]) -> NDArray[np.float64]:
        eta, nu, act = x[0:3], x[3:6], x[6:9]
        tau = command_to_tau(act, thrusters)
        if env_load is not None:
            tau = tau + np.asarray(env_load(t, eta, nu), dtype=float)
        nu_c = np.array([vc * np.cos(bc - eta[2]), vc * np.sin(bc - eta[2]), 0.0])
        return np.concatenate([rot(eta[2]) @ nu, plant.nu_dot(nu, tau, nu_c), (cmd - act) / tc])

    t_end = float(t_eval[-1])
    cuts = np.unique(np.concatenate([[0.0, t_end], ct, np.asarray(breakpoints, dtype=float)]))
    cuts = cuts[(cuts >= 0.0) & (cuts <= t_end)]
    x = np.concatenate([np.asarray(eta0, float), np.asarray(nu0, float), np.asarray(act0, float)])
    out = np.empty((t_eval.size, 9))
    if t_eval[0] == 0.0:
        out[0] = x
    for t0, t1 in zip(cuts[:-1], cuts[1:], strict=True):
        k = int(np.searchsorted(ct, t0, side="right")) - 1
        cmd = cmds[max(k, 0)]
        mask = (t_eval > t0) & (t_eval <= t1)
        sol = solve_ivp(
            rhs, (t0, t1), x, method=method, rtol=rtol, atol=atol,
            t_eval=t_eval[mask] if mask.any() else None, args=(cmd,),
        )  # fmt: skip
        if not sol.success:
            raise RuntimeError(f"reference integration failed on [{t0}, {t1}]: {sol.message}")
        if mask.any():
            out[mask] = sol.y.T[-mask.sum() :]
        x = sol.y[:, -1] if not mask.any() or sol.t[-1] == t1 else x
        if mask.any() and sol.t[-1] != t1:  # pragma: no cover - solve_ivp always ends at t1
            raise RuntimeError("reference integration did not reach the segment end")
    return ReferenceSolution(t_eval, out[:, 0:3], out[:, 3:6], out[:, 6:9])
