r"""The mechanics every native batched env shares, and the single env as its batch of one.

The envs are written once over N >= 1 envs (arrays with a leading axis of N): the stepped
tasks' :class:`~shipgym.envs.stepped.TaskEnv` and the plan tasks'
:class:`~shipgym.envs.vector.ShipVectorEnv`. :class:`BatchedEnv` supplies Gymnasium's
``VectorEnv`` protocol around their hooks: seeding (env ``i`` seeded ``seed + i``), reset
masks, the autoreset modes (``"next-step"``, ``"same-step"``), the ``_key`` masks of
``info``, action validation and the episode metrics at each episode's end.
:class:`SingleEnv` is the Gymnasium single env of a family: its batch of one, with the
single-env API (rows unbatched, scalars as Python numbers). Env ``i`` of a batch of N
therefore is the single env seeded ``seed + i``, bit for bit, provided each row's arithmetic
does not depend on N (elementwise array operations and per-row compiled loops; no batched
BLAS products).

Public names: ``AUTORESET_MODES``, ``MAX_ENVS``, ``BatchedEnv``, ``SingleEnv``, ``unbatch``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

__all__ = ["AUTORESET_MODES", "MAX_ENVS", "BatchedEnv", "SingleEnv", "check_num_envs", "unbatch"]

Array = NDArray[np.float64]
Bools = NDArray[np.bool_]

#: the most envs in one batch: each env holds its physics, disturbances and noise streams
#: (tens of kB), so 65 536 envs are a few GB; more is a mistake that would exhaust the memory
MAX_ENVS = 1 << 16

#: the accepted ``autoreset_mode`` values (strings or :class:`gymnasium.vector.AutoresetMode`)
AUTORESET_MODES = {
    "next-step": AutoresetMode.NEXT_STEP,
    "same-step": AutoresetMode.SAME_STEP,
    AutoresetMode.NEXT_STEP: AutoresetMode.NEXT_STEP,
    AutoresetMode.SAME_STEP: AutoresetMode.SAME_STEP,
}


def check_num_envs(num_envs: Any) -> None:
    """``num_envs`` is an int in ``[1, MAX_ENVS]``, or a ``ValueError`` saying so."""
    if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
        raise ValueError(f"num_envs must be an int >= 1, got {num_envs!r}")
    if num_envs > MAX_ENVS:
        raise ValueError(
            f"num_envs must be at most {MAX_ENVS} (one process; use several processes for "
            f"more), got {num_envs}"
        )


class BatchedEnv(gym.vector.VectorEnv[Any, Any, Any]):
    """Base of a native batched env (module docstring).

    A subclass calls :meth:`_setup` in its ``__init__`` and implements the hooks:

    - ``_reset_envs(mask)``: reset the envs of ``mask``, env ``i`` drawing from
      ``self._rngs[i]`` in its fixed order;
    - ``_observation()``: the observation of every env now, ``(N, ...)``;
    - ``_reset_info(mask)``: the info of a reset, a dict of ``(N, ...)`` arrays (or nested
      dicts of them), rows of ``mask`` meaningful;
    - ``_step_envs(actions, active)``: one control period of the ``active`` envs (the others,
      resetting at this step, must not change), from ``actions`` ``(N, m)`` float64, finite,
      of the action space's shape; returns ``(reward, terminated, truncated, info)``, each a
      ``(N,)`` array but ``info``, a dict as ``_reset_info``'s;
    - ``_episode_metrics(done)`` (optional): the metrics of the envs of ``done`` at their
      episode's end, a dict of ``(N, ...)`` arrays, reported as ``info["episode_metrics"]``;
    - ``_reset_options(options, mask)`` (optional): the family's own reset options.

    Actions in the single action space's range are the task's; the subclass clips and flags
    them (``info["action_clipped"]``): the base checks the shape and finiteness only.
    """

    metadata: dict[str, Any] = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}
    #: whether ``_step_envs``' info already holds every key's ``_key`` mask (all envs), those
    #: of its nested dicts too, so that :meth:`step` need not add them
    _step_info_masked: ClassVar[bool] = False

    def __new__(cls, *args: Any, **kwargs: Any) -> Any:
        if args or kwargs:  # (none: unpickling) before a subclass builds anything for them
            check_num_envs(args[0] if args else kwargs.get("num_envs"))
        return super().__new__(cls)

    def _setup(
        self,
        num_envs: int,
        single_observation_space: spaces.Space[Any],
        single_action_space: spaces.Box,
        autoreset_mode: str | AutoresetMode = "next-step",
    ) -> None:
        """The batch's size, spaces and autoreset mode, checked."""
        check_num_envs(num_envs)
        if autoreset_mode not in AUTORESET_MODES:
            raise ValueError(
                f"autoreset_mode must be 'next-step' or 'same-step', got {autoreset_mode!r}"
            )
        self.num_envs = num_envs
        self.autoreset_mode = AUTORESET_MODES[autoreset_mode]
        self.metadata = dict(self.metadata, autoreset_mode=self.autoreset_mode)
        self.single_observation_space = single_observation_space
        self.single_action_space = single_action_space
        self.observation_space = batch_space(single_observation_space, num_envs)
        self.action_space = batch_space(single_action_space, num_envs)
        self._rngs: list[np.random.Generator | None] = [None] * num_envs
        self._ended = np.zeros(num_envs, dtype=bool)  # NEXT_STEP: reset at the next step
        self._started = False

    # ---- hooks ---------------------------------------------------------------------------
    def _reset_envs(self, mask: Bools) -> None:
        raise NotImplementedError

    def _observation(self) -> Any:
        raise NotImplementedError

    def _reset_info(self, mask: Bools) -> dict[str, Any]:
        raise NotImplementedError

    def _step_envs(
        self, actions: Array, active: Bools
    ) -> tuple[Array, Bools, Bools, dict[str, Any]]:
        raise NotImplementedError

    def _episode_metrics(self, done: Bools) -> dict[str, Any] | None:
        return None

    def _reset_options(self, options: dict[str, Any], mask: Bools) -> None:
        """Take the family's own reset ``options`` (``reset_mask`` removed) for the envs of
        ``mask``; here: none, so any is refused."""
        if options:
            raise ValueError(f"unknown reset options {sorted(options)}; valid: ['reset_mask']")

    # ---- gymnasium API -------------------------------------------------------------------
    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[Any, dict[str, Any]]:
        """Reset every env (or those of ``options["reset_mask"]``); env ``i`` is seeded with
        ``seed + i`` (an int), ``seed[i]`` (a sequence) or, without a seed, goes on with its
        generator (fresh entropy before the first seed)."""
        n = self.num_envs
        options = dict(options or {})
        mask = np.asarray(options.pop("reset_mask", np.ones(n, bool)), dtype=bool)
        if mask.shape != (n,):
            raise ValueError(f"options['reset_mask'] must be ({n},) booleans, got {mask.shape}")
        self._reset_options(options, mask)
        if seed is None:
            seeds: list[int | None] = [None] * n
        elif isinstance(seed, int | np.integer) and not isinstance(seed, bool):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)  # type: ignore[arg-type]
            if len(seeds) != n:
                raise ValueError(f"seed must be an int or {n} seeds (one per env), got {seed!r}")
        for i in np.nonzero(mask)[0].tolist():
            if seeds[i] is not None or self._rngs[i] is None:
                self._rngs[i], _ = seeding.np_random(seeds[i])
        if not self._started:
            if not mask.all():
                raise ValueError("the first reset must reset every env (no reset_mask)")
            self._started = True
        self._reset_envs(mask)
        self._ended = self._ended & ~mask  # (rebound: the last step's info holds the old)
        return self._observation(), _masked(self._reset_info(mask), mask)

    def step(self, actions: Any) -> tuple[Any, Array, Bools, Bools, dict[str, Any]]:
        """One control period of every env (``actions``: ``(num_envs, *action_shape)``).

        Raises:
            gymnasium.error.ResetNeeded: before the first :meth:`reset`.
            ValueError: actions of the wrong shape or with NaN / infinite values.
        """
        if not self._started:
            raise gym.error.ResetNeeded("call reset() before step()")
        a = np.asarray(actions, dtype=float)
        shape = self.action_space.shape
        if a.shape != shape:
            raise ValueError(f"actions must have shape {shape} (num_envs, ...), got {a.shape}")
        if not np.isfinite(a).all():
            bad = np.nonzero(~np.all(np.isfinite(a.reshape(len(a), -1)), axis=1))[0].tolist()
            raise ValueError(f"actions must be finite; NaN or infinite in envs {bad}")
        resetting = self._ended  # NEXT_STEP: these reset now and ignore their action
        active = ~resetting
        reward, terminated, truncated, info = self._step_envs(a, active)
        terminated = terminated & active
        truncated = truncated & active
        done = terminated | truncated
        if not self._step_info_masked:
            info = _masked(info, np.ones(self.num_envs, bool))
        ended = np.count_nonzero(done)  # (any(): count_nonzero is the cheaper reduction)
        if ended:
            metrics = self._episode_metrics(done)
            if metrics is not None:
                info["episode_metrics"] = metrics
                info["_episode_metrics"] = done
        obs = self._observation()
        if self.autoreset_mode == AutoresetMode.NEXT_STEP:
            if np.count_nonzero(resetting):
                self._reset_envs(resetting)
                obs = _where_rows(resetting, self._observation(), obs)
                reward = np.where(resetting, 0.0, reward)
                info = _merge_rows(info, self._reset_info(resetting), resetting)
            self._ended = done
            return obs, reward, terminated, truncated, info
        if ended:  # SAME_STEP: reset now, the last observation and info kept aside
            info["final_obs"] = _where_rows(done, obs, np.full_like(obs, np.nan))
            info["_final_obs"] = done
            info["final_info"] = {
                k: v for k, v in info.items() if not k.lstrip("_").startswith("final")
            }
            info["_final_info"] = done
            self._reset_envs(done)
            obs = _where_rows(done, self._observation(), obs)
        return obs, reward, terminated, truncated, info


def _where_rows(mask: Bools, a: Any, b: Any) -> Any:
    """Rows of ``a`` where ``mask``, else of ``b``."""
    a, b = np.asarray(a), np.asarray(b)
    out = np.where(mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, b)
    return out.astype(a.dtype, copy=False)  # (a new array already: no second copy)


def _masked(info: dict[str, Any], mask: Bools) -> dict[str, Any]:
    """``info`` with Gymnasium's ``_key`` mask beside every key that has none (nested dicts
    too)."""
    out = dict(info)
    for k, v in info.items():
        if k[:1] != "_":
            if "_" + k not in info:
                out["_" + k] = mask
            if type(v) is dict:
                out[k] = _masked(v, mask)
    return out


def _merge_rows(info: dict[str, Any], reset: dict[str, Any], mask: Bools) -> dict[str, Any]:
    """``info`` with the rows of ``mask`` from a reset's ``reset`` info (keys of both with
    the same shape; numeric rows that only a step has, such as reward terms, are zeroed)."""
    out = dict(info)
    for k, v in out.items():
        if k.startswith("_") or k == "episode_metrics":
            continue
        r = reset.get(k)
        if isinstance(v, dict):
            out[k] = _merge_rows(v, r if isinstance(r, dict) else {}, mask)
        elif isinstance(r, np.ndarray) and isinstance(v, np.ndarray) and r.shape == v.shape:
            out[k] = _where_rows(mask, r, v)
        elif isinstance(v, np.ndarray) and v.shape[:1] == mask.shape and v.dtype.kind == "f":
            out[k] = _where_rows(mask, np.zeros_like(v), v)
    for k, r in reset.items():
        if k not in out and isinstance(r, np.ndarray):
            out[k] = r
            out["_" + k] = mask
    return out


def unbatch(value: Any) -> Any:
    """Row 0 of a batched value: arrays lose their leading axis (0-d ones become Python
    numbers), dicts are unbatched per key (their ``_key`` masks dropped)."""
    t = type(value)
    if t is np.ndarray:
        row = value[0]
        return row.item() if row.ndim == 0 else row
    if t is dict or isinstance(value, Mapping):
        return {k: unbatch(v) for k, v in value.items() if k[:1] != "_"}
    return value


class SingleEnv(gym.Env[Any, Any]):
    """A family's Gymnasium single env: its :class:`BatchedEnv` of one (module docstring).

    A subclass names its batched class in ``batched``; its ``__init__`` arguments are the
    batched class's but ``num_envs`` and ``autoreset_mode``, plus ``render_mode`` where the
    family renders. The batch is :attr:`batch`; :meth:`episode_metrics` reports the current
    episode's metrics (the batch's ``episode_metrics(i)`` of env 0).
    """

    #: the family's batched env class
    batched: ClassVar[type[BatchedEnv]]
    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 1}

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(
                f"render_mode must be None or one of {self.metadata['render_modes']}, got "
                f"{render_mode!r}"
            )
        self.render_mode = render_mode
        self.batch = self.batched(1, **kwargs)  # type: ignore[call-arg]
        self.observation_space = self.batch.single_observation_space
        self.action_space = self.batch.single_action_space
        self._done = False
        self._view: Any = None  # (renderer, model, data) of the world's top camera

    def render(self) -> Any:
        """An RGB frame of the world's ``top`` camera (``render_mode="rgb_array"``), the hull at
        its pose now; ``None`` without a render mode or before the first reset."""
        physics = getattr(self.batch, "physics", None)
        if self.render_mode is None or physics is None or not self.batch._started:
            return None
        from shipgym.sim._mujoco import mujoco

        from .scene import build_model, make_renderer

        if self._view is None:
            model = build_model(physics.vessel, "open-water", physics.actuators)
            self._view = (make_renderer(model), model, mujoco.MjData(model))
        renderer, model, data = self._view
        data.qpos[:] = physics.qpos(0)
        mujoco.mj_forward(model, data)
        renderer.update_scene(data, camera="top")
        return renderer.render()

    def close(self) -> None:
        if self._view is not None:
            self._view[0].close()
            self._view = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        super().reset(seed=seed)
        if options:
            raise ValueError(f"unknown reset options {sorted(options)}")
        # the batch's generator is this env's: seeded as gym.Env.reset seeds np_random
        obs, info = self.batch.reset(seed=None if seed is None else [seed])
        self._np_random = self.batch._rngs[0]
        self._done = False
        return obs[0], unbatch(info)

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if self._done:
            raise gym.error.ResetNeeded("the episode has ended: call reset() before step()")
        a = np.asarray(action, dtype=float)
        if a.shape != self.action_space.shape:
            raise ValueError(f"action must have shape {self.action_space.shape}, got {a.shape}")
        obs, reward, terminated, truncated, info = self.batch.step(a[None])
        self._done = bool(terminated[0] or truncated[0])
        return obs[0], float(reward[0]), bool(terminated[0]), bool(truncated[0]), unbatch(info)

    def episode_metrics(self) -> dict[str, Any]:
        """The metrics of the episode so far."""
        return unbatch(self.batch._episode_metrics(np.ones(1, bool)) or {})
