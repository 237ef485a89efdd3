r"""The DP controller and its thrust allocation for N envs at once (the vector env's stack).

What :class:`~shipgym.controllers.wrappers.DPControllerWrapper` runs every control period for
``controller="pid"`` (and ``"pid-smooth"``, ``"pid-raw"``, ``"pid-smooth-raw"``,
``"pid-seed"``), for N envs: :class:`~shipgym.controllers.pid.BatchedPID` (Tomera 2014 eq. 23),
:class:`BatchedAllocation` (the closed form of the Blue Lady pattern, Tomera 2014 eqs. 12,
25-27: :func:`~shipgym.controllers.allocation.fixed3.fixed3_law`) and the reversal hysteresis
(:class:`~shipgym.controllers.conditioning.BatchedReversalHysteresis`). Each is the one
compiled run-time form of its law, which the single env's controller wrapper runs at N = 1, so
env i of a batch equals the single env bit for bit. The iterative allocations (active-set
weighted least squares, the azimuth QP) run per env inside the step, each env with the
single env's allocator. Inputs and outputs are
``(N, 3)`` arrays (``(N, n_channels)`` for commands).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.vessel import Vessel, load_vessel

from .actuation import fixed3_parameters, make_allocator
from .allocation.fixed3 import law_parameters, run_law
from .conditioning import BatchedReversalHysteresis, reversal_threshold
from .pid import BatchedPID, _mask, vessel_pid

__all__ = [
    "BATCHED_CONTROLLERS",
    "BatchedAllocation",
    "BatchedAllocationResult",
    "BatchedDPController",
    "BatchedPID",
    "apply_residual",
    "batched_dp_controller",
]

Array = NDArray[np.float64]


# ---- thrust allocation -----------------------------------------------------------------------
class BatchedAllocationResult(NamedTuple):
    """The allocations of N envs (the scalar :class:`~shipgym.controllers.allocation.Allocation`
    with a leading env axis).

    Attributes:
        command: actuator commands (n, n_channels), in the channels' units, within range.
        force: thrust of every actuator (n, n_actuators) (N).
        tau: delivered ``[X, Y, N]`` (n, 3) (N, N, N m).
        tau_error: requested minus delivered (n, 3): what the PID's ``saturated`` takes.
        saturated: per channel (n, n_channels) bool.
    """

    command: Array
    force: Array
    tau: Array
    tau_error: Array
    saturated: NDArray[np.bool_]


class BatchedAllocation:
    """The thrust allocation of ``vessel`` for N envs.

    The closed form of the Blue Lady pattern
    (:func:`~shipgym.controllers.actuation.fixed3_parameters`: ``"constrained"``,
    :func:`~shipgym.controllers.allocation.allocate`, or ``"inverse"``,
    :func:`~shipgym.controllers.allocation.allocate_inverse`) runs as one compiled law over the
    envs; the iterative allocations (the active-set weighted least squares of other fixed
    thruster sets, the azimuth QP) run per env, each env with its own allocator of
    :func:`~shipgym.controllers.actuation.make_allocator` (what the single env's controller
    wrapper calls), so env ``i`` gets the single env's allocation.

    Args:
        vessel: a vessel, a packaged vessel's name or a package path.
        method: ``"constrained"`` or ``"inverse"``.
        dt: control period (s): how far an azimuth may turn per call.

    Raises:
        ValueError: what :func:`~shipgym.controllers.actuation.make_allocator` raises (an
            unknown method, ``"inverse"`` for another layout, a set it cannot allocate).
    """

    def __init__(self, vessel: Vessel | str, method: str = "constrained", dt: float = 1.0) -> None:
        v = load_vessel(vessel)
        make_allocator(v, method, dt)  # the scalar's checks and errors
        acts = v.actuators
        self.vessel = v
        self.actuators = acts
        self.method = method
        self.dt = dt
        self.n_channels = acts.n_channels
        self.thrusters = p = fixed3_parameters(acts)
        self._P = None if p is None else law_parameters(p)
        self._inverse = method == "inverse"
        self._each: list[Any] = []  # the per-env allocators of an iterative allocation

    def __call__(self, tau: ArrayLike, state: ArrayLike | None = None) -> BatchedAllocationResult:
        """Allocate ``tau`` (n, 3) (N, N, N m) of every env; ``state``: the actuator states
        (n, n_channels) (the azimuth angles an iterative allocation starts from; unused by
        the closed form).

        Returns:
            The :class:`BatchedAllocationResult` (new arrays).
        """
        t = np.asarray(tau, dtype=float)
        if t.ndim != 2 or t.shape[1] != 3:
            raise ValueError(f"tau must have shape (n, 3) ([X N, Y N, N N m]), got {t.shape}")
        if self._P is not None:
            t = t if t.flags.c_contiguous else np.ascontiguousarray(t)
            return BatchedAllocationResult(*run_law(self._P, t, self._inverse))
        n = t.shape[0]
        if state is None:
            raise ValueError(
                f"the allocation of {self.vessel.name!r} is iterative and starts from the "
                "actuator states: pass state= (n, n_channels)"
            )
        if len(self._each) != n:
            self._each = [make_allocator(self.vessel, self.method, self.dt) for _ in range(n)]
        batch = getattr(self._each[0], "batch", None)
        if batch is not None:  # a law over N (the fixed thruster sets' least squares)
            return BatchedAllocationResult(*batch(t))
        st = None if state is None else np.asarray(state, dtype=float)
        rows = [alloc(t[i], None if st is None else st[i]) for i, alloc in enumerate(self._each)]
        return BatchedAllocationResult(*(np.array(field) for field in zip(*rows, strict=True)))

    def command_to_action(self, command: ArrayLike) -> Array:
        """Physical commands (n, n_channels) -> normalised actions
        (:meth:`ActuatorSet.command_to_action <shipgym.dynamics.actuators.ActuatorSet.
        command_to_action>` over the leading env axis)."""
        return self.actuators.command_to_action(command)


def apply_residual(
    controller_action: ArrayLike, residual: ArrayLike, residual_scale: float
) -> tuple[Array, NDArray[np.bool_]]:
    """The action the controller wrapper sends to the env, for N envs.

    ``total = controller_action + residual_scale * residual``, ``applied = clip(total, -1, 1)``
    (what :class:`~shipgym.controllers.wrappers.DPControllerWrapper` does; the wrapper then
    passes ``applied.astype(float32)`` to the env).

    Returns:
        ``(applied, residual_clipped)``: the clipped actions (n, n_channels) (float64) and
        where the clip changed them.
    """
    total = np.asarray(controller_action, dtype=float) + residual_scale * np.asarray(
        residual, dtype=float
    )
    applied = np.minimum(np.maximum(total, -1.0), 1.0)
    return applied, applied != total


# ---- the named controllers -------------------------------------------------------------------
#: the batched controller names: (gain preset, bandwidth scale, allocation, conditioned), as
#: the PID entries of :data:`shipgym.controllers.wrappers.CONTROLLERS` (a test checks they
#: agree); conditioned: the vessel's velocity filter and reversal hysteresis
#: (:mod:`shipgym.controllers.conditioning`)
BATCHED_CONTROLLERS: dict[str, tuple[str, float, str, bool]] = {
    "pid": ("tuned", 1.0, "constrained", True),
    "pid-smooth": ("smooth", 0.7, "constrained", True),
    "pid-raw": ("tuned", 1.0, "constrained", False),
    "pid-smooth-raw": ("smooth", 0.7, "constrained", False),
    "pid-seed": ("seed", 1.0, "inverse", False),
}


class BatchedDPController:
    """A :class:`BatchedPID` and its :class:`BatchedAllocation`, with the ``tau_error`` each
    env feeds back (the controller wrapper's state, less the leg bookkeeping).

    Attributes:
        name: the controller name.
        pid: the :class:`BatchedPID`.
        allocation: the :class:`BatchedAllocation`.
        tau_error: each env's last ``tau_error`` (n, 3) (zeros after a reset: not read then).
    """

    def __init__(
        self,
        name: str,
        pid: BatchedPID,
        allocation: BatchedAllocation,
        hysteresis: BatchedReversalHysteresis | None = None,
    ) -> None:
        self.name = name
        self.pid = pid
        self.allocation = allocation
        self.hysteresis = hysteresis if hysteresis is not None and hysteresis.active else None
        self.n = pid.n
        self.tau_error = np.zeros((pid.n, 3))

    def reset(self, mask: ArrayLike | None = None) -> None:
        """Start new episodes: every env, or those where ``mask``."""
        m = _mask(mask, self.n)
        self.pid.reset(m)
        if self.hysteresis is not None:
            self.hysteresis.reset(m)
        if m is None:
            self.tau_error[:] = 0.0
        else:
            self.tau_error[m] = 0.0

    def change_frame(self, dpsi: ArrayLike, mask: ArrayLike | None = None) -> None:
        """A leg switch of the envs in ``mask``: :meth:`BatchedPID.change_frame`."""
        self.pid.change_frame(dpsi, mask)

    def __call__(
        self,
        eta_r: ArrayLike,
        nu: ArrayLike,
        eta_d_r: ArrayLike,
        eta_dot_d_r: ArrayLike | None = None,
        eta_ddot_d_r: ArrayLike | None = None,
        state: ArrayLike | None = None,
    ) -> tuple[Array, BatchedAllocationResult, Array]:
        """One control period of every env (the wrapper's ``_control`` and action).

        Returns:
            ``(tau_c, allocation, controller_action)``: the PID's ``tau`` (n, 3), its
            allocation and the normalised command (n, n_channels) before the residual.
        """
        tau = self.pid(eta_r, nu, eta_d_r, eta_dot_d_r, eta_ddot_d_r, saturated=self.tau_error)
        alloc = self.allocation(tau, state)
        if self.hysteresis is not None:  # what is delivered: the anti-windup sees it
            cmd, force, t_del, err = self.hysteresis(
                alloc.command, alloc.force, alloc.tau, alloc.tau_error
            )
            alloc = BatchedAllocationResult(cmd, force, t_del, err, alloc.saturated)
        self.tau_error = alloc.tau_error
        return tau, alloc, self.allocation.command_to_action(alloc.command)


def batched_dp_controller(
    name: str, vessel: Vessel | str, n: int, dt: float, velocity_source: str = "kinematic"
) -> BatchedDPController:
    """The named DP controller for ``n`` envs of ``vessel`` at control period ``dt`` (s),
    designed as the controller wrapper's factory designs it (``make(..., controller=name)``).

    Args:
        name: ``"pid"``, ``"pid-smooth"`` or ``"pid-seed"`` (:data:`BATCHED_CONTROLLERS`).
        vessel: a vessel or a packaged vessel's name.
        n: number of envs.
        dt: control period (s).
        velocity_source: where the velocity comes from (``"truth"``, ``"kinematic"``,
            ``"model"``; :func:`~shipgym.controllers.pid.vessel_pid`): sets the velocity
            filter of a conditioned controller, as the wrapper does.

    Raises:
        NotImplementedError: a controller that is not batched (the LQ family), or a vessel
            whose allocation is iterative (:class:`BatchedAllocation`).
        ValueError: an unknown name, a 4-DOF vessel, ``"pid-seed"`` for a vessel without the
            printed gains, or what the scalar allocator raises.
    """
    if name not in BATCHED_CONTROLLERS:
        raise NotImplementedError(
            f"controller {name!r} has no batched form; batched: {', '.join(BATCHED_CONTROLLERS)}"
        )
    v = load_vessel(vessel)
    if v.dofs != 3:
        raise ValueError(f"the batched DP controller is 3-DOF; {v.name!r} has {v.dofs} DOF")
    preset, scale, method, conditioned = BATCHED_CONTROLLERS[name]
    pid = BatchedPID.from_scalar(
        vessel_pid(v, preset, scale, dt, conditioned=conditioned, velocity_source=velocity_source),
        n,
    )
    hyst = BatchedReversalHysteresis(v.actuators, reversal_threshold(v), n) if conditioned else None
    return BatchedDPController(name, pid, BatchedAllocation(v, method, dt), hyst)
