"""Two-way interop (issue 32, item 3): shipgym models in plain stable-baselines3 through
``vecnormalize.pkl``, and SB3 / rl-zoo3 models (no ``shipgym.json``) scored by ``shipgym run``
and ``shipgym bench controllers`` (shipgym.rl.interop).

rl-zoo3 is not installed here: its output is produced with plain SB3 as the zoo writes it
(rl-zoo3 2.9's ``ExperimentManager``: ``logs/<algo>/<ENV>_<N>/<ENV>.zip``, and in
``<ENV>/`` ``vecnormalize.pkl`` and the ``yaml.dump`` of two ``OrderedDict`` s, ``args.yml``
with ``env`` and ``env_kwargs`` and ``config.yml`` with the block: ``env_wrapper``,
``env_kwargs``, ``normalize``, ``policy_kwargs`` as the zoo's string).
"""

from __future__ import annotations

import json
import pickle
from collections import OrderedDict
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("stable_baselines3")
pytest.importorskip("torch")

from stable_baselines3 import PPO  # noqa: E402
from stable_baselines3.common.env_util import make_vec_env  # noqa: E402
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize  # noqa: E402

from shipgym.controllers.learned import load_policy, read_metadata  # noqa: E402
from shipgym.rl.interop import (  # noqa: E402
    find_sb3_model,
    import_sb3_model,
    read_vecnormalize,
    resolve_controller,
    vecnormalize_path,
)
from shipgym.rl.train import build_env, train  # noqa: E402

STATION = "shipgym/StationKeeping-v0"
ENV = "shipgym-StationKeeping-v0"  # rl-zoo3's folder name of the id ('/' -> '-')


# ---- shipgym -> plain SB3 ------------------------------------------------------------------------
@pytest.fixture(scope="module")
def shipgym_run(tmp_path_factory):
    """A tiny ``shipgym train``: 256 steps, two evaluations (best_model.zip), a checkpoint."""
    out = tmp_path_factory.mktemp("shipgym")
    return train(
        "ppo", timesteps=256, seed=0, n_envs=2, out=out, observer="truth",
        overrides={"n_steps": 64, "batch_size": 64, "n_epochs": 1}, eval_freq=128,
        eval_seeds=[100], checkpoint_freq=128, progress=False, vec_env="dummy",
    )  # fmt: skip


def _raw_observations(env_id, hp, n=40):
    """Raw observations of the training stack, from a few random steps (wider than the
    statistics: a normalised entry beyond clip_obs tests the clip as well)."""
    env = build_env(env_id, hp, randomize=False)
    obs, _ = env.reset(seed=3)
    out = [obs]
    rng = np.random.default_rng(0)
    for _ in range(n - 1):
        obs, *_ = env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
        out.append(obs)
    env.close()
    rows = np.asarray(out, dtype=np.float32)
    return np.concatenate([rows, rows * 50.0]).astype(np.float32)


def test_train_writes_vecnormalize_next_to_every_model(shipgym_run):
    out = shipgym_run.out_dir
    assert vecnormalize_path(out / "model.zip") == out / "vecnormalize.pkl"
    for zip_, pkl in (
        (out / "model.zip", out / "vecnormalize.pkl"),
        (out / "best_model.zip", out / "best_model_vecnormalize.pkl"),
        (out / "checkpoints" / "ppo_128_steps.zip",
         out / "checkpoints" / "ppo_128_steps_vecnormalize.pkl"),
    ):  # fmt: skip
        assert zip_.is_file() and pkl.is_file(), pkl
        # SB3's own loader (which unpickles) reads the same statistics as shipgym.json
        norm = read_metadata(zip_).normalization
        vn = VecNormalize.load(str(pkl), DummyVecEnv([lambda n=norm: _spaces_env(n)]))
        np.testing.assert_array_equal(vn.obs_rms.mean, norm.mean)
        np.testing.assert_array_equal(vn.obs_rms.var, norm.var)
        assert vn.obs_rms.count == norm.count
        assert (vn.clip_obs, vn.epsilon, vn.gamma) == (norm.clip_obs, norm.epsilon, norm.gamma)
        assert (vn.norm_obs, vn.norm_reward, vn.clip_reward) == (
            norm.norm_obs, norm.norm_reward, norm.clip_reward,
        )  # fmt: skip
        assert float(vn.ret_rms.var) == norm.ret_var
        assert read_vecnormalize(pkl) == norm  # and shipgym's reader, unpickling nothing
    # the final statistics are those of the VecNormalize the run trained with
    np.testing.assert_array_equal(
        VecNormalize.load(
            str(out / "vecnormalize.pkl"), DummyVecEnv([lambda: _spaces_env(norm)])
        ).obs_rms.mean,
        shipgym_run.vec_normalize.obs_rms.mean,
    )


def _spaces_env(norm):
    import gymnasium as gym

    class E(gym.Env):
        observation_space = gym.spaces.Box(-np.inf, np.inf, (len(norm.mean),), np.float32)
        action_space = gym.spaces.Box(-1, 1, (3,), np.float32)

    return E()


def test_plain_sb3_gives_shipgym_actions(shipgym_run):
    """The documented recipe: ``VecNormalize.load`` + ``PPO.load`` on the training stack give
    the deterministic actions of shipgym's loader for the same raw observations."""
    zip_ = shipgym_run.model_path
    meta = read_metadata(zip_)
    raw = _raw_observations(meta.env_id, meta.hyperparams)
    venv = DummyVecEnv([lambda: build_env(meta.env_id, meta.hyperparams, randomize=False)])
    venv = VecNormalize.load(str(vecnormalize_path(zip_)), venv)
    venv.training, venv.norm_reward = False, False
    model = PPO.load(zip_, device="cpu")
    sb3, _ = model.predict(venv.normalize_obs(raw), deterministic=True)
    ours = load_policy(zip_)(raw)
    assert np.abs(venv.normalize_obs(raw)).max() == venv.clip_obs  # the clip is exercised
    np.testing.assert_allclose(ours, sb3, rtol=0, atol=1e-6)
    assert np.ptp(sb3, axis=0).max() > 1e-3  # not a constant action
    # the loop of the recipe: obs from the VecNormalize, the same actions step by step
    obs = venv.reset()
    for _ in range(5):
        a, _ = model.predict(obs, deterministic=True)
        np.testing.assert_allclose(load_policy(zip_)(venv.get_original_obs()), a, atol=1e-6)
        obs, *_ = venv.step(a)


def test_a_model_trained_without_normalisation_has_no_pkl(tmp_path):
    res = train(
        "ppo", timesteps=64, seed=0, n_envs=2, out=tmp_path, observer="truth",
        overrides={"n_steps": 32, "batch_size": 32, "n_epochs": 1, "normalize": False},
        eval_freq=0, checkpoint_freq=0, progress=False, vec_env="dummy",
    )  # fmt: skip
    assert read_metadata(res.model_path).normalization is None
    assert not (tmp_path / "vecnormalize.pkl").exists()


# ---- reading a vecnormalize.pkl unpickles nothing ------------------------------------------
class _Exploit:
    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (Path(self.marker),))


def test_read_vecnormalize_runs_no_code(tmp_path):
    marker = tmp_path / "pwned"
    bad = tmp_path / "vecnormalize.pkl"
    bad.write_bytes(pickle.dumps(_Exploit(str(marker))))
    with pytest.raises(ValueError, match="refers to pathlib.*not hold"):
        read_vecnormalize(bad)
    assert not marker.exists()
    bad.write_bytes(pickle.dumps({"obs_rms": 1}))
    with pytest.raises(ValueError, match="not a stable-baselines3 VecNormalize file"):
        read_vecnormalize(bad)
    bad.write_bytes(b"not a pickle")
    with pytest.raises(ValueError, match="not a stable-baselines3 VecNormalize file"):
        read_vecnormalize(bad)
    with pytest.raises(FileNotFoundError):
        read_vecnormalize(tmp_path / "missing.pkl")


# ---- plain SB3 / rl-zoo3 -> shipgym ---------------------------------------------------------
#: what the zoo's block says: Star Hercules, a residual on the PID through the KBF (the plan
#: tasks take observer= and controller= in gym.make; the ObserverWrapper form of env_wrapper
#: under SB3's make_vec_env: tests/test_observer_wrapper.py)
ENV_KWARGS = {"vessel": "star-hercules", "observer": "kbf", "controller": "pid",
              "residual_scale": 0.25}  # fmt: skip


def _zoo_run(root: Path) -> Path:
    """What ``python -m rl_zoo3.train --algo ppo --env shipgym/StationKeeping-v0
    --gym-packages shipgym`` leaves, made with plain SB3 (256 steps, 2 envs)."""
    save = root / "logs" / "ppo" / f"{ENV}_1"
    params = save / ENV
    params.mkdir(parents=True)
    venv = VecNormalize(make_vec_env(STATION, n_envs=2, seed=0, env_kwargs=ENV_KWARGS), gamma=0.99)
    import torch.nn as nn

    model = PPO(
        "MlpPolicy", venv, n_steps=64, batch_size=64, n_epochs=1, seed=0, device="cpu",
        policy_kwargs={"net_arch": [32, 32], "activation_fn": nn.ReLU},
    )  # fmt: skip
    model.learn(256)
    model.save(save / ENV)  # the zoo's save_trained_model
    venv.save(str(params / "vecnormalize.pkl"))
    venv.close()
    args = OrderedDict(sorted({"algo": "ppo", "env": STATION, "env_kwargs": None, "seed": 0,
                               "gym_packages": ["shipgym"]}.items()))  # fmt: skip
    (params / "args.yml").write_text(yaml.dump(args))
    block = OrderedDict(sorted({
        "env_kwargs": ENV_KWARGS, "n_envs": 2, "n_timesteps": 256,
        "normalize": True, "policy": "MlpPolicy",
        "policy_kwargs": "dict(net_arch=[32, 32], activation_fn=nn.ReLU)",
    }.items()))  # fmt: skip
    (params / "config.yml").write_text(yaml.dump(block))
    assert "!!python/object/apply:collections.OrderedDict" in (params / "args.yml").read_text()
    return save / f"{ENV}.zip"


@pytest.fixture(scope="module")
def zoo_model(tmp_path_factory):
    return _zoo_run(tmp_path_factory.mktemp("zoo"))


def test_zoo_model_is_described_by_its_files(zoo_model):
    m = find_sb3_model(zoo_model, "ppo")
    assert m.env_id == STATION and m.env_kwargs == {"vessel": "star-hercules"}
    assert (m.observer, m.controller, m.residual_scale) == ("kbf", "pid", 0.25)
    assert m.error_integral is None
    assert m.vecnormalize == zoo_model.parent / ENV / "vecnormalize.pkl"


def test_zoo_model_gives_its_sb3_actions_through_shipgym(zoo_model, tmp_path):
    imported = import_sb3_model(find_sb3_model(zoo_model, "ppo"), tmp_path / "imported.zip")
    meta = read_metadata(imported)
    assert (meta.residual, meta.controller, meta.observer) == (True, "pid", "kbf")
    assert meta.policy_kwargs == {"net_arch": [32, 32], "activation_fn": "relu"}
    pkl = zoo_model.parent / ENV / "vecnormalize.pkl"
    hp = {"env_kwargs": {"vessel": "star-hercules"}, "observer": "kbf", "residual": True,
          "controller": "pid", "residual_scale": 0.25}  # fmt: skip
    raw = _raw_observations(STATION, hp)
    vn = VecNormalize.load(str(pkl), DummyVecEnv([lambda: build_env(STATION, hp)]))
    sb3, _ = PPO.load(zoo_model, device="cpu").predict(vn.normalize_obs(raw), deterministic=True)
    np.testing.assert_allclose(load_policy(imported)(raw), sb3, rtol=0, atol=1e-6)
    # the copy is still a plain SB3 zip
    again, _ = PPO.load(imported, device="cpu").predict(vn.normalize_obs(raw), deterministic=True)
    np.testing.assert_array_equal(again, sb3)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """The imported models go to a cache folder of the test."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    return tmp_path / "cache" / "shipgym" / "imported"


def test_shipgym_run_and_bench_score_a_zoo_model(zoo_model, tmp_path, cache, capsys):
    from shipgym.cli import main

    out = tmp_path / "run.json"
    rc = main(["run", "station-keeping", "--vessel", "star-hercules", "--controller",
               f"ppo:{zoo_model}", "--json", str(out), "--no-progress"])  # fmt: skip
    assert rc == 0
    err = capsys.readouterr().err
    assert "stable-baselines3 model without shipgym.json" in err and STATION in err
    res = json.loads(out.read_text())
    assert res["station_keeping"]["steps"] > 0
    assert 0.0 <= res["station_keeping"]["inside_fraction"] <= 1.0
    # the results name the imported copy, a file that stays (in the cache), which records
    # where it came from
    imported = Path(res["model"]["path"])
    assert imported.parent.parent == cache and imported.name == zoo_model.name
    assert res["model"]["trained_on"] == STATION
    assert read_metadata(imported).extra["imported_from"] == str(zoo_model)
    bench = tmp_path / "bench.json"
    rc = main(["bench", "controllers", "--task", "station-keeping", "--controllers",
               f"ppo:{zoo_model}", "--seeds", "1", "--workers", "1", "--json", str(bench),
               "--no-progress"])  # fmt: skip
    assert rc == 0
    rows = json.loads(bench.read_text())["rows"]
    assert len(rows) == 1 and rows[0]["controller"] == "ppo"
    assert rows[0]["vessel"] == "star-hercules"


def test_what_a_model_without_shipgym_json_needs(zoo_model, tmp_path, cache):
    import shutil

    # the zip alone: no env id
    lone = tmp_path / "lone" / "model.zip"
    lone.parent.mkdir()
    shutil.copy(zoo_model, lone)
    with pytest.raises(ValueError, match="args.yml with 'env: <shipgym env id"):
        resolve_controller(f"ppo:{lone}")
    # the env id, not the statistics
    (lone.parent / "args.yml").write_text(f"env: {STATION}\n")
    with pytest.raises(ValueError, match="no vecnormalize.pkl next to it"):
        resolve_controller(f"ppo:{lone}")
    # said to be trained without VecNormalize: imported (wrong stack: refused by its shape)
    (lone.parent / "args.yml").write_text(
        f"env: {STATION}\nnormalize: false\nenv_kwargs: {{vessel: star-hercules}}\n"
    )
    name = resolve_controller(f"ppo:{lone}", quiet=True)
    assert name.startswith("ppo:") and read_metadata(name[4:]).normalization is None
    # statistics of another observation (a stack with the error integral appended)
    shutil.copy(zoo_model.parent / ENV / "vecnormalize.pkl", lone.parent / "vecnormalize.pkl")
    (lone.parent / "config.yml").write_text(
        "env_wrapper:\n- shipgym.observers.wrapper.ObserverWrapper: {observer: kbf}\n"
        "- shipgym.envs.integral.ErrorIntegralObservation: {time_constant: 100.0}\n"
    )
    (lone.parent / "args.yml").write_text(
        f"env: {STATION}\nenv_kwargs: {{vessel: star-hercules, controller: pid}}\n"
    )
    with pytest.raises(ValueError, match=r"normalises \d+ observation entries.*gives"):
        import_sb3_model(find_sb3_model(lone, "ppo"), tmp_path / "x.zip")
    # not a shipgym env
    (lone.parent / "args.yml").write_text("env: Pendulum-v1\n")
    with pytest.raises(ValueError, match="not a shipgym environment"):
        find_sb3_model(lone, "ppo")
    # a shipgym model and the other names pass through unchanged
    assert resolve_controller("pid") == "pid" and resolve_controller("ppo") == "ppo"


def test_plain_sb3_sac_model_is_imported_with_its_actions(tmp_path, cache):
    """A SAC model (policy_kwargs as SAC saves them, with use_sde) from a plain SB3 run."""
    from stable_baselines3 import SAC

    folder = tmp_path / "sac"
    folder.mkdir()
    kw = {"vessel": "star-hercules"}
    venv = VecNormalize(make_vec_env(STATION, n_envs=1, seed=0, env_kwargs=kw))
    model = SAC("MlpPolicy", venv, learning_starts=32, batch_size=32, seed=0, device="cpu",
                policy_kwargs={"net_arch": [32, 32]})  # fmt: skip
    model.learn(64)
    model.save(folder / "model.zip")
    venv.save(str(folder / "vecnormalize.pkl"))
    (folder / "args.yml").write_text(f"env: {STATION}\nenv_kwargs: {{vessel: star-hercules}}\n")
    name = resolve_controller(f"sac:{folder / 'model.zip'}", quiet=True)
    imported = Path(name.partition(":")[2])
    assert read_metadata(imported).algorithm == "sac"
    raw = _raw_observations(STATION, {"env_kwargs": kw})
    sb3, _ = model.predict(venv.normalize_obs(raw), deterministic=True)
    np.testing.assert_allclose(load_policy(imported)(raw), sb3, rtol=0, atol=1e-6)
    with pytest.raises(ValueError, match="holds a sac model, not ppo: use sac:"):
        resolve_controller(f"ppo:{folder / 'model.zip'}")


def test_zoo_yaml_is_read_without_constructing_objects(zoo_model, tmp_path, cache):
    import shutil

    folder = tmp_path / "m"
    folder.mkdir()
    shutil.copy(zoo_model, folder / "model.zip")
    shutil.copy(zoo_model.parent / ENV / "vecnormalize.pkl", folder / "vecnormalize.pkl")
    marker = tmp_path / "PWNED"
    (folder / "args.yml").write_text(
        f"env: {STATION}\nx: !!python/object/apply:pathlib.Path.touch [{str(marker)!r}]\n"
    )
    with pytest.raises(ValueError, match="not the YAML rl-zoo3 writes"):
        find_sb3_model(folder / "model.zip", "ppo")
    assert not marker.exists()
    # the tags rl-zoo3 does write: an OrderedDict, a tuple among the values
    (folder / "args.yml").write_text(
        "!!python/object/apply:collections.OrderedDict\n- - - env\n    - "
        f"{STATION}\n  - - train_freq\n    - !!python/tuple [1, episode]\n"
    )
    assert find_sb3_model(folder / "model.zip", "ppo").env_id == STATION
