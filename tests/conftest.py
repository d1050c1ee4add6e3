"""Shared fixtures: the thesis baseline scenario and its geometry."""

from __future__ import annotations

import pytest

from physics.gear.geometry import mesh_geometry
from physics.params import GearPair, Scenario


@pytest.fixture(scope="session")
def baseline() -> Scenario:
    return Scenario()


@pytest.fixture(scope="session")
def geom():
    return mesh_geometry(GearPair())
