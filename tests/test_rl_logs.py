"""The training log (issue 32, item 5): progress lines at a fixed interval off a terminal, no
``inf`` in TensorBoard or progress.csv, evaluations stamped at the step they were taken."""

from __future__ import annotations

import csv
import math
import re
import threading
import time

import pytest
import yaml

pytest.importorskip("stable_baselines3")
pytest.importorskip("torch")

from shipgym.rl import train as train_mod  # noqa: E402
from shipgym.rl.train import ProgressLog, evaluation_text, hyperparams_path, train  # noqa: E402

LINE = re.compile(
    r"^shipgym train ppo, seed 0: (?P<done>[\d,]+)/(?P<planned>[\d,]+) steps \([\d.]+%\), "
    r"(?P<fps>[\d,]+) fps, \d+:\d\d:\d\d elapsed"
)


class _Model:
    num_timesteps = 0


class _Stamped:
    """A stream that keeps each line with the time it was written."""

    def __init__(self):
        self.lines = []
        self.lock = threading.Lock()

    def write(self, text):
        with self.lock:
            for part in text.splitlines():
                if part:
                    self.lines.append((time.perf_counter(), part))

    def flush(self):
        pass


def test_progress_lines_come_at_a_fixed_interval_also_without_steps():
    """A line every interval of wall-clock time, also while no step is taken (a long
    gradient update or evaluation): the thread does not wait for the training loop."""
    model, stream = _Model(), _Stamped()
    evals = []
    t0 = time.perf_counter()
    log = ProgressLog(
        model, 1000, 0.05, "shipgym train ppo, seed 0",
        lambda: evals[-1] if evals else None, stream=stream,
    ).start()  # fmt: skip
    model.num_timesteps = 200
    time.sleep(0.3)
    evals.append({"timesteps": 200, "evaluation": "harbour", "completed": 1, "runs": 2,
                  "J_c": 0.25})  # fmt: skip
    time.sleep(0.3)  # no steps now
    log.stop()
    times = [t for t, _ in stream.lines]
    texts = [x for _, x in stream.lines]
    assert len(texts) >= 5, texts  # 0.6 s / 0.05 s = 12 (fewer on a loaded machine)
    periodic = times[:-1]  # the last line is stop()'s
    gaps = [b - a for a, b in zip([t0, *periodic[:-1]], periodic, strict=True)]
    assert max(gaps) < 0.5, gaps  # a fixed interval (with slack for a loaded machine)
    for text in texts:
        m = LINE.match(text)
        assert m is not None, text
        assert m["done"] == "200" and m["planned"] == "1,000"
    assert texts[0].endswith("; no evaluation yet")
    assert texts[-1].endswith("last evaluation at 200 steps: completed 1/2, J_c 0.250")
    n = len(texts)
    time.sleep(0.15)
    assert len(stream.lines) == n  # stopped: no more lines


def test_evaluation_text():
    assert evaluation_text(None) == "no evaluation yet"
    harbour = {"timesteps": 1000, "evaluation": "harbour", "completed": 0, "runs": 2,
               "J_c": math.inf}  # fmt: skip
    assert evaluation_text(harbour) == "last evaluation at 1,000 steps: completed 0/2"
    station = {"timesteps": 5, "evaluation": "station-keeping", "inside_fraction": 0.5,
               "radius_m": 2.0, "return": -12.5}  # fmt: skip
    assert evaluation_text(station) == (
        "last evaluation at 5 steps: 50.0% of the time within 2 m, mean return -12.5"
    )
    with pytest.raises(ValueError, match="finite number of seconds > 0"):
        train_mod.check_log_interval(0)
    with pytest.raises(ValueError, match="finite number of seconds > 0"):
        train("ppo", timesteps=64, log_interval_s=math.inf, progress=False)


def _small_yaml(tmp_path):
    """The shipped ppo.yml with rollouts of 64 steps per env (seconds of training)."""
    data = yaml.safe_load(hyperparams_path("ppo").read_text())
    data["shipgym/BlueLadyTracking-v0"].update(n_steps=64, batch_size=64, n_epochs=1)
    p = tmp_path / "ppo.yml"
    p.write_text(yaml.safe_dump(data))
    return p


def test_shipgym_train_off_a_terminal_writes_progress_lines(tmp_path, capsys):
    """``shipgym train ... > log 2>&1``: stderr is not a terminal (pytest captures it), so no
    bar; progress lines at --log-interval instead, whole lines (no bar frames)."""
    from shipgym.cli import main

    rc = main(["train", "ppo", "--hyperparams", str(_small_yaml(tmp_path)), "--timesteps", "512",
               "--n-envs", "2", "--out", str(tmp_path / "run"), "--observer", "truth",
               "--eval-freq", "128", "--checkpoint-freq", "0", "--vec-env", "dummy",
               "--log-interval", "0.2"])  # fmt: skip
    assert rc == 0
    err = capsys.readouterr().err
    assert "\r" not in err
    lines = [x for x in err.splitlines() if x.startswith("shipgym train ppo, seed 0: ")]
    assert len(lines) >= 2, err  # during the run and the last one
    assert all(LINE.match(x) for x in lines), lines
    assert LINE.match(lines[-1])["done"] == "512"
    assert "last evaluation at 512 steps: completed" in lines[-1]


# ---- what goes to TensorBoard and progress.csv -------------------------------------------------
@pytest.fixture(scope="module")
def pure_run(tmp_path_factory):
    """Pure PPO after 256 steps (completes nothing), evaluated every 64 steps inside rollouts
    of 128 (64 steps x 2 envs)."""
    out = tmp_path_factory.mktemp("logs")
    res = train(
        "ppo", timesteps=256, seed=0, n_envs=2, out=out, observer="truth",
        overrides={"n_steps": 64, "batch_size": 64, "n_epochs": 1}, eval_freq=64,
        eval_seeds=[100], checkpoint_freq=0, progress=False, vec_env="dummy",
        tensorboard=True,
    )  # fmt: skip
    return res


def _scalars(folder):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    acc = EventAccumulator(str(folder))
    acc.Reload()
    return {tag: acc.Scalars(tag) for tag in acc.Tags()["scalars"]}


def _progress(folder):
    with (folder / "progress.csv").open() as fh:
        return list(csv.DictReader(fh))


def test_no_inf_logged_and_completion_logged_separately(pure_run):
    pytest.importorskip("tensorboard")
    assert all(e["completed"] == 0 for e in pure_run.evaluations)  # none completed
    assert all(e["J_c"] == math.inf for e in pure_run.evaluations)  # (evaluations.json's)
    scalars = _scalars(pure_run.out_dir / "tb")
    assert "eval/J_c" not in scalars  # not logged without a completed run
    assert [e.value for e in scalars["eval/completed_fraction"]] == [0.0] * 4
    for tag, events in scalars.items():
        assert all(math.isfinite(e.value) for e in events), tag
    text = (pure_run.out_dir / "progress.csv").read_text()
    assert "inf" not in text.lower() and "nan" not in text.lower()


def test_evaluations_are_stamped_at_their_step(pure_run):
    """Evaluations at 64, 128, 192 and 256 steps, inside rollouts that end at 128 and 256:
    stamped 64 ... 256 (the next logger dump would stamp them 128 and 256)."""
    pytest.importorskip("tensorboard")
    want = [64, 128, 192, 256]
    assert [e["timesteps"] for e in pure_run.evaluations] == want
    scalars = _scalars(pure_run.out_dir / "tb")
    for tag in ("eval/completed_fraction", "eval/duration_s", "eval/quay_contact"):
        assert [e.step for e in scalars[tag]] == want, tag
    rows = _progress(pure_run.out_dir)
    evals = [int(r["time/total_timesteps"]) for r in rows if r["eval/completed_fraction"]]
    assert evals == want
    # the training's own rows stay at the end of each rollout
    assert [int(r["time/total_timesteps"]) for r in rows if r["time/fps"]] == [128, 256]
    assert [e.step for e in scalars["time/fps"]] == [128, 256]


def test_harbour_scalars_j_c_over_completed_runs_only():
    from shipgym.rl.train import HARBOUR

    def row(seed, completed, jc):
        return {"seed": seed, "completed": completed, "quay_contact": False, "J_c": jc,
                "duration_s": 100.0}  # fmt: skip

    _, scalars, _ = HARBOUR.summarize([row(0, False, math.inf), row(1, False, math.inf)])
    assert scalars["completed_fraction"] == 0.0 and "J_c" not in scalars
    _, scalars, _ = HARBOUR.summarize([row(0, True, 0.2), row(1, False, math.inf)])
    assert scalars["completed_fraction"] == 0.5 and scalars["J_c"] == pytest.approx(0.2)
