"""The observer interface shared by every state observer, and its registry.

Public names: ``OBSERVERS``, ``Estimate``, ``Observer``, ``OutlierGate``, ``StepInfo``,
``as_pose``, ``as_tau``, ``make_observer``, ...
Sources: Tomera (2014); Tomera (2011).

Design notes: docs/design/observers.base.md.
"""

from __future__ import annotations

import importlib
import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import chdtri

from shipgym._text import did_you_mean

__all__ = [
    "OBSERVERS",
    "Estimate",
    "Observer",
    "OutlierGate",
    "StepInfo",
    "as_pose",
    "as_tau",
    "make_observer",
    "no_measurement",
    "register_observer",
]


@dataclass(frozen=True)
class Estimate:
    """An observer's estimate at one instant (copies; never aliases the observer's state).

    Attributes:
        t: time of the estimate (s).
        eta: NED pose ``[x, y, psi]`` (m, m, rad), (3,); heading continuous (not wrapped).
        nu: body velocity ``[u, v, r]`` (m/s, m/s, rad/s), (3,): ``R^T(psi) eta_dot``
            (Tomera 2011 eq. 60).
        P: error covariance of the observer's full state (layout documented by each observer;
            the double-integrator filters use ``[x, y, psi, x_dot, y_dot, psi_dot]``).
        P_eta: covariance of ``eta`` (m^2, rad^2), (3, 3).
        P_nu: covariance of ``nu`` ((m/s)^2, (rad/s)^2), (3, 3), ``None`` where not meaningful.
        bias: estimated slowly varying bias force ``[b_X, b_Y, b_N]`` (N, N, N m) for observers
            that have one (EKF), else ``None``.
    """

    t: float
    eta: NDArray[np.float64]
    nu: NDArray[np.float64]
    P: NDArray[np.float64]
    P_eta: NDArray[np.float64]
    P_nu: NDArray[np.float64] | None
    bias: NDArray[np.float64] | None = None


@dataclass(frozen=True)
class StepInfo:
    """What one observer step did with its measurement.

    Attributes:
        innovation: ``z - H x_pred`` (m, m, rad; heading wrapped to ``(-pi, pi]``), (3,);
            NaN when no measurement was given.
        nis: normalised innovation squared ``innovation^T S^-1 innovation`` (-; chi-square
            with 3 dof for a consistent filter), ``None`` without a measurement.
        rejected: the measurement failed the NIS gate and was not used (the observer coasted).
        forced: the measurement failed the gate but was accepted because ``max_rejections``
            measurements in a row had been rejected already.
    """

    innovation: NDArray[np.float64]
    nis: float | None
    rejected: bool
    forced: bool = False


_NO_MEASUREMENT_INNOVATION = np.full(3, np.nan)
_NO_MEASUREMENT_INNOVATION.setflags(write=False)


def no_measurement() -> StepInfo:
    """The :class:`StepInfo` of a step without measurement (NaN innovation, no NIS)."""
    return StepInfo(_NO_MEASUREMENT_INNOVATION, None, False)


class Observer(ABC):
    """The interface of every observer: ``reset``, ``step``, ``estimate`` and a ``name``.

    ``step`` is called once per sample (1 s by default) and must be cheap.

    Attributes:
        name: the observer's name.
        thrust_input: which thrust the env hands to :meth:`step`: ``"applied"`` (default),
            the actuators' applied generalised force (:attr:`Measurement.tau
            <shipgym.records.Measurement.tau>`); ``"command"``, the steady-state force of the
            held commands (:attr:`Measurement.tau_command
            <shipgym.records.Measurement.tau_command>`), for filters that model the thruster
            lags themselves (Al-Takie 1982 eq. 3.21).
        model_based: the estimate comes from a model of the hull driven by the thrust (an
            EKF, a wave filter), not from the position fixes alone (a kinematic filter): its
            velocity is much less noisy, and the DP controller's velocity filter is chosen
            for it (the vessel's ``[control] velocity_filter_model_based``).
    """

    name: str = "observer"
    thrust_input: str = "applied"
    model_based: bool = False

    @abstractmethod
    def reset(
        self,
        t0: float,
        eta0: ArrayLike,
        *,
        nu0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
    ) -> None:
        """Start a new estimate at time ``t0``.

        Args:
            t0: initial time (s).
            eta0: initial pose ``[x, y, psi]`` (m, m, rad), usually the first measurement.
            nu0: initial body velocity ``[u, v, r]`` (m/s, m/s, rad/s); ``None`` = at rest,
                with the observer's default initial velocity uncertainty.
            P0: initial covariance of the observer's full state (its documented layout);
                ``None`` = the observer's default.
        """

    @abstractmethod
    def step(self, t: float, z: ArrayLike | None, tau: ArrayLike | None = None) -> StepInfo:
        """Propagate from the previous call's time to ``t``, then update with ``z``.

        Args:
            t: time now (s), not earlier than the previous call.
            z: measured NED pose ``[x, y, psi]`` (m, m, rad; heading in any branch), or
                ``None`` when there is no measurement (dropout: coast).
            tau: body thrust ``[X, Y, N]`` (N, N, N m) held since the previous call, for
                model-based observers; ``None`` = unknown/zero.

        Returns:
            :class:`StepInfo`: innovation, NIS and the outlier gate's decision.
        """

    @abstractmethod
    def estimate(self) -> Estimate:
        """The current :class:`Estimate`."""


# --------------------------------------------------------------------------------------------
# Shared helpers
# --------------------------------------------------------------------------------------------


def as_pose(
    z: ArrayLike, name: str = "z", what: str = "[x, y, psi] (m, m, rad)"
) -> NDArray[np.float64]:
    """``z`` as 3 finite floats (a pose ``[x, y, psi]`` by default), else ``ValueError``."""
    try:
        a = np.asarray(z, dtype=float)
    except (TypeError, ValueError):
        a = np.empty(0)
    if a.shape != (3,) or not np.isfinite(a).all():
        raise ValueError(
            f"{name} must be 3 finite values {what}"
            + (" or None for a missing sample" if name == "z" else "")
            + f", got {z!r}"
        )
    return a


def as_tau(tau: ArrayLike | None) -> NDArray[np.float64] | None:
    """``tau`` as 3 finite floats ``[X, Y, N]`` (N, N, N m) or ``None``, else ``ValueError``."""
    if tau is None:
        return None
    return as_pose(tau, "tau", "[X, Y, N] (N, N, N m)")


class OutlierGate:
    """Chi-square NIS gate that never rejects more than ``max_rejections`` in a row.

    Args:
        probability: gate probability (-), e.g. 0.9999; measurements with
            ``NIS > chi2.ppf(probability, dof)`` are rejected. ``None`` disables the gate.
        dof: number of measured components (3: x, y, psi).
        max_rejections: most measurements rejected in a row (>= 1); the next one is accepted
            ("forced") and the gate stays open until a measurement passes it.

    Attributes:
        threshold: the NIS threshold (-), ``inf`` when disabled.
    """

    def __init__(
        self, probability: float | None = 0.9999, *, dof: int = 3, max_rejections: int = 5
    ) -> None:
        if probability is None:
            self.threshold = math.inf
        else:
            p = float(probability)
            if not 0.0 < p < 1.0:
                raise ValueError(f"gate_probability must be in (0, 1) or None, got {probability!r}")
            self.threshold = float(chdtri(dof, 1.0 - p))
        if isinstance(max_rejections, bool) or int(max_rejections) != max_rejections:
            raise ValueError(f"max_rejections must be an integer >= 1, got {max_rejections!r}")
        if max_rejections < 1:
            raise ValueError(f"max_rejections must be >= 1, got {max_rejections!r}")
        self.probability = probability
        self.max_rejections = int(max_rejections)
        self.reset()

    def reset(self) -> None:
        """Forget the rejection history."""
        self._count = 0
        self._open = False

    def check(self, nis: float) -> Literal["accept", "reject", "force"]:
        """Decide on one measurement from its NIS."""
        if nis <= self.threshold:
            self._count = 0
            self._open = False
            return "accept"
        if self._open:
            return "force"
        if self._count >= self.max_rejections:
            self._count = 0
            self._open = True
            return "force"
        self._count += 1
        return "reject"


# --------------------------------------------------------------------------------------------
# Registry
# --------------------------------------------------------------------------------------------

OBSERVERS: dict[str, Callable[..., Observer]] = {}
"""Observer factories by name; ``factory(**overrides)`` returns a new observer."""

_BUILTIN_MODULES = (
    "shipgym.observers.kalman",
    "shipgym.observers.ekf",
    "shipgym.observers.wavefilter",
    "shipgym.observers.notch",
)


#: ``name -> adapt(vessel) -> overrides``: how a preset is fitted to a vessel (see
#: :func:`make_observer`); presets without one are used as registered
VESSEL_ADAPTERS: dict[str, Callable[[Any], dict[str, Any]]] = {}


def register_observer(
    name: str,
    factory: Callable[..., Observer],
    vessel_overrides: Callable[[Any], dict[str, Any]] | None = None,
) -> None:
    """Add (or replace) a named observer factory in :data:`OBSERVERS`.

    ``vessel_overrides(vessel)`` returns the factory arguments that fit the preset to a
    :class:`~shipgym.dynamics.vessel.Vessel` (:func:`make_observer` with ``vessel=``).
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"an observer name must be a non-empty string, got {name!r}")
    OBSERVERS[name] = factory
    if vessel_overrides is not None:
        VESSEL_ADAPTERS[name] = vessel_overrides
    else:
        VESSEL_ADAPTERS.pop(name, None)


def _load_builtins() -> None:
    for mod in _BUILTIN_MODULES:
        try:
            importlib.import_module(mod)
        except ModuleNotFoundError as exc:  # only a missing optional module, not its imports
            if exc.name != mod:
                raise


def make_observer(name: str, vessel: Any = None, **overrides: Any) -> Observer:
    """A new observer by registered name (``dkf``, ``kbf``, ``tomera-dkf``, ...).

    Args:
        name: a key of :data:`OBSERVERS`.
        vessel: the :class:`~shipgym.dynamics.vessel.Vessel` the observer is for, or ``None``
            (the preset as registered, i.e. designed for the Blue Lady). With a vessel, the
            preset's registered adapter fits it: the tuned kinematic filters (``dkf``,
            ``kbf``) take its white-noise acceleration intensities (``[observer]`` of the
            vessel file), the EKFs (``ekf``, ``tomera-ekf``) its design model ``M``, ``D_L``
            with the bias noise scaled by the squared ratio of its force capacity to the
            Blue Lady's.
        **overrides: passed to the factory (e.g. design fields, ``gate_probability``);
            they win over the vessel's values.

    Raises:
        ValueError: unknown name (the message lists the valid names) or bad overrides.
    """
    if name not in OBSERVERS:
        _load_builtins()
    try:
        factory = OBSERVERS[name]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown observer {name!r}{did_you_mean(name, OBSERVERS)}; valid names are: "
            f"{', '.join(sorted(OBSERVERS))}"
        ) from None
    if vessel is not None and name in VESSEL_ADAPTERS:
        overrides = {**VESSEL_ADAPTERS[name](vessel), **overrides}
    return factory(**overrides)
