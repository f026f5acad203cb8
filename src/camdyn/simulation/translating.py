"""Simulation of a translating follower on a cam profile (:mod:`camdyn.model.translating_follower`):
the parameters, the run through the compiled driver, and the result as an xarray Dataset.

This model is not part of the :class:`~camdyn.params.system.System` machinery (which
describes the rocking follower); its parameters are the frozen dataclass
:class:`TranslatingFollower`. Its configuration files are read by
:mod:`camdyn.params.profiles` into a :class:`~camdyn.params.profiles.TranslatingSpec`,
which :func:`follower_from_spec` turns into a follower; :func:`alzate_rig` is the preset
``alzate`` written in Python.
"""

from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from camdyn.errors import ParameterError
from camdyn.integrator import driver
from camdyn.model import translating_follower as model
from camdyn.model.profiles import (
    Profile,
    circular_arc_profile,
    eccentric_circle,
    rise_return_profile,
    tabulated_profile,
)
from camdyn.params.profiles import TranslatingSpec
from camdyn.params.units import angular_speed
from camdyn.simulation import limits
from camdyn.simulation.translating_contact import HertzContact
from camdyn.systems import registry as systems

__all__ = ["TranslatingFollower", "HertzContact", "simulate_translating", "alzate_rig", "liftoff_speed",
           "follower_from_spec", "CONTACT_LAWS"]

CONTACT_LAWS = {"rigid": model.RIGID, "compliant": model.COMPLIANT, "hertz": model.HERTZ}


@dataclass(frozen=True)
class TranslatingFollower:
    """A spring-loaded translating follower on a cam, validated when built.

    Attributes
    ----------
    profile : Profile
        The cam's lift law (:mod:`camdyn.model.profiles`).
    mass : float
        Follower mass m [kg].
    stiffness : float
        Spring stiffness k [N/m].
    preload : float
        Spring force F0 [N] when the follower rests on the base circle.
    damping : float
        Viscous damping c [N s/m].
    gravity : float
        Gravity g [m/s^2] along the follower's line, towards the cam (0: none).
    contact : str
        ``"rigid"`` (Newton restitution, sustained contact), ``"compliant"`` (linear
        spring-dashpot penalty) or ``"hertz"`` (the Hertz law of ``hertz``).
    restitution : float
        Newton's coefficient of restitution e [-] (rigid).
    capture_velocity : float
        Impacts slower than this [m/s] end in sustained contact (rigid).
    contact_stiffness, contact_damping : float
        kc [N/m] and cc [N s/m] of the compliant law.
    hertz : HertzContact or None
        Materials, geometry and damping of the Hertz law (required by ``"hertz"``).
    lever : Profile or None
        For a rocking arm run on this model (:mod:`camdyn.simulation.rocking_roller`), the
        lever ``L_n`` [m] of the contact normal about the pivot over the cam angle, in a
        profile's table: the Hertz law then works on the normal penetration ``L_n delta``
        and gives the moment ``L_n N`` (eqs. 8-9 of
        :mod:`camdyn.model.translating_follower`). Hertz contact only.
    curvature : Profile or None
        With ``lever``, the curvature ``kappa_cam`` [1/m] of the cam's surface at the
        contact over the cam angle: required by point contact.
    citation : str
        Where the numbers come from.
    """

    profile: Profile
    mass: float
    stiffness: float
    preload: float
    damping: float = 0.0
    gravity: float = 0.0
    contact: str = "rigid"
    restitution: float = 0.8
    capture_velocity: float = 1e-6
    contact_stiffness: float = 0.0
    contact_damping: float = 0.0
    hertz: HertzContact | None = None
    lever: Profile | None = None
    curvature: Profile | None = None
    citation: str = field(default="", compare=False)

    def __post_init__(self):
        self._check_lever()
        if not isinstance(self.profile, Profile):
            raise ParameterError(f"profile must be a camdyn Profile, got {type(self.profile).__name__}")
        if self.contact not in CONTACT_LAWS:
            raise ParameterError(f"contact must be one of {', '.join(CONTACT_LAWS)}, got {self.contact!r}")
        for name in ("mass", "stiffness", "preload", "damping", "gravity", "restitution", "capture_velocity",
                     "contact_stiffness", "contact_damping"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ParameterError(f"{name} must be a finite number, got {value!r}")
            if value < 0.0:
                raise ParameterError(f"{name} must not be negative, got {value!r}")
        if self.mass <= 0.0:
            raise ParameterError(f"mass must be positive, got {self.mass!r} kg")
        if self.restitution > 1.0:
            raise ParameterError(f"restitution must be between 0 and 1, got {self.restitution!r}")
        if self.contact == "compliant" and self.contact_stiffness <= 0.0:
            raise ParameterError("the compliant contact needs a positive contact_stiffness [N/m]")
        if self.contact == "hertz":
            if not isinstance(self.hertz, HertzContact):
                raise ParameterError("the Hertz contact needs its materials and geometry (hertz=HertzContact(...))")
            if self.lever is not None and self.hertz.geometry_of(self.profile.follower) == "point" and (
                    self.curvature is None):
                raise ParameterError("the arm's Hertz point contact needs the cam's curvature at its contact "
                                     "(curvature=...)")
            self.hertz.check(self.profile, self.curvature)

    def _check_lever(self):
        """Refuse lever and curvature tables that are not tables, or where no Hertz law
        reads them."""
        for name in ("lever", "curvature"):
            table = getattr(self, name)
            if table is not None and not isinstance(table, Profile):
                raise ParameterError(f"{name} must be a table in a camdyn Profile, got {type(table).__name__}")
        if self.curvature is not None and self.lever is None:
            raise ParameterError("the curvature table belongs with a lever table (a rocking arm)")
        if self.lever is not None and self.contact != "hertz":
            raise ParameterError(f"the lever table is read by the Hertz law only, not the {self.contact} one")

    def pack(self, speed, phase=0.0):
        """The parameter vector of the compiled model at ``speed`` [rad/s], cam angle
        ``phase`` [rad] at t = 0."""
        contact = {"restitution": self.restitution, "contact_stiffness": self.contact_stiffness,
                   "contact_damping": self.contact_damping}
        if self.contact == "hertz":   # its damping and restitution, and its slots
            contact.update(restitution=self.hertz.restitution, contact_damping=self.hertz.damping,
                           hertz_law=self.hertz.slots(self.profile))
        return model.pack(self.profile, self.mass, self.stiffness, self.preload, speed, damping=self.damping,
                          phase=phase, gravity=self.gravity, law=CONTACT_LAWS[self.contact],
                          capture=self.capture_velocity, **contact,
                          lever=None if self.lever is None else self.lever.table,
                          curvature=None if self.curvature is None else self.curvature.table)


#: The circular-arc cam of the Siconos cam-follower example (the cam law of its
#: ``FollowerPlugin``, after di Bernardo, Osorio and Santini): base radius, flank arc
#: (centre distance, radius), nose arc (centre distance, radius), top radius [m], and the
#: angles where flank and nose end, from the end of the base dwell [rad].
ALZATE_ARCS = {"base": 0.40, "flank_centre": 0.45, "flank_radius": 0.85, "nose_centre": 0.40393320723821,
               "nose_radius": 0.15, "top": 0.55393320723821, "flank_end": 1.050328174371336,
               "nose_end": 1.22173047639603}
ALZATE_CITATION = (
    "Siconos examples, mechanics/CamFollower (FollowerPlugin, CamFollower.cpp): follower mass 1.221 kg, "
    "spring 1430.8 N/m, Newton restitution 0.8, circular-arc cam; after M. di Bernardo, G. Osorio, "
    "S. Santini, 'Corner-impact bifurcations: a novel class of discontinuity-induced bifurcations in cam-follower "
    "systems', arXiv:0711.1008 (2007)")


def alzate_rig(contact="rigid", contact_stiffness=0.0, contact_damping=0.0, hertz=None):
    """The cam-follower rig of Alzate and di Bernardo as the Siconos project's example
    gives it: an in-line knife-edge follower (m = 1.221 kg, k = 1430.8 N/m, e = 0.8) on a
    symmetric cam of circular arcs: the base circle (r = 0.40 m) for half a turn, a flank
    arc (radius 0.85 m, centre 0.45 m behind the axis), a nose arc (radius 0.15 m, centre
    0.4039 m out) and a top arc concentric with the axis (r = 0.5539 m), then the same
    back. The spring is relaxed at 0.30 m from the axis, so its preload on the base circle
    is ``k (0.40 - 0.30) = 143.08 N``; no gravity, no damping. Use the phase pi/2 of the
    source (``simulate_translating(..., phase=math.pi / 2)``) to start where it starts,
    at the end of the base dwell. ``contact="hertz"`` takes the Hertz law's
    :class:`HertzContact` as ``hertz`` (a rounded tip: ``HertzContact(tip_radius=...)``)."""
    a = ALZATE_ARCS
    quarter = 0.5 * math.pi
    nose_angle = math.pi - math.pi / 9.0   # the nose arc's centre in the cam's frame [rad]
    arcs = [
        (quarter, 0.0, 0.0, a["base"]),
        (a["flank_end"], a["flank_centre"], -quarter, a["flank_radius"]),
        (a["nose_end"] - a["flank_end"], a["nose_centre"], nose_angle, a["nose_radius"]),
        (math.pi - 2.0 * a["nose_end"], 0.0, 0.0, a["top"]),
        (a["nose_end"] - a["flank_end"], a["nose_centre"], -nose_angle, a["nose_radius"]),
        (a["flank_end"], a["flank_centre"], quarter, a["flank_radius"]),
        (quarter, 0.0, 0.0, a["base"]),
    ]
    profile = circular_arc_profile(arcs, a["base"], follower="knife")
    stiffness = 1430.8
    return TranslatingFollower(profile, mass=1.221, stiffness=stiffness, preload=stiffness * (a["base"] - 0.30),
                               contact=contact, restitution=0.8, contact_stiffness=contact_stiffness,
                               contact_damping=contact_damping, hertz=hertz, citation=ALZATE_CITATION)


def follower_from_spec(spec, lift=None):
    """The :class:`TranslatingFollower` of a configuration.

    Parameters
    ----------
    spec : TranslatingSpec
        The configuration in SI units (:func:`camdyn.params.profiles.read_translating`).
    lift : array_like, optional
        The lift samples [m] at equally spaced cam angles from 0, for a tabulated profile
        (read from ``spec.file`` by :func:`camdyn.io.lift_table.read_lift_table`).

    Returns
    -------
    TranslatingFollower
        Its profile checked for a cam that can be made (a ``GeometryError`` otherwise).
    """
    if not isinstance(spec, TranslatingSpec):
        raise ParameterError(f"expected a TranslatingSpec, got {type(spec).__name__}")
    face = {"follower": spec.face, "roller_radius": spec.roller_radius}
    if spec.profile_kind == "rise-return":
        profile = rise_return_profile(spec.segments, spec.base_radius, offset=spec.offset, **face)
    elif spec.profile_kind == "tabulated":
        if lift is None:
            raise ParameterError(f"a tabulated profile needs its lift samples (from {spec.file})")
        profile = tabulated_profile(lift, spec.base_radius, offset=spec.offset, **face)
    else:
        if spec.offset != 0.0:
            raise ParameterError(f"follower.offset: a {spec.profile_kind} cam takes an in-line follower only "
                                 f"(offset 0), not {spec.offset} m")
        if spec.profile_kind == "circular-arc":
            profile = circular_arc_profile(spec.arcs, spec.base_radius, **face)
        else:
            profile = eccentric_circle(spec.radius, spec.eccentricity, **face)
    return TranslatingFollower(profile, mass=spec.mass, stiffness=spec.stiffness, preload=spec.preload,
                               damping=spec.damping, gravity=spec.gravity, contact=spec.contact,
                               restitution=spec.restitution, capture_velocity=spec.capture_velocity,
                               contact_stiffness=spec.contact_stiffness, contact_damping=spec.contact_damping,
                               hertz=_hertz_of(spec), citation=spec.citation)


def _hertz_of(spec):
    """The :class:`HertzContact` of a configuration whose contact law is ``"hertz"``."""
    if spec.contact != "hertz":
        return None
    return HertzContact(cam_modulus=spec.cam_modulus, cam_poisson=spec.cam_poisson,
                        follower_modulus=spec.follower_modulus, follower_poisson=spec.follower_poisson,
                        geometry=spec.geometry, width=spec.width, tip_radius=spec.tip_radius,
                        damping_law=spec.damping_law, damping=spec.contact_damping, restitution=spec.restitution,
                        reference_velocity=spec.reference_velocity)


def liftoff_speed(follower, samples=200_000):
    """The lowest cam speed [rad/s] at which a follower held on the cam would need a pull:
    the smallest positive root over the cam angles of the contact force (eq. 3 of
    :mod:`camdyn.model.translating_follower`), ``m s'' omega^2 + c s' omega + F0 + k s +
    m g = 0``; without damping ``omega^2 = min over s'' < 0 of (F0 + k s + m g) / (-m
    s'')``. Infinite for a cam that never needs a pull. Evaluated on ``samples`` angles and
    at both sides of every joint."""
    theta = np.unique(np.r_[np.linspace(0.0, 2.0 * math.pi, samples, endpoint=False),
                            follower.profile.joints, follower.profile.joints - 1e-12])
    s, s1, s2, _ = follower.profile.lift(theta)
    a = follower.mass * s2
    b = follower.damping * s1
    c = follower.preload + follower.stiffness * s + follower.mass * follower.gravity
    if np.any(c <= 0.0):
        return 0.0   # the spring does not even hold the follower at rest
    with np.errstate(invalid="ignore", divide="ignore"):
        # a < 0 < c: one positive root, (-b - sqrt(b^2 - 4 a c)) / (2 a)
        roots = np.where(a < 0.0, (-b - np.sqrt(b * b - 4.0 * a * c)) / (2.0 * a), np.inf)
        # a >= 0 and b < 0: a positive root only where b^2 >= 4 a c, the smaller one
        both = (a > 0.0) & (b < 0.0) & (b * b >= 4.0 * a * c)
        roots = np.where(both, (-b - np.sqrt(b * b - 4.0 * a * c)) / (2.0 * a), roots)
        roots = np.where((a == 0.0) & (b < 0.0), -c / b, roots)
    return float(np.min(roots))


def check_run_arguments(speed, duration, sample_rate, rtol, atol):
    """Refuse a speed [rad/s], duration [s], sample rate [Hz] or tolerances (``atol`` [m])
    that are not positive and finite, or tolerances outside 1e-14 to 1e-2."""
    for name, value, unit in (("speed", speed, "rad/s"), ("duration", duration, "s"),
                              ("sample_rate", sample_rate, "Hz"), ("rtol", rtol, ""), ("atol", atol, "m")):
        limits.check_number(name, value, unit)
        if not (math.isfinite(value) and value > 0.0):
            raise ParameterError(f"{name} must be positive and finite, got {value!r} {unit}".rstrip())
    if not (1e-14 <= rtol <= 1e-2 and 1e-16 <= atol <= 1e-2):
        raise ParameterError(f"rtol = {rtol!r} or atol = {atol!r} is outside the sensible range (1e-14 to 1e-2)")


def simulate_translating(follower, speed, duration, sample_rate=10e3, phase=0.0, initial_state=None, rtol=1e-10,
                         atol=1e-12, max_step=None, max_events=None, max_steps=50_000_000) -> xr.Dataset:
    """Simulate a translating follower.

    Parameters
    ----------
    follower : TranslatingFollower
        The follower and its cam.
    speed : float or str
        Cam speed [Hz] (revolutions per second), or text with units such as ``"358 rpm"``,
        ``"37.5 rad/s"`` or ``"6 Hz"`` (:func:`camdyn.params.units.parse_speed`); positive
        (counter-clockwise). Compiled code runs on omega [rad/s].
    duration : float
        Length of the run [s].
    sample_rate : float
        Output sampling rate [Hz].
    phase : float
        Cam angle theta0 [rad] at t = 0.
    initial_state : (float, float), optional
        ``(x [m], x_dot [m/s])``; default on the cam, moving with it.
    rtol, atol : float
        Local error tolerances, relative [-] and absolute [m, m/s].
    max_step : float, optional
        Largest step [s]; default 1/64 of the cam period.
    max_events : int, optional
        Room in the event log; default 64 per revolution plus 1000.
    max_steps : int
        Largest number of steps; a run that needs more stops with a ``SimulationError``.

    Returns
    -------
    xarray.Dataset
        Over ``time``: ``x``, ``x_dot``, the cam's ``lift`` and ``lift_rate``, the ``gap``,
        the ``contact_force`` and ``in_contact``; over ``event``: ``event_time``,
        ``event_kind`` (``impact``, ``capture`` into sustained contact, ``graze``: a
        touch slower than the capture velocity where the cam does not push, which leaves
        the follower in flight, ``separation``, where the force falls to zero or at a
        joint of the profile beyond which the cam would pull, and for the compliant and Hertz laws
        ``contact onset`` and ``contact end``), ``event_velocity`` (approach velocity of an impact, ``x_dot -
        s_dot`` [m/s]). Attributes hold the parameters and the solver counters.
    """
    if not isinstance(follower, TranslatingFollower):
        raise ParameterError(f"expected a TranslatingFollower, got {type(follower).__name__}")
    speed = angular_speed(speed)   # omega [rad/s] from Hz or text with units
    check_run_arguments(speed, duration, sample_rate, rtol, atol)
    if not math.isfinite(limits.check_number("phase", phase, "rad")):
        raise ParameterError(f"phase must be finite, got {phase!r} rad")
    period = 2.0 * math.pi / speed
    n_out = limits.check_sampling(sample_rate, period, duration)
    limits.check_memory(limits.result_bytes(n_out, 8), "the simulation's result")
    p = follower.pack(float(speed), float(phase))
    if initial_state is None:
        _, s, sd, _, _ = model.cam(0.0, p)
        y0 = np.array([s, sd])
    else:
        y0 = np.asarray(initial_state, dtype=float).reshape(-1)
        if y0.shape != (2,) or not np.all(np.isfinite(y0)):
            raise ParameterError(f"initial_state must be two finite numbers (x [m], x_dot [m/s]), "
                                 f"got {initial_state!r}")
        if y0[0] < model.cam(0.0, p)[1] - 1e-12 * max(1.0, abs(y0[0])) and follower.contact == "rigid":
            raise ParameterError(f"the follower starts inside the cam (x = {y0[0]} m below the lift "
                                 f"{model.cam(0.0, p)[1]} m); a rigid contact allows no penetration")
    t_out, y, modes, events, counters, elapsed = run_follower(
        systems.TRANSLATING_FOLLOWER, p, y0, duration, sample_rate, n_out, period, rtol, atol, max_step, max_events,
        max_steps)
    return _dataset(follower, p, t_out, y, modes, events, counters, elapsed, speed, phase, rtol, atol)


def run_follower(system_id, p, y0, duration, sample_rate, n_out, period, rtol, atol, max_step, max_events,
                 max_steps):
    """Run a follower model ``system_id`` from ``y0`` over ``duration`` [s], sampled at
    ``n_out`` times ``sample_rate`` [Hz] apart, with the limits of
    :func:`simulate_translating` (``max_step`` [s] default ``period / 64``, ``max_events``
    default 64 a revolution plus 1000), refused before the run when meaningless.

    Returns ``(t_out [s], y, modes, events, counters, elapsed [s])``."""
    max_step = period / 64.0 if max_step is None else max_step
    max_events = int(1000 + 64 * duration / period) if max_events is None else max_events
    if not (isinstance(max_step, (int, float)) and math.isfinite(max_step) and max_step > 0.0):
        raise ParameterError(f"max_step must be a positive number of seconds, got {max_step!r}")
    for name, value in (("max_events", max_events), ("max_steps", max_steps)):
        if isinstance(value, bool) or not (isinstance(value, (int, np.integer)) and value > 0):
            raise ParameterError(f"{name} must be a positive whole number, got {value!r}")
    t_out = np.minimum(np.arange(n_out) / sample_rate, duration)
    start = _time.perf_counter()
    y, modes, events, counters = driver.integrate(system_id, p, y0, 0.0, float(duration), t_out, float(rtol),
                                                  float(atol), float(max_step), driver.METHOD_AUTO, int(max_steps),
                                                  int(max_events), True, math.inf)
    elapsed = _time.perf_counter() - start
    limits.check_run(counters, "simulation")
    return t_out, y, modes, events, counters, elapsed


def leaves_at_joint(t, p):
    """Whether a follower in rigid sustained contact leaves the cam at the profile's joint
    it reaches at ``t`` [s]: the force N (eq. 3) on the joint's far side is at most zero
    (the model's rule, :func:`camdyn.model.translating_follower.joint_transition`)."""
    segment = model.segment_at(p[model.PHASE] + p[model.SPEED] * t, p)[0]
    s, s_dot, s_ddot = model.far_side(t, segment, p)
    return p[model.MASS] * s_ddot + model.spring_force(s, s_dot, p) <= 0.0


def _event_table(events, p, contact):
    """Kinds and approach velocities [m/s] of the logged events, ``contact`` whether the
    run starts in sustained contact. A joint of the profile (guard 2) is a separation
    where the follower leaves the cam there, else the kind ``joint``."""
    m = systems.guard_count(systems.TRANSLATING_FOLLOWER)
    kinds, velocities = [], []
    for ev in events:
        t, k, v = ev[0], int(ev[1]), ev[driver.EVENT_GUARDS + m + 1]
        sd = model.cam(t, p)[2]
        if k == model.JOINT:
            kind = "joint"
            if contact and p[model.LAW] == model.RIGID and leaves_at_joint(t, p):
                kind, contact = "separation", False
            kinds.append(kind)
        elif p[model.LAW] != model.RIGID:
            kinds.append("contact onset" if ev[2] < 0 else "contact end")
        elif k == 1:
            kinds.append("separation")
            contact = False
        elif -(v - sd) > p[model.CAPTURE]:
            kinds.append("impact")
        else:
            # a touch slower than the capture velocity: held on the cam where it pushes,
            # else a graze (the gap's rounding noise just after a separation, where gap,
            # rate and gap acceleration all start at zero), which changes nothing
            contact = ev[driver.EVENT_NEW_SIGN] == 0.0
            kinds.append("capture" if contact else "graze")
        velocities.append(v - sd)
    return np.array(kinds, dtype=str), np.array(velocities, dtype=float)


def _dataset(follower, p, t, y, modes, events, counters, elapsed, speed, phase, rtol, atol):
    lift = np.empty((t.size, 4))
    force = np.empty(t.size)
    y = y.copy()
    for i, ti in enumerate(t):
        lift[i] = model.cam(ti, p)[1:]
        y[i] = model.follower_state(ti, y[i], modes[i], p)
        force[i] = model.contact_force(ti, y[i], modes[i], p)
    kinds, velocities = _event_table(events, p, modes.shape[0] > 0 and modes[0, 0] > 0.5)
    shown = kinds != "joint"   # the joints that changed nothing are left out
    events, kinds, velocities = events[shown], kinds[shown], velocities[shown]
    data = {
        "x": (("time",), y[:, 0], {"units": "m", "long_name": "follower position from the base circle"}),
        "x_dot": (("time",), y[:, 1], {"units": "m/s", "long_name": "follower velocity"}),
        "lift": (("time",), lift[:, 0], {"units": "m", "long_name": "cam lift s"}),
        "lift_rate": (("time",), lift[:, 1], {"units": "m/s", "long_name": "cam lift rate s_dot"}),
        "gap": (("time",), y[:, 0] - lift[:, 0], {"units": "m", "long_name": "gap x - s"}),
        "contact_force": (("time",), force, {"units": "N", "long_name": "force of the cam on the follower"}),
        "in_contact": (("time",), modes[:, 0].astype(np.int8), {"units": "1", "long_name": "contact mode"}),
        "event_time": (("event",), events[:, 0], {"units": "s", "long_name": "event time"}),
        "event_kind": (("event",), kinds, {"long_name": "event kind"}),
        "event_velocity": (("event",), velocities,
                           {"units": "m/s", "long_name": "relative velocity x_dot - s_dot before the event"}),
    }
    ds = xr.Dataset(data, coords={"time": ("time", t, {"units": "s", "long_name": "time"})})
    ds.attrs.update({
        "title": "camdyn translating follower", "citation": follower.citation, "speed_rad_s": float(speed),
        "phase_rad": float(phase), "mass_kg": follower.mass, "stiffness_N_per_m": follower.stiffness,
        "preload_N": follower.preload, "damping_N_s_per_m": follower.damping, "gravity_m_per_s2": follower.gravity,
        "contact": follower.contact, "restitution": follower.restitution,
        "capture_velocity_m_per_s": follower.capture_velocity,
        "contact_stiffness_N_per_m": follower.contact_stiffness,
        "contact_damping_N_s_per_m": follower.contact_damping, "follower": follower.profile.follower,
        "base_radius_m": follower.profile.base_radius, "rtol": rtol, "atol": atol, "elapsed_s": elapsed,
        "status": driver.STATUS_MESSAGES[int(counters[driver.COUNT_STATUS])],
    })
    if follower.contact == "hertz":
        law = follower.hertz
        ds.attrs.update({
            "hertz_modulus_Pa": law.modulus, "hertz_geometry": law.geometry_of(follower.profile.follower),
            "hertz_width_m": law.width, "hertz_follower_radius_m": float(p[model.FOLLOWER_RADIUS]),
            "hertz_damping_law": law.damping_law, "hertz_damping_N_s_per_m": law.damping,
            "hertz_restitution": law.restitution, "hertz_reference_velocity_m_per_s": law.reference_velocity})
    for i, name in enumerate(driver.COUNTER_NAMES):
        ds.attrs[f"solver_{name}"] = int(counters[i])
    return ds
