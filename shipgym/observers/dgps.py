r"""A DGPS receiver's position-velocity Kalman filter (Artyszuk 2003), and what it does to trials.

Public names: ``DGPS_DT``, ``DGPS_SIGMA``, ``S_P_OPTIMAL``, ``DGPSOutput``, ``DGPSPVFilter``,
``DGPSReceiver``, ``PVModel``, ``antenna_motion``, ...

Design notes: docs/design/observers.dgps.md.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.frames import wrap_angle

__all__ = [
    "DGPS_DT",
    "DGPS_SIGMA",
    "S_P_OPTIMAL",
    "DGPSOutput",
    "DGPSPVFilter",
    "DGPSReceiver",
    "PVModel",
    "antenna_motion",
    "apply_current",
    "gain_cycles",
    "pv_lag",
    "pv_filter_batch",
    "pv_model",
    "pv_steady_gain",
    "raw_velocity",
    "velocity_outputs",
    "water_velocity",
]

Array = NDArray[np.float64]

#: the receiver's sample time (s) [printed, Artyszuk 2003 eq. 4]
DGPS_DT = 1.0
#: the DGPS position noise standard deviation (m) per axis [printed, R = diag(4, 4) m^2]
DGPS_SIGMA = 2.0
#: the seed's "optimal" spectral amplitude of the PV random walk (m^2/s^3) [printed]
S_P_OPTIMAL = 0.01


class PVModel(NamedTuple):
    """The printed PV filter matrices (Artyszuk 2003 eqs. 3-4): ``Phi`` (4, 4), ``H`` (2, 4),
    ``Q`` (4, 4) (``S_p`` times the printed pattern of powers of ``dt``; m^2/s^2 on the
    velocities, m^2 on the positions), ``R`` (2, 2) (m^2)."""

    Phi: Array
    H: Array
    Q: Array
    R: Array


def _positive(x: float, name: str, unit: str) -> float:
    if not (isinstance(x, int | float) and math.isfinite(x) and x > 0):
        raise ValueError(f"{name} must be > 0 {unit}, got {x!r}")
    return float(x)


def pv_model(S_p: float = S_P_OPTIMAL, dt: float = DGPS_DT, sigma: float = DGPS_SIGMA) -> PVModel:
    """The PV filter of Artyszuk (2003) eqs. 3-4.

    Args:
        S_p: spectral amplitude of the velocity random walk (m^2/s^3), > 0.
        dt: sample time (s).
        sigma: position noise standard deviation per axis (m).
    """
    S_p = _positive(S_p, "S_p", "m^2/s^3")
    dt = _positive(dt, "dt", "s")
    sigma = _positive(sigma, "sigma", "m")
    Phi = np.eye(4)
    Phi[2, 0] = Phi[3, 1] = dt
    H = np.zeros((2, 4))
    H[0, 2] = H[1, 3] = 1.0
    Q = S_p * np.array(
        [
            [dt, 0.0, dt**2 / 2, 0.0],
            [0.0, dt, 0.0, dt**2 / 2],
            [dt**2 / 2, 0.0, dt**3 / 3, 0.0],
            [0.0, dt**2 / 2, 0.0, dt**3 / 3],
        ]
    )
    R = sigma**2 * np.eye(2)
    return PVModel(Phi, H, Q, R)


def pv_steady_gain(
    S_p: float = S_P_OPTIMAL, dt: float = DGPS_DT, sigma: float = DGPS_SIGMA
) -> tuple[Array, Array]:
    """``(K_inf (4, 2), P_prior (4, 4))``: the converged gain of eq. 5 and the a-priori
    covariance, from the discrete Riccati equation (scipy ``solve_discrete_are``)."""
    m = pv_model(S_p, dt, sigma)
    P = scipy.linalg.solve_discrete_are(m.Phi.T, m.H.T, m.Q, m.R)
    K = P @ m.H.T @ np.linalg.inv(m.H @ P @ m.H.T + m.R)
    return K, P


def gain_cycles(
    S_p: float = S_P_OPTIMAL,
    P0: ArrayLike | None = None,
    tol: float = 0.01,
    dt: float = DGPS_DT,
    sigma: float = DGPS_SIGMA,
    max_cycles: int = 1000,
) -> int:
    """Cycles of the recursion from ``P0`` (default 0) until the gain stays within ``tol``
    (relative, largest entry) of ``K_inf`` (the seed: "< 30 cycles")."""
    m = pv_model(S_p, dt, sigma)
    K_inf, _ = pv_steady_gain(S_p, dt, sigma)
    P = np.zeros((4, 4)) if P0 is None else np.asarray(P0, dtype=float)
    scale = float(np.max(np.abs(K_inf)))
    last_bad = 0
    for k in range(1, max_cycles + 1):
        Pm = m.Phi @ P @ m.Phi.T + m.Q
        K = Pm @ m.H.T @ np.linalg.inv(m.H @ Pm @ m.H.T + m.R)
        P = (np.eye(4) - K @ m.H) @ Pm
        if np.max(np.abs(K - K_inf)) > tol * scale:
            last_bad = k
        elif k - last_bad > 50:
            break
    return last_bad + 1


def pv_lag(
    S_p: float = S_P_OPTIMAL, dt: float = DGPS_DT, sigma: float = DGPS_SIGMA
) -> tuple[float, float, float]:
    """``(tau s, position lag m per m/s^2, noise-only sigma_v m/s)`` of the steady filter.

    ``tau``: the velocity estimate's steady lag behind a velocity that grows at a constant
    acceleration ``a`` (``v_hat = v - a tau``); the position lags by the second figure times
    ``a``; ``sigma_v``: the velocity estimate's standard deviation from the position noise
    alone (a true motion the model holds exactly), from a discrete Lyapunov equation.
    """
    m = pv_model(S_p, dt, sigma)
    K, _ = pv_steady_gain(S_p, dt, sigma)
    IKH = np.eye(4) - K @ m.H
    A = IKH @ m.Phi
    # one axis (north): the truth's step under a unit acceleration, v += dt, x += v dt + dt^2/2
    d = np.array([dt, 0.0, dt**2 / 2, 0.0])
    # the error truth - estimate obeys e+ = (I - K H)(Phi e + d): its steady value for a = 1
    e = np.linalg.solve(np.eye(4) - A, IKH @ d)
    S = scipy.linalg.solve_discrete_lyapunov(A, K @ m.R @ K.T)
    return float(e[0]), float(e[2]), float(math.sqrt(S[0, 0]))


class DGPSPVFilter:
    """The receiver's PV filter: ``step(z) -> [v_NS, v_EW, x, y]`` (m/s, m/s, m, m).

    Args:
        S_p: spectral amplitude of the velocity random walk (m^2/s^3).
        dt: sample time (s).
        sigma: position noise per axis (m).
        steady: the converged gain of eq. 5 (the receiver, default) or the recursion.
        x0: initial state (default: at rest at the origin); the first measurement after
            :meth:`reset` starts the position if ``x0`` is not given.
        P0: initial covariance (the recursion; default ``P_prior`` of the steady filter).
    """

    def __init__(
        self,
        S_p: float = S_P_OPTIMAL,
        dt: float = DGPS_DT,
        sigma: float = DGPS_SIGMA,
        *,
        steady: bool = True,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
    ) -> None:
        self.model = pv_model(S_p, dt, sigma)
        self.S_p, self.dt, self.sigma = float(S_p), float(dt), float(sigma)
        self.steady = bool(steady)
        self.K_inf, self.P_inf = pv_steady_gain(S_p, dt, sigma)
        self._x0 = None if x0 is None else np.asarray(x0, dtype=float).reshape(4).copy()
        self._P0 = self.P_inf.copy() if P0 is None else np.asarray(P0, dtype=float).copy()
        if self._P0.shape != (4, 4):
            raise ValueError(f"P0 must be 4x4, got {self._P0.shape}")
        self.reset()

    def reset(self) -> None:
        """Back to ``x0`` (or to the next measurement) and ``P0``."""
        self.x: Array = np.zeros(4) if self._x0 is None else self._x0.copy()
        self._started = self._x0 is not None
        self.P: Array = self._P0.copy()
        self.K: Array = self.K_inf.copy()

    def step(self, z: ArrayLike) -> Array:
        """One cycle with the measured position ``z = [x, y]`` (m, north, east)."""
        z = np.asarray(z, dtype=float).reshape(-1)
        if z.shape != (2,) or not np.all(np.isfinite(z)):
            raise ValueError(f"z must be a finite position [x, y] (m), got {z}")
        if not self._started:  # the first fix starts the position, at rest
            self.x = np.array([0.0, 0.0, z[0], z[1]])
            self._started = True
            return self.x.copy()
        m = self.model
        x_pred = m.Phi @ self.x
        if self.steady:
            K = self.K_inf
        else:
            Pm = m.Phi @ self.P @ m.Phi.T + m.Q
            K = Pm @ m.H.T @ np.linalg.inv(m.H @ Pm @ m.H.T + m.R)
            self.P = (np.eye(4) - K @ m.H) @ Pm
        self.K = K
        self.x = x_pred + K @ (z - m.H @ x_pred)
        return self.x.copy()

    def run(self, positions: ArrayLike) -> Array:
        """The filter over a series of positions (n, 2): the estimates (n, 4)."""
        p = np.asarray(positions, dtype=float)
        return np.array([self.step(z) for z in p])


def velocity_outputs(
    v_ns: ArrayLike, v_ew: ArrayLike, psi: ArrayLike
) -> tuple[Array, Array, Array]:
    """``(v_xy m/s, course chi rad, drift angle beta_A rad)`` from a ground velocity (north,
    east, m/s) and the gyro heading ``psi`` (rad): ``beta_A = psi - chi`` wrapped (Artyszuk
    2003 §2; ``tan beta = -v/u`` in the body frame)."""
    vn, ve = np.asarray(v_ns, dtype=float), np.asarray(v_ew, dtype=float)
    chi = np.arctan2(ve, vn)
    return np.hypot(vn, ve), chi, np.asarray(wrap_angle(np.asarray(psi, dtype=float) - chi))


def raw_velocity(positions: ArrayLike, dt: float = DGPS_DT) -> Array:
    """The seed's alternative: the raw positions (n, 2) differentiated (central differences,
    one-sided at the ends; ``numpy.gradient``), (n, 2) m/s."""
    p = np.asarray(positions, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 2:
        raise ValueError(f"positions must be (n >= 2, 2), got {p.shape}")
    return np.gradient(p, _positive(dt, "dt", "s"), axis=0)


def _current_body(psi: ArrayLike, speed: float, gamma_c: float) -> Array:
    """The current ``[u_c, v_c]`` (m/s) in the body frame: ``D^T(psi) [|v_c| cos g, |v_c| sin
    g]`` (Artyszuk 2003 §1, ``gamma_c = 0``: a current towards north)."""
    ps = np.asarray(psi, dtype=float)
    cn, ce = speed * math.cos(gamma_c), speed * math.sin(gamma_c)
    return np.stack([np.cos(ps) * cn + np.sin(ps) * ce, -np.sin(ps) * cn + np.cos(ps) * ce], -1)


def water_velocity(v_ground: ArrayLike, psi: ArrayLike, speed: float, gamma_c: float) -> Array:
    """The seed's current correction (§1): ``v_water = v_ground - D^T(psi) [|v_c| cos gamma_c,
    |v_c| sin gamma_c]``, velocities ``[v_x, v_y]`` in the body frame (m/s, (..., 2)).

    Args:
        v_ground: the ground-referenced body velocity (..., 2) (m/s).
        psi: heading (rad), broadcast with ``v_ground[..., 0]``.
        speed: current speed (m/s), >= 0.
        gamma_c: the direction the current goes to (rad; 0 north, pi/2 east).
    """
    if not (math.isfinite(speed) and speed >= 0):
        raise ValueError(f"the current speed must be >= 0 m/s, got {speed!r}")
    return np.asarray(v_ground, dtype=float) - _current_body(psi, speed, gamma_c)


def apply_current(v_water: ArrayLike, psi: ArrayLike, speed: float, gamma_c: float) -> Array:
    """The inverse of :func:`water_velocity`: the ground-referenced body velocity (m/s)."""
    if not (math.isfinite(speed) and speed >= 0):
        raise ValueError(f"the current speed must be >= 0 m/s, got {speed!r}")
    return np.asarray(v_water, dtype=float) + _current_body(psi, speed, gamma_c)


class DGPSOutput(NamedTuple):
    """The receiver's outputs per sample (arrays (..., n)): the velocity estimate ``v_ns``,
    ``v_ew`` (m/s), the position estimate ``x_hat``, ``y_hat`` (m, north, east), the track
    speed ``v_xy`` (m/s), the course ``chi`` and the drift angle ``beta_A`` (rad, with the
    gyro heading; :func:`velocity_outputs`), and the measured antenna positions ``z``
    (..., n, 2) (m)."""

    v_ns: Array
    v_ew: Array
    x_hat: Array
    y_hat: Array
    v_xy: Array
    chi: Array
    beta_A: Array
    z: Array


def _steady_step(x: Array, z: Array, K: Array, dt: float) -> Array:
    """One cycle of eq. 5, ``x+ = Phi x + K (z - H Phi x)``, written out elementwise so that
    a single state (4,) and a batch (..., 4) give bit-identical results."""
    vn, ve = x[..., 0], x[..., 1]
    px, py = x[..., 2] + dt * vn, x[..., 3] + dt * ve
    ex, ey = z[..., 0] - px, z[..., 1] - py
    return np.stack(
        [
            vn + K[0, 0] * ex + K[0, 1] * ey,
            ve + K[1, 0] * ex + K[1, 1] * ey,
            px + K[2, 0] * ex + K[2, 1] * ey,
            py + K[3, 0] * ex + K[3, 1] * ey,
        ],
        axis=-1,
    )


def antenna_motion(eta: ArrayLike, nu: ArrayLike, antenna: ArrayLike) -> tuple[Array, Array]:
    """``(position (..., 2) m, ground velocity (..., 2) m/s)`` north/east of an antenna at
    ``antenna = [x_a, y_a]`` (m, body frame, from the point ``eta``/``nu`` describe):
    ``p = [x, y] + R(psi) a`` and ``v = R(psi) [u - r y_a, v + r x_a]``."""
    eta = np.asarray(eta, dtype=float)
    nu = np.asarray(nu, dtype=float)
    ax, ay = (float(a) for a in np.asarray(antenna, dtype=float).reshape(2))
    c, s = np.cos(eta[..., 2]), np.sin(eta[..., 2])
    pos = np.stack([eta[..., 0] + c * ax - s * ay, eta[..., 1] + s * ax + c * ay], -1)
    ub, vb = nu[..., 0] - nu[..., 2] * ay, nu[..., 1] + nu[..., 2] * ax
    return pos, np.stack([c * ub - s * vb, s * ub + c * vb], -1)


class DGPSReceiver:
    """A DGPS receiver: antenna positions with noise through the PV filter of Artyszuk (2003).

    Given the true pose at the receiver's samples, it forms the antenna position (``eta``'s
    ``[x, y] + R(psi) antenna``), adds ``N(0, sigma^2)`` per axis, runs :class:`DGPSPVFilter`
    started at the truth's antenna state at the first sample (``x0 = [v_N, v_E, x, y]``, the
    straight-run steady state of the notes' setup), and outputs :class:`DGPSOutput` with the
    gyro heading ``psi`` of ``eta`` (noise-free). The outputs are at the antenna; they are not
    transformed back to midship (the seed's comparison with an antenna 40 m aft is at the
    antenna).

    Sample 0 is the initial state itself (no measurement is used there); sample ``k >= 1`` is
    the filter after the measurement ``z_k``. The noise of samples ``1, 2, ...`` comes from
    the generator in that order, two values (north, east) per sample, so the batch
    (:meth:`run`) and the streaming form (:meth:`reset`, :meth:`update`) agree exactly.

    Args:
        S_p: the filter's spectral amplitude (m^2/s^3).
        sigma: the position noise added per axis (m, >= 0; 0 noise-free).
        dt: sample time (s).
        antenna: the antenna's ``[x, y]`` in the body frame (m, forward and starboard of the
            point ``eta`` describes, midship in :mod:`shipgym.dynamics.mmg`); the seed's aft
            antenna is e.g. ``(-40.0, 0.0)``.
        steady: the converged gain (eq. 5, the receiver) or the recursion from ``P_prior``.
        rng: a ``numpy.random.Generator``, a seed, or ``None`` (seed 0).
        filter_sigma: the noise the filter's ``R`` assumes (m; printed ``R = diag(4, 4)``,
            2 m), kept when ``sigma`` is 0.
    """

    def __init__(
        self,
        S_p: float = S_P_OPTIMAL,
        *,
        sigma: float = DGPS_SIGMA,
        dt: float = DGPS_DT,
        antenna: ArrayLike = (0.0, 0.0),
        steady: bool = True,
        rng: np.random.Generator | int | None = None,
        filter_sigma: float = DGPS_SIGMA,
    ) -> None:
        if not (isinstance(sigma, int | float) and math.isfinite(sigma) and sigma >= 0):
            raise ValueError(f"sigma must be >= 0 m, got {sigma!r}")
        a = np.asarray(antenna, dtype=float).reshape(-1)
        if a.shape != (2,) or not np.all(np.isfinite(a)):
            raise ValueError(f"antenna must be a finite [x, y] (m), got {antenna!r}")
        self.filter = DGPSPVFilter(S_p, dt, filter_sigma, steady=steady)
        self.S_p, self.sigma, self.dt = float(S_p), float(sigma), float(dt)
        self.antenna = a
        self.steady = bool(steady)
        self.rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
        self._x: Array | None = None

    def _initial(self, eta0: ArrayLike, nu0: ArrayLike) -> Array:
        p, v = antenna_motion(eta0, nu0, self.antenna)
        return np.r_[v, p]

    def _outputs(self, x: Array, psi: ArrayLike, z: Array) -> DGPSOutput:
        vxy, chi, beta = velocity_outputs(x[..., 0], x[..., 1], psi)
        return DGPSOutput(x[..., 0], x[..., 1], x[..., 2], x[..., 3], vxy, chi, beta, z)

    def _measure(self, pos: Array) -> Array:
        if self.sigma == 0:
            return pos
        return pos + self.sigma * self.rng.standard_normal(pos.shape)

    def _step(self, x: Array, z: Array) -> Array:
        if self.steady:
            return _steady_step(x, z, self.filter.K_inf, self.dt)
        self.filter.x = x
        return self.filter.step(z)

    def reset(self, eta0: ArrayLike, nu0: ArrayLike) -> DGPSOutput:
        """Start at the truth ``eta0 = [x, y, psi]``, ``nu0 = [u, v, r]``; the outputs of
        sample 0 (the initial state)."""
        self.filter.reset()
        self.filter._started = True
        self._x = self._initial(eta0, nu0)
        pos, _ = antenna_motion(eta0, nu0, self.antenna)
        return self._outputs(self._x, np.asarray(eta0, dtype=float)[2], pos)

    def update(self, eta: ArrayLike) -> DGPSOutput:
        """One sample ``dt`` after the last: measure the antenna at the true pose ``eta``,
        filter, and return the outputs."""
        if self._x is None:
            raise RuntimeError("call reset(eta0, nu0) first")
        eta = np.asarray(eta, dtype=float).reshape(3)
        pos, _ = antenna_motion(eta, np.zeros(3), self.antenna)
        z = self._measure(pos)
        self._x = self._step(self._x, z)
        return self._outputs(self._x, eta[2], z)

    def run(self, eta: ArrayLike, nu0: ArrayLike) -> DGPSOutput:
        """The receiver over the true poses ``eta`` (n, 3) sampled at ``dt``, started at the
        truth (``eta[0]``, ``nu0``): outputs of shape (n,)."""
        eta = np.asarray(eta, dtype=float)
        if eta.ndim != 2 or eta.shape[1] != 3 or eta.shape[0] < 1:
            raise ValueError(f"eta must be (n >= 1, 3), got {eta.shape}")
        x = np.empty((eta.shape[0], 4))
        self.reset(eta[0], nu0)
        assert self._x is not None
        x[0] = self._x
        pos, _ = antenna_motion(eta, np.zeros_like(eta), self.antenna)
        z = pos.copy()
        z[1:] = self._measure(pos[1:])
        for k in range(1, eta.shape[0]):
            x[k] = self._x = self._step(self._x, z[k])
        return self._outputs(x, eta[:, 2], z)


def pv_filter_batch(
    z: ArrayLike, x0: ArrayLike, S_p: float = S_P_OPTIMAL, dt: float = DGPS_DT,
    sigma: float = DGPS_SIGMA,
) -> Array:  # fmt: skip
    """The steady filter (eq. 5) over a batch of measurement series at once.

    Args:
        z: measured positions (..., n, 2) (m); sample 0 is not used (the initial state).
        x0: the initial states (..., 4) or (4,) (``[v_N, v_E, x, y]``).
        S_p, dt, sigma: the filter (:func:`pv_model`).

    Returns:
        The estimates (..., n, 4), sample 0 ``x0``; bit-identical to :class:`DGPSReceiver`'s.
    """
    z = np.asarray(z, dtype=float)
    if z.ndim < 2 or z.shape[-1] != 2:
        raise ValueError(f"z must be (..., n, 2), got {z.shape}")
    K, _ = pv_steady_gain(S_p, dt, sigma)
    x = np.broadcast_to(np.asarray(x0, dtype=float), z.shape[:-2] + (4,)).copy()
    out = np.empty(z.shape[:-1] + (4,))
    out[..., 0, :] = x
    for k in range(1, z.shape[-2]):
        x = _steady_step(x, z[..., k, :], K, float(dt))
        out[..., k, :] = x
    return out
