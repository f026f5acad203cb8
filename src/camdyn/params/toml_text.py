"""Reading TOML text: within bounds, and flattened into dotted keys.

Within bounds: a configuration, profile, mechanism or sweep spec is
a few kilobytes nested a few levels, and Python's TOML parser recurses once per level, so
deeper or longer text is refused with a clear message instead of a ``RecursionError``."""

from __future__ import annotations

import tomllib

from camdyn.errors import ParameterError

__all__ = ["loads_toml", "flatten", "MAX_TOML_DEPTH", "MAX_TOML_CHARS"]

#: Deepest nesting of tables, arrays and inline tables a TOML file camdyn reads may have
#: [-] (camdyn's own files nest three deep; Python's TOML parser recurses once per level).
MAX_TOML_DEPTH = 32
#: Longest TOML file camdyn reads [characters]: a configuration or sweep spec is a few
#: kilobytes; 10 MB is no configuration.
MAX_TOML_CHARS = 10_000_000


def loads_toml(text: str, source="TOML") -> dict:
    """``tomllib.loads(text)`` bounded: a text longer than :data:`MAX_TOML_CHARS` or
    nested deeper than :data:`MAX_TOML_DEPTH` levels is refused with a
    :class:`ParameterError` naming ``source`` (``tomllib.TOMLDecodeError`` passes to the
    caller)."""
    deep = ParameterError(f"{source}: TOML nested deeper than {MAX_TOML_DEPTH} levels (tables, arrays and "
                          f"inline tables inside one another); a configuration nests a few levels")
    if len(text) > MAX_TOML_CHARS:
        raise ParameterError(f"{source}: {len(text)} characters of TOML is more than the {MAX_TOML_CHARS} a "
                             f"configuration may have")
    try:
        table = tomllib.loads(text)
    except RecursionError:
        raise deep from None
    stack = [(table, 1)]
    while stack:
        value, depth = stack.pop()
        if depth > MAX_TOML_DEPTH:
            raise deep
        items = value.values() if isinstance(value, dict) else value
        stack.extend((item, depth + 1) for item in items if isinstance(item, (dict, list)))
    return table


def flatten(table: dict, prefix: str = "") -> dict:
    """Flatten nested TOML tables into dotted keys."""
    out = {}
    for key, value in table.items():
        dotted = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(flatten(value, dotted + "."))
        else:
            out[dotted] = value
    return out
