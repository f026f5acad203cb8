"""The rocking follower on a flexible pivot bearing (:mod:`camdyn.model.flexible_pivot`):
:func:`simulate_flexible_pivot` returns an xarray Dataset with units, from the static
equilibrium of the follower and its bearing; :func:`chapter3_flexible_pivot` is the
chapter 3 impact rig on a stand-in bearing."""

from __future__ import annotations

import math
import typing

import numpy as np
import xarray as xr

from camdyn.errors import ParameterError, SimulationError
from camdyn.model import dynamics
from camdyn.model import flexible_pivot as pivot
from camdyn.model import layout as L
from camdyn.model.outputs import pivot_reaction
from camdyn.params.system import System
from camdyn.simulation import limits
from camdyn.simulation.mechanisms import run_mechanism
from camdyn.simulation.runner import prepare
from camdyn.systems import registry as systems

__all__ = ["simulate_flexible_pivot", "flexible_pivot_equilibrium", "natural_frequencies", "chapter3_flexible_pivot",
           "FlexiblePivotRig", "PIVOT_STATE"]

#: The flexible pivot's state: name, unit, long name, in the state's order.
PIVOT_STATE = (
    ("alpha", "rad", "follower angle (clockwise)"),
    ("alpha_dot", "rad/s", "follower angular velocity"),
    ("u", "m", "horizontal displacement of the follower pivot from its rest position"),
    ("u_dot", "m/s", "horizontal velocity of the follower pivot"),
    ("v", "m", "vertical displacement of the follower pivot from its rest position"),
    ("v_dot", "m/s", "vertical velocity of the follower pivot"),
    ("cam_work", "J", "work done by the cam on the follower"),
    ("bearing_work", "J", "work lost in the bearing's damper"),
)


class FlexiblePivotRig(typing.NamedTuple):
    """A cam-follower and its pivot bearing: ``system``, ``pivot_stiffness`` [N/m] and
    ``pivot_damping`` [N s/m], the arguments of :func:`simulate_flexible_pivot`."""

    system: System
    pivot_stiffness: float
    pivot_damping: float


def chapter3_flexible_pivot() -> FlexiblePivotRig:
    """The chapter 3 impact rig (preset ``sundar2014-impact``, Sundar 2014, section 3.6.1)
    on a flexible pivot bearing.

    From the thesis: the whole cam-follower (follower mass and inertia, cam, spring,
    Hertz contact, damping and friction laws) as the preset holds it. Stand-ins: the
    bearing. The thesis treats the pivot as rigid and gives no bearing data, so its
    stiffness and damping here are chosen, not measured: ``kp = 2e7 N/m`` in ``x`` and
    ``y``, of the order of the radial stiffness of a small preloaded ball bearing and
    its housing, near the contact's own linearized stiffness (about 1e7 N/m at the
    static preload), so that the bearing visibly moves the contact resonance; and a
    damping ratio of 5 % of the follower mass on that stiffness,
    ``cp = 2 (0.05) sqrt(kp m)``.
    """
    from camdyn.params.config import load_system

    system = load_system("sundar2014-impact")
    stiffness = 2e7
    damping = 2.0 * 0.05 * math.sqrt(stiffness * system.follower.mass)
    return FlexiblePivotRig(system, stiffness, damping)


def _check_bearing(system, pivot_stiffness, pivot_damping) -> tuple[float, float]:
    limits.check_system(system)
    if system.profile is not None:
        raise ParameterError("the flexible pivot runs on an elliptic or circular cam (cam.semi_major, "
                             "cam.semi_minor), not on a cam profile table")
    kp = limits.check_number("pivot_stiffness", pivot_stiffness, "N/m")
    cp = limits.check_number("pivot_damping", pivot_damping, "N s/m")
    if not (math.isfinite(kp) and kp > 0.0):
        raise ParameterError(f"pivot_stiffness must be a finite, positive number of N/m, got {pivot_stiffness!r}")
    if not (math.isfinite(cp) and cp >= 0.0):
        raise ParameterError(f"pivot_damping must be a finite, non-negative number of N s/m, got {pivot_damping!r}")
    f = system.follower
    if not f.inertia > f.mass * f.cg_distance ** 2 * (1.0 + 1e-9):
        raise ParameterError(
            f"a follower on a flexible pivot needs an inertia about its centre of gravity: follower.inertia "
            f"({f.inertia:g} kg m^2) must exceed m*l_cg^2 ({f.mass * f.cg_distance ** 2:g} kg m^2)")
    if system.motion.kind != "constant":
        raise ParameterError("the flexible pivot runs at a constant cam speed (motion.kind = 'constant'); "
                             f"got {system.motion.kind!r}")
    return kp, cp


def flexible_pivot_equilibrium(system: System, pivot_stiffness: float, pivot_damping: float = 0.0):
    """Parameter vector and initial state of the flexible pivot at its static equilibrium.

    The follower rests (all velocities zero) at the start's cam angle, contact damping
    dropped and friction in the direction the turning cam gives it (as
    :func:`camdyn.model.equilibrium.static_equilibrium`); the bearing carries the load.
    Solved from the rigid pivot's equilibrium with the bearing deflected by that load,
    by :func:`scipy.optimize.root` on the generalized forces [N m, N].

    Returns
    -------
    p : ndarray
        The parameter vector (:mod:`camdyn.model.flexible_pivot`).
    y0 : ndarray
        The initial state (:data:`PIVOT_STATE`).
    prep : camdyn.simulation.runner.Prepared
        The rigid pivot's preparation (its equilibrium, Theta0, contact damping).
    """
    from scipy.optimize import root

    kp, cp = _check_bearing(system, pivot_stiffness, pivot_damping)
    prep = prepare(system)
    p = np.r_[prep.p, kp, cp]
    theta0 = float(p[L.THETA0])
    speed = float(p[L.OMEGA])
    m = system.follower.mass
    weights = np.array([system.follower.inertia - m * system.follower.cg_distance ** 2, m, m])
    mode = np.zeros(L.MODE_SIZE)
    start = np.array([prep.equilibrium.angle, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    systems.initial_mode(systems.FLEXIBLE_PIVOT, 0.0, start, p, mode)
    # the start: the rigid pivot's equilibrium, the bearing deflected by its reaction
    # (unknowns alpha [rad] and the bearing's spring force kp (u, v) [N])
    res = dynamics.evaluate(0.0, prep.equilibrium.angle, 0.0, mode, prep.p)
    reaction = pivot_reaction(prep.equilibrium.angle, 0.0, 0.0, res[1], res[2], res[3], prep.p)
    guess = np.array([prep.equilibrium.angle, -reaction[0], -reaction[1]])

    def residual(x):   # [N m, N, N]
        return pivot.static_residual(np.array([x[0], x[1] / kp, x[2] / kp]), theta0, speed, mode, p) * weights

    sol = root(residual, guess, method="hybr", options={"xtol": 1e-13})
    # a converged root leaves only rounding: 1e-9 of the spring's force (about 10 N on the rigs)
    bound = 1e-9 * max(abs(guess[1]), abs(guess[2]), 1.0)
    if not np.all(np.isfinite(sol.x)) or np.max(np.abs(residual(sol.x))) > bound:
        raise SimulationError(f"no static equilibrium on the flexible pivot (kp = {kp:g} N/m): {sol.message}")
    y0 = np.array([sol.x[0], 0.0, sol.x[1] / kp, 0.0, sol.x[2] / kp, 0.0, 0.0, 0.0])
    return p, y0, prep


def natural_frequencies(system: System, pivot_stiffness: float) -> np.ndarray:
    """Undamped natural frequencies [Hz] of the follower on its bearing, linearized about
    the static equilibrium of :func:`flexible_pivot_equilibrium` with the cam frozen.

    The accelerations of (4)-(5) of :mod:`camdyn.model.flexible_pivot` at rest,
    ``q'' = a(q)``, have the Jacobian ``A = da/dq`` (3 x 3, central differences with
    steps of 1e-7 rad and 1e-10 m); its eigenvalues are ``-omega^2`` (the velocity terms
    are quadratic and drop out). The contact damping and the bearing's damper are left
    out; the contact is held closed.

    Returns
    -------
    ndarray
        The three frequencies, lowest first [Hz]; the rigid pivot's contact mode
        (:attr:`camdyn.model.equilibrium.Equilibrium.natural_frequency`) is the lowest's
        limit as ``pivot_stiffness`` grows.
    """
    p, y0, prep = flexible_pivot_equilibrium(system, pivot_stiffness, 0.0)
    mode = np.zeros(L.MODE_SIZE)
    systems.initial_mode(systems.FLEXIBLE_PIVOT, 0.0, y0, p, mode)
    theta0, speed = float(p[L.THETA0]), float(p[L.OMEGA])
    x0 = y0[[0, 2, 4]]
    steps = np.array([1e-7, 1e-10, 1e-10])
    jac = np.empty((3, 3))
    for j in range(3):
        up, down = x0.copy(), x0.copy()
        up[j] += steps[j]
        down[j] -= steps[j]
        jac[:, j] = (pivot.static_residual(up, theta0, speed, mode, p)
                     - pivot.static_residual(down, theta0, speed, mode, p)) / (2.0 * steps[j])
    squares = np.sort(-np.linalg.eigvals(jac).real)
    return np.sqrt(np.clip(squares, 0.0, None)) / (2.0 * math.pi)


def simulate_flexible_pivot(system: System, pivot_stiffness: float, pivot_damping: float, revolutions: float = 5.0,
                            duration: float | None = None, sample_rate: float = 20e3, rtol: float = 1e-9,
                            atol: float = 1e-11, method: str = "auto", max_step: float | None = None) -> xr.Dataset:
    """Simulate the rocking follower on a flexible pivot bearing.

    Parameters
    ----------
    system : System
        The cam-follower (:func:`camdyn.load_system`), at a constant cam speed.
    pivot_stiffness : float
        Bearing stiffness ``kp`` [N/m], the same in ``x`` and ``y``.
    pivot_damping : float
        Bearing damping ``cp`` [N s/m], the same in ``x`` and ``y``.
    revolutions : float
        Length of the run in cam revolutions [-]; ignored with ``duration``.
    duration : float, optional
        Length of the run [s].
    sample_rate : float
        Output sampling rate [Hz].
    rtol, atol : float
        Local error tolerances: relative [-] and absolute [rad, rad/s, m, m/s].
    method : {"auto", "dop853", "explicit", "rosenbrock", "radau", "switching"}
        Stepper choice (``auto``: DOP853), as in :func:`camdyn.simulate`.
    max_step : float, optional
        Largest step [s]; default 1/12 of the cam period (guards checked every 1/32).

    Returns
    -------
    xarray.Dataset
        Over ``time``: the state (:data:`PIVOT_STATE`) and the channels of
        :data:`camdyn.model.flexible_pivot.CHANNELS` (``Nx``, ``Ny``: the bearing's spring
        and damper force on the follower); attributes: the bearing, the equilibrium the
        run starts from and the solver counters.

    Raises
    ------
    ParameterError
        For a bearing that is not finite and positive (stiffness) or non-negative
        (damping), a follower without inertia about its centre of gravity, a cam given as
        a profile table, a motion that is not constant, or bad run settings; all before
        any work.
    """
    kp, cp = _check_bearing(system, pivot_stiffness, pivot_damping)
    speed = system.motion.angular_speed
    period = 2.0 * math.pi / abs(speed) if speed != 0.0 else math.inf
    if duration is None:
        if not math.isfinite(period):
            raise ParameterError("the cam is at rest: give a duration in seconds")
        duration = limits.check_number("revolutions", revolutions) * period
    p, y0, prep = flexible_pivot_equilibrium(system, kp, cp)
    t, y, modes, events, attrs = run_mechanism(systems.FLEXIBLE_PIVOT, p, y0, duration, sample_rate, period, rtol,
                                               atol, method, max_step)
    data = {name: (("time",), y[:, i], {"units": unit, "long_name": long})
            for i, (name, unit, long) in enumerate(PIVOT_STATE)}
    derived = pivot.channels(t, y, modes, p)
    for i, (name, unit, long) in enumerate(pivot.CHANNELS):
        data[name] = (("time",), derived[:, i], {"units": unit, "long_name": long})
    attrs.update(pivot_stiffness=kp, pivot_damping=cp, initial_alpha=float(y0[0]), initial_u=float(y0[2]),
                 initial_v=float(y0[4]), rigid_equilibrium_angle=prep.equilibrium.angle,
                 speed_hz=system.motion.speed, theta0=float(p[L.THETA0]))
    return xr.Dataset(data, coords={"time": ("time", t, {"units": "s", "long_name": "time"})}, attrs=attrs)
