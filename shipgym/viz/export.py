"""A recorded run's time series as a table: CSV (one column per signal component, the unit in
each column name) or a NumPy archive (``.npz``).

:func:`run_columns` names every component of a :class:`~shipgym.viz.run.Run`'s per-step
arrays (``x [m]``, ``psi [rad]``, ``u [m/s]``, ``thrust_bow_tunnel [N]``, ...) or of its
measurements (their own times); :func:`write_run_csv` and :func:`write_run_npz` write them
atomically (a complete file or the earlier one). ``shipgym export RUN --csv`` / ``--npz``
calls them.

Public names: ``Column``, ``TABLES``, ``export_path``, ``run_columns``, ``write_run_csv``,
``write_run_npz``.
"""

from __future__ import annotations

import csv
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .run import Run, _clean

__all__ = [
    "TABLES",
    "Column",
    "export_path",
    "run_columns",
    "write_run_csv",
    "write_run_npz",
]

#: the tables of a run: one row per control step (the reset state first), or one row per valid
#: position measurement (the DGPS and gyrocompass samples, at their own times)
TABLES = ("steps", "measurements")

#: the unit written for a dimensionless quantity (a run's channels say ``"1"``)
DIMENSIONLESS = "-"


@dataclass(frozen=True)
class Column:
    """One component of a recorded signal.

    Attributes:
        name: the component's name without its unit (``"x"``, ``"thrust_bow_tunnel"``).
        unit: its SI unit (``"m"``, ``"rad/s"``, ``"N m"``; ``"-"``: dimensionless, a flag or
            an index).
        values: the samples, (N,): float64, int64 for counters and indices, bool for flags.
    """

    name: str
    unit: str
    values: NDArray[Any]

    @property
    def label(self) -> str:
        """The CSV column name: ``"x [m]"``."""
        return f"{self.name} [{self.unit}]"


#: per-step arrays of three components: field -> (component names, units)
_POSE = ("m", "m", "rad")
_RATE = ("m/s", "m/s", "rad/s")
_LOAD = ("N", "N", "N m")
_TRIPLES: tuple[tuple[str, tuple[str, str, str], tuple[str, str, str]], ...] = (
    ("eta", ("x", "y", "psi"), _POSE),
    ("nu", ("u", "v", "r"), _RATE),
    ("nav_eta", ("nav_x", "nav_y", "nav_psi"), _POSE),
    ("nav_nu", ("nav_u", "nav_v", "nav_r"), _RATE),
    ("eta_d", ("x_d", "y_d", "psi_d"), _POSE),
    ("eta_d_r", ("x_d_r", "y_d_r", "psi_d_r"), _POSE),
    ("eta_dot_d_r", ("x_dot_d_r", "y_dot_d_r", "psi_dot_d_r"), _RATE),
    ("eta_r", ("x_r", "y_r", "psi_r"), _POSE),
    ("eta_P", ("x_P", "y_P", "psi_P"), _POSE),
    ("tau_wind", ("tau_wind_X", "tau_wind_Y", "tau_wind_N"), _LOAD),
    ("tau_waves", ("tau_waves_X", "tau_waves_Y", "tau_waves_N"), _LOAD),
    ("current_body", ("current_u", "current_v", "current_r"), _RATE),
)
_ACCURACY = (("x_E", "m"), ("y_E", "m"), ("psi_E", "deg"), ("J_c", DIMENSIONLESS))


def _unit(unit: Any) -> str:
    u = str(unit or "").strip()
    return DIMENSIONLESS if u in ("", "1", "-") else u


def _split(
    a: NDArray[Any], names: Any, units: Any, n: int
) -> list[Column]:  # columns of an (n, k) array
    a = np.asarray(a)
    if a.ndim != 2 or a.shape[0] != n or a.shape[1] != len(names):
        return []  # absent (an older run file without it) or of another width
    return [
        Column(nm, _unit(u), a[:, i]) for i, (nm, u) in enumerate(zip(names, units, strict=True))
    ]


def _step_columns(run: Run) -> list[Column]:
    n = len(run.t)
    cols = [Column("t", "s", np.asarray(run.t, float)), Column("step", DIMENSIONLESS, run.step)]
    for field, names, units in _TRIPLES[:9]:
        cols += _split(getattr(run, field), names, units, n)
    cols += [
        Column("leg", DIMENSIONLESS, run.leg),
        Column("legs_completed", DIMENSIONLESS, run.legs_completed),
    ]
    acts = run.actuators
    channels = list(acts.get("channels") or [])
    cols += _split(run.command, [f"command_{c}" for c in channels], acts.get("units") or
                   [""] * len(channels), n)  # fmt: skip
    state_units = acts.get("state_units") or [""] * len(channels)
    cols += _split(run.actuator_state, [f"state_{c}" for c in channels], state_units, n)
    cols += _split(run.saturated, [f"saturated_{c}" for c in channels], [""] * len(channels), n)
    actuators = list(acts.get("names") or [])
    cols += _split(run.thrust, [f"thrust_{a}" for a in actuators], ["N"] * len(actuators), n)
    for field, comp, units in _TRIPLES[9:]:
        cols += _split(getattr(run, field), comp, units, n)
    cols += _split(run.wind, ("wind_speed", "wind_from"), ("m/s", "rad"), n)
    acc_names = [a for a, _ in _ACCURACY]
    acc_units = [u for _, u in _ACCURACY]
    cols += _split(run.accuracy, acc_names, acc_units, n)
    cols += _split(run.accuracy_measured, [f"{a}_meas" for a in acc_names], acc_units, n)
    cols += _split(run.roll, ("phi", "p"), ("rad", "rad/s"), n)
    return cols


def _measurement_columns(run: Run) -> list[Column]:
    m = len(run.meas_t)
    cols = [
        Column("t", "s", np.asarray(run.meas_t, float)),
        Column("step", DIMENSIONLESS, run.meas_step),
    ]
    cols += _split(run.meas_z, ("x", "y", "psi"), _POSE, m)
    cols += _split(run.meas_z_r, ("x_r", "y_r", "psi_r"), _POSE, m)
    cols.append(Column("outlier", DIMENSIONLESS, np.asarray(run.meas_outlier, bool)))
    return cols


def run_columns(run: Run, table: str = "steps") -> list[Column]:
    """The components of a run's time series, one :class:`Column` each, in a fixed order.

    Args:
        run: a run (:func:`~shipgym.viz.load_run`, or a recorder's ``last_run``).
        table: ``"steps"``: one row per control step, the reset state first: ``t [s]``,
            ``step``, the true pose ``x [m]``, ``y [m]``, ``psi [rad]`` and velocity ``u [m/s]``,
            ``v [m/s]``, ``r [rad/s]``, what the controller used (``nav_*``), the desired pose
            (``*_d``, and ``*_d_r``, ``*_dot_d_r`` in the leg's r-frame), the true pose in
            the r-frame (``*_r``), the leg's start (``*_P``), ``leg``, ``legs_completed``,
            per control channel ``command_<channel>`` (in the channel's unit),
            ``state_<channel>`` and ``saturated_<channel>``, per actuator
            ``thrust_<actuator> [N]``, the wind and wave loads ``tau_wind_X [N]``,
            ``tau_wind_Y [N]``, ``tau_wind_N [N m]`` (``tau_waves_*``), the current on the
            body axes ``current_u [m/s]`` ..., the wind ``wind_speed [m/s]`` and
            ``wind_from [rad]``, the running accuracy indices ``x_E [m]``, ``y_E [m]``,
            ``psi_E [deg]``, ``J_c`` (and ``*_meas`` from the measurements) and, for a 4-DOF
            vessel, ``phi [rad]`` and ``p [rad/s]``. ``"measurements"``: one row per valid
            position measurement: ``t [s]``, ``step``, ``x``, ``y``, ``psi`` (NED) and
            ``x_r``, ``y_r``, ``psi_r`` (the leg's r-frame), ``outlier``.

    Returns:
        The columns, each of the table's length (an array a run file lacks is left out).

    Raises:
        ValueError: an unknown ``table``.
    """
    if table == "steps":
        return _step_columns(run)
    if table == "measurements":
        return _measurement_columns(run)
    raise ValueError(f"unknown table {table!r}; choose one of: {', '.join(TABLES)}")


def export_path(run_path: str | os.PathLike[str], fmt: str, table: str = "steps") -> Path:
    """The default output of an export: next to the run file, its suffix replaced
    (``run.rrd`` -> ``run.csv``; the measurements: ``run.measurements.csv``)."""
    p = Path(run_path)
    stem = p.stem if table == "steps" else f"{p.stem}.{table}"
    return p.with_name(f"{stem}.{fmt}")


def _texts(values: NDArray[Any]) -> list[str]:
    """A column's values as CSV fields: floats round-trip exactly (``repr``), NaN as
    ``nan``, flags as 0/1."""
    a = np.asarray(values)
    if a.dtype.kind == "b":
        return ["1" if v else "0" for v in a.tolist()]
    if a.dtype.kind in "iu":
        return [str(v) for v in a.tolist()]
    return [repr(v) for v in a.astype(float).tolist()]


def write_run_csv(
    run: Run, path: str | os.PathLike[str], *, table: str = "steps"
) -> tuple[Path, list[Column]]:
    """Write a run's table (:func:`run_columns`) as CSV: a header of ``name [unit]`` labels,
    then one row per sample; ``pandas.read_csv(path)`` or :mod:`csv` read it back (floats
    written to round-trip exactly, NaN as ``nan``, flags as 0/1).

    Returns:
        The path written (atomically: a complete file or the earlier one) and the columns.

    Raises:
        ValueError: an unknown ``table``.
        OSError: the file could not be written (it is then unchanged).
    """
    from shipgym._io import atomic_path

    cols = run_columns(run, table)
    fields = [_texts(c.values) for c in cols]
    path = Path(path)
    with atomic_path(path) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow([c.label for c in cols])
        w.writerows(zip(*fields, strict=True))
        fh.flush()
        if tmp.is_file():
            os.fsync(fh.fileno())
    return path, cols


def write_run_npz(run: Run, path: str | os.PathLike[str]) -> tuple[Path, list[Column]]:
    """Write a run's time series as a compressed NumPy archive (``numpy.load`` reads it
    without pickles).

    Entries: each column of the ``"steps"`` table under its name (``t``, ``x``, ``psi``,
    ``thrust_bow_tunnel``, ...) and of the ``"measurements"`` table under ``meas_`` + its
    name (``meas_t``, ``meas_x``, ...), as 1-D arrays; ``units``: a ``(K, 2)`` string array
    of ``(entry, unit)`` pairs (``dict(archive["units"])``: entry -> unit); ``metadata``: a
    JSON string of the run's ``metadata``, ``metrics``, ``actuators`` and ``vessel``.

    Returns:
        The path written (atomically; ``path`` is used as given, no ``.npz`` is appended) and
        the columns (the measurements' with their ``meas_`` names).

    Raises:
        OSError: the file could not be written (it is then unchanged).
    """
    from shipgym._io import atomic_path

    cols = run_columns(run, "steps")
    cols += [Column(f"meas_{c.name}", c.unit, c.values) for c in run_columns(run, "measurements")]
    arrays: dict[str, NDArray[Any]] = {c.name: np.asarray(c.values) for c in cols}
    arrays["units"] = np.array([[c.name, c.unit] for c in cols], dtype=str).reshape(-1, 2)
    doc = {"metadata": run.metadata, "metrics": run.metrics, "actuators": run.actuators,
           "vessel": run.vessel}  # fmt: skip
    arrays["metadata"] = np.array(json.dumps(_clean(doc)))
    path = Path(path)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        # a file object: no ".npz" appended to the name
        np.savez_compressed(fh, **arrays)  # type: ignore[arg-type]
        fh.flush()
        if tmp.is_file():
            os.fsync(fh.fileno())
    return path, cols
