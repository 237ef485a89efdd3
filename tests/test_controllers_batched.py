"""Every DP controller written once over N envs: ``gymnasium.make_vec(ID, num_envs=N,
controller=NAME)`` on the plan tasks equals, env by env and bit for bit, the single env
``shipgym.make(ID, controller=NAME)`` seeded ``seed + i`` (observations, rewards,
terminations, truncations and the controller's info arrays), over whole short episodes with
autoresets in both autoreset modes; the batched laws against their N = 1 use on random
inputs; the SDRE's compiled Riccati solver against SciPy's."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import shipgym
from shipgym.controllers.batch import CONTROLLERS, batched_dp_controller
from shipgym.controllers.design import lqr
from shipgym.controllers.grimble import GrimbleLQController, care, grimble_weights
from shipgym.dynamics.vessel import load_vessel, vessel_names
from shipgym.envs.registration import VECTOR_IDS, task_fits_vessel

#: the plan tasks (ShipVectorEnv) and their Blue Lady aliases
PLAN = [i for i in VECTOR_IDS if VECTOR_IDS[i].startswith("shipgym.envs.vector:")]
ALIASES = [i for i in PLAN if i.startswith("shipgym/BlueLady")]
VESSELS = [n for n in vessel_names() if load_vessel(n).dofs == 3]


def _fits(name: str, vessel: str) -> bool:
    try:
        CONTROLLERS[name].factory(load_vessel(vessel), 1.0)
    except ValueError:
        return False
    return True


def _cases() -> list[tuple[str, str, str | None]]:
    out = []
    for env_id in PLAN:
        vessels = [None] if env_id in ALIASES else VESSELS
        for v in vessels:
            if v is not None and not task_fits_vessel(env_id, load_vessel(v)):
                continue
            for name in CONTROLLERS:
                if _fits(name, v or "blue-lady"):
                    out.append((name, env_id, v))
    return out


CASES = _cases()


def _compare_info(vinfo: dict, i: int, sinfo: dict, where: str) -> None:
    for k in ("tau_c", "tau_delivered", "tau_error", "controller_action", "residual_clipped"):
        assert np.array_equal(vinfo[k][i], sinfo[k]), (where, k)
    for k, v in vinfo.items():
        if k.startswith("_") or k not in sinfo or not isinstance(v, np.ndarray):
            continue
        if v.dtype == object or not vinfo.get("_" + k, np.ones(len(v), bool))[i]:
            continue
        s = np.asarray(sinfo[k])
        if s.dtype != object and s.shape == v[i].shape:
            assert np.array_equal(v[i], s, equal_nan=True), (where, k)


#: with an observer (the controller on its estimate): each controller with a kinematic and a
#: model-based one
OBSERVED = [(name, "shipgym/Tracking-v0", obs, mode) for name in CONTROLLERS
            for obs, mode in (("kbf", "next-step"), ("ekf", "same-step"))]  # fmt: skip


@pytest.mark.parametrize(("name", "env_id", "vessel"), CASES)
def test_vector_env_with_the_controller_equals_the_single_envs(name, env_id, vessel):
    """N = 3 envs, episodes of 6 control steps (autoresets), 16 steps, random residuals;
    the autoreset mode alternates over the cases (both modes for every controller)."""
    mode = ("next-step", "same-step")[CASES.index((name, env_id, vessel)) % 2]
    _run(name, env_id, vessel, mode, None)


@pytest.mark.parametrize(("name", "env_id", "observer", "mode"), OBSERVED)
def test_vector_env_with_an_observer_equals_the_single_envs(name, env_id, observer, mode):
    """The same through the Kalman-Bucy filter and the EKF (model-based: the velocity
    source of a conditioned PID; the Blue Lady, or Star Hercules for the printed gains)."""
    vessel = "star-hercules" if name == "alt-lq-printed" else "blue-lady"
    _run(name, env_id, vessel, mode, observer)


def _run(name, env_id, vessel, mode, observer):
    n, steps, total = 3, 6, 16
    kw = {} if vessel is None else {"vessel": vessel}
    kw.update(controller=name, max_episode_steps=steps)
    if observer is not None:
        kw["observer"] = observer
    try:
        singles = [shipgym.make(env_id, **kw) for _ in range(n)]
    except ValueError as e:  # the task refuses the vessel (the harbour's size): so does the batch
        with pytest.raises(ValueError, match=str(e)[:30].replace("(", r"\(")):
            gym.make_vec(env_id, num_envs=n, **kw)
        pytest.skip(str(e))
    venv = gym.make_vec(env_id, num_envs=n, autoreset_mode=mode, **kw)
    assert venv.unwrapped.controller.name == name
    obs, _ = venv.reset(seed=11)
    for i, s in enumerate(singles):
        assert np.array_equal(obs[i], s.reset(seed=11 + i)[0])
    rng = np.random.default_rng(5)
    pending = np.zeros(n, bool)
    ends = 0
    for t in range(total):
        a = (0.3 * rng.standard_normal((n, *venv.single_action_space.shape))).astype(np.float32)
        obs, rew, term, trunc, info = venv.step(a)
        for i, s in enumerate(singles):
            where = (t, i)
            if pending[i]:  # next-step: this step resets env i
                o, _ = s.reset()
                assert np.array_equal(obs[i], o), where
                assert rew[i] == 0.0 and not term[i] and not trunc[i], where
                pending[i] = False
                continue
            o, r, te, tr, inf = s.step(a[i])
            assert rew[i] == r and term[i] == te and trunc[i] == tr, where
            if te or tr:
                ends += 1
                if mode == "same-step":
                    assert np.array_equal(info["final_obs"][i], o), where
                    o, _ = s.reset()
                else:
                    pending[i] = True
                    _compare_info(info, i, inf, where)
            else:
                _compare_info(info, i, inf, where)
            assert np.array_equal(obs[i], o), where
    assert ends >= n
    venv.close()
    for s in singles:
        s.close()


@pytest.mark.parametrize("name", list(CONTROLLERS))
def test_batched_law_rows_equal_the_law_at_n_1(name):
    """Row i of the batched controller (law and allocation) on random inputs equals a
    batch of one on row i's inputs, step after step, with resets of some envs and leg
    switches (frame turns) in between."""
    vessel = "star-hercules" if name == "alt-lq-printed" else "blue-lady"
    n = 4
    batch = batched_dp_controller(name, vessel, n, 0.5)
    ones = [batched_dp_controller(name, vessel, 1, 0.5) for _ in range(n)]
    rng = np.random.default_rng(3)
    state = np.tile(load_vessel(vessel).actuators.initial_state(), (n, 1))
    for k in range(30):
        eta = rng.normal(0, [3.0, 3.0, 0.3], (n, 3))
        nu = rng.normal(0, [0.2, 0.2, 0.02], (n, 3))
        ref = rng.normal(0, [1.0, 1.0, 0.1], (3, n, 3))
        got = batch(eta, nu, *ref, state=state)
        for i, one in enumerate(ones):
            want = one(eta[i : i + 1], nu[i : i + 1], *ref[:, i : i + 1], state=state[i : i + 1])
            assert np.array_equal(got[0][i], want[0][0]), (k, i)
            assert np.array_equal(got[2][i], want[2][0]), (k, i)
        if k % 7 == 3:
            m = rng.random(n) < 0.5
            dpsi = rng.normal(0, 1.0, n)
            batch.change_frame(dpsi, m)
            for i in np.nonzero(m)[0]:
                ones[i].change_frame(dpsi[i : i + 1])
        if k % 11 == 5:
            m = rng.random(n) < 0.5
            batch.reset(m)
            for i in np.nonzero(m)[0]:
                ones[i].reset()


@pytest.mark.parametrize("vessel", ["blue-lady", "star-hercules", "wimpey-sealab"])
def test_sdre_riccati_solver_matches_scipy(vessel):
    """:func:`~shipgym.controllers.grimble.care` (the compiled sign-function solver the
    SDRE runs per env) against SciPy's ``solve_continuous_are`` (through ``lqr``) on the LF
    model linearised at thruster states up to twice the saturation level ``F1``."""
    c = GrimbleLQController(load_vessel(vessel), 0.5, variant="sdre")
    lf, d = c.lf, c._design
    Q, R, _, _ = grimble_weights(lf.A, lf.B, lf.C)
    for level in (0.0, 0.3, 1.0, 2.0):
        A1 = np.array(lf.A)
        A1[:4, 4:6] *= np.exp(-np.abs(np.array([level, -0.5 * level])))
        K_ref, S_ref, _ = lqr(A1, lf.B, Q, R)
        S = care(A1, np.array(d.G), np.array(d.Q))  # (the law's writable types: its compile)
        np.testing.assert_allclose(S, S_ref, rtol=1e-9, atol=1e-11 * np.abs(S_ref).max())
        np.testing.assert_allclose(d.RiBt @ S, K_ref, rtol=1e-9, atol=1e-11)


def test_sdre_first_gain_is_the_lq_gain():
    """At rest (thruster states zero) the SDRE's model is the LF model: its first gain is
    the ``alt-lq`` gain (to the solvers' rounding)."""
    v = load_vessel("wimpey-sealab")
    sdre = GrimbleLQController(v, 0.5, variant="sdre")
    lq = GrimbleLQController(v, 0.5)
    e = np.array([1.0, -2.0, 0.05])
    np.testing.assert_allclose(sdre(e, np.zeros(3), np.zeros(3)), lq(e, np.zeros(3), np.zeros(3)),
                               rtol=1e-9)  # fmt: skip
