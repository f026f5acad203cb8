"""Periodic orbits of forced hybrid systems by single shooting, and their Floquet
multipliers.

A period-``k`` orbit of a system forced with period ``T`` [s] is a state ``x`` at the
phase ``t0`` with ``phi(t0 + kT; t0, x) = x``, where ``phi`` is the hybrid flow (smooth
flow between events, resets and mode changes at them). Newton's method solves the
residual ``F(x) = phi(t0 + kT; t0, x) - x`` with the Jacobian ``M - I``, where ``M`` is
the monodromy matrix: the state-transition matrix over ``kT`` with the saltation matrix
applied at every event (Leine & Nijmeijer 2004, *Dynamics and Bifurcations of
Non-Smooth Mechanical Systems*, ch. 3 and 7; Seydel 2010, *Practical Bifurcation and
Stability Analysis*, sec. 7.1-7.3). The eigenvalues of ``M`` are the orbit's Floquet
multipliers: the orbit is asymptotically stable when all lie inside the unit circle.
Multiple shooting (``find_orbit(..., segments=m)``, the linear algebra in
:mod:`~camdyn.continuation.multiple`) cuts the period into ``m`` segments for orbits too
unstable for one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from camdyn.continuation import multiple
from camdyn.continuation.margins import contact_margins, flight_margin
from camdyn.continuation.problem import Problem
from camdyn.errors import ParameterError, SimulationError
from camdyn.integrator import driver
from camdyn.simulation import limits
from camdyn.systems import registry as systems

__all__ = ["Flow", "Orbit", "driver_settings", "flow", "find_orbit", "make_orbit", "segment_ends",
           "segment_runs", "shoot", "transient_state", "STABILITY_MARGIN"]

#: A multiplier counts as inside the unit circle when its modulus is below 1 - this [-].
STABILITY_MARGIN = 1e-7
#: Samples per forcing period of the orbit's guard, for its smallest value.
SAMPLES_PER_PERIOD = 256
#: Halvings of a multiple-shooting Newton step whose trial states make a run fail.
HALVINGS = 10
#: The most steps of one shooting run [-].
MAX_STEPS = 50_000_000
#: :func:`find_orbit` stops Newton's method where a variational run from an iterate needs
#: more than this many times the steps of the first one (and more than
#: :data:`NEWTON_STEP_FLOOR`): the iterate has left the start's neighbourhood for a state
#: no orbit near it passes through. On the flexible pivot past its period doubling (16 Hz,
#: a start on the period-2 attractor) an iterate put the follower 4.7 mm into the cam
#: (2.7 MN): its variational run took 1.1 million steps (123 s) for a sixteenth of the
#: period, the first one 2 000 steps for the whole period.
NEWTON_STEP_FACTOR = 20
#: The smallest step budget of a variational run of Newton's method [-].
NEWTON_STEP_FLOOR = 20_000


@dataclass(frozen=True)
class Flow:
    """One shooting run over ``k`` forcing periods.

    Attributes
    ----------
    end : ndarray (u,)
        The unknown components of the state at the run's end.
    matrix : ndarray (u, u)
        Their derivative with respect to the unknown components at the start (the
        monodromy matrix when the start lies on the orbit), saltation included.
    impacts : int
        Events on the contact guard (guard 0) that count as impacts.
    events : int
        Events of all kinds passed.
    guard_minimum : float
        Smallest sampled value of guard 0 over the run (the gap to the wall [m] of the
        rigid-impact oscillator, the contact penetration [m] of the cam-follower).
    states : ndarray (samples, n)
        Sampled full states over the run, at ``times`` [s].
    times : ndarray (samples,)
        Sample times [s].
    modes : ndarray (samples, mode size)
        The hybrid mode at each sample.
    steps : int
        The integrator's steps, accepted and rejected (0 where not counted).
    contact_times : ndarray or None
        Times of the events on the contact guard (guard 0), onsets and ends [s].
    elapsed : float
        The advance of the problem's clock component over the run [s]
        (:attr:`Problem.clock`; NaN without one).
    """

    end: np.ndarray
    matrix: np.ndarray
    impacts: int
    events: int
    guard_minimum: float
    states: np.ndarray
    times: np.ndarray
    modes: np.ndarray
    steps: int = 0
    contact_times: np.ndarray | None = None
    elapsed: float = math.nan


@dataclass(frozen=True)
class Orbit:
    """A periodic orbit and its stability.

    Attributes
    ----------
    state : ndarray (u,)
        The shooting unknowns at the phase ``t_start`` (the cam-follower's alpha [rad]
        and alpha_dot [rad/s]; a test model's x [m] and x' [m/s]).
    full_state : ndarray (n,)
        The full initial state (quadratures from the problem's template).
    parameter : float
        The scalar parameter's value [its unit].
    period : float
        The orbit's period [s]: ``k T``, or for an autonomous mechanism (whose forcing
        period ``T`` is ``2 pi`` in the cam angle) the time its cam takes to turn
        ``2 pi k`` (:attr:`~camdyn.continuation.problem.Problem.clock`).
    periods : int
        ``k``: forcing periods per orbit period.
    multipliers : ndarray (u,) complex
        Floquet multipliers, by decreasing modulus.
    stable : bool
        True when every multiplier's modulus is below ``1 - STABILITY_MARGIN``.
    impacts_per_period : int
        Impacts (events of the contact guard) per orbit period.
    iterations : int
        Newton iterations used.
    residual : float
        Final residual's norm (units of the state).
    guard_minimum : float
        Smallest sampled value of the contact guard over the orbit.
    monodromy : ndarray (u, u)
        The monodromy matrix.
    force_minimum : float
        The cam-follower's smallest normal force over the orbit, unclipped [N]
        (:func:`~camdyn.continuation.margins.contact_margins`; NaN for a test model).
    sliding_minimum : float
        The cam-follower's smallest sliding velocity in contact, signed by the direction
        of sliding [m/s] (NaN for a test model).
    extent : ndarray (u,) or None
        The largest magnitude of each unknown over the orbit (its units), the scale of
        that unknown in the continuation.
    segment_states : ndarray (m, u) or None
        With multiple shooting (``m`` segments), the unknowns at each segment's start
        (row 0 is ``state``); None with single shooting.
    flight_margin : float
        The cam-follower's smallest gap at a closest approach in flight [m]
        (:func:`~camdyn.continuation.margins.flight_margin`; NaN for a test model or an
        orbit without one).
    """

    state: np.ndarray
    full_state: np.ndarray
    parameter: float
    period: float
    periods: int
    multipliers: np.ndarray
    stable: bool
    impacts_per_period: int
    iterations: int
    residual: float
    guard_minimum: float
    monodromy: np.ndarray
    force_minimum: float = math.nan
    sliding_minimum: float = math.nan
    extent: np.ndarray | None = None
    segment_states: np.ndarray | None = None
    flight_margin: float = math.nan


def _full(problem: Problem, x: np.ndarray, value: float) -> np.ndarray:
    return problem.full_state(x, value)


def driver_settings(problem: Problem, period: float, max_steps: int = 50_000_000) -> tuple:
    """The driver's arguments after the tolerances for the problem's model forced with
    period ``period`` [s]: the largest step [s] and the scan interval [s] of
    :func:`~camdyn.simulation.limits.step_limits`, DOP853, the limits on steps and
    events, interruptible."""
    if problem.step_fraction is not None:
        h_max = scan = problem.step_fraction * period
    else:
        h_max, scan = limits.step_limits(period, problem.system_id)
    return h_max, driver.METHOD_DOP853, int(max_steps), 100_000, True, scan


def flow(problem: Problem, x, value: float | None = None, periods: int = 1, samples: int = 0,
         max_steps: int = MAX_STEPS) -> Flow:
    """Integrate the variational system from unknowns ``x`` at ``t_start`` over
    ``periods`` forcing periods at the scalar parameter ``value`` (default the problem's),
    at the problem's matrix tolerances (:meth:`Problem.matrix_tolerances`; its end state
    is only as accurate as those: residuals come from :func:`shoot`). Raises
    :class:`SimulationError` if the integrator stops (after ``max_steps`` steps too)."""
    value = problem.value if value is None else float(value)
    p, period = problem.build(value)
    return _variational(problem, p, period, x, value, problem.t_start, problem.t_start + periods * period, samples,
                        max_steps)


def _variational(problem: Problem, p, period, x, value, t0, t1, samples, max_steps: int = MAX_STEPS) -> Flow:
    n = problem.template.size
    u = problem.unknowns
    y0 = _full(problem, np.asarray(x, dtype=float), value)
    count = max(samples, 2)
    times = np.linspace(t0, t1, count)
    start = np.concatenate([y0, np.eye(n).ravel()])
    rtol, atol = problem.matrix_tolerances()
    y, modes, log, counters = problem.run(systems.VARIATIONAL + problem.system_id, p, start, t0, t1,
                                          times, rtol, atol, *driver_settings(problem, period, max_steps))
    limits.check_run(counters, f"shooting run at {problem.name} = {value:g}")
    on_contact = log[:, driver.EVENT_GUARD] == 0
    if not problem.impacts:
        on_contact &= False
    elif problem.impact_sign != 0.0:
        on_contact &= log[:, driver.EVENT_NEW_SIGN] == problem.impact_sign
    states = y[:, :n]
    matrix = y[-1, n:].reshape(n, n)[:u, :u].copy()
    return Flow(y[-1, :u].copy(), matrix, int(on_contact.sum()), int(counters[driver.COUNT_EVENTS]),
                _guard_minimum(problem, p, times, states) if samples else math.nan, states, times, modes,
                int(counters[driver.COUNT_ACCEPTED] + counters[driver.COUNT_REJECTED]),
                log[log[:, driver.EVENT_GUARD] == 0, driver.EVENT_TIME].copy(),
                math.nan if problem.clock is None else float(y[-1, problem.clock] - y0[problem.clock]))


def _guard_minimum(problem: Problem, p: np.ndarray, times: np.ndarray, states: np.ndarray) -> float:
    """Smallest value of guard 0 over the sampled states, refined by the parabola through
    the smallest sample and its neighbours (error of order the sample spacing cubed)."""
    sampled = np.empty(times.size)
    problem.engine().systems.guard_samples(problem.system_id, p, times, np.ascontiguousarray(states), 0, sampled)
    i = int(np.argmin(sampled))
    if 0 < i < sampled.size - 1:
        left, middle, right = sampled[i - 1], sampled[i], sampled[i + 1]
        curvature = left - 2.0 * middle + right
        if curvature > 0:                                          # vertex of the parabola
            return float(middle - (right - left) ** 2 / (8.0 * curvature))
    return float(sampled[i])


def shoot(problem: Problem, x, value: float, periods: int = 1) -> np.ndarray:
    """The unknown components after ``periods`` forcing periods from unknowns ``x`` at
    ``t_start``, by the plain model without its state-transition matrix (several times
    cheaper: the matrix's error control takes the variational run's steps)."""
    p, period = problem.build(float(value))
    return _plain(problem, p, period, x, value, problem.t_start, problem.t_start + periods * period)


def _plain(problem: Problem, p, period, x, value, t0, t1) -> np.ndarray:
    y, _, _, counters = problem.run(problem.system_id, p, _full(problem, x, value), t0, t1,
                                    np.array([t1]), problem.rtol, problem.atol,
                                    *driver_settings(problem, period))
    limits.check_run(counters, f"shooting run at {problem.name} = {value:g}")
    return y[-1, :problem.unknowns].copy()


def transient_state(problem: Problem, periods: int = 50, value: float | None = None) -> np.ndarray:
    """The unknown components after ``periods`` forcing periods of plain simulation from
    the problem's template state at ``t_start``: a start for Newton's method on an
    attracting orbit."""
    if periods < 1:
        raise ParameterError(f"periods must be at least 1, got {periods}")
    value = problem.value if value is None else float(value)
    p, period = problem.build(value)
    t0 = problem.t_start
    t1 = t0 + periods * period
    start = problem.full_state(problem.template[:problem.unknowns], value)
    y, _, _, counters = problem.run(problem.system_id, p, start, t0, t1, np.array([t1]),
                                    problem.rtol * 100, problem.atol * 100, *driver_settings(problem, period))
    limits.check_run(counters, "transient run")
    return y[-1, :problem.unknowns].copy()


def make_orbit(problem: Problem, x, value, periods, run: Flow, iterations, residual) -> Orbit:
    """The :class:`Orbit` at unknowns ``x`` and parameter ``value`` from its run ``run``
    over ``periods`` forcing periods (sampled, for the guard's minimum)."""
    values = np.linalg.eigvals(run.matrix)
    values = values[np.argsort(-np.abs(values), kind="stable")]
    p, period = problem.build(value)
    force, sliding = contact_margins(problem.system_id, p, run.times, run.states, run.modes)
    own = periods * period if problem.clock is None else run.elapsed       # the time to turn 2 pi k
    return Orbit(np.asarray(x, float).copy(), _full(problem, x, value), float(value), float(own),
                 periods, values,
                 bool(np.all(np.abs(values) < 1.0 - STABILITY_MARGIN)), run.impacts, iterations, residual,
                 run.guard_minimum, run.matrix, force, sliding,
                 np.max(np.abs(run.states[:, :problem.unknowns]), axis=0) if run.times.size > 2 else None,
                 flight_margin=flight_margin(problem.system_id, p, run.times, run.states, run.modes,
                                             run.contact_times))


def find_orbit(problem: Problem, start=None, value: float | None = None, periods: int = 1, tolerance: float = 1e-10,
               max_iterations: int = 30, transient: int = 50, segments: int = 1) -> Orbit:
    """A period-``periods`` orbit by Newton's method on the shooting residual (by the plain
    model, :func:`shoot`), its Jacobian ``M - I`` from a variational run renewed only when
    the residual stops shrinking fourfold per step (a chord method otherwise), and the
    multipliers from a variational run at the converged state.

    Parameters
    ----------
    problem : Problem
        The system (:func:`~camdyn.continuation.problem.model_problem` or
        :func:`~camdyn.continuation.problem.system_problem`).
    start : array_like (u,) or (segments, u), optional
        First guess of the unknowns; default the state after ``transient`` forcing periods
        of plain simulation from the problem's template. With several segments, either
        the states at every segment's start or one state, which a plain run carries to
        the other segments' starts.
    value : float, optional
        The scalar parameter (default the problem's).
    periods : int
        ``k``, forcing periods per orbit period.
    tolerance : float
        Convergence when the residual's norm is below ``tolerance (1 + |x|)`` (units of
        the state).
    max_iterations : int
        Newton iterations before giving up with :class:`SimulationError`.
    segments : int
        ``m``, the number of shooting segments: 1 is single shooting; more is multiple
        shooting (:mod:`~camdyn.continuation.multiple`), for strongly unstable orbits.

    Returns
    -------
    Orbit
        With multiple shooting its ``segment_states`` are the states at the segments'
        starts, and its monodromy the product of the segments' matrices.
    """
    if int(periods) != periods or periods < 1:
        raise ParameterError(f"periods must be a positive integer, got {periods!r}")
    if not (tolerance > 0 and max_iterations >= 1):
        raise ParameterError("tolerance must be positive and max_iterations at least 1")
    if isinstance(segments, bool) or int(segments) != segments or segments < 1:
        raise ParameterError(f"segments must be a positive integer, got {segments!r}")
    value = problem.value if value is None else float(value)
    if segments > 1:
        return _find_segmented(problem, start, value, int(periods), tolerance, max_iterations, transient,
                               int(segments))
    if start is None:
        x = transient_state(problem, transient, value)
    else:
        x = np.asarray(start, dtype=float).copy()
        if x.size != problem.unknowns or not np.all(np.isfinite(x)):
            raise ParameterError(f"start must be {problem.unknowns} finite numbers")
    eye = np.eye(problem.unknowns)
    residual = np.full(problem.unknowns, math.inf)
    matrix, previous, budget = None, math.inf, MAX_STEPS
    unit = f" {problem.unit}" if problem.unit else ""
    for iteration in range(max_iterations + 1):
        residual = shoot(problem, x, value, periods) - x
        size = float(np.linalg.norm(residual))
        if size <= tolerance * (1.0 + np.linalg.norm(x)):
            run = flow(problem, x, value, periods, SAMPLES_PER_PERIOD * periods)
            return make_orbit(problem, x, value, periods, run, iteration, size)
        if iteration < max_iterations:
            if matrix is None or not size < 0.25 * previous:      # chord steps while they contract fast
                variational = _newton_matrix(problem, x, value, periods, budget, iteration, unit)
                if budget == MAX_STEPS:
                    budget = max(NEWTON_STEP_FACTOR * variational.steps, NEWTON_STEP_FLOOR)
                matrix = variational.matrix
            previous = size
            x = x + np.linalg.lstsq(matrix - eye, -residual, rcond=None)[0]
    raise SimulationError(f"no period-{periods} orbit found at {problem.name} = {value:g}{unit}: Newton's "
                          f"method did not converge in {max_iterations} iterations (last residual "
                          f"{float(np.linalg.norm(residual)):.3g}); start closer (a longer transient) or change "
                          f"the parameter")


def _newton_matrix(problem: Problem, x, value: float, periods: int, budget: int, iteration: int,
                   unit: str) -> Flow:
    """The variational run of Newton's iterate ``x``, at most ``budget`` steps (see
    :data:`NEWTON_STEP_FACTOR`); past them a :class:`SimulationError` that says so."""
    try:
        return flow(problem, x, value, periods, max_steps=budget)
    except SimulationError as error:
        if budget == MAX_STEPS:
            raise
        raise SimulationError(f"no period-{periods} orbit found at {problem.name} = {value:g}{unit}: Newton's "
                              f"iterate {iteration} left the start's neighbourhood (its variational run needed "
                              f"more than {budget} steps, {NEWTON_STEP_FACTOR} times the first one's: {error}); "
                              "start closer (another transient) or change the parameter") from None


def _segment_starts(problem: Problem, start, value: float, times: np.ndarray, transient: int) -> np.ndarray:
    """The first guess of every segment's start state, ``(m, u)``: given, or carried from
    one state (given or after a transient) by a plain run through the boundaries."""
    m, u = times.size - 1, problem.unknowns
    if start is None:
        start = transient_state(problem, transient, value)
    states = np.asarray(start, dtype=float)
    if states.shape not in ((u,), (m, u)) or not np.all(np.isfinite(states)):
        raise ParameterError(f"start must be {u} finite numbers or {m} rows of them (one per segment)")
    if states.shape == (m, u):
        return states.copy()
    p, period = problem.build(value)
    y, _, _, counters = problem.run(problem.system_id, p, _full(problem, states, value), times[0], times[-1],
                                    times[:-1].copy(), problem.rtol, problem.atol, *driver_settings(problem, period))
    limits.check_run(counters, "run to the segments' starts")
    return y[:, :u].copy()


def _join(problem: Problem, p: np.ndarray, runs: list[Flow], matrix: np.ndarray) -> Flow:
    """One :class:`Flow` over the orbit from its segments' sampled runs (the first sample
    of each later segment repeats the last of the one before and is dropped)."""
    states = np.concatenate([runs[0].states] + [run.states[1:] for run in runs[1:]])
    times = np.concatenate([runs[0].times] + [run.times[1:] for run in runs[1:]])
    modes = np.concatenate([runs[0].modes] + [run.modes[1:] for run in runs[1:]])
    return Flow(runs[-1].end, matrix, sum(run.impacts for run in runs), sum(run.events for run in runs),
                _guard_minimum(problem, p, times, states), states, times, modes,
                contact_times=np.concatenate([run.contact_times for run in runs]),
                elapsed=sum(run.elapsed for run in runs))


def segment_ends(problem: Problem, states, value: float, periods: int = 1) -> np.ndarray:
    """Each segment's end ``phi_i(x_i)`` by the plain model, ``(m, u)``, for the states
    ``states`` ``(m, u)`` at the ``m`` equally spaced times of ``periods`` forcing periods
    from ``t_start`` (:func:`~camdyn.continuation.multiple.segment_times`); raises
    :class:`SimulationError` if a run fails."""
    states = np.asarray(states, dtype=float)
    p, period = problem.build(float(value))
    times = multiple.segment_times(problem.t_start, periods * period, states.shape[0])
    return np.array([_plain(problem, p, period, states[i], value, times[i], times[i + 1])
                     for i in range(states.shape[0])])


def segment_runs(problem: Problem, states, value: float, periods: int = 1,
                 sampled: bool = False) -> tuple[Flow, np.ndarray]:
    """The segments' variational runs from ``states`` ``(m, u)`` (as :func:`segment_ends`):
    their state-transition matrices ``(m, u, u)``, and one :class:`Flow` over the whole
    orbit whose matrix is their product, the monodromy (sampled, ``SAMPLES_PER_PERIOD``
    per forcing period, when ``sampled``)."""
    states = np.asarray(states, dtype=float)
    m = states.shape[0]
    p, period = problem.build(float(value))
    times = multiple.segment_times(problem.t_start, periods * period, m)
    samples = max(SAMPLES_PER_PERIOD * periods // m, 16) + 1 if sampled else 0
    runs = [_variational(problem, p, period, states[i], value, times[i], times[i + 1], samples) for i in range(m)]
    matrices = np.array([run.matrix for run in runs])
    matrix = multiple.monodromy(matrices)
    if not sampled:
        return Flow(runs[-1].end, matrix, sum(run.impacts for run in runs), sum(run.events for run in runs),
                    math.nan, runs[-1].states, runs[-1].times, runs[-1].modes,
                    elapsed=sum(run.elapsed for run in runs)), matrices
    return _join(problem, p, runs, matrix), matrices


def _segment_ends(problem: Problem, states: np.ndarray, value: float, periods: int) -> np.ndarray | None:
    """:func:`segment_ends`, or None if a run fails (a start beyond a rigid wall, say)."""
    try:
        return segment_ends(problem, states, value, periods)
    except SimulationError:
        return None


def _find_segmented(problem: Problem, start, value: float, periods: int, tolerance: float, max_iterations: int,
                    transient: int, segments: int) -> Orbit:
    """:func:`find_orbit` by multiple shooting: Newton's method on the continuity residuals
    of :mod:`~camdyn.continuation.multiple` (each segment's end by the plain model), the
    cyclic Jacobian from the segments' variational runs renewed as in single shooting
    (chord steps while the residual shrinks fourfold per step). A Newton step whose trial
    states make a run fail is halved, up to ``HALVINGS`` times."""
    _, period = problem.build(value)
    times = multiple.segment_times(problem.t_start, periods * period, segments)
    states = _segment_starts(problem, start, value, times, transient)
    ends = _segment_ends(problem, states, value, periods)
    if ends is None:
        raise SimulationError(f"a shooting run from the start at {problem.name} = {value:g} failed")
    jacobian, previous, size = None, math.inf, math.inf
    for iteration in range(max_iterations + 1):
        residuals = multiple.continuity(ends, states)
        size = float(np.linalg.norm(residuals))
        scale = 1.0 + np.linalg.norm(np.roll(states, -1, axis=0), axis=1)
        if np.all(np.linalg.norm(residuals, axis=1) <= tolerance * scale):
            run, _ = segment_runs(problem, states, value, periods, sampled=True)
            orbit = make_orbit(problem, states[0], value, periods, run, iteration, size)
            return replace(orbit, segment_states=states.copy())
        if iteration == max_iterations:
            break
        if jacobian is None or not size < 0.25 * previous:       # chord steps while they contract fast
            jacobian = multiple.cyclic_jacobian(segment_runs(problem, states, value, periods)[1])
        previous = size
        step = multiple.newton_step(jacobian, residuals)
        for _ in range(HALVINGS + 1):
            ends = _segment_ends(problem, states + step, value, periods)
            if ends is not None:
                break
            step = 0.5 * step
        else:
            break
        states = states + step
    unit = f" {problem.unit}" if problem.unit else ""
    raise SimulationError(f"no period-{periods} orbit found at {problem.name} = {value:g}{unit} with {segments} "
                          f"shooting segments: Newton's method did not converge in {iteration} iterations "
                          f"(last residual {size:.3g}); start closer or change the parameter")
