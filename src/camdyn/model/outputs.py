"""Derived output channels at the sampled states (compiled, vectorised over samples)."""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.model import layout as L
from camdyn.model.dynamics import evaluate, spring_force_trig
from camdyn.model.geometry import contact_point_rate

#: name, unit, long name of each derived channel, in column order.
CHANNELS = (
    ("alpha_ddot", "rad/s^2", "follower angular acceleration"),
    ("penetration", "m", "contact penetration delta (negative: gap)"),
    ("penetration_rate", "m/s", "penetration rate delta_dot"),
    ("Fn", "N", "normal contact force on the follower"),
    ("Fk", "N", "elastic (Hertz) part of the normal force"),
    ("Ff", "N", "friction force on the follower along the bar (u)"),
    ("Fs", "N", "spring force (compression)"),
    ("moment_arm", "m", "moment arm chi of the normal force about the pivot"),
    ("sliding_velocity", "m/s", "sliding velocity vr of the cam relative to the follower"),
    ("sum_velocity", "m/s", "sum (entraining) velocity ve = u_c + u_b"),
    ("Nx", "N", "pivot reaction on the follower, horizontal"),
    ("Ny", "N", "pivot reaction on the follower, vertical"),
    ("cam_angle", "rad", "cam angle Theta"),
    ("cam_speed", "rad/s", "cam angular speed Theta_dot"),
    ("in_contact", "1", "1 while the follower touches the cam"),
)


@numba.njit(cache=True)
def pivot_reaction(alpha, alpha_dot, alpha_ddot, fn, ff, fs, p):
    """Pivot reaction ``(Nx, Ny)`` [N] on the follower from Newton's law for its centre of gravity.

    ``N = m a_G + Fn n - Ff u - Fs (sin sigma, cos sigma) + m g e_y`` with
    ``a_G = -l_cg (alpha_ddot n + alpha_dot^2 u)`` (eqs 4.27-4.28, 4.45-4.46).

    Parameters
    ----------
    alpha, alpha_dot, alpha_ddot : float
        Follower angle [rad], rate [rad/s] and acceleration [rad/s^2].
    fn, ff, fs : float
        Normal contact, friction and spring forces [N].
    """
    m = p[L.MASS]
    lcg = p[L.CG]
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    agx = -lcg * (alpha_ddot * sa + alpha_dot * alpha_dot * ca)
    agy = -lcg * (alpha_ddot * ca - alpha_dot * alpha_dot * sa)
    st = math.sin(p[L.TILT])
    ct = math.cos(p[L.TILT])
    nx = m * agx + fn * sa - ff * ca - fs * st
    ny = m * agy + fn * ca + ff * sa - fs * ct + m * p[L.GRAVITY]
    return nx, ny


@numba.njit(cache=True)
def derived(t, y, modes, p):
    """Channels of :data:`CHANNELS` for samples ``t`` [s], states ``y`` (n, 3), modes (n, 4)."""
    n = t.shape[0]
    out = np.full((n, len(CHANNELS)), np.nan)
    for i in range(n):
        if math.isnan(y[i, 0]):
            continue
        alpha = y[i, 0]
        ad = y[i, 1]
        mode = modes[i]
        acc, fn, ff, fs, chi, delta, delta_dot, vr, theta, theta_dot, power, fk = evaluate(
            t[i], alpha, ad, mode, p)
        chi_dot = contact_point_rate(alpha, ad, theta, theta_dot, p)
        ub = -chi_dot
        ve = vr + 2.0 * ub
        nx, ny = pivot_reaction(alpha, ad, acc, fn, ff, fs, p)
        row = out[i]
        row[0] = acc
        row[1] = delta
        row[2] = delta_dot
        row[3] = fn
        row[4] = fk
        row[5] = ff
        row[6] = fs
        row[7] = chi
        row[8] = vr
        row[9] = ve
        row[10] = nx
        row[11] = ny
        row[12] = theta
        row[13] = theta_dot
        row[14] = mode[L.MODE_CONTACT]
    return out


@numba.njit(cache=True)
def contact_forces_from_reaction(alpha, alpha_dot, alpha_ddot, nx, ny, p):
    """Normal and friction force ``(Fn, Ff)`` [N] from a measured pivot reaction: the
    inverse of :func:`pivot_reaction` (eqs 4.29-4.30, with the centripetal term and the
    spring tilt kept), vectorised over samples.

    Parameters
    ----------
    alpha, alpha_dot, alpha_ddot : ndarray
        Follower angle [rad], rate [rad/s] and acceleration [rad/s^2].
    nx, ny : ndarray
        Pivot reaction on the follower [N].
    """
    n = alpha.size
    fn = np.empty(n)
    ff = np.empty(n)
    m = p[L.MASS]
    lcg = p[L.CG]
    st = math.sin(p[L.TILT])
    ct = math.cos(p[L.TILT])
    for i in range(n):
        ca = math.cos(alpha[i])
        sa = math.sin(alpha[i])
        ad2 = alpha_dot[i] * alpha_dot[i]
        agx = -lcg * (alpha_ddot[i] * sa + ad2 * ca)
        agy = -lcg * (alpha_ddot[i] * ca - ad2 * sa)
        fs = spring_force_trig(ca, sa, p)
        a = nx[i] - m * agx + fs * st
        b = ny[i] - m * agy + fs * ct - m * p[L.GRAVITY]
        fn[i] = a * sa + b * ca
        ff[i] = -a * ca + b * sa
    return fn, ff
