"""The loader of the rocking flat-faced follower's configuration (the thesis model): the
TOML file or preset (:mod:`camdyn.params.config`), and, when the file has a ``[profile]``
table, the cam profile built from it (a tabulated profile's CSV file read by
:func:`camdyn.io.lift_table.read_lift_table`) in place of the ellipse::

    [profile]
    kind = "rise-return"
    base_radius = "15.75 mm"
    segments = [{law = "cycloidal", span = "120 deg", lift = "3.5 mm"},
                {law = "dwell", span = "60 deg"},
                {law = "cycloidal", span = "120 deg", lift = "-3.5 mm"},
                {law = "dwell", span = "60 deg"}]

The table takes the keys of a translating follower's profile
(:data:`camdyn.params.config.PROFILE_KEYS`), checked by the same reader; the profile
must be made for a flat face.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from camdyn.errors import GeometryError, ParameterError
from camdyn.params.config import read_system
from camdyn.params.system import System

__all__ = ["load_system"]


def load_system(source: str | Path, overrides: dict | None = None) -> System:
    """Load a preset or TOML file of the rocking flat-faced follower, with dotted-key
    overrides; a ``[profile]`` table becomes the system's cam profile.

    Parameters
    ----------
    source : str or Path
        Preset name (:func:`camdyn.params.config.list_presets`) or TOML file.
    overrides : dict, optional
        Dotted key -> value as text with its unit (``{"cam.pivot_x": "1 mm"}``,
        ``{"profile.base_radius": "16 mm"}``).

    Returns
    -------
    System
        With ``profile`` set (a :class:`camdyn.model.profiles.Profile` made for a flat
        face, checked for a convex cam) when the file has a ``[profile]`` table.
    """
    system, spec = read_system(source, overrides)
    if spec is None:
        return system
    # the profile's builders are imported only for a profile: loading the ellipse stays light
    from camdyn.io.lift_table import read_lift_table
    from camdyn.simulation.translating import follower_from_spec

    lift = None
    if spec.profile_kind == "tabulated":
        lift = read_lift_table(spec.file, spec.base_radius, spec.face, spec.roller_radius, spec.offset)
    try:
        profile = follower_from_spec(spec, lift).profile
        return dataclasses.replace(system, profile=profile)
    except (GeometryError, ParameterError) as exc:
        raise type(exc)(f"{system.name}: [profile]: {exc}") from None
