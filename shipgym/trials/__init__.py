"""Sea trials: the IMO manoeuvres as scripts, their metrics and IMO pass/fail, and the
receiver-bias study of Artyszuk (2003).

- :mod:`~shipgym.trials.manoeuvres`: :data:`MANOEUVRES`, ``manoeuvre(name)``; each has
  ``duration(L, U0)`` and ``law()``; :class:`~shipgym.trials.manoeuvres.Scripts` commands N
  of them at once (``command(psi) -> (rudder rad, shaft / n0)``, each (N,));
- :mod:`~shipgym.trials.metrics`: :func:`trial_metrics`, :func:`imo_criteria`
  (IMO MSC.137(76) (2002));
- :mod:`~shipgym.trials.bias`: :func:`receiver_bias`, the DGPS receiver's velocity bias and
  noise on a trial (Artyszuk 2003).

Pure NumPy/SciPy.
"""

from __future__ import annotations

from .manoeuvres import MANOEUVRES, manoeuvre, manoeuvre_names
from .metrics import TrialMetrics, imo_criteria, trial_metrics, zigzag_limits

__all__ = [
    "MANOEUVRES",
    "TrialMetrics",
    "imo_criteria",
    "manoeuvre",
    "manoeuvre_names",
    "trial_metrics",
    "zigzag_limits",
]
