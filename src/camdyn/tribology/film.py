"""Hertz contact size and pressure, film thickness, lambda ratio and lubrication regime
over a cam revolution (thesis 4.5.1, figs 4.4-4.5).

Point contact (chapter 4, a dowel pin of radius ``rd`` crossed with the cam): the
entraining motion runs along the bar, so ``Rx = rho_c`` (the cam's radius of curvature in
its plane; the pin is straight along the bar) and ``Ry = rd``. Line contact (chapter 2):
``R = rho_c`` against the flat bar face, over the length ``l``.

References
----------
B. J. Hamrock, D. Dowson, "Isothermal elastohydrodynamic lubrication of point contacts,
Part III: fully flooded results", J. Lubr. Technol. 99 (1977) 264-275,
doi:10.1115/1.3453074.
P. Pan, B. J. Hamrock, "Simple formulas for performance parameters used in
elastohydrodynamically lubricated line contacts", J. Tribol. 111 (1989) 246-251,
doi:10.1115/1.3261906.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numpy as np
import xarray as xr

from camdyn.analysis.kinematics import inverse_kinematics
from camdyn.errors import ParameterError, PresetError
from camdyn.model.contact import equivalent_radius
from camdyn.model.layout import effective_modulus
from camdyn.params.system import System
from camdyn.params.units import parse_quantity, parse_speed

__all__ = ["Lubricant", "load_lubricant", "list_lubricants", "roughness_preset", "hamrock_dowson_film",
           "pan_hamrock_film", "lambda_ratio", "lubrication_regime", "contact_conditions"]

#: Lambda-ratio limits of the regimes: boundary below 1, mixed from 1 to 3, EHL above 3.
REGIME_LIMITS = (1.0, 3.0)


@dataclass(frozen=True)
class Lubricant:
    """A lubricant at its working temperature.

    Attributes
    ----------
    name : str
    viscosity : float
        Dynamic viscosity ``eta_0`` at atmospheric pressure [Pa s].
    pressure_viscosity : float
        Barus pressure-viscosity coefficient ``alpha_p`` [m^2/N].
    """

    name: str
    viscosity: float
    pressure_viscosity: float

    def __post_init__(self):
        for key in ("viscosity", "pressure_viscosity"):
            value = getattr(self, key)
            if not (math.isfinite(value) and value > 0):
                raise ParameterError(f"lubricant {key} must be positive, got {value!r}")


@lru_cache(maxsize=1)
def _table() -> dict:
    return tomllib.loads(resources.files("camdyn.tribology").joinpath("lubricants.toml").read_text())


def list_lubricants() -> list[str]:
    """Names of the bundled lubricants."""
    return [k for k in _table() if k != "roughness"]


def load_lubricant(name: str) -> Lubricant:
    """A bundled lubricant (``agma-4ep``, ``iso-32``)."""
    table = _table()
    if name not in table or name == "roughness":
        raise PresetError(f"unknown lubricant {name!r}; bundled: {', '.join(list_lubricants())}")
    entry = table[name]
    return Lubricant(name=entry["name"], viscosity=parse_quantity(entry["viscosity"], "Pa*s", "viscosity"),
                     pressure_viscosity=parse_quantity(entry["pressure_viscosity"], "m**2/N", "pressure_viscosity"))


def roughness_preset(name: str) -> tuple[float, float]:
    """rms roughness ``(cam, follower)`` [m] of a bundled finish (``ground``, ``sand-blasted``)."""
    finishes = _table()["roughness"]
    if name not in finishes:
        raise PresetError(f"unknown surface finish {name!r}; bundled: {', '.join(finishes)}")
    return (parse_quantity(finishes[name]["cam"], "m", "roughness"),
            parse_quantity(finishes[name]["follower"], "m", "roughness"))


def hamrock_dowson_film(load, entrainment_velocity, radius_x, radius_y, reduced_modulus, lubricant: Lubricant):
    """Minimum film thickness of an elliptical point contact [m] (Hamrock and Dowson 1977)::

        h_min / Rx = 3.63 U^0.68 G^0.49 W^-0.073 (1 - exp(-0.68 k)),  k = 1.0339 (Ry/Rx)^0.636

    with ``U = eta_0 u / (E' Rx)``, ``G = alpha_p E'``, ``W = w / (E' Rx^2)``.

    Parameters
    ----------
    load : array_like
        Normal load ``w`` [N].
    entrainment_velocity : array_like
        Mean entraining velocity ``u = (u_c + u_b) / 2`` [m/s] (its magnitude is used).
    radius_x, radius_y : array_like
        Reduced radii along and across the entraining motion [m].
    reduced_modulus : float
        ``E' = 2 / ((1-nu_c^2)/Y_c + (1-nu_b^2)/Y_b)`` [Pa].

    Notes
    -----
    The formula was fitted for ``k`` from 1 to 8; the chapter 4 pin contact has
    ``Ry/Rx = 0.18`` (``k = 0.35``, entrainment along the ellipse's major axis), where it
    is an extrapolation that Chittenden et al. (1985) found to hold within about 20 %.
    """
    w = np.maximum(np.asarray(load, float), 0.0)
    u = np.abs(np.asarray(entrainment_velocity, float))
    rx = np.asarray(radius_x, float)
    k = 1.0339 * (np.asarray(radius_y, float) / rx) ** 0.636
    e = reduced_modulus
    big_u = lubricant.viscosity * u / (e * rx)
    big_g = lubricant.pressure_viscosity * e
    with np.errstate(divide="ignore", invalid="ignore"):
        big_w = w / (e * rx ** 2)
        h = rx * 3.63 * big_u ** 0.68 * big_g ** 0.49 * big_w ** -0.073 * (1.0 - np.exp(-0.68 * k))
    return np.where(w > 0, h, np.nan)


def pan_hamrock_film(load, entrainment_velocity, radius, length, reduced_modulus, lubricant: Lubricant):
    """Minimum film thickness of a line contact [m] (Pan and Hamrock 1989).

    ::

        h_min / R = 1.714 W'^-0.128 U^0.694 G^0.568,  W' = w / (E' R l)
    """
    w = np.maximum(np.asarray(load, float), 0.0)
    u = np.abs(np.asarray(entrainment_velocity, float))
    r = np.asarray(radius, float)
    e = reduced_modulus
    big_u = lubricant.viscosity * u / (e * r)
    big_g = lubricant.pressure_viscosity * e
    with np.errstate(divide="ignore", invalid="ignore"):
        big_w = w / (e * r * length)
        h = r * 1.714 * big_w ** -0.128 * big_u ** 0.694 * big_g ** 0.568
    return np.where(w > 0, h, np.nan)


def lambda_ratio(film_thickness, roughness_cam: float, roughness_follower: float):
    """``Lambda = h_min / sqrt(Rq_c^2 + Rq_b^2)`` [-] (rms roughnesses [m])."""
    composite = math.hypot(roughness_cam, roughness_follower)
    if not composite > 0:
        raise ParameterError("the composite roughness must be positive")
    return np.asarray(film_thickness, float) / composite


def lubrication_regime(lam) -> np.ndarray:
    """``"boundary"`` (Lambda < 1), ``"mixed"`` (1 to 3) or ``"EHL"`` (> 3), elementwise."""
    lam = np.asarray(lam, float)
    return np.where(lam < REGIME_LIMITS[0], "boundary", np.where(lam < REGIME_LIMITS[1], "mixed", "EHL"))


def contact_conditions(system: System, speed: float | None = None, lubricant: Lubricant | str | None = None,
                       roughness: tuple[float, float] | str = "ground", points: int = 720,
                       kinematics: xr.Dataset | None = None) -> xr.Dataset:
    """Hertz contact, velocities, film thickness and lambda ratio over one revolution,
    from the rigid-contact motion of :func:`camdyn.analysis.kinematics.inverse_kinematics`.

    Parameters
    ----------
    system : System
    speed : float, optional
        Cam speed [Hz].
    lubricant : Lubricant or str, optional
        A :class:`Lubricant` or a bundled name; None leaves the film variables out.
    roughness : (float, float) or str
        rms roughness of cam and follower [m], or a bundled finish name.
    kinematics : xarray.Dataset, optional
        A result of ``inverse_kinematics`` at this speed, to reuse.

    Returns
    -------
    xarray.Dataset
        Over ``cam_angle``: ``Fn`` [N], ``penetration`` [m], ``contact_radius`` [m]
        (semi-width for line contact), ``peak_pressure`` [Pa] (eq 4.42),
        ``sliding_velocity``, ``sum_velocity`` [m/s], ``slide_to_roll`` [-], and with a
        lubricant ``film_thickness`` [m], ``lambda_ratio`` [-], ``regime``.
    """
    if kinematics is None:
        hz = system.motion.speed if speed is None else parse_speed(speed)
        if not (math.isfinite(hz) and hz > 0):
            raise ParameterError(f"the contact conditions need a turning cam: the speed must be positive and finite, "
                                 f"got {speed if speed is not None else hz!r} (at rest the velocities vanish and the "
                                 f"film thickness is undefined)")
        speed = hz
    ik = kinematics if kinematics is not None else inverse_kinematics(system, speed=speed, points=points)
    fn = np.maximum(ik["Fn"].values, 0.0)
    rho_c = ik["cam_curvature_radius"].values
    e_star = effective_modulus(system)
    if system.contact.kind == "point":
        rd = system.follower.pin_radius
        if rd == 0.0:
            raise ParameterError("the film thickness of a point contact needs the dowel pin (follower.pin_radius > 0); "
                                 "for the cam on the bar face use contact.kind = 'line'")
        rho_e = equivalent_radius(rho_c, rd)                       # eq 4.18
        k = 4.0 / 3.0 * e_star * np.sqrt(rho_e)
        delta = (fn / k) ** (2.0 / 3.0)
        radius = np.sqrt(rho_e * delta)
        with np.errstate(divide="ignore", invalid="ignore"):
            pressure = np.where(delta > 0, 3.0 * fn / (2.0 * np.pi * rho_e * delta), 0.0)   # eq 4.42
    else:
        length = system.contact.length
        delta = fn / (np.pi / 4.0 * e_star * length)
        radius = np.sqrt(4.0 * fn * rho_c / (np.pi * length * e_star))
        with np.errstate(divide="ignore", invalid="ignore"):
            pressure = np.where(radius > 0, 2.0 * fn / (np.pi * radius * length), 0.0)
    ds = ik[["time", "Fn", "sliding_velocity", "sum_velocity", "slide_to_roll", "cam_curvature_radius"]].copy()
    ds["penetration"] = ("cam_angle", delta, {"units": "m", "long_name": "Hertz penetration"})
    ds["contact_radius"] = ("cam_angle", radius, {"units": "m", "long_name": "Hertz contact radius (semi-width)"})
    ds["peak_pressure"] = ("cam_angle", pressure, {"units": "Pa", "long_name": "Hertz peak pressure (eq 4.42)"})
    if lubricant is not None:
        lub = load_lubricant(lubricant) if isinstance(lubricant, str) else lubricant
        rough = roughness_preset(roughness) if isinstance(roughness, str) else tuple(float(r) for r in roughness)
        u = 0.5 * ik["sum_velocity"].values
        if system.contact.kind == "point":
            h = hamrock_dowson_film(fn, u, rho_c, system.follower.pin_radius, 2.0 * e_star, lub)
        else:
            h = pan_hamrock_film(fn, u, rho_c, system.contact.length, 2.0 * e_star, lub)
        lam = lambda_ratio(h, *rough)
        ds["film_thickness"] = ("cam_angle", h, {"units": "m", "long_name": "minimum film thickness h_min"})
        ds["lambda_ratio"] = ("cam_angle", lam, {"units": "1", "long_name": "lambda ratio h_min / composite Rq"})
        ds["regime"] = ("cam_angle", lubrication_regime(lam), {"long_name": "lubrication regime"})
        ds.attrs.update(lubricant=lub.name, viscosity=lub.viscosity, pressure_viscosity=lub.pressure_viscosity,
                        roughness_cam=rough[0], roughness_follower=rough[1])
    ds.attrs.update(ik.attrs)
    return ds
