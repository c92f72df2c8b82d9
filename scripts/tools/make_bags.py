"""Generate the bundled replay bags from our world models (deterministic: same code and priors, same bytes).

    python scripts/tools/make_bags.py [--out-dir bags] [--only heli|arm] [--robot-description URDF_FILE]

Each bag (one rosbag2 MCAP file, see ``drd_msgs_py.bags``) holds, at these offsets from its start:

- 0.0 s: the maps of one sampled world (helicopter: ``/terrain`` cloud + ``/obstacles`` markers in
  ``map``; arm: ``/obstacles`` in ``panda_link0``, plus ``/robot_description`` with
  ``--robot-description``: the Panda URDF is not copied into the repository, the node falls back to
  the prior's own model without it);
- 0.0 s: the robot's state at the prior's stored start (helicopter: ``/odom``, ``nav_msgs/Odometry`` in
  ``map``; arm: ``/joint_states``), where the node's plans start;
- 0.5 s: request 0, for the stored goal (``/goal_pose`` at the goal position; arm: ``/goal_joints``): the
  query of the prior's precomputed tree;
- 1.5 s: the whole obstacle map again plus one new sphere placed on an edge of the first plan (so that
  edge is now in collision; every ``obstacles`` message is a full map because the topic is latched
  with depth 1);
- 2.5 s: request 1, the same goal again (now planned around the new obstacle);
- 3.5 s: the robot has moved to a vertex halfway along that plan (a new ``/odom`` / ``/joint_states``);
- 4.0 s: request 2, to another goal: a query no tree was built for (a library and tree made online);
- 5.0 s: the robot is between two vertices, halfway along an edge of the plan of request 2;
- 5.5 s: request 3, from there (joined to the graph by a new, checked motion) back to the stored start
  (arm), or on to the stored goal (helicopter: flying on).

The world seed is the first (from ``--first-seed``) whose first plan has at least one blocked check
and on whose plan an added sphere blocks an edge yet leaves a free path; the goal of request 2 is the
first of a seeded vertex order whose plan has a blocked check. Every request is planned as the node
plans it (:func:`drd_planner.planning.bag_plan.plan_bag_request`), and the written bag is read back
and planned again to the same check logs. The script prints what it chose.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order

from drd_msgs_py.bags import BagMessage, bag_requests, jazzy_typestore, open_bag, write_bag
from drd_msgs_py.factory import RosbagsMessages, header
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.arm_worlds import ArmWorld
from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.exceptions import DrdError
from drd_planner.geometry.moveit_scene import ScenePrimitive
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Sphere
from drd_planner.planner import load_prior
from drd_planner.planning.bag_plan import BagPlan, maps_until, plan_bag_request
from drd_planner.planning.session import QuerySession
from drd_planner.planning.world_messages import (
    arm_world_messages,
    helicopter_world_messages,
    obstacle_markers,
)

REPO = Path(__file__).resolve().parents[2]
#: Bag time of the first message (2023-11-14T22:13:20Z): fixed, so the bags are byte-for-byte reproducible.
START_NS = 1_700_000_000 * 10**9
MAPS_S, FIRST_REQUEST_S, UPDATE_S, SECOND_REQUEST_S = 0.0, 0.5, 1.5, 2.5
MOVE_S, THIRD_REQUEST_S, SECOND_MOVE_S, FOURTH_REQUEST_S = 3.5, 4.0, 5.0, 5.5
#: Radius (m) of the sphere added at 1.5 s: helicopter (the vehicle radius and margin add to it), arm.
HELI_SPHERE_RADIUS = 3.0
ARM_SPHERE_RADIUS = 0.04
PLAN_SEED = 0
#: Candidate goals of request 2 tried (in a seeded order of the graph's vertices).
GOAL_TRIES = 200


@dataclass(frozen=True)
class HeliBag:
    """How one helicopter bag is made.

    Attributes:
        world_model: the world model its map is drawn from.
        any_stop: the robot may stop at any vertex of request 1's plan for request 2 (the middle one first);
            False: only the middle one (on the real-scale lattice few goals are reachable from some vertices).
    """

    world_model: str
    any_stop: bool = False


#: The helicopter bags: bag name -> how it is made (its prior is ``trees/<name>.npz``).
HELI_BAGS: dict[str, HeliBag] = {
    "heli_wires": HeliBag("wires"),
    "heli_lines": HeliBag("corridors", any_stop=True),
}


@dataclass
class Scenario:
    """One generated bag: its messages and what was chosen."""

    name: str
    seed: int
    messages: list[BagMessage]
    blocked_edge: int
    frame: str
    notes: list[str] = field(default_factory=list)
    plans: list[BagPlan] = field(default_factory=list)


def _ns(offset_s: float) -> int:
    return START_NS + round(offset_s * 1e9)


def _stamp(time_ns: int) -> tuple[int, int]:
    return time_ns // 10**9, time_ns % 10**9


def _middle_out(edges: tuple[int, ...]) -> Iterator[int]:
    """Inner path edges (not the first or last: start and goal stay clear), middle first."""
    inner = list(edges[1:-1]) or list(edges)
    mid = (len(inner) - 1) / 2.0
    yield from sorted(inner, key=lambda e: (abs(inner.index(e) - mid), inner.index(e)))


def _snapshot(session: QuerySession, messages: list[BagMessage], time_ns: int, frame: str) -> Any:
    maps = maps_until(messages, time_ns, frame_id=frame, margin=session.margin, robot_loader=session.robot_loader)
    if maps.refused:
        raise DrdError(f"generated maps were refused: {maps.refused}")
    return maps.snapshot


def _plan(session: QuerySession, messages: list[BagMessage], index: int, frame: str) -> BagPlan:
    """Request ``index`` of time-ordered ``messages``, planned as the node plans it."""
    return plan_bag_request(session, sorted(messages, key=lambda m: m.time_ns), index, frame=frame, seed=PLAN_SEED)


def _edge_blocked(session: QuerySession, messages: list[BagMessage], time_ns: int, frame: str, edge: int) -> bool:
    return not session.checker(_snapshot(session, messages, time_ns, frame)).check(edge)


def _joints(msgs: RosbagsMessages, session: QuerySession, q: Any, frame: str, time_ns: int) -> Any:
    """A JointState of the arm's chain joints at ``q`` (rad)."""
    return msgs(
        "sensor_msgs/msg/JointState",
        header=header(msgs, frame, _stamp(time_ns)),
        name=list(session.joint_names),
        position=np.asarray(q, dtype=np.float64),
    )


def _pose(msgs: RosbagsMessages, state: Any) -> Any:
    """A Pose at a helicopter state (x, y, z m; heading rad as a yaw quaternion)."""
    yaw = float(state[3]) if state.size > 3 else 0.0
    return msgs(
        "geometry_msgs/msg/Pose",
        position=msgs("geometry_msgs/msg/Point", x=float(state[0]), y=float(state[1]), z=float(state[2])),
        orientation=msgs("geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0)),
    )


def _request(msgs: RosbagsMessages, session: QuerySession, goal: Any, frame: str, time_ns: int) -> BagMessage:
    """A request for the state ``goal``: ``/goal_joints`` (arm) or ``/goal_pose`` (helicopter)."""
    if session.domain.plans_joint_goals:
        msg = _joints(msgs, session, goal, frame, time_ns)
        return BagMessage("/goal_joints", "sensor_msgs/msg/JointState", time_ns, msg)
    pose = _pose(msgs, goal)
    msg = msgs("geometry_msgs/msg/PoseStamped", header=header(msgs, frame, _stamp(time_ns)), pose=pose)
    return BagMessage("/goal_pose", "geometry_msgs/msg/PoseStamped", time_ns, msg)


def _robot_state(msgs: RosbagsMessages, session: QuerySession, state: Any, frame: str, time_ns: int) -> BagMessage:
    """The robot at ``state``: ``/odom`` (helicopter) or ``/joint_states`` (arm)."""
    if session.domain.plans_joint_goals:
        msg = _joints(msgs, session, state, frame, time_ns)
        return BagMessage("/joint_states", "sensor_msgs/msg/JointState", time_ns, msg)
    pose = _pose(msgs, state)
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
    session: QuerySession,
    frame: str,
    messages: list[BagMessage],
    edge: int,
    msgs: RosbagsMessages,
) -> Scenario | None:
    """Add the robot's state and requests 0 and 1; the scenario if request 1's plan avoids ``edge``."""
    stored_start, stored_goal = int(session.domain.start), int(session.domain.goal)
    messages = [
        *messages,
        _robot_state(msgs, session, session.vertex_state(stored_start), frame, _ns(MAPS_S)),
        _request(msgs, session, session.vertex_state(stored_goal), frame, _ns(FIRST_REQUEST_S)),
        _request(msgs, session, session.vertex_state(stored_goal), frame, _ns(SECOND_REQUEST_S)),
    ]
    second = _plan(session, messages, 1, frame).result
    if not second.ok or edge in second.path_edges:
        return None
    messages.sort(key=lambda m: m.time_ns)
    return Scenario(name, seed, messages, edge, frame)


def _reachable(graph: ExplicitGraph, free: npt.NDArray[np.bool_], source: int) -> npt.NDArray[np.bool_]:
    """(V,) whether each vertex is reached from ``source`` along the ``free`` (E,) edges of ``graph``."""
    edges = graph.edges[free]
    ones = np.ones(len(edges), dtype=np.int8)
    matrix = coo_matrix((ones, (edges[:, 0], edges[:, 1])), shape=(graph.num_vertices,) * 2).tocsr()
    order = breadth_first_order(matrix, source, directed=graph.directed, return_predecessors=False)
    reached = np.zeros(graph.num_vertices, dtype=bool)
    reached[order] = True
    return reached


def _tour(
    scenario: Scenario,
    session: QuerySession,
    msgs: RosbagsMessages,
    *,
    any_stop: bool = False,
    onward: bool = False,
) -> Scenario | None:
    """Add the moving robot and requests 2 (a new goal) and 3 (from between two vertices).

    Request 3 goes home (the stored start), else on to the stored goal; with ``onward`` (the helicopter,
    flying on) the other way round, whichever a joining motion reaches first.

    The robot stops at the middle vertex of request 1's plan; with ``any_stop``, else at the next nearest
    to the middle with a fitting goal (see :class:`HeliBag`).
    Candidates are planned on one snapshot of the maps in force (they do not change after the update),
    from the states the robot reports; :func:`_verify` then plans every request from the bag.
    """
    snapshot = _snapshot(session, scenario.messages, _ns(UPDATE_S), scenario.frame)
    path = _plan(session, scenario.messages, 1, scenario.frame).result.path_vertices
    graph = session.prior.graph
    free = session.checker(snapshot).check_many(np.arange(graph.num_edges))
    mid = len(path) // 2
    stops = sorted(range(1, len(path) - 1), key=lambda i: (abs(i - mid), i)) if any_stop else []
    for at in [mid, *(i for i in stops if i != mid)]:
        found = _tour_from(scenario, session, msgs, snapshot, int(path[at]), _reachable(graph, free, path[at]), onward)
        if found is not None:
            return found
    return None


def _tour_from(
    scenario: Scenario,
    session: QuerySession,
    msgs: RosbagsMessages,
    snapshot: Any,
    here: int,
    reachable: npt.NDArray[np.bool_],
    onward: bool,
) -> Scenario | None:
    """:func:`_tour` with the robot stopped at vertex ``here``; ``reachable`` (V,): vertices it can reach.

    Goals are tried in a seeded order of the vertices. Those it cannot reach give no plan and are skipped
    unplanned, so up to :data:`GOAL_TRIES` goals are planned and the choice is the one without the skip.
    """
    frame = scenario.frame
    home = int(session.domain.start)
    taken = {home, int(session.domain.goal), here}
    graph = session.prior.graph
    order = np.random.default_rng(scenario.seed).permutation(graph.num_vertices)
    lengths = graph.lengths
    candidates = [int(v) for v in order if reachable[v] and int(v) not in taken]
    for goal in candidates[:GOAL_TRIES]:
        third = session.plan(snapshot, session.vertex_state(here), goal, seed=PLAN_SEED)
        if not third.ok or third.num_blocked == 0 or third.query != "online" or len(third.path_edges) < 3:
            continue
        inner = list(third.path_edges[1:-1])
        edge = max(inner, key=lambda e: (float(lengths[e]), -inner.index(e)))
        samples = session.edge_states(edge)
        between = samples[len(samples) // 2]
        ends = (int(session.domain.goal), home) if onward else (home, int(session.domain.goal))
        last = next(
            (
                end
                for end in ends
                if end != goal
                and (plan := session.plan(snapshot, between, end, seed=PLAN_SEED)).ok
                and plan.query == "connected"
            ),
            None,
        )
        if last is None:
            continue
        scenario.messages = sorted(
            [
                *scenario.messages,
                _robot_state(msgs, session, session.vertex_state(here), frame, _ns(MOVE_S)),
                _request(msgs, session, session.vertex_state(goal), frame, _ns(THIRD_REQUEST_S)),
                _robot_state(msgs, session, between, frame, _ns(SECOND_MOVE_S)),
                _request(msgs, session, session.vertex_state(last), frame, _ns(FOURTH_REQUEST_S)),
            ],
            key=lambda m: m.time_ns,
        )
        scenario.notes.append(
            f"request 2: from vertex {here} to vertex {goal}; request 3: from the middle of edge {edge} "
            f"to vertex {last}"
        )
        return scenario
    return None


def _first_plan(session: QuerySession, base: list[BagMessage], frame: str, msgs: RosbagsMessages) -> Any:
    """Request 0 (the stored goal from the stored start) on the maps ``base``."""
    t0 = _ns(MAPS_S)
    stored_start, stored_goal = int(session.domain.start), int(session.domain.goal)
    messages = [
        *base,
        _robot_state(msgs, session, session.vertex_state(stored_start), frame, t0),
        _request(msgs, session, session.vertex_state(stored_goal), frame, _ns(FIRST_REQUEST_S)),
    ]
    return _plan(session, messages, 0, frame).result


def heli_scenario(msgs: RosbagsMessages, *, first_seed: int, tries: int, name: str = "heli_wires") -> Scenario:
    """A helicopter bag (prior ``trees/<name>.npz``, its world model :data:`HELI_BAGS` ``[name]``, frame ``map``)."""
    bag = HELI_BAGS[name]
    session = QuerySession(load_prior(REPO / "trees" / f"{name}.npz"), name=name)
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    segments = domain.spec()["wire_segments"]
    frame = "map"
    for seed in range(first_seed, first_seed + tries):
        world = domain.make_world(bag.world_model, seed)
        t0, t1 = _ns(MAPS_S), _ns(UPDATE_S)
        markers, cloud = helicopter_world_messages(
            world, wire_segments=segments, frame_id=frame, stamp=_stamp(t0), msgs=msgs
        )
        base = [
            BagMessage("/terrain", "sensor_msgs/msg/PointCloud2", t0, cloud),
            BagMessage("/obstacles", "visualization_msgs/msg/MarkerArray", t0, markers),
        ]
        first = _first_plan(session, base, frame, msgs)
        if not first.ok or first.num_blocked == 0:
            continue
        for edge in _middle_out(first.path_edges):
            states = session.edge_states(edge)[:, :3]
            centre = states[len(states) // 2]
            again, _ = helicopter_world_messages(
                world, wire_segments=segments, frame_id=frame, stamp=_stamp(t1), msgs=msgs
            )
            added = obstacle_markers(
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
            scenario = _finish(name, seed, session, frame, messages, edge, msgs)
            if scenario is not None:
                scenario = _tour(scenario, session, msgs, any_stop=bag.any_stop, onward=True)
            if scenario is not None:
                scenario.notes.append(f"sphere r={HELI_SPHERE_RADIUS} m at {np.round(centre, 2).tolist()} (map)")
                return scenario
    raise DrdError(f"no helicopter world seed in [{first_seed}, {first_seed + tries}) fits the scenario")


def arm_scenario(msgs: RosbagsMessages, *, first_seed: int, tries: int, robot_description: str | None) -> Scenario:
    """The arm Table+Clutter bag (prior ``trees/arm_table_clutter.npz``, frame ``panda_link0``)."""
    session = QuerySession(load_prior(REPO / "trees" / "arm_table_clutter.npz"), name="arm_table_clutter")
    session.planner.growth = None  # the scenario is chosen on the roadmap alone (its plans need no growth)
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
        first = _first_plan(session, base, frame, msgs)
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
                scenario = _finish("arm_table_clutter", seed, session, frame, messages, edge, msgs)
                if scenario is not None:
                    scenario = _tour(scenario, session, msgs)
                if scenario is not None:
                    where = np.round(centres[k], 3).tolist()
                    scenario.notes.append(f"sphere r={ARM_SPHERE_RADIUS} m at {where} (panda_link0)")
                    return scenario
    raise DrdError(f"no arm world seed in [{first_seed}, {first_seed + tries}) fits the scenario")


def _planned(session: QuerySession, messages: list[BagMessage], frame: str) -> list[BagPlan]:
    """Every request of time-ordered ``messages``, planned as the node plans it."""
    return [plan_bag_request(session, messages, r.index, frame=frame, seed=PLAN_SEED) for r in bag_requests(messages)]


def _verify(path: Path, scenario: Scenario, prior_file: str) -> None:
    """Plan every request of the scenario, then of the written bag read back: the same check logs."""
    scenario.plans = _planned(
        QuerySession(load_prior(REPO / "trees" / prior_file), name="generate"),
        scenario.messages,
        scenario.frame,
    )
    session = QuerySession(load_prior(REPO / "trees" / prior_file), name="verify")
    again = _planned(session, open_bag(path).decoded(), scenario.frame)
    for want, got in zip(scenario.plans, again, strict=True):
        if [(c.edge, c.free) for c in got.result.checks] != [(c.edge, c.free) for c in want.result.checks]:
            raise DrdError(
                f"{path}: request {want.request.index} re-planned from the bag differs from the generated plan"
            )
    queries = [p.result.query for p in again]
    if not all(p.result.ok for p in again) or queries[2:] != ["online", "connected"]:
        raise DrdError(f"{path}: the requests do not plan as intended: {[p.result.outcome for p in again]}, {queries}")


def _where(endpoint: Any) -> str:
    return f"vertex {endpoint}" if isinstance(endpoint, int) else "the robot's state"


def _report(scenario: Scenario, path: Path) -> None:
    print(f"{scenario.name}: world seed {scenario.seed}")
    print(f"  update at {UPDATE_S} s blocks plan edge {scenario.blocked_edge}: {scenario.notes[-1]}")
    for plan in scenario.plans:
        r = plan.result
        stages = sorted({c.stage for c in r.checks})
        print(
            f"  request {plan.request.index} at +{(plan.request.time_ns - START_NS) / 1e9:.1f} s from "
            f"{_where(plan.start)} to {_where(plan.goal)}: {len(r.checks)} checks, {r.num_blocked} blocked, "
            f"query {r.query}, stages {stages}, path of {len(r.path_edges)} edges"
        )
    for note in scenario.notes[:-1]:
        print(f"  {note}")
    print(f"  wrote {path} ({path.stat().st_size / 1024:.1f} KiB, {len(scenario.messages)} messages)")


def main(argv: list[str] | None = None) -> int:
    """Entry point (see the module docstring); errors print one line and exit 2."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out-dir", default=str(REPO / "bags"), help="folder of the bags (default: bags/)")
    parser.add_argument(
        "--only", choices=("heli", "arm", *HELI_BAGS), help="write one bag (heli: every helicopter bag)"
    )
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
        jobs: list[tuple[str, str, Callable[[], Scenario]]] = []
        for heli in HELI_BAGS:
            if args.only in (None, "heli", heli):
                jobs.append(
                    (
                        heli,
                        "map",
                        partial(heli_scenario, msgs, first_seed=args.first_seed, tries=args.tries, name=heli),
                    )
                )
        if args.only in (None, "arm"):
            jobs.append(
                (
                    "arm_table_clutter",
                    "panda_link0",
                    partial(
                        arm_scenario,
                        msgs,
                        first_seed=args.first_seed,
                        tries=args.tries,
                        robot_description=description,
                    ),
                )
            )
        for name, _frame, make in jobs:
            scenario = make()
            path = write_bag(out_dir / f"{name}.mcap", scenario.messages, overwrite=True)
            _verify(path, scenario, f"{name}.npz")
            _report(scenario, path)
    except (DrdError, ValueError) as exc:  # ValueError: MessageError / BagError of drd_msgs_py
        print(f"make_bags: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
