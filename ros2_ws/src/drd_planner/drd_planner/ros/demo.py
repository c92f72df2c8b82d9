"""The main job (``planner_demo``): the planner node on a bundled bag, end to end, no hardware.

It starts the real :class:`~drd_planner.ros.node.PlannerNode` (rclpy) with a shipped tree, configures
and activates it, replays a bundled MCAP bag into it with the bag's timing
(:func:`~drd_planner.ros.replay.replay_bag`: maps, a request, an obstacle that blocks the first plan,
the request again), records everything the node publishes into ``OUT/outputs.mcap``, then prints each
plan with its per-check log and writes a picture of each (``OUT/plan_<k>.png``: terrain, wires, no-fly
zones, checked edges green/red, the plan).

It runs on a private ROS domain (:func:`~drd_planner.ros.private_domain.private_domain`: one where no other
node on this host is seen, discovery limited to this host) so it neither publishes into a robot stack nor hears
one; ``--domain-id N`` runs it on domain N instead (e.g. to watch it in rviz). The bag is stepped by events:
each message waits until the node has taken the ones before it and answered every request, so the story
(plan, blocking obstacle and replan, the goal again, a new goal, a start off the graph) happens in that order
on any machine, however loaded.

Defaults: the real-scale helicopter prior (``trees/heli_lines.npz``: power-line corridors, known no-fly
zones and registration error over 2.5 km of real terrain, 20 999 lattice edges) and ``bags/heli_lines.mcap``;
``--prior heli_wires --bag heli_wires`` runs the small Wires corridor, ``--prior arm_table_clutter --bag
arm_table_clutter`` the arm. The flags are parsed in :mod:`drd_planner.cli.planner_demo`, which calls
:func:`run_planner_demo` with a :class:`PlannerDemoOptions`.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import rclpy
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.node import Node
from rclpy.parameter import Parameter

from drd_msgs_py.bags import BagContents, bag_frame, open_bag, read_bag
from drd_msgs_py.exceptions import MessageError
from drd_planner.exceptions import DrdError
from drd_planner.planning.service import PlanRecord
from drd_planner.planning.shipped import resolve_bag_path
from drd_planner.ros.node import PlannerNode
from drd_planner.ros.private_domain import private_domain
from drd_planner.ros.replay import ReplayOptions, replay_bag

__all__ = [
    "PlannerDemoOptions",
    "ReplayReport",
    "active_planner_node",
    "demo_domain",
    "print_record",
    "replay_and_report",
    "report_served",
    "run_planner_demo",
]


@dataclass(frozen=True)
class PlannerDemoOptions:
    """One ``planner_demo`` run.

    Attributes:
        prior: the prior file, or a shipped tree's name.
        bag: the bag file, or a bundled bag's name.
        out: the output folder (``outputs.mcap`` and ``plan_<k>.png`` go there; made if missing).
        rate: playback speed factor (> 0; 2 plays twice as fast).
        seed: the policy's seed.
        pictures: draw a picture of each plan (needs matplotlib).
        domain_id: the ROS domain to run on, in [0, 232] (None: a private one where no other node is seen).
    """

    prior: str = "heli_lines"
    bag: str = "heli_lines"
    out: Path = Path("out")
    rate: float = 2.0
    seed: int = 0
    pictures: bool = True
    domain_id: int | None = None


def print_record(number: int, record: PlanRecord) -> None:
    """Print one served request: what asked, the per-check log, and the plan (or why there is none)."""
    result, session = record.result, record.session
    asked = record.request.get("request", "request")
    print(f"\nplan {number}: {asked} on map version {result.map_version}, prior {result.prior}")
    if "replan_reason" in record.request:
        print(f"  why: {record.request['replan_reason']}")
    cached = " (reused from the query cache)" if result.query_cached and not result.query.startswith("tree:") else ""
    served = _served_by(result.query, result.stage)
    print(f"  served by: {served}{cached} ({result.seconds.get('library', 0.0) * 1e3:.1f} ms)")
    for check in result.checks:
        state = "free   " if check.free else "BLOCKED"
        source = "cache" if check.cached else f"{check.check_ms:7.3f} ms"
        ends = "({}->{})".format(*check.endpoints)
        print(f"  check {check.step:3d}: edge {check.edge:5d} {ends:13s} {state} [{check.stage:6s}] {source}")
    seconds = result.seconds
    print(
        f"  -> {result.message}; {seconds.get('checks', 0.0) * 1e3:.1f} ms in collision checks, "
        f"{seconds.get('selection', 0.0) * 1e3:.1f} ms choosing edges, {seconds.get('total', 0.0) * 1e3:.1f} ms in all"
    )
    if not result.ok:
        return
    positions = session.positions(result.states, record.snapshot)
    length = float(np.sum(np.linalg.norm(np.diff(positions, axis=0), axis=1)))
    what = "end-effector path" if session.domain.publishes_joint_trajectory else "path"
    print(f"  {what}: edges {list(result.path_edges)}, {len(positions)} poses, {length:.2f} m long")
    for label, row in (("start", positions[0]), ("goal ", positions[-1])):
        print(f"    {label} ({row[0]:9.3f}, {row[1]:9.3f}, {row[2]:8.3f}) m")


def _served_by(query: str, stage: str) -> str:
    """What the summary's ``query`` label (and a ``probe`` or ``lead`` stage) means, for people."""
    if query.startswith("tree:"):
        return f"the precomputed DiRECt tree {query[5:]!r} of this query"
    if stage == "probe":
        return "a new query: the probe, its union path checked first; no library needed"
    if stage == "lead":
        return "a new query: the lead, a lazy search cheaper than its library at the stated check cost"
    if query == "online":
        return "a new query: its path library and DiRECt tree built online from the prior"
    if query == "connected":
        return "a new query from or to a state off the graph, joined by new motions; library and tree built online"
    return query or "-"


def report_served(node: PlannerNode, out: Path, *, pictures: bool) -> int:
    """Print the node's errors and every served request's check log; draw ``out/plan_<k>.png`` of each.

    Returns 0 when every request got a verified plan, 1 if one did not or none was served.
    """
    for error in node.errors:
        print(f"node error: {error}")
    history = node.history
    for k, served in enumerate(history):
        print_record(k, served)
    if pictures:
        from drd_planner.pictures.plan import plan_picture

        for k, served in enumerate(history):
            if served.snapshot is None:  # an old record: its maps are no longer kept
                continue
            files = plan_picture(
                served.session,
                served.snapshot,
                served.result,
                out / f"plan_{k}.png",
                query_cached=served.result.query_cached,
            )
            print(f"picture: {', '.join(str(f) for f in files)}")
    if not history:
        print("planner_demo: the node served no request", file=sys.stderr)
        return 1
    return 0 if all(s.result.ok for s in history) else 1


def demo_domain(domain_id: int | None) -> int:
    """The ROS domain of a demo run: ``domain_id``, or a private one where no other node is seen (None).

    Raises:
        DrdError: a domain id outside [0, 232].
    """
    if domain_id is not None and not 0 <= domain_id <= 232:
        raise DrdError(f"--domain-id must lie in [0, 232], got {domain_id}")
    return private_domain() if domain_id is None else domain_id


def active_planner_node(context: rclpy.context.Context, *, prior: str, frame: str, seed: int) -> PlannerNode | None:
    """A planner node on ``prior`` in planning frame ``frame``, configured and active.

    Returns None (the reason printed, the node destroyed) when it cannot be configured.
    """
    node = PlannerNode(
        context=context,
        parameter_overrides=[
            Parameter("prior_paths", value=[prior]),
            Parameter("frame_id", value=frame),
            Parameter("seed", value=seed),
        ],
    )
    if node.trigger_configure() != TransitionCallbackReturn.SUCCESS:
        print(f"planner_demo: error: {node.errors[-1] if node.errors else 'configure failed'}", file=sys.stderr)
        node.destroy_node()
        return None
    node.trigger_activate()
    return node


def replay_and_report(
    contents: BagContents,
    *,
    context: rclpy.context.Context,
    nodes: Sequence[Node],
    node: PlannerNode,
    options: ReplayReport,
) -> int:
    """Replay ``contents`` into ``nodes`` (the planner ``node`` among them) and report what it served.

    The node's outputs are recorded into ``out/outputs.mcap``; it prints what was published and recorded, then
    every served request (:func:`report_served`). Each message is sent after the node took the ones before
    (counted from now) and answered; after the last, until it answered. Returns :func:`report_served`'s status.
    """
    options.out.mkdir(parents=True, exist_ok=True)
    record = options.out / "outputs.mcap"
    taken = node.inputs_taken
    replay_options = ReplayOptions(
        record=record,
        overwrite=True,
        rate=options.rate,
        settle_until=lambda: node.planning_idle,
        ready=lambda published: node.inputs_taken - taken >= published and node.planning_idle,
    )
    summary = replay_bag(contents, context=context, nodes=list(nodes), options=replay_options)
    print(
        f"published {len(summary.published)} {options.what}; recorded "
        + ", ".join(f"{n} on {t}" for t, n in sorted(summary.recorded_per_topic.items()))
        + f" into {record}"
    )
    return report_served(node, options.out, pictures=options.pictures)


@dataclass(frozen=True)
class ReplayReport:
    """How :func:`replay_and_report` replays and reports.

    Attributes:
        out: output folder (outputs.mcap, plan pictures).
        rate: playback speed factor.
        pictures: draw the plan pictures.
        what: what the messages are, for the summary line ("bag messages").
    """

    out: Path
    rate: float
    pictures: bool
    what: str


def run_planner_demo(options: PlannerDemoOptions) -> int:
    """Run the main job; 0 when every request got a verified plan, 1 if one did not, 2 on bad input."""
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    try:
        bag_path = resolve_bag_path(options.bag)
        bag = open_bag(bag_path)
        frame = bag_frame(read_bag(bag_path)) or "map"
        domain_id = demo_domain(options.domain_id)
    except (DrdError, MessageError) as exc:
        print(f"planner_demo: error: {exc}", file=sys.stderr)
        return 2
    print(f"ROS domain {domain_id}" + (" (private)" if options.domain_id is None else ""))
    context = rclpy.context.Context()
    rclpy.init(context=context, domain_id=domain_id)
    node = active_planner_node(context, prior=options.prior, frame=frame, seed=options.seed)
    if node is None:
        context.try_shutdown()
        return 2
    try:
        print(f"replaying {bag_path} into the planner node (frame {frame!r}, prior {node.sessions[0].name})")
        report = ReplayReport(options.out, options.rate, options.pictures, "bag messages")
        return replay_and_report(bag, context=context, nodes=[node], node=node, options=report)
    except (DrdError, MessageError) as exc:
        print(f"planner_demo: error: {exc}", file=sys.stderr)
        return 2
    finally:
        node.destroy_node()
        context.try_shutdown()
