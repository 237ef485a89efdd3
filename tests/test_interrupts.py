"""Nothing lost, nothing left behind: real SIGINT, SIGTERM and SIGKILL of the command line.

Each command runs in a subprocess in its own session (process group), started with the code
under test first on PYTHONPATH. The test waits for a known point (the partial recording or the
first finished bench row on disk) before signalling, and every wait is bounded. Afterwards:
the earlier complete pair (recording + JSON) is byte-identical, the partial files are named as
partial, no recording sits next to a JSON of another run, and no process of the group is alive.
"""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import shipgym
from shipgym.viz import load_run, recording_problem

ROOT = Path(shipgym.__file__).resolve().parent.parent  # the code under test
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
#: runs a shipgym command like ``python -m shipgym.cli``, with SIGINT as in an interactive shell
#: (a background job inherits it ignored) and each recorded step slowed by argv[1] seconds, so
#: that a signal lands in mid-episode whatever the machine's speed
DRIVER = """
import signal, sys, time
signal.signal(signal.SIGINT, signal.default_int_handler)
slow = float(sys.argv[1])
if slow:
    from shipgym.viz import recorder
    _step = recorder.RecordEpisode.step
    def step(self, action):
        time.sleep(slow)
        return _step(self, action)
    recorder.RecordEpisode.step = step
from shipgym.cli import main
sys.exit(main(sys.argv[2:]))
"""
SIGNALS = {"SIGINT": signal.SIGINT, "SIGTERM": signal.SIGTERM, "SIGKILL": signal.SIGKILL}
WAIT = 60.0  # the longest wait for anything (s)


def _cli(*args, cwd, timeout=WAIT):
    return subprocess.run(
        [sys.executable, "-m", "shipgym.cli", *map(str, args)],
        cwd=cwd, env=ENV, capture_output=True, text=True, timeout=timeout, check=False,
    )  # fmt: skip


def _start(args, cwd, slow=0.0):
    return subprocess.Popen(
        [sys.executable, "-c", DRIVER, str(slow), *map(str, args)],
        cwd=cwd, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        start_new_session=True,
    )  # fmt: skip


def _wait_for(cond, proc, what):
    deadline = time.monotonic() + WAIT
    while not cond():
        if proc.poll() is not None:
            out, err = proc.communicate()
            pytest.fail(f"the command ended (rc {proc.returncode}) before {what}:\n{err}")
        if time.monotonic() > deadline:
            _kill_group(proc.pid)
            pytest.fail(f"timed out waiting for {what}")
        time.sleep(0.02)


def _group(pgid):
    """Pids of the live processes (not zombies) in process group ``pgid``."""
    try:
        import psutil
    except ImportError:
        psutil = None
    out = []
    if psutil is not None:
        for p in psutil.process_iter(["pid", "status"]):
            try:
                if p.info["status"] != psutil.STATUS_ZOMBIE and os.getpgid(p.pid) == pgid:
                    out.append(p.pid)
            except (ProcessLookupError, psutil.Error):
                pass
        return out
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                fields = (d / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if fields[0] != "Z" and int(fields[2]) == pgid:
                out.append(int(d.name))
    return out


def _kill_group(pgid):
    try:
        os.killpg(pgid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def _assert_group_gone(pgid):
    deadline = time.monotonic() + 15.0
    while (alive := _group(pgid)) and time.monotonic() < deadline:
        time.sleep(0.1)
    _kill_group(pgid)  # clean up whatever the assertion below reports
    assert not alive, f"processes left alive: {alive}"


def _rerun_verify(path):
    """(ok, output) of ``rerun rrd verify`` (footer checked); None without the rerun CLI."""
    exe = shutil.which("rerun") or str(Path(sys.executable).parent / "rerun")
    if not Path(exe).exists():
        return None
    out = subprocess.run(
        [exe, "rrd", "verify", str(path)], capture_output=True, text=True, timeout=WAIT
    )
    return out.returncode == 0, out.stdout + out.stderr


def _assert_pair(rrd, js):
    """A verifiable recording and the JSON of the same run (never a stale pair)."""
    res = json.loads(js.read_text())
    run = load_run(rrd)
    assert recording_problem(run) is None
    assert run.metadata["seed"] == res["seed"]
    assert run.metrics["J_c"] == pytest.approx(res["J_c"], rel=1e-12)
    verified = _rerun_verify(rrd)
    if verified is not None:
        assert verified[0], verified[1]


@pytest.fixture(scope="module")
def earlier(tmp_path_factory):
    """An earlier complete pair of ``shipgym run harbour --seed 0 --record --json``."""
    d = tmp_path_factory.mktemp("earlier")
    out = _cli("run", "harbour", "--seed", 0, "--record", "h.rrd", "--json", "h.json", cwd=d)
    assert out.returncode == 0, out.stderr
    _assert_pair(d / "h.rrd", d / "h.json")
    assert sorted(p.name for p in d.iterdir()) == ["h.json", "h.rrd"]
    return d


@pytest.mark.parametrize("name", list(SIGNALS))
def test_signalled_rerun_keeps_the_earlier_pair(tmp_path, earlier, name):
    for f in ("h.rrd", "h.json"):
        shutil.copyfile(earlier / f, tmp_path / f)
    before = {f: (tmp_path / f).read_bytes() for f in ("h.rrd", "h.json")}
    partial = tmp_path / "h.partial.rrd"
    args = ["run", "harbour", "--seed", 1, "--record", "h.rrd", "--json", "h.json", "--no-progress"]
    proc = _start(args, tmp_path, slow=0.003)  # about 4 s of episode
    _wait_for(lambda: partial.is_file() and partial.stat().st_size > 0, proc, "the recording")
    time.sleep(0.6)  # some steps into the episode (a first block of rows written, mostly)
    proc.send_signal(SIGNALS[name])
    out, err = proc.communicate(timeout=WAIT)
    _assert_group_gone(proc.pid)

    # the earlier pair is untouched, and nothing but the partial recording was added (and,
    # after SIGKILL, the run's output locks, which the next run takes over: no process holds
    # them)
    assert {f: (tmp_path / f).read_bytes() for f in before} == before
    _assert_pair(tmp_path / "h.rrd", tmp_path / "h.json")
    locks = sorted(p.name for p in tmp_path.iterdir() if p.name.endswith(".lock"))
    assert locks == ([".h.json.lock", ".h.rrd.lock"] if name == "SIGKILL" else [])
    names = sorted(p.name for p in tmp_path.iterdir() if not p.name.endswith(".lock"))
    assert names == ["h.json", "h.partial.rrd", "h.rrd"]
    if name == "SIGKILL":
        assert proc.returncode == -signal.SIGKILL
        # cut short: the report says so in one line (unreadable) or marks it incomplete
        rep = _cli("report", partial, "--out", tmp_path / "rep", cwd=tmp_path)
        if rep.returncode == 2:
            assert rep.stderr.count("\n") == 1, rep.stderr
            assert "truncated" in rep.stderr or "incomplete recording" in rep.stderr
        else:
            assert rep.returncode == 0, rep.stderr
            assert "incomplete recording" in rep.stderr
            assert "INCOMPLETE RECORDING" in (tmp_path / "rep" / "metrics.md").read_text()
        return
    assert proc.returncode == 128 + SIGNALS[name], err
    assert err.strip().splitlines()[-1] == (
        f"shipgym: interrupted ({name}); partial recording kept at h.partial.rrd; "
        "h.rrd left as it was; h.json left as it was"
    )
    assert "Traceback" not in err
    run = load_run(partial)  # finalised on the way out: readable, and says it is incomplete
    assert run.metadata["recording"]["complete"] is False
    assert 0 < run.n_steps < 1220 and run.metadata["seed"] == 1
    assert "stopped before its end" in recording_problem(run)
    verified = _rerun_verify(partial)
    if verified is not None:
        assert verified[0], verified[1]
    rep = _cli("report", partial, "--out", tmp_path / "rep", cwd=tmp_path)
    assert rep.returncode == 0 and "incomplete recording" in rep.stderr, rep.stderr
    assert "INCOMPLETE RECORDING" in (tmp_path / "rep" / "metrics.md").read_text()


def test_completed_rerun_replaces_the_pair_and_the_partial_file(tmp_path, earlier):
    for f in ("h.rrd", "h.json"):
        shutil.copyfile(earlier / f, tmp_path / f)
    (tmp_path / "h.partial.rrd").write_bytes(b"left by a killed run")
    out = _cli("run", "harbour", "--seed", 2, "--record", "h.rrd", "--json", "h.json", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert json.loads((tmp_path / "h.json").read_text())["seed"] == 2
    _assert_pair(tmp_path / "h.rrd", tmp_path / "h.json")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["h.json", "h.rrd"]


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_json_to_a_full_device_prints_the_results(tmp_path):
    out = _cli("run", "station-keeping", "--json", "/dev/full", "--no-progress", cwd=tmp_path)
    assert out.returncode == 2
    res = json.loads(out.stdout)
    assert res["scenario"] == "station-keeping" and res["duration_s"] > 0
    assert out.stderr.count("\n") == 1, out.stderr
    assert "cannot write the results to /dev/full" in out.stderr
    assert "printed on stdout" in out.stderr


def test_failed_json_write_keeps_the_earlier_pair(tmp_path, earlier, monkeypatch, capsys):
    """The JSON cannot be written (disk full): the earlier pair stays byte for byte, the new
    recording stays at its partial name, the results are printed; exit 2 (issue 33)."""
    import errno

    import shipgym._io
    from shipgym.cli import main

    for f in ("h.rrd", "h.json"):
        shutil.copyfile(earlier / f, tmp_path / f)
    before = {f: (tmp_path / f).read_bytes() for f in ("h.rrd", "h.json")}

    def full(path, text):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(shipgym._io, "write_partial_text", full)
    rrd, js = tmp_path / "h.rrd", tmp_path / "h.json"
    argv = ["run", "station-keeping", "--seed", "3", "--record", str(rrd), "--json", str(js)]
    assert main([*argv, "--no-progress"]) == 2
    captured = capsys.readouterr()
    res = json.loads(captured.out)
    assert "No space left on device" in captured.err and captured.err.count("\n") == 1
    assert "earlier outputs are kept" in captured.err
    assert {f: (tmp_path / f).read_bytes() for f in before} == before
    run = load_run(tmp_path / "h.partial.rrd")
    assert run.metadata["seed"] == 3 and run.metrics["J_c"] == pytest.approx(res["J_c"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["h.json", "h.partial.rrd", "h.rrd"]


def test_a_recording_cut_short_is_never_renamed_onto_the_earlier_one(
    tmp_path, earlier, monkeypatch, capsys
):
    """A recording that could not be written to its end (a full disk: rerun's file sink
    drops what it cannot write) lacks its footer: it is not renamed onto ``h.rrd``, the
    earlier pair stays byte for byte, the results are printed; exit 2."""
    import shipgym.runner
    from shipgym._io import rrd_complete
    from shipgym.cli import main

    assert rrd_complete(earlier / "h.rrd")
    cut = tmp_path / "cut.rrd"
    cut.write_bytes((earlier / "h.rrd").read_bytes()[:-20000])
    assert not rrd_complete(cut) and not rrd_complete(tmp_path / "missing.rrd")
    for f in ("h.rrd", "h.json"):
        shutil.copyfile(earlier / f, tmp_path / f)
    before = {f: (tmp_path / f).read_bytes() for f in ("h.rrd", "h.json")}
    commit = shipgym.runner._commit_results

    def disk_full(res, recorder, json_path, *args, **kwargs):  # the sink lost its last bytes
        for src, _ in recorder.ended:
            Path(src).write_bytes(Path(src).read_bytes()[:-5000])
        return commit(res, recorder, json_path, *args, **kwargs)

    monkeypatch.setattr(shipgym.runner, "_commit_results", disk_full)
    argv = ["run", "station-keeping", "--seed", "4", "--record", str(tmp_path / "h.rrd"),
            "--json", str(tmp_path / "h.json"), "--no-progress"]  # fmt: skip
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert json.loads(captured.out)["seed"] == 4
    assert "could not be written to its end" in captured.err
    assert captured.err.count("\n") == 1, captured.err
    assert {f: (tmp_path / f).read_bytes() for f in before} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "cut.rrd",
        "h.json",
        "h.partial.rrd",
        "h.rrd",
    ]


def _rows(path):
    """The finished rows of a row log (its first line holds the bench's settings)."""
    if not path.is_file():
        return []
    lines = [json.loads(line) for line in path.read_text().splitlines() if line.endswith("}")]
    return [d for d in lines if "index" in d]


@pytest.mark.parametrize("name", list(SIGNALS))
def test_signalled_bench_keeps_finished_rows_and_no_worker(tmp_path, name):
    rows = tmp_path / "b.partial.jsonl"
    args = ["bench", "observers", "--seeds", 2, "--workers", 2, "--json", "b.json", "--no-progress"]
    proc = _start(args, tmp_path)
    _wait_for(lambda: len(_rows(rows)) >= 1, proc, "the first finished row")
    workers = [p for p in _group(proc.pid) if p != proc.pid]
    assert len(workers) == 2, workers
    proc.send_signal(SIGNALS[name])
    out, err = proc.communicate(timeout=WAIT)
    _assert_group_gone(proc.pid)  # the workers too, SIGKILL of the parent included

    kept = _rows(rows)
    assert 1 <= len(kept) < 6
    for item in kept:
        row = item["row"]
        assert row["observer"] in ("dkf", "kbf", "ekf") and row["seed"] in (0, 1)
        assert row["measured"]["J_c"] > 0
    assert not (tmp_path / "b.json").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.partial.jsonl"]
    if name == "SIGKILL":
        assert proc.returncode == -signal.SIGKILL
        return
    assert proc.returncode == 128 + SIGNALS[name], err
    line = err.strip().splitlines()[-1]
    assert line.startswith(f"shipgym: interrupted ({name}); ")
    assert "finished rows kept at b.partial.jsonl (the same command with --resume" in line
    assert "Traceback" not in err


def test_finished_bench_assembles_the_rows(tmp_path):
    out = _cli(
        "bench", "observers", "--observers", "kbf", "--seeds", 2, "--workers", 2,
        "--json", "b.json", "--markdown", "b.md", cwd=tmp_path,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    doc = json.loads((tmp_path / "b.json").read_text())
    assert [(r["observer"], r["seed"]) for r in doc["rows"]] == [("kbf", 0), ("kbf", 1)]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.json", "b.md"]


@pytest.mark.parametrize("method", ["fork", "forkserver"])
def test_run_jobs_hands_out_results_and_stops_its_workers_on_a_failure(method):
    import math
    import multiprocessing

    from shipgym.bench import run_jobs

    got = []
    out = run_jobs(
        math.sqrt, [9.0, 1.0, 4.0], workers=2, progress=False, start_method=method,
        on_result=lambda i, r: got.append((i, r)),
    )  # fmt: skip
    assert out == [3.0, 1.0, 2.0]
    assert sorted(got) == [(0, 3.0), (1, 1.0), (2, 2.0)]
    with pytest.raises(ValueError, match="math domain error"):
        run_jobs(math.sqrt, [0.0, -1.0, *[2.0] * 50], workers=2, progress=False)
    assert not multiprocessing.active_children()


def test_row_log_keeps_rows_in_job_order(tmp_path):
    from shipgym.bench import RowLog

    log = RowLog(tmp_path / "x.partial.jsonl", total=3)
    assert log.summary() == "none of the 3 runs had finished"
    log.add(2, {"seed": 2})
    log.add(0, {"seed": 0})
    assert RowLog.read(log.path) == [{"seed": 0}, {"seed": 2}]
    assert log.summary() == (
        f"2 of 3 finished rows kept at {log.path} (the same command with --resume continues)"
    )
    log.discard(tmp_path / "x.json")
    assert not log.path.exists()
    assert log.summary() == f"the rows were written to {tmp_path / 'x.json'}"


@pytest.mark.parametrize("method", ["fork", "forkserver"])
def test_killed_pool_owner_takes_its_workers_along(tmp_path, method):
    """SIGKILL of the process owning a run_jobs pool: workers, forkserver, resource tracker go.

    (A forkserver outlives a killed owner while workers hold its "alive" pipe, so forkserver
    workers need the watchdog, forked ones PR_SET_PDEATHSIG.)
    """
    code = (
        "import sys, time\n"
        "from shipgym.bench import run_jobs\n"
        "print('started', flush=True)\n"
        f"run_jobs(time.sleep, [60.0] * 4, workers=2, progress=False, start_method={method!r})\n"
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", code], cwd=tmp_path, env=ENV, stdout=subprocess.PIPE,
        text=True, start_new_session=True,
    )  # fmt: skip
    assert proc.stdout.readline().strip() == "started"
    n = 3 if method == "fork" else 5  # owner, 2 workers (, forkserver, resource tracker)
    _wait_for(lambda: len(_group(proc.pid)) >= n, proc, "the workers")
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=WAIT)
    proc.stdout.close()
    _assert_group_gone(proc.pid)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["SIGTERM", "SIGKILL"])
def test_signalled_training_leaves_no_process(tmp_path, name, request):
    """``shipgym train`` with subprocess envs: SIGTERM stops it like Ctrl-C (exit 143, one
    line), SIGKILL leaves no env worker behind. About 15 s each (torch start-up)."""
    if not (os.environ.get("SHIPGYM_SLOW") or "slow" in (request.config.getoption("-m") or "")):
        pytest.skip("slow: run with -m slow or SHIPGYM_SLOW=1")
    pytest.importorskip("stable_baselines3")
    out = tmp_path / "train"
    args = ["train", "ppo", "--timesteps", 100000, "--n-envs", 2, "--vec-env", "subproc"]
    proc = _start([*args, "--out", out, "--no-progress"], tmp_path)
    _wait_for(lambda: (out / "command.txt").is_file(), proc, "the training set-up")
    _wait_for(lambda: len(_group(proc.pid)) >= 3, proc, "the env workers")
    time.sleep(1.0)  # into model.learn
    proc.send_signal(SIGNALS[name])
    _, err = proc.communicate(timeout=WAIT)
    _assert_group_gone(proc.pid)
    assert not (out / "model.zip").exists()
    if name == "SIGKILL":
        assert proc.returncode == -signal.SIGKILL
        return
    assert proc.returncode == 143, err
    assert err.strip().splitlines()[-1].startswith("shipgym: interrupted (SIGTERM); ")
    assert "no final model.zip written" in err and "Traceback" not in err


def test_a_report_that_cannot_be_written_leaves_the_earlier_report_whole(
    tmp_path, monkeypatch, capsys
):
    """A report folder is replaced as a whole with its recording and JSON, or not at all: a
    figure that cannot be written (a full disk) leaves every earlier file byte for byte and no
    new figure beside them; the results are printed; exit 2 (issue 33)."""
    import errno

    import shipgym.viz.report as report
    from shipgym.cli import main

    rep, js = tmp_path / "rep", tmp_path / "rep" / "h.json"
    argv = ["run", "station-keeping", "--report", str(rep), "--json", str(js), "--no-progress"]
    assert main([*argv, "--seed", "5"]) == 0
    capsys.readouterr()
    before = {p.name: p.read_bytes() for p in rep.iterdir()}
    assert {"metrics.md", "trajectory.png", "run.rrd", "h.json"} <= set(before)

    def full(run, path):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(report, "_plot_velocities", full)
    assert main([*argv, "--seed", "6"]) == 2
    captured = capsys.readouterr()
    assert json.loads(captured.out)["seed"] == 6
    assert "cannot write the report" in captured.err and captured.err.count("\n") == 1
    after = {p.name: p.read_bytes() for p in rep.iterdir() if p.name != "run.partial.rrd"}
    assert after == before


@pytest.mark.parametrize(
    "delay", [1.6, *(pytest.param(d, marks=pytest.mark.slow) for d in (0.2, 0.8, 2.4, 3.2))]
)
def test_a_report_rerun_killed_at_any_moment_leaves_the_earlier_report_whole(tmp_path, delay):
    """SIGKILL at moments spread over a ``run --report DIR --json DIR/h.json`` re-run (during
    the episode, the figures, the renames): every earlier file stays byte for byte, next to at
    most partial files and the dead run's locks; never a mix of two runs (issue 33)."""
    rep = tmp_path / "rep"
    args = ["run", "station-keeping", "--report", str(rep), "--json", str(rep / "h.json")]
    out = _cli(*args, "--seed", 1, "--no-progress", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    before = {p.name: p.read_bytes() for p in rep.iterdir()}
    proc = _start([*args, "--seed", 2, "--no-progress"], tmp_path, slow=0.002)
    time.sleep(delay)
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=WAIT)
    _assert_group_gone(proc.pid)
    now = {p.name: p.read_bytes() for p in rep.iterdir()}
    if proc.returncode == 0:  # it finished first: the new run's files, all of them
        assert set(now) == set(before) and json.loads(now["h.json"])["seed"] == 2
        return
    extra = {n for n in set(now) - set(before) if ".partial" not in n and not n.endswith(".lock")}
    assert not extra, extra
    assert {n: now[n] for n in before} == before
