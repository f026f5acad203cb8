"""Per-point metrics of a mechanism's run (the Dataset of
:func:`camdyn.io.mechanism_config.simulate_mechanism`), over the kept window only: the
samples from ``discard`` periods of the starting cam speed on (the run is sampled
``samples`` times per such period, so the window starts at sample ``discard * samples``).

- ``impacts``: contact onsets per cam revolution [1/rev], per follower: the rises of the
  sampled contact flag ``in_contact`` in the window (counting from the sample before it),
  plus the sample intervals that begin and end out of contact but over which the cam did
  work on the follower (its ``cam_work`` state, which free flight leaves unchanged to the
  last bit, changed): a contact that fell between two samples, counted once however
  many it was; over the cam revolutions the window spans (its cam-angle advance over
  2 pi; ``kept`` at the flexible pivot's constant speed).
- ``max_force``: the largest sampled normal force [N], per follower (a contact between
  two samples is not seen here: raise ``samples_per_revolution`` to resolve its peak).
- ``poincare``: follower angle [rad] and angular velocity [rad/s], per follower, once
  per cam revolution: at the samples of whole periods for the flexible pivot (constant
  speed), and where the cam angle passes whole turns from its start (linear
  interpolation between the two samples around each) for a driven cam, whose turns do
  not keep time; NaN past the turns the window holds.
- ``regime``: as :data:`camdyn.sweeps.metrics.REGIMES`: 0 every follower kept contact
  over the window (1: and a sliding velocity reversed), 2 periodic (the Poincare section
  of every follower's angle and velocity, and of the cam speed of a driven cam, repeats
  with a period k <= ``MAX_PERIOD`` within ``PERIOD_TOLERANCE`` of each channel's
  spread), 3 irregular; -1 failed. ``period``: that k, 0 if none.
- ``speed_fluctuation`` (driven cam, two followers): the cam speed's coefficient of
  fluctuation (max - min) / mean over the window [-] (Norton, *Design of Machinery*, 5th
  ed., 2012, eq 11.18) and its mean [rad/s].
- ``bearing_force`` (flexible pivot): the largest sampled magnitude of the bearing's
  force on the follower, ``sqrt(Nx^2 + Ny^2)`` [N].
- ``residual``: ``alpha - alpha_rigid`` per follower, ``alpha_rigid`` the angle of rigid
  contact at the sample's cam angle (in follower 2's frame ``Theta - phi``) of that
  follower's own system on a rigid pivot (:func:`camdyn.model.geometry.rigid_angles`):
  its rms about zero and its peak-to-peak [rad], as the rocking sweep's.
- ``spectrum``: per follower, the amplitudes of the first ``harmonics`` cam harmonics of
  ``alpha_ddot`` [rad/s^2] and the frequency [Hz] and amplitude of the largest peak above
  0 Hz, as ``camdyn spectrum`` finds them on the run
  (:func:`camdyn.analysis.spectra.follower_series`, then
  :func:`camdyn.analysis.harmonics.harmonic_amplitudes` and the Hann-windowed
  :func:`camdyn.analysis.harmonics.amplitude_spectrum`) over the last whole cam turns of
  the window: all ``kept`` at a constant cam speed, else as many as it holds.
- ``stick_slip`` (two followers): per follower, the sticks, slips (break-aways) and
  sprags of the run's event log at or after the window's first sample, per cam
  revolution of the window [1/rev]; NaN where the log ran out of room (the run's
  ``events_dropped`` attribute: the log holds 64 + 16 events per period of the starting
  speed).
"""

from __future__ import annotations

import numpy as np

from camdyn.sweeps import metrics as M

__all__ = ["variables", "point_metrics", "stack", "FOLLOWERS"]

#: followers of each mechanism kind
FOLLOWERS = {"driven-cam": 1, "flexible-pivot": 1, "two-followers": 2}


def variables(kind: str, metrics, kept: int, harmonics: int = 10) -> dict:
    """name -> (extra dimensions, their sizes, dtype, units, long name) of each result
    variable of a sweep over a ``kind`` mechanism (per-follower ones over ``follower``)."""
    each = (("follower",), (2,)) if FOLLOWERS[kind] == 2 else ((), ())
    out = {}
    if "impacts" in metrics:
        out["impacts_per_revolution"] = (*each, "f8", "1/rev", "contact onsets per cam revolution")
    if "poincare" in metrics:
        dims, sizes = each[0] + ("revolution",), each[1] + (kept,)
        out["poincare_alpha"] = (dims, sizes, "f8", "rad", "follower angle once per cam revolution")
        out["poincare_alpha_dot"] = (dims, sizes, "f8", "rad/s", "follower angular velocity once per cam revolution")
    if "max_force" in metrics:
        out["max_normal_force"] = (*each, "f8", "N", "largest sampled normal contact force")
    if "regime" in metrics:
        out["regime"] = ((), (), "i1", "1", "dynamic regime (see flag_meanings)")
        out["period"] = ((), (), "i2", "rev", f"Poincare period (0: none up to {M.MAX_PERIOD})")
    if "speed_fluctuation" in metrics:
        out["coefficient_of_fluctuation"] = ((), (), "f8", "1",
                                             "cam speed's coefficient of fluctuation (max - min) / mean")
        out["mean_cam_speed"] = ((), (), "f8", "rad/s", "mean cam speed")
    if "bearing_force" in metrics:
        out["peak_bearing_force"] = ((), (), "f8", "N", "largest sampled force of the bearing on the follower")
    if "residual" in metrics:
        out["residual_rms"] = (*each, "f8", "rad", "rms of the residual response alpha - alpha_rigid")
        out["residual_peak_to_peak"] = (*each, "f8", "rad", "peak-to-peak of the residual response")
    if "spectrum" in metrics:
        dims, sizes = each[0] + ("harmonic",), each[1] + (harmonics,)
        out["harmonic_amplitude"] = (dims, sizes, "f8", "rad/s^2", "amplitude of alpha_ddot at the cam harmonics")
        out["peak_frequency"] = (*each, "f8", "Hz", "frequency of the largest spectral peak of alpha_ddot")
        out["peak_amplitude"] = (*each, "f8", "rad/s^2", "amplitude of the largest spectral peak of alpha_ddot")
    if "stick_slip" in metrics:
        for name in ("sticks", "slips", "sprags"):
            out[f"{name}_per_revolution"] = (*each, "f8", "1/rev", f"{name} of the contact per cam revolution")
    return out


def _from(values: np.ndarray, start: int) -> np.ndarray:
    """The samples from the one before the window's first (index ``start``) on; with no
    sample before it (nothing discarded) the first one stands in for it."""
    return values[start - 1:] if start > 0 else np.concatenate([values[:1], values])


def _channels(ds, kind: str, start: int) -> dict:
    """The window's channels as arrays (samples, followers) (cam ones (samples,)), from
    the sample before the window on."""
    def per(name):
        values = _from(ds[name].values, start)
        return values if values.ndim == 2 else values[:, None]
    out = {name: per(name) for name in ("alpha", "alpha_dot", "Fn", "in_contact", "cam_work")}
    if "sliding_velocity" in ds:
        out["sliding_velocity"] = per("sliding_velocity")
    out["cam_angle"] = _from(ds["cam_angle"].values, start)
    out["cam_start"] = float(ds["cam_angle"].values[0])
    if kind != "flexible-pivot":
        out["cam_speed"] = _from(ds["cam_speed"].values, start)
    else:
        out["bearing"] = np.hypot(ds["Nx"].values[start:], ds["Ny"].values[start:])
    return out


def _section(ch: dict, kind: str, kept: int, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """Poincare samples (kept, channels) of alpha, alpha_dot per follower (and the cam
    speed of a driven cam), NaN past the last whole turn; and each channel's
    peak-to-peak over the window (the yardstick of the period test)."""
    names = ["alpha", "alpha_dot"]
    columns = [ch[n][1:] for n in names]
    if "cam_speed" in ch:
        columns.append(ch["cam_speed"][1:, None])
    series = np.concatenate(columns, axis=1)
    out = np.full((kept, series.shape[1]), np.nan)
    scale = np.ptp(series, axis=0)
    if kind == "flexible-pivot":
        rows = series[::samples][:kept]
        out[:len(rows)] = rows
        return out, scale
    theta = ch["cam_angle"][1:]
    direction = 1.0 if theta[-1] >= theta[0] else -1.0
    progress = np.maximum.accumulate(direction * (theta - ch["cam_start"]) / (2.0 * np.pi))
    count = 0
    level = float(np.ceil(progress[0]))
    while count < kept and level <= progress[-1]:
        j = int(np.searchsorted(progress, level, side="left"))
        if progress[j] == level or j == 0:
            out[count] = series[j]
        else:
            f = (level - progress[j - 1]) / (progress[j] - progress[j - 1])
            out[count] = series[j - 1] + f * (series[j] - series[j - 1])
        count += 1
        level += 1.0
    return out, scale


def point_metrics(ds, kind: str, metrics, revolutions: int, discard: int, samples: int, mechanism=None,
                  harmonics: int = 10) -> dict:
    """The metrics of one run (see the module docstring): name -> value or array
    (``mechanism``, the run's :class:`~camdyn.io.mechanism_config.Mechanism`, for
    ``residual``)."""
    kept = revolutions - discard
    start = discard * samples
    ch = _channels(ds, kind, start)
    contact = ch["in_contact"] > 0.5
    work = ch["cam_work"]
    free = ~contact[:-1] & ~contact[1:]
    hidden = free & (work[1:] != work[:-1])   # a contact between two samples out of contact
    onsets = np.sum((~contact[:-1] & contact[1:]) | hidden, axis=0).astype(float)
    if kind == "flexible-pivot":
        turns = float(kept)
    else:
        turns = abs(float(ch["cam_angle"][-1] - ch["cam_angle"][1])) / (2.0 * np.pi)
    squeeze = (lambda a: a) if FOLLOWERS[kind] == 2 else (lambda a: a[0])
    out = {}
    if "impacts" in metrics:
        out["impacts_per_revolution"] = squeeze(onsets / turns)
    section, scale = _section(ch, kind, kept, samples)
    if "poincare" in metrics:
        n = FOLLOWERS[kind]
        out["poincare_alpha"] = squeeze(section[:, :n].T.copy())
        out["poincare_alpha_dot"] = squeeze(section[:, n:2 * n].T.copy())
    if "max_force" in metrics:
        out["max_normal_force"] = squeeze(np.max(ch["Fn"][1:], axis=0))
    if "regime" in metrics:
        out["regime"], out["period"] = _regime(ch, section, scale, contact, onsets)
    if "speed_fluctuation" in metrics:
        speed = ch["cam_speed"][1:]
        mean = float(np.mean(speed))
        out["coefficient_of_fluctuation"] = (float(speed.max() - speed.min()) / abs(mean)) if mean else np.nan
        out["mean_cam_speed"] = mean
    if "bearing_force" in metrics:
        out["peak_bearing_force"] = float(np.max(ch["bearing"]))
    if "residual" in metrics:
        residual = ch["alpha"][1:] - _rigid(ds, mechanism, ch["cam_angle"][1:])
        out["residual_rms"] = squeeze(np.sqrt(np.mean(residual * residual, axis=0)))
        out["residual_peak_to_peak"] = squeeze(np.ptp(residual, axis=0))
    if "spectrum" in metrics:
        whole = kept if kind == "flexible-pivot" or np.ptp(ch["cam_speed"]) == 0.0 else int(np.floor(turns + 1e-9))
        rows = [_spectrum(ds, k, whole, harmonics) for k in range(1, FOLLOWERS[kind] + 1)]
        out["harmonic_amplitude"] = squeeze(np.array([r[0] for r in rows]))
        out["peak_frequency"] = squeeze(np.array([r[1] for r in rows]))
        out["peak_amplitude"] = squeeze(np.array([r[2] for r in rows]))
    if "stick_slip" in metrics:
        t0 = float(ds["time"].values[start])
        late = ds["transition_time"].values >= t0
        who = ds["transition_follower"].values[late]
        what = ds["transition_kind"].values[late]
        for name, event in (("sticks", "stick"), ("slips", "slip"), ("sprags", "sprag")):
            counts = np.array([np.count_nonzero((who == k) & (what == event)) for k in (1, 2)], dtype=float)
            out[f"{name}_per_revolution"] = counts / turns if not ds.attrs.get("events_dropped") else counts * np.nan
    return out


def _rigid(ds, mechanism, thetas: np.ndarray) -> np.ndarray:
    """Rigid-contact follower angles [rad] (samples, followers) at the cam angles
    ``thetas`` [rad], of each follower's system on a rigid pivot in its own frame."""
    from camdyn.model import layout as L
    from camdyn.model.equilibrium import touch_angle
    from camdyn.model.geometry import rigid_angles

    systems = [mechanism.system]
    if FOLLOWERS[mechanism.spec.kind] == 2:
        systems.append(mechanism.second or mechanism.system)
    columns = []
    for i, system in enumerate(systems):
        frame = thetas - (float(ds.attrs["placement"]) if i == 1 else 0.0)
        p = L.pack(system, initial_angle=0.0)
        columns.append(rigid_angles(np.ascontiguousarray(frame), p, touch_angle(p, float(frame[0]))))
    return np.stack(columns, axis=1)


def _spectrum(ds, follower: int, window: int, harmonics: int) -> tuple[np.ndarray, float, float]:
    """Follower ``follower``'s cam-harmonic amplitudes [rad/s^2], largest peak's frequency
    [Hz] and amplitude [rad/s^2] over the last ``window`` whole cam turns (NaN for none)."""
    from camdyn.analysis.harmonics import amplitude_spectrum, harmonic_amplitudes
    from camdyn.analysis.spectra import follower_series

    if window < 1:
        return np.full(harmonics, np.nan), np.nan, np.nan
    series = follower_series(ds, follower if "follower" in ds.dims else None, window)
    amplitudes = harmonic_amplitudes(series, "alpha_ddot", range(1, harmonics + 1), revolutions=window)
    freq, amp = amplitude_spectrum(series, "alpha_ddot", revolutions=window)
    peak = 1 + int(np.argmax(amp[1:]))
    return amplitudes, float(freq[peak]), float(amp[peak])


def _regime(ch: dict, section: np.ndarray, scale: np.ndarray, contact: np.ndarray,
            onsets: np.ndarray) -> tuple[int, int]:
    """The regime code (:data:`camdyn.sweeps.metrics.REGIMES`) and Poincare period (as
    the rocking sweep's, also while contact is kept)."""
    rows = section[np.all(np.isfinite(section), axis=1)]
    period = int(M.poincare_period(rows[None], scale[None] + 1e-15)[0]) if len(rows) >= 2 else 0
    if np.all(contact[1:]) and not np.any(onsets):
        vr = ch.get("sliding_velocity")
        reversal = vr is not None and bool(np.any((np.min(vr[1:], axis=0) < 0.0) & (np.max(vr[1:], axis=0) > 0.0)))
        return (1 if reversal else 0), period
    return (2 if period > 0 else 3), period


def stack(rows: list, kind: str, metrics, kept: int, harmonics: int = 10) -> dict:
    """One array per variable over a chunk's points (None rows: failed, NaN; regime -1)."""
    out = {}
    for name, (_, sizes, dtype, _, _) in variables(kind, metrics, kept, harmonics).items():
        fill = {"f8": np.nan, "i1": -1, "i2": 0}[dtype]
        array = np.full((len(rows),) + tuple(sizes), fill, dtype=dtype)
        for i, row in enumerate(rows):
            if row is not None:
                array[i] = row[name]
        out[name] = array
    return out
