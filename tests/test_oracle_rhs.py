"""The compiled right-hand side of the cam-follower against the independent SciPy model,
state by state.

:func:`camdyn.model.dynamics.rhs` (the acceleration ``alpha_ddot`` [rad/s^2] and the
cam's power [W] that the integrator sees) is evaluated directly, without the integrator,
at chosen states: in contact while the penetration grows and while it shrinks, with
Coulomb friction sliding either way, under the viscous law, law D (Hunt-Crossley's
``beta F_k`` while compressing, viscous while restoring) and the restitution law of
Flores et al., with a pulling force clipped to zero, and out of contact; with the
spring's arm offset ``dx``, upright and tilted. The expected values are those of
:class:`camdyn.testing.oracle.ReferenceModel`, which writes the geometry (the cam's
parametric form), the forces (from the papers) and the moments (cross products) again.

Only the functions the right-hand side calls are compiled (seconds), so this file is
also the fast part of the mutation check (tools/mutation_check.py).

Both models are handed the same viscous coefficient (camdyn's eq 2.24 value, itself
compared with the oracle's to 1e-6 in tests/test_oracle_laws.py) and the same hybrid
mode (contact, sliding sign, approach velocity); the states are placed by the oracle's
own penetration. Tolerance: the penetration (a few um) is a difference of lengths near
0.1 m, so each model's rounding leaves it good to about 1e-17 m / 1e-6 m = 1e-11
relative, and the contact force with it; the two acceleration values (and the
powers) agree to a few 1e-12 of the largest moment in the sum (measured: at most 2.1e-12
in contact, 3e-16 out of it), checked at 1e-10 of it. The terms the mutation check
alters are far above that at the states chosen (measured, as fractions of that scale):
twice the friction moment 0.09, the Flores factor's 1/16 of the damping 7.5e-3, the
tilted arm's depth part 1e-3, the spring arm's ``sec(alpha) - 1`` 8e-5 (alpha ~ 0.07
rad), the swapped branches of law D 0.6; a clipped state pulls with more than 1 N
unclipped.
"""

import math

import numpy as np
import pytest

from camdyn.model import layout as L
from camdyn.model.dynamics import rhs
from camdyn.simulation.runner import prepare
from camdyn.testing.oracle import ReferenceModel

#: Agreement asked of alpha_ddot [rad/s^2] and the power [W], relative to the largest term.
AGREE = 1e-10
#: Instants [s] of the cam's constant rotation (11.55 Hz: about a quarter of a revolution).
TIMES = (0.0, 7e-3, 19e-3)
#: Penetration [m] and its rate [m/s] of the contact states (static penetration 0.8 um).
PENETRATION = 5e-6
RATES = (0.1, -0.1)

#: configuration -> parameter changes of the chapter 4 rig (Coulomb friction, point contact)
CONFIGS = {
    "viscous": {},
    "tilted spring +5 deg": {"spring.tilt": math.radians(5.0)},
    "tilted spring -3 deg": {"spring.tilt": math.radians(-3.0)},
    "law D": {"contact.damping": "stiffness-proportional-viscous", "contact.beta": 20.0,
              "contact.damping_ratio": 0.05},
    "flores": {"contact.damping": "flores", "contact.restitution": 0.7},
}


def models(friction_rig, changes):
    """Parameter vector, oracle (with camdyn's viscous coefficient) of the changed rig."""
    s = friction_rig.with_values(**changes)
    prep = prepare(s)
    return prep.p, ReferenceModel(s, prep.theta0, viscous_c=prep.viscous_c)


def placed(oracle, t, delta, delta_dot):
    """``(alpha [rad], alpha_dot [rad/s])`` at time ``t`` [s] with the oracle's penetration
    ``delta`` [m] and rate ``delta_dot`` [m/s]: Newton steps on ``d delta/d alpha = -chi``
    and ``d delta_dot / d alpha_dot = -chi``."""
    alpha = 0.0735
    for _ in range(6):
        d, _, chi, *_ = oracle.geometry(t, alpha, 0.0)
        alpha += (d - delta) / chi
    d, rate0, chi, *_ = oracle.geometry(t, alpha, 0.0)
    assert abs(d - delta) < 1e-15
    return alpha, (rate0 - delta_dot) / chi


def compare(p, oracle, t, alpha, alpha_dot, contact, slip, approach=0.5):
    """Compiled and oracle ``(alpha_ddot, P_cam)`` at one state; returns the oracle's
    forces and the largest relative disagreement (of the scale of the moments)."""
    mode = np.zeros(L.MODE_SIZE)
    mode[L.MODE_CONTACT] = 1.0 if contact else 0.0
    mode[L.MODE_SLIP] = slip
    mode[L.MODE_APPROACH] = approach
    got = np.zeros(3)
    rhs(t, np.array([alpha, alpha_dot, 0.0]), mode, p, got)
    acc, fn, ff, fs, power = oracle.forces(t, [alpha, alpha_dot, 0.0], contact, slip, approach)
    inertia = oracle.s.follower.inertia
    chi = oracle.geometry(t, alpha, alpha_dot)[2]
    # the largest moment [N m] in the sum: contact, friction, spring (arm < 0.1 m), gravity
    scale = max(abs(fn) * chi, abs(ff) * oracle.h, abs(fs) * 0.1,
                oracle.s.follower.mass * oracle.s.gravity * oracle.s.follower.cg_distance)
    v_cam = abs(oracle.geometry(t, alpha, alpha_dot)[5]).max()
    err_acc = abs(got[1] - acc) / (scale / inertia)
    err_power = abs(got[2] - power) / max((abs(fn) + abs(ff)) * v_cam, 1e-300) if contact else abs(got[2])
    assert got[0] == alpha_dot
    return (fn, ff, fs), max(err_acc, err_power)


@pytest.mark.parametrize("config", list(CONFIGS))
def test_rhs_in_contact_agrees_with_oracle(friction_rig, config):
    p, oracle = models(friction_rig, CONFIGS[config])
    worst = 0.0
    for t in TIMES:
        for rate in RATES:
            alpha, alpha_dot = placed(oracle, t, PENETRATION, rate)
            for slip in (1.0, -1.0):
                (fn, ff, _), err = compare(p, oracle, t, alpha, alpha_dot, True, slip)
                assert fn > 10.0 and ff == pytest.approx(0.3 * slip * fn, rel=1e-15)
                worst = max(worst, err)
    print(f"{config}: largest disagreement {worst:.2e} of the largest moment")
    assert worst < AGREE


@pytest.mark.parametrize("config", ["viscous", "tilted spring +5 deg", "tilted spring -3 deg"])
def test_rhs_out_of_contact_agrees_with_oracle(friction_rig, config):
    # spring and gravity alone, the follower a little off the cam
    p, oracle = models(friction_rig, CONFIGS[config])
    worst = 0.0
    for t in TIMES:
        alpha, alpha_dot = placed(oracle, t, -2e-4, 0.3)
        for a in (alpha, alpha - 0.2):
            _, err = compare(p, oracle, t, a, alpha_dot, False, 1.0)
            worst = max(worst, err)
    print(f"{config}: largest disagreement {worst:.2e} of the largest moment")
    assert worst < AGREE


def test_rhs_clips_a_pulling_force_like_the_oracle(friction_rig):
    # receding fast at a small penetration: the viscous force outweighs the elastic one,
    # and unclipped the contact would pull the follower onto the cam
    changes = {"contact.damping_ratio": 0.05}
    p_free, free = models(friction_rig, changes)
    p, oracle = models(friction_rig, {**changes, "contact.clip_adhesion": True})
    for t in TIMES:
        alpha, alpha_dot = placed(oracle, t, 0.5e-6, -0.1)
        (pull, _, _), err_free = compare(p_free, free, t, alpha, alpha_dot, True, 1.0)
        assert pull < -1.0 and err_free < AGREE
        (fn, ff, _), err = compare(p, oracle, t, alpha, alpha_dot, True, 1.0)
        assert fn == 0.0 and ff == 0.0 and err < AGREE
