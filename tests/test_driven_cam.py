"""The cam as a rigid body: the rigid-shaft limit against the prescribed-speed model, the
energy balance of the whole mechanism, an independent SciPy solution of its equations,
the PI controller's zero mean speed error, and the refusal of bad drives."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import camdyn
from camdyn.errors import ParameterError
from camdyn.simulation.mechanisms import CamDrive, simulate_driven_cam
from camdyn.simulation.runner import prepare
from camdyn.testing.oracle import ReferenceModel


def test_an_infinitely_heavy_shaft_turns_at_constant_speed(friction_rig):
    # J = 1e9 kg m^2 and no torque: the contact torque (~0.1 N m) changes the speed by
    # ~1e-10 rad/s per second, so the follower must move as under the prescribed speed
    s = friction_rig.with_values(**{"motion.speed": 11.55})
    prescribed = camdyn.simulate(s, revolutions=2, sample_rate=20e3, rtol=1e-11, atol=1e-13)
    driven = simulate_driven_cam(s, CamDrive(shaft_inertia=1e9), revolutions=2, rtol=1e-11, atol=1e-13)
    np.testing.assert_allclose(driven.time.values, prescribed.time.values)
    scale = np.max(np.abs(prescribed.alpha.values))
    np.testing.assert_allclose(driven.alpha.values, prescribed.alpha.values, rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(driven.Fn.values, prescribed.Fn.values, rtol=0, atol=1e-6 * np.max(prescribed.Fn.values))
    assert driven.attrs["coefficient_of_fluctuation"] < 1e-9


def test_the_energy_of_the_mechanism_balances_the_drive_work(impact_rig):
    # undamped, frictionless contact, a circular cam (constant Hertz radius), a DC motor
    # and a light shaft: T_follower + T_shaft + V_spring + V_gravity + V_contact - W_drive
    # is constant through impacts. The potentials are written here from docs/model.md.
    s = impact_rig.with_values(**{"contact.damping": "none", "friction.law": "none", "motion.speed": 16.0})
    assert s.cam.is_circle and s.contact.kind == "point" and s.spring.tilt == 0.0
    omega = s.motion.angular_speed
    drive = CamDrive(shaft_inertia=2e-4, kind="motor", stall_torque=0.5, free_speed=1.1 * omega)
    ds = simulate_driven_cam(s, drive, revolutions=3, sample_rate=50e3, rtol=1e-11, atol=1e-13)
    assert ds.attrs["events"] > 4 and np.ptp(ds.in_contact.values) == 1   # impacts: contact and flight
    assert ds.attrs["coefficient_of_fluctuation"] > 1e-3
    f, sp, c = s.follower, s.spring, s.cam
    a, ad = ds.alpha.values, ds.alpha_dot.values
    kinetic = 0.5 * f.inertia * ad ** 2 + 0.5 * drive.shaft_inertia * ds.cam_speed.values ** 2
    # spring moment M = -Fs dx with Fs = ks (Ls - dy + dx tan a + 0.5 wb sec a): its potential
    v_spring = sp.stiffness * sp.attachment_x * (
        (sp.free_length - sp.ground_depth) * a - sp.attachment_x * np.log(np.cos(a))
        + 0.5 * f.width * np.log(1 / np.cos(a) + np.tan(a)))
    v_gravity = -f.mass * s.gravity * f.cg_distance * np.sin(a)
    rho_e = 1 / (1 / c.semi_major + 1 / f.pin_radius)
    estar = 1 / ((1 - c.poisson_ratio ** 2) / c.youngs_modulus + (1 - f.poisson_ratio ** 2) / f.youngs_modulus)
    delta = np.clip(ds.penetration.values, 0, None)
    v_contact = 0.4 * 4 / 3 * estar * math.sqrt(rho_e) * delta ** 2.5     # integral of K delta^1.5
    total = kinetic + v_spring + v_gravity + v_contact - ds.drive_work.values
    assert np.ptp(total) < 1e-6 * np.ptp(kinetic), np.ptp(total) / np.ptp(kinetic)
    # the cam's work on the follower is the shaft's loss: W_drive = dT_shaft + W_cam
    shaft = 0.5 * drive.shaft_inertia * ds.cam_speed.values ** 2
    np.testing.assert_allclose(ds.drive_work.values - (shaft - shaft[0]), ds.cam_work.values, rtol=0,
                               atol=1e-6 * np.ptp(kinetic))


def _scipy_driven_cam(system, drive, y0, t_eval):
    """The driven cam's equations written again on the independent geometry and forces of
    :class:`camdyn.testing.oracle.ReferenceModel` (tanh friction, the motor drive):
    ``J Theta'' = T_stall (1 - Theta'/omega_free) - c_b Theta' - T_c tanh(Theta'/omega_b)
    + T_contact`` with ``T_contact`` the moment about E of the follower's reaction
    ``+Fn n - Ff u`` at the contact point; contact begins and ends where the penetration
    crosses zero (terminal events, then a restart)."""
    prep = prepare(system)
    model = ReferenceModel(system, prep.theta0, prep.viscous_c)
    approach = system.contact.reference_velocity

    def penetration(t, y, *_):
        return model.geometry_at(y[2], y[3], y[0], y[1])[0]

    def rhs(t, y, contact):
        alpha, alpha_dot, theta, theta_dot = y
        model.cam = lambda _t: (theta, theta_dot)   # the shaft's state instead of the prescribed motion
        acc, fn, ff, _, _ = model.forces(t, [alpha, alpha_dot], contact, 1.0, approach)
        *_, arm, n, u = model.geometry_at(theta, 1.0, alpha, alpha_dot)   # arm = z x (Xc - E)
        torque = fn * (n @ arm) - ff * (u @ arm)
        drive_torque = drive.stall_torque * (1 - theta_dot / drive.free_speed)
        bearing = drive.bearing_viscous * theta_dot + drive.bearing_coulomb * math.tanh(theta_dot / drive.bearing_speed)
        return [alpha_dot, acc, theta_dot, (drive_torque - bearing + torque) / drive.shaft_inertia]

    out = np.full((4, t_eval.size), np.nan)
    t, y, contact, switches = 0.0, np.asarray(y0, float), penetration(0.0, y0) > 0, 0
    while t < t_eval[-1]:
        penetration.terminal, penetration.direction = True, -1 if contact else 1
        sol = solve_ivp(rhs, (t, t_eval[-1]), y, method="DOP853", args=(contact,), events=penetration,
                        dense_output=True, rtol=1e-12, atol=1e-14)
        inside = (t_eval >= t) & (t_eval <= sol.t[-1])
        out[:, inside] = sol.sol(t_eval[inside])
        t, y = sol.t[-1], sol.y[:, -1]
        if sol.status == 1:
            contact, switches = not contact, switches + 1
    return out, switches


def test_an_independent_scipy_solution_agrees(friction_rig):
    s = friction_rig.with_values(**{"motion.speed": 11.55, "friction.law": "tanh"})
    omega = s.motion.angular_speed
    drive = CamDrive(shaft_inertia=1e-4, kind="motor", stall_torque=1.0, free_speed=1.2 * omega,
                     bearing_viscous=1e-4, bearing_coulomb=0.02, bearing_speed=5.0)
    ds = simulate_driven_cam(s, drive, revolutions=1, sample_rate=10e3, rtol=1e-11, atol=1e-13)
    prep = prepare(s)
    ref, switches = _scipy_driven_cam(s, drive, [prep.equilibrium.angle, 0.0, prep.theta0, omega], ds.time.values)
    # the start from the static equilibrium launches the follower: it flies and lands
    assert switches >= 2 and np.ptp(ds.in_contact.values) == 1
    assert ds.attrs["coefficient_of_fluctuation"] > 0.01
    for i, name in enumerate(["alpha", "alpha_dot", "cam_angle", "cam_speed"]):
        scale = np.max(np.abs(ref[i]))
        np.testing.assert_allclose(ds[name].values, ref[i], rtol=0, atol=1e-6 * scale, err_msg=name)


def test_the_speed_controller_holds_the_mean_speed(friction_rig):
    # PI control: z' = omega_ref - Theta', so over a periodic steady state the mean speed
    # equals the set point exactly (z returns to its value); the run's last revolutions
    # are close to periodic (the slowest closed-loop mode has decayed), which bounds the check
    s = friction_rig.with_values(**{"motion.speed": 11.55})
    target = 1.05 * s.motion.angular_speed
    drive = CamDrive(shaft_inertia=1e-4, kind="controller", torque=0.0, proportional=0.02, integral=0.5,
                     target_speed=target, bearing_viscous=2e-4)
    ds = simulate_driven_cam(s, drive, duration=1.5, sample_rate=20e3, rtol=1e-10, atol=1e-12)
    last = ds.time.values >= 1.5 - 2 * 2 * math.pi / target
    cycles = ds.cam_angle.values[last]
    mean = (cycles[-1] - cycles[0]) / (ds.time.values[last][-1] - ds.time.values[last][0])
    assert abs(mean / target - 1) < 1e-5, mean / target   # measured 1.3e-7


@pytest.mark.parametrize("kwargs, words", [
    (dict(shaft_inertia=0.0), "shaft_inertia must be positive"),
    (dict(shaft_inertia=1.0, kind="turbine"), "drive kind must be one of"),
    (dict(shaft_inertia=1.0, kind="motor", stall_torque=1.0), "finite, non-zero free_speed"),
    (dict(shaft_inertia=1.0, bearing_coulomb=-1.0), "bearing_coulomb must not be negative"),
    (dict(shaft_inertia=math.nan), "must be a number"),
])
def test_bad_drives_are_refused(kwargs, words):
    with pytest.raises(ParameterError, match=words):
        CamDrive(**kwargs)


def test_an_oscillating_cam_is_refused(friction_rig):
    s = friction_rig.with_values(**{"motion.kind": "oscillating", "motion.amplitude": 0.6, "motion.frequency": 3.0})
    with pytest.raises(ParameterError, match="constant motion"):
        simulate_driven_cam(s, CamDrive(shaft_inertia=1.0))


def test_bad_run_settings_are_refused(friction_rig):
    drive = CamDrive(shaft_inertia=1e-3)
    with pytest.raises(ParameterError, match="duration"):
        simulate_driven_cam(friction_rig, drive, duration=-1.0)
    with pytest.raises(ParameterError, match="give a duration"):
        simulate_driven_cam(friction_rig, drive, initial_speed=0.0)
    with pytest.raises(ParameterError, match="initial_speed must be finite"):
        simulate_driven_cam(friction_rig, drive, initial_speed=math.inf)


def test_the_rosenbrock_stepper_agrees_with_dop853(friction_rig):
    # the driven cam's Jacobian (central differences) serves RODAS4: the same run by
    # both steppers agrees far inside the 1e-6 the tests above use
    s = friction_rig.with_values(**{"motion.speed": 11.55, "friction.law": "tanh"})
    drive = CamDrive(shaft_inertia=1e-4, kind="controller", proportional=0.02, integral=0.5,
                     target_speed=s.motion.angular_speed)
    runs = [simulate_driven_cam(s, drive, revolutions=0.5, sample_rate=5e3, rtol=1e-10, atol=1e-12, method=m)
            for m in ("dop853", "rosenbrock")]
    for name in ("alpha", "cam_speed"):
        scale = np.max(np.abs(runs[0][name].values))
        np.testing.assert_allclose(runs[1][name].values, runs[0][name].values, rtol=0, atol=1e-6 * scale)
