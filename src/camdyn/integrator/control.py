"""The step-size control of the driver (:mod:`camdyn.integrator.driver`): the verdict on
a trial step from its scaled error norm, and the stabilized proposal after a DOP853
step. Neither calls a model, so one compiled copy serves every model's driver."""

from __future__ import annotations

import math

import numba

from camdyn.integrator.counters import COUNT_REJECTED, COUNT_STATUS, STATUS_NOT_FINITE

__all__ = ["STABILIZATION", "STEP_ACCEPTED", "STEP_RETRY", "STEP_FAILED", "verdict", "stabilized"]

#: Weight of the last accepted step's error norm in the step-size control of DOP853 steps
#: controlled by their 5th-order estimate alone (:func:`stabilized`) [-].
STABILIZATION = 0.04

STEP_ACCEPTED = 0  # verdicts on a trial step
STEP_RETRY = 1
STEP_FAILED = 2


@numba.njit(cache=True, inline="always")
def verdict(t, h, e, order, y1, counters):
    """Accept or refuse the step of ``h`` [s] with error norm ``e``.

    Returns
    -------
    h : float
        The step [s] to retry with after a refusal, else ``h``.
    verdict : int
        ``STEP_ACCEPTED``, ``STEP_RETRY`` or ``STEP_FAILED`` (a state that stays infinite
        or NaN down to the resolution of time; the status is set).
    """
    finite = True
    for i in range(y1.shape[0]):
        finite = finite and math.isfinite(y1[i])
    if not (e == e) or not finite:
        counters[COUNT_REJECTED] += 1
        h *= 0.25
        if h <= 4e-16 * max(1.0, abs(t)):  # else the next pass reports underflow
            counters[COUNT_STATUS] = STATUS_NOT_FINITE
            return h, STEP_FAILED
        return h, STEP_RETRY
    if e > 1.0:
        counters[COUNT_REJECTED] += 1
        h *= max(0.2, 0.9 * e ** (-1.0 / order))
        return h, STEP_RETRY
    return h, STEP_ACCEPTED


@numba.njit(cache=True, inline="always")
def stabilized(h, e, e_last):
    """The next step [s] after an accepted DOP853 step of error norm ``e`` (the last
    accepted one's ``e_last``, at least 1e-4) for which :func:`_advance` proposed ``h`` by
    ``0.9 e^(-1/8)``: times ``e^(0.75 beta) e_last^beta``, the proportional-integral
    control of Gustafsson (1991, ACM TOMS 17(4) 533-554, doi:10.1145/210232.210242) as
    Hairer's DOPRI5 applies it (``beta = 0.04``; Hairer, Norsett and Wanner, *Solving
    Ordinary Differential Equations I*, 2nd ed., 1993, sec. II.4, "stabilized step size
    control"). Without it the step hunts where a lightly damped contact's eigenvalues
    reach the method's stability boundary: 23-54 refusals per revolution at rtol 1e-5 and
    3e-6 on the chapter 4 rig in sustained contact, whose error then did not fall with
    rtol (docs/integrator.md, *Accuracy in sustained contact*)."""
    if e <= 0.0:
        return h
    return h * e ** (0.75 * STABILIZATION) * e_last ** STABILIZATION
