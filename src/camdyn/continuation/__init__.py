"""Periodic orbits of the forced hybrid systems, their Floquet multipliers, and their
continuation in a parameter with bifurcation detection (:mod:`.orbits`, :mod:`.branches`;
the problem definitions in :mod:`.problem`, a protocol model's too
(:func:`bound_problem`), the cam-follower's contact margins in
:mod:`.margins`, branch switching at a period doubling in :mod:`.switching`, the
cam-follower's branches and their tables in :mod:`.results`, the translating follower's
problem, branches and table in :mod:`.translating`, the problem and branches of the
mechanisms held at a prescribed cam speed in :mod:`.mechanisms`)."""

from camdyn.continuation.branches import Bifurcation, Branch, continue_orbits
from camdyn.continuation.mechanisms import mechanism_problem, trace_mechanism
from camdyn.continuation.orbits import Orbit, find_orbit, flow, transient_state
from camdyn.continuation.problem import Problem, bound_problem, model_problem, system_problem
from camdyn.continuation.results import trace_branch
from camdyn.continuation.switching import doubled_orbit, switch_branch
from camdyn.continuation.translating import trace_translating, translating_dataset, translating_problem

__all__ = ["Bifurcation", "Branch", "Orbit", "Problem", "bound_problem",
           "continue_orbits", "doubled_orbit", "find_orbit", "flow",
           "mechanism_problem", "model_problem", "switch_branch", "system_problem", "trace_branch", "trace_mechanism",
           "trace_translating", "transient_state", "translating_dataset", "translating_problem"]
