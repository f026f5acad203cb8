"""The modified Benedict-Kelley friction law of the lubricated contact (thesis eqs
4.41-4.43, as docs/model.md §6 reads the garbled text)::

    mu = C1 / (C2 - Rm) * log10( <p> / (eta <|vr| ve^2>) )          (4.41)
    <p> = < 3 Fn / (2 pi rho_e delta) >                                (4.42)
    mu_bar = C1 / (C2 - Rm)                                            (4.43)

with ``Rm = (Rc + Rb) / 2`` the mean roughness and ``< >`` the average over a
revolution. The logarithm's argument is evaluated in SI units (Pa, Pa s, m/s), which
is what the thesis's constants (C1 = 0.0288 um, C2 = 2.03 um for AGMA 4EP; 0.0509 um,
1.6512 um for ISO 32) assume as far as the text tells; C1 and C2 are fitted in metres.

Reference: J. L. Benedict, B. W. Kelley, "Instantaneous coefficients of gear tooth
friction", ASLE Trans. 4 (1961) 59-70, doi:10.1080/05698196108972420.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import curve_fit

from camdyn.errors import IdentificationError, ParameterError

__all__ = ["benedict_kelley", "normalized_friction", "fit_benedict_kelley", "BenedictKelleyFit",
           "operating_term"]


def operating_term(mean_pressure: float, viscosity: float, velocity_term: float) -> float:
    """``log10(<p> / (eta <|vr| ve^2>))`` [-] from ``<p>`` [Pa], ``eta`` [Pa s] and
    ``<|vr| ve^2>`` [m^3/s^3]."""
    if not (mean_pressure > 0 and viscosity > 0 and velocity_term > 0):
        raise ParameterError("the Benedict-Kelley term needs a positive pressure, viscosity and velocity term")
    return math.log10(mean_pressure / (viscosity * velocity_term))


def normalized_friction(roughness_mean, c1: float, c2: float):
    """``mu_bar = C1 / (C2 - Rm)`` [-] (eq 4.43); ``Rm``, ``C1``, ``C2`` in metres."""
    rm = np.asarray(roughness_mean, float)
    if np.any(rm >= c2):
        raise ParameterError("the mean roughness must stay below C2")
    return c1 / (c2 - rm)


def benedict_kelley(roughness_mean, log_term, c1: float, c2: float):
    """Coefficient of friction [-] of eq 4.41 for mean roughness ``Rm`` [m] and the
    operating term ``log10(<p>/(eta <|vr| ve^2>))`` [-]."""
    return normalized_friction(roughness_mean, c1, c2) * np.asarray(log_term, float)


@dataclass(frozen=True)
class BenedictKelleyFit:
    """Fitted constants of eq 4.41.

    Attributes
    ----------
    c1, c2 : float
        Constants [m].
    c1_std, c2_std : float
        Their standard errors from the fit's covariance [m].
    rms_error : float
        rms of ``mu - mu_fit`` [-].
    """

    c1: float
    c2: float
    c1_std: float
    c2_std: float
    rms_error: float


def fit_benedict_kelley(roughness_mean, mu, log_term) -> BenedictKelleyFit:
    """Fit ``C1`` and ``C2`` to measurements ``(Rm [m], mu [-])`` at operating terms
    ``log_term`` [-] (one per measurement, or one for all) by nonlinear least squares.

    Raises
    ------
    IdentificationError
        With fewer than three points, or a roughness span too narrow to separate C1 and C2.
    """
    rm = np.asarray(roughness_mean, float)
    mu = np.asarray(mu, float)
    term = np.broadcast_to(np.asarray(log_term, float), rm.shape)
    if rm.size < 3 or mu.shape != rm.shape:
        raise IdentificationError("fitting C1 and C2 needs at least three (Rm, mu) pairs of equal length")
    if not (np.all(np.isfinite(rm)) and np.all(np.isfinite(mu)) and np.all(mu > 0)):
        raise IdentificationError("the (Rm, mu) data must be finite with mu > 0")
    if np.ptp(rm) < 0.05 * np.mean(rm):
        raise IdentificationError("the mean roughnesses span less than 5 %: C1 and C2 cannot be told apart")
    # 1/mu_bar = (C2 - Rm) / C1 is linear in Rm: a start for the nonlinear fit
    slope, intercept = np.polyfit(rm, term / mu, 1)
    c1_0 = -1.0 / slope if slope < 0 else 1e-8
    c2_0 = intercept * c1_0 if slope < 0 else rm.max() * 2
    scale = max(rm.max(), 1e-9)

    def model(x, a, b):
        return benedict_kelley(x[0], x[1], a * scale, b * scale)

    try:
        popt, pcov = curve_fit(model, np.vstack([rm, term]), mu, p0=[c1_0 / scale, max(c2_0, 1.01 * rm.max()) / scale],
                               bounds=([0, rm.max() / scale * (1 + 1e-9)], [np.inf, np.inf]))
    except (RuntimeError, ValueError) as exc:
        raise IdentificationError(f"the Benedict-Kelley fit did not converge ({exc})") from None
    err = np.sqrt(np.diag(pcov)) * scale
    resid = mu - model(np.vstack([rm, term]), *popt)
    return BenedictKelleyFit(c1=float(popt[0] * scale), c2=float(popt[1] * scale), c1_std=float(err[0]),
                             c2_std=float(err[1]), rms_error=float(np.sqrt(np.mean(resid ** 2))))
