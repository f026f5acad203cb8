"""Simulate the cam-follower and return the results as an xarray Dataset."""

from __future__ import annotations

import copy
import functools
import math
import time as _time

import numpy as np
import xarray as xr

from camdyn.errors import GeometryError, ParameterError, SimulationError
from camdyn.integrator import driver
from camdyn.model import layout as L
from camdyn.model.equilibrium import (
    Equilibrium,
    static_equilibrium,
    viscous_coefficient,
)
from camdyn.model.geometry import profile_reach, zero_state
from camdyn.model.outputs import CHANNELS, derived
from camdyn.model.profiles import check_profile
from camdyn.params.config import system_to_toml
from camdyn.params.system import System
from camdyn.params.units import parse_speed
from camdyn.simulation import limits
from camdyn.simulation.datasets import dataset
from camdyn.simulation.settling import check_settled
from camdyn.systems import registry as systems
from camdyn.systems.protocol import BoundModel, Model

__all__ = ["simulate", "prepare", "impact_table", "Prepared", "penetration_resolution", "run_dataset"]

METHODS = {"auto": driver.METHOD_AUTO, "explicit": driver.METHOD_EXPLICIT,
           "dop853": driver.METHOD_DOP853, "rosenbrock": driver.METHOD_ROSENBROCK, "radau": driver.METHOD_RADAU,
           "switching": driver.METHOD_SWITCHING}


class Prepared:
    """A system made ready for the compiled core: parameter vector, initial state, equilibrium."""

    def __init__(self, system: System):
        self.system = system
        if system.profile is not None:
            check_profile(system.profile)   # convex, lift and slope continuous
        theta0 = system.motion.initial_angle
        if theta0 is None:
            theta0 = zero_state(system)[1]
        self.theta0 = theta0
        self.equilibrium: Equilibrium = static_equilibrium(system, theta0)
        _check_contact_on_follower(system, self.equilibrium)
        self.viscous_c = viscous_coefficient(system, self.equilibrium) if self.equilibrium.in_contact else 0.0
        if system.contact.law.needs_damping_ratio and not self.equilibrium.in_contact:
            self.viscous_c = viscous_coefficient(system)  # raises a clear error
        self.p = L.pack(system, viscous_c=self.viscous_c, initial_angle=theta0)
        self.y0 = np.array([self.equilibrium.angle, 0.0, 0.0])


def _check_contact_on_follower(system: System, eq: Equilibrium) -> None:
    """Refuse a geometry whose contact leaves the follower: over a revolution the contact
    point moves along the bar by at most the runout plus the difference of the semi-axes
    [m] from where it sits at equilibrium (``chi*``)."""
    if not eq.in_contact:
        return
    cam, length = system.cam, system.follower.length
    if system.profile is not None:   # chi = u.E - h' (eq R3 of camdyn.model.rocking_profile)
        _, slope_min, slope_max = profile_reach(system.profile)
        slope = float(system.profile.lift(eq.angle + eq.cam_angle - 0.5 * math.pi)[1][0])   # h' now (eq R1)
        near, far = eq.moment_arm + slope - slope_max, eq.moment_arm + slope - slope_min
    else:
        reach = cam.runout + (cam.semi_major - cam.semi_minor)
        near, far = eq.moment_arm - reach, eq.moment_arm + reach
    if near <= 0.0 or far >= length:
        raise GeometryError(
            f"the cam touches the follower between {near * 1e3:.3g} and {far * 1e3:.3g} mm from the pivot over a "
            f"revolution, but the bar runs from 0 to {length * 1e3:.3g} mm (follower.length): move the cam "
            f"(cam.pivot_x) or lengthen the bar")


@functools.lru_cache(maxsize=64)
def _prepared(system: System) -> Prepared:
    return Prepared(system)


def prepare(system: System) -> Prepared:
    """Validate ``system`` against its geometry and compute the initial state.

    The static equilibrium is solved once per distinct system (systems are immutable and
    hashable; the last 64 are kept): the result is a copy whose arrays the caller may
    change. A refused system is refused again on every call."""
    cached = _prepared(system)
    prep = copy.copy(cached)
    prep.p = cached.p.copy()
    prep.y0 = cached.y0.copy()
    return prep


#: The parameters as TOML text, for the result's attributes (once per distinct system).
_parameters_toml = functools.lru_cache(maxsize=64)(functools.partial(system_to_toml, ignore_profile=True))


def penetration_resolution(prep: Prepared, rtol: float, atol: float) -> float:
    """Ratio of the integration error the tolerances allow in the penetration [m] to the
    static penetration ``delta*`` [m] (0 when the follower rests off the cam).

    The local error in ``alpha`` is about ``rtol |alpha| + atol`` [rad], with ``|alpha|``
    up to ``|alpha*| + e/chi*``; times ``chi*`` it is an error in the penetration. When it
    is not well below ``delta*`` (a stiff, lightly preloaded contact: nanometres), the
    solver's own error can open the contact and record spurious impacts; tighten
    ``rtol``/``atol`` until this ratio is below about 0.1.
    """
    eq = prep.equilibrium
    if not eq.in_contact or eq.penetration <= 0.0:
        return 0.0
    chi = abs(eq.moment_arm)
    runout = prep.system.cam.runout if prep.system.profile is None else 0.5 * profile_reach(prep.system.profile)[0]
    swing = abs(eq.angle) + runout / chi
    return (rtol * swing + atol) * chi / eq.penetration


def with_speed(system: System, speed) -> System:
    if speed is None:
        return system
    hz = parse_speed(speed)
    if not math.isfinite(hz) or hz < 0:
        raise ParameterError(f"speed must be a finite, non-negative number of Hz, got {speed!r}")
    return system.with_values(**{"motion.speed": hz})


def impact_table(events: np.ndarray) -> dict:
    """Impacts from the event log: contacts that began with an onset event and ended.

    Returns a dict of arrays: ``time`` [s], ``approach_velocity`` [m/s] (delta_dot at
    onset), ``separation_velocity`` [m/s] (-delta_dot at separation), ``peak_penetration``
    [m], ``peak_force`` [N], ``duration`` [s].
    """
    delta_at = driver.EVENT_GUARDS + 0          # the guards' values at each event (camdyn.model.dynamics.guards)
    delta_dot_at = driver.EVENT_GUARDS + 2
    force_at = driver.EVENT_MONITOR            # the peak force since the previous event (registry.monitor)
    rows = []
    start = None
    peak_delta = 0.0
    peak_force = 0.0
    for ev in events:
        t, k, new_sign = ev[0], int(ev[1]), ev[2]
        if k == 0 and new_sign > 0:
            start = ev
            peak_delta = 0.0
            peak_force = 0.0
        elif start is not None and k == 2 and new_sign <= 0:  # end of compression
            peak_delta = max(peak_delta, ev[delta_at])
            peak_force = max(peak_force, ev[force_at])
        elif start is not None:
            peak_force = max(peak_force, ev[force_at])
            if k == 0 and new_sign < 0:
                rows.append((start[0], start[delta_dot_at], -ev[delta_dot_at], peak_delta, peak_force, t - start[0]))
                start = None
    arr = np.array(rows, dtype=float).reshape(-1, 6)
    names = ("time", "approach_velocity", "separation_velocity", "peak_penetration", "peak_force", "duration")
    return {name: arr[:, i] for i, name in enumerate(names)}


def simulate(system: System, speed=None, revolutions: float = 30.0, duration: float | None = None,
             sample_rate: float = 20e3, rtol: float = 1e-8, atol: float = 1e-10, method: str = "auto",
             initial_state=None, max_step: float | None = None, max_steps: int = 50_000_000,
             variables=None) -> xr.Dataset:
    """Simulate the follower's motion.

    Parameters
    ----------
    system : System, Model or BoundModel
        The cam-follower system (see :func:`camdyn.load_system`), or a model of the model
        protocol with its parameters (``Model.bind({...})``, docs/user-models.md; its
        Dataset holds its states, output channels, modes and event table).
    speed : float or str, optional
        Cam speed [Hz] or text such as ``"693 rpm"``; default ``system.motion.speed``.
    revolutions : float
        Length of the run in cam periods (revolutions, or oscillations of an
        oscillating cam) [-]. Ignored when ``duration`` is given.
    duration : float, optional
        Length of the run [s].
    sample_rate : float
        Output sampling rate [Hz].
    rtol, atol : float
        Local error tolerances: relative [-] and absolute [rad, rad/s].
    method : {"auto", "dop853", "explicit", "rosenbrock", "radau", "switching"}
        ``auto`` lets the system choose (the cam-follower: DOP853, docs/integrator.md);
        ``explicit`` is Dormand-Prince 5(4), ``rosenbrock`` RODAS4, ``radau`` Radau IIA
        of order 5; ``switching`` runs DOP853 and Radau IIA in sustained contact.
    initial_state : (float, float), optional
        ``(alpha [rad], alpha_dot [rad/s])``; default the static equilibrium at ``Theta0``.
    max_step : float, optional
        Largest step [s]; default 1/12 of the cam period (:func:`default_max_step`).
        Whatever the step, the contact guards are checked at least every 1/32 of the
        period (a longer step is scanned on its continuous extension,
        :func:`default_scan`), so that no contact is skipped in free flight.
    max_steps : int
        Largest number of accepted steps.
    variables : sequence of str, optional
        The time series to return (:data:`VARIABLES`: the state ``alpha``,
        ``alpha_dot``, ``cam_work``, and the derived channels such as ``Fn`` or
        ``Nx``), and ``"impact"`` for the impact table; default all. The derived
        channels come from one compiled pass over the samples, which is skipped when
        none is asked for.

    Returns
    -------
    xarray.Dataset
        Over ``time``: the state and every force and kinematic channel with ``units``
        and ``long_name``; over ``impact``: the impact table. Attributes record the
        parameters (as TOML), the solver counters and the static equilibrium.

    Warns
    -----
    TransientWarning
        When a run of 9 cam periods or more has a last period that repeats none of the 8
        before it (within 1e-3 of ``alpha``'s range, :mod:`camdyn.simulation.settling`):
        its harmonics and extremes then describe a transient, or a motion that is not
        periodic.
    """
    if isinstance(system, (Model, BoundModel)):   # a model of the model protocol
        if method != "auto" or variables is not None:
            raise ParameterError("method and variables are not offered for a protocol model: leave them out")
        from camdyn.simulation.models import simulate_model

        return simulate_model(system.bind() if isinstance(system, Model) else system, speed=speed,
                              revolutions=revolutions, duration=duration, sample_rate=sample_rate, rtol=rtol,
                              atol=atol, initial_state=initial_state, max_step=max_step, max_steps=max_steps)
    limits.check_system(system)
    system = with_speed(system, speed)
    if not isinstance(method, str) or method not in METHODS:
        raise ParameterError(f"method must be one of {sorted(METHODS)}, got {method!r}")
    limits.check_tolerances(rtol, atol)
    wanted = check_variables(variables)
    period = system.motion.period
    duration = _duration(period, revolutions, duration)
    max_step, max_steps = limits.check_steps(max_step, max_steps, duration)
    n_out = limits.check_sampling(sample_rate, period, duration)
    limits.check_memory(limits.result_bytes(n_out, 3 + len(CHANNELS)), "the simulation's result")
    prep = prepare(system)
    y0 = starting_state(prep, initial_state)
    t_out = np.minimum(np.arange(n_out) / sample_rate, duration)  # the last sample may round past the end
    if max_step is None:
        max_step = default_max_step(period, duration)
    max_events = limits.event_room(duration, period)
    start = _time.perf_counter()
    y, modes, events, counters = limits.with_room_for_events(
        lambda room: driver.integrate(systems.CAM_FOLLOWER, prep.p.copy(), y0, 0.0, float(duration), t_out, float(rtol),
                                      float(atol), float(max_step), METHODS[method], int(max_steps), room, True,
                                      default_scan(period, duration)),
        max_events)
    elapsed = _time.perf_counter() - start
    status = int(counters[driver.COUNT_STATUS])
    if status == driver.STATUS_INTERRUPTED:
        raise KeyboardInterrupt
    if status != driver.STATUS_OK:
        t_fail = t_out[np.isnan(y[:, 0])][0] if np.isnan(y[:, 0]).any() else duration
        raise SimulationError(f"simulation {driver.STATUS_MESSAGES[status]} near t = {t_fail:.6g} s")
    check_settled(t_out, y[:, 0], period, "alpha")
    return _dataset(system, prep, t_out, y, modes, events, counters, elapsed, rtol, atol, method, wanted)


def _duration(period: float, revolutions, duration) -> float:
    """The run's length [s]: ``duration`` [s] if given, else ``revolutions`` cam periods of
    ``period`` [s]; refused unless positive and finite."""
    revolutions = limits.check_number("revolutions", revolutions)
    if duration is not None:
        duration = limits.check_number("duration", duration, "s")
    if duration is None:
        if not math.isfinite(period):
            raise ParameterError("the cam does not move (speed 0): give a duration in seconds")
        if not (math.isfinite(revolutions) and revolutions > 0):
            raise ParameterError(f"revolutions must be positive, got {revolutions!r}")
        duration = revolutions * period
    if not (math.isfinite(duration) and duration > 0):
        raise ParameterError(f"duration must be positive, got {duration!r}")
    return duration


#: The state's time series: name, unit, long name, in the state's order.
STATE_VARIABLES = (
    ("alpha", "rad", "follower angle (clockwise)"),
    ("alpha_dot", "rad/s", "follower angular velocity"),
    ("cam_work", "J", "work done by the cam on the follower"),
)
#: Every name :func:`simulate` accepts in ``variables``.
VARIABLES = tuple(name for name, _, _ in STATE_VARIABLES + CHANNELS) + ("impact",)


def starting_state(prep: Prepared, initial_state=None) -> np.ndarray:
    """The state a run starts from: the prepared static equilibrium, or ``initial_state``
    ``(alpha [rad], alpha_dot [rad/s])`` in its place (refused unless finite)."""
    y0 = prep.y0.copy()
    if initial_state is not None:
        try:
            given = np.asarray(initial_state, dtype=float)
        except (TypeError, ValueError):
            given = np.empty(0)
        if given.shape != (2,) or isinstance(initial_state, (str, bytes)):
            raise ParameterError(f"initial_state must be two numbers (alpha [rad], alpha_dot [rad/s]), "
                                 f"got {initial_state!r:.60}")
        y0[0], y0[1] = float(given[0]), float(given[1])
        if not np.all(np.isfinite(y0)):
            raise ParameterError("initial_state must be finite")
    return y0


def default_max_step(period: float, duration: float) -> float:
    """The largest step [s] by default: :data:`~camdyn.simulation.limits.STEP_FRACTION`
    (1/12) of the cam period [s], or 1/64 of the duration [s] when the cam stands still."""
    return limits.step_limits(period)[0] if math.isfinite(period) else duration / 64.0


def default_scan(period: float, duration: float) -> float:
    """The scan interval [s], the longest interval whose guards one cubic checks (a
    longer step is scanned on its continuous extension,
    :mod:`camdyn.integrator.crossings`): :data:`~camdyn.simulation.limits.SCAN_FRACTION`
    (1/32) of the cam period [s], or 1/64 of the duration [s] when the cam stands still."""
    return limits.step_limits(period)[1] if math.isfinite(period) else duration / 64.0


def check_variables(variables) -> frozenset:
    """The set of names asked for (all of :data:`VARIABLES` for ``None``); an unknown
    name, a bare string or an empty list is refused with a :class:`ParameterError`."""
    if variables is None:
        return frozenset(VARIABLES)
    if isinstance(variables, str):
        raise ParameterError(f"variables must be a list of names, got the string {variables!r}")
    if not isinstance(variables, (list, tuple, set, frozenset)):
        raise ParameterError(f"variables must be a list of names, got {type(variables).__name__} {variables!r:.60}")
    names = list(variables)
    unknown = [name for name in names if name not in VARIABLES]
    if unknown:
        raise ParameterError(f"unknown variable(s) {', '.join(map(repr, unknown))}; "
                             f"choose from {', '.join(VARIABLES)}")
    if not names:
        raise ParameterError("variables is empty: ask for at least one, e.g. ['alpha']")
    return frozenset(names)


def run_dataset(system: System, prep: Prepared, t, y, modes, events, counters, elapsed: float, rtol: float,
                atol: float, method: str, variables=None) -> xr.Dataset:
    """The Dataset :func:`simulate` returns, for a cam-follower run made elsewhere (one that
    packs its own parameter vector ``prep.p``): output times ``t`` [s], states ``y``,
    ``modes``, ``events`` and ``counters`` of :func:`camdyn.integrator.driver.integrate`,
    its wall time ``elapsed`` [s], and the tolerances and method it ran with."""
    return _dataset(system, prep, t, y, modes, events, counters, elapsed, rtol, atol, method,
                    check_variables(variables))


def _dataset(system, prep, t, y, modes, events, counters, elapsed, rtol, atol, method, wanted) -> xr.Dataset:
    data = {}
    for j, (name, unit, long_name) in enumerate(STATE_VARIABLES):
        if name in wanted:
            data[name] = (("time",), y[:, j], {"units": unit, "long_name": long_name})
    if any(name in wanted for name, _, _ in CHANNELS):
        chans = derived(t, y, modes, prep.p)
        for j, (name, unit, long_name) in enumerate(CHANNELS):
            if name in wanted:
                values = chans[:, j].astype(np.int8) if name == "in_contact" else chans[:, j]
                data[name] = (("time",), values, {"units": unit, "long_name": long_name})
    if "impact" in wanted:
        data.update(_impact_variables(events))
    ds = dataset(data, coords={"time": ("time", t, {"units": "s", "long_name": "time"})})
    ds.attrs.update(_attributes(system, prep, counters, elapsed, rtol, atol, method))
    return ds


def _impact_variables(events) -> dict:
    """The impact table as ``impact_*`` variables over the ``impact`` dimension."""
    imp = impact_table(events)
    imp_meta = {
        "time": ("s", "impact onset time"),
        "approach_velocity": ("m/s", "approach velocity delta_dot at onset"),
        "separation_velocity": ("m/s", "separation velocity -delta_dot at the end of contact"),
        "peak_penetration": ("m", "peak penetration"),
        "peak_force": ("N", "peak normal force"),
        "duration": ("s", "contact duration"),
    }
    return {f"impact_{name}": (("impact",), imp[name], {"units": unit, "long_name": long_name})
            for name, (unit, long_name) in imp_meta.items()}


def _attributes(system, prep, counters, elapsed, rtol, atol, method) -> dict:
    """The run's attributes: parameters as TOML, tolerances, equilibrium, solver counters."""
    eq = prep.equilibrium
    attrs = {
        "title": f"camdyn simulation of {system.name}",
        "citation": system.citation,
        "parameters_toml": _parameters_toml(system),
        "speed_hz": system.motion.speed,
        "rtol": rtol, "atol": atol, "method": method,
        "elapsed_s": elapsed,
        "status": driver.STATUS_MESSAGES[int(counters[driver.COUNT_STATUS])],
        "equilibrium_angle_rad": eq.angle,
        "equilibrium_contact_force_N": eq.contact_force,
        "natural_frequency_Hz": eq.natural_frequency,
        "initial_cam_angle_rad": prep.theta0,
        "viscous_damping_N_s_per_m": prep.viscous_c,
    }
    if system.profile is not None:   # the parameters' TOML describes the cam by its ellipse: say it is replaced
        attrs["cam_profile"] = (f"profile table of {int(system.profile.table[0])} segments, base radius "
                                f"{system.profile.base_radius!r} m, in place of the ellipse")
    for i, name in enumerate(driver.COUNTER_NAMES):
        attrs[f"solver_{name}"] = int(counters[i])
    return attrs
