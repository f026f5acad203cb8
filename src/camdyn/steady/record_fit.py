"""Parameters fitted to a steady-state record with the harmonic-balance orbit as the
forward model: the coefficient of friction (the default), or any continuous parameters.

The thesis identifies the coefficient of friction from the DC and first cam harmonic of
the pivot reactions and the follower's acceleration through a force balance
(:func:`camdyn.identification.friction.estimate_friction`, eqs 4.34-4.40). Here the
whole model predicts them instead: for trial parameter values, the rig's periodic orbit
at the record's cam speed by harmonic balance (:func:`camdyn.steady.harmonic_balance`,
about 2 ms warm-started from the last trial), its channels on the orbit's time grid
(the same functions as :func:`camdyn.simulate`'s outputs), and their mean and cam
harmonic amplitudes 1..K. Levenberg-Marquardt (``scipy.optimize.least_squares``) fits
the parameters so that these match the record's, each channel's residuals divided by
the record's rms of that channel. Amplitudes, not phases, are compared: the record's
time origin does not matter.

What this adds to the force balance: every harmonic the model carries enters (no
truncation of products of signals), and other parameters (a damping, a stiffness) can
be fitted with the friction. What it assumes: the model is right but for the fitted
parameters, and the rig stays in contact with one sliding direction over the orbit
(harmonic balance refuses an orbit that loses contact).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import xarray as xr
from scipy.optimize import least_squares

from camdyn.analysis.harmonics import fit_harmonics
from camdyn.continuation.problem import parameter_unit, system_problem
from camdyn.errors import IdentificationError, ParameterError, SimulationError
from camdyn.model.equilibrium import as_system
from camdyn.model.outputs import CHANNELS, derived
from camdyn.params.system import System
from camdyn.records.schema import angular_acceleration, check_consistency, check_record, record_speed, require_record
from camdyn.steady.harmonic_balance import GridModel, HarmonicOrbit, harmonic_balance

__all__ = ["RecordFit", "fit_record"]

_NAMES = [name for name, _, _ in CHANNELS]
_UNITS = {name: unit for name, unit, _ in CHANNELS}


@dataclass
class RecordFit:
    """Parameters fitted to a steady-state record through the harmonic-balance orbit.

    Attributes
    ----------
    values : dict
        ``{key: fitted value}`` in each key's SI unit (``friction.coefficient``: [-]).
    standard_errors : dict
        ``{key: standard error}`` from the residuals' scatter and the Jacobian at the
        solution (same units); a guide, not a calibrated interval.
    speed_hz : float
        The cam speed [Hz] the orbit was balanced at.
    channels : tuple of str
        The record's channels compared.
    harmonics : int
        K, the cam harmonics 1..K compared per channel besides the mean [-].
    measured, predicted : dict
        ``{channel: [mean, |c_1|, ..., |c_K|]}`` in the channel's unit, from the record's
        last whole revolutions and from the fitted orbit.
    residual : float
        rms of the residuals, each divided by its channel's rms [-].
    evaluations : int
        Orbits balanced during the fit.
    units : dict
        ``{key: SI unit}`` of the fitted parameters (``""`` for a pure number).
    orbit : HarmonicOrbit
        The fitted orbit.
    """

    values: dict
    standard_errors: dict
    speed_hz: float
    channels: tuple
    harmonics: int
    measured: dict
    predicted: dict
    residual: float
    evaluations: int
    units: dict
    orbit: HarmonicOrbit = field(repr=False)

    def to_dict(self) -> dict:
        """The fit as plain numbers (JSON-ready); units in ``units``."""
        return {"values": dict(self.values), "standard_errors": dict(self.standard_errors),
                "speed_hz": self.speed_hz, "channels": list(self.channels), "harmonics": self.harmonics,
                "measured": {k: [float(x) for x in v] for k, v in self.measured.items()},
                "predicted": {k: [float(x) for x in v] for k, v in self.predicted.items()},
                "units": {**{c: _UNITS[c] for c in self.channels}, **self.units},
                "residual": self.residual, "evaluations": self.evaluations,
                "orbit_harmonics": self.orbit.harmonics}


def _observations(record: xr.Dataset, channels, speed: float, harmonics: int, revolutions: int | None) -> dict:
    """``{channel: [mean, |c_1|..|c_K|]}`` over the record's last ``revolutions`` whole
    cam revolutions (None: all), by a least-squares fit of the cam harmonics (no leakage)."""
    t = record["time"].values
    fs = 1.0 / (t[1] - t[0])
    available = int(math.floor((t[-1] - t[0] + 1.0 / fs) * speed + 1e-9))
    revolutions = available if revolutions is None else revolutions
    if available < max(revolutions, 1):
        raise IdentificationError(f"the record spans {available} whole cam revolutions at {speed:.4g} Hz; "
                                  f"{revolutions} are asked for")
    if harmonics > math.floor(0.45 * fs / speed):
        raise IdentificationError(f"sampling at {fs:.4g} Hz resolves fewer than {harmonics} cam harmonics")
    keep = t >= t[-1] + 1.0 / fs - revolutions / speed - 0.5 / fs
    out = {}
    for name in channels:
        c = fit_harmonics(t[keep], record[name].values[keep], speed, harmonics)
        out[name] = np.concatenate([[c[0].real], np.abs(c[1:])])
    return out


class _Forward:
    """The orbit's observations as a function of the fitted parameters, each orbit
    started from the last one's coefficients."""

    def __init__(self, system: System, keys, speed: float, channels, harmonics: int):
        self.system, self.keys, self.speed = system, tuple(keys), speed
        self.channels, self.harmonics = tuple(channels), harmonics
        self.guess, self.orbit_harmonics, self.orbit, self.evaluations = None, "auto", None, 0

    def __call__(self, x: np.ndarray) -> dict:
        values = {"motion.speed": self.speed, **{k: float(v) for k, v in zip(self.keys, x)}}
        problem = system_problem(self.system.with_values(**values), "motion.speed")
        try:
            orbit = harmonic_balance(problem, self.orbit_harmonics, guess=self.guess)
            if orbit.harmonics < self.harmonics:                    # the grid must resolve K harmonics
                orbit = harmonic_balance(problem, self.harmonics, guess=orbit.coefficients)
        except SimulationError as exc:
            trial = ", ".join(f"{k} = {v:.6g}" for k, v in zip(self.keys, x))
            raise IdentificationError(f"no orbit in sustained contact at {trial}: {exc}") from None
        self.evaluations += 1
        self.guess, self.orbit_harmonics, self.orbit = orbit.coefficients, orbit.harmonics, orbit
        model = GridModel(problem, problem.value)
        states, modes = model.balanced_modes(orbit.times, orbit.samples)
        values = derived(orbit.times, np.ascontiguousarray(states[:, :3]), modes, model.p)
        out = {}
        for name in self.channels:
            c = np.fft.rfft(values[:, _NAMES.index(name)]) / orbit.times.size
            out[name] = np.concatenate([[c[0].real], 2.0 * np.abs(c[1:self.harmonics + 1])])
        return out


def _start_values(system: System, keys) -> tuple[tuple[str, ...], np.ndarray]:
    """The keys checked (distinct numbers a problem can vary; not the speed, which the
    record sets) and their values in ``system``: the fit's starting guess."""
    if isinstance(keys, str):
        keys = (keys,)
    keys = tuple(keys)
    if not keys or len(set(keys)) != len(keys) or "motion.speed" in keys or not all(isinstance(k, str) for k in keys):
        raise ParameterError(f"keys must name distinct parameters other than motion.speed, got {keys!r:.80}")
    return keys, np.array([system_problem(system, key).value for key in keys])


def fit_record(system: System | str, record: xr.Dataset, keys=("friction.coefficient",), speed=None,
               harmonics: int = 4, channels=("Nx", "Ny", "alpha_ddot"), revolutions: int | None = None,
               bounds=None) -> RecordFit:
    """Fit parameters of ``system`` to a steady-state record, with the periodic orbit by
    harmonic balance as the forward model (see the module's text).

    Parameters
    ----------
    system : System or str
        The rig, or a preset's name; its values of ``keys`` are the starting guess.
    record : xarray.Dataset
        The channels over ``time`` [s] (``Nx``, ``Ny`` [N], ``alpha_ddot`` [rad/s^2] or
        ``a_t`` [m/s^2]), as :func:`camdyn.io.measurements.read_measurement` reads them,
        in steady state at the end.
    keys : str or sequence of str
        The parameters fitted (dotted keys, ``camdyn presets keys``).
    speed : float or str, optional
        Cam speed [Hz], or text with a unit (``"11.55 Hz"``); default the record's
        ``speed_hz`` attribute.
    harmonics : int
        K: the cam harmonics 1..K compared per channel, besides the mean [-].
    channels : sequence of str
        The record's channels compared (any of :data:`camdyn.model.outputs.CHANNELS`).
    revolutions : int, optional
        The last whole cam revolutions of the record used [-]; default all of them.
    bounds : (lower, upper), optional
        Bounds of the parameters (sequences in the keys' order, in the keys' units);
        default ``[0, inf)`` for a key that starts at or above 0, unbounded otherwise. A
        parameter that ends on a bound has no standard error (NaN).

    Raises
    ------
    ParameterError
        A bad system, record, key or setting, before any work.
    DataError
        The record lacks a channel, or holds NaN or clipped samples.
    IdentificationError
        Too short a record, or a trial of the fit where the rig loses contact.
    """
    system = as_system(system)
    record = require_record(record)
    speed = record_speed(speed)
    keys, x0 = _start_values(system, keys)
    if isinstance(harmonics, bool) or not isinstance(harmonics, int) or not 1 <= harmonics <= 32:
        raise ParameterError(f"harmonics must be an integer from 1 to 32, got {harmonics!r:.60}")
    if revolutions is not None and (isinstance(revolutions, bool) or not isinstance(revolutions, int)
                                    or revolutions < 1):
        raise ParameterError(f"revolutions must be a positive integer, got {revolutions!r:.60}")
    channels = tuple(channels)
    unknown = [c for c in channels if c not in _NAMES]
    if not channels or unknown:
        raise ParameterError(f"channels must be among {', '.join(_NAMES)}; got {channels!r:.80}")
    if speed is None:
        if "speed_hz" not in record.attrs:
            raise ParameterError("the record has no speed_hz attribute: give the cam speed")
        speed = record_speed(record.attrs["speed_hz"], "the record's speed_hz")
    if system.motion.kind != "constant":
        raise ParameterError("fitting a steady-state record needs constant cam motion")
    record = angular_acceleration(record, system.follower.sensor_distance)
    check_record(record, channels)
    check_consistency(record, speed=speed, runout=system.cam.runout, preset=system.name, what="the system and options")
    measured = _observations(record, channels, speed, harmonics, revolutions)
    scale = {c: max(float(np.sqrt(np.mean(record[c].values ** 2))), 1e-300) for c in channels}
    forward = _Forward(system, keys, speed, channels, harmonics)

    def residuals(x):
        predicted = forward(x)
        return np.concatenate([(predicted[c] - measured[c]) / scale[c] for c in channels])

    lower, upper = (np.where(x0 >= 0.0, 0.0, -np.inf), np.full(len(keys), np.inf)) if bounds is None else (
        np.asarray(bounds[0], float), np.asarray(bounds[1], float))
    if lower.shape != x0.shape or upper.shape != x0.shape or np.any(lower >= upper):
        raise ParameterError(f"bounds must be two sequences of {len(keys)} values, lower below upper")
    x0 = np.clip(x0, lower, upper)
    solution = least_squares(residuals, x0, bounds=(lower, upper), x_scale="jac", diff_step=1e-7)
    predicted = forward(solution.x)                                  # and the fitted orbit
    r = solution.fun
    dof = max(r.size - len(keys), 1)
    try:
        covariance = np.linalg.inv(solution.jac.T @ solution.jac) * float(r @ r) / dof
        errors = np.sqrt(np.abs(np.diag(covariance)))
    except np.linalg.LinAlgError:
        errors = np.full(len(keys), np.inf)
    errors = np.where(solution.active_mask != 0, np.nan, errors)     # on a bound: no standard error
    return RecordFit(values=dict(zip(keys, map(float, solution.x))),
                     standard_errors=dict(zip(keys, map(float, errors))), speed_hz=speed, channels=channels,
                     harmonics=harmonics, measured=measured, predicted=predicted,
                     residual=float(np.sqrt(np.mean(r ** 2))), evaluations=forward.evaluations,
                     units={k: parameter_unit(system, k) for k in keys}, orbit=forward.orbit)
