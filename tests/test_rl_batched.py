"""The SB3 adapter of the native batched env (shipgym.rl.vec) and ``shipgym train --vec-env
batched``: the same transitions as SB3's DummyVecEnv of the single envs, seeded the same way."""

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")
pytest.importorskip("torch")

from stable_baselines3.common.vec_env import DummyVecEnv  # noqa: E402

import shipgym  # noqa: E402
from shipgym.rl.train import build_vec_env, load_hyperparams, train  # noqa: E402
from shipgym.rl.vec import BatchedVecEnv, make_batched_vec_env  # noqa: E402

ID = "shipgym/BlueLadyTracking-v0"


def test_batched_vec_env_gives_dummy_vec_envs_transitions():
    n, kw = 3, {"max_episode_steps": 6, "controller": "pid", "residual_scale": 0.25,
                "observer": "kbf"}  # fmt: skip
    batched = make_batched_vec_env(ID, n, **kw)
    dummy = DummyVecEnv([lambda: shipgym.make(ID, **kw) for _ in range(n)])
    for venv in (batched, dummy):
        venv.seed(21)
    o1, o2 = batched.reset(), dummy.reset()
    np.testing.assert_array_equal(o1, o2)
    rng = np.random.default_rng(1)
    dones = 0
    for _ in range(14):
        a = rng.uniform(-1, 1, (n, 3)).astype(np.float32)
        o1, r1, d1, i1 = batched.step(a)
        o2, r2, d2, i2 = dummy.step(a)
        np.testing.assert_array_equal(o1, o2)
        np.testing.assert_array_equal(r1, r2)
        np.testing.assert_array_equal(d1, d2)
        for i in np.nonzero(d1)[0]:
            t1, t2 = i1[i]["terminal_observation"], i2[i]["terminal_observation"]
            np.testing.assert_array_equal(t1, t2)
            assert i1[i]["TimeLimit.truncated"] == i2[i]["TimeLimit.truncated"]
            dones += 1
    assert dones >= 2 * n  # two autoresets per env
    assert batched.env_is_wrapped(object) == [False] * n
    assert batched.get_attr("control_period") == [1.0] * n


def test_adapter_needs_the_same_step_mode():
    import gymnasium as gym

    venv = gym.make_vec(ID, num_envs=2)
    with pytest.raises(ValueError, match="same-step"):
        BatchedVecEnv(venv.unwrapped)


def test_train_on_the_batched_env(tmp_path):
    """``vec_env: batched`` builds the training stack as one batched env and PPO learns on it."""
    hp = load_hyperparams("ppo", ID, residual=True)  # the shipped stack: KBF, PID residual
    venv = build_vec_env(ID, hp, 4, 0, "batched")
    assert venv.venv.venv.observer is not None and venv.venv.venv.controller is not None
    assert isinstance(venv.venv, BatchedVecEnv)
    venv.reset()
    sigmas = [c.position_sigma for c in venv.venv.venv.sensors.configs]
    assert len(set(sigmas)) == 4  # each env its own drawn sensor noise (randomize.sensors)
    run = train("ppo", timesteps=256, seed=0, n_envs=4, out=tmp_path, observer="kbf",
                residual=True, vec_env="batched", eval_freq=0, checkpoint_freq=0,
                overrides={"n_steps": 64, "batch_size": 64, "n_epochs": 1})  # fmt: skip
    assert run.model_path.exists()


def test_train_cli_seeds_options_are_checked(capsys):
    from shipgym.cli import main

    assert main(["train", "ppo", "--workers", "2", "--timesteps", "8"]) == 2
    assert "go with --seeds" in capsys.readouterr().err
    with pytest.raises(ValueError, match="distinct"):
        from shipgym.rl.train import train_seeds

        train_seeds("ppo", [1, 1])


@pytest.mark.parametrize("vec_env", ["batched", "dummy"])
def test_randomized_sensor_noise_keeps_the_recipes_faults(vec_env):
    """``randomize.sensors`` draws the noise on top of ``env_kwargs.sensors``: a recipe's
    dropouts and outliers reach every env (they were silently replaced by the default
    sensors with drawn noise)."""
    hp = load_hyperparams("ppo", ID)
    hp["env_kwargs"] = {**hp["env_kwargs"], "sensors": {"dropout_probability": 0.005,
                                                        "dropout_duration": 5.0,
                                                        "outlier_probability": 0.01}}  # fmt: skip
    venv = build_vec_env(ID, hp, 3, 0, vec_env)
    venv.reset()
    inner = venv
    while not hasattr(inner, "envs" if vec_env == "dummy" else "sensors"):
        inner = inner.venv
    if vec_env == "batched":
        configs = inner.sensors.configs
    else:
        configs = [e.unwrapped.sensor_config for e in inner.envs]
    assert len({c.position_sigma for c in configs}) == 3  # drawn per env
    for c in configs:
        assert (c.dropout_probability, c.dropout_duration, c.outlier_probability) == (
            0.005,
            5.0,
            0.01,
        )
