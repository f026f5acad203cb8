"""The restoring-force regression of the direct impact-damping method
(:mod:`camdyn.identification.impact_direct`, step 4): with the penetration ``delta`` [m]
and its rate ``delta_dot`` [m/s] rebuilt, ``Fn - K delta^1.5 = beta delta^n delta_dot``
(eq 3.14) is linear in ``beta`` (and in a factor on ``K``) at each ``n``; ``n`` is found by a
bounded one-dimensional search (variable projection). The covariance is the
impact-clustered sandwich estimate.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.stats import t as student_t

from camdyn.errors import IdentificationError

__all__ = ["ForceRegression", "per_impact_table", "interval_95", "EXPONENT_RANGE"]

#: Range of the exponent searched [-].
EXPONENT_RANGE = (0.0, 3.0)


def _columns(s, anchors: np.ndarray, penetration):
    """The regression's samples in contact: ``delta`` [m], ``delta_dot`` [m/s], ``Fn`` [N],
    ``K`` [N/m^1.5] and the impact index of each."""
    parts = []
    for k in range(s.count):
        delta, rate = penetration(s, k, *anchors[k])
        on = delta > 0
        parts.append((delta[on], rate[on], s.force[k][on], np.full(on.sum(), s.stiffness[k]), np.full(on.sum(), k)))
    return [np.concatenate(c) for c in zip(*parts)]


class ForceRegression:
    """Step 4: ``Fn - K delta^1.5 = beta delta^n delta_dot`` (eq 3.14), linear in ``beta``
    (and in a common factor of ``K`` when ``fit_stiffness``) at each ``n``.

    Parameters
    ----------
    s : ImpactSamples
        The rebuilt impacts (:class:`camdyn.identification.impact_direct.ImpactSamples`).
    anchors : ndarray
        ``(d [m], v [m/s], a [m/s^2])`` of each impact.
    fit_stiffness : bool
        Fit a factor on the Hertz coefficient ``K`` as well.
    penetration : callable
        ``penetration(s, k, d, v, a)`` returning ``delta`` [m] and ``delta_dot`` [m/s].
    """

    def __init__(self, s, anchors: np.ndarray, fit_stiffness: bool, penetration):
        self.delta, self.rate, self.force, self.k, self.impact = _columns(s, anchors, penetration)
        if self.delta.size < 4:
            raise IdentificationError("the rebuilt penetration is positive at fewer than 4 samples: the contacts "
                                      "are not resolved")
        self.elastic = self.delta ** s.elastic_exponent * self.k
        self.log_delta = np.log(self.delta)
        self.fit_stiffness = fit_stiffness

    def design(self, exponent: float) -> np.ndarray:
        damp = self.delta ** exponent * self.rate
        return np.column_stack([damp, self.elastic]) if self.fit_stiffness else damp[:, None]

    def solve(self, exponent: float) -> tuple[np.ndarray, np.ndarray]:
        """Coefficients (``beta``, then the factor on ``K``) and residuals [N] at ``exponent``."""
        a = self.design(exponent)
        y = self.force if self.fit_stiffness else self.force - self.elastic
        coef = np.linalg.lstsq(a, y, rcond=None)[0]
        return coef, y - a @ coef

    def cost(self, exponent: float) -> float:
        return float(np.sum(self.solve(exponent)[1] ** 2))

    def best_exponent(self) -> float:
        grid = np.linspace(*EXPONENT_RANGE, 13)
        costs = [self.cost(n) for n in grid]
        j = int(np.argmin(costs))
        lo, hi = grid[max(j - 1, 0)], grid[min(j + 1, grid.size - 1)]
        return float(minimize_scalar(self.cost, bounds=(lo, hi), method="bounded",
                                     options={"xatol": 1e-6}).x)

    def covariance(self, exponent: float, free: bool, impacts: int) -> tuple[np.ndarray, np.ndarray]:
        """Impact-clustered sandwich covariance of (``beta``, ``n``) [or ``beta`` alone],
        and the Jacobian columns."""
        coef, res = self.solve(exponent)
        cols = [self.delta ** exponent * self.rate]
        if free:
            cols.append(coef[0] * self.log_delta * cols[0])          # d(beta delta^n delta_dot)/dn
        if self.fit_stiffness:
            cols.append(self.elastic)
        jac = np.column_stack(cols)
        norm = np.linalg.norm(jac, axis=0)
        scaled = jac / norm                      # columns scaled to unit length: beta and n differ by 1e10
        bread = np.linalg.pinv(scaled.T @ scaled)
        meat = np.zeros_like(bread)
        for k in range(impacts):
            g = scaled[self.impact == k].T @ res[self.impact == k]
            meat += np.outer(g, g)
        factor = impacts / max(impacts - 1, 1)
        return factor * (bread @ meat @ bread) / np.outer(norm, norm), jac


def per_impact_table(reg: ForceRegression, s, anchors, exponent, beta, jac) -> dict:
    """Per-impact table: peak penetration [m], approach velocity [m/s], ``beta`` from the
    impact alone [N s m^-(n+1)], its share of the information on ``n`` [-], rms residual [N]."""
    count = s.count
    peak, approach, alone, share, rms = (np.full(count, np.nan) for _ in range(5))
    coef, res = reg.solve(exponent)
    if jac.shape[1] > 1:
        jb, jn = jac[:, 0], jac[:, 1]
        info = (jn - jb * (jb @ jn) / (jb @ jb)) ** 2                   # n's information, beta projected out
    else:
        info = jac[:, 0] ** 2
    for k in range(count):
        on = reg.impact == k
        if not on.any():
            continue
        peak[k] = reg.delta[on].max()
        approach[k] = reg.rate[on][0]
        x = reg.delta[on] ** exponent * reg.rate[on]
        alone[k] = float(x @ (reg.force[on] - coef[-1] * reg.elastic[on] if reg.fit_stiffness
                              else reg.force[on] - reg.elastic[on]) / (x @ x))
        share[k] = info[on].sum() / info.sum()
        rms[k] = math.sqrt(float(np.mean(res[on] ** 2)))
    return {"onset_time": s.onset_time, "record": s.record, "peak_penetration": peak,
            "approach_velocity": approach, "beta_alone": alone, "information_share": share,
            "rms_residual": rms, "moment_arm": s.arm}


def interval_95(value: float, sd: float, dof: int) -> tuple[float, float]:
    """Two-sided 95 % interval ``value +- t sd`` (Student's t with ``dof`` degrees)."""
    half = float(student_t.ppf(0.975, max(dof, 1))) * sd
    return value - half, value + half
