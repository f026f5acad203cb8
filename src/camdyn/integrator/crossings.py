"""Guard crossings within one accepted step of the driver (its algorithm's steps 3-4).

Every guard active in the current mode is sampled at the step end and at the extrema of
the guard's own cubic Hermite polynomial (from its exact rates at both ends), or at the
midpoint for a guard whose rate is unknown; the earliest sign change against the
expected sign is located by the Illinois method on the step's continuous extension.

The cubic is only accurate on a short interval (its error grows as the interval's fourth
power): a step longer than the scan interval the caller gives (``scan`` [s]) is scanned
on its continuous extension (:func:`scan_crossing`). The guards and their rates are
evaluated at its midpoint (the state's rate from the extension's derivative after a
DOP853 step, from the right-hand side after the others); where every active guard stays
clear of zero on both half-step cubics by more than the whole-step cubic's error there
(:func:`clear_margin`), the step holds no crossing; else it is split into an even number
of equal sub-intervals no longer than ``scan``, each checked as a short step would be. A
step no longer than ``scan`` is checked as a whole, with the very arithmetic of before.

The functions marked ``inline="always"`` are compiled into the driver's loop (numba IR
inlining), so that they add no call per step.
"""

from __future__ import annotations

import math

import numba

from camdyn.integrator.counters import COUNT_RHS, COUNT_ROOT_ITERATIONS
from camdyn.integrator.steppers import KIND_DOP853, dense, dop853_dense_rate, dop853_extend
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


@numba.njit(cache=True)
def interior_guards(system, t, h, tau, y0, f0, y1, f1, work, kind, mode, p, ytmp, rate, vals, rates, counters):
    """Guards ``vals`` and their rates ``rates`` at the fraction ``tau`` of the step of
    ``h`` [s] from ``t`` [s], on the step's continuous extension; the state's rate there
    (into ``rate``) is the extension's derivative after a DOP853 step, else the
    right-hand side (one call, counted)."""
    dense(tau, h, y0, f0, y1, f1, work, kind, ytmp)
    if kind == KIND_DOP853:
        dop853_dense_rate(tau, h, work, rate)
    else:
        systems.rhs(system, t + tau * h, ytmp, mode, p, rate)
        counters[COUNT_RHS] += 1
    systems.guards(system, t + tau * h, ytmp, rate, True, p, vals, rates)


@numba.njit(cache=True)
def crossing_between(system, ta, tb, t, h, y, f, y1, f1, dwork, kind, mode, p, ytmp, ga, gra, gb, grb, pts, g_tmp,
                     gr_tmp, counters):
    """The earliest guard crossing in the sub-interval ``(ta, tb]`` (fractions of the step
    of ``h`` [s] from ``t`` [s]) from the guards ``ga``, ``gb`` and their rates ``gra``,
    ``grb`` at its ends: each active guard sampled at its cubic's extrema (or the
    sub-interval's midpoint when a rate is unknown) and at ``tb``, as a whole step is.
    Returns where it lies (a fraction of the step, 2 if none) and the guard (-1 if none)."""
    tau_event = 2.0
    k_event = -1
    width = tb - ta
    for k in range(ga.shape[0]):
        s = systems.expected_sign(system, k, mode, p)
        if s == 0.0:
            continue
        has_rate = not (math.isnan(gra[k]) or math.isnan(grb[k]))
        ext1 = -1.0
        ext2 = -1.0
        if has_rate:
            ext1, ext2 = cubic_extrema(ga[k], gb[k], gra[k], grb[k], width * h)
        sample_points(pts, ext1, ext2, has_rate)
        prev = ta
        found = -1.0
        for j in range(4):
            if pts[j] <= 0.0 or pts[j] > 1.0:
                continue
            if pts[j] == 1.0:
                tau = tb
                v = s * gb[k]
            else:
                tau = ta + pts[j] * width
                guard_at(system, t, h, tau, y, f, y1, f1, dwork, kind, p, ytmp, g_tmp, gr_tmp)
                v = s * g_tmp[k]
            if v < 0.0:
                found = tau
                break
            prev = tau
        if found > 0.0 and prev < tau_event:
            tau_k = locate_crossing(system, k, s, t, h, prev, found, y, f, y1, f1, dwork, kind, p, ytmp, g_tmp,
                                    gr_tmp, counters)
            if tau_k < tau_event:
                tau_event = tau_k
                k_event = k
    return tau_event, k_event


@numba.njit(cache=True, inline="always")
def cubic_value(g0, g1, r0, r1, h, tau):
    """A guard's cubic Hermite over a step of ``h`` [s] (values ``g0``, ``g1``, rates
    ``r0``, ``r1`` [1/s] at its ends, as in :func:`cubic_extrema`) at the fraction ``tau``."""
    d0 = h * r0
    d1 = h * r1
    a3 = 2.0 * g0 + d0 - 2.0 * g1 + d1
    a2 = -3.0 * g0 - 2.0 * d0 + 3.0 * g1 - d1
    return g0 + tau * (d0 + tau * (a2 + tau * a3))


@numba.njit(cache=True, inline="always")
def cubic_lowest(s, g0, g1, r0, r1, h):
    """The smallest value of ``s`` times a guard's cubic over a step of ``h`` [s] (from
    its ends and the extrema inside)."""
    low = min(s * g0, s * g1)
    ext1, ext2 = cubic_extrema(g0, g1, r0, r1, h)
    if 0.0 < ext1 < 1.0:
        low = min(low, s * cubic_value(g0, g1, r0, r1, h, ext1))
    if 0.0 < ext2 < 1.0:
        low = min(low, s * cubic_value(g0, g1, r0, r1, h, ext2))
    return low


@numba.njit(cache=True)
def clear_margin(system, h, mode, p, g, gr, g1, gr1, gm, grm):
    """Whether every active guard keeps its expected sign on the step of ``h`` [s] with
    room to spare: the lowest point of its two half-step cubics (through the guard ``gm``
    and rate ``grm`` at the midpoint) lies further from zero than the whole-step cubic
    misses the midpoint by. That miss estimates the whole cubic's error, which a half
    cubic's is about 1/16 of (the error of cubic Hermite interpolation grows as the
    interval's fourth power)."""
    for k in range(g.shape[0]):
        s = systems.expected_sign(system, k, mode, p)
        if s == 0.0:
            continue
        if math.isnan(gr[k]) or math.isnan(gr1[k]) or math.isnan(grm[k]):
            return False
        miss = abs(gm[k] - cubic_value(g[k], g1[k], gr[k], gr1[k], h, 0.5))
        low = min(cubic_lowest(s, g[k], gm[k], gr[k], grm[k], 0.5 * h),
                  cubic_lowest(s, gm[k], g1[k], grm[k], gr1[k], 0.5 * h))
        if not low > miss:
            return False
    return True


@numba.njit(cache=True)
def scan_crossing(system, t, h, scan, y, f, y1, f1, dwork, kind, mode, p, ytmp, g, gr, g1, gr1, pts, g_tmp,
                  gr_tmp, scan_arrays, counters):
    """The earliest guard crossing in a step of ``h`` [s] from ``t`` [s] longer than
    ``scan`` [s] (its continuous extension ready; the guards ``g``, ``g1`` and rates
    ``gr``, ``gr1`` at its ends). The guards are evaluated at the midpoint; where every
    active guard keeps a clear margin (:func:`clear_margin`) there is none; else the step
    is split into an even number of equal sub-intervals no longer than ``scan``, each
    checked by :func:`crossing_between` in turn until one holds a crossing.
    ``scan_arrays``: a state's rate and guards and rates at three points. Returns as
    :func:`crossing_between`."""
    rate, ga, gra, gb, grb, gm, grm = scan_arrays
    interior_guards(system, t, h, 0.5, y, f, y1, f1, dwork, kind, mode, p, ytmp, rate, gm, grm, counters)
    if clear_margin(system, h, mode, p, g, gr, g1, gr1, gm, grm):
        return 2.0, -1
    pieces = 2 * int(math.ceil(0.5 * h / scan))
    for i in range(g.shape[0]):
        gb[i] = g[i]
        grb[i] = gr[i]
    for j in range(pieces):
        for i in range(g.shape[0]):
            ga[i] = gb[i]
            gra[i] = grb[i]
        ta = j / pieces
        tb = (j + 1) / pieces
        if j == pieces - 1 or 2 * (j + 1) == pieces:
            tb = 1.0 if j == pieces - 1 else 0.5
            for i in range(g.shape[0]):
                gb[i] = g1[i] if j == pieces - 1 else gm[i]
                grb[i] = gr1[i] if j == pieces - 1 else grm[i]
        else:
            interior_guards(system, t, h, tb, y, f, y1, f1, dwork, kind, mode, p, ytmp, rate, gb, grb, counters)
        tau_event, k_event = crossing_between(system, ta, tb, t, h, y, f, y1, f1, dwork, kind, mode, p, ytmp, ga,
                                              gra, gb, grb, pts, g_tmp, gr_tmp, counters)
        if k_event >= 0:
            return tau_event, k_event
    return 2.0, -1


@numba.njit(cache=True, inline="always")
def earliest_crossing(system, t, h, y, f, y1, f1, dwork, kind, mode, p, k16, ytmp, f7, g, gr, g1, gr1, gv, pts,
                      g_tmp, gr_tmp, ready, scan, scan_arrays, counters):
    """The earliest guard crossing in the step (see the module's algorithm, steps 3-4);
    a step longer than ``scan`` [s] is scanned on sub-intervals (:func:`scan_crossing`).

    Returns
    -------
    tau_event : float
        Where it lies, as a fraction of the step (2 if none).
    k_event : int
        The guard that crosses (-1 if none).
    ready : bool
        Whether the continuous extension is ready.
    """
    if h > scan:
        ready = ensure_extension(ready, system, t, y, h, y1, f1, mode, p, k16, ytmp, f7, counters)
        tau_event, k_event = scan_crossing(system, t, h, scan, y, f, y1, f1, dwork, kind, mode, p, ytmp, g, gr, g1,
                                           gr1, pts, g_tmp, gr_tmp, scan_arrays, counters)
        return tau_event, k_event, ready
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
