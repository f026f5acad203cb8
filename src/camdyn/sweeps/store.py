"""Checkpoints and the result file.

Each finished chunk of points is written at once to ``OUTPUT.parts/chunk_NNNNNN.npz``
(to a temporary name, then renamed, so a killed run never leaves half a file). A
``manifest.json`` holds the spec's digest: a rerun of the same spec skips the chunks on
disk, and a changed spec is refused rather than mixed with old results. When every
chunk is there, the parts are streamed one at a time into the netCDF result (written
through h5netcdf under a temporary name, then renamed), so memory holds one chunk, never
the whole sweep. The parts are removed once the result is complete.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import h5netcdf
import h5py
import numpy as np

from camdyn import __version__
from camdyn.errors import ParameterError
from camdyn.sweeps import metrics as M
from camdyn.sweeps.spec import METRICS, SweepSpec

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
    """The parts folder of one sweep."""

    def __init__(self, spec: SweepSpec, restart: bool = False):
        self.spec = spec
        self.folder = Path(str(spec.output) + ".parts")
        manifest = self.folder / "manifest.json"
        digest = spec.digest()
        if self.folder.exists() and restart:
            shutil.rmtree(self.folder)
        if manifest.exists():
            old = json.loads(manifest.read_text()).get("digest")
            if old != digest:
                raise ParameterError(f"{self.folder} holds checkpoints of a different sweep (digest {old}, this "
                                     f"spec {digest}); rerun with --restart to discard them")
        else:
            self.folder.mkdir(parents=True, exist_ok=True)
            _atomic_text(manifest, json.dumps({"digest": digest, "chunks": spec.chunks, "points": spec.points,
                                               "camdyn": __version__}))

    def path(self, chunk: int) -> Path:
        return self.folder / f"chunk_{chunk:06d}.npz"

    def done(self) -> set[int]:
        return {int(p.stem[6:]) for p in self.folder.glob("chunk_*.npz")}

    def save(self, chunk: int, arrays: dict) -> None:
        tmp = self.folder / f".chunk_{chunk:06d}.{os.getpid()}.tmp.npz"
        np.savez(tmp, **arrays)
        os.replace(tmp, self.path(chunk))

    def load(self, chunk: int) -> dict:
        with np.load(self.path(chunk), allow_pickle=False) as data:
            return {k: data[k] for k in data.files}

    def assemble(self, keep_parts: bool = False) -> Path:
        """Stream every part into the netCDF result; return its path."""
        spec = self.spec
        missing = set(range(spec.chunks)) - self.done()
        if missing:
            raise ParameterError(f"cannot assemble {spec.output}: {len(missing)} chunks are missing")
        out = Path(spec.output)
        tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp")
        kept = spec.kept_revolutions
        layout = M.variables(spec.metrics, spec.harmonics, kept)
        dims = [d for d, _ in spec.dimensions]
        with h5netcdf.File(tmp, "w") as f:
            sizes = dict(spec.dimensions)
            if "poincare" in spec.metrics:
                sizes["revolution"] = kept
            if "spectrum" in spec.metrics:
                sizes["harmonic"] = spec.harmonics
            f.dimensions = sizes
            _coordinates(f, spec)
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
                for name, var in variables.items():
                    _write_rows(var, block[name], start, spec.shape)
            f.attrs.update(_global_attributes(spec))
        os.replace(tmp, out)
        if not keep_parts:
            shutil.rmtree(self.folder, ignore_errors=True)
        return out


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


def _atomic_text(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


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
    return {
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
        "metric_definitions": "; ".join(f"{m}: {METRICS[m]}" for m in spec.metrics),
    }
