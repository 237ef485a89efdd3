"""Visualisation: headless rerun recordings and matplotlib reports.

The only subpackage that imports ``rerun`` and ``matplotlib``; both are imported lazily, inside
the functions that need them, so ``import shipgym`` and ``import shipgym.viz`` stay light.

- :class:`RecordEpisode`: a Gymnasium wrapper recording every episode to a ``.rrd`` file
  (and optionally a JSON run file);
- :func:`load_run`: read a run back from a ``.rrd`` or JSON file into NumPy arrays
  (:class:`Run`); :func:`save_run_json` writes the JSON form; :func:`recording_problem` says
  whether a recording is incomplete (interrupted, or cut short by a killed process);
- :func:`write_report`: PNG figures (trajectory, positions, velocities, thrusters) and
  ``metrics.md`` of a run.

Example (what ``shipgym run ... --record RUN.rrd --report DIR`` does)::

    env = shipgym.viz.RecordEpisode(shipgym.make("harbour", controller="pid"), "RUN.rrd")
    env.reset(seed=0)
    ...  # step until terminated or truncated (or interrupted)
    env.close()  # RUN.rrd is complete (RUN.partial.rrd if stopped early); env.last_run: arrays
    shipgym.viz.write_report("RUN.rrd", "DIR")  # or write_report(env.last_run, "DIR")
"""

from __future__ import annotations

from .compare import COMPARE_SIZES, write_observer_report
from .recorder import RecordEpisode, episode_path
from .report import DPI, FIGURE_SIZES, pixel_size, report_paths, write_report
from .run import Run, load_run, recording_problem, save_run_json

__all__ = [
    "COMPARE_SIZES",
    "DPI",
    "FIGURE_SIZES",
    "RecordEpisode",
    "Run",
    "episode_path",
    "load_run",
    "pixel_size",
    "recording_problem",
    "report_paths",
    "save_run_json",
    "write_observer_report",
    "write_report",
]
