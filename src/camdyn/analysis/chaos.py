"""The largest Lyapunov exponent of the hybrid cam-follower (thesis 3.6).

Two nearby trajectories are integrated side by side through every contact, impact and
separation, each with its own event location (so the exponent is computed across the
impacts properly, without linearising the jump), and the gap between them is measured
and renormalised once per cam period (Benettin's method; Benettin et al., Meccanica 15,
9-20, 1980, doi:10.1007/BF02128236):

``lambda = (1 / (N T)) sum_k ln(d_k / d0)``  [1/s]

with ``d = sqrt(d_alpha^2 + (d_alpha_dot / Omega)^2)`` [rad], the angular-velocity gap
scaled by the cam's angular speed ``Omega`` so that both parts are angles. The gap is
restored to ``d0`` along its own direction after each period. A periodic motion gives
``lambda < 0`` (its slowest decay rate), a chaotic one ``lambda > 0``.

Each period restarts the integration from the state (the hybrid mode is found again from
the geometry), which is exact for every damping law whose force depends on the state
only; restitution-parameterised laws (Hunt-Crossley, Lankarani-Nikravesh, Flores) read
the approach velocity of the current contact, which a restart inside a contact resets.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from camdyn.analysis.lyapunov import LyapunovSpectrum, check_periods, count, standard_error
from camdyn.errors import ParameterError, SimulationError
from camdyn.integrator import driver
from camdyn.model.equilibrium import as_system
from camdyn.params.system import System
from camdyn.simulation import limits
from camdyn.simulation.limits import SCAN_FRACTION, STEP_FRACTION
from camdyn.systems import registry as systems

__all__ = ["LyapunovResult", "lyapunov_exponent", "agreement", "START_ALLOWANCE"]


@numba.njit(cache=True)
def _advance(p, y, t0, t1, rtol, atol, period):
    t_out = np.array([t1])
    # np.int64 and np.bool_, not literals: a literal argument is a type of its own to numba,
    # and each new type of argument costs a whole compile of the driver
    out, modes, events, counters = driver.integrate(systems.CAM_FOLLOWER, p, y, t0, t1, t_out, rtol, atol,
                                                    period * STEP_FRACTION, driver.METHOD_AUTO, np.int64(10 ** 8),
                                                    np.int64(16), np.bool_(True), period * SCAN_FRACTION)
    return out[0].copy(), counters[driver.COUNT_STATUS]


@numba.njit(cache=True)
def _benettin(p, y0, period, omega, transient, revolutions, d0, rtol, atol):
    """ln(d_k / d0) for each period k after the transient; status (0 ok)."""
    y = y0.copy()
    t = 0.0
    for _ in range(transient):
        y, status = _advance(p, y, t, t + period, rtol, atol, period)
        if status != 0:
            return np.empty(0), status
        t += period
    z = y.copy()
    z[0] += d0 / math.sqrt(2.0)
    z[1] += omega * d0 / math.sqrt(2.0)
    logs = np.empty(revolutions)
    for k in range(revolutions):
        y, status = _advance(p, y, t, t + period, rtol, atol, period)
        if status != 0:
            return logs[:k], status
        z, status = _advance(p, z, t, t + period, rtol, atol, period)
        if status != 0:
            return logs[:k], status
        t += period
        da = z[0] - y[0]
        dv = (z[1] - y[1]) / omega
        d = math.sqrt(da * da + dv * dv)
        if d == 0.0:
            d = 1e-300
        logs[k] = math.log(d / d0)
        z[0] = y[0] + da * d0 / d
        z[1] = y[1] + dv * omega * d0 / d
        z[2] = y[2]
    return logs, 0


@dataclass(frozen=True)
class LyapunovResult:
    """Largest Lyapunov exponent of one operating point.

    Attributes
    ----------
    exponent : float
        lambda [1/s].
    per_revolution : float
        lambda T, the mean log growth of the gap per cam period [-].
    running : ndarray
        The estimate [1/s] after 1, 2, ... periods (its convergence).
    speed : float
        Cam speed [Hz].
    revolutions, transient : int
        Periods averaged, and discarded first [-].
    error : float
        Standard error of ``exponent`` [1/s]
        (:func:`camdyn.analysis.lyapunov.standard_error`, from the per-period
        ``ln(d_k / d0)``): its statistical uncertainty over ``revolutions``.
    """

    exponent: float
    per_revolution: float
    running: np.ndarray
    speed: float
    revolutions: int
    transient: int
    error: float = math.nan


def lyapunov_exponent(system: System, speed: float | None = None, revolutions: int = 400, transient: int = 200,
                      separation: float = 1e-7, rtol: float = 1e-10, atol: float = 1e-13) -> LyapunovResult:
    """Largest Lyapunov exponent of the follower's steady motion at one cam speed.

    Parameters
    ----------
    system : System
        Constant cam motion.
    speed : float, optional
        Cam speed [Hz]; default ``system.motion.speed``.
    revolutions : int
        Cam periods averaged [-].
    transient : int
        Cam periods simulated and dropped first [-].
    separation : float
        Gap d0 between the trajectories [rad]; far above the integration error at
        ``rtol`` (about 1e-11 rad per period here) and far below the motion (0.1 rad).
    rtol, atol : float
        Local error tolerances.
    """
    from camdyn.simulation.runner import prepare, with_speed

    system = as_system(system)
    if system.motion.kind != "constant":
        raise ParameterError("the Lyapunov exponent here needs constant cam motion (motion.kind = 'constant')")
    system = with_speed(system, speed)
    revolutions = count("revolutions", revolutions, 1)
    transient = count("transient", transient, 0)
    check_periods(revolutions, transient, 1)
    separation = limits.check_number("separation", separation, "rad")
    if not (0 < separation < 1e-3):
        raise ParameterError(f"separation must lie in (0, 1e-3) rad, got {separation!r}")
    limits.check_tolerances(rtol, atol)
    period = system.motion.period
    if not math.isfinite(period):
        raise ParameterError("the cam does not move (speed 0)")
    prep = prepare(system)
    omega = 2.0 * math.pi / period
    logs, status = _benettin(prep.p, prep.y0, period, omega, transient, revolutions, separation, rtol, atol)
    if status == driver.STATUS_INTERRUPTED:
        raise KeyboardInterrupt
    if status != 0:
        raise SimulationError(f"Lyapunov exponent at {system.motion.speed:g} Hz: "
                              f"{driver.STATUS_MESSAGES[int(status)]}")
    running = np.cumsum(logs) / (np.arange(1, revolutions + 1) * period)
    return LyapunovResult(exponent=float(running[-1]), per_revolution=float(running[-1] * period),
                          running=running, speed=system.motion.speed, revolutions=revolutions, transient=transient,
                          error=standard_error(logs, period))


#: Bias of a finite-time exponent from its start [-, times 1 / (N T)]: the first gap's
#: (or tangent vector's) share ``c`` of the slowest-decaying direction adds
#: ``ln|c| / (N T)``; ``|ln c| <= ln 10`` is allowed for each estimate.
START_ALLOWANCE = math.log(10.0)


def agreement(two: LyapunovResult, spectrum: LyapunovSpectrum) -> tuple[bool, str]:
    """Whether the largest exponent of two trajectories (``two``) and of the variational
    spectrum (``spectrum``) agree, and a sentence that says so or why not.

    They agree when they differ by at most twice their combined standard error plus
    each one's start allowance :data:`START_ALLOWANCE` / (N T). The two follow different
    trajectories: the spectrum's run controls the error of the matrix too, at its own
    tolerance, so on a chaotic attractor its orbit parts from the two-trajectory run's
    within a few revolutions, and each is the average of a different finite stretch of
    the attractor, whose growth per revolution scatters widely. Both carry the saltation
    of every impact (the two trajectories through their own events, the tangent vectors
    by the saltation matrices).
    """
    period = 1.0 / two.speed
    difference = two.exponent - spectrum.largest
    combined = math.hypot(two.error, spectrum.errors[0]) if spectrum.errors.size else math.nan
    start = START_ALLOWANCE * (1.0 / (two.revolutions * period) + 1.0 / (spectrum.periods * period))
    allowed = 2.0 * combined + start
    numbers = (f"{two.exponent:.4g} and {spectrum.largest:.4g} 1/s differ by {abs(difference):.3g} 1/s; "
               f"allowed {allowed:.3g} (twice the combined standard error {combined:.3g}, plus {start:.3g} for "
               f"the starts)")
    if math.isfinite(allowed) and abs(difference) <= allowed:
        return True, (f"the two largest exponents agree within their uncertainty: {numbers}. They average different "
                      f"stretches of the motion (the two runs part within a few revolutions on a chaotic "
                      f"attractor), so they agree only to within that uncertainty; more revolutions narrow it")
    return False, (f"the two largest exponents do not agree within their uncertainty: {numbers}. The two runs "
                   f"follow different trajectories: the motion may not have settled within the transient, or "
                   f"may switch between coexisting motions (the runs can end on different ones); try a longer "
                   f"--transient and more --revolutions")
