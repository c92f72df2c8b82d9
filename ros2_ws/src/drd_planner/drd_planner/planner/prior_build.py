"""``drd build-tree`` as a library call: build a world prior with its DiRECt trees and write it.

:func:`write_prior` builds and writes a prior (:class:`BuildTreeOptions`): from a dataset (the prior's training
worlds over every edge, its validated eta and kappa, the dataset query's tree), or adding the trees of further
queries to an existing prior (:func:`query_tree`). The command line that makes the options is
:mod:`drd_planner.cli.build_tree`.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drd_planner import __version__
from drd_planner.core.problem import Problem
from drd_planner.core.tree import build_tree
from drd_planner.core.worlds import WorldDatabase
from drd_planner.data.problem_source import ProblemSource, problem_domain
from drd_planner.exceptions import DrdError
from drd_planner.planner.build_settings import LeafChoice, TreeSettings
from drd_planner.planner.endpoints import EndpointResolver, QueryText, endpoint_value
from drd_planner.planner.leaf_validation import TreeLeaf
from drd_planner.planner.prior import LeafSetting, QueryTree, WorldPrior, prior_from_problem
from drd_planner.planner.prior_file import load_prior, save_prior
from drd_planner.planner.query_library import query_library

__all__ = ["BuildTreeOptions", "build_prior", "query_tree", "resolve_query", "unused_tree_note", "write_prior"]


@dataclass(frozen=True)
class BuildTreeOptions:
    """What ``drd build-tree`` builds and writes.

    Attributes:
        out: the prior file to write (``.npz``).
        source: the dataset to build the prior from (None: add trees to ``prior``).
        prior: an existing prior file to add the ``queries``' trees to (None: build from ``source``).
        queries: further queries to precompute a tree for (each a start and goal as text: a vertex id, or a
            state's numbers separated by spaces or ';').
        leaf: how the prior's and each tree's eta, kappa and region rule are chosen (its seed is also the
            prior's library seed).
        tree: how the trees are built (the region rule comes from ``leaf``'s choice).
        validate_tree_leaves: validate every tree's own setting on its query (False: trees use the prior's).
    """

    out: str
    source: ProblemSource | None = None
    prior: str | None = None
    queries: tuple[QueryText, ...] = ()
    leaf: LeafChoice = field(default_factory=LeafChoice)
    tree: TreeSettings = field(default_factory=TreeSettings)
    validate_tree_leaves: bool = True


def resolve_query(prior: WorldPrior, query: QueryText) -> tuple[int, int]:
    """Vertex ids of a ``--query`` on the prior's graph (states snap to their nearest vertex)."""
    resolver = EndpointResolver(prior.graph)
    return resolver.resolve(endpoint_value(query[0]), "start"), resolver.resolve(endpoint_value(query[1]), "goal")


def query_tree(
    prior: WorldPrior,
    start: int,
    goal: int,
    *,
    tree: TreeSettings,
    name: str | None = None,
    leaf: LeafChoice | None = None,
) -> tuple[QueryTree, str]:
    """An offline DiRECt tree for another query of ``prior``, on the library the planner would build online.

    ``leaf`` chooses the tree's own ``(leaf, region_rule, note)`` on its query
    (:meth:`LeafChoice.tree_leaf`; None: the prior's leaf and rule).
    """
    if prior.worlds is None:
        raise DrdError("this prior has no training worlds over every edge; rebuild it from its dataset")
    from drd_planner.core.lazysp import GraphArcs
    from drd_planner.planner.goal_trees import SearchWorlds

    search = SearchWorlds(GraphArcs(prior.graph), prior.graph.lengths, prior.worlds, seed=prior.library_seed)
    library = query_library(search, prior.graph.edges, start, goal, start_vertex=start, max_paths=prior.max_paths)
    if library is None:
        raise DrdError(f"no training world has a free path from {start} to {goal}: nothing to build a tree on")
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
    own: TreeLeaf = TreeLeaf(None, prior.region_rule, "") if leaf is None else leaf.tree_leaf(problem, tree)
    built = build_tree(problem, **{**tree.kwargs(), "region_rule": own.region_rule})
    return QueryTree(problem.name, start, goal, library, built, own.leaf), own.note


def build_prior(options: BuildTreeOptions) -> tuple[WorldPrior, list[str]]:
    """The prior ``drd build-tree`` writes, and a few lines per tree built (see :func:`write_prior`).

    ``options.leaf`` chooses the prior's setting (:meth:`LeafChoice.prior_leaf`) and, with
    ``validate_tree_leaves``, each tree's own (:meth:`LeafChoice.tree_leaf`; else trees use the prior's).
    """
    lines: list[str] = []
    tree_leaf = options.leaf if options.validate_tree_leaves else None
    if options.prior:
        prior = load_prior(options.prior)
        if not options.queries:
            raise DrdError("--prior adds trees: give at least one --query START,GOAL")
    else:
        problem = (options.source or ProblemSource()).load()
        setting = options.leaf.prior_leaf(problem)
        lines += setting.note.splitlines()
        t0 = time.perf_counter()
        own_tree = (
            TreeLeaf(None, setting.region_rule, "") if tree_leaf is None else tree_leaf.tree_leaf(problem, options.tree)
        )
        tree = build_tree(problem, **{**options.tree.kwargs(), "region_rule": own_tree.region_rule})
        assert problem.start is not None and problem.goal is not None
        lines.append(
            f"tree {problem.name} ({problem.start} -> {problem.goal}): {tree.num_nodes} nodes, depth "
            f"{tree.depth()}, built in {time.perf_counter() - t0:.2f} s"
        )
        own = QueryTree(problem.name, int(problem.start), int(problem.goal), problem.library, tree, own_tree.leaf)
        lines += ["  " + line for line in own_tree.note.splitlines()]
        prior = prior_from_problem(
            problem,
            domain=problem_domain(problem),
            trees=(own,),
            eta=setting.eta,
            pseudo_count=setting.pseudo_count,
            region_rule=setting.region_rule,
            library_seed=options.leaf.seed,
            provenance={
                "command": " ".join(sys.argv),
                "dataset": problem.name,
                "software": __version__,
                "eta": setting.note,
            },
        )
        lines += unused_tree_note(prior.leaf_for(own), prior.num_worlds)
    trees = list(prior.trees)
    for query in options.queries:
        start, goal = resolve_query(prior, query)
        if prior.tree_for(start, goal) is not None:
            raise DrdError(f"the prior already has a tree for {start} -> {goal}")
        t0 = time.perf_counter()
        qt, note = query_tree(prior, start, goal, tree=options.tree, leaf=tree_leaf)
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


def write_prior(options: BuildTreeOptions) -> int:
    """``drd build-tree``: write a world prior (training worlds over every edge) with its DiRECt trees.

    Prints a few short lines: how eta and kappa were chosen (with the validation's time and the mean
    checks of every candidate), each tree built, the file written and the whole command's time.
    """
    t0 = time.perf_counter()
    prior, lines = build_prior(options)
    out = save_prior(options.out, prior)
    for line in lines:
        print(line)
    size = Path(out).stat().st_size / 1024
    print(
        f"wrote {out} ({size:.0f} KiB): world prior of {prior.num_worlds} training worlds x "
        f"{prior.graph.num_edges} edges, {len(prior.trees)} precomputed tree(s)"
    )
    print(f"done in {time.perf_counter() - t0:.1f} s (loading, validation, trees and writing)")
    return 0
