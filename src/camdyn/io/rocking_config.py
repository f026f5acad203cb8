"""The loader of a rocking roller or knife-edge follower's configuration: the TOML file
(:mod:`camdyn.params.rocking`), a tabulated profile's CSV file
(:func:`camdyn.io.lift_table.read_lift_table`), and the follower built from them."""

from __future__ import annotations

from pathlib import Path

from camdyn.errors import GeometryError, ParameterError
from camdyn.io.lift_table import read_lift_table
from camdyn.params.rocking import read_rocking
from camdyn.simulation.rocking_roller import rocking_from_spec

__all__ = ["load_rocking"]


def load_rocking(source: str | Path, overrides: dict | None = None):
    """A rocking follower and its configuration from a TOML file.

    Parameters
    ----------
    source : str or Path
        The TOML file (``[follower] kind = "rocking"``).
    overrides : dict, optional
        Dotted key -> value as text with its unit (``{"spring.preload": "0.06 N*m"}``).

    Returns
    -------
    follower : RockingFollower
        With its profile and geometry built and checked.
    spec : RockingSpec
        The configuration in SI units (``spec.profile.speed`` [rad/s] and
        ``spec.profile.phase`` [rad] are the motion's).
    """
    spec = read_rocking(source, overrides)
    profile = spec.profile
    lift = None
    if profile.profile_kind == "tabulated":
        lift = read_lift_table(profile.file, profile.base_radius, profile.face, profile.roller_radius,
                               profile.offset)
    try:
        return rocking_from_spec(spec, lift), spec
    except (GeometryError, ParameterError) as exc:
        raise type(exc)(f"{spec.name}: {exc}") from None
