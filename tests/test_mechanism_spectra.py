"""Spectra of mechanisms (camdyn.analysis.spectra.follower_series, `camdyn spectrum` on a
mechanism file) and the residual, spectrum and stick-slip metrics of sweeps over a
mechanism: the flexible pivot in steady contact against inverse kinematics, two identical
followers on a cam symmetric under half a turn, a sweep's point against a direct run, the
residual against the rigid-contact angle in closed form, stick-slip counts against the
event log and the sampled stick flag, and the command's refusals."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import find_peaks
from typer.testing import CliRunner

from camdyn.analysis.harmonics import amplitude_spectrum
from camdyn.analysis.kinematics import inverse_kinematics
from camdyn.analysis.spectra import follower_series, spectrum_summary
from camdyn.cli.app import app, main
from camdyn.errors import ParameterError
from camdyn.io.mechanism_config import load_mechanism, simulate_mechanism
from camdyn.params.config import load_system
from camdyn.simulation.mechanisms import CamDrive
from camdyn.simulation.two_followers import simulate_two_followers
from camdyn.sweeps import run_sweep, spec_from_dict

MECHANISMS = Path(__file__).resolve().parents[1] / "examples" / "mechanisms"
PIVOT = str(MECHANISMS / "flexible_pivot.toml")
BRAKE = str(MECHANISMS / "drum_brake.toml")
STICK_SLIP = str(MECHANISMS / "drum_brake_stick_slip.toml")


@pytest.fixture(autouse=True)
def _in_tmp_path(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def _sweep(source, key, value, revolutions, discard, samples, metrics, set_=None):
    spec = spec_from_dict({"system": {"source": source, "set": set_ or {}}, "vary": [{"key": key, "values": [value]}],
                           "run": {"revolutions": revolutions, "discard": discard,
                                   "samples_per_revolution": samples},
                           "metrics": {"names": metrics}, "output": {"path": "m.nc"}}, name="m")
    return spec, run_sweep(spec, workers=0, progress=False).load().isel({key: 0})


def test_the_flexible_pivot_in_steady_contact_peaks_at_the_cam_harmonics_of_inverse_kinematics():
    changes = {"system.cam.runout": "0.3 mm", "system.motion.speed": "5 Hz"}
    mechanism = load_mechanism(PIVOT, changes)
    ds = simulate_mechanism(mechanism, revolutions=12, sample_rate=20e3)
    assert float(ds["in_contact"].min()) == 1.0                      # steady contact
    series = follower_series(ds)
    freq, amp = amplitude_spectrum(series, "alpha_ddot", 10)
    peaks, _ = find_peaks(amp)
    largest = freq[peaks[np.argsort(amp[peaks])[::-1][:2]]]
    np.testing.assert_allclose(largest, [5.0, 10.0], atol=0.5 * (freq[1] - freq[0]))
    # the harmonics are those of rigid contact on a rigid pivot (the bearing and the Hertz
    # contact give way by about 1e-5 rad; the dynamics add (5 Hz / 600 Hz)^2)
    kin = inverse_kinematics(mechanism.system, speed=5.0, points=1024)["alpha_ddot"].values
    rigid = 2.0 * np.abs(np.fft.rfft(kin)[1:3]) / kin.size
    summary = spectrum_summary(series, window=10, harmonics=2)
    measured = [h["amplitude"] for h in summary["harmonics"]]
    np.testing.assert_allclose(measured, rigid, rtol=2e-3)


def test_two_identical_followers_on_a_cam_symmetric_under_half_a_turn_have_one_spectrum():
    # an ellipse about its centre turns into itself in half a turn: the followers opposite
    # each other see one motion, and share the shaft, on a DC motor
    s = load_system("sundar2014-friction", {"cam.runout": "0 mm", "cam.semi_minor": "16 mm",
                                            "environment.gravity": "0 m/s^2"})
    omega = s.motion.angular_speed
    drive = CamDrive(shaft_inertia=2e-4, kind="motor", stall_torque=1.0, free_speed=1.2 * omega,
                     bearing_viscous=2e-4)
    ds = simulate_two_followers(s, drive, placement=math.pi, revolutions=8, sample_rate=20e3)
    assert float(np.ptp(ds["cam_speed"].values[-20000:])) > 0.0        # the shaft's speed responds
    one, two = (spectrum_summary(follower_series(ds, k, 6), window=6) for k in (1, 2))
    assert one["speed_hz"] == two["speed_hz"]
    first, second = ([h["amplitude"] for h in x["harmonics"]] for x in (one, two))
    np.testing.assert_allclose(second, first, rtol=0, atol=1e-9 * first[1])
    assert first[1] > 100 * first[0]                               # an ellipse: the second harmonic leads
    assert [p["frequency_hz"] for p in one["peaks"]] == [p["frequency_hz"] for p in two["peaks"]]


def test_a_sweeps_spectrum_and_residual_are_those_of_a_direct_run_of_the_point():
    revolutions, discard, samples = 8, 4, 512
    spec, point = _sweep(BRAKE, "drive.torque", "0.1 N*m", revolutions, discard, samples, ["spectrum", "residual"])
    mechanism = load_mechanism(BRAKE, {"drive.torque": "0.1 N*m"})
    direct = simulate_mechanism(mechanism, revolutions=revolutions, sample_rate=samples * 11.55, rtol=spec.rtol)
    start = discard * samples
    theta = direct["cam_angle"].values[start:]
    whole = int(abs(theta[-1] - theta[0]) / (2 * math.pi))          # whole cam turns in the window
    assert whole >= 2
    for k in (1, 2):
        summary = spectrum_summary(follower_series(direct, k, whole), window=whole, harmonics=spec.harmonics)
        np.testing.assert_allclose(point["harmonic_amplitude"].sel(follower=k).values,
                                   [h["amplitude"] for h in summary["harmonics"]], rtol=1e-12)
    # the residual against rigid contact in closed form: on a circle of radius a, centre
    # G = E - e (cos T, sin T) in the follower's frame, delta = 0 reads
    # sin(alpha) Gx + cos(alpha) Gy = h + a, so alpha = psi - acos((h + a) / |G|),
    # psi = atan2(Gx, Gy)
    s = mechanism.system
    h, a, e = s.follower.surface_offset, s.cam.semi_major, s.cam.runout
    alpha = direct["alpha"].values[start:]
    for k, frame in ((1, theta), (2, theta - float(direct.attrs["placement"]))):
        gx, gy = s.cam.pivot_x - e * np.cos(frame), s.cam.pivot_y - e * np.sin(frame)
        rigid = np.arctan2(gx, gy) - np.arccos((h + a) / np.hypot(gx, gy))
        residual = alpha[:, k - 1] - rigid
        np.testing.assert_allclose(point["residual_rms"].sel(follower=k), np.sqrt(np.mean(residual ** 2)), rtol=1e-9)
        np.testing.assert_allclose(point["residual_peak_to_peak"].sel(follower=k), np.ptp(residual), rtol=1e-7)


def test_stick_slip_counts_per_revolution_are_the_event_logs_and_the_stick_flags():
    # the slow controller's drum brake started at 100 rad/s: friction stops the cam within
    # the first period, and the contacts stick and slip (nothing discarded: the window
    # starts at the first sample)
    revolutions, samples = 2, 4096
    spec, point = _sweep(STICK_SLIP, "drive.initial_speed", "100 rad/s", revolutions, 0, samples, ["stick_slip"])
    mechanism = load_mechanism(STICK_SLIP, {"drive.initial_speed": "100 rad/s"})
    direct = simulate_mechanism(mechanism, revolutions=revolutions, sample_rate=samples * 100.0 / (2 * math.pi),
                                rtol=spec.rtol)
    assert direct.attrs["events_dropped"] == 0                      # the log holds every switch
    turns = abs(direct["cam_angle"].values[-1] - direct["cam_angle"].values[0]) / (2 * math.pi)
    kinds, who = direct["transition_kind"].values, direct["transition_follower"].values
    flag = direct["sticking"].values > 0.5
    for k in (1, 2):
        sticks, slips, sprags = (int(np.sum((kinds == kind) & (who == k))) for kind in ("stick", "slip", "sprag"))
        assert sticks >= 1 and slips >= 1
        assert point["sticks_per_revolution"].sel(follower=k) * turns == pytest.approx(sticks, rel=1e-12)
        assert point["slips_per_revolution"].sel(follower=k) * turns == pytest.approx(slips, rel=1e-12)
        assert point["sprags_per_revolution"].sel(follower=k) * turns == pytest.approx(sprags, abs=0)
        # every stick outlasts a sample here, so the sampled flag rises and falls as often
        column = flag[:, k - 1]
        assert sticks == int(np.sum(~column[:-1] & column[1:]))
        assert slips == int(np.sum(column[:-1] & ~column[1:]))


def test_camdyn_spectrum_on_a_mechanism_file_per_follower():
    runner = CliRunner()
    result = runner.invoke(app, ["spectrum", BRAKE, "--revolutions", "8", "--window", "5", "--json"])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert document["summary"]["mechanism"] == "two-followers"
    assert [f["follower"] for f in document["followers"]] == [1, 2]
    ds = simulate_mechanism(load_mechanism(BRAKE), revolutions=8, sample_rate=20e3)
    for entry, k in zip(document["followers"], (1, 2)):
        summary = spectrum_summary(follower_series(ds, k, 5), window=5)
        assert [h["amplitude"] for h in entry["harmonics"]] == [h["amplitude"] for h in summary["harmonics"]]
    one = runner.invoke(app, ["spectrum", BRAKE, "--revolutions", "8", "--window", "5", "--follower", "2",
                              "--plot", "two.png"])
    assert one.exit_code == 0, one.output
    assert one.stdout.startswith("follower 2: alpha_ddot at") and Path("two.png").stat().st_size > 0


@pytest.mark.parametrize("arguments, message", [
    ([BRAKE, "--follower", "3"], "--follower: the two-followers mechanism has 2 followers, got 3"),
    ([BRAKE, "--plot", "x.png"], "--plot draws one follower's spectrum: give --follower 1 or 2"),
    ([PIVOT, "--follower", "2"], "--follower: the flexible-pivot mechanism has 1 follower, got 2"),
    (["sundar2014-friction", "--follower", "2"], "--follower: sundar2014-friction has one follower, got 2"),
    ([BRAKE, "--variable", "Nx"], "--variable must be a time series of the result"),
])
def test_camdyn_spectrum_refuses_a_bad_follower_in_one_line(arguments, message, capsys):
    assert main(["spectrum", *arguments, "--revolutions", "3", "--window", "1"]) == 2
    error = capsys.readouterr().err
    assert message in error and len(error.strip().splitlines()) == 1


def test_follower_series_refuses_what_it_cannot_take():
    ds = simulate_mechanism(load_mechanism(BRAKE), revolutions=2, sample_rate=5e3)
    with pytest.raises(ParameterError, match="give follower 1 or 2"):
        follower_series(ds)
    with pytest.raises(ParameterError, match="the window needs 9"):
        follower_series(ds, 1, 9)
