"""The observer bench's API: bad arguments fail before any run; failed runs do not poison means."""

import math

import pytest

from shipgym.bench import bench_observers, mean_std, observer_table
from shipgym.envs.physics import VesselPhysics


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"seeds": 0}, "seeds"),
        ({"seeds": -3}, "seeds"),
        ({"seeds": 2.5}, "seeds"),
        ({"workers": 0}, "workers"),
        ({"workers": -1}, "workers"),
        ({"observers": []}, "observers"),
        ({"observers": "kbf"}, "observers"),
    ],
)
def test_bench_observers_refuses_bad_arguments(kwargs, name):
    with pytest.raises(ValueError, match=name):
        bench_observers(**{"observers": ["kbf"], **kwargs})


def test_mean_std_skips_undefined_indices():
    assert mean_std([1.0, 3.0, math.nan, None]) == "2.0000 +- 1.0000"
    assert mean_std([math.nan, None]) == "n/a"


def test_observer_table_keeps_the_completed_runs_mean():
    ok = {"x_E": 0.1, "y_E": 0.2, "psi_E": 0.3, "J_c": 0.4}
    bad = dict.fromkeys(ok, math.nan)
    rmse = {"u": 0.01, "v": 0.02, "r": 0.03}
    rows = [
        {"observer": "kbf", "completed": True, "quay_contact": False, "truth": ok,
         "measured": ok, "rmse": rmse},
        {"observer": "kbf", "completed": False, "quay_contact": True, "truth": bad,
         "measured": bad, "rmse": rmse},
    ]  # fmt: skip
    line = observer_table(rows).splitlines()[2]
    assert "| 1/2 |" in line and "0.4000 +- 0.0000" in line and "nan" not in line


@pytest.mark.parametrize("timestep", [1e-9, 0.0, -0.05, 2.0, math.inf, math.nan])
def test_vessel_physics_bounds_the_timestep(timestep):
    with pytest.raises(ValueError, match="timestep"):
        VesselPhysics("blue-lady", timestep=timestep)
