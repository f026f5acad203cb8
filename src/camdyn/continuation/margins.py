"""The cam-follower's contact margins over a periodic orbit: the smallest normal force
and the smallest sliding velocity (signed by the direction of sliding), the test
functions of loss of contact and of sliding reversal along a branch.

- Loss of contact in sustained contact is where the smallest normal force over the
  orbit reaches zero, ``min Fn = 0`` (thesis 4.5.1, eq 4.25 in rigid contact). The force
  here is the contact law ``F = F_k(delta) + c delta_dot`` (:func:`camdyn.model.contact.contact_force`)
  evaluated at every sample as if in contact and never clipped at zero, so that the
  test function is smooth and changes sign there (past it, the law would pull).
- Sliding reversal is where the sliding velocity ``vr`` (docs/model.md, sec. 2.3)
  first touches zero: the test function is ``min s vr`` over the samples in contact,
  with ``s`` the sign of ``vr``'s mean over them (the direction the branch slides in).

Both minima are refined by the parabola through the smallest sample and its neighbours.

- Grazing in flight is where the follower's closest approach to the cam between two
  contacts touches it: the test function is the smallest gap at the interior maxima of
  the penetration over samples out of contact, ``min(-delta_max) = 0`` (Di Bernardo et
  al. 2008, *Piecewise-smooth Dynamical Systems*, sec. 8.2). Past it the orbit gains a
  contact; a branch that cannot step across it ends there.
"""

from __future__ import annotations

import math

import numpy as np

from camdyn.model import layout as L
from camdyn.model.outputs import CHANNELS, derived
from camdyn.systems import registry as systems

__all__ = ["contact_margins", "flight_margin"]

_FN = [name for name, _, _ in CHANNELS].index("Fn")
_VR = [name for name, _, _ in CHANNELS].index("sliding_velocity")
_DELTA = [name for name, _, _ in CHANNELS].index("penetration")


def _smallest(values: np.ndarray) -> float:
    """Smallest of periodic samples, refined by the parabola through it and its
    neighbours (error of order the sample spacing cubed)."""
    i = int(np.argmin(values))
    left, middle, right = values[i - 1], values[i], values[(i + 1) % values.size]
    if not (math.isfinite(left) and math.isfinite(right)):
        return float(middle)
    curvature = left - 2.0 * middle + right
    if curvature > 0:
        return float(middle - (right - left) ** 2 / (8.0 * curvature))
    return float(middle)


def contact_margins(system_id: int, p: np.ndarray, times: np.ndarray, states: np.ndarray,
                    modes: np.ndarray) -> tuple[float, float]:
    """``(min Fn [N], min s vr [m/s])`` over an orbit's samples (NaN for a system other
    than the cam-follower, and ``min s vr`` NaN without a sample in contact).

    Parameters
    ----------
    system_id : int
        The registered model; only the cam-follower has these margins.
    p : ndarray
        Its parameter vector.
    times : ndarray (samples,)
        Sample times over one orbit period, the last at the period's end [s].
    states, modes : ndarray (samples, n), (samples, mode size)
        The states (alpha [rad], alpha_dot [rad/s], ...) and hybrid modes there.
    """
    if system_id != systems.CAM_FOLLOWER or times.size < 3:
        return math.nan, math.nan
    unclipped = p.copy()
    unclipped[L.CLIP] = 0.0
    touching = modes.copy()
    touching[:, L.MODE_CONTACT] = 1.0
    channels = derived(times[:-1], states[:-1, :3], touching[:-1], unclipped)   # the last sample is the first
    force = _smallest(channels[:, _FN])
    in_contact = modes[:-1, L.MODE_CONTACT] > 0.5
    if not in_contact.any():
        return force, math.nan
    vr = channels[:, _VR]
    sign = 1.0 if np.mean(vr[in_contact]) >= 0.0 else -1.0
    signed = np.where(in_contact, sign * vr, np.inf)
    return force, _smallest(signed)


def flight_margin(system_id: int, p: np.ndarray, times: np.ndarray, states: np.ndarray,
                  modes: np.ndarray, contact_times: np.ndarray | None) -> float:
    """The cam-follower's smallest gap at a closest approach in flight over an orbit's
    samples [m]: ``-delta`` at the largest interior maximum of the penetration ``delta``
    among samples out of contact, with both neighbours out of contact and no contact
    event between them (a contact shorter than the sample spacing), refined by the
    parabola through it and its neighbours; zero at a grazing (NaN for another system or
    an orbit with no such maximum). ``contact_times`` [s] are the run's contact events;
    the other arguments as :func:`contact_margins`."""
    if system_id != systems.CAM_FOLLOWER or times.size < 4 or contact_times is None:
        return math.nan
    delta = derived(times[:-1], states[:-1, :3], modes[:-1], p)[:, _DELTA]
    free = modes[:-1, L.MODE_CONTACT] < 0.5
    left, right = np.roll(delta, 1), np.roll(delta, -1)
    peaks = free & np.roll(free, 1) & np.roll(free, -1) & (delta > left) & (delta >= right)
    for t in contact_times:        # a contact in the interval (k - 1, k): no peak beside it
        k = int(np.searchsorted(times, t)) % peaks.size
        peaks[[k - 1, k, (k + 1) % peaks.size]] = False
    if not peaks.any():
        return math.nan
    curvature = left[peaks] - 2.0 * delta[peaks] + right[peaks]
    vertex = delta[peaks] - (right[peaks] - left[peaks]) ** 2 / (8.0 * np.minimum(curvature, -1e-300))
    return float(-np.max(vertex))
