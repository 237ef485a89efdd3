r"""Ocean / lake current: constant or slowly varying (Gauss-Markov) speed and direction.

``u_c = V_c cos(beta_c - psi)``, ``v_c = V_c sin(beta_c - psi)`` (Fossen 2011 ch. 8.3);
``V_c_dot = -mu (V_c - speed) + w`` sampled exactly.

Sources: Fossen (2011) ch. 8.3; DNV-RP-C205 (2010) for the wind-driven current; the
defaults are the project's assumptions. Full entries: ``docs/references.md``.

Public names: ``CurrentConfig``, ``Current``, ``current_body_velocity``, ``MAX_CURRENT_SPEED``.

Design notes: docs/design/disturbances.current.md.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import from_mapping, is_real, param, require_angles, require_finite

from ._boundary import coerce_config, parse_config
from ._grid import CHUNK, GridPair, gauss_markov_piece

__all__ = ["CurrentConfig", "Current", "current_body_velocity", "MAX_CURRENT_SPEED"]

#: Largest accepted mean current speed (m/s). Basis: the fastest tidal currents known are
#: about 20 kn (~10 m/s) in narrow straits such as Saltstraumen (Norway); the strongest ocean
#: currents (the Gulf Stream) stay below about 2.5 m/s, and a 1:24 model sees about a fifth of
#: the full-scale speed. A larger number is a unit mistake or a typo, so it is refused.
MAX_CURRENT_SPEED = 10.0

_N3 = "a modelling assumption"


def current_body_velocity(V_c: float, beta_c: float, psi: float) -> tuple[float, float]:
    """Current velocity on the body axes (Fossen 2011 ch. 8.3).

    Args:
        V_c: Current speed (m/s).
        beta_c: Direction the current goes to (rad, clockwise from north).
        psi: Heading (rad).

    Returns:
        ``(u_c, v_c)`` in m/s (surge, sway); ``nu_r = nu - [u_c, v_c, 0]``.
    """
    a = beta_c - psi
    return V_c * math.cos(a), V_c * math.sin(a)


@dataclass(frozen=True)
class CurrentConfig:
    """Mean current plus optional Gauss-Markov variation (SI units, radians).

    At the public boundary directions are degrees: :meth:`parse` (``"0.1@90"``: 0.1 m/s going
    to 90 deg, i.e. east), :meth:`from_speed_dir` and :meth:`coerce` (the one conversion every
    entry point uses).

    Attributes:
        speed: Mean current speed (m/s, 0 to :data:`MAX_CURRENT_SPEED`). Lake/harbour: 0
            nominal or ~0.01 U_wind;
            offshore DP 0.5-1 m/s full scale = 0.10-0.20 m/s at 1:24 (assumption).
        direction_to: Mean direction the current goes TO (rad, clockwise from north).
        mu: Mean-reversion rate of the speed (1/s, >= 0); assumed 1/300.
        sigma: Intensity of the white noise driving the speed (m/s^1.5, >= 0); 0 = constant.
        v_min: Lower saturation of the speed (m/s, >= 0).
        v_max: Upper saturation of the speed (m/s) or ``None`` (no upper bound).
        direction_mu: Mean-reversion rate of the direction (1/s, >= 0; 0 = random walk).
        direction_sigma: Intensity of the noise on the direction (rad/s^0.5, >= 0).
        sample_period: Grid of the samples (s); linear interpolation in between.
    """

    speed: float = param(0.0, "m/s", "assumption: lake nominal 0")
    direction_to: float = param(0.0, "rad", "oceanographic, clockwise from north")
    mu: float = param(1.0 / 300.0, "1/s", _N3)
    sigma: float = param(0.0, "m/s^1.5", _N3 + ": 0 = constant current")
    v_min: float = param(0.0, "m/s", "saturation")
    v_max: float | None = param(None, "m/s", "saturation (None: unbounded)")
    direction_mu: float = param(1.0 / 300.0, "1/s", _N3)
    direction_sigma: float = param(0.0, "rad/s^0.5", _N3 + ": 0 = constant direction")
    sample_period: float = param(1.0, "s", "slowly varying: 1 s grid [assumption]")

    def __post_init__(self) -> None:
        name = type(self).__name__
        for key in (
            "speed",
            "direction_to",
            "mu",
            "sigma",
            "v_min",
            "direction_mu",
            "direction_sigma",
            "sample_period",
        ):
            val = getattr(self, key)
            if not is_real(val):
                raise ValueError(f"{name}.{key} must be a real number, got {val!r}")
        if self.v_max is not None and not is_real(self.v_max):
            raise ValueError(f"{name}.v_max must be a real number or None, got {self.v_max!r}")
        require_finite(self)
        require_angles(self, "direction_to")
        for key in ("speed", "mu", "sigma", "v_min", "direction_mu", "direction_sigma"):
            if getattr(self, key) < 0:
                raise ValueError(f"{name}.{key} must be >= 0, got {getattr(self, key)!r}")
        if not self.sample_period > 0:
            raise ValueError(f"{name}.sample_period must be > 0 s, got {self.sample_period!r}")
        if self.speed > MAX_CURRENT_SPEED:
            raise ValueError(
                f"{name}.speed must be <= {MAX_CURRENT_SPEED:g} m/s (about the fastest tidal "
                f"currents), got {self.speed!r}"
            )
        hi = math.inf if self.v_max is None else self.v_max
        if not self.v_min <= self.speed <= hi:
            raise ValueError(
                f"{name}: the mean speed {self.speed!r} m/s must lie in [v_min, v_max] = "
                f"[{self.v_min!r}, {self.v_max!r}]"
            )

    @property
    def is_constant(self) -> bool:
        """True when speed and direction never change (both noise intensities 0)."""
        return self.sigma == 0.0 and self.direction_sigma == 0.0

    @property
    def speed_std(self) -> float:
        """Stationary std of the speed before saturation, ``sigma / sqrt(2 mu)`` (m/s)."""
        if self.sigma == 0.0:
            return 0.0
        return math.inf if self.mu == 0.0 else self.sigma / math.sqrt(2.0 * self.mu)

    @property
    def direction_std(self) -> float:
        """Stationary std of the direction, ``direction_sigma / sqrt(2 direction_mu)`` (rad)."""
        if self.direction_sigma == 0.0:
            return 0.0
        if self.direction_mu == 0.0:
            return math.inf
        return self.direction_sigma / math.sqrt(2.0 * self.direction_mu)

    @classmethod
    def from_std(
        cls,
        speed: float,
        direction_to: float,
        std: float = 0.0,
        time_constant: float = 300.0,
        *,
        direction_std: float = 0.0,
        direction_time_constant: float = 300.0,
        **kw: Any,
    ) -> CurrentConfig:
        """Build from stationary standard deviations and time constants (``mu = 1/T``).

        Args:
            speed: Mean speed (m/s).
            direction_to: Mean direction the current goes to (rad).
            std: Stationary speed std (m/s), e.g. 0.01 (the assumed lake default).
            time_constant: ``1 / mu`` of the speed (s), e.g. 300.
            direction_std: Stationary direction std (rad).
            direction_time_constant: ``1 / direction_mu`` (s).
            **kw: Other fields (``v_min``, ``v_max``, ``sample_period``).

        Returns:
            The config with ``sigma = std sqrt(2 / T)``.
        """
        for key, val in (
            ("time_constant", time_constant),
            ("direction_time_constant", direction_time_constant),
        ):
            if not (isinstance(val, numbers.Real) and val > 0 and math.isfinite(val)):
                raise ValueError(f"CurrentConfig.from_std: {key} must be > 0 s, got {val!r}")
        return cls(
            speed=speed,
            direction_to=direction_to,
            mu=1.0 / time_constant,
            sigma=std * math.sqrt(2.0 / time_constant),
            direction_mu=1.0 / direction_time_constant,
            direction_sigma=direction_std * math.sqrt(2.0 / direction_time_constant),
            **kw,
        )

    @classmethod
    def from_dict(cls, mapping: Mapping[str, Any]) -> CurrentConfig:
        """Build from a mapping of field names (SI units, radians); unknown keys raise."""
        return from_mapping(cls, mapping, where="current config")

    @classmethod
    def from_speed_dir(cls, speed: float, to_deg: float, **kw: Any) -> CurrentConfig:
        """A constant current from a speed (m/s) and the direction it goes TO (deg).

        Args:
            speed: Mean speed (m/s).
            to_deg: Direction the water goes to (deg, clockwise from north), e.g. 90 = east.
            **kw: Any other :class:`CurrentConfig` field (SI units, radians).
        """
        return cls(speed=speed, direction_to=math.radians(to_deg), **kw)

    @classmethod
    def parse(cls, text: str, *, name: str = "current") -> CurrentConfig:
        """Parse ``"SPEED@TO_DEG"``: speed in m/s, direction the water goes TO in degrees.

        ``"0.1@90"`` is a constant 0.1 m/s current setting to the east.

        Raises:
            ValueError: Malformed text, or a value :class:`CurrentConfig` refuses (the message
                names ``name`` and the field).
        """
        return parse_config(
            text, from_deg=cls.from_speed_dir, name=name, form="SPEED@TO_DEG",
            example="0.1@90 (0.1 m/s going to 90 deg)",
        )  # fmt: skip

    @classmethod
    def coerce(cls, value: Any, *, name: str = "current") -> CurrentConfig | None:
        """The one conversion of a user's current setting, used by every public entry point.

        Accepted: ``None`` (no current), a :class:`CurrentConfig`, ``"SPEED@TO_DEG"``
        (:meth:`parse`), ``(speed m/s, to deg)`` (:meth:`from_speed_dir`) or a mapping of
        :class:`CurrentConfig` fields (SI units, radians; ``direction_to_deg`` is accepted as
        the degree twin).

        Raises:
            ValueError: Any other form or an invalid value; the message names ``name`` and
                the accepted forms.
        """
        return coerce_config(
            cls,
            value,
            name=name,
            parse=lambda text: cls.parse(text, name=name),
            from_deg=cls.from_speed_dir,
            deg_fields={"direction_to_deg": "direction_to"},
            accepted=(
                "None, a CurrentConfig, 'SPEED@TO_DEG' (e.g. '0.1@90': 0.1 m/s going to 90 "
                "deg), (speed m/s, to deg) or a mapping of CurrentConfig fields"
            ),
        )

    def label(self) -> str:
        """Short human-readable form, e.g. ``"0.1 m/s to 90 deg"``."""
        deg = math.degrees(float(self.direction_to)) % 360.0
        return f"{float(self.speed):g} m/s to {deg:.4g} deg"


class Current(GridPair):
    """Runtime current: ``at(t) -> (V_c, beta_c)`` from a lazily generated sample grid.

    Args:
        config: Current parameters (default: no current).

    Example:
        >>> c = Current(CurrentConfig.from_std(0.05, 1.0, std=0.01))
        >>> c.reset(np.random.default_rng(1))
        >>> V_c, beta_c = c.at(12.3)
        >>> u_c, v_c = c.body_velocity(12.3, psi=0.2)
    """

    def __init__(self, config: CurrentConfig | None = None) -> None:
        self.config = cfg = CurrentConfig() if config is None else config
        self._dt = float(cfg.sample_period)
        self._inv_dt = 1.0 / self._dt
        self._mean = (float(cfg.speed), float(cfg.direction_to))
        self._const: tuple[float, float] | None = self._mean if cfg.is_constant else None
        mus = (float(cfg.mu), float(cfg.direction_mu))
        sigs = (float(cfg.sigma), float(cfg.direction_sigma))
        self._a = tuple(math.exp(-m * self._dt) for m in mus)
        self._b = tuple(
            s
            * (
                math.sqrt(-math.expm1(-2.0 * m * self._dt) / (2.0 * m))
                if m > 0
                else math.sqrt(self._dt)
            )
            for s, m in zip(sigs, mus, strict=True)
        )
        self._std0 = tuple(
            s / math.sqrt(2.0 * m) if m > 0 else 0.0 for s, m in zip(sigs, mus, strict=True)
        )
        self._lo = float(cfg.v_min)
        self._hi = math.inf if cfg.v_max is None else float(cfg.v_max)
        self._rng: np.random.Generator | None = None
        self._clear()

    def _clear(self) -> None:
        super()._clear()
        self._state = self._mean

    @property
    def is_constant(self) -> bool:
        """True when the current never changes (no generator needed)."""
        return self._const is not None

    def reset(self, rng: np.random.Generator | int | None = None) -> None:
        """Start a new realisation from a child of ``rng`` (one ``integers(2**63)`` draw).

        Args:
            rng: Parent generator or seed; ``None`` only for a constant current.

        Raises:
            ValueError: ``rng`` is ``None`` for a varying current.
        """
        self._draws(self._start(rng, "a varying current"))

    def _draws(self, child: np.random.Generator | None) -> None:
        """The states' start from the reset's child generator."""
        if child is not None and self._const is None:
            z = child.standard_normal(2)
            v = min(max(self._mean[0] + self._std0[0] * float(z[0]), self._lo), self._hi)
            self._state = (v, self._mean[1] + self._std0[1] * float(z[1]))

    def _ready_check(self) -> None:
        if self._rng is None:
            raise RuntimeError("call Current.reset(rng) before querying a varying current")

    def _begin(self, j: int) -> NDArray[np.float64]:
        """Chunk ``j`` begun from the states at its start: its normals
        ``standard_normal((2, CHUNK))``, the last row as far as read
        (:meth:`~shipgym.disturbances._grid.PieceGrid._normals`)."""
        assert self._rng is not None
        (av, ab), (bv, bb) = self._a, self._b
        mv, mb = self._mean
        m, a, b = np.array([mv, mb]), np.array([av, ab]), np.array([bv, bb])
        lows, highs = np.array([self._lo, -math.inf]), np.array([self._hi, math.inf])
        self._gm = (np.array(self._state), m, a, b, lows, highs)
        self._e = self._normals(self._rng, (2, CHUNK), out=self._spent)  # the last chunk's
        self._spent = self._e
        return np.empty((2, CHUNK + 1))

    def _piece(self, j: int, ka: int, kb: int) -> None:
        """Samples ``ka ... kb - 1`` of chunk ``j``: speed clipped to ``[v_min, v_max]``,
        direction free (:func:`~shipgym.disturbances._grid.gauss_markov_piece`)."""
        x, m, a, b, lows, highs = self._gm
        self._draw_to(self._e, kb)
        gauss_markov_piece(x, m, a, b, lows, highs, False, self._e, ka, kb, self._chunk(j))
        if kb == CHUNK + 1:
            self._state = (float(x[0]), float(x[1]))

    def at(self, t: float) -> tuple[float, float]:
        """Current at time ``t`` (cheap; call it every physics step).

        Args:
            t: Time (s), ``>= 0``.

        Returns:
            ``(V_c, beta_c)``: speed (m/s) and direction it goes to (rad, continuous).
        """
        if self._const is not None:
            return self._const
        return self._interp(t)

    def body_velocity(self, t: float, psi: float) -> tuple[float, float]:
        """Body-frame current velocity ``(u_c, v_c)`` (m/s) at time ``t`` and heading ``psi``."""
        V, b = self.at(t)
        return current_body_velocity(V, b, psi)

    def velocity_ned(self, t: float) -> tuple[float, float]:
        """NED current velocity ``(V_c cos beta_c, V_c sin beta_c)`` (m/s, north, east)."""
        V, b = self.at(t)
        return V * math.cos(b), V * math.sin(b)

    def series(self, t: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`at` for arrays (same values): ``(V_c, beta_c)`` of the shape of ``t``."""
        tt = np.asarray(t, dtype=float)
        if self._const is not None:
            return np.full(tt.shape, self._const[0]), np.full(tt.shape, self._const[1])
        return self._interp_series(tt)

    def __repr__(self) -> str:
        return f"Current(config={self.config!r})"
