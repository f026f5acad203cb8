"""What a sweep takes from the family of its ``[system] source``: the keys it may vary
and their units, the checks of their values, the run defaults, the metrics it may keep,
and where its points run.

Three families:

- the rocking cam-follower (a preset or system TOML): every chunk runs in the compiled
  batch kernel (:mod:`camdyn.sweeps.worker`), its metrics those of
  :mod:`camdyn.sweeps.metrics`;
- a mechanism file (:mod:`camdyn.sweeps.mechanism_spec`, :mod:`camdyn.sweeps.mechanism_run`);
- a model of the model protocol in a Python file, such as a user's own
  (:mod:`camdyn.sweeps.model_run`).

The last two run their points one after another in Python; the module that does so is
the family's ``runner``, and the sweep engine calls it through the same functions
(``prepare_chunk``, ``run_args``, ``run_chunk``, ``finish``, ``variables``,
``definitions``) whatever the family.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from camdyn.errors import CamdynError, ParameterError
from camdyn.params.config import (
    SCHEMA,
    convert_value,
    load_system,
    system_from_toml,
    system_to_toml,
    unknown_key_error,
)

__all__ = ["Family", "ROCKING_METRICS", "STATUS_OK", "STATUS_REFUSED", "STATUS_SOLVER", "chunk_task", "family_of",
           "finish", "metric_definitions", "result_variables"]

#: A point's status: run, refused before the run (its values make no model), or stopped
#: by the solver.
STATUS_OK, STATUS_REFUSED, STATUS_SOLVER = 0, 1, 2
#: metric name -> what it adds to the result of a sweep over the rocking cam-follower
ROCKING_METRICS = {
    "residual": "rms and peak-to-peak of the residual response alpha - alpha_rigid [rad]",
    "impacts": "impacts (contact onsets) per revolution [1/rev]",
    "poincare": "once-per-revolution samples of alpha [rad] and alpha_dot [rad/s]",
    "max_force": "largest normal contact force [N]",
    "regime": "contact kept / sliding reversal / periodic impacts / irregular impacts, and the "
              "Poincare period",
    "spectrum": "cam-harmonic amplitudes of alpha_ddot [rad/s^2] and the largest spectral peak",
}
#: run defaults over a mechanism: its metrics come from the sampled run, so it is sampled
#: finely enough to resolve an impact's contact and peak force (about 0.4 ms at the
#: chapter 3 rig's 16 Hz)
_MECHANISM_RUN = {"samples_per_revolution": 1024, "atol": 1e-11}


@dataclass(frozen=True)
class Family:
    """What a sweep spec takes from its source's family.

    Attributes
    ----------
    source : the source as the spec keeps it (absolute for a model file).
    text : the base point written out (TOML of the system or mechanism, or the model's
        parameter values): the digest's and the result's record of it.
    key_unit : ``key -> (SI unit, raw value -> SI value)``; refuses an unknown key.
    check_values : ``vary -> None``; refuses a value that makes no valid point.
    metrics : the metric names the family may keep, with their definitions.
    default_metrics : those kept when the spec names none.
    run_defaults : the ``[run]`` defaults that differ from the spec's own.
    kind : the mechanism kind (empty for the other families).
    runner : the module that runs the points in Python (empty: the compiled kernel).
    atol : whether ``[run] atol`` may be given.
    base : the base system of the rocking cam-follower (None for the others).
    speed_key : the key of the cam's speed [Hz], the axis of a bifurcation diagram (empty
        where the drive sets the speed: a cam under its drive).
    diagram_metrics : the metrics a bifurcation diagram keeps.
    """

    source: str
    text: str
    key_unit: Callable
    check_values: Callable
    metrics: dict
    default_metrics: tuple
    run_defaults: dict = field(default_factory=dict)
    kind: str = ""
    runner: str = ""
    atol: bool = True
    base: object = None
    speed_key: str = "motion.speed"
    diagram_metrics: tuple = ("poincare", "impacts", "regime", "residual", "max_force")


def family_of(source: str, overrides: dict, base_dir: Path) -> Family:
    """The family of a spec's ``[system] source`` (preset, system or mechanism TOML, or
    ``FILE.py:NAME``), with its base point built and checked."""
    from camdyn.params.mechanism import is_mechanism
    from camdyn.systems.model_files import is_model_reference

    if is_model_reference(source):
        from camdyn.sweeps import model_run
        source = model_run.absolute_source(source, base_dir)
        return Family(source=source, text=model_run.base_text(source, overrides),
                      key_unit=model_run.key_unit(source),
                      check_values=lambda vary: model_run.check_values(source, overrides, vary),
                      metrics=model_run.METRICS, default_metrics=tuple(model_run.METRICS),
                      run_defaults=model_run.RUN_DEFAULTS, runner="camdyn.sweeps.model_run",
                      speed_key=model_run.speed_key(source), diagram_metrics=("poincare", "events", "period"))
    if source.endswith(".toml") and not Path(source).is_absolute():
        source = str(base_dir / source)
    if is_mechanism(source):
        from camdyn.sweeps import mechanism_spec
        kind, text = mechanism_spec.base_mechanism(source, overrides)
        return Family(source=source, text=text, key_unit=mechanism_spec.key_unit,
                      check_values=lambda vary: mechanism_spec.check_values(source, overrides, vary),
                      metrics=mechanism_spec.MECHANISM_METRICS, default_metrics=mechanism_spec.KIND_METRICS[kind],
                      run_defaults=_MECHANISM_RUN, kind=kind, runner="camdyn.sweeps.mechanism_run", atol=False,
                      speed_key="" if mechanism_spec.drive_sets_speed(text) else "system.motion.speed",
                      diagram_metrics=("poincare", "impacts", "regime", "max_force"))
    text = system_to_toml(load_system(source, overrides))
    base = system_from_toml(text)
    return Family(source=source, text=text, key_unit=_rocking_key,
                  check_values=lambda vary: _check_rocking(base, vary),
                  metrics=ROCKING_METRICS, default_metrics=tuple(ROCKING_METRICS), base=base)


def _rocking_key(key: str) -> tuple[str, Callable]:
    """The SI unit of a rocking sweep's varied ``key`` and its raw-to-SI conversion."""
    if key not in SCHEMA:
        raise unknown_key_error(key)
    unit, _ = SCHEMA[key]
    if unit in ("str", "bool", "int", "law"):
        raise ParameterError(f"sweep spec: {key} cannot be swept (only quantities with units can)")
    return ("Hz" if unit == "speed" else unit), (lambda raw: float(convert_value(key, raw, {})))


def _check_rocking(base, vary) -> None:
    """Every value on its own must make a valid system (negative mass, unreachable cam,
    ...); only combinations of values may fail (those points are recorded as failed)."""
    from camdyn.simulation.runner import prepare
    from camdyn.sweeps.spec import checked_values

    for v in vary:
        for value in checked_values(v.values):
            try:
                prepare(base.with_values(**{v.key: value}))
            except CamdynError as exc:
                raise ParameterError(f"sweep spec: {v.key} = {value:g} {v.unit}: {exc}") from None


def _runner(spec):
    import importlib

    return importlib.import_module(spec.runner) if spec.runner else None


def result_variables(spec) -> dict:
    """name -> (extra dimensions, their sizes, dtype, units, long name) of each metric
    variable of the sweep's result."""
    runner = _runner(spec)
    if runner is not None:
        return runner.variables(spec)
    from camdyn.sweeps import metrics

    return metrics.variables(spec.metrics, spec.harmonics, spec.kept_revolutions)


def metric_definitions(spec) -> tuple[dict, dict]:
    """The definitions of the family's metrics and the result's extra global attributes
    that name what was swept (the mechanism kind, the model)."""
    runner = _runner(spec)
    return (ROCKING_METRICS, {}) if runner is None else runner.definitions(spec)


def chunk_task(spec, chunk: int):
    """``(function, arguments, preparation, finish)`` of one chunk run in Python by the
    family's runner, or None for the compiled kernel."""
    runner = _runner(spec)
    if runner is None:
        return None
    prepared = runner.prepare_chunk(spec, chunk)
    return runner.run_chunk, runner.run_args(spec, prepared), prepared, runner.finish


def finish(prepared: dict, result: dict) -> dict:
    """Merge a worker's result with the chunk's preparation: status and failure reason."""
    status = prepared["status"].copy()
    failure = list(prepared["failure"])
    solver = result.pop("solver_failure")
    for i in range(status.size):
        if status[i] == STATUS_OK and solver[i]:
            status[i] = STATUS_SOLVER
            failure[i] = str(solver[i])
    result["status"] = status
    result["failure"] = np.array(failure, dtype=str)
    return result
