"""Run time: the one compiled physics step over N >= 1 hulls (:mod:`shipgym.sim.step`)."""
