"""Written once, tested for free, for a stepped task: a new task (a zig-zag autopilot's job:
swing the heading between +-10 deg with the rudder, seeing the gyros) defined in this file
alone runs single and batched through ``gym.make`` and ``gym.make_vec`` with no change to a
package file, on every vessel that fits it: :class:`~shipgym.envs.stepped.TaskEnv` steps it,
:class:`~shipgym.envs.stepped.TaskSingleEnv` is its batch of one, so env i of the batch is
the single env seeded ``seed + i`` to the last bit (over autoresets)."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from gymnasium.utils.env_checker import check_env

import shipgym  # noqa: F401 (registers the ids)
from shipgym.dynamics import wrap_angle
from shipgym.dynamics.vessel import load_vessel, vessel_names
from shipgym.envs.batchphysics import BatchedPhysics
from shipgym.envs.stepped import StepTask, TaskEnv

ID = "shipgym-test/ZigZagPilot-v0"
SWING = math.radians(10.0)  # rad: the heading set-points +-10 deg
GYRO = math.radians(0.1)  # rad: the gyro's noise


class ZigZagPilotTask(StepTask):
    """Swing the heading to +-``SWING`` and back, each set-point held ``period`` s, with
    the rudder; the ship starts straight at its approach speed on a drawn heading. The
    observation is ``[heading error (gyro), yaw rate, rudder / max]``; the reward terms
    ``heading = -(e/10 deg)^2`` and ``rudder = -0.1 (delta/max)^2``; terminated when the
    heading error passes 90 deg, truncated after ``episode_duration``."""

    reward_terms = ("heading", "rudder")

    def __init__(self, num_envs, *, vessel, period=40.0, episode_duration=120.0,
                 timestep=0.05, control_period=0.5):  # fmt: skip
        v = load_vessel(vessel)
        if not v.rudders or v.approach_speed is None:
            raise ValueError(f"{v.name!r} needs a rudder and an approach speed")
        self.vessel, self.period = v, float(period)
        self.set_timing(timestep, control_period, episode_duration)
        obs = spaces.Box(
            np.array([-3.2, -1.0, -1.01], np.float32), np.array([3.2, 1.0, 1.01], np.float32)
        )
        self.attach(num_envs, obs, spaces.Box(-1.0, 1.0, (1,), dtype=np.float32))
        self.physics = BatchedPhysics(v, num_envs, timestep=self.timestep)
        chans = list(self.physics.actuators.channel_names)
        self.rudder = chans.index(v.rudders[0])
        self.max_angle = float(self.physics.actuators.upper[self.rudder])
        self.psi0 = np.zeros(num_envs)
        self.gens = [None] * num_envs
        self.obs = np.zeros((num_envs, 3), dtype=np.float32)
        self.error_sum = np.zeros(num_envs)

    def setpoint(self):
        k = np.floor(self.steps * self.control_period / self.period).astype(np.int64)
        return self.psi0 + np.where(k % 2 == 0, SWING, -SWING)

    def sense(self, mask):
        phys = self.physics
        noise = np.zeros(self.num_envs)
        for i in np.nonzero(mask)[0].tolist():
            noise[i] = self.gens[i].normal(0.0, GYRO)
        dofs = phys.dofs
        psi = phys.eta_full[:, dofs - 1]
        r = phys.nu_full[:, dofs - 1]
        e = wrap_angle(psi + noise - self.setpoint())
        rud = phys.actuator_state[:, self.rudder] / self.max_angle
        obs = np.stack([e, r, rud], axis=1).astype(np.float32)
        self.obs = np.where(mask[:, None], obs, self.obs)

    def initialize_episode(self, rngs, mask):
        phys = self.physics
        U = self.vessel.approach_speed
        gens = [None] * self.num_envs
        for i in np.nonzero(mask)[0].tolist():
            self.psi0[i] = rngs[i].uniform(-math.pi, math.pi)
            gens[i] = np.random.default_rng(rngs[i].integers(2**63))
            self.gens[i] = np.random.default_rng(rngs[i].integers(2**63))
        nu = np.zeros((self.num_envs, 3))  # [u, v, r]; a 4-DOF hull starts upright
        nu[:, 0] = U
        eta = np.zeros((self.num_envs, 3))  # [x, y, psi]
        eta[:, 2] = self.psi0
        act = phys.initial_actuator_state()
        if self.vessel.shafts:  # the main propeller at the command that holds U
            from shipgym.envs.seatrial import approach_command

            shaft = list(phys.actuators.channel_names).index(self.vessel.shafts[0])
            act[:, shaft] = approach_command(phys, shaft, U)
        phys.reset(eta=eta, nu=nu, actuators=act, mask=mask, rngs=gens)
        phys.set_command(np.where(mask[:, None], act, phys.command))
        self.error_sum[mask] = 0.0
        self.sense(mask)

    def before_step(self, actions, active):
        cmd = self.physics.command.copy()
        a = np.clip(actions[:, 0], -1.0, 1.0)
        cmd[:, self.rudder] = np.where(active, a * self.max_angle, cmd[:, self.rudder])
        self.physics.set_command(cmd)

    def after_step(self, active):
        self.sense(active)
        phys = self.physics
        e = wrap_angle(phys.eta_full[:, phys.dofs - 1] - self.setpoint())
        rud = phys.actuator_state[:, self.rudder] / self.max_angle
        terms = {"heading": -((e / SWING) ** 2), "rudder": -0.1 * rud**2}
        self.error_sum += np.where(active, e * e, 0.0)
        info = {"heading_error": e, "rudder": rud * self.max_angle}
        return terms, np.abs(e) > math.pi / 2, info

    def observation(self):
        return self.obs.copy()

    def reset_info(self, mask):
        return {"psi0": self.psi0.copy()}

    def episode_metrics(self, done):
        return {"heading_rms": np.sqrt(self.error_sum / np.maximum(self.steps, 1))}


def fitting_vessels():
    return [n for n in vessel_names()
            if load_vessel(n).rudders and load_vessel(n).approach_speed is not None]  # fmt: skip


@pytest.fixture(scope="module", autouse=True)
def registered():
    gym.register(ID, entry_point="shipgym.envs.stepped:TaskSingleEnv",
                 vector_entry_point="shipgym.envs.stepped:TaskEnv",
                 kwargs={"task": ZigZagPilotTask})  # fmt: skip
    yield
    gym.registry.pop(ID, None)


def test_some_vessels_fit():
    assert len(fitting_vessels()) >= 3


@pytest.mark.parametrize("vessel", fitting_vessels())
@pytest.mark.parametrize("mode", ["next-step", "same-step"])
def test_the_new_stepped_task_single_and_batched_is_one_code_path(vessel, mode):
    env = gym.make(ID, vessel=vessel, episode_duration=6.0)
    check_env(env.unwrapped, skip_render_check=True)
    n = 3
    venv = gym.make_vec(ID, num_envs=n, vessel=vessel, episode_duration=6.0,
                        vectorization_mode="vector_entry_point", autoreset_mode=mode)  # fmt: skip
    assert isinstance(venv.unwrapped, TaskEnv)
    singles = [gym.make(ID, vessel=vessel, episode_duration=6.0) for _ in range(n)]
    obs, info = venv.reset(seed=3)
    for i, s in enumerate(singles):
        o, inf = s.reset(seed=3 + i)
        np.testing.assert_array_equal(obs[i], o)
        assert inf["psi0"] == info["psi0"][i]
    rng = np.random.default_rng(0)
    pending = np.zeros(n, bool)
    ends = 0
    for _ in range(30):
        a = rng.uniform(-1.0, 1.0, (n, 1)).astype(np.float32)
        obs, rew, term, trunc, info = venv.step(a)
        done = term | trunc
        for i, s in enumerate(singles):
            if pending[i]:  # next-step: the reset step
                o, _ = s.reset()
                assert rew[i] == 0.0
            else:
                o, r, te, tr, inf = s.step(a[i])
                assert (te, tr) == (bool(term[i]), bool(trunc[i]))
                assert r == rew[i] == sum(inf["reward_terms"].values())
                assert inf["heading_error"] == info["heading_error"][i]
                if te or tr:
                    m = info["final_info"] if mode == "same-step" else info
                    rms = s.unwrapped.episode_metrics()["heading_rms"]
                    assert m["episode_metrics"]["heading_rms"][i] == rms > 0
                    if mode == "same-step":
                        np.testing.assert_array_equal(info["final_obs"][i], o)
                        o, _ = s.reset()
            np.testing.assert_array_equal(obs[i], o)
        ends += int(done.sum())
        pending = done if mode == "next-step" else np.zeros(n, bool)
    assert ends >= 2 * n  # every env ended two episodes (6 s = 12 control steps) and went on


def test_the_task_reads_through_the_env_and_bad_settings_are_refused():
    env = gym.make(ID, vessel="kvlcc2-100m")
    assert env.unwrapped.period == 40.0  # the task's setting, through the single env
    assert env.unwrapped.batch.physics is env.unwrapped.batch.task.physics
    with pytest.raises(ValueError, match="whole multiple"):
        gym.make(ID, vessel="kvlcc2-100m", control_period=0.12)
    with pytest.raises(TypeError, match="StepTask subclass"):
        TaskEnv(2, task=dict)
