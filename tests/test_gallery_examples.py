"""The sphinx-gallery examples (examples/gallery/plot_*.py, run by ``make docs``) draw in
camdyn's figure style: each script, run whole as sphinx-gallery runs it, leaves its
figures open (the gallery shows the open figures), made inside
:func:`camdyn.plotting.style.figure_style` (a constrained layout), with every axis label a
symbol and a unit, and no text that overlaps or leaves the figure
(:func:`camdyn.plotting.style.layout_problems`, shown to fail on crowded figures in
tests/test_figures.py). About two seconds a script once camdyn's compiled code is cached.
"""

import runpy
from pathlib import Path

import matplotlib.pyplot as plt
import pytest
from matplotlib.layout_engine import ConstrainedLayoutEngine

from camdyn.plotting import layout_problems

GALLERY = Path(__file__).resolve().parents[1] / "examples" / "gallery"
SCRIPTS = sorted(path.name for path in GALLERY.glob("plot_*.py"))


@pytest.fixture
def no_open_figures():
    """No figure open before the test, none left after it."""
    plt.close("all")
    yield
    plt.close("all")


def test_the_gallery_has_its_scripts():
    assert len(SCRIPTS) >= 5


@pytest.mark.parametrize("script", SCRIPTS)
def test_the_gallery_figures_are_in_the_house_style(script, no_open_figures, capsys):
    runpy.run_path(str(GALLERY / script), run_name="__main__")
    figures = [plt.figure(number) for number in plt.get_fignums()]
    assert figures, f"{script} leaves no figure open for sphinx-gallery to show"
    for fig in figures:
        assert isinstance(fig.get_layout_engine(), ConstrainedLayoutEngine), f"{script}: not drawn in figure_style()"
        labels = [label for ax in fig.axes for label in (ax.get_xlabel(), ax.get_ylabel()) if label]
        assert labels and all(label.endswith("]") and " [" in label for label in labels), labels
        assert not any("[rad]" in label for label in labels), labels
        assert layout_problems(fig) == []


def test_the_work_precision_figure_is_readable(tmp_path, monkeypatch):
    # the README's benchmark figure, drawn again from its recorded results
    # (benchmarks/bench_peers.py --redraw), through the same overlap check
    import json
    import sys

    from camdyn.plotting import style

    benchmarks = Path(__file__).resolve().parents[1] / "benchmarks"
    monkeypatch.syspath_prepend(str(benchmarks))
    seen = []
    monkeypatch.setattr(style, "SAVE_HOOKS", [lambda fig: seen.append(layout_problems(fig))])
    bench_peers = __import__("bench_peers")
    try:
        bench_peers.plot(json.loads((benchmarks / "peers.json").read_text()), tmp_path / "work_precision.png")
    finally:
        sys.modules.pop("bench_peers", None)
        sys.modules.pop("peer_models", None)
    assert seen == [[]]
    assert (tmp_path / "work_precision.png").stat().st_size > 10_000
