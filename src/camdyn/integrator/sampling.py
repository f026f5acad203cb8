"""Output samples of the driver: the requested output times that a step (or the part of
it before an event) passes over, filled from the step's continuous extension."""

from __future__ import annotations

import numba

from camdyn.integrator.nordsieck import nordsieck_dense
from camdyn.integrator.steppers import KIND_DOP853, KIND_NORDSIECK, dense, dop853_dense


@numba.njit(cache=True, inline="always")
def sample(t, h, t_stop, i_out, t_out, y0, f0, y1, f1, work, kind, mode, scratch, y_out, mode_out):
    """Fill the output times in (t, t_stop] of the current step; return the next index."""
    n_out = t_out.shape[0]
    while i_out < n_out and t_out[i_out] <= t_stop:
        if kind == KIND_DOP853:
            dop853_dense((t_out[i_out] - t) / h, y0, work, scratch)
        elif kind == KIND_NORDSIECK:
            nordsieck_dense((t_out[i_out] - t) / h, work, y0.shape[0], scratch)
        else:
            dense((t_out[i_out] - t) / h, h, y0, f0, y1, f1, work, kind, scratch)
        for i in range(y0.shape[0]):
            y_out[i_out, i] = scratch[i]
        for i in range(mode.shape[0]):
            mode_out[i_out, i] = mode[i]
        i_out += 1
    return i_out
