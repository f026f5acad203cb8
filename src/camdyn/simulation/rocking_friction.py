"""Simulation of a rocking arm with Coulomb friction at its cam contact: the arm of
:mod:`camdyn.simulation.rocking_roller` (rigid contact law) run through the sliding
follower's compiled model (:mod:`camdyn.model.sliding_follower`, system 10) with the
arm's own levers and slip speed.

**The moment balance.** The cam pushes the roller (or the knife's tip) with ``N n + F t``
[N]: ``N`` along the pitch curve's outward normal ``n``, the friction ``F`` along the
tangent ``t`` (``n`` turned clockwise by a right angle, the sense in which the roller
centre moves relative to the cam, which turns counter-clockwise). The roller passes this
force to the arm at its axle ``C``, so its moment about the pivot ``P``, in the arm's
lift sense ``sigma``, is ``N L_n + F L_t`` with

    L_n = L cos(phi),    L_t = L sin(phi)                                          (F1)

[m], ``L`` the arm length and ``phi`` the pressure angle (eq. K4 of
:mod:`camdyn.model.rocking_roller`: ``n`` is the lift direction ``m = sigma e'(psi)``
turned by ``phi``, so ``L m . t = L sin(phi)``). In sustained rigid contact the arm
follows the cam, ``x = s(theta)``, and the moment balance

    I x'' = -M_0 - k_t x - c_t x' + N L_n + F L_t                                  (F2)

gives ``N L_n + F L_t = M`` with ``M = I omega^2 s'' + c_t omega s' + M_0 + k_t s`` [N m]
the holding moment of the frictionless arm: the arm's motion in rigid contact is the
cam's, unchanged by friction; the normal force, the pivot's reaction and the heat change.
Sliding (``F = -mu_k sign(u) N``)

    N = M / (L (cos(phi) - mu_k sign(u) sin(phi)))                                 (F3)

and the geometry jams where the bracket reaches zero: refused before the run. The slip
velocity [m/s] of the roller's material point on the cam's is

    u = omega V(theta) + r_r (omega_r - omega),
    V = (psi_c' L e'(psi) - z x C) . t                                             (F4)

with ``psi_c'`` [rad/rad] the contact angle's slope, ``z x C`` [m] the cam's velocity per
unit speed at the roller centre: ``omega V`` is the roller centre's speed relative to the
cam's point under it (the knife's tip slides at it). A roller with spin inertia ``J_r``
[kg m^2] about its (frictionless) axle turns by ``J_r omega_r' = r_r F``, rolls (``u =
0``, ``omega_r' = -omega^2 V' / r_r``, ``F = J_r omega_r' / r_r``, ``N = (M / L - F
sin(phi)) / cos(phi)``) while ``|F| <= mu_s N``, else slides: the laws of the sliding
follower with ``F_line = M / L`` and ``V`` in place of its ``L``. ``phi`` and ``V`` are
sampled exactly with the arm's contact angle and interpolated by periodic cubic splines;
``V' = dV/dtheta`` is the spline's slope.

**The pivot.** The arm's centre of mass is taken at its pivot (a balanced arm; the arm's
mass distribution is not part of the model), so the pivot holds the arm with ``R = -(N n
+ F t)`` [N].
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from camdyn.errors import GeometryError, ParameterError
from camdyn.integrator import driver
from camdyn.model import sliding_follower as model
from camdyn.model import translating_follower as base
from camdyn.params.units import angular_speed
from camdyn.simulation import limits
from camdyn.simulation.rocking_roller import RockingFollower, rocking_table, spline_table
from camdyn.simulation.sliding import FollowerFriction, friction_dataset
from camdyn.simulation.translating import TranslatingFollower, check_run_arguments, run_follower
from camdyn.systems import registry as systems

__all__ = ["check_arm_friction", "arm_tables", "simulate_rocking_friction", "arm_jamming_margin"]


def arm_tables(geometry, samples):
    """``(phi [rad], V [m])`` at the cam angles of the arm's lift table (eqs. K4, F4), from
    its exact contact angle, slope and pressure angle."""
    table = rocking_table(geometry, samples)
    sigma, length = geometry.lift_direction, geometry.arm_length
    psi = table.rest_angle + sigma * table.lift[0]
    slope = sigma * table.lift[1]
    phi = table.pressure_angle
    centre = (geometry.pivot_x + length * np.cos(psi), geometry.pivot_y + length * np.sin(psi))
    normal = psi + sigma * 0.5 * math.pi + phi          # the angle of n: m = sigma e'(psi) turned by phi
    tangent = (np.sin(normal), -np.cos(normal))         # t: n turned clockwise
    relative = (-slope * length * np.sin(psi) + centre[1],              # psi' L e' - z x C
                slope * length * np.cos(psi) - centre[0])
    return phi, relative[0] * tangent[0] + relative[1] * tangent[1]   # (F4)


def arm_jamming_margin(follower, kinetic):
    """``(margin [-], cam angle [rad])``: the smallest ``cos(phi) - mu_k |sin(phi)|`` over
    the table's cam angles and where it lies (eq. F3's bracket)."""
    phi, _ = arm_tables(follower.geometry, follower.samples)
    margin = np.cos(phi) - kinetic * np.abs(np.sin(phi))
    worst = int(np.argmin(margin))
    return float(margin[worst]), float(rocking_table(follower.geometry, follower.samples).theta[worst])


def check_arm_friction(follower, friction):
    """Refuse a friction that has no meaning for the arm: a law other than rigid, a roller
    inertia on a knife edge, or a geometry that jams (eq. F3), naming the cam angle."""
    if not isinstance(follower, RockingFollower):
        raise ParameterError(f"expected a RockingFollower, got {type(follower).__name__}")
    if not isinstance(friction, FollowerFriction):
        raise ParameterError(f"expected a FollowerFriction, got {type(friction).__name__}")
    if friction.roller_inertia > 0.0 and follower.geometry.roller_radius == 0.0:
        raise ParameterError(f"friction.roller_inertia: a knife edge has no roller to spin (roller_inertia "
                             f"{friction.roller_inertia} kg m^2)")
    if (friction.static > 0.0 or friction.roller_inertia > 0.0) and follower.contact != "rigid":
        raise ParameterError(f"friction at the arm's cam contact needs the rigid contact law, not "
                             f"{follower.contact!r}")
    _, relative = arm_tables(follower.geometry, follower.samples)
    if np.min(relative) <= 0.0:   # the slip's sign of a knife edge, and the model's, assume V > 0
        worst = float(rocking_table(follower.geometry, follower.samples).theta[int(np.argmin(relative))])
        raise GeometryError(f"at cam angle {math.degrees(worst):.3f} deg the roller centre stops or runs back "
                            "along the cam (V <= 0 in eq. F4): friction is not modelled there")
    margin, angle = arm_jamming_margin(follower, friction.kinetic)
    if margin <= 0.0:
        raise GeometryError(f"friction.kinetic = {friction.kinetic}: the arm jams at cam angle "
                            f"{math.degrees(angle):.3f} deg, where cos(phi) - mu_k |sin(phi)| = {margin:.3g} (eq. F3 "
                            "of the normal force); lower the friction or the pressure angle")


def _parameters(follower, friction, speed, phase):
    """The sliding follower's parameter vector of the arm (module docstring)."""
    geometry = follower.geometry
    table = rocking_table(geometry, follower.samples)
    translating = TranslatingFollower(table.profile, mass=follower.inertia, stiffness=follower.stiffness,
                                      preload=follower.preload, damping=follower.damping,
                                      restitution=follower.restitution, capture_velocity=follower.capture_velocity,
                                      citation=follower.citation)
    phi, relative = arm_tables(geometry, follower.samples)
    arm = (geometry.arm_length, spline_table(table.theta, phi), spline_table(table.theta, relative))
    return model.pack(translating.pack(float(speed), float(phase)), friction.static, friction.kinetic,
                      friction.roller_inertia, arm=arm), table


def _initial_state(follower, table, p, initial_state, roller_speed):
    """``(x [rad], x_dot [rad/s], omega_r [rad/s], Q [J])``: by default on the cam, moving
    with it and rolling (or spinning at ``roller_speed`` [rad/s])."""
    _, s, sd, _, _ = base.cam(0.0, p)
    rolling = model.rolling_spin(0.0, p) if follower.geometry.roller_radius > 0.0 else 0.0
    if roller_speed is not None:
        if not math.isfinite(limits.check_number("roller_speed", roller_speed, "rad/s")):
            raise ParameterError(f"roller_speed must be finite, got {roller_speed!r} rad/s")
        if follower.geometry.roller_radius == 0.0 and roller_speed != 0.0:
            raise ParameterError("roller_speed: a knife edge has no roller to spin")
        rolling = float(roller_speed)
    if initial_state is None:
        return np.array([s, sd, rolling, 0.0])
    y0 = np.asarray(initial_state, dtype=float).reshape(-1)
    if y0.shape not in ((2,), (3,)) or not np.all(np.isfinite(y0)):
        raise ParameterError(f"initial_state must be two or three finite numbers (psi [rad], psi_dot [rad/s], "
                             f"roller speed [rad/s]), got {initial_state!r}")
    sigma = follower.geometry.lift_direction
    x = sigma * (y0[0] - table.rest_angle)
    if x < s - 1e-12 * max(1.0, abs(x)):
        raise ParameterError(f"the arm starts inside the cam (lift angle {x} rad below the contact's {s} rad); "
                             "a rigid contact allows no penetration")
    return np.array([x, sigma * y0[1], y0[2] if y0.size == 3 else rolling, 0.0])


def simulate_rocking_friction(follower, friction, speed, duration, sample_rate=10e3, phase=0.0,
                              initial_state=None, roller_speed=None, rtol=1e-10, atol=1e-12, max_step=None,
                              max_events=None, max_steps=50_000_000) -> xr.Dataset:
    """Simulate a rocking arm with Coulomb friction at its cam contact (rigid law).

    Parameters
    ----------
    follower : RockingFollower
        The arm and its cam, with the rigid contact law.
    friction : FollowerFriction
        The coefficients mu_s, mu_k [-] and the roller's spin inertia J_r [kg m^2].
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
        ``(psi [rad], psi_dot [rad/s])`` or ``(psi, psi_dot, roller speed [rad/s])``;
        default on the cam, moving with it, the roller rolling.
    roller_speed : float, optional
        The roller's spin [rad/s] at the start where ``initial_state`` gives none
        (default: rolling).
    rtol, atol : float
        Local error tolerances, relative [-] and absolute [rad, rad/s].
    max_step, max_events, max_steps
        As :func:`camdyn.simulation.translating.simulate_translating`.

    Returns
    -------
    xarray.Dataset
        Over ``time``: ``psi``, ``psi_dot``, ``lift_angle``, ``contact_angle``, ``gap``
        [rad], ``pressure_angle`` [rad], ``contact_moment`` M [N m], ``contact_force`` N
        [N], ``friction_force`` F [N] (along the tangent), ``slip_velocity`` u [m/s],
        ``roller_speed`` omega_r [rad/s], ``friction_heat`` Q [J], ``pivot_force_x``,
        ``pivot_force_y`` [N] (the pivot's reaction on a balanced arm), ``in_contact``,
        ``rolling``; over ``event``: ``event_time`` [s], ``event_kind`` (``impact``,
        ``capture``, ``graze``, ``separation``, ``rolling``, ``reversal``, ``slip``) and
        ``event_velocity`` [rad/s].
    """
    check_arm_friction(follower, friction)
    speed = angular_speed(speed)   # omega [rad/s]
    check_run_arguments(speed, duration, sample_rate, rtol, atol)
    if not math.isfinite(limits.check_number("phase", phase, "rad")):
        raise ParameterError(f"phase must be finite, got {phase!r} rad")
    period = 2.0 * math.pi / speed
    n_out = limits.check_sampling(sample_rate, period, duration)
    limits.check_memory(limits.result_bytes(n_out, 18), "the simulation's result")
    p, table = _parameters(follower, friction, speed, phase)
    y0 = _initial_state(follower, table, p, initial_state, roller_speed)
    t_out, y, modes, events, counters, elapsed = run_follower(
        systems.SLIDING_FOLLOWER, p, y0, duration, sample_rate, n_out, period, rtol, atol, max_step, max_events,
        max_steps)
    ds = _dataset(follower, table, p, t_out, y, modes, events)
    geometry = follower.geometry
    ds.attrs.update({"title": "camdyn rocking arm with friction", "citation": follower.citation,
                     "speed_rad_s": float(speed), "phase_rad": float(phase), "inertia_kg_m2": follower.inertia,
                     "stiffness_N_m_per_rad": follower.stiffness, "preload_N_m": follower.preload,
                     "damping_N_m_s_per_rad": follower.damping, "restitution": follower.restitution,
                     "capture_velocity_rad_per_s": follower.capture_velocity, "contact_law": follower.contact,
                     "pivot_x_m": geometry.pivot_x, "pivot_y_m": geometry.pivot_y,
                     "arm_length_m": geometry.arm_length, "roller_radius_m": geometry.roller_radius,
                     "lift_direction": geometry.lift_direction, "rest_angle_rad": table.rest_angle,
                     "table_samples": follower.samples, "static_friction": friction.static,
                     "kinetic_friction": friction.kinetic, "roller_inertia_kg_m2": friction.roller_inertia,
                     "rtol": rtol, "atol": atol, "elapsed_s": elapsed,
                     "status": driver.STATUS_MESSAGES[int(counters[driver.COUNT_STATUS])]})
    for i, name in enumerate(driver.COUNTER_NAMES):
        ds.attrs[f"solver_{name}"] = int(counters[i])
    return ds


def _samples(follower, table, p, t, y, modes):
    """Per sample, the columns of :data:`SERIES`: the arm's state and contact angle, the
    pressure angle, the moment, forces, slip, spin and heat, and the pivot's reaction."""
    sigma = follower.geometry.lift_direction
    columns = np.zeros((t.size, len(SERIES)))
    for i, ti in enumerate(t):
        x, v = base.follower_state(ti, y[i], modes[i], p)
        s = base.cam(ti, p)[1]
        sin, cos, _, _, line = model.geometry(ti, p)
        phi = math.atan2(sin, cos)
        spin = y[i, 2]
        if model.in_contact(modes[i], p):
            slip = modes[i, model.SLIP]
            normal, tangential, _ = model.forces(ti, slip, p)
            if slip == 0.0 and follower.geometry.roller_radius > 0.0:
                spin = model.rolling_spin(ti, p)
            angle = table.rest_angle + sigma * (s + 0.5 * math.pi) + phi        # of n: m turned by phi
            c, d = math.cos(angle), math.sin(angle)
            force = (normal * c + tangential * d, normal * d - tangential * c)   # N n + F t, t = (n_y, -n_x)
            columns[i, 4:8] = line * follower.geometry.arm_length, normal, tangential, model.slip_velocity(ti, spin, p)
            columns[i, 10:12] = -force[0], -force[1]
        columns[i, :4] = x, v, s, phi
        columns[i, 8:10] = spin, y[i, 3]
    return columns


#: The sampled series: name, unit, meaning (the columns of :func:`_samples`).
SERIES = (("lift_angle", "rad", "arm angle from rest, in the lift sense"),
          ("lift_rate", "rad/s", "lift angle rate"),
          ("contact_angle", "rad", "lift angle of contact with the cam"),
          ("pressure_angle", "rad", "pressure angle of the contact"),
          ("contact_moment", "N*m", "moment of the cam on the arm about the pivot"),
          ("contact_force", "N", "normal force N of the cam on the roller"),
          ("friction_force", "N", "friction F on the roller along the contact tangent"),
          ("slip_velocity", "m/s", "slip velocity u of the roller on the cam"),
          ("roller_speed", "rad/s", "roller spin omega_r"),
          ("friction_heat", "J", "heat of friction since the start"),
          ("pivot_force_x", "N", "pivot reaction on a balanced arm, x"),
          ("pivot_force_y", "N", "pivot reaction on a balanced arm, y"))


def _dataset(follower, table, p, t, y, modes, events):
    """The run's Dataset in the arm's terms."""
    sigma = follower.geometry.lift_direction
    c = _samples(follower, table, p, t, y, modes)
    data = {name: (("time",), c[:, i], {"units": unit, "long_name": long}) for i, (name, unit, long)
            in enumerate(SERIES)}
    data.update({
        "psi": (("time",), table.rest_angle + sigma * c[:, 0], {"units": "rad", "long_name": "arm angle"}),
        "psi_dot": (("time",), sigma * c[:, 1], {"units": "rad/s", "long_name": "arm angular velocity"}),
    })
    return friction_dataset(p, t, modes, events, data, c[:, 0] - c[:, 2],
                            {"units": "rad", "long_name": "angular gap to the cam"},
                            {"units": "rad/s", "long_name": "relative angular velocity x_dot - s_dot before the event"})
