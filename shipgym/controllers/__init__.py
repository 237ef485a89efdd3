"""Controllers and thrust allocation.

- :mod:`~shipgym.controllers.pid`: the multivariable PID-type DP controller of Tomera (2014)
  (eqs. 13-23), its gain presets and the pole-placement design function.
- :mod:`~shipgym.controllers.allocation`: thrust allocation (Tomera 2014 eqs. 24-27 and a
  box-constrained weighted least-squares allocation) and the normalised action mapping.

Pure NumPy; never imports mujoco.
"""

from . import lq as _lq  # noqa: E402,F401,I001 - registers the "lq" controller
from .allocation import (
    Allocation,
    action_to_command,
    allocate,
    allocate_inverse,
    command_to_action,
    default_weights,
    force_capacity,
)
from .pid import (
    GAIN_PRESETS,
    MultivariablePID,
    PIDGains,
    error_loop,
    pid_gains,
    pid_pole_placement,
)

__all__ = [
    "GAIN_PRESETS",
    "Allocation",
    "MultivariablePID",
    "PIDGains",
    "action_to_command",
    "allocate",
    "allocate_inverse",
    "command_to_action",
    "default_weights",
    "error_loop",
    "force_capacity",
    "pid_gains",
    "pid_pole_placement",
]
