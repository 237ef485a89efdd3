"""Learned controllers: stable-baselines3 policies saved as shipgym models.

Public names: ``ALGORITHMS``, ``BASELINE_MODELS``, ``BASELINE_NAMES``, ``BASELINE_TASKS``,
``METADATA_NAME``, ``MODEL_FORMAT``, ``LearnedControllerWrapper``, ``LearnedPolicy``, ...

Design notes: docs/design/controllers.learned.md.
"""

from __future__ import annotations

import dataclasses
import io
import json
import math
import re
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._safeload import parse

__all__ = [
    "ALGORITHMS",
    "BASELINE_MODELS",
    "BASELINE_NAMES",
    "BASELINE_TASKS",
    "METADATA_NAME",
    "MODEL_FORMAT",
    "POLICY_ENV_KEYS",
    "LearnedControllerWrapper",
    "LearnedPolicy",
    "ModelMetadata",
    "ObsNormalization",
    "BaselineModel",
    "baseline_model_path",
    "policy_fingerprint",
    "model_fingerprint",
    "normalization_bytes",
    "recorded_fingerprints",
    "FINGERPRINT_KEYS",
    "baseline_task",
    "find_baseline",
    "check_policy_spec",
    "is_learned_controller",
    "load_policy",
    "models_dir",
    "parse_learned_controller",
    "policy_env_kwargs",
    "policy_parameter_count",
    "read_metadata",
    "read_state_dicts",
    "trained_vessel",
    "write_metadata",
]

#: value of ``format`` in ``shipgym.json``
MODEL_FORMAT = "shipgym-model"
#: version of the metadata layout (bumped on incompatible changes)
MODEL_FORMAT_VERSION = 1
#: name of the metadata member inside the model zip
METADATA_NAME = "shipgym.json"
#: algorithms a shipgym model may hold (lower case, as on the command line)
ALGORITHMS = ("ppo", "sac")
#: the training env arguments that belong to the policy, not to the conditions it met: its
#: action filter (``condition_commands``: the reversal hysteresis of its propeller commands).
#: Every env the policy runs in gets them (evaluation, :func:`~shipgym.stacks.
#: make_learned_env`), whatever the task and its conditions.
POLICY_ENV_KEYS = ("condition_commands",)


def policy_env_kwargs(env_kwargs: Mapping[str, Any] | None) -> dict[str, Any]:
    """The :data:`POLICY_ENV_KEYS` of a model's training ``env_kwargs`` (those it has)."""
    kw = env_kwargs or {}
    return {k: kw[k] for k in POLICY_ENV_KEYS if k in kw}


@dataclass(frozen=True)
class BaselineModel:
    """One shipped learned policy: a file in ``shipgym/assets/models`` (:data:`BASELINE_MODELS`).

    A baseline is found by its controller name, the task it runs and the vessel it drives
    (:func:`find_baseline`): ``ppo`` on the harbour manoeuvre is the Blue Lady's pure PPO, ``ppo``
    on station keeping with ``star-hercules`` is that vessel's station-keeping PPO.

    Attributes:
        name: the controller name (:data:`BASELINE_NAMES`: ``ppo``, ``sac``, ``ppo-residual``).
        task: :data:`BASELINE_TASKS`: ``"harbour"`` (trained on the tracking task, evaluated on
            the harbour manoeuvre; also the tracking task's) or ``"station-keeping"``.
        vessel: the vessel the policy was trained for (a library name).
        file: its file name in ``shipgym/assets/models``.
        algorithm: ``"ppo"`` or ``"sac"`` (what the file's metadata must say).
        residual: ``True`` for a residual on the PID (the file's metadata must agree).
        what: one line for ``shipgym list``.
    """

    name: str
    task: str
    vessel: str
    file: str
    algorithm: str
    residual: bool
    what: str

    def __post_init__(self) -> None:
        if self.task not in BASELINE_TASKS or self.algorithm not in ALGORITHMS:
            raise ValueError(f"bad baseline entry {self!r}")

    def label(self) -> str:
        """``"ppo (harbour, blue-lady)"``."""
        return f"{self.name} ({self.task}, {self.vessel})"


#: tasks a shipped baseline is registered for
BASELINE_TASKS = ("harbour", "station-keeping")
#: controller names of the shipped baselines (``ppo``: pure PPO, ``sac``: pure SAC,
#: ``ppo-residual``: PPO on top of the tuned PID). Until issue 17 ``ppo`` named the residual.
BASELINE_NAMES = ("ppo", "sac", "ppo-residual")
#: the shipped learned policies: (name, task, vessel) -> file; a file not (yet) in the package
#: is refused with a FileNotFoundError that lists those present (:func:`baseline_model_path`)
BASELINE_MODELS: tuple[BaselineModel, ...] = (
    BaselineModel(
        "ppo", "harbour", "blue-lady", "ppo_harbour_kbf.zip", "ppo", False,
        "pure PPO (no PID underneath), trained on tracking through the KBF",
    ),
    BaselineModel(
        "sac", "harbour", "blue-lady", "sac_harbour_kbf.zip", "sac", False,
        "pure SAC (no PID underneath), trained on tracking through the KBF",
    ),
    BaselineModel(
        "ppo-residual", "harbour", "blue-lady", "ppo_residual_pid_kbf.zip", "ppo", True,
        "PPO residual on top of the tuned PID, trained on tracking through the KBF",
    ),
    BaselineModel(
        "ppo", "station-keeping", "star-hercules", "ppo_station_star_hercules_kbf.zip", "ppo",
        False, "pure PPO station keeping in 10 m/s wind, through the KBF",
    ),
)  # fmt: skip

#: activation functions allowed in ``policy_kwargs`` (plain names, no eval)
ACTIVATIONS = ("tanh", "relu", "elu", "leaky_relu", "silu", "gelu")


# ---- limits of a model file (refused from the zip directory / metadata, before allocation) --
_MIB = 1 << 20
#: largest model file on disk; the shipped baseline is 0.2 MB
MAX_MODEL_FILE_BYTES = 256 * _MIB
#: most members in a model zip (stable-baselines3 writes 6-9, shipgym adds one)
MAX_MEMBERS = 32
#: largest uncompressed ``shipgym.json`` (the baseline's is 4 kB)
MAX_METADATA_BYTES = 1 * _MIB
#: largest uncompressed member (``MAX_PARAMETERS`` float32 weights and Adam's two moments
#: are 48 MB)
MAX_MEMBER_BYTES = 128 * _MIB
#: largest uncompressed archive, all members together
MAX_TOTAL_BYTES = 256 * _MIB
#: highest uncompressed / compressed size of a member above 1 MiB (float weights compress
#: about 1.1 times; deflate reaches ~1000 only on repetitive filler, i.e. zip bombs)
MAX_COMPRESSION_RATIO = 100.0
#: widest hidden layer of a policy or value network
MAX_LAYER_WIDTH = 4096
#: most hidden layers per network
MAX_LAYERS = 16
#: most parameters of the whole policy (all networks; SAC's target critics included):
#: 4 million float32 are 16 MB, hundreds of times the baseline's 10 000
MAX_PARAMETERS = 4_000_000
#: largest observation / action vectors a model may declare
MAX_OBS_SIZE = 10_000
#: policies a shipgym model may use (observations are vectors)
POLICIES = ("MlpPolicy",)
#: ``policy_kwargs`` keys allowed in metadata and hyperparameters (plain data only)
POLICY_KWARGS = (
    "net_arch",
    "activation_fn",
    "log_std_init",
    "ortho_init",
    "full_std",
    "use_expln",
    "squash_output",
    "share_features_extractor",
    "n_critics",
    "optimizer_kwargs",
)
#: members a model zip may hold (stable-baselines3's PPO and SAC files plus shipgym.json)
_MEMBERS = (
    "data",
    "policy.pth",
    "policy.optimizer.pth",
    "actor.optimizer.pth",
    "critic.optimizer.pth",
    "ent_coef_optimizer.pth",
    "pytorch_variables.pth",
    "_stable_baselines3_version",
    "system_info.txt",
    "shipgym.json",
)


# ---- metadata ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class ObsNormalization:
    """Observation normalisation of ``VecNormalize``, as plain numbers.

    ``obs_n = clip((obs - mean) / sqrt(var + epsilon), -clip_obs, clip_obs)`` (float32), which
    is exactly ``VecNormalize.normalize_obs``.

    Attributes:
        mean: running mean of each observation entry (units of the observation).
        var: running variance of each entry (units squared).
        count: number of samples behind the statistics.
        epsilon: added to the variance (units squared).
        clip_obs: clip of the normalised observation (-).
        norm_obs: whether observations are normalised at all.
        norm_reward: whether training normalised rewards (not used by the controller).
        clip_reward: reward clip in training (-).
        gamma: discount of the return statistics (-).
        ret_mean, ret_var, ret_count: return statistics (for resuming training).
    """

    mean: tuple[float, ...]
    var: tuple[float, ...]
    count: float
    epsilon: float = 1e-8
    clip_obs: float = 10.0
    norm_obs: bool = True
    norm_reward: bool = True
    clip_reward: float = 10.0
    gamma: float = 0.99
    ret_mean: float = 0.0
    ret_var: float = 1.0
    ret_count: float = 1e-4

    def __post_init__(self) -> None:
        mean = tuple(float(x) for x in self.mean)
        var = tuple(float(x) for x in self.var)
        if len(mean) != len(var) or not all(math.isfinite(x) for x in mean + var):
            raise ValueError("normalisation mean and var must be finite and of equal length")
        if min(var, default=0.0) < 0:
            raise ValueError("normalisation var must be >= 0")
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "var", var)

    def normalize(self, obs: ArrayLike) -> NDArray[np.float32]:
        """Normalise one observation or a batch (last axis = observation entries)."""
        o = np.asarray(obs)
        if not self.norm_obs:
            return o.astype(np.float32)
        mean = np.asarray(self.mean)
        var = np.asarray(self.var)
        out = np.clip((o - mean) / np.sqrt(var + self.epsilon), -self.clip_obs, self.clip_obs)
        return out.astype(np.float32)

    @classmethod
    def from_vec_normalize(cls, vn: Any) -> ObsNormalization:
        """The statistics of a ``stable_baselines3`` ``VecNormalize``."""
        return cls(
            mean=tuple(np.asarray(vn.obs_rms.mean, float).tolist()),
            var=tuple(np.asarray(vn.obs_rms.var, float).tolist()),
            count=float(vn.obs_rms.count),
            epsilon=float(vn.epsilon),
            clip_obs=float(vn.clip_obs),
            norm_obs=bool(vn.norm_obs),
            norm_reward=bool(vn.norm_reward),
            clip_reward=float(vn.clip_reward),
            gamma=float(vn.gamma),
            ret_mean=float(np.asarray(vn.ret_rms.mean)),
            ret_var=float(np.asarray(vn.ret_rms.var)),
            ret_count=float(vn.ret_rms.count),
        )

    def apply_to(self, vn: Any) -> None:
        """Write the statistics into a ``VecNormalize`` (resuming training)."""
        vn.obs_rms.mean = np.array(self.mean)
        vn.obs_rms.var = np.array(self.var)
        vn.obs_rms.count = self.count
        vn.ret_rms.mean = np.float64(self.ret_mean)
        vn.ret_rms.var = np.float64(self.ret_var)
        vn.ret_rms.count = self.ret_count


@dataclass(frozen=True)
class ModelMetadata:
    """What ``shipgym.json`` inside a model zip says (JSON object, plain data only).

    Attributes:
        algorithm: ``"ppo"`` or ``"sac"``.
        env_id: training environment id.
        env_kwargs: its constructor arguments (plain data).
        observer: observer name the policy saw (``None``: the truth).
        residual: ``True`` if the policy's action was added to a DP controller's command.
        controller: that controller's name (``"pid"``) when ``residual``.
        residual_scale: factor on the policy action in the residual sum (-).
        error_integral: forgetting time (s) of the error integral appended to the observation
            (:class:`~shipgym.envs.integral.ErrorIntegralObservation`); ``None``: none.
        normalization: observation statistics, or ``None`` without ``VecNormalize``.
        policy: SB3 policy alias (``"MlpPolicy"``).
        policy_kwargs: SB3 policy arguments as plain data (activation as a name).
        use_sde: state-dependent exploration flag of the algorithm (needed to rebuild PPO).
        observation_shape: observation shape the policy takes.
        action_shape: action shape it returns (Box(-1, 1)).
        seed: training seed.
        command: the command that trains this model (reproducible form).
        num_timesteps: environment steps trained.
        hyperparams: the hyperparameters used (plain data, as in the YAML file).
        shipgym_version, sb3_version, torch_version: versions at training time.
        format, format_version: :data:`MODEL_FORMAT`, :data:`MODEL_FORMAT_VERSION`.
        extra: anything else (wall time, evaluation results, ...).
    """

    algorithm: str
    env_id: str
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    observer: str | None = None
    residual: bool = False
    controller: str | None = None
    residual_scale: float = 1.0
    error_integral: float | None = None
    normalization: ObsNormalization | None = None
    policy: str = "MlpPolicy"
    policy_kwargs: dict[str, Any] = field(default_factory=dict)
    use_sde: bool = False
    observation_shape: tuple[int, ...] = (15,)
    action_shape: tuple[int, ...] = (3,)
    seed: int | None = None
    command: str = ""
    num_timesteps: int = 0
    hyperparams: dict[str, Any] = field(default_factory=dict)
    shipgym_version: str = ""
    sb3_version: str = ""
    torch_version: str = ""
    format: str = MODEL_FORMAT
    format_version: int = MODEL_FORMAT_VERSION
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("algorithm", "env_id", "policy", "command"):
            if not isinstance(getattr(self, name), str):
                raise TypeError(f"{name} must be a string, got {getattr(self, name)!r}")
        for name in ("observer", "controller"):
            if getattr(self, name) is not None and not isinstance(getattr(self, name), str):
                raise TypeError(f"{name} must be a string or null, got {getattr(self, name)!r}")
        if self.algorithm not in ALGORITHMS:
            raise ValueError(f"algorithm must be one of {ALGORITHMS}, got {self.algorithm!r}")
        if self.residual and not self.controller:
            raise ValueError("a residual model needs the name of its controller (e.g. 'pid')")
        if not (math.isfinite(self.residual_scale) and self.residual_scale >= 0):
            raise ValueError(f"residual_scale must be finite and >= 0, got {self.residual_scale}")
        if self.error_integral is not None:
            from shipgym.envs.integral import check_time_constant

            object.__setattr__(self, "error_integral", check_time_constant(self.error_integral))
        if isinstance(self.normalization, Mapping):
            object.__setattr__(self, "normalization", ObsNormalization(**self.normalization))
        for name in ("env_kwargs", "policy_kwargs", "hyperparams", "extra"):
            if not isinstance(getattr(self, name), Mapping):
                raise ValueError(f"{name} must be a mapping, got {getattr(self, name)!r}")
        object.__setattr__(self, "observation_shape", _shape(self.observation_shape, "observation"))
        object.__setattr__(self, "action_shape", _shape(self.action_shape, "action"))
        check_policy_spec(
            self.algorithm, self.policy, self.policy_kwargs,
            self.observation_shape, self.action_shape,
        )  # fmt: skip
        norm = self.normalization
        n_obs = math.prod(self.observation_shape)
        if norm is not None and len(norm.mean) != n_obs:
            raise ValueError(f"normalisation has {len(norm.mean)} entries, the observation {n_obs}")

    def to_json(self) -> str:
        """The ``shipgym.json`` text."""
        return json.dumps(dataclasses.asdict(self), indent=2, sort_keys=True)

    @classmethod
    def from_json(cls, text: str, *, where: str = "shipgym.json") -> ModelMetadata:
        """Parse ``shipgym.json``; raises ``ValueError`` naming what is wrong."""
        d = parse(text, "json", where)
        if not isinstance(d, dict) or d.get("format") != MODEL_FORMAT:
            raise ValueError(
                f"{where} does not describe a shipgym model (format != {MODEL_FORMAT})"
            )
        version = d.get("format_version")
        if not isinstance(version, int) or version > MODEL_FORMAT_VERSION:
            raise ValueError(
                f"{where} has format_version {version!r}; this shipgym reads up to "
                f"{MODEL_FORMAT_VERSION}: upgrade shipgym"
            )
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(d) - names)
        if unknown:
            raise ValueError(f"{where} has unknown keys {unknown}")
        try:
            return cls(**d)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{where}: {exc}") from None


def _shape(value: Any, what: str) -> tuple[int, ...]:
    """A declared observation / action shape: 1-4 whole numbers >= 1, small in total."""
    try:
        dims = tuple(value)
    except TypeError:
        raise ValueError(f"{what}_shape must be a list of whole numbers, got {value!r}") from None
    if not 1 <= len(dims) <= 4 or not all(
        isinstance(n, int) and not isinstance(n, bool) and n >= 1 for n in dims
    ):
        raise ValueError(f"{what}_shape must be 1-4 whole numbers >= 1, got {value!r}")
    if math.prod(dims) > MAX_OBS_SIZE:
        raise ValueError(f"{what}_shape {dims} has more than {MAX_OBS_SIZE} entries")
    return dims


def _layers(arch: Any, where: str) -> list[int]:
    if not isinstance(arch, list | tuple) or len(arch) > MAX_LAYERS:
        raise ValueError(
            f"{where} must be a list of at most {MAX_LAYERS} layer widths, got {arch!r}"
        )
    for w in arch:
        if isinstance(w, bool) or not isinstance(w, int) or not 1 <= w <= MAX_LAYER_WIDTH:
            raise ValueError(
                f"{where}: layer widths must be whole numbers from 1 to {MAX_LAYER_WIDTH}, "
                f"got {w!r}"
            )
    return list(arch)


def _mlp_count(n_in: int, layers: list[int], n_out: int) -> int:
    count, prev = 0, n_in
    for w in layers:
        count += (prev + 1) * w
        prev = w
    return count + (prev + 1) * n_out


def policy_parameter_count(
    algorithm: str,
    policy_kwargs: Mapping[str, Any],
    observation_shape: tuple[int, ...] = (15,),
    action_shape: tuple[int, ...] = (3,),
) -> int:
    """Number of parameters the policy of these settings has (no torch needed).

    PPO: policy MLP + action head + log-std and value MLP + value head; SAC: actor MLP + mean
    and log-std heads, ``n_critics`` Q networks on (observation, action) and their target
    copies. stable-baselines3's defaults (PPO 64x64, SAC 256x256) apply without ``net_arch``.

    Raises:
        ValueError: a malformed ``net_arch`` (see :func:`check_policy_spec` for the limits).
    """
    n_obs, n_act = math.prod(observation_shape), math.prod(action_shape)
    arch = policy_kwargs.get("net_arch")
    default = [64, 64] if algorithm == "ppo" else [256, 256]
    second = "vf" if algorithm == "ppo" else "qf"
    if arch is None:
        pi = vf = default
    elif isinstance(arch, Mapping):
        unknown = sorted(set(arch) - {"pi", second})
        if unknown:
            raise ValueError(f"net_arch has unknown keys {unknown}; valid: ['pi', '{second}']")
        pi = _layers(arch.get("pi", []), "net_arch['pi']")
        vf = _layers(arch.get(second, []), f"net_arch['{second}']")
    else:
        pi = vf = _layers(arch, "net_arch")
    if algorithm == "ppo":
        return _mlp_count(n_obs, pi, n_act) + n_act + _mlp_count(n_obs, vf, 1)
    n_critics = policy_kwargs.get("n_critics", 2)
    if isinstance(n_critics, bool) or not isinstance(n_critics, int) or not 1 <= n_critics <= 10:
        raise ValueError(f"n_critics must be a whole number from 1 to 10, got {n_critics!r}")
    actor = _mlp_count(n_obs, pi, 2 * n_act)
    return actor + 2 * n_critics * _mlp_count(n_obs + n_act, vf, 1)


def _plain(value: Any, where: str, depth: int = 0) -> None:
    """Plain data only: numbers, strings, bools, None, lists and string-keyed mappings."""
    if depth > 8:
        raise ValueError(f"{where} is nested too deeply")
    if value is None or isinstance(value, bool | int | str):
        return
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"{where} must be finite, got {value!r}")
        return
    if isinstance(value, list | tuple):
        for v in value:
            _plain(v, where, depth + 1)
        return
    if isinstance(value, Mapping) and all(isinstance(k, str) for k in value):
        for k, v in value.items():
            _plain(v, f"{where}[{k!r}]", depth + 1)
        return
    raise ValueError(f"{where} must be plain data (numbers, strings, lists), got {value!r}")


def check_policy_spec(
    algorithm: str,
    policy: Any,
    policy_kwargs: Any,
    observation_shape: tuple[int, ...] = (15,),
    action_shape: tuple[int, ...] = (3,),
) -> int:
    """Check a policy description before anything is built; returns its parameter count.

    The policy must be one of :data:`POLICIES`; ``policy_kwargs`` plain data with keys from
    :data:`POLICY_KWARGS` (``activation_fn`` by name, see :data:`ACTIVATIONS`); the networks
    at most :data:`MAX_LAYERS` layers of at most :data:`MAX_LAYER_WIDTH` units and
    :data:`MAX_PARAMETERS` parameters in all.

    Raises:
        ValueError: naming the offending key and what is valid.
    """
    if policy not in POLICIES:
        raise ValueError(
            f"policy must be one of {', '.join(POLICIES)} (shipgym observations are vectors), "
            f"got {policy!r}"
        )
    if not isinstance(policy_kwargs, Mapping):
        raise ValueError(f"policy_kwargs must be a mapping, got {policy_kwargs!r}")
    unknown = sorted(str(k) for k in set(policy_kwargs) - set(POLICY_KWARGS))
    if unknown:
        raise ValueError(
            f"policy_kwargs has unknown or unsupported keys {unknown}; valid: "
            f"{', '.join(POLICY_KWARGS)}"
        )
    _plain(dict(policy_kwargs), "policy_kwargs")
    if "activation_fn" in policy_kwargs and str(policy_kwargs["activation_fn"]) not in ACTIVATIONS:
        raise ValueError(
            f"unknown activation_fn {policy_kwargs['activation_fn']!r}; choose one of: "
            f"{', '.join(ACTIVATIONS)}"
        )
    opt = policy_kwargs.get("optimizer_kwargs")
    if opt is not None and not isinstance(opt, Mapping):
        raise ValueError(f"policy_kwargs['optimizer_kwargs'] must be a mapping, got {opt!r}")
    for key in ("ortho_init", "full_std", "use_expln", "squash_output", "share_features_extractor"):
        if key in policy_kwargs and not isinstance(policy_kwargs[key], bool):
            raise ValueError(f"policy_kwargs['{key}'] must be true or false")
    n = policy_parameter_count(algorithm, policy_kwargs, observation_shape, action_shape)
    if n > MAX_PARAMETERS:
        raise ValueError(
            f"the policy would have {n:,} parameters, more than the limit of "
            f"{MAX_PARAMETERS:,}: use a smaller net_arch"
        )
    return n


def _archive(zf: zipfile.ZipFile, p: Path) -> dict[str, zipfile.ZipInfo]:
    """The members of a model zip, checked from its directory (nothing is decompressed)."""
    infos = zf.infolist()
    if len(infos) > MAX_MEMBERS:
        raise ValueError(f"{p}: {len(infos)} members, more than a model has ({MAX_MEMBERS})")
    out: dict[str, zipfile.ZipInfo] = {}
    total = 0
    for info in infos:
        name = info.filename
        if name not in _MEMBERS:
            raise ValueError(
                f"{p}: unexpected member {name!r}; a model zip holds only {', '.join(_MEMBERS)}"
            )
        if name in out:
            raise ValueError(f"{p}: member {name!r} appears twice")
        limit = MAX_METADATA_BYTES if name == METADATA_NAME else MAX_MEMBER_BYTES
        if info.file_size > limit:
            raise ValueError(
                f"{p}: member {name!r} unpacks to {info.file_size:,} bytes, more than the "
                f"limit of {limit:,}"
            )
        ratio = info.file_size / max(info.compress_size, 1)
        if info.file_size > _MIB and ratio > MAX_COMPRESSION_RATIO:
            raise ValueError(
                f"{p}: member {name!r} is compressed {ratio:.0f} times (limit "
                f"{MAX_COMPRESSION_RATIO:g}): not a model, a zip bomb?"
            )
        total += info.file_size
        out[name] = info
    if total > MAX_TOTAL_BYTES:
        raise ValueError(f"{p}: unpacks to {total:,} bytes, more than {MAX_TOTAL_BYTES:,}")
    return out


def _check_directory_size(p: Path, size: int) -> None:
    """Refuse a zip whose end record announces too many members, before ``zipfile`` parses its
    directory (a directory of millions of entries would fill memory with ``ZipInfo``s)."""
    with p.open("rb") as fh:
        n = min(size, 22 + 0xFFFF)  # end record plus the longest comment
        fh.seek(size - n)
        tail = fh.read(n)
    i = tail.rfind(b"PK\x05\x06")
    if i < 0 or len(tail) - i < 22:
        return  # not a zip: zipfile says so below
    entries = int.from_bytes(tail[i + 10 : i + 12], "little")
    dir_bytes = int.from_bytes(tail[i + 12 : i + 16], "little")
    if entries > MAX_MEMBERS or dir_bytes > MAX_MEMBERS * 1024:
        raise ValueError(
            f"{p}: its directory announces {entries} members ({dir_bytes:,} bytes), more than a "
            f"model has ({MAX_MEMBERS})"
        )


def _open_model(path: str | Path) -> tuple[Path, zipfile.ZipFile, dict[str, zipfile.ZipInfo]]:
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"model file {str(p)!r} does not exist")
    if not p.is_file():
        raise ValueError(f"model file {str(p)!r} is not a file")
    size = p.stat().st_size
    if size > MAX_MODEL_FILE_BYTES:
        raise ValueError(f"{p}: {size:,} bytes, more than a model file may have")
    _check_directory_size(p, size)
    try:
        zf = zipfile.ZipFile(p)
    except (zipfile.BadZipFile, OSError) as exc:
        raise ValueError(
            f"{p} is not a shipgym model: not a zip archive ({exc}); expected a file "
            "written by 'shipgym train'"
        ) from None
    try:
        return p, zf, _archive(zf, p)
    except BaseException:
        zf.close()
        raise


def _read_member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, p: Path) -> bytes:
    """A member's bytes; the read stops at the size of the directory (already bounded)."""
    try:
        with zf.open(info) as fh:
            data = fh.read(info.file_size + 1)
    except (zipfile.BadZipFile, OSError, EOFError, RuntimeError, NotImplementedError) as exc:
        raise ValueError(f"{p}: member {info.filename!r} is corrupt: {exc}") from None
    if len(data) != info.file_size:
        raise ValueError(f"{p}: member {info.filename!r} is not the size its directory says")
    return data


def read_metadata(path: str | Path) -> ModelMetadata:
    """The metadata of a shipgym model file, checked before anything else reads the file.

    The zip's directory is checked first (member names and sizes, see the module
    docstring); only ``shipgym.json`` is read.

    Raises:
        FileNotFoundError: no such file.
        ValueError: not a zip, a zip beyond the limits, or one without valid
            ``shipgym.json`` (not a shipgym model).
    """
    p, zf, members = _open_model(path)
    with zf:
        if METADATA_NAME not in members:
            hint = (
                " (a plain stable-baselines3 zip; shipgym only loads models saved by "
                "'shipgym train', which carry shipgym.json)"
                if "data" in members
                else ""
            )
            raise ValueError(f"{p} is not a shipgym model: it has no {METADATA_NAME}{hint}")
        raw = _read_member(zf, members[METADATA_NAME], p)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{p}:{METADATA_NAME} is not UTF-8 text (not a shipgym model)") from None
    return ModelMetadata.from_json(text, where=f"{p}:{METADATA_NAME}")


def _torch_member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, p: Path, device: str) -> Any:
    """A ``.pth`` member through ``torch.load(weights_only=True)``: tensors and containers only."""
    import torch as th

    raw = _read_member(zf, info, p)
    try:
        return th.load(io.BytesIO(raw), map_location=device, weights_only=True)
    except Exception as exc:  # noqa: BLE001 - torch raises many kinds; all mean "refused"
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ValueError(
            f"{p}: member {info.filename!r} is not a plain tensor file; "
            f"torch.load(weights_only=True) refused it ({type(exc).__name__}: {first[:200]})"
        ) from None


def _check_sb3_members(zf: zipfile.ZipFile, members: dict[str, zipfile.ZipInfo], p: Path) -> None:
    """``data`` is a JSON object, the text members are UTF-8 (nothing here is unpickled)."""
    for name in ("data", "policy.pth"):
        if name not in members:
            raise ValueError(f"{p} is not a complete model: it has no {name!r}")
    try:
        data = parse(_read_member(zf, members["data"], p).decode("utf-8"), "json", "")
    except (UnicodeDecodeError, ValueError):
        raise ValueError(f"{p}: member 'data' is not the JSON stable-baselines3 writes") from None
    if not isinstance(data, dict):
        raise ValueError(f"{p}: member 'data' is not a JSON object")
    for name in ("_stable_baselines3_version", "system_info.txt"):
        if name in members:
            try:
                _read_member(zf, members[name], p).decode("utf-8")
            except UnicodeDecodeError:
                raise ValueError(f"{p}: member {name!r} is not text") from None


def read_state_dicts(path: str | Path, *, device: str = "cpu") -> dict[str, Any]:
    """Every ``.pth`` member of a model, safely: ``{"policy": ..., "policy.optimizer": ...}``.

    The archive and its metadata are checked first (:func:`read_metadata`), ``data`` must be
    JSON, and each ``.pth`` member goes through ``torch.load(weights_only=True)``. Keys are
    the member names without ``.pth`` (what ``set_parameters`` of stable-baselines3 takes;
    ``pytorch_variables`` holds SAC's entropy coefficient).

    Raises:
        FileNotFoundError, ValueError: see :func:`read_metadata`; a member torch refuses.
        ImportError: torch missing.
    """
    read_metadata(path)
    p, zf, members = _open_model(path)
    with zf:
        _check_sb3_members(zf, members, p)
        out = {}
        for name, info in members.items():
            if name.endswith(".pth"):
                out[name[: -len(".pth")]] = _torch_member(zf, info, p, device)
    for name, val in out.items():
        if not isinstance(val, dict):
            raise ValueError(f"{p}: member '{name}.pth' does not hold a state dict")
    return out


def cpu_identity() -> str:
    """The CPU a policy fingerprint holds on: its model name and the widest vector
    instructions it has (``avx512``, ``avx2`` or ``baseline``), which NumPy's and torch's
    kernels dispatch on, so that their last bits differ between them. A virtual machine may
    name two CPU generations alike (``AMD EPYC``); the instructions tell them apart."""
    import platform

    name, flags = "", set()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            if key.strip() == "model name" and not name:
                name = value.strip()
            elif key.strip() == "flags" and not flags:
                flags = set(value.split())
    except OSError:
        pass
    name = name or platform.processor() or "unknown"
    isa = "avx512" if "avx512f" in flags else "avx2" if "avx2" in flags else "baseline"
    return f"{name} ({isa})"


def _hash_state(h: Any, state: Mapping[str, Any], *, dtype: bool) -> None:
    """Feed a state dict to ``h``: per tensor in key order its name, shape (and, with
    ``dtype``, its dtype) and its bytes in the machine's order."""
    for key in sorted(state):
        t = state[key].detach().cpu().contiguous()
        h.update(key.encode())
        h.update(str(tuple(t.shape)).encode())
        if dtype:
            h.update(str(t.dtype).encode())
        h.update(t.numpy().tobytes())


def policy_fingerprint(path: str | Path) -> str:
    """SHA-256 (hex) of a model's policy weights alone, tensor by tensor in key order.

    Covers ``policy.pth`` (every tensor of the policy module: for PPO the policy and value
    networks and ``log_std``, for SAC the actor, the critics and their targets): per tensor its
    name, shape and float bytes. It does **not** cover the observation normalisation the model
    runs with, so two files with the same policy fingerprint may act differently; what the
    policy's actions depend on is :func:`model_fingerprint`. Kept because the reproduction
    records (``reproduce.policy_sha256`` of a shipped model's metadata) hold it.
    """
    import hashlib

    h = hashlib.sha256()
    _hash_state(h, read_state_dicts(path)["policy"], dtype=False)
    return h.hexdigest()


#: first bytes of the stream :func:`model_fingerprint` hashes (its layout's version)
_MODEL_FINGERPRINT_TAG = b"shipgym-model-fingerprint/1\n"


def normalization_bytes(norm: ObsNormalization | None) -> bytes:
    """The canonical bytes of a model's normalisation statistics (:func:`model_fingerprint`).

    Every field of :class:`ObsNormalization` in name order, each as its name and its value:
    ``mean`` and ``var`` as their length and little-endian float64 entries, the other numbers
    as one little-endian float64, the flags as one byte. Exact: the float64 of ``shipgym.json``
    (written with ``repr``, read back to the same float) go in bit for bit, so a change of one
    unit in the last place changes the bytes; JSON's spacing and key order do not. ``None``
    (a model trained without ``VecNormalize``) has bytes of its own.
    """
    import struct

    if norm is None:
        return b"normalization:none\n"
    out = [b"normalization\n"]
    for f in sorted(dataclasses.fields(norm), key=lambda f: f.name):
        value = getattr(norm, f.name)
        out.append(f.name.encode() + b"=")
        if isinstance(value, bool):
            out.append(b"\x01" if value else b"\x00")
        elif isinstance(value, tuple):
            out.append(struct.pack("<Q", len(value)))
            out.append(np.asarray(value, dtype="<f8").tobytes())
        else:
            out.append(struct.pack("<d", float(value)))
        out.append(b"\n")
    return b"".join(out)


def model_fingerprint(path: str | Path) -> str:
    """SHA-256 (hex) of what decides a model's actions: its policy weights and the observation
    normalisation it runs with.

    Covers, in this order:

    - ``policy.pth``: every tensor of the policy module, in key order, each as its name,
      shape, dtype and bytes (the weights :func:`policy_fingerprint` covers, plus their dtype);
    - the ``normalization`` of the model's ``shipgym.json`` (:func:`normalization_bytes`), the
      statistics :class:`LearnedPolicy` normalises observations with: ``mean``, ``var``,
      ``count``, ``epsilon``, ``clip_obs``, ``norm_obs``, and the reward statistics saved
      with them (``norm_reward``, ``clip_reward``, ``gamma``, ``ret_mean``, ``ret_var``,
      ``ret_count``). ``count`` and the reward statistics do not change an action (they
      decide how training goes on, ``shipgym train --resume``); they are covered so that a
      fingerprint stands for every statistic the file saves.

    Not covered: the optimizer's state, the rest of the metadata (architecture and activation
    by name, env, observer, command, versions) and the ``vecnormalize.pkl`` beside a model
    saved by ``shipgym train``, a copy of the same statistics for plain stable-baselines3
    (:func:`shipgym.rl.train.save_model` writes it from them).

    Two files with the same model fingerprint and the same architecture give the same actions
    on the same observations, on the same CPU and software. The reproduction records of the
    shipped baselines hold it per CPU (``reproduce.model_sha256``, :func:`recorded_fingerprints`).

    Raises:
        FileNotFoundError, ValueError: see :func:`read_state_dicts`.
    """
    import hashlib

    meta = read_metadata(path)
    h = hashlib.sha256(_MODEL_FINGERPRINT_TAG)
    h.update(b"policy\n")
    _hash_state(h, read_state_dicts(path)["policy"], dtype=True)
    h.update(normalization_bytes(meta.normalization))
    return h.hexdigest()


#: fingerprints a ``reproduce`` record may hold per CPU: :func:`policy_fingerprint` (weights
#: alone; every record has it) and :func:`model_fingerprint` (weights and normalisation)
FINGERPRINT_KEYS = ("policy_sha256", "model_sha256")


def recorded_fingerprints(reproduce: Mapping[str, Any]) -> dict[str, dict[str, str]]:
    """CPU -> ``{"policy_sha256": ..., "model_sha256": ...}`` of a ``reproduce`` record.

    A record (``extra.reproduce`` of a shipped model's metadata) names the CPU it was taken on
    (``cpu``, :func:`cpu_identity`) with its fingerprints beside (``policy_sha256``, and since
    the model fingerprint ``model_sha256``), and may hold other CPUs' in ``other_cpus``: each
    CPU to a mapping of the same keys, or, in records written before the model fingerprint, to
    the policy fingerprint alone (read as ``{"policy_sha256": ...}``). A CPU without
    ``model_sha256`` was recorded before it existed.

    Raises:
        ValueError: a record without ``cpu`` or ``policy_sha256``, a fingerprint that is not
            64 hex digits, or an unknown key.
    """

    def entry(cpu: Any, value: Any) -> dict[str, str]:
        got = {"policy_sha256": value} if isinstance(value, str) else value
        if not isinstance(cpu, str) or not isinstance(got, Mapping) or not got:
            raise ValueError(f"reproduce: bad fingerprints of CPU {cpu!r}: {value!r}")
        unknown = sorted(set(got) - set(FINGERPRINT_KEYS))
        if unknown or "policy_sha256" not in got:
            raise ValueError(
                f"reproduce: the fingerprints of {cpu!r} must have policy_sha256 (and may have "
                f"model_sha256), got keys {sorted(got)}"
            )
        for k, sha in got.items():
            if not isinstance(sha, str) or not re.fullmatch("[0-9a-f]{64}", sha):
                raise ValueError(f"reproduce: {k} of {cpu!r} is not a SHA-256: {sha!r}")
        return dict(got)

    if "cpu" not in reproduce:
        raise ValueError(f"reproduce record without 'cpu': keys {sorted(reproduce)}")
    main = {k: reproduce[k] for k in FINGERPRINT_KEYS if k in reproduce}
    out = {reproduce["cpu"]: entry(reproduce["cpu"], main)}
    others = reproduce.get("other_cpus", {})
    if not isinstance(others, Mapping):
        raise ValueError(f"reproduce: other_cpus must be a mapping, got {others!r}")
    for cpu, value in others.items():
        if cpu in out:
            raise ValueError(f"reproduce: CPU {cpu!r} is both 'cpu' and in other_cpus")
        out[cpu] = entry(cpu, value)
    return out


def write_metadata(path: str | Path, meta: ModelMetadata) -> None:
    """Add (or replace) ``shipgym.json`` in the zip that SB3's ``model.save`` wrote."""
    p = Path(path)
    with zipfile.ZipFile(p) as zf:
        names = zf.namelist()
        if "data" not in names or "policy.pth" not in names:
            raise ValueError(f"{p} is not a stable-baselines3 model zip")
        if METADATA_NAME in names:
            members = {n: zf.read(n) for n in names if n != METADATA_NAME}
        else:
            members = None
    if members is not None:  # rewrite without the old metadata
        with zipfile.ZipFile(p, "w", zipfile.ZIP_DEFLATED) as zf:
            for n, b in members.items():
                zf.writestr(n, b)
    with zipfile.ZipFile(p, "a", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr(METADATA_NAME, meta.to_json())


# ---- policies -------------------------------------------------------------------------------
def activation_class(name: str) -> Any:
    """The torch activation class of a plain name (``"tanh"``, ``"relu"``, ...)."""
    import torch.nn as nn

    table = {
        "tanh": nn.Tanh,
        "relu": nn.ReLU,
        "elu": nn.ELU,
        "leaky_relu": nn.LeakyReLU,
        "silu": nn.SiLU,
        "gelu": nn.GELU,
    }
    try:
        return table[str(name).lower()]
    except KeyError:
        raise ValueError(
            f"unknown activation_fn {name!r}; choose one of: {', '.join(ACTIVATIONS)}"
        ) from None


def sb3_policy_kwargs(plain: Mapping[str, Any]) -> dict[str, Any]:
    """SB3 ``policy_kwargs`` from plain data (the activation given by name)."""
    out = dict(plain)
    if "activation_fn" in out:
        out["activation_fn"] = activation_class(out["activation_fn"])
    return out


def algorithm_class(algorithm: str) -> Any:
    """The stable-baselines3 class of ``"ppo"`` / ``"sac"`` (needs ``shipgym[rl]``)."""
    if algorithm not in ALGORITHMS:
        raise ValueError(f"unknown algorithm {algorithm!r}; choose one of: {', '.join(ALGORITHMS)}")
    try:
        import stable_baselines3 as sb3
    except ImportError:
        raise ImportError(
            "learned controllers need stable-baselines3 and torch: run 'make rl' (it installs "
            "the CPU build torch==2.13.0 first, then stable-baselines3)"
        ) from None
    return {"ppo": sb3.PPO, "sac": sb3.SAC}[algorithm]


class LearnedPolicy:
    """A trained policy with its observation normalisation: observation in, action out.

    Built by :func:`load_policy`. ``policy(obs)`` normalises the raw environment observation
    with the training statistics (:class:`ObsNormalization`) and returns the deterministic
    action of the network (``Box(-1, 1)``), the same numbers as SB3's
    ``model.predict(vec_normalize.normalize_obs(obs), deterministic=True)``.

    Args:
        policy: an SB3 policy module (``ActorCriticPolicy``, ``SACPolicy``) in eval mode.
        metadata: the model's :class:`ModelMetadata`.
    """

    def __init__(self, policy: Any, metadata: ModelMetadata) -> None:
        self.policy = policy
        self.metadata = metadata
        self.normalization = metadata.normalization

    def normalize(self, obs: ArrayLike) -> NDArray[np.float32]:
        """The observation as the network sees it."""
        if self.normalization is None:
            return np.asarray(obs, dtype=np.float32)
        return self.normalization.normalize(obs)

    def __call__(self, obs: ArrayLike, *, deterministic: bool = True) -> NDArray[np.float32]:
        """Action(s) for one observation (shape (15,)) or a batch (shape (n, 15))."""
        o = np.asarray(obs)
        if o.shape[-len(self.metadata.observation_shape) :] != self.metadata.observation_shape:
            raise ValueError(
                f"observation must have shape {self.metadata.observation_shape} (or a batch of "
                f"them), got {o.shape}"
            )
        if not np.all(np.isfinite(o)):
            raise ValueError(f"observation contains NaN or infinite values: {o}")
        action, _ = self.policy.predict(self.normalize(o), deterministic=deterministic)
        return np.asarray(action, dtype=np.float32)


def load_policy(path: str | Path, *, device: str = "cpu") -> LearnedPolicy:
    """Load a shipgym model as a :class:`LearnedPolicy` without unpickling anything.

    The archive and metadata are checked first (:func:`read_metadata`: sizes, architecture
    limits); the network is rebuilt from ``policy`` and ``policy_kwargs`` and its weights are
    read from ``policy.pth`` with ``torch.load(weights_only=True)`` (every other ``.pth``
    member too, so a file with a crafted member is refused: :func:`read_state_dicts`).

    Raises:
        FileNotFoundError, ValueError: see :func:`read_metadata`; weights that do not fit the
            architecture in the metadata.
        ImportError: stable-baselines3 / torch missing.
    """
    meta = read_metadata(path)
    algo = algorithm_class(meta.algorithm)
    from gymnasium import spaces

    try:
        policy_cls = algo.policy_aliases[meta.policy]
    except KeyError:
        raise ValueError(
            f"{path}: unknown policy {meta.policy!r} for {meta.algorithm}; choose one of: "
            f"{', '.join(algo.policy_aliases)}"
        ) from None
    obs_space = spaces.Box(-np.inf, np.inf, meta.observation_shape, np.float32)
    act_space = spaces.Box(-1.0, 1.0, meta.action_shape, np.float32)
    kwargs = sb3_policy_kwargs(meta.policy_kwargs)
    if meta.algorithm == "ppo":
        kwargs["use_sde"] = meta.use_sde
    states = read_state_dicts(path, device=device)
    try:
        policy = policy_cls(obs_space, act_space, lambda _: 0.0, **kwargs)
    except (TypeError, ValueError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ValueError(f"{path}: cannot build the policy of {METADATA_NAME}: {first}") from None
    try:
        policy.load_state_dict(states["policy"])
    except (RuntimeError, TypeError, KeyError) as exc:
        first = " ".join(str(exc).split())[:300]
        raise ValueError(
            f"{path}: weights do not match the policy in {METADATA_NAME}: {first}"
        ) from None
    policy.to(device)
    policy.set_training_mode(False)
    return LearnedPolicy(policy, meta)


# ---- controller names ----------------------------------------------------------------------
def models_dir() -> Path:
    """The folder of the shipped model files (``shipgym/assets/models``)."""
    return Path(str(resources.files("shipgym") / "assets" / "models"))


#: env ids per baseline task (scenario names map through ``shipgym.envs.registration.SCENARIOS``)
_TASK_IDS = {
    "harbour": (
        "shipgym/Harbour-v0", "shipgym/BlueLadyHarbour-v0", "shipgym/Tracking-v0",
        "shipgym/BlueLadyTracking-v0",
    ),
    "station-keeping": ("shipgym/StationKeeping-v0", "shipgym/BlueLadyStationKeeping-v0"),
}  # fmt: skip


def baseline_task(scenario: str | None) -> str:
    """The baseline task (:data:`BASELINE_TASKS`) of a scenario name or env id.

    ``None``, ``harbour``, ``tracking`` and their ids: ``"harbour"`` (the harbour policies are
    trained on tracking); ``station-keeping`` and its ids: ``"station-keeping"``.

    Raises:
        ValueError: a task no shipped baseline is registered for.
    """
    if scenario is None or scenario in BASELINE_TASKS:
        return scenario or "harbour"
    from shipgym.envs.registration import SCENARIOS

    env_id = SCENARIOS.get(scenario, scenario)
    for task, ids in _TASK_IDS.items():
        if env_id in ids:
            return task
    raise ValueError(
        f"no shipped learned baseline runs {scenario!r} (baselines exist for: "
        f"{', '.join(BASELINE_TASKS)}); pass ppo:PATH or sac:PATH to a model trained for it"
    )


def _shipped_list() -> str:
    return "; ".join(f"{b.label()}: {b.file}" for b in BASELINE_MODELS)


def find_baseline(name: str, task: str | None = None, vessel: Any = None) -> BaselineModel:
    """The shipped baseline of a controller name for a task and vessel (:data:`BASELINE_MODELS`).

    The entry of the task itself wins; without one, station keeping takes the vessel's harbour
    entry (those policies are trained on the tracking task, whose observation and actions every
    positioning task shares: the Blue Lady's ``ppo-residual`` keeps station as it did before).

    Args:
        name: ``ppo``, ``sac`` or ``ppo-residual``.
        task: a baseline task, scenario name or env id (:func:`baseline_task`; default the
            harbour manoeuvre).
        vessel: a vessel name (default ``blue-lady``), a :class:`~shipgym.dynamics.vessel.Vessel`
            or a package path (matched by its folder name).

    Raises:
        ValueError: no baseline of that name, task and vessel; the message lists the shipped
            ones.
    """
    kind = baseline_task(task)
    v = "blue-lady" if vessel is None else getattr(vessel, "name", vessel)
    v = Path(str(v)).name
    # a policy of the task itself, else (station keeping) the vessel's harbour policy: trained
    # on the tracking task, it drives any positioning task of its vessel (same observation)
    for want in dict.fromkeys((kind, "harbour")):
        for b in BASELINE_MODELS:
            if b.name == name and b.task == want and b.vessel == v:
                return b
    algo = "sac" if name == "sac" else "ppo"
    raise ValueError(
        f"no shipped baseline {name!r} for {kind} with vessel {v!r}; shipped: {_shipped_list()}; "
        f"pass {algo}:PATH to a model trained with 'shipgym train {algo}'"
    )


def baseline_model_path(name: str = "ppo", task: str | None = None, vessel: Any = None) -> Path:
    """Path of a shipped baseline (:func:`find_baseline`) in ``shipgym/assets/models``.

    Raises:
        ValueError: no baseline of that name for the task and vessel.
        FileNotFoundError: the baseline is registered but its file is not in the package (not
            added yet, or the package data was not installed); the message names the files
            that are there.
    """
    b = find_baseline(name, task, vessel)
    folder = models_dir()
    p = folder / b.file
    if not p.is_file():
        present = [x.label() for x in BASELINE_MODELS if (folder / x.file).is_file()]
        raise FileNotFoundError(
            f"the shipped baseline {b.label()}, {b.what}, is missing: {p} does not exist "
            "(not shipped yet, or the package data was not installed); shipped here: "
            f"{', '.join(present) or 'none'}; pass {b.algorithm}:PATH to a model file instead"
        )
    return p


def is_learned_controller(name: str) -> bool:
    """``True`` for the baseline names (``ppo``, ``sac``, ``ppo-residual``) and ``ppo:PATH``,
    ``sac:PATH`` (learned-controller names)."""
    name = str(name)
    return name in BASELINE_NAMES or name.split(":", 1)[0] in ALGORITHMS


def parse_learned_controller(
    name: str, *, task: str | None = None, vessel: Any = None
) -> tuple[str, Path]:
    """A baseline name -> its shipped file; ``"ppo:PATH"`` / ``"sac:PATH"`` -> that file.

    Args:
        name: ``ppo``, ``sac``, ``ppo-residual`` (shipped, :data:`BASELINE_MODELS`: chosen by
            ``task`` and ``vessel``), ``ppo:PATH`` or ``sac:PATH``.
        task: scenario name or env id the controller will run (default: the harbour
            manoeuvre); only for the baseline names.
        vessel: the vessel it will drive (default: the Blue Lady); only for the baseline names.

    Returns:
        ``(algorithm, model_path)``; the path is checked to be a shipgym model of that
        algorithm (and, for a baseline, of its residual setup).

    Raises:
        ValueError: not a learned-controller name, no such baseline, or the file's algorithm
            differs.
        FileNotFoundError: no such file (a baseline not shipped yet included).
    """
    name = str(name)
    algo, sep, rest = name.partition(":")
    if not is_learned_controller(name):
        raise ValueError(
            f"not a learned controller: {name!r}; use {', '.join(BASELINE_NAMES)} (shipped "
            "baselines), ppo:PATH or sac:PATH"
        )
    if sep and not rest.strip():
        raise ValueError(
            f"empty model path in {name!r}: use {algo}:PATH (a model trained with 'shipgym train "
            f"{algo}') or a shipped baseline ({', '.join(BASELINE_NAMES)})"
        )
    base = None
    if sep:
        path = Path(rest).expanduser()
    else:
        base = find_baseline(name, task, vessel)
        algo = base.algorithm
        path = baseline_model_path(name, task, vessel)
    meta = read_metadata(path)
    if meta.algorithm != algo:
        raise ValueError(
            f"{path} holds a {meta.algorithm} model, not {algo}: use {meta.algorithm}:"
        )
    if base is not None and meta.residual != base.residual:
        kind = "a residual" if meta.residual else "a pure"
        raise ValueError(f"{path} holds {kind} policy; the baseline {base.label()} is not")
    check_trained_env(meta, path)
    return algo, path


def trained_vessel(meta: ModelMetadata) -> str | None:
    """The vessel a model was trained for: ``blue-lady`` for the Blue Lady ids, else the
    ``vessel`` of its ``env_kwargs`` (``None`` if it names none)."""
    from shipgym.envs.registration import ALIASES

    if meta.env_id in ALIASES:
        return "blue-lady"
    v = meta.env_kwargs.get("vessel")
    return str(v) if isinstance(v, str) else None


def check_trained_env(meta: ModelMetadata, path: str | Path) -> None:
    """Refuse a model trained outside shipgym's environments.

    The three shipgym tasks share one observation and action layout, so a policy trained on
    one of them (the baseline: tracking) runs on any (the harbour manoeuvre is its
    evaluation); its ``env_id`` must be one of them. Results record it (``trained_on``).
    """
    from shipgym.envs.registration import ENV_IDS

    if meta.env_id not in ENV_IDS:
        raise ValueError(
            f"{path} was trained on {meta.env_id!r}, not a shipgym environment; shipgym runs "
            f"models trained on: {', '.join(ENV_IDS)}"
        )


# ---- the wrapper -----------------------------------------------------------------------------
def _stack(env: gym.Env[Any, Any]) -> list[gym.Env[Any, Any]]:
    out = []
    e: Any = env
    while isinstance(e, gym.Wrapper):
        out.append(e)
        e = e.env
    out.append(e)
    return out


class LearnedControllerWrapper(
    gym.Wrapper[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32], NDArray[np.float32]],
    gym.utils.RecordConstructorArgs,
):
    """Runs a trained policy inside ``step``: the learned controller as a Gymnasium wrapper.

    Each step the policy maps the latest observation (the environment's layout: navigation
    data from the observer below, reference, previous action) to a normalised action; the
    wrapper's own action, a *residual* (``Box(-1, 1)`` of the environment's action shape; zero:
    the policy alone) is added and the sum clipped to [-1, 1] (flagged in
    ``info["learned_clipped"]``). For a residual model the environment below must run the DP
    controller it was trained on (``controller=``, same residual scale), whose residual input
    the policy drives.

    Info gains ``policy_action`` (the network's action, before the residual).

    Args:
        env: the environment stack the model expects (see :func:`shipgym.stacks.make_learned_env`).
        model_path: a shipgym model file (``shipgym train``).
        deterministic: use the policy's mean action (default) or sample it.

    Raises:
        ValueError: not a shipgym model, or a residual model on an env without the matching
            DP controller.

    Note:
        Records its constructor arguments, so ``gym.make(env.spec)`` rebuilds the stack.
    """

    def __init__(
        self, env: gym.Env[Any, Any], model_path: str | Path, deterministic: bool = True
    ) -> None:
        gym.utils.RecordConstructorArgs.__init__(
            self, model_path=str(model_path), deterministic=deterministic
        )
        gym.Wrapper.__init__(self, env)
        self.model_path = Path(model_path)
        self.policy = load_policy(self.model_path)
        # the model's metadata; ``self.metadata`` stays the env's (render modes, fps)
        self.model_metadata = self.policy.metadata
        self.deterministic = bool(deterministic)
        _check_stack(env, self.model_metadata)
        vessel = getattr(env.unwrapped, "vessel", None)
        trained = trained_vessel(self.model_metadata)
        if (
            vessel is not None
            and trained is not None
            and vessel.name not in (trained, Path(trained).name)
        ):
            raise ValueError(
                f"{self.model_path.name} was trained on {trained!r} "
                f"({self.model_metadata.env_id}); it cannot drive vessel {vessel.name!r} "
                f"({vessel.actuators.n_channels} actuator channels): train one for that "
                "vessel"
            )
        if env.observation_space.shape != self.model_metadata.observation_shape:
            raise ValueError(
                "the model takes observations of shape "
                f"{self.model_metadata.observation_shape}, the environment gives "
                f"{env.observation_space.shape}"
            )
        shape = tuple(env.action_space.shape or ())
        if shape != self.model_metadata.action_shape:
            raise ValueError(
                f"the model gives actions of shape {self.model_metadata.action_shape}, the "
                f"environment takes {shape}"
            )
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape, np.float32)
        self._obs: NDArray[np.float32] | None = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        obs, info = self.env.reset(seed=seed, options=options)
        self._obs = obs
        return obs, info

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        residual = np.asarray(action, dtype=np.float64)
        n = tuple(self.action_space.shape or ())
        if residual.shape != n or not np.all(np.isfinite(residual)):
            raise ValueError(
                f"residual action must be {math.prod(n)} finite numbers in [-1, 1], got {action!r}"
            )
        if self._obs is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        a_pol = self.policy(self._obs, deterministic=self.deterministic).astype(np.float64)
        total = a_pol + residual
        applied = np.clip(total, -1.0, 1.0)
        obs, reward, terminated, truncated, info = self.env.step(applied.astype(np.float32))
        info["policy_action"] = a_pol
        info["learned_clipped"] = applied != total
        self._obs = obs
        return obs, reward, terminated, truncated, info


def _check_stack(env: gym.Env[Any, Any], meta: ModelMetadata) -> None:
    """Check that ``env`` contains what the model was trained on (controller, observer)."""
    layers = _stack(env)
    base = env.unwrapped
    controller = getattr(base, "controller_name", None)
    if meta.residual:
        if controller is None:
            raise ValueError(
                f"this model is a residual policy on the {meta.controller!r} controller: make "
                f"the environment with controller={meta.controller!r}, residual_scale="
                f"{meta.residual_scale} (shipgym.make), or use make_learned_env()"
            )
        scale = float(getattr(base, "residual_scale", 1.0))
        if controller != meta.controller or not math.isclose(scale, meta.residual_scale):
            raise ValueError(
                f"the model was trained on controller {meta.controller!r} with residual_scale "
                f"{meta.residual_scale}, the environment has {controller!r} with {scale}"
            )
    elif controller is not None:
        raise ValueError(
            "this model drives the thrusters directly (not residual) but the environment runs "
            f"the DP controller {controller!r}: build the stack with make_learned_env()"
        )
    want = bool(policy_env_kwargs(meta.env_kwargs).get("condition_commands", False))
    if (getattr(getattr(base, "batch", base), "conditioning", None) is not None) != want:
        raise ValueError(
            f"the model was trained with condition_commands={want} (the reversal hysteresis "
            f"on its propeller commands) and the environment has the other: build the stack "
            f"with make_learned_env(), or make the env with condition_commands={want}"
        )
    integ = [w for w in layers if type(w).__name__ == "ErrorIntegralObservation"]
    have = getattr(integ[0], "time_constant", None) if integ else None
    if have != meta.error_integral:
        fix = (
            "no ErrorIntegralObservation"
            if meta.error_integral is None
            else f"shipgym.envs.integral.ErrorIntegralObservation(env, time_constant="
            f"{meta.error_integral:g}) on top"
        )
        raise ValueError(
            f"the model was trained with the error integral of time constant "
            f"{meta.error_integral} s appended to its observation; the environment has "
            f"{have}: build the stack with make_learned_env(), or give the env {fix}"
        )
    name = getattr(base, "observer_name", None)
    if name != meta.observer:
        gym.logger.warn(
            f"the model was trained with observer {meta.observer or 'truth'!r}; the environment "
            f"uses {name or 'truth'!r}"
        )
