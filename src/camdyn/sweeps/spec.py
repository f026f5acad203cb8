"""The sweep specification: which system, which parameters vary over which values, how
long each point runs, and which metrics it keeps.

A spec is a TOML file (or the same tables as a dict)::

    [system]
    source = "sundar2014-impact"          # preset name or path to a system TOML
    set = { "cam.runout" = "3.5 mm" }     # optional overrides, units as text

    [[vary]]                              # one table per varied parameter
    key = "motion.speed"
    start = "5 Hz"                        # start/stop/num (inclusive) ...
    stop = "30 Hz"
    num = 400
    # values = ["5 Hz", "10 Hz"]          # ... or an explicit list
    # spacing = "log"                     # geometric spacing for start/stop/num
    # dimension = "speed"                 # vary tables sharing a dimension are zipped

    [run]
    revolutions = 300                     # cam periods simulated per point
    discard = 200                         # of which the first are the transient
    samples_per_revolution = 64           # output samples per cam period
    rtol = 3e-7                           # local error tolerances of the compiled core
    atol = 1e-10
    chunk = 8                             # points per task (and per checkpoint file)

    [metrics]
    names = ["residual", "impacts", "poincare", "max_force", "regime", "spectrum"]
    harmonics = 10                        # cam harmonics of alpha_ddot kept by "spectrum"

    [output]
    path = "bifurcation.nc"               # relative to the working directory, or absolute

A ``[system] source`` that is a mechanism file (a ``[mechanism]`` table) makes a sweep
over that mechanism: its keys, checks and metrics are those of
:mod:`camdyn.sweeps.mechanism_spec`, and each point runs through
:func:`camdyn.io.mechanism_config.simulate_mechanism`. A source ``"FILE.py:NAME"`` makes
a sweep over that model of the model protocol (:mod:`camdyn.sweeps.model_run`); the
families are told apart in :mod:`camdyn.sweeps.families`.

A relative ``[system] source`` TOML path is taken relative to the spec's folder; a
relative ``[output] path`` relative to the current working directory (the result goes
where the command runs, never beside a spec in the package's or the examples' folders).

Every value is checked, and every point's varied values are applied one parameter at a
time to the base system, before any simulation starts (:func:`load_spec`), so a bad
spec is refused up front with a message naming the table and key.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from camdyn import __version__
from camdyn.errors import CamdynError, ParameterError
from camdyn.params.config import loads_toml, system_from_toml
from camdyn.params.system import System
from camdyn.params.toml_text import read_toml_text
from camdyn.sweeps.families import ROCKING_METRICS, family_of, result_variables

__all__ = ["METRICS", "Vary", "SweepSpec", "load_spec", "spec_from_dict"]

#: metric name -> what it adds to the result of a sweep over the rocking cam-follower
METRICS = ROCKING_METRICS

_RUN_DEFAULTS = {"revolutions": 60.0, "discard": 20.0, "samples_per_revolution": 64, "rtol": 3e-7,
                 "atol": 1e-10, "chunk": 8}
_TABLES = {"system", "vary", "run", "metrics", "output"}
#: Most points a sweep may have [-] (10^9 at a millisecond each is 12 CPU-days).
MAX_POINTS = 10 ** 9
#: Most values one varied parameter may take [-]: finer than 10^5 values along one
#: parameter resolves nothing a bifurcation diagram or map shows; split the range.
MAX_VALUES = 10 ** 5
#: Values of each varied parameter that are checked to make a valid system before the
#: sweep (its ends and evenly spaced ones between), however many it takes [-].
CHECKED_VALUES = 17
#: Memory a parameter value takes while the spec is read: the float and its array
#: element [B].
BYTES_PER_VALUE = 40
#: Most output samples a worker's chunk may hold (points x revolutions x samples per
#: revolution) [-].
MAX_CHUNK_SAMPLES = 10 ** 9
#: Memory one output sample of one point takes in the sweep kernel: the window's seven
#: channels, the state, the derived channels and the output times, 8 B each, rounded up [B].
BYTES_PER_SAMPLE = 320


@dataclass(frozen=True)
class Vary:
    """One varied parameter: dotted ``key``, its ``values`` in SI units along ``dimension``.

    ``unit`` is the SI unit of ``values``; ``display_unit`` the unit the spec wrote them in
    (``"mm"``, ``"rpm"``; empty for bare numbers) and ``display_factor`` the display value
    of one SI unit (1000 for mm), for figures only.
    """

    key: str
    dimension: str
    values: tuple[float, ...]
    unit: str
    display_unit: str = ""
    display_factor: float = 1.0

    def display_attrs(self) -> dict:
        """Attributes of the result's coordinate that name the display unit (empty when
        the spec wrote bare numbers)."""
        if not self.display_unit:
            return {}
        return {"display_units": self.display_unit, "display_factor": self.display_factor}


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep.

    Attributes
    ----------
    source, overrides : the base system (preset or TOML path, and dotted overrides).
    system_toml : the base system written out as TOML (what every point starts from).
    vary : the varied parameters.
    dimensions : dimension names in order, with their lengths.
    revolutions, discard : cam periods simulated and discarded per point [-].
    samples_per_revolution : output samples per cam period [-].
    rtol, atol : local error tolerances [-], [rad, rad/s].
    chunk : points per task and per checkpoint file [-].
    metrics : metric names (:data:`METRICS`); harmonics: cam harmonics kept [-].
    output : result path (netCDF).
    mechanism : the mechanism kind of a sweep over a mechanism file (its ``system_toml``
        is then the whole mechanism, :mod:`camdyn.sweeps.mechanism_spec`); empty for the
        other families.
    runner : the module that runs the points in Python (a mechanism's or a protocol
        model's, :mod:`camdyn.sweeps.families`); empty for the compiled kernel of the
        rocking cam-follower.
    """

    source: str
    overrides: dict
    system_toml: str
    vary: tuple[Vary, ...]
    dimensions: tuple[tuple[str, int], ...]
    revolutions: int
    discard: int
    samples_per_revolution: int
    rtol: float
    atol: float
    chunk: int
    metrics: tuple[str, ...]
    harmonics: int
    output: Path
    name: str = "sweep"
    mechanism: str = ""
    runner: str = ""
    _base: System | None = field(default=None, compare=False, repr=False)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(n for _, n in self.dimensions)

    @property
    def points(self) -> int:
        return int(np.prod(self.shape)) if self.shape else 1

    @property
    def chunks(self) -> int:
        return math.ceil(self.points / self.chunk)

    @property
    def kept_revolutions(self) -> int:
        return self.revolutions - self.discard

    def base_system(self) -> System:
        """The base system, rebuilt from :attr:`system_toml` (so that every process, local
        or on a cluster without the spec's files, starts from the same numbers); a sweep
        over a mechanism's base cam-follower (follower 1)."""
        if self.mechanism and self._base is None:
            from camdyn.sweeps.mechanism_spec import point_mechanism
            object.__setattr__(self, "_base", point_mechanism(self.source, self.overrides, {}).system)
        if self._base is None:
            object.__setattr__(self, "_base", system_from_toml(self.system_toml))
        return self._base

    def point_values(self, index: int) -> dict:
        """Dotted key -> SI value of the flat (C-order) point ``index``."""
        where = np.unravel_index(index, self.shape) if self.shape else ()
        dims = [d for d, _ in self.dimensions]
        return {v.key: v.values[where[dims.index(v.dimension)]] for v in self.vary}

    def digest(self) -> str:
        """A hash of everything that determines the result (checkpoints must match it)."""
        text = json.dumps({
            "camdyn": __version__, "system": self.system_toml,
            "vary": [(v.key, v.dimension, list(v.values)) for v in self.vary],
            "run": [self.revolutions, self.discard, self.samples_per_revolution, self.rtol, self.atol,
                    self.chunk],
            "metrics": list(self.metrics), "harmonics": self.harmonics,
        }, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def __getstate__(self):            # the cached System travels as its TOML, not pickled
        state = self.__dict__.copy()
        state["_base"] = None
        return state


def _table(spec: dict, name: str, allowed: set) -> dict:
    table = spec.get(name, {})
    if not isinstance(table, dict):
        raise ParameterError(f"sweep spec: [{name}] must be a table")
    extra = set(table) - allowed
    if extra:
        raise ParameterError(f"sweep spec: unknown key(s) {sorted(extra)} in [{name}]; allowed: {sorted(allowed)}")
    return table


def _number(table: str, key: str, raw, integer: bool = False, minimum: float | None = None) -> float:
    """A finite number from the spec: > 0, or >= ``minimum`` when one is given."""
    if isinstance(raw, bool) or not isinstance(raw, (int, float)) or not math.isfinite(raw):
        raise ParameterError(f"sweep spec: [{table}] {key} must be a finite number, got {raw!r}")
    if integer and int(raw) != raw:
        raise ParameterError(f"sweep spec: [{table}] {key} must be a whole number, got {raw!r}")
    if (minimum is None and raw <= 0) or (minimum is not None and raw < minimum):
        bound = "> 0" if minimum is None else f">= {minimum:g}"
        raise ParameterError(f"sweep spec: [{table}] {key} must be {bound}, got {raw!r}")
    return int(raw) if integer else float(raw)


def _limits():
    """:mod:`camdyn.simulation.limits`, imported when a spec is checked (a worker that
    unpickles a spec needs none of it)."""
    from camdyn.simulation import limits

    return limits


def _values(i: int, entry: dict, key_unit) -> Vary:
    where = f"[[vary]] #{i + 1}"
    allowed = {"key", "values", "start", "stop", "num", "spacing", "dimension"}
    extra = set(entry) - allowed
    if extra:
        raise ParameterError(f"sweep spec: unknown key(s) {sorted(extra)} in {where}; allowed: {sorted(allowed)}")
    key = entry.get("key")
    if not isinstance(key, str):
        raise ParameterError(f"sweep spec: {where} needs key = \"dotted.parameter\"")
    si_unit, convert = key_unit(key)

    def si(raw):
        return convert(raw)

    if "values" in entry:
        if {"start", "stop", "num", "spacing"} & set(entry):
            raise ParameterError(f"sweep spec: {where} gives values and start/stop/num; give one")
        raw = entry["values"]
        if not isinstance(raw, list) or not raw:
            raise ParameterError(f"sweep spec: {where} values must be a non-empty list")
        _limits().check_request(f"sweep spec: {where} ({key}) values", len(raw), BYTES_PER_VALUE, limit=MAX_VALUES,
                             unit="values")
        values = np.array([si(r) for r in raw])
    else:
        missing = [k for k in ("start", "stop", "num") if k not in entry]
        if missing:
            raise ParameterError(f"sweep spec: {where} ({key}) needs values, or start, stop and num "
                                 f"(missing {', '.join(missing)})")
        num = int(_number("vary", "num", entry["num"], integer=True))
        _limits().check_request(f"sweep spec: {where} ({key}) num = {num}", num, BYTES_PER_VALUE, limit=MAX_VALUES,
                             unit="values")
        start, stop = si(entry["start"]), si(entry["stop"])
        spacing = entry.get("spacing", "linear")
        if spacing == "linear":
            values = np.linspace(start, stop, num)
        elif spacing == "log":
            if start <= 0 or stop <= 0:
                raise ParameterError(f"sweep spec: {where} log spacing needs positive start and stop")
            values = np.geomspace(start, stop, num)
        else:
            raise ParameterError(f"sweep spec: {where} spacing must be 'linear' or 'log', got {spacing!r}")
    if not np.all(np.isfinite(values)):
        raise ParameterError(f"sweep spec: {where} ({key}) has a value that is not finite")
    _check_order(f"sweep spec: {where} ({key})", values, si_unit)
    dimension = entry.get("dimension", key)
    if not isinstance(dimension, str) or not dimension.strip():
        raise ParameterError(f"sweep spec: {where} dimension must be a name")
    written = entry["values"][0] if "values" in entry else entry["start"]
    display, factor = _display_unit(convert, written, si_unit)
    return Vary(key=key, dimension=dimension.strip(), values=tuple(float(v) for v in values),
                unit=si_unit, display_unit=display, display_factor=factor)


def _check_order(what: str, values: np.ndarray, si_unit: str) -> None:
    """Refuse a value given twice (``start = stop`` with ``num > 1``, or a list repeating
    one): its points would be computed again and the result's coordinate could not tell
    them apart. Warn about values that do not increase: they are run and stored in the
    order given (the result's coordinate decreases, or jumps back)."""
    unique, counts = np.unique(values, return_counts=True)
    if len(unique) < len(values):
        value = unique[np.argmax(counts)]
        raise ParameterError(f"{what} gives the value {value:.6g} {si_unit} {counts.max()} times (start = stop, "
                             f"or a value listed twice): give each value once")
    if len(values) > 1 and not np.all(np.diff(values) > 0):
        shape = "decrease" if np.all(np.diff(values) < 0) else "do not increase steadily"
        warnings.warn(f"{what} values {shape} (from {values[0]:.6g} to {values[-1]:.6g} {si_unit}): the points are "
                      f"run and stored in that order, and the result's coordinate with them",
                      stacklevel=3)


#: the number at the head of a quantity's text, e.g. ``3.5`` of ``"3.5 mm"``
_LEADING_NUMBER = re.compile(r"^\s*[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?\s*")


def _display_unit(convert, raw, si_unit: str) -> tuple[str, float]:
    """The unit a swept value was written in (``"3.5 mm"`` -> ``"mm"``) and the display
    value of one SI unit (1000); ``("", 1.0)`` for bare numbers, and the SI unit for units
    with an offset (degC)."""
    text = _LEADING_NUMBER.sub("", raw, count=1).strip() if isinstance(raw, str) else ""
    if not text or text == si_unit:
        return text, 1.0
    try:
        one, zero = (convert(f"{x} {text}") for x in (1, 0))
    except CamdynError:
        return si_unit, 1.0
    if zero != 0.0 or not math.isfinite(one) or one <= 0.0:
        return si_unit, 1.0
    return text, 1.0 / one


def spec_from_dict(spec: dict, base_dir: Path | None = None, name: str = "sweep") -> SweepSpec:
    """Validate a sweep given as nested dicts (the TOML's tables); see the module docstring."""
    base_dir = Path(base_dir or ".")
    if not isinstance(spec, dict):
        raise ParameterError(f"sweep spec: expected a dict of tables (as the TOML file's), got "
                             f"{type(spec).__name__} {spec!r:.60}")
    extra = set(spec) - _TABLES
    if extra:
        raise ParameterError(f"sweep spec: unknown table(s) {sorted(extra)}; allowed: {sorted(_TABLES)}")
    sys_t = _table(spec, "system", {"source", "set"})
    if "source" not in sys_t:
        raise ParameterError("sweep spec: [system] needs source = \"PRESET\" or \"path/to/system.toml\"")
    overrides = sys_t.get("set", {})
    if not isinstance(overrides, dict):
        raise ParameterError("sweep spec: [system] set must be a table of KEY = \"VALUE\"")
    family = family_of(str(sys_t["source"]), overrides, base_dir)

    entries = spec.get("vary", [])
    if not isinstance(entries, list) or not entries:
        raise ParameterError("sweep spec: give at least one [[vary]] table")
    vary = tuple(_values(i, e if isinstance(e, dict) else {}, family.key_unit) for i, e in enumerate(entries))
    keys = [v.key for v in vary]
    if len(set(keys)) != len(keys):
        raise ParameterError(f"sweep spec: a parameter is varied twice ({keys})")
    dims: dict[str, int] = {}
    for v in vary:
        n = dims.setdefault(v.dimension, len(v.values))
        if n != len(v.values):
            raise ParameterError(f"sweep spec: parameters zipped along {v.dimension!r} need equal numbers of "
                                 f"values ({n} and {len(v.values)} for {v.key})")
    points = math.prod(dims.values())
    if points > MAX_POINTS:
        raise ParameterError(f"sweep spec: {points:.3g} points ({' x '.join(str(n) for n in dims.values())}) is more "
                             f"than {MAX_POINTS:.0e}; at a millisecond or more each that is beyond any machine's "
                             f"reach: coarsen the grid or split the sweep")
    family.check_values(vary)

    run = {**_RUN_DEFAULTS, **family.run_defaults, **_table(spec, "run", set(_RUN_DEFAULTS))}
    if not family.atol and "atol" in spec.get("run", {}):
        raise ParameterError("sweep spec: [run] atol: a mechanism runs with its entry's own absolute tolerance "
                             "(1e-11); give rtol only")
    revolutions = int(_number("run", "revolutions", run["revolutions"], integer=True))
    discard = int(_number("run", "discard", run["discard"], integer=True, minimum=0))
    if discard >= revolutions:
        raise ParameterError(f"sweep spec: [run] discard ({discard}) must be less than revolutions ({revolutions})")
    samples = int(_number("run", "samples_per_revolution", run["samples_per_revolution"], integer=True))
    if samples < 8:
        raise ParameterError("sweep spec: [run] samples_per_revolution must be at least 8")
    rtol = _number("run", "rtol", run["rtol"])
    atol = _number("run", "atol", run["atol"])
    if rtol >= 1e-2:
        raise ParameterError(f"sweep spec: [run] rtol = {rtol:g} is too loose to mean anything (use < 1e-2)")
    limits = _limits()
    try:
        limits.check_tolerances(rtol, atol)
    except ParameterError as exc:
        raise ParameterError(f"sweep spec: [run] {exc}") from None
    chunk = int(_number("run", "chunk", run["chunk"], integer=True))
    # a worker holds a chunk's sampled runs at once: every revolution's samples of each point
    limits.check_request(f"sweep spec: [run] samples_per_revolution = {samples} over {revolutions} revolutions "
                         f"for each of a chunk's {chunk} points", chunk * revolutions * samples, BYTES_PER_SAMPLE,
                         limit=MAX_CHUNK_SAMPLES, unit="samples")

    met = _table(spec, "metrics", {"names", "harmonics"})
    allowed = list(family.default_metrics)
    names = met.get("names", allowed)
    if not isinstance(names, list) or not names:
        raise ParameterError("sweep spec: [metrics] names must be a non-empty list")
    unknown = [n for n in names if n not in allowed]
    if unknown:
        over = f" over a {family.kind} mechanism" if family.kind else ""
        raise ParameterError(f"sweep spec: [metrics] names: unknown metric(s){over} {unknown}; choose from {allowed}")
    harmonics = int(_number("metrics", "harmonics", met.get("harmonics", 10), integer=True))
    if 2 * harmonics >= samples:
        raise ParameterError(f"sweep spec: {harmonics} harmonics need samples_per_revolution > {2 * harmonics}")

    out = _table(spec, "output", {"path"})
    path = Path(str(out.get("path", f"{name}.nc")))   # a relative path: the working directory's
    if path.suffix not in (".nc", ".h5"):
        raise ParameterError(f"sweep spec: [output] path must end in .nc (netCDF4/HDF5), got {path.name!r}")
    result = SweepSpec(source=family.source, overrides=dict(overrides), system_toml=family.text, vary=vary,
                       dimensions=tuple(dims.items()), revolutions=revolutions, discard=discard,
                       samples_per_revolution=samples, rtol=rtol, atol=atol, chunk=chunk,
                       metrics=tuple(dict.fromkeys(names)), harmonics=harmonics, output=path, name=name,
                       mechanism=family.kind, runner=family.runner, _base=family.base)
    _check_result_size(result)
    return result


def checked_values(values) -> list[float]:
    """The values of one varied parameter that are checked before a sweep: all of them,
    sorted, up to :data:`CHECKED_VALUES`; of more, the ends and evenly spaced ones
    between (the check does not grow with the grid)."""
    values = sorted(set(values))
    if len(values) > CHECKED_VALUES:
        values = [values[int(i)] for i in np.unique(np.linspace(0, len(values) - 1, CHECKED_VALUES).round())]
    return values


def result_bytes(spec: SweepSpec) -> int:
    """Size of a sweep's result [B]: its metric variables and per-point solver bookkeeping
    (about 40 B)."""
    per_point = 40
    for _, sizes, dtype, _, _ in result_variables(spec).values():
        per_point += math.prod(sizes) * {"f8": 8, "i8": 8, "i2": 2, "i1": 1}.get(dtype, 8)
    return spec.points * per_point


def _check_result_size(spec: SweepSpec) -> None:
    """Refuse a sweep whose result (plus its checkpoints, as large again) does not fit on
    the output's disk; warn when it is large."""
    from camdyn.io.atomic import free_space

    needed = 2 * result_bytes(spec)
    folder = spec.output.parent if spec.output.parent.exists() else Path(".")
    free = free_space(folder)
    if 0 <= free < needed:
        raise ParameterError(f"sweep spec: the result and its checkpoints need about {needed / 1e9:.3g} GB but "
                             f"{folder} has {free / 1e9:.3g} GB free")
    if needed > 1e9:
        warnings.warn(f"the sweep's result and checkpoints will take about {needed / 1e9:.3g} GB on disk",
                      UserWarning, stacklevel=3)


def load_spec(path: str | Path) -> SweepSpec:
    """Read and validate a sweep spec TOML file (see the module docstring)."""
    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"sweep spec {str(path)!r} does not exist")
    try:
        table = loads_toml(read_toml_text(path, f"sweep spec {path.name}"), f"sweep spec {path.name}")
    except UnicodeDecodeError as exc:
        raise ParameterError(f"sweep spec {path.name}: not UTF-8 text (byte {exc.object[exc.start]:#04x} at offset "
                             f"{exc.start}); a sweep spec is TOML, saved as UTF-8") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"sweep spec {path.name}: not valid TOML ({exc})") from None
    return spec_from_dict(table, base_dir=path.parent, name=path.stem)
