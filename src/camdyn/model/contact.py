"""Normal contact laws: Hertz stiffness and contact damping (docs/model.md §3).

Hertz (eqs 2.13-2.14, 3.11-3.13), with ``1/E* = (1-nu_c^2)/Y_c + (1-nu_b^2)/Y_b``:

- line contact of length ``l``: ``F_k = (pi/4) E* l delta``;
- point contact of crossed cylinders: ``F_k = (4/3) E* sqrt(rho_e) delta^1.5`` with
  ``rho_e = (1/rho_c + 1/rd)^-1`` (eq 4.18).

Damping laws (thesis 2.3.4, 3.2): A viscous, B ``beta F_k(delta)``, C Zhang-Whiten
``beta delta^0.25``, D = B compressing / A restoring, E = C compressing / A restoring,
the generalized ``beta delta^n delta_dot`` (thesis eq 3.2), and the restitution-parameterised
laws ``F_d = chi(e) K delta^nH delta_dot / v_approach`` (docs/model.md §3.4). Each law is a row of
:data:`camdyn.params.laws.TABLE`: the integer codes dispatched on below and the factors
``chi(e)`` (compiled here from the rows' functions) come from there.
"""

from __future__ import annotations

import math

import numba

from camdyn.errors import ParameterError
from camdyn.model import layout as L
from camdyn.params.laws import FIRST_RESTITUTION_CODE, LAWS, lookup

__all__ = [
    "effective_modulus", "stiffness_at", "damped_force", "hertz_point_coefficient", "hertz_line_coefficient",
    "equivalent_radius", "restitution_factor", "hunt_crossley_beta", "contact_force",
]


@numba.njit(cache=True)
def equivalent_radius(cam_radius, pin_radius):
    """``rho_e = (1/rho_c + 1/rd)^-1`` [m] of the crossed-cylinder point contact (eq 4.18);
    ``rd = 0`` (no pin: the cam on the bar face) gives the cam's radius alone (eq 2.34)."""
    if pin_radius == 0.0:
        return cam_radius
    return cam_radius * pin_radius / (cam_radius + pin_radius)   # one division, not three


def hertz_point_coefficient(modulus: float, radius: float) -> float:
    """Hertz point-contact coefficient ``K = (4/3) E* sqrt(rho_e)`` [N/m^1.5] (eq 3.11).

    Parameters
    ----------
    modulus : float
        Effective modulus ``E*`` [Pa].
    radius : float
        Equivalent radius ``rho_e`` [m].
    """
    return 4.0 / 3.0 * modulus * math.sqrt(radius)


def hertz_line_coefficient(modulus: float, length: float) -> float:
    """Hertz line-contact stiffness ``K = (pi/4) E* l`` [N/m] (eq 2.14)."""
    return math.pi / 4.0 * modulus * length


# Codes of the damping laws in the parameter vector (numba reads these module-level
# integers as compile-time constants).
VISCOUS = LAWS["viscous"].code
STIFFNESS_PROPORTIONAL = LAWS["stiffness-proportional"].code
ZHANG_WHITEN = LAWS["zhang-whiten"].code
STIFFNESS_PROPORTIONAL_VISCOUS = LAWS["stiffness-proportional-viscous"].code
ZHANG_WHITEN_VISCOUS = LAWS["zhang-whiten-viscous"].code
POWER = LAWS["power"].code
HUNT_CROSSLEY = LAWS["hunt-crossley"].code
LANKARANI_NIKRAVESH = LAWS["lankarani-nikravesh"].code
FLORES = LAWS["flores"].code
GONTHIER = LAWS["gonthier"].code
# The restitution factors chi(e) [-], compiled from the rows' functions.
_hunt_crossley = numba.njit(LAWS["hunt-crossley"].restitution)
_lankarani_nikravesh = numba.njit(LAWS["lankarani-nikravesh"].restitution)
_flores = numba.njit(LAWS["flores"].restitution)
_gonthier = numba.njit(LAWS["gonthier"].restitution)
_hu_guo = numba.njit(LAWS["hu-guo"].restitution)


def restitution_factor(law: str, restitution: float) -> float:
    """Hysteresis factor ``chi(e)`` [-] of a restitution-parameterised law for the
    coefficient of restitution ``e`` = ``restitution`` [-] (its row's relation)."""
    factor = lookup(law).restitution
    if factor is None:
        raise ParameterError(f"{law!r} is not a restitution-parameterised damping law")
    return factor(restitution)


def hunt_crossley_beta(gamma: float, stiffness: float) -> float:
    """Hunt-Crossley damping ``beta = (3/2) gamma K`` [N s/m^2.5] from the equivalent
    restitution slope ``gamma`` [s/m] of ``xi = 1 - gamma v`` (thesis 3.8.3)."""
    return 1.5 * gamma * stiffness


@numba.njit(cache=True)
def _factor(code, e):
    """Factor ``chi(e)`` [-] of the restitution law with ``code``, for restitution ``e`` [-]."""
    if code == HUNT_CROSSLEY:
        return _hunt_crossley(e)
    if code == LANKARANI_NIKRAVESH:
        return _lankarani_nikravesh(e)
    if code == FLORES:
        return _flores(e)
    if code == GONTHIER:
        return _gonthier(e)
    return _hu_guo(e)


def effective_modulus(cam_modulus: float, cam_poisson: float, follower_modulus: float,
                      follower_poisson: float) -> float:
    """Contact modulus ``E*`` [Pa]: ``1/E* = (1-nu_c^2)/Y_c + (1-nu_b^2)/Y_b`` (eq 2.13, 3.12;
    K. L. Johnson, *Contact Mechanics*, 1985, eq 4.22).

    Parameters
    ----------
    cam_modulus, follower_modulus : float
        Young's moduli ``Y_c`` and ``Y_b`` [Pa].
    cam_poisson, follower_poisson : float
        Poisson's ratios ``nu_c`` and ``nu_b`` [-].
    """
    return 1.0 / ((1 - cam_poisson ** 2) / cam_modulus + (1 - follower_poisson ** 2) / follower_modulus)


@numba.njit(cache=True, inline="always")
def stiffness_at(line, modulus, radius, length, delta):
    """Secant stiffness ``k(delta) = F_k / delta`` [N/m] of the Hertz law: line contact
    ``(pi/4) E* l`` (eq 2.14), point contact ``(4/3) E* sqrt(rho_e) |delta|^0.5`` (eq 3.11).

    Parameters
    ----------
    line : bool
        True for line contact, False for point contact.
    modulus : float
        Effective modulus ``E*`` [Pa].
    radius : float
        Equivalent radius ``rho_e`` [m] (point contact).
    length : float
        Contact length ``l`` [m] (line contact).
    delta : float
        Penetration [m].
    """
    if not line:
        k = 4.0 / 3.0 * modulus * math.sqrt(radius)
        return k * math.sqrt(abs(delta))
    return 0.25 * math.pi * modulus * length


@numba.njit(cache=True, inline="always")
def damped_force(delta, delta_dot, kd, approach, code, viscous, beta, exponent, restitution, v_reference, clip):
    """Normal force ``F_k + F_d`` [N] of the Hertz spring with secant stiffness ``kd`` and
    the damping law ``code`` (a row of :data:`camdyn.params.laws.TABLE`).

    Parameters
    ----------
    delta : float
        Penetration [m]; negative values (a step overshooting separation) use the odd
        continuation ``sgn(delta)|delta|^nH`` so the force stays smooth.
    delta_dot : float
        Penetration rate [m/s].
    kd : float
        Secant stiffness ``k(delta) = F_k / delta`` [N/m] (:func:`stiffness_at`).
    approach : float
        Approach velocity of this contact [m/s] (restitution laws).
    code : int
        Code of the damping law.
    viscous : float
        ``c`` of laws A, D and E [N s/m].
    beta, exponent : float
        ``beta`` [law-dependent unit] and ``n`` [-] of laws B-E and the power law.
    restitution : float
        Coefficient of restitution ``e`` [-] of the restitution laws.
    v_reference : float
        Smallest approach velocity used by the restitution laws [m/s].
    clip : bool
        True clips a pulling (negative) force to zero.

    Returns
    -------
    fn : float
        Normal force ``F_k + F_d`` [N].
    fk : float
        Elastic part ``F_k`` [N].
    """
    ad = abs(delta)
    fk = kd * delta
    c = 0.0
    if code == VISCOUS:
        c = viscous
    elif code == STIFFNESS_PROPORTIONAL:  # c = beta F_k(delta): beta [s/m] times a force (see docs/model.md)
        c = beta * kd * ad
    elif code == ZHANG_WHITEN:
        c = beta * ad ** 0.25
    elif code == STIFFNESS_PROPORTIONAL_VISCOUS:
        # D and E switch on the sign of delta_dot itself: F_d = c delta_dot is continuous
        # there, so the switch needs no event (an event on delta_dot would chatter on
        # rounding noise in sustained stiff contact)
        c = beta * kd * ad if delta_dot > 0.0 else viscous
    elif code == ZHANG_WHITEN_VISCOUS:
        c = beta * ad ** 0.25 if delta_dot > 0.0 else viscous
    elif code == POWER:
        if exponent == 1.5:
            c = beta * ad * math.sqrt(ad)
        elif exponent == 0.0:
            c = beta
        else:
            c = beta * ad ** exponent
    elif code >= FIRST_RESTITUTION_CODE:
        v = max(approach, v_reference)
        c = _factor(code, restitution) * kd * ad / v   # chi(e) K delta^nH / v
    fn = fk + c * delta_dot
    if clip and fn < 0.0:
        fn = 0.0
    return fn, fk


@numba.njit(cache=True, inline="always")
def contact_force(delta, delta_dot, rho_c, approach, p):
    """Normal force on the rocking follower [N] while in contact: :func:`damped_force`
    with the coefficients of the parameter vector ``p`` (:mod:`camdyn.model.layout`).

    Parameters
    ----------
    delta : float
        Penetration [m] (negative values: the odd continuation of :func:`damped_force`).
    delta_dot : float
        Penetration rate [m/s].
    rho_c : float
        Cam curvature radius at the contact [m].
    approach : float
        Approach velocity of this contact [m/s] (restitution laws).
    p : ndarray
        Parameter vector (:mod:`camdyn.model.layout`).

    Returns
    -------
    fn : float
        Normal force ``F_k + F_d`` [N] (clipped at zero if requested).
    fk : float
        Elastic part ``F_k`` [N].
    """
    line = p[L.CONTACT_KIND] != 0.0
    rho_e = 0.0 if line else equivalent_radius(rho_c, p[L.PIN])
    kd = stiffness_at(line, p[L.ESTAR], rho_e, p[L.LINE_LENGTH], delta)
    return damped_force(delta, delta_dot, kd, approach, int(p[L.DAMPING_LAW]), p[L.VISCOUS_C], p[L.BETA],
                        p[L.EXPONENT], p[L.RESTITUTION], p[L.V_REFERENCE], p[L.CLIP] > 0.5)
