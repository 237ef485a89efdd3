"""Two-way interop with plain stable-baselines3 and rl-zoo3: ``vecnormalize.pkl`` files.

shipgym -> SB3: every model ``shipgym train`` saves is an SB3 zip plus ``shipgym.json``;
:func:`save_vecnormalize` writes the same observation statistics as SB3's ``VecNormalize``
file next to it (:func:`vecnormalize_path`), so that ``VecNormalize.load(path, venv)`` and
``PPO.load(zip)`` give the actions shipgym's own loader gives.

SB3 / rl-zoo3 -> shipgym: a model without ``shipgym.json`` (``PPO.save`` / ``SAC.save``, or
rl-zoo3's ``logs/<algo>/<ENV>_<N>/<ENV>.zip``) is described by :class:`Sb3Model`: the algorithm
(``ppo:PATH``, ``sac:PATH``), the env id it was trained on with its keyword arguments, the
observer / DP controller / error-integral stack and its ``vecnormalize.pkl``.
:func:`find_sb3_model` reads them from the files next to the zip (rl-zoo3's layout:
``args.yml`` with ``env`` and ``env_kwargs``, ``config.yml`` with ``env_wrapper`` and
``env_kwargs``, ``vecnormalize.pkl``; a plain SB3 user writes the same files, see
docs/tutorials/train-ppo.md), :func:`import_sb3_model` adds ``shipgym.json`` to a copy of the
zip, and :func:`resolve_controller` does both for ``shipgym run`` and ``shipgym bench
controllers``.

Nothing is unpickled: ``vecnormalize.pkl`` is read by :func:`read_vecnormalize` with an
unpickler that builds numpy arrays only and records every other object as plain attributes
(any class outside :data:`_PICKLE_STUBS` is refused); the zip's ``data`` is read as the JSON
SB3 writes, the weights with ``torch.load(weights_only=True)`` (shipgym's model loader).
"""

from __future__ import annotations

import copy
import hashlib
import io
import math
import os
import pickle
import re
import shutil
import sys
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from shipgym.controllers.learned import (
    ALGORITHMS,
    METADATA_NAME,
    POLICY_KWARGS,
    ModelMetadata,
    ObsNormalization,
    is_learned_controller,
    write_metadata,
)

#: the wrapper that puts an observer into the loop (``env_wrapper`` in a block)
OBSERVER_WRAPPER = "shipgym.observers.wrapper.ObserverWrapper"
#: the wrapper that appends the leaky integral of the observed errors (after the observer)
INTEGRAL_WRAPPER = "shipgym.envs.integral.ErrorIntegralObservation"

__all__ = [
    "INTEGRAL_WRAPPER",
    "OBSERVER_WRAPPER",
    "VECNORMALIZE_NAME",
    "Sb3Model",
    "find_sb3_model",
    "import_sb3_model",
    "is_sb3_model",
    "parse_env_wrapper",
    "read_vecnormalize",
    "resolve_controller",
    "save_vecnormalize",
    "vecnormalize_path",
]

#: SB3's and rl-zoo3's file name of the ``VecNormalize`` statistics
VECNORMALIZE_NAME = "vecnormalize.pkl"
#: largest ``vecnormalize.pkl`` read (a 64-env run's is about 12 kB: statistics, spaces and the
#: last observation of each env)
MAX_VECNORMALIZE_BYTES = 16 << 20


# ---- shipgym -> SB3 --------------------------------------------------------------------------
def vecnormalize_path(model_path: str | Path) -> Path:
    """The ``VecNormalize`` file of a model: ``vecnormalize.pkl`` next to ``model.zip`` (rl-zoo3's
    and SB3's usual name), ``<stem>_vecnormalize.pkl`` next to any other ``<stem>.zip``
    (``best_model_vecnormalize.pkl``, ``checkpoints/ppo_1000_steps_vecnormalize.pkl``)."""
    p = Path(model_path)
    stem = p.stem if p.suffix == ".zip" else p.name
    name = VECNORMALIZE_NAME if stem == "model" else f"{stem}_{VECNORMALIZE_NAME}"
    return p.with_name(name)


def save_vecnormalize(
    norm: ObsNormalization, path: str | Path, observation_space: Any, action_space: Any
) -> Path:
    """Write ``norm`` as SB3's ``VecNormalize`` file (``pickle`` of a ``VecNormalize``).

    The file holds exactly the statistics of ``shipgym.json`` (:class:`ObsNormalization`:
    observation mean and variance and their count, ``epsilon``, ``clip_obs``, ``norm_obs``,
    ``norm_reward``, ``clip_reward``, ``gamma``, the return statistics), with
    ``training=True`` as SB3 saves it during training; for evaluation set ``training = False``
    and ``norm_reward = False`` after ``VecNormalize.load(path, venv)``.

    Args:
        norm: the statistics.
        path: the ``.pkl`` to write.
        observation_space, action_space: the spaces the policy was trained on (the shapes are
            what ``VecNormalize.load`` checks against its ``venv``).
    """
    import gymnasium as gym
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    n = len(norm.mean)
    if tuple(observation_space.shape) != (n,):
        raise ValueError(
            f"the normalisation has {n} entries, the observation space shape "
            f"{observation_space.shape}"
        )

    class _Spaces(gym.Env):  # type: ignore[type-arg]
        """The spaces only (VecNormalize needs a venv to be built; it is not pickled)."""

        def __init__(self) -> None:
            self.observation_space = observation_space
            self.action_space = action_space

    venv = DummyVecEnv([_Spaces])
    vn = VecNormalize(
        venv, training=True, norm_obs=norm.norm_obs, norm_reward=norm.norm_reward,
        clip_obs=norm.clip_obs, clip_reward=norm.clip_reward, gamma=norm.gamma,
        epsilon=norm.epsilon,
    )  # fmt: skip
    norm.apply_to(vn)
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    vn.save(str(p))
    return p


# ---- reading vecnormalize.pkl without unpickling objects ------------------------------------
class _Record:
    """What an object of an allowed class becomes: its pickled state as attributes."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.__dict__["_args"] = args

    def __setstate__(self, state: Any) -> None:
        if isinstance(state, tuple) and len(state) == 2 and isinstance(state[0], dict | None):
            state = state[0] or {}
        if isinstance(state, dict):
            self.__dict__.update({str(k): v for k, v in state.items()})
        else:
            self.__dict__["_state"] = state


#: globals of a ``VecNormalize`` pickle that become :class:`_Record` s (no code of theirs runs);
#: numpy's array reconstruction is the only real code called (:func:`_numpy_global`), and
#: numpy's random generators (of the pickled spaces) are records too
_PICKLE_STUBS = {
    ("stable_baselines3.common.vec_env.vec_normalize", "VecNormalize"),
    ("stable_baselines3.common.running_mean_std", "RunningMeanStd"),
    ("gymnasium.spaces.box", "Box"),
    ("gymnasium.spaces.discrete", "Discrete"),
    ("gym.spaces.box", "Box"),
    ("collections", "OrderedDict"),
}


def _numpy_global(module: str, name: str) -> Any:
    """numpy's own array pickling: ``numpy.dtype``, ``numpy.ndarray`` and the
    ``multiarray._reconstruct`` / ``scalar`` helpers (``None`` for anything else)."""
    if module == "numpy" and name in ("dtype", "ndarray"):
        return getattr(np, name)
    if module in ("numpy.core.multiarray", "numpy._core.multiarray") and name in (
        "_reconstruct",
        "scalar",
    ):
        try:
            import numpy._core.multiarray as ma  # numpy >= 2
        except ImportError:  # pragma: no cover - numpy 1
            import numpy.core.multiarray as ma
        return getattr(ma, name)
    return None


class _StatsUnpickler(pickle.Unpickler):
    def find_class(self, module: str, name: str) -> Any:
        real = _numpy_global(module, name)
        if real is not None:
            return real
        if (module, name) in _PICKLE_STUBS or module.startswith("numpy.random"):
            return _Record
        raise pickle.UnpicklingError(
            f"it refers to {module}.{name}, which a VecNormalize file does not hold"
        )


def read_vecnormalize(path: str | Path) -> ObsNormalization:
    """The statistics of an SB3 ``VecNormalize`` file (``VecNormalize.save``), unpickling nothing
    but numpy arrays (see the module docstring).

    Raises:
        FileNotFoundError: no such file.
        ValueError: not a ``VecNormalize`` file, one of a dict observation space, or
            statistics that are not finite.
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"VecNormalize file {str(p)!r} does not exist")
    size = p.stat().st_size
    if size > MAX_VECNORMALIZE_BYTES:
        raise ValueError(f"{p}: {size:,} bytes, more than a VecNormalize file has")
    try:
        obj = _StatsUnpickler(io.BytesIO(p.read_bytes())).load()
    except Exception as exc:  # noqa: BLE001 - a malformed pickle raises many kinds
        raise ValueError(
            f"{p} is not a stable-baselines3 VecNormalize file (VecNormalize.save): "
            f"{type(exc).__name__}: {str(exc)[:200]}"
        ) from None
    state = getattr(obj, "__dict__", {})
    need = ("obs_rms", "ret_rms", "clip_obs", "clip_reward", "gamma", "epsilon", "norm_obs",
            "norm_reward")  # fmt: skip
    missing = [k for k in need if k not in state]
    if not isinstance(obj, _Record) or missing:
        raise ValueError(
            f"{p} is not a stable-baselines3 VecNormalize file (VecNormalize.save): missing "
            f"{missing or 'the VecNormalize object'}"
        )
    obs_rms, ret_rms = state["obs_rms"], state["ret_rms"]
    if isinstance(obs_rms, dict):
        raise ValueError(f"{p}: normalises a dict observation; shipgym observations are vectors")

    def arr(x: Any, what: str) -> np.ndarray:
        a = np.asarray(getattr(x, what, None), dtype=float)
        if a.dtype == object or not np.all(np.isfinite(a)):
            raise ValueError(f"{p}: {what} of the statistics is not finite numbers")
        return a

    mean, var = arr(obs_rms, "mean"), arr(obs_rms, "var")
    if mean.ndim != 1 or mean.shape != var.shape:
        raise ValueError(f"{p}: observation mean {mean.shape} and var {var.shape} do not match")
    try:
        return ObsNormalization(
            mean=tuple(mean.tolist()),
            var=tuple(var.tolist()),
            count=float(arr(obs_rms, "count")),
            epsilon=float(state["epsilon"]),
            clip_obs=float(state["clip_obs"]),
            norm_obs=bool(state["norm_obs"]),
            norm_reward=bool(state["norm_reward"]),
            clip_reward=float(state["clip_reward"]),
            gamma=float(state["gamma"]),
            ret_mean=float(arr(ret_rms, "mean")),
            ret_var=float(arr(ret_rms, "var")),
            ret_count=float(arr(ret_rms, "count")),
        )
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{p}: {exc}") from None


# ---- SB3 / rl-zoo3 -> shipgym ---------------------------------------------------------------
@dataclass(frozen=True)
class Sb3Model:
    """A stable-baselines3 model without ``shipgym.json`` and what shipgym needs to run it.

    Attributes:
        path: the SB3 zip (``model.save``).
        algorithm: ``"ppo"`` or ``"sac"`` (from the controller name ``ppo:PATH``).
        env_id: the shipgym env id it was trained on (a registered id, e.g.
            ``shipgym/StationKeeping-v0``); the vessel check and the results use it.
        env_kwargs: the env's keyword arguments in training (``vessel=`` decides the vessel
            the policy may drive; the rest documents the training conditions).
        observer: the observer in the training loop (``None``: the truth; ``kbf`` ...), from
            ``env_kwargs['observer']`` or rl-zoo3's ``env_wrapper`` (``ObserverWrapper``).
        controller: for a residual policy, the DP controller under it (``env_kwargs
            ['controller']``, e.g. ``pid``); ``None``: the policy drives the thrusters.
        residual_scale: factor on the residual actions (-; ``env_kwargs['residual_scale']``).
        error_integral: time constant (s) of the error integral appended to the observation
            (``ErrorIntegralObservation`` in ``env_wrapper``), or ``None``.
        vecnormalize: its ``vecnormalize.pkl``, or ``None`` (trained without ``VecNormalize``).
        sources: where each came from (for messages and the results).
    """

    path: Path
    algorithm: str
    env_id: str
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    observer: str | None = None
    controller: str | None = None
    residual_scale: float = 1.0
    error_integral: float | None = None
    vecnormalize: Path | None = None
    sources: dict[str, str] = field(default_factory=dict)


#: what a model without shipgym.json needs, for the error messages
NEEDS = (
    "an SB3 model without shipgym.json needs, next to the zip (rl-zoo3 writes them in "
    "<zip folder>/<ENV>/): args.yml with 'env: <shipgym env id it was trained on>' (and "
    "'env_kwargs:', e.g. vessel, observer, controller and residual_scale of a residual "
    "policy), and vecnormalize.pkl if it was trained with VecNormalize (if not, an "
    "args.yml key 'normalize: false' says so); see docs/tutorials/train-ppo.md"
)


def is_sb3_model(path: str | Path) -> bool:
    """``True`` for a zip with SB3's ``data`` and ``policy.pth`` members and no ``shipgym.json``
    (its directory checked as a shipgym model's first: member names, sizes and count; a file
    that fails those is not one, and the model loader says why)."""
    from shipgym.controllers.learned import _open_model

    try:
        _, zf, members = _open_model(path)
    except (OSError, ValueError):
        return False
    zf.close()
    return {"data", "policy.pth"} <= set(members) and METADATA_NAME not in members


def _yaml(path: Path) -> dict[str, Any]:
    """An ``args.yml`` / ``config.yml``: plain YAML, or rl-zoo3's dump of an ``OrderedDict``
    (the ``!!python/object/apply:collections.OrderedDict`` tag read as a mapping,
    ``!!python/tuple`` as a list; no other Python tag is constructed: a file with one is
    refused)."""
    import yaml

    class Loader(yaml.SafeLoader):
        pass

    def ordered(loader: Any, node: Any) -> dict[str, Any]:
        args = loader.construct_sequence(node, deep=True)
        pairs = args[0] if args else []
        return {str(k): v for k, v in pairs}

    Loader.add_constructor("tag:yaml.org,2002:python/object/apply:collections.OrderedDict", ordered)
    # a tuple among the values (rl-zoo3's -params evaluates them): read as a list
    Loader.add_constructor(
        "tag:yaml.org,2002:python/tuple", lambda loader, node: loader.construct_sequence(node)
    )
    if path.stat().st_size > 1 << 20:
        raise ValueError(f"{path}: larger than 1 MiB, not an rl-zoo3 args.yml / config.yml")
    try:
        data = yaml.load(path.read_text(), Loader=Loader)  # noqa: S506 - SafeLoader subclass
    except yaml.YAMLError as exc:
        raise ValueError(f"{path}: not the YAML rl-zoo3 writes: {str(exc)[:200]}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ValueError(f"{path}: must be a mapping (rl-zoo3's args.yml / config.yml)")
    return data


def _sidecar_dirs(zip_path: Path) -> list[Path]:
    """The folders holding a model's files: its own, then rl-zoo3's ``<ENV>/`` below it."""
    here = zip_path.parent
    subs = sorted(d for d in here.iterdir() if d.is_dir() and (d / "args.yml").is_file())
    return [here, *subs]


def find_sb3_model(
    path: str | Path,
    algorithm: str,
    *,
    env_id: str | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
    vecnormalize: str | Path | None = None,
) -> Sb3Model:
    """Describe an SB3 / rl-zoo3 model from the files next to it (:data:`NEEDS`).

    Looked for in the zip's folder, then in a sub-folder with an ``args.yml`` (rl-zoo3's
    ``<ENV>/``; one only): ``args.yml`` (``env``: the env id; ``env_kwargs``), ``config.yml``
    (``env_wrapper``: shipgym's ``ObserverWrapper`` and ``ErrorIntegralObservation``;
    ``env_kwargs``, which the command line's in ``args.yml`` override), and
    ``vecnormalize.pkl`` (or :func:`vecnormalize_path`'s name). Arguments given here win over
    the files.

    Args:
        path: the SB3 zip.
        algorithm: ``"ppo"`` or ``"sac"``.
        env_id: the training env id (default: ``args.yml``'s ``env``).
        env_kwargs: its keyword arguments (default: the files'); ``observer``,
            ``controller``, ``residual_scale`` among them describe the stack.
        vecnormalize: its ``vecnormalize.pkl`` (default: found next to the zip).

    Raises:
        ValueError: a missing env id, an env id that is not a shipgym env, two rl-zoo3 folders,
            an unsupported ``env_wrapper``; each says what to give.
        FileNotFoundError: the zip or a given ``vecnormalize`` file is missing.
    """
    from shipgym.envs.registration import ENV_IDS

    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"model file {str(p)!r} does not exist")
    if algorithm not in ALGORITHMS:
        raise ValueError(f"algorithm must be one of {', '.join(ALGORITHMS)}, got {algorithm!r}")
    dirs = _sidecar_dirs(p)
    if len(dirs) > 2:
        raise ValueError(
            f"{p}: several rl-zoo3 folders next to it ({', '.join(d.name for d in dirs[1:])}); "
            "keep the zip with its own <ENV>/ folder only"
        )
    sources: dict[str, str] = {}
    args: dict[str, Any] = {}
    config: dict[str, Any] = {}
    for d in dirs:
        if not args and (d / "args.yml").is_file():
            args, sources["args"] = _yaml(d / "args.yml"), str(d / "args.yml")
        if not config and (d / "config.yml").is_file():
            config, sources["config"] = _yaml(d / "config.yml"), str(d / "config.yml")
    if env_id is None:
        env_id = args.get("env")
        if env_id is None:
            raise ValueError(f"{p}: the env id it was trained on is unknown: {NEEDS}")
        sources["env_id"] = sources["args"]
    if not isinstance(env_id, str) or env_id not in ENV_IDS:
        raise ValueError(
            f"{p} was trained on {env_id!r}, not a shipgym environment; shipgym runs models "
            f"trained on: {', '.join(ENV_IDS)}"
        )
    if env_kwargs is None:
        kw: dict[str, Any] = {}
        for src in (config.get("env_kwargs"), args.get("env_kwargs")):
            if src is None:
                continue
            if not isinstance(src, Mapping):
                raise ValueError(f"{p}: env_kwargs must be a mapping, got {src!r}")
            kw.update(copy.deepcopy(dict(src)))
    else:
        kw = copy.deepcopy(dict(env_kwargs))
    wrapper_obs, integral = parse_env_wrapper(
        config.get("env_wrapper"), where=sources.get("config", str(p))
    )
    observer = kw.pop("observer", None) or wrapper_obs
    if observer == "truth":
        observer = None
    controller = kw.pop("controller", None)
    scale = kw.pop("residual_scale", 1.0)
    if controller is not None and not isinstance(controller, str):
        raise ValueError(f"{p}: env_kwargs controller must be a name such as 'pid'")
    if not (isinstance(scale, int | float) and math.isfinite(scale) and scale >= 0):
        raise ValueError(f"{p}: env_kwargs residual_scale must be a number >= 0, got {scale!r}")
    vn: Path | None
    if vecnormalize is not None:
        vn = Path(vecnormalize)
        if not vn.is_file():
            raise FileNotFoundError(f"VecNormalize file {str(vn)!r} does not exist")
    else:
        found = [
            f for d in dirs for f in (d / VECNORMALIZE_NAME, vecnormalize_path(d / p.name))
            if f.is_file()
        ]  # fmt: skip
        vn = found[0] if found else None
        # rl-zoo3's config.yml has 'normalize' only when it normalised; a plain SB3 user says
        # 'normalize: false' in args.yml
        normalize = args.get("normalize", config.get("normalize", False if config else None))
        if vn is None and normalize is not False:
            raise ValueError(
                f"{p}: no {VECNORMALIZE_NAME} next to it (looked in "
                f"{', '.join(str(d) for d in dirs)}); a policy trained with VecNormalize "
                f"gives wrong actions on raw observations. {NEEDS}"
            )
    if vn is not None:
        sources["vecnormalize"] = str(vn)
    return Sb3Model(
        path=p, algorithm=algorithm, env_id=env_id, env_kwargs=kw, observer=observer,
        controller=controller, residual_scale=float(scale), error_integral=integral,
        vecnormalize=vn, sources=sources,
    )  # fmt: skip


#: SB3 writes a class in ``data`` as ``"<class 'torch.nn.modules.activation.ReLU'>"``
_ACTIVATION_REPR = re.compile(r"<class 'torch\.nn\.modules\.activation\.(\w+)'>")
_ACTIVATIONS = {"Tanh": "tanh", "ReLU": "relu", "ELU": "elu", "LeakyReLU": "leaky_relu",
                "SiLU": "silu", "GELU": "gelu"}  # fmt: skip
#: the ``MlpPolicy`` class of each algorithm, as SB3 names it in ``data['policy_class']``
_MLP_POLICY = {"ppo": "ActorCriticPolicy", "sac": "SACPolicy"}


def _sb3_data(path: Path) -> dict[str, Any]:
    """The JSON ``data`` member of an SB3 zip (checked as shipgym checks its own models)."""
    import json

    from shipgym.controllers.learned import _check_sb3_members, _open_model, _read_member

    p, zf, members = _open_model(path)
    with zf:
        _check_sb3_members(zf, members, p)
        return dict(json.loads(_read_member(zf, members["data"], p).decode("utf-8")))


def _policy_spec(algorithm: str, data: Mapping[str, Any], p: Path) -> tuple[dict[str, Any], bool]:
    """``(policy_kwargs as plain data, use_sde)`` from SB3's ``data`` (no unpickling: the
    JSON fields SB3 writes beside each pickled value)."""
    cls = data.get("policy_class")
    init = str(cls.get("__init__", "")) if isinstance(cls, Mapping) else ""
    want = _MLP_POLICY[algorithm]
    for other, cls_name in _MLP_POLICY.items():
        if other != algorithm and init.startswith(f"<function {cls_name}.__init__"):
            raise ValueError(f"{p} holds a {other} model, not {algorithm}: use {other}:{p}")
    if not init.startswith(f"<function {want}.__init__"):
        raise ValueError(
            f"{p}: its policy is not the {algorithm.upper()} MlpPolicy ({want}); shipgym runs "
            "MlpPolicy models (vector observations)"
        )
    raw = data.get("policy_kwargs") or {}
    if not isinstance(raw, Mapping):
        raise ValueError(f"{p}: policy_kwargs in 'data' is not a mapping")
    kw: dict[str, Any] = {}
    for key, val in raw.items():
        if key in (":type:", ":serialized:", "optimizer_class"):
            continue  # the optimizer does not change the actions
        if key == "use_sde":  # SAC puts it here (OffPolicyAlgorithm); PPO beside the kwargs
            if val:
                raise ValueError(
                    f"{p}: a {algorithm.upper()} policy with gSDE (use_sde=True) is not one "
                    "shipgym rebuilds; train it with use_sde=False"
                )
            continue
        if key == "activation_fn":
            m = _ACTIVATION_REPR.fullmatch(str(val))
            if m is None or m.group(1) not in _ACTIVATIONS:
                raise ValueError(
                    f"{p}: activation_fn {val!r} is not one shipgym rebuilds "
                    f"({', '.join('nn.' + a for a in _ACTIVATIONS)})"
                )
            kw[key] = _ACTIVATIONS[m.group(1)]
        elif key in POLICY_KWARGS:
            kw[key] = val
        else:
            raise ValueError(
                f"{p}: policy_kwargs key {key!r} is not one shipgym rebuilds (it takes: "
                f"{', '.join(POLICY_KWARGS)})"
            )
    kw.setdefault("activation_fn", "tanh" if algorithm == "ppo" else "relu")
    return kw, bool(data.get("use_sde", False))


def import_sb3_model(model: Sb3Model, out: str | Path) -> Path:
    """A shipgym model of an SB3 / rl-zoo3 one: a copy of its zip with ``shipgym.json``.

    The metadata comes from ``model`` (:func:`find_sb3_model`) and the zip's ``data``
    (policy architecture, activation, ``use_sde``); the normalisation from its
    ``vecnormalize.pkl`` (:func:`read_vecnormalize`). The env stack (observer, residual
    controller, error integral) is built once to check that its observation and action
    shapes are the policy's. The copy still loads in plain SB3 (an extra member is ignored).

    Returns:
        ``out`` (a ``.zip``).

    Raises:
        ValueError: a policy shipgym cannot rebuild, statistics of another observation size,
            weights that do not fit (from :func:`~shipgym.controllers.learned.load_policy`).
    """
    import stable_baselines3
    import torch

    import shipgym
    from shipgym.controllers.learned import load_policy
    from shipgym.stacks import make

    p = model.path
    data = _sb3_data(p)
    policy_kwargs, use_sde = _policy_spec(model.algorithm, data, p)
    norm = read_vecnormalize(model.vecnormalize) if model.vecnormalize is not None else None
    env = make(
        model.env_id, observer=model.observer, controller=model.controller,
        residual_scale=model.residual_scale, **model.env_kwargs,
    )  # fmt: skip
    try:
        if model.error_integral is not None:
            from shipgym.envs.integral import ErrorIntegralObservation

            env = ErrorIntegralObservation(env, time_constant=model.error_integral)
        obs_shape = tuple(env.observation_space.shape or ())
        act_shape = tuple(env.action_space.shape or ())
    finally:
        env.close()
    if norm is not None and (len(norm.mean),) != obs_shape:
        raise ValueError(
            f"{model.vecnormalize} normalises {len(norm.mean)} observation entries; "
            f"{model.env_id} with {_stack_text(model)} gives {obs_shape}: the stack (observer, "
            "error integral in env_wrapper) or the env id is not the one it was trained on"
        )
    meta = ModelMetadata(
        algorithm=model.algorithm,
        env_id=model.env_id,
        env_kwargs=copy.deepcopy(model.env_kwargs),
        observer=model.observer,
        residual=model.controller is not None,
        controller=model.controller,
        residual_scale=model.residual_scale if model.controller is not None else 1.0,
        error_integral=model.error_integral,
        normalization=norm,
        policy="MlpPolicy",
        policy_kwargs=policy_kwargs,
        use_sde=use_sde,
        observation_shape=obs_shape,
        action_shape=act_shape,
        seed=data.get("seed") if isinstance(data.get("seed"), int) else None,
        command="",
        num_timesteps=int(data.get("num_timesteps", 0) or 0),
        hyperparams={},
        shipgym_version=shipgym.__version__,
        sb3_version=stable_baselines3.__version__,
        torch_version=torch.__version__,
        extra={"imported_from": str(p), "sources": dict(model.sources)},
    )
    o = Path(out)
    o.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(p, o)
    write_metadata(o, meta)
    load_policy(o)  # the weights fit the architecture of the metadata (one clear line if not)
    return o


def _stack_text(model: Sb3Model) -> str:
    parts = [f"observer {model.observer or 'truth'}"]
    if model.controller is not None:
        parts.append(f"controller {model.controller} (residual_scale {model.residual_scale:g})")
    if model.error_integral is not None:
        parts.append(f"error integral {model.error_integral:g} s")
    return ", ".join(parts)


def import_dir() -> Path:
    """Where :func:`resolve_controller` keeps imported models: ``$XDG_CACHE_HOME`` (or
    ``~/.cache``) ``/shipgym/imported``, private (0700: :func:`shipgym._io.private_cache_dir`);
    a folder of this process (removed at exit) where that cannot be made private."""
    from shipgym._io import private_cache_dir

    path = private_cache_dir("imported")
    return _temporary_dir() if path is None else path


_TEMP_DIR: Path | None = None


def _temporary_dir() -> Path:
    global _TEMP_DIR
    if _TEMP_DIR is None:
        import atexit

        _TEMP_DIR = Path(tempfile.mkdtemp(prefix="shipgym-imported-"))
        atexit.register(_remove_dir, _TEMP_DIR, os.getpid())
    return _TEMP_DIR


def _remove_dir(folder: Path, owner: int) -> None:
    """At exit of the process that made it (not of a forked worker that inherited the hook)."""
    if os.getpid() == owner:
        shutil.rmtree(folder, ignore_errors=True)


def _digest(model: Sb3Model) -> str:
    """What an import depends on: the zip, its statistics and its description (SHA-256)."""
    h = hashlib.sha256(repr(sorted(vars(model).items(), key=str)).encode())
    for f in (model.path, model.vecnormalize):
        if f is not None:
            h.update(Path(f).read_bytes())
    return h.hexdigest()[:16]


def resolve_controller(name: str, *, quiet: bool = False) -> str:
    """A controller name for ``shipgym run`` / ``bench controllers``: ``ppo:PATH`` /
    ``sac:PATH`` of an SB3 or rl-zoo3 model (no ``shipgym.json``) becomes ``ppo:IMPORTED``, the
    model imported (:func:`find_sb3_model`, :func:`import_sb3_model`) into
    :func:`import_dir` as ``<digest of its files>/<its file name>`` (kept, so that the results
    name a file that stays; imported again when a file changes); any other name is returned
    as it is. Says on stderr what it read and where the copy is (unless ``quiet``).

    Raises:
        ValueError, FileNotFoundError: what :func:`find_sb3_model` and
            :func:`import_sb3_model` raise (each says what to provide).
    """
    algo, sep, rest = str(name).partition(":")
    if not (sep and is_learned_controller(name)) or not is_sb3_model(Path(rest).expanduser()):
        return name
    src = Path(rest).expanduser()
    model = find_sb3_model(src, algo)
    out = import_dir() / _digest(model) / src.name
    if not out.is_file():
        tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp")
        try:
            import_sb3_model(model, tmp)
            tmp.replace(out)
        finally:
            tmp.unlink(missing_ok=True)
    if not quiet:
        vn = model.vecnormalize or "none (trained without VecNormalize)"
        print(
            f"shipgym: {src} is a stable-baselines3 model without shipgym.json: trained on "
            f"{model.env_id} ({_stack_text(model)}; from {model.sources.get('env_id', 'the call')}"
            f"), normalisation {vn}; scored as the shipgym model {out}",
            file=sys.stderr,
        )
    return f"{algo}:{out}"


def parse_env_wrapper(spec: Any, where: str = "hyperparameters") -> tuple[str | None, float | None]:
    """``(observer, error_integral)`` from a block's ``env_wrapper`` (rl-zoo3's form).

    rl-zoo3 wraps every env in what ``env_wrapper`` names (``rl_zoo3.utils.get_wrapper_class``),
    in order: a class path, or a one-entry mapping ``{class path: keyword arguments}``, or a
    list of these. shipgym takes :data:`OBSERVER_WRAPPER` (``ObserverWrapper``, which rebuilds
    the env as ``shipgym.make(..., observer=)`` makes it), with at most the argument ``observer``
    (default ``kbf``), then optionally :data:`INTEGRAL_WRAPPER` (``ErrorIntegralObservation``,
    the leaky integral of the observed errors, with at most ``time_constant`` in s); so the
    zoo and ``shipgym train`` build the same stack. ``None`` / ``None``: the truth, no integral.

    Raises:
        ValueError: any other wrapper, order or argument, with the form to use.
    """
    from shipgym.envs.integral import check_time_constant
    from shipgym.rl.evaluation import check_observer

    form = (
        f"env_wrapper: [{{{OBSERVER_WRAPPER}: {{observer: kbf}}}}] optionally followed by "
        f"{{{INTEGRAL_WRAPPER}: {{time_constant: 100}}}}"
    )
    if spec is None:
        return None, None
    entries = spec if isinstance(spec, list) else [spec]
    parsed: list[tuple[str, dict[str, Any]]] = []
    for entry in entries:
        kwargs: Any
        if isinstance(entry, str):
            name, kwargs = entry, {}
        elif isinstance(entry, dict) and len(entry) == 1:
            name, kwargs = next(iter(entry.items()))
            kwargs = {} if kwargs is None else kwargs
        else:
            raise ValueError(f"{where}: env_wrapper entries are a class path or {{path: kwargs}}")
        if not isinstance(kwargs, dict):
            raise ValueError(f"{where}: the arguments of env_wrapper {name!r} must be a mapping")
        parsed.append((name, kwargs))
    names = [n for n, _ in parsed]
    if names not in ([OBSERVER_WRAPPER], [OBSERVER_WRAPPER, INTEGRAL_WRAPPER]):
        raise ValueError(f"{where}: shipgym train supports {form}; got {names!r}")
    kwargs = parsed[0][1]
    unknown = sorted(set(kwargs) - {"observer"})
    if unknown:
        raise ValueError(
            f"{where}: env_wrapper {OBSERVER_WRAPPER} takes only 'observer', got {unknown}"
        )
    observer = kwargs.get("observer", "kbf")
    if not isinstance(observer, str):
        raise ValueError(f"{where}: env_wrapper observer must be a name, got {observer!r}")
    integral = None
    if len(parsed) == 2:
        kw = parsed[1][1]
        unknown = sorted(set(kw) - {"time_constant"})
        if unknown:
            raise ValueError(
                f"{where}: env_wrapper {INTEGRAL_WRAPPER} takes only 'time_constant', got {unknown}"
            )
        try:
            integral = check_time_constant(kw.get("time_constant", 100.0))
        except ValueError as exc:
            raise ValueError(f"{where}: env_wrapper {INTEGRAL_WRAPPER}: {exc}") from None
    return check_observer(observer), integral
