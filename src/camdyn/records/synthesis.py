"""Synthetic measurement records: simulate, keep the steady state, add sensor noise."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from camdyn.analysis.kinematics import contact_start
from camdyn.errors import ParameterError
from camdyn.model.equilibrium import as_system
from camdyn.params.system import System
from camdyn.records.schema import check_noise, check_seed, make_record
from camdyn.simulation import limits
from camdyn.simulation.runner import simulate, with_speed

__all__ = ["synthesize", "synthesize_impact_map"]


def _checked(system, speed, revolutions: float, noise: float, settle: float, seed=0):
    """The system at ``speed`` (a System or a preset's name; a speed [Hz] or text with
    units), and ``revolutions`` and ``settle`` [cam periods] as floats; a ParameterError
    for a meaningless value, before any work."""
    check_noise(noise)
    check_seed(seed)
    settle = limits.check_number("settle", settle, "revolutions")
    if not (math.isfinite(settle) and settle >= 0):
        raise ParameterError(f"settle must be a non-negative number of revolutions, got {settle!r}")
    revolutions = limits.check_number("revolutions", revolutions, "revolutions")
    if not (math.isfinite(revolutions) and revolutions > 0):
        raise ParameterError(f"revolutions must be a positive, finite number, got {revolutions!r}")
    return with_speed(as_system(system), speed), revolutions, settle


def synthesize(system: System, speed: float | None = None, revolutions: float = 40.0, sample_rate: float = 20e3,
               noise: float = 0.0, settle: float = 20.0, seed: int | None = 0,
               channels=("Nx", "Ny", "alpha_ddot"), transducer_angle: float = 0.0) -> xr.Dataset:
    """A measurement-like record of the simulated system.

    Parameters
    ----------
    system : System
    speed : float, optional
        Cam speed [Hz]; default ``system.motion.speed``.
    revolutions : float
        Length of the kept record [cam periods].
    sample_rate : float
        Sampling rate [Hz].
    noise : float
        Gaussian noise added to each channel, as a fraction of that channel's rms about
        its mean [-] (0.01 is "1 % noise").
    settle : float
        Cam periods simulated and dropped first, so the record is in steady state [-].
        Where inverse kinematics keeps contact, the run starts on the contact motion
        (:func:`camdyn.analysis.kinematics.contact_start`), so that the start-up cannot
        leave the follower on an impacting motion; otherwise from rest.
    seed : int, optional
        Seed of the noise generator (None: fresh entropy).
    channels : sequence of str
        Channels to keep, from ``Nx``, ``Ny``, ``alpha_ddot``, ``a_t`` (``a_t = l_a alpha_ddot``).
    transducer_angle : float
        Misalignment ``kappa`` [rad] of the vertical force transducer: it records
        ``Ny cos(kappa)`` (thesis 4.8).

    Returns
    -------
    xarray.Dataset
        A record (see :mod:`camdyn.io.measurements`) starting at ``time = 0``, with the
        true forces of the simulation (DC included), attributes ``speed_hz``, ``runout``,
        ``preset`` and ``noise``.
    """
    system, revolutions, settle = _checked(system, speed, revolutions, noise, settle, seed)
    transducer_angle = limits.check_number("transducer_angle", transducer_angle, "rad")
    if isinstance(channels, str) or not all(isinstance(name, str) for name in np.atleast_1d(channels)):
        raise ParameterError(f"channels must be a sequence of names from Nx, Ny, alpha_ddot, a_t, got {channels!r}")
    ds = simulate(system, revolutions=settle + revolutions, sample_rate=sample_rate,
                  initial_state=contact_start(system))
    period = system.motion.period
    keep = ds["time"].values >= settle * period - 0.5 / sample_rate
    ds = ds.isel(time=keep)
    t = ds["time"].values - ds["time"].values[0]
    rng = np.random.default_rng(seed)
    out = {}
    for name in channels:
        if name == "a_t":
            x = ds["alpha_ddot"].values * system.follower.sensor_distance
        elif name in ("Nx", "Ny", "alpha_ddot"):
            x = ds[name].values.copy()
        else:
            raise ParameterError(f"unknown channel {name!r}; choose from Nx, Ny, alpha_ddot, a_t")
        if name == "Ny" and transducer_angle:
            x = x * math.cos(transducer_angle)
        if noise > 0:
            x = x + noise * np.std(x) * rng.standard_normal(x.size)
        out[name] = x
    return make_record(t, out, speed_hz=system.motion.speed, runout=system.cam.runout, preset=system.name,
                       noise=noise)


def synthesize_impact_map(system: System, speed: float | None = None, revolutions: float = 40.0,
                          sample_rate: float = 204.8e3, gamma: float = 0.8, noise: float = 0.0,
                          settle: float = 60.0, seed: int | None = 0, pulse_samples: int = 32) -> xr.Dataset:
    """A record of the instantaneous-restitution simulation S3 (thesis 3.8.2, table 3.3).

    The follower's acceleration is sampled in free flight; each impact's jump of
    ``alpha_dot`` appears as a Hann-shaped pulse of ``pulse_samples`` samples starting at
    the impact, with the jump as its area, as a band-limited accelerometer would see an
    instantaneous impact. The follower is integrated through each pulse
    (:func:`camdyn.simulation.impact_map.simulate_impact_map` with ``pulse_duration``), so that the
    record is one consistent motion that touches the cam at every onset.
    Only ``alpha_ddot`` is recorded (the restitution estimate needs no forces).

    Parameters
    ----------
    gamma : float
        Slope of ``xi = 1 - gamma v_a`` [s/m].
    pulse_samples : int
        Length of the impulse pulses [samples] (32 at 204.8 kHz: 156 us, half the length of
        the rig's real contacts; 8 or fewer samples cannot be integrated accurately).
    Other parameters as :func:`synthesize`.
    """
    from camdyn.simulation.impact_map import simulate_impact_map

    system, revolutions, settle = _checked(system, speed, revolutions, noise, settle, seed)
    if not (isinstance(pulse_samples, (int, np.integer)) and pulse_samples >= 2):
        raise ParameterError(f"pulse_samples must be an integer of at least 2, got {pulse_samples!r}")
    sample_rate = limits.check_number("sample_rate", sample_rate, "Hz")
    if not (math.isfinite(sample_rate) and sample_rate > 0):
        raise ParameterError(f"sample_rate must be a positive, finite number of Hz, got {sample_rate!r}")
    tau = 1.0 / sample_rate
    ds = simulate_impact_map(system, revolutions=settle + revolutions, gamma=gamma, sample_rate=sample_rate,
                             pulse_duration=pulse_samples * tau)
    t = ds["time"].values
    acc = ds["alpha_ddot"].values.copy()
    keep = t >= settle / system.motion.speed - 0.5 * tau
    t = t[keep] - t[keep][0]
    acc = acc[keep]
    if noise > 0:
        acc = acc + noise * np.std(acc) * np.random.default_rng(seed).standard_normal(acc.size)
    return make_record(t, {"alpha_ddot": acc}, speed_hz=system.motion.speed, runout=system.cam.runout,
                       preset=system.name, noise=noise, gamma=gamma)
