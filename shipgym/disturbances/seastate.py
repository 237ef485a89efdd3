r"""The Beaufort table (WMO 1998) and its sea states at any Froude scale.

Sources: WMO (1998), Price & Bishop (1974) and NORSOK N-003 (Beaufort table), Hasselmann
et al. (1973) (JONSWAP), ISO 19901-1 (2015) (NPD gusts). Full entries: ``docs/references.md``.
Mean wind ``U10`` = middle of the WMO band (0 for BF0), ``Hs`` = WMO "probable wave height",
``Tp`` from the NORSOK relation ``4.883 + 2.68 Hs^0.54``, all at full scale;
:func:`beaufort` Froude-scales them (re-exported by :mod:`shipgym.scenarios`).
"""

from __future__ import annotations

import math
import numbers
from typing import NamedTuple

from .spectra import norsok_peak_period
from .waves import AL_TAKIE_HF_POLYNOMIALS, WaveConfig
from .wind import WindConfig

__all__ = ["BEAUFORT_TABLE", "BeaufortRow", "SeaState", "beaufort", "beaufort_row"]

# ---------------------------------------------------------------------------------------------
# Beaufort table
# ---------------------------------------------------------------------------------------------


class BeaufortRow(NamedTuple):
    """One Beaufort number at full scale (WMO 1998).

    Attributes:
        number: Beaufort number 0-9.
        name: WMO description.
        U10_min: Lower bound of the WMO wind band at 10 m (m/s).
        U10_max: Upper bound of the band (m/s).
        U10: Representative mean wind (m/s): the middle of the band (0 for BF0).
        Hs: WMO probable significant wave height (m).
        Tp: Peak period from NORSOK ``4.883 + 2.68 Hs^0.54`` (s); not a wind-sea value for
            BF1-2 (see the notes of :func:`beaufort`).
    """

    number: int
    name: str
    U10_min: float
    U10_max: float
    U10: float
    Hs: float
    Tp: float


_WMO: tuple[tuple[str, float, float, float], ...] = (
    ("calm", 0.0, 0.2, 0.0),
    ("light air", 0.3, 1.5, 0.1),
    ("light breeze", 1.6, 3.3, 0.2),
    ("gentle breeze", 3.4, 5.4, 0.6),
    ("moderate breeze", 5.5, 7.9, 1.0),
    ("fresh breeze", 8.0, 10.7, 2.0),
    ("strong breeze", 10.8, 13.8, 3.0),
    ("near gale", 13.9, 17.1, 4.0),
    ("gale", 17.2, 20.7, 5.5),
    ("strong gale", 20.8, 24.4, 7.0),
)

#: Beaufort 0-9 at full scale: WMO wind bands and probable wave heights, NORSOK Tp.
BEAUFORT_TABLE: tuple[BeaufortRow, ...] = tuple(
    BeaufortRow(
        n,
        name,
        lo,
        hi,
        0.0 if n == 0 else 0.5 * (lo + hi),
        hs,
        norsok_peak_period(hs),
    )
    for n, (name, lo, hi, hs) in enumerate(_WMO)
)


def beaufort_row(n: int) -> BeaufortRow:
    """The full-scale :class:`BeaufortRow` of Beaufort number ``n`` (0-9)."""
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or not 0 <= n <= 9:
        raise ValueError(f"Beaufort number must be an int 0-9, got {n!r}")
    return BEAUFORT_TABLE[int(n)]


class SeaState(NamedTuple):
    """Wind and waves of one sea state (unpacks as ``wind, waves = beaufort(5)``)."""

    wind: WindConfig
    waves: WaveConfig


def beaufort(
    n: int,
    scale: float = 24.0,
    *,
    direction_from: float = 0.0,
    gamma: float = 3.3,
    gust_spectrum: str = "npd",
    first_order: bool = True,
    drift: bool = True,
    wf_model: str = "fossen",
) -> SeaState:
    """Beaufort ``n`` sea state, Froude-scaled to a model at ``1:scale``.

    Model values: ``U = U10 / sqrt(scale)``, ``Hs / scale``, ``Tp / sqrt(scale)``. The wind gust
    follows ``gust_spectrum`` evaluated at full scale (``spectrum_scale = scale``); wind and
    waves come from the same direction. The WF-motion stds are the :class:`WaveConfig`
    defaults (``Hs/16`` along the waves, ``radians(2) Hs w_p^2 / g`` in heading); for BF5-9
    ``wf_beaufort`` is set so that ``wf_model="al-takie"`` works.

    Args:
        n: Beaufort number 0-9 (0: calm, no wind, ``Hs = 0``).
        scale: Froude scale ``lambda`` (24 = Blue Lady; 1 = full scale).
        direction_from: Direction wind and waves come from (rad).
        gamma: JONSWAP peak factor.
        gust_spectrum: ``"npd"`` (default), ``"harris"`` or ``"gauss-markov"``.
        first_order: WF motion on the measured pose.
        drift: Second-order drift loads.
        wf_model: ``"fossen"``, ``"al-takie"`` or ``"rao"``.

    Returns:
        ``SeaState(wind, waves)``.
    """
    row = beaufort_row(n)
    if isinstance(scale, bool) or not isinstance(scale, numbers.Real) or not scale >= 1.0:
        raise ValueError(f"beaufort: scale must be a number >= 1, got {scale!r}")
    sq = math.sqrt(float(scale))
    tp = row.Tp / sq
    wind = WindConfig(
        speed=row.U10 / sq,
        direction_from=float(direction_from),
        gust_spectrum=gust_spectrum,
        spectrum_scale=float(scale),
    )
    waves = WaveConfig(
        spectrum="jonswap",
        Hs=row.Hs / float(scale),
        Tp=tp,
        gamma=gamma,
        direction_from=float(direction_from),
        drift=drift,
        first_order=first_order,
        wf_model=wf_model,
        wf_beaufort=row.number if row.number in AL_TAKIE_HF_POLYNOMIALS else None,
        sample_period=min(0.05, tp / 20.0),
    )
    return SeaState(wind, waves)
