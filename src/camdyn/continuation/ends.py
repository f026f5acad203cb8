"""The ends of a branch of periodic orbits where the corrector fails next to a loss of
contact or a grazing: the bifurcation placed at the zero of the secant through the last
two points' contact margin (the smallest normal force, the smallest guard value), as
``(kind, parameter, orbit)``; the check that refuses a step over both at once; and the
tests that end a branch before its steps fail: a period-``2k`` branch back at its
period-``k`` orbit (:func:`half_distance`), a branch that stalls (:func:`stall_end`)."""

from __future__ import annotations

import math

import numpy as np

from camdyn.continuation.orbits import Orbit, shoot
from camdyn.continuation.problem import Problem

__all__ = ["END_FRACTION", "STALL_FRACTION", "contact_loss_end", "flight_grazing_end", "grazing_end",
           "half_distance", "jumped_off_contact", "stall_end"]

#: A branch that ends with its last orbit's contact margin (the smallest guard value, the
#: smallest normal force) below this fraction of the margin's largest along the branch
#: ends at that margin's zero [-].
END_FRACTION = 1e-3
#: A branch whose last ``stall`` points lie within this fraction of its range in the
#: parameter has stalled: it winds through a chattering accumulation or a cascade of
#: folds (on the chapter 3 rig the branch from 5 Hz spent 60 of its 75 points and 16 of
#: its 18 s of CPU time within 6.903-6.915 Hz, past its loss of contact at 6.90709 Hz) [-].
STALL_FRACTION = 2e-3


def half_distance(problem: Problem, orbit: Orbit, scales: np.ndarray) -> float:
    """Scaled distance (``scales``: the continuation's, of the state then the parameter)
    between a period-``2k`` orbit's state and its state after ``k`` forcing periods: it
    falls to zero where the branch meets the period-``k`` orbit at that orbit's period
    doubling, a branch point of the period-``2k`` problem (there ``M^2 - I`` of the
    period-``k`` orbit is singular), where the continuation would creep (on the chapter 3
    rig the period-4 branch from 20.7 Hz spent 200 of its 300 points within 1e-6 Hz of the
    period-2 branch's doubling at 20.41352 Hz)."""
    half = shoot(problem, orbit.state, orbit.parameter, orbit.periods // 2)
    return float(np.linalg.norm((half - orbit.state) / scales[:-1]))


def stall_end(orbits: list[Orbit], stall: int, span: float, problem: Problem) -> str:
    """Why a branch ends if its last ``stall`` points lie within :data:`STALL_FRACTION`
    of its range ``span`` [the parameter's unit] (the coverage of a range restarts past
    it, :mod:`~camdyn.continuation.coverage`), or an empty string (always for ``stall``
    0)."""
    if not stall or len(orbits) < stall:
        return ""
    recent = [o.parameter for o in orbits[-stall:]]
    if max(recent) - min(recent) >= STALL_FRACTION * span:
        return ""
    unit = f" {problem.unit}" if problem.unit else ""
    return (f"the branch stalled: its last {stall} points lie within {max(recent) - min(recent):.3g}{unit} of "
            f"{problem.name} = {recent[-1]:.9g}{unit} (a chattering accumulation or a cascade of folds)")


def grazing_end(orbits: list[Orbit]) -> list[tuple[str, float, Orbit]]:
    """A branch that ends because its orbit touches the contact guard (the smallest guard
    value has fallen to a thousandth of its largest along the branch): a grazing
    bifurcation at the parameter where the secant through the last two points' smallest
    guard values reaches zero. Past it the orbit gains an impact whose monodromy grows as
    the inverse of the impact velocity (Di Bernardo et al. 2008, sec. 8.2), so the branch
    cannot be continued through it."""
    if len(orbits) < 2:
        return []
    a, b = orbits[-2], orbits[-1]
    largest = max(abs(o.guard_minimum) for o in orbits)
    if not (0 <= b.guard_minimum < END_FRACTION * largest and a.guard_minimum > b.guard_minimum):
        return []
    slope = (b.guard_minimum - a.guard_minimum) / (b.parameter - a.parameter)
    return [("grazing", b.parameter - b.guard_minimum / slope, b)]


def contact_loss_end(orbits: list[Orbit]) -> list[tuple[str, float, Orbit]]:
    """A cam-follower branch that ends (the corrector fails) just before its smallest
    normal force reaches zero: a contact loss at the zero of the secant through the last
    two points' ``min Fn``, if it lies within the last step beyond the end or the last
    ``min Fn`` has fallen below ``END_FRACTION`` of its largest along the branch. (Where
    the orbit must jump to an impacting motion as the contact opens, as on the chapter 3
    rig, no corrected point exists past it, and the halved steps before the end can be
    shorter than the distance left to the zero: from 5 Hz the last step was 9.1e-6 Hz,
    the zero 1.6e-5 Hz beyond it, and the contact loss went unreported.)"""
    return _secant_end("contact-loss", orbits, [o.force_minimum for o in orbits])


def flight_grazing_end(orbits: list[Orbit]) -> list[tuple[str, float, Orbit]]:
    """A cam-follower branch that ends (the corrector fails) as the follower's closest
    approach to the cam in flight closes (:func:`~camdyn.continuation.margins.flight_margin`):
    a grazing at the zero of the secant through the last two points' smallest gaps, on
    the rule of :func:`contact_loss_end`. (The chapter 3 rig's period-5 branch from 9.0 Hz
    ends so at 9.00712 Hz: the gap of its closest approach, 6.3e-6 m at 9.0071 Hz and
    5.8e-7 m at 9.00712 Hz, falls linearly to zero at 9.007122 Hz, where a new contact
    appears and no corrected point is found past it.)"""
    return _secant_end("grazing", orbits, [o.flight_margin for o in orbits])


def _secant_end(kind: str, orbits: list[Orbit], margins: list[float]) -> list[tuple[str, float, Orbit]]:
    """``(kind, zero, last orbit)`` where the secant through the last two ``margins``
    (falling, still positive) reaches zero within the last step beyond the end, or
    anywhere once the last margin is below ``END_FRACTION`` of the largest."""
    if len(orbits) < 2:
        return []
    (a, b), (ma, mb) = orbits[-2:], margins[-2:]
    if not (math.isfinite(ma) and ma > mb > 0):
        return []
    zero = b.parameter - mb * (b.parameter - a.parameter) / (mb - ma)
    largest = max(m for m in margins if math.isfinite(m))
    if abs(zero - b.parameter) > abs(b.parameter - a.parameter) and not mb < END_FRACTION * largest:
        return []
    return [(kind, zero, b)]


def jumped_off_contact(last: Orbit, new: Orbit) -> bool:
    """Whether a step went from a cam-follower orbit in contact (no impact, smallest
    unclipped normal force above zero) straight to an impacting orbit: past a loss of
    contact the force's zero comes first, the first impact later, at a grazing (chapter 3
    rig: 6.9070915 and 6.9071053 Hz), and a step over both was bisected across them, up
    to 4e-3 Hz early; shorter steps pass them one at a time."""
    return (last.impacts_per_period == 0 and new.impacts_per_period > 0
            and math.isfinite(last.force_minimum) and last.force_minimum > 0)
