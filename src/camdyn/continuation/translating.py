"""The periodic problem of the translating follower (:mod:`camdyn.model.translating_follower`,
:class:`~camdyn.simulation.translating.TranslatingFollower`): its orbits over whole cam
revolutions, the scalar parameter being the cam speed ``motion.speed`` [rad/s] (the key
of the translating follower's configuration files, :mod:`camdyn.params.profiles`).

The shooting unknowns are the follower's position x [m] and velocity x' [m/s] at the cam
angle ``phase`` [rad] (the orbit's phase; the brute-force diagram of
:func:`camdyn.analysis.poincare.poincare_section` samples cam angle 0). The saltation
matrices of the variational system (:mod:`camdyn.systems.variational`) carry the shooting
through its events:

- an impact, ``x'+ = (1 + e) s_dot(t) - e x'-``: the reset moves with the cam, so the
  saltation matrix has the term ``R_t = (0, (1 + e) s_ddot)``;
- a capture into sustained contact and a lift-off: the state after it is the cam's,
  ``(s(t), s_dot(t))``, whatever it was before, so the saltation matrix is zero and the
  monodromy matrix of an orbit that rides the cam for a while is singular (a multiplier
  0: the cam wipes out every perturbation; Leine & Nijmeijer 2004, sec. 7.3);
- the compliant law's contact onset and end: a switch of the field, no reset.

An orbit whose impacts accumulate (an infinite sequence of ever smaller impacts ending in
a capture, as the rig's at and below about 358 rpm) is integrated up to the capture
velocity's cut, where the event count is large and the monodromy ill-conditioned:
continuation there is not reliable (docs/continuation.md, Limits).
"""

from __future__ import annotations

import math

import numpy as np

from camdyn.continuation.problem import Problem
from camdyn.errors import ParameterError
from camdyn.model import translating_follower as model
from camdyn.simulation import limits
from camdyn.simulation.translating import TranslatingFollower
from camdyn.systems import registry as systems

__all__ = ["translating_problem", "SPEED_KEY"]

#: The scalar parameter's name: the cam speed's key in the configuration files.
SPEED_KEY = "motion.speed"


def translating_problem(follower: TranslatingFollower, speed: float, phase: float = 0.0, initial_state=None,
                        rtol: float = 1e-10, atol: float = 1e-12) -> Problem:
    """The translating follower's periodic problem over one cam revolution ``2 pi /
    omega`` [s], the scalar parameter being the cam speed omega [rad/s].

    Parameters
    ----------
    follower : TranslatingFollower
        The follower and its cam (rigid or compliant contact).
    speed : float
        The starting cam speed omega [rad/s] (``rpm * 2 pi / 60``).
    phase : float
        Cam angle theta0 [rad] at the orbit's phase ``t = 0``: the Poincare section.
    initial_state : (float, float), optional
        ``(x [m], x' [m/s])``; default on the cam, moving with it.
    rtol, atol : float
        Integration tolerances, relative [-] and absolute [m, m/s].

    Returns
    -------
    Problem
        With ``name = "motion.speed"``, unit ``rad/s`` and impacts counted on the gap
        guard where the follower stays in flight (a capture is not an impact; for the
        compliant law, the contacts that end).
    """
    if not isinstance(follower, TranslatingFollower):
        raise ParameterError(f"expected a TranslatingFollower, got {type(follower).__name__}")
    limits.check_tolerances(rtol, atol)
    speed = limits.check_number("speed", speed, "rad/s")
    phase = limits.check_number("phase", phase, "rad")
    if not (math.isfinite(speed) and speed > 0.0):
        raise ParameterError(f"the cam speed must be positive and finite, got {speed!r} rad/s")
    if not math.isfinite(phase):
        raise ParameterError(f"the phase must be finite, got {phase!r} rad")

    def build(value: float) -> tuple[np.ndarray, float]:
        if not (math.isfinite(value) and value > 0.0):
            raise ParameterError(f"the cam must turn to have a period; motion.speed = {value} rad/s gives none")
        return follower.pack(float(value), float(phase)), 2.0 * math.pi / value

    p, _ = build(speed)
    if initial_state is None:
        _, s, sd, _, _ = model.cam(0.0, p)
        template = np.array([s, sd])
    else:
        template = np.asarray(initial_state, dtype=float).reshape(-1)
        if template.shape != (2,) or not np.all(np.isfinite(template)):
            raise ParameterError(f"initial_state is (x [m], x' [m/s]), got {initial_state!r}")
    return Problem(systems.TRANSLATING_FOLLOWER, build, float(speed), template, model.STATE_SIZE, name=SPEED_KEY,
                   unit="rad/s", rtol=rtol, atol=atol, impact_sign=1.0,
                   key=SPEED_KEY)
