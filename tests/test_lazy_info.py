"""The single env's ``info`` is a :class:`~shipgym.records.LazyInfo`: made on its first read,
with the values of the step that returned it whenever it is read, and the dict it would be."""

from __future__ import annotations

import copy
import json
import math
import pickle

import gymnasium as gym
import numpy as np
import pytest

import shipgym
from shipgym.dynamics.vessel import load_vessel, vessel_names
from shipgym.envs.base import ShipEnv
from shipgym.envs.registration import ALIASES, PLAN_IDS, task_fits_vessel
from shipgym.envs.scene import fits
from shipgym.records import LazyInfo, StepRecord

CASES = [
    (task, vessel, {})
    for task in sorted(PLAN_IDS - set(ALIASES))
    for vessel in vessel_names()
    if task_fits_vessel(task, load_vessel(vessel))
    and (task != "shipgym/Harbour-v0" or fits(load_vessel(vessel), "harbour"))
] + [
    ("shipgym/Tracking-v0", "blue-lady", {"observer": "kbf", "controller": "pid"}),
    ("shipgym/StationKeeping-v0", "star-hercules", {"observer": "kbf", "controller": "pid"}),
    ("shipgym/DPStationKeeping-v0", "wimpey-sealab", {"controller": "pid"}),
]
IDS = [f"{t.split('/')[1]}-{v}-{'-'.join(k.values()) or 'plain'}" for t, v, k in CASES]


def _same(a, b) -> bool:
    """Exact equality of info values (arrays and floats NaN-equal, records by their fields)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        x, y = np.asarray(a), np.asarray(b)
        return x.shape == y.shape and bool(np.array_equal(x, y, equal_nan=x.dtype.kind == "f"))
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_same(p, q) for p, q in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return bool(a == b)


def _make(task: str, vessel: str, kw: dict) -> gym.Env:
    steps = None if "DP" in task else 4
    extra = {"episode_duration": 3.0} if "DP" in task else {}
    return shipgym.make(task, vessel=vessel, max_episode_steps=steps, **kw, **extra)


@pytest.mark.parametrize(("task", "vessel", "kw"), CASES, ids=IDS)
def test_an_info_read_late_has_its_own_steps_values(task: str, vessel: str, kw: dict) -> None:
    """Two envs of one seed and actions: one's infos copied as they come, the other's kept
    unread over two episodes and their resets, then read: the same, key for key (in order)."""
    now, late = _make(task, vessel, kw), _make(task, vessel, kw)
    assert isinstance(now.unwrapped, ShipEnv)
    rng = np.random.default_rng(3)
    copies, kept = [], []
    for seed in (5, 6):
        for env, out in ((now, copies), (late, kept)):
            info = env.reset(seed=seed)[1]
            out.append(copy.deepcopy(info) if env is now else info)
        done = False
        while not done:
            a = rng.uniform(-1.0, 1.0, now.action_space.shape).astype(np.float32)
            for env, out in ((now, copies), (late, kept)):
                _, _, term, trunc, info = env.step(a)
                out.append(copy.deepcopy(info) if env is now else info)
            done = term or trunc
    assert all(isinstance(i, LazyInfo) for i in kept[2:])
    assert len(copies) == len(kept) > 4
    for i, (c, k) in enumerate(zip(copies, kept, strict=True)):
        assert isinstance(k["record"], StepRecord)
        assert _same(c, dict(k)), f"info {i} read late differs from its step's"


def test_a_step_makes_no_info_until_it_is_read(monkeypatch) -> None:
    """The dict and its record are made on the first read only: a loop that does not read
    ``info`` (training) makes none; reading a key makes it once."""
    env = shipgym.make("tracking", observer="kbf")
    env.reset(seed=0)
    for _ in range(2):  # (the first step's info is made at once for its keys; Gymnasium's
        env.step(env.action_space.sample())  # checker reads the first two)
    made = []
    base = env.unwrapped
    real = base._make_info
    monkeypatch.setattr(base, "_make_info", lambda *a: made.append(1) or real(*a))
    infos = [env.step(env.action_space.sample())[4] for _ in range(3)]
    assert made == []
    assert "eta" in infos[0] and "episode" not in infos[0] and infos[0].get("episode") is None
    assert len(infos[0]) == len(infos[1].keys())  # (keys() makes infos[1])
    assert made == [1]
    assert infos[0]["t"] == pytest.approx(3.0) and infos[2]["t"] == pytest.approx(5.0)
    assert made == [1, 1, 1]
    infos[0]["eta"], infos[0]["leg"]
    assert made == [1, 1, 1]


def _lazy(calls: list) -> LazyInfo:
    def make() -> dict:
        calls.append(1)
        return {"a": 1, "b": np.arange(3.0), "c": None}

    return LazyInfo(frozenset("abc"), make)


def test_lazy_info_is_the_dict_it_would_be() -> None:
    calls: list = []
    info = _lazy(calls)
    assert isinstance(info, dict)
    assert "a" in info and "z" not in info and len(info) == 3 and info.get("z", 7) == 7
    info["episode"] = {"r": 1.0}  # a wrapper's key before any read: kept, after the made ones
    info["a"] = 2  # a made key written before the first read: the written value stays
    assert len(info) == 4 and "episode" in info and calls == []
    assert list(info) == ["a", "b", "c", "episode"] and calls == [1]
    assert info["a"] == 2 and info["c"] is None and calls == [1]
    plain = {"a": 2, "b": np.arange(3.0), "c": None, "episode": {"r": 1.0}}
    assert _same(dict(info), plain) and _same({**info}, plain) and _same(info.copy(), plain)
    for other in (copy.copy(info), copy.deepcopy(info), pickle.loads(pickle.dumps(info))):
        assert type(other) is dict and _same(other, plain)
    assert json.loads(json.dumps({k: v for k, v in info.items() if k != "b"})) == {
        "a": 2, "c": None, "episode": {"r": 1.0}}  # fmt: skip
    assert "LazyInfo" not in repr(info) and repr(info).startswith("{'a': 2")


@pytest.mark.parametrize(
    "use",
    [
        lambda i: i["b"],
        lambda i: i.get("a"),
        lambda i: list(i.keys()),
        lambda i: list(i.values()),
        lambda i: list(i.items()),
        lambda i: repr(i),
        lambda i: i == {},
        lambda i: i.pop("a"),
        lambda i: i.setdefault("a", 0),
        lambda i: i.popitem(),
        lambda i: i | {"x": 1},
        lambda i: {"x": 1} | i,
        lambda i: i.__delitem__("a"),
        lambda i: list(reversed(i)),
    ],
)
def test_every_read_of_a_value_makes_the_values_once(use) -> None:
    calls: list = []
    info = _lazy(calls)
    use(info)
    assert calls == [1]
    assert info.get("b") is not None and list(info) and calls == [1]  # (made once)


def test_clear_drops_the_values_unmade_and_a_wrong_key_set_is_an_error() -> None:
    calls: list = []
    info = _lazy(calls)
    info.clear()
    assert len(info) == 0 and "a" not in info and calls == []
    bad = LazyInfo(frozenset("ab"), lambda: {"a": 1})
    with pytest.raises(RuntimeError, match="made the keys"):
        bad["a"]


def test_an_error_while_making_is_raised_at_every_read() -> None:
    def make() -> dict:
        raise ZeroDivisionError("made badly")

    info = LazyInfo(frozenset("a"), make)
    for _ in range(2):
        with pytest.raises(ZeroDivisionError):
            info["a"]
    assert "a" in info and len(info) == 1
