"""stable-baselines3's ``VecEnv`` over shipgym's native batched env.

Public names: ``BatchedVecEnv``, ``ErrorIntegralVecEnv``, ``make_batched_vec_env``.

Design notes: docs/design/rl.vec.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper

from shipgym.envs.batched import BatchedEnv
from shipgym.envs.integral import ErrorIntegral
from shipgym.envs.vector import ShipVectorEnv

__all__ = ["BatchedVecEnv", "ErrorIntegralVecEnv", "make_batched_vec_env"]


class BatchedVecEnv(VecEnv):
    """An SB3 ``VecEnv`` of a :class:`ShipVectorEnv` or a family's
    :class:`~shipgym.envs.batched.BatchedEnv` (module docstring).

    Args:
        venv: a ``ShipVectorEnv`` or ``BatchedEnv`` in ``autoreset_mode="same-step"``.
    """

    def __init__(self, venv: ShipVectorEnv | BatchedEnv) -> None:
        if not isinstance(venv, ShipVectorEnv | BatchedEnv):
            raise TypeError(
                f"BatchedVecEnv needs a ShipVectorEnv or a BatchedEnv, got {type(venv).__name__}"
            )
        if venv.autoreset_mode != gym.vector.AutoresetMode.SAME_STEP:
            raise ValueError(
                "BatchedVecEnv needs the same-step autoreset (SB3's semantics): make the env "
                "with autoreset_mode='same-step'"
            )
        self.venv = venv
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self._actions: np.ndarray | None = None

    def reset(self) -> np.ndarray:
        seeds = list(self._seeds)
        seed = None if all(s is None for s in seeds) else seeds
        obs, _ = self.venv.reset(seed=seed)
        self._reset_seeds()
        self._reset_options()
        self.reset_infos = [{} for _ in range(self.num_envs)]
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        if self._actions is None:
            raise RuntimeError("step_async(actions) must come before step_wait()")
        obs, reward, terminated, truncated, info = self.venv.step(self._actions)
        self._actions = None
        done = terminated | truncated
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        if done.any():
            final = info["final_obs"]
            for i in np.nonzero(done)[0].tolist():
                infos[i]["terminal_observation"] = final[i]
                infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
                self.reset_infos[i] = {}
        return obs, reward.astype(np.float32), done, infos

    def close(self) -> None:
        self.venv.close()

    def _shared(self, name: str) -> Any:
        """An attribute every env shares: the vector env's, else its task's."""
        venv = self.venv
        if hasattr(venv, name):
            return getattr(venv, name)
        task = getattr(venv, "task", None)
        if task is not None and hasattr(task, name):
            return getattr(task, name)
        raise AttributeError(f"the batched env and its task have no attribute {name!r}")

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        value = self._shared(attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        raise AttributeError(
            f"BatchedVecEnv: the envs share one configuration; cannot set {attr_name!r}"
        )

    def env_method(
        self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any
    ) -> list[Any]:
        fn = self._shared(method_name)
        return [fn(*method_args, **method_kwargs) for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: Any = None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [None for _ in range(self.num_envs)]


def make_batched_vec_env(
    env_id: str, n_envs: int, *, seed: int | None = None, **kwargs: Any
) -> BatchedVecEnv:
    """``gymnasium.make_vec(env_id, n_envs, vector_entry_point, autoreset_mode="same-step",
    **kwargs)`` as an SB3 ``VecEnv`` (seeded with ``seed`` at its first reset when given)."""
    venv = gym.make_vec(
        env_id, num_envs=n_envs, vectorization_mode="vector_entry_point",
        autoreset_mode="same-step", **kwargs,
    )  # fmt: skip
    out = BatchedVecEnv(venv.unwrapped)  # type: ignore[arg-type]
    if seed is not None:
        out.seed(seed)
    return out


class ErrorIntegralVecEnv(VecEnvWrapper):
    """:class:`~shipgym.envs.integral.ErrorIntegralObservation` of every env of an SB3
    ``VecEnv``: the leaky integral of the observed errors appended to each observation (the
    same arrays as the single wrapper's, step by step; a test checks it).

    An env whose episode ended gets its terminal observation augmented with the integral up
    to that step (``infos[i]["terminal_observation"]``), then a zero integral for the next
    episode's first observation.

    Args:
        venv: a ``VecEnv`` of shipgym positioning envs (unnormalised observations).
        dt: control period (s).
        time_constant: forgetting time ``T`` (s).
    """

    def __init__(self, venv: VecEnv, dt: float, time_constant: float) -> None:
        space = venv.observation_space
        assert isinstance(space, gym.spaces.Box) and len(space.shape) == 1
        n = space.shape[0]
        super().__init__(
            venv, observation_space=gym.spaces.Box(-np.inf, np.inf, (n + 3,), np.float32)
        )
        self.integral = ErrorIntegral(venv.num_envs, dt, time_constant)

    def reset(self) -> np.ndarray:
        obs = self.venv.reset()
        self.integral.reset()
        return self.integral.augment(obs)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        obs, reward, done, infos = self.venv.step_wait()
        done = np.asarray(done, bool)
        if done.any():
            final = np.array(obs, dtype=np.float64)
            for i in np.nonzero(done)[0].tolist():
                final[i] = infos[i]["terminal_observation"]
            value = self.integral.step(final)
            for i in np.nonzero(done)[0].tolist():
                aug = self.integral.augment(final[i : i + 1], value[i : i + 1])[0]
                infos[i]["terminal_observation"] = aug
            self.integral.reset(done)
            # the next episodes' first errors are not integrated: zero, as after a reset
        else:
            self.integral.step(obs)
        return self.integral.augment(obs), reward, done, infos
