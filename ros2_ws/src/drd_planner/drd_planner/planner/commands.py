"""``drd build-tree`` (write a world prior with its trees) and ``drd plan`` (one plan through :class:`Planner`).

``drd plan`` plans on a dataset world (a table oracle, :func:`cmd_plan`) or a MoveIt request in a MoveIt scene
with the real checker (:func:`cmd_plan_scene`, :mod:`drd_planner.planning.scene_plan`); its ``--bag`` form lives
in :mod:`drd_planner.planning.bag_cli`.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner import __version__
from drd_planner.core.problem import Problem
from drd_planner.core.tree import build_tree
from drd_planner.core.worlds import WorldDatabase
from drd_planner.exceptions import DrdError
from drd_planner.planner.endpoints import EndpointResolver
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import LeafSetting, QueryTree, WorldPrior, prior_from_problem
from drd_planner.planner.prior_file import load_prior, save_prior
from drd_planner.planner.query_library import query_library
from drd_planner.planner.result import PlanResult

QueryText = tuple[str, str]


def query_arg(text: str) -> QueryText:
    """``--query START,GOAL``: each a vertex id, or a state as numbers separated by spaces or ';'.

    Examples: ``0,730`` (vertex ids), ``"0 0 65 0,700 0 65 0"`` (helicopter states).
    """
    parts = text.split(",")
    if len(parts) != 2 or not all(p.strip() for p in parts):
        raise argparse.ArgumentTypeError(
            f"expected START,GOAL (vertex ids, or states as space-separated numbers), got {text!r}"
        )
    return parts[0].strip(), parts[1].strip()


def endpoint_value(text: str) -> int | np.ndarray:
    """A vertex id (one integer) or a state (several numbers) from its command-line text."""
    fields = text.replace(";", " ").split()
    try:
        if len(fields) == 1 and fields[0].lstrip("-").isdigit():
            return int(fields[0])
        return np.array([float(f) for f in fields], dtype=np.float64)
    except ValueError:
        raise DrdError(f"{text!r} is neither a vertex id nor a state of numbers") from None


def resolve_query(prior: WorldPrior, query: QueryText) -> tuple[int, int]:
    """Vertex ids of a ``--query`` on the prior's graph (states snap to their nearest vertex)."""
    resolver = EndpointResolver(prior.graph)
    return resolver.resolve(endpoint_value(query[0]), "start"), resolver.resolve(
        endpoint_value(query[1]), "goal"
    )


def query_tree(
    prior: WorldPrior,
    start: int,
    goal: int,
    *,
    tree_options: dict[str, Any],
    name: str | None = None,
    tree_leaf: Any = None,
) -> tuple[QueryTree, str]:
    """An offline DiRECt tree for another query of ``prior``, on the library the planner would build online.

    ``tree_leaf(problem)`` gives the tree's own ``(leaf, region_rule, note)``
    (:class:`~drd_planner.planner.leaf_validation.TreeLeaf`; None: the prior's leaf and rule).
    """
    if prior.worlds is None:
        raise DrdError("this prior has no training worlds over every edge; rebuild it from its dataset")
    from drd_planner.core.lazysp import GraphArcs
    from drd_planner.planner.goal_trees import SearchWorlds

    search = SearchWorlds(GraphArcs(prior.graph), prior.graph.lengths, prior.worlds, seed=prior.library_seed)
    library = query_library(
        search, prior.graph.edges, start, goal, start_vertex=start, max_paths=prior.max_paths
    )
    if library is None:
        raise DrdError(
            f"no training world has a free path from {start} to {goal}: nothing to build a tree on"
        )
    n = prior.num_worlds
    problem = Problem(
        name=name or f"{start}-{goal}",
        library=library,
        edge_costs=prior.edge_costs,
        graph=prior.graph,
        start=start,
        goal=goal,
        worlds=WorldDatabase(
            prior.worlds,
            library.valid_paths(prior.worlds),
            np.arange(n),
            np.zeros(0, dtype=np.int64),
            prior.world_weights,
        ),
    )
    leaf, rule, note = (None, prior.region_rule, "") if tree_leaf is None else tree_leaf(problem)
    tree = build_tree(problem, **{**tree_options, "region_rule": rule})
    return QueryTree(problem.name, start, goal, library, tree, leaf), note


def build_prior(
    args: argparse.Namespace, *, tree_options: dict[str, Any], leaf: Any, tree_leaf: Any = None
) -> tuple[WorldPrior, list[str]]:
    """The prior ``drd build-tree`` writes, and a few lines per tree built (see :func:`cmd_build_tree`).

    ``leaf(problem, args)`` gives the prior's setting (:class:`~drd_planner.planner.leaf_validation.PriorLeaf`);
    ``tree_leaf(problem, args)`` each tree's own (:class:`~drd_planner.planner.leaf_validation.TreeLeaf`;
    None as the callable: trees use the prior's).
    """
    import dataclasses

    from drd_planner.data.dataset_cli import load_problem_from_args, problem_domain

    lines: list[str] = []
    if getattr(args, "prior", None):
        prior = load_prior(args.prior)
        if not args.query:
            raise DrdError("--prior adds trees: give at least one --query START,GOAL")
    else:
        problem = load_problem_from_args(args)
        setting = leaf(problem, args)
        lines += setting.note.splitlines()
        t0 = time.perf_counter()
        own_leaf, own_rule, own_note = (
            (None, setting.region_rule, "") if tree_leaf is None else tree_leaf(problem, args)
        )
        tree = build_tree(problem, **{**tree_options, "region_rule": own_rule})
        assert problem.start is not None and problem.goal is not None
        lines.append(
            f"tree {problem.name} ({problem.start} -> {problem.goal}): {tree.num_nodes} nodes, depth "
            f"{tree.depth()}, built in {time.perf_counter() - t0:.2f} s"
        )
        own = QueryTree(problem.name, int(problem.start), int(problem.goal), problem.library, tree, own_leaf)
        lines += ["  " + line for line in own_note.splitlines()]
        prior = prior_from_problem(
            problem,
            domain=problem_domain(problem),
            trees=(own,),
            eta=setting.eta,
            pseudo_count=setting.pseudo_count,
            region_rule=setting.region_rule,
            library_seed=args.seed,
            provenance={
                "command": " ".join(sys.argv),
                "dataset": problem.name,
                "software": __version__,
                "eta": setting.note,
            },
        )
    if not getattr(args, "prior", None):
        lines += unused_tree_note(prior.leaf_for(own), prior.num_worlds)
    trees = list(prior.trees)
    for query in args.query or ():
        start, goal = resolve_query(prior, query)
        if prior.tree_for(start, goal) is not None:
            raise DrdError(f"the prior already has a tree for {start} -> {goal}")
        t0 = time.perf_counter()
        own_leaf_of = None if tree_leaf is None else (lambda p: tree_leaf(p, args))
        qt, note = query_tree(prior, start, goal, tree_options=tree_options, tree_leaf=own_leaf_of)
        trees.append(qt)
        lines.append(
            f"tree {qt.name}: {qt.tree.num_nodes} nodes, depth {qt.tree.depth()}, {qt.library.num_paths} "
            f"paths, built in {time.perf_counter() - t0:.2f} s"
        )
        lines += ["  " + line for line in note.splitlines()]
        prior = dataclasses.replace(prior, trees=tuple(trees))
        lines += unused_tree_note(prior.leaf_for(qt), prior.num_worlds)
    return prior, lines


def unused_tree_note(leaf: LeafSetting, num_worlds: int) -> list[str]:
    """A note when a query's validated eta is 1: its DiRECt tree is then never used (BiSECt from check 1).

    Args:
        leaf: the eta and kappa the query plans with (``WorldPrior.leaf_for``).
        num_worlds: the prior's training worlds.

    Returns:
        No line when the tree is used (eta < 1), else the note's lines.
    """
    if leaf.eta < 1.0:
        return []
    return [
        "  note: validation chose eta 1, so this query's DiRECt tree is never used: BiSECt chooses every check "
        "(no eta made the validation episodes need fewer checks).",
        f"  A tree pays when its first checks tell the training worlds apart: more worlds (now {num_worlds}; "
        "--worlds), a longer query across the map (--query START,GOAL) whose paths cross what varies "
        "between worlds, or a world model with more uncertainty where the paths run.",
    ]


def cmd_build_tree(
    args: argparse.Namespace, *, tree_options: dict[str, Any], leaf: Any, tree_leaf: Any = None
) -> int:
    """``drd build-tree``: write a world prior (training worlds over every edge) with its DiRECt trees.

    Prints a few short lines: how eta and kappa were chosen (with the validation's time and the mean
    checks of every candidate), each tree built, the file written and the whole command's time.
    """
    t0 = time.perf_counter()
    prior, lines = build_prior(args, tree_options=tree_options, leaf=leaf, tree_leaf=tree_leaf)
    out = save_prior(args.out, prior)
    for line in lines:
        print(line)
    size = Path(out).stat().st_size / 1024
    print(
        f"wrote {out} ({size:.0f} KiB): world prior of {prior.num_worlds} training worlds x "
        f"{prior.graph.num_edges} edges, {len(prior.trees)} precomputed tree(s)"
    )
    print(f"done in {time.perf_counter() - t0:.1f} s (loading, validation, trees and writing)")
    return 0


def add_plan_parser(sub: Any) -> None:
    """The ``drd plan`` subcommand's parser (its forms: ``--gccd``/``--dataset``, ``--bag``, ``--scene``)."""
    from drd_planner.planner.planner import PLAN_POLICIES

    p = sub.add_parser(
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
    p.add_argument(
        "--policy", default="direct_bisect", choices=PLAN_POLICIES, help="the library stage's policy"
    )
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=cmd_plan)


def cmd_plan(args: argparse.Namespace) -> int:
    """``drd plan``: one offline plan on a dataset world, a bag's request (no ROS) or a MoveIt scene."""
    if args.scene:
        return cmd_plan_scene(args)
    if args.bag:
        from drd_planner.planning.bag_cli import cmd_plan_bag

        args.request = request_index(args.request)
        return cmd_plan_bag(args)
    return cmd_plan_dataset(args)


def cmd_plan_dataset(args: argparse.Namespace) -> int:
    """``drd plan --gccd/--dataset``: one plan through :class:`Planner` against one dataset world (a table oracle)."""
    from drd_planner.core.episode import TableOracle
    from drd_planner.data.dataset_cli import load_problem_from_args, problem_domain

    if args.world is None:
        raise DrdError("--world is required with --gccd / --dataset")
    problem = load_problem_from_args(args)
    planner = Planner.from_file(args.tree, expected_domain=problem_domain(problem))
    graph = problem.graph
    if graph is None or not np.array_equal(planner.prior.graph.edges, graph.edges):
        raise DrdError(f"{args.tree} was built for another graph than {problem.name!r}")
    worlds = problem.require_worlds()
    if not 0 <= args.world < worlds.num_worlds:
        raise DrdError(f"--world must lie in [0, {worlds.num_worlds})")
    if planner.prior.name != problem.name:
        print(f"note: the prior was built from {planner.prior.name}; planning on a world of {problem.name}")
    if args.world in set(worlds.train_ids.tolist()):
        print(
            f"note: world {args.world} is a training world (the prior has seen it); test worlds: "
            f"{', '.join(str(w) for w in worlds.test_ids[:8].tolist())}, ..."
        )
    start, goal = (
        (problem.start, problem.goal)
        if args.query is None
        else (
            endpoint_value(args.query[0]),
            endpoint_value(args.query[1]),
        )
    )
    assert start is not None and goal is not None
    result = planner.plan(
        start,
        goal,
        TableOracle(worlds.X[args.world]),
        seed=args.seed,
        max_checks=args.max_checks,
        policy=args.policy,
    )
    print_plan(planner, result)
    return 0 if result.found else 1


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


def cmd_plan_scene(args: argparse.Namespace) -> int:
    """``drd plan --prior P --scene S --request R [--json F]``: a MoveIt request planned with the real checker.

    Prints the outcome in one line (and the path's states when found); exit status 0 when a path was
    found and verified, 1 otherwise; the JSON record (:meth:`ScenePlan.to_json`) with ``--json``.
    """
    import json

    from drd_planner.planning.scene_plan import SceneRequest, plan_moveit_request

    if not args.request:
        raise DrdError("--scene needs --request REQUEST.yaml (the MoveIt MotionPlanRequest to plan)")
    if args.time_budget is not None and not args.time_budget > 0:
        raise DrdError(f"--time-budget must be a positive number of seconds, got {args.time_budget}")
    request = SceneRequest(
        Path(args.scene),
        Path(args.request),
        seed=args.seed,
        max_checks=args.max_checks,
        time_budget_s=args.time_budget,
    )
    plan = plan_moveit_request(load_prior(args.tree), request, label=Path(args.tree).name)
    result = plan.result
    print(
        f"{request.request.name} in {request.scene.name}: {result.status.value} after {result.num_checks} "
        f"checks in {plan.wall_s:.2f} s: {result.reason}"
    )
    for k, state in enumerate(plan.path_states[:: max(1, len(plan.path_states) // 10)]):
        print(f"  path state {k}: " + " ".join(f"{v:7.3f}" for v in state))
    if args.json:
        try:
            Path(args.json).write_text(json.dumps(plan.to_json(), indent=1) + "\n", encoding="utf-8")
        except OSError as exc:
            raise DrdError(f"cannot write --json {args.json}: {exc}") from exc
    return 0 if result.found else 1


def print_plan(planner: Planner, result: PlanResult) -> None:
    """The check log and the outcome of one plan, one line each."""
    edges = planner.prior.graph.edges
    for k, rec in enumerate(result.checks):
        u, v = (int(x) for x in edges[rec.edge])
        state = "free   " if rec.free else "BLOCKED"
        ends = f"({u}->{v})"
        print(f"  check {k + 1:3d}: edge {rec.edge:5d} {ends:14s}{state} [{rec.stage}]")
    t = result.timings
    print(
        f"  -> {result.status.value}: {result.reason} [query {result.query or '-'}, "
        f"stage {result.stage.value if result.stage else '-'}; library {t.library_s * 1e3:.1f} ms, "
        f"selection {t.selection_s * 1e3:.1f} ms, checks {t.checks_s * 1e3:.1f} ms]"
    )
