"""Reference frames and angles (Fossen 2011, ch. 2).

NED earth frame (x north, y east, psi clockwise from north) and body frame (x forward,
y starboard). Every function accepts a leading batch axis.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import njit

__all__ = ["rot", "wrap_angle", "wrap", "body_to_ned", "ned_to_body"]

_PI = math.pi
_TWO_PI = 2.0 * math.pi


def wrap_angle(angle: ArrayLike) -> NDArray[np.float64] | float:
    """Wrap an angle (rad) to the interval (-pi, pi].

    Used for every differenced angle (errors, innovations, residuals) so that a heading
    crossing 0/360 deg never produces a jump.
    """
    if type(angle) is float or type(angle) is int:  # fast path for plain numbers
        return _PI - math.fmod(math.fmod(_PI - angle, _TWO_PI) + _TWO_PI, _TWO_PI)
    if type(angle) is np.float64:  # the array formula below on one float, the same result
        x = _PI - float(angle)
        if math.isfinite(x):
            # np.mod(x, 2 pi): fmod, moved into [0, 2 pi) as NumPy's npy_divmod moves it
            m = math.fmod(x, _TWO_PI)
            if m:
                if m < 0.0:
                    m += _TWO_PI
            else:
                m = 0.0
            return _PI - m
    a = np.asarray(angle, dtype=float)
    w = np.pi - np.mod(np.pi - a, 2.0 * np.pi)
    return float(w) if w.ndim == 0 else w


@njit(inline="always")
def wrap(a):  # type: ignore[no-untyped-def]
    """:func:`wrap_angle` of one float in compiled code: ``pi - ((pi - a) mod 2 pi)`` with
    Python's (and NumPy's) floor modulo, the same bits."""
    return _PI - (_PI - a) % _TWO_PI


def rot(psi: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrix R(psi) from body to NED, shape (..., 3, 3) (Fossen 2011, eq. 2.62).

    ``R(psi) = [[c, -s, 0], [s, c, 0], [0, 0, 1]]``; ``eta_dot = R(psi) nu``.
    """
    psi = np.asarray(psi, dtype=float)
    c, s = np.cos(psi), np.sin(psi)
    out = np.zeros(psi.shape + (3, 3))
    out[..., 0, 0] = c
    out[..., 0, 1] = -s
    out[..., 1, 0] = s
    out[..., 1, 1] = c
    out[..., 2, 2] = 1.0
    return out


def body_to_ned(psi: ArrayLike, vec_b: ArrayLike) -> NDArray[np.float64]:
    """Rotate body-frame 3-vectors ``[u, v, r]`` (..., 3) to NED: ``R(psi) vec_b``."""
    return np.einsum("...ij,...j->...i", rot(psi), np.asarray(vec_b, dtype=float))


def ned_to_body(psi: ArrayLike, vec_n: ArrayLike) -> NDArray[np.float64]:
    """Rotate NED 3-vectors (..., 3) to the body frame: ``R(psi)^T vec_n``."""
    return np.einsum("...ji,...j->...i", rot(psi), np.asarray(vec_n, dtype=float))
