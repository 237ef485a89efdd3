r"""The leaky integral of the observed tracking errors, appended to the observation.

A memoryless policy (an MLP of the observation) cannot cancel a steady load such as the mean
wind: it settles where its proportional action balances the load, off the reference. A DP
controller removes that offset with integral action (Fossen 2011, sec. 12.2); this module
gives a learned policy the same information, the integral of the errors it sees.

Public names: ``ErrorIntegral``, ``ErrorIntegralObservation``, ``check_time_constant``.
Sources: Fossen (2011).

Design notes: docs/design/envs.integral.md.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from shipgym._config import is_real

__all__ = [
    "ErrorIntegral",
    "ErrorIntegralObservation",
    "check_time_constant",
]

#: bounds of the forgetting time (s): at least one control period, at most a day
_T_MIN, _T_MAX = 1e-3, 86_400.0


def check_time_constant(time_constant: Any) -> float:
    """The forgetting time ``T`` (s) as a float; raises ``ValueError`` naming the bounds."""
    if not is_real(time_constant) or not (_T_MIN <= float(time_constant) <= _T_MAX):
        raise ValueError(
            f"time_constant (the error integral's forgetting time) must be a number of "
            f"seconds in [{_T_MIN:g}, {_T_MAX:g}], got {time_constant!r}"
        )
    return float(time_constant)


class ErrorIntegral:
    """The leaky error integrals of ``n`` envs (module docstring), as arrays.

    Args:
        n: number of envs.
        dt: control period (s).
        time_constant: forgetting time ``T`` (s).
    """

    def __init__(self, n: int, dt: float, time_constant: float) -> None:
        self.dt = float(dt)
        self.time_constant = check_time_constant(time_constant)
        if not (self.dt > 0 and math.isfinite(self.dt)):
            raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
        self.decay = math.exp(-self.dt / self.time_constant)
        self.value = np.zeros((int(n), 3))

    def reset(self, mask: NDArray[np.bool_] | None = None) -> None:
        """Zero the integrals (of the envs in ``mask``; all without one)."""
        if mask is None:
            self.value[:] = 0.0
        else:
            self.value[np.asarray(mask, bool)] = 0.0

    def step(self, obs: NDArray[Any]) -> NDArray[np.float64]:
        """Integrate the errors ``obs[:, 0:3]`` of one control step; returns the integrals."""
        self.value = self.decay * self.value + self.dt * np.asarray(obs, np.float64)[:, :3]
        return self.value

    def augment(self, obs: NDArray[Any], value: NDArray[Any] | None = None) -> NDArray[np.float32]:
        """``obs`` (N, n) with the integrals (N, 3) appended, float32."""
        v = self.value if value is None else value
        return np.concatenate([np.asarray(obs, np.float32), v.astype(np.float32)], axis=1)


class ErrorIntegralObservation(
    gym.Wrapper[NDArray[np.float32], Any, NDArray[np.float32], Any],
    gym.utils.RecordConstructorArgs,
):
    """Appends the leaky integral of the observed errors to the observation (module docstring).

    Stack it last, above the observer (and a DP controller): it integrates what the policy
    sees. The observation space grows by three entries (``observation_structure`` gets
    ``error_integral``); actions, rewards and ``info`` pass through unchanged.

    Args:
        env: a shipgym positioning env (its observation starts with the body-frame errors).
        time_constant: forgetting time ``T`` (s), e.g. 100.
    """

    def __init__(self, env: gym.Env[Any, Any], time_constant: float = 100.0) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, time_constant=time_constant)
        gym.Wrapper.__init__(self, env)
        base = env.unwrapped
        structure = getattr(base, "observation_structure", None)
        if not structure or structure.get("pos_error_body") != slice(0, 3):
            raise ValueError(
                "ErrorIntegralObservation needs a shipgym positioning env (Harbour, Tracking, "
                f"StationKeeping: observation starting with the body-frame errors); got {base!r}"
            )
        space = env.observation_space
        assert isinstance(space, gym.spaces.Box) and len(space.shape) == 1
        n = space.shape[0]
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (n + 3,), np.float32)
        self.observation_structure = {**structure, "error_integral": slice(n, n + 3)}
        self.integral = ErrorIntegral(1, float(base.control_period), time_constant)
        self.time_constant = self.integral.time_constant

    def reset(self, **kwargs: Any) -> tuple[NDArray[np.float32], dict[str, Any]]:
        obs, info = self.env.reset(**kwargs)
        self.integral.reset()
        return self.integral.augment(np.asarray(obs)[None])[0], info

    def step(self, action: Any) -> tuple[NDArray[np.float32], Any, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        row = np.asarray(obs)[None]
        self.integral.step(row)
        return self.integral.augment(row)[0], reward, terminated, truncated, info
