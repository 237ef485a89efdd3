"""MuJoCo, imported once (:mod:`shipgym.sim._mujoco`)."""

from shipgym.sim._mujoco import mujoco

__all__ = ["mujoco"]
