"""Shared fixtures: the bundled presets and their prepared forms."""

import pytest

import camdyn


@pytest.fixture(scope="session")
def friction_rig():
    return camdyn.load_system("sundar2014-friction")


@pytest.fixture(scope="session")
def impact_rig():
    return camdyn.load_system("sundar2014-impact")


@pytest.fixture(scope="session")
def standin_rig():
    return camdyn.load_system("alzate2007-standin")


@pytest.fixture(scope="session")
def impacting_standin():
    return camdyn.load_system("alzate2007-standin-impacting")


#: Test files that take the longest (about a minute or more each on 2 cores, measured with
#: ``--durations``). ``make test`` runs the suite on two pytest-xdist workers that take
#: whole files in collection order (``--dist loadfile``); collected first, these long
#: files start at once and the short ones fill in around them, so neither worker is left
#: alone with a long file at the end (the longest-first rule of scheduling).
LONG_FILES = ("test_parameter_sensitivity.py", "test_oracle_laws.py", "test_thesis_tables.py",
              "test_impact_identification.py", "test_lyapunov_spectrum.py", "test_maps_spectra.py",
              "test_sweeps.py", "test_faults.py", "test_oracle_energy.py", "test_figures.py",
              "test_continuation_chapter3_windows.py", "test_mechanism_sweeps.py")


def pytest_collection_modifyitems(config, items):
    """Put the tests of :data:`LONG_FILES` first, in that order; the rest keep theirs."""
    rank = {name: i for i, name in enumerate(LONG_FILES)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))
