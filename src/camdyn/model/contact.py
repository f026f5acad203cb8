"""Normal contact laws: Hertz stiffness and contact damping (docs/model.md §3).

Hertz (eqs 2.13-2.14, 3.11-3.13), with ``1/E* = (1-nu_c^2)/Y_c + (1-nu_b^2)/Y_b``:

- line contact of length ``l``: ``F_k = (pi/4) E* l delta``;
- point contact of crossed cylinders: ``F_k = (4/3) E* sqrt(rho_e) delta^1.5`` with
  ``rho_e = (1/rho_c + 1/rd)^-1`` (eq 4.18).

Damping laws (thesis 2.3.4, 3.2): A viscous, B ``beta F_k(delta)``, C Zhang-Whiten
``beta delta^0.25``, D = B compressing / A restoring, E = C compressing / A restoring,
and the generalized ``beta delta^n delta_dot`` (eq 3.2). Restitution-parameterised laws
``F_d = chi(e) K delta^nH delta_dot / v_approach`` with the literature's factors:

=================== ====================== =======================================
law                  factor chi(e)          reference
=================== ====================== =======================================
Hunt-Crossley        3 (1 - e) / 2          doi:10.1115/1.3423596
Lankarani-Nikravesh  3 (1 - e^2) / 4        doi:10.1115/1.2912617
Flores et al.        8 (1 - e) / (5 e)      doi:10.1007/s11044-010-9237-4
Gonthier et al.      (1 - e^2) / e          doi:10.1023/B:MUBO.0000029392.21648.bc
Hu and Guo           3 (1 - e) / (2 e)      doi:10.1007/s11044-015-9453-z
=================== ====================== =======================================
"""

from __future__ import annotations

import math

import numba

from camdyn.model import layout as L

__all__ = [
    "hertz_point_coefficient", "hertz_line_coefficient", "equivalent_radius",
    "restitution_factor", "hunt_crossley_beta", "contact_force",
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


def restitution_factor(law: str, restitution: float) -> float:
    """Hysteresis factor ``chi(e)`` [-] of a restitution-parameterised law (table above)."""
    e = restitution
    factors = {
        "hunt-crossley": 1.5 * (1 - e),
        "lankarani-nikravesh": 0.75 * (1 - e * e),
        "flores": 1.6 * (1 - e) / e,
        "gonthier": (1 - e * e) / e,
        "hu-guo": 1.5 * (1 - e) / e,
    }
    return factors[law]


def hunt_crossley_beta(gamma: float, stiffness: float) -> float:
    """Hunt-Crossley damping ``beta = (3/2) gamma K`` [N s/m^2.5] from the equivalent
    restitution slope ``gamma`` [s/m] of ``xi = 1 - gamma v`` (thesis 3.8.3)."""
    return 1.5 * gamma * stiffness


@numba.njit(cache=True)
def _factor(code, e):
    if code == 7:
        return 1.5 * (1.0 - e)
    if code == 8:
        return 0.75 * (1.0 - e * e)
    if code == 9:
        return 1.6 * (1.0 - e) / e
    if code == 10:
        return (1.0 - e * e) / e
    return 1.5 * (1.0 - e) / e


@numba.njit(cache=True, inline="always")
def contact_force(delta, delta_dot, rho_c, approach, p):
    """Normal force on the follower [N] while in contact.

    Parameters
    ----------
    delta : float
        Penetration [m]. Negative values (a step overshooting separation) use the
        odd continuation ``sgn(delta)|delta|^nH`` so the force stays smooth.
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
    ad = abs(delta)
    if p[L.CONTACT_KIND] == 0.0:
        rho_e = equivalent_radius(rho_c, p[L.PIN])
        k = 4.0 / 3.0 * p[L.ESTAR] * math.sqrt(rho_e)
        kd = k * math.sqrt(ad)          # k(delta) = F_k / delta
    else:
        k = 0.25 * math.pi * p[L.ESTAR] * p[L.LINE_LENGTH]
        kd = k
    fk = kd * delta
    code = int(p[L.DAMPING_LAW])
    c = 0.0
    if code == 1:
        c = p[L.VISCOUS_C]
    elif code == 2:  # c = beta F_k(delta): beta [s/m] times a force (see docs/model.md)
        c = p[L.BETA] * kd * ad
    elif code == 3:
        c = p[L.BETA] * ad ** 0.25
    elif code == 4:
        # D and E switch on the sign of delta_dot itself: F_d = c delta_dot is continuous
        # there, so the switch needs no event (an event on delta_dot would chatter on
        # rounding noise in sustained stiff contact)
        c = p[L.BETA] * kd * ad if delta_dot > 0.0 else p[L.VISCOUS_C]
    elif code == 5:
        c = p[L.BETA] * ad ** 0.25 if delta_dot > 0.0 else p[L.VISCOUS_C]
    elif code == 6:
        n = p[L.EXPONENT]
        if n == 1.5:
            c = p[L.BETA] * ad * math.sqrt(ad)
        elif n == 0.0:
            c = p[L.BETA]
        else:
            c = p[L.BETA] * ad ** n
    elif code >= 7:
        v = max(approach, p[L.V_REFERENCE])
        c = _factor(code, p[L.RESTITUTION]) * kd * ad / v   # chi(e) K delta^nH / v
    fn = fk + c * delta_dot
    if p[L.CLIP] > 0.5 and fn < 0.0:
        fn = 0.0
    return fn, fk
