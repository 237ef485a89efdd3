"""Small helpers for frozen configuration dataclasses: documented fields and strict loading."""

from __future__ import annotations

import dataclasses
import functools
import math
import numbers
from collections.abc import Mapping
from typing import Any, TypeVar

T = TypeVar("T")

__all__ = [
    "param",
    "required_param",
    "require_given",
    "from_mapping",
    "replace_drawn",
    "describe",
    "fields_of",
    "is_real",
    "require_finite",
    "require_positive",
]


def param(default: Any, unit: str, source: str) -> Any:
    """A dataclass field carrying its physical unit and its source in ``metadata``."""
    return dataclasses.field(default=default, metadata={"unit": unit, "source": source})


def required_param(unit: str, meaning: str) -> Any:
    """A dataclass field without a default, carrying its physical unit and its meaning.

    For parameters that belong to one vessel (no vessel is a default): the values and their
    sources live in the vessel's package or in a named record such as ``BLUE_LADY_HULL``.
    """
    return dataclasses.field(metadata={"unit": unit, "meaning": meaning})


def require_given(where: str, hint: str, **values: Any) -> None:
    """Raise ``TypeError`` naming the arguments of ``values`` that are ``None`` and what to pass.

    For vessel-specific arguments that have no default (no vessel is a default below the
    registry), e.g. ``require_given("LQController()", "...", M=M, D_L=D_L)``.
    """
    missing = [k for k, v in values.items() if v is None]
    if missing:
        raise TypeError(f"{where} needs {' and '.join(missing)} (no vessel is a default): {hint}")


def replace_drawn(obj: T, **changes: Any) -> T:
    """A copy of the frozen dataclass ``obj`` (validated when it was made) with ``changes``,
    WITHOUT running its validation again: for an episode's draws, every reset, whose values the
    task draws inside ranges it validated when it was made (a wind speed in ``[0,
    max_wind_speed]``); every other change goes through ``dataclasses.replace``. The copy equals
    the validated one (``==``). Raises ``ValueError`` for a name that is not a field."""
    own = obj.__dict__
    unknown = sorted(set(changes) - set(own))
    if unknown:
        raise ValueError(f"{type(obj).__name__} has no field(s) {unknown}")
    new = object.__new__(type(obj))
    new.__dict__.update(own)
    new.__dict__.update(changes)
    return new


def from_mapping(cls: type[T], mapping: Mapping[str, Any], *, where: str = "") -> T:
    """Build a dataclass from a mapping; unknown keys raise ``ValueError`` naming the valid ones."""
    names = [f.name for f in fields_of(cls)]
    unknown = sorted(set(mapping) - set(names))
    if unknown:
        ctx = f" in {where}" if where else ""
        raise ValueError(
            f"unknown key(s) {unknown}{ctx} for {cls.__name__}; valid keys are: {', '.join(names)}"
        )
    return cls(**dict(mapping))


def is_real(x: Any) -> bool:
    """Whether ``x`` is a real number (Python or NumPy int or float), ``bool`` excluded."""
    t = type(x)
    if t is float or t is int:  # the common case, without the ABC check
        return True
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


@functools.cache
def fields_of(cls: type) -> tuple[dataclasses.Field, ...]:  # type: ignore[type-arg]
    """``dataclasses.fields`` of a dataclass type, looked up once per type (validation at
    every construction, such as an episode's drawn configs, reads them)."""
    return dataclasses.fields(cls)


def describe(obj: Any) -> list[tuple[str, Any, str, str]]:
    """Rows ``(name, value, unit, source)`` for every field of a parameter dataclass."""
    return [
        (f.name, getattr(obj, f.name), f.metadata.get("unit", ""), f.metadata.get("source", ""))
        for f in dataclasses.fields(obj)
    ]


def require_finite(obj: Any) -> None:
    """Raise ``ValueError`` for any non-finite float field of a dataclass."""
    for f in fields_of(type(obj)):
        val = getattr(obj, f.name)
        if isinstance(val, float | int) and not isinstance(val, bool) and not math.isfinite(val):
            raise ValueError(f"{type(obj).__name__}.{f.name} must be finite, got {val!r}")


#: the largest |angle| a direction may have (rad): a hundred turns; more is a unit mistake (a
#: bearing in degrees given as radians, a typo), not a direction
MAX_ANGLE = 200.0 * math.pi


def require_angles(obj: Any, *names: str) -> None:
    """Raise ``ValueError`` for a named angle field beyond :data:`MAX_ANGLE`."""
    for name in names:
        val = getattr(obj, name)
        if val is not None and abs(val) > MAX_ANGLE:
            raise ValueError(
                f"{type(obj).__name__}.{name} must be within +-{MAX_ANGLE:.0f} rad (a hundred "
                f"turns), got {val!r}: a direction in degrees given as radians?"
            )


#: the largest ship dimension accepted (m): above the longest ship ever built (Seawise Giant,
#: 458 m); a larger value is a unit mistake (mm for m), not a ship
MAX_DIMENSION = 1000.0


def require_dimensions(obj: Any, *names: str) -> None:
    """Raise ``ValueError`` for a named length (m) beyond :data:`MAX_DIMENSION`."""
    for name in names:
        val = getattr(obj, name)
        if val is not None and val > MAX_DIMENSION:
            raise ValueError(
                f"{type(obj).__name__}.{name} must be at most {MAX_DIMENSION:g} m, got {val!r}: "
                "a length in mm given as m?"
            )


def require_positive(obj: Any, *names: str) -> None:
    """Raise ``ValueError`` if any named field is not strictly positive."""
    for name in names:
        val = getattr(obj, name)
        if not val > 0:
            raise ValueError(
                f"{type(obj).__name__}.{name} must be > 0, got {val!r} "
                f"(unit: {_unit(obj, name)}); masses, inertias and time constants are positive"
            )


def _unit(obj: Any, name: str) -> str:
    for f in dataclasses.fields(obj):
        if f.name == name:
            return f.metadata.get("unit", "?")
    return "?"
