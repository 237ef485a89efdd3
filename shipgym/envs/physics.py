r"""The physics of one hull: MuJoCo's rigid body moved exactly as the hull's model says.

:class:`VesselPhysics` is the batch of one of :class:`~shipgym.envs.batchphysics.BatchedPhysics`
(one code path: the single and the batched physics step the same compiled loop on the same
arrays), with the single physics' API: Python numbers and ``(3,)`` rows, commands and resets
of the one hull, its MuJoCo model and data.

Public names: ``INTEGRATORS``, ``VesselPhysics``, ``SimulationDiverged``, ``MAX_TIMESTEP``,
``MIN_TIMESTEP``, ``check_timestep``, ``contact_pairs``, ``joint_inertia``.

Design notes: docs/design/envs.physics.md.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym.disturbances import CurrentConfig, WaveConfig, WindConfig, WindLoad, blendermann
from shipgym.dynamics import PlantModel, WindageParameters
from shipgym.dynamics.hull4 import Hull4
from shipgym.dynamics.vessel import Vessel
from shipgym.sim.step import SimulationDiverged

from .batchphysics import (
    DEFAULT_TIMESTEP,
    INTEGRATORS,
    MAX_TIMESTEP,
    MIN_TIMESTEP,
    BatchedPhysics,
    HullView,
    check_lags,
    check_timestep,
    contact_pairs,
    joint_inertia,
)

__all__ = [
    "INTEGRATORS",
    "MAX_TIMESTEP",
    "MIN_TIMESTEP",
    "NO_CURRENT",
    "SimulationDiverged",
    "VesselPhysics",
    "check_lags",
    "check_timestep",
    "contact_pairs",
    "joint_inertia",
]

#: the current of a physics without one
NO_CURRENT = CurrentConfig()


class VesselPhysics(HullView):
    """A MuJoCo hull driven by its actuators, its hull model, wind, waves and current.

    Args:
        vessel: a :class:`~shipgym.dynamics.vessel.Vessel`, a packaged vessel's name
            (``"blue-lady"``, ``shipgym.vessels()``) or the path of a vessel package.
        plant: a plant variant name of the vessel (``"default"``, ...) or a model object
            (:class:`PlantModel` for 3 DOF, :class:`~shipgym.dynamics.hull4.Hull4` for 4).
        wind: wind: a :class:`~shipgym.disturbances.WindConfig`, ``"SPEED@FROM_DEG"``,
            ``(speed m/s, from deg)`` or a mapping (any form of
            :meth:`WindConfig.coerce <shipgym.disturbances.WindConfig.coerce>`). ``None``
            switches aerodynamic loads off altogether; ``WindConfig(speed=0)`` is still air, in
            which a moving hull feels air drag.
        windage: projected areas for the wind load; ``None``: the vessel's.
        current: current in NED: a :class:`~shipgym.disturbances.CurrentConfig` (constant or
            Gauss-Markov), ``"SPEED@TO_DEG"``, a constant ``(speed m/s, direction it goes to,
            deg)``, a mapping (:meth:`CurrentConfig.coerce
            <shipgym.disturbances.CurrentConfig.coerce>`) or ``None`` (no current). It acts
            through the relative velocity ``nu_r = nu - nu_c`` only.
        waves: a :class:`~shipgym.disturbances.WaveConfig` for the second-order (mean and
            slowly varying) drift load on the hull, or ``None``. First-order wave motion is
            not a hull motion: the environment adds it to the measurements
            (:meth:`wave_motion`).
        world: ``"open-water"`` or ``"harbour"`` (:data:`shipgym.envs.scene.WORLDS`).
        timestep: physics step (s), :data:`MIN_TIMESTEP` to :data:`MAX_TIMESTEP` and at most
            half the shortest actuator lag; ``None`` keeps the world's value (0.05 s).
        integrator: ``"mujoco"`` (MuJoCo's ``mj_step``: contacts, the harbour, rendering) or
            ``"leapfrog"`` (the same update without MuJoCo, as the batched physics; open
            water, no contacts); both apply the same forces (:mod:`shipgym.sim.step`).

    Pose and velocity: :attr:`eta` ``[x, y, psi]`` and :attr:`nu` ``[u, v, r]`` for every
    vessel (what the planar DP stack uses); a 4-DOF vessel adds :attr:`phi`, :attr:`p` and the
    Fossen-ordered :attr:`eta_full` ``[x, y, phi, psi]``, :attr:`nu_full` ``[u, v, p, r]``.
    Commands and actuator states follow the vessel's channel order
    (``physics.actuators.channel_names``).

    The physics owns no task logic: commands in, state out (dm_control's Physics/Task split).
    """

    def __init__(
        self,
        vessel: Vessel | str | Path,
        plant: PlantModel | Hull4 | str = "default",
        *,
        wind: WindConfig | str | tuple[float, float] | Mapping[str, Any] | None = None,
        windage: WindageParameters | None = None,
        current: CurrentConfig | str | tuple[float, float] | Mapping[str, Any] | None = None,
        waves: WaveConfig | None = None,
        world: str = "open-water",
        timestep: float | None = None,
        integrator: str = "mujoco",
    ) -> None:
        if integrator not in INTEGRATORS:
            raise ValueError(
                f"integrator must be one of {', '.join(INTEGRATORS)}, got {integrator!r}"
            )
        batch = BatchedPhysics(
            vessel, 1, plant, wind=wind, current=current, waves=waves,
            timestep=DEFAULT_TIMESTEP if timestep is None else timestep, integrator=integrator,
            world=world if integrator == "mujoco" else None, windage=windage,
        )  # fmt: skip
        super().__init__(batch, 0)
        self.world = world
        self.hull_body = self.model.body("hull").id
        self._opt = self.model.opt  # (read at every step: has the timestep changed?)
        self.reset()

    @property
    def _hulls(self) -> Any:
        """The hull batch of one (:class:`~shipgym.sim.step.HullBatch`) the batch steps."""
        return self.batch._hulls

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        del state["_opt"]  # (MuJoCo's MjOption view cannot be pickled: taken from the model)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._opt = self.model.opt

    # ---- set-up ----------------------------------------------------------------------------
    def set_current(
        self, current: CurrentConfig | str | tuple[float, float] | Mapping[str, Any] | None
    ) -> None:
        """Replace the current model (any form of ``current=``; effective at :meth:`reset`)."""
        b = self.batch
        b.set_disturbances(0, b.wind_configs[0], current)

    def set_wind(
        self, wind: WindConfig | str | tuple[float, float] | Mapping[str, Any] | None
    ) -> None:
        """Replace the wind model (any form of ``wind=``; takes effect at :meth:`reset`); a
        wind that names other Blendermann (1994) coefficients brings their load law."""
        b = self.batch
        cfg = WindConfig.coerce(wind, name="wind")
        name = (cfg.coefficients if cfg is not None else None) or self.windage.coefficients
        if cfg is not None and name != b._coeffs:  # the one hull's load law: its constants
            b._hulls.kw[:] = WindLoad(blendermann(name), self.windage).kernel_constants()
            b._coeffs = name
        b.set_disturbances(0, cfg, b.current_configs[0])

    # ---- state -----------------------------------------------------------------------------
    def initial_actuator_state(self) -> NDArray[np.float64]:
        """Actuator states after a reset: zero thrust, azimuths at their rest angle."""
        return self.actuators.initial_state()

    def _vector(self, x: ArrayLike | None, n: tuple[int, ...], what: str) -> NDArray[np.float64]:
        a = np.asarray(x, dtype=float)
        if a.shape not in [(k,) for k in n] or not np.all(np.isfinite(a)):
            raise ValueError(f"{what} must be {' or '.join(map(str, n))} finite numbers, got {x!r}")
        return a

    def reset(
        self,
        eta: ArrayLike = (0.0, 0.0, 0.0),
        nu: ArrayLike = (0.0, 0.0, 0.0),
        actuators: ArrayLike | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        """Reset to pose ``eta``, body velocity ``nu`` and actuator states.

        ``eta`` is ``[x, y, psi]`` (m, m, rad) or, for a 4-DOF vessel, ``[x, y, phi, psi]``;
        ``nu`` likewise ``[u, v, r]`` or ``[u, v, p, r]``. ``actuators`` defaults to
        :meth:`initial_actuator_state`. ``rng`` seeds the stochastic disturbances (wind
        gusts, current, waves); ``None`` uses a fixed seed 0.
        """
        n = (3, 4) if self.dofs == 4 else (3,)
        eta_a = self._vector(eta, n, "eta")
        nu_a = self._vector(nu, n, "nu")
        act = None if actuators is None else self.actuators.check_states(actuators, "actuators")
        self._follow_timestep()
        self.batch.reset(eta_a[None], nu_a[None], None if act is None else act[None],
                         rngs=None if rng is None else [rng])  # fmt: skip

    # ---- forces ----------------------------------------------------------------------------
    def _tau(self, st: NDArray[np.float64]) -> NDArray[np.float64]:
        """``[X, Y, K, N]`` of the plant's actuator laws at the states ``st``."""
        return self._hulls.actuator_loads(np.reshape(st, (1, -1)), None, None)[0]

    @property
    def tau_thrusters(self) -> NDArray[np.float64]:
        """Body-frame actuator force ``[X, Y, N]`` (N, N, N m) at the current actuator states
        (rudders at the current flow)."""
        X, Y, _K, N = self._tau(self._hulls.act[0]).tolist()
        return np.array([X, Y, N])

    @property
    def tau_actuators(self) -> NDArray[np.float64]:
        """Body-frame actuator force ``[X, Y, K, N]`` (N, N, N m, N m) at the current actuator
        states and flow (``K`` is 0 for a 3-DOF vessel)."""
        return self._tau(self._hulls.act[0])

    @property
    def external_force(self) -> tuple[float, float, float, float]:
        """The external load ``[X, Y, K, N]`` (N, N, N m, N m, body) set by
        :meth:`set_external_force`."""
        X, Y, K, N = self._hulls.external[0].tolist()
        return X, Y, K, N

    def set_external_force(self, tau: ArrayLike) -> None:
        """Hold an external body load ``[X, Y, K, N]`` (N, N, N m, N m; ``[X, Y, N]`` for 3 DOF)
        until changed: a task's disturbance (wave roll and yaw moments). Reset clears it.

        Raises:
            ValueError: wrong shape or a non-finite value.
        """
        a = self._vector(tau, (self.dofs,), "external force").tolist()
        self._hulls.external[0] = a if self.dofs == 4 else (a[0], a[1], 0.0, a[2])

    # ---- stepping --------------------------------------------------------------------------
    def set_command(self, command: ArrayLike) -> NDArray[np.bool_]:
        """Set the actuator commands (channel order), clipped to the physical ranges.

        Returns:
            Flags of the commands that were clipped (also kept in :attr:`saturated`).

        Raises:
            ValueError: wrong shape, NaN or infinite values.
        """
        _, vals = self.actuators.as_vector(command, "command")
        return self.batch.set_command(np.array(vals).reshape(1, -1))[0]

    def step(self, n: int = 1, *, stop_on_contact: bool = False) -> int:
        """Advance ``n`` physics steps with hydrodynamics, wind and current refreshed every step.

        Args:
            n: number of physics steps.
            stop_on_contact: return early, after the step in which MuJoCo detects a contact
                (the ``mujoco`` integrator; the ``leapfrog`` one has no contacts).

        Returns:
            The number of steps taken.

        Raises:
            SimulationDiverged: a non-finite or absurd state (the state before the step is kept).
        """
        if self._opt.timestep != self.batch.h:
            self._follow_timestep()
        return self._hulls.advance(n, stop_on_contact=stop_on_contact)  # type: ignore[no-any-return]

    def _follow_timestep(self) -> None:
        """The physics step of the model's ``opt.timestep``, where a user changed it."""
        h = float(self._opt.timestep)
        if h != self.batch.h:
            self.batch.set_timestep(h)
