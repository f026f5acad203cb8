"""Checks a simulation request passes before any work or memory is spent on it.

A request is refused (:class:`~camdyn.errors.ParameterError`) when its tolerances are
meaningless, when the sample rate cannot resolve the cam's motion, or when its result
would not fit in the memory this machine has free; it is warned about
(:class:`LargeResultWarning`) when the result is large.
"""

from __future__ import annotations

import math
import os
import warnings

import numpy as np

from camdyn.errors import ParameterError, SimulationError
from camdyn.integrator import driver
from camdyn.params.system import System
from camdyn.systems import registry as systems

__all__ = ["LargeResultWarning", "check_number", "check_system", "check_tolerances", "check_sampling",
           "result_bytes", "available_memory", "check_memory", "event_room", "with_room_for_events",
           "RTOL_RANGE", "ATOL_RANGE", "MIN_SAMPLES_PER_PERIOD", "WARN_BYTES", "STEP_FRACTION",
           "SCAN_FRACTION", "LONG_STEP_MODELS", "step_limits", "MAX_STEPS", "check_steps", "check_request"]

#: Sensible relative tolerances [-]: tighter than 1e-14 is below double precision's
#: resolution of the state; looser than 1e-2 no longer resolves the contact.
RTOL_RANGE = (1e-14, 1e-2)
#: Sensible absolute tolerances on the angle and rate [rad, rad/s].
ATOL_RANGE = (1e-16, 1e-3)
#: Fewest output samples per cam period: four resolve the first cam harmonic without
#: aliasing onto the mean [-].
MIN_SAMPLES_PER_PERIOD = 4
#: Samples per period below which a warning says which harmonics are lost [-].
WARN_SAMPLES_PER_PERIOD = 64
#: Result size above which a warning names it [B].
WARN_BYTES = 500e6
#: The cam-follower's largest step, as a fraction of the cam period [-], chosen by
#: measurement (docs/integrator.md, *Long steps: the guard scan*): the longest of 1/4,
#: 1/8, 1/10, 1/12, 1/16 and 1/32 with which the error of the chapter 3 and chapter 4
#: rigs still falls at every rung of rtol from 1e-4 to 3e-11 (with 1/8 and 1/10 a loose
#: rung rose or stalled).
STEP_FRACTION = 1.0 / 12.0
#: The cam-follower's scan interval, as a fraction of the cam period [-]: the longest
#: interval whose guards one cubic checks (:mod:`camdyn.integrator.crossings`; longer
#: steps are scanned on their continuous extension), so that no contact is skipped in
#: free flight.
SCAN_FRACTION = 1.0 / 32.0
#: The models that step up to :data:`STEP_FRACTION` of the period (:func:`step_limits`).
LONG_STEP_MODELS = (systems.CAM_FOLLOWER, systems.DRIVEN_CAM, systems.FLEXIBLE_PIVOT, systems.TWO_FOLLOWERS,
                    systems.DRIVEN_CAM_ANGLE, systems.TWO_FOLLOWERS_ANGLE)
#: Bytes per output sample and channel at the peak of assembling the result: 8 for the
#: value and the temporaries (measured peak 9.6 B with tracemalloc for 1.65 million samples
#: of the chapter 3 rig), rounded up [B].
BYTES_PER_VALUE = 12
#: Most accepted steps a run may be given (``max_steps``) [-]: at the integrator's
#: fastest (about 10^7 steps a second) 10^12 steps are more than a day of stepping.
MAX_STEPS = 10 ** 12


class LargeResultWarning(UserWarning):
    """A result, or a sampling choice, that the user should know about before waiting."""


def step_limits(period: float, model: int = systems.CAM_FOLLOWER) -> tuple[float, float]:
    """The largest step [s] and scan interval [s] of a run of registered ``model``
    forced with period ``period`` [s]: :data:`STEP_FRACTION` and :data:`SCAN_FRACTION`
    of it for the cam-follower and the mechanisms built on its contact
    (:data:`LONG_STEP_MODELS`); for the other models (the oscillators that test the
    integrator, the translating follower, stick-slip), whose orbits and spectra were
    measured with steps of at most :data:`SCAN_FRACTION`, that fraction for both."""
    if model in LONG_STEP_MODELS:
        return period * STEP_FRACTION, period * SCAN_FRACTION
    return period * SCAN_FRACTION, period * SCAN_FRACTION


def check_number(name: str, value, unit: str = "") -> float:
    """``value`` as a float, or a ParameterError naming ``name`` when it is not a real number."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ParameterError(f"{name} must be a number{f' of {unit}' if unit else ''}, got {value!r}")
    return float(value)


def check_system(system) -> None:
    """Refuse anything but a :class:`~camdyn.params.system.System`."""
    if not isinstance(system, System):
        hint = (" (load it first: camdyn.load_system(" + repr(system) + "))") if isinstance(system, str) else ""
        raise ParameterError(f"expected a camdyn System, got {type(system).__name__}{hint}")


def check_tolerances(rtol: float, atol: float) -> None:
    """Refuse tolerances outside :data:`RTOL_RANGE` and :data:`ATOL_RANGE`."""
    for name, value, (low, high), unit in (("rtol", rtol, RTOL_RANGE, ""), ("atol", atol, ATOL_RANGE, " rad")):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and low <= value <= high):
            raise ParameterError(f"{name} = {value!r} is outside the sensible range {low:g} to {high:g}{unit}: "
                                 f"tighter is below double precision, looser does not resolve the contact")


def check_steps(max_step, max_steps, duration: float | None = None) -> tuple[float | None, int]:
    """Refuse, before any work, a largest step ``max_step`` [s] (``None``: the default)
    that is not a positive finite number of seconds, a step budget ``max_steps`` that is
    not a whole number from 1 to :data:`MAX_STEPS`, and a pair that cannot cover a run of
    ``duration`` [s] (it needs at least ``duration / max_step`` steps). Returns them as
    ``(float or None, int)``."""
    if max_step is not None:
        max_step = check_number("max_step", max_step, "s")
        if not (math.isfinite(max_step) and max_step > 0):
            raise ParameterError(f"max_step must be a positive, finite number of seconds, got {max_step!r}")
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) \
            or not 1 <= max_steps <= MAX_STEPS:
        raise ParameterError(f"max_steps must be a whole number from 1 to {MAX_STEPS:.0e}, got {max_steps!r}")
    max_steps = int(max_steps)
    if max_step is not None and duration is not None and math.isfinite(duration) \
            and duration / max_step > max_steps:
        raise ParameterError(f"max_step = {max_step:g} s needs at least {duration / max_step:.3g} steps over "
                             f"{duration:g} s, more than max_steps = {max_steps}; lengthen max_step or raise "
                             f"max_steps")
    return max_step, max_steps


def check_request(what: str, items: float, item_bytes: float, limit: float | None = None,
                  unit: str = "items") -> int:
    """Refuse, before anything is allocated, a request that implies ``items`` items
    (samples, grid points, resamples) of ``item_bytes`` bytes each: more than ``limit``
    items (when given), or more memory than is free (:func:`check_memory`, which also
    announces a large one). The message names the count, its size and the limit.
    Returns the count as an int."""
    items = float(items)
    if not (math.isfinite(items) and items >= 0):
        raise ParameterError(f"{what} implies {items!r} {unit}: not a size that can be computed")
    size = items * float(item_bytes)
    if limit is not None and items > limit:
        raise ParameterError(f"{what} implies {items:.3g} {unit} (about {_size_text(size)}); the limit is "
                             f"{limit:.3g} {unit}")
    free = available_memory()
    if free >= 0 and size > 0.8 * free:
        raise ParameterError(f"{what} implies {items:.3g} {unit} of {item_bytes:g} B, about {_size_text(size)}, "
                             f"but only {_size_text(free)} of memory are free (the limit is 80 % of it)")
    check_memory(int(size), what)
    return int(items)


def _size_text(size: float) -> str:
    """``size`` [B] as text in kB, MB, GB or TB."""
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if size >= scale:
            return f"{size / scale:.3g} {unit}"
    return f"{size:.0f} B"


def check_sampling(sample_rate: float, period: float, duration: float) -> int:
    """Refuse a sample rate that cannot resolve the cam's motion; return the sample count.

    Parameters
    ----------
    sample_rate : float
        Output sampling rate [Hz].
    period : float
        Cam period [s] (infinite for a cam at rest).
    duration : float
        Length of the run [s].
    """
    if not (isinstance(sample_rate, (int, float)) and math.isfinite(sample_rate) and sample_rate > 0):
        raise ParameterError(f"sample_rate must be a positive number of Hz, got {sample_rate!r}")
    if math.isfinite(period):
        per_period = sample_rate * period
        if per_period < MIN_SAMPLES_PER_PERIOD:
            raise ParameterError(
                f"a sample rate of {sample_rate:g} Hz gives {per_period:.3g} samples per cam period "
                f"({1 / period:g} Hz): at least {MIN_SAMPLES_PER_PERIOD} are needed to resolve the cam's first "
                f"harmonic; raise the sample rate above {MIN_SAMPLES_PER_PERIOD / period:g} Hz")
        if per_period < WARN_SAMPLES_PER_PERIOD:
            warnings.warn(f"{per_period:.3g} samples per cam period resolve cam harmonics only up to order "
                          f"{int(per_period // 2)}", LargeResultWarning, stacklevel=3)
    samples = duration * sample_rate
    if samples > 2 ** 62:
        raise ParameterError(f"{duration:g} s at {sample_rate:g} Hz is {samples:.3g} samples; that is not a run "
                             f"this machine can hold")
    return int(math.floor(samples + 1e-9)) + 1


def result_bytes(samples: int, channels: int) -> int:
    """Memory a result of ``samples`` samples of ``channels`` channels needs [B]."""
    return int(samples) * int(channels) * BYTES_PER_VALUE


def available_memory() -> int:
    """Memory available to new allocations [B] (Linux ``MemAvailable``; -1 if unknown)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return -1


def check_memory(needed: int, what: str) -> None:
    """Refuse a result that does not fit in the free memory; warn when it is large.

    Parameters
    ----------
    needed : int
        Estimated size [B].
    what : str
        What the memory is for, for the messages (e.g. "the simulation's result").
    """
    free = available_memory()
    if free >= 0 and needed > 0.8 * free:
        raise ParameterError(f"{what} needs about {needed / 1e9:.3g} GB but only {free / 1e9:.3g} GB of memory "
                             f"are free; shorten the run or lower the sample rate")
    if needed > WARN_BYTES:
        warnings.warn(f"{what} will take about {needed / 1e6:.0f} MB of memory", LargeResultWarning, stacklevel=3)


def check_run(counters, what: str) -> None:
    """Raise for a compiled run that did not end well: ``KeyboardInterrupt`` if it was
    interrupted, else :class:`SimulationError` ``"<what> <the driver's reason>"``."""
    status = int(counters[driver.COUNT_STATUS])
    if status == driver.STATUS_INTERRUPTED:
        raise KeyboardInterrupt
    if status != driver.STATUS_OK:
        raise SimulationError(f"{what} {driver.STATUS_MESSAGES[status]}")


def event_room(duration: float, period: float) -> int:
    """The events a run's log first has room for: 64 + 16 per cam period ``period`` [s]
    over ``duration`` [s] (a hundred periods' worth where the period is infinite);
    :func:`with_room_for_events` makes room for more where a run counts more."""
    return int(64 + 16 * (duration / period if math.isfinite(period) else 100))


def with_room_for_events(run, max_events: int):
    """``run(max_events)`` (a compiled run whose result ends with the driver's counters),
    again with room for every event it counted if its event log ran out of room: the
    driver applies an event past the log's room but does not log it, and the run is
    deterministic, so the second run takes the same steps and logs them all."""
    result = run(int(max_events))
    counters = result[-1]
    if int(counters[driver.COUNT_EVENTS_DROPPED]) > 0 and int(counters[driver.COUNT_STATUS]) == driver.STATUS_OK:
        result = run(int(counters[driver.COUNT_EVENTS]) + 16)
    return result
