"""Equation of motion of the rocking follower (docs/model.md §3), compiled with numba.

Clockwise moments about the pivot P (eq 3.16, 4.13, with the friction sign settled in
:mod:`camdyn.model.friction`)::

    I_P alpha_ddot = m g l_cg cos(alpha) + M_spring(alpha) + Fn chi + Ff h

The state is ``y = (alpha [rad], alpha_dot [rad/s], W_cam [J])``; the third component
integrates the power the cam delivers, ``P_cam = -Fn n.v_cam + Ff u.v_cam``, for the
energy bookkeeping. The hybrid mode (:mod:`camdyn.model.layout`) holds whether the
follower is in contact, the sign of the sliding velocity for Coulomb friction, the
compression phase, and the approach velocity of the current contact.
"""

from __future__ import annotations

import math

import numba

from camdyn.model import layout as L
from camdyn.model.contact import contact_force
from camdyn.model.friction import friction_coefficient
from camdyn.model.geometry import (
    cam_acceleration,
    cam_angle,
    contact_kinematics,
    contact_kinematics_trig,
    contact_rates_trig,
)

__all__ = ["spring_force", "spring_moment", "evaluate", "evaluate_cam", "rhs", "guards", "jacobian",
           "central_jacobian", "mode_expected_sign", "mode_transition", "mode_initial"]


@numba.njit(cache=True)
def spring_force(alpha, p):
    """Spring force ``Fs`` [N] along its axis, positive in compression.

    Eq 3.10 / 4.14, ``ks (Ls - dy + dx tan(alpha) + 0.5 wb sec(alpha))``, times
    ``cos(alpha) / cos(alpha - sigma)`` for a spring tilted by ``sigma`` (our reading
    of the garbled eq 4.44).
    """
    return spring_force_trig(math.cos(alpha), math.sin(alpha), p)


@numba.njit(cache=True)
def spring_force_trig(ca, sa, p):
    """:func:`spring_force` from ``cos(alpha)`` and ``sin(alpha)``."""
    inv_c = 1.0 / ca
    fs = p[L.KS] * (p[L.LS] - p[L.DY] + (p[L.DX] * sa + 0.5 * p[L.WIDTH]) * inv_c)
    if p[L.TILT] != 0.0:
        fs *= ca / (ca * math.cos(p[L.TILT]) + sa * math.sin(p[L.TILT]))
    return fs


@numba.njit(cache=True)
def spring_moment(alpha, fs, p):
    """Clockwise moment about P [N m] of the spring force ``fs`` [N].

    The force acts along ``(sin sigma, cos sigma)`` at the attachment point
    ``(dx, -(0.5 wb sec(alpha) + dx tan(alpha)))`` on the bar's lower face.
    """
    return spring_moment_trig(math.cos(alpha), math.sin(alpha), fs, p)


@numba.njit(cache=True)
def spring_moment_trig(ca, sa, fs, p):
    """:func:`spring_moment` from ``cos(alpha)`` and ``sin(alpha)``."""
    if p[L.TILT] == 0.0:
        return -fs * p[L.DX]
    depth = (0.5 * p[L.WIDTH] + p[L.DX] * sa) / ca
    return -fs * (p[L.DX] * math.cos(p[L.TILT]) + depth * math.sin(p[L.TILT]))


@numba.njit(cache=True)
def evaluate(t, alpha, alpha_dot, mode, p):
    """All forces and kinematics at one instant, for the given hybrid mode.

    See :func:`evaluate_shifted`; this is the case ``delta_shift = 0``.
    """
    return evaluate_shifted(t, alpha, alpha_dot, mode, p, 0.0)


@numba.njit(cache=True)
def evaluate_shifted(t, alpha, alpha_dot, mode, p, delta_shift):
    """All forces and kinematics at one instant, for the given hybrid mode, with the
    penetration shifted by ``delta_shift`` [m] (used by :func:`jacobian`).

    Returns
    -------
    tuple
        ``(alpha_ddot [rad/s^2], Fn [N], Ff [N], Fs [N], chi [m], delta [m],
        delta_dot [m/s], vr [m/s], theta [rad], theta_dot [rad/s], P_cam [W], Fk [N])``
    """
    theta, theta_dot = cam_angle(t, p)
    return evaluate_cam(theta, theta_dot, alpha, alpha_dot, mode, p, delta_shift)


@numba.njit(cache=True)
def evaluate_cam(theta, theta_dot, alpha, alpha_dot, mode, p, delta_shift):
    """:func:`evaluate_shifted` at a given cam angle ``theta`` [rad] and speed
    ``theta_dot`` [rad/s] instead of the prescribed motion (the cam as a body,
    :mod:`camdyn.model.driven_cam`, takes them from its state); same returns."""
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    delta, delta_dot, chi, rho_c, vr, n_v, u_v = contact_kinematics_trig(
        ca, sa, math.cos(theta), math.sin(theta), alpha_dot, theta_dot, p)
    delta += delta_shift
    fs = spring_force_trig(ca, sa, p)
    moment = p[L.MASS] * p[L.GRAVITY] * p[L.CG] * ca + spring_moment_trig(ca, sa, fs, p)
    fn = 0.0
    ff = 0.0
    fk = 0.0
    power = 0.0
    if mode[L.MODE_CONTACT] > 0.5:
        fn, fk = contact_force(delta, delta_dot, rho_c, mode[L.MODE_APPROACH], p)
        ff = friction_coefficient(vr, mode[L.MODE_SLIP], p) * fn
        moment += fn * chi + ff * p[L.OFFSET]
        power = -fn * n_v + ff * u_v
    return (moment / p[L.INERTIA], fn, ff, fs, chi, delta, delta_dot, vr, theta, theta_dot, power, fk)


@numba.njit(cache=True, inline="always")
def rhs(t, y, mode, p, dydt):
    """Right-hand side ``dy/dt`` of the state ``(alpha, alpha_dot, W_cam)``.

    The same forces as :func:`evaluate`, computed directly: only the acceleration and
    the cam's power leave this function, so the compiled helpers fold into one body.
    """
    alpha = y[0]
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    fs = spring_force_trig(ca, sa, p)
    moment = p[L.MASS] * p[L.GRAVITY] * p[L.CG] * ca + spring_moment_trig(ca, sa, fs, p)
    power = 0.0
    if mode[L.MODE_CONTACT] > 0.5:
        theta, theta_dot = cam_angle(t, p)
        delta, delta_dot, chi, rho_c, vr, n_v, u_v = contact_kinematics_trig(
            ca, sa, math.cos(theta), math.sin(theta), y[1], theta_dot, p)
        fn, fk = contact_force(delta, delta_dot, rho_c, mode[L.MODE_APPROACH], p)
        ff = friction_coefficient(vr, mode[L.MODE_SLIP], p) * fn
        moment += fn * chi + ff * p[L.OFFSET]
        power = -fn * n_v + ff * u_v
    dydt[0] = y[1]
    dydt[1] = moment / p[L.INERTIA]
    dydt[2] = power


@numba.njit(cache=True, inline="always")
def guards(t, y, alpha_ddot, p, out, rates):
    """Event functions ``out = (delta [m], vr [m/s], delta_dot [m/s])`` and their exact
    time derivatives ``rates = (delta_dot [m/s], vr_dot [m/s^2], delta_ddot [m/s^2])``.

    ``delta`` changes sign at contact onset and separation, ``vr`` at a reversal of
    sliding (Coulomb friction), ``delta_dot`` at peak penetration (laws D and E switch
    there; the impact table records the peak). ``alpha_ddot`` [rad/s^2] is the state's
    acceleration (the right-hand side at ``(t, y)``), or NaN where it is not known,
    which leaves the rates of ``vr`` and ``delta_dot`` NaN.
    """
    theta, theta_dot = cam_angle(t, p)
    delta, vr, delta_dot, vr_dot, delta_ddot = contact_rates_trig(
        math.cos(y[0]), math.sin(y[0]), math.cos(theta), math.sin(theta), y[1], alpha_ddot, theta_dot,
        cam_acceleration(t, p), p)
    out[0] = delta
    out[1] = vr
    out[2] = delta_dot
    rates[0] = delta_dot
    rates[1] = vr_dot
    rates[2] = delta_ddot


@numba.njit(cache=True)
def jacobian(t, y, f0, mode, p, jac):
    """Jacobian rows 1 and 2 of the right-hand side: ``jac[1, 0:2] = d f1 / d (y0, y1)``
    and ``jac[2, 0:2] = d f2 / d (y0, y1)`` (``jac`` is 3 x 3; its other entries, row 0's
    ``(0, 1, 0)`` and the zero third column, are left as the caller set them).

    The penetration ``delta`` is a small difference of large lengths (about 1 um out of
    tens of mm), so a finite difference in ``alpha`` through ``delta`` loses most of its
    digits, and a Rosenbrock method with such a Jacobian loses its order. The chain rule
    separates the two paths: ``d/d alpha = (d/d alpha at fixed delta) - chi d/d delta``
    (the envelope theorem gives ``d delta/d alpha = -chi`` exactly). The first is a
    well-conditioned forward difference with ``delta`` held fixed, the second a
    relative difference of the contact law in ``delta`` itself.
    """
    _differenced_jacobian(t, y, mode, p, jac, False)


@numba.njit(cache=True)
def central_jacobian(t, y, f0, mode, p, jac):
    """:func:`jacobian` by central differences at larger steps, ``1e-6`` rad in
    ``alpha`` and ``1e-6 max(|alpha_dot|, 1 rad/s)`` in ``alpha_dot``, for the
    variational system, which integrates ``Phi' = J Phi`` under error control: the
    forward differences' rounding noise (about 1e-8 of ``J``) acts there as a local error
    proportional to the step, which held DOP853 to 2.8e5 steps per revolution of the
    chapter 4 rig at rtol 1e-11 and left the state-transition matrix off by 3.5e-6 of its
    largest entry; the central differences' truncation error is of order 1e-12 of ``J``
    and their noise 1e-10 (measured: 2 226 steps, 8e-8 off)."""
    _differenced_jacobian(t, y, mode, p, jac, True)


@numba.njit(cache=True)
def _differenced_jacobian(t, y, mode, p, jac, central):
    """Rows 1 and 2 of the Jacobian (see :func:`jacobian`): by forward differences
    (steps 1e-8 rad and 1.5e-8 max(|alpha_dot|, 1e-3 rad/s)), or, if ``central``, by
    central ones (:func:`central_jacobian`)."""
    alpha = y[0]
    ad = y[1]
    eps_a = 1e-6 if central else 1e-8
    eps_v = 1e-6 * max(abs(ad), 1.0) if central else 1.5e-8 * max(abs(ad), 1e-3)
    contact = mode[L.MODE_CONTACT] > 0.5
    theta, theta_dot = cam_angle(t, p)
    # the moment arm from the kinematics alone: the central differences need no force at
    # y itself (the forward ones evaluate it below)
    delta, delta_dot, chi, rho_c, vr, n_v, u_v = contact_kinematics(alpha, ad, theta, theta_dot, p)
    if not contact:
        chi = 0.0
    # alpha moved with delta held (delta moves by -chi d alpha): forward, or central
    res_a = evaluate_shifted(t, alpha + eps_a, ad, mode, p, chi * eps_a)
    if central:
        res_b = evaluate_shifted(t, alpha - eps_a, ad, mode, p, -chi * eps_a)
        res_w = evaluate_shifted(t, alpha, ad - eps_v, mode, p, 0.0)
    else:                                       # the forces at y itself
        res_b = evaluate_shifted(t, alpha, ad, mode, p, 0.0)
        res_w = res_b
    span_a = 2.0 * eps_a if central else eps_a
    j10 = (res_a[0] - res_b[0]) / span_a
    j20 = (res_a[10] - res_b[10]) / span_a if contact else 0.0
    if contact:
        # d Fn / d delta by a central relative difference of the contact law
        d = 1e-6 * max(abs(delta), 1e-12)
        fp = contact_force(delta + d, delta_dot, rho_c, mode[L.MODE_APPROACH], p)[0]
        fm = contact_force(delta - d, delta_dot, rho_c, mode[L.MODE_APPROACH], p)[0]
        dfn = (fp - fm) / (2.0 * d)
        mu = friction_coefficient(vr, mode[L.MODE_SLIP], p)
        j10 -= chi * dfn * (chi + mu * p[L.OFFSET]) / p[L.INERTIA]
        j20 -= chi * dfn * (-n_v + mu * u_v)
    res_v = evaluate_shifted(t, alpha, ad + eps_v, mode, p, 0.0)
    span_v = 2.0 * eps_v if central else eps_v
    jac[1, 0] = j10
    jac[1, 1] = (res_v[0] - res_w[0]) / span_v
    jac[2, 0] = j20
    jac[2, 1] = (res_v[10] - res_w[10]) / span_v


@numba.njit(cache=True)
def free_acceleration(alpha, p):
    """Angular acceleration [rad/s^2] of the free follower at ``alpha`` [rad] (eq 3.9:
    spring and gravity, no contact)."""
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    fs = spring_force_trig(ca, sa, p)
    return (p[L.MASS] * p[L.GRAVITY] * p[L.CG] * ca + spring_moment_trig(ca, sa, fs, p)) / p[L.INERTIA]


# --- the contact modes of a rocking follower on a cam (the cam-follower, system 0, and
# the cam as a rigid body, camdyn.model.driven_cam), over the guards of :func:`guards`


@numba.njit(cache=True)
def mode_expected_sign(k, mode, p):
    """+1 or -1 for an active guard ``k``, 0 for an inactive one: the penetration
    always; the sliding velocity in contact under Coulomb friction; ``delta_dot`` during
    an impact, until its peak penetration (for the impact table: laws D and E switch on
    the sign of ``delta_dot`` inside the force law and need no event)."""
    contact = mode[L.MODE_CONTACT] > 0.5
    if k == 0:
        return 1.0 if contact else -1.0
    if not contact:
        return 0.0
    if k == 1:
        return mode[L.MODE_SLIP] if p[L.FRICTION_LAW] == 1.0 else 0.0
    if mode[L.MODE_IMPACT] > 0.5:
        return 1.0 if mode[L.MODE_COMPRESSING] > 0.5 else -1.0
    return 0.0


@numba.njit(cache=True)
def mode_transition(k, values, mode):
    """The mode after guard ``k`` crossed, from the guard values ``values`` at the
    event: contact onset (an impact begins, with its approach velocity) or separation, a
    reversal of sliding, the peak penetration of an impact."""
    if k == 0:
        if mode[L.MODE_CONTACT] > 0.5:
            mode[L.MODE_CONTACT] = 0.0
        else:
            mode[L.MODE_CONTACT] = 1.0
            mode[L.MODE_IMPACT] = 1.0
            mode[L.MODE_APPROACH] = values[2]
            mode[L.MODE_SLIP] = 1.0 if values[1] >= 0.0 else -1.0
            mode[L.MODE_COMPRESSING] = 1.0 if values[2] > 0.0 else 0.0
    elif k == 1:
        mode[L.MODE_SLIP] = -mode[L.MODE_SLIP]
    else:
        mode[L.MODE_COMPRESSING] = 1.0 - mode[L.MODE_COMPRESSING]
        if mode[L.MODE_COMPRESSING] < 0.5:
            # the impact's peak is passed (its force peaks at or before it): stop
            # watching delta_dot, which in sustained stiff contact hovers at zero and
            # would cross it on rounding noise alone
            mode[L.MODE_IMPACT] = 0.0


@numba.njit(cache=True)
def mode_initial(values, p, mode):
    """The mode at the start from the guard values ``values``: in contact where the
    penetration is positive, no impact under way."""
    mode[L.MODE_CONTACT] = 1.0 if values[0] > 0.0 else 0.0
    mode[L.MODE_SLIP] = 1.0 if values[1] >= 0.0 else -1.0
    mode[L.MODE_COMPRESSING] = 1.0 if values[2] > 0.0 else 0.0
    mode[L.MODE_APPROACH] = p[L.V_REFERENCE]
    mode[L.MODE_IMPACT] = 0.0
