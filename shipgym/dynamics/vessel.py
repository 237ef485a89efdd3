"""Vessels as data packages: :class:`Vessel`, :func:`load_vessel` and the registry.

Public names: ``ACTUATOR_READERS``, ``COMMON_ACTUATOR_KEYS``, ``HULL_FAMILIES``, ``ActuatorSite``,
``DesignModel``, ``HullFamily``, ``Vessel``, ``VesselError``, ...

Design notes: docs/design/dynamics.vessel.md.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shipgym._text import did_you_mean

from .actuators import Actuator, ActuatorSet, Azimuth, MMGPropulsion, Propeller, Rudder
from .hull4 import KINEMATICS, Hull4
from .model import PlantModel, plant_model
from .params import HullParameters, WindageParameters

__all__ = [
    "ACTUATOR_READERS",
    "COMMON_ACTUATOR_KEYS",
    "HULL_FAMILIES",
    "ActuatorSite",
    "DesignModel",
    "HullFamily",
    "Vessel",
    "VesselError",
    "VesselReader",
    "load_vessel",
    "register_actuator_kind",
    "register_hull_family",
    "vessel_names",
    "vessels",
]

#: the folder of the packaged vessel packages (one sub-folder per vessel; ``worlds`` is not one)
_ASSET_DIR = Path(__file__).resolve().parent.parent / "assets" / "mjcf"


class VesselError(ValueError):
    """A vessel package is invalid; the message names the file and the key."""


@dataclass(frozen=True)
class DesignModel:
    """The linear planar model ``M nu_dot + D_L nu = tau`` that controllers and observers use.

    Attributes:
        M: inertia incl. added mass (3, 3) (kg, kg m, kg m^2), surge-sway-yaw.
        D_L: linear damping (3, 3) (N s/m, N s, N m s).
        source: where it comes from.
    """

    M: NDArray[np.float64]
    D_L: NDArray[np.float64]
    source: str = ""

    def __post_init__(self) -> None:
        for nm in ("M", "D_L"):
            a = np.array(getattr(self, nm), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, nm, a)


@dataclass(frozen=True)
class Vessel:
    """A ship: hull model(s), actuators, windage, design model, limits; loaded from a package.

    Attributes:
        name: registry name (``"blue-lady"``).
        title: human-readable name.
        folder: the package folder (``vessel.toml``, ``vessel.xml``, ``README.md``).
        dofs: 3 (surge, sway, yaw) or 4 (surge, sway, roll, yaw).
        scale: model scale ``lambda`` (1: full scale; 24: a 1:24 model).
        hull: the hull parameters (:class:`HullParameters` for the ``fossen3`` family, with
            the dimensions ``L_oa``, ``L_pp``, ``B``, ``T``) or the 4-DOF parameters.
        plants: plant variants by name (``"default"`` first), each a
            :class:`~shipgym.dynamics.model.PlantModel` or :class:`~shipgym.dynamics.hull4.Hull4`.
        actuators: the :class:`~shipgym.dynamics.actuators.ActuatorSet`.
        windage: projected wind areas and the Blendermann (1994) ship type.
        design: the :class:`DesignModel` of the controllers and observers.
        limits: guidance limits (a mapping of :class:`~shipgym.guidance.Limits` fields).
        control: controller settings (``bandwidth`` rad/s per DOF of the generic PID's pole
            placement, default 0.05 rad/s: a conservative DP bandwidth, to be tuned per
            vessel; ``zeta``; the names of the vessel's PID presets).
        observer: kinematic KF settings (``accel_psd_xy`` m^2/s^3, ``accel_psd_psi``).
        nominal_wind: the wind (m/s) the vessel's default tasks use.
        rigid_inertia: ``(m, I_x, I_z)`` of the MuJoCo body (kg, kg m^2).
        sources: ``key -> (unit, source)`` for every value given with a source.
        roll_control: the rudder-roll design of a 4-DOF rudder vessel (``[roll_control]``:
            ``design_speed`` m/s, the LQR weights ``Q`` (5, state ``[v, r, psi, p, phi]``)
            and ``R``, the heading autopilot's ``heading_bandwidth`` rad/s and
            ``heading_zeta``); empty when the file has none.
        trials: the sea-trial settings (``[trials]``: ``approach_speed`` m/s, the speed of the
            IMO manoeuvres); empty when the file has none.
        plant_actuators: the actuators of the plant variants declared with ``actuators =
            "bollard"`` (:meth:`actuators_for`); the others drive :attr:`actuators`.
    """

    name: str
    title: str
    folder: Path
    dofs: int
    scale: float
    hull: Any
    plants: Mapping[str, Any]
    actuators: ActuatorSet
    windage: WindageParameters
    design: DesignModel
    limits: Mapping[str, float]
    control: Mapping[str, Any]
    observer: Mapping[str, float]
    nominal_wind: float
    rigid_inertia: tuple[float, float, float]
    dimensions: tuple[float, float, float, float]
    sources: Mapping[str, tuple[str, str]] = field(default_factory=dict, repr=False)
    roll_control: Mapping[str, Any] = field(default_factory=dict, repr=False)
    trials: Mapping[str, float] = field(default_factory=dict, repr=False)
    plant_actuators: Mapping[str, ActuatorSet] = field(default_factory=dict, repr=False)

    def actuators_for(self, plant: Any = "default") -> ActuatorSet:
        """The actuators a plant variant drives: :attr:`actuators`, or for a variant declared
        with ``actuators = "bollard"`` (a model of the paper's simulation as printed) the same
        channels with every propeller on its bollard law and no rate limit
        (:meth:`ActuatorSet.bollard`). ``plant``: a variant name or one of :attr:`plants`
        (another model object: :attr:`actuators`)."""
        if not isinstance(plant, str):
            plant = next((k for k, p in self.plants.items() if p is plant), None)
        return self.plant_actuators.get(plant, self.actuators) if plant else self.actuators

    @property
    def body_xml(self) -> Path:
        """The MJCF hull body (``vessel.xml``)."""
        return self.folder / "vessel.xml"

    @property
    def L_oa(self) -> float:
        """Length over all (m)."""
        return self.dimensions[0]

    @property
    def L_pp(self) -> float:
        """Length between perpendiculars (m)."""
        return self.dimensions[1]

    @property
    def B(self) -> float:
        """Beam (m)."""
        return self.dimensions[2]

    @property
    def T(self) -> float:
        """Draught (m)."""
        return self.dimensions[3]

    @property
    def can_position(self) -> bool:
        """Whether the actuators can push the hull in surge, sway and yaw at zero speed.

        The condition of the dynamic-positioning and harbour tasks: a ship steered by rudders
        only (their force needs a flow speed) cannot hold a position.
        """
        cap = self.actuators.capacity()
        planar = cap[[0, 1, -1]]
        return bool(np.all(planar > 0.0))

    @property
    def rudders(self) -> tuple[str, ...]:
        """Channel names of the vessel's rudders (the steering of the course-keeping, trial and
        rudder-roll tasks): every :class:`Rudder` and the rudder of every MMG unit."""
        out = []
        for a in self.actuators:
            if isinstance(a, Rudder):
                out.append(a.name)
            elif isinstance(a, MMGPropulsion):
                out.append(a.rudder_name)
        return tuple(out)

    @property
    def approach_speed(self) -> float | None:
        """The speed (m/s) of the vessel's trials and course keeping: ``[trials]
        approach_speed``, else the rudder-roll design speed, else ``None``."""
        if "approach_speed" in self.trials:
            return float(self.trials["approach_speed"])
        if "design_speed" in self.roll_control:
            return float(self.roll_control["design_speed"])
        return None

    @property
    def shafts(self) -> tuple[str, ...]:
        """Channel names of the vessel's main propellers (the ahead/astern thrust of the
        stopping manoeuvres): every MMG unit's propeller and every fixed propeller pointing
        ahead (not tunnels)."""
        out = []
        for a in self.actuators:
            if isinstance(a, MMGPropulsion):
                out.append(a.name)
            elif isinstance(a, Propeller) and not a.tunnel and a.alpha == 0.0:
                out.append(a.name)
        return tuple(out)

    def plant(self, name: str = "default", **options: bool) -> Any:
        """A plant variant by name (``options`` for the ``fossen3`` default only).

        Raises:
            ValueError: unknown name or option (the message lists the valid ones).
        """
        if name not in self.plants:
            raise ValueError(
                f"unknown plant variant {name!r}{did_you_mean(name, self.plants)} for vessel "
                f"{self.name!r}; choose one of: "
                f"{', '.join(self.plants)}"
            )
        if options:
            if name != "default" or not isinstance(self.hull, HullParameters):
                raise ValueError(f"plant {name!r} of {self.name!r} takes no options")
            return plant_model("default", self.hull, **options)
        return self.plants[name]

    def __repr__(self) -> str:
        return (
            f"Vessel({self.name!r}, {self.dofs} DOF, L_oa {self.L_oa:g} m, "
            f"{len(self.actuators)} actuators: {', '.join(self.actuators.names)})"
        )


# ---- reading ---------------------------------------------------------------------------------
_UNITS_HULL3 = {f.name: f.metadata.get("unit", "") for f in fields(HullParameters)}
_UNITS_WINDAGE = {f.name: f.metadata.get("unit", "") for f in fields(WindageParameters)}


class VesselReader:
    """Reads values from the TOML tables, recording units and sources; errors name the key."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.sources: dict[str, tuple[str, str]] = {}

    def fail(self, key: str, msg: str) -> VesselError:
        return VesselError(f"{self.path}: {key}: {msg}")

    def table(self, data: Mapping[str, Any], key: str, *, required: bool = True) -> dict[str, Any]:
        sub = data.get(key.rsplit(".", 1)[-1])
        if sub is None:
            if required:
                raise self.fail(key, "missing table")
            return {}
        if not isinstance(sub, Mapping):
            raise self.fail(key, f"must be a table, got {type(sub).__name__}")
        return dict(sub)

    def keys(self, t: Mapping[str, Any], where: str, allowed: set[str]) -> None:
        bad = sorted(set(t) - allowed)
        if bad:
            raise self.fail(
                f"{where}.{bad[0]}", f"unknown key; valid keys are: {', '.join(sorted(allowed))}"
            )

    def value(self, t: Mapping[str, Any], key: str, where: str, unit: str | None = None,
              default: Any = ...) -> Any:  # fmt: skip
        full = f"{where}.{key}"
        if key not in t:
            if default is ...:
                raise self.fail(full, "missing value" + (f" ({unit})" if unit else ""))
            return default
        v = t[key]
        if isinstance(v, Mapping):
            extra = sorted(set(v) - {"value", "unit", "source"})
            if extra or "value" not in v:
                raise self.fail(full, "a table value needs 'value' (and optional 'unit', 'source')")
            given = v.get("unit")
            if given is not None and unit is not None and given != unit:
                raise self.fail(full, f"unit must be {unit!r}, got {given!r}")
            self.sources[full] = (str(given or unit or ""), str(v.get("source", "")))
            v = v["value"]
        return v

    def number(self, t: Mapping[str, Any], key: str, where: str, unit: str | None = None,
               default: Any = ..., positive: bool = False) -> float:  # fmt: skip
        v = self.value(t, key, where, unit, default)
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise self.fail(f"{where}.{key}", f"must be a finite number ({unit}), got {v!r}")
        if positive and not v > 0:
            raise self.fail(f"{where}.{key}", f"must be > 0 ({unit}), got {v!r}")
        return float(v)

    def matrix(self, t: Mapping[str, Any], key: str, where: str, n: int, unit: str = "") -> NDArray:
        v = self.value(t, key, where, unit or None)
        try:
            a = np.array(v, dtype=float)
        except (TypeError, ValueError):
            raise self.fail(f"{where}.{key}", f"must be a {n}x{n} matrix of numbers") from None
        if a.shape != (n, n) or not np.all(np.isfinite(a)):
            raise self.fail(f"{where}.{key}", f"must be a finite {n}x{n} matrix, got {a.shape}")
        return a

    def vector(self, t: Mapping[str, Any], key: str, where: str, n: int, unit: str = "",
               default: Any = ...) -> tuple[float, ...]:  # fmt: skip
        v = self.value(t, key, where, unit or None, default)
        try:
            a = np.array(v, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise self.fail(f"{where}.{key}", f"must be {n} numbers") from None
        if a.shape != (n,) or not np.all(np.isfinite(a)):
            raise self.fail(f"{where}.{key}", f"must be {n} finite numbers ({unit}), got {v!r}")
        return tuple(float(x) for x in a)

    def string(self, t: Mapping[str, Any], key: str, where: str, default: Any = ...) -> str:
        v = self.value(t, key, where, None, default)
        if not isinstance(v, str):
            raise self.fail(f"{where}.{key}", f"must be a string, got {v!r}")
        return v


def _check_mass_matrix(r: VesselReader, M: NDArray, key: str) -> None:
    if not np.all(np.diag(M) > 0):
        raise r.fail(key, f"the mass matrix needs a positive diagonal, got {np.diag(M).tolist()}")
    if not np.linalg.cond(M) < 1e12:
        raise r.fail(key, f"the mass matrix is singular: {M.tolist()}")


@dataclass(frozen=True)
class HullFamily:
    """A hull model family a vessel file names (``[hull] family = "..."``).

    Attributes:
        dofs: the degrees of freedom of its hulls (3: surge, sway, yaw; 4: and roll).
        read: ``read(reader, data, table) -> (hull, plants)``: the family's ``[hull]`` table
            read with a :class:`VesselReader` (``data`` the whole file), giving the vessel's
            ``hull`` (its dimensions and rigid inertia as attributes ``m``, ``I_x`` (4 DOF),
            ``I_z``, ``L_oa``, ``L_pp``, ``B``, ``T``) and its plant variants (``{"default":
            model}``), each a hull model with a compiled ``accel_kernel``
            (:data:`shipgym._jit.ACCEL_SIG`), ``kernel_constants()`` and ``nu_dot``.
    """

    dofs: int
    read: Callable[..., tuple[Any, dict[str, Any]]]


#: the hull families by the name vessel files use (:func:`register_hull_family`)
HULL_FAMILIES: dict[str, HullFamily] = {}


def register_hull_family(name: str, family: HullFamily) -> None:
    """Make ``family`` readable from vessel files as ``[hull] family = name``."""
    if not isinstance(family, HullFamily) or family.dofs not in (3, 4):
        raise ValueError(f"hull family {name!r}: need a HullFamily of 3 or 4 DOF, got {family!r}")
    HULL_FAMILIES[name] = family


def _read_hull(r: VesselReader, data: Mapping[str, Any], dofs: int) -> tuple[Any, dict[str, Any]]:
    t = r.table(data, "hull")
    name = r.string(t, "family", "hull")
    family = HULL_FAMILIES.get(name)
    if family is None:
        raise r.fail(
            "hull.family",
            f"unknown hull family {name!r}; choose one of {', '.join(sorted(HULL_FAMILIES))}",
        )
    if family.dofs != dofs:
        raise r.fail("hull.family", f"{name!r} is a {family.dofs}-DOF family, the vessel has "
                                    f"dofs = {dofs}")  # fmt: skip
    return family.read(r, data, t)


def _read_fossen3(
    r: VesselReader, data: Mapping[str, Any], t: Mapping[str, Any]
) -> tuple[Any, dict[str, Any]]:
    """A ``fossen3`` hull: :class:`~shipgym.dynamics.params.HullParameters` (Tomera 2014
    Table 2 names) and its default plant."""
    r.keys(t, "hull", {"family", *_UNITS_HULL3})
    vals: dict[str, Any] = {"name": str(data.get("vessel", {}).get("title", r.path.parent.name))}
    for k, unit in _UNITS_HULL3.items():
        if k == "name":
            continue
        vals[k] = r.number(t, k, "hull", unit)
    for k in ("m", "I_z", "L_oa", "L_pp", "B", "T"):
        if not vals[k] > 0:
            raise r.fail(f"hull.{k}", f"must be > 0 ({_UNITS_HULL3[k]}), got {vals[k]!r}")
    try:
        hull = HullParameters(**vals)
        default = plant_model("default", hull)
    except ValueError as exc:
        raise r.fail("hull", str(exc)) from None
    _check_mass_matrix(r, default.mass_matrix(), "hull (M = M_RB + M_A)")
    return hull, {"default": default}


def _read_linear4(
    r: VesselReader, data: Mapping[str, Any], t: Mapping[str, Any]
) -> tuple[Any, dict[str, Any]]:
    """A ``linear4`` hull: :class:`~shipgym.dynamics.hull4.Hull4` matrices and dimensions."""
    keys = {"family", "M", "D_L", "D_u", "kinematics", "K_phi", "phi_coupling", "d_quad", "m",
            "I_x", "I_z", "nabla", "rho",
            "L_oa", "L_pp", "B", "T"}  # fmt: skip
    r.keys(t, "hull", keys)
    M = r.matrix(t, "M", "hull", 4)
    _check_mass_matrix(r, M, "hull.M")
    D = r.matrix(t, "D_L", "hull", 4)
    Du = r.matrix(t, "D_u", "hull", 4) if "D_u" in t else np.zeros((4, 4))
    kin = r.string(t, "kinematics", "hull", "fossen")
    if kin not in KINEMATICS:
        raise r.fail("hull.kinematics", f"choose one of {', '.join(KINEMATICS)}, got {kin!r}")
    vals = {k: r.number(t, k, "hull", u, positive=True) for k, u in (
        ("K_phi", "N m/rad"), ("m", "kg"), ("I_x", "kg m^2"), ("I_z", "kg m^2"),
        ("L_oa", "m"), ("L_pp", "m"), ("B", "m"), ("T", "m"))}  # fmt: skip
    dq = r.vector(t, "d_quad", "hull", 4, default=(0.0, 0.0, 0.0, 0.0))
    if min(dq) < 0:
        raise r.fail("hull.d_quad", f"must be >= 0, got {dq}")
    pc = r.vector(t, "phi_coupling", "hull", 2, default=(0.0, 0.0))
    nabla = r.number(t, "nabla", "hull", "m^3", default=0.0)
    rho = r.number(t, "rho", "hull", "kg/m^3", default=1025.0, positive=True)
    if nabla < 0:
        raise r.fail("hull.nabla", f"must be >= 0 m^3 (0: none), got {nabla!r}")
    hull = Hull4("default", M, D, vals["K_phi"], dq, vals["m"], Du, kin, pc, nabla, rho)
    hull_info = dict(vals)
    return _Dims4(hull_info), {"default": hull}


#: units of the MMG parameters in a vessel file (the rest are nondimensional: "1")
_UNITS_MMG = {"L": "m", "B": "m", "d": "m", "nabla": "m^3", "x_G": "m", "D_P": "m", "H_R": "m",
              "A_R": "m^2", "rho": "kg/m^3", "stall_angle": "rad"}  # fmt: skip


def _read_mmg(
    r: VesselReader, data: Mapping[str, Any], t: Mapping[str, Any]
) -> tuple[Any, dict[str, Any]]:
    """An ``mmg`` hull: one key per :class:`~shipgym.dynamics.mmg.MMGParameters` field (the
    published values), an optional ``scale_to`` (m: the same hull geometrically scaled to
    this length between perpendiculars) and ``L_oa`` (m)."""
    from .mmg import MMGHull, MMGParameters  # here, so that the family's import stays here

    pf = [f for f in fields(MMGParameters)]
    units = {f.name: _UNITS_MMG.get(f.name, "1") for f in pf}
    r.keys(t, "hull", {"family", "source", "scale_to", "L_oa", *units})
    vals = {}
    for f in pf:
        dflt = f.default if f.default is not dataclasses.MISSING else ...
        if f.name not in t and dflt is not ...:  # (a default may be inf: no stall)
            vals[f.name] = dflt
            continue
        vals[f.name] = r.number(t, f.name, "hull", units[f.name], default=dflt)
    try:
        p = MMGParameters(**vals)
        if "scale_to" in t:
            p = p.scaled(r.number(t, "scale_to", "hull", "m", positive=True))
    except ValueError as exc:
        raise r.fail("hull", str(exc)) from None
    hull = MMGHull(p)
    _check_mass_matrix(r, hull.mass_matrix(), "hull (M = M_RB + M_A)")
    L_oa = r.number(t, "L_oa", "hull", "m", positive=True)
    if L_oa < p.L:
        raise r.fail("hull.L_oa", f"must be >= L = {p.L:g} m (the length between perpendiculars)")
    Iz = hull.model.IzG + p.x_G**2 * hull.m  # about midship, the body origin
    info = {"m": hull.m, "I_x": Iz, "I_z": Iz, "L_oa": L_oa, "L_pp": p.L, "B": p.B, "T": p.d,
            "params": p}  # fmt: skip
    return _Dims4(info), {"default": hull}


def _read_blanke4(
    r: VesselReader, data: Mapping[str, Any], t: Mapping[str, Any]
) -> tuple[Any, dict[str, Any]]:
    """A ``blanke4`` hull: one key per :class:`~shipgym.dynamics.blanke4.Blanke4Hull` field.

    Plus ``L_oa`` and the MuJoCo body's rigid inertia ``m``, ``I_x``, ``I_z``, which must
    equal the hull's ``rho nabla``, ``I_xx``, ``I_zz`` (one number, one source).
    """
    from .blanke4 import Blanke4Hull  # here, so that the family's import stays in its reader

    hull_fields = {
        f.name: f.metadata["unit"]
        for f in fields(Blanke4Hull)
        if f.init and f.name not in ("name", "source")
    }
    extra = {"L_oa": "m", "m": "kg", "I_x": "kg m^2", "I_z": "kg m^2"}
    r.keys(t, "hull", {"family", "source", *hull_fields, *extra})
    vals: dict[str, Any] = {k: r.number(t, k, "hull", u) for k, u in hull_fields.items()}
    name = str(data.get("vessel", {}).get("title", r.path.parent.name))
    source = r.string(t, "source", "hull", f"{r.path}")
    try:
        hull = Blanke4Hull(name=name, source=source, **vals)
    except ValueError as exc:
        raise r.fail("hull", str(exc)) from None
    _check_mass_matrix(r, hull.mass_matrix(), "hull (M = M_RB + M_A)")
    info = {k: r.number(t, k, "hull", u, positive=True) for k, u in extra.items()}
    for key, want in (("m", hull.m), ("I_x", hull.I_xx), ("I_z", hull.I_zz)):
        if not math.isclose(info[key], want, rel_tol=1e-9):
            raise r.fail(
                f"hull.{key}",
                f"must equal the hull's {want:.10g} ({extra[key]}; m = rho nabla, I_x = I_xx, "
                f"I_z = I_zz), got {info[key]!r}",
            )
    info.update(L_pp=hull.L_pp, B=hull.B, T=hull.T)
    return _Dims4(info), {"default": hull}


for _name, _family in (
    ("fossen3", HullFamily(3, _read_fossen3)),
    ("linear4", HullFamily(4, _read_linear4)),
    ("blanke4", HullFamily(4, _read_blanke4)),
    ("mmg", HullFamily(3, _read_mmg)),
):
    register_hull_family(_name, _family)


@dataclass(frozen=True)
class _Dims4:
    """The dimensions and rigid inertia of a 4-DOF hull package (``hull`` of a ``linear4``)."""

    values: Mapping[str, float]

    def __getattr__(self, name: str) -> float:
        try:
            return self.values[name]
        except KeyError:
            raise AttributeError(name) from None


def _read_plants(
    r: VesselReader, data: Mapping[str, Any], hull: Any, plants: dict[str, Any]
) -> set[str]:
    """The ``[plants.NAME]`` variants into ``plants``; returns the names of those that drive
    the bollard actuators (``actuators = "bollard"``)."""
    bollard: set[str] = set()
    extra = r.table(data, "plants", required=False)
    for name, t in extra.items():
        where = f"plants.{name}"
        if not isinstance(t, Mapping):
            raise r.fail(where, "must be a table")
        family = r.string(t, "family", where)
        if family not in ("linear3", "fossen3") or not isinstance(hull, HullParameters):
            raise r.fail(
                f"{where}.family",
                "extra plant variants must be 'linear3' (M, D_L only) or 'fossen3' (the hull "
                "with some of its values replaced), 3 DOF with a 'fossen3' hull",
            )
        if family == "fossen3":
            plants[name] = _read_fossen3_variant(r, t, where, name, hull)
            continue
        r.keys(t, where, {"family", "M", "D_L", "actuators"})
        M = r.matrix(t, "M", where, 3)
        _check_mass_matrix(r, M, f"{where}.M")
        D = r.matrix(t, "D_L", where, 3)
        M_RB = np.diag([hull.m, hull.m, M[2, 2]])
        plants[name] = PlantModel(name, M_RB, M - M_RB, D, (0.0, 0.0, 0.0), False, hull.m, 0.0)
        acts = r.string(t, "actuators", where, "vessel")
        if acts not in ("vessel", "bollard"):
            raise r.fail(
                f"{where}.actuators",
                f"choose 'vessel' (the vessel's actuators) or 'bollard' (every propeller on its "
                f"bollard law, no rate limits), got {acts!r}",
            )
        if acts == "bollard":
            bollard.add(name)
    return bollard


def _read_fossen3_variant(
    r: VesselReader, t: Mapping[str, Any], where: str, name: str, hull: HullParameters
) -> PlantModel:
    """A ``fossen3`` plant variant: the default plant of the ``[hull]`` with the hydrodynamic
    values given here (same keys and units as ``[hull]``) in place of the hull's; the rigid
    body (``m``, ``I_z``, ``x_g``) and the dimensions stay those of the hull."""
    rigid = {"name", "m", "I_z", "x_g", "L_oa", "L_pp", "B", "T"}
    allowed = {k for k in _UNITS_HULL3 if k not in rigid}
    r.keys(t, where, {"family", *allowed})
    over = {k: r.number(t, k, where, _UNITS_HULL3[k]) for k in sorted(allowed) if k in t}
    if not over:
        raise r.fail(
            where, f"a 'fossen3' variant replaces at least one of: {', '.join(sorted(allowed))}"
        )
    try:
        plant = dataclasses.replace(plant_model("default", dataclasses.replace(hull, **over)),
                                    name=name)  # fmt: skip
    except ValueError as exc:
        raise r.fail(where, str(exc)) from None
    _check_mass_matrix(r, plant.mass_matrix(), f"{where} (M = M_RB + M_A)")
    return plant


@dataclass(frozen=True)
class ActuatorSite:
    """What every ``[[actuator]]`` table gives, read before its kind's reader runs."""

    name: str
    where: str
    position: tuple[float, float, float]
    colour: str
    hull: Any  # the vessel's hull (its dimensions; an ``mmg`` hull's parameters)


#: the readers of the actuator kinds vessel files name (``kind = "..."``):
#: ``read(reader, table, site) -> Actuator`` (:func:`register_actuator_kind`)
ACTUATOR_READERS: dict[str, Callable[..., Actuator]] = {}

#: the keys every actuator table may hold, whatever its kind
#: an actuator's colour in the figures and the recording: ``#rrggbb``
_HEX_COLOUR = re.compile(r"#[0-9a-fA-F]{6}")
COMMON_ACTUATOR_KEYS = frozenset({"name", "kind", "position", "time_constant", "colour"})


def register_actuator_kind(kind: str, read: Callable[..., Actuator]) -> None:
    """Make an actuator kind readable from vessel files as ``kind = ...``: ``read(reader,
    table, site)`` (a :class:`VesselReader`, the ``[[actuator]]`` table, its
    :class:`ActuatorSite`) returns the actuator, whose class has a compiled force law
    (``force_law``, ``law_row``: :meth:`~shipgym.dynamics.actuators.ActuatorSet.law_table`)."""
    if not callable(read):
        raise ValueError(f"actuator kind {kind!r}: read must be callable, got {read!r}")
    ACTUATOR_READERS[kind] = read


def _read_actuators(
    r: VesselReader,
    data: Mapping[str, Any],
    dofs: int,
    dims: tuple[float, float, float, float],
    hull: Any = None,
) -> ActuatorSet:
    items = data.get("actuator")
    if not isinstance(items, list) or not items:
        raise r.fail("actuator", "missing: give one [[actuator]] table per actuator")
    L_oa, _, B, T = dims
    out = []
    for i, t in enumerate(items):
        where = f"actuator[{i}]"
        if not isinstance(t, Mapping):
            raise r.fail(where, "must be a table")
        name = r.string(t, "name", where)
        where = f"actuator.{name}"
        kind = r.string(t, "kind", where)
        pos = r.vector(t, "position", where, 3, "m")
        x, y, z = pos
        if abs(x) > 0.5 * L_oa * 1.02 or abs(y) > 0.5 * B * 1.02 or abs(z) > 2.0 * T:
            raise r.fail(
                f"{where}.position",
                f"[{x:g}, {y:g}, {z:g}] m lies outside the hull (|x| <= L_oa/2 = {0.5 * L_oa:g}, "
                f"|y| <= B/2 = {0.5 * B:g}, |z| <= 2 T = {2 * T:g} m from the centre of gravity)",
            )
        read = ACTUATOR_READERS.get(kind)
        if read is None:
            raise r.fail(
                f"{where}.kind",
                f"unknown actuator kind {kind!r}; choose {', '.join(ACTUATOR_READERS)}",
            )
        colour = r.string(t, "colour", where, "#1f77b4")
        if not _HEX_COLOUR.fullmatch(colour):  # the plots and the recording read it after a run
            raise r.fail(f"{where}.colour", f"must be a colour #rrggbb, got {colour!r}")
        site = ActuatorSite(name, where, (x, y, z), colour, hull)
        try:
            out.append(read(r, t, site))
        except ValueError as exc:
            if isinstance(exc, VesselError):
                raise
            raise r.fail(where, str(exc)) from None
    try:
        return ActuatorSet(out, dofs)
    except ValueError as exc:
        raise r.fail("actuator", str(exc)) from None


def _read_propeller(r: VesselReader, t: Mapping[str, Any], site: ActuatorSite) -> Actuator:
    """A ``propeller`` or ``tunnel`` table (:class:`~shipgym.dynamics.actuators.Propeller`)."""
    where = site.where
    kind = t["kind"]
    r.keys(t, where, COMMON_ACTUATOR_KEYS | {
        "law", "k_ahead", "k_astern", "k", "unit", "range", "alpha_deg", "advance", "wake",
        "loss_speed", "loss_depth", "rate_limit"})  # fmt: skip
    tc = r.number(t, "time_constant", where, "s", positive=True)
    unit = r.string(t, "unit", where, "1")
    law = r.string(t, "law", where, "linear")
    ku = {"linear": f"N/{unit}", "quadratic": f"N/{unit}^2"}.get(law, "")
    if unit == "1":
        ku = "N"
    if "k" in t:
        k = r.number(t, "k", where, ku, positive=True)
        ka = kb = k
    else:
        ka = r.number(t, "k_ahead", where, ku, positive=True)
        kb = r.number(t, "k_astern", where, ku, positive=True)
    lo, hi = r.vector(t, "range", where, 2, unit, default=(-1.0, 1.0))
    alpha = r.number(t, "alpha_deg", where, "deg", default=90.0 if kind == "tunnel" else 0.0)
    # the advance-speed loss (Blanke 1981), the tunnel loss, the rate limit
    per = "" if unit == "1" else f"{unit} "
    flow = {
        "advance": r.number(t, "advance", where, f"N/({per}m/s)" if per else "N s/m",
                            default=0.0),
        "wake": r.number(t, "wake", where, "1", default=0.0),
        "loss_speed": r.number(t, "loss_speed", where, "m/s", default=1.0),
        "loss_depth": r.number(t, "loss_depth", where, "1", default=0.0),
        "rate_limit": r.number(t, "rate_limit", where, f"{unit}/s", positive=True)
        if "rate_limit" in t else math.inf,
    }  # fmt: skip
    if ("loss_depth" in t) != ("loss_speed" in t):
        raise r.fail(
            f"{where}.loss_speed",
            "give both loss_speed (m/s) and "
            "loss_depth (1) for a thrust loss with forward speed, or neither",
        )
    if "wake" in t and "advance" not in t:
        raise r.fail(
            f"{where}.wake",
            "a wake fraction needs an advance coefficient "
            "(advance: the thrust loss per unit and m/s)",
        )
    return Propeller(
        name=site.name, position=site.position, alpha=math.radians(alpha), law=law, k_ahead=ka,
        k_astern=kb, lower=lo, upper=hi, unit=unit, time_constant=tc, colour=site.colour,
        tunnel=kind == "tunnel", **flow)  # fmt: skip


def _read_azimuth(r: VesselReader, t: Mapping[str, Any], site: ActuatorSite) -> Actuator:
    """An ``azimuth`` table (:class:`~shipgym.dynamics.actuators.Azimuth`)."""
    where = site.where
    r.keys(t, where, COMMON_ACTUATOR_KEYS | {"max_thrust", "reversible", "max_rate_deg",
                                             "angle0_deg"})  # fmt: skip
    tc = r.number(t, "time_constant", where, "s", positive=True)
    rev = r.value(t, "reversible", where, None, True)
    if not isinstance(rev, bool):
        raise r.fail(f"{where}.reversible", f"must be true or false, got {rev!r}")
    return Azimuth(
        name=site.name, position=site.position,
        max_thrust_n=r.number(t, "max_thrust", where, "N", positive=True),
        lower=-1.0 if rev else 0.0, time_constant=tc,
        max_rate=math.radians(r.number(t, "max_rate_deg", where, "deg/s", positive=True)),
        angle0=math.radians(r.number(t, "angle0_deg", where, "deg", default=0.0)),
        colour=site.colour)  # fmt: skip


#: the unit of a rudder's lift gain k_L = rho A dC_L/dalpha / 2
LIFT_GAIN_UNIT = "N s^2/(m^2 rad)"


def _read_rudder(r: VesselReader, t: Mapping[str, Any], site: ActuatorSite) -> Rudder:
    """A ``kind = "rudder"`` table: the lift gain directly or from area, slope and density."""
    where, name, pos, colour = site.where, site.name, site.position, site.colour
    r.keys(t, where, {"name", "kind", "position", "colour", "lift_gain", "area", "lift_slope",
                      "rho", "stall_angle_deg", "post_stall", "max_angle_deg", "max_rate_deg",
                      "servo_time_constant", "inflow"})  # fmt: skip
    foil = [k for k in ("area", "lift_slope", "rho") if k in t]
    if ("lift_gain" in t) == bool(foil) or (foil and len(foil) != 3):
        raise r.fail(
            f"{where}.lift_gain",
            f"give either lift_gain ({LIFT_GAIN_UNIT}) or all of area (m^2), lift_slope (1/rad)"
            " and rho (kg/m^3)",
        )
    if foil:
        k = (
            0.5
            * r.number(t, "rho", where, "kg/m^3", positive=True)
            * r.number(t, "area", where, "m^2", positive=True)
            * r.number(t, "lift_slope", where, "1/rad", positive=True)
        )
    else:
        k = r.number(t, "lift_gain", where, LIFT_GAIN_UNIT, positive=True)
    inflow = r.value(t, "inflow", where, None, False)
    if not isinstance(inflow, bool):
        raise r.fail(f"{where}.inflow", f"must be true or false, got {inflow!r}")
    stall = r.number(t, "stall_angle_deg", where, "deg") if "stall_angle_deg" in t else math.inf
    return Rudder(
        name=name, position=pos, lift_gain=k,
        max_angle=math.radians(r.number(t, "max_angle_deg", where, "deg", positive=True)),
        max_rate=math.radians(r.number(t, "max_rate_deg", where, "deg/s", positive=True)),
        stall_angle=math.radians(stall) if math.isfinite(stall) else math.inf,
        post_stall=r.number(t, "post_stall", where, "1", default=1.0),
        servo_time_constant=r.number(t, "servo_time_constant", where, "s", default=0.0),
        inflow=inflow, colour=colour,
    )  # fmt: skip


def _read_mmg_unit(r: VesselReader, t: Mapping[str, Any], site: ActuatorSite) -> MMGPropulsion:
    """A ``kind = "mmg"`` table: the propeller and rudder of the ``mmg`` hull (its law's
    parameters are the hull's), their ranges, rates and servos."""
    where, name, pos, colour = site.where, site.name, site.position, site.colour
    params = getattr(site.hull, "values", {}).get("params")
    if params is None:
        raise r.fail(f"{where}.kind", "an 'mmg' unit needs an 'mmg' hull family")
    r.keys(t, where, {"name", "kind", "position", "colour", "max_rps", "min_rps", "shaft_rate",
                      "shaft_time_constant", "max_angle_deg", "max_rate_deg",
                      "servo_time_constant", "rudder_name"})  # fmt: skip
    return MMGPropulsion(
        name=name, params=params, position=pos, colour=colour,
        max_rps=r.number(t, "max_rps", where, "rps", positive=True),
        min_rps=r.number(t, "min_rps", where, "rps"),
        shaft_rate=r.number(t, "shaft_rate", where, "rps/s", positive=True),
        shaft_time_constant=r.number(t, "shaft_time_constant", where, "s", default=0.0),
        max_angle=math.radians(r.number(t, "max_angle_deg", where, "deg", positive=True)),
        max_rate=math.radians(r.number(t, "max_rate_deg", where, "deg/s", positive=True)),
        servo_time_constant=r.number(t, "servo_time_constant", where, "s", default=0.0),
        rudder_name=r.string(t, "rudder_name", where, "rudder"),
    )  # fmt: skip


for _kind, _read_kind in (
    ("propeller", _read_propeller),
    ("tunnel", _read_propeller),
    ("azimuth", _read_azimuth),
    ("rudder", _read_rudder),
    ("mmg", _read_mmg_unit),
):
    register_actuator_kind(_kind, _read_kind)


_LIMIT_KEYS = {
    "surge_speed": "m/s", "surge_accel": "m/s^2", "surge_astern_speed": "m/s",
    "surge_astern_accel": "m/s^2", "sway_speed": "m/s", "sway_accel": "m/s^2",
    "yaw_rate": "rad/s", "yaw_accel": "rad/s^2",
}  # fmt: skip


def _read(path: Path) -> Vessel:
    toml_path = path / "vessel.toml"
    r = VesselReader(toml_path)
    if not toml_path.is_file():
        raise VesselError(f"{path}: not a vessel package (no vessel.toml)")
    from shipgym._safeload import parse, read_bounded

    try:
        raw = read_bounded(toml_path, "vessel file")
        data = parse(raw.decode("utf-8"), "toml", str(toml_path))
    except (ValueError, UnicodeDecodeError) as exc:
        raise VesselError(str(exc)) from None
    top = {"vessel", "hull", "plants", "design", "windage", "actuator", "limits", "control",
           "roll_control", "trials",
           "observer"}  # fmt: skip
    r.keys(data, "(top level)", top)
    v = r.table(data, "vessel")
    r.keys(v, "vessel", {"name", "title", "dofs", "scale", "nominal_wind"})
    name = r.string(v, "name", "vessel")
    title = r.string(v, "title", "vessel", name)
    dofs = r.value(v, "dofs", "vessel", None, 3)
    if dofs not in (3, 4) or isinstance(dofs, bool):
        raise r.fail("vessel.dofs", f"must be 3 (surge, sway, yaw) or 4 (+ roll), got {dofs!r}")
    scale = r.number(v, "scale", "vessel", "1", 1.0, positive=True)
    nominal_wind = r.number(v, "nominal_wind", "vessel", "m/s", positive=True)
    hull, plants = _read_hull(r, data, int(dofs))
    dims = (hull.L_oa, hull.L_pp, hull.B, hull.T)
    if dofs == 3:  # a planar hull body: I_x = I_z (scene.build_model)
        rigid = (hull.m, hull.I_z, hull.I_z)
    else:
        rigid = (hull.m, hull.I_x, hull.I_z)
        if not hull.I_x <= 2 * hull.I_z:
            raise r.fail("hull.I_x", "a rigid body needs I_x <= I_y + I_z = 2 I_z")
    bollard_plants = _read_plants(r, data, hull, plants)
    d = r.table(data, "design")
    r.keys(d, "design", {"M", "D_L", "source"})
    M = r.matrix(d, "M", "design", 3)
    _check_mass_matrix(r, M, "design.M")
    design = DesignModel(M, r.matrix(d, "D_L", "design", 3), r.string(d, "source", "design", ""))
    w = r.table(data, "windage")
    r.keys(w, "windage", set(_UNITS_WINDAGE))
    try:
        windage = WindageParameters(**{
            k: r.string(w, k, "windage") if k == "coefficients"
            else r.number(w, k, "windage", u, getattr(WindageParameters, k, ...))
            for k, u in _UNITS_WINDAGE.items()})  # fmt: skip
    except ValueError as exc:
        if isinstance(exc, VesselError):
            raise
        raise r.fail("windage", str(exc)) from None
    actuators = _read_actuators(r, data, int(dofs), dims, hull)
    plant_actuators = {name: actuators.bollard() for name in sorted(bollard_plants)}
    # any subset: shipgym.guidance.limits.vessel_limits derives the others from the capacity
    lim = r.table(data, "limits", required=False)
    r.keys(lim, "limits", set(_LIMIT_KEYS))
    limits = {k: r.number(lim, k, "limits", _LIMIT_KEYS[k], positive=True) for k in lim}
    c = r.table(data, "control", required=False)
    r.keys(c, "control", {"bandwidth", "zeta", "pid_presets", "sensors", "velocity_filter",
                          "velocity_filter_model_based", "command_filter",
                          "command_filter_model_based", "reversal_threshold"})  # fmt: skip
    control: dict[str, Any] = {
        "bandwidth": r.vector(c, "bandwidth", "control", 3, "rad/s", default=(0.05, 0.05, 0.05)),
        "zeta": r.number(c, "zeta", "control", "1", 1.0, positive=True),
        "pid_presets": tuple(r.value(c, "pid_presets", "control", None, ())),
        # command conditioning (shipgym.controllers.conditioning): off unless given
        "velocity_filter": r.vector(c, "velocity_filter", "control", 3, "s", default=(0, 0, 0)),
        "velocity_filter_model_based": r.vector(
            c, "velocity_filter_model_based", "control", 3, "s", default=(0, 0, 0)
        ),
        "command_filter": r.vector(c, "command_filter", "control", 3, "s", default=(0, 0, 0)),
        "command_filter_model_based": r.vector(
            c, "command_filter_model_based", "control", 3, "s", default=(0, 0, 0)
        ),
        "reversal_threshold": r.vector(
            c,
            "reversal_threshold",
            "control",
            len(actuators),
            "N",
            default=(0.0,) * len(actuators),
        ),  # fmt: skip
    }
    if min(control["bandwidth"]) <= 0:
        raise r.fail("control.bandwidth", "must be > 0 rad/s")
    for key in (
        "velocity_filter",
        "velocity_filter_model_based",
        "command_filter",
        "command_filter_model_based",
    ):
        if min(control[key]) < 0:
            raise r.fail(f"control.{key}", "time constants must be >= 0 s (0: no filter)")
    if min(control["reversal_threshold"]) < 0:
        raise r.fail("control.reversal_threshold", "must be >= 0 N per actuator (0: no hysteresis)")
    o = r.table(data, "observer", required=False)
    r.keys(o, "observer", {"accel_psd_xy", "accel_psd_psi"})
    observer = {
        k: r.number(o, k, "observer", u, positive=True, default=dflt)
        for k, u, dflt in (
            ("accel_psd_xy", "m^2/s^3", 1.5e-4),
            ("accel_psd_psi", "rad^2/s^3", 1e-6),
        )
    }
    roll_control = _read_roll_control(r, data, int(dofs), actuators)
    tr = r.table(data, "trials", required=False)
    r.keys(tr, "trials", {"approach_speed"})
    trials = {k: r.number(tr, k, "trials", "m/s", positive=True) for k in tr}
    if not (path / "vessel.xml").is_file():
        raise VesselError(f"{path}: vessel.xml (the MJCF hull body) is missing")
    return Vessel(
        name=name, title=title, folder=path, dofs=int(dofs), scale=scale, hull=hull,
        plants=plants, actuators=actuators, windage=windage, design=design, limits=limits,
        control=control, observer=observer, nominal_wind=nominal_wind, rigid_inertia=rigid,
        dimensions=dims, sources=dict(r.sources), roll_control=roll_control, trials=trials,
        plant_actuators=plant_actuators,
    )  # fmt: skip


def _read_roll_control(
    r: VesselReader, data: Mapping[str, Any], dofs: int, actuators: ActuatorSet
) -> dict[str, Any]:
    """The optional ``[roll_control]`` table: the rudder-roll design of a 4-DOF rudder vessel."""
    t = r.table(data, "roll_control", required=False)
    if not t:
        return {}
    if dofs != 4 or not any(isinstance(a, Rudder) for a in actuators):
        raise r.fail("roll_control", "needs a 4-DOF vessel with a rudder")
    r.keys(t, "roll_control", {"design_speed", "Q", "R", "heading_bandwidth", "heading_zeta"})
    out = {
        "design_speed": r.number(t, "design_speed", "roll_control", "m/s", positive=True),
        "Q": r.vector(t, "Q", "roll_control", 5, "1"),
        "R": r.number(t, "R", "roll_control", "1", positive=True),
        "heading_bandwidth": r.number(t, "heading_bandwidth", "roll_control", "rad/s",
                                      default=0.1, positive=True),
        "heading_zeta": r.number(t, "heading_zeta", "roll_control", "1", default=1.0,
                                 positive=True),
    }  # fmt: skip
    if min(out["Q"]) < 0:
        raise r.fail("roll_control.Q", f"the LQR state weights must be >= 0, got {out['Q']}")
    return out


@lru_cache(maxsize=64)
def _load_cached(path: Path, mtime: float) -> Vessel:
    return _read(path)


def _packaged() -> dict[str, Path]:
    out = {}
    for p in sorted(_ASSET_DIR.iterdir()):
        if (p / "vessel.toml").is_file():
            out[p.name.replace("_", "-")] = p
    return out


def vessel_names() -> list[str]:
    """Names of the packaged vessels (``shipgym/assets/mjcf/<name>/``)."""
    return list(_packaged())


def vessels() -> dict[str, Vessel]:
    """Every packaged vessel, loaded, by name."""
    return {n: load_vessel(n) for n in _packaged()}


def load_vessel(vessel: str | Path | Vessel) -> Vessel:
    """A vessel by registry name (``"blue-lady"``), package folder or ``vessel.toml`` path.

    Loading is cached per file (and reloaded when the file changes).

    Raises:
        VesselError: an invalid package (names the file and the key) or an unknown name
            (lists the packaged vessels).
    """
    if isinstance(vessel, Vessel):
        return vessel
    if not isinstance(vessel, str | Path):
        raise TypeError(f"vessel must be a name, a path or a Vessel, got {vessel!r}")
    packaged = _packaged()
    key = str(vessel).replace("_", "-")
    if isinstance(vessel, str) and key in packaged:
        path = packaged[key]
    else:
        path = Path(vessel).expanduser()
        if path.name == "vessel.toml":
            path = path.parent
        if not path.exists():
            raise VesselError(
                f"unknown vessel {str(vessel)!r}{did_you_mean(str(vessel), packaged)}: not a "
                f"packaged vessel ({', '.join(packaged)}) and no such folder"
            )
    path = path.resolve()
    toml_path = path / "vessel.toml"
    mtime = toml_path.stat().st_mtime if toml_path.is_file() else 0.0
    return _load_cached(path, mtime)
