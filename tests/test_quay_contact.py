"""The compiled quay-contact check of the leapfrog integrator against MuJoCo's contacts: the
check itself at random poses near the quays, a batch of hulls driven into the harbour (each
stops at the step MuJoCo's integrator stops it), and the harbour env with
``integrator="leapfrog"`` against its MuJoCo default (the same episode to round-off, the same
contact step) and single against batched."""

from __future__ import annotations

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import shipgym  # noqa: F401  (registers the ids)
from shipgym.envs.batchphysics import BatchedPhysics, contact_geometry
from shipgym.sim.step import obstacles_touched

HARBOUR = "shipgym/BlueLadyHarbour-v0"


def _starts(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-5, 40, n), rng.uniform(-30, 0, n), rng.uniform(-3, 3, n)])


def test_the_footprint_and_the_quays_of_the_harbour_world():
    model = BatchedPhysics("blue-lady", 1, integrator="mujoco", world="harbour").models[0]
    fp, rects, names = contact_geometry(model)
    assert set(names) == {"quay_east", "quay_south", "quay_west", "quay_north", "pier_berth_b",
                          "pier_finger"}  # fmt: skip
    # a convex counter-clockwise polygon the size of the hull mesh (13.8 m x 2.4 m)
    e = np.roll(fp, -1, 0) - fp
    f = np.roll(e, -1, 0)
    assert (e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0] > 0).all()
    assert 13.0 < np.ptp(fp[:, 0]) < 14.5 and 2.0 < np.ptp(fp[:, 1]) < 2.8
    assert rects.shape == (6, 9) and (rects[:, 6:8] > 0).all()


def test_the_check_is_mujocos_contact_at_random_poses_near_the_quays():
    model = BatchedPhysics("blue-lady", 1, integrator="mujoco", world="harbour").models[0]
    data = mujoco.MjData(model)
    fp, rects, _ = contact_geometry(model)
    hull = model.geom("hull").id
    rng = np.random.default_rng(0)
    touching = 0
    for _ in range(2000):
        r = rects[rng.integers(len(rects))]
        x, y = r[:2] + rng.uniform(-1, 1, 2) * (r[6:8] + 8.0)
        psi = rng.uniform(-np.pi, np.pi)
        data.qpos[:3] = x, y, psi
        mujoco.mj_forward(model, data)
        want = {int(c.geom2 if c.geom1 == hull else c.geom1) for c in data.contact[: data.ncon]}
        got = obstacles_touched(x, y, psi, fp, rects, len(rects))
        assert got == len(want), (x, y, psi, want)
        touching += got > 0
    assert 500 < touching < 1900  # both sides of the boundary sampled


def test_a_leapfrog_batch_stops_each_hull_where_mujocos_integrator_does():
    n = 60
    eta = _starts(n, 1)
    acts = np.clip(np.random.default_rng(7).normal(0.3, 0.7, (n, 3)), -1, 1)
    runs = {}
    for integ in ("mujoco", "leapfrog"):
        bp = BatchedPhysics("blue-lady", n, integrator=integ, world="harbour")
        bp.reset(eta=eta)
        bp.set_command(bp.actuators.action_to_command(acts))
        steps = np.zeros(n, dtype=np.int64)
        active = np.ones(n, bool)
        poses = []
        for _ in range(150):
            poses.append(np.where(active[:, None], bp.eta, np.nan))
            steps += bp.step(20, stop_on_contact=True, mask=active)
            active &= bp.contact_counts == 0  # touched in this call: the hull stopped
            if not active.any():
                break
        runs[integ] = steps, np.array(poses)
    (s_mj, p_mj), (s_lf, p_lf) = runs["mujoco"], runs["leapfrog"]
    np.testing.assert_array_equal(s_lf, s_mj)
    assert (s_mj < 3000).sum() > n // 2  # most hulls reached a quay
    # before their contact the integrators agree to round-off
    k = min(len(p_mj), len(p_lf))
    np.testing.assert_allclose(p_lf[:k], p_mj[:k], rtol=0, atol=1e-9)


@pytest.mark.parametrize("seed", [0, 3])
def test_the_harbour_env_with_the_leapfrog_integrator_is_its_mujoco_episode(seed):
    """Driven into a quay: the same observations to round-off, the same contact step,
    termination and contact pairs (the last step's pose differs by MuJoCo's contact impulse,
    which the leapfrog hull does not feel)."""
    ends = []
    for integ in ("mujoco", "leapfrog"):
        env = gym.make(HARBOUR, observer="kbf", integrator=integ)
        env.reset(seed=seed)
        rng = np.random.default_rng(seed)
        obs = []
        for _ in range(400):
            a = np.array([1.0, rng.uniform(-1, 1), rng.uniform(-1, 1)], np.float32)
            o, _, term, trunc, info = env.step(a)
            obs.append(o)
            assert bool(info["contacts"]) == info["quay_contact"]  # the same contact in info
            if term or trunc:
                break
        ends.append((len(obs), term, info["quay_contact"], info["contacts"], np.array(obs)))
    (k0, t0, q0, c0, o0), (k1, t1, q1, c1, o1) = ends
    assert (k0, t0, q0) == (k1, t1, q1) and t0 and q0
    assert c1 and {b for _, b in c1} == {b for _, b in c0}
    np.testing.assert_allclose(o1[:-1], o0[:-1], rtol=0, atol=1e-4)  # float32 observations


def test_env_i_of_the_leapfrog_harbour_batch_is_its_single_env():
    n, seed = 2, 5
    venv = gym.make_vec(HARBOUR, num_envs=n, integrator="leapfrog")
    singles = [gym.make(HARBOUR, integrator="leapfrog") for _ in range(n)]
    obs, _ = venv.reset(seed=seed)
    for i, s in enumerate(singles):
        np.testing.assert_array_equal(s.reset(seed=seed + i)[0], obs[i])
    rng = np.random.default_rng(1)
    for _ in range(60):
        a = rng.uniform(-1, 1, (n, 3)).astype(np.float32)
        obs, rew, term, trunc, _ = venv.step(a)
        for i, s in enumerate(singles):
            o, r, te, tr, _ = s.step(a[i])
            np.testing.assert_array_equal(o, obs[i])
            assert (r, te, tr) == (rew[i], term[i], trunc[i])
        if term.any() or trunc.any():
            break


def test_a_leapfrog_world_needs_a_three_dof_hull():
    with pytest.raises(ValueError, match="3-DOF"):
        BatchedPhysics("naval-vessel", 1, integrator="leapfrog", world="open-water")
