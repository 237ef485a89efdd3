r"""Notch-filter wave filtering of the measured pose (Al-Takie 1982 section 1.2, eq. 1.1).

Section (Al-Takie 1982 eq. 1.1): ``H(s) = (s^2 + (b d / k) s + w0^2) / (s^2 + (b / k) s
+ w0^2)``, ``k = sqrt(1 - 2 d^2)``; three sections on the wave band.

The classical DP wave filter that the thesis compares its Kalman filters with: the measured pose
``[x, y, psi]`` passes through a cascade of notch filters centred on the first-order wave band,
so that the controller sees the low-frequency (LF) motion only.

Public names: ``BatchedNotch``, ``NotchCascade``, ``NotchDesign``, ``NotchObserver``,
``MEASUREMENT_VARIANCE_ALTAKIE``, ``notch_section``.
Sources: Al-Takie (1982); Fossen (2011).

Design notes: docs/design/observers.notch.md.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.signal
from numpy.typing import ArrayLike, NDArray

from .._config import from_mapping, param
from .._jit import njit
from .base import Estimate, as_pose, register_observer
from .batch import BatchedStepInfo, BatchOfOne, register_batched_form

__all__ = [
    "BatchedNotch",
    "NotchCascade",
    "NotchDesign",
    "NotchObserver",
    "MEASUREMENT_VARIANCE_ALTAKIE",
    "notch_section",
]

MEASUREMENT_VARIANCE_ALTAKIE = (1.0 / 9.0, 1.0 / 9.0, 4e-4)
"""Measurement variances ``(x, y, psi)`` (m^2, m^2, rad^2): position sigma 1/3 m, gyro sigma
0.02 rad [printed, Al-Takie (1982) 2.4]."""

_DT_RTOL = 1e-6


def _positive(name: str, value: Any, unit: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if isinstance(value, bool) or not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be a finite number > 0 ({unit}), got {value!r}")
    return v


def notch_section(w0: float, b: float, d: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """One continuous notch section, Al-Takie (1982) eq. 1.1.

    ``H(s) = (s^2 + (b d / sqrt(1 - 2 d^2)) s + w0^2) / (s^2 + (b / sqrt(1 - 2 d^2)) s + w0^2)``.

    Args:
        w0: centre frequency (rad/s), > 0.
        b: 3-dB bandwidth (rad/s), > 0: ``|H| = 1/sqrt(2)`` at
            ``sqrt(w0^2 + b^2/4) +- b/2`` (module doc).
        d: gain at the centre, ``|H(j w0)| = d`` (-), ``0 < d < 1/sqrt(2)``.

    Returns:
        ``(num, den)``: polynomial coefficients in ``s``, highest power first (as
        ``scipy.signal.freqs`` takes them), each (3,).

    Raises:
        ValueError: a non-finite or out-of-range argument.
    """
    w0 = _positive("w0 (notch centre)", w0, "rad/s")
    b = _positive("b (3-dB bandwidth)", b, "rad/s")
    try:
        d = float(d)
    except (TypeError, ValueError):
        d = math.nan
    if not 0.0 < d < 1.0 / math.sqrt(2.0):
        raise ValueError(
            f"d (gain at the notch centre) must be in (0, 1/sqrt(2)) = (0, 0.7071), got {d!r}; "
            "e.g. 0.1 for -20 dB"
        )
    k = math.sqrt(1.0 - 2.0 * d * d)
    num = np.array([1.0, b * d / k, w0 * w0])
    den = np.array([1.0, b / k, w0 * w0])
    return num, den


@dataclass(frozen=True)
class NotchDesign:
    """The notch cascade and velocity filter of :class:`NotchObserver` (full scale by default).

    Attributes:
        centres_hz: centre frequencies of the sections (Hz), ascending, each > 0.
        bandwidth_ratio: 3-dB bandwidth of each section over its centre, ``b / w0`` (-).
        attenuation: gain ``d`` at each centre (-), ``0 < d < 1/sqrt(2)``.
        velocity_time_constant: ``T_v`` of the filtered difference that gives the velocity (s).
    """

    centres_hz: tuple[float, ...] = param(
        (0.069, 0.083, 0.128),
        "Hz",
        "chosen: HF peaks of the Beaufort 9, 8, 5 wave models, Al-Takie (1982) App. 2; "
        "printed range 0.06-0.12 Hz, 3 sections, Al-Takie (1982) 1.2",
    )
    bandwidth_ratio: float = param(0.3, "-", "chosen: b = 0.3 w0")
    attenuation: float = param(0.1, "-", "chosen: d = 0.1 (-20 dB at each centre)")
    velocity_time_constant: float = param(
        3.0, "s", "chosen: smooths the residual wave motion, small next to DP time scales"
    )

    def __post_init__(self) -> None:
        c = self.centres_hz
        if isinstance(c, int | float):
            c = (c,)
        try:
            cs = tuple(float(x) for x in c)
        except (TypeError, ValueError):
            raise ValueError(
                f"centres_hz must be a sequence of frequencies > 0 (Hz), got {self.centres_hz!r}"
            ) from None
        if not cs or not all(math.isfinite(x) and x > 0.0 for x in cs):
            raise ValueError(
                f"centres_hz must be one or more finite frequencies > 0 (Hz), got {c!r}"
            )
        object.__setattr__(self, "centres_hz", cs)
        object.__setattr__(
            self, "bandwidth_ratio", _positive("bandwidth_ratio", self.bandwidth_ratio, "b / w0")
        )
        object.__setattr__(
            self,
            "velocity_time_constant",
            _positive("velocity_time_constant", self.velocity_time_constant, "s"),
        )
        notch_section(1.0, self.bandwidth_ratio, self.attenuation)  # validates d
        object.__setattr__(self, "attenuation", float(self.attenuation))

    @classmethod
    def from_dict(cls, mapping: Mapping[str, Any]) -> NotchDesign:
        """A design from a mapping of its fields; unknown keys raise ``ValueError``."""
        return from_mapping(cls, mapping, where="the notch design")

    def sections(self) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
        """The continuous sections ``(num, den)`` of :func:`notch_section`, one per centre."""
        out = []
        for f in self.centres_hz:
            w0 = 2.0 * math.pi * f
            out.append(notch_section(w0, self.bandwidth_ratio * w0, self.attenuation))
        return out

    def froude_scaled(self, scale: float) -> NotchDesign:
        """The design for a ``1:scale`` model: frequencies times ``sqrt(scale)``, the velocity
        time constant divided by it (Froude similarity: time scales as ``sqrt(L)``)."""
        lam = _positive("scale", scale, "model scale lambda")
        r = math.sqrt(lam)
        return dataclasses.replace(
            self,
            centres_hz=tuple(f * r for f in self.centres_hz),
            velocity_time_constant=self.velocity_time_constant / r,
        )

    def frequency_response(self, f_hz: ArrayLike) -> NDArray[np.complex128]:
        """The continuous cascade's ``H(j 2 pi f)`` at frequencies ``f_hz`` (Hz)."""
        w = 2.0 * math.pi * np.asarray(f_hz, dtype=float)
        h = np.ones(w.shape, dtype=complex)
        for num, den in self.sections():
            h = h * scipy.signal.freqs(num, den, worN=np.atleast_1d(w))[1].reshape(w.shape)
        return h

    def ramp_lag(self) -> float:
        """Low-frequency group delay of the continuous cascade (s): ``sum b (1 - d) / (k w0^2)``."""
        d = self.attenuation
        k = math.sqrt(1.0 - 2.0 * d * d)
        return sum(
            self.bandwidth_ratio * (1.0 - d) / (k * 2.0 * math.pi * f) for f in self.centres_hz
        )


class NotchCascade:
    """The sections of a :class:`NotchDesign` in cascade, discretised for a fixed ``dt``.

    Bilinear transform prewarped at each section's centre (the notch stays exactly at ``w0``
    with gain ``d``; DC gain exactly 1); transposed direct form II second-order sections with
    state, vectorised over a leading channel axis.

    Args:
        design: the :class:`NotchDesign` (or a mapping of its fields).
        dt: sampling interval (s), > 0; every centre must be below ``1 / (2 dt)``.
        channels: number of independent channels (e.g. 3 for ``x, y, psi``).

    Attributes:
        sos: (n_sections, 6) ``[b0, b1, b2, 1, a1, a2]`` rows (``scipy.signal.sosfilt`` layout).
    """

    def __init__(
        self, design: NotchDesign | Mapping[str, Any], dt: float, channels: int = 3
    ) -> None:
        if isinstance(design, Mapping):
            design = NotchDesign.from_dict(design)
        if not isinstance(design, NotchDesign):
            raise ValueError(f"design must be a NotchDesign or a mapping, got {design!r}")
        dt = _positive("dt (sampling interval)", dt, "s")
        if isinstance(channels, bool) or int(channels) != channels or channels < 1:
            raise ValueError(f"channels must be an integer >= 1, got {channels!r}")
        nyquist = 0.5 / dt
        too_high = [f for f in design.centres_hz if f >= nyquist]
        if too_high:
            raise ValueError(
                f"notch centre(s) {too_high} Hz at or above the Nyquist frequency {nyquist:.4g} Hz "
                f"of dt = {dt:.6g} s: sample faster (dt < {0.5 / max(too_high):.4g} s) or "
                "choose centres_hz below it"
            )
        rows = []
        for f, (num, den) in zip(design.centres_hz, design.sections(), strict=True):
            w0 = 2.0 * math.pi * f
            fs_warp = w0 / (2.0 * math.tan(0.5 * w0 * dt))  # s = 2 fs_warp (z - 1)/(z + 1)
            bz, az = scipy.signal.bilinear(num, den, fs=fs_warp)
            rows.append(np.concatenate([bz / az[0], az / az[0]]))
        self.design = design
        self.dt = dt
        self.channels = int(channels)
        self.sos = np.array(rows)
        self.sos.setflags(write=False)
        self._state = np.zeros((self.channels, len(rows), 2))

    @property
    def state(self) -> NDArray[np.float64]:
        """A copy of the section states, (channels, n_sections, 2) (``sosfilt``'s ``zi``)."""
        return self._state.copy()

    def reset(self, x0: ArrayLike = 0.0) -> None:
        """Start in steady state at the constant input ``x0`` (scalar or (channels,)): the
        output is ``x0`` from the first step on (DC gain 1, no start transient)."""
        x = np.broadcast_to(np.asarray(x0, dtype=float), (self.channels,))
        if not np.isfinite(x).all():
            raise ValueError(f"x0 must be finite, got {x0!r}")
        b0, b1, b2, _, a1, a2 = self.sos.T
        s2 = (b2 - a2)[None, :] * x[:, None]
        s1 = (b1 - a1)[None, :] * x[:, None] + s2
        self._state = np.stack([s1, s2], axis=-1)

    def step(self, u: ArrayLike) -> NDArray[np.float64]:
        """Filter one sample ``u`` (scalar or (channels,)); returns the output (channels,)."""
        x = np.array(np.broadcast_to(np.asarray(u, dtype=float), (self.channels,)))
        if not np.isfinite(x).all():
            raise ValueError(f"the cascade's input must be finite, got {u!r}")
        out = np.empty(self.channels)
        _cascade(self.sos, self._state, x, out)
        return out

    def frequency_response(self, f_hz: ArrayLike) -> NDArray[np.complex128]:
        """The discrete cascade's frequency response at ``f_hz`` (Hz), ``scipy.signal.sosfreqz``."""
        f = np.atleast_1d(np.asarray(f_hz, dtype=float))
        return scipy.signal.sosfreqz(np.array(self.sos), worN=f, fs=1.0 / self.dt)[1]

    @property
    def dc_group_delay(self) -> float:
        """Group delay at zero frequency (s): a ramp comes out delayed by exactly this much
        in steady state (DC gain 1). Per section ``sum n b_n / sum b_n - sum n a_n / sum a_n``
        samples."""
        n = np.arange(3.0)
        b, a = self.sos[:, :3], self.sos[:, 3:]
        samples = (b @ n) / b.sum(axis=1) - (a @ n) / a.sum(axis=1)
        return float(samples.sum() * self.dt)

    def impulse_response(self, n: int) -> NDArray[np.float64]:
        """The first ``n`` samples of the cascade's impulse response (-)."""
        x = np.zeros(int(n))
        x[0] = 1.0
        return scipy.signal.sosfilt(np.array(self.sos), x)


@njit(inline="always")
def _sections(sos, st, x):  # type: ignore[no-untyped-def]
    """One sample ``x`` of one channel through the sections ``sos`` with its states ``st``
    (n_sections, 2), in place (transposed direct form II); returns the output."""
    for i in range(sos.shape[0]):
        y = sos[i, 0] * x + st[i, 0]
        st[i, 0] = sos[i, 1] * x - sos[i, 4] * y + st[i, 1]
        st[i, 1] = sos[i, 2] * x - sos[i, 5] * y
        x = y
    return x


@njit
def _cascade(sos, st, x, out):  # type: ignore[no-untyped-def]
    """Every channel's sample ``x[c]`` through the sections (states ``st[c]``) into
    ``out[c]``."""
    for c in range(x.shape[0]):
        out[c] = _sections(sos, st[c], x[c])


@njit
def _notch_step(sel, valid, z, tt, h, a, delay, sos, t, eta, ed, yp, st, innov):  # type: ignore[no-untyped-def]  # noqa: E501
    """One sampling interval ``h`` (s) of the envs ``sel`` to ``tt``, in place: the
    prediction with the rate, the cascade fed the sample (``valid``; the innovation's
    heading wrapped to ``(-pi, pi]``) or else the prediction led by the cascade's ``delay``
    (s), so that on a ramp its input goes on as the measurements would; the rate filtered
    from the output's difference (``a = exp(-h / T_v)``) where there was a sample."""
    pi, two_pi = math.pi, 2.0 * math.pi
    for j in range(t.shape[0]):
        if not sel[j]:
            continue
        for i in range(3):
            pred = eta[j, i] + ed[j, i] * h
            if valid[j]:
                e = z[j, i] - pred
                if i == 2:
                    e = pi - np.fmod(np.fmod(pi - e, two_pi) + two_pi, two_pi)
                innov[j, i] = e
                y = _sections(sos, st[j, i], pred + e)
                ed[j, i] = a * ed[j, i] + (1.0 - a) * (y - yp[j, i]) / h
                eta[j, i] = y
            else:
                y = _sections(sos, st[j, i], pred + ed[j, i] * delay)
                eta[j, i] = pred
            yp[j, i] = y
        t[j] = tt[j]


class BatchedNotch:
    """``n`` notch observers (:class:`NotchObserver`) stepped together, elementwise over the
    envs (module doc); one sampling interval for the batch.

    Args:
        design, measurement_variance, dt, name: as :class:`NotchObserver`.
        n: number of envs, >= 1.
    """

    #: discretised for one sampling interval: stepped at its samples only (an env does not
    #: coast it to the end of a period without a sample)
    fixed_interval = True

    model_based = False

    def __init__(
        self,
        design: NotchDesign,
        n: int,
        *,
        measurement_variance: NDArray[np.float64],
        dt: float | None,
        name: str,
    ) -> None:
        self.design = design
        self.name = name
        self.n = n
        self._R = measurement_variance
        self._dt_fixed = dt
        self.dt: float | None = None
        self.cascade: NotchCascade | None = None
        self._P6: NDArray[np.float64] | None = None
        self._t = np.zeros(n)
        self._started = np.zeros(n, dtype=bool)
        self._eta = np.zeros((n, 3))
        self._eta_dot = np.zeros((n, 3))
        self._y_prev = np.zeros((n, 3))
        self._state = np.zeros((n, 3, len(design.centres_hz), 2))
        self._learn = np.zeros(n, dtype=bool)  # the first step after reset learns the interval
        if dt is not None:
            self._build(dt)

    def check_sample_interval(self, period: float, control_period: float) -> None:
        """Refuse, when an env is built, a sensor ``period`` (s) at which a notch centre lies at
        or above the Nyquist frequency, or that differs from a fixed ``dt``: the first step
        would raise (``control_period`` unused: the notch filters the samples).

        Raises:
            ValueError: naming the centres, the period and what to change.
        """
        if self._dt_fixed is not None and abs(period - self._dt_fixed) > 1e-9 * self._dt_fixed:
            raise ValueError(
                f"{self.name} samples every dt = {self._dt_fixed:.6g} s; the env's sensor period "
                f"is {period:.6g} s: make them equal"
            )
        NotchCascade(self.design, period, channels=3)  # raises above Nyquist

    def batch(self, n: int) -> BatchedNotch:
        """A new batch of ``n`` envs with these settings."""
        return BatchedNotch(self.design, n, measurement_variance=self._R, dt=self._dt_fixed,
                            name=self.name)  # fmt: skip

    def _build(self, dt: float) -> None:
        self.dt = dt
        self.cascade = NotchCascade(self.design, dt, channels=3)
        self._sos = np.array(self.cascade.sos)
        self._delay = self.cascade.dc_group_delay
        self._a = math.exp(-dt / self.design.velocity_time_constant)
        hh, gg, hg = self.noise_gains()
        P6 = np.zeros((6, 6))
        i = np.arange(3)
        P6[i, i] = hh * self._R
        P6[i + 3, i + 3] = gg * self._R
        P6[i, i + 3] = P6[i + 3, i] = hg * self._R
        self._P6 = P6

    def _steady(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """The section states (m, 3, n_sections, 2) in steady state at the inputs ``x``
        (m, 3) (:meth:`NotchCascade.reset`)."""
        assert self.cascade is not None
        _, b1, b2, _, a1, a2 = self.cascade.sos.T
        s2 = (b2 - a2) * x[..., None]
        s1 = (b1 - a1) * x[..., None] + s2
        return np.stack([s1, s2], axis=-1)

    def reset(
        self,
        t0: ArrayLike,
        eta0: ArrayLike,
        *,
        mask: ArrayLike | None = None,
        nu0: ArrayLike | None = None,
    ) -> None:
        """Start the envs of ``mask`` at ``t0`` (n,) in steady state at ``eta0`` (n, 3), with
        the NED rates of ``nu0`` (n, 3) (``None``: rest)."""
        m = np.ones(self.n, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        tt = np.broadcast_to(np.asarray(t0, dtype=float), (self.n,))
        eta = np.broadcast_to(np.asarray(eta0, dtype=float), (self.n, 3))
        if not (np.isfinite(tt[m]).all() and np.isfinite(eta[m]).all()):
            raise ValueError("t0 and eta0 must be finite")
        if nu0 is None:
            ed = np.zeros((self.n, 3))
        else:
            nu = np.broadcast_to(np.asarray(nu0, dtype=float), (self.n, 3))
            c, s = np.cos(eta[:, 2]), np.sin(eta[:, 2])
            ed = np.stack([c * nu[:, 0] - s * nu[:, 1], s * nu[:, 0] + c * nu[:, 1], nu[:, 2]], 1)
        self._t[m] = tt[m]
        self._eta[m] = eta[m]
        self._eta_dot[m] = ed[m]
        self._y_prev[m] = eta[m]
        self._started[m] = True
        if self._dt_fixed is None and m.all():  # the interval is learned again
            self.dt = self.cascade = self._P6 = None
        if self.cascade is not None:
            self._state[m] = self._steady(eta[m])
        self._learn[m] = self.cascade is None

    def step(
        self,
        t: ArrayLike,
        z: ArrayLike | None = None,
        valid: ArrayLike | None = None,
        tau: ArrayLike | None = None,
    ) -> BatchedStepInfo:
        """One sampling interval to ``t`` (n,) of every env whose time moves (an env whose
        time stands and has no sample is left alone), filtering ``z`` (n, 3) where ``valid``
        (else coasting). ``tau``: unused (a signal filter).

        Raises:
            RuntimeError: an env was never reset.
            ValueError: an interval that is not the fixed one (or a first one <= 0).
        """
        n = self.n
        if not self._started.all():
            raise RuntimeError(f"{self.name}: call reset(t0, eta0) before step()")
        tt = np.ascontiguousarray(np.broadcast_to(np.asarray(t, dtype=float), (n,)))
        za = np.zeros((n, 3)) if z is None else np.ascontiguousarray(z, dtype=float)
        vm = (np.ones(n, bool) if z is not None else np.zeros(n, bool)) if valid is None else (
            np.ascontiguousarray(valid, dtype=bool))  # fmt: skip
        dt = tt - self._t
        sel = vm | (dt != 0.0)
        out = BatchedStepInfo(np.full((n, 3), np.nan), np.full(n, np.nan), np.zeros(n, bool),
                              np.zeros(n, bool))  # fmt: skip
        if not sel.any():
            return out
        d = dt[sel]
        if self.cascade is None:
            d0 = float(d[0])
            if not (math.isfinite(d0) and d0 > 0.0):
                i = int(np.nonzero(sel)[0][0])
                raise ValueError(
                    f"{self.name}: the first step must come after reset (t0 = {self._t[i]}, "
                    f"got t = {tt[i]!r}); its interval fixes the sampling interval"
                )
            self._build(d0)
        assert self.dt is not None and self.cascade is not None
        h = self.dt
        bad = ~(np.abs(d - h) <= _DT_RTOL * h)
        if bad.any():
            raise ValueError(
                f"{self.name}: the notch filter is discretised for a fixed sampling interval "
                f"{h:.9g} s but this step is {float(d[bad][0]):.9g} s after the previous one: call "
                "step() once per sample (z=None for a missing one), or make a new observer (dt=...)"
            )
        learn = self._learn & sel
        if learn.any():  # the first step after a reset with the interval unknown
            self._state[learn] = self._steady(self._y_prev[learn])
            self._learn[learn] = False
        if not np.isfinite(za[vm]).all():
            raise ValueError(f"{self.name}: z must be finite where valid")
        _notch_step(sel, vm, za, tt, h, self._a, self._delay, self._sos, self._t, self._eta,
                    self._eta_dot, self._y_prev, self._state, out.innovation)  # fmt: skip
        return out

    @property
    def eta(self) -> NDArray[np.float64]:
        """The estimated poses (n, 3) (m, m, rad; heading continuous)."""
        return self._eta.copy()

    @property
    def nu(self) -> NDArray[np.float64]:
        """The body velocities ``R^T(psi) eta_dot`` (n, 3) (m/s, m/s, rad/s)."""
        c, s = np.cos(self._eta[:, 2]), np.sin(self._eta[:, 2])
        ed = self._eta_dot
        return np.stack([c * ed[:, 0] + s * ed[:, 1], -s * ed[:, 0] + c * ed[:, 1], ed[:, 2]], 1)

    def estimate(self, j: int) -> Estimate:
        """Env ``j``'s estimate; ``P`` in ``[x, y, psi, x_dot, y_dot, psi_dot]``, the
        measurement-noise covariance through the filter (module doc)."""
        eta = self._eta[j].copy()
        c, s = math.cos(eta[2]), math.sin(eta[2])
        ed = self._eta_dot[j]
        nu = np.array([c * ed[0] + s * ed[1], -s * ed[0] + c * ed[1], ed[2]])
        t = float(self._t[j])
        if self._P6 is None:
            P6 = np.diag(np.concatenate([self._R, np.full(3, np.inf)]))
            return Estimate(t, eta, nu, P6, np.diag(self._R), None)
        P6 = self._P6.copy()
        J = np.zeros((3, 6))
        J[0, 2], J[1, 2] = nu[1], -nu[0]
        J[0, 3], J[0, 4], J[1, 3], J[1, 4], J[2, 5] = c, s, -s, c, 1.0
        P_nu = J @ P6 @ J.T
        return Estimate(t, eta, nu, P6, P6[:3, :3].copy(), 0.5 * (P_nu + P_nu.T))

    def noise_gains(self) -> tuple[float, float, float]:
        """``(sum h^2, sum g^2, sum h g)`` of the chain's impulse responses (``h``: pose, -;
        ``g``: rate, 1/s): the pose variance, rate variance and their covariance per unit
        measurement variance."""
        if self.cascade is None or self.dt is None:
            raise RuntimeError(f"{self.name}: the sampling interval is not known yet")
        dt = self.dt
        slowest = min(self.design.centres_hz)
        damping = math.pi * slowest * self.design.bandwidth_ratio  # b / 2 of the slowest (1/s)
        tmax = 60.0 / damping + 60.0 * self.design.velocity_time_constant
        n = int(min(max(math.ceil(tmax / dt), 64), 2_000_000))
        hresp = self.cascade.impulse_response(n)
        a = math.exp(-dt / self.design.velocity_time_constant)
        diff = np.diff(hresp, prepend=0.0) / dt
        g = scipy.signal.lfilter([1.0 - a], [1.0, -a], diff)
        return float(hresp @ hresp), float(g @ g), float(hresp @ g)


class NotchObserver(BatchOfOne):
    """Notch-filter wave filter with a filtered-difference velocity (module doc): one env of
    :class:`BatchedNotch`.

    Args:
        design: the :class:`NotchDesign` (or a mapping of its fields); default the full-scale
            design of Al-Takie (1982) 1.2 with the [chosen] values (module doc).
        measurement_variance: variance of one measurement ``(x, y, psi)`` (m^2, m^2, rad^2),
            only for the noise covariance ``P`` reported; default Al-Takie (1982) 2.4.
        dt: the fixed sampling interval (s); ``None``: the first interval between calls.
        name: the observer's name.
    """

    def __init__(
        self,
        design: NotchDesign | Mapping[str, Any] | None = None,
        *,
        measurement_variance: ArrayLike = MEASUREMENT_VARIANCE_ALTAKIE,
        dt: float | None = None,
        name: str = "notch",
    ) -> None:
        if design is None:
            design = NotchDesign()
        elif isinstance(design, Mapping):
            design = NotchDesign.from_dict(design)
        if not isinstance(design, NotchDesign):
            raise ValueError(f"design must be a NotchDesign or a mapping, got {design!r}")
        R = np.asarray(measurement_variance, dtype=float)
        if R.shape != (3,) or not np.isfinite(R).all() or (R < 0).any():
            raise ValueError(
                "measurement_variance must be 3 finite values >= 0 (m^2, m^2, rad^2), "
                f"got {measurement_variance!r}"
            )
        self.design = design
        self.name = str(name)
        fixed = None if dt is None else _positive("dt (sampling interval)", dt, "s")
        self._b = BatchedNotch(design, 1, measurement_variance=R, dt=fixed, name=self.name)

    def check_sample_interval(self, period: float, control_period: float) -> None:
        """The batch's :meth:`BatchedNotch.check_sample_interval`."""
        self._b.check_sample_interval(period, control_period)

    def batch(self, n: int) -> BatchedNotch:
        """This observer's law over ``n`` envs (the vector env's)."""
        return self._b.batch(n)

    def reset(
        self,
        t0: float,
        eta0: ArrayLike,
        *,
        nu0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
    ) -> None:
        """Start at ``t0`` in steady state at the pose ``eta0`` (no start transient).

        Args:
            t0: initial time (s).
            eta0: ``[x, y, psi]`` (m, m, rad); the heading's branch is kept.
            nu0: ``[u, v, r]`` (m/s, m/s, rad/s), the velocity filter's start; ``None`` = 0.
            P0: must be ``None``: the notch filter has no covariance state.

        Raises:
            ValueError: non-finite or mis-shaped arguments, or ``P0`` given.
        """
        if P0 is not None:
            raise ValueError(
                "the notch observer has no covariance state: pass P0=None "
                "(its P is the measurement-noise covariance through the filter, module doc)"
            )
        if nu0 is not None:
            nu0 = as_pose(nu0, "nu0", "[u, v, r] (m/s, m/s, rad/s)")
        self._reset_one(t0, eta0, nu0=nu0)

    @property
    def dt(self) -> float | None:
        """The fixed sampling interval (s), ``None`` until known."""
        return self._b.dt

    @property
    def cascade(self) -> NotchCascade | None:
        """The discretised cascade, ``None`` until the sampling interval is known."""
        return self._b.cascade

    @property
    def t(self) -> float | None:
        """Time of the current estimate (s), ``None`` before :meth:`reset`."""
        return float(self._b._t[0]) if self._started else None

    def noise_gains(self) -> tuple[float, float, float]:
        """:meth:`BatchedNotch.noise_gains`."""
        return self._b.noise_gains()


# --------------------------------------------------------------------------------------------
# Preset and registry
# --------------------------------------------------------------------------------------------

_DESIGN_KEYS = tuple(f.name for f in dataclasses.fields(NotchDesign))
_CTOR_KEYS = ("design", "measurement_variance", "dt")


def notch_observer(**overrides: Any) -> NotchObserver:
    """The ``notch`` preset: :class:`NotchObserver` with the full-scale :class:`NotchDesign`.

    Args:
        **overrides: :class:`NotchDesign` fields (``centres_hz``, ``bandwidth_ratio``,
            ``attenuation``, ``velocity_time_constant``) and the constructor's keywords
            (``design``, ``measurement_variance``, ``dt``).

    Raises:
        ValueError: an unknown option (the message lists the valid ones).
    """
    unknown = sorted(set(overrides) - set(_DESIGN_KEYS) - set(_CTOR_KEYS))
    if unknown:
        raise ValueError(
            f"unknown option(s) {unknown} for observer 'notch'; valid: "
            f"{', '.join(sorted(_DESIGN_KEYS + _CTOR_KEYS))}"
        )
    design = overrides.pop("design", None)
    if design is None:
        design = NotchDesign()
    elif isinstance(design, Mapping):
        design = NotchDesign.from_dict(design)
    changes = {k: overrides.pop(k) for k in list(overrides) if k in _DESIGN_KEYS}
    if changes:
        design = dataclasses.replace(design, **changes)
    return NotchObserver(design, name="notch", **overrides)


def vessel_design(vessel: Any) -> dict[str, Any]:
    """The ``notch`` preset for a vessel: the full-scale design Froude-scaled to its
    ``vessel.scale`` (``f_model = f_full sqrt(scale)``, ``T_v`` divided by ``sqrt(scale)``)."""
    return {"design": NotchDesign().froude_scaled(float(vessel.scale))}


register_observer("notch", notch_observer, vessel_design)
register_batched_form("notch")
