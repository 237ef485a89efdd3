r"""Rudder-roll stabilisation (RRS) on the Van der Klugt (1987) model: LQR design, margins, PID.

Public names: ``RRS_WEIGHTS``, ``NOMOTO_FITS``, ``GainSchedule``, ``HeadingAutopilot``,
``HeadingPIDGains``, ``Onset``, ``RollDampingController``, ``closed_loop``, ...
Sources: Van der Klugt (1987); Radhakrishnan (n.d.).

Design notes: docs/design/controllers.rollcontrol.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.frames import wrap_angle
from shipgym.dynamics.vanderklugt import RollModel, roll_model

from .design import lqr

__all__ = [
    "RRS_WEIGHTS",
    "NOMOTO_FITS",
    "GainSchedule",
    "HeadingAutopilot",
    "HeadingPIDGains",
    "Onset",
    "RollDampingController",
    "closed_loop",
    "heading_pid_gains",
    "instability_onset",
    "nomoto_first_order",
    "roll_ratio",
    "rrs_lqr",
    "scheduled_rrs_gains",
    "stability_margin",
]

Array = NDArray[np.float64]

#: The RRS LQR weights [chosen]: ``Q = diag(10, 0, 0.01, 1, 1)`` on ``[v, r, psi, p, phi]``
#: (units 1/(m/s)^2, -, 1/rad^2, 1/(rad/s)^2, 1/rad^2, relative to the rudder weight) and
#: ``R = 1e-3`` (1/rad^2): roll and roll rate weighted equally, a light heading weight that
#: keeps the psi integrator regulated, sway penalised to keep the heading loop robust to speed.
RRS_WEIGHTS: Mapping[str, Any] = MappingProxyType({"Q": (10.0, 0.0, 0.01, 1.0, 1.0), "R": 1.0e-3})

_V, _R, _PSI, _P, _PHI = range(5)


def _gain(K: ArrayLike) -> Array:
    K_ = np.asarray(K, dtype=float).reshape(-1)
    if K_.shape != (5,) or not np.all(np.isfinite(K_)):
        raise ValueError(
            f"K must be 5 finite gains on [v, r, psi, p, phi] (rad per state unit), got {K!r}"
        )
    return K_


def _scaled(K: ArrayLike, sway_scale: float) -> Array:
    if not math.isfinite(sway_scale):
        raise ValueError(f"sway_scale must be finite (1 full, 0 none), got {sway_scale!r}")
    K_ = _gain(K).copy()
    K_[_V] *= sway_scale
    return K_


def rrs_lqr(
    model: RollModel, Q: ArrayLike | None = None, R: float | None = None
) -> tuple[Array, Array, NDArray[np.complex128]]:
    """The continuous full-state LQR of the rudder on the roll model (``u = -K x``).

    Minimises ``int (x^T Q x + R u^2) dt`` with :func:`~shipgym.controllers.design.lqr`
    (scipy's CARE).

    Args:
        model: a :class:`~shipgym.dynamics.vanderklugt.RollModel`.
        Q: (5,) diagonal or (5, 5) state weight; default :data:`RRS_WEIGHTS` ``Q``.
        R: rudder weight (1/rad^2), > 0; default :data:`RRS_WEIGHTS` ``R``.

    Returns:
        ``(K, S, E)``: the gain (5,) (rad per unit of ``[v, r, psi, p, phi]``), the Riccati
        solution (5, 5) and the closed-loop eigenvalues (5,) (1/s). At 8 m/s (reconstructed)
        ``K = [107.74, -5.05, -3.16, -25.07, -29.54]``.

    Raises:
        ValueError: bad shapes or no stabilising solution.
    """
    Q_ = np.asarray(RRS_WEIGHTS["Q"] if Q is None else Q, dtype=float)
    if Q_.ndim == 1:
        Q_ = np.diag(Q_)
    R_ = float(RRS_WEIGHTS["R"] if R is None else R)
    K, S, E = lqr(model.A, model.B.reshape(5, 1), Q_, [[R_]])
    return K.reshape(-1), S, E


def closed_loop(model: RollModel, K: ArrayLike, sway_scale: float = 1.0) -> Array:
    """``A - B K'`` with ``K'`` = ``K`` but the sway gain ``K[0]`` times ``sway_scale``.

    Args:
        model: the plant (at its own speed).
        K: (5,) state-feedback gain (``u = -K x``).
        sway_scale: factor on the sway-velocity gain (1 full, 0.2 scaled, 0 no sway feedback).

    Returns:
        the closed-loop state matrix (5, 5) (1/s).
    """
    return model.A - np.outer(model.B, _scaled(K, sway_scale))


def stability_margin(model: RollModel, K: ArrayLike, sway_scale: float = 1.0) -> float:
    """The largest real part of the closed-loop eigenvalues (1/s); < 0 is stable."""
    return float(np.max(np.linalg.eigvals(closed_loop(model, K, sway_scale)).real))


class Onset(NamedTuple):
    """Where a fixed-gain loop loses stability as the speed grows.

    Attributes:
        speed: the lowest speed (m/s) above which the loop is unstable (to the tolerance).
        frequency: ``|Im|`` of the unstable eigenvalue just above it (rad/s); 0 for a real
            mode.
    """

    speed: float
    frequency: float


def instability_onset(
    K: ArrayLike,
    sway_scale: float = 1.0,
    speeds: tuple[float, float] = (2.0, 30.0),
    kdp_law: str = "U2",
    *,
    tol: float = 1.0e-3,
    grid: float = 0.05,
    model_fn: Callable[..., RollModel] = roll_model,
) -> Onset | None:
    """The lowest speed above which the fixed gain ``K`` gives an unstable loop.

    The loop ``A(U) - B(U) K'`` is checked on a grid of ``grid`` m/s over ``speeds``; the last
    stable grid speed below an unstable tail is refined by bisection to ``tol``.

    Args:
        K: (5,) gain, e.g. the 8 m/s :func:`rrs_lqr` gain.
        sway_scale: factor on the sway gain.
        speeds: ``(U_min, U_max)`` (m/s).
        kdp_law: the ``K_dp`` law of the model.
        tol: bisection tolerance (m/s).
        grid: scan step (m/s); a stable window narrower than it could be missed.
        model_fn: ``model_fn(U, kdp_law=...) -> RollModel`` (the reconstructed model).

    Returns:
        :class:`Onset`, or ``None`` if the loop is stable at ``U_max``. If it is unstable on
        the whole range the onset is ``U_min``.
    """
    lo_U, hi_U = (float(s) for s in speeds)
    if not (0.0 < lo_U < hi_U and math.isfinite(hi_U)):
        raise ValueError(f"speeds must be (U_min, U_max) with 0 < U_min < U_max m/s, got {speeds}")
    if not (tol > 0 and grid > 0):
        raise ValueError("tol and grid must be > 0 m/s")

    def margin(U: float) -> float:
        return stability_margin(model_fn(U, kdp_law=kdp_law), K, sway_scale)

    grid_U = np.linspace(lo_U, hi_U, max(2, int(math.ceil((hi_U - lo_U) / grid)) + 1))
    unstable = np.array([margin(U) >= 0.0 for U in grid_U])
    if not unstable[-1]:
        return None
    stable_idx = np.flatnonzero(~unstable)
    if stable_idx.size == 0:
        a, b = lo_U, lo_U
    else:
        i = int(stable_idx[-1])
        a, b = float(grid_U[i]), float(grid_U[i + 1])
        while b - a > tol:
            mid = 0.5 * (a + b)
            if margin(mid) >= 0.0:
                b = mid
            else:
                a = mid
    eig = np.linalg.eigvals(closed_loop(model_fn(b, kdp_law=kdp_law), K, sway_scale))
    worst = eig[np.argmax(eig.real)]
    return Onset(speed=0.5 * (a + b), frequency=float(abs(worst.imag)))


def roll_ratio(
    model: RollModel, K: ArrayLike, sway_scale: float = 1.0, omega: float = 0.43
) -> float:
    """Closed- over open-loop steady roll amplitude for a sinusoidal rudder disturbance.

    The rudder is ``u = delta_sin - K' x`` (the seed's high-frequency rudder plus the RRS
    feedback), so the roll per unit of ``delta_sin`` is ``[(j w I - A + B K')^-1 B]_phi`` against
    ``[(j w I - A)^-1 B]_phi`` open loop: an exact frequency response (no simulation).

    Args:
        model: the plant.
        K: (5,) gain.
        sway_scale: factor on the sway gain.
        omega: frequency of ``delta_sin`` (rad/s), > 0.

    Returns:
        the amplitude ratio (-); meaningful only for a stable closed loop.
    """
    if not (math.isfinite(omega) and omega > 0):
        raise ValueError(f"omega must be finite and > 0 rad/s, got {omega!r}")
    s = 1j * omega * np.eye(5)
    cl = np.linalg.solve(s - closed_loop(model, K, sway_scale), model.B)[_PHI]
    ol = np.linalg.solve(s - model.A, model.B)[_PHI]
    return float(abs(cl) / abs(ol))


# --------------------------------------------------------------------------------------------
# Gain scheduling
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class GainSchedule:
    """LQR gains designed on a speed grid, interpolated linearly (clamped at the ends).

    Attributes:
        speeds: (n,) increasing design speeds (m/s).
        gains: (n, 5) the gains at those speeds.
    """

    speeds: Array
    gains: Array

    def __call__(self, U: float) -> Array:
        """The gain (5,) at the speed ``U`` (m/s)."""
        if not math.isfinite(U):
            raise ValueError(f"U must be finite (m/s), got {U!r}")
        return np.array([np.interp(U, self.speeds, g) for g in self.gains.T])


def scheduled_rrs_gains(
    speeds: Sequence[float],
    Q: ArrayLike | None = None,
    R: float | None = None,
    model_fn: Callable[[float], RollModel] = roll_model,
) -> GainSchedule:
    """An LQR redesigned at each speed of ``speeds`` (:func:`rrs_lqr`), as a :class:`GainSchedule`.

    Args:
        speeds: increasing design speeds (m/s), at least one.
        Q, R: the weights (default :data:`RRS_WEIGHTS`).
        model_fn: ``U -> RollModel`` (default the reconstructed model, ``"U2"`` law).
    """
    U = np.asarray(speeds, dtype=float).reshape(-1)
    if U.size == 0 or not np.all(np.isfinite(U)) or np.any(np.diff(U) <= 0) or U[0] <= 0:
        raise ValueError(f"speeds must be > 0 m/s, finite and strictly increasing, got {speeds!r}")
    gains = np.stack([rrs_lqr(model_fn(float(u)), Q, R)[0] for u in U])
    return GainSchedule(U, gains)


# --------------------------------------------------------------------------------------------
# Controllers
# --------------------------------------------------------------------------------------------


def _limit(delta_max: float | None) -> float:
    if delta_max is None:
        return math.inf
    d = float(delta_max)
    if not d > 0:
        raise ValueError(f"delta_max must be > 0 rad (the rudder limit), got {delta_max!r}")
    return d


def _heading_and_rate(y: ArrayLike) -> tuple[float, float]:
    y_ = np.asarray(y, dtype=float).reshape(-1)
    if y_.size == 4:  # measured [r, psi, p, phi]
        return float(y_[1]), float(y_[0])
    if y_.size == 5:  # estimated [v, r, psi, p, phi]
        return float(y_[_PSI]), float(y_[_R])
    raise ValueError(
        f"expected the measurement [r, psi, p, phi] (4) or the state [v, r, psi, p, phi] (5), "
        f"got {y_.size} values"
    )


class HeadingPIDGains(NamedTuple):
    """PID gains of :class:`HeadingAutopilot` (``delta = -(kp e + ki int e + kd r)``).

    Attributes:
        kp: rad of rudder per rad of heading error.
        ki: rad of rudder per rad s of integrated error.
        kd: rad of rudder per rad/s of yaw rate.
    """

    kp: float
    ki: float
    kd: float


NOMOTO_FITS = ("first-order", "direct")


def nomoto_first_order(model: Any) -> tuple[float, float]:
    r"""The first-order Nomoto model ``r/delta = K / (1 + T s)`` of a model's yaw response.

    Matched to the yaw-rate/rudder transfer function ``G(s) = c (sI - A')^-1 b`` of the model
    without its heading state (nothing depends on ``psi``) at ``s = 0`` in value and slope:
    ``K = G(0) = -c A'^-1 b`` and ``T = -G'(0)/G(0) = -c A'^-2 b / (c A'^-1 b)``. For the Van
    der Klugt model this is Nomoto's ``T = T_1 + T_2 - T_3`` of ``r/delta = K (1 + T_3 s) /
    ((1 + T_v s)(1 + T_r s))`` with ``K = K_dr + K_vr K_dv`` and ``T_3 = K_dr T_v / K``
    (Nomoto's approximation, Fossen (1995)): the sway path is included.

    Args:
        model: ``A`` (n, n), ``B`` (n,) in the seed's state order (``r`` = 1, ``psi`` = 2).

    Returns:
        ``(K, T)``: yaw-rate gain ((rad/s)/rad) and time constant (s).
    """
    A = np.asarray(model.A, dtype=float)
    b = np.asarray(model.B, dtype=float).reshape(-1)
    keep = [i for i in range(A.shape[0]) if i != _PSI]
    Ar, br = A[np.ix_(keep, keep)], b[keep]
    c = np.zeros(len(keep))
    c[keep.index(_R)] = 1.0
    x1 = np.linalg.solve(Ar, br)
    x2 = np.linalg.solve(Ar, x1)
    K = -float(c @ x1)
    if K == 0.0:
        raise ValueError("the model's rudder has no steady yaw-rate effect: no Nomoto model")
    T = -float(c @ x2) / float(c @ x1)
    return K, T


def heading_pid_gains(
    model: Any,
    bandwidth: float,
    zeta: float = 1.0,
    integral_ratio: float = 0.1,
    nomoto: str = "first-order",
) -> HeadingPIDGains:
    r"""PID heading gains by pole placement on the Nomoto part of the model.

    The heading loop is designed on ``r_dot = -a r + b delta``, ``psi_dot = r``, with

    - ``nomoto="first-order"`` (default): ``a = 1/T``, ``b = K/T`` of the first-order Nomoto
      model of the whole yaw response, sway path included (:func:`nomoto_first_order`);
    - ``nomoto="direct"``: the yaw-rate row alone, ``a = -A[1, 1] = 1/T_r`` and
      ``b = B[1] = K_dr/T_r`` (the sway coupling ``K_vr v`` left out). On the Van der Klugt
      model the sway path carries most of the low-frequency yaw response (``K_vr K_dv`` is
      1.7 x ``K_dr``), so this design is unstable on the full model below about 0.15 rad/s at
      8 m/s; kept for comparison.

    The law ``delta = -(kp e + ki int e + kd r)`` makes the characteristic polynomial
    ``s^3 + (a + b kd) s^2 + b kp s + b ki``, placed at ``(s^2 + 2 zeta w s + w^2)(s + w_i)``
    with ``w = bandwidth`` and ``w_i = integral_ratio w`` (the integral pole a decade below,
    a rule of thumb for PID autopilots, e.g. Fossen (1995))::

        kd = (2 zeta w + w_i - a) / b,  kp = (w^2 + 2 zeta w w_i) / b,  ki = w^2 w_i / b

    The gains carry the sign of ``b`` (negative for ``K_dr < 0``), so the law steers the right
    way for either rudder sign. Check the full loop (its eigenvalues, the roll coupling) for
    the chosen bandwidth.

    Args:
        model: anything with ``A`` (n, n) and ``B`` (n,) in the seed's state order (a
            :class:`~shipgym.dynamics.vanderklugt.RollModel`).
        bandwidth: natural frequency ``w`` of the heading loop (rad/s), > 0.
        zeta: damping ratio (-), > 0.
        integral_ratio: ``w_i / w`` (-), >= 0 (0: PD).
        nomoto: :data:`NOMOTO_FITS`.

    Returns:
        :class:`HeadingPIDGains`.
    """
    if not (math.isfinite(bandwidth) and bandwidth > 0):
        raise ValueError(f"bandwidth must be > 0 rad/s, got {bandwidth!r}")
    if not (math.isfinite(zeta) and zeta > 0):
        raise ValueError(f"zeta must be > 0, got {zeta!r}")
    if not (math.isfinite(integral_ratio) and integral_ratio >= 0):
        raise ValueError(f"integral_ratio must be >= 0, got {integral_ratio!r}")
    if nomoto == "first-order":
        K, T = nomoto_first_order(model)
        a, b = 1.0 / T, K / T
    elif nomoto == "direct":
        a = -float(np.asarray(model.A)[_R, _R])
        b = float(np.asarray(model.B).reshape(-1)[_R])
    else:
        raise ValueError(f"nomoto must be one of {NOMOTO_FITS}, got {nomoto!r}")
    if b == 0.0:
        raise ValueError("the model's rudder has no yaw-rate effect (B[1] = 0): no heading PID")
    w, wi = float(bandwidth), float(bandwidth) * float(integral_ratio)
    return HeadingPIDGains(
        kp=(w**2 + 2.0 * zeta * w * wi) / b, ki=w**2 * wi / b, kd=(2.0 * zeta * w + wi - a) / b
    )


class HeadingAutopilot:
    """PID heading autopilot, ``delta = -(kp e + ki int e + kd r)``, ``e = wrap(psi - psi_d)``.

    The yaw rate is the D term (no differentiated noise). The integral is forward Euler over the
    time between calls and is frozen while the output is at the limit and the error would push
    it further (conditional-integration anti-windup).

    Args:
        kp, ki, kd: the gains (:func:`heading_pid_gains`; signs as the rudder's).
        delta_max: rudder limit (rad), > 0; the output is clipped to ``+-delta_max``.
        psi_d: the default desired heading (rad).
    """

    def __init__(
        self, kp: float, ki: float, kd: float, delta_max: float, psi_d: float = 0.0
    ) -> None:
        for name, g in (("kp", kp), ("ki", ki), ("kd", kd), ("psi_d", psi_d)):
            if not math.isfinite(g):
                raise ValueError(f"{name} must be finite, got {g!r}")
        self.kp, self.ki, self.kd = float(kp), float(ki), float(kd)
        self.delta_max = _limit(delta_max)
        self.psi_d = float(psi_d)
        self.reset()

    def reset(self) -> None:
        """Clear the integral and the time of the last call."""
        self.integral = 0.0
        self._t: float | None = None
        self._saturated = 0.0  # sign of the last saturation (0: none)

    def __call__(self, t: float, y: ArrayLike, psi_d: float | None = None) -> float:
        """The rudder command (rad) at time ``t`` (s).

        Args:
            t: time (s), non-decreasing between calls.
            y: the measurement ``[r, psi, p, phi]`` or the state estimate ``[v, r, psi, p, phi]``
                (rad, rad/s).
            psi_d: desired heading (rad); default the constructor's.
        """
        psi, r = _heading_and_rate(y)
        e = float(wrap_angle(psi - (self.psi_d if psi_d is None else float(psi_d))))
        if self._t is not None:
            dt = float(t) - self._t
            if dt < 0:
                raise ValueError(f"time went backwards: t = {t} after {self._t}")
            # the integral's push on the output is -ki e; hold it while that deepens saturation
            if not (self._saturated != 0.0 and np.sign(-self.ki * e) == self._saturated):
                self.integral += e * dt
        self._t = float(t)
        u = -(self.kp * e + self.ki * self.integral + self.kd * r)
        clipped = float(np.clip(u, -self.delta_max, self.delta_max))
        self._saturated = float(np.sign(u)) if clipped != u else 0.0
        return clipped


class RollDampingController:
    """Full-state RRS feedback ``delta = -K' (x_hat - x_ref)``, ``x_ref = [0, 0, psi_d, 0, 0]``.

    The heading is held through the LQR's ``psi`` state (the error wrapped to ``(-pi, pi]``);
    ``K'`` is ``K`` with the sway gain times ``sway_scale``.

    Args:
        K: (5,) gain (e.g. :func:`rrs_lqr`); ignored when ``schedule`` is given.
        sway_scale: factor on the sway gain (1 full, 0 none).
        schedule: optional ``U -> K`` (a :class:`GainSchedule`); then the call needs ``U``.
        delta_max: rudder limit (rad), or ``None`` for none.
        psi_d: the default desired heading (rad).
    """

    def __init__(
        self,
        K: ArrayLike | None = None,
        sway_scale: float = 1.0,
        schedule: Callable[[float], ArrayLike] | None = None,
        delta_max: float | None = None,
        psi_d: float = 0.0,
    ) -> None:
        if K is None and schedule is None:
            raise ValueError("give the gain K (5,) or a schedule U -> K")
        self.K = None if K is None else _gain(K)
        self.sway_scale = float(sway_scale)
        _scaled(np.zeros(5), self.sway_scale)  # validates
        self.schedule = schedule
        self.delta_max = _limit(delta_max)
        self.psi_d = float(psi_d)

    def reset(self) -> None:
        """Nothing to clear (the law is static); kept for the controller interface."""

    def gain(self, U: float | None = None) -> Array:
        """The gain ``K'`` in use at the speed ``U`` (m/s; needed with a schedule)."""
        if self.schedule is not None:
            if U is None:
                raise ValueError("a scheduled RollDampingController needs the speed U (m/s)")
            return _scaled(self.schedule(float(U)), self.sway_scale)
        assert self.K is not None
        return _scaled(self.K, self.sway_scale)

    def __call__(
        self, t: float, x_hat: ArrayLike, psi_d: float | None = None, U: float | None = None
    ) -> float:
        """The rudder command (rad).

        Args:
            t: time (s) (unused: the law is static).
            x_hat: the state estimate ``[v, r, psi, p, phi]`` (m/s, rad/s, rad, rad/s, rad).
            psi_d: desired heading (rad); default the constructor's.
            U: forward speed (m/s), for a schedule.
        """
        x = np.asarray(x_hat, dtype=float).reshape(-1)
        if x.shape != (5,):
            raise ValueError(f"x_hat must be [v, r, psi, p, phi] (5), got {x.size} values")
        e = x.copy()
        e[_PSI] = wrap_angle(x[_PSI] - (self.psi_d if psi_d is None else float(psi_d)))
        u = -float(self.gain(U) @ e)
        return float(np.clip(u, -self.delta_max, self.delta_max))
