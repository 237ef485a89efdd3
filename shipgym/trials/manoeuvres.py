r"""The IMO manoeuvres of a sea trial as scripts (IMO MSC.137(76) (2002); Artyszuk 2003 §3).

Public names: ``MANOEUVRES``, ``InitialTurning``, ``Scripts`` (the scripts of N envs as one
law), ``Stop``, ``TurningCircle``, ``ZigZag``, ``manoeuvre``, ...

The half-ahead 65 deg turn (``turning65_half_ahead``, Artyszuk 2003 Figs. 2-3: "turning test
data at half ahead speed and 65 deg rudder (of Schilling type)") is flown with the Schilling
rudder option (:data:`shipgym.dynamics.mmg.RUDDER_OPTIONS`) from the steady speed of the
half-ahead shaft command :data:`HALF_AHEAD`. The seed prints neither the ship's half-ahead
setting nor its speed; 0.85 of the full-ahead command is [chosen] (a controllable-pitch
propeller's half-ahead pitch at a constant shaft speed), the value at which this hull's turn
shows the seed's "order 0.5 m/s and 10 deg" receiver bias: the bias grows with the approach
speed of the turn (0.15 m/s and 5.0 deg at 0.5 n0, 0.47 m/s and 8.9 deg at 0.85 n0, 0.65 m/s
and 10.8 deg at n0; docs/papers/artyszuk-2003.md).

Design notes: docs/design/trials.manoeuvres.md.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.frames import wrap_angle

__all__ = [
    "HALF_AHEAD",
    "MANOEUVRES",
    "InitialTurning",
    "Scripts",
    "Stop",
    "TurningCircle",
    "ZigZag",
    "manoeuvre",
    "manoeuvre_names",
]

_DEG = math.pi / 180.0


def _time_scale(L: float, U0: float) -> float:
    if not (math.isfinite(L) and L > 0):
        raise ValueError(f"L must be > 0 m, got {L!r}")
    if not (math.isfinite(U0) and U0 > 0):
        raise ValueError(f"U0 must be > 0 m/s, got {U0!r}")
    return L / U0


def _side(side: int) -> int:
    if side not in (1, -1):
        raise ValueError(f"side must be +1 (starboard) or -1 (port), got {side!r}")
    return side


class Scripts:
    """The scripts of N manoeuvres, one per env, as one law over ``(N,)`` arrays:
    ``command(psi) -> (rudder rad, shaft fraction of n0)``, each ``(N,)``.

    A turning, initial-turning or stopping script holds its command; a zig-zag's rudder is
    ``side`` first (a starboard order is ``-angle``), reversed whenever the heading change
    from ``psi0`` reaches ``angle`` towards the side the rudder is on (classic Z-test).

    Args:
        manoeuvres: one manoeuvre per env (:data:`MANOEUVRES` values).
    """

    def __init__(self, manoeuvres: Sequence[Manoeuvre]) -> None:
        laws = np.array([m.law() for m in manoeuvres], dtype=float).reshape(-1, 3)
        self.rudder, self.shaft, self.angle = laws.T.copy()
        self.zigzag = self.angle > 0.0
        self.psi0 = np.zeros(len(laws))
        self.towards = np.zeros(len(laws))  # +1: rudder to starboard, heading change growing
        self.reset(np.zeros(len(laws)))

    def reset(self, psi0: ArrayLike, mask: NDArray[np.bool_] | None = None) -> None:
        """Start the runs of ``mask`` (default all) from the approach headings ``psi0`` (rad)."""
        m = np.ones(self.psi0.shape, bool) if mask is None else mask
        self.psi0 = np.where(m, psi0, self.psi0)
        self.towards = np.where(m, -np.sign(self.rudder), self.towards)

    def command(self, psi: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(rudder rad, shaft fraction of n0)`` at the headings ``psi`` (rad), each (N,)."""
        if not self.zigzag.any():
            return self.rudder.copy(), self.shaft.copy()
        dpsi = wrap_angle(psi - self.psi0)
        self.towards = np.where(self.zigzag & (self.towards * dpsi >= self.angle),
                                -self.towards, self.towards)  # fmt: skip
        return np.where(self.zigzag, -self.towards * self.angle, self.rudder), self.shaft.copy()


@dataclass(frozen=True)
class TurningCircle:
    """The turning circle: rudder ``angle`` to ``side`` at ``t = 0``, the shaft held at
    ``shaft n0`` from the approach on (the ship approaches at the steady speed of that
    command).

    Attributes:
        name: registry name; angle: rudder angle (rad, > 0); side: +1 starboard, -1 port.
        shaft: the shaft command of the approach and the turn (fraction of the full-ahead
            approach command ``n0``, in (0, 1]; 1 full ahead).
        rudder: the rudder the trial is flown with: ``None`` the vessel's own, else a name of
            :data:`shipgym.dynamics.mmg.RUDDER_OPTIONS` (``"schilling"``).
    """

    name: str
    angle: float
    side: int
    shaft: float = 1.0
    rudder: str | None = None

    kind = "turning"

    def __post_init__(self) -> None:
        if not (math.isfinite(self.shaft) and 0.0 < self.shaft <= 1.0):
            raise ValueError(f"shaft must be in (0, 1] (a fraction of n0), got {self.shaft!r}")
        if not (math.isfinite(self.angle) and 0.0 < self.angle < math.pi / 2):
            raise ValueError(f"angle must be in (0, pi/2) rad, got {self.angle!r}")

    def duration(self, L: float, U0: float) -> float:
        """36 ``L/U0`` (s) [chosen, module docstring]."""
        return 36.0 * _time_scale(L, U0)

    def approach_shaft(self) -> float:
        """The shaft command of the approach (fraction of ``n0``): :attr:`shaft`."""
        return self.shaft

    def law(self) -> tuple[float, float, float]:
        """The script's ``(rudder rad, shaft fraction, zig-zag angle)``: shipgym rudder
        ``-side * angle``, shaft :attr:`shaft`, no zig-zag."""
        return -_side(self.side) * self.angle, self.shaft, 0.0


@dataclass(frozen=True)
class ZigZag:
    """The ``angle``/``angle`` zig-zag, the first order to ``side``.

    Attributes:
        name: registry name; angle: rudder and heading-change angle (rad); side: +1 starboard.
    """

    name: str
    angle: float
    side: int

    kind = "zigzag"
    rudder = None

    def approach_shaft(self) -> float:
        """The approach's shaft command (fraction of ``n0``): 1, full ahead."""
        return 1.0

    def duration(self, L: float, U0: float) -> float:
        """40 ``L/U0`` (s) [chosen]."""
        return 40.0 * _time_scale(L, U0)

    def law(self) -> tuple[float, float, float]:
        """The script's ``(first rudder rad, shaft fraction, zig-zag angle rad)``."""
        return -_side(self.side) * self.angle, 1.0, self.angle


@dataclass(frozen=True)
class InitialTurning:
    """The initial turning test: rudder ``angle`` to ``side``; the metric is the distance run
    until the heading has changed by ``heading_change`` (IMO MSC.137(76) Annex 5.3.2: 10 deg
    rudder, 10 deg heading change).

    Attributes:
        name, angle, side, heading_change: the test's name, rudder angle (rad), side (+1
            starboard) and heading change (rad).
    """

    name: str
    angle: float
    side: int
    heading_change: float

    kind = "initial_turning"
    rudder = None

    def approach_shaft(self) -> float:
        """The approach's shaft command (fraction of ``n0``): 1, full ahead."""
        return 1.0

    def duration(self, L: float, U0: float) -> float:
        """6 ``L/U0`` (s) [chosen]."""
        return 6.0 * _time_scale(L, U0)

    def law(self) -> tuple[float, float, float]:
        """The script's ``(rudder rad, shaft fraction, zig-zag angle)``: shipgym rudder
        ``-side * angle``, shaft 1, no zig-zag."""
        return -_side(self.side) * self.angle, 1.0, 0.0


@dataclass(frozen=True)
class Stop:
    """A stopping manoeuvre: rudder amidships, shaft command ``shaft`` at ``t = 0``.

    Attributes:
        name; shaft: the shaft command (fraction of ``n0``: -1 full astern, 0 stop);
        end_speed: the speed (m/s) that ends the trial when ``u`` never reaches 0 (the
            coasting stop: 2 m/s [chosen, as the notes]; 0 for the crash stop);
        factor: the duration in ``L/U0``.
    """

    name: str
    shaft: float
    end_speed: float
    factor: float

    kind = "stop"
    rudder = None

    def approach_shaft(self) -> float:
        """The approach's shaft command (fraction of ``n0``): 1, full ahead."""
        return 1.0

    def duration(self, L: float, U0: float) -> float:
        """``factor * L/U0`` (s) [chosen]: 30 the crash stop, 80 the coasting stop."""
        return self.factor * _time_scale(L, U0)

    def law(self) -> tuple[float, float, float]:
        """The script's ``(rudder 0, shaft fraction, no zig-zag)``."""
        return 0.0, self.shaft, 0.0


Manoeuvre = TurningCircle | ZigZag | InitialTurning | Stop

#: the half-ahead shaft command, a fraction of the full-ahead approach command ``n0`` (1)
#: [chosen, see the module docstring]
HALF_AHEAD = 0.85

#: the manoeuvres by name (IMO MSC.137(76) (2002); the coasting stop of Artyszuk 2003 §3)
MANOEUVRES: dict[str, Manoeuvre] = {
    "turning35_stbd": TurningCircle("turning35_stbd", 35.0 * _DEG, 1),
    "turning35_port": TurningCircle("turning35_port", 35.0 * _DEG, -1),
    "zigzag10": ZigZag("zigzag10", 10.0 * _DEG, 1),
    "zigzag20": ZigZag("zigzag20", 20.0 * _DEG, 1),
    "crash_stop": Stop("crash_stop", -1.0, 0.0, 30.0),
    "coasting_stop": Stop("coasting_stop", 0.0, 2.0, 80.0),
    "initial_turning": InitialTurning("initial_turning", 10.0 * _DEG, 1, 10.0 * _DEG),
    "turning65_half_ahead": TurningCircle(
        "turning65_half_ahead", 65.0 * _DEG, 1, shaft=HALF_AHEAD, rudder="schilling"
    ),
}


def manoeuvre_names() -> list[str]:
    """The names :func:`manoeuvre` accepts."""
    return list(MANOEUVRES)


def manoeuvre(name: str) -> Manoeuvre:
    """The manoeuvre ``name``.

    Raises:
        ValueError: unknown name (the message lists the valid ones).
    """
    try:
        return MANOEUVRES[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown manoeuvre {name!r}; valid: {', '.join(MANOEUVRES)}") from None
