"""Parameter sweeps: a spec (TOML), a batched compiled kernel, local or Dask execution,
checkpoints, and the result as an xarray Dataset over the swept dimensions.

>>> from camdyn.sweeps import load_spec, run_sweep
>>> ds = run_sweep(load_spec("bifurcation.toml"))          # doctest: +SKIP

The names below are loaded on first use, so that a worker process, which imports only
:mod:`camdyn.sweeps.worker`, starts without xarray, pint or SciPy's optimizers.
"""

_EXECUTION = ("compute_chunk", "default_workers", "run_sweep")
_SPEC = ("METRICS", "SweepSpec", "Vary", "load_spec", "spec_from_dict")

__all__ = [*_SPEC, "run_sweep", "compute_chunk", "default_workers"]


def __getattr__(name):
    from camdyn.interrupts import deferred

    with deferred():   # a Ctrl-C waits for the import's end (camdyn.interrupts)
        if name in _EXECUTION:
            from camdyn.sweeps import execution
            return getattr(execution, name)
        if name in _SPEC:
            from camdyn.sweeps import spec
            return getattr(spec, name)
    raise AttributeError(name)
