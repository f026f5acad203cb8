"""Cam profiles of a translating follower against closed forms written here: each rise law
(cycloidal, simple harmonic, 3-4-5, 4-5-6-7), circular arcs (flat face: the support
function; knife edge: the ray's intersection with the circle, differentiated implicitly
and by complex steps), a tabulated lift against the eccentric circle it was sampled from
(within the cubic spline's error bounds), the pressure angle against the pitch curve's
tangent, and the refusals (non-convex flat-faced cam, undercut roller cam, bad input)."""

import math

import numpy as np
import pytest
from numpy.polynomial import Polynomial

from camdyn.errors import GeometryError, ParameterError
from camdyn.model import profiles

BETA = 1.1      # span of the rise [rad]
LIFT = 0.012    # [m]
ANGLES = np.array([0.0, 0.05, 0.3, 0.55, 0.8, 1.05, BETA - 1e-9])


def _profile(law, follower="flat"):
    """The law as a rise from 0, a dwell, the same law as a return, a dwell."""
    rest = math.pi - BETA
    return profiles.rise_return_profile([(law, BETA, LIFT), ("dwell", rest, 0.0), (law, BETA, -LIFT),
                                         ("dwell", rest, 0.0)], base_radius=0.08, follower=follower)


def _cycloidal(t):
    w = 2.0 * math.pi / BETA
    return (LIFT * (t / BETA - np.sin(w * t) / (2.0 * math.pi)), LIFT / BETA * (1.0 - np.cos(w * t)),
            LIFT * w / BETA * np.sin(w * t), LIFT * w * w / BETA * np.cos(w * t))


def _harmonic(t):
    w = math.pi / BETA
    return (LIFT / 2.0 * (1.0 - np.cos(w * t)), LIFT * w / 2.0 * np.sin(w * t), LIFT * w * w / 2.0 * np.cos(w * t),
            -LIFT * w ** 3 / 2.0 * np.sin(w * t))


def _polynomial(coefficients):
    """A polynomial law in u = theta / beta, differentiated by numpy."""
    poly = Polynomial(coefficients)

    def law(t):
        u = t / BETA
        return tuple(LIFT * poly.deriv(k)(u) / BETA ** k if k else LIFT * poly(u) for k in range(4))
    return law


CLOSED_FORMS = {
    "cycloidal": _cycloidal,
    "harmonic": _harmonic,
    "polynomial-345": _polynomial([0, 0, 0, 10, -15, 6]),
    "polynomial-4567": _polynomial([0, 0, 0, 0, 35, -84, 70, -20]),
}


@pytest.mark.parametrize("law", sorted(CLOSED_FORMS))
def test_each_rise_law_follows_its_closed_form(law):
    got = _profile(law).lift(ANGLES)
    expected = CLOSED_FORMS[law](ANGLES)
    for k in range(4):
        np.testing.assert_allclose(got[k], expected[k], rtol=1e-10, atol=1e-10 * LIFT / BETA ** k,
                                   err_msg=f"derivative {k}")


@pytest.mark.parametrize("law", sorted(CLOSED_FORMS))
def test_the_return_mirrors_the_rise_and_the_dwells_hold(law):
    prof = _profile(law)
    rise = prof.lift(ANGLES)
    back = prof.lift(math.pi + ANGLES)
    np.testing.assert_allclose(back[0], LIFT - rise[0], atol=1e-15)
    np.testing.assert_allclose(back[1], -rise[1], atol=1e-14)
    dwell = prof.lift(np.array([BETA + 0.1, 2.0 * math.pi - 0.1, 4 * math.pi + 0.5 * (BETA + math.pi)]))
    np.testing.assert_allclose(dwell[0], [LIFT, 0.0, LIFT], atol=1e-17)


@pytest.mark.parametrize("law", sorted(CLOSED_FORMS))
def test_lift_and_velocity_are_continuous_at_every_joint(law):
    prof = _profile(law)
    joints = prof.joints
    before = prof.lift(joints - 1e-10)
    after = prof.lift(joints + 1e-10)
    np.testing.assert_allclose(after[0], before[0], atol=1e-12)
    np.testing.assert_allclose(after[1], before[1], atol=1e-9)
    jump = np.abs(after[2] - before[2]).max()
    if law == "harmonic":   # the simple harmonic law's acceleration jumps at a dwell: pi^2 L / (2 beta^2)
        assert jump == pytest.approx(math.pi ** 2 * LIFT / (2 * BETA ** 2), rel=1e-6)
    else:                   # the others start and end with zero acceleration
        assert jump < 1e-8


def test_a_flat_face_on_an_eccentric_circle_lifts_by_its_support_function():
    radius, e = 0.05, 0.012
    prof = profiles.eccentric_circle(radius, e)
    theta = np.linspace(-1.0, 7.0, 23)
    s, s1, s2, s3 = prof.lift(theta)
    np.testing.assert_allclose(s, e * (1.0 + np.cos(theta)), atol=1e-16)
    np.testing.assert_allclose(s1, -e * np.sin(theta), atol=1e-16)
    np.testing.assert_allclose(s2, -e * np.cos(theta), atol=1e-16)
    np.testing.assert_allclose(s3, e * np.sin(theta), atol=1e-16)
    assert prof.base_radius == pytest.approx(radius - e)


def _ray_to_circle(phi, d, rho):
    """Where the ray from the axis at angle phi leaves the circle of radius rho centred at
    distance d on the axis phi = 0: the larger root of r^2 - 2 d r cos(phi) + d^2 - rho^2."""
    b = d * np.cos(phi)
    return b + np.sqrt(b * b - d * d + rho * rho)


def _ray_rates(phi, d, rho):
    """r' and r'' from the implicit derivative of r^2 - 2 d r cos(phi) + d^2 = rho^2."""
    r = _ray_to_circle(phi, d, rho)
    den = r - d * np.cos(phi)
    r1 = -d * r * np.sin(phi) / den
    r2 = (-2.0 * d * r1 * np.sin(phi) - d * r * np.cos(phi) - r1 * r1) / den
    return r1, r2


def test_a_knife_edge_on_a_circle_meets_the_circle():
    radius, e = 0.05, 0.02
    prof = profiles.eccentric_circle(radius, e, follower="knife")
    theta = np.linspace(0.01, 6.2, 17)
    s, s1, s2, s3 = prof.lift(theta)
    h = 1e-30   # complex step: derivatives to rounding
    np.testing.assert_allclose(s, _ray_to_circle(theta, e, radius) - (radius - e), atol=1e-15)
    np.testing.assert_allclose(s1, _ray_to_circle(theta + 1j * h, e, radius).imag / h, atol=1e-14)
    r1, r2 = _ray_rates(theta, e, radius)
    np.testing.assert_allclose(s1, r1, atol=1e-14)
    np.testing.assert_allclose(s2, _ray_rates(theta + 1j * h, e, radius)[0].imag / h, atol=1e-13)
    np.testing.assert_allclose(s2, r2, atol=1e-13)
    np.testing.assert_allclose(s3, _ray_rates(theta + 1j * h, e, radius)[1].imag / h, atol=1e-12)


def test_a_tabulated_lift_sampled_from_an_eccentric_circle_matches_it():
    """The periodic cubic spline through n samples of f = e (1 + cos theta) errs by at most
    5/384 h^4 |f''''|, h^3 / 24 |f''''| and 3/8 h^2 |f''''| in s, s' and s'' (C. A. Hall and
    W. W. Meyer, J. Approx. Theory 16 (1976) 105-122), with h = 2 pi / n, |f''''| <= e."""
    e, n = 0.01, 720
    grid = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    prof = profiles.tabulated_profile(e * (1.0 + np.cos(grid)), base_radius=0.04)
    theta = np.linspace(0.0, 2.0 * math.pi, 997)
    s, s1, s2, _ = prof.lift(theta)
    h = 2.0 * math.pi / n
    assert np.abs(s - e * (1.0 + np.cos(theta))).max() <= 5.0 / 384.0 * h ** 4 * e
    assert np.abs(s1 + e * np.sin(theta)).max() <= h ** 3 / 24.0 * e
    assert np.abs(s2 + e * np.cos(theta)).max() <= 3.0 / 8.0 * h ** 2 * e
    np.testing.assert_allclose(prof.lift(grid)[0], e * (1.0 + np.cos(grid)), atol=1e-17)


def test_the_pressure_angle_is_the_pitch_curves_slope_seen_from_the_follower():
    """The pitch point in the cam's frame, P = R(-theta) (eps, Y(theta)), differentiated by
    central differences and turned back into the ground frame: its tangent's slope there
    is the pressure angle."""
    eps, roller = 0.006, 0.01
    prof = profiles.rise_return_profile([("cycloidal", 2.0, 0.01), ("polynomial-345", 2.0, -0.01),
                                         ("dwell", 2.0 * math.pi - 4.0, 0.0)], 0.04, "roller", roller, eps)
    y0 = math.sqrt(prof.prime_radius ** 2 - eps ** 2)

    def pitch(theta):
        big = y0 + prof.lift(theta)[0]
        c, s = np.cos(theta), np.sin(theta)
        return np.array([c * eps + s * big, -s * eps + c * big])

    theta = np.array([0.3, 1.0, 1.7, 2.5, 3.4, 5.0])
    step = 1e-6
    tangent = (pitch(theta + step) - pitch(theta - step)) / (2 * step)
    c, s = np.cos(theta), np.sin(theta)
    ground = np.array([c * tangent[0] - s * tangent[1], s * tangent[0] + c * tangent[1]])
    np.testing.assert_allclose(profiles.pressure_angle(prof, theta), np.arctan(ground[1] / ground[0]), atol=1e-8)


def test_a_flat_faced_cam_that_is_not_convex_is_refused_with_its_angle():
    with pytest.raises(GeometryError, match=r"not convex.* at \d+\.\d+ deg"):
        profiles.rise_return_profile([("cycloidal", 0.3, 0.02), ("dwell", math.pi - 0.3, 0.0),
                                      ("cycloidal", 0.3, -0.02), ("dwell", math.pi - 0.3, 0.0)], 0.01)
    # the same law on a base circle large enough: r_base > max(-s - s'')
    profiles.rise_return_profile([("cycloidal", 0.3, 0.02), ("dwell", math.pi - 0.3, 0.0),
                                  ("cycloidal", 0.3, -0.02), ("dwell", math.pi - 0.3, 0.0)], 1.5)


def test_an_undercut_roller_cam_is_refused_and_a_smaller_roller_is_not():
    law = [("cycloidal", 0.5, 0.01), ("dwell", math.pi - 0.5, 0.0), ("cycloidal", 0.5, -0.01),
           ("dwell", math.pi - 0.5, 0.0)]
    with pytest.raises(GeometryError, match=r"undercut.* at \d+\.\d+ deg"):
        profiles.rise_return_profile(law, 0.03, "roller", 0.02)
    profiles.rise_return_profile(law, 0.03, "roller", 0.002)


@pytest.mark.parametrize("segments, match", [
    ([("cycloidal", math.pi, 0.01), ("dwell", math.pi, 0.0)], "come back"),
    ([("cycloidal", 1.0, 0.01), ("cycloidal", 1.0, -0.01)], "one revolution"),
    ([("linear", math.pi, 0.01), ("cycloidal", math.pi, -0.01)], "lift law"),
    ([("dwell", math.pi, 0.01), ("dwell", math.pi, -0.01)], "no lift"),
    ([("cycloidal", -1.0, 0.01), ("cycloidal", 2 * math.pi + 1.0, -0.01)], "positive"),
])
def test_bad_segments_are_refused(segments, match):
    with pytest.raises(ParameterError, match=match):
        profiles.rise_return_profile(segments, 0.05)


def test_joints_that_do_not_meet_are_refused():
    # two arcs of a flat-faced cam that are not tangent: the lift jumps at 180 deg
    with pytest.raises(GeometryError, match="jumps"):
        profiles.circular_arc_profile([(math.pi, 0.01, 0.0, 0.05), (math.pi, 0.0, 0.0, 0.05)], 0.04)
    with pytest.raises(ParameterError, match="follower"):
        profiles.eccentric_circle(0.05, 0.01, follower="mushroom")
    with pytest.raises(GeometryError, match="eccentricity"):
        profiles.eccentric_circle(0.05, 0.06)
