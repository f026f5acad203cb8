"""The parameter schema: each dataclass field declares its unit, key and meaning once.

A field of a parameter dataclass (:mod:`camdyn.params.system`) is declared with
:func:`parameter`, which records in the field's metadata the unit its SI value is stored
in, what it means and the unit configuration files are written in. A field of
:class:`~camdyn.params.system.System` holding one of those dataclasses is declared with
:func:`group`: its name is the TOML table (``[cam]``). :func:`parameters` walks them and
returns one :class:`Parameter` per dotted key (``cam.runout``), in the dataclasses' order.
The configuration's key list (:data:`camdyn.params.config.SCHEMA`), its reader and writer,
and the packing of the compiled parameter vector (:mod:`camdyn.model.layout`) all read it.

Units are pint text for quantities (``"m"``, ``"kg*m**2"``, ``""`` for dimensionless
numbers), or one of the kinds in :data:`KINDS` for values that are not quantities.
"""

from __future__ import annotations

import operator
from dataclasses import MISSING, dataclass, field, fields
from functools import lru_cache

__all__ = ["KINDS", "Parameter", "parameter", "group", "groups", "parameters", "parameter_index"]

#: Units that are kinds of value rather than units: text, true/false, integer, a cam speed
#: (Hz, rpm or rad/s, stored in Hz) and the damping coefficient beta, whose unit depends on
#: the damping law (:mod:`camdyn.params.laws`).
KINDS = ("str", "bool", "int", "speed", "law")


@dataclass(frozen=True)
class Parameter:
    """One configurable parameter.

    Attributes
    ----------
    key : str
        Dotted key, ``table.name`` (``"cam.runout"``).
    path : tuple of str
        Attributes leading from a :class:`~camdyn.params.system.System` to the value
        (``("cam", "runout")``; ``("gravity",)`` for ``environment.gravity``).
    unit : str
        Unit of the stored SI value for pint, or one of :data:`KINDS`.
    meaning : str
        What the parameter is, for ``camdyn presets keys`` and error messages.
    written : str
        Unit the value is written in by :func:`camdyn.params.config.system_to_toml`.
    required : bool
        True when the field has no default.
    optional : bool
        True when None is a valid value (then the key is written only when set).
    default : object
        The field's default [unit]; ``dataclasses.MISSING`` when ``required``.
    """

    key: str
    path: tuple[str, ...]
    unit: str
    meaning: str
    written: str
    required: bool
    optional: bool
    default: object = MISSING

    @property
    def name(self) -> str:
        """The field's name in its dataclass."""
        return self.path[-1]

    @property
    def getter(self) -> operator.attrgetter:
        """Function reading the value [unit] from a system: ``parameter.getter(system)``."""
        return operator.attrgetter(".".join(self.path))


def parameter(unit: str, meaning: str, default=MISSING, *, written: str | None = None, table: str = ""):
    """Declare a dataclass field as a parameter.

    Parameters
    ----------
    unit : str
        Unit of the stored SI value for pint (``""`` when dimensionless) or one of :data:`KINDS`.
    meaning : str
        What it is, with its thesis symbol and equation.
    default : optional
        Default value; none makes the parameter required.
    written : str, optional
        Unit the writer uses; by default ``unit`` with ``**`` written as ``^``.
    table : str
        TOML table of a parameter declared directly on the system (``"environment"``).
    """
    if written is None:
        written = unit.replace("**", "^")
    metadata = {"unit": unit, "meaning": meaning, "written": written, "table": table}
    return field(default=default, metadata=metadata)


def group(cls: type, *, required: bool = False):
    """Declare a system field holding the parameter dataclass ``cls``; the field's name is
    the TOML table of its parameters. A group that is not ``required`` defaults to ``cls()``."""
    if required:
        return field(metadata={"group": cls})
    return field(default_factory=cls, metadata={"group": cls})


def groups(system_cls: type) -> dict[str, type]:
    """Field name -> parameter dataclass of each group of ``system_cls``, in order."""
    return {f.name: f.metadata["group"] for f in fields(system_cls) if "group" in f.metadata}


def _declared(f, key: str, path: tuple[str, ...]) -> Parameter:
    meta = f.metadata
    required = f.default is MISSING and f.default_factory is MISSING
    return Parameter(key=key, path=path, unit=meta["unit"], meaning=meta["meaning"], written=meta["written"],
                     required=required, optional=f.default is None, default=f.default)


@lru_cache(maxsize=4)
def parameters(system_cls: type) -> tuple[Parameter, ...]:
    """Every parameter of ``system_cls``, group by group, in the order the fields are declared."""
    out = []
    for f in fields(system_cls):
        if "group" in f.metadata:
            out += [_declared(g, f"{f.name}.{g.name}", (f.name, g.name)) for g in fields(f.metadata["group"])]
        elif "unit" in f.metadata:
            out.append(_declared(f, f"{f.metadata['table']}.{f.name}", (f.name,)))
    return tuple(out)


@lru_cache(maxsize=4)
def parameter_index(system_cls: type) -> dict[str, Parameter]:
    """Dotted key -> :class:`Parameter` of ``system_cls``."""
    return {p.key: p for p in parameters(system_cls)}
