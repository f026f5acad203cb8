"""Branch switching at a period doubling: from a located period-doubling point of a
period-``k`` branch onto the period-``2k`` branch born there, and its continuation.

At a period doubling the monodromy matrix ``M`` of the period-``k`` orbit ``x*`` has a
multiplier -1 with eigenvector ``v``. Over ``2k`` forcing periods the bifurcation is a
pitchfork: ``M^2 - I`` is singular along ``v`` and the period-``2k`` branch leaves
``(x*, lambda*)`` with the tangent ``(v, 0)`` (Seydel 2010, *Practical Bifurcation and
Stability Analysis*, doi:10.1007/978-1-4419-1740-9, sec. 7.4; Kuznetsov 2004, *Elements
of Applied Bifurcation Theory*, doi:10.1007/978-1-4757-3978-7, sec. 4.5). The first orbit
of the new branch is the solution ``u = (x, lambda)`` of::

    phi(t0 + 2kT; t0, x, lambda) - x = 0,      d . (u - u*) = epsilon,      d = (v, 0),

by Newton's method from ``u* + epsilon d`` (all in the scaled variables of the
continuation). The period-``k`` branch crosses the same hyperplane too, but at a
parameter ``O(epsilon)`` from ``lambda*`` against the new branch's ``O(epsilon^2)``, so
from a small ``epsilon`` Newton's method lands on the new branch; the result is checked
(its state after ``k`` periods must differ from its start) and refused otherwise.
"""

from __future__ import annotations

import math

import numpy as np

from camdyn.continuation.branches import Bifurcation, Branch, continuation_scales, continue_orbits
from camdyn.continuation.orbits import SAMPLES_PER_PERIOD, Orbit, flow, make_orbit, shoot
from camdyn.continuation.problem import Problem
from camdyn.errors import ParameterError, SimulationError

__all__ = ["doubled_orbit", "switch_branch"]

#: A period-doubling point's multiplier must lie within this of -1 [-].
MULTIPLIER_TOLERANCE = 0.05
#: Newton's method for the first period-``2k`` orbit stops, diverged, at a step this long
#: (scaled) [-], or from its third step on at one not shorter than ``CONTRACTION`` times
#: the step before (the corrector's rule along a branch). Next to the chapter 3 rig's
#: period doublings past its loss of contact (6.904-6.911 Hz, chattering orbits) its
#: iterates wandered (down to 1.6 Hz) and three switches took 34 s to find nothing; now
#: they stop after 3 or 4 iterations (1.2 s together).
DIVERGED = 0.5
CONTRACTION = 0.8


def _critical_vector(orbit: Orbit) -> np.ndarray:
    """The real eigenvector of the monodromy matrix for the multiplier nearest -1."""
    values, vectors = np.linalg.eig(orbit.monodromy)
    i = int(np.argmin(np.abs(values + 1.0)))
    if not abs(values[i] + 1.0) < MULTIPLIER_TOLERANCE:
        raise ParameterError(f"the orbit at {orbit.parameter:.9g} has no multiplier near -1 (nearest "
                             f"{complex(values[i]):.4g}): it is not a period-doubling point")
    return np.real(vectors[:, i])


def doubled_orbit(problem: Problem, orbit: Orbit, amplitude: float = 1e-3, tolerance: float = 1e-10,
                  max_iterations: int = 30) -> Orbit:
    """The first orbit of the period-``2k`` branch born at the period-doubling point
    ``orbit`` (a period-``k`` orbit with a multiplier at -1).

    Parameters
    ----------
    problem : Problem
        The problem of the period-``k`` branch.
    orbit : Orbit
        The located period-doubling point (:class:`~camdyn.continuation.branches.Bifurcation`
        ``.orbit``).
    amplitude : float
        ``epsilon``, the distance from the point along the critical eigenvector, in the
        continuation's scaled units [-].
    tolerance : float
        Newton's convergence on the scaled step [-].
    max_iterations : int
        Newton iterations before :class:`SimulationError`.

    Returns
    -------
    Orbit
        A period-``2k`` orbit, its parameter within ``O(amplitude^2)`` of the point's.
    """
    if not (0 < amplitude < 0.5 and tolerance > 0 and max_iterations >= 1):
        raise ParameterError(f"amplitude must lie in (0, 0.5), tolerance be positive and max_iterations at least "
                             f"1; got {amplitude}, {tolerance}, {max_iterations}")
    k = orbit.periods
    scales = continuation_scales(orbit)
    sx = scales[:-1]
    vector = _critical_vector(orbit) / sx
    direction = np.r_[vector / np.linalg.norm(vector), 0.0]
    anchor = np.r_[orbit.state, orbit.parameter] / scales
    z = anchor + amplitude * direction
    last = math.inf
    for iteration in range(max_iterations):
        x, value = z[:-1] * sx, float(z[-1] * scales[-1])
        run = flow(problem, x, value, 2 * k)
        h = 1e-6 * scales[-1]
        plus, minus = shoot(problem, x, value + h, 2 * k), shoot(problem, x, value - h, 2 * k)
        slope = (plus - minus) / (2.0 * h)                                 # central difference
        jacobian = np.vstack([np.c_[(run.matrix - np.eye(x.size)) * sx[None, :], slope * scales[-1]] / sx[:, None],
                              direction])
        rhs = np.r_[(shoot(problem, x, value, 2 * k) - x) / sx, direction @ (z - anchor) - amplitude]
        step = np.linalg.solve(jacobian, -rhs)
        size = float(np.linalg.norm(step))
        if not size < min(DIVERGED, CONTRACTION * last if iteration >= 2 else DIVERGED):
            raise SimulationError(f"no period-{2 * k} orbit found next to the period doubling at "
                                  f"{orbit.parameter:.9g}: Newton's method diverged (step {iteration + 1}: "
                                  f"{size:.3g}, scaled)")
        z = z + step
        last = size
        if size < tolerance * (1.0 + np.linalg.norm(z)):
            break
    else:
        raise SimulationError(f"no period-{2 * k} orbit found next to the period doubling at "
                              f"{orbit.parameter:.9g}: Newton's method did not converge")
    x, value = z[:-1] * sx, float(z[-1] * scales[-1])
    half = np.linalg.norm((shoot(problem, x, value, k) - x) / sx)
    if not half > 0.1 * amplitude:                 # the period-k orbit itself: not a new branch
        raise SimulationError(f"the search from the period doubling at {orbit.parameter:.9g} fell back onto the "
                              f"period-{k} orbit; try a larger amplitude")
    run = flow(problem, x, value, 2 * k, SAMPLES_PER_PERIOD * 2 * k)
    return make_orbit(problem, x, value, 2 * k, run, 0, float(np.linalg.norm(shoot(problem, x, value, 2 * k) - x)))


def switch_branch(problem: Problem, bifurcation: Bifurcation, stop: float, amplitude: float = 1e-3,
                  **settings) -> Branch:
    """Continue the period-``2k`` branch born at the period doubling ``bifurcation``
    towards the parameter ``stop`` [its unit].

    The first orbit is :func:`doubled_orbit`; the rest is
    :func:`~camdyn.continuation.branches.continue_orbits` with ``settings`` (``step``,
    ``max_points``, ...). Raises :class:`ParameterError` if ``bifurcation`` is not a
    period doubling.
    """
    if bifurcation.kind != "period-doubling":
        raise ParameterError(f"branch switching needs a period-doubling point, got a {bifurcation.kind}")
    start = doubled_orbit(problem, bifurcation.orbit, amplitude)
    if math.isclose(start.parameter, stop, rel_tol=0.0, abs_tol=1e-12 * max(1.0, abs(stop))):
        return Branch([start], [], "the period doubling lies at the end of the range")
    return continue_orbits(problem, start, stop, **settings)
