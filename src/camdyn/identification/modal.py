"""Modal damping from an impulse test: the half-power bandwidth of an accelerance peak
(thesis 4.5.2, fig 4.7), and a synthetic two-mass impulse test to check it.

The accelerance ``A(f) = FFT(acceleration) / FFT(force)`` of a hammer test is searched
for its peak ``f_n``; the half-power frequencies ``f_1 < f_n < f_2`` where ``|A|`` falls
to ``|A(f_n)| / sqrt(2)`` are interpolated linearly between spectral lines, and
``zeta = (f_2 - f_1) / (2 f_n)``. The estimate is refused when the half-power band
holds fewer than :data:`MIN_LINES` spectral lines (the peak is not resolved: record
longer) or when the response has not decayed by the end of the record (leakage).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass

import numpy as np
import xarray as xr

from camdyn.errors import IdentificationError, ParameterError
from camdyn.records.schema import check_noise, check_record, check_seed, make_record

__all__ = ["ModalDamping", "accelerance", "half_power_damping", "synthesize_impulse_test", "MIN_LINES"]

#: Fewest spectral lines inside the half-power band for a resolved peak [-].
MIN_LINES = 5
#: Force-spectrum level, relative to its peak, below which the accelerance is not formed [-].
FORCE_FLOOR = 0.05
#: Largest response amplitude left at the end of the record, relative to its peak [-].
DECAY_LIMIT = 0.02


@dataclass(frozen=True)
class ModalDamping:
    """Half-power estimate of one mode.

    Attributes
    ----------
    natural_frequency : float
        Peak frequency ``f_n`` [Hz].
    damping_ratio : float
        ``zeta`` [-].
    lower, upper : float
        Half-power frequencies [Hz].
    peak : float
        ``|A(f_n)|`` [m/(N s^2) = 1/kg].
    lines : int
        Spectral lines inside the half-power band [-].
    resolution : float
        Line spacing [Hz].
    """

    natural_frequency: float
    damping_ratio: float
    lower: float
    upper: float
    peak: float
    lines: int
    resolution: float

    def to_dict(self) -> dict:
        return asdict(self)


def accelerance(record: xr.Dataset) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies [Hz] and complex accelerance [1/kg] of an impulse-test record with
    ``force`` [N] and ``acceleration`` [m/s^2] channels (rectangular window). Lines where
    the force spectrum is below :data:`FORCE_FLOOR` of its peak (outside the hammer's
    band) are NaN."""
    check_record(record, ("force", "acceleration"))
    t = record["time"].values
    dt = t[1] - t[0]
    f = record["force"].values
    a = record["acceleration"].values
    peak = np.max(np.abs(a))
    tail = np.max(np.abs(a[-max(8, a.size // 50):]))
    if peak == 0 or np.max(np.abs(f)) == 0:
        raise IdentificationError("the record holds no impulse: force or acceleration is zero throughout")
    if tail > DECAY_LIMIT * peak:
        raise IdentificationError(f"the response has not decayed by the end of the record (the last 2 % still "
                                  f"reach {100 * tail / peak:.1f} % of the peak): the spectrum leaks; "
                                  "record longer")
    spec_f = np.fft.rfft(f)
    spec_a = np.fft.rfft(a)
    freq = np.fft.rfftfreq(t.size, dt)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = spec_a / spec_f
    # outside the hammer's band the force spectrum is near zero and the ratio is noise
    h[np.abs(spec_f) < FORCE_FLOOR * np.abs(spec_f).max()] = np.nan
    return freq, h


def half_power_damping(frequency: np.ndarray, response: np.ndarray,
                       band: tuple[float, float] | None = None) -> ModalDamping:
    """Half-power (-3 dB) damping ratio of the highest peak of ``|response|`` in ``band`` [Hz].

    Raises
    ------
    IdentificationError
        If the band holds no clear peak, the half-power points fall outside the data,
        or the half-power band holds fewer than :data:`MIN_LINES` lines.
    """
    try:
        freq = np.asarray(frequency, float)
        mag = np.abs(np.asarray(response, complex))
    except (TypeError, ValueError):
        raise ParameterError("frequency [Hz] and response must be arrays of numbers") from None
    if freq.ndim != 1 or mag.shape != freq.shape or freq.size < 3:
        raise ParameterError(f"frequency [Hz] and response must be 1-D arrays of the same length, at least 3 "
                             f"spectral lines; got shapes {freq.shape} and {mag.shape}")
    try:
        lo, hi = (float(f) for f in band) if band is not None else (freq[1], freq[-1])
    except (TypeError, ValueError):
        raise ParameterError(f"the search band must be two frequencies [Hz], got {band!r:.60}") from None
    if not (0 <= lo < hi):
        raise ParameterError(f"the search band must be increasing frequencies, got {band!r}")
    sel = np.nonzero((freq >= lo) & (freq <= hi) & np.isfinite(mag))[0]
    if sel.size < 3:
        raise IdentificationError(f"the band {lo:g}-{hi:g} Hz holds fewer than 3 spectral lines")
    i = sel[np.argmax(mag[sel])]
    if i in (sel[0], sel[-1]):
        raise IdentificationError(f"the largest response in {lo:g}-{hi:g} Hz is at the band's edge "
                                  f"({freq[i]:.4g} Hz): no resonance peak inside it")
    # parabolic refinement of the peak in |A|^2 over three lines
    y0, y1, y2 = mag[i - 1] ** 2, mag[i] ** 2, mag[i + 1] ** 2
    denom = y0 - 2 * y1 + y2
    shift = 0.5 * (y0 - y2) / denom if denom < 0 else 0.0
    df = freq[1] - freq[0]
    fn = freq[i] + shift * df
    peak_sq = y1 - 0.25 * (y0 - y2) * shift
    level = math.sqrt(peak_sq / 2.0)
    j = i
    while j > 0 and mag[j] > level:
        j -= 1
    k = i
    while k < mag.size - 1 and mag[k] > level:
        k += 1
    if mag[j] > level or mag[k] > level:
        raise IdentificationError("the response does not fall to half power on both sides of the peak")
    f1 = freq[j] + (level - mag[j]) / (mag[j + 1] - mag[j]) * df
    f2 = freq[k - 1] + (mag[k - 1] - level) / (mag[k - 1] - mag[k]) * df
    lines = int(k - j - 1)
    if lines < MIN_LINES:
        needed = MIN_LINES / max(f2 - f1, 1e-300)        # lines ~ bandwidth x record length
        raise IdentificationError(
            f"the peak at {fn:.4g} Hz is not resolved: its half-power band ({f2 - f1:.3g} Hz) holds {lines} "
            f"spectral lines at {df:.3g} Hz spacing; at least {MIN_LINES} are needed (a record of about "
            f"{needed:.3g} s or longer)")
    return ModalDamping(natural_frequency=float(fn), damping_ratio=float((f2 - f1) / (2.0 * fn)), lower=float(f1),
                        upper=float(f2), peak=float(math.sqrt(peak_sq)), lines=lines, resolution=float(df))


#: Fewest samples an impulse test may hold [-].
MIN_IMPULSE_SAMPLES = 16


def _positive(name: str, value, unit: str) -> float:
    """``value`` [unit] as a float, or a ParameterError unless it is a positive, finite number."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not (math.isfinite(value) and value > 0):
        raise ParameterError(f"{name} must be a positive, finite number of {unit}, got {value!r:.60}")
    return float(value)


def _positive_pair(name: str, value, unit: str) -> tuple[float, float]:
    """Two positive, finite numbers [unit], or a ParameterError."""
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        raise ParameterError(f"{name} must be two positive numbers of {unit}, got {value!r:.60}")
    first, second = value
    return _positive(name, first, unit), _positive(name, second, unit)


def synthesize_impulse_test(masses=(0.21, 0.05), stiffnesses=(8.0e6, 6.0e6), damping_ratios=(0.02, 0.02),
                            duration: float = 1.0, sample_rate: float = 20e3, pulse: float = 2e-4,
                            force_peak: float = 100.0, noise: float = 0.0, seed: int | None = 0) -> xr.Dataset:
    """Hammer test on a chain of two masses: ground - k1 - m1 - k2 - m2, hit and measured at m1.

    Modal damping (``C = M Phi diag(2 zeta_r omega_r) Phi^T M`` with mass-normalised
    modes) keeps each mode's damping ratio exact. The response comes from
    :func:`scipy.signal.lsim` on the state-space model, independently of the FFT the
    estimator uses.

    Parameters
    ----------
    masses : (float, float)
        ``m1, m2`` [kg].
    stiffnesses : (float, float)
        ``k1, k2`` [N/m].
    damping_ratios : (float, float)
        Modal damping ratios of the lower and upper mode [-].
    duration, sample_rate : float
        Record length [s] and sampling rate [Hz].
    pulse : float
        Duration of the half-sine hammer pulse [s].
    force_peak : float
        Peak hammer force [N].
    noise : float
        Gaussian noise on each channel, as a fraction of its rms [-].

    Returns
    -------
    xarray.Dataset
        Record with ``force`` and ``acceleration``; attributes ``natural_frequencies``
        [Hz] and ``damping_ratios`` [-] of the true modes.
    """
    from scipy.linalg import eigh
    from scipy.signal import lsim

    m1, m2 = _positive_pair("masses", masses, "kg")
    k1, k2 = _positive_pair("stiffnesses", stiffnesses, "N/m")
    duration, sample_rate, pulse, force_peak = (_positive(name, value, unit) for name, value, unit in (
        ("duration", duration, "s"), ("sample_rate", sample_rate, "Hz"), ("pulse", pulse, "s"),
        ("force_peak", force_peak, "N")))
    if duration * sample_rate < MIN_IMPULSE_SAMPLES:
        raise ParameterError(f"an impulse test of {duration:g} s at {sample_rate:g} Hz holds fewer than "
                             f"{MIN_IMPULSE_SAMPLES} samples")
    check_noise(noise)
    check_seed(seed)
    from camdyn.simulation import limits  # here: reading a hammer test needs no integrator

    # t, the force, the response, lsim's four states and its temporaries: about 12 doubles a sample
    limits.check_request(f"an impulse test of {duration:g} s at {sample_rate:g} Hz", duration * sample_rate, 96,
                         unit="samples")
    mass = np.diag([m1, m2])
    stiff = np.array([[k1 + k2, -k2], [-k2, k2]])
    w2, phi = eigh(stiff, mass)                     # mass-normalised: phi^T M phi = I
    omega = np.sqrt(w2)
    try:
        zeta = np.asarray(damping_ratios, float)
    except (TypeError, ValueError):
        zeta = np.empty(0)
    if zeta.shape != (2,) or not np.all((zeta >= 0.0) & (zeta < 1.0)):
        raise ParameterError(f"modal damping ratios must lie in [0, 1) (0 undamped, 1 critically damped, where "
                             f"no resonance peak is left to measure), got {damping_ratios!r}")
    damp = mass @ phi @ np.diag(2 * zeta * omega) @ phi.T @ mass
    minv = np.linalg.inv(mass)
    a_mat = np.block([[np.zeros((2, 2)), np.eye(2)], [-minv @ stiff, -minv @ damp]])
    b_mat = np.concatenate([np.zeros((2, 1)), minv @ np.array([[1.0], [0.0]])])
    c_mat = np.concatenate([-minv @ stiff, -minv @ damp], axis=1)[:1]    # acceleration of m1
    d_mat = minv[:1, :1]
    t = np.arange(int(round(duration * sample_rate))) / sample_rate
    force = np.where(t < pulse, force_peak * np.sin(np.pi * t / pulse), 0.0)
    _, acc, _ = lsim((a_mat, b_mat, c_mat, d_mat), force, t)
    rng = np.random.default_rng(seed)
    if noise > 0:
        force = force + noise * np.std(force) * rng.standard_normal(t.size)
        acc = acc + noise * np.std(acc) * rng.standard_normal(t.size)
    return make_record(t, {"force": force, "acceleration": acc}, natural_frequencies=list(omega / (2 * np.pi)),
                       damping_ratios=list(zeta))
