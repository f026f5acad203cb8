"""Tabulated cam profiles in CSV with units in the header, and the loader of a
translating-follower configuration (TOML, its CSV profile, the follower built from them).

CSV layout
----------
Comment lines start with ``#``; the first other line is the header; then one row per
sample, comma-separated (a UTF-8 byte-order mark and UTF-16 text are accepted, as for
records: :func:`camdyn.io.csv_records.decode_text`)::

    # eccentric circle R = 25 mm, e = 5 mm, flat face
    angle [deg],lift [mm]
    0,10
    10,9.92404
    ...

- the first column is the cam angle, ``angle [deg]`` or ``angle [rad]`` (any angle unit
  pint knows);
- the second is either ``lift [mm]``, the follower's lift s from the base circle, or
  ``radius [mm]``, the distance from the cam's axis to the follower's reference point along
  its line: ``r_base + s`` for a knife edge or a flat face (the face's distance from the
  axis), ``r_base + r_r + s`` for a roller's centre. A radius is accepted only for an
  in-line follower (offset 0). Any length unit pint knows; the unit is required.
- the angles must start at 0 and be equally spaced over one revolution, ``360 i / n``
  deg; a last row at 360 deg repeating the first sample is allowed (and dropped). Each
  angle may be off its place by at most :data:`ANGLE_TOLERANCE` of the spacing (numbers
  written with few digits); a row further off is refused, naming its line.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from camdyn.errors import DataError, GeometryError, ParameterError
from camdyn.io.csv_records import decode_text
from camdyn.io.record_fields import unit_factor
from camdyn.params.profiles import read_translating
from camdyn.simulation.translating import follower_from_spec

__all__ = ["read_lift_table", "load_translating", "ANGLE_TOLERANCE", "MINIMUM_ROWS"]

#: Largest distance of a sample's angle from its place ``2 pi i / n``, as a fraction of the
#: spacing ``2 pi / n`` [-].
ANGLE_TOLERANCE = 1e-3
#: Fewest samples over one revolution (the periodic spline's own minimum).
MINIMUM_ROWS = 8
_HEADER_FIELD = re.compile(r"\s*\"?\s*(?P<name>[A-Za-z_]+)\s*[\[(](?P<unit>[^\])]+)[\])]\s*\"?\s*")
_COLUMNS = {"angle": "rad", "lift": "m", "radius": "m"}


def _header(path: Path, line: str, number: int) -> tuple[str, float, float]:
    """The second column's name and the factors of both columns to radians and metres."""
    fields = line.rstrip().rstrip(",").split(",")
    expected = "expected 'angle [deg],lift [mm]' or 'angle [deg],radius [mm]'"
    if len(fields) != 2:
        raise DataError(f"{path}: line {number}: the header has {len(fields)} columns; {expected}")
    parsed = []
    for field in fields:
        match = _HEADER_FIELD.fullmatch(field)
        if match is None:
            raise DataError(f"{path}: line {number}: cannot read the column {field.strip()!r}: each column is "
                            f"named with its unit in brackets; {expected}")
        parsed.append((match["name"].lower(), match["unit"].strip()))
    (first, angle_unit), (second, length_unit) = parsed
    if first != "angle" or second not in ("lift", "radius"):
        raise DataError(f"{path}: line {number}: the columns are {first!r} and {second!r}; {expected}")
    factors = []
    for (name, unit) in parsed:
        try:
            factors.append(unit_factor(unit, _COLUMNS[name], f"the {name} column", str(path)))
        except DataError:
            raise DataError(f"{path}: line {number}: the {name} column's unit {unit!r} is not "
                            f"{'an angle' if name == 'angle' else 'a length'}") from None
    return second, factors[0], factors[1]


def _rows(path: Path, lines: list[str], start: int) -> tuple[list[int], np.ndarray]:
    numbers, values = [], []
    for number, line in enumerate(lines[start:], start=start + 1):
        text = line.strip().rstrip(",")
        if not text or text.startswith("#"):
            continue
        fields = text.split(",")
        if len(fields) != 2:
            raise DataError(f"{path}: line {number} has {len(fields)} values; the header names 2 columns")
        try:
            row = [float(f) for f in fields]
        except ValueError:
            raise DataError(f"{path}: line {number}: {text[:40]!r} is not two numbers") from None
        if not all(math.isfinite(v) for v in row):
            raise DataError(f"{path}: line {number}: the values must be finite, got {text!r}")
        numbers.append(number)
        values.append(row)
    return numbers, np.array(values, dtype=float).reshape(-1, 2)


def _spacing(path: Path, numbers: list[int], angles: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The samples over one revolution, a closing row at 2 pi dropped; refuses an angle off
    its place ``2 pi i / n``, naming its line."""
    n = angles.size
    closing = n > 1 and abs(angles[-1] - 2.0 * math.pi) <= ANGLE_TOLERANCE * 2.0 * math.pi / (n - 1)
    if closing:
        scale = max(float(np.max(np.abs(values))), 1e-300)
        if abs(values[-1] - values[0]) > 1e-9 * scale:
            raise DataError(f"{path}: line {numbers[-1]}: the row at 360 deg must repeat the one at 0 deg "
                            f"(line {numbers[0]}), but its value differs by {values[-1] - values[0]:.3g} m")
        angles, values, n = angles[:-1], values[:-1], n - 1
    if n < MINIMUM_ROWS:
        raise DataError(f"{path}: {n} samples; a tabulated profile needs at least {MINIMUM_ROWS} over one revolution")
    step = 2.0 * math.pi / n
    places = step * np.arange(n)
    off = np.abs(angles - places)
    worst = int(np.argmax(off))
    if off[worst] > ANGLE_TOLERANCE * step:
        raise DataError(f"{path}: line {numbers[worst]}: angle {math.degrees(angles[worst]):.6g} deg, but {n} "
                        f"equally spaced samples over one revolution put sample {worst} at "
                        f"{math.degrees(places[worst]):.6g} deg (the angles must start at 0 and step by "
                        f"{math.degrees(step):.6g} deg)")
    return values


def read_lift_table(path: str | Path, base_radius: float, face: str = "flat", roller_radius: float = 0.0,
                    offset: float = 0.0) -> np.ndarray:
    """Read a tabulated cam profile (see the module description).

    Parameters
    ----------
    path : str or Path
        The CSV file.
    base_radius : float
        r_base [m]: a ``radius`` column is turned into the lift ``radius - r_base``.
    face : str
        ``"flat"``, ``"knife"`` or ``"roller"``.
    roller_radius : float
        r_r [m], subtracted too from a ``radius`` column for a roller.
    offset : float
        epsilon [m] of the follower's line; a ``radius`` column needs 0.

    Returns
    -------
    ndarray (n,)
        The lift s [m] at the cam angles ``2 pi i / n`` [rad], ``i = 0 ... n - 1``.
    """
    path = Path(path)
    if not path.is_file():
        raise DataError(f"the profile file {path} does not exist")
    try:
        lines = decode_text(path, path.read_bytes())
    except OSError as exc:
        raise DataError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    start = next((i for i, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")), None)
    if start is None:
        raise DataError(f"{path}: no header row; expected 'angle [deg],lift [mm]'")
    column, angle_factor, length_factor = _header(path, lines[start], start + 1)
    numbers, table = _rows(path, lines, start + 1)
    if table.shape[0] == 0:
        raise DataError(f"{path}: the header (line {start + 1}) is followed by no samples")
    values = _spacing(path, numbers, table[:, 0] * angle_factor, table[:, 1] * length_factor)
    if column == "radius":
        if offset != 0.0:
            raise DataError(f"{path}: a radius column is read only for an in-line follower (offset 0); give "
                            "the lift instead")
        values = values - base_radius - (roller_radius if face == "roller" else 0.0)
    low = int(np.argmin(values))
    if values[low] < -1e-9 * max(base_radius, 1e-300):
        raise DataError(f"{path}: the {column} at {math.degrees(2.0 * math.pi * low / values.size):.6g} deg "
                        f"puts the follower {-values[low]:.4g} m inside the base circle (radius {base_radius} m)")
    return np.maximum(values, 0.0)


def load_translating(source: str | Path, overrides: dict | None = None):
    """A translating follower and its configuration from a preset name or TOML file.

    Parameters
    ----------
    source : str or Path
        Preset name (``"alzate"``) or TOML file (:mod:`camdyn.params.profiles`).
    overrides : dict, optional
        Dotted key -> value as text with its unit (``{"spring.preload": "150 N"}``).

    Returns
    -------
    follower : TranslatingFollower
        With its profile built and checked (a tabulated profile read from its CSV file).
    spec : TranslatingSpec
        The configuration in SI units (its ``speed`` [rad/s] and ``phase`` [rad] are the
        motion's).
    """
    spec = read_translating(source, overrides)
    lift = None
    if spec.profile_kind == "tabulated":
        lift = read_lift_table(spec.file, spec.base_radius, spec.face, spec.roller_radius, spec.offset)
    try:
        return follower_from_spec(spec, lift), spec
    except (GeometryError, ParameterError) as exc:
        raise type(exc)(f"{spec.name}: {exc}") from None
