"""Accuracy indices and run statistics (Tomera 2014 eqs. 54-57). Pure NumPy.

Public names: ``CHATTER_KEYS``, ``HF_PERIOD_S``, ``INDEX_KEYS``, ``MIN_SAMPLES``,
``REVERSAL_BAND``, ``SEED_WEIGHTS``, ``accuracy_indices``, ``command_chatter``, ...

Design notes: docs/design/metrics.md.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from shipgym.dynamics.frames import wrap_angle

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

#: the per-channel chatter statistics of :func:`command_chatter` (also in the episode summary)
CHATTER_KEYS = (
    "reversals_per_min",
    "limit_fraction",
    "hf_variance_fraction",
    "travel_per_min",
)

SEED_WEIGHTS: tuple[float, float, float] = (1.0, 1.0, 0.01)
"""``(lambda_1, lambda_2, lambda_3)`` of Tomera (2014) eq. 57 (1/m, 1/m, 1/deg)."""

_TWO_PI = 2.0 * math.pi
_NAN = float("nan")
_DEG = 180.0 / math.pi


def _wrap(a: float) -> float:
    """Scalar wrap to (-pi, pi] (same convention as :func:`shipgym.dynamics.wrap_angle`)."""
    return math.pi - (math.pi - a) % _TWO_PI


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
    from scipy.signal import periodogram

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
    k, n = a.shape
    rev = np.ones(n, bool) if reversible is None else np.asarray(reversible, dtype=bool)
    if rev.shape != (n,):
        raise ValueError(f"reversible must have {n} flags, got shape {rev.shape}")
    nan = _NAN  # one object: two summaries of the same run compare equal
    if k == 0:
        return {key: [nan] * n for key in CHATTER_KEYS}
    minutes = k * dt / 60.0
    out: dict[str, list[float]] = {key: [] for key in CHATTER_KEYS}
    for j in range(n):
        x = a[:, j]
        if rev[j]:
            side = 0
            count = 0
            for v in x.tolist():
                s = 1 if v > band else -1 if v < -band else 0
                if s != 0:
                    if side != 0 and s != side:
                        count += 1
                    side = s
            out["reversals_per_min"].append(count / minutes)
        else:  # it cannot reverse
            out["reversals_per_min"].append(0.0)
        out["limit_fraction"].append(float(np.mean(np.abs(x) >= 1.0 - limit_tol)))
        out["travel_per_min"].append(float(np.abs(np.diff(x)).sum()) / minutes)
        hf = nan
        if k >= 4 and hf_period > 2.0 * dt:  # else no resolved content below hf_period
            f, p = periodogram(x, fs=1.0 / dt, window="boxcar", detrend="linear")
            total = float(p[1:].sum())
            # no variance left (round-off of a constant or a ramp): no high-frequency content
            hf = float(p[f > 1.0 / hf_period].sum()) / total if total > 1e-24 else 0.0
        out["hf_variance_fraction"].append(hf)
    return out


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


def _floats3(v: Any, what: str) -> tuple[float, float, float]:
    if isinstance(v, np.ndarray):
        x = v.tolist()
    elif type(v) is tuple and len(v) == 3 and type(v[0]) is type(v[1]) is type(v[2]) is float:
        x = v  # the environment's measured pose (every control step): floats already
    else:
        x = [float(e) for e in v]
    if len(x) != 3:
        raise ValueError(f"{what} must have 3 elements, got {len(x)}")
    a, b, c = x
    if not (math.isfinite(a) and math.isfinite(b) and math.isfinite(c)):
        raise ValueError(f"{what} must be finite, got {x}")
    return a, b, c


class _Acc:
    """Running sums of |errors| of eqs. 54-56 (Python floats; cheap)."""

    __slots__ = ("sx", "sy", "sp", "n")

    def __init__(self) -> None:
        self.sx = self.sy = self.sp = 0.0
        self.n = 0

    def add(self, a: tuple[float, float, float], d: tuple[float, float, float]) -> None:
        self.sx += abs(d[0] - a[0])
        self.sy += abs(d[1] - a[1])
        self.sp += abs(_wrap(d[2] - a[2]))
        self.n += 1

    def result(self, w: tuple[float, float, float]) -> dict[str, float] | None:
        if self.n == 0:
            return None
        return _indices(self.sx, self.sy, self.sp, self.n, w)


class ManoeuvreMetrics:
    """Online accumulator of the Tomera (2014) accuracy indices and thruster usage over a run.

    Call :meth:`record` once per control step. The accuracy indices (eqs. 54-57) are sampled
    at ``t = k * sample_period`` (the first call at or after each multiple; the tolerance
    ``1e-6 * sample_period`` absorbs accumulated float error in ``t``), both from the true pose
    (``eta_r``) and, when given, from the measured pose (``eta_meas_r``; the paper's choice).
    Thruster statistics use every call (every control step).

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
        sample_period = float(sample_period)
        if not (math.isfinite(sample_period) and sample_period > 0.0):
            raise ValueError(f"sample_period must be a positive number of s, got {sample_period}")
        if int(n_actuators) < 1:
            raise ValueError(f"n_actuators must be >= 1, got {n_actuators}")
        self.sample_period = sample_period
        self.weights = _weights(weights)
        self.n_actuators = int(n_actuators)
        self.n_channels = self.n_actuators if n_channels is None else int(n_channels)
        if control_period is not None and not (
            math.isfinite(float(control_period)) and float(control_period) > 0.0
        ):
            raise ValueError(f"control_period must be > 0 s or None, got {control_period!r}")
        self.control_period = None if control_period is None else float(control_period)
        if reversible is not None and len(reversible) != self.n_channels:
            raise ValueError(f"reversible must have {self.n_channels} flags, got {reversible!r}")
        self.reversible = None if reversible is None else tuple(bool(x) for x in reversible)
        self._tol = 1e-6 * sample_period
        self.reset()

    def reset(self) -> None:
        """Forget everything recorded."""
        n = self.n_actuators
        self._next_k = 0
        self._t_last: float | None = None
        self._truth = _Acc()
        self._meas = _Acc()
        self._per_leg: dict[int, _Acc] = {}
        self._n_steps = 0
        self._f_abs = [0.0] * n
        self._f_tv = [0.0] * n
        self._f_prev: list[float] | None = None
        self._n_thrust = 0
        self._sat_count = [0] * n
        self._sat_time = [0.0] * n
        self._sat_prev: list[bool] | None = None
        self._n_sat = 0
        self._leg: int | None = None
        self._leg_start: float | None = None
        self._leg_times: list[float] = []
        self._leg_completion: list[float] = []
        self._t_first: float | None = None
        self._commands: list[list[float]] = []
        self._t_commands: list[float] = []

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
        """
        if type(t) is not float:  # (a float already every control step: no call)
            t = float(t)
        t_last = self._t_last
        if not math.isfinite(t):
            raise ValueError(f"t must be finite, got {t!r}")
        if t_last is None:
            dt = 0.0
        elif t < t_last:
            raise ValueError(
                f"time went backwards ({t} s < {t_last} s); call reset() for a new run"
            )
        else:
            dt = t - t_last
        if self._t_first is None:
            self._t_first = t
            self._next_k = max(0, math.ceil((t - self._tol) / self.sample_period))
        self._t_last = t
        self._n_steps += 1

        if leg is not None:
            if type(leg) is not int:
                leg = int(leg)
            if self._leg is None:
                self._leg, self._leg_start = leg, t
            elif leg != self._leg:
                self.complete_leg(t, next_leg=leg)

        if thrust is not None:
            self._record_thrust(thrust)
        if saturated is not None:
            self._record_saturation(saturated, dt)
        if command is not None:
            c = command.tolist() if isinstance(command, np.ndarray) else [float(x) for x in command]
            if len(c) != self.n_channels:
                raise ValueError(f"command must have {self.n_channels} elements, got {len(c)}")
            self._commands.append(c)
            self._t_commands.append(t)

        sampled = t >= self._next_k * self.sample_period - self._tol
        if sampled:
            a = _floats3(eta_r, "eta_r")
            d = _floats3(eta_d_r, "eta_d_r")
            self._truth.add(a, d)
            if eta_meas_r is not None:
                self._meas.add(_floats3(eta_meas_r, "eta_meas_r"), d)
            if self._leg is not None:
                acc = self._per_leg.get(self._leg)
                if acc is None:
                    acc = self._per_leg[self._leg] = _Acc()
                acc.add(a, d)
            self._next_k = math.floor((t + self._tol) / self.sample_period) + 1
        return sampled

    def _record_thrust(self, thrust: Any) -> None:
        f = thrust.tolist() if isinstance(thrust, np.ndarray) else [float(x) for x in thrust]
        n = self.n_actuators
        if len(f) != n:
            raise ValueError(f"thrust must have {n} elements, got {len(f)}")
        # one test of the sum (every control step), of the elements only when it fails
        if not math.isfinite(sum(f)) and not all(map(math.isfinite, f)):
            raise ValueError(f"thrust must be finite, got {f}")
        prev = self._f_prev
        fa = self._f_abs
        if prev is None:
            for i, fi in enumerate(f):
                fa[i] += abs(fi)
        else:
            tv = self._f_tv
            for i, fi in enumerate(f):
                fa[i] += abs(fi)
                tv[i] += abs(fi - prev[i])
        self._f_prev = f
        self._n_thrust += 1

    def _record_saturation(self, saturated: Any, dt: float) -> None:
        s = saturated.tolist() if isinstance(saturated, np.ndarray) else list(saturated)
        n = self.n_actuators
        if len(s) != n:
            raise ValueError(f"saturated must have {n} flags, got {len(s)}")
        if any(s):  # (the loops only when a flag is set: rarely, every control step)
            count = self._sat_count
            for i, x in enumerate(s):
                if x:
                    count[i] += 1
        prev = self._sat_prev
        if prev is not None and any(prev):
            held = self._sat_time
            for i, x in enumerate(prev):
                if x:
                    held[i] += dt  # zero-order hold of the previous step's flag
        self._sat_prev = list(map(bool, s))
        self._n_sat += 1

    def complete_leg(self, t: float, next_leg: int | None = None) -> None:
        """Mark the current leg complete at ``t`` (s); ``next_leg`` (if any) starts at ``t``.

        :meth:`record` calls this when its ``leg`` argument changes; call it yourself for the
        last leg (e.g. when ``Guidance.finished`` becomes True).
        """
        t = float(t)
        if self._leg_start is not None:
            self._leg_times.append(t - self._leg_start)
            self._leg_completion.append(t)
        self._leg = next_leg
        self._leg_start = t if next_leg is not None else None

    # -- results -----------------------------------------------------------------------------
    @property
    def n_samples(self) -> int:
        """Number of accuracy samples taken (truth)."""
        return self._truth.n

    def summary(self) -> dict[str, Any]:
        """The run's statistics.

        Returns:
            A dict with:

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
            - ``reversals_per_min``, ``limit_fraction``, ``hf_variance_fraction``,
              ``travel_per_min``: :func:`command_chatter` of the recorded commands, lists per
              channel (NaN without commands).
        """
        w = self.weights
        nan = float("nan")
        truth = self._truth.result(w) or {"x_E": nan, "y_E": nan, "psi_E": nan, "J_c": nan}
        n = self.n_actuators
        if self._n_thrust:
            mean_abs = [x / self._n_thrust for x in self._f_abs]
            tv = list(self._f_tv)
        else:
            mean_abs, tv = [nan] * n, [nan] * n
        sat = [c / self._n_sat for c in self._sat_count] if self._n_sat else [nan] * n
        per_leg = {}
        for k in sorted(self._per_leg):
            acc = self._per_leg[k]
            res = acc.result(w)
            if res is not None:
                per_leg[k] = {**res, "n_samples": acc.n}
        return {
            **truth,
            "measured": self._meas.result(w),
            "n_samples": self._truth.n,
            "n_measured_samples": self._meas.n,
            "n_steps": self._n_steps,
            "thrust_mean_abs": mean_abs,
            "thrust_total_variation": tv,
            "saturated_fraction": sat,
            "saturated_time": list(self._sat_time),
            "legs_completed": len(self._leg_times),
            "leg_times": list(self._leg_times),
            "leg_completion_times": list(self._leg_completion),
            "per_leg": per_leg,
            **self.chatter(),
        }

    def chatter(self) -> dict[str, list[float]]:
        """:func:`command_chatter` of the commands recorded so far (lists per channel)."""
        k = len(self._commands)
        dt = self.control_period
        if dt is None:
            ts = self._t_commands
            dt = (ts[-1] - ts[0]) / (k - 1) if k > 1 and ts[-1] > ts[0] else 1.0
        a = np.array(self._commands, dtype=float).reshape(k, self.n_channels)
        return command_chatter(a, dt, reversible=self.reversible)
