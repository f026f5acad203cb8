"""Direct identification of the impact damping ``beta``, ``n`` of
``Fn = K delta^1.5 + beta delta^n delta_dot`` (eq 3.14) by restoring-force regression.

The thesis calls a direct method impossible (3.5.2) and asks for one (future work 5).
This module rebuilds, for every impact of a record, the contact force and the
penetration from the measured signals, and regresses the one on the other (the
restoring-force method of Haddadi and Hashtrudi-Zaad, IEEE T-RO 28 (2012),
doi:10.1109/TRO.2011.2165310, written for Hunt-Crossley contacts):

1. **Contact force.** ``Fn`` and ``Ff`` [N] from the pivot reaction ``Nx``, ``Ny`` and the
   follower's inertia times its measured acceleration (eqs 3.21, 4.29-4.30,
   :func:`camdyn.model.outputs.contact_forces_from_reaction`), as the thesis does for
   ``F_lambda``.
2. **Moment arm.** Over one impact the spring and gravity moment is nearly constant, so
   ``I_P alpha_ddot - Ff h = M + chi Fn`` (eq 3.16) gives the moment arm ``chi`` [m] of the
   impact by linear regression of two measured signals.
3. **Penetration.** The measured acceleration is integrated over the impact (Simpson's
   rule): ``delta_dot = v - chi W``, ``delta = d + v t - chi WW`` (``W``, ``WW``: the first
   and second integrals of ``alpha_ddot`` from the window's start; ``delta_dot = -chi
   alpha_dot - n.v_cam``, docs/model.md §2, the cam's part constant over the impact).
   The two anchors ``d`` [m] and ``v`` [m/s] of each impact (where contact starts, and at
   what approach velocity), and the cam's normal acceleration over it, are fitted with the
   impact's own damping coefficient, so that the penetration is zero at the contact onset
   and the force there follows Hertz (:mod:`camdyn.identification.impact_anchors`: all
   impacts' Levenberg-Marquardt steps taken together).
4. **Regression.** With the penetrations fixed, ``Fn - K delta^1.5 = beta delta^n
   delta_dot`` is linear in ``beta`` (and in ``K`` when it is fitted), solved by least
   squares at each ``n``; ``n`` minimises the residual (a bounded one-dimensional search,
   variable projection). Steps 3-4 alternate until ``n`` settles; the alternation
   converges linearly, so every third exponent is extrapolated by Aitken's method.

Confidence intervals come from the impact-clustered (sandwich) covariance of the
regression, which counts the errors every sample of one impact shares (its anchors);
``correlation`` is the correlation of ``beta`` and ``n``. Records whose penetration cannot
be rebuilt are refused: contacts spanning too few samples, a rebuilt force that does
not return to zero between impacts (drift or offset), clipped or non-finite samples,
moment arms the rig cannot have. Nothing here assumes one impact per revolution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import xarray as xr
from scipy.integrate import cumulative_simpson

from camdyn.errors import IdentificationError, ParameterError
from camdyn.identification.impact_anchors import PaddedImpacts, fit_anchors
from camdyn.identification.impact_events import detect_contacts
from camdyn.identification.impact_regression import EXPONENT_RANGE, ForceRegression, interval_95, per_impact_table
from camdyn.model import layout as L
from camdyn.model.contact import hertz_line_coefficient, hertz_point_coefficient
from camdyn.model.equilibrium import as_system
from camdyn.model.geometry import contact_kinematics, zero_state
from camdyn.model.outputs import contact_forces_from_reaction
from camdyn.records.schema import angular_acceleration, check_consistency, check_record, record_speed, require_record

__all__ = ["DirectImpactEstimate", "ImpactSamples", "estimate_impact_damping_direct", "rebuild_impacts",
           "penetration", "COLLINEARITY_LIMIT"]

#: Largest ``|correlation|`` of ``beta`` and ``n`` at which ``n`` still counts as told apart
#: from ``beta`` [-]; above it the estimate is flagged not identifiable.
COLLINEARITY_LIMIT = 0.999
#: Smallest spread (largest minus smallest over the median) of the impacts' peak
#: penetrations for ``n`` to count as identified across impacts [-].
SPREAD_LIMIT = 0.05
#: Largest free-flight level of the rebuilt contact force, as a fraction of the median
#: peak force, before the record is refused as drifting [-].
DRIFT_LIMIT = 0.02


@dataclass
class ImpactSamples:
    """The samples of the impacts of one or more records, rebuilt for the regression.

    Per impact ``k`` (lists over impacts): ``offset`` times from the window's start [s],
    ``force`` the rebuilt normal force [N], ``rate_integral`` ``W`` [rad/s] and
    ``angle_integral`` ``WW`` [rad] of the measured ``alpha_ddot``; ``arm`` the fitted moment
    arm ``chi`` [m] (array over impacts); ``stiffness`` the Hertz coefficient ``K``
    [N/m^elastic_exponent] of each impact.
    """

    offset: list
    force: list
    rate_integral: list
    angle_integral: list
    arm: np.ndarray
    stiffness: np.ndarray
    elastic_exponent: float
    onset_time: np.ndarray          # absolute time of each window's start in its record [s]
    record: np.ndarray              # record index of each impact [-]
    contact_samples: np.ndarray     # samples each contact spans [-]

    @property
    def count(self) -> int:
        return len(self.force)


@dataclass
class DirectImpactEstimate:
    """Result of :func:`estimate_impact_damping_direct` (units in the comments)."""

    beta: float                  # [N s m^-(n+1)]
    exponent: float              # n [-]
    mode: str                    # "free" or "fixed"
    stiffness: float             # K [N/m^1.5] used or fitted
    damping_at_peak: float       # beta * delta_peak^n [N s/m]
    peak_penetration: float      # median peak penetration over impacts [m]
    confidence: dict             # 95 % intervals of beta, n, damping_at_peak
    correlation: float           # correlation of beta and n [-] (NaN when n is fixed)
    correlation_at_peak: float   # correlation of log(damping_at_peak) and n [-]
    identifiable: bool           # False when n cannot be told from beta
    diagnosis: str               # why not identifiable ("" when it is)
    rms_residual: float          # rms force residual over the contact samples [N]
    impacts_used: int
    records: int
    iterations: int              # alternations of anchors and regression
    per_impact: dict = field(repr=False, default_factory=dict)

    @property
    def beta_units(self) -> str:
        return f"N*s/m^{self.exponent + 1:.4g}"

    def to_dict(self) -> dict:
        return {
            "method": "direct", "beta": self.beta, "beta_units": self.beta_units, "n": self.exponent,
            "mode": self.mode, "stiffness": self.stiffness, "damping_at_peak": self.damping_at_peak,
            "damping_at_peak_units": "N*s/m", "peak_penetration": self.peak_penetration,
            "peak_penetration_units": "m", "confidence_95": {k: list(v) for k, v in self.confidence.items()},
            "correlation": self.correlation, "correlation_at_peak": self.correlation_at_peak,
            "identifiable": self.identifiable, "diagnosis": self.diagnosis,
            "rms_residual": self.rms_residual, "impacts_used": self.impacts_used, "records": self.records,
            "iterations": self.iterations,
            "per_impact": {k: np.asarray(v).tolist() for k, v in self.per_impact.items()},
        }


def _hertz(p: np.ndarray, alpha: float, theta: float) -> tuple[float, float]:
    """Hertz coefficient ``K`` and elastic exponent (1.5 point, 1 line) at the contact of
    the follower at ``alpha`` [rad] with the cam at ``theta`` [rad] (eqs 2.14, 3.11, 4.18)."""
    rho_c = contact_kinematics(alpha, 0.0, theta, 0.0, p)[3]
    if p[L.CONTACT_KIND] == 0:
        rho_e = 1.0 / (1.0 / rho_c + 1.0 / p[L.PIN])    # eq (4.18)
        return hertz_point_coefficient(p[L.ESTAR], rho_e), 1.5
    return hertz_line_coefficient(p[L.ESTAR], p[L.LINE_LENGTH]), 1.0


def _integrals(acc: np.ndarray, tau: float) -> tuple[np.ndarray, np.ndarray]:
    """First and second integrals [rad/s, rad] of ``acc`` [rad/s^2] from its first sample."""
    w = cumulative_simpson(acc, dx=tau, initial=0.0)
    return w, cumulative_simpson(w, dx=tau, initial=0.0)


def _windows(acc, tau, period, min_contact_samples):
    """Contact windows with margins, ``(lo, hi, start, stop)`` sample indices, and the
    median contact length [samples]; refuses records without resolvable impacts."""
    starts, stops, _ = detect_contacts(acc, 1.0 / tau, period)
    if starts.size < 2:
        raise IdentificationError(f"found {starts.size} impact(s): the direct method needs at least 2 impacts "
                                  "with free flight between them")
    span = stops - starts
    median = int(np.median(span))
    if median < min_contact_samples:
        raise IdentificationError(
            f"the sampling rate {1 / tau:.6g} Hz is too low to rebuild the penetration: impacts span {median} "
            f"samples, the direct method needs {min_contact_samples} (about "
            f"{min_contact_samples / (median * tau):.3g} Hz or more)")
    margin = max(4, median // 3)
    lo = np.maximum(starts - margin, 0)
    hi = np.minimum(stops + margin, acc.size)
    keep = (starts - margin >= 0) & (stops + margin <= acc.size)
    keep[1:] &= starts[1:] - margin >= stops[:-1]
    keep[:-1] &= stops[:-1] + margin <= starts[1:]
    return lo[keep], hi[keep], starts[keep], stops[keep], median


def rebuild_impacts(system, record: xr.Dataset, speed: float | None = None, runout: float | None = None,
                    min_contact_samples: int = 8) -> ImpactSamples:
    """Cut a record into impacts and rebuild each impact's force and acceleration integrals
    (steps 1-2 of the module).

    Parameters
    ----------
    system : System
        The rig.
    record : xarray.Dataset
        ``Nx``, ``Ny`` [N] and ``alpha_ddot`` [rad/s^2] (or ``a_t`` [m/s^2]) over ``time`` [s].
    speed : float, optional
        Cam speed [Hz]; default the record's ``speed_hz``.
    runout : float, optional
        Cam runout [m]; default the record's ``runout``, else the system's.
    min_contact_samples : int
        Fewest samples a contact must span [-].

    Raises
    ------
    IdentificationError
        Too few impacts, too few samples per contact, a drifting force, implausible arms.
    DataError
        Missing, non-finite or clipped channels.
    """
    record = require_record(record)
    system = as_system(system)
    record = angular_acceleration(record, system.follower.sensor_distance)
    check_record(record, ("Nx", "Ny", "alpha_ddot"))
    speed = record_speed(speed) or record_speed(record.attrs.get("speed_hz"), "speed_hz")
    if speed is None:
        raise ParameterError("give the cam speed: the record has no speed_hz metadata")
    check_consistency(record, speed=speed, runout=runout, preset=system.name, what="the options")
    runout = runout if runout is not None else record.attrs.get("runout")
    values = {"motion.speed": speed} | ({"cam.runout": float(runout)} if runout is not None else {})
    system = system.with_values(**values)
    p = L.pack(system)
    t = record["time"].values
    tau = float(t[1] - t[0])
    acc = record["alpha_ddot"].values.astype(float)
    lo, hi, starts, stops, median = _windows(acc, tau, 1.0 / speed, min_contact_samples)
    alpha_ref, theta_ref = zero_state(system)
    stiffness, elastic = _hertz(p, alpha_ref, theta_ref)
    chi_ref = contact_kinematics(alpha_ref, 0.0, theta_ref, 0.0, p)[2]
    nx, ny = record["Nx"].values.astype(float), record["Ny"].values.astype(float)
    fn_all, ff_all = contact_forces_from_reaction(np.full(acc.size, alpha_ref), np.zeros(acc.size), acc, nx, ny, p)
    out = {k: [] for k in ("offset", "force", "w", "ww")}
    arms = []
    for a, b in zip(lo, hi):
        sl = slice(a, b)
        # eq (3.16) over one impact: I_P alpha_ddot - Ff h = M + chi Fn, M nearly constant
        rhs = p[L.INERTIA] * acc[sl] - ff_all[sl] * p[L.OFFSET]
        design = np.column_stack([np.ones(b - a), fn_all[sl]])
        arms.append(np.linalg.lstsq(design, rhs, rcond=None)[0][1])
        w, ww = _integrals(acc[sl], tau)
        out["offset"].append(tau * np.arange(b - a))
        out["force"].append(fn_all[sl])
        out["w"].append(w)
        out["ww"].append(ww)
    arms = np.array(arms)
    _check_rebuild(fn_all, lo, hi, starts, stops, arms, chi_ref, system.cam.runout)
    return ImpactSamples(offset=out["offset"], force=out["force"], rate_integral=out["w"],
                         angle_integral=out["ww"], arm=arms, stiffness=np.full(arms.size, stiffness),
                         elastic_exponent=elastic, onset_time=t[lo], record=np.zeros(arms.size, int),
                         contact_samples=stops - starts)


def _check_rebuild(fn, lo, hi, starts, stops, arms, chi_ref, runout):
    """Refuse a rebuild whose force drifts between impacts or whose moment arms the rig
    cannot have (more than twice the runout, plus 2 mm, from the 0-state's arm [m])."""
    peak = float(np.median([fn[a:b].max() for a, b in zip(starts, stops)]))
    free = np.concatenate([np.r_[fn[a:s], fn[e:b]] for a, b, s, e in zip(lo, hi, starts, stops)])
    level = float(np.median(free))
    if not peak > 0:
        raise IdentificationError("the rebuilt contact force is not positive at the impacts: check the signs of "
                                  "Nx, Ny and alpha_ddot and the preset's geometry")
    if abs(level) > DRIFT_LIMIT * peak:
        raise IdentificationError(
            f"the rebuilt contact force stays at {level:.4g} N between impacts ({abs(level) / peak:.1%} of the "
            f"peak {peak:.4g} N; at most {DRIFT_LIMIT:.0%}): the force channels drift or carry an offset, or the "
            "preset's mass, inertia or spring do not match the rig")
    bad = np.abs(arms - chi_ref) > 2.0 * runout + 2e-3
    if bad.any():
        raise IdentificationError(
            f"the moment arm fitted from acceleration and force is {arms[bad][0] * 1e3:.4g} mm at impact "
            f"{int(np.flatnonzero(bad)[0]) + 1}, the rig's is {chi_ref * 1e3:.4g} mm: the acceleration and the "
            "forces disagree (check the inertia, the accelerometer distance and the channels' signs)")


def penetration(s: ImpactSamples, k: int, d: float, v: float, a: float = 0.0):
    """Penetration [m] and its rate [m/s] of impact ``k`` with anchors ``d`` [m], ``v`` [m/s]
    and the cam's normal acceleration ``a`` [m/s^2]."""
    chi = s.arm[k]
    t = s.offset[k]
    return d + v * t + 0.5 * a * t * t - chi * s.angle_integral[k], v + a * t - chi * s.rate_integral[k]


def _initial_anchors(s: ImpactSamples) -> np.ndarray:
    """Anchors ``(d, v)`` per impact from the force peak, where ``delta_dot = 0`` and
    ``Fn = K delta^1.5`` (eq 3.11)."""
    x = np.zeros((s.count, 3))
    for k in range(s.count):
        j = int(np.argmax(s.force[k]))
        v = s.arm[k] * s.rate_integral[k][j]
        peak = (max(s.force[k][j], 0.0) / s.stiffness[k]) ** (1.0 / s.elastic_exponent)
        x[k, :2] = peak - v * s.offset[k][j] + s.arm[k] * s.angle_integral[k][j], v
    return x


def estimate_impact_damping_direct(system, records, speed=None, runout=None, exponent: float | None = None,
                                   fit_stiffness: bool = False, min_contact_samples: int = 8,
                                   max_iterations: int = 30) -> DirectImpactEstimate:
    """Identify ``beta``, ``n`` directly by restoring-force regression (see the module).

    Parameters
    ----------
    system : System
        The rig (its damping settings are not used).
    records : Dataset or list of Dataset
        Records with ``Nx``, ``Ny`` [N] and ``alpha_ddot`` [rad/s^2] (or ``a_t`` [m/s^2]);
        any number of impacts per revolution, periodic or not.
    speed, runout : float or list, optional
        Cam speed [Hz] and runout [m], one for all records or one per record; default each
        record's ``speed_hz`` and ``runout`` attributes.
    exponent : float, optional
        Fix ``n`` [-]; default free.
    fit_stiffness : bool
        Fit a factor on the Hertz coefficient ``K`` too (default: ``K`` from the geometry).
    min_contact_samples : int
        Fewest samples a contact must span to rebuild its penetration [-].
    max_iterations : int
        Most alternations of the anchors (step 3) and the regression (step 4).

    Returns
    -------
    DirectImpactEstimate

    Raises
    ------
    IdentificationError
        A record whose penetration cannot be rebuilt (the message says why).
    """
    records = [records] if isinstance(records, xr.Dataset) else list(records)
    if not records:
        raise ParameterError("no records to fit")
    if exponent is not None and not (math.isfinite(exponent) and EXPONENT_RANGE[0] <= exponent <= EXPONENT_RANGE[1]):
        raise ParameterError(f"the fixed exponent n must be between 0 and 3, got {exponent!r}")
    n_rec = len(records)
    speeds = list(speed) if isinstance(speed, (list, tuple)) else [speed] * n_rec
    runouts = list(runout) if isinstance(runout, (list, tuple)) else [runout] * n_rec
    if len(speeds) != n_rec or len(runouts) != n_rec:
        raise ParameterError(f"give one speed and one runout per record ({n_rec}), or one for all")
    parts = [rebuild_impacts(system, r, sp, ro, min_contact_samples) for r, sp, ro in zip(records, speeds, runouts)]
    s = _merge(parts)
    return _estimate(s, exponent, fit_stiffness, max_iterations, n_rec)


def _merge(parts: list[ImpactSamples]) -> ImpactSamples:
    """The impacts of several records as one set."""
    if len(parts) == 1:
        return parts[0]
    cat = lambda name: [x for q in parts for x in getattr(q, name)]
    arr = lambda name: np.concatenate([getattr(q, name) for q in parts])
    return ImpactSamples(offset=cat("offset"), force=cat("force"), rate_integral=cat("rate_integral"),
                         angle_integral=cat("angle_integral"), arm=arr("arm"), stiffness=arr("stiffness"),
                         elastic_exponent=parts[0].elastic_exponent, onset_time=arr("onset_time"),
                         record=np.concatenate([np.full(q.count, i) for i, q in enumerate(parts)]),
                         contact_samples=arr("contact_samples"))


def _aitken(n: list) -> float:
    """Aitken's extrapolation of three successive exponents of the alternation [-] (it
    converges linearly); the last one where the steps do not shrink geometrically."""
    d1, d2 = n[1] - n[0], n[2] - n[1]
    if d1 == 0 or not 0.0 < d2 / d1 < 0.95:
        return n[2]
    return float(np.clip(n[2] - d2 * d2 / (d2 - d1), *EXPONENT_RANGE))


def _estimate(s: ImpactSamples, exponent, fit_stiffness, max_iterations, n_rec) -> DirectImpactEstimate:
    """Steps 3-4 alternated, then the intervals and the diagnostics."""
    anchors = _initial_anchors(s)
    pad = PaddedImpacts(s)
    n_hat = 1.5 if exponent is None else float(exponent)
    beta = ForceRegression(s, anchors, fit_stiffness, penetration).solve(n_hat)[0][0]
    iterations, history = 0, [n_hat]
    while iterations < max_iterations:
        iterations += 1
        # the peak's anchors are rough (the force peaks before the penetration does), and
        # the first beta may come out negative; each impact's own factor absorbs the sign
        anchors = fit_anchors(s, n_hat, anchors, abs(beta) if beta else 1.0, padded=pad)
        reg = ForceRegression(s, anchors, fit_stiffness, penetration)
        n_new = reg.best_exponent() if exponent is None else n_hat
        beta = reg.solve(n_new)[0][0]
        done = abs(n_new - n_hat) < 1e-4
        history = [n_new] if done else history[-2:] + [n_new]
        n_hat = _aitken(history) if len(history) == 3 else n_new
        history = [n_hat] if n_hat != n_new else history
        if done:
            break
    coef, res = reg.solve(n_hat)
    if not (math.isfinite(beta) and beta > 0):
        raise IdentificationError(f"the regression gives a damping coefficient {beta:.4g} that is not positive: "
                                  "the rebuilt force shows no dissipation (check the channels and the preset)")
    free = exponent is None
    cov, jac = reg.covariance(n_hat, free, s.count)
    peaks = np.array([reg.delta[reg.impact == k].max() for k in np.unique(reg.impact)])
    peak = float(np.median(peaks))
    damping = beta * peak ** n_hat
    sd_b = math.sqrt(cov[0, 0])
    dof = s.count - 1
    conf = {"beta": interval_95(beta, sd_b, dof)}
    if free:
        sd_n = math.sqrt(cov[1, 1])
        corr = float(cov[0, 1] / (sd_b * sd_n))
        # d log(c_peak) = d beta / beta + log(delta_peak) d n
        g = np.array([1.0 / beta, math.log(peak)])
        sd_c = damping * math.sqrt(float(g @ cov[:2, :2] @ g))
        # in (log damping_at_peak, n) the valley of beta against n is straightened
        corr_peak = float((g @ cov[:2, 1]) * damping / (sd_c * sd_n))
        conf["n"] = interval_95(n_hat, sd_n, dof)
    else:
        corr, corr_peak, sd_c = math.nan, math.nan, damping * sd_b / beta
        conf["n"] = (n_hat, n_hat)
    conf["damping_at_peak"] = interval_95(damping, sd_c, dof)
    identifiable, why = True, ""
    if free and abs(corr_peak) > COLLINEARITY_LIMIT:
        identifiable = False
        why = (f"the damping at the peak penetration and n are correlated at {corr_peak:.5f} (limit "
               f"{COLLINEARITY_LIMIT}): the impacts are too alike "
               f"(approach velocities and peak penetrations) to tell n from beta; fix n, or add records at other "
               f"speeds or runouts")
    spread = float(np.ptp(peaks) / peak)
    if free and identifiable and spread < SPREAD_LIMIT:
        identifiable = False
        why = (f"the impacts' peak penetrations spread by {spread:.2%} only (at least {SPREAD_LIMIT:.0%} wanted): n "
               "then rests on the shape of the force within each impact alone, not on impacts of different "
               "approach velocity; fix n, or add records at other speeds or runouts")
    stiffness = float(s.stiffness[0] * (coef[-1] if fit_stiffness else 1.0))
    return DirectImpactEstimate(
        beta=float(beta), exponent=n_hat, mode="free" if free else "fixed", stiffness=stiffness,
        damping_at_peak=float(damping), peak_penetration=peak, confidence=conf, correlation=corr,
        correlation_at_peak=corr_peak,
        identifiable=identifiable, diagnosis=why, rms_residual=math.sqrt(float(np.mean(res ** 2))),
        impacts_used=s.count, records=n_rec, iterations=iterations,
        per_impact=per_impact_table(reg, s, anchors, n_hat, beta, jac))
