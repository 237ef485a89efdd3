r"""Command conditioning of the DP stack: the controller-design parts (not physics).

Design notes: docs/design/controllers.conditioning.md.
Example (the state is per episode: call :meth:`ReversalHysteresis.reset` at its start):

    >>> from shipgym.dynamics.vessel import load_vessel
    >>> from shipgym.controllers.actuation import make_allocator
    >>> v = load_vessel("blue-lady")
    >>> hyst = ReversalHysteresis(v.actuators, [10.0, 0.0, 0.0])
    >>> alloc = make_allocator(v)
    >>> a1 = hyst(alloc([50.0, 0.0, 0.0], None))  # ahead: passed
    >>> a2 = hyst(alloc([-5.0, 0.0, 0.0], None))  # 5 N astern < 10 N: held at zero
    >>> float(a2.force[0]), float(a2.tau_error[0])
    (0.0, -5.0)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import entry, njit
from shipgym.dynamics.actuators import ActuatorSet, Propeller

from .allocation import Allocation

__all__ = ["BatchedReversalHysteresis", "ReversalHysteresis", "reversal_threshold"]


def reversal_threshold(vessel: Any) -> tuple[float, ...]:
    """The vessel's ``[control] reversal_threshold`` (N per actuator; zeros if unset)."""
    n = len(vessel.actuators)
    h = tuple(float(x) for x in vessel.control.get("reversal_threshold", (0.0,) * n))
    if len(h) != n:
        raise ValueError(f"reversal_threshold must have {n} entries (one per actuator), got {h}")
    return h


class _Units:
    """The hysteresis units of an actuator set, as the arrays the compiled laws read: per
    conditioned propeller ``I[k] = (actuator index, command channel)`` and
    ``H[k] = (F_h ahead (N), F_h astern (N), its planar or 4-DOF column of the thrust
    configuration)``."""

    def __init__(self, actuators: ActuatorSet, threshold: Sequence[float]) -> None:
        h = [float(x) for x in threshold]
        if len(h) != len(actuators):
            raise ValueError(
                f"threshold must have one force (N) per actuator ({len(actuators)}: "
                f"{', '.join(actuators.names)}), got {list(threshold)!r}"
            )
        if not all(math.isfinite(x) and x >= 0.0 for x in h):
            raise ValueError(f"thresholds must be finite forces >= 0 (N; 0: off), got {h!r}")
        planar = actuators.dofs == 3
        idx, rows = [], []
        for i, a in enumerate(actuators.actuators):
            if h[i] == 0.0 or not isinstance(a, Propeller):
                continue  # azimuths turn instead of reversing; 0: off
            c, s = a.direction
            x, y, _ = a.position
            col = (c, s, x * s - y * c) if planar else (c, s, 0.0, x * s - y * c)
            idx.append((i, actuators.slices[i].start))
            # thrust (N) the request must exceed on the new side: ahead, astern (> 0)
            rows.append((h[i], h[i], *col))
        self.I = np.array(idx, dtype=np.int64).reshape(-1, 2)
        self.H = np.array(rows, dtype=float).reshape(len(idx), 2 + (3 if planar else 4))


@njit
def reversal_law(I: Any, H: Any, dirs: Any, force: Any, hold: Any) -> int:
    """The running directions ``dirs`` (n, units) after the allocated thrusts ``force``
    (n, actuators) (N), and which units are held at zero ``hold`` (n, units); returns how
    many are held (:class:`ReversalHysteresis`)."""
    held = 0
    for e in range(force.shape[0]):
        for k in range(I.shape[0]):
            f = force[e, I[k, 0]]
            d = dirs[e, k]
            hold[e, k] = False
            if d == 0.0 or f * d >= 0.0:  # same side (or not yet set): passed
                if f != 0.0:
                    dirs[e, k] = 1.0 if f > 0.0 else -1.0
            elif (f > H[k, 0]) if f > 0.0 else (-f > H[k, 1]):  # a reversal
                dirs[e, k] = -d
            else:
                hold[e, k] = True
                held += 1
    return held


@njit
def reversal_hold(I: Any, H: Any, hold: Any, command: Any, force: Any, tau: Any,
                  err: Any) -> None:  # fmt: skip
    """Set the held units' thrust and command to zero and correct ``tau`` and ``tau_error``
    (n, dofs) by the thrust held back (``tau -= b F``, ``tau_error += b F``)."""
    for e in range(force.shape[0]):
        for k in range(I.shape[0]):
            if not hold[e, k]:
                continue
            i = I[k, 0]
            f = force[e, i]
            command[e, I[k, 1]] = 0.0
            force[e, i] = 0.0
            for j in range(H.shape[1] - 2):
                b = H[k, 2 + j]
                if b != 0.0:
                    bf = b * f
                    tau[e, j] -= bf
                    err[e, j] += bf


_ENTRIES: dict[str, Any] = {}


def _run(name: str, fn: Any, *args: Any) -> int:
    e = _ENTRIES.get(name)
    if e is None:
        e = _ENTRIES[name] = entry(fn, args)
    return e(*args)  # type: ignore[no-any-return]


def _c2(a: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a`` as a C-contiguous float (n, k) array (a copy: the laws write into it)."""
    return np.array(a, dtype=float, order="C", ndmin=2)


class BatchedReversalHysteresis:
    """Zero-thrust deadband with hysteresis for propeller reversals, ``n`` envs at once: the
    one run-time form (:class:`ReversalHysteresis` is its ``n = 1`` adapter).

    Per conditioned propeller (a :class:`~shipgym.dynamics.actuators.Propeller` whose
    threshold ``F_h > 0``) and env the state is its running direction ``d`` (+1 ahead, -1
    astern, 0 not yet set). For an allocated thrust ``F`` (N):

    - ``d = 0`` or ``F d >= 0`` (same side, or zero): ``F`` is passed; ``d = sign(F)`` if
      ``F != 0``;
    - ``F d < 0`` and ``|F| > F_h``: ``F`` is passed and ``d = sign(F)`` (a reversal);
    - otherwise the thrust and its command are set to zero, and the allocation's ``tau`` and
      ``tau_error`` are corrected by the held-back thrust (``tau -= b F``,
      ``tau_error += b F``, ``b`` the actuator's column of the thrust configuration).

    Args:
        actuators: the vessel's actuator set.
        threshold: per actuator, the thrust ``F_h`` (N, >= 0) a request in the other
            direction must exceed (0: off; non-propeller actuators are never conditioned).
        n: number of envs, >= 1.
    """

    def __init__(self, actuators: ActuatorSet, threshold: Sequence[float], n: int = 1) -> None:
        self.actuators = actuators
        self.threshold = tuple(float(x) for x in threshold)
        u = _Units(actuators, threshold)
        self._I, self._H = u.I, u.H
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ValueError(f"n must be an int >= 1 (the number of envs), got {n!r}")
        self.n = int(n)
        self._dir = np.zeros((self.n, len(u.I)))
        self._hold = np.zeros((self.n, len(u.I)), dtype=np.bool_)

    @property
    def active(self) -> bool:
        """Whether any actuator is conditioned (else calls return the allocation unchanged)."""
        return bool(len(self._I))

    def reset(self, mask: ArrayLike | None = None) -> None:
        """Forget the running directions of every env, or of those where ``mask``."""
        if mask is None:
            self._dir[:] = 0.0
        else:
            self._dir[np.asarray(mask, dtype=bool)] = 0.0

    def __call__(
        self, command: NDArray[np.float64], force: NDArray[np.float64], tau: NDArray[np.float64],
        tau_error: NDArray[np.float64],
    ) -> tuple[NDArray[np.float64], ...]:  # fmt: skip
        """``(command, force, tau, tau_error)`` (each (n, k)) after the hysteresis (copies
        where anything changed, else the inputs)."""
        if not len(self._I):
            return command, force, tau, tau_error
        f = force if force.flags.c_contiguous and force.dtype == np.float64 else _c2(force)
        if not _run("law", reversal_law, self._I, self._H, self._dir, f, self._hold):
            return command, force, tau, tau_error
        out = (_c2(command), _c2(force), _c2(tau), _c2(tau_error))
        _run("hold", reversal_hold, self._I, self._H, self._hold, *out)
        return out

    def __repr__(self) -> str:
        return f"BatchedReversalHysteresis(n={self.n}, threshold={self.threshold})"


class ReversalHysteresis:
    """:class:`BatchedReversalHysteresis` for one env, on an
    :class:`~shipgym.controllers.allocation.Allocation`.

    Args:
        actuators: the vessel's actuator set.
        threshold: per actuator, the thrust ``F_h`` (N, >= 0) a request in the other
            direction must exceed (0: off; non-propeller actuators are never conditioned).
    """

    def __init__(self, actuators: ActuatorSet, threshold: Sequence[float]) -> None:
        self._law = BatchedReversalHysteresis(actuators, threshold, 1)
        self.actuators = actuators
        self.threshold = self._law.threshold

    @property
    def active(self) -> bool:
        """Whether any actuator is conditioned (else calls return the allocation unchanged)."""
        return self._law.active

    def reset(self) -> None:
        """Forget the running directions (start of an episode)."""
        self._law.reset()

    def __call__(self, alloc: Allocation) -> Allocation:
        """The allocation with the reversal hysteresis applied (a new one if it changed)."""
        f = alloc.force[None]
        out = self._law(alloc.command[None], f, alloc.tau[None], alloc.tau_error[None])
        if out[1] is f:
            return alloc
        return Allocation(out[0][0], out[1][0], out[2][0], out[3][0], alloc.saturated)

    def __repr__(self) -> str:
        return f"ReversalHysteresis(threshold={self.threshold})"
