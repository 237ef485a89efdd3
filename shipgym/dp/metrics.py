r"""Metrics of a dynamic-positioning run (Al-Takie 1982 2.3, 3.1). Pure NumPy/SciPy.

Public names: ``DP_RADIUS_MAX``, ``dp_metrics``, ``dp_radius``, ``hf_thrust_rms``,
``step_metrics``, ``wave_band_ratio``.

Design notes: docs/design/dp.metrics.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.signal
from numpy.typing import ArrayLike, NDArray
from scipy.stats import chi2

from shipgym.dynamics.frames import wrap_angle

__all__ = [
    "DP_RADIUS_MAX",
    "dp_metrics",
    "dp_radius",
    "hf_thrust_rms",
    "step_metrics",
    "wave_band_ratio",
]

DP_RADIUS_MAX = 7.0
"""The largest allowed radius of the DP requirement (m) [printed, Al-Takie (1982) 2.3]."""
DP_RADIUS_DEPTH_FRACTION = 0.03
"""The allowed radius as a fraction of the water depth (-) [printed, Al-Takie (1982) 2.3]."""
HF_BAND = (0.05, 0.25)
"""The first-order wave band of the thrust command (Hz) [printed, Al-Takie (1982) 3.1]."""
LF_BAND = (0.0, 0.04)
"""The low-frequency band of the thrust command (Hz) [printed, Al-Takie (1982) 3.1]."""
BINS_PER_LF_BAND = 4
"""Welch frequency bins across the LF band's width [chosen]: 0.04 Hz / 4 = 0.01 Hz
resolution, a 100 s Hann segment, so that a Hann main lobe (+- 2 bins) of a tone in the
middle of the band stays inside it."""
_T_RTOL = 1e-6


def dp_radius(depth: float | None = None) -> float:
    """The allowed radius of the DP requirement (m): 3 % of the water depth or 7 m, whichever
    is smaller (Al-Takie 1982 2.3).

    Args:
        depth: water depth (m), > 0; ``None``: unknown, the 7 m limit.

    Raises:
        ValueError: a depth that is not finite and > 0.
    """
    if depth is None:
        return DP_RADIUS_MAX
    try:
        h = float(depth)
    except (TypeError, ValueError):
        h = math.nan
    if isinstance(depth, bool) or not (math.isfinite(h) and h > 0.0):
        raise ValueError(f"depth must be a finite water depth > 0 (m) or None, got {depth!r}")
    return min(DP_RADIUS_DEPTH_FRACTION * h, DP_RADIUS_MAX)


def _times(t: ArrayLike) -> tuple[NDArray[np.float64], float]:
    """``t`` as uniform sample times (s) and their interval, else ``ValueError``."""
    tt = np.asarray(t, dtype=float)
    if tt.ndim != 1 or tt.size < 2 or not np.isfinite(tt).all():
        raise ValueError(f"t must be 2 or more finite sample times (s), got shape {tt.shape}")
    d = np.diff(tt)
    dt = float(d.mean())
    if not dt > 0.0 or np.abs(d - dt).max() > _T_RTOL * dt:
        raise ValueError(
            "t must be increasing uniformly (a fixed sampling interval, within 1e-6 relative): "
            "resample the record onto a uniform grid first"
        )
    return tt, dt


def _series(name: str, x: ArrayLike, n: int, cols: int | None = None) -> NDArray[np.float64]:
    a = np.asarray(x, dtype=float)
    if a.ndim == 1 and cols is None:
        a = a[:, None]
    if a.ndim != 2 or a.shape[0] != n or (cols is not None and a.shape[1] != cols):
        want = f"({n}, {cols})" if cols is not None else f"({n},) or ({n}, k)"
        raise ValueError(f"{name} must have shape {want} (one row per sample), got {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{name} must be finite")
    return a


def _capacity(capacity: ArrayLike, m: int) -> NDArray[np.float64]:
    c = np.asarray(capacity, dtype=float).ravel()
    if c.shape != (m,) or not np.isfinite(c).all() or (c <= 0).any():
        raise ValueError(
            f"capacity must be {m} finite values > 0 (the force capacity per DOF of tau_c: "
            f"N, N, N m), got {capacity!r}"
        )
    return c


def _band(name: str, band: Any) -> tuple[float, float]:
    try:
        lo, hi = (float(x) for x in band)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be (low, high) in Hz, got {band!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 <= lo < hi):
        raise ValueError(f"{name} must be (low, high) Hz with 0 <= low < high, got {band!r}")
    return lo, hi


def _band_powers(
    t: ArrayLike,
    tau_c: ArrayLike,
    capacity: ArrayLike,
    bands: tuple[tuple[float, float], ...],
    lf: tuple[float, float],
    detrend: Any,
) -> Callable[[tuple[float, float]], float]:
    """``power(band)``: the summed Welch power over the DOFs of ``tau_c / capacity`` in a
    band (edges included), Hann segments of ``BINS_PER_LF_BAND / width(lf)`` seconds, half
    overlap, ``detrend`` as :func:`scipy.signal.welch`'s; after the checks of ``t``, the
    arrays, the ``bands`` against the Nyquist frequency and the record's length."""
    tt, dt = _times(t)
    u = _series("tau_c", tau_c, tt.size)
    u = u / _capacity(capacity, u.shape[1])
    fs = 1.0 / dt
    if max(b[1] for b in bands) > 0.5 * fs:
        raise ValueError(
            f"the bands {', '.join(map(str, bands))} Hz must lie below the Nyquist frequency "
            f"{0.5 * fs:.4g} Hz of the sampling interval {dt:.4g} s"
        )
    seg_s = BINS_PER_LF_BAND / (lf[1] - lf[0])
    nperseg = int(math.ceil(seg_s * fs))
    if tt.size < nperseg:
        raise ValueError(
            f"the record ({tt.size} samples, {tt[-1] - tt[0]:.4g} s) is shorter than one Welch "
            f"segment ({nperseg} samples, {seg_s:.4g} s) that resolves the LF band {lf} Hz"
        )
    f, P = scipy.signal.welch(u, fs=fs, window="hann", nperseg=nperseg, detrend=detrend, axis=0)
    df = f[1] - f[0]

    def power(band: tuple[float, float]) -> float:
        sel = (f >= band[0] - 1e-9 * df) & (f <= band[1] + 1e-9 * df)
        return float(P[sel].sum() * df)

    return power


def wave_band_ratio(
    t: ArrayLike,
    tau_c: ArrayLike,
    capacity: ArrayLike,
    hf_band: tuple[float, float] = HF_BAND,
    lf_band: tuple[float, float] = LF_BAND,
) -> float:
    """HF/LF power ratio of the capacity-normalised thrust command (Al-Takie 1982 3.1 bands).

    ``sum_i P_i(hf_band) / sum_i P_i(lf_band)`` with ``P_i(band)`` the integral over the band
    (edges included) of the Welch PSD of ``tau_c_i / capacity_i`` (Hann segments of
    ``BINS_PER_LF_BAND / width(lf_band)`` seconds, 100 s for the default bands, half overlap,
    no detrending: the mean thrust, e.g. against the mean wind, is LF effort). A sine of
    amplitude ``A`` contributes ``A^2 / 2`` to the band that holds its main lobe.

    Args:
        t: uniform sample times (s), (N,); the record must last at least one segment.
        tau_c: commanded generalised force per sample, (N, m) (N, N, N m) or (N,).
        capacity: the force capacity per DOF (same units), (m,), > 0.
        hf_band: the wave band (Hz).
        lf_band: the low-frequency band (Hz).

    Returns:
        The power ratio (-); ``inf`` if the LF band holds no power but the HF band does.

    Raises:
        ValueError: non-uniform or too short ``t``, mis-shaped or non-finite arrays, bad bands,
            a band above the Nyquist frequency, or a command that is zero throughout.
    """
    hf = _band("hf_band", hf_band)
    lf = _band("lf_band", lf_band)
    power = _band_powers(t, tau_c, capacity, (hf, lf), lf, detrend=False)
    p_hf, p_lf = power(hf), power(lf)
    if p_lf == 0.0:
        if p_hf == 0.0:
            raise ValueError("tau_c holds no power in either band (a zero command?)")
        return math.inf
    return p_hf / p_lf


def hf_thrust_rms(
    t: ArrayLike,
    tau_c: ArrayLike,
    capacity: ArrayLike,
    hf_band: tuple[float, float] = HF_BAND,
) -> float:
    """The wave-band RMS of the capacity-normalised thrust command (-, a fraction of capacity).

    ``sqrt(sum_i P_i(hf_band))``, ``P_i(band)`` the integral over the band (edges included)
    of the Welch PSD of ``tau_c_i / capacity_i`` with each segment's linear trend removed
    (Hann segments of 100 s, half overlap): the thrust modulation at the first-order wave
    frequencies (Al-Takie 1982 3.1: 0.05-0.25 Hz) that a wave filter exists to suppress,
    free of the mean load and of slow drifts (which :func:`wave_band_ratio` divides by). A
    sine of amplitude ``A`` (a fraction of capacity) in one DOF inside the band gives
    ``A / sqrt(2)``.

    Args:
        t: uniform sample times (s), (N,), at least 100 s.
        tau_c: commanded generalised force per sample, (N, m) (N, N, N m) or (N,).
        capacity: the force capacity per DOF (same units), (m,), > 0.
        hf_band: the wave band (Hz).

    Raises:
        ValueError: as :func:`wave_band_ratio`.
    """
    hf = _band("hf_band", hf_band)
    power = _band_powers(t, tau_c, capacity, (hf,), LF_BAND, detrend="linear")
    return math.sqrt(power(hf))


def dp_metrics(
    t: ArrayLike,
    eta: ArrayLike,
    eta_d: ArrayLike,
    tau_c: ArrayLike,
    capacity: ArrayLike,
    *,
    saturated: ArrayLike | None = None,
    radius: float = DP_RADIUS_MAX,
    lf_error: ArrayLike | None = None,
    nis: ArrayLike | None = None,
    nis_dof: int = 2,
) -> dict[str, Any]:
    """The DP metrics of one station-keeping record (module doc).

    Args:
        t: uniform sample times (s), (N,).
        eta: pose ``[x, y, psi]`` per sample (m, m, rad), (N, 3) (the truth, or the measured
            pose for a measured score).
        eta_d: desired pose (m, m, rad), (N, 3) or (3,) for a fixed set-point.
        tau_c: commanded generalised force per sample, (N, m) (N, N, N m).
        capacity: the force capacity per DOF of ``tau_c`` (N, N, N m), (m,), > 0.
        saturated: per sample (N,) or per sample and actuator (N, k), true where saturated;
            a sample counts if any actuator is; ``None``: not reported.
        radius: the allowed radius (m), e.g. :func:`dp_radius` (default 7 m).
        lf_error: LF estimation error per sample, truth minus estimate (N,) or (N, k), in the
            components' units (angles already wrapped); ``None``: not reported.
        nis: normalised innovation squared per sample (N',); NaN entries (no measurement)
            are left out; ``None``: not reported.
        nis_dof: degrees of freedom of ``nis`` (the number of measured components).

    Returns:
        A dict: ``samples``, ``duration_s`` (s), ``radius_m`` (m), ``position_rms_m`` (m,
        RMS radial error), ``max_radial_error_m`` (m), ``inside_radius_pct`` (% of samples
        with radial error <= radius), ``heading_rms_deg`` (deg, wrapped), ``thrust_usage``
        (tuple per DOF of mean ``|tau_c_i|/capacity_i``, -), ``thrust_usage_mean`` (-),
        ``saturated_pct`` (% or ``None``), ``wave_band_ratio`` (-, :func:`wave_band_ratio`;
        ``None`` if the record is shorter than its 100 s segment), ``hf_thrust_rms`` (-,
        :func:`hf_thrust_rms`; ``None`` likewise), ``lf_rmse`` (tuple per
        component or ``None``), ``nis_mean`` (-, or ``None``), ``nis_inside_95_pct`` (% of
        the NIS values inside ``[chi2.ppf(0.025, dof), chi2.ppf(0.975, dof)]``, or ``None``).

    Raises:
        ValueError: non-uniform ``t``, mis-shaped or non-finite arrays, ``capacity`` or
            ``radius`` not > 0, ``nis`` negative or ``nis_dof`` not a positive integer.
    """
    tt, _ = _times(t)
    n = tt.size
    e = _series("eta", eta, n, 3)
    ed = np.asarray(eta_d, dtype=float)
    if ed.shape == (3,):
        ed = np.broadcast_to(ed, (n, 3))
    ed = _series("eta_d", ed, n, 3)
    u = _series("tau_c", tau_c, n)
    cap = _capacity(capacity, u.shape[1])
    try:
        r_ok = float(radius)
    except (TypeError, ValueError):
        r_ok = math.nan
    if not (math.isfinite(r_ok) and r_ok > 0.0):
        raise ValueError(
            f"radius must be finite and > 0 (m), e.g. dp_radius(depth), got {radius!r}"
        )
    err = e - ed
    rho = np.hypot(err[:, 0], err[:, 1])
    dpsi = np.asarray(wrap_angle(err[:, 2]), dtype=float)
    usage = np.mean(np.abs(u) / cap, axis=0)
    out: dict[str, Any] = {
        "samples": n,
        "duration_s": float(tt[-1] - tt[0]),
        "radius_m": r_ok,
        "position_rms_m": float(np.sqrt(np.mean(rho * rho))),
        "max_radial_error_m": float(rho.max()),
        "inside_radius_pct": 100.0 * float(np.mean(rho <= r_ok)),
        "heading_rms_deg": math.degrees(float(np.sqrt(np.mean(dpsi * dpsi)))),
        "thrust_usage": tuple(float(x) for x in usage),
        "thrust_usage_mean": float(usage.mean()),
        "saturated_pct": None,
        "wave_band_ratio": None,
        "hf_thrust_rms": None,
        "lf_rmse": None,
        "nis_mean": None,
        "nis_inside_95_pct": None,
    }
    if saturated is not None:
        s = np.asarray(saturated)
        if s.ndim == 1:
            s = s[:, None]
        if s.ndim != 2 or s.shape[0] != n:
            raise ValueError(f"saturated must have shape ({n},) or ({n}, k), got {s.shape}")
        out["saturated_pct"] = 100.0 * float(np.mean(s.astype(bool).any(axis=1)))
    try:
        out["wave_band_ratio"] = wave_band_ratio(tt, u, cap)
        out["hf_thrust_rms"] = hf_thrust_rms(tt, u, cap)
    except ValueError as exc:
        if "shorter than one Welch segment" not in str(exc):
            raise
    if lf_error is not None:
        le = _series("lf_error", lf_error, n)
        out["lf_rmse"] = tuple(float(x) for x in np.sqrt(np.mean(le * le, axis=0)))
    if nis is not None:
        if isinstance(nis_dof, bool) or int(nis_dof) != nis_dof or nis_dof < 1:
            raise ValueError(f"nis_dof must be an integer >= 1, got {nis_dof!r}")
        q = np.asarray(nis, dtype=float).ravel()
        q = q[~np.isnan(q)]
        if q.size == 0 or not np.isfinite(q).all() or (q < 0).any():
            raise ValueError("nis must hold finite values >= 0 (NaN marks a missing sample)")
        lo, hi = chi2.ppf([0.025, 0.975], int(nis_dof))
        out["nis_mean"] = float(q.mean())
        out["nis_inside_95_pct"] = 100.0 * float(np.mean((q >= lo) & (q <= hi)))
    return out


def step_metrics(
    t: ArrayLike, y: ArrayLike, t_step: float, step: float, *, settle: float = 0.05
) -> dict[str, float]:
    """Rise time, overshoot and settling time of a set-point step response.

    Args:
        t: sample times (s), increasing.
        y: the response (the true sway position, m), measured from its pre-step value.
        t_step: when the set-point stepped (s).
        step: the step (m), nonzero.
        settle: the settling band (fraction of the step; 5 %).

    Returns:
        ``rise_time_s`` (10 % to 90 % of the step; ``inf`` if never reached),
        ``overshoot_pct`` (largest excess over the step, % of it, >= 0) and ``settling_time_s``
        (from the step until the response stays inside the band; ``inf`` if it never does).
    """
    if not (math.isfinite(step) and step != 0.0):
        raise ValueError(f"step must be a finite nonzero length, got {step!r}")
    tt = np.asarray(t, dtype=float)
    yy = np.asarray(y, dtype=float) / float(step)
    if tt.shape != yy.shape or tt.ndim != 1:
        raise ValueError(f"t and y must be 1-D of one length, got {tt.shape} and {yy.shape}")
    after = tt >= t_step
    ta, ya = tt[after], yy[after]
    if ta.size == 0:
        raise ValueError(f"no samples after the step time {t_step!r} s")

    def first(level: float) -> float:
        hit = np.nonzero(ya >= level)[0]
        return float(ta[hit[0]]) if hit.size else math.inf

    outside = np.nonzero(np.abs(ya - 1.0) > settle)[0]
    if outside.size == 0:
        settling = 0.0
    elif outside[-1] + 1 < ta.size:
        settling = float(ta[outside[-1] + 1] - t_step)
    else:
        settling = math.inf
    return {
        "rise_time_s": first(0.9) - first(0.1),
        "overshoot_pct": max(0.0, 100.0 * (float(ya.max()) - 1.0)),
        "settling_time_s": settling,
    }
