"""Visualisation: headless rerun recordings and matplotlib reports.

The only subpackage that imports ``rerun`` and ``matplotlib``; both are imported lazily, inside
the functions that need them, so ``import shipgym`` and ``import shipgym.viz`` stay light.

Public names: ``COMPARE_SIZES``, ``DPI``, ``FIGURE_SIZES``, ``RecordEpisode``, ``Run``,
``episode_path``, ``load_run``, ``pixel_size``, ``viewer_hint``, ``web_viewer_url``, ...

Design notes: docs/design/viz.md.
"""

from __future__ import annotations

from .compare import COMPARE_SIZES, write_observer_report
from .export import run_columns, write_run_csv, write_run_npz
from .recorder import RecordEpisode, episode_path
from .report import (
    DPI,
    FIGURE_SIZES,
    pixel_size,
    report_paths,
    write_report,
    write_results_report,
)
from .run import (
    Run,
    is_results,
    load_results,
    load_run,
    load_run_or_results,
    recording_problem,
    save_run_json,
)
from .viewer import viewer_hint, web_viewer_url

__all__ = [
    "COMPARE_SIZES",
    "DPI",
    "FIGURE_SIZES",
    "RecordEpisode",
    "Run",
    "episode_path",
    "is_results",
    "load_results",
    "load_run",
    "load_run_or_results",
    "pixel_size",
    "recording_problem",
    "report_paths",
    "run_columns",
    "save_run_json",
    "viewer_hint",
    "web_viewer_url",
    "write_observer_report",
    "write_report",
    "write_results_report",
    "write_run_csv",
    "write_run_npz",
]
