r"""Named scenarios and sea-state presets: Beaufort 0-9, the lake, Tomera's trials.

Sources: WMO (1998), Price & Bishop (1974) and NORSOK N-003 (Beaufort table), Hasselmann
et al. (1973) (JONSWAP), ISO 19901-1 (2015) (NPD gusts), DNV-RP-C205 (2010) (current);
the lake values are the project's own estimates. Full entries: ``docs/references.md``.

Public names: ``ENV_SCENARIOS``, ``BeaufortRow``, ``BEAUFORT_TABLE``, ``beaufort_row``,
``SeaState``, ``beaufort``, ``lake_waves``, ``lake_current``, ...

Design notes: docs/design/scenarios.md.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from shipgym._config import is_real
from shipgym._text import did_you_mean
from shipgym.disturbances.current import CurrentConfig
from shipgym.disturbances.waves import WaveConfig
from shipgym.disturbances.wind import WindConfig
from shipgym.envs.registration import SCENARIOS as ENV_SCENARIOS  # the env scenario names

__all__ = [
    "ENV_SCENARIOS",
    "BeaufortRow",
    "BEAUFORT_TABLE",
    "beaufort_row",
    "SeaState",
    "beaufort",
    "lake_waves",
    "lake_current",
    "lake_current_mapping",
    "LAKE_CURRENT_WIND_FACTOR",
    "WAVE_PRESETS",
    "Scenario",
    "SCENARIOS",
    "scenario_from_dict",
    "load_scenario",
    "scenario_files",
]

from shipgym.disturbances.seastate import (  # noqa: E402 - re-exported
    BEAUFORT_TABLE,
    BeaufortRow,
    SeaState,
    beaufort,
    beaufort_row,
)


def lake_waves(direction_from: float = 0.0, **overrides: Any) -> WaveConfig:
    """The Lake Silm sea of Blue Lady's trials (an estimate of the project).

    Fetch-limited JONSWAP ``Hs = 0.05 m``, ``Tp = 1.0 s``, gamma 3.3, drift on, no first-order
    motion (mm-level for a 13.5 m hull in 1.56 m waves).

    Args:
        direction_from: Direction the waves come from (rad); aligned with the wind (an assumption).
        **overrides: Any other :class:`WaveConfig` field.
    """
    kw: dict[str, Any] = {
        "spectrum": "jonswap",
        "Hs": 0.05,
        "Tp": 1.0,
        "gamma": 3.3,
        "direction_from": float(direction_from),
        "drift": True,
        "first_order": False,
    }
    kw.update(overrides)
    return WaveConfig(**kw)


#: wind-driven lake current as a fraction of the wind speed (-): DNV-RP-C205 (2010) k U10,
#: k = 0.015-0.03 at the surface, about 0.01 averaged over Blue Lady's draft (an estimate);
#: chosen 1/300 (0.01 m/s in the trial's 3 m/s wind): with 0.03 m/s the harbour manoeuvre
#: with the corrected sway added mass completes 2 of 10 runs (the bow tunnel at its limit
#: ~60 % of the time), 0.015 m/s 9 of 10, 0.01 m/s 10 of 10; the real trial completed
LAKE_CURRENT_WIND_FACTOR = 1.0 / 300.0


def lake_current_mapping(wind_speed: float = 3.0, wind_from_deg: float = 300.0) -> dict:
    """The scenario-file form of :func:`lake_current` (what ``current:`` of a scenario file
    holds for it; the packaged ``tomera2014-lake.yaml`` writes it out)."""
    if not is_real(wind_speed) or not 0.0 <= wind_speed < math.inf:
        raise ValueError(f"lake_current: wind_speed must be a number >= 0 m/s, got {wind_speed!r}")
    if not is_real(wind_from_deg) or not math.isfinite(wind_from_deg):
        raise ValueError(f"lake_current: wind_from_deg must be finite, got {wind_from_deg!r}")
    return {
        "speed": round(LAKE_CURRENT_WIND_FACTOR * float(wind_speed), 12),
        "direction_to_deg": (float(wind_from_deg) + 180.0) % 360.0,
        "std": 0.01,
        "time_constant": 300.0,
        "direction_std_deg": 10.0,
        "direction_time_constant": 300.0,
    }


def lake_current(
    wind_speed: float = 3.0, wind_from_deg: float = 300.0, **overrides: Any
) -> CurrentConfig:
    """The wind-driven current of Lake Silm for a wind (an estimate of the project).

    Mean speed :data:`LAKE_CURRENT_WIND_FACTOR` times the wind speed (0.01 m/s for the trial's
    3 m/s), going where the wind goes (``wind_from + 180 deg``); slowly varying: speed std
    0.01 m/s and direction std 10 deg, both Gauss-Markov with time constant 300 s (Fossen
    2011 ch. 8.3 form; the numbers are estimates); speed kept >= 0.

    Args:
        wind_speed: mean wind speed (m/s).
        wind_from_deg: direction the wind comes from (deg).
        **overrides: any :class:`CurrentConfig` field (SI units, radians).
    """
    cfg = _current(lake_current_mapping(wind_speed, wind_from_deg), None, "lake_current")
    assert cfg is not None
    return dataclasses.replace(cfg, **overrides) if overrides else cfg


def _calm_waves(direction_from: float = 0.0, **overrides: Any) -> WaveConfig:
    return WaveConfig(**{"Hs": 0.0, "direction_from": float(direction_from), **overrides})


#: Named wave presets: ``name -> factory(direction_from=0.0, **overrides)``.
WAVE_PRESETS: dict[str, Callable[..., WaveConfig]] = {"lake": lake_waves, "calm": _calm_waves}

# ---------------------------------------------------------------------------------------------
# Scenario
# ---------------------------------------------------------------------------------------------


def _plant_names() -> tuple[str, ...]:
    from shipgym.dynamics.model import PLANT_VARIANTS

    return tuple(PLANT_VARIANTS)


def _sensor_presets() -> tuple[str, ...]:
    from shipgym.observers.sensors import SENSOR_PRESETS

    return tuple(SENSOR_PRESETS)


def _plan_names() -> tuple[str, ...]:
    from shipgym.guidance.plan import PLANS

    return tuple(PLANS)


@dataclass(frozen=True)
class Scenario:
    """Everything an episode needs besides the agent (validated on construction).

    Attributes:
        name: Scenario name.
        env: Environment scenario: ``harbour``, ``station-keeping`` or ``tracking``.
        plant: Plant variant (``shipgym.dynamics.model.PLANT_VARIANTS``).
        wind: Wind, or ``None`` for no wind.
        waves: Waves, or ``None`` for none.
        current: Current, or ``None`` for none.
        sensors: Sensor preset name, a ``SensorConfig``, or ``None`` (no sensors).
        plan: Plan name, a ``ManoeuvrePlan``, or ``None`` (the environment's default plan).
        start_pose: NED start pose ``(x m, y m, psi rad)``.
        description: Free text.
    """

    name: str
    env: str = "harbour"
    plant: str = "default"
    wind: WindConfig | None = None
    waves: WaveConfig | None = None
    current: CurrentConfig | None = None
    sensors: Any = "default"
    plan: Any = None
    start_pose: tuple[float, float, float] = (0.0, 0.0, 0.0)
    description: str = ""

    def __post_init__(self) -> None:
        from shipgym.guidance.plan import ManoeuvrePlan
        from shipgym.observers.sensors import SensorConfig

        where = f"scenario {self.name!r}"
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"scenario name must be a non-empty string, got {self.name!r}")
        if self.env not in ENV_SCENARIOS:
            raise ValueError(
                f"{where}: unknown env {self.env!r}{did_you_mean(self.env, ENV_SCENARIOS)}; "
                f"valid names are: {', '.join(ENV_SCENARIOS)}"
            )
        if self.plant not in _plant_names():
            raise ValueError(
                f"{where}: unknown plant variant {self.plant!r}"
                f"{did_you_mean(self.plant, _plant_names())}; valid names are: "
                f"{', '.join(_plant_names())}"
            )
        for key, cls in (("wind", WindConfig), ("waves", WaveConfig), ("current", CurrentConfig)):
            val = getattr(self, key)
            if val is not None and not isinstance(val, cls):
                raise ValueError(f"{where}: {key} must be a {cls.__name__} or None, got {val!r}")
        s = self.sensors
        if isinstance(s, str):
            if s not in _sensor_presets():
                raise ValueError(
                    f"{where}: unknown sensor preset {s!r}"
                    f"{did_you_mean(s, _sensor_presets())}; valid names are: "
                    f"{', '.join(_sensor_presets())}"
                )
        elif s is not None and not isinstance(s, SensorConfig):
            raise ValueError(
                f"{where}: sensors must be a preset name, a SensorConfig or None, got {s!r}"
            )
        p = self.plan
        if isinstance(p, str):
            if p not in _plan_names():
                raise ValueError(
                    f"{where}: unknown plan {p!r}{did_you_mean(p, _plan_names())}; valid "
                    f"names are: {', '.join(_plan_names())}"
                )
        elif p is not None and not isinstance(p, ManoeuvrePlan):
            raise ValueError(
                f"{where}: plan must be a plan name, a ManoeuvrePlan or None, got {p!r}"
            )
        object.__setattr__(self, "start_pose", _pose(self.start_pose, f"{where}: start_pose"))
        if not isinstance(self.description, str):
            raise ValueError(f"{where}: description must be a string, got {self.description!r}")

    @property
    def env_id(self) -> str:
        """The registered Gymnasium id of :attr:`env`."""
        return ENV_SCENARIOS[self.env]

    def env_kwargs(self) -> dict[str, Any]:
        """Keyword arguments for the environment (``shipgym.make(self.env, **kwargs)``).

        Returns:
            ``plant``, ``wind`` (``WindConfig`` or ``None``), ``waves`` (``WaveConfig`` or
            ``None``), ``current`` (``CurrentConfig`` or ``None``), ``sensors``,
            ``start_pose`` and, unless it is ``None`` (the environment's default), ``plan``.
        """
        kw: dict[str, Any] = {
            "plant": self.plant,
            "wind": self.wind,
            "waves": self.waves,
            "current": self.current,
            "sensors": self.sensors,
            "start_pose": self.start_pose,
        }
        if self.plan is not None:
            kw["plan"] = self.plan
        return kw

    def make(self, **overrides: Any) -> Any:
        """``shipgym.make(self.env, **self.env_kwargs(), **overrides)`` (imports MuJoCo)."""
        import shipgym

        kw = self.env_kwargs()
        kw.update(overrides)
        return shipgym.make(self.env, **kw)

    def replace(self, **changes: Any) -> Scenario:
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """Plain data that :func:`scenario_from_dict` reads back (SI units, radians)."""
        from shipgym.observers.sensors import SensorConfig

        def cfg(c: Any) -> Any:
            return (
                None if c is None else {f.name: getattr(c, f.name) for f in dataclasses.fields(c)}
            )

        s = self.sensors
        sensors = s.to_dict() if isinstance(s, SensorConfig) else s
        if isinstance(sensors, dict) and "antenna_offset" in sensors:
            sensors["antenna_offset"] = list(sensors["antenna_offset"])
        p = self.plan
        return {
            "name": self.name,
            "description": self.description,
            "env": self.env,
            "plant": self.plant,
            "wind": cfg(self.wind),
            "waves": cfg(self.waves),
            "current": cfg(self.current),
            "sensors": sensors,
            "plan": p if p is None or isinstance(p, str) else p.to_dict(),
            "start_pose": list(self.start_pose),
        }


def _pose(value: Any, where: str) -> tuple[float, float, float]:
    if isinstance(value, Mapping):
        _reject(value, ("x", "y", "psi", "psi_deg"), where)
        d = _angles(value, ("psi",), where)
        vals = [d.get("x", 0.0), d.get("y", 0.0), d.get("psi", 0.0)]
    elif isinstance(value, list | tuple):
        vals = list(value)
    else:
        try:
            vals = list(value)
        except TypeError:
            vals = [value]
    if len(vals) != 3 or not all(is_real(v) and math.isfinite(v) for v in vals):
        raise ValueError(
            f"{where} must be three finite numbers (x m, y m, psi rad) or a mapping "
            f"{{x, y, psi | psi_deg}}, got {value!r}"
        )
    return (float(vals[0]), float(vals[1]), float(vals[2]))


def _reject(d: Mapping[str, Any], valid: tuple[str, ...] | list[str], where: str) -> None:
    unknown = sorted(str(k) for k in set(d) - set(valid))
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {unknown}; valid keys are: {', '.join(valid)}")


def _angles(d: Mapping[str, Any], names: tuple[str, ...], where: str) -> dict[str, Any]:
    """Copy of ``d`` with every ``<name>_deg`` key turned into ``<name>`` in radians."""
    out = dict(d)
    for name in names:
        dk = f"{name}_deg"
        if dk in out:
            if name in out:
                raise ValueError(f"{where}: give either '{name}' (rad) or '{dk}' (deg), not both")
            val = out.pop(dk)
            if not is_real(val) or not math.isfinite(val):
                raise ValueError(f"{where}: {dk} must be a finite number of degrees, got {val!r}")
            out[name] = math.radians(val)
    return out


def _fields(cls: type) -> list[str]:
    return [f.name for f in dataclasses.fields(cls)]


def _config(
    cls: type,
    value: Mapping[str, Any],
    current: Any,
    where: str,
    angle_names: tuple[str, ...],
    extra: tuple[str, ...] = (),
) -> Any:
    """A config from a mapping applied over ``current`` (or the defaults), with clear errors."""
    valid = _fields(cls)
    _reject(value, valid + [f"{a}_deg" for a in angle_names] + list(extra), where)
    d = _angles(value, angle_names, where)
    base = {} if current is None else {f: getattr(current, f) for f in valid}
    base.update(d)
    try:
        return cls(**base)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None


def _wind(value: Any, current: WindConfig | None, where: str) -> WindConfig | None:
    if value is None or value is False:
        return None
    if isinstance(value, str):
        return WindConfig.parse(value, name=where)
    if not isinstance(value, Mapping):
        raise ValueError(
            f"{where} must be a mapping of WindConfig fields, 'SPEED@FROM_DEG' (e.g. '3@300'), "
            f"null or false, got {value!r}"
        )
    return _config(WindConfig, value, current, where, ("direction_from", "direction_std"))


def _waves(value: Any, current: WaveConfig | None, where: str) -> WaveConfig | None:
    if value is None or value is False:
        return None
    if isinstance(value, str):
        value = {"preset": value}
    if not isinstance(value, Mapping):
        raise ValueError(
            f"{where} must be a preset name ({', '.join(WAVE_PRESETS)}), a mapping of "
            f"WaveConfig fields, null or false, got {value!r}"
        )
    value = dict(value)
    if "preset" in value:
        name = value.pop("preset")
        if name not in WAVE_PRESETS:
            raise ValueError(
                f"{where}: unknown wave preset {name!r}{did_you_mean(name, WAVE_PRESETS)}; "
                f"valid names are: {', '.join(WAVE_PRESETS)}"
            )
        d = current.direction_from if current is not None else 0.0
        current = WAVE_PRESETS[name](direction_from=d)
    return _config(
        WaveConfig, value, current, where, ("direction_from", "wf_heading_std"), ("preset",)
    )


def _current(value: Any, current: CurrentConfig | None, where: str) -> CurrentConfig | None:
    if value is None or value is False:
        return None
    if isinstance(value, str):
        return CurrentConfig.parse(value, name=where)
    if not isinstance(value, Mapping):
        raise ValueError(
            f"{where} must be a mapping of CurrentConfig fields, 'SPEED@TO_DEG' (e.g. '0.1@90'), "
            f"null or false, got {value!r}"
        )
    d = dict(value)
    # convenience: stationary std and time constant instead of (mu, sigma), for the speed
    # and for the direction (degrees allowed)
    if "direction_std_deg" in d:
        if "direction_std" in d:
            raise ValueError(f"{where}: give either 'direction_std' (rad) or 'direction_std_deg'")
        deg = d.pop("direction_std_deg")
        if not is_real(deg) or not math.isfinite(deg):
            raise ValueError(f"{where}: direction_std_deg must be a finite number, got {deg!r}")
        d["direction_std"] = math.radians(deg)
    for pre, unit, sigma_unit in (("", "m/s", "m/s^1.5"), ("direction_", "rad", "rad/s^0.5")):
        _gauss_markov_keys(d, where, pre, unit, sigma_unit, current)
    valid = _fields(CurrentConfig)
    _reject(
        value,
        valid + ["direction_to_deg", "std", "time_constant", "direction_std", "direction_std_deg",
                 "direction_time_constant"],
        where,
    )  # fmt: skip
    return _config(CurrentConfig, d, current, where, ("direction_to",))


def _gauss_markov_keys(
    d: dict[str, Any], where: str, pre: str, unit: str, sigma_unit: str, current: Any
) -> None:
    """Turn ``{pre}time_constant`` (s) into ``{pre}mu`` (1/s) and ``{pre}std`` (``unit``) into
    ``{pre}sigma`` (``sigma_unit``) of a current's Gauss-Markov process, in place: the
    stationary std of ``x_dot = -mu x + sigma w`` is ``sigma / sqrt(2 mu)``."""
    mu_key, tc_key, sigma_key, std_key = (pre + k for k in ("mu", "time_constant", "sigma", "std"))
    if tc_key in d:
        if mu_key in d:
            raise ValueError(f"{where}: give either '{mu_key}' (1/s) or '{tc_key}' (s), not both")
        tc = d.pop(tc_key)
        if not is_real(tc) or not tc > 0 or not math.isfinite(tc):
            raise ValueError(f"{where}: {tc_key} must be a number > 0 s, got {tc!r}")
        d[mu_key] = 1.0 / tc
    if std_key in d:
        if sigma_key in d:
            raise ValueError(
                f"{where}: give either '{sigma_key}' ({sigma_unit}) or '{std_key}' ({unit}), "
                "not both"
            )
        std = d.pop(std_key)
        if not is_real(std) or not std >= 0 or not math.isfinite(std):
            raise ValueError(f"{where}: {std_key} must be a number >= 0 {unit}, got {std!r}")
        default = getattr(current if current is not None else CurrentConfig(), mu_key)
        mu = d.get(mu_key, default)
        if not (is_real(mu) and mu > 0):
            raise ValueError(
                f"{where}: '{std_key}' needs {mu_key} > 0 (or {tc_key}), got {mu_key} = {mu!r}"
            )
        d[sigma_key] = std * math.sqrt(2.0 * mu)


def _sensors(value: Any, where: str) -> Any:
    from shipgym.observers.sensors import SensorConfig, sensor_config

    if value is None or value is False:
        return None
    if isinstance(value, str):
        if value not in _sensor_presets():
            raise ValueError(
                f"{where}: unknown sensor preset {value!r}"
                f"{did_you_mean(value, _sensor_presets())}; valid names are: "
                f"{', '.join(_sensor_presets())}"
            )
        return value
    if isinstance(value, SensorConfig):
        return value
    if not isinstance(value, Mapping):
        raise ValueError(
            f"{where} must be a preset name, a mapping of SensorConfig fields, null or false, "
            f"got {value!r}"
        )
    d = dict(value)
    name = d.pop("preset", "default")
    if name not in _sensor_presets():
        raise ValueError(
            f"{where}: unknown sensor preset {name!r}"
            f"{did_you_mean(name, _sensor_presets())}; valid names are: "
            f"{', '.join(_sensor_presets())}"
        )
    _reject(d, _fields(SensorConfig), where)
    try:
        return sensor_config(name, **d)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None


def _plan(value: Any, where: str) -> Any:
    from shipgym.guidance.plan import ManoeuvrePlan

    if value is None:
        return None
    if isinstance(value, str):
        if value not in _plan_names():
            raise ValueError(
                f"{where}: unknown plan {value!r}{did_you_mean(value, _plan_names())}; valid "
                f"names are: {', '.join(_plan_names())}"
            )
        return value
    if isinstance(value, ManoeuvrePlan):
        return value
    if not isinstance(value, Mapping):
        raise ValueError(
            f"{where} must be a plan name or a mapping for ManoeuvrePlan.from_dict, got {value!r}"
        )
    try:
        return ManoeuvrePlan.from_dict(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None


_BF_KEYS = (
    "number",
    "scale",
    "direction_from",
    "direction_from_deg",
    "gamma",
    "gust_spectrum",
    "first_order",
    "drift",
    "wf_model",
)


def _beaufort(value: Any, where: str) -> SeaState:
    if isinstance(value, Mapping):
        _reject(value, _BF_KEYS, where)
        d = _angles(value, ("direction_from",), where)
        if "number" not in d:
            raise ValueError(f"{where}: missing 'number' (the Beaufort number 0-9)")
        n = d.pop("number")
    else:
        n, d = value, {}
    try:
        return beaufort(n, **d)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None


#: Top-level keys of a scenario file or mapping.
SCENARIO_KEYS = (
    "name",
    "description",
    "base",
    "env",
    "plant",
    "beaufort",
    "wind",
    "waves",
    "current",
    "sensors",
    "plan",
    "start_pose",
)


def scenario_from_dict(data: Mapping[str, Any], *, name: str | None = None) -> Scenario:
    """Build and validate a :class:`Scenario` from plain data (parsed YAML/TOML).

    Args:
        data: The mapping (keys: :data:`SCENARIO_KEYS`, see the module docstring).
        name: Default name when ``data`` has none (e.g. the file stem).

    Returns:
        The scenario.

    Raises:
        ValueError: For any unknown key (listing the valid ones) or bad value; the message
            names the offending key.
    """
    if not isinstance(data, Mapping):
        raise ValueError(f"a scenario must be a mapping of keys, got {type(data).__name__}")
    label = data.get("name", name) or "scenario"
    where = f"scenario {label!r}"
    _reject(data, SCENARIO_KEYS, where)
    for key in ("name", "description", "base", "env", "plant"):
        if key in data and not isinstance(data[key], str):
            raise ValueError(f"{where}: {key} must be a string, got {data[key]!r}")
    if "base" in data:
        if data["base"] not in SCENARIOS:
            raise ValueError(
                f"{where}: unknown base scenario {data['base']!r}"
                f"{did_you_mean(data['base'], SCENARIOS)}; valid names are: "
                f"{', '.join(SCENARIOS)}"
            )
        base = SCENARIOS[data["base"]]
    else:
        base = Scenario(name=str(label))
    wind, waves, current = base.wind, base.waves, base.current
    if "beaufort" in data:
        wind, waves = _beaufort(data["beaufort"], f"{where}: beaufort")
    if "wind" in data:
        wind = _wind(data["wind"], wind, f"{where}: wind")
    if "waves" in data:
        waves = _waves(data["waves"], waves, f"{where}: waves")
    if "current" in data:
        current = _current(data["current"], current, f"{where}: current")
    kw: dict[str, Any] = {
        "name": str(label),
        "wind": wind,
        "waves": waves,
        "current": current,
        "description": data.get("description", base.description),
        "env": data.get("env", base.env),
        "plant": data.get("plant", base.plant),
        "sensors": _sensors(data["sensors"], f"{where}: sensors")
        if "sensors" in data
        else base.sensors,
        "plan": _plan(data["plan"], f"{where}: plan") if "plan" in data else base.plan,
        "start_pose": _pose(data["start_pose"], f"{where}: start_pose")
        if "start_pose" in data
        else base.start_pose,
    }
    return Scenario(**kw)


def scenario_files() -> dict[str, Path]:
    """The packaged example scenario files, ``stem -> path`` (``shipgym/assets/scenarios``)."""
    from importlib import resources

    folder = Path(str(resources.files("shipgym.assets").joinpath("scenarios")))
    if not folder.is_dir():
        return {}
    return {p.stem: p for p in sorted(folder.iterdir()) if p.suffix in (".yaml", ".yml", ".toml")}


def _read_file(path: Path) -> Any:
    """Plain data of a scenario file, bounded (:mod:`shipgym._safeload`: at most 1 MiB, YAML
    through libyaml's safe loader when present, no Python objects)."""
    from shipgym._safeload import load_config_file

    return load_config_file(path, "scenario file")


def load_scenario(name_or_path: str | Path) -> Scenario:
    """A named scenario, a packaged example file by stem, or a YAML / TOML file.

    Args:
        name_or_path: A key of :data:`SCENARIOS`, the stem of a packaged file
            (:func:`scenario_files`), or a path ending in ``.yaml``, ``.yml`` or ``.toml``.

    Returns:
        The validated scenario.

    Raises:
        ValueError: Unknown name (the message lists the valid ones), unreadable or invalid
            file (the message names the bad key / value).
        FileNotFoundError: A path that does not exist.
    """
    if isinstance(name_or_path, str) and name_or_path in SCENARIOS:
        return SCENARIOS[name_or_path]
    files = scenario_files()
    if isinstance(name_or_path, str) and name_or_path in files:
        path = files[name_or_path]
    else:
        path = Path(name_or_path)
        if path.suffix not in (".yaml", ".yml", ".toml"):
            raise ValueError(
                f"unknown scenario {str(name_or_path)!r}"
                f"{did_you_mean(str(name_or_path), [*SCENARIOS, *files])}; valid names are: "
                f"{', '.join(list(SCENARIOS) + [f for f in files if f not in SCENARIOS])}; "
                "or give a .yaml / .toml file"
            )
        if not path.exists():
            raise FileNotFoundError(f"scenario file {str(path)!r} does not exist")
    data = _read_file(path)
    if data is None:
        data = {}
    if not isinstance(data, Mapping):
        raise ValueError(
            f"scenario file {str(path)!r} must hold a mapping of keys, got {type(data).__name__}"
        )
    try:
        return scenario_from_dict(data, name=path.stem)
    except ValueError as exc:
        raise ValueError(f"{path.name}: {exc}") from None


# ---------------------------------------------------------------------------------------------
# Named presets
# ---------------------------------------------------------------------------------------------


def _presets() -> dict[str, Scenario]:
    out: dict[str, Scenario] = {}
    out["calm"] = Scenario(
        name="calm",
        env="harbour",
        wind=None,
        plan="tomera2014",
        description="The harbour manoeuvre in calm water: no wind, waves or current.",
    )
    d300 = math.radians(300.0)
    out["tomera2014-lake"] = Scenario(
        name="tomera2014-lake",
        env="harbour",
        wind=WindConfig.from_speed_dir(3.0, 300.0),
        waves=lake_waves(direction_from=d300),
        current=lake_current(3.0, 300.0),
        sensors="tomera2014-lake",
        plan="tomera2014",
        description=(
            "Blue Lady's lake trial (Tomera 2014): the 5-leg harbour manoeuvre on "
            "Lake Silm, wind 3 m/s from 300 deg with Gauss-Markov gusts, small fetch-limited "
            "JONSWAP waves from the same direction (Hs 0.05 m, Tp 1 s, drift only; estimated), "
            "a wind-driven current of 0.01 m/s going to 120 deg (slowly varying; estimated), "
            "DGPS with Gauss-Markov errors and a gyrocompass bias."
        ),
    )
    out["tomera2011-sim"] = Scenario(
        name="tomera2011-sim",
        env="harbour",
        wind=WindConfig.from_speed_dir(2.0, 0.0),
        waves=None,
        sensors="default",
        plan="tomera2014",
        description=(
            "The simulation study of Tomera (2011): wind 2 m/s from 0 deg with "
            "Gauss-Markov gusts, no waves, its sensor noise; the manoeuvre of the study "
            "is not given there, the harbour plan of Tomera (2014) is used."
        ),
    )
    for n in range(10):
        row = BEAUFORT_TABLE[n]
        wind, waves = beaufort(n, 24.0)
        out[f"beaufort{n}"] = Scenario(
            name=f"beaufort{n}",
            env="station-keeping",
            wind=wind,
            waves=waves,
            sensors="default",
            description=(
                f"Station keeping in Beaufort {n} ({row.name}) Froude-scaled to 1:24: wind "
                f"{wind.speed:.2f} m/s (NPD gusts), JONSWAP Hs {waves.Hs:.3f} m, Tp "
                f"{waves.Tp:.2f} s, first-order motion and drift."
            ),
        )
    return out


#: Named scenario presets (:func:`load_scenario` also finds the packaged example files).
SCENARIOS: dict[str, Scenario] = _presets()
