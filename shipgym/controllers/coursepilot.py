r"""The classical course-keeping autopilot: a PID on the gyro heading and the rate gyro.

``delta_c = -(k_p e + k_i int e dt + k_d r_hat)``, ``e = wrap(psi_g - psi_d)``, tuned on
Nomoto's ``r/delta = K/(1 + T s)`` (Fossen 1995).

Public names: ``COURSE_BANDWIDTH_PRIME``, ``COURSE_INTEGRAL_RATIO``, ``INTEGRAL_BAND``,
``RATE_FILTER_PRIME``, ``CoursePilot``, ``SteeringModel``, ``closed_loop_poles``,
``course_autopilot``, ...
Sources: Fossen (1995).

Design notes: docs/design/controllers.coursepilot.md.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.dynamics.actuators import tau_of_table
from shipgym.dynamics.frames import wrap_angle

from .rollcontrol import HeadingPIDGains, heading_pid_gains

__all__ = [
    "COURSE_BANDWIDTH_PRIME",
    "COURSE_INTEGRAL_RATIO",
    "INTEGRAL_BAND",
    "RATE_FILTER_PRIME",
    "CoursePilot",
    "SteeringModel",
    "closed_loop_poles",
    "course_autopilot",
    "course_pilot_gains",
    "steering_model",
]

Array = NDArray[np.float64]

#: the heading loop's bandwidth of a vessel without a ``[roll_control]`` table, per ``U/L``
#: [chosen]: 0.7 (0.049 rad/s, a 128 s period, for the 100 m tanker at 7 m/s), a quarter of
#: the yaw-rate pole (-0.20 rad/s) and slow enough for the 2.32 deg/s steering gear (0.5
#: settles the tanker's heading changes more slowly: 1.5 deg against 0.6 deg RMS, the tests)
COURSE_BANDWIDTH_PRIME = 0.7

#: the yaw-rate low-pass of the D term, per ``L/U`` [chosen]: 0.35 (5 s for the 100 m tanker
#: at 7 m/s), inside the loop's bandwidth (``w T_f`` = 0.25)
RATE_FILTER_PRIME = 0.35

#: the integral pole over the bandwidth [chosen]: 0.25, a steady wind moment trimmed in about
#: 1/(0.25 w) = 82 s on the tanker (a tenth, the roll pilots' rule of thumb, takes 200 s)
COURSE_INTEGRAL_RATIO = 0.25

#: the heading error below which the integral runs [chosen]: 5 deg (no wind-up in a turn)
INTEGRAL_BAND = math.radians(5.0)

_V, _R, _PSI = 0, 1, 2


class SteeringModel(NamedTuple):
    """The linear sway-yaw model of a 3-DOF hull about straight running at ``U``.

    Attributes:
        A: (3, 3) system matrix on ``x = [v, r, psi]`` (1/s, m/rad, ...; SI).
        B: (3,) input matrix per rad of rudder (shipgym's sign: positive turns to port).
        U: the speed (m/s).
        source: what was linearised.
    """

    A: Array
    B: Array
    U: float
    source: str


def _operating_states(vessel: Any, U: float) -> list[float]:
    """The actuator states of straight running at ``U``: an MMG unit's propeller at its
    self-propulsion point, everything else at rest (rudders amidships)."""
    from shipgym.dynamics.actuators import MMGPropulsion

    st = [0.0] * vessel.actuators.n_channels
    for a, sl in zip(vessel.actuators, vessel.actuators.slices, strict=True):
        if isinstance(a, MMGPropulsion):
            st[sl.start] = float(vessel.plant().model.self_propulsion(U))
    return st


def steering_model(vessel: Any, U: float, *, rudder: str | None = None) -> Any:
    """The vessel's linear steering model at the speed ``U`` (module docstring).

    Args:
        vessel: a :class:`~shipgym.dynamics.vessel.Vessel` with a rudder.
        U: forward speed through the water (m/s), > 0.
        rudder: the rudder channel (default: the first of ``vessel.rudders``).

    Returns:
        :class:`SteeringModel` (3 DOF) or :class:`~shipgym.dynamics.vanderklugt.RollModel`
        (4 DOF); both have ``A`` and ``B`` with ``r`` at index 1 and ``psi`` at index 2.

    Raises:
        ValueError: no rudder, an unknown rudder, ``U <= 0``.
    """
    if not (isinstance(U, int | float) and math.isfinite(U) and U > 0):
        raise ValueError(f"U must be a forward speed > 0 m/s, got {U!r}")
    if not vessel.rudders:
        raise ValueError(f"vessel {vessel.name!r} has no rudder: no steering model")
    name = vessel.rudders[0] if rudder is None else rudder
    if name not in vessel.rudders:
        raise ValueError(
            f"vessel {vessel.name!r} has no rudder {name!r}; its rudders: "
            f"{', '.join(vessel.rudders)}"
        )
    if vessel.dofs == 4:
        from shipgym.dynamics.linearise import roll_model_of

        return roll_model_of(vessel, float(U), rudder=name)
    U = float(U)
    hull = vessel.plant()
    accel, k = type(hull).accel_kernel, hull.kernel_constants()
    table, laws, kinds = vessel.actuators.law_table()
    out = np.zeros(len(kinds)), np.zeros(len(kinds))
    j = vessel.actuators.channel_names.index(name)
    st0 = np.asarray(_operating_states(vessel, U), dtype=np.float64)

    def f(v: float, r: float, delta: float) -> Array:
        st = st0.copy()
        st[j] = delta
        X, Y, _K, N = tau_of_table(table, laws, kinds, st, U, v, 0.0, r, *out)
        _ud, vd, _pd, rd = accel(k, U, v, 0.0, r, 0.0, X, Y, 0.0, N, 0.0, 0.0)
        return np.array([vd, rd])

    # central differences with small steps (a v|v| term differences to h, not 0)
    hv, hr, hd = 1e-6 * U, 1e-8, 1e-5
    A = np.zeros((3, 3))
    A[:2, 0] = (f(hv, 0.0, 0.0) - f(-hv, 0.0, 0.0)) / (2 * hv)
    A[:2, 1] = (f(0.0, hr, 0.0) - f(0.0, -hr, 0.0)) / (2 * hr)
    A[_PSI, _R] = 1.0
    B = np.zeros(3)
    B[:2] = (f(0.0, 0.0, hd) - f(0.0, 0.0, -hd)) / (2 * hd)
    src = f"{vessel.name} ({type(hull).__name__}) with rudder {name!r}, linearised at U = {U:g} m/s"
    return SteeringModel(A, B, U, src)


def _design_bandwidth(vessel: Any, U: float) -> tuple[float, float]:
    rc = vessel.roll_control
    if rc and "heading_bandwidth" in rc:
        return float(rc["heading_bandwidth"]), float(rc.get("heading_zeta", 1.0))
    return COURSE_BANDWIDTH_PRIME * U / vessel.L_pp, 1.0


def course_pilot_gains(
    vessel: Any,
    U: float,
    bandwidth: float | None = None,
    zeta: float | None = None,
    integral_ratio: float | None = None,
) -> HeadingPIDGains:
    """The PID gains of the vessel's course autopilot at ``U`` (module docstring).

    Args:
        vessel: a :class:`~shipgym.dynamics.vessel.Vessel` with a rudder.
        U: speed (m/s).
        bandwidth: the heading loop's natural frequency (rad/s); default the vessel's
            ``heading_bandwidth`` or :data:`COURSE_BANDWIDTH_PRIME` ``U/L``.
        zeta: damping ratio; default the vessel's ``heading_zeta`` or 1.
        integral_ratio: the integral pole over the bandwidth; default
            :data:`COURSE_INTEGRAL_RATIO`.

    Returns:
        :class:`~shipgym.controllers.rollcontrol.HeadingPIDGains`.
    """
    w0, z0 = _design_bandwidth(vessel, U)
    w = w0 if bandwidth is None else float(bandwidth)
    z = z0 if zeta is None else float(zeta)
    ir = COURSE_INTEGRAL_RATIO if integral_ratio is None else float(integral_ratio)
    return heading_pid_gains(steering_model(vessel, U), w, z, integral_ratio=ir)


def closed_loop_poles(model: Any, gains: HeadingPIDGains) -> Array:
    """Poles (rad/s) of the linear model under ``delta = -(kp psi + ki int psi + kd r)``
    (no rudder servo, no rate filter, continuous time): the eigenvalues of the model's
    ``A - B [kd e_r + kp e_psi]`` augmented with the integral state."""
    A = np.asarray(model.A, dtype=float)
    b = np.asarray(model.B, dtype=float).reshape(-1)
    n = A.shape[0]
    k = np.zeros(n)
    k[_R], k[_PSI] = gains.kd, gains.kp
    Ac = np.zeros((n + 1, n + 1))
    Ac[:n, :n] = A - np.outer(b, k)
    Ac[:n, n] = -b * gains.ki
    Ac[n, _PSI] = 1.0
    return np.linalg.eigvals(Ac)


class CoursePilot:
    """The PID course autopilot on the gyro heading and the low-passed rate gyro.

    ``delta = -(kp e + ki int e + kd r_f)``, clipped to ``+-delta_max``; the integral is
    forward Euler over ``dt`` and runs only while ``|e| < integral_band`` (it trims a steady
    wind or current moment and does not wind up during a heading change) and not while the
    output is at its limit with the error pushing it further (conditional integration, as
    :class:`~shipgym.controllers.rollcontrol.HeadingAutopilot`).

    Args:
        gains: :class:`~shipgym.controllers.rollcontrol.HeadingPIDGains` (rad/rad, rad/(rad
            s), rad/(rad/s); the rudder's sign).
        delta_max: rudder limit (rad), > 0.
        dt: sample time (s) of the calls.
        rate_filter: time constant (s) of the yaw rate's first-order low-pass (0: none).
        integral_band: the largest ``|e|`` (rad) at which the integral runs (``inf``: always).
    """

    def __init__(
        self,
        gains: HeadingPIDGains,
        *,
        delta_max: float,
        dt: float,
        rate_filter: float = 0.0,
        integral_band: float = math.inf,
    ) -> None:
        for name, g in zip(("kp", "ki", "kd"), gains, strict=True):
            if not math.isfinite(g):
                raise ValueError(f"{name} must be finite, got {g!r}")
        if not (math.isfinite(delta_max) and delta_max > 0):
            raise ValueError(f"delta_max must be > 0 rad, got {delta_max!r}")
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be > 0 s, got {dt!r}")
        if not (math.isfinite(rate_filter) and rate_filter >= 0):
            raise ValueError(f"rate_filter must be >= 0 s, got {rate_filter!r}")
        if not integral_band > 0:
            raise ValueError(f"integral_band must be > 0 rad, got {integral_band!r}")
        self.gains = HeadingPIDGains(*(float(g) for g in gains))
        self.delta_max = float(delta_max)
        self.dt = float(dt)
        self.rate_filter = float(rate_filter)
        self.integral_band = float(integral_band)
        # the exact discretisation of the low-pass at the sample time
        self._alpha = 1.0 if rate_filter == 0 else 1.0 - math.exp(-self.dt / self.rate_filter)
        self.reset()

    def reset(self) -> None:
        """Clear the integral and the rate filter."""
        self.integral = 0.0
        self._r: float | None = None
        self._saturated = 0.0  # sign of the last saturation (0: none)

    def __call__(self, psi: float, r: float, psi_d: float) -> float:
        """The rudder command (rad) after measuring the heading ``psi`` (rad) and the yaw rate
        ``r`` (rad/s), for the desired heading ``psi_d`` (rad); one call per ``dt``."""
        kp, ki, kd = self.gains
        e = float(wrap_angle(float(psi) - float(psi_d)))
        if self._r is None:  # the first call only measures
            self._r = float(r)
        else:
            self._r += self._alpha * (float(r) - self._r)
            pushes = self._saturated != 0.0 and math.copysign(1.0, -ki * e) == self._saturated
            if abs(e) < self.integral_band and not pushes:
                self.integral += e * self.dt
        u = -(kp * e + ki * self.integral + kd * self._r)
        out = min(max(u, -self.delta_max), self.delta_max)
        self._saturated = math.copysign(1.0, u) if out != u else 0.0
        return out

    def act(self, obs: ArrayLike) -> float:
        """The command from a :class:`~shipgym.envs.coursekeeping.CourseKeepingEnv`
        observation ``[e_psi, r, ...]`` (the heading error is the heading relative to the
        set-point, so ``psi_d`` is 0)."""
        o = np.asarray(obs, dtype=float).reshape(-1)
        return self(float(o[0]), float(o[1]), 0.0)


def course_autopilot(
    env: Any,
    bandwidth: float | None = None,
    zeta: float | None = None,
    integral_ratio: float | None = None,
    integral_band: float = INTEGRAL_BAND,
) -> Any:
    """A policy ``obs -> action`` (float32, shape ``env.action_space.shape``) that steers a
    :class:`~shipgym.envs.coursekeeping.CourseKeepingEnv` with :class:`CoursePilot`.

    The gains come from :func:`course_pilot_gains` at the env's speed; the rate filter is
    :data:`RATE_FILTER_PRIME` ``L/U``. Call ``policy.reset()`` after each ``env.reset()``
    (the integral and the filter); every rudder gets the same command.

    Args:
        env: the environment (its ``unwrapped`` is used): ``base_vessel``, ``U``,
            ``control_period``, ``max_angle`` (rad per rudder), ``action_space``.
        bandwidth, zeta, integral_ratio: as :func:`course_pilot_gains`.
        integral_band: as :class:`CoursePilot`.
    """
    e = getattr(env, "unwrapped", env)
    v = e.base_vessel
    gains = course_pilot_gains(v, e.U, bandwidth, zeta, integral_ratio)
    dmax = float(np.min(e.max_angle))
    pilot = CoursePilot(gains, delta_max=dmax, dt=e.control_period,
                        rate_filter=RATE_FILTER_PRIME * v.L_pp / e.U,
                        integral_band=integral_band)  # fmt: skip
    shape = e.action_space.shape

    class _Policy:
        def __init__(self) -> None:
            self.pilot = pilot

        def reset(self) -> None:
            pilot.reset()

        def __call__(self, obs: ArrayLike) -> NDArray[np.float32]:
            cmd = pilot.act(obs)
            return np.full(shape, cmd / dmax, dtype=np.float32)

    return _Policy()
