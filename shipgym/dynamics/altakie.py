r"""The DP models of Al-Takie (1982): LF sway-yaw model, HF wave model, the 14-state model.

Everything here is in the thesis's per-unit system (:class:`~shipgym.dynamics.perunit.PerUnit`:
bases ``m``, ``L_pp``, ``g``; time ``t' = t / sqrt(L/g)``), as printed, so the thesis's
matrices can be checked entry by entry; :meth:`PerUnit.model_to_si` converts.

Public names: ``BEAUFORT_NUMBERS``, ``D_H_RECONSTRUCTED``, ``HF_ALPHA``, ``LF_STATES``,
``Q_L_PRINTED``, ``R_PRINTED``, ``THESIS_LF``, ``THESIS_PER_UNIT``, ...

Design notes: docs/design/dynamics.altakie.md.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import njit
from shipgym.disturbances.waves import AL_TAKIE_HF_POLYNOMIALS

from .perunit import PerUnit

__all__ = [
    "BEAUFORT_NUMBERS",
    "D_H_RECONSTRUCTED",
    "HF_ALPHA",
    "LF_STATES",
    "Q_L_PRINTED",
    "R_PRINTED",
    "THESIS_LF",
    "THESIS_PER_UNIT",
    "LFModel",
    "WaveFilterModel",
    "discretise",
    "hf_alpha",
    "hf_block",
    "hf_peak_frequency",
    "lf_model",
    "lf_model_from_vessel",
    "saturated_lf_matrix",
    "saturated_lf_rows",
    "saturated_lf_step",
    "saturation",
    "saturation_slope",
    "surge_model_from_vessel",
    "wave_filter_model",
]

Array = NDArray[np.float64]

#: Beaufort numbers of the thesis's HF tables (App. 2)
BEAUFORT_NUMBERS = (5, 6, 7, 8, 9)

#: the per-unit kinds of the LF states and inputs (generalised-force inputs)
LF_STATES = ("velocity", "length", "angular_velocity", "angle", "force", "moment")
LF_INPUTS = ("force", "moment")

#: Per-unit bases of the thesis's ships: ``(m kg, L_pp m)`` [printed, App. 1]
THESIS_PER_UNIT: Mapping[str, PerUnit] = MappingProxyType(
    {
        "wimpey-sealab": PerUnit(5.670e6, 94.49),
        "star-hercules": PerUnit(4.377e6, 73.0),
    }
)

#: ``Q_l = diag(0.00228^2, 0.00031^2)`` p.u.^2: the mean wind forcing 126.8 kN and 1636 kN m of
#: Wimpey Sealab (Al-Takie 1982 2.4.1) [printed]
Q_L_PRINTED = (0.00228**2, 0.00031**2)
#: ``R = diag(1e-5, 4e-4)`` p.u.^2: position sigma 1/3 m, gyro 0.02 rad (Al-Takie 1982 2.4.2)
#: [printed]
R_PRINTED = (1.0e-5, 4.0e-4)

#: The HF noise gain ``d`` of ``D_h = [0, 0, 0, d]`` per DOF (sway, yaw) and the factor on the
#: printed yaw ``Q_l`` [reconstructed]: the steady Kalman gain fitted to the printed Wimpey
#: gains (Al-Takie 1982 5.1); sway ``d = 0.020`` with ``Q_l`` as printed reproduces the
#: sway column to <= 6 %; yaw needs ``d = 0.075`` and 17.8 x the printed yaw ``Q_l``
#: (sigma 0.0013 p.u.) to come within 20 % (with the printed ``Q_l`` its LF gains are 3-5x
#: too small).
D_H_RECONSTRUCTED: Mapping[str, float] = MappingProxyType(
    {"d_sway": 0.020, "d_yaw": 0.075, "q_yaw_factor": 17.8}
)

#: App. 2 per-unit alphas ``(a1, a2, a3, a4)`` by ship and Beaufort number [printed]
HF_ALPHA: Mapping[str, Mapping[int, tuple[float, float, float, float]]] = MappingProxyType(
    {
        "wimpey-sealab": MappingProxyType(
            {
                5: (4.594, 4.384, 2.988, 1.470),
                6: (3.663, 2.698, 1.452, 0.556),
                7: (3.166, 2.119, 0.974, 0.341),
                8: (2.794, 1.789, 0.754, 0.251),
                9: (2.545, 1.353, 0.486, 0.131),
            }
        ),
        "star-hercules": MappingProxyType(
            {5: (4.037, 3.853, 2.626, 1.292), 8: (2.455, 1.572, 0.662, 0.22)}
        ),
    }
)


@dataclass(frozen=True)
class LFModel:
    """A per-unit LF sway-yaw model ``dx/dt' = A x + B u + D w + E n``, ``y = C x``.

    Attributes:
        A: (6, 6) state matrix (per-unit time).
        B: (6, 2) input matrix.
        C: (2, 6) measurement matrix (sway position, yaw angle).
        D: (6, 2) process-noise input (sway force, yaw moment noise).
        E: (6, 2) wind-disturbance input (``D / sqrt(2)`` as printed for Wimpey).
        per_unit: the bases.
        Y: (2, 2) from the model inputs (thruster outputs ``f_1, f_2``) to the per-unit
            generalised force ``[Y', N']``; identity for generalised-force inputs.
        source: where the numbers come from.
    """

    A: Array
    B: Array
    C: Array
    D: Array
    E: Array
    per_unit: PerUnit
    Y: Array = field(default_factory=lambda: np.eye(2))
    source: str = ""

    @property
    def thruster_pole(self) -> Array:
        """The thruster poles ``b = T_b / T`` (per-unit time), (2,)."""
        return -np.diag(self.A)[4:6].copy()

    def generalised(self) -> LFModel:
        """The same model with generalised-force inputs (thruster states ``Y f``; ``Y = I``).

        Exact when both thrusters have the same lag (as in the thesis: ``b_1 = b_2``).
        """
        if np.allclose(self.Y, np.eye(2)):
            return self
        b = self.thruster_pole
        if not math.isclose(b[0], b[1], rel_tol=1e-9):
            raise ValueError("generalised(): the thruster lags differ, the change is not exact")
        T = scipy.linalg.block_diag(np.eye(4), self.Y)
        Ti = np.linalg.inv(T)
        return replace(
            self,
            A=T @ self.A @ Ti,
            B=T @ self.B @ np.linalg.inv(self.Y),
            C=self.C @ Ti,
            D=T @ self.D,
            E=T @ self.E,
            Y=np.eye(2),
            source=self.source + " (generalised-force inputs)",
        )


def _printed_lf(
    name: str, a: list[list[float]], b: float, D: tuple[float, float], Y: Array, source: str
) -> LFModel:
    B = np.zeros((6, 2))
    B[4, 0] = B[5, 1] = b
    C = np.zeros((2, 6))
    C[0, 1] = C[1, 3] = 1.0
    Dm = np.zeros((6, 2))
    Dm[0, 0], Dm[2, 1] = D
    return LFModel(
        np.array(a, dtype=float), B, C, Dm, Dm / math.sqrt(2.0), THESIS_PER_UNIT[name], Y, source
    )


#: The printed LF models [printed: Al-Takie (1982) eqs. 3.23-3.26 (Wimpey Sealab), 3.30-3.32 (Star
#: Hercules); Star Hercules ``D``, ``E`` not printed, chosen by analogy: ``D = diag(B_1, B_2)``
#: columns, ``E = D / sqrt(2)``]
THESIS_LF: Mapping[str, LFModel] = MappingProxyType(
    {
        "wimpey-sealab": _printed_lf(
            "wimpey-sealab",
            [
                [-0.0546, 0, 0.0016, 0, 0.5435, 0.272],
                [1, 0, 0, 0, 0, 0],
                [0.0573, 0, -0.0695, 0, 3.268, -1.634],
                [0, 0, 1, 0, 0, 0],
                [0, 0, 0, 0, -1.55, 0],
                [0, 0, 0, 0, 0, -1.55],
            ],
            1.55,
            (0.5435, 9.785),
            np.array([[1.0, 0.5], [1.0 / 3.0, -1.0 / 6.0]]),
            "Al-Takie (1982) eqs. 3.23-3.26 (printed); Y reconstructed from a15..a36",
        ),
        "star-hercules": _printed_lf(
            "star-hercules",
            [
                [-0.01935, 0, 0.00129, 0, 0.585, 0],
                [1, 0, 0, 0, 0, 0],
                [0.04168, 0, -0.0314, 0, 0, 9.596],
                [0, 0, 1, 0, 0, 0],
                [0, 0, 0, 0, -1.364, 0],
                [0, 0, 0, 0, 0, -1.364],
            ],
            1.364,
            (0.585, 9.596),
            np.eye(2),
            "Al-Takie (1982) eqs. 3.30-3.32 (printed); D, E chosen by analogy with Wimpey",
        ),
    }
)


def lf_model(name: str) -> LFModel:
    """The printed LF model of a thesis ship (``"wimpey-sealab"``, ``"star-hercules"``)."""
    try:
        return THESIS_LF[name]
    except KeyError:
        raise ValueError(
            f"Al-Takie (1982) prints LF models for {', '.join(THESIS_LF)} only, not {name!r}; "
            "use lf_model_from_vessel(vessel) for another vessel"
        ) from None


def _lag(vessel: Any, time_constant: float | None) -> float:
    if time_constant is not None:
        return float(time_constant)
    taus = [
        float(c.time_constant)
        for c in vessel.actuators.channels
        if c.dynamics == "lag" and c.time_constant > 0
    ]
    if not taus:
        raise ValueError(
            f"vessel {vessel.name!r} has no thruster lag; pass time_constant= (s) for the "
            "model's first-order thruster states"
        )
    return float(np.median(taus))


def lf_model_from_vessel(vessel: Any, time_constant: float | None = None) -> LFModel:
    """The LF sway-yaw model of eqs. 3.21-3.26 for any vessel, from its design model.

    ``M_sy v_dot = -D_sy [v, r] + [f_Y, f_N]`` with the sway-yaw blocks of the vessel's design
    ``M`` and ``D_L`` (``[design]`` of its package), first-order thruster states of time
    constant ``T`` (the median of the actuators' lags unless given) and generalised-force
    inputs, converted to the per-unit system of the vessel (``m``, ``L_pp``). For the thesis
    ships this reproduces the printed ``A`` (their design matrices are eqs. 3.18-3.20 in SI).

    Args:
        vessel: a :class:`~shipgym.dynamics.vessel.Vessel`.
        time_constant: thruster lag (s); ``None``: from the actuators.
    """
    pu = PerUnit.of_vessel(vessel)
    M = np.asarray(vessel.design.M, dtype=float)[1:, 1:]
    D = np.asarray(vessel.design.D_L, dtype=float)[1:, 1:]
    T = _lag(vessel, time_constant)
    Mi = np.linalg.inv(M)
    A = np.zeros((6, 6))
    A[np.ix_([0, 2], [0, 2])] = -Mi @ D
    A[np.ix_([0, 2], [4, 5])] = Mi
    A[1, 0] = A[3, 2] = 1.0
    A[4, 4] = A[5, 5] = -1.0 / T
    B = np.zeros((6, 2))
    B[4, 0] = B[5, 1] = 1.0 / T
    A_pu, B_pu = pu.model_from_si(A, B, LF_STATES, LF_INPUTS)
    C = np.zeros((2, 6))
    C[0, 1] = C[1, 3] = 1.0
    Dn = np.zeros((6, 2))
    Dn[0, 0], Dn[2, 1] = A_pu[0, 4], A_pu[2, 5]
    return LFModel(
        A_pu,
        B_pu,
        C,
        Dn,
        Dn / math.sqrt(2.0),
        pu,
        np.eye(2),
        f"{vessel.name}: design M, D_L (sway-yaw) and a {T:g} s thruster lag, per unit",
    )


def surge_model_from_vessel(
    vessel: Any, time_constant: float | None = None
) -> tuple[Array, Array, Array, Array]:
    """The decoupled surge model ``x = [u, x, f_X]`` (per unit), as the thesis's eq. 3.18.

    ``m11 u_dot = -d11 u + f_X``, ``x_dot = u``, ``f_X`` a first-order thruster state.

    Returns:
        ``(A, B, C, D)``: (3, 3), (3, 1), (1, 3) measuring the position, (3, 1) noise on the
        force equation.
    """
    pu = PerUnit.of_vessel(vessel)
    m11 = float(np.asarray(vessel.design.M)[0, 0])
    d11 = float(np.asarray(vessel.design.D_L)[0, 0])
    T = _lag(vessel, time_constant)
    A = np.array([[-d11 / m11, 0.0, 1.0 / m11], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0 / T]])
    B = np.array([[0.0], [0.0], [1.0 / T]])
    A_pu, B_pu = pu.model_from_si(A, B, ("velocity", "length", "force"), ("force",))
    C = np.array([[0.0, 1.0, 0.0]])
    D = np.array([[A_pu[0, 2]], [0.0], [0.0]])
    return A_pu, B_pu, C, D


# ---- HF model ---------------------------------------------------------------------------------


def hf_alpha(
    beaufort: int, per_unit: PerUnit, ship: str | None = None
) -> tuple[float, float, float, float]:
    """The per-unit alphas of the HF model for a Beaufort number 5-9.

    The printed row of App. 2 where the thesis has it (``ship`` one of :data:`HF_ALPHA`),
    else the thesis's common real-time polynomial times the ship's ``T_b``
    (``alpha_i = c_i T_b``).
    """
    if isinstance(beaufort, bool) or beaufort not in BEAUFORT_NUMBERS:
        raise ValueError(f"the thesis's HF model exists for Beaufort 5-9, got {beaufort!r}")
    rows = HF_ALPHA.get(ship or "", {})
    if beaufort in rows:
        return rows[beaufort]
    Tb = per_unit.time
    c = AL_TAKIE_HF_POLYNOMIALS[int(beaufort)]
    return tuple(ci * Tb for ci in c)  # type: ignore[return-value]


def hf_block(alpha: ArrayLike, Tb: float) -> Array:
    """``A_hs`` of App. 2: the 4-state companion form in per-unit time, (4, 4)."""
    a1, a2, a3, a4 = np.asarray(alpha, dtype=float)
    return np.array(
        [[0.0, Tb, 0.0, 0.0], [0.0, 0.0, Tb, 0.0], [0.0, 0.0, 0.0, Tb], [-a4, -a3, -a2, -a1]]
    )


def hf_peak_frequency(alpha: ArrayLike, Tb: float) -> float:
    """Peak frequency (Hz, real time) of the HF motion ``|G(jw)|``, ``G = s^2 / den(s)``.

    The real-time denominator is ``s^4 + c1 s^3 + c2 s^2 + c3 s + c4``, ``c_i = alpha_i / T_b``
    (the 3rd state's response to noise into the 4th); found on a fine grid, refined by a
    bounded scalar search.
    """
    from scipy.optimize import minimize_scalar

    den = np.concatenate([[1.0], np.asarray(alpha, dtype=float) / Tb])

    def neg(w: float) -> float:
        s = 1j * w
        return -abs(s * s / np.polyval(den, s))

    w = np.linspace(0.01, 5.0, 50001)
    s = 1j * w
    k = int(np.argmax(np.abs(s * s / np.polyval(den, s))))
    res = minimize_scalar(neg, bounds=(w[max(k - 1, 0)], w[k + 1]), method="bounded")
    return float(res.x) / (2.0 * math.pi)


# ---- the 14-state model -----------------------------------------------------------------------


@dataclass(frozen=True)
class WaveFilterModel:
    """The combined LF + HF model of Al-Takie (1982) ch. 5 (per unit).

    ``dx/dt' = A x + B u + G w`` (``E{w w^T} = Q delta``), ``z = H x + v`` (``E{v v^T} = R``),
    ``x = [LF(6); HF sway(4); HF yaw(4)]``, ``w = [w_Y, w_N, w_hs, w_hy]``; with bias states
    (``bias_q`` of :func:`wave_filter_model`) also ``[b_Y, b_N]`` (16 states, 6 noises).

    Attributes:
        A, B, G, H, Q, R: the matrices, (n, n), (n, 2), (n, p), (2, n), (p, p), (2, 2); ``n``
            14 (the thesis) or 16, ``p`` 4 or 6.
        lf: the LF model inside.
        beaufort: Beaufort numbers of the sway and yaw HF blocks.
        d_h: HF noise gains ``(d_sway, d_yaw)``.
    """

    A: Array
    B: Array
    G: Array
    H: Array
    Q: Array
    R: Array
    lf: LFModel
    beaufort: tuple[int, int]
    d_h: tuple[float, float]

    #: indices of the HF outputs (x9, x13: the first-order wave motion in sway and yaw)
    HF_OUT = (8, 12)

    @property
    def n(self) -> int:
        """Number of states."""
        return int(self.A.shape[0])


def wave_filter_model(
    lf: LFModel,
    beaufort: int | tuple[int, int] = 8,
    *,
    ship: str | None = None,
    d_h: tuple[float, float] | None = None,
    q_l: tuple[float, float] | None = None,
    r: tuple[float, float] = R_PRINTED,
    bias_q: tuple[float, float] | None = None,
) -> WaveFilterModel:
    """The 14-state LF + HF model of Al-Takie (1982) ch. 5 (optionally with 2 bias states).

    Args:
        lf: the LF model (:func:`lf_model`, :func:`lf_model_from_vessel`).
        beaufort: Beaufort number of the HF model (5-9), or ``(sway, yaw)``; the thesis's
            nominal design is 8 for both.
        ship: a thesis ship name for its printed alphas (``None``: the common polynomial).
        d_h: HF noise gains ``(d_sway, d_yaw)`` (p.u.); ``None``: :data:`D_H_RECONSTRUCTED`.
        q_l: LF noise variances (sway force, yaw moment; p.u.^2); ``None``: the printed
            :data:`Q_L_PRINTED` with the yaw entry times the reconstructed factor (17.8).
        r: measurement-noise variances (position p.u.^2, heading rad^2).
        bias_q: ``None`` (the thesis: the mean wind is fed forward) or the intensities
            (p.u.^2 per p.u. time) of two random-walk bias forces ``b_Y``, ``b_N`` that act on
            the hull like the thruster states (states 15, 16; Fossen 2011 ch. 11.3.3): the slowly
            varying wind, drift and current loads a simulated plant has and the model lacks.
    """
    bf = (beaufort, beaufort) if isinstance(beaufort, int) else tuple(beaufort)
    if len(bf) != 2:
        raise ValueError(f"beaufort must be an int or a (sway, yaw) pair, got {beaufort!r}")
    if d_h is None:
        d_h = (D_H_RECONSTRUCTED["d_sway"], D_H_RECONSTRUCTED["d_yaw"])
    if q_l is None:
        q_l = (Q_L_PRINTED[0], Q_L_PRINTED[1] * D_H_RECONSTRUCTED["q_yaw_factor"])
    checks = [("d_h", d_h), ("q_l", q_l), ("r", r)] + ([("bias_q", bias_q)] if bias_q else [])
    for name, pair in checks:
        vals = np.asarray(pair, dtype=float)
        if vals.shape != (2,) or not np.isfinite(vals).all() or (vals < 0).any():
            raise ValueError(f"{name} must be two finite numbers >= 0, got {pair!r}")
    if not min(r) > 0:
        raise ValueError(f"r must be two variances > 0, got {r!r}")
    pu = lf.per_unit
    Tb = pu.time
    Ah = [hf_block(hf_alpha(int(b), pu, ship), Tb) for b in bf]
    A = scipy.linalg.block_diag(lf.A, *Ah)
    B = np.zeros((14, 2))
    B[:6] = lf.B
    G = np.zeros((14, 4))
    G[:6, :2] = lf.D
    G[9, 2] = float(d_h[0])
    G[13, 3] = float(d_h[1])
    H = np.zeros((2, 14))
    H[:, :6] = lf.C
    H[0, 8] = H[1, 12] = 1.0
    Q = np.diag([float(q_l[0]), float(q_l[1]), 1.0, 1.0])
    if bias_q is not None:
        A = scipy.linalg.block_diag(A, np.zeros((2, 2)))
        A[:4, 14:16] = lf.A[:4, 4:6]  # a force on the hull, like the thruster outputs
        B = np.vstack([B, np.zeros((2, 2))])
        G = scipy.linalg.block_diag(G, np.eye(2))
        H = np.hstack([H, np.zeros((2, 2))])
        Q = scipy.linalg.block_diag(Q, np.diag(np.asarray(bias_q, dtype=float)))
    return WaveFilterModel(
        A,
        B,
        G,
        H,
        Q,
        np.diag(np.asarray(r, dtype=float)),
        lf,
        (int(bf[0]), int(bf[1])),
        (float(d_h[0]), float(d_h[1])),
    )


def discretise(A: ArrayLike, B: ArrayLike, G: ArrayLike, dt: float) -> tuple[Array, Array, Array]:
    """``Phi = e^{A dt}``, ``Delta = int_0^dt Phi B``, ``Gamma = int_0^dt Phi G`` (App. 3).

    One matrix exponential of the augmented matrix ``[[A, B, G], [0, 0, 0]] dt`` (exact).
    """
    A_ = np.asarray(A, dtype=float)
    B_ = np.asarray(B, dtype=float)
    G_ = np.asarray(G, dtype=float)
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be finite and > 0, got {dt!r}")
    n, m, p = A_.shape[0], B_.shape[1], G_.shape[1]
    M = np.zeros((n + m + p, n + m + p))
    M[:n, :n] = A_
    M[:n, n : n + m] = B_
    M[:n, n + m :] = G_
    E = scipy.linalg.expm(M * dt)
    return E[:n, :n], E[:n, n : n + m], E[:n, n + m :]


# ---- thruster saturation (ch. 7) --------------------------------------------------------------


def saturation(x: ArrayLike, F1: float = 0.02, F2: float = 50.0) -> Any:
    """``psi(x) = F1 sign(x) (1 - exp(-F2 |x|))``: the EKF's smooth thruster saturation.

    Al-Takie (1982) eqs. 7.5-7.8 [reconstructed from the printed Jacobian
    ``F1 F2 e^{-F2 |x|}``]: slope ``F1 F2`` (1) at 0, limit ``+-F1`` (0.02 p.u.).
    """
    x_ = np.asarray(x, dtype=float)
    return F1 * np.sign(x_) * -np.expm1(-F2 * np.abs(x_))


def saturation_slope(x: ArrayLike, F1: float = 0.02, F2: float = 50.0) -> Any:
    """``d psi / dx = F1 F2 exp(-F2 |x|)`` (Al-Takie 1982 eqs. 7.7-7.8)."""
    x_ = np.asarray(x, dtype=float)
    return F1 * F2 * np.exp(-F2 * np.abs(x_))


def saturated_lf_matrix(A: ArrayLike, f: ArrayLike, F1: float = 0.02, F2: float = 50.0) -> Array:
    """The LF matrix linearised at the thruster states ``f = [x5, x6]`` (Al-Takie 1982 7.2).

    The hull rows (``v``, ``y``, ``r``, ``psi``) see the thruster outputs through ``psi(f)``:
    their thruster columns are scaled by ``psi'(f)``; the thruster rows (the lags) stay linear.
    The state matrix of the EKF's prediction and of the SDRE controller; (6, 6) or larger.
    """
    A1 = np.array(A, dtype=float)
    A1[:4, 4:6] = A1[:4, 4:6] * saturation_slope(np.asarray(f, dtype=float), F1, F2)
    return A1


def saturated_lf_step(
    x: ArrayLike,
    u: ArrayLike,
    A: ArrayLike,
    dt: float,
    F1: float = 0.02,
    F2: float = 50.0,
    substeps: int = 8,
) -> Array:
    """Integrate the LF model with saturating thrusters over ``dt`` (RK4), input held.

    ``dx/dt = A_0 x + A_f psi(x5, x6) + u`` on the hull rows (``A_0`` = ``A`` without its
    thruster columns there, ``A_f`` those columns) and ``A x + u`` on the thruster rows;
    ``u`` is the whole input ``B u_d (+ other states' coupling)``, (6,). One row of
    :func:`saturated_lf_rows`.
    """
    out = np.array(x, dtype=float).reshape(1, 6)
    u_ = np.ascontiguousarray(np.asarray(u, dtype=float).reshape(1, 6))
    A_ = np.ascontiguousarray(np.asarray(A, dtype=float)[:6, :6])
    saturated_lf_rows(out, u_, A_, float(dt), float(F1), float(F2), int(substeps))
    return out[0]


@njit
def saturated_lf_rows(x, u, A, dt, F1, F2, substeps):  # type: ignore[no-untyped-def]
    """:func:`saturated_lf_step` of every row of ``x`` (N, 6) with its input ``u`` (N, 6),
    in place (``A``: the (6, 6) LF matrix); each row's floats are its own."""
    h = dt / substeps
    k = np.empty((4, 6))
    s = np.empty(6)
    for j in range(x.shape[0]):
        for _ in range(substeps):
            for stage in range(4):
                c = 0.0 if stage == 0 else (h if stage == 3 else 0.5 * h)
                for i in range(6):
                    s[i] = x[j, i] if stage == 0 else x[j, i] + c * k[stage - 1, i]
                p0, p1 = s[4], s[5]
                sat0 = F1 * (1.0 if p0 > 0 else (-1.0 if p0 < 0 else 0.0)) * -math.expm1(
                    -F2 * abs(p0))  # fmt: skip
                sat1 = F1 * (1.0 if p1 > 0 else (-1.0 if p1 < 0 else 0.0)) * -math.expm1(
                    -F2 * abs(p1))  # fmt: skip
                for i in range(6):
                    acc = 0.0
                    for q in range(6):
                        if not (i < 4 and q >= 4):  # the hull rows see psi(x5), psi(x6)
                            acc += A[i, q] * s[q]
                    thr = A[i, 4] * sat0 + A[i, 5] * sat1 if i < 4 else 0.0
                    k[stage, i] = (acc + thr) + u[j, i]
            for i in range(6):
                x[j, i] = x[j, i] + (h / 6.0) * (
                    ((k[0, i] + 2.0 * k[1, i]) + 2.0 * k[2, i]) + k[3, i]
                )
