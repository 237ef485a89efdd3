"""Sensors and state observers (Kalman filters).

- :mod:`~shipgym.observers.sensors`: DGPS position and gyrocompass heading samples;
- :mod:`~shipgym.observers.design`: ``lqe``/``dlqe`` gain design (python-control style);
- :mod:`~shipgym.observers.kalman`: discrete KF and Kalman-Bucy filters per DOF;
- :mod:`~shipgym.observers.ekf`: the 9-state extended Kalman filter of Tomera (2014);
- :mod:`~shipgym.observers.batch`: the observers written once over N envs, which the envs run
  (``shipgym.make(id, observer=NAME)``, ``gym.make_vec(id, N, observer=NAME)``);
- :mod:`~shipgym.observers.wrapper`: :class:`ObserverWrapper`, rl-zoo3's ``env_wrapper`` form
  of ``observer=``.

``make_observer(name)`` builds any registered observer (``observer_names()`` lists them).
"""

from __future__ import annotations

from typing import Any

from .sensors import Measurement, SensorConfig, Sensors, sensor_config

__all__ = [
    "Measurement",
    "SensorConfig",
    "Sensors",
    "make_observer",
    "observer_names",
    "sensor_config",
]


def observer_names() -> list[str]:
    """Names accepted by :func:`make_observer`."""
    from .base import OBSERVERS, _load_builtins

    _load_builtins()
    return sorted(OBSERVERS)


def make_observer(name: str, **overrides: Any) -> Any:
    """An observer by name (``dkf``, ``kbf``, ``ekf``, ``tomera-dkf``, ...).

    Raises:
        ValueError: unknown name (the message lists the valid ones).
    """
    from .base import make_observer as _make

    return _make(name, **overrides)
