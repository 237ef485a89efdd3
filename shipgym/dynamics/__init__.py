"""Pure-NumPy ship dynamics: frames, parameter sets, the 3-DOF and 4-DOF hull models, actuator
kinds, vessels (data packages), reference integration. Never imports mujoco; used by the
physics, observers and controllers alike."""

from .actuators import ActuatorSet, Azimuth, Propeller
from .frames import body_to_ned, ned_to_body, rot, wrap_angle
from .hull4 import Hull4
from .model import PLANT_VARIANTS, PlantModel, plant_model, seed_linear_matrices
from .params import BLUE_LADY_HULL, BLUE_LADY_WINDAGE, HullParameters, WindageParameters
from .reference import ReferenceSolution, simulate_reference
from .thrusters import (
    ACTUATOR_NAMES,
    BLUE_LADY_THRUSTERS,
    ThrusterParameters,
    command_to_tau,
    configuration_matrix,
    inverse_thrust,
    saturate,
    thrust,
    thrust_to_tau,
    validate_command,
)
from .vessel import Vessel, VesselError, load_vessel, vessel_names, vessels

__all__ = [
    "ACTUATOR_NAMES",
    "ActuatorSet",
    "Azimuth",
    "Hull4",
    "Propeller",
    "Vessel",
    "VesselError",
    "load_vessel",
    "vessel_names",
    "vessels",
    "BLUE_LADY_HULL",
    "BLUE_LADY_THRUSTERS",
    "BLUE_LADY_WINDAGE",
    "HullParameters",
    "PLANT_VARIANTS",
    "PlantModel",
    "ReferenceSolution",
    "ThrusterParameters",
    "WindageParameters",
    "body_to_ned",
    "command_to_tau",
    "configuration_matrix",
    "inverse_thrust",
    "ned_to_body",
    "plant_model",
    "rot",
    "saturate",
    "seed_linear_matrices",
    "simulate_reference",
    "thrust",
    "thrust_to_tau",
    "validate_command",
    "wrap_angle",
]
