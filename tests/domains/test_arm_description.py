"""robot_description checks: sizes refused before parsing, frames and spheres that planning cannot use refused after."""

from __future__ import annotations

import time

import pytest
from conftest import SHARED_DATA

from drd_planner.domains.arm import ArmDomain
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.map_limits import MapLimits

PANDA = SHARED_DATA / "panda"


@pytest.fixture(scope="module")
def domain(small_arm: ArmDomain) -> ArmDomain:
    return small_arm


def _with_extra_links(urdf: str, count: int) -> str:
    """``urdf`` with ``count`` more links, each fixed to the hand with one collision sphere."""
    extra = "".join(
        f'<link name="extra_{k}"><collision><geometry><sphere radius="0.01"/></geometry></collision></link>'
        f'<joint name="extra_joint_{k}" type="fixed"><parent link="panda_hand"/><child link="extra_{k}"/>'
        f'<origin xyz="0 0 {0.001 * k}"/></joint>'
        for k in range(count)
    )
    return urdf.replace("</robot>", extra + "</robot>")


def test_the_shipped_descriptions_pass(domain: ArmDomain) -> None:
    for name in ("panda.urdf", "panda_spherized.urdf"):
        robot = domain.robot_from_description((PANDA / name).read_text())
        assert robot.chain.joint_names == domain.robot.chain.joint_names


def test_thousands_of_links_are_refused_before_the_model_is_built(
    domain: ArmDomain, monkeypatch: pytest.MonkeyPatch
) -> None:
    def no_parse(*_: object) -> None:
        raise AssertionError("the description was parsed before its size was checked")

    monkeypatch.setattr(domain.loader, "model", no_parse)
    big = _with_extra_links((PANDA / "panda_spherized.urdf").read_text(), 8000)
    start = time.perf_counter()
    with pytest.raises(ProblemError) as info:
        domain.robot_from_description(big)
    assert time.perf_counter() - start < 5.0
    assert str(info.value) == (
        "robot_description has 8013 links, over the limit max_robot_links = 512 (parameter max_robot_links)"
    )
    with pytest.raises(ProblemError, match=r"over the limit max_message_bytes = 1000 \(parameter max_message_bytes\)"):
        domain.robot_from_description(big, limits=MapLimits(max_message_bytes=1000))
    spheres = (PANDA / "panda_spherized.urdf").read_text()  # 59 collision spheres
    with pytest.raises(ProblemError, match="59 collision spheres, over the limit max_robot_spheres = 58"):
        domain.robot_from_description(spheres, limits=MapLimits(max_robot_spheres=58))


def test_a_few_hundred_extra_links_are_accepted(domain: ArmDomain) -> None:
    robot = domain.robot_from_description(_with_extra_links((PANDA / "panda_spherized.urdf").read_text(), 400))
    assert len(robot.chain.link_names) == 413


@pytest.mark.parametrize(
    ("old", "new", "says"),
    [
        (
            '<origin xyz="0.0 0.0 0.05" rpy="0 0 0">',
            '<origin xyz="1e308 0.0 0.05" rpy="0 0 0">',
            "max_coordinate",
        ),
        (
            '<origin xyz="0.0 0.0 0.05" rpy="0 0 0">',
            '<origin xyz="2e6 0.0 0.05" rpy="0 0 0">',
            "reach 2e+06 m",
        ),
        ('xyz="0 0 0.333"', 'xyz="0 0 1e308"', "origins"),
    ],
)
def test_origins_planning_cannot_use_are_refused(domain: ArmDomain, old: str, new: str, says: str) -> None:
    # Issue 19 item 8: collision origins at 1e308 were accepted and every plan failed afterwards.
    name = "panda.urdf" if "0.333" in old else "panda_spherized.urdf"
    text = (PANDA / name).read_text()
    assert old in text
    with pytest.raises(ProblemError, match=says.replace("+", r"\+")):
        domain.robot_from_description(text.replace(old, new, 1))


def test_origins_that_compose_beyond_the_limit_are_refused(domain: ArmDomain) -> None:
    far = (
        '<link name="far_0"/><joint name="far_joint_0" type="fixed"><parent link="panda_hand"/>'
        '<child link="far_0"/><origin xyz="8e5 0 0"/></joint>'
        '<link name="far_1"/><joint name="far_joint_1" type="fixed"><parent link="far_0"/>'
        '<child link="far_1"/><origin xyz="8e5 0 0"/></joint>'
    )
    # 1.6e6 m along the hand's x, which is turned 45 degrees: 1.13e6 m in the arm's x and y.
    text = (PANDA / "panda_spherized.urdf").read_text().replace("</robot>", far + "</robot>")
    with pytest.raises(
        ProblemError, match=r"joint and link origins reach 1\.13\d*e\+06 m .* \(parameter max_coordinate\)"
    ):
        domain.robot_from_description(text)
    assert domain.robot_from_description(text, limits=MapLimits(max_coordinate=2e6)).chain.dof == 7
