"""Environmental disturbances: wind (and later waves and current), pure NumPy (SPEC section 6).

Every stochastic part draws from a generator handed in by the environment, so the same seed
gives the same run.
"""

from .wind import (
    BLENDERMANN,
    BlendermannCoefficients,
    Wind,
    WindConfig,
    WindLoad,
    blendermann,
    blendermann_coefficients,
    relative_wind,
    wind_load,
)

__all__ = [
    "BLENDERMANN",
    "BlendermannCoefficients",
    "Wind",
    "WindConfig",
    "WindLoad",
    "blendermann",
    "blendermann_coefficients",
    "relative_wind",
    "wind_load",
]
