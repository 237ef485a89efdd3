r"""Command conditioning of the DP stack: the controller-design parts (not physics).

Design notes: docs/design/controllers.conditioning.md.
Example (the state is per episode: call :meth:`ReversalHysteresis.reset` at its start):

    >>> from shipgym.dynamics.vessel import load_vessel
    >>> from shipgym.controllers.actuation import make_allocator
    >>> v = load_vessel("blue-lady")
    >>> hyst = ReversalHysteresis(v.actuators, [10.0, 0.0, 0.0], idle=0.0)
    >>> alloc = make_allocator(v)
    >>> a1 = hyst(alloc([50.0, 0.0, 0.0], None))  # ahead: passed
    >>> a2 = hyst(alloc([-5.0, 0.0, 0.0], None))  # 5 N astern < 10 N: held at zero
    >>> float(a2.force[0]), float(a2.tau_error[0])
    (0.0, -5.0)
    >>> idling = ReversalHysteresis(v.actuators, [10.0, 0.0, 0.0])  # idles at 5 % instead
    >>> a1 = idling(alloc([50.0, 0.0, 0.0], None))
    >>> a2 = idling(alloc([-5.0, 0.0, 0.0], None))  # 24 rpm ahead, 1.13 N
    >>> round(float(a2.command[0]), 1), round(float(a2.force[0]), 2)
    (24.0, 1.13)
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

__all__ = [
    "IDLE_FRACTION",
    "REVERSAL_FILTER_S",
    "BatchedCommandConditioning",
    "BatchedReversalHysteresis",
    "ReversalHysteresis",
    "reversal_threshold",
]


def reversal_threshold(vessel: Any) -> tuple[float, ...]:
    """The vessel's ``[control] reversal_threshold`` (N per actuator; zeros if unset)."""
    n = len(vessel.actuators)
    h = tuple(float(x) for x in vessel.control.get("reversal_threshold", (0.0,) * n))
    if len(h) != n:
        raise ValueError(f"reversal_threshold must have {n} entries (one per actuator), got {h}")
    return h


#: the idle shaft speed of a conditioned propeller, as a fraction of its command range on
#: each side (so 5 % of n_max ahead, 5 % of |n_min| astern). [chosen]: a running propeller
#: idles instead of stopping when the request drops inside the reversal hysteresis, so that
#: a request wandering about zero does not cycle the shaft stop/start (the law held it at
#: zero before: the Blue Lady's main propeller stood still 31 % of the harbour manoeuvre
#: and restarted 3.0 times a minute, KBF + pid, seeds 0-9). 5 % is 24 rpm ahead on the
#: Blue Lady: 1.1 N of bollard thrust, 0.25 % of the 451 N ahead (10 rpm, 0.2 N astern),
#: small against the surge command's ~20-40 N RMS noise with a kinematic observer, and above
#: the 4 % at which :func:`shipgym.metrics.command_chatter` counts a shaft as started.
IDLE_FRACTION = 0.05

#: the time constant (s) of the low-pass of the allocated thrust that decides a reversal:
#: the propeller reverses when the request is past ``F_h`` on the other side and so is its
#: low-pass (the law filters with the control period ``dt``; without it, the request alone
#: decides). [chosen]: see the measurements of :class:`BatchedReversalHysteresis`.
REVERSAL_FILTER_S = 4.0


class _Units:
    """The hysteresis units of an actuator set, as the arrays the compiled laws read: per
    conditioned propeller ``I[k] = (actuator index, command channel)`` and
    ``H[k] = (F_h ahead (N), F_h astern (N), idle command ahead (> 0), idle command astern
    (< 0), idle bollard thrust ahead (N, >= 0), astern (N, <= 0), its planar or 4-DOF column
    of the thrust configuration)``."""

    def __init__(
        self, actuators: ActuatorSet, threshold: Sequence[float], idle: float = IDLE_FRACTION
    ) -> None:
        h = [float(x) for x in threshold]
        if len(h) != len(actuators):
            raise ValueError(
                f"threshold must have one force (N) per actuator ({len(actuators)}: "
                f"{', '.join(actuators.names)}), got {list(threshold)!r}"
            )
        if not all(math.isfinite(x) and x >= 0.0 for x in h):
            raise ValueError(f"thresholds must be finite forces >= 0 (N; 0: off), got {h!r}")
        if isinstance(idle, bool) or not (isinstance(idle, int | float) and 0.0 <= idle < 1.0):
            raise ValueError(
                f"idle must be a fraction of the command range in [0, 1) (0: stop), got {idle!r}"
            )
        planar = actuators.dofs == 3
        idx, rows = [], []
        for i, a in enumerate(actuators.actuators):
            if h[i] == 0.0 or not isinstance(a, Propeller):
                continue  # azimuths turn instead of reversing; 0: off
            c, s = a.direction
            x, y, _ = a.position
            col = (c, s, x * s - y * c) if planar else (c, s, 0.0, x * s - y * c)
            n_ahead, n_astern = idle * a.upper, idle * a.lower
            f_ahead, f_astern = a.k_ahead * n_ahead, -a.k_astern * abs(n_astern)
            if a.law == "quadratic":
                f_ahead, f_astern = f_ahead * n_ahead, f_astern * abs(n_astern)
            if max(f_ahead, -f_astern) >= h[i]:
                raise ValueError(
                    f"actuator {a.name!r}: the idle thrust ({f_ahead:.3g} N ahead, "
                    f"{-f_astern:.3g} N astern at {idle:g} of the range) must be below the "
                    f"reversal threshold {h[i]:g} N"
                )
            idx.append((i, actuators.slices[i].start))
            # thrust (N) the request must exceed on the new side: ahead, astern (> 0); idle
            rows.append((h[i], h[i], n_ahead, n_astern, f_ahead, f_astern, *col))
        self.I = np.array(idx, dtype=np.int64).reshape(-1, 2)
        self.H = np.array(rows, dtype=float).reshape(len(idx), 6 + (3 if planar else 4))


@njit
def reversal_law(I: Any, H: Any, dirs: Any, low: Any, a: float, force: Any,
                 hold: Any) -> int:  # fmt: skip
    """The running directions ``dirs`` (n, units) after the allocated thrusts ``force``
    (n, actuators) (N), and which units idle ``hold`` (n, units): a request on the other
    side inside the hysteresis or whose low-pass ``low`` (n, units; advanced here,
    ``low += a (F - low)``) is not yet past it, or on the running side below the idle
    thrust; returns how many idle (:class:`BatchedReversalHysteresis`)."""
    held = 0
    for e in range(force.shape[0]):
        for k in range(I.shape[0]):
            f = force[e, I[k, 0]]
            d = dirs[e, k]
            lo = low[e, k] + a * (f - low[e, k])
            low[e, k] = lo
            hold[e, k] = False
            if d == 0.0:  # not yet set: passed
                if f != 0.0:
                    dirs[e, k] = 1.0 if f > 0.0 else -1.0
            elif f * d >= 0.0:  # same side (or zero): passed, at least the idle thrust
                if (f < H[k, 4]) if d > 0.0 else (f > H[k, 5]):
                    hold[e, k] = True
                    held += 1
            elif (
                ((f > H[k, 0]) and (lo > H[k, 0]))
                if f > 0.0
                else ((-f > H[k, 1]) and (-lo > H[k, 1]))
            ):  # the request and its low-pass past the hysteresis: a reversal
                dirs[e, k] = -d
            else:
                hold[e, k] = True
                held += 1
    return held


@njit
def reversal_hold(I: Any, H: Any, dirs: Any, hold: Any, command: Any, force: Any, tau: Any,
                  err: Any) -> None:  # fmt: skip
    """Set the idling units' thrust and command to the idle of their running direction
    ``dirs`` and correct ``tau`` and ``tau_error`` (n, dofs) by the thrust held back
    (``tau -= b (F - F_idle)``, ``tau_error += b (F - F_idle)``)."""
    for e in range(force.shape[0]):
        for k in range(I.shape[0]):
            if not hold[e, k]:
                continue
            i = I[k, 0]
            ahead = dirs[e, k] > 0.0
            f_idle = H[k, 4] if ahead else H[k, 5]
            df = force[e, i] - f_idle
            command[e, I[k, 1]] = H[k, 2] if ahead else H[k, 3]
            force[e, i] = f_idle
            for j in range(H.shape[1] - 6):
                b = H[k, 6 + j]
                if b != 0.0:
                    bf = b * df
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
    """Reversal hysteresis with an idling shaft for propellers, ``n`` envs at once: the one
    run-time form (:class:`ReversalHysteresis` is its ``n = 1`` adapter).

    Per conditioned propeller (a :class:`~shipgym.dynamics.actuators.Propeller` whose
    threshold ``F_h > 0``) and env the state is its running direction ``d`` (+1 ahead, -1
    astern, 0 not yet set). With the idle command ``c_i`` (``idle`` times the command range
    on the running side) and its bollard thrust ``F_i``, for an allocated thrust ``F`` (N):

    - ``d = 0``: ``F`` is passed; ``d = sign(F)`` if ``F != 0`` (the shaft is at rest before
      the first request);
    - ``F d >= 0`` (same side, or zero): ``F`` is passed where ``|F| >= |F_i|``, else the
      propeller idles (command ``d c_i``, thrust ``d F_i``);
    - ``F d < 0``, ``|F| > F_h`` and its low-pass ``F_lp`` also past ``F_h`` on that side
      (``F_lp += a (F - F_lp)`` every call, ``a = dt / (T_r + dt)``, the implicit Euler step
      of a first-order filter of time constant ``T_r``; ``a = 1`` without ``dt``): ``F`` is
      passed and ``d = sign(F)`` (a reversal). The low-pass keeps the surge command's noise
      with a kinematic observer, which crosses ``F_h`` for a few seconds at a time, from
      reversing the propeller, and lets a sustained braking demand through after about
      ``T_r``;
    - otherwise (a request on the other side inside the hysteresis) the propeller idles on
      its running side.

    Idling, the allocation's ``tau`` and ``tau_error`` are corrected by the thrust held back
    (``tau -= b (F - F_i)``, ``tau_error += b (F - F_i)``, ``b`` the actuator's column of the
    thrust configuration), which the controller's anti-windup reads. A running propeller so
    never stops: it reverses (through the hysteresis) or idles, and a request wandering
    about zero cycles neither reversals nor stops and starts. ``idle = 0`` holds the thrust
    at zero instead (a stopped shaft, the law before issue 31).

    Args:
        actuators: the vessel's actuator set.
        threshold: per actuator, the thrust ``F_h`` (N, >= 0) a request in the other
            direction must exceed (0: off; non-propeller actuators are never conditioned).
        n: number of envs, >= 1.
        idle: the idle command as a fraction of the command range on each side, in [0, 1)
            (:data:`IDLE_FRACTION`, [chosen]); its bollard thrust must be below ``F_h``.
        dt: the control period (s) > 0 between calls, or ``None``: no low-pass (a request
            past ``F_h`` reverses at once).
        filter_time: ``T_r`` (s, >= 0), the time constant of the low-pass that decides a
            reversal (:data:`REVERSAL_FILTER_S`, [chosen]; used with ``dt``).

    Measured (issue 31; harbour, 3 m/s from 300 deg, KBF + ``pid``, seeds 0-9, mean [worst
    seed]): the law that held the thrust at zero (40 N, no filter) reversed the main
    propeller 1.06 [1.31] times a minute and left it at zero 31 % of the time with 3.04
    [3.32] starts a minute; idling alone: 1.14 [1.49] reversals, no time at zero. With the
    guidance limited by the thrust capacity (:mod:`shipgym.guidance.limits`) and 50 N: the
    request alone 0.96 [1.14] reversals at J_c 0.158; its 4 s low-pass 0.75-0.80 [0.94-1.02]
    at J_c 0.17-0.18 (the figure of the default stack: 0.80 [0.94], 0.84 [0.97] starts);
    8-15 s or a 60 N threshold no fewer, at a larger J_c (0.19-0.21: the braking comes late
    and overshoots). A dwell (the request past ``F_h`` for 4-12 s on end, restarted when it
    falls back inside) did no better. What is left is the surge loop hunting across the
    hysteresis on the KBF's position noise (period 60-80 s), not single noise spikes.
    """

    def __init__(
        self, actuators: ActuatorSet, threshold: Sequence[float], n: int = 1,
        idle: float = IDLE_FRACTION, *, dt: float | None = None,
        filter_time: float = REVERSAL_FILTER_S,
    ) -> None:  # fmt: skip
        if dt is not None and not (
            not isinstance(dt, bool) and isinstance(dt, int | float) and math.isfinite(dt)
            and dt > 0.0
        ):  # fmt: skip
            raise ValueError(f"dt must be a control period > 0 s or None, got {dt!r}")
        if isinstance(filter_time, bool) or not (
            isinstance(filter_time, int | float) and math.isfinite(filter_time)
            and filter_time >= 0.0
        ):  # fmt: skip
            raise ValueError(f"filter_time must be a time constant >= 0 s, got {filter_time!r}")
        self.dt = None if dt is None else float(dt)
        self.filter_time = float(filter_time) if dt is not None else 0.0
        self._a = 1.0 if dt is None else float(dt) / (self.filter_time + float(dt))
        self.actuators = actuators
        self.threshold = tuple(float(x) for x in threshold)
        u = _Units(actuators, threshold, idle)
        self.idle = float(idle)
        self._I, self._H = u.I, u.H
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ValueError(f"n must be an int >= 1 (the number of envs), got {n!r}")
        self.n = int(n)
        self._dir = np.zeros((self.n, len(u.I)))
        self._low = np.zeros((self.n, len(u.I)))  # (N) the low-pass of the allocated thrust
        self._hold = np.zeros((self.n, len(u.I)), dtype=np.bool_)

    @property
    def active(self) -> bool:
        """Whether any actuator is conditioned (else calls return the allocation unchanged)."""
        return bool(len(self._I))

    def reset(self, mask: ArrayLike | None = None) -> None:
        """Forget the running directions of every env, or of those where ``mask``."""
        if mask is None:
            self._dir[:] = 0.0
            self._low[:] = 0.0
        else:
            m = np.asarray(mask, dtype=bool)
            self._dir[m] = 0.0
            self._low[m] = 0.0

    def __call__(
        self, command: NDArray[np.float64], force: NDArray[np.float64], tau: NDArray[np.float64],
        tau_error: NDArray[np.float64],
    ) -> tuple[NDArray[np.float64], ...]:  # fmt: skip
        """``(command, force, tau, tau_error)`` (each (n, k)) after the hysteresis (copies
        where anything changed, else the inputs)."""
        if not len(self._I):
            return command, force, tau, tau_error
        f = force if force.flags.c_contiguous and force.dtype == np.float64 else _c2(force)
        if not _run("law", reversal_law, self._I, self._H, self._dir, self._low, self._a, f,
                    self._hold):  # fmt: skip
            return command, force, tau, tau_error
        out = (_c2(command), _c2(force), _c2(tau), _c2(tau_error))
        _run("hold", reversal_hold, self._I, self._H, self._dir, self._hold, *out)
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
        idle, dt, filter_time: as :class:`BatchedReversalHysteresis`.
    """

    def __init__(
        self, actuators: ActuatorSet, threshold: Sequence[float], idle: float = IDLE_FRACTION,
        *, dt: float | None = None, filter_time: float = REVERSAL_FILTER_S,
    ) -> None:  # fmt: skip
        self._law = BatchedReversalHysteresis(
            actuators, threshold, 1, idle, dt=dt, filter_time=filter_time
        )
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


class BatchedCommandConditioning:
    """:class:`BatchedReversalHysteresis` on commands that no allocation made: a policy's
    (a learned controller that drives the actuators itself, ``condition_commands=True`` of
    the plan envs), ``n`` envs at once.

    The law decides on thrust, so each conditioned propeller's command ``c`` (rpm, or the
    relative command) is read as its bollard thrust first: ``k c`` (linear law) or
    ``k c |c|`` (quadratic), with the ahead or astern constant ``k`` of its side (the form
    that gives the idle thrust). The propeller then reverses only when the command asks for
    more than ``F_h`` on the other side and so does the low-pass of that thrust; otherwise it
    idles on its running side (command ``idle`` of the range), as the PID's propeller does.
    What it holds is returned as a mask, for the env's ``info``.

    Args:
        actuators: the vessel's actuator set.
        threshold: per actuator, ``F_h`` (N, >= 0; the vessel's ``[control]
            reversal_threshold``); at least one propeller must have ``F_h > 0``.
        n: number of envs, >= 1.
        dt: the control period (s) > 0.
        idle, filter_time: as :class:`BatchedReversalHysteresis`.

    Raises:
        ValueError: no propeller with a threshold (nothing to condition), or a bad argument.
    """

    def __init__(
        self, actuators: ActuatorSet, threshold: Sequence[float], n: int, *, dt: float,
        idle: float = IDLE_FRACTION, filter_time: float = REVERSAL_FILTER_S,
    ) -> None:  # fmt: skip
        self.law = BatchedReversalHysteresis(
            actuators, threshold, n, idle, dt=dt, filter_time=filter_time
        )
        if not self.law.active:
            raise ValueError(
                "command conditioning needs a reversible propeller with a reversal threshold "
                "> 0 N (the vessel's [control] reversal_threshold); this vessel has none: "
                f"threshold {list(threshold)!r}"
            )
        units = self.law._I
        props = [actuators.actuators[int(i)] for i in units[:, 0]]
        self._act = units[:, 0].copy()
        self._ch = units[:, 1].copy()
        self._k_ahead = np.array([p.k_ahead for p in props], dtype=float)
        self._k_astern = np.array([p.k_astern for p in props], dtype=float)
        self._quadratic = np.array([p.law == "quadratic" for p in props])
        self._upper = np.array([p.upper for p in props], dtype=float)
        self._lower = np.array([p.lower for p in props], dtype=float)
        self._n_act = len(actuators)
        self._dofs = actuators.dofs

    def reset(self, mask: ArrayLike | None = None) -> None:
        """Forget the running directions of every env, or of those where ``mask``."""
        self.law.reset(mask)

    def bollard_thrust(self, command: NDArray[np.float64]) -> NDArray[np.float64]:
        """The conditioned propellers' bollard thrust (N) of the commands (n, channels), as
        (n, actuators) (0 for the others)."""
        c = command[:, self._ch]
        k = np.where(c >= 0.0, self._k_ahead, self._k_astern)
        f = k * np.where(self._quadratic, c * np.abs(c), c)
        out = np.zeros((command.shape[0], self._n_act))
        out[:, self._act] = f
        return out

    def __call__(
        self, command: NDArray[np.float64], action: NDArray[np.float64]
    ) -> NDArray[np.bool_]:
        """Condition the physical commands ``command`` (n, channels) and their normalised
        actions ``action`` (n, channels, in [-1, 1]) in place; returns where a command was
        held at the idle, (n, channels)."""
        held = np.zeros(command.shape, dtype=bool)
        force = self.bollard_thrust(command)
        n = command.shape[0]
        zeros = np.zeros((n, self._dofs))
        out = self.law(command, force, zeros, zeros.copy())
        if out[1] is force:  # nothing held
            return held
        new = out[0][:, self._ch]
        old = command[:, self._ch]
        h = new != old
        held[:, self._ch] = h
        command[:, self._ch] = new
        action[:, self._ch] = np.where(
            h, np.where(new >= 0.0, new / self._upper, new / -self._lower), action[:, self._ch]
        )
        return held

    def __repr__(self) -> str:
        return f"BatchedCommandConditioning(n={self.law.n}, threshold={self.law.threshold})"
