"""Thrust allocation: from a requested generalised force ``tau`` to actuator forces.

- :mod:`~shipgym.controllers.allocation.fixed3`: the Blue Lady's three fixed thrusters in closed
  form (Tomera 2014 eqs. 24-27): :func:`allocate`, :func:`allocate_inverse`, the normalised
  action mapping. The fast path for that vessel and a test oracle for the general methods.
- :mod:`~shipgym.controllers.allocation.wls`: :func:`allocate_wls`, box-constrained weighted
  least squares for any number of fixed-direction thrusters, 3 or 4 DOF (Fossen 2011 sec. 12.3).
- :mod:`~shipgym.controllers.allocation.azimuth`: :func:`allocate_azimuth`, azimuth thrusters
  by the extended-thrust formulation with magnitude and angle-rate limits, mixed with fixed
  thrusters, solved as a small convex QP (Johansen & Fossen 2013).

The general allocators work on plain arrays in SI units (N, N m, rad) and know nothing of
vessels.
"""

from .azimuth import (
    AzimuthAllocation,
    AzimuthAllocator,
    Azimuths,
    allocate_azimuth,
    extended_thrust_matrix,
)
from .fixed3 import (
    Allocation,
    action_to_command,
    allocate,
    allocate_inverse,
    command_to_action,
    default_weights,
    force_capacity,
)
from .wls import WLSAllocation, WLSAllocator, allocate_wls

__all__ = [
    "Allocation",
    "AzimuthAllocation",
    "AzimuthAllocator",
    "Azimuths",
    "WLSAllocation",
    "WLSAllocator",
    "action_to_command",
    "allocate",
    "allocate_azimuth",
    "allocate_inverse",
    "allocate_wls",
    "command_to_action",
    "default_weights",
    "extended_thrust_matrix",
    "force_capacity",
]
