r"""The named DP controllers, and each with its thrust allocation for N envs at once (the vector
env's stack).

What a plan-task env with ``controller=NAME`` runs every control period, for N envs (the
single env: N = 1): the law (:class:`~shipgym.controllers.pid.BatchedPID`,
Tomera 2014 eq. 23, for the ``pid*`` names; :class:`~shipgym.controllers.lq.BatchedLQ` for
``"lq"``; :class:`~shipgym.controllers.grimble.BatchedGrimbleLQ` for ``"alt-lq"``,
``"alt-lq-printed"``, ``"alt-sdre"``),
:class:`BatchedAllocation` (the closed form of the Blue Lady pattern, Tomera 2014 eqs. 12,
25-27: :func:`~shipgym.controllers.allocation.fixed3.fixed3_law`) and the reversal hysteresis
(:class:`~shipgym.controllers.conditioning.BatchedReversalHysteresis`). Each is the one
compiled run-time form of its law, which the single env runs at N = 1, so
env i of a batch equals the single env bit for bit. The iterative allocations (active-set
weighted least squares, the azimuth QP) run per env inside the step, each env with the
single env's allocator. Inputs and outputs are
``(N, 3)`` arrays (``(N, n_channels)`` for commands).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._text import did_you_mean
from shipgym.dynamics.vessel import Vessel, load_vessel

from .actuation import fixed3_parameters, make_allocator
from .allocation.fixed3 import law_parameters, run_law
from .conditioning import BatchedReversalHysteresis, reversal_threshold
from .grimble import GrimbleLQController
from .pid import BatchedPID, _mask, vessel_pid

__all__ = [
    "BATCHED_CONTROLLERS",
    "CONTROLLERS",
    "ControllerSpec",
    "BatchedAllocation",
    "BatchedAllocationResult",
    "BatchedDPController",
    "BatchedPID",
    "apply_residual",
    "batched_dp_controller",
    "controller_spec",
    "register_controller",
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
    the single env's), so env ``i`` gets the single env's allocation.

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
        if batch is not None:  # a law over N (least squares, the azimuth QP: from the states)
            return BatchedAllocationResult(*batch(t, np.asarray(state, dtype=float)))
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
    """The action a DP controller with a residual on top sends to the physics, for N envs.

    ``total = controller_action + residual_scale * residual``, ``applied = clip(total, -1, 1)``
    (the env then applies ``applied.astype(float32)``, the action a policy's float32 would
    be).

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
@dataclass(frozen=True)
class ControllerSpec:
    """A named controller: a factory ``f(vessel, dt)`` of a law (the
    ``law(eta_r, nu, eta_d_r, eta_dot_d_r, eta_ddot_d_r, *, saturated=None) -> tau``, with
    ``reset()``, ``change_frame(dpsi)`` and ``batched(n)``) and an allocation.

    The factory designs the controller for the vessel (its design model, capacity and
    presets) and the control period ``dt`` (s); it raises ``ValueError`` for a vessel the
    controller does not apply to. The law's ``batched(n)`` is its form for ``n`` envs (what
    :func:`batched_dp_controller` runs).
    """

    factory: Callable[..., Any]
    allocation: str
    description: str
    #: apply the vessel's reversal hysteresis after the allocation
    #: (:class:`~shipgym.controllers.conditioning.ReversalHysteresis`), and call the factory
    #: as ``f(vessel, dt, velocity_source=...)`` (:data:`~shipgym.controllers.pid.
    #: VELOCITY_SOURCES`: where the controller's velocity comes from, which sets its filter)
    conditioned: bool = False


def _pid(preset: str, scale: float = 1.0, conditioned: bool = False) -> Callable[..., Any]:
    """PID of Tomera (2014) eq. 23 for a vessel: its preset gains where it has them (the
    Blue Lady's tuned gains), else pole placement at the vessel's bandwidth times ``scale``
    on its design model (:func:`~shipgym.controllers.pid.pid_pole_placement`); with
    ``conditioned`` its velocity and its output are low-passed with the vessel's time
    constants for the velocity source (:func:`~shipgym.controllers.pid.vessel_pid`)."""

    def make(vessel: Vessel, dt: float, velocity_source: str = "kinematic") -> Any:
        return vessel_pid(
            vessel, preset, scale, dt, conditioned=conditioned, velocity_source=velocity_source
        )

    return make


def _grimble(variant: str) -> Callable[..., Any]:
    """Al-Takie (1982) LQ of :class:`~shipgym.controllers.grimble.GrimbleLQController`."""

    def make(vessel: Vessel, dt: float) -> Any:
        return GrimbleLQController(vessel, dt, variant=variant)

    return make


#: the PID designs by name: (gain preset, bandwidth scale, allocation, conditioned), the PID
#: entries of :data:`CONTROLLERS`; conditioned: the vessel's velocity filter and reversal
#: hysteresis (:mod:`shipgym.controllers.conditioning`)
BATCHED_CONTROLLERS: dict[str, tuple[str, float, str, bool]] = {
    "pid": ("tuned", 1.0, "constrained", True),
    "pid-smooth": ("smooth", 0.7, "constrained", True),
    "pid-raw": ("tuned", 1.0, "constrained", False),
    "pid-smooth-raw": ("smooth", 0.7, "constrained", False),
    "pid-seed": ("seed", 1.0, "inverse", False),
}
_PID_TEXT = {
    "pid": "Tomera (2014) eq. 23 PID (Blue Lady: tuned gains; other vessels: pole placement at "
    "the vessel's bandwidth), constrained allocation, command conditioning (the vessel's "
    "velocity and output filters and reversal hysteresis)",
    "pid-smooth": "Tomera (2014) eq. 23 PID, lower bandwidth for observer feedback, "
    "constrained allocation, command conditioning",
    "pid-raw": "'pid' without command conditioning (the unfiltered eq. 23 and the "
    "allocation's commands as they are)",
    "pid-smooth-raw": "'pid-smooth' without command conditioning",
    "pid-seed": "Tomera (2014) eq. 23 PID with the printed gains (eqs. 46-48), eq. 25 T^-1 "
    "(the Blue Lady only)",
}

#: Controllers selectable by name (``shipgym run --controller NAME``); extend with
#: :func:`register_controller`. Every one has a batched form (:func:`batched_dp_controller`).
CONTROLLERS: dict[str, ControllerSpec] = {
    **{
        name: ControllerSpec(_pid(preset, scale, cond), method, _PID_TEXT[name], cond)
        for name, (preset, scale, method, cond) in BATCHED_CONTROLLERS.items()
    },
    "alt-lq": ControllerSpec(
        _grimble("lq"),
        "constrained",
        "Al-Takie (1982) ch. 4 LQ with Grimble's weights (case b) re-solved on the vessel's "
        "per-unit LF model, surge alike; no integral action; constrained allocation",
    ),
    "alt-lq-printed": ControllerSpec(
        _grimble("printed"),
        "constrained",
        "Al-Takie (1982) 4.4-4.5: the printed LQ gain of Wimpey Sealab (case b) or Star "
        "Hercules (those vessels only), constrained allocation",
    ),
    "alt-sdre": ControllerSpec(
        _grimble("sdre"),
        "constrained",
        "Al-Takie (1982) ch. 7: the LQ re-solved every 2 steps on the model linearised at the "
        "saturating thruster states (SDRE), constrained allocation",
    ),
}


def register_controller(name: str, spec: ControllerSpec) -> None:
    """Add a named controller (e.g. ``"lq"``); names are unique."""
    if name in CONTROLLERS:
        raise ValueError(f"controller {name!r} is already registered")
    if spec.allocation not in _ALLOCATIONS:
        raise ValueError(f"unknown allocation {spec.allocation!r}; choose {list(_ALLOCATIONS)}")
    CONTROLLERS[name] = spec


#: allocation methods (:func:`~shipgym.controllers.actuation.make_allocator`)
_ALLOCATIONS = ("constrained", "inverse")


def controller_spec(name: str) -> ControllerSpec:
    """The :class:`ControllerSpec` of a controller name; unknown names list the valid ones."""
    try:
        return CONTROLLERS[name]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown controller {name!r}{did_you_mean(name, CONTROLLERS)}; choose one of: "
            f"{', '.join(CONTROLLERS)}"
        ) from None


class BatchedDPController:
    """A batched control law (:class:`BatchedPID`, :class:`~shipgym.controllers.lq.BatchedLQ`,
    :class:`~shipgym.controllers.grimble.BatchedGrimbleLQ`) and its
    :class:`BatchedAllocation`, with the ``tau_error`` each env feeds back (the controller
    state in an env, less the leg bookkeeping).

    Attributes:
        name: the controller name.
        pid: the batched law (any of the above; the name is historical).
        allocation: the :class:`BatchedAllocation`.
        tau_error: each env's last ``tau_error`` (n, 3) (zeros after a reset: not read then).
    """

    def __init__(
        self,
        name: str,
        pid: Any,
        allocation: BatchedAllocation,
        hysteresis: BatchedReversalHysteresis | None = None,
        velocity_source: str = "kinematic",
    ) -> None:
        self.name = name
        #: where the law's velocity comes from (``"truth"``, ``"kinematic"``, ``"model"``),
        #: which set its velocity filter
        self.velocity_source = velocity_source
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
        """A leg switch of the envs in ``mask``: the law's ``change_frame``."""
        self.pid.change_frame(dpsi, mask)

    def __call__(
        self,
        eta_r: ArrayLike,
        nu: ArrayLike,
        eta_d_r: ArrayLike,
        eta_dot_d_r: ArrayLike | None = None,
        eta_ddot_d_r: ArrayLike | None = None,
        state: ArrayLike | None = None,
        tau_ff: ArrayLike | None = None,
    ) -> tuple[Array, BatchedAllocationResult, Array]:
        """One control period of every env (the law, its allocation and the action).

        Args:
            tau_ff: a feedforward (n, 3) (N, N, N m, body) added to the law's ``tau``
                (:mod:`shipgym.controllers.feedforward`); ``None``: none.

        Returns:
            ``(tau_c, allocation, controller_action)``: the demand ``tau`` (n, 3) (the
            law's plus the feedforward), its allocation and the normalised command
            (n, n_channels) before the residual.
        """
        tau = self.pid(eta_r, nu, eta_d_r, eta_dot_d_r, eta_ddot_d_r, saturated=self.tau_error)
        if tau_ff is not None:
            tau = tau + np.asarray(tau_ff, dtype=float)
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
    designed as the single env's factory designs it (``make(..., controller=name)``).

    Args:
        name: a name of :data:`CONTROLLERS`: the PIDs of
            :data:`BATCHED_CONTROLLERS`, ``"lq"``, ``"alt-lq"``, ``"alt-lq-printed"``,
            ``"alt-sdre"``.
        vessel: a vessel or a packaged vessel's name.
        n: number of envs.
        dt: control period (s).
        velocity_source: where the velocity comes from (``"truth"``, ``"kinematic"``,
            ``"model"``; :func:`~shipgym.controllers.pid.vessel_pid`): sets the velocity
            filter of a conditioned controller.

    Raises:
        NotImplementedError: a registered controller whose law has no batched form.
        ValueError: an unknown name, a vessel the controller does not apply
            to (``"pid-seed"``, ``"alt-lq-printed"`` without printed gains), or what the
            scalar allocator raises.
    """
    spec = controller_spec(name)
    v = load_vessel(vessel)
    if spec.conditioned:
        single = spec.factory(v, dt, velocity_source=velocity_source)
    else:
        single = spec.factory(v, dt)
    law = _batched_law(name, single, n)
    hyst = (
        BatchedReversalHysteresis(v.actuators, reversal_threshold(v), n, dt=dt)
        if spec.conditioned
        else None
    )
    return BatchedDPController(
        name, law, BatchedAllocation(v, spec.allocation, dt), hyst, velocity_source
    )


def _batched_law(name: str, single: Any, n: int) -> Any:
    """The batched form of a controller's law, for ``n`` envs (its
    ``batched(n)``: the same design, the states at zero)."""
    batched = getattr(single, "batched", None)
    if batched is None:
        raise NotImplementedError(
            f"controller {name!r} ({type(single).__name__}) has no batched form (no batched(n))"
        )
    return batched(n)
