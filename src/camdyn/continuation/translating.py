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
a capture, as the rig's between lift-off and about 300 rpm) is integrated up to the
capture velocity's cut and found with both multipliers 0; along its branch the number of
impacts before the capture changes every few tenths of an rpm, and each change is
reported as a grazing. An orbit in rigid sustained contact at the section's phase has no
well-posed problem: the contact mode keeps any offset of the state from the cam, so its
monodromy is the identity; put the section where the follower flies (docs/continuation.md,
Limits).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import xarray as xr

from camdyn.continuation.branches import MIN_STEP, Branch, continue_orbits
from camdyn.continuation.orbits import Orbit, find_orbit, shoot
from camdyn.continuation.problem import Problem
from camdyn.errors import ParameterError
from camdyn.model import translating_follower as model
from camdyn.params.units import angular_speed
from camdyn.simulation import limits
from camdyn.simulation.translating import TranslatingFollower
from camdyn.systems import registry as systems

__all__ = ["translating_problem", "trace_translating", "translating_dataset", "SPEED_KEY", "RPM"]

#: The scalar parameter's name: the cam speed's key in the configuration files.
SPEED_KEY = "motion.speed"
#: One revolution per minute [rad/s].
RPM = 2.0 * math.pi / 60.0


def translating_problem(follower: TranslatingFollower, speed: float, phase: float = 0.0, initial_state=None,
                        rtol: float = 1e-10, atol: float = 1e-12) -> Problem:
    """The translating follower's periodic problem over one cam revolution ``2 pi /
    omega`` [s], the scalar parameter being the cam speed omega [rad/s].

    Parameters
    ----------
    follower : TranslatingFollower
        The follower and its cam (rigid or compliant contact).
    speed : float or str
        The starting cam speed [Hz], or text with units (``"700 rpm"``, ``"73.3 rad/s"``);
        the problem's parameter is omega [rad/s].
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
    speed = angular_speed(speed)   # omega [rad/s] from Hz or text with units
    phase = limits.check_number("phase", phase, "rad")
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


def trace_translating(follower: TranslatingFollower, start: float, stop: float, periods: int = 1, phase: float = 0.0,
                      step: float = 0.01, max_points: int = 200, transient: int = 100, rtol: float = 1e-10,
                      progress: Callable[[Orbit], None] | None = None, stall: int = 0) -> tuple[Problem, Branch]:
    """The branch of period-``periods`` orbits from the cam speed ``start`` towards
    ``stop`` (each in Hz, or text with units such as ``"700 rpm"``; the branch's parameter
    is omega [rad/s]): the orbit at ``start`` after ``transient`` revolutions from
    the follower resting on the cam (Newton's method on the shooting residual), then
    pseudo-arclength continuation (:func:`~camdyn.continuation.branches.continue_orbits`,
    ``stall`` its stall test).

    Raises
    ------
    ParameterError
        For a bad range or setting, before any work.
    SimulationError
        If no orbit is found at ``start``.
    """
    start, stop = angular_speed(start, "start"), angular_speed(stop, "stop")   # omega [rad/s]
    if start == stop:
        raise ParameterError("the range must be two different speeds")
    if int(periods) != periods or periods < 1:
        raise ParameterError(f"the period must be a positive whole number of revolutions, got {periods}")
    if transient < 1 or max_points < 2 or not step >= MIN_STEP:
        raise ParameterError(f"transient must be at least 1, max_points at least 2 and step at least {MIN_STEP:g}")
    problem = translating_problem(follower, f"{float(start)!r} rad/s", phase, rtol=rtol, atol=rtol * 1e-2)
    orbit = find_orbit(problem, periods=int(periods), transient=transient)
    branch = continue_orbits(problem, orbit, stop, step=step, max_step=max(step, 0.05), max_points=max_points,
                             progress=progress, stall=stall)
    return problem, branch


def _section(problem: Problem, orbit: Orbit) -> np.ndarray:
    """The orbit's points on the stroboscopic section: ``(x [m], x' [m/s])`` at the start
    of each of its revolutions."""
    x, points = orbit.state, [orbit.state]
    for _ in range(orbit.periods - 1):
        x = shoot(problem, x, orbit.parameter, 1)
        points.append(x)
    return np.array(points)


def translating_dataset(problem: Problem, branches: list[Branch]) -> xr.Dataset:
    """The branches as a Dataset over ``point`` (the branches one after the other, their
    index in ``branch``), ``section`` (an orbit's points on the stroboscopic section,
    NaN past its ``periods``), ``multiplier`` and ``bifurcation``: the speed in rad/s and
    rpm, stability, the section's ``x`` [m] and ``x_dot`` [m/s], impacts per period, the
    multipliers and the located bifurcations."""
    orbits = [(index, orbit) for index, branch in enumerate(branches) for orbit in branch.orbits]
    if not orbits:
        raise ParameterError("no orbit to store")
    width = max(orbit.periods for _, orbit in orbits)
    points = np.full((len(orbits), width, 2), np.nan)
    mu = np.full((len(orbits), problem.unknowns), np.nan + 0j)
    for i, (_, orbit) in enumerate(orbits):
        section = _section(problem, orbit)
        points[i, :section.shape[0]] = section
        mu[i] = orbit.multipliers
    found = [(index, item) for index, branch in enumerate(branches) for item in branch.bifurcations]
    speed = np.array([orbit.parameter for _, orbit in orbits])
    data = {
        "parameter": ("point", speed, {"units": "rad/s", "long_name": "cam speed"}),
        "speed_rpm": ("point", speed / RPM, {"units": "rpm", "long_name": "cam speed"}),
        "branch": ("point", np.array([i for i, _ in orbits], dtype=np.int32), {"units": "1", "long_name": "branch"}),
        "stable": ("point", np.array([o.stable for _, o in orbits], dtype=np.int8),
                   {"units": "1", "long_name": "1 if every |multiplier| < 1"}),
        "periods": ("point", np.array([o.periods for _, o in orbits], dtype=np.int32),
                    {"units": "1", "long_name": "revolutions per orbit period"}),
        "impacts_per_period": ("point", np.array([o.impacts_per_period for _, o in orbits], dtype=np.int32),
                               {"units": "1", "long_name": "impacts per orbit period"}),
        "poincare_x": (("point", "section"), points[:, :, 0],
                       {"units": "m", "long_name": "follower position once per revolution (Poincare points)"}),
        "poincare_x_dot": (("point", "section"), points[:, :, 1],
                           {"units": "m/s", "long_name": "follower velocity once per revolution (Poincare points)"}),
        "multiplier_real": (("point", "multiplier"), mu.real, {"units": "1", "long_name": "Floquet multiplier, real"}),
        "multiplier_imag": (("point", "multiplier"), mu.imag, {"units": "1", "long_name": "Floquet multiplier, imag"}),
        "bifurcation_kind": ("bifurcation", np.array([b.kind for _, b in found], dtype=str),
                             {"units": "1", "long_name": "fold, period-doubling, neimark-sacker, grazing or "
                                                          "multiplier-jump"}),
        "bifurcation_parameter": ("bifurcation", np.array([b.parameter for _, b in found], dtype=float),
                                  {"units": "rad/s", "long_name": "cam speed at the bifurcation"}),
        "bifurcation_branch": ("bifurcation", np.array([i for i, _ in found], dtype=np.int32),
                               {"units": "1", "long_name": "branch index"}),
    }
    return xr.Dataset(data, attrs={"parameter_name": SPEED_KEY, "parameter_units": "rad/s",
                                   "method": "single shooting, pseudo-arclength continuation",
                                   "rtol": problem.rtol, "atol": problem.atol})
