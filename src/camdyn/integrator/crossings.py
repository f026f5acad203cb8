"""Guard crossings within one accepted step of the driver (its algorithm's steps 3-4).

Every guard active in the current mode is sampled at the step end and at the extrema of
the guard's own cubic Hermite polynomial (from its exact rates at both ends), or at the
midpoint for a guard whose rate is unknown; the earliest sign change against the
expected sign is located by the Illinois method on the step's continuous extension.

The functions marked ``inline="always"`` are compiled into the driver's loop (numba IR
inlining), so that they add no call per step.
"""

from __future__ import annotations

import math

import numba

from camdyn.integrator.counters import COUNT_RHS, COUNT_ROOT_ITERATIONS
from camdyn.integrator.steppers import dense, dop853_extend
from camdyn.systems import registry as systems


@numba.njit(cache=True)
def guard_at(system, t, h, tau, y0, f0, y1, f1, work, kind, p, ytmp, vals, rates):
    """Guards ``vals`` (and their rates, ``rates``) at the fraction ``tau`` of the step of
    ``h`` [s] from ``t`` [s], on the step's continuous extension."""
    dense(tau, h, y0, f0, y1, f1, work, kind, ytmp)
    systems.guards(system, t + tau * h, ytmp, ytmp, False, p, vals, rates)


@numba.njit(cache=True)
def locate_crossing(system, k, sign, t, h, ta, tb, y0, f0, y1, f1, work, kind, p, ytmp, vals, rates, counters):
    """Illinois iteration for the crossing of guard ``k`` in (ta, tb] (fractions of h).

    ``sign * g`` is >= 0 at ``ta`` and < 0 at ``tb``; returns the right end of the final
    bracket, where the guard already has its new sign.
    """
    guard_at(system, t, h, ta, y0, f0, y1, f1, work, kind, p, ytmp, vals, rates)
    fa = max(sign * vals[k], 0.0)
    guard_at(system, t, h, tb, y0, f0, y1, f1, work, kind, p, ytmp, vals, rates)
    fb = sign * vals[k]
    side = 0
    tol = 4e-16 * max(1.0, abs(t)) / max(abs(h), 1e-300) + 1e-15
    for _ in range(200):
        if tb - ta <= tol:
            break
        tm = tb - fb * (tb - ta) / (fb - fa) if fb != fa else 0.5 * (ta + tb)
        if not (ta < tm < tb):
            tm = 0.5 * (ta + tb)
        guard_at(system, t, h, tm, y0, f0, y1, f1, work, kind, p, ytmp, vals, rates)
        counters[COUNT_ROOT_ITERATIONS] += 1
        fm = sign * vals[k]
        if fm < 0.0:
            tb, fb = tm, fm
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            ta, fa = tm, fm
            if side == 1:
                fb *= 0.5
            side = 1
    return tb


@numba.njit(cache=True, inline="always")
def ensure_extension(ready, system, t, y, h, y1, f1, mode, p, k16, ytmp, f7, counters):
    """DOP853's continuous extension of the step, unless ``ready``; returns True."""
    if not ready:
        counters[COUNT_RHS] += dop853_extend(system, t, y, h, y1, f1, mode, p, k16, ytmp, f7)
    return True


@numba.njit(cache=True, inline="always")
def midpoint_guards(system, t, h, y, f, y1, f1, dwork, kind, mode, p, k16, ytmp, f7, ymid, gr, gr1, gv, grv,
                    ready, counters):
    """Guards ``gv`` at the step's midpoint when an active guard has no rate at an end
    (else zeros, unused); returns whether the continuous extension is ready."""
    need_mid = False
    for k in range(gr.shape[0]):
        if systems.expected_sign(system, k, mode, p) != 0.0 and (math.isnan(gr[k]) or math.isnan(gr1[k])):
            need_mid = True
    if need_mid:
        ready = ensure_extension(ready, system, t, y, h, y1, f1, mode, p, k16, ytmp, f7, counters)
        dense(0.5, h, y, f, y1, f1, dwork, kind, ymid)
        systems.guards(system, t + 0.5 * h, ymid, ymid, False, p, gv, grv)
    else:
        for k in range(gv.shape[0]):
            gv[k] = 0.0   # not used: every active guard has its cubic
    return ready


@numba.njit(cache=True, inline="always")
def cubic_extrema(g0, g1, r0, r1, h):
    """Extrema of a guard's cubic Hermite over a step of ``h`` [s], from its values
    ``g0``, ``g1`` and rates ``r0``, ``r1`` [1/s] at both ends, as fractions of the step
    (-1 where there is none)."""
    ext1 = -1.0
    ext2 = -1.0
    d0 = h * r0
    d1 = h * r1
    a3 = 2.0 * g0 + d0 - 2.0 * g1 + d1
    a2 = -3.0 * g0 - 2.0 * d0 + 3.0 * g1 - d1
    a1 = d0
    qa = 3.0 * a3
    qb = 2.0 * a2
    qc = a1
    if abs(qa) > 1e-300:
        disc = qb * qb - 4.0 * qa * qc
        if disc >= 0.0:
            sq = math.sqrt(disc)
            ext1 = (-qb - sq) / (2.0 * qa)
            ext2 = (-qb + sq) / (2.0 * qa)
    elif abs(qb) > 1e-300:
        ext1 = -qc / qb
    return ext1, ext2


@numba.njit(cache=True, inline="always")
def sample_points(pts, ext1, ext2, has_rate):
    """Ordered sample points (fractions of the step) into ``pts``: the guard's extrema,
    the midpoint for a guard without a rate, and the end."""
    pts[0] = min(ext1, ext2)
    pts[1] = max(ext1, ext2)
    pts[2] = -1.0 if has_rate else 0.5   # guards with a rate use their cubic instead
    pts[3] = 1.0
    for a_ in range(1, 4):
        b_ = a_
        while b_ > 0 and pts[b_ - 1] > pts[b_]:
            tmp_ = pts[b_ - 1]
            pts[b_ - 1] = pts[b_]
            pts[b_] = tmp_
            b_ -= 1


@numba.njit(cache=True, inline="always")
def first_crossing(system, k, s, t, h, y, f, y1, f1, dwork, kind, mode, p, k16, ytmp, f7, g1, val0, pts, g_tmp,
                   gr_tmp, ready, counters):
    """Scan the sample points ``pts`` for the first where guard ``k`` has left its
    expected sign ``s``.

    Returns
    -------
    prev : float
        The last sample point before it (0: the step's start).
    found : float
        The sample point where the sign changed (-1 if none).
    ready : bool
        Whether the continuous extension is ready.
    """
    prev = 0.0
    found = -1.0
    for j in range(4):
        tau = pts[j]
        if tau <= 0.0 or tau > 1.0:
            continue
        if tau == 0.5:
            v = val0
        elif tau == 1.0:
            v = s * g1[k]
        else:
            ready = ensure_extension(ready, system, t, y, h, y1, f1, mode, p, k16, ytmp, f7, counters)
            guard_at(system, t, h, tau, y, f, y1, f1, dwork, kind, p, ytmp, g_tmp, gr_tmp)
            v = s * g_tmp[k]
        if v < 0.0:
            found = tau
            break
        prev = tau
    return prev, found, ready


@numba.njit(cache=True, inline="always")
def earliest_crossing(system, t, h, y, f, y1, f1, dwork, kind, mode, p, k16, ytmp, f7, g, gr, g1, gr1, gv, pts,
                      g_tmp, gr_tmp, ready, counters):
    """The earliest guard crossing in the step (see the module's algorithm, steps 3-4).

    Returns
    -------
    tau_event : float
        Where it lies, as a fraction of the step (2 if none).
    k_event : int
        The guard that crosses (-1 if none).
    ready : bool
        Whether the continuous extension is ready.
    """
    tau_event = 2.0
    k_event = -1
    for k in range(g.shape[0]):
        s = systems.expected_sign(system, k, mode, p)
        if s == 0.0:
            continue
        has_rate = not (math.isnan(gr[k]) or math.isnan(gr1[k]))
        val0 = s * gv[k]
        ext1 = -1.0
        ext2 = -1.0
        if has_rate:
            ext1, ext2 = cubic_extrema(g[k], g1[k], gr[k], gr1[k], h)
        sample_points(pts, ext1, ext2, has_rate)
        prev, found, ready = first_crossing(system, k, s, t, h, y, f, y1, f1, dwork, kind, mode, p, k16, ytmp,
                                            f7, g1, val0, pts, g_tmp, gr_tmp, ready, counters)
        if found > 0.0 and prev < tau_event:
            ready = ensure_extension(ready, system, t, y, h, y1, f1, mode, p, k16, ytmp, f7, counters)
            tau_k = locate_crossing(system, k, s, t, h, prev, found, y, f, y1, f1, dwork, kind, p,
                                    ytmp, g_tmp, gr_tmp, counters)
            if tau_k < tau_event:
                tau_event = tau_k
                k_event = k
    return tau_event, k_event, ready
