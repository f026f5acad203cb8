"""Direct identification of the impact damping (restoring-force regression): round trips
on records from an independent event-driven SciPy model of the impacting follower
(written here from docs/model.md, with the chapter 3 rig's numbers typed in, no camdyn
code), the identifiability flag, and refusals.

The independent model is frictionless (camdyn's rig is set to mu = 0 to match), with a
circular cam of runout e/rc = 0.25 at 15 Hz. It starts 20 mrad away from the cam at rest,
so that its first impacts differ from the steady ones (approach velocities and peak
penetrations from 33 to 50 um), which is what lets n be told across impacts.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import camdyn
from camdyn.errors import CamdynError, DataError, IdentificationError
from camdyn.identification.impact_direct import estimate_impact_damping_direct
from camdyn.records.schema import make_record

# chapter 3 rig (docs/model.md §4), SI units
M, I_P, L_CG = 0.257, 3300e-6, 0.086
WB, RD = 12.7e-3, 3.2e-3
H = 0.5 * WB + 2 * RD
RC = 17.5e-3
E_RUN = 0.25 * RC
PEX, PEY = 0.089, 0.027
KS, LS, DX, DY, G = 3319.0, 0.053, 0.035, 0.058, 9.81
ESTAR = 210e9 / (2 * (1 - 0.3 ** 2))
K_HERTZ = 4.0 / 3.0 * ESTAR * math.sqrt(1.0 / (1.0 / RC + 1.0 / RD))
SPEED = 15.0
OMEGA = 2 * math.pi * SPEED
RATE = 204.8e3


def _geometry(t, alpha, alpha_dot, runout=E_RUN, omega=OMEGA):
    """Penetration [m], its rate [m/s], moment arm [m], normal (nx, ny) of the circle cam."""
    th = omega * t
    sa, ca = np.sin(alpha), np.cos(alpha)
    gx, gy = PEX - runout * np.cos(th), PEY - runout * np.sin(th)
    delta = H + RC - (sa * gx + ca * gy)
    xc, yc = gx - RC * sa, gy - RC * ca
    chi = ca * xc - sa * yc
    vx, vy = -omega * (yc - PEY), omega * (xc - PEX)
    return delta, -alpha_dot * chi - (sa * vx + ca * vy), chi, sa, ca


def _acceleration_and_force(t, alpha, alpha_dot, beta, n, runout=E_RUN, omega=OMEGA):
    delta, rate, chi, sa, ca = _geometry(t, alpha, alpha_dot, runout, omega)
    pos = np.maximum(delta, 0.0)
    fn = np.where(delta > 0, K_HERTZ * pos ** 1.5 + beta * pos ** n * rate, 0.0)
    fs = KS * (LS - DY + DX * np.tan(alpha) + 0.5 * WB / ca)
    acc = (M * G * L_CG * ca - fs * DX + fn * chi) / I_P
    return acc, fn, fs, sa, ca


def simulate_independent(beta, n, runout=E_RUN, speed=SPEED, duration=0.5, gap=0.02, sample_rate=RATE):
    """Event-driven DOP853 solution from rest ``gap`` [rad] off the cam; returns the time
    [s], the channels (alpha_ddot, Nx, Ny) and the true peak penetration of each contact [m]."""
    omega = 2 * math.pi * speed
    geo = lambda t, a, ad: _geometry(t, a, ad, runout, omega)
    touch = brentq(lambda a: geo(0.0, a, 0.0)[0], -0.5, 0.5)
    y = np.array([touch + gap, 0.0])
    t0, contact, segments = 0.0, False, []

    def rhs(t, s):
        return [s[1], _acceleration_and_force(t, s[0], s[1], beta, n, runout, omega)[0]]

    def event(t, s):
        return geo(t, s[0], s[1])[0]
    event.terminal = True
    while t0 < duration:
        event.direction = -1.0 if contact else 1.0
        sol = solve_ivp(rhs, (t0, duration), y, method="DOP853", rtol=1e-11, atol=1e-13, events=event,
                        dense_output=True, max_step=2e-6 if contact else 1e-3)
        segments.append((t0, sol.t[-1], sol.sol, contact))
        t0, y = sol.t[-1], sol.y[:, -1]
        contact = not contact if sol.status == 1 else contact
    t = np.arange(int(duration * sample_rate)) / sample_rate
    alpha, rate = np.empty(t.size), np.empty(t.size)
    peaks = []
    for a, b, dense, in_contact in segments:
        idx = (t >= a) & (t < b)
        alpha[idx], rate[idx] = dense(t[idx])
        if in_contact:
            fine = np.linspace(a, b, 2001)
            peaks.append(geo(fine, *dense(fine))[0].max())
    acc, fn, fs, sa, ca = _acceleration_and_force(t, alpha, rate, beta, n, runout, omega)
    agx = -L_CG * (acc * sa + rate ** 2 * ca)
    agy = -L_CG * (acc * ca - rate ** 2 * sa)
    channels = {"alpha_ddot": acc, "Nx": M * agx + fn * sa, "Ny": M * agy + fn * ca - fs + M * G}
    return t, channels, np.array(peaks)


def noisy_record(t, channels, noise, seed=0):
    """Gaussian noise of ``noise`` times each channel's rms about its mean."""
    rng = np.random.default_rng(seed)
    out = {k: v + noise * np.std(v) * rng.standard_normal(v.size) for k, v in channels.items()}
    return make_record(t, out, speed_hz=SPEED, runout=E_RUN)


@pytest.fixture(scope="module")
def rig():
    return camdyn.load_system("sundar2014-impact").with_values(**{"cam.runout": E_RUN,
                                                                  "friction.coefficient": 0.0})


LAWS = {"thesis S2": (24.7e9, 1.5), "n = 1.2": (1.2e9, 1.2)}


@pytest.fixture(scope="module", params=list(LAWS))
def transient(request):
    beta, n = LAWS[request.param]
    return (beta, n) + simulate_independent(beta, n, duration=0.6)


@pytest.mark.parametrize("noise, n_tol, c_tol", [(0.005, 0.01, 0.03), (0.02, 0.03, 0.10)])
def test_round_trip_on_independent_model(rig, transient, noise, n_tol, c_tol):
    """n within 1 % and beta delta_peak^n within 3 % at 0.5 % noise; 3 % and 10 % at 2 %
    (the tolerances of the task, not tuned); the rebuilt peak penetration within 3 % of
    the independent model's."""
    beta, n, t, channels, peaks = transient
    est = estimate_impact_damping_direct(rig, noisy_record(t, channels, noise))
    truth = beta * est.peak_penetration ** n
    assert abs(est.exponent / n - 1) < n_tol
    assert abs(est.damping_at_peak / truth - 1) < c_tol
    assert abs(est.peak_penetration / np.median(peaks) - 1) < 0.03
    assert est.identifiable, est.diagnosis


def test_interval_of_n_covers_the_truth(rig, transient):
    """The truth lies within 3 half-widths of the 95 % interval of n (0.5 % noise).
    Measured: n = 1.5 error 0.0013 against 0.0024, n = 1.2 error 0.0014 against 0.0016
    (narrowly: the clustered interval does not count the bias the impacts' fitted anchors
    share). It missed for n = 1.2 (error 0.0017) while the alternation stopped at steps of
    1e-4 in n, 5e-4 short of its fixed point; Aitken's extrapolation now reaches it."""
    beta, n, t, channels, _ = transient
    est = estimate_impact_damping_direct(rig, noisy_record(t, channels, 0.005))
    lo, hi = est.confidence["n"]
    assert abs(est.exponent - n) < 3 * (hi - lo) / 2


def test_transient_impacts_differ(transient):
    """The round-trip record's first impacts differ from the steady ones (peak
    penetrations spread by more than 20 %)."""
    *_, peaks = transient
    assert np.ptp(peaks) / np.median(peaks) > 0.2


def test_equal_impacts_are_flagged(rig, transient):
    """The same model's steady period-1 part (every impact alike) is flagged: n rests on
    the force's shape within impacts alone."""
    _, _, t, channels, _ = transient
    keep = t >= 0.25
    rec = noisy_record(t[keep] - t[keep][0], {k: v[keep] for k, v in channels.items()}, 0.005)
    est = estimate_impact_damping_direct(rig, rec)
    assert not est.identifiable
    assert "spread" in est.diagnosis


@pytest.fixture(scope="module")
def clean(transient):
    *_, t, channels, _ = transient
    return t, channels


def test_refuses_low_sampling_rate(rig, clean):
    t, channels = clean
    rec = make_record(t[::12], {k: v[::12] for k, v in channels.items()}, speed_hz=SPEED, runout=E_RUN)
    with pytest.raises(IdentificationError, match="too low to rebuild the penetration"):
        estimate_impact_damping_direct(rig, rec)


def test_refuses_drifting_force(rig, clean):
    t, channels = clean
    shifted = dict(channels, Ny=channels["Ny"] + 0.1 * channels["Ny"].max())
    with pytest.raises(IdentificationError, match="drift"):
        estimate_impact_damping_direct(rig, make_record(t, shifted, speed_hz=SPEED, runout=E_RUN))


def test_refuses_clipped_channel(rig, clean):
    t, channels = clean
    top = np.percentile(channels["Ny"], 99.9)
    clipped = dict(channels, Ny=np.minimum(channels["Ny"], top))
    with pytest.raises(DataError, match="clipped"):
        estimate_impact_damping_direct(rig, make_record(t, clipped, speed_hz=SPEED, runout=E_RUN))


def test_refuses_a_single_impact(rig, clean):
    t, channels = clean
    keep = t < 0.01
    with pytest.raises(CamdynError):
        estimate_impact_damping_direct(rig, make_record(t[keep], {k: v[keep] for k, v in channels.items()},
                                                        speed_hz=SPEED, runout=E_RUN))
