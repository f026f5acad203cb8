"""Simulation Datasets are built without xarray's duck-array checks, which import
``dask.array`` (about 0.3 s of a new process's first run), and equal the ones xarray
builds with its checks. (xarray's own operations on it, a reduction for one, still import
``dask.array`` when first used.)"""

import subprocess
import sys

import numpy as np
import xarray as xr

from camdyn.simulation.datasets import dataset

SPEC = {
    "alpha": ("time", np.linspace(0.0, 1.0, 5), {"units": "rad"}),
    "in_contact": (("time",), np.array([1, 0, 1, 1, 0], dtype=np.int8), {"units": ""}),
    "impact_time": (("impact",), np.array([0.1, 0.3]), {"units": "s"}),
    "event_guard": ("event", np.array(["contact", "stick"], dtype=object), {"long_name": "guard"}),
}
COORDS = {"time": ("time", np.arange(5) * 0.25, {"units": "s"})}


def test_equals_the_dataset_xarray_builds_with_its_checks():
    ours = dataset(SPEC, COORDS, {"rtol": 1e-8})
    theirs = xr.Dataset(SPEC, coords=COORDS, attrs={"rtol": 1e-8})
    assert ours.identical(theirs)
    assert ours["in_contact"].dtype == np.int8
    assert ours["event_guard"].dtype == object     # went through xarray's own checks
    assert list(ours.indexes) == ["time"]


def test_a_new_process_builds_one_without_importing_dask_array():
    code = ("import sys, numpy as np\n"
            "from camdyn.simulation.datasets import dataset\n"
            "ds = dataset({'alpha': ('time', np.zeros(3), {'units': 'rad'})},"
            " {'time': ('time', np.arange(3.0), {'units': 's'})})\n"
            "ds.attrs['rtol'] = 1e-8; ds['alpha'].values.max()\n"
            "print('dask.array' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False", out.stderr
    # the check this module avoids does import it: xarray's own constructor
    out = subprocess.run([sys.executable, "-c", code.replace("from camdyn.simulation.datasets import dataset",
                                                             "import xarray as xr; dataset = xr.Dataset")],
                         capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True", out.stderr
