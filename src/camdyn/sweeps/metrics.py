"""Per-point metrics from the kernel's window (plain numpy, vectorised over the batch).

Every metric is computed from the kept window only (the transient is discarded):

- ``residual``: ``alpha_r = alpha - alpha_rigid`` with ``alpha_rigid`` the follower angle
  of rigid contact at the same cam angle (inverse kinematics, thesis 2.4); its rms (about
  zero, not about its mean: the static Hertz deflection belongs to the residual) and its
  peak-to-peak [rad] (figs 2.4, 2.7, 2.8).
- ``impacts``: contact onsets per revolution [1/rev]; 0 while contact is kept.
- ``poincare``: alpha [rad] and alpha_dot [rad/s] once per cam period, at the cam angle
  of the start (the stroboscopic Poincare section).
- ``max_force``: the largest normal force [N], over the window's samples and over the
  impact peaks the event log tracks between samples.
- ``regime``: 0 contact kept, 1 contact kept with sliding-velocity reversal, 2 periodic
  impacts, 3 irregular impacts (no period up to :data:`MAX_PERIOD` on the Poincare
  section; quasi-periodic and chaotic motion are told apart by the Lyapunov exponent,
  not here); -1 failed. ``period``: the smallest k with ``x[j + k] == x[j]`` on the
  Poincare section within :data:`PERIOD_TOLERANCE` of the section's spread, 0 if none.
- ``spectrum``: amplitudes of the first cam harmonics of ``alpha_ddot`` [rad/s^2]
  (one-sided, from the DFT over a whole number of periods, so every harmonic falls on a
  bin) and the frequency [Hz] and amplitude of the largest non-zero-frequency peak.
  The window is sampled, not filtered: content above ``samples / 2`` cam orders (the
  contact resonance of impacts) aliases, so raise ``samples_per_revolution`` to see it.
"""

from __future__ import annotations

import numpy as np

from camdyn.sweeps.kernel import WINDOW

__all__ = ["MAX_PERIOD", "PERIOD_TOLERANCE", "REGIMES", "compute", "variables"]

MAX_PERIOD = 16
#: tolerance of the period test, as a fraction of the orbit's peak-to-peak alpha and
#: alpha_dot. At the sweep's default rtol 3e-7 the integration error through a few hundred
#: impacts reaches about 1e-4 of the orbit (benchmarks/results.json: 1.0e-4 at 16 Hz), and
#: the Poincare points of period-1 impact motion wander by that much; 1e-3 sits ten times
#: above it and below the split of a period doubling once it is visible in a diagram.
PERIOD_TOLERANCE = 1e-3
REGIMES = {-1: "failed", 0: "contact_kept", 1: "sliding_reversal", 2: "periodic_impacts",
           3: "irregular_impacts"}

_CH = {name: i for i, name in enumerate(WINDOW)}


def variables(metrics, harmonics: int, kept: int) -> dict:
    """name -> (extra dimensions, their sizes, dtype, units, long name) of each result variable."""
    out = {}
    if "residual" in metrics:
        out["residual_rms"] = ((), (), "f8", "rad", "rms of the residual response alpha - alpha_rigid")
        out["residual_peak_to_peak"] = ((), (), "f8", "rad", "peak-to-peak of the residual response")
    if "impacts" in metrics:
        out["impacts_per_revolution"] = ((), (), "f8", "1/rev", "contact onsets per cam revolution")
    if "poincare" in metrics:
        out["poincare_alpha"] = (("revolution",), (kept,), "f8", "rad", "follower angle once per cam period")
        out["poincare_alpha_dot"] = (("revolution",), (kept,), "f8", "rad/s",
                                     "follower angular velocity once per cam period")
    if "max_force" in metrics:
        out["max_normal_force"] = ((), (), "f8", "N", "largest normal contact force")
    if "regime" in metrics:
        out["regime"] = ((), (), "i1", "1", "dynamic regime (see flag_meanings)")
        out["period"] = ((), (), "i2", "rev", f"Poincare period (0: none up to {MAX_PERIOD})")
    if "spectrum" in metrics:
        out["harmonic_amplitude"] = (("harmonic",), (harmonics,), "f8", "rad/s^2",
                                     "amplitude of alpha_ddot at the cam harmonics")
        out["peak_frequency"] = ((), (), "f8", "Hz", "frequency of the largest spectral peak of alpha_ddot")
        out["peak_amplitude"] = ((), (), "f8", "rad/s^2", "amplitude of the largest spectral peak of alpha_ddot")
    return out


def poincare_period(section: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Smallest period k <= MAX_PERIOD of each row of ``section`` (n, kept, 2) [rad, rad/s];
    0 if none. ``scale`` (n, 2): the orbit's peak-to-peak alpha and alpha_dot, the yardstick
    of :data:`PERIOD_TOLERANCE`."""
    n, kept, _ = section.shape
    period = np.zeros(n, dtype=np.int16)
    for k in range(1, min(MAX_PERIOD, kept // 2) + 1):
        diff = np.abs(section[:, k:, :] - section[:, :-k, :]) / scale[:, None, :]
        ok = np.all(diff <= PERIOD_TOLERANCE, axis=(1, 2)) & (period == 0)
        period[ok] = k
    return period


def compute(window: np.ndarray, onsets: np.ndarray, impact_force: np.ndarray, periods: np.ndarray,
            ok: np.ndarray, metrics, harmonics: int, samples: int) -> dict:
    """Metric arrays for a batch; rows where ``ok`` is False are NaN (regime -1)."""
    n, _, m = window.shape
    kept = m // samples
    out = {}
    if "residual" in metrics:
        res = window[:, _CH["alpha"]] - window[:, _CH["alpha_rigid"]]
        out["residual_rms"] = np.sqrt(np.mean(res * res, axis=1))
        out["residual_peak_to_peak"] = np.ptp(res, axis=1)
    if "impacts" in metrics:
        out["impacts_per_revolution"] = np.where(ok, onsets / kept, np.nan)
    section = np.stack([window[:, _CH["alpha"], ::samples], window[:, _CH["alpha_dot"], ::samples]], axis=2)
    if "poincare" in metrics:
        out["poincare_alpha"] = section[:, :, 0].copy()
        out["poincare_alpha_dot"] = section[:, :, 1].copy()
    if "max_force" in metrics:
        sampled = np.max(window[:, _CH["Fn"]], axis=1)
        out["max_normal_force"] = np.where(ok, np.maximum(sampled, impact_force), np.nan)
    if "regime" in metrics:
        orbit = np.stack([np.ptp(window[:, _CH["alpha"]], axis=1), np.ptp(window[:, _CH["alpha_dot"]], axis=1)],
                         axis=1)
        period = poincare_period(section, orbit + 1e-15)
        contact = window[:, _CH["in_contact"]]
        kept_contact = np.all(contact > 0.5, axis=1) & (onsets == 0)
        vr = window[:, _CH["sliding_velocity"]]
        reversal = (np.min(vr, axis=1) < 0.0) & (np.max(vr, axis=1) > 0.0)
        regime = np.where(kept_contact, np.where(reversal, 1, 0), np.where(period > 0, 2, 3)).astype(np.int8)
        regime[~ok] = -1
        period[~ok] = 0
        out["regime"] = regime
        out["period"] = period
    if "spectrum" in metrics:
        acc = np.where(ok[:, None], window[:, _CH["alpha_ddot"]], 0.0)
        amp = np.abs(np.fft.rfft(acc, axis=1)) * (2.0 / m)   # numpy's: a worker need not import SciPy
        amp[:, 0] *= 0.5
        out["harmonic_amplitude"] = np.where(ok[:, None], amp[:, kept:kept * (harmonics + 1):kept], np.nan)
        peak = 1 + np.argmax(amp[:, 1:], axis=1)
        out["peak_frequency"] = np.where(ok, peak / (kept * periods), np.nan)
        out["peak_amplitude"] = np.where(ok, amp[np.arange(n), peak], np.nan)
    return out
