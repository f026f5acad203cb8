"""Periodic orbits of the forced hybrid systems, their Floquet multipliers, and their
continuation in a parameter with bifurcation detection (:mod:`.orbits`, :mod:`.branches`;
the problem definitions in :mod:`.problem`)."""

from camdyn.continuation.orbits import Orbit, find_orbit, flow, transient_state
from camdyn.continuation.problem import Problem, model_problem, system_problem

__all__ = ["Orbit", "Problem", "find_orbit", "flow", "model_problem", "system_problem", "transient_state"]
