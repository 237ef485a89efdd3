"""Environmental disturbances: wind, waves and current, pure NumPy/SciPy.

Every stochastic part draws from a generator handed in by the environment at ``reset(rng)``,
so the same seed gives the same run. Users give a wind or a current in any form of
:meth:`WindConfig.coerce` / :meth:`CurrentConfig.coerce` (``"3@300"``, ``(3, 300)``, a config
or a mapping); plain-number directions are degrees, fields are radians.
"""

from .current import MAX_CURRENT_SPEED, Current, CurrentConfig, current_body_velocity
from .spectra import (
    dnv_gamma,
    fit_shaping_filter_lambda,
    froude_factor,
    froude_scale,
    gauss_markov_psd,
    harris_wind_spectrum,
    jonswap,
    norsok_peak_period,
    npd_wind_spectrum,
    pierson_moskowitz,
    significant_wave_height,
    wave_spectrum,
    wind_gust_spectrum,
)
from .waves import WaveConfig, Waves, al_takie_hf_polynomial, drift_coefficients
from .wind import (
    BLENDERMANN,
    GUST_SPECTRA,
    MAX_WIND_SPEED,
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
    "GUST_SPECTRA",
    "MAX_CURRENT_SPEED",
    "MAX_WIND_SPEED",
    "BlendermannCoefficients",
    "Current",
    "CurrentConfig",
    "WaveConfig",
    "Waves",
    "Wind",
    "WindConfig",
    "WindLoad",
    "al_takie_hf_polynomial",
    "blendermann",
    "blendermann_coefficients",
    "current_body_velocity",
    "dnv_gamma",
    "drift_coefficients",
    "fit_shaping_filter_lambda",
    "froude_factor",
    "froude_scale",
    "gauss_markov_psd",
    "harris_wind_spectrum",
    "jonswap",
    "norsok_peak_period",
    "npd_wind_spectrum",
    "pierson_moskowitz",
    "relative_wind",
    "significant_wave_height",
    "wave_spectrum",
    "wind_gust_spectrum",
    "wind_load",
]
