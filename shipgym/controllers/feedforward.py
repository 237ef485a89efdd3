r"""Environmental feedforward of a DP controller: the wind load from the measured wind and the
vessel's windage model, the current load from the known mean current and the hull model.

Al-Takie (1982) 2.4 (Fig. 1.1) assumes that "wind feedforward control is used to counteract
the effect of steady wind", so that the positioning loop (the wave filter and the LQ law,
which has no integral action) sees only the wind's fluctuation; the current, "constant over
hours", enters through the point the LF model is linearised at (3.1), i.e. its steady load
is known to the designer. Both are feedforward terms here, as in a DP system's control law
``tau = tau_feedback + tau_ff`` (Fossen 2011 ch. 13.1, 12.2.5: wind feedforward):

- **wind**: the anemometer's true wind (speed and the direction it comes from, NED), low-pass
  filtered (first order, time constant ``wind_time_constant``, on the NED wind vector so that
  the direction never jumps), gives the Blendermann (1994) load of the vessel's windage model
  (:class:`~shipgym.disturbances.wind.WindLoad`) at the estimated heading and velocity;
- **current**: the mean current (the environment's configured speed and direction: the
  slow Gauss-Markov variation about it is not known) gives the hull's load on a ship at rest
  in it, ``M nu_dot(nu = 0, tau = 0, nu_c)`` of the vessel's design plant (damping and Munk
  moment at the relative velocity ``-nu_c``), at the estimated heading;
- **drift** (optional, off by default: the thesis leaves the drift to the LF model): the mean
  second-order wave drift of the sea state (:meth:`~shipgym.disturbances.waves.Waves.
  mean_drift_load`, the vessel's drift coefficients and the spectrum, as a wave radar's sea
  state would give it) at the estimated heading; its slowly varying part is left to the
  feedback.

``tau_ff = -(wind load + current load [+ mean drift load])`` (N, N, N m, body frame). The
observer of a model-based stack is fed ``thrust - tau_ff`` (the thrust plus the loads the
feedforward estimates), so that its model sees the loads as known inputs.

Public names: ``FEEDFORWARD_PRESETS``, ``BatchedFeedforward``, ``FeedforwardConfig``,
``current_load``.
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

from shipgym._text import did_you_mean

__all__ = ["FEEDFORWARD_PRESETS", "BatchedFeedforward", "FeedforwardConfig", "current_load"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class FeedforwardConfig:
    """Which environmental loads a DP controller feeds forward.

    Attributes:
        wind: feed forward the wind load of the filtered anemometer wind.
        current: feed forward the hull's load in the mean current.
        drift: feed forward the mean second-order wave drift load.
        wind_time_constant: the anemometer filter's time constant (s, full scale, > 0;
            Froude-scaled for a model) [chosen: 3 s, from a scan of 1, 3 and 10 s with the
            14-state filter and the printed LQ, both thesis vessels, Beaufort 5 and 8, seeds
            0-2 (the docs' Al-Takie (1982) page): 1 s and 3 s hold within 0.07 m of each
            other, 10 s lets the gusts through (Star Hercules, Beaufort 8: 1.27 m RMS, NIS
            6.1, against 1.10 m, 5.5 at 3 s)]: the gusts' load is fed forward, the
            anemometer's turbulence above about 0.05 Hz is not. The anemometer is noise-free
            (the wind is uniform over the ship).
    """

    wind: bool = True
    current: bool = True
    drift: bool = False
    wind_time_constant: float = 3.0

    def __post_init__(self) -> None:
        for name in ("wind", "current", "drift"):
            x = getattr(self, name)
            if not isinstance(x, bool):
                raise ValueError(f"FeedforwardConfig.{name} must be a bool, got {x!r}")
        T = self.wind_time_constant
        real = isinstance(T, int | float) and not isinstance(T, bool)
        if not (real and math.isfinite(T) and T > 0):
            raise ValueError(f"wind_time_constant must be a finite time > 0 s, got {T!r}")

    @property
    def active(self) -> bool:
        """Whether anything is fed forward."""
        return self.wind or self.current or self.drift

    @property
    def label(self) -> str:
        """The loads fed forward joined by ``+`` (``"wind+current"``, ...), or ``"none"``."""
        parts = [k for k in ("wind", "current", "drift") if getattr(self, k)]
        return "+".join(parts) or "none"

    @classmethod
    def coerce(cls, value: Any) -> FeedforwardConfig:
        """A config from a preset name (:data:`FEEDFORWARD_PRESETS`), a bool (``True``: both
        loads, ``False``: none), a mapping of the fields, or a config.

        Raises:
            ValueError: an unknown name or key, or a bad value.
        """
        if isinstance(value, FeedforwardConfig):
            return value
        if isinstance(value, bool):
            return FEEDFORWARD_PRESETS["wind+current" if value else "none"]
        if isinstance(value, str):
            try:
                return FEEDFORWARD_PRESETS[value]
            except KeyError:
                raise ValueError(
                    f"unknown feedforward {value!r}{did_you_mean(value, FEEDFORWARD_PRESETS)}; "
                    f"choose from {', '.join(FEEDFORWARD_PRESETS)}, a bool or a mapping of "
                    f"{', '.join(f.name for f in dataclasses.fields(cls))}"
                ) from None
        if isinstance(value, Mapping):
            names = {f.name for f in dataclasses.fields(cls)}
            unknown = sorted(set(value) - names)
            if unknown:
                raise ValueError(f"unknown feedforward keys {unknown}; valid: {sorted(names)}")
            return cls(**value)
        raise ValueError(
            f"feedforward must be a name ({', '.join(FEEDFORWARD_PRESETS)}), a bool, a mapping "
            f"or a FeedforwardConfig, got {value!r}"
        )


#: the named feedforward settings
FEEDFORWARD_PRESETS: Mapping[str, FeedforwardConfig] = MappingProxyType(
    {
        "wind+current": FeedforwardConfig(),
        "wind+current+drift": FeedforwardConfig(drift=True),
        "wind": FeedforwardConfig(current=False),
        "current": FeedforwardConfig(wind=False),
        "none": FeedforwardConfig(wind=False, current=False),
    }
)


def current_load(plant: Any, nu_c: ArrayLike) -> Array:
    """The hull's load (N, N, N m) on a ship at rest in the body-frame current ``nu_c``
    ``(..., 3)`` (``[u_c, v_c, 0]``, m/s): ``M nu_dot(0, 0, nu_c)`` of ``plant`` (its damping
    and Munk moment at ``nu_r = -nu_c``, Fossen 2011 eq. 10.1).

    Raises:
        ValueError: a plant without ``mass_matrix()`` and ``nu_dot(nu, tau, nu_c)``.
    """
    if not (hasattr(plant, "mass_matrix") and hasattr(plant, "nu_dot")):
        raise ValueError(
            f"current feedforward needs a 3-DOF plant with mass_matrix() and nu_dot(nu, tau, "
            f"nu_c), not {type(plant).__name__}: pass feedforward='wind'"
        )
    c = np.asarray(nu_c, dtype=float)
    acc = plant.nu_dot(np.zeros_like(c), np.zeros_like(c), c)
    return np.asarray(acc @ np.asarray(plant.mass_matrix(), dtype=float).T, dtype=float)


class BatchedFeedforward:
    """The feedforward of ``n`` envs of one vessel (:class:`FeedforwardConfig`).

    Args:
        vessel: the :class:`~shipgym.dynamics.vessel.Vessel` (its ``windage``; its design
            plant ``vessel.plant()`` for the current load).
        config: what to feed forward.
        n: number of envs, >= 1.
        dt: the control period (s), > 0: the anemometer filter's step.
    """

    def __init__(self, vessel: Any, config: FeedforwardConfig, n: int, dt: float) -> None:
        self.config = config
        self.n = int(n)
        self.dt = float(dt)
        from shipgym.disturbances.wind import WindLoad

        self._load = None
        if config.wind:
            if getattr(vessel, "windage", None) is None:
                raise ValueError(
                    f"wind feedforward needs the vessel's windage model; {vessel.name!r} has "
                    "none: pass feedforward='current' or 'none'"
                )
            self._load = WindLoad(None, vessel.windage)
        self._plant = vessel.plant() if config.current else None
        if self._plant is not None:
            current_load(self._plant, np.zeros(3))  # refused now, not at the first step
        # the filter's time constant is full scale: Froude-scaled for a model
        T = config.wind_time_constant / math.sqrt(float(getattr(vessel, "scale", 1.0)))
        self._a = math.exp(-self.dt / T)
        self._w = np.zeros((self.n, 2))  # the filtered NED wind vector (m/s, from-direction)
        self._started = np.zeros(self.n, dtype=bool)

    def reset(self, mask: ArrayLike | None = None) -> None:
        """Forget the filtered wind of the envs in ``mask`` (``None``: all): the next
        measurement starts the filter."""
        m = np.ones(self.n, bool) if mask is None else np.asarray(mask, dtype=bool)
        self._started[m] = False

    def __call__(
        self,
        eta: ArrayLike,
        nu: ArrayLike,
        wind: ArrayLike | None = None,
        current: ArrayLike | None = None,
        drift: ArrayLike | None = None,
    ) -> Array:
        """``tau_ff`` (n, 3) (N, N, N m, body frame): minus the estimated wind and current
        loads.

        Args:
            eta, nu: the navigation pose (NED, m, m, rad) and body velocity (m/s, rad/s),
                (n, 3) each.
            wind: the anemometer's true wind ``[V_w (m/s), beta_w (rad, from)]``, (n, 2);
                filtered here, one sample per call (every control period).
            current: the mean current ``[V_c (m/s), beta_c (rad, going to)]``, (n, 2).
            drift: the mean drift load at the estimated heading (N, N, N m, body), (n, 3).
        """
        e = np.asarray(eta, dtype=float)
        v = np.asarray(nu, dtype=float)
        psi = e[:, 2]
        tau = np.zeros((self.n, 3))
        if self._load is not None:
            if wind is None:
                raise ValueError("wind feedforward needs the measured wind, (n, 2)")
            w = np.asarray(wind, dtype=float)
            vec = np.stack([w[:, 0] * np.cos(w[:, 1]), w[:, 0] * np.sin(w[:, 1])], axis=1)
            new = ~self._started
            self._w = np.where(new[:, None], vec, self._a * self._w + (1.0 - self._a) * vec)
            self._started[:] = True
            V = np.hypot(self._w[:, 0], self._w[:, 1])
            beta = np.arctan2(self._w[:, 1], self._w[:, 0])
            tau += self._load.array(psi, v[:, 0], v[:, 1], V, beta)
        if self._plant is not None:
            if current is None:
                raise ValueError("current feedforward needs the mean current, (n, 2)")
            c = np.asarray(current, dtype=float)
            a = c[:, 1] - psi
            nu_c = np.stack([c[:, 0] * np.cos(a), c[:, 0] * np.sin(a), np.zeros(self.n)], axis=1)
            tau += current_load(self._plant, nu_c)
        if self.config.drift:
            if drift is None:
                raise ValueError("drift feedforward needs the mean drift load, (n, 3)")
            tau += np.asarray(drift, dtype=float)
        return -tau

    @property
    def filtered_wind(self) -> Array:
        """The filtered wind ``[V_w, beta_w]`` (m/s, rad from) of every env, (n, 2)."""
        return np.stack([np.hypot(self._w[:, 0], self._w[:, 1]),
                         np.arctan2(self._w[:, 1], self._w[:, 0])], axis=1)  # fmt: skip
