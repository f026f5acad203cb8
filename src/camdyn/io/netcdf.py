"""Reading and writing results (netCDF via h5netcdf)."""

from __future__ import annotations

import os
from pathlib import Path

import xarray as xr

from camdyn.errors import PresetError
from camdyn.io.atomic import atomic_output

__all__ = ["save_netcdf", "load_netcdf", "write_netcdf"]


def write_netcdf(ds: xr.Dataset, path: str | Path) -> None:
    """Write ``ds`` as netCDF-4 (h5netcdf engine) to the file ``path`` (a temporary of
    :func:`camdyn.io.atomic.atomic_output`, which exists already).

    The file is built in memory by HDF5, then written with plain system calls. HDF5 never
    writes to the disk itself: when the disk fills during a write straight to the file,
    HDF5 fails to close it, leaves the h5py and h5netcdf objects in a state where any use
    crashes the interpreter (the next garbage collection or the interpreter's exit is
    a segmentation fault), and prints one warning per failed block. Here a full disk is
    an ``OSError`` (ENOSPC) of ``os.write``, with nothing left open. The cost is memory
    for one copy of the file while it is written.
    """
    data = ds.to_netcdf(engine="h5netcdf")
    fd = os.open(path, os.O_WRONLY | os.O_TRUNC | os.O_NOFOLLOW)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]
    finally:
        os.close(fd)


def save_netcdf(ds: xr.Dataset, path: str | Path) -> Path:
    """Write a result Dataset to netCDF-4 (h5netcdf engine), keeping units attributes.

    The write is atomic (:func:`camdyn.io.atomic.atomic_output`): an existing file of that
    name is replaced only once the new one is complete. A full disk raises
    :class:`camdyn.errors.StorageError` and leaves nothing open (:func:`write_netcdf`).
    """
    path = Path(path)
    with atomic_output(path, int(ds.nbytes)) as tmp:
        write_netcdf(ds, tmp)
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
