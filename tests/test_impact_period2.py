"""The direct impact-damping method on a record whose impacts are not one per revolution:
the independent event-driven SciPy model of tests/test_impact_direct.py at 9 Hz settles
into a period-2 response with three impacts in two revolutions (found by trying speeds
from 8 to 30 Hz: 8 Hz gives two impacts a revolution, 10-15 Hz one, 21-27 Hz one in two
revolutions). The thesis's residue method refuses that record; the direct method, and
the output-error fit started from it, identify the damping from it."""

import numpy as np
import pytest
from test_impact_direct import E_RUN, simulate_independent

import camdyn
from camdyn.errors import IdentificationError
from camdyn.identification.impact_damping import estimate_impact_damping
from camdyn.identification.impact_direct import estimate_impact_damping_direct
from camdyn.identification.impact_output_error import estimate_impact_damping_output_error
from camdyn.records.schema import make_record

BETA, N = 24.7e9, 1.5
SPEED = 9.0
SETTLE, KEEP = 18, 12        # revolutions discarded, kept


@pytest.fixture(scope="module")
def period2():
    """The last 12 of 30 revolutions, 0.5 % noise; the independent model's impacts there."""
    t, channels, _ = simulate_independent(BETA, N, speed=SPEED, duration=(SETTLE + KEEP) / SPEED)
    keep = t >= SETTLE / SPEED
    rng = np.random.default_rng(0)
    noisy = {k: v[keep] + 0.005 * np.std(v[keep]) * rng.standard_normal(keep.sum()) for k, v in channels.items()}
    return make_record(t[keep] - t[keep][0], noisy, speed_hz=SPEED, runout=E_RUN)


@pytest.fixture(scope="module")
def rig():
    return camdyn.load_system("sundar2014-impact").with_values(**{"cam.runout": E_RUN,
                                                                  "friction.coefficient": 0.0})


def test_direct_identifies_period_two_with_three_impacts(rig, period2):
    """Three impacts in two revolutions (18 in 12, of three different peak penetrations,
    repeating every two revolutions); n within 1 % and beta delta_peak^n within 3 % (0.5 %
    noise, the task's tolerances). Measured: n -0.41 %, damping at the peak +2.2 %."""
    est = estimate_impact_damping_direct(rig, period2)
    assert est.impacts_used >= 15
    onsets = np.asarray(est.per_impact["onset_time"])
    assert np.allclose(onsets[3:] - onsets[:-3], 2.0 / SPEED, rtol=0.01)      # three impacts per two turns
    peaks = np.asarray(est.per_impact["peak_penetration"])
    assert np.allclose(peaks[3:], peaks[:-3], rtol=0.02)            # period 2: repeats every 3 impacts
    assert np.ptp(peaks[:3]) / np.median(peaks) > 0.3                # the three impacts differ
    assert est.identifiable, est.diagnosis
    assert abs(est.exponent / N - 1) < 0.01
    assert abs(est.damping_at_peak / (BETA * est.peak_penetration ** N) - 1) < 0.03


def test_residue_method_refuses_it(rig, period2):
    with pytest.raises(IdentificationError, match="needs exactly one impact per revolution"):
        estimate_impact_damping(rig, period2, bootstrap=0)


def test_output_error_on_period_two(rig, period2):
    """The output-error fit (started from the direct estimate) on the same record: n within
    1 %, beta delta_peak^n within 3 %. Measured: n +0.003 %, damping at the peak +0.14 %."""
    est = estimate_impact_damping_output_error(rig, period2)
    assert abs(est.exponent / N - 1) < 0.01
    assert abs(est.damping_at_peak / (BETA * est.peak_penetration ** N) - 1) < 0.03
