"""The Poincaré section of a translating follower against cam speed: the bifurcation
diagram's data.

The cam turns at constant speed, so the stroboscopic section at a fixed cam angle is a
Poincaré section of the (periodically forced) follower: the state ``(x [m], x_dot [m/s])``
is recorded at cam angle 0, once per revolution, after a transient. A period-n motion
shows n points per speed, a quasi-periodic or chaotic one a cloud (S. Strogatz,
*Nonlinear Dynamics and Chaos*, 2nd ed., Westview 2015, section 8.7; the cam-follower
case in R. Alzate et al., Nonlinear Dynamics 50 (2007) 409-429,
doi:10.1007/s11071-006-9177-2).
"""

from __future__ import annotations

import math
import time

import numpy as np
import xarray as xr

from camdyn.errors import ParameterError, SimulationError
from camdyn.simulation.translating import TranslatingFollower, simulate_translating

__all__ = ["poincare_section"]

#: Output samples per revolution of each run [-]; every this-many-th sample is at cam angle 0.
SAMPLES_PER_REVOLUTION = 64


def _check(speeds, transient, revolutions):
    rpm = np.asarray(speeds, dtype=float).reshape(-1)
    if rpm.size == 0 or not np.all(np.isfinite(rpm)) or np.any(rpm <= 0.0):
        raise ParameterError("the cam speeds must be positive and finite [rpm]")
    for name, value in (("transient", transient), ("revolutions", revolutions)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < (1 if name ==
                                                                                             "revolutions" else 0):
            raise ParameterError(f"{name} must be a whole number of revolutions (at least "
                                 f"{1 if name == 'revolutions' else 0}), got {value!r}")
    return rpm


def poincare_section(follower: TranslatingFollower, speeds, transient: int = 100, revolutions: int = 50,
                     rtol: float = 1e-10) -> xr.Dataset:
    """The follower's state at cam angle 0 of each revolution, for each cam speed.

    Each speed is a separate run from the follower resting on the cam at cam angle 0
    (``phase`` 0), over ``transient + revolutions`` revolutions; the first ``transient``
    are dropped.

    Parameters
    ----------
    follower : TranslatingFollower
        The follower and its cam.
    speeds : array_like
        Cam speeds [rpm].
    transient, revolutions : int
        Revolutions dropped, then recorded [-].
    rtol : float
        Relative tolerance of the runs [-].

    Returns
    -------
    xarray.Dataset
        ``x`` [m] and ``x_dot`` [m/s] over ``speed_rpm`` and ``revolution``;
        ``impacts_per_revolution``, ``separations_per_revolution`` and ``elapsed_s`` over
        ``speed_rpm``; ``status``, "ok" or the message of a run that stopped (its points
        NaN). Attributes: the settings and the total time [s].
    """
    rpm = _check(speeds, transient, revolutions)
    n = SAMPLES_PER_REVOLUTION
    x = np.full((rpm.size, revolutions), np.nan)
    v = np.full((rpm.size, revolutions), np.nan)
    impacts, separations, elapsed = (np.full(rpm.size, np.nan) for _ in range(3))
    status = []
    start = time.perf_counter()
    for i, speed in enumerate(rpm):
        omega = speed * 2.0 * math.pi / 60.0
        rate = omega / (2.0 * math.pi)
        total = transient + revolutions
        clock = time.perf_counter()
        try:
            ds = simulate_translating(follower, omega, (total + 0.5 / n) / rate, sample_rate=n * rate, rtol=rtol)
        except SimulationError as exc:
            status.append(str(exc))
            continue
        elapsed[i] = time.perf_counter() - clock
        status.append("ok")
        x[i] = ds["x"].values[n * transient:n * total + 1:n][:revolutions]
        v[i] = ds["x_dot"].values[n * transient:n * total + 1:n][:revolutions]
        recorded = ds["event_time"].values >= transient / rate
        kinds = ds["event_kind"].values[recorded]
        impacts[i] = np.count_nonzero(kinds == "impact") / revolutions
        separations[i] = np.count_nonzero(kinds == "separation") / revolutions
    coords = {"speed_rpm": ("speed_rpm", rpm, {"units": "rpm", "long_name": "cam speed"}),
              "revolution": ("revolution", np.arange(transient, transient + revolutions),
                             {"units": "1", "long_name": "revolution since the start"})}
    data = {
        "x": (("speed_rpm", "revolution"), x, {"units": "m", "long_name": "follower position at cam angle 0"}),
        "x_dot": (("speed_rpm", "revolution"), v, {"units": "m/s", "long_name": "follower velocity at cam angle 0"}),
        "impacts_per_revolution": (("speed_rpm",), impacts, {"units": "1", "long_name": "impacts per revolution"}),
        "separations_per_revolution": (("speed_rpm",), separations,
                                       {"units": "1", "long_name": "separations per revolution"}),
        "elapsed_s": (("speed_rpm",), elapsed, {"units": "s", "long_name": "time the run took"}),
        "status": (("speed_rpm",), np.array(status, dtype=str), {"long_name": "ok, or why the run stopped"}),
    }
    return xr.Dataset(data, coords=coords, attrs={
        "title": "Poincaré section of a translating follower at cam angle 0", "citation": follower.citation,
        "transient_revolutions": int(transient), "recorded_revolutions": int(revolutions), "rtol": float(rtol),
        "total_elapsed_s": time.perf_counter() - start})
