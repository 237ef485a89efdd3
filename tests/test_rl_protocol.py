"""``shipgym bench rl``: the suites' held-out conditions lie outside the training conditions
(read from the hyperparameter files, not from the suites), the aggregates are the IQM and the
stratified bootstrap of the cells (checked against scipy), the conditions do what they say,
and the command writes its JSON with units."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml
from scipy.stats import trim_mean

from shipgym.disturbances import WindConfig
from shipgym.rl.protocol import (
    SUITES,
    UNITS,
    Condition,
    Method,
    bench_rl,
    parse_method,
    rl_tables,
    summarise,
)
from shipgym.rl.train import hyperparams_path

TRAINING_ID = {"harbour": "shipgym/BlueLadyTracking-v0", "tracking": "shipgym/BlueLadyTracking-v0",
               "station-keeping": "shipgym/StationKeeping-v0"}  # fmt: skip


def _training(task: str) -> list[tuple[dict, dict]]:
    """(env block, shipgym block) of every hyperparameter file's recipe for the task (the
    shipped ppo.yml and sac.yml, and the robust recipe ppo_robust.yml)."""
    out = []
    files = [hyperparams_path(a) for a in ("ppo", "sac")]
    for path in (*files, files[0].with_name("ppo_robust.yml")):
        hp = yaml.safe_load(path.read_text())
        env_id = TRAINING_ID[task]
        if env_id in hp:
            out.append((hp[env_id], hp.get("shipgym", {}).get(env_id, {})))
    assert out, task
    return out


def _wind_range(block: dict) -> tuple[float, float]:
    kw = block.get("env_kwargs", {})
    if "random_wind" in kw:
        lo, hi = kw["random_wind"]
        return float(lo), float(hi)
    return 0.0, float(kw["max_wind_speed"])


@pytest.mark.parametrize("name", list(SUITES))
def test_held_out_conditions_are_outside_the_training_and_held_in_inside(name):
    s = SUITES[name]
    assert s.split(False) and s.split(True)
    for block, own in _training(s.task):
        lo, hi = _wind_range(block)
        kw = block.get("env_kwargs", {})
        assert "dropout" not in str(own.get("randomize", {}))  # faults only in env_kwargs
        trained = {k: float(v) for k, v in (kw.get("sensors") or {}).items()}
        trained_current = float(kw.get("max_current_speed", 0.0)) > 0.0
        for c in s.conditions:
            speed = WindConfig.coerce(c.wind, name="wind").speed
            novel = []
            if speed > hi:
                novel.append("wind")
            # a fault beyond the training's: more frequent or longer than any trained on
            if any(v > trained.get(k, 0.0) for k, v in c.sensors.items()):
                novel.append("sensors")
            if c.current is not None and not trained_current:
                novel.append("current")
            if c.held_out:
                assert novel, (name, c.name)
            else:
                assert not novel and lo <= speed <= hi, (name, c.name)


@pytest.mark.parametrize("name", list(SUITES))
def test_episode_seeds_are_not_the_model_selection_seeds(name):
    s = SUITES[name]
    for _, own in _training(s.task):
        assert min(own.get("eval_seeds", [10**6])) >= 10  # bench rl's seeds are 0..9 (--seeds)


def test_conditions_reach_the_sensors_and_the_physics():
    import shipgym

    drop = next(c for c in SUITES["harbour"].conditions if c.name == "dropout")
    env = shipgym.make("harbour", controller="pid", wind=drop.wind, **drop.env_kwargs())
    try:
        env.reset(seed=0)
        valid = []
        for _ in range(600):
            info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))[-1]
            valid += [bool(m["valid"]) for m in info["measurements"]]
        lost = 1.0 - np.mean(valid)
        assert 0.02 < lost < 0.3  # about 9 % of the fixes (a 10 s dropout every 100 s)
    finally:
        env.close()
    cur = next(c for c in SUITES["harbour"].conditions if c.name == "current")
    env = shipgym.make("harbour", wind=cur.wind, **cur.env_kwargs())
    try:
        env.reset(seed=0)
        assert env.unwrapped.current_config.speed == pytest.approx(0.01)
    finally:
        env.close()
    assert Condition("x", "3@300", False, "").env_kwargs() == {}


def test_parse_method(tmp_path):
    assert parse_method("pid") == Method("pid", ("pid",))
    assert parse_method("ppo") == Method("ppo", ("ppo",))
    m = parse_method("mine=ppo:a.zip, ppo:b.zip")
    assert m == Method("mine", ("ppo:a.zip", "ppo:b.zip"))
    for k in (2, 0, 1):
        (tmp_path / f"seed{k}").mkdir()
        (tmp_path / f"seed{k}" / "model.zip").write_bytes(b"")
    m = parse_method(f"ppo=ppo:{tmp_path}/seed*/model.zip")
    assert [r.split("/")[-2] for r in m.runs] == ["seed0", "seed1", "seed2"]
    with pytest.raises(ValueError, match="matches no model"):
        parse_method(f"ppo=ppo:{tmp_path}/none*/model.zip")
    with pytest.raises(ValueError, match="empty controller spec"):
        parse_method("ppo=ppo:a.zip,")
    with pytest.raises(ValueError, match="needs a name"):
        parse_method("=pid")


def _rows(rng: np.random.Generator) -> list[dict]:
    """Synthetic episodes of two methods (3 runs and 1 run) on the harbour suite."""
    rows = []
    s = SUITES["harbour"]
    for method, runs in (("ppo", 3), ("pid", 1)):
        for run in range(runs):
            for c in s.conditions:
                for seed in range(4):
                    ok = bool(rng.random() < 0.8) or (method == "pid")
                    if method == "ppo" and run == 0 and c.name == "4@300":
                        ok = False  # a cell whose episodes all failed: J_c missing
                    rows.append({
                        "method": method, "run": run, "controller": f"{method}:{run}",
                        "condition": c.name, "held_out": c.held_out, "seed": seed,
                        "success": ok, "J_c": float(rng.uniform(0.1, 0.5)) if ok else math.nan,
                        "return": float(rng.normal()), "reversals_per_min": float(rng.random()),
                        "starts_per_min": float(rng.random()),
                        "limit_pct": float(100 * rng.random()),
                    })  # fmt: skip
    return rows


def test_aggregates_are_the_iqm_and_bootstrap_of_the_cells():
    rows = _rows(np.random.default_rng(0))
    S = summarise(rows, "harbour", reps=2000)
    s = SUITES["harbour"]
    for split, held in (("held-in", False), ("held-out", True)):
        conds = [c.name for c in s.split(held)]
        # the cells by hand: the mean over each run's episodes of one condition
        cell = np.full((3, len(conds)), np.nan)
        ok = np.zeros((3, len(conds)))
        for j, c in enumerate(conds):
            for run in range(3):
                mine = [r for r in rows if r["method"] == "ppo" and r["run"] == run
                        and r["condition"] == c]  # fmt: skip
                ok[run, j] = 100.0 * np.mean([r["success"] for r in mine])
                jc = [r["J_c"] for r in mine if r["success"]]
                cell[run, j] = np.mean(jc) if jc else np.nan
        agg = S["aggregates"][split]["ppo"]
        # the success rate's mean (an IQM would trim away a condition every run fails)
        assert agg["success_pct"]["estimate"] == pytest.approx(ok.mean())
        assert agg["success_pct"]["statistic"] == "mean" and agg["J_c"]["statistic"] == "IQM"
        assert agg["J_c"]["estimate"] == pytest.approx(trim_mean(cell[np.isfinite(cell)], 0.25))
        assert agg["J_c"]["missing"] == int(np.isnan(cell).sum()) == (1 if held else 0)
        assert agg["J_c"]["low"] <= agg["J_c"]["estimate"] <= agg["J_c"]["high"]
        assert agg["J_c"]["runs"] == 3 and agg["J_c"]["conditions"] == len(conds)
        # one run: an interval over no training seed
        pid = S["aggregates"][split]["pid"]["J_c"]
        assert pid["runs"] == 1 and pid["low"] == pid["high"]
    table = rl_tables(S, "harbour")
    assert "**held-out**" in table and "1 cells without a completed run" in table
    assert S == summarise(rows, "harbour", reps=2000)  # seeded


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: bench_rl("harbor"), "unknown suite 'harbor'"),
        (lambda: bench_rl("harbour", seeds=0), "seeds must be"),
        (lambda: bench_rl("harbour", split="out"), "split must be"),
        (lambda: bench_rl("harbour", [Method("a", ("pid",)), Method("a", ("lq",))]), "distinct"),
        (lambda: bench_rl("harbour", [Method("a", ("pidd",))]), "pidd"),
    ],
)
def test_bad_input_says_what_to_do(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_station_keeping_suite_end_to_end_with_two_runs(tmp_path, capsys):
    from shipgym.cli import main

    out = tmp_path / "rl.json"
    rc = main(["bench", "rl", "--suite", "station-keeping-star-hercules", "--method",
               "dp=pid,pid-smooth", "--seeds", "1", "--split", "held-out", "--reps", "200",
               "--workers", "1", "--no-progress", "--json", str(out)])  # fmt: skip
    assert rc == 0
    doc = json.loads(out.read_text())
    assert doc["schema_version"] == 1 and doc["units"] == UNITS
    held_out = [c["name"] for c in doc["suite"]["conditions"] if c["held_out"]]
    assert len(doc["rows"]) == 2 * len(held_out)
    assert {r["run"] for r in doc["rows"]} == {0, 1}
    agg = doc["aggregates"]["held-out"]["dp"]
    assert agg["inside_pct"]["runs"] == 2 and agg["inside_pct"]["conditions"] == len(held_out)
    for r in doc["rows"]:
        assert 0.0 <= r["inside_pct"] <= 100.0 and r["observer"] == "kbf"
        assert r["success"] == (r["inside_pct"] >= 95.0)
    assert "held-out" in capsys.readouterr().out
