"""Sweeps over a model of the model protocol (:mod:`camdyn.systems.protocol`), such as a
model a user wrote in a file of their own.

A sweep is over such a model when its ``[system] source`` names the model's file,
``"valve_train.py:VALVE_TRAIN"`` (:mod:`camdyn.systems.model_files`; a relative path is
read from the spec's folder). Its ``set`` and ``[[vary]]`` keys are the model's parameter
names, with values as numbers in the parameter's SI unit or as text with units. The model
must have a speed parameter: a point runs ``revolutions`` periods of its speed through
:func:`camdyn.simulate` and keeps the metrics of :data:`METRICS` over the periods after
``discard``.

Each worker process loads the model from its file (same machine, or a shared folder on a
cluster) and its compiled driver from camdyn's cache, so the file is read, not pickled.
"""

from __future__ import annotations

import difflib
import hashlib
from pathlib import Path

import numpy as np

from camdyn.errors import CamdynError, ParameterError, UnknownKeyError
from camdyn.sweeps.families import STATUS_OK, STATUS_REFUSED, STATUS_SOLVER, finish
from camdyn.sweeps.metrics import poincare_period

__all__ = ["METRICS", "RUN_DEFAULTS", "STATUS_OK", "STATUS_REFUSED", "STATUS_SOLVER", "absolute_source",
           "base_text", "check_values", "definitions", "finish", "key_unit", "prepare_chunk", "run_args",
           "run_chunk", "speed_key", "variables"]


#: metric name -> what it adds to the result of a sweep over a protocol model
METRICS = {
    "events": "crossings of each guard, both ways, per period of the speed over the kept window "
              "(events_<guard>) [1/rev]",
    "poincare": "each state once per period, at the start of every kept period (poincare_<state>) "
                "[the state's unit]",
    "extremes": "largest and smallest sample of each state and output channel over the kept window "
                "(max_<name>, min_<name>) [the channel's unit]",
    "period": "the Poincare period: the smallest k <= 16 with every state's section repeating after k periods "
              "to 1e-3 of its peak-to-peak (0: none)",
}
#: run defaults over a protocol model (``simulate``'s tolerances)
RUN_DEFAULTS = {"rtol": 1e-8, "atol": 1e-10}


def _model(source: str):
    from camdyn.systems.model_files import load_model

    return load_model(source)


def speed_key(source: str) -> str:
    """The model's speed parameter [Hz] (empty if it names none)."""
    return _model(source).speed or ""


def absolute_source(source: str, base_dir: Path) -> str:
    """``source`` with its file made absolute (relative to the spec's folder), and the
    model's name written out."""
    from camdyn.systems.model_files import load_model, model_reference

    path, _, name = source.rpartition(":") if not source.endswith(".py") else (source, "", "")
    if not Path(path).is_absolute():
        path = str((Path(base_dir) / path).resolve())
    model = load_model(f"{path}:{name}" if name else path)
    if model.speed is None:
        raise ParameterError(f"sweep spec: model {model.name!r} has no speed parameter; a sweep runs whole "
                             "periods of the speed")
    return model_reference(model)


def key_unit(source: str):
    """The function ``key -> (SI unit, raw -> SI value)`` of the model's parameters."""
    from camdyn.systems.protocol import read_value

    model = _model(source)
    quantities = {q.name: q for q in model.parameters}

    def convert_of(key: str):
        if key not in quantities:
            close = difflib.get_close_matches(key, list(quantities), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else f"; its parameters: {', '.join(quantities)}"
            raise UnknownKeyError(f"sweep spec: model {model.name!r} has no parameter {key!r}{hint}")
        q = quantities[key]
        return q.unit, (lambda raw: read_value(raw, q))
    return convert_of


def base_text(source: str, overrides: dict) -> str:
    """The base point written out: the model's reference, the SHA-256 of its file (a
    changed file changes the sweep's digest) and every parameter's value [SI unit]."""
    model = _model(source)
    bound = model.bind(overrides)
    file = Path(source.rpartition(":")[0])
    lines = [f"model = {source!r}", f"file_sha256 = {hashlib.sha256(file.read_bytes()).hexdigest()!r}"]
    lines += [f"{q.name!r} = {value!r}   # [{q.unit}]" for q, value in zip(model.parameters, bound.values)]
    return "\n".join(lines) + "\n"


def check_values(source: str, overrides: dict, vary) -> None:
    """Each checked value of each varied key must make a model with a positive speed and
    a state at rest (only combinations of values may fail)."""
    from camdyn.sweeps.spec import checked_values

    base = _model(source).bind(overrides)
    for v in vary:
        for value in checked_values(v.values):
            try:
                _ready(base.replace({v.key: value}))
            except CamdynError as exc:
                raise ParameterError(f"sweep spec: {v.key} = {value:g} {v.unit}: {exc}") from None


def _ready(bound):
    speed = bound[bound.model.speed]
    if not (np.isfinite(speed) and speed > 0.0):
        raise ParameterError(f"the speed {bound.model.speed} must be positive, got {speed!r} Hz")
    bound.initial_state()
    return bound


def prepare_chunk(spec, chunk: int) -> dict:
    """Each point's parameter values (None where they make no model: refused with the
    reason)."""
    start = chunk * spec.chunk
    n = min(start + spec.chunk, spec.points) - start
    base = _model(spec.source).bind(spec.overrides)
    points, status, failure = [], np.zeros(n, dtype=np.int8), [""] * n
    for i in range(n):
        try:
            values = dict(zip(base.model.parameter_names, _ready(base.replace(spec.point_values(start + i))).values))
        except (CamdynError, ValueError, ArithmeticError) as exc:
            values = None
            status[i] = STATUS_REFUSED
            failure[i] = f"{type(exc).__name__}: {exc}"
        points.append(values)
    return {"points": points, "status": status, "failure": failure}


def run_args(spec, prepared: dict) -> tuple:
    """Arguments of :func:`run_chunk` for a prepared chunk (plain values only)."""
    run = (spec.revolutions, spec.discard, spec.samples_per_revolution, spec.rtol, spec.atol)
    return spec.source, prepared["points"], run, tuple(spec.metrics)


def run_chunk(source: str, points: list, run: tuple, metrics) -> dict:
    """Simulate a chunk's points and reduce each run to its metrics.

    Parameters
    ----------
    source : str
        The model's ``"FILE.py:NAME"``.
    points : list
        Per point, parameter name -> value [SI unit], or None for a refused point.
    run : tuple
        ``(revolutions, discard, samples_per_revolution, rtol, atol)``: periods simulated
        and discarded [-], samples per period [-], local error tolerances [-], [the
        states' units].
    metrics : sequence of str
        Names of :data:`METRICS`.

    Returns
    -------
    dict
        One array per result variable (:func:`variables`), plus ``solver_failure``,
        ``accepted_steps``, ``rejected_steps`` and ``events``.
    """
    from camdyn.simulation.models import simulate_model

    model = _model(source)
    revolutions, discard, samples, rtol, atol = run
    layout = _variables(model, metrics, revolutions - discard)
    out = {name: np.full((len(points),) + sizes, np.nan if dtype == "f8" else 0, dtype=dtype)
           for name, (_, sizes, dtype, _, _) in layout.items()}
    failure = [""] * len(points)
    counters = np.zeros((len(points), 3), dtype=np.int64)
    for i, values in enumerate(points):
        if values is None:
            continue
        try:
            bound = model.bind(values)
            ds = simulate_model(bound, revolutions=revolutions, sample_rate=samples * bound[model.speed],
                                rtol=rtol, atol=atol)
        except CamdynError as exc:
            failure[i] = f"{type(exc).__name__}: {exc}"
            continue
        for name, value in _point_metrics(model, ds, metrics, discard, revolutions - discard, samples).items():
            out[name][i] = value
        counters[i] = [ds.attrs["steps"], ds.attrs["rejected_steps"], ds.sizes["event"]]
    out["solver_failure"] = np.array(failure, dtype=str)
    out["accepted_steps"], out["rejected_steps"], out["events"] = counters.T
    return out


def _point_metrics(model, ds, metrics, discard: int, kept: int, samples: int) -> dict:
    """One point's metrics over its kept periods (after ``discard``), from its run ``ds``
    sampled ``samples`` times per period."""
    period = 1.0 / ds.attrs["speed_hz"]
    first = discard * samples
    row = {}
    if "events" in metrics:
        late = ds["event_time"].values >= discard * period * (1.0 - 1e-12)
        guards = ds["event_guard"].values
        for name in model.guards:
            row[f"events_{name}"] = np.count_nonzero(late & (guards == name)) / kept
    states = np.stack([ds[q.name].values for q in model.states], axis=1)
    section = states[first:first + kept * samples:samples][:kept]
    if "poincare" in metrics:
        for j, q in enumerate(model.states):
            row[f"poincare_{q.name}"] = section[:, j]
    if "extremes" in metrics:
        for q in (*model.states, *model.outputs):
            window = ds[q.name].values[first:]
            row[f"max_{q.name}"], row[f"min_{q.name}"] = np.max(window), np.min(window)
    if "period" in metrics:
        scale = np.ptp(states[first:], axis=0) + 1e-15
        row["period"] = poincare_period(section[None], scale[None])[0]
    return row




def _variables(model, metrics, kept: int) -> dict:
    out = {}
    if "events" in metrics:
        for name in model.guards:
            out[f"events_{name}"] = ((), (), "f8", "1/rev", f"crossings of the guard {name!r} per period")
    if "poincare" in metrics:
        for q in model.states:
            out[f"poincare_{q.name}"] = (("revolution",), (kept,), "f8", q.unit,
                                         f"{q.description or q.name} once per period")
    if "extremes" in metrics:
        for q in (*model.states, *model.outputs):
            for side in ("max", "min"):
                out[f"{side}_{q.name}"] = ((), (), "f8", q.unit, f"{side} of {q.description or q.name}")
    if "period" in metrics:
        out["period"] = ((), (), "i2", "rev", "Poincare period (0: none up to 16)")
    return out


def variables(spec) -> dict:
    """name -> (extra dimensions, their sizes, dtype, units, long name) of each result
    variable of a sweep over a protocol model."""
    return _variables(_model(spec.source), spec.metrics, spec.kept_revolutions)


def definitions(spec) -> tuple[dict, dict]:
    """The metric definitions and the result's extra global attributes."""
    return METRICS, {"model": _model(spec.source).name, "model_source": spec.source}
