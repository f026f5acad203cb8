"""The compliant contacts of the rocking roller (:mod:`camdyn.simulation.rocking_roller`),
against values computed here from outside the code:

- an event-driven SciPy solution in the arm angle with its own geometry (the eccentric
  circle's closed form of test_rocking_roller.py) and its own contact moments:
  a torsional spring-dashpot, and Hertz line contact ``(pi/4) E* l L_e^2 delta`` with
  Hunt and Crossley's damping ``chi = 3 (1 - e) / 2`` (Hunt and Crossley 1975,
  doi:10.1115/1.3423596) or a dashpot ``c L_e^2 delta'``, the lever ``L_e`` the root
  mean square of ``L cos(phi)`` over the closed form's pressure angles;
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
from test_rocking_roller import ARM, INERTIA, PRELOAD, STIFFNESS, circle_geometry, closed_form

from camdyn.cli.app import main
from camdyn.errors import ParameterError, UnknownKeyError
from camdyn.io.rocking_config import load_rocking
from camdyn.simulation.rocking_roller import (
    RockingFollower,
    contact_lever,
    rocking_liftoff_speed,
    simulate_rocking,
)
from camdyn.simulation.translating_contact import HertzContact

#: Soft materials [Pa] and a roller width [m], so that a contact lasts about a millisecond.
MODULUS, POISSON, WIDTH = 2e8, 0.3, 5e-3
RESTITUTION = 0.5
DROP = 0.01   # the arm starts this far [rad] above the cam, at rest


def _lever():
    """``L_e`` [m]: the root mean square of ``ARM cos(phi)`` at 8192 cam angles."""
    phi = np.array([closed_form(t)[3] for t in np.linspace(0, 2 * math.pi, 8192, endpoint=False)])
    return math.sqrt(np.mean((ARM * np.cos(phi)) ** 2))


def _moment_law(kind):
    """The contact moment [N m] as a function of penetration delta [rad], its rate [rad/s]
    and the approach rate at the onset [rad/s]."""
    if kind == "compliant":
        return lambda d, dd, v: 2000.0 * d + 0.1 * dd
    lever = _lever()
    star = MODULUS / (2 * (1 - POISSON ** 2))             # 1/E* = 2 (1 - nu^2) / Y (Johnson, eq. 4.22)
    k = math.pi / 4 * star * WIDTH * lever ** 2           # line contact, (pi/4) E* l, times L_e^2
    if kind == "hertz-viscous":    # c = 50 N s/m on the roller: the moment c L_e^2 delta'
        return lambda d, dd, v: k * d + 50.0 * lever ** 2 * dd
    v_reference = 1e-3 / lever
    return lambda d, dd, v: k * d * (1 + 1.5 * (1 - RESTITUTION) * dd / max(v, v_reference))


def _follower(kind):
    geometry = circle_geometry()
    if kind == "compliant":
        return RockingFollower(geometry, INERTIA, STIFFNESS, PRELOAD, contact="compliant", contact_stiffness=2000.0,
                               contact_damping=0.1)
    law = HertzContact(cam_modulus=MODULUS, follower_modulus=MODULUS, cam_poisson=POISSON, follower_poisson=POISSON,
                       width=WIDTH, damping_law="hunt-crossley", restitution=RESTITUTION)
    if kind == "hertz-viscous":
        law = HertzContact(cam_modulus=MODULUS, follower_modulus=MODULUS, cam_poisson=POISSON,
                           follower_poisson=POISSON, width=WIDTH, damping_law="viscous", damping=50.0)
    return RockingFollower(geometry, INERTIA, STIFFNESS, PRELOAD, contact="hertz", hertz=law)


def reference(kind, w, t_end, rest):
    """Event-driven SciPy solution: I psi'' = -M0 - k (psi - psi0) + M_c(delta, delta',
    v) with the penetration delta = psi_c(w t) - psi while it is positive."""
    moment = _moment_law(kind)

    def rates(t, y, contact, approach):
        psi, psi1, _, _ = closed_form(w * t)
        push = moment(psi - y[0], w * psi1 - y[1], approach) if contact else 0.0
        return [y[1], (-PRELOAD - STIFFNESS * (y[0] - rest) + push) / INERTIA]

    def gap(t, y, *args):
        return y[0] - closed_form(w * t)[0]
    gap.terminal = True
    t, y, contact, approach, events, pieces = 0.0, np.array([closed_form(0.0)[0] + DROP, 0.0]), False, 0.0, [], []
    while t < t_end:
        gap.direction = 1 if contact else -1
        sol = solve_ivp(rates, (t, t_end), y, method="DOP853", rtol=1e-12, atol=1e-14, events=gap,
                        dense_output=True, args=(contact, approach), max_step=1e-5)
        pieces.append((t, sol.t[-1], sol.sol))
        t, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status != 1:
            break
        contact = not contact
        approach = w * closed_form(w * t)[1] - y[1] if contact else 0.0
        events.append((t, "contact onset" if contact else "contact end"))
    return events, pieces


@pytest.mark.parametrize("kind", ["compliant", "hertz", "hertz-viscous"])
def test_a_revolution_with_impacts_matches_an_independent_solution(kind):
    """The arm dropped onto the cam at 1.15 times the rigid lift-off speed: it bounces,
    settles, leaves the cam and lands again within the revolution. The compiled run (on
    the spline table) against the reference: the same contact onsets and ends, within
    1e-8 s (measured 2e-13 to 9e-13 s), and the arm angle within 1e-8 rad (measured
    2e-13 rad for the Hertz laws). On this
    rig the lever's rms is 59.5 mm of the 60 mm arm and its square spreads 2.9 % over the
    revolution."""
    follower = _follower(kind)
    w = 1.15 * rocking_liftoff_speed(follower)
    duration = 2 * math.pi / w
    psi0 = closed_form(0.0)[0] + DROP
    ds = simulate_rocking(follower, w, duration, sample_rate=4000, initial_state=(psi0, 0.0), rtol=1e-12,
                          atol=1e-14)
    events, pieces = reference(kind, w, duration, ds.attrs["rest_angle_rad"])
    kinds = [k for _, k in events]
    assert list(ds.event_kind.values) == kinds
    assert kinds.count("contact onset") >= 3
    np.testing.assert_allclose(ds.event_time.values, [t for t, _ in events], rtol=0, atol=1e-8)
    for t, psi in zip(ds.time.values, ds.psi.values):
        for t0, t1, sol in pieces:
            if t0 <= t <= t1:
                assert abs(psi - sol(t)[0]) < 1e-8
                break
    if kind != "compliant":
        lever, spread = contact_lever(follower)
        assert lever == pytest.approx(_lever(), rel=1e-12)
        assert 0.0 < spread < 0.5 and ds.attrs["lever_spread"] == spread


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
    ds = simulate_rocking(rigid, w, 0.05, **options)
    impacts = ds.event_time.values[ds.event_kind.values == "impact"][:3]
    assert impacts.size == 3
    errors = []
    for stiffness in (1e3, 1e4, 1e5, 1e6):
        arm = RockingFollower(geometry, INERTIA, STIFFNESS, PRELOAD, contact="compliant",
                              contact_stiffness=stiffness, contact_damping=_penalty_damping(stiffness))
        run = simulate_rocking(arm, w, 0.05, **options)
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
    ({"contact": "hertz", "hertz": HertzContact(geometry="point", width=WIDTH)}, "line contact only"),
    ({"contact": "hertz", "hertz": HertzContact(width=WIDTH, tip_radius=1e-3)}, "tip_radius"),
    ({"contact": "hertz", "hertz": HERTZ, "contact_damping": 1.0}, "belong to the compliant law"),
])
def test_bad_contacts_are_refused_when_built(change, match):
    with pytest.raises(ParameterError, match=match):
        RockingFollower(circle_geometry(), INERTIA, STIFFNESS, PRELOAD, **change)


def test_a_knife_edge_takes_no_hertz_contact():
    with pytest.raises(ParameterError, match="knife edge takes the compliant contact only"):
        RockingFollower(circle_geometry("knife", roller=0.0), INERTIA, STIFFNESS, PRELOAD, contact="hertz",
                        hertz=HertzContact(tip_radius=1e-3, geometry=""))


EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "profiles" / "rocking_roller.toml"


def test_the_contact_keys_of_a_configuration_build_the_follower():
    follower, _ = load_rocking(EXAMPLE, {"contact.law": "hertz", "contact.width": "6 mm",
                                         "contact.cam_modulus": "200 GPa", "contact.damping_law": "hunt-crossley",
                                         "contact.restitution": "0.7"})
    assert follower.contact == "hertz" and follower.hertz == HertzContact(
        cam_modulus=200e9, geometry="line", width=6e-3, damping_law="hunt-crossley", restitution=0.7)
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
    ({"contact.law": "hertz", "contact.width": "5 mm", "contact.geometry": "point"}, ParameterError,
     "line contact only"),
    ({"contact.law": "hertz", "contact.width": "5 mm", "contact.tip_radius": "1 mm"}, UnknownKeyError,
     "contact.tip_radius"),
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
    ds = simulate_rocking(follower, w, 2 * math.pi / w, sample_rate=2000.0, rtol=1e-10)
    onsets = int(np.count_nonzero(ds.event_kind.values == "contact onset"))
    assert summary["contact_law"] == "compliant" and summary["contact_onsets"] == onsets >= 1
    assert summary["impacts"] == 0
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err := io.StringIO()):
        status = main(["simulate", str(EXAMPLE), "--set", "contact.law=soft"])
    assert status == 2 and "contact.law" in err.getvalue() and "Traceback" not in err.getvalue()
