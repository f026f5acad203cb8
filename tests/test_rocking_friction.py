"""Coulomb friction at a rocking arm's cam contact (camdyn.simulation.rocking_friction, on
camdyn.model.sliding_follower): the frictionless limit against the rocking arm, the arm's
kinematics unchanged by friction, the knife edge's normal force and slip against a closed
form of its own geometry (an eccentric circle: the arm angle a circle-circle intersection,
differentiated implicitly here), the roller's spin-up on a dwell, an independent SciPy
solution of a roller set down without spin that slides and rolls (its own geometry and
stick/slip logic), and the refusals."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from camdyn.errors import GeometryError, ParameterError
from camdyn.model.profiles import eccentric_circle, rise_return_profile
from camdyn.model.rocking_roller import RockingGeometry
from camdyn.params.rocking import rocking_spec_from_table
from camdyn.simulation.rocking_friction import simulate_rocking_friction
from camdyn.simulation.rocking_roller import RockingFollower, rocking_liftoff_speed, simulate_rocking
from camdyn.simulation.sliding import FollowerFriction

RADIUS, RUNOUT, ARM, ROLLER = 0.025, 0.005, 0.06, 0.008
PIVOT = np.array([-0.06, 0.03])
INERTIA, STIFFNESS, PRELOAD = 2e-4, 0.5, 0.05
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "profiles" / "rocking_friction.toml"


def arm_on_circle(face="knife", samples=8192, restitution=0.5):
    """The arm on the eccentric circle (radius RADIUS about a centre RUNOUT from the axis),
    a knife edge or a roller of radius ROLLER, lifted counter-clockwise."""
    roller = ROLLER if face == "roller" else 0.0
    profile = eccentric_circle(RADIUS, RUNOUT, follower=face, roller_radius=roller)
    geometry = RockingGeometry(profile, float(PIVOT[0]), float(PIVOT[1]), ARM, roller, 1)
    return RockingFollower(geometry, INERTIA, STIFFNESS, PRELOAD, restitution=restitution, samples=samples)


def intersection(pivot, arm, centre, radius):
    """The arm angle psi [rad] at which the circle of ``arm`` about ``pivot`` meets the
    circle of ``radius`` about ``centre`` where turning the arm counter-clockwise moves
    its end out of the latter; with ``e(psi)``, ``e'(psi)`` and ``d = C - centre``."""
    gap = centre - pivot
    dist = math.hypot(*gap)
    half = math.acos((arm ** 2 + dist ** 2 - radius ** 2) / (2 * arm * dist))
    for sign in (1, -1):
        psi = math.atan2(gap[1], gap[0]) + sign * half
        e, e1 = np.array([math.cos(psi), math.sin(psi)]), np.array([-math.sin(psi), math.cos(psi)])
        d = pivot + arm * e - centre
        if e1 @ d > 0:
            return psi, e, e1, d
    raise AssertionError("no lifting contact")


def contact(theta, radius):
    """The arm on the circle turned by ``theta`` [rad] (its centre at ``O = RUNOUT (-sin,
    cos)(theta)``), the roller centre C on the circle of ``radius`` about O: with ``d = P
    + ARM e(psi) - O``, ``|d| = radius``; implicit differentiation of ``|d|^2`` gives
    ``psi' = A / B`` with ``A = d.O'``, ``B = ARM d.e'``, and ``psi'' = (A' B - A B') /
    B^2``. Returns ``(psi, psi', psi'', phi, n, V)``: the pressure angle from the lift
    direction ``e'`` to the normal ``n = d / radius``, and the speed per unit cam speed of
    C relative to the cam's point under it along ``t = (n_y, -n_x)`` [m]."""
    c, s = math.cos(theta), math.sin(theta)
    centre = RUNOUT * np.array([-s, c])
    slope, curve = RUNOUT * np.array([-c, -s]), RUNOUT * np.array([s, -c])
    psi, e, e1, d = intersection(PIVOT, ARM, centre, radius)
    a, b = d @ slope, ARM * (d @ e1)
    psi1 = a / b
    d1 = ARM * e1 * psi1 - slope
    a1 = d1 @ slope + d @ curve
    b1 = ARM * (d1 @ e1) - ARM * psi1 * (d @ e)
    psi2 = (a1 * b - a * b1) / b ** 2
    n = d / radius
    phi = math.atan2(e1[0] * n[1] - e1[1] * n[0], e1 @ n)
    roller = PIVOT + ARM * e
    relative = ARM * psi1 * e1 - np.array([-roller[1], roller[0]])
    return psi, psi1, psi2, phi, n, relative @ np.array([n[1], -n[0]])


def rest_angle(radius):
    """The least arm angle over the cam angles (where psi' = 0, near the circle's far side)."""
    grid = np.linspace(0.0, 2 * math.pi, 721)
    psi = [contact(t, radius)[0] for t in grid]
    k = int(np.argmin(psi))
    return contact(brentq(lambda t: contact(t, radius)[1], grid[k - 1], grid[k + 1], xtol=1e-15), radius)[0]


def moment(theta, w, radius, rest):
    """The holding moment [N m] of the arm in sustained contact: I w^2 psi'' + M0 + k (psi - psi0)."""
    psi, _, psi2 = contact(theta, radius)[:3]
    return INERTIA * w * w * psi2 + PRELOAD + STIFFNESS * (psi - rest)


# --- the frictionless limit and the kinematics ------------------------------------------


def test_without_friction_the_rocking_arm_is_reproduced_bitwise():
    """mu = 0 through the sliding follower's model: the rocking arm's samples, events and
    step counts, bit for bit, over three revolutions with lift-off, impacts and captures."""
    follower = arm_on_circle("roller")
    w = 1.15 * rocking_liftoff_speed(follower)
    duration = 3 * 2 * math.pi / w
    plain = simulate_rocking(follower, w / (2 * math.pi), duration, sample_rate=4000)
    rough = simulate_rocking_friction(follower, FollowerFriction(0.0), w / (2 * math.pi), duration, sample_rate=4000)
    assert plain.attrs["solver_events"] > 10
    for name in ("psi", "psi_dot", "event_time"):
        np.testing.assert_array_equal(rough[name].values, plain[name].values)
    np.testing.assert_allclose(rough.contact_force.values, plain.contact_force.values, rtol=1e-12)
    assert list(rough.event_kind.values) == list(plain.event_kind.values)
    for name in ("accepted_steps", "rejected_steps", "events"):
        assert rough.attrs[f"solver_{name}"] == plain.attrs[f"solver_{name}"]
    assert float(np.abs(rough["friction_heat"]).max()) == 0.0


@pytest.mark.parametrize("face", ["knife", "roller"])
def test_friction_leaves_the_arm_angle_unchanged(face):
    """The arm's motion in rigid contact is the cam's and friction acts in contact only:
    with mu_k = 0.3 (a roller with spin inertia that rolls and slides) the arm angle and
    the events' times are the frictionless arm's to 1e-15, through lift-off and landings,
    while the normal force and the heat change."""
    follower = arm_on_circle(face)
    w = 1.15 * rocking_liftoff_speed(follower)
    duration = 2 * 2 * math.pi / w
    inertia = 2e-7 if face == "roller" else 0.0
    plain = simulate_rocking(follower, w / (2 * math.pi), duration, sample_rate=4000)
    rough = simulate_rocking_friction(follower, FollowerFriction(0.4, 0.3, inertia), w / (2 * math.pi), duration,
                                      sample_rate=4000)
    np.testing.assert_allclose(rough.psi.values, plain.psi.values, rtol=0, atol=1e-15)
    keep = rough.event_kind.values
    shared = np.isin(keep, ("impact", "capture", "separation", "graze"))
    np.testing.assert_allclose(rough.event_time.values[shared], plain.event_time.values, rtol=0, atol=1e-15)
    touching = rough.in_contact.values == 1
    assert np.abs(rough.contact_force.values - plain.contact_force.values)[touching].max() > 1e-3
    assert float(rough["friction_heat"][-1]) > 0.0


# --- closed forms ------------------------------------------------------------------------


def test_knife_edge_normal_force_and_slip_against_the_closed_form():
    """A knife edge held on the eccentric circle slides at u = omega V > 0, so N = M / (L
    (cos phi - mu_k sin phi)) (the moment balance with the friction's lever L sin phi),
    F = -mu_k N, and the pivot holds the balanced arm with -(N n + F t). Against the
    closed form at every sample: u and the pivot's reaction to 1e-10; the ratio N / M
    to 1e-10 (the friction's law; M the compiled run's own holding moment; all three
    measured 2e-15); N itself to the lift table's accuracy, 1e-7 relative (its spline's
    s'' is good to some 1e-8 rad/rad^2; measured 5.7e-8)."""
    mu = 0.3
    follower = arm_on_circle("knife")
    w = 0.6 * rocking_liftoff_speed(follower)
    ds = simulate_rocking_friction(follower, FollowerFriction(mu), w / (2 * math.pi), 2 * math.pi / w, sample_rate=2000)
    assert np.all(ds.in_contact.values == 1) and ds.event_time.size == 0
    rest = rest_angle(RADIUS)
    for t, normal, friction, slip, moment_run, fx, fy in zip(
            ds.time.values, ds.contact_force.values, ds.friction_force.values, ds.slip_velocity.values,
            ds.contact_moment.values, ds.pivot_force_x.values, ds.pivot_force_y.values):
        _, _, _, phi, n, speed = contact(w * t, RADIUS)
        closed = moment(w * t, w, RADIUS, rest) / (ARM * (math.cos(phi) - mu * math.sin(phi)))
        assert abs(normal - closed) < 1e-7 * abs(closed)
        assert abs(normal * ARM * (math.cos(phi) - mu * math.sin(phi)) / moment_run - 1.0) < 1e-10
        assert abs(friction + mu * normal) < 1e-12 * normal
        assert abs(slip - w * speed) < 1e-10 * w * speed
        force = normal * n + friction * np.array([n[1], -n[0]])
        assert abs(fx + force[0]) < 1e-10 * normal and abs(fy + force[1]) < 1e-10 * normal


CYCLOIDAL = [("cycloidal", 2 * math.pi / 3, 0.008), ("dwell", math.pi / 3, 0.0),
             ("cycloidal", 2 * math.pi / 3, -0.008), ("dwell", math.pi / 3, 0.0)]


def test_roller_spin_up_on_a_dwell_ends_at_the_closed_form_time():
    """A roller set down without spin on the base-circle dwell (300 to 360 deg): the arm is
    still, C on the circle of radius Rp = r_base + r_r about the cam's axis, so V = Rp, N
    = M0 / (L (cos phi - mu_k sin phi)) with phi of that circle's intersection with the
    arm's, and J_r omega_r' = -r_r mu_k N until u = omega Rp + r_r (omega_r - omega)
    vanishes: at t* = J_r omega (Rp - r_r) / (mu_k N r_r^2), then it rolls at omega (1 -
    Rp / r_r)."""
    base, mu, inertia, w = 0.03, 0.2, 1e-7, 40.0
    profile = rise_return_profile(CYCLOIDAL, base, follower="flat")
    geometry = RockingGeometry(profile, -0.07, 0.04, 0.07, ROLLER, 1)
    follower = RockingFollower(geometry, INERTIA, STIFFNESS, PRELOAD)
    start = math.radians(305.0)
    ds = simulate_rocking_friction(follower, FollowerFriction(0.3, mu, inertia), w / (2 * math.pi),
                                   math.radians(50.0) / w,
                                   sample_rate=20000, phase=start, roller_speed=0.0)
    pivot, pitch = np.array([-0.07, 0.04]), base + ROLLER
    psi, _, e1, d = intersection(pivot, 0.07, np.zeros(2), pitch)
    n = d / pitch
    phi = math.atan2(e1[0] * n[1] - e1[1] * n[0], e1 @ n)
    normal = PRELOAD / (0.07 * (math.cos(phi) - mu * math.sin(phi)))
    t_stop = inertia * w * (pitch - ROLLER) / (mu * normal * ROLLER ** 2)
    assert list(ds.event_kind.values) == ["rolling"]
    assert abs(ds.event_time.values[0] - t_stop) < 1e-10
    assert abs(ds.psi.values[0] - psi) < 1e-12
    sliding = ds.time.values < t_stop
    np.testing.assert_allclose(ds.contact_force.values[sliding], normal, rtol=1e-12)
    np.testing.assert_allclose(ds.roller_speed.values[~sliding], w * (1 - pitch / ROLLER), rtol=1e-12)
    np.testing.assert_allclose(ds.roller_speed.values[sliding],
                               -ROLLER * mu * normal / inertia * ds.time.values[sliding], rtol=1e-10, atol=1e-12)


# --- an independent solution ------------------------------------------------------------


def reference(w, t_end, mu_s, mu_k, inertia):
    """SciPy solution of the roller on the eccentric circle held in contact, set down
    without spin at t = 0, in its own geometry (:func:`contact`) and stick/slip logic:
    sliding with sign(u), N = M / (L (cos phi - mu_k sign(u) sin phi)), J omega_r' = r F,
    F = -mu_k sign(u) N, until u = omega V + r (omega_r - omega) vanishes; then rolling if
    the friction rolling needs, F = -J omega^2 V' / r^2 (V' by a five-point difference),
    lies within mu_s N, N = (M / L - F sin phi) / cos phi, else sliding the other way;
    rolling until |F| reaches mu_s N (found on a grid, then by brentq). Returns the
    events ``(t, kind)`` and pieces ``(t0, t1, spin(t))``."""
    radius = RADIUS + ROLLER
    rest = rest_angle(radius)

    def speed(t):
        return contact(w * t, radius)[5]

    def rolling(t):
        h = 1e-3
        slope = sum(c * speed(t + k * h / w) for c, k in ((1, -2), (-8, -1), (8, 1), (-1, 2))) / (12 * h)
        friction = -inertia * w * w * slope / ROLLER ** 2
        phi = contact(w * t, radius)[3]
        normal = (moment(w * t, w, radius, rest) / ARM - friction * math.sin(phi)) / math.cos(phi)
        return friction, normal

    def spin_rate(t, y, sign):
        phi = contact(w * t, radius)[3]
        normal = moment(w * t, w, radius, rest) / (ARM * (math.cos(phi) - mu_k * sign * math.sin(phi)))
        return [-ROLLER * mu_k * sign * normal / inertia]

    def slip(t, y, sign):
        return w * speed(t) + ROLLER * (y[0] - w)
    slip.terminal = True

    t, spin, events, pieces = 0.0, 0.0, [], []
    sign = 1.0 if slip(0.0, [spin], 0) > 0 else -1.0
    while t < t_end:
        if sign != 0.0:
            sol = solve_ivp(spin_rate, (t, t_end), [spin], method="DOP853", args=(sign,), events=slip,
                            dense_output=True, rtol=1e-13, atol=1e-12)
            pieces.append((t, sol.t[-1], lambda u, s=sol.sol: s(u)[0]))
            if sol.status != 1:
                break
            t, spin = sol.t[-1], sol.y[0, -1]
            friction, normal = rolling(t)
            sign = 0.0 if abs(friction) <= mu_s * normal else -math.copysign(1.0, friction)
            events.append((t, "rolling" if sign == 0.0 else "reversal"))
            continue

        def margin(u):
            friction, normal = rolling(u)
            return mu_s * normal - abs(friction)
        grid = np.arange(t, t_end, 2e-4)[1:]
        broken = [u for u in grid if margin(u) < 0.0]
        t_next = t_end if not broken else brentq(margin, broken[0] - 2e-4, broken[0], xtol=1e-15)
        pieces.append((t, t_next, lambda u: w * (1.0 - speed(u) / ROLLER)))
        if not broken:
            break
        friction, _ = rolling(t_next)
        t, spin, sign = t_next, w * (1.0 - speed(t_next) / ROLLER), -math.copysign(1.0, friction)
        events.append((t, "slip"))
    return events, pieces


def test_roller_set_down_without_spin_against_an_independent_solution():
    """A roller (J_r = 5e-7 kg m^2, mu_s 0.2, mu_k 0.15) set down without spin on the
    eccentric circle, held in contact over one revolution: it slides until friction has
    spun it up, then rolls. The compiled run against :func:`reference`: the same events,
    their times within 1e-10 s (measured 2e-12 s), the spin within 1e-9 of its largest
    value, about 200 rad/s (measured 3.3e-8 rad/s while it slides, 6e-13 rad/s while it
    rolls). The sliding spin integrates N, whose error is the arm's lift table's: its
    cubic spline's s'' is good to some 1e-8 rad/rad^2 (N within 3.5e-8 relative, -7e-10 on
    average over the slide; a finer table does worse, the rounding of the samples then
    dominating s'')."""
    follower = arm_on_circle("roller")
    w = 0.6 * rocking_liftoff_speed(follower)
    duration = 2 * math.pi / w
    ds = simulate_rocking_friction(follower, FollowerFriction(0.2, 0.15, 5e-7), w / (2 * math.pi), duration,
                                   sample_rate=2000,
                                   roller_speed=0.0, rtol=1e-12, atol=1e-14)
    events, pieces = reference(w, duration, 0.2, 0.15, 5e-7)
    assert [k for _, k in events] == list(ds.event_kind.values)
    assert "rolling" in ds.event_kind.values
    np.testing.assert_allclose(ds.event_time.values, [t for t, _ in events], rtol=0, atol=1e-10)
    worst = 0.0
    for t, spin in zip(ds.time.values, ds.roller_speed.values):
        for t0, t1, piece in pieces:
            if t0 <= t <= t1:
                worst = max(worst, abs(spin - piece(t)))
                break
    assert worst < 1e-9 * float(np.abs(ds.roller_speed.values).max()), worst


# --- refusals and the configuration -----------------------------------------------------


def test_refusals_name_the_parameter():
    knife, roller = arm_on_circle("knife"), arm_on_circle("roller")
    with pytest.raises(ParameterError, match="friction.static must not be negative"):
        FollowerFriction(-0.1)
    with pytest.raises(ParameterError, match="must not exceed friction.static"):
        FollowerFriction(0.1, 0.2)
    with pytest.raises(ParameterError, match="friction.roller_inertia: a knife edge has no roller"):
        simulate_rocking_friction(knife, FollowerFriction(0.1, roller_inertia=1e-6), 40.0 / (2 * math.pi), 0.01)
    compliant = RockingFollower(roller.geometry, INERTIA, STIFFNESS, PRELOAD, contact="compliant",
                                contact_stiffness=1e4)
    with pytest.raises(ParameterError, match="needs the rigid contact law"):
        simulate_rocking_friction(compliant, FollowerFriction(0.1), 40.0 / (2 * math.pi), 0.01)
    # pressure angles from -7 to 19 deg: cos(phi) - mu_k sin(phi) reaches zero for mu_k above 2.93
    with pytest.raises(GeometryError, match=r"the arm jams at cam angle \d+\.\d+ deg"):
        simulate_rocking_friction(knife, FollowerFriction(3.0), 40.0 / (2 * math.pi), 0.01)
    with pytest.raises(ParameterError, match="roller_speed: a knife edge"):
        simulate_rocking_friction(knife, FollowerFriction(0.1), 40.0 / (2 * math.pi), 0.01, roller_speed=3.0)
    with pytest.raises(ParameterError, match="expected a RockingFollower"):
        simulate_rocking_friction(object(), FollowerFriction(0.1), 40.0 / (2 * math.pi), 0.01)


def _flat(**changes):
    flat = {"follower.kind": "rocking", "follower.face": "knife", "follower.pivot_x": "-60 mm",
            "follower.pivot_y": "30 mm", "follower.arm_length": "60 mm", "follower.inertia": "2e-4 kg*m^2",
            "spring.stiffness": "0.5 N*m/rad", "spring.preload": "0.05 N*m", "profile.kind": "eccentric-circle",
            "profile.face": "knife", "profile.radius": "25 mm", "profile.eccentricity": "5 mm",
            "friction.static": 0.1}
    flat.update(changes)
    return flat


@pytest.mark.parametrize("changes, message", [
    ({"friction.static": -0.2}, "friction.static must not be negative"),
    ({"friction.roller_inertia": "1 kg*mm^2"}, "friction.roller_inertia: a knife follower"),
    ({"contact.law": "compliant", "contact.stiffness": "1e4 N*m/rad"}, "friction at the follower needs"),
    ({"friction.kinetic": 0.3}, "friction.kinetic .* must not exceed"),
    ({"friction.mu": 0.3}, "unknown key 'friction.mu'"),
])
def test_configuration_refusals_name_the_key(changes, message):
    with pytest.raises(ParameterError, match=message):
        rocking_spec_from_table(_flat(**changes))


def test_the_example_runs_on_the_command_line(tmp_path):
    """``camdyn simulate examples/profiles/rocking_friction.toml --revolutions 3 --json``:
    the friction's summary agrees with the same run through the Python interface, the
    netCDF result carries the friction's variables with units; a bad key is one line,
    exit 2."""
    import contextlib
    import io
    import json

    import xarray as xr

    from camdyn.cli.app import main
    from camdyn.io.rocking_config import load_rocking
    from camdyn.simulation.sliding import friction_from_spec

    def run(*argv):
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = main([str(a) for a in argv])
        return status, out.getvalue(), err.getvalue()

    nc = tmp_path / "run.nc"
    status, out, err = run("simulate", EXAMPLE, "--revolutions", "3", "--json", "--out", nc)
    assert status == 0, err
    summary = json.loads(out)["summary"]
    follower, spec = load_rocking(EXAMPLE, {})
    friction = friction_from_spec(spec)
    assert (friction.static, friction.kinetic) == (0.1, 0.08)
    assert friction.roller_inertia == pytest.approx(4e-7, rel=1e-15)
    ds = simulate_rocking_friction(follower, friction, spec.profile.speed / (2 * math.pi),
                                   3 * 2 * math.pi / spec.profile.speed,
                                   sample_rate=20e3, phase=spec.profile.phase)   # the command's default rate
    kinds = ds["event_kind"].values
    assert summary["separations"] == np.count_nonzero(kinds == "separation") > 0
    assert summary["friction"]["rolling_starts"] == np.count_nonzero(kinds == "rolling") > 0
    assert summary["friction"]["friction_heat_J"] == pytest.approx(float(ds["friction_heat"][-1]), rel=1e-9)
    saved = xr.load_dataset(nc, engine="h5netcdf")
    assert saved["roller_speed"].attrs["units"] == "rad/s" and saved["slip_velocity"].attrs["units"] == "m/s"
    assert saved["pivot_force_x"].attrs["units"] == "N" and saved["contact_moment"].attrs["units"] == "N*m"
    status, out, err = run("simulate", EXAMPLE, "--set", "friction.static=-1")
    assert status == 2 and "friction.static must not be negative" in err + out and "Traceback" not in err + out


def test_a_run_that_ends_on_a_dwell_completes():
    # The example's arm without friction (system 4) over exactly 3 revolutions at 500 rpm:
    # its last step, on the dwell, was exact in DOP853's fifth-order estimate with a third-
    # order estimate that underflowed, and the error norm's 0/0 raised ZeroDivisionError.
    from camdyn.io.rocking_config import load_rocking
    follower, _ = load_rocking(EXAMPLE, {})
    speed = 500.0 * 2.0 * math.pi / 60.0
    for duration in (0.36, 0.3599):
        ds = simulate_rocking(follower, speed / (2 * math.pi), duration, sample_rate=20e3)
        assert np.isfinite(ds["psi"].values).all()
        assert ds["time"].values[-1] == pytest.approx(duration, abs=1e-12)
