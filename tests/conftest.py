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
