"""Wind and current settings at the public boundary: the forms a user may give, one coercion.

Public names: ``coerce_config``, ``parse_config``, ``parse_speed_at``.

Design notes: docs/design/disturbances._boundary.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any, TypeVar

import numpy as np

from shipgym._config import is_real

__all__ = ["coerce_config", "parse_config", "parse_speed_at"]

C = TypeVar("C")


def parse_speed_at(text: Any, *, name: str, form: str, example: str) -> tuple[float, float]:
    """Split ``"SPEED@DEG"`` into ``(speed, degrees)`` as written (no range checks here).

    Args:
        text: The string.
        name: The argument's name for the message (``"wind"``).
        form: The accepted form for the message (``"SPEED@FROM_DEG"``).
        example: An example with its meaning (``"3@300 (3 m/s from 300 deg)"``).

    Raises:
        ValueError: Not a string of two numbers separated by ``@``.
    """
    parts = text.split("@") if isinstance(text, str) else []
    try:
        if len(parts) != 2 or "_" in text:  # float() would read "3_0" as 30
            raise ValueError
        speed, deg = float(parts[0]), float(parts[1])
    except ValueError:
        raise ValueError(f"malformed {name} {text!r}: expected {form}, e.g. {example}") from None
    return speed, deg


def parse_config(
    text: Any,
    *,
    from_deg: Callable[[float, float], C],
    name: str,
    form: str,
    example: str,
) -> C:
    """``"SPEED@DEG"`` to a config: :func:`parse_speed_at`, then ``from_deg(speed, deg)``.

    Raises:
        ValueError: Malformed text, or a value the config refuses (the message names ``name``,
            the text and the field).
    """
    speed, deg = parse_speed_at(text, name=name, form=form, example=example)
    try:
        return from_deg(speed, deg)
    except ValueError as exc:
        raise ValueError(f"{name} {text!r}: {exc}") from None


def coerce_config(
    cls: type[C],
    value: Any,
    *,
    name: str,
    parse: Callable[[str], C],
    from_deg: Callable[[float, float], C],
    deg_fields: Mapping[str, str],
    accepted: str,
) -> C | None:
    """The one coercion of a wind or current setting (see the module docstring).

    Args:
        cls: The config class.
        value: What the user gave.
        name: The argument's name, used in every message.
        parse: ``cls.parse`` (``"SPEED@DEG"``).
        from_deg: ``(speed m/s, direction deg) -> config``.
        deg_fields: ``{"direction_from_deg": "direction_from", ...}`` accepted in a mapping.
        accepted: The accepted forms, for the message.

    Returns:
        The config, or ``None`` for ``None``.

    Raises:
        ValueError: An unaccepted form (naming ``name`` and the accepted forms) or an invalid
            value (naming ``name`` and the field).
    """
    if value is None or isinstance(value, cls):
        return value
    if isinstance(value, str):
        return parse(value)
    try:
        if isinstance(value, Mapping):
            d = dict(value)
            for deg_key, key in deg_fields.items():
                if deg_key in d:
                    if key in d:
                        raise ValueError(f"give '{key}' (rad) or '{deg_key}' (deg), not both")
                    deg = d.pop(deg_key)
                    if not is_real(deg):
                        raise ValueError(f"{deg_key} must be a number of degrees, got {deg!r}")
                    d[key] = math.radians(deg)
            return cls.from_dict(d)  # type: ignore[attr-defined, no-any-return]
        if isinstance(value, tuple | list | np.ndarray) and len(value) == 2:
            speed, deg = (x.item() if isinstance(x, np.generic) else x for x in value)
            if is_real(speed) and is_real(deg):
                return from_deg(float(speed), float(deg))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} {value!r}: {exc}") from None
    raise ValueError(f"{name} must be {accepted}; got {value!r}")
