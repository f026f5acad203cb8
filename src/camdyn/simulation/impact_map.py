"""Instantaneous-restitution simulation of the impacting follower (thesis 3.8.1,
simulation S3).

Between impacts the follower flies freely (eq 3.9). At contact onset the impact is
instantaneous: the penetration rate reverses with the coefficient of restitution
``xi = 1 - gamma v_a`` (eq 3.24, Hunt and Crossley's velocity-dependent form) or a
constant ``xi``,

    psi_dot(after) = -xi psi_dot(before)            (eq 3.25)

and, with the angle and cam angle unchanged through the instant, the follower's rate
after impact follows from ``psi_dot = -alpha_dot chi - n . v_cam`` (eq 3.27):

    alpha_dot(after) = (xi psi_dot(before) - n . v_cam) / chi

Each flight is one whole compiled simulation (:func:`camdyn.integrator.driver.integrate`),
stopped at the next onset; friction impulses are not modelled (as in eq 3.27).

A sampled accelerometer cannot show an instantaneous jump. With ``pulse_duration > 0``
the same jump of ``alpha_dot`` is spread over a Hann-shaped acceleration pulse that
starts at the onset, and the follower's angle is integrated through it, so the record
(``alpha``, ``alpha_dot``, ``alpha_ddot``) is one consistent trajectory that touches the
cam exactly at each onset. The follower then sinks slightly into the cam during the
pulse (``v_a w (1 - xi) / 2`` at its end, a few um for a 156 us pulse): the contact has no
stiffness in S3, only the restitution law.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from scipy.integrate import solve_ivp

from camdyn.errors import ParameterError, SimulationError
from camdyn.integrator import driver
from camdyn.model import layout as L
from camdyn.model.dynamics import free_acceleration
from camdyn.model.geometry import cam_angle, contact_kinematics
from camdyn.params.config import system_to_toml
from camdyn.params.system import System
from camdyn.params.units import parse_speed
from camdyn.simulation import limits
from camdyn.simulation.runner import prepare
from camdyn.systems import registry as systems

#: event-log column of alpha at the event (then alpha_dot): after the cam-follower's 3 guards
ALPHA_AT = driver.event_columns(3, 3).index("state0")

__all__ = ["simulate_impact_map"]


def simulate_impact_map(system: System, speed=None, revolutions: float = 30.0, gamma: float | None = 0.8,
                        restitution: float | None = None, sample_rate: float = 20e3,
                        rtol: float = 1e-10, atol: float = 1e-12, max_impacts: int | None = None,
                        pulse_duration: float = 0.0) -> xr.Dataset:
    """Simulate the follower with instantaneous impacts (simulation S3).

    Parameters
    ----------
    system : System
        The rig (its contact damping law is not used).
    speed : float or str, optional
        Cam speed [Hz] or text (``"16 Hz"``); default ``system.motion.speed``.
    revolutions : float
        Length [cam revolutions].
    gamma : float
        Slope of ``xi = 1 - gamma v_a`` [s/m] (eq 3.24); ignored if ``restitution`` is given.
    restitution : float, optional
        A constant coefficient of restitution ``xi`` [-].
    sample_rate : float
        Output rate [Hz].
    pulse_duration : float
        0 for instantaneous impacts; otherwise the length [s] of the Hann-shaped
        acceleration pulse that carries each jump of ``alpha_dot`` (its area is the jump).

    Returns
    -------
    xarray.Dataset
        ``alpha`` [rad], ``alpha_dot`` [rad/s], ``alpha_ddot`` [rad/s^2] (free flight, plus
        the pulses when ``pulse_duration > 0``; otherwise the impulses are Dirac pulses,
        listed over ``impact``), ``cam_angle`` [rad] over
        ``time``; over ``impact``: ``impact_time`` [s], ``impact_approach_velocity`` and
        ``impact_separation_velocity`` [m/s], ``impact_restitution`` [-] and
        ``impact_rate_jump`` [rad/s].
    """
    system = _checked_system(system, speed, revolutions, gamma, restitution, pulse_duration)
    period = system.motion.period
    prep = prepare(system)
    p = prep.p.copy()
    # S3 has no contact force: the restitution law is the whole contact (a pulse may
    # leave the follower a micrometre inside the cam, which must not push it)
    p[L.ESTAR] = 0.0
    p[L.VISCOUS_C] = 0.0
    p[L.BETA] = 0.0
    duration = revolutions * period
    n_out = int(math.floor(duration * sample_rate + 1e-9)) + 1
    t_out = np.arange(n_out) / sample_rate
    y_out = np.full((n_out, 2), np.nan)
    # start in free flight just off the cam at the static angle, falling onto it
    chi = contact_kinematics(prep.y0[0], 0.0, prep.theta0, 0.0, p)[2]
    y = np.array([prep.y0[0] + math.copysign(1e-4, chi), 0.0, 0.0])
    law = (restitution, gamma)
    limit = max_impacts if max_impacts is not None else int(20 * revolutions + 100)
    rows = _flights(p, y, duration, period, t_out, y_out, rtol, atol, law, limit, pulse_duration)
    imp = np.array(rows, dtype=float).reshape(-1, 5)
    acc = np.array([free_acceleration(a, p) if math.isfinite(a) else math.nan for a in y_out[:, 0]])
    if pulse_duration > 0:
        for t_hit, jump in imp[:, [0, 4]]:
            inside = (t_out >= t_hit) & (t_out < t_hit + pulse_duration)
            acc[inside] += jump * _hann(t_out[inside] - t_hit, pulse_duration)
    return _dataset(system, prep, p, t_out, y_out, acc, imp, law, pulse_duration)


def _checked_system(system: System, speed, revolutions: float, gamma: float | None, restitution: float | None,
                    pulse_duration: float) -> System:
    """The rig at ``speed`` [Hz], after checking the arguments of :func:`simulate_impact_map`."""
    if speed is not None:
        system = system.with_values(**{"motion.speed": parse_speed(speed)})
    if system.motion.kind != "constant":
        raise ParameterError("the impact-map simulation needs constant cam motion")
    if restitution is None:
        if gamma is None or not (math.isfinite(gamma) and gamma >= 0):
            raise ParameterError(f"gamma must be a non-negative slope in s/m, got {gamma!r}")
    elif not (0.0 <= restitution <= 1.0):
        raise ParameterError(f"the coefficient of restitution must lie in [0, 1], got {restitution!r}")
    period = system.motion.period
    if not (math.isfinite(period) and revolutions > 0):
        raise ParameterError("give a positive speed and number of revolutions")
    if not (math.isfinite(pulse_duration) and 0.0 <= pulse_duration < 0.05 * period):
        raise ParameterError(f"the impulse pulse must last between 0 and 5 % of the cam period, "
                             f"got {pulse_duration!r} s")
    return system


def _flights(p, y, duration, period, t_out, y_out, rtol, atol, law, limit, pulse_duration) -> list:
    """Simulate the free flights between impacts and apply each impact.

    Parameters
    ----------
    p : ndarray
        Parameter vector without contact force (:mod:`camdyn.model.layout`).
    y : ndarray (3,)
        Initial state: angle [rad], rate [rad/s], cam work [J].
    duration, period : float
        Length of the run and cam period [s].
    t_out : ndarray
        Output times [s]; ``y_out`` (n_out, 2) receives the angle [rad] and rate [rad/s].
    rtol, atol : float
        Tolerances of the driver.
    law : tuple
        ``(restitution, gamma)``: a constant ``xi`` [-] or None, and the slope [s/m].
    limit : int
        Most impacts allowed [-].
    pulse_duration : float
        Length of each impulse pulse [s] (0: instantaneous).

    Returns
    -------
    list of tuple
        Per impact: time [s], approach and separation velocity [m/s], ``xi`` [-] and
        the jump of ``alpha_dot`` [rad/s].
    """
    t = 0.0
    rows = []
    h_max, scan = limits.step_limits(period)
    while t < duration:
        mask = t_out >= t
        span_end = min(duration, t + 1.5 * period)
        times = t_out[mask & (t_out <= span_end)]
        ys, modes, events, counters = driver.integrate(
            systems.CAM_FOLLOWER, p, y, t, span_end, times if times.size else np.array([span_end]),
            rtol, atol, h_max, driver.METHOD_DOP853, 10_000_000, 64, False, scan)
        if counters[driver.COUNT_STATUS] != driver.STATUS_OK:
            raise SimulationError(f"impact-map simulation {driver.STATUS_MESSAGES[int(counters[driver.COUNT_STATUS])]}"
                                  f" near t = {t:.6g} s")
        onsets = events[(events[:, 1] == 0) & (events[:, 2] > 0)]
        onsets = onsets[onsets[:, 0] > t + 1e-12]
        t_hit = onsets[0, 0] if onsets.size else math.inf
        if times.size:
            keep = times < t_hit
            idx = np.flatnonzero(mask & (t_out <= span_end))[keep]
            y_out[idx] = ys[keep, :2]
        if not math.isfinite(t_hit):
            t = span_end
            y = ys[-1].copy() if times.size else y
            continue
        alpha, rate = onsets[0, ALPHA_AT], onsets[0, ALPHA_AT + 1]
        row, new_rate = _impact(p, t_hit, alpha, rate, law)
        rows.append(row)
        if len(rows) > limit:
            raise SimulationError(f"more than {limit} impacts: the follower chatters (xi near 1 at low "
                                  "approach velocity); shorten the run or lower the restitution")
        if pulse_duration > 0:
            t, state = _through_pulse(p, t_hit, alpha, rate, row[4], pulse_duration, t_out, y_out)
            y = np.array([state[0], state[1], 0.0])
        else:
            t = t_hit
            y = np.array([alpha, new_rate, 0.0])
    return rows


def _impact(p, t_hit, alpha, rate, law) -> tuple[tuple, float]:
    """The restitution law at one impact (eqs 3.24-3.27).

    Parameters
    ----------
    p : ndarray
        Parameter vector.
    t_hit : float
        Time of the contact onset [s].
    alpha, rate : float
        Follower angle [rad] and rate [rad/s] at the onset.
    law : tuple
        ``(restitution, gamma)``: a constant ``xi`` [-] or None, and the slope [s/m].

    Returns
    -------
    row : tuple
        Time [s], approach and separation velocity [m/s], ``xi`` [-] and the jump of
        ``alpha_dot`` [rad/s].
    new_rate : float
        ``alpha_dot`` after the impact [rad/s].
    """
    restitution, gamma = law
    theta, theta_dot = cam_angle(t_hit, p)
    _, delta_dot, chi, _, _, n_v, _ = contact_kinematics(alpha, rate, theta, theta_dot, p)
    xi = restitution if restitution is not None else 1.0 - gamma * delta_dot
    if xi < 0:
        raise SimulationError(f"approach velocity {delta_dot:.4g} m/s exceeds 1/gamma: xi = 1 - gamma v "
                              "would be negative")
    new_rate = (xi * delta_dot - n_v) / chi
    return (t_hit, delta_dot, xi * delta_dot, xi, new_rate - rate), new_rate


def _dataset(system, prep, p, t_out, y_out, acc, imp, law, pulse_duration) -> xr.Dataset:
    """The record of :func:`simulate_impact_map` from its time series and impact table."""
    restitution, gamma = law
    theta = p[L.THETA0] + p[L.OMEGA] * t_out
    return xr.Dataset(
        {"alpha": ("time", y_out[:, 0], {"units": "rad", "long_name": "follower angle (clockwise)"}),
         "alpha_dot": ("time", y_out[:, 1], {"units": "rad/s", "long_name": "follower angular velocity"}),
         "alpha_ddot": ("time", acc, {"units": "rad/s^2", "long_name": "follower angular acceleration " + (
             "(free flight and impulse pulses)" if pulse_duration > 0 else "(free flight; impulses excluded)")}),
         "cam_angle": ("time", theta, {"units": "rad", "long_name": "cam angle Theta"}),
         "impact_time": ("impact", imp[:, 0], {"units": "s", "long_name": "impact time"}),
         "impact_approach_velocity": ("impact", imp[:, 1], {"units": "m/s", "long_name": "approach velocity"}),
         "impact_separation_velocity": ("impact", imp[:, 2], {"units": "m/s",
                                                              "long_name": "separation velocity"}),
         "impact_restitution": ("impact", imp[:, 3], {"units": "1", "long_name": "coefficient of restitution xi"}),
         "impact_rate_jump": ("impact", imp[:, 4], {"units": "rad/s", "long_name": "jump of alpha_dot"})},
        coords={"time": ("time", t_out, {"units": "s", "long_name": "time"})},
        attrs={"title": f"camdyn impact-map simulation (S3) of {system.name}", "speed_hz": system.motion.speed,
               "gamma_s_per_m": gamma if restitution is None else math.nan,
               "restitution": restitution if restitution is not None else math.nan,
               "pulse_duration_s": pulse_duration,
               "parameters_toml": system_to_toml(system, ignore_profile=True), "initial_cam_angle_rad": prep.theta0})


def _hann(u, width):
    """Hann pulse of unit area over ``[0, width)`` [1/s] at times ``u`` [s] after its start."""
    return (1.0 - np.cos(2.0 * math.pi * u / width)) / width


def _through_pulse(p, t_hit, alpha, rate, jump, width, t_out, y_out):
    """Integrate the follower through one impulse pulse (free flight plus a Hann pulse of
    area ``jump`` [rad/s]), fill the output samples inside it, and return the time and
    ``(alpha, alpha_dot)`` at its end."""
    def rhs(t, y):
        return (y[1], free_acceleration(y[0], p) + jump * _hann(t - t_hit, width))

    sol = solve_ivp(rhs, (t_hit, t_hit + width), (alpha, rate), method="DOP853", rtol=1e-12, atol=1e-14,
                    dense_output=True)
    inside = np.flatnonzero((t_out >= t_hit) & (t_out < t_hit + width))
    if inside.size:
        y_out[inside] = sol.sol(t_out[inside]).T
    return t_hit + width, sol.y[:, -1]
