"""Derived output channels at the sampled states (compiled, vectorised over samples)."""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.geometry import contact_point_rate
from camdyn.model import layout as L
from camdyn.model.dynamics import evaluate

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
def derived(t, y, modes, p):
    """Channels of :data:`CHANNELS` for samples ``t`` [s], states ``y`` (n, 3), modes (n, 4)."""
    n = t.shape[0]
    out = np.full((n, len(CHANNELS)), np.nan)
    m = p[L.MASS]
    lcg = p[L.CG]
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
        ca = math.cos(alpha)
        sa = math.sin(alpha)
        # N = m a_G + Fn n - Ff u - Fs (sin sigma, cos sigma) + m g y,  a_G = -l (alpha_ddot n + alpha_dot^2 u)
        agx = -lcg * (acc * sa + ad * ad * ca)
        agy = -lcg * (acc * ca - ad * ad * sa)
        st = math.sin(p[L.TILT])
        ct = math.cos(p[L.TILT])
        nx = m * agx + fn * sa - ff * ca - fs * st
        ny = m * agy + fn * ca + ff * sa - fs * ct + m * p[L.GRAVITY]
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
