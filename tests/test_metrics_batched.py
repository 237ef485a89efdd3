"""BatchedManoeuvreMetrics: env i of a batch is ManoeuvreMetrics fed env i's rows alone, and a
plain-Python accumulation of Tomera (2014) eqs. 54-57 written here, float for float."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shipgym.metrics import (
    SEED_WEIGHTS,
    BatchedManoeuvreMetrics,
    ManoeuvreMetrics,
    command_chatter,
)

DEG = 180.0 / math.pi


class Reference:
    """The statistics of one run, accumulated by hand from the formulas of the docstrings:
    samples at the first call at or after ``k * period`` (tolerance ``1e-6 * period``);
    ``x_E = (1/n) sum |x_d - x|`` (eq. 54), ``y_E`` likewise (eq. 55),
    ``psi_E = (1/n) sum |wrap(psi_d - psi)|`` in degrees (eq. 56, wrap to (-pi, pi]),
    ``J_c = l1 x_E + l2 y_E + l3 psi_E`` (eq. 57); thrust mean |F| and sum |F_k - F_{k-1}|;
    saturation: fraction of the steps with the flag, time with the previous step's flag held;
    legs: a new index completes the current leg at ``t``."""

    def __init__(self, period=1.0, weights=SEED_WEIGHTS, na=3, nc=3, control_period=None):
        self.period, self.w, self.na, self.nc = period, weights, na, nc
        self.control_period = control_period
        self.tol = 1e-6 * period
        self.next_k = None
        self.t_last = None
        self.truth = [0.0, 0.0, 0.0, 0]
        self.meas = [0.0, 0.0, 0.0, 0]
        self.legs = {}
        self.leg = None
        self.leg_start = None
        self.leg_times, self.leg_done = [], []
        self.steps = 0
        self.f_sum, self.f_tv, self.f_prev, self.n_f = [0.0] * na, [0.0] * na, None, 0
        self.s_count, self.s_time, self.s_prev, self.n_s = [0] * na, [0.0] * na, None, 0
        self.cmds, self.t_cmds = [], []

    @staticmethod
    def add(acc, a, d):
        acc[0] += abs(d[0] - a[0])
        acc[1] += abs(d[1] - a[1])
        e = d[2] - a[2]
        acc[2] += abs(math.pi - (math.pi - e) % (2.0 * math.pi))  # wrap to (-pi, pi]
        acc[3] += 1

    def indices(self, acc):
        n = acc[3]
        if n == 0:
            return None
        x, y, p = acc[0] / n, acc[1] / n, acc[2] / n * DEG
        return {"x_E": x, "y_E": y, "psi_E": p, "J_c": self.w[0] * x + self.w[1] * y
                + self.w[2] * p}  # fmt: skip

    def complete_leg(self, t, next_leg=None):
        if self.leg_start is not None:
            self.leg_times.append(t - self.leg_start)
            self.leg_done.append(t)
        self.leg = next_leg
        self.leg_start = None if next_leg is None else t

    def record(self, t, a, d, m=None, f=None, s=None, leg=None, c=None):
        dt = 0.0 if self.t_last is None else t - self.t_last
        if self.next_k is None:
            self.next_k = max(0, math.ceil((t - self.tol) / self.period))
        self.t_last = t
        self.steps += 1
        if leg is not None:
            if self.leg is None:
                self.leg, self.leg_start = leg, t
            elif leg != self.leg:
                self.complete_leg(t, leg)
        if f is not None:
            for j in range(self.na):
                self.f_sum[j] += abs(f[j])
                if self.f_prev is not None:
                    self.f_tv[j] += abs(f[j] - self.f_prev[j])
            self.f_prev = list(f)
            self.n_f += 1
        if s is not None:
            for j in range(self.na):
                if s[j]:
                    self.s_count[j] += 1
                if self.s_prev is not None and self.s_prev[j]:
                    self.s_time[j] += dt
            self.s_prev = [bool(x) for x in s]
            self.n_s += 1
        if c is not None:
            self.cmds.append(list(c))
            self.t_cmds.append(t)
        sampled = t >= self.next_k * self.period - self.tol
        if sampled:
            self.add(self.truth, a, d)
            if m is not None:
                self.add(self.meas, m, d)
            if self.leg is not None:
                self.add(self.legs.setdefault(self.leg, [0.0, 0.0, 0.0, 0]), a, d)
            self.next_k = math.floor((t + self.tol) / self.period) + 1
        return sampled

    def summary(self):
        nan = float("nan")
        na = self.na
        k = len(self.cmds)
        dt = self.control_period
        if dt is None:
            ts = self.t_cmds
            dt = (ts[-1] - ts[0]) / (k - 1) if k > 1 and ts[-1] > ts[0] else 1.0
        chatter = command_chatter(np.array(self.cmds, float).reshape(k, self.nc), dt)
        return {
            **(self.indices(self.truth) or dict.fromkeys(("x_E", "y_E", "psi_E", "J_c"), nan)),
            "measured": self.indices(self.meas),
            "n_samples": self.truth[3],
            "n_measured_samples": self.meas[3],
            "n_steps": self.steps,
            "thrust_mean_abs": [x / self.n_f for x in self.f_sum] if self.n_f else [nan] * na,
            "thrust_total_variation": list(self.f_tv) if self.n_f else [nan] * na,
            "saturated_fraction": [c / self.n_s for c in self.s_count] if self.n_s else [nan] * na,
            "saturated_time": list(self.s_time),
            "legs_completed": len(self.leg_times),
            "leg_times": list(self.leg_times),
            "leg_completion_times": list(self.leg_done),
            "per_leg": {
                leg: {**self.indices(acc), "n_samples": acc[3]}
                for leg, acc in sorted(self.legs.items())
                if acc[3]
            },
            **chatter,
        }


def same(a, b, where="summary"):
    """``a == b`` with NaN equal to NaN, and the same types (floats, ints, lists, dicts)."""
    assert type(a) is type(b), f"{where}: {type(a).__name__} != {type(b).__name__}"
    if isinstance(a, dict):
        assert list(a) == list(b), f"{where}: keys {list(a)} != {list(b)}"
        for k in a:
            same(a[k], b[k], f"{where}[{k!r}]")
    elif isinstance(a, list):
        assert len(a) == len(b), f"{where}: {a} != {b}"
        for k, (x, y) in enumerate(zip(a, b, strict=True)):
            same(x, y, f"{where}[{k}]")
    elif isinstance(a, float):
        assert a == b or (math.isnan(a) and math.isnan(b)), f"{where}: {a!r} != {b!r}"
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


def _random_run(seed, n=7, steps=320, na=3, nc=3, period=1.0, control_period=None):
    """Random rows for ``n`` envs (own time steps, masks, resets by mask, legs changing at
    different times and revisited, missing measurements, saturation, headings across pi),
    fed to the batch, to one ManoeuvreMetrics per env and to one Reference per env."""
    rng = np.random.default_rng(seed)
    kw = dict(n_channels=nc, control_period=control_period)
    batch = BatchedManoeuvreMetrics(n, period, SEED_WEIGHTS, na, **kw)
    singles = [ManoeuvreMetrics(period, SEED_WEIGHTS, na, **kw) for _ in range(n)]
    refs = [Reference(period, SEED_WEIGHTS, na, nc, control_period) for _ in range(n)]
    dts = rng.choice([0.1, 0.25, 0.3, 0.5, 0.7, 1.0, 1.5], n)
    t = rng.uniform(0.0, 3.0, n) * rng.integers(0, 2, n)
    legs = np.zeros(n, np.int64)
    f_prev = rng.normal(0.0, 100.0, (n, na))
    for k in range(steps):
        if k and k % 97 == 0:  # some envs start a new run
            reset = rng.random(n) < 0.4
            batch.reset(reset)
            for i in np.flatnonzero(reset):
                singles[i].reset()
                refs[i] = Reference(period, SEED_WEIGHTS, na, nc, control_period)
                t[i] = rng.uniform(0.0, 2.0)
        mask = rng.random(n) < 0.85
        t = t + np.where(mask, dts, 0.0)  # accumulated float time, as an env's clock
        eta = rng.normal(0.0, 5.0, (n, 3))
        eta_d = eta + rng.normal(0.0, 1.0, (n, 3))
        eta[:, 2] = rng.uniform(-4.0, 4.0, n)
        eta_d[:, 2] = np.where(rng.random(n) < 0.3, eta[:, 2] + rng.choice([-1, 1], n) * (
            2 * math.pi - rng.uniform(0.0, 0.1, n)), rng.uniform(-7.0, 7.0, n))  # fmt: skip
        measured = rng.random(n) < 0.7
        meas = np.where(measured[:, None], eta + rng.normal(0.0, 0.3, (n, 3)), np.nan)
        thrust = np.where(rng.random((n, na)) < 0.2, f_prev, rng.normal(0.0, 100.0, (n, na)))
        f_prev = thrust
        sat = rng.random((n, na)) < 0.15
        change = rng.random(n) < 0.04
        legs = np.where(change, rng.integers(0, 9, n), legs)  # revisits some legs
        cmd = np.clip(rng.normal(0.0, 0.6, (n, nc)), -1.0, 1.0)
        give = {  # each optional input absent in some calls
            "eta_meas_r": k % 11 != 3,
            "thrust": k % 13 != 5,
            "saturated": k % 7 != 2,
            "leg": k % 17 != 4,
            "command": k % 19 != 6,
        }
        rows = {"eta_meas_r": meas, "thrust": thrust, "saturated": sat, "leg": legs,
                "command": cmd}  # fmt: skip
        args = {key: rows[key] if give[key] else None for key in rows}
        got = batch.record(t, eta, eta_d, **args, mask=mask,
                           measured=measured if give["eta_meas_r"] else None)  # fmt: skip
        for i in np.flatnonzero(mask):
            ti = float(t[i])
            row = {key: None if v is None else v[i] for key, v in args.items()}
            if row["eta_meas_r"] is not None and not measured[i]:
                row["eta_meas_r"] = None
            if row["leg"] is not None:
                row["leg"] = int(row["leg"])
            s1 = singles[i].record(ti, eta[i], eta_d[i], **row)
            plain = {key: v.tolist() if isinstance(v, np.ndarray) else v for key, v in row.items()}
            m, f, s, c = (plain[key] for key in ("eta_meas_r", "thrust", "saturated", "command"))
            s2 = refs[i].record(ti, eta[i].tolist(), eta_d[i].tolist(), m, f, s, row["leg"], c)
            assert got[i] == s1 == s2
        assert not got[~mask].any()
        if k % 53 == 40:  # a leg completed by hand in some envs
            done = rng.random(n) < 0.5
            nxt = rng.integers(0, 9, n) if k % 2 else None
            tc = t + 0.01
            batch.complete_leg(tc, nxt, mask=done)
            for i in np.flatnonzero(done):
                n_i = None if nxt is None else int(nxt[i])
                singles[i].complete_leg(float(tc[i]), n_i)
                refs[i].complete_leg(float(tc[i]), n_i)
    return batch, singles, refs


@pytest.mark.parametrize(
    "seed, na, nc, period, control_period",
    [(0, 3, 3, 1.0, None), (1, 4, 6, 1.0, 0.5), (2, 1, 2, 0.5, None), (3, 3, 3, 2.0, 1.0)],
)
def test_env_i_of_a_batch_is_the_single_and_the_hand_accumulation(
    seed, na, nc, period, control_period
):
    batch, singles, refs = _random_run(seed, na=na, nc=nc, period=period,
                                       control_period=control_period)  # fmt: skip
    for i, (single, ref) in enumerate(zip(singles, refs, strict=True)):
        want = ref.summary()
        same(batch.summary(i), want, f"batch env {i}")
        same(single.summary(), want, f"single env {i}")
        assert batch.n_samples[i] == single.n_samples == want["n_samples"]
        same(batch.chatter(i), single.chatter())
    # the run exercised what it is meant to
    s = [ref.summary() for ref in refs]
    assert max(x["legs_completed"] for x in s) >= 5 and max(len(x["per_leg"]) for x in s) >= 4
    assert any(x["n_measured_samples"] < x["n_samples"] for x in s)
    assert any(x["saturated_time"][0] > 0 for x in s)


def test_headings_wrap_like_wrap_angle_at_the_branch_cut():
    """psi_d - psi at and around +-pi, 2 pi multiples and -0.0: the same floats as the hand
    accumulation (Python's floor modulo)."""
    d = [math.pi, -math.pi, 3 * math.pi, -3 * math.pi, 2 * math.pi, -0.0, 0.0, 1e-300,
         math.nextafter(math.pi, 4.0), math.nextafter(-math.pi, -4.0), 7.5, -7.5, 1e6]  # fmt: skip
    n = len(d)
    batch = BatchedManoeuvreMetrics(n)
    refs = [Reference() for _ in range(n)]
    for k in range(3):
        psi_d = np.array(d) * (k + 1)
        eta = np.zeros((n, 3))
        eta_d = np.zeros((n, 3))
        eta_d[:, 2] = psi_d
        batch.record(float(k), eta, eta_d)
        for i in range(n):
            refs[i].record(float(k), [0.0, 0.0, 0.0], eta_d[i].tolist())
    for i in range(n):
        same(batch.summary(i), refs[i].summary(), f"env {i}")


def test_a_masked_env_is_untouched_and_errors_change_nothing():
    batch = BatchedManoeuvreMetrics(3)
    z = np.zeros((3, 3))
    batch.record([0.0, 0.0, 0.0], z, z + 1.0, thrust=np.ones((3, 3)), leg=[0, 0, 0])
    before = [batch.summary(i) for i in range(3)]
    with pytest.raises(ValueError, match=r"env 1: time went backwards"):
        batch.record([1.0, -1.0, 1.0], z, z)
    bad = z.copy()
    bad[2, 0] = np.nan
    with pytest.raises(ValueError, match=r"env 2: eta_r must be finite"):
        batch.record(1.0, bad, z)
    with pytest.raises(ValueError, match=r"env 0: thrust must be finite"):
        batch.record(1.0, z, z, thrust=np.full((3, 3), np.inf))
    with pytest.raises(ValueError, match=r"eta_d_r must have shape \(3, 3\)"):
        batch.record(1.0, z, np.zeros(3))
    with pytest.raises(ValueError, match=r"mask must be \(3,\) booleans"):
        batch.reset([True])
    for i in range(3):
        same(batch.summary(i), before[i])
    # NaN rows of envs outside the mask, or not measured, are ignored
    nan = np.full((3, 3), np.nan)
    got = batch.record([1.0, np.nan, 1.0], np.where([[1], [0], [1]], z, nan), z, eta_meas_r=nan,
                       mask=[True, False, True], measured=[False, False, False])  # fmt: skip
    assert got.tolist() == [True, False, True]
    same(batch.summary(1), before[1])
    assert batch.summary(0)["n_samples"] == 2 and batch.summary(0)["measured"] is None
    with pytest.raises(ValueError, match="n must be a number of envs"):
        BatchedManoeuvreMetrics(0)


def test_single_errors_leave_the_run_as_it_was():
    m = ManoeuvreMetrics()
    m.record(0.0, [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], thrust=[1.0, 2.0, 3.0], leg=0)
    before = m.summary()
    with pytest.raises(ValueError, match="eta_meas_r must be finite"):
        m.record(1.0, np.zeros(3), np.zeros(3), eta_meas_r=[0.0, np.nan, 0.0])
    with pytest.raises(ValueError, match="saturated must have 3 flags, got 2"):
        m.record(1.0, np.zeros(3), np.zeros(3), saturated=[True, False])
    with pytest.raises(ValueError, match="t must be finite"):
        m.record(float("inf"), np.zeros(3), np.zeros(3))
    same(m.summary(), before)


# ---- the vector env's episode metrics: the single env's episode_metrics() of env i --------------
def _env_row(metrics, i):
    """Env ``i``'s dict of the vector env's ``info["episode_metrics"]``."""
    return {k: v[i].item() if v.dtype != object else v[i] for k, v in metrics.items()
            if not k.startswith("_")}  # fmt: skip


@pytest.mark.parametrize(
    ("env_id", "kw", "steps", "total"),
    [
        ("shipgym/BlueLadyTracking-v0", {"max_legs": 2}, 320, 660),
        ("shipgym/BlueLadyHarbour-v0", {}, 90, 200),
        ("shipgym/DPStationKeeping-v0", {"vessel": "star-hercules", "episode_duration": 8.0},
         None, 100),
    ],
)  # fmt: skip
def test_vector_env_episode_metrics_are_the_single_envs(env_id, kw, steps, total):
    """Env i of ``ShipVectorEnv`` seeded s + i reports at each episode end the single env's
    ``episode_metrics()`` (same keys, types and floats): legs completed (Tracking), sensor
    dropouts (a stale fix measured), saturated and clipped actions, autoresets."""
    import gymnasium as gym

    import shipgym

    n = 3
    if "vessel" not in kw:  # (the DP tasks' sensors come with their timing)
        kw = {**kw, "sensors": {"dropout_probability": 0.3}}
    if steps is not None:
        kw["max_episode_steps"] = steps
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kw)
    # the single envs under the PID controller (legs complete), plus a random residual that
    # saturates and clips; the vector env gets the actions they applied
    singles = [shipgym.make(env_id, controller="pid", residual_scale=1.5, **kw) for _ in range(n)]
    venv.reset(seed=11)
    for i, s in enumerate(singles):
        s.reset(seed=11 + i)
    rng = np.random.default_rng(3)
    pending = np.zeros(n, bool)
    ends = legs = saturated = 0
    for _ in range(total):
        actions = np.zeros((n, venv.single_action_space.shape[0]), np.float32)
        mine = []
        for i, s in enumerate(singles):
            if pending[i]:
                s.reset()
                mine.append(None)
            else:
                res = rng.normal(0.0, 0.5, s.action_space.shape).astype(np.float32)
                _, _, te, tr, _ = s.step(res)
                actions[i] = s.unwrapped.prev_action
                mine.append(s.unwrapped.episode_metrics() if te or tr else None)
        _, _, term, trunc, info = venv.step(actions)
        done = term | trunc
        for i, want in enumerate(mine):
            assert (want is not None) == bool(done[i])
            if want is not None:
                assert info["_episode_metrics"][i]
                same(_env_row(info["episode_metrics"], i), want, f"env {i}")
                ends += 1
                legs += want["legs_completed"]
                saturated += sum(want["saturated_time"]) > 0
                assert want["n_measured_samples"] > 0
        pending = done
    assert ends >= n
    if env_id == "shipgym/BlueLadyTracking-v0":
        assert legs > 0


def test_vector_env_episode_metrics_in_same_step_mode_and_types():
    """Same-step autoreset: the ended episode's metrics in ``final_info`` too; numbers are
    numeric arrays (NaN / 0 / False for the envs that did not end), the rest object arrays."""
    import gymnasium as gym

    kw = {"max_episode_steps": 5, "autoreset_mode": "same-step"}
    venv = gym.make_vec("shipgym/BlueLadyStationKeeping-v0", num_envs=2,
                        vectorization_mode="vector_entry_point", **kw)  # fmt: skip
    venv.reset(seed=0)
    for _ in range(5):
        _, _, term, trunc, info = venv.step(np.full((2, 3), 0.5, np.float32))
    assert (term | trunc).all()
    m = info["episode_metrics"]
    assert info["final_info"]["episode_metrics"] is m
    assert m["J_c"].dtype == np.float64 and m["n_steps"].dtype == np.int64
    assert m["completed"].dtype == bool and m["thrust_mean_abs"].dtype == object
    assert m["n_steps"].tolist() == [6, 6]  # the reset and 5 control steps, as the single env


def test_metrics_pickle_and_copy():
    import copy
    import pickle

    m = ManoeuvreMetrics()
    m.record(0.0, np.zeros(3), np.ones(3), leg=0)
    for other in (copy.deepcopy(m), pickle.loads(pickle.dumps(m))):
        other.record(1.0, np.zeros(3), np.ones(3), leg=1)
        assert other.n_samples == 2 and other.summary()["legs_completed"] == 1
    assert m.n_samples == 1 and m.summary()["legs_completed"] == 0


def test_record_rows_is_record_without_its_checks():
    """An env's path (``record_rows``: its own rows, no checks or conversions) accumulates
    what ``record`` does, bit for bit, with and without saturation, commands and
    measurements, over masks, resets and leg changes."""
    rng = np.random.default_rng(4)
    n, na, nc = 5, 3, 4
    a = BatchedManoeuvreMetrics(n, 1.0, SEED_WEIGHTS, na, n_channels=nc, control_period=0.5)
    b = BatchedManoeuvreMetrics(n, 1.0, SEED_WEIGHTS, na, n_channels=nc, control_period=0.5)
    t = np.zeros(n)
    legs = np.zeros(n, np.int64)
    for k in range(300):
        if k % 71 == 70:
            reset = rng.random(n) < 0.5
            a.reset(reset)
            b.reset(reset)
        mask = rng.random(n) < 0.9
        t = t + np.where(mask, 0.5, 0.0)
        eta = rng.normal(0.0, 5.0, (n, 3))
        eta_d = eta + rng.normal(0.0, 1.0, (n, 3))
        measured = rng.random(n) < 0.7
        meas = None if k % 9 == 1 else np.where(measured[:, None], eta + 0.1, np.nan)
        thrust = rng.normal(0.0, 100.0, (n, na))
        sat = None if k % 7 == 2 else rng.random((n, na)) < 0.2
        legs = np.where(rng.random(n) < 0.05, legs + 1, legs)
        cmd = None if k % 5 == 3 else np.clip(rng.normal(0.0, 0.6, (n, nc)), -1.0, 1.0)
        a.record(t, eta, eta_d, meas, thrust, sat, legs, cmd, mask=mask,
                 measured=None if meas is None else measured)  # fmt: skip
        b.record_rows(t, mask, eta, eta_d, meas, measured, thrust, sat, legs, cmd)
    for x, y in ((a._F, b._F), (a._I, b._I), (a._L, b._L), (a._CH, b._CH)):
        np.testing.assert_array_equal(x, y)
    for i in range(n):
        same(b.summary(i), a.summary(i), f"env {i}")
    assert a.summary(0)["legs_completed"] >= 1 and a.n_samples.min() >= 5
