"""Small dense linear algebra for the steppers: LU factorization with partial pivoting
and its solve, in place, for the few-by-few matrices of an implicit stage
(``(I / (gamma h) - J) g = r``). Compiled without LAPACK's call overhead, which for a
3 x 3 matrix is larger than the arithmetic."""

from __future__ import annotations

import numba


@numba.njit(cache=True)
def lu_factor(a, pivots):
    """Factor the square matrix ``a`` in place into ``P a = L U`` (unit lower ``L`` below
    the diagonal, ``U`` on and above it); ``pivots[k]`` is the row swapped with row ``k``.

    Returns
    -------
    singular : bool
        Whether a pivot is zero (``a`` is then not invertible; the solve is not valid).
    """
    n = a.shape[0]
    singular = False
    for k in range(n):
        best = k
        size = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > size:
                size = abs(a[i, k])
                best = i
        pivots[k] = best
        if best != k:
            for j in range(n):
                tmp = a[k, j]
                a[k, j] = a[best, j]
                a[best, j] = tmp
        if a[k, k] == 0.0:
            singular = True
            continue
        for i in range(k + 1, n):
            a[i, k] /= a[k, k]
            factor = a[i, k]
            for j in range(k + 1, n):
                a[i, j] -= factor * a[k, j]
    return singular


@numba.njit(cache=True)
def lu_solve(lu, pivots, b, x):
    """Solve ``a x = b`` from :func:`lu_factor`'s ``lu`` and ``pivots`` (``x`` may be
    ``b``)."""
    n = lu.shape[0]
    for i in range(n):
        x[i] = b[i]
    for k in range(n):
        j = pivots[k]
        if j != k:
            tmp = x[k]
            x[k] = x[j]
            x[j] = tmp
    for i in range(n):
        acc = x[i]
        for j in range(i):
            acc -= lu[i, j] * x[j]
        x[i] = acc
    for i in range(n - 1, -1, -1):
        acc = x[i]
        for j in range(i + 1, n):
            acc -= lu[i, j] * x[j]
        x[i] = acc / lu[i, i]
