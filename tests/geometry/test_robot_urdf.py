"""URDF/SRDF parsing: chains of hand-written URDFs with known answers, the Panda files, malformed input."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import SHARED_DATA

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.kinematics import ForwardKinematics
from drd_planner.geometry.urdf_model import parse_collision_spheres, parse_srdf, parse_urdf_chain

PANDA = SHARED_DATA / "panda"


def panda_text(name: str) -> str:
    path = PANDA / name
    if not path.is_file():
        pytest.skip(f"shared Panda model {path} not present (set DRD_SHARED_DATA)")
    return Path(path).read_text(encoding="utf-8")


def joint(name: str, kind: str, parent: str, child: str, xyz: str = "0 0 0", extra: str = "") -> str:
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="0 0 0"/>{extra}</joint>'
    )


LIMIT = '<axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/>'
LEFT = '<axis xyz="0 1 0"/><limit lower="0.01" upper="0.04"/>'
RIGHT = '<axis xyz="0 -1 0"/><limit lower="0" upper="0.04"/>'

#: A planar two-link arm (unit links, z axes) with a fixed tool and a prismatic gripper with two fingers.
TWO_LINK = f"""<?xml version="1.0"?>
<robot name="two_link">
  <link name="base"/><link name="upper"/><link name="fore"/><link name="tool"/>
  <link name="left"/><link name="right"/>
  {joint("shoulder", "revolute", "base", "upper", extra=LIMIT)}
  {joint("elbow", "revolute", "upper", "fore", xyz="1 0 0", extra=LIMIT)}
  {joint("tool_joint", "fixed", "fore", "tool", xyz="1 0 0")}
  {joint("left_finger", "prismatic", "tool", "left", extra=LEFT)}
  {joint("right_finger", "prismatic", "tool", "right", extra=RIGHT)}
</robot>"""


# --------------------------------------------------------------------------------------------------
# Hand-written URDFs


def test_two_link_chain_structure() -> None:
    chain = parse_urdf_chain(TWO_LINK)
    assert chain.robot_name == "two_link"
    assert chain.root_link == "base"
    assert chain.joint_names == ("shoulder", "elbow")  # the two fingers tie: common prefix only
    assert chain.tip_link == "fore"
    assert chain.dof == 2
    np.testing.assert_array_equal(chain.lower, [-3.0, -3.0])
    np.testing.assert_array_equal(chain.upper, [3.0, 3.0])
    frames = dict(zip(chain.link_names, chain.link_frames.tolist(), strict=True))
    assert frames == {"base": 0, "upper": 1, "fore": 2, "tool": 2, "left": 2, "right": 2}


def test_two_link_forward_kinematics_by_hand() -> None:
    chain = parse_urdf_chain(TWO_LINK)
    fk = ForwardKinematics(chain)
    q = np.array([[0.0, 0.0], [math.pi / 2, -math.pi / 2], [math.pi / 2, math.pi / 2], [0.3, 0.4]])
    tool = fk.link_pose(q, "tool")[:, :3, 3]
    expected = [
        [2.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
        [math.cos(0.3) + math.cos(0.7), math.sin(0.3) + math.sin(0.7), 0.0],
    ]
    np.testing.assert_allclose(tool, expected, atol=1e-12)
    # the left finger is frozen at its lower limit 0.01 along the tool's +y
    left = fk.link_pose(np.zeros(2), "left")[0, :3, 3]
    np.testing.assert_allclose(left, [2.0, 0.01, 0.0], atol=1e-12)


def test_explicit_tip_link_puts_a_finger_on_the_chain() -> None:
    chain = parse_urdf_chain(TWO_LINK, tip_link="left")
    assert chain.joint_names == ("shoulder", "elbow", "left_finger")
    assert chain.joint_types == ("revolute", "revolute", "prismatic")
    pose = ForwardKinematics(chain).link_pose(np.array([0.0, 0.0, 0.03]), "left")
    np.testing.assert_allclose(pose[0, :3, 3], [2.0, 0.03, 0.0], atol=1e-12)


def test_continuous_joint_gets_pi_limits() -> None:
    urdf = f"""<robot name="wheel"><link name="a"/><link name="b"/>
      {joint("spin", "continuous", "a", "b", extra='<axis xyz="1 0 0"/>')}</robot>"""
    chain = parse_urdf_chain(urdf)
    assert chain.joint_types == ("revolute",)
    np.testing.assert_allclose([chain.lower[0], chain.upper[0]], [-math.pi, math.pi])


def test_unnormalised_axis_is_normalised() -> None:
    urdf = f"""<robot name="r"><link name="a"/><link name="b"/>
      {joint("j", "revolute", "a", "b", extra='<axis xyz="0 0 2"/><limit lower="-1" upper="1"/>')}</robot>"""
    chain = parse_urdf_chain(urdf)
    np.testing.assert_allclose(chain.axes[0], [0.0, 0.0, 1.0])


# --------------------------------------------------------------------------------------------------
# Malformed input


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "empty"),
        ("<robot name='x'><link name='a'></robot>", "not well-formed XML"),
        ("this is not xml", "not well-formed XML"),
        ("<model name='x'/>", "<robot> root"),
        ("<robot name='x'><link name='a'/></robot>", "no movable"),
        (
            f"<robot name='x'><link name='a'/>{joint('j', 'revolute', 'a', 'b', extra=LIMIT)}</robot>",
            "unknown child link 'b'",
        ),
        (
            f"<robot name='x'><link name='a'/><link name='b'/>{joint('j', 'revolute', 'a', 'b')}</robot>",
            "no <limit",
        ),
        (
            f"<robot name='x'><link name='a'/><link name='b'/>{joint('j', 'floating', 'a', 'b')}</robot>",
            "unsupported type 'floating'",
        ),
        (
            "<robot name='x'><link name='a'/><link name='b'/>"
            f"{joint('j', 'revolute', 'a', 'b', extra=LIMIT)}{joint('k', 'revolute', 'b', 'a', extra=LIMIT)}"
            "</robot>",
            "one tree",
        ),
        (
            "<robot name='x'><link name='a'/><link name='b'/><link name='c'/>"
            f"{joint('j', 'revolute', 'a', 'b', extra=LIMIT)}{joint('k', 'revolute', 'a', 'c', extra=LIMIT)}"
            "</robot>",
            "give tip_link",
        ),
    ],
)
def test_malformed_urdf_raises_clear_geometry_error(text: str, message: str) -> None:
    with pytest.raises(GeometryError, match=message):
        parse_urdf_chain(text)


def test_unknown_tip_link() -> None:
    with pytest.raises(GeometryError, match="tip link 'nowhere'"):
        parse_urdf_chain(TWO_LINK, tip_link="nowhere")


def test_spheres_refuse_other_collision_geometry() -> None:
    urdf = (
        "<robot name='x'><link name='a'><collision><geometry><box size='1 1 1'/></geometry></collision></link></robot>"
    )
    with pytest.raises(GeometryError, match="link 'a' has a non-sphere collision element \\(box\\)"):
        parse_collision_spheres(urdf)
    with pytest.raises(GeometryError, match="no <collision><sphere>"):
        parse_collision_spheres("<robot name='x'><link name='a'/></robot>")


def test_malformed_srdf() -> None:
    with pytest.raises(GeometryError, match="SRDF is not well-formed"):
        parse_srdf("<robot name='x'><disable_collisions link1='a'</robot>")
    with pytest.raises(GeometryError, match="lacks the attribute 'link2'"):
        parse_srdf("<robot name='x'><disable_collisions link1='a'/></robot>")
    with pytest.raises(GeometryError, match="not a number"):
        parse_srdf("<robot name='x'><group_state group='g' name='s'><joint name='j' value='up'/></group_state></robot>")


# --------------------------------------------------------------------------------------------------
# The Panda files


def test_panda_chain_and_limits() -> None:
    chain = parse_urdf_chain(panda_text("panda.urdf"))
    assert chain.joint_names == tuple(f"panda_joint{i}" for i in range(1, 8))
    assert chain.root_link == "panda_link0"
    assert chain.tip_link == "panda_link7"
    np.testing.assert_allclose(chain.lower, [-2.9671, -1.8326, -2.9671, -3.1416, -2.9671, -0.0873, -2.9671])
    np.testing.assert_allclose(chain.upper, [2.9671, 1.8326, 2.9671, 0.0873, 2.9671, 3.8223, 2.9671])
    # links after joint 7 are folded into frame 7 through the fixed joints
    for name in ("panda_link8", "panda_hand", "panda_leftfinger", "panda_rightfinger", "panda_grasptarget"):
        assert chain.link_frames[chain.link_index(name)] == 7


def test_panda_mesh_and_spherized_urdfs_have_the_same_kinematics() -> None:
    a = parse_urdf_chain(panda_text("panda.urdf"))
    b = parse_urdf_chain(panda_text("panda_spherized.urdf"))
    np.testing.assert_allclose(a.joint_origins, b.joint_origins, atol=1e-12)
    np.testing.assert_allclose(a.axes, b.axes)
    assert a.link_names == b.link_names


def test_panda_sphere_model_count() -> None:
    spheres = parse_collision_spheres(panda_text("panda_spherized.urdf"))
    assert spheres.count == 59
    per_link = {name: spheres.link_names.count(name) for name in set(spheres.link_names)}
    assert per_link["panda_link0"] == 1
    assert per_link["panda_hand"] == 18
    assert per_link["panda_leftfinger"] == per_link["panda_rightfinger"] == 2
    np.testing.assert_allclose(spheres.centres[0], [0.0, 0.0, 0.05])
    assert spheres.radii[0] == pytest.approx(0.08)
    with pytest.raises(GeometryError, match="mesh"):
        parse_collision_spheres(panda_text("panda.urdf"))


def test_panda_srdf() -> None:
    info = parse_srdf(panda_text("panda.srdf"))
    assert info.robot_name == "panda"
    assert len(info.disabled_pairs) == 34
    assert ("panda_link0", "panda_link1") in info.disabled_pairs
    assert ("panda_hand", "panda_link7") in info.disabled_pairs
    assert ("panda_link5", "panda_link7") not in info.disabled_pairs
    assert info.chains == {"panda_arm": ("panda_link0", "panda_link8")}
    ready = info.group_states[("panda_arm", "ready")]
    assert [ready[f"panda_joint{i}"] for i in range(1, 8)] == [0, -0.785, 0, -2.356, 0, 1.571, 0.785]
    assert info.group_states[("hand", "open")] == {"panda_finger_joint1": 0.035, "panda_finger_joint2": 0.035}
