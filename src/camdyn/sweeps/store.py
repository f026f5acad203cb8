"""Checkpoints and the result file.

Each finished chunk of points is written at once to ``OUTPUT.parts/chunk_NNNNNN.npz``
(to a temporary name, fsync'ed, then renamed, so a killed run never leaves half a file),
stamped with the spec's digest and a SHA-256 checksum of its arrays. A ``manifest.json``,
written before the first chunk, holds the digest too: a rerun of the same spec skips the
intact chunks on disk and computes damaged ones again, and a changed spec is refused
rather than mixed with old results. ``OUTPUT.lock`` is held while a sweep runs, so a
second sweep onto the same output is refused. When every
chunk is there, the parts are streamed one at a time into the netCDF result (written
through h5netcdf under a temporary name, then renamed), so memory holds one chunk, never
the whole sweep. The parts are removed once the result is complete.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import hashlib
import json
import os
import shutil
import stat
import zipfile
from pathlib import Path

import h5netcdf
import h5py
import numpy as np

from camdyn import __version__
from camdyn.errors import OutputError, ParameterError
from camdyn.io.atomic import atomic_output, remove_stale, write_text
from camdyn.io.netcdf import GuardedFile
from camdyn.sweeps import metrics as M
from camdyn.sweeps.families import metric_definitions, result_variables
from camdyn.sweeps.spec import SweepSpec

__all__ = ["Checkpoint", "SOLVER_VARIABLES"]

#: memory for the parts joined into one write of the result file [bytes]
BLOCK_BYTES = 32 * 2 ** 20

#: per-point bookkeeping kept whatever the metrics
SOLVER_VARIABLES = {
    "status": ("i1", "1", "0 ok, 1 parameters refused, 2 solver stopped"),
    "failure": ("str", "", "why the point failed (empty when it did not)"),
    "accepted_steps": ("i8", "1", "accepted integration steps"),
    "rejected_steps": ("i8", "1", "rejected integration steps"),
    "events": ("i8", "1", "located events (contact onsets, separations, ...)"),
}


class Checkpoint:
    """The parts folder of one sweep, locked for this process while it runs.

    Parameters
    ----------
    spec : SweepSpec
        The sweep.
    restart : bool
        Discard existing parts instead of resuming.
    say : callable, optional
        Receives one-line notes (a damaged part that will be computed again).

    Raises
    ------
    ParameterError
        Another process is running a sweep onto the same output, or the parts folder
        holds parts of a different sweep (rerun with ``--restart`` to discard them).
    """

    def __init__(self, spec: SweepSpec, restart: bool = False, say=None):
        self.spec = spec
        self.say = say or (lambda _msg: None)
        self.folder = Path(str(spec.output) + ".parts")
        self.digest = spec.digest()
        self._verified: set[int] = set()   # chunks this process wrote or has checked
        self._lock_path = Path(str(spec.output) + ".lock")
        self._lock = _lock(self._lock_path)
        self._created = False
        try:
            manifest = self.folder / "manifest.json"
            if self.folder.exists() and restart:
                shutil.rmtree(self.folder)
            self._created = not self.folder.exists()   # this run makes the parts folder
            if manifest.exists():
                try:
                    old = json.loads(manifest.read_text()).get("digest")
                except (OSError, ValueError):
                    old = None
                if old != self.digest:
                    raise ParameterError(f"{self.folder} holds checkpoints of a different sweep (digest {old}, this "
                                         f"spec {self.digest}); rerun with --restart to discard them")
            else:
                foreign = [p.name for p in self.folder.glob("chunk_*.npz") if self._part_digest(p) != self.digest]
                if foreign:
                    raise ParameterError(f"{self.folder} holds {len(foreign)} checkpoint(s) that are not of this sweep "
                                         f"(for example {foreign[0]}); rerun with --restart to discard them")
                self.folder.mkdir(parents=True, exist_ok=True)
                write_text(manifest, json.dumps({"digest": self.digest, "chunks": spec.chunks,
                                                 "points": spec.points, "camdyn": __version__}))
            remove_stale(self.folder)   # parts half written by a killed run (not per part: O(chunks^2))
        except BaseException:   # refused (another spec), or the disk is full: no lock left behind
            self.discard_if_unused()
            self.close()
            raise

    def discard_if_unused(self) -> None:
        """Remove the parts folder this run created when it holds no chunk yet (only the
        manifest): a sweep refused or failing before its first chunk leaves nothing behind."""
        if not self._created or any(self.folder.glob("chunk_*")):
            return
        with contextlib.suppress(OSError):
            (self.folder / "manifest.json").unlink(missing_ok=True)
            self.folder.rmdir()

    def close(self) -> None:
        """Release the output's lock (also released when the process ends, however it ends)."""
        if self._lock is not None:
            self._lock_path.unlink(missing_ok=True)
            self._lock.close()
            self._lock = None

    def path(self, chunk: int) -> Path:
        return self.folder / f"chunk_{chunk:06d}.npz"

    def done(self) -> set[int]:
        """Chunks whose parts are on disk and intact. A part that cannot be read, belongs to
        another sweep or fails its checksum is removed (and so computed again). Each part is
        read and checked once per process: the ones written or checked before are trusted."""
        good = set()
        for path in sorted(self.folder.glob("chunk_*.npz")):
            chunk = int(path.stem[6:])
            if chunk in self._verified:
                good.add(chunk)
                continue
            try:
                self.load(chunk)
            except ValueError as exc:
                self.say(f"note: {path.name} is damaged ({exc}); it will be computed again")
                path.unlink(missing_ok=True)
                continue
            good.add(chunk)
            self._verified.add(chunk)
        return good

    def save(self, chunk: int, arrays: dict) -> None:
        """Write one chunk's arrays with this sweep's digest and their checksum, atomically."""
        stamped = dict(arrays, _digest=np.array(self.digest), _checksum=np.array(_checksum(arrays)))
        with atomic_output(self.path(chunk), clean=False) as tmp:   # cleaned once, in __init__
            with tmp.open("wb") as fh:
                np.savez(fh, **stamped)
        self._verified.add(chunk)

    def load(self, chunk: int) -> dict:
        """The arrays of one chunk.

        Raises
        ------
        ValueError
            The part is truncated or corrupt, was written by another sweep, or fails its
            checksum.
        """
        try:
            with np.load(self.path(chunk), allow_pickle=False) as data:
                arrays = {k: data[k] for k in data.files}
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
            raise ValueError(f"unreadable: {type(exc).__name__}") from None
        digest = str(arrays.pop("_digest", ""))
        checksum = str(arrays.pop("_checksum", ""))
        if digest != self.digest:
            raise ValueError("written by a different sweep")
        if checksum != _checksum(arrays):
            raise ValueError("checksum mismatch")
        return arrays

    @staticmethod
    def _part_digest(path: Path) -> str | None:
        try:
            with np.load(path, allow_pickle=False) as data:
                return str(data["_digest"]) if "_digest" in data.files else None
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
            return None

    def assemble(self, keep_parts: bool = False) -> Path:
        """Stream every part into the netCDF result; return its path."""
        spec = self.spec
        missing = set(range(spec.chunks)) - self.done()
        if missing:
            raise ParameterError(f"cannot assemble {spec.output}: {len(missing)} chunks are missing")
        out = Path(spec.output)
        with atomic_output(out) as tmp, GuardedFile(tmp) as sink:
            try:
                self._write_result(sink)
            except Exception:
                sink.check()   # a full disk is the cause of what HDF5 then said
                raise
            sink.check()   # a full disk: raised now, with HDF5's file closed normally
        if not keep_parts:
            shutil.rmtree(self.folder, ignore_errors=True)
        return out

    def _write_result(self, sink) -> None:
        """Write the result file into ``sink`` (a :class:`camdyn.io.netcdf.GuardedFile`)."""
        spec = self.spec
        kept = spec.kept_revolutions
        layout = _layout(spec)
        dims = [d for d, _ in spec.dimensions]
        with h5netcdf.File(sink, "w") as f:
            sizes = dict(spec.dimensions)
            if "poincare" in spec.metrics:
                sizes["revolution"] = kept
            if "spectrum" in spec.metrics:
                sizes["harmonic"] = spec.harmonics
            for extra, extra_sizes, *_ in layout.values():
                sizes.update(zip(extra, extra_sizes))
            f.dimensions = sizes
            _coordinates(f, spec)
            if "follower" in sizes:
                var = f.create_variable("follower", ("follower",), "i8")
                var[:] = np.arange(1, sizes["follower"] + 1)
                var.attrs.update(units="1", long_name="follower number")
            coords = " ".join(v.key for v in spec.vary if v.key != v.dimension)
            variables = {}
            for name, (extra, _, dtype, unit, long_name) in layout.items():
                variables[name] = _variable(f, name, tuple(dims) + extra, dtype, unit, long_name, coords)
            for name, (dtype, unit, long_name) in SOLVER_VARIABLES.items():
                variables[name] = _variable(f, name, tuple(dims), dtype, unit, long_name, coords)
            if "regime" in variables:
                reg = variables["regime"]
                reg.attrs["flag_values"] = np.array(sorted(M.REGIMES), dtype=np.int8)
                reg.attrs["flag_meanings"] = " ".join(M.REGIMES[k] for k in sorted(M.REGIMES))
            for start, block in self._blocks():
                if sink.error is not None:   # the disk is full: the file is discarded, HDF5 need only close it
                    break
                for name, var in variables.items():
                    _write_rows(var, block[name], start, spec.shape)
            f.attrs.update(_global_attributes(spec))


    def _blocks(self):
        """Consecutive parts joined into blocks of at most :data:`BLOCK_BYTES` (at least one
        part each): ``(first point, arrays)``. Each write into the netCDF file costs about
        a millisecond whatever its size, so writing blocks instead of parts keeps the
        assembly of a sweep of many small chunks from taking seconds."""
        parts, size, first = [], 0, 0
        for chunk in range(self.spec.chunks):
            part = self.load(chunk)
            parts.append(part)
            size += sum(a.nbytes for a in part.values())
            if size >= BLOCK_BYTES or chunk == self.spec.chunks - 1:
                yield first, {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
                first = (chunk + 1) * self.spec.chunk
                parts, size = [], 0


def _layout(spec: SweepSpec) -> dict:
    """The result's metric variables (:func:`camdyn.sweeps.families.result_variables`)."""
    return result_variables(spec)


def _checksum(arrays: dict) -> str:
    """SHA-256 over the names, dtypes, shapes and bytes of a chunk's arrays."""
    digest = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        digest.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        digest.update(a.tobytes())
    return digest.hexdigest()


def _lock(path: Path):
    """Hold an exclusive lock on ``path`` (a lock file beside the output) for the sweep;
    the operating system releases it when the process ends, even by SIGKILL.

    The lock file is opened with ``O_NOFOLLOW`` and must be a plain file with one link:
    a symbolic link planted at its name is removed (never followed) and the lock file
    created in its place; a hard link or anything else there is refused, so the process
    id written into the lock never lands in another file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    for _ in range(5):
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600)
        except OSError as exc:
            if exc.errno == errno.ELOOP:       # a symbolic link at the lock's name: remove the link only
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(path)
                continue
            raise OutputError(f"cannot create the lock file {path}: {exc.strerror or exc}") from None
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_nlink != 1:
            os.close(fd)
            raise OutputError(f"{path} is not a lock file camdyn made (a link or a special file); remove it and "
                              f"run again")
        handle = os.fdopen(fd, "a+")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.seek(0)
            owner = handle.read(100).strip() or "another process"
            handle.close()
            raise ParameterError(f"another sweep ({owner}) is writing {path.with_suffix('')}; wait for it to "
                                 f"finish or choose another output") from None
        try:
            same = os.path.samestat(os.fstat(handle.fileno()), os.stat(path, follow_symlinks=False))
        except OSError:
            same = False
        if not same:   # the holder removed it as we locked it: lock the file now under that name
            handle.close()
            continue
        handle.seek(0)
        handle.truncate()
        handle.write(f"pid {os.getpid()}")
        handle.flush()
        return handle
    raise OutputError(f"cannot lock {path}: it keeps being replaced (a link planted there?)")


def _coordinates(f, spec: SweepSpec) -> None:
    for dim, n in spec.dimensions:
        on_dim = [v for v in spec.vary if v.dimension == dim]
        if not any(v.key == dim for v in on_dim):
            var = f.create_variable(dim, (dim,), "i8")
            var[:] = np.arange(n)
            var.attrs["long_name"] = f"sweep index along {dim}"
        for v in on_dim:
            var = f.create_variable(v.key, (dim,), "f8")
            var[:] = np.asarray(v.values)
            var.attrs["units"] = v.unit
            var.attrs["long_name"] = f"swept parameter {v.key}"
            var.attrs.update(v.display_attrs())


def _variable(f, name, dims, dtype, unit, long_name, coords):
    if dtype == "str":
        var = f.create_variable(name, dims, dtype=h5py.string_dtype())
    elif dtype == "f8":
        var = f.create_variable(name, dims, dtype, fillvalue=np.nan)
    else:
        var = f.create_variable(name, dims, dtype)
    if unit:
        var.attrs["units"] = unit
    var.attrs["long_name"] = long_name
    if coords:
        var.attrs["coordinates"] = coords
    return var


def _write_rows(var, rows: np.ndarray, start: int, shape: tuple[int, ...]) -> None:
    """Write points ``start .. start + len(rows)`` (flat C order) of a variable over ``shape``,
    one contiguous run along the last swept dimension at a time."""
    if rows.dtype.kind == "U":
        rows = rows.astype(object)
    last = shape[-1]
    i = 0
    while i < len(rows):
        flat = start + i
        where = np.unravel_index(flat, shape)
        run = min(len(rows) - i, last - where[-1])
        var[tuple(int(w) for w in where[:-1]) + (slice(int(where[-1]), int(where[-1]) + run),)] = rows[i:i + run]
        i += run


def _global_attributes(spec: SweepSpec) -> dict:
    definitions, extra = metric_definitions(spec)
    return {**extra,
        "title": f"camdyn sweep {spec.name}",
        "source": f"camdyn {__version__}",
        "sweep_digest": spec.digest(),
        "parameters_toml": spec.system_toml,
        "swept": ", ".join(f"{v.key} [{v.unit}] along {v.dimension} ({len(v.values)} values)" for v in spec.vary),
        "revolutions": spec.revolutions,
        "discarded_revolutions": spec.discard,
        "samples_per_revolution": spec.samples_per_revolution,
        "rtol": spec.rtol,
        "atol": spec.atol,
        "metrics": ", ".join(spec.metrics),
        "metric_definitions": "; ".join(f"{m}: {definitions[m]}" for m in spec.metrics),
    }
