"""The plan picture: files written, and the drawing encodes the maps, the check log and the plan."""

from __future__ import annotations

import struct
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib", reason="the plots extra (matplotlib) is not installed")

from conftest import REPO_ROOT, SHARED_DATA
from rosbags.typesys import Stores, get_typestore

from drd_msgs_py.factory import RosbagsMessages
from drd_msgs_py.obstacles import markers_from_obstacles
from drd_planner.bench.plots import COLOURS
from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.geometry.shapes import Capsule
from drd_planner.planner import load_tree_bundle
from drd_planner.planning.map_intake import obstacle_map, obstacles_data, terrain_from_cloud
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.picture import PictureError, draw_plan_picture, plan_picture
from drd_planner.planning.session import PlanningSession, PlanResult
from drd_planner.planning.world_messages import helicopter_world_messages

TREES = REPO_ROOT / "trees"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@dataclass
class Case:
    session: PlanningSession
    snapshot: MapSnapshot
    result: PlanResult


def _msgs() -> RosbagsMessages:
    return RosbagsMessages(get_typestore(Stores.ROS2_JAZZY))


def _snapshot_from_markers(markers: object, frame: str, cloud: object | None, margin: float) -> MapSnapshot:
    obstacles = obstacle_map(markers, frame_id=frame)
    terrain = None if cloud is None else terrain_from_cloud(cloud, frame_id=frame)
    return MapSnapshot(1, obstacles, terrain, margin)


def _heli_case(session: PlanningSession, seed: int) -> Case:
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    markers, cloud = helicopter_world_messages(
        domain.make_world("wires", seed), wire_segments=8, frame_id="map", msgs=_msgs()
    )
    snapshot = _snapshot_from_markers(markers, "map", cloud, session.margin)
    return Case(session, snapshot, session.plan(snapshot, seed=0))


@pytest.fixture(scope="module")
def heli() -> Case:
    """The first world from seed 3 on with a plan and a blocked check (seed 3 with the shipped tree)."""
    session = PlanningSession(load_tree_bundle(TREES / "heli_wires.npz"), name="heli_wires")
    cases = (_heli_case(session, seed) for seed in range(3, 23))
    case = next((c for c in cases if c.result.ok and c.result.num_blocked > 0), None)
    assert case is not None, "no world in 20 with a plan and a blocked check"
    return case


@pytest.fixture(scope="module")
def arm_session() -> PlanningSession:
    if not (SHARED_DATA / "panda" / "panda_spherized.urdf").is_file():
        pytest.skip("shared Panda model not present (set DRD_SHARED_DATA)")
    return PlanningSession(load_tree_bundle(TREES / "arm_table_clutter.npz"), name="arm_table_clutter")


def _arm_case(session: PlanningSession, seeds: range, *, ok: bool) -> Case:
    """The first world of ``seeds`` with (ok) a plan after a blocked check, or (not ok) no plan."""
    for seed in seeds:
        case = _arm_world(session, seed)
        if case.result.ok == ok and (not ok or case.result.num_blocked > 0):
            return case
    raise AssertionError(f"no world in {seeds} with ok = {ok}")


def _arm_world(session: PlanningSession, seed: int) -> Case:
    domain = session.domain
    assert isinstance(domain, ArmDomain)
    world = domain.make_world("table_clutter", seed)
    obstacles = [(f"object/{k}", o.shape, o.pose) for k, o in enumerate(world.obstacles)]
    markers = markers_from_obstacles(obstacles_data(obstacles), frame_id="panda_link0", msgs=_msgs())
    snapshot = _snapshot_from_markers(markers, "panda_link0", None, session.margin)
    return Case(session, snapshot, session.plan(snapshot, seed=0))


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC and data[12:16] == b"IHDR"
    width, height = struct.unpack(">II", data[16:24])
    return int(width), int(height)


def _segments(drawing: object, key: str) -> list[np.ndarray]:
    return list(drawing.layers[key].get_segments())  # type: ignore[attr-defined]


# --------------------------------------------------------------------------------------------------
# Helicopter


def test_helicopter_drawing_encodes_the_check_log(heli: Case) -> None:
    session, snapshot, result = heli.session, heli.snapshot, heli.result
    drawing = draw_plan_picture(session, snapshot, result)
    free = [c.edge for c in result.checks if c.free]
    blocked = [c.edge for c in result.checks if not c.free]
    assert drawing.counts["free"] == len(free) == len(_segments(drawing, "free"))
    assert drawing.counts["blocked"] == len(blocked) == len(_segments(drawing, "blocked"))
    # Each checked edge is drawn where its trajectory lies, in check order.
    for edge, segment in zip(free, _segments(drawing, "free"), strict=True):
        assert segment == pytest.approx(session.edge_states(edge)[:, :2])
    library = set(session.bundle.problem.library.library_edges.tolist())
    unchecked = library - {c.edge for c in result.checks}
    assert drawing.counts["unchecked"] == len(unchecked) == len(_segments(drawing, "unchecked"))
    # The plan is one polyline through the result's states.
    (plan,) = _segments(drawing, "path")
    assert plan == pytest.approx(result.states[:, :2])
    assert drawing.counts["path"] == len(result.path_edges)
    # Check numbers 1..n, in the colour of each outcome.
    assert [t.get_text() for t in drawing.labels] == [str(k) for k in range(1, len(result.checks) + 1)]
    colours = [COLOURS["free"] if c.free else COLOURS["blocked"] for c in result.checks]
    assert [t.get_color() for t in drawing.labels] == colours
    # Maps: one dark line per wire capsule, one footprint per other part, crossings under the plan.
    capsules = sum(isinstance(s, Capsule) for parts in snapshot.obstacles.values() for s, _ in parts)
    others = sum(not isinstance(s, Capsule) for parts in snapshot.obstacles.values() for s, _ in parts)
    assert capsules > 0 and others > 0
    assert drawing.counts["wires"] == capsules and drawing.counts["solids"] == others
    top_images = drawing.top.get_images()
    assert len(top_images) == 1 and top_images[0].get_gid() == "terrain"
    assert drawing.counts["crossings"] > 0
    assert "altitude" in drawing.side.get_ylabel() and "(m)" in drawing.top.get_xlabel()
    legend = drawing.top.get_legend()
    assert legend is not None
    assert {"wire", "plan", "checked free", "checked blocked", "start", "goal"} <= {
        t.get_text() for t in legend.get_texts()
    }


def test_helicopter_files_are_valid_and_deterministic(heli: Case, tmp_path: Path) -> None:
    first = plan_picture(heli.session, heli.snapshot, heli.result, tmp_path / "a" / "plan")
    again = plan_picture(heli.session, heli.snapshot, heli.result, tmp_path / "b" / "plan")
    assert [p.suffix for p in first] == [".png", ".svg"] and all(p.is_file() for p in first)
    width, height = _png_size(first[0])
    assert 1200 <= width <= 2400 and 1200 <= height <= 2400
    assert first[0].stat().st_size > 50_000
    svg = first[1].read_text()
    assert svg.startswith("<?xml") and "<svg" in svg and 'id="free_edges"' in svg
    for a, b in zip(first, again, strict=True):
        assert a.read_bytes() == b.read_bytes()
    only_svg = plan_picture(heli.session, heli.snapshot, heli.result, tmp_path / "plan.svg")
    assert only_svg == [tmp_path / "plan.svg"] and not (tmp_path / "plan.png").exists()


def test_helicopter_failed_request(heli: Case, tmp_path: Path) -> None:
    capped = PlanningSession(heli.session.bundle, name="capped", max_checks=4)
    result = capped.plan(heli.snapshot, seed=0)
    assert not result.ok and len(result.checks) == 4
    drawing = draw_plan_picture(capped, heli.snapshot, result)
    title = drawing.figure.get_suptitle()
    assert "NO PLAN" in title and "max_checks" in title
    assert _segments(drawing, "path") == []
    assert len(_segments(drawing, "free")) + len(_segments(drawing, "blocked")) == 4
    assert "start-goal line" in drawing.side.get_xlabel()
    (path,) = plan_picture(capped, heli.snapshot, result, tmp_path / "failed.png", title="custom")
    assert _png_size(path)[0] >= 1200


def test_missing_matplotlib_is_a_clear_error(
    heli: Case, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # what "not installed" looks like to import
    with pytest.raises(PictureError, match=r"drd_planner\[plots\]"):
        plan_picture(heli.session, heli.snapshot, heli.result, tmp_path / "x.png")
    assert not (tmp_path / "x.png").exists()


# --------------------------------------------------------------------------------------------------
# Arm


def test_arm_drawing_shows_end_effector_paths(arm_session: PlanningSession, tmp_path: Path) -> None:
    case = _arm_case(arm_session, range(40, 80), ok=True)  # seed 40 with the shipped tree
    result = case.result
    assert result.ok and result.num_blocked > 0
    domain = arm_session.domain
    drawing = draw_plan_picture(arm_session, case.snapshot, result)
    free = [c.edge for c in result.checks if c.free]
    assert len(_segments(drawing, "free")) == len(free)
    assert len(_segments(drawing, "blocked")) == result.num_blocked
    # Each curve runs between the end-effector positions of its edge's vertices (the node's positions).
    for edge, segment in zip(free, _segments(drawing, "free"), strict=True):
        u, v = domain.graph.edges[edge]
        ends = arm_session.positions(
            np.stack([arm_session.vertex_state(int(u)), arm_session.vertex_state(int(v))])
        )
        assert segment[[0, -1]] == pytest.approx(ends[:, :2])
        assert segment.shape[0] > 2  # a curve through the edge's samples, not a chord
    (plan,) = _segments(drawing, "path")
    start_tool = arm_session.positions(arm_session.vertex_state(domain.start))[0]
    assert plan[0] == pytest.approx(start_tool[:2])
    assert plan[-1] == pytest.approx(arm_session.goal_position[:2])
    assert drawing.counts["solids"] == len(case.snapshot.obstacles) and drawing.counts["wires"] == 0
    assert drawing.side.get_ylabel() == "z (m)"
    (path,) = plan_picture(arm_session, case.snapshot, result, tmp_path / "arm.png")
    width, height = _png_size(path)
    assert width >= 1200 and 600 <= height <= width


def test_arm_without_a_free_path(arm_session: PlanningSession) -> None:
    case = _arm_case(arm_session, range(3, 43), ok=False)  # seed 3 with the shipped tree
    assert not case.result.ok
    drawing = draw_plan_picture(arm_session, case.snapshot, case.result)
    assert "NO PLAN" in drawing.figure.get_suptitle() and "no library path" in drawing.figure.get_suptitle()
    assert _segments(drawing, "path") == []
    assert drawing.counts["labels"] == len(case.result.checks)
