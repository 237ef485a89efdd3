"""Thruster models of the Blue Lady DP system (Tomera 2014 eqs. 8-12, 24-27).

Three actuators are used, in this order everywhere (commands, states, forces):

0. main propeller: shaft speed ``n1`` (rpm), thrust ``F1 = k1 |n1| n1``;
1. bow tunnel thruster: relative revolutions ``p2`` in [-1, 1], ``F2 = k2 p2``;
2. stern tunnel thruster: ``p3`` in [-1, 1], ``F3 = k3 p3``.

``tau = T u`` with ``T = [[1, 0, 0], [0, 1, 1], [0, L2, -L3]]`` (eq. 12). Each actuator
state follows its command through a first-order lag (time constant ``T_main``, ``T_tunnel``).
All functions accept a leading batch axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import require_finite, require_positive, required_param

__all__ = [
    "ThrusterParameters",
    "BLUE_LADY_THRUSTERS",
    "ACTUATOR_NAMES",
    "configuration_matrix",
    "thrust",
    "thrust_to_tau",
    "command_to_tau",
    "inverse_thrust",
    "saturate",
    "validate_command",
]

ACTUATOR_NAMES = ("main_propeller", "bow_tunnel", "stern_tunnel")


@dataclass(frozen=True)
class ThrusterParameters:
    """Constants, lever arms, ranges and lags of the three-thruster pattern of Tomera (2014).

    Every field must be given (no vessel is a default): the Blue Lady's values are
    :data:`BLUE_LADY_THRUSTERS`; any vessel of this pattern gives its own through
    :func:`shipgym.controllers.actuation.fixed3_parameters`.
    """

    k1: float = required_param("N/rpm^2", "main propeller thrust constant, F1 = k1 |n1| n1")
    k2: float = required_param("N", "bow tunnel thrust constant, F2 = k2 p2")
    k3: float = required_param("N", "stern tunnel thrust constant, F3 = k3 p3")
    L2: float = required_param("m", "bow tunnel forward of the CG")
    L3: float = required_param("m", "stern tunnel aft of the CG")
    x_main: float = required_param("m", "main propeller position (drawing only; no moment)")
    n_min: float = required_param("rpm", "main propeller lowest shaft speed (astern)")
    n_max: float = required_param("rpm", "main propeller highest shaft speed (ahead)")
    p_min: float = required_param("1", "tunnel thrusters lowest relative revolutions")
    p_max: float = required_param("1", "tunnel thrusters highest relative revolutions")
    T_main: float = required_param("s", "main propeller first-order lag")
    T_tunnel: float = required_param("s", "tunnel thrusters first-order lag")

    def __post_init__(self) -> None:
        require_finite(self)
        require_positive(self, "k1", "k2", "k3", "L2", "L3", "T_main", "T_tunnel")
        if not (self.n_min < 0 < self.n_max and self.p_min < 0 < self.p_max):
            raise ValueError(
                "thruster ranges must contain zero: n_min < 0 < n_max, p_min < 0 < p_max"
            )

    @property
    def lower(self) -> NDArray[np.float64]:
        """Lower command limits ``[n_min (rpm), p_min, p_min]``."""
        return np.array([self.n_min, self.p_min, self.p_min])

    @property
    def upper(self) -> NDArray[np.float64]:
        """Upper command limits ``[n_max (rpm), p_max, p_max]``."""
        return np.array([self.n_max, self.p_max, self.p_max])

    @property
    def time_constants(self) -> NDArray[np.float64]:
        """Lag time constants (s) of the three actuators."""
        return np.array([self.T_main, self.T_tunnel, self.T_tunnel])

    @property
    def force_lower(self) -> NDArray[np.float64]:
        """Smallest thrust of each actuator (N)."""
        return thrust(self.lower, self)

    @property
    def force_upper(self) -> NDArray[np.float64]:
        """Largest thrust of each actuator (N)."""
        return thrust(self.upper, self)


#: The Blue Lady's three thrusters (Tomera 2014 eqs. 8-12): unit and source in each comment.
BLUE_LADY_THRUSTERS = ThrusterParameters(
    # N/rpm^2; Tomera (2014) eq. 8 prints k1 = 1.9589 with n in rpm, i.e. 451 kN at 480 rpm:
    # impossible for a 23 t model; read as 1.9589e-3 N/rpm^2 (451 N ahead, 78 N astern)
    k1=1.9589e-3,
    k2=44.145,  # N; Tomera (2014) eq. 9 prints 44145: decimal comma lost
    k3=44.145,  # N; Tomera (2014) eq. 9 prints 44145: decimal comma lost
    L2=3.24,  # m; Tomera (2014) eq. 12: bow tunnel forward of CG
    L3=2.376,  # m; Tomera (2014) eq. 12: stern tunnel aft of CG
    x_main=-6.5,  # m; assumption: propeller near the stern (drawing only; no moment)
    n_min=-200.0,  # rpm; Tomera (2014): main propeller range
    n_max=480.0,  # rpm; Tomera (2014): main propeller range
    p_min=-1.0,  # 1; Tomera (2014) eq. 9: relative revolutions
    p_max=1.0,  # 1; Tomera (2014) eq. 9: relative revolutions
    T_main=2.0,  # s; assumption: electric drive, first-order lag on shaft speed
    T_tunnel=1.0,  # s; assumption: tunnel thruster first-order lag
)


def configuration_matrix(p: ThrusterParameters) -> NDArray[np.float64]:
    """Thrust configuration matrix ``T`` of Tomera (2014) eq. 12, (3, 3)."""
    return np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0], [0.0, p.L2, -p.L3]])


def thrust(state: ArrayLike, p: ThrusterParameters) -> NDArray[np.float64]:
    """Thrusts ``[F1, F2, F3]`` (N) from actuator states ``[n1 (rpm), p2, p3]`` (eqs. 8-9)."""
    s = np.asarray(state, dtype=float)
    return np.stack([p.k1 * np.abs(s[..., 0]) * s[..., 0], p.k2 * s[..., 1], p.k3 * s[..., 2]], -1)


def thrust_to_tau(forces: ArrayLike, p: ThrusterParameters) -> NDArray[np.float64]:
    """Body-frame ``tau = T u`` (N, N, N m) from thrusts (N), eq. 11."""
    return np.einsum("ij,...j->...i", configuration_matrix(p), np.asarray(forces, dtype=float))


def command_to_tau(state: ArrayLike, p: ThrusterParameters) -> NDArray[np.float64]:
    """Body-frame ``tau`` from actuator states: ``T @ thrust(state)``."""
    return thrust_to_tau(thrust(state, p), p)


def inverse_thrust(forces: ArrayLike, p: ThrusterParameters) -> NDArray[np.float64]:
    """Commands ``[n1 (rpm), p2, p3]`` that produce the thrusts (N), eqs. 26-27 (unsaturated)."""
    f = np.asarray(forces, dtype=float)
    n1 = np.sign(f[..., 0]) * np.sqrt(np.abs(f[..., 0]) / p.k1)
    return np.stack([n1, f[..., 1] / p.k2, f[..., 2] / p.k3], -1)


def validate_command(cmd: ArrayLike, shape: tuple[int, ...] = (3,)) -> NDArray[np.float64]:
    """Return ``cmd`` as a float array after checking shape and finiteness.

    Raises:
        ValueError: wrong shape, NaN or infinite entries (message names the entries).
    """
    a = np.asarray(cmd, dtype=float)
    if a.shape == (3,) and shape == (3,):  # fast path (every control step)
        x0, x1, x2 = a.tolist()
        if math.isfinite(x0 + x1 + x2) or (
            math.isfinite(x0) and math.isfinite(x1) and math.isfinite(x2)
        ):
            return a
    if a.shape[-len(shape) :] != shape:
        raise ValueError(
            f"thruster command must have shape {shape} ([n1 rpm, p2, p3]), got {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        bad = [ACTUATOR_NAMES[i % 3] for i in np.flatnonzero(~np.isfinite(a.reshape(-1, 3)).any(0))]
        raise ValueError(f"thruster command contains NaN or infinite values for {bad}: {a}")
    return a


def saturate(
    cmd: ArrayLike, p: ThrusterParameters
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Clip commands to the physical ranges; return ``(clipped, saturated_flags)``."""
    a = validate_command(cmd)
    clipped = np.clip(a, p.lower, p.upper)
    return clipped, clipped != a
