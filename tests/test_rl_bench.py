"""The shipped learned baselines (registry by name, task and vessel), ``shipgym bench controllers``
on the harbour manoeuvre and on station keeping, and the learning curves of training runs.

Tiny models are trained in ``tmp_path`` (a few hundred steps: seconds); the shipped files that
are not in the package yet are stood in for by copies in a temporary models folder.
"""

from __future__ import annotations

import csv
import json
import math
import shutil
import struct

import numpy as np
import pytest

from shipgym.metrics import CHATTER_KEYS

pytest.importorskip("stable_baselines3")
pytest.importorskip("torch")

import shipgym.controllers.learned as learned  # noqa: E402
from shipgym.cli import main  # noqa: E402
from shipgym.controllers.learned import (  # noqa: E402
    BASELINE_MODELS,
    baseline_model_path,
    find_baseline,
    is_learned_controller,
    parse_learned_controller,
    read_metadata,
    trained_vessel,
)
from shipgym.dynamics import wrap_angle  # noqa: E402
from shipgym.rl.bench import (  # noqa: E402
    bench_controllers,
    bench_title,
    controller_table,
    default_controllers,
    missing_baselines,
    station_table,
)
from shipgym.rl.train import train  # noqa: E402
from shipgym.stacks import make, make_learned_env  # noqa: E402
from shipgym.viz.training import (  # noqa: E402
    plot_training,
    read_training_run,
    training_figure,
)

RESIDUAL = learned.models_dir() / "ppo_residual_pid_kbf.zip"
SMALL = {"n_steps": 64, "batch_size": 64, "n_epochs": 1}
SK_ID = "shipgym/StationKeeping-v0"

SK_YAML = """
shipgym/StationKeeping-v0:
  n_timesteps: 128
  policy: MlpPolicy
  n_envs: 1
  env_wrapper:
    - shipgym.observers.wrapper.ObserverWrapper:
        observer: kbf
  env_kwargs:
    vessel: star-hercules
    max_episode_steps: 32
  normalize:
    norm_obs: true
    norm_reward: true
  n_steps: 64
  batch_size: 64
  n_epochs: 1
  policy_kwargs:
    net_arch: [16, 16]
shipgym:
  shipgym/StationKeeping-v0:
    vec_env: dummy
    eval_freq: 0
    checkpoint_freq: 0
"""


@pytest.fixture(scope="module")
def pure_ppo(tmp_path_factory):
    """A pure PPO (no PID) on the Blue Lady's tracking task, 128 steps."""
    out = tmp_path_factory.mktemp("pure")
    return train(
        "ppo", timesteps=128, seed=0, n_envs=2, out=out, overrides=SMALL, observer="kbf",
        eval_freq=0, checkpoint_freq=0, progress=False, vec_env="dummy",
    ).model_path  # fmt: skip


@pytest.fixture(scope="module")
def station_ppo(tmp_path_factory):
    """A pure PPO on station keeping with star-hercules (4 actuator channels), 128 steps."""
    out = tmp_path_factory.mktemp("station")
    yml = out / "sk.yml"
    yml.write_text(SK_YAML)
    return train(
        "ppo", timesteps=128, seed=0, out=out / "run", env_id=SK_ID, hyperparams=yml,
        progress=False,
    ).model_path  # fmt: skip


@pytest.fixture
def models(tmp_path, monkeypatch):
    """A temporary models folder holding only the residual baseline (as shipped today)."""
    folder = tmp_path / "models"
    folder.mkdir()
    shutil.copy(RESIDUAL, folder / RESIDUAL.name)
    monkeypatch.setattr(learned, "models_dir", lambda: folder)
    return folder


# ---- the registry ----------------------------------------------------------------------------
def test_baselines_are_found_by_name_task_and_vessel():
    assert find_baseline("ppo").file == "ppo_harbour_kbf.zip"
    assert find_baseline("ppo", "tracking").file == "ppo_harbour_kbf.zip"
    assert find_baseline("sac", "shipgym/BlueLadyHarbour-v0").file == "sac_harbour_kbf.zip"
    assert find_baseline("ppo-residual", "harbour", "blue-lady").file == RESIDUAL.name
    for task in ("station-keeping", SK_ID):
        b = find_baseline("ppo", task, "star-hercules")
        assert b.file == "ppo_station_star_hercules_kbf.zip" and not b.residual
    with pytest.raises(ValueError, match="no shipped baseline 'ppo' for station-keeping with "
                       "vessel 'wimpey-sealab'.*star-hercules.*ppo:PATH"):  # fmt: skip
        find_baseline("ppo", "station-keeping", "wimpey-sealab")
    with pytest.raises(ValueError, match="no shipped baseline 'sac' for station-keeping"):
        find_baseline("sac", "station-keeping", "star-hercules")
    # without a station-keeping entry the vessel's harbour (tracking-trained) policy keeps
    # station, as the residual did before; the task's own entry wins where there is one
    assert find_baseline("ppo-residual", "station-keeping").file == RESIDUAL.name
    assert find_baseline("ppo", "station-keeping", "blue-lady").file == "ppo_harbour_kbf.zip"
    with pytest.raises(ValueError, match="no shipped learned baseline runs"):
        find_baseline("ppo", "shipgym/DPSwayStep-v0")
    assert all(is_learned_controller(b.name) for b in BASELINE_MODELS)
    assert not is_learned_controller("ppo-residual:x.zip") and not is_learned_controller("pid")


def test_a_missing_shipped_file_says_what_is_shipped(models):
    with pytest.raises(FileNotFoundError) as exc:
        baseline_model_path("ppo")
    msg = str(exc.value)
    assert "ppo_harbour_kbf.zip does not exist" in msg
    assert "shipped here: ppo-residual (harbour, blue-lady)" in msg and "ppo:PATH" in msg
    with pytest.raises(FileNotFoundError, match="sac_harbour_kbf.zip.*sac:PATH"):
        parse_learned_controller("sac")
    assert parse_learned_controller("ppo-residual") == ("ppo", models / RESIDUAL.name)
    assert default_controllers("harbour") == ["pid", "lq", "ppo-residual"]
    assert missing_baselines("harbour") == [
        "ppo (ppo_harbour_kbf.zip)",
        "sac (sac_harbour_kbf.zip)",
    ]
    assert default_controllers("station-keeping", "star-hercules") == ["pid", "lq"]
    from shipgym.catalogue import controller_catalogue

    cat = controller_catalogue()  # what 'shipgym list' prints
    assert "sac_harbour_kbf.zip, not shipped yet" in cat["sac"]
    assert cat["ppo-residual"].endswith("ppo_residual_pid_kbf.zip)")
    assert default_controllers("station-keeping", "blue-lady") == ["pid", "lq", "ppo-residual"]


def test_ppo_means_the_pure_policy_once_its_file_is_there(models, pure_ppo):
    shutil.copy(pure_ppo, models / "ppo_harbour_kbf.zip")
    assert parse_learned_controller("ppo") == ("ppo", models / "ppo_harbour_kbf.zip")
    assert default_controllers("harbour") == ["pid", "lq", "ppo", "ppo-residual"]
    # the residual file under the pure policy's name is refused (its metadata says residual)
    shutil.copy(RESIDUAL, models / "ppo_harbour_kbf.zip")
    with pytest.raises(ValueError, match="holds a residual policy"):
        parse_learned_controller("ppo")


def test_shipped_files_agree_with_the_table():
    """Every shipped file's metadata says the algorithm, residual setup and vessel of its
    entry (the residual baseline is shipped today, so at least one is checked)."""
    checked = 0
    for b in BASELINE_MODELS:
        path = learned.models_dir() / b.file
        if not path.is_file():
            continue
        meta = read_metadata(path)
        assert (meta.algorithm, meta.residual) == (b.algorithm, b.residual), b
        assert trained_vessel(meta) == b.vessel, b
        assert meta.observer == "kbf", b
        checked += 1
    assert checked >= 1


def test_cli_run_uses_the_baseline_of_the_scenario(models, capsys):
    assert main(["run", "--controller", "ppo-residual", "--no-progress"]) == 0
    capsys.readouterr()
    assert main(["run", "--controller", "ppo", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "ppo_harbour_kbf.zip does not exist" in err and "ppo-residual" in err


# ---- station keeping -------------------------------------------------------------------------
def _reference_station_keeping(vessel, seed, steps):
    """The loop of tests/test_station_keeping.py, written out here: env -> kbf -> pid."""
    env = make(SK_ID, vessel=vessel, controller="pid", observer="kbf", max_episode_steps=steps)
    env.reset(seed=seed)
    zero = np.zeros(env.action_space.shape, np.float32)
    r, e = [], []
    for _ in range(steps):
        _, _, term, trunc, info = env.step(zero)
        eta, d = info["eta"], info["eta_d"]
        r.append(math.hypot(eta[0] - d[0], eta[1] - d[1]))
        e.append(math.degrees(wrap_angle(eta[2] - d[2])))
        if term or trunc:
            break
    env.close()
    return np.array(r), np.array(e)


def test_station_keeping_rows_match_a_direct_run():
    """The bench's row equals the statistics of the same episode stepped directly, and the
    PID meets the documented requirement (95 % of 1000 s within 2 m, Star Hercules, 10 m/s)."""
    rows = bench_controllers(["pid"], seeds=2, task="station-keeping", workers=1, progress=False)
    assert [r["seed"] for r in rows] == [0, 1]
    for row in rows:
        r, e = _reference_station_keeping("star-hercules", row["seed"], 1000)
        assert r.size == 1000 == row["steps"]
        assert row["inside_fraction"] == float(np.mean(r <= 2.0))
        assert row["r95"] == pytest.approx(float(np.percentile(r, 95)), rel=1e-12)
        assert row["r_max"] == pytest.approx(float(r.max()), rel=1e-12)
        assert row["heading_rms_deg"] == pytest.approx(float(np.sqrt(np.mean(e**2))), rel=1e-12)
        assert row["inside_fraction"] >= 0.95 and row["heading_rms_deg"] <= 2.0
        assert row["wind"] == {"speed": 10.0, "from_deg": pytest.approx(300.0)}
        assert row["duration_s"] == pytest.approx(1000.0)
        assert len(row["thrust_mean_abs"]) == 4 == len(row["actuators"])
    table = station_table(rows)
    assert "| pid | 2 |" in table and "2/2" in table and "stern_tunnel" in table
    title = bench_title(rows, None, "station-keeping")
    assert "star-hercules" in title and "10 m/s from 300 deg" in title and "1000 s" in title


def test_station_keeping_with_a_learned_policy(models, station_ppo):
    shutil.copy(station_ppo, models / "ppo_station_star_hercules_kbf.zip")
    assert default_controllers("station-keeping", "star-hercules") == ["pid", "lq", "ppo"]
    rows = bench_controllers(
        ["pid", "ppo", f"ppo:{station_ppo}"], seeds=1, task="station-keeping", duration_s=40,
        workers=1, progress=False,
    )  # fmt: skip
    assert [r["controller"] for r in rows] == ["pid", "ppo", f"ppo:{station_ppo.stem}"]
    # the shipped name and the explicit path are the same policy: the same episode
    for k in ("inside_fraction", "r95", "heading_rms_deg", "thrust_mean_abs"):
        assert rows[1][k] == rows[2][k]
    assert all(r["steps"] == 40 for r in rows)
    # a station-keeping policy of star-hercules drives no other vessel and not the harbour
    with pytest.raises(ValueError, match="no shipped baseline 'ppo' for station-keeping"):
        bench_controllers(["ppo"], seeds=1, task="station-keeping", vessel="wimpey-sealab")
    with pytest.raises(ValueError, match="trained for vessel 'star-hercules', not 'wimpey"):
        bench_controllers([f"ppo:{station_ppo}"], seeds=1, task="station-keeping",
                          vessel="wimpey-sealab")  # fmt: skip
    with pytest.raises(ValueError, match="trained for vessel 'star-hercules', not 'blue-lady'"):
        bench_controllers([f"ppo:{station_ppo}"], seeds=1)


def test_the_wrapper_takes_the_vessels_action_shape_and_refuses_other_vessels(station_ppo):
    env = make_learned_env(SK_ID, station_ppo, vessel="star-hercules", max_episode_steps=5)
    assert env.action_space.shape == (4,) == env.model_metadata.action_shape
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.zeros(4, np.float32))  # the policy alone
    assert info["policy_action"].shape == (4,)
    with pytest.raises(ValueError, match="residual action must be 4 finite numbers"):
        env.step(np.zeros(3, np.float32))
    env.close()
    with pytest.raises(ValueError, match="trained on 'star-hercules'.*cannot drive vessel "
                       "'wimpey-sealab'"):  # fmt: skip
        make_learned_env(SK_ID, station_ppo, vessel="wimpey-sealab")
    with pytest.raises(ValueError, match="trained on 'blue-lady'.*cannot drive vessel 'star-h"):
        make_learned_env("tracking", RESIDUAL, vessel="star-hercules")
    with pytest.raises(ValueError, match="does not fit the harbour world"):  # before any run
        bench_controllers(["pid"], seeds=1, vessel="star-hercules")


def test_cli_bench_station_keeping(models, station_ppo, tmp_path, capsys):
    shutil.copy(station_ppo, models / "ppo_station_star_hercules_kbf.zip")
    md, js = tmp_path / "t.md", tmp_path / "rows.json"
    argv = ["bench", "controllers", "--task", "station-keeping", "--controllers", "pid", "ppo",
            "--seeds", "1", "--workers", "1", "--no-progress", "--markdown", str(md),
            "--json", str(js)]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "Station keeping of star-hercules" in out and "| ppo | 1 |" in out
    rows = json.loads(js.read_text())["rows"]
    assert [r["controller"] for r in rows] == ["pid", "ppo"]
    assert rows[0]["inside_fraction"] >= 0.95  # the PID's 1000 s meet the requirement


def test_harbour_rows_keep_their_keys(models):
    rows = bench_controllers(["pid", "ppo-residual"], seeds=1, workers=1, progress=False)
    assert [r["controller"] for r in rows] == ["pid", "ppo-residual"]
    keys = {"controller", "controller_spec", "observer", "seed", "completed", "legs_completed",
            "quay_contact", "duration_s", "x_E", "y_E", "psi_E", "J_c", "measured", "leg_times",
            "thrust_mean_abs", "thrust_total_variation", "saturated_fraction", "rmse",
            "wall_time_s", *CHATTER_KEYS}  # fmt: skip
    assert all(set(r) == keys for r in rows)
    table = controller_table(rows)
    assert "| ppo-residual | 1 |" in table
    # issue 31: the chatter beside the indices (time at a limit, main-propeller reversals,
    # starts and time at zero), one cell per column in every line
    head, rule, *lines = table.splitlines()
    for col in ("at a limit (%)", "main reversals / min", "main starts / min", "main at zero"):
        assert col in head
    assert all(line.count("|") == head.count("|") == rule.count("|") for line in lines)
    pid = rows[0]
    cells = lines[0].split("|")[11:15]
    assert cells[1].strip().startswith(f"{pid['reversals_per_min'][0]:.2f}")
    assert cells[2].strip().startswith(f"{pid['starts_per_min'][0]:.2f}")
    assert "wind 3 m/s from 300 deg" in bench_title(rows, "3@300")


# ---- learning curves -------------------------------------------------------------------------
PROGRESS = """time/time_elapsed,time/total_timesteps,time/iterations,rollout/ep_len_mean,\
rollout/ep_rew_mean,eval/completed
0,16384,1,,,
1,32768,2,800.0,-3488.5,
3,49152,3,800.0,-3443.25,0.5
4,65536,4,790.0,-3012.0,
"""
EVALS = [
    {"timesteps": 32768, "completed": 0, "runs": 2, "J_c": None, "J_c_measured": None,
     "rows": []},
    {"timesteps": 65536, "completed": 1, "runs": 2, "J_c": 0.25, "J_c_measured": 0.3,
     "rows": []},
]  # fmt: skip


def _synthetic(folder, evals=EVALS):
    folder.mkdir(parents=True)
    (folder / "progress.csv").write_text(PROGRESS)
    (folder / "evaluations.json").write_text(json.dumps(evals))
    return folder


def test_curves_of_a_synthetic_run(tmp_path):
    run = _synthetic(tmp_path / "ppo_a")
    c = read_training_run(run)
    assert c.label == "ppo_a" and c.eval_kind == "harbour"
    np.testing.assert_array_equal(c.steps, [32768, 49152, 65536])  # rows with a return only
    np.testing.assert_array_equal(c.returns, [-3488.5, -3443.25, -3012.0])
    np.testing.assert_array_equal(c.eval_steps, [32768, 65536])
    np.testing.assert_array_equal(c.eval_score, [0.0, 0.5])
    assert math.isnan(c.eval_jc[0]) and c.eval_jc[1] == 0.25
    sk_evals = [
        {"timesteps": 10, "inside_fraction": 0.4},
        {"timesteps": 20, "rows": [{"inside_fraction": 0.5}, {"inside_fraction": 1.0}]},
    ]
    sk = _synthetic(tmp_path / "sk", sk_evals)
    s = read_training_run(sk)
    assert s.eval_kind == "station-keeping"
    np.testing.assert_array_equal(s.eval_score, [0.4, 0.75])
    fig = training_figure([c, s])
    ax_r, ax_e, ax_j = fig.axes  # the J_c panel: the harbour run has a finite J_c
    assert [ln.get_label() for ln in ax_j.lines] == ["ppo_a"]
    np.testing.assert_array_equal(ax_j.lines[0].get_ydata(), c.eval_jc)
    assert [ln.get_label() for ln in ax_r.lines] == ["ppo_a", "sk"]
    np.testing.assert_array_equal(ax_r.lines[0].get_xdata(), c.steps)
    np.testing.assert_array_equal(ax_r.lines[0].get_ydata(), c.returns)
    np.testing.assert_array_equal(ax_e.lines[0].get_ydata(), [0.0, 50.0])  # percent
    np.testing.assert_array_equal(ax_e.lines[1].get_ydata(), [40.0, 75.0])
    png = plot_training([run, sk], tmp_path / "fig" / "curves.png")
    head = png.read_bytes()[:24]
    assert head[:8] == b"\x89PNG\r\n\x1a\n"
    w, h = struct.unpack(">II", head[16:24])
    assert (w, h) == (1000, 980)  # 10 x 9.8 inches at 100 dpi: three panels
    assert len(training_figure([s]).axes) == 2  # station keeping only: no J_c panel


def test_a_station_keeping_evaluation_is_what_the_curves_read(tmp_path):
    """The periodic station-keeping evaluation of ``shipgym train``
    (:data:`shipgym.rl.train.STATION_KEEPING`) gives the statistics of the direct loop, and
    the curves read its evaluations.json entries back as station keeping."""
    from shipgym.rl.train import STATION_KEEPING

    env = make(SK_ID, vessel="star-hercules", controller="pid", observer="kbf",
               max_episode_steps=200)  # fmt: skip
    evals = []
    for n in (1000, 2000):  # as the callback stores them: the timesteps, then the summary
        summary, _, _ = STATION_KEEPING.summarize([STATION_KEEPING.episode(env, s, None)
                                                   for s in (3, 4)])  # fmt: skip
        evals.append({"timesteps": n, **summary})
    env.close()
    for e in evals:
        for row in e["rows"]:
            r, _ = _reference_station_keeping("star-hercules", row["seed"], 200)
            assert row["inside_fraction"] == float(np.mean(r <= 2.0))
            assert row["r95"] == pytest.approx(float(np.percentile(r, 95)), rel=1e-12)
    assert evals[0]["rows"] == evals[1]["rows"]  # same seeds, same controller: same runs
    run = _synthetic(tmp_path / "sk", evals)
    c = read_training_run(run)
    assert c.eval_kind == "station-keeping"
    np.testing.assert_array_equal(c.eval_steps, [1000, 2000])
    want = np.mean([row["inside_fraction"] for row in evals[0]["rows"]])
    np.testing.assert_array_equal(c.eval_score, [want, want])


def test_curves_refuse_what_train_does_not_write(tmp_path):
    with pytest.raises(FileNotFoundError, match="no progress.csv"):
        read_training_run(tmp_path)
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "progress.csv").write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="no column time/total_timesteps, rollout/ep_rew_mean"):
        read_training_run(bad)
    mixed = _synthetic(tmp_path / "mixed", [EVALS[0], {"timesteps": 9, "inside_fraction": 1}])
    with pytest.raises(ValueError, match="mixes harbour and station-keeping"):
        read_training_run(mixed)
    with pytest.raises(ValueError, match="one per run"):
        plot_training([mixed], tmp_path / "x.png", labels=["a", "b"])


def test_curves_of_a_tiny_training_run(tmp_path, capsys):
    """A real ``train`` run with short episodes (returns logged) and two harbour evaluations:
    the curves are the numbers of its progress.csv and of its evaluations."""
    res = train(
        "ppo", timesteps=256, seed=0, n_envs=2, out=tmp_path / "run", overrides={
            **SMALL, "env_kwargs": {"max_legs": 1, "max_episode_steps": 40}},
        observer="truth", eval_freq=128, eval_seeds=[100], checkpoint_freq=0, progress=False,
        vec_env="dummy",
    )  # fmt: skip
    with open(res.out_dir / "progress.csv", newline="") as fh:
        table = [r for r in csv.DictReader(fh) if r["rollout/ep_rew_mean"]]
    assert len(table) >= 1
    c = read_training_run(res.out_dir)
    np.testing.assert_array_equal(c.steps, [float(r["time/total_timesteps"]) for r in table])
    np.testing.assert_array_equal(c.returns, [float(r["rollout/ep_rew_mean"]) for r in table])
    assert len(res.evaluations) >= 2
    np.testing.assert_array_equal(c.eval_steps, [e["timesteps"] for e in res.evaluations])
    np.testing.assert_array_equal(c.eval_score, [e["completed"] / e["runs"]
                                                 for e in res.evaluations])  # fmt: skip
    out = tmp_path / "curves.png"
    assert main(["plot", "training", str(res.out_dir), "--out", str(out)]) == 0
    assert out.read_bytes()[:4] == b"\x89PNG" and "wrote" in capsys.readouterr().out


@pytest.mark.slow
def test_shipped_station_keeping_policy_meets_the_requirement():
    """Issue 17's acceptance: the shipped pure PPO keeps Star Hercules within the 2 m watch
    circle 95 % of the time in 10 m/s wind (seeds 0-4, 1000 s, through the KBF), the same
    requirement and loop as the generic PID's (tests/test_station_keeping.py)."""
    assert (learned.models_dir() / "ppo_station_star_hercules_kbf.zip").is_file()
    rows = bench_controllers(["ppo"], seeds=5, task="station-keeping", vessel="star-hercules",
                             workers=1, progress=False)  # fmt: skip
    inside = [r["inside_fraction"] for r in rows]
    assert len(rows) == 5 and min(inside) >= 0.95, inside


@pytest.mark.slow
def test_shipped_pure_ppo_completes_the_harbour_manoeuvre():
    """Issue 17's acceptance: the shipped pure PPO (no PID underneath), harbour manoeuvre
    through the KBF in 3 m/s from 300 deg, seeds 0-9: at least 8/10 complete without quay
    contact, mean J_c at most 1.5x the tuned PID's on the same seeds."""
    assert (learned.models_dir() / "ppo_harbour_kbf.zip").is_file()
    rows = bench_controllers(["pid", "ppo"], seeds=10, workers=1, progress=False)
    by = {c: [r for r in rows if r["controller"] == c] for c in ("pid", "ppo")}
    ok = [r for r in by["ppo"] if r["completed"] and not r["quay_contact"]]
    assert len(ok) >= 8, [(r["seed"], r["quay_contact"]) for r in by["ppo"]]
    jc = {c: float(np.mean([r["J_c"] for r in by[c]])) for c in by}
    assert jc["ppo"] <= 1.5 * jc["pid"], jc
