r"""Discrete Kalman filter and Kalman-Bucy filter per DOF on a double integrator (Tomera 2011,
2014).

Per DOF ``s = [p_dot, p]``, ``A = [[0, 0], [1, 0]]``, ``C = [0, 1]`` (Tomera 2011 eqs.
53-59); DKF: Tomera (2014) Table 3; KBF: Tomera (2014) eqs. 33-35; ``nu = R^T(psi) eta_dot``.

Public names: ``OBSERVERS``, ``DiscreteKalmanFilter``, ``KalmanBucyFilter``, ``make_observer``.

Design notes: docs/design/observers.kalman.md.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .base import (
    OBSERVERS,
    Estimate,
    Observer,
    OutlierGate,
    StepInfo,
    as_pose,
    as_tau,
    make_observer,
    no_measurement,
    register_observer,
)
from .batch import DEFAULT_INITIAL_VELOCITY_STD, BatchedKalman
from .design import DKF_DESIGN, KBF_DESIGN, TOMERA_DKF, TOMERA_KBF, KalmanDesign

__all__ = [
    "OBSERVERS",
    "DiscreteKalmanFilter",
    "KalmanBucyFilter",
    "make_observer",
]


class _DoubleIntegratorFilter(Observer):
    """The :class:`~shipgym.observers.base.Observer` interface of one env of
    :class:`~shipgym.observers.batch.BatchedKalman` (``n = 1``), which holds the state and runs
    the law (the outlier gate's count included: :attr:`gate` gives its settings)."""

    _continuous = False

    def __init__(
        self,
        design: KalmanDesign | Mapping[str, Any],
        *,
        name: str,
        constant_gain: bool,
        gate_probability: float | None = 0.9999,
        max_rejections: int = 5,
        initial_velocity_std: ArrayLike = DEFAULT_INITIAL_VELOCITY_STD,
    ) -> None:
        if isinstance(design, Mapping):
            design = KalmanDesign.from_dict(dict(design))
        if not isinstance(design, KalmanDesign):
            raise ValueError(f"design must be a KalmanDesign or a mapping, got {design!r}")
        std = np.asarray(initial_velocity_std, dtype=float)
        if std.shape != (3,) or not np.isfinite(std).all() or (std < 0).any():
            raise ValueError(
                "initial_velocity_std must be 3 finite values >= 0 (m/s, m/s, rad/s), "
                f"got {initial_velocity_std!r}"
            )
        self.name = str(name)
        self.design = design
        self.gate = OutlierGate(gate_probability, dof=3, max_rejections=max_rejections)
        self.initial_velocity_std = std
        self._b = BatchedKalman.from_design(
            design,
            1,
            continuous=self._continuous,
            constant_gain=constant_gain,
            name=self.name,
            gate_probability=gate_probability,
            max_rejections=max_rejections,
            initial_velocity_std=std,
        )
        self._t1 = np.zeros(1)
        self._z1 = np.zeros((1, 3))
        self._valid1 = np.ones(1, dtype=bool)

    def _batch_settings(self) -> dict[str, Any]:
        """What :class:`~shipgym.observers.batch.BatchedKalman` needs to batch this filter."""
        b = self._b
        return {
            "design": self.design,
            "continuous": b.continuous,
            "constant_gain": b.constant_gain,
            "name": self.name,
            "gate": self.gate,
            "initial_velocity_std": self.initial_velocity_std,
        }

    # ---- interface ---------------------------------------------------------------------------
    def reset(
        self,
        t0: float,
        eta0: ArrayLike,
        *,
        nu0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
    ) -> None:
        """Start at ``t0`` from the pose ``eta0`` (and body velocity ``nu0``, default rest).

        Args:
            t0: initial time (s).
            eta0: ``[x, y, psi]`` (m, m, rad); the heading's branch is kept (continuous
                estimate from there on).
            nu0: ``[u, v, r]`` (m/s, m/s, rad/s), ``None`` = 0.
            P0: (6, 6) covariance of ``[x, y, psi, x_dot, y_dot, psi_dot]``; cross-DOF terms
                are ignored. ``None``: the measurement variances ``R`` for the pose and
                ``initial_velocity_std**2`` for the rates.

        Raises:
            ValueError: non-finite or mis-shaped arguments, ``P0`` not symmetric ``>= 0``.
        """
        t0 = float(t0)
        if not math.isfinite(t0):
            raise ValueError(f"t0 must be finite, got {t0!r}")
        eta = as_pose(eta0, "eta0")
        nu = None if nu0 is None else as_pose(nu0, "nu0", "[u, v, r] (m/s, m/s, rad/s)")
        if P0 is not None and np.shape(P0) != (6, 6):
            raise ValueError(f"P0 must be a finite 6x6 matrix, got shape {np.shape(P0)}")
        self._b.reset(t0, eta, nu0=nu, P0=P0)

    def step(self, t: float, z: ArrayLike | None, tau: ArrayLike | None = None) -> StepInfo:
        """Propagate to ``t`` and update with the measured pose ``z`` (``None``: coast).

        Args:
            t: time now (s), not earlier than the previous call.
            z: measured ``[x, y, psi]`` (m, m, rad; heading in any branch) or ``None``.
            tau: body thrust ``[X, Y, N]`` (N, N, N m); checked, not used (kinematic model).

        Returns:
            :class:`~shipgym.observers.base.StepInfo` (innovation, NIS, gate decision).

        Raises:
            RuntimeError: :meth:`reset` was not called.
            ValueError: time going backwards, ``z`` or ``tau`` not 3 finite values.
        """
        b = self._b
        if not b._all_started:
            raise RuntimeError(f"{self.name}: call reset(t0, eta0) before step()")
        if tau is not None:
            as_tau(tau)
        self._t1[0] = t
        if z is None:
            b._advance(self._t1, b._z0, b._none)
            return no_measurement()
        self._z1[0] = as_pose(z)
        b._advance(self._t1, self._z1, self._valid1)
        return StepInfo(b._innov[0].copy(), float(b._nis[0]), bool(b._rej[0]), bool(b._forced[0]))

    def estimate(self) -> Estimate:
        """The current estimate (copies); ``P`` in ``[x, y, psi, x_dot, y_dot, psi_dot]``."""
        b = self._b
        if not b._all_started:
            raise RuntimeError(f"{self.name}: call reset(t0, eta0) before estimate()")
        eta, nu, P, P_nu = b._readouts()
        return Estimate(
            t=float(b._t[0]),
            eta=eta[0].copy(),
            nu=nu[0].copy(),
            P=P[0].copy(),
            P_eta=P[0, :3, :3].copy(),
            P_nu=P_nu[0].copy(),
        )

    # ---- extras ------------------------------------------------------------------------------
    @property
    def x(self) -> NDArray[np.float64]:
        """A copy of the state ``[x, y, psi, x_dot, y_dot, psi_dot]`` (NED, heading continuous)."""
        return self._b.x[0]

    @property
    def P(self) -> NDArray[np.float64]:
        """A copy of the (6, 6) covariance of :attr:`x`."""
        return self._b._readouts()[2][0].copy()

    @property
    def t(self) -> float | None:
        """Time of the current estimate (s), ``None`` before :meth:`reset`."""
        return float(self._b._t[0]) if self._b._all_started else None

    @property
    def steady_state_gain(self) -> NDArray[np.float64]:
        """Steady-state gain at the design period ``T``, (3, 2), seed order ``[velocity,
        position]`` per DOF: the DKF's filter form (Tomera 2014 eq. 30), the KBF's ``L = P C^T
        R_c^-1`` (Tomera 2014 eq. 35)."""
        return self._b._steady_gain(self.design.R).copy()


class DiscreteKalmanFilter(_DoubleIntegratorFilter):
    """Discrete Kalman filter per DOF on the double integrator (Tomera 2014 Table 3).

    Args:
        design: :class:`~shipgym.observers.design.KalmanDesign` (or a mapping of its fields);
            default the Blue Lady's tuned :data:`~shipgym.observers.design.DKF_DESIGN` (for
            another vessel: ``make_observer("dkf", vessel)``).
        constant_gain: use the steady-state filter-form gain of
            :func:`~shipgym.observers.design.dlqe` at the design period ``T`` (Tomera 2014
            eq. 30) instead of the time-varying gain of Table 3.
        name: the observer's name.
        gate_probability: NIS gate probability (``None``: no gate), see
            :class:`~shipgym.observers.base.OutlierGate`.
        max_rejections: most measurements rejected in a row.
        initial_velocity_std: default initial std of ``[x_dot, y_dot, psi_dot]``
            (m/s, m/s, rad/s).
    """

    def __init__(
        self,
        design: KalmanDesign | Mapping[str, Any] = DKF_DESIGN,
        *,
        constant_gain: bool = False,
        name: str = "dkf",
        gate_probability: float | None = 0.9999,
        max_rejections: int = 5,
        initial_velocity_std: ArrayLike = DEFAULT_INITIAL_VELOCITY_STD,
    ) -> None:
        super().__init__(
            design,
            name=name,
            constant_gain=bool(constant_gain),
            gate_probability=gate_probability,
            max_rejections=max_rejections,
            initial_velocity_std=initial_velocity_std,
        )
        self.constant_gain = bool(constant_gain)

    @property
    def last_gain(self) -> NDArray[np.float64]:
        """Gain of the last update, (3, 2), seed order ``[velocity, position]`` per DOF: the
        constant gain, or the time-varying one from the updated covariance, ``K = P^+ H^T R^-1``
        (equal to ``P^- H^T S^-1`` to round-off)."""
        b = self._b
        if self.constant_gain:
            return b._gain[:, :, 0].T.copy()
        return (b._X[3:5, :, 0] / b._R[:, 0]).T.copy()


class KalmanBucyFilter(_DoubleIntegratorFilter):
    """Continuous Kalman-Bucy filter per DOF, sampled-data implementation (Tomera 2014 Table 4).

    Args:
        design: :class:`~shipgym.observers.design.KalmanDesign` (or a mapping of its fields);
            the continuous measurement intensity is ``R_c = R T``; default the Blue Lady's
            tuned :data:`~shipgym.observers.design.KBF_DESIGN` (for another vessel:
            ``make_observer("kbf", vessel)``).
        steady_state: use the constant gain of :func:`~shipgym.observers.design.lqe`
            (Tomera 2014 eqs. 33-35) instead of integrating the Riccati ODE.
        name: the observer's name.
        gate_probability: NIS gate probability (``None``: no gate).
        max_rejections: most measurements rejected in a row.
        initial_velocity_std: default initial std of ``[x_dot, y_dot, psi_dot]``
            (m/s, m/s, rad/s).
    """

    _continuous = True

    def __init__(
        self,
        design: KalmanDesign | Mapping[str, Any] = KBF_DESIGN,
        *,
        steady_state: bool = False,
        name: str = "kbf",
        gate_probability: float | None = 0.9999,
        max_rejections: int = 5,
        initial_velocity_std: ArrayLike = DEFAULT_INITIAL_VELOCITY_STD,
    ) -> None:
        super().__init__(
            design,
            name=name,
            constant_gain=bool(steady_state),
            gate_probability=gate_probability,
            max_rejections=max_rejections,
            initial_velocity_std=initial_velocity_std,
        )
        self.steady_state = bool(steady_state)


# --------------------------------------------------------------------------------------------
# Presets and registry
# --------------------------------------------------------------------------------------------

_DESIGN_KEYS = tuple(f.name for f in dataclasses.fields(KalmanDesign) if f.name != "model")


def _factory(
    cls: type[_DoubleIntegratorFilter], design: KalmanDesign, name: str, **fixed: Any
) -> Callable[..., Observer]:
    ctor_keys = ("gate_probability", "max_rejections", "initial_velocity_std") + tuple(fixed)

    def make(**overrides: Any) -> Observer:
        design_changes = {k: overrides.pop(k) for k in list(overrides) if k in _DESIGN_KEYS}
        pv = overrides.pop("position_variance", None)
        hv = overrides.pop("heading_variance", None)
        if pv is not None or hv is not None:
            R = list(design_changes.get("R", design.R))
            if len(R) != 3:
                R = [float(R[0])] * 3
            if pv is not None:
                R[0] = R[1] = float(pv)
            if hv is not None:
                R[2] = float(hv)
            design_changes["R"] = tuple(R)
        unknown = sorted(set(overrides) - set(ctor_keys))
        if unknown:
            valid = sorted(
                set(_DESIGN_KEYS) | set(ctor_keys) | {"position_variance", "heading_variance"}
            )
            raise ValueError(
                f"unknown option(s) {unknown} for observer {name!r}; valid: {', '.join(valid)}"
            )
        kwargs = {"name": name, **fixed, **overrides}
        d = dataclasses.replace(design, **design_changes) if design_changes else design
        return cls(d, **kwargs)

    make.__doc__ = f"A new {cls.__name__} preset {name!r} (keyword overrides, see module doc)."
    return make


register_observer(
    "tomera-dkf", _factory(DiscreteKalmanFilter, TOMERA_DKF, "tomera-dkf", constant_gain=True)
)
register_observer(
    "tomera-kbf", _factory(KalmanBucyFilter, TOMERA_KBF, "tomera-kbf", steady_state=True)
)


def vessel_noise(vessel: Any) -> dict[str, Any]:
    """The tuned presets' white-noise acceleration intensities for a vessel (its
    ``[observer]`` values ``accel_psd_xy`` m^2/s^3, ``accel_psd_psi`` rad^2/s^3)."""
    q_xy = float(vessel.observer["accel_psd_xy"])
    q_psi = float(vessel.observer["accel_psd_psi"])
    return {"Q": (((q_xy,),), ((q_xy,),), ((q_psi,),))}


register_observer(
    "dkf", _factory(DiscreteKalmanFilter, DKF_DESIGN, "dkf", constant_gain=False), vessel_noise
)
register_observer(
    "kbf", _factory(KalmanBucyFilter, KBF_DESIGN, "kbf", steady_state=False), vessel_noise
)
