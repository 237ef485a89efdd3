"""Thrust allocation for any vessel: from a requested ``tau`` to actuator commands.

Public names: ``Allocator``, ``fixed3_parameters``, ``make_allocator``, ``planar_capacity``.
Sources: Tomera (2014).

Design notes: docs/design/controllers.actuation.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.actuators import (
    ActuatorSet,
    Azimuth,
    Propeller,
    bollard_inverse,
    bollard_inverse_rows,
)
from shipgym.dynamics.thrusters import ThrusterParameters
from shipgym.dynamics.vessel import Vessel

from .allocation import Allocation, force_capacity
from .allocation.fixed3 import Fixed3Allocator

__all__ = ["Allocator", "fixed3_parameters", "make_allocator", "planar_capacity"]

Allocator = Callable[[ArrayLike, NDArray[np.float64]], Allocation]
"""``allocator(tau, state) -> Allocation``: ``state`` the actuator states now (for rates)."""


def planar_capacity(vessel: Vessel) -> NDArray[np.float64]:
    """Largest ``|X|, |Y|, |N|`` of the vessel's actuators, each DOF alone (N, N, N m).

    The exact box of the closed form (:func:`~shipgym.controllers.allocation.force_capacity`)
    for the Blue Lady pattern; otherwise :meth:`ActuatorSet.capacity`.
    """
    p3 = fixed3_parameters(vessel.actuators)
    if p3 is not None:
        return force_capacity(p3)
    cap = vessel.actuators.capacity()
    return cap if cap.size == 3 else cap[[0, 1, 3]]


def fixed3_parameters(actuators: ActuatorSet) -> ThrusterParameters | None:
    """The :class:`ThrusterParameters` of a Blue-Lady-pattern set, else ``None``.

    The pattern: a main propeller on the centre line (``alpha = 0``, quadratic or linear law
    with one constant) followed by a bow and a stern tunnel thruster (``alpha = 90 deg``,
    linear, same range and lag, on the centre line), as in Tomera (2014) eq. 12.
    """
    a = actuators.actuators
    if len(a) != 3 or not all(isinstance(x, Propeller) for x in a) or actuators.dofs != 3:
        return None
    main, bow, stern = a  # type: ignore[misc]
    ok = (
        main.law == "quadratic"
        and main.k_ahead == main.k_astern
        and main.direction == (1.0, 0.0)
        and main.position[1] == 0.0
        and all(t.direction == (0.0, 1.0) and t.position[1] == 0.0 for t in (bow, stern))
        and bow.static_gain is not None
        and stern.static_gain is not None
        and (bow.lower, bow.upper, bow.time_constant)
        == (stern.lower, stern.upper, stern.time_constant)
        and bow.position[0] > 0.0 > stern.position[0]
    )
    if not ok:
        return None
    return ThrusterParameters(
        k1=main.k_ahead, k2=bow.k_ahead, k3=stern.k_ahead, L2=bow.position[0],
        L3=-stern.position[0], x_main=main.position[0], n_min=main.lower, n_max=main.upper,
        p_min=bow.lower, p_max=bow.upper, T_main=main.time_constant,
        T_tunnel=bow.time_constant,
    )  # fmt: skip


def make_allocator(vessel: Vessel, method: str = "constrained", dt: float = 1.0) -> Allocator:
    """The thrust allocation of ``vessel``.

    Args:
        vessel: the vessel.
        method: ``"constrained"`` (optimal within the actuator limits) or ``"inverse"``
            (Tomera 2014 eq. 25, the Blue Lady pattern only).
        dt: control period (s): how far an azimuth may turn per call.

    Raises:
        ValueError: unknown method, or ``"inverse"`` for a vessel it does not fit.
    """
    if method not in ("constrained", "inverse"):
        raise ValueError(f"unknown allocation {method!r}; choose 'constrained' or 'inverse'")
    acts = vessel.actuators
    p3 = fixed3_parameters(acts)
    if p3 is not None:
        return Fixed3Allocator(p3, inverse=method == "inverse")
    if method == "inverse":
        raise ValueError(
            f"allocation 'inverse' (Tomera 2014 eq. 25) needs the Blue Lady's three-thruster "
            f"layout; vessel {vessel.name!r} has {acts!r}: use 'constrained'"
        )
    if acts.fixed:
        return _FixedAllocator(acts)
    return _AzimuthAllocator(acts, dt)


def _planar_B(acts: ActuatorSet, idx: list[int]) -> NDArray[np.float64]:
    """Planar (X, Y, N) columns of the fixed-direction actuators ``idx``."""
    cols = []
    for i in idx:
        a = acts.actuators[i]
        assert isinstance(a, Propeller)
        c, s = a.direction
        x, y, _ = a.position
        cols.append([c, s, x * s - y * c])
    return np.array(cols, dtype=float).reshape(-1, 3).T


def _inverse_constants(props: Any) -> tuple[Any, Any, Any]:
    """The propellers' constants of :func:`~shipgym.dynamics.actuators.bollard_inverse`, as
    rows: ``k_ahead``, ``k_astern``, quadratic."""
    return (
        np.array([a.k_ahead for a in props], dtype=float),
        np.array([a.k_astern for a in props], dtype=float),
        np.array([a.law == "quadratic" for a in props]),
    )


def _tau3(tau: ArrayLike) -> NDArray[np.float64]:
    t = np.asarray(tau, dtype=float)
    if t.shape != (3,) or not np.all(np.isfinite(t)):
        raise ValueError(f"tau must be 3 finite numbers [X N, Y N, N N m], got {tau!r}")
    return t


class _FixedAllocator:
    """Box-constrained weighted least squares over fixed-direction thrusters."""

    def __init__(self, acts: ActuatorSet) -> None:
        from .allocation import WLSAllocator

        self.acts = acts
        self.B = _planar_B(acts, list(range(len(acts))))
        self.f_min = np.array([a.force_lower for a in acts.actuators])  # type: ignore[attr-defined]
        self.f_max = np.array([a.force_upper for a in acts.actuators])  # type: ignore[attr-defined]
        # each DOF's error relative to its capacity
        self.W = 1.0 / np.maximum(acts.capacity()[[0, 1, -1]], 1e-9) ** 2
        self._wls = WLSAllocator(self.B, self.f_min, self.f_max, W=self.W)
        self._inverse = _inverse_constants(acts.actuators)
        self._lower, self._upper = acts.lower, acts.upper

    def __call__(self, tau: ArrayLike, state: NDArray[np.float64]) -> Allocation:
        return Allocation(*(x[0] for x in self.batch(_tau3(tau).reshape(1, 3))))

    def batch(self, tau: NDArray[np.float64], state: Any = None) -> tuple[Any, ...]:
        """The allocations of N requests ``tau`` (N, 3): ``(command, force, tau, tau_error,
        saturated)``, each with a leading axis N (the compiled law over N, one call)."""
        force, delivered, error, sat = self._wls.batch(tau)
        cmd = np.empty_like(force)
        bollard_inverse_rows(force, *self._inverse, cmd)  # (the constants are C rows)
        np.minimum(np.maximum(cmd, self._lower, out=cmd), self._upper, out=cmd)  # np.clip's
        return cmd, force, delivered, error, sat


class _AzimuthAllocator:
    """Extended-thrust allocation over azimuths (plus any fixed thrusters), rate-limited.

    The angle rate limit of the QP is the unit's turning rate times the control period, so
    the angle command (a rate, the azimuth's second channel) reaches the allocated angle at
    the end of the period without exceeding its limit.
    """

    #: the QP's cost on turning (``AzimuthAllocator(turn_weight=...)``). Off: with it (0.01 to
    #: 0.1) Wimpey Sealab's units turned ~60 instead of ~7 900 deg in 1 000 s of station keeping,
    #: but one case of 40 (15 m/s from 225 deg, seed 3) drifted 25 m off; not yet understood
    TURN_WEIGHT = 0.0

    def __init__(self, acts: ActuatorSet, dt: float) -> None:
        from .allocation import AzimuthAllocator, Azimuths

        self.acts = acts
        self.dt = float(dt)
        self.az = [i for i, a in enumerate(acts.actuators) if isinstance(a, Azimuth)]
        self.fx = [i for i, a in enumerate(acts.actuators) if isinstance(a, Propeller)]
        units: list[Azimuth] = [acts.actuators[i] for i in self.az]  # type: ignore[misc]
        self._thrust_idx = np.array([acts.slices[i].start for i in self.az], dtype=np.intp)
        self._angle_idx = self._thrust_idx + 1
        self._rate = np.array([a.max_rate for a in units])
        self._f_max = np.array([a.max_thrust_n for a in units])
        spec = Azimuths(
            positions=np.array([a.position[:2] for a in units]),
            f_max=np.array([a.max_thrust_n for a in units]),
            angle_prev=np.array([a.angle0 for a in units]),
            max_dangle=np.minimum(self._rate * self.dt, math.radians(80.0)),
            reversible=np.array([a.reversible for a in units]),
        )
        fixed: Any = None
        self._inverse = _inverse_constants([acts.actuators[i] for i in self.fx])
        self._fixed_channels = np.array([acts.slices[i].start for i in self.fx], dtype=np.intp)
        if self.fx:
            fa = [acts.actuators[i] for i in self.fx]
            fixed = (
                _planar_B(acts, self.fx),
                np.array([a.force_lower for a in fa]),  # type: ignore[attr-defined]
                np.array([a.force_upper for a in fa]),  # type: ignore[attr-defined]
            )
        W = 1.0 / np.maximum(acts.capacity()[[0, 1, -1]], 1e-9) ** 2
        self._qp = AzimuthAllocator(spec, fixed=fixed, W=W, turn_weight=self.TURN_WEIGHT)

    def __call__(self, tau: ArrayLike, state: NDArray[np.float64]) -> Allocation:
        st = np.asarray(state, dtype=float).reshape(1, -1)
        return Allocation(*(x[0] for x in self.batch(_tau3(tau).reshape(1, 3), st)))

    def batch(self, tau: NDArray[np.float64], state: ArrayLike) -> tuple[Any, ...]:
        """The allocations of N requests ``tau`` (N, 3) from the actuator states ``state``
        (N, n_channels) (the azimuths' angles now): ``(command, force, tau, tau_error,
        saturated)``, each with a leading axis N (the compiled law over N, one call)."""
        acts = self.acts
        angle_prev = np.asarray(state, dtype=float)[:, self._angle_idx]
        thrust, angle, _, f_fixed, delivered, error, sat_qp, rate_lim = self._qp.batch(
            tau, angle_prev
        )
        n = thrust.shape[0]
        cmd = np.zeros((n, acts.n_channels))
        force = np.zeros((n, len(acts)))
        sat = np.zeros((n, acts.n_channels), dtype=bool)
        j = self._thrust_idx
        cmd[:, j] = thrust / self._f_max
        rate = (angle - angle_prev) / self.dt
        cmd[:, j + 1] = np.minimum(np.maximum(rate, -self._rate), self._rate)
        force[:, self.az] = thrust
        sat[:, j] = sat_qp[:, : len(self.az)] & ~rate_lim
        sat[:, j + 1] = rate_lim
        if self.fx:
            fx = self._fixed_channels
            cmd[:, fx] = bollard_inverse(f_fixed, *self._inverse)
            force[:, self.fx] = f_fixed
            sat[:, fx] = sat_qp[:, len(self.az) :]
        cmd = np.clip(cmd, acts.lower, acts.upper)
        return cmd, force, delivered, error, sat
