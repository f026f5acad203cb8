"""The Hertz contact law of the translating follower, against values from outside camdyn:
event-driven SciPy solutions with their own force laws (the lift, the cam's curvature,
the Hertz point force with Hunt-Crossley damping and the line force with a dashpot written
out here), the energy of undamped bounces on a dwell
with the Hertz potentials (2/5) K delta^2.5 and (1/2) K delta^2, the rigid limit (growing
moduli, the Hunt-Crossley law tuned here to restitute e = 0.8, converging to Newton's
e = 0.8), and the refusals of geometries and keys that make no sense."""

import contextlib
import dataclasses
import io
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from camdyn.cli.app import main
from camdyn.errors import GeometryError, ParameterError, UnknownKeyError
from camdyn.model.profiles import rise_return_profile
from camdyn.params.profiles import read_translating, spec_from_table
from camdyn.simulation.translating import (
    HertzContact,
    TranslatingFollower,
    alzate_rig,
    follower_from_spec,
    simulate_translating,
)

MASS, SPRING, PRELOAD = 0.5, 2000.0, 20.0          # [kg], [N/m], [N]
BASE, RISE = 0.04, 0.01                            # base radius, lift [m]
TIP = 2e-3                                         # knife-edge tip radius [m]
MODULUS, POISSON = 2.1e9, 0.3                      # both bodies [Pa], [-]
E_STAR = MODULUS / (2.0 * (1.0 - POISSON ** 2))    # Johnson 1985, eq 4.22, equal bodies [Pa]
SPAN = 2.0 * math.pi / 3.0                         # rise and return spans [rad]


def cycloidal(theta):
    """Lift ``(s, s', s'')`` [m, m/rad, m/rad^2] of the cam of the oracle test: cycloidal
    rise of RISE over 120 deg, dwell 60 deg, cycloidal return over 120 deg, dwell 60 deg
    (s = h (u - sin(2 pi u) / (2 pi)), Norton 2009)."""
    theta = theta % (2.0 * math.pi)
    if theta < SPAN:
        u, sign, start = theta / SPAN, 1.0, 0.0
    elif theta < math.pi:
        return RISE, 0.0, 0.0
    elif theta < math.pi + SPAN:
        u, sign, start = (theta - math.pi) / SPAN, -1.0, RISE
    else:
        return 0.0, 0.0, 0.0
    s = start + sign * RISE * (u - math.sin(2.0 * math.pi * u) / (2.0 * math.pi))
    s1 = sign * RISE / SPAN * (1.0 - math.cos(2.0 * math.pi * u))
    s2 = sign * RISE / SPAN ** 2 * 2.0 * math.pi * math.sin(2.0 * math.pi * u)
    return s, s1, s2


def cam_curvature(theta):
    """Curvature [1/m] of the in-line knife-edge cam r(theta) = BASE + s, a polar curve:
    ``(r^2 + 2 r'^2 - r r'') / (r^2 + r'^2)^1.5``."""
    s, s1, s2 = cycloidal(theta)
    r = BASE + s
    return (r * r + 2.0 * s1 * s1 - r * s2) / (r * r + s1 * s1) ** 1.5


def knife_follower(damping_law="hunt-crossley", restitution=0.8, scale=1.0, profile=None):
    profile = profile or rise_return_profile([("cycloidal", SPAN, RISE), ("dwell", math.pi - SPAN, 0.0),
                                              ("cycloidal", SPAN, -RISE), ("dwell", math.pi - SPAN, 0.0)],
                                             BASE, follower="knife")
    law = HertzContact(cam_modulus=MODULUS * scale, follower_modulus=MODULUS * scale, cam_poisson=POISSON,
                       follower_poisson=POISSON, tip_radius=TIP, damping_law=damping_law, restitution=restitution)
    return TranslatingFollower(profile, MASS, SPRING, PRELOAD, contact="hertz", hertz=law)


WIDTH, VISCOUS = 0.01, 50.0                         # line contact: width [m], damping c [N s/m]


def oracle(speed, duration, y0, face, times):
    """An event-driven SciPy solution of eq. (1) of the model with a Hertz contact written
    out here: for the rounded knife edge, point contact with Hunt-Crossley damping, ``F = K
    delta^1.5 (1 + chi delta' / v0)``, ``K = (4/3) E* sqrt(rho_e)``, ``1/rho_e = kappa_cam +
    1/r_tip``, ``chi = 3 (1 - e) / 2`` with e = 0.8 (Hunt and Crossley 1975), v0 the
    approach velocity at the onset; for the flat face, line contact with a dashpot, ``F =
    (pi/4) E* l delta + c delta'`` (Johnson 1985). Returns the positions at ``times`` and
    the event times."""
    chi = 1.5 * (1.0 - 0.8)

    def field(t, y, contact, approach):
        theta = speed * t
        force = 0.0
        if contact:
            s, s1, _ = cycloidal(theta)
            delta, rate = s - y[0], speed * s1 - y[1]
            if face == "flat":
                force = math.pi / 4.0 * E_STAR * WIDTH * delta + VISCOUS * rate
            else:
                stiffness = 4.0 / 3.0 * E_STAR * math.sqrt(1.0 / (cam_curvature(theta) + 1.0 / TIP))
                force = stiffness * math.copysign(abs(delta) ** 1.5, delta) * (1.0 + chi * rate / approach)
        return [y[1], (force - PRELOAD - SPRING * y[0]) / MASS]

    def gap(t, y, *args):
        return y[0] - cycloidal(speed * t)[0]

    t, y, contact, approach = 0.0, np.array(y0, float), False, 1.0
    pieces, events = [], []
    while t < duration:
        gap.terminal, gap.direction = True, (1.0 if contact else -1.0)
        sol = solve_ivp(field, (t, duration), y, method="DOP853", rtol=1e-12, atol=1e-15, events=gap,
                        dense_output=True, args=(contact, approach), max_step=1e-3)
        pieces.append((t, sol.t[-1], sol.sol))
        t, y = sol.t[-1], sol.y[:, -1]
        if sol.status == 1:
            events.append(t)
            contact = not contact
            approach = speed * cycloidal(speed * t)[1] - y[1]
    x = np.empty(len(times))
    for i, ti in enumerate(times):
        x[i] = next(p for a, b, p in pieces if a <= ti <= b)(ti)[0]
    return x, np.array(events)


@pytest.mark.parametrize("face", ["knife", "flat"])
def test_agrees_with_an_independent_scipy_solution(face):
    speed, duration = 90.0, 3 * 2 * math.pi / 90.0       # [rad/s], three revolutions [s]
    y0 = (0.003, 0.0)                                    # dropped from 3 mm above the dwell
    if face == "knife":
        follower = knife_follower()
    else:
        law = HertzContact(cam_modulus=MODULUS, follower_modulus=MODULUS, width=WIDTH, damping_law="viscous",
                           damping=VISCOUS)
        follower = dataclasses.replace(knife_follower(), profile=rise_return_profile(
            [("cycloidal", SPAN, RISE), ("dwell", math.pi - SPAN, 0.0), ("cycloidal", SPAN, -RISE),
             ("dwell", math.pi - SPAN, 0.0)], BASE, follower="flat"), hertz=law)
    ds = simulate_translating(follower, speed / (2 * math.pi), duration, sample_rate=5000.0, initial_state=y0,
                              rtol=1e-12,
                              atol=1e-15)
    onsets = ds.event_time.values
    assert np.count_nonzero(ds.event_kind.values == "contact onset") >= 6   # a run with impacts
    x, events = oracle(speed, duration, y0, face, ds.time.values)
    assert events.size == onsets.size
    # both solve the same equations to rtol 1e-12 (measured: knife 1.2e-11 s, 1.5e-11 m; flat 2e-12 s, 8e-12 m)
    assert np.max(np.abs(onsets - events)) < 1e-9
    assert np.max(np.abs(ds.x.values - x)) < 1e-9


def bounce_energy(follower, line_stiffness=None, point_stiffness=None):
    """Largest change [J] of the energy of undamped bounces on the dwell, and its scale."""
    ds = simulate_translating(follower, 0.5 / (2 * math.pi), 1.0, sample_rate=20000.0, phase=2.0,
                              initial_state=(0.002, 0.0),
                              rtol=1e-12, atol=1e-15)
    assert np.all(ds.lift.values == 0.0)   # on the dwell throughout: the cam does no work
    x, v = ds.x.values, ds.x_dot.values
    delta = np.maximum(-x, 0.0)
    if line_stiffness is not None:
        contact = 0.5 * line_stiffness * delta ** 2               # (1/2) K delta^2
    else:
        contact = 0.4 * point_stiffness * delta ** 2.5            # (2/5) K delta^2.5 (Johnson 1985)
    energy = 0.5 * MASS * v ** 2 + PRELOAD * x + 0.5 * SPRING * x ** 2 + contact
    assert np.count_nonzero(ds.event_kind.values == "contact onset") >= 10
    return np.max(np.abs(energy - energy[0])), energy[0]


def dwell_profile(face):
    return rise_return_profile([("cycloidal", math.pi / 6, 1e-3), ("cycloidal", math.pi / 6, -1e-3),
                                ("dwell", 5 * math.pi / 3, 0.0)], BASE, follower=face)


def test_undamped_bounces_keep_their_energy_line_contact():
    width = 0.01
    law = HertzContact(cam_modulus=MODULUS, follower_modulus=MODULUS, width=width)
    follower = TranslatingFollower(dwell_profile("flat"), MASS, SPRING, PRELOAD, contact="hertz", hertz=law)
    change, scale = bounce_energy(follower, line_stiffness=math.pi / 4 * E_STAR * width)   # Johnson eq 4.29
    assert change < 1e-8 * scale   # measured 1.3e-11 of the energy


def test_undamped_bounces_keep_their_energy_point_contact():
    follower = knife_follower("none", profile=dwell_profile("knife"))
    rho = 1.0 / (1.0 / BASE + 1.0 / TIP)   # the base circle and the rounded tip
    change, scale = bounce_energy(follower, point_stiffness=4.0 / 3.0 * E_STAR * math.sqrt(rho))
    assert change < 1e-8 * scale   # measured 1.1e-10 of the energy


def hunt_crossley_restitution(chi):
    """Restitution of u'' = -u^1.5 (1 + chi u'), u(0) = 0, u'(0) = 1: the Hunt-Crossley
    impact of a free mass scaled to unit stiffness, mass and approach velocity."""
    def field(t, u):
        return [u[1], -math.copysign(abs(u[0]) ** 1.5, u[0]) * (1.0 + chi * u[1])]

    def back(t, u):
        return u[0]
    back.terminal, back.direction = True, -1.0
    sol = solve_ivp(field, (0.0, 50.0), [0.0, 1.0], method="DOP853", rtol=1e-12, atol=1e-14, events=back,
                    first_step=1e-6)
    return -sol.y_events[0][0][1]


def test_rigid_limit_converges_to_newton_restitution():
    """The Alzate rig with a rounded knife edge (5 mm), dropped 5 mm onto the base dwell:
    moduli x1 ... x1000 (the last is steel on steel) with the Hunt-Crossley law whose chi
    restitutes 0.8 in a free impact, against the rigid law with e = 0.8."""
    chi = brentq(lambda c: hunt_crossley_restitution(c) - 0.8, 0.05, 1.0, xtol=1e-13)
    tuned = 1.0 - chi / 1.5       # the law's input e for that chi (chi = 3 (1 - e) / 2)
    rig, speed, y0 = alzate_rig(), 358 * 2 * math.pi / 60, (0.005, 0.0)
    rigid = simulate_translating(rig, speed / (2 * math.pi), 0.05, initial_state=y0)
    impacts = rigid.event_kind.values == "impact"
    times, approach = rigid.event_time.values[impacts][:3], rigid.event_velocity.values[impacts][:3]
    assert times.size == 3
    errors = []
    for scale in (1.0, 10.0, 100.0, 1000.0):
        law = HertzContact(cam_modulus=2.1e8 * scale, follower_modulus=2.1e8 * scale, tip_radius=5e-3,
                           damping_law="hunt-crossley", restitution=tuned)
        ds = simulate_translating(dataclasses.replace(rig, contact="hertz", hertz=law), speed / (2 * math.pi), 0.05,
                                  initial_state=y0)
        kinds = ds.event_kind.values
        onsets = kinds == "contact onset"
        time_error = np.max(np.abs(ds.event_time.values[onsets][:3] - times))
        velocity_error = np.max(np.abs(ds.event_velocity.values[onsets][:3] - approach))
        rebound = ds.event_velocity.values[kinds == "contact end"][:2]
        rebound_error = np.max(np.abs(rebound + 0.8 * approach[:2]))   # Newton: -e times the approach
        errors.append((time_error, velocity_error, rebound_error))
    errors = np.array(errors)
    assert np.all(np.diff(errors, axis=0) < 0.0)              # every error falls at every rung
    # contact lasts ~ K^-0.4 (Hertz, n = 3/2): the errors fall ~2.5 times per decade
    rates = np.log10(errors[-2] / errors[-1])
    assert np.all((0.3 < rates) & (rates < 0.6)), rates
    # steel on steel (the last rung): contact ~0.2 ms; impact times within 0.5 ms and
    # velocities within 1.5 % of the ~0.9 m/s approach (measured 4.2e-4 s, 1.1e-2 m/s)
    assert errors[-1, 0] < 5e-4 and errors[-1, 1] < 1.5e-2 and errors[-1, 2] < 1.5e-2


def run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


HERTZ_TOML = """
[follower]
kind = "translating"
face = "knife"
mass = "1.221 kg"
[spring]
stiffness = "1430.8 N/m"
preload = "143.08 N"
[contact]
law = "hertz"
tip_radius = "5 mm"
damping_law = "hunt-crossley"
restitution = 0.8
cam_modulus = "210 GPa"
follower_modulus = "210 GPa"
[profile]
kind = "eccentric-circle"
radius = "40 mm"
eccentricity = "10 mm"
[motion]
speed = "300 rpm"
"""


def test_cli_simulates_a_hertz_configuration(tmp_path):
    path = tmp_path / "hertz.toml"
    path.write_text(HERTZ_TOML)
    status, out, err = run("simulate", path, "--revolutions", "2", "--sample-rate", "2kHz")
    assert status == 0, err
    follower = follower_from_spec(read_translating(path))
    assert follower.contact == "hertz" and follower.hertz.tip_radius == 5e-3


def flat(**contact):
    table = {"follower.kind": "translating", "follower.face": "knife", "follower.mass": "1 kg",
             "spring.stiffness": "1000 N/m", "spring.preload": "10 N", "profile.kind": "eccentric-circle",
             "profile.radius": "40 mm", "profile.eccentricity": "5 mm"}
    table.update(contact)
    return follower_from_spec(spec_from_table(table))


@pytest.mark.parametrize("keys, error, named", [
    ({"contact.law": "hertz"}, ParameterError, "contact.tip_radius"),               # a sharp knife edge
    ({"contact.law": "hertz", "contact.tip_radius": "1 mm", "contact.geometry": "line"}, ParameterError,
     "contact.geometry"),
    ({"contact.law": "hertz", "follower.face": "flat"}, ParameterError, "contact.width"),
    ({"contact.law": "hertz", "follower.face": "flat", "contact.width": "1 cm", "contact.geometry": "point"},
     ParameterError, "contact.geometry"),
    ({"contact.law": "hertz", "contact.tip_radius": "1 mm", "contact.damping_law": "power"}, ParameterError,
     "contact.damping_law"),
    ({"contact.law": "hertz", "contact.tip_radius": "1 mm", "contact.cam_poisson": 0.6}, ParameterError,
     "contact.cam_poisson"),
    ({"contact.law": "hertz", "contact.tip_radius": "1 mm", "contact.stiffness": "1e6 N/m"}, UnknownKeyError,
     "contact.stiffness"),
    ({"contact.law": "rigid", "contact.width": "1 cm"}, UnknownKeyError, "contact.width"),
    ({"contact.law": "hertz", "contact.tip_radius": "1 mm", "contact.cam_modulus": "210 N"}, Exception,
     "contact.cam_modulus"),
])
def test_refusals_name_the_key(keys, error, named):
    with pytest.raises(error, match=named.replace(".", r"\.")):
        flat(**keys)


def test_a_tip_that_does_not_fit_a_concave_cam_is_refused():
    # a steep cycloidal rise on a small knife-edge cam is concave where it bends back
    profile = rise_return_profile([("cycloidal", math.pi / 3, 0.03), ("cycloidal", math.pi / 3, -0.03),
                                   ("dwell", 4 * math.pi / 3, 0.0)], 0.02, follower="knife")
    law = HertzContact(tip_radius=0.05)
    with pytest.raises(GeometryError, match="concave"):
        TranslatingFollower(profile, MASS, SPRING, PRELOAD, contact="hertz", hertz=law)
    TranslatingFollower(profile, MASS, SPRING, PRELOAD, contact="hertz", hertz=HertzContact(tip_radius=1e-4))


@pytest.mark.parametrize("damping_law", ["none", "viscous"])
def test_the_variational_system_matches_finite_differences(damping_law):
    """The state-transition matrix over a landing and a lift-off (the Jacobian of the Hertz
    force by central differences, the saltation at both events) against central
    differences of whole runs."""
    from camdyn.integrator import driver
    from camdyn.systems import registry as systems

    law = HertzContact(cam_modulus=2.1e8, follower_modulus=2.1e8, tip_radius=5e-3, damping_law=damping_law,
                       damping=20.0)
    rig = dataclasses.replace(alzate_rig(), contact="hertz", hertz=law)
    p = rig.pack(358 * 2 * math.pi / 60, math.pi / 2)
    y0, t_end = np.array([0.02, 0.0]), 0.08

    def run(system, y):
        out, _, events, counters = driver.integrate(system, p, y, 0.0, t_end, np.array([t_end]), 1e-12, 1e-14,
                                                    1e-3, driver.METHOD_AUTO, 10 ** 6, 1000, False, math.inf)
        assert counters[driver.COUNT_STATUS] == driver.STATUS_OK
        return out[-1], events
    big = run(systems.VARIATIONAL + systems.TRANSLATING_FOLLOWER, np.r_[y0, 1.0, 0.0, 0.0, 1.0])[0]
    assert run(systems.TRANSLATING_FOLLOWER, y0)[1].shape[0] >= 2   # it lands and leaves
    steps = (1e-6, 1e-5)
    fd = np.column_stack([(run(systems.TRANSLATING_FOLLOWER, y0 + steps[j] * np.eye(2)[j])[0]
                           - run(systems.TRANSLATING_FOLLOWER, y0 - steps[j] * np.eye(2)[j])[0]) / (2 * steps[j])
                          for j in range(2)])
    # measured 3e-8 relative (the differences' own truncation at steps 1e-6, 1e-5)
    np.testing.assert_allclose(big[2:].reshape(2, 2), fd, rtol=1e-6, atol=1e-6)
