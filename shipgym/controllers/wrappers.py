"""Controllers as Gymnasium wrappers (style: gymnasium.wrappers).

Stack order: env -> observer wrapper (optional) -> controller wrapper. The controller reads
the navigation data (``info["record"].nav``, a :class:`shipgym.records.NavigationData`: the
truth, or an observer's estimate when an observer wrapper sits below) and the guidance
reference (``info["record"].reference``) of the previous step, so it uses only what a real DP
system would know.
"""

from __future__ import annotations

from typing import Any, Protocol

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics import wrap_angle
from shipgym.dynamics.vessel import Vessel
from shipgym.guidance import to_r_frame
from shipgym.records import ControlData, StepRecord, step_record

from .actuation import make_allocator
from .allocation import Allocation
from .batch import CONTROLLERS, ControllerSpec, controller_spec, register_controller
from .conditioning import ReversalHysteresis, reversal_threshold

__all__ = [
    "CONTROLLERS",
    "ControllerSpec",
    "DPController",
    "DPControllerWrapper",
    "controller_spec",
    "register_controller",
]


class DPController(Protocol):
    """What the wrapper needs of a DP control law (r-frame errors in, body tau out)."""

    def __call__(
        self,
        eta_r: ArrayLike,
        nu: ArrayLike,
        eta_d_r: ArrayLike,
        eta_dot_d_r: ArrayLike | None = None,
        eta_ddot_d_r: ArrayLike | None = None,
        *,
        saturated: ArrayLike | None = None,
    ) -> NDArray[np.float64]: ...

    def reset(self) -> None: ...

    def change_frame(self, dpsi: float) -> None: ...


def velocity_source(env: gym.Env[Any, Any]) -> str:
    """Where a controller wrapper on ``env`` gets its velocity: ``"truth"`` (no observer below
    it), ``"model"`` (an observer whose ``model_based`` is true, e.g. the EKF) or
    ``"kinematic"`` (any other observer, e.g. ``kbf``, ``dkf``)."""
    e: Any = env
    while isinstance(e, gym.Wrapper):
        obs = getattr(e, "observer", None)
        if obs is not None and hasattr(obs, "estimate"):
            return "model" if getattr(obs, "model_based", False) else "kinematic"
        e = e.env
    return "truth"


class DPControllerWrapper(
    gym.Wrapper[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32], NDArray[np.float32]],
    gym.utils.RecordConstructorArgs,
):
    """Runs the DP controller (Tomera 2014 eq. 23) and the thrust allocation inside ``step``.

    The wrapper's action is a *residual* added to the controller's normalised command
    (``Box(-1, 1, (n,))``, one per actuator channel; zero: the pure controller), so
    ``env.step(np.zeros(n))`` runs the
    classical DP system and a learned policy can act on top of it. The sum is clipped to
    [-1, 1] and the clipping flagged in ``info["residual_clipped"]``.

    Info gains ``tau_c`` (controller output, N, N, N m, body), ``tau_delivered`` and
    ``tau_error`` (what the allocation could not deliver), ``controller_action`` (normalised)
    and ``allocation_saturated`` (per actuator); the same in ``info["record"].control`` (a
    :class:`~shipgym.records.ControlData`).

    Args:
        env: an environment whose ``info`` carries a :class:`~shipgym.records.StepRecord`
            (any ``shipgym/BlueLady*`` env, possibly under an observer wrapper).
        controller: a name in :data:`CONTROLLERS` (``"pid"``, ``"pid-seed"``).
        residual_scale: factor on the residual action (0 disables it).

    Note:
        Records its constructor arguments, so ``gym.make(env.spec)`` rebuilds the stack.
    """

    def __init__(
        self, env: gym.Env[Any, Any], controller: str = "pid", residual_scale: float = 1.0
    ) -> None:
        gym.utils.RecordConstructorArgs.__init__(
            self, controller=controller, residual_scale=residual_scale
        )
        gym.Wrapper.__init__(self, env)
        spec = controller_spec(controller)
        if not (
            isinstance(residual_scale, int | float)
            and not isinstance(residual_scale, bool)
            and 0 <= residual_scale < np.inf
        ):  # (a negative scale would turn the policy's residual against it)
            raise ValueError(f"residual_scale must be a finite number >= 0, got {residual_scale!r}")
        self.controller_name = controller
        self.residual_scale = float(residual_scale)
        base = env.unwrapped
        self.vessel: Vessel = base.vessel  # type: ignore[attr-defined]
        self.actuators = self.vessel.actuators
        dt = base.control_period  # type: ignore[attr-defined]
        self.velocity_source = velocity_source(env)
        if spec.conditioned:
            self.controller = spec.factory(self.vessel, dt, velocity_source=self.velocity_source)
        else:
            self.controller = spec.factory(self.vessel, dt)
        self._allocate = make_allocator(self.vessel, spec.allocation, dt)
        hyst = (
            ReversalHysteresis(self.actuators, reversal_threshold(self.vessel))
            if spec.conditioned
            else None
        )
        self._hysteresis = hyst if hyst is not None and hyst.active else None
        self.action_space = spaces.Box(-1.0, 1.0, (self.actuators.n_channels,), np.float32)
        self._record: StepRecord | None = None
        self._leg = 0
        self._psi_P = 0.0
        self._tau_error: NDArray[np.float64] | None = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        obs, info = self.env.reset(seed=seed, options=options)
        self.controller.reset()
        if self._hysteresis is not None:
            self._hysteresis.reset()
        rec = step_record(info)
        self._record = rec
        self._leg = rec.reference.leg
        self._psi_P = float(rec.reference.eta_P[2])
        self._tau_error = None
        return obs, info

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        residual, _ = self.actuators.as_vector(action, "residual action")
        if self._record is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        tau_c, alloc = self._control(self._record)
        a_ctrl = self.actuators.command_to_action(alloc.command)
        total = a_ctrl + self.residual_scale * residual
        applied = np.clip(total, -1.0, 1.0)
        obs, reward, terminated, truncated, info = self.env.step(applied.astype(np.float32))
        info["tau_c"] = tau_c
        info["tau_delivered"] = alloc.tau
        info["tau_error"] = alloc.tau_error
        info["controller_action"] = a_ctrl
        info["allocation_saturated"] = alloc.saturated
        info["residual_clipped"] = applied != total
        self._tau_error = alloc.tau_error
        rec = step_record(info).with_control(
            ControlData(
                self.controller_name,
                tau_c,
                alloc.tau,
                alloc.tau_error,
                a_ctrl,
                alloc.saturated,
                info["residual_clipped"],
            )
        )
        info["record"] = rec
        ref = rec.reference
        if ref.leg != self._leg:
            psi_P = float(ref.eta_P[2])
            # wrapped as the vector env wraps its array of angles (the same bits)
            self.controller.change_frame(float(wrap_angle(np.float64(psi_P - self._psi_P))))
            self._leg, self._psi_P = ref.leg, psi_P
        self._record = rec
        return obs, reward, terminated, truncated, info

    def _control(self, rec: StepRecord) -> tuple[NDArray[np.float64], Allocation]:
        """Controller and allocation from the navigation data and reference of a record."""
        ref, nav = rec.reference, rec.nav
        eta_d_r = ref.eta_d_r
        eta_r = to_r_frame(nav.eta, ref.eta_P, psi_ref_r=float(eta_d_r[2]))
        tau_c = self.controller(
            eta_r,
            nav.nu,
            eta_d_r,
            ref.eta_dot_d_r,
            ref.eta_ddot_d_r,
            saturated=self._tau_error,
        )
        # the actuator states of the record (azimuth angles: where the rate limit starts)
        alloc = self._allocate(tau_c, rec.actuators.state)
        if self._hysteresis is not None:  # what is delivered: the anti-windup sees it
            alloc = self._hysteresis(alloc)
        return tau_c, alloc
