"""Impact events of a periodic-impact record, reconstructed as in thesis 3.5.1.

A record of the follower impacting the cam once per revolution is cut into impact
events, each from one contact onset to the next. Per event:

1. the mean of ``alpha_ddot`` is removed and the rest integrated (trapezoidal rule) to
   ``alpha_dot``; the mean of ``alpha_dot`` is removed and the rest integrated again, which
   gives ``alpha`` up to a constant (both means vanish for a periodic motion);
2. the constant comes from the return-time map (eq 3.19): the free flight of eq 3.9
   from the end of contact, with the measured rate there, must come back to the angle of
   the next onset in the measured time;
3. the cam angle at onset ``Theta(0)`` comes from the contact condition (eq 3.5 with zero
   penetration; of the roots, the one at which the cam approaches), and
   ``Theta(t) = Theta(0) + Omega t`` (eq 3.20);
4. the contact force is computed from the force balance (eq 3.21, here solved for both the
   normal and the friction force, :func:`camdyn.model.outputs.contact_forces_from_reaction`),
   and the penetration ``psi(t)`` from the geometry.

The refusals (one impact per revolution, periodic, enough impacts, contact resolved by
the sampling) are made here, before any fitting.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import xarray as xr
from scipy.integrate import cumulative_simpson, simpson
from scipy.optimize import brentq, minimize_scalar

from camdyn.errors import IdentificationError, ParameterError
from camdyn.identification.impact_kernel import parabola_peak, return_time
from camdyn.model import layout as L
from camdyn.model.geometry import contact_kinematics
from camdyn.model.outputs import contact_forces_from_reaction
from camdyn.params.system import System
from camdyn.records.schema import angular_acceleration, check_record

__all__ = ["ImpactEvents", "impact_events", "detect_contacts"]

#: Largest spread of the onset-to-onset intervals, as a fraction of the cam period, for
#: a record to count as periodic [-].
PERIODIC_SPREAD = 0.02


@dataclass
class ImpactEvents:
    """The reconstructed impact events of one record (all arrays over impacts ``K``).

    Times are from each event's onset [s]; angles [rad]; rates [rad/s].
    """

    system: System
    speed: float                      # cam speed [Hz]
    sample_interval: float            # tau [s]
    onset_time: np.ndarray            # absolute onset times in the record [s]
    event_length: np.ndarray          # onset to next onset [s]
    contact_length: np.ndarray        # onset to end of contact [s]
    alpha0: np.ndarray                # alpha at onset [rad]
    alpha0_map: np.ndarray            # alpha at onset from the return-time map alone [rad] (alpha0
                                      # differs where it had to be moved onto the cam)
    alpha_dot0: np.ndarray            # alpha_dot at onset [rad/s]
    alpha_ddot0: np.ndarray           # alpha_ddot at onset [rad/s^2]
    theta0: np.ndarray                # cam angle at onset [rad]
    peak: np.ndarray                  # alpha_m: extreme angle of the free flight [rad] (eq 3.22)
    offsets: np.ndarray               # (K, M) contact samples after onset [s], NaN padded
    force: np.ndarray                 # (K, M) contact force from the force balance [N] (eq 3.21)
    penetration: np.ndarray           # (K, M) penetration psi from the reconstructed angle [m]
    alpha: list = field(repr=False, default_factory=list)       # per event: alpha samples [rad]
    alpha_dot: list = field(repr=False, default_factory=list)   # per event: alpha_dot samples [rad/s]
    noise: float = 0.0                # noise level of alpha_ddot [rad/s^2] (robust estimate)

    @property
    def count(self) -> int:
        return int(self.onset_time.size)

    @property
    def swing(self) -> np.ndarray:
        """``alpha_m - alpha(0)`` [rad]: the free flight's excursion from the onset angle."""
        return self.peak - self.alpha0


def _noise_level(a: np.ndarray) -> float:
    """Robust standard deviation of white noise on a slowly varying signal."""
    return float(np.median(np.abs(np.diff(a))) / (0.6745 * math.sqrt(2.0)))


def detect_contacts(alpha_ddot: np.ndarray, sample_rate: float, period: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Contact windows ``(start, stop)`` (sample indices, stop exclusive) in ``alpha_ddot``.

    A record whose largest departure from the median is under 10 times the median
    departure has no impulsive events. A contact is where the acceleration departs from
    its free-flight level by more than a threshold (the larger of 8 noise deviations and
    2 % of the largest departure); each window is then widened while the departure from
    the local free-flight level stays above 3 noise deviations (at least 0.1 % of the
    largest departure, which a noise-free record needs: its free-flight acceleration
    drifts). Windows closer than 0.2 % of the cam period are merged.
    """
    a = np.asarray(alpha_ddot, dtype=float)
    level = float(np.median(a))
    noise = _noise_level(a)
    excess = np.abs(a - level)
    top = float(excess.max())
    threshold = max(8.0 * noise, 0.02 * top)
    hot = np.flatnonzero(excess > threshold)
    # impacts are short pulses standing far out of the free-flight acceleration
    crest = top / max(float(np.median(excess)), 1e-300)
    if hot.size == 0 or top <= 0 or crest < 10.0:
        return np.empty(0, int), np.empty(0, int), noise
    gap = max(3, int(0.002 * period * sample_rate))
    breaks = np.flatnonzero(np.diff(hot) > gap)
    starts = np.concatenate(([hot[0]], hot[breaks + 1]))
    stops = np.concatenate((hot[breaks], [hot[-1]])) + 1
    quiet = max(3.0 * noise, 1e-3 * top)
    side = max(8, int(0.002 * period * sample_rate))
    for w in range(starts.size):
        before = a[max(0, starts[w] - 3 * side):max(1, starts[w] - side)]
        base = float(np.median(before)) if before.size else level
        k = starts[w]
        while k > 0 and abs(a[k - 1] - base) > quiet:
            k -= 1
        starts[w] = k
        after = a[min(a.size - 1, stops[w] + side):stops[w] + 3 * side]
        base = float(np.median(after)) if after.size else level
        k = stops[w]
        while k < a.size and abs(a[k] - base) > quiet:
            k += 1
        stops[w] = k
    return starts, stops, noise


def _peak(x: np.ndarray, direction: float) -> float:
    """Extreme of ``direction * x`` refined by a parabola, returned in ``x``'s sign."""
    v = direction * x
    k = int(np.argmax(v))
    best = v[k]
    if 0 < k < v.size - 1:
        best = parabola_peak(v[k - 1], v[k], v[k + 1])
    return direction * best


def _free_before(acc: np.ndarray, k0: int) -> float:
    """Free-flight acceleration [rad/s^2] just before the contact that starts at sample ``k0``."""
    return float(acc[k0 - 1]) if k0 > 0 else float(acc[k0])


def _onset_lead(acc: np.ndarray, k0: int, tau: float) -> float:
    """Time [s] by which the contact onset precedes sample ``k0``.

    Near onset the contact force grows as ``(t - t*)^1.5`` (Hertz, and the power-law
    damping with ``n = 1.5``), and so does the acceleration in excess of free flight; the
    ratio of the excesses at samples ``k0`` and ``k0 + 1`` gives ``t*``. Without this the
    simulated impacts start up to one sample late.
    """
    free = _free_before(acc, k0)
    e0 = acc[k0] - free
    e1 = acc[k0 + 1] - free
    if not (e1 != 0 and e0 / e1 > 0):
        return 0.0
    ratio = min(abs(e0 / e1), 1.0) ** (1.0 / 1.5)
    if ratio >= 1.0:
        return tau
    return float(min(tau, ratio * tau / (1.0 - ratio)))


def onset_cam_angle(p: np.ndarray, alpha0: float, alpha_dot0: float, theta_dot: float) -> tuple[float, float]:
    """Cam angle [rad] at which the follower at ``alpha0`` just touches the cam (eq 3.5
    with zero penetration), choosing the root at which the cam approaches fastest.

    Impacts near the cam's highest lift are sensitive: an angle reconstructed a few
    micro-radians beyond the cam's reach has no root. Then the cam angle of highest lift
    is taken and the angle moved onto the cam, if the move is small (under 2 % of the
    runout, as a moment about the pivot); returns ``(Theta(0), alpha(0))``.
    """
    touch = lambda th, a=alpha0: contact_kinematics(a, 0.0, th, 0.0, p)[0]
    grid = np.linspace(0.0, 2.0 * math.pi, 181)
    delta = np.array([touch(th) for th in grid])
    roots = []
    for k in np.flatnonzero(np.sign(delta[:-1]) != np.sign(delta[1:])):
        th = brentq(touch, grid[k], grid[k + 1], xtol=1e-14, rtol=1e-14)
        rate = contact_kinematics(alpha0, alpha_dot0, th, theta_dot, p)[1]
        roots.append((rate, th))
    if roots:
        return max(roots)[1], alpha0
    k = int(np.argmax(delta))
    best = minimize_scalar(lambda th: -touch(th), bracket=(grid[k] - 0.05, grid[k], grid[k] + 0.05))
    gap = -float(-best.fun)
    chi = contact_kinematics(alpha0, 0.0, best.x, 0.0, p)[2]
    if gap > 0.02 * p[L.RUNOUT] + 1e-7:
        raise IdentificationError(
            f"at the reconstructed onset angle {alpha0:.5g} rad the follower cannot touch the cam "
            f"(it stays {gap * 1e6:.3g} um away); the record does not match the rig's geometry "
            "(check cam.runout and the speed)")
    return float(best.x), alpha0 - gap / chi


def _angle_constant(p, x_start, v_start, t_flight):
    """The constant ``c`` of the integrated angle (``alpha = x + c``, ``x = 0`` at onset)
    from the return-time map (eq 3.19): the free flight from ``(x_start + c, v_start)``
    at the end of contact comes back to the onset angle ``c`` after ``t_flight`` [s]."""
    step = t_flight / 4000.0

    def mismatch(c):
        t = return_time(x_start + c, v_start, c, p, step, 3.0 * t_flight)
        return (t if math.isfinite(t) else 3.0 * t_flight) - t_flight

    # the follower touches the cam somewhere in +-0.6 rad of horizontal; search there
    cs = np.linspace(-0.6, 0.6, 25)
    vals = np.array([mismatch(c) for c in cs])
    signs = np.flatnonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0)
    if signs.size == 0:
        raise IdentificationError(
            "the return-time map has no solution: no follower angle makes the free flight of "
            f"{t_flight * 1e3:.4g} ms match the spring and gravity model; check the spring "
            "parameters, the speed and the sign of the acceleration channel")
    roots = [brentq(mismatch, cs[k], cs[k + 1], xtol=1e-13, rtol=1e-13) for k in signs]
    return min(roots, key=abs) if len(roots) > 1 else roots[0]


def _reconstruct(acc, k0, k1, lead0, lead1, tau):
    """Rate and angle (up to a constant) over one event, from its acceleration samples.

    The event runs from the onset ``t*`` (``lead0`` [s] before sample ``k0``) to the next
    onset (``lead1`` before sample ``k1``), a length ``U``. The means removed are the means
    over exactly ``[t*, t* + U]`` (the partial sample intervals at both ends included), so
    that a period that is not a whole number of samples leaves no drift.

    Returns ``(u, v, x, U)``: offsets of samples ``k0 .. k1-1`` from onset [s], rate
    [rad/s] and angle relative to the onset angle [rad] there, event length [s].
    """
    a = acc[k0:k1]
    n = a.size
    free0 = _free_before(acc, k0)
    u = lead0 + tau * np.arange(n)
    length = (n - 1) * tau + lead0 + (tau - lead1)
    tail = length - u[-1]
    # integral of the onset piece: free flight plus a contact excess growing as u^1.5
    head = lead0 * free0 + (a[0] - free0) * lead0 / 2.5
    bias = (head + simpson(a, dx=tau) + tail * a[-1]) / length
    v = np.empty(n)
    v[0] = head - bias * lead0
    v[1:] = v[0] + cumulative_simpson(a, dx=tau) - bias * tau * np.arange(1, n)
    # v(t*) = v(t* + U) = 0 before the mean of the rate is removed
    mean = (0.5 * lead0 * v[0] + simpson(v, dx=tau) + 0.5 * tail * v[-1]) / length
    v -= mean
    x = np.empty(n)
    x[0] = 0.5 * lead0 * (v[0] - mean)
    x[1:] = x[0] + cumulative_simpson(v, dx=tau)
    return u, v, x, length, -mean


def _record_speed(record: xr.Dataset, speed: float | None) -> float:
    """Cam speed [Hz]: ``speed`` if given, else the record's ``speed_hz`` attribute."""
    if speed is None:
        if "speed_hz" not in record.attrs:
            raise ParameterError("give the cam speed: the record has no speed_hz metadata")
        speed = float(record.attrs["speed_hz"])
    speed = float(speed)
    if not (math.isfinite(speed) and speed > 0):
        raise ParameterError(f"the cam speed must be positive, got {speed!r} Hz")
    return speed


def _periodic_contacts(t: np.ndarray, acc: np.ndarray, speed: float, min_impacts: int,
                       min_contact_samples: int) -> tuple[np.ndarray, np.ndarray, float]:
    """The contact windows of a record with one periodic impact per revolution.

    Parameters
    ----------
    t : ndarray
        Sample times [s], equally spaced.
    acc : ndarray
        ``alpha_ddot`` [rad/s^2] at ``t``.
    speed : float
        Cam speed [Hz].
    min_impacts, min_contact_samples : int
        As in :func:`impact_events`.

    Returns
    -------
    starts, stops : ndarray of int
        Contact windows (sample indices, stop exclusive), see :func:`detect_contacts`.
    noise : float
        Noise level of ``acc`` [rad/s^2].

    Raises
    ------
    IdentificationError
        No periodic impacts, more than one per revolution, too few, or contacts the
        sampling does not resolve.
    """
    tau = float(t[1] - t[0])
    rate = 1.0 / tau
    period = 1.0 / speed
    starts, stops, noise = detect_contacts(acc, rate, period)
    revolutions = (t[-1] - t[0] + tau) * speed
    if starts.size < 2:
        raise IdentificationError(f"found {starts.size} impact(s) in {revolutions:.3g} revolutions: "
                                  "the record shows no periodic impacts")
    per_rev = starts.size / revolutions
    intervals = np.diff(starts) * tau / period
    if per_rev > 1.3 or np.median(intervals) < 0.75:
        why = (f"{per_rev:.2f} impacts per revolution" if per_rev > 1.3 else
               f"{per_rev:.2f} impacts per revolution, but half of the intervals between them are shorter than "
               f"0.75 cam periods (median {np.median(intervals):.3g}, shortest {intervals.min():.3g}): a double "
               f"impact or chatter")
        raise IdentificationError(
            f"found {starts.size} impacts in {revolutions:.3g} revolutions, {why}; the estimator needs exactly one "
            "impact per revolution, because it reconstructs each impact from the free flight of the cam period "
            "before it; change the speed or runout")
    spread = float(intervals.max() - intervals.min())
    if spread > PERIODIC_SPREAD or abs(np.median(intervals) - 1.0) > PERIODIC_SPREAD:
        raise IdentificationError(
            f"the impacts are not periodic: the intervals between impacts range over "
            f"{intervals.min():.4f}-{intervals.max():.4f} cam periods (allowed spread {PERIODIC_SPREAD:g}); "
            "the motion is period-doubled, quasi-periodic or chaotic, or the speed is wrong")
    count = starts.size - 1
    if count < min_impacts:
        raise IdentificationError(f"only {count} complete impact events (need at least {min_impacts}); "
                                  "record more revolutions")
    contact_samples = stops[:-1] - starts[:-1]
    if min_contact_samples and np.median(contact_samples) < min_contact_samples:
        need = min_contact_samples / (np.median(contact_samples) * tau)
        raise IdentificationError(
            f"the sampling rate {rate:.6g} Hz is too low to resolve the contact: impacts span "
            f"{int(np.median(contact_samples))} samples, the estimator needs {min_contact_samples} "
            f"(about {need:.3g} Hz or more)")
    return starts, stops, noise


def _event_motion(p: np.ndarray, acc: np.ndarray, k0: int, k1: int, stop: int, lead0: float, lead1: float,
                  tau: float):
    """Reconstruct the follower's motion over one impact event (steps 1-3 of the module).

    Parameters
    ----------
    p : ndarray
        Parameter vector (:mod:`camdyn.model.layout`).
    acc : ndarray
        The record's ``alpha_ddot`` [rad/s^2].
    k0, k1 : int
        First samples of this contact and of the next one.
    stop : int
        End of this contact (sample index, exclusive).
    lead0, lead1 : float
        Times [s] by which the onsets precede samples ``k0`` and ``k1``.
    tau : float
        Sample interval [s].

    Returns
    -------
    values : dict
        The event's scalars, named as the fields of :class:`ImpactEvents` (``length`` and
        ``contact`` for ``event_length`` and ``contact_length``).
    u : ndarray
        Offsets of samples ``k0 .. k1-1`` from the onset [s].
    v, alpha : ndarray
        Follower rate [rad/s] and angle [rad] there.
    """
    u, v, x, length, alpha_dot0 = _reconstruct(acc, k0, k1, lead0, lead1, tau)
    k_end = min(stop - k0, x.size - 3)
    # the return-time map starts a tenth of the flight after the detected end of
    # contact: a heavily damped contact ends with a long low-force tail that the
    # detection cannot see, and the map needs a state in true free flight
    k_free = k_end + (x.size - k_end) // 10
    c = _angle_constant(p, x[k_free], v[k_free], length - u[k_free])
    alpha = x + c
    direction = 1.0 if v[k_end] >= 0 else -1.0
    theta0, alpha0 = onset_cam_angle(p, c, alpha_dot0, p[L.OMEGA])
    alpha = alpha + (alpha0 - c)
    values = {"alpha0": alpha0, "alpha0_map": c, "alpha_dot0": alpha_dot0, "alpha_ddot0": _free_before(acc, k0),
              "theta0": theta0, "peak": _peak(alpha[k_end:], direction), "length": length, "contact": u[k_end]}
    return values, u, v, alpha


def impact_events(system: System, record: xr.Dataset, speed: float | None = None, min_impacts: int = 5,
                  min_contact_samples: int = 8, need_forces: bool = True) -> ImpactEvents:
    """Cut a periodic-impact record into impact events and reconstruct each (thesis 3.5.1).

    Parameters
    ----------
    system : System
        The rig (geometry, inertia, spring; ``cam.runout`` as in the record).
    record : xarray.Dataset
        ``alpha_ddot`` [rad/s^2] (or ``a_t`` [m/s^2]) and, when ``need_forces``, ``Nx``,
        ``Ny`` [N], over ``time`` [s].
    speed : float, optional
        Cam speed [Hz]; default the record's ``speed_hz`` attribute.
    min_impacts : int
        Fewest complete impact events accepted.
    min_contact_samples : int
        Fewest samples a contact must span for its force history to count as resolved
        (0 skips the check, as the restitution estimate may).
    need_forces : bool
        Compute the contact force from the pivot reactions (eq 3.21).

    Raises
    ------
    IdentificationError
        More than one impact per revolution, impacts not periodic, too few impacts, a
        sampling rate too low to resolve the contact, or a record the rig cannot produce.
    """
    if system.motion.kind != "constant":
        raise ParameterError("the impact estimators need constant cam motion")
    record = angular_acceleration(record, system.follower.sensor_distance)
    check_record(record, ("Nx", "Ny", "alpha_ddot") if need_forces else ("alpha_ddot",))
    speed = _record_speed(record, speed)
    system = system.with_values(**{"motion.speed": speed})
    p = L.pack(system)
    t = record["time"].values
    tau = float(t[1] - t[0])
    acc = record["alpha_ddot"].values.astype(float)
    starts, stops, noise = _periodic_contacts(t, acc, speed, min_impacts, min_contact_samples)
    count = starts.size - 1
    nx = record["Nx"].values if need_forces else None
    ny = record["Ny"].values if need_forces else None
    theta_dot = p[L.OMEGA]
    width = int((stops[:-1] - starts[:-1]).max()) + 2
    offsets = np.full((count, width), np.nan)
    force = np.full((count, width), np.nan)
    pen = np.full((count, width), np.nan)
    fields = {k: np.empty(count) for k in ("alpha0", "alpha0_map", "alpha_dot0", "alpha_ddot0",
                                           "theta0", "peak", "length", "contact")}
    alphas, rates = [], []
    leads = np.array([_onset_lead(acc, k, tau) for k in starts])
    for i in range(count):
        k0 = starts[i]
        values, u, v, alpha = _event_motion(p, acc, k0, starts[i + 1], stops[i], leads[i], leads[i + 1], tau)
        for name, value in values.items():
            fields[name][i] = value
        # step 4: penetration and contact force over the contact
        nc = min(stops[i] - k0 + 1, u.size)
        offsets[i, :nc] = u[:nc]
        thetas = values["theta0"] + theta_dot * u[:nc]
        pen[i, :nc] = [contact_kinematics(alpha[k], v[k], thetas[k], theta_dot, p)[0] for k in range(nc)]
        if need_forces:
            fn, _ = contact_forces_from_reaction(alpha[:nc], v[:nc], acc[k0:k0 + nc], nx[k0:k0 + nc],
                                                 ny[k0:k0 + nc], p)
            force[i, :nc] = fn
        alphas.append(alpha)
        rates.append(v)
    return ImpactEvents(
        system=system, speed=speed, sample_interval=tau, onset_time=t[starts[:-1]],
        event_length=fields["length"], contact_length=fields["contact"], alpha0=fields["alpha0"],
        alpha0_map=fields["alpha0_map"],
        alpha_dot0=fields["alpha_dot0"], alpha_ddot0=fields["alpha_ddot0"], theta0=fields["theta0"],
        peak=fields["peak"], offsets=offsets, force=force,
        penetration=pen, alpha=alphas, alpha_dot=rates, noise=noise)
