"""Atomic, durable file writes, safe in a folder other users can write to.

Every file camdyn writes (netCDF, CSV, UFF, PNG, JSON, checkpoints) goes through
:func:`atomic_output`: the content is written to a temporary file in the destination's
folder, flushed and fsync'ed, then renamed over the destination in one step. A write that
fails (disk full, permission, interrupt) therefore never touches an existing file of that
name and never leaves a partial file under the final name; the temporary file is removed,
and so are the folders the write created for it.

The temporary file is created exclusively under an unpredictable name
(:func:`tempfile.mkstemp`: ``O_CREAT | O_EXCL``, mode 0600), so a symbolic link planted
beside the output is never written through. Its name, ``.NAME.PID-HOST.RANDOM.tmp``, says
which process made it: a temporary left by a process that was killed (SIGKILL, a power
cut) is removed by the next write of ``NAME`` on that machine. The written file gets the
mode of the file it replaces, or ``0666`` less the umask for a new file.

An output registered by :func:`expect_new` (the command line does so for every output
when ``--force`` is not given) is published by an exclusive hard link instead of a
rename: if another process created the file meanwhile, the write is refused and the
other process's file is kept.

:func:`check_writable` is called before a long computation, so that an output that cannot
be written is refused before the work starts, not after. It creates nothing.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import os
import re
import shutil
import socket
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from camdyn.errors import CamdynError, OutputError, StorageError

__all__ = ["atomic_output", "write_text", "check_writable", "expect_new", "remove_stale", "temporary_prefix",
           "free_space"]

#: Outputs to publish only if no file of that name exists by then (:func:`expect_new`).
_EXPECT_NEW: set[str] = set()


def _host_tag() -> str:
    return hashlib.sha1(socket.gethostname().encode(errors="replace")).hexdigest()[:8]


def temporary_prefix(name: str) -> str:
    """The start of the temporaries' names of output ``name`` written by this process:
    ``.NAME.PID-HOST.`` (a random part and ``.tmp`` or ``.probe`` follow)."""
    return f".{name}.{os.getpid()}-{_host_tag()}."


def expect_new(path: str | os.PathLike, new: bool = True) -> None:
    """Publish the next write of ``path`` by this process only if no file of that name
    exists then (the file is created by an exclusive hard link, not a rename); refuse it
    with :class:`OutputError` otherwise. For outputs checked without ``--force``: a second
    writer that started meanwhile must not silently replace the first one's result.
    ``new=False`` withdraws the registration (``--force``)."""
    if new:
        _EXPECT_NEW.add(os.path.abspath(path))
    else:
        _EXPECT_NEW.discard(os.path.abspath(path))


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


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists on this machine (one of another user counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def remove_stale(folder: Path, name: str | None = None) -> list[str]:
    """Remove the temporaries of output ``name`` (of any output: None) in ``folder`` left by
    processes of this machine that no longer run (killed during a write); return their
    names. A symbolic link of such a name is removed, never followed."""
    output = ".+" if name is None else re.escape(name)
    pattern = re.compile(rf"\.{output}\.(\d+)-{_host_tag()}\.[A-Za-z0-9_]+\.(tmp|probe)")
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if match is None:
            continue
        pid = int(match.group(1))
        if pid == os.getpid() or _alive(pid):
            continue
        with contextlib.suppress(OSError):
            os.unlink(entry.path)
            removed.append(entry.name)
    return removed


def _make_folders(folder: Path) -> list[Path]:
    """Create ``folder`` and its missing parents; return those created, deepest last."""
    missing = []
    current = folder
    while not os.path.lexists(current) and current != current.parent:
        missing.append(current)
        current = current.parent
    created = []
    for path in reversed(missing):
        try:
            os.mkdir(path)
        except FileExistsError:
            continue
        except OSError:
            _remove_folders(created)
            raise
        created.append(path)
    return created


def _remove_folders(created: list[Path]) -> None:
    """Remove the folders of ``created`` that are still empty, deepest first."""
    for path in reversed(created):
        with contextlib.suppress(OSError):
            os.rmdir(path)


def _umask() -> int:
    with contextlib.suppress(OSError, ValueError), open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    mask = os.umask(0o022)   # no /proc: read it by setting it (and put it back at once)
    os.umask(mask)
    return mask


def _mode_for(path: Path) -> int:
    """The mode of the file ``path`` replaces, or the usual one of a new file."""
    try:
        st = os.stat(path)
        if stat.S_ISREG(st.st_mode):
            return stat.S_IMODE(st.st_mode)
    except OSError:
        pass
    return 0o666 & ~_umask()


def _publish(tmp: Path, path: Path, exclusive: bool) -> None:
    """Give ``tmp`` (complete, synced) the name ``path``: a rename, or with ``exclusive``
    a hard link that fails if ``path`` exists (then ``tmp`` is removed by the caller)."""
    if not exclusive:
        os.replace(tmp, path)
        return
    try:
        os.link(tmp, path, follow_symlinks=False)
    except FileExistsError:
        raise OutputError(f"{path} exists (written by another process meanwhile); pass --force to overwrite") \
            from None
    except OSError as exc:
        if exc.errno not in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EMLINK, errno.ENOSYS):
            raise
        # a file system without hard links: claim the name exclusively, then rename over it
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
        except FileExistsError:
            raise OutputError(f"{path} exists (written by another process meanwhile); pass --force to "
                              f"overwrite") from None
        os.close(fd)
        os.replace(tmp, path)
        return
    os.unlink(tmp)


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, expected_bytes: int | None = None,
                  exclusive: bool | None = None, clean: bool = True) -> Iterator[Path]:
    """Write to a temporary path that replaces ``path`` only if the block succeeds.

    Parameters
    ----------
    path : path-like
        The final file name. Its folder is created if missing (and removed again, if
        still empty, when the write fails).
    expected_bytes : int, optional
        The size the file is expected to reach [B], for the message when the disk fills.
    exclusive : bool, optional
        Refuse to replace a file of that name that exists when the write ends (default:
        whether :func:`expect_new` registered ``path``).
    clean : bool
        First remove the temporaries of ``path`` that killed writers left
        (:func:`remove_stale`: one pass over the folder). A caller writing many files
        into one folder passes False and calls :func:`remove_stale` once instead.

    Yields
    ------
    Path
        The temporary file, created empty (mode 0600) by this process under a name no
        other process could have predicted; the caller writes it by name and closes it
        before the block ends.

    Raises
    ------
    StorageError
        The disk filled up (the message names the path and the size), or another
        operating-system error stopped the write.
    OutputError
        The folder cannot be written (permissions, read-only file system), or
        ``exclusive`` and a file of that name appeared meanwhile.
    """
    path = Path(path)
    key = os.path.abspath(path)
    if exclusive is None:
        exclusive = key in _EXPECT_NEW
    try:
        created = _make_folders(path.parent)
    except OSError as exc:
        raise _explain(exc, path, expected_bytes) from None
    if clean:
        remove_stale(path.parent, path.name)
    try:
        fd, name = tempfile.mkstemp(dir=path.parent, prefix=temporary_prefix(path.name), suffix=".tmp")
        os.close(fd)
    except OSError as exc:
        _remove_folders(created)
        raise _explain(exc, path, expected_bytes) from None
    tmp = Path(name)
    try:
        yield tmp
        fd = os.open(tmp, os.O_RDONLY | os.O_NOFOLLOW)
        try:
            os.fchmod(fd, _mode_for(path))
            os.fsync(fd)
        finally:
            os.close(fd)
        _publish(tmp, path, exclusive)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        _remove_folders(created)
        if isinstance(exc, OSError) and not isinstance(exc, CamdynError):
            raise _explain(exc, path, expected_bytes) from None
        raise
    _EXPECT_NEW.discard(key)
    _fsync_folder(path.parent)


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; return the path."""
    path = Path(path)
    with atomic_output(path, len(text.encode())) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def check_writable(path: str | os.PathLike, expected_bytes: int | None = None) -> Path:
    """Refuse, before any work, an output that cannot be written.

    Checks that ``path`` is not a folder, that a file can be created in its folder or,
    when the folder is missing, in the nearest existing folder above it (the one the
    write will create it in), and, given ``expected_bytes`` [B], that the disk has that
    much free space. Creates nothing: the probe file is created exclusively under an
    unpredictable name and removed at once, and a missing folder is created only by the
    write itself.

    Raises
    ------
    OutputError
        With the reason, naming the path.
    """
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"cannot write {path}: it is a folder")
    folder = path.parent
    existing = folder
    while not os.path.lexists(existing) and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise OutputError(f"cannot write {path}: the folder {folder} cannot be created ({existing} is not a "
                          f"folder)")
    try:
        fd, probe = tempfile.mkstemp(dir=existing, prefix=temporary_prefix(path.name), suffix=".probe")
    except OSError as exc:
        what = f"the folder {folder} cannot be created" if existing != folder else "cannot create a file there"
        raise OutputError(f"cannot write {path}: {what} ({exc.strerror or exc})") from None
    os.close(fd)
    with contextlib.suppress(OSError):
        os.unlink(probe)
    if expected_bytes:
        free = free_space(existing)
        if 0 <= free < expected_bytes:
            raise OutputError(f"cannot write {path}: about {expected_bytes / 1e6:.3g} MB are needed but only "
                              f"{free / 1e6:.3g} MB are free on that disk")
    return path
