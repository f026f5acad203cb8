"""The ``[friction]`` keys of a translating follower's configuration
(:mod:`camdyn.params.profiles`): Coulomb friction at its cam contact and the roller's spin
inertia (the model: :mod:`camdyn.model.sliding_follower`), refused with the key named
where they mean nothing."""

from __future__ import annotations

from camdyn.errors import ParameterError

__all__ = ["FRICTION_SCHEMA", "check_friction"]

#: Dotted key -> (unit, default, meaning), as :data:`camdyn.params.profiles.SCHEMA`; the
#: kinetic coefficient's default (None) is the static one.
FRICTION_SCHEMA = {
    "friction.static": ("", 0.0, "static friction coefficient mu_s at the cam contact (rigid contact law)"),
    "friction.kinetic": ("", None, "kinetic friction coefficient mu_k <= mu_s (default mu_s)"),
    "friction.roller_inertia": ("kg*m**2", 0.0, "the roller's moment of inertia J_r about its axle (roller face)"),
}


def check_friction(values: dict) -> None:
    """Refuse negative coefficients or inertia, a kinetic coefficient above the static one,
    friction under a contact law other than rigid, and a roller inertia without a roller
    (``values``: dotted key -> SI value, as read)."""
    for key in FRICTION_SCHEMA:
        if values.get(key) is not None and values[key] < 0.0:
            raise ParameterError(f"{key} must not be negative, got {values[key]!r}")
    static, kinetic = values["friction.static"], values["friction.kinetic"]
    if kinetic is not None and kinetic > static:
        raise ParameterError(f"friction.kinetic ({kinetic}) must not exceed friction.static ({static})")
    if static > 0.0 and values["contact.law"] != "rigid":
        raise ParameterError(f"friction.static: friction at the follower needs contact.law = 'rigid', "
                             f"not {values['contact.law']!r}")
    face = values["follower.face"]
    if values["friction.roller_inertia"] > 0.0 and face != "roller":
        raise ParameterError(f"friction.roller_inertia: a {face} follower has no roller to spin")
