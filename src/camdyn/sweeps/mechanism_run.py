"""What a worker runs for a sweep over a mechanism: each prepared point through
:func:`camdyn.io.mechanism_config.simulate_mechanism`, reduced to its metrics over the
kept window (:mod:`camdyn.sweeps.mechanism_metrics`).

The parent builds every point's mechanism (:func:`prepare_chunk`, which refuses a point
whose values do not make a mechanism); a worker receives the mechanisms themselves
(plain frozen dataclasses) and the run settings, so it reads no file.
"""

from __future__ import annotations

import numpy as np

from camdyn.errors import CamdynError
from camdyn.sweeps import mechanism_metrics as MM
from camdyn.sweeps.families import STATUS_OK, STATUS_REFUSED, STATUS_SOLVER, finish

__all__ = ["STATUS_OK", "STATUS_REFUSED", "STATUS_SOLVER", "prepare_chunk", "run_args", "run_chunk", "finish",
           "sample_rate", "variables", "definitions"]



def sample_rate(mechanism, samples: int) -> float:
    """Output sampling rate [Hz]: ``samples`` per period of the starting cam speed (the
    motion's speed [Hz], or a driven shaft's ``initial_speed`` [rad/s] over 2 pi)."""
    if mechanism.spec.initial_speed is not None:
        return samples * abs(mechanism.spec.initial_speed) / (2.0 * np.pi)
    return samples * abs(mechanism.system.motion.speed)


def prepare_chunk(spec, chunk: int) -> dict:
    """The mechanisms of chunk ``chunk`` (None where the point's values make none: the
    point is refused with its reason)."""
    from camdyn.sweeps.mechanism_spec import check_mechanism, point_mechanism

    start = chunk * spec.chunk
    n = min(start + spec.chunk, spec.points) - start
    mechanisms, status, failure = [], np.zeros(n, dtype=np.int8), [""] * n
    for i in range(n):
        try:
            mechanism = point_mechanism(spec.source, spec.overrides, spec.point_values(start + i))
            check_mechanism(mechanism)
        except (CamdynError, ValueError, ArithmeticError) as exc:
            mechanism = None
            status[i] = STATUS_REFUSED
            failure[i] = f"{type(exc).__name__}: {exc}"
        mechanisms.append(mechanism)
    return {"mechanisms": mechanisms, "status": status, "failure": failure}


def run_args(spec, prepared: dict) -> tuple:
    """Arguments of :func:`run_chunk` for a prepared chunk."""
    run = (spec.revolutions, spec.discard, spec.samples_per_revolution, spec.rtol, spec.harmonics)
    return prepared["mechanisms"], run, spec.mechanism, tuple(spec.metrics)


def run_chunk(mechanisms: list, run: tuple, kind: str, metrics) -> dict:
    """Simulate a chunk's mechanisms and reduce each run to its metrics.

    Parameters
    ----------
    mechanisms : list
        :class:`~camdyn.io.mechanism_config.Mechanism` per point, None for a refused one.
    run : tuple
        ``(revolutions, discard, samples_per_revolution, rtol, harmonics)``: periods of the
        starting cam speed simulated and discarded [-], samples per period [-], relative
        tolerance [-], cam harmonics kept by the ``spectrum`` metric [-].
    kind : str
        The mechanism kind.
    metrics : sequence of str
        The spec's metric names (:data:`camdyn.sweeps.mechanism_spec.MECHANISM_METRICS`).

    Returns
    -------
    dict
        The metric arrays (one row per point) plus ``solver_failure`` (the reason a run
        stopped, empty when it did not), ``accepted_steps``, ``rejected_steps`` and
        ``events``.
    """
    from camdyn.io.mechanism_config import simulate_mechanism

    revolutions, discard, samples, rtol, harmonics = run
    rows, failure = [], []
    counters = np.zeros((len(mechanisms), 3), dtype=np.int64)
    for i, mechanism in enumerate(mechanisms):
        row, reason = None, ""
        if mechanism is not None:
            try:
                ds = simulate_mechanism(mechanism, revolutions=revolutions,
                                        sample_rate=sample_rate(mechanism, samples), rtol=rtol)
                row = MM.point_metrics(ds, kind, metrics, revolutions, discard, samples, mechanism, harmonics)
                counters[i] = [ds.attrs["accepted_steps"], ds.attrs["rejected_steps"], ds.attrs["events"]]
            except CamdynError as exc:
                reason = f"{type(exc).__name__}: {exc}"
        rows.append(row)
        failure.append(reason)
    out = MM.stack(rows, kind, metrics, revolutions - discard, harmonics)
    out["solver_failure"] = np.array(failure, dtype=str)
    out["accepted_steps"] = counters[:, 0]
    out["rejected_steps"] = counters[:, 1]
    out["events"] = counters[:, 2]
    return out




def variables(spec) -> dict:
    """name -> (extra dimensions, their sizes, dtype, units, long name) of each result
    variable of a sweep over a mechanism."""
    return MM.variables(spec.mechanism, spec.metrics, spec.kept_revolutions, spec.harmonics)


def definitions(spec) -> tuple[dict, dict]:
    """The metric definitions and the result's extra global attributes."""
    from camdyn.sweeps.mechanism_spec import MECHANISM_METRICS

    return MECHANISM_METRICS, {"mechanism": spec.mechanism, "mechanism_source": str(spec.source)}
