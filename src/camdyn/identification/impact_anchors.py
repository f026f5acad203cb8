"""The per-impact anchors of the direct impact-damping method
(:mod:`camdyn.identification.impact_direct`, step 3), fitted for all impacts at once.

Each impact ``k`` has four unknowns: where contact starts ``d`` [m], the approach velocity
``v`` [m/s], the cam's normal acceleration ``a`` [m/s^2] over the impact, and a factor
``c`` [-] on the damping coefficient. With them the penetration and its rate are
``delta = d + v t + a t^2/2 - chi WW`` and ``delta_dot = v + a t - chi W`` (docs/model.md
§2), and the impact's force residual is ``K delta^1.5 + c beta delta^n delta_dot - Fn``
(eq 3.14). The impacts' problems are independent: their windows are padded to one
length and Levenberg-Marquardt steps are taken on all of them together (a batch of
4 x 4 normal equations), each impact with its own step length, instead of one solve of
the block-diagonal whole.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PaddedImpacts", "fit_anchors"]

#: Typical size of ``d`` [m], ``v`` [m/s], ``a`` [m/s^2] and ``c`` [-]: the step test's scale.
ANCHOR_SCALE = np.array([1e-6, 1e-2, 10.0, 1.0])


class PaddedImpacts:
    """The impacts' samples as ``(impacts, samples)`` arrays padded with zeros; ``mask``
    [-] marks the real samples.

    Parameters
    ----------
    s : ImpactSamples
        Lists per impact of ``offset`` [s], ``force`` [N], ``rate_integral`` [rad/s],
        ``angle_integral`` [rad]; ``arm`` [m], ``stiffness`` [N/m^elastic_exponent].
    """

    def __init__(self, s):
        count = len(s.force)
        width = max(f.size for f in s.force)
        self.mask = np.zeros((count, width))
        self.t, self.force, self.w, self.ww = (np.zeros((count, width)) for _ in range(4))
        for k in range(count):
            m = s.force[k].size
            self.mask[k, :m] = 1.0
            self.t[k, :m] = s.offset[k]
            self.force[k, :m] = s.force[k]
            self.w[k, :m] = s.rate_integral[k]
            self.ww[k, :m] = s.angle_integral[k]
        self.chi = np.asarray(s.arm, float)[:, None]
        self.k = np.asarray(s.stiffness, float)[:, None]
        self.e = float(s.elastic_exponent)

    def residual(self, x: np.ndarray, exponent: float, damping: float, jacobian: bool = True):
        """Force residuals [N], ``(impacts, samples)``, at the anchors ``x`` (``d, v, a, c`` per
        row) and, with ``jacobian``, their derivatives ``(impacts, samples, 4)``."""
        d, v, a, c = (x[:, i:i + 1] for i in range(4))
        t = self.t
        delta = d + v * t + 0.5 * a * t * t - self.chi * self.ww      # docs/model.md §2
        rate = v + a * t - self.chi * self.w
        on = delta > 0
        pos = np.where(on, delta, 0.0)
        pn = pos ** exponent
        r = (self.k * pos ** self.e + c * damping * pn * rate - self.force) * self.mask     # eq (3.14)
        if not jacobian:
            return r, None
        dfd = np.where(on, self.e * self.k * pos ** (self.e - 1) + c * damping * exponent
                       * pos ** max(exponent - 1, 0.0) * rate, 0.0)
        dfv = c * damping * pn
        jac = np.stack([dfd, dfd * t + dfv, dfd * 0.5 * t * t + dfv * t, damping * pn * rate], axis=-1)
        return r, jac * self.mask[..., None]


def fit_anchors(s, exponent: float, anchors: np.ndarray, damping: float, max_steps: int = 200,
                xtol: float = 1e-10, padded: PaddedImpacts | None = None) -> np.ndarray:
    """Anchors ``(d [m], v [m/s], a [m/s^2])`` of every impact, each fitted with its own
    damping factor at ``exponent`` [-] (step 3 of the direct method).

    Parameters
    ----------
    s : ImpactSamples
        The rebuilt impacts.
    exponent : float
        The exponent ``n`` [-] held fixed.
    anchors : ndarray
        Starting ``(d, v, a)`` per impact, shape ``(impacts, 3)``.
    damping : float
        The damping coefficient ``beta`` [N s m^-(n+1)] the factors multiply.
    max_steps : int
        Most Levenberg-Marquardt steps [-].
    xtol : float
        An impact is done when its step, in units of :data:`ANCHOR_SCALE`, is below
        ``xtol`` times its anchors' size [-].
    padded : PaddedImpacts, optional
        ``s`` already padded (reused across calls).

    Returns
    -------
    ndarray
        ``(impacts, 3)``.
    """
    pad = padded if padded is not None else PaddedImpacts(s)
    count = anchors.shape[0]
    x = np.column_stack([anchors, np.ones(count)])
    r, jac = pad.residual(x, exponent, damping)
    cost = np.einsum("kj,kj->k", r, r)
    lam = np.full(count, 1e-3)
    live = np.ones(count, bool)
    eye = np.eye(4)
    for _ in range(max_steps):
        # normal equations of each live impact, columns scaled to unit norm (Marquardt)
        jl, rl = jac[live], r[live]
        a = np.einsum("kji,kjl->kil", jl, jl)
        g = np.einsum("kji,kj->ki", jl, rl)
        norm = np.sqrt(np.maximum(np.einsum("kii->ki", a), 1e-300))
        scaled = a / (norm[:, :, None] * norm[:, None, :]) + lam[live][:, None, None] * eye
        step = -np.linalg.solve(scaled, (g / norm)[..., None])[..., 0] / norm
        trial = x.copy()
        trial[live] += step
        r_new, jac_new = pad.residual(trial, exponent, damping)      # all rows: cheaper than gathering
        cost_new = np.einsum("kj,kj->k", r_new, r_new)
        idx = np.flatnonzero(live)
        better = cost_new[idx] < cost[idx]
        good = idx[better]
        x[good], r[good], jac[good], cost[good] = trial[good], r_new[good], jac_new[good], cost_new[good]
        lam[good] *= 0.3
        lam[idx[~better]] *= 10.0
        small = np.max(np.abs(step) / ANCHOR_SCALE, axis=1) <= xtol * (np.max(np.abs(x[idx]) / ANCHOR_SCALE,
                                                                              axis=1) + xtol)
        live[idx[(better & small) | (lam[idx] > 1e12)]] = False
        if not live.any():
            break
    return x[:, :3]
