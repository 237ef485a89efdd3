r"""The thesis's simulation in per-unit time (``seed-per-unit``): Al-Takie (1982) ch. 5-7.

Public names: ``FILTERS``, ``SEAS``, ``SeedRun``, ``PLANT_NOISE``, ``physical_d_h``,
``simulate_seed``.

The plant's first-order (HF) motion is the physical sea's by default: the JONSWAP sea of the
Beaufort number (:func:`shipgym.disturbances.seastate.beaufort`: WMO ``Hs``, NORSOK ``Tp``)
gives the HF position std ``Hs / 16`` and its heading std, which set the plant's HF noise
gains through the thesis's own HF filters (:func:`physical_d_h`): 0.34 m and 0.33 deg in
Beaufort 8. The filter keeps its design noise (:data:`~shipgym.dynamics.altakie.
D_H_RECONSTRUCTED`, which reproduces the printed gains): it implies 9.6 m sway and 22 deg
yaw HF motion in Beaufort 8, which no ship of this size has. The Kalman gain depends on the
noise covariances' ratios only (``K(a Q, a R) = K(Q, R)``), so the printed gains fix the HF
noise relative to the printed measurement noise ``R`` (1/3 m, 0.02 rad); a physical HF noise
reproduces them only with ``R`` and ``Q_l`` scaled down by the same factor (a position
reference of about 1 cm): the thesis's ``D_h`` is a tuning knob of the filter, not the sea
(``sea="design"`` drives the plant with it, as the thesis's own simulation did).

Design notes: docs/design/dp.seed.md.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from shipgym.controllers.design import lqr
from shipgym.controllers.grimble import PRINTED_GAINS, grimble_weights
from shipgym.dynamics.altakie import (
    R_PRINTED,
    discretise,
    lf_model,
    saturated_lf_matrix,
    saturated_lf_step,
    wave_filter_model,
)
from shipgym.observers.wavefilter import DiscreteKF, ReducedKF, WaveFilterEKF

__all__ = ["FILTERS", "SEAS", "SeedRun", "PLANT_NOISE", "physical_d_h", "simulate_seed"]

Array = NDArray[np.float64]

#: the simulation's LF disturbance variances (sway force, yaw moment; p.u.^2) [printed 5.3.2]
PLANT_NOISE = (4.0e-6, 9.0e-8)

#: filters of :func:`simulate_seed`
FILTERS = ("kf14", "kf12", "semiconstant", "ekf")

#: what drives the plant's HF motion in :func:`simulate_seed`: ``"physical"`` the Beaufort
#: sea's first-order motion (:func:`physical_d_h`), ``"design"`` the filter's reconstructed
#: design noise (the thesis's own simulation)
SEAS = ("physical", "design")


def physical_d_h(ship: str, beaufort: int) -> tuple[float, float]:
    """The HF noise gains ``(d_sway, d_yaw)`` (p.u.) that give the thesis's HF filter of
    ``ship`` in ``beaufort`` the first-order motion of the physical sea: the position std
    ``Hs / 16`` (m) and heading std (rad) of :func:`shipgym.disturbances.seastate.beaufort`
    at full scale (the stationary std of the HF block, :func:`~shipgym.observers.wavefilter.
    hf_gain_for_std`)."""
    from shipgym.disturbances.seastate import beaufort as sea_state
    from shipgym.dynamics.altakie import hf_alpha
    from shipgym.observers.wavefilter import hf_gain_for_std

    pu = lf_model(ship).per_unit
    waves = sea_state(int(beaufort), scale=1.0).waves  # the thesis's ships: full scale
    alpha = hf_alpha(int(beaufort), pu, ship)
    return (
        hf_gain_for_std(alpha, pu.time, float(waves.position_std) / pu.L),
        hf_gain_for_std(alpha, pu.time, float(waves.heading_std)),
    )


@dataclass(frozen=True)
class SeedRun:
    """One per-unit run.

    Attributes:
        t: sample times (s, real time), (n,).
        x: true states (p.u.), (n, 14).
        x_hat: filter estimates (p.u.; the reduced filter's thruster states are the measured
            ones), (n, 14).
        u: thruster demands (p.u.), (n, 2).
        z: measurements (p.u.), (n, 2).
        K: the filter gain at every step, (n, n_filter, 2).
        nis: normalised innovation squared per step, (n,).
        filter_seconds: wall time spent in the filter (s).
        per_unit_time: ``T_b`` (s).
    """

    t: Array
    x: Array
    x_hat: Array
    u: Array
    z: Array
    K: Array
    nis: Array
    filter_seconds: float
    per_unit_time: float

    def lf_rms_error(self) -> Array:
        """RMS of ``x_hat - x`` over the LF states ``[v, y, r, psi]`` (p.u.)."""
        return np.sqrt(np.mean((self.x_hat[:, :4] - self.x[:, :4]) ** 2, axis=0))

    def rise_time(self, step: float, fraction: float = 0.9) -> float:
        """First time (s) the true sway position reaches ``fraction`` of the step."""
        hit = np.nonzero(self.x[:, 1] >= fraction * step)[0]
        return float(self.t[hit[0]]) if hit.size else math.inf


def simulate_seed(
    ship: str = "wimpey-sealab",
    filter: str = "kf14",
    *,
    duration: float = 120.0,
    step: float = 0.02,
    step_yaw: float = 0.0,
    beaufort: int = 8,
    filter_beaufort: int | None = None,
    noise_scale: float = 1.0,
    saturate: bool = False,
    F1: float = 0.02,
    relinearise_every: int = 2,
    freeze_time: float = 28.0,
    gain: str = "b",
    dt: float = 0.1,
    seed: int = 0,
    noise: bool = True,
    sea: str = "physical",
) -> SeedRun:
    """Run the thesis's closed loop (plant, filter, LQ) in per-unit time.

    Args:
        ship: ``"wimpey-sealab"`` or ``"star-hercules"`` (printed LF models).
        filter: one of :data:`FILTERS`.
        duration: real time (s).
        step, step_yaw: set-point steps (p.u. position, rad) applied at ``t = 0``.
        beaufort: the plant's HF model (5-9); ``filter_beaufort`` the filter's (default the
            same; 6.4: plant 8, filter 5).
        noise_scale: factor on the plant's measurement-noise variance (the filter keeps R).
        saturate: plant thrusters through ``psi`` (ch. 7); with ``filter="ekf"`` the
            controller is the SDRE, re-solved every ``relinearise_every`` steps.
        F1: saturation level (p.u.); ``F2 = 1 / F1``.
        freeze_time: the semi-constant filter's freeze (s real time).
        gain: ``"b"`` or ``"a"`` (Grimble's cases, re-solved by CARE) or ``"printed"`` (the
            printed gain: Wimpey case b, the Star Hercules gain).
        dt: sampling interval (p.u. time).
        seed: noise seed.
        noise: ``False``: no disturbance and no measurement noise (the deterministic response).
        sea: what drives the plant's HF motion, one of :data:`SEAS` (module docstring):
            ``"physical"`` (default) or ``"design"`` (the filter's design noise).
    """
    if filter not in FILTERS:
        raise ValueError(f"filter must be one of {', '.join(FILTERS)}, got {filter!r}")
    if not (isinstance(noise_scale, int | float) and noise_scale > 0):
        raise ValueError(f"noise_scale must be > 0, got {noise_scale!r}")
    if sea not in SEAS:
        raise ValueError(f"sea must be one of {', '.join(SEAS)}, got {sea!r}")
    lf = lf_model(ship)
    Tb = lf.per_unit.time
    d_h = physical_d_h(ship, beaufort) if sea == "physical" else None
    plant = wave_filter_model(lf, beaufort, ship=ship, q_l=PLANT_NOISE, d_h=d_h)
    design = wave_filter_model(lf, filter_beaufort or beaufort, ship=ship)
    Phi, Delta, Gamma = discretise(plant.A, plant.B, plant.G, dt)
    Q, R, _, _ = grimble_weights(lf.A, lf.B, lf.C, (1.5, 1.0) if gain == "a" else None)
    if gain == "printed":
        key = f"{ship}/b" if ship == "wimpey-sealab" else ship
        K = -PRINTED_GAINS[key]
    elif gain in ("a", "b"):
        K = lqr(lf.A, lf.B, Q, R)[0]
    else:
        raise ValueError(f"gain must be 'a', 'b' or 'printed', got {gain!r}")
    freeze = math.ceil(freeze_time / (dt * Tb) - 1e-9) if filter == "semiconstant" else None
    if filter == "kf12":
        kf: DiscreteKF = ReducedKF(design, dt)
    elif filter == "ekf":
        kf = WaveFilterEKF(design, dt, F1=F1, F2=1.0 / F1, relinearise_every=relinearise_every)
    else:
        kf = DiscreteKF(design.A, design.B, design.G, design.H, design.Q, design.R, dt, freeze)
    rng = np.random.default_rng(seed)
    n = int(round(duration / (dt * Tb)))
    x = np.zeros(14)
    x_ref = np.array([0.0, step, 0.0, step_yaw, 0.0, 0.0])
    w_std = np.sqrt(np.diag(plant.Q) / dt) * float(noise)
    v_std = np.sqrt(np.asarray(R_PRINTED) * noise_scale) * float(noise)
    out_x = np.zeros((n, 14))
    out_xh = np.zeros((n, 14))
    out_u = np.zeros((n, 2))
    out_z = np.zeros((n, 2))
    out_K = np.zeros((n, kf.n, 2))
    out_nis = np.full(n, np.nan)
    sdre = filter == "ekf" and saturate
    K_now = K
    spent = 0.0
    for k in range(n):
        lf_hat = _lf_estimate(kf, x) if k else np.zeros(6)
        if sdre and k % relinearise_every == 0:
            # the slope of psi at the estimate, as the thesis's linearised entries (7.19-7.21)
            A1 = saturated_lf_matrix(lf.A, lf_hat[4:6], F1, 1.0 / F1)
            K_now = lqr(A1, lf.B, Q, R)[0]
        u = -K_now @ (lf_hat - x_ref)
        f0 = x[4:6].copy()
        w = rng.normal(size=4) * w_std
        if saturate:
            x_lf = saturated_lf_step(x[:6], plant.B[:6] @ u, plant.A, dt, F1, 1.0 / F1)
            x = np.concatenate([x_lf, Phi[6:, 6:] @ x[6:]]) + Gamma @ w
        else:
            x = Phi @ x + Delta @ u + Gamma @ w
        z = plant.H @ x + rng.normal(size=2) * v_std
        t0 = time.perf_counter()
        if isinstance(kf, ReducedKF):
            kf.step_thrust(z, f0, x[4:6])
        else:
            kf.predict(u)
            kf.update(z)
        spent += time.perf_counter() - t0
        out_x[k] = x
        out_xh[k] = _full_estimate(kf, x)
        out_u[k] = u
        out_z[k] = z
        out_K[k] = kf.K
        out_nis[k] = np.nan if kf.nis is None else kf.nis
    t = (np.arange(n) + 1) * dt * Tb
    return SeedRun(t, out_x, out_xh, out_u, out_z, out_K, out_nis, spent, Tb)


def _lf_estimate(kf: DiscreteKF, x_true: Array) -> Array:
    if isinstance(kf, ReducedKF):  # the thruster states are measured
        return np.r_[kf.x[:4], x_true[4:6]]
    return kf.x[:6].copy()


def _full_estimate(kf: DiscreteKF, x_true: Array) -> Array:
    if isinstance(kf, ReducedKF):
        return np.r_[kf.x[:4], x_true[4:6], kf.x[4:]]
    return kf.x.copy()
