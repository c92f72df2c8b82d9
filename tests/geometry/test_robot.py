"""RobotModel: batched FK against yourdfpy, the sphere model, SRDF pairs and self-collision of the Panda."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
import yourdfpy
from conftest import SHARED_DATA

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.kinematics import ForwardKinematics
from drd_planner.geometry.robot import RobotModel, _excluded_pairs, build_sphere_groups
from drd_planner.geometry.urdf_model import parse_collision_spheres, parse_srdf

PANDA = SHARED_DATA / "panda"
READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
#: Elbow folded completely (joint 4 near its lower limit) with the shoulder tipped forward: the hand
#: comes back down onto the shoulder (link 1) and sinks about 4.5 cm into it.
FOLDED = np.array([0.0, 0.3, 0.0, -3.0, 0.0, 0.3, 0.0])


def panda_text(name: str) -> str:
    path = PANDA / name
    if not path.is_file():
        pytest.skip(f"shared Panda model {path} not present (set DRD_SHARED_DATA)")
    return Path(path).read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def panda() -> RobotModel:
    return RobotModel.from_urdf(
        panda_text("panda.urdf"),
        sphere_urdf=panda_text("panda_spherized.urdf"),
        srdf=panda_text("panda.srdf"),
    )


@pytest.fixture(scope="module")
def panda_no_srdf() -> RobotModel:
    return RobotModel.from_urdf(panda_text("panda_spherized.urdf"))


# --------------------------------------------------------------------------------------------------
# Forward kinematics


@pytest.mark.parametrize("file", ["panda.urdf", "panda_spherized.urdf"])
def test_fk_matches_yourdfpy_on_random_configurations(file: str) -> None:
    text = panda_text(file)
    robot = RobotModel.from_urdf(text, sphere_urdf=panda_text("panda_spherized.urdf"))
    reference = yourdfpy.URDF.load(io.BytesIO(text.encode()), build_scene_graph=True, load_meshes=False)
    rng = np.random.default_rng(7)
    q = rng.uniform(robot.lower, robot.upper, size=(8, 7))
    q[0] = 0.0
    poses = robot.link_poses(q)  # one batched call
    assert poses.shape == (8, len(robot.chain.link_names), 4, 4)
    for n in range(q.shape[0]):
        reference.update_cfg(q[n])
        for i, link in enumerate(robot.chain.link_names):
            np.testing.assert_allclose(poses[n, i], reference.get_transform(link, "panda_link0"), atol=1e-9)


def test_fk_zero_configuration_by_hand(panda: RobotModel) -> None:
    # At q = 0 the flange is at x = 0.0825 - 0.0825 + 0.088, z = 0.333 + 0.316 + 0.384 - 0.107, pointing down.
    flange = panda.link_poses(np.zeros(7))[0, panda.chain.link_index("panda_link8")]
    np.testing.assert_allclose(flange[:3, 3], [0.088, 0.0, 0.926], atol=1e-12)
    np.testing.assert_allclose(flange[:3, :3], np.diag([1.0, -1.0, -1.0]), atol=1e-9)


def test_fk_batched_equals_one_by_one(panda: RobotModel) -> None:
    q = np.random.default_rng(3).uniform(panda.lower, panda.upper, size=(50, 7))
    batched = panda.sphere_centres(q)
    single = np.stack([panda.sphere_centres(q[n])[0] for n in range(q.shape[0])])
    np.testing.assert_allclose(batched, single, atol=1e-14)
    # centres equal the link poses applied to the spherized URDF's own link-frame centres
    spheres = parse_collision_spheres(panda_text("panda_spherized.urdf"))
    links = [panda.chain.link_index(name) for name in spheres.link_names]
    poses = panda.link_poses(q)[:, links]
    via_links = np.einsum("nsij,sj->nsi", poses[..., :3, :3], spheres.centres) + poses[..., :3, 3]
    np.testing.assert_allclose(batched, via_links, atol=1e-12)


def test_fk_rejects_bad_shapes(panda: RobotModel) -> None:
    with pytest.raises(GeometryError, match=r"shape \(N, 7\)"):
        panda.sphere_centres(np.zeros((3, 6)))
    with pytest.raises(GeometryError, match="finite"):
        panda.link_poses(np.full(7, np.nan))


# --------------------------------------------------------------------------------------------------
# Sphere model and pairs


def test_sphere_model(panda: RobotModel) -> None:
    assert panda.spheres.count == 59
    assert panda.dof == 7
    base = panda.sphere_centres(READY)[0, panda.spheres.frame_index == 0]
    np.testing.assert_allclose(base, [[0.0, 0.0, 0.05]])  # link0's sphere never moves


def test_sphere_groups_cover_their_spheres(panda: RobotModel) -> None:
    groups = build_sphere_groups(panda.spheres, max_size=4)
    assert sorted(groups.members.tolist()) == list(range(59))
    assert np.all(np.diff(groups.offsets) <= 4)
    q = np.random.default_rng(5).uniform(panda.lower, panda.upper, size=(20, 7))
    frames = panda.fk.frames(q)
    spheres = panda.sphere_centres_from_frames(frames)
    centres = ForwardKinematics.apply_point_map(frames, panda.fk.point_map(groups.frame_index, groups.centres))
    which, member = groups.expand(np.arange(groups.count))
    reach = np.linalg.norm(spheres[:, member] - centres[:, which], axis=2) + panda.spheres.radii[member]
    assert np.all(reach <= groups.radii[which] + 1e-12)
    # the robot's own first-level groups: one per link with spheres, each enclosing its spheres
    links = panda.groups
    assert links.count == 11
    assert sorted(links.link_index.tolist()) == sorted(set(panda.spheres.link_index.tolist()))
    centres = panda.group_centres_from_frames(frames)
    which, member = links.expand(np.arange(links.count))
    reach = np.linalg.norm(spheres[:, member] - centres[:, which], axis=2) + panda.spheres.radii[member]
    assert np.all(reach <= links.radii[which] + 1e-12)


def test_srdf_pairs(panda: RobotModel, panda_no_srdf: RobotModel) -> None:
    assert len(panda.checked_link_pairs) == 21
    assert ("panda_hand", "panda_link1") in panda.checked_link_pairs
    assert ("panda_link5", "panda_link7") in panda.checked_link_pairs
    assert ("panda_link5", "panda_link6") not in panda.checked_link_pairs  # adjacent
    assert ("panda_link0", "panda_link2") not in panda.checked_link_pairs  # "Never" in the SRDF
    assert ("panda_hand", "panda_leftfinger") not in panda.checked_link_pairs  # rigidly attached
    # without an SRDF: every pair of links with spheres except parent/child and rigidly attached ones
    assert ("panda_link0", "panda_link2") in panda_no_srdf.checked_link_pairs
    assert ("panda_link1", "panda_link2") not in panda_no_srdf.checked_link_pairs
    assert ("panda_hand", "panda_link7") not in panda_no_srdf.checked_link_pairs
    # 11 links with spheres: C(11, 2) pairs - 7 joints between them - C(4, 2) pairs rigid on frame 7
    assert len(panda_no_srdf.checked_link_pairs) == 55 - 7 - 6
    assert panda.named_state("ready") == pytest.approx(READY)
    with pytest.raises(GeometryError, match="no named state 'home'"):
        panda.named_state("home")


def test_srdf_naming_unknown_links_is_refused() -> None:
    srdf = "<robot name='panda'><disable_collisions link1='panda_link0' link2='gripper_base'/></robot>"
    with pytest.raises(GeometryError, match="gripper_base"):
        RobotModel.from_urdf(panda_text("panda_spherized.urdf"), srdf=srdf)


# --------------------------------------------------------------------------------------------------
# Self-collision


def test_ready_pose_is_free_and_folded_pose_self_collides(panda: RobotModel, panda_no_srdf: RobotModel) -> None:
    for robot in (panda, panda_no_srdf):
        assert robot.self_collision(np.stack([READY, FOLDED])).tolist() == [False, True]
    # the folded pose: the hand's spheres sink into link 1's
    centres = panda.sphere_centres(FOLDED)[0]
    hand = panda.spheres.link_index == panda.chain.link_index("panda_hand")
    link1 = panda.spheres.link_index == panda.chain.link_index("panda_link1")
    gap = np.linalg.norm(centres[hand][:, None] - centres[link1][None], axis=2) - (
        panda.spheres.radii[hand][:, None] + panda.spheres.radii[link1][None]
    )
    assert gap.min() < -0.04


def test_every_named_state_is_free(panda: RobotModel) -> None:
    states = np.stack([panda.named_state(n) for n in ("ready", "extended", "transport")])
    assert not panda.self_collision(states).any()


def test_hierarchical_self_collision_equals_brute_force(panda: RobotModel) -> None:
    q = np.random.default_rng(11).uniform(panda.lower, panda.upper, size=(3000, 7))
    fast = panda.self_collision(q)
    assert np.array_equal(fast, panda.self_collision_brute_force(q))
    assert 0.02 < fast.mean() < 0.5  # random configurations: some, not most, self-collide


# --------------------------------------------------------------------------------------------------
# Issue 33 item 5: a description's pairs cost what they are, not the square of its links


def _with_extra_links(
    count: int, parents: tuple[str, ...] = ("panda_hand", "panda_link3", "panda_link5", "panda_link0")
) -> str:
    """The spherized Panda with ``count`` one- or two-sphere links fixed to ``parents`` in turn."""
    extra = "".join(
        f'<link name="extra_{k}"><collision><geometry><sphere radius="0.01"/></geometry></collision>'
        + (
            '<collision><origin xyz="0.01 0 0"/><geometry><sphere radius="0.02"/></geometry></collision>'
            if k % 3 == 0
            else ""
        )
        + f'</link><joint name="extra_joint_{k}" type="fixed"><parent link="{parents[k % len(parents)]}"/>'
        f'<child link="extra_{k}"/><origin xyz="0 0 {0.001 * k}"/></joint>'
        for k in range(count)
    )
    return panda_text("panda_spherized.urdf").replace("</robot>", extra + "</robot>")


@pytest.mark.parametrize("srdf", [False, True], ids=["parent-child", "srdf"])
def test_pairs_of_many_links_equal_their_definition(srdf: bool) -> None:
    """Checked link pairs, sphere pairs and group pairs against the pair-by-pair definitions."""
    robot = RobotModel.from_urdf(_with_extra_links(40), srdf=panda_text("panda.srdf") if srdf else None)
    chain, spheres = robot.chain, robot.spheres
    names = sorted({chain.link_names[i] for i in spheres.link_index})
    frame = {name: chain.link_frames[chain.link_index(name)] for name in names}
    if srdf:
        excluded = set(parse_srdf(panda_text("panda.srdf")).disabled_pairs)
    else:
        excluded = {(min(a, b), max(a, b)) for a, b in chain.parent_child}
    expected = [
        (a, b) for i, a in enumerate(names) for b in names[i + 1 :] if frame[a] != frame[b] and (a, b) not in excluded
    ]
    assert list(robot.checked_link_pairs) == expected
    checked = {(chain.link_index(a), chain.link_index(b)) for a, b in expected}
    checked |= {(b, a) for a, b in checked}
    link = spheres.link_index.tolist()
    brute = [(i, j) for i in range(len(link)) for j in range(i + 1, len(link)) if (link[i], link[j]) in checked]
    assert robot.self_pairs.tolist() == [list(p) for p in brute]
    groups = robot._self_groups
    group_link = groups.link_index.tolist()
    group_brute = [
        (a, b)
        for a in range(groups.count)
        for b in range(a + 1, groups.count)
        if (group_link[a], group_link[b]) in checked
    ]
    assert robot._group_pairs.tolist() == [list(p) for p in group_brute]
    members = [groups.members[groups.offsets[g] : groups.offsets[g + 1]].tolist() for g in range(groups.count)]
    sphere_pairs = [(a, b) for ga, gb in group_brute for a in members[ga] for b in members[gb]]
    assert list(zip(robot._pair_a.tolist(), robot._pair_b.tolist(), strict=True)) == sphere_pairs
    assert robot._pair_offsets[-1] == len(sphere_pairs)


@pytest.mark.parametrize("count", [100, 400])
def test_links_of_one_frame_are_not_listed_as_pairs(count: int) -> None:
    """The links fixed to one frame are left out where pairs are made, not listed: the excluded set is the joints.

    Before, ``count`` links on the hand listed their count^2 / 2 same-frame pairs (80,000 at 400 links, 32
    million at 8,000), the part of a description's cost that grew with the square of its links; the pairs
    checked (each extra link with the links of other frames) grow with the links.
    """
    robot = RobotModel.from_urdf(_with_extra_links(count, ("panda_hand",)))
    assert len(_excluded_pairs(robot.chain, None)) <= len(robot.chain.parent_child)
    per_frame = np.bincount(robot.chain.link_frames)
    assert int((per_frame * (per_frame - 1) // 2).sum()) > count**2 // 2  # what the old set held, at least
    assert len(robot.checked_link_pairs) < 15 * count
