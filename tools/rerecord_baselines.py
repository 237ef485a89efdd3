"""Re-record the shipped RL baselines' reproduction fingerprints after a change that moves
trajectories (a new float order in a run-time law): for each shipped policy
(``shipgym/assets/models/*.zip``) with a ``reproduce`` record, run its documented training
command to the recorded checkpoint and write the checkpoint's fingerprints into the zip's
``shipgym.json``: ``policy_sha256`` (``policy_fingerprint``: the policy weights) and
``model_sha256`` (``model_fingerprint``: the weights and the observation-normalisation
statistics, what decides the actions). The policies themselves are not retrained or replaced
(so after a change of the floats a record's ``shipped_reproduces``, the claim that the command
gives the shipped file itself, is dropped: retrain the file to regain it); check them with
``make test-slow`` (``tests/test_rl_bench.py``: their acceptance on the current env;
``tests/test_baseline_reproduction.py``: the new fingerprints, bit for bit).

Usage: ``make rerecord`` or ``.venv/bin/python tools/rerecord_baselines.py [--add-cpu]
[FILE.zip ...]`` (one file after the other; on the 2-core development machine 50-150 s for each
PPO baseline and 9.5 min for the SAC one).

A fingerprint holds on one CPU model and instruction set (``cpu_identity``). After a change of
the floats every fingerprint is stale, and a re-record keeps this CPU's alone. ``--add-cpu``
is for unchanged floats: it adds or completes this CPU's fingerprints and keeps the other
CPUs'; where this CPU already has a policy fingerprint the re-run must give it again (else the
floats did change: the tool stops and says so). It is also how a record written before the
model fingerprint gains it (``model_sha256``) on a CPU it holds.
"""

from __future__ import annotations

import dataclasses
import sys
import tempfile
import time
import zipfile
from pathlib import Path
from typing import Any

import shipgym.controllers.learned as learned
from shipgym.controllers.learned import (
    FINGERPRINT_KEYS,
    METADATA_NAME,
    cpu_identity,
    model_fingerprint,
    policy_fingerprint,
    read_metadata,
    recorded_fingerprints,
)
from shipgym.rl.train import reproduction_run


def _record(rep: dict[str, Any], prints: dict[str, dict[str, str]], **keep: Any) -> dict[str, Any]:
    """A ``reproduce`` record from ``prints`` (CPU -> fingerprints): the CPU it names stays
    first if it is still there, the others go to ``other_cpus`` (omitted when none)."""
    first = rep["cpu"] if rep["cpu"] in prints else next(iter(prints))
    out = {k: v for k, v in rep.items() if k not in (*FINGERPRINT_KEYS, "other_cpus", "cpu")}
    out.update(keep)
    out.update({"cpu": first, **prints[first]})
    others = {cpu: p for cpu, p in prints.items() if cpu != first}
    if others:
        out["other_cpus"] = others
    return out


def rerecord(path: Path, physics: str, add_cpu: bool = False) -> str | None:
    """Re-run ``path``'s documented command to its checkpoint and record this CPU's
    fingerprints; returns a line saying what changed, or None without a ``reproduce`` record.

    Without ``add_cpu`` the floats have changed: this CPU's fingerprints replace the record's
    (the other CPUs' are dropped, ``physics`` is written). With ``add_cpu`` they have not: this
    CPU's fingerprints are added or completed beside the others.

    Raises:
        ValueError: ``add_cpu`` and the re-run's policy fingerprint differs from the one
            recorded for this CPU (the floats changed: re-record without ``--add-cpu``).
    """
    meta = read_metadata(path)
    rep = meta.extra.get("reproduce")
    if not rep:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        ckpt = reproduction_run(path, tmp)
        new = {"policy_sha256": policy_fingerprint(ckpt), "model_sha256": model_fingerprint(ckpt)}
    cpu = cpu_identity()
    prints = recorded_fingerprints(rep)
    had = prints.get(cpu, {})
    if add_cpu:
        if had and had["policy_sha256"] != new["policy_sha256"]:
            raise ValueError(
                f"{path.name}: on {cpu!r} the re-run gives policy fingerprint "
                f"{new['policy_sha256'][:12]}, the record {had['policy_sha256'][:12]}: the floats "
                "changed since it was recorded; re-record without --add-cpu"
            )
        rep = _record(rep, {**prints, cpu: new})
    else:  # this CPU's fingerprints alone (a change of the floats makes the others stale),
        # and the shipped file no longer comes from the command: shipped_reproduces goes
        rep = {k: v for k, v in rep.items() if k != "shipped_reproduces"}
        rep = _record({**rep, "cpu": cpu}, {cpu: new}, physics=physics)
    meta = dataclasses.replace(meta, extra={**meta.extra, "reproduce": rep})
    out = path.with_suffix(".tmp")
    with zipfile.ZipFile(path) as zin, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            data = meta.to_json().encode() if info.filename == METADATA_NAME else zin.read(info)
            zout.writestr(info, data)
    out.replace(path)
    return ", ".join(
        f"{k} {had.get(k, '')[:12] or '(none)'} -> {new[k][:12]}" for k in FINGERPRINT_KEYS
    )


def main(argv: list[str]) -> None:
    physics = "shipgym.sim.step (one compiled physics); one compiled form per run-time law"
    add_cpu = "--add-cpu" in argv
    files = [a for a in argv if a != "--add-cpu"]
    known = [b.file for b in learned.BASELINE_MODELS]
    unknown = [f for f in files if f not in known]
    if unknown:
        raise SystemExit(f"not a shipped baseline: {', '.join(unknown)}; choose from {known}")
    for b in learned.BASELINE_MODELS:
        path = learned.models_dir() / b.file
        if not path.is_file() or (files and b.file not in files):
            continue
        t0 = time.time()
        got = rerecord(path, physics, add_cpu)
        if got is not None:
            print(f"{b.file} on {cpu_identity()}: {got} ({time.time() - t0:.0f} s)", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
