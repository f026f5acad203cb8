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

Each flight is one whole compiled simulation (:func:`camdyn.core.driver.integrate`),
stopped at the next onset; friction impulses are not modelled (as in eq 3.27).
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from camdyn.config import system_to_toml
from camdyn.core import driver, systems
from camdyn.errors import ParameterError, SimulationError
from camdyn.geometry import cam_angle, contact_kinematics
from camdyn.model import layout as L
from camdyn.model.dynamics import free_acceleration
from camdyn.parameters import System
from camdyn.simulation import prepare
from camdyn.units import parse_speed

__all__ = ["simulate_impact_map"]


def simulate_impact_map(system: System, speed=None, revolutions: float = 30.0, gamma: float | None = 0.8,
                        restitution: float | None = None, sample_rate: float = 20e3,
                        rtol: float = 1e-10, atol: float = 1e-12, max_impacts: int | None = None) -> xr.Dataset:
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

    Returns
    -------
    xarray.Dataset
        ``alpha`` [rad], ``alpha_dot`` [rad/s], ``alpha_ddot`` [rad/s^2] (free flight; the
        impulses are Dirac pulses, listed over ``impact``), ``cam_angle`` [rad] over
        ``time``; over ``impact``: ``impact_time`` [s], ``impact_approach_velocity`` and
        ``impact_separation_velocity`` [m/s], ``impact_restitution`` [-] and
        ``impact_rate_jump`` [rad/s].
    """
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
    prep = prepare(system)
    p = prep.p
    duration = revolutions * period
    n_out = int(math.floor(duration * sample_rate + 1e-9)) + 1
    t_out = np.arange(n_out) / sample_rate
    y_out = np.full((n_out, 2), np.nan)
    # start in free flight just off the cam at the static angle, falling onto it
    chi = contact_kinematics(prep.y0[0], 0.0, prep.theta0, 0.0, p)[2]
    y = np.array([prep.y0[0] + math.copysign(1e-4, chi), 0.0, 0.0])
    t = 0.0
    rows = []
    h_max = period / 32.0
    limit = max_impacts if max_impacts is not None else int(20 * revolutions + 100)
    while t < duration:
        mask = t_out >= t
        span_end = min(duration, t + 1.5 * period)
        times = t_out[mask & (t_out <= span_end)]
        ys, modes, events, counters = driver.integrate(
            systems.CAM_FOLLOWER, p, y, t, span_end, times if times.size else np.array([span_end]),
            rtol, atol, h_max, driver.METHOD_DOP853, 10_000_000, 64)
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
        alpha, rate = onsets[0, 3], onsets[0, 4]
        theta, theta_dot = cam_angle(t_hit, p)
        _, delta_dot, chi, _, _, n_v, _ = contact_kinematics(alpha, rate, theta, theta_dot, p)
        xi = restitution if restitution is not None else 1.0 - gamma * delta_dot
        if xi < 0:
            raise SimulationError(f"approach velocity {delta_dot:.4g} m/s exceeds 1/gamma: xi = 1 - gamma v "
                                  "would be negative")
        new_rate = (xi * delta_dot - n_v) / chi
        rows.append((t_hit, delta_dot, xi * delta_dot, xi, new_rate - rate))
        if len(rows) > limit:
            raise SimulationError(f"more than {limit} impacts: the follower chatters (xi near 1 at low "
                                  "approach velocity); shorten the run or lower the restitution")
        t = t_hit
        y = np.array([alpha, new_rate, 0.0])
    imp = np.array(rows, dtype=float).reshape(-1, 5)
    acc = np.array([free_acceleration(a, p) if math.isfinite(a) else math.nan for a in y_out[:, 0]])
    theta = p[L.THETA0] + p[L.OMEGA] * t_out
    ds = xr.Dataset(
        {"alpha": ("time", y_out[:, 0], {"units": "rad", "long_name": "follower angle (clockwise)"}),
         "alpha_dot": ("time", y_out[:, 1], {"units": "rad/s", "long_name": "follower angular velocity"}),
         "alpha_ddot": ("time", acc, {"units": "rad/s^2", "long_name": "follower angular acceleration "
                                                                          "(free flight; impulses excluded)"}),
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
               "parameters_toml": system_to_toml(system), "initial_cam_angle_rad": prep.theta0})
    return ds
