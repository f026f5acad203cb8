"""The periodic problem of the autonomous mechanisms: the driven cam
(:mod:`camdyn.model.driven_cam`, :class:`~camdyn.simulation.mechanisms.DrivenCamRig`) and
two followers on a shaft under a torque, a motor or a PI controller
(:mod:`camdyn.model.two_followers`, :class:`~camdyn.simulation.two_followers.TwoFollowerRig`).

Their cam's speed is a state: a steady state repeats in the cam angle, over a period that
is an unknown. The problem is posed with the cam angle as the independent variable
(:mod:`camdyn.model.cam_angle`): the orbit is sought on the Poincare section
``Theta = Theta_0`` (the system's starting cam angle, ``motion.initial_angle``) and the
period map over ``2 pi k`` [rad] is the section's return map, so the shooting and
continuation of :mod:`~camdyn.continuation.orbits` and :mod:`~camdyn.continuation.branches`
run unchanged. Which states are unknowns, and which are not:

- periodic, the unknowns: the followers' angles and rates, the shaft's speed
  ``Theta_dot`` [rad/s], and the PI controller's integral ``z`` [rad] where it enters the
  torque (``drive.kind = "controller"`` with ``drive.integral`` not zero: the torque is
  then periodic only if ``z`` is, which fixes the mean speed at the set point);
- not periodic, kept from the template: the time [s] (its advance over the orbit is the
  orbit's period, :attr:`~camdyn.continuation.problem.Problem.clock`), the works of the
  drive, the bearing and the cam [J] (they grow by the energy per period), and ``z``
  where it feeds back into nothing (``z' = omega_ref - Theta_dot`` grows by
  ``omega_ref T - 2 pi k`` per period); none of them enters the rates.

The section removes the trivial Floquet multiplier (1, along the flow): the monodromy
matrix in the cam angle is the Jacobian of the return map, whose eigenvalues are the
orbit's other multipliers (Seydel 2010, *Practical Bifurcation and Stability Analysis*,
sec. 7.1-7.2, doi:10.1007/978-1-4419-1740-9).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from camdyn.continuation.problem import Problem, parameter_unit
from camdyn.errors import ParameterError
from camdyn.model import cam_angle, contact
from camdyn.model import layout as L
from camdyn.model import two_followers as pair
from camdyn.params.schema import parameter_index
from camdyn.params.system import System
from camdyn.simulation import limits
from camdyn.simulation.mechanisms import CamDrive, DrivenCamRig
from camdyn.simulation.runner import prepare
from camdyn.simulation.two_followers import TwoFollowerRig, pack_two_followers
from camdyn.systems import registry as systems

__all__ = ["autonomous_problem", "DRIVE_KEYS", "default_key", "is_autonomous", "key_unit"]

#: The drive's continuous keys, their units, and the drive kinds each enters (None: all).
DRIVE_KEYS = {
    "drive.shaft_inertia": ("kg m^2", None),
    "drive.torque": ("N m", ("constant", "controller")),
    "drive.stall_torque": ("N m", ("motor",)),
    "drive.free_speed": ("rad/s", ("motor",)),
    "drive.proportional": ("N m s/rad", ("controller",)),
    "drive.integral": ("N m/rad", ("controller",)),
    "drive.target_speed": ("rad/s", ("controller",)),
    "drive.bearing_viscous": ("N m s/rad", None),
    "drive.bearing_coulomb": ("N m", None),
    "drive.bearing_speed": ("rad/s", None),
}
#: The key :func:`default_key` gives each drive kind: the one that sets the speed.
_DEFAULT = {"constant": "drive.torque", "motor": "drive.free_speed", "controller": "drive.target_speed"}
#: The full-turn forcing period of the cam-angle systems [rad].
TURN = 2.0 * math.pi


def is_autonomous(rig) -> bool:
    """Whether ``rig``'s cam turns under its drive (a driven cam, or two followers whose
    drive is not ``"prescribed"``)."""
    return isinstance(rig, DrivenCamRig) or (isinstance(rig, TwoFollowerRig) and isinstance(rig.drive, CamDrive)
                                              and rig.drive.kind != "prescribed")


def default_key(rig) -> str:
    """The drive's key that sets the cam's speed: ``drive.torque`` (a constant torque),
    ``drive.free_speed`` (a motor) or ``drive.target_speed`` (a controller)."""
    return _DEFAULT.get(rig.drive.kind, "drive.torque")


def _check_drive(drive: CamDrive, speed: float) -> None:
    """Refuse a drive that cannot keep the cam turning forward, before any work."""
    if drive.kind == "prescribed":
        raise ParameterError("a cam held at its speed (drive.kind = 'prescribed') has a fixed period: the driven cam "
                             "is then the cam-follower (camdyn.continuation.problem.system_problem)")
    if not speed > 0.0:
        raise ParameterError(f"the cam must start turning forward (counter-clockwise, motion.direction = 1) for its "
                             f"periodic orbits in the cam angle; its starting speed is {speed:g} rad/s")
    if drive.kind == "constant" and not drive.torque > 0.0:
        raise ParameterError(f"a constant drive torque of {drive.torque:g} N m cannot keep the cam turning against "
                             "its losses: no steady state; give drive.torque > 0")
    if drive.kind == "motor" and not (drive.stall_torque > 0.0 and drive.free_speed > 0.0):
        raise ParameterError("a motor turns the cam forward only with drive.stall_torque > 0 and drive.free_speed > 0")
    if drive.kind == "controller" and drive.integral != 0.0 and not drive.target_speed > 0.0:
        raise ParameterError("a PI controller with an integral gain holds the mean speed at its set point: it needs "
                             f"drive.target_speed > 0 (got {drive.target_speed:g} rad/s)")


def _unknowns(drive: CamDrive, followers: int) -> int:
    """The followers' angles and rates, the shaft's speed, and the controller's integral
    where it enters the torque (module docstring)."""
    return 2 * followers + 1 + (drive.kind == "controller" and drive.integral != 0.0)


def _moved_drive(drive: CamDrive, key: str, value: float, reference: CamDrive) -> CamDrive:
    """``drive`` with its ``key`` at ``value`` (its checks rerun), refused where the
    integral gain of a controller whose integral is an unknown reaches zero or turns."""
    moved = dataclasses.replace(drive, **{key.split(".", 1)[1]: float(value)})
    _check_drive(moved, 1.0)
    if key == "drive.integral" and reference.integral * moved.integral <= 0.0:
        raise ParameterError("drive.integral must keep its sign: where it vanishes the controller's integral is no "
                             f"longer periodic (got {value:g} N m/rad from {reference.integral:g})")
    return moved


def _key(rig, key: str) -> tuple[str, float, bool]:
    """The unit, starting value and whether ``key`` is the drive's, refused where it does
    not enter the mechanism."""
    if key in DRIVE_KEYS:
        unit, kinds = DRIVE_KEYS[key]
        if kinds is not None and rig.drive.kind not in kinds:
            own = [k for k, (_, entered) in DRIVE_KEYS.items() if entered is None or rig.drive.kind in entered]
            raise ParameterError(f"{key} does not enter a {rig.drive.kind!r} drive; its keys are {', '.join(own)}")
        value = float(getattr(rig.drive, key.split(".", 1)[1]))
        if not math.isfinite(value):
            raise ParameterError(f"{key} has no finite value to start from")
        return unit, value, True
    if key.startswith("drive."):
        raise ParameterError(f"{key} is not a continuous drive key; they are {', '.join(DRIVE_KEYS)}")
    if key.startswith("motion."):
        raise ParameterError(f"{key} sets only where the driven cam starts (its speed is a state that settles where "
                             f"the drive and the load balance): continue in a drive key such as {default_key(rig)}, "
                             "or in a key of the cam or the follower")
    unit = parameter_unit(rig.system, key)
    value = parameter_index(type(rig.system))[key].getter(rig.system)
    if value is None or not math.isfinite(float(value)):
        raise ParameterError(f"{key} has no finite value to start from")
    return unit, float(value), False


def key_unit(rig, key: str) -> str:
    """The unit of the continuous parameter ``key`` of an autonomous mechanism, refused
    (:class:`ParameterError`) where it does not enter the mechanism (as
    :func:`autonomous_problem` refuses it)."""
    return _key(rig, key)[0]


def _check_system(system: System) -> None:
    limits.check_system(system)
    if system.profile is not None:
        raise ParameterError("the driven cam takes an elliptic or circular cam, not a cam profile (system.profile)")
    if system.motion.kind != "constant":
        raise ParameterError(f"a driven cam starts from a constant motion (motion.kind = 'constant'); got "
                             f"{system.motion.kind!r}")


def _start(template: np.ndarray, initial_state, count: int) -> np.ndarray:
    if initial_state is None:
        return template
    start = np.asarray(initial_state, dtype=float).reshape(-1)
    if start.size != count or not np.all(np.isfinite(start)):
        raise ParameterError(f"initial_state is the {count} unknowns (the followers' angles and rates, the cam's "
                             f"speed [rad/s] and, under a PI controller with an integral gain, its integral [rad]); "
                             f"got {initial_state!r}")
    out = template.copy()
    out[:count] = start
    return out


def _driven_problem(rig: DrivenCamRig, key: str, initial_state, rtol: float, atol: float) -> Problem:
    _check_system(rig.system)
    _check_drive(rig.drive, rig.system.motion.angular_speed)
    unit, value, is_drive = _key(rig, key)
    prep = prepare(rig.system)
    base = prep.p.copy()

    def build(value: float) -> tuple[np.ndarray, float]:
        if is_drive:
            return np.r_[base, _moved_drive(rig.drive, key, value, rig.drive).slots()], TURN
        moved = rig.system.with_values(**{key: value})
        _check_system(moved)
        return np.r_[prepare(moved).p, rig.drive.slots()], TURN

    build(value)
    y0 = np.array([prep.equilibrium.angle, 0.0, prep.theta0, rig.system.motion.angular_speed, 0.0, 0.0, 0.0, 0.0])
    template = np.empty(y0.size)
    cam_angle.to_angle(y0, 0.0, 0, template)
    count = _unknowns(rig.drive, 1)
    return Problem(systems.DRIVEN_CAM_ANGLE, build, value, _start(template, initial_state, count), count, name=key,
                   unit=str(unit), t_start=float(prep.theta0), rtol=rtol, atol=atol, impact_sign=1.0, key=key,
                   matrix_rtol=100.0 * rtol, matrix_atol=100.0 * atol, clock=int(cam_angle.clock_slot(0)))


def _pair_problem(rig: TwoFollowerRig, key: str, initial_state, static_friction, rtol: float,
                  atol: float) -> Problem:
    for system in (rig.system, rig.second):
        _check_system(system)
    _check_drive(rig.drive, rig.system.motion.angular_speed)
    unit, value, is_drive = _key(rig, key)
    both = rig.second == rig.system or key.startswith("cam.")

    def pack(value: float) -> tuple[np.ndarray, np.ndarray]:
        first, second, drive = rig.system, rig.second, rig.drive
        if is_drive:
            drive = _moved_drive(rig.drive, key, value, rig.drive)
        else:
            first = rig.system.with_values(**{key: value})
            second = rig.second.with_values(**{key: value}) if both else rig.second
        return pack_two_followers(first, second, rig.placement, drive, static_friction=static_friction)

    p, y0 = pack(value)
    for which in (p, p[pair.SECOND:pair.SECOND + L.SIZE]):
        if which[L.DAMPING_LAW] >= contact.FIRST_RESTITUTION_CODE:
            raise ParameterError("two followers under a restitution-parameterised contact damping law have no "
                                 "monodromy matrix here: use contact.damping = 'viscous', 'power', or another law "
                                 "without a restitution coefficient")
    template = np.empty(y0.size)
    cam_angle.to_angle(y0, 0.0, 1, template)
    count = _unknowns(rig.drive, 2)
    return Problem(systems.TWO_FOLLOWERS_ANGLE, lambda value: (pack(value)[0], TURN), value,
                   _start(template, initial_state, count), count, name=key, unit=str(unit), t_start=float(y0[4]),
                   rtol=rtol, atol=atol, impact_sign=1.0, key=key, matrix_rtol=100.0 * rtol,
                   matrix_atol=100.0 * atol, clock=int(cam_angle.clock_slot(1)))


def autonomous_problem(rig, key: str | None = None, initial_state=None, static_friction=None, rtol: float = 1e-10,
                       atol: float = 1e-12) -> Problem:
    """The periodic problem of an autonomous mechanism (module docstring), over one turn
    of the cam ``2 pi`` [rad] in the cam angle, the scalar parameter being ``key``: a
    drive key of :data:`DRIVE_KEYS` that enters the rig's drive (default
    :func:`default_key`), or a continuous key of the system (not ``motion.*``, which sets
    only where the run starts). The orbit's ``period`` is then its own [s]."""
    key = default_key(rig) if key is None else key
    if isinstance(rig, DrivenCamRig):
        if static_friction is not None:
            raise ParameterError("static_friction is for two followers; the driven cam has no stick phase")
        return _driven_problem(rig, key, initial_state, rtol, atol)
    return _pair_problem(rig, key, initial_state, static_friction, rtol, atol)
