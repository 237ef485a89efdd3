"""The reference frame r of a manoeuvre leg (Tomera 2014 eqs. 1-2, Fig. 2).

Public names: ``to_r_frame``, ``r_frame_poses``, ``r_pose``, ``from_r_frame``.

Design notes: docs/design/guidance.rframe.md.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import entry, njit
from shipgym.dynamics.frames import wrap

__all__ = ["to_r_frame", "r_frame_poses", "r_pose", "from_r_frame"]


@njit(inline="always")
def r_pose(x, y, psi, xp, yp, psip, psi_ref, has_ref):  # type: ignore[no-untyped-def]
    """One NED pose ``(x, y, psi)`` in the r-frame of a leg starting at ``(xp, yp, psip)``
    (Tomera 2014 eq. 1), the heading on the branch within pi of ``psi_ref`` where
    ``has_ref``: the one r-frame law, inlined where compiled code needs it."""
    c, s = math.cos(psip), math.sin(psip)
    dx, dy, dpsi = x - xp, y - yp, psi - psip
    psi_r = psi_ref + wrap(dpsi - psi_ref) if has_ref else wrap(dpsi)
    return c * dx + s * dy, -s * dx + c * dy, psi_r


@njit
def r_frame_poses(eta, eta_P, psi_ref, has_ref, out):  # type: ignore[no-untyped-def]
    """The compiled map of :func:`to_r_frame` over N poses: ``eta`` and ``eta_P`` (N, 3),
    ``psi_ref`` (N,) (read where ``has_ref``), into ``out`` (N, 3)."""
    for i in range(eta.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = r_pose(
            eta[i, 0], eta[i, 1], eta[i, 2], eta_P[i, 0], eta_P[i, 1], eta_P[i, 2], psi_ref[i],
            has_ref,
        )  # fmt: skip


_ENTRY: list[Any] = []


def to_r_frame(
    eta_n: ArrayLike, eta_P: ArrayLike, psi_ref_r: ArrayLike | None = None
) -> NDArray[np.float64]:
    """Express NED poses in the r-frame of a leg that starts at ``eta_P`` (Tomera 2014 eq. 1).

    Args:
        eta_n: NED poses ``[x, y, psi]`` (m, m, rad), shape (3,) or (..., 3).
        eta_P: NED pose of the leg's start point P (m, m, rad), shape (3,) or (..., 3).
        psi_ref_r: optional r-frame heading (rad), scalar or shape (...), that the result's
            heading is unwrapped against: ``psi^r = psi_ref_r + wrap(psi - psi_P - psi_ref_r)``,
            i.e. the branch within pi of ``psi_ref_r``. Pass the desired r-frame heading
            ``psi_d^r`` so that legs turning by pi or more give continuous r-frame headings.
            Without it the heading is ``wrap(psi - psi_P)`` in (-pi, pi].

    Returns:
        r-frame poses ``[x^r, y^r, psi^r]`` (m, m, rad), shape broadcast of the inputs: one
        compiled law (:func:`r_frame_poses`) for one pose or many.
    """
    eta_n = np.asarray(eta_n, dtype=float)
    eta_P = np.asarray(eta_P, dtype=float)
    if eta_n.shape[-1:] != (3,) or eta_P.shape[-1:] != (3,):
        raise ValueError(
            f"eta_n and eta_P must have a last axis of length 3 ([x, y, psi]), got shapes "
            f"{eta_n.shape} and {eta_P.shape}"
        )
    one = eta_n.shape == eta_P.shape == (3,)
    if one and (psi_ref_r is None or np.ndim(psi_ref_r) == 0):  # one pose (every step)
        lead: tuple[int, ...] = ()
        e = np.ascontiguousarray(eta_n).reshape(1, 3)
        p = np.ascontiguousarray(eta_P).reshape(1, 3)
        ref = np.array([0.0 if psi_ref_r is None else psi_ref_r], dtype=float)
    else:
        lead = np.broadcast_shapes(eta_n.shape[:-1], eta_P.shape[:-1])
        if psi_ref_r is not None:
            lead = np.broadcast_shapes(lead, np.shape(psi_ref_r))
        e = np.ascontiguousarray(np.broadcast_to(eta_n, (*lead, 3)).reshape(-1, 3))
        p = np.ascontiguousarray(np.broadcast_to(eta_P, (*lead, 3)).reshape(-1, 3))
        ref = (
            np.zeros(e.shape[0])
            if psi_ref_r is None
            else np.ascontiguousarray(
                np.broadcast_to(np.asarray(psi_ref_r, dtype=float), lead).reshape(-1)
            )
        )
    out = np.empty_like(e)
    args = (e, p, ref, psi_ref_r is not None, out)
    if not _ENTRY:
        _ENTRY.append(entry(r_frame_poses, args))
    _ENTRY[0](*args)
    return out.reshape(*lead, 3)


def from_r_frame(eta_r: ArrayLike, eta_P: ArrayLike) -> NDArray[np.float64]:
    """Map r-frame poses back to NED: ``p^n = p_P + R(psi_P) p^r``, ``psi^n = psi_P + psi^r``.

    The NED heading is *not* wrapped: it is continuous in ``psi^r`` and keeps the branch of
    ``psi_P`` (a leg starting at 350 deg and turning 90 deg clockwise ends at 440 deg, not
    at 80 deg), so desired headings never jump across 0/360 deg. Compare headings with
    :func:`shipgym.dynamics.wrap_angle`.

    Args:
        eta_r: r-frame poses ``[x^r, y^r, psi^r]`` (m, m, rad), shape (3,) or (..., 3).
        eta_P: NED pose of the leg's start point P (m, m, rad), shape (3,) or (..., 3).

    Returns:
        NED poses ``[x, y, psi]`` (m, m, rad), shape broadcast of the inputs.
    """
    eta_r = np.asarray(eta_r, dtype=float)
    eta_P = np.asarray(eta_P, dtype=float)
    if eta_r.shape[-1:] != (3,) or eta_P.shape[-1:] != (3,):
        raise ValueError(
            f"eta_r and eta_P must have a last axis of length 3 ([x, y, psi]), got shapes "
            f"{eta_r.shape} and {eta_P.shape}"
        )
    c = np.cos(eta_P[..., 2])
    s = np.sin(eta_P[..., 2])
    xr = eta_r[..., 0]
    yr = eta_r[..., 1]
    out = np.empty(np.broadcast_shapes(eta_r.shape, eta_P.shape))
    out[..., 0] = eta_P[..., 0] + c * xr - s * yr
    out[..., 1] = eta_P[..., 1] + s * xr + c * yr
    out[..., 2] = eta_P[..., 2] + eta_r[..., 2]
    return out
