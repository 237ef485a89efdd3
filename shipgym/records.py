"""Typed records of a step: env (physics, observer, DP controller) -> wrappers -> recorder.

Public names: ``POSE_3DOF``, ``VELOCITY_3DOF``, ``ActuatorData``, ``ControlData``, ``LazyInfo``,
``Measurement``, ``NavigationData``, ``StepRecord``, ``step_record``, ...

Design notes: docs/design/records.md.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shipgym.guidance import Reference

__all__ = [
    "POSE_3DOF",
    "VELOCITY_3DOF",
    "ActuatorData",
    "ControlData",
    "LazyInfo",
    "Measurement",
    "NavigationData",
    "StepRecord",
    "step_record",
    "step_record_of_env",
]

#: component names of a surge-sway-yaw pose (NED metres, radians) and body velocity
POSE_3DOF = ("x", "y", "psi")
VELOCITY_3DOF = ("u", "v", "r")

Array = NDArray[np.float64]


def _same(x: Any, y: Any) -> bool:
    """Exact equality of record fields (arrays element-wise, NaN equal to NaN)."""
    if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
        a, b = np.asarray(x), np.asarray(y)
        nan = a.dtype.kind in "fc" and b.dtype.kind in "fc"
        return a.shape == b.shape and bool(np.array_equal(a, b, equal_nan=nan))
    if isinstance(x, tuple) and isinstance(y, tuple):
        return len(x) == len(y) and all(_same(p, q) for p, q in zip(x, y, strict=True))
    if dataclasses.is_dataclass(x) and not isinstance(x, type):  # e.g. a guidance Reference
        return type(x) is type(y) and all(
            _same(getattr(x, f.name), getattr(y, f.name)) for f in dataclasses.fields(x)
        )
    return bool(x == y)


def _equal(self: Any, other: Any) -> Any:
    """``==`` of two records: same type and every field equal (:func:`_same`)."""
    if type(other) is not type(self):
        return NotImplemented
    return all(
        _same(getattr(self, f.name), getattr(other, f.name)) for f in dataclasses.fields(self)
    )


@dataclass(slots=True, eq=False)
class NavigationData:
    """Pose and velocity at one instant: the true state, or an observer's estimate of it.

    Attributes:
        t: time (s).
        eta: NED pose, components named by ``pose_names`` (m, rad; ``x, y, psi`` today).
        nu: body velocity, components named by ``velocity_names`` (m/s, rad/s).
        P_eta: error covariance of ``eta`` (``None``: the truth, or not given).
        P_nu: error covariance of ``nu`` (``None``: the truth, or not meaningful).
        source: ``"truth"`` or the observer's name.
        pose_names, velocity_names: the component names.
    """

    __eq__ = _equal
    __hash__ = None  # type: ignore[assignment]  # mutable arrays inside

    t: float
    eta: Array
    nu: Array
    P_eta: Array | None = None
    P_nu: Array | None = None
    source: str = "truth"
    pose_names: tuple[str, ...] = POSE_3DOF
    velocity_names: tuple[str, ...] = VELOCITY_3DOF

    @property
    def is_truth(self) -> bool:
        """Whether this is the true state (no observer)."""
        return self.source == "truth"


@dataclass(slots=True, eq=False)
class ActuatorData:
    """Commands and forces of the vessel's actuators.

    The command vectors have one entry per control channel (``channels``: a MuJoCo actuator;
    an azimuth thruster has two, its thrust and its turning rate), the thrust one entry per
    actuator (``names``); for a set of single-channel thrusters (the Blue Lady) both are the
    same.

    Attributes:
        names: the actuators' names (the vessel's actuator set).
        action: the normalised action applied, in [-1, 1] (after clipping), per channel.
        command: the commands applied, in each channel's own unit (rpm, fraction of full
            thrust, rad/s, ...).
        thrust: the thrust each actuator delivers (N), per actuator.
        saturated: whether each command sat at a limit, or its normalised action was clipped.
        action_clipped: whether each normalised action was changed before it was applied:
            outside [-1, 1] and clipped, or (``condition_commands``) a propeller command held
            at its idle by the reversal hysteresis.
        channels: the channel names, in the order of ``action`` (``names`` when empty).
        state: the actuator states (lagged commands; an azimuth's angle in rad), per
            channel, or ``None``.
    """

    __eq__ = _equal
    __hash__ = None  # type: ignore[assignment]  # mutable arrays inside

    names: tuple[str, ...]
    action: Array
    command: Array
    thrust: Array
    saturated: NDArray[np.bool_]
    action_clipped: NDArray[np.bool_]
    channels: tuple[str, ...] = ()
    state: Array | None = None

    def __post_init__(self) -> None:
        n = len(self.names)
        m = len(self.channels) if self.channels else n
        a, c, f, s, k = self.action, self.command, self.thrust, self.saturated, self.action_clipped
        if not (len(a) == len(c) == len(s) == len(k) == m and len(f) == n):  # kept cheap
            raise ValueError(
                f"ActuatorData: action, command, saturated and action_clipped must have one "
                f"entry per channel ({m}: {', '.join(self.channels or self.names)}) and thrust "
                f"one per actuator ({n}: {', '.join(self.names)}), got lengths "
                f"{len(a)}, {len(c)}, {len(s)}, {len(k)} and {len(f)}"
            )


@dataclass(slots=True, eq=False)
class Measurement:
    """One position-reference sample (DGPS and gyrocompass) with the thrust applied then.

    Attributes:
        t: sample time (s).
        z: measured NED pose, or ``None`` in a dropout.
        valid: whether the receiver flagged the sample valid.
        outlier: whether the sample is an injected outlier.
        tau: the actuators' generalised force at the sample (body frame, N and N m) as the DP
            system computes it from the actuator states with its thrust model (the bollard
            laws: :attr:`VesselPhysics.tau_model <shipgym.envs.physics.VesselPhysics.tau_model>`;
            the plant's advance-speed and tunnel losses are not in it).
        tau_command: the generalised force ``[X, Y, N]`` (N, N, N m, body) that the commands
            held over the interval ending at the sample would give in steady state, at the
            actuators' current angles: the demand a model-based filter with its own thruster
            lags takes as input (Al-Takie 1982 eq. 3.21 ``u``); ``None`` where not reported.
    """

    __eq__ = _equal
    __hash__ = None  # type: ignore[assignment]  # mutable arrays inside

    t: float
    z: Array | None
    valid: bool
    outlier: bool
    tau: Array
    tau_command: Array | None = None

    @classmethod
    def from_mapping(cls, m: Mapping[str, Any]) -> Measurement:
        """From the form of ``info["measurements"]`` (``t``, ``z``, ``valid``, ``outlier``,
        ``tau`` and, when present, ``tau_command``)."""
        return cls(
            float(m["t"]),
            m["z"],
            bool(m["valid"]),
            bool(m["outlier"]),
            m["tau"],
            m.get("tau_command"),
        )


@dataclass(slots=True, eq=False)
class ControlData:
    """What the env's DP controller computed for the step.

    Attributes:
        controller: the controller's name.
        tau_c: the controller's generalised force demand (body frame).
        tau_delivered: what the allocation delivers of it.
        tau_error: ``tau_c - tau_delivered``.
        action: the controller's normalised action, one entry per actuator.
        allocation_saturated: per actuator, whether the allocation hit a limit.
        residual_clipped: per actuator, whether controller + residual action was clipped.
        tau_ff: the feedforward part of ``tau_c`` (N, N, N m; minus the wind and current loads
            it estimates, :mod:`shipgym.controllers.feedforward`; zeros without one).
    """

    __eq__ = _equal
    __hash__ = None  # type: ignore[assignment]  # mutable arrays inside

    controller: str
    tau_c: Array
    tau_delivered: Array
    tau_error: Array
    action: Array
    allocation_saturated: NDArray[np.bool_]
    residual_clipped: NDArray[np.bool_]
    tau_ff: Array


@dataclass(slots=True, eq=False)
class StepRecord:
    """Everything one control step produced, as typed fields (``info["record"]``).

    Attributes:
        truth: the true state.
        nav: what a controller uses: the truth, or an observer's estimate
            (:meth:`with_nav`).
        eta_r: the true pose in the r-frame of the current leg.
        reference: the guidance reference (:class:`shipgym.guidance.Reference`: desired pose
            and its derivatives in the r-frame, ``eta_d_n``, ``eta_P``, ``leg``, ...).
        legs_completed: legs completed so far.
        actuators: commands and thrust per actuator.
        tau_wind, tau_waves: the wind and (second-order) wave loads (body frame).
        current_body: the current's velocity in the body frame (the ``nu`` layout).
        measurements: the sensor samples taken during the step (oldest first).
        quay_contact: whether the hull has touched a quay in this episode.
        control: the DP controller's part (``None`` without a controller).
        estimation_rmse: the observer's estimation RMSE over the episode, on its last step
            (``None`` otherwise, and without an observer).
    """

    __eq__ = _equal
    __hash__ = None  # type: ignore[assignment]  # mutable arrays inside

    truth: NavigationData
    nav: NavigationData
    eta_r: Array
    reference: Reference
    legs_completed: int
    actuators: ActuatorData
    tau_wind: Array
    tau_waves: Array
    current_body: Array
    measurements: tuple[Measurement, ...]
    quay_contact: bool
    control: ControlData | None = None
    estimation_rmse: Mapping[str, float] | None = None

    @property
    def t(self) -> float:
        """Simulation time (s)."""
        return self.truth.t

    def with_nav(
        self, nav: NavigationData, estimation_rmse: Mapping[str, float] | None = None
    ) -> StepRecord:
        """This record with an observer's navigation data (and its RMSE at the episode end)."""
        return self._with(nav, self.control, estimation_rmse)

    def with_control(self, control: ControlData) -> StepRecord:
        """This record with a DP controller's part."""
        return self._with(self.nav, control, self.estimation_rmse)

    def _with(
        self,
        nav: NavigationData,
        control: ControlData | None,
        estimation_rmse: Mapping[str, float] | None,
    ) -> StepRecord:
        # the constructor, not dataclasses.replace: this runs on every step (hot path)
        return StepRecord(
            self.truth,
            nav,
            self.eta_r,
            self.reference,
            self.legs_completed,
            self.actuators,
            self.tau_wind,
            self.tau_waves,
            self.current_body,
            self.measurements,
            self.quay_contact,
            control,
            estimation_rmse,
        )


def step_record(info: Mapping[str, Any]) -> StepRecord:
    """The :class:`StepRecord` of an ``info`` dict.

    Raises:
        ValueError: ``info`` has no record (not from a shipgym environment).
    """
    rec = info.get("record")
    if not isinstance(rec, StepRecord):
        raise ValueError(
            "info has no shipgym StepRecord under 'record': the environment below is not a "
            "shipgym environment (or a wrapper dropped the key)"
        )
    return rec


def step_record_of_env(
    info: Mapping[str, Any],
    reference: Reference,
    action: Array,
    actuator_names: tuple[str, ...],
    channel_names: tuple[str, ...] = (),
) -> StepRecord:
    """The record an environment attaches to its ``info`` (same arrays, no copies).

    Args:
        info: the environment's own ``info`` of the step (its keys ``t``, ``eta``, ``nu``,
            ``eta_r``, ``legs_completed``, ``command``, ``thrust``, ``saturated``,
            ``action_clipped``, ``tau_wind``, ``tau_waves``, ``current_body``,
            ``measurements``, ``quay_contact``).
        reference: the guidance reference the step's info was made from.
        action: the normalised action applied (zeros after a reset).
        actuator_names: the names of the vessel's actuators, in the order of ``thrust``.
        channel_names: the names of its control channels, in the order of the commands
            (empty: one channel per actuator).
    """
    truth = NavigationData(info["t"], info["eta"], info["nu"])
    ms = info["measurements"]
    # positional arguments and no conversions: this runs on every step (hot path)
    return StepRecord(
        truth,
        truth,
        info["eta_r"],
        reference,
        info["legs_completed"],
        ActuatorData(
            actuator_names,
            action,
            info["command"],
            info["thrust"],
            info["saturated"],
            info["action_clipped"],
            channel_names,
            info.get("actuator_state"),
        ),
        info["tau_wind"],
        info["tau_waves"],
        info["current_body"],
        tuple(
            [
                Measurement(
                    m["t"], m["z"], m["valid"], m["outlier"], m["tau"], m.get("tau_command")
                )
                for m in ms
            ]
        )
        if ms
        else (),
        info["quay_contact"],
    )


class LazyInfo(dict):  # type: ignore[type-arg]
    """A step's ``info``: a ``dict`` whose values are made when one is first read.

    The single env's ``info`` (truth, references, loads, measurements, the typed ``record``)
    costs more than the step's physics. The env reads the state it needs at the step (small
    copies) and makes the dict from them on the first read, so a loop that never reads
    ``info`` (training) does not pay for it, and a read at any later time gives the values of
    the step that returned it.

    It is the dict it would be: its keys are known at once (``in``, ``len`` and ``get`` of a
    key it does not hold make nothing), a key written before the first read keeps the written
    value, and ``copy()``, ``copy.copy``, pickling and ``dict(info)`` give a plain ``dict``.

    Args:
        keys: the keys ``make`` returns.
        make: the function that makes the values, in their order (called once).
    """

    __slots__ = ("_keys", "_make")

    def __init__(self, keys: frozenset[str], make: Callable[[], dict[str, Any]]) -> None:
        super().__init__()
        self._keys = keys
        self._make: Callable[[], dict[str, Any]] | None = make

    def _fill(self) -> None:
        """Make the values (the keys written since stay as written)."""
        make = self._make
        if make is None:
            return
        made = make()  # (an error here leaves it unmade: a read again raises it again)
        if made.keys() != self._keys:  # a bug of the env: its keys said something else
            raise RuntimeError(f"LazyInfo made the keys {sorted(made)}, not {sorted(self._keys)}")
        self._make = None
        written = dict.copy(self)
        dict.clear(self)
        dict.update(self, made)
        dict.update(self, written)

    # ---- reads that need no values --------------------------------------------------------
    def __contains__(self, key: object) -> bool:
        return dict.__contains__(self, key) or (self._make is not None and key in self._keys)

    def __len__(self) -> int:
        if self._make is None:
            return dict.__len__(self)
        return len(self._keys) + sum(1 for k in dict.__iter__(self) if k not in self._keys)

    def get(self, key: Any, default: Any = None) -> Any:
        if self._make is not None and key in self._keys:
            self._fill()
        return dict.get(self, key, default)

    # ---- everything else reads the values -------------------------------------------------
    def __getitem__(self, key: Any) -> Any:
        if self._make is not None and key in self._keys:
            self._fill()
        return dict.__getitem__(self, key)

    def __iter__(self) -> Iterator[Any]:
        self._fill()
        return dict.__iter__(self)

    def __reversed__(self) -> Iterator[Any]:
        self._fill()
        return dict.__reversed__(self)

    def keys(self) -> Any:
        self._fill()
        return dict.keys(self)

    def values(self) -> Any:
        self._fill()
        return dict.values(self)

    def items(self) -> Any:
        self._fill()
        return dict.items(self)

    def __repr__(self) -> str:
        self._fill()
        return dict.__repr__(self)

    def __eq__(self, other: object) -> bool:
        self._fill()
        if isinstance(other, LazyInfo):
            other._fill()
        return dict.__eq__(self, other)

    def __ne__(self, other: object) -> bool:
        return not self == other

    __hash__ = None  # type: ignore[assignment]

    def __or__(self, other: Any) -> Any:
        self._fill()
        return dict.__or__(self, other)

    def __ror__(self, other: Any) -> Any:
        self._fill()
        return dict.__ror__(self, other)

    def copy(self) -> dict[str, Any]:
        self._fill()
        return dict.copy(self)

    def __copy__(self) -> dict[str, Any]:
        return self.copy()

    def __deepcopy__(self, memo: dict[int, Any]) -> dict[str, Any]:
        return copy.deepcopy(self.copy(), memo)

    def __reduce__(self) -> Any:
        return dict, (self.copy(),)

    def pop(self, key: Any, *default: Any) -> Any:
        self._fill()
        return dict.pop(self, key, *default)

    def popitem(self) -> Any:
        self._fill()
        return dict.popitem(self)

    def setdefault(self, key: Any, default: Any = None) -> Any:
        self._fill()
        return dict.setdefault(self, key, default)

    def __delitem__(self, key: Any) -> None:
        self._fill()
        dict.__delitem__(self, key)

    def clear(self) -> None:
        self._make = None
        dict.clear(self)

    @classmethod
    def fromkeys(cls, keys: Any, value: Any = None) -> dict[Any, Any]:  # type: ignore[override]
        return dict.fromkeys(keys, value)
