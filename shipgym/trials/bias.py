r"""The DGPS receiver's bias on a manoeuvring trial (Artyszuk 2003 §2-3, the notes' study).

Public names: ``METHODS``, ``ReceiverBias``, ``receiver_bias``, ``resample``.

Design notes: docs/design/trials.bias.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.frames import wrap_angle
from shipgym.observers.dgps import (
    DGPS_DT,
    DGPS_SIGMA,
    antenna_motion,
    pv_filter_batch,
    velocity_outputs,
    water_velocity,
)

__all__ = ["METHODS", "ReceiverBias", "receiver_bias", "resample"]

Array = NDArray[np.float64]

#: the velocity estimates of :func:`receiver_bias`: the receiver's PV filter, or the raw
#: positions differentiated (the seed's recommendation)
METHODS = ("dgps-pv", "raw")


@dataclass(frozen=True)
class ReceiverBias:
    """The receiver's bias and noise on one trial (SI: m/s, rad, m).

    Attributes:
        S_p (m^2/s^3), sigma (m), runs, seed, transient (s), corrected, method: the set-up.
        speed_bias_max, speed_bias_min, speed_bias_rms: ``v_xy_hat - v_xy`` (m/s).
        drift_bias_max, drift_bias_min, drift_bias_rms: ``beta_A_hat - beta_A`` (rad).
        position_bias_max, position_bias_rms: ``|p_hat - p|`` (m).
        sigma_v (m/s), sigma_beta (rad): the Monte-Carlo spread (0 when ``sigma`` is 0).
        t: the receiver's sample times (s); truth: ``v_xy``, ``beta_A``, ``x``, ``y`` of the
            truth; estimate: the same of the noise-free estimate and its ``position_error``
            (arrays, for plots; not compared).
    """

    S_p: float
    sigma: float
    runs: int
    seed: int
    transient: float
    corrected: bool
    method: str
    speed_bias_max: float
    speed_bias_min: float
    speed_bias_rms: float
    drift_bias_max: float
    drift_bias_min: float
    drift_bias_rms: float
    position_bias_max: float
    position_bias_rms: float
    sigma_v: float
    sigma_beta: float
    t: Array = field(compare=False, repr=False)
    truth: dict[str, Array] = field(compare=False, repr=False)
    estimate: dict[str, Array] = field(compare=False, repr=False)


def resample(
    t: ArrayLike, eta: ArrayLike, nu: ArrayLike, dt: float = DGPS_DT
) -> tuple[Array, Array, Array]:
    """``(t_k, eta_k, nu_k)`` at ``t[0] + k dt`` up to ``t[-1]``, linearly interpolated
    (``psi`` unwrapped, then wrapped back)."""
    t = np.asarray(t, dtype=float).reshape(-1)
    eta = np.asarray(eta, dtype=float)
    nu = np.asarray(nu, dtype=float)
    if t.size < 2 or eta.shape != (t.size, 3) or nu.shape != (t.size, 3):
        raise ValueError(f"t (n,), eta (n, 3), nu (n, 3) needed, got {t.shape}, {eta.shape}, "
                         f"{nu.shape}")  # fmt: skip
    if not np.all(np.diff(t) > 0):
        raise ValueError("t must be increasing")
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be > 0 s, got {dt!r}")
    n = int(math.floor((t[-1] - t[0]) / dt + 1e-9)) + 1
    tk = t[0] + dt * np.arange(n)
    psi = np.unwrap(eta[:, 2])
    e = np.stack([np.interp(tk, t, eta[:, 0]), np.interp(tk, t, eta[:, 1]),
                  np.asarray(wrap_angle(np.interp(tk, t, psi)))], -1)  # fmt: skip
    v = np.stack([np.interp(tk, t, nu[:, i]) for i in range(3)], -1)
    return tk, e, v


def _speed_drift(
    v_ne: Array, psi: Array, current: tuple[float, float] | None, correct: bool
) -> tuple[Array, Array]:
    """``(v_xy, beta_A)`` of ground velocities (..., 2) north/east: as the receiver outputs
    them, or water-referenced (the seed's correction)."""
    if not correct:
        vxy, _, beta = velocity_outputs(v_ne[..., 0], v_ne[..., 1], psi)
        return vxy, beta
    c, s = np.cos(psi), np.sin(psi)
    body = np.stack([c * v_ne[..., 0] + s * v_ne[..., 1], -s * v_ne[..., 0] + c * v_ne[..., 1]],
                    -1)  # fmt: skip
    speed, gamma = current if current is not None else (0.0, 0.0)
    w = water_velocity(body, psi, speed, gamma)
    return np.hypot(w[..., 0], w[..., 1]), np.arctan2(-w[..., 1], w[..., 0])


def receiver_bias(
    t: ArrayLike,
    eta: ArrayLike,
    nu: ArrayLike,
    *,
    S_p: float,
    sigma: float = DGPS_SIGMA,
    antenna: ArrayLike = (0.0, 0.0),
    runs: int = 50,
    seed: int = 0,
    current: tuple[float, float] | None = None,
    correct: bool = False,
    dt: float = DGPS_DT,
    transient: float = 30.0,
    method: str = "dgps-pv",
) -> ReceiverBias:
    """The receiver's bias and noise on a true trial (module docstring).

    Args:
        t: sample times (s) of the truth, (n,), increasing.
        eta: the true ground-referenced pose ``[x, y, psi]`` (m, m, rad) (n, 3).
        nu: the true ground-referenced body velocity ``[u, v, r]`` (m/s, m/s, rad/s) (n, 3).
        S_p: the filter's spectral amplitude (m^2/s^3).
        sigma: the position noise of the Monte Carlo (m per axis, >= 0).
        antenna: the antenna ``[x, y]`` in the body frame (m from the point of ``eta``).
        runs: Monte-Carlo runs (>= 2 unless ``sigma`` is 0).
        seed: the Monte Carlo's generator seed.
        current: ``(speed m/s, gamma_c rad)`` of the current (Artyszuk 2003 §1: ``gamma_c = 0``
            a current towards north), used when ``correct``.
        correct: compare water-referenced velocities (the seed's correction).
        dt: the receiver's sample time (s); transient: the seconds the noise statistics skip.
        method: ``"dgps-pv"`` (the receiver's filter) or ``"raw"``: the seed's recommended
            alternative, the raw positions differentiated (central differences,
            :func:`~shipgym.observers.dgps.raw_velocity`; no lag, the full noise).

    Returns:
        :class:`ReceiverBias`.
    """
    if not (isinstance(sigma, int | float) and math.isfinite(sigma) and sigma >= 0):
        raise ValueError(f"sigma must be >= 0 m, got {sigma!r}")
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if not (isinstance(runs, int) and runs >= 2):
        raise ValueError(f"runs must be an integer >= 2, got {runs!r}")
    if current is not None:
        speed, gamma = (float(c) for c in current)
        if not (math.isfinite(speed) and speed >= 0 and math.isfinite(gamma)):
            raise ValueError(f"current must be (speed >= 0 m/s, gamma_c rad), got {current!r}")
        current = (speed, gamma)
    tk, e, v = resample(t, eta, nu, dt)
    if tk.size < 2:
        raise ValueError("the record is shorter than one receiver sample")
    psi = e[:, 2]
    pos, vel = antenna_motion(e, v, antenna)
    x0 = np.r_[vel[0], pos[0]]

    def estimate(z: Array) -> Array:
        if method == "raw":
            return np.concatenate([np.gradient(z, dt, axis=-2), z], -1)
        return pv_filter_batch(z, x0, S_p, dt)

    free = estimate(pos)
    v_true, b_true = _speed_drift(vel, psi, current, correct)
    v_hat, b_hat = _speed_drift(free[:, :2], psi, current, correct)
    dv = v_hat - v_true
    db = np.asarray(wrap_angle(b_hat - b_true))
    perr = np.hypot(free[:, 2] - pos[:, 0], free[:, 3] - pos[:, 1])
    keep = tk - tk[0] >= transient
    if sigma > 0 and keep.any():
        rng = np.random.default_rng(seed)
        z = np.broadcast_to(pos, (runs,) + pos.shape).copy()
        z[:, 1:] += sigma * rng.standard_normal((runs, tk.size - 1, 2))
        mc = estimate(z)
        v_mc, b_mc = _speed_drift(mc[..., :2], psi, current, correct)
        sig_v = float(np.sqrt(np.mean((v_mc - v_hat)[:, keep] ** 2)))
        sig_b = float(np.sqrt(np.mean(np.asarray(wrap_angle(b_mc - b_hat))[:, keep] ** 2)))
    else:
        sig_v = sig_b = 0.0
    rms = lambda a: float(np.sqrt(np.mean(a**2)))  # noqa: E731
    return ReceiverBias(
        S_p=float(S_p), sigma=float(sigma), runs=runs, seed=int(seed),
        transient=float(transient), corrected=bool(correct), method=method,
        speed_bias_max=float(dv.max()), speed_bias_min=float(dv.min()), speed_bias_rms=rms(dv),
        drift_bias_max=float(db.max()), drift_bias_min=float(db.min()), drift_bias_rms=rms(db),
        position_bias_max=float(perr.max()), position_bias_rms=rms(perr),
        sigma_v=sig_v, sigma_beta=sig_b, t=tk,
        truth={"v_xy": v_true, "beta_A": b_true, "x": pos[:, 0], "y": pos[:, 1]},
        estimate={"v_xy": v_hat, "beta_A": b_hat, "x": free[:, 2], "y": free[:, 3],
                  "position_error": perr},
    )  # fmt: skip
