r"""``shipgym bench dp``: the wave filters of Al-Takie (1982) in closed loop, Beaufort 5-9.

Each run is one episode of ``shipgym/DPStationKeeping-v0`` (the vessel at its set-point in the
Beaufort preset's wind, waves with first-order motion on the measurements, current; sensors
of the thesis sampled every 0.1 per-unit time) with one estimator + controller pair:

=====================  ==================  =============  ===========================
method                 observer            controller     note
=====================  ==================  =============  ===========================
``kf14``               ``alt-kf14``        ``alt-lq``     14-state KF + Grimble LQ
``kf12``               ``alt-kf12``        ``alt-lq``     reduced filter
``semiconstant``       ``alt-semiconstant``  ``alt-lq``   gain frozen at 28 s
``ekf``                ``alt-ekf``         ``alt-sdre``   saturating thrusters, SDRE
``notch-pid``          ``notch``           ``pid``        three notches + PID
``raw-lq``             ``alt-raw``         ``alt-lq``     LQ on raw measurements
``kbf-pid``            ``kbf``             ``pid``        the vessel library's generic DP
``kf14-bf5``           ``alt-kf14`` (Bf 5) ``alt-lq``     robustness: filter for Bf 5
``kf14-noise100``      ``alt-kf14``        ``alt-lq``     robustness: plant noise x100
=====================  ==================  =============  ===========================

The ``alt-*`` filters are designed for the run's Beaufort number (``kf14-bf5``: for 5,
whatever the sea). Metrics: :func:`~shipgym.dp.metrics.dp_metrics` on the true pose against the
set-point, the controller's command ``tau_c``, the allocation's saturation flags, the estimation
error of the pose, the observers' NIS; the cost per filter step is the wall time of the
observer's ``step`` calls.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .metrics import dp_metrics

__all__ = ["METHODS", "bench_dp", "dp_run", "dp_table"]

#: method -> (observer, controller, observer options, env overrides); see the module docstring
METHODS: dict[str, tuple[str, str, dict[str, Any] | None, str | None]] = {
    "kf14": ("alt-kf14", "alt-lq", None, None),
    "kf12": ("alt-kf12", "alt-lq", None, None),
    "semiconstant": ("alt-semiconstant", "alt-lq", None, None),
    "ekf": ("alt-ekf", "alt-sdre", None, None),
    "notch-pid": ("notch", "pid", None, None),
    "raw-lq": ("alt-raw", "alt-lq", None, None),
    "kbf-pid": ("kbf", "pid", None, None),
    "kf14-bf5": ("alt-kf14", "alt-lq", {"beaufort": 5}, None),
    "kf14-noise100": ("alt-kf14", "alt-lq", None, "noise100"),
}


def dp_run(job: tuple[str, int, str, int, float]) -> dict[str, Any]:
    """One episode: ``(vessel, beaufort, method, seed, duration_s)`` -> a row of metrics."""
    import shipgym
    from shipgym.dynamics.vessel import load_vessel
    from shipgym.envs.offshore import dp_control_period
    from shipgym.observers.sensors import AL_TAKIE1982_HEADING_SIGMA, AL_TAKIE1982_POSITION_SIGMA

    vessel_name, bf, method, seed, duration = job
    obs_name, ctl, opts, env_mod = METHODS[method]
    vessel = load_vessel(vessel_name)
    options = None
    if obs_name.startswith("alt-"):
        options = {"beaufort": bf} if opts is None else dict(opts)
    kwargs: dict[str, Any] = {}
    if env_mod == "noise100":
        scale = float(vessel.scale)
        kwargs["sensors"] = {
            "period": dp_control_period(float(vessel.hull.L_pp)),
            "position_variance": 100.0 * (AL_TAKIE1982_POSITION_SIGMA / scale) ** 2,
            "heading_variance": 100.0 * AL_TAKIE1982_HEADING_SIGMA**2,
        }
    env = shipgym.make(
        "shipgym/DPStationKeeping-v0",
        vessel=vessel_name,
        beaufort=bf,
        episode_duration=duration,
        observer=obs_name,
        observer_options=options,
        controller=ctl,
        **kwargs,
    )
    observer = env.env.observer  # the ObserverWrapper's observer (controller wrapper above)
    spent = [0.0, 0]
    step = observer.step

    def timed(*a: Any, **k: Any) -> Any:
        t0 = time.perf_counter()
        out = step(*a, **k)
        spent[0] += time.perf_counter() - t0
        spent[1] += 1
        return out

    observer.step = timed  # type: ignore[method-assign]
    _, info = env.reset(seed=seed)
    a = np.zeros(env.action_space.shape, np.float32)
    t, eta, eta_d, tau, sat, err, nis = [], [], [], [], [], [], []
    while True:
        _, _, term, trunc, info = env.step(a)
        rec = info["record"]
        t.append(rec.t)
        eta.append(rec.truth.eta)
        eta_d.append(rec.reference.eta_P)
        tau.append(info["tau_c"])
        sat.append(bool(np.any(info["allocation_saturated"])))
        err.append(info["est_error_eta"])
        nis.append(np.nan if info["observer_nis"] is None else info["observer_nis"])
        if term or trunc:
            break
    env.close()
    cap = np.asarray(vessel.actuators.capacity(), dtype=float)
    cap = cap if cap.size == 3 else cap[[0, 1, 3]]
    nis_a = np.array(nis, dtype=float)
    m = dp_metrics(
        np.array(t),
        np.array(eta),
        np.array(eta_d),
        np.array(tau),
        cap,
        saturated=np.array(sat)[:, None],
        lf_error=np.array(err),
        nis=nis_a[np.isfinite(nis_a)] if np.isfinite(nis_a).any() else None,
        nis_dof=3,
    )
    m.update(
        vessel=vessel_name,
        beaufort=bf,
        method=method,
        observer=obs_name,
        controller=ctl,
        seed=seed,
        filter_step_us=1e6 * spent[0] / max(spent[1], 1),
    )
    return m


def bench_dp(
    vessels: Sequence[str],
    beauforts: Sequence[int],
    seeds: int,
    *,
    methods: Sequence[str] | None = None,
    duration: float = 600.0,
    workers: int | None = None,
    progress: bool = True,
    on_row: Callable[[int, Any], None] | None = None,
) -> list[dict[str, Any]]:
    """All (vessel, Beaufort, method, seed) runs, in worker processes; rows of metrics."""
    from shipgym.bench import run_jobs

    names = list(METHODS) if methods is None else list(methods)
    for m in names:
        if m not in METHODS:
            raise ValueError(f"unknown DP method {m!r}; choose from {', '.join(METHODS)}")
    jobs = [
        (v, int(bf), m, s, float(duration))
        for v in vessels
        for bf in beauforts
        for m in names
        for s in range(seeds)
    ]
    return run_jobs(
        dp_run, jobs, workers=workers, progress=progress, desc="dp runs", on_result=on_row
    )


def _ms(vals: list[float], fmt: str) -> str:
    a = np.array([v for v in vals if v is not None and math.isfinite(v)], dtype=float)
    if not a.size:
        return "-"
    return f"{a.mean():{fmt}}" if a.size == 1 else f"{a.mean():{fmt}} ± {a.std():{fmt}}"


def dp_table(rows: Sequence[dict[str, Any]]) -> str:
    """A Markdown table: one line per (vessel, Beaufort, method), means ± std over seeds."""
    keys: dict[tuple[str, int, str], list[dict[str, Any]]] = {}
    for r in rows:
        keys.setdefault((r["vessel"], r["beaufort"], r["method"]), []).append(r)
    head = (
        "| vessel | Bf | method | pos RMS (m) | max radial (m) | inside 7 m (%) | "
        "heading RMS (deg) | thrust use | saturated (%) | wave-band ratio | "
        "est. RMSE x, y (m) | NIS mean | filter step (us) |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    )
    lines = [head]
    for (v, bf, m), rs in keys.items():
        lf = [r.get("lf_rmse") for r in rs]
        lf_xy = [None if x is None else float(np.hypot(x[0], x[1])) for x in lf]
        lines.append(
            f"| {v} | {bf} | {m} | "
            f"{_ms([r['position_rms_m'] for r in rs], '.2f')} | "
            f"{_ms([r['max_radial_error_m'] for r in rs], '.2f')} | "
            f"{_ms([r['inside_radius_pct'] for r in rs], '.1f')} | "
            f"{_ms([r['heading_rms_deg'] for r in rs], '.2f')} | "
            f"{_ms([r['thrust_usage_mean'] for r in rs], '.3f')} | "
            f"{_ms([r['saturated_pct'] for r in rs], '.1f')} | "
            f"{_ms([r['wave_band_ratio'] for r in rs], '.3f')} | "
            f"{_ms(lf_xy, '.2f')} | "
            f"{_ms([r['nis_mean'] for r in rs], '.2f')} | "
            f"{_ms([r['filter_step_us'] for r in rs], '.0f')} |"
        )
    return "\n".join(lines)
