"""Coverage of a parameter range by branches of periodic orbits: where a branch ends inside
the range (a step underflow in a chattering accumulation, a non-smooth fold, a grazing),
the continuation restarts beyond it from the orbit that a short simulation settles on,
continues that orbit back towards the gap and on towards the range's end, and reports
every gap it leaves with what ended the branch before it.

The orbit's period at a restart is read from the simulation: after a transient, the
state is sampled once per forcing period (a stroboscopic Poincare section) and the period
is the smallest ``k`` for which every sample returns to itself after ``k`` periods
(:func:`response_period`). Where no period up to :data:`MAX_PERIOD` repeats (a chaotic
or a still-settling response), the restart moves on by one more jump.

Any family whose branches come from a :class:`~camdyn.continuation.problem.Problem`
(the cam-follower, the mechanisms held at a prescribed speed, a model of your own) is
covered alike: :func:`cover_range` takes the problem and the first branch.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from camdyn.continuation.branches import Branch, continue_orbits
from camdyn.continuation.orbits import Orbit, find_orbit, shoot, transient_state
from camdyn.continuation.problem import Problem
from camdyn.errors import CamdynError, ParameterError

__all__ = ["Coverage", "Gap", "MAX_PERIOD", "ROUNDS", "STALL_POINTS", "cover_range", "covered_branches",
           "coverage_summary", "gap_records", "response_period"]

#: Longest period, in forcing periods, that a restart looks for in its simulation [-].
MAX_PERIOD = 8
#: Scaled distance under which two Poincare samples are the same point [-]: each state
#: component by its largest magnitude over the samples (by no less than a tenth of the
#: largest component's). The period read is a start for Newton's method, which then
#: converges on the orbit itself: on the rigid-impact oscillator at W = 2.69, past its
#: doubling, 50 forcing periods from rest leave the period-2 samples 2.6e-4 apart (its
#: multipliers 0.51 per two periods), 200 periods 1e-11.
SAME_POINT = 1e-3
#: Rounds of ``transient`` forcing periods simulated at a restart before it gives up
#: reading a period [-].
ROUNDS = 3
#: Default jump past a branch's end to the next restart, as a fraction of the range [-].
JUMP_FRACTION = 0.02
#: The stall test of the branches a coverage traces
#: (:func:`~camdyn.continuation.ends.stall_end`): their last this many points [-].
STALL_POINTS = 15


@dataclass(frozen=True)
class Gap:
    """A part of the range that no branch covers.

    Attributes
    ----------
    start, stop : float
        Its ends [the parameter's unit], in the direction of the range.
    reason : str
        What ended the branch before it, and what the restarts inside it found.
    """

    start: float
    stop: float
    reason: str


@dataclass
class Coverage:
    """The branches that cover a range, in the order they were traced, and its gaps.

    Attributes
    ----------
    branches : list of Branch
        The first branch, then for each restart the branch continued back towards the
        gap (if it has more than its start) and the one continued on towards the end.
    gaps : list of Gap
        In the direction of the range.
    stopped : str
        Why the coverage ended: the range's end reached, or the time limit.
    """

    branches: list[Branch] = field(default_factory=list)
    gaps: list[Gap] = field(default_factory=list)
    stopped: str = ""


def _front(branch: Branch, direction: float) -> float:
    """The farthest parameter a branch reached in the range's direction [its unit]."""
    values = [o.parameter for o in branch.orbits]
    return max(values) if direction > 0 else min(values)


def response_period(problem: Problem, value: float, transient: int = 50,
                    max_period: int = MAX_PERIOD) -> tuple[int | None, np.ndarray]:
    """The period of the response a simulation settles on at the parameter ``value``.

    Parameters
    ----------
    problem : Problem
        The system and its parameter.
    value : float
        The parameter [its unit].
    transient : int
        Forcing periods simulated before the samples are taken [-], and again before
        each of up to :data:`ROUNDS` - 1 more tries when no period repeats.
    max_period : int
        Longest period looked for [forcing periods].

    Returns
    -------
    period : int or None
        The smallest ``k`` for which each of ``max_period`` stroboscopic samples returns
        to itself (to :data:`SAME_POINT`, scaled) after ``k`` forcing periods; None when
        none does.
    state : ndarray
        The unknowns at the last sample: a start for Newton's method.
    """
    state = transient_state(problem, transient, value)
    for round_ in range(ROUNDS):
        if round_:
            state = shoot(problem, state, value, transient)
        samples = [state]
        for _ in range(2 * max_period):
            samples.append(shoot(problem, samples[-1], value, 1))
        x = np.array(samples)
        state = x[-1]
        scale = np.max(np.abs(x), axis=0)
        scale = np.maximum(scale, max(0.1 * scale.max(), 1e-300))
        for k in range(1, max_period + 1):
            if np.all(np.abs(x[k:k + max_period] - x[:max_period]) / scale < SAME_POINT):
                return k, state
    return None, state


def _restart(problem: Problem, value: float, transient: int, segments: int) -> tuple[Orbit | None, str]:
    """The orbit a simulation settles on at ``value``, or None and why there is none."""
    unit = f" {problem.unit}" if problem.unit else ""
    try:
        k, state = response_period(problem, value, transient)
        if k is None:
            return None, (f"the response at {problem.name} = {value:.6g}{unit} repeats within no "
                          f"{MAX_PERIOD} forcing periods after {ROUNDS * transient}")
        return find_orbit(problem, start=state, value=value, periods=k, segments=segments), ""
    except CamdynError as exc:
        return None, f"no orbit at {problem.name} = {value:.6g}{unit}: {str(exc).splitlines()[0]}"


def cover_range(problem: Problem, first_branch: Branch, start: float, stop: float, step: float = 0.02,
                max_points: int = 200, transient: int = 50, jump: float | None = None,
                max_time: float = math.inf, progress: Callable[[Orbit], None] | None = None,
                phase: Callable[[str], None] | None = None, segments: int = 1) -> Coverage:
    """Carry a continuation over the whole range ``start``-``stop`` past where its first
    branch ended.

    Parameters
    ----------
    problem : Problem
        The problem the first branch was traced in.
    first_branch : Branch
        The branch from ``start`` (:func:`~camdyn.continuation.results.trace_branch`).
    start, stop : float
        The range [the parameter's unit].
    step : float
        First arclength step of each branch, scaled [-].
    max_points : int
        Most points per branch [-]: a branch that used them all ends the coverage (its
        budget, not the dynamics, ended it), with a gap to the range's end.
    transient : int
        Forcing periods simulated at each restart before its period is read [-].
    jump : float, optional
        Distance from a branch's end to the next restart [the parameter's unit]; default
        :data:`JUMP_FRACTION` of the range.
    max_time : float
        Wall-clock time after which no new branch is started [s] (a branch under way
        finishes, within ``max_points``).
    progress : callable, optional
        Called with each orbit found.
    phase : callable, optional
        Called with a line that says what the coverage does now.
    segments : int
        Shooting segments of the orbits found at restarts [-].

    Returns
    -------
    Coverage
    """
    if start == stop or not (math.isfinite(start) and math.isfinite(stop)):
        raise ParameterError(f"the range must be two different finite values, got {start} and {stop}")
    direction = 1.0 if stop > start else -1.0
    jump = abs(stop - start) * JUMP_FRACTION if jump is None else float(jump)
    if not (jump > 0 and math.isfinite(jump)):
        raise ParameterError(f"jump must be positive and finite, got {jump}")
    if not max_time > 0:
        raise ParameterError(f"max_time must be positive [s], got {max_time}")
    began = time.monotonic()
    cover = Coverage([first_branch])
    front, reason = _front(first_branch, direction), first_branch.stopped
    while (stop - front) * direction > 1e-9 * abs(stop - start):
        if len(cover.branches[-1].orbits) >= max_points:
            cover.gaps.append(Gap(front, stop, f"{reason}: the budget of {max_points} points per branch ran out"))
            cover.stopped = reason
            return cover
        if time.monotonic() - began > max_time:
            cover.gaps.append(Gap(front, stop, f"{reason}; the time limit of {max_time:g} s was reached"))
            cover.stopped = f"the time limit of {max_time:g} s was reached"
            return cover
        value, found = front, None
        while found is None and (stop - value) * direction > 0 and time.monotonic() - began <= max_time:
            value = value + direction * jump
            value = min(value, stop) if direction > 0 else max(value, stop)
            if phase:
                phase(f"a restart at {value:.6g} {problem.unit} past the end at {front:.6g}")
            found, why = _restart(problem, value, transient, segments)
            if found is None:
                reason = f"{reason}; {why}"
        if found is None:
            late = (stop - value) * direction > 0
            cover.gaps.append(Gap(front, stop, f"{reason}; the time limit of {max_time:g} s was reached" if late
                                  else reason))
            cover.stopped = f"the time limit of {max_time:g} s was reached" if late else ""
            break
        if progress:
            progress(found)
        back = continue_orbits(problem, found, front, step=step, max_step=max(step, 0.1), max_points=max_points,
                               progress=progress, stall=STALL_POINTS)
        resumed = _front(back, -direction)
        if (resumed - front) * direction > 0:
            cover.gaps.append(Gap(front, resumed, reason))
        if (stop - value) * direction <= 0:
            cover.branches.append(back)
            break
        if len(back.orbits) > 1:
            cover.branches.append(back)
        on = continue_orbits(problem, found, stop, step=step, max_step=max(step, 0.1), max_points=max_points,
                             progress=progress, stall=STALL_POINTS)
        cover.branches.append(on)
        front, reason = max(_front(on, direction) * direction, value * direction) * direction, on.stopped
    cover.stopped = cover.stopped or f"{problem.name} reached the end of its range"
    return cover


def covered_branches(problem: Problem, branch: Branch, start: float, stop: float, step: float, max_points: int,
                     transient: int, doublings: int, cover: bool = True, max_time: float = math.inf,
                     progress: Callable[[Orbit], None] | None = None, phase: Callable[[str], None] | None = None,
                     segments: int = 1) -> tuple[Coverage, list[Branch]]:
    """The coverage of ``start``-``stop`` from the first branch (:func:`cover_range`; the
    first branch alone without ``cover``) and every branch of the result: the covering
    ones, then those switched onto at their period doublings, ``doublings`` levels deep
    (:func:`~camdyn.continuation.results.switch_doublings`)."""
    from camdyn.continuation.results import switch_doublings

    coverage = Coverage([branch], [], branch.stopped)
    if cover:
        coverage = cover_range(problem, branch, start, stop, step, max_points, transient, max_time=max_time,
                               progress=progress, phase=phase, segments=segments)
    if phase and doublings:
        phase("the period-doubled branches")
    branches = list(coverage.branches)
    for covering in coverage.branches:
        branches += switch_doublings(problem, covering, stop, doublings, step, max_points, progress=progress,
                                     stall=STALL_POINTS if cover else 0)
    return coverage, branches


def coverage_summary(coverage: Coverage, branches: list[Branch]) -> dict:
    """The keys of ``camdyn continue``'s JSON summary that describe the coverage: orbits
    (``points``) and stable ones on the covering branches, why it ended (``stopped``), the
    counts of branches, covering branches and gaps."""
    covering = [o for b in coverage.branches for o in b.orbits]
    return {"points": len(covering), "stable_points": sum(o.stable for o in covering),
            "stopped": coverage.stopped, "branch_count": len(branches),
            "covering_branch_count": len(coverage.branches), "gap_count": len(coverage.gaps)}


def gap_records(coverage: Coverage) -> list[dict]:
    """The gaps as records: ``start``, ``stop`` [the parameter's unit], ``reason``."""
    return [{"start": g.start, "stop": g.stop, "reason": g.reason} for g in coverage.gaps]
