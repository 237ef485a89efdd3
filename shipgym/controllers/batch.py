r"""The DP controller and its thrust allocation for N envs at once (batched forms).

The batched counterparts of what :class:`~shipgym.controllers.wrappers.DPControllerWrapper`
runs every control period for ``controller="pid"`` (and ``"pid-smooth"``, ``"pid-raw"``,
``"pid-smooth-raw"``, ``"pid-seed"``), command conditioning included
(:mod:`shipgym.controllers.conditioning`):

- :class:`BatchedPID`: :class:`~shipgym.controllers.pid.MultivariablePID` (Tomera 2014 eq. 23
  in the r-frame of the current leg, forward-Euler integral (eq. 17) with conditional
  integration from the allocation's saturation directions, the clamp of the integral force,
  :meth:`~shipgym.controllers.pid.MultivariablePID.change_frame` on a leg switch) for N envs
  with the same gains and model and one integral state per env;
- :class:`BatchedAllocation`: the allocations that are closed forms, i.e. the Blue Lady
  pattern (a main propeller and two tunnel thrusters, Tomera 2014 eq. 12): the exact
  box-constrained least squares :func:`~shipgym.controllers.allocation.allocate`
  (``"constrained"``) and the paper's ``F = T^-1 tau`` with saturation
  :func:`~shipgym.controllers.allocation.allocate_inverse` (``"inverse"``, eq. 25), with the
  inverse thruster characteristics (eqs. 26-27) and the normalised actions of the envs;
- :func:`batched_dp_controller`: the two for a vessel and a controller name, designed as the
  wrapper's factories design them (:class:`BatchedDPController`).

Every env's result equals the scalar class's to round-off: the same floating-point operations
in the same order on ``(N,)`` arrays instead of Python floats (only ``cos``/``sin`` may differ
in the last bit), and every branch of the scalar code (anti-windup, clamp, allocation edge) is
a per-env selection (``np.where``) here, with the work skipped when no env takes it.

The iterative allocations (the active-set weighted least squares of fixed-thruster sets, the
azimuth QP) are not batched: :class:`BatchedAllocation` raises ``NotImplementedError`` naming
the vessel and the method. (An exact batch of the active-set method would not even agree with
the scalar solver to 1e-10: the regularised problem of a redundant set is conditioned ~2e9
(Star Hercules), so another exact solver of the same system moves the least-thrust direction by
~5e-9 of the thrust range (LU against the scalar's Cholesky, unsaturated requests); only an
operation-for-operation copy of the LAPACK path would match.)

Layout: inputs and outputs are ``(N, 3)`` arrays (``(N, n_channels)`` for commands); the
state is kept as ``(3, N)`` rows so each DOF is one contiguous ``(N,)`` array.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.vessel import Vessel, load_vessel

from .actuation import fixed3_parameters, make_allocator
from .allocation.fixed3 import _force_box
from .conditioning import BatchedReversalHysteresis, reversal_threshold
from .pid import SATURATION_TOL, MultivariablePID, PIDGains, vessel_pid

__all__ = [
    "BATCHED_CONTROLLERS",
    "BatchedAllocation",
    "BatchedAllocationResult",
    "BatchedDPController",
    "BatchedPID",
    "apply_residual",
    "batched_dp_controller",
]

Array = NDArray[np.float64]

_TWO_PI = 2.0 * math.pi
#: as in :mod:`shipgym.controllers.allocation.fixed3`
_AT_LIMIT_RTOL = 1e-9
_ROUND_OFF_RTOL = 1e-12


def _mask(mask: ArrayLike | None, n: int) -> NDArray[np.bool_] | None:
    """``None`` (all envs) or a ``(n,)`` boolean mask; ``ValueError`` on a wrong shape."""
    if mask is None:
        return None
    m = np.asarray(mask, dtype=bool)
    if m.shape != (n,):
        raise ValueError(f"mask must be ({n},) booleans, got shape {m.shape}")
    return m


class _MatVec:
    """``A x`` for a fixed 3x3 ``A`` and ``x`` of shape (3, n), summed per row as the scalar
    ``_mv`` sums it (``a0 x0 + a1 x1 + a2 x2``, left to right), so the result is the scalar's
    bit for bit. All-zero columns are left out (adding ``0 * x = +-0`` to a finite sum changes
    nothing but the sign of a zero result); a diagonal ``A`` is one product."""

    __slots__ = ("diag", "cols")

    def __init__(self, A: tuple[tuple[float, float, float], ...]) -> None:
        a = np.array(A, dtype=float)
        off = a - np.diag(np.diag(a))
        self.diag = np.diag(a).reshape(3, 1).copy() if not off.any() else None
        self.cols = [(j, a[:, j : j + 1].copy()) for j in range(3) if a[:, j].any()]

    def __call__(self, x: Array) -> Array:
        if self.diag is not None:
            return self.diag * x
        if not self.cols:
            return np.zeros_like(x)
        j, col = self.cols[0]
        acc = col * x[j]
        for j, col in self.cols[1:]:
            acc += col * x[j]
        return acc


def _check_n3(x: ArrayLike, name: str, n: int) -> Array:
    a = np.asarray(x, dtype=float)
    if a.shape != (n, 3):
        raise ValueError(f"{name} must have shape ({n}, 3), got {a.shape}")
    return a


def _check_finite(arrays: list[tuple[str, Array]]) -> None:
    """One reduction per input in the common case; name the input when one is not finite."""
    total = 0.0
    for _, a in arrays:
        total += float(a.sum())
    if math.isfinite(total):
        return
    for name, a in arrays:
        if not np.isfinite(a).all():
            raise ValueError(f"{name} contains NaN or infinite values")


class _Rotation:
    """``R(psi)`` and ``R^T(psi)`` of N headings applied to the first two rows of (k, N)
    arrays, each row as the scalar code computes it (``c x - s y``, ``s x + c y`` and
    ``c x + s y``, ``-s x + c y``; IEEE sums commute, so the order of the two terms is free).
    ``C = [c, c]``, ``S = [s, -s]``: ``R^T x = C x + S x'``, ``R x = C x - S x'`` with
    ``x' = [x1, x0]``."""

    __slots__ = ("C", "S")

    def __init__(self, n: int) -> None:
        self.C = np.empty((2, n))
        self.S = np.empty((2, n))

    def set(self, psi: Array) -> None:
        np.cos(psi, out=self.C[0])
        self.C[1] = self.C[0]
        np.sin(psi, out=self.S[0])
        np.negative(self.S[0], out=self.S[1])

    def to_body(self, x: Array, out: Array) -> None:
        """``out[:2] = R^T x[:2]``."""
        np.add(self.C * x[:2], self.S * x[1::-1], out=out[:2])

    def from_body(self, x: Array, out: Array) -> None:
        """``out[:2] = R x[:2]``."""
        np.subtract(self.C * x[:2], self.S * x[1::-1], out=out[:2])


class BatchedPID:
    """:class:`~shipgym.controllers.pid.MultivariablePID` for ``n`` envs (module docstring).

    Same arguments as the scalar class (validated by it) plus ``n``; one integral state and
    one pending integral increment per env. Per env, a sequence of calls, resets and frame
    changes gives the scalar controller's ``tau`` to round-off.

    Args:
        n: number of envs, >= 1.
        gains: a :class:`~shipgym.controllers.pid.PIDGains` or a Blue Lady preset name.
        M: inertia matrix of the control model (kg, kg m^2), 3x3.
        D_L: linear damping of the control model (N s/m, N s, N m s), 3x3.
        dt: control period (s).
        integral_limit: bound on the integral force per body DOF (N, N, N m), or ``inf``.
    """

    def __init__(
        self,
        n: int,
        gains: PIDGains | str = "tuned",
        M: ArrayLike | None = None,
        D_L: ArrayLike | None = None,
        dt: float = 1.0,
        *,
        integral_limit: ArrayLike | None = None,
    ) -> None:
        scalar = MultivariablePID(gains, M=M, D_L=D_L, dt=dt, integral_limit=integral_limit)
        self._setup(n, scalar)

    @classmethod
    def from_scalar(cls, controller: MultivariablePID, n: int) -> BatchedPID:
        """``n`` envs of a scalar controller's design (its gains, model, period and limit;
        the integral states start at zero)."""
        if not isinstance(controller, MultivariablePID):
            raise TypeError(f"controller must be a MultivariablePID, got {controller!r}")
        self = cls.__new__(cls)
        self._setup(n, controller)
        return self

    def _setup(self, n: int, s: MultivariablePID) -> None:
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ValueError(f"n must be an int >= 1 (the number of envs), got {n!r}")
        self.n = n
        self.gains = g = s.gains
        self.M, self.D_L, self.dt, self.integral_limit = s.M, s.D_L, s.dt, s.integral_limit
        self._M = _MatVec(s._M)
        self._Mi = _MatVec(s._Mi)
        self._D = _MatVec(s._D)
        col = lambda v: np.array(v, dtype=float).reshape(3, 1)  # noqa: E731
        self._kP, self._kI, self._kD = col(g.K_P), col(g.K_I), col(g.K_D)
        self._kI_pos = self._kI > 0.0
        self._kI_all = bool(self._kI_pos.all())
        self._kI_div = np.where(self._kI_pos, self._kI, 1.0)
        self._lim = col(s._lim)
        self._clamps = bool(np.isfinite(self._lim).any())
        kx, ky = g.K_I[0], g.K_I[1]
        self._rot = (kx, ky) if kx > 0 and ky > 0 else (1.0, 1.0)
        self._xi = np.zeros((3, n))
        # the pending increment's (ex, ey, epsi, psi) of the last call, and who has one
        self._pend = np.zeros((4, n))
        self._has = np.zeros(n, dtype=bool)
        self._any_pending = self._all_pending = False
        self._R = _Rotation(n)  # at the heading of the call
        self._Rp = _Rotation(n)  # at the heading of the pending increment
        self._buf = np.empty((3, n))
        # the model-aided velocity filter (scalar _filter): its state, the last tau, who
        # has started (a call since the reset)
        self.velocity_filter = s.velocity_filter
        self._filters = s._filters
        self._alpha = col(s._alpha)
        self._pass = self._alpha == 1.0  # DOFs without a filter: the velocity as given
        self._velocities = s._velocities
        # the output low-pass (scalar command_filter): gain per DOF, state
        self.command_filter = s.command_filter
        self._commands = s._commands
        self._beta = col(s._beta)
        self._cpass = self._beta == 1.0
        self._tau_f = np.zeros((3, n))
        self._nu_f = np.zeros((3, n))
        self._tau_prev = np.zeros((3, n))
        self._started = np.zeros(n, dtype=bool)

    # ---- state -------------------------------------------------------------------------------
    def reset(self, mask: ArrayLike | None = None) -> None:
        """Clear the integral state of every env, or of those where ``mask`` (``(n,)`` bool)."""
        m = _mask(mask, self.n)
        if m is None:
            self._xi[:] = 0.0
            self._has[:] = False
            self._any_pending = False
        else:
            self._xi[:, m] = 0.0
            self._has[m] = False
        self._all_pending = False
        if m is None:
            self._started[:] = False
        else:
            self._started[m] = False

    @property
    def integral(self) -> Array:
        """The integral states ``xi`` (m s, m s, rad s), shape (n, 3) (a copy)."""
        return self._xi.T.copy()

    def change_frame(self, dpsi: ArrayLike, mask: ArrayLike | None = None) -> None:
        """Re-express the integral states in the next leg's r-frame (the scalar
        :meth:`~shipgym.controllers.pid.MultivariablePID.change_frame` per env).

        Args:
            dpsi: rotation of the frame (rad), shape (n,) or a scalar.
            mask: ``(n,)`` bool, the envs that switched leg (``None``: all); the others are
                left exactly as they are (their ``dpsi`` is not read).

        Raises:
            ValueError: a non-finite ``dpsi`` of a switching env, a wrong shape.
        """
        n = self.n
        m = _mask(mask, n)
        d = np.broadcast_to(np.asarray(dpsi, dtype=float), (n,))
        if m is not None:
            if not m.any():
                return
            d = np.where(m, d, 0.0)
        if not np.isfinite(d).all():
            raise ValueError("dpsi must be finite (rad)")
        c, s = np.cos(d), np.sin(d)
        sx, sy = self._rot
        xi, pend = self._xi, self._pend
        nx, ny = self._rotate(c, s, sx, sy, xi[0], xi[1])
        px, py = self._rotate(c, s, sx, sy, pend[0], pend[1])
        pm = self._has if m is None else (self._has & m)
        if m is None:
            xi[0], xi[1] = nx, ny
        else:
            np.copyto(xi[0], nx, where=m)
            np.copyto(xi[1], ny, where=m)
        np.copyto(pend[0], px, where=pm)
        np.copyto(pend[1], py, where=pm)
        np.copyto(pend[3], pend[3] - d, where=pm)

    @staticmethod
    def _rotate(c: Array, s: Array, sx: float, sy: float, x: Array, y: Array) -> tuple:
        ax, ay = sx * x, sy * y
        return (c * ax + s * ay) / sx, (-s * ax + c * ay) / sy

    # ---- integral update with anti-windup ----------------------------------------------------
    def _directions(self, saturated: ArrayLike | None) -> Array | None:
        """Per DOF and env (3, n): +1 / -1 (cut while pushing +/-), 2 (flagged), 0 (free)."""
        if saturated is None:
            return None
        a = np.asarray(saturated)
        if a.shape != (self.n, 3):
            raise ValueError(f"saturated must have shape ({self.n}, 3), got {a.shape}")
        if a.dtype == np.bool_:
            return np.where(a.T, 2.0, 0.0)
        f = a.astype(float, copy=False).T
        if not math.isfinite(float(f.sum())) and np.isnan(f).any():
            raise ValueError("saturated contains NaN")
        d = np.where(f > SATURATION_TOL, 1.0, 0.0)
        d -= f < -SATURATION_TOL
        return d

    def _to_body_force(self, R: _Rotation, q: Array) -> Array:
        """``M [R^T q_xy; q_psi]`` (the body force of an r-frame acceleration)."""
        b = self._buf
        R.to_body(q, b)
        b[2] = q[2]
        return self._M(b)

    def _to_r_frame(self, R: _Rotation, f: Array) -> Array:
        """``[R (M^-1 f)_xy; (M^-1 f)_psi] / K_I``, where ``K_I > 0`` (else 1)."""
        b = self._Mi(f)
        R.from_body(b, b)
        b /= self._kI_div
        return b

    def _integrate(self, dirs: Array | None) -> None:
        if not self._any_pending:
            return
        d = self.dt * self._pend[:3]  # (dx, dy, dz)
        if dirs is not None and dirs.any():
            R = self._Rp
            R.set(self._pend[3])
            f = self._to_body_force(R, self._kI * d)  # body force of the increment
            # tau changes by -f[j]; drop it where it pushes further into the cut direction
            drop = np.where(dirs == 2.0, f != 0.0, dirs * -f > 0.0)
            changed = drop.any(axis=0)
            if changed.any():
                f[drop] = 0.0
                q = self._to_r_frame(R, f)
                sel = changed if self._kI_all else (changed & self._kI_pos)
                np.copyto(d, q, where=sel)
        xi = self._xi
        if self._all_pending:
            xi += d
        else:
            np.add(xi, d, out=xi, where=self._has)
        self._has[:] = False
        self._any_pending = self._all_pending = False

    def _clamp(self) -> None:
        if not self._clamps:
            return
        xi = self._xi
        f = self._to_body_force(self._R, self._kI * xi)
        # the scalar returns unless every |f_j| <= lim_j
        over = ~(np.abs(f) <= self._lim).all(axis=0)
        if not over.any():
            return
        lim = self._lim
        np.maximum(-lim, np.minimum(lim, f), out=f)
        q = self._to_r_frame(self._R, f)
        sel = over if self._kI_all else (over & self._kI_pos)
        np.copyto(xi, q, where=sel)

    # ---- control law -------------------------------------------------------------------------
    def __call__(
        self,
        eta_r: ArrayLike,
        nu: ArrayLike,
        eta_d_r: ArrayLike,
        eta_dot_d_r: ArrayLike | None = None,
        eta_ddot_d_r: ArrayLike | None = None,
        *,
        saturated: ArrayLike | None = None,
    ) -> Array:
        """Body-frame control forces ``tau = [X, Y, N]`` (N, N, N m) of every env, eq. 23.

        Args:
            eta_r: poses ``[x, y, psi]`` (m, m, rad) in the r-frames, shape (n, 3).
            nu: body velocities ``[u, v, r]`` (m/s, m/s, rad/s), shape (n, 3).
            eta_d_r: reference poses (m, m, rad), shape (n, 3).
            eta_dot_d_r: reference velocities (m/s, m/s, rad/s), (n, 3); default zero.
            eta_ddot_d_r: reference accelerations (m/s^2, m/s^2, rad/s^2), (n, 3); default zero.
            saturated: the allocation's ``tau_error`` of the previous ``tau`` of every env
                (n, 3) floats (N, N, N m), or (n, 3) booleans, or ``None`` (integrate
                unconditionally), as the scalar's ``saturated``. After a reset an env has no
                pending increment, so its row is not read (zeros do).

        Returns:
            ``tau``, shape (n, 3) (a new array, a transposed view of a (3, n) one).

        Raises:
            ValueError: an input of the wrong shape or not finite (the state is unchanged).
        """
        n = self.n
        e = _check_n3(eta_r, "eta_r", n)
        w = _check_n3(nu, "nu", n)
        ed = _check_n3(eta_d_r, "eta_d_r", n)
        checks = [("eta_r", e), ("nu", w), ("eta_d_r", ed)]
        vd = ad = None
        if eta_dot_d_r is not None:
            vd = _check_n3(eta_dot_d_r, "eta_dot_d_r", n)
            checks.append(("eta_dot_d_r", vd))
        if eta_ddot_d_r is not None:
            ad = _check_n3(eta_ddot_d_r, "eta_ddot_d_r", n)
            checks.append(("eta_ddot_d_r", ad))
        _check_finite(checks)
        dirs = self._directions(saturated)
        eT, wT = e.T, w.T
        if self._velocities:
            wT = self._filter(wT, saturated)
        self._integrate(dirs)
        psi = eT[2]
        R = self._R
        R.set(psi)
        self._clamp()
        pend = self._pend
        E = pend[:3]  # this call's error is the next call's pending increment
        np.subtract(eT[:2], ed.T[:2], out=E[:2])
        # heading error wrapped to (-pi, pi]
        np.subtract(math.pi, np.remainder(math.pi - (psi - ed[:, 2]), _TWO_PI), out=E[2])
        pend[3] = psi
        # eq. 19 in the r-frame; r-frame velocity R(psi) nu (eq. 3)
        V = np.empty((3, n))
        R.from_body(wT, V)
        V[2] = wT[2]
        if vd is not None:
            V -= vd.T
        if ad is None:
            A = self._kD * V
            np.negative(A, out=A)
        else:
            A = ad.T - self._kD * V
        A -= self._kP * E
        A -= self._kI * self._xi
        # eqs. 21-22: nu_dot = R^T a - r S nu
        Nd = V  # reuse
        R.to_body(A, Nd)
        Nd[2] = A[2]
        r = wT[2]
        Nd[0] += r * wT[1]
        Nd[1] -= r * wT[0]
        tau = self._M(Nd)
        tau += self._D(wT)
        self._has[:] = True
        self._any_pending = self._all_pending = True
        if self._commands:
            st = self._started
            tf = self._tau_f
            new = np.where(self._cpass, tau, tf + self._beta * (tau - tf))
            np.copyto(tf, new, where=st)
            np.copyto(tf, tau, where=~st)
            tau = tf.copy()
        if self._filters:
            self._tau_prev[:] = tau
            self._started[:] = True
        return tau.T

    def _filter(self, wT: Array, saturated: ArrayLike | None) -> Array:
        """The model-aided velocity filter of every env (scalar ``_filter``), (3, n)."""
        nf = self._nu_f
        st = self._started
        if st.any():
            td = self._tau_prev
            if saturated is not None:
                a = np.asarray(saturated)
                if a.dtype != np.bool_:
                    td = td - a.astype(float, copy=False).T
            q = self._Mi(td - self._D(nf))
            p = nf + self.dt * q
            new = np.where(self._pass, wT, p + self._alpha * (wT - p))
            np.copyto(nf, new, where=st)
        if not st.all():
            np.copyto(nf, wT, where=~st)
        return nf.copy()

    def __repr__(self) -> str:
        g = self.gains
        return f"BatchedPID(n={self.n}, K_P={g.K_P}, K_I={g.K_I}, K_D={g.K_D}, dt={self.dt})"


# ---- thrust allocation -----------------------------------------------------------------------
class BatchedAllocationResult(NamedTuple):
    """The allocations of N envs (the scalar :class:`~shipgym.controllers.allocation.Allocation`
    with a leading env axis).

    Attributes:
        command: actuator commands (n, n_channels), in the channels' units, within range.
        force: thrust of every actuator (n, n_actuators) (N).
        tau: delivered ``[X, Y, N]`` (n, 3) (N, N, N m).
        tau_error: requested minus delivered (n, 3): what the PID's ``saturated`` takes.
        saturated: per channel (n, n_channels) bool.
    """

    command: Array
    force: Array
    tau: Array
    tau_error: Array
    saturated: NDArray[np.bool_]


class BatchedAllocation:
    """The thrust allocation of ``vessel`` for N envs, where it is a closed form.

    Supported: the Blue Lady pattern
    (:func:`~shipgym.controllers.actuation.fixed3_parameters`) with ``"constrained"``
    (:func:`~shipgym.controllers.allocation.allocate`, default weights, as
    :func:`~shipgym.controllers.actuation.make_allocator` uses it) or ``"inverse"``
    (:func:`~shipgym.controllers.allocation.allocate_inverse`).

    Args:
        vessel: a vessel, a packaged vessel's name or a package path.
        method: ``"constrained"`` or ``"inverse"``.
        dt: control period (s) (the azimuth rate limits; kept for the scalar's signature).

    Raises:
        ValueError: what :func:`~shipgym.controllers.actuation.make_allocator` raises (an
            unknown method, ``"inverse"`` for another layout, a set it cannot allocate).
        NotImplementedError: an iterative allocation (weighted least squares by active set,
            the azimuth QP): the message names the vessel and the method.
    """

    def __init__(self, vessel: Vessel | str, method: str = "constrained", dt: float = 1.0) -> None:
        v = load_vessel(vessel)
        make_allocator(v, method, dt)  # the scalar's checks and errors
        acts = v.actuators
        p = fixed3_parameters(acts)
        if p is None:
            kind = (
                "box-constrained weighted least squares (active-set, iterative)"
                if acts.fixed
                else "extended-thrust azimuth QP (iterative)"
            )
            raise NotImplementedError(
                f"BatchedAllocation: vessel {v.name!r} allocates by {kind} "
                f"({acts!r}); only the closed form of the Blue Lady pattern (a main propeller "
                f"and two tunnel thrusters, Tomera 2014 eqs. 24-27) is batched"
            )
        self.vessel = v
        self.actuators = acts
        self.method = method
        self.thrusters = p
        self.n_channels = acts.n_channels
        self._p = p
        self._box = _force_box(p)
        lever = p.L2 + p.L3
        self._lever = lever
        self._wY, self._wN = wY, wN = 1.0, 10.0 / (lever * lever)  # default_weights
        L2, L3 = p.L2, p.L3
        self._d3 = wY + wN * L3 * L3  # curvature along F3 (F2 fixed)
        self._d2 = wY + wN * L2 * L2  # curvature along F2 (F3 fixed)
        self._wNL3, self._wNL2 = wN * L3, wN * L2
        f2lo, f2hi, f3lo, f3hi = self._box[2:]
        self._LL = np.array([[L3], [L2]])
        self._k23 = np.array([[p.k2], [p.k3]])
        self._lo23 = np.array([[f2lo], [f3lo]])
        self._hi23 = np.array([[f2hi], [f3hi]])
        tol = _ROUND_OFF_RTOL * (self._hi23 - self._lo23)  # round-off, not saturation
        self._in_lo, self._in_hi = self._lo23 - tol, self._hi23 + tol
        tol = _AT_LIMIT_RTOL * (self._hi23 - self._lo23)  # on a limit
        self._at_lo, self._at_hi = self._lo23 + tol, self._hi23 - tol
        self._E2 = np.array([[f2lo], [f2hi]])
        self._L2E2 = np.array([[L2 * f2lo], [L2 * f2hi]])
        self._E3 = np.array([[f3lo], [f3hi]])
        self._L3E3 = np.array([[L3 * f3lo], [L3 * f3hi]])
        lo = acts.lower
        hi = acts.upper
        self._lo, self._hi = lo, hi
        self._two_sided = bool((lo < 0.0).all())
        self._neg_lo = np.where(lo < 0, -lo, 1.0)

    def __call__(self, tau: ArrayLike, state: ArrayLike | None = None) -> BatchedAllocationResult:
        """Allocate ``tau`` (n, 3) (N, N, N m) of every env; ``state``: the actuator states
        (n, n_channels), unused by the closed forms (the scalar allocator's signature).

        Returns:
            The :class:`BatchedAllocationResult` (its arrays are transposed views of (3, n)
            ones). A zero main-propeller force gives the command ``+-0`` (the scalar: ``0``).
        """
        t = np.asarray(tau, dtype=float)
        if t.ndim != 2 or t.shape[1] != 3:
            raise ValueError(f"tau must have shape (n, 3) ([X N, Y N, N N m]), got {t.shape}")
        if not math.isfinite(float(t.sum())) and not np.isfinite(t).all():
            raise ValueError("tau contains NaN or infinite values (check the controller)")
        n = t.shape[0]
        tT = t.T
        X, Y, N = tT[0], tT[1], tT[2]
        f1lo, f1hi = self._box[:2]
        F = np.empty((3, n))  # the thrusts
        sat = np.empty((3, n), dtype=bool)
        np.minimum(np.maximum(X, f1lo), f1hi, out=F[0])
        np.not_equal(F[0], X, out=sat[0])
        # F2, F3 = T^-1 (Y, N) (eq. 25): ((L3 Y + N), (L2 Y - N)) / (L2 + L3)
        P = self._LL * Y
        P[0] += N
        P[1] -= N
        P /= self._lever
        lo, hi = self._lo23, self._hi23
        inside23 = (self._in_lo <= P) & (P <= self._in_hi)
        G = F[1:]
        np.minimum(np.maximum(P, lo), hi, out=G)
        if self.method == "inverse":
            np.logical_not(inside23, out=sat[1:])
        else:
            inside = inside23.all(axis=0)
            if inside.all():
                sat[1:] = False
            else:
                b = self._edges(Y, N)
                out = ~inside
                np.copyto(G, b, where=out)
                np.logical_and(out, (b <= self._at_lo) | (b >= self._at_hi), out=sat[1:])
        return self._result(tT, F, sat)

    def _edges(self, Y: Array, N: Array) -> Array:
        """The best of the four box edges of :func:`~shipgym.controllers.allocation.allocate`
        (F2 on its lower, upper bound with F3 free, then F3 on its bounds), each edge's terms
        as the scalar computes them; ``argmin`` keeps the first minimum, as the scalar's
        strict ``<`` does."""
        p = self._p
        L2, L3 = p.L2, p.L3
        wY, wN = self._wY, self._wN
        n = Y.shape[0]
        J = np.empty((4, n))
        B2 = np.empty((4, n))
        B3 = np.empty((4, n))
        E2, L2E2, E3, L3E3 = self._E2, self._L2E2, self._E3, self._L3E3
        _, _, f2lo, f2hi, f3lo, f3hi = self._box
        # F2 = edge, minimise over F3
        f3 = wY * (Y - E2)
        f3 += self._wNL3 * (L2E2 - N)
        f3 /= self._d3
        np.minimum(np.maximum(f3, f3lo, out=f3), f3hi, out=f3)
        eY = E2 + f3 - Y
        eN = L2E2 - L3 * f3
        eN -= N
        np.add(wY * eY * eY, wN * eN * eN, out=J[:2])
        B2[:2] = E2
        B3[:2] = f3
        # F3 = edge, minimise over F2
        f2 = wY * (Y - E3)
        f2 += self._wNL2 * (N + L3E3)
        f2 /= self._d2
        np.minimum(np.maximum(f2, f2lo, out=f2), f2hi, out=f2)
        eY = f2 + E3 - Y
        eN = L2 * f2 - L3E3
        eN -= N
        np.add(wY * eY * eY, wN * eN * eN, out=J[2:])
        B2[2:] = f2
        B3[2:] = E3
        k = J.argmin(axis=0)
        cols = np.arange(n)
        out = np.empty((2, n))
        out[0] = B2[k, cols]
        out[1] = B3[k, cols]
        return out

    def _result(self, tT: Array, F: Array, sat: NDArray[np.bool_]) -> BatchedAllocationResult:
        p = self._p
        delivered = tT.copy()
        delivered[0] = F[0]
        cut = sat[1] | sat[2]
        if cut.any():  # else F2, F3 = T^-1 (Y, N): the request, so tau_error is exactly zero
            np.copyto(delivered[1], F[1] + F[2], where=cut)
            np.copyto(delivered[2], p.L2 * F[1] - p.L3 * F[2], where=cut)
        err = tT - delivered
        # inverse thruster characteristics, eqs. 26-27 (with |F1|), clipped for round-off
        cmd = np.empty_like(F)
        F1 = F[0]
        np.copysign(np.sqrt(np.abs(F1) / p.k1), F1, out=cmd[0])
        np.minimum(np.maximum(cmd[0], p.n_min), p.n_max, out=cmd[0])
        np.divide(F[1:], self._k23, out=cmd[1:])
        np.minimum(np.maximum(cmd[1:], p.p_min), p.p_max, out=cmd[1:])
        return BatchedAllocationResult(cmd.T, F.T, delivered.T, err.T, sat.T)

    def command_to_action(self, command: ArrayLike) -> Array:
        """Physical commands (n, n_channels) -> normalised actions, as
        :meth:`ActuatorSet.command_to_action <shipgym.dynamics.actuators.ActuatorSet.
        command_to_action>` (``c / upper`` for ``c >= 0``, ``c / |lower|`` below)."""
        c = np.asarray(command, dtype=float)
        two = np.where(c >= 0.0, c / self._hi, c / self._neg_lo)
        if self._two_sided:
            return two
        lo, hi = self._lo, self._hi
        return np.where(lo < 0.0, two, 2.0 * (c - lo) / (hi - lo) - 1.0)


def apply_residual(
    controller_action: ArrayLike, residual: ArrayLike, residual_scale: float
) -> tuple[Array, NDArray[np.bool_]]:
    """The action the controller wrapper sends to the env, for N envs.

    ``total = controller_action + residual_scale * residual``, ``applied = clip(total, -1, 1)``
    (what :class:`~shipgym.controllers.wrappers.DPControllerWrapper` does; the wrapper then
    passes ``applied.astype(float32)`` to the env).

    Returns:
        ``(applied, residual_clipped)``: the clipped actions (n, n_channels) (float64) and
        where the clip changed them.
    """
    total = np.asarray(controller_action, dtype=float) + residual_scale * np.asarray(
        residual, dtype=float
    )
    applied = np.minimum(np.maximum(total, -1.0), 1.0)
    return applied, applied != total


# ---- the named controllers -------------------------------------------------------------------
#: the batched controller names: (gain preset, bandwidth scale, allocation, conditioned), as
#: the PID entries of :data:`shipgym.controllers.wrappers.CONTROLLERS` (a test checks they
#: agree); conditioned: the vessel's velocity filter and reversal hysteresis
#: (:mod:`shipgym.controllers.conditioning`)
BATCHED_CONTROLLERS: dict[str, tuple[str, float, str, bool]] = {
    "pid": ("tuned", 1.0, "constrained", True),
    "pid-smooth": ("smooth", 0.7, "constrained", True),
    "pid-raw": ("tuned", 1.0, "constrained", False),
    "pid-smooth-raw": ("smooth", 0.7, "constrained", False),
    "pid-seed": ("seed", 1.0, "inverse", False),
}


class BatchedDPController:
    """A :class:`BatchedPID` and its :class:`BatchedAllocation`, with the ``tau_error`` each
    env feeds back (the controller wrapper's state, less the leg bookkeeping).

    Attributes:
        name: the controller name.
        pid: the :class:`BatchedPID`.
        allocation: the :class:`BatchedAllocation`.
        tau_error: each env's last ``tau_error`` (n, 3) (zeros after a reset: not read then).
    """

    def __init__(
        self,
        name: str,
        pid: BatchedPID,
        allocation: BatchedAllocation,
        hysteresis: BatchedReversalHysteresis | None = None,
    ) -> None:
        self.name = name
        self.pid = pid
        self.allocation = allocation
        self.hysteresis = hysteresis if hysteresis is not None and hysteresis.active else None
        self.n = pid.n
        self.tau_error = np.zeros((pid.n, 3))

    def reset(self, mask: ArrayLike | None = None) -> None:
        """Start new episodes: every env, or those where ``mask``."""
        m = _mask(mask, self.n)
        self.pid.reset(m)
        if self.hysteresis is not None:
            self.hysteresis.reset(m)
        if m is None:
            self.tau_error[:] = 0.0
        else:
            self.tau_error[m] = 0.0

    def change_frame(self, dpsi: ArrayLike, mask: ArrayLike | None = None) -> None:
        """A leg switch of the envs in ``mask``: :meth:`BatchedPID.change_frame`."""
        self.pid.change_frame(dpsi, mask)

    def __call__(
        self,
        eta_r: ArrayLike,
        nu: ArrayLike,
        eta_d_r: ArrayLike,
        eta_dot_d_r: ArrayLike | None = None,
        eta_ddot_d_r: ArrayLike | None = None,
        state: ArrayLike | None = None,
    ) -> tuple[Array, BatchedAllocationResult, Array]:
        """One control period of every env (the wrapper's ``_control`` and action).

        Returns:
            ``(tau_c, allocation, controller_action)``: the PID's ``tau`` (n, 3), its
            allocation and the normalised command (n, n_channels) before the residual.
        """
        tau = self.pid(eta_r, nu, eta_d_r, eta_dot_d_r, eta_ddot_d_r, saturated=self.tau_error)
        alloc = self.allocation(tau, state)
        if self.hysteresis is not None:  # what is delivered: the anti-windup sees it
            cmd, force, t_del, err = self.hysteresis(
                alloc.command, alloc.force, alloc.tau, alloc.tau_error
            )
            alloc = BatchedAllocationResult(cmd, force, t_del, err, alloc.saturated)
        self.tau_error = alloc.tau_error
        return tau, alloc, self.allocation.command_to_action(alloc.command)


def batched_dp_controller(
    name: str, vessel: Vessel | str, n: int, dt: float, velocity_source: str = "kinematic"
) -> BatchedDPController:
    """The named DP controller for ``n`` envs of ``vessel`` at control period ``dt`` (s),
    designed as the controller wrapper's factory designs it (``make(..., controller=name)``).

    Args:
        name: ``"pid"``, ``"pid-smooth"`` or ``"pid-seed"`` (:data:`BATCHED_CONTROLLERS`).
        vessel: a vessel or a packaged vessel's name.
        n: number of envs.
        dt: control period (s).
        velocity_source: where the velocity comes from (``"truth"``, ``"kinematic"``,
            ``"model"``; :func:`~shipgym.controllers.pid.vessel_pid`): sets the velocity
            filter of a conditioned controller, as the wrapper does.

    Raises:
        NotImplementedError: a controller that is not batched (the LQ family), or a vessel
            whose allocation is iterative (:class:`BatchedAllocation`).
        ValueError: an unknown name, a 4-DOF vessel, ``"pid-seed"`` for a vessel without the
            printed gains, or what the scalar allocator raises.
    """
    if name not in BATCHED_CONTROLLERS:
        raise NotImplementedError(
            f"controller {name!r} has no batched form; batched: {', '.join(BATCHED_CONTROLLERS)}"
        )
    v = load_vessel(vessel)
    if v.dofs != 3:
        raise ValueError(f"the batched DP controller is 3-DOF; {v.name!r} has {v.dofs} DOF")
    preset, scale, method, conditioned = BATCHED_CONTROLLERS[name]
    pid = BatchedPID.from_scalar(
        vessel_pid(v, preset, scale, dt, conditioned=conditioned, velocity_source=velocity_source),
        n,
    )
    hyst = BatchedReversalHysteresis(v.actuators, reversal_threshold(v), n) if conditioned else None
    return BatchedDPController(name, pid, BatchedAllocation(v, method, dt), hyst)
