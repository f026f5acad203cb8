"""Impact damping ``beta``, ``n`` of ``Fn = k delta^1.5 + beta delta^n delta_dot`` from
measured vibration (thesis 3.5.2).

Every reconstructed impact event (:mod:`camdyn.identification.impact_events`) is
simulated from its measured onset state with trial ``(beta, n)`` (simulation S1, batched
in the compiled core), and three residues compare S1 with the measurement (eq 3.23):

- ``Lambda1 = (alpha_m^S1 - alpha_m) / (alpha_m - alpha(0))``: the peak angle of the
  free flight that follows the impact. The thesis divides by ``alpha_m`` itself, which
  depends on where ``alpha = 0`` is; we divide by the swing, which does not (the
  minimiser is the same);
- ``Lambda2 = int (F^S1 - F)^2 dt / int F^2 dt``: the contact-force history;
- ``Lambda3 = (oint F^S1 dpsi - oint F dpsi) / oint F dpsi``: the hysteresis area.

The estimate minimises the sum of squares of the chosen residue over impacts (the thesis
minimises its average; Lambda1, the most sensitive, by default), with ``n`` free, fixed
(1.5, 1.45, ...) or zero (viscous). Internally the unknowns are ``log c_ref`` and ``n``,
``c_ref = beta delta_ref^n`` being the damping [N s/m] at the operating penetration:
the thesis found ``beta`` and ``n`` trade off along a valley (a 3 % change of ``n`` moved
``beta`` by 46 %), and these coordinates straighten it. Confidence intervals come from a
bootstrap over impacts (stratified by record), each replicate refitted by Gauss-Newton
steps from the estimate.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field, replace

import numpy as np
import xarray as xr
from scipy.optimize import least_squares

from camdyn.errors import IdentificationError, ParameterError
from camdyn.identification.impact_events import ImpactEvents, impact_events
from camdyn.identification.impact_kernel import simulate_impacts
from camdyn.model import layout as L
from camdyn.model.equilibrium import as_system
from camdyn.model.geometry import cam_angle, contact_kinematics
from camdyn.records.schema import check_consistency, record_speed, require_record
from camdyn.simulation import limits

__all__ = ["ImpactDampingEstimate", "ImpactProblem", "estimate_impact_damping", "residue_landscape",
           "check_bootstrap", "MAX_BOOTSTRAP"]

RESIDUES = ("lambda1", "lambda2", "lambda3")
OBJECTIVES = RESIDUES + ("combined",)
#: Grid samples per event on which S1's peak angle is searched (then refined by a parabola).
PEAK_GRID = 401


@dataclass
class ImpactDampingEstimate:
    """Result of :func:`estimate_impact_damping`."""

    beta: float                  # [N s m^-(n+1)]
    exponent: float              # n [-]
    mode: str                    # "free", "fixed" or "viscous"
    residue_used: str
    residues: dict               # mean |Lambda| per impact at the estimate [-]
    impacts_used: int
    records: int
    damping_at_peak: float       # beta * delta_peak^n [N s/m]
    peak_penetration: float      # median S1 peak penetration [m]
    confidence: dict             # 95 % bootstrap intervals of beta, exponent, damping_at_peak
    bootstrap: np.ndarray = field(repr=False)       # (B, 2): beta, n of the replicates
    per_impact: dict = field(repr=False, default_factory=dict)
    problem: ImpactProblem = field(repr=False, default=None)

    @property
    def beta_units(self) -> str:
        return f"N*s/m^{self.exponent + 1:.4g}"

    def to_dict(self) -> dict:
        return {
            "beta": self.beta, "beta_units": self.beta_units, "n": self.exponent, "mode": self.mode,
            "residue": self.residues.get(self.residue_used, self.residues["lambda1"]),
            "residue_used": self.residue_used,
            "residues": self.residues, "impacts_used": self.impacts_used, "records": self.records,
            "damping_at_peak": self.damping_at_peak, "damping_at_peak_units": "N*s/m",
            "peak_penetration": self.peak_penetration, "peak_penetration_units": "m",
            "confidence_95": {k: list(v) for k, v in self.confidence.items()},
            "bootstrap_replicates": int(self.bootstrap.shape[0]),
            "per_impact": {k: np.asarray(v).tolist() for k, v in self.per_impact.items()},
        }


class ImpactProblem:
    """The impact events of one or more records, ready for batched S1 simulations."""

    def __init__(self, events: list[ImpactEvents], rtol: float = 1e-9, atol: float = 1e-11):
        if not events:
            raise ParameterError("no records to fit")
        self.events = events
        width = max(e.offsets.shape[1] for e in events)
        rows, offsets, force, pen, record = [], [], [], [], []
        for r, ev in enumerate(events):
            p = L.pack(ev.system)
            for i in range(ev.count):
                q = p.copy()
                q[L.THETA0] = ev.theta0[i]
                rows.append(q)
                record.append(r)
            pad = width - ev.offsets.shape[1]
            offsets.append(np.pad(ev.offsets, ((0, 0), (0, pad)), constant_values=np.nan))
            force.append(np.pad(ev.force, ((0, 0), (0, pad)), constant_values=np.nan))
            pen.append(np.pad(ev.penetration, ((0, 0), (0, pad)), constant_values=np.nan))
        self.params = np.array(rows)
        self.record = np.array(record)
        cat = lambda name: np.concatenate([getattr(e, name) for e in events])
        self.alpha0, self.alpha_dot0 = cat("alpha0"), cat("alpha_dot0")
        self.length, self.peak, self.swing = cat("event_length"), cat("peak"), cat("swing")
        self.offsets = np.concatenate(offsets)
        self.force = np.concatenate(force)
        self.penetration = np.concatenate(pen)
        self.tau = np.concatenate([np.full(e.count, e.sample_interval) for e in events])
        self.h_max = float(min(1.0 / (32.0 * e.speed) for e in events))
        self.rtol, self.atol = rtol, atol
        self.count = self.alpha0.size
        with np.errstate(invalid="ignore"):
            self.force_energy = np.nansum(self.force ** 2, axis=1) * self.tau
            self.loop_area = self._area(self.force, self.penetration)

    @staticmethod
    def _area(f, psi):
        """Hysteresis area ``oint F dpsi`` [J] of each row (trapezoidal rule)."""
        out = np.empty(f.shape[0])
        for j in range(f.shape[0]):
            ok = np.isfinite(f[j]) & np.isfinite(psi[j])
            out[j] = -np.trapezoid(f[j, ok], psi[j, ok]) if ok.sum() > 1 else np.nan
        return out

    def simulate(self, impact, beta, exponent):
        """Simulation S1 of the impacts ``impact`` with trial ``beta``, ``exponent`` (arrays)."""
        impact = np.ascontiguousarray(impact, dtype=np.int64)
        beta = np.ascontiguousarray(np.broadcast_to(beta, impact.shape), dtype=float)
        exponent = np.ascontiguousarray(np.broadcast_to(exponent, impact.shape), dtype=float)
        return simulate_impacts(self.params, impact, beta, exponent, self.alpha0, self.alpha_dot0, self.length,
                                self.offsets, PEAK_GRID, self.rtol, self.atol, self.h_max)

    def residues(self, impact, beta, exponent) -> dict:
        """Signed Lambda1, Lambda2 (>= 0) and signed Lambda3 of each job (eq 3.23)."""
        impact = np.asarray(impact, dtype=np.int64)
        peak, force, pen, _, status = self.simulate(impact, beta, exponent)
        ok = status == 0
        l1 = np.where(ok, (peak - self.peak[impact]) / self.swing[impact], -1.0)
        with np.errstate(invalid="ignore"):
            diff = np.nansum((force - self.force[impact]) ** 2, axis=1) * self.tau[impact]
            l2 = np.where(ok, diff / self.force_energy[impact], np.inf)
            area = self._area(force, pen)
            l3 = np.where(ok, (area - self.loop_area[impact]) / self.loop_area[impact], np.inf)
        return {"lambda1": l1, "lambda2": l2, "lambda3": l3, "status": status, "force": force,
                "penetration": pen}


def _beta(u, reference):
    return math.exp(u[0]) / reference ** u[1]


def _objective(residue: str | None, exponent: float | None) -> str:
    """The residue to minimise (default by whether ``n`` is fixed), after checking the
    arguments of :func:`estimate_impact_damping`."""
    if residue is None:
        residue = "lambda1" if exponent is not None else "combined"
    if not isinstance(residue, str) or residue not in OBJECTIVES:
        raise ParameterError(f"residue must be one of {', '.join(OBJECTIVES)}, got {residue!r:.60}")
    if exponent is not None and (isinstance(exponent, bool) or not isinstance(exponent, numbers.Real)
                                 or not (math.isfinite(exponent) and 0 <= exponent <= 5)):
        raise ParameterError(f"the fixed exponent n must be between 0 and 5, got {exponent!r}")
    return residue


def _record_events(base, records, speed, runout, min_impacts: int, progress) -> list[ImpactEvents]:
    """Reconstruct the impact events of each record.

    Parameters
    ----------
    base : System
        The rig with the power-law damping.
    records : Dataset or list of Dataset
        The records.
    speed, runout : float or list, optional
        Cam speed [Hz] and runout [m], scalars or one per record; a record's own
        ``runout`` attribute when None.
    min_impacts : int
        Fewest impact events per record [-].
    progress : callable, optional
        Called with a message after each record.

    Returns
    -------
    list of ImpactEvents
    """
    if isinstance(records, xr.Dataset):
        records = [records]
    if not isinstance(records, (list, tuple)) or not records:
        raise ParameterError(f"records must be a record or a list of records (from read_measurement), got "
                             f"{type(records).__name__} {records!r:.60}")
    records = list(records)
    for i, rec in enumerate(records):
        require_record(rec, f"record (#{i + 1})")
        if any(rec is other for other in records[:i]):
            raise ParameterError(f"record #{i + 1} is the same record as an earlier one: each record must be a "
                                 f"different operating point (a record given twice counts its impacts twice)")
    n_rec = len(records)
    speeds = list(speed) if isinstance(speed, (list, tuple)) else [speed] * n_rec
    runouts = list(runout) if isinstance(runout, (list, tuple)) else [runout] * n_rec
    if len(speeds) != n_rec or len(runouts) != n_rec:
        raise ParameterError(f"give one speed and one runout per record ({n_rec}), or one for all; got "
                             f"{len(speeds)} and {len(runouts)}")
    speeds = [record_speed(sp, f"speed (record #{i + 1})") for i, sp in enumerate(speeds)]
    runouts = [None if ro is None else limits.check_number(f"runout (record #{i + 1})", ro, "m")
               for i, ro in enumerate(runouts)]
    events = []
    for rec, sp, ro in zip(records, speeds, runouts):
        check_consistency(rec, speed=sp, runout=ro, preset=base.name, what="the options")
        ro = ro if ro is not None else rec.attrs.get("runout")
        sys_r = base.with_values(**{"cam.runout": float(ro)}) if ro is not None else base
        events.append(impact_events(sys_r, rec, speed=sp, min_impacts=min_impacts))
        if progress:
            progress(f"record {len(events)}/{n_rec}: {events[-1].count} impacts")
    return events


class _Residuals:
    """Residue vectors of the fit in the unknowns ``u = (log c_ref, n)`` (or ``log c_ref``
    alone with ``n`` fixed), ``c_ref`` [N s/m] being the damping at the reference
    penetration ``reference`` [m]."""

    def __init__(self, prob: ImpactProblem, reference: float, exponent: float | None, residue: str):
        self.prob, self.reference, self.exponent, self.residue = prob, reference, exponent, residue

    def __call__(self, u_rows, impacts=None):
        """Residue vectors for several parameter rows at once: (rows, K or K*M)."""
        prob, residue = self.prob, self.residue
        u_rows = np.atleast_2d(u_rows)
        idx = np.arange(prob.count) if impacts is None else impacts
        jobs = np.tile(idx, len(u_rows))
        rows = np.repeat(np.arange(len(u_rows)), idx.size)
        n_val = u_rows[rows, 1] if u_rows.shape[1] > 1 else np.full(jobs.size, self.exponent)
        beta = np.exp(u_rows[rows, 0]) / self.reference ** n_val
        res = prob.residues(jobs, beta, n_val)
        if residue in ("lambda2", "combined"):
            f = np.nan_to_num(res["force"]) - np.nan_to_num(prob.force[jobs])
            val = f * np.sqrt(prob.tau[jobs] / prob.force_energy[jobs])[:, None]
            if residue == "combined":
                val = np.column_stack([res["lambda1"], val])
            return val.reshape(len(u_rows), -1)
        return res[residue].reshape(len(u_rows), idx.size)

    def single(self, u):
        """The residue vector at one parameter row ``u``."""
        return self(u)[0]

    def jacobian(self, u):
        """Forward-difference Jacobian of :meth:`single` at ``u``."""
        h = np.array([0.01, 0.002])[: u.size]
        rows_ = np.vstack([u] + [u + h[j] * np.eye(u.size)[j] for j in range(u.size)])
        r = self(rows_)
        return ((r[1:] - r[0]) / h[:, None]).T


def _coarse_scan(vector: _Residuals, exponent: float | None) -> np.ndarray:
    """Starting point of the least-squares fit: the best of a coarse scan of the damping
    at the reference penetration (1 to 1e6 N s/m; ``n`` at 1.5 when free).

    Returns
    -------
    ndarray
        ``u`` (see :class:`_Residuals`).
    """
    n_start = 1.5 if exponent is None else exponent
    scan = np.log(np.logspace(0, 6, 25))
    rows = np.column_stack([scan, np.full(scan.size, n_start)]) if exponent is None else scan[:, None]
    cost = np.nansum(np.nan_to_num(vector(rows), nan=1.0, posinf=1e3) ** 2, axis=1)
    u0 = rows[int(np.argmin(cost))]
    return u0


def _interval(x: np.ndarray) -> tuple[float, float]:
    """95 % interval of bootstrap replicates ``x`` (NaN without replicates)."""
    return (float(np.nanpercentile(x, 2.5)), float(np.nanpercentile(x, 97.5))) if x.size else (
        math.nan, math.nan)


#: Most bootstrap replicates [-]: each refits the damping over every impact (seconds);
#: the 95 % intervals settle within a few thousand.
MAX_BOOTSTRAP = 10_000


def check_bootstrap(bootstrap) -> int:
    """Refuse a number of bootstrap replicates that is not a whole number from 0 to
    :data:`MAX_BOOTSTRAP`, before any work."""
    if isinstance(bootstrap, bool) or not isinstance(bootstrap, (int, np.integer)) or bootstrap < 0:
        raise ParameterError(f"bootstrap must be a whole number of replicates >= 0 (0: none), got {bootstrap!r}")
    # each replicate keeps beta and n and refits with the Jacobian over every impact
    return limits.check_request(f"bootstrap = {bootstrap}", bootstrap, 16, limit=MAX_BOOTSTRAP, unit="replicates")


def estimate_impact_damping(system, records, speed=None, runout=None, exponent: float | None = None,
                            residue: str | None = None, bootstrap: int = 64, seed: int | None = 0,
                            min_impacts: int = 5, events: list[ImpactEvents] | None = None,
                            progress=None) -> ImpactDampingEstimate:
    """Identify the impact damping ``beta``, ``n`` from periodic-impact records.

    Parameters
    ----------
    system : System
        The rig; its own damping settings are replaced by the power law.
    records : Dataset or list of Dataset
        Records with ``Nx``, ``Ny`` [N] and ``alpha_ddot`` [rad/s^2] (or ``a_t``), one
        per operating point; each record's ``speed_hz`` and ``runout`` attributes (or the
        ``speed`` [Hz] / ``runout`` [m] arguments, scalars or one per record) set its
        operating point. Several records are fitted jointly.
    exponent : float, optional
        Fix ``n`` (1.5, 1.45; 0 gives viscous damping ``beta`` [N s/m]); default free.
    residue : {"lambda1", "lambda2", "lambda3", "combined"}, optional
        Residue minimised (eq 3.23). Default: ``lambda1`` (the thesis's choice) when ``n``
        is fixed; ``combined`` (Lambda1 and the force history of Lambda2 together) when
        ``n`` is free, because at one operating point every impact is alike and the peak
        angle alone cannot separate ``beta`` from ``n``: the force history's shape can.
    bootstrap : int
        Bootstrap replicates over impacts for the confidence intervals (0: none).
    events : list of ImpactEvents, optional
        Already reconstructed events (skips the reconstruction).

    Raises
    ------
    IdentificationError
        A record the estimator must refuse (see :func:`impact_events`), or no damping
        that reproduces the measured swings.
    """
    check_bootstrap(bootstrap)
    residue = _objective(residue, exponent)
    base = as_system(system).with_values(**{"contact.damping": "power"})
    if events is None:
        events = _record_events(base, records, speed, runout, min_impacts, progress)
    else:
        events = [replace(e, system=e.system.with_values(**{"contact.damping": "power"})) for e in events]
    prob = ImpactProblem(events)
    k = prob.count
    reference = float(np.nanmedian(np.nanmax(prob.penetration, axis=1)))
    if not (math.isfinite(reference) and reference > 0):
        reference = 1e-5
    mode = "free" if exponent is None else ("viscous" if exponent == 0 else "fixed")
    vector = _Residuals(prob, reference, exponent, residue)
    u0 = _coarse_scan(vector, exponent)   # then least squares
    if progress:
        progress("coarse scan done")
    sol = least_squares(vector.single, u0, jac=vector.jacobian, method="lm", xtol=1e-12, ftol=1e-14,
                        max_nfev=200)
    u = sol.x
    n_hat = float(u[1]) if exponent is None else float(exponent)
    beta_hat = math.exp(u[0]) / reference ** n_hat
    res = prob.residues(np.arange(k), np.full(k, beta_hat), np.full(k, n_hat))
    bad = res["status"] != 0
    if bad.all():
        raise IdentificationError("no damping reproduces the measured impacts: every S1 simulation failed")
    if progress:
        progress("fit done")
    peaks = np.nanmax(res["penetration"], axis=1)
    peak_pen = float(np.nanmedian(peaks))
    boot = _bootstrap(vector, vector.jacobian, u, prob.record, bootstrap, seed, reference, exponent)
    if progress and bootstrap:
        progress("bootstrap done")
    betas = boot[:, 0]
    ns = boot[:, 1]
    c_peak = betas * peak_pen ** ns
    per = {"lambda1": res["lambda1"], "lambda2": res["lambda2"], "lambda3": res["lambda3"],
           "peak_penetration": peaks, "record": prob.record,
           "beta_alone": _per_impact_beta(prob, n_hat, beta_hat), "approach_velocity": _approach(prob)}
    return ImpactDampingEstimate(
        beta=beta_hat, exponent=n_hat, mode=mode, residue_used=residue,
        residues={r: float(np.nanmean(np.abs(res[r]))) for r in RESIDUES},
        impacts_used=k, records=len(events), damping_at_peak=beta_hat * peak_pen ** n_hat,
        peak_penetration=peak_pen,
        confidence={"beta": _interval(betas), "n": _interval(ns), "damping_at_peak": _interval(c_peak)},
        bootstrap=boot, per_impact=per, problem=prob)


def _bootstrap(vector, jac, u_hat, record, replicates, seed, reference, exponent, steps: int = 2):
    """Bootstrap over impacts (stratified by record); each replicate takes Gauss-Newton
    steps from the full estimate on its resampled impacts. Returns (B, 2): beta, n."""
    if replicates <= 0:
        return np.empty((0, 2))
    rng = np.random.default_rng(seed)
    k = record.size
    weights = np.zeros((replicates, k))
    for r in np.unique(record):
        members = np.flatnonzero(record == r)
        draws = rng.choice(members, size=(replicates, members.size), replace=True)
        for b in range(replicates):
            np.add.at(weights[b], draws[b], 1.0)
    us = np.tile(u_hat, (replicates, 1))
    p = u_hat.size
    h = np.array([0.01, 0.002])[:p]
    for _ in range(steps):
        rows = np.vstack([us] + [us + h[j] * np.eye(p)[j] for j in range(p)])
        r = vector(rows)
        r = np.nan_to_num(r, nan=0.0, posinf=0.0)
        m = r.shape[1] // k
        base = r[:replicates].reshape(replicates, k, m)
        for b in range(replicates):
            J = np.stack([(r[(j + 1) * replicates + b].reshape(k, m) - base[b]) / h[j] for j in range(p)], axis=-1)
            w = np.sqrt(weights[b])[:, None, None]
            Jw = (J * w).reshape(-1, p)
            rw = (base[b] * w[..., 0]).reshape(-1)
            step, *_ = np.linalg.lstsq(Jw, -rw, rcond=None)
            us[b] += step
    n_val = us[:, 1] if p > 1 else np.full(replicates, float(exponent))
    return np.column_stack([np.exp(us[:, 0]) / reference ** n_val, n_val])


def _per_impact_beta(prob: ImpactProblem, n: float, beta: float, iterations: int = 12) -> np.ndarray:
    """``beta`` [N s m^-(n+1)] that makes each impact's Lambda1 vanish alone, at the fitted
    ``n`` (batched secant iterations on ``log beta``)."""
    k = prob.count
    idx = np.arange(k)
    x0 = np.full(k, math.log(beta) - 0.05)
    x1 = np.full(k, math.log(beta) + 0.05)
    f0 = prob.residues(idx, np.exp(x0), np.full(k, n))["lambda1"]
    f1 = prob.residues(idx, np.exp(x1), np.full(k, n))["lambda1"]
    for _ in range(iterations):
        den = f1 - f0
        safe = np.abs(den) > 1e-15
        x2 = np.where(safe, x1 - f1 * (x1 - x0) / np.where(safe, den, 1.0), x1)
        x2 = np.clip(x2, x1 - 2.0, x1 + 2.0)
        if np.all(np.abs(x2 - x1) < 1e-10):
            x1 = x2
            break
        x0, f0 = x1, f1
        x1 = x2
        f1 = prob.residues(idx, np.exp(x1), np.full(k, n))["lambda1"]
    return np.exp(x1)


def _approach(prob: ImpactProblem) -> np.ndarray:
    """Approach velocity [m/s] at onset of each impact, from the reconstructed state."""
    out = np.empty(prob.count)
    for i in range(prob.count):
        q = prob.params[i]
        th, thd = cam_angle(0.0, q)
        out[i] = contact_kinematics(prob.alpha0[i], prob.alpha_dot0[i], th, thd, q)[1]
    return out


def residue_landscape(estimate: ImpactDampingEstimate, exponents=None, betas=None, residue: str = "lambda1",
                      points: int = 21) -> xr.DataArray:
    """Mean ``|Lambda|`` per impact over a grid of ``(n, beta)`` around the estimate.

    Default grid: ``n`` within +-0.25 of the estimate, and at each ``n`` the ``beta`` that
    keeps the damping at the operating penetration within a factor 3 of the estimate's
    (so the valley stays in view); returned over ``exponent`` and ``damping_factor``, with
    ``beta`` [N s m^-(n+1)] as a 2-D coordinate.
    """
    prob = estimate.problem
    if prob is None:
        raise ParameterError("the estimate carries no impact events")
    n_hat = estimate.exponent
    ns = np.linspace(n_hat - 0.25, n_hat + 0.25, points) if exponents is None else np.asarray(exponents, float)
    factors = np.logspace(-math.log10(3), math.log10(3), points) if betas is None else None
    k = prob.count
    delta = estimate.peak_penetration
    if factors is not None:
        beta_grid = estimate.damping_at_peak * factors[None, :] / delta ** ns[:, None]
        cols = factors
    else:
        cols = np.asarray(betas, float)
        beta_grid = np.tile(cols, (ns.size, 1))
    jobs = np.tile(np.arange(k), beta_grid.size)
    b = np.repeat(beta_grid.ravel(), k)
    n = np.repeat(np.repeat(ns, beta_grid.shape[1]), k)
    res = prob.residues(jobs, b, n)[residue]
    mean = np.nanmean(np.abs(res).reshape(beta_grid.size, k), axis=1).reshape(beta_grid.shape)
    dim = "damping_factor" if factors is not None else "beta_value"
    return xr.DataArray(
        mean, dims=("exponent", dim),
        coords={"exponent": ("exponent", ns, {"units": "1", "long_name": "damping exponent n"}),
                dim: (dim, cols, {"units": "1" if factors is not None else "N*s/m^(n+1)",
                                  "long_name": "damping at the operating penetration / estimate"
                                  if factors is not None else "beta"}),
                "beta": (("exponent", dim), beta_grid, {"units": "N*s/m^(n+1)", "long_name": "beta"})},
        attrs={"units": "1", "long_name": f"mean |{residue}| per impact"}, name=residue)
