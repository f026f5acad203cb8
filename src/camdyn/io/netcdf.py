"""Reading and writing results (netCDF via h5netcdf)."""

from __future__ import annotations

import io
import os
from pathlib import Path

import xarray as xr

from camdyn.errors import PresetError
from camdyn.io.atomic import atomic_output

__all__ = ["save_netcdf", "load_netcdf", "write_netcdf", "GuardedFile"]


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


class GuardedFile(io.RawIOBase):
    """A file for HDF5 (``h5netcdf.File(GuardedFile(path), "w")``) that never tells HDF5
    a write failed, for files too large to build in memory (:func:`write_netcdf`).

    HDF5 left to fail a write on a full disk ends in a segmentation fault (see
    :func:`write_netcdf`). Here the first failed write is kept in :attr:`error`, and from
    then on nothing more goes to the disk: the writes are kept in memory instead (reported
    as done), so that HDF5 finishes and closes its file normally; the caller then calls
    :meth:`check`, which raises that error, and discards the file.

    HDF5 reads back what it wrote (its heaps of strings, its B-trees, chunks written in
    part): those reads see the kept writes, never the zeros of a write that did not reach
    the disk, which HDF5 would take for its own structures (a "bad heap index" error, or
    a crash). Writes after the failure larger than :attr:`KEPT_WRITE` bytes (blocks of
    raw data, which HDF5 does not parse) are dropped rather than kept, so that the memory
    held stays small; the file is discarded anyway. ``path`` exists already (a temporary
    of :func:`camdyn.io.atomic.atomic_output`) and is opened without following a link.
    """

    PAGE = 4096
    """Bytes per page of the writes kept in memory."""
    KEPT_WRITE = 2 ** 20
    """The largest write [B] kept in memory once the disk is full; larger ones are dropped."""

    def __init__(self, path: str | Path):
        super().__init__()
        self._fd = os.open(path, os.O_RDWR | os.O_NOFOLLOW)
        self.error: OSError | None = None
        self._pages: dict[int, bytearray] = {}   # page number -> content, once the disk is full
        self._end = 0                              # the file's size as HDF5 sees it [B]

    def readable(self) -> bool:
        return True

    def writable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return True

    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        return os.lseek(self._fd, offset, whence)

    def tell(self) -> int:
        return os.lseek(self._fd, 0, os.SEEK_CUR)

    def readinto(self, buffer) -> int:
        if self.error is None:
            data = os.read(self._fd, len(buffer))
            buffer[:len(data)] = data
            return len(data)
        start = self.tell()
        data = bytearray(os.pread(self._fd, len(buffer), start))
        size = max(len(data), min(len(buffer), self._end - start))
        data.extend(bytes(size - len(data)))
        for page in range(start // self.PAGE, (start + size - 1) // self.PAGE + 1):
            kept = self._pages.get(page)
            if kept is not None:
                lo, hi = max(start, page * self.PAGE), min(start + size, (page + 1) * self.PAGE)
                data[lo - start:hi - start] = kept[lo - page * self.PAGE:hi - page * self.PAGE]
        buffer[:size] = data
        os.lseek(self._fd, start + size, os.SEEK_SET)
        return size

    def write(self, data) -> int:
        view = memoryview(data).cast("B")
        size = len(view)
        start = self.tell()
        if self.error is None:
            try:
                while view:
                    view = view[os.write(self._fd, view):]
                return size
            except OSError as exc:
                self.error = exc
                self._end = max(self._end, os.fstat(self._fd).st_size)
        at = start + size - len(view)   # where the bytes not written begin
        if len(view) <= self.KEPT_WRITE:
            self._keep(at, view)
        self._end = max(self._end, at + len(view))
        os.lseek(self._fd, at + len(view), os.SEEK_SET)
        return size

    def _keep(self, at: int, view: memoryview) -> None:
        """Keep the bytes ``view``, to be written at ``at``, in memory pages."""
        end = at + len(view)
        for page in range(at // self.PAGE, (end - 1) // self.PAGE + 1):
            base = page * self.PAGE
            kept = self._pages.get(page)
            if kept is None:
                kept = bytearray(os.pread(self._fd, self.PAGE, base))
                kept.extend(bytes(self.PAGE - len(kept)))
                self._pages[page] = kept
            lo, hi = max(at, base), min(end, base + self.PAGE)
            kept[lo - base:hi - base] = view[lo - at:hi - at]

    def truncate(self, size: int | None = None) -> int:
        size = self.tell() if size is None else size
        if self.error is None:
            try:
                os.ftruncate(self._fd, size)
            except OSError as exc:
                self.error = exc
        if self.error is not None:
            self._end = size
        return size

    def close(self) -> None:
        if not self.closed:
            os.close(self._fd)
            self._pages.clear()
        super().close()

    def check(self) -> None:
        """Raise the first write's error, if one failed."""
        if self.error is not None:
            raise self.error


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
