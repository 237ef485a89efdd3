"""No vessel is a default below the registry (issue 11 item 4).

The public callables of the controllers, observers, disturbances and dynamics take the
vessel's data explicitly; the parameter records have no numeric defaults; the Blue Lady's
named records equal what its vessel package holds.
"""

from __future__ import annotations

import dataclasses
import inspect
import math

import numpy as np
import pytest

import shipgym.controllers
import shipgym.controllers.allocation
import shipgym.controllers.lq
import shipgym.disturbances
import shipgym.dynamics
import shipgym.observers
import shipgym.observers.ekf
from shipgym.controllers.actuation import fixed3_parameters
from shipgym.dynamics import (
    BLUE_LADY_HULL,
    BLUE_LADY_THRUSTERS,
    BLUE_LADY_WINDAGE,
    HullParameters,
    ThrusterParameters,
    WindageParameters,
)
from shipgym.dynamics.vessel import load_vessel
from shipgym.guidance import BLUE_LADY_LIMITS, Leg, Limits, leg_profile

_MODULES = (
    shipgym.controllers,
    shipgym.controllers.allocation,
    shipgym.controllers.lq,
    shipgym.observers,
    shipgym.observers.ekf,
    shipgym.disturbances,
    shipgym.dynamics,
)
_BLUE_LADY_OBJECTS = (BLUE_LADY_HULL, BLUE_LADY_THRUSTERS, BLUE_LADY_WINDAGE, BLUE_LADY_LIMITS)


def _public_callables():
    seen = set()
    for mod in _MODULES:
        for name in getattr(mod, "__all__", dir(mod)):
            obj = getattr(mod, name, None)
            if obj is None or not callable(obj) or id(obj) in seen:
                continue
            seen.add(id(obj))
            yield f"{mod.__name__}.{name}", obj
            if inspect.isclass(obj):
                for mname, meth in vars(obj).items():
                    if callable(meth) and (not mname.startswith("_") or mname == "__init__"):
                        yield f"{mod.__name__}.{name}.{mname}", meth


def test_the_walk_sees_the_callables_that_used_to_default_to_the_blue_lady():
    names = {n.rsplit(".", 1)[-1] for n, _ in _public_callables()}
    for expected in ("allocate", "force_capacity", "thrust", "WindLoad", "Waves", "LQController"):
        assert expected in names


def test_no_public_parameter_defaults_to_a_blue_lady_record():
    bad = []
    for name, obj in _public_callables():
        try:
            sig = inspect.signature(obj)
        except (TypeError, ValueError):
            continue
        for p in sig.parameters.values():
            if any(p.default is o for o in _BLUE_LADY_OBJECTS):
                bad.append(f"{name}({p.name}=...)")
    assert not bad, f"parameters defaulting to the Blue Lady: {bad}"


@pytest.mark.parametrize("cls", [HullParameters, ThrusterParameters, WindageParameters, Limits])
def test_parameter_records_have_no_vessel_defaults(cls):
    with pytest.raises(TypeError):
        cls()


def test_only_the_air_density_keeps_a_default():
    with_default = [
        f.name
        for cls in (HullParameters, ThrusterParameters, WindageParameters, Limits)
        for f in dataclasses.fields(cls)
        if f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING
    ]
    assert with_default == ["rho_a"]


def test_blue_lady_records_equal_its_vessel_package():
    v = load_vessel("blue-lady")
    assert v.hull == BLUE_LADY_HULL
    assert v.windage == BLUE_LADY_WINDAGE
    assert fixed3_parameters(v.actuators) == BLUE_LADY_THRUSTERS
    assert Limits.from_dict(dict(v.limits)) == BLUE_LADY_LIMITS
    # the guidance's limits at 75 % of the thrust capacity in the nominal wind (issue 31)
    assert BLUE_LADY_LIMITS.yaw_rate == math.radians(0.5)
    # the design model of the package is the one printed by Tomera (2014) eqs. 49-50
    np.testing.assert_array_equal(v.design.M, np.diag([23664.9, 24830.6, 455182.1]))
    np.testing.assert_array_equal(v.design.D_L[1], [0.0, 259.8, -855.4])


def _raises_naming(fn, *words):
    with pytest.raises(TypeError) as exc:
        fn()
    for w in words:
        assert w in str(exc.value), str(exc.value)


def test_missing_vessel_data_gives_a_type_error_saying_what_to_pass():
    from shipgym.controllers import MultivariablePID
    from shipgym.controllers.lq import LQController, lq_design, lq_model
    from shipgym.disturbances.waves import Waves
    from shipgym.disturbances.wind import Wind, WindLoad
    from shipgym.dynamics import plant_model, simulate_reference

    _raises_naming(lambda: MultivariablePID("tuned", dt=1.0), "M and D_L", "design")
    _raises_naming(lambda: LQController(dt=1.0), "M and D_L", "load_vessel")
    _raises_naming(lambda: lq_model(), "M and D_L")
    _raises_naming(lambda: lq_design("tuned"), "M and D_L")
    v = load_vessel("blue-lady")
    _raises_naming(
        lambda: MultivariablePID(M=v.design.M, D_L=v.design.D_L), "integral_limit", "capacity"
    )
    _raises_naming(lambda: WindLoad("tanker-loaded"), "windage", "load_vessel")
    _raises_naming(lambda: Wind(), "windage")
    _raises_naming(lambda: Waves(), "hull")
    _raises_naming(lambda: plant_model("default"), "hull")
    _raises_naming(
        lambda: simulate_reference(v.plant(), [0.0, 1.0], [0.0], [[0, 0, 0]]), "actuators"
    )
    _raises_naming(lambda: leg_profile(Leg(surge=1.0)), "limits")


def test_explicit_blue_lady_gives_what_the_package_gives():
    """The named records and the loaded package are interchangeable (same loads)."""
    from shipgym.disturbances.wind import WindLoad

    v = load_vessel("blue-lady")
    a = WindLoad(None, BLUE_LADY_WINDAGE)(0.3, 0.1, 0.0, 3.0, 1.0)
    b = WindLoad(None, v.windage)(0.3, 0.1, 0.0, 3.0, 1.0)
    assert (
        a == b and WindLoad(None, v.windage).coeffs == WindLoad("tanker-loaded", v.windage).coeffs
    )
