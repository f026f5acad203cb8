"""Sensitivities of a simulation to its initial state: the state-transition matrix
``Phi(t) = d y(t) / d y(t0)``, integrated with the state as the registered model's
variational system (:mod:`camdyn.systems.variational`), with the saltation matrix applied
at every contact onset and separation, friction reversal and impact reset. Over one cam
period of a periodic orbit it is the monodromy matrix, whose eigenvalues are the Floquet
multipliers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from camdyn.errors import ParameterError, SimulationError
from camdyn.integrator import driver
from camdyn.params.system import System
from camdyn.simulation import limits
from camdyn.simulation.runner import default_max_step, prepare, starting_state, with_speed
from camdyn.systems import registry as systems

__all__ = ["Sensitivity", "state_transition", "integrate_variational"]


@dataclass(frozen=True)
class Sensitivity:
    """The end of a run with its state-transition matrix.

    Attributes
    ----------
    time : float
        End time [s].
    state : ndarray (n,)
        State at ``time`` (the cam-follower's: alpha [rad], alpha_dot [rad/s], the
        friction-work quadrature [J]).
    matrix : ndarray (n, n)
        ``d state / d initial state`` (units of the row's component over the column's).
    events : int
        Events passed (each applied its saltation matrix).
    """

    time: float
    state: np.ndarray
    matrix: np.ndarray
    events: int

    @property
    def multipliers(self) -> np.ndarray:
        """Eigenvalues of :attr:`matrix` (Floquet multipliers when the run is one period of
        a periodic orbit), by decreasing modulus."""
        values = np.linalg.eigvals(self.matrix)
        return values[np.argsort(-np.abs(values))]


def integrate_variational(system_id: int, p: np.ndarray, y0, t_start: float, t_end: float, rtol: float = 1e-10,
                          atol: float = 1e-12, max_step: float = math.inf, max_steps: int = 50_000_000,
                          max_events: int = 100_000) -> Sensitivity:
    """Integrate registered model ``system_id`` (:mod:`camdyn.systems.registry`) from
    ``y0`` over ``[t_start, t_end]`` [s] with its state-transition matrix, starting from
    the identity. Raises :class:`SimulationError` with the driver's reason if it stops."""
    y0 = np.asarray(y0, dtype=float)
    n = y0.size
    if n != systems.state_size(system_id):
        raise ParameterError(f"the initial state has {n} components; the system has {systems.state_size(system_id)}")
    if not (t_end > t_start):
        raise ParameterError(f"t_end must exceed t_start, got {t_start} and {t_end}")
    start = np.concatenate([y0, np.eye(n).ravel()])
    y, _, events, counters = driver.integrate(systems.VARIATIONAL + system_id, np.asarray(p, float), start,
                                              float(t_start), float(t_end), np.array([float(t_end)]), float(rtol),
                                              float(atol), float(min(max_step, t_end - t_start)),
                                              driver.METHOD_DOP853, int(max_steps), int(max_events), True)
    status = int(counters[driver.COUNT_STATUS])
    if status == driver.STATUS_INTERRUPTED:
        raise KeyboardInterrupt
    if status != driver.STATUS_OK:
        raise SimulationError(f"sensitivity run {driver.STATUS_MESSAGES[status]}")
    return Sensitivity(float(t_end), y[-1, :n].copy(), y[-1, n:].reshape(n, n).copy(),
                       int(counters[driver.COUNT_EVENTS]))


def state_transition(system: System, duration: float | None = None, speed=None, initial_state=None,
                     t_start: float = 0.0, rtol: float = 1e-10, atol: float = 1e-12) -> Sensitivity:
    """The cam-follower's state at ``t_start + duration`` [s] and its derivative with
    respect to the state at ``t_start`` [s] (default duration: one cam period, which
    gives the monodromy matrix when the start lies on a periodic orbit).

    ``initial_state`` is ``(alpha [rad], alpha_dot [rad/s])`` (default: the static
    equilibrium); tolerances as for :func:`camdyn.simulate`, tighter by default because
    the matrix is error-controlled with the state.
    """
    limits.check_system(system)
    system = with_speed(system, speed)
    limits.check_tolerances(rtol, atol)
    period = system.motion.period
    if duration is None:
        if not math.isfinite(period):
            raise ParameterError("the cam does not move (speed 0): give a duration in seconds")
        duration = period
    duration = limits.check_number("duration", duration, "s")
    if not (math.isfinite(duration) and duration > 0):
        raise ParameterError(f"duration must be positive, got {duration!r}")
    prep = prepare(system)
    return integrate_variational(systems.CAM_FOLLOWER, prep.p, starting_state(prep, initial_state), float(t_start),
                                 float(t_start) + duration, rtol, atol, default_max_step(period, duration))
