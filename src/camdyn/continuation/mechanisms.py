"""The periodic problem of the mechanisms: the rocking follower on a flexible pivot
bearing (:mod:`camdyn.model.flexible_pivot`,
:class:`~camdyn.simulation.flexible_pivot.FlexiblePivotRig`), two rocking followers on one
cam (:mod:`camdyn.model.two_followers`, :class:`~camdyn.simulation.two_followers.TwoFollowerRig`)
and the driven cam (:mod:`camdyn.model.driven_cam`,
:class:`~camdyn.simulation.mechanisms.DrivenCamRig`).

The flexible pivot and two followers held at a prescribed speed (the drive kind
``"prescribed"``) are forced with the cam's period ``T = 1 / speed`` [s], so their
periodic orbits are the fixed points of the period map, found and continued by the
shooting methods of :mod:`~camdyn.continuation.orbits` and
:mod:`~camdyn.continuation.branches` unchanged:

- the flexible pivot's unknowns are ``(alpha [rad], alpha_dot [rad/s], u [m], u_dot [m/s],
  v [m], v_dot [m/s])``, the follower and its bearing; the works are quadratures;
- two followers' unknowns are ``(alpha_1 [rad], alpha_1_dot [rad/s], alpha_2 [rad],
  alpha_2_dot [rad/s])``; the shaft's angle and speed are kept (the angle starts at the
  system's starting cam angle, the speed is the prescribed one at the parameter's value:
  :attr:`~camdyn.continuation.problem.Problem.template_at`), as are the controller's
  integral and the works. The shaft's rows of the state-transition matrix stay those of
  the identity (``Theta_ddot = 0`` whatever the followers do), so the followers' block is
  the monodromy matrix.

The driven cam and two followers on a shaft under a torque, a motor or a PI controller
are autonomous: their cam's speed is a state that settles where the drive and the load
balance, and their steady states repeat in the cam angle over a period that is an
unknown. They are solved in the cam angle, on the section at the starting cam angle
(:mod:`~camdyn.continuation.autonomous`): the unknowns are the followers' angles and
rates, the cam's speed and, under a PI controller with an integral gain, its integral;
the parameter is a drive key (:data:`~camdyn.continuation.autonomous.DRIVE_KEYS`) or a
key of the cam or the followers; an orbit's ``period`` is the time its cam takes to turn
``2 pi k`` [s].
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from camdyn.continuation.autonomous import autonomous_problem, is_autonomous
from camdyn.continuation.branches import Branch, continue_orbits
from camdyn.continuation.orbits import Orbit, find_orbit
from camdyn.continuation.problem import Problem, parameter_unit
from camdyn.continuation.results import check_trace_settings
from camdyn.errors import ParameterError, SimulationError
from camdyn.model import contact
from camdyn.model import layout as L
from camdyn.params.schema import parameter_index
from camdyn.params.system import System
from camdyn.simulation import limits
from camdyn.simulation.flexible_pivot import FlexiblePivotRig, flexible_pivot_equilibrium
from camdyn.simulation.mechanisms import CamDrive
from camdyn.simulation.runner import prepare
from camdyn.simulation.two_followers import TwoFollowerRig, pack_two_followers
from camdyn.systems import registry as systems

__all__ = ["mechanism_problem", "trace_mechanism", "BEARING_KEYS"]

#: The flexible pivot's own continuous parameters and their units.
BEARING_KEYS = {"pivot.stiffness": "N/m", "pivot.damping": "N s/m"}
#: The keys of a cam motion that is not constant, which a prescribed speed does not take.
_NOT_CONSTANT = ("motion.frequency", "motion.amplitude", "motion.start_speed", "motion.ramp_time")


def _system_key(system: System, key: str) -> tuple[str, float]:
    """The unit and starting value of the system's continuous parameter ``key``."""
    if key in _NOT_CONSTANT:
        raise ParameterError(f"{key} does not enter a cam turning at constant speed (motion.kind = 'constant')")
    unit = parameter_unit(system, key)
    value = parameter_index(type(system))[key].getter(system)
    if value is None or not math.isfinite(float(value)):
        raise ParameterError(f"{key} has no finite value to start from")
    return unit, float(value)


def _period(system: System, key: str, value: float) -> float:
    """The cam period [s] of ``system`` (whose ``key`` is ``value``), refused if none."""
    limits.check_system(system)
    period = system.motion.period
    if not (math.isfinite(period) and period > 0):
        raise ParameterError(f"the cam must turn to have a period; {key} = {value} gives none")
    return period


def _pivot_problem(rig: FlexiblePivotRig, key: str, initial_state, rtol: float, atol: float) -> Problem:
    """The flexible pivot's problem (module docstring); ``key`` a system key or one of
    :data:`BEARING_KEYS`."""
    system, kp, cp = rig.system, rig.pivot_stiffness, rig.pivot_damping
    if key in BEARING_KEYS:
        unit, value = BEARING_KEYS[key], float(kp if key == "pivot.stiffness" else cp)
    else:
        unit, value = _system_key(system, key)
    _, template, _ = flexible_pivot_equilibrium(system, kp, cp)     # refuses a bad bearing or system

    def build(value: float) -> tuple[np.ndarray, float]:
        moved, stiffness, damping = system, kp, cp
        if key == "pivot.stiffness":
            stiffness = value
        elif key == "pivot.damping":
            damping = value
        else:
            moved = system.with_values(**{key: value})
        if not (math.isfinite(stiffness) and stiffness > 0.0 and math.isfinite(damping) and damping >= 0.0):
            raise ParameterError(f"the bearing needs a positive stiffness and a non-negative damping; {key} = "
                                 f"{value} gives none")
        period = _period(moved, key, value)
        return np.r_[prepare(moved).p, stiffness, damping], period

    build(value)
    if initial_state is not None:
        template = _with_start(template, initial_state, 6, "(alpha, alpha_dot, u, u_dot, v, v_dot)")
    return Problem(systems.FLEXIBLE_PIVOT, build, value, template, 6, name=key, unit=str(unit), rtol=rtol, atol=atol,
                   impact_sign=1.0, key=key, matrix_rtol=1000.0 * rtol, matrix_atol=1000.0 * atol)


def _with_start(template: np.ndarray, initial_state, count: int, names: str) -> np.ndarray:
    """``template`` with its first ``count`` components from ``initial_state``."""
    start = np.asarray(initial_state, dtype=float).reshape(-1)
    if start.size != count or not np.all(np.isfinite(start)):
        raise ParameterError(f"initial_state is {names}: {count} finite numbers, got {initial_state!r}")
    out = template.copy()
    out[:count] = start
    return out


def _pair_problem(rig: TwoFollowerRig, key: str, initial_state, static_friction, rtol: float,
                  atol: float) -> Problem:
    """Two followers' problem (module docstring): ``key`` moves the cam of both, or a
    follower's setting of both where the two followers are the same system, else of
    follower 1 only."""
    if not isinstance(rig.drive, CamDrive):
        raise ParameterError(f"the two followers' drive must be a CamDrive, got {type(rig.drive).__name__}")
    unit, value = _system_key(rig.system, key)
    both = rig.second == rig.system or key.startswith(("cam.", "motion."))

    def systems_at(value: float) -> tuple[System, System]:
        first = rig.system.with_values(**{key: value})
        return first, rig.second.with_values(**{key: value}) if both else rig.second

    def pack(value: float) -> tuple[np.ndarray, np.ndarray]:
        first, second = systems_at(value)
        _period(first, key, value)
        return pack_two_followers(first, second, rig.placement, rig.drive, static_friction=static_friction)

    def build(value: float) -> tuple[np.ndarray, float]:
        p, _ = pack(value)
        return p, _period(systems_at(value)[0], key, value)

    p, template = pack(value)
    from camdyn.model import two_followers as pair

    for which in (p, p[pair.SECOND:pair.SECOND + L.SIZE]):
        if which[L.DAMPING_LAW] >= contact.FIRST_RESTITUTION_CODE:
            raise ParameterError("two followers under a restitution-parameterised contact damping law (whose "
                                 "force depends on the approach velocity at each contact's onset) have no "
                                 "monodromy matrix here: use contact.damping = 'viscous', 'power', or another "
                                 "law without a restitution coefficient")
    if initial_state is not None:
        template = _with_start(template, initial_state, 4, "(alpha_1, alpha_1_dot, alpha_2, alpha_2_dot)")
    start = template.copy()

    def template_at(value: float) -> np.ndarray:
        moved = start.copy()
        moved[5] = systems_at(value)[0].motion.angular_speed     # the shaft's prescribed speed [rad/s]
        return moved

    return Problem(systems.TWO_FOLLOWERS, build, value, template, 4, name=key, unit=str(unit), rtol=rtol,
                   atol=atol, impact_sign=1.0, key=key, matrix_rtol=100.0 * rtol, matrix_atol=100.0 * atol,
                   template_at=template_at)


def mechanism_problem(rig, key: str | None = None, initial_state=None, static_friction=None,
                      rtol: float = 1e-10, atol: float = 1e-12) -> Problem:
    """The periodic problem of a mechanism (module docstring), the scalar parameter being
    ``key``: over one cam period ``1 / speed`` [s] for a cam at a prescribed speed, over one
    turn of the cam ``2 pi`` [rad] in the cam angle for a cam under its drive.

    Parameters
    ----------
    rig : FlexiblePivotRig, TwoFollowerRig or DrivenCamRig
        The flexible pivot (:func:`~camdyn.simulation.flexible_pivot.chapter3_flexible_pivot`),
        two followers (:func:`~camdyn.simulation.two_followers.drum_brake`) or the driven
        cam (:func:`camdyn.io.mechanism_config.mechanism_rig` builds each from a
        mechanism file).
    key : str, optional
        The dotted key of the system (``motion.speed`` in [Hz], the default for a cam at a
        prescribed speed; ``cam.runout`` in [m], ...), for the flexible pivot
        ``pivot.stiffness`` [N/m] or ``pivot.damping`` [N s/m], and for a cam under its
        drive a key of :data:`~camdyn.continuation.autonomous.DRIVE_KEYS` (default the one
        that sets the speed: ``drive.torque`` [N m], ``drive.free_speed`` [rad/s] or
        ``drive.target_speed`` [rad/s]) or of the cam or the followers.
    initial_state : array_like, optional
        The unknowns to start from (module docstring); default the static equilibrium.
    static_friction : float or (float, float), optional
        Two followers' static friction coefficients (their stick phase), as
        :func:`~camdyn.simulation.two_followers.pack_two_followers`.
    rtol, atol : float
        Tolerances of the plain runs (every residual); the variational runs (the
        monodromy matrix only) use ``100 rtol, 100 atol`` for two followers and the driven
        cam (as :func:`~camdyn.continuation.problem.system_problem`) and
        ``1000 rtol, 1000 atol`` for the flexible pivot, whose matrix carries the
        bearing's modes (tens of kHz on a stiff bearing): on the chapter 4 rig at
        11.55 Hz on 1e9 N/m a variational run takes 29 s at ``rtol = 1e-8`` and 2.5 s at
        ``1e-7``, the multipliers moving by less than 1e-11 (measured).

    Returns
    -------
    Problem
        For :func:`~camdyn.continuation.orbits.find_orbit` and
        :func:`~camdyn.continuation.branches.continue_orbits`; its ``system`` is None
        (the cam-follower's per-orbit force table does not apply) and impacts are counted
        on follower 1's contact.

    Raises
    ------
    ParameterError
        For another object, an unknown or non-continuous key (or one that does not enter
        the mechanism), a motion that is not constant, a bad bearing, a drive that cannot
        keep the cam turning forward, or a bad start; all before any work.
    """
    limits.check_tolerances(rtol, atol)
    if is_autonomous(rig):
        return autonomous_problem(rig, key, initial_state, static_friction, rtol, atol)
    key = "motion.speed" if key is None else key
    if isinstance(rig, FlexiblePivotRig):
        if static_friction is not None:
            raise ParameterError("static_friction is for two followers; the flexible pivot has no stick phase")
        return _pivot_problem(rig, key, initial_state, rtol, atol)
    if isinstance(rig, TwoFollowerRig):
        return _pair_problem(rig, key, initial_state, static_friction, rtol, atol)
    raise ParameterError(f"periodic orbits are found on the flexible pivot, two followers and the driven cam; got "
                         f"{type(rig).__name__}")


def trace_mechanism(rig, key: str, start: float, stop: float, periods: int = 1, step: float = 0.02,
                    max_points: int = 200, transient: int = 50, rtol: float = 1e-10,
                    progress: Callable[[Orbit], None] | None = None, segments: int = 1,
                    stall: int = 0) -> tuple[Problem, Branch]:
    """The branch of period-``periods`` orbits of a mechanism (:func:`mechanism_problem`)
    from ``key`` [SI unit] at ``start`` towards ``stop``: the orbit at ``start`` after
    ``transient`` cam periods (turns of the cam, for a cam under its drive) from the
    static equilibrium and Newton's method, then pseudo-arclength continuation (``stall``
    its stall test), as
    :func:`~camdyn.continuation.results.trace_branch` does for the cam-follower.

    Raises
    ------
    ParameterError
        For a bad mechanism, key, range or setting, before any work.
    SimulationError
        If no orbit is found at ``start``; for a cam under its drive, also where the cam
        stops or turns back in the transient, or where its speed does not settle (a
        constant torque that no loss growing with the speed balances).
    """
    check_trace_settings(start, stop, periods, segments, transient, max_points, step, "cam periods")
    problem = mechanism_problem(rig, key, rtol=rtol, atol=rtol * 1e-2)
    problem.build(start)                                      # refuse an end value the mechanism cannot take
    problem.build(stop)
    try:
        orbit = find_orbit(problem, value=start, periods=int(periods), transient=transient, segments=int(segments))
    except SimulationError as error:
        if problem.clock is None:
            raise
        raise SimulationError(f"{error} (a cam under its drive has a periodic orbit only where its speed settles: "
                              "the drive must keep it turning forward against the load, and a loss that grows with "
                              "the speed, such as drive.bearing_viscous, must balance a constant torque)") from None
    branch = continue_orbits(problem, orbit, stop, step=step, max_step=max(step, 0.1), max_points=max_points,
                             progress=progress, stall=stall)
    return problem, branch
