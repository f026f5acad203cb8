"""Simulate a model described by the model protocol (:mod:`camdyn.systems.protocol`):
its own compiled driver (:mod:`camdyn.integrator.instances`), one xarray Dataset.

:func:`camdyn.simulate` sends a :class:`~camdyn.systems.protocol.BoundModel` here.
"""

from __future__ import annotations

import math
import time as _time

import numpy as np
import xarray as xr

from camdyn.errors import ParameterError
from camdyn.integrator import driver as bundled
from camdyn.integrator import instances
from camdyn.simulation import limits
from camdyn.simulation.datasets import dataset
from camdyn.systems.protocol import MODEL_ID, BoundModel, adapter_source

__all__ = ["simulate_model", "model_driver"]

#: Events a run's log has room for at first, per period (more are made room for).
_EVENTS_PER_PERIOD = 16


def model_driver(model):
    """The driver module compiled for ``model`` (a :class:`~camdyn.systems.protocol.Model`):
    compiled on its first use on a machine, loaded from camdyn's cache folder later."""
    return instances.instance(adapter_source(model), model.dependencies())


def _speed(bound: BoundModel, speed) -> tuple[BoundModel, float]:
    """The bound model with its speed parameter set, and the period [s] (infinite for a
    model without a speed)."""
    model = bound.model
    if model.speed is None:
        if speed is not None:
            raise ParameterError(f"model {model.name!r} has no speed parameter; leave speed out")
        return bound, math.inf
    if speed is not None:   # read as the speed parameter is (numbers in Hz, text with units)
        bound = bound.replace({model.speed: speed})
    hz = bound[model.speed]
    if not (math.isfinite(hz) and hz > 0.0):
        raise ParameterError(f"speed must be a positive number of Hz, got {hz!r}")
    return bound, 1.0 / hz


def simulate_model(bound: BoundModel, speed=None, revolutions: float = 10.0, duration: float | None = None,
                   sample_rate: float | None = None, rtol: float = 1e-8, atol: float = 1e-10, initial_state=None,
                   max_step: float | None = None, max_steps: int = 50_000_000) -> xr.Dataset:
    """Simulate a protocol model (see :func:`camdyn.simulate`, whose arguments these are).

    Parameters
    ----------
    bound : BoundModel
        The model with its parameters (``Model.bind``).
    speed : float or str, optional
        The model's speed parameter [Hz] or text such as ``"2400 rpm"``.
    revolutions : float
        Length of the run in periods (1 / speed) [-]; ignored when ``duration`` is given.
    duration : float, optional
        Length of the run [s]; needed for a model without a speed.
    sample_rate : float, optional
        Output sampling rate [Hz]; default 256 samples per period.
    rtol, atol : float
        Local error tolerances: relative [-] and absolute [the states' units].
    initial_state : sequence of float, optional
        The state at the start [the states' units]; default the model's state at rest.
    max_step : float, optional
        Largest step [s]; default ``model.max_step_fraction`` of the period.
    max_steps : int
        Largest number of accepted steps.

    Returns
    -------
    xarray.Dataset
        One variable per state and output channel over ``time`` [s], the mode slots at
        every sample (``mode_<name>``), and the event table over ``event``: ``event_time``
        [s], ``event_guard`` (the guard's name), ``event_sign`` (its new sign) and
        ``event_monitor`` (the largest monitored value since the event before).
    """
    if not isinstance(bound, BoundModel):
        raise ParameterError(f"expected a model with its parameters (Model.bind()), got {type(bound).__name__}")
    model = bound.model
    bound, period = _speed(bound, speed)
    if duration is None:
        if not math.isfinite(period):
            raise ParameterError(f"model {model.name!r} has no speed: give the run's duration [s]")
        revolutions = limits.check_number("revolutions", revolutions)
        duration = revolutions * period
    duration = limits.check_number("duration", duration, "s")
    if not (math.isfinite(duration) and duration > 0):
        raise ParameterError(f"duration must be positive, got {duration!r}")
    limits.check_tolerances(rtol, atol)
    if sample_rate is None:
        sample_rate = 256.0 / period if math.isfinite(period) else 256.0 / duration
    n_out = limits.check_sampling(limits.check_number("sample_rate", sample_rate, "Hz"), period, duration)
    channels = len(model.states) + len(model.outputs) + len(model.modes)
    limits.check_memory(limits.result_bytes(n_out, channels), "the simulation's result")
    scale = period if math.isfinite(period) else duration
    max_step, max_steps = limits.check_steps(model.max_step_fraction * scale if max_step is None else max_step,
                                             max_steps, duration)
    y0 = bound.initial_state() if initial_state is None else np.asarray(initial_state, dtype=float)
    if y0.shape != (len(model.states),) or not np.all(np.isfinite(y0)):
        raise ParameterError(f"initial_state must be {len(model.states)} finite numbers "
                             f"({', '.join(model.state_names)}), got {initial_state!r}")
    driver = model_driver(model)
    p = bound.p
    t_out = np.minimum(np.arange(n_out) / sample_rate, duration)
    start = _time.perf_counter()
    scan = float(model.max_step_fraction * scale)
    y, modes, events, counters = limits.with_room_for_events(
        lambda room: driver.integrate(MODEL_ID, p.copy(), y0.copy(), 0.0, float(duration), t_out, float(rtol),
                                      float(atol), float(max_step), 0, int(max_steps), room, True, scan),
        int(64 + _EVENTS_PER_PERIOD * duration / scale))
    elapsed = _time.perf_counter() - start
    limits.check_run(counters, f"the simulation of {model.name!r}")
    return _dataset(bound, driver, t_out, y, modes, events, counters, elapsed, period, rtol, atol)


def _dataset(bound, driver, t_out, y, modes, events, counters, elapsed, period, rtol, atol) -> xr.Dataset:
    model = bound.model
    data = {}
    for i, q in enumerate(model.states):
        data[q.name] = ("time", y[:, i], {"units": q.unit, "long_name": q.description or q.name})
    if model.outputs:
        out = np.full((t_out.shape[0], len(model.outputs)), np.nan)
        driver.systems.models.output_samples(t_out, y, modes, bound.p, out)
        for i, q in enumerate(model.outputs):
            data[q.name] = ("time", out[:, i], {"units": q.unit, "long_name": q.description or q.name})
    for i, name in enumerate(model.modes):
        data[f"mode_{name}"] = ("time", modes[:, i], {"units": "", "long_name": f"mode slot {name!r}"})
    guards = np.asarray(events[:, 1], dtype=int)
    data["event_time"] = ("event", events[:, 0], {"units": "s", "long_name": "time of the event"})
    data["event_guard"] = ("event", np.array([model.guards[k] for k in guards], dtype=object),
                           {"long_name": "the guard that crossed"})
    data["event_sign"] = ("event", events[:, 2], {"units": "", "long_name": "the guard's new sign"})
    data["event_monitor"] = ("event", events[:, 3],
                             {"units": "", "long_name": "largest monitored value since the event before"})
    attrs = {"model": model.name, "rtol": rtol, "atol": atol, "elapsed_s": elapsed,
             "steps": int(counters[bundled.COUNT_ACCEPTED]), "rejected_steps": int(counters[bundled.COUNT_REJECTED]),
             "rhs_calls": int(counters[bundled.COUNT_RHS])}
    if math.isfinite(period):
        attrs["speed_hz"] = 1.0 / period
    for q, value in zip(model.parameters, bound.values):
        attrs[f"parameter {q.name} [{q.unit}]"] = value
    return dataset(data, coords={"time": ("time", t_out, {"units": "s", "long_name": "time"})}, attrs=attrs)
