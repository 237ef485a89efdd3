"""The shipped learned baselines are reproducible: re-running each one's documented training
command (the shipped hyperparameter file, its seed) up to the checkpoint recorded in its
metadata gives bit-identical policy weights (``policy_fingerprint``) and observation-
normalisation statistics (``model_fingerprint``: the weights and the statistics, what decides
the actions; fast tests below check that it sees one ulp of either), on each CPU a
fingerprint was taken on (``cpu_identity``: its model name and its widest vector instructions;
torch's and NumPy's kernels differ between them, so elsewhere the test says so and skips;
``reproduce.other_cpus`` holds the fingerprints of CPUs added on unchanged floats,
``tools/rerecord_baselines.py --add-cpu``).
Slow: each re-run trains 250 000 to a million steps (on the 2-core development machine 50-80 s
for each PPO baseline, 9.5 min for the SAC one).

The two ``ppo`` files were trained on the one compiled physics (:mod:`shipgym.sim.step`) and
their commands give the shipped files themselves (``shipped_reproduces``, the slow test below).
``sac`` and ``ppo-residual`` were trained on the NumPy form of the batched physics it replaced
(the same to round-off, not bit for bit): their fingerprints were re-recorded on the one
physics, and their shipped weights are those trained then (pinned in ``SHIPPED``); their
acceptance figures hold on the one physics (``tests/test_rl_bench.py``, slow)."""

from __future__ import annotations

import dataclasses
import io
import re
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")
pytest.importorskip("torch")

import shipgym.controllers.learned as learned  # noqa: E402
from shipgym.controllers.learned import (  # noqa: E402
    METADATA_NAME,
    cpu_identity,
    model_fingerprint,
    policy_fingerprint,
    read_metadata,
    recorded_fingerprints,
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
    form = re.compile(r".+ \((avx512|avx2|baseline)\)$")
    assert form.match(cpu_identity())
    for file in _reproducible():
        rep = read_metadata(learned.models_dir() / file).extra["reproduce"]
        for cpu in recorded_fingerprints(rep):  # it checks each SHA-256's form
            assert form.match(cpu), (file, cpu)


def test_every_record_holds_the_model_fingerprint_on_one_cpu_at_least():
    """The weights-and-normalisation fingerprint is recorded (not the weights alone), on the
    compiled physics; a CPU recorded before it may hold the weights' alone."""
    for file in _reproducible():
        rep = read_metadata(learned.models_dir() / file).extra["reproduce"]
        assert any("model_sha256" in p for p in recorded_fingerprints(rep).values()), file
        assert rep["physics"].startswith("shipgym.sim.step"), file


def test_each_record_reruns_its_documented_command():
    """The run a record re-runs is the one its command documents: the algorithm, the seed and
    the shipped hyperparameter file it names (``--hyperparams``, ``reproduce.hyperparams``),
    and that file still resolves to the hyperparameters the model was trained with."""
    from shipgym.rl.train import packaged_hyperparams, reproduction_hyperparams

    for file in _reproducible():
        meta, path = reproduction_hyperparams(learned.models_dir() / file)
        words = meta.command.split()
        assert words[:3] == ["shipgym", "train", meta.algorithm], (file, meta.command)
        assert words[words.index("--seed") + 1] == str(meta.seed), file
        named = meta.extra["reproduce"].get("hyperparams")
        if named is None:
            assert "--hyperparams" not in words and path is None, file
        else:
            assert path == packaged_hyperparams(named), file
            assert words[words.index("--hyperparams") + 1] == f"shipgym/rl/hyperparams/{named}"
    # a file that reproduces whole is one whose shipped fingerprint is pinned (a re-record
    # after a change of the floats drops the claim: tools/rerecord_baselines.py)
    assert all(f in SHIPPED for f in _shipped_reproduces())


def test_a_record_whose_file_changed_is_refused(tiny_model, tmp_path):
    """A model whose shipped hyperparameter file resolves to other values than it was trained
    with is refused before any training, naming the keys; so is an unknown file."""
    from shipgym.rl.train import load_hyperparams, reproduction_hyperparams

    meta = read_metadata(tiny_model)
    hp = load_hyperparams("ppo", meta.env_id, residual=meta.residual)
    rep = {"checkpoint_steps": 128, "cpu": "X (avx2)", "policy_sha256": "a" * 64}
    same = dataclasses.replace(meta, seed=0, hyperparams=hp, extra={"reproduce": rep})
    ok = _rewrite(tiny_model, tmp_path / "ok.zip", METADATA_NAME, same.to_json().encode())
    assert reproduction_hyperparams(ok)[1] is None
    moved = dataclasses.replace(same, hyperparams={**hp, "gamma": 0.5, "n_timesteps": 1})
    bad = _rewrite(tiny_model, tmp_path / "bad.zip", METADATA_NAME, moved.to_json().encode())
    with pytest.raises(ValueError, match=r"ppo\.yml resolves to other .*\(gamma\)"):
        reproduction_hyperparams(bad)
    odd = dataclasses.replace(same, extra={"reproduce": {**rep, "hyperparams": "nope.yml"}})
    odd_path = _rewrite(tiny_model, tmp_path / "odd.zip", METADATA_NAME, odd.to_json().encode())
    with pytest.raises(ValueError, match="no shipped hyperparameter file 'nope.yml'"):
        reproduction_hyperparams(odd_path)


def test_old_records_stay_readable():
    """A record of before the model fingerprint (a CPU to its policy fingerprint alone) reads
    as such; a malformed one is refused with what is wrong."""
    a, b, c = "a" * 64, "b" * 64, "c" * 64
    old = {"cpu": "X (avx2)", "policy_sha256": a, "other_cpus": {"Y (avx512)": b}}
    assert recorded_fingerprints(old) == {
        "X (avx2)": {"policy_sha256": a},
        "Y (avx512)": {"policy_sha256": b},
    }
    new = {"cpu": "X (avx2)", "policy_sha256": a, "model_sha256": c,
           "other_cpus": {"Y (avx512)": {"policy_sha256": b, "model_sha256": c}}}  # fmt: skip
    assert recorded_fingerprints(new)["Y (avx512)"] == {"policy_sha256": b, "model_sha256": c}
    with pytest.raises(ValueError, match="policy_sha256"):
        recorded_fingerprints({"cpu": "X (avx2)", "model_sha256": c})
    with pytest.raises(ValueError, match="not a SHA-256"):
        recorded_fingerprints({"cpu": "X (avx2)", "policy_sha256": "abc"})
    with pytest.raises(ValueError, match="without 'cpu'"):
        recorded_fingerprints({"policy_sha256": a})


#: ``model_fingerprint`` of each shipped file itself (its policy weights and normalisation
#: statistics, on any CPU: the bytes of the file); a file retrained or replaced updates its line
#: here and in shipgym/assets/models/README.md
SHIPPED = {
    "ppo_harbour_kbf.zip": "41207cb5b25a2e002785dc12f377293ff2ef7211f8c9dc7f1b7ded45b7b3a017",
    "sac_harbour_kbf.zip": "09c00f2411297b290d6e3db7bc329a56972c6acdd297c237956a573b5c2d0ace",
    "ppo_residual_pid_kbf.zip": "e32da4d0a6b915c907048f0a1a378ba1f5bbab86b3f0a0fbece682bbbfe2aa6f",
    "ppo_station_star_hercules_kbf.zip": (
        "e8734de274700be5eb840491103deb29956a73b23e6891e2c171e1a64c902f8f"
    ),
}


def test_shipped_files_hold_the_fingerprinted_weights_and_statistics():
    """The shipped weights and normalisation statistics are those fingerprinted (a re-record
    of the ``reproduce`` records rewrites ``shipgym.json`` and must leave them alone)."""
    shipped = [b.file for b in learned.BASELINE_MODELS if (learned.models_dir() / b.file).is_file()]
    assert shipped and set(shipped) <= set(SHIPPED)
    for file in shipped:
        assert model_fingerprint(learned.models_dir() / file) == SHIPPED[file], file


# ---- the model fingerprint sees one ulp of a weight or of the normalisation (fast) ----------
@pytest.fixture(scope="module")
def tiny_model(tmp_path_factory) -> Path:
    """A shipgym checkpoint of a tiny PPO (128 steps, observation normalisation on)."""
    from shipgym.rl.train import train

    out = tmp_path_factory.mktemp("tiny")
    train("ppo", timesteps=128, seed=0, n_envs=2, out=out, observer="truth", residual=True,
          eval_freq=0, checkpoint_freq=128, progress=False,
          overrides={"n_steps": 64, "batch_size": 64, "n_epochs": 1})  # fmt: skip
    path = out / "checkpoints" / "ppo_128_steps.zip"
    assert read_metadata(path).normalization is not None
    return path


def _rewrite(src: Path, dst: Path, member: str, data: bytes) -> Path:
    """A copy of the model zip ``src`` with one member's bytes replaced."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            zout.writestr(info, data if info.filename == member else zin.read(info))
    return dst


def test_model_fingerprint_equal_for_a_byte_identical_copy(tiny_model, tmp_path):
    copy = Path(shutil.copyfile(tiny_model, tmp_path / "copy.zip"))
    assert model_fingerprint(copy) == model_fingerprint(tiny_model)
    assert policy_fingerprint(copy) == policy_fingerprint(tiny_model)
    assert re.fullmatch("[0-9a-f]{64}", model_fingerprint(tiny_model))
    assert model_fingerprint(tiny_model) != policy_fingerprint(tiny_model)


def test_model_fingerprint_sees_one_ulp_of_a_weight(tiny_model, tmp_path):
    import torch

    with zipfile.ZipFile(tiny_model) as zf:
        state = torch.load(io.BytesIO(zf.read("policy.pth")), weights_only=True)
    key = sorted(k for k in state if k.endswith("weight"))[0]
    w = state[key].clone()
    flat = w.view(-1)
    flat[0] = torch.nextafter(flat[0], torch.tensor(np.inf, dtype=w.dtype))
    assert not torch.equal(w, state[key])
    buf = io.BytesIO()
    torch.save({**state, key: w}, buf)
    moved = _rewrite(tiny_model, tmp_path / "w.zip", "policy.pth", buf.getvalue())
    assert model_fingerprint(moved) != model_fingerprint(tiny_model)
    assert policy_fingerprint(moved) != policy_fingerprint(tiny_model)


def test_model_fingerprint_sees_one_ulp_of_the_normalisation_mean(tiny_model, tmp_path):
    meta = read_metadata(tiny_model)
    norm = meta.normalization
    assert norm is not None
    mean = list(norm.mean)
    mean[3] = float(np.nextafter(mean[3], np.inf))
    moved_meta = dataclasses.replace(meta, normalization=dataclasses.replace(norm, mean=mean))
    moved = _rewrite(tiny_model, tmp_path / "m.zip", METADATA_NAME, moved_meta.to_json().encode())
    assert read_metadata(moved).normalization.mean[3] == mean[3] != norm.mean[3]  # JSON keeps it
    assert model_fingerprint(moved) != model_fingerprint(tiny_model)
    # the weights alone do not see it: what policy_fingerprint leaves out
    assert policy_fingerprint(moved) == policy_fingerprint(tiny_model)


def test_model_fingerprint_ignores_the_rest_of_the_metadata(tiny_model, tmp_path):
    """The command, versions and extras are not what decides the actions: a re-recorded
    ``reproduce`` record does not move the fingerprint it holds."""
    meta = read_metadata(tiny_model)
    other = dataclasses.replace(meta, command="other", extra={"reproduce": {"cpu": "X"}})
    moved = _rewrite(tiny_model, tmp_path / "x.zip", METADATA_NAME, other.to_json().encode())
    assert model_fingerprint(moved) == model_fingerprint(tiny_model)


@pytest.mark.slow
@pytest.mark.parametrize("file", _reproducible())
def test_documented_command_gives_the_same_weights(file, tmp_path):
    from shipgym.rl.train import reproduction_run

    meta = read_metadata(learned.models_dir() / file)
    rep = meta.extra["reproduce"]
    prints = recorded_fingerprints(rep)
    if cpu_identity() not in prints:
        pytest.skip(
            f"the fingerprints of {file} were taken on {sorted(prints)}, this is "
            f"{cpu_identity()!r}: bit-identical weights hold on the same CPU model and "
            "instructions only"
        )
    ckpt = reproduction_run(learned.models_dir() / file, tmp_path)
    want = prints[cpu_identity()]
    # the weights and the normalisation statistics (where this CPU's record has them: one
    # recorded before the model fingerprint holds the weights' alone)
    got = {"policy_sha256": policy_fingerprint(ckpt), "model_sha256": model_fingerprint(ckpt)}
    assert {k: got[k] for k in want} == want


def _shipped_reproduces() -> list[str]:
    def record(file: str) -> dict:
        return read_metadata(learned.models_dir() / file).extra["reproduce"]

    return [f for f in _reproducible() if record(f).get("shipped_reproduces")]


@pytest.mark.slow
@pytest.mark.parametrize("file", _shipped_reproduces())
def test_documented_command_gives_the_shipped_file(file, tmp_path):
    """Where the record says so (``shipped_reproduces``), the documented command run to the
    shipped model's own step (its best periodic evaluation; evaluation draws nothing from the
    training's streams) gives the shipped weights and statistics themselves, on the CPU the
    record names first (``cpu``). Slow: 3 M steps (6 min on the 2-core development machine)
    for the station-keeping policy, 14 M (15 min) for the harbour one."""
    from shipgym.rl.train import reproduction_run

    path = learned.models_dir() / file
    meta = read_metadata(path)
    cpu = meta.extra["reproduce"]["cpu"]
    if cpu_identity() != cpu:
        pytest.skip(f"{file} was reproduced whole on {cpu!r}, this is {cpu_identity()!r}")
    ckpt = reproduction_run(path, tmp_path, steps=meta.num_timesteps)
    assert model_fingerprint(ckpt) == model_fingerprint(path) == SHIPPED[file]


# ---- the re-record tool's bookkeeping (tools/rerecord_baselines.py; training stubbed) --------
def _tool():
    import importlib.util

    path = Path(__file__).resolve().parents[1] / "tools" / "rerecord_baselines.py"
    spec = importlib.util.spec_from_file_location("rerecord_baselines", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _with_record(src: Path, dst: Path, rep: dict) -> Path:
    meta = read_metadata(src)
    meta = dataclasses.replace(meta, seed=0, extra={**meta.extra, "reproduce": rep})
    return _rewrite(src, dst, METADATA_NAME, meta.to_json().encode())


def test_rerecord_keeps_or_drops_the_other_cpus(tiny_model, tmp_path, monkeypatch):
    """``--add-cpu`` (floats unchanged) completes this CPU's fingerprints beside the others and
    refuses a re-run whose weights differ from this CPU's record; without it (floats changed)
    this CPU's fingerprints alone remain, on the physics named, and the claim that the command
    gives the shipped file itself goes (the file is not retrained)."""
    tool = _tool()
    a, b, c, d = "a" * 64, "b" * 64, "c" * 64, "d" * 64
    monkeypatch.setattr(tool, "reproduction_run", lambda path, out: Path(out) / "ckpt.zip")
    monkeypatch.setattr(tool, "policy_fingerprint", lambda p: a)
    monkeypatch.setattr(tool, "model_fingerprint", lambda p: c)
    monkeypatch.setattr(tool, "cpu_identity", lambda: "HERE (avx512)")
    old = {"checkpoint_steps": 128, "physics": "P", "cpu": "FIRST (avx2)", "policy_sha256": b,
           "shipped_reproduces": True, "other_cpus": {"HERE (avx512)": a}}  # fmt: skip
    path = _with_record(tiny_model, tmp_path / "m.zip", old)
    tool.rerecord(path, "NEW", add_cpu=True)
    rep = read_metadata(path).extra["reproduce"]
    assert rep == {**old, "other_cpus": {"HERE (avx512)": {"policy_sha256": a, "model_sha256": c}}}
    assert model_fingerprint(path) == model_fingerprint(tiny_model)  # the file's weights stay
    monkeypatch.setattr(tool, "policy_fingerprint", lambda p: d)
    with pytest.raises(ValueError, match="floats"):
        tool.rerecord(path, "NEW", add_cpu=True)
    tool.rerecord(path, "NEW")
    rep = read_metadata(path).extra["reproduce"]
    assert rep == {"checkpoint_steps": 128, "physics": "NEW", "cpu": "HERE (avx512)",
                   "policy_sha256": d, "model_sha256": c}  # fmt: skip
