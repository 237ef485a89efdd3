r"""Wave roll and yaw moments in beam and quartering seas (long-wave Froude-Krylov).

Public names: ``RollWaveConfig``, ``RollWaves``.
Sources: Perez (2005); Fossen (2011).

Design notes: docs/design/disturbances.rollwaves.md.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import from_mapping, is_real, param
from shipgym._jit import njit
from shipgym._seeding import child_seeds

from .spectra import harmonic_components, wave_spectrum

__all__ = ["RollWaveConfig", "RollWaves", "roll_wave_moments"]

_G = 9.81


@dataclass(frozen=True)
class RollWaveConfig:
    """A long-crested sea for the wave roll moment (SI units, radians).

    Attributes:
        Hs: significant wave height (m, >= 0).
        Tp: peak period (s, > 0).
        spectrum: ``"jonswap"`` or ``"pm"`` (Pierson-Moskowitz).
        gamma: JONSWAP peak enhancement (1 to 10; ignored for ``"pm"``).
        chi: encounter angle (rad): 0 following, pi/2 beam, pi head sea.
        n_components: number of harmonic components (>= 1).
        omega_min: lowest wave frequency (rad/s, > 0).
        omega_max: highest wave frequency (rad/s, > omega_min).
        U: forward speed for the encounter frequency (m/s, >= 0).
    """

    Hs: float = param(2.0, "m", "chosen: sea state 4 (moderate), a roll-damping case")
    Tp: float = param(8.0, "s", "chosen: a 8 s peak period (wave length 100 m, 2 L)")
    spectrum: str = param("jonswap", "-", "Hasselmann et al. (1973) / DNV-RP-C205")
    gamma: float = param(3.3, "1", "JONSWAP mean peak factor (Hasselmann et al. 1973)")
    chi: float = param(math.pi / 2, "rad", "chosen: beam sea")
    n_components: int = param(200, "1", "chosen: 200 components (no repeat within hours)")
    omega_min: float = param(0.15, "rad/s", "chosen: below the spectrum's energy")
    omega_max: float = param(3.0, "rad/s", "chosen: above the 1.1 rad/s roll mode")
    U: float = param(0.0, "m/s", "chosen: at rest")

    def __post_init__(self) -> None:
        name = type(self).__name__
        for key in ("Hs", "Tp", "gamma", "chi", "omega_min", "omega_max", "U"):
            val = getattr(self, key)
            if not is_real(val) or not math.isfinite(val):
                raise ValueError(f"{name}.{key} must be a finite real number, got {val!r}")
        if self.spectrum not in ("jonswap", "pm"):
            raise ValueError(f"{name}.spectrum must be 'jonswap' or 'pm', got {self.spectrum!r}")
        if self.Hs < 0:
            raise ValueError(f"{name}.Hs must be >= 0 m, got {self.Hs!r}")
        if not self.Tp > 0:
            raise ValueError(f"{name}.Tp must be > 0 s, got {self.Tp!r}")
        if not 1.0 <= self.gamma <= 10.0:
            raise ValueError(f"{name}.gamma must lie in [1, 10], got {self.gamma!r}")
        n = self.n_components
        if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1:
            raise ValueError(f"{name}.n_components must be an integer >= 1, got {n!r}")
        if not 0 < self.omega_min < self.omega_max:
            raise ValueError(
                f"{name}: need 0 < omega_min < omega_max (rad/s), got "
                f"{self.omega_min!r}, {self.omega_max!r}"
            )
        if self.U < 0:
            raise ValueError(f"{name}.U must be >= 0 m/s (forward speed), got {self.U!r}")

    @classmethod
    def from_dict(cls, mapping: Mapping[str, Any]) -> RollWaveConfig:
        """Build from a mapping of field names (SI units, radians); unknown keys raise."""
        return from_mapping(cls, mapping, where="roll wave config")

    @classmethod
    def coerce(cls, value: Any, *, name: str = "roll_waves") -> RollWaveConfig | None:
        """``None``, a :class:`RollWaveConfig` or a mapping of its fields (``chi_deg`` in deg
        is accepted for ``chi``).

        Raises:
            ValueError: any other form or an invalid value (the message names ``name``).
        """
        if value is None or isinstance(value, cls):
            return value
        if not isinstance(value, Mapping):
            raise ValueError(
                f"{name} must be None, a RollWaveConfig or a mapping of its fields; got {value!r}"
            )
        d = dict(value)
        try:
            if "chi_deg" in d:
                if "chi" in d:
                    raise ValueError("give 'chi' (rad) or 'chi_deg' (deg), not both")
                deg = d.pop("chi_deg")
                if not is_real(deg):
                    raise ValueError(f"chi_deg must be a number of degrees, got {deg!r}")
                d["chi"] = math.radians(deg)
            return cls.from_dict(d)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{name} {value!r}: {exc}") from None


@njit
def roll_wave_moments(t, rows, we, eps, cK, cN, K, N):  # type: ignore[no-untyped-def]
    """The roll and yaw moments (N m) at the times ``t`` (M,), time ``j`` of the sea in row
    ``rows[j]`` of the components ``we``, ``eps``, ``cK``, ``cN`` (R, n): ``K = sum cK_i
    sin(w_e,i t + eps_i)``, ``N = sum cN_i cos(w_e,i t + eps_i)``, summed in component order
    into ``K``, ``N`` (M,). One row's sum does not depend on the others (a batch of seas)."""
    for j in range(t.shape[0]):
        r = rows[j]
        k_ = 0.0
        n_ = 0.0
        for c in range(we.shape[1]):
            ph = we[r, c] * t[j] + eps[r, c]
            k_ += math.sin(ph) * cK[r, c]
            n_ += math.cos(ph) * cN[r, c]
        K[j] = k_
        N[j] = n_


class RollWaves:
    """Wave roll and yaw moments on a hull: ``moment(t) -> (K, N)`` (N m).

    Args:
        config: the sea (:class:`RollWaveConfig`).
        restoring: the hull's linear roll restoring ``K_phi = rho g nabla GM`` (N m/rad, > 0).
        length: the hull's length (m, > 0) for the yaw moment.
        nabla: displaced volume (m^3, > 0) for the yaw moment.
        rho: water density (kg/m^3, > 0).
        g: gravity (m/s^2).

    Example:
        >>> w = RollWaves(RollWaveConfig(Hs=2.0, Tp=8.0), 3.9e6, length=51.5, nabla=357.0,
        ...               rho=1014.0)
        >>> w.reset(np.random.default_rng(0))
        >>> K, N = w.moment(np.arange(0.0, 10.0, 0.1))
    """

    def __init__(
        self,
        config: RollWaveConfig,
        restoring: float,
        *,
        length: float,
        nabla: float,
        rho: float,
        g: float = _G,
    ) -> None:
        if not isinstance(config, RollWaveConfig):
            raise TypeError(f"config must be a RollWaveConfig, got {config!r}")
        for nm, v in (("restoring", restoring), ("length", length), ("nabla", nabla),
                      ("rho", rho), ("g", g)):  # fmt: skip
            if not is_real(v) or not math.isfinite(v) or not v > 0:
                raise ValueError(f"{nm} must be a finite number > 0, got {v!r}")
        self.config = config
        self.restoring = float(restoring)
        self.length = float(length)
        self.nabla = float(nabla)
        self.rho = float(rho)
        self.g = float(g)
        self._w: NDArray[np.float64] | None = None

    def spectrum(self, w: ArrayLike) -> NDArray[np.float64]:
        """The wave spectrum ``S(w)`` (m^2 s/rad) of the configuration."""
        c = self.config
        return wave_spectrum(c.spectrum, w, c.Hs, c.Tp, c.gamma)

    def reset(self, rng: np.random.Generator | int) -> None:
        """Draw the components' frequencies and phases (same generator/seed, same sea).

        Args:
            rng: a numpy Generator or a seed; one child generator is taken from it.
        """
        if not isinstance(rng, np.random.Generator):
            if isinstance(rng, bool) or not isinstance(rng, numbers.Integral):
                raise ValueError(f"rng must be a numpy Generator or an integer seed, got {rng!r}")
            rng = np.random.default_rng(rng)
        child = np.random.default_rng(child_seeds(rng))
        c = self.config
        w, a, eps = harmonic_components(self.spectrum, c.omega_min, c.omega_max,
                                        c.n_components, child)  # fmt: skip
        k = w * w / self.g
        self._w, self._a, self._eps, self._k = w, a, eps, k
        self._we = w - k * c.U * math.cos(c.chi)
        kappa = k * math.cos(c.chi)
        half = 0.5 * self.length
        small = np.abs(kappa * half) < 1e-3
        ks = np.where(small, 1.0, kappa)
        G = np.where(
            small,
            kappa * self.length**3 / 12.0,
            2.0 * (np.sin(ks * half) - ks * half * np.cos(ks * half)) / (ks * ks),
        )
        s = math.sin(c.chi)
        self._cK = self.restoring * s * k * a
        self._cN = -self.rho * self.g * (self.nabla / self.length) * s * k * a * G

    def _need(self) -> None:
        if self._w is None:
            raise RuntimeError("RollWaves.reset(rng) must be called before use")

    @property
    def components(self) -> tuple[NDArray[np.float64], ...]:
        """``(w, a, eps, w_e)``: frequencies (rad/s), amplitudes (m), phases, encounter freqs."""
        self._need()
        return self._w, self._a, self._eps, self._we  # type: ignore[return-value]

    def _phase(self, t: ArrayLike) -> NDArray[np.float64]:
        tt = np.asarray(t, dtype=float)
        return np.multiply.outer(tt, self._we) + self._eps

    def elevation(self, t: ArrayLike) -> NDArray[np.float64]:
        """Wave elevation at the hull's origin (m), ``sum a_i sin(w_e,i t + eps_i)``."""
        self._need()
        return np.sin(self._phase(t)) @ self._a

    def slope(self, t: ArrayLike) -> NDArray[np.float64]:
        """The effective wave slope ``alpha_eff(t)`` (rad), shape of ``t``."""
        self._need()
        return math.sin(self.config.chi) * (np.sin(self._phase(t)) @ (self._k * self._a))

    @property
    def moment_constants(self) -> tuple[NDArray[np.float64], ...]:
        """``(w_e, eps, c_K, c_N)`` (n,) each: a row of :func:`roll_wave_moments`."""
        self._need()
        return self._we, self._eps, self._cK, self._cN  # type: ignore[return-value]

    def moment(self, t: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Roll and yaw moments ``(K, N)`` (N m) at the times ``t`` (s), each of ``t``'s shape
        (:func:`roll_wave_moments`)."""
        tt = np.asarray(t, dtype=float)
        flat = np.ascontiguousarray(tt.reshape(-1))
        K, N = np.empty_like(flat), np.empty_like(flat)
        rows = np.zeros(flat.size, dtype=np.int64)
        roll_wave_moments(flat, rows, *(c[None] for c in self.moment_constants), K, N)
        return K.reshape(tt.shape), N.reshape(tt.shape)
