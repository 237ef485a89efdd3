"""Accuracy indices and run statistics (Tomera 2014 eqs. 54-57): the analysis forms (NumPy)
and the online accumulator of N >= 1 runs (one compiled step over the N envs).

Public names: ``CHATTER_KEYS``, ``HF_PERIOD_S``, ``INDEX_KEYS``, ``MIN_SAMPLES``,
``REVERSAL_BAND``, ``SEED_WEIGHTS``, ``BatchedManoeuvreMetrics``, ``ManoeuvreMetrics``,
``accuracy_indices``, ``command_chatter``, ...

Design notes: docs/design/metrics.md.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import entry, njit
from shipgym.dynamics.frames import wrap, wrap_angle

if TYPE_CHECKING:  # pragma: no cover - typing only
    from shipgym.records import StepRecord

__all__ = [
    "CHATTER_KEYS",
    "HF_PERIOD_S",
    "INDEX_KEYS",
    "MIN_SAMPLES",
    "REVERSAL_BAND",
    "SEED_WEIGHTS",
    "accuracy_indices",
    "BatchedManoeuvreMetrics",
    "command_chatter",
    "episode_result",
    "honest_indices",
    "indices_note",
    "j_c",
    "ManoeuvreMetrics",
    "rmse",
]

#: the accuracy indices of eqs. 54-57
INDEX_KEYS = ("x_E", "y_E", "psi_E", "J_c")

#: fewest accuracy samples (1 s apart) behind indices that describe a run: below this the
#: mean of a few near-zero errors at the start would look like a perfect run
MIN_SAMPLES = 10

#: half-width of the band around zero a command must leave, on the other side, for a sign
#: change to count as a reversal (normalised command, i.e. 2 % of the full command on
#: that side; :func:`command_chatter`)
REVERSAL_BAND = 0.02

#: periods below this (s) count as high-frequency command content (:func:`command_chatter`)
HF_PERIOD_S = 20.0

#: a command counts as stopped (at zero) inside the reversal band ``|a_k| <= band`` and as
#: started again once ``|a_k| > START_FACTOR * band`` (hysteresis, so that a command dithering
#: at the band's edge is not counted as starting every step; [chosen]: twice the band, i.e.
#: 4 % of the full command on that side; for the Blue Lady's main propeller 19 rpm ahead,
#: 0.7 N of its 451 N; :func:`command_chatter`)
START_FACTOR = 2.0

#: the per-channel chatter statistics of :func:`command_chatter` (also in the episode summary)
CHATTER_KEYS = (
    "reversals_per_min",
    "starts_per_min",
    "zero_fraction",
    "limit_fraction",
    "hf_variance_fraction",
    "travel_per_min",
)

SEED_WEIGHTS: tuple[float, float, float] = (1.0, 1.0, 0.01)
"""``(lambda_1, lambda_2, lambda_3)`` of Tomera (2014) eq. 57 (1/m, 1/m, 1/deg)."""

_NAN = float("nan")
_DEG = 180.0 / math.pi


def _weights(weights: Sequence[float]) -> tuple[float, float, float]:
    w = tuple(float(x) for x in weights)
    if len(w) != 3 or not all(math.isfinite(x) for x in w):
        raise ValueError(f"weights must be three finite numbers (l1, l2, l3), got {weights!r}")
    return w  # type: ignore[return-value]


def j_c(x_E: float, y_E: float, psi_E: float, weights: Sequence[float] = SEED_WEIGHTS) -> float:
    """The functional of Tomera (2014) eq. 57: ``J_c = l1 x_E + l2 y_E + l3 psi_E``.

    Args:
        x_E: mean absolute surge-direction error (m), eq. 54.
        y_E: mean absolute sway-direction error (m), eq. 55.
        psi_E: mean absolute heading error (deg), eq. 56.
        weights: ``(l1, l2, l3)`` (default the paper's ``(1, 1, 0.01)``).
    """
    w = _weights(weights)
    return w[0] * x_E + w[1] * y_E + w[2] * psi_E


def _indices(sx: float, sy: float, sp: float, n: int, w: tuple[float, float, float]) -> dict:
    x_e, y_e, psi_e = sx / n, sy / n, sp / n * _DEG
    return {
        "x_E": x_e,
        "y_E": y_e,
        "psi_E": psi_e,
        "J_c": w[0] * x_e + w[1] * y_e + w[2] * psi_e,
    }


def accuracy_indices(
    eta_r: ArrayLike, eta_d_r: ArrayLike, weights: Sequence[float] = SEED_WEIGHTS
) -> dict[str, float]:
    """The accuracy indices of Tomera (2014) eqs. 54-57 from sampled r-frame poses.

    Args:
        eta_r: ship poses ``[x^r, y^r, psi^r]`` (m, m, rad), shape (N, 3), one per sample
            (Tomera 2014: measured, every 1 s).
        eta_d_r: desired poses at the same samples (m, m, rad), shape (N, 3).
        weights: ``(l1, l2, l3)`` of eq. 57 (default the paper's ``(1, 1, 0.01)``).

    Returns:
        ``{"x_E": m, "y_E": m, "psi_E": deg, "J_c": -}``: mean absolute errors (eqs. 54-56;
        heading error wrapped to (-pi, pi], then converted to degrees) and eq. 57.

    Raises:
        ValueError: mismatched shapes, no samples or non-finite values.
    """
    w = _weights(weights)
    a = np.asarray(eta_r, dtype=float)
    b = np.asarray(eta_d_r, dtype=float)
    if a.ndim != 2 or a.shape[1] != 3 or a.shape != b.shape:
        raise ValueError(
            f"eta_r and eta_d_r must both have shape (N, 3), got {a.shape} and {b.shape}"
        )
    if a.shape[0] == 0:
        raise ValueError("no samples: accuracy indices need at least one sample")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ValueError("eta_r and eta_d_r must be finite")
    e = np.abs(b - a)
    e[:, 2] = np.abs(wrap_angle(b[:, 2] - a[:, 2]))
    s = e.sum(axis=0)
    return _indices(float(s[0]), float(s[1]), float(s[2]), a.shape[0], w)


def indices_note(metrics: Any, *, plan_finite: bool = True) -> str | None:
    """Why a run's accuracy indices do not describe a whole run, or ``None`` when they do.

    The indices (eqs. 54-57) are means over the manoeuvre that was flown; a run that hit a
    quay, stopped before its plan was finished or took fewer than :data:`MIN_SAMPLES`
    samples has means over a part only (a contact after 0.6 s leaves one sample at the
    start, with zero error: ``J_c = 0``), so they must not be compared with complete runs.

    Args:
        metrics: an ``episode_metrics`` mapping (``quay_contact``, ``completed``,
            ``n_samples``, ``duration_s``, ``legs_completed``).
        plan_finite: whether the task's plan ends (harbour, tracking); station keeping holds
            until the time limit, so not finishing is its normal end.
    """
    t = float(metrics.get("duration_s", float("nan")))
    n = int(metrics.get("n_samples", 0))
    if metrics.get("quay_contact"):
        return f"quay contact at {t:.1f} s: the manoeuvre failed, the indices cover only its start"
    if n < MIN_SAMPLES:
        return f"too short: {n} accuracy samples (at least {MIN_SAMPLES} needed)"
    if plan_finite and not metrics.get("completed", True):
        legs = int(metrics.get("legs_completed", 0))
        return (
            f"manoeuvre not finished ({legs} legs completed in {t:.0f} s): the indices cover "
            "only the part that was flown"
        )
    return None


def honest_indices(metrics: Any, *, plan_finite: bool = True) -> dict[str, Any]:
    """The indices of a run, NaN (with the reason) when they do not describe a whole run.

    Returns:
        ``{x_E, y_E, psi_E, J_c, measured, indices_note, partial_indices}``: the values of
        ``metrics`` when :func:`indices_note` finds nothing; otherwise NaN (the ``measured``
        indices too), ``indices_note`` the reason and ``partial_indices`` the raw means over
        the part that was flown (``{"truth": ..., "measured": ...}``).
    """
    note = indices_note(metrics, plan_finite=plan_finite)
    truth = {k: float(metrics[k]) for k in INDEX_KEYS}
    measured = metrics.get("measured")
    if note is None:
        return {**truth, "measured": measured, "indices_note": None, "partial_indices": None}
    nan = float("nan")
    return {
        **{k: nan for k in INDEX_KEYS},
        "measured": None if measured is None else {k: nan for k in INDEX_KEYS},
        "indices_note": note,
        "partial_indices": {"truth": truth, "measured": measured},
    }


def episode_result(
    metrics: Any,
    record: StepRecord | None,
    *,
    terminated: bool,
    truncated: bool,
    plan_finite: bool = True,
) -> dict[str, Any]:
    """The plain-data result of one finished episode, shared by ``shipgym run`` and evaluation.

    Args:
        metrics: the episode's :meth:`ManoeuvreMetrics.summary` (``env.episode_metrics()``).
        record: the last step's :class:`~shipgym.records.StepRecord` (``info["record"]``; for
            the observer's ``estimation_rmse``), or ``None``.
        terminated, truncated: how the episode ended.
        plan_finite: whether the task's plan ends (see :func:`indices_note`).

    Returns:
        ``completed``, ``legs_completed``, ``duration_s`` (s), ``quay_contact``, ``terminated``,
        ``truncated``, the indices of :func:`honest_indices` (``x_E``, ``y_E`` (m), ``psi_E``
        (deg), ``J_c``, ``measured``, ``indices_note``, ``partial_indices``), ``n_samples``,
        ``leg_times`` (s), ``thrust_mean_abs``, ``thrust_total_variation`` (N),
        ``saturated_fraction``, the command chatter per channel (:data:`CHATTER_KEYS`, see
        :func:`command_chatter`) and ``rmse`` (``None`` without an observer).
    """
    idx = honest_indices(metrics, plan_finite=plan_finite)
    return {
        "completed": bool(metrics["completed"]),
        "legs_completed": int(metrics["legs_completed"]),
        "duration_s": float(metrics["duration_s"]),
        "quay_contact": bool(metrics["quay_contact"]),
        "terminated": bool(terminated),
        "truncated": bool(truncated),
        **idx,
        "n_samples": int(metrics["n_samples"]),
        "leg_times": list(metrics["leg_times"]),
        "thrust_mean_abs": list(metrics["thrust_mean_abs"]),
        "thrust_total_variation": list(metrics["thrust_total_variation"]),
        "saturated_fraction": list(metrics["saturated_fraction"]),
        **{k: list(metrics.get(k, ())) for k in CHATTER_KEYS},
        "rmse": None
        if record is None or record.estimation_rmse is None
        else dict(record.estimation_rmse),
    }


def command_chatter(
    command: ArrayLike,
    dt: float,
    *,
    reversible: ArrayLike | None = None,
    band: float = REVERSAL_BAND,
    hf_period: float = HF_PERIOD_S,
    limit_tol: float = 1e-6,
) -> dict[str, list[float]]:
    r"""Chatter statistics of sampled actuator commands, per channel.

    The commands are the normalised actions ``a_k`` in [-1, 1] sent at ``t_k = k dt`` and held
    for one control period ``dt`` (s), shape (K, n_channels). For a two-sided channel the sign
    of ``a`` is the sign of the physical command (``c / upper`` ahead, ``c / |lower|``
    astern). With ``T = K dt / 60`` (min):

    - ``reversals_per_min``: reversals / T. A *reversal* is a change of the command's
      direction through zero counted with hysteresis: the channel's direction becomes +1 when
      ``a_k > band`` and -1 when ``a_k < -band`` (it keeps its direction inside the band
      ``|a_k| <= band``; unset before the first exit); a reversal is a change of that direction
      from +1 to -1 or back. So a command that dithers inside the band, or leaves it and comes
      back on the same side, does not count. 0 for channels that are not ``reversible``.
    - ``starts_per_min``: starts / T. The channel is *stopped* before the first sample,
      whenever ``|a_k| <= band`` and when the command crosses to the other side of zero;
      a *start* is a sample with ``|a_k| > START_FACTOR band`` (:data:`START_FACTOR`: a
      hysteresis, so that a command hovering at the band's edge does not count again and
      again) on another side than the one the shaft was running on: from rest, or straight
      through zero (every reversal starts the shaft again). A command that drops to zero
      and picks up again on the same side (stop/start cycling, what a reversal hysteresis
      that holds the thrust at zero trades reversals for) counts as starts without
      reversals. Every channel counts.
    - ``zero_fraction``: fraction of the samples at zero, ``|a_k| <= band``.
    - ``limit_fraction``: fraction of the samples with ``|a_k| >= 1 - limit_tol`` (at a
      command limit).
    - ``hf_variance_fraction``: the share of the variance of the linearly detrended command
      at periods below ``hf_period`` (s): with the one-sided periodogram ``P(f_j)`` of the
      detrended sequence (rectangular window, so that ``sum_j P(f_j) df`` is its variance,
      Parseval), ``sum_{f_j > 1/hf_period} P(f_j) / sum_{j >= 1} P(f_j)``; 0 for a command
      without variance after detrending (a constant or a ramp); NaN for fewer than 4 samples
      or ``hf_period <= 2 dt`` (no resolved frequency above ``1/hf_period``).
    - ``travel_per_min``: ``sum_k |a_k - a_{k-1}| / T`` (normalised units per minute).

    Args:
        command: normalised commands, shape (K, n_channels) (or (K,) for one channel).
        dt: control period (s) > 0.
        reversible: per channel, whether reversals count (a two-sided channel, e.g. a
            reversible propeller, a tunnel thruster); default all.
        band: the reversal band half-width (normalised) in [0, 1).
        hf_period: the period (s) below which content counts as high frequency.
        limit_tol: tolerance of the limit test (normalised).

    Returns:
        ``{key: [value per channel]}`` for the keys of :data:`CHATTER_KEYS`; all NaN for an
        empty command.
    """
    a = np.asarray(command, dtype=float)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2:
        raise ValueError(f"command must have shape (K, n_channels), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError("command must be finite (normalised actions in [-1, 1])")
    dt = float(dt)
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a control period > 0 (s), got {dt!r}")
    if not (0.0 <= band < 1.0):
        raise ValueError(f"band must be in [0, 1) (normalised command), got {band!r}")
    if not (math.isfinite(hf_period) and hf_period > 0.0):
        raise ValueError(f"hf_period must be a period > 0 (s), got {hf_period!r}")
    n = a.shape[1]
    rev = np.ones(n, bool) if reversible is None else np.asarray(reversible, dtype=bool)
    if rev.shape != (n,):
        raise ValueError(f"reversible must have {n} flags, got shape {rev.shape}")
    rows = chatter_rows(a[None], dt, rev, band, hf_period, limit_tol)
    return {key: v[0] for key, v in rows.items()}


def chatter_rows(
    a: NDArray[np.float64],
    dt: float,
    reversible: NDArray[np.bool_],
    band: float = REVERSAL_BAND,
    hf_period: float = HF_PERIOD_S,
    limit_tol: float = 1e-6,
) -> dict[str, list[list[float]]]:
    """:func:`command_chatter` of M runs of the same length at once (the one law; arguments
    checked by the caller): ``a`` (M, K, n_channels) finite commands, ``dt`` (s) > 0,
    ``reversible`` (n_channels,) bools. Returns ``{key: [[value per channel] per run]}``;
    run ``r``'s values are those of ``a[r]`` alone, bit for bit, whatever M."""
    m, k, n = a.shape
    nan = _NAN  # one object: two summaries of the same run compare equal
    if k == 0:
        return {key: [[nan] * n for _ in range(m)] for key in CHATTER_KEYS}
    minutes = k * dt / 60.0
    resolved = k >= 4 and hf_period > 2.0 * dt  # else no resolved content below hf_period
    hf_all = _hf_fractions(a, dt, hf_period) if resolved else [[nan] * n for _ in range(m)]
    counts = np.zeros((5, m, n))  # reversals, samples at a limit, travel, starts, at zero
    _chatter_sums(np.ascontiguousarray(a), reversible, float(band), 1.0 - limit_tol,
                  START_FACTOR * float(band), counts)  # fmt: skip
    reversals, at_limit, travel, starts, at_zero = counts.tolist()
    return {
        "reversals_per_min": [[c / minutes for c in r] for r in reversals],
        "starts_per_min": [[c / minutes for c in r] for r in starts],
        "zero_fraction": [[c / k for c in r] for r in at_zero],
        "limit_fraction": [[c / k for c in r] for r in at_limit],
        "hf_variance_fraction": hf_all,
        "travel_per_min": [[x / minutes for x in r] for r in travel],
    }


@njit
def _chatter_sums(a, rev, band, limit, start, out):  # type: ignore[no-untyped-def]
    """:func:`command_chatter`'s sums per run ``r`` and channel ``j`` of the commands ``a``
    (M, K, n) into ``out`` (5, M, n): the reversals through the band ``|a| <= band`` (0 where
    not ``rev[j]``), the samples with ``|a| >= limit``, the travel
    ``sum_k |a_k - a_{k-1}|``, the starts (stopped at ``|a| <= band``, started at
    ``|a| > start``) and the samples with ``|a| <= band``."""
    m, k, n = a.shape
    for q in range(m):
        for j in range(n):
            side = 0
            count = 0
            hits = 0
            travel = 0.0
            run = 0  # the shaft's running side: 0 stopped (at rest before the first sample)
            starts = 0
            zeros = 0
            for i in range(k):
                v = a[q, i, j]
                sv = 1 if v > 0.0 else -1
                if abs(v) <= band:
                    zeros += 1
                    run = 0
                elif abs(v) > start:
                    if run != sv:  # from rest, or straight through zero to the other side
                        starts += 1
                    run = sv
                elif run != sv:  # through zero, not yet past the start band: stopped
                    run = 0
                s = 1 if v > band else (-1 if v < -band else 0)
                if s != 0:
                    if side != 0 and s != side:
                        count += 1
                    side = s
                if abs(v) >= limit:
                    hits += 1
                if i > 0:
                    travel += abs(v - a[q, i - 1, j])
            out[0, q, j] = count if rev[j] else 0
            out[1, q, j] = hits
            out[2, q, j] = travel
            out[3, q, j] = starts
            out[4, q, j] = zeros


def _hf_fractions(a: NDArray[np.float64], dt: float, hf_period: float) -> list[list[float]]:
    """:func:`command_chatter`'s ``hf_variance_fraction`` of each column of each run of ``a``
    (M, K, n) (K >= 4 samples ``dt`` apart): the one-sided periodogram of the linearly
    detrended column (rectangular window, density scaling ``|X_j|^2 dt / K``, doubled except
    at 0 and the Nyquist frequency; SciPy's ``periodogram(x, 1/dt, "boxcar",
    detrend="linear")``, which the tests compare it with), its sum above ``1/hf_period`` over
    its sum above 0; 0 where the detrended column has no variance left (``sum < 1e-24``:
    round-off of a constant or a ramp). Each run's floats are its own alone, whatever M.
    """
    k = a.shape[1]
    i = np.arange(k, dtype=float) - 0.5 * (k - 1)  # centred sample index
    # each column of each run a contiguous row (M, n, K): every sum below runs along its row
    # alone (NumPy's pairwise sum), so the floats of a run do not depend on M or n
    x = np.ascontiguousarray(a.transpose(0, 2, 1))
    centred = x - x.mean(axis=2, keepdims=True)
    slope = (centred * i).sum(axis=2) / (i @ i)
    z = np.fft.rfft(centred - slope[:, :, None] * i, axis=2)
    p = (z.real * z.real + z.imag * z.imag) * (dt / k)
    p[:, :, 1 : (k + 1) // 2] *= 2.0  # one-sided: every bin but 0 and (even K) Nyquist twice
    f = np.arange(p.shape[2]) / (k * dt)
    j0 = int(np.searchsorted(f, 1.0 / hf_period, side="right"))  # the first f > 1/hf_period
    total = p[:, :, 1:].sum(axis=2)
    high = p[:, :, j0:].sum(axis=2)  # (a slice: a row's sum whatever M, as a mask's is not)
    return [
        [float(h / s) if s > 1e-24 else 0.0 for h, s in zip(hr, sr, strict=True)]
        for hr, sr in zip(high.tolist(), total.tolist(), strict=True)
    ]


def rmse(a: ArrayLike, b: ArrayLike, angle: bool = False, axis: int | None = 0) -> Any:
    """Root-mean-square error ``sqrt(mean((a - b)^2))`` along ``axis``.

    Args:
        a: estimates, e.g. shape (N,) or (N, k).
        b: true values, same shape.
        angle: wrap the differences to (-pi, pi] first (for headings, rad).
        axis: axis of the mean (default 0, the samples); ``None`` for all elements.

    Returns:
        A float for a scalar result, else an array (e.g. (k,) for (N, k) inputs).
    """
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    if d.size == 0:
        raise ValueError("rmse of empty arrays")
    if angle:
        d = np.asarray(wrap_angle(d))
    out = np.sqrt(np.mean(d * d, axis=axis))
    return float(out) if np.ndim(out) == 0 else out


# ---- the run-time law: one compiled accumulator over N >= 1 envs ------------------------------
# Per env i the state is a row of F (float64) and of I (int64), with the columns below, and
# rows of two growing tables: L (float64) holds in its row s the per-leg sums of leg slot s
# (leg index, samples, |errors| of eqs. 54-56; integers below 2**53, exact as floats) and the
# s-th completed leg (duration, completion time); CH holds the recorded commands (the command,
# then its time). A flag column holds what the Python form held as ``None``.
_F_T_LAST, _F_LEG_START, _F_SUM, _F_MEAS, _F_ACT = 0, 1, 2, 5, 8  # F: then 4 blocks of n_act
_I_HAS_T, _I_NEXT_K, _I_N_TRUTH, _I_N_MEAS, _I_N_STEPS, _I_SAMPLED = 0, 1, 2, 3, 4, 5
_I_HAS_LEG, _I_LEG, _I_SLOT, _I_HAS_FPREV, _I_N_THRUST = 6, 7, 8, 9, 10
_I_HAS_SPREV, _I_N_SAT, _I_N_SLOTS, _I_N_LT, _I_N_CMD, _I_ACT = 11, 12, 13, 14, 15, 16
_L_LEG, _L_N, _L_SUM, _L_TIME = 0, 1, 2, 5  # L: slot (leg, n, 3 sums), completed leg (2)
#: ``given`` bits of the kernel: which optional inputs this call has
_G_THRUST, _G_SAT, _G_LEG, _G_CMD = 1, 2, 4, 8
#: kernel error codes (returned as ``-(code + 16 * env)``)
_E_T, _E_BACK, _E_THRUST, _E_ETA, _E_ETA_D, _E_MEAS, _E_L, _E_CMD = range(1, 9)


@njit
def _slot(i, leg, I, L):  # type: ignore[no-untyped-def]
    """The per-leg slot of ``leg`` in env ``i``; a new, empty one if the leg is new (the
    caller made room)."""
    n = I[i, _I_N_SLOTS]
    for s in range(n):
        if L[i, s, _L_LEG] == leg:
            return s
    L[i, n, _L_LEG] = leg
    L[i, n, _L_N] = L[i, n, _L_SUM] = L[i, n, _L_SUM + 1] = L[i, n, _L_SUM + 2] = 0.0
    I[i, _I_N_SLOTS] = n + 1
    return n


@njit
def _complete_leg(i, t, has_next, next_leg, F, I, L):  # type: ignore[no-untyped-def]
    """Env ``i``'s current leg (if any) completed at ``t`` (s): its duration
    ``t - t_start`` and ``t`` appended; ``next_leg`` (if ``has_next``) starts at ``t``."""
    if I[i, _I_HAS_LEG]:
        k = I[i, _I_N_LT]
        L[i, k, _L_TIME] = t - F[i, _F_LEG_START]
        L[i, k, _L_TIME + 1] = t
        I[i, _I_N_LT] = k + 1
    if has_next:
        I[i, _I_HAS_LEG] = 1
        I[i, _I_LEG] = next_leg
        I[i, _I_SLOT] = _slot(i, next_leg, I, L)
        F[i, _F_LEG_START] = t
    else:
        I[i, _I_HAS_LEG] = 0
        I[i, _I_SLOT] = -1


@njit
def _finite3(x, i):  # type: ignore[no-untyped-def]
    o = 3 * i
    return math.isfinite(x[o]) and math.isfinite(x[o + 1]) and math.isfinite(x[o + 2])


@njit
def _record(t, mask, eta, eta_d, meas, has_meas, thrust, sat, leg, cmd, given, period, tol,
            F, I, L, CH):  # type: ignore[no-untyped-def]  # fmt: skip
    """One control step of the envs of ``mask`` (module section above; the inputs flat,
    C-order rows: ``eta[3 i + j]``; ``meas`` read where ``has_meas``). First every env is
    checked (nothing changes on an error: ``-(code + 16 i)`` is returned, also where a table
    must grow first); then each env's sums advance in the order of its own step. Returns the
    number of envs sampled (``I[i, _I_SAMPLED]``: env ``i`` took an accuracy sample)."""
    n = t.shape[0]
    na = (F.shape[1] - _F_ACT) // 4
    nc = CH.shape[2] - 1
    cap = L.shape[1]
    for i in range(n):  # checks only
        if not mask[i]:
            continue
        ti = t[i]
        if not math.isfinite(ti):
            return -(_E_T + 16 * i)
        if I[i, _I_HAS_T]:
            if ti < F[i, _F_T_LAST]:
                return -(_E_BACK + 16 * i)
            next_k = I[i, _I_NEXT_K]
        else:
            next_k = max(0, math.ceil((ti - tol) / period))
        if given & _G_THRUST:
            for j in range(na):
                if not math.isfinite(thrust[na * i + j]):
                    return -(_E_THRUST + 16 * i)
        if ti >= next_k * period - tol:
            if not _finite3(eta, i):
                return -(_E_ETA + 16 * i)
            if not _finite3(eta_d, i):
                return -(_E_ETA_D + 16 * i)
            if has_meas[i] and not _finite3(meas, i):
                return -(_E_MEAS + 16 * i)
        if given & _G_LEG and (I[i, _I_N_SLOTS] == cap or I[i, _I_N_LT] == cap):
            return -(_E_L + 16 * i)
        if given & _G_CMD and I[i, _I_N_CMD] == CH.shape[1]:
            return -(_E_CMD + 16 * i)
    f_abs, f_tv, f_prev, s_time = _F_ACT, _F_ACT + na, _F_ACT + 2 * na, _F_ACT + 3 * na
    s_count, s_prev = _I_ACT, _I_ACT + na
    count = 0
    for i in range(n):
        if not mask[i]:
            I[i, _I_SAMPLED] = 0
            continue
        ti = t[i]
        if I[i, _I_HAS_T]:
            dt = ti - F[i, _F_T_LAST]
        else:  # the first step: the first sample at the first multiple of the period
            dt = 0.0
            I[i, _I_HAS_T] = 1
            I[i, _I_NEXT_K] = max(0, math.ceil((ti - tol) / period))
        F[i, _F_T_LAST] = ti
        I[i, _I_N_STEPS] += 1
        if given & _G_LEG:  # a new leg index completes the current leg at ti
            lg = leg[i]
            if not I[i, _I_HAS_LEG] or lg != I[i, _I_LEG]:
                _complete_leg(i, ti, True, lg, F, I, L)
        if given & _G_THRUST:  # sum |F_k| and sum |F_k - F_{k-1}|
            o = na * i
            has_prev = I[i, _I_HAS_FPREV]
            for j in range(na):
                fj = thrust[o + j]
                F[i, f_abs + j] += abs(fj)
                if has_prev:
                    F[i, f_tv + j] += abs(fj - F[i, f_prev + j])
                F[i, f_prev + j] = fj
            I[i, _I_HAS_FPREV] = 1
            I[i, _I_N_THRUST] += 1
        if given & _G_SAT:  # steps with the flag; time with the previous step's flag held
            o = na * i
            for j in range(na):
                if sat[o + j]:
                    I[i, s_count + j] += 1
            if I[i, _I_HAS_SPREV]:
                for j in range(na):
                    if I[i, s_prev + j]:
                        F[i, s_time + j] += dt
            for j in range(na):
                I[i, s_prev + j] = 1 if sat[o + j] else 0
            I[i, _I_HAS_SPREV] = 1
            I[i, _I_N_SAT] += 1
        if given & _G_CMD:
            k = I[i, _I_N_CMD]
            for j in range(nc):
                CH[i, k, j] = cmd[nc * i + j]
            CH[i, k, nc] = ti
            I[i, _I_N_CMD] = k + 1
        s = ti >= I[i, _I_NEXT_K] * period - tol
        I[i, _I_SAMPLED] = s
        if s:  # eqs. 54-56: |x_d - x|, |y_d - y|, |wrap(psi_d - psi)|
            count += 1
            o = 3 * i
            ex = abs(eta_d[o] - eta[o])
            ey = abs(eta_d[o + 1] - eta[o + 1])
            ep = abs(wrap(eta_d[o + 2] - eta[o + 2]))
            F[i, _F_SUM] += ex
            F[i, _F_SUM + 1] += ey
            F[i, _F_SUM + 2] += ep
            I[i, _I_N_TRUTH] += 1
            if has_meas[i]:
                F[i, _F_MEAS] += abs(eta_d[o] - meas[o])
                F[i, _F_MEAS + 1] += abs(eta_d[o + 1] - meas[o + 1])
                F[i, _F_MEAS + 2] += abs(wrap(eta_d[o + 2] - meas[o + 2]))
                I[i, _I_N_MEAS] += 1
            if I[i, _I_HAS_LEG]:
                sl = I[i, _I_SLOT]
                L[i, sl, _L_N] += 1.0
                L[i, sl, _L_SUM] += ex
                L[i, sl, _L_SUM + 1] += ey
                L[i, sl, _L_SUM + 2] += ep
            I[i, _I_NEXT_K] = math.floor((ti + tol) / period) + 1
    return count


_EMPTY_F = np.empty(0)
_EMPTY_B = np.empty(0, bool)
_EMPTY_I = np.empty(0, np.int64)
_ENTRY: list[Any] = []


def _record_entry() -> Any:
    """The compiled entry point of :func:`_record` (:func:`shipgym._jit.entry`: no per-call
    type resolution), for inputs of any strides (1-D float64, bool and int64 vectors) and
    the C-contiguous state: the caller passes arrays of these dtypes and dimensions."""
    if not _ENTRY:
        f, b, i = np.zeros(2)[::2], np.zeros(2, bool)[::2], np.zeros(2, np.int64)[::2]
        state = (np.zeros((1, 8)), np.zeros((1, 1), np.int64), np.zeros((1, 1, 1)),
                 np.zeros((1, 1, 1)))  # fmt: skip
        _ENTRY.append(entry(_record, (f, b, f, f, f, b, f, b, i, f, 0, 1.0, 1.0, *state)))
    return _ENTRY[0]


def _grown(a: NDArray[Any]) -> NDArray[Any]:
    """``a`` with its axis 1 (a table's rows per env) twice as long, the new rows zero."""
    out = np.zeros((a.shape[0], 2 * a.shape[1], *a.shape[2:]), a.dtype)
    out[:, : a.shape[1]] = a
    return out


class BatchedManoeuvreMetrics:
    """Online accumulators of the Tomera (2014) accuracy indices and thruster usage of N >= 1
    runs (envs) at once: :class:`ManoeuvreMetrics` of each env, with one compiled step over
    the N envs.

    Call :meth:`record` once per control step with the rows of the envs (arrays with a
    leading axis of N); env ``i``'s statistics (:meth:`summary`) are those of
    :class:`ManoeuvreMetrics` fed env ``i``'s rows alone, bit for bit: the same operations in
    the same order per env. The sampling rule, the statistics and the arguments are
    :class:`ManoeuvreMetrics`'s.

    Args:
        n: number of envs N >= 1.
        sample_period, weights, n_actuators, n_channels, control_period, reversible: as
            :class:`ManoeuvreMetrics` (the same for every env).
    """

    def __init__(
        self,
        n: int,
        sample_period: float = 1.0,
        weights: Sequence[float] = SEED_WEIGHTS,
        n_actuators: int = 3,
        *,
        n_channels: int | None = None,
        control_period: float | None = None,
        reversible: Sequence[bool] | None = None,
    ) -> None:
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ValueError(f"n must be a number of envs >= 1, got {n!r}")
        sample_period = float(sample_period)
        if not (math.isfinite(sample_period) and sample_period > 0.0):
            raise ValueError(f"sample_period must be a positive number of s, got {sample_period}")
        if int(n_actuators) < 1:
            raise ValueError(f"n_actuators must be >= 1, got {n_actuators}")
        self.n = n = int(n)
        self.sample_period = sample_period
        self.weights = _weights(weights)
        self.n_actuators = na = int(n_actuators)
        self.n_channels = nc = na if n_channels is None else int(n_channels)
        if control_period is not None and not (
            math.isfinite(float(control_period)) and float(control_period) > 0.0
        ):
            raise ValueError(f"control_period must be > 0 s or None, got {control_period!r}")
        self.control_period = None if control_period is None else float(control_period)
        if reversible is not None and len(reversible) != nc:
            raise ValueError(f"reversible must have {nc} flags, got {reversible!r}")
        self.reversible = None if reversible is None else tuple(bool(x) for x in reversible)
        self._tol = 1e-6 * sample_period
        self._F = np.zeros((n, _F_ACT + 4 * na))
        self._I = np.zeros((n, _I_ACT + 2 * na), np.int64)
        self._L = np.zeros((n, 4, _L_TIME + 2))
        self._CH = np.zeros((n, 64, nc + 1))
        self._all = np.ones(n, bool)
        self._none = np.zeros(n, bool)
        self._rec = _record_entry()
        self._shape_a, self._shape_c = (na,), (nc,)
        self.reset()

    def __getstate__(self) -> dict[str, Any]:  # the compiled entry point is found again
        state = dict(self.__dict__)
        del state["_rec"]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._rec = _record_entry()

    def reset(self, mask: ArrayLike | None = None) -> None:
        """Forget everything recorded by the envs of ``mask`` ((N,) bools; default all)."""
        m = slice(None) if mask is None else self._mask(mask, "mask")
        self._F[m] = 0.0
        self._I[m] = 0
        self._I[m, _I_SLOT] = -1

    def _mask(self, mask: ArrayLike, what: str) -> NDArray[np.bool_]:
        m = np.asarray(mask, dtype=bool)
        if m.shape != (self.n,):
            raise ValueError(f"{what} must be ({self.n},) booleans, got shape {m.shape}")
        return m

    def _rows(self, x: ArrayLike, k: int, what: str, dtype: Any = float) -> NDArray[Any]:
        """``x`` (N, k) as a flat vector of its rows (a view of a C-contiguous array)."""
        a = np.asarray(x, dtype=dtype)
        if a.shape != (self.n, k):
            raise ValueError(f"{what} must have shape ({self.n}, {k}), got {a.shape}")
        return a.reshape(-1)  # (a copy only where the rows are not C-contiguous)

    # -- recording ---------------------------------------------------------------------------
    def record(
        self,
        t: ArrayLike,
        eta_r: ArrayLike,
        eta_d_r: ArrayLike,
        eta_meas_r: ArrayLike | None = None,
        thrust: ArrayLike | None = None,
        saturated: ArrayLike | None = None,
        leg: ArrayLike | None = None,
        command: ArrayLike | None = None,
        mask: ArrayLike | None = None,
        measured: ArrayLike | None = None,
    ) -> NDArray[np.bool_]:
        """Record one control step of the envs of ``mask`` (the others are untouched and
        their rows ignored).

        Args:
            t: time (s) per env, (N,) (or one number for all), non-decreasing per env.
            eta_r: true poses in the current legs' r-frames (m, m, rad), (N, 3).
            eta_d_r: desired poses in the same r-frames (m, m, rad), (N, 3).
            eta_meas_r: measured poses in the same r-frames (m, m, rad), (N, 3), or None (no
                env measured).
            thrust: actuator forces (N), (N, n_actuators), or None.
            saturated: per-actuator saturation flags, (N, n_actuators), or None.
            leg: the leg index per env, (N,) ints, or None; a change marks env ``i``'s
                previous leg complete at ``t[i]``.
            command: the normalised commands (N, n_channels) applied over the step that ended
                at ``t``, or None.
            mask: (N,) bools, the envs that record this step (default all).
            measured: (N,) bools, the envs whose row of ``eta_meas_r`` is a measurement this
                step (default all when ``eta_meas_r`` is given); the other rows are ignored
                and may hold anything (NaN). A missing measurement is a ``False`` here, as
                ``eta_meas_r=None`` is in :meth:`ManoeuvreMetrics.record`.

        Returns:
            (N,) bools: the envs that took an accuracy sample at this call.

        Raises:
            ValueError: wrong shapes; for an env of ``mask``: a non-finite time, time going
                backwards, non-finite thrust, or a non-finite pose at a sample. Nothing is
                recorded then.
        """
        n = self.n
        tt = np.asarray(t, dtype=float)
        if tt.ndim == 0:
            tt = np.full(n, float(tt))
        elif tt.shape != (n,):
            raise ValueError(f"t must be one time or ({n},) times, got shape {tt.shape}")
        eta = self._rows(eta_r, 3, "eta_r")
        eta_d = self._rows(eta_d_r, 3, "eta_d_r")
        m = self._all if mask is None else self._mask(mask, "mask")
        if eta_meas_r is None:
            meas, has_meas = _EMPTY_F, self._none
        else:
            meas = self._rows(eta_meas_r, 3, "eta_meas_r")
            has_meas = self._all if measured is None else self._mask(measured, "measured")
        na, nc = self.n_actuators, self.n_channels
        given = 0
        f = s = c = _EMPTY_F
        s = _EMPTY_B
        lg = _EMPTY_I
        if thrust is not None:
            f, given = self._rows(thrust, na, "thrust"), given | _G_THRUST
        if saturated is not None:
            s, given = self._rows(saturated, na, "saturated", bool), given | _G_SAT
        if leg is not None:
            lg = np.asarray(leg, dtype=np.int64)
            if lg.shape != (n,):
                raise ValueError(f"leg must be ({n},) leg indices, got shape {lg.shape}")
            given |= _G_LEG
        if command is not None:
            c, given = self._rows(command, nc, "command"), given | _G_CMD
        self._step((tt, m, eta, eta_d, meas, has_meas, f, s, lg, c, given))
        return self._I[:, _I_SAMPLED].astype(bool)

    def record_rows(
        self,
        t: NDArray[np.float64],
        mask: NDArray[np.bool_],
        eta_r: NDArray[np.float64],
        eta_d_r: NDArray[np.float64],
        eta_meas_r: NDArray[np.float64] | None,
        measured: NDArray[np.bool_],
        thrust: NDArray[np.float64],
        saturated: NDArray[np.bool_] | None,
        leg: NDArray[np.int64],
        command: NDArray[np.float64] | None,
    ) -> None:
        """:meth:`record` of arrays its caller made to the shapes and dtypes it checks (an
        env's own rows: ``t`` (N,) float64, ``mask`` and ``measured`` (N,) bools, the poses
        (N, 3) and ``thrust`` (N, n_actuators) float64, ``saturated`` (N, n_actuators)
        bools, ``leg`` (N,) int64, ``command`` (N, n_channels) float64), without the checks
        and conversions: the same compiled step (the errors of a non-finite value or of time
        going backwards are raised as there)."""
        given = _G_THRUST | _G_LEG
        s, c = _EMPTY_B, _EMPTY_F
        if saturated is not None:
            s, given = saturated.reshape(-1), given | _G_SAT
        if command is not None:
            c, given = command.reshape(-1), given | _G_CMD
        meas = _EMPTY_F if eta_meas_r is None else eta_meas_r.reshape(-1)
        self._step((t, mask, eta_r.reshape(-1), eta_d_r.reshape(-1), meas,
                    self._none if eta_meas_r is None else measured, thrust.reshape(-1), s,
                    leg, c, given))  # fmt: skip

    def _step(self, args: tuple[Any, ...]) -> None:
        """The compiled step (:func:`_record`) on ``args``, its tables grown where full."""
        r = self._rec(*args, self.sample_period, self._tol, self._F, self._I, self._L, self._CH)
        if r < 0:
            self._retry(r, args)

    def _retry(self, r: int, args: tuple[Any, ...]) -> int:
        """After the compiled step (:func:`_record`) returned ``r < 0``: the full table grown
        and the step run again, or the error raised as ``ValueError``."""
        while r < 0:
            code, i = -r % 16, -r // 16
            if code == _E_L:
                self._L = _grown(self._L)
            elif code == _E_CMD:
                self._CH = _grown(self._CH)
            else:
                raise ValueError(self._error(code, i, args))
            r = self._rec(*args, self.sample_period, self._tol, self._F, self._I, self._L,
                          self._CH)  # fmt: skip
        return r

    def _error(self, code: int, i: int, args: tuple[Any, ...]) -> str:
        t, _, eta, eta_d, meas, _, thrust = args[:7]
        na = self.n_actuators
        ti = float(t[i])
        if code == _E_T:
            msg = f"t must be finite, got {ti!r}"
        elif code == _E_BACK:
            t_last = float(self._F[i, _F_T_LAST])
            msg = f"time went backwards ({ti} s < {t_last} s); call reset() for a new run"
        elif code == _E_THRUST:
            msg = f"thrust must be finite, got {thrust[na * i : na * i + na].tolist()}"
        else:
            what, x = {_E_ETA: ("eta_r", eta), _E_ETA_D: ("eta_d_r", eta_d)}.get(
                code, ("eta_meas_r", meas)
            )
            msg = f"{what} must be finite, got {x[3 * i : 3 * i + 3].tolist()}"
        return msg if self.n == 1 else f"env {i}: {msg}"

    def complete_leg(
        self, t: ArrayLike, next_leg: ArrayLike | None = None, mask: ArrayLike | None = None
    ) -> None:
        """Mark the current leg of each env of ``mask`` complete at ``t`` (s, one or (N,));
        ``next_leg`` ((N,) ints, if any) starts at ``t`` (:meth:`ManoeuvreMetrics.complete_leg`).
        """
        n = self.n
        tt = np.broadcast_to(np.asarray(t, dtype=float), (n,))
        nxt = None if next_leg is None else np.broadcast_to(np.asarray(next_leg, np.int64), (n,))
        envs = range(n) if mask is None else np.flatnonzero(self._mask(mask, "mask")).tolist()
        for i in envs:  # a rare event: per env
            if max(self._I[i, _I_N_LT], self._I[i, _I_N_SLOTS]) == self._L.shape[1]:
                self._L = _grown(self._L)
            _complete_leg(i, float(tt[i]), nxt is not None, 0 if nxt is None else int(nxt[i]),
                          self._F, self._I, self._L)  # fmt: skip

    # -- results -----------------------------------------------------------------------------
    @property
    def n_samples(self) -> NDArray[np.int64]:
        """Number of accuracy samples taken (truth), (N,)."""
        return self._I[:, _I_N_TRUTH].copy()

    def _result(self, sums: list[float], n: int) -> dict[str, float] | None:
        return None if n == 0 else _indices(sums[0], sums[1], sums[2], n, self.weights)

    def indices(self, i: int = 0) -> tuple[dict[str, float] | None, dict[str, float] | None]:
        """Env ``i``'s accuracy indices so far (``x_E``, ``y_E``, ``psi_E`` (deg), ``J_c``:
        Tomera 2014 eqs. 54-57), from the truth and from the measured pose, each ``None``
        before its first sample: those of :meth:`summary`, without the rest."""
        F, I = self._F[i], self._I[i]
        return (
            self._result(F[_F_SUM : _F_SUM + 3].tolist(), int(I[_I_N_TRUTH])),
            self._result(F[_F_MEAS : _F_MEAS + 3].tolist(), int(I[_I_N_MEAS])),
        )

    def summary(self, i: int = 0) -> dict[str, Any]:
        """Env ``i``'s statistics: :meth:`ManoeuvreMetrics.summary` of its rows."""
        return self.summaries([i])[0]

    def summaries(self, envs: Sequence[int]) -> list[dict[str, Any]]:
        """:meth:`summary` of each env of ``envs`` (the chatter of the envs with as many
        recorded commands computed together: the same floats as one by one)."""
        envs = [int(i) for i in envs]
        chatter = self.chatters(envs)
        return [self._summary(i, c) for i, c in zip(envs, chatter, strict=True)]

    def _summary(self, i: int, chatter: dict[str, list[float]]) -> dict[str, Any]:
        F, I = self._F[i].tolist(), self._I[i].tolist()  # Python floats and ints
        na = self.n_actuators
        nan = float("nan")
        truth = self._result(F[_F_SUM : _F_SUM + 3], I[_I_N_TRUTH]) or {
            "x_E": nan, "y_E": nan, "psi_E": nan, "J_c": nan
        }  # fmt: skip
        fa = _F_ACT
        n_thrust, n_sat = I[_I_N_THRUST], I[_I_N_SAT]
        if n_thrust:
            mean_abs = [x / n_thrust for x in F[fa : fa + na]]
            tv = F[fa + na : fa + 2 * na]
        else:
            mean_abs, tv = [nan] * na, [nan] * na
        count = I[_I_ACT : _I_ACT + na]
        sat = [c / n_sat for c in count] if n_sat else [nan] * na
        per_leg = {}
        for row in sorted(self._L[i, : I[_I_N_SLOTS], : _L_SUM + 3].tolist()):
            k, n = int(row[_L_LEG]), int(row[_L_N])
            if n:
                sx, sy, sp = row[_L_SUM : _L_SUM + 3]
                per_leg[k] = {**_indices(sx, sy, sp, n, self.weights), "n_samples": n}
        lt = self._L[i, : I[_I_N_LT], _L_TIME:].tolist()
        return {
            **truth,
            "measured": self._result(F[_F_MEAS : _F_MEAS + 3], I[_I_N_MEAS]),
            "n_samples": I[_I_N_TRUTH],
            "n_measured_samples": I[_I_N_MEAS],
            "n_steps": I[_I_N_STEPS],
            "thrust_mean_abs": mean_abs,
            "thrust_total_variation": tv,
            "saturated_fraction": sat,
            "saturated_time": F[fa + 3 * na : fa + 4 * na],
            "legs_completed": len(lt),
            "leg_times": [x[0] for x in lt],
            "leg_completion_times": [x[1] for x in lt],
            "per_leg": per_leg,
            **chatter,
        }

    def chatter(self, i: int = 0) -> dict[str, list[float]]:
        """:func:`command_chatter` of env ``i``'s commands recorded so far (lists per
        channel)."""
        return self.chatters([i])[0]

    def chatters(self, envs: Sequence[int]) -> list[dict[str, list[float]]]:
        """:meth:`chatter` of each env of ``envs``: one :func:`chatter_rows` call for the envs
        with the same number of commands and period."""
        nc, rev = self.n_channels, self.reversible
        rev = np.ones(nc, bool) if rev is None else np.asarray(rev, dtype=bool)
        groups: dict[tuple[int, float], list[int]] = {}
        for i in envs:
            k = int(self._I[i, _I_N_CMD])
            dt = self.control_period
            if dt is None:
                ts = self._CH[i, :k, nc].tolist()
                dt = (ts[-1] - ts[0]) / (k - 1) if k > 1 and ts[-1] > ts[0] else 1.0
            groups.setdefault((k, float(dt)), []).append(i)
        out: dict[int, dict[str, list[float]]] = {}
        for (k, dt), rows in groups.items():
            a = self._CH[rows, :k, :nc]  # (M, k, n_channels), a copy
            if not np.all(np.isfinite(a)):
                raise ValueError("command must be finite (normalised actions in [-1, 1])")
            res = chatter_rows(a, dt, rev)
            for r, i in enumerate(rows):
                out[i] = {key: v[r] for key, v in res.items()}
        return [out[i] for i in envs]


class ManoeuvreMetrics:
    """Online accumulator of the Tomera (2014) accuracy indices and thruster usage over a run.

    Call :meth:`record` once per control step. The accuracy indices (eqs. 54-57) are sampled
    at ``t = k * sample_period`` (the first call at or after each multiple; the tolerance
    ``1e-6 * sample_period`` absorbs accumulated float error in ``t``), both from the true pose
    (``eta_r``) and, when given, from the measured pose (``eta_meas_r``; the paper's choice).
    Thruster statistics use every call (every control step). The run of one env of
    :class:`BatchedManoeuvreMetrics` (N = 1; its compiled step).

    Args:
        sample_period: sampling time of the indices (s; Tomera 2014: 1 s).
        weights: ``(l1, l2, l3)`` of eq. 57.
        n_actuators: number of thrust channels (3 for the Blue Lady: main, bow, stern).
        n_channels: number of command channels recorded with ``command`` (default
            ``n_actuators``; an azimuth has two: thrust and turning rate).
        control_period: the period (s) of the recorded commands, for the chatter statistics
            (:func:`command_chatter`); ``None``: the mean spacing of the recorded times.
        reversible: per channel, whether its reversals count (:func:`command_chatter`).
    """

    def __init__(
        self,
        sample_period: float = 1.0,
        weights: Sequence[float] = SEED_WEIGHTS,
        n_actuators: int = 3,
        *,
        n_channels: int | None = None,
        control_period: float | None = None,
        reversible: Sequence[bool] | None = None,
    ) -> None:
        self.batch = b = BatchedManoeuvreMetrics(
            1, sample_period, weights, n_actuators, n_channels=n_channels,
            control_period=control_period, reversible=reversible,
        )  # fmt: skip
        self.sample_period, self.weights = b.sample_period, b.weights
        self.n_actuators, self.n_channels = b.n_actuators, b.n_channels
        self.control_period, self.reversible = b.control_period, b.reversible
        self._t = np.zeros(1)
        self._leg = np.zeros(1, np.int64)
        self._sat = np.zeros(b.n_actuators, bool)

    def reset(self) -> None:
        """Forget everything recorded."""
        self.batch.reset()

    # -- recording ---------------------------------------------------------------------------
    def record(
        self,
        t: float,
        eta_r: ArrayLike,
        eta_d_r: ArrayLike,
        eta_meas_r: ArrayLike | None = None,
        thrust: ArrayLike | None = None,
        saturated: ArrayLike | None = None,
        leg: int | None = None,
        command: ArrayLike | None = None,
    ) -> bool:
        """Record one control step.

        Args:
            t: time (s), non-decreasing between calls.
            eta_r: true pose in the current leg's r-frame (m, m, rad), (3,).
            eta_d_r: desired pose in the same r-frame (m, m, rad), (3,).
            eta_meas_r: measured pose in the same r-frame (m, m, rad), (3,), or None.
            thrust: actuator forces (N), (n_actuators,), or None.
            saturated: per-actuator saturation flags, (n_actuators,), or None.
            leg: index of the leg being performed; a change of index marks the previous leg
                complete at ``t`` (see also :meth:`complete_leg`).
            command: the normalised command (``n_channels``,) applied over the step that
                ended at ``t`` (for :func:`command_chatter`), or None.

        Returns:
            True when this call was taken as an accuracy sample.

        Raises:
            ValueError: a wrong number of elements, a non-finite time, time going backwards,
                non-finite thrust, or a non-finite pose at a sample; nothing is recorded then.
        """
        # the arrays as they come where they are float64 vectors of the right length (every
        # control step: no conversion), else converted and checked by _vector
        b = self.batch
        self._t[0] = t if type(t) is float else float(t)
        given = 0
        nd, f8, s3 = np.ndarray, _F8, _SHAPE3
        eta, eta_d = eta_r, eta_d_r
        if type(eta) is not nd or eta.dtype is not f8 or eta.shape != s3:
            eta = _vector(eta_r, 3, "eta_r")
        if type(eta_d) is not nd or eta_d.dtype is not f8 or eta_d.shape != s3:
            eta_d = _vector(eta_d_r, 3, "eta_d_r")
        if eta_meas_r is None:
            meas, has_meas = _EMPTY_F, b._none
        else:
            meas, has_meas = eta_meas_r, b._all
            if type(meas) is not nd or meas.dtype is not f8 or meas.shape != s3:
                meas = _vector(eta_meas_r, 3, "eta_meas_r")
        if thrust is None:
            f = _EMPTY_F
        else:
            f, given = thrust, _G_THRUST
            if type(f) is not nd or f.dtype is not f8 or f.shape != b._shape_a:
                f = _vector(thrust, b.n_actuators, "thrust")
        if saturated is None:
            s = _EMPTY_B
        else:
            s = self._sat
            if type(saturated) is list and len(saturated) == len(s):
                s[:] = saturated  # (the env's flags)
            else:
                s = np.array(saturated, dtype=bool)
                if s.shape != (b.n_actuators,):
                    raise ValueError(f"saturated must have {b.n_actuators} flags, got {s.size}")
            given |= _G_SAT
        if leg is None:
            lg = _EMPTY_I
        else:
            lg = self._leg
            lg[0] = leg if type(leg) is int else int(leg)
            given |= _G_LEG
        if command is None:
            c = _EMPTY_F
        else:
            c, given = command, given | _G_CMD
            if type(c) is not nd or c.dtype is not f8 or c.shape != b._shape_c:
                c = _vector(command, b.n_channels, "command")
        mask = b._all
        r = b._rec(self._t, mask, eta, eta_d, meas, has_meas, f, s, lg, c, given,
                   b.sample_period, b._tol, b._F, b._I, b._L, b._CH)  # fmt: skip
        if r < 0:
            r = b._retry(r, (self._t, mask, eta, eta_d, meas, has_meas, f, s, lg, c, given))
        return r > 0

    def complete_leg(self, t: float, next_leg: int | None = None) -> None:
        """Mark the current leg complete at ``t`` (s); ``next_leg`` (if any) starts at ``t``.

        :meth:`record` calls this when its ``leg`` argument changes; call it yourself for the
        last leg (e.g. when ``Guidance.finished`` becomes True).
        """
        self.batch.complete_leg(float(t), None if next_leg is None else int(next_leg))

    # -- results -----------------------------------------------------------------------------
    @property
    def n_samples(self) -> int:
        """Number of accuracy samples taken (truth)."""
        return int(self.batch._I[0, _I_N_TRUTH])

    def indices(self) -> tuple[dict[str, float] | None, dict[str, float] | None]:
        """The accuracy indices so far, from the truth and from the measured pose
        (:meth:`BatchedManoeuvreMetrics.indices`)."""
        return self.batch.indices(0)

    def summary(self) -> dict[str, Any]:
        """The run's statistics, a dict with:

        - ``x_E``, ``y_E`` (m), ``psi_E`` (deg), ``J_c``: Tomera (2014) eqs. 54-57 from the
          true pose (NaN if no sample was taken);
        - ``measured``: the same four from the measured pose, or None if none recorded;
        - ``n_samples``, ``n_measured_samples``, ``n_steps`` (calls of :meth:`record`);
        - ``thrust_mean_abs`` (N), ``thrust_total_variation`` (N, sum of |F_k - F_{k-1}|
          over consecutive steps), ``saturated_fraction`` (fraction of steps with the flag
          set), ``saturated_time`` (s): lists per actuator (NaN / 0 if not recorded);
        - ``legs_completed``, ``leg_times`` (duration of each completed leg, s),
          ``leg_completion_times`` (s);
        - ``per_leg``: ``{leg index: indices dict (with n_samples)}`` from the truth;
        - ``reversals_per_min``, ``starts_per_min``, ``zero_fraction``, ``limit_fraction``,
          ``hf_variance_fraction``, ``travel_per_min``: :func:`command_chatter` of the
          recorded commands, lists per channel (NaN without commands).
        """
        return self.batch.summary(0)

    def chatter(self) -> dict[str, list[float]]:
        """:func:`command_chatter` of the commands recorded so far (lists per channel)."""
        return self.batch.chatter(0)


_F8 = np.dtype(np.float64)
_SHAPE3 = (3,)


def _vector(x: Any, n: int, what: str) -> NDArray[np.float64]:
    """``x`` as a float64 vector of ``n`` elements (an array of them as it is)."""
    if type(x) is not np.ndarray or x.dtype is not _F8:
        x = np.asarray(x, dtype=float)
    if x.shape != (n,):
        raise ValueError(f"{what} must have {n} elements, got {len(x) if x.ndim else x.shape}")
    return x
