"""MoveIt PlanningScene importer: the shared MotionBenchMaker scenes and malformed scenes written here."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import SHARED_DATA

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.moveit_scene import parse_planning_scene, read_planning_scene
from drd_planner.geometry.shapes import Box, Cylinder, Sphere

MBM = SHARED_DATA / "mbm"


def mbm_scene(family: str, number: int) -> Path:
    path = MBM / family / f"scene{number:04d}.yaml"
    if not path.is_file():
        pytest.skip(f"shared MotionBenchMaker scene {path} not present (set DRD_SHARED_DATA)")
    return path


# --------------------------------------------------------------------------------------------------
# Shared scenes


@pytest.mark.parametrize("number", [1, 2, 17, 50, 100])
def test_table_pick_scenes_have_twelve_primitives(number: int) -> None:
    primitives = read_planning_scene(mbm_scene("table_pick_panda", number))
    assert len(primitives) == 12
    names = {p.name for p in primitives}
    assert {"table_top", "Can1", "Cube"} <= names
    assert sum(isinstance(p.shape, Cylinder) for p in primitives) == 2  # Can1 and Object1
    assert sum(isinstance(p.shape, Box) for p in primitives) == 10


@pytest.mark.parametrize("number", [1, 3, 42, 99])
def test_box_scenes_have_seven_primitives(number: int) -> None:
    primitives = read_planning_scene(mbm_scene("box_panda", number))
    assert len(primitives) == 7
    assert [p.name for p in primitives if isinstance(p.shape, Cylinder)] == ["Can1"]


def test_known_table_top_and_can_of_scene_one() -> None:
    primitives = {p.name: p for p in read_planning_scene(mbm_scene("table_pick_panda", 1))}
    top = primitives["table_top"]
    assert isinstance(top.shape, Box)
    np.testing.assert_allclose(top.shape.size, [1.2, 2.0, 0.04])
    np.testing.assert_allclose(top.pose.position, [0.4409202333062346, 1.026368632242444, 0.1984669621486253])
    np.testing.assert_allclose(top.pose.quaternion_xyzw, [0, 0, 0.4966790222940755, 0.8679342998251661])
    can = primitives["Can1"]
    assert isinstance(can.shape, Cylinder)
    assert can.shape.length == pytest.approx(0.12)  # MoveIt cylinder dimensions are (height, radius)
    assert can.shape.radius == pytest.approx(0.03)


# --------------------------------------------------------------------------------------------------
# Written here


def scene_yaml(objects: str) -> str:
    return f"world:\n  collision_objects:\n{objects}"


ONE_BOX = """    - id: crate
      primitives:
        - type: box
          dimensions: [0.1, 0.2, 0.3]
      primitive_poses:
        - position: [1, 2, 3]
          orientation: [0, 0, 0, 1]
"""


def test_object_pose_is_composed_with_primitive_pose() -> None:
    s = math.sin(math.pi / 4)
    text = scene_yaml(
        f"""    - id: shelf
      pose:
        position: {{x: 1.0, y: 0.0, z: 0.5}}
        orientation: {{x: 0, y: 0, z: {s}, w: {s}}}
      primitives:
        - {{type: 1, dimensions: [0.4, 0.1, 0.1]}}
        - {{type: 2, dimensions: [0.05]}}
      primitive_poses:
        - {{position: [1, 0, 0], orientation: [0, 0, 0, 1]}}
        - {{position: [0, 0, 0.2], orientation: [0, 0, 0, 1]}}
"""
    )
    board, ball = parse_planning_scene(text)
    assert (board.name, ball.name) == ("shelf/0", "shelf/1")
    assert isinstance(board.shape, Box)
    assert isinstance(ball.shape, Sphere)
    assert ball.shape.radius == pytest.approx(0.05)
    # the object is turned 90 degrees about z: its local +x offset ends up along world +y
    np.testing.assert_allclose(board.pose.position, [1.0, 1.0, 0.5], atol=1e-12)
    np.testing.assert_allclose(board.pose.quaternion_xyzw, [0, 0, s, s], atol=1e-12)
    np.testing.assert_allclose(ball.pose.position, [1.0, 0.0, 0.7], atol=1e-12)


def test_unset_object_quaternion_means_no_rotation(tmp_path: Path) -> None:
    text = scene_yaml(
        """    - id: crate
      pose: {position: [0, 0, 1], orientation: [0, 0, 0, 0]}
      primitives: [{type: box, dimensions: [0.1, 0.1, 0.1]}]
      primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 1]}]
"""
    )
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    (crate,) = read_planning_scene(path)
    np.testing.assert_allclose(crate.pose.position, [0, 0, 1])
    np.testing.assert_allclose(crate.pose.quaternion_xyzw, [0, 0, 0, 1])


def test_plain_box() -> None:
    (crate,) = parse_planning_scene(scene_yaml(ONE_BOX))
    assert crate.name == "crate"
    np.testing.assert_allclose(crate.pose.position, [1, 2, 3])


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (("type: box", "type: mesh"), "crate.*primitive type 'mesh' is not supported"),
        (("type: box", "type: cone"), "crate.*'cone' is not supported"),
        (("type: box", "type: 4"), "crate.*'cone' is not supported"),
        (("dimensions: [0.1, 0.2, 0.3]", "dimensions: [0.1, 0.2]"), "crate.*box dimensions"),
        (("dimensions: [0.1, 0.2, 0.3]", "dimensions: [0.1, .nan, 0.3]"), "crate.*finite"),
        (("dimensions: [0.1, 0.2, 0.3]", "dimensions: [0.1, -0.2, 0.3]"), "crate.*> 0"),
        (("          dimensions: [0.1, 0.2, 0.3]\n", ""), "crate.*no dimensions"),
        (("position: [1, 2, 3]", "position: [1, .inf, 3]"), "crate.*finite"),
        (("position: [1, 2, 3]", "position: [1, 2]"), "crate.*position"),
        (("orientation: [0, 0, 0, 1]", "orientation: {x: 0, y: 0, z: 0}"), "crate.*lacks w"),
        (("    - id: crate\n", "    - id: crate\n      operation: 1\n"), "crate.*operation"),
        (
            ("    - id: crate\n", "    - id: crate\n      header: {frame_id: camera}\n"),
            "crate.*frame 'camera'",
        ),
        (("    - id: crate\n", "    - id: crate\n      planes: [{coef: [0, 0, 1, 0]}]\n"), "crate.*planes"),
        (
            ("    - id: crate\n", "    - id: crate\n      meshes: [{triangles: [], vertices: []}]\n"),
            "crate.*meshes",
        ),
    ],
)
def test_malformed_object_names_the_object(tmp_path: Path, edit: tuple[str, str], message: str) -> None:
    old, new = edit
    text = scene_yaml(ONE_BOX)
    assert old in text
    path = tmp_path / "bad.yaml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(GeometryError, match=message) as info:
        read_planning_scene(path)
    assert "bad.yaml" in str(info.value)


def test_mesh_object_is_refused() -> None:
    text = scene_yaml(ONE_BOX + "      meshes:\n        - {triangles: [[0, 1, 2]], vertices: [[0, 0, 0]]}\n")
    with pytest.raises(GeometryError, match="'crate' has meshes"):
        parse_planning_scene(text)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("world: [unclosed", "not valid YAML"),
        ("- a\n- b\n", "must be a YAML mapping"),
        ("name: scene\n", "no world.collision_objects"),
        ("world:\n  collision_objects: 3\n", "must be a list"),
        (
            "robot_state:\n  attached_collision_objects: [{object: {id: tool}}]\n" + scene_yaml(ONE_BOX),
            "attached collision objects",
        ),
        (
            "robot_state:\n  multi_dof_joint_state:\n"
            "    transforms: [{translation: [0, 0, 0.5], rotation: [0, 0, 0, 1]}]\n" + scene_yaml(ONE_BOX),
            "virtual joint away from the origin",
        ),
    ],
)
def test_malformed_scene(text: str, message: str) -> None:
    with pytest.raises(GeometryError, match=message):
        parse_planning_scene(text, source="test.yaml")


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(GeometryError, match="cannot read planning scene"):
        read_planning_scene(tmp_path / "absent.yaml")
