"""The bundled presets: every configuration shipped in ``camdyn/params/presets`` (the
thesis's rigs, the translating and rocking followers on cam profiles, the mechanisms),
its kind, and the resolver that turns a preset's name into its file.

Every reader of a configuration (:func:`camdyn.params.config.read_table`,
:func:`camdyn.params.profiles.read_translating`, :func:`camdyn.params.rocking.read_rocking`,
:func:`camdyn.params.mechanism.read_mechanism` and the tests of which family a source is)
passes its source through :func:`resolve`, so a preset's name works wherever a file path
does (``camdyn simulate drum-brake``, ``[system] source = "drum-brake"`` in a sweep
spec). A name is looked up before a file of that name in the working directory.
"""

from __future__ import annotations

import difflib
import functools
import tomllib
from importlib import resources
from pathlib import Path

from camdyn.errors import PresetError
from camdyn.params.toml_text import loads_toml

__all__ = ["KINDS", "preset_names", "preset_file", "preset_kind", "preset_meta", "presets_of_kind", "resolve",
           "unknown_preset"]

#: The kinds of configuration, as ``camdyn presets`` lists them: the thesis's rocking
#: flat-faced follower on its ellipse, the same on a cam profile, a translating follower,
#: a rocking roller or knife edge, and the mechanisms (``[mechanism] kind``).
KINDS = ("cam-follower", "cam-follower, profile", "translating", "rocking", "driven-cam", "flexible-pivot",
         "two-followers")
_PACKAGE = "camdyn.params.presets"


@functools.cache
def _folder() -> Path:
    """The folder of the bundled presets (package data; an installation unpacked on disk)."""
    return Path(str(resources.files(_PACKAGE)))


@functools.cache
def preset_names() -> tuple[str, ...]:
    """Names of every bundled preset (the file names without ``.toml``), sorted."""
    return tuple(sorted(p.name[:-5] for p in _folder().iterdir() if p.name.endswith(".toml")))


def unknown_preset(name: str) -> PresetError:
    """The error for a name that is neither a preset nor a file, naming the close presets."""
    close = difflib.get_close_matches(name, preset_names(), n=3, cutoff=0.5)
    hint = f"; did you mean {', '.join(close)}?" if close else "; 'camdyn presets' lists them"
    return PresetError(f"no preset named {name!r} and no such configuration file{hint}")


def preset_file(name: str) -> Path:
    """The TOML file of the bundled preset ``name``.

    Raises
    ------
    PresetError
        For a name that is no preset, suggesting close ones.
    """
    if name not in preset_names():
        raise unknown_preset(name)
    return _folder() / f"{name}.toml"


def resolve(source: str | Path) -> str | Path:
    """The file of a preset's name; any other source (a path) unchanged."""
    return preset_file(str(source)) if isinstance(source, str) and source in preset_names() else source


@functools.cache
def _table(name: str) -> dict:
    try:
        return loads_toml(preset_file(name).read_text(encoding="utf-8"), name)
    except tomllib.TOMLDecodeError as exc:   # a broken package, not a user's error
        raise PresetError(f"bundled preset {name!r} is not valid TOML ({exc})") from None


def preset_meta(name: str) -> dict:
    """The ``[preset]`` table of a bundled preset (``name``, ``description``,
    ``citation``, ``provenance``; each may be missing)."""
    meta = _table(name).get("preset", {})
    return dict(meta) if isinstance(meta, dict) else {}


def preset_kind(name: str) -> str:
    """The kind of a bundled preset, one of :data:`KINDS`: a mechanism's ``[mechanism]
    kind``, the ``[follower] kind`` (``translating``, ``rocking``), else the thesis's
    rocking flat-faced follower, on its ellipse or (with a ``[profile]`` table) a profile."""
    table = _table(name)
    mechanism = table.get("mechanism")
    if isinstance(mechanism, dict):
        return str(mechanism.get("kind", ""))
    follower = table.get("follower")
    kind = follower.get("kind") if isinstance(follower, dict) else None
    if kind is not None:
        return str(kind)
    return "cam-follower, profile" if "profile" in table else "cam-follower"


def presets_of_kind(*kinds: str) -> list[str]:
    """Names of the bundled presets of the given kinds (:data:`KINDS`), sorted."""
    return [name for name in preset_names() if preset_kind(name) in kinds]
