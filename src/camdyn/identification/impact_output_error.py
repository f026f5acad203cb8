"""Output-error identification of the impact damping ``beta``, ``n`` of
``Fn = K delta^1.5 + beta delta^n delta_dot`` (eq 3.14).

The contact force of every impact, rebuilt from the measured pivot reactions and
acceleration by the direct method (:func:`camdyn.identification.impact_direct.rebuild_impacts`,
eqs 3.21, 4.29-4.30), is compared sample by sample with the model's impact simulated from
its contact onset by the compiled batch of the residue method
(:func:`camdyn.identification.impact_kernel.simulate_impacts`, simulation S1), and the
sum of squares of the differences is minimised by ``scipy.optimize.least_squares``
(trust-region reflective) over:

- ``log c_ref`` and ``n``, ``c_ref = beta delta_ref^n`` [N s/m] being the damping at the
  direct estimate's peak penetration ``delta_ref`` (the coordinates that straighten the
  valley of ``beta`` against ``n``, as in the residue method);
- the cam's phase ``phi`` [rad]: the cam angle at the record's time ``t`` is
  ``phi + Omega t`` (eq 3.20);
- per impact, its contact onset ``t_k`` [s] within the window and its approach velocity
  ``v_k`` [m/s]; the follower's onset angle follows from zero penetration at the cam's
  angle then (eq 3.5) and its rate from ``delta_dot = -chi alpha_dot - n.v_cam``.

The fit starts from the direct estimate (``beta``, ``n``, each impact's approach
velocity) and from the best cam phase of a coarse scan. The Jacobian is by forward
differences of the batched simulation: each impact's force depends on its own onset and
approach velocity only, so all impacts' onsets are perturbed in one batch and all
approach velocities in another (6 rows of one batch per Jacobian, whatever the number
of impacts);
camdyn's parameter sensitivities are not used. The 95 % intervals come from the
Gauss-Newton covariance ``s^2 (J^T J)^-1`` at the solution (nuisance parameters included,
white force noise assumed), ``correlation`` from the same matrix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import t as student_t

from camdyn.errors import IdentificationError, ParameterError
from camdyn.identification.impact_direct import estimate_impact_damping_direct, rebuild_impacts
from camdyn.identification.impact_kernel import simulate_impacts
from camdyn.model import layout as L
from camdyn.model.equilibrium import as_system
from camdyn.model.geometry import contact_kinematics, zero_state
from camdyn.records.schema import record_speed

__all__ = ["OutputErrorEstimate", "estimate_impact_damping_output_error"]

#: Cam phases of the coarse scan that starts the fit [-].
PHASE_SCAN = 36
#: Forward-difference steps: ``log c_ref`` [-], ``n`` [-], ``phi`` [rad], onset [samples],
#: approach velocity [relative].
STEPS = (1e-4, 1e-4, 1e-4, 0.02, 1e-4)


@dataclass
class OutputErrorEstimate:
    """Result of :func:`estimate_impact_damping_output_error` (units in the comments)."""

    beta: float                  # [N s m^-(n+1)]
    exponent: float              # n [-]
    mode: str                    # "free" or "fixed"
    damping_at_peak: float       # beta * delta_peak^n [N s/m]
    peak_penetration: float      # median simulated peak penetration [m]
    confidence: dict             # 95 % intervals of beta, n, damping_at_peak
    correlation: float           # correlation of beta and n [-] (NaN when n is fixed)
    rms_residual: float          # rms force residual over the windows' samples [N]
    impacts_used: int
    evaluations: int             # residual evaluations of least_squares
    start: dict                  # the direct estimate it started from: beta, n
    per_impact: dict = field(repr=False, default_factory=dict)

    @property
    def beta_units(self) -> str:
        return f"N*s/m^{self.exponent + 1:.4g}"

    def to_dict(self) -> dict:
        return {
            "method": "output-error", "beta": self.beta, "beta_units": self.beta_units, "n": self.exponent,
            "mode": self.mode, "damping_at_peak": self.damping_at_peak, "damping_at_peak_units": "N*s/m",
            "peak_penetration": self.peak_penetration, "peak_penetration_units": "m",
            "confidence_95": {k: list(v) for k, v in self.confidence.items()},
            "correlation": self.correlation, "rms_residual": self.rms_residual,
            "impacts_used": self.impacts_used, "records": 1, "evaluations": self.evaluations, "start": self.start,
            "per_impact": {k: np.asarray(v).tolist() for k, v in self.per_impact.items()},
        }


def _baseline(offset: np.ndarray, force: np.ndarray, edge: int = 3) -> np.ndarray:
    """The straight line [N] through the mean rebuilt force of the window's first and last
    ``edge`` samples (free flight): the force balance at the reference angle leaves an
    offset of about 0.1 % of the peak there, which the simulated force does not have."""
    t0, t1 = offset[:edge].mean(), offset[-edge:].mean()
    f0, f1 = force[:edge].mean(), force[-edge:].mean()
    return f0 + (f1 - f0) * (offset - t0) / (t1 - t0)


class _Problem:
    """The impacts of one record and their batched simulation at trial parameters."""

    def __init__(self, system, samples, speed: float):
        self.p = L.pack(system)
        self.s = samples
        self.k = samples.count
        self.omega = self.p[L.OMEGA]
        self.tau = float(samples.offset[0][1] - samples.offset[0][0])
        width = max(o.size for o in samples.offset)
        self.times = np.full((self.k, width), np.nan)
        self.force = np.zeros((self.k, width))
        for i, (o, f) in enumerate(zip(samples.offset, samples.force)):
            self.times[i, :o.size] = o
            self.force[i, :o.size] = f - _baseline(o, f)
        self.valid = np.isfinite(self.times)
        self.length = np.array([o[-1] for o in samples.offset])
        self.alpha_ref = zero_state(system)[0]
        self.h_max = 1.0 / (32.0 * speed)

    def onset_state(self, phi: float, onset: np.ndarray, approach: np.ndarray):
        """Cam angle [rad], follower angle [rad] and rate [rad/s] at each impact's onset:
        zero penetration (eq 3.5, Newton's method with ``d delta / d alpha = -chi``) and
        ``v = -chi alpha_dot - n.v_cam`` (docs/model.md §2)."""
        theta = phi + self.omega * (self.s.onset_time + onset)
        alpha = np.full(self.k, self.alpha_ref)
        for _ in range(8):
            for i in range(self.k):
                delta, _, chi = contact_kinematics(alpha[i], 0.0, theta[i], self.omega, self.p)[:3]
                alpha[i] += delta / chi
        rate = np.empty(self.k)
        for i in range(self.k):
            out = contact_kinematics(alpha[i], 0.0, theta[i], self.omega, self.p)
            rate[i] = -(approach[i] + out[5]) / out[2]
        return theta, alpha, rate

    def simulate(self, rows, extra: np.ndarray | None = None):
        """Force [N] (and penetration [m]) at the window samples for each parameter row
        ``(log c_ref, n, phi, onsets (K), approach velocities (K))``, all rows in one batch;
        ``extra`` adds columns of offsets after onset [s]."""
        rows = np.atleast_2d(rows)
        k = self.k
        params, a0, ad0, offsets, lengths = [], [], [], [], []
        for row in rows:
            onset, approach = row[3:3 + k], row[3 + k:]
            theta, alpha, rate = self.onset_state(row[2], onset, approach)
            q = np.tile(self.p, (k, 1))
            q[:, L.THETA0] = theta
            params.append(q)
            a0.append(alpha)
            ad0.append(rate)
            off = self.times - onset[:, None]
            off[~(off >= 0.0)] = np.nan
            if extra is not None:
                off = np.column_stack([off, extra])
            offsets.append(off)
            lengths.append(2.0 * self.length - onset)
        r = rows.shape[0]
        n_val = np.repeat(rows[:, 1], k)
        beta = np.exp(np.repeat(rows[:, 0], k)) / self.reference ** n_val
        _, force, pen, _, status = simulate_impacts(
            np.vstack(params), np.arange(r * k, dtype=np.int64), beta, n_val, np.concatenate(a0),
            np.concatenate(ad0), np.concatenate(lengths), np.ascontiguousarray(np.vstack(offsets)), 64,
            1e-9, 1e-12, self.h_max)
        return np.nan_to_num(force).reshape(r, k, -1), pen.reshape(r, k, -1), status.reshape(r, k)

    def residuals(self, rows) -> np.ndarray:
        """Simulated minus measured force [N] over the windows' samples, one row per row."""
        force, _, status = self.simulate(rows)
        res = np.where(self.valid, force - self.force, 0.0)
        res[status != 0] = 10.0 * np.abs(self.force).max()     # an impact that never separates
        return res.reshape(len(res), -1)[:, self.valid.ravel()]


def _jacobian(prob: _Problem, x: np.ndarray, fixed_n: bool) -> np.ndarray:
    """Forward-difference Jacobian of the residuals: the three global parameters one by
    one, the onsets and the approach velocities each in one batch (an impact's force
    depends on its own only)."""
    k = prob.k
    steps = np.concatenate([STEPS[:3], np.full(k, STEPS[3] * prob.tau), np.abs(x[3 + k:]) * STEPS[4]])
    rows = [x.copy()]
    for j in range(3):
        rows.append(x + steps[j] * np.eye(x.size)[j])
    for part in (slice(3, 3 + k), slice(3 + k, 3 + 2 * k)):
        row = x.copy()
        row[part] += steps[part]
        rows.append(row)
    r = prob.residuals(np.array(rows))
    base = r[0]
    jac = np.zeros((base.size, x.size))
    for j in range(3):
        jac[:, j] = (r[1 + j] - base) / steps[j]
    owner = np.repeat(np.arange(k)[:, None], prob.times.shape[1], axis=1)[prob.valid]
    for b, start in ((4, 3), (5, 3 + k)):
        cols = start + owner
        jac[np.arange(base.size), cols] = (r[b] - base) / steps[cols]
    if fixed_n:
        jac[:, 1] = 0.0
    return jac


def _phase_scan(prob: _Problem, x: np.ndarray) -> float:
    """The cam phase [rad] of least force misfit on a coarse scan of a whole turn."""
    phases = np.linspace(0.0, 2.0 * math.pi, PHASE_SCAN, endpoint=False)
    rows = np.tile(x, (phases.size, 1))
    rows[:, 2] = phases
    cost = np.sum(prob.residuals(rows) ** 2, axis=1)
    return float(phases[int(np.argmin(cost))])


def estimate_impact_damping_output_error(system, record, speed=None, runout=None, exponent: float | None = None,
                                         min_contact_samples: int = 8,
                                         max_evaluations: int = 60) -> OutputErrorEstimate:
    """Identify ``beta``, ``n`` by output-error fitting of the impacts' force histories
    (see the module), starting from the direct estimate.

    Parameters
    ----------
    system : System
        The rig; its damping law is replaced by the power law.
    record : xarray.Dataset
        One record with ``Nx``, ``Ny`` [N] and ``alpha_ddot`` [rad/s^2] (or ``a_t``
        [m/s^2]); any number of impacts per revolution.
    speed, runout : float, optional
        Cam speed [Hz] and runout [m]; default the record's ``speed_hz`` and ``runout``.
    exponent : float, optional
        Fix ``n`` [-]; default free.
    min_contact_samples : int
        Fewest samples a contact must span [-] (as the direct method).
    max_evaluations : int
        Most residual evaluations of ``least_squares`` [-].

    Returns
    -------
    OutputErrorEstimate

    Raises
    ------
    IdentificationError
        A record the direct method refuses, or no fit whose simulations all separate.
    """
    if isinstance(record, (list, tuple)):
        if len(record) != 1:
            raise ParameterError("the output-error method fits one record at a time")
        record = record[0]
    if isinstance(speed, (list, tuple)):
        speed = speed[0]
    if isinstance(runout, (list, tuple)):
        runout = runout[0]
    direct = estimate_impact_damping_direct(system, record, speed=speed, runout=runout, exponent=exponent,
                                            min_contact_samples=min_contact_samples)
    system = as_system(system)
    samples = rebuild_impacts(system, record, speed, runout, min_contact_samples)
    speed = record_speed(speed) or record_speed(record.attrs.get("speed_hz"), "speed_hz")
    runout = runout if runout is not None else record.attrs.get("runout")
    values = {"motion.speed": speed, "contact.damping": "power"}
    values |= {"cam.runout": float(runout)} if runout is not None else {}
    prob = _Problem(system.with_values(**values), samples, speed)
    prob.reference = direct.peak_penetration
    return _fit(prob, direct, exponent is not None, max_evaluations)


def _initial(prob: _Problem, direct) -> np.ndarray:
    """Start: the direct ``(log c_ref, n)``, onsets where each rebuilt force first exceeds
    5 % of its peak, the direct approach velocities, the best cam phase of a scan."""
    onset = np.empty(prob.k)
    for i, f in enumerate(prob.s.force):
        j = int(np.argmax(f > 0.05 * f.max()))
        onset[i] = prob.s.offset[i][max(j - 1, 0)]
    approach = np.abs(np.asarray(direct.per_impact["approach_velocity"], float))
    x = np.concatenate([[math.log(direct.damping_at_peak), direct.exponent, 0.0], onset, approach])
    x[2] = _phase_scan(prob, x)
    return x


def _fit(prob: _Problem, direct, fixed_n: bool, max_evaluations: int) -> OutputErrorEstimate:
    """The least-squares fit, its covariance and the estimate."""
    k = prob.k
    x0 = _initial(prob, direct)
    scale = np.concatenate([[0.01, 0.01, 0.01], np.full(k, prob.tau), 0.01 * np.abs(x0[3 + k:])])
    free = [0, 2] + list(range(3, x0.size)) if fixed_n else list(range(x0.size))

    def full(xf):
        x = x0.copy()
        x[free] = xf
        return x
    sol = least_squares(lambda xf: prob.residuals(full(xf))[0], x0[free],
                        jac=lambda xf: _jacobian(prob, full(xf), fixed_n)[:, free], method="trf",
                        x_scale=scale[free], max_nfev=max_evaluations, xtol=1e-10, ftol=1e-12)
    x = full(sol.x)
    force, pen, status = prob.simulate(x, extra=np.linspace(0.0, 1.5, 301)[None, :] * prob.length[:, None])
    if (status != 0).any():
        raise IdentificationError("no damping reproduces the measured impacts: a simulated impact did not "
                                  "separate from the cam")
    peaks = np.nanmax(pen[0], axis=1)
    peak = float(np.median(peaks))
    n_hat = float(x[1])
    beta = math.exp(x[0]) / prob.reference ** n_hat
    damping = beta * peak ** n_hat
    res = sol.fun
    jac = _jacobian(prob, x, fixed_n)
    dof = max(res.size - len(free), 1)
    s2 = float(res @ res) / dof
    cov_f = s2 * np.linalg.pinv(jac[:, free].T @ jac[:, free])
    cov = np.zeros((x.size, x.size))
    cov[np.ix_(free, free)] = cov_f
    # beta = exp(u) / delta_ref^n: d log beta = du - log(delta_ref) dn; c_peak: du + log(peak / ref) dn
    g_beta = np.array([1.0, -math.log(prob.reference)])
    g_peak = np.array([1.0, math.log(peak / prob.reference)])
    c2 = cov[:2, :2]
    sd_lb, sd_lc, sd_n = (math.sqrt(max(float(g @ c2 @ g), 0.0)) for g in (g_beta, g_peak, np.array([0.0, 1.0])))
    z = float(student_t.ppf(0.975, dof))
    conf = {"beta": (beta * math.exp(-z * sd_lb), beta * math.exp(z * sd_lb)),
            "n": (n_hat - z * sd_n, n_hat + z * sd_n),
            "damping_at_peak": (damping * math.exp(-z * sd_lc), damping * math.exp(z * sd_lc))}
    corr = math.nan if fixed_n or sd_n == 0 else float((g_beta @ c2[:, 1]) / (sd_lb * sd_n))
    width = prob.times.shape[1]
    per = {"onset_time": prob.s.onset_time + x[3:3 + k], "approach_velocity": x[3 + k:],
           "peak_penetration": peaks,
           "rms_residual": np.sqrt(np.array([np.mean((force[0, i, :width][prob.valid[i]] - prob.force[i][prob.valid[i]])
                                                     ** 2) for i in range(k)]))}
    return OutputErrorEstimate(
        beta=float(beta), exponent=n_hat, mode="fixed" if fixed_n else "free", damping_at_peak=float(damping),
        peak_penetration=peak, confidence=conf, correlation=corr, rms_residual=math.sqrt(float(np.mean(res ** 2))),
        impacts_used=k, evaluations=int(sol.nfev), start={"beta": direct.beta, "n": direct.exponent},
        per_impact=per)
