"""The ``[profile]`` table of a rocking follower's configuration, read by the translating
follower's reader (:func:`camdyn.params.profiles.spec_from_table`).

Both rocking followers describe their cam with the keys of a translating follower's
profile (:data:`camdyn.params.profiles.PROFILE_KINDS`), plus ``profile.face``, the
follower the profile was made for (``"flat"`` by default), and ``profile.offset``, that
follower's offset [m]. :func:`profile_spec` passes them to the translating follower's
reader with placeholder dynamics, so that they are checked key by key, with their units,
as there; the profile itself is built from the returned spec by
:func:`camdyn.simulation.translating.follower_from_spec` (this layer knows no cam model).
"""

from __future__ import annotations

from pathlib import Path

from camdyn.errors import ParameterError
from camdyn.params.profiles import TranslatingSpec, spec_from_table

__all__ = ["PROFILE_EXTRA_KEYS", "profile_spec"]

#: Keys of a rocking follower's ``[profile]`` besides the translating follower's profile keys.
PROFILE_EXTRA_KEYS = ("profile.face", "profile.offset")


def profile_spec(flat: dict, face: str, roller_radius: float, name: str, folder: Path | None) -> TranslatingSpec:
    """The profile (and motion) of a rocking follower through the translating follower's
    reader: its follower is the one the profile was made for, its dynamics placeholders.

    Parameters
    ----------
    flat : dict
        The ``profile.*`` keys (and ``motion.*`` keys, read as a translating follower's)
        -> raw values as written in the file (``"30 mm"``).
    face : str
        The rocking follower's face: ``"flat"``, ``"roller"`` or ``"knife"``.
    roller_radius : float
        Its roller radius r_r [m] (0 unless a roller).
    name : str
        The configuration's name.
    folder : Path or None
        The folder a relative ``profile.file`` is read from (the TOML file's folder).

    Returns
    -------
    TranslatingSpec
        The profile's keys in SI units; its follower's mass, spring and contact are placeholders.
    """
    made_for = str(flat.get("profile.face", "flat"))
    table = {key: value for key, value in flat.items() if key not in PROFILE_EXTRA_KEYS}
    table.update({"follower.kind": "translating", "follower.face": made_for, "follower.mass": "1 kg",
                  "spring.stiffness": "0 N/m", "spring.preload": "0 N"})
    if "profile.offset" in flat:
        table["follower.offset"] = flat["profile.offset"]
    if made_for == "roller":
        table["follower.roller_radius"] = f"{roller_radius} m"
    if made_for != "flat" and made_for != face:
        raise ParameterError(f"profile.face {made_for!r}: a profile made for a knife edge or a roller is that "
                             f"follower's pitch curve; it takes a rocking {made_for} only, not a {face} (a profile "
                             "made for a flat face takes either)")
    return spec_from_table(table, name=name, folder=folder)
