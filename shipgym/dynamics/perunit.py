r"""The per-unit ("bis", prime-II) system of Al-Takie (1982): bases from ``m``, ``L_pp`` and ``g``.

Public names: ``KINDS``, ``PerUnit``.
Sources: Al-Takie (1982); Fossen (2011).

Design notes: docs/design/dynamics.perunit.md.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import param, require_dimensions

__all__ = ["KINDS", "PerUnit"]

#: gravity of the per-unit bases (m/s^2): reproduces the printed bases of Al-Takie (1982) App. 1
G_PER_UNIT = 9.81

#: quantity kinds and the power of ``(m, L, g)`` of their base (``m^a L^b g^c``)
KINDS: dict[str, tuple[float, float, float]] = {
    "time": (0.0, 0.5, -0.5),
    "length": (0.0, 1.0, 0.0),
    "angle": (0.0, 0.0, 0.0),
    "velocity": (0.0, 0.5, 0.5),
    "angular_velocity": (0.0, -0.5, 0.5),
    "acceleration": (0.0, 0.0, 1.0),
    "angular_acceleration": (0.0, -1.0, 1.0),
    "force": (1.0, 0.0, 1.0),
    "moment": (1.0, 1.0, 1.0),
    "mass": (1.0, 0.0, 0.0),
    "inertia": (1.0, 2.0, 0.0),
    "frequency": (0.0, -0.5, 0.5),
    # force per unit velocity (X_u, Y_v: N s/m), moment per angular velocity (N_r: N m s),
    # force per angular velocity / moment per velocity (Y_r, N_v: N s)
    "damping": (1.0, -0.5, 0.5),
    "rot_damping": (1.0, 1.5, 0.5),
    "cross_damping": (1.0, 0.5, 0.5),
}


@dataclass(frozen=True)
class PerUnit:
    """Per-unit bases of one ship (Al-Takie 1982 App. 1; Fossen 2011 ch. 7.2.1, bis system).

    Attributes:
        m: Mass (kg).
        L: Length between perpendiculars ``L_pp`` (m).
        g: Gravity (m/s^2).

    Example:
        >>> pu = PerUnit(5.670e6, 94.49)
        >>> round(pu.time, 3), round(pu.force / 1e3)   # s, kN
        (3.104, 55623)
        >>> pu.to_si(0.02, "length")                    # the thesis's 0.02 p.u. step (m)
        1.8898
    """

    m: float = param(None, "kg", "the ship's mass")
    L: float = param(None, "m", "the ship's length between perpendiculars")
    g: float = param(G_PER_UNIT, "m/s^2", "reproduces Al-Takie (1982) App. 1 to 4 digits")

    def __post_init__(self) -> None:
        for key in ("m", "L", "g"):
            val = getattr(self, key)
            if isinstance(val, bool) or not isinstance(val, int | float) or not val > 0:
                raise ValueError(f"PerUnit.{key} must be a number > 0, got {val!r}")
            if not math.isfinite(val):
                raise ValueError(f"PerUnit.{key} must be finite, got {val!r}")
            object.__setattr__(self, key, float(val))
        require_dimensions(self, "L")

    @classmethod
    def of_vessel(cls, vessel: Any) -> PerUnit:
        """The bases of a :class:`~shipgym.dynamics.vessel.Vessel` (its hull ``m`` and ``L_pp``)."""
        hull = vessel.hull
        return cls(float(hull.m), float(hull.L_pp))

    # ---- bases ---------------------------------------------------------------------------
    def base(self, kind: str) -> float:
        """The SI value of one per-unit of ``kind`` (a key of :data:`KINDS`)."""
        try:
            a, b, c = KINDS[kind]
        except KeyError:
            raise ValueError(
                f"unknown per-unit kind {kind!r}; choose one of: {', '.join(KINDS)}"
            ) from None
        return float(self.m**a * self.L**b * self.g**c)

    @property
    def time(self) -> float:
        """Time base ``T_b = sqrt(L/g)`` (s)."""
        return self.base("time")

    @property
    def velocity(self) -> float:
        """Velocity base ``sqrt(g L)`` (m/s)."""
        return self.base("velocity")

    @property
    def angular_velocity(self) -> float:
        """Angular-velocity base ``sqrt(g/L)`` (rad/s)."""
        return self.base("angular_velocity")

    @property
    def force(self) -> float:
        """Force base ``m g`` (N)."""
        return self.base("force")

    @property
    def moment(self) -> float:
        """Moment base ``m g L`` (N m)."""
        return self.base("moment")

    # ---- conversions ---------------------------------------------------------------------
    def to_si(self, value: ArrayLike, kind: str | Sequence[str]) -> Any:
        """Per-unit ``value`` in SI; ``kind`` one kind or one per last-axis entry."""
        return _scaled(value, self._bases(kind), multiply=True)

    def from_si(self, value: ArrayLike, kind: str | Sequence[str]) -> Any:
        """SI ``value`` in per-unit; ``kind`` one kind or one per last-axis entry."""
        return _scaled(value, self._bases(kind), multiply=False)

    def model_to_si(
        self,
        A: ArrayLike,
        B: ArrayLike,
        states: Sequence[str],
        inputs: Sequence[str],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """A per-unit-time model ``dx'/dt' = A x' + B u'`` as the SI real-time ``(A_si, B_si)``.

        ``x = S x'``, ``u = U u'``, ``t = T_b t'`` with ``S``, ``U`` the diagonal bases of
        ``states`` and ``inputs``: ``A_si = S A S^-1 / T_b``, ``B_si = S B U^-1 / T_b``.
        """
        S = np.diag(self._bases(states))
        U = np.diag(self._bases(inputs))
        A_ = np.asarray(A, dtype=float)
        B_ = np.asarray(B, dtype=float)
        Tb = self.time
        return S @ A_ @ np.linalg.inv(S) / Tb, S @ B_ @ np.linalg.inv(U) / Tb

    def model_from_si(
        self,
        A: ArrayLike,
        B: ArrayLike,
        states: Sequence[str],
        inputs: Sequence[str],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The inverse of :meth:`model_to_si`: SI real time to per-unit time."""
        S = np.diag(self._bases(states))
        U = np.diag(self._bases(inputs))
        A_ = np.asarray(A, dtype=float)
        B_ = np.asarray(B, dtype=float)
        Tb = self.time
        return np.linalg.inv(S) @ A_ @ S * Tb, np.linalg.inv(S) @ B_ @ U * Tb

    def _bases(self, kind: str | Sequence[str]) -> Any:
        if isinstance(kind, str):
            return self.base(kind)
        return np.array([self.base(k) for k in kind])


def _scaled(value: ArrayLike, bases: Any, *, multiply: bool) -> Any:
    v = np.asarray(value, dtype=float)
    out = v * bases if multiply else v / bases
    return float(out) if np.ndim(out) == 0 else out
