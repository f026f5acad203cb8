"""Coefficient-of-restitution studies of the contact laws.

:func:`single_impact` drops the follower onto a frozen cam, with gravity, spring and
friction removed, so that one impact happens under the contact law alone; the
effective coefficient of restitution is then ``-delta_dot(separation) /
delta_dot(onset)``. Restitution-parameterised laws promise to return the ``e`` they
were given; how well they keep that promise is :func:`restitution_error_curve`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq

from camdyn.params.system import System

__all__ = ["single_impact", "restitution_error_curve", "energy_balance_residual"]


def single_impact(system: System, law: str, restitution: float, approach_velocity: float = 0.5,
                  rtol: float = 1e-10) -> dict:
    """Simulate one impact and measure its coefficient of restitution.

    Parameters
    ----------
    system : System
        Supplies geometry, inertia and Hertz contact.
    law : str
        Damping law name (see :data:`camdyn.params.system.DAMPING_LAWS`).
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
    from camdyn.model.geometry import contact_point
    from camdyn.simulation.runner import prepare, simulate

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


def energy_balance_residual(system: System, speeds, restitution: float) -> np.ndarray:
    """Peak residual angle by the approximate energy-balance technique (thesis 2.5.2,
    eqs 2.30-2.33).

    Assumptions (the thesis's): the follower rests at its static equilibrium ``alpha*``
    before each impact; the cam contact point moves at its largest speed ``e Omega``
    along the contact normal; the coefficient of restitution ``xi`` does not depend on
    speed. Then the follower leaves with ``u_b = (1 + xi) e Omega`` (eq 2.31), i.e. the
    kinetic energy ``T = 0.5 I_P ((1 + xi) e Omega / chi*)^2`` (eq 2.32), which the
    follower spends climbing the potential of the free follower (eq 2.33) up to
    ``alpha_p``: ``T = -int_{alpha*}^{alpha_p} M_free(alpha) d alpha``. camdyn integrates
    the moment the simulator uses for the free follower (spring, its tilt, gravity), so
    the estimate and the contact model share one potential; the thesis's eq 2.33 writes
    the spring term alone. The spring's ``sec(alpha)`` makes the potential diverge at
    90 degrees, so ``alpha_p`` saturates at ``pi/2`` (thesis fig 2.8: 1.36 rad).

    Parameters
    ----------
    system : System
        The rig (follower resting on the cam).
    speeds : array_like
        Cam speeds [Hz].
    restitution : float
        Coefficient of restitution ``xi`` [-], 0 to 1.

    Returns
    -------
    ndarray
        ``alpha_p - alpha*`` [rad] per speed.
    """
    from camdyn.errors import ParameterError
    from camdyn.model.dynamics import free_acceleration
    from camdyn.simulation.runner import prepare
    if not 0.0 <= restitution <= 1.0:
        raise ParameterError(f"the coefficient of restitution must lie in [0, 1], got {restitution!r}")
    prep = prepare(system)
    eq = prep.equilibrium
    if not eq.in_contact:
        raise ParameterError("the energy balance starts from a follower resting on the cam, but it rests off the cam")
    p, a0, inertia = prep.p, eq.angle, system.follower.inertia
    top = 0.5 * math.pi - 1e-6

    def climb(alpha):  # potential gained from alpha* [J]
        return -inertia * quad(lambda a: free_acceleration(a, p), a0, alpha, limit=200)[0]

    ceiling = climb(top)
    out = []
    for hz in np.atleast_1d(np.asarray(speeds, dtype=float)):
        if not (math.isfinite(hz) and hz >= 0):
            raise ParameterError(f"speeds must be finite and non-negative [Hz], got {hz!r}")
        kinetic = 0.5 * inertia * ((1.0 + restitution) * system.cam.runout * 2 * math.pi * hz / eq.moment_arm) ** 2
        if kinetic == 0.0:
            out.append(0.0)
        elif kinetic >= ceiling:
            out.append(top - a0)
        else:
            out.append(brentq(lambda a: climb(a) - kinetic, a0, top, xtol=1e-12) - a0)
    return np.array(out)
