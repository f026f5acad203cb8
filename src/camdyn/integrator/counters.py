"""Solver counters and status codes of the compiled driver.

A run returns its counters as one int64 array indexed by ``COUNT_*`` (named by
:data:`COUNTER_NAMES`); slot ``COUNT_STATUS`` holds a ``STATUS_*`` code, explained by
:data:`STATUS_MESSAGES`. :mod:`camdyn.integrator.driver` re-exports them all.
"""

from __future__ import annotations

COUNT_ACCEPTED = 0
COUNT_REJECTED = 1
COUNT_RHS = 2
COUNT_JACOBIANS = 3
COUNT_EXPLICIT = 4
COUNT_ROSENBROCK = 5
COUNT_EVENTS = 6
COUNT_ROOT_ITERATIONS = 7
COUNT_STATUS = 8
COUNT_EVENTS_DROPPED = 9
COUNT_BDF = 10   # accepted steps of the BDF family (METHOD_MULTISTEP); the others are explicit_steps
COUNT_RADAU = 11  # accepted Radau IIA steps (METHOD_RADAU, METHOD_SWITCHING)
COUNT_SIZE = 12
COUNTER_NAMES = ("accepted_steps", "rejected_steps", "rhs_calls", "jacobians", "explicit_steps",
                 "rosenbrock_steps", "events", "root_iterations", "status", "events_dropped", "bdf_steps",
                 "radau_steps")

STATUS_OK = 0
STATUS_MAX_STEPS = 1
STATUS_STEP_UNDERFLOW = 2
STATUS_NOT_FINITE = 3
STATUS_ZENO = 4
STATUS_INTERRUPTED = 5
STATUS_MESSAGES = {
    STATUS_OK: "completed",
    STATUS_MAX_STEPS: "stopped: the maximum number of steps was reached",
    STATUS_STEP_UNDERFLOW: "stopped: the step size fell below the resolution of time",
    STATUS_NOT_FINITE: "stopped: the state became infinite or NaN",
    STATUS_ZENO: "stopped: events accumulated at one instant (sticking or chattering contact); "
                 "try tanh friction or another damping law",
    STATUS_INTERRUPTED: "interrupted (Ctrl-C)",
}
