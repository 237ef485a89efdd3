r"""Position and heading sensors: DGPS + gyrocompass (Tomera 2011, 2014; Artyszuk 2003).

``z_k = [p_k + R_2(psi_k) [x_a, y_a]^T, psi_k] + v_k``; noise Tomera (2011) eqs. 61-62
(``R_psi`` read as 0.1 deg^2), DGPS bias and heading bias models.

Public names: ``AL_TAKIE1982_HEADING_SIGMA``, ``AL_TAKIE1982_POSITION_SIGMA``,
``LAKE_HEADING_BIAS_STD``, ``LAKE_SILM_LATITUDE_DEG``, ``TOMERA2011_HEADING_VARIANCE``,
``SENSOR_PRESETS``, ``Measurement``, ``SensorConfig``, ...
Sources: Tomera (2011); Artyszuk (2003); Tomera (2014); Farrell & Barth (1999); Groves (2013);
Bierman (1995).

Design notes: docs/design/observers.sensors.md.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import fields_of, from_mapping, param
from shipgym._jit import entry, njit, spread
from shipgym._seeding import child_seeds
from shipgym._text import did_you_mean

__all__ = [
    "AL_TAKIE1982_HEADING_SIGMA",
    "AL_TAKIE1982_POSITION_SIGMA",
    "LAKE_HEADING_BIAS_STD",
    "LAKE_SILM_LATITUDE_DEG",
    "TOMERA2011_HEADING_VARIANCE",
    "SENSOR_PRESETS",
    "Measurement",
    "SensorConfig",
    "BatchedSensors",
    "Sensors",
    "sensor_config",
]

#: Tomera (2011) eq. 62 ``R_psi = 0.1`` read as deg^2, in rad^2 (sigma 0.316 deg)
TOMERA2011_HEADING_VARIANCE = 0.1 * (math.pi / 180.0) ** 2

_EPS_T = 1e-9  # relative tolerance on sample instants (s / period)
_BLOCK = 256  # samples drawn at once (the same streams as one draw per sample)


@dataclass(frozen=True)
class SensorConfig:
    """DGPS + gyrocompass sensor parameters.

    Attributes:
        period: sampling period (s), Tomera (2014) "sampling time equal 1 (s)".
        position_variance: DGPS noise variance per NED axis (m^2), Tomera (2011) eq. 61.
        heading_variance: gyrocompass noise variance (rad^2), Tomera (2011) eq. 62 (read as deg^2).
        antenna_offset: DGPS antenna position ``(x_a, y_a)`` in the body frame (m), x forward,
            y starboard; the GPS reads ``p + R(psi) [x_a, y_a]``; the heading is unaffected.
        outlier_probability: probability per sample of a position outlier (-).
        outlier_magnitude: size of an outlier, a position jump in a random direction (m).
        dropout_probability: probability per sample that a dropout starts (-).
        dropout_duration: length of a dropout (s); samples in ``[t_start, t_start + d)`` are
            missing.
        position_correlated_fraction: share ``f`` of ``position_variance`` carried by the
            Gauss-Markov DGPS error (-, in [0, 1]); 0: white (default).
        position_correlation_time: correlation time ``tau_p`` of the Gauss-Markov DGPS error
            (s, > 0 when ``f > 0``).
        heading_bias_std: standard deviation of the gyrocompass bias (rad), drawn per
            episode; 0: none (default).
        heading_bias_correlation_time: correlation time of the bias (s); 0: constant over
            the episode.
    """

    period: float = param(1.0, "s", "Tomera (2014): 'sampling time equal 1 (s)'")
    position_variance: float = param(
        0.01, "m^2", "Tomera (2011) eq. 61: R_x = R_y = 0.01 (Blue Lady DGPS, experimental)"
    )
    heading_variance: float = param(
        TOMERA2011_HEADING_VARIANCE,
        "rad^2",
        "Tomera (2011) eq. 62: R_psi = 0.1, read as deg^2 (sigma 0.316 deg; see module docstring)",
    )
    antenna_offset: tuple[float, float] = param(
        (0.0, 0.0), "m", "assumption: antenna at the CG; body frame (x forward, y starboard)"
    )
    outlier_probability: float = param(0.0, "-", "assumption: no outliers by default")
    outlier_magnitude: float = param(20.0, "m", "assumption: a gross DGPS error of 20 m")
    dropout_probability: float = param(0.0, "-", "assumption: no dropouts by default")
    dropout_duration: float = param(10.0, "s", "assumption: a 10 s loss of the DGPS fix")
    position_correlated_fraction: float = param(
        0.0, "-", "default: white DGPS noise (Tomera 2011 models it so); see module docstring"
    )
    position_correlation_time: float = param(
        0.0, "s", "unused at f = 0; DGPS errors correlate over 10-100 s (Farrell & Barth 1999)"
    )
    heading_bias_std: float = param(0.0, "rad", "default: no gyrocompass bias")
    heading_bias_correlation_time: float = param(
        0.0, "s", "0: constant per episode (a settle-point error, IMO A.424(XI) 1979)"
    )

    def __post_init__(self) -> None:
        cls = type(self).__name__
        try:
            off = tuple(float(x) for x in np.asarray(self.antenna_offset, dtype=float).ravel())
        except (TypeError, ValueError) as exc:
            raise ValueError(
                f"{cls}.antenna_offset must be two numbers (x_a, y_a) in m, "
                f"got {self.antenna_offset!r}"
            ) from exc
        if len(off) != 2:
            raise ValueError(
                f"{cls}.antenna_offset must be two numbers (x_a, y_a) in m (body frame), "
                f"got {self.antenna_offset!r}"
            )
        object.__setattr__(self, "antenna_offset", off)
        for f in fields_of(type(self)):
            if f.name == "antenna_offset":
                vals: tuple[Any, ...] = off
            else:
                val = getattr(self, f.name)
                if type(val) is not float and (
                    isinstance(val, bool) or not isinstance(val, int | float | np.number)
                ):
                    raise ValueError(
                        f"{cls}.{f.name} must be a number ({f.metadata['unit']}), got {val!r}"
                    )
                object.__setattr__(self, f.name, float(val))
                vals = (float(val),)
            if not all(math.isfinite(v) for v in vals):
                raise ValueError(f"{cls}.{f.name} must be finite, got {getattr(self, f.name)!r}")
        for name in ("period", "dropout_duration"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{cls}.{name} must be > 0 s, got {getattr(self, name)!r}")
        for name in (
            "position_variance",
            "heading_variance",
            "outlier_magnitude",
            "position_correlation_time",
            "heading_bias_std",
            "heading_bias_correlation_time",
        ):
            if getattr(self, name) < 0:
                raise ValueError(
                    f"{cls}.{name} must be >= 0 ({_unit(name)}), got {getattr(self, name)!r}; "
                    "variances are squared standard deviations"
                )
        if not 0.0 <= self.position_correlated_fraction <= 1.0:
            raise ValueError(
                f"{cls}.position_correlated_fraction is the share of position_variance in the "
                f"Gauss-Markov error and must lie in [0, 1], got "
                f"{self.position_correlated_fraction!r}"
            )
        if self.position_correlated_fraction > 0 and not self.position_correlation_time > 0:
            raise ValueError(
                f"{cls}.position_correlation_time must be > 0 s when "
                f"position_correlated_fraction > 0 (got {self.position_correlation_time!r}); "
                "DGPS errors correlate over tens of seconds to minutes"
            )
        for name in ("outlier_probability", "dropout_probability"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(
                    f"{cls}.{name} is a probability per sample and must lie in [0, 1], "
                    f"got {getattr(self, name)!r}"
                )

    @classmethod
    def from_dict(cls, mapping: Mapping[str, Any]) -> SensorConfig:
        """Build from a mapping; unknown keys raise ``ValueError`` naming the valid ones."""
        return from_mapping(cls, mapping, where="sensor configuration")

    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (round-trips through :meth:`from_dict`)."""
        return {f.name: getattr(self, f.name) for f in fields_of(type(self))}

    def replace(self, **changes: Any) -> SensorConfig:
        """A validated copy with some fields changed (unknown names raise ``ValueError``)."""
        return from_mapping(type(self), {**self.to_dict(), **changes}, where="sensor overrides")

    @property
    def covariance(self) -> NDArray[np.float64]:
        """Measurement noise covariance ``diag(s_p^2, s_p^2, s_psi^2)`` (m^2, m^2, rad^2)."""
        return np.diag([self.position_variance, self.position_variance, self.heading_variance])

    @property
    def correlated(self) -> bool:
        """True when a Gauss-Markov DGPS error or a gyrocompass bias is on."""
        return self.position_correlated_fraction > 0.0 or self.heading_bias_std > 0.0

    def correlated_parameters(self) -> tuple[float, float, float, float]:
        """``(a_p, sd_p, a_b, sd_b)``: the per-sample factors of the exact recursions
        ``b_{k+1} = a b_k + q w_k`` (``q = sd sqrt(1 - a^2)``) of the DGPS error (per axis) and
        of the heading bias, with their stationary standard deviations (m, rad)."""
        f, T = self.position_correlated_fraction, self.period
        a_p = math.exp(-T / self.position_correlation_time) if f > 0.0 else 0.0
        tb = self.heading_bias_correlation_time
        a_b = 1.0 if tb == 0.0 else math.exp(-T / tb)
        return a_p, math.sqrt(f * self.position_variance), a_b, self.heading_bias_std

    @property
    def position_sigma(self) -> float:
        """Standard deviation of the position noise per axis (m), white and correlated."""
        return math.sqrt(self.position_variance)

    @property
    def position_white_sigma(self) -> float:
        """Standard deviation of the white part of the position noise per axis (m)."""
        return math.sqrt((1.0 - self.position_correlated_fraction) * self.position_variance)

    @property
    def heading_sigma(self) -> float:
        """Standard deviation of the heading noise (rad)."""
        return math.sqrt(self.heading_variance)


def _unit(name: str) -> str:
    for f in dataclasses.fields(SensorConfig):
        if f.name == name:
            return str(f.metadata.get("unit", "?"))
    return "?"  # pragma: no cover


_RTK_HEADING_SIGMA = math.radians(0.2)

#: Lake Silm (Ilawa, Poland), where Blue Lady's trials were held: latitude (deg N), approx.
LAKE_SILM_LATITUDE_DEG = 53.6
#: gyrocompass bias std of the lake preset (rad): IMO A.424(XI) (1979) 4.1.3, settle-point
#: repeatability from one run-up to another 0.25 deg sec(lat), at Lake Silm
LAKE_HEADING_BIAS_STD = math.radians(0.25 / math.cos(math.radians(LAKE_SILM_LATITUDE_DEG)))
#: DGPS Gauss-Markov share of the position variance (-) and correlation time (s), lake preset
LAKE_DGPS_CORRELATED_FRACTION = 0.8
LAKE_DGPS_CORRELATION_TIME = 60.0

#: Al-Takie (1982) 2.4.2 [printed]: position-reference sigma 1/3 m per axis (m), from
#: R = 1e-5 p.u.^2 (sigma 0.0033 Lpp), and gyro sigma 0.02 rad (R = 4e-4 rad^2)
AL_TAKIE1982_POSITION_SIGMA = 1.0 / 3.0
AL_TAKIE1982_HEADING_SIGMA = 0.02

#: named sensor presets (overrides of the :class:`SensorConfig` defaults)
SENSOR_PRESETS: Mapping[str, Mapping[str, Any]] = MappingProxyType(
    {
        # Tomera (2011) eqs. 61-62, Tomera (2014) sampling time: the default
        "default": MappingProxyType({}),
        # plain DGPS of Artyszuk (2003): sigma 2 m per axis; gyrocompass as default
        "dgps": MappingProxyType({"position_variance": 2.0**2}),
        # RTK GNSS: sigma 0.02 m, heading sigma 0.2 deg (typical figures, an assumption)
        "rtk": MappingProxyType(
            {"position_variance": 0.02**2, "heading_variance": _RTK_HEADING_SIGMA**2}
        ),
        # the Blue Lady trials of Tomera (2011, 2014): same as default
        "tomera2014": MappingProxyType({}),
        # the lake trial with real-sensor errors: Tomera (2011) total variances, Gauss-Markov
        # DGPS error (80 %, tau 60 s) and a constant gyrocompass bias (IMO A.424(XI) 1979)
        "tomera2014-lake": MappingProxyType(
            {
                "position_correlated_fraction": LAKE_DGPS_CORRELATED_FRACTION,
                "position_correlation_time": LAKE_DGPS_CORRELATION_TIME,
                "heading_bias_std": LAKE_HEADING_BIAS_STD,
                "heading_bias_correlation_time": 0.0,
            }
        ),
        # Al-Takie (1982) 2.4.2, Wimpey Sealab: R = diag(1e-5, 4e-4) p.u.^2, i.e. position
        # sigma 1/3 m per axis and gyro sigma 0.02 rad (printed); no faults. Sampled every
        # 0.1 p.u. (App. 3; 0.31 s Wimpey): the DP tasks set the period to their control
        # period (shipgym.envs.offshore), the preset keeps the default 1 s.
        "al-takie1982": MappingProxyType(
            {
                "position_variance": AL_TAKIE1982_POSITION_SIGMA**2,
                "heading_variance": AL_TAKIE1982_HEADING_SIGMA**2,
            }
        ),
    }
)


def sensor_config(name: str = "default", **overrides: Any) -> SensorConfig:
    """A named sensor preset with optional field overrides.

    Args:
        name: one of :data:`SENSOR_PRESETS` (``default``, ``dgps``, ``rtk``, ``tomera2014``,
            ``tomera2014-lake``, ``al-takie1982``).
        **overrides: :class:`SensorConfig` fields to change.

    Raises:
        ValueError: unknown preset name (the message lists the valid ones), unknown field or
            invalid value.
    """
    if name not in SENSOR_PRESETS:
        raise ValueError(
            f"unknown sensor preset {name!r}{did_you_mean(name, SENSOR_PRESETS)}; valid names "
            f"are: {', '.join(SENSOR_PRESETS)}"
        )
    return SensorConfig.from_dict({**SENSOR_PRESETS[name], **overrides})


@dataclass(frozen=True)
class Measurement:
    """One sensor sample.

    Attributes:
        t: sample time (s).
        z: measured NED pose ``[x, y, psi]`` (m, m, rad; heading in ``(-pi, pi]``), or ``None``
            during a dropout.
        valid: ``z`` is available.
        outlier: truth flag: this sample carries an outlier (for tests and diagnostics only;
            an observer must not use it).
    """

    t: float
    z: NDArray[np.float64] | None
    valid: bool
    outlier: bool = False


#: the fields a batched env's sensors share (each env may have its own noise variances)
_SHARED_FIELDS = tuple(
    f.name
    for f in dataclasses.fields(SensorConfig)
    if f.name not in ("position_variance", "heading_variance")
)


def _streams(
    rng: np.random.Generator, used: tuple[bool, ...] = (True, True, True, True)
) -> tuple[np.random.Generator | None, ...]:
    """The noise, outlier, dropout and correlated-error streams of one sensor set: one
    ``integers(2**63)`` draw from ``rng`` seeds a sequence whose four spawned children seed
    them (the first three are those of a three-child spawn: adding the fourth changed none of
    them). Only the streams where ``used`` is True are made (``None`` for the others): each
    child is the spawn's ``SeedSequence(entropy, spawn_key=(k,))``, so a stream left out
    changes none of the others."""
    entropy = child_seeds(rng)
    return tuple(
        np.random.default_rng(np.random.SeedSequence(entropy, spawn_key=(k,))) if use else None
        for k, use in enumerate(used)
    )


@njit
def _sense(mask, t, eta, k, draws, st, cf, par, out):
    """The measurement law of every env ``j`` with ``mask[j]`` at its time ``t[j]`` (s) and
    true pose ``eta[j]`` (m, m, rad), in place.

    ``draws[j, k[j]]``: the env's next pre-drawn numbers, 3 standard normals (white noise),
    2 uniforms (outlier, its direction), 1 uniform (dropout), 3 standard normals (correlated
    errors); ``st[j]``: the correlated errors ``[b_x, b_y, b_psi]`` (m, m, rad) and the end of
    the dropout (s); ``cf[j]``: the white sigmas ``[x, y, psi]`` (m, m, rad) and the
    Gauss-Markov steps ``q = sd sqrt(1 - a^2)``; ``par``: ``a_p, a_p, a_b`` (-), dropout
    probability (-) and duration (s), outlier probability (-) and size (m), antenna ``x_a,
    y_a`` (m), the instant tolerance (s), correlated errors on (1.0). ``out[j]``: the measured
    pose ``[x, y, psi]`` (NaN in a dropout), valid (1.0/0.0), outlier (1.0/0.0). Returns
    ``-1``, or (doing nothing) the first env whose pre-drawn numbers are used up.
    """
    for j in range(t.shape[0]):
        if mask[j] and k[j] >= draws.shape[1]:
            return j
    pi, two_pi = math.pi, 2.0 * math.pi
    for j in range(t.shape[0]):
        if not mask[j]:
            continue
        d = draws[j, k[j]]
        k[j] += 1
        n0, n1, n2 = d[0] * cf[j, 0], d[1] * cf[j, 1], d[2] * cf[j, 2]
        if par[10] > 0.0:  # one exact Gauss-Markov step per sample, also in dropouts
            for i in range(3):
                st[j, i] = par[i] * st[j, i] + cf[j, 3 + i] * d[6 + i]
            n0 += st[j, 0]
            n1 += st[j, 1]
            n2 += st[j, 2]
        tj = t[j]
        if tj < st[j, 3] - par[9] or d[5] < par[3]:
            if not tj < st[j, 3] - par[9]:  # a dropout starts
                st[j, 3] = tj + par[4]
            out[j, 0] = out[j, 1] = out[j, 2] = np.nan
            out[j, 3] = out[j, 4] = 0.0
            continue
        psi = eta[j, 2]
        c, s = math.cos(psi), math.sin(psi)
        z0 = (eta[j, 0] + c * par[7] - s * par[8]) + n0
        z1 = (eta[j, 1] + s * par[7] + c * par[8]) + n1
        outlier = d[3] < par[5]
        if outlier:  # a jump of par[6] m in a uniformly random direction
            a = two_pi * d[4]
            z0 += par[6] * math.cos(a)
            z1 += par[6] * math.sin(a)
        out[j, 0], out[j, 1] = z0, z1
        out[j, 2] = pi - np.fmod(np.fmod(pi - (psi + n2), two_pi) + two_pi, two_pi)
        out[j, 3] = 1.0
        out[j, 4] = 1.0 if outlier else 0.0
    return -1


_SENSE: list[Any] = []  # _sense's compiled entry point (its argument types never change)


class BatchedSensors:
    """The sensors of ``n`` envs, the one run-time form of the measurement law (compiled,
    :func:`_sense`): each env with its own streams, drawn as :meth:`reset` draws them from the
    env's generator, so that env ``i`` measures bit for bit what the same law at ``n = 1``
    (:class:`Sensors`) reset with the same generator measures, the Gauss-Markov DGPS error and
    the gyrocompass bias included. Draws are taken in blocks (a generator's
    ``standard_normal((k, 3))`` is the stream of ``k`` calls of ``standard_normal(3)``).

    Args:
        config: the sensor parameters (shared by the envs).
        n: number of envs.
        block: samples drawn per refill.
    """

    def __init__(self, config: SensorConfig, n: int, block: int = 256) -> None:
        if not isinstance(config, SensorConfig):
            raise TypeError(f"config must be a SensorConfig, got {type(config).__name__}")
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ValueError(f"n must be an int >= 1, got {n!r}")
        self.config = config
        self.n = n
        self.block = int(block)
        self._corr_on = config.correlated
        # the streams a sample reads: an outlier or dropout draw decides nothing where its
        # probability is 0 (``u < 0`` is False for every uniform), so its stream is not made
        self._used = (
            True,
            config.outlier_probability > 0.0,
            config.dropout_probability > 0.0,
            self._corr_on,
        )
        a_p, _, a_b, _ = config.correlated_parameters()
        c = config
        self._par = np.array(
            [a_p, a_p, a_b, c.dropout_probability, c.dropout_duration, c.outlier_probability,
             c.outlier_magnitude, *c.antenna_offset, _EPS_T * c.period, float(self._corr_on)]
        )  # fmt: skip
        self._cf = np.zeros((n, 6))
        self._sd = np.zeros((n, 3))  # stationary std of the correlated errors
        self.configs = [config] * n
        for i in range(n):
            self._set_coefficients(i, config)
        self._st = np.zeros((n, 4))
        self._st[:, 3] = -math.inf
        self._gens: list[tuple[np.random.Generator | None, ...] | None] = [None] * n
        self._draws = np.zeros((n, self.block, 9))
        self._k = np.full(n, self.block, dtype=np.int64)  # next unused draw (block: refill)
        self._all = np.ones(n, dtype=bool)
        self._t = np.zeros(n)
        self._out = np.zeros((n, 5))

    def _set_coefficients(self, i: int, config: SensorConfig) -> None:
        a_p, sd_p, a_b, sd_b = config.correlated_parameters()
        self._cf[i, :3] = _sigmas(config)
        self._sd[i] = (sd_p, sd_p, sd_b)
        self._cf[i, 3:] = (sd_p * math.sqrt(1.0 - a_p * a_p),) * 2 + (
            sd_b * math.sqrt(1.0 - a_b * a_b),
        )

    def set_config(self, i: int, config: SensorConfig) -> None:
        """Env ``i``'s own noise variances (``config`` may differ from the shared one in
        ``position_variance`` and ``heading_variance`` only: the sample grid, dropouts,
        outliers and the correlated errors' fraction, times and bias std are the batch's;
        the Gauss-Markov DGPS error takes its share of env ``i``'s variance). Call it before
        :meth:`reset` of that env (the reset draws the errors' start from it)."""
        if config is not self.config and any(
            getattr(config, f) != getattr(self.config, f) for f in _SHARED_FIELDS
        ):
            raise ValueError(
                "a batched env's sensors may differ only in position_variance and "
                f"heading_variance; got {config!r} against {self.config!r}"
            )
        self.configs[i] = config
        self._set_coefficients(i, config)

    def reset(self, rngs: list[np.random.Generator], mask: ArrayLike | None = None) -> None:
        """Restart the streams of the envs (all, or those where ``mask`` is True), one
        generator per env (the reset ones are used): one child seed drawn from each (see
        :meth:`Sensors.reset`)."""
        if len(rngs) != self.n:
            raise ValueError(f"rngs must hold one generator per env ({self.n}), got {len(rngs)}")
        m = self._all if mask is None else np.asarray(mask, dtype=bool)
        for i in np.nonzero(m)[0].tolist():
            self._gens[i] = gens = _streams(rngs[i], self._used)
            self._k[i] = self.block
            self._st[i, 3] = -math.inf
            corr = gens[3]  # made where the correlated errors are on
            if corr is not None:  # stationary start, b_0 ~ N(0, sd^2)
                self._st[i, :3] = self._sd[i] * corr.standard_normal(3)

    def _refill(self, i: int) -> None:
        gens = self._gens[i]
        if gens is None:
            raise RuntimeError("Sensors.reset(rng) must be called before measure()")
        noise, outlier, dropout, corr = gens
        d = self._draws[i]
        d[:, 0:3] = noise.standard_normal((self.block, 3))
        # no outliers or no dropouts: zeros, which decide the same (never)
        d[:, 3:5] = 0.0 if outlier is None else outlier.random((self.block, 2))
        d[:, 5] = 0.0 if dropout is None else dropout.random(self.block)
        if corr is not None:
            d[:, 6:9] = corr.standard_normal((self.block, 3))
        self._k[i] = 0

    @property
    def correlated_error(self) -> NDArray[np.float64]:
        """The correlated errors of each env's last sample (n, 3): DGPS ``[x, y]`` (m) and
        gyrocompass bias (rad); zeros when they are off."""
        return self._st[:, :3].copy()

    def _call(self, args: tuple[Any, ...]) -> None:
        """:func:`_sense` on ``args``, refilling the envs whose draws are used up."""
        if not _SENSE:
            _SENSE.append(entry(_sense, args))
        i = _SENSE[0](*args)
        while i >= 0:
            # every env whose draws are used up (a batch in step uses them up together), side
            # by side: each env's draws from its own streams, the same numbers
            mask = args[0]
            due = i + np.nonzero(mask[i:] & (self._k[i:] >= self.block))[0]
            spread(self._refill, due.tolist())
            i = _SENSE[0](*args)

    def measure(
        self, t: ArrayLike, eta_true: ArrayLike, mask: NDArray[np.bool_] | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_]]:
        """Sample every env (or those where ``mask`` is True: only their streams advance) at
        its time ``t`` (n,) for its true pose ``eta_true`` (n, 3).

        Returns:
            ``(z, valid, outlier)``: the measured poses (n, 3) (``nan`` rows during a
            dropout and for the envs not sampled; heading in ``(-pi, pi]``), whether each is
            available, and the outlier truth flags.
        """
        eta = np.array(eta_true, dtype=float)
        if eta.shape != (self.n, 3) or not np.isfinite(eta).all():
            raise ValueError(f"eta_true must be ({self.n}, 3) finite values, got {eta.shape}")
        m = self._all if mask is None else np.array(mask, dtype=bool)
        return self.measure_rows(t, eta, m)

    def measure_rows(
        self, t: ArrayLike, eta_true: NDArray[np.float64], mask: NDArray[np.bool_]
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_]]:
        """:meth:`measure` of rows its caller made: ``eta_true`` (n, 3) finite float64 (a
        physics' state), ``mask`` (n,) bools; without the checks and copies (an env's own
        arrays: the same compiled law)."""
        self._t[:] = t  # a scalar or (n,) (broadcast, as np.broadcast_to refuses other shapes)
        m, eta = mask, eta_true
        out = self._out
        out[:, :3] = np.nan
        out[:, 3:] = 0.0
        self._call((m, self._t, eta, self._k, self._draws, self._st, self._cf, self._par, out))
        return out[:, :3].copy(), out[:, 3] > 0.0, out[:, 4] > 0.0


class Sensors:
    """Runtime DGPS + gyrocompass model drawing its noise from a seeded generator: the
    ``n = 1`` adapter of :class:`BatchedSensors` (one law).

    Usage::

        sensors = Sensors(sensor_config("dgps"))
        sensors.reset(np.random.default_rng(7))
        for t in sensors.sample_times(t_prev, t_now):
            meas = sensors.measure(t, eta_true_at_t)

    Args:
        config: the sensor parameters (default: :func:`sensor_config` ``("default")``).
    """

    def __init__(self, config: SensorConfig | None = None) -> None:
        if config is None:
            config = SensorConfig()
        if not isinstance(config, SensorConfig):
            raise TypeError(f"config must be a SensorConfig, got {type(config).__name__}")
        self.config = config
        self._b = b = BatchedSensors(config, 1, _BLOCK)
        self._t1 = np.zeros(1)
        self._eta1 = np.zeros((1, 3))
        self._args = (b._all, self._t1, self._eta1, b._k, b._draws, b._st, b._cf, b._par, b._out)

    def reset(self, rng: np.random.Generator | int) -> None:
        """Restart the random streams from a generator (or an integer seed).

        A child seed is drawn from ``rng`` (one draw), so the same generator state gives the
        same measurements; the noise, outlier and dropout streams are spawned from it.
        """
        if isinstance(rng, int | np.integer) and not isinstance(rng, bool):
            rng = np.random.default_rng(int(rng))
        if not isinstance(rng, np.random.Generator):
            raise TypeError(
                f"rng must be a numpy.random.Generator or an int seed, got {type(rng).__name__}"
            )
        self._b.reset([rng])

    @property
    def correlated_error(self) -> NDArray[np.float64]:
        """The correlated errors of the last sample (or of the reset): DGPS ``[x, y]`` (m)
        and gyrocompass bias (rad); zeros when they are off (truth, for tests and plots)."""
        return self._b._st[0, :3].copy()

    def sample_times(self, t0: float, t1: float) -> NDArray[np.float64]:
        """Sample instants ``k * period`` in ``(t0, t1]`` (s), ascending (may be empty)."""
        p = self.config.period
        k0 = math.floor(t0 / p + _EPS_T) + 1
        k1 = math.floor(t1 / p + _EPS_T)
        return np.arange(k0, k1 + 1, dtype=float) * p if k1 >= k0 else np.empty(0)

    def measure(self, t: float, eta_true: ArrayLike) -> Measurement:
        """Sample the sensors at time ``t`` (s) for the true pose ``eta_true`` ``[x, y, psi]``.

        Returns:
            The :class:`Measurement` (``z=None`` during a dropout).

        Raises:
            RuntimeError: :meth:`reset` was not called.
            ValueError: ``eta_true`` is not 3 finite values.
        """
        eta = np.asarray(eta_true, dtype=float)
        e = eta.tolist() if eta.shape == (3,) else None
        if e is None or not all(map(math.isfinite, e)):
            raise ValueError(f"eta_true must be 3 finite values [x, y, psi], got {eta_true!r}")
        t, z, valid, outlier = self.measure_pose(t, e[0], e[1], e[2])
        return Measurement(t, None if z is None else np.array(z), valid, outlier)

    def measure_pose(
        self, t: float, x: float, y: float, psi: float
    ) -> tuple[float, tuple[float, float, float] | None, bool, bool]:
        """:meth:`measure` of the true pose ``(x, y, psi)`` (floats) in plain floats: ``(t,
        z, valid, outlier)`` with ``z`` the measured pose as three floats or ``None`` (the
        environment's per-step form: it keeps its poses as floats).

        Raises:
            RuntimeError: :meth:`reset` was not called.
            ValueError: a non-finite pose.
        """
        b = self._b
        if b._gens[0] is None:
            raise RuntimeError("Sensors.reset(rng) must be called before measure()")
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(psi)):
            raise ValueError(
                f"the true pose must be 3 finite values [x, y, psi], got {[x, y, psi]}"
            )
        t = float(t)
        self._t1[0] = t
        e = self._eta1
        e[0, 0], e[0, 1], e[0, 2] = x, y, psi
        b._call(self._args)
        z0, z1, z2, valid, outlier = b._out[0].tolist()
        if not valid:
            return t, None, False, False
        return t, (z0, z1, z2), True, outlier > 0.0


def _sigmas(config: SensorConfig) -> NDArray[np.float64]:
    """White-noise standard deviations ``[x, y, psi]`` (m, m, rad) of a configuration (the
    Gauss-Markov share of the position variance excluded)."""
    w = config.position_white_sigma
    return np.array([w, w, config.heading_sigma])
