"""A recorded run as NumPy arrays, and its file formats: rerun ``.rrd`` and JSON.

:class:`Run` is what :class:`~shipgym.viz.RecordEpisode` records and what
:func:`~shipgym.viz.write_report` plots. :func:`load_run` reads it back from a ``.rrd`` file
(with ``rerun.chunk.RrdReader``; no viewer) or from a JSON run file written by
:func:`save_run_json`.

Public names: ``P``, ``Run``, ``actuator_description``, ``command_path``, ``indices_warning``,
``load_run``, ``recording_problem``, ``save_run_json``.
Sources: Tomera (2014).

Design notes: docs/design/viz.run.md.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shipgym.metrics import indices_note

__all__ = [
    "P",
    "Run",
    "actuator_description",
    "command_path",
    "indices_warning",
    "is_results",
    "load_results",
    "load_run",
    "load_run_or_results",
    "recording_problem",
    "save_run_json",
]

JSON_FORMAT = "shipgym-run"
JSON_VERSION = 1


class P:
    """Entity paths of the ``.rrd`` files (see the module docstring)."""

    MAP = "map"
    NED = "map/ned"
    QUAYS = "map/ned/quays"
    PLAN = "map/ned/plan"
    WAYPOINTS = "map/ned/waypoints"
    SHIP = "map/ned/ship"
    HULL = "map/ned/ship/hull"
    THRUST = "map/ned/ship/thrust"
    TARGET = "map/ned/target"
    TRACK_TRUTH = "map/ned/track/truth"
    TRACK_REF = "map/ned/track/reference"
    TRACK_EST = "map/ned/track/estimate"
    DGPS = "map/ned/dgps"
    DGPS_OUTLIERS = "map/ned/dgps_outliers"
    HULL_TRACE = "map/ned/hull_trace"
    WIND = "map/ned/wind"
    POSITION = "plots/position"  # /x, /y, /psi and /<dof>/measured
    VELOCITY = "plots/velocity"  # /u, /v, /r
    PLOT_THRUST = "plots/thrust"
    COMMAND = "plots/command"  # /<unit>: command_path(unit)
    ROLL = "plots/roll"
    ACCURACY = "plots/accuracy/truth"
    ACCURACY_MEAS = "plots/accuracy/measured"
    DATA = "data"  # /<name> for the names in DATA_VECTORS
    SUMMARY = "metadata/summary"
    META_JSON = "metadata/json"


#: Per-step float64 vectors logged under ``data/<name>`` (name -> width; ``None``: one entry
#: per control channel or per actuator of the vessel). 4-DOF vessels add ``data/roll``
#: (``[phi (rad), p (rad/s)]``).
DATA_VECTORS: dict[str, int | None] = {
    "eta": 3,
    "nu": 3,
    "nav_eta": 3,
    "nav_nu": 3,
    "eta_d": 3,
    "eta_d_r": 3,
    "eta_dot_d_r": 3,
    "eta_r": 3,
    "eta_P": 3,
    "command": None,
    "thrust": None,
    "saturated": None,
    "actuator_state": None,
    "tau_wind": 3,
    "tau_waves": 3,
    "current_body": 3,
    "wind": 2,
    "leg": 2,
}

#: unit -> entity name under ``plots/command`` (units with a slash or "1" are renamed)
_UNIT_SLUGS = {"1": "relative", "rad/s": "rad_per_s", "deg/s": "deg_per_s"}


def command_path(unit: str) -> str:
    """Entity path of the command plot of the channels whose command unit is ``unit``."""
    slug = _UNIT_SLUGS.get(unit) or "".join(c if c.isalnum() else "_" for c in unit) or "none"
    return f"{P.COMMAND}/{slug}"


def actuator_description(actuators: Any) -> dict[str, list[Any]]:
    """Names, colours, channels and units of an ActuatorSet, as stored with a run.

    Keys: ``names``, ``colours``, ``kinds``, ``max_thrust`` (N) per actuator; ``channels``,
    ``units`` (command unit), ``state_units`` and ``channel_actuator`` (index of the
    actuator owning the channel) per control channel.
    """
    owner = [i for i, sl in enumerate(actuators.slices) for _ in range(sl.start, sl.stop)]
    return {
        "names": list(actuators.names),
        "colours": list(actuators.colours),
        "kinds": [a.kind for a in actuators],
        "max_thrust": [float(a.max_thrust) for a in actuators],
        "channels": list(actuators.channel_names),
        "units": list(actuators.units),
        "state_units": [c.state_unit for c in actuators.channels],
        "channel_actuator": owner,
    }


def _legacy_actuators(n_thrust: int) -> dict[str, list[Any]]:
    """The actuators of a run recorded before runs carried them: the Blue Lady's (the only
    vessel then), or numbered ones when the widths do not match hers."""
    from shipgym.dynamics.vessel import load_vessel

    bl = actuator_description(load_vessel("blue-lady").actuators)
    if n_thrust == len(bl["names"]):
        return bl
    names = [f"actuator {i + 1}" for i in range(n_thrust)]
    return {
        "names": names,
        "colours": ["#1f77b4"] * n_thrust,
        "kinds": [""] * n_thrust,
        "max_thrust": [float("nan")] * n_thrust,
        "channels": list(names),
        "units": [""] * n_thrust,
        "state_units": [""] * n_thrust,
        "channel_actuator": list(range(n_thrust)),
    }


_N3 = ("eta", "nu", "nav_eta", "nav_nu", "eta_d", "eta_d_r", "eta_dot_d_r", "eta_r", "eta_P")


@dataclass
class Run:
    """One recorded episode as arrays (``N`` control steps including the reset state).

    Attributes:
        t: time (s), (N,); ``step``: control step index (0 = after reset), (N,).
        eta, nu: true NED pose (m, m, rad) and body velocity (m/s, m/s, rad/s), (N, 3).
        nav_eta, nav_nu: what the controller used (truth or the observer's estimate), (N, 3).
        eta_d: desired NED pose; eta_d_r, eta_dot_d_r: desired pose and its rate in the leg's
            r-frame; eta_r: true pose in the r-frame; eta_P: NED pose of the leg start, (N, 3).
        leg: index of the leg being performed, legs_completed, (N,) int.
        command: the channel commands (each in its unit), (N, C); actuator_state: the
            channel states (lagged commands; an azimuth's angle in rad), (N, C); saturated:
            per-channel flags, (N, C); thrust: per actuator (N), (N, A).
        tau_wind: wind load ``[X (N), Y (N), N (N m)]`` in the body frame, (N, 3).
        tau_waves: second-order wave drift load, body frame (N, N, N m), (N, 3).
        current_body: current velocity on the body axes ``[u_c, v_c, 0]`` (m/s), (N, 3).
        wind: ``[speed (m/s), direction from (rad)]`` at each step, (N, 2).
        meas_t, meas_step: times (s) and control steps of the valid measurements, (M,).
        meas_z: measured NED pose (m, m, rad), (M, 3); meas_z_r: in the leg's r-frame, (M, 3).
        meas_outlier: truth flag of outliers, (M,).
        accuracy, accuracy_measured: running ``[x_E (m), y_E (m), psi_E (deg), J_c]`` from the
            truth and from the measurements (NaN before the first sample), (N, 4).
        waypoints: planned NED leg end points (m, m, rad), (legs + 1, 3).
        quays: NED corner polygons (m), (K, 4, 2); quay_names: their geom names.
        hull: body-frame hull outline ``(x forward, y starboard)`` (m), (H, 2).
        thrusters: body-frame actuator positions (m), (A, 2).
        actuators: the vessel's actuators (:func:`actuator_description`: ``names``,
            ``colours``, ``channels``, ``units``, ...).
        vessel: ``name``, ``title``, ``dofs``, ``L_oa`` (m), ``B`` (m) of the vessel.
        roll: ``[phi (rad), p (rad/s)]`` of a 4-DOF vessel, (N, 2); (0, 2) for 3 DOF.
        metadata: env id, scenario, seed, observer, controller, wind, plan, ...
        metrics: the environment's episode metrics (accuracy indices, leg times, thrusters).
    """

    t: NDArray[np.float64]
    step: NDArray[np.int64]
    eta: NDArray[np.float64]
    nu: NDArray[np.float64]
    nav_eta: NDArray[np.float64]
    nav_nu: NDArray[np.float64]
    eta_d: NDArray[np.float64]
    eta_d_r: NDArray[np.float64]
    eta_dot_d_r: NDArray[np.float64]
    eta_r: NDArray[np.float64]
    eta_P: NDArray[np.float64]
    leg: NDArray[np.int64]
    legs_completed: NDArray[np.int64]
    command: NDArray[np.float64]
    thrust: NDArray[np.float64]
    saturated: NDArray[np.bool_]
    tau_wind: NDArray[np.float64]
    wind: NDArray[np.float64]
    meas_t: NDArray[np.float64]
    meas_step: NDArray[np.int64]
    meas_z: NDArray[np.float64]
    meas_z_r: NDArray[np.float64]
    meas_outlier: NDArray[np.bool_]
    accuracy: NDArray[np.float64]
    accuracy_measured: NDArray[np.float64]
    waypoints: NDArray[np.float64]
    quays: NDArray[np.float64]
    quay_names: list[str] = field(default_factory=list)
    hull: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))
    thrusters: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))
    metadata: dict[str, Any] = field(default_factory=dict)
    metrics: dict[str, Any] = field(default_factory=dict)
    tau_waves: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    current_body: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    actuator_state: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 0)))
    actuators: dict[str, list[Any]] = field(default_factory=dict)
    vessel: dict[str, Any] = field(default_factory=dict)
    roll: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))

    def __post_init__(self) -> None:
        if not self.actuators:
            self.actuators = _legacy_actuators(self.thrust.shape[1] if self.thrust.ndim == 2 else 3)
        if not self.vessel:  # recorded before runs carried it: the Blue Lady
            self.vessel = {"name": "blue-lady", "title": "Blue Lady", "dofs": 3}
        if self.actuator_state.size == 0 and len(self.t):
            self.actuator_state = np.full((len(self.t), len(self.channel_names)), np.nan)

    @property
    def actuator_names(self) -> list[str]:
        """Names of the vessel's actuators (the columns of ``thrust``)."""
        return list(self.actuators["names"])

    @property
    def channel_names(self) -> list[str]:
        """Names of the control channels (the columns of ``command``)."""
        return list(self.actuators["channels"])

    @property
    def vessel_title(self) -> str:
        """The vessel's human-readable name."""
        return str(self.vessel.get("title") or self.vessel.get("name") or "vessel")

    @property
    def n_steps(self) -> int:
        """Number of ``env.step`` calls recorded (rows minus the reset state)."""
        return max(len(self.t) - 1, 0)

    @property
    def nu_d(self) -> NDArray[np.float64]:
        """Desired body velocity ``R(psi_d^r)^T eta_dot_d^r`` (m/s, m/s, rad/s), (N, 3)."""
        return desired_body_velocity(self.eta_d_r, self.eta_dot_d_r)

    @property
    def nav_eta_r(self) -> NDArray[np.float64]:
        """Navigation pose in the leg's r-frame (heading near psi_d^r), (N, 3)."""
        from shipgym.guidance import to_r_frame

        if len(self.t) == 0:
            return np.zeros((0, 3))
        return to_r_frame(self.nav_eta, self.eta_P, psi_ref_r=self.eta_d_r[:, 2])


def desired_body_velocity(eta_d_r: Any, eta_dot_d_r: Any) -> NDArray[np.float64]:
    """``nu_d = R(psi_d^r)^T eta_dot_d^r`` row by row (m/s, m/s, rad/s)."""
    e = np.asarray(eta_d_r, dtype=float).reshape(-1, 3)
    v = np.asarray(eta_dot_d_r, dtype=float).reshape(-1, 3)
    c, s = np.cos(e[:, 2]), np.sin(e[:, 2])
    return np.column_stack([c * v[:, 0] + s * v[:, 1], -s * v[:, 0] + c * v[:, 1], v[:, 2]])


# ---- JSON ------------------------------------------------------------------------------------
def _clean(obj: Any) -> Any:
    """JSON-safe copy: arrays to lists, NaN/inf to None, numpy scalars to Python."""
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind == "f":
            bad = ~np.isfinite(obj)
            if not bad.any():
                return obj.tolist()
            out = obj.astype(object)
            out[bad] = None
            return out.tolist()
        if obj.dtype.kind in "biu":
            return obj.tolist()
        return _clean(obj.tolist())
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.bool_ | bool):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        f = float(obj)
        return f if math.isfinite(f) else None
    return obj


def save_run_json(run: Run, path: str | os.PathLike[str]) -> Path:
    """Write a run to a JSON file (arrays as nested lists, NaN as ``null``).

    Args:
        run: the run (from the recorder or :func:`load_run`).
        path: destination file (parent folders are created).

    Returns:
        The path written (atomically: a complete file or the earlier one, never half a file).
    """
    from shipgym._io import atomic_write_text

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = {}
    for f in fields(run):
        if f.name in _DOC_FIELDS:
            continue
        arrays[f.name] = getattr(run, f.name)
    doc = {
        "format": JSON_FORMAT,
        "version": JSON_VERSION,
        "metadata": run.metadata,
        "metrics": run.metrics,
        "quay_names": list(run.quay_names),
        "actuators": run.actuators,
        "vessel": run.vessel,
        "arrays": arrays,
    }
    atomic_write_text(path, json.dumps(_clean(doc), separators=(",", ":")))
    return path


_DOC_FIELDS = ("metadata", "metrics", "quay_names", "actuators", "vessel")
#: arrays a run file written before they existed may lack (the Run's defaults fill them)
_OPTIONAL_ARRAYS = ("actuator_state", "roll")
_INT_FIELDS = ("step", "leg", "legs_completed", "meas_step")
_BOOL_FIELDS = ("saturated", "meas_outlier")
_SHAPES = {
    "meas_z": (0, 3),
    "meas_z_r": (0, 3),
    "accuracy": (0, 4),
    "accuracy_measured": (0, 4),
    "waypoints": (0, 3),
    "quays": (0, 4, 2),
    "hull": (0, 2),
    "thrusters": (0, 2),
    "wind": (0, 2),
    "roll": (0, 2),
    **{k: (0, 3) for k in (*_N3, "tau_wind", "tau_waves", "current_body")},
}


def _as_array(name: str, value: Any) -> NDArray[Any]:
    if name in _BOOL_FIELDS:
        a = np.asarray(value, dtype=bool)
    elif name in _INT_FIELDS:
        a = np.asarray(value, dtype=np.int64)
    else:
        a = np.array(value, dtype=float)  # None -> nan
    if a.size == 0 and name in _SHAPES:
        a = a.reshape(_SHAPES[name])
    return a


#: largest JSON run file read (bytes)
MAX_RUN_JSON_BYTES = 1 << 30
#: the largest recording ``load_run`` reads (bytes), read whole into memory by rerun
MAX_RUN_RRD_BYTES = 4 << 30


def is_results(doc: Any) -> bool:
    """Whether the JSON document ``doc`` is the results of ``shipgym run --json`` (the
    episode's metrics and what ran; no time series), not a run file."""
    return isinstance(doc, dict) and "format" not in doc and "env_id" in doc and "seed" in doc


def _read_json(path: Path, what: str) -> Any:
    """The JSON document of ``path`` (bounded, code-free; ``what``: the file's kind, for the
    messages)."""
    from shipgym._safeload import parse, read_bounded

    try:  # a run of days at 1 s is a few hundred MB of JSON
        raw = read_bounded(path, what, MAX_RUN_JSON_BYTES)
        return parse(raw.decode("utf-8"), "json", f"{what} {path}", limit=1 << 27)
    except (ValueError, UnicodeDecodeError) as exc:
        raise ValueError(f"cannot read the {what} {path}: {exc}") from None


def load_results(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The results of ``shipgym run --json`` read from ``path`` (bounded, code-free JSON).

    Raises:
        ValueError: an unreadable file, or one that is not such results (a run file, say).
    """
    p = Path(path)
    doc = _read_json(p, "results file")
    if not is_results(doc):
        raise ValueError(f"{p} is not the results of 'shipgym run --json'")
    return doc  # type: ignore[no-any-return]


def load_run_or_results(path: str | os.PathLike[str]) -> Run | dict[str, Any]:
    """:func:`load_run`, or the results of ``shipgym run --json`` (a dict, :func:`load_results`)
    where ``path`` holds those: the file read once.

    Raises:
        ValueError: as :func:`load_run`, but for the results.
    """
    p = Path(path)
    if p.suffix.lower() == ".json" and p.is_file():
        return _load_json(p, results=True)
    return load_run(p)


def _load_json(path: Path, results: bool = False) -> Run | dict[str, Any]:
    """The run of the JSON run file ``path``; ``results``: the results of ``shipgym run
    --json`` (a dict) where it holds those (else they are refused)."""
    doc = _read_json(path, "run file")
    if is_results(doc):
        if results:
            return doc  # type: ignore[no-any-return]
        raise ValueError(
            f"{path} holds the results of 'shipgym run --json' (metrics, no time series): "
            "record the run with 'shipgym run --record RUN.rrd' and read the recording "
            "('shipgym report RUN.rrd', 'shipgym export RUN.rrd --csv'), or make the figures "
            "with 'shipgym run --report DIR'"
        )
    if not isinstance(doc, dict) or doc.get("format") != JSON_FORMAT:
        raise ValueError(
            f"{path} is not a shipgym run file (expected a JSON object with "
            f'"format": "{JSON_FORMAT}", as written by shipgym.viz.save_run_json)'
        )
    try:
        return _run_of_doc(doc, path)
    except (ValueError, TypeError, KeyError, AttributeError) as exc:  # a file of the wrong shape
        msg = str(exc)
        raise ValueError(msg if msg.startswith(str(path)) else f"{path}: {msg}") from None


def _run_of_doc(doc: dict[str, Any], path: Path) -> Run:
    """The :class:`Run` of a parsed run file ``doc`` (``path``: for the messages)."""
    arrays = doc.get("arrays", {})
    if not isinstance(arrays, dict):
        raise ValueError(f"{path}: 'arrays' must be a JSON object of named arrays")
    widths = {"command": 3, "thrust": 3, "saturated": 3}  # files before per-vessel widths
    acts = doc.get("actuators")
    if isinstance(acts, dict) and acts.get("names"):
        widths = {
            "command": len(acts["channels"]),
            "saturated": len(acts["channels"]),
            "actuator_state": len(acts["channels"]),
            "thrust": len(acts["names"]),
        }
    kwargs: dict[str, Any] = {}
    for f in fields(Run):
        if f.name in _DOC_FIELDS:
            continue
        if f.name not in arrays and f.name in _OPTIONAL_ARRAYS:
            continue
        if f.name not in arrays:
            raise ValueError(f"{path}: the run file lacks the array {f.name!r}")
        a = _as_array(f.name, arrays[f.name])
        if a.size == 0 and f.name in widths:
            a = a.reshape(0, widths[f.name])
        kwargs[f.name] = a
    _check_lengths(kwargs, path)
    return Run(
        **kwargs,
        actuators=dict(acts) if isinstance(acts, dict) else {},
        vessel=dict(doc.get("vessel") or {}),
        quay_names=list(doc.get("quay_names", [])),
        metadata=dict(doc.get("metadata") or {}),
        metrics=dict(doc.get("metrics") or {}),
    )


#: the arrays of a run with a row per control step (and the width of a row, None: any)
_PER_STEP = {"step": None, "leg": None, "legs_completed": None, "command": None,
             "thrust": None, "saturated": None, "actuator_state": None, "wind": 2,
             **dict.fromkeys(("eta", "nu", "nav_eta", "nav_nu", "eta_d", "eta_d_r",
                              "eta_dot_d_r", "eta_r", "eta_P", "tau_wind", "tau_waves",
                              "current_body"), 3)}  # fmt: skip
#: the arrays with a row per valid measurement
_PER_SAMPLE = {"meas_step": None, "meas_outlier": None, "meas_z": 3, "meas_z_r": 3}


def _check_lengths(arrays: dict[str, Any], path: Path) -> None:
    """Every per-step array has a row per time of ``t`` and every per-sample array a row per
    time of ``meas_t``, of the expected width (a run file of the wrong shape is named, not
    met later as a plotting library's broadcast error)."""
    for times, group in (("t", _PER_STEP), ("meas_t", _PER_SAMPLE)):
        n = len(arrays[times])
        for name, width in group.items():
            a = arrays.get(name)
            if a is None:
                continue
            if a.shape[:1] != (n,) or (width is not None and a.shape[1:] != (width,)):
                want = f"({n},)" if width is None else f"({n}, {width})"
                raise ValueError(
                    f"{path}: the array {name!r} has shape {a.shape}; a run with {n} "
                    f"{'control steps' if times == 't' else 'measurements'} needs {want}"
                )


# ---- rrd -------------------------------------------------------------------------------------
def _has_footer(reader: Any) -> bool:
    """Whether a rerun file has its footer (manifest), written when the file was finalised."""
    try:
        reader.store()  # needs the manifest; a file without footer cannot be opened this way
    except Exception:  # noqa: BLE001 - any failure means the same: no usable footer
        return False
    return True


def _chunks_by_entity(path: Path) -> tuple[dict[str, dict[str, Any]], bool]:
    """Per entity path: ``{"static": {component: value}, "rows": {column: list}}``, and
    whether the file has its footer."""
    import warnings

    from rerun.chunk import RrdReader

    with warnings.catch_warnings():  # "no footer" is reported by recording_problem instead
        warnings.simplefilter("ignore")
        reader = RrdReader(path)
        footer = _has_footer(reader)
    out: dict[str, dict[str, Any]] = {}
    for ch in reader.stream():
        ent = ch.entity_path.lstrip("/")
        rb = ch.to_record_batch()
        slot = out.setdefault(ent, {"static": {}, "rows": {}})
        cols = {name: rb.column(i) for i, name in enumerate(rb.schema.names)}
        if ch.is_static:
            for name, col in cols.items():
                if name.startswith("rerun.controls"):
                    continue
                val = col.to_pylist()[-1]
                if isinstance(val, list) and len(val) == 1:
                    val = val[0]
                slot["static"][name] = val
            continue
        n = rb.num_rows
        for name, col in cols.items():
            if name.startswith("rerun.controls"):
                continue
            if name == "sim_time":
                vals = col.cast("int64").to_pylist()
            else:
                vals = col.to_pylist()
            slot["rows"].setdefault(name, []).extend(vals)
        for name in list(slot["rows"]):
            if name not in cols:  # component absent from this chunk
                slot["rows"][name].extend([None] * n)
    return out, footer


def _rows(ents: dict[str, dict[str, Any]], entity: str) -> dict[str, list[Any]]:
    if entity not in ents:
        raise ValueError(f"the recording lacks the entity {entity!r}: not a shipgym recording?")
    return ents[entity]["rows"]


def _sorted_by_step(rows: dict[str, list[Any]], column: str) -> tuple[NDArray[Any], Any]:
    step = np.asarray(rows["step"], dtype=np.int64)
    order = np.argsort(step, kind="stable")
    vals = rows[column]
    return step[order], [vals[i] for i in order]


def _vectors(ents: dict[str, dict[str, Any]], name: str, width: int) -> NDArray[np.float64]:
    rows = _rows(ents, f"{P.DATA}/{name}")
    _, vals = _sorted_by_step(rows, "Scalars:scalars")
    if not vals:
        return np.zeros((0, width))
    return np.array(vals, dtype=float).reshape(len(vals), -1)


def _load_rrd(path: Path) -> Run:
    try:
        ents, footer = _chunks_by_entity(path)
    except Exception as exc:  # noqa: BLE001 - any reader failure means the same to the user
        why = " ".join(str(exc).split())  # one line
        raise ValueError(
            f"cannot read the rerun recording {path}: it is truncated (an interrupted or killed "
            f"recording?) or not a rerun file ({why})"
        ) from None
    meta_doc = ents.get(P.META_JSON, {}).get("static", {}).get("TextDocument:text")
    doc: dict[str, Any] = json.loads(meta_doc) if meta_doc else {}
    metadata = dict(doc.get("metadata") or {})
    status = metadata.get("recording")
    # files recorded before the end marker existed: complete if finalised (footer)
    status = dict(status) if isinstance(status, dict) else {"complete": True, "ended": None}
    status["footer"] = footer
    metadata["recording"] = status
    if f"{P.DATA}/eta" not in ents and _status_problem(status) is not None:
        raise ValueError(
            f"{path} is an incomplete recording ({_status_problem(status)}) that holds no "
            "control step yet: nothing to read"
        )
    rows = _rows(ents, f"{P.DATA}/eta")
    step, _ = _sorted_by_step(rows, "Scalars:scalars")
    t_ns = np.asarray(rows["sim_time"], dtype=np.int64)[np.argsort(rows["step"], kind="stable")]
    static = ents.get(f"{P.DATA}/static", {}).get("static", {})
    geo = json.loads(static["TextDocument:text"]) if static else {}
    acts = geo.get("actuators") if isinstance(geo.get("actuators"), dict) else {}
    n_ch, n_act = (len(acts["channels"]), len(acts["names"])) if acts else (3, 3)
    widths = {"command": n_ch, "saturated": n_ch, "actuator_state": n_ch, "thrust": n_act}
    vec = {
        name: _vectors(ents, name, w if w is not None else widths[name])
        for name, w in DATA_VECTORS.items()
        if f"{P.DATA}/{name}" in ents or name != "actuator_state"  # older files lack it
    }
    roll = _vectors(ents, "roll", 2) if f"{P.DATA}/roll" in ents else np.zeros((0, 2))
    legs = vec.pop("leg").astype(np.int64)
    wind = vec.pop("wind")
    sat = vec.pop("saturated") > 0.5

    def acc(entity: str) -> NDArray[np.float64]:
        r = _rows(ents, entity)
        _, vals = _sorted_by_step(r, "Scalars:scalars")
        return np.array(vals, dtype=float).reshape(-1, 4)

    # measurements: the x panel holds the r-frame values, data/measurements the NED ones
    mrows = ents.get(f"{P.DATA}/measurements", {}).get("rows", {})
    if mrows.get("Scalars:scalars"):
        mt = np.asarray(np.asarray(mrows["sim_time"], dtype=np.int64) * 1e-9, dtype=float)
        mstep = np.asarray(mrows["step"], dtype=np.int64)
        m = np.array(mrows["Scalars:scalars"], dtype=float).reshape(-1, 7)
        order = np.lexsort((mt, mstep))
        mt, mstep, m = mt[order], mstep[order], m[order]
    else:
        mt, mstep, m = np.zeros(0), np.zeros(0, np.int64), np.zeros((0, 7))
    return Run(
        t=np.asarray(t_ns * 1e-9, dtype=float),
        step=step,
        leg=legs[:, 0],
        legs_completed=legs[:, 1],
        saturated=sat,
        wind=wind,
        **vec,
        meas_t=mt,
        meas_step=mstep,
        meas_z=m[:, 0:3],
        meas_z_r=m[:, 3:6],
        meas_outlier=m[:, 6] > 0.5,
        accuracy=acc(P.ACCURACY),
        accuracy_measured=acc(P.ACCURACY_MEAS),
        waypoints=_as_array("waypoints", geo.get("waypoints", [])),
        quays=_as_array("quays", geo.get("quays", [])),
        quay_names=list(geo.get("quay_names", [])),
        hull=_as_array("hull", geo.get("hull", [])),
        thrusters=_as_array("thrusters", geo.get("thrusters", [])),
        actuators=dict(acts),
        vessel=dict(geo.get("vessel") or {}),
        roll=roll,
        metadata=metadata,
        metrics=dict(doc.get("metrics") or {}),
    )


def recording_problem(run: Run) -> str | None:
    """Why ``run`` is an incomplete recording, in words; ``None`` for a complete one.

    Incomplete: the episode was stopped before its end (``metadata["recording"]["complete"]``
    false: interrupted, closed early), or the ``.rrd`` file lacks rerun's footer (the process
    was killed before the file was finalised). Runs without the marker (built in memory, or
    recorded by an older version) count as complete.
    """
    return _status_problem(run.metadata.get("recording"))


def _status_problem(status: Any) -> str | None:
    if not isinstance(status, dict):
        return None
    if status.get("footer") is False:
        return "the file has no rerun footer: the recording process was killed or crashed"
    if status.get("complete") is False:
        steps = status.get("steps")
        n = f" after {steps} steps" if isinstance(steps, int) and steps > 0 else ""
        return f"the episode was stopped before its end{n} (interrupted or closed early)"
    return None


def load_run(path: str | os.PathLike[str]) -> Run:
    """Read a run from a rerun ``.rrd`` recording or a JSON run file.

    The results file of ``shipgym run --json`` is not a run file (it holds the metrics, no
    time series) and is refused with a message saying how to record one.

    Args:
        path: a ``.rrd`` file written by :class:`~shipgym.viz.RecordEpisode` (``shipgym run
            --record RUN.rrd``), or a ``.json`` file written by :func:`save_run_json` (or the
            recorder's ``json_path``).

    The :class:`Run` returned holds one episode as NumPy arrays with a row per control step
    (``N`` rows, the reset state first; SI units, angles in rad unless named ``_deg``):

    - ``t`` (s) and ``step``, (N,);
    - ``eta`` (``x`` m, ``y`` m, ``psi`` rad, NED) and ``nu`` (``u`` m/s, ``v`` m/s,
      ``r`` rad/s, body), the truth, (N, 3); ``nav_eta``, ``nav_nu``: what the
      controller used (the truth or the observer's estimate);
    - the guidance: ``eta_d`` (desired pose), ``eta_d_r`` and ``eta_dot_d_r`` (desired
      pose and rate in the leg's r-frame), ``eta_r`` (true pose in the r-frame),
      ``eta_P`` (the leg's start), (N, 3); ``leg``, ``legs_completed``, (N,);
    - the actuators: ``command`` (each channel in its unit: ``actuators["units"]``),
      ``actuator_state``, ``saturated`` (flags), (N, channels); ``thrust`` (N), (N,
      actuators); their names in :attr:`Run.channel_names` and :attr:`Run.actuator_names`;
    - the environment: ``tau_wind`` and ``tau_waves`` (``X`` N, ``Y`` N, ``N`` N m,
      body), ``current_body`` (m/s on the body axes), (N, 3); ``wind`` (speed m/s,
      direction it comes from, rad), (N, 2);
    - ``accuracy`` and ``accuracy_measured``: the running indices ``x_E`` (m), ``y_E``
      (m), ``psi_E`` (deg), ``J_c`` from the truth and from the measurements, (N, 4);
    - ``roll`` (``phi`` rad, ``p`` rad/s) of a 4-DOF vessel, (N, 2), else (0, 2);
    - the valid position measurements, at their own times: ``meas_t`` (s),
      ``meas_step``, ``meas_z`` (NED pose), ``meas_z_r`` (r-frame), ``meas_outlier``;
    - the static data: ``waypoints``, ``quays``, ``hull``, ``thrusters`` (m), and the
      dicts ``actuators``, ``vessel``, ``metadata`` (env id, scenario, seed, observer,
      controller, wind, plan, ...) and ``metrics`` (the episode's metrics).

    :func:`shipgym.viz.export.run_columns` names every component with its unit
    (``shipgym export RUN --csv`` writes them as a table). Positions read from a
    ``.rrd`` are the float64 values of the ``data/*`` entities (the map entities hold
    the same values as float32). ``metadata["recording"]`` says whether the recording is
    complete (see :func:`recording_problem`).

    Returns:
        The :class:`Run` (above).

    Raises:
        ValueError: unknown suffix, missing file, a file that is not a shipgym run (the
            results of ``shipgym run --json`` included), or a ``.rrd`` file rerun cannot
            read (one line; e.g. cut short by a killed process).
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"run file {path} does not exist (expected a .rrd or .json file)")
    suffix = path.suffix.lower()
    if suffix == ".json":
        return _load_json(path)  # type: ignore[return-value]  # (a Run: results refused)
    if suffix == ".rrd":
        size = path.stat().st_size
        if size > MAX_RUN_RRD_BYTES:  # rerun reads a recording whole into memory
            raise ValueError(
                f"recording {path} has {size:,} bytes, more than the limit of "
                f"{MAX_RUN_RRD_BYTES:,} (a run of days records a few hundred MB)"
            )
        return _load_rrd(path)
    raise ValueError(f"unsupported run file {path}: expected a .rrd or .json file")


def indices_warning(metrics: dict[str, Any] | None, meta: dict[str, Any]) -> str | None:
    """A markdown line when a run's indices cover only part of it (failed, unfinished, short).

    ``meta`` is the run's metadata (its ``terminate_on_finish``: whether the plan ends).
    """
    if not metrics:
        return None
    note = indices_note(metrics, plan_finite=meta.get("terminate_on_finish", True))
    return None if note is None else f"**These indices do not describe a whole run**: {note}."
