"""Coefficient-of-restitution studies of the contact laws.

:func:`single_impact` drops the follower onto a frozen cam, with gravity, spring and
friction removed, so that one impact happens under the contact law alone; the
effective coefficient of restitution is then ``-delta_dot(separation) /
delta_dot(onset)``. Restitution-parameterised laws promise to return the ``e`` they
were given; how well they keep that promise is :func:`restitution_error_curve`.
"""

from __future__ import annotations

import numpy as np

from camdyn.parameters import System

__all__ = ["single_impact", "restitution_error_curve"]


def single_impact(system: System, law: str, restitution: float, approach_velocity: float = 0.5,
                  rtol: float = 1e-10) -> dict:
    """Simulate one impact and measure its coefficient of restitution.

    Parameters
    ----------
    system : System
        Supplies geometry, inertia and Hertz contact.
    law : str
        Damping law name (see :data:`camdyn.parameters.DAMPING_LAWS`).
    restitution : float
        Coefficient ``e`` given to the law [-].
    approach_velocity : float
        Normal approach velocity at first contact [m/s].

    Returns
    -------
    dict
        ``restitution`` (measured) [-], ``approach_velocity``, ``separation_velocity``
        [m/s], ``peak_penetration`` [m], ``duration`` [s].
    """
    from camdyn.geometry import contact_point
    from camdyn.simulation import prepare, simulate

    s = system.with_values(**{
        "motion.speed": 0.0, "environment.gravity": 0.0, "spring.stiffness": 0.0,
        "friction.law": "none", "contact.damping": law, "contact.restitution": restitution,
        "contact.clip_adhesion": False,
    })
    prep = prepare(s)
    theta0 = prep.theta0
    # start 1 um away from the cam, closing at approach_velocity
    from scipy.optimize import brentq
    gap = 1e-6
    alpha = prep.equilibrium.angle
    f = lambda a: contact_point(a, theta0, prep.p)[0] + gap
    lo, hi = alpha - 0.05, alpha + 0.05
    alpha0 = brentq(f, lo, hi, xtol=1e-16)
    chi = contact_point(alpha0, theta0, prep.p)[1]
    alpha_dot0 = -approach_velocity / chi
    # contact lasts well under a millisecond; fly 1 um, hit, separate
    duration = gap / approach_velocity + 2e-3
    ds = simulate(s, duration=duration, sample_rate=1e4, rtol=rtol, atol=1e-14,
                  initial_state=(alpha0, alpha_dot0), max_step=2e-5)
    if ds.sizes["impact"] < 1:
        raise RuntimeError("no completed impact in the single-impact simulation")
    i = 0
    v_in = float(ds.impact_approach_velocity[i])
    v_out = float(ds.impact_separation_velocity[i])
    return {"restitution": v_out / v_in, "approach_velocity": v_in, "separation_velocity": v_out,
            "peak_penetration": float(ds.impact_peak_penetration[i]), "duration": float(ds.impact_duration[i])}


def restitution_error_curve(system: System, law: str, values=None, approach_velocity: float = 0.5):
    """Relative error ``(e_measured - e)/e`` of a law over ``values`` of ``e``.

    Returns (values, measured, relative_error) as arrays.
    """
    values = np.asarray(values if values is not None else np.round(np.arange(0.1, 1.0, 0.05), 2), float)
    measured = np.array([single_impact(system, law, e, approach_velocity)["restitution"] for e in values])
    return values, measured, (measured - values) / values
