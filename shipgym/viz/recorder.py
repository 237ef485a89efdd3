"""Headless rerun recording of shipgym episodes: the :class:`RecordEpisode` wrapper.

Public names: ``RecordEpisode``, ``episode_path``.

Design notes: docs/design/viz.recorder.md.
"""

from __future__ import annotations

import atexit
import copy
import datetime as _dt
import json
import math
import os
import shutil
import socket
import sys
import uuid
import weakref
from operator import attrgetter
from pathlib import Path
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from shipgym._io import partial_path, replace_together, signals_held
from shipgym.metrics import ManoeuvreMetrics
from shipgym.records import step_record

from .geometry import (
    REFERENCE_LENGTH,
    hull_outline,
    hull_polygon,
    quay_polygons,
    thrust_arrows,
    thruster_positions,
)
from .run import (
    DATA_VECTORS,
    P,
    Run,
    actuator_description,
    command_path,
    desired_body_velocity,
    indices_warning,
    save_run_json,
)
from .viewer import viewer_hint

__all__ = ["RecordEpisode", "episode_path"]

_DEG = 180.0 / math.pi
#: values buffered every step: the name (an ``info`` key and a :class:`~shipgym.viz.Run`
#: field) and where it is in the step's :class:`~shipgym.records.StepRecord`
_VEC_FIELDS = (
    ("eta", attrgetter("truth.eta")),
    ("nu", attrgetter("truth.nu")),
    ("nav_eta", attrgetter("nav.eta")),
    ("nav_nu", attrgetter("nav.nu")),
    ("eta_d", attrgetter("reference.eta_d_n")),
    ("eta_d_r", attrgetter("reference.eta_d_r")),
    ("eta_dot_d_r", attrgetter("reference.eta_dot_d_r")),
    ("eta_r", attrgetter("eta_r")),
    ("eta_P", attrgetter("reference.eta_P")),
    ("command", attrgetter("actuators.command")),
    ("thrust", attrgetter("actuators.thrust")),
    ("saturated", attrgetter("actuators.saturated")),
    ("actuator_state", attrgetter("actuators.state")),
    ("tau_wind", attrgetter("tau_wind")),
    ("tau_waves", attrgetter("tau_waves")),
    ("current_body", attrgetter("current_body")),
)
_VEC_KEYS = tuple(k for k, _ in _VEC_FIELDS)
#: port of a spawned rerun viewer, and the longest wait for the sinks at the end (s).
VIEWER_PORT = 9876
FLUSH_TIMEOUT = 60.0
#: Lengths on the map are given for a hull of REFERENCE_LENGTH and multiplied by
#: ``L_oa / REFERENCE_LENGTH``: the arrow of an actuator at full thrust (m), the wind arrow
#: per m/s (m), map margins and line widths.
THRUST_ARROW_LENGTH = 4.0
WIND_ARROW_SCALE = 2.0

# colours (RGBA)
_C_TRUTH = (235, 235, 235, 255)
_C_REF = (255, 160, 40, 255)
_C_EST = (220, 80, 220, 255)
_C_MEAS = (80, 200, 120, 255)
_C_OUTLIER = (255, 60, 60, 255)
_C_HULL = (255, 215, 0, 255)
_C_TRACE = (255, 215, 0, 110)
_C_QUAY = (150, 150, 140, 255)
_C_PLAN = (255, 160, 40, 160)
_C_WIND = (120, 190, 255, 255)
_SERIES_COLORS = [_C_REF, _C_TRUTH, _C_EST]
_C_PLOT_BACKGROUND = (24, 28, 34, 255)
#: what the colours of the time series mean (the plots have no legend: see _blueprint)
PLOT_KEY = (
    "Plots: orange desired, white true, magenta estimate, green DGPS fix; thrust and commands "
    "in the colour of the actuator's arrow on the map. Hover a curve for its name."
)


_LIVE: weakref.WeakSet[RecordEpisode] = weakref.WeakSet()
_ATEXIT = False


def _release_streams() -> None:
    """Free the threads of the recording streams nobody holds any longer: rerun keeps a
    dropped Python stream's native threads (a batcher, a writer) until asked, so a process
    recording thousands of episodes would gather thousands of idle threads."""
    import gc

    import rerun as rr

    cleanup = getattr(getattr(rr, "bindings", None), "flush_and_cleanup_orphaned_recordings", None)
    if cleanup is not None:
        gc.collect(0)  # the young generation holds the last episode's stream
        cleanup()


def _send_blueprint(rec: Any, blueprint: Any) -> None:
    """``rec.send_blueprint(blueprint)`` (active and default), without its thread leak: rerun
    0.41 builds the blueprint in a stream of its own whose two native threads outlive it, two
    threads per episode for ever; that stream is disconnected here once its contents are sent.
    Falls back to the public call where rerun's internals differ."""
    try:
        from rerun import bindings
        from rerun.recording_stream import RecordingStream, get_application_id

        stream = RecordingStream._from_native(
            bindings.new_blueprint(application_id=get_application_id(recording=rec),
                                   make_default=False, make_thread_default=False,
                                   default_enabled=True)
        )  # fmt: skip
    except (ImportError, AttributeError, TypeError):
        rec.send_blueprint(blueprint, make_active=True, make_default=True)
        return
    try:
        stream.set_time("blueprint", sequence=0)
        blueprint.to_blueprint()._log_to_stream(stream)
        storage = stream.memory_recording().storage
        bindings.send_blueprint(storage, True, True, recording=rec.to_native())
    finally:
        stream.disconnect()


def _finish_all() -> None:
    """At interpreter exit: finish the files of recorders nobody closed."""
    for recorder in list(_LIVE):
        try:
            recorder._finish(None)
        except Exception:  # noqa: BLE001, S110 - best effort at exit
            pass


def episode_path(path: str | os.PathLike[str], episode: int) -> Path:
    """The file of episode ``episode`` (0-based) for a recording path.

    ``{episode}`` in the path is replaced by the number; otherwise episode 0 uses the path
    itself and episode k >= 1 ``<stem>-<k><suffix>``.
    """
    text = os.fspath(path)
    if "{episode}" in text:
        return Path(text.replace("{episode}", str(episode)))
    p = Path(text)
    return p if episode == 0 else p.with_name(f"{p.stem}-{episode}{p.suffix}")


def _check_writable(path: Path, suffix: str, what: str) -> None:
    """Create the parent folders and make sure ``path`` can be written (ValueError if not)."""
    if path.suffix.lower() != suffix:
        raise ValueError(f"{what} {path} must end with {suffix}")
    if path.is_dir():
        raise ValueError(f"cannot record to {path}: it is a directory; give a {suffix} file")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(
            f"cannot record to {path}: cannot create the folder {path.parent} "
            f"({exc.strerror or exc}); choose a writable {what}"
        ) from None
    existed = path.exists()
    try:
        with open(path, "ab"):
            pass
    except OSError as exc:
        raise ValueError(
            f"cannot record to {path}: the file is not writable ({exc.strerror or exc}); "
            f"choose a writable {what}"
        ) from None
    if not existed:
        path.unlink(missing_ok=True)


def _stack(items: list[Any], n: int, width: int = 3) -> NDArray[np.float64]:
    if not items:
        return np.zeros((0, width))
    return np.asarray(items, dtype=float).reshape(n, width)


def _rgba(colour: str) -> tuple[int, int, int, int]:
    """``#rrggbb`` -> an RGBA tuple (opaque); mid grey for anything else."""
    c = colour.lstrip("#")
    try:
        return (int(c[0:2], 16), int(c[2:4], 16), int(c[4:6], 16), 255)
    except (ValueError, IndexError):
        return (128, 128, 128, 255)


def _command_groups(units: tuple[str, ...]) -> list[tuple[str, list[int]]]:
    """Channels grouped by command unit, in order of first appearance: ``(unit, [index])``."""
    groups: dict[str, list[int]] = {}
    for i, u in enumerate(units):
        groups.setdefault(u, []).append(i)
    return list(groups.items())


def _find_attr(env: gym.Env[Any, Any], name: str) -> Any:
    """The first ``name`` attribute found walking down a wrapper stack (None if none)."""
    e: Any = env
    while e is not None:
        if name in vars(e):
            return vars(e)[name]
        e = getattr(e, "env", None)
    return None


def _viewer_executable() -> str | None:
    exe = shutil.which("rerun")
    if exe:
        return exe
    cand = Path(sys.executable).parent / "rerun"
    return str(cand) if cand.exists() else None


class _Episode:
    """Buffers, derived quantities and the rerun stream of one episode."""

    def __init__(self, rec: Any, path: Path, json_path: Path | None, ctx: dict[str, Any]):
        self.rec = rec
        self.path = path  # the final name; the episode records to self.tmp
        self.tmp = partial_path(path)
        self.json_path = json_path
        self.ctx = ctx
        self.t: list[float] = []
        self.vec: dict[str, list[Any]] = {k: [] for k in _VEC_KEYS}
        self.legs: list[tuple[int, int]] = []
        self.roll: list[tuple[float, float]] | None = [] if ctx["dofs"] == 4 else None
        self.meas: list[tuple[float, int, Any, bool]] = []
        # derived, per flushed block
        self.blocks: dict[str, list[NDArray[Any]]] = {
            k: [] for k in ("wind", "acc", "acc_meas", "meas_r")
        }
        self.rows_done = 0
        self.meas_done = 0
        # running accuracy (Tomera 2014 eqs. 54-57): the env's own metrics, fed the rows
        self.sample_period = float(ctx["sample_period"])
        self.metrics = ManoeuvreMetrics(self.sample_period, ctx["weights"])
        self.last_z: NDArray[np.float64] | None = None
        self.next_trace = 0.0
        self.prev_leg: int | None = None

    # -- hot path ------------------------------------------------------------------------------
    def capture(self, info: dict[str, Any]) -> None:
        """Buffer one control step (cheap: references only), from the step's
        :class:`~shipgym.records.StepRecord` (``info["record"]``)."""
        rec = step_record(info)
        i = len(self.t)
        self.t.append(float(rec.t))
        vec = self.vec
        for k, get in _VEC_FIELDS:
            vec[k].append(get(rec))
        if self.roll is not None:
            self.roll.append((info["phi"], info["p"]))
        ref = rec.reference
        self.legs.append((ref.leg, rec.legs_completed))
        for m in rec.measurements:
            if m.z is not None:
                self.meas.append((m.t, i, m.z, m.outlier))

    @property
    def pending(self) -> int:
        return len(self.t) - self.rows_done

    # -- columns -------------------------------------------------------------------------------
    def flush(self) -> None:
        """Send the buffered rows to the recording as columns.

        An interrupt (Ctrl-C, SIGTERM) on the way leaves the state a flush changes as it was
        (the running indices, the last fix, the leg and hull-trace marks): the clean-up's
        flush sends the same rows again from the same state, and the block is booked (its
        derived rows kept, the rows marked done) with the signals held."""
        saved = (copy.deepcopy(self.metrics), self.last_z, self.prev_leg, self.next_trace)
        booked = self.rows_done, self.meas_done
        try:
            self._send()
        except BaseException:
            if (self.rows_done, self.meas_done) == booked:
                self.metrics, self.last_z, self.prev_leg, self.next_trace = saved
            raise

    def _send(self) -> None:
        """:meth:`flush`'s work."""
        import rerun as rr

        i0, i1 = self.rows_done, len(self.t)
        j0, j1 = self.meas_done, len(self.meas)
        if i1 == i0 and j1 == j0:
            return
        n = i1 - i0
        rec = self.rec
        t = np.asarray(self.t[i0:i1], dtype=float)
        steps = np.arange(i0, i1)
        idx = [rr.TimeColumn("sim_time", duration=t), rr.TimeColumn("step", sequence=steps)]
        widths = self.ctx["widths"]
        v = {k: _stack(self.vec[k][i0:i1], n, widths[k]) for k in _VEC_KEYS}
        legs = np.asarray(self.legs[i0:i1], dtype=float).reshape(n, 2)
        eta, eta_d_r = v["eta"], v["eta_d_r"]
        nu_d = desired_body_velocity(eta_d_r, v["eta_dot_d_r"])
        nav_r = _to_r(v["nav_eta"], v["eta_P"], eta_d_r[:, 2])
        wind = self._wind(t)

        # measurements of these rows: r-frame of the row they arrived in
        ms = self.meas[j0:j1]
        m_t = np.array([m[0] for m in ms], dtype=float)
        m_step = np.array([m[1] for m in ms], dtype=np.int64)
        m_z = _stack([m[2] for m in ms], len(ms))
        m_out = np.array([m[3] for m in ms], dtype=bool)
        rows = m_step - i0
        m_zr = _to_r(m_z, v["eta_P"][rows], eta_d_r[rows, 2]) if len(ms) else np.zeros((0, 3))
        acc, acc_m = self._accuracy(t, v["eta_r"], eta_d_r, v["eta_P"], m_step, m_z)

        # ---- map -----------------------------------------------------------------------------
        zeros = np.zeros((n, 1))
        half = 0.5 * eta[:, 2]
        quat = np.column_stack([zeros, zeros, np.sin(half), np.cos(half)])
        rec.send_columns(
            P.SHIP,
            idx,
            rr.Transform3D.columns(
                translation=np.column_stack([eta[:, :2], zeros]), quaternion=quat
            ),
        )
        acts = self.ctx["actuators"]
        n_act = len(acts)
        vectors = thrust_arrows(acts, v["actuator_state"], self.ctx["arrow_length"], v["thrust"])
        origins = np.broadcast_to(self.ctx["thrusters"], (n, n_act, 2)).reshape(-1, 2)
        rec.send_columns(
            P.THRUST,
            idx,
            rr.Arrows2D.columns(vectors=vectors.reshape(-1, 2), origins=origins).partition(
                [n_act] * n
            ),
        )
        rec.send_columns(P.TRACK_TRUTH, idx, rr.Points2D.columns(positions=eta[:, :2]))
        rec.send_columns(P.TRACK_REF, idx, rr.Points2D.columns(positions=v["eta_d"][:, :2]))
        differs = np.any(v["nav_eta"] != eta, axis=1)
        if np.any(differs):
            sel = np.flatnonzero(differs)
            rec.send_columns(
                P.TRACK_EST,
                [
                    rr.TimeColumn("sim_time", duration=t[sel]),
                    rr.TimeColumn("step", sequence=steps[sel]),
                ],
                rr.Points2D.columns(positions=v["nav_eta"][sel, :2]),
            )
        if len(ms):
            for ent, sel in ((P.DGPS, ~m_out), (P.DGPS_OUTLIERS, m_out)):
                if np.any(sel):
                    rec.send_columns(
                        ent,
                        [
                            rr.TimeColumn("sim_time", duration=m_t[sel]),
                            rr.TimeColumn("step", sequence=m_step[sel]),
                        ],
                        rr.Points2D.columns(positions=m_z[sel, :2]),
                    )
        self._log_target(legs, t, steps)
        self._log_hull_trace(t, steps, eta)
        if wind is not None:
            to = wind[:, 1] + math.pi
            length = WIND_ARROW_SCALE * self.ctx["scale"] * wind[:, :1]
            vec = length * np.column_stack([np.cos(to), np.sin(to)])
            anchor = self.ctx["wind_anchor"]
            labels = [
                f"wind {s:.1f} m/s from {math.degrees(b) % 360.0:.0f}°" for s, b in wind.tolist()
            ]
            rec.send_columns(
                P.WIND,
                idx,
                rr.Arrows2D.columns(vectors=vec, origins=anchor - 0.5 * vec, labels=labels),
            )

        # ---- time series ---------------------------------------------------------------------
        def scal(entity: str, arr: NDArray[np.float64], index: Any = idx) -> None:
            rec.send_columns(entity, index, rr.Scalars.columns(scalars=arr))

        deg = np.array([1.0, 1.0, _DEG])
        pos = np.stack([eta_d_r, v["eta_r"], nav_r], axis=2) * deg[None, :, None]
        vel = np.stack([nu_d, v["nu"], v["nav_nu"]], axis=2) * deg[None, :, None]
        for k, dof in enumerate(("x", "y", "psi")):
            scal(f"{P.POSITION}/{dof}", pos[:, k, :])
        for k, dof in enumerate(("u", "v", "r")):
            scal(f"{P.VELOCITY}/{dof}", vel[:, k, :])
        if len(ms):
            m_idx = [
                rr.TimeColumn("sim_time", duration=m_t),
                rr.TimeColumn("step", sequence=m_step),
            ]
            for k, dof in enumerate(("x", "y", "psi")):
                scal(f"{P.POSITION}/{dof}/measured", m_zr[:, k] * deg[k], m_idx)
            scal(
                f"{P.DATA}/measurements",
                np.column_stack([m_z, m_zr, m_out.astype(float)]),
                m_idx,
            )
        scal(P.PLOT_THRUST, v["thrust"])
        for unit, cols in _command_groups(acts.units):
            scal(command_path(unit), v["command"][:, cols])
        if self.roll is not None:
            roll = _stack(self.roll[i0:i1], n, 2)
            scal(P.ROLL, roll * _DEG)
            scal(f"{P.DATA}/roll", roll)
        scal(P.ACCURACY, acc)
        scal(P.ACCURACY_MEAS, acc_m)
        scal("plots/disturbances/wind_load", v["tau_wind"])
        scal("plots/disturbances/wave_drift", v["tau_waves"])
        scal("plots/disturbances/current_body", v["current_body"][:, :2])
        data = dict(v)
        data["leg"] = legs
        data["wind"] = wind if wind is not None else np.full((n, 2), np.nan)
        for name in DATA_VECTORS:
            scal(f"{P.DATA}/{name}", np.asarray(data[name], dtype=float))

        with signals_held():  # the block's rows and its booking together, or neither
            self.blocks["wind"].append(data["wind"])
            self.blocks["acc"].append(acc)
            self.blocks["acc_meas"].append(acc_m)
            self.blocks["meas_r"].append(m_zr)
            self.rows_done, self.meas_done = i1, j1

    def _wind(self, t: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """``[speed (m/s), from (rad)]`` at the times ``t``, or None without aerodynamics."""
        phys = self.ctx["physics"]
        if phys is None or not getattr(phys, "aerodynamics", True):
            return None
        try:
            speed, beta = phys.wind.series(t)
        except Exception:  # noqa: BLE001 - the wind model is optional for the recording
            cfg = getattr(phys, "wind_config", None)
            if cfg is None:
                return None
            speed = np.full(len(t), float(cfg.speed))
            beta = np.full(len(t), float(cfg.direction_from))
        return np.column_stack([speed, beta])

    def _accuracy(
        self,
        t: NDArray[np.float64],
        eta_r: NDArray[np.float64],
        eta_d_r: NDArray[np.float64],
        eta_P: NDArray[np.float64],
        m_step: NDArray[np.int64],
        m_z: NDArray[np.float64],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Running Tomera (2014) indices ``[x_E, y_E, psi_E (deg), J_c]`` (truth, measured)
        after each row: :class:`~shipgym.metrics.ManoeuvreMetrics` fed the rows as the env
        feeds it (the last valid fix in the r-frame of the row's leg as the measured pose)."""
        n = len(t)
        out = np.full((n, 4), np.nan)
        out_m = np.full((n, 4), np.nan)
        fix = np.full((n, 3), np.nan)  # each row's last valid fix (NaN before the first)
        i0, j, steps = self.rows_done, 0, m_step.tolist()
        for i in range(n):
            while j < len(steps) and steps[j] <= i0 + i:
                self.last_z = m_z[j]
                j += 1
            if self.last_z is not None:
                fix[i] = self.last_z
        meas = _to_r(fix, eta_P, eta_d_r[:, 2])
        m = self.metrics
        for i, (ti, has) in enumerate(zip(t.tolist(), (fix[:, 0] == fix[:, 0]).tolist(),
                                          strict=True)):  # fmt: skip
            m.record(ti, eta_r[i], eta_d_r[i], eta_meas_r=meas[i] if has else None)
            for row, ind in zip((out, out_m), m.indices(), strict=True):
                if ind is not None:
                    row[i] = (ind["x_E"], ind["y_E"], ind["psi_E"], ind["J_c"])
        return out, out_m

    def _log_target(
        self, legs: NDArray[np.float64], t: NDArray[np.float64], steps: NDArray[np.int64]
    ) -> None:
        import rerun as rr

        wp = self.ctx["waypoints"]
        if len(wp) < 2:
            return
        leg = legs[:, 0].astype(int)
        prev = np.concatenate([[-1 if self.prev_leg is None else self.prev_leg], leg[:-1]])
        sel = np.flatnonzero(leg != prev)
        self.prev_leg = int(leg[-1])
        if not len(sel):
            return
        k = np.clip(leg[sel] + 1, 1, len(wp) - 1)
        self.rec.send_columns(
            P.TARGET,
            [
                rr.TimeColumn("sim_time", duration=t[sel]),
                rr.TimeColumn("step", sequence=steps[sel]),
            ],
            rr.Points2D.columns(positions=wp[k, :2], labels=[f"K{int(x)}" for x in k]),
        )

    def _log_hull_trace(
        self, t: NDArray[np.float64], steps: NDArray[np.int64], eta: NDArray[np.float64]
    ) -> None:
        import rerun as rr

        every = self.ctx["hull_every"]
        if not every or every <= 0:
            return
        sel = []
        for i, ti in enumerate(t.tolist()):
            if ti >= self.next_trace - 1e-9:
                sel.append(i)
                self.next_trace = (math.floor(ti / every + 1e-9) + 1) * every
        if not sel:
            return
        strips = [hull_polygon(self.ctx["hull"], eta[i]) for i in sel]
        self.rec.send_columns(
            P.HULL_TRACE,
            [
                rr.TimeColumn("sim_time", duration=t[sel]),
                rr.TimeColumn("step", sequence=steps[sel]),
            ],
            rr.LineStrips2D.columns(strips=strips),
        )

    # -- end -----------------------------------------------------------------------------------
    def to_run(self, metrics: dict[str, Any]) -> Run:
        """The flushed rows as a :class:`Run` (float64, exactly the ``info`` values)."""
        n = self.rows_done
        widths = self.ctx["widths"]
        v = {k: _stack(self.vec[k][:n], n, widths[k]) for k in _VEC_KEYS}
        legs = np.asarray(self.legs[:n], dtype=np.int64).reshape(n, 2)
        ms = self.meas[: self.meas_done]

        def cat(name: str, width: int) -> NDArray[np.float64]:
            b = self.blocks[name]
            return np.concatenate(b) if b else np.zeros((0, width))

        ctx = self.ctx
        return Run(
            t=np.asarray(self.t[:n], dtype=float),
            step=np.arange(n, dtype=np.int64),
            **{k: v[k] for k in _VEC_KEYS if k != "saturated"},
            saturated=v["saturated"] > 0.5,
            leg=legs[:, 0],
            legs_completed=legs[:, 1],
            wind=cat("wind", 2),
            meas_t=np.array([m[0] for m in ms], dtype=float),
            meas_step=np.array([m[1] for m in ms], dtype=np.int64),
            meas_z=_stack([m[2] for m in ms], len(ms)),
            meas_z_r=cat("meas_r", 3),
            meas_outlier=np.array([m[3] for m in ms], dtype=bool),
            accuracy=cat("acc", 4),
            accuracy_measured=cat("acc_meas", 4),
            waypoints=np.asarray(ctx["waypoints"], dtype=float),
            quays=np.asarray(ctx["quays"], dtype=float),
            quay_names=list(ctx["quay_names"]),
            hull=np.asarray(ctx["hull"], dtype=float),
            thrusters=np.asarray(ctx["thrusters"], dtype=float),
            actuators=actuator_description(ctx["actuators"]),
            vessel=dict(ctx["vessel"]),
            roll=_stack(self.roll[:n], n, 2) if self.roll is not None else np.zeros((0, 2)),
            metadata=dict(ctx["metadata"]),
            metrics=metrics,
        )


def _to_r(eta: NDArray[np.float64], eta_P: NDArray[np.float64], psi_ref: Any) -> Any:
    from shipgym.guidance import to_r_frame

    if len(eta) == 0:
        return np.zeros((0, 3))
    return to_r_frame(eta, eta_P, psi_ref_r=psi_ref)


class RecordEpisode(
    gym.Wrapper[Any, Any, Any, Any],
    gym.utils.RecordConstructorArgs,
):
    """Records every episode to a rerun ``.rrd`` file, headless (stack it outermost).

    Logs a top-down map in NED metres with north up (quays, planned path and current leg end
    point, the hull outline at every control step, true, desired, estimated and measured
    positions, a thrust arrow per actuator along its force, a wind arrow), time series of the
    r-frame pose and body velocity (desired, true, estimate, measured), the actuators'
    commands (one plot per command unit) and thrusts, the running accuracy indices of Tomera
    (2014) eqs. 54-57, and the run's metadata; entity paths in :mod:`shipgym.viz.run`. The
    file opens in the rerun viewer with the map on the left and the time series on the right
    (``rerun PATH.rrd``; without a display rerun's web viewer: :func:`~shipgym.viz.viewer_hint`).

    Values are buffered per step and written in columns every ``flush_every`` steps, at the
    end of an episode, in :meth:`close` and when the wrapper is garbage collected: an episode
    interrupted (e.g. by ``KeyboardInterrupt`` in the caller's loop) leaves a readable file
    with every step taken so far once ``env.close()`` runs, named ``<stem>.partial.rrd``. An
    episode records to that partial name and is renamed onto the final one only when it ends
    (terminated or truncated), so an earlier recording at the final name is replaced only by a
    complete one (see the module docstring). An episode closed before any step is discarded.

    Args:
        env: a shipgym environment of any vessel, possibly under observer and controller
            wrappers (``shipgym.make(..., observer=..., controller=...)``).
        path: the ``.rrd`` file of the first episode; later episodes go to
            ``<stem>-<k>.rrd`` (or replace ``{episode}`` in the path). Parent folders are
            created; a path that cannot be written raises ``ValueError`` here, before any
            episode starts.
        spawn: also stream to a rerun viewer (spawned once). Without a display or a viewer
            executable a message says so and the recording goes to the file only.
        flush_every: control steps buffered between two writes (>= 1).
        json_path: also write each episode as a JSON run file (:func:`save_run_json`), named
            like the ``.rrd`` files (and renamed with them).
        hull_every: period (s) of the hull outlines kept on the map as a trace (0: none).
        rename: rename an ended episode's files onto their final names (``False``: leave them
            at the partial names and list them in :attr:`ended`, for a caller that renames
            them together with files of its own, e.g. ``shipgym run --json``).

    Attributes:
        paths: where the ``.rrd`` files written so far are (one per episode; a partial name
            for an episode stopped before its end, or not renamed with ``rename=False``).
        json_paths: the JSON run files written so far, likewise.
        ended: ``(partial, final)`` name pairs of the ended episodes' files not renamed yet
            (``rename=False`` only).
        last_run: the :class:`~shipgym.viz.Run` of the last finished episode (float64).

    Note:
        Records its constructor arguments, so ``gym.make(env.spec)`` rebuilds the stack.
    """

    def __init__(
        self,
        env: gym.Env[Any, Any],
        path: str | os.PathLike[str],
        *,
        spawn: bool = False,
        flush_every: int = 100,
        json_path: str | os.PathLike[str] | None = None,
        hull_every: float = 60.0,
        rename: bool = True,
    ) -> None:
        gym.utils.RecordConstructorArgs.__init__(
            self,
            path=os.fspath(path),
            spawn=spawn,
            flush_every=flush_every,
            json_path=None if json_path is None else os.fspath(json_path),
            hull_every=hull_every,
            rename=rename,
        )
        gym.Wrapper.__init__(self, env)
        self._episode: _Episode | None = None
        if isinstance(flush_every, bool) or not isinstance(flush_every, int) or flush_every < 1:
            raise ValueError(
                f"flush_every must be an int >= 1 (control steps), got {flush_every!r}"
            )
        if not (isinstance(hull_every, int | float) and math.isfinite(hull_every)):
            raise ValueError(f"hull_every must be a finite number of seconds, got {hull_every!r}")
        self.path = Path(os.fspath(path)).expanduser()
        self.json_path = None if json_path is None else Path(os.fspath(json_path)).expanduser()
        _check_writable(episode_path(self.path, 0), ".rrd", "recording path")
        if self.json_path is not None:
            _check_writable(episode_path(self.json_path, 0), ".json", "JSON run path")
        self.spawn = bool(spawn)
        self.flush_every = flush_every
        self.hull_every = float(hull_every)
        self.rename = bool(rename)
        self.paths: list[Path] = []
        self.json_paths: list[Path] = []
        self.ended: list[tuple[Path, Path]] = []
        self.last_run: Run | None = None
        self._n_episodes = 0
        self._viewer: bool | None = None  # None: not tried yet

    # ---- gym API -----------------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Finish the previous episode's file, reset the env and start a new recording."""
        ep = self._episode
        if ep is not None:
            if len(ep.t) > 1:
                self._finish(None)
            else:  # reset twice in a row: the new episode replaces the empty one
                self._discard()
        obs, info = self.env.reset(seed=seed, options=options)
        self._start(seed, options)
        ep = self._episode
        if ep is not None:
            ep.capture(info)
        return obs, info

    def step(self, action: Any) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the env and buffer the step (written every ``flush_every`` steps)."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        ep = self._episode
        if ep is not None:
            ep.capture(info)
            if terminated or truncated:
                self._finish("terminated" if terminated else "truncated")
            elif ep.pending >= self.flush_every:
                ep.flush()
        return obs, reward, terminated, truncated, info

    def close(self) -> None:
        """Write what is buffered, finish the file, then close the env."""
        try:
            self._finish(None)
        finally:
            _release_streams()
            super().close()

    def __del__(self) -> None:
        try:
            self._finish(None)
        except Exception:  # noqa: BLE001, S110 - nothing can be reported from a finaliser
            pass

    # ---- episodes ----------------------------------------------------------------------------
    def _start(self, seed: int | None, options: dict[str, Any] | None) -> None:
        import rerun as rr

        _release_streams()  # the finished episodes' streams and their threads
        global _ATEXIT
        if not _ATEXIT:  # registered after rerun's own handler, so it runs before it
            atexit.register(_finish_all)
            _ATEXIT = True
        _LIVE.add(self)

        k = self._n_episodes
        path = episode_path(self.path, k)
        json_path = None if self.json_path is None else episode_path(self.json_path, k)
        if k:
            _check_writable(path, ".rrd", "recording path")
        ctx = self._context(seed)
        rec = rr.RecordingStream(
            "shipgym", recording_id=f"{ctx['metadata']['run_id']}", send_properties=True
        )
        blueprint = _blueprint(ctx)
        episode = _Episode(rec, path, json_path, ctx)
        self._open_sinks(rec, episode.tmp, blueprint)
        self._episode = episode
        _log_static(rec, ctx)

    def _open_sinks(self, rec: Any, path: Path, blueprint: Any) -> None:
        import rerun as rr

        if self.spawn and self._viewer is None:
            reason = None
            exe = _viewer_executable()
            if sys.platform.startswith("linux") and not (
                os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
            ):
                reason = "no display (DISPLAY and WAYLAND_DISPLAY are unset)"
            elif exe is None:
                reason = "the rerun viewer executable was not found (pip install rerun-sdk)"
            else:
                try:
                    rr.spawn(port=VIEWER_PORT, connect=False, executable_path=exe, recording=rec)
                    with socket.create_connection(("127.0.0.1", VIEWER_PORT), timeout=2.0):
                        pass
                except Exception as exc:  # noqa: BLE001 - any failure: keep recording
                    reason = f"the viewer did not start: {exc}"
            self._viewer = reason is None
            if reason is not None:
                final = episode_path(self.path, self._n_episodes)  # path: its partial file
                print(
                    f"shipgym: no rerun viewer available ({reason}); recording to {final} "
                    f"only. Once it is written, {viewer_hint(final)}",
                    file=sys.stderr,
                )
        if self.spawn and self._viewer:
            url = f"rerun+http://127.0.0.1:{VIEWER_PORT}/proxy"
            rec.set_sinks(rr.FileSink(path), rr.GrpcSink(url))
        else:
            rec.save(path)  # the footer (manifest) is written when the sink is finalised
        _send_blueprint(rec, blueprint)

    def _context(self, seed: int | None) -> dict[str, Any]:
        """Static facts of the episode: geometry, metadata, constants for the hot path."""
        base: Any = self.env.unwrapped
        phys: Any = getattr(base, "physics", None)
        model: Any = getattr(phys, "model", None)
        data: Any = getattr(phys, "data", None)
        guidance: Any = getattr(base, "guidance", None)
        try:
            waypoints = np.asarray(guidance.waypoints, dtype=float).reshape(-1, 3)
        except Exception:  # noqa: BLE001 - a task without guidance has no plan to draw
            waypoints = np.zeros((0, 3))
        if model is not None and data is not None:
            quay_names, quays = quay_polygons(model, data)
        else:
            quay_names, quays = [], np.zeros((0, 4, 2))
        vessel: Any = getattr(base, "vessel", None)
        actuators: Any = getattr(base, "actuators", None)
        if vessel is None or actuators is None or model is None:
            raise ValueError(
                "RecordEpisode needs a shipgym environment (with a vessel, its actuators and a "
                f"MuJoCo model) under its wrappers, got {type(base).__name__}"
            )
        scale = float(vessel.L_oa) / REFERENCE_LENGTH
        # map extent: quays, else the plan, with margins (m)
        pts = quays.reshape(-1, 2) if len(quays) else waypoints[:, :2]
        if len(pts) == 0:
            pts = np.zeros((1, 2))
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        if not len(quays):
            lo, hi = lo - 15.0 * scale, hi + 15.0 * scale
        wind_anchor = np.array([hi[0] + 6.0 * scale, lo[1] + 6.0 * scale])
        widths = {k: 3 for k in _VEC_KEYS}
        widths.update(
            command=actuators.n_channels,
            saturated=actuators.n_channels,
            actuator_state=actuators.n_channels,
            thrust=len(actuators),
        )
        metrics_obj = getattr(base, "metrics", None)
        from shipgym.metrics import SEED_WEIGHTS

        ctx: dict[str, Any] = {
            "physics": phys,
            "waypoints": waypoints,
            "quays": quays,
            "quay_names": quay_names,
            "hull": hull_outline(model),
            "thrusters": thruster_positions(actuators),
            "actuators": actuators,
            "dofs": int(vessel.dofs),
            "vessel": {
                "name": str(vessel.name),
                "title": str(vessel.title),
                "dofs": int(vessel.dofs),
                "L_oa": float(vessel.L_oa),
                "B": float(vessel.B),
            },
            "scale": scale,
            "arrow_length": THRUST_ARROW_LENGTH * scale,
            "widths": widths,
            "extent": (lo, hi),
            "wind_anchor": wind_anchor,
            "sample_period": float(getattr(metrics_obj, "sample_period", 1.0)),
            "weights": tuple(getattr(metrics_obj, "weights", SEED_WEIGHTS)),
            "hull_every": self.hull_every,
        }
        ctx["metadata"] = self._describe(seed, base, phys, guidance)
        return ctx

    def _describe(self, seed: int | None, base: Any, phys: Any, guidance: Any) -> dict[str, Any]:
        import rerun as rr

        import shipgym
        from shipgym.envs.registration import SCENARIOS

        spec = self.env.spec
        env_id = spec.id if spec is not None else type(base).__name__
        scenario = next((k for k, v in SCENARIOS.items() if v == env_id), env_id)
        if seed is None:
            seed = getattr(base, "np_random_seed", None)
        observer = _find_attr(self.env, "observer_name") or "truth"
        controller = _find_attr(self.env, "controller_name") or "none"
        wind: dict[str, Any] | None = None
        cfg = getattr(phys, "wind_config", None)
        if cfg is not None and getattr(phys, "aerodynamics", True):
            wind = {
                "speed": float(cfg.speed),
                "from_deg": math.degrees(float(cfg.direction_from)) % 360.0,
                "gust_std": None if cfg.gust_std is None else float(cfg.gust_std),
                "coefficients": str(getattr(cfg, "coefficients", "")),
            }
        plan = getattr(guidance, "plan", None)
        legs = [str(getattr(leg, "name", "")) for leg in getattr(plan, "legs", ())]
        thr = base.actuators
        limits = [np.asarray(thr.lower, float).tolist(), np.asarray(thr.upper, float).tolist()]
        now = _dt.datetime.now(_dt.UTC)
        run_id = f"{scenario}-seed{seed}-{now:%Y%m%dT%H%M%S}-{uuid.uuid4().hex[:6]}"
        return {
            "run_id": run_id,
            "env_id": env_id,
            "scenario": scenario,
            "vessel": str(base.vessel.name),
            "seed": None if seed is None else int(seed),
            "observer": str(observer),
            "controller": str(controller),
            "wind": wind,
            "plan": getattr(plan, "name", None),
            "legs": legs,
            "terminate_on_finish": bool(getattr(base, "terminate_on_finish", True)),
            "scene": getattr(base, "scene", None),
            "control_period_s": float(getattr(base, "control_period", float("nan"))),
            "timestep_s": float(getattr(phys, "timestep", float("nan"))),
            "sensors": repr(getattr(base, "sensor_config", None)),
            "command_limits": limits,
            "episode": self._n_episodes,
            "recorded_at": now.isoformat(timespec="seconds"),
            "shipgym_version": shipgym.__version__,
            "rerun_version": rr.__version__,
        }

    def _episode_metrics(self) -> dict[str, Any]:
        fn = getattr(self.env.unwrapped, "episode_metrics", None)
        if fn is None:
            return {}
        try:
            return dict(fn())
        except Exception:  # noqa: BLE001 - metrics are a bonus in the file
            return {}

    def _finish(self, ended: str | None) -> None:
        """Flush, log the metrics and the end marker, write the JSON file, close the recording.

        ``ended``: ``"terminated"`` or ``"truncated"`` when the episode reached its end (the
        files are then renamed onto their final names), ``None`` when it was stopped before.
        An episode stopped before its first step is discarded.
        """
        ep = self._episode
        if ep is None:
            return
        if ended is None and len(ep.t) <= 1:
            self._discard()
            return
        self._episode = None
        status = {"complete": ended is not None, "ended": ended, "steps": len(ep.t) - 1}
        json_tmp = None if ep.json_path is None else partial_path(ep.json_path)
        try:
            ep.flush()
            metrics = self._episode_metrics()
            run = ep.to_run(metrics)
            run.metadata["recording"] = dict(status)
            _log_summary(ep.rec, ep.ctx, metrics, len(ep.t) - 1, status)
            if json_tmp is not None:
                save_run_json(run, json_tmp)
            self.last_run = run
        finally:
            try:
                ep.rec.flush(timeout_sec=FLUSH_TIMEOUT)
            except RuntimeError as exc:  # a viewer that went away; the file is complete
                print(f"shipgym: rerun flush: {exc}", file=sys.stderr)
            ep.rec.disconnect()  # finalises the file (footer)
            self._n_episodes += 1
        moves = [(ep.tmp, ep.path)]
        if json_tmp is not None and ep.json_path is not None and json_tmp.is_file():
            moves.append((json_tmp, ep.json_path))
        if ended is not None and self.rename:
            replace_together(moves)
            done = [dst for _, dst in moves]
        else:
            if ended is not None:
                self.ended += moves
            done = [src for src, _ in moves]
        self.paths.append(done[0])
        self.json_paths += done[1:]

    def _discard(self) -> None:
        """Drop the current episode and its partial file."""
        ep = self._episode
        self._episode = None
        if ep is not None:
            ep.rec.disconnect()
            ep.tmp.unlink(missing_ok=True)


# ---- static content and blueprint ------------------------------------------------------------
def _log_static(rec: Any, ctx: dict[str, Any]) -> None:
    import rerun as rr

    # north up, east right: NED x -> screen up, NED y -> screen right
    rec.log(
        P.NED,
        rr.Transform3D(rotation=rr.RotationAxisAngle(axis=[0, 0, 1], degrees=-90.0)),
        static=True,
    )
    quays = ctx["quays"]
    if len(quays):
        strips = [np.vstack([q, q[:1]]) for q in quays]
        rec.log(
            P.QUAYS,
            rr.LineStrips2D(
                strips, radii=0.12, colors=[_C_QUAY], labels=ctx["quay_names"], show_labels=False
            ),
            static=True,
        )
    wp = ctx["waypoints"]
    if len(wp):
        labels = ["P (start)"] + [str(i) for i in range(1, len(wp))]
        rec.log(P.PLAN, rr.LineStrips2D([wp[:, :2]], radii=0.05, colors=[_C_PLAN]), static=True)
        rec.log(
            P.WAYPOINTS,
            rr.Points2D(wp[:, :2], radii=0.25, colors=[_C_PLAN], labels=labels),
            static=True,
        )
    hull = ctx["hull"]
    k = ctx["scale"]
    acts = ctx["actuators"]
    colours = [_rgba(c) for c in acts.colours]
    rec.log(
        P.HULL,
        rr.LineStrips2D(
            [np.vstack([hull, hull[:1]])],
            radii=0.06 * k,
            colors=[_C_HULL],
            labels=[ctx["vessel"]["title"]],
            show_labels=False,
        ),
        static=True,
    )
    rec.log(
        P.THRUST,
        rr.Arrows2D.from_fields(
            colors=colours, radii=0.1 * k, labels=list(acts.names), show_labels=False
        ),
        static=True,
    )
    styles = (
        (P.TRACK_TRUTH, _C_TRUTH, 0.08),
        (P.TRACK_REF, _C_REF, 0.06),
        (P.TRACK_EST, _C_EST, 0.07),
        (P.DGPS, _C_MEAS, 0.09),
        (P.DGPS_OUTLIERS, _C_OUTLIER, 0.2),
        (P.TARGET, _C_REF, 0.4),
    )
    for ent, color, radius in styles:
        rec.log(ent, rr.Points2D.from_fields(colors=[color], radii=radius * k), static=True)
    rec.log(
        P.HULL_TRACE, rr.LineStrips2D.from_fields(colors=[_C_TRACE], radii=0.04 * k), static=True
    )
    rec.log(P.WIND, rr.Arrows2D.from_fields(colors=[_C_WIND], radii=0.12 * k), static=True)
    for dof, unit in (("x", "m"), ("y", "m"), ("psi", "deg")):
        rec.log(
            f"{P.POSITION}/{dof}",
            rr.SeriesLines(
                names=[f"{dof}_d^r ({unit})", f"{dof}^r true", f"{dof}^r estimate"],
                colors=_SERIES_COLORS,
                widths=[2.0, 1.5, 1.0],
            ),
            static=True,
        )
        rec.log(
            f"{P.POSITION}/{dof}/measured",
            rr.SeriesPoints(names=[f"{dof}^r measured"], colors=[_C_MEAS], marker_sizes=[1.5]),
            static=True,
        )
    for dof, unit in (("u", "m/s"), ("v", "m/s"), ("r", "deg/s")):
        rec.log(
            f"{P.VELOCITY}/{dof}",
            rr.SeriesLines(
                names=[f"{dof}_d ({unit})", f"{dof} true", f"{dof} estimate"],
                colors=_SERIES_COLORS,
                widths=[2.0, 1.5, 1.0],
            ),
            static=True,
        )
    rec.log(
        P.PLOT_THRUST,
        rr.SeriesLines(names=[f"{a} (N)" for a in acts.names], colors=colours),
        static=True,
    )
    owner = actuator_description(acts)["channel_actuator"]
    for unit, cols in _command_groups(acts.units):
        rec.log(
            command_path(unit),
            rr.SeriesLines(
                names=[f"{acts.channel_names[i]} ({unit})" for i in cols],
                colors=[colours[owner[i]] for i in cols],
            ),
            static=True,
        )
    if ctx["dofs"] == 4:
        rec.log(P.ROLL, rr.SeriesLines(names=["phi (deg)", "p (deg/s)"]), static=True)
    acc_names = ["x_E (m)", "y_E (m)", "psi_E (deg)", "J_c"]
    for ent, tag in ((P.ACCURACY, "true"), (P.ACCURACY_MEAS, "measured")):
        rec.log(ent, rr.SeriesLines(names=[f"{a} {tag}" for a in acc_names]), static=True)
    geo = {
        "waypoints": ctx["waypoints"],
        "quays": ctx["quays"],
        "quay_names": ctx["quay_names"],
        "hull": ctx["hull"],
        "thrusters": ctx["thrusters"],
        "actuators": actuator_description(acts),
        "vessel": ctx["vessel"],
    }
    from .run import _clean

    rec.log(
        f"{P.DATA}/static",
        rr.TextDocument(json.dumps(_clean(geo)), media_type="text/plain"),
        static=True,
    )
    _log_summary(rec, ctx, None, 0, {"complete": False, "ended": None, "steps": 0})


def _summary_markdown(
    meta: dict[str, Any], metrics: dict[str, Any] | None, steps: int, status: dict[str, Any]
) -> str:
    wind = meta.get("wind")
    wind_txt = "none" if not wind else f"{wind['speed']:.1f} m/s from {wind['from_deg']:.0f}°"
    lines = [
        f"# {meta.get('scenario')} — seed {meta.get('seed')}",
        "",
        PLOT_KEY,
        "",
        "| | |",
        "|---|---|",
        f"| env | `{meta.get('env_id')}` |",
        f"| vessel | {meta.get('vessel')} |",
        f"| observer | {meta.get('observer')} |",
        f"| controller | {meta.get('controller')} |",
        f"| wind | {wind_txt} |",
        f"| plan | {meta.get('plan')} ({len(meta.get('legs') or [])} legs) |",
        f"| control period | {meta.get('control_period_s')} s |",
        f"| recorded | {meta.get('recorded_at')} (shipgym {meta.get('shipgym_version')}) |",
    ]
    if status["complete"]:
        lines.append(f"| recording | complete (episode {status['ended']}) |")
    elif metrics:
        lines.append(f"| recording | INCOMPLETE: stopped after {steps} steps |")
    else:
        lines.append("| recording | in progress (incomplete if nothing follows) |")
    if metrics:
        lines.append(f"| steps | {steps} ({metrics.get('duration_s', float('nan')):.0f} s) |")
        lines.append(
            f"| completed | {metrics.get('completed')} ({metrics.get('legs_completed')} legs), "
            f"quay contact: {metrics.get('quay_contact')} |"
        )
        lines += ["", "| indices (eqs. 54-57) | x_E (m) | y_E (m) | psi_E (deg) | J_c |"]
        lines.append("|---|---|---|---|---|")
        rows = [("truth", metrics), ("measured", metrics.get("measured") or {})]
        for name, m in rows:
            if m:
                vals = " | ".join(
                    f"{float(m.get(k, float('nan'))):.4f}" for k in ("x_E", "y_E", "psi_E", "J_c")
                )
                lines.append(f"| {name} | {vals} |")
        warning = indices_warning(metrics, meta)
        if warning is not None:
            lines += ["", warning]
    return "\n".join(lines) + "\n"


def _log_summary(
    rec: Any,
    ctx: dict[str, Any],
    metrics: dict[str, Any] | None,
    n: int,
    status: dict[str, Any],
) -> None:
    """The run summary and the machine-readable metadata; ``status`` is the end marker
    (``metadata["recording"]``: ``complete``, ``ended``, ``steps``), logged last."""
    import rerun as rr

    from .run import _clean

    meta = {**ctx["metadata"], "recording": dict(status)}
    rec.log(
        P.SUMMARY,
        rr.TextDocument(
            _summary_markdown(meta, metrics, n, status), media_type=rr.MediaType.MARKDOWN
        ),
        static=True,
    )
    doc = {"metadata": meta, "metrics": metrics or {}}
    rec.log(
        P.META_JSON, rr.TextDocument(json.dumps(_clean(doc)), media_type="text/plain"), static=True
    )


def _whole_timeline() -> Any:
    """The time axis range of the time-series views: the whole recording (both ends unbounded).

    Without it rerun shows a timeline longer than 60 s as the time cursor +- 30 s (its
    ``TimeAxis.view_range`` fallback): about the last 50 s of a 1,285 s harbour run."""
    import rerun.blueprint as rrb

    return rrb.TimeRange(
        start=rrb.TimeRangeBoundary.infinite(), end=rrb.TimeRangeBoundary.infinite()
    )


def _blueprint(ctx: dict[str, Any]) -> Any:
    """Map (left, with the run summary) and time series (right, like Tomera (2014) Figs. 9-11)."""
    import rerun.blueprint as rrb

    lo, hi = ctx["extent"]
    k = ctx["scale"]
    m = 4.0 * k
    # screen coordinates of the map view: x = east, y = -north (rerun 2-D y points down)
    bounds = rrb.VisualBounds2D(
        x_range=[float(lo[1] - m), float(hi[1] + m)],
        y_range=[float(-(hi[0] + 12.0 * k)), float(-(lo[0] - m))],
    )
    trail = rrb.VisibleTimeRanges(
        timeline="sim_time",
        start=rrb.TimeRangeBoundary.infinite(),
        end=rrb.TimeRangeBoundary.cursor_relative(),
    )
    trails: dict[Any, Any] = {
        f"/{p}": trail
        for p in (P.TRACK_TRUTH, P.TRACK_REF, P.TRACK_EST, P.DGPS, P.DGPS_OUTLIERS, P.HULL_TRACE)
    }
    map_view = rrb.Spatial2DView(
        origin=P.MAP,
        name=("Harbour map" if len(ctx["quays"]) else "Map") + " (north up, m)",
        visual_bounds=bounds,
        background=[12, 40, 64],
        overrides=trails,
    )

    # The whole episode on the time axis; no legend over the curves (rerun draws a legend
    # inside the plot, in a corner, over the data: the colours are in the run summary's key,
    # a curve's name shows on hover, and a view's selection panel switches its legend on, at
    # the top left); a dark plot background, on which the white "true" curves show in the
    # viewer's light theme too.
    whole = rrb.TimeAxis(view_range=_whole_timeline())
    legend = rrb.PlotLegend(corner=rrb.Corner2D.LeftTop, visible=False)
    background = rrb.archetypes.PlotBackground(color=list(_C_PLOT_BACKGROUND), show_grid=True)

    def ts(origin: str, name: str) -> Any:
        return rrb.TimeSeriesView(
            origin=origin, name=name, axis_x=whole, plot_legend=legend, background=background
        )

    dofs = rrb.Grid(
        ts(f"{P.POSITION}/x", "x^r (m)"),
        ts(f"{P.VELOCITY}/u", "u (m/s)"),
        ts(f"{P.POSITION}/y", "y^r (m)"),
        ts(f"{P.VELOCITY}/v", "v (m/s)"),
        ts(f"{P.POSITION}/psi", "psi^r (deg)"),
        ts(f"{P.VELOCITY}/r", "r (deg/s)"),
        grid_columns=2,
        name="r-frame pose and body velocity",
    )
    acts = ctx["actuators"]
    commands = [
        ts(command_path(unit), f"commands ({unit}): " + ", ".join(acts.channel_names[i] for i in c))
        for unit, c in _command_groups(acts.units)
    ]
    roll = [ts(P.ROLL, "roll (deg, deg/s)")] if ctx["dofs"] == 4 else []
    thr = rrb.Tabs(
        ts(P.PLOT_THRUST, "thrust (N)"),
        *commands,
        *roll,
        ts("plots/accuracy", "accuracy indices"),
        ts("plots/disturbances", "disturbances (wind, wave drift: N, N, N m; current m/s)"),
    )
    left = rrb.Vertical(
        map_view, rrb.TextDocumentView(origin=P.SUMMARY, name="Run"), row_shares=[4, 1]
    )
    right = rrb.Vertical(dofs, thr, row_shares=[3, 1])
    return rrb.Blueprint(
        rrb.Horizontal(left, right, column_shares=[1, 1.3]),
        rrb.TimePanel(timeline="sim_time", state="collapsed"),
        collapse_panels=False,
    )
