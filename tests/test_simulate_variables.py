"""``simulate(variables=...)`` returns only what was asked, with the same values as a
full run, and refuses names it does not know before any work."""

import numpy as np
import pytest

import camdyn
from camdyn.errors import ParameterError
from camdyn.simulation.runner import VARIABLES


@pytest.fixture(scope="module")
def rig():
    return camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"})


@pytest.fixture(scope="module")
def full(rig):
    return camdyn.simulate(rig, speed=16.0, revolutions=3, sample_rate=5e3)


@pytest.mark.parametrize("names", [["alpha"], ["alpha_dot", "Fn", "Nx"], ["impact"], ["in_contact", "cam_work"]])
def test_only_the_asked_variables_with_the_full_runs_values(rig, full, names):
    ds = camdyn.simulate(rig, speed=16.0, revolutions=3, sample_rate=5e3, variables=names)
    expected = [name for name in full.data_vars
                if name in names or ("impact" in names and name.startswith("impact_"))]
    assert sorted(ds.data_vars) == sorted(expected)
    for name in expected:
        np.testing.assert_array_equal(ds[name].values, full[name].values, err_msg=name)
        assert ds[name].attrs == full[name].attrs
    assert ds.attrs["solver_accepted_steps"] == full.attrs["solver_accepted_steps"]


def test_default_is_every_variable(full):
    names = set(full.data_vars)
    for name in VARIABLES:
        assert name in names or any(n.startswith(f"{name}_") for n in names), name


@pytest.mark.parametrize("variables, words", [
    (["alpha", "force"], "unknown variable(s) 'force'"),
    ("alpha", "must be a list"),
    ([], "is empty"),
])
def test_bad_variables_are_refused(rig, variables, words):
    with pytest.raises(ParameterError, match=None) as info:
        camdyn.simulate(rig, speed=16.0, revolutions=3, variables=variables)
    assert words in str(info.value)
