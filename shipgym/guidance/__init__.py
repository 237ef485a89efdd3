"""Guidance for harbour manoeuvres (Tomera 2014 Figs. 2-3 and 7).

- :mod:`~shipgym.guidance.rframe`: the leg's r-frame (Tomera 2014 eqs. 1-2), ``to_r_frame`` and
  ``from_r_frame``;
- :mod:`~shipgym.guidance.reference`: :class:`Limits` and the smooth reference of a leg
  (raised-cosine-acceleration trapezoid, DOFs synchronised on a straight r-frame line);
- :mod:`~shipgym.guidance.plan`: :class:`Leg`, :class:`ManoeuvrePlan`, the paper's 5-leg plan
  and the plan registry;
- :mod:`~shipgym.guidance.batch`: :class:`BatchedGuidance`, the run-time guidance of N >= 1
  envs (each its own plan), compiled once: the reference and the switching rule;
- :mod:`~shipgym.guidance.runtime`: :class:`Guidance` (current leg, reference, switching),
  the same compiled guidance for one env.
"""

from .batch import BatchedGuidance, BatchedReference
from .plan import PLANS, Leg, ManoeuvrePlan, plan, tomera2014_plan
from .reference import (
    BLUE_LADY_LIMITS,
    LegProfile,
    Limits,
    leg_duration,
    leg_profile,
    leg_reference,
)
from .rframe import from_r_frame, to_r_frame
from .runtime import Guidance, Reference

__all__ = [
    "PLANS",
    "BatchedGuidance",
    "BatchedReference",
    "Guidance",
    "Leg",
    "LegProfile",
    "BLUE_LADY_LIMITS",
    "Limits",
    "ManoeuvrePlan",
    "Reference",
    "from_r_frame",
    "leg_duration",
    "leg_profile",
    "leg_reference",
    "plan",
    "to_r_frame",
    "tomera2014_plan",
]
