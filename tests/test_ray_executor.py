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
