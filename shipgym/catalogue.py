"""Every name ``shipgym`` accepts, read from the registries (``shipgym list`` prints it).

The command line and the benchmarks validate controller names here before any work
(:func:`check_controller`).
"""

from __future__ import annotations

from typing import Any

from shipgym._text import did_you_mean

__all__ = ["catalogue", "check_controller", "controller_catalogue"]


def catalogue() -> dict[str, Any]:
    """Every name ``shipgym`` accepts, read from the registries (``shipgym list`` prints it).

    Returns:
        A mapping of plain data: ``env_ids``, ``env_scenarios`` (name -> id),
        ``scenario_presets`` (name -> description, the named presets and the packaged files),
        ``controllers`` (name -> description, including the shipped baselines ``ppo``, ``sac``,
        ``ppo-residual`` and ``ppo:PATH``, ``sac:PATH``),
        ``observers``, ``sensor_presets``, ``wave_presets``, ``plans``, ``plant_variants`` (with
        ``vessel_plants``: the vessels that declare variants of their own),
        ``wind_models`` and ``actuators``.
    """
    from shipgym import ENV_IDS
    from shipgym.controllers.batch import CONTROLLERS
    from shipgym.disturbances import BLENDERMANN
    from shipgym.dynamics import ACTUATOR_NAMES, PLANT_VARIANTS
    from shipgym.dynamics.vessel import vessels
    from shipgym.envs.registration import SCENARIOS
    from shipgym.guidance.plan import PLANS
    from shipgym.observers import observer_names
    from shipgym.observers.sensors import SENSOR_PRESETS
    from shipgym.scenarios import SCENARIOS as SCENARIO_PRESETS
    from shipgym.scenarios import WAVE_PRESETS, scenario_files

    ves = vessels()
    presets = {k: v.description for k, v in SCENARIO_PRESETS.items()}
    for stem, path in scenario_files().items():
        presets.setdefault(stem, f"packaged scenario file {path.name}")
    return {
        "env_ids": list(ENV_IDS),
        "env_scenarios": dict(SCENARIOS),
        "scenario_presets": presets,
        "controllers": controller_catalogue(CONTROLLERS),
        "observers": ["truth", *observer_names()],
        "sensor_presets": list(SENSOR_PRESETS),
        "wave_presets": list(WAVE_PRESETS),
        "plans": list(PLANS),
        # the generic variants and every packaged vessel's own ([plants.NAME] of vessel.toml)
        "plant_variants": list(
            dict.fromkeys([*PLANT_VARIANTS, *(p for v in ves.values() for p in v.plants)])
        ),
        "vessel_plants": {n: list(v.plants) for n, v in ves.items() if len(v.plants) > 1},
        "wind_models": [f"blendermann:{k}" for k in BLENDERMANN],
        "actuators": list(ACTUATOR_NAMES),
        "vessels": {
            n: f"{v.title}: {v.dofs} DOF, L_oa {v.L_oa:g} m, "
            + ", ".join(f"{a.name} ({a.label})" for a in v.actuators)
            for n, v in ves.items()
        },
    }


def controller_catalogue(classical: Any = None) -> dict[str, str]:
    """Controller names and descriptions: the classical registry plus the learned names."""
    if classical is None:
        from shipgym.controllers.batch import CONTROLLERS as classical
    from shipgym.controllers.learned import (
        ALGORITHMS,
        BASELINE_MODELS,
        BASELINE_NAMES,
        models_dir,
    )

    out = {name: spec.description for name, spec in classical.items()}
    for name in BASELINE_NAMES:
        out[name] = "shipped baseline: " + "; ".join(
            f"{b.what} ({b.task}, {b.vessel}: shipgym/assets/models/{b.file}"
            f"{'' if (models_dir() / b.file).is_file() else ', not shipped yet'})"
            for b in BASELINE_MODELS
            if b.name == name
        )
    for algo in ALGORITHMS:
        out[f"{algo}:PATH"] = f"a {algo.upper()} model trained with 'shipgym train {algo}'"
    return out


def check_controller(name: str, *, task: str | None = None, vessel: Any = None) -> None:
    """Raise ``ValueError`` (listing every valid name) unless ``name`` is a controller name.

    A shipped learned baseline is looked up for ``task`` (scenario or env id; default the
    harbour manoeuvre) and ``vessel`` (default the Blue Lady); a missing file raises
    ``FileNotFoundError``.
    """
    from shipgym.controllers.learned import is_learned_controller, parse_learned_controller

    if is_learned_controller(name):
        # the file exists and is a shipgym model
        parse_learned_controller(name, task=task, vessel=vessel)
        return
    names = controller_catalogue()
    if name not in names:
        raise ValueError(
            f"unknown controller {name!r}{did_you_mean(name, names)}; choose one of: "
            f"{', '.join(names)}"
        )
