"""The plan picture: files written, and the drawing encodes the maps, the check log and the plan."""

from __future__ import annotations

import dataclasses
import struct
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib", reason="the plots extra (matplotlib) is not installed")

from conftest import REPO_ROOT, SHARED_DATA, own_query
from matplotlib.colors import to_hex
from rosbags.typesys import Stores, get_typestore

from drd_msgs_py.factory import RosbagsMessages
from drd_msgs_py.obstacles import markers_from_obstacles
from drd_planner.bench.plots import COLOURS
from drd_planner.core.status import PlanStatus
from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.geometry.shapes import Capsule
from drd_planner.pictures.geometry import profile_crossings, split_obstacles
from drd_planner.pictures.labels import BACKGROUND_SHARE, boxes_hit_segments
from drd_planner.pictures.plan import PictureError, PlanDrawing, draw_plan_picture, plan_picture, served_by
from drd_planner.planner import load_prior
from drd_planner.planning.map_intake import obstacle_map, obstacles_data, terrain_from_cloud
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionCheck, SessionPlan
from drd_planner.planning.world_messages import helicopter_world_messages

TREES = REPO_ROOT / "trees"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@dataclass
class Case:
    session: QuerySession
    snapshot: MapSnapshot
    result: SessionPlan


def _msgs() -> RosbagsMessages:
    return RosbagsMessages(get_typestore(Stores.ROS2_JAZZY))


def _snapshot_from_markers(markers: object, frame: str, cloud: object | None, margin: float) -> MapSnapshot:
    obstacles = obstacle_map(markers, frame_id=frame)
    terrain = None if cloud is None else terrain_from_cloud(cloud, frame_id=frame)
    return MapSnapshot(1, obstacles, terrain, margin)


def _heli_case(session: QuerySession, seed: int) -> Case:
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    markers, cloud = helicopter_world_messages(
        domain.make_world("wires", seed), wire_segments=8, frame_id="map", msgs=_msgs()
    )
    snapshot = _snapshot_from_markers(markers, "map", cloud, session.margin)
    return Case(session, snapshot, session.plan(snapshot, *own_query(session), seed=0))


@pytest.fixture(scope="module")
def heli() -> Case:
    """The first world from seed 3 on with a plan and a blocked check (seed 3 with the shipped tree)."""
    session = QuerySession(load_prior(TREES / "heli_wires.npz"), name="heli_wires")
    cases = (_heli_case(session, seed) for seed in range(3, 23))
    case = next((c for c in cases if c.result.ok and c.result.num_blocked > 0), None)
    assert case is not None, "no world in 20 with a plan and a blocked check"
    return case


@pytest.fixture(scope="module")
def arm_session() -> QuerySession:
    if not (SHARED_DATA / "panda" / "panda_spherized.urdf").is_file():
        pytest.skip("shared Panda model not present (set DRD_SHARED_DATA)")
    return QuerySession(load_prior(TREES / "arm_table_clutter.npz"), name="arm_table_clutter")


def _arm_case(session: QuerySession, seeds: range, *, ok: bool) -> Case:
    """The first world of ``seeds`` with (ok) a plan after a blocked check, or (not ok) no plan."""
    for seed in seeds:
        case = _arm_world(session, seed)
        if case.result.ok == ok and (not ok or case.result.num_blocked > 0):
            return case
    raise AssertionError(f"no world in {seeds} with ok = {ok}")


def _arm_world(session: QuerySession, seed: int) -> Case:
    domain = session.domain
    assert isinstance(domain, ArmDomain)
    world = domain.make_world("table_clutter", seed)
    obstacles = [(f"object/{k}", o.shape, o.pose) for k, o in enumerate(world.obstacles)]
    markers = markers_from_obstacles(obstacles_data(obstacles), frame_id="panda_link0", msgs=_msgs())
    snapshot = _snapshot_from_markers(markers, "panda_link0", None, session.margin)
    return Case(session, snapshot, session.plan(snapshot, *own_query(session), seed=0))


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC
    assert data[12:16] == b"IHDR"
    width, height = struct.unpack(">II", data[16:24])
    return int(width), int(height)


def _segments(drawing: object, key: str) -> list[np.ndarray]:
    return list(drawing.layers[key].get_segments())  # type: ignore[attr-defined]


def _labels_over_obstacles(drawing: PlanDrawing) -> list[str]:
    """Each (label, obstacle) overlap in the rendered figure, measured on the artists themselves.

    Label boxes are the rendered extents of their white boxes; wires are their segments grown by half
    their line width, footprints their filled paths (only the outline of a background surface, one that
    spans BACKGROUND_SHARE of the panel both ways), tower dots their marker discs' boxes; all in pixels.
    """
    from matplotlib.path import Path as MplPath

    fig = drawing.figure
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    scale = fig.dpi / 72.0
    found = []
    for panel in drawing.panels:
        ax = panel.ax
        boxes = [
            (t.get_text(), t.get_bbox_patch().get_window_extent(renderer)) for t in panel.labels if t.get_visible()
        ]
        for child in ax.get_children():
            gid = child.get_gid()
            if gid == "wires":
                half = 0.5 * scale * max(child.get_linewidths())
                pieces = [MplPath(child.get_transform().transform(np.asarray(p))) for p in child.get_segments()]
                found += [
                    f"{text} on a wire"
                    for text, box in boxes
                    if any(p.intersects_bbox(box.padded(half), filled=False) for p in pieces)
                ]
            elif gid == "obstacle":
                path = child.get_path().transformed(child.get_transform())
                extent = path.get_extents()
                background = (
                    extent.width >= BACKGROUND_SHARE * ax.bbox.width
                    and extent.height >= BACKGROUND_SHARE * ax.bbox.height
                )
                found += [
                    f"{text} on a footprint" for text, box in boxes if path.intersects_bbox(box, filled=not background)
                ]
            elif gid == "obstacle_dot":
                (centre,) = child.get_transform().transform(child.get_xydata())
                radius = 0.5 * scale * child.get_markersize()
                found += [f"{text} on a tower" for text, box in boxes if box.padded(radius).contains(*centre)]
    return found


# --------------------------------------------------------------------------------------------------
# Helicopter


def test_helicopter_drawing_encodes_the_check_log(heli: Case) -> None:
    session, snapshot, result = heli.session, heli.snapshot, heli.result
    drawing = draw_plan_picture(session, snapshot, result)
    free = [c.edge for c in result.checks if c.free]
    blocked = [c.edge for c in result.checks if not c.free]
    assert drawing.counts["free"] == len(free) == len(_segments(drawing, "free"))
    assert drawing.counts["blocked"] == len(blocked) == len(_segments(drawing, "blocked"))
    # Each checked edge is drawn where its trajectory lies (lifted up the picture by its altitude above
    # the middle of the drawn range, a few pixels), in check order.
    base, per_metre = drawing.lift
    assert per_metre > 0.0
    assert 40.0 <= base <= 90.0

    def drawn(states: np.ndarray) -> np.ndarray:
        return states[:, :2] + np.outer(per_metre * (states[:, 2] - base), [0.0, 1.0])

    for edge, segment in zip(free, _segments(drawing, "free"), strict=True):
        assert segment == pytest.approx(drawn(session.edge_states(edge)))
    library = set(session.library_edges().tolist())
    unchecked = library - {c.edge for c in result.checks}
    assert drawing.counts["unchecked"] == len(unchecked) == len(_segments(drawing, "unchecked"))
    # The plan is one polyline through the result's states.
    (plan,) = _segments(drawing, "path")
    assert plan == pytest.approx(drawn(result.states))
    assert drawing.counts["path"] == len(result.path_edges)
    # Check numbers 1..n, in the colour of each outcome.
    assert [t.get_text() for t in drawing.labels] == [str(k) for k in range(1, len(result.checks) + 1)]
    colours = [COLOURS["free"] if c.free else COLOURS["blocked"] for c in result.checks]
    assert [t.get_color() for t in drawing.labels] == colours
    # Maps: one dark line per wire capsule, one footprint per other part, crossings under the plan.
    capsules = sum(isinstance(s, Capsule) for parts in snapshot.obstacles.values() for s, _ in parts)
    others = sum(not isinstance(s, Capsule) for parts in snapshot.obstacles.values() for s, _ in parts)
    assert capsules > 0
    assert others > 0
    assert drawing.counts["wires"] == capsules
    assert drawing.counts["solids"] == others
    top_images = drawing.top.get_images()
    assert len(top_images) == 1
    assert top_images[0].get_gid() == "terrain"
    assert drawing.counts["crossings"] > 0
    assert "altitude" in drawing.side.get_ylabel()
    assert "(m)" in drawing.top.get_xlabel()
    # One legend for both views, in its own row: it covers neither view.
    (legend,) = [ax.get_legend() for ax in drawing.figure.axes if ax.get_legend() is not None]
    assert legend.axes not in (drawing.top, drawing.side)
    assert {"wire", "plan", "checked free", "checked blocked", "start", "goal", "wire crossing"} <= {
        t.get_text() for t in legend.get_texts()
    }
    assert "served by the precomputed DiRECt tree 'heli_wires'" in drawing.figure.get_suptitle()


def test_labels_never_cover_obstacles_in_a_crowded_picture(heli: Case) -> None:
    """60 checks on library edges that cross wires seen from above: every number finds a spot off them."""
    session, snapshot = heli.session, heli.snapshot
    wires, _ = split_obstacles(snapshot)
    crossing = [
        int(e) for e in session.library_edges() if profile_crossings(session.edge_states(int(e))[:, :3], wires)[0].size
    ]
    assert len(crossing) >= 60
    checks = tuple(
        SessionCheck(k + 1, edge, (0, 0), k % 3 != 0, "bisect", 0.1, 0.0, False) for k, edge in enumerate(crossing[:60])
    )
    crowded = dataclasses.replace(heli.result, checks=checks)
    drawing = draw_plan_picture(session, snapshot, crowded)
    # The numbers on their own edges would cover the wires: measured so, before placing them.
    midpoints = [_covers_a_wire(drawing, session.edge_states(c.edge)) for c in checks]
    assert sum(midpoints) >= 10
    assert _labels_over_obstacles(drawing) == []
    assert drawing.counts["labels"] == 60
    assert drawing.counts["labels_hidden"] <= 3
    assert drawing.counts["labels_moved"] >= 10  # off their edge, with a leader line
    shown = [t for t in drawing.labels if t.get_visible()]
    assert len(shown) == 60 - drawing.counts["labels_hidden"]
    # Every other text on the top view (the terrain's contour labels) is drawn under every obstacle.
    obstacles = [c for c in drawing.top.get_children() if c.get_gid() in ("wires", "obstacle", "obstacle_dot")]
    others = [t for t in drawing.top.texts if t not in drawing.labels]
    assert others
    assert max(t.get_zorder() for t in others) < min(c.get_zorder() for c in obstacles)
    plain = draw_plan_picture(session, snapshot, heli.result)  # the real check log
    assert _labels_over_obstacles(plain) == []
    assert plain.counts["labels_hidden"] == 0


def _covers_a_wire(drawing: PlanDrawing, states: np.ndarray) -> bool:
    """Whether a number's box centred on the middle of an edge would touch a wire (pixels)."""
    ax = drawing.top
    middle = ax.transData.transform(states[states.shape[0] // 2, :2][None, :])[0]
    (wires,) = [c for c in ax.collections if c.get_gid() == "wires"]
    segments = np.stack([ax.transData.transform(np.asarray(p)) for p in wires.get_segments()])
    half = np.array([12.0, 9.0])  # about a two-digit number's box at 150 dpi
    box = np.concatenate([middle - half, middle + half])[None, :]
    return bool(boxes_hit_segments(box, segments, np.full(len(segments), 1.0))[0])


def test_edges_at_different_altitudes_differ_in_colour(heli: Case) -> None:
    """Library edges over the same ground at 40, 65 and 90 m take different colours; checks keep theirs."""
    session, snapshot = heli.session, heli.snapshot
    levels = sorted({float(z) for z in session.domain.graph.vertex_states[:, 2]})
    assert len(levels) >= 3
    # Two edges over the same ground at the lowest and highest level: same x, y, other z.
    by_ground: dict[bytes, list[int]] = {}
    for e in range(session.domain.graph.num_edges):
        states = session.edge_states(e)
        if np.ptp(states[:, 2]) == 0.0:
            by_ground.setdefault(np.round(states[:, :2], 6).tobytes(), []).append(e)
    low, high = next(
        (
            min(g, key=lambda e: session.edge_states(e)[0, 2]),
            max(g, key=lambda e: session.edge_states(e)[0, 2]),
        )
        for g in by_ground.values()
        if len(g) >= 3
    )
    assert session.edge_states(low)[0, 2] == levels[0]
    assert session.edge_states(high)[0, 2] == levels[-1]
    checks = (
        SessionCheck(1, low, (0, 0), True, "bisect", 0.1, 0.0, False),
        SessionCheck(2, high, (0, 0), True, "bisect", 0.1, 0.0, False),
    )
    result = dataclasses.replace(heli.result, checks=checks)
    drawing = draw_plan_picture(session, snapshot, result)
    drawing.figure.canvas.draw()
    # The checked pair lies side by side: the higher one lifted up the picture by 7 to 16 pixels.
    low_line, high_line = (drawing.top.transData.transform(s) for s in _segments(drawing, "free"))
    lift = high_line - low_line
    assert lift[:, 0] == pytest.approx(np.zeros(len(lift)), abs=1e-6)
    assert 7.0 <= float(lift[0, 1]) <= 16.0
    assert np.ptp(lift[:, 1]) < 1e-6
    # One outline colour (free), two core colours, ordered by altitude.
    core = drawing.altitude["free"]
    assert core.get_array().tolist() == [levels[0], levels[-1]]
    low_rgba, high_rgba = core.get_colors()
    assert np.abs(low_rgba - high_rgba).max() > 0.3
    assert np.sum(high_rgba[:3]) < np.sum(low_rgba[:3])  # higher is darker
    casings = drawing.layers["free"].get_colors()
    assert len(casings) == 1
    assert to_hex(casings[0]) == COLOURS["free"]
    assert drawing.layers["free"].get_linewidths()[0] > core.get_linewidths()[0]
    # The library edges: one colour per altitude, from the mean altitude of each edge.
    library = drawing.altitude["unchecked"]
    means = [
        float(np.mean(session.edge_states(e)[:, 2]))
        for e in sorted(set(session.library_edges().tolist()) - {low, high})
    ]
    assert np.asarray(library.get_array()).tolist() == pytest.approx(means)
    colours = {tuple(np.round(c, 6)) for c, z in zip(library.get_colors(), means, strict=True) if z in levels}
    assert len(colours) == len({z for z in means if z in levels}) >= 2
    # A colour bar in metres says which is which.
    assert any("edge altitude (m)" == ax.get_ylabel() for ax in drawing.figure.axes)


def test_title_says_what_served_the_plan(heli: Case) -> None:
    session, snapshot = heli.session, heli.snapshot
    first = draw_plan_picture(session, snapshot, heli.result).figure.get_suptitle()
    assert "served by the precomputed DiRECt tree 'heli_wires'" in first
    assert "cache" not in first
    # The same request again on the same maps: every check comes from the snapshot's cache.
    again = session.plan(snapshot, *own_query(session), seed=0)
    assert again.checks
    assert all(c.cached for c in again.checks)
    title = draw_plan_picture(session, snapshot, again).figure.get_suptitle()
    assert f"served from cache: all {len(again.checks)} checks answered from map v1's check cache" in title
    # What a prior's session says of new queries (SessionPlan.query), first built and then reused.
    common = {"status": PlanStatus.FOUND, "message": "m", "map_version": 4, "prior": "t"}
    fresh = SessionCheck(1, 5, (0, 1), True, "bisect", 0.1, 0.0, False)
    reused = dataclasses.replace(fresh, step=2, edge=6, cached=True)
    online = SessionPlan(**common, checks=(fresh, reused), query="online")
    assert served_by(online) == (
        "served by a library and DiRECt tree built online for this query; 1 of 2 checks from the map's check cache"
    )
    assert served_by(online, query_cached=True).startswith("served from cache: the library and DiRECt tree")
    connected = SessionPlan(**common, checks=(fresh,), query="connected")
    assert "joined by new motions" in served_by(connected)
    assert "cache" not in served_by(connected)
    tree = SessionPlan(**common, checks=(reused,), query="tree:heli_wires")
    assert served_by(tree) == (
        "served from cache: all 1 checks answered from map v4's check cache; the precomputed DiRECt tree 'heli_wires'"
    )
    assert served_by(tree, query_cached=True) == served_by(tree)  # a precomputed tree is never rebuilt
    probed = SessionPlan(**common, checks=(dataclasses.replace(fresh, stage="probe"),), query="online", stage="probe")
    assert served_by(probed) == "served by the probe (the union path checked first; no library built)"
    led = SessionPlan(**common, checks=(dataclasses.replace(fresh, stage="lead"),), query="connected", stage="lead")
    assert served_by(led).startswith("served by the lead (a lazy search")
    assert served_by(led).endswith("(joined by new motions)")


def test_helicopter_files_are_valid_and_deterministic(heli: Case, tmp_path: Path) -> None:
    first = plan_picture(heli.session, heli.snapshot, heli.result, tmp_path / "a" / "plan")
    again = plan_picture(heli.session, heli.snapshot, heli.result, tmp_path / "b" / "plan")
    assert [p.suffix for p in first] == [".png", ".svg"]
    assert all(p.is_file() for p in first)
    width, height = _png_size(first[0])
    assert 1200 <= width <= 2400
    assert 1200 <= height <= 2400
    assert first[0].stat().st_size > 50_000
    svg = first[1].read_text()
    assert svg.startswith("<?xml")
    assert "<svg" in svg
    assert 'id="free_edges"' in svg
    for a, b in zip(first, again, strict=True):
        assert a.read_bytes() == b.read_bytes()
    only_svg = plan_picture(heli.session, heli.snapshot, heli.result, tmp_path / "plan.svg")
    assert only_svg == [tmp_path / "plan.svg"]
    assert not (tmp_path / "plan.png").exists()


def test_helicopter_failed_request(heli: Case, tmp_path: Path) -> None:
    capped = QuerySession(heli.session.prior, name="capped", max_checks=4)
    result = capped.plan(heli.snapshot, *own_query(capped), seed=0)
    assert not result.ok
    assert len(result.checks) == 4
    drawing = draw_plan_picture(capped, heli.snapshot, result)
    title = drawing.figure.get_suptitle()
    assert "NO PLAN" in title
    assert "check budget" in title
    assert _segments(drawing, "path") == []
    assert len(_segments(drawing, "free")) + len(_segments(drawing, "blocked")) == 4
    assert "start-goal line" in drawing.side.get_xlabel()
    (path,) = plan_picture(capped, heli.snapshot, result, tmp_path / "failed.png", title="custom")
    assert _png_size(path)[0] >= 1200


def test_missing_matplotlib_is_a_clear_error(heli: Case, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # what "not installed" looks like to import
    with pytest.raises(PictureError, match=r"drd_planner\[plots\]"):
        plan_picture(heli.session, heli.snapshot, heli.result, tmp_path / "x.png")
    assert not (tmp_path / "x.png").exists()


# --------------------------------------------------------------------------------------------------
# Arm


def test_arm_drawing_shows_end_effector_paths(arm_session: QuerySession, tmp_path: Path) -> None:
    case = _arm_case(arm_session, range(40, 80), ok=True)  # seed 40 with the shipped tree
    result = case.result
    assert result.ok
    assert result.num_blocked > 0
    domain = arm_session.domain
    drawing = draw_plan_picture(arm_session, case.snapshot, result)
    free = [c.edge for c in result.checks if c.free]
    assert len(_segments(drawing, "free")) == len(free)
    assert len(_segments(drawing, "blocked")) == result.num_blocked
    # Each curve runs between the end-effector positions of its edge's vertices (the node's positions).
    for edge, segment in zip(free, _segments(drawing, "free"), strict=True):
        u, v = domain.graph.edges[edge]
        ends = arm_session.positions(np.stack([arm_session.vertex_state(int(u)), arm_session.vertex_state(int(v))]))
        assert segment[[0, -1]] == pytest.approx(ends[:, :2])
        assert segment.shape[0] > 2  # a curve through the edge's samples, not a chord
    (plan,) = _segments(drawing, "path")
    start_tool = arm_session.positions(arm_session.vertex_state(domain.start))[0]
    assert plan[0] == pytest.approx(start_tool[:2])
    assert plan[-1] == pytest.approx(arm_session.goal_position[:2])
    assert drawing.counts["solids"] == len(case.snapshot.obstacles)
    assert drawing.counts["wires"] == 0
    assert drawing.side.get_ylabel() == "z (m)"
    # Numbers in both views, none across an obstacle's outline or on a footprint but the table's top.
    assert [len(p.labels) for p in drawing.panels] == [len(result.checks)] * 2
    assert _labels_over_obstacles(drawing) == []
    (path,) = plan_picture(arm_session, case.snapshot, result, tmp_path / "arm.png")
    width, height = _png_size(path)
    assert width >= 1200
    assert 600 <= height <= width


def test_arm_without_a_verified_path(arm_session: QuerySession) -> None:
    capped = QuerySession(arm_session.prior, name="capped", max_checks=2)
    case = _arm_case(capped, range(3, 43), ok=False)  # a world whose plan needs more than two checks
    assert not case.result.ok
    drawing = draw_plan_picture(capped, case.snapshot, case.result)
    assert "NO PLAN" in drawing.figure.get_suptitle()
    assert "check budget" in drawing.figure.get_suptitle()
    assert _segments(drawing, "path") == []
    assert drawing.counts["labels"] == len(case.result.checks)
