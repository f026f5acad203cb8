"""Friction laws at the cam-follower contact (docs/model.md §3).

The tangential force of the cam on the follower along ``u`` is ``Ff = mu(vr) Fn``,
with ``vr`` the sliding velocity of the cam surface relative to the follower:

- model I, Coulomb: ``mu = mu_m sgn(vr)``; the compiled core treats ``sgn(vr)`` as part
  of the hybrid mode and locates every reversal of ``vr`` as an event;
- model II, smoothed: ``mu = mu_m tanh(sigma vr)`` (the thesis used sigma = 10 s/m).

Sign convention: the force of friction on the follower is ``+Ff u`` (it drags the
follower along with the cam surface), so its moment about P, clockwise, is ``+Ff h``.
docs/model.md writes ``-Ff h`` in the equation of motion but ``-Ff u`` in the pivot
reaction ``N = m a_G + Fn n - Ff u - ...``; only ``+Ff h`` is consistent with that
reaction and with friction opposing slip. camdyn uses ``+Ff h``.
"""

from __future__ import annotations

import math

import numba

from camdyn.model import layout as L

__all__ = ["friction_coefficient"]


@numba.njit(cache=True)
def friction_coefficient(vr, slip_sign, p):
    """Signed friction coefficient ``mu(vr)`` [-].

    Parameters
    ----------
    vr : float
        Sliding velocity [m/s].
    slip_sign : float
        Sign of ``vr`` held by the hybrid mode (Coulomb law) [-].
    p : ndarray
        Parameter vector.
    """
    law = p[L.FRICTION_LAW]
    if law == 1.0:
        return p[L.MU] * slip_sign
    if law == 2.0:
        return p[L.MU] * math.tanh(p[L.SMOOTHING] * vr)
    return 0.0
