"""One step of each method, with its error estimate (the stepper half of the integrator).

The steppers integrate a state of any size ``n`` (the length of ``y``) of a system of
:mod:`camdyn.systems.registry`; scratch arrays have ``n`` columns. The error norms are
taken over the state's first ``controlled`` components (the system's
``controlled_size``: components past them, such as quadratures that feed back into
nothing, are integrated but not error-controlled). The Rosenbrock stepper solves its
linear systems with a small LU factorization (:mod:`camdyn.integrator.linalg`).
"""

from __future__ import annotations

import math

import numba

from camdyn.integrator.linalg import lu_factor, lu_solve
from camdyn.integrator.nordsieck import nordsieck_dense
from camdyn.integrator.radau_newton import radau_dense
from camdyn.integrator.tableaus import (
    D8_A,
    D8_A_FROM,
    D8_B,
    D8_B_FROM,
    D8_C,
    D8_D,
    D8_D_FROM,
    D8_E3,
    D8_E5,
    D8_STAGES,
    DP_A21,
    DP_A31,
    DP_A32,
    DP_A41,
    DP_A42,
    DP_A43,
    DP_A51,
    DP_A52,
    DP_A53,
    DP_A54,
    DP_A61,
    DP_A62,
    DP_A63,
    DP_A64,
    DP_A65,
    DP_B1,
    DP_B3,
    DP_B4,
    DP_B5,
    DP_B6,
    DP_C2,
    DP_C3,
    DP_C4,
    DP_C5,
    DP_E1,
    DP_E3,
    DP_E4,
    DP_E5,
    DP_E6,
    DP_E7,
    DP_P,
    RB_A,
    RB_C,
    RB_CC,
    RB_G,
    RB_GAMMA,
    RB_M,
    RB_STAGES,
)
from camdyn.integrator.tolerances import absolute_tolerance
from camdyn.systems import registry as systems


@numba.njit(cache=True)
def error_norm(y0, y1, err, rtol, atol, controlled):
    """RMS of the error over the first ``controlled`` components, scaled by
    ``atol + rtol |y|`` (``atol`` one number or one per component)."""
    acc = 0.0
    for i in range(controlled):
        sc = absolute_tolerance(atol, i) + rtol * max(abs(y0[i]), abs(y1[i]))
        acc += (err[i] / sc) ** 2
    return math.sqrt(acc / controlled)


@numba.njit(cache=True)
def hermite(tau, h, y0, f0, y1, f1, out):
    """Cubic Hermite interpolant at ``tau`` in [0, 1] of a step of size ``h``."""
    t2 = tau * tau
    t3 = t2 * tau
    h00 = 2.0 * t3 - 3.0 * t2 + 1.0
    h10 = t3 - 2.0 * t2 + tau
    h01 = -2.0 * t3 + 3.0 * t2
    h11 = t3 - t2
    for i in range(y0.shape[0]):
        out[i] = h00 * y0[i] + h10 * h * f0[i] + h01 * y1[i] + h11 * h * f1[i]


KIND_DP5 = 0
KIND_HERMITE = 1
KIND_DOP853 = 2
KIND_NORDSIECK = 3
KIND_RADAU = 4


@numba.njit(cache=True, inline="always")
def dop853_dense(tau, y0, work, out):
    """State at ``t + tau h`` inside a DOP853 step from its 7th-order extension, whose
    coefficients :func:`dop853_extend` has put in ``work[0:7]``; compiled into its caller
    (numba IR inlining: the output samples call it once each, and a call of a function
    taking arrays costs several times this arithmetic)."""
    s = 1.0 - tau
    for i in range(y0.shape[0]):   # nested form: ((F6 x + F5)(1 - x) + F4) x ...
        acc = ((((((work[6, i] * tau + work[5, i]) * s + work[4, i]) * tau + work[3, i]) * s
                  + work[2, i]) * tau + work[1, i]) * s + work[0, i]) * tau
        out[i] = y0[i] + acc


@numba.njit(cache=True, inline="always")
def dop853_dense_rate(tau, h, work, out):
    """Rate ``dy/dt`` at ``t + tau h`` inside a DOP853 step of ``h`` [s]: the derivative
    of the polynomial of :func:`dop853_dense` (Horner's scheme carrying the derivative,
    ``d/dtau`` of ``v tau + c`` is ``v' tau + v`` and of ``v (1 - tau) + c`` is
    ``v' (1 - tau) - v``), divided by ``h``."""
    s = 1.0 - tau
    for i in range(out.shape[0]):
        v = work[6, i]
        d = 0.0
        for r in range(5, -1, -1):   # rows 5, 3, 1 after a factor tau; 4, 2, 0 after 1 - tau
            if r % 2 == 1:
                d = d * tau + v
                v = v * tau + work[r, i]
            else:
                d = d * s - v
                v = v * s + work[r, i]
        out[i] = (d * tau + v) / h   # the last factor tau


@numba.njit(cache=True)
def dense(tau, h, y0, f0, y1, f1, work, kind, out):
    """State at ``t + tau h`` inside the last step.

    Dormand-Prince 5(4) steps (``kind`` 0) use their own 4th-order continuous extension
    (stages k2..k6 are still in ``work[1:6]``); Rosenbrock steps (1) the cubic Hermite
    interpolant; DOP853 steps (2) their 7th-order extension, whose coefficients
    :func:`dop853_extend` has put in ``work[0:7]``; Adams steps (3) their Nordsieck
    polynomial (``work`` is the history of :mod:`camdyn.integrator.nordsieck`); Radau IIA
    steps (4) their collocation polynomial, whose coefficients
    :func:`camdyn.integrator.implicit.implicit_step` has put in ``work[0:4]``.
    """
    if kind == KIND_HERMITE:
        hermite(tau, h, y0, f0, y1, f1, out)
        return
    n = y0.shape[0]
    if kind == KIND_NORDSIECK:
        nordsieck_dense(tau, work, n, out)
        return
    if kind == KIND_DOP853:
        dop853_dense(tau, y0, work, out)
        return
    if kind == KIND_RADAU:
        radau_dense(tau, work, out)
        return
    t2 = tau * tau
    t3 = t2 * tau
    t4 = t3 * tau
    for i in range(n):
        acc = f0[i] * (DP_P[0, 0] * tau + DP_P[0, 1] * t2 + DP_P[0, 2] * t3 + DP_P[0, 3] * t4)
        for s in range(2, 6):  # work[s] holds k_(s+1); P row s; k2's row is zero
            acc += work[s, i] * (DP_P[s, 1] * t2 + DP_P[s, 2] * t3 + DP_P[s, 3] * t4)
        acc += f1[i] * (DP_P[6, 1] * t2 + DP_P[6, 2] * t3 + DP_P[6, 3] * t4)
        out[i] = y0[i] + h * acc


@numba.njit(cache=True)
def dormand_prince_step(system, t, y, f0, h, mode, p, work, y1, f1, err):
    """Explicit Dormand-Prince 5(4) step; ``f1`` receives f(t + h, y1) (FSAL).

    ``work`` is a (6, n) scratch array. Returns the number of right-hand-side calls.
    """
    n = y.shape[0]
    yt = work[0]
    k2 = work[1]
    k3 = work[2]
    k4 = work[3]
    k5 = work[4]
    k6 = work[5]
    for i in range(n):
        yt[i] = y[i] + h * DP_A21 * f0[i]
    systems.rhs(system, t + DP_C2 * h, yt, mode, p, k2)
    for i in range(n):
        yt[i] = y[i] + h * (DP_A31 * f0[i] + DP_A32 * k2[i])
    systems.rhs(system, t + DP_C3 * h, yt, mode, p, k3)
    for i in range(n):
        yt[i] = y[i] + h * (DP_A41 * f0[i] + DP_A42 * k2[i] + DP_A43 * k3[i])
    systems.rhs(system, t + DP_C4 * h, yt, mode, p, k4)
    for i in range(n):
        yt[i] = y[i] + h * (DP_A51 * f0[i] + DP_A52 * k2[i] + DP_A53 * k3[i] + DP_A54 * k4[i])
    systems.rhs(system, t + DP_C5 * h, yt, mode, p, k5)
    for i in range(n):
        yt[i] = y[i] + h * (DP_A61 * f0[i] + DP_A62 * k2[i] + DP_A63 * k3[i] + DP_A64 * k4[i]
                            + DP_A65 * k5[i])
    systems.rhs(system, t + h, yt, mode, p, k6)
    for i in range(n):
        y1[i] = y[i] + h * (DP_B1 * f0[i] + DP_B3 * k3[i] + DP_B4 * k4[i] + DP_B5 * k5[i] + DP_B6 * k6[i])
    systems.rhs(system, t + h, y1, mode, p, f1)
    for i in range(n):
        err[i] = h * (DP_E1 * f0[i] + DP_E3 * k3[i] + DP_E4 * k4[i] + DP_E5 * k5[i] + DP_E6 * k6[i]
                      + DP_E7 * f1[i])
    return 6


@numba.njit(cache=True)
def rosenbrock_step(system, t, y, f0, h, mode, p, work, stages, matrix, pivots, y1, err):
    """Linearly implicit RODAS4 step.

    The Jacobian comes from the system (:func:`camdyn.systems.registry.jacobian`), the time
    derivative of the right-hand side from a central difference. ``work`` and ``stages``
    are (6, n) scratch arrays, ``matrix`` (n, n) and ``pivots`` (n,) the iteration
    matrix ``I / (gamma h) - J`` and its LU factorization's row swaps. Returns the number
    of right-hand-side calls (a singular iteration matrix makes ``err`` infinite, so the
    step is refused and retried shorter).
    """
    n = y.shape[0]
    yt = work[0]
    fe = work[1]
    dfdt = work[2]
    r = work[3]
    systems.jacobian(system, t, y, f0, mode, p, matrix)
    c = 1.0 / (RB_GAMMA * h)
    for i in range(n):
        for j in range(n):
            matrix[i, j] = -matrix[i, j]
        matrix[i, i] += c
    singular = lu_factor(matrix, pivots)
    # df/dt by a central difference at a millionth of the step (at least 64 ulp of t),
    # divided by the span as represented: the forward difference at 1.5e-8 max(t, 1e-3)
    # it replaces grew with t, and the steps of the chapter 4 rig grew with it, from 1,561
    # per revolution in the first to 7,100 on average over 30 (a constant 1,135 with this)
    epst = max(1e-6 * h, 64.0 * 2.220446049250313e-16 * max(abs(t), 1.0))
    systems.rhs(system, t + epst, y, mode, p, fe)
    systems.rhs(system, t - epst, y, mode, p, r)
    span = (t + epst) - (t - epst)
    for i in range(n):
        dfdt[i] = (fe[i] - r[i]) / span
    calls = 2
    for s in range(RB_STAGES):
        if s == 0:
            for i in range(n):
                fe[i] = f0[i]
        else:
            for i in range(n):
                acc = y[i]
                for j in range(s):
                    acc += RB_A[s, j] * stages[j, i]
                yt[i] = acc
            systems.rhs(system, t + RB_C[s] * h, yt, mode, p, fe)
            calls += 1
        for i in range(n):
            acc = fe[i] + h * RB_G[s] * dfdt[i]
            for j in range(s):
                acc += RB_CC[s, j] * stages[j, i] / h
            r[i] = acc
        lu_solve(matrix, pivots, r, stages[s])
    for i in range(n):
        acc = y[i]
        for s in range(RB_STAGES):
            acc += RB_M[s] * stages[s, i]
        y1[i] = acc
        err[i] = math.inf if singular else stages[RB_STAGES - 1, i]
    return calls


@numba.njit(cache=True, inline="always")
def _dop853_stage(system, t, y, h, s, mode, p, k, yt):
    """Stage ``s`` of DOP853 (steps and continuous extension alike) into ``k[s]``, summed
    over the row's nonzero columns only (:data:`camdyn.integrator.tableaus.D8_A_FROM`)."""
    start = D8_A_FROM[s]
    if y.shape[0] == 3:   # the cam-follower's size, unrolled (the same sums, in the same order)
        c = D8_A[s, 0]
        a0 = c * k[0, 0]
        a1 = c * k[0, 1]
        a2 = c * k[0, 2]
        for j in range(start, s):
            c = D8_A[s, j]
            a0 += c * k[j, 0]
            a1 += c * k[j, 1]
            a2 += c * k[j, 2]
        yt[0] = y[0] + h * a0
        yt[1] = y[1] + h * a1
        yt[2] = y[2] + h * a2
    else:
        for i in range(y.shape[0]):
            acc = D8_A[s, 0] * k[0, i]
            for j in range(start, s):
                acc += D8_A[s, j] * k[j, i]
            yt[i] = y[i] + h * acc
    systems.rhs_inline(system, t + D8_C[s] * h, yt, mode, p, k[s])


@numba.njit(cache=True, inline="always")
def dop853_step(system, t, y, f0, h, mode, p, k, yt, y1, f1, err5, err3, controlled):
    """Explicit DOP853 step: 12 stages plus f(t + h, y1) into ``k[12]`` (``k`` is 16 x n).

    ``err5`` and ``err3`` receive the two embedded error estimates (without the factor
    h) of the first ``controlled`` components (zero for the rest);
    :func:`dop853_error_norm` combines them as Hairer's DOP853 does. ``yt`` is scratch.
    """
    n = y.shape[0]
    for i in range(n):
        k[0, i] = f0[i]
    for s in range(1, D8_STAGES):
        _dop853_stage(system, t, y, h, s, mode, p, k, yt)
    for i in range(n):
        acc = D8_B[0] * k[0, i]
        for j in range(D8_B_FROM, D8_STAGES):
            acc += D8_B[j] * k[j, i]
        y1[i] = y[i] + h * acc
    systems.rhs_inline(system, t + h, y1, mode, p, f1)
    for i in range(n):
        k[D8_STAGES, i] = f1[i]
    for i in range(controlled):   # the estimates of the components the error norm reads
        e5 = D8_E5[0] * k[0, i]
        e3 = D8_E3[0] * k[0, i]
        for j in range(D8_B_FROM, D8_STAGES + 1):
            e5 += D8_E5[j] * k[j, i]
            e3 += D8_E3[j] * k[j, i]
        err5[i] = e5
        err3[i] = e3
    for i in range(controlled, n):
        err5[i] = 0.0
        err3[i] = 0.0
    return D8_STAGES


@numba.njit(cache=True, inline="always")
def dop853_error_norm(y0, y1, err5, err3, h, rtol, atol, controlled, plain):
    """Scaled error norm of a DOP853 step over the first ``controlled`` components:
    Hairer's combination ``h err5^2 / sqrt(err5^2 + 0.01 err3^2)`` of the 5th- and
    3rd-order estimates, or, if ``plain``, the 5th-order estimate ``h |err5|`` alone (never
    smaller; the combination is far smaller where ``err3 >> err5``, which let a step
    approaching a contact separation of the chapter 4 rig through with ``err5`` at 41
    times the tolerance: docs/integrator.md, *Accuracy in sustained contact*) [-]."""
    e5 = 0.0
    e3 = 0.0
    for i in range(controlled):
        sc = absolute_tolerance(atol, i) + rtol * max(abs(y0[i]), abs(y1[i]))
        e5 += (err5[i] / sc) ** 2
        e3 += (err3[i] / sc) ** 2
    if plain:
        return abs(h) * math.sqrt(e5 / controlled)
    denominator = math.sqrt((e5 + 0.01 * e3) * controlled)
    if denominator == 0.0:   # both estimates zero, or e5 zero and 0.01 e3 below the smallest float
        return 0.0
    return abs(h) * e5 / denominator


@numba.njit(cache=True, inline="always")
def dop853_extend(system, t, y, h, y1, f1, mode, p, k, yt, out):
    """Three extra stages and the 7 coefficient rows of DOP853's continuous extension
    into ``out`` (7 x n). Returns the number of right-hand-side calls."""
    for s in range(D8_STAGES + 1, 16):
        _dop853_stage(system, t, y, h, s, mode, p, k, yt)
    for i in range(y.shape[0]):
        dy = y1[i] - y[i]
        out[0, i] = dy
        out[1, i] = h * k[0, i] - dy
        out[2, i] = 2.0 * dy - h * (f1[i] + k[0, i])
        for r in range(4):
            acc = D8_D[r, 0] * k[0, i]
            for j in range(D8_D_FROM, 16):
                acc += D8_D[r, j] * k[j, i]
            out[3 + r, i] = h * acc
    return 3
