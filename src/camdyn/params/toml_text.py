"""Reading TOML text: within bounds, and flattened into dotted keys.

Within bounds: a configuration, profile, mechanism or sweep spec is
a few kilobytes nested a few levels, and Python's TOML parser recurses once per level, so
deeper or longer text is refused with a clear message instead of a ``RecursionError``."""

from __future__ import annotations

import tomllib

from camdyn.errors import ParameterError

__all__ = ["loads_toml", "read_toml_text", "flatten", "MAX_TOML_DEPTH", "MAX_TOML_CHARS"]

#: Deepest nesting of tables, arrays and inline tables a TOML file camdyn reads may have
#: [-] (camdyn's own files nest three deep; Python's TOML parser recurses once per level).
MAX_TOML_DEPTH = 32
#: Longest TOML file camdyn reads [characters]: a configuration or sweep spec is a few
#: kilobytes; 10 MB is no configuration.
MAX_TOML_CHARS = 10_000_000


def read_toml_text(path, source="TOML") -> str:
    """The text of the TOML file ``path`` (UTF-8), read no further than
    :data:`MAX_TOML_CHARS` characters: a longer file (a record or an archive given as a
    configuration) is refused with a :class:`ParameterError` naming ``source`` before it
    is read whole into memory. ``OSError`` and ``UnicodeDecodeError`` pass to the caller."""
    with open(path, encoding="utf-8") as fh:
        text = fh.read(MAX_TOML_CHARS + 1)
    if len(text) > MAX_TOML_CHARS:
        raise ParameterError(f"{source}: more than {MAX_TOML_CHARS} characters of TOML, the most a configuration "
                             f"may have")
    return text


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
