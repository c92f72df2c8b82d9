"""Arm world models: determinism, ranges, objects standing on the table, keep-clear spheres."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from drd_planner.domains.arm_worlds import (
    CLUTTER_COUNT,
    CLUTTER_REGION,
    TABLE_OBJECTS,
    TABLE_THICKNESS,
    TABLE_TOP_HEIGHT,
    WORLD_MODELS,
    ArmWorld,
    KeepClear,
    sample_arm_world,
)
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.shapes import Box, Cylinder

NOTHING = KeepClear(np.zeros((0, 3)), np.zeros(0))
#: A keep-clear column (like an arm reaching down) at x = 0.5, y = 0 from 0.4 m (above any table) to 1 m.
COLUMN = KeepClear(np.array([[0.5, 0.0, z] for z in np.linspace(0.4, 1.0, 7)]), np.full(7, 0.1))


@pytest.mark.parametrize("model", WORLD_MODELS)
def test_same_seed_same_world(model: str) -> None:
    a = sample_arm_world(model, 12, keep_clear=COLUMN)
    b = sample_arm_world(model, 12, keep_clear=COLUMN)
    c = sample_arm_world(model, 13, keep_clear=COLUMN)
    assert a == b
    assert a != c
    assert (a.model, a.seed) == (model, 12)
    assert len({o.name for o in a.obstacles}) == len(a.obstacles)


def test_clutter_ranges() -> None:
    for seed in range(20):
        world = sample_arm_world("clutter", seed, keep_clear=NOTHING)
        assert CLUTTER_COUNT[0] <= len(world.obstacles) <= CLUTTER_COUNT[1]  # nothing to avoid: all placed
        for obstacle in world.obstacles:
            assert isinstance(obstacle.shape, Box | Cylinder)
            for axis, (lo, hi) in enumerate(CLUTTER_REGION):
                assert lo <= obstacle.pose.position[axis] <= hi


def test_table_clutter_objects_stand_on_the_table() -> None:
    for seed in range(20):
        world = sample_arm_world("table_clutter", seed, keep_clear=NOTHING)
        parts = {o.name: o for o in world.obstacles}
        top = parts["table_top"]
        assert isinstance(top.shape, Box)
        top_z = top.pose.position[2] + TABLE_THICKNESS / 2
        assert TABLE_TOP_HEIGHT[0] <= top_z <= TABLE_TOP_HEIGHT[1]
        yaw = Rotation.from_quat(top.pose.quaternion_xyzw).as_euler("xyz")
        assert yaw[0] == pytest.approx(0.0, abs=1e-12)
        assert yaw[1] == pytest.approx(0.0, abs=1e-12)
        objects = [o for o in world.obstacles if not o.name.startswith("table")]
        assert TABLE_OBJECTS[0] <= len(objects) <= TABLE_OBJECTS[1]
        to_table = top.pose.inverse()
        for obstacle in objects:
            shape = obstacle.shape
            height = shape.size[2] if isinstance(shape, Box) else shape.length
            assert obstacle.pose.position[2] - height / 2 == pytest.approx(top_z)  # bottom on the top surface
            local = to_table.transform_points(obstacle.pose.position[None])[0]
            assert np.all(np.abs(local[:2]) <= top.shape.size[:2] / 2)  # over the table
        legs = [o for o in world.obstacles if o.name.startswith("table_leg")]
        assert len(legs) in (0, 4)
        for leg in legs:
            assert leg.pose.position[2] - leg.shape.size[2] / 2 == pytest.approx(0.0)  # leg on the floor


@pytest.mark.parametrize("model", WORLD_MODELS)
def test_keep_clear_spheres_stay_free(model: str) -> None:
    for seed in range(10):
        world = sample_arm_world(model, seed, keep_clear=COLUMN)
        assert not world.to_scene().spheres_collide(COLUMN.centres, COLUMN.radii)


def test_impossible_keep_clear_is_reported() -> None:
    everywhere = KeepClear(np.array([[0.8, 0.0, 0.1]]), np.array([5.0]))
    with pytest.raises(ProblemError, match="no table pose"):
        sample_arm_world("table_clutter", 0, keep_clear=everywhere)
    world = sample_arm_world("clutter", 0, keep_clear=everywhere)
    assert world.obstacles == ()  # every object is redrawn, then dropped


def test_unknown_model() -> None:
    with pytest.raises(ProblemError, match="unknown arm world model 'forest'"):
        sample_arm_world("forest", 0, keep_clear=NOTHING)


def test_to_scene_holds_every_obstacle() -> None:
    world = sample_arm_world("table_clutter", 3, keep_clear=NOTHING)
    scene = world.to_scene(margin=0.01)
    assert scene.names == tuple(o.name for o in world.obstacles)
    assert scene.margin == 0.01
    empty = ArmWorld(obstacles=(), model="empty")
    assert len(empty.to_scene()) == 0
    assert math.isfinite(float(world.obstacles[0].pose.position[0]))
