"""Atomic, durable file writes.

Every file camdyn writes (netCDF, CSV, UFF, PNG, JSON, checkpoints) goes through
:func:`atomic_output`: the content is written to a temporary file in the destination's
folder, flushed and fsync'ed, then renamed over the destination in one step. A write that
fails (disk full, permission, interrupt) therefore never touches an existing file of that
name and never leaves a partial file under the final name; the temporary file is removed.

:func:`check_writable` is called before a long computation, so that an output that cannot
be written is refused before the work starts, not after.
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
from collections.abc import Iterator
from pathlib import Path

from camdyn.errors import OutputError, StorageError

__all__ = ["atomic_output", "write_text", "check_writable", "temporary_name", "free_space"]


def temporary_name(path: Path) -> Path:
    """A hidden temporary name beside ``path``, unique to this process."""
    return path.with_name(f".{path.name}.{os.getpid()}.tmp")


def free_space(folder: Path) -> int:
    """Bytes available to this user in ``folder`` [B]."""
    try:
        return shutil.disk_usage(folder).free
    except OSError:
        return -1


def _fsync_folder(folder: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _explain(exc: OSError, path: Path, needed: int | None) -> Exception:
    if exc.errno in (errno.ENOSPC, errno.EDQUOT):
        free = free_space(path.parent)
        sizes = [f"about {needed / 1e6:.3g} MB needed"] if needed else []
        sizes += [f"{free / 1e6:.3g} MB free"] if free >= 0 else []
        detail = f" ({', '.join(sizes)})" if sizes else ""
        return StorageError(f"cannot write {path}: the disk is full{detail}; nothing was written under that name")
    if exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return OutputError(f"cannot write {path}: permission denied")
    return StorageError(f"cannot write {path}: {exc.strerror or exc}")


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, expected_bytes: int | None = None) -> Iterator[Path]:
    """Write to a temporary path that replaces ``path`` only if the block succeeds.

    Parameters
    ----------
    path : path-like
        The final file name. Its folder is created if missing.
    expected_bytes : int, optional
        The size the file is expected to reach [B], for the message when the disk fills.

    Yields
    ------
    Path
        The temporary file to write (closed by the caller before the block ends).

    Raises
    ------
    StorageError
        The disk filled up (the message names the path and the size), or another
        operating-system error stopped the write.
    OutputError
        The folder cannot be written (permissions, read-only file system).
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _explain(exc, path, expected_bytes) from None
    tmp = temporary_name(path)
    try:
        yield tmp
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, path)
    except OSError as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise _explain(exc, path, expected_bytes) from None
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    _fsync_folder(path.parent)


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; return the path."""
    path = Path(path)
    with atomic_output(path, len(text.encode())) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def check_writable(path: str | os.PathLike, expected_bytes: int | None = None) -> Path:
    """Refuse, before any work, an output that cannot be written.

    Checks that the folder exists or can be created, that a file can be created in it,
    that ``path`` is not a folder, and, given ``expected_bytes`` [B], that the disk has
    that much free space.

    Raises
    ------
    OutputError
        With the reason, naming the path.
    """
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"cannot write {path}: it is a folder")
    folder = path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot write {path}: the folder {folder} cannot be created "
                          f"({exc.strerror or exc})") from None
    probe = folder / f".{path.name}.{os.getpid()}.probe"
    try:
        probe.write_bytes(b"")
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {exc.strerror or exc}") from None
    finally:
        with contextlib.suppress(OSError):
            probe.unlink()
    if expected_bytes:
        free = free_space(folder)
        if 0 <= free < expected_bytes:
            raise OutputError(f"cannot write {path}: about {expected_bytes / 1e6:.3g} MB are needed but only "
                              f"{free / 1e6:.3g} MB are free on that disk")
    return path
