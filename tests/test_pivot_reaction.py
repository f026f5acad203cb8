"""The pivot reaction ``Nx, Ny`` and its inverse against Newton-Euler written here in vector form.

The simulated channels (alpha, alpha_dot, alpha_ddot, Fn, Ff, Fs) are fed to an independent
rigid-body calculation: 3-D vectors and cross products, the angular velocity
``omega = -alpha_dot z`` of a clockwise angle, the centre of gravity at ``l_cg u``, every
force applied at its own point (docs/model.md §1, §3.1, §3.7, §3.8). The runs are chosen so that the
inertia force, its centripetal part and the friction force are each many orders of
magnitude above the tolerance: dropping any of them, or flipping a sign, fails.

Tolerances: the two calculations differ only by rounding, about 1e-16 of the largest
term per operation over a few dozen operations, so each check allows 1e-9 of the
largest term it sums: far above rounding, and 1e4 times below the smallest physical
term the test asserts is present.
"""

import math

import numpy as np
import pytest

import camdyn
from camdyn.model.outputs import contact_forces_from_reaction
from camdyn.simulation.runner import prepare
from camdyn.testing.oracle import ReferenceModel

Z = np.array([0.0, 0.0, 1.0])
ROUNDING = 1e-9      # relative to the largest term summed (see the module docstring)
PRESENT = 1e4        # each physical term tested must exceed the tolerance this many times


def _vec(x, y):
    """Stack of 3-D vectors [any unit] from x and y components."""
    return np.stack([x, y, np.zeros_like(x)], axis=-1)


def newton_euler(system, ds):
    """Independent rigid-body quantities of the follower at every sample.

    Returns
    -------
    dict
        ``N`` (n, 3) [N]: bearing force on the follower from ``sum F = m a_G``; ``alpha_ddot``
        (n,) [rad/s^2] from the angular momentum about P; the terms [N] and moments [N m]
        that went in (for the tolerances and the presence checks).
    """
    f, sp = system.follower, system.spring
    a, ad, add = ds.alpha.values, ds.alpha_dot.values, ds.alpha_ddot.values
    fn, ff, fs, chi = ds.Fn.values, ds.Ff.values, ds.Fs.values, ds.moment_arm.values
    u = _vec(np.cos(a), -np.sin(a))
    n = _vec(np.sin(a), np.cos(a))
    omega = -ad[:, None] * Z                 # alpha is clockwise: the body turns about -z
    omega_dot = -add[:, None] * Z
    r_g = f.cg_distance * u
    a_g = np.cross(omega_dot, r_g) + np.cross(omega, np.cross(omega, r_g))
    centripetal = np.cross(omega, np.cross(omega, r_g))
    f_contact = -fn[:, None] * n + ff[:, None] * u      # the cam pushes along -n, drags along +u
    f_spring = fs[:, None] * np.array([math.sin(sp.tilt), math.cos(sp.tilt), 0.0])
    weight = np.array([0.0, -f.mass * system.gravity, 0.0])
    reaction = f.mass * a_g - f_contact - f_spring - weight
    # angular momentum about the fixed pivot: I_P omega_dot = sum r x F (the bearing has no arm)
    h = f.surface_offset
    r_contact = chi[:, None] * u + h * n
    wb = f.width
    along = (sp.attachment_x + 0.5 * wb * np.sin(a)) / np.cos(a)   # the lower face point at x = dx
    r_spring = along[:, None] * u - 0.5 * wb * n
    moments = [np.cross(r_contact, f_contact), np.cross(r_spring, np.broadcast_to(f_spring, r_spring.shape)),
               np.cross(r_g, np.broadcast_to(weight, r_g.shape))]
    alpha_ddot = -sum(m[:, 2] for m in moments) / f.inertia
    terms = [f.mass * a_g, f_contact, f_spring, np.broadcast_to(weight, a_g.shape)]
    return {"N": reaction, "alpha_ddot": alpha_ddot, "inertia": f.mass * a_g,
            "centripetal": f.mass * centripetal, "friction": ff[:, None] * u,
            "force_scale": max(np.max(np.abs(t)) for t in terms),
            "moment_scale": max(np.max(np.abs(m)) for m in moments) / f.inertia}


CASES = {
    # chapter 4 rig at e/a = 0.3: the start-up transient impacts (alpha_ddot ~ 1e4 rad/s^2),
    # then rolling-sliding contact with Coulomb friction
    "coulomb e/a=0.3": ("sundar2014-friction", {"cam.runout": 5.25e-3}, 11.55, 1.0),
    # the same with tanh friction and a spring tilted by 4 degrees (eqs 4.44-4.46)
    "tanh, tilted spring": ("sundar2014-friction", {"cam.runout": 5.25e-3, "friction.law": "tanh",
                                                    "spring.tilt": math.radians(4.0)}, 11.55, 1.0),
    # chapter 3 rig: free flight between impacts, alpha_dot up to ~10 rad/s
    "impacts": ("sundar2014-impact", {}, 16.0, 2.0),
}


@pytest.fixture(scope="module", params=list(CASES))
def run(request):
    preset, changes, speed, revolutions = CASES[request.param]
    system = camdyn.load_system(preset).with_values(**changes)
    ds = camdyn.simulate(system, speed=speed, revolutions=revolutions, sample_rate=20e3)
    return system, ds, newton_euler(system, ds)


def test_reaction_is_newton_euler(run):
    system, ds, ne = run
    tol = ROUNDING * ne["force_scale"]
    np.testing.assert_allclose(ds.Nx.values, ne["N"][:, 0], rtol=0, atol=tol)
    np.testing.assert_allclose(ds.Ny.values, ne["N"][:, 1], rtol=0, atol=tol)
    # the terms that a wrong formula would drop or flip are present, far above the tolerance
    assert np.max(np.abs(ne["inertia"])) > PRESENT * tol
    assert np.max(np.abs(ne["centripetal"])) > PRESENT * tol
    assert np.max(np.abs(ne["friction"])) > PRESENT * tol


def test_inverse_recovers_the_contact_forces_from_the_independent_reaction(run):
    # the inverse is fed the reaction computed here, not the code's own (which would let an
    # error shared by the forward and inverse formulas cancel)
    system, ds, ne = run
    p = prepare(system).p
    fn, ff = contact_forces_from_reaction(ds.alpha.values, ds.alpha_dot.values, ds.alpha_ddot.values,
                                          ne["N"][:, 0].copy(), ne["N"][:, 1].copy(), p)
    tol = ROUNDING * ne["force_scale"]
    np.testing.assert_allclose(fn, ds.Fn.values, rtol=0, atol=tol)
    np.testing.assert_allclose(ff, ds.Ff.values, rtol=0, atol=tol)
    assert np.max(np.abs(ds.Fn.values)) > PRESENT * tol


def test_acceleration_is_the_moment_balance_with_independent_geometry_and_spring(run):
    system, ds, ne = run
    prep = prepare(system)
    ref = ReferenceModel(system, prep.theta0, 0.0)   # parametric geometry, eq 4.44 spring
    t, a, ad = ds.time.values, ds.alpha.values, ds.alpha_dot.values
    chi = np.array([ref.geometry(tt, x, v)[2] for tt, x, v in zip(t, a, ad)])
    fs = np.array([ref.spring(x)[0] for x in a])
    # both are closed-form in double precision: 1e-12 m of a ~0.09 m arm, 1e-9 of ~30 N
    np.testing.assert_allclose(ds.moment_arm.values, chi, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.Fs.values, fs, rtol=0, atol=1e-9 * np.max(np.abs(fs)))
    np.testing.assert_allclose(ds.alpha_ddot.values, ne["alpha_ddot"], rtol=0, atol=ROUNDING * ne["moment_scale"])
    # the friction moment Ff h alone is far above that tolerance
    friction = np.max(np.abs(ds.Ff.values)) * system.follower.surface_offset / system.follower.inertia
    assert friction > PRESENT * ROUNDING * ne["moment_scale"]


def test_acceleration_channel_is_the_derivative_of_the_rate(friction_rig):
    # sustained contact (the maximum-lift 0-state starts without impact), sampled finely:
    # the channel from the output code must be the derivative of the integrated alpha_dot
    s = friction_rig.with_values(**{"motion.zero_state": "maximum-lift"})
    fs = 400e3
    ds = camdyn.simulate(s, duration=5e-3, sample_rate=fs, rtol=1e-11, atol=1e-13)
    assert ds.in_contact.values.min() == 1
    ad, add = ds.alpha_dot.values, ds.alpha_ddot.values
    central = (ad[2:] - ad[:-2]) * (fs / 2)
    # central-difference error (omega h)^2 / 6 ~ 4e-5 of the ~1 kHz contact vibration at
    # h = 2.5 us, plus the integration error: 1e-3 of the channel's range; friction alone
    # (2 Ff h / I_P ~ 20 rad/s^2) is ~100 times that
    span = np.ptp(add)
    np.testing.assert_allclose(add[1:-1], central, rtol=0, atol=1e-3 * span)
    assert 2 * np.max(np.abs(ds.Ff.values)) * s.follower.surface_offset / s.follower.inertia > 50 * 1e-3 * span
