"""The order of the examples in the gallery (sphinx-gallery's ``within_subsection_order``)."""

from pathlib import Path

#: from a single simulation up to identification and sweeps; scripts not listed come last,
#: by file name
ORDER = ["plot_impact_rig.py", "plot_friction_rig_spectrum.py", "plot_equilibrium_runout.py",
         "plot_friction_identification.py", "plot_bifurcation_sweep.py"]


class GalleryOrder:
    """Sort key of an example file name: its place in :data:`ORDER`."""

    def __init__(self, src_dir):
        self.src_dir = src_dir

    def __repr__(self) -> str:
        return "<GalleryOrder>"

    def __call__(self, filename) -> tuple[int, str]:
        name = Path(filename).name
        return (ORDER.index(name) if name in ORDER else len(ORDER), name)
