"""Coulomb friction at a translating follower's cam contact (camdyn.model.sliding_follower,
camdyn.simulation.sliding): the frictionless limit against the translating follower, the
roller's spin-up on a dwell and the knife edge's normal force against closed forms, an
independent SciPy solution of a roller that lifts off, lands, skids and rolls again on an
eccentric circle (its own geometry, in closed form, and its own stick/slip logic), the
energy balance, and the refusals."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from camdyn.errors import ParameterError
from camdyn.model.profiles import eccentric_circle, rise_return_profile
from camdyn.params.profiles import spec_from_table
from camdyn.simulation.sliding import FollowerFriction, simulate_sliding
from camdyn.simulation.translating import TranslatingFollower, alzate_rig, simulate_translating

# --- the frictionless limit ------------------------------------------------------------


@pytest.mark.parametrize("face", ["knife", "roller"])
def test_without_friction_the_translating_follower_is_reproduced_bitwise(face):
    """mu = 0: the same steps, so the same samples and counters as the translating
    follower (the knife edge on the Alzate rig through impacts and captures; a roller)."""
    if face == "knife":
        follower, speed, phase = alzate_rig(), 700.0 * math.pi / 30.0, math.pi / 2.0
    else:
        profile = eccentric_circle(0.05, 0.01, follower="roller", roller_radius=0.012)
        follower = TranslatingFollower(profile, mass=0.5, stiffness=2000.0, preload=20.0, restitution=0.6)
        speed, phase = 140.0, 0.0
    duration = 3 * 2.0 * math.pi / speed
    plain = simulate_translating(follower, speed / (2 * math.pi), duration, sample_rate=4000.0, phase=phase)
    rough = simulate_sliding(follower, FollowerFriction(0.0), speed / (2 * math.pi), duration, sample_rate=4000.0,
                             phase=phase)
    assert plain.attrs["solver_events"] > 3   # impacts and separations happen
    np.testing.assert_array_equal(rough["x"].values, plain["x"].values)
    np.testing.assert_array_equal(rough["x_dot"].values, plain["x_dot"].values)
    np.testing.assert_array_equal(rough["event_time"].values, plain["event_time"].values)
    for name in ("accepted_steps", "rejected_steps", "events"):
        assert rough.attrs[f"solver_{name}"] == plain.attrs[f"solver_{name}"]
    assert float(np.abs(rough["friction_heat"]).max()) == 0.0


# --- closed forms ----------------------------------------------------------------------


def test_roller_spin_up_on_a_dwell_ends_at_the_closed_form_time():
    """A roller set down without spin on a base circle (constant normal force N = F0):
    J_r omega_r' = -r_r mu_k N until the slip u = omega r_base + r_r omega_r vanishes, at
    t* = J_r omega r_base / (mu_k N r_r^2); then it rolls at -omega r_base / r_r."""
    r_base, r_r, inertia, mu, preload, omega = 0.05, 0.01, 2e-6, 0.2, 50.0, 100.0
    profile = eccentric_circle(r_base, 0.0, follower="roller", roller_radius=r_r)
    follower = TranslatingFollower(profile, mass=0.5, stiffness=1000.0, preload=preload)
    ds = simulate_sliding(follower, FollowerFriction(0.3, mu, roller_inertia=inertia), omega / (2 * math.pi), 0.02,
                          sample_rate=5000.0, initial_state=(0.0, 0.0, 0.0))
    t_stop = inertia * omega * r_base / (mu * preload * r_r ** 2)
    kinds = list(ds["event_kind"].values)
    assert kinds == ["rolling"]
    assert abs(float(ds["event_time"][0]) - t_stop) < 1e-12   # measured 3e-18 s
    sliding = ds["time"].values < t_stop
    np.testing.assert_allclose(ds["roller_speed"].values[sliding], -mu * preload * r_r / inertia
                               * ds["time"].values[sliding], rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(ds["roller_speed"].values[~sliding], -omega * r_base / r_r, rtol=1e-14)
    np.testing.assert_allclose(ds["contact_force"].values, preload, rtol=1e-12)
    # the heat of friction: mu N times the slip, which falls linearly to zero; it equals
    # the spin's kinetic energy gained (the energy balance of a slipping clutch)
    heat = float(ds["friction_heat"][-1])
    np.testing.assert_allclose(heat, 0.5 * mu * preload * omega * r_base * t_stop, rtol=1e-12)
    np.testing.assert_allclose(heat, 0.5 * inertia * (omega * r_base / r_r) ** 2, rtol=1e-12)   # measured 9e-16


def _offset_knife(follower="knife", offset=0.004):
    segments = [("cycloidal", math.radians(120), 0.01), ("dwell", math.radians(60), 0.0),
                ("cycloidal", math.radians(120), -0.01), ("dwell", math.radians(60), 0.0)]
    profile = rise_return_profile(segments, 0.04, follower=follower, offset=offset)
    return TranslatingFollower(profile, mass=0.5, stiffness=2000.0, preload=20.0)


def test_knife_edge_normal_force_against_the_classical_relation():
    """Sustained contact below lift-off: N = F_line / (cos phi - mu sin phi) (Norton 2009),
    with F_line = m s_ddot + F0 + k s and tan phi = (s' - eps) / (sqrt(rb^2 - eps^2) + s)
    written here from the lift; the cam turning counter-clockwise drags the tip back on
    the rise."""
    follower, omega, mu, eps = _offset_knife(), 40.0, 0.15, 0.004
    ds = simulate_sliding(follower, FollowerFriction(mu), omega / (2 * math.pi), 2 * math.pi / omega,
                          sample_rate=2000.0)
    assert ds["in_contact"].values.all()
    theta = omega * ds["time"].values
    s, s1, s2, _ = follower.profile.lift(theta)
    line = follower.mass * omega ** 2 * s2 + follower.preload + follower.stiffness * s
    phi = np.arctan((s1 - eps) / (math.sqrt(0.04 ** 2 - eps ** 2) + s))
    expected = line / (np.cos(phi) - mu * np.sin(phi))
    np.testing.assert_allclose(ds["contact_force"].values, expected, rtol=1e-12)
    np.testing.assert_allclose(ds["friction_force"].values, -mu * expected, rtol=1e-12)
    np.testing.assert_allclose(ds["line_force"].values, line, rtol=1e-12)
    rise = s1 > eps   # phi > 0: the tip dragged back, the cam pushes harder than the line needs
    assert rise.any() and np.all(ds["contact_force"].values[rise] > ds["line_force"].values[rise])


def test_flat_face_friction_loads_only_the_guide():
    """A flat face: the friction is normal to its line, so the motion is the frictionless
    one; the face slides at omega (r_base + s)."""
    follower, omega = _offset_knife("flat", 0.0), 90.0   # 860 rpm, above lift-off
    plain = simulate_translating(follower, omega / (2 * math.pi), 0.2, sample_rate=2000.0)
    rough = simulate_sliding(follower, FollowerFriction(0.3), omega / (2 * math.pi), 0.2, sample_rate=2000.0)
    np.testing.assert_array_equal(rough["x"].values, plain["x"].values)
    touching = rough["in_contact"].values == 1
    np.testing.assert_allclose(rough["slip_velocity"].values[touching],
                               omega * (0.04 + rough["lift"].values[touching]), rtol=1e-12)
    np.testing.assert_allclose(rough["friction_force"].values, -0.3 * rough["contact_force"].values, rtol=1e-12)


# --- an independent solution: a roller on an eccentric circle ---------------------------


class EccentricRoller:
    """A roller of radius ``r`` on a circle of radius ``R`` turning counter-clockwise at
    ``omega`` about a point ``e`` from its centre, in-line follower: the centre of the
    circle at ``c = (-e sin theta, e cos theta)``, the roller's centre at ``(0, Y)`` with
    ``|C - c| = R + r``; all vectors written out here, independently of camdyn."""

    def __init__(self, R, e, r, m, k, f0, inertia, mu_s, mu_k, omega, phase):
        self.R, self.e, self.r, self.m, self.k, self.f0 = R, e, r, m, k, f0
        self.J, self.mu_s, self.mu_k, self.omega, self.phase = inertia, mu_s, mu_k, omega, phase

    def centre(self, t):
        """``Y, dY/dtheta, d2Y/dtheta2`` of the roller's centre [m]."""
        e, th = self.e, self.phase + self.omega * t
        q = (self.R + self.r) ** 2 - (e * math.sin(th)) ** 2
        y = e * math.cos(th) + math.sqrt(q)
        y1 = -e * math.sin(th) - e * e * math.sin(2 * th) / (2 * math.sqrt(q))
        y2 = (-e * math.cos(th) - e * e * math.cos(2 * th) / math.sqrt(q)
              - e ** 4 * math.sin(2 * th) ** 2 / (4 * q ** 1.5))
        return y, y1, y2

    def lift(self, t):
        return self.centre(t)[0] - (self.R + self.r - self.e)

    def frame(self, t):
        """Contact normal n (out of the cam), tangent t = n turned clockwise, contact point P."""
        th = self.phase + self.omega * t
        y = self.centre(t)[0]
        n = np.array([self.e * math.sin(th), y - self.e * math.cos(th)]) / (self.R + self.r)
        return n, np.array([n[1], -n[0]]), np.array([0.0, y]) - self.r * n

    def slip(self, t, spin):
        """Velocity of the roller's material point at P less the cam's, along the tangent."""
        n, tan, point = self.frame(t)
        v_cam = self.omega * np.array([-point[1], point[0]])
        v_roller = np.array([0.0, self.omega * self.centre(t)[1]]) + self.r * spin * tan
        return float((v_roller - v_cam) @ tan)

    def line_force(self, t):
        y, _, y2 = self.centre(t)
        return self.m * self.omega ** 2 * y2 + self.f0 + self.k * self.lift(t)

    def rolling_spin(self, t):
        return -self.slip(t, 0.0) / self.r   # the slip is slip(t, 0) + r spin

    def rolling_forces(self, t, h=1e-5):
        """N and F while rolling: F = J spin' / r (spin' by a 4th-order central difference)."""
        g = self.rolling_spin
        rate = (-g(t + 2 * h) + 8 * g(t + h) - 8 * g(t - h) + g(t - 2 * h)) / (12 * h)
        friction = self.J * rate / self.r
        n, tan, _ = self.frame(t)
        return (self.line_force(t) - friction * tan[1]) / n[1], friction

    def sliding_forces(self, t, sign):
        n, tan, _ = self.frame(t)
        normal = self.line_force(t) / (n[1] - self.mu_k * sign * tan[1])
        return normal, -self.mu_k * sign * normal


def _root(f, a, b, step):
    """First sign change of f on [a, b] from positive, by scanning and brentq."""
    from scipy.optimize import brentq
    t0, f0 = a, f(a)
    while t0 < b:
        t1 = min(t0 + step, b)
        f1 = f(t1)
        if f1 <= 0.0 < f0:
            return brentq(f, t0, t1, xtol=1e-15, rtol=1e-15)
        t0, f0 = t1, f1
    return None


def _oracle(cam, t_end, spin0):
    """Event times and kinds, and the spin as a function of time (a list of pieces)."""
    t, mode, spin, x, v = 0.0, "roll", spin0, cam.lift(0.0), None
    events, pieces = [], []
    tol = dict(rtol=1e-12, atol=1e-12)
    while t < t_end:
        if mode == "roll":
            margins = [lambda s: cam.mu_s * cam.rolling_forces(s)[0] - cam.rolling_forces(s)[1],
                       lambda s: cam.mu_s * cam.rolling_forces(s)[0] + cam.rolling_forces(s)[1]]
            hits = [_root(g, t, t_end, 2e-4) for g in margins]
            pieces.append((t, "roll", None))
            if hits[0] is None and hits[1] is None:
                break
            which = 0 if hits[1] is None or (hits[0] is not None and hits[0] < hits[1]) else 1
            t = hits[which]
            spin, mode, sign = cam.rolling_spin(t), "slide", -1.0 if which == 0 else 1.0
            events.append((t, "slip"))
        elif mode == "slide":
            def rhs(s, z, sign=sign):
                return [cam.r * cam.sliding_forces(s, sign)[1] / cam.J]

            def zero_slip(s, z):
                return cam.slip(s, z[0])

            def leave(s, z):
                return cam.line_force(s)
            zero_slip.terminal = leave.terminal = True
            zero_slip.direction = -sign   # u returns to zero from its sign's side (not a rounding-level start)
            sol = solve_ivp(rhs, (t, t_end), [spin], method="DOP853", dense_output=True,
                            events=(zero_slip, leave), **tol)
            pieces.append((t, "slide", sol.sol))
            if sol.status == 0:
                break
            t, spin = sol.t[-1], sol.y[0, -1]
            if sol.t_events[1].size:
                mode, x, v = "flight", cam.lift(t), cam.omega * cam.centre(t)[1]
                events.append((t, "separation"))
                continue
            normal, friction = cam.rolling_forces(t)
            if abs(friction) <= cam.mu_s * normal:
                mode = "roll"
                events.append((t, "rolling"))
            else:
                sign = -1.0 if friction > 0.0 else 1.0
                events.append((t, "reversal"))
        else:
            def fly(s, z):
                return [z[1], (-cam.f0 - cam.k * z[0]) / cam.m]

            def land(s, z):
                return z[0] - cam.lift(s)
            land.terminal, land.direction = True, -1.0
            sol = solve_ivp(fly, (t, t_end), [x, v], method="DOP853", events=land, **tol)
            pieces.append((t, "flight", spin))
            if sol.status == 0:
                break
            t = sol.t[-1]
            events.append((t, "capture"))
            u = cam.slip(t, spin)
            mode, sign = "slide", 1.0 if u > 0.0 else -1.0
    return events, pieces


def _spin_at(cam, pieces, times):
    out = np.empty(times.size)
    for i, ti in enumerate(times):
        start, kind, data = [p for p in pieces if p[0] <= ti][-1]
        out[i] = cam.rolling_spin(ti) if kind == "roll" else (data(ti)[0] if kind == "slide" else data)
    return out


def test_roller_lift_off_skid_and_roll_against_an_independent_solution():
    """One revolution from the bottom of an eccentric circle at 120 rad/s: the roller rolls,
    the cone breaks as the normal force falls, it slides, lifts off, lands (a plastic
    landing: every touch is a capture) without spin change, skids and rolls again; every
    event time and the roller's spin against the solution above (SciPy, rtol 1e-12)."""
    R, e, r, m, k, f0, J, mu_s, mu_k, omega = 0.05, 0.01, 0.012, 0.5, 2000.0, 20.0, 2.5e-6, 0.15, 0.1, 120.0
    profile = eccentric_circle(R, e, follower="roller", roller_radius=r)
    follower = TranslatingFollower(profile, mass=m, stiffness=k, preload=f0, capture_velocity=100.0)
    period = 2 * math.pi / omega
    ds = simulate_sliding(follower, FollowerFriction(mu_s, mu_k, J), omega / (2 * math.pi), period, sample_rate=20000.0,
                          phase=math.pi, rtol=1e-12, atol=1e-14)
    cam = EccentricRoller(R, e, r, m, k, f0, J, mu_s, mu_k, omega, math.pi)
    events, pieces = _oracle(cam, period, float(ds["roller_speed"][0]))
    kinds = [kind for _, kind in events]
    assert kinds == list(ds["event_kind"].values)
    assert kinds == ["slip", "separation", "capture", "rolling"]
    # both solutions at rtol 1e-12: event times measured within 1e-14 s, the spin 7e-13
    np.testing.assert_allclose(ds["event_time"].values, [t for t, _ in events], rtol=0, atol=1e-12)
    spin = _spin_at(cam, pieces, ds["time"].values)
    scale = float(np.abs(spin).max())
    assert float(np.abs(ds["roller_speed"].values - spin).max()) < 1e-10 * scale
    # the cam can neither pull (N >= 0, |F| <= mu N and cos phi > mu |sin phi| give F_line
    # >= 0) nor change the motion of a follower it holds: the lift motion is the
    # frictionless one (measured 1e-17 m), the friction only sets N, F and the spin
    plain = simulate_translating(follower, omega / (2 * math.pi), period, sample_rate=20000.0, phase=math.pi,
                                 rtol=1e-12,
                                 atol=1e-14)
    assert float(np.abs(ds["x"].values - plain["x"].values).max()) < 1e-12
    np.testing.assert_allclose(ds["event_time"].values[1:3], plain["event_time"].values, rtol=0, atol=1e-12)


# --- refusals ------------------------------------------------------------------------------


def test_refusals_name_the_parameter():
    knife = _offset_knife()
    with pytest.raises(ParameterError, match="friction.static must not be negative"):
        FollowerFriction(-0.1)
    with pytest.raises(ParameterError, match="must not exceed friction.static"):
        FollowerFriction(0.1, 0.2)
    with pytest.raises(ParameterError, match="friction.roller_inertia: a knife follower has no roller"):
        simulate_sliding(knife, FollowerFriction(0.1, roller_inertia=1e-6), 40.0 / (2 * math.pi), 0.01)
    compliant = TranslatingFollower(knife.profile, mass=0.5, stiffness=2000.0, preload=20.0, contact="compliant",
                                    contact_stiffness=1e7)
    with pytest.raises(ParameterError, match="needs the rigid contact law"):
        simulate_sliding(compliant, FollowerFriction(0.1), 40.0 / (2 * math.pi), 0.01)
    with pytest.raises(ParameterError, match="jams"):   # pressure angles up to about 20 deg, mu tan(phi) > 1
        simulate_sliding(knife, FollowerFriction(3.5), 40.0 / (2 * math.pi), 0.01)


@pytest.mark.parametrize("key, value, face, law, message", [
    ("friction.static", -0.2, "knife", "rigid", "friction.static must not be negative"),
    ("friction.roller_inertia", "1 kg*mm^2", "knife", "rigid", "friction.roller_inertia: a knife follower"),
    ("friction.static", 0.2, "knife", "compliant", "friction.static: friction at the follower needs"),
    ("friction.kinetic", 0.3, "knife", "rigid", "friction.kinetic .* must not exceed"),
    ("friction.mu", 0.3, "knife", "rigid", "unknown key 'friction.mu'"),
])
def test_configuration_refusals_name_the_key(key, value, face, law, message):
    flat = {"follower.kind": "translating", "follower.face": face, "follower.mass": "0.5 kg",
            "spring.stiffness": "2 kN/m", "spring.preload": "20 N", "contact.law": law,
            "contact.stiffness": "1e7 N/m", "profile.kind": "eccentric-circle", "profile.radius": "50 mm",
            "profile.eccentricity": "10 mm", "friction.static": 0.1, key: value}
    with pytest.raises(ParameterError, match=message):
        spec_from_table(flat)


def test_configuration_reads_the_friction_table():
    from camdyn.io.lift_table import load_translating
    from camdyn.simulation.sliding import friction_from_spec

    example = Path(__file__).resolve().parents[1] / "examples" / "profiles" / "roller_friction.toml"
    follower, spec = load_translating(example, {})
    friction = friction_from_spec(spec)
    assert (friction.static, friction.kinetic) == (0.15, 0.1)
    assert friction.roller_inertia == pytest.approx(2.5e-6, rel=1e-15)
    assert follower.profile.follower == "roller" and follower.profile.roller_radius == 0.012


def test_the_example_runs_on_the_command_line(tmp_path):
    """``camdyn simulate examples/profiles/roller_friction.toml --revolutions 3 --json``: the
    friction's summary agrees with the same run through the Python interface; the netCDF
    result carries the friction's variables with units; a bad key is one line, exit 2."""
    import contextlib
    import io
    import json

    import xarray as xr

    from camdyn.cli.app import main
    from camdyn.io.lift_table import load_translating
    from camdyn.simulation.sliding import friction_from_spec

    def run(*argv):
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = main([str(a) for a in argv])
        return status, out.getvalue(), err.getvalue()

    example = Path(__file__).resolve().parents[1] / "examples" / "profiles" / "roller_friction.toml"
    nc = tmp_path / "run.nc"
    status, out, err = run("simulate", example, "--revolutions", "3", "--json", "--out", nc)
    assert status == 0, err
    summary = json.loads(out)["summary"]
    follower, spec = load_translating(example, {})
    ds = simulate_sliding(follower, friction_from_spec(spec), spec.speed / (2 * math.pi), 3 * 2 * math.pi / spec.speed,
                          sample_rate=20e3, phase=spec.phase)   # the command's default rate, 20 kHz
    kinds = ds["event_kind"].values
    assert summary["separations"] == np.count_nonzero(kinds == "separation") == 3
    assert summary["friction"]["slips"] == np.count_nonzero(kinds == "slip") == 3
    assert summary["friction"]["friction_heat_J"] == pytest.approx(float(ds["friction_heat"][-1]), rel=1e-9)
    saved = xr.load_dataset(nc, engine="h5netcdf")
    assert saved["roller_speed"].attrs["units"] == "rad/s" and saved["slip_velocity"].attrs["units"] == "m/s"
    status, out, err = run("simulate", example, "--set", "friction.static=-1")
    assert status == 2 and "friction.static must not be negative" in err + out and "Traceback" not in err + out
