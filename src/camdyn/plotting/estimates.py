"""Figures of estimates and of contact conditions: accelerance and half-power band,
impact force and hysteresis, the residue landscape, restitution, and Hertz pressure,
velocities and film over a cam revolution."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from camdyn.plotting.style import axis_label, engineering, save_figure, styled, tidy_axis

__all__ = ["plot_contact_conditions", "plot_accelerance", "plot_impact_fit", "plot_residue_landscape",
           "plot_restitution"]


@styled
def plot_contact_conditions(ds: xr.Dataset, path: str | Path) -> Path:
    """Hertz peak pressure p_max [GPa], sliding and sum velocities v_r, v_e [m/s],
    slide-to-roll ratio (fig 4.5), and the lambda ratio Λ, over one cam revolution θ [deg]."""
    theta = np.degrees(ds["cam_angle"].values)
    rows = 4 if "lambda_ratio" in ds else 3
    fig, axes = plt.subplots(rows, 1, figsize=(7.0, 1.8 * rows + 0.9), sharex=True)
    axes[0].plot(theta, ds["peak_pressure"].values / 1e9, color="C0")
    axes[0].set_ylabel(axis_label(r"$p_{\max}$", "GPa"))
    axes[1].plot(theta, ds["sliding_velocity"].values, label="$v_r$ (sliding)")
    axes[1].plot(theta, ds["sum_velocity"].values, label="$v_e$ (sum)")
    axes[1].set_ylabel(axis_label("$v$", "m/s"))
    axes[1].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[2].plot(theta, ds["slide_to_roll"].values, color="C2")
    axes[2].set_ylabel(axis_label("$v_r/v_e$", "-"))
    if "lambda_ratio" in ds:
        axes[3].plot(theta, ds["lambda_ratio"].values, color="C3")
        for level in (1.0, 3.0):
            axes[3].axhline(level, color="k", lw=0.6, ls="--")
        axes[3].set_ylabel(axis_label(r"$\Lambda$", "-"))
        axes[3].set_title(f"{ds.attrs.get('lubricant', '')}: boundary < 1 < mixed < 3 < EHL")
    for ax in axes:
        tidy_axis(ax.yaxis, 4)
    axes[-1].xaxis.set_major_locator(plt.MultipleLocator(60))
    axes[-1].set_xlabel(axis_label(r"cam angle $\theta$", "deg"))
    fig.align_ylabels(axes)
    return save_figure(fig, path)


@styled
def plot_accelerance(frequency, response, estimate, path: str | Path) -> Path:
    """Accelerance magnitude ``|A|`` [1/kg] near a peak with its half-power band (fig 4.7)."""
    fig, ax = plt.subplots(figsize=(7.0, 4.0))
    fn = estimate.natural_frequency
    width = max(8 * (estimate.upper - estimate.lower), 20 * estimate.resolution)
    sel = (frequency > fn - width) & (frequency < fn + width)
    ax.plot(frequency[sel], np.abs(response[sel]), ".-", color="C0", label="$|A(f)|$")
    ax.axhline(estimate.peak / np.sqrt(2), color="k", ls="--", lw=0.7, label="half power")
    ax.axvspan(estimate.lower, estimate.upper, color="C1", alpha=0.2,
               label=rf"$\zeta$ = {100 * estimate.damping_ratio:.2f} %")
    tidy_axis(ax.xaxis, 7)
    ax.set_xlabel(axis_label("$f$", "Hz"))
    ax.set_ylabel(axis_label("$|A|$", "1/kg"))
    ax.legend(loc="upper right")
    return save_figure(fig, path)


@styled
def plot_impact_fit(estimate, path: str | Path, impact: int = 0) -> Path:
    """Contact force F_n [N] of one impact, measured (force balance, eq 3.21) against
    simulation S1 at the estimate: over the time since onset [µs], and as a hysteresis
    loop over the penetration δ [µm] (figs 3.4, 3.7, 3.8)."""
    prob = estimate.problem
    k = int(np.clip(impact, 0, prob.count - 1))
    res = prob.residues(np.array([k]), np.array([estimate.beta]), np.array([estimate.exponent]))
    u = prob.offsets[k] * 1e6
    fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.9))
    axes[0].plot(u, prob.force[k], "o", ms=3, color="C0", label="measured (force balance)")
    axes[0].plot(u, res["force"][0], "-", color="C3", label="simulation S1 at the estimate")
    axes[0].set_xlabel(axis_label("$t - t_0$", "µs"))
    axes[0].set_title(f"impact {k + 1} of {prob.count}")
    axes[1].plot(prob.penetration[k] * 1e6, prob.force[k], "o", ms=3, color="C0")
    axes[1].plot(res["penetration"][0] * 1e6, res["force"][0], "-", color="C3")
    axes[1].set_xlabel(axis_label(r"$\delta$", "µm"))
    axes[1].set_title(rf"$\beta$ = {engineering(estimate.beta, estimate.beta_units)}, $n$ = {estimate.exponent:.4g}")
    for ax in axes:
        ax.set_ylabel(axis_label("$F_n$", "N"))
        tidy_axis(ax.xaxis, 6)
    fig.legend(handles=axes[0].get_lines(), loc="outside lower center", ncol=2)
    return save_figure(fig, path)


@styled
def plot_residue_landscape(landscape: xr.DataArray, estimate, path: str | Path) -> Path:
    """Mean ``|Λ|`` per impact over (n, β), with the estimate and the bootstrap replicates:
    the (β, n) valley of thesis 3.7."""
    ns = landscape["exponent"].values
    beta = landscape["beta"].values
    fig, ax = plt.subplots(figsize=(6.5, 4.8))
    nn = np.repeat(ns[:, None], beta.shape[1], axis=1)
    mesh = ax.pcolormesh(nn, np.log10(beta), np.log10(landscape.values + 1e-16), shading="auto", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label=rf"$\log_{{10}}$ {landscape.attrs.get('long_name', 'residue')}")
    if estimate.bootstrap.size:
        ax.plot(estimate.bootstrap[:, 1], np.log10(estimate.bootstrap[:, 0]), "o", mfc="w", mec="k", mew=0.4,
                ms=3.5, ls="none", label="bootstrap replicates")
    ax.plot([estimate.exponent], [np.log10(estimate.beta)], "r*", ms=12, label="estimate")
    ax.grid(False)
    ax.set_xlabel(axis_label("damping exponent $n$", "-"))
    ax.set_ylabel(r"$\log_{10}\beta$ [$\beta$ in N s m$^{-(n+1)}$]")
    ax.legend(loc="upper left")
    return save_figure(fig, path)


@styled
def plot_restitution(estimate, path: str | Path) -> Path:
    """Coefficient of restitution ξ of each impact against its approach velocity v_a
    [m/s], with the fitted ``ξ = 1 - γ v_a`` (figs 3.9, 3.10)."""
    v = estimate.approach_velocity
    fig, ax = plt.subplots(figsize=(6.0, 4.2))
    ax.plot(v, estimate.restitution, "o", ms=4, label="impacts")
    grid = np.linspace(0.0, max(v.max() * 1.1, 1e-3), 50)
    ax.plot(grid, 1.0 - estimate.gamma * grid, "-", color="C3",
            label=rf"$\xi = 1 - \gamma v_a$, $\gamma$ = {estimate.gamma:.4g} s/m")
    ax.set_xlabel(axis_label("approach velocity $v_a$", "m/s"))
    ax.set_ylabel(axis_label(r"restitution $\xi$", "-"))
    ax.legend(loc="best")
    return save_figure(fig, path)
