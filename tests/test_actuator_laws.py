"""The compiled actuator force laws (:data:`shipgym._jit.LAW_SIG`) against the kinds' array
forms.

Every actuator kind has one compiled law (``law_propeller``, ``law_azimuth``, ``law_rudder``,
``law_mmg``) and a row of constants (``law_row``); :meth:`ActuatorSet.law_table` collects them
and :func:`tau_of_table` sums them. The independent oracle is the array form of each kind
(:meth:`ActuatorSet.tau`, :meth:`ActuatorSet.thrust`, :meth:`Rudder.flow`, and through them
:meth:`Propeller.thrust`, :meth:`Rudder.lift`, :meth:`MMGPropulsion.generalised`), at random
seeded states within every channel's range and random velocities through the water, for every
packaged vessel and plant variant and for hand-made rudders that stall.
"""

from __future__ import annotations

import dataclasses
import math
import pickle
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import pytest

from shipgym._jit import LAW_SIG, address, njit
from shipgym.dynamics.actuators import (
    Actuator,
    ActuatorSet,
    Azimuth,
    Channel,
    Propeller,
    Rudder,
    law_azimuth,
    law_mmg,
    law_propeller,
    law_rudder,
    tau_of_table,
)
from shipgym.dynamics.vessel import load_vessel, vessels

D = math.pi / 180.0
N_SAMPLES = 200
MAX_ERR: dict[str, float] = {}  # the largest relative error seen per quantity (a report)

# first-class functions are "experimental" in Numba (shipgym._jit); pytest resets the filter
pytestmark = pytest.mark.filterwarnings("ignore::numba.core.errors.NumbaExperimentalFeatureWarning")


def _hand_made() -> dict[str, ActuatorSet]:
    """Sets no packaged vessel has: stalling rudders with and without inflow (off the centre
    line, so that ``y`` enters nothing), and every kind at once (padding, several laws)."""
    stall_in = Rudder(name="r", position=(-20.0, 1.5, 2.0), lift_gain=1000.0,
                      stall_angle=15 * D, post_stall=0.5, inflow=True)  # fmt: skip
    stall_out = Rudder(name="r", position=(-20.0, -1.0, 3.0), lift_gain=800.0,
                       stall_angle=12 * D, post_stall=0.7, inflow=False)  # fmt: skip
    main = Propeller(name="main", position=(-30.0, 2.0, 3.0), alpha=5 * D, law="quadratic",
                     k_ahead=3.0, k_astern=1.7, lower=-150.0, upper=200.0, unit="rpm",
                     advance=0.8, wake=0.25, loss_speed=2.0, loss_depth=0.3)  # fmt: skip
    tunnel = Propeller(name="tunnel", position=(25.0, 0.0, 2.5), alpha=90 * D, k_ahead=5e4,
                       k_astern=4e4, tunnel=True, loss_speed=1.1, loss_depth=0.6)  # fmt: skip
    mixed = [
        main,
        tunnel,
        Azimuth(name="azi", position=(-28.0, -3.0, 4.0), max_thrust_n=2e5),
        stall_in,
        Propeller(name="plain", position=(-30.0, -2.0, 3.0), k_ahead=2e5, k_astern=1.2e5),
    ]
    unit = load_vessel("kvlcc2-l7").actuators.actuators[0]  # with the astern side force
    side = dataclasses.replace(unit, params=dataclasses.replace(unit.params, c_y=0.3))
    return {
        "kvlcc2-l7-astern-side-force": ActuatorSet([side], dofs=3),
        "rudder-inflow-stall": ActuatorSet([stall_in], dofs=4),
        "rudder-no-inflow-stall": ActuatorSet([stall_out], dofs=4),
        "rudder-no-inflow-stall-3dof": ActuatorSet([stall_out], dofs=3),
        "mixed-4dof": ActuatorSet(mixed, dofs=4),
        "mixed-3dof": ActuatorSet(mixed, dofs=3),
    }


def _sets() -> dict[str, ActuatorSet]:
    out: dict[str, ActuatorSet] = {}
    for name, v in sorted(vessels().items()):
        seen: list[ActuatorSet] = []
        for plant in v.plants:
            acts = v.actuators_for(plant)
            if any(acts is s for s in seen):
                continue
            seen.append(acts)
            out[f"{name}:{plant}"] = acts
    return {**out, **_hand_made()}


SETS = _sets()


def _sample(acts: ActuatorSet, seed: int) -> tuple[np.ndarray, ...]:
    """States (n, n_channels) in the channels' ranges (an azimuth's angle: any number, a
    few at 0 and the range ends) and velocities through the water (n,) each; the 3-DOF sets'
    roll rate 0."""
    rng = np.random.default_rng(seed)
    n = N_SAMPLES
    st = rng.uniform(acts.lower, acts.upper, size=(n, acts.n_channels))
    st[0], st[1], st[2] = 0.0, acts.lower, acts.upper
    for a, sl in zip(acts.actuators, acts.slices, strict=True):
        if isinstance(a, Azimuth):
            st[:, sl.start + 1] = rng.uniform(-20.0, 20.0, n)
    u = rng.uniform(-3.0, 8.0, n)
    v = rng.uniform(-2.0, 2.0, n)
    p = rng.uniform(-0.1, 0.1, n) if acts.dofs == 4 else np.zeros(n)
    r = rng.uniform(-0.05, 0.05, n)
    u[3:6] = 0.0  # at rest through the water (the rudder's numpy sign(u) = 0)
    v[4] = 0.0
    return st, u, v, p, r


def _nu(acts: ActuatorSet, u, v, p, r) -> np.ndarray:
    return np.stack([u, v, r] if acts.dofs == 3 else [u, v, p, r], -1)


def _run_table(acts: ActuatorSet, st, u, v, p, r) -> tuple[np.ndarray, ...]:
    table, laws, kind_index = acts.law_table()
    n, na = len(u), len(acts)
    tau = np.empty((n, 4))
    forces = np.empty((n, na))
    flags = np.empty((n, na))
    for i in range(n):
        tau[i] = tau_of_table(table, laws, kind_index, np.ascontiguousarray(st[i]), u[i], v[i],
                              p[i], r[i], forces[i], flags[i])  # fmt: skip
    return tau, forces, flags


def _dofs(acts: ActuatorSet, tau4: np.ndarray) -> np.ndarray:
    return tau4[..., [0, 1, 3]] if acts.dofs == 3 else tau4


def _close(got, ref, scale, what):
    """``got`` within rtol 1e-9, atol 1e-12 ``scale`` of ``ref``; the largest error relative
    to ``|ref| + 1e-12 scale``."""
    atol = 1e-12 * np.maximum(scale, 1e-300)
    err = np.abs(got - ref)
    bad = ~(err <= 1e-9 * np.abs(ref) + atol)
    assert not bad.any(), (
        f"{what}: {bad.sum()} of {bad.size} differ, first at {np.argwhere(bad)[0]}: "
        f"{got[bad][0]!r} vs {ref[bad][0]!r}"
    )
    rel = float(np.max(err / (np.abs(ref) + atol)))
    MAX_ERR[what.split(": ")[-1]] = max(MAX_ERR.get(what.split(": ")[-1], 0.0), rel)
    return rel


def _scale(acts: ActuatorSet, ref_tau: np.ndarray) -> np.ndarray:
    """Per DOF: the set's capacity, or where it has none (rudders) the largest |tau| seen."""
    return np.maximum(acts.capacity(), np.max(np.abs(ref_tau), axis=0))


@pytest.mark.parametrize("key", list(SETS))
def test_table_sum_equals_the_array_forms(key):
    acts = SETS[key]
    st, u, v, p, r = _sample(acts, seed=sum(map(ord, key)))
    nu = _nu(acts, u, v, p, r)
    tau4, forces, flags = _run_table(acts, st, u, v, p, r)
    ref = acts.tau(st, nu)
    assert ref.shape == (N_SAMPLES, acts.dofs)
    scale = _scale(acts, ref)
    _close(_dofs(acts, tau4), ref, scale, f"{key}: tau")
    # each actuator's own force reading: thrust (a rudder's lift, an MMG unit's T)
    thr = acts.thrust(st, nu)
    _close(forces, thr, np.max(np.abs(thr), axis=0) + 1e-300, f"{key}: forces")
    # stall flags: a rudder's from Rudder.flow, every other kind's 0
    for k, (a, sl) in enumerate(zip(acts.actuators, acts.slices, strict=True)):
        if isinstance(a, Rudder):
            stalled = a.flow(st[:, sl], nu)[2]
            np.testing.assert_array_equal(flags[:, k], stalled.astype(float), err_msg=a.name)
        else:
            np.testing.assert_array_equal(flags[:, k], 0.0, err_msg=a.name)


@pytest.mark.parametrize("key", list(SETS))
def test_each_law_equals_its_actuator_alone(key):
    """Per actuator (its law called from Python on its row) against a set of that actuator
    alone: every generalised component, so that no error hides in the sum."""
    acts = SETS[key]
    st, u, v, p, r = _sample(acts, seed=7 + len(key))
    st = st[:50]
    u, v, p, r = u[:50], v[:50], p[:50], r[:50]
    nu = _nu(acts, u, v, p, r)
    table, laws, kind_index = acts.law_table()
    for k, (a, sl) in enumerate(zip(acts.actuators, acts.slices, strict=True)):
        law = type(a).force_law
        assert laws[kind_index[k]] == address(law, LAW_SIG)
        got = np.array([law(table[k], np.ascontiguousarray(st[i]), u[i], v[i], p[i], r[i])
                        for i in range(len(u))])  # fmt: skip
        alone = ActuatorSet([a], acts.dofs)
        ref = alone.tau(st[:, sl], nu)
        scale = _scale(alone, ref)
        _close(_dofs(acts, got[:, :4]), ref, scale, f"{key}/{a.name}: tau")
        if a.force_law is law_mmg:
            assert np.all(got[:, 2] == 0.0)  # planar
        if acts.dofs == 4 or not isinstance(a, Rudder | Propeller | Azimuth):
            continue
        z = a.position[2]  # 3-DOF: K of the point force all the same
        np.testing.assert_allclose(got[:, 2], -z * got[:, 1], rtol=1e-12, atol=1e-9 * scale[1])


def test_hand_made_rudders_stall_and_not():
    for key in ("rudder-inflow-stall", "rudder-no-inflow-stall"):
        acts = SETS[key]
        st, u, v, p, r = _sample(acts, seed=3)
        _, forces, flags = _run_table(acts, st, u, v, p, r)
        assert 0 < flags[:, 0].sum() < N_SAMPLES, key  # both sides of the stall angle
        rud = acts.actuators[0]
        stalled = flags[:, 0] == 1.0
        # past the stall: the lift is the post-stall fraction of the stall lift, sign of alpha
        alpha, q, _ = rud.flow(st, _nu(acts, u, v, p, r))
        c_s = rud.post_stall * rud.stall_angle
        np.testing.assert_allclose(
            forces[stalled, 0], rud.lift_gain * q[stalled] * np.sign(alpha[stalled]) * c_s,
            rtol=1e-12, atol=1e-9,
        )  # fmt: skip


def test_stalled_rudder_by_hand():
    """One stalled point worked out by hand: inflow, ``alpha_e = delta - atan2(v_R, |u|)``."""
    rud = SETS["rudder-inflow-stall"].actuators[0]
    row = np.array(rud.law_row(0))
    u, v, p, r, delta = 4.0, 1.0, 0.05, -0.02, 20 * D
    vr = v + (-20.0) * r - 2.0 * p  # 1.3 m/s
    alpha = delta - math.atan2(vr, u)  # 20 deg - 18.0 deg: not stalled
    X, Y, K, N, F, flag = law_rudder(row, np.array([delta]), u, v, p, r)
    assert flag == 0.0 and F == pytest.approx(1000.0 * (u * u + vr * vr) * alpha, rel=1e-14)
    X, Y, K, N, F, flag = law_rudder(row, np.array([-20 * D]), u, v, p, r)
    alpha = -20 * D - math.atan2(vr, u)  # -38 deg: stalled, half the stall value, negative
    assert flag == 1.0
    assert F == pytest.approx(1000.0 * (u * u + vr * vr) * -0.5 * 15 * D, rel=1e-14)
    assert (X, Y, K, N) == pytest.approx((0.0, F, -2.0 * F, -20.0 * F), rel=1e-14)
    # astern: the flow reverses the force; at u = 0 (numpy's sign(u) = 0) there is none
    F_astern = law_rudder(row, np.array([5 * D]), -u, 0.0, 0.0, 0.0)[4]
    assert F_astern == pytest.approx(-1000.0 * u * u * 5 * D, rel=1e-14)
    assert law_rudder(row, np.array([5 * D]), 0.0, 0.5, 0.0, 0.0)[4] == 0.0
    # an infinite stall angle never stalls
    free = Rudder(name="f", lift_gain=1.0, inflow=True)
    assert free.law_row(0)[4:6] == (math.inf, 0.0)
    assert law_rudder(np.array(free.law_row(0)), np.array([0.6]), 3.0, 2.0, 0.0, 0.0)[5] == 0.0


def test_propeller_without_losses_is_exactly_the_bollard_law():
    rng = np.random.default_rng(11)
    props = [a for s in SETS.values() for a in s.actuators
             if isinstance(a, Propeller) and not a.flow_dependent]  # fmt: skip
    assert any(a.law == "quadratic" for a in props) and any(a.law == "linear" for a in props)
    assert any(a.k_ahead != a.k_astern for a in props)
    for a in props:
        row = np.array(a.law_row(0))
        for s in rng.uniform(a.lower, a.upper, 50).tolist() + [a.lower, 0.0, a.upper]:
            g = a.k_ahead if s >= 0 else a.k_astern
            bollard = (g * abs(s)) * s if a.law == "quadratic" else g * s
            for u in (0.0, -2.5, 6.0):
                F = law_propeller(row, np.array([s]), u, 0.3, 0.0, 0.01)[4]
                assert F == bollard, (a.name, s, u)


def test_blue_lady_losses_differ_from_the_bollard_law():
    """The Blue Lady's default actuators have the advance-speed loss (main propeller) and the
    tunnel loss; its ``seed-linear`` plant drives them on the bollard law."""
    v = load_vessel("blue-lady")
    lossy, bollard = v.actuators, v.actuators_for("seed-linear")
    assert lossy is not bollard and lossy.flow_dependent and not bollard.flow_dependent
    main, bow = lossy.actuators[0], lossy.actuators[1]
    assert main.advance > 0 and bow.loss_depth > 0
    st = np.array([300.0, 0.8, -0.6])
    t_l, laws_l, ki_l = lossy.law_table()
    t_b, laws_b, ki_b = bollard.law_table()
    f_l, f_b, fl = np.zeros(3), np.zeros(3), np.zeros(3)
    tau_of_table(t_b, laws_b, ki_b, st, 1.2, 0.1, 0.0, 0.01, f_b, fl)
    # at rest through the water both laws agree exactly
    tau_of_table(t_l, laws_l, ki_l, st, 0.0, 0.1, 0.0, 0.01, f_l, fl)
    np.testing.assert_array_equal(f_l, f_b)
    # moving: the advance-speed term and the tunnel factor, worked out by hand
    tau_of_table(t_l, laws_l, ki_l, st, 1.2, 0.1, 0.0, 0.01, f_l, fl)
    assert np.all(f_l != f_b)
    k_u = main.advance * (1 - main.wake)
    assert f_l[0] == pytest.approx(f_b[0] - k_u * 300.0 * 1.2, rel=1e-14)
    assert f_l[0] < f_b[0]  # ahead, the thrust falls with the speed
    x2 = (1.2 / bow.loss_speed) ** 2
    assert f_l[1] == pytest.approx(f_b[1] * (1 - bow.loss_depth * x2 * math.exp(1 - x2)))
    # at U_50 the tunnel keeps 1 - d of its bollard thrust, either direction of travel
    for u in (bow.loss_speed, -bow.loss_speed):
        tau_of_table(t_l, laws_l, ki_l, st, u, 0.0, 0.0, 0.0, f_l, fl)
        tau_of_table(t_b, laws_b, ki_b, st, u, 0.0, 0.0, 0.0, f_b, fl)
        assert f_l[1:] == pytest.approx((1 - bow.loss_depth) * f_b[1:], rel=1e-14)


def test_mmg_law_by_hand_at_straight_running():
    """KVLCC2 L7 at straight running with the rudder amidships: no side force, the thrust
    ``rho n^2 D^4 K_T(J)``, ``J = u (1 - w_P0) / (n D)``; a rudder angle to starboard gives
    a force to starboard (shipgym's sign) and a yaw moment to port."""
    unit = load_vessel("kvlcc2-l7").actuators.actuators[0]
    p = unit.params
    row = np.array(unit.law_row(0))
    u, n = 1.179, 10.4
    X, Y, K, N, T, flag = law_mmg(row, np.array([n, 0.0]), u, 0.0, 0.0, 0.0)
    J = u * (1 - p.w_P0) / (n * p.D_P)
    assert T == pytest.approx(p.rho * n * n * p.D_P**4 * (p.k0 + p.k1 * J + p.k2 * J * J))
    assert X == pytest.approx((1 - p.t_P) * T) and Y == 0.0 and N == 0.0
    assert K == 0.0 and flag == 0.0
    _, Y, _, N, _, _ = law_mmg(row, np.array([n, 10 * D]), u, 0.0, 0.0, 0.0)
    assert Y > 0.0 and N < 0.0


@njit(cache=False)
def _law_constant(row, st, u, v, p, r):  # type: ignore[no-untyped-def]
    f = row[1] * st[int(row[0])]
    return f, 0.0, 0.0, -row[2] * f, f, 0.0


@dataclass(frozen=True)
class _Pusher(Actuator):
    """A kind defined outside the package: a force ``k a`` ahead at ``y``."""

    kind: ClassVar[str] = "pusher"
    force_law: ClassVar[Any] = staticmethod(_law_constant)
    name: str = "pusher"
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    k: float = 10.0
    colour: str = "#000000"

    @property
    def channels(self) -> tuple[Channel, ...]:
        return (Channel(self.name, "1", -1.0, 1.0, "lag", 1.0),)

    def force(self, states):  # type: ignore[no-untyped-def]
        f = self.k * np.asarray(states, dtype=float)[..., 0]
        return f, 0.0 * f

    def thrust(self, states):  # type: ignore[no-untyped-def]
        return self.force(states)[0]

    @property
    def max_thrust(self) -> float:
        return self.k

    def law_row(self, channel: int) -> tuple[float, ...]:
        return (float(channel), self.k, self.position[1])


def test_law_table_layout_and_a_new_kind():
    base = SETS["mixed-4dof"]
    acts = ActuatorSet([*base.actuators, _Pusher(position=(0.0, 3.0, 1.0))], dofs=4)
    table, laws, ki = acts.law_table()
    assert acts.law_table()[0] is table  # cached
    assert table.dtype == np.float64 and table.flags.c_contiguous
    assert ki.dtype == np.int64 and ki.shape == (len(acts),)
    assert table.shape == (len(acts), 12)  # the propeller's row is the widest
    widths = [len(a.law_row(sl.start)) for a, sl in zip(acts.actuators, acts.slices, strict=True)]
    assert widths == [12, 12, 5, 7, 12, 3]
    for k, (a, sl) in enumerate(zip(acts.actuators, acts.slices, strict=True)):
        assert table[k, 0] == sl.start
        assert np.all(table[k, widths[k] :] == 0.0)
        assert laws[ki[k]] == address(type(a).force_law, LAW_SIG)
    fns = [law_propeller, law_azimuth, law_rudder, _law_constant]
    assert laws.tolist() == [address(f, LAW_SIG) for f in fns]
    assert ki.tolist() == [0, 0, 1, 2, 0, 3]
    st, u, v, p, r = _sample(acts, seed=5)
    tau4, forces, _ = _run_table(acts, st, u, v, p, r)
    ref = acts.tau(st, _nu(acts, u, v, p, r))
    _close(tau4, ref, _scale(acts, ref), "with a new kind")
    np.testing.assert_array_equal(forces[:, -1], 10.0 * st[:, -1])
    # the set still pickles (the compiled laws are rebuilt on demand)
    again = pickle.loads(pickle.dumps(base))
    np.testing.assert_array_equal(again.law_table()[0], base.law_table()[0])


def test_a_kind_without_a_law_is_refused():
    @dataclass(frozen=True)
    class Bare(_Pusher):
        force_law: ClassVar[Any] = None

    with pytest.raises(TypeError, match="no compiled force law"):
        ActuatorSet([Bare()]).law_table()
