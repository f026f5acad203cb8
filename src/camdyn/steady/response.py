"""Frequency responses by harmonic balance: pseudo-arclength continuation of the
harmonic-balance orbit (:mod:`camdyn.steady.harmonic_balance`) in a problem's scalar
parameter, with Hill's multipliers at every point.

The unknowns are ``z = (X, lambda)``: the Fourier coefficients of the orbit and the
parameter, scaled as shooting's continuation scales them
(:func:`~camdyn.continuation.branches.continuation_scales`: every coefficient of a state
component by that component's scale, the parameter by its magnitude). On the curve
``R(X, lambda) = 0``, with the Jacobian ``[dR/dX, dR/dlambda]`` (``dR/dX`` exact,
``dR/dlambda`` by central differences). A step predicts along the unit tangent ``t``
(the null vector of that Jacobian, oriented along the previous one) and corrects by
Newton's method on ``R = 0`` with ``t . (z - z_predicted) = 0`` (Keller's pseudo-arclength
condition; Allgower & Georg 2003, ch. 2 and 6). The step control is shooting's
(:data:`~camdyn.continuation.branches.FAST_CORRECTIONS`,
:data:`~camdyn.continuation.branches.JUMP_DISTANCE`).

Test functions at every point, a sign change located by the secant method (Illinois
variant) along the arclength from the point before it (Seydel 2010, sec. 5.3):

* fold: the parameter component of the tangent;
* period doubling: ``prod(mu + 1)`` over Hill's multipliers (``det(M + I)``);
* Neimark-Sacker: ``prod_{i<j} (mu_i mu_j - 1)``;
* contact loss (the cam-follower): the smallest normal force over the orbit, unclipped
  (:func:`~camdyn.continuation.margins.contact_margins`). The cam-follower's orbits are
  balanced with the contact law unclipped (``contact.clip_adhesion`` off): identical to
  the physical orbit while ``min Fn >= 0`` and smooth through ``min Fn = 0``, so that the
  test function changes sign there; the curve ends at the located contact loss, past
  which the follower leaves the cam (shooting follows it).

A guard changing sign on an orbit (an impact of another model) ends the curve too.
With ``harmonics="auto"`` the harmonic count H doubles wherever the convergence measure
``tail`` exceeds its tolerance.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np

from camdyn.continuation.branches import (
    FAST_CORRECTIONS,
    JUMP_DISTANCE,
    MIN_STEP,
    Bifurcation,
    Branch,
    continuation_scales,
)
from camdyn.continuation.margins import contact_margins
from camdyn.continuation.orbits import STABILITY_MARGIN, Orbit
from camdyn.continuation.problem import Problem
from camdyn.errors import ParameterError, SimulationError
from camdyn.steady.harmonic_balance import (
    GridModel,
    HarmonicOrbit,
    harmonic_balance,
    harmonic_residual,
    hill_multipliers,
    resize,
    tail_measure,
)
from camdyn.systems.traits import contact_mode_slot, unclipped

__all__ = ["HarmonicBranch", "continue_harmonic", "harmonic_orbit_view"]

#: Most corrector iterations per step.
CORRECTIONS = 8
#: Relative step of the central difference ``dR/dlambda`` (of the parameter's scale) [-].
PARAMETER_STEP = 1e-6


@dataclass(frozen=True)
class HarmonicBranch:
    """A frequency-response curve by harmonic balance.

    Attributes
    ----------
    harmonic_orbits : list of HarmonicOrbit
        The accepted points (coefficients, grid samples, Hill's multipliers), in order.
    parameters : list of float
        The scalar parameter at each point [its unit].
    branch : Branch
        The same points as shooting's :class:`~camdyn.continuation.branches.Branch` of
        :class:`~camdyn.continuation.orbits.Orbit` (state at the phase ``t_start``,
        multipliers, ``force_minimum`` [N], ``sliding_minimum`` [m/s]; ``monodromy`` NaN),
        its located bifurcations and why it stopped: what the records, Dataset and figure
        of :mod:`camdyn.continuation.results` take.
    """

    harmonic_orbits: list
    parameters: list
    branch: Branch


def _unclipped(problem: Problem):
    """The map of the parameter vector to the one balanced: the cam-follower's contact law
    unclipped (smooth through ``min Fn = 0``); None for another model."""
    if unclipped(problem.system_id, problem.build(problem.value)[0]) is None:
        return None
    return lambda p: unclipped(problem.system_id, p)


def harmonic_orbit_view(problem: Problem, orbit: HarmonicOrbit, value: float, mode: np.ndarray) -> Orbit:
    """The harmonic-balance ``orbit`` at the parameter ``value`` [its unit] as shooting's
    :class:`~camdyn.continuation.orbits.Orbit`: its state at ``t_start``, Hill's
    multipliers, no impacts, the contact margins over its grid samples (``mode`` the hybrid
    mode there) and each unknown's largest magnitude over them; ``monodromy`` NaN and
    ``residual`` the frequency-domain residual's max-norm (unit of the state rates)."""
    p, period = problem.build(value)
    states = np.tile(problem.full_state(orbit.samples[0], value), (orbit.samples.shape[0], 1))
    states[:, :problem.unknowns] = orbit.samples
    closed = np.vstack([states, states[:1]])                       # the last sample is the first
    times = np.r_[orbit.times, orbit.times[0] + period]
    modes = np.tile(mode, (closed.shape[0], 1))
    slot = contact_mode_slot(problem.system_id)
    if slot is not None:
        modes[:, slot] = 1.0
    force, sliding = contact_margins(problem.system_id, p, times, closed, modes)
    u = problem.unknowns
    stable = bool(np.all(np.abs(orbit.multipliers) < 1.0 - STABILITY_MARGIN))
    return Orbit(orbit.samples[0].copy(), states[0], float(value), period, 1, orbit.multipliers, stable, 0,
                 orbit.iterations, orbit.residual, math.nan, np.full((u, u), math.nan), force, sliding,
                 np.max(np.abs(orbit.samples), axis=0), None, math.nan)


@dataclass
class _Point:
    z: np.ndarray
    tangent: np.ndarray
    harmonic: HarmonicOrbit
    orbit: Orbit
    iterations: int
    column: np.ndarray


class _Curve:
    """The scaled residual ``F(z)`` of the curve and its Jacobian at H harmonics."""

    def __init__(self, problem: Problem, harmonics: int, scales: np.ndarray, omega: float, tolerance: float):
        self.problem, self.harmonics, self.tolerance = problem, harmonics, tolerance
        self.u, self.parameters = problem.unknowns, _unclipped(problem)
        self.scales, self.omega = scales, omega                      # (u + 1,), [rad/s]
        self.mode = None

    def resized(self, harmonics: int) -> _Curve:
        return _Curve(self.problem, harmonics, self.scales, self.omega, self.tolerance)

    @property
    def columns(self) -> np.ndarray:
        """Scale of every entry of ``z`` (each coefficient its component's, the parameter's)."""
        return np.r_[np.repeat(self.scales[:-1], 2 * self.harmonics + 1), self.scales[-1]]

    def pack(self, x: np.ndarray, value: float) -> np.ndarray:
        return np.r_[x.ravel(), value] / self.columns

    def unpack(self, z: np.ndarray) -> tuple[np.ndarray, float]:
        w = z * self.columns
        return w[:-1].reshape(self.u, 2 * self.harmonics + 1), float(w[-1])

    def _rows(self) -> np.ndarray:
        return 1.0 / (self.omega * np.repeat(self.scales[:-1], 2 * self.harmonics + 1))

    def _residual(self, x: np.ndarray, value: float, jacobian: bool):
        return harmonic_residual(GridModel(self.problem, value, self.parameters), x, self.harmonics, jacobian)

    def column(self, z: np.ndarray, residual: np.ndarray | None = None) -> np.ndarray:
        """The scaled ``dF/dlambda`` at ``z``: by central differences, or by a forward
        difference from the ``residual`` R there when given."""
        x, value = self.unpack(z)
        h = PARAMETER_STEP * self.scales[-1]
        ahead = self._residual(x, value + h, False)[0]
        if residual is not None:
            return (ahead - residual) / h * self.columns[-1] * self._rows()
        behind = self._residual(x, value - h, False)[0]
        return (ahead - behind) / (2.0 * h) * self.columns[-1] * self._rows()

    def evaluate(self, z: np.ndarray, column: np.ndarray):
        """``(F, dF/dz, dR/dX)``: F the residual over ``w s_c`` per row, dF/dz with the
        parameter's ``column``."""
        x, value = self.unpack(z)
        residual, jac, times, samples, self.mode = self._residual(x, value, True)
        rows = self._rows()
        return residual * rows, np.hstack([jac * self.columns[:-1] * rows[:, None], column[:, None]]), jac

    def tangent(self, jacobian: np.ndarray, previous: np.ndarray) -> np.ndarray:
        """The unit null vector of ``jacobian`` oriented along ``previous``."""
        e = np.zeros(jacobian.shape[1])
        e[-1] = 1.0
        t = np.linalg.solve(np.vstack([jacobian, previous]), e)
        t /= np.linalg.norm(t)
        return t if float(t @ previous) >= 0.0 else -t

    def correct(self, guess: np.ndarray, direction: np.ndarray, anchor: np.ndarray, previous: np.ndarray,
                budget: int = CORRECTIONS, column: np.ndarray | None = None, hill: bool = True) -> _Point:
        """Newton on ``F(z) = 0`` and ``direction . (z - anchor) = 0`` from ``guess``, the
        parameter's column of the Jacobian from ``guess`` (or ``column``, the previous
        point's) kept; the point's tangent oriented along ``previous``; its multipliers NaN
        unless ``hill``."""
        z = guess.copy()
        column = self.column(z) if column is None else column
        for iteration in range(1, budget + 1):
            f, jz, jac = self.evaluate(z, column)
            step = np.linalg.solve(np.vstack([jz, direction]), -np.r_[f, direction @ (z - anchor)])
            if not np.all(np.isfinite(step)):
                break
            z = z + step
            if np.max(np.abs(step)) <= self.tolerance:
                return self.point(z, previous, iteration, jz, jac, hill)
        raise SimulationError("the harmonic-balance corrector did not converge")

    def point(self, z: np.ndarray, previous: np.ndarray, iterations: int, jz: np.ndarray, jac: np.ndarray,
              hill: bool = True) -> _Point:
        """The point at the converged ``z`` (``jz``, ``jac``: the Jacobians of its last
        Newton step): its tangent, Hill's
        multipliers, its residual at ``z`` (and the parameter's column by a forward
        difference from it), its Orbit view."""
        x, value = self.unpack(z)
        residual, _, times, samples, mode = self._residual(x, value, False)
        jz[:, -1] = self.column(z, residual)
        self.mode = mode
        period = self.problem.build(value)[1]
        nan = np.full(self.u, math.nan + 0j)
        exponents, multipliers = hill_multipliers(jac, self.u, period) if hill else (nan, nan)
        harmonic = HarmonicOrbit(x, times, samples, period, self.harmonics, float(np.max(np.abs(residual))),
                                 iterations, tail_measure(x, self.harmonics), multipliers, exponents)
        return _Point(z, self.tangent(jz, previous), harmonic,
                      harmonic_orbit_view(self.problem, harmonic, value, self.mode), iterations, jz[:, -1])


def _tests(point: _Point) -> dict[str, float]:
    mu = point.orbit.multipliers
    pairs = [mu[i] * mu[j] - 1.0 for i in range(mu.size) for j in range(i + 1, mu.size)]
    return {"fold": float(point.tangent[-1]), "period-doubling": float(np.prod(mu + 1.0).real),
            "neimark-sacker": float(np.prod(pairs).real) if pairs else 1.0,
            "contact-loss": point.orbit.force_minimum}


def _locate(curve: _Curve, a: _Point, b: _Point, kind: str) -> _Point | None:
    """The point between ``a`` and ``b`` where the test function ``kind`` is zero
    (:func:`_secant`). A contact loss's iterates skip Hill's eigenvalues, and the located
    point, corrected again at its parameter, gets them. A fold is not corrected at its
    parameter (there the orbit's Jacobian at a fixed parameter is singular: such a
    correction does not converge): it is the secant's last point, corrected on the plane
    across the tangent, so its iterates compute Hill's eigenvalues (each about 0.2 ms at
    H = 8)."""
    if kind != "contact-loss":
        return _secant(curve, a, b, kind, hill=True)
    c = _secant(curve, a, b, kind, hill=False)
    if c is None:
        return c
    axis = np.zeros(c.z.size)
    axis[-1] = 1.0
    return curve.correct(c.z, axis, c.z, c.tangent, column=c.column)


def _secant(curve: _Curve, a: _Point, b: _Point, kind: str, hill: bool, max_iterations: int = 30) -> _Point | None:
    """The secant (Illinois) on the arclength ``s`` from ``a`` along its tangent for the
    zero of the test function ``kind`` between ``a`` and ``b``, each iterate corrected on
    the plane ``t_a . (z - z_a - s t_a) = 0`` (multipliers only if ``hill``)."""
    fa, fb = _tests(a)[kind], _tests(b)[kind]
    sa, sb = 0.0, float(a.tangent @ (b.z - a.z))
    best, side = None, 0
    for _ in range(max_iterations):
        s = sb - fb * (sb - sa) / (fb - fa)
        try:
            c = curve.correct(a.z + s * a.tangent, a.tangent, a.z + s * a.tangent, a.tangent, column=a.column,
                              hill=hill)
        except SimulationError:
            return best
        best, fc = c, _tests(c)[kind]
        if abs(sb - sa) < 1e-12 or fc == 0.0 or abs(s - (sa if side < 0 else sb)) < 1e-13:
            return c
        if fc * fb < 0:
            sa, fa, side = sb, fb, 0
        else:
            fa, side = (fa * 0.5, side) if side == -1 else (fa, -1)
        sb, fb = s, fc
        if abs(fc) < 1e-12 * max(abs(fa), 1.0):
            return c
    return best


def _detect(curve: _Curve, a: _Point, b: _Point) -> tuple[list[Bifurcation], _Point | None]:
    """The bifurcations located between ``a`` and ``b``, and the contact-loss point (None
    where the smallest normal force keeps its sign)."""
    found, loss = [], None
    ta, tb = _tests(a), _tests(b)
    for kind in ("fold", "period-doubling", "neimark-sacker", "contact-loss"):
        if not (math.isfinite(ta[kind]) and math.isfinite(tb[kind])) or ta[kind] * tb[kind] >= 0:
            continue
        c = _locate(curve, a, b, kind)
        if c is None:
            continue
        mu = c.orbit.multipliers
        if kind == "period-doubling" and np.min(np.abs(mu + 1.0)) > 0.1:
            continue
        if kind == "neimark-sacker" and not np.any(np.abs(mu.imag) > 1e-8):
            continue                                          # a neutral saddle
        found.append(Bifurcation(kind, c.orbit.parameter, c.orbit))
        if kind == "contact-loss":
            loss = c
    found.sort(key=lambda item: abs(item.parameter - a.orbit.parameter))
    return found, loss


def _refined(curve: _Curve, point: _Point, auto: bool, tail_tolerance: float, max_harmonics: int):
    """Where ``auto`` and the point's ``tail`` exceeds ``tail_tolerance``: the curve at
    2H (up to ``max_harmonics``) and the point recomputed there at the same parameter."""
    while auto and point.harmonic.tail > tail_tolerance and 2 * curve.harmonics <= max_harmonics:
        old = curve.harmonics
        curve = curve.resized(2 * old)
        z = curve.pack(resize(point.harmonic.coefficients, 2 * old), point.orbit.parameter)
        tangent = np.r_[resize(point.tangent[:-1].reshape(curve.u, 2 * old + 1), 2 * old).ravel(), point.tangent[-1]]
        axis = np.zeros(z.size)
        axis[-1] = 1.0
        point = curve.correct(z, axis, z, tangent / np.linalg.norm(tangent), budget=2 * CORRECTIONS)
    return curve, point


def _check(step: float, min_step: float, max_step: float, max_points: int) -> None:
    if not (0 < min_step <= step <= max_step):
        raise ParameterError(f"steps must satisfy 0 < min_step <= step <= max_step, got {min_step}, {step}, "
                             f"{max_step}")
    if max_points < 2:
        raise ParameterError(f"max_points must be at least 2, got {max_points}")


def _start(problem: Problem, start: float, harmonics, guess, tolerance: float, direction: float,
           max_harmonics: int) -> tuple[_Curve, _Point, bool]:
    """The curve and its first point, its tangent along the parameter's ``direction``
    (+-1): the orbit at ``start`` by :func:`harmonic_balance` (the physical, clipped
    contact law: it refuses an orbit that leaves the cam)."""
    first = harmonic_balance(problem, harmonics, guess=guess, value=start, max_harmonics=max_harmonics)
    model = GridModel(problem, start)
    mode = model.mode(first.times[0], model.full_states(first.samples[:1])[0])
    view = harmonic_orbit_view(problem, first, start, mode)
    if view.force_minimum < 0.0:
        raise SimulationError(f"the follower leaves the cam on the orbit at {problem.name} = {start:.6g} "
                              f"(smallest normal force {view.force_minimum:.3g} N): harmonic balance needs "
                              "sustained contact; use shooting (camdyn continue without --method harmonic-balance)")
    curve = _Curve(problem, first.harmonics, continuation_scales(view), 2.0 * math.pi / first.period, tolerance)
    z = curve.pack(first.coefficients, start)
    axis = np.zeros(z.size)
    axis[-1] = 1.0                                              # the parameter fixed at start
    return curve, curve.correct(z, axis, z, axis * direction), harmonics == "auto"


def continue_harmonic(problem: Problem, start: float, stop: float, harmonics: int | str = "auto", guess=None,
                      step: float = 0.01, min_step: float = MIN_STEP, max_step: float = 0.1, max_points: int = 500,
                      tolerance: float = 1e-10, tail_tolerance: float = 1e-8, max_harmonics: int = 64,
                      progress=None) -> HarmonicBranch:
    """The frequency response of ``problem`` by harmonic balance: its orbit at the scalar
    parameter ``start`` continued towards ``stop`` [both in the parameter's unit].

    Parameters
    ----------
    harmonics : int or "auto"
        H; "auto": chosen at the start by :func:`harmonic_balance` and doubled along the
        curve wherever ``tail`` [-] exceeds ``tail_tolerance``, up to ``max_harmonics``.
    guess : array or None
        The first orbit's guess, as :func:`harmonic_balance` takes it.
    step, min_step, max_step : float
        First, smallest and largest arclength step in scaled units [-], as
        :func:`~camdyn.continuation.branches.continue_orbits` takes them.
    max_points : int
        Most points on the curve.
    tolerance : float
        The corrector's convergence on the scaled Newton step [-].
    progress : callable, optional
        Called with each accepted point's :class:`~camdyn.continuation.orbits.Orbit`.

    Returns
    -------
    HarmonicBranch
        Its ``branch.stopped`` says why it ended: the end of the range, the point budget,
        the step's underflow, a contact loss (located, the last point) or an impact.

    Raises
    ------
    SimulationError
        No orbit at ``start``, or one on which the follower leaves the cam.
    """
    _check(step, min_step, max_step, max_points)
    start, stop = float(start), float(stop)
    if not (math.isfinite(start) and math.isfinite(stop)) or start == stop:
        raise ParameterError(f"the range must be two different finite values, got {start} and {stop}")
    problem.build(stop)                                         # refuse an end value the problem cannot take
    problem = replace(problem, build=functools.lru_cache(maxsize=8)(problem.build))   # each value built once
    curve, point, auto = _start(problem, start, harmonics, guess, tolerance, 1.0 if stop > start else -1.0,
                                max_harmonics)
    curve, point = _refined(curve, point, auto, tail_tolerance, max_harmonics)
    points, bifurcations = [point], []
    if progress:
        progress(point.orbit)
    stopped = _march(curve, points, bifurcations, sorted((start, stop)), (step, min_step, max_step, max_points),
                     (auto, tail_tolerance, max_harmonics), progress)
    orbits = [p.orbit for p in points]
    return HarmonicBranch([p.harmonic for p in points], [o.parameter for o in orbits],
                          Branch(orbits, bifurcations, stopped))


def _march(curve: _Curve, points: list, bifurcations: list, bounds, steps, refine, progress) -> str:
    """Step along the curve from ``points[-1]``, appending points and bifurcations; the
    reason it ended."""
    (lo, hi), (ds, min_step, max_step, max_points), name = bounds, steps, curve.problem.name
    point, sp = points[-1], curve.scales[-1]
    while len(points) < max_points:
        edge = hi if point.tangent[-1] > 0 else lo
        landing = (point.z[-1] + ds * point.tangent[-1] - edge / sp) * point.tangent[-1] > 0 \
            and abs(point.tangent[-1]) > 1e-3
        if landing:
            ds = (edge / sp - point.z[-1]) / point.tangent[-1]
        guess = point.z + ds * point.tangent
        try:
            if landing:                                     # land on the edge: the parameter fixed there
                axis = np.zeros(guess.size)
                axis[-1] = 1.0
                anchor = np.zeros(guess.size)
                anchor[-1] = edge / sp
                new = curve.correct(guess, axis, anchor, point.tangent, column=point.column)
            else:
                new = curve.correct(guess, point.tangent, guess, point.tangent, column=point.column)
                if np.linalg.norm(new.z - guess) > JUMP_DISTANCE * ds:
                    raise SimulationError("the corrector left the curve")
        except (SimulationError, ParameterError, np.linalg.LinAlgError):
            ds *= 0.5
            if ds < min_step:
                return f"the step fell below {min_step:g} at {name} = {point.orbit.parameter:.9g}"
            continue
        found, loss = _detect(curve, point, new)
        if loss is not None:
            bifurcations.extend(b for b in found if abs(b.parameter - point.orbit.parameter)
                                <= abs(loss.orbit.parameter - point.orbit.parameter))
            points.append(loss)
            if progress:
                progress(loss.orbit)
            return (f"contact lost at {name} = {loss.orbit.parameter:.9g} (the smallest normal force is zero): past "
                    "it the follower leaves the cam; shooting follows it (camdyn continue without --method "
                    "harmonic-balance)")
        guards = GridModel(curve.problem, new.orbit.parameter).guard_changes(new.harmonic.times, new.harmonic.samples,
                                                                             curve.mode)
        if guards:
            return (f"guard(s) {guards} change sign on the orbit at {name} = {new.orbit.parameter:.9g} (an impact): "
                    "harmonic balance does not apply past it; use shooting")
        curve, new = _refined(curve, new, *refine)
        bifurcations.extend(found)
        points.append(new)
        if progress:
            progress(new.orbit)
        value = new.orbit.parameter
        if landing or not (lo - 1e-12 * sp <= value <= hi + 1e-12 * sp):
            return f"{name} reached the end of its range"
        point = new
        ds = min(ds * 1.5, max_step) if new.iterations <= FAST_CORRECTIONS else max(ds * 0.7, min_step)
    return f"{max_points} points computed"
