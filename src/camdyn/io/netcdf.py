"""Reading and writing results (netCDF via h5netcdf)."""

from __future__ import annotations

from pathlib import Path

import xarray as xr

from camdyn.errors import PresetError
from camdyn.io.atomic import atomic_output

__all__ = ["save_netcdf", "load_netcdf"]


def save_netcdf(ds: xr.Dataset, path: str | Path) -> Path:
    """Write a result Dataset to netCDF-4 (h5netcdf engine), keeping units attributes.

    The write is atomic (:func:`camdyn.io.atomic.atomic_output`): an existing file of that
    name is replaced only once the new one is complete.
    """
    path = Path(path)
    with atomic_output(path, int(ds.nbytes)) as tmp:
        ds.to_netcdf(tmp, engine="h5netcdf")
    return path


def load_netcdf(path: str | Path) -> xr.Dataset:
    """Read a result written by :func:`save_netcdf`."""
    path = Path(path)
    if not path.is_file():
        raise PresetError(f"no such file: {path}")
    try:
        return xr.load_dataset(path, engine="h5netcdf")
    except (OSError, ValueError) as exc:
        raise PresetError(f"{path}: not a readable netCDF file ({exc})") from None
