r"""The classical rudder-roll pilot: the sway-velocity filter and a heading or roll controller.

Public names: ``PILOT_MODES``, ``RollPilot``, ``roll_pilot``.
Sources: Radhakrishnan (n.d.).

Design notes: docs/design/controllers.rollpilot.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.vanderklugt import RollModel
from shipgym.observers.sway import SwayVelocityKF, calm_water_intensities

from .rollcontrol import HeadingAutopilot, RollDampingController, heading_pid_gains, rrs_lqr

__all__ = ["PILOT_MODES", "RollPilot", "roll_pilot"]

#: the pilot's modes
PILOT_MODES = ("autopilot", "rrs")


class RollPilot:
    """Sway filter + heading autopilot or roll-damping LQR: measurements in, rudder out.

    Args:
        model: the design model (the filter's and, unless ``K`` or ``schedule`` is given, the
            LQR's).
        mode: :data:`PILOT_MODES`.
        delta_max: rudder limit (rad).
        dt: sample time (s) of the calls.
        q: the filter's disturbance intensities (:class:`SwayVelocityKF`).
        Q, R: LQR weights (``mode="rrs"``, default the chosen :data:`~shipgym.controllers.
            rollcontrol.RRS_WEIGHTS`).
        K: a fixed (5,) LQR gain instead of designing one on ``model``.
        schedule: ``U -> K`` (gain scheduling); the call then needs ``U``.
        sway_scale: factor on the sway-velocity gain.
        bandwidth: the autopilot's closed-loop bandwidth (rad/s) (``mode="autopilot"``).
        zeta: its damping ratio.
    """

    def __init__(
        self,
        model: RollModel,
        *,
        mode: str = "rrs",
        delta_max: float,
        dt: float = 0.1,
        q: ArrayLike | None = None,
        Q: ArrayLike | None = None,
        R: float | None = None,
        K: ArrayLike | None = None,
        schedule: Callable[[float], ArrayLike] | None = None,
        sway_scale: float = 1.0,
        bandwidth: float = 0.1,
        zeta: float = 1.0,
    ) -> None:
        if mode not in PILOT_MODES:
            raise ValueError(f"mode must be one of {PILOT_MODES}, got {mode!r}")
        if not (math.isfinite(delta_max) and delta_max > 0):
            raise ValueError(f"delta_max must be a rudder limit > 0 rad, got {delta_max!r}")
        self.model = model
        self.mode = mode
        self.dt = float(dt)
        self.filter = SwayVelocityKF(model, dt=self.dt, q=q)
        self.controller: Any
        if mode == "rrs":
            if K is None and schedule is None:
                Qm = None if Q is None else np.diag(np.asarray(Q, dtype=float))
                K = rrs_lqr(model, Qm, R)[0]
            self.controller = RollDampingController(
                K, sway_scale=sway_scale, schedule=schedule, delta_max=delta_max
            )
        else:
            g = heading_pid_gains(model, bandwidth, zeta)
            self.controller = HeadingAutopilot(g.kp, g.ki, g.kd, delta_max)
        self.reset()

    @property
    def gain(self) -> NDArray[np.float64] | None:
        """The LQR gain in use (``mode="rrs"``, at the design speed), else ``None``."""
        if self.mode != "rrs" or self.controller.schedule is not None:
            return None
        return self.controller.gain()

    def reset(self, x0: ArrayLike | None = None) -> None:
        """Restart the filter (at ``x0``, default rest) and the controller."""
        self.filter = SwayVelocityKF(self.model, dt=self.dt, q=self.filter.Q, x0=x0)
        self.controller.reset()
        self._t = 0.0
        self._first = True

    def __call__(
        self, y: ArrayLike, delta: float, U: float | None = None, psi_d: float = 0.0
    ) -> float:
        """The rudder command (rad) after the measurement ``y``.

        Args:
            y: measured ``[r, psi, p, phi]`` (rad/s, rad).
            delta: the rudder angle (rad) held over the step that ends at ``y``.
            U: forward speed (m/s), for a schedule.
            psi_d: desired heading (rad).
        """
        y = np.asarray(y, dtype=float)
        if self._first:  # the first call only measures: no step has passed
            self._first = False
        else:
            self._t += self.dt
            self.filter.step(y, float(delta))
        if self.mode == "rrs":
            return float(self.controller(self._t, self.filter.x, psi_d=psi_d, U=U))
        # the autopilot on the filtered heading and yaw rate (the raw rate gyro would put its
        # noise through the D term straight onto the rudder rate)
        return float(self.controller(self._t, self.filter.x, psi_d=psi_d))

    @property
    def v_hat(self) -> float:
        """The filter's sway-velocity estimate (m/s)."""
        return float(self.filter.x[0])


def roll_pilot(
    vessel: Any,
    speed: float,
    mode: str = "rrs",
    *,
    sway_scale: float = 1.0,
    schedule: bool = False,
    dt: float = 0.1,
    q: ArrayLike | None = None,
) -> RollPilot:
    """The vessel's classical pilot at the forward speed ``speed`` (m/s).

    The filter is designed on the vessel's linear model at ``speed``
    (:func:`~shipgym.dynamics.linearise.roll_model_of`); the roll-damping LQR with the weights
    of the vessel's ``[roll_control]`` table at its ``design_speed`` (a fixed gain), or, with
    ``schedule=True``, at ``speed`` itself (gain scheduling: the LQR redesigned for the speed);
    the autopilot with its ``heading_bandwidth`` and ``heading_zeta``.

    Args:
        vessel: a :class:`~shipgym.dynamics.vessel.Vessel` with a ``[roll_control]`` table.
        speed: forward speed (m/s).
        mode: :data:`PILOT_MODES`.
        sway_scale: factor on the sway-velocity gain (1 full, 0.2 scaled, 0 none).
        schedule: redesign the LQR at ``speed`` instead of the design speed.
        dt: sample time (s).
        q: the filter's disturbance intensities ((N m)^2 s of roll and yaw moment); default
            :func:`~shipgym.observers.sway.calm_water_intensities` (a task's waves: its
            :meth:`~shipgym.envs.rollstab.RudderRollEnv.filter_intensities`).

    Raises:
        ValueError: the vessel has no ``[roll_control]`` table.
    """
    from shipgym.dynamics.linearise import roll_model_of, rudder_of

    rc = vessel.roll_control
    if not rc:
        raise ValueError(
            f"vessel {vessel.name!r} has no [roll_control] table (design_speed, Q, R) in its "
            "vessel.toml: the roll pilot's design needs one"
        )
    rud = rudder_of(vessel)
    if q is None:
        q = calm_water_intensities(vessel.plant())
    model = roll_model_of(vessel, speed, q=(float(q[0]), float(q[1])))
    K = None
    if mode == "rrs":
        design = model if schedule else roll_model_of(vessel, rc["design_speed"])
        K = rrs_lqr(design, np.diag(rc["Q"]), rc["R"])[0]
    return RollPilot(
        model, mode=mode, delta_max=rud.max_angle, dt=dt, q=q, K=K, sway_scale=sway_scale,
        bandwidth=rc["heading_bandwidth"], zeta=rc["heading_zeta"],
    )  # fmt: skip
