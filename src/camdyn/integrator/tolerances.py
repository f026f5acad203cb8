"""The absolute tolerance of one state component, for the error norms of the steppers:
``atol`` is one number for every component (a float) or one per component (an array
as long as the state, in each component's unit). numba compiles the integrator once
per kind; with a float the compiled norms are those of a scalar ``atol``."""

from __future__ import annotations

from numba import types
from numba.extending import overload

__all__ = ["absolute_tolerance"]


def absolute_tolerance(atol, i):
    """``atol`` [component ``i``'s unit] of state component ``i``: ``atol`` itself if it
    is a number, else ``atol[i]``."""
    return atol[i] if hasattr(atol, "__getitem__") else atol


@overload(absolute_tolerance, inline="always")
def _compiled_absolute_tolerance(atol, i):
    if isinstance(atol, types.Array):
        return lambda atol, i: atol[i]
    return lambda atol, i: atol
