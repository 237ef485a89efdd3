"""Dynamic positioning (DP) evaluation: metrics of a station-keeping run (Al-Takie 1982).

A high layer: it may use :mod:`shipgym.dynamics`, :mod:`shipgym.observers` and
:mod:`shipgym.controllers`, and only the command line and the bench import it. Pure
NumPy/SciPy.

- :mod:`~shipgym.dp.metrics`: :func:`dp_metrics`, :func:`dp_radius`, :func:`wave_band_ratio`.
"""

from __future__ import annotations

from .metrics import DP_RADIUS_MAX, dp_metrics, dp_radius, wave_band_ratio

__all__ = ["DP_RADIUS_MAX", "dp_metrics", "dp_radius", "wave_band_ratio"]
