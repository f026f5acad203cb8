"""Figures of simulation results (matplotlib, headless), in one style
(:mod:`camdyn.plotting.style`): quantities in the units the user gave, the follower angle
in degrees, short labels with symbols, no overlapping or clipped text.

- :mod:`~camdyn.plotting.signals`: time histories and spectra of one simulation;
- :mod:`~camdyn.plotting.maps`: sweeps, regime maps and design maps;
- :mod:`~camdyn.plotting.estimates`: estimates (accelerance, impacts, restitution) and
  contact conditions.
"""

from camdyn.plotting.estimates import (
    plot_accelerance,
    plot_contact_conditions,
    plot_impact_fit,
    plot_residue_landscape,
    plot_restitution,
)
from camdyn.plotting.maps import plot_design_map, plot_regime_map, plot_sweep
from camdyn.plotting.signals import plot_spectrum, plot_time_history
from camdyn.plotting.style import STYLE, figure_format, figure_style, layout_problems, styled

__all__ = ["STYLE", "figure_format", "figure_style", "layout_problems", "styled", "plot_time_history",
           "plot_spectrum", "plot_sweep", "plot_regime_map", "plot_design_map", "plot_contact_conditions",
           "plot_accelerance", "plot_impact_fit", "plot_residue_landscape", "plot_restitution"]
