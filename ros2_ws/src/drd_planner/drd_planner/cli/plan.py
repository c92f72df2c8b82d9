"""``drd plan``: its flags, made into the options of one of its three forms.

``--gccd``/``--dataset`` -> :class:`~drd_planner.planner.dataset_plan.DatasetPlanOptions`, ``--bag`` ->
:class:`~drd_planner.planning.bag_command.BagPlanOptions`, ``--scene`` ->
:class:`~drd_planner.planning.scene_command.ScenePlanOptions`.
"""

from __future__ import annotations

import argparse
from typing import Any

from drd_planner.cli.argtypes import query_arg
from drd_planner.cli.shared_flags import problem_source
from drd_planner.exceptions import DrdError
from drd_planner.planner.dataset_plan import DatasetPlanOptions, plan_dataset_world

__all__ = ["add_plan_parser", "cmd_plan", "request_index"]


def add_plan_parser(sub: Any) -> argparse.ArgumentParser:
    """Register ``plan`` (its forms: ``--gccd``/``--dataset``, ``--bag``, ``--scene``); returns the new parser."""
    from drd_planner.planner.planner import PLAN_POLICIES

    p: argparse.ArgumentParser = sub.add_parser(
        "plan",
        help="plan once offline with a prior on one dataset world, at a request of a bag, or a MoveIt request "
        "in a MoveIt scene",
    )
    p.add_argument(
        "--tree",
        "--prior",
        dest="tree",
        required=True,
        help="prior or tree file (or a shipped tree's name with --bag)",
    )
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--gccd", metavar="DIR", help="authors'-format dataset folder")
    where.add_argument("--dataset", metavar="FILE", help="dataset file written by drd build-dataset")
    where.add_argument(
        "--bag",
        metavar="BAG",
        help="rosbag2 MCAP bag of maps and requests (or a shipped bag's name): plan as the node would",
    )
    where.add_argument(
        "--scene",
        metavar="SCENE.yaml",
        help="MoveIt PlanningScene YAML: plan --request in it with the prior's real checker (roadmap growth on)",
    )
    p.add_argument("--world", type=int, default=None, help="0-based world row (--gccd / --dataset)")
    p.add_argument(
        "--request",
        default=None,
        metavar="N|REQUEST.yaml",
        help="--bag: its 0-based request (default 0); --scene: the MoveIt MotionPlanRequest YAML (start state "
        "and first joint goal, rad)",
    )
    p.add_argument(
        "--json",
        metavar="FILE",
        help='--scene: write {"status", "checks", "path_edges", "time_s", "reason", ...}',
    )
    p.add_argument(
        "--time-budget",
        type=float,
        default=None,
        metavar="S",
        help="--scene: end the plan after S seconds (default: none; roadmap growth stops by itself after 10 s)",
    )
    p.add_argument("--frame", default=None, help="planning frame for --bag (default: the maps' frame)")
    p.add_argument(
        "--prior-start",
        action="store_true",
        help="--bag: plan from the prior's start when the bag has no robot state (odom / joint_states) yet",
    )
    p.add_argument(
        "--skip-refused-maps",
        action="store_true",
        help="--bag: plan on the maps before a map message the node would refuse (as the node does) instead of "
        "stopping with its reason",
    )
    p.add_argument(
        "--query",
        type=query_arg,
        default=None,
        metavar="START,GOAL",
        help="plan this query (vertex ids or states) instead of the dataset's own (--gccd / --dataset)",
    )
    p.add_argument("--max-checks", type=int, default=None, help="end the plan after this many checks")
    p.add_argument("--policy", default="direct_bisect", choices=PLAN_POLICIES, help="the library stage's policy")
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=cmd_plan)
    return p


def cmd_plan(args: argparse.Namespace) -> int:
    """``drd plan``: one offline plan on a dataset world, a bag's request (no ROS) or a MoveIt scene."""
    if args.scene:
        from drd_planner.planning.scene_command import ScenePlanOptions, plan_scene

        return plan_scene(
            ScenePlanOptions(
                prior=args.tree,
                scene=args.scene,
                request=args.request,
                json=args.json,
                time_budget_s=args.time_budget,
                max_checks=args.max_checks,
                seed=args.seed,
            )
        )
    if args.bag:
        return _plan_bag(args)
    return plan_dataset_world(
        DatasetPlanOptions(
            prior=args.tree,
            source=problem_source(args),
            world=args.world,
            query=args.query,
            max_checks=args.max_checks,
            policy=args.policy,
            seed=args.seed,
        )
    )


def _plan_bag(args: argparse.Namespace) -> int:
    """``drd plan --bag``: the flags that do not go with a bag are refused."""
    from drd_planner.planning.bag_command import BagPlanOptions, plan_bag

    request = request_index(args.request)
    if args.policy != "direct_bisect":
        raise DrdError("--bag plans as the node does (direct_bisect); --policy cannot be changed")
    if args.world is not None or args.query is not None:
        raise DrdError("--world and --query select a dataset world and query; with --bag use --request")
    return plan_bag(
        BagPlanOptions(
            prior=args.tree,
            bag=args.bag,
            request=request,
            frame=args.frame,
            prior_start=args.prior_start,
            skip_refused_maps=args.skip_refused_maps,
            max_checks=args.max_checks,
            seed=args.seed,
        )
    )


def request_index(value: str | None) -> int:
    """``--request`` of ``--bag``: a 0-based request number (default 0)."""
    if value is None:
        return 0
    try:
        index = int(value)
    except ValueError:
        raise DrdError(f"--request with --bag is a 0-based request number, got {value!r}") from None
    if index < 0:
        raise DrdError(f"--request must be >= 0, got {index}")
    return index
