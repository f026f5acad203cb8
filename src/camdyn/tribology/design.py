"""Experiment design for friction identification (thesis 4.4, figs 4.4 and 4.10).

Over a grid of runout ratio ``e/a`` (or axis ratio ``b/a`` of an elliptic cam) and cam
speed, inverse kinematics checks the design criteria of the chapter 4 experiment:

1. the follower keeps contact (the required normal force stays positive);
2. the sliding velocity keeps one sign (Coulomb friction has one direction);
3. the first five cam harmonics lie well below the contact resonance
   (``5 f_cam <= harmonic_margin * f_n``, stiffness-controlled response);
4. optionally, the lubrication regime at the thinnest film of the revolution is the
   one asked for (boundary, mixed or EHL).

The recommended operating point is the admissible one with the largest first-harmonic
acceleration (the strongest signal for the estimator) whose smallest normal force keeps
a margin of ``contact_margin`` times the mean normal force against loss of contact.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
import xarray as xr

from camdyn.analysis.kinematics import inverse_kinematics
from camdyn.errors import CamdynError, ParameterError
from camdyn.model.equilibrium import static_equilibrium
from camdyn.params.system import System
from camdyn.tribology import contact_conditions, lubrication_regime

__all__ = ["design_map", "check_design_size", "AXES", "MAX_POINTS"]

#: Grid axes: name -> (dotted parameter set from the ratio, long name).
AXES = {
    "runout": "runout ratio e/a",
    "axis_ratio": "axis ratio b/a",
}


#: Most grid points a design map may have [-]: each point is an inverse-kinematics
#: revolution and a contact analysis, some milliseconds; 10^5 of them take minutes.
MAX_POINTS = 10 ** 5
#: Memory one grid point takes in the map's layers and values, with room [B].
BYTES_PER_POINT = 64


def check_design_size(points: float) -> None:
    """Refuse, before anything is allocated, a design grid of more than
    :data:`MAX_POINTS` points (:func:`camdyn.simulation.limits.check_request`)."""
    from camdyn.simulation import limits

    limits.check_request("the design grid", points, BYTES_PER_POINT, limit=MAX_POINTS, unit="points")


def _system_at(system: System, axis: str, ratio: float) -> System:
    """The rig with runout ``e = ratio a`` or semi-minor axis ``b = ratio a`` [m]."""
    a = system.cam.semi_major
    if axis == "runout":
        return system.with_values(**{"cam.runout": ratio * a})
    return system.with_values(**{"cam.semi_minor": ratio * a})


def design_map(system: System, axis: str, ratios, speeds, lubricant=None, roughness="ground",
               regime: str | None = None, harmonic_margin: float = 0.2, contact_margin: float = 0.2,
               points: int = 256, progress: Callable[[int, int], None] | None = None) -> xr.Dataset:
    """Design criteria over ``ratios`` x ``speeds``.

    Parameters
    ----------
    system : System
        The rig; its cam runout (for ``axis="axis_ratio"``) or axis ratio (for
        ``axis="runout"``) stays as given.
    axis : {"runout", "axis_ratio"}
        Which ratio the first grid axis varies: ``e/a`` or ``b/a``.
    ratios : array_like
        Values of that ratio [-].
    speeds : array_like
        Cam speeds [Hz].
    lubricant : str or Lubricant, optional
        Adds the lambda ratio and regime (see :func:`camdyn.tribology.contact_conditions`).
    regime : {"boundary", "mixed", "EHL"}, optional
        Required regime; None accepts any.
    harmonic_margin : float
        Largest ``5 f_cam / f_n`` [-].
    contact_margin : float
        Smallest ``min Fn / mean Fn`` of the recommended point [-].
    points : int
        Samples per revolution of the inverse kinematics [-].
    progress : callable, optional
        Called as ``progress(done, total)`` after each grid point.

    Returns
    -------
    xarray.Dataset
        Over (``ratio``, ``speed``): ``contact_kept``, ``sliding_reversal``,
        ``harmonics_clear``, ``regime_ok``, ``admissible`` (bool), ``min_contact_force``
        and ``mean_contact_force`` [N], ``first_harmonic`` [rad/s^2], ``lambda_min`` [-];
        over ``ratio``: ``natural_frequency`` [Hz]. Attributes name the axis, the
        criteria and the recommended point (``recommended_ratio``, ``recommended_speed``;
        NaN when no point is admissible).
    """
    ratios, speeds = _checked_grid(axis, ratios, speeds, regime)
    check_design_size(ratios.size * speeds.size)
    for name, margin, low in (("harmonic_margin", harmonic_margin, "positive"),
                              ("contact_margin", contact_margin, "non-negative")):
        if isinstance(margin, bool) or not isinstance(margin, (int, float, np.integer, np.floating)) \
                or not (math.isfinite(margin) and (margin > 0 if low == "positive" else margin >= 0)):
            raise ParameterError(f"{name} must be a {low}, finite ratio, got {margin!r}")
    shape = (ratios.size, speeds.size)
    layers = {name: np.zeros(shape, bool) for name in ("contact_kept", "sliding_reversal", "harmonics_clear",
                                                      "regime_ok")}
    values = {name: np.full(shape, np.nan) for name in ("min_contact_force", "mean_contact_force",
                                                       "first_harmonic", "lambda_min")}
    fn_hz = np.full(ratios.size, np.nan)
    total, done = ratios.size * speeds.size, 0
    for i, ratio in enumerate(ratios):
        try:
            sys_i = _system_at(system, axis, float(ratio))
            fn_hz[i] = static_equilibrium(sys_i).natural_frequency
        except CamdynError:
            sys_i = None
        for j, speed in enumerate(speeds):
            done += 1
            if sys_i is not None:
                try:
                    _point(sys_i, float(speed), fn_hz[i], i, j, layers, values, lubricant, roughness, regime,
                           harmonic_margin, points)
                except CamdynError:
                    pass  # impossible geometry: every criterion stays False / NaN
            if progress:
                progress(done, total)
    admissible = (layers["contact_kept"] & ~layers["sliding_reversal"] & layers["harmonics_clear"]
                  & layers["regime_ok"])
    rec_ratio, rec_speed = _recommended(admissible, values, ratios, speeds, contact_margin)
    ds = _dataset(ratios, speeds, axis, layers, values, admissible, fn_hz, harmonic_margin)
    ds.attrs.update(axis=axis, harmonic_margin=harmonic_margin, contact_margin=contact_margin,
                    regime=regime or "any", lubricant=str(getattr(lubricant, "name", lubricant) or "none"),
                    recommended_ratio=rec_ratio, recommended_speed=rec_speed, system=system.name)
    return ds


def _checked_grid(axis: str, ratios, speeds, regime: str | None) -> tuple[np.ndarray, np.ndarray]:
    """The grid's ratios [-] and speeds [Hz] as arrays, after checking the arguments of
    :func:`design_map`."""
    if axis not in AXES:
        raise ParameterError(f"axis must be one of {sorted(AXES)}, got {axis!r}")
    ratios = np.atleast_1d(np.asarray(ratios, float))
    speeds = np.atleast_1d(np.asarray(speeds, float))
    if ratios.size == 0 or speeds.size == 0 or not (np.all(np.isfinite(ratios)) and np.all(speeds > 0)):
        raise ParameterError("the design grid needs finite ratios and positive speeds")
    if axis == "axis_ratio" and (np.any(ratios <= 0) or np.any(ratios > 1)):
        raise ParameterError("axis ratios b/a must lie in (0, 1]")
    if axis == "runout" and (np.any(ratios < 0) or np.any(ratios >= 1)):
        raise ParameterError(f"runout ratios e/a must lie in [0, 1): the cam's pivot must be inside the cam, "
                             f"got {', '.join(f'{r:g}' for r in ratios if not 0 <= r < 1)}")
    for name, grid, unit in (("ratios", ratios, ""), ("speeds", speeds, " Hz")):
        if grid.size > 1 and not np.all(np.diff(grid) > 0):
            raise ParameterError(f"the design {name} must increase, each value once (START:STOP with START < "
                                 f"STOP), got {grid[0]:g}{unit} ... {grid[-1]:g}{unit}")
    if regime not in (None, "boundary", "mixed", "EHL"):
        raise ParameterError(f"regime must be boundary, mixed or EHL, got {regime!r}")
    return ratios, speeds


def _recommended(admissible: np.ndarray, values: dict, ratios: np.ndarray, speeds: np.ndarray,
                 contact_margin: float) -> tuple[float, float]:
    """The recommended ratio [-] and speed [Hz]: the admissible point with the largest
    first harmonic whose normal force keeps the margin (NaN, NaN without one)."""
    score = np.where(admissible & (values["min_contact_force"] >= contact_margin * values["mean_contact_force"]),
                     values["first_harmonic"], -np.inf)
    if np.isfinite(score).any():
        bi, bj = np.unravel_index(np.argmax(score), admissible.shape)
        return float(ratios[bi]), float(speeds[bj])
    return math.nan, math.nan


def _dataset(ratios, speeds, axis, layers, values, admissible, fn_hz, harmonic_margin) -> xr.Dataset:
    """The criteria of :func:`design_map` as a Dataset over (``ratio``, ``speed``)."""
    dims = ("ratio", "speed")
    ds = xr.Dataset(coords={"ratio": ("ratio", ratios, {"units": "1", "long_name": AXES[axis]}),
                            "speed": ("speed", speeds, {"units": "Hz", "long_name": "cam speed"})})
    long = {"contact_kept": "follower keeps contact", "sliding_reversal": "sliding velocity reverses",
            "harmonics_clear": f"5 f_cam <= {harmonic_margin:g} f_n", "regime_ok": "lubrication regime as asked"}
    for name, arr in layers.items():
        ds[name] = (dims, arr, {"long_name": long[name]})
    ds["admissible"] = (dims, admissible, {"long_name": "every design criterion met"})
    units = {"min_contact_force": ("N", "smallest required normal force"),
             "mean_contact_force": ("N", "mean normal force"),
             "first_harmonic": ("rad/s^2", "alpha_ddot amplitude at the cam frequency"),
             "lambda_min": ("1", "smallest lambda ratio over a revolution")}
    for name, arr in values.items():
        ds[name] = (dims, arr, {"units": units[name][0], "long_name": units[name][1]})
    ds["natural_frequency"] = ("ratio", fn_hz, {"units": "Hz", "long_name": "linearized natural frequency"})
    return ds


def _point(system, speed, natural_hz, i, j, layers, values, lubricant, roughness, regime, margin, points):
    """Evaluate the criteria at one grid point (``speed`` [Hz], ``natural_hz`` [Hz]) into
    ``layers[name][i, j]`` and ``values[name][i, j]``."""
    ik = inverse_kinematics(system, speed=speed, points=points)
    fn = ik["Fn"].values
    acc = ik["alpha_ddot"].values
    layers["contact_kept"][i, j] = bool(ik.attrs["contact_kept"])
    layers["sliding_reversal"][i, j] = bool(ik.attrs["sliding_reversal"])
    layers["harmonics_clear"][i, j] = bool(5.0 * speed <= margin * natural_hz)
    values["min_contact_force"][i, j] = fn.min()
    values["mean_contact_force"][i, j] = fn.mean()
    values["first_harmonic"][i, j] = 2.0 * abs(np.fft.rfft(acc)[1]) / acc.size
    if lubricant is not None and fn.min() > 0:
        cc = contact_conditions(system, speed, lubricant, roughness, points=points, kinematics=ik)
        lam = float(np.nanmin(cc["lambda_ratio"].values))
        values["lambda_min"][i, j] = lam
        layers["regime_ok"][i, j] = regime is None or str(lubrication_regime(lam)) == regime
    else:
        layers["regime_ok"][i, j] = regime is None
