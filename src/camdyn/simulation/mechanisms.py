"""Mechanisms with more degrees of freedom than the cam-follower with a prescribed cam:
the cam as a rigid body driven by a torque (:func:`simulate_driven_cam`) and the
stick-slip oscillator (:func:`simulate_stick_slip`), each returned as an xarray Dataset
with units; and the cam-follower under a cam angle tabulated over one period
(:func:`simulate_tabulated`)."""

from __future__ import annotations

import dataclasses
import math
import time as _time
import typing

import numpy as np
import xarray as xr

from camdyn.errors import ParameterError
from camdyn.integrator import driver
from camdyn.model import driven_cam, stick_slip
from camdyn.params.system import System
from camdyn.params.units import speed_text_rad_s
from camdyn.simulation import limits
from camdyn.simulation.runner import METHODS, default_max_step, default_scan, prepare
from camdyn.systems import registry as systems

__all__ = ["CamDrive", "DrivenCamRig", "simulate_driven_cam", "simulate_stick_slip", "speed_fluctuation",
           "tabulated_motion", "simulate_tabulated", "run_mechanism"]


@dataclasses.dataclass(frozen=True)
class CamDrive:
    """The cam shaft as a rigid body: its inertia, its drive and its bearing.

    Attributes
    ----------
    shaft_inertia : float
        Inertia ``J`` [kg m^2] of the cam and its shaft about the cam pivot.
    kind : str
        ``"constant"``: the torque ``torque``; ``"motor"``: a DC motor's line
        ``stall_torque (1 - Theta_dot / free_speed)``; ``"controller"``: a PI speed
        controller, ``torque + proportional (target_speed - Theta_dot) + integral z``
        with ``z' = target_speed - Theta_dot``; ``"prescribed"``: the shaft held at its
        starting speed whatever the load (the limit of an infinite inertia; the drive's
        torque is the one that holds it).
    torque : float
        Constant drive torque, or the controller's feed-forward [N m].
    stall_torque : float
        Motor torque at rest [N m].
    free_speed : float or str
        Motor's no-load speed [rad/s] (non-zero for a motor), or text with units
        (``"600 rpm"``, ``"10 Hz"``); a bare number stays rad/s.
    proportional : float
        Controller's proportional gain [N m s/rad].
    integral : float
        Controller's integral gain [N m/rad].
    target_speed : float or str
        Controller's speed set point [rad/s], or text with units.
    bearing_viscous : float
        Bearing's viscous friction coefficient [N m s/rad].
    bearing_coulomb : float
        Bearing's Coulomb friction torque [N m].
    bearing_speed : float or str
        Speed [rad/s] (or text with units) over which the Coulomb torque is smoothed (tanh).
    """

    shaft_inertia: float
    kind: str = "constant"
    torque: float = 0.0
    stall_torque: float = 0.0
    free_speed: float = math.inf
    proportional: float = 0.0
    integral: float = 0.0
    target_speed: float = 0.0
    bearing_viscous: float = 0.0
    bearing_coulomb: float = 0.0
    bearing_speed: float = 1.0

    def __post_init__(self):
        for name in ("free_speed", "target_speed", "bearing_speed"):   # text with units -> rad/s
            if isinstance(getattr(self, name), str):
                object.__setattr__(self, name, speed_text_rad_s(getattr(self, name), f"drive {name}"))
        if self.kind not in driven_cam.DRIVE_KINDS:
            raise ParameterError(f"drive kind must be one of {sorted(driven_cam.DRIVE_KINDS)}, got {self.kind!r}")
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if field.name == "kind":
                continue
            if not isinstance(value, (int, float)) or math.isnan(value):
                raise ParameterError(f"drive {field.name} must be a number, got {value!r}")
            if field.name != "free_speed" and not math.isfinite(value):
                raise ParameterError(f"drive {field.name} must be finite, got {value!r}")
        if not self.shaft_inertia > 0.0:
            raise ParameterError(f"drive shaft_inertia must be positive [kg m^2], got {self.shaft_inertia!r}")
        for name in ("bearing_viscous", "bearing_coulomb"):
            if getattr(self, name) < 0.0:
                raise ParameterError(f"drive {name} must not be negative, got {getattr(self, name)!r}")
        if not self.bearing_speed > 0.0:
            raise ParameterError(f"drive bearing_speed must be positive [rad/s], got {self.bearing_speed!r}")
        if self.kind == "motor" and not (math.isfinite(self.free_speed) and self.free_speed != 0.0):
            raise ParameterError("a motor drive needs a finite, non-zero free_speed [rad/s]")

    def slots(self) -> np.ndarray:
        """The drive's slots of the driven cam's parameter vector (:mod:`camdyn.model.driven_cam`)."""
        return np.array([self.shaft_inertia, driven_cam.DRIVE_KINDS[self.kind], self.torque, self.stall_torque,
                         self.free_speed, self.proportional, self.integral, self.target_speed,
                         self.bearing_viscous, self.bearing_coulomb, self.bearing_speed])


class DrivenCamRig(typing.NamedTuple):
    """The driven cam: the arguments of :func:`simulate_driven_cam`, ``system`` (the
    cam-follower; its constant motion gives the starting cam angle and speed) and
    ``drive`` (:class:`CamDrive`)."""

    system: System
    drive: CamDrive


#: The driven cam's state: name, unit, long name, in the state's order.
DRIVEN_STATE = (
    ("alpha", "rad", "follower angle (clockwise)"),
    ("alpha_dot", "rad/s", "follower angular velocity"),
    ("cam_angle", "rad", "cam angle Theta (counter-clockwise)"),
    ("cam_speed", "rad/s", "cam angular speed Theta_dot"),
    ("speed_error_integral", "rad", "integral of the speed error of the PI controller"),
    ("drive_work", "J", "work done by the drive on the shaft"),
    ("bearing_work", "J", "work lost in the bearing"),
    ("cam_work", "J", "work done by the cam on the follower"),
)


def run_mechanism(system_id, p, y0, duration, sample_rate, period, rtol, atol, method, max_step):
    """Integrate mechanism ``system_id`` (:func:`_run_counters`: the shared checks and the
    compiled call) and return the output times [s], states, modes, events and the
    counters as a Dataset's attributes (``events``: those logged; ``events_dropped``:
    those past the log's room, located and applied but not logged)."""
    t_out, y, modes, events, counters, elapsed = _run_counters(system_id, p, y0, duration, sample_rate, period,
                                                               rtol, atol, method, max_step)
    attrs = {"rtol": rtol, "atol": atol, "method": method, "elapsed_s": elapsed,
             "accepted_steps": int(counters[driver.COUNT_ACCEPTED]),
             "rejected_steps": int(counters[driver.COUNT_REJECTED]), "events": int(events.shape[0]),
             "events_dropped": int(counters[driver.COUNT_EVENTS_DROPPED])}
    return t_out, y, modes, events, attrs


def _run_counters(system_id, p, y0, duration, sample_rate, period, rtol, atol, method, max_step):
    """The shared checks and the compiled call; returns the output times [s], states,
    modes, events, counters and wall time [s], or raises ``SimulationError``."""
    if method not in METHODS:
        raise ParameterError(f"method must be one of {sorted(METHODS)}, got {method!r}")
    limits.check_tolerances(rtol, atol)
    duration = limits.check_number("duration", duration, "s")
    if not (math.isfinite(duration) and duration > 0):
        raise ParameterError(f"duration must be positive, got {duration!r}")
    max_step, _ = limits.check_steps(max_step, 50_000_000, duration)
    n_out = limits.check_sampling(sample_rate, period, duration)
    limits.check_memory(limits.result_bytes(n_out, 20), "the simulation's result")
    t_out = np.minimum(np.arange(n_out) / sample_rate, duration)
    if max_step is None:
        max_step = default_max_step(period, duration)
    max_events = limits.event_room(duration, period)
    start = _time.perf_counter()
    y, modes, events, counters = limits.with_room_for_events(
        lambda room: driver.integrate(system_id, p.copy(), y0, 0.0, float(duration), t_out, float(rtol), float(atol),
                                      float(max_step), METHODS[method], 50_000_000, room, True,
                                      default_scan(period, duration)), max_events)
    elapsed = _time.perf_counter() - start
    limits.check_run(counters, "simulation")
    return t_out, y, modes, events, counters, elapsed


def speed_fluctuation(cam_speed: np.ndarray) -> float:
    """Coefficient of speed fluctuation ``(omega_max - omega_min) / omega_mean`` [-]
    (Norton, *Design of Machinery*, 5th ed., 2012, eq 11.18) of a sampled speed [rad/s]."""
    speed = np.asarray(cam_speed, float)
    mean = float(np.mean(speed))
    if mean == 0.0:
        return math.nan
    return float((speed.max() - speed.min()) / abs(mean))


def simulate_driven_cam(system: System, drive: CamDrive, revolutions: float = 5.0, duration: float | None = None,
                        sample_rate: float = 20e3, initial_speed: float | None = None, rtol: float = 1e-9,
                        atol: float = 1e-11, method: str = "auto", max_step: float | None = None) -> xr.Dataset:
    """Simulate the cam-follower with the cam shaft as a rigid body.

    Parameters
    ----------
    system : System
        The cam-follower (:func:`camdyn.load_system`); its constant motion gives the
        starting cam angle and speed; the run starts at the static equilibrium.
    drive : CamDrive
        The shaft's inertia, drive and bearing.
    revolutions : float
        Length of the run in periods of the starting speed [-]; ignored with ``duration``.
    duration : float, optional
        Length of the run [s].
    sample_rate : float
        Output sampling rate [Hz].
    initial_speed : float, optional
        Starting cam speed [rad/s]; default ``system.motion``'s angular speed.
    rtol, atol : float
        Local error tolerances: relative [-] and absolute [rad, rad/s, J].
    method : {"auto", "dop853", "explicit", "rosenbrock", "radau", "switching"}
        Stepper choice (``auto``: DOP853), as in :func:`camdyn.simulate`.
    max_step : float, optional
        Largest step [s]; default 1/12 of the starting period (guards checked every 1/32).

    Returns
    -------
    xarray.Dataset
        Over ``time``: the state (:data:`DRIVEN_STATE`), the channels of
        :data:`camdyn.model.driven_cam.CHANNELS` and ``speed_fluctuation``, the cam speed
        less its mean [rad/s]; attributes: the coefficient of speed fluctuation, the mean
        speed and the solver counters.

    Raises
    ------
    ParameterError
        For an oscillating cam motion, or bad run settings.
    """
    limits.check_system(system)
    if system.profile is not None:
        raise ParameterError("the driven cam takes an elliptic or circular cam, not a cam profile (system.profile)")
    if system.motion.kind != "constant":
        raise ParameterError("a driven cam starts from a constant motion (motion.kind = 'constant'); "
                             f"got {system.motion.kind!r}")
    speed = system.motion.angular_speed if initial_speed is None else limits.check_number(
        "initial_speed", initial_speed, "rad/s")
    if not math.isfinite(speed):
        raise ParameterError(f"initial_speed must be finite, got {speed!r}")
    period = 2.0 * math.pi / abs(speed) if speed != 0.0 else math.inf
    if duration is None:
        if not math.isfinite(period):
            raise ParameterError("the cam starts at rest: give a duration in seconds")
        duration = limits.check_number("revolutions", revolutions) * period
    prep = prepare(system)
    p = np.r_[prep.p, drive.slots()]
    angle = prep.equilibrium.angle
    if initial_speed is not None and speed != 0.0 and speed != system.motion.angular_speed:
        # the static equilibrium under the friction of the speed the run starts at
        start = system.with_values(**{"motion.speed": abs(speed) / (2.0 * math.pi),
                                      "motion.direction": 1 if speed > 0.0 else -1})
        angle = prepare(start).equilibrium.angle
    y0 = np.array([angle, 0.0, prep.theta0, speed, 0.0, 0.0, 0.0, 0.0])
    t, y, modes, events, attrs = run_mechanism(systems.DRIVEN_CAM, p, y0, duration, sample_rate, period, rtol,
                                               atol, method, max_step)
    data = {name: (("time",), y[:, i], {"units": unit, "long_name": long})
            for i, (name, unit, long) in enumerate(DRIVEN_STATE)}
    derived = driven_cam.channels(y, modes, p)
    for i, (name, unit, long) in enumerate(driven_cam.CHANNELS):
        data[name] = (("time",), derived[:, i], {"units": unit, "long_name": long})
    mean = float(np.mean(y[:, 3]))
    data["speed_fluctuation"] = (("time",), y[:, 3] - mean,
                                 {"units": "rad/s", "long_name": "cam speed less its mean"})
    attrs.update(mean_cam_speed=mean, coefficient_of_fluctuation=speed_fluctuation(y[:, 3]),
                 drive_kind=drive.kind, shaft_inertia=drive.shaft_inertia)
    return xr.Dataset(data, coords={"time": ("time", t, {"units": "s", "long_name": "time"})}, attrs=attrs)


def simulate_stick_slip(mass: float, stiffness: float, belt_speed: float, static_friction: float,
                        kinetic_friction: float, duration: float, damping: float = 0.0, gravity: float = 9.80665,
                        initial_state=(0.0, 0.0), sample_rate: float = 1e3, rtol: float = 1e-10,
                        atol: float = 1e-13, method: str = "auto") -> xr.Dataset:
    """Simulate the stick-slip oscillator of :mod:`camdyn.model.stick_slip`.

    Parameters
    ----------
    mass, stiffness, belt_speed, static_friction, kinetic_friction, damping, gravity : float
        As :func:`camdyn.model.stick_slip.pack` ([kg], [N/m], [m/s], [-], [-], [N s/m],
        [m/s^2]).
    duration : float
        Length of the run [s].
    initial_state : (float, float)
        Spring extension [m] and velocity [m/s] at the start.
    sample_rate : float
        Output sampling rate [Hz].
    rtol, atol : float
        Local error tolerances: relative [-] and absolute [m, m/s].
    method : {"auto", "dop853", "explicit", "rosenbrock", "radau", "switching"}
        Stepper choice, as in :func:`camdyn.simulate`.

    Returns
    -------
    xarray.Dataset
        Over ``time``: ``x`` [m], ``x_dot`` [m/s], ``friction_heat`` [J],
        ``friction_force`` [N] and ``sticking`` (1 or 0); over ``transition``: the time
        [s], kind (``"stick"`` or ``"slip"``) and extension [m] of every switch.
    """
    p = stick_slip.pack(mass, stiffness, belt_speed, static_friction, kinetic_friction, damping, gravity)
    start = np.array([*map(float, initial_state), 0.0])
    if start.shape != (3,) or not np.isfinite(start).all():
        raise ParameterError(f"initial_state must be two finite numbers (x [m], x_dot [m/s]), got {initial_state!r}")
    period = 2.0 * math.pi * math.sqrt(mass / stiffness)
    t, y, modes, events, attrs = run_mechanism(systems.STICK_SLIP, p, start, duration, sample_rate, period, rtol,
                                               atol, method, None)
    sticking = modes[:, 0] == 0.0
    normal = mass * gravity
    force = np.where(sticking, stiffness * y[:, 0] + damping * y[:, 1], -kinetic_friction * normal * modes[:, 0])
    m = stick_slip.GUARD_COUNT
    new_modes = np.where(events[:, driver.EVENT_GUARD] == 0, 0, 1)
    # a zero of the relative velocity is a stick unless the belt cannot hold the mass (a reversal)
    held = np.abs(stiffness * events[:, driver.EVENT_GUARDS + m] + damping * belt_speed) <= static_friction * normal
    kinds = np.where((new_modes == 0) & held, "stick", "slip")
    data = {
        "x": (("time",), y[:, 0], {"units": "m", "long_name": "spring extension"}),
        "x_dot": (("time",), y[:, 1], {"units": "m/s", "long_name": "velocity of the mass"}),
        "friction_heat": (("time",), y[:, 2], {"units": "J", "long_name": "heat dissipated by friction"}),
        "friction_force": (("time",), force, {"units": "N", "long_name": "friction force of the belt on the mass"}),
        "sticking": (("time",), sticking.astype(np.int8), {"units": "1", "long_name": "1 while sticking"}),
        "transition_time": (("transition",), events[:, driver.EVENT_TIME], {"units": "s", "long_name": "time"}),
        "transition_kind": (("transition",), kinds, {"long_name": "stick or slip from this time"}),
        "transition_x": (("transition",), events[:, driver.EVENT_GUARDS + m],
                         {"units": "m", "long_name": "spring extension at the switch"}),
    }
    attrs.update(mass=mass, stiffness=stiffness, belt_speed=belt_speed, static_friction=static_friction,
                 kinetic_friction=kinetic_friction, damping=damping, gravity=gravity)
    return xr.Dataset(data, coords={"time": ("time", t, {"units": "s", "long_name": "time"})}, attrs=attrs)


def tabulated_motion(times, angles) -> tuple[float, float, np.ndarray]:
    """The periodic cubic spline of a cam angle tabulated over one period.

    Parameters
    ----------
    times : array_like
        Sample times [s] at uniform steps from 0 to the period ``T`` (both included).
    angles : array_like
        Cam angle ``Theta`` [rad] at each time; ``Theta(T) - Theta(0)`` is the angle turned
        per period (0 for an oscillation, ``2 pi`` for one revolution).

    Returns
    -------
    period : float
        ``T`` [s].
    mean_speed : float
        ``W = (Theta(T) - Theta(0)) / T`` [rad/s].
    coefficients : ndarray (4 n,)
        ``(a0, a1, a2, a3)`` of each of the ``n`` intervals [rad, rad/s, rad/s^2, rad/s^3]:
        ``Theta = a0 + a1 s + a2 s^2 + a3 s^3 + W t`` at ``s`` [s] into the interval (the
        periodic part interpolated with a periodic cubic spline, ``scipy.interpolate.
        CubicSpline`` with ``bc_type="periodic"``: continuous to the second derivative
        across the period too).

    Raises
    ------
    ParameterError
        If the table is not two finite 1-D arrays of equal length (at least 4 samples), or
        its times do not start at 0 and run up at uniform steps.
    """
    from scipy.interpolate import CubicSpline

    t = np.asarray(times, dtype=float)
    theta = np.asarray(angles, dtype=float)
    if t.ndim != 1 or theta.shape != t.shape or t.size < 4:
        raise ParameterError("a cam-angle table needs two 1-D arrays of equal length, at least 4 samples "
                             f"(times {t.shape}, angles {theta.shape})")
    if not (np.isfinite(t).all() and np.isfinite(theta).all()):
        raise ParameterError("a cam-angle table must hold finite numbers only")
    step = np.diff(t)
    if t[0] != 0.0 or not (step > 0).all() or np.ptp(step) > 1e-9 * step.mean():
        raise ParameterError("the table's times must start at 0 s and rise at uniform steps over one period")
    period = float(t[-1])
    mean_speed = float((theta[-1] - theta[0]) / period)
    periodic = theta - mean_speed * t
    periodic[-1] = periodic[0]   # closes exactly (rounding of the drift aside)
    c = CubicSpline(t, periodic, bc_type="periodic").c   # c[k, i]: coefficient of s^(3-k)
    return period, mean_speed, c[::-1].T.ravel().copy()


def simulate_tabulated(system: System, times, angles, periods: float = 5.0, duration: float | None = None,
                       sample_rate: float = 20e3, rtol: float = 1e-8, atol: float = 1e-10, method: str = "auto",
                       variables=None) -> xr.Dataset:
    """Simulate the cam-follower with the cam angle prescribed by a table over one period,
    repeated (:func:`tabulated_motion`).

    Parameters
    ----------
    system : System
        The cam-follower; its motion is replaced by the table, which starts at
        ``Theta(0) = angles[0]`` with the follower at its static equilibrium there (with
        the friction of the table's starting speed, as :func:`camdyn.simulate` takes it).
        The result's ``speed_hz`` attribute is that starting speed.
    times, angles : array_like
        The table (:func:`tabulated_motion`): times [s], cam angles [rad].
    periods : float
        Length of the run in table periods [-]; ignored with ``duration``.
    duration : float, optional
        Length of the run [s].
    sample_rate : float
        Output sampling rate [Hz].
    rtol, atol : float
        Local error tolerances: relative [-] and absolute [rad, rad/s].
    method : {"auto", "dop853", "explicit", "rosenbrock", "radau", "switching"}
        Stepper choice, as in :func:`camdyn.simulate`.
    variables : sequence of str, optional
        As :func:`camdyn.simulate`.

    Returns
    -------
    xarray.Dataset
        As :func:`camdyn.simulate` returns, the cam angle and speed following the table.
    """
    from camdyn.model import layout as L
    from camdyn.simulation.runner import run_dataset

    period, mean_speed, coefficients = tabulated_motion(times, angles)
    limits.check_system(system)
    if duration is None:
        duration = limits.check_number("periods", periods) * period
    # the static equilibrium the run starts from takes the friction's direction (and, for
    # tanh friction, its size) from the cam speed at t = 0: the table's, as constant motion
    start_speed = float(coefficients[1] + mean_speed)
    s = system.with_values(**{"motion.kind": "constant", "motion.initial_angle": float(np.asarray(angles)[0]),
                              "motion.speed": abs(start_speed) / (2.0 * math.pi),
                              "motion.direction": 1 if start_speed >= 0.0 else -1})
    prep = prepare(s)
    p = np.r_[prep.p, coefficients]
    p[L.MOTION_KIND] = 3.0
    p[L.TABLE_START] = prep.p.size   # after a cam profile's table, if any
    p[L.TABLE_INTERVALS] = coefficients.size // 4
    p[L.TABLE_PERIOD] = period
    p[L.TABLE_DRIFT] = mean_speed
    prep.p = p
    t, y, modes, events, counters, elapsed = _run_counters(systems.CAM_FOLLOWER, p, prep.y0, duration, sample_rate,
                                                           period, rtol, atol, method, None)
    return run_dataset(s, prep, t, y, modes, events, counters, elapsed, rtol, atol, method, variables)
