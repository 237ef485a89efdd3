"""Observers as a Gymnasium wrapper: env -> ObserverWrapper -> controller wrapper.

Not an ``ObservationWrapper``: the model-based observers need the applied thrust, which the
environment reports with every sensor sample (:class:`shipgym.records.Measurement`, in the
step's :class:`~shipgym.records.StepRecord`, ``info["record"]``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from shipgym.dynamics import wrap_angle
from shipgym.records import NavigationData, StepRecord, step_record

__all__ = ["ObserverWrapper"]


class ObserverWrapper(
    gym.Wrapper[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32], NDArray[np.float32]],
    gym.utils.RecordConstructorArgs,
):
    """Feeds the sensor samples and applied thrust to an observer; exposes its estimate.

    The thrust handed to ``observer.step`` is each sample's applied force
    (:attr:`Measurement.tau <shipgym.records.Measurement.tau>`), or, for an observer with
    ``thrust_input = "command"`` (one that models the thruster lags itself), the steady-state
    force of the held commands (:attr:`Measurement.tau_command
    <shipgym.records.Measurement.tau_command>`).

    After every ``reset``/``step`` the observation is rebuilt from the estimate (same layout
    as the environment's), the record's navigation data (``info["record"].nav``, a
    :class:`~shipgym.records.NavigationData`: what a controller wrapper stacked above uses)
    and ``info["nav_eta"]``/``info["nav_nu"]`` become the estimate, and the info gains the
    estimation errors against the truth: ``est_error_eta`` (m, m, rad; heading wrapped),
    ``est_error_nu`` (m/s, m/s, rad/s), ``observer_nis`` and ``observer_rejected`` (outlier
    gate) of the last update, and at the end of an episode ``estimation_rmse`` (x, y, psi, u,
    v, r; psi and r in degrees and deg/s; also ``info["record"].estimation_rmse``).

    Args:
        env: a ``shipgym/BlueLady*`` environment with sensors.
        observer: an observer name (``shipgym.observers.OBSERVERS``: ``dkf``, ``kbf``, ``ekf``,
            ``tomera-dkf``, ``alt-kf14``, ...).
        options: keyword arguments for the observer's factory (e.g. ``{"beaufort": 5}``, the
            sea state an ``alt-*`` wave filter is designed for); they win over the vessel's.

    Note:
        Records its constructor arguments, so ``gym.make(env.spec)`` rebuilds the stack.
    """

    def __init__(
        self,
        env: gym.Env[Any, Any],
        observer: str = "kbf",
        options: Mapping[str, Any] | None = None,
    ) -> None:
        gym.utils.RecordConstructorArgs.__init__(
            self, observer=observer, options=None if options is None else dict(options)
        )
        gym.Wrapper.__init__(self, env)
        from shipgym.observers import make_observer

        self.observer_name = observer
        base = env.unwrapped
        self.observer = make_observer(
            observer, vessel=getattr(base, "vessel", None), **dict(options or {})
        )
        mode = getattr(self.observer, "thrust_input", "applied")
        if mode not in ("applied", "command"):
            raise ValueError(
                f"observer {observer!r}: thrust_input must be 'applied' or 'command', got {mode!r}"
            )
        # "command": the filter models the thruster lags itself and takes the commands' force
        self._command_input = mode == "command"
        if getattr(base, "sensors", None) is None:
            raise ValueError(
                "an observer needs sensors: create the environment with sensors='default' "
                "(or another preset), not sensors=None"
            )
        check = getattr(self.observer, "check_sample_interval", None)
        if check is not None:  # an interval the filter cannot take: refused now, not at step
            check(base.sensors.config.period, base.control_period)
        self._sq = np.zeros(6)
        self._n = 0
        # the env's observation layout, rebuilt around the estimate
        self._observation = base.navigation_observation

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        obs, info = self.env.reset(seed=seed, options=options)
        rec = step_record(info)
        meas = [m for m in rec.measurements if m.z is not None]
        if meas:
            self.observer.reset(meas[0].t, meas[0].z)
        else:  # a dropout at the start: begin from the planned start pose (the berth)
            self.observer.reset(rec.t, rec.reference.eta_P)
        self._sq[:] = 0.0
        self._n = 0
        return self._apply(obs, info, rec, None)

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        rec = step_record(info)
        last = None
        ms = rec.measurements
        command = self._command_input
        for m in ms:
            last = self.observer.step(m.t, m.z, m.tau_command if command else m.tau)
        if not ms or ms[-1].t < rec.t:
            tau = None if not ms else (ms[-1].tau_command if command else ms[-1].tau)
            self.observer.step(rec.t, None, tau)  # coast to now
        obs, info = self._apply(obs, info, rec, last, ended=terminated or truncated)
        return obs, reward, terminated, truncated, info

    def estimation_rmse(self) -> dict[str, float]:
        """RMSE of the estimate over the control steps so far (m, m, deg, m/s, m/s, deg/s)."""
        r = np.sqrt(self._sq / max(self._n, 1))
        r[2] = math.degrees(r[2])
        r[5] = math.degrees(r[5])
        return dict(zip(("x", "y", "psi", "u", "v", "r"), r.tolist(), strict=True))

    def _apply(
        self,
        obs: NDArray[np.float32],
        info: dict[str, Any],
        rec: StepRecord,
        step_info: Any,
        ended: bool = False,
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        est = self.observer.estimate()
        eta, nu = rec.truth.eta, rec.truth.nu
        e_eta = np.array(
            [est.eta[0] - eta[0], est.eta[1] - eta[1], wrap_angle(est.eta[2] - eta[2])]
        )
        e_nu = est.nu - nu
        self._sq += np.concatenate([e_eta, e_nu]) ** 2
        self._n += 1
        nav = NavigationData(
            rec.t, np.array(est.eta), np.array(est.nu), est.P_eta, est.P_nu, self.observer_name
        )
        rmse = self.estimation_rmse() if ended else None
        info["nav_eta"] = nav.eta
        info["nav_nu"] = nav.nu
        info["est_error_eta"] = e_eta
        info["est_error_nu"] = e_nu
        info["observer_nis"] = None if step_info is None else step_info.nis
        info["observer_rejected"] = False if step_info is None else bool(step_info.rejected)
        if rmse is not None:
            info["estimation_rmse"] = rmse
        info["record"] = rec.with_nav(nav, estimation_rmse=rmse)
        obs = self._observation(est.eta, est.nu, rec.reference, rec.actuators.action)
        return obs, info
