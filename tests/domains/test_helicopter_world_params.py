"""Tests of the world models' parameter records and no-fly zones (model behaviour: test_helicopter_worlds)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drd_planner.domains.helicopter_world_params import (
    NOFLY_Z_RANGE,
    CanyonParams,
    NoFlyZone,
    TerrainParams,
    WiresParams,
)
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.shapes import Box, Cylinder


def test_no_fly_zones_as_solids_and_footprints() -> None:
    cyl = NoFlyZone("cylinder", (10.0, 0.0), radius=5.0)
    shape, pose = cyl.solid()
    assert isinstance(shape, Cylinder)
    assert pose.position[2] == pytest.approx(sum(NOFLY_Z_RANGE) / 2)
    assert cyl.contains_xy([[12.0, 0.0], [16.0, 0.0]]).tolist() == [True, False]
    prism = NoFlyZone("prism", (0.0, 0.0), size=(10.0, 2.0), yaw_deg=90.0)
    assert isinstance(prism.solid()[0], Box)
    assert prism.footprint_radius == pytest.approx(0.5 * math.hypot(10.0, 2.0))
    assert prism.contains_xy(np.array([[0.0, 4.0], [4.0, 0.0]])).tolist() == [True, False]
    with pytest.raises(ProblemError, match="shape"):
        NoFlyZone("sphere")
    with pytest.raises(ProblemError, match="bottom < top"):
        NoFlyZone(z_range=(5.0, 5.0))


def test_records_normalise_and_validate() -> None:
    assert WiresParams(nofly=[{"center": [1, 2]}]).nofly == (NoFlyZone(center=(1.0, 2.0)),)
    assert CanyonParams(meander_modes=2.0).meander_modes == 2
    with pytest.raises(ProblemError, match="nofly count"):
        WiresParams(nofly=-1)
    with pytest.raises(ProblemError, match="meander_modes"):
        CanyonParams(meander_modes=0)
    with pytest.raises(ProblemError, match="mirror"):
        TerrainParams(mirror=2.0)
    with pytest.raises(ProblemError, match="site fractions"):
        TerrainParams(site=(0.5, 1.5))
    with pytest.raises(ProblemError, match="max_tries"):
        TerrainParams(max_tries=0)
    assert TerrainParams(path="x.asc").resolved_path().name == "x.asc"
