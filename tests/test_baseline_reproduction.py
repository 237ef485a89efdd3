"""The shipped learned baselines are reproducible: re-running each one's documented training
command (the shipped hyperparameter file, its seed) up to the checkpoint recorded in its
metadata gives bit-identical policy weights (``policy_fingerprint``), on each CPU a
fingerprint was taken on (``cpu_identity``: its model name and its widest vector instructions;
torch's and NumPy's kernels differ between them, so elsewhere the test says so and skips;
``reproduce.other_cpus`` holds the fingerprints of CPUs added on unchanged floats,
``tools/rerecord_baselines.py --add-cpu``).
Slow: each re-run trains about a million steps (a few minutes).

The shipped models were trained on the NumPy form of the batched physics, which the one
compiled physics step (:mod:`shipgym.sim.step`) replaced; it agrees with that form to round-off,
not bit for bit, and training turns the last bits into other weights: the fingerprints were
re-recorded on the one physics (``reproduce.physics`` in each file's metadata). The shipped
weights themselves are those trained then; their acceptance figures hold on the one physics
(``tests/test_rl_bench.py``, slow)."""

from __future__ import annotations

import pytest

pytest.importorskip("stable_baselines3")
pytest.importorskip("torch")

import shipgym.controllers.learned as learned  # noqa: E402
from shipgym.controllers.learned import (  # noqa: E402
    cpu_identity,
    policy_fingerprint,
    read_metadata,
)


def _reproducible() -> list[str]:
    out = []
    for b in learned.BASELINE_MODELS:
        p = learned.models_dir() / b.file
        if p.is_file() and "reproduce" in read_metadata(p).extra and b.file not in out:
            out.append(b.file)
    return out


def test_every_pure_baseline_records_how_to_reproduce_it():
    """Not vacuous: the pure baselines that are shipped carry a fingerprint."""
    shipped = [b.file for b in learned.BASELINE_MODELS
               if not b.residual and (learned.models_dir() / b.file).is_file()]  # fmt: skip
    assert shipped and set(shipped) <= set(_reproducible())


def test_each_fingerprint_names_the_cpu_and_its_vector_instructions():
    """A fingerprint holds on one CPU model and instruction set (``cpu_identity``); a record
    with the model name alone would let the slow test run, and fail, on another generation
    of the same name."""
    import re

    form = re.compile(r".+ \((avx512|avx2|baseline)\)$")
    assert form.match(cpu_identity())
    for file in _reproducible():
        rep = read_metadata(learned.models_dir() / file).extra["reproduce"]
        for cpu, sha in _fingerprints(rep).items():
            assert form.match(cpu) and re.fullmatch("[0-9a-f]{64}", sha), (file, cpu)


def _fingerprints(rep: dict) -> dict[str, str]:
    """CPU -> policy fingerprint of a ``reproduce`` record."""
    return {rep["cpu"]: rep["policy_sha256"], **rep.get("other_cpus", {})}


@pytest.mark.slow
@pytest.mark.parametrize("file", _reproducible())
def test_documented_command_gives_the_same_weights(file, tmp_path):
    from shipgym.rl.train import train

    meta = read_metadata(learned.models_dir() / file)
    rep = meta.extra["reproduce"]
    prints = _fingerprints(rep)
    if cpu_identity() not in prints:
        pytest.skip(
            f"the fingerprints of {file} were taken on {sorted(prints)}, this is "
            f"{cpu_identity()!r}: bit-identical weights hold on the same CPU model and "
            "instructions only"
        )
    steps = int(rep["checkpoint_steps"])
    assert f"--seed {meta.seed}" in meta.command and meta.command.startswith(
        f"shipgym train {meta.algorithm}"
    )
    train(meta.algorithm, env_id=meta.env_id, seed=int(meta.seed), timesteps=steps,
          residual=meta.residual, out=tmp_path, eval_freq=0, checkpoint_freq=steps,
          progress=False)  # fmt: skip
    ckpt = tmp_path / "checkpoints" / f"{meta.algorithm}_{steps}_steps.zip"
    assert policy_fingerprint(ckpt) == prints[cpu_identity()]
