"""Regime maps over two parameters (thesis fig 2.9, 4.5.1): brute-force simulation of
every grid point (a sweep) beside the inverse-kinematics prediction.

Regions, from simulation (the sweep's ``regime`` and ``impacts_per_revolution``): contact
kept; contact kept with the sliding velocity reversing; periodic impacts with k impacts
per revolution (``k`` may be a fraction: 1/2 is one impact every other revolution);
irregular impacts. From inverse kinematics, at the same points: contact kept, contact
kept with ``vr`` reversal, contact lost; and, when one axis is the cam speed, the
loss-of-contact speed as a curve over the other axis. :func:`boundary_agreement` counts
where the two agree on each side of the boundary.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from camdyn.analysis.kinematics import inverse_kinematics, loss_of_contact_speed
from camdyn.errors import CamdynError, ParameterError
from camdyn.io.atomic import atomic_output
from camdyn.io.netcdf import write_netcdf
from camdyn.sweeps.spec import SweepSpec

__all__ = ["KINEMATIC_REGIMES", "kinematic_regimes", "loss_of_contact_curve", "boundary_agreement",
           "regime_map", "parse_curve", "map_curves"]

#: inverse-kinematics regime codes
KINEMATIC_REGIMES = {0: "contact kept", 1: "contact kept, vr reversal", 2: "contact lost", -1: "failed"}


def _point_system(spec: SweepSpec, index: int):
    """The cam-follower of point ``index``: over a mechanism, its follower 1 with the
    point's ``system.`` values (the rigid pivot at the prescribed starting speed, the
    reference inverse kinematics gives)."""
    return _with_values(spec, spec.point_values(index))


def _with_values(spec: SweepSpec, values: dict):
    if not spec.mechanism:
        return spec.base_system().with_values(**values)
    own = {key[len("system."):]: value for key, value in values.items() if key.startswith("system.")}
    return spec.base_system().with_values(**own)


def kinematic_regimes(spec: SweepSpec, points: int = 512) -> xr.DataArray:
    """Inverse-kinematics regime (:data:`KINEMATIC_REGIMES`) at every point of ``spec``."""
    codes = np.full(spec.points, -1, dtype=np.int8)
    for i in range(spec.points):
        try:
            ik = inverse_kinematics(_point_system(spec, i), points=points)
        except CamdynError:
            continue
        codes[i] = 2 if not ik.attrs["contact_kept"] else (1 if ik.attrs["sliding_reversal"] else 0)
    dims = [d for d, _ in spec.dimensions]
    return xr.DataArray(codes.reshape(spec.shape), dims=dims,
                        attrs={"long_name": "regime by inverse kinematics", "units": "1",
                               "flag_values": list(KINEMATIC_REGIMES),
                               "flag_meanings": " ".join(v.replace(" ", "_").replace(",", "")
                                                         for v in KINEMATIC_REGIMES.values())})


def loss_of_contact_curve(spec: SweepSpec, points: int = 512) -> xr.DataArray | None:
    """Loss-of-contact speed [Hz] along the other axis, when one axis is ``motion.speed``
    (and the map has two dimensions); None otherwise."""
    dims = [d for d, _ in spec.dimensions]
    keys = {v.dimension: v.key for v in spec.vary}
    speed_dims = [d for d in dims if keys.get(d) in ("motion.speed", "system.motion.speed")]
    if len(dims) != 2 or len(speed_dims) != 1:
        return None
    other = [d for d in dims if d != speed_dims[0]][0]
    values = [v for v in spec.vary if v.dimension == other]
    curve = []
    for j in range(len(values[0].values)):
        system = _with_values(spec, {v.key: v.values[j] for v in values})
        try:
            curve.append(loss_of_contact_speed(system, points=points))
        except CamdynError:
            curve.append(math.nan)
    return xr.DataArray(np.array(curve), dims=(other,),
                        attrs={"long_name": "loss-of-contact speed by inverse kinematics", "units": "Hz"})


def boundary_agreement(ds: xr.Dataset) -> dict:
    """Where simulation and inverse kinematics agree on contact kept against lost.

    Returns counts: ``kept`` / ``kept_agree`` (points inverse kinematics keeps in contact,
    and how many of them the simulation kept: regime 0 or 1), ``lost`` / ``lost_agree``
    (the same for contact lost: regime 2 or 3); failed points are left out.
    """
    ik = ds["kinematic_regime"].values
    sim = ds["regime"].values
    valid = (ik >= 0) & (sim >= 0)
    ik_kept = valid & (ik <= 1)
    ik_lost = valid & (ik == 2)
    sim_kept = sim <= 1
    return {"kept": int(ik_kept.sum()), "kept_agree": int((ik_kept & sim_kept).sum()),
            "lost": int(ik_lost.sum()), "lost_agree": int((ik_lost & ~sim_kept).sum())}


def regime_map(spec: SweepSpec, **run) -> xr.Dataset:
    """Run the sweep of ``spec`` (``run``: keywords of :func:`camdyn.sweeps.run_sweep`), add
    the inverse-kinematics regime and loss-of-contact curve, and rewrite the result file."""
    from camdyn.sweeps import run_sweep
    needed = {"regime", "impacts"} if spec.mechanism else {"regime", "impacts", "residual"}
    if not needed <= set(spec.metrics):
        raise CamdynError(f"a regime map needs the metrics {sorted(needed)}")
    ds = run_sweep(spec, **run)
    ds = ds.load()
    ds.close()
    ds["kinematic_regime"] = kinematic_regimes(spec)
    curve = loss_of_contact_curve(spec)
    if curve is not None:
        ds["loss_of_contact_speed"] = curve
    ds.attrs.update({f"agreement_{k}": v for k, v in boundary_agreement(ds).items()})
    with atomic_output(spec.output, int(ds.nbytes)) as tmp:
        write_netcdf(ds, tmp)   # built in memory: a full disk cannot crash HDF5
    return ds


def parse_curve(text: str, spec: SweepSpec) -> tuple[str, float]:
    """``KIND=GUESS`` of ``camdyn map --curve`` -> (kind, guess in the second axis's SI
    unit). The curve's parameter is the map's second axis, traced over its first;
    ``GUESS`` is where the bifurcation lies at the first axis's first value."""
    from camdyn.continuation.curves import CURVE_KINDS
    from camdyn.params.config import convert_value
    kind, sep, guess = text.partition("=")
    kind = kind.strip()
    if not sep or kind not in CURVE_KINDS or not guess.strip():
        raise ParameterError(f"--curve: expected KIND=VALUE with KIND one of {', '.join(CURVE_KINDS)}, got {text!r}")
    if len(spec.dimensions) != 2:
        raise ParameterError("--curve needs a map over two parameters")
    key = spec.vary[1].key
    return kind, float(convert_value(key, guess.strip(), {}))


def map_curves(spec: SweepSpec, ds: xr.Dataset, requests: list[tuple[str, float]], progress=None) -> xr.Dataset:
    """Follow each ``(kind, guess)`` of ``requests`` (:func:`parse_curve`) by two-parameter
    continuation (:func:`camdyn.continuation.curves.system_curve`) over the map's first
    axis, the bifurcation's parameter being the second axis (searched within two grid
    spacings of each prediction); add each as ``<kind>_curve`` along the first axis (NaN
    where the curve ended early, the reason in its ``stopped`` attribute) and rewrite the
    result file."""
    from camdyn.continuation.curves import system_curve
    first, second = spec.vary[0], spec.vary[1]
    grid = np.asarray(second.values, dtype=float)
    window = 2.0 * float(np.min(np.abs(np.diff(grid)))) if grid.size > 1 else 0.1 * abs(float(grid[0]))
    for kind, guess in requests:
        curve = system_curve(spec.base_system(), kind, second.key, first.key, first.values, guess, window,
                             progress=progress)
        values = np.full(len(first.values), np.nan)
        values[:len(curve.points)] = curve.parameters
        ds[f"{kind.replace('-', '_')}_curve"] = xr.DataArray(
            values, dims=[first.dimension],
            attrs={"long_name": f"{kind} by two-parameter continuation", "units": second.unit,
                   "curve_kind": kind, "stopped": curve.stopped})
    with atomic_output(spec.output, int(ds.nbytes)) as tmp:
        write_netcdf(ds, tmp)   # built in memory: a full disk cannot crash HDF5
    return ds
