"""MuJoCo physics of ships and the Gymnasium tasks built on it."""

from .physics import DEFAULT_SCENE, SimulationDiverged, VesselPhysics

__all__ = ["DEFAULT_SCENE", "SimulationDiverged", "VesselPhysics"]
