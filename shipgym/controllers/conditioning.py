r"""Command conditioning of the DP stack: the controller-design parts (not physics).

A DP system does not send the raw output of its control law to the thrusters. Between the
navigation data and the actuators a DP engineer puts, as controller *design* choices:

- a **filtered derivative**: the velocity the PID's ``K_D`` term (and its damping and
  Coriolis feed-forward) uses is a first-order low-pass of the estimated velocity,
  ``T_f nu_f_dot + nu_f = nu`` per body DOF (sampled exactly:
  ``nu_f <- nu_f + (1 - exp(-dt / T_f)) (nu - nu_f)``), so that the observer's velocity noise
  times ``M K_D`` does not reach the thrusters
  (:class:`~shipgym.controllers.pid.MultivariablePID` ``velocity_filter``; the vessel's
  ``[control] velocity_filter``, s);
- a **zero-thrust deadband with hysteresis for propeller reversals** (:class:`ReversalHysteresis`,
  after the allocation): a reversible fixed-direction propeller that runs in one direction and
  is asked for thrust in the other is held at zero thrust until the request exceeds a
  threshold ``F_h`` (N) (the vessel's ``[control] reversal_threshold``, one per actuator;
  0: no hysteresis). Requests on
  the side it already runs are passed unchanged, so the fine control about a working point is
  kept, and only the sign changes are filtered: a shaft is not reversed for a few newtons of
  noise.

The integral anti-windup of the PID sees what is delivered after the conditioning: the
hysteresis updates the allocation's ``tau`` and ``tau_error`` (requested - delivered) by the
thrust it holds back, so a DOF held at zero counts as cut in the requested direction.

What is *physics*, not conditioning: the actuators' own lags and rate limits (the vessel
package's actuator tables; enforced by the simulator, the controller cannot exceed them).

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
    """The hysteresis units of an actuator set: index, channel, thresholds (N), planar column."""

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
        self.units: list[tuple[int, int, float, float, tuple[float, ...]]] = []
        for i, a in enumerate(actuators.actuators):
            if h[i] == 0.0 or not isinstance(a, Propeller):
                continue  # azimuths turn instead of reversing; 0: off
            c, s = a.direction
            x, y, _ = a.position
            col = (c, s, x * s - y * c) if planar else (c, s, 0.0, x * s - y * c)
            ch = actuators.slices[i].start
            # thrust (N) the request must exceed on the new side: ahead, astern (> 0)
            self.units.append((i, ch, h[i], h[i], col))


class ReversalHysteresis:
    """Zero-thrust deadband with hysteresis for propeller reversals (module docstring).

    Per conditioned propeller (a :class:`~shipgym.dynamics.actuators.Propeller` whose
    threshold ``F_h > 0``) the state is its running direction ``d`` (+1 ahead, -1
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
    """

    def __init__(self, actuators: ActuatorSet, threshold: Sequence[float]) -> None:
        self.actuators = actuators
        self.threshold = tuple(float(x) for x in threshold)
        self._units = _Units(actuators, threshold).units
        self._dir = [0] * len(self._units)

    @property
    def active(self) -> bool:
        """Whether any actuator is conditioned (else calls return the allocation unchanged)."""
        return bool(self._units)

    def reset(self) -> None:
        """Forget the running directions (start of an episode)."""
        self._dir = [0] * len(self._units)

    def __call__(self, alloc: Allocation) -> Allocation:
        """The allocation with the reversal hysteresis applied (a new one if it changed)."""
        if not self._units:
            return alloc
        command = force = tau = err = None
        for k, (i, ch, h_ahead, h_astern, col) in enumerate(self._units):
            f = float(alloc.force[i])
            d = self._dir[k]
            if d == 0 or f * d >= 0.0:
                if f != 0.0:
                    self._dir[k] = 1 if f > 0.0 else -1
                continue
            if (f > h_ahead) if f > 0.0 else (-f > h_astern):
                self._dir[k] = -d
                continue
            if command is None:
                command, force = alloc.command.copy(), alloc.force.copy()
                tau, err = alloc.tau.copy(), alloc.tau_error.copy()
            assert force is not None and tau is not None and err is not None
            command[ch] = 0.0
            force[i] = 0.0
            for j, b in enumerate(col):
                if b != 0.0:
                    bf = b * f
                    tau[j] -= bf
                    err[j] += bf
        if command is None:
            return alloc
        return Allocation(command, force, tau, err, alloc.saturated)  # type: ignore[arg-type]

    def __repr__(self) -> str:
        return f"ReversalHysteresis(threshold={self.threshold})"


class BatchedReversalHysteresis:
    """:class:`ReversalHysteresis` for ``n`` envs at once, the same operations per env.

    Works on (n, k) arrays (commands, forces, tau, tau_error) and keeps one running direction
    per env and conditioned propeller.
    """

    def __init__(self, actuators: ActuatorSet, threshold: Sequence[float], n: int) -> None:
        self.actuators = actuators
        self.threshold = tuple(float(x) for x in threshold)
        self._units = _Units(actuators, threshold).units
        self.n = int(n)
        self._dir = np.zeros((len(self._units), self.n))

    @property
    def active(self) -> bool:
        return bool(self._units)

    def reset(self, mask: ArrayLike | None = None) -> None:
        """Forget the running directions of every env, or of those where ``mask``."""
        if mask is None:
            self._dir[:] = 0.0
        else:
            self._dir[:, np.asarray(mask, dtype=bool)] = 0.0

    def __call__(
        self, command: NDArray[np.float64], force: NDArray[np.float64], tau: NDArray[np.float64],
        tau_error: NDArray[np.float64],
    ) -> tuple[NDArray[np.float64], ...]:  # fmt: skip
        """``(command, force, tau, tau_error)`` (each (n, k)) after the hysteresis (copies
        where anything changed, else the inputs)."""
        if not self._units:
            return command, force, tau, tau_error
        copied = False
        for k, (i, ch, h_ahead, h_astern, col) in enumerate(self._units):
            f = force[:, i]
            d = self._dir[k]
            same = (d == 0.0) | (f * d >= 0.0)
            big = np.where(f > 0.0, f > h_ahead, -f > h_astern)
            hold = ~same & ~big
            sign = np.where(f > 0.0, 1.0, -1.0)
            # same side: the sign of a non-zero thrust; a reversal: the new side
            np.copyto(d, sign, where=(same & (f != 0.0)) | (~same & big))
            if not hold.any():
                continue
            if not copied:
                command, force = command.copy(), force.copy()
                tau, tau_error = tau.copy(), tau_error.copy()
                copied = True
                f = force[:, i]
            fh = np.where(hold, f, 0.0)
            for j, b in enumerate(col):
                if b != 0.0:
                    bf = b * fh
                    np.subtract(tau[:, j], bf, out=tau[:, j], where=hold)
                    np.add(tau_error[:, j], bf, out=tau_error[:, j], where=hold)
            command[hold, ch] = 0.0
            force[hold, i] = 0.0
        return command, force, tau, tau_error
