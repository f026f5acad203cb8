"""Sensitivities of a simulation to its initial state and to its parameters: the
state-transition matrix ``Phi(t) = d y(t) / d y(t0)`` and, on request, ``d y(t) / d q``
for chosen parameters ``q``, integrated with the state as the registered model's
variational system (:mod:`camdyn.systems.variational`), with the saltation matrix applied
at every contact onset and separation, friction reversal and impact reset. Over one cam
period of a periodic orbit ``Phi`` is the monodromy matrix, whose eigenvalues are the
Floquet multipliers; ``d y / d q`` is the gradient of any output built from the state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from camdyn.errors import ParameterError
from camdyn.integrator import driver
from camdyn.params.schema import parameter_index
from camdyn.params.system import System
from camdyn.simulation import limits
from camdyn.simulation.runner import default_max_step, default_scan, prepare, starting_state, with_speed
from camdyn.systems import registry as systems

__all__ = ["Sensitivity", "state_transition", "integrate_variational", "parameter_directions"]


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
    parameters : ndarray (n, k)
        ``d state / d q_j`` for the ``k`` parameters asked for, at a fixed initial state
        (units of the row's component over the parameter's SI unit); ``(n, 0)`` when none.
    names : tuple of str
        The parameters' names, in the order of the columns of :attr:`parameters`.
    """

    time: float
    state: np.ndarray
    matrix: np.ndarray
    events: int
    parameters: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    names: tuple = ()

    @property
    def multipliers(self) -> np.ndarray:
        """Eigenvalues of :attr:`matrix` (Floquet multipliers when the run is one period of
        a periodic orbit), by decreasing modulus."""
        values = np.linalg.eigvals(self.matrix)
        return values[np.argsort(-np.abs(values))]


def _packed_directions(p: np.ndarray, directions, steps) -> tuple[np.ndarray, int]:
    """``p`` followed by each parameter's ``(h_j, h_j dp/dq_j)`` (the layout of
    :mod:`camdyn.systems.variational`), and the parameter count."""
    if directions is None:
        return p, 0
    directions = np.atleast_2d(np.asarray(directions, dtype=float))
    steps = np.atleast_1d(np.asarray(steps, dtype=float))
    if directions.shape[1] != p.size or steps.shape != (directions.shape[0],):
        raise ParameterError(f"each parameter direction needs {p.size} values and one step; got directions of "
                             f"shape {directions.shape} and {steps.size} steps")
    if not (np.all(np.isfinite(directions)) and np.all(np.isfinite(steps)) and np.all(steps > 0)):
        raise ParameterError("parameter directions must be finite and their steps positive")
    tail = [np.r_[h, h * d] for d, h in zip(directions, steps)]
    return np.concatenate([p, *tail]), directions.shape[0]


def integrate_variational(system_id: int, p: np.ndarray, y0, t_start: float, t_end: float, rtol: float = 1e-10,
                          atol: float = 1e-12, max_step: float = math.inf, max_steps: int = 50_000_000,
                          max_events: int = 100_000, directions=None, steps=None,
                          names: tuple = (), scan: float = math.inf) -> Sensitivity:
    """Integrate registered model ``system_id`` (:mod:`camdyn.systems.registry`) from
    ``y0`` over ``[t_start, t_end]`` [s] with its state-transition matrix, starting from
    the identity, and with ``d y / d q_j`` for each row of ``directions`` (``dp/dq_j``,
    the rate of each slot of ``p`` per unit of parameter ``q_j``), differenced in the
    model's functions with the steps ``steps`` [unit of ``q_j``]. Raises
    :class:`SimulationError` with the driver's reason if it stops."""
    y0 = np.asarray(y0, dtype=float)
    n = y0.size
    if n != systems.state_size(system_id):
        raise ParameterError(f"the initial state has {n} components; the system has {systems.state_size(system_id)}")
    if not (t_end > t_start):
        raise ParameterError(f"t_end must exceed t_start, got {t_start} and {t_end}")
    packed, count = _packed_directions(np.asarray(p, float), directions, steps)
    start = np.concatenate([y0, np.eye(n).ravel(), np.zeros(n * count)])
    variational = systems.PARAMETRIC * count + systems.VARIATIONAL + system_id
    y, _, events, counters = driver.integrate(variational, packed, start,
                                              float(t_start), float(t_end), np.array([float(t_end)]), float(rtol),
                                              float(atol), float(min(max_step, t_end - t_start)),
                                              driver.METHOD_DOP853, int(max_steps), int(max_events), True,
                                              float(scan))
    limits.check_run(counters, "sensitivity run")
    end = y[-1]
    return Sensitivity(float(t_end), end[:n].copy(), end[n:n + n * n].reshape(n, n).copy(),
                       int(counters[driver.COUNT_EVENTS]), end[n + n * n:].reshape(count, n).T.copy(),
                       tuple(names))


#: Relative step of the central differences in a parameter [-] (of its value; of 1 in its
#: SI unit when it is 0). Measured on the chapter 3 rig (one revolution, four events):
#: d(alpha, alpha_dot)/d(motion.speed) against differences of whole simulations is off
#: by 1e-4, 3e-6, 1e-7 and 3e-8 of the derivative at steps 1e-5 ... 1e-8 (falling as
#: h^1.5: a moved cam angle moves the penetration across zero inside the difference's
#: stencil, where the Hertz force delta^1.5 is not smooth); stiffness and runout agree to
#: 3e-7 at every step from 1e-6 to 1e-8.
PARAMETER_STEP = 1e-8


def parameter_directions(system: System, keys) -> tuple[np.ndarray, np.ndarray]:
    """For each dotted key of ``system`` (in SI units: ``motion.speed`` in [Hz]), the rate
    ``dp/dq`` of the packed parameter vector per unit of the parameter (central differences
    of the packing, exact for the slots that hold the parameter or a multiple of it) and
    the difference step [unit of the parameter] for the model's functions."""
    known = parameter_index(type(system))
    rows, steps = [], []
    for key in keys:
        if key not in known:
            raise ParameterError(f"unknown parameter {key!r}; `camdyn presets keys` lists them")
        if known[key].unit in ("str", "bool", "int"):
            raise ParameterError(f"{key} is not a continuous parameter (its kind is {known[key].unit})")
        value = known[key].getter(system)
        if value is None or not math.isfinite(float(value)):
            raise ParameterError(f"{key} has no finite value to differentiate at")
        value = float(value)
        step = PARAMETER_STEP * (abs(value) if value != 0.0 else 1.0)
        up = value + 1e3 * step
        down = value - 1e3 * step
        plus = prepare(system.with_values(**{key: up})).p
        minus = prepare(system.with_values(**{key: down})).p
        rows.append((plus - minus) / (up - down))
        steps.append(step)
    return np.array(rows), np.array(steps)


def state_transition(system: System, duration: float | None = None, speed=None, initial_state=None,
                     t_start: float = 0.0, rtol: float = 1e-10, atol: float = 1e-12,
                     parameters: tuple = ()) -> Sensitivity:
    """The cam-follower's state at ``t_start + duration`` [s] and its derivative with
    respect to the state at ``t_start`` [s] (default duration: one cam period, which
    gives the monodromy matrix when the start lies on a periodic orbit).

    ``initial_state`` is ``(alpha [rad], alpha_dot [rad/s])`` (default: the static
    equilibrium); tolerances as for :func:`camdyn.simulate`, tighter by default because
    the matrix is error-controlled with the state.

    ``parameters`` are dotted keys (``spring.stiffness``, ``motion.speed`` [Hz],
    ``contact.beta``...): the result's :attr:`Sensitivity.parameters` holds ``d state /
    d q`` for each, with the initial state held fixed (differentiate the equilibrium
    yourself if the start moves with the parameter). A parameter that changes the cam's
    speed changes the period: ``duration`` stays as given.
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
    directions, steps = parameter_directions(system, parameters) if parameters else (None, None)
    return integrate_variational(systems.CAM_FOLLOWER, prep.p, starting_state(prep, initial_state), float(t_start),
                                 float(t_start) + duration, rtol, atol, default_max_step(period, duration),
                                 directions=directions, steps=steps, names=tuple(parameters),
                                 scan=default_scan(period, duration))
