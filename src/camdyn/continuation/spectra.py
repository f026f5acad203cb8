"""The cam harmonics of a periodic orbit's output channels: the amplitudes of harmonics
1..H of the forcing (cam) frequency of each channel, from equally spaced samples over one
orbit period (a discrete Fourier transform; the thesis identifies friction from those of
the follower's acceleration, tables 4.4-4.7).

For samples ``v_j = v(t_0 + j kT / N)``, ``j = 0..N-1``, of an orbit of ``k`` forcing
periods ``T``, the cam harmonic ``h`` is the DFT bin ``h k`` and its amplitude (of
``a cos + b sin``) is ``sqrt(a^2 + b^2) = 2 |V_{hk}| / N`` (exact for a band-limited
signal with ``N > 2 h k``; otherwise with the aliasing of the harmonics above ``N / 2``).
"""

from __future__ import annotations

import numpy as np

from camdyn.errors import ParameterError
from camdyn.model.outputs import CHANNELS, derived
from camdyn.systems.traits import has_cam_channels

__all__ = ["HARMONIC_CHANNELS", "cam_harmonics", "channel_harmonics", "channel_units"]

#: The channels whose cam harmonics a branch's points carry by default.
HARMONIC_CHANNELS = ("alpha_ddot", "Fn", "Nx", "Ny")
_COLUMNS = {name: i for i, (name, _, _) in enumerate(CHANNELS)}


def channel_units(names=HARMONIC_CHANNELS) -> dict[str, str]:
    """The unit of each named cam-follower channel (:data:`camdyn.model.outputs.CHANNELS`)."""
    units = {name: unit for name, unit, _ in CHANNELS}
    unknown = [n for n in names if n not in units]
    if unknown:
        raise ParameterError(f"no output channel {unknown[0]!r}; channels: {', '.join(units)}")
    return {n: units[n] for n in names}


def cam_harmonics(values, harmonics: int, periods: int = 1) -> list[float]:
    """Amplitudes of the cam harmonics 1..``harmonics`` of periodic samples ``values``
    (N,), equally spaced over one orbit period of ``periods`` forcing periods, the end
    point excluded, in the unit of ``values`` (``2 |V_{hk}| / N``)."""
    v = np.asarray(values, dtype=float)
    if harmonics < 1 or 2 * harmonics * periods >= v.size:
        raise ParameterError(f"{v.size} samples resolve fewer than {harmonics} cam harmonics of a period-{periods} "
                             "orbit")
    spectrum = np.fft.rfft(v)
    return [float(2.0 * abs(spectrum[h * periods]) / v.size) for h in range(1, harmonics + 1)]


def channel_harmonics(system_id: int, p: np.ndarray, times: np.ndarray, states: np.ndarray, modes: np.ndarray,
                      harmonics: int, periods: int = 1, names=HARMONIC_CHANNELS) -> dict[str, list[float]] | None:
    """``{channel: [amplitude of cam harmonic 1..H]}`` (each in its channel's unit,
    :func:`channel_units`) of the cam-follower's channels computed from an orbit's samples:
    ``times`` (N,) [s] over one orbit period, end point excluded, ``states`` (N, >= 3)
    (alpha [rad], alpha_dot [rad/s], ...), ``modes`` (N, mode size) and the parameter
    vector ``p``. None for another system (its channels are not the cam-follower's)."""
    if not has_cam_channels(system_id):
        return None
    channel_units(names)
    values = derived(np.asarray(times, float), np.ascontiguousarray(states[:, :3], dtype=float),
                     np.ascontiguousarray(modes, dtype=float), p)
    return {n: cam_harmonics(values[:, _COLUMNS[n]], harmonics, periods) for n in names}
