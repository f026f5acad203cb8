"""Two-parameter curves of bifurcations: a fold, period doubling, grazing or loss of
contact, located on a one-parameter branch, followed as a second parameter moves.

The curve is traced by natural-parameter continuation in the second parameter ``mu``
(Seydel 2010, *Practical Bifurcation and Stability Analysis*, Springer,
doi:10.1007/978-1-4419-1740-9, sec. 5.8, the "two-parameter" boundary traced point by
point): at each ``mu_k`` of a given sequence the first parameter ``lambda`` of the
bifurcation is predicted by linear extrapolation through the last two points, a short
branch of orbits (:func:`~camdyn.continuation.branches.continue_orbits`) is followed
across ``lambda_predicted +- window`` from the previous point's orbit, and the
bifurcation of the wanted kind nearest the prediction is located on it by the branch's
own test functions (fold, period doubling, grazing, contact loss; secant or bisection,
as along a branch). Each point of the curve is therefore a codimension-one bifurcation
located to the one-parameter accuracy (the tests in ``docs/continuation.md``). The
curve ends where no such bifurcation lies within the window, or where the curve turns
back in ``mu`` (a fold of the curve itself, which this scheme cannot pass).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from camdyn.continuation.branches import KINDS, MIN_STEP, continue_orbits
from camdyn.continuation.orbits import Orbit, find_orbit
from camdyn.continuation.problem import Problem, system_problem
from camdyn.errors import CamdynError, ParameterError, SimulationError
from camdyn.params.system import System

__all__ = ["CurvePoint", "Curve", "bifurcation_curve", "system_curve"]

#: Smallest arclength step of the short branches that end at a loss of contact (scaled
#: units) [-]: no orbit exists past it, and the step halves down to this before the end
#: is placed by the secant of the smallest normal force (the other kinds go down to
#: :data:`~camdyn.continuation.branches.MIN_STEP`, which a grazing's end needs).
END_STEP = 1e-4
#: Most orbits on one short branch.
MAX_POINTS = 120
#: Kinds a curve can follow (Neimark-Sacker and sliding reversal are not offered).
CURVE_KINDS = ("fold", "period-doubling", "grazing", "contact-loss")


@dataclass(frozen=True)
class CurvePoint:
    """One point of a two-parameter curve.

    Attributes
    ----------
    second : float
        The second parameter ``mu`` [its unit].
    parameter : float
        The first parameter ``lambda`` of the bifurcation there [its unit].
    orbit : Orbit
        The orbit at the located bifurcation.
    """

    second: float
    parameter: float
    orbit: Orbit


@dataclass
class Curve:
    """A bifurcation followed over a second parameter.

    Attributes
    ----------
    kind : str
        The bifurcation (:data:`CURVE_KINDS`).
    name, second_name : str
        The first and the second parameter's names.
    points : list of CurvePoint
        In the order of the second parameter's values.
    stopped : str
        Why the curve ended.
    """

    kind: str
    name: str
    second_name: str
    points: list[CurvePoint] = field(default_factory=list)
    stopped: str = ""

    @property
    def seconds(self) -> np.ndarray:
        """The second parameter at each point [its unit]."""
        return np.array([p.second for p in self.points])

    @property
    def parameters(self) -> np.ndarray:
        """The first parameter at each point [its unit]."""
        return np.array([p.parameter for p in self.points])


def _check(kind: str, seconds: np.ndarray, near: float, window: float) -> None:
    if kind not in CURVE_KINDS:
        raise ParameterError(f"a curve follows one of {', '.join(CURVE_KINDS)}, not {kind!r}"
                             + (" (not offered)" if kind in KINDS else ""))
    if seconds.ndim != 1 or seconds.size < 2 or not np.all(np.isfinite(seconds)):
        raise ParameterError("the second parameter needs at least two finite values")
    steps = np.diff(seconds)
    if not (np.all(steps > 0) or np.all(steps < 0)):
        raise ParameterError("the second parameter's values must be strictly monotonic")
    if not (math.isfinite(near) and math.isfinite(window) and window > 0):
        raise ParameterError(f"the bifurcation's first guess and window must be finite, window > 0; got {near}, "
                             f"{window}")


def _locate(problem: Problem, kind: str, centre: float, window: float, start, periods: int, step: float,
            transient: int) -> tuple[float, Orbit] | None:
    """The bifurcation ``kind`` nearest ``centre`` on the branch across ``centre +- window``,
    started from the state ``start`` (a transient if None or if Newton fails from it)."""
    low = centre - window
    try:
        orbit = find_orbit(problem, start=start, value=low, periods=periods) if start is not None else None
    except SimulationError:
        orbit = None
    if orbit is None:
        orbit = find_orbit(problem, value=low, periods=periods, transient=transient)
    smallest = min(step, END_STEP) if kind == "contact-loss" else min(step, MIN_STEP)
    branch = continue_orbits(problem, orbit, centre + window, step=step, min_step=smallest,
                             max_step=max(step, 0.05), max_points=MAX_POINTS)
    found = [b for b in branch.bifurcations if b.kind == kind]
    if not found:
        return None
    best = min(found, key=lambda b: abs(b.parameter - centre))
    return best.parameter, best.orbit


def bifurcation_curve(problem_at: Callable[[float], Problem], kind: str, seconds: Sequence[float], near: float,
                      window: float, periods: int = 1, step: float = 0.01, transient: int = 100,
                      second_name: str = "mu",
                      progress: Callable[[CurvePoint], None] | None = None) -> Curve:
    """Follow the bifurcation ``kind`` found near ``lambda = near`` over the second
    parameter's ``seconds``.

    Parameters
    ----------
    problem_at : callable
        ``problem_at(mu) -> Problem``: the periodic problem at the second parameter
        ``mu``, its scalar parameter being the first parameter ``lambda``.
    kind : str
        ``fold``, ``period-doubling``, ``grazing`` or ``contact-loss``.
    seconds : sequence of float
        The second parameter's values [its unit], strictly monotonic, the first where
        the bifurcation lies near ``near``.
    near : float
        First guess of the bifurcation's ``lambda`` at ``seconds[0]`` [its unit].
    window : float
        Half-width of the search in ``lambda`` about each prediction [its unit].
    periods : int
        Period of the orbits on which the bifurcation lies, in forcing periods.
    step : float
        Arclength step of the short branches (scaled units).
    transient : int
        Forcing periods of transient for an orbit Newton's method cannot reach.
    second_name : str
        Name of ``mu``.
    progress : callable, optional
        Called with each point found.

    Returns
    -------
    Curve
        Ended by the last value, by a bifurcation missing from its window, or by a run
        that failed (its message in ``stopped``).
    """
    values = np.asarray(seconds, dtype=float)
    _check(kind, values, float(near), float(window))
    first = problem_at(float(values[0]))
    curve = Curve(kind, first.name, second_name)
    centre, state = float(near), None
    for k, mu in enumerate(values):
        if len(curve.points) >= 2:                         # secant predictor through the last two points
            a, b = curve.points[-2], curve.points[-1]
            centre = b.parameter + (b.parameter - a.parameter) * (mu - b.second) / (b.second - a.second)
        try:
            found = _locate(first if k == 0 else problem_at(float(mu)), kind, centre, window, state, periods, step,
                            transient)
        except CamdynError as error:
            curve.stopped = f"at {second_name} = {mu:.9g}: {error}"
            return curve
        if found is None:
            curve.stopped = (f"no {kind} within {window:g} of {centre:.9g} at {second_name} = {mu:.9g}")
            return curve
        point = CurvePoint(float(mu), found[0], found[1])
        curve.points.append(point)
        centre, state = point.parameter, point.orbit.state
        if progress:
            progress(point)
    curve.stopped = f"{second_name} reached its last value"
    return curve


def system_curve(system: System, kind: str, key: str, second_key: str, seconds: Sequence[float], near: float,
                 window: float, periods: int = 1, step: float = 0.01, transient: int = 100, rtol: float = 1e-10,
                 progress: Callable[[CurvePoint], None] | None = None) -> Curve:
    """:func:`bifurcation_curve` for the cam-follower: the first parameter the dotted
    key ``key`` (e.g. ``motion.speed`` [Hz]), the second ``second_key`` (e.g.
    ``cam.runout`` [m]), both in the units of :class:`~camdyn.params.system.System`.

    Raises
    ------
    ParameterError
        For a bad key, kind or range, before any work.
    """
    if second_key == key:
        raise ParameterError(f"the two parameters must differ, got {key} twice")
    values = np.asarray(seconds, dtype=float)
    _check(kind, values, float(near), float(window))
    for mu in (values[0], values[-1]):                    # refuse what the system cannot take, before work
        system_problem(system.with_values(**{second_key: float(mu), key: float(near)}), key)

    def problem_at(mu: float) -> Problem:
        return system_problem(system.with_values(**{second_key: mu, key: float(near)}), key, rtol=rtol,
                              atol=rtol * 1e-2)
    return bifurcation_curve(problem_at, kind, values, near, window, periods, step, transient, second_key,
                             progress)
