"""Datasets of simulation runs built from NumPy arrays, without xarray's duck-array checks.

xarray checks every new variable's data against the duck-array types of the libraries it
knows; with dask installed (camdyn's sweeps need it) that check imports ``dask.array``,
about 0.3 s of a new process's first simulation (and more at its exit) that a run which
holds only NumPy arrays does not need. Variables of numeric NumPy arrays are therefore
made as they are (``xarray.Variable(..., fastpath=True)``, the path xarray itself takes
for data it has checked); any other data goes through xarray's checks as usual.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

__all__ = ["dataset"]


def _variable(spec):
    """An ``xarray.Variable`` of ``spec`` = ``(dims, data, attrs)``, as it is when ``data``
    is a numeric NumPy array; otherwise ``spec`` unchanged, for xarray to check."""
    dims, data, *attrs = spec
    if type(data) is np.ndarray and data.dtype.kind in "biuf":   # not a subclass (masked)
        dims = (dims,) if isinstance(dims, str) else tuple(dims)
        return xr.Variable(dims, data, attrs[0] if attrs else None, fastpath=True)
    return spec


def dataset(data: dict, coords: dict, attrs: dict | None = None) -> xr.Dataset:
    """``xarray.Dataset(data, coords, attrs)`` for variables and coordinates given as
    ``(dims, data, attrs)`` tuples."""
    return xr.Dataset({name: _variable(spec) for name, spec in data.items()},
                      coords={name: _variable(spec) for name, spec in coords.items()}, attrs=attrs)
