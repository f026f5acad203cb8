"""The compliant contacts of the rocking roller (:mod:`camdyn.simulation.rocking_roller`),
against values computed here from outside the code:

- an event-driven SciPy solution in the arm angle with its own geometry (the eccentric
  circle's closed form of test_rocking_roller.py) and its own contact moments:
  a torsional spring-dashpot, and Hertz contact at the exact lever of every cam angle:
  the normal penetration ``L_n (psi_c - psi)`` with the lever ``L_n`` and its slope in
  closed form (circle-circle geometry, below), the normal force of line contact ``(pi/4)
  E* l delta_n`` or point contact ``(4/3) E* sqrt(rho_e) delta_n^1.5`` (``1/rho_e = 1/R +
  1/r_f``, the cam a circle of radius R; K. L. Johnson, *Contact Mechanics*, 1985, eqs.
  4.22, 4.23, 5.37) with Hunt and Crossley's damping ``chi = 3 (1 - e) / 2`` (Hunt and
  Crossley 1975, doi:10.1115/1.3423596) or a dashpot ``c delta_n'``, and the moment
  ``L_n N``;
- a translating follower given a lever table of 1 m runs as without one, bit for bit;
- the keys of a configuration file and ``camdyn simulate`` on a compliant one;
- the rigid limit: a stiffening spring-dashpot matched to Newton's restitution lands
  where the rigid run impacts, the error falling at every decade;
- refusals before any work.
"""

import contextlib
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from test_rocking_roller import (
    ARM,
    CYCLOIDAL,
    INERTIA,
    PIVOT,
    PRELOAD,
    RADIUS,
    ROLLER,
    RUNOUT,
    STIFFNESS,
    circle_geometry,
    closed_form,
)

from camdyn.cli.app import main
from camdyn.errors import ParameterError, UnknownKeyError
from camdyn.io.rocking_config import load_rocking
from camdyn.model.lift_laws import CUBIC
from camdyn.model.profiles import Profile, eccentric_circle, rise_return_profile
from camdyn.model.rocking_roller import RockingGeometry, contact_configuration, surface_curvature
from camdyn.simulation.rocking_roller import RockingFollower, rocking_liftoff_speed, rocking_table, simulate_rocking
from camdyn.simulation.translating import TranslatingFollower, simulate_translating
from camdyn.simulation.translating_contact import HertzContact

#: Soft materials [Pa] and a roller width [m], so that a contact lasts about a millisecond.
MODULUS, POISSON, WIDTH = 2e8, 0.3, 5e-3
RESTITUTION = 0.5
TIP = 2e-3      # the knife edge's tip radius [m]
DROP = 0.01     # the arm starts this far [rad] above the cam, at rest
#: kind: (face, Hertz geometry, damping law, dashpot c [N s/m] of the viscous law) of the Hertz runs.
HERTZ_KINDS = {"hertz": ("roller", "line", "hunt-crossley", 0.0), "hertz-viscous": ("roller", "line", "viscous", 50.0),
               "hertz-point": ("roller", "point", "hunt-crossley", 0.0),
               "knife-point": ("knife", "point", "viscous", 2.0)}


def normal_lever(theta, radius=RADIUS + ROLLER):
    """The lever ``L_n`` [m] of the contact normal about the pivot and its slope
    ``dL_n/dtheta`` [m/rad] on the eccentric circle (lifted counter-clockwise). With the
    circle's centre ``O`` and ``d = O - P``, the roller centre ``C = P + L e(psi)`` moves
    along ``e'(psi)``, the normal is ``n = (C - O) / radius``, so ``L_n = L e'.n = -L
    e'.d / radius`` (``e'.e = 0``), and ``dL_n/dtheta = -L (e'.d' - psi' e.d) / radius``."""
    psi, psi1, _, phi = closed_form(theta, radius=radius)
    c, s = math.cos(theta), math.sin(theta)
    d = np.array([-RUNOUT * s, RUNOUT * c]) - np.asarray(PIVOT)
    d1 = np.array([-RUNOUT * c, -RUNOUT * s])
    e, e1 = np.array([math.cos(psi), math.sin(psi)]), np.array([-math.sin(psi), math.cos(psi)])
    lever = -ARM * (e1 @ d) / radius
    assert abs(lever - ARM * math.cos(phi)) < 1e-15   # the lever is L cos(phi)
    return lever, -ARM * (e1 @ d1 - psi1 * (e @ d)) / radius


def _normal_force(kind):
    """The normal force [N] of the Hertz law of ``kind`` at the normal penetration [m], its
    rate [m/s] and the normal approach velocity of the onset [m/s]."""
    face, shape, law, dashpot = HERTZ_KINDS[kind]
    star = MODULUS / (2 * (1 - POISSON ** 2))             # 1/E* = 2 (1 - nu^2) / Y (Johnson, eq. 4.22)
    if shape == "line":
        k, power = math.pi / 4 * star * WIDTH, 1.0          # (pi/4) E* l
    else:
        rho = 1 / (1 / RADIUS + 1 / (ROLLER if face == "roller" else TIP))
        k, power = 4 / 3 * star * math.sqrt(rho), 1.5       # (4/3) E* sqrt(rho_e)
    # a trial step past the separation (d < 0) takes the law's odd continuation d |d|^(power - 1)
    if law == "viscous":       # c on the roller
        return lambda d, dd, v: k * d * abs(d) ** (power - 1) + dashpot * dd
    return lambda d, dd, v: k * d * abs(d) ** (power - 1) * (1 + 1.5 * (1 - RESTITUTION) * dd / max(v, 1e-3))


def _moment_law(kind, w):
    """The contact moment [N m] as a function of the cam angle [rad], the penetration
    delta = psi_c - psi [rad], its rate [rad/s] and the normal approach velocity [m/s]."""
    if kind == "compliant":
        return lambda theta, d, dd, v: 2000.0 * d + 0.1 * dd
    force = _normal_force(kind)
    radius = RADIUS + (ROLLER if HERTZ_KINDS[kind][0] == "roller" else 0.0)

    def moment(theta, d, dd, v):
        lever, slope = normal_lever(theta, radius)
        return lever * force(lever * d, lever * dd + w * slope * d, v)   # M = L_n N(delta_n, delta_n')
    return moment


def _follower(kind):
    if kind == "compliant":
        return RockingFollower(circle_geometry(), INERTIA, STIFFNESS, PRELOAD, contact="compliant",
                               contact_stiffness=2000.0, contact_damping=0.1)
    face, shape, law, dashpot = HERTZ_KINDS[kind]
    geometry = circle_geometry() if face == "roller" else circle_geometry("flat", roller=0.0)
    materials = {"cam_modulus": MODULUS, "follower_modulus": MODULUS, "cam_poisson": POISSON,
                 "follower_poisson": POISSON, "geometry": shape, "damping_law": law}
    if shape == "line":
        materials["width"] = WIDTH
    if face == "knife":
        materials["tip_radius"] = TIP
    if law == "viscous":
        materials["damping"] = dashpot
    else:
        materials["restitution"] = RESTITUTION
    return RockingFollower(geometry, INERTIA, STIFFNESS, PRELOAD, contact="hertz", hertz=HertzContact(**materials))


def reference(kind, w, t_end, rest):
    """Event-driven SciPy solution: I psi'' = -M0 - k (psi - psi0) + M_c(theta, delta,
    delta', v_n) with the penetration delta = psi_c(w t) - psi while it is positive."""
    moment = _moment_law(kind, w)
    radius = RADIUS + (0.0 if kind == "knife-point" else ROLLER)

    def rates(t, y, contact, approach):
        psi, psi1, _, _ = closed_form(w * t, radius=radius)
        push = moment(w * t, psi - y[0], w * psi1 - y[1], approach) if contact else 0.0
        return [y[1], (-PRELOAD - STIFFNESS * (y[0] - rest) + push) / INERTIA]

    def gap(t, y, *args):
        return y[0] - closed_form(w * t, radius=radius)[0]
    gap.terminal = True
    start = np.array([closed_form(0.0, radius=radius)[0] + DROP, 0.0])
    t, y, contact, approach, events, pieces = 0.0, start, False, 0.0, [], []
    while t < t_end:
        gap.direction = 1 if contact else -1
        sol = solve_ivp(rates, (t, t_end), y, method="DOP853", rtol=1e-12, atol=1e-14, events=gap,
                        dense_output=True, args=(contact, approach), max_step=1e-4)
        pieces.append((t, sol.t[-1], sol.sol))
        t, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status != 1:
            break
        contact = not contact
        lever = normal_lever(w * t, radius)[0] if kind != "compliant" else 1.0
        approach = lever * (w * closed_form(w * t, radius=radius)[1] - y[1]) if contact else 0.0   # v_n
        events.append((t, "contact onset" if contact else "contact end"))
    return events, pieces


@pytest.mark.parametrize("kind", ["compliant", *HERTZ_KINDS])
def test_a_revolution_with_impacts_matches_an_independent_solution(kind):
    """The arm dropped onto the cam at 1.15 times the rigid lift-off speed: it bounces,
    settles, leaves the cam and lands again within the revolution. The compiled run (on
    the spline tables of psi_c, L_n and kappa_cam) against the reference: the same contact
    onsets and ends, within 1e-8 s (measured 1.5e-13 to 1.2e-12 s), and the arm angle
    within 1e-8 rad (measured 9e-14 to 5.5e-13 rad). On this rig ``L_n^2`` spreads 2.9 %
    about its mean over the revolution: the reference run with the constant rms lever
    instead differs by 6e-5 rad, and without the term ``omega L_n' delta`` of the
    penetration rate by 8e-7 rad (viscous line contact)."""
    follower = _follower(kind)
    w = 1.15 * rocking_liftoff_speed(follower)
    duration = 2 * math.pi / w
    radius = RADIUS + (0.0 if kind == "knife-point" else ROLLER)
    psi0 = closed_form(0.0, radius=radius)[0] + DROP
    ds = simulate_rocking(follower, w / (2 * math.pi), duration, sample_rate=4000, initial_state=(psi0, 0.0),
                          rtol=1e-12,
                          atol=1e-14)
    events, pieces = reference(kind, w, duration, ds.attrs["rest_angle_rad"])
    kinds = [k for _, k in events]
    assert list(ds.event_kind.values) == kinds
    assert kinds.count("contact onset") >= 3
    times = np.abs(ds.event_time.values - [t for t, _ in events])
    angles = []
    for t, psi in zip(ds.time.values, ds.psi.values):
        for t0, t1, sol in pieces:
            if t0 <= t <= t1:
                angles.append(abs(psi - sol(t)[0]))
                break
    print(f"{kind}: event times {times.max():.2e} s, arm angle {max(angles):.2e} rad")
    assert times.max() < 1e-8 and max(angles) < 1e-8


def test_a_unit_lever_leaves_the_translating_hertz_law_as_it_is():
    """A translating roller follower given a lever table of 1 m (slope 0) has the normal
    penetration of its own law and the moment equal to its force: the run is the same,
    bit for bit, as without the table (line contact, Hunt and Crossley's damping)."""
    profile = eccentric_circle(RADIUS, RUNOUT, follower="roller", roller_radius=ROLLER)
    law = HertzContact(cam_modulus=MODULUS, follower_modulus=MODULUS, width=WIDTH, damping_law="hunt-crossley",
                       restitution=RESTITUTION)
    # one cubic segment over the revolution: 1 + 0 t + 0 t^2 + 0 t^3 [m] (the table format of camdyn.model.profiles)
    unit = Profile(np.array([1.0, CUBIC, 0.0, 2 * math.pi, 1.0, 0.0, 0.0, 0.0, 0.0]), 1.0, "roller", ROLLER)
    runs = []
    for lever in (None, unit):
        follower = TranslatingFollower(profile, 0.02, 50.0, 0.5, contact="hertz", hertz=law, lever=lever)
        runs.append(simulate_translating(follower, 150.0 / (2 * math.pi), 0.1, sample_rate=2000,
                                         initial_state=(0.012, 0.0)))
    assert runs[0].event_time.size >= 2
    for name in ("x", "x_dot", "contact_force"):
        np.testing.assert_array_equal(runs[0][name].values, runs[1][name].values)


def _penalty_damping(stiffness, restitution=RESTITUTION):
    """c_c [N m s/rad] restituting e in one impact of the arm's inertia on k_c: the damped
    oscillator's half period gives e = exp(-zeta pi / sqrt(1 - zeta^2))."""
    log = math.log(restitution)
    return 2 * (-log / math.sqrt(math.pi ** 2 + log ** 2)) * math.sqrt(stiffness * INERTIA)


def test_the_stiffening_contact_converges_to_the_rigid_impacts():
    """Dropped onto the cam, the arm's first three landings (rigid: impacts; compliant:
    contact onsets) agree better at every decade of k_c; a contact lasts pi sqrt(I /
    k_c), so the error should fall about sqrt(10) times a decade (measured at k_c = 1e3 to
    1e6 N m/rad: 1.6e-3, 4.7e-4, 1.5e-4, 4.6e-5 s)."""
    geometry = circle_geometry()
    rigid = RockingFollower(geometry, INERTIA, STIFFNESS, PRELOAD, restitution=RESTITUTION)
    w = 0.5 * rocking_liftoff_speed(rigid)
    start = (closed_form(0.0)[0] + DROP, 0.0)
    options = {"sample_rate": 1000, "initial_state": start, "rtol": 1e-11, "atol": 1e-13}
    ds = simulate_rocking(rigid, w / (2 * math.pi), 0.05, **options)
    impacts = ds.event_time.values[ds.event_kind.values == "impact"][:3]
    assert impacts.size == 3
    errors = []
    for stiffness in (1e3, 1e4, 1e5, 1e6):
        arm = RockingFollower(geometry, INERTIA, STIFFNESS, PRELOAD, contact="compliant",
                              contact_stiffness=stiffness, contact_damping=_penalty_damping(stiffness))
        run = simulate_rocking(arm, w / (2 * math.pi), 0.05, **options)
        onsets = run.event_time.values[run.event_kind.values == "contact onset"][:3]
        errors.append(np.abs(onsets - impacts).max())
    assert all(a > b for a, b in zip(errors, errors[1:])), errors
    slopes = np.diff(np.log10(errors))   # per decade of k_c
    np.testing.assert_allclose(slopes, -0.5, atol=0.1)


HERTZ = HertzContact(width=WIDTH)


@pytest.mark.parametrize("change, match", [
    ({"contact": "soft"}, "contact must be one of"),
    ({"contact": "compliant"}, "positive contact_stiffness"),
    ({"contact": "compliant", "contact_stiffness": -1.0}, "must not be negative"),
    ({"contact_stiffness": 10.0}, "belong to the compliant law"),
    ({"hertz": HERTZ}, "the Hertz law's"),
    ({"contact": "hertz"}, "materials and width"),
    ({"contact": "hertz", "hertz": HertzContact()}, "contact.width"),
    ({"contact": "hertz", "hertz": HertzContact(width=WIDTH, tip_radius=1e-3)}, "tip_radius is for a knife edge"),
    ({"contact": "hertz", "hertz": HertzContact(geometry="point", tip_radius=1e-3)}, "tip_radius is for a knife"),
    ({"contact": "hertz", "hertz": HERTZ, "contact_damping": 1.0}, "belong to the compliant law"),
])
def test_bad_contacts_are_refused_when_built(change, match):
    with pytest.raises(ParameterError, match=match):
        RockingFollower(circle_geometry(), INERTIA, STIFFNESS, PRELOAD, **change)


@pytest.mark.parametrize("law, match", [
    (HertzContact(geometry="line", width=WIDTH, tip_radius=1e-3), "knife edge with a rounded tip makes point"),
    (HertzContact(), "a sharp knife edge has no Hertz stiffness"),
])
def test_a_knife_edge_takes_point_contact_through_its_tip_only(law, match):
    with pytest.raises(ParameterError, match=match):
        RockingFollower(circle_geometry("knife", roller=0.0), INERTIA, STIFFNESS, PRELOAD, contact="hertz",
                        hertz=law)


def test_the_arm_point_contact_needs_the_cam_curvature():
    """The translating model refuses the arm's point contact without the curvature table
    (the lift table's own curvature would be the contact angle's, not the cam's)."""
    follower = _follower("hertz-point")
    with pytest.raises(ParameterError, match="curvature"):
        TranslatingFollower(eccentric_circle(RADIUS, RUNOUT, follower="roller", roller_radius=ROLLER), 1.0, 1.0,
                            1.0, contact="hertz", hertz=follower.hertz, lever=Profile(np.array([1.0, CUBIC, 0.0,
                                                                                               2 * math.pi, 1.0,
                                                                                               0.0, 0.0, 0.0, 0.0]),
                                                                                     1.0, "roller", ROLLER))


EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "profiles" / "rocking_roller.toml"


def test_the_contact_keys_of_a_configuration_build_the_follower():
    follower, _ = load_rocking(EXAMPLE, {"contact.law": "hertz", "contact.width": "6 mm",
                                         "contact.cam_modulus": "200 GPa", "contact.damping_law": "hunt-crossley",
                                         "contact.restitution": "0.7"})
    assert follower.contact == "hertz" and follower.hertz == HertzContact(
        cam_modulus=200e9, width=6e-3, damping_law="hunt-crossley", restitution=0.7)
    follower, _ = load_rocking(EXAMPLE, {"contact.law": "hertz", "contact.geometry": "point"})
    assert follower.hertz == HertzContact(geometry="point", restitution=0.5)   # a crowned roller: r_f = r_r
    follower, _ = load_rocking(EXAMPLE, {"contact.law": "compliant", "contact.stiffness": "3e4 N*m",
                                         "contact.damping": "0.2 N*m*s"})
    assert (follower.contact, follower.contact_stiffness, follower.contact_damping) == ("compliant", 3e4, 0.2)


@pytest.mark.parametrize("change, error, match", [
    ({"contact.law": "soft"}, ParameterError, "contact.law must be one of"),
    ({"contact.law": "compliant"}, ParameterError, "contact.stiffness"),
    ({"contact.law": "compliant", "contact.stiffness": "-1 N*m"}, ParameterError, "contact.stiffness"),
    ({"contact.stiffness": "1 N*m"}, UnknownKeyError, "not a key of the 'rigid' contact law"),
    ({"contact.law": "hertz", "contact.stiffness": "1 N*m"}, UnknownKeyError, "not a key of the 'hertz'"),
    ({"contact.law": "hertz"}, ParameterError, "contact.width"),
    ({"contact.law": "hertz", "contact.width": "5 mm", "contact.tip_radius": "1 mm"}, ParameterError,
     "tip_radius is for a knife edge"),
    ({"contact.law": "hertz", "contact.tip_radius": "-1 mm", "contact.geometry": "point"}, ParameterError,
     "contact.tip_radius"),
    ({"contact.law": "hertz", "contact.geometry": "plane"}, ParameterError, "contact.geometry"),
    ({"contact.law": "hertz", "contact.width": "5 mm", "contact.cam_poisson": "0.7"}, ParameterError,
     "contact.cam_poisson"),
])
def test_bad_contact_keys_are_refused(change, error, match):
    with pytest.raises(error, match=match):
        load_rocking(EXAMPLE, change)


def test_simulate_runs_a_compliant_configuration_and_refuses_a_bad_law():
    settings = ("--set", "contact.law=compliant", "--set", "contact.stiffness=1e4 N*m", "--set",
                "contact.damping=0.02 N*m*s")
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(["simulate", str(EXAMPLE), "--revolutions", "1", "--sample-rate", "2kHz", "--json", *settings])
    assert status == 0, err.getvalue()
    summary = json.loads(out.getvalue())["summary"]
    follower, spec = load_rocking(EXAMPLE, {"contact.law": "compliant", "contact.stiffness": "1e4 N*m",
                                            "contact.damping": "0.02 N*m*s"})
    w = spec.profile.speed
    ds = simulate_rocking(follower, w / (2 * math.pi), 2 * math.pi / w, sample_rate=2000.0, rtol=1e-10)
    onsets = int(np.count_nonzero(ds.event_kind.values == "contact onset"))
    assert summary["contact_law"] == "compliant" and summary["contact_onsets"] == onsets >= 1
    assert summary["impacts"] == 0
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err := io.StringIO()):
        status = main(["simulate", str(EXAMPLE), "--set", "contact.law=soft"])
    assert status == 2 and "contact.law" in err.getvalue() and "Traceback" not in err.getvalue()


def _cycloidal_lift(u, lift=0.008, beta=2 * math.pi / 3):
    """``(s, s', s'')`` [m, m/rad, m/rad^2] of the cycloidal rise-dwell-return cam of
    test_rocking_roller.py, written here: ``s = L (x - sin(2 pi x) / (2 pi))``, ``x = u /
    beta``, on the rise, mirrored on the return."""
    u = u % (2 * math.pi)
    if u < beta or math.pi <= u < math.pi + beta:
        x = (u % math.pi) / beta
        sign = 1.0 if u < beta else -1.0
        s = lift * (x - math.sin(2 * math.pi * x) / (2 * math.pi))
        return (s if sign > 0 else lift - s, sign * lift * (1 - math.cos(2 * math.pi * x)) / beta,
                sign * lift * 2 * math.pi * math.sin(2 * math.pi * x) / beta ** 2)
    return (lift if u < math.pi else 0.0), 0.0, 0.0


@pytest.mark.parametrize("face", ["flat", "roller"])
def test_the_cam_curvature_at_the_contact_matches_the_cam_drawn_here(face):
    """The cam surface's curvature at the arm's contact on the cycloidal cam (base 30 mm,
    roller 8 mm), against the cam written here: for the profile made for a flat face, the
    support function's radius of curvature ``h + h''`` with ``h = r_base + s`` (Rothbart
    2004); for the roller profile, the pitch curve in polar form ``r = r_base + r_r +
    s(u)`` at the polar angle ``pi/2 - u``, whose radius of curvature is ``(r^2 +
    r'^2)^1.5 / (r^2 + 2 r'^2 - r r'')`` (``r' = -s'``, ``r'' = s''``), less the roller's
    radius. At 40 random cam angles to 1e-9 relative (measured 2e-16 and 3e-16); the
    table (straight lines between 8192 samples) between its samples within 1e-5 relative
    (measured 3e-7, its error ``h^2 kappa'' / 8``)."""
    roller = 0.008
    profile = rise_return_profile(CYCLOIDAL, 0.03, follower=face, roller_radius=roller if face == "roller" else 0.0)
    geometry = RockingGeometry(profile, -0.07, 0.04, 0.07, roller, 1)
    theta = np.random.default_rng(11).uniform(0.0, 2 * math.pi, 40)
    config = contact_configuration(geometry, theta)
    expected = []
    for u in config.parameter:
        s, s1, s2 = _cycloidal_lift(u)
        if face == "flat":
            expected.append(1 / (0.03 + s + s2))
        else:
            r = 0.03 + roller + s
            expected.append(1 / ((r * r + s1 * s1) ** 1.5 / (r * r + 2 * s1 * s1 - r * s2) - roller))
    curvature = surface_curvature(geometry, config.parameter)
    table = rocking_table(geometry, 8192).curvature.lift(theta)[0]
    print(f"{face}: {np.abs(curvature / expected - 1).max():.1e}, table {np.abs(table / curvature - 1).max():.1e}")
    np.testing.assert_allclose(curvature, expected, rtol=1e-9)
    np.testing.assert_allclose(table, curvature, rtol=1e-5)
