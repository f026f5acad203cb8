"""The Alzate / di Bernardo cam-follower rig (the Siconos project's CamFollower example)
run in Siconos's own engine: Moreau-Jean time stepping (theta = 0.5) with Newton's impact
law solved as an LCP at every step. It writes the reference results that
``tests/test_siconos_benchmark.py`` compares camdyn's event-driven solution with.

Run with Debian's interpreter, which has Siconos (not the project's virtual environment)::

    apt-get install python3-siconos
    /usr/bin/python3 benchmarks/siconos_camfollower.py [--quick]

The equations are camdyn's (``camdyn.model.translating_follower``, eq. 1 and 2) written in
the follower's position relative to the cam, ``z = x - s(theta)`` [m], ``theta = pi/2 +
omega t``. Eq. (1) in flight, ``m x'' = -F0 - k x``, becomes the linear oscillator::

    m z'' + k z = -F0 - k s(t) - m s''(t)                                  (1)

with ``F0 = k (0.40 - 0.30)`` [N] (the spring relaxed 0.30 m from the axis), and the cam
is the wall ``z >= 0`` at rest, where Newton's law ``z'+ = -e z'-`` (2) is camdyn's eq. 2
exactly (its relative velocity is ``z'``). The time-dependent right-hand side is given
to Siconos by a Python subclass of ``LagrangianLinearTIDS`` whose ``computeFExt`` Siconos
calls at both ends of each step. The script does not import camdyn: the cam's law is
written below in numpy from the arcs of the example (the distance from the axis to each
arc along the follower's line, law of cosines, and its derivatives in the cam angle).
"""

import json
import math
import multiprocessing
import os
import sys
import tempfile
import time

import numpy as np
import siconos
import siconos.kernel as sk

MASS, STIFFNESS, RESTITUTION = 1.221, 1430.8, 0.8      # [kg], [N/m], [-]
BASE, RELAXED = 0.40, 0.30                             # base radius, spring relaxed at [m]
PRELOAD = STIFFNESS * (BASE - RELAXED)                 # F0 [N]
FLANK_CENTRE, FLANK_RADIUS = 0.45, 0.85                # [m]
NOSE_CENTRE, NOSE_RADIUS = 0.40393320723821, 0.15      # [m]
TOP = NOSE_CENTRE + NOSE_RADIUS                        # [m]
FLANK_END, NOSE_END = 1.050328174371336, 1.22173047639603   # after the base dwell [rad]
PHASE = math.pi / 2                                    # cam angle at t = 0 [rad]
THETA = 0.5                                            # Moreau-Jean's theta [-]
SPEEDS = (358.0, 660.0, 700.0)                         # long runs [rpm]
ACTIVATION = 1e-10      # the contact is in the LCP where the predicted gap is below this [m]
VELOCITY_FLOOR = 1e-2   # impacts counted per revolution are faster than this [m/s]
LONGEST = 24            # the longest period looked for [revolutions]
NOISE = 0.2             # a section repeats where it returns within this fraction of its RMS [-]
SETTLED = 50            # a repeat counts over at least this many revolutions at the window's end
TARGET = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, "tests", "data",
                      "siconos_camfollower.json")


def arc(phi, d, rho):
    """Distance r [m] from the axis to a circle of radius rho [m] centred at distance d [m]
    on the ray phi = 0, along the ray at phi [rad] (law of cosines, r^2 - 2 d r cos phi +
    d^2 = rho^2), and r'' [m/rad^2] by differentiating that relation twice."""
    c, s = math.cos(phi), math.sin(phi)
    root = math.sqrt(rho * rho - d * d * s * s)
    r = d * c + root
    r1 = -d * s - d * d * s * c / root
    r2 = -d * c - d * d * (c * c - s * s) / root - d ** 4 * s * s * c * c / root ** 3
    return r, r1, r2


def cam(theta):
    """Distance h [m] from the axis to the contact point, and h' [m/rad], h'' [m/rad^2] in
    the cam angle theta [rad] (FollowerPlugin's FextFunction, symmetric about pi)."""
    beta = theta % (2.0 * math.pi)
    sign = 1.0
    if beta > math.pi:
        beta, sign = 2.0 * math.pi - beta, -1.0
    if beta <= 0.5 * math.pi:
        return BASE, 0.0, 0.0
    if beta <= 0.5 * math.pi + FLANK_END:
        h, h1, h2 = arc(beta + 0.5 * math.pi, FLANK_CENTRE, FLANK_RADIUS)
    elif beta <= 0.5 * math.pi + NOSE_END:
        h, h1, h2 = arc(beta + math.pi / 9.0 - math.pi, NOSE_CENTRE, NOSE_RADIUS)
    else:
        return TOP, 0.0, 0.0
    return h, sign * h1, h2


def cam_force(t, omega):
    """Right-hand side of eq. (1) at t [s] and cam speed omega [rad/s]: -F0 - k s - m s'' [N]."""
    h, _, h2 = cam(PHASE + omega * t)
    return -PRELOAD - STIFFNESS * (h - BASE) - MASS * omega * omega * h2


class Follower(sk.LagrangianLinearTIDS):
    """The follower in z = x - s: mass m, stiffness k, and eq. (1)'s time-dependent force,
    which Siconos asks for at both ends of every step (theta-weighted)."""

    def __init__(self, omega, z0, v0):
        super().__init__(np.array([z0]), np.array([v0]), np.array([[MASS]]))
        self.setKPtr(np.array([[STIFFNESS]]))
        self.setFExtPtr(np.array([cam_force(0.0, omega)]))
        self.omega = omega

    def computeFExt(self, t):
        self.fExt()[0] = cam_force(t, self.omega)


def simulate(rpm, revolutions, steps, z0=0.0, v0=0.0, keep_path=False):
    """Moreau-Jean run from (z0 [m], z'0 [m/s]) at the end of the base dwell: ``steps``
    steps per revolution. Returns the Poincare section (z, z') once per revolution, the
    impacts (time [s], approach velocity z'- [m/s] at the start of the step whose impulse
    reverses the approach; approaches slower than half a step's velocity change under
    eq. (1)'s force are steps of sustained contact, not impacts), the least impulse per
    step / h (the least mean contact force [N] of a step; 0 once a step needs none) and,
    if asked, z and z' at every step."""
    omega = rpm * 2.0 * math.pi / 60.0
    period = 2.0 * math.pi / omega
    h = period / steps
    n = int(round(revolutions * steps))
    follower = Follower(omega, z0, v0)
    relation = sk.LagrangianLinearTIR(np.array([[1.0]]))
    interaction = sk.Interaction(sk.NewtonImpactNSL(RESTITUTION), relation)
    system = sk.NonSmoothDynamicalSystem(0.0, n * h)
    system.insertDynamicalSystem(follower)
    system.link(interaction, follower)
    integrator = sk.MoreauJeanOSI(THETA)
    # the default threshold, 0, lets the rounding of z in sustained contact (1e-22 m) switch the
    # contact off for a step, which then lets the follower sink into the cam
    integrator.setConstraintActivationThreshold(ACTIVATION)
    stepping = sk.TimeStepping(system, sk.TimeDiscretisation(0.0, h), integrator, sk.LCP())
    q, v = follower.q(), follower.velocity()
    section = np.empty((n // steps + 1, 2))
    section[0] = q[0], v[0]
    path = np.empty((n + 1, 2)) if keep_path else None
    if keep_path:
        path[0] = section[0]
    impacts = []
    least = math.inf
    k = 0
    while stepping.hasNextEvent() and k < n:
        before = v[0]
        stepping.computeOneStep()
        impulse = interaction.lambda_(1)[0]
        k += 1
        if impulse > 0.0:
            least = min(least, impulse / h)
            if before < 0.0 and v[0] > 0.0 and -before > 0.5 * h * abs(cam_force(k * h, omega)) / MASS:
                impacts.append((k * h - h, before))
        else:
            least = min(least, 0.0)
        stepping.nextStep()
        q, v = follower.q(), follower.velocity()
        if keep_path:
            path[k] = q[0], v[0]
        if k % steps == 0:
            section[k // steps] = q[0], v[0]
    return {"section": section, "impacts": np.array(impacts).reshape(-1, 2), "least_force": least,
            "path": path, "h": h, "period": period}


def separates(rpm, steps):
    """Does the follower, started on the cam, leave it before the end of the nose arc, a
    quarter revolution? (a step whose LCP needs no impulse: the cam would have to pull)"""
    return simulate(rpm, 0.25, steps)["least_force"] <= 0.0


def liftoff(steps, low=100.0, high=130.0, tolerance=2e-5):
    """The loss-of-contact speed [rpm] bisected to a relative bracket below ``tolerance``."""
    if separates(low, steps) or not separates(high, steps):
        raise RuntimeError(f"lift-off not bracketed by {low} and {high} rpm")
    while (high - low) / low > tolerance:
        middle = 0.5 * (low + high)
        low, high = (low, middle) if separates(middle, steps) else (middle, high)
    return 0.5 * (low + high)


def lag_deviations(section, longest=LONGEST):
    """For p = 1 .. longest, the largest change of the section points (z [m], z' [m/s])
    over p revolutions, relative to the points' root mean square, per coordinate."""
    size = np.sqrt(np.mean(section ** 2, axis=0))
    lags = range(1, min(longest, len(section) // 2) + 1)
    return [(np.abs(section[p:] - section[:-p]).max(axis=0) / size).tolist() for p in lags]


def period_of(deviations):
    """The least p whose lag deviations are within NOISE in both coordinates (the
    section repeats after p revolutions up to the time stepping's scatter), else None."""
    for p, deviation in enumerate(deviations, start=1):
        if max(deviation) <= NOISE:
            return p
    return None


def regime(section, least=SETTLED):
    """The first revolution of the window from which the section repeats to its end, with
    at least ``least`` revolutions left, its period and lag deviations from there on; or
    None, None and the whole window's lag deviations (no repeat: chaos, or a transient
    longer than the window)."""
    for start in range(len(section) - least + 1):
        deviations = lag_deviations(section[start:])
        period = period_of(deviations)
        if period is not None:
            return start, period, deviations
    return None, None, lag_deviations(section)


def long_run(rpm, steps, transient, revolutions):
    """The regime over ``revolutions`` after ``transient`` revolutions: the Poincare section
    at the end of the base dwell, its period, the impacts faster than VELOCITY_FLOOR per
    revolution, their cam angles [rad] after the section and approach velocities [m/s]."""
    start = time.perf_counter()
    run = simulate(rpm, transient + revolutions, steps)
    period = run["period"]
    section = run["section"][transient:]
    times, velocities = run["impacts"].T if len(run["impacts"]) else (np.empty(0), np.empty(0))
    fast = (times >= transient * period) & (-velocities > VELOCITY_FLOOR)
    turn = np.floor(times[fast] / period + 1e-9).astype(int)
    counts = np.bincount(turn - transient, minlength=revolutions)[:revolutions]
    omega = 2.0 * math.pi / period
    settled, period_revolutions, deviations = regime(section)
    return {"steps_per_revolution": steps, "step_s": run["h"], "transient_revolutions": transient,
            "revolutions": revolutions, "seconds": time.perf_counter() - start,
            "settled_after_revolutions": settled, "period_revolutions": period_revolutions,
            "lag_deviations": deviations,
            "impacts_per_revolution": counts.tolist(),
            "impacts": {"revolution": (turn - transient).tolist(),
                        "angle_rad": (omega * times[fast] - 2.0 * math.pi * turn).tolist(),
                        "velocity_m_per_s": velocities[fast].tolist()},
            "section": section.tolist(),
            "first_impacts": run["impacts"][:40].tolist()}


def time_series(rpm, steps, revolutions, every):
    """z, z' and the cam lift s [m] every ``every`` steps, for the figures."""
    run = simulate(rpm, revolutions, steps, keep_path=True)
    t = np.arange(0, revolutions * steps + 1, every) * run["h"]
    omega = rpm * 2.0 * math.pi / 60.0
    lift = np.array([cam(PHASE + omega * u)[0] - BASE for u in t])
    return {"time_s": t.tolist(), "gap_m": run["path"][::every, 0].tolist(),
            "gap_rate_m_per_s": run["path"][::every, 1].tolist(), "lift_m": lift.tolist()}


def write(result, target):
    """Write the JSON atomically (a temporary file in the same folder, then renamed)."""
    folder = os.path.dirname(os.path.abspath(target))
    os.makedirs(folder, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=folder, suffix=".json")
    with os.fdopen(handle, "w") as stream:
        json.dump(result, stream, indent=1)
        stream.write("\n")
    os.chmod(temporary, 0o644)
    os.replace(temporary, target)


def task(job):
    """One job of the pool: ("liftoff", steps), ("run", rpm, steps, transient, revolutions) or
    ("series", rpm, steps, revolutions, every)."""
    if job[0] == "liftoff":
        return liftoff(job[1])
    if job[0] == "run":
        return long_run(*job[1:])
    return time_series(*job[1:])


def main(quick=False, workers=3):
    base = 1024 if quick else 2048
    ladder = (base, 2 * base, 4 * base)
    transient, revolutions = (10, 30) if quick else (200, 100)
    jobs = [("run", rpm, steps, transient, revolutions) for steps in reversed(ladder) for rpm in SPEEDS]
    jobs += [("liftoff", 16 * steps) for steps in ladder]
    jobs += [("series", 358.0, ladder[-1], 6, ladder[-1] // 128),
             ("series", 660.0, ladder[-1], 10, ladder[-1] // 128)]
    start = time.perf_counter()
    with multiprocessing.Pool(workers) as pool:
        answers = dict(zip(map(repr, jobs), pool.map(task, jobs, chunksize=1)))
    result = {
        "source": "benchmarks/siconos_camfollower.py: Siconos Moreau-Jean time stepping (MoreauJeanOSI theta "
                  f"{THETA}, LCP, NewtonImpactNSL e {RESTITUTION}) of the Alzate / di Bernardo rig in the "
                  "relative coordinate z = x - s",
        "siconos_version": siconos.version, "python": sys.version.split()[0], "numpy": np.__version__,
        "rig": {"mass_kg": MASS, "stiffness_N_per_m": STIFFNESS, "restitution": RESTITUTION,
                "preload_N": PRELOAD, "phase_rad": PHASE},
        "activation_threshold_m": ACTIVATION, "velocity_floor_m_per_s": VELOCITY_FLOOR,
        "section": "z [m] and z' [m/s] at the end of the base dwell (cam angle pi/2 + 2 pi n), every revolution",
        "liftoff_rpm": {str(job[1]): answers[repr(job)] for job in jobs if job[0] == "liftoff"},
        "speeds": {f"{rpm:g}": {str(steps): answers[repr(("run", rpm, steps, transient, revolutions))]
                                for steps in ladder} for rpm in SPEEDS},
        "figures": {f"{job[1]:g}": answers[repr(job)] for job in jobs if job[0] == "series"},
        "seconds": time.perf_counter() - start,
    }
    for steps, rpm in result["liftoff_rpm"].items():
        print(f"lift-off at {steps} steps per revolution: {rpm:.5f} rpm")
    for rpm, runs in result["speeds"].items():
        for steps, run in runs.items():
            print(f"{rpm} rpm, {steps} steps per revolution: period {run['period_revolutions']} from revolution "
                  f"{run['settled_after_revolutions']} of the window, impacts per revolution "
                  f"{sorted(set(run['impacts_per_revolution']))} ({run['seconds']:.0f} s)")
    write(result, TARGET)
    print(f"wrote {os.path.normpath(TARGET)} in {result['seconds']:.0f} s")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv[1:])
