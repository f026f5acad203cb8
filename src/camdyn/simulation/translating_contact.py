"""The Hertz contact law of a translating follower (law 2 of
:mod:`camdyn.model.translating_follower`): materials, geometry and damping law, checked
when built, and packed into the model's parameter slots.

The geometry follows the follower's face (K. L. Johnson, *Contact Mechanics*, Cambridge
University Press 1985, sections 4.2-4.3):

- a flat face on a cam of width ``l`` touches it along a line: line contact, ``F_k =
  (pi/4) E* l delta``;
- a cylindrical roller of width ``l``: line contact too (the default for a roller);
- a crowned roller (``geometry = "point"``): point contact with ``1/rho_e = 1/rho_cam +
  1/r_r``;
- a knife edge with a rounded tip of radius ``r_f``: point contact with ``1/rho_e =
  1/rho_cam + 1/r_f``. A sharp knife edge (``r_f = 0``) has no Hertz stiffness and is
  refused.

The damping laws are those of :mod:`camdyn.model.contact`: ``none``, ``viscous`` (``c``
[N s/m] given directly) and the restitution-parameterised laws (``hunt-crossley``,
``lankarani-nikravesh``, ``flores``, ``gonthier``, ``hu-guo``) with the coefficient of
restitution ``e``. The laws whose ``beta`` has a law-dependent unit are not offered here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from camdyn.errors import GeometryError, ParameterError
from camdyn.model import contact as hertz
from camdyn.model import translating_follower as model
from camdyn.params.laws import lookup
from camdyn.params.profiles import HERTZ_DAMPING_LAWS as OFFERED_DAMPING

__all__ = ["HertzContact", "GEOMETRIES", "OFFERED_DAMPING"]

GEOMETRIES = ("line", "point")
#: Cam angles [rad] at which the equivalent radius of point contact is checked.
_CHECK_ANGLES = 7200


@dataclass(frozen=True)
class HertzContact:
    """Materials, geometry and damping of a Hertz contact, validated when built.

    Attributes
    ----------
    cam_modulus, follower_modulus : float
        Young's moduli ``Y_c`` and ``Y_f`` [Pa] (``contact.cam_modulus``,
        ``contact.follower_modulus``).
    cam_poisson, follower_poisson : float
        Poisson's ratios ``nu_c`` and ``nu_f`` [-], in (-1, 0.5).
    geometry : str
        ``"line"``, ``"point"``, or ``""`` for the face's own: point for a knife edge, line
        otherwise.
    width : float
        Contact length ``l`` [m] of line contact (the cam's or the roller's width).
    tip_radius : float
        Tip radius ``r_f`` [m] of a knife edge (point contact); a roller's point contact
        uses its roller radius.
    damping_law : str
        One of :data:`OFFERED_DAMPING`.
    damping : float
        ``c`` [N s/m] of the viscous law.
    restitution : float
        Coefficient of restitution ``e`` [-] of the restitution laws.
    reference_velocity : float
        Smallest approach velocity the restitution laws divide by [m/s] (used when a run
        starts in contact, with no approach to measure).
    """

    cam_modulus: float = 210e9
    cam_poisson: float = 0.3
    follower_modulus: float = 210e9
    follower_poisson: float = 0.3
    geometry: str = ""
    width: float = 0.0
    tip_radius: float = 0.0
    damping_law: str = "none"
    damping: float = 0.0
    restitution: float = 1.0
    reference_velocity: float = 1e-3

    def __post_init__(self):
        for name in ("cam_modulus", "cam_poisson", "follower_modulus", "follower_poisson", "width", "tip_radius",
                     "damping", "restitution", "reference_velocity"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ParameterError(f"contact.{name} must be a finite number, got {value!r}")
        for name in ("cam_modulus", "follower_modulus", "reference_velocity"):
            if getattr(self, name) <= 0.0:
                raise ParameterError(f"contact.{name} must be positive, got {getattr(self, name)!r}")
        for name in ("cam_poisson", "follower_poisson"):
            if not -1.0 < getattr(self, name) < 0.5:
                raise ParameterError(f"contact.{name} must lie in (-1, 0.5), got {getattr(self, name)!r}")
        for name in ("width", "tip_radius", "damping"):
            if getattr(self, name) < 0.0:
                raise ParameterError(f"contact.{name} must not be negative, got {getattr(self, name)!r}")
        if self.geometry not in GEOMETRIES + ("",):
            raise ParameterError(f"contact.geometry must be one of {', '.join(GEOMETRIES)}, got {self.geometry!r}")
        if self.damping_law not in OFFERED_DAMPING:
            raise ParameterError(f"contact.damping_law must be one of {', '.join(OFFERED_DAMPING)} for a "
                                 f"translating follower, got {self.damping_law!r}")
        row = lookup(self.damping_law)
        if row.restitution is not None and not max(row.lowest_restitution, 0.0) < self.restitution <= 1.0:
            raise ParameterError(f"contact.restitution must lie in ({row.lowest_restitution:g}, 1] for the "
                                 f"{self.damping_law} law, got {self.restitution!r}")

    @property
    def modulus(self) -> float:
        """Effective modulus ``E*`` [Pa] (:func:`camdyn.model.contact.effective_modulus`)."""
        return hertz.effective_modulus(self.cam_modulus, self.cam_poisson, self.follower_modulus,
                                       self.follower_poisson)

    def geometry_of(self, face: str) -> str:
        """The contact's geometry on a follower with ``face``: the one given, or the face's."""
        return self.geometry or ("point" if face == "knife" else "line")

    def follower_radius(self, profile) -> float:
        """``r_f`` [m] of point contact: the knife edge's tip or the roller's radius."""
        return self.tip_radius if profile.follower == "knife" else profile.roller_radius

    def check(self, profile, curvature=None) -> None:
        """Refuse, before any work, a geometry the follower's face does not allow: point
        contact of a flat face, line contact of a knife edge, a sharp knife edge, a missing
        width, a tip radius on a face without a tip, and point contact where the follower
        does not fit the cam's concave surface (``1/rho_e <= 0``: GeometryError). A
        rocking arm gives the cam's curvature at its contact [1/m] as a table
        (``curvature``, a :class:`~camdyn.model.profiles.Profile`) in place of the
        profile's own."""
        face = profile.follower
        geometry = self.geometry_of(face)
        if face == "flat" and geometry == "point":
            raise ParameterError("contact.geometry: a flat face touches the cam along a line; use 'line' "
                                 "with contact.width")
        if face == "knife" and geometry == "line":
            raise ParameterError("contact.geometry: a knife edge with a rounded tip makes point contact; use "
                                 "'point' with contact.tip_radius")
        if face != "knife" and self.tip_radius != 0.0:
            raise ParameterError(f"contact.tip_radius is for a knife edge only, not a {face} face")
        if geometry == "line" and self.width <= 0.0:
            raise ParameterError("contact.width: line contact needs the positive width l [m] of the contact")
        if face == "knife" and self.tip_radius <= 0.0:
            raise ParameterError("contact.tip_radius: a sharp knife edge has no Hertz stiffness; give the "
                                 "edge's tip radius [m] (point contact)")
        if geometry == "point":
            theta = np.linspace(0.0, 2.0 * math.pi, _CHECK_ANGLES, endpoint=False)
            p = self._vector(profile, curvature)
            inverse = np.array([model.equivalent_curvature(a, p) for a in theta])
            if not np.all(inverse > 0.0):
                worst = int(np.argmin(inverse))
                raise GeometryError(f"the follower (radius {p[model.FOLLOWER_RADIUS]} m) does not fit the cam's "
                                    f"concave surface at {math.degrees(theta[worst]):.3f} deg: no Hertz point "
                                    "contact there; use a smaller tip radius or roller")

    def _vector(self, profile, curvature=None) -> np.ndarray:
        """A parameter vector holding the profile, this law and a rocking arm's curvature
        table (its other slots unused)."""
        table = None if curvature is None else curvature.table
        return model.pack(profile, 1.0, 0.0, 0.0, 1.0, law=model.HERTZ, hertz_law=self.slots(profile),
                          curvature=table)

    def slots(self, profile) -> dict:
        """The model's Hertz slots (slot -> value) for a follower on ``profile``."""
        line = self.geometry_of(profile.follower) == "line"
        return {model.CONTACT_KIND: 1.0 if line else 0.0, model.MODULUS: self.modulus,
                model.WIDTH: self.width if line else 0.0,
                model.FOLLOWER_RADIUS: 0.0 if line else self.follower_radius(profile),
                model.DAMPING_LAW: float(lookup(self.damping_law).code), model.V_REFERENCE: self.reference_velocity}

    def stiffness(self, profile, theta=None) -> float:
        """The Hertz coefficient ``K`` [N/m for line, N/m^1.5 for point contact] (eqs. 5-6
        of :mod:`camdyn.model.translating_follower`), for point contact at the cam angle
        ``theta`` [rad]."""
        if self.geometry_of(profile.follower) == "line":
            return hertz.hertz_line_coefficient(self.modulus, self.width)
        return hertz.hertz_point_coefficient(self.modulus, model.equivalent_radius(float(theta),
                                                                                self._vector(profile)))
