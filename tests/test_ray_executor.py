"""Sweeps on Ray (``--executor ray``): the same results as the process pool for the same seeds,
on a local Ray instance with 2 workers; skipped when the ``ray`` extra is absent."""

from __future__ import annotations

import sys

import pytest

from shipgym.bench import Executor, run_jobs


def _square(x: int) -> int:
    return x * x


def test_executor_validation_and_a_missing_extra(monkeypatch):
    with pytest.raises(ValueError, match="unknown executor 'dask'"):
        Executor("dask")
    with pytest.raises(ValueError, match="needs kind='ray'"):
        Executor("process", "auto")
    monkeypatch.setitem(sys.modules, "ray", None)  # as if the extra were not installed
    with pytest.raises(ImportError, match=r"shipgym\[ray\]"):
        run_jobs(_square, [1, 2], executor="ray", progress=False)


def test_cli_refuses_an_address_without_ray(capsys):
    from shipgym.cli import main

    assert main(["bench", "observers", "--ray-address", "auto", "--no-progress"]) == 2
    assert "--ray-address needs --executor ray" in capsys.readouterr().err


@pytest.fixture(scope="module")
def ray():
    ray = pytest.importorskip("ray", reason="the ray extra is not installed: pip install "
                              "'shipgym[ray]' (make ray)")  # fmt: skip
    yield ray
    if ray.is_initialized():
        ray.shutdown()


def test_run_jobs_on_ray_equals_the_process_pool(ray):
    """A job function the Ray workers can import (a shipgym function, not this test module's)."""
    from shipgym.dynamics.frames import wrap_angle

    jobs = [0.5 * k for k in range(-7, 8)]
    seen = []
    out = run_jobs(wrap_angle, jobs, workers=2, executor="ray", progress=False,
                   on_result=lambda i, r: seen.append(i))  # fmt: skip
    assert out == run_jobs(wrap_angle, jobs, workers=2, progress=False)
    assert out == [wrap_angle(j) for j in jobs]
    assert sorted(seen) == list(range(len(jobs)))
    assert not ray.is_initialized()  # the local instance it started is stopped again


@pytest.mark.slow
def test_bench_observers_table_is_the_same_on_ray(ray, capsys):
    from shipgym.cli import main

    argv = ["bench", "observers", "--seeds", "2", "--workers", "2", "--no-progress"]
    assert main(argv) == 0
    plain = capsys.readouterr().out
    assert main([*argv, "--executor", "ray"]) == 0
    on_ray = capsys.readouterr().out
    table = lambda text: [ln for ln in text.splitlines() if ln.startswith("|")]  # noqa: E731
    assert table(plain) and table(plain) == table(on_ray)


def _tiny_training(out, executor):
    from shipgym.rl.train import train_seeds

    return train_seeds("ppo", [3, 4], out=out, executor=executor, workers=2, progress=False,
                       timesteps=64, n_envs=2, observer="truth", eval_freq=0,
                       checkpoint_freq=0, overrides={"n_steps": 32, "batch_size": 32,
                                                     "n_epochs": 1})  # fmt: skip


def _weights(path):
    import zipfile

    with zipfile.ZipFile(path) as z:
        return z.read("policy.pth")


@pytest.mark.slow
def test_multi_seed_training_on_ray_equals_the_process_pool(ray, tmp_path):
    """``train_seeds`` (``shipgym train --seeds``): the same models from Ray as from the process
    pool, and from a rerun (each run's result depends on its seed only)."""
    pytest.importorskip("stable_baselines3")
    pool = _tiny_training(tmp_path / "pool", "process")
    on_ray = _tiny_training(tmp_path / "ray", "ray")
    assert [r["seed"] for r in pool] == [r["seed"] for r in on_ray] == [3, 4]
    for a, b in zip(pool, on_ray, strict=True):
        assert a["model_path"].endswith(f"seed{a['seed']}/model.zip")
        assert _weights(a["model_path"]) == _weights(b["model_path"])
    assert _weights(pool[0]["model_path"]) != _weights(pool[1]["model_path"])


@pytest.mark.slow
def test_bench_on_a_cluster_named_by_ray_address_gives_the_pool_table(ray, tmp_path):
    """``RAY_ADDRESS`` set (a cluster: here a local head this test starts), ``--executor ray``
    connects to it without local-only settings (it exited 2, "num_cpus must not be
    provided"), and the table is the process pool's; so is ``--ray-address`` to it."""
    import os
    import shutil
    import socket
    import subprocess
    import tempfile

    exe = shutil.which("ray", path=os.path.dirname(sys.executable))
    if exe is None:
        pytest.skip("the ray command is not installed beside this Python")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}
    short = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # (Ray's socket paths: <= 107 bytes)
    head = subprocess.run(
        [exe, "start", "--head", f"--port={port}", "--num-cpus=2", "--include-dashboard=false",
         "--disable-usage-stats", f"--temp-dir={short}"],
        capture_output=True, text=True, timeout=120, env=env,
    )  # fmt: skip
    assert head.returncode == 0, head.stderr[-2000:]
    try:
        argv = [sys.executable, "-m", "shipgym.cli", "bench", "observers", "--seeds", "2",
                "--observers", "kbf", "dkf", "--no-progress"]  # fmt: skip

        def table(extra: list[str], **env_extra: str) -> list[str]:
            out = subprocess.run([*argv, *extra], capture_output=True, text=True, timeout=300,
                                 env={**env, **env_extra})  # fmt: skip
            assert out.returncode == 0, out.stderr[-2000:]
            return [ln for ln in out.stdout.splitlines() if ln.startswith("|")]

        address = f"127.0.0.1:{port}"
        pool = table([])
        assert pool
        assert table(["--executor", "ray"], RAY_ADDRESS=address) == pool
        assert table(["--executor", "ray", "--ray-address", address]) == pool
    finally:
        subprocess.run([exe, "stop", "--force"], capture_output=True, timeout=120, env=env)
        shutil.rmtree(short, ignore_errors=True)
