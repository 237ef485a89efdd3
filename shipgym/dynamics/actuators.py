r"""Actuator kinds and the :class:`ActuatorSet` of a vessel: one thrust law per kind.

Thrust laws ``F = k a`` or ``F = k |a| a`` (Tomera 2014 eqs. 8-9); ``X = F_x``, ``Y = F_y``,
``K = -z F_y``, ``N = x F_y - y F_x``.

Public names: ``ACTUATOR_KINDS``, ``Actuator``, ``ActuatorSet``, ``Azimuth``, ``Channel``,
``MMGPropulsion``, ``Propeller``, ``Rudder``, ...
Sources: Tomera (2014); Fossen (2011); Blanke (1981); Fossen (2021); Johansen & Fossen (2013);
Blanke & Christensen (1993).

Design notes: docs/design/dynamics.actuators.md.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._jit import LAW_SIG, address, entry, law_at, njit
from .mmg import propeller_side_force, rudder_normal_coefficient

__all__ = [
    "ACTUATOR_KINDS",
    "Actuator",
    "ActuatorSet",
    "Azimuth",
    "Channel",
    "MMGPropulsion",
    "Propeller",
    "Rudder",
    "law_azimuth",
    "law_mmg",
    "law_propeller",
    "law_rudder",
    "tau_of_table",
]


@dataclass(frozen=True)
class Channel:
    """One MuJoCo actuator of an actuator: command range, unit and dynamics.

    Attributes:
        name: MuJoCo actuator name (the actuator's name, or ``NAME_angle`` etc.).
        unit: unit of the command and of the state (e.g. ``"rpm"``, ``"1"``, ``"rad/s"``).
        lower, upper: command range (``lower <= 0 <= upper`` or ``0 <= lower``).
        dynamics: ``"lag"`` (first-order lag of the state to the command, ``time_constant``),
            ``"integrator"`` (the state integrates the command: an angle from a rate) or
            ``"servo"`` (the command is an angle the state follows at a rate limited to
            ``+-rate``: ``state_dot = clip((command - state) / T, -rate, rate)`` with
            ``T = time_constant``, or the physics step when ``time_constant`` is 0: an ideal
            rate-limited servo; MuJoCo integrates the rate, :mod:`shipgym.envs.physics`).
        time_constant: lag time constant (s), ``nan`` for an integrator, ``>= 0`` for a servo.
        state_unit: unit of the state (differs from ``unit`` for an integrator).
        rate: largest rate of a servo's state (state unit per second); of a lag's state, its
            rate limit (``state_dot = clip((command - state) / T, -rate, rate)``), ``nan``
            for none.
    """

    name: str
    unit: str
    lower: float
    upper: float
    dynamics: str = "lag"
    time_constant: float = math.nan
    state_unit: str = ""
    rate: float = math.nan

    def __post_init__(self) -> None:
        if not (math.isfinite(self.lower) and math.isfinite(self.upper)):
            raise ValueError(f"{self.name}: command range must be finite")
        if not self.lower < self.upper:
            raise ValueError(f"{self.name}: command range needs lower < upper, got "
                             f"[{self.lower}, {self.upper}]")  # fmt: skip
        if self.dynamics not in ("lag", "integrator", "servo"):
            raise ValueError(f"{self.name}: unknown dynamics {self.dynamics!r}")
        if self.dynamics == "servo" and not (self.time_constant >= 0 and self.rate > 0):
            raise ValueError(
                f"{self.name}: a servo needs time_constant >= 0 s and rate > 0, got "
                f"{self.time_constant}, {self.rate}"
            )
        if self.dynamics == "lag" and not self.time_constant > 0:
            raise ValueError(f"{self.name}: time_constant must be > 0 s, got {self.time_constant}")
        if not self.state_unit:
            object.__setattr__(self, "state_unit", self.unit)


class Actuator:
    """Protocol of an actuator kind (a frozen dataclass subclass)."""

    kind: ClassVar[str] = ""
    #: whether the force depends on the flow past the hull (``force(states, nu)``); MuJoCo's
    #: actuator then carries no force and the physics adds it (:meth:`ActuatorSet.law_table`)
    flow_dependent: ClassVar[bool] = False
    #: the kind's compiled force law (:data:`shipgym._jit.LAW_SIG`; a ``staticmethod`` of a
    #: module-level :func:`~shipgym._jit.njit` function), with :meth:`law_row` its constants
    #: (:meth:`ActuatorSet.law_table`). Named ``force_law``: a :class:`Propeller`'s ``law`` is
    #: its thrust law's name (``"linear"``, ``"quadratic"``).
    force_law: ClassVar[Any] = None
    name: str
    position: tuple[float, float, float]
    colour: str

    @property
    def label(self) -> str:
        """The kind as a vessel file names it (``propeller``, ``tunnel``, ``azimuth``)."""
        return self.kind

    def law_row(self, channel: int) -> tuple[float, ...]:  # pragma: no cover - protocol
        """The row of :attr:`force_law`: ``channel`` (the index of this actuator's first
        channel in the state vector, as a float) first, then the law's constants."""
        raise NotImplementedError

    def rest_state(self) -> tuple[float, ...]:
        """Its channels' states after a reset: no force (zeros; a kind with another rest
        state, such as an azimuth's angle, says so)."""
        return (0.0,) * len(self.channels)

    @property
    def channels(self) -> tuple[Channel, ...]:  # pragma: no cover - protocol
        raise NotImplementedError

    def force(self, states: NDArray[np.float64]) -> tuple[Any, Any]:  # pragma: no cover
        """Body force ``(F_x, F_y)`` (N) from this actuator's states (..., n_channels)."""
        raise NotImplementedError

    def thrust(self, states: NDArray[np.float64]) -> Any:  # pragma: no cover
        """Signed thrust magnitude (N) along the actuator's direction."""
        raise NotImplementedError

    @property
    def max_thrust(self) -> float:  # pragma: no cover
        """Largest thrust magnitude (N), either direction."""
        raise NotImplementedError


def _check_position(name: str, position: Any) -> tuple[float, float, float]:
    try:
        p = tuple(float(v) for v in position)
    except (TypeError, ValueError):
        raise ValueError(f"actuator {name!r}: position must be [x, y, z] in m") from None
    if len(p) == 2:
        p = (*p, 0.0)
    if len(p) != 3 or not all(math.isfinite(v) for v in p):
        raise ValueError(f"actuator {name!r}: position must be 3 finite numbers [x, y, z] (m)")
    return p  # type: ignore[return-value]


# ---- compiled force laws ---------------------------------------------------------------------
# One law per kind, of the signature shipgym._jit.LAW_SIG: ``law(row, st, u, v, p, r) -> (X, Y,
# K, N, F, flag)``, ``row[0]`` the index of the actuator's first channel in ``st``, the rest its
# constants (each kind's ``law_row``), ``(u, v, p, r)`` the body velocity through the water.
# Plain float arithmetic on the same expressions, in the same order, as the kinds' array forms
# (Propeller.thrust, Azimuth.force, Rudder.lift, MMGModel.propulsion_forces), which the tests
# compare them with.


@njit
def law_propeller(row, st, u, v, p, r):  # type: ignore[no-untyped-def]
    """A :class:`Propeller` (or tunnel): the bollard law ``g a`` (linear) or ``g |a| a``
    (quadratic), ``g`` = ``k_ahead`` for ``a >= 0`` else ``k_astern``; minus the advance-speed
    term ``k_u (1 - w) |a| u``; times the tunnel factor ``1 - d x^2 exp(1 - x^2)``, ``x = u /
    U_50``; along ``(cos alpha, sin alpha)`` at ``(x, y, z)`` (row: :meth:`Propeller.law_row`)."""
    a = st[int(row[0])]
    g = row[1] if a >= 0.0 else row[2]
    aa = abs(a)
    if row[3] != 0.0:  # quadratic: (k |a|) a
        g = g * aa
    f = g * a
    if row[4] != 0.0:  # advance-speed loss
        f = f - row[4] * aa * u
    if row[5] != 0.0:  # tunnel loss with forward speed
        xu = u / row[6]
        x2 = xu * xu
        f = (1.0 - row[5] * x2 * math.exp(1.0 - x2)) * f
    fx = row[7] * f
    fy = row[8] * f
    return fx, fy, -row[11] * fy, row[9] * fy - row[10] * fx, f, 0.0


@njit
def law_azimuth(row, st, u, v, p, r):  # type: ignore[no-untyped-def]
    """An :class:`Azimuth`: ``F = F_max a`` along the angle state ``alpha`` (channels ``[a,
    alpha]``), at ``(x, y, z)`` (row: :meth:`Azimuth.law_row`)."""
    j = int(row[0])
    f = row[1] * st[j]
    alpha = st[j + 1]
    fx = f * math.cos(alpha)
    fy = f * math.sin(alpha)
    return fx, fy, -row[4] * fy, row[2] * fy - row[3] * fx, f, 0.0


@njit
def law_rudder(row, st, u, v, p, r):  # type: ignore[no-untyped-def]
    """A :class:`Rudder`: lift ``F = k_L q C(alpha_e)`` (:meth:`Rudder.flow`,
    :meth:`Rudder.lift`; ``q = sign(u) (u^2 + v_R^2)`` with inflow, ``u |u|`` without), ``Y =
    F``, ``K = -z F``, ``N = x F``; ``flag`` 1 where stalled (row: :meth:`Rudder.law_row`)."""
    delta = st[int(row[0])]
    x = row[2]
    z = row[3]
    if row[6] != 0.0:  # the hull's motion changes the inflow
        vr = v + x * r - z * p
        sg = 1.0 if u > 0.0 else (-1.0 if u < 0.0 else 0.0)  # numpy's sign(u)
        q = sg * (u * u + vr * vr)
        alpha = delta - math.atan2(vr, abs(u))
    else:
        q = u * abs(u)
        alpha = delta
    flag = 0.0
    c = alpha
    if abs(alpha) > row[4]:  # stalled (never with an infinite stall angle)
        flag = 1.0
        c = row[5] if alpha > 0.0 else -row[5]
    f = row[1] * q * c
    return 0.0, f, -z * f, x * f, f, flag


@njit
def law_mmg(row, st, u, v, p, r):  # type: ignore[no-untyped-def]
    """An :class:`MMGPropulsion` unit (channels ``[n, delta]``, the paper's rudder angle
    ``-delta``): :meth:`~shipgym.dynamics.mmg.MMGModel.propulsion_forces`
    on plain floats; ``K = 0`` (planar), ``F`` the propeller thrust ``T`` (row:
    :meth:`MMGPropulsion.law_row`)."""
    j = int(row[0])
    n = st[j]
    delta = -st[j + 1]
    L, rho, D, D4 = row[1], row[2], row[3], row[4]
    k0, k1, k2 = row[5], row[6], row[7]
    w0, C1, C2p, C2n, xP = row[8], row[9], row[10], row[11], row[12]
    tP, cy, xPL = row[13], row[14], row[15]
    tR, aH, arm = row[16], row[17], row[18]
    eta, kap, eps, gn, gp, lR = row[19], row[20], row[21], row[22], row[23], row[24]
    hA, fa = row[25], row[26]
    cyb, stall, post = row[27], row[28], row[29]
    U = math.sqrt(u * u + v * v)
    Us = U if U > 1e-9 else 1e-9
    rp = r * L / Us
    beta = math.atan2(-v, u)
    # propeller: K_T(J_P) with the wake 1 - w_P(beta_P), T = rho n^2 D^4 K_T without dividing
    # by n (a stopped shaft drags); astern K_T; the side force (propeller_side_force)
    bP = beta - xP * rp
    one_w = w0 * (1.0 + (1.0 - math.exp(-C1 * abs(bP))) * ((C2p if bP > 0.0 else C2n) - 1.0))
    na = abs(n)
    ua = u * one_w
    J = ua / ((na if na > 1e-9 else 1e-9) * D)
    ahead = n > 0.0
    if n >= 0.0:
        T = rho * (k0 * (n * n) * D4 + k1 * n * (D4 / D) * ua + k2 * (D * D) * (ua * ua))
    else:
        T = -rho * (0.2 * (n * n) * D4 + 0.25 * na * (D4 / D) * ua)
    XP = (1.0 - tP) * T
    YP = propeller_side_force(n, XP, cy, cyb)
    NP = xPL * YP
    # rudder: inflow with the propeller's slipstream (ahead only), flow straightening
    uR = eps * ua
    if ahead:
        Js = J if abs(J) > 1e-9 else 1e-9
        KT = T / (rho * (n * n) * D4)
        race = 1.0 + 8.0 * KT / (math.pi * (Js * Js))
        race = math.sqrt(race) if race > 0.0 else 0.0
        sq = 1.0 + kap * (race - 1.0)
        uR = uR * math.sqrt(eta * (sq * sq) + 1.0 - eta)
    bR = beta - lR * rp
    vR = U * (gn if bR < 0.0 else gp) * bR
    # F_N = (rho A_R / 2) U_R^2 C_N(alpha_R), alpha_R = delta - atan2(v_R, u_R)
    sd = math.sin(delta)
    cd = math.cos(delta)
    alpha = delta - math.atan2(vR, uR)
    FN = hA * (uR * uR + vR * vR) * rudder_normal_coefficient(alpha, fa, stall, post)
    XR = -(1.0 - tR) * FN * sd
    YR = -(1.0 + aH) * FN * cd
    NR = -arm * FN * cd
    return XP + XR, YP + YR, 0.0, NP + NR, T, 0.0


@njit(inline="always")
def channel_command(v, lo, hi):  # type: ignore[no-untyped-def]
    """A channel's physical command of its normalised action ``v`` in ``[-1, 1]``, its range
    ``[lo, hi]``: a range around zero is scaled on each side (``v >= 0 -> v hi``, ``v < 0 ->
    v |lo|``), another one mapped affinely (-1 -> lo, 1 -> hi). The one compiled form of
    :meth:`ActuatorSet.action_to_command`, inlined where compiled code needs it."""
    if lo < 0.0:
        return v * hi if v >= 0.0 else v * -lo
    return lo + 0.5 * (v + 1.0) * (hi - lo)


@njit
def action_commands(a, lo, hi, out):  # type: ignore[no-untyped-def]
    """:func:`channel_command` of every row of the actions ``a`` (n, n_channels), the
    channels' ranges ``lo``, ``hi`` (n_channels,), into ``out`` (n, n_channels)."""
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            out[i, j] = channel_command(a[i, j], lo[j], hi[j])


@njit(inline="always")
def channel_action(c, lo, hi):  # type: ignore[no-untyped-def]
    """A channel's normalised action of its physical command ``c``, its range ``[lo, hi]``:
    the inverse of :func:`channel_command` (``c >= 0 -> c / hi``, ``c < 0 -> c / |lo|``
    around zero, else affine). The one compiled form of :meth:`ActuatorSet.command_to_action`,
    inlined where compiled code needs it."""
    if lo < 0.0:
        return c / hi if c >= 0.0 else c / -lo
    return 2.0 * (c - lo) / (hi - lo) - 1.0


@njit
def command_actions(c, lo, hi, out):  # type: ignore[no-untyped-def]
    """:func:`channel_action` of every row of the commands ``c`` (n, n_channels), the
    channels' ranges ``lo``, ``hi`` (n_channels,), into ``out`` (n, n_channels)."""
    for i in range(c.shape[0]):
        for j in range(c.shape[1]):
            out[i, j] = channel_action(c[i, j], lo[j], hi[j])


@njit(inline="always")
def tau_of_table(table, laws, kind_index, st, u, v, p, r, forces, flags):  # type: ignore[no-untyped-def]
    """The generalised force ``(X, Y, K, N)`` (N, N, N m, N m) of every actuator of a
    :meth:`ActuatorSet.law_table` at the actuator states ``st`` and the body velocity through
    the water ``(u, v, p, r)``, summed in actuator order; actuator ``a``'s own force ``F`` (N)
    is written to ``forces[a]`` and its stall flag (1.0 or 0.0) to ``flags[a]``. ``laws``:
    the addresses of the compiled laws (int64, :func:`shipgym._jit.address`)."""
    X = 0.0
    Y = 0.0
    K = 0.0
    N = 0.0
    for a in range(table.shape[0]):
        law = law_at(laws[kind_index[a]])
        fx, fy, fk, fn, fa, fl = law(table[a], st, u, v, p, r)
        X += fx
        Y += fy
        K += fk
        N += fn
        forces[a] = fa
        flags[a] = fl
    return X, Y, K, N


@njit
def _bollard_inverse(f, k_ahead, k_astern, quadratic, out):  # type: ignore[no-untyped-def]
    """:func:`bollard_inverse` over rows: ``f`` (N, n), constants (n,), ``out`` (N, n)."""
    for i in range(f.shape[0]):
        for j in range(f.shape[1]):
            x = f[i, j]
            k = k_ahead[j] if x >= 0.0 else k_astern[j]
            if quadratic[j]:
                sg = 1.0 if x > 0.0 else (-1.0 if x < 0.0 else x)  # numpy's sign (0, NaN kept)
                out[i, j] = sg * math.sqrt(abs(x) / k)
            else:
                out[i, j] = x / k


def bollard_inverse(force: Any, k_ahead: Any, k_astern: Any, quadratic: Any) -> Any:
    """The state (command) that gives the bollard thrust ``force`` (N) of a propeller's law
    (:class:`Propeller`: ``F = k a`` linear, ``F = k |a| a`` quadratic; ``k = k_ahead`` for
    ``F >= 0``, else ``k_astern``), unsaturated. ``force`` (..., n) with the constants (n,)
    (one call inverts a set's propellers over N requests), or any shape with scalar
    constants; the result has the shape of ``force`` (a float for a scalar)."""
    f = np.asarray(force, dtype=float)
    ka, kb = np.atleast_1d(np.asarray(k_ahead, float)), np.atleast_1d(np.asarray(k_astern, float))
    q = np.atleast_1d(np.asarray(quadratic, dtype=np.bool_))
    n = ka.size
    rows = np.ascontiguousarray(f.reshape(-1, n) if n > 1 else f.reshape(-1, 1))
    out = np.empty_like(rows)
    bollard_inverse_rows(rows, ka, kb, q, out)
    return out.reshape(f.shape) if f.ndim else out[0, 0]


def bollard_inverse_rows(force: Any, k_ahead: Any, k_astern: Any, quadratic: Any, out: Any) -> None:
    """:func:`bollard_inverse` of the rows ``force`` (N, n) into ``out`` (N, n), the constants
    (n,) as C-contiguous float64 (``quadratic`` bool) arrays: the compiled law without the
    conversions (an allocator's hot path, its constants prepared once)."""
    args = (force, k_ahead, k_astern, quadratic, out)
    if not _INVERSE:
        _INVERSE.append(entry(_bollard_inverse, args))
    _INVERSE[0](*args)


_INVERSE: list[
    Any
] = []  # _bollard_inverse's compiled entry point (its argument types never change)


@dataclass(frozen=True)
class Propeller(Actuator):
    r"""A fixed-direction thruster: main propeller (``alpha = 0``) or tunnel (90 deg).

    Thrust of the state ``a`` at the surge speed through the water ``u_r`` (m/s):

    .. math::

        F = \eta(|u_r|)\,\bigl(F_0(a) - k_u |a|\,(1 - w)\,u_r\bigr),\qquad
        \eta(U) = 1 - d\,x^2\,e^{1 - x^2},\quad x = U / U_{50}

    with the bollard law ``F_0`` (``law``), the advance-speed term of Blanke (1981)
    (Fossen 2021 ch. 9: ``T = T_nn |n| n - T_nu |n| u_a``, ``u_a = (1 - w) u_r``; the linear
    ``K_T(J)`` of a fixed-pitch propeller, ahead and astern alike) and the tunnel thruster's
    loss with forward speed ``eta`` (1 at rest and flat at low speed, its minimum ``1 - d`` at
    ``U_50``, back to 1 at high speed; the curve of the model tests of a tanker's bow
    thruster, KMW/HyA, International Shipbuilding Progress 1967). ``k_u = 0`` and ``d = 0``
    (the defaults) give the bollard law at every speed; either makes the propeller flow-dependent
    (:attr:`flow_dependent`): its force then comes from :meth:`ActuatorSet.law_table`.

    The state follows its command through a first-order lag whose rate is limited to
    ``rate_limit`` (state unit per second; ``inf``: none): ``a_dot = clip((c - a) / T,
    -rate_limit, rate_limit)`` (an engine's or a thruster motor's ramp).

    Attributes:
        name: actuator (and MuJoCo actuator) name.
        position: ``(x, y, z)`` of the thrust's point of action (m, body frame, z down).
        alpha: thrust direction (rad) from the bow, positive to starboard.
        law: ``"linear"`` (``F = k a``) or ``"quadratic"`` (``F = k |a| a``).
        k_ahead, k_astern: thrust coefficients (N per command unit, or per unit^2) for
            ``a >= 0`` and ``a < 0``; both > 0.
        lower, upper: command range (``lower < 0 < upper``), in ``unit``.
        unit: command unit (``"rpm"`` for a shaft speed, ``"1"`` for relative thrust).
        time_constant: first-order lag of the state to the command (s).
        colour: plot colour (``#rrggbb``).
        tunnel: a tunnel thruster (a label for listings and plots).
        advance: ``k_u`` (N per state unit per m/s; 0: no advance-speed loss).
        wake: wake fraction ``w`` (0 to < 1) of the advance speed ``u_a = (1 - w) u_r``.
        loss_speed: ``U_50`` (m/s), the surge speed of the largest loss of :math:`\eta`.
        loss_depth: ``d`` (0 to 1), the largest relative loss (0: none).
        rate_limit: largest rate of the state (state unit per s, ``inf``: none).
    """

    kind: ClassVar[str] = "propeller"
    force_law: ClassVar[Any] = staticmethod(law_propeller)
    name: str = ""
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    alpha: float = 0.0
    law: str = "linear"
    k_ahead: float = 1.0
    k_astern: float = 1.0
    lower: float = -1.0
    upper: float = 1.0
    unit: str = "1"
    time_constant: float = 1.0
    colour: str = "#1f77b4"
    tunnel: bool = False
    advance: float = 0.0
    wake: float = 0.0
    loss_speed: float = 1.0
    loss_depth: float = 0.0
    rate_limit: float = math.inf
    _c: float = field(init=False, repr=False, compare=False)
    _s: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", _check_position(self.name, self.position))
        if self.law not in ("linear", "quadratic"):
            raise ValueError(
                f"actuator {self.name!r}: law must be 'linear' or 'quadratic', got {self.law!r}"
            )
        for k in ("k_ahead", "k_astern", "time_constant"):
            v = getattr(self, k)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ValueError(f"actuator {self.name!r}: {k} must be > 0, got {v!r}")
        if not (self.lower < 0.0 < self.upper):
            raise ValueError(
                f"actuator {self.name!r}: the command range must contain zero "
                f"(lower < 0 < upper), got [{self.lower}, {self.upper}]"
            )
        if not math.isfinite(self.alpha):
            raise ValueError(f"actuator {self.name!r}: alpha must be finite")
        checks = (
            ("advance", self.advance, lambda v: v >= 0.0 and math.isfinite(v), ">= 0"),
            ("wake", self.wake, lambda v: 0.0 <= v < 1.0, "from 0 to below 1"),
            ("loss_speed", self.loss_speed, lambda v: v > 0.0 and math.isfinite(v), "> 0 m/s"),
            ("loss_depth", self.loss_depth, lambda v: 0.0 <= v <= 1.0, "from 0 to 1"),
            ("rate_limit", self.rate_limit, lambda v: v > 0.0, "> 0 (inf: none)"),
        )
        for k, v, ok, what in checks:
            if isinstance(v, bool) or not isinstance(v, int | float) or math.isnan(v) or not ok(v):
                raise ValueError(f"actuator {self.name!r}: {k} must be {what}, got {v!r}")
        object.__setattr__(self, "_c", math.cos(self.alpha))
        object.__setattr__(self, "_s", math.sin(self.alpha))

    @property
    def label(self) -> str:
        return "tunnel" if self.tunnel else "propeller"

    @property
    def flow_dependent(self) -> bool:  # type: ignore[override]
        """Whether the thrust depends on the speed through the water (advance or loss)."""
        return self.advance > 0.0 or self.loss_depth > 0.0

    @property
    def channels(self) -> tuple[Channel, ...]:
        return (
            Channel(
                self.name,
                self.unit,
                self.lower,
                self.upper,
                "lag",
                self.time_constant,
                rate=self.rate_limit if math.isfinite(self.rate_limit) else math.nan,
            ),
        )

    def bollard(self) -> Propeller:
        """This propeller with the bollard law at every speed and no rate limit."""
        return dataclasses.replace(self, advance=0.0, loss_depth=0.0, rate_limit=math.inf)

    def efficiency(self, u_r: Any) -> Any:
        """The tunnel factor ``eta(|u_r|)`` (1 without a loss) at the surge speed ``u_r``."""
        if self.loss_depth == 0.0:
            return np.ones_like(np.asarray(u_r, dtype=float))
        x2 = (np.asarray(u_r, dtype=float) / self.loss_speed) ** 2
        return 1.0 - self.loss_depth * x2 * np.exp(1.0 - x2)

    @property
    def direction(self) -> tuple[float, float]:
        """Unit thrust direction ``(cos alpha, sin alpha)`` in the body frame."""
        c, s = self._c, self._s
        # exact axes for the usual mounting angles (0, +-90, 180 deg)
        return (0.0 if abs(c) < 1e-15 else c, 0.0 if abs(s) < 1e-15 else s)

    @property
    def static_gain(self) -> float | None:
        """MuJoCo's constant actuator gain (N per state unit), ``None`` if state-dependent."""
        if self.law == "linear" and self.k_ahead == self.k_astern:
            return self.k_ahead
        return None

    def gain(self, a: Any) -> Any:
        """``F / a`` (N per state unit): the MuJoCo actuator gain at state ``a``."""
        k = np.where(np.asarray(a) >= 0, self.k_ahead, self.k_astern)
        return k * np.abs(a) if self.law == "quadratic" else k * np.ones_like(np.asarray(a, float))

    def thrust(self, states: NDArray[np.float64], nu: ArrayLike | None = None) -> Any:
        """Signed thrust (N) of the states (..., 1) at the body velocity through the water
        ``nu`` (``[u, v, r]`` or ``[u, v, p, r]``; ``None``: at rest, the bollard law)."""
        a = np.asarray(states, dtype=float)[..., 0]
        f = self.gain(a) * a
        if nu is None or not self.flow_dependent:
            return f
        ur = np.asarray(nu, dtype=float)[..., 0]
        f = f - self.advance * (1.0 - self.wake) * np.abs(a) * ur
        return self.efficiency(ur) * f

    def inverse(self, force: ArrayLike) -> NDArray[np.float64]:
        """The state (command) that gives the bollard thrust ``force`` (N), unsaturated (the
        design model of the allocation: the advance-speed and tunnel losses are left out)."""
        return bollard_inverse(force, self.k_ahead, self.k_astern, self.law == "quadratic")

    def force(self, states: NDArray[np.float64], nu: ArrayLike | None = None) -> tuple[Any, Any]:
        f = self.thrust(states, nu)
        c, s = self.direction
        return c * f, s * f

    @property
    def force_lower(self) -> float:
        """Thrust (N) at the lower end of the command range (negative: astern)."""
        return float(self.thrust(np.array([self.lower])))

    @property
    def force_upper(self) -> float:
        """Thrust (N) at the upper end of the command range."""
        return float(self.thrust(np.array([self.upper])))

    @property
    def max_thrust(self) -> float:
        return max(self.force_upper, -self.force_lower)

    def law_row(self, channel: int) -> tuple[float, ...]:
        """The row of :func:`law_propeller` (12 values): ``channel``, ``k_ahead``,
        ``k_astern`` (N per state unit, or per unit^2), ``quadratic`` (1.0 for ``k |a| a``,
        0.0 linear), ``k_u (1 - w)`` (N per state unit per m/s; 0: no advance-speed loss),
        ``d`` (1; 0: no tunnel loss), ``U_50`` (m/s), ``cos alpha``, ``sin alpha``
        (:attr:`direction`), ``x``, ``y``, ``z`` (m, body frame, z down)."""
        c, s = self.direction
        x, y, z = self.position
        return (
            float(channel), float(self.k_ahead), float(self.k_astern),
            1.0 if self.law == "quadratic" else 0.0, self.advance * (1.0 - self.wake),
            float(self.loss_depth), float(self.loss_speed), c, s, x, y, z,
        )  # fmt: skip


@dataclass(frozen=True)
class Azimuth(Actuator):
    """An azimuth thruster: thrust along an angle that turns at a limited rate.

    Channels: ``NAME`` (relative thrust ``a`` in ``[lower, 1]``, first-order lag
    ``time_constant``; ``lower = -1`` for a reversible (variable-pitch) unit, 0 otherwise)
    and ``NAME_angle`` (command: the turning rate in rad/s, ``+-max_rate``; state: the angle
    ``alpha`` in rad from the bow, positive to starboard, continuous). Thrust
    ``F = max_thrust a`` along ``(cos alpha, sin alpha)``.

    Attributes:
        name, position, colour: as for :class:`Propeller`.
        max_thrust_n: largest thrust (N).
        lower: lower end of the relative-thrust command (-1 reversible, 0 ahead only).
        time_constant: lag of the thrust (s).
        max_rate: largest turning rate (rad/s).
        angle0: angle at rest (rad), the state after a reset.
    """

    kind: ClassVar[str] = "azimuth"
    force_law: ClassVar[Any] = staticmethod(law_azimuth)
    name: str = ""
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    max_thrust_n: float = 1.0
    lower: float = -1.0
    time_constant: float = 1.0
    max_rate: float = math.radians(10.0)
    angle0: float = 0.0
    colour: str = "#1f77b4"

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", _check_position(self.name, self.position))
        for k in ("max_thrust_n", "time_constant", "max_rate"):
            v = getattr(self, k)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ValueError(f"actuator {self.name!r}: {k} must be > 0, got {v!r}")
        if self.lower not in (-1.0, 0.0):
            raise ValueError(
                f"actuator {self.name!r}: lower must be -1 (reversible) or 0, got {self.lower!r}"
            )
        if not math.isfinite(self.angle0):
            raise ValueError(f"actuator {self.name!r}: angle0 must be finite")

    def rest_state(self) -> tuple[float, ...]:
        """No thrust, the angle at rest (:attr:`angle0`, rad)."""
        return (0.0, self.angle0)

    @property
    def reversible(self) -> bool:
        """Whether the thrust can be reversed (variable pitch)."""
        return self.lower < 0

    @property
    def channels(self) -> tuple[Channel, ...]:
        return (
            Channel(self.name, "1", self.lower, 1.0, "lag", self.time_constant),
            Channel(
                self.name + "_angle", "rad/s", -self.max_rate, self.max_rate, "integrator",
                state_unit="rad",
            ),
        )  # fmt: skip

    def thrust(self, states: NDArray[np.float64]) -> Any:
        return self.max_thrust_n * np.asarray(states, dtype=float)[..., 0]

    def force(self, states: NDArray[np.float64]) -> tuple[Any, Any]:
        s = np.asarray(states, dtype=float)
        f = self.max_thrust_n * s[..., 0]
        return f * np.cos(s[..., 1]), f * np.sin(s[..., 1])

    @property
    def max_thrust(self) -> float:
        return float(self.max_thrust_n)

    def law_row(self, channel: int) -> tuple[float, ...]:
        """The row of :func:`law_azimuth` (5 values): ``channel`` (the thrust channel; the
        angle is the next), ``max_thrust_n`` (N), ``x``, ``y``, ``z`` (m, body frame, z
        down)."""
        x, y, z = self.position
        return (float(channel), float(self.max_thrust_n), x, y, z)


@dataclass(frozen=True)
class Rudder(Actuator):
    r"""A rudder: a lifting foil whose force grows with the square of the flow speed.

    One channel ``NAME``: the command is the rudder angle ``delta_c`` (rad, ``+-max_angle``),
    the state the angle ``delta`` (rad), which follows the command through a rate-limited
    servo (``delta_dot = clip((delta_c - delta) / T, +-max_rate)``, ``T = servo_time_constant``
    or, for 0, one physics step: an ideal servo that moves at full rate until it reaches the
    command; MuJoCo integrates the rate and clamps the angle to ``+-max_angle``, so neither
    limit can be exceeded). Positive ``delta`` gives a force to starboard (at a rudder aft of
    the centre of gravity, a yaw moment to port).

    Force (lifting-line form without drag, Fossen 2011 ch. 9.? "rudder forces"; the chosen
    model of the notes of the rudder-roll task): sway force at the rudder

    .. math::

        F = k_L\,U_R |U_R|\, C(\alpha_e),\qquad k_L = \tfrac12 \rho A_R\, \partial C_L /
        \partial\alpha,\qquad C(\alpha) = \begin{cases} \alpha & |\alpha| \le
        \alpha_s\\ \operatorname{sign}(\alpha)\, f_s \alpha_s & |\alpha| > \alpha_s
        \end{cases}

    with the flow speed ``U_R = u`` (``inflow = False``: the hull's derivatives already hold
    the rudder's share of the sway and yaw damping, as captive-model derivatives measured
    with the rudder on do) or ``U_R^2 = u^2 + v_R^2`` and the effective angle ``alpha_e =
    delta - atan2(v_R, |u|)``, ``v_R = v + x_R r - z_R p`` (``inflow = True``). Past the stall
    angle ``alpha_s`` the lift stops growing (``f_s = 1``, a cap) or drops to the fraction
    ``f_s`` of its stall value. Generalised force: ``Y = F``, ``K = -z_R F``, ``N = x_R F``.

    Attributes:
        name, position, colour: as for :class:`Propeller` (the position is the rudder's centre
            of pressure, body frame, z down).
        lift_gain: ``k_L`` (N per rad per (m/s)^2).
        max_angle: largest angle (rad).
        max_rate: largest turning rate (rad/s).
        stall_angle: stall angle (rad), ``inf`` for none.
        post_stall: fraction ``f_s`` of the stall lift kept past the stall angle (0 to 1).
        servo_time_constant: servo time constant (s), 0 for an ideal servo.
        inflow: whether the hull's motion changes the rudder's inflow (above).
    """

    kind: ClassVar[str] = "rudder"
    flow_dependent: ClassVar[bool] = True
    force_law: ClassVar[Any] = staticmethod(law_rudder)
    name: str = ""
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    lift_gain: float = 1.0
    max_angle: float = math.radians(35.0)
    max_rate: float = math.radians(10.0)
    stall_angle: float = math.inf
    post_stall: float = 1.0
    servo_time_constant: float = 0.0
    inflow: bool = False
    colour: str = "#d62728"

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", _check_position(self.name, self.position))
        for k in ("lift_gain", "max_angle", "max_rate", "stall_angle"):
            v = getattr(self, k)
            if not (isinstance(v, int | float) and v > 0 and not math.isnan(v)):
                raise ValueError(f"actuator {self.name!r}: {k} must be > 0, got {v!r}")
        if not 0.0 <= self.post_stall <= 1.0:
            raise ValueError(
                f"actuator {self.name!r}: post_stall must be from 0 to 1, got {self.post_stall!r}"
            )
        if not (math.isfinite(self.servo_time_constant) and self.servo_time_constant >= 0):
            raise ValueError(
                f"actuator {self.name!r}: servo_time_constant must be >= 0 s (0: an ideal "
                f"servo), got {self.servo_time_constant!r}"
            )

    @property
    def channels(self) -> tuple[Channel, ...]:
        return (
            Channel(
                self.name, "rad", -self.max_angle, self.max_angle, "servo",
                self.servo_time_constant, rate=self.max_rate,
            ),
        )  # fmt: skip

    def flow(self, states: ArrayLike, nu: ArrayLike) -> tuple[Any, Any, Any]:
        """``(alpha_e, U_R |U_R|, stalled)`` at the rudder (rad, (m/s)^2, bool).

        Args:
            states: the rudder's state (..., 1): the angle (rad).
            nu: body velocity ``[u, v, r]`` or ``[u, v, p, r]`` (m/s, rad/s), (..., 3 or 4).
        """
        delta = np.asarray(states, dtype=float)[..., 0]
        n = np.asarray(nu, dtype=float)
        if n.shape[-1] not in (3, 4):
            raise ValueError(f"nu must be [u, v, r] or [u, v, p, r], got shape {n.shape}")
        u, v = n[..., 0], n[..., 1]
        r = n[..., -1]
        p = n[..., 2] if n.shape[-1] == 4 else 0.0
        if self.inflow:
            x, _y, z = self.position
            vr = v + x * r - z * p
            q = np.sign(u) * (u * u + vr * vr)
            alpha = delta - np.arctan2(vr, np.abs(u))
        else:
            q = u * np.abs(u)
            alpha = delta + 0.0 * u
        return alpha, q, np.abs(alpha) > self.stall_angle

    def lift(self, states: ArrayLike, nu: ArrayLike) -> Any:
        """The rudder's sway force ``F`` (N), shape (...)."""
        alpha, q, stalled = self.flow(states, nu)
        if not math.isfinite(self.stall_angle):  # no stall
            return self.lift_gain * q * alpha
        c = np.where(stalled, np.sign(alpha) * self.post_stall * self.stall_angle, alpha)
        return self.lift_gain * q * c

    def force(self, states: NDArray[np.float64], nu: ArrayLike | None = None) -> tuple[Any, Any]:
        if nu is None:
            raise ValueError(
                f"the force of rudder {self.name!r} depends on the flow: pass the body velocity "
                "nu = [u, v, r] or [u, v, p, r]"
            )
        f = self.lift(states, nu)
        return 0.0 * f, f

    def thrust(self, states: NDArray[np.float64], nu: ArrayLike | None = None) -> Any:
        return self.force(states, nu)[1]

    @property
    def max_thrust(self) -> float:
        """0: a rudder's force has no bound without a flow speed (:meth:`lift`)."""
        return 0.0

    def law_row(self, channel: int) -> tuple[float, ...]:
        """The row of :func:`law_rudder` (7 values): ``channel``, ``lift_gain`` (N per rad
        per (m/s)^2), ``x``, ``z`` (m, the centre of pressure, z down), ``stall_angle`` (rad,
        ``inf``: none), the post-stall value ``post_stall * stall_angle`` (rad; 0 without a
        stall), ``inflow`` (1.0 or 0.0)."""
        x, _y, z = self.position
        a_s = float(self.stall_angle)
        c_s = self.post_stall * a_s if math.isfinite(a_s) else 0.0
        return (float(channel), float(self.lift_gain), x, z, a_s, c_s, 1.0 if self.inflow else 0.0)


@dataclass(frozen=True)
class MMGPropulsion(Actuator):
    r"""The propeller and rudder of an MMG hull (Yasukawa & Yoshimura 2015), one unit: the
    rudder works in the propeller's slipstream, so the two forces are one law.

    Two channels: ``NAME`` the propeller speed ``n`` (rps, ``[min_rps, max_rps]``), which
    follows its command at a rate limited to ``shaft_rate`` (a servo: a controllable-pitch
    propeller's pitch change or an engine's speed change, approximated as the shaft speed's
    ramp; the notes' [chosen] stopping manoeuvres reverse it from ``+n0`` to ``-n0`` in 20 s),
    and ``rudder`` (:attr:`rudder_name`) the rudder angle (rad, ``+-max_angle``), a
    rate-limited servo as for :class:`Rudder`. Positive ``delta`` gives a force to starboard
    (a turn to port), shipgym's sign for every rudder; the paper's angle is ``-delta``.

    Force: :meth:`~shipgym.dynamics.mmg.MMGModel.propulsion_forces` of :attr:`params` at the
    velocity through the water (thrust from ``K_T(J_P)`` with the wake and thrust
    deduction, the rudder's normal force with the flow straightening and the slipstream,
    the hull-rudder interaction ``a_H``, ``x_H``; the astern extensions). The generalised
    force is not that of one point force (``N_R = -(x_R + a_H x_H) F_N cos delta``):
    :meth:`generalised`. A 3-DOF unit: the MMG standard model is planar.

    Attributes:
        name: the unit's name and its propeller channel's.
        params: the ship's :class:`~shipgym.dynamics.mmg.MMGParameters`.
        position: the propeller's position (m, body frame; for drawing: the law uses
            ``params``).
        max_rps, min_rps: propeller speed range (rps; ``min_rps < 0`` astern).
        shaft_rate: largest rate of the propeller speed (rps/s).
        shaft_time_constant: the shaft servo's time constant (s), 0 for an ideal ramp.
        max_angle, max_rate, servo_time_constant: the rudder's, as for :class:`Rudder`.
        rudder_name: the rudder channel's name.
    """

    kind: ClassVar[str] = "mmg"
    flow_dependent: ClassVar[bool] = True
    force_law: ClassVar[Any] = staticmethod(law_mmg)
    name: str = ""
    params: Any = None
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    max_rps: float = 1.0
    min_rps: float = -1.0
    shaft_rate: float = 1.0
    shaft_time_constant: float = 0.0
    max_angle: float = math.radians(35.0)
    max_rate: float = math.radians(2.32)
    servo_time_constant: float = 0.0
    rudder_name: str = "rudder"
    colour: str = "#9467bd"

    def __post_init__(self) -> None:
        from .mmg import MMGModel, MMGParameters

        if not isinstance(self.params, MMGParameters):
            raise ValueError(f"actuator {self.name!r}: params must be MMGParameters")
        object.__setattr__(self, "position", _check_position(self.name, self.position))
        for k in ("max_rps", "shaft_rate", "max_angle", "max_rate"):
            v = getattr(self, k)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ValueError(f"actuator {self.name!r}: {k} must be > 0, got {v!r}")
        if not (math.isfinite(self.min_rps) and self.min_rps <= 0):
            raise ValueError(f"actuator {self.name!r}: min_rps must be <= 0, got {self.min_rps!r}")
        for k in ("shaft_time_constant", "servo_time_constant"):
            v = getattr(self, k)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"actuator {self.name!r}: {k} must be >= 0 s, got {v!r}")
        if self.rudder_name == self.name:
            raise ValueError(f"actuator {self.name!r}: rudder_name must differ from the name")
        object.__setattr__(self, "_model", MMGModel(self.params))

    @property
    def channels(self) -> tuple[Channel, ...]:
        return (
            Channel(self.name, "rps", self.min_rps, self.max_rps, "servo",
                    self.shaft_time_constant, rate=self.shaft_rate),
            Channel(self.rudder_name, "rad", -self.max_angle, self.max_angle, "servo",
                    self.servo_time_constant, rate=self.max_rate),
        )  # fmt: skip

    def _parts(self, states: ArrayLike, nu: ArrayLike | None) -> tuple[Any, ...]:
        if nu is None:
            raise ValueError(
                f"the force of the MMG unit {self.name!r} depends on the flow: pass the body "
                "velocity through the water nu = [u, v, r]"
            )
        s = np.asarray(states, dtype=float)
        n = np.asarray(nu, dtype=float)
        if n.shape[-1] != 3:
            raise ValueError(f"an MMG unit is planar: nu must be [u, v, r], got shape {n.shape}")
        return self._model.propulsion_forces(n, -s[..., 1], s[..., 0])  # type: ignore[attr-defined]

    def generalised(self, states: ArrayLike, nu: ArrayLike | None = None) -> tuple[Any, Any, Any]:
        """``(X, Y, N)`` (N, N, N m) of the propeller and rudder, shape (...)."""
        X, Y, N, _ = self._parts(states, nu)
        return X, Y, N

    def force(self, states: NDArray[np.float64], nu: ArrayLike | None = None) -> tuple[Any, Any]:
        X, Y, _N, _ = self._parts(states, nu)
        return X, Y

    def thrust(self, states: NDArray[np.float64], nu: ArrayLike | None = None) -> Any:
        """The propeller thrust ``T`` (N, signed), shape (...)."""
        return self._parts(states, nu)[3]["T"]

    @property
    def max_thrust(self) -> float:
        """The bollard-pull surge force ``(1 - t_P) rho n_max^2 D_P^4 k_0`` (N)."""
        p = self.params
        return (1 - p.t_P) * p.rho * self.max_rps**2 * p.D_P**4 * p.k0

    def law_row(self, channel: int) -> tuple[float, ...]:
        """The row of :func:`law_mmg` (from :attr:`params`): ``channel`` (the
        propeller speed's; the rudder angle is the next), ``L`` (m), ``rho`` (kg/m^3),
        ``D_P`` (m), ``D_P^4`` (m^4), ``k0``, ``k1``, ``k2``, ``1 - w_P0``, ``C1``,
        ``C2_pos``, ``C2_neg``, ``x_P`` (1; of ``L``), ``t_P``, ``c_y``, ``x_P L`` (m),
        ``t_R``, ``a_H``, ``x_R L + a_H x_H L`` (m), ``eta = D_P / H_R``, ``kappa``,
        ``eps``, ``gamma_neg``, ``gamma_pos``, ``l_R`` (1), ``rho A_R / 2`` (kg/m),
        ``f_alpha`` (1), ``c_y_brake`` (1), ``stall_angle`` (rad, ``inf``: none),
        ``post_stall`` (1): 30 values."""
        p = self.params
        return tuple(float(c) for c in (
            channel, p.L, p.rho, p.D_P, p.D_P**4, p.k0, p.k1, p.k2, 1 - p.w_P0, p.C1,
            p.C2_pos, p.C2_neg, p.x_P, p.t_P, p.c_y, p.x_P * p.L, p.t_R, p.a_H,
            p.x_R * p.L + p.a_H * p.x_H * p.L, p.D_P / p.H_R, p.kappa, p.eps, p.gamma_neg,
            p.gamma_pos, p.l_R, 0.5 * p.rho * p.A_R, p.f_alpha, p.c_y_brake, p.stall_angle,
            p.post_stall,
        ))  # fmt: skip


#: actuator kinds by the name used in vessel files (``kind = "..."``)
ACTUATOR_KINDS: dict[str, type[Actuator]] = {
    "propeller": Propeller,
    "tunnel": Propeller,
    "azimuth": Azimuth,
    "rudder": Rudder,
    "mmg": MMGPropulsion,
}


class ActuatorSet:
    """The actuators of a vessel, in order: channels, bounds, ``tau(states)``, action scaling.

    Args:
        actuators: the actuators (unique names).
        dofs: 3 (``tau = [X, Y, N]``) or 4 (``[X, Y, K, N]``).

    The state vector (MuJoCo's ``act``) and the command vector (``ctrl``) hold the channels
    of every actuator in order (:attr:`channel_names`). The normalised action of an env is
    one number in ``[-1, 1]`` per channel (:meth:`action_to_command`).
    """

    def __init__(self, actuators: Sequence[Actuator], dofs: int = 3) -> None:
        self.actuators: tuple[Actuator, ...] = tuple(actuators)
        if not self.actuators:
            raise ValueError("a vessel needs at least one actuator")
        names = [a.name for a in self.actuators]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"actuator names must be unique, repeated: {dup}")
        if dofs not in (3, 4):
            raise ValueError(f"dofs must be 3 or 4, got {dofs!r}")
        self.dofs = dofs
        self.channels: tuple[Channel, ...] = tuple(c for a in self.actuators for c in a.channels)
        cnames = [c.name for c in self.channels]
        dup = sorted({n for n in cnames if cnames.count(n) > 1})
        if dup:
            raise ValueError(f"actuator channel names must be unique, repeated: {dup}")
        self.slices: tuple[slice, ...] = ()
        i = 0
        sl = []
        for a in self.actuators:
            n = len(a.channels)
            sl.append(slice(i, i + n))
            i += n
        self.slices = tuple(sl)
        self.lower = np.array([c.lower for c in self.channels])
        self.upper = np.array([c.upper for c in self.channels])
        for arr in (self.lower, self.upper):
            arr.setflags(write=False)
        #: per channel: whether its command is the state it moves to (a lag, a servo), not a
        #: rate (an integrator: an azimuth's angle)
        self.holds_state = np.array([c.dynamics in ("lag", "servo") for c in self.channels])
        self.holds_state.setflags(write=False)

    # ---- description -----------------------------------------------------------------------
    @property
    def names(self) -> tuple[str, ...]:
        """Actuator names, in order."""
        return tuple(a.name for a in self.actuators)

    @property
    def channel_names(self) -> tuple[str, ...]:
        """MuJoCo actuator (channel) names, in order: the layout of commands and states."""
        return tuple(c.name for c in self.channels)

    @property
    def units(self) -> tuple[str, ...]:
        """Command unit of every channel."""
        return tuple(c.unit for c in self.channels)

    @property
    def colours(self) -> tuple[str, ...]:
        """Plot colour of every actuator."""
        return tuple(a.colour for a in self.actuators)

    @property
    def n_channels(self) -> int:
        return len(self.channels)

    def __len__(self) -> int:
        return len(self.actuators)

    def __iter__(self):  # type: ignore[no-untyped-def]
        return iter(self.actuators)

    def __repr__(self) -> str:
        kinds = ", ".join(f"{a.name} ({a.label})" for a in self.actuators)
        return f"ActuatorSet({kinds})"

    def bollard(self) -> ActuatorSet:
        """The same actuators with every :class:`Propeller` on its bollard law at every speed
        and without a rate limit (:meth:`Propeller.bollard`; the other kinds unchanged): the
        actuators of a plant that models them as printed (a ``seed-linear`` plant)."""
        out = [a.bollard() if isinstance(a, Propeller) else a for a in self.actuators]
        if all(b is a or b == a for a, b in zip(self.actuators, out, strict=True)):
            return self
        return ActuatorSet(out, self.dofs)

    @property
    def rate_limited(self) -> bool:
        """Whether a lagged channel's rate is limited (:attr:`Channel.rate` finite)."""
        return any(c.dynamics == "lag" and math.isfinite(c.rate) for c in self.channels)

    @property
    def fixed(self) -> bool:
        """Whether every actuator has a fixed direction (no azimuths)."""
        return all(isinstance(a, Propeller) for a in self.actuators)

    # ---- forces ----------------------------------------------------------------------------
    @property
    def flow_dependent(self) -> bool:
        """Whether a force depends on the flow past the hull (a rudder): pass ``nu``."""
        return any(a.flow_dependent for a in self.actuators)

    def _each(self, states: ArrayLike, nu: ArrayLike | None, what: str) -> list[Any]:
        s = self.check_states(states)
        out = []
        for a, sl in zip(self.actuators, self.slices, strict=True):
            if a.flow_dependent:
                out.append(getattr(a, what)(s[..., sl], nu))
            else:
                out.append(getattr(a, what)(s[..., sl]))
        return out

    def forces(self, states: ArrayLike, nu: ArrayLike | None = None) -> NDArray[np.float64]:
        """Body forces ``(F_x, F_y)`` (N) of every actuator, shape (..., n_actuators, 2).

        ``nu``: the body velocity ``[u, v, r]`` or ``[u, v, p, r]`` (m/s, rad/s), needed by the
        flow-dependent kinds (a :class:`Rudder`).
        """
        out = [np.stack(np.broadcast_arrays(*f), -1) for f in self._each(states, nu, "force")]
        return np.stack(out, -2)

    def thrust(self, states: ArrayLike, nu: ArrayLike | None = None) -> NDArray[np.float64]:
        """Signed thrust (N) of every actuator, shape (..., n_actuators) (a rudder: its lift)."""
        return np.stack(np.broadcast_arrays(*self._each(states, nu, "thrust")), -1)

    def tau(self, states: ArrayLike, nu: ArrayLike | None = None) -> NDArray[np.float64]:
        """Generalised body force (..., dofs): ``[X, Y, N]`` or ``[X, Y, K, N]`` (N, N m).

        ``nu`` as for :meth:`forces`.
        """
        s = self.check_states(states)
        X = Y = K = N = 0.0
        for a, sl in zip(self.actuators, self.slices, strict=True):
            st = s[..., sl]
            if hasattr(a, "generalised"):  # not one point force (an MMG unit, planar)
                gx, gy, gn = a.generalised(st, nu)
                X, Y, N = X + gx, Y + gy, N + gn
                continue
            fx, fy = a.force(st, nu) if a.flow_dependent else a.force(st)
            x, y, z = a.position
            X, Y, N = X + fx, Y + fy, N + (x * fy - y * fx)
            K = K - z * fy
        out = (X, Y, N) if self.dofs == 3 else (X, Y, K, N)
        return np.stack(np.broadcast_arrays(*out, np.zeros(s.shape[:-1])), -1)[..., :-1]

    def configuration_matrix(self) -> NDArray[np.float64]:
        """``B`` (dofs, n_actuators) of the fixed-direction actuators: ``tau = B F``.

        Raises:
            ValueError: the set holds an azimuth (its column depends on the angle).
        """
        if not self.fixed:
            raise ValueError("configuration_matrix needs fixed-direction actuators only")
        cols = []
        for a in self.actuators:
            c, s = a.direction  # type: ignore[attr-defined]
            x, y, z = a.position
            col = [c, s, x * s - y * c] if self.dofs == 3 else [c, s, -z * s, x * s - y * c]
            cols.append(col)
        return np.array(cols).T

    def capacity(self) -> NDArray[np.float64]:
        """Largest ``|tau_i|`` per DOF with every actuator helping (N, N m), shape (dofs,).

        Each DOF on its own (the others free): the sum over actuators of the largest
        contribution; the scale of integral clamps and guidance limits. Rudders are not
        counted: their force depends on the flow speed.
        """
        out = np.zeros(self.dofs)
        for a in self.actuators:
            x, y, z = a.position
            F = a.max_thrust
            if isinstance(a, Rudder):  # no bound without a flow speed
                continue
            if isinstance(a, MMGPropulsion):  # the propeller's bollard pull (the rudder: none)
                out[0] += F
                continue
            if isinstance(a, Propeller):
                c, s = a.direction
                col = np.abs([c, s, x * s - y * c] if self.dofs == 3 else
                             [c, s, z * s, x * s - y * c])  # fmt: skip
                out += F * col
            else:  # azimuth: any direction
                r = math.hypot(x, y)
                col = [1.0, 1.0, r] if self.dofs == 3 else [1.0, 1.0, abs(z), r]
                out += F * np.asarray(col)
        return out

    def initial_state(self) -> NDArray[np.float64]:
        """The actuator states after a reset (n_channels,): each kind's :meth:`~Actuator.
        rest_state` (no force; azimuths at their rest angle)."""
        return np.array([x for a in self.actuators for x in a.rest_state()], dtype=np.float64)

    # ---- commands and actions --------------------------------------------------------------
    def check_states(self, states: ArrayLike, what: str = "actuator states") -> NDArray[Any]:
        """``states`` as a float array (..., n_channels); ``ValueError`` on shape or NaN."""
        a = np.asarray(states, dtype=float)
        if a.ndim == 0 or a.shape[-1] != self.n_channels:
            raise ValueError(
                f"{what} must have shape (..., {self.n_channels}) "
                f"({', '.join(self.channel_names)}),"
                f" got {a.shape}"
            )
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{what} contain NaN or infinite values: {a}")
        return a

    def as_vector(self, x: ArrayLike, what: str) -> tuple[NDArray[np.float64], list[float]]:
        """One command or action ``x`` (one value per channel) as an array and a list of
        floats; ``ValueError`` naming ``what`` on a wrong shape or NaN/inf (cheap: every step).
        """
        a = np.asarray(x, dtype=float)
        if a.shape != (self.n_channels,):
            raise ValueError(
                f"{what} must have shape ({self.n_channels},) "
                f"({', '.join(self.channel_names)}), got {a.shape}"
            )
        vals = a.tolist()
        if not math.isfinite(sum(vals)) and not all(math.isfinite(v) for v in vals):
            raise ValueError(f"{what} contains NaN or infinite values: {a}")
        return a, vals

    def clip(self, command: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Commands clipped to their ranges and the flags of those clipped."""
        c = self.check_states(command, "command")
        out = np.clip(c, self.lower, self.upper)
        return out, out != c

    def action_to_command(self, action: ArrayLike) -> NDArray[np.float64]:
        """Normalised action (..., n_channels) in ``[-1, 1]`` -> physical command.

        A range around zero is scaled on each side separately (``a >= 0 -> a upper``,
        ``a < 0 -> a |lower|``), so 0 is "off" and +-1 the range ends; a range that does not
        contain zero (``lower >= 0``) is mapped affinely (-1 -> lower, 1 -> upper): the
        compiled law :func:`channel_command` on every row.
        """
        return self._rows_law(action_commands, action)

    def command_to_action(self, command: ArrayLike) -> NDArray[np.float64]:
        """Physical command -> normalised action (the inverse of :meth:`action_to_command`:
        the compiled law :func:`channel_action` on every row)."""
        return self._rows_law(command_actions, command)

    def _rows_law(self, law: Any, x: ArrayLike) -> NDArray[np.float64]:
        """``law`` (:func:`action_commands` or :func:`command_actions`) on the rows of ``x``
        (..., n_channels), or of a value broadcast to every channel."""
        a = np.asarray(x, dtype=float)
        nc = self.n_channels
        if a.ndim == 2 and a.shape[1] == nc and a.flags.c_contiguous:  # rows already (a step)
            rows, shape = a, a.shape
        else:
            shape = a.shape if a.ndim and a.shape[-1] == nc else np.broadcast_shapes(a.shape, (nc,))
            rows = np.ascontiguousarray(np.broadcast_to(a, shape).reshape(-1, nc))
        out = np.empty(rows.shape)
        args = (rows, self.lower, self.upper, out)
        entries = self.__dict__.setdefault("_row_laws", {})
        fn = entries.get(law)
        if fn is None:
            fn = entries[law] = entry(law, args)
        fn(*args)
        return out.reshape(shape)

    # ---- run time ------------------------------------------------------------------------
    def law_table(self) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
        """``(table, laws, kind_index)``: every actuator's compiled force law and its row.

        - ``table``: float64, C-contiguous, (n_actuators, W): actuator ``a``'s
          :meth:`~Actuator.law_row` (its first channel's index first), zero-padded to the
          widest row ``W``;
        - ``laws``: the addresses (int64) of the distinct compiled laws of the set's kinds
          (each kind's ``force_law``, in order of first use, compiled for
          :data:`shipgym._jit.LAW_SIG`), so that a compiled loop calls
          ``law_at(laws[kind_index[a]])(table[a], st, u, v, p, r)`` (:func:`tau_of_table`);
        - ``kind_index``: int64 (n_actuators,), each actuator's law in ``laws``.

        Built once per set and cached (the arrays are shared: do not modify them). A kind
        takes part through its class's ``force_law`` and ``law_row`` alone.
        """
        cached = self.__dict__.get("_law_table")
        if cached is not None:
            return cached  # type: ignore[no-any-return]
        rows: list[tuple[float, ...]] = []
        fns: list[Any] = []
        index: list[int] = []
        for a, sl in zip(self.actuators, self.slices, strict=True):
            fn = getattr(type(a), "force_law", None)
            if fn is None or not callable(getattr(a, "law_row", None)):
                raise TypeError(
                    f"actuator {a.name!r} ({type(a).__name__}) has no compiled force law: its "
                    "kind needs a force_law ClassVar (shipgym._jit.LAW_SIG) and law_row()"
                )
            row = tuple(float(c) for c in a.law_row(sl.start))
            if not row or row[0] != sl.start:
                raise ValueError(
                    f"actuator {a.name!r}: law_row must start with its channel {sl.start}, "
                    f"got {row[:1]}"
                )
            k = next((i for i, f in enumerate(fns) if f is fn), -1)
            if k < 0:
                fns.append(fn)
                k = len(fns) - 1
            rows.append(row)
            index.append(k)
        table = np.zeros((len(rows), max(len(r) for r in rows)))
        for i, row in enumerate(rows):
            table[i, : len(row)] = row
        out = (
            np.ascontiguousarray(table),
            np.array([address(f, LAW_SIG) for f in fns], dtype=np.int64),
            np.array(index, dtype=np.int64),
        )
        self._law_table = out
        return out

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state.pop("_law_table", None)  # compiled functions: rebuilt on demand
        state.pop("_row_laws", None)
        return state
