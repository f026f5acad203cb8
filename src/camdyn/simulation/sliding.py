"""Simulation of a translating follower with Coulomb friction at its cam contact
(:mod:`camdyn.model.sliding_follower`): the friction's parameters, the run through the
compiled driver, and the result as an xarray Dataset.

The follower is a :class:`~camdyn.simulation.translating.TranslatingFollower` with the
rigid contact law; :class:`FollowerFriction` adds the friction coefficients and the
roller's spin inertia.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr

from camdyn.errors import ParameterError
from camdyn.integrator import driver
from camdyn.model import sliding_follower as model
from camdyn.model import translating_follower as base
from camdyn.model.profiles import pressure_angle
from camdyn.params.units import angular_speed
from camdyn.simulation import limits
from camdyn.simulation.translating import TranslatingFollower, check_run_arguments, leaves_at_joint, run_follower
from camdyn.systems import registry as systems

__all__ = ["FollowerFriction", "simulate_sliding", "jamming_margin", "friction_from_spec"]

#: Names of the slip modes in the results.
SLIP_NAMES = {1.0: "sliding forward", -1.0: "sliding backward", 0.0: "rolling"}


@dataclass(frozen=True)
class FollowerFriction:
    """Coulomb friction at the cam contact, validated when built.

    Attributes
    ----------
    static : float
        Static coefficient mu_s [-] (a roller rolls while the friction its spin needs
        stays within ``mu_s N``).
    kinetic : float or None
        Kinetic coefficient mu_k [-] while sliding, ``<= static``; default ``static``.
    roller_inertia : float
        The roller's moment of inertia about its axle J_r [kg m^2] (a roller only).
    """

    static: float
    kinetic: float | None = None
    roller_inertia: float = 0.0

    def __post_init__(self):
        if self.kinetic is None:
            object.__setattr__(self, "kinetic", self.static)
        for name in ("static", "kinetic", "roller_inertia"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ParameterError(f"friction.{name} must be a finite number, got {value!r}")
            if value < 0.0:
                raise ParameterError(f"friction.{name} must not be negative, got {value!r}")
        if self.kinetic > self.static:
            raise ParameterError(f"friction.kinetic ({self.kinetic}) must not exceed friction.static "
                                 f"({self.static})")

    def check(self, follower):
        """Refuse a friction that has no meaning for ``follower`` (a
        :class:`TranslatingFollower`): friction with a law other than rigid, a roller
        inertia without a roller, or a cam on which the knife edge or roller would jam."""
        if not isinstance(follower, TranslatingFollower):
            raise ParameterError(f"expected a TranslatingFollower, got {type(follower).__name__}")
        face = follower.profile.follower
        if self.roller_inertia > 0.0 and face != "roller":
            raise ParameterError(f"friction.roller_inertia: a {face} follower has no roller to spin "
                                 f"(roller_inertia {self.roller_inertia} kg m^2)")
        if self.static > 0.0 and follower.contact != "rigid":
            raise ParameterError(f"friction at the follower needs the rigid contact law, not {follower.contact!r}")
        margin = jamming_margin(follower, self.kinetic)
        if margin <= 0.0:
            raise ParameterError(f"friction.kinetic = {self.kinetic}: the follower jams, cos(phi) - mu_k "
                                 f"|sin(phi)| reaches {margin:.3g} (eq. 3 of the normal force); lower the friction "
                                 "or the pressure angle")


def friction_from_spec(spec):
    """The :class:`FollowerFriction` of a configuration's ``[friction]`` keys
    (:mod:`camdyn.params.follower_friction`), or None where it has none (no friction and
    no roller inertia: the translating follower without friction)."""
    if spec.static_friction == 0.0 and spec.roller_inertia == 0.0:
        return None
    return FollowerFriction(spec.static_friction, spec.kinetic_friction, spec.roller_inertia)


def jamming_margin(follower, kinetic, samples=7200):
    """The smallest ``cos(phi) - mu_k |sin(phi)|`` [-] over the cam angles: the normal
    force of a sliding follower, ``F_line / (cos phi -+ mu_k sin phi)``, grows without
    bound where it reaches zero (the follower jams in its guide)."""
    theta = np.linspace(0.0, 2.0 * math.pi, samples, endpoint=False)
    phi = pressure_angle(follower.profile, theta)
    return float(np.min(np.cos(phi) - kinetic * np.abs(np.sin(phi))))


def _initial_state(follower, p, initial_state):
    """``(x, x_dot, omega_r, Q)``: by default on the cam, moving with it and rolling."""
    _, s, sd, _, _ = base.cam(0.0, p)
    rolling = model.rolling_spin(0.0, p) if follower.profile.follower == "roller" else 0.0
    if initial_state is None:
        return np.array([s, sd, rolling, 0.0])
    y0 = np.asarray(initial_state, dtype=float).reshape(-1)
    if y0.shape not in ((2,), (3,)) or not np.all(np.isfinite(y0)):
        raise ParameterError(f"initial_state must be two or three finite numbers (x [m], x_dot [m/s], "
                             f"roller speed [rad/s]), got {initial_state!r}")
    if y0[0] < s - 1e-12 * max(1.0, abs(y0[0])):
        raise ParameterError(f"the follower starts inside the cam (x = {y0[0]} m below the lift {s} m); "
                             "a rigid contact allows no penetration")
    return np.array([y0[0], y0[1], y0[2] if y0.size == 3 else rolling, 0.0])


def simulate_sliding(follower, friction, speed, duration, sample_rate=10e3, phase=0.0, initial_state=None,
                     rtol=1e-10, atol=1e-12, max_step=None, max_events=None, max_steps=50_000_000) -> xr.Dataset:
    """Simulate a translating follower with friction at its cam contact.

    Parameters
    ----------
    follower : TranslatingFollower
        The follower and its cam (rigid contact law where the friction is not zero).
    friction : FollowerFriction
        The friction coefficients and the roller's inertia.
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
    initial_state : sequence of 2 or 3 floats, optional
        ``(x [m], x_dot [m/s])`` or ``(x, x_dot, roller speed [rad/s])``; default on
        the cam, moving with it, the roller rolling.
    rtol, atol : float
        Local error tolerances, relative [-] and absolute [m, m/s].
    max_step, max_events, max_steps
        As :func:`camdyn.simulation.translating.simulate_translating`.

    Returns
    -------
    xarray.Dataset
        Over ``time``: ``x``, ``x_dot``, ``lift``, ``gap``, ``contact_force`` (the normal force N),
        ``line_force`` (along the follower's line), ``friction_force`` F (along the
        contact tangent), ``slip_velocity`` u, ``roller_speed`` omega_r,
        ``friction_heat`` Q, ``in_contact`` and ``rolling``; over ``event``:
        ``event_time``, ``event_kind`` (``impact``, ``capture``, ``graze``,
        ``separation``, ``rolling``: the slip ended inside the cone, ``reversal``,
        ``slip``: the cone broke) and ``event_velocity`` (``x_dot - s_dot`` [m/s]).
    """
    if not isinstance(friction, FollowerFriction):
        raise ParameterError(f"expected a FollowerFriction, got {type(friction).__name__}")
    friction.check(follower)
    speed = angular_speed(speed)   # omega [rad/s] from Hz or text with units
    check_run_arguments(speed, duration, sample_rate, rtol, atol)
    if not math.isfinite(limits.check_number("phase", phase, "rad")):
        raise ParameterError(f"phase must be finite, got {phase!r} rad")
    period = 2.0 * math.pi / speed
    n_out = limits.check_sampling(sample_rate, period, duration)
    limits.check_memory(limits.result_bytes(n_out, 14), "the simulation's result")
    p = model.pack(follower.pack(float(speed), float(phase)), friction.static, friction.kinetic,
                   friction.roller_inertia)
    y0 = _initial_state(follower, p, initial_state)
    t_out, y, modes, events, counters, elapsed = run_follower(
        systems.SLIDING_FOLLOWER, p, y0, duration, sample_rate, n_out, period, rtol, atol, max_step, max_events,
        max_steps)
    ds = _dataset(p, t_out, y, modes, events)
    ds.attrs.update({"title": "camdyn translating follower with friction", "citation": follower.citation,
                     "speed_rad_s": float(speed), "phase_rad": float(phase), "mass_kg": follower.mass,
                     "stiffness_N_per_m": follower.stiffness, "preload_N": follower.preload,
                     "damping_N_s_per_m": follower.damping, "restitution": follower.restitution,
                     "contact": follower.contact, "gravity_m_per_s2": follower.gravity,
                     "follower": follower.profile.follower, "static_friction": friction.static,
                     "kinetic_friction": friction.kinetic, "roller_inertia_kg_m2": friction.roller_inertia,
                     "rtol": rtol, "atol": atol, "elapsed_s": elapsed,
                     "status": driver.STATUS_MESSAGES[int(counters[driver.COUNT_STATUS])]})
    for i, name in enumerate(driver.COUNTER_NAMES):
        ds.attrs[f"solver_{name}"] = int(counters[i])
    return ds


def _samples(p, t, y, modes):
    """Per sample: the follower's state, lift, forces, slip and spin."""
    columns = np.zeros((t.size, 9))
    for i, ti in enumerate(t):
        x, v = base.follower_state(ti, y[i], modes[i], p)
        s = base.cam(ti, p)[1]
        spin = y[i, 2]
        if model.in_contact(modes[i], p):
            slip = modes[i, model.SLIP]
            normal, tangential, _ = model.forces(ti, slip, p)
            if slip == 0.0 and p[base.FACE] == base.ROLLER_FACE:
                spin = model.rolling_spin(ti, p)
            line = model.geometry(ti, p)[4]
            columns[i, 3:7] = normal, line, tangential, model.slip_velocity(ti, spin, p)
        columns[i, :3] = x, v, s
        columns[i, 7:] = spin, y[i, 3]
    return columns


def event_kinds(p, events, contact):
    """Kinds and approach velocities [m/s] of the logged events, ``contact`` whether the
    run starts in sustained contact; a joint of the profile is a separation where the
    follower leaves the cam there, else the kind ``joint``."""
    m = model.GUARD_COUNT
    kinds, velocities = [], []
    for ev in events:
        t, k, v = ev[0], int(ev[1]), ev[driver.EVENT_GUARDS + m + 1]
        sd = base.cam(t, p)[2]
        if k == base.JOINT:
            leaves = contact and leaves_at_joint(t, p)
            contact = contact and not leaves
            kinds.append("separation" if leaves else "joint")
        elif k == 1:
            kinds.append("separation")
            contact = False
        elif k == model.SLIP_GUARD:
            kinds.append("rolling" if ev[driver.EVENT_NEW_SIGN] == 0.0 else "reversal")
        elif k > model.SLIP_GUARD:
            kinds.append("slip")
        elif -(v - sd) > p[base.CAPTURE]:
            kinds.append("impact")
        else:
            contact = ev[driver.EVENT_NEW_SIGN] == 0.0
            kinds.append("capture" if contact else "graze")
        velocities.append(v - sd)
    return np.array(kinds, dtype=str), np.array(velocities, dtype=float)


def friction_dataset(p, t, modes, events, data: dict, gap, gap_attrs: dict, velocity_attrs: dict) -> xr.Dataset:
    """The Dataset of a run with friction at the cam contact (system 10, translating or
    rocking): the sampled variables ``data`` with the ``gap`` [m or rad], the contact mode,
    the roller's rolling flag and the event log (the joints that changed nothing left
    out), the events' relative velocity in ``velocity_attrs``'s unit."""
    kinds, velocities = event_kinds(p, events, modes.shape[0] > 0 and modes[0, 0] > 0.5)
    shown = kinds != "joint"   # the joints that changed nothing are left out
    events, kinds, velocities = events[shown], kinds[shown], velocities[shown]
    rolling = (modes[:, 0] > 0.5) & (modes[:, model.SLIP] == 0.0)
    data = dict(data)
    data.update({
        "gap": (("time",), gap, gap_attrs),
        "in_contact": (("time",), modes[:, 0].astype(np.int8), {"units": "1", "long_name": "contact mode"}),
        "rolling": (("time",), rolling.astype(np.int8), {"units": "1", "long_name": "roller rolling (sticking)"}),
        "event_time": (("event",), events[:, 0], {"units": "s", "long_name": "event time"}),
        "event_kind": (("event",), kinds, {"long_name": "event kind"}),
        "event_velocity": (("event",), velocities, velocity_attrs),
    })
    return xr.Dataset(data, coords={"time": ("time", t, {"units": "s", "long_name": "time"})})


def _dataset(p, t, y, modes, events):
    c = _samples(p, t, y, modes)
    series = (("x", 0, "m", "follower position from the base circle"), ("x_dot", 1, "m/s", "follower velocity"),
              ("lift", 2, "m", "cam lift s"), ("contact_force", 3, "N", "normal force N of the cam on the follower"),
              ("line_force", 4, "N", "force of the cam along the follower's line"),
              ("friction_force", 5, "N", "friction F on the follower along the contact tangent"),
              ("slip_velocity", 6, "m/s", "slip velocity u of the follower on the cam"),
              ("roller_speed", 7, "rad/s", "roller spin omega_r"),
              ("friction_heat", 8, "J", "heat of friction since the start"))
    data = {name: (("time",), c[:, i], {"units": unit, "long_name": long}) for name, i, unit, long in series}
    return friction_dataset(p, t, modes, events, data, c[:, 0] - c[:, 2], {"units": "m", "long_name": "gap x - s"},
                            {"units": "m/s", "long_name": "relative velocity x_dot - s_dot before the event"})
