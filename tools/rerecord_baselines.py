"""Re-record the shipped RL baselines' reproduction fingerprints after a change that moves
trajectories (a new float order in a run-time law): for each shipped policy
(``shipgym/assets/models/*.zip``) with a ``reproduce`` record, run its documented training
command to the recorded checkpoint and write the new policy fingerprint into the zip's
``shipgym.json``. The policies themselves are not retrained or replaced; check them with
``make test-slow`` (``tests/test_rl_bench.py``: their acceptance on the current env;
``tests/test_baseline_reproduction.py``: the new fingerprints, bit for bit).

Usage: ``make rerecord`` or ``.venv/bin/python tools/rerecord_baselines.py [--add-cpu]
[FILE.zip ...]`` (about 10 minutes for the four on a 2-core machine, most of it the SAC
baseline).

A fingerprint holds on one CPU model and instruction set (``cpu_identity``). After a change of
the floats every fingerprint is stale, and a re-record keeps this CPU's alone. ``--add-cpu``
is for a new CPU on unchanged floats: it adds this CPU's fingerprint (``other_cpus``) and
keeps the others, so the test checks the weights on each CPU recorded.
"""

from __future__ import annotations

import dataclasses
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import shipgym.controllers.learned as learned
from shipgym.controllers.learned import (
    METADATA_NAME,
    cpu_identity,
    policy_fingerprint,
    read_metadata,
)
from shipgym.rl.train import train


def rerecord(path: Path, physics: str, add_cpu: bool = False) -> tuple[str, str] | None:
    """Re-run ``path``'s documented command to its checkpoint; returns (old, new) or None
    (``add_cpu``: this CPU's fingerprint beside the others, the floats unchanged)."""
    meta = read_metadata(path)
    rep = meta.extra.get("reproduce")
    if not rep:
        return None
    steps = int(rep["checkpoint_steps"])
    with tempfile.TemporaryDirectory() as tmp:
        train(meta.algorithm, env_id=meta.env_id, seed=int(meta.seed), timesteps=steps,
              residual=meta.residual, out=Path(tmp), eval_freq=0, checkpoint_freq=steps,
              progress=False)  # fmt: skip
        new = policy_fingerprint(Path(tmp) / "checkpoints" / f"{meta.algorithm}_{steps}_steps.zip")
    cpu = cpu_identity()
    if add_cpu and cpu != rep["cpu"]:
        others = dict(rep.get("other_cpus", {}))
        old = others.get(cpu, "")
        rep = {**rep, "other_cpus": {**others, cpu: new}}
    else:  # this CPU's fingerprint alone (a change of the floats makes the others stale)
        old = rep["policy_sha256"]
        rep = {k: v for k, v in rep.items() if k != "other_cpus"}
        rep = {**rep, "policy_sha256": new, "physics": physics, "cpu": cpu}
    meta = dataclasses.replace(meta, extra={**meta.extra, "reproduce": rep})
    out = path.with_suffix(".tmp")
    with zipfile.ZipFile(path) as zin, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            data = meta.to_json().encode() if info.filename == METADATA_NAME else zin.read(info)
            zout.writestr(info, data)
    out.replace(path)
    return old, new


def main(argv: list[str]) -> None:
    physics = "shipgym.sim.step (one compiled physics); one compiled form per run-time law"
    add_cpu = "--add-cpu" in argv
    files = [a for a in argv if a != "--add-cpu"]
    for b in learned.BASELINE_MODELS:
        path = learned.models_dir() / b.file
        if not path.is_file() or (files and b.file not in files):
            continue
        t0 = time.time()
        got = rerecord(path, physics, add_cpu)
        if got is not None:
            took = time.time() - t0
            print(
                f"{b.file}: {got[0][:12] or '(none)'} -> {got[1][:12]} ({took:.0f} s)", flush=True
            )


if __name__ == "__main__":
    main(sys.argv[1:])
