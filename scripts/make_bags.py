"""Generate the bundled replay bags from our world models (deterministic: same code and trees, same bytes).

    python scripts/make_bags.py [--out-dir bags] [--only heli|arm] [--robot-description URDF_FILE]

Each bag (one rosbag2 MCAP file, see ``drd_msgs_py.bags``) holds, at these offsets from its start:

- 0.0 s: the maps of one sampled world (helicopter: ``/terrain`` cloud + ``/obstacles`` markers in
  ``map``; arm: ``/obstacles`` in ``panda_link0``, plus ``/robot_description`` with
  ``--robot-description``: the Panda URDF is not copied into the repository, the node falls back to
  the tree's own model without it);
- 0.0 s: the robot's state at the tree's start (helicopter: ``/odom``, ``nav_msgs/Odometry`` in ``map``;
  arm: ``/joint_states``), where the node's plans start;
- 0.5 s: a request for the tree's goal (``/goal_pose`` at the goal position; arm: ``/goal_joints``);
- 1.5 s: the whole obstacle map again plus one new sphere placed on an edge of the first plan (so that
  edge is now in collision; every ``obstacles`` message is a full map because the topic is latched
  with depth 1);
- 2.5 s: the same request again (now planned around the new obstacle).

The world seed is the first (from ``--first-seed``) whose first plan has at least one blocked check
and on whose plan an added sphere blocks an edge yet leaves a free path; the script prints it.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from drd_msgs_py.bags import BagMessage, jazzy_typestore, maps_at_request, maps_until, open_bag, write_bag
from drd_msgs_py.factory import RosbagsMessages, header
from drd_msgs_py.obstacles import markers_from_obstacles
from drd_msgs_py.worlds import arm_world_messages, helicopter_world_messages
from drd_planner.data.moveit_scene import ScenePrimitive
from drd_planner.data.tree_file import load_tree
from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.arm_worlds import ArmWorld
from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.exceptions import DrdError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Sphere
from drd_planner.planning.session import PlanningSession, PlanResult

REPO = Path(__file__).resolve().parents[1]
#: Bag time of the first message (2023-11-14T22:13:20Z): fixed, so the bags are byte-for-byte reproducible.
START_NS = 1_700_000_000 * 10**9
MAPS_S, FIRST_REQUEST_S, UPDATE_S, SECOND_REQUEST_S = 0.0, 0.5, 1.5, 2.5
#: Radius (m) of the sphere added at 1.5 s: helicopter (the vehicle radius and margin add to it), arm.
HELI_SPHERE_RADIUS = 3.0
ARM_SPHERE_RADIUS = 0.04
PLAN_SEED = 0


@dataclass
class Scenario:
    """One generated bag: its messages and what was chosen."""

    name: str
    seed: int
    messages: list[BagMessage]
    first: PlanResult
    second: PlanResult
    blocked_edge: int
    notes: list[str] = field(default_factory=list)


def _ns(offset_s: float) -> int:
    return START_NS + round(offset_s * 1e9)


def _stamp(time_ns: int) -> tuple[int, int]:
    return time_ns // 10**9, time_ns % 10**9


def _middle_out(edges: tuple[int, ...]) -> Iterator[int]:
    """Inner path edges (not the first or last: start and goal stay clear), middle first."""
    inner = list(edges[1:-1]) or list(edges)
    mid = (len(inner) - 1) / 2.0
    yield from sorted(inner, key=lambda e: (abs(inner.index(e) - mid), inner.index(e)))


def _plan_at(session: PlanningSession, messages: list[BagMessage], time_ns: int, frame: str) -> PlanResult:
    maps = maps_until(
        messages,
        time_ns,
        frame_id=frame,
        margin=session.margin,
        robot_from_description=_robot_loader(session),
    )
    if maps.refused:
        raise DrdError(f"generated maps were refused: {maps.refused}")
    return session.plan(maps.snapshot, seed=PLAN_SEED)


def _robot_loader(session: PlanningSession) -> Any:
    domain = session.domain
    return domain.robot_from_description if isinstance(domain, ArmDomain) else None


def _edge_blocked(
    session: PlanningSession, messages: list[BagMessage], time_ns: int, frame: str, edge: int
) -> bool:
    maps = maps_until(
        messages,
        time_ns,
        frame_id=frame,
        margin=session.margin,
        robot_from_description=_robot_loader(session),
    )
    return not session.checker(maps.snapshot).check(edge)


def _joints(msgs: RosbagsMessages, session: PlanningSession, q: Any, frame: str, time_ns: int) -> Any:
    """A JointState of the arm's chain joints at ``q`` (rad)."""
    assert isinstance(session.domain, ArmDomain)
    return msgs(
        "sensor_msgs/msg/JointState",
        header=header(msgs, frame, _stamp(time_ns)),
        name=list(session.domain.robot.chain.joint_names),
        position=np.asarray(q, dtype=np.float64),
    )


def _pose(msgs: RosbagsMessages, state: Any) -> Any:
    """A Pose at a helicopter state (x, y, z m; heading rad as a yaw quaternion)."""
    yaw = float(state[3]) if state.size > 3 else 0.0
    return msgs(
        "geometry_msgs/msg/Pose",
        position=msgs("geometry_msgs/msg/Point", x=float(state[0]), y=float(state[1]), z=float(state[2])),
        orientation=msgs(
            "geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0)
        ),
    )


def _request(msgs: RosbagsMessages, session: PlanningSession, frame: str, time_ns: int) -> BagMessage:
    goal = session.goal_state
    if isinstance(session.domain, ArmDomain):
        msg = _joints(msgs, session, goal, frame, time_ns)
        return BagMessage("/goal_joints", "sensor_msgs/msg/JointState", time_ns, msg)
    pose = _pose(msgs, goal)
    msg = msgs("geometry_msgs/msg/PoseStamped", header=header(msgs, frame, _stamp(time_ns)), pose=pose)
    return BagMessage("/goal_pose", "geometry_msgs/msg/PoseStamped", time_ns, msg)


def _robot_state(msgs: RosbagsMessages, session: PlanningSession, frame: str, time_ns: int) -> BagMessage:
    """The robot at the tree's start: ``/odom`` (helicopter) or ``/joint_states`` (arm)."""
    start = session.vertex_state(session.domain.start)
    if isinstance(session.domain, ArmDomain):
        msg = _joints(msgs, session, start, frame, time_ns)
        return BagMessage("/joint_states", "sensor_msgs/msg/JointState", time_ns, msg)
    pose = _pose(msgs, start)
    msg = msgs(
        "nav_msgs/msg/Odometry",
        header=header(msgs, frame, _stamp(time_ns)),
        child_frame_id="base_link",
        pose=msgs("geometry_msgs/msg/PoseWithCovariance", pose=pose, covariance=np.zeros(36)),
        twist=msgs(
            "geometry_msgs/msg/TwistWithCovariance",
            twist=msgs(
                "geometry_msgs/msg/Twist",
                linear=msgs("geometry_msgs/msg/Vector3", x=0.0, y=0.0, z=0.0),
                angular=msgs("geometry_msgs/msg/Vector3", x=0.0, y=0.0, z=0.0),
            ),
            covariance=np.zeros(36),
        ),
    )
    return BagMessage("/odom", "nav_msgs/msg/Odometry", time_ns, msg)


def _finish(
    name: str,
    seed: int,
    session: PlanningSession,
    frame: str,
    messages: list[BagMessage],
    first: PlanResult,
    edge: int,
    msgs: RosbagsMessages,
) -> Scenario | None:
    """Add the two requests; the scenario if the second plan finds a path that avoids ``edge``."""
    second = _plan_at(session, messages, _ns(UPDATE_S), frame)
    if not second.ok or edge in second.path_edges:
        return None
    messages = [
        *messages,
        _robot_state(msgs, session, frame, _ns(MAPS_S)),
        _request(msgs, session, frame, _ns(FIRST_REQUEST_S)),
        _request(msgs, session, frame, _ns(SECOND_REQUEST_S)),
    ]
    messages.sort(key=lambda m: m.time_ns)
    return Scenario(name, seed, messages, first, second, edge)


def heli_scenario(msgs: RosbagsMessages, *, first_seed: int, tries: int) -> Scenario:
    """The helicopter Wires bag (tree ``trees/heli_wires.npz``, world model ``wires``, frame ``map``)."""
    session = PlanningSession(load_tree(REPO / "trees" / "heli_wires.npz"), name="heli_wires")
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    segments = domain.spec()["wire_segments"]
    frame = "map"
    for seed in range(first_seed, first_seed + tries):
        world = domain.make_world("wires", seed)
        t0, t1 = _ns(MAPS_S), _ns(UPDATE_S)
        markers, cloud = helicopter_world_messages(
            world, wire_segments=segments, frame_id=frame, stamp=_stamp(t0), msgs=msgs
        )
        base = [
            BagMessage("/terrain", "sensor_msgs/msg/PointCloud2", t0, cloud),
            BagMessage("/obstacles", "visualization_msgs/msg/MarkerArray", t0, markers),
        ]
        first = _plan_at(session, base, t0, frame)
        if not first.ok or first.num_blocked == 0:
            continue
        for edge in _middle_out(first.path_edges):
            states = session.edge_states(edge)[:, :3]
            centre = states[len(states) // 2]
            again, _ = helicopter_world_messages(
                world, wire_segments=segments, frame_id=frame, stamp=_stamp(t1), msgs=msgs
            )
            added = markers_from_obstacles(
                [("new_obstacle/0", Sphere(HELI_SPHERE_RADIUS), Pose(centre))],
                frame_id=frame,
                stamp=_stamp(t1),
                msgs=msgs,
                delete_all_first=False,
                color=(1.0, 0.8, 0.0, 0.9),
            )
            update = msgs("visualization_msgs/msg/MarkerArray", markers=[*again.markers, *added.markers])
            messages = [*base, BagMessage("/obstacles", "visualization_msgs/msg/MarkerArray", t1, update)]
            if not _edge_blocked(session, messages, t1, frame, edge):
                continue
            scenario = _finish("heli_wires", seed, session, frame, messages, first, edge, msgs)
            if scenario is not None:
                scenario.notes.append(
                    f"sphere r={HELI_SPHERE_RADIUS} m at {np.round(centre, 2).tolist()} (map)"
                )
                return scenario
    raise DrdError(f"no helicopter world seed in [{first_seed}, {first_seed + tries}) fits the scenario")


def arm_scenario(
    msgs: RosbagsMessages, *, first_seed: int, tries: int, robot_description: str | None
) -> Scenario:
    """The arm Table+Clutter bag (tree ``trees/arm_table_clutter.npz``, frame ``panda_link0``)."""
    session = PlanningSession(load_tree(REPO / "trees" / "arm_table_clutter.npz"), name="arm_table_clutter")
    domain = session.domain
    assert isinstance(domain, ArmDomain)
    frame = "panda_link0"
    t0, t1 = _ns(MAPS_S), _ns(UPDATE_S)
    prefix = []
    if robot_description is not None:
        text = msgs("std_msgs/msg/String", data=robot_description)
        prefix.append(BagMessage("/robot_description", "std_msgs/msg/String", t0, text))
    for seed in range(first_seed, first_seed + tries):
        world = domain.make_world("table_clutter", seed)
        markers = arm_world_messages(world, frame_id=frame, stamp=_stamp(t0), msgs=msgs)
        base = [*prefix, BagMessage("/obstacles", "visualization_msgs/msg/MarkerArray", t0, markers)]
        first = _plan_at(session, base, t0, frame)
        if not first.ok or first.num_blocked == 0:
            continue
        for edge in _middle_out(first.path_edges):
            q_mid = session.edge_states(edge).mean(axis=0)
            centres = domain.robot.sphere_centres(q_mid[None])[0]
            order = np.argsort(-np.linalg.norm(centres, axis=1), kind="stable")  # far from the base first
            for k in order[:8]:
                sphere = ScenePrimitive("new_obstacle", Sphere(ARM_SPHERE_RADIUS), Pose(centres[k]))
                if domain.keep_clear.blocked_by(sphere):
                    continue
                grown = ArmWorld((*world.obstacles, sphere), world.model, world.seed)
                update = arm_world_messages(grown, frame_id=frame, stamp=_stamp(t1), msgs=msgs)
                messages = [*base, BagMessage("/obstacles", "visualization_msgs/msg/MarkerArray", t1, update)]
                if not _edge_blocked(session, messages, t1, frame, edge):
                    continue
                scenario = _finish("arm_table_clutter", seed, session, frame, messages, first, edge, msgs)
                if scenario is not None:
                    where = np.round(centres[k], 3).tolist()
                    scenario.notes.append(f"sphere r={ARM_SPHERE_RADIUS} m at {where} (panda_link0)")
                    return scenario
    raise DrdError(f"no arm world seed in [{first_seed}, {first_seed + tries}) fits the scenario")


def _verify(path: Path, scenario: Scenario, session_tree: str, frame: str) -> None:
    """Read the written bag back and re-plan request 0 and 1 from it: the same check logs."""
    session = PlanningSession(load_tree(REPO / "trees" / session_tree), name="verify")
    messages = open_bag(path).decoded()
    for index, want in ((0, scenario.first), (1, scenario.second)):
        maps, _ = maps_at_request(
            messages,
            index,
            frame_id=frame,
            margin=session.margin,
            robot_from_description=_robot_loader(session),
        )
        got = session.plan(maps.snapshot, seed=PLAN_SEED)
        if [(c.edge, c.free) for c in got.checks] != [(c.edge, c.free) for c in want.checks]:
            raise DrdError(f"{path}: request {index} re-planned from the bag differs from the generated plan")


def _report(scenario: Scenario, path: Path) -> None:
    first, second = scenario.first, scenario.second
    print(f"{scenario.name}: world seed {scenario.seed}")
    print(
        f"  request 0: {len(first.checks)} checks, {first.num_blocked} blocked, path of {len(first.path_edges)} "
        f"edges {list(first.path_edges)}"
    )
    print(f"  update at {UPDATE_S} s blocks plan edge {scenario.blocked_edge}: {'; '.join(scenario.notes)}")
    print(
        f"  request 1: {len(second.checks)} checks, {second.num_blocked} blocked, path of {len(second.path_edges)} "
        f"edges {list(second.path_edges)}"
    )
    print(f"  wrote {path} ({path.stat().st_size / 1024:.1f} KiB, {len(scenario.messages)} messages)")


def main(argv: list[str] | None = None) -> int:
    """Entry point (see the module docstring); errors print one line and exit 2."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out-dir", default=str(REPO / "bags"), help="folder of the bags (default: bags/)")
    parser.add_argument("--only", choices=("heli", "arm"), help="write one of the two bags")
    parser.add_argument(
        "--robot-description", metavar="URDF_FILE", help="add /robot_description (this URDF) to the arm bag"
    )
    parser.add_argument("--first-seed", type=int, default=0, help="first world seed tried")
    parser.add_argument("--tries", type=int, default=50, help="world seeds tried per bag")
    args = parser.parse_args(argv)
    out_dir = Path(args.out_dir)
    msgs = RosbagsMessages(jazzy_typestore())
    try:
        description = None
        if args.robot_description:
            try:
                description = Path(args.robot_description).read_text()
            except OSError as exc:
                raise DrdError(f"cannot read --robot-description {args.robot_description}: {exc}") from exc
        jobs = []
        if args.only in (None, "heli"):
            jobs.append(
                (
                    "heli_wires",
                    "map",
                    lambda: heli_scenario(msgs, first_seed=args.first_seed, tries=args.tries),
                )
            )
        if args.only in (None, "arm"):
            jobs.append(
                (
                    "arm_table_clutter",
                    "panda_link0",
                    lambda: arm_scenario(
                        msgs, first_seed=args.first_seed, tries=args.tries, robot_description=description
                    ),
                )
            )
        for name, frame, make in jobs:
            scenario = make()
            path = write_bag(out_dir / f"{name}.mcap", scenario.messages, overwrite=True)
            _verify(path, scenario, f"{name}.npz", frame)
            _report(scenario, path)
    except (DrdError, ValueError) as exc:  # ValueError: MessageError / BagError of drd_msgs_py
        print(f"make_bags: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
