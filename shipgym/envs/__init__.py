"""MuJoCo physics of ships and the Gymnasium tasks built on it."""

from .physics import SimulationDiverged, VesselPhysics
from .scene import WORLDS, build_model

__all__ = ["WORLDS", "SimulationDiverged", "VesselPhysics", "build_model"]
