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
``--tree heli_wires --bag heli_wires`` runs the small Wires corridor, ``--tree arm_table_clutter --bag
arm_table_clutter`` the arm.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import rclpy
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter

from drd_msgs_py.bags import bag_frame, open_bag, read_bag
from drd_msgs_py.exceptions import MessageError
from drd_planner.exceptions import DrdError
from drd_planner.planning.service import PlanRecord
from drd_planner.planning.shipped import resolve_bag_path
from drd_planner.ros.node import PlannerNode
from drd_planner.ros.private_domain import private_domain
from drd_planner.ros.replay import ReplayOptions, replay_bag

__all__ = ["main", "print_record"]


def print_record(number: int, record: PlanRecord) -> None:
    """Print one served request: what asked, the per-check log, and the plan (or why there is none)."""
    result, session = record.result, record.session
    asked = record.request.get("request", "request")
    print(f"\nplan {number}: {asked} on map version {result.map_version}, tree {result.tree}")
    if "replan_reason" in record.request:
        print(f"  why: {record.request['replan_reason']}")
    cached = (
        " (reused from the query cache)"
        if result.query_cached and not result.query.startswith("tree:")
        else ""
    )
    print(
        f"  served by: {_served_by(result.query)}{cached} ({result.seconds.get('library', 0.0) * 1e3:.1f} ms)"
    )
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


def _served_by(query: str) -> str:
    """What the summary's ``query`` label means, for people."""
    if query.startswith("tree:"):
        return f"the precomputed DiRECt tree {query[5:]!r} of this query"
    if query == "online":
        return "a new query: its path library and DiRECt tree built online from the prior"
    if query == "connected":
        return "a new query from or to a state off the graph, joined by new motions; library and tree built online"
    return query or "-"


def build_parser() -> argparse.ArgumentParser:
    """The ``planner_demo`` argument parser."""
    parser = argparse.ArgumentParser(prog="planner_demo", description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--tree", default="heli_lines", help="tree file or shipped tree name (default heli_lines)"
    )
    parser.add_argument(
        "--bag", default="heli_lines", help="bag file or bundled bag name (default heli_lines)"
    )
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default ./out)")
    parser.add_argument("--rate", type=float, default=2.0, help="playback speed factor (default 2)")
    parser.add_argument("--seed", type=int, default=0, help="policy seed (default 0)")
    parser.add_argument("--no-pictures", action="store_true", help="skip the pictures (no matplotlib needed)")
    parser.add_argument(
        "--domain-id",
        type=int,
        default=None,
        help="ROS domain to run on (default: a private one where no other node is seen)",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the main job; 0 when every request got a verified plan, 1 if one did not, 2 on bad input."""
    args = build_parser().parse_args(argv)
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    try:
        bag_path = resolve_bag_path(args.bag)
        bag = open_bag(bag_path)
        frame = bag_frame(read_bag(bag_path)) or "map"
        if args.domain_id is not None and not 0 <= args.domain_id <= 232:
            raise DrdError(f"--domain-id must lie in [0, 232], got {args.domain_id}")
        domain_id = private_domain() if args.domain_id is None else args.domain_id
    except (DrdError, MessageError) as exc:
        print(f"planner_demo: error: {exc}", file=sys.stderr)
        return 2
    print(f"ROS domain {domain_id}" + (" (private)" if args.domain_id is None else ""))
    context = rclpy.context.Context()
    rclpy.init(context=context, domain_id=domain_id)
    node = PlannerNode(
        context=context,
        parameter_overrides=[
            Parameter("tree_paths", value=[args.tree]),
            Parameter("frame_id", value=frame),
            Parameter("seed", value=args.seed),
        ],
    )
    try:
        if node.trigger_configure() != TransitionCallbackReturn.SUCCESS:
            print(
                f"planner_demo: error: {node.errors[-1] if node.errors else 'configure failed'}",
                file=sys.stderr,
            )
            return 2
        node.trigger_activate()
        args.out.mkdir(parents=True, exist_ok=True)
        record = args.out / "outputs.mcap"
        print(f"replaying {bag_path} into the planner node (frame {frame!r}, tree {node.sessions[0].name})")
        # Each message after the node took the ones before and answered; after the bag, until it answered.
        options = ReplayOptions(
            record=record,
            overwrite=True,
            rate=args.rate,
            settle_until=lambda: node.planning_idle,
            ready=lambda published: node.inputs_taken >= published and node.planning_idle,
        )
        summary = replay_bag(bag, context=context, nodes=[node], options=options)
        print(
            f"published {len(summary.published)} bag messages; recorded "
            + ", ".join(f"{n} on {t}" for t, n in sorted(summary.recorded_per_topic.items()))
            + f" into {record}"
        )
        for error in node.errors:
            print(f"node error: {error}")
        history = node.history
        for k, served in enumerate(history):
            print_record(k, served)
        if not args.no_pictures:
            from drd_planner.pictures.plan import plan_picture

            for k, served in enumerate(history):
                if served.snapshot is None:  # an old record: its maps are no longer kept
                    continue
                files = plan_picture(
                    served.session,
                    served.snapshot,
                    served.result,
                    args.out / f"plan_{k}.png",
                    query_cached=served.result.query_cached,
                )
                print(f"picture: {', '.join(str(f) for f in files)}")
        if not history:
            print("planner_demo: the node served no request", file=sys.stderr)
            return 1
        return 0 if all(s.result.ok for s in history) else 1
    except (DrdError, MessageError) as exc:
        print(f"planner_demo: error: {exc}", file=sys.stderr)
        return 2
    finally:
        node.destroy_node()
        context.try_shutdown()


if __name__ == "__main__":
    raise SystemExit(main())
