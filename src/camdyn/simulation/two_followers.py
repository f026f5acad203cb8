"""Two rocking followers on one driven cam (:mod:`camdyn.model.two_followers`):
:func:`simulate_two_followers` returns an xarray Dataset whose per-follower variables run
over a ``follower`` dimension (1, 2), with units; :func:`pack_two_followers` builds the
parameter vector and the starting state; :func:`drum_brake` is a two-follower preset."""

from __future__ import annotations

import math
import typing

import numpy as np
import xarray as xr

from camdyn.errors import ParameterError
from camdyn.model import layout as L
from camdyn.model import two_followers as pair
from camdyn.params.system import System
from camdyn.simulation import limits
from camdyn.simulation.mechanisms import CamDrive, run_mechanism, speed_fluctuation
from camdyn.simulation.runner import prepare
from camdyn.systems import registry as systems

__all__ = ["simulate_two_followers", "pack_two_followers", "drum_brake", "TwoFollowerRig", "PER_FOLLOWER_STATE",
           "SHAFT_STATE"]

#: Per-follower states: name, unit, long name, and the state slots of followers 1 and 2.
PER_FOLLOWER_STATE = (
    ("alpha", "rad", "follower angle (clockwise, in the follower's frame)", (0, 2)),
    ("alpha_dot", "rad/s", "follower angular velocity", (1, 3)),
    ("cam_work", "J", "work done by the cam on the follower", (9, 10)),
)
#: The shaft's states: name, unit, long name, state slot.
SHAFT_STATE = (
    ("cam_angle", "rad", "cam angle Theta (counter-clockwise)", 4),
    ("cam_speed", "rad/s", "cam angular speed Theta_dot", 5),
    ("speed_error_integral", "rad", "integral of the speed error of the PI controller", 6),
    ("drive_work", "J", "work done by the drive on the shaft", 7),
    ("bearing_work", "J", "work lost in the bearing", 8),
)


class TwoFollowerRig(typing.NamedTuple):
    """Two followers on one cam: the arguments of :func:`simulate_two_followers`.

    ``system`` (follower 1 and the cam), ``second`` (follower 2; its cam section equals
    ``system``'s), ``placement`` [rad] and ``drive`` (:class:`CamDrive`)."""

    system: System
    second: System
    placement: float
    drive: CamDrive


def _check_pair(system: System, second: System, placement: float) -> float:
    """Refuse what the two-follower model does not take; return the placement [rad]."""
    for which, s in (("system", system), ("second", second)):
        limits.check_system(s)
        if s.profile is not None:
            raise ParameterError(f"{which}: the two-follower model takes an elliptic or circular cam, not a cam "
                                 "profile (system.profile)")
        if s.motion.kind != "constant":
            raise ParameterError(f"{which}: a driven cam starts from a constant motion (motion.kind = 'constant'); "
                                 f"got {s.motion.kind!r}")
    if second.cam != system.cam:
        raise ParameterError("the two followers ride on one cam: second.cam must equal system.cam")
    phi = limits.check_number("placement", placement, "rad")
    if not math.isfinite(phi):
        raise ParameterError(f"placement must be finite [rad], got {placement!r}")
    if math.remainder(phi, 2.0 * math.pi) != 0.0 and second.gravity != 0.0:
        raise ParameterError("follower 2 rotated about the cam pivot sees gravity rotated too, which the rocking "
                             "follower's moment balance does not take: set second's environment.gravity = 0 "
                             f"for a placement other than 0 (got {placement!r} rad)")
    return phi


def _check_static(static_friction, systems_pair) -> np.ndarray:
    """The ``mu_s`` slots: -1 (no stick phase) or each follower's static coefficient,
    checked against its kinetic one."""
    if static_friction is None:
        return np.array([-1.0, -1.0])
    values = np.broadcast_to(np.asarray(static_friction, dtype=float), (2,)).copy() if np.ndim(
        static_friction) == 0 or np.size(static_friction) == 2 else None
    if values is None or not np.isfinite(values).all():
        raise ParameterError(f"static_friction must be one or two finite coefficients, got {static_friction!r}")
    for k, (mu_s, s) in enumerate(zip(values, systems_pair), start=1):
        if s.friction.law != "coulomb":
            raise ParameterError(f"the stick phase needs Coulomb friction (follower {k} has "
                                 f"friction.law = {s.friction.law!r})")
        if mu_s < s.friction.coefficient:
            raise ParameterError(f"follower {k}: the static friction coefficient ({mu_s}) must not be below the "
                                 f"kinetic one ({s.friction.coefficient})")
    return values


def pack_two_followers(system: System, second: System, placement: float, drive: CamDrive,
                       initial_speed: float | None = None, static_friction=None, initial_angles=None):
    """Parameter vector and starting state of the two-follower model.

    Parameters
    ----------
    system, second : System
        Followers 1 and 2 (:class:`TwoFollowerRig`); ``system``'s motion gives the
        starting cam angle and speed.
    placement : float
        Angle [rad] by which follower 2's pivot is rotated counter-clockwise about the cam
        pivot from where ``second`` places it.
    drive : CamDrive
        The shaft's inertia, drive and bearing.
    initial_speed : float, optional
        Starting cam speed [rad/s]; default ``system.motion``'s angular speed.
    static_friction : float or (float, float), optional
        Static friction coefficients ``mu_s`` [-] of the followers (one for both, or one
        each), at least their Coulomb ``friction.coefficient``; default none, no stick
        phase (kinetic Coulomb friction only).
    initial_angles : (float, float), optional
        Starting follower angles [rad], at rest; default each follower's static
        equilibrium.

    Returns
    -------
    p : ndarray
        The parameter vector (:mod:`camdyn.model.two_followers`). Each follower's
        viscous contact damping coefficient [N s/m] (a damping law set by a damping
        ratio) is the single follower's: from its system's static equilibrium at that
        system's own starting cam angle, not at follower 2's placed one, so that two
        followers of one system get the same coefficient.
    y0 : ndarray (11,)
        Each follower at its static equilibrium (with the friction of the starting
        speed), the shaft at ``system``'s starting angle and speed, the works zero.
    """
    phi = _check_pair(system, second, placement)
    if not isinstance(drive, CamDrive):
        raise ParameterError(f"drive must be a CamDrive, got {type(drive).__name__}")
    speed = system.motion.angular_speed if initial_speed is None else limits.check_number(
        "initial_speed", initial_speed, "rad/s")
    if not math.isfinite(speed):
        raise ParameterError(f"initial_speed must be finite, got {speed!r}")
    motion = {"motion.speed": abs(speed) / (2.0 * math.pi), "motion.direction": 1 if speed >= 0.0 else -1}
    first = prepare(system.with_values(**motion) if initial_speed is not None else system)
    theta0 = first.theta0
    other = prepare(second.with_values(**motion, **{"motion.initial_angle": theta0 - phi}))
    # follower 2's viscous contact damping from its static equilibrium where the single
    # follower takes it, at its own system's starting cam angle (not at the placed
    # follower's starting angle ``theta0 - phi``): a follower's damping coefficient is
    # a property of its system, so two followers of one system get one coefficient
    reference = prepare(second.with_values(**motion) if initial_speed is not None else second)
    other.p[L.VISCOUS_C] = reference.viscous_c
    statics = _check_static(static_friction, (system, second))
    p = np.r_[first.p, drive.slots(), phi, statics, np.zeros(pair.MODE_SIZE), other.p]
    assert p.size == pair.SIZE
    y0 = np.zeros(pair.STATE_SIZE)
    y0[0] = first.equilibrium.angle
    y0[2] = other.equilibrium.angle
    if initial_angles is not None:
        angles = np.asarray(initial_angles, dtype=float)
        if angles.shape != (2,) or not np.isfinite(angles).all():
            raise ParameterError(f"initial_angles must be two finite angles [rad], got {initial_angles!r}")
        y0[[0, 2]] = angles
    y0[4] = theta0
    y0[5] = speed
    return p, y0


def simulate_two_followers(system: System, drive: CamDrive, second: System | None = None,
                           placement: float = math.pi, revolutions: float = 5.0, duration: float | None = None,
                           sample_rate: float = 20e3, initial_speed: float | None = None, static_friction=None,
                           initial_angles=None, rtol: float = 1e-9, atol: float = 1e-11, method: str = "auto",
                           max_step: float | None = None) -> xr.Dataset:
    """Simulate two rocking followers on one cam turning as a rigid body.

    Parameters
    ----------
    system : System
        Follower 1 and the cam (:func:`camdyn.load_system`); its constant motion gives the
        starting cam angle and speed.
    drive : CamDrive
        The shaft's inertia, drive and bearing.
    second : System, optional
        Follower 2 (pivot, spring, contact, friction) in its own frame; default
        ``system``. Its cam section must equal ``system``'s.
    placement : float
        Angle [rad] of follower 2's pivot rotated counter-clockwise about the cam pivot;
        ``pi`` (the default) places an identical follower opposite the first. A
        placement other than 0 needs ``second``'s gravity zero (the frame rotates it).
    revolutions : float
        Length of the run in periods of the starting speed [-]; ignored with ``duration``.
    duration : float, optional
        Length of the run [s].
    sample_rate : float
        Output sampling rate [Hz].
    initial_speed : float, optional
        Starting cam speed [rad/s]; default ``system.motion``'s angular speed.
    static_friction : float or (float, float), optional
        Static friction coefficients ``mu_s`` [-] (:func:`pack_two_followers`); given, the
        Coulomb contacts stick (stick-slip); default none, kinetic friction only.
    initial_angles : (float, float), optional
        Starting follower angles [rad] (:func:`pack_two_followers`).
    rtol, atol : float
        Local error tolerances: relative [-] and absolute [rad, rad/s, J].
    method : {"auto", "dop853", "explicit", "rosenbrock"}
        Stepper choice (``auto``: DOP853).
    max_step : float, optional
        Largest step [s]; default 1/12 of the starting period (guards checked every 1/32).

    Returns
    -------
    xarray.Dataset
        Over ``time`` and ``follower`` (1, 2): :data:`PER_FOLLOWER_STATE` and the
        channels of :data:`camdyn.model.two_followers.CHANNELS`; over ``time``:
        :data:`SHAFT_STATE`, the shaft channels, ``contact_torque_total`` [N m] and
        ``speed_fluctuation`` [rad/s]; over ``transition``: the stick-slip and sprag switches
        (``transition_time`` [s], ``transition_follower``, ``transition_kind``);
        attributes: the placement, the coefficient of speed fluctuation, the mean speed,
        the counts of sticks and sprags, and the solver counters.

    Raises
    ------
    ParameterError
        For a cam profile, a motion that is not constant, two different cams, a
        placement with gravity, or bad run settings; all before any work.
    """
    second = system if second is None else second
    p, y0 = pack_two_followers(system, second, placement, drive, initial_speed, static_friction, initial_angles)
    speed = y0[5]
    period = 2.0 * math.pi / abs(speed) if speed != 0.0 else math.inf
    if duration is None:
        if not math.isfinite(period):
            raise ParameterError("the cam starts at rest: give a duration in seconds")
        duration = limits.check_number("revolutions", revolutions) * period
    t, y, modes, events, attrs = run_mechanism(systems.TWO_FOLLOWERS, p, y0, duration, sample_rate, period, rtol,
                                               atol, method, max_step)
    data = {}
    for name, unit, long, slots in PER_FOLLOWER_STATE:
        data[name] = (("time", "follower"), y[:, list(slots)], {"units": unit, "long_name": long})
    for name, unit, long, slot in SHAFT_STATE:
        data[name] = (("time",), y[:, slot], {"units": unit, "long_name": long})
    per, shaft = pair.channels(y, modes, p)
    for i, (name, unit, long) in enumerate(pair.CHANNELS):
        data[name] = (("time", "follower"), per[:, :, i], {"units": unit, "long_name": long})
    for i, (name, unit, long) in enumerate(pair.SHAFT_CHANNELS):
        data[name] = (("time",), shaft[:, i], {"units": unit, "long_name": long})
    data["contact_torque_total"] = (("time",), per[:, 0, 1] + per[:, 1, 1],
                                    {"units": "N m", "long_name": "moment of both followers' reactions on the cam"})
    mean = float(np.mean(y[:, 5]))
    data["speed_fluctuation"] = (("time",), y[:, 5] - mean, {"units": "rad/s", "long_name": "cam speed less its mean"})
    sticking = [name for name, *_ in pair.CHANNELS].index("sticking")
    switches = _transitions(events, t, per[:, :, sticking])
    data.update(switches)
    attrs.update(sticks=int(np.sum(switches["transition_kind"][1] == "stick")),
                 sprags=int(np.sum(switches["transition_kind"][1] == "sprag")))
    attrs.update(placement=float(p[pair.PLACEMENT]), mean_cam_speed=mean,
                 coefficient_of_fluctuation=speed_fluctuation(y[:, 5]), drive_kind=drive.kind,
                 shaft_inertia=drive.shaft_inertia)
    coords = {"time": ("time", t, {"units": "s", "long_name": "time"}),
              "follower": ("follower", np.array([1, 2]), {"units": "1", "long_name": "follower number"})}
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _transitions(events: np.ndarray, t: np.ndarray, sticking: np.ndarray) -> dict:
    """The stick-slip transitions from the event log, over a ``transition`` dimension:
    time [s], follower (1, 2) and kind: ``"slip"``, a stick that broke (a stick guard);
    at a zero of the sliding velocity, ``"stick"`` if the follower's next switch is a
    stick that breaks (or, with none, if it still sticks at the first sample after),
    else ``"reversal"`` (it slid through); ``"sprag"`` and ``"sprag-end"`` where the
    sprag margin (:func:`camdyn.model.two_followers.sprag_margin`) turns negative
    (self-locking begins) and positive again. ``sticking`` (n, 2) is the sampled flag."""
    from camdyn.integrator import driver

    guard = events[:, driver.EVENT_GUARD].astype(int)
    follower, local = np.divmod(guard, pair.GUARDS_EACH)
    times, followers, kinds = [], [], []
    for row in np.nonzero(np.isin(local, (1, 3, 4, 5)))[0]:
        i = follower[row]
        if local[row] == 5:
            kind = "sprag" if events[row, driver.EVENT_NEW_SIGN] < 0 else "sprag-end"
        elif local[row] != 1:
            kind = "slip"
        else:
            later = np.nonzero((follower[row + 1:] == i) & np.isin(local[row + 1:], (0, 1, 3, 4)))[0]
            if later.size and local[row + 1 + later[0]] in (1, 3, 4):
                kind = "stick" if local[row + 1 + later[0]] != 1 else "reversal"
            else:
                after = np.searchsorted(t, events[row, driver.EVENT_TIME], side="right")
                kind = "stick" if after < t.size and sticking[after, i] > 0.5 else "reversal"
        times.append(events[row, driver.EVENT_TIME])
        followers.append(i + 1)
        kinds.append(kind)
    return {"transition_time": (("transition",), np.array(times, dtype=float), {"units": "s", "long_name": "time"}),
            "transition_follower": (("transition",), np.array(followers, dtype=np.int64),
                                    {"units": "1", "long_name": "follower that switched"}),
            "transition_kind": (("transition",), np.array(kinds, dtype=str),
                                {"long_name": "stick, slip, reversal, sprag or sprag-end"})}


def drum_brake() -> TwoFollowerRig:
    """A two-follower "drum brake": two identical rocking followers placed opposite each
    other (``placement = pi``) on the cam of the chapter 4 friction rig, the shaft under
    a constant drive torque.

    From the thesis (preset ``sundar2014-friction``, Sundar 2014, chapter 4): each
    follower (mass, inertia, geometry), the cam, the spring, the Hertz contact with its
    damping law, and Coulomb friction with ``mu = 0.3``. Stand-ins, chosen here and not
    measured: gravity is set to zero (the second follower, rotated by half a turn, would
    see it reversed, which the follower's moment balance does not take); the shaft
    inertia ``J = 2e-4 kg m^2`` (a small steel cam and shaft); the drive torque
    ``0.1 N m`` and the bearing's viscous coefficient ``2e-4 N m s/rad``, of the order
    of the followers' mean friction torque so that the cam's speed visibly fluctuates.
    """
    from camdyn.params.config import load_system

    s = load_system("sundar2014-friction").with_values(**{"environment.gravity": 0.0})
    drive = CamDrive(shaft_inertia=2e-4, kind="constant", torque=0.1, bearing_viscous=2e-4)
    return TwoFollowerRig(system=s, second=s, placement=math.pi, drive=drive)
