"""Training of learned controllers: ``shipgym train ppo|sac`` (rl-baselines3-zoo style).

Public names: ``DEFAULT_ENV_ID``, ``EVALUATIONS``, ``EVAL_ENV_ID``, ``Evaluation``, ``SECTION``,
``STATION_RADIUS``, ``TrainResult``, ``evaluation_for``, ...

Design notes: docs/design/rl.train.md.
"""

from __future__ import annotations

import copy
import inspect
import json
import math
import shlex
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import yaml

from shipgym._config import is_real
from shipgym._safeload import jsonable
from shipgym._text import did_you_mean
from shipgym.controllers.learned import (
    ALGORITHMS,
    METADATA_NAME,
    LearnedPolicy,
    ModelMetadata,
    ObsNormalization,
    algorithm_class,
    check_policy_spec,
    check_trained_env,
    read_metadata,
    read_state_dicts,
    sb3_policy_kwargs,
    write_metadata,
)

from .evaluation import STATION_RADIUS, StationTrack, check_observer, run_env_episode
from .interop import INTEGRAL_WRAPPER, OBSERVER_WRAPPER, parse_env_wrapper

__all__ = [
    "DEFAULT_ENV_ID",
    "INTEGRAL_WRAPPER",
    "OBSERVER_WRAPPER",
    "EVALUATIONS",
    "EVAL_ENV_ID",
    "Evaluation",
    "SECTION",
    "STATION_RADIUS",
    "TrainResult",
    "evaluation_for",
    "parse_env_wrapper",
    "plain_policy_kwargs",
    "station_keeping_episode",
    "build_env",
    "build_vec_env",
    "train_seeds",
    "check_hyperparams",
    "hyperparams_path",
    "load_hyperparams",
    "packaged_hyperparams",
    "planned_timesteps",
    "reproduction_hyperparams",
    "reproduction_run",
    "restore_model_state",
    "rounding_notice",
    "set_deterministic",
    "train",
    "train_command",
]

#: the training task
DEFAULT_ENV_ID = "shipgym/BlueLadyTracking-v0"
#: the periodic evaluation of the Blue Lady's tracking task: the 5-leg harbour manoeuvre in its
#: default lake-trial wind (:data:`EVALUATIONS`)
EVAL_ENV_ID = "shipgym/BlueLadyHarbour-v0"

#: the top-level key of a hyperparameter file that holds shipgym's own options, per env id;
#: rl-zoo3 reads only the block of its ``--env`` (``ExperimentManager.read_hyperparameters``)
SECTION = "shipgym"
#: keys of an entry of the ``shipgym`` section
SECTION_KEYS = ("vec_env", "randomize", "eval_freq", "eval_seeds", "checkpoint_freq", "residual")
#: keys of an env-id block besides the algorithm's arguments: those rl-zoo3 2.9 reads itself
#: (``ExperimentManager._preprocess_hyperparams``) and shipgym uses
ZOO_BLOCK_KEYS = (
    "n_timesteps",
    "policy",
    "n_envs",
    "env_kwargs",
    "env_wrapper",
    "normalize",
    "policy_kwargs",
)
#: the activation of each algorithm's policy when ``policy_kwargs`` names none:
#: stable-baselines3's defaults (``ActorCriticPolicy``: ``nn.Tanh``; SAC's actor and critics:
#: ``nn.ReLU``); resolved hyperparameters always carry it by name
DEFAULT_ACTIVATION = {"ppo": "tanh", "sac": "relu"}
#: torch activation class names of the zoo's string form of ``policy_kwargs``
_ZOO_ACTIVATIONS = {
    "Tanh": "tanh",
    "ReLU": "relu",
    "ELU": "elu",
    "LeakyReLU": "leaky_relu",
    "SiLU": "silu",
    "GELU": "gelu",
}

#: keys of a hyperparameter block that shipgym uses (everything else goes to the algorithm)
SHIPGYM_KEYS = (
    "n_timesteps",
    "policy",
    "n_envs",
    "vec_env",
    "observer",
    "env_kwargs",
    "randomize",
    "normalize",
    "eval_freq",
    "eval_seeds",
    "checkpoint_freq",
    "residual",
    "controller",
    "residual_scale",
    "error_integral",
)
_INT_KEYS = (
    "n_timesteps",
    "n_envs",
    "n_steps",
    "batch_size",
    "n_epochs",
    "buffer_size",
    "learning_starts",
    "train_freq",
    "gradient_steps",
    "eval_freq",
    "checkpoint_freq",
)
_NOT_ALGO_ARGS = ("policy", "env", "seed", "device", "verbose", "_init_setup_model")

#: bounds of the integer hyperparameters (inclusive); they keep buffers and run lengths
#: within what a workstation holds: the rollout buffer is ``n_steps * n_envs`` transitions,
#: SAC's replay buffer ``buffer_size`` (10 million transitions of 15 + 3 floats: ~1.5 GB)
HP_INT_BOUNDS: dict[str, tuple[int, int]] = {
    "n_timesteps": (1, 10**10),
    "n_envs": (1, 256),
    "n_steps": (1, 1 << 20),
    "batch_size": (1, 1 << 20),
    "n_epochs": (1, 1000),
    "buffer_size": (1, 10_000_000),
    "learning_starts": (0, 10**10),
    "train_freq": (1, 1 << 20),
    "gradient_steps": (-1, 1 << 20),
    "eval_freq": (0, 10**10),
    "checkpoint_freq": (0, 10**10),
}
#: most transitions in PPO's rollout buffer (``n_steps * n_envs``)
MAX_ROLLOUT = 1 << 22
#: algorithm arguments that take Python objects (classes, noise processes): not settable from
#: a plain-data file
_OBJECT_ARGS = (
    "rollout_buffer_class",
    "rollout_buffer_kwargs",
    "replay_buffer_class",
    "replay_buffer_kwargs",
    "action_noise",
)
#: arguments that are a number or a schedule string (``"lin_3e-4"``), or ``"auto"`` (SAC)
_NUMBER_OR_STRING = ("learning_rate", "clip_range", "clip_range_vf", "ent_coef", "target_entropy")
#: keys of ``normalize`` (``VecNormalize`` arguments)
_NORMALIZE_KEYS = ("norm_obs", "norm_reward", "clip_obs", "clip_reward", "gamma", "epsilon")


# ---- hyperparameters -------------------------------------------------------------------------
def hyperparams_path(algo: str) -> Path:
    """The shipped YAML file of an algorithm (``shipgym/rl/hyperparams/<algo>.yml``)."""
    if algo not in ALGORITHMS:
        raise ValueError(f"unknown algorithm {algo!r}; choose one of: {', '.join(ALGORITHMS)}")
    return packaged_hyperparams(f"{algo}.yml")


def packaged_hyperparams(name: str) -> Path:
    """A hyperparameter file shipped with the package (``shipgym/rl/hyperparams/<name>``, e.g.
    ``"ppo_robust.yml"``); what a shipped model's ``reproduce`` record names.

    Raises:
        ValueError: no such file (the message lists the shipped ones).
    """
    folder = resources.files("shipgym.rl") / "hyperparams"
    names = sorted(p.name for p in folder.iterdir() if p.name.endswith(".yml"))
    if name not in names:
        raise ValueError(
            f"no shipped hyperparameter file {name!r}{did_you_mean(name, names)}; the package "
            f"has: {', '.join(names)}"
        )
    return Path(str(folder / name))


def _merge(base: dict[str, Any], over: Mapping[str, Any]) -> dict[str, Any]:
    """``base`` updated with ``over``, recursing into mappings except ``policy_kwargs``."""
    out = copy.deepcopy(base)
    for k, v in over.items():
        if isinstance(v, Mapping) and isinstance(out.get(k), dict) and k != "policy_kwargs":
            out[k] = _merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def load_hyperparams(
    algo: str,
    env_id: str = DEFAULT_ENV_ID,
    *,
    residual: bool = False,
    path: str | Path | None = None,
    overrides: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Resolved hyperparameters of ``algo`` for ``env_id`` (plain data).

    Reads the YAML file (``path`` or the shipped one) with ``yaml.safe_load``: the block of
    ``env_id`` (rl-zoo3's, keys the zoo accepts: :data:`ZOO_BLOCK_KEYS` and the algorithm's
    arguments) and its entry in the ``shipgym`` section (:data:`SECTION_KEYS`). The block's
    ``env_wrapper`` gives ``observer`` and ``error_integral`` (:func:`parse_env_wrapper`), its
    ``policy_kwargs`` become plain data with the activation by name
    (:func:`plain_policy_kwargs`); then the section's options, the ``residual`` overrides when
    ``residual`` and ``overrides`` are applied. The result has ``residual`` (bool),
    ``observer``, ``controller`` and ``residual_scale`` resolved.

    Raises:
        ValueError: missing env block, malformed values, unknown keys or algorithm arguments.
    """
    from shipgym._safeload import load_config_file

    p = Path(path) if path is not None else hyperparams_path(algo)
    if p.suffix.lower() not in (".yml", ".yaml"):
        raise ValueError(f"hyperparameter file {str(p)!r} must be a .yml / .yaml file")
    data = load_config_file(p, "hyperparameter file")
    if not isinstance(data, dict) or env_id == SECTION or env_id not in data:
        keys = [str(k) for k in data if k != SECTION] if isinstance(data, dict) else []
        raise ValueError(
            f"{p} has no hyperparameters for {env_id!r}{did_you_mean(env_id, keys)} (it has: "
            f"{', '.join(keys) or 'none'})"
        )
    block = data[env_id]
    if not isinstance(block, dict):
        raise ValueError(f"{p}: the block of {env_id!r} must be a mapping")
    section = data.get(SECTION) or {}
    if not isinstance(section, dict) or not all(isinstance(v, dict) for v in section.values()):
        raise ValueError(f"{p}: '{SECTION}' must map env ids to mappings of shipgym options")
    opts = copy.deepcopy(section.get(env_id) or {})
    unknown = sorted(set(opts) - set(SECTION_KEYS))
    if unknown:
        raise ValueError(
            f"{p}: {SECTION}.{env_id} has unknown keys {unknown}; valid: {', '.join(SECTION_KEYS)}"
        )
    hp = copy.deepcopy(block)
    misplaced = sorted(set(hp) & (set(SECTION_KEYS) | {"observer", "controller", "residual_scale"}))
    if misplaced:
        raise ValueError(
            f"{p}: {misplaced} in the block of {env_id!r} are not rl-zoo3 keys (the zoo hands "
            f"them to the algorithm, which fails): put them under '{SECTION}: {env_id}:' "
            f"(the observer goes into env_wrapper: {OBSERVER_WRAPPER})"
        )
    hp["observer"], integral = parse_env_wrapper(hp.pop("env_wrapper", None), where=str(p))
    if integral is not None:
        hp["error_integral"] = integral
    res_block = opts.pop("residual", None) or {}
    if not isinstance(res_block, dict):
        raise ValueError(f"{p}: '{SECTION}.{env_id}.residual' must be a mapping of overrides")
    hp.update(opts)
    if residual:
        hp = _merge(hp, res_block)
        hp.setdefault("controller", "pid")
        hp.setdefault("residual_scale", 1.0)
    else:
        hp.pop("controller", None)
        hp.pop("residual_scale", None)
    hp["residual"] = bool(residual)
    if overrides:
        hp = _merge(hp, overrides)
    if "policy_kwargs" in hp:
        hp["policy_kwargs"] = plain_policy_kwargs(algo, hp["policy_kwargs"], where=str(p))
    for k in _INT_KEYS:
        if k in hp and hp[k] is not None:
            v = hp[k]
            if isinstance(v, str):
                v = float(v)
            if isinstance(v, float) and v.is_integer():
                v = int(v)
            if not isinstance(v, int) or isinstance(v, bool):
                raise ValueError(f"{p}: {k} must be a whole number, got {hp[k]!r}")
            hp[k] = v
    _check_algo_args(algo, hp, where=str(p))
    check_hyperparams(algo, hp, where=str(p))
    return hp


def plain_policy_kwargs(algo: str, value: Any, where: str = "hyperparameters") -> dict[str, Any]:
    """``policy_kwargs`` of a file as plain data, the activation by name.

    A mapping as it is, or rl-zoo3's string form ``"dict(net_arch=[64, 64],
    activation_fn=nn.ReLU)"``, which the zoo evaluates and shipgym parses instead: a call of
    ``dict`` with keyword arguments whose values are literals, ``activation_fn`` one of
    ``nn.Tanh``, ``nn.ReLU``, ``nn.ELU``, ``nn.LeakyReLU``, ``nn.SiLU``, ``nn.GELU``. Without
    ``activation_fn`` the algorithm's default is filled in (:data:`DEFAULT_ACTIVATION`).

    Raises:
        ValueError: any other string (nothing is evaluated), or not a mapping.
    """
    if isinstance(value, str):
        value = _parse_zoo_policy_kwargs(value, where)
    if not isinstance(value, Mapping):
        raise ValueError(f"{where}: policy_kwargs must be a mapping, got {value!r}")
    out = copy.deepcopy(dict(value))
    out.setdefault("activation_fn", DEFAULT_ACTIVATION[algo])
    return out


def _parse_zoo_policy_kwargs(text: str, where: str) -> dict[str, Any]:
    """``"dict(key=literal, ..., activation_fn=nn.Name)"`` -> plain data (no eval)."""
    import ast

    form = 'policy_kwargs: "dict(net_arch=[64, 64], activation_fn=nn.ReLU)"'
    bad = ValueError(
        f"{where}: policy_kwargs as a string must be rl-zoo3's narrow form {form} (a call of "
        f"dict with literal keyword values; activation_fn one of "
        f"{', '.join('nn.' + n for n in _ZOO_ACTIVATIONS)}); shipgym evaluates nothing, so "
        f"write anything else as a mapping. Got {text[:200]!r}"
    )
    if len(text) > 10_000:
        raise bad
    try:
        tree = ast.parse(text.strip(), mode="eval").body
    except SyntaxError:
        raise bad from None
    if not (
        isinstance(tree, ast.Call)
        and isinstance(tree.func, ast.Name)
        and tree.func.id == "dict"
        and not tree.args
        and all(kw.arg is not None for kw in tree.keywords)
    ):
        raise bad
    out: dict[str, Any] = {}
    for kw in tree.keywords:
        node = kw.value
        if kw.arg == "activation_fn":
            if not (
                isinstance(node, ast.Attribute)
                and isinstance(node.value, ast.Name)
                and node.value.id == "nn"
                and node.attr in _ZOO_ACTIVATIONS
            ):
                raise bad
            out["activation_fn"] = _ZOO_ACTIVATIONS[node.attr]
            continue
        try:
            out[str(kw.arg)] = ast.literal_eval(node)
        except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
            raise bad from None
    return out


def check_hyperparams(algo: str, hp: Mapping[str, Any], where: str = "hyperparameters") -> None:
    """Refuse hyperparameters beyond the limits, before anything is allocated.

    Integers within :data:`HP_INT_BOUNDS`, ``n_steps * n_envs`` at most :data:`MAX_ROLLOUT`,
    numbers finite, the policy within the architecture limits of
    :func:`shipgym.controllers.learned.check_policy_spec` (``MlpPolicy``, plain
    ``policy_kwargs``, layer width, parameter count).

    Raises:
        ValueError: naming the hyperparameter and its valid range.
    """
    for k, (lo, hi) in HP_INT_BOUNDS.items():
        v = hp.get(k)
        if v is None:
            continue
        if algo == "sac" and k == "train_freq" and isinstance(v, list | tuple):
            v = v[0] if v else None
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            raise ValueError(f"{where}: {k} must be a whole number from {lo} to {hi}, got {v!r}")
    rollout = int(hp.get("n_steps", 1) or 1) * int(hp.get("n_envs", 1) or 1)
    if algo == "ppo" and rollout > MAX_ROLLOUT:
        raise ValueError(
            f"{where}: n_steps * n_envs = {rollout:,} transitions, more than {MAX_ROLLOUT:,}"
        )
    for k, v in hp.items():
        if isinstance(v, float) and not math.isfinite(v):
            raise ValueError(f"{where}: {k} must be finite, got {v!r}")
    _check_hp_types(algo, hp, where)
    try:
        check_policy_spec(algo, hp.get("policy", "MlpPolicy"), hp.get("policy_kwargs") or {})
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def _is_number(v: Any) -> bool:
    return is_real(v) and math.isfinite(v)


def _check_hp_types(algo: str, hp: Mapping[str, Any], where: str) -> None:
    """Types of the hyperparameters: as the algorithm's defaults, plain data only."""
    from shipgym.controllers.learned import _plain

    sig = inspect.signature(algorithm_class(algo).__init__).parameters
    for k, v in hp.items():
        _plain(v, f"{where}: {k}")
        if k in _OBJECT_ARGS and v is not None:
            raise ValueError(f"{where}: {k} takes Python objects; not settable from a file")
        if k in SHIPGYM_KEYS or k not in sig or k in ("policy_kwargs", "train_freq"):
            continue
        default = sig[k].default
        if k in _NUMBER_OR_STRING:
            ok = v is None or _is_number(v) or isinstance(v, str)
        elif isinstance(default, bool):
            ok = isinstance(v, bool)
        elif isinstance(default, int | float):
            ok = _is_number(v)
        else:
            ok = True
        if not ok:
            kind = "true or false" if isinstance(default, bool) else "a finite number"
            raise ValueError(f"{where}: {k} must be {kind}, got {v!r}")
    norm = hp.get("normalize")
    if norm is not None and not isinstance(norm, bool):
        if not isinstance(norm, Mapping):
            raise ValueError(f"{where}: normalize must be true/false or a mapping, got {norm!r}")
        unknown = sorted(set(norm) - set(_NORMALIZE_KEYS))
        if unknown:
            raise ValueError(
                f"{where}: normalize has unknown keys {unknown}; valid: "
                f"{', '.join(_NORMALIZE_KEYS)}"
            )
        for k, v in norm.items():  # VecNormalize's flags and positive bounds
            flag = k in ("norm_obs", "norm_reward")
            ok = isinstance(v, bool) if flag else _is_number(v) and v > 0
            if ok and k == "gamma":
                ok = v <= 1
            if not ok:
                what = (
                    "true or false"
                    if flag
                    else ("a number in (0, 1]" if k == "gamma" else "a finite number > 0")
                )
                raise ValueError(f"{where}: normalize.{k} must be {what}, got {v!r}")
    seeds = hp.get("eval_seeds")
    if seeds is not None and not (
        isinstance(seeds, list | tuple)
        and len(seeds) <= 1000
        and all(isinstance(x, int) and not isinstance(x, bool) and x >= 0 for x in seeds)
    ):
        raise ValueError(f"{where}: eval_seeds must be a list of at most 1000 ints >= 0")
    for key in ("env_kwargs", "randomize"):
        if hp.get(key) is not None and not isinstance(hp[key], Mapping):
            raise ValueError(f"{where}: {key} must be a mapping, got {hp[key]!r}")
    scale = hp.get("residual_scale")
    if scale is not None and not (_is_number(scale) and scale >= 0):
        raise ValueError(f"{where}: residual_scale must be a finite number >= 0, got {scale!r}")


def _check_algo_args(algo: str, hp: Mapping[str, Any], where: str) -> None:
    cls = algorithm_class(algo)
    params = set(inspect.signature(cls.__init__).parameters) - set(_NOT_ALGO_ARGS)
    unknown = sorted(k for k in hp if k not in SHIPGYM_KEYS and k not in params)
    if unknown:
        raise ValueError(
            f"{where}: unknown hyperparameter(s) {unknown} for {algo}; shipgym keys: "
            f"{', '.join(SHIPGYM_KEYS)}; {algo} arguments: {', '.join(sorted(params))}"
        )


def _schedule(value: Any, name: str) -> Any:
    """A number, or ``"lin_<x>"``: linear decay from ``x`` to 0 over training."""
    if isinstance(value, str):
        if value.startswith("lin_"):
            try:
                x0 = float(value[4:])
            except ValueError:
                raise ValueError(f"{name}: malformed schedule {value!r} (use lin_3e-4)") from None
            return lambda progress_remaining: progress_remaining * x0
        try:
            return float(value)
        except ValueError:
            raise ValueError(f"{name} must be a number or 'lin_<number>', got {value!r}") from None
    return value


def _algo_kwargs(algo: str, hp: Mapping[str, Any]) -> dict[str, Any]:
    kw = {k: v for k, v in hp.items() if k not in SHIPGYM_KEYS}
    for key in ("learning_rate", "clip_range", "clip_range_vf"):
        if key in kw:
            kw[key] = _schedule(kw[key], key)
    if "policy_kwargs" in kw:
        kw["policy_kwargs"] = sb3_policy_kwargs(kw["policy_kwargs"])
    if algo == "sac" and isinstance(kw.get("train_freq"), list):
        kw["train_freq"] = tuple(kw["train_freq"])
    return kw


# ---- environments ----------------------------------------------------------------------------
def _draw_sensors(spec: Mapping[str, Any], seed: int, rank: int, base: Any = "default") -> Any:
    """``base`` (the recipe's ``env_kwargs.sensors``: a preset name, a mapping or a
    SensorConfig; its faults, period and everything not drawn are kept) with the noise sigmas
    drawn uniformly from ``spec`` (own seeded stream)."""
    import dataclasses

    from shipgym.envs.task import parse_sensors_arg

    known = {"position_sigma", "heading_sigma_deg"}
    unknown = sorted(set(spec) - known)
    if unknown:
        raise ValueError(f"randomize.sensors: unknown keys {unknown}; valid: {sorted(known)}")
    rng = np.random.default_rng([int(seed), int(rank), 7919])
    kw: dict[str, float] = {}
    if "position_sigma" in spec:
        lo, hi = (float(x) for x in spec["position_sigma"])
        kw["position_variance"] = float(rng.uniform(lo, hi)) ** 2
    if "heading_sigma_deg" in spec:
        lo, hi = (float(x) for x in spec["heading_sigma_deg"])
        kw["heading_variance"] = math.radians(float(rng.uniform(lo, hi))) ** 2
    given = parse_sensors_arg(base)
    if given is None:
        raise ValueError(
            "randomize.sensors draws the sensor noise, but env_kwargs.sensors is None (no "
            "sensors): give sensors or drop randomize.sensors"
        )
    return dataclasses.replace(given, **kw)


def build_env(
    env_id: str,
    hp: Mapping[str, Any],
    *,
    seed: int = 0,
    rank: int = 0,
    env_kwargs: Mapping[str, Any] | None = None,
    randomize: bool = True,
) -> gym.Env[Any, Any]:
    """One environment of the training stack: env -> observer -> [DP controller (residual)].

    Args:
        env_id: env id.
        hp: resolved hyperparameters (:func:`load_hyperparams`).
        seed: training seed (only used by the sensor randomisation).
        rank: index of this env in the vector env.
        env_kwargs: environment arguments (default: ``hp["env_kwargs"]``).
        randomize: apply ``hp["randomize"]``.
    """
    import shipgym  # noqa: F401  (registers the ids in worker processes)
    from shipgym.stacks import make

    kwargs = dict(hp.get("env_kwargs") or {}) if env_kwargs is None else dict(env_kwargs)
    rnd = hp.get("randomize") or {}
    unknown = sorted(set(rnd) - {"sensors"})
    if unknown:
        raise ValueError(f"randomize: unknown keys {unknown}; valid: ['sensors']")
    if randomize and "sensors" in rnd:
        kwargs["sensors"] = _draw_sensors(
            rnd["sensors"], seed, rank, kwargs.get("sensors", "default")
        )
    residual = bool(hp.get("residual"))
    env = make(
        env_id,
        observer=check_observer(hp.get("observer")),
        controller=hp["controller"] if residual else None,
        residual_scale=float(hp["residual_scale"]) if residual else 1.0,
        **kwargs,
    )
    if hp.get("error_integral") is not None:
        from shipgym.envs.integral import ErrorIntegralObservation

        env = ErrorIntegralObservation(env, time_constant=float(hp["error_integral"]))
    return env


def build_vec_env(
    env_id: str, hp: Mapping[str, Any], n_envs: int, seed: int, vec_env: str = "dummy"
) -> Any:
    """``VecMonitor(DummyVecEnv | SubprocVecEnv)`` of ``n_envs`` training envs (not normalised)."""
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecMonitor

    if not (isinstance(n_envs, int) and n_envs >= 1):
        raise ValueError(f"n_envs must be an int >= 1, got {n_envs!r}")
    hp = dict(hp)
    fns = [_EnvFactory(env_id, hp, seed, i) for i in range(n_envs)]
    if vec_env == "batched":
        return VecMonitor(_batched_vec_env(env_id, hp, n_envs, seed))
    if vec_env == "dummy":
        venv = DummyVecEnv(fns)  # type: ignore[arg-type]
    elif vec_env == "subproc":
        venv = SubprocVecEnv(fns, start_method="forkserver")  # type: ignore[arg-type]
    else:
        raise ValueError(f"vec_env must be 'dummy', 'subproc' or 'batched', got {vec_env!r}")
    return VecMonitor(venv)


def _batched_vec_env(env_id: str, hp: Mapping[str, Any], n_envs: int, seed: int) -> Any:
    """The training stack of :func:`build_env` for ``n_envs`` envs as one native batched env
    (:mod:`shipgym.rl.vec`): the same envs, observer, controller and per-env sensors."""
    import shipgym  # noqa: F401  (registers the ids)
    from shipgym.rl.vec import make_batched_vec_env

    kwargs = dict(hp.get("env_kwargs") or {})
    rnd = hp.get("randomize") or {}
    unknown = sorted(set(rnd) - {"sensors"})
    if unknown:
        raise ValueError(f"randomize: unknown keys {unknown}; valid: ['sensors']")
    if "sensors" in rnd:
        base = kwargs.get("sensors", "default")
        kwargs["env_sensors"] = [
            _draw_sensors(rnd["sensors"], seed, i, base) for i in range(n_envs)
        ]
        kwargs["sensors"] = kwargs["env_sensors"][0]
    observer = check_observer(hp.get("observer"))
    if observer is not None:
        kwargs["observer"] = observer
    if hp.get("residual"):
        kwargs["controller"] = hp["controller"]
        kwargs["residual_scale"] = float(hp["residual_scale"])
    venv = make_batched_vec_env(env_id, n_envs, **kwargs)
    if hp.get("error_integral") is not None:
        from shipgym.rl.vec import ErrorIntegralVecEnv

        dt = float(venv.venv.control_period)
        return ErrorIntegralVecEnv(venv, dt, float(hp["error_integral"]))
    return venv


@dataclass
class _EnvFactory:
    """A picklable ``() -> env`` for the vector envs."""

    env_id: str
    hp: dict[str, Any]
    seed: int
    rank: int

    def __call__(self) -> gym.Env[Any, Any]:
        return build_env(self.env_id, self.hp, seed=self.seed, rank=self.rank)


def set_deterministic(seed: int, threads: int = 1) -> None:
    """Seed python, numpy and torch; single-threaded, deterministic torch algorithms."""
    import torch
    from stable_baselines3.common.utils import set_random_seed

    torch.set_num_threads(threads)
    torch.use_deterministic_algorithms(True)
    set_random_seed(seed)


# ---- metadata --------------------------------------------------------------------------------
def train_command(
    algo: str,
    *,
    timesteps: int,
    seed: int,
    n_envs: int,
    out: str | Path,
    residual: bool,
    observer: str | None,
    resume: str | Path | None = None,
    max_minutes: float | None = None,
    env_id: str = DEFAULT_ENV_ID,
    hyperparams: str | Path | None = None,
) -> str:
    """The ``shipgym train`` command line that reproduces a run (stored in the metadata);
    ``hyperparams``: a hyperparameter file other than the shipped one (``--hyperparams``)."""
    parts = ["shipgym", "train", algo]
    if hyperparams is not None:
        parts += ["--hyperparams", str(hyperparams)]
    if env_id != DEFAULT_ENV_ID:
        parts += ["--env", env_id]
    parts += ["--timesteps", str(timesteps), "--seed", str(seed)]
    parts += ["--n-envs", str(n_envs), "--out", str(out)]
    if residual:
        parts.append("--residual")
    parts += ["--observer", observer or "truth"]
    if resume is not None:
        parts += ["--resume", str(resume)]
    if max_minutes is not None:
        parts += ["--max-minutes", f"{max_minutes:g}"]
    return shlex.join(parts)


def _versions() -> dict[str, str]:
    import stable_baselines3
    import torch

    import shipgym

    return {
        "shipgym_version": shipgym.__version__,
        "sb3_version": stable_baselines3.__version__,
        "torch_version": torch.__version__,
    }


def _metadata(
    algo: str,
    env_id: str,
    hp: Mapping[str, Any],
    model: Any,
    venv: Any,
    *,
    seed: int,
    command: str,
    extra: Mapping[str, Any] | None = None,
) -> ModelMetadata:
    from stable_baselines3.common.vec_env import VecNormalize

    norm = ObsNormalization.from_vec_normalize(venv) if isinstance(venv, VecNormalize) else None
    return ModelMetadata(
        algorithm=algo,
        env_id=env_id,
        env_kwargs=copy.deepcopy(dict(hp.get("env_kwargs") or {})),
        observer=check_observer(hp.get("observer")),
        residual=bool(hp.get("residual")),
        controller=hp.get("controller") if hp.get("residual") else None,
        residual_scale=float(hp.get("residual_scale", 1.0)) if hp.get("residual") else 1.0,
        error_integral=hp.get("error_integral"),
        normalization=norm,
        policy=str(hp.get("policy", "MlpPolicy")),
        policy_kwargs=copy.deepcopy(dict(hp.get("policy_kwargs") or {})),
        use_sde=bool(hp.get("use_sde", False)),
        observation_shape=tuple(model.observation_space.shape),
        action_shape=tuple(model.action_space.shape),
        seed=seed,
        command=command,
        num_timesteps=int(model.num_timesteps),
        hyperparams=copy.deepcopy(dict(hp)),
        extra=dict(extra or {}),
        **_versions(),
    )


def save_model(model: Any, path: str | Path, meta: ModelMetadata) -> Path:
    """``model.save(path)`` plus ``shipgym.json``; returns the path of the zip.

    With normalisation statistics in ``meta`` the same statistics go to SB3's
    ``VecNormalize`` file next to the zip (:func:`~shipgym.rl.interop.vecnormalize_path`:
    ``vecnormalize.pkl`` for ``model.zip``, ``<stem>_vecnormalize.pkl`` for the others), so
    that plain SB3 loads the model with ``VecNormalize.load``; without them a stale file of
    that name is removed.
    """
    from shipgym.rl.interop import save_vecnormalize, vecnormalize_path

    p = Path(path)
    if p.suffix != ".zip":
        p = p.with_name(p.name + ".zip")
    p.parent.mkdir(parents=True, exist_ok=True)
    model.save(p)
    write_metadata(p, meta)
    pkl = vecnormalize_path(p)
    if meta.normalization is not None:
        save_vecnormalize(meta.normalization, pkl, model.observation_space, model.action_space)
    else:
        pkl.unlink(missing_ok=True)
    return p


# ---- callbacks -------------------------------------------------------------------------------
def _callbacks() -> Any:
    from stable_baselines3.common import callbacks

    return callbacks


# ---- periodic evaluation --------------------------------------------------------------------


@dataclass(frozen=True)
class Evaluation:
    """A periodic evaluation of the policy during training (see :data:`EVALUATIONS`).

    Attributes:
        name: what it is (``harbour``, ``station-keeping``).
        build: ``(env_id, hp) -> env``: the evaluation env (observer of ``hp``, no sensor
            randomisation).
        episode: ``(env, seed, policy) -> row``: one episode.
        summarize: ``rows -> (summary, scalars, score)``: the plain-data summary (stored in
            ``evaluations.json``), the scalars logged as ``eval/<name>`` (progress.csv,
            TensorBoard) and the score ``best_model.zip`` maximises.
    """

    name: str
    build: Callable[[str, Mapping[str, Any]], gym.Env[Any, Any]]
    episode: Callable[[gym.Env[Any, Any], int, Any], dict[str, Any]]
    summarize: Callable[
        [Sequence[Mapping[str, Any]]], tuple[dict[str, Any], dict[str, float], tuple[float, ...]]
    ]


def _score(rows: Sequence[Mapping[str, Any]]) -> tuple[int, float]:
    """(runs completed without quay contact, -mean J_c): larger is better."""
    ok = sum(bool(r["completed"]) and not r["quay_contact"] for r in rows)
    jc = [float(r["J_c"]) for r in rows if math.isfinite(float(r["J_c"]))]
    return ok, -(float(np.mean(jc)) if jc else math.inf)


def _harbour_env(env_id: str, hp: Mapping[str, Any]) -> gym.Env[Any, Any]:
    from shipgym.controllers.learned import policy_env_kwargs

    # the harbour's own conditions; of the training env's arguments only the policy's own
    kw = policy_env_kwargs(hp.get("env_kwargs"))
    return build_env(EVAL_ENV_ID, hp, env_kwargs=kw, randomize=False)


def _harbour_summary(
    rows: Sequence[Mapping[str, Any]],
) -> tuple[dict[str, Any], dict[str, float], tuple[float, ...]]:
    """Completion (without quay contact), J_c (truth and measured), contacts, duration."""
    ok, neg_jc = _score(rows)
    meas = [
        r["measured"]["J_c"]
        for r in rows
        if r.get("measured") and math.isfinite(r["measured"]["J_c"])
    ]
    summary: dict[str, Any] = {
        "completed": ok,
        "runs": len(rows),
        "J_c": -neg_jc,
        "J_c_measured": float(np.mean(meas)) if meas else None,
        "rows": [
            {k: r[k] for k in ("seed", "completed", "quay_contact", "J_c", "duration_s")}
            for r in rows
        ],
    }
    # the completion is its own scalar; J_c (the mean over the runs that completed, the others
    # have none) only when one did: never inf in progress.csv or TensorBoard
    scalars: dict[str, float] = {"completed_fraction": ok / max(len(rows), 1)}
    if math.isfinite(summary["J_c"]):
        scalars["J_c"] = summary["J_c"]
    if meas:
        scalars["J_c_measured"] = summary["J_c_measured"]
    scalars["quay_contact"] = float(sum(r["quay_contact"] for r in rows))
    scalars["duration_s"] = float(np.mean([r["duration_s"] for r in rows]))
    return summary, scalars, (ok, neg_jc)


def _station_env(env_id: str, hp: Mapping[str, Any]) -> gym.Env[Any, Any]:
    return build_env(env_id, hp, randomize=False)


def station_keeping_episode(env: gym.Env[Any, Any], seed: int, policy: Any) -> dict[str, Any]:
    """One station-keeping episode: the fraction of steps within :data:`STATION_RADIUS` of the
    set point (true position), the 95th percentile of the distance (m), the heading error RMS
    (deg) and the return (:class:`~shipgym.rl.evaluation.StationTrack`)."""
    track = StationTrack()
    row = run_env_episode(env, seed, policy, on_step=track)
    st = track.summary(STATION_RADIUS)
    return {
        "seed": int(seed),
        "inside_fraction": st["inside_fraction"] if st["steps"] else 0.0,
        "r95": st["r95"] if st["steps"] else math.inf,
        "heading_rms_deg": st["heading_rms_deg"],
        "return": float(row["return"]),
        "steps": int(st["steps"]),
    }


def _station_summary(
    rows: Sequence[Mapping[str, Any]],
) -> tuple[dict[str, Any], dict[str, float], tuple[float, ...]]:
    """Mean fraction of time within the radius, mean r95 and mean return."""
    inside = float(np.mean([r["inside_fraction"] for r in rows]))
    ret = float(np.mean([r["return"] for r in rows]))
    summary: dict[str, Any] = {
        "inside_fraction": inside,
        "radius_m": STATION_RADIUS,
        "return": ret,
        "runs": len(rows),
        "rows": [dict(r) for r in rows],
    }
    r95 = [float(r["r95"]) for r in rows if math.isfinite(float(r["r95"]))]
    scalars = {"inside_fraction": inside, "return": ret}
    if r95:  # the runs that took a step (a run ended at once has none)
        scalars["r95"] = float(np.mean(r95))
    return summary, scalars, (inside, ret)


HARBOUR = Evaluation("harbour", _harbour_env, run_env_episode, _harbour_summary)
STATION_KEEPING = Evaluation(
    "station-keeping", _station_env, station_keeping_episode, _station_summary
)
#: the periodic evaluation of each training env id: the Blue Lady's tracking task is judged
#: on the harbour manoeuvre of Tomera (2014) (completion without quay contact, then J_c),
#: a station-keeping task on station keeping of the same vessel and wind (the fraction of
#: time within :data:`STATION_RADIUS`, then the return)
EVALUATIONS: dict[str, Evaluation] = {
    "shipgym/BlueLadyTracking-v0": HARBOUR,
    "shipgym/StationKeeping-v0": STATION_KEEPING,
    "shipgym/BlueLadyStationKeeping-v0": STATION_KEEPING,
}


def evaluation_for(env_id: str) -> Evaluation:
    """The periodic evaluation of a training env id (:data:`EVALUATIONS`).

    Raises:
        ValueError: an id without one (train it with ``eval_freq: 0``).
    """
    try:
        return EVALUATIONS[env_id]
    except KeyError:
        raise ValueError(
            f"no periodic evaluation for {env_id!r} (evaluated ids: {', '.join(EVALUATIONS)}); "
            "train it with --eval-freq 0 (or eval_freq: 0 in the shipgym section)"
        ) from None


def _make_eval_callback(**kw: Any) -> Any:
    cb = _callbacks()

    class PeriodicEvalCallback(cb.BaseCallback):  # type: ignore[misc, name-defined]
        """Every ``eval_freq`` steps: the env id's :class:`Evaluation` of the current policy.

        Runs the deterministic policy (current ``VecNormalize`` statistics) for each seed,
        logs the evaluation's scalars as ``eval/<name>`` (harbour: ``completed_fraction``, the
        fraction completed without quay contact, ``J_c`` and ``J_c_measured``, means over the
        completed runs and left out when none completed, ``quay_contact``, ``duration_s``;
        station keeping: ``inside_fraction``, ``r95``, ``return``), appends the summary to
        ``evaluations.json`` and saves ``best_model.zip`` when the score improves (harbour:
        more runs completed, then lower mean J_c; station keeping: more time inside the
        radius, then a higher return).

        The scalars are written at once, stamped with the step the evaluation was taken at
        (a row of their own in ``progress.csv`` with ``time/total_timesteps``; TensorBoard
        events at that step), not at the next dump of the training log; a value that is not
        finite is never logged.
        """

        def __init__(
            self,
            evaluation: Evaluation,
            env: gym.Env[Any, Any],
            metadata_fn: Callable[[], ModelMetadata],
            save_fn: Callable[[Path], Path],
            eval_freq: int,
            seeds: Sequence[int],
            out_dir: Path,
        ) -> None:
            super().__init__()
            self.evaluation = evaluation
            self.env = env
            self.metadata_fn = metadata_fn
            self.save_fn = save_fn
            self.eval_freq = int(eval_freq)
            self.seeds = [int(s) for s in seeds]
            self.out_dir = out_dir
            self.evaluations: list[dict[str, Any]] = []
            self.best: tuple[float, ...] | None = None
            self._last = 0

        def _on_step(self) -> bool:
            if self.eval_freq > 0 and self.num_timesteps - self._last >= self.eval_freq:
                self._last = self.num_timesteps
                self.evaluate()
            return True

        def evaluate(self) -> dict[str, Any]:
            policy = LearnedPolicy(self.model.policy, self.metadata_fn())
            rows = [self.evaluation.episode(self.env, s, policy) for s in self.seeds]
            summary, scalars, score = self.evaluation.summarize(rows)
            summary = {
                "timesteps": int(self.num_timesteps),
                "evaluation": self.evaluation.name,
                **summary,
            }
            self.evaluations.append(summary)
            log_at_step(
                self.logger, {f"eval/{k}": v for k, v in scalars.items()}, self.num_timesteps
            )
            text = json.dumps(jsonable(self.evaluations), indent=1)
            (self.out_dir / "evaluations.json").write_text(text)
            if self.best is None or score > self.best:
                self.best = score
                self.save_fn(self.out_dir / "best_model.zip")
            return summary

    return PeriodicEvalCallback(**kw)


def log_at_step(logger: Any, scalars: Mapping[str, float], step: int) -> None:
    """Write ``scalars`` to SB3's ``logger`` now, stamped ``step`` (with
    ``time/total_timesteps``), leaving what the training has recorded since its last dump to
    that dump; values that are not finite are left out (no ``inf`` in TensorBoard)."""
    pending = (
        dict(logger.name_to_value),
        dict(logger.name_to_count),
        dict(logger.name_to_excluded),
    )
    for d in (logger.name_to_value, logger.name_to_count, logger.name_to_excluded):
        d.clear()
    try:
        for name, value in scalars.items():
            if math.isfinite(float(value)):
                logger.record(name, float(value))
        logger.record("time/total_timesteps", int(step))
        logger.dump(int(step))
    finally:
        logger.name_to_value.update(pending[0])
        logger.name_to_count.update(pending[1])
        logger.name_to_excluded.update(pending[2])


def _make_checkpoint_callback(
    save_fn: Callable[[Path], Path], freq: int, folder: Path, algo: str
) -> Any:
    cb = _callbacks()

    class ShipgymCheckpoint(cb.BaseCallback):  # type: ignore[misc, name-defined]
        """Saves a shipgym model (with normalisation statistics) every ``freq`` steps."""

        def __init__(self) -> None:
            super().__init__()
            self._last = 0

        def _on_step(self) -> bool:
            if freq > 0 and self.num_timesteps - self._last >= freq:
                self._last = self.num_timesteps
                save_fn(folder / f"{algo}_{self.num_timesteps}_steps.zip")
            return True

    return ShipgymCheckpoint()


def _make_time_limit_callback(max_seconds: float) -> Any:
    cb = _callbacks()

    class WallTimeLimit(cb.BaseCallback):  # type: ignore[misc, name-defined]
        """Stops training after ``max_seconds`` of wall-clock time."""

        def _on_training_start(self) -> None:
            self._t0 = time.perf_counter()

        def _on_step(self) -> bool:
            return time.perf_counter() - self._t0 < max_seconds

    return WallTimeLimit()


def _make_progress_callback(total: int | None = None) -> Any:
    """SB3's rich progress bar when ``rich`` is installed, else a plain tqdm bar; over
    ``total`` environment steps (:func:`planned_timesteps`: the whole rollouts the run takes,
    so that the bar ends at 100 %), by default the steps asked for."""
    cb = _callbacks()
    try:
        import rich  # noqa: F401

        class RichProgress(cb.ProgressBarCallback):  # type: ignore[misc, name-defined]
            def _on_training_start(self) -> None:  # SB3's bar, over ``total``
                from tqdm.rich import tqdm as rich_tqdm

                n = self.locals["total_timesteps"] - self.model.num_timesteps
                self.pbar = rich_tqdm(total=n if total is None else total)

        return RichProgress()
    except ImportError:
        pass

    class TqdmProgress(cb.BaseCallback):  # type: ignore[misc, name-defined]
        """A tqdm progress bar over the environment steps of this run."""

        def _on_training_start(self) -> None:
            from tqdm import tqdm

            n = self.locals["total_timesteps"] - self.model.num_timesteps
            self.pbar = tqdm(
                total=n if total is None else total, unit="step", desc="training", smoothing=0.05
            )

        def _on_step(self) -> bool:
            self.pbar.update(self.training_env.num_envs)
            return True

        def _on_training_end(self) -> None:
            self.pbar.close()

    return TqdmProgress()


#: seconds between two progress lines of ``shipgym train`` off a terminal (``--log-interval``)
LOG_INTERVAL_S = 30.0


def _clock(seconds: float) -> str:
    """``h:mm:ss``."""
    s = max(int(round(seconds)), 0)
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


def evaluation_text(summary: Mapping[str, Any] | None) -> str:
    """One line's account of a periodic evaluation (``evaluations.json``'s entry)."""
    if summary is None:
        return "no evaluation yet"
    head = f"last evaluation at {int(summary['timesteps']):,} steps: "
    if summary.get("evaluation") == "station-keeping":
        return head + (
            f"{float(summary['inside_fraction']):.1%} of the time within "
            f"{float(summary['radius_m']):g} m, mean return {float(summary['return']):.4g}"
        )
    text = head + f"completed {summary['completed']}/{summary['runs']}"
    jc = summary.get("J_c")
    if jc is not None and math.isfinite(float(jc)):
        text += f", J_c {float(jc):.3f}"
    return text


class ProgressLog:
    """Progress lines at a fixed wall-clock interval, for logs (``shipgym train > log 2>&1``).

    A daemon thread writes one line every ``interval_s`` seconds, also while the policy is
    updated or evaluated (no environment steps then): the steps so far of ``planned``, the
    steps per second of this run, the elapsed and the estimated remaining time, and the last
    periodic evaluation (:func:`evaluation_text`); a last line when it is stopped.

    Args:
        model: the SB3 model (``num_timesteps`` is read).
        planned: the environment steps this run ends at (:func:`planned_timesteps`, plus a
            resumed run's).
        interval_s: seconds between lines (> 0).
        label: the line's head (``shipgym train ppo, seed 0``).
        last_evaluation: ``() -> summary or None``; ``None``: no evaluation in this run.
        stream: where the lines go (default: stderr, as the progress bar).
    """

    def __init__(
        self,
        model: Any,
        planned: int,
        interval_s: float,
        label: str,
        last_evaluation: Callable[[], Mapping[str, Any] | None] | None = None,
        stream: Any = None,
    ) -> None:
        import threading

        self.model = model
        self.planned = int(planned)
        self.interval_s = check_log_interval(interval_s)
        self.label = label
        self.last_evaluation = last_evaluation
        self.stream = stream
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="shipgym-progress", daemon=True)
        self._t0 = 0.0
        self._start_steps = 0

    def start(self) -> ProgressLog:
        self._t0 = time.perf_counter()
        self._start_steps = int(self.model.num_timesteps)
        self._thread.start()
        return self

    def line(self) -> str:
        """The progress line now."""
        done = int(self.model.num_timesteps)
        elapsed = time.perf_counter() - self._t0
        fps = (done - self._start_steps) / elapsed if elapsed > 0 else 0.0
        share = done / self.planned if self.planned > 0 else 1.0
        text = (
            f"{self.label}: {done:,}/{self.planned:,} steps ({share:.1%}), {fps:,.0f} fps, "
            f"{_clock(elapsed)} elapsed"
        )
        if fps > 0 and done < self.planned:
            text += f", ~{_clock((self.planned - done) / fps)} left"
        if self.last_evaluation is not None:
            text += f"; {evaluation_text(self.last_evaluation())}"
        return text

    def _write(self) -> None:
        stream = sys.stderr if self.stream is None else self.stream
        print(self.line(), file=stream, flush=True)

    def _run(self) -> None:
        while not self._stop.wait(self.interval_s):
            self._write()

    def stop(self) -> None:
        """Stop the thread and write the last line (once)."""
        if self._thread.is_alive():
            self._stop.set()
            self._thread.join()
            self._write()


def check_log_interval(interval_s: Any) -> float:
    """A progress-line interval: a finite number of seconds > 0."""
    if (
        isinstance(interval_s, bool)
        or not isinstance(interval_s, int | float)
        or not (math.isfinite(interval_s) and interval_s > 0)
    ):
        raise ValueError(
            f"the progress-line interval must be a finite number of seconds > 0, got "
            f"{interval_s!r} (at most {LOG_INTERVAL_S:g} s keeps a log line at least every "
            "minute)"
        )
    return float(interval_s)


def planned_timesteps(algo: str, hp: Mapping[str, Any], timesteps: int) -> tuple[int, int]:
    """The environment steps a run of ``timesteps`` takes, and the steps of one collection.

    Stable-Baselines3 collects whole rollouts until the steps asked for are reached: PPO
    ``n_steps * n_envs`` steps at a time, SAC ``train_freq * n_envs`` (a ``train_freq`` in
    episodes: not known ahead, the steps asked for are returned). So ``--timesteps 20000``
    with 16 envs of 2048 steps trains 32,768 steps.

    Args:
        algo: ``"ppo"`` or ``"sac"``.
        hp: the run's hyperparameters (``n_envs``, ``n_steps``, ``train_freq``).
        timesteps: the steps asked for (this run's, a resumed run's included).
    """
    n_envs = int(hp.get("n_envs", 1) or 1)
    if algo == "ppo":
        per = int(hp.get("n_steps", 2048) or 2048) * n_envs
    else:
        freq = hp.get("train_freq", 1)
        k, unit = (freq[0], str(freq[1])) if isinstance(freq, list | tuple) else (freq, "step")
        if unit != "step":
            return int(timesteps), 0
        per = int(k) * n_envs
    per = max(per, 1)
    return -(-int(timesteps) // per) * per, per


def rounding_notice(algo: str, hp: Mapping[str, Any], timesteps: int) -> str | None:
    """One line when the steps asked for are not a whole number of collections
    (:func:`planned_timesteps`), saying what the run trains instead; ``None`` otherwise."""
    planned, per = planned_timesteps(algo, hp, timesteps)
    if planned == timesteps:
        return None
    n_envs = int(hp.get("n_envs", 1) or 1)
    if algo == "ppo":
        what = f"n_steps {int(hp.get('n_steps', 2048) or 2048):,} x n_envs {n_envs:,}"
    else:
        freq = hp.get("train_freq", 1)
        what = f"train_freq {freq[0] if isinstance(freq, list | tuple) else freq} x n_envs {n_envs}"
    return (
        f"shipgym train: note: the budget of {timesteps:,} timesteps is rounded up to "
        f"{planned:,}, a whole number of rollouts of {per:,} steps ({what})"
    )


# ---- logging ---------------------------------------------------------------------------------
#: what ``train`` says once when TensorBoard logging is off because the package is missing
TENSORBOARD_NOTE = (
    "shipgym train: the tensorboard package is not installed: training curves go to "
    "progress.csv only (pip install tensorboard, part of the rl extra, to log to OUT/tb)"
)


def _tensorboard_dir(out_dir: Path, enabled: bool | None) -> Path | None:
    """``OUT/tb`` when TensorBoard logging is on (``None``: when the package is installed)."""
    import importlib.util

    if enabled is False:
        return None
    if importlib.util.find_spec("tensorboard") is None:
        if enabled:
            raise ImportError(
                "tensorboard=True needs the tensorboard package: pip install tensorboard"
            )
        print(TENSORBOARD_NOTE, file=sys.stderr)
        return None
    return out_dir / "tb"


def _logger(out_dir: Path, tb_dir: Path | None, verbose: int) -> Any:
    """SB3's logger: ``progress.csv`` in ``out_dir``, TensorBoard events in ``tb_dir``, the
    console with ``verbose``."""
    from stable_baselines3.common.logger import Logger, make_output_format

    formats = [make_output_format("csv", str(out_dir))]
    if tb_dir is not None:
        formats.append(make_output_format("tensorboard", str(tb_dir)))
    if verbose:
        formats.append(make_output_format("stdout", str(out_dir)))
    return Logger(folder=str(out_dir), output_formats=formats)


# ---- training --------------------------------------------------------------------------------
@dataclass
class TrainResult:
    """What :func:`train` produced.

    Attributes:
        model_path: the final model (``OUT/model.zip``).
        best_model_path: the best periodic evaluation's model, if evaluation ran.
        out_dir: the output folder.
        metadata: the final model's metadata.
        num_timesteps: environment steps trained in total (including a resumed run's).
        wall_time_s: wall-clock time of the training (s).
        evaluations: the periodic evaluations (see ``evaluations.json``).
        model: the trained SB3 model (in memory).
        vec_normalize: its ``VecNormalize`` (closed; statistics still readable), or ``None``.
    """

    model_path: Path
    best_model_path: Path | None
    out_dir: Path
    metadata: ModelMetadata
    num_timesteps: int
    wall_time_s: float
    evaluations: list[dict[str, Any]] = field(default_factory=list)
    model: Any = field(default=None, repr=False)
    vec_normalize: Any = field(default=None, repr=False)


def train(
    algo: str,
    *,
    timesteps: int | None = None,
    seed: int = 0,
    n_envs: int | None = None,
    out: str | Path | None = None,
    resume: str | Path | None = None,
    residual: bool = False,
    observer: str | None = None,
    env_id: str = DEFAULT_ENV_ID,
    hyperparams: str | Path | None = None,
    overrides: Mapping[str, Any] | None = None,
    eval_freq: int | None = None,
    eval_seeds: Sequence[int] | None = None,
    checkpoint_freq: int | None = None,
    vec_env: str | None = None,
    max_minutes: float | None = None,
    progress: bool = True,
    deterministic: bool = True,
    verbose: int = 0,
    tensorboard: bool | None = None,
    log_interval_s: float | None = LOG_INTERVAL_S,
) -> TrainResult:
    """Train a PPO or SAC controller; the function behind ``shipgym train``.

    Args:
        algo: ``"ppo"`` or ``"sac"``.
        timesteps: environment steps of this run (all envs together); default the YAML's
            ``n_timesteps``. With ``resume`` the steps are added to the checkpoint's.
        seed: seed of everything (envs ``seed + i``, torch, numpy, sensor randomisation).
        n_envs: parallel environments (default: YAML).
        out: output folder (default ``runs/train/<algo>[-residual]-seed<seed>``).
        resume: a checkpoint or model (shipgym model zip) to continue; its metadata decides
            the task, observer and residual setup. Nothing is unpickled
            (:func:`restore_model_state`).
        residual: learn a residual on top of the YAML's ``controller`` (the tuned PID).
        observer: ``"truth"``, ``"kbf"``, ... (default: YAML, ``kbf``).
        env_id: training env id (a block of that name must exist in the YAML); the periodic
            evaluation follows it (:data:`EVALUATIONS`: the harbour manoeuvre for the Blue
            Lady's tracking task, station keeping for a station-keeping task).
        hyperparams: another YAML file in the same layout.
        overrides: hyperparameters replacing the YAML's (plain data, merged).
        eval_freq: steps between periodic evaluations (default YAML; 0 disables).
        eval_seeds: episode seeds of each evaluation (default YAML, ``[100, 101]``).
        checkpoint_freq: steps between checkpoints (default YAML; 0 disables).
        vec_env: ``"dummy"``, ``"subproc"`` or ``"batched"`` (the native batched env,
            :mod:`shipgym.rl.vec`) (default YAML).
        max_minutes: stop after this wall-clock time (the model so far is saved).
        progress: show a progress bar.
        log_interval_s: without the bar (``progress=False``: off a terminal, or in a worker
            of :func:`train_seeds`), a progress line on stderr every this many seconds of
            wall-clock time (:class:`ProgressLog`: steps, fps, the last evaluation);
            default :data:`LOG_INTERVAL_S`; ``None``: none.
        deterministic: single thread, deterministic torch algorithms (see module docstring).
        verbose: SB3 verbosity (1 prints the training log).
        tensorboard: log to ``OUT/tb`` for TensorBoard as well as to ``progress.csv``
            (the training curves and the evaluation scalars); ``None`` (default): when the
            ``tensorboard`` package is installed, else a one-line note.

    Returns:
        A :class:`TrainResult`.
    """
    from stable_baselines3.common.vec_env import VecNormalize

    cls = algorithm_class(algo)
    resume_meta = read_metadata(resume) if resume is not None else None
    if resume_meta is not None:
        # a registered shipgym id only: Gymnasium imports the module a "module:Name-v0" id names
        check_trained_env(resume_meta, resume)
        if resume_meta.algorithm != algo:
            raise ValueError(f"{resume} holds a {resume_meta.algorithm} model, not {algo}")
        hp = copy.deepcopy(dict(resume_meta.hyperparams))
        env_id = resume_meta.env_id
        residual = bool(hp.get("residual"))
        if overrides:
            hp = _merge(hp, overrides)
        where = f"{resume}: {METADATA_NAME} hyperparams"
        _check_algo_args(algo, hp, where=where)
        check_hyperparams(algo, hp, where=where)
    else:
        hp = load_hyperparams(
            algo, env_id, residual=residual, path=hyperparams, overrides=overrides
        )
    if observer is not None:
        hp["observer"] = None if observer == "truth" else observer
    hp["observer"] = check_observer(hp.get("observer"))
    _check_train_args(seed=seed, n_envs=n_envs, max_minutes=max_minutes, timesteps=timesteps)
    if log_interval_s is not None:
        check_log_interval(log_interval_s)
    if n_envs is not None:
        hp["n_envs"] = int(n_envs)
    if vec_env is not None:
        hp["vec_env"] = vec_env
    for key, val in (("eval_freq", eval_freq), ("checkpoint_freq", checkpoint_freq)):
        if val is not None:
            hp[key] = int(val)
    if eval_seeds is not None:
        hp["eval_seeds"] = list(eval_seeds)
    n_steps = int(timesteps if timesteps is not None else hp.get("n_timesteps", 100_000))
    if n_steps < 1:
        raise ValueError(f"timesteps must be >= 1, got {n_steps}")
    hp["n_timesteps"] = n_steps
    check_hyperparams(algo, hp, where="train")  # again, with the arguments applied
    n = int(hp.get("n_envs", 1))
    out_dir = Path(
        out
        if out is not None
        else Path("runs", "train", f"{algo}{'-residual' * residual}-seed{seed}")
    )
    out_dir.mkdir(parents=True, exist_ok=True)
    command = train_command(
        algo, timesteps=n_steps, seed=seed, n_envs=n, out=out_dir, residual=residual,
        observer=hp["observer"], resume=resume, max_minutes=max_minutes, env_id=env_id,
        hyperparams=hyperparams,
    )  # fmt: skip
    evaluation = evaluation_for(env_id) if int(hp.get("eval_freq", 0) or 0) > 0 else None
    tb_dir = _tensorboard_dir(out_dir, tensorboard)
    if deterministic:
        set_deterministic(seed)

    venv = build_vec_env(env_id, hp, n, seed, str(hp.get("vec_env", "dummy")))
    norm = hp.get("normalize")
    if norm:
        norm_kw = dict(norm) if isinstance(norm, Mapping) else {}
        norm_kw.setdefault("gamma", float(hp.get("gamma", 0.99)))
        venv = VecNormalize(venv, **norm_kw)
        if resume_meta is not None and resume_meta.normalization is not None:
            resume_meta.normalization.apply_to(venv)
    model = cls(
        hp.get("policy", "MlpPolicy"), venv, seed=seed, device="cpu", verbose=verbose,
        **_algo_kwargs(algo, hp),
    )  # fmt: skip
    if resume is not None:
        assert resume_meta is not None
        restore_model_state(model, resume, resume_meta)
    model.set_logger(_logger(out_dir, tb_dir, verbose))

    t_start = time.perf_counter()

    def metadata_fn(extra: Mapping[str, Any] | None = None) -> ModelMetadata:
        return _metadata(algo, env_id, hp, model, venv, seed=seed, command=command, extra=extra)

    def save_fn(path: Path) -> Path:
        extra = {"wall_time_s": time.perf_counter() - t_start}
        return save_model(model, path, metadata_fn(extra))

    cbs: list[Any] = []
    eval_cb = None
    if evaluation is not None:
        eval_cb = _make_eval_callback(
            evaluation=evaluation, env=evaluation.build(env_id, hp), metadata_fn=metadata_fn,
            save_fn=save_fn,
            eval_freq=int(hp["eval_freq"]), seeds=hp.get("eval_seeds", [100, 101]),
            out_dir=out_dir,
        )  # fmt: skip
        cbs.append(eval_cb)
    if int(hp.get("checkpoint_freq", 0) or 0) > 0:
        cbs.append(
            _make_checkpoint_callback(
                save_fn, int(hp["checkpoint_freq"]), out_dir / "checkpoints", algo
            )
        )
    if max_minutes is not None:
        cbs.append(_make_time_limit_callback(60.0 * float(max_minutes)))
    planned, _ = planned_timesteps(algo, hp, n_steps)
    notice = rounding_notice(algo, hp, n_steps)
    if notice is not None:
        print(notice, file=sys.stderr)
    if progress:
        cbs.append(_make_progress_callback(planned))
    _write_config(out_dir, hp, command, algo=algo, seed=seed, env_id=env_id, resume=resume)

    lines = None
    if not progress and log_interval_s is not None:
        lines = ProgressLog(
            model,
            planned + (int(model.num_timesteps) if resume is not None else 0),
            log_interval_s,
            f"shipgym train {algo}, seed {seed}",
            (lambda: eval_cb.evaluations[-1] if eval_cb.evaluations else None)
            if eval_cb is not None
            else None,
        ).start()
    try:
        model.learn(
            total_timesteps=n_steps,
            callback=cbs or None,
            reset_num_timesteps=resume is None,
            progress_bar=False,
        )
        wall = time.perf_counter() - t_start
        if eval_cb is not None and eval_cb._last != model.num_timesteps:
            eval_cb.evaluate()  # logged at its step
            model.logger.dump(model.num_timesteps)  # what the last update recorded
    finally:
        if lines is not None:
            lines.stop()
    final = save_model(model, out_dir / "model.zip", metadata_fn({"wall_time_s": wall}))
    best = out_dir / "best_model.zip"
    model.logger.close()  # flushes and closes progress.csv
    venv.close()
    return TrainResult(
        model_path=final,
        best_model_path=best if best.is_file() else None,
        out_dir=out_dir,
        metadata=read_metadata(final),
        num_timesteps=int(model.num_timesteps),
        wall_time_s=wall,
        evaluations=list(eval_cb.evaluations) if eval_cb is not None else [],
        model=model,
        vec_normalize=venv if isinstance(venv, VecNormalize) else None,
    )


def train_seeds(
    algo: str,
    seeds: Sequence[int],
    *,
    out: str | Path | None = None,
    executor: Any = None,
    workers: int | None = None,
    progress: bool = True,
    **kwargs: Any,
) -> list[dict[str, Any]]:
    """:func:`train` once per seed, in parallel: a process pool or Ray tasks.

    Each run is :func:`train` with that seed (single-threaded and deterministic), written to
    ``out/seed<S>`` (default: each run's own default folder), so the results depend on the
    seeds only and every executor gives the same models.

    Args:
        algo: ``"ppo"`` or ``"sac"``.
        seeds: distinct seeds (>= 0).
        out: parent folder of the runs.
        executor: ``"process"`` (default), ``"ray"`` or a :class:`shipgym.bench.Executor`
            (Ray: a local instance of ``workers`` CPUs, or a cluster address).
        workers: parallel runs (default: one per seed, at most the CPUs).
        progress: a bar over the runs (on a terminal).
        **kwargs: the other arguments of :func:`train` (not ``seed``, ``out``, ``progress``).

    Returns:
        One summary per seed, in the order of ``seeds``: ``seed``, ``model_path``,
        ``out_dir``, ``num_timesteps``, ``wall_time_s``, ``evaluations``.
    """
    from shipgym.bench import run_jobs

    seeds = [int(s) for s in seeds]
    if not seeds or len(set(seeds)) != len(seeds) or min(seeds) < 0:
        raise ValueError(f"seeds must be distinct integers >= 0, got {seeds!r}")
    bad = sorted({"seed", "out", "progress"} & set(kwargs))
    if bad:
        raise TypeError(f"train_seeds takes the seeds and out itself; drop {bad}")
    jobs = [
        dict(kwargs, algo=algo, seed=s, out=None if out is None else str(Path(out) / f"seed{s}"))
        for s in seeds
    ]
    return run_jobs(_train_job, jobs, workers=workers, progress=progress, desc="training runs",
                    executor=executor)  # fmt: skip


def _train_job(job: dict[str, Any]) -> dict[str, Any]:
    """One run of :func:`train_seeds` (module level: picklable for workers and Ray)."""
    job = dict(job)
    algo = job.pop("algo")
    res = train(algo, progress=False, **job)
    return {
        "seed": job["seed"],
        "model_path": str(res.model_path),
        "out_dir": str(res.out_dir),
        "num_timesteps": res.num_timesteps,
        "wall_time_s": res.wall_time_s,
        "evaluations": res.evaluations,
    }


def _check_train_args(*, seed: Any, n_envs: Any, max_minutes: Any, timesteps: Any) -> None:
    """The arguments of :func:`train` that the CLI validates too (API users get the same)."""
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed must be an int >= 0, got {seed!r}")
    lo, hi = HP_INT_BOUNDS["n_envs"]
    if n_envs is not None and (
        isinstance(n_envs, bool) or not isinstance(n_envs, int) or not lo <= n_envs <= hi
    ):
        raise ValueError(f"n_envs must be an int from {lo} to {hi}, got {n_envs!r}")
    if max_minutes is not None and not (
        isinstance(max_minutes, int | float) and math.isfinite(max_minutes) and max_minutes > 0
    ):
        raise ValueError(f"max_minutes must be a finite number > 0, got {max_minutes!r}")
    lo, hi = HP_INT_BOUNDS["n_timesteps"]
    if timesteps is not None and (
        isinstance(timesteps, bool) or not isinstance(timesteps, int) or not lo <= timesteps <= hi
    ):
        raise ValueError(f"timesteps must be an int from {lo} to {hi}, got {timesteps!r}")


def restore_model_state(model: Any, path: str | Path, meta: ModelMetadata) -> None:
    """Put a saved model's weights, optimizer states and step count into a fresh ``model``.

    ``model`` is built from the hyperparameters in ``meta`` (same algorithm, policy and
    spaces); the states come from :func:`shipgym.controllers.learned.read_state_dicts`
    (``torch.load(weights_only=True)``: no unpickling), so resuming from a file is as safe as
    running it as a controller. SAC's entropy coefficient comes from ``pytorch_variables``.

    Raises:
        ValueError: the file's states do not fit the model (one line).
    """
    import torch as th
    from stable_baselines3.common.save_util import recursive_setattr

    states = read_state_dicts(path)
    variables = states.pop("pytorch_variables", {})
    needed, var_names = model._get_torch_save_params()
    missing = sorted(set(needed) - set(states))
    extra = sorted(set(states) - set(needed))
    if missing or extra:
        raise ValueError(
            f"{path}: its states do not fit a {meta.algorithm} model of its metadata "
            f"(missing {missing}, unexpected {extra})"
        )
    try:
        model.set_parameters(states, exact_match=True, device="cpu")
    except (RuntimeError, ValueError, KeyError, TypeError) as exc:
        first = " ".join(str(exc).split())[:300]
        raise ValueError(f"{path}: its weights do not fit its metadata: {first}") from None
    unknown = sorted(set(variables) - set(var_names))
    if unknown:
        raise ValueError(f"{path}: unexpected pytorch variables {unknown}")
    for name in var_names:
        val = variables.get(name)
        if val is None:
            continue
        target = getattr(model, name, None)
        if not isinstance(val, th.Tensor) or not isinstance(target, th.Tensor):
            raise ValueError(f"{path}: pytorch variable {name!r} is not a tensor")
        if val.shape != target.shape:
            raise ValueError(f"{path}: pytorch variable {name!r} has shape {tuple(val.shape)}")
        recursive_setattr(model, f"{name}.data", val.data)
    model.num_timesteps = int(meta.num_timesteps)


def _write_config(out_dir: Path, hp: Mapping[str, Any], command: str, **args: Any) -> None:
    """``config.yml``, ``args.yml`` and ``command.txt`` next to the model (as the zoo does)."""
    (out_dir / "config.yml").write_text(yaml.safe_dump(dict(hp), sort_keys=True))
    plain = {k: (str(v) if isinstance(v, Path) else v) for k, v in args.items()}
    (out_dir / "args.yml").write_text(yaml.safe_dump(plain, sort_keys=True))
    (out_dir / "command.txt").write_text(command + "\n")


def reproduction_hyperparams(model: str | Path) -> tuple[ModelMetadata, Path | None]:
    """The metadata of the model zip ``model`` and the hyperparameter file its ``reproduce``
    record names (``reproduce.hyperparams``, a file of ``shipgym/rl/hyperparams``; None: the
    algorithm's shipped file), checked to resolve to the hyperparameters the model was trained
    with, the total steps (``n_timesteps``, which ``--timesteps`` sets) apart: a file edited
    since would train another policy.

    Raises:
        ValueError: no ``reproduce`` record or seed, an unknown file, or a file that resolves
            to other hyperparameters than the model's (the keys that differ are named).
    """
    meta = read_metadata(model)
    rep = meta.extra.get("reproduce")
    name = Path(model).name
    if not rep or meta.seed is None:
        raise ValueError(f"{name}: its metadata has no reproduce record and seed to re-run")
    path = packaged_hyperparams(rep["hyperparams"]) if "hyperparams" in rep else None
    hp = load_hyperparams(meta.algorithm, meta.env_id, residual=meta.residual, path=path)
    trained = dict(meta.hyperparams)
    differ = sorted(k for k in set(hp) | set(trained)
                    if k != "n_timesteps" and hp.get(k) != trained.get(k))  # fmt: skip
    if differ:
        where = path.name if path is not None else hyperparams_path(meta.algorithm).name
        raise ValueError(
            f"{name}: {where} resolves to other hyperparameters than the model was trained with "
            f"({', '.join(differ)}): the re-run would train another policy"
        )
    return meta, path


def reproduction_run(model: str | Path, out: str | Path, steps: int | None = None) -> Path:
    """Re-run the documented training command of the model zip ``model`` up to the checkpoint
    of its ``reproduce`` record (or ``steps``) and return that checkpoint (in
    ``out/checkpoints``).

    The run is the model's algorithm, env id, seed and residual setup with the hyperparameter
    file of :func:`reproduction_hyperparams` (its ``n_envs``), periodic evaluation off (it
    draws nothing from the training's random streams: a run with it gives the same weights)
    and one checkpoint at ``steps`` (default ``reproduce.checkpoint_steps``). On a CPU the
    record holds (``cpu_identity``) the checkpoint's fingerprints are the recorded ones bit for
    bit (``tests/test_baseline_reproduction.py``, ``tools/rerecord_baselines.py``); where the
    record says ``shipped_reproduces``, the run to the model's own ``num_timesteps`` gives the
    shipped file's weights and statistics on its CPU (``cpu``).

    Raises:
        ValueError: as :func:`reproduction_hyperparams`; ``steps`` below 1.
    """
    meta, path = reproduction_hyperparams(model)
    steps = int(meta.extra["reproduce"]["checkpoint_steps"] if steps is None else steps)
    if steps < 1:
        raise ValueError(f"steps must be at least 1, got {steps}")
    train(meta.algorithm, env_id=meta.env_id, seed=int(meta.seed), timesteps=steps,
          residual=meta.residual, hyperparams=path, out=out, eval_freq=0,
          checkpoint_freq=steps, progress=False)  # fmt: skip
    return Path(out) / "checkpoints" / f"{meta.algorithm}_{steps}_steps.zip"
