"""The coefficients of Radau IIA of order 5 (:mod:`camdyn.integrator.radau`): the
Butcher tableau, the transformation that splits its Newton iteration into one real and
one complex ``n x n`` system, the weights of the embedded error estimate and those of
the collocation polynomial (dense output), all computed here once, at import, from the
tableau's closed forms ([1], IV.5 and IV.8; RADAU5's constants [2]). The tests check
them against Hairer and Wanner's closed forms.

References
----------
[1] E. Hairer, G. Wanner, Solving Ordinary Differential Equations II: Stiff and
    Differential-Algebraic Problems, 2nd ed., Springer (1996), sections IV.5 and IV.8,
    doi:10.1007/978-3-642-05221-7.
[2] E. Hairer, G. Wanner, radau5.f (Fortran code of RADAU5, version of 1996), described
    in [1], IV.8.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["RADAU_A", "RADAU_B", "RADAU_C", "RADAU_T", "RADAU_TI", "RADAU_GAMMA", "RADAU_ALPHA", "RADAU_BETA",
           "RADAU_E", "RADAU_P"]

# Coefficients ([1], IV.5: the Radau IIA method of order 5, s = 3).
_S6 = math.sqrt(6.0)
RADAU_C = np.array([(4.0 - _S6) / 10.0, (4.0 + _S6) / 10.0, 1.0])
RADAU_A = np.array([
    [(88.0 - 7.0 * _S6) / 360.0, (296.0 - 169.0 * _S6) / 1800.0, (-2.0 + 3.0 * _S6) / 225.0],
    [(296.0 + 169.0 * _S6) / 1800.0, (88.0 + 7.0 * _S6) / 360.0, (-2.0 - 3.0 * _S6) / 225.0],
    [(16.0 - _S6) / 36.0, (16.0 + _S6) / 36.0, 1.0 / 9.0],
])
RADAU_B = RADAU_A[2].copy()   # stiffly accurate: b is A's last row, y_1 = y + z_3


def _transformation():
    """``T``, ``T^-1`` and ``gamma, alpha, beta`` of ``A^-1 = T Lambda T^-1`` ([1], IV.8):
    the eigenvector of ``A^-1``'s real eigenvalue ``gamma`` and the real and imaginary
    parts ``u, w`` of the eigenvector of ``alpha + i beta`` (``A^-1 (u + i w) =
    (alpha + i beta)(u + i w)``), each scaled to a last component of 1 (so that ``w``'s
    last component is 0, as in RADAU5)."""
    a_inv = np.linalg.inv(RADAU_A)
    values, vectors = np.linalg.eig(a_inv)
    real = int(np.argmin(np.abs(values.imag)))
    pair = int(np.argmax(values.imag))           # alpha + i beta with beta > 0
    v_real = (vectors[:, real] / vectors[2, real]).real
    v_pair = vectors[:, pair] / vectors[2, pair]
    t = np.column_stack([v_real, v_pair.real, v_pair.imag])
    ti = np.linalg.inv(t)
    lam = ti @ a_inv @ t
    return (np.ascontiguousarray(t), np.ascontiguousarray(ti),
            float(lam[0, 0]), float(lam[1, 1]), float(lam[1, 2]))


RADAU_T, RADAU_TI, RADAU_GAMMA, RADAU_ALPHA, RADAU_BETA = _transformation()


def _error_weights():
    """``e`` of the embedded error estimate ([1], IV.8, "Error estimation"; RADAU5's
    ``DD1..DD3``): the third-order formula ``y^_1 = y + h (gamma_0 f(t, y) + sum_i
    b^_i F_i)`` with ``gamma_0 = 1 / gamma`` (the real eigenvalue of ``A``) gives
    ``y^_1 - y_1 = gamma_0 (h f(t, y) + sum_i e_i z_i)``, with ``e^T = (b^ - b)^T A^-1 /
    gamma_0`` since ``h F = (A^-1 x I) Z``."""
    gamma0 = 1.0 / RADAU_GAMMA
    # order conditions sum b^_i c_i^(k-1) = 1/k - gamma_0 [k = 1], k = 1, 2, 3
    vander = np.vstack([RADAU_C ** k for k in range(3)])
    rhs = np.array([1.0 - gamma0, 0.5, 1.0 / 3.0])
    b_hat = np.linalg.solve(vander, rhs)
    return np.ascontiguousarray((b_hat - RADAU_B) @ np.linalg.inv(RADAU_A) / gamma0)


RADAU_E = _error_weights()


def _dense_weights():
    """``P`` of the collocation polynomial ``u(t + theta h) = y + sum_i z_i sum_k P[i, k]
    theta^(k+1)``: the cubic through ``(0, y)`` and ``(c_i, y + z_i)`` (Lagrange basis
    polynomials of the nodes ``c_i`` that vanish at 0) ([1], IV.8, "Starting values for
    the Newton iteration"; RADAU5's CONTR5 evaluates the same polynomial in Newton form)."""
    vander = np.array([[c ** (k + 1) for k in range(3)] for c in RADAU_C])   # rows: nodes
    # polynomial i's coefficients q_i satisfy vander @ q_i = e_i
    return np.ascontiguousarray(np.linalg.inv(vander).T)


RADAU_P = _dense_weights()
