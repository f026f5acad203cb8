"""Two rocking followers on one driven cam: the symmetric placement against the single
driven follower, the energy balance with the drive's work, an independent SciPy solution
of the equations, the follower dimension of the result, and the refusals."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from camdyn.errors import ParameterError
from camdyn.integrator import driver
from camdyn.model import driven_cam
from camdyn.model import layout as L
from camdyn.model import two_followers as pair
from camdyn.simulation.mechanisms import DRIVEN_STATE, CamDrive, simulate_driven_cam
from camdyn.simulation.runner import prepare
from camdyn.simulation.two_followers import drum_brake, pack_two_followers, simulate_two_followers
from camdyn.systems import registry
from camdyn.testing.oracle import ReferenceModel


def test_two_opposite_identical_followers_each_match_the_single_follower(friction_rig):
    # a cam symmetric under half a turn (an ellipse about its centre: no runout) and two
    # identical followers half a turn apart: both move as one follower does, and the
    # shaft takes twice its reaction. J Theta'' = T_drive + 2 T_contact is the single
    # follower's shaft with J/2 and half the drive and bearing torques.
    s = friction_rig.with_values(**{"motion.speed": 11.55, "cam.runout": 0.0, "cam.semi_minor": 0.016,
                                    "environment.gravity": 0.0})
    omega = s.motion.angular_speed
    drive = CamDrive(shaft_inertia=2e-4, kind="motor", stall_torque=1.0, free_speed=1.2 * omega,
                     bearing_viscous=2e-4)
    half = CamDrive(shaft_inertia=1e-4, kind="motor", stall_torque=0.5, free_speed=1.2 * omega,
                    bearing_viscous=1e-4)
    both = simulate_two_followers(s, drive, placement=math.pi, revolutions=0.5, sample_rate=10e3, rtol=1e-12,
                                  atol=1e-14)
    one = simulate_driven_cam(s, half, revolutions=0.5, sample_rate=10e3, rtol=1e-12, atol=1e-14)
    assert one.attrs["coefficient_of_fluctuation"] > 1e-3   # the shaft's speed does respond
    for name in ("alpha", "alpha_dot"):
        scale = np.max(np.abs(one[name].values))
        for k in (1, 2):
            np.testing.assert_allclose(both[name].sel(follower=k).values, one[name].values, rtol=0,
                                       atol=1e-9 * scale, err_msg=f"{name} of follower {k}")
    for name in ("cam_angle", "cam_speed"):
        np.testing.assert_allclose(both[name].values, one[name].values, rtol=0,
                                   atol=1e-9 * np.max(np.abs(one[name].values)), err_msg=name)
    # the shaft's books: the cam's work on both followers is twice that on the one
    np.testing.assert_allclose(both.cam_work.sum("follower").values, 2 * one.cam_work.values, rtol=0,
                               atol=1e-9 * np.max(np.abs(one.cam_work.values)))
    # the reaction torque at one state is doubled. (Along the runs it agrees to
    # about 2e-8 only: the normal force follows the micrometre penetration, a small
    # difference of millimetre lengths, so the 1e-10 agreement of the angles becomes
    # about 1e-8 in the force.)
    p_one = np.r_[prepare(s).p, half.slots()]
    p_both, _ = pack_two_followers(s, s, math.pi, drive)
    for row in range(0, one.time.size, 7):
        y = np.array([one[name].values[row] for name, *_ in DRIVEN_STATE])
        mode = np.empty(L.MODE_SIZE)
        registry.initial_mode(registry.DRIVEN_CAM, 0.0, y, p_one, mode)
        single = driven_cam.accelerations(y, mode, p_one)[4]
        y2 = np.r_[y[:2], y[:2], y[2:5], y[5:6], 0.0, y[7], y[7]]
        modes = np.empty(pair.MODE_SIZE)
        pair.initial_mode(0.0, y2, p_both, modes)
        torque1, torque2 = pair.accelerations(y2, modes, p_both)[5:7]
        assert torque1 == single   # follower 1 is the single follower's code on the same numbers
        # follower 2 sees the cam at Theta - pi: the rounding of that angle (1e-16) is
        # amplified by the penetration's conditioning (millimetres over micrometres, ~1e4)
        assert torque2 == pytest.approx(single, rel=1e-9, abs=1e-15)


def test_the_energy_of_both_followers_and_the_shaft_balances_the_drive_work(impact_rig):
    # undamped, frictionless contacts, a circular eccentric cam, follower 2 placed 2 rad
    # round with a stiffer spring, a DC motor and a light shaft: the kinetic energies, the
    # springs' and contacts' potentials less the drive's work stay constant through
    # impacts. The potentials are written here from docs/model.md (as in test_driven_cam).
    s = impact_rig.with_values(**{"contact.damping": "none", "friction.law": "none", "motion.speed": 16.0,
                                  "environment.gravity": 0.0})
    second = s.with_values(**{"spring.stiffness": 1.3 * s.spring.stiffness})
    assert s.cam.is_circle and s.contact.kind == "point" and s.spring.tilt == 0.0
    omega = s.motion.angular_speed
    drive = CamDrive(shaft_inertia=2e-4, kind="motor", stall_torque=0.5, free_speed=1.1 * omega)
    ds = simulate_two_followers(s, drive, second=second, placement=2.0, revolutions=2, sample_rate=50e3,
                                rtol=1e-11, atol=1e-13)
    assert ds.attrs["events"] > 4 and (np.ptp(ds.in_contact.values, axis=0) == 1).all()
    assert ds.attrs["coefficient_of_fluctuation"] > 1e-3
    c = s.cam
    rho_e = 1 / (1 / c.semi_major + 1 / s.follower.pin_radius)
    estar = 1 / ((1 - c.poisson_ratio ** 2) / c.youngs_modulus + (1 - s.follower.poisson_ratio ** 2)
                 / s.follower.youngs_modulus)
    total = 0.5 * drive.shaft_inertia * ds.cam_speed.values ** 2 - ds.drive_work.values
    kinetic = 0.5 * drive.shaft_inertia * ds.cam_speed.values ** 2
    for k, sk in ((1, s), (2, second)):
        f, sp = sk.follower, sk.spring
        a, ad = ds.alpha.sel(follower=k).values, ds.alpha_dot.sel(follower=k).values
        v_spring = sp.stiffness * sp.attachment_x * (
            (sp.free_length - sp.ground_depth) * a - sp.attachment_x * np.log(np.cos(a))
            + 0.5 * f.width * np.log(1 / np.cos(a) + np.tan(a)))
        delta = np.clip(ds.penetration.sel(follower=k).values, 0, None)
        v_contact = 0.4 * 4 / 3 * estar * math.sqrt(rho_e) * delta ** 2.5
        total = total + 0.5 * f.inertia * ad ** 2 + v_spring + v_contact
        kinetic = kinetic + 0.5 * f.inertia * ad ** 2
    assert np.ptp(total) < 1e-6 * np.ptp(kinetic), np.ptp(total) / np.ptp(kinetic)
    # the shaft's books: W_drive = dT_shaft + W_cam,1 + W_cam,2
    shaft = 0.5 * drive.shaft_inertia * ds.cam_speed.values ** 2
    np.testing.assert_allclose(ds.drive_work.values - (shaft - shaft[0]), ds.cam_work.sum("follower").values,
                               rtol=0, atol=1e-6 * np.ptp(kinetic))


def _scipy_two_followers(models, phi, drive, y0, t_eval):
    """The two followers' and the shaft's equations written again on the independent
    geometry and forces of :class:`camdyn.testing.oracle.ReferenceModel` (one per
    follower; follower 2 sees the cam at ``Theta - phi``), with the DC motor and the
    bearing: ``J Theta'' = T_stall (1 - Theta'/omega_free) - c_b Theta' + T_1 + T_2``,
    ``T_i`` the moment about E of follower i's reaction ``+Fn n - Ff u`` at its contact
    point. Contacts begin and end where a penetration crosses zero (terminal events,
    then a restart)."""
    shifts = (0.0, phi)

    def penetration(i):
        def event(t, y, *_):
            return models[i].geometry_at(y[4] - shifts[i], y[5], y[2 * i], y[2 * i + 1])[0]
        return event

    events = [penetration(0), penetration(1)]

    def rhs(t, y, contact):
        theta, theta_dot = y[4], y[5]
        out = [0.0] * 6
        torque = drive.stall_torque * (1 - theta_dot / drive.free_speed) - drive.bearing_viscous * theta_dot
        for i, model in enumerate(models):
            th = theta - shifts[i]
            model.cam = lambda _t, th=th: (th, theta_dot)
            acc, fn, ff, _, _ = model.forces(t, [y[2 * i], y[2 * i + 1]], contact[i], 1.0,
                                             model.s.contact.reference_velocity)
            *_, arm, n, u = model.geometry_at(th, 1.0, y[2 * i], y[2 * i + 1])   # arm = z x (Xc - E)
            if contact[i]:
                torque += fn * (n @ arm) - ff * (u @ arm)
            out[2 * i], out[2 * i + 1] = y[2 * i + 1], acc
        out[4], out[5] = theta_dot, torque / drive.shaft_inertia
        return out

    out = np.full((6, t_eval.size), np.nan)
    t, y = 0.0, np.asarray(y0, float)
    contact = [events[i](0.0, y) > 0 for i in range(2)]
    switches = 0
    while t < t_eval[-1]:
        for i in range(2):
            events[i].terminal, events[i].direction = True, -1 if contact[i] else 1
        sol = solve_ivp(rhs, (t, t_eval[-1]), y, method="DOP853", args=(tuple(contact),), events=events,
                        dense_output=True, rtol=1e-12, atol=1e-14)
        inside = (t_eval >= t) & (t_eval <= sol.t[-1])
        if inside.any():
            out[:, inside] = sol.sol(t_eval[inside])
        t, y = sol.t[-1], sol.y[:, -1]
        if sol.status == 1:
            for i in range(2):
                if sol.t_events[i].size:
                    contact[i] = not contact[i]
                    switches += 1
    return out, switches


def test_an_independent_scipy_solution_agrees(friction_rig):
    s = friction_rig.with_values(**{"motion.speed": 11.55, "friction.law": "tanh", "environment.gravity": 0.0})
    second = s.with_values(**{"spring.stiffness": 0.8 * s.spring.stiffness})
    phi = 2.5
    omega = s.motion.angular_speed
    drive = CamDrive(shaft_inertia=1e-4, kind="motor", stall_torque=1.5, free_speed=1.2 * omega,
                     bearing_viscous=1e-4)
    ds = simulate_two_followers(s, drive, second=second, placement=phi, revolutions=1, sample_rate=10e3,
                                rtol=1e-11, atol=1e-13)
    p, y0 = pack_two_followers(s, second, phi, drive)
    models = (ReferenceModel(s, y0[4], p[L.VISCOUS_C]),
              ReferenceModel(second, y0[4] - phi, p[pair.SECOND + L.VISCOUS_C]))
    ref, switches = _scipy_two_followers(models, phi, drive, y0[:6], ds.time.values)
    assert switches >= 2 and ds.attrs["coefficient_of_fluctuation"] > 0.01
    names = [("alpha", 1), ("alpha_dot", 1), ("alpha", 2), ("alpha_dot", 2), ("cam_angle", None),
             ("cam_speed", None)]
    for i, (name, k) in enumerate(names):
        got = ds[name].values if k is None else ds[name].sel(follower=k).values
        scale = np.max(np.abs(ref[i]))
        np.testing.assert_allclose(got, ref[i], rtol=0, atol=1e-6 * scale, err_msg=f"{name} {k}")


def test_the_drum_brake_carries_a_follower_dimension_with_units():
    rig = drum_brake()
    ds = simulate_two_followers(rig.system, rig.drive, second=rig.second, placement=rig.placement,
                                revolutions=0.25, sample_rate=5e3)
    assert ds.sizes["follower"] == 2 and list(ds.follower.values) == [1, 2]
    assert ds.alpha.dims == ("time", "follower") and ds.alpha.attrs["units"] == "rad"
    assert ds.Fn.dims == ("time", "follower") and ds.Fn.attrs["units"] == "N"
    assert ds.cam_speed.dims == ("time",) and ds.cam_speed.attrs["units"] == "rad/s"
    assert ds.attrs["placement"] == math.pi
    # the total reaction torque is the sum of the followers'
    np.testing.assert_array_equal(ds.contact_torque_total.values, ds.contact_torque.sum("follower").values)


def test_bad_pairs_are_refused(friction_rig, impact_rig):
    drive = CamDrive(shaft_inertia=1e-3)
    with pytest.raises(ParameterError, match="ride on one cam"):
        simulate_two_followers(friction_rig, drive, second=impact_rig, placement=0.0)
    with pytest.raises(ParameterError, match="gravity"):
        simulate_two_followers(friction_rig, drive, placement=1.0)
    with pytest.raises(ParameterError, match="placement must be finite"):
        simulate_two_followers(friction_rig, drive, placement=math.nan)
    s = friction_rig.with_values(**{"motion.kind": "oscillating", "motion.amplitude": 0.6, "motion.frequency": 3.0})
    with pytest.raises(ParameterError, match="constant motion"):
        simulate_two_followers(s, drive, placement=0.0)
    with pytest.raises(ParameterError, match="CamDrive"):
        simulate_two_followers(friction_rig, "motor", placement=0.0)


def _statics(system, theta, alpha):
    """Normal force [N] and the friction force [N] along u that holds the follower at
    rest at ``alpha`` [rad] on a cam at rest at ``theta`` [rad]: its moment balance
    ``0 = M_spring + Fn chi + F h`` about P, with the forces of the independent
    :class:`camdyn.testing.oracle.ReferenceModel` (the friction left out: slip 0)."""
    model = ReferenceModel(system, theta)
    model.cam = lambda _t: (theta, 0.0)
    acc, fn, _, _, _ = model.forces(0.0, [alpha, 0.0], True, 0.0, system.contact.reference_velocity)
    h = 0.5 * system.follower.width + 2.0 * system.follower.pin_radius
    return fn, -acc * system.follower.inertia / h


@pytest.mark.parametrize("offset, sticks", [(-5e-7, True), (2e-7, False)])
def test_a_follower_at_rest_on_a_still_cam_sticks_inside_the_friction_cone(friction_rig, offset, sticks):
    # the cam held still (J = 1e9 kg m^2, no drive) and follower 1 at rest a little off
    # its equilibrium: it sticks, and stays, while the friction statics needs is within
    # mu_s Fn (F/Fn = -0.11 at -0.5 urad), and slides at once where it is not (0.48 > 0.4)
    s = friction_rig.with_values(**{"environment.gravity": 0.0})
    drive = CamDrive(shaft_inertia=1e9)
    _, y0 = pack_two_followers(s, s, math.pi, drive, initial_speed=0.0, static_friction=0.4)
    alpha = y0[0] + offset
    fn, needed = _statics(s, y0[4], alpha)
    assert (abs(needed) <= 0.4 * fn) == sticks
    ds = simulate_two_followers(s, drive, placement=math.pi, duration=0.02, sample_rate=5e3, initial_speed=0.0,
                                static_friction=0.4, initial_angles=(alpha, y0[2]))
    first = ds.sel(follower=1)
    if sticks:
        assert (first.sticking.values == 1).all()
        np.testing.assert_allclose(first.alpha.values, alpha, rtol=0, atol=1e-12)
        # the holding force at each sampled state: the contact's stiffness (~3e6 N/rad)
        # turns the 1e-14 rad the angle drifts by into 3e-8 N
        statics = np.array([_statics(s, theta, a) for theta, a in zip(first.cam_angle.values, first.alpha.values)])
        np.testing.assert_allclose(first.Fn.values, statics[:, 0], rtol=1e-9)
        np.testing.assert_allclose(first.Ff.values, statics[:, 1], rtol=1e-9)
        np.testing.assert_allclose(first.Ff.values, needed, rtol=1e-6)
    else:
        assert first.sticking.values[0] == 0
        assert np.ptp(first.alpha.values) > 1e-9


def test_a_stick_slip_cycle_keeps_the_switch_model_laws():
    # the drum brake under a slow PI speed controller: the friction stops the cam, both
    # contacts stick, the controller's integral winds the torque up until they break
    # loose. While a contact sticks its sliding velocity stays zero and its friction
    # inside mu_s Fn; while it slides (in contact) its friction is mu_k Fn exactly.
    # Follower 1 sticks 3 times and slips twice, follower 2 sticks and slips twice, both
    # breaking loose at 71 ms (with follower 2's contact damping 5 % below follower 1's,
    # before both took the single follower's, the contacts alternated some 18 times).
    rig = drum_brake()
    drive = CamDrive(shaft_inertia=2e-4, kind="controller", proportional=0.01, integral=0.5, target_speed=2.0)
    ds = simulate_two_followers(rig.system, drive, second=rig.second, placement=rig.placement, duration=0.1,
                                sample_rate=20e3, initial_speed=2.0, static_friction=0.4, rtol=1e-10, atol=1e-12)
    kinds = ds.transition_kind.values
    for k in (1, 2):
        mine = kinds[ds.transition_follower.values == k]
        assert (mine == "stick").sum() >= 2 and (mine == "slip").sum() >= 2
        f = ds.sel(follower=k)
        stuck = f.sticking.values == 1
        sliding = ~stuck & (f.in_contact.values == 1)
        assert stuck.sum() > 100 and sliding.sum() > 100
        assert np.max(np.abs(f.sliding_velocity.values[stuck])) < 1e-12 * np.max(np.abs(f.sliding_velocity.values))
        assert np.all(np.abs(f.Ff.values[stuck]) <= 0.4 * f.Fn.values[stuck] * (1 + 1e-12))
        np.testing.assert_allclose(np.abs(f.Ff.values[sliding]), 0.3 * f.Fn.values[sliding], rtol=1e-12)
    assert np.all(np.diff(ds.transition_time.values) >= 0)
    assert ds.cam_speed.values.min() < 1e-2 * 2.0 < ds.cam_speed.values.max()   # it stops, then runs again


def test_bad_static_friction_is_refused(friction_rig):
    drive = CamDrive(shaft_inertia=1e-3)
    with pytest.raises(ParameterError, match="must not be below the kinetic"):
        simulate_two_followers(friction_rig, drive, placement=0.0, static_friction=0.1)
    with pytest.raises(ParameterError, match="needs Coulomb friction"):
        simulate_two_followers(friction_rig.with_values(**{"friction.law": "tanh"}), drive, placement=0.0,
                               static_friction=0.5)
    with pytest.raises(ParameterError, match="one or two finite"):
        simulate_two_followers(friction_rig, drive, placement=0.0, static_friction=(0.4, 0.5, 0.6))
    with pytest.raises(ParameterError, match="initial_angles"):
        simulate_two_followers(friction_rig, drive, placement=0.0, initial_angles=(0.1,))


def test_the_sprag_margin_is_the_contact_force_lever_about_the_pivot():
    # chi + mu_k s h from the reference model's independent geometry, on the drum brake
    # turning backwards (s = -1: the margin is chi - mu_k h); no sprag at mu_k = 0.3
    rig = drum_brake()
    ds = simulate_two_followers(rig.system, CamDrive(shaft_inertia=1e-2), second=rig.second,
                                placement=rig.placement, duration=0.01, sample_rate=20e3, initial_speed=-5.0)
    s = rig.system
    h = 0.5 * s.follower.width + 2.0 * s.follower.pin_radius
    for k, shift in ((1, 0.0), (2, rig.placement)):
        f = ds.sel(follower=k)
        touching = f.in_contact.values == 1
        assert touching.sum() > 10 and np.all(f.sliding_velocity.values[touching] < 0)
        model = ReferenceModel(s, 0.0)
        chi = np.array([model.geometry_at(th - shift, w, a, ad)[2] for th, w, a, ad in
                        zip(ds.cam_angle.values, ds.cam_speed.values, f.alpha.values, f.alpha_dot.values)])
        np.testing.assert_allclose(f.sprag_margin.values[touching], (chi - 0.3 * h)[touching], rtol=1e-12)
    assert ds.attrs["sprags"] == 0


def test_the_first_stick_comes_when_an_independent_solution_stops_sliding():
    # the figure's run up to its first switch: both contacts slide forward (s = +1) while
    # friction brakes the cam; the equations written again on the reference model with
    # Coulomb friction and the PI controller, integrated by SciPy to the first zero of a
    # sliding velocity, give the time and the follower of camdyn's first stick event
    rig = drum_brake()
    drive = CamDrive(shaft_inertia=2e-4, kind="controller", proportional=0.01, integral=0.5, target_speed=2.0)
    ds = simulate_two_followers(rig.system, drive, second=rig.second, placement=rig.placement, duration=0.01,
                                sample_rate=20e3, initial_speed=2.0, static_friction=0.4, rtol=1e-10, atol=1e-12)
    p, y0 = pack_two_followers(rig.system, rig.second, rig.placement, drive, initial_speed=2.0,
                               static_friction=0.4)
    s, phi = rig.system, rig.placement
    models = (ReferenceModel(s, y0[4], p[L.VISCOUS_C]), ReferenceModel(s, y0[4] - phi, p[pair.SECOND + L.VISCOUS_C]))
    shifts = (0.0, phi)

    def rhs(t, y):
        theta, theta_dot = y[4], y[5]
        out = [0.0] * 7
        torque = drive.proportional * (drive.target_speed - theta_dot) + drive.integral * y[6]
        for i, model in enumerate(models):
            th = theta - shifts[i]
            model.cam = lambda _t, th=th: (th, theta_dot)
            acc, fn, ff, _, _ = model.forces(t, [y[2 * i], y[2 * i + 1]], True, 1.0, s.contact.reference_velocity)
            *_, arm, n, u = model.geometry_at(th, 1.0, y[2 * i], y[2 * i + 1])
            torque += fn * (n @ arm) - ff * (u @ arm)
            out[2 * i], out[2 * i + 1] = y[2 * i + 1], acc
        out[4], out[5], out[6] = theta_dot, torque / drive.shaft_inertia, drive.target_speed - theta_dot
        return out

    def sliding(i):
        def event(t, y):
            return models[i].geometry_at(y[4] - shifts[i], y[5], y[2 * i], y[2 * i + 1])[4]
        event.terminal, event.direction = True, -1
        return event

    def touching(i):
        def event(t, y):
            return models[i].geometry_at(y[4] - shifts[i], y[5], y[2 * i], y[2 * i + 1])[0]
        event.terminal = True
        return event

    sol = solve_ivp(rhs, (0.0, 0.01), [*y0[:6], 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                    events=[sliding(0), sliding(1), touching(0), touching(1)])
    hits = [(e[0], k) for k, e in enumerate(sol.t_events) if e.size]
    t_stop, which = min(hits)
    assert which in (0, 1)   # a sliding velocity reaches zero before any contact opens
    first = int(np.argmax(ds.transition_kind.values == "stick"))
    assert first == 0 and ds.transition_follower.values[0] == which + 1
    assert ds.transition_time.values[0] == pytest.approx(t_stop, abs=1e-9)


def test_a_stuck_pair_breaks_loose_when_an_independent_solution_leaves_the_cone(friction_rig):
    # cam and followers at rest, both contacts stuck, a PI controller starting the cam:
    # the followers roll with it until the friction one of them needs reaches mu_s Fn.
    # The test writes the stuck phase again as a constrained system on the reference
    # model: M q'' = f - G^T F, G q'' = -c0 (vr = -h alpha_i' + w_i Theta' held at zero;
    # c0, the part of vr' at zero accelerations, by a central difference in time), solved
    # by numpy, integrated by SciPy to the first |F_i| = mu_s Fn_i
    s = friction_rig.with_values(**{"environment.gravity": 0.0})
    second = s.with_values(**{"spring.stiffness": 0.8 * s.spring.stiffness})
    drive = CamDrive(shaft_inertia=2e-4, kind="controller", proportional=0.02, integral=2.0, target_speed=1.0)
    ds = simulate_two_followers(s, drive, second=second, placement=math.pi, duration=0.05, sample_rate=20e3,
                                initial_speed=0.0, static_friction=0.4, rtol=1e-10, atol=1e-12)
    p, y0 = pack_two_followers(s, second, math.pi, drive, initial_speed=0.0, static_friction=0.4)
    models = (ReferenceModel(s, y0[4], p[L.VISCOUS_C]), ReferenceModel(second, y0[4] - math.pi,
                                                                       p[pair.SECOND + L.VISCOUS_C]))
    shifts = (0.0, math.pi)
    h = 0.5 * s.follower.width + 2.0 * s.follower.pin_radius

    def stuck(t, y):
        """Accelerations (alpha_1'', alpha_2'', Theta''), friction forces and normal forces."""
        theta, theta_dot = y[4], y[5]
        mass = np.diag([s.follower.inertia, second.follower.inertia, drive.shaft_inertia])
        force = np.zeros(3)
        force[2] = drive.proportional * (drive.target_speed - theta_dot) + drive.integral * y[6]
        g, c0, fns = np.zeros((2, 3)), np.zeros(2), np.zeros(2)
        for i, model in enumerate(models):
            th = theta - shifts[i]
            model.cam = lambda _t, th=th: (th, theta_dot)
            acc, fns[i], _, _, _ = model.forces(t, [y[2 * i], y[2 * i + 1]], True, 0.0,
                                                model.s.contact.reference_velocity)
            *_, arm, n, u = model.geometry_at(th, 1.0, y[2 * i], y[2 * i + 1])
            force[i] = acc * model.s.follower.inertia
            force[2] += fns[i] * (n @ arm)
            g[i, i], g[i, 2] = -h, u @ arm
            dt = 1e-7

            def vr(sign, i=i, th=th):
                return models[i].geometry_at(th + sign * dt * theta_dot, theta_dot,
                                             y[2 * i] + sign * dt * y[2 * i + 1], y[2 * i + 1])[4]
            c0[i] = (vr(1) - vr(-1)) / (2 * dt)
        kkt = np.block([[mass, g.T], [g, np.zeros((2, 2))]])
        solution = np.linalg.solve(kkt, np.r_[force, -c0])
        return solution[:3], solution[3:], fns

    def rhs(t, y):
        acc, _, _ = stuck(t, y)
        return [y[1], acc[0], y[3], acc[1], y[5], acc[2], drive.target_speed - y[5]]

    def cone(i):
        def event(t, y):
            _, friction, fns = stuck(t, y)
            return 0.4 * fns[i] - abs(friction[i])
        event.terminal, event.direction = True, -1
        return event

    sol = solve_ivp(rhs, (0.0, 0.05), [*y0[:6], 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                    events=[cone(0), cone(1)])
    t_break, which = min((e[0], k) for k, e in enumerate(sol.t_events) if e.size)
    assert (ds.sticking.values[0] == 1).all() and ds.transition_kind.values[0] == "slip"
    assert ds.transition_follower.values[0] == which + 1
    assert ds.transition_time.values[0] == pytest.approx(t_break, abs=1e-9), ds.transition_time.values[0] - t_break


def test_two_followers_of_one_system_get_the_single_followers_contact_damping():
    """Each follower's viscous contact damping coefficient (the drum brake's law, set by a
    damping ratio at a static equilibrium) is the single follower's, from its system's
    equilibrium at that system's own starting cam angle: the drum brake's two identical
    followers get one coefficient, although follower 2 starts half a turn round, where
    its equilibrium there would give another (64.29 against the single follower's 67.54
    N s/m)."""
    rig = drum_brake()
    p, _ = pack_two_followers(rig.system, rig.second, rig.placement, rig.drive)
    single = prepare(rig.system).viscous_c
    assert single > 0.0
    assert p[L.VISCOUS_C] == single and p[pair.SECOND + L.VISCOUS_C] == single
    placed = prepare(rig.second.with_values(**{"motion.initial_angle": prepare(rig.system).theta0 - rig.placement}))
    assert abs(placed.viscous_c - single) > 0.01 * single      # the placed start would not do
    # a follower 2 of another system gets that system's own coefficient
    other = rig.second.with_values(**{"spring.stiffness": 0.8 * rig.second.spring.stiffness})
    p, _ = pack_two_followers(rig.system, other, rig.placement, rig.drive)
    assert p[pair.SECOND + L.VISCOUS_C] == prepare(other).viscous_c != single


def test_follower_two_on_a_held_cam_moves_as_the_single_follower_placed_where_it_sits():
    """The drum brake on a cam held at its speed (``kind = "prescribed"``): follower 2,
    released from its static equilibrium half a turn round, rings on its contact and
    settles. The single follower of the cam-follower model (:func:`camdyn.simulate`'s
    model), its cam started half a turn round and its contact damping its own, released
    from the same angle, moves the same to 1e-9 of the range of its angle and speed
    (measured 6e-12 and 4e-10). With follower 2's coefficient from its equilibrium
    there, 5 % lower, they differ by 1.4e-3 and 8.6e-2 of those ranges."""
    rig = drum_brake()
    drive = CamDrive(2e-4, kind="prescribed")
    p_pair, y_pair = pack_two_followers(rig.system, rig.second, rig.placement, drive)
    revolutions = 0.25
    period = rig.system.motion.period
    times = np.linspace(0.0, revolutions * period, 401)
    both, _, _, counters = driver.integrate(registry.TWO_FOLLOWERS, p_pair, y_pair, 0.0, times[-1], times, 1e-12,
                                            1e-14, period / 64.0, driver.METHOD_DOP853, 10_000_000, 100_000,
                                            False, math.inf)
    assert counters[driver.COUNT_STATUS] == 0
    shifted = rig.system.with_values(**{"motion.initial_angle": y_pair[4] - rig.placement})
    p_one = prepare(shifted).p
    p_one[L.VISCOUS_C] = prepare(rig.system).viscous_c        # the single follower's own coefficient
    one, _, _, counters = driver.integrate(registry.CAM_FOLLOWER, p_one, np.array([y_pair[2], 0.0, 0.0]), 0.0,
                                           times[-1], times, 1e-12, 1e-14, period / 64.0, driver.METHOD_DOP853,
                                           10_000_000, 100_000, False, math.inf)
    assert counters[driver.COUNT_STATUS] == 0
    for column, slot in ((0, 2), (1, 3)):
        expected = one[:, column]
        scale = np.ptp(expected)
        assert scale > 0.0
        np.testing.assert_allclose(both[:, slot], expected, rtol=0, atol=1e-9 * scale)
