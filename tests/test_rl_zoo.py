"""The hyperparameter files in rl-zoo3's layout, ``shipgym train --env``, TensorBoard logging.

The keys an rl-zoo3 env block may hold are pinned from rl-zoo3 2.9.2's source
(``rl_zoo3/exp_manager.py``): ``ExperimentManager._preprocess_hyperparams``,
``_preprocess_normalization`` and ``_preprocess_action_noise`` take these keys out of the
block; every other key is passed to the algorithm's constructor
(``ALGOS[algo](env=env, tensorboard_log=..., seed=..., verbose=..., device=...,
**hyperparams)``), so it must be one of its arguments.
"""

from __future__ import annotations

import importlib.util
import inspect
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("stable_baselines3")
pytest.importorskip("torch")

from stable_baselines3 import PPO, SAC  # noqa: E402

from shipgym.rl import train as train_mod  # noqa: E402
from shipgym.rl.train import (  # noqa: E402
    DEFAULT_ACTIVATION,
    EVALUATIONS,
    SECTION,
    STATION_RADIUS,
    hyperparams_path,
    load_hyperparams,
    plain_policy_kwargs,
    train,
)

ROOT = Path(__file__).resolve().parents[1]
#: what rl-zoo3 2.9.2's ExperimentManager consumes itself (exp_manager.py, see the docstring)
ZOO_OWN_KEYS = {
    "n_envs",
    "n_timesteps",
    "normalize",
    "policy_kwargs",
    "replay_buffer_class",
    "replay_buffer_kwargs",
    "monitor_kwargs",
    "env_kwargs",
    "frame_stack",
    "policy",
    "env_wrapper",
    "vec_env_wrapper",
    "callback",
    "noise_type",
    "noise_std",
}
#: what the zoo passes to the constructor itself (a block must not repeat them)
ZOO_PASSES = {"env", "tensorboard_log", "seed", "verbose", "device"}
ALGOS = {"ppo": PPO, "sac": SAC}
TRACKING = "shipgym/BlueLadyTracking-v0"
STATION = "shipgym/StationKeeping-v0"


def _zoo_keys(algo: str) -> set[str]:
    args = set(inspect.signature(ALGOS[algo].__init__).parameters) - {"self", "_init_setup_model"}
    return ZOO_OWN_KEYS | (args - ZOO_PASSES)


def _file(algo: str) -> dict:
    return yaml.safe_load(hyperparams_path(algo).read_text())


# ---- the files ---------------------------------------------------------------------------------
@pytest.mark.parametrize("algo", ["ppo", "sac"])
def test_env_blocks_hold_only_keys_the_zoo_accepts(algo):
    data = _file(algo)
    blocks = {k: v for k, v in data.items() if k != SECTION}
    assert TRACKING in blocks
    for env_id, block in blocks.items():
        bad = sorted(set(block) - _zoo_keys(algo))
        assert not bad, f"{algo}.yml {env_id}: not rl-zoo3 keys {bad}"
        # the zoo evaluates strings in policy_kwargs: the shipped files use mappings
        assert isinstance(block.get("policy_kwargs", {}), dict)
        assert "activation_fn" not in block.get("policy_kwargs", {})
        # and gives a string learning rate to "lin_<x>".split("_")
        lr = block.get("learning_rate", 0.0)
        assert isinstance(lr, float | int) or (lr.startswith("lin_") and float(lr[4:]) > 0)
        # every env block has its shipgym options (or none) and resolves
        assert set(data.get(SECTION, {}).get(env_id, {})) <= set(train_mod.SECTION_KEYS)
        load_hyperparams(algo, env_id)
    # the shipgym section names only env ids that have a block
    assert set(data.get(SECTION, {})) <= set(blocks)


def test_the_bad_keys_of_the_old_layout_are_refused(tmp_path):
    """A key the zoo would hand to the algorithm is refused, naming where it belongs; the
    test list of accepted keys does refuse them (it can fail)."""
    assert "vec_env" not in _zoo_keys("ppo") and "eval_freq" not in _zoo_keys("ppo")
    assert set(train_mod.ZOO_BLOCK_KEYS) <= ZOO_OWN_KEYS  # what shipgym reads, the zoo reads
    for key, val in (("vec_env", "dummy"), ("observer", "kbf"), ("eval_freq", 0)):
        p = tmp_path / "h.yml"
        p.write_text(yaml.safe_dump({TRACKING: {"n_timesteps": 10, key: val}}))
        with pytest.raises(ValueError, match=f"'{key}'.*not rl-zoo3 keys.*shipgym"):
            load_hyperparams("ppo", path=p)
    p.write_text(yaml.safe_dump({TRACKING: {"n_timesteps": 10}, SECTION: {TRACKING: {"x": 1}}}))
    with pytest.raises(ValueError, match="unknown keys"):
        load_hyperparams("ppo", path=p)


@pytest.mark.parametrize("algo", ["ppo", "sac"])
@pytest.mark.parametrize("residual", [False, True])
def test_resolution_merges_block_and_section(algo, residual):
    """The resolved hyperparameters are the block's algorithm arguments unchanged, the
    section's options, the observer of env_wrapper and the activation by name (the layout
    before the split had exactly these keys in one block)."""
    data = _file(algo)
    block, opts = data[TRACKING], dict(data[SECTION][TRACKING])
    res = opts.pop("residual")
    hp = load_hyperparams(algo, residual=residual)
    for k, v in block.items():
        if k in ("env_wrapper", "policy_kwargs"):
            continue
        if not (residual and k in res):
            assert hp[k] == v, k
    for k, v in opts.items():
        if not (residual and k in res):
            assert hp[k] == v, k
    if residual:  # the residual's own overrides win, merged into mappings
        for k, v in res.items():
            if not isinstance(v, dict):
                assert hp[k] == v, k
    assert hp["observer"] == block["env_wrapper"][0][train_mod.OBSERVER_WRAPPER]["observer"]
    wrappers = [next(iter(w)) for w in block["env_wrapper"]]
    integral = train_mod.INTEGRAL_WRAPPER in wrappers
    if integral and not (residual and "error_integral" in res):
        time_constant = block["env_wrapper"][1][train_mod.INTEGRAL_WRAPPER]["time_constant"]
        assert hp["error_integral"] == time_constant
    pk = res["policy_kwargs"] if residual and "policy_kwargs" in res else block["policy_kwargs"]
    assert hp["policy_kwargs"] == {**pk, "activation_fn": DEFAULT_ACTIVATION[algo]}
    if residual:
        assert hp["controller"] == res["controller"]
        assert hp["residual_scale"] == res["residual_scale"]
    extra = set(hp) - set(block) - set(opts) - set(res if residual else {})
    from_wrapper = {"observer", "error_integral"} if integral else {"observer"}
    assert extra - {"residual", "controller", "residual_scale"} == from_wrapper - set(
        res if residual else {}
    )


def test_the_old_layout_and_the_zoo_layout_resolve_alike(tmp_path):
    """A block in the layout before rl-zoo3 compatibility (shipgym keys inline, activation
    by name) and the same in the new one: the same resolved hyperparameters (written out)."""
    new = {
        TRACKING: {
            "n_timesteps": 1000,
            "policy": "MlpPolicy",
            "n_envs": 2,
            "env_wrapper": [{train_mod.OBSERVER_WRAPPER: {"observer": "kbf"}}],
            "env_kwargs": {"max_legs": 1},
            "normalize": {"norm_obs": True},
            "n_steps": 64,
            "policy_kwargs": "dict(net_arch=[32, 32], activation_fn=nn.ReLU, log_std_init=-1)",
        },
        SECTION: {
            TRACKING: {
                "vec_env": "dummy",
                "eval_freq": 0,
                "checkpoint_freq": 0,
                "residual": {"controller": "pid", "residual_scale": 0.5},
            }
        },
    }
    p = tmp_path / "new.yml"
    p.write_text(yaml.safe_dump(new))
    expected = {
        "n_timesteps": 1000,
        "policy": "MlpPolicy",
        "n_envs": 2,
        "observer": "kbf",
        "vec_env": "dummy",
        "env_kwargs": {"max_legs": 1},
        "normalize": {"norm_obs": True},
        "n_steps": 64,
        "policy_kwargs": {"net_arch": [32, 32], "activation_fn": "relu", "log_std_init": -1},
        "eval_freq": 0,
        "checkpoint_freq": 0,
        "residual": True,
        "controller": "pid",
        "residual_scale": 0.5,
    }
    assert load_hyperparams("ppo", path=p, residual=True) == expected


def test_default_activations_are_stable_baselines3s():
    import torch.nn as nn
    from stable_baselines3.common.policies import ActorCriticPolicy
    from stable_baselines3.sac.policies import SACPolicy

    names = {nn.Tanh: "tanh", nn.ReLU: "relu"}
    for algo, cls in (("ppo", ActorCriticPolicy), ("sac", SACPolicy)):
        default = inspect.signature(cls.__init__).parameters["activation_fn"].default
        assert DEFAULT_ACTIVATION[algo] == names[default]


def test_policy_kwargs_strings_are_parsed_narrowly_never_evaluated(tmp_path):
    ok = plain_policy_kwargs("sac", "dict(net_arch=[64, 64], activation_fn=nn.ELU)")
    assert ok == {"net_arch": [64, 64], "activation_fn": "elu"}
    assert plain_policy_kwargs("ppo", {"net_arch": [8]}) == {
        "net_arch": [8],
        "activation_fn": "tanh",
    }
    marker = tmp_path / "ran"
    for text in (
        f"dict(net_arch=__import__('pathlib').Path({str(marker)!r}).touch())",
        "dict(activation_fn=th.nn.ReLU)",
        "dict(activation_fn=nn.Sigmoid)",
        "{'net_arch': [64]}",
        "dict(**x)",
        "dict(net_arch=[64]",
        "tanh",
    ):
        with pytest.raises(ValueError, match="narrow form"):
            plain_policy_kwargs("ppo", text)
    assert not marker.exists()


def test_env_wrapper_must_be_the_observer(tmp_path):
    base = {"n_timesteps": 10, "policy": "MlpPolicy"}
    cases = [
        ("rl_zoo3.wrappers.TimeFeatureWrapper", "supports env_wrapper"),
        ([{train_mod.OBSERVER_WRAPPER: {"observer": "kbf", "options": {}}}], "only 'observer'"),
        ([train_mod.OBSERVER_WRAPPER, train_mod.OBSERVER_WRAPPER], "supports env_wrapper"),
        ([{train_mod.OBSERVER_WRAPPER: {"observer": "crystal-ball"}}], "not available"),
    ]
    p = tmp_path / "h.yml"
    for spec, msg in cases:
        p.write_text(yaml.safe_dump({TRACKING: {**base, "env_wrapper": spec}}))
        with pytest.raises(ValueError, match=msg):
            load_hyperparams("ppo", path=p)
    p.write_text(yaml.safe_dump({TRACKING: {**base, "env_wrapper": train_mod.OBSERVER_WRAPPER}}))
    assert load_hyperparams("ppo", path=p)["observer"] == "kbf"  # ObserverWrapper's default
    p.write_text(yaml.safe_dump({TRACKING: base}))
    assert load_hyperparams("ppo", path=p)["observer"] is None  # no wrapper: the true state


def test_the_zoo_builds_the_same_env_as_shipgym():
    """rl-zoo3 builds ``gym.make(id, **env_kwargs)`` wrapped in the env_wrapper classes; the
    observer wrapper it imports rebuilds the env with the observer: the env
    ``shipgym.make(..., observer=)`` makes, step for step."""
    import importlib

    import gymnasium as gym

    import shipgym
    from shipgym.observers.wrapper import ObserverWrapper

    mod, _, name = train_mod.OBSERVER_WRAPPER.rpartition(".")
    assert getattr(importlib.import_module(mod), name) is ObserverWrapper
    zoo = ObserverWrapper(gym.make(TRACKING, max_legs=2), observer="kbf")
    ours = shipgym.make(TRACKING, observer="kbf", max_legs=2)
    assert zoo.observer_name == zoo.unwrapped.observer_name == "kbf"
    np.testing.assert_array_equal(zoo.reset(seed=4)[0], ours.reset(seed=4)[0])
    for _ in range(30):
        a = np.full(3, 0.2, np.float32)
        (o1, r1, *_, i1), (o2, r2, *_, i2) = zoo.step(a), ours.step(a)
        np.testing.assert_array_equal(o1, o2)
        assert r1 == r2 and i1["observer_nis"] == i2["observer_nis"]
    with pytest.raises(ValueError, match="already runs observer"):
        ObserverWrapper(ours, observer="ekf")
    with pytest.raises(ValueError, match="plan-task env"):
        ObserverWrapper(gym.make("shipgym/CourseKeeping-v0"), observer="kbf")
    zoo.close()
    ours.close()


# ---- shipgym train --env, evaluations, TensorBoard ---------------------------------------------
def test_evaluation_follows_the_env_id():
    assert EVALUATIONS[TRACKING].name == "harbour"
    assert EVALUATIONS[STATION].name == "station-keeping"
    with pytest.raises(ValueError, match="no periodic evaluation"):
        train_mod.evaluation_for("shipgym/DPSwayStep-v0")
    # the radius is the station-keeping test's documented watch circle
    from test_station_keeping import RADIUS

    assert STATION_RADIUS == RADIUS


def test_station_keeping_episode_counts_the_watch_circle():
    """The pid keeps Star Hercules within 2 m nearly all the time (tests/test_station_keeping.py)
    and a policy of zero thrust drifts away: the fraction tells them apart."""
    import shipgym

    kw = {"vessel": "star-hercules", "wind": "10@300", "observer": "kbf", "max_episode_steps": 300}
    pid = shipgym.make(STATION, controller="pid", **kw)
    bare = shipgym.make(STATION, **kw)
    zero = np.zeros(bare.action_space.shape, np.float32)
    good = train_mod.station_keeping_episode(pid, 0, None)
    drift = train_mod.station_keeping_episode(bare, 0, lambda obs: zero)
    assert good["steps"] == drift["steps"] == 300
    assert good["inside_fraction"] >= 0.95 and good["r95"] <= STATION_RADIUS
    assert drift["inside_fraction"] < 0.5 < drift["r95"]
    pid.close()
    bare.close()


SMALL = {"n_steps": 32, "batch_size": 32, "n_epochs": 1}


def test_train_station_keeping_env_on_the_batched_env(tmp_path):
    """``--env shipgym/StationKeeping-v0``: Star Hercules in 10 m/s wind on the batched env,
    evaluated on station keeping of the same vessel and wind; best_model.zip picks by it.
    One rollout of the shipped block (2 envs x 256 steps), one evaluation."""
    import shipgym
    from shipgym.cli import main
    from shipgym.controllers.learned import read_metadata
    from shipgym.rl.vec import BatchedVecEnv

    hp = load_hyperparams("ppo", STATION)
    assert hp["vec_env"] == "batched" and hp["observer"] == "kbf"
    venv = train_mod.build_vec_env(STATION, hp, 2, 0, "batched")
    assert isinstance(venv.venv, BatchedVecEnv) and venv.venv.venv.observer is not None
    single = shipgym.make(STATION, vessel="star-hercules", observer="kbf")
    assert venv.observation_space == single.observation_space
    assert venv.action_space.shape == (4,)  # Star Hercules: propeller and three tunnels
    single.close()
    venv.close()
    out = tmp_path / "sk"
    rc = main([
        "train", "ppo", "--env", STATION, "--timesteps", "512", "--n-envs", "2", "--seed", "1",
        "--out", str(out), "--eval-freq", "512", "--checkpoint-freq", "0", "--no-progress",
    ])  # fmt: skip
    assert rc == 0
    meta = read_metadata(out / "model.zip")
    assert meta.env_id == STATION and meta.env_kwargs["vessel"] == "star-hercules"
    assert meta.command.startswith(f"shipgym train ppo --env {STATION} --timesteps 512")
    evals = yaml.safe_load((out / "evaluations.json").read_text())
    assert [e["evaluation"] for e in evals] == ["station-keeping"]
    assert len(evals[0]["rows"]) == len(hp["eval_seeds"])
    assert 0.0 <= evals[0]["inside_fraction"] <= 1.0 and evals[0]["radius_m"] == 2.0
    assert (out / "best_model.zip").is_file()


def _train_small(out, **kw):
    return train(
        "ppo", timesteps=64, seed=0, n_envs=2, out=out, observer="truth", overrides=SMALL,
        eval_freq=64, eval_seeds=[100], checkpoint_freq=0, progress=False, vec_env="dummy",
        **kw,
    )  # fmt: skip


@pytest.mark.skipif(
    importlib.util.find_spec("tensorboard") is None,
    reason="tensorboard is not installed (pip install tensorboard, part of the rl extra)",
)
def test_tensorboard_events_hold_training_and_evaluation_scalars(tmp_path):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    res = _train_small(tmp_path)
    events = list((tmp_path / "tb").glob("events.out.tfevents.*"))
    assert len(events) == 1
    acc = EventAccumulator(str(tmp_path / "tb"))
    acc.Reload()
    tags = set(acc.Tags()["scalars"])
    assert {"eval/completed_fraction", "time/fps"} <= tags, tags
    completed = acc.Scalars("eval/completed_fraction")
    assert [e.step for e in completed] == [64]
    assert completed[0].value == res.evaluations[-1]["completed"] / 1
    # J_c is logged over completed runs only: 64 steps of training complete none
    assert res.evaluations[-1]["completed"] == 0 and "eval/J_c" not in tags
    head = (tmp_path / "progress.csv").read_text().splitlines()[0]
    assert "eval/completed_fraction" in head and "eval/J_c," not in head


def test_without_tensorboard_a_note_and_progress_csv_only(tmp_path, monkeypatch, capsys):
    real = importlib.util.find_spec

    def find_spec(name, *args, **kw):
        return None if name == "tensorboard" else real(name, *args, **kw)

    monkeypatch.setattr(importlib.util, "find_spec", find_spec)
    _train_small(tmp_path, tensorboard=None)
    assert capsys.readouterr().err.count("tensorboard package is not installed") == 1
    assert not (tmp_path / "tb").exists() and (tmp_path / "progress.csv").is_file()
    with pytest.raises(ImportError, match="pip install tensorboard"):
        _train_small(tmp_path / "b", tensorboard=True)


# ---- rl-zoo3 itself ------------------------------------------------------------------------------
def _zoo_python() -> str | None:
    """A Python with rl_zoo3: this one, or ``$SHIPGYM_ZOO_PYTHON`` (rl-zoo3 2.9's dependencies
    conflict with the locked ones, so it may live in a venv of its own)."""
    if importlib.util.find_spec("rl_zoo3") is not None:
        return sys.executable
    return os.environ.get("SHIPGYM_ZOO_PYTHON") or None


@pytest.mark.slow
@pytest.mark.parametrize("algo", ["ppo", "sac"])
def test_rl_zoo3_trains_the_shipped_file_unchanged(algo, tmp_path):
    """``python -m rl_zoo3.train`` on the shipped file as it is, the observer and the error
    integral in the loop: 10 000 steps for PPO (one rollout of 64 x 256 steps: ~20 s on the
    2-core machine), 20 000 for SAC (whose block takes 10 000 random steps before its first
    gradient step, so that it trains at all)."""
    py = _zoo_python()
    if py is None:
        pytest.skip(
            "rl_zoo3 is not installed (pip install 'shipgym[zoo]' in a venv of its own, "
            "then SHIPGYM_ZOO_PYTHON=that/venv/bin/python)"
        )
    conf = tmp_path / f"{algo}.yml"
    shutil.copy(hyperparams_path(algo), conf)
    steps = {"ppo": 10_000, "sac": 20_000}[algo]
    cmd = [
        py, "-m", "rl_zoo3.train", "--algo", algo, "--env", TRACKING, "--gym-packages",
        "shipgym", "--conf-file", str(conf), "-n", str(steps), "--seed", "0", "--log-folder",
        str(tmp_path / "logs"), "--num-threads", "1",
    ]  # fmt: skip
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
    }
    t0 = time.perf_counter()
    run = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600, cwd=tmp_path)
    wall = time.perf_counter() - t0
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert conf.read_bytes() == hyperparams_path(algo).read_bytes()
    runs = list((tmp_path / "logs" / algo).glob("shipgym-BlueLadyTracking-v0_*"))
    assert len(runs) == 1
    assert (runs[0] / "shipgym-BlueLadyTracking-v0.zip").is_file()
    # the zoo's record of the block it used (an OrderedDict dump: read as text, not loaded)
    saved = (runs[0] / "shipgym-BlueLadyTracking-v0" / "config.yml").read_text()
    assert train_mod.OBSERVER_WRAPPER in saved and "observer: kbf" in saved
    assert train_mod.INTEGRAL_WRAPPER in saved
    assert "total_timesteps" in run.stdout  # SB3's training log: gradient steps were taken
    print(f"rl-zoo3 {algo}: {steps} steps in {wall:.0f} s")
