r"""N hulls of one vessel stepped together: the physics of every env (the single
:class:`~shipgym.envs.physics.VesselPhysics` is its batch of one), and hull ``i`` read as a
single physics (:class:`HullView`).

Public names: ``BatchedPhysics``, ``HullView``, and the physics' checks and constants
(``INTEGRATORS``, ``MIN_TIMESTEP``, ``MAX_TIMESTEP``, ``check_timestep``, ``check_lags``,
``joint_inertia``, ``contact_pairs``).

Design notes: docs/design/envs.batchphysics.md.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._config import is_real
from shipgym._jit import njit
from shipgym.disturbances import (
    BLENDERMANN,
    Current,
    CurrentConfig,
    WaveConfig,
    Waves,
    Wind,
    WindConfig,
    WindLoad,
    blendermann,
)
from shipgym.dynamics import WindageParameters
from shipgym.dynamics.vessel import Vessel, load_vessel
from shipgym.sim._mujoco import mujoco

from .batched import MAX_ENVS
from .scene import build_model

__all__ = [
    "INTEGRATORS",
    "MAX_TIMESTEP",
    "MIN_TIMESTEP",
    "BatchedPhysics",
    "HullView",
    "check_lags",
    "check_timestep",
    "contact_pairs",
    "joint_inertia",
]

Array = NDArray[np.float64]

#: the default physics step of the worlds (s), as :class:`~shipgym.envs.physics.VesselPhysics`
DEFAULT_TIMESTEP = 0.05
#: largest |roll| (rad) of a reset state (69 deg: far beyond any ship's capsize angle)
_MAX_ROLL = 1.2


#: the integrators of :class:`VesselPhysics` (:mod:`shipgym.sim.step`)
INTEGRATORS = ("mujoco", "leapfrog")

#: smallest physics timestep (s). The default 0.05 s resolves the fastest dynamics (thruster
#: lags of 1-2 s, the hull's surge/sway/yaw time constants of tens of seconds) many times
#: over; below 1e-4 s each simulated second costs more than 10 000 MuJoCo steps for nothing.
MIN_TIMESTEP = 1e-4
#: largest physics timestep (s): half the Blue Lady's shortest thruster time constant (1 s,
#: the tunnel thrusters), where MuJoCo's semi-implicit Euler still tracks the lags; a vessel
#: with faster actuators needs a smaller step (checked against its lags when it is built).
MAX_TIMESTEP = 0.5


def joint_inertia(model: Any, actuators: Any, dofs: int) -> tuple[float, float, float]:
    """MuJoCo's joint-space inertia ``(m, I_z, I_x)`` (kg, kg m^2, kg m^2; ``I_x = 0`` for 3
    DOF) of a vessel model built by :func:`~shipgym.envs.scene.build_model`, after checking
    the model's layout: the joints ``x, y, psi[, phi]`` in this order, the actuators the
    channels in order, a constant diagonal inertia ``diag(m, m, I_z[, I_x])`` and no bias
    force (what the compiled step's ``qfrc_applied = M_q qacc`` relies on)."""
    m = model
    names = ("x", "y", "psi", "phi")[:dofs]
    jids = [m.joint(n).id for n in names]
    act_ids = [m.actuator(n).id for n in actuators.channel_names]
    if jids != list(range(dofs)) or m.nv != dofs:
        raise ValueError(f"the hull must have exactly the joints {names}, in this order")
    if act_ids != list(range(m.nu)) or m.nu != actuators.n_channels:
        raise ValueError("MuJoCo actuators must be the vessel's channels, in order")
    d = mujoco.MjData(m)
    if dofs == 4:  # a rolled, moving state: the inertia must not depend on it
        d.qpos[3] = 0.3
        d.qvel[:] = (0.4, -0.2, 0.05, 0.1)
    mujoco.mj_forward(m, d)
    Mq = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, Mq)
    diag = np.diag(Mq)
    scale = float(np.max(np.abs(Mq)))
    if (
        np.any(np.abs(Mq - np.diag(diag)) > 1e-9 * scale)
        or abs(diag[0] - diag[1]) > 1e-12 * diag[0]
        or np.any(np.abs(d.qfrc_bias) > 1e-9 * scale)
    ):
        raise ValueError(
            f"unexpected joint-space inertia (need a constant diag(m, m, I_z[, I_x])): {Mq}"
        )
    return float(Mq[0, 0]), float(Mq[2, 2]), float(Mq[3, 3]) if dofs == 4 else 0.0


def check_lags(actuators: Any, h: float, name: str) -> None:
    """``ValueError`` where the physics step ``h`` (s) is more than half the shortest
    actuator lag of the vessel ``name`` (the bound both physics classes set on their step)."""
    lags = [c.time_constant for c in actuators.channels if c.dynamics == "lag"]
    if lags and h > 0.5 * min(lags) + 1e-12:
        raise ValueError(
            f"timestep {h:g} s is more than half the shortest actuator lag of "
            f"{name!r} ({min(lags):g} s): use timestep <= {0.5 * min(lags):g}"
        )


def check_timestep(timestep: Any) -> float:
    """The physics timestep (s) as a float; ``TypeError``/``ValueError`` outside the bounds."""
    if not is_real(timestep):
        raise TypeError(f"timestep must be a number of seconds, got {timestep!r}")
    if not MIN_TIMESTEP <= timestep <= MAX_TIMESTEP:  # NaN fails too
        raise ValueError(
            f"timestep must be from {MIN_TIMESTEP:g} to {MAX_TIMESTEP:g} s, got {timestep!r}"
        )
    return float(timestep)


def contact_pairs(model: Any, data: Any) -> list[tuple[str, str]]:
    """Pairs of geom names in contact in ``data`` now (the hull's geom first when it is
    involved)."""
    if not data.ncon:  # (slicing MuJoCo's contact buffer costs about 0.2 ms)
        return []
    hull = model.body("hull").id
    out = []
    for c in data.contact[: data.ncon]:
        a, b = model.geom(c.geom1), model.geom(c.geom2)
        if b.bodyid[0] == hull:
            a, b = b, a
        out.append((a.name, b.name))
    return out


def _convex_hull(pts: Array) -> Array:
    """The convex hull of 2-D points (k, 2), counter-clockwise (Andrew's monotone chain)."""
    p = np.unique(np.round(pts, 12), axis=0)
    if p.shape[0] < 3:
        raise ValueError("the hull's footprint needs at least three distinct points")

    def half(seq: Array) -> list[Array]:
        out: list[Array] = []
        for q in seq:
            while len(out) >= 2:
                (ax, ay), (bx, by) = out[-1] - out[-2], q - out[-2]
                if ax * by - ay * bx > 0.0:  # a left turn: keep
                    break
                out.pop()
            out.append(q)
        return out

    lower, upper = half(p), half(p[::-1])
    return np.array(lower[:-1] + upper[:-1])


def contact_geometry(model: Any) -> tuple[Array, Array, list[str]]:
    """What the ``leapfrog`` integrator's contact check needs of a world's ``model``
    (:meth:`~shipgym.sim.step.HullBatch.set_obstacles`): the footprint of the hull's collision
    geoms (their convex hull in the horizontal plane, (k, 2), counter-clockwise, in the frame of
    the hull's planar joints: m), the rectangles of the box geoms it can collide with (R, 9) at
    their placed poses, and those geoms' names.

    The check is MuJoCo's contact test where it is two-dimensional: each obstacle's height must
    span the hull's, and the hull must have no roll joint (3 DOF).

    Raises:
        ValueError: a hull or obstacle geom the check does not handle (a hull geom other than a
            mesh or box, an obstacle other than a box), an obstacle lower or higher than the
            hull, or a hull body that does not sit at the origin of its joints.
    """
    d = mujoco.MjData(model)
    footprint, hull_geoms = _footprint(model, d)
    rects, names = _obstacle_rects(model, d, *hull_geoms)
    return footprint, rects, names


def _footprint(model: Any, d: Any) -> tuple[Array, tuple[list[int], float, float, float]]:
    """The hull's footprint (:func:`contact_geometry`) and what :func:`_obstacle_rects` needs
    of its geoms: their ids, their height range (m) and the footprint's reach (m)."""
    mujoco.mj_kinematics(model, d)
    hull = model.body("hull").id
    if model.body_jntnum[hull] != 3 or np.abs(d.xpos[hull][:2]).max() > 1e-12:
        raise ValueError("the leapfrog contact check needs a 3-DOF hull at its joints' origin")
    own = [g for g in range(model.ngeom) if model.geom_bodyid[g] == hull
           and (model.geom_contype[g] or model.geom_conaffinity[g])]  # fmt: skip
    pts = []
    for g in own:
        kind = model.geom_type[g]
        if kind == mujoco.mjtGeom.mjGEOM_MESH:
            m = model.geom_dataid[g]
            a, k = model.mesh_vertadr[m], model.mesh_vertnum[m]
            local = model.mesh_vert[a : a + k].astype(float)
        elif kind == mujoco.mjtGeom.mjGEOM_BOX:
            local = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T
            local = local * model.geom_size[g]
        else:
            raise ValueError(f"the leapfrog contact check handles mesh and box hull geoms, "
                             f"not geom {model.geom(g).name!r}")  # fmt: skip
        pts.append(local @ d.geom_xmat[g].reshape(3, 3).T + d.geom_xpos[g])
    world = np.concatenate(pts)
    footprint = _convex_hull(world[:, :2])
    reach = float(np.sqrt((footprint**2).sum(axis=1)).max())
    return footprint, (own, float(world[:, 2].min()), float(world[:, 2].max()), reach)


def _obstacle_rects(
    model: Any, d: Any, own: list[int], z_lo: float, z_hi: float, reach: float
) -> tuple[Array, list[str]]:
    """The rectangles (R, 9) and names of the box geoms that can collide with the hull's geoms
    ``own``, at their poses in ``d`` (after ``mj_kinematics``) (:func:`contact_geometry`)."""
    hull = model.geom_bodyid[own[0]]
    ct, ca = model.geom_contype, model.geom_conaffinity
    rects, names = [], []
    for g in range(model.ngeom):
        if model.geom_bodyid[g] == hull or not any((ct[g] & ca[o]) or (ct[o] & ca[g]) for o in own):
            continue  # the hull's own, or one that cannot touch it
        name = model.geom(g).name
        if model.geom_type[g] != mujoco.mjtGeom.mjGEOM_BOX:
            raise ValueError(f"the leapfrog contact check handles box obstacles, not {name!r}")
        R = d.geom_xmat[g].reshape(3, 3)
        half = model.geom_size[g]
        c = d.geom_xpos[g]
        if abs(R[2, 2]) < 1.0 - 1e-12 or not (c[2] - half[2] <= z_lo and z_hi <= c[2] + half[2]):
            raise ValueError(f"obstacle {name!r} must be an upright box spanning the hull's "
                             f"height ({z_lo:.3g} to {z_hi:.3g} m)")  # fmt: skip
        rects.append((c[0], c[1], R[0, 0], R[1, 0], R[0, 1], R[1, 1], half[0], half[1],
                      math.hypot(half[0], half[1]) + reach))  # fmt: skip
        names.append(name)
    return np.array(rects, dtype=float).reshape(-1, 9), names


#: the columns ``[u, v, r]`` of a hull's ``(u, v, p, r)``
_UVR = np.array([0, 1, 3])
#: Fossen's 4-DOF pose order [x, y, phi, psi] from the joints' [x, y, psi, phi]
_FOSSEN4 = np.array([0, 1, 3, 2])
_XYN = _UVR  # (X, Y, N) of (X, Y, K, N)


@njit
def _hold_commands(c, lo, hi, cmd, flags):  # type: ignore[no-untyped-def]
    """The commands ``c`` (n, n_channels) clipped to each channel's ``[lo, hi]`` into ``cmd``
    and where they were clipped into ``flags``: ``min(max(c, lo), hi)`` as two comparisons,
    the single physics' clip (:meth:`VesselPhysics.set_command
    <shipgym.envs.physics.VesselPhysics.set_command>`). Returns -1, or the first row with a
    command that is not finite (then nothing is written)."""
    n, m = c.shape
    for i in range(n):
        for j in range(m):
            if not math.isfinite(c[i, j]):
                return i
    for i in range(n):
        for j in range(m):
            x = c[i, j]
            y = hi[j] if x > hi[j] else (lo[j] if x < lo[j] else x)
            cmd[i, j] = y
            flags[i, j] = y != x
    return -1


class BatchedPhysics:
    """``n`` hulls of ``vessel`` stepped together (module docstring).

    Args:
        vessel: a :class:`~shipgym.dynamics.vessel.Vessel`, a packaged vessel's name or a
            package path.
        n: number of hulls, >= 1.
        plant: a plant variant name of the vessel or a hull model of a hull family.
        wind: any form of ``VesselPhysics(wind=)`` or ``None`` (no aerodynamic load).
        current: any form of ``VesselPhysics(current=)`` or ``None``.
        waves: a :class:`~shipgym.disturbances.WaveConfig` (the second-order drift acts on
            the hulls) or ``None``.
        timestep: physics step (s), at most half the shortest actuator lag.
        integrator: ``"leapfrog"`` (the compiled step) or ``"mujoco"`` (MuJoCo's
            ``mj_step`` per hull, in ``world``).
        world: the hulls' world (:data:`~shipgym.envs.scene.WORLDS`; default ``"open-water"``);
            each hull has its own model (:attr:`models`), so a world's layout may be placed
            per hull. Leapfrog hulls in a world touch its obstacles through a compiled
            two-dimensional contact check (:func:`contact_geometry`: MuJoCo's contacts of a
            3-DOF hull among upright boxes spanning its height) and stop on contact as the
            ``mujoco`` ones do.
    """

    def __init__(
        self,
        vessel: Vessel | str | Path,
        n: int,
        plant: Any = "default",
        *,
        wind: Any = None,
        current: Any = None,
        waves: WaveConfig | None = None,
        timestep: float = DEFAULT_TIMESTEP,
        integrator: str = "leapfrog",
        world: str | None = None,
        windage: WindageParameters | None = None,
    ) -> None:
        from shipgym.sim.step import HullBatch

        self.vessel = load_vessel(vessel)
        v = self.vessel
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_ENVS:
            raise ValueError(f"n must be an int in [1, {MAX_ENVS}] (the hulls), got {n!r}")
        self.n = n
        self.plant = v.plant(plant) if isinstance(plant, str) else plant
        dofs = getattr(self.plant, "dofs", None)
        if dofs not in (3, 4) or getattr(type(self.plant), "accel_kernel", None) is None:
            raise TypeError(
                f"plant must be a hull model of a hull family (PlantModel, Hull4, Blanke4Hull, "
                f"MMGHull, ...: a compiled accel_kernel) or a variant name, got {plant!r}"
            )
        if dofs != v.dofs:
            raise ValueError(f"plant {plant!r} has {dofs} DOF but vessel {v.name!r} has {v.dofs}")
        self.windage = v.windage if windage is None else windage
        if not isinstance(self.windage, WindageParameters):
            raise TypeError(f"windage must be WindageParameters or None, got {windage!r}")
        if (self.windage.coefficients or "") not in BLENDERMANN:
            raise ValueError(
                f"vessel {v.name!r}: windage.coefficients {self.windage.coefficients!r} is not a "
                f"Blendermann (1994) ship type; valid: {', '.join(sorted(BLENDERMANN))}"
            )
        self.dofs = v.dofs
        # the actuators this plant drives (a plant of the paper's model: the bollard laws)
        self.actuators = acts = v.actuators_for(self.plant)
        self.h = check_timestep(timestep)
        check_lags(acts, self.h, v.name)
        if waves is not None and not isinstance(waves, WaveConfig):
            raise ValueError(f"waves must be a WaveConfig or None, got {waves!r}")
        self.lower = acts.lower.copy()
        self.upper = acts.upper.copy()
        self._holds = acts.holds_state
        wind_cfg = WindConfig.coerce(wind, name="wind")
        # the configs of "none" (one object each, so that a hull's process is kept: see
        # set_disturbances)
        self._calm_wind = WindConfig()
        self._still_water = CurrentConfig()
        cc = CurrentConfig.coerce(current, name="current") or self._still_water
        self._coeffs = (wind_cfg.coefficients if wind_cfg else None) or self.windage.coefficients
        wind_load = WindLoad(blendermann(self._coeffs), self.windage)
        if integrator not in INTEGRATORS:
            raise ValueError(
                f"integrator must be one of {', '.join(INTEGRATORS)}, got {integrator!r}"
            )
        self.integrator = integrator
        #: the hulls' world (``None``: open water without a model of its own)
        self.world = world
        self.models: list[Any] = []
        self.datas: list[Any] = []
        inertia = (0.0, 0.0, 0.0, 0.0)  # the leapfrog integrator does not use it
        if integrator == "mujoco" or world is not None:
            model = build_model(v, world or "open-water", acts)
            model.opt.timestep = self.h
            self.models = [model] + [copy.deepcopy(model) for _ in range(n - 1)]
        self._footprint: Array | None = None
        if integrator == "mujoco":
            self.datas = [mujoco.MjData(m) for m in self.models]
            m_q, i_q, i_x = joint_inertia(self.models[0], acts, self.dofs)
            inertia = (m_q, m_q, i_q, i_x)
        elif world is not None:  # leapfrog hulls among the world's obstacles
            if self.dofs != 3:
                raise ValueError("world= with the leapfrog integrator needs a 3-DOF vessel")
            self._scratch = [mujoco.MjData(m) for m in self.models]  # (the placed obstacles)
            self._footprint, self._hull_geoms = _footprint(self.models[0], self._scratch[0])
        self._hulls = HullBatch(self.plant, acts, wind_load.kernel_constants(), n, self.h,
                                inertia, integrator=integrator,
                                model=self.models if self.datas else None,
                                data=self.datas or None)  # fmt: skip
        self.wind_configs: list[WindConfig | None] = [wind_cfg] * n
        self.current_configs: list[CurrentConfig] = [cc] * n
        self.wave_config = waves
        self.winds = [Wind(wind_cfg or self._calm_wind, self.windage) for _ in range(n)]
        self.currents = [Current(cc) for _ in range(n)]
        self.waves = [Waves(waves, v.hull) if waves is not None else None for _ in range(n)]
        self._wf: Any = None  # wave_motion's windows
        self.saturated = np.zeros((n, acts.n_channels), dtype=bool)
        self._servo_channels = np.array(
            [i for i, c in enumerate(acts.channels) if c.dynamics == "servo"], dtype=np.int64
        )
        self._flow_actuators = np.array(
            [i for i, a in enumerate(acts) if a.flow_dependent], dtype=np.int64
        )
        self.reset()

    def qpos(self, i: int) -> Array:
        """Hull ``i``'s MuJoCo joint positions (its world's ``qpos``: rendering)."""
        return self._hulls.q[i].copy()

    @property
    def timestep(self) -> float:
        """The physics step (s)."""
        return self.h

    @property
    def aerodynamics(self) -> bool:
        """Whether any hull feels a wind load."""
        return any(w is not None for w in self.wind_configs)

    @property
    def t(self) -> Array:
        """Each hull's time (s), (n,)."""
        return self._hulls.t

    def set_disturbances(self, i: int, wind: Any = None, current: Any = None) -> None:
        """Give hull ``i`` its own wind and current (any form of ``VesselPhysics(wind=,
        current=)``; ``None``: none), effective at its next :meth:`reset`, as
        ``VesselPhysics.set_wind`` / ``set_current``. Every hull's wind uses the same
        Blendermann coefficients (the vessel's, or those the constructor's wind names)."""
        wind_cfg = WindConfig.coerce(wind, name="wind")
        cc = CurrentConfig.coerce(current, name="current") or self._still_water
        if wind_cfg is not None and (wind_cfg.coefficients or self._coeffs) != self._coeffs:
            raise ValueError(
                f"hull {i}: wind coefficients {wind_cfg.coefficients!r} differ from the batch's "
                f"{self._coeffs!r}; one batch uses one set of Blendermann coefficients"
            )
        # the same config as the hull's last one (a task's fixed wind): its process object is
        # kept (each reset draws the realisation afresh), not built again
        if wind_cfg is not self.wind_configs[i]:
            self.winds[i] = Wind(wind_cfg or self._calm_wind, self.windage)
        if cc is not self.current_configs[i]:
            self.currents[i] = Current(cc)
        self.wind_configs[i] = wind_cfg
        self.current_configs[i] = cc

    def set_actuators(self, i: int, vessel: Vessel) -> None:
        """Give hull ``i`` the actuator constants of ``vessel``, a variant of the batch's
        vessel with the same actuator kinds and channels (a rudder moved: the printed
        ``K_dp`` law of :func:`~shipgym.dynamics.vanderklugt.seed_vessel` at each hull's
        speed); effective from its next step. :attr:`actuators` stays the batch's."""
        self._hulls.set_actuators(i, vessel.actuators_for(self.plant))

    def set_timestep(self, timestep: float) -> None:
        """Change every hull's physics step (s), keeping their states, commands, processes and
        actuator constants (the worlds' ``opt.timestep`` too)."""
        from shipgym.sim.step import HullBatch

        h = check_timestep(timestep)
        check_lags(self.actuators, h, self.vessel.name)
        old = self._hulls
        for m in self.models:
            m.opt.timestep = h
        self.h = h
        hb = HullBatch(self.plant, self.actuators, old.kw, self.n, h, tuple(old.inertia.tolist()),
                       integrator=self.integrator, model=self.models if self.datas else None,
                       data=self.datas or None)  # fmt: skip
        for name in ("q", "qv", "qa", "act", "cmd", "t", "external", "table"):
            getattr(hb, name)[:] = getattr(old, name)
        for name in ("footprint", "obstacles", "n_obstacles", "touching"):
            setattr(hb, name, getattr(old, name).copy())
        drift = self.wave_config is not None and self.wave_config.drift
        for i in range(self.n):
            wind = self.winds[i] if self.wind_configs[i] is not None else None
            hb.set_processes(i, wind, self.currents[i], self.waves[i] if drift else None)
        self._hulls = hb

    # ---- state -----------------------------------------------------------------------------
    def _rows(self, x: ArrayLike | None, width: int, what: str, default: Array) -> Array:
        if x is None:
            return default.copy()
        a = np.asarray(x, dtype=float)
        if a.shape == (width,):
            a = np.broadcast_to(a, (self.n, width))
        if a.shape != (self.n, width) or not np.all(np.isfinite(a)):
            raise ValueError(
                f"{what} must be ({width},) or ({self.n}, {width}) finite numbers, got shape "
                f"{np.shape(x)}"
            )
        return np.array(a, dtype=float)

    def initial_actuator_state(self) -> Array:
        """Actuator states after a reset, (n, n_channels): those of the single physics."""
        out = self.actuators.initial_state()
        return np.broadcast_to(out, (self.n, out.size)).copy()

    def reset(
        self,
        eta: ArrayLike | None = None,
        nu: ArrayLike | None = None,
        actuators: ArrayLike | None = None,
        mask: ArrayLike | None = None,
        rngs: list[np.random.Generator] | None = None,
    ) -> None:
        """Reset the hulls (all, or those where ``mask`` is True) to ``eta``, ``nu`` and
        actuator states; commands are set to hold them.

        ``eta``, ``nu``: ``(3,)`` or ``(n, 3)`` (``[x, y, psi]``, ``[u, v, r]``), or for a
        4-DOF vessel also Fossen's ``(4,)`` or ``(n, 4)`` (``[x, y, phi, psi]``, ``[u, v,
        p, r]``). ``rngs``: one generator per hull (the reset ones are used) for its wind
        gusts, current and waves, drawn in the single physics' order; ``None``: seed 0 for
        each, as ``VesselPhysics.reset(rng=None)``.
        """
        width = 4 if self.dofs == 4 and eta is not None and np.shape(eta)[-1] == 4 else 3
        e = self._rows(eta, width, "eta", np.zeros((self.n, width)))
        width = 4 if self.dofs == 4 and nu is not None and np.shape(nu)[-1] == 4 else 3
        w = self._rows(nu, width, "nu", np.zeros((self.n, width)))
        if self.dofs == 4:
            if e.shape[1] == 4 and np.any(np.abs(e[:, 2]) >= _MAX_ROLL):
                raise ValueError(f"roll angle must be below {_MAX_ROLL} rad, got {e[:, 2]!r}")
            if e.shape[1] == 3:
                e = np.stack([e[:, 0], e[:, 1], np.zeros(self.n), e[:, 2]], 1)
            if w.shape[1] == 3:
                w = np.stack([w[:, 0], w[:, 1], np.zeros(self.n), w[:, 2]], 1)
        act = self._rows(actuators, self.actuators.n_channels, "actuators",
                         self.initial_actuator_state())  # fmt: skip
        act = np.where(self._holds, np.clip(act, self.lower, self.upper), act)
        m = np.ones(self.n, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        if m.shape != (self.n,):
            raise ValueError(f"mask must be ({self.n},) booleans, got shape {m.shape}")
        if rngs is not None and len(rngs) != self.n:
            raise ValueError(f"rngs must hold one generator per hull ({self.n}), got {len(rngs)}")
        hb = self._hulls
        drift = self.wave_config is not None and self.wave_config.drift
        for i in np.nonzero(m)[0].tolist():
            self.saturated[i] = False
            if self._footprint is not None:  # the obstacles where the world's are placed now
                mujoco.mj_kinematics(self.models[i], self._scratch[i])
                rects = _obstacle_rects(self.models[i], self._scratch[i], *self._hull_geoms)[0]
                hb.set_obstacles(self._footprint, i, rects)
            if self._wf is not None:
                self._wf.invalidate(i)
            hb.reset_hull(
                i, e[i], w[i], act[i], self._holds,
                rngs[i] if rngs is not None else np.random.default_rng(0),
                self.winds[i], self.currents[i], self.waves[i],
                aerodynamics=self.wind_configs[i] is not None, drift=bool(drift),
            )  # fmt: skip

    @property
    def eta(self) -> Array:
        """Poses ``[x, y, psi]`` (n, 3) (m, m, rad; psi continuous)."""
        return self._hulls.q[:, :3].copy()

    @property
    def eta_full(self) -> Array:
        """``[x, y, psi]`` (n, 3), or Fossen's ``[x, y, phi, psi]`` (n, 4) for 4 DOF."""
        q = self._hulls.q
        # (take: C-contiguous whatever n, as the compiled consumers are typed; a fancy index
        # gives Fortran order for n > 1, another compile of each)
        return q.copy() if self.dofs == 3 else q.take(_FOSSEN4, axis=1)

    @property
    def nu(self) -> Array:
        """Body velocities ``[u, v, r]`` (n, 3) at the whole step."""
        return self._hulls.body_velocities().take(_UVR, axis=1)

    @property
    def nu_full(self) -> Array:
        """``[u, v, r]`` (n, 3), or Fossen's ``[u, v, p, r]`` (n, 4) for 4 DOF."""
        w = self._hulls.body_velocities()
        return w.take(_UVR, axis=1) if self.dofs == 3 else w

    @property
    def actuator_state(self) -> Array:
        """Actuator states (n, n_channels)."""
        return self._hulls.act.copy()

    @property
    def command(self) -> Array:
        """The held (clipped) commands (n, n_channels)."""
        return self._hulls.cmd.copy()

    @property
    def rate_limited(self) -> NDArray[np.bool_]:
        """Per hull and servo channel, (n, n_servos): still at its rate limit in the last
        physics step (as ``VesselPhysics.rate_limited``)."""
        return self._hulls.hits[:, self._servo_channels] > 0

    @property
    def nu_c(self) -> Array:
        """Each hull's current ``(u_c, v_c)`` (m/s) in its body frame at the last physics step,
        (n, 2) (as ``VesselPhysics.nu_c``)."""
        return self._hulls.loads[:, 6:8].copy()

    @property
    def servo_channels(self) -> list[int]:
        """The channels with servo dynamics (the columns of :attr:`rate_limited`)."""
        return list(self._servo_channels)

    @property
    def stalled(self) -> NDArray[np.bool_]:
        """Per hull and flow-dependent actuator, (n, n_flow): past its stall angle at the
        last step (as ``VesselPhysics.stalled``)."""
        return self._hulls.flags[:, self._flow_actuators] > 0

    # ---- stepping --------------------------------------------------------------------------
    def set_external_force(self, tau: ArrayLike) -> None:
        """Hold an external body load on every hull, ``(n, 4)`` ``[X, Y, K, N]`` (N, N, N m,
        N m; ``K`` acts on a 4-DOF hull only) until the next call or the hull's reset."""
        self._hulls.external[:] = self._rows(tau, 4, "external force", self._hulls.external)

    def set_command(self, command: ArrayLike) -> NDArray[np.bool_]:
        """Commands ``(n, n_channels)`` (or one row for all), clipped to the channels' ranges;
        returns the clip flags (also :attr:`saturated`)."""
        nc = self.actuators.n_channels
        # (C-contiguous: the compiled hold's one type; a transposed command is another)
        c = None if command is None else np.ascontiguousarray(command, dtype=float)
        if c is None or c.shape != (self.n, nc):
            c = self._rows(command, nc, "command", self._hulls.cmd)  # one row, none, or refused
        flags = np.empty((self.n, nc), dtype=bool)
        if _hold_commands(c, self.lower, self.upper, self._hulls.cmd, flags) >= 0:
            self._rows(command, nc, "command", self._hulls.cmd)  # refused: not finite
        self.saturated = flags
        return flags.copy()

    def step(
        self, k: int = 1, *, stop_on_contact: bool = False, mask: ArrayLike | None = None
    ) -> NDArray[np.int64]:
        """Advance every hull (or those where ``mask`` is True) ``k`` physics steps; returns
        the steps each hull took, (n,) (fewer than ``k`` only where ``stop_on_contact``
        stopped a hull of the ``mujoco`` integrator after the step in which it touched
        something; 0 for the hulls outside ``mask``).

        Raises:
            SimulationDiverged: a non-finite or absurd state (naming the time and the state).
        """
        hb = self._hulls
        m = None if mask is None else np.asarray(mask, dtype=bool)
        hb.advance(k, stop_on_contact=stop_on_contact, mask=m)
        taken = k - hb.stopped
        return taken if m is None else np.where(m, taken, 0)

    def wave_motion(self) -> Array:
        """Each hull's first-order wave-frequency motion ``(dx m, dy m, dpsi rad)`` (NED) now,
        (n, 3), what its sensors see (zeros without first-order waves), as
        :meth:`VesselPhysics.wave_motion <shipgym.envs.physics.VesselPhysics.wave_motion>`
        (one law: :func:`~shipgym.disturbances.waves.wf_rows`)."""
        if self.wave_config is None or not self.wave_config.first_order:
            return np.zeros((self.n, 3))
        if self._wf is None:
            from shipgym.disturbances.waves import WaveMotionRows

            self._wf = WaveMotionRows(self.waves)
        return self._wf(self.t)

    def hull(self, i: int) -> HullView:
        """Hull ``i`` with the single physics' read-out (:class:`HullView`)."""
        return HullView(self, i)

    @property
    def contact_counts(self) -> NDArray[np.int64]:
        """MuJoCo's number of contacts of each hull now, (n,) (zeros for ``leapfrog``)."""
        return self._hulls.contact_counts()

    # ---- the thrust a DP system's observer is fed (VesselPhysics.tau_model, tau_command) ----
    @property
    def tau_model(self) -> Array:
        """Each hull's :attr:`VesselPhysics.tau_model <shipgym.envs.physics.VesselPhysics.
        tau_model>`, (n, 3) ``[X, Y, N]`` (N, N, N m): the bollard thrust model of its actuator
        states (the same compiled laws, the same floats)."""
        return self._tau_rows(self._hulls.act, self._bollard())

    def _bollard(self) -> Any:
        """The bollard laws' table (``None``: the plant's own laws are the model), found once."""
        if not hasattr(self, "_bollard_table"):
            model = self.actuators.bollard()
            self._bollard_table = None if model is self.actuators else model.law_table()
        return self._bollard_table

    @property
    def tau_command(self) -> Array:
        """Each hull's :attr:`VesselPhysics.tau_command <shipgym.envs.physics.VesselPhysics.
        tau_command>`, (n, 3): the plant's thrust law at the held commands (lagged and servo
        channels) and the current integrator states."""
        hb = self._hulls
        return self._tau_rows(np.where(self._holds, hb.cmd, hb.act), None)

    @property
    def thrust(self) -> Array:
        """Each hull's :attr:`VesselPhysics.thrust <shipgym.envs.physics.VesselPhysics.
        thrust>`, (n, n_actuators) (N): every actuator's signed thrust at its state and the
        hull's flow (the plant's compiled laws, the same floats)."""
        hb = self._hulls
        forces = np.empty((self.n, hb.kind_index.shape[0]))
        hb.actuator_loads(hb.act, None, forces)
        return forces

    def readouts(self, command: bool = False) -> tuple[Array, Array, Array | None]:
        """``(thrust, tau_model, tau_command)`` now, the properties' floats from one compiled
        call (:meth:`HullBatch.readouts <shipgym.sim.step.HullBatch.readouts>`);
        ``tau_command`` only where ``command`` (else ``None``): what an env reads of one
        state."""
        return self._hulls.readouts(self._bollard(), self._holds, command)  # type: ignore[no-any-return]

    def _tau_rows(self, st: Array, table: Any, forces: Array | None = None) -> Array:
        """``[X, Y, N]`` (n, 3) of the actuator laws ``table`` at the states ``st`` (n, nc)
        and each hull's velocity through the water; each actuator's own force (N) into
        ``forces`` (n, n_actuators) where given
        (:meth:`HullBatch.actuator_loads <shipgym.sim.step.HullBatch.actuator_loads>`)."""
        return self._hulls.actuator_loads(st, table, forces)[:, _XYN]


class HullView:
    """Hull ``i`` of a :class:`BatchedPhysics`, read as a single physics is
    (:class:`~shipgym.envs.physics.VesselPhysics`' read-out: Python numbers, ``(3,)`` rows):
    what the single env of a plan task, its recorder and its users read. It holds no state
    of its own: every value is the batch's row ``i`` now.
    """

    def __init__(self, batch: BatchedPhysics, i: int) -> None:
        self.batch = batch
        self.i = i
        self.vessel = batch.vessel
        self.plant = batch.plant
        self.actuators = batch.actuators
        self.dofs = batch.dofs
        self.integrator = batch.integrator
        self.wave_config = batch.wave_config
        self.windage = batch.windage
        #: the world the hull is drawn in
        self.world = batch.world or "open-water"
        self._view: Any = None  # (model, data) of a leapfrog hull's pose (rendering)

    # ---- configuration of the episode ------------------------------------------------------
    @property
    def timestep(self) -> float:
        """The physics step (s)."""
        return self.batch.h

    @property
    def aerodynamics(self) -> bool:
        """Whether the hull feels a wind load."""
        return self.batch.wind_configs[self.i] is not None

    @property
    def wind_config(self) -> WindConfig:
        """The wind now (``WindConfig()``, still air, where :attr:`aerodynamics` is off)."""
        cfg = self.batch.wind_configs[self.i]
        return self.batch._calm_wind if cfg is None else cfg

    @property
    def wind(self) -> Wind:
        """The hull's wind process."""
        return self.batch.winds[self.i]

    @property
    def current_config(self) -> CurrentConfig:
        """The current now (``speed == 0``: none)."""
        return self.batch.current_configs[self.i]

    @property
    def current(self) -> Current:
        """The hull's current process."""
        return self.batch.currents[self.i]

    @property
    def waves(self) -> Waves | None:
        """The hull's sea (``None`` without waves)."""
        return self.batch.waves[self.i]

    # ---- state -----------------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Simulation time (s)."""
        return float(self.batch.t[self.i])

    @property
    def eta(self) -> Array:
        """Pose ``[x, y, psi]`` (m, m, rad; psi continuous)."""
        return self.batch._hulls.q[self.i, :3].copy()

    @property
    def nu(self) -> Array:
        """Body velocity ``[u, v, r]`` (m/s, m/s, rad/s)."""
        u, v, _p, r = self.batch._hulls.body_velocity(self.i)
        return np.array([u, v, r])

    @property
    def phi(self) -> float:
        """Roll angle (rad), 0 for a 3-DOF vessel."""
        return float(self.batch._hulls.q[self.i, 3]) if self.dofs == 4 else 0.0

    @property
    def p(self) -> float:
        """Roll rate (rad/s), 0 for a 3-DOF vessel."""
        return float(self.batch._hulls.body_velocity(self.i)[2])

    @property
    def eta_full(self) -> Array:
        """``[x, y, psi]`` (3 DOF) or Fossen's ``[x, y, phi, psi]`` (4 DOF)."""
        return self.batch.eta_full[self.i]

    @property
    def nu_full(self) -> Array:
        """``[u, v, r]`` (3 DOF) or Fossen's ``[u, v, p, r]`` (4 DOF)."""
        return self.batch.nu_full[self.i]

    @property
    def actuator_state(self) -> Array:
        """Actuator states, in channel order."""
        return self.batch._hulls.act[self.i].copy()

    @property
    def command(self) -> Array:
        """The held (clipped) commands, in channel order."""
        return self.batch._hulls.cmd[self.i].copy()

    @property
    def saturated(self) -> NDArray[np.bool_]:
        """The clip flags of the last commands."""
        return self.batch.saturated[self.i].copy()

    @property
    def thrust(self) -> Array:
        """Signed thrust of every actuator (N) at its state and the hull's flow."""
        return self.batch.thrust[self.i]

    @property
    def tau_model(self) -> Array:
        """:attr:`BatchedPhysics.tau_model` of the hull, ``[X, Y, N]`` (N, N, N m)."""
        return self.batch.tau_model[self.i]

    @property
    def tau_command(self) -> Array:
        """:attr:`BatchedPhysics.tau_command` of the hull, ``[X, Y, N]`` (N, N, N m)."""
        return self.batch.tau_command[self.i]

    @property
    def tau_wind(self) -> tuple[float, float, float]:
        """Wind load ``[X, Y, N]`` (N, N, N m, body) of the last physics step."""
        X, Y, N = self.batch._hulls.loads[self.i, 0:3].tolist()
        return X, Y, N

    @property
    def tau_waves(self) -> tuple[float, float, float]:
        """Second-order wave drift load ``[X, Y, N]`` (N, N, N m, body) of the last step."""
        X, Y, N = self.batch._hulls.loads[self.i, 3:6].tolist()
        return X, Y, N

    def environment_loads(self) -> tuple[Array, Array, Array]:
        """``(tau_wind, tau_waves, current_body)`` of the last physics step as new arrays:
        :attr:`tau_wind`, :attr:`tau_waves` (N, N, N m) and ``[u_c, v_c, 0]`` (m/s, the
        ``nu`` layout) from one read of the hull's row."""
        out = np.zeros(9)  # one new array, the three its rows
        out[:8] = self.batch._hulls.loads[self.i, :8]
        return out[0:3], out[3:6], out[6:9]

    @property
    def nu_c(self) -> tuple[float, float]:
        """Current ``(u_c, v_c)`` (m/s) in the body frame at the last physics step."""
        u, v = self.batch._hulls.loads[self.i, 6:8].tolist()
        return u, v

    @property
    def rate_limited(self) -> NDArray[np.bool_]:
        """Per servo channel: at its rate limit in the last physics step."""
        return self.batch.rate_limited[self.i]

    @property
    def stalled(self) -> NDArray[np.bool_]:
        """Per flow-dependent actuator: past its stall angle at the last step."""
        return self.batch.stalled[self.i]

    def wave_motion(self) -> tuple[float, float, float]:
        """First-order wave motion ``(dx m, dy m, dpsi rad)`` (NED) now, what sensors see."""
        dx, dy, dpsi = self.batch.wave_motion()[self.i].tolist()
        return dx, dy, dpsi

    def wave_elevation(self) -> float:
        """Wave elevation (m) now at the wave field's reference point (0 without waves)."""
        w = self.waves
        return 0.0 if w is None else float(w.elevation(self.time))

    # ---- MuJoCo ----------------------------------------------------------------------------
    @property
    def model(self) -> Any:
        """The hull's MuJoCo model (its world's, or an open-water one for a leapfrog hull)."""
        return self._mujoco()[0]

    @property
    def data(self) -> Any:
        """The hull's ``MjData`` now (a leapfrog hull's pose and clock copied in)."""
        model, data = self._mujoco()
        if self.integrator == "leapfrog":
            data.qpos[:] = self.batch._hulls.q[self.i]
            data.time = self.time
            mujoco.mj_forward(model, data)
        return data

    def _mujoco(self) -> tuple[Any, Any]:
        b = self.batch
        if b.datas:
            return b.models[self.i], b.datas[self.i]
        if self._view is None:
            if b.models:  # (its world's placed layout)
                model = b.models[self.i]
            else:
                model = build_model(b.vessel, self.world, b.actuators)
                model.opt.timestep = b.h
            self._view = (model, mujoco.MjData(model))
        return self._view  # type: ignore[no-any-return]

    def contacts(self) -> list[tuple[str, str]]:
        """Pairs of geom names in contact now (the hull's geom first when it is involved):
        MuJoCo's of the last step (``mujoco``); for a ``leapfrog`` hull in a world, MuJoCo's
        contacts at its pose where the contact check found it touching at its last step's
        start (none otherwise, and none in open water)."""
        if not self.batch.models:
            return []
        if self.integrator == "leapfrog":
            if not self.batch.contact_counts[self.i]:
                return []
            return contact_pairs(self.model, self.data)
        return contact_pairs(*self._mujoco())
