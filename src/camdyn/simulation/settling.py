"""Whether a run has settled: its last cam period repeats one of the periods before it.

A run from rest at the edge of contact loss can take tens of revolutions to settle, and
its harmonics, extremes and impact counts then describe the transient: on the chapter 4
rig at 17 Hz (e/a = 0.1) the follower still bounces after 12 revolutions (37 impacts),
its last period 6.5 % of alpha's range away from the one before; after 40 revolutions
1.8e-6. :func:`check_settled` warns of such a run, with the steady-state solvers that
find the periodic response itself.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

__all__ = ["MAX_PERIOD", "REPEAT_TOLERANCE", "TransientWarning", "check_settled", "repeat"]

#: Longest period looked for, in cam periods [-].
MAX_PERIOD = 8
#: Largest difference between the last cam period and one ``k`` periods before it, as a
#: fraction of the signal's range over them, for the run to count as settled [-].
REPEAT_TOLERANCE = 1e-3


class TransientWarning(UserWarning):
    """The last cam periods of a run do not repeat: it has not settled (or never does)."""


def repeat(times: np.ndarray, values: np.ndarray, period: float,
           max_period: int = MAX_PERIOD) -> tuple[int | None, float]:
    """The smallest ``k`` for which the signal's last cam period repeats the one ``k``
    periods before it, and the smallest relative difference found.

    Parameters
    ----------
    times : ndarray
        Sample times, increasing [s].
    values : ndarray
        The signal at those times (a position: it is interpolated linearly in time).
    period : float
        The cam period [s].
    max_period : int
        Longest period looked for [cam periods].

    Returns
    -------
    k : int or None
        None when no ``k`` up to ``max_period`` (and up to the whole periods before the
        last) repeats within :data:`REPEAT_TOLERANCE`, or the run is shorter than two
        periods.
    difference : float
        The smallest largest difference over the last period, as a fraction of the
        signal's range over the periods compared [-] (nan when nothing was compared).
    """
    end = float(times[-1])
    whole = int(math.floor((end - float(times[0])) / period + 1e-9))
    last = times >= end - period
    t, x = times[last], values[last]
    best = math.nan
    for k in range(1, min(max_period, whole - 1) + 1):
        earlier = np.interp(t - k * period, times, values)
        span = float(np.ptp(values[times >= end - (k + 1) * period]))
        if span == 0.0:
            return k, 0.0
        difference = float(np.max(np.abs(x - earlier))) / span
        best = difference if math.isnan(best) else min(best, difference)
        if difference < REPEAT_TOLERANCE:
            return k, difference
    return None, best


def check_settled(times: np.ndarray, values: np.ndarray, period: float, name: str, stacklevel: int = 3) -> None:
    """Warn (:class:`TransientWarning`) when the last cam period of the signal ``name``
    repeats none of the :data:`MAX_PERIOD` before it (:func:`repeat`); nothing for a cam
    at rest or a run shorter than ``MAX_PERIOD + 1`` cam periods, too short to tell a
    transient from an orbit of a longer period (a period-4 orbit simulated over its 4
    cam periods)."""
    if not (math.isfinite(period) and period > 0) or times.size < 3 \
            or times[-1] - times[0] < (MAX_PERIOD + 1) * period * (1 - 1e-9):
        return
    k, difference = repeat(times, values, period)
    if k is None and math.isfinite(difference):
        warnings.warn(f"the run has not settled: its last cam period repeats none of the {MAX_PERIOD} before it "
                      f"(in {name}, the closest differs by {100 * difference:.2g} % of its range); its harmonics "
                      "and extremes describe a transient, or a motion that is not periodic. Run longer, or find "
                      "the periodic response with camdyn.continuation.find_orbit or "
                      "camdyn.steady.harmonic_balance", TransientWarning, stacklevel=stacklevel)
