"""Training and learned controllers (shipgym.rl, shipgym.controllers.learned); fast smoke runs."""

import json
import zipfile

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")
pytest.importorskip("torch")

import torch  # noqa: E402
from stable_baselines3 import PPO  # noqa: E402

from shipgym.controllers.learned import (  # noqa: E402
    METADATA_NAME,
    LearnedControllerWrapper,
    ModelMetadata,
    baseline_model_path,
    is_learned_controller,
    load_policy,
    parse_learned_controller,
    read_metadata,
)
from shipgym.rl.train import hyperparams_path, load_hyperparams, train  # noqa: E402
from shipgym.stacks import make_learned_env  # noqa: E402

#: a few hundred steps of a tiny PPO: seconds
SMALL = {"n_steps": 64, "batch_size": 64, "n_epochs": 2}


def _train(out, seed=0, timesteps=256, **kw):
    kw.setdefault("residual", True)
    kw.setdefault("observer", "truth")
    kw.setdefault("eval_freq", 0)
    kw.setdefault("checkpoint_freq", 0)
    return train(
        "ppo", timesteps=timesteps, seed=seed, n_envs=2, out=out, overrides=SMALL,
        progress=False, **kw,
    )  # fmt: skip


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    out = tmp_path_factory.mktemp("ppo")
    return _train(out, checkpoint_freq=128, eval_freq=256, eval_seeds=[100])


# ---- hyperparameter files ----------------------------------------------------------------------
@pytest.mark.parametrize("algo", ["ppo", "sac"])
@pytest.mark.parametrize("residual", [False, True])
def test_shipped_hyperparams_load(algo, residual):
    hp = load_hyperparams(algo, residual=residual)
    assert hp["residual"] is residual
    assert isinstance(hp["n_timesteps"], int) and hp["n_timesteps"] > 0
    assert hp["observer"] == "kbf"
    assert isinstance(hp["policy_kwargs"]["activation_fn"], str)  # plain data, no objects
    if residual:
        assert hp["controller"] == "pid" and 0 < hp["residual_scale"] <= 1
    assert hyperparams_path(algo).is_file()


def test_hyperparams_errors(tmp_path):
    bad = tmp_path / "h.yml"
    bad.write_text("shipgym/BlueLadyTracking-v0:\n  n_steps: 64\n  warp_drive: 9\n")
    with pytest.raises(ValueError, match="warp_drive"):
        load_hyperparams("ppo", path=bad)
    with pytest.raises(ValueError, match="no hyperparameters"):
        load_hyperparams("ppo", env_id="shipgym/BlueLadyHarbour-v0")
    # safe_load: python tags are refused, never executed
    bad.write_text("shipgym/BlueLadyTracking-v0: !!python/object/apply:os.system ['true']\n")
    with pytest.raises(ValueError, match="YAML"):
        load_hyperparams("ppo", path=bad)


# ---- the pipeline ----------------------------------------------------------------------------
def test_smoke_train_save_load_run(trained):
    out = trained.out_dir
    assert trained.num_timesteps == 256
    for name in ("model.zip", "best_model.zip", "config.yml", "args.yml", "command.txt"):
        assert (out / name).is_file(), name
    assert sorted(p.name for p in (out / "checkpoints").iterdir()) == [
        "ppo_128_steps.zip",
        "ppo_128_steps_vecnormalize.pkl",  # SB3's VecNormalize file of each (issue 32)
        "ppo_256_steps.zip",
        "ppo_256_steps_vecnormalize.pkl",
    ]
    evals = json.loads((out / "evaluations.json").read_text())
    assert evals[-1]["timesteps"] == 256 and "J_c" in evals[-1]
    meta = read_metadata(trained.model_path)
    assert meta.algorithm == "ppo" and meta.env_id == "shipgym/BlueLadyTracking-v0"
    assert meta.residual and meta.controller == "pid" and meta.residual_scale == 0.25
    assert meta.normalization is not None and len(meta.normalization.mean) == 15
    assert meta.seed == 0 and meta.command.startswith("shipgym train ppo --timesteps 256")
    assert meta.command == (out / "command.txt").read_text().strip()
    assert trained.model_path.stat().st_size < 1_000_000

    env = make_learned_env("harbour", trained.model_path)
    layers = [type(w).__name__ for w in _stack(env)]
    assert layers[0] == "LearnedControllerWrapper" and env.unwrapped.controller_name == "pid"
    obs, _ = env.reset(seed=0)
    for _ in range(10):
        obs, reward, terminated, truncated, info = env.step(np.zeros(3, np.float32))
        assert np.isfinite(reward) and not terminated
    assert info["policy_action"].shape == (3,) and "controller_action" in info
    # the spec rebuilds the whole stack (RecordConstructorArgs)
    env2 = gym.make(env.spec)
    assert type(env2).__name__ == "LearnedControllerWrapper"
    env.close()
    env2.close()


def _stack(env):
    out = []
    while isinstance(env, gym.Wrapper):
        out.append(env)
        env = env.env
    return out


def test_loaded_policy_reproduces_actions_exactly(trained):
    model, vn = trained.model, trained.vec_normalize
    rng = np.random.default_rng(0)
    mean = np.asarray(vn.obs_rms.mean)
    std = np.sqrt(np.asarray(vn.obs_rms.var))
    obs = (mean + std * rng.normal(size=(64, 15)) * 3).astype(np.float32)
    expected, _ = model.predict(vn.normalize_obs(obs), deterministic=True)
    policy = load_policy(trained.model_path)
    np.testing.assert_array_equal(policy(obs), expected)
    for k in range(4):  # one observation at a time, as the wrapper calls it (batch size 1)
        single, _ = model.predict(vn.normalize_obs(obs[k]), deterministic=True)
        np.testing.assert_array_equal(policy(obs[k]), single)
    # and SB3's own loader (which unpickles) agrees as well
    sb3 = PPO.load(trained.model_path, device="cpu")
    np.testing.assert_array_equal(
        sb3.predict(vn.normalize_obs(obs), deterministic=True)[0], expected
    )


def test_same_seed_same_training(tmp_path):
    a = _train(tmp_path / "a", seed=3)
    b = _train(tmp_path / "b", seed=3)
    c = _train(tmp_path / "c", seed=4)
    pa = a.model.policy.state_dict()
    pb = b.model.policy.state_dict()
    pc = c.model.policy.state_dict()
    assert all(torch.equal(pa[k], pb[k]) for k in pa)
    assert not all(torch.equal(pa[k], pc[k]) for k in pa)
    np.testing.assert_array_equal(a.vec_normalize.obs_rms.mean, b.vec_normalize.obs_rms.mean)
    log_a = (tmp_path / "a" / "progress.csv").read_text().splitlines()
    log_b = (tmp_path / "b" / "progress.csv").read_text().splitlines()
    strip = _without_time_columns
    assert strip(log_a) == strip(log_b)  # the same training curve


def _without_time_columns(lines):
    head = lines[0].split(",")
    keep = [i for i, h in enumerate(head) if not h.startswith("time/")]
    return [[row.split(",")[i] for i in keep] for row in lines]


def test_resume_from_checkpoint(trained, tmp_path):
    ckpt = trained.out_dir / "checkpoints" / "ppo_128_steps.zip"
    res = train(
        "ppo", timesteps=128, seed=1, out=tmp_path / "r", resume=ckpt, eval_freq=0,
        checkpoint_freq=0, progress=False,
    )  # fmt: skip
    assert res.num_timesteps == 256
    meta = read_metadata(res.model_path)
    assert meta.residual and "--resume" in meta.command
    # the normalisation statistics went on from the checkpoint's
    assert meta.normalization.count > read_metadata(ckpt).normalization.count


# ---- refusing what is not a shipgym model ------------------------------------------------------
def test_refuses_plain_sb3_zip_and_other_files(tmp_path):
    plain = tmp_path / "plain.zip"
    PPO("MlpPolicy", "Pendulum-v1", n_steps=64, batch_size=64, device="cpu").save(plain)
    for fn in (read_metadata, load_policy, lambda p: make_learned_env("harbour", p)):
        with pytest.raises(ValueError, match="not a shipgym model.*no shipgym.json"):
            fn(plain)
    text = tmp_path / "model.zip"
    text.write_text("hello")
    with pytest.raises(ValueError, match="not a shipgym model: not a zip"):
        read_metadata(text)
    forged = tmp_path / "forged.zip"
    with zipfile.ZipFile(forged, "w") as zf:
        zf.writestr(METADATA_NAME, json.dumps({"format": "something-else"}))
    with pytest.raises(ValueError, match="does not describe a shipgym model"):
        read_metadata(forged)
    with pytest.raises(FileNotFoundError):
        read_metadata(tmp_path / "missing.zip")


def test_controller_names_and_stack_checks(trained):
    assert is_learned_controller("ppo") and is_learned_controller("sac:x.zip")
    assert not is_learned_controller("pid")
    assert parse_learned_controller(f"ppo:{trained.model_path}") == ("ppo", trained.model_path)
    with pytest.raises(ValueError, match="holds a ppo model"):
        parse_learned_controller(f"sac:{trained.model_path}")
    # a residual model needs its DP controller below it
    env = gym.make("shipgym/BlueLadyHarbour-v0")
    with pytest.raises(ValueError, match="controller='pid'"):
        LearnedControllerWrapper(env, trained.model_path)
    other = gym.make("shipgym/BlueLadyHarbour-v0", controller="pid", residual_scale=1.0)
    with pytest.raises(ValueError, match="residual_scale"):
        LearnedControllerWrapper(other, trained.model_path)
    meta = read_metadata(trained.model_path)
    assert ModelMetadata.from_json(meta.to_json()) == meta


def test_shipped_baseline():
    path = baseline_model_path("ppo-residual")
    assert path.stat().st_size < 1_000_000
    meta = read_metadata(path)
    assert meta.algorithm == "ppo" and meta.command.startswith("shipgym train ppo")
    assert parse_learned_controller("ppo-residual") == ("ppo", path)
    load_policy(path)


def test_learned_wrapper_keeps_the_env_metadata():
    # the model's metadata lives in model_metadata; gymnasium's metadata (render modes) stays
    env = make_learned_env("harbour", "ppo-residual")
    assert env.metadata["render_modes"] == ["rgb_array"]
    assert isinstance(env.model_metadata, ModelMetadata)
    assert env.model_metadata.algorithm == "ppo"
    env.close()


def test_sac_smoke(tmp_path):
    res = train(
        "sac", timesteps=150, seed=0, n_envs=1, out=tmp_path, observer="truth",
        overrides={"learning_starts": 100, "batch_size": 32}, eval_freq=0, checkpoint_freq=0,
        progress=False,
    )  # fmt: skip
    policy = load_policy(res.model_path)
    assert policy.metadata.error_integral == 100.0  # sac.yml's env_wrapper: 15 + 3 entries
    a = policy(np.zeros(18, np.float32))
    assert a.shape == (3,) and np.all(np.abs(a) <= 1)


def test_bench_rows(trained):
    from shipgym.rl.bench import bench_controllers, controller_table

    rows = bench_controllers(
        ["pid", f"ppo:{trained.model_path}"], seeds=1, observer="truth", workers=1,
        progress=False,
    )  # fmt: skip
    assert [r["controller"] for r in rows] == ["pid", "ppo"]
    for r in rows:
        assert {"seed", "completed", "quay_contact", "J_c"} <= set(r)
    table = controller_table(rows)
    assert (
        table.count("\n") == 3 and "| legs |" in table and "| pid |" in table and "| ppo |" in table
    )


def test_sac_resume_restores_what_sb3_load_does(tmp_path):
    """SAC through the safe resume path: actor, critics, their optimizers and the entropy
    coefficient equal stable-baselines3's own (unpickling) load of the same trusted file."""
    from stable_baselines3 import SAC

    from shipgym.rl.train import _algo_kwargs, build_vec_env, restore_model_state

    res = train(
        "sac", timesteps=150, seed=0, n_envs=1, out=tmp_path, observer="truth",
        overrides={"learning_starts": 100, "batch_size": 32}, eval_freq=0, checkpoint_freq=0,
        progress=False,
    )  # fmt: skip
    meta = read_metadata(res.model_path)
    venv = build_vec_env(meta.env_id, meta.hyperparams, 1, 0)
    fresh = SAC("MlpPolicy", venv, device="cpu", **_algo_kwargs("sac", meta.hyperparams))
    restore_model_state(fresh, res.model_path, meta)
    ref = SAC.load(res.model_path, device="cpu")  # our own file: trusted reference
    a, b = fresh.policy.state_dict(), ref.policy.state_dict()
    assert a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)
    assert torch.equal(fresh.log_ent_coef, ref.log_ent_coef)
    assert fresh.num_timesteps == ref.num_timesteps == 150
    again = train(
        "sac", timesteps=20, seed=0, out=tmp_path / "r", resume=res.model_path, eval_freq=0,
        checkpoint_freq=0, progress=False,
    )  # fmt: skip
    assert again.num_timesteps == 170
    venv.close()


def test_a_run_from_another_hyperparameter_file_records_it_in_its_command(tmp_path):
    """The stored command reproduces the run: it names the file the hyperparameters came
    from (the robust recipe), which the shipped file's command does not need to."""
    from shipgym.rl.train import train_command

    robust = hyperparams_path("ppo").with_name("ppo_robust.yml")
    hp = load_hyperparams("ppo", "shipgym/StationKeeping-v0", path=robust)
    assert hp["env_kwargs"]["random_wind"] == [4.0, 14.0]
    assert hp["env_kwargs"]["sensors"]["dropout_probability"] > 0
    cmd = train_command("ppo", timesteps=10, seed=1, n_envs=2, out="o", residual=False,
                        observer="kbf", env_id="shipgym/StationKeeping-v0",
                        hyperparams=robust)  # fmt: skip
    assert f"--hyperparams {robust}" in cmd
    assert "--hyperparams" not in train_command("ppo", timesteps=10, seed=1, n_envs=2, out="o",
                                                residual=False, observer="kbf")  # fmt: skip


def test_the_robust_harbour_recipe_trains_with_its_action_filter_and_runs_with_it(tmp_path):
    """The Blue Lady's block of ppo_robust.yml: its faults reach the training envs, its
    policy's commands pass the reversal hysteresis there and in every env the model runs in
    (``make_learned_env``), and a stack without the filter is refused."""
    import gymnasium as gym

    from shipgym.controllers.learned import read_metadata
    from shipgym.stacks import make_learned_env

    robust = hyperparams_path("ppo").with_name("ppo_robust.yml")
    hp = load_hyperparams("ppo", path=robust)
    assert hp["env_kwargs"]["condition_commands"] is True
    assert hp["env_kwargs"]["sensors"]["dropout_duration"] == 5.0
    run = train("ppo", timesteps=128, seed=0, n_envs=2, out=tmp_path, hyperparams=robust,
                eval_freq=0, checkpoint_freq=0, progress=False,
                overrides={"n_steps": 64, "batch_size": 64, "n_epochs": 1})  # fmt: skip
    meta = read_metadata(run.model_path)
    assert meta.env_kwargs["condition_commands"] is True
    env = make_learned_env("harbour", run.model_path)
    assert env.unwrapped.batch.conditioning is not None
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.zeros(3, np.float32))
    with pytest.raises(ValueError, match="condition_commands"):
        from shipgym.controllers.learned import LearnedControllerWrapper

        LearnedControllerWrapper(gym.make("shipgym/BlueLadyHarbour-v0", observer="kbf"),
                                 run.model_path)  # fmt: skip
