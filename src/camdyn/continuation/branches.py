"""Pseudo-arclength continuation of periodic orbits in one parameter, with detection of
folds, period doublings, Neimark-Sacker bifurcations and grazing along the branch.

The unknowns are ``u = (x, lambda)``: the orbit's state at the phase ``t0`` and the
parameter. On the branch ``G(u) = phi(t0 + kT; t0, x, lambda) - x = 0``, with the
Jacobian ``[M - I, G_lambda]`` (``M`` the saltation-corrected monodromy matrix,
``G_lambda`` by central differences). A step predicts along the unit tangent ``t``, the
null vector of that Jacobian, and corrects by Newton's method on ``G(u) = 0`` together
with ``t . (u - u_predicted) = 0`` (Keller's pseudo-arclength condition; Allgower &
Georg 2003, *Introduction to Numerical Continuation Methods*, ch. 2 and 6; Seydel 2010,
sec. 4.4-4.5). The step shrinks when the corrector fails, or converges farther from
the predicted point than the step's length (onto another branch), and grows when it
converges fast. All of it runs in scaled variables ``u / s`` so that a parameter in Hz and a state
in rad weigh alike in the arclength.

Test functions, evaluated at every point; a sign change between two points is located
by the secant method (Illinois variant) along the arclength (Seydel 2010, sec. 5.3):

* fold: the parameter component of the tangent;
* period doubling: ``det(M + I)`` (a real multiplier crosses -1); a sign change where
  the monodromy matrix jumps, with no multiplier near -1 at the located point, is
  reported as a multiplier jump (a discontinuity-induced bifurcation: Di Bernardo et al.
  2008, ch. 8; on a cam of circular arcs, an impact crossing a joint of the profile);
* Neimark-Sacker: ``prod_{i<j} (mu_i mu_j - 1)`` (a complex pair crosses the unit
  circle; a real pair with product 1, a neutral saddle, is discarded after location);
* grazing: the number of impacts per period changes (located by bisection, as the
  orbit's topology changes there: Di Bernardo et al. 2008, *Piecewise-smooth Dynamical
  Systems*, ch. 8);
* contact loss (the cam-follower): the smallest normal force over the orbit, unclipped
  (``min Fn = 0``; :mod:`.margins`);
* sliding reversal (the cam-follower): the smallest sliding velocity in contact, signed
  by the direction of sliding (``min s vr = 0``; :mod:`.margins`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from camdyn.continuation import multiple
from camdyn.continuation.ends import (
    END_FRACTION,
    contact_loss_end,
    flight_grazing_end,
    grazing_end,
    half_distance,
    jumped_off_contact,
    stall_end,
)
from camdyn.continuation.orbits import (
    SAMPLES_PER_PERIOD,
    Flow,
    Orbit,
    flow,
    make_orbit,
    segment_ends,
    segment_runs,
    shoot,
)
from camdyn.continuation.problem import Problem
from camdyn.errors import ParameterError, SimulationError

#: Smallest arclength step by default (scaled units) [-].
MIN_STEP = 1e-6
#: Below this |det([J; t])| (scaled units) the tangent is oriented along the previous one.
ORIENTATION_FLOOR = 1e-12
#: A located period doubling needs a multiplier within this of -1 [-]: where the sign of
#: ``det(M + I)`` changes because the monodromy matrix jumps (a translating follower's
#: impact crossing a joint of its cam profile, where the cam's acceleration jumps: a
#: corner-impact bifurcation) the secant converges onto the jump with no multiplier near
#: -1, and the point is reported as a ``multiplier-jump``.
JUMP_TOLERANCE = 0.1
#: A corrected point farther than this many step lengths from its predicted point is
#: refused and the step halved: the corrector has converged onto another branch (past a
#: grazing, where the branch it follows ends or turns sharply, a long step landed on an
#: orbit of another impact count up to 1.8 Hz away on the chapter 3 rig). On a smooth
#: branch the distance is about half the curvature times the step squared (Allgower &
#: Georg 2003, sec. 6.1), far below the step. Across a grazing, where the branch turns
#: sharply, a point up to one step length away is legitimate (with 1.0 the chapter 3
#: rig's one-impact branch stopped at its grazing, 9.5593 Hz, unreported).
JUMP_DISTANCE = 2.0
#: A corrector that converges in this many iterations or fewer grows the next step by 1.5.
FAST_CORRECTIONS = 4
#: Two new points in a row, each within this fraction of the last step from the point
#: before the last, end the branch: the tangent's orientation flips at every point and
#: the continuation steps to and fro over its own points (on the chapter 3 rig the
#: period-4 branch from 20.7 Hz alternated between 20.41412 and 20.41513 Hz for 200
#: points near the branch point where it meets the period-2 orbit). One step back alone
#: does not end it: the period-2 branch from 9.2 Hz takes one next to its grazing near
#: 9.013 Hz and goes on until its step falls below the minimum [-].
RETRACE = 0.1
#: Most iterations of the corrector's fallback, Newton's method with the Jacobian renewed
#: at every iterate (a variational run each).
NEWTON_CORRECTIONS = 15

__all__ = ["Bifurcation", "Branch", "continue_orbits", "continuation_scales", "KINDS"]

#: The bifurcations detected, as named in results.
KINDS = ("fold", "period-doubling", "neimark-sacker", "grazing", "contact-loss", "sliding-reversal",
         "multiplier-jump")
#: The kinds located by the sign change of a smooth test function.
_SMOOTH = ("fold", "period-doubling", "neimark-sacker", "contact-loss", "sliding-reversal")


@dataclass(frozen=True)
class Bifurcation:
    """A located bifurcation.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    parameter : float
        The parameter's value there [its unit].
    orbit : Orbit
        The orbit at the located point.
    """

    kind: str
    parameter: float
    orbit: Orbit


@dataclass(frozen=True)
class Branch:
    """A continued branch of periodic orbits.

    Attributes
    ----------
    orbits : list of Orbit
        The accepted points, in order along the branch.
    bifurcations : list of Bifurcation
        The located bifurcations, in order along the branch.
    stopped : str
        Why the continuation ended.
    """

    orbits: list[Orbit] = field(default_factory=list)
    bifurcations: list[Bifurcation] = field(default_factory=list)
    stopped: str = ""


@dataclass
class _Point:
    z: np.ndarray          # scaled unknowns (x / sx, lambda / s_lambda)
    tangent: np.ndarray    # unit tangent, scaled
    orbit: Orbit
    iterations: int
    jacobian: np.ndarray   # scaled [M - I, G_lambda]


class _Continuation:
    """The state of one continuation: the problem, the scales and the settings."""

    def __init__(self, problem: Problem, periods: int, scales: np.ndarray, tolerance: float, max_corrections: int,
                 segments: int = 1):
        self.problem = problem
        self.periods = periods
        self.scales = scales
        self.tolerance = tolerance
        self.max_corrections = max_corrections
        self.segments = segments
        self.u = problem.unknowns * segments
        self.orientation = 0.0      # sign of det([J; t]) along the branch, set at its first point
        self.retraced = 0           # consecutive points that stepped back onto the point before the last

    def unscale(self, z: np.ndarray) -> tuple[np.ndarray, float]:
        u = z * self.scales
        return u[:-1], float(u[-1])

    def pack(self, orbit: Orbit) -> np.ndarray:
        """The unscaled unknowns ``(x, lambda)`` of ``orbit`` (every segment's state with
        multiple shooting)."""
        states = orbit.state if self.segments == 1 else orbit.segment_states.ravel()
        return np.r_[states, orbit.parameter]

    def _ends(self, x: np.ndarray, value: float) -> np.ndarray:
        """Every segment's end, stacked (the end of the period with one segment)."""
        if self.segments == 1:
            return shoot(self.problem, x, value, self.periods)
        return segment_ends(self.problem, x.reshape(self.segments, -1), value, self.periods).ravel()

    def _gap(self, ends: np.ndarray, x: np.ndarray) -> np.ndarray:
        """The residual from the ends: ``G`` or the continuity conditions, stacked."""
        if self.segments == 1:
            return ends - x
        return multiple.continuity(ends.reshape(self.segments, -1), x.reshape(self.segments, -1)).ravel()

    def residual(self, z: np.ndarray) -> np.ndarray:
        """Scaled residual ``G / s_x`` at scaled ``z``, by the plain model."""
        x, value = self.unscale(z)
        return self._gap(self._ends(x, value), x) / self.scales[:-1]

    def _run(self, x: np.ndarray, value: float, sampled: bool) -> tuple[Flow, np.ndarray]:
        """The variational run (sampled, for an orbit) and the Jacobian of the residual in
        the states (unsampled runs step alike: the same matrix, 12% cheaper)."""
        if self.segments == 1:
            run = flow(self.problem, x, value, self.periods, SAMPLES_PER_PERIOD * self.periods if sampled else 0)
            return run, run.matrix - np.eye(self.u)
        run, matrices = segment_runs(self.problem, x.reshape(self.segments, -1), value, self.periods, sampled)
        return run, multiple.cyclic_jacobian(matrices)

    def linearization(self, z: np.ndarray, sampled: bool = True) -> tuple[Flow, np.ndarray, np.ndarray]:
        """The variational run at scaled ``z`` (sampled where ``sampled``), the scaled Jacobian
        ``[M - I, G_lambda]`` there (``G_lambda`` by central differences) and an
        estimate of the scaled residual (the mean of the two differenced runs, exact to
        ``O(h^2)``: what the orbit reports, never what Newton's method solves)."""
        x, value = self.unscale(z)
        run, states_jacobian = self._run(x, value, sampled)
        h = 1e-6 * self.scales[-1]
        plus = self._ends(x, value + h)
        minus = self._ends(x, value - h)
        jac = np.empty((self.u, self.u + 1))
        jac[:, :-1] = states_jacobian
        jac[:, -1] = (plus - minus) / (2.0 * h)                        # central difference
        sx = self.scales[:-1]
        return run, jac * self.scales[None, :] / sx[:, None], self._gap(0.5 * (plus + minus), x) / sx

    def point(self, z: np.ndarray, previous: np.ndarray, iterations: int) -> _Point:
        """The converged point at ``z``: its orbit (monodromy and multipliers from the
        variational run), its Jacobian and the tangent oriented along ``previous``."""
        run, jac, residual = self.linearization(z)
        x, value = self.unscale(z)
        states = x.reshape(self.segments, -1)
        orbit = make_orbit(self.problem, states[0], value, self.periods, run, iterations,
                           float(np.linalg.norm(residual * self.scales[:-1])))
        if self.segments > 1:
            orbit = replace(orbit, segment_states=states.copy())
        vector = np.linalg.svd(jac)[2][-1]                               # the null vector
        return _Point(z, self.orient(jac, vector, previous), orbit, iterations, jac)

    def orient(self, jac: np.ndarray, vector: np.ndarray, previous: np.ndarray) -> np.ndarray:
        """The null vector ``vector`` of ``jac`` signed so that ``det([jac; t])`` keeps the
        sign it had at the branch's first point (Allgower & Georg 2003, sec. 2.1: the sign
        is constant along a branch through regular points and folds, smooth or not, since
        it equals that of ``det(M - I) t_lambda``); along ``previous`` at the first point,
        or where the determinant is too small to tell."""
        determinant = float(np.linalg.det(np.vstack([jac, vector])))
        if self.orientation == 0.0 or abs(determinant) < ORIENTATION_FLOOR:
            return vector if vector @ previous >= 0 else -vector
        return vector if determinant * self.orientation > 0 else -vector

    def correct(self, guess: np.ndarray, direction: np.ndarray, anchor: np.ndarray, arclength: float,
                jac: np.ndarray, others: tuple = ()) -> _Point:
        """Corrector on ``G = 0`` and ``direction . (z - anchor) = arclength``: chord
        iterations with the Jacobian ``jac`` of the last point (Allgower & Georg 2003,
        sec. 6.1), then, if they fail (the Jacobian jumps where the orbit gains or loses
        an event), chord iterations with each Jacobian of ``others`` in turn (another
        point's: a location's bracket end across the jump), then Newton's iterations with
        the Jacobian renewed at each; raises :class:`SimulationError` when none converges."""
        for matrix in (jac, *others):
            try:
                return self._iterate(guess, direction, anchor, arclength, matrix)
            except (SimulationError, ParameterError):
                pass
        return self._iterate(guess, direction, anchor, arclength, None)

    def _iterate(self, guess, direction, anchor, arclength, jac) -> _Point:
        """Chord iterations with ``jac``, or Newton's with a renewed Jacobian if None."""
        z = guess.copy()
        last = math.inf
        limit = self.max_corrections if jac is not None else min(self.max_corrections, NEWTON_CORRECTIONS)
        for iteration in range(1, limit + 1):
            if jac is None:
                _, fresh, _ = self.linearization(z, sampled=False)
                residual = self.residual(z)
                full = np.vstack([fresh, direction])
            else:
                residual = self.residual(z)
                full = np.vstack([jac, direction])
            rhs = np.concatenate([residual, [direction @ (z - anchor) - arclength]])
            step = np.linalg.solve(full, -rhs)
            size = float(np.linalg.norm(step))
            if not size < min(0.5, 0.8 * last if iteration > 2 else 0.5):   # diverging or stalling
                break
            z = z + step
            last = size
            if size < self.tolerance * (1.0 + np.linalg.norm(z)):
                return self.point(z, direction, iteration)
        raise SimulationError("the corrector did not converge")


def _tests(point: _Point) -> dict:
    """The smooth test functions at a point."""
    mu = point.orbit.multipliers
    pairs = [mu[i] * mu[j] - 1.0 for i in range(mu.size) for j in range(i + 1, mu.size)]
    return {"fold": float(point.tangent[-1]),
            "period-doubling": float(np.real(np.prod(mu + 1.0))),
            "neimark-sacker": float(np.real(np.prod(pairs))) if pairs else 1.0,
            "contact-loss": point.orbit.force_minimum,
            "sliding-reversal": point.orbit.sliding_minimum}


def _locate(job: _Continuation, a: _Point, b: _Point, kind: str, max_iterations: int = 60) -> _Point | None:
    """The point between ``a`` and ``b`` where test ``kind`` vanishes (or, for grazing,
    where the impact count changes), along the arclength from ``a``, until the bracket is
    below 1e-12 of the arclength (grazing: the corrector's tolerance, as the impact count
    comes from the variational run, at ``matrix_rtol``). Where the corrector
    fails inside the bracket (near grazing it may), the last point it reached stands for
    the bifurcation, less accurately."""
    s_b = float(a.tangent @ (b.z - a.z))
    lo, hi = (0.0, a), (s_b, b)

    def value(point: _Point) -> float:
        if kind == "grazing":
            return 1.0 if point.orbit.impacts_per_period == a.orbit.impacts_per_period else -1.0
        return _tests(point)[kind]

    f_lo, f_hi = value(a), value(b)
    side, best, width = 0, b, (job.tolerance if kind == "grazing" else 1e-12) * (1.0 + abs(s_b))
    for _ in range(max_iterations):
        if abs(hi[0] - lo[0]) < width:
            break
        if kind == "grazing":
            s = 0.5 * (lo[0] + hi[0])
        else:
            s = hi[0] - f_hi * (hi[0] - lo[0]) / (f_hi - f_lo)
        try:
            point = job.correct(a.z + s * a.tangent, a.tangent, a.z, s, a.jacobian,
                                (hi[1].jacobian,) if kind == "grazing" else ())
        except (SimulationError, ParameterError):
            break                                 # the corrector fails here: keep the bracket's best point
        f = value(point)
        best = point
        if f == 0.0 or (kind != "grazing" and abs(f) < 1e-14):
            break
        if (f > 0) == (f_lo > 0):
            lo, f_lo = (s, point), f
            if side == -1 and kind != "grazing":
                f_hi *= 0.5                                           # Illinois
            side = -1
        else:
            hi, f_hi = (s, point), f
            if side == 1 and kind != "grazing":
                f_lo *= 0.5
            side = 1
    mu = best.orbit.multipliers
    if kind == "neimark-sacker" and not np.any(np.abs(mu.imag) > 1e-8 * np.abs(mu)):
        return None                                                   # a neutral saddle
    return best


def _detect(job: _Continuation, a: _Point, b: _Point) -> list[Bifurcation]:
    found = []
    before, after = _tests(a), _tests(b)
    for kind in _SMOOTH:
        if before[kind] * after[kind] < 0:                       # False for NaN (a test model)
            point = _locate(job, a, b, kind)
            if point is None:
                continue
            if kind == "period-doubling" and not np.min(np.abs(point.orbit.multipliers + 1.0)) < JUMP_TOLERANCE:
                kind = "multiplier-jump"        # det(M + I) jumped across zero: M is discontinuous there
            found.append(Bifurcation(kind, point.orbit.parameter, point.orbit))
    if a.orbit.impacts_per_period != b.orbit.impacts_per_period:
        point = _locate(job, a, b, "grazing")
        if point is not None:
            found.append(Bifurcation("grazing", point.orbit.parameter, point.orbit))
    return sorted(found, key=lambda item: float(a.tangent @ (job.pack(item.orbit) / job.scales)))


def _ended(job: _Continuation, new: _Point, last: _Point, before: np.ndarray | None, halves: list | None) -> str:
    """Why the branch ends at its new point ``new`` (after ``last``, itself after the
    scaled point ``before``), or an empty string: it steps back onto its own points
    (:data:`RETRACE`), or a period-``2k`` branch meets its period-``k`` orbit
    (:func:`~camdyn.continuation.ends.half_distance`, appended to ``halves``)."""
    where = f"{job.problem.name} = {new.orbit.parameter:.9g}"
    back = before is not None and np.linalg.norm(new.z - before) < RETRACE * np.linalg.norm(last.z - before)
    job.retraced = job.retraced + 1 if back else 0
    if job.retraced >= 2:
        return f"the continuation stepped to and fro over its own points at {where}"
    if halves is not None:
        halves.append(half_distance(job.problem, new.orbit, job.scales))
        if halves[-1] < END_FRACTION * max(halves):
            return f"the branch reached the period-{new.orbit.periods // 2} orbit (its period doubling) at {where}"
    return ""


def _check_steps(step: float, min_step: float, max_step: float, max_points: int) -> None:
    if not (0 < min_step <= step <= max_step):
        raise ParameterError(f"steps must satisfy 0 < min_step <= step <= max_step, got {min_step}, {step}, "
                             f"{max_step}")
    if max_points < 2:
        raise ParameterError(f"max_points must be at least 2, got {max_points}")


def continuation_scales(orbit: Orbit) -> np.ndarray:
    """Scales of the unknowns ``(x, lambda)`` in the continuation: each state component by
    its largest magnitude over the orbit (:attr:`Orbit.extent`; its magnitude at the
    orbit's phase when not sampled), but by no less than a tenth of the largest, the
    parameter by its magnitude. A component that passes near zero at the orbit's phase
    (a follower at rest there) keeps the scale of its motion, not of the integration
    noise."""
    x0 = np.abs(orbit.state) if orbit.extent is None else np.maximum(np.abs(orbit.state), orbit.extent)
    return np.r_[np.maximum(x0, max(0.1 * x0.max(), 1e-12)), max(abs(orbit.parameter), 1e-12)]


def continue_orbits(problem: Problem, start: Orbit, stop: float, step: float = 0.01, min_step: float = MIN_STEP,
                    max_step: float = 0.1, max_points: int = 500, tolerance: float = 1e-10,
                    max_corrections: int = 15, progress: Callable[[Orbit], None] | None = None,
                    stall: int = 0) -> Branch:
    """Continue the orbit ``start`` in the problem's scalar parameter towards ``stop``.

    Parameters
    ----------
    problem : Problem
        The system and its scalar parameter.
    start : Orbit
        A converged orbit (:func:`~camdyn.continuation.orbits.find_orbit`) of ``problem``.
        One found by multiple shooting (``segments=m``) is continued with the same ``m``
        segments: the unknowns are then every segment's state and the parameter.
    stop : float
        The parameter's far end [its unit]: continuation starts towards it and ends when
        the parameter leaves the interval between ``start.parameter`` and ``stop`` (the
        last point lands on it) or comes back past its start (after a fold).
    step, min_step, max_step : float
        First, smallest and largest arclength step, in scaled units
        (:func:`continuation_scales`: the parameter by its starting magnitude, each state
        component by its largest magnitude over the starting orbit, but by no less than a
        tenth of the largest).
    max_points : int
        Most points on the branch.
    tolerance : float
        Corrector's convergence on the scaled Newton step.
    progress : callable, optional
        Called with each accepted orbit.
    stall : int
        End the branch when it stalls over its last ``stall`` points (0: never;
        :func:`~camdyn.continuation.ends.stall_end`).

    Returns
    -------
    Branch
    """
    _check_steps(step, min_step, max_step, max_points)
    lo, hi = sorted((start.parameter, float(stop)))
    if not hi > lo:
        raise ParameterError(f"stop must differ from the start {start.parameter}")
    direction = 1.0 if stop > start.parameter else -1.0
    segments = 1 if start.segment_states is None else start.segment_states.shape[0]
    scales = continuation_scales(start)
    if segments > 1:                                           # every segment's state scaled alike
        scales = np.r_[np.tile(scales[:-1], segments), scales[-1]]
    job = _Continuation(problem, start.periods, scales, tolerance, max_corrections, segments)
    z0 = job.pack(start) / scales
    seed = np.zeros(z0.size)
    seed[-1] = direction
    point = job.point(z0, seed, start.iterations)
    job.orientation = math.copysign(1.0, float(np.linalg.det(np.vstack([point.jacobian, point.tangent]))))
    point.orbit = start
    branch = Branch([start], [], "")
    if progress:
        progress(start)
    ds = step
    before = None                                              # the point before the last
    halves = [half_distance(problem, start, scales)] if start.periods % 2 == 0 and segments == 1 else None
    while len(branch.orbits) < max_points:
        last_step = False
        target = point.z[-1] + ds * point.tangent[-1]
        edge = hi if point.tangent[-1] > 0 else lo
        if (target - edge / scales[-1]) * point.tangent[-1] > 0 and abs(point.tangent[-1]) > 1e-3:
            ds = (edge / scales[-1] - point.z[-1]) / point.tangent[-1]
            last_step = True
        try:                                               # a failed run or a parameter out of bounds
            if last_step:                                  # land on the edge: the parameter fixed there
                axis = np.zeros(point.z.size)
                axis[-1] = 1.0
                new = job.correct(point.z + ds * point.tangent, axis, np.zeros(point.z.size), edge / scales[-1],
                                  point.jacobian)
            else:
                new = job.correct(point.z + ds * point.tangent, point.tangent, point.z, ds, point.jacobian)
                if np.linalg.norm(new.z - point.z - ds * point.tangent) > JUMP_DISTANCE * ds:
                    raise SimulationError("the corrector left the branch")
            if jumped_off_contact(point.orbit, new.orbit):
                raise SimulationError("the orbit jumped off its contact")
        except (SimulationError, ParameterError):
            ds *= 0.5
            if ds < min_step:
                branch.bifurcations.extend(Bifurcation(*end) for end in contact_loss_end(branch.orbits)
                                           + grazing_end(branch.orbits) + flight_grazing_end(branch.orbits))
                return Branch(branch.orbits, branch.bifurcations,
                              f"the step fell below {min_step:g} at {problem.name} = {point.orbit.parameter:.9g}")
            continue
        branch.bifurcations.extend(_detect(job, point, new))
        branch.orbits.append(new.orbit)
        if progress:
            progress(new.orbit)
        ended = _ended(job, new, point, before, halves) or stall_end(branch.orbits, stall, hi - lo, problem)
        if ended:
            return Branch(branch.orbits, branch.bifurcations, ended)
        before, point = point.z, new
        value = new.orbit.parameter
        if last_step or not (lo - 1e-12 * scales[-1] <= value <= hi + 1e-12 * scales[-1]):
            return Branch(branch.orbits, branch.bifurcations, f"{problem.name} reached the end of its range")
        ds = (min(ds * 1.5, max_step) if new.iterations <= FAST_CORRECTIONS
              else max(ds * 0.7, min_step) if new.iterations > 8 else ds)
    return Branch(branch.orbits, branch.bifurcations, f"{max_points} points computed")
