"""The rocking follower on a flexible pivot: the stiff-bearing limit against the rigid
pivot, the energy balance without damping or friction, an independent SciPy solution of
its equations, and the refusal of bad bearings."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import camdyn
from camdyn.errors import ParameterError
from camdyn.simulation.flexible_pivot import chapter3_flexible_pivot, simulate_flexible_pivot


@pytest.fixture(scope="module")
def rig():
    return chapter3_flexible_pivot().system


def _critical(kp, system, ratio=1.0):
    """Bearing damping [N s/m] of a damping ratio ``ratio`` for the follower's mass on ``kp``."""
    return 2.0 * ratio * math.sqrt(kp * system.follower.mass)


def test_a_stiff_bearing_gives_the_rigid_pivot(rig):
    # kp -> infinity with a critically damped bearing, over three quarters of a revolution
    # in which the follower leaves the cam, lands and bounces: in the landing the contact's
    # stiffness (about 5e7 N/m at its peak force) is in series with the bearing's, so the
    # follower angle must approach the rigid pivot's as 1/kp once kp is far above it, and
    # the bearing's force the rigid pivot's reaction
    s = rig.with_values(**{"friction.law": "tanh", "friction.smoothing": 10.0})
    rigid = camdyn.simulate(s, revolutions=0.75, sample_rate=10e3, rtol=1e-11, atol=1e-13)
    assert np.count_nonzero(np.diff(rigid.in_contact.values)) >= 3   # it leaves the cam, lands, bounces
    scale = np.max(np.abs(rigid.alpha.values))
    force = np.max(np.hypot(rigid.Nx.values, rigid.Ny.values))
    errors, force_errors = [], []
    for kp in (1e8, 1e9, 1e10, 1e11, 1e12):
        ds = simulate_flexible_pivot(s, kp, _critical(kp, s), revolutions=0.75, sample_rate=10e3, rtol=1e-11,
                                     atol=1e-13)
        errors.append(np.max(np.abs(ds.alpha.values - rigid.alpha.values)) / scale)
        force_errors.append(max(np.max(np.abs(ds.Nx.values - rigid.Nx.values)),
                                np.max(np.abs(ds.Ny.values - rigid.Ny.values))) / force)
    assert all(b < a for a, b in zip(errors, errors[1:])), errors
    assert errors[-1] < 1e-5, errors
    assert errors[-1] < 0.2 * errors[-2] and errors[-2] < 0.2 * errors[-3], errors   # 1/kp at the stiff end
    assert all(b < a for a, b in zip(force_errors, force_errors[1:])), force_errors
    assert force_errors[-1] < 1e-4, force_errors


def _spring_potential(alpha, u, v, system):
    """The spring's potential [J] on a pivot displaced by ``(u, v)`` [m] (untilted spring):
    the rigid pivot's ``V_r`` (moment ``-Fs dx``, ``Fs = ks (Ls - dy + dx tan a + 0.5 wb
    sec a)``) less ``Fs s`` plus ``ks s^2 / 2``, ``s = v`` the shortening of the vertical
    spring by the translation of its follower end."""
    sp, wb = system.spring, system.follower.width
    ks, dx = sp.stiffness, sp.attachment_x
    v_rigid = ks * dx * ((sp.free_length - sp.ground_depth) * alpha - dx * np.log(np.cos(alpha))
                         + 0.5 * wb * np.log(1 / np.cos(alpha) + np.tan(alpha)))
    fs = ks * (sp.free_length - sp.ground_depth + dx * np.tan(alpha) + 0.5 * wb / np.cos(alpha))
    return v_rigid - fs * v + 0.5 * ks * v * v


def _hertz(system):
    """Hertz coefficient K [N/m^1.5] of the crossed cylinders (eq 3.11): circle of radius
    rc against the pin rd."""
    c, f = system.cam, system.follower
    rho_e = 1 / (1 / c.semi_major + 1 / f.pin_radius)
    estar = 1 / ((1 - c.poisson_ratio ** 2) / c.youngs_modulus + (1 - f.poisson_ratio ** 2) / f.youngs_modulus)
    return 4 / 3 * estar * math.sqrt(rho_e)


def test_energy_balances_without_damping_or_friction(rig):
    # T + V_spring + V_gravity + V_bearing + V_contact - W_cam is constant; the bearing's
    # damper removes W_bearing. Everything written here from the model's definition.
    s = rig.with_values(**{"contact.damping": "none", "friction.law": "none"})
    assert s.cam.is_circle and s.spring.tilt == 0.0
    f = s.follower
    for kp, cp in ((5e6, 0.0), (5e6, 50.0)):
        ds = simulate_flexible_pivot(s, kp, cp, revolutions=2, sample_rate=50e3, rtol=1e-11, atol=1e-14)
        assert ds.attrs["events"] >= 4 and np.ptp(ds.in_contact.values) == 1   # impacts: contact and flight
        a, ad = ds.alpha.values, ds.alpha_dot.values
        u, ud, v, vd = ds.u.values, ds.u_dot.values, ds.v.values, ds.v_dot.values
        lcg = f.cg_distance
        vgx = ud - lcg * ad * np.sin(a)        # v_G = P' - l_cg alpha' n
        vgy = vd - lcg * ad * np.cos(a)
        kinetic = 0.5 * f.mass * (vgx ** 2 + vgy ** 2) + 0.5 * (f.inertia - f.mass * lcg ** 2) * ad ** 2
        v_gravity = f.mass * s.gravity * (v - lcg * np.sin(a))
        v_bearing = 0.5 * kp * (u ** 2 + v ** 2)
        v_contact = 0.4 * _hertz(s) * np.clip(ds.penetration.values, 0, None) ** 2.5
        total = (kinetic + _spring_potential(a, u, v, s) + v_gravity + v_bearing + v_contact
                 - ds.cam_work.values + ds.bearing_work.values)
        assert np.ptp(total) < 1e-6 * np.ptp(kinetic), (cp, np.ptp(total) / np.ptp(kinetic))
        if cp > 0.0:
            assert ds.bearing_work.values[-1] > 1e-3 * np.ptp(kinetic)   # the damper did work


def _scipy_flexible_pivot(system, kp, cp, y0, theta0, t_eval):
    """The flexible pivot written again for a circular cam, by Newton-Euler: ``m a_G = F``
    and the moment about the moving pivot, ``M_P = I_P alpha'' + (r_G x m a_P).(-z)``
    (clockwise), a 3 x 3 linear solve per call. The contact point of a circle is
    ``Xc = Gc - rc n``; the forces act at their points; the spring's generalized forces
    are minus the gradient of its potential (:func:`_spring_potential`), by complex-step
    differentiation."""
    c, f = system.cam, system.follower
    m, lcg, inertia, g = f.mass, f.cg_distance, f.inertia, system.gravity
    h = 0.5 * f.width + 2.0 * f.pin_radius
    big_k, beta, n_exp = _hertz(system), system.contact.beta, system.contact.exponent
    mu, smooth = system.friction.coefficient, system.friction.smoothing
    omega = system.motion.angular_speed
    e0 = np.array([c.pivot_x, c.pivot_y])

    def cross(a, b):
        return a[0] * b[1] - a[1] * b[0]

    def contact(t, y):
        alpha, ad, pos, vel = y[0], y[1], y[[2, 4]], y[[3, 5]]
        n = np.array([math.sin(alpha), math.cos(alpha)])
        th = theta0 + omega * t
        centre = e0 - c.runout * np.array([math.cos(th), math.sin(th)])
        xc = centre - c.semi_major * n
        delta = h + c.semi_major - n @ (centre - pos)
        xb = xc + delta * n                                   # the follower's surface point
        v_cam = omega * np.array([-(xc - e0)[1], (xc - e0)[0]])
        r = xb - pos
        v_fol = vel - ad * np.array([-r[1], r[0]])            # clockwise rotation
        return delta, (v_fol - v_cam) @ n, (v_cam - v_fol) @ np.array([math.cos(alpha), -math.sin(alpha)]), xb

    def spring_forces(alpha, u, v):   # minus the gradient, by complex steps (exact to rounding)
        qa = -_spring_potential(alpha + 1e-30j, u, v, system).imag / 1e-30
        qv = -_spring_potential(alpha, u, v + 1e-30j, system).imag / 1e-30
        return qa, 0.0, qv

    def rhs(t, y, in_contact):
        alpha, ad, u, ud, v, vd = y
        n = np.array([math.sin(alpha), math.cos(alpha)])
        ub = np.array([math.cos(alpha), -math.sin(alpha)])
        pos = np.array([u, v])
        bearing = -kp * pos - cp * np.array([ud, vd])
        qa, qu, qv = spring_forces(alpha, u, v)
        force = bearing + np.array([qu, qv]) + np.array([0.0, -m * g])
        moment = qa - cross(lcg * ub, np.array([0.0, -m * g]))   # clockwise about P
        if in_contact:
            delta, delta_dot, vr, xb = contact(t, y)
            fn = big_k * abs(delta) ** 1.5 * math.copysign(1, delta) + beta * abs(delta) ** n_exp * delta_dot
            fc = -fn * n + mu * math.tanh(smooth * vr) * fn * ub
            force = force + fc
            moment -= cross(xb - pos, fc)
        # unknowns (alpha'', u'', v''): a_G = P'' - l alpha'' n - l alpha'^2 ub
        a_mat = np.zeros((3, 3))
        b = np.zeros(3)
        a_mat[0, 0] = inertia
        a_mat[0, 1:] = -m * lcg * np.array([-ub[1], ub[0]])     # -(r_G x m P'').z
        b[0] = moment
        a_mat[1:, 0] = -m * lcg * n
        a_mat[1:, 1:] = m * np.eye(2)
        b[1:] = force + m * lcg * ad * ad * ub
        acc = np.linalg.solve(a_mat, b)
        return [ad, acc[0], ud, acc[1], vd, acc[2]]

    def penetration(t, y, *_):
        return contact(t, y)[0]

    out = np.full((6, t_eval.size), np.nan)
    t, y, switches = 0.0, np.asarray(y0, float), 0
    in_contact = penetration(0.0, y) > 0
    while t < t_eval[-1]:
        penetration.terminal, penetration.direction = True, -1 if in_contact else 1
        sol = solve_ivp(rhs, (t, t_eval[-1]), y, method="DOP853", args=(in_contact,), events=penetration,
                        dense_output=True, rtol=1e-12, atol=1e-15, max_step=1e-4)
        inside = (t_eval >= t) & (t_eval <= sol.t[-1])
        out[:, inside] = sol.sol(t_eval[inside])
        t, y = sol.t[-1], sol.y[:, -1]
        if sol.status == 1:
            in_contact, switches = not in_contact, switches + 1
    return out, switches


def test_an_independent_scipy_solution_agrees(rig):
    s = rig.with_values(**{"friction.law": "tanh", "friction.smoothing": 10.0})
    kp, cp = 5e6, 100.0
    ds = simulate_flexible_pivot(s, kp, cp, revolutions=1, sample_rate=5e3, rtol=1e-11, atol=1e-14)
    y0 = [ds.attrs["initial_alpha"], 0.0, ds.attrs["initial_u"], 0.0, ds.attrs["initial_v"], 0.0]
    ref, switches = _scipy_flexible_pivot(s, kp, cp, y0, ds.attrs["theta0"], ds.time.values)
    assert switches >= 2 and np.ptp(ds.in_contact.values) == 1    # an impact: flight and landing
    for i, name in enumerate(["alpha", "alpha_dot", "u", "u_dot", "v", "v_dot"]):
        scale = np.max(np.abs(ref[i]))
        np.testing.assert_allclose(ds[name].values, ref[i], rtol=0, atol=1e-6 * scale, err_msg=name)


@pytest.mark.parametrize("stiffness, damping, match", [
    (0.0, 1.0, "pivot_stiffness"), (-1e7, 1.0, "pivot_stiffness"), (math.inf, 1.0, "pivot_stiffness"),
    (math.nan, 1.0, "pivot_stiffness"), ("1e7", 1.0, "pivot_stiffness"), (1e7, -1.0, "pivot_damping"),
    (1e7, math.nan, "pivot_damping"), (1e7, math.inf, "pivot_damping"),
])
def test_bad_bearings_are_refused(rig, stiffness, damping, match):
    with pytest.raises(ParameterError, match=match):
        simulate_flexible_pivot(rig, stiffness, damping)


def test_bad_followers_and_motions_are_refused(rig):
    f = rig.follower
    with pytest.raises(ParameterError, match="centre of gravity"):
        simulate_flexible_pivot(rig.with_values(**{"follower.inertia": f.mass * f.cg_distance ** 2}), 1e7, 1.0)
    with pytest.raises(ParameterError, match="constant"):
        simulate_flexible_pivot(rig.with_values(**{"motion.kind": "oscillating", "motion.frequency": 5.0,
                                                   "motion.amplitude": 0.5}), 1e7, 1.0)
    with pytest.raises(ParameterError, match="expected a camdyn System"):
        simulate_flexible_pivot("sundar2014-impact", 1e7, 1.0)
    with pytest.raises(ParameterError, match="rtol"):
        simulate_flexible_pivot(rig, 1e7, 1.0, rtol=0.5)


def test_a_cam_profile_table_is_refused():
    import dataclasses

    from camdyn.model.profiles import eccentric_circle
    system = camdyn.load_system("sundar2014-impact")
    on_profile = dataclasses.replace(system, profile=eccentric_circle(system.cam.semi_major, system.cam.runout))
    with pytest.raises(ParameterError, match="profile"):
        simulate_flexible_pivot(on_profile, 2e7, 200.0)
