"""Parameter sweeps: a spec (TOML), a batched compiled kernel, local or Dask execution,
checkpoints, and the result as an xarray Dataset over the swept dimensions.

>>> from camdyn.sweeps import load_spec, run_sweep
>>> ds = run_sweep(load_spec("bifurcation.toml"))          # doctest: +SKIP
"""

from camdyn.sweeps.execution import compute_chunk, default_workers, run_sweep
from camdyn.sweeps.spec import METRICS, SweepSpec, Vary, load_spec, spec_from_dict

__all__ = ["METRICS", "SweepSpec", "Vary", "load_spec", "spec_from_dict", "run_sweep", "compute_chunk",
           "default_workers"]
