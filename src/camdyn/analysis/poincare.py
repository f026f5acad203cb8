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
import warnings

import numpy as np
import xarray as xr

from camdyn.errors import ParameterError, SimulationError
from camdyn.params.units import parse_speed
from camdyn.simulation.limits import LargeResultWarning
from camdyn.simulation.translating import TranslatingFollower, simulate_translating

__all__ = ["poincare_section"]

#: Output samples per revolution of each run [-].
SAMPLES_PER_REVOLUTION = 64
#: Most integration steps one revolution may take [-]: a revolution of the Alzate rig
#: takes about 400 near its lift-off speed and 80 at 750 rpm; a run caught in endless
#: shrinking steps is stopped at this bound instead of running for minutes.
STEPS_PER_REVOLUTION = 20_000
#: Tolerances tried, in order, after the requested one, for a revolution whose run stops.
FALLBACK_RTOLS = (1e-9, 1e-11, 1e-8, 1e-12)


def _check(speeds, transient, revolutions):
    """The cam speeds [rpm] from ``speeds`` (Hz, or text with units), and the counts checked."""
    items = np.asarray([speeds] if isinstance(speeds, str) else speeds, dtype=object).reshape(-1)
    hz = np.array([parse_speed(s, "speeds") if isinstance(s, str) else float(s) for s in items], dtype=float)
    rpm = 60.0 * hz
    if rpm.size == 0 or not np.all(np.isfinite(rpm)) or np.any(rpm <= 0.0):
        raise ParameterError("the cam speeds must be positive and finite (a number is read as Hz)")
    for name, value, least in (("transient", transient, 0), ("revolutions", revolutions, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
            raise ParameterError(f"{name} must be a whole number of revolutions, at least {least}, got {value!r}")
    return rpm


def _revolution(follower, omega, state, rtols):
    """One revolution from cam angle 0 (the one-revolution map): the run, and the tolerance
    that completed it; ``(None, message)`` when every tolerance stopped."""
    message = ""
    for rtol in rtols:
        try:
            with warnings.catch_warnings():   # only the end state is used: 64 samples are plenty
                warnings.simplefilter("ignore", LargeResultWarning)
                ds = simulate_translating(follower, f"{float(omega)!r} rad/s", 2.0 * math.pi / omega,
                                          sample_rate=SAMPLES_PER_REVOLUTION * omega / (2.0 * math.pi),
                                          initial_state=state, rtol=rtol, max_steps=STEPS_PER_REVOLUTION)
        except SimulationError as exc:
            message = str(exc)
            continue
        return ds, rtol
    return None, message


def poincare_section(follower: TranslatingFollower, speeds, transient: int = 100, revolutions: int = 50,
                     rtol: float = 1e-10) -> xr.Dataset:
    """The follower's state at cam angle 0 of each revolution, for each cam speed.

    Each speed starts from the follower resting on the cam at cam angle 0 and iterates the
    one-revolution map: a run of one revolution from cam angle 0, started from the state
    the previous one ended in. A revolution whose run stops (rare since the profile's joints
    are events of the model; one long run then works as well) is run
    again at the tolerances of :data:`FALLBACK_RTOLS`; the tolerance that completed each
    revolution is recorded. The first ``transient`` revolutions are dropped.

    Parameters
    ----------
    follower : TranslatingFollower
        The follower and its cam.
    speeds : array_like or str
        Cam speeds [Hz] (revolutions per second), or text with units (``"358 rpm"``,
        ``["6 Hz", "37.5 rad/s"]``). The result is tabulated over ``speed_rpm`` [rpm].
    transient, revolutions : int
        Revolutions dropped, then recorded [-].
    rtol : float
        Relative tolerance of the runs [-].

    Returns
    -------
    xarray.Dataset
        ``x`` [m], ``x_dot`` [m/s] and ``rtol`` over ``speed_rpm`` and ``revolution``;
        ``impacts_per_revolution``, ``separations_per_revolution`` and ``elapsed_s`` over
        ``speed_rpm``; ``status``, "ok" or the message of the run that stopped (the
        points after it NaN). Attributes: the settings and the total time [s].
    """
    rpm = _check(speeds, transient, revolutions)
    rtols = (rtol,) + tuple(r for r in FALLBACK_RTOLS if r != rtol)
    shape = (rpm.size, revolutions)
    x, v, used = np.full(shape, np.nan), np.full(shape, np.nan), np.full(shape, np.nan)
    impacts, separations, elapsed = np.zeros(rpm.size), np.zeros(rpm.size), np.zeros(rpm.size)
    status = []
    start = time.perf_counter()
    for i, speed in enumerate(rpm):
        omega = speed * 2.0 * math.pi / 60.0
        clock = time.perf_counter()
        state, message = None, "ok"
        for k in range(transient + revolutions):
            ds, tolerance = _revolution(follower, omega, state, rtols)
            if ds is None:
                message = f"revolution {k}: {tolerance}"
                break
            state = (float(ds["x"].values[-1]), float(ds["x_dot"].values[-1]))
            if k >= transient:
                j = k - transient
                x[i, j], v[i, j], used[i, j] = state[0], state[1], tolerance
                kinds = ds["event_kind"].values
                impacts[i] += np.count_nonzero(kinds == "impact")
                separations[i] += np.count_nonzero(kinds == "separation")
        elapsed[i] = time.perf_counter() - clock
        status.append(message)
    coords = {"speed_rpm": ("speed_rpm", rpm, {"units": "rpm", "long_name": "cam speed"}),
              "revolution": ("revolution", np.arange(transient, transient + revolutions),
                             {"units": "1", "long_name": "revolution since the start"})}
    data = {
        "x": (("speed_rpm", "revolution"), x, {"units": "m", "long_name": "follower position at cam angle 0"}),
        "x_dot": (("speed_rpm", "revolution"), v, {"units": "m/s", "long_name": "follower velocity at cam angle 0"}),
        "rtol": (("speed_rpm", "revolution"), used, {"units": "1", "long_name": "tolerance of the revolution's run"}),
        "impacts_per_revolution": (("speed_rpm",), impacts / revolutions,
                                   {"units": "1", "long_name": "impacts per recorded revolution"}),
        "separations_per_revolution": (("speed_rpm",), separations / revolutions,
                                       {"units": "1", "long_name": "separations per recorded revolution"}),
        "elapsed_s": (("speed_rpm",), elapsed, {"units": "s", "long_name": "time the speed's runs took"}),
        "status": (("speed_rpm",), np.array(status, dtype=str), {"long_name": "ok, or why the runs stopped"}),
    }
    return xr.Dataset(data, coords=coords, attrs={
        "title": "Poincaré section of a translating follower at cam angle 0", "citation": follower.citation,
        "transient_revolutions": int(transient), "recorded_revolutions": int(revolutions), "rtol": float(rtol),
        "samples_per_revolution": SAMPLES_PER_REVOLUTION, "total_elapsed_s": time.perf_counter() - start})
