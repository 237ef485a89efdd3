r"""A DGPS receiver's position-velocity Kalman filter (Artyszuk 2003), and what it does to trials.

Public names: ``DGPS_DT``, ``DGPS_SIGMA``, ``S_P_OPTIMAL``, ``DGPSOutput``,
``DGPSReceiver``, ``PVModel``, ``antenna_motion``, ...

Design notes: docs/design/observers.dgps.md.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.frames import wrap_angle

__all__ = [
    "DGPS_DT",
    "DGPS_SIGMA",
    "S_P_OPTIMAL",
    "DGPSOutput",
    "DGPSReceiver",
    "NormalStreams",
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
    """The receivers' outputs (arrays (n,) per sample, (n, k) over ``k`` samples; a single
    receiver's without the leading n): the velocity estimate ``v_ns``, ``v_ew`` (m/s), the
    position estimate ``x_hat``, ``y_hat`` (m, north, east), the track speed ``v_xy`` (m/s),
    the course ``chi`` and the drift angle ``beta_A`` (rad, with the gyro heading;
    :func:`velocity_outputs`), and the measured antenna positions ``z`` (..., 2) (m)."""

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
    out = np.empty(np.broadcast_shapes(x.shape, z.shape[:-1] + (4,)))
    out[..., 0] = vn + K[0, 0] * ex + K[0, 1] * ey
    out[..., 1] = ve + K[1, 0] * ex + K[1, 1] * ey
    out[..., 2] = px + K[2, 0] * ex + K[2, 1] * ey
    out[..., 3] = py + K[3, 0] * ex + K[3, 1] * ey
    return out


def _antenna(eta: Array, ax: float, ay: float) -> tuple[Array, Array, Array]:
    """``(position (..., 2), cos psi, sin psi)`` of the antenna ``[ax, ay]`` at ``eta``."""
    c, s = np.cos(eta[..., 2]), np.sin(eta[..., 2])
    pos = np.empty(eta.shape[:-1] + (2,))
    pos[..., 0] = eta[..., 0] + c * ax - s * ay
    pos[..., 1] = eta[..., 1] + s * ax + c * ay
    return pos, c, s


def antenna_motion(eta: ArrayLike, nu: ArrayLike, antenna: ArrayLike) -> tuple[Array, Array]:
    """``(position (..., 2) m, ground velocity (..., 2) m/s)`` north/east of an antenna at
    ``antenna = [x_a, y_a]`` (m, body frame, from the point ``eta``/``nu`` describe):
    ``p = [x, y] + R(psi) a`` and ``v = R(psi) [u - r y_a, v + r x_a]``."""
    eta = np.asarray(eta, dtype=float)
    nu = np.asarray(nu, dtype=float)
    ax, ay = np.asarray(antenna, dtype=float).reshape(2).tolist()
    pos, c, s = _antenna(eta, ax, ay)
    ub, vb = nu[..., 0] - nu[..., 2] * ay, nu[..., 1] + nu[..., 2] * ax
    vel = np.empty(np.broadcast_shapes(eta.shape[:-1], nu.shape[:-1]) + (2,))
    vel[..., 0] = c * ub - s * vb
    vel[..., 1] = s * ub + c * vb
    return pos, vel


class NormalStreams:
    """Standard normal draws of ``n`` envs, ``width`` per draw, each env from its own
    generator in blocks of ``block`` draws, refilled when used up: ``standard_normal((k,
    width))`` is the stream of ``k`` calls of ``standard_normal(width)``, whatever ``n``.

    Args:
        n: number of envs; width: values per draw; block: draws per refill.
        rng: each env's generator: a ``numpy.random.Generator``, a seed or ``None`` (seed 0),
            or a sequence of ``n`` of them.
    """

    def __init__(self, n: int, width: int, block: int = 64, rng: Any = None) -> None:
        self.n, self.width, self.block = n, int(width), int(block)
        rngs = list(rng) if isinstance(rng, list | tuple) else [rng] * n
        if len(rngs) != n:
            raise ValueError(f"rng must be one generator or seed, or {n} of them; got {rng!r}")
        self._draws = np.zeros((n, self.block, self.width))
        self._k = np.full(n, self.block, dtype=np.int64)  # next unused draw (block: refill)
        self._rows = np.arange(n)
        self.rngs: list[np.random.Generator] = [None] * n  # type: ignore[list-item]
        for i, r in enumerate(rngs):
            self.seed(i, r)

    def seed(self, i: int, rng: Any) -> None:
        """Env ``i`` draws from ``rng`` (a generator or a seed) from now on."""
        self.rngs[i] = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
        self._k[i] = self.block

    def draw(self, mask: NDArray[np.bool_]) -> Array:
        """The next draw (n, width) of the envs of ``mask`` (zeros elsewhere)."""
        for i in np.nonzero(mask & (self._k >= self.block))[0].tolist():
            self._draws[i] = self.rngs[i].standard_normal((self.block, self.width))
            self._k[i] = 0
        k = np.minimum(self._k, self.block - 1)
        self._k += mask
        return np.where(mask[:, None], self._draws[self._rows, k], 0.0)


class DGPSReceiver:
    """``n`` DGPS receivers: antenna positions with noise through the PV filter of Artyszuk
    (2003), one row per receiver (the one form of the receiver; ``n = 1`` is a single one).

    Given each receiver's true pose at its samples, it forms the antenna position (``eta``'s
    ``[x, y] + R(psi) antenna``), adds ``N(0, sigma^2)`` per axis, runs the filter (eq. 5,
    :func:`_steady_step`; or the recursion from ``P_prior``) started at the truth's antenna
    state (``x0 = [v_N, v_E, x, y]``, the straight-run steady state of the notes' setup), and
    outputs :class:`DGPSOutput` with the gyro heading ``psi`` of ``eta`` (noise-free), at the
    antenna (not transformed back to midship).

    Sample 0 is the initial state itself (:meth:`reset`, no measurement); each
    :meth:`update` is the filter after one more measurement. Receiver ``i``'s noise comes
    from its own generator, two values (north, east) per update (:class:`NormalStreams`,
    drawn ahead in blocks: give each receiver its own generator), so receiver ``i`` of a
    batch is bit for bit a single receiver with the same generator. Poses are ``(n, 3)`` and
    outputs ``(n,)`` (``z`` ``(n, 2)``); a single receiver also takes ``(3,)``, giving its row.

    Args:
        S_p: the filter's spectral amplitude (m^2/s^3).
        n: the number of receivers, >= 1.
        sigma: the position noise added per axis (m, >= 0; 0 noise-free, no draws).
        dt: sample time (s).
        antenna: the antenna's ``[x, y]`` in the body frame (m, forward and starboard of the
            point ``eta`` describes, midship in :mod:`shipgym.dynamics.mmg`); the seed's aft
            antenna is e.g. ``(-40.0, 0.0)``.
        steady: the converged gain (eq. 5, the receiver) or the recursion from ``P_prior``.
        rng: each receiver's noise generator: a ``numpy.random.Generator``, a seed or
            ``None`` (seed 0), or a sequence of ``n`` of them; :meth:`reset` may replace them.
        filter_sigma: the noise the filter's ``R`` assumes (m; printed ``R = diag(4, 4)``,
            2 m), kept when ``sigma`` is 0.
        block: updates drawn per refill of a receiver's noise.
    """

    def __init__(
        self,
        S_p: float = S_P_OPTIMAL,
        *,
        n: int = 1,
        sigma: float = DGPS_SIGMA,
        dt: float = DGPS_DT,
        antenna: ArrayLike = (0.0, 0.0),
        steady: bool = True,
        rng: Any = None,
        filter_sigma: float = DGPS_SIGMA,
        block: int = 64,
    ) -> None:
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ValueError(f"n must be an int >= 1 (the number of receivers), got {n!r}")
        if not (isinstance(sigma, int | float) and math.isfinite(sigma) and sigma >= 0):
            raise ValueError(f"sigma must be >= 0 m, got {sigma!r}")
        a = np.asarray(antenna, dtype=float).reshape(-1)
        if a.shape != (2,) or not np.all(np.isfinite(a)):
            raise ValueError(f"antenna must be a finite [x, y] (m), got {antenna!r}")
        self.model = pv_model(S_p, dt, filter_sigma)
        self.K_inf, self.P_inf = pv_steady_gain(S_p, dt, filter_sigma)
        self.n = n
        self.S_p, self.sigma, self.dt = float(S_p), float(sigma), float(dt)
        self.antenna = a
        self.steady = bool(steady)
        self.block = int(block)
        self.noise = NormalStreams(n, 2, self.block, rng)
        self.x = np.zeros((n, 4))  # the estimates [v_N, v_E, x, y]
        self.z = np.zeros((n, 2))  # the last measured antenna positions
        self.psi = np.zeros(n)  # the gyro headings of the last samples (rad)
        self.P = np.broadcast_to(self.P_inf, (n, 4, 4)).copy()  # the recursion's covariance
        self.K = np.broadcast_to(self.K_inf, (n, 4, 2)).copy()  # the last gain
        self._all = np.ones(n, dtype=bool)
        self._started = False

    @property
    def rngs(self) -> list[np.random.Generator]:
        """Each receiver's noise generator."""
        return self.noise.rngs

    def _rows(self, x: ArrayLike, what: str) -> tuple[Array, bool]:
        a = np.asarray(x, dtype=float)
        one = a.ndim == 1 and self.n == 1
        a = a.reshape(1, -1) if one else a
        if a.shape != (self.n, 3) or not np.all(np.isfinite(a)):
            raise ValueError(f"{what} must be ({self.n}, 3) finite values, got {np.shape(x)}")
        return a, one

    def _outputs(self, one: bool) -> DGPSOutput:
        x = self.x
        vxy, chi, beta = velocity_outputs(x[:, 0], x[:, 1], self.psi)
        out = DGPSOutput(x[:, 0], x[:, 1], x[:, 2], x[:, 3], vxy, chi, beta, self.z)
        return DGPSOutput(*(f[0].copy() if one else f.copy() for f in out))

    def reset(
        self, eta0: ArrayLike, nu0: ArrayLike, *, rngs: Any = None, mask: ArrayLike | None = None
    ) -> DGPSOutput:
        """Start the receivers (all, or those where ``mask`` is True) at the truth ``eta0 =
        [x, y, psi]``, ``nu0 = [u, v, r]``; ``rngs``: new noise generators (or seeds), one
        per receiver (the reset ones are taken), else each goes on with its own. Returns the
        outputs of sample 0 (the initial state)."""
        eta, one = self._rows(eta0, "eta0")
        nu, _ = self._rows(nu0, "nu0")
        m = self._all if mask is None else np.asarray(mask, dtype=bool)
        if m.shape != (self.n,):
            raise ValueError(f"mask must be ({self.n},) booleans, got {m.shape}")
        if rngs is not None and len(rngs) != self.n:
            raise ValueError(f"rngs must hold one generator per receiver ({self.n})")
        for i in np.nonzero(m)[0].tolist() if rngs is not None else ():
            self.noise.seed(i, rngs[i])
        p, v = antenna_motion(eta, nu, self.antenna)
        mc = m[:, None]
        self.x = np.where(mc, np.concatenate([v, p], 1), self.x)
        self.z = np.where(mc, p, self.z)
        self.psi = np.where(m, eta[:, 2], self.psi)
        self.P = np.where(mc[:, :, None], self.P_inf, self.P)
        self.K = np.where(mc[:, :, None], self.K_inf, self.K)
        self._started = True
        return self._outputs(one)

    def update(self, eta: ArrayLike, *, mask: ArrayLike | None = None) -> DGPSOutput:
        """One sample ``dt`` after the last, of the receivers of ``mask`` (default all; the
        others keep their state and draws): measure the antenna at the true poses ``eta``,
        filter, and return the outputs (every row; the others' as after their last sample)."""
        if not self._started:
            raise RuntimeError("call reset(eta0, nu0) first")
        e, one = self._rows(eta, "eta")
        m = self._all if mask is None else np.asarray(mask, dtype=bool)
        pos, _, _ = _antenna(e, *self.antenna.tolist())
        z = pos if self.sigma == 0 else pos + self.sigma * self.noise.draw(m)
        if self.steady:
            x = _steady_step(self.x, z, self.K_inf, self.dt)
        else:  # the recursion, each receiver's 4x4 matrices (stacked products)
            md = self.model
            Pm = md.Phi @ self.P @ md.Phi.T + md.Q
            K = Pm @ md.H.T @ np.linalg.inv(md.H @ Pm @ md.H.T + md.R)
            xp = (md.Phi @ self.x[:, :, None])[:, :, 0]
            x = xp + (K @ (z - xp[:, 2:])[:, :, None])[:, :, 0]
            mm = m[:, None, None]
            self.P = np.where(mm, (np.eye(4) - K @ md.H) @ Pm, self.P)
            self.K = np.where(mm, K, self.K)
        if m.all():
            self.x, self.z, self.psi = x, z, e[:, 2].copy()
        else:
            self.x = np.where(m[:, None], x, self.x)
            self.z = np.where(m[:, None], z, self.z)
            self.psi = np.where(m, e[:, 2], self.psi)
        return self._outputs(one)

    def run(self, eta: ArrayLike, nu0: ArrayLike) -> DGPSOutput:
        """The receivers over their true poses ``eta`` (n, k, 3) (or (k, 3) for a single
        one) sampled at ``dt``, started at the truth (``eta[..., 0, :]``, ``nu0``): the
        outputs of shape (n, k) (or (k,)); :meth:`reset`, then :meth:`update` per sample."""
        e = np.asarray(eta, dtype=float)
        if e.ndim < 2 or e.shape[-1] != 3 or e.shape[-2] < 1:
            raise ValueError(f"eta must be (n, k >= 1, 3) or (k >= 1, 3), got {e.shape}")
        outs = [self.reset(e[..., 0, :], nu0)]
        outs += [self.update(e[..., k, :]) for k in range(1, e.shape[-2])]
        fields = list(zip(*outs, strict=True))
        return DGPSOutput(*(np.stack(f, axis=-2 if j == 7 else -1) for j, f in enumerate(fields)))


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
