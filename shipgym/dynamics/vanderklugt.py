r"""The linear sway-roll-yaw model of Van der Klugt (1987) as used by Radhakrishnan (n.d.).

Public names: ``KDP_LAWS``, ``OUTPUT_NAMES``, ``STATE_NAMES``, ``VAN_DER_KLUGT``, ``VARIANTS``,
``RollModel``, ``RollParameters``, ``VanDerKlugtParameters``, ...
Sources: Van der Klugt (1987); Radhakrishnan (n.d.); Fossen (1995).

Design notes: docs/design/dynamics.vanderklugt.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "KDP_LAWS",
    "OUTPUT_NAMES",
    "STATE_NAMES",
    "VAN_DER_KLUGT",
    "VARIANTS",
    "RollModel",
    "RollParameters",
    "VanDerKlugtParameters",
    "frequency_response",
    "open_loop_amplitudes",
    "roll_model",
    "roll_rudder_zero",
    "transfer_functions",
]

Array = NDArray[np.float64]

#: laws for the direct rudder-to-roll gain ``K_dp``: ``"U2"`` = ``-0.0014 U^2``
#: [reconstructed], ``"printed"`` = ``-0.0014 / U^2`` [printed]
KDP_LAWS = ("U2", "printed")
#: state-space variants: eqs. 5-7 rebuilt (default) or eqs. 10-11 as printed
VARIANTS = ("reconstructed", "seed-printed")
#: the state order of Radhakrishnan (n.d.) eq. 9
STATE_NAMES = ("v", "r", "psi", "p", "phi")
#: the measured outputs (rate gyros and gyros): yaw rate, heading, roll rate, roll angle
OUTPUT_NAMES = ("r", "psi", "p", "phi")


def _check_speed(U: float) -> float:
    U_ = float(U)
    if not (math.isfinite(U_) and U_ > 0.0):
        raise ValueError(
            f"the forward speed U must be finite and > 0 m/s (the laws divide by U), got {U!r}"
        )
    return U_


def _check_law(kdp_law: str) -> str:
    if kdp_law not in KDP_LAWS:
        raise ValueError(f"kdp_law must be one of {KDP_LAWS}, got {kdp_law!r}")
    return kdp_law


@dataclass(frozen=True)
class RollParameters:
    """The Van der Klugt (1987) parameters evaluated at one speed (SI).

    Attributes:
        U: forward speed (m/s).
        omega_n: roll natural frequency (rad/s).
        T_v: sway time constant (s).
        T_r: yaw time constant (s).
        K_vr: yaw-rate gain per sway velocity ((rad/s)/(m/s)).
        K_dr: yaw-rate gain per rudder angle ((rad/s)/rad).
        K_dp: direct roll gain per rudder angle (rad/rad).
        K_dv: sway-velocity gain per rudder angle ((m/s)/rad).
        K_vp: roll gain per sway velocity (rad/(m/s)).
        xi: roll damping ratio (-).
        q_phi: intensity of the roll disturbance ``w_phi`` (a roll angle, rad^2 s).
        q_psi: intensity of the yaw disturbance ``w_psi`` (a yaw rate, rad^2/s).
        kdp_law: the ``K_dp`` law used (:data:`KDP_LAWS`).
    """

    U: float
    omega_n: float
    T_v: float
    T_r: float
    K_vr: float
    K_dr: float
    K_dp: float
    K_dv: float
    K_vp: float
    xi: float
    q_phi: float
    q_psi: float
    kdp_law: str


@dataclass(frozen=True)
class VanDerKlugtParameters:
    """The speed laws of the Van der Klugt (1987) model, Radhakrishnan (n.d.) section 4.

    Each law is ``coefficient * U^k`` with ``U`` the forward speed in m/s; the labels say where
    each number comes from.

    Attributes:
        omega_n: roll natural frequency, 0.63 rad/s [printed].
        T_v_U: ``T_v = T_v_U / U``, 78 m (T_v in s) [printed].
        T_r_U: ``T_r = T_r_U / U``, 13 m (T_r in s) [printed; 1.6 s at 8 m/s is short for a
            ship's yaw lag, perhaps an OCR loss, kept].
        K_vr: -0.46 (rad/s)/(m/s) [printed].
        K_dr_U: ``K_dr = K_dr_U U``, -0.0027 1/m [printed].
        K_dp_U: ``K_dp = K_dp_U U^2`` (law ``"U2"``, [reconstructed]) or ``K_dp_U / U^2``
            (law ``"printed"``), -0.0014 [printed coefficient].
        K_dv_U: ``K_dv = K_dv_U U``, 0.01 (-) [printed].
        K_vp_U: ``K_vp = K_vp_U U``, 0.21 s^2/m^2 [printed].
        xi_0, xi_U: ``xi = xi_0 + xi_U U``, 0.064 (-) and 0.0038 s/m [printed].
        omega_phi_deg: 0.7 deg [printed number], read as ``sqrt(q_phi)`` in degrees of roll
            [chosen: the paper calls it a signal and gives no unit; read as radians it gives
            a 52 deg roll RMS, as degrees a realistic 0.9 deg at 8 m/s].
        omega_psi_deg: 0.35 deg [printed number], read as ``sqrt(q_psi)`` in deg/s of yaw rate
            (the signal enters the yaw-rate equation) [chosen, as ``omega_phi_deg``].
    """

    omega_n: float = 0.63
    T_v_U: float = 78.0
    T_r_U: float = 13.0
    K_vr: float = -0.46
    K_dr_U: float = -0.0027
    K_dp_U: float = -0.0014
    K_dv_U: float = 0.01
    K_vp_U: float = 0.21
    xi_0: float = 0.064
    xi_U: float = 0.0038
    omega_phi_deg: float = 0.7
    omega_psi_deg: float = 0.35

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not (isinstance(value, int | float) and math.isfinite(value)):
                raise ValueError(f"{f.name} must be a finite number, got {value!r}")
        for name in ("omega_n", "T_v_U", "T_r_U"):
            if getattr(self, name) <= 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        for name in ("omega_phi_deg", "omega_psi_deg"):
            if getattr(self, name) < 0:
                raise ValueError(
                    f"{name} must be >= 0 (an RMS-like level), got {getattr(self, name)!r}"
                )

    def at(self, U: float, kdp_law: str = "U2") -> RollParameters:
        """The parameters at the forward speed ``U``.

        Args:
            U: forward speed (m/s), > 0.
            kdp_law: ``"U2"`` (``K_dp = -0.0014 U^2``, reconstructed) or ``"printed"``
                (``-0.0014 / U^2``).

        Returns:
            :class:`RollParameters`: ``omega_n`` (rad/s), ``T_v``, ``T_r`` (s), ``K_vr``
            ((rad/s)/(m/s)), ``K_dr`` ((rad/s)/rad), ``K_dp`` (rad/rad), ``K_dv``
            ((m/s)/rad), ``K_vp`` (rad/(m/s)), ``xi`` (-), ``q_phi`` (rad^2 s), ``q_psi``
            (rad^2/s).

        Raises:
            ValueError: ``U <= 0`` or an unknown law.
        """
        U_ = _check_speed(U)
        law = _check_law(kdp_law)
        xi = self.xi_0 + self.xi_U * U_
        if not xi > 0.0:
            raise ValueError(f"the roll damping ratio xi = {xi:g} at U = {U_:g} m/s is not > 0")
        return RollParameters(
            U=U_,
            omega_n=self.omega_n,
            T_v=self.T_v_U / U_,
            T_r=self.T_r_U / U_,
            K_vr=self.K_vr,
            K_dr=self.K_dr_U * U_,
            K_dp=self.K_dp_U * (U_**2 if law == "U2" else U_**-2),
            K_dv=self.K_dv_U * U_,
            K_vp=self.K_vp_U * U_,
            xi=xi,
            q_phi=math.radians(self.omega_phi_deg) ** 2,
            q_psi=math.radians(self.omega_psi_deg) ** 2,
            kdp_law=law,
        )


#: the printed parameter laws (Radhakrishnan (n.d.) section 4, after Van der Klugt 1987)
VAN_DER_KLUGT = VanDerKlugtParameters()


@dataclass(frozen=True)
class RollModel:
    """The linear sway-roll-yaw model ``x_dot = A x + B delta + G w``, ``y = C x``.

    Attributes:
        A: (5, 5) state matrix (1/s), state ``x = [v, r, psi, p, phi]`` (m/s, rad/s, rad,
            rad/s, rad).
        B: (5,) rudder input (per rad of rudder).
        G: (5, 2) wave-disturbance input, ``w = [w_phi, w_psi]`` (rad, rad/s).
        C: (4, 5) the measured outputs ``y = [r, psi, p, phi]``.
        U: forward speed (m/s).
        parameters: the numbers at ``U`` (:class:`RollParameters`), or ``None`` for a model
            that is not the seed's (:func:`shipgym.dynamics.linearise.roll_model_of`).
        variant: ``"reconstructed"`` or ``"seed-printed"``.
        states, outputs: the names.
        source: where the matrices come from.
    """

    A: Array
    B: Array
    G: Array
    C: Array
    U: float
    parameters: RollParameters | None
    variant: str
    states: tuple[str, ...] = STATE_NAMES
    outputs: tuple[str, ...] = OUTPUT_NAMES
    source: str = ""
    q: tuple[float, float] | None = None

    @property
    def Q_w(self) -> Array:
        """The disturbance intensity (2, 2): ``q`` if given, else the seed's ``diag(q_phi,
        q_psi)`` (rad^2 s, rad^2/s).

        Raises:
            ValueError: neither ``q`` nor the seed's parameters.
        """
        if self.q is not None:
            return np.diag(np.asarray(self.q, dtype=float))
        if self.parameters is None:
            raise ValueError(f"the model {self.source!r} has no disturbance intensity q")
        return np.diag([self.parameters.q_phi, self.parameters.q_psi])


def roll_model(
    U: float,
    variant: str = "reconstructed",
    kdp_law: str = "U2",
    parameters: VanDerKlugtParameters = VAN_DER_KLUGT,
) -> RollModel:
    r"""The Van der Klugt (1987) state space at the speed ``U`` (Radhakrishnan (n.d.) eqs. 8-12).

    ``"seed-printed"`` is eqs. 10-11 as printed::

        A = [[ 1/T_v,      0,      0, 0,        0    ],
             [ K_vr,     -1/T_r,   0, 0,        0    ],
             [ 0,          1,      0, 0,        0    ],
             [ w_n^2 K_vp, 0,      0, -2 xi w_n, w_n^2],
             [ 0,          0,      0, 1,        0    ]]
        B = [K_dv/T_v, K_dr/T_r, 0, -w_n^2 K_dp, 0]

    ``"reconstructed"`` makes the state space agree with the transfer functions eqs. 5-7 (which
    the paper says it realises); each fix and its evidence:

    1. ``A[0, 0] = -1/T_v``: eq. 5 gives ``v_dot = (-v + K_dv delta) / T_v``; the printed
       ``+1/T_v`` is an unstable sway mode ``+U/78`` (and ``B[0] = K_dv/T_v`` is printed with
       the eq. 5 scaling).
    2. ``A[3, 4] = -w_n^2``: eq. 6's denominator ``s^2 + 2 xi w_n s + w_n^2``; the printed
       ``+w_n^2`` is a root near +0.57 rad/s at every speed (a 1.7 s e-folding roll capsize).
    3. ``A[1, 0] = K_vr/T_r``: eq. 7 gives ``r_dot = (-r + K_dr delta + K_vr v)/T_r``; B is
       printed with ``K_dr/T_r``, so the printed ``K_vr`` lacks the same ``1/T_r``.
    4. ``B[3] = +w_n^2 K_dp``: the numerator of eq. 6 (the printed minus sign disagrees with
       it; with ``+`` and the ``"U2"`` law the roll response has the classic right-half-plane
       zero, initial inward then final outward heel).

    In both variants ``G = [[0, 0], [0, 1/T_r], [0, 0], [w_n^2, 0], [0, 0]]`` [reconstructed
    from where ``w_phi``, ``w_psi`` enter eqs. 6-7; the paper prints no G] and
    ``C`` picks ``[r, psi, p, phi]`` [chosen: the gyros and rate gyros the paper names].

    Args:
        U: forward speed (m/s), > 0.
        variant: :data:`VARIANTS`.
        kdp_law: :data:`KDP_LAWS`.
        parameters: the speed laws (the printed ones by default).

    Returns:
        :class:`RollModel`.

    Raises:
        ValueError: ``U <= 0``, an unknown variant or an unknown law (the message lists the
            valid ones).
    """
    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {VARIANTS}, got {variant!r}")
    p = parameters.at(U, kdp_law)
    w2 = p.omega_n**2
    printed = variant == "seed-printed"
    A = np.zeros((5, 5))
    A[0, 0] = (1.0 if printed else -1.0) / p.T_v
    A[1, 0] = p.K_vr if printed else p.K_vr / p.T_r
    A[1, 1] = -1.0 / p.T_r
    A[2, 1] = 1.0
    A[3, 0] = w2 * p.K_vp
    A[3, 3] = -2.0 * p.xi * p.omega_n
    A[3, 4] = w2 if printed else -w2
    A[4, 3] = 1.0
    B = np.array([p.K_dv / p.T_v, p.K_dr / p.T_r, 0.0, (-w2 if printed else w2) * p.K_dp, 0.0])
    G = np.zeros((5, 2))
    G[3, 0] = w2
    G[1, 1] = 1.0 / p.T_r
    C = np.zeros((4, 5))
    for i, name in enumerate(OUTPUT_NAMES):
        C[i, STATE_NAMES.index(name)] = 1.0
    source = (
        "Radhakrishnan (n.d.) eqs. 10-11 as printed"
        if printed
        else "Radhakrishnan (n.d.) eqs. 5-7 (Van der Klugt 1987) as a state space, reconstructed"
    )
    return RollModel(A, B, G, C, p.U, p, variant, source=f"{source}; K_dp law {p.kdp_law!r}")


Polynomial = tuple[Array, Array]


def transfer_functions(
    U: float, kdp_law: str = "U2", parameters: VanDerKlugtParameters = VAN_DER_KLUGT
) -> dict[str, Polynomial]:
    r"""Eqs. 5-7 as rational functions of ``s`` from the rudder angle, built from the equations.

    Polynomial products only (no state space), so they are an independent check of
    :func:`roll_model`::

        v/delta   = K_dv / (T_v s + 1)
        phi/delta = w_n^2 [K_dp (T_v s + 1) + K_vp K_dv] / ((T_v s + 1)(s^2 + 2 xi w_n s + w_n^2))
        psi/delta = [K_dr (T_v s + 1) + K_vr K_dv] / ((T_v s + 1)(T_r s + 1) s)

    Args:
        U: forward speed (m/s), > 0.
        kdp_law: :data:`KDP_LAWS`.
        parameters: the speed laws.

    Returns:
        ``{"v": (num, den), "phi": (num, den), "psi": (num, den)}``, coefficients in
        descending powers of ``s`` (``numpy.polyval`` order); units m/s, rad, rad per rad.
    """
    p = parameters.at(U, kdp_law)
    w2 = p.omega_n**2
    sway = np.array([p.T_v, 1.0])  # T_v s + 1
    roll = np.array([1.0, 2.0 * p.xi * p.omega_n, w2])
    yaw = np.polymul([p.T_r, 1.0], [1.0, 0.0])  # (T_r s + 1) s
    num_phi = w2 * np.polyadd(p.K_dp * sway, [p.K_vp * p.K_dv])
    num_psi = np.polyadd(p.K_dr * sway, [p.K_vr * p.K_dv])
    return {
        "v": (np.array([p.K_dv]), sway),
        "phi": (num_phi, np.polymul(sway, roll)),
        "psi": (num_psi, np.polymul(sway, yaw)),
    }


def roll_rudder_zero(
    U: float, kdp_law: str = "U2", parameters: VanDerKlugtParameters = VAN_DER_KLUGT
) -> Array:
    """The zero(s) of the roll/rudder transfer function (eq. 6 with eq. 5), rad/s.

    ``K_dp (T_v s + 1) + K_vp K_dv = 0``: ``s = -(1 + K_vp K_dv / K_dp) / T_v``, ``+U/156`` with
    the ``"U2"`` law (a right-half-plane zero: non-minimum-phase roll).

    Returns:
        the zeros (rad/s), a (1,) array.
    """
    num, _ = transfer_functions(U, kdp_law, parameters)["phi"]
    return np.real_if_close(np.roots(num)).astype(float)


def frequency_response(model: RollModel, omega: ArrayLike) -> NDArray[np.complex128]:
    """The complex gain ``(j omega I - A)^-1 B`` of every state per rad of rudder.

    Args:
        model: a :class:`RollModel`.
        omega: frequency or frequencies (rad/s), > 0 (the heading has a pole at 0).

    Returns:
        (5,) for a scalar ``omega``, else (len(omega), 5): the complex amplitude of
        ``[v, r, psi, p, phi]`` (m/s, rad/s, rad, rad/s, rad) per rad of rudder.
    """
    w = np.asarray(omega, dtype=float)
    if not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise ValueError("omega must be finite and > 0 rad/s (the heading integrates: no DC gain)")
    flat = np.atleast_1d(w)
    out = np.stack([np.linalg.solve(1j * wk * np.eye(5) - model.A, model.B) for wk in flat])
    return out[0] if w.ndim == 0 else out


def open_loop_amplitudes(
    U: float,
    amplitude: float = math.radians(10.0),
    omega: float = 0.43,
    kdp_law: str = "U2",
    variant: str = "reconstructed",
) -> dict[str, float]:
    """Steady amplitudes of the states for the rudder ``delta = amplitude sin(omega t)``.

    The seed's test input is 10 (deg, reconstructed) at 0.43 rad/s (Radhakrishnan (n.d.)
    section 4). Only meaningful for a stable model (the reconstructed one; the heading's free
    integrator drifts with the initial condition but its oscillation has this amplitude).

    Args:
        U: forward speed (m/s).
        amplitude: rudder amplitude (rad).
        omega: rudder frequency (rad/s).
        kdp_law: :data:`KDP_LAWS`.
        variant: :data:`VARIANTS`.

    Returns:
        ``{"v": m/s, "r": rad/s, "psi": rad, "p": rad/s, "phi": rad}``.
    """
    if not (math.isfinite(amplitude) and amplitude >= 0.0):
        raise ValueError(f"amplitude must be finite and >= 0 rad, got {amplitude!r}")
    gain = frequency_response(roll_model(U, variant, kdp_law), omega)
    return {name: float(abs(g) * amplitude) for name, g in zip(STATE_NAMES, gain, strict=True)}


#: the rudder's roll arm (m) of the ``van-der-klugt`` package times ``U^4``, for the printed
#: law ``K_dp = -0.0014/U^2``: ``z_R = -w_n^2 K_dp T_v / K_dv = 0.63^2 (0.0014)(78)/(0.01 U^4)``
PRINTED_ROLL_ARM_U4 = 0.63**2 * 0.0014 * 78.0 / 0.01


def seed_vessel(kdp_law: str = "U2", speed: float | None = None) -> Any:
    """The ``van-der-klugt`` vessel package with the direct rudder-roll law ``kdp_law``.

    ``"U2"`` (the reconstructed ``K_dp = -0.0014 U^2``) is the package itself, valid at every
    speed: the rudder's lift grows with ``U^2`` at a fixed point. ``"printed"``
    (``K_dp = -0.0014/U^2``) cannot be one rudder at a fixed point: the package's rudder is
    moved to the roll arm ``z_R = 4.334/U^4`` m that gives the printed law at ``speed`` (m/s)
    only (kept to compare with the seed's print, Radhakrishnan (n.d.) section 4).

    Raises:
        ValueError: an unknown law, or ``"printed"`` without a speed > 0.
    """
    import dataclasses

    from .actuators import ActuatorSet, Rudder
    from .vessel import load_vessel

    law = _check_law(kdp_law)
    v = load_vessel("van-der-klugt")
    if law == "U2":
        return v
    if speed is None:
        raise ValueError("the printed K_dp law holds at one speed only: give speed= (m/s)")
    U = _check_speed(speed)
    acts = []
    for a in v.actuators:
        if isinstance(a, Rudder):
            x, y, _z = a.position
            a = dataclasses.replace(a, position=(x, y, PRINTED_ROLL_ARM_U4 / U**4))
        acts.append(a)
    return dataclasses.replace(
        v, title=f"{v.title} (printed K_dp law at {U:g} m/s)",
        actuators=ActuatorSet(acts, v.dofs),
    )  # fmt: skip
