"""Figures of simulation results (matplotlib, headless)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.backend_bases import FigureCanvasBase  # noqa: E402

from camdyn.errors import OutputError  # noqa: E402
from camdyn.io.atomic import atomic_output  # noqa: E402


def _label(da: xr.DataArray) -> str:
    return f"{da.attrs.get('long_name', da.name)} [{da.attrs.get('units', '-')}]"


def figure_format(path: str | Path) -> str:
    """The image format of a figure path, from its suffix (png, pdf, svg, ...).

    Raises
    ------
    OutputError
        If matplotlib cannot write that format; call this before a long computation.
    """
    suffix = Path(path).suffix.lower().lstrip(".")
    formats = FigureCanvasBase.get_supported_filetypes()
    if suffix not in formats:
        raise OutputError(f"cannot write the figure {path}: unknown image format {suffix or '(no suffix)'!r}; "
                          f"use one of {', '.join(sorted(formats))}")
    return suffix


def _save(fig, path) -> Path:
    fig.tight_layout()
    path = Path(path)
    fmt = figure_format(path)
    try:
        with atomic_output(path) as tmp:
            fig.savefig(tmp, dpi=110, format=fmt)
    finally:
        plt.close(fig)
    return path


def plot_time_history(ds: xr.Dataset, path: str | Path, revolutions: float = 3.0) -> Path:
    """Plot alpha, alpha_ddot, the contact force and the pivot reactions over the last
    ``revolutions`` cam periods; write a PNG to ``path``."""
    t = ds["time"].values
    speed = float(ds.attrs.get("speed_hz", 0.0)) or None
    t0 = t[-1] - revolutions / speed if speed else t[0]
    sel = ds.sel(time=slice(max(t0, t[0]), None))
    fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    tt = sel["time"].values
    axes[0].plot(tt, np.degrees(sel["alpha"].values), color="C0")
    axes[0].set_ylabel("follower angle alpha [deg]")
    axes[1].plot(tt, sel["alpha_ddot"].values, color="C1")
    axes[1].set_ylabel(_label(sel["alpha_ddot"]))
    axes[2].plot(tt, sel["Fn"].values, color="C2", label="Fn")
    axes[2].plot(tt, sel["Ff"].values, color="C3", label="Ff")
    axes[2].set_ylabel("contact forces [N]")
    axes[2].legend(loc="upper right")
    axes[3].plot(tt, sel["Nx"].values, label="Nx")
    axes[3].plot(tt, sel["Ny"].values, label="Ny")
    axes[3].set_ylabel("pivot reaction [N]")
    axes[3].legend(loc="upper right")
    axes[3].set_xlabel("time [s]")
    if "impact_time" in ds and ds.sizes.get("impact", 0):
        for ti in ds["impact_time"].values:
            if ti >= tt[0]:
                for ax in axes:
                    ax.axvline(ti, color="0.8", lw=0.5, zorder=0)
    fig.suptitle(ds.attrs.get("title", "camdyn simulation"))
    return _save(fig, path)


def plot_spectrum(ds: xr.Dataset, path: str | Path, variable: str = "alpha_ddot",
                  harmonics: int = 10, revolutions: int | None = None, resonances=()) -> Path:
    """Amplitude spectrum of ``variable`` over whole revolutions: cam harmonics marked (grey),
    the linearized natural frequency (red dashed) and ``resonances`` [Hz] (triangles)."""
    from camdyn.analysis.harmonics import amplitude_spectrum
    freq, amp = amplitude_spectrum(ds, variable, revolutions)
    speed = float(ds.attrs.get("speed_hz", 0.0))
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.semilogy(freq, np.maximum(amp, 1e-12), lw=0.8, label=variable)
    if speed:
        for k in range(1, harmonics + 1):
            ax.axvline(k * speed, color="0.8", lw=0.5, zorder=0)
    for f in resonances:
        ax.plot([f], [np.interp(f, freq, amp)], "v", color="C3", ms=6)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(f"|{variable}| [{ds[variable].attrs.get('units', '-')}]")
    fn = float(ds.attrs.get("natural_frequency_Hz", 0.0) or 0.0)
    if fn == fn and fn > 0:
        ax.axvline(fn, color="C3", lw=0.8, ls="--", label=f"linearized natural frequency {fn:.0f} Hz")
    ax.legend(loc="upper right", fontsize=8)
    upper = max(40 * speed, 1.5 * fn if fn == fn else 0.0) if speed else freq[-1]
    ax.set_xlim(0, min(freq[-1], upper))
    return _save(fig, path)


def plot_design_map(ds: xr.Dataset, path: str | Path) -> Path:
    """Regime map of a design study (figs 4.4, 4.10): loss of contact, sliding reversal,
    harmonics too close to resonance, wrong lubrication regime, and the admissible
    window, with the recommended point starred."""
    from matplotlib.colors import ListedColormap

    code = np.full(ds["admissible"].shape, 4, dtype=float)           # admissible
    code[~ds["regime_ok"].values] = 3
    code[~ds["harmonics_clear"].values] = 2
    code[ds["sliding_reversal"].values] = 1
    code[~ds["contact_kept"].values] = 0
    names = ["loss of contact", "vr reversal", "harmonics near resonance", "other lubrication regime",
             "admissible"]
    colours = ["#d62728", "#ff7f0e", "#7f7f7f", "#bcbd22", "#2ca02c"]
    fig, ax = plt.subplots(figsize=(7, 5))
    ratio = ds["ratio"].values
    speed = ds["speed"].values
    ax.pcolormesh(ratio, speed, code.T, cmap=ListedColormap(colours), vmin=-0.5, vmax=4.5, shading="nearest")
    for c, n in zip(colours, names):
        ax.plot([], [], "s", color=c, label=n, markersize=9)
    if np.isfinite(ds.attrs.get("recommended_ratio", np.nan)):
        ax.plot(ds.attrs["recommended_ratio"], ds.attrs["recommended_speed"], "*", color="white",
                markeredgecolor="black", markersize=16, label="recommended")
    ax.set_xlabel(_label(ds["ratio"]))
    ax.set_ylabel(_label(ds["speed"]))
    ax.set_title(f"design map, {ds.attrs.get('system', '')}")
    ax.legend(fontsize=7, loc="upper right", framealpha=0.9)
    return _save(fig, path)


def plot_contact_conditions(ds: xr.Dataset, path: str | Path) -> Path:
    """Hertz pressure, velocities and slide-to-roll ratio (fig 4.5), and the lambda ratio,
    over one revolution."""
    theta = np.degrees(ds["cam_angle"].values)
    rows = 4 if "lambda_ratio" in ds else 3
    fig, axes = plt.subplots(rows, 1, figsize=(7, 2.2 * rows + 1), sharex=True)
    axes[0].plot(theta, ds["peak_pressure"].values / 1e9, color="C0")
    axes[0].set_ylabel("peak pressure [GPa]")
    axes[1].plot(theta, ds["sliding_velocity"].values, label="sliding vr")
    axes[1].plot(theta, ds["sum_velocity"].values, label="sum ve")
    axes[1].set_ylabel("velocity [m/s]")
    axes[1].legend(fontsize=8)
    axes[2].plot(theta, ds["slide_to_roll"].values, color="C2")
    axes[2].set_ylabel("slide-to-roll vr/ve [-]")
    if "lambda_ratio" in ds:
        axes[3].plot(theta, ds["lambda_ratio"].values, color="C3")
        for level in (1.0, 3.0):
            axes[3].axhline(level, color="k", lw=0.6, ls="--")
        axes[3].set_ylabel("lambda ratio [-]")
        axes[3].set_title(f"{ds.attrs.get('lubricant', '')}: boundary < 1 < mixed < 3 < EHL", fontsize=8)
    axes[-1].set_xlabel("cam angle [deg]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    return _save(fig, path)


def plot_accelerance(frequency, response, estimate, path: str | Path) -> Path:
    """Accelerance magnitude near a peak with its half-power band (fig 4.7)."""
    fig, ax = plt.subplots(figsize=(7, 4))
    fn = estimate.natural_frequency
    width = max(8 * (estimate.upper - estimate.lower), 20 * estimate.resolution)
    sel = (frequency > fn - width) & (frequency < fn + width)
    ax.plot(frequency[sel], np.abs(response[sel]), ".-", color="C0", label="|A(f)|")
    ax.axhline(estimate.peak / np.sqrt(2), color="k", ls="--", lw=0.7, label="half power")
    ax.axvspan(estimate.lower, estimate.upper, color="C1", alpha=0.2,
               label=f"zeta = {100 * estimate.damping_ratio:.2f} %")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("accelerance [1/kg]")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return _save(fig, path)


def plot_impact_fit(estimate, path: str | Path, impact: int = 0) -> Path:
    """Contact force of one impact, measured (force balance, eq 3.21) against simulation
    S1 at the estimate: over time, and as a hysteresis loop over the penetration (figs
    3.4, 3.7, 3.8)."""
    prob = estimate.problem
    k = int(np.clip(impact, 0, prob.count - 1))
    res = prob.residues(np.array([k]), np.array([estimate.beta]), np.array([estimate.exponent]))
    u = prob.offsets[k] * 1e6
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    axes[0].plot(u, prob.force[k], "o", ms=3, color="C0", label="measured (force balance)")
    axes[0].plot(u, res["force"][0], "-", color="C3", label="simulation S1 at the estimate")
    axes[0].set_xlabel("time after onset [us]")
    axes[0].set_ylabel("normal contact force [N]")
    axes[0].legend()
    axes[1].plot(prob.penetration[k] * 1e6, prob.force[k], "o", ms=3, color="C0", label="measured")
    axes[1].plot(res["penetration"][0] * 1e6, res["force"][0], "-", color="C3", label="simulation S1")
    axes[1].set_xlabel("penetration [um]")
    axes[1].set_ylabel("normal contact force [N]")
    axes[1].set_title(f"beta = {estimate.beta:.4g} {estimate.beta_units}, n = {estimate.exponent:.4g}")
    axes[1].legend()
    return _save(fig, path)


def plot_residue_landscape(landscape: xr.DataArray, estimate, path: str | Path) -> Path:
    """Mean |Lambda| per impact over (n, beta), with the estimate and the bootstrap
    replicates: the (beta, n) valley of thesis 3.7."""
    ns = landscape["exponent"].values
    beta = landscape["beta"].values
    fig, ax = plt.subplots(figsize=(7, 5))
    nn = np.repeat(ns[:, None], beta.shape[1], axis=1)
    mesh = ax.pcolormesh(nn, np.log10(beta), np.log10(landscape.values + 1e-16), shading="auto", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label=f"log10 {landscape.attrs.get('long_name', 'residue')}")
    if estimate.bootstrap.size:
        ax.plot(estimate.bootstrap[:, 1], np.log10(estimate.bootstrap[:, 0]), ".", color="w", ms=3,
                label="bootstrap replicates")
    ax.plot([estimate.exponent], [np.log10(estimate.beta)], "r*", ms=12, label="estimate")
    ax.set_xlabel("damping exponent n [-]")
    ax.set_ylabel("log10 beta [N s m^-(n+1)]")
    ax.legend(loc="upper left")
    return _save(fig, path)


def plot_restitution(estimate, path: str | Path) -> Path:
    """Coefficient of restitution of each impact against its approach velocity, with the
    fitted ``xi = 1 - gamma v_a`` (figs 3.9, 3.10)."""
    v = estimate.approach_velocity
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.plot(v, estimate.restitution, "o", ms=4, label="impacts")
    grid = np.linspace(0.0, max(v.max() * 1.1, 1e-3), 50)
    ax.plot(grid, 1.0 - estimate.gamma * grid, "-", color="C3",
            label=f"xi = 1 - gamma v_a, gamma = {estimate.gamma:.4g} s/m")
    ax.set_xlabel("approach velocity v_a [m/s]")
    ax.set_ylabel("coefficient of restitution xi [-]")
    ax.legend()
    return _save(fig, path)


_REGIME_COLOURS = {-1: "#000000", 0: "#2ca02c", 1: "#ff7f0e", 2: "#1f77b4", 3: "#d62728"}


def plot_sweep(ds: xr.Dataset, path: str | Path) -> Path:
    """Figure of a sweep result (:func:`camdyn.sweeps.run_sweep`).

    One swept dimension: the bifurcation diagram (Poincare alpha against the parameter),
    impacts per revolution and the residual rms, as far as the metrics hold them. Two or
    more: maps of the regime and of impacts per revolution over the first two swept
    dimensions (later dimensions at their first value).
    """
    from matplotlib.colors import ListedColormap

    dims = [d for d in ds["status"].dims]
    first = ds[dims[0]]
    if len(dims) == 1:
        panels = [n for n in ("poincare_alpha", "impacts_per_revolution", "residual_rms", "max_normal_force")
                  if n in ds]
        fig, axes = plt.subplots(len(panels), 1, figsize=(7, 2.2 * len(panels) + 0.6), sharex=True, squeeze=False)
        for ax, name in zip(axes[:, 0], panels):
            da = ds[name]
            if name == "poincare_alpha":
                x = np.repeat(first.values, da.sizes["revolution"])
                ax.plot(x, da.values.ravel(), ",", color="k", alpha=0.6)
                ax.set_title("bifurcation diagram: follower angle once per cam period")
            else:
                ax.plot(first.values, da.values, ".-", lw=0.8, ms=3)
            ax.set_ylabel(_label(da), fontsize=8)
        axes[-1, 0].set_xlabel(_label(first))
        return _save(fig, path)
    sel = {d: 0 for d in dims[2:]}
    second = ds[dims[1]]
    names = [n for n in ("regime", "impacts_per_revolution") if n in ds]
    if not names:
        names = ["status"]
    fig, axes = plt.subplots(1, len(names), figsize=(6 * len(names), 4.6), squeeze=False)
    for ax, name in zip(axes[0], names):
        da = ds[name].isel(sel)
        values = da.transpose(dims[1], dims[0]).values.astype(float)
        if name == "regime":
            codes = sorted(_REGIME_COLOURS)
            ax.pcolormesh(first.values, second.values, values, shading="nearest", vmin=-1.5, vmax=3.5,
                          cmap=ListedColormap([_REGIME_COLOURS[c] for c in codes]))
            for c in codes:
                label = {-1: "failed", 0: "contact kept", 1: "vr reversal", 2: "periodic impacts",
                         3: "irregular impacts"}[c]
                ax.plot([], [], "s", color=_REGIME_COLOURS[c], label=label, markersize=9)
            ax.legend(fontsize=7, loc="upper right", framealpha=0.9)
        else:
            mesh = ax.pcolormesh(first.values, second.values, values, shading="nearest", cmap="viridis")
            fig.colorbar(mesh, ax=ax, label=_label(ds[name]))
        ax.set_xlabel(_label(first))
        ax.set_ylabel(_label(second))
        ax.set_title(ds[name].attrs.get("long_name", name), fontsize=9)
    return _save(fig, path)


def _map_categories(ds: xr.Dataset):
    """Simulation regions of a regime map: codes and labels (periodic impacts banded by
    impacts per revolution)."""
    regime = ds["regime"].values
    rate = ds["impacts_per_revolution"].values
    codes = np.full(regime.shape, -1, dtype=int)
    labels = {-1: "failed", 0: "contact kept", 1: "contact kept, vr reversal", 2: "irregular impacts"}
    codes[regime == 0] = 0
    codes[regime == 1] = 1
    codes[regime == 3] = 2
    periodic = regime == 2
    bands = [(0.0, 0.999, "periodic, < 1 impact/rev (subharmonic)"), (0.999, 1.001, "periodic, 1 impact/rev"),
             (1.001, 5.0, "periodic, 1-5 impacts/rev"), (5.0, np.inf, "periodic, > 5 impacts/rev (chattering)")]
    for i, (low, high, label) in enumerate(bands):
        codes[periodic & (rate > low) & (rate <= high)] = 3 + i
        labels[3 + i] = label
    return codes, labels


def plot_regime_map(ds: xr.Dataset, path: str | Path) -> Path:
    """Regime map (:func:`camdyn.sweeps.regime_map.regime_map`): simulated regions over
    the two swept parameters, with the inverse-kinematics loss-of-contact curve (solid)
    and the boundary of sliding-velocity reversal (dashed)."""
    from matplotlib.colors import ListedColormap

    dims = list(ds["regime"].dims)
    x, y = ds[dims[0]], ds[dims[1]]
    codes, labels = _map_categories(ds)
    fixed = ["#000000", "#2ca02c", "#ff7f0e", "#d62728"]
    colours = fixed + [tuple(c) for c in plt.get_cmap("Blues")(np.linspace(0.35, 0.95, 4))]
    fig, ax = plt.subplots(figsize=(7.5, 5))
    ax.pcolormesh(x.values, y.values, codes.T, shading="nearest", vmin=-1.5, vmax=len(colours) - 1.5,
                  cmap=ListedColormap(colours))
    present = set(np.unique(codes))
    for c, label in labels.items():
        if c in present:
            ax.plot([], [], "s", color=colours[c + 1], label=label, markersize=9)
    if "loss_of_contact_speed" in ds:
        curve = ds["loss_of_contact_speed"]
        other = curve.dims[0]
        if other == dims[0]:
            ax.plot(x.values, curve.values, "k-", lw=1.5, label="loss of contact (inverse kinematics)")
        else:
            ax.plot(curve.values, y.values, "k-", lw=1.5, label="loss of contact (inverse kinematics)")
    kin = ds["kinematic_regime"].values.astype(float)
    if np.any(kin == 1) and kin.shape[0] > 1 and kin.shape[1] > 1:
        ax.contour(x.values, y.values, (kin == 1).T.astype(float), levels=[0.5], colors="k", linestyles="--",
                   linewidths=1.0)
        ax.plot([], [], "k--", label="vr reversal (inverse kinematics)")
    agree = {k[len("agreement_"):]: ds.attrs[k] for k in ds.attrs if k.startswith("agreement_")}
    if agree:
        ax.set_title(f"simulation agrees with inverse kinematics at {agree['kept_agree']}/{agree['kept']} points "
                     f"in contact and {agree['lost_agree']}/{agree['lost']} beyond", fontsize=9)
    ax.set_xlim(x.values.min(), x.values.max())
    ax.set_ylim(y.values.min(), y.values.max())
    ax.set_xlabel(_label(x))
    ax.set_ylabel(_label(y))
    ax.legend(fontsize=7, loc="best", framealpha=0.9)
    return _save(fig, path)
