"""``shipgym bench ... --resume`` (issue 33): an interrupted benchmark continues from the rows
it kept, runs only the missing jobs and prints the table of an uninterrupted run; a run with
other settings is not resumed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from shipgym.cli import main

#: the benchmarks, each with small settings (the slow ones marked)
BENCHES = [
    pytest.param(["bench", "observers", "--seeds", "2", "--observers", "kbf", "dkf"],
                 id="observers"),
    pytest.param(["bench", "dp", "--vessel", "star-hercules", "--beaufort", "5", "--seeds", "1",
                  "--methods", "kf14", "kbf-pid", "--duration", "100"], id="dp",
                 marks=pytest.mark.slow),
    pytest.param(["bench", "roll", "--vessel", "van-der-klugt", "--speeds", "8,13",
                  "--duration", "150"], id="roll", marks=pytest.mark.slow),
    pytest.param(["bench", "controllers", "--controllers", "pid", "pid-smooth", "--seeds", "1",
                  "--task", "station-keeping"], id="controllers", marks=pytest.mark.slow),
]  # fmt: skip


#: measured times in the rows and tables, different on every run
TIMES = ("filter_step_us", "wall_time_s")


def _table(text: str) -> list[str]:
    """The table's rows, without a last column of measured times (the DP table's ``filter step
    (us)``, the controllers' ``wall (s)``)."""
    lines = [line for line in text.splitlines() if line.startswith("|")]
    if lines and lines[0].rstrip().endswith(("filter step (us) |", "wall (s) |")):
        lines = [line.rstrip().rstrip("|").rsplit("|", 1)[0] for line in lines]
    return lines


def _rows(path):
    """A bench file's rows: ``rows``, or the keyed runs of ``bench roll`` (schema 2)."""
    data = json.loads(path.read_text())
    if "runs" in data:
        from shipgym.rrs.bench import roll_from_json

        return roll_from_json(data)[0]
    return data["rows"]


def _untimed(rows: list[dict]) -> list[dict]:
    return [{k: v for k, v in r.items() if k not in TIMES} for r in rows]


def _settings(argv: list[str]) -> dict:
    from shipgym._argtypes import bench_settings
    from shipgym.cli import _parser

    return json.loads(json.dumps(bench_settings(_parser().parse_args(argv)), default=repr))


_MODULES = ("shipgym.bench", "shipgym.dp.bench", "shipgym.rrs.bench", "shipgym.rl.bench")


def _patch_run_jobs(monkeypatch, wrapper) -> None:
    """``run_jobs`` wrapped wherever a benchmark took it from (every module imported first,
    so that none imports the wrapper while it is in place)."""
    import importlib

    import shipgym.bench

    modules = [importlib.import_module(name) for name in _MODULES]
    real = shipgym.bench.run_jobs
    for module in modules:
        if getattr(module, "run_jobs", None) is real:
            monkeypatch.setattr(module, "run_jobs", wrapper(real))


@pytest.mark.parametrize("argv", BENCHES)
def test_a_resumed_bench_runs_the_missing_jobs_and_gives_the_whole_table(
    argv, tmp_path, capsys, monkeypatch
):
    base = [*argv, "--workers", "1", "--no-progress"]
    assert main([*base, "--json", str(tmp_path / "whole.json")]) == 0
    whole = _table(capsys.readouterr().out)
    rows = _rows(tmp_path / "whole.json")
    assert whole and len(rows) >= 2
    out, partial = tmp_path / "b.json", tmp_path / "b.partial.jsonl"

    def interrupted(real):  # the user presses Ctrl-C once the first row is in
        def run(fn, jobs, **kw):
            on = kw["on_result"]

            def first_then_stop(i, row):
                on(i, row)
                raise KeyboardInterrupt

            return real(fn, jobs, **{**kw, "on_result": first_then_stop})

        return run

    with monkeypatch.context() as m:
        _patch_run_jobs(m, interrupted)
        assert main([*base, "--json", str(out)]) == 130
    assert "--resume continues" in capsys.readouterr().err
    assert not out.exists() and len(partial.read_text().splitlines()) == 2
    ran = []

    def counted(real):
        def run(fn, jobs, **kw):
            ran.append(len(jobs) - len(kw.get("known") or {}))
            return real(fn, jobs, **kw)

        return run

    with monkeypatch.context() as m:
        _patch_run_jobs(m, counted)
        assert main([*base, "--json", str(out), "--resume"]) == 0
    assert _table(capsys.readouterr().out) == whole
    assert ran == [len(rows) - 1]  # the kept row was not run again
    assert _untimed(_rows(out)) == _untimed(rows)
    assert not partial.exists()


def test_a_run_with_other_settings_or_nothing_kept_is_not_resumed(tmp_path, capsys):
    base = ["bench", "observers", "--seeds", "2", "--observers", "kbf", "--workers", "1",
            "--no-progress", "--json", str(tmp_path / "b.json")]  # fmt: skip
    assert main([*base, "--resume"]) == 2
    assert "nothing to resume" in capsys.readouterr().err
    head = {"settings": {**_settings(base), "seeds": 3}}
    (tmp_path / "b.partial.jsonl").write_text(
        json.dumps(head) + "\n" + json.dumps({"index": 0, "row": {}}) + "\n"
    )
    assert main([*base, "--resume"]) == 2
    err = capsys.readouterr().err
    assert "other settings (seeds" in err and err.count("\n") == 1
    assert main(["bench", "observers", "--seeds", "1", "--resume", "--no-progress"]) == 2
    assert "--resume continues the partial rows of --json or --markdown" in capsys.readouterr().err
    assert Path(tmp_path / "b.partial.jsonl").exists()  # a refused resume keeps the rows
