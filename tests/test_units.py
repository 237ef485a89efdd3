"""One unit convention at every public boundary (issue 10, item 3).

Every entry point that takes a wind or a current (the env via ``gym.make`` for every id,
``shipgym.make``, :class:`VesselPhysics` and its setters, ``run_episode``, the CLI's
``--wind``, scenario mappings, the benchmarks) is fed the same wind and current in every
accepted form; the load on the hull must be the same. Plain-number directions are DEGREES
everywhere: wind where it comes FROM, current where it goes TO. The absolute numbers are
checked against Blendermann's (1994) formulas written out here and against the geometry of
the current, not against the code's own output.
"""

import math

import gymnasium as gym
import numpy as np
import pytest

import shipgym
from shipgym import cli
from shipgym.disturbances import CurrentConfig, WindConfig
from shipgym.disturbances.current import MAX_CURRENT_SPEED
from shipgym.disturbances.wind import MAX_WIND_SPEED
from shipgym.dynamics.params import BLUE_LADY_WINDAGE
from shipgym.envs.physics import VesselPhysics
from shipgym.envs.registration import ALIASES
from shipgym.scenarios import scenario_from_dict

IDS = list(ALIASES)  # the Blue Lady ids (every vessel x task: test_vessel_envs.py)

#: 3 m/s from 300 deg with the default gusts, and 0.1 m/s going to 90 deg (east)
REF_WIND = WindConfig(speed=3.0, direction_from=math.radians(300.0))
REF_CURRENT = CurrentConfig(speed=0.1, direction_to=math.radians(90.0))

WIND_FORMS = [
    "3@300",
    " 3 @ 300 ",
    (3, 300),
    [3.0, 300.0],
    np.array([3.0, 300.0]),
    (np.float64(3.0), np.int64(300)),
    {"speed": 3.0, "direction_from_deg": 300.0},
    {"speed": 3.0, "direction_from": math.radians(300.0)},
    WindConfig.parse("3@300"),
    WindConfig.from_speed_dir(3.0, 300.0),
    cli.parse_wind("3@300"),
]
CURRENT_FORMS = [
    "0.1@90",
    (0.1, 90),
    [0.1, 90.0],
    np.array([0.1, 90.0]),
    {"speed": 0.1, "direction_to_deg": 90.0},
    {"speed": 0.1, "direction_to": math.pi / 2},
    CurrentConfig.parse("0.1@90"),
    CurrentConfig.from_speed_dir(0.1, 90.0),
]
#: a few pairs for the slower entry points (each form appears at least once)
PAIRS = list(zip(WIND_FORMS, CURRENT_FORMS + CURRENT_FORMS, strict=False))


def _id(x):
    return type(x).__name__ + ":" + (x if isinstance(x, str) else "")


@pytest.mark.parametrize("form", WIND_FORMS, ids=_id)
def test_every_wind_form_is_the_same_config(form):
    assert WindConfig.coerce(form) == REF_WIND


@pytest.mark.parametrize("form", CURRENT_FORMS, ids=_id)
def test_every_current_form_is_the_same_config(form):
    assert CurrentConfig.coerce(form) == REF_CURRENT


def test_regressions_of_the_old_radian_tuples():
    # the CLI parser's output fed to the env's coercion is still 3 m/s from 300 deg (it was a
    # wind from 300 rad -> 5.2 deg, because the CLI gave radians and the env read degrees)
    w = WindConfig.coerce(cli.parse_wind("3@300"))
    assert w.direction_from == pytest.approx(math.radians(300.0), abs=1e-15)
    # VesselPhysics("blue-lady", current=(0.1, 90)) is 90 deg (east), not 90 rad
    phys = VesselPhysics("blue-lady", current=(0.1, 90))
    assert phys.current_config.direction_to == pytest.approx(math.pi / 2, abs=1e-15)
    # heading north at rest, a current going east is 0.1 m/s to starboard in the body frame
    assert phys.nu_c == pytest.approx((0.0, 0.1), abs=1e-15)
    phys.set_current((0.2, 180))  # going south: straight astern
    phys.reset()
    assert phys.nu_c == pytest.approx((-0.2, 0.0), abs=1e-15)


def _env_trace(make, seed=3, steps=4):
    env = make()
    _, info = env.reset(seed=seed)
    out = [info["tau_wind"], info["current_body"], info["eta"]]
    action = np.array([0.4, 0.3, -0.2], np.float32)
    for _ in range(steps):
        _, _, _, _, info = env.step(action)
        out += [info["tau_wind"], info["current_body"], info["eta"]]
    u = env.unwrapped
    assert u.physics.wind_config == REF_WIND and u.wind_config is u.physics.wind_config
    assert u.physics.current_config == REF_CURRENT and u.current_config is u.physics.current_config
    env.close()
    return np.array(out)


@pytest.mark.parametrize("env_id", IDS)
def test_gym_make_every_form_gives_the_same_load(env_id):
    ref = None
    for wind in WIND_FORMS:
        for current in CURRENT_FORMS[:2] if wind is not WIND_FORMS[0] else CURRENT_FORMS:
            trace = _env_trace(lambda w=wind, c=current: gym.make(env_id, wind=w, current=c))
            if ref is None:
                ref = trace
                assert np.abs(ref[0]).max() > 1.0  # a real wind load (N) at the start
            np.testing.assert_array_equal(trace, ref)


def test_shipgym_make_and_the_controller_stack_give_the_same_load():
    traces = [
        _env_trace(lambda w=w, c=c: shipgym.make("harbour", controller="pid", wind=w, current=c))
        for w, c in PAIRS
    ]
    for t in traces[1:]:
        np.testing.assert_array_equal(t, traces[0])


def _physics_trace(phys):
    phys.reset(rng=np.random.default_rng(7))
    phys.set_command([300.0, 0.5, -0.5])
    out = [(*phys.tau_wind, *phys.nu_c)]
    for _ in range(5):
        phys.step(10)
        out.append((*phys.tau_wind, *phys.nu_c))
    assert phys.wind_config == REF_WIND and phys.current_config == REF_CURRENT
    return np.array(out)


def test_vessel_physics_and_its_setters_take_every_form():
    ref = _physics_trace(VesselPhysics("blue-lady", wind=WIND_FORMS[0], current=CURRENT_FORMS[0]))
    for w, c in PAIRS:
        np.testing.assert_array_equal(
            _physics_trace(VesselPhysics("blue-lady", wind=w, current=c)), ref
        )
        phys = VesselPhysics("blue-lady", wind=None, current=None)
        phys.set_wind(w)
        phys.set_current(c)
        np.testing.assert_array_equal(_physics_trace(phys), ref)


@pytest.mark.parametrize(("wind", "current"), PAIRS[:4], ids=lambda x: _id(x))
def test_run_episode_takes_every_form(wind, current):
    res = cli.run_episode(
        "harbour", wind=wind, env_kwargs={"current": current, "max_episode_steps": 3}
    )
    ref = cli.run_episode(
        "harbour", env_kwargs={"current": REF_CURRENT, "max_episode_steps": 3}
    )  # the default wind of the harbour task is 3@300
    assert res["wind"] == {"speed": 3.0, "from_deg": pytest.approx(300.0)}
    # a 3-step run is too short for the accuracy indices (NaN with a note): compare the
    # partial ones, which are computed from the same trajectory
    for key in ("x_E", "y_E", "psi_E", "J_c"):
        assert res["partial_indices"]["truth"][key] == ref["partial_indices"]["truth"][key]
    for key in ("thrust_mean_abs", "duration_s"):
        assert res[key] == ref[key]


@pytest.mark.parametrize(
    "argv",
    [["run", "harbour"], ["demo"], ["bench", "observers"], ["bench", "controllers"]],
)
def test_cli_wind_argument_is_a_wind_config(argv):
    parser = cli._parser()
    for text in ("3@300", "3.0@300.0", "3@-60"):
        args = parser.parse_args([*argv, "--wind", text])
        assert isinstance(args.wind, WindConfig)
        assert args.wind.speed == 3.0
        assert math.cos(args.wind.direction_from - REF_WIND.direction_from) == pytest.approx(1.0)
    default = parser.parse_args(argv).wind
    # run and the benches: None = the scenario's wind (3@300 for bench observers without a
    # --scenario and for the Blue Lady's harbour in bench controllers, the vessel's nominal
    # wind for its station keeping; resolved when the command runs)
    if argv[0] == "run" or argv[0] == "bench":
        assert default is None
    else:
        assert default == REF_WIND


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("10000@0", "WindConfig.speed must be <= 70 m/s"),
        ("nan@0", "finite"),
        ("3@inf", "finite"),
        ("-3@0", ">= 0"),
        ("3 from 300", "expected SPEED@FROM_DEG"),
        ("3@", "expected SPEED@FROM_DEG"),
        ("3_0@300", "expected SPEED@FROM_DEG"),
        ("3@300deg", "expected SPEED@FROM_DEG"),
    ],
)
def test_cli_bad_wind_is_a_one_line_error(text, match, capsys):
    try:
        rc = cli.main(["run", "harbour", f"--wind={text}"])
    except SystemExit as exc:  # plain argparse exits; a one-line parser may return instead
        rc = exc.code
    assert rc == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    last = err.strip().splitlines()[-1]
    assert "error: argument --wind:" in last and match in last


def test_cli_demo_prints_the_wind_it_used(capsys):
    assert cli.main(["demo", "--wind", "2@90", "--duration", "2"]) == 0
    assert "wind 2 m/s from 90 deg" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("wind", "current"),
    [
        ("3@300", "0.1@90"),
        ({"speed": 3.0, "direction_from_deg": 300}, {"speed": 0.1, "direction_to_deg": 90}),
        ({"speed": 3.0, "direction_from": math.radians(300.0)},
         {"speed": 0.1, "direction_to": math.pi / 2}),
    ],
)  # fmt: skip
def test_scenario_mappings_and_strings(wind, current):
    sc = scenario_from_dict({"env": "harbour", "wind": wind, "current": current})
    assert sc.wind == REF_WIND and sc.current == REF_CURRENT
    env = sc.make()
    env.reset(seed=0)
    assert env.unwrapped.physics.wind_config == REF_WIND
    assert env.unwrapped.physics.current_config == REF_CURRENT


def test_benchmark_wind_arguments():
    from shipgym.bench import bench_observers
    from shipgym.rl.bench import bench_title
    from shipgym.rl.evaluation import make_controlled_env

    rows = [{"seed": 0, "observer": "kbf"}]
    assert "wind 3 m/s from 300 deg" in bench_title(rows, "3@300")
    assert "wind 3 m/s from 300 deg" in bench_title(rows, (3, 300))
    assert "calm" in bench_title(rows, None)
    for w in ("3@300", (3, 300), REF_WIND):
        env = make_controlled_env("harbour", "pid", wind=w)
        assert env.unwrapped.physics.wind_config == REF_WIND
    with pytest.raises(ValueError, match="wind '100@0': WindConfig.speed must be <= 70"):
        bench_observers(["dkf"], seeds=1, wind="100@0", workers=1, progress=False)


@pytest.mark.parametrize("env_id", IDS)
def test_bad_values_raise_value_errors_naming_the_argument(env_id):
    cases = [
        ({"wind": (1e4, 0)}, "wind .*WindConfig.speed must be <= 70 m/s"),
        ({"wind": "3@300@1"}, "malformed wind"),
        ({"wind": 3.0}, "wind must be None, a WindConfig, 'SPEED@FROM_DEG'"),
        ({"wind": (3, 300, 0)}, "wind must be None"),
        ({"wind": ("3", "300")}, "wind must be None"),
        ({"current": "abc"}, "malformed current 'abc': expected SPEED@TO_DEG"),
        ({"current": (20.0, 0)}, "current .*CurrentConfig.speed must be <= 10 m/s"),
        ({"current": {"speed": 0.1, "direction_to": 1, "direction_to_deg": 5}}, "not both"),
        ({"current": (math.nan, 0)}, "current .*finite"),
    ]
    for kwargs, match in cases:
        with pytest.raises(ValueError, match=match):
            gym.make(env_id, **kwargs)


def test_config_limits():
    assert MAX_WIND_SPEED == 70.0 and MAX_CURRENT_SPEED == 10.0
    WindConfig(speed=MAX_WIND_SPEED)
    CurrentConfig(speed=MAX_CURRENT_SPEED)
    for kw in ({"speed": 70.5}, {"speed": 3.0, "gust_std": 100.0}, {"speed": math.inf}):
        with pytest.raises(ValueError, match="WindConfig"):
            WindConfig(**kw)
    for kw in ({"speed": 10.5}, {"speed": math.nan}, {"speed": 0.1, "direction_to": math.inf}):
        with pytest.raises(ValueError, match="CurrentConfig"):
            CurrentConfig(**kw)
    with pytest.raises(ValueError, match="wind"):
        VesselPhysics("blue-lady", wind="10000@0")
    with pytest.raises(ValueError, match="current"):
        VesselPhysics("blue-lady").set_current("-1@0")


# --- the absolute numbers, against Blendermann (1994) written out independently ------------

#: Blendermann (1994) "tanker, loaded" row (Fossen 2011, Table 8.2): CD_t, CD_lAF(0),
#: CD_lAF(pi), delta
_TANKER = (0.70, 0.90, 0.55, 0.40)


def _blendermann_loads(gamma: float, V: float) -> tuple[float, float, float]:
    """X, Y, N (N, N, N m) of the relative wind V (m/s) at angle of attack gamma (rad)."""
    cd_t, cd0, cdpi, delta = _TANKER
    w = BLUE_LADY_WINDAGE
    g = abs(gamma)
    cd_laf = cd0 if g <= math.pi / 2 else cdpi
    cd_l = cd_laf * w.A_F / w.A_L
    den = 1.0 - 0.5 * delta * (1.0 - cd_l / cd_t) * math.sin(2.0 * gamma) ** 2
    cx = -cd_laf * math.cos(gamma) / den
    cy = cd_t * math.sin(gamma) / den
    cn = (w.s_L / w.L_oa - 0.18 * (g - math.pi / 2)) * cy
    q = 0.5 * w.rho_a * V * V
    return q * cx * w.A_F, q * cy * w.A_L, q * cn * w.A_L * w.L_oa


@pytest.mark.parametrize(
    ("from_deg", "psi_deg", "gamma_deg", "signs"),
    [
        (300.0, 0.0, 60.0, (-1, 1)),  # from the port bow: pushed astern and to starboard
        (90.0, 0.0, -90.0, (0, -1)),  # from starboard, on the beam: pushed to port
        (0.0, 0.0, 0.0, (-1, 0)),  # head wind: pushed astern
        (300.0, 90.0, 150.0, (1, 1)),  # heading east, from the port quarter
        (200.0, 350.0, 150.0, (1, 1)),  # across north: the same relative wind
    ],
)
def test_wind_load_at_rest_matches_blendermann(from_deg, psi_deg, gamma_deg, signs):
    """A ship at rest feels the true wind; its angle of attack is psi - beta_w (wrapped)."""
    gamma = math.radians(gamma_deg)
    expected = _blendermann_loads(gamma, 3.0)
    wind = {"speed": 3.0, "direction_from_deg": from_deg, "gust_std": 0.0, "direction_std": 0.0}
    phys = VesselPhysics("blue-lady", wind=wind)
    phys.reset(eta=(0.0, 0.0, math.radians(psi_deg)))
    np.testing.assert_allclose(phys.tau_wind, expected, rtol=1e-9, atol=1e-9)
    X, Y, _ = phys.tau_wind
    assert (np.sign(round(X, 9)), np.sign(round(Y, 9))) == signs
    # the env: harbour start pose heading psi, at rest, the same load in info
    start = (0.0, 0.0, math.radians(psi_deg))
    env = gym.make("shipgym/BlueLadyHarbour-v0", wind=wind, start_pose=start)
    _, info = env.reset(seed=0)
    np.testing.assert_allclose(info["tau_wind"], expected, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("psi_deg", [0.0, 30.0, 90.0, 200.0])
def test_current_body_velocity_is_the_geometry(psi_deg):
    """0.1 m/s going to 90 deg (east) seen from a ship heading psi: the current's direction
    relative to the bow is 90 deg - psi (to starboard positive)."""
    psi = math.radians(psi_deg)
    rel = math.radians(90.0 - psi_deg)
    env = gym.make(
        "shipgym/BlueLadyHarbour-v0", wind=None, current="0.1@90", start_pose=(0.0, 0.0, psi)
    )
    _, info = env.reset(seed=0)
    expected = [0.1 * math.cos(rel), 0.1 * math.sin(rel), 0.0]
    np.testing.assert_allclose(info["current_body"], expected, atol=1e-15)
