r"""The IMO manoeuvres of a sea trial as scripts (IMO MSC.137(76) (2002); Artyszuk 2003 §3).

Public names: ``MANOEUVRES``, ``ConstantScript``, ``InitialTurning``, ``Stop``, ``TurningCircle``,
``ZigZag``, ``ZigZagScript``, ``manoeuvre``, ...

Design notes: docs/design/trials.manoeuvres.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from shipgym.dynamics.frames import wrap_angle

__all__ = [
    "MANOEUVRES",
    "ConstantScript",
    "InitialTurning",
    "Stop",
    "TurningCircle",
    "ZigZag",
    "ZigZagScript",
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


class ConstantScript:
    """A script holding one command: ``command(t, psi, u) -> (rudder rad, shaft fraction)``.

    Args:
        rudder: the rudder command (rad, shipgym convention: positive turns to port).
        shaft: the shaft command as a fraction of the approach shaft speed ``n0``.
    """

    def __init__(self, rudder: float, shaft: float) -> None:
        self.rudder, self.shaft = float(rudder), float(shaft)
        self.psi0 = 0.0

    def reset(self, psi0: float) -> None:
        """Start a run from the approach heading ``psi0`` (rad)."""
        self.psi0 = float(psi0)

    def command(self, t: float, psi: float, u: float) -> tuple[float, float]:
        """``(rudder rad, shaft fraction of n0)`` at time ``t`` (s), heading ``psi`` (rad) and
        surge speed ``u`` (m/s)."""
        return self.rudder, self.shaft


class ZigZagScript:
    """The zig-zag's rudder logic: ``side`` first, reversed whenever the heading change from
    ``psi0`` reaches ``angle`` towards the side the rudder is on (classic Z-test).

    Args:
        angle: the rudder angle and the heading-change angle (rad), > 0.
        side: +1 the first order to starboard (command ``-angle``), -1 to port.
        shaft: the shaft command (fraction of ``n0``).

    Attributes:
        executes: the times (s) of the rudder reversals so far.
    """

    def __init__(self, angle: float, side: int, shaft: float = 1.0) -> None:
        self.angle, self.side, self.shaft = float(angle), _side(side), float(shaft)
        self.reset(0.0)

    def reset(self, psi0: float) -> None:
        """Start a run from the approach heading ``psi0`` (rad)."""
        self.psi0 = float(psi0)
        self._towards = self.side  # +1: rudder to starboard, heading change growing
        self.executes: list[float] = []

    def command(self, t: float, psi: float, u: float) -> tuple[float, float]:
        """``(rudder rad, shaft fraction of n0)``; see the class."""
        dpsi = float(wrap_angle(float(psi) - self.psi0))
        if self._towards * dpsi >= self.angle:
            self._towards = -self._towards
            self.executes.append(float(t))
        return -self._towards * self.angle, self.shaft


@dataclass(frozen=True)
class TurningCircle:
    """The turning circle: rudder ``angle`` to ``side`` at ``t = 0``, shaft at ``n0``.

    Attributes:
        name: registry name; angle: rudder angle (rad, > 0); side: +1 starboard, -1 port.
    """

    name: str
    angle: float
    side: int

    kind = "turning"

    def duration(self, L: float, U0: float) -> float:
        """36 ``L/U0`` (s) [chosen, module docstring]."""
        return 36.0 * _time_scale(L, U0)

    def script(self) -> ConstantScript:
        """A fresh script (shipgym rudder ``-side * angle``, shaft 1)."""
        return ConstantScript(-_side(self.side) * self.angle, 1.0)


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

    def duration(self, L: float, U0: float) -> float:
        """40 ``L/U0`` (s) [chosen]."""
        return 40.0 * _time_scale(L, U0)

    def script(self) -> ZigZagScript:
        """A fresh :class:`ZigZagScript`."""
        return ZigZagScript(self.angle, self.side, 1.0)


@dataclass(frozen=True)
class InitialTurning:
    """The initial turning test: rudder ``angle`` to ``side``; the metric is the distance run
    until the heading has changed by ``heading_change`` (IMO MSC.137(76) Annex 5.3.2: 10 deg
    rudder, 10 deg heading change).

    Attributes:
        name; angle (rad); side (+1 starboard); heading_change (rad).
    """

    name: str
    angle: float
    side: int
    heading_change: float

    kind = "initial_turning"

    def duration(self, L: float, U0: float) -> float:
        """6 ``L/U0`` (s) [chosen]."""
        return 6.0 * _time_scale(L, U0)

    def script(self) -> ConstantScript:
        """A fresh script (shipgym rudder ``-side * angle``, shaft 1)."""
        return ConstantScript(-_side(self.side) * self.angle, 1.0)


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

    def duration(self, L: float, U0: float) -> float:
        """``factor * L/U0`` (s) [chosen]: 30 the crash stop, 80 the coasting stop."""
        return self.factor * _time_scale(L, U0)

    def script(self) -> ConstantScript:
        """A fresh script (rudder 0, shaft ``shaft``)."""
        return ConstantScript(0.0, self.shaft)


Manoeuvre = TurningCircle | ZigZag | InitialTurning | Stop

#: the manoeuvres by name (IMO MSC.137(76) (2002); the coasting stop of Artyszuk 2003 §3)
MANOEUVRES: dict[str, Manoeuvre] = {
    "turning35_stbd": TurningCircle("turning35_stbd", 35.0 * _DEG, 1),
    "turning35_port": TurningCircle("turning35_port", 35.0 * _DEG, -1),
    "zigzag10": ZigZag("zigzag10", 10.0 * _DEG, 1),
    "zigzag20": ZigZag("zigzag20", 20.0 * _DEG, 1),
    "crash_stop": Stop("crash_stop", -1.0, 0.0, 30.0),
    "coasting_stop": Stop("coasting_stop", 0.0, 2.0, 80.0),
    "initial_turning": InitialTurning("initial_turning", 10.0 * _DEG, 1, 10.0 * _DEG),
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
