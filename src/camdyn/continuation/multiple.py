"""The linear algebra of multiple shooting for periodic orbits.

The orbit's period ``k T`` [s] is cut at ``m`` equally spaced times ``t_0 < t_1 < ... <
t_m = t_0 + k T``. The unknowns are the states ``x_i`` at ``t_i`` (``i = 0 .. m-1``); the
residuals are the continuity conditions

``r_i = phi_i(x_i) - x_{i+1}``,  with ``x_m = x_0``,                             (1)

where ``phi_i`` is the hybrid flow from ``t_i`` to ``t_{i+1}``. Their Jacobian is cyclic
block-bidiagonal: block row ``i`` holds the segment's state-transition matrix ``A_i``
(saltation included) in block column ``i`` and ``-I`` in block column ``i + 1`` (mod
``m``); Newton's step solves ``J dX = -R`` (Seydel 2010, *Practical Bifurcation and
Stability Analysis*, Springer, doi:10.1007/978-1-4419-1740-9, ch. 7; Ascher, Mattheij &
Russell 1995, *Numerical Solution of Boundary Value Problems for Ordinary Differential
Equations*, SIAM, doi:10.1137/1.9781611971231, sec. 4.3). The monodromy matrix of the
orbit is the product ``A_{m-1} ... A_1 A_0`` (the chain rule through the segments).
With ``m = 1`` the Jacobian is ``A_0 - I``, single shooting's.

The system is assembled dense, ``(m u) x (m u)`` for ``u`` unknowns per state, and solved
by least squares (as single shooting's ``M - I``, which is singular at a fold): with the
two or three unknowns of camdyn's models and tens of segments it has at most a few
hundred rows, and its sparsity is not worth exploiting. It is not condensed onto ``x_0`` (which would form
the product of the ``A_i`` and bring back single shooting's conditioning in the linear
step).
"""

from __future__ import annotations

import numpy as np

__all__ = ["continuity", "cyclic_jacobian", "monodromy", "newton_step", "segment_times"]


def segment_times(t_start: float, duration: float, segments: int) -> np.ndarray:
    """The ``segments + 1`` boundaries ``t_i = t_start + i duration / segments`` [s]; the
    last is ``t_start + duration`` exactly (single shooting's end time when ``segments``
    is 1)."""
    times = t_start + duration * np.arange(segments + 1) / segments
    times[0], times[-1] = t_start, t_start + duration
    return times


def continuity(ends: np.ndarray, states: np.ndarray) -> np.ndarray:
    """The residuals (1): ``ends[i] - states[(i + 1) mod m]``, shape ``(m, u)`` (units of
    the state)."""
    return ends - np.roll(states, -1, axis=0)


def cyclic_jacobian(matrices: np.ndarray) -> np.ndarray:
    """The Jacobian of the residuals (1) with respect to the stacked states, ``(m u, m
    u)``, from the segments' state-transition matrices ``matrices`` ``(m, u, u)``."""
    m, u, _ = matrices.shape
    jacobian = np.zeros((m * u, m * u))
    eye = np.eye(u)
    for i in range(m):
        rows = slice(i * u, (i + 1) * u)
        jacobian[rows, rows] += matrices[i]
        after = (i + 1) % m
        jacobian[rows, after * u:(after + 1) * u] -= eye
    return jacobian


def newton_step(jacobian: np.ndarray, residuals: np.ndarray) -> np.ndarray:
    """Newton's correction ``dX`` of the states, shape ``(m, u)``: the least-squares
    solution of ``J dX = -R``."""
    m, u = residuals.shape
    return np.linalg.lstsq(jacobian, -residuals.ravel(), rcond=None)[0].reshape(m, u)


def monodromy(matrices: np.ndarray) -> np.ndarray:
    """The monodromy matrix at ``t_0``: the product of the segments' matrices ``(m, u,
    u)``, the last leftmost. Formed plainly: its eigenvalues are as accurate as the
    product's entries, which is enough while the largest multiplier's modulus times the
    integration tolerance stays well below 1 (a periodic Schur decomposition would keep
    the small multipliers' accuracy beside very large ones)."""
    product = matrices[0].copy()
    for matrix in matrices[1:]:
        product = matrix @ product
    return product
