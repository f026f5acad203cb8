"""The look shared by every camdyn figure, and the checks that keep it readable.

One style (:data:`STYLE`, applied by :func:`styled`): constrained layout, 9-point text,
light grids, PNGs at 120 dpi. Quantities are drawn in the unit the user gave (a sweep's
coordinates carry ``display_units`` and ``display_factor``) or, without one, in the SI
unit with a prefix that keeps the numbers between 1 and 1000 (mm, kN, ms). Labels are a
symbol and a unit in brackets (``e [mm]``, ``Ω [rpm]``); the follower angle is always in
degrees.

:func:`layout_problems` lists text that overlaps other text or leaves the figure; the
tests run it on every figure (through :data:`SAVE_HOOKS`).

Importing camdyn's plotting leaves matplotlib's backend alone (a window, a notebook's
inline figures); the command line draws off screen (``MPLBACKEND=Agg``, set by
:func:`camdyn.cli.run` unless the user set it).
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.backend_bases import FigureCanvasBase
from matplotlib.text import Text
from matplotlib.ticker import MaxNLocator

from camdyn.errors import OutputError
from camdyn.io.atomic import atomic_output

__all__ = ["STYLE", "DPI", "SAVE_HOOKS", "SYMBOLS", "styled", "figure_style", "figure_format", "save_figure",
           "legend_below", "unit_text", "display_scale", "display_values", "engineering", "speed_text", "axis_label",
           "tidy_axis", "layout_problems"]

#: matplotlib settings of every camdyn figure
STYLE = {
    "figure.constrained_layout.use": True,
    "figure.constrained_layout.h_pad": 0.06,
    "figure.constrained_layout.w_pad": 0.06,
    "font.size": 9.0,
    "axes.titlesize": 9.0,
    "axes.labelsize": 9.0,
    "xtick.labelsize": 8.0,
    "ytick.labelsize": 8.0,
    "legend.fontsize": 8.0,
    "legend.framealpha": 0.9,
    "figure.titlesize": 10.0,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "grid.linewidth": 0.5,
    "axes.formatter.limits": (-3, 5),
    "axes.formatter.use_mathtext": True,
    "lines.linewidth": 1.0,
    "savefig.facecolor": "white",
}
#: resolution of the PNGs [dots per inch]
DPI = 120
#: functions called with every figure just before it is written and closed (tests check
#: the layout through this)
SAVE_HOOKS: list = []

#: symbol (matplotlib mathtext) of each swept parameter in axis labels
SYMBOLS = {
    "cam.radius": r"$r_c$", "cam.semi_major": "$a$", "cam.semi_minor": "$b$", "cam.runout": "$e$",
    "cam.pivot_x": "$x_P$", "cam.pivot_y": "$y_P$", "follower.mass": "$m$", "follower.inertia": "$I$",
    "follower.cg_distance": "$d_G$", "follower.length": "$L$", "spring.stiffness": "$k_s$",
    "spring.free_length": "$l_0$", "spring.tilt": r"$\psi$", "contact.length": "$l_c$",
    "contact.damping_ratio": r"$\zeta$", "contact.exponent": "$n$", "contact.beta": r"$\beta$",
    "contact.restitution": r"$\xi$", "contact.reference_velocity": "$v_r$", "friction.coefficient": r"$\mu$",
    "friction.smoothing": r"$\varepsilon$", "motion.speed": r"$\Omega$", "motion.amplitude": r"$\theta_a$",
    "motion.frequency": "$f_o$", "environment.gravity": "$g$",
}
#: SI units drawn with a prefix (mm, kN, ms) when no display unit was given
_PREFIXED = {"m", "Hz", "N", "Pa", "s", "N/m", "J", "W"}
_PREFIXES = {-9: "n", -6: "µ", -3: "m", 0: "", 3: "k", 6: "M", 9: "G"}
_ANGLES = {"rad": ("deg", 180.0 / math.pi)}


def styled(func):
    """Run a figure function inside :data:`STYLE`."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with plt.rc_context(STYLE):
            return func(*args, **kwargs)
    return wrapper


def figure_style():
    """A context in which matplotlib draws in :data:`STYLE` (for a script's own figures):
    ``with figure_style(): fig, ax = plt.subplots()``."""
    return plt.rc_context(STYLE)


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


def save_figure(fig, path: str | Path) -> Path:
    """Write ``fig`` atomically to ``path`` (format from the suffix) and close it."""
    path = Path(path)
    fmt = figure_format(path)
    try:
        for hook in SAVE_HOOKS:
            fig.canvas.draw()
            hook(fig)
        with atomic_output(path) as tmp:
            fig.savefig(tmp, dpi=DPI, format=fmt)
    finally:
        plt.close(fig)
    return path


def legend_below(fig, ax, ncols: int) -> None:
    """One legend for the whole figure, below its panels, of the labelled artists of
    ``ax`` in ``ncols`` columns (the figure needs a constrained layout)."""
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=ncols)


def unit_text(unit: str) -> str:
    """A unit as a label shows it: ``rad/s**2`` -> ``rad/s²``, ``1`` or empty -> ``-``."""
    unit = (unit or "").strip()
    if unit in ("", "1"):
        return "-"
    unit = unit.replace("**", "^").replace("^2.5", "$^{2.5}$").replace("^2", "²").replace("^3", "³")
    return unit.replace("*", " ").replace("um", "µm").replace("us", "µs")


def _prefixed(values: np.ndarray, unit: str) -> tuple[float, str]:
    """Factor and unit that bring the largest |value| of an SI quantity into [1, 1000)."""
    finite = np.abs(values[np.isfinite(values)])
    if unit not in _PREFIXED or not finite.size or finite.max() == 0:
        return 1.0, unit
    power = int(np.clip(3 * math.floor(math.log10(finite.max()) / 3), -9, 9))
    if unit == "Hz" and power < 0:
        return 1.0, unit
    return 10.0 ** -power, _PREFIXES[power] + unit


def display_scale(da: xr.DataArray) -> tuple[float, str]:
    """Factor from the stored (SI) values of ``da`` to the values drawn, and their unit:
    ``display_factor`` and ``display_units`` when the data carry them (the unit a sweep
    spec was written in), degrees for angles, else the SI unit with a prefix that brings
    the largest value into [1, 1000) (mm, kN, ms; not for Hz below 1)."""
    if da.attrs.get("display_units"):
        return float(da.attrs.get("display_factor", 1.0)), str(da.attrs["display_units"])
    unit = str(da.attrs.get("units", ""))
    if unit in _ANGLES:
        name, factor = _ANGLES[unit]
        return factor, name
    return _prefixed(np.asarray(da.values, dtype=float), unit)


def display_values(da: xr.DataArray) -> tuple[np.ndarray, str]:
    """Values of ``da`` as drawn, and their unit (:func:`display_scale`)."""
    factor, unit = display_scale(da)
    return np.asarray(da.values, dtype=float) * factor, unit


def engineering(value: float, unit: str, digits: int = 4) -> str:
    """``value`` [unit] with an SI prefix: ``engineering(2.4637e10, "N s/m^2.5")`` ->
    ``24.64 GN s/m$^{2.5}$``."""
    power = int(np.clip(3 * math.floor(math.log10(abs(value)) / 3), -9, 9)) if value else 0
    return f"{value / 10.0 ** power:.{digits}g} {_PREFIXES[power]}{unit_text(unit)}"


def speed_text(speed: float) -> str:
    """A cam speed in Hz and rpm: ``Ω = 11.55 Hz (693 rpm)``."""
    return f"Ω = {speed:.4g} Hz ({60 * speed:.4g} rpm)"


def axis_label(symbol: str, unit: str) -> str:
    """``symbol [unit]``."""
    return f"{symbol} [{unit_text(unit)}]"


def tidy_axis(axis, bins: int = 6, integer: bool = False) -> None:
    """At most ``bins`` ticks at round numbers on a matplotlib axis (x or y)."""
    axis.set_major_locator(MaxNLocator(nbins=bins, steps=[1, 2, 2.5, 5, 10], integer=integer, min_n_ticks=3))


def _texts(fig) -> list[Text]:
    """The visible, non-empty text artists of a drawn figure: titles, axis labels, offset
    texts, tick labels inside the view limits, legend texts, free texts."""
    found = list(fig.texts)
    for legend in fig.legends:
        found += legend.get_texts() + [legend.get_title()]
    for ax in fig.axes:
        titles = [getattr(ax, name, None) for name in ("title", "_left_title", "_right_title")]
        found += [t for t in titles if t is not None] + list(ax.texts)
        found += [ax.xaxis.label, ax.yaxis.label, ax.xaxis.get_offset_text(), ax.yaxis.get_offset_text()]
        legend = ax.get_legend()
        if legend is not None:
            found += legend.get_texts() + [legend.get_title()]
        for axis in (ax.xaxis, ax.yaxis):
            # compared on the axis's scale (a log axis in decades), so that rounding of the
            # limits keeps a tick at a limit, and a tick a decade outside stays out
            scale = axis.get_transform()
            low, high = sorted(scale.transform(np.asarray(axis.get_view_interval(), dtype=float)))
            pad = 1e-9 * max(abs(low), abs(high), 1e-300)
            for ticks in (axis.get_major_ticks(len(axis.get_majorticklocs())),
                          axis.get_minor_ticks(len(axis.get_minorticklocs()))):
                for tick in ticks:
                    with np.errstate(divide="ignore", invalid="ignore"):
                        place = float(scale.transform(np.array([tick.get_loc()], dtype=float))[0])
                    if low - pad <= place <= high + pad:
                        found += [tick.label1, tick.label2]
    return [t for t in found if t.get_visible() and t.get_text().strip() and t.get_figure() is not None]


def layout_problems(fig, tolerance: float = 1.0) -> list[str]:
    """Text of a figure that overlaps other text or lies (partly) outside the figure.

    Every visible text artist (see :func:`_texts`) is measured with the renderer's tight
    bounding box; two boxes that overlap by more than ``tolerance`` [pixels] in both
    directions are reported, and so is any box, or legend frame, that crosses the figure's
    edge by more than ``tolerance``.

    Returns
    -------
    list of str
        One line per problem; empty when the figure is clean.
    """
    renderer = fig.canvas.get_renderer()
    fig.canvas.draw()
    width, height = fig.bbox.width, fig.bbox.height
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in _texts(fig)]
    frames = [(f"legend {i}", leg.get_window_extent(renderer))
              for i, leg in enumerate(list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend()])]
    problems = []
    for text, box in boxes + frames:
        if (box.x0 < -tolerance or box.y0 < -tolerance or box.x1 > width + tolerance
                or box.y1 > height + tolerance):
            problems.append(f"outside the figure: {text!r}")
    for i, (text, box) in enumerate(boxes):
        for other, obox in boxes[i + 1:]:
            dx = min(box.x1, obox.x1) - max(box.x0, obox.x0)
            dy = min(box.y1, obox.y1) - max(box.y0, obox.y0)
            if dx > tolerance and dy > tolerance:
                problems.append(f"overlap: {text!r} and {other!r}")
    return problems
