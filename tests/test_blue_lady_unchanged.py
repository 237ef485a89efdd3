"""The Blue Lady is unchanged by the vessel library: the harbour manoeuvre of seeds 0-9 with
``pid`` on the true state and ``kbf`` + ``pid-smooth`` gives the completion, leg times and
J_c recorded on the commit before it (564f1c2, tests/data), within 1e-6 relative, through the
Blue Lady's id and the vessel-neutral id with ``vessel="blue-lady"``. Since the command
conditioning (velocity filter, reversal hysteresis) is on in ``pid`` and ``pid-smooth``, the
record is checked against their unconditioned forms ``pid-raw`` and ``pid-smooth-raw``,
which keep the behaviour of that commit."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from shipgym.runner import run_episode

RECORD = json.loads(
    (Path(__file__).parent / "data" / "blue_lady_harbour_564f1c2.json").read_text()
)["runs"]
STACKS = [("pid", None), ("pid-smooth", "kbf")]
IDS = [("harbour", None), ("shipgym/Harbour-v0", {"vessel": "blue-lady"})]


def _check(env: str, kwargs: dict | None, controller: str, observer: str | None, seed: int):
    r = run_episode(
        env, controller=f"{controller}-raw", observer=observer, seed=seed, wind="3@300",
        env_kwargs=kwargs,
    )  # fmt: skip
    want = RECORD[f"{controller}|{observer or 'truth'}|{seed}"]
    assert r["completed"] == want["completed"]
    assert r["leg_times"] == pytest.approx(want["leg_times"], rel=1e-6)
    assert r["J_c"] == pytest.approx(want["J_c"], rel=1e-6)


@pytest.mark.parametrize(("env", "kwargs"), IDS, ids=["alias", "neutral"])
@pytest.mark.parametrize(("controller", "observer"), STACKS, ids=["pid", "kbf+pid-smooth"])
@pytest.mark.parametrize("seed", [0, 7])
def test_harbour_results_unchanged(env, kwargs, controller, observer, seed) -> None:
    _check(env, kwargs, controller, observer, seed)


@pytest.mark.slow
@pytest.mark.parametrize(("env", "kwargs"), IDS, ids=["alias", "neutral"])
@pytest.mark.parametrize(("controller", "observer"), STACKS, ids=["pid", "kbf+pid-smooth"])
@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5, 6, 8, 9])
def test_harbour_results_unchanged_all_seeds(env, kwargs, controller, observer, seed) -> None:
    _check(env, kwargs, controller, observer, seed)
